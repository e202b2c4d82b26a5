//! Every seed and every reproducer `cargo xtask fuzz` has kept runs through its target without
//! a finding: the fuzzers' results as regression tests.

use std::path::Path;

use subdiv_fuzz::Target;

#[test]
fn seeds_and_reproducers_pass() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("reproducers");
    let mut replayed = 0;
    for target in Target::ALL {
        for seed in target.seeds() {
            target.run(&seed);
        }
        let folder = root.join(target.name());
        let Ok(entries) = std::fs::read_dir(&folder) else { continue };
        for entry in entries {
            let path = entry.unwrap().path();
            let input = std::fs::read(&path).unwrap();
            let run = std::panic::catch_unwind(|| target.run(&input));
            assert!(run.is_ok(), "{} fails again", path.display());
            replayed += 1;
        }
    }
    // The reproducers found so far (the first: a curve scheme named "\n", whose error
    // message spanned two lines).
    assert!(replayed >= 1, "the reproducers folder {} is missing", root.display());
}
