//! The `own_device` example as a test: an application's own device, encoder and submission,
//! checked against the CPU (the example's `run`, shared through `#[path]`).

#[path = "../examples/own_device.rs"]
#[allow(dead_code)] // its `main`
mod own_device;

#[test]
fn an_applications_own_device_evaluates_like_the_cpu() {
    // Skips without an adapter, fails under SUBDIV_REQUIRE_GPU=1 (the example makes its own
    // device, on the same adapter).
    if subdiv_testkit::gpu().is_none() {
        return;
    }
    let report = own_device::run().unwrap_or_else(|e| panic!("own_device: {e}"));
    // The whole tessellation: 60 quads' 64 cells each and the vertex points.
    let mesh = subdiv_mesh::Mesh::build(subdiv_mesh::shapes::default_model()).unwrap();
    let rates = vec![8; mesh.face_count()];
    assert_eq!(report.vertices, subdiv_tess::dual::predicted_vertex_count(&mesh, subdiv_schemes::Split::Quad, &rates));
    assert!(report.vertices > 60 * 64);
    assert!(report.position <= 1e-5 && report.normal <= 1e-5, "{report}");
    assert!(report.to_string().contains(&report.adapter));
}
