//! Surface stencils on demand: stencils (position and both tangents) per second, one thread, by
//! periodic addresses over the derived sub-patch matrices, at the primal grid points of rate
//! n = 7 (denominators with a 3-digit period) of a regular and an extraordinary Catmull-Clark
//! patch and a Loop patch — each point alone (`surface_stencil`), and the whole grid through
//! one `StencilEvaluator` that shares work between points; then whole stencil tables (both
//! grids, rate 16). Stencils/s = points / median time. Run with `cargo xtask bench stencil`.
//! Figures are in the Stencils issue note.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use subdiv::mesh::BoundaryInterpolation;
use subdiv::schemes::{Builtin, PatchMatrices, PatchType};
use subdiv::stencil::{Dyadic, StencilEvaluator, StencilTable, surface_stencil};

fn stencils(c: &mut Criterion) {
    let mut group = c.benchmark_group("stencil");
    group.sample_size(10);
    let n = 7;
    let cases = [
        ("catmull_clark_regular_n7", Builtin::CatmullClark, 4),
        ("catmull_clark_valence5_n7", Builtin::CatmullClark, 5),
        ("loop_valence7_n7", Builtin::Loop, 7),
    ];
    for (name, builtin, valence) in cases {
        let matrices =
            PatchMatrices::of(builtin.scheme(), PatchType::interior(valence), BoundaryInterpolation::EdgeOnly)
                .expect("built-in patch matrices");
        let points: Vec<Dyadic> = (0..=n)
            .flat_map(|j| (0..=n).map(move |i| Dyadic::new(i, j, n)))
            .filter(|p| matrices.face_size == 4 || p.u + p.v <= n)
            .collect();
        group.throughput(Throughput::Elements(points.len() as u64));
        group.bench_function(name, |b| {
            b.iter(|| {
                for &p in &points {
                    std::hint::black_box(surface_stencil(&matrices, 0, p).expect("inside the face"));
                }
            });
        });
        group.bench_function(format!("{name}_shared"), |b| {
            b.iter(|| {
                let mut evaluator = StencilEvaluator::new(&*matrices);
                for &p in &points {
                    std::hint::black_box(evaluator.stencil(0, p).expect("inside the face"));
                }
            });
        });
        let rate = 16;
        let table = StencilTable::compute_rates(&matrices, BoundaryInterpolation::EdgeOnly, rate..=rate)
            .expect("built-in tables")
            .remove(0);
        group.throughput(Throughput::Elements(table.stored_points() as u64));
        group.bench_function(format!("{}_table_n{rate}", name.trim_end_matches("_n7")), |b| {
            b.iter(|| {
                std::hint::black_box(
                    StencilTable::compute_rates(&matrices, BoundaryInterpolation::EdgeOnly, rate..=rate)
                        .expect("built-in tables"),
                )
            });
        });
    }
    group.finish();
}

criterion_group!(benches, stencils);
criterion_main!(benches);
