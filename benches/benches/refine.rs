//! Uniform refinement throughput: refined faces per second, one thread.
//!
//! Peers on this machine (`../shared/peers/`): OpenSubdiv Far primvar interpolation 61-149 M
//! faces/s, subdiv-kernels 112 M faces/s (Catmull-Clark, 64×32 torus, level 4) and 373 M faces/s
//! (Loop), opensubdiv-rs 31 M faces/s. Run with `cargo bench -p subdiv-benches --bench refine`;
//! faces/s = refined faces / median time.

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
