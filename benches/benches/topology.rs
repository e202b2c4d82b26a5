//! Topology construction: `Mesh::build` on a 1000 × 1000 quad grid (one million faces).
//!
//! OpenSubdiv's issue #792 reports about 465 ms for building its topology of such a grid; our
//! target is 150 ms on one thread. Run with `cargo bench -p subdiv-benches --bench topology`.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use subdiv::mesh::{Mesh, shapes};

fn topology(c: &mut Criterion) {
    let mut group = c.benchmark_group("topology");
    group.sample_size(20);
    for size in [100usize, 1000] {
        let soup = shapes::quad_grid(size, size);
        group.bench_function(format!("quad_grid_{}k_faces", size * size / 1000), |b| {
            b.iter_batched(|| soup.clone(), |soup| Mesh::build(soup).expect("grid is valid"), BatchSize::LargeInput);
        });
    }
    group.finish();
}

criterion_group!(benches, topology);
criterion_main!(benches);
