//! Uniform refinement equals OpenSubdiv's on every shared mesh OpenSubdiv accepts, at levels 1,
//! 2 and 3, to 1e-12 × bbox (vertices as point sets, hole-free faces by count), and so do the
//! refined texture coordinates (per face corner) in all six face-varying modes.
//!
//! OpenSubdiv's side is the peer harness's `osd_refine`, named by `SUBDIV_OSD_REFINE` (`.ci/run`
//! installs Debian's libosd-dev and builds it outside the repository). When the variable is set,
//! the program must exist; when it is unset, the test says so and does not run.

#[test]
fn refinement_equals_opensubdiv_on_the_shared_corpus() {
    let Some(osd_refine) = subdiv_testkit::peer_program("SUBDIV_OSD_REFINE") else { return };
    let meshes = subdiv_testkit::meshes_dir().expect("the shared corpus is needed for the comparison");
    let report = subdiv_testkit::opensubdiv::compare_refinement(&osd_refine, &meshes, &[1, 2, 3]).unwrap();
    assert!(report.differ.is_empty(), "differ from OpenSubdiv:\n{}", report.differ.join("\n"));
    // 134 files, of which 15 are not valid meshes here (non-manifold, degenerate, misoriented).
    assert_eq!(report.skipped.len(), 15, "{:#?}", report.skipped);
    assert_eq!(report.equal, 119 * 3);
}

/// Face-varying refinement (the texture coordinates of every shared mesh that has them) equals
/// `osd_refine --fvar` at levels 1-3 in all six modes of `FaceVaryingInterpolation`, per face
/// corner.
#[test]
fn face_varying_refinement_equals_opensubdiv_in_all_six_modes() {
    let Some(osd_refine) = subdiv_testkit::peer_program("SUBDIV_OSD_REFINE") else { return };
    let meshes = subdiv_testkit::meshes_dir().expect("the shared corpus is needed for the comparison");
    let modes: Vec<_> = subdiv_mesh::FaceVaryingInterpolation::ALL_MODES.into_iter().map(Some).collect();
    let report =
        subdiv_testkit::opensubdiv::compare_face_varying(&osd_refine, &meshes, |_| true, &[1, 2, 3], &modes).unwrap();
    assert!(report.differ.is_empty(), "differ from OpenSubdiv:\n{}", report.differ.join("\n"));
    // 113 files have texture coordinates, of which 10 are not valid meshes here.
    assert_eq!(report.skipped.len(), 10, "{:#?}", report.skipped);
    assert_eq!(report.equal, 103 * 6 * 3);
}
