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
            eprintln!("replaying {}", path.display());
            target.run(&input);
            replayed += 1;
        }
    }
    eprintln!("{replayed} reproducers replayed");
}
