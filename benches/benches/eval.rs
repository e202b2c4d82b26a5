//! Eigenbasis evaluation (subdiv-eval): exact limit points per second at pseudo-random `(u, v)`,
//! one thread, with first derivatives (`_d1`) and with second derivatives too (`_d2`): on one
//! regular Catmull-Clark patch, one valence-5 Catmull-Clark patch, one valence-7 Loop patch
//! (`PatchSurface`, the per-face object), and over whole meshes through `EigenEvaluator`
//! (random face, random point; and the same points grouped by face, `_by_face`): a 64 × 64 quad torus, OpenSubdiv's `catmark_righthanded` and
//! the creased `catmark_car` (every face: crease patches through the exact stencils) from the
//! shared corpus (`SUBDIV_SHARED`, default `../shared`; skipped when absent). Points/s = points
//! / median time. Run with `cargo xtask bench eval`.

use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use subdiv::eval::{EigenBasis, EigenEvaluator, Method};
use subdiv::mesh::{DVec3, FaceId, Mesh, shapes};
use subdiv::schemes::{Builtin, RefineOptions};

const POINTS: usize = 1 << 14;

/// Deterministic pseudo-random numbers in [0, 1) (64-bit LCG, top 53 bits).
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn parameters(triangle: bool) -> Vec<(f64, f64)> {
    let mut r = uniform(7);
    (0..POINTS)
        .map(|_| {
            let (u, v) = (r(), r());
            if triangle && u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) }
        })
        .collect()
}

fn patches(c: &mut Criterion) {
    let mut group = c.benchmark_group("eval");
    group.throughput(Throughput::Elements(POINTS as u64));
    for (name, builtin, valence) in [
        ("patch_catmull_clark_regular", Builtin::CatmullClark, 4),
        ("patch_catmull_clark_valence5", Builtin::CatmullClark, 5),
        ("patch_loop_valence7", Builtin::Loop, 7),
    ] {
        let basis = EigenBasis::interior(builtin.scheme(), valence).expect("built-in eigenbasis");
        let mut r = uniform(valence as u64);
        let points: Vec<DVec3> = (0..basis.size()).map(|_| DVec3::new(r(), r(), r())).collect();
        let surface = basis.surface(&points).expect("sized control points");
        let params = parameters(builtin == Builtin::Loop);
        group.bench_function(format!("{name}_d1"), |b| {
            b.iter(|| {
                for &(u, v) in &params {
                    std::hint::black_box(surface.eval(u, v).expect("inside"));
                }
            });
        });
        group.bench_function(format!("{name}_d2"), |b| {
            b.iter(|| {
                for &(u, v) in &params {
                    std::hint::black_box(surface.eval_second(u, v).expect("inside"));
                }
            });
        });
    }
    let shared = std::env::var_os("SUBDIV_SHARED").map_or_else(|| PathBuf::from("../shared"), PathBuf::from);
    let corpus = shared.join("testdata/meshes/opensubdiv");
    // (name, mesh, whether every face is asked, not only those the eigenbasis takes).
    let mut meshes = vec![("mesh_quad_torus_64x64", Mesh::build(shapes::quad_torus(64, 64)).expect("torus"), false)];
    for (file, name, all) in
        [("catmark_righthanded.obj", "mesh_catmark_righthanded", false), ("catmark_car.obj", "mesh_catmark_car", true)]
    {
        if let Ok(mesh) = subdiv::io::load_mesh(corpus.join(file), &Default::default()) {
            meshes.push((name, mesh, all));
        }
    }
    for (name, mesh, all) in meshes {
        let eval = EigenEvaluator::new(Builtin::CatmullClark.scheme(), &mesh, &RefineOptions::DEFAULT, Method::Auto)
            .expect("evaluator");
        let mut r = uniform(11);
        // Faces the eigenbasis takes (all of a closed mesh's), or for the creased car every face
        // (`Method::Auto` routes its crease patches to the exact stencils); quads only so
        // (u, v) ∈ [0, 1]².
        let faces: Vec<FaceId> = mesh
            .face_ids()
            .filter(|&f| mesh.face_size(f) == 4 && (all || eval.uses_eigenbasis(f).is_ok_and(|r| r.is_ok())))
            .collect();
        let samples: Vec<(FaceId, f64, f64)> =
            (0..POINTS).map(|_| (faces[(r() * faces.len() as f64) as usize], r(), r())).collect();
        group.bench_function(format!("{name}_d1"), |b| {
            b.iter(|| {
                for &(f, u, v) in &samples {
                    std::hint::black_box(eval.eval(f, u, v).expect("inside"));
                }
            });
        });
        // The same points grouped by face, faces in order, as a tessellator asks for them.
        let mut by_face = samples.clone();
        by_face.sort_by_key(|&(f, ..)| f.index());
        group.bench_function(format!("{name}_by_face_d1"), |b| {
            b.iter(|| {
                for &(f, u, v) in &by_face {
                    std::hint::black_box(eval.eval(f, u, v).expect("inside"));
                }
            });
        });
        // Second derivatives are the eigenbasis's alone (the exact stencils give first ones).
        if all {
            continue;
        }
        group.bench_function(format!("{name}_d2"), |b| {
            b.iter(|| {
                for &(f, u, v) in &samples {
                    std::hint::black_box(eval.eval_second(f, u, v).expect("inside"));
                }
            });
        });
    }
    group.finish();
}

criterion_group!(benches, patches);
criterion_main!(benches);
