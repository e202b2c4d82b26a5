//! Uniform refinement has two paths to the refined positions: the masks applied to the values
//! level by level (`refine_uniform`, what `subdiv refine` runs), and stencil rows
//! (`Refiner`, for callers that re-apply them). Both must give the same mesh on every shared
//! mesh: the same faces, sharpness, holes and channels, positions to 1e-14 × the bounding box.

#![allow(clippy::print_stderr)]

use subdiv::mesh::Mesh;
use subdiv::schemes::{Builtin, RefineOptions, Refiner, refine_uniform};
use subdiv_testkit::shared_meshes;

fn assert_same_mesh(name: &str, direct: &Mesh, rows: &Mesh) {
    assert!(direct.faces().eq(rows.faces()), "{name}: faces differ");
    assert_eq!(direct.vertex_count(), rows.vertex_count(), "{name}: vertex counts");
    for e in direct.edges() {
        assert_eq!(direct.edge_sharpness(e), rows.edge_sharpness(e), "{name}: sharpness of edge {e}");
    }
    for v in direct.vertices() {
        assert_eq!(direct.vertex_sharpness(v), rows.vertex_sharpness(v), "{name}: sharpness of vertex {v}");
    }
    for f in direct.face_ids() {
        assert_eq!(direct.is_hole(f), rows.is_hole(f), "{name}: hole flag of face {f}");
    }
    assert_eq!(direct.channels(), rows.channels(), "{name}: channels");
    // The two paths sum in other orders: a vertex of valence k sums k spokes (and k faces), each
    // rounded, so past valence 11 the bound grows with k (catmark_pole360: 2.1e-14 × bbox).
    let (lo, hi) = rows.bounding_box().expect("refined meshes have vertices");
    let valence = direct.vertices().map(|v| direct.valence(v)).max().unwrap_or(0);
    let tolerance = (hi - lo).length() * 1e-14_f64.max(valence as f64 * 4.0 * f64::EPSILON);
    for (v, (a, b)) in direct.positions().iter().zip(rows.positions()).enumerate() {
        assert!(a.distance(*b) <= tolerance, "{name}: vertex {v} at {a}, the stencils' at {b}");
    }
}

#[test]
fn refined_values_equal_the_stencil_rows_on_every_shared_mesh() {
    let meshes = shared_meshes();
    assert!(subdiv_testkit::shared_dir().is_none() || meshes.len() > 100, "the shared corpus is missing");
    let mut compared = 0;
    for (path, builtin, mesh) in &meshes {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        // Bilinear takes every mesh; Schaefer and Warren's, the four-point and Butterfly rules
        // take closed meshes without tags (the last two go through stencil rows on both paths).
        let extra = match builtin {
            Builtin::Loop => vec![Builtin::Bilinear, Builtin::Butterfly],
            _ => vec![Builtin::Bilinear, Builtin::Kobbelt, Builtin::SwQuad],
        };
        for scheme in std::iter::once(*builtin).chain(extra) {
            for levels in 1..=2 {
                let options = RefineOptions::DEFAULT;
                let Ok(direct) = refine_uniform(mesh, scheme.scheme(), levels, &options) else {
                    assert!(scheme != *builtin, "{name}: its own scheme refuses it");
                    continue;
                };
                let rows = Refiner::new(mesh, scheme.scheme(), levels, &options).expect("the same checks").into_mesh();
                assert_same_mesh(&format!("{name} ({scheme:?}, {levels} levels)"), &direct, &rows);
                compared += 1;
            }
        }
    }
    eprintln!("{compared} refined meshes compared");
}

#[test]
fn stencil_tables_reproduce_the_refined_positions_on_every_shared_mesh() {
    let mut compared = 0;
    for (path, builtin, mesh) in &shared_meshes() {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        for levels in [1, 3] {
            let Ok(refiner) = Refiner::new(mesh, builtin.scheme(), levels, &RefineOptions::DEFAULT) else {
                panic!("{name}: its own scheme refuses it");
            };
            let table = refiner.stencil_table();
            assert_eq!((table.len(), table.cage_count()), (refiner.mesh().vertex_count(), mesh.vertex_count()));
            let mut out = Vec::new();
            table.apply(mesh.positions(), &mut out);
            let (lo, hi) = refiner.mesh().bounding_box().expect("refined meshes have vertices");
            for (v, (a, b)) in out.iter().zip(refiner.mesh().positions()).enumerate() {
                assert!(
                    a.distance(*b) <= 1e-12 * (hi - lo).length(),
                    "{name}, {levels} levels: vertex {v} at {a}, {b}"
                );
            }
            compared += 1;
        }
    }
    eprintln!("{compared} stencil tables compared");
}

#[test]
fn threads_change_no_bit_of_a_refinement() {
    use subdiv::mesh::{Parallelism, shapes};
    // Large enough that every pass forks (`MIN_PARALLEL_ITEMS` items and more).
    let cases = [
        (Builtin::CatmullClark, shapes::quad_torus(128, 64)),
        (Builtin::Loop, shapes::triangle_torus(96, 48)),
        (Builtin::Bilinear, shapes::quad_torus(128, 64)),
    ];
    for (builtin, soup) in cases {
        let mut mesh = Mesh::build(soup).unwrap();
        // A semi-sharp edge and a corner, so that the crease rules run on the threads too.
        mesh.set_edge_sharpness(subdiv::mesh::EdgeId::new(5), 2.5);
        mesh.set_vertex_sharpness(subdiv::mesh::VertexId::new(700), 1.5);
        let refine = |parallelism| {
            let options = RefineOptions::DEFAULT.with_parallelism(parallelism);
            refine_uniform(&mesh, builtin.scheme(), 2, &options).unwrap()
        };
        let (serial, threads) = (refine(Parallelism::Serial), refine(Parallelism::Rayon));
        assert!(serial.faces().eq(threads.faces()), "{builtin:?}: faces");
        assert_eq!(serial.positions(), threads.positions(), "{builtin:?}: positions");
        assert!(serial.edges().all(|e| serial.edge_sharpness(e) == threads.edge_sharpness(e)));
    }
}
