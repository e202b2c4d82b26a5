//! Uniform refinement equals OpenSubdiv's on every shared mesh OpenSubdiv accepts, at levels 1,
//! 2 and 3, to 1e-12 × bbox (vertices as point sets, hole-free faces by count).
//!
//! OpenSubdiv's side is the peer harness's `osd_refine`, named by `SUBDIV_OSD_REFINE` (`.ci/run`
//! installs Debian's libosd-dev and builds it outside the repository). When the variable is set,
//! the program must exist; when it is unset, the test says so and does not run.

use std::path::PathBuf;

#[test]
fn refinement_equals_opensubdiv_on_the_shared_corpus() {
    let Some(osd_refine) = std::env::var_os("SUBDIV_OSD_REFINE").map(PathBuf::from) else {
        #[allow(clippy::print_stderr)]
        {
            eprintln!("SUBDIV_OSD_REFINE is unset: comparison with OpenSubdiv not run");
        }
        return;
    };
    assert!(osd_refine.is_file(), "SUBDIV_OSD_REFINE={} does not exist", osd_refine.display());
    let meshes = subdiv_testkit::meshes_dir().expect("the shared corpus is needed for the comparison");
    let report = subdiv_testkit::opensubdiv::compare_refinement(&osd_refine, &meshes, &[1, 2, 3]).unwrap();
    assert!(report.differ.is_empty(), "differ from OpenSubdiv:\n{}", report.differ.join("\n"));
    // 134 files, of which 15 are not valid meshes here (non-manifold, degenerate, misoriented).
    assert_eq!(report.skipped.len(), 15, "{:#?}", report.skipped);
    assert_eq!(report.equal, 119 * 3);
}
