//! Uniform refinement throughput: refined faces per second, one thread.
//!
//! Run with `cargo bench -p subdiv-benches --bench refine -- _positions`; faces/s = refined faces
//! / median time. The `_positions` cases time `Refiner::interpolate` alone: what the peers'
//! primvar figures measure. `cargo xtask bench refine` (its own harness, not criterion) measures
//! refinement beside OpenSubdiv's Far in the same rounds.
//!
//! One session on the 2-core machine (shared and noisy: take the figures to ±20 %), 64 × 32
//! torus to level 4, f64 positions:
//!
//! | case | before the stencil palette | after |
//! |---|---|---|
//! | Catmull-Clark, 524,288 faces | 8.11 ms = 65 M faces/s | 4.52 ms = 116 M faces/s |
//! | Loop, 1,048,576 faces | 5.47 ms = 192 M faces/s | 3.23 ms = 325 M faces/s |
//!
//! Peers in the same session (`../shared/peers/`; f32 positions unless said): subdiv-kernels
//! 70-86 M faces/s Catmull-Clark on the same torus (47 M in f64), 182-218 M faces/s Loop on the
//! same-size triangle torus (115 M in f64) and 148-257 M faces/s on the 16 × 8 one (65,536
//! faces, where we reach 320-515 M faces/s); opensubdiv-rs 10-11 M faces/s (31 M on a quiet
//! machine); OpenSubdiv Far (`osd_bench`, 128 × 64 torus to level 3, the same 524,288 faces)
//! 39 M faces/s primvar and 67 M faces/s stencil tables for Catmull-Clark, 48 M and 115 M for
//! Loop. Earlier quiet-machine figures: subdiv-kernels 112 M (Catmull-Clark) and 373 M faces/s
//! (Loop, 16 × 8 torus), OpenSubdiv 61-149 M faces/s.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use subdiv::mesh::{Mesh, shapes};
use subdiv::schemes::{Builtin, RefineOptions, Refiner, refine_uniform};

fn refine(c: &mut Criterion) {
    let mut group = c.benchmark_group("refine");
    group.sample_size(10);
    let cases = [
        ("catmull_clark_torus64x32_level4", Builtin::CatmullClark, shapes::quad_torus(64, 32)),
        ("loop_torus64x32_level4", Builtin::Loop, shapes::triangle_torus(64, 32)),
    ];
    for (name, scheme, soup) in cases {
        let mesh = Mesh::build(soup).expect("torus is valid");
        let refined_faces = mesh.face_count() as u64 * 4u64.pow(4);
        group.throughput(Throughput::Elements(refined_faces));
        // Topology and stencils, then positions: what a first refinement costs.
        group.bench_function(format!("{name}_topology_and_positions"), |b| {
            b.iter(|| refine_uniform(&mesh, scheme.scheme(), 4, &RefineOptions::DEFAULT).expect("refines"));
        });
        // Positions alone through precomputed stencils: the animation case, and what the peers'
        // primvar figures measure.
        let refiner = Refiner::new(&mesh, scheme.scheme(), 4, &RefineOptions::DEFAULT).expect("refines");
        let (mut out, mut scratch) = (Vec::new(), Vec::new());
        group.bench_function(format!("{name}_positions"), |b| {
            b.iter(|| refiner.interpolate(mesh.positions(), &mut out, &mut scratch));
        });
    }
    group.finish();
}

criterion_group!(benches, refine);
criterion_main!(benches);
