//! Dual-grid stitching (subdiv-tess `DualTessellator`), one thread (`Parallelism::Serial`):
//! triangles per second (Throughput::Elements = output triangles) at uniform rates 8, 16, 32 on
//! a regular 128 × 64 quad torus (every face on the separable bicubic route), the cube (every
//! face through its children: exact stencils) and the default model. Four measurements per
//! case: `tessellate` (topology, stencil records and evaluation), `tessellate_flat` (the same
//! straight into the welded f32 buffers, without surface parameters), `update_cage` (the animation
//! path: f64 positions and normals only) and `update_cage_flat` (the animation path straight
//! into the welded f32 buffers a renderer uploads, indices included). Run with
//! `cargo bench -p subdiv-benches --bench tess`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use subdiv::mesh::{Mesh, shapes};
use subdiv::schemes::Builtin;
use subdiv::tess::{DualOptions, DualTessellator, FlatMesh, Parallelism};

fn dual(c: &mut Criterion) {
    let mut group = c.benchmark_group("dual");
    group.sample_size(10);
    let options = DualOptions::DEFAULT.with_parallelism(Parallelism::Serial);
    for (name, soup) in [
        ("torus128x64", shapes::quad_torus(128, 64)),
        ("cube", shapes::cube()),
        ("default_model", shapes::default_model()),
    ] {
        let mesh = Mesh::build(soup).expect("procedural meshes build");
        for rate in [8u32, 16, 32] {
            let mut tess =
                DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &options).expect("Catmull-Clark takes it");
            let rates = vec![rate; tess.face_count()];
            let triangles = tess.tessellate(&rates).expect("valid rates").triangles.len();
            group.throughput(Throughput::Elements(triangles as u64));
            group.bench_function(format!("{name}_n{rate}_tessellate"), |b| {
                b.iter(|| std::hint::black_box(tess.tessellate(&rates).expect("valid rates").triangles.len()));
            });
            let mut flat = FlatMesh::default();
            group.bench_function(format!("{name}_n{rate}_tessellate_flat"), |b| {
                b.iter(|| {
                    tess.tessellate_flat(&rates, &mut flat).expect("valid rates");
                    std::hint::black_box(flat.indices.len())
                });
            });
            let cage = mesh.positions().to_vec();
            group.bench_function(format!("{name}_n{rate}_update_cage"), |b| {
                b.iter(|| std::hint::black_box(tess.update_cage(&cage).expect("finite cage").positions.len()));
            });
            group.bench_function(format!("{name}_n{rate}_update_cage_flat"), |b| {
                b.iter(|| {
                    tess.update_cage_flat(&cage, &mut flat).expect("finite cage");
                    std::hint::black_box(flat.indices.len())
                });
            });
        }
    }
    group.finish();
}

criterion_group!(benches, dual);
criterion_main!(benches);
