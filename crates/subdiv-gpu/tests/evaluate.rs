//! GPU evaluation against the CPU tessellator (f32 against f64): positions to 1e-6 of the
//! model's size and normals to 1e-5 rad (1e-4 on creased meshes, whose patches `l` levels down
//! sum derivative weights of size `2^l` in f32), on procedural, shared and creased meshes, at
//! several rates, over animation frames, with the stencil data split over many buffers, and
//! through the rate cache.

#![allow(clippy::print_stderr)]

use glam::{DVec3, Vec3};
use subdiv_gpu::{Gpu, GpuError, GpuEvalOptions, GpuTessellation, RateCache};
use subdiv_mesh::{Mesh, shapes};
use subdiv_schemes::Builtin;
use subdiv_tess::dual::{PlanError, PlanItem};
use subdiv_tess::rates::ErrorRates;
use subdiv_tess::{
    DualOptions, DualTessellator, EvaluationPlan, FlatMesh, QuadtreeTessellator, TessError, TessMesh, Tolerance,
};

fn diagonal(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.bounding_box().expect("a mesh with vertices");
    (hi - lo).length()
}

/// The worst position distance / bbox diagonal and the worst normal distance, over the flat
/// vertices (the vertices, then one per extra normal at its vertex's position).
fn compare(gpu_vertices: &[f32], cpu: &TessMesh, diag: f64) -> (f64, f64) {
    assert_eq!(gpu_vertices.len(), 6 * cpu.flat_vertex_count());
    let vertices = cpu.positions.len();
    let (mut dp, mut dn) = (0.0f64, 0.0f64);
    for (k, v) in gpu_vertices.chunks_exact(6).enumerate() {
        let p = DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
        let n = DVec3::new(f64::from(v[3]), f64::from(v[4]), f64::from(v[5]));
        let vertex = k.checked_sub(vertices).map_or(k, |e| cpu.normal_vertices[e] as usize);
        dp = dp.max(p.distance(cpu.positions[vertex]) / diag);
        dn = dn.max(n.distance(cpu.normals[k]));
    }
    (dp, dn)
}

/// The cage of animation frame `frame`: twisted about its vertical axis, more each frame.
fn twisted(cage: &[DVec3], frame: usize) -> Vec<DVec3> {
    shapes::twist(cage, 0.3 * frame as f64)
}

struct Case {
    tess: DualTessellator,
    plan: EvaluationPlan,
    flat: FlatMesh,
}

fn case(builtin: Builtin, mesh: &Mesh, rates: &[u32]) -> Case {
    let mut tess = DualTessellator::new(builtin.scheme(), mesh, &DualOptions::default()).unwrap();
    let mut flat = FlatMesh::default();
    tess.tessellate(rates).unwrap();
    tess.write_flat(&mut flat);
    let plan = tess.evaluation_plan();
    Case { tess, plan, flat }
}

/// GPU against CPU on `mesh` at `rates`, then over three animation frames; returns the worst
/// position (× bbox) and normal distances.
fn check(gpu: &Gpu, name: &str, builtin: Builtin, mesh: &Mesh, rates: &[u32]) -> (f64, f64) {
    check_to(gpu, name, builtin, mesh, rates, 1e-5)
}

/// [`check`] with normals to `normal_bound`.
fn check_to(gpu: &Gpu, name: &str, builtin: Builtin, mesh: &Mesh, rates: &[u32], normal_bound: f64) -> (f64, f64) {
    let Case { mut tess, plan, flat } = case(builtin, mesh, rates);
    let diag = diagonal(mesh);
    let on_gpu = GpuTessellation::new(gpu, &plan, &flat.indices, mesh.positions(), &GpuEvalOptions::default()).unwrap();
    assert_eq!(on_gpu.vertex_count() as usize, flat.vertices.len() / 6);
    assert_eq!(on_gpu.index_count() as usize, flat.indices.len());
    let (dp, dn) = compare(&on_gpu.read_vertices(gpu).unwrap(), tess.mesh(), diag);
    eprintln!("{name} at {:?}..: position {dp:.1e} × bbox, normal {dn:.1e}", &rates[..rates.len().min(3)]);
    assert!(dp <= 1e-6 && dn <= normal_bound, "{name}: position {dp:e}, normal {dn:e}");
    let mut worst = (dp, dn);
    for frame in 1..=3 {
        let cage = twisted(mesh.positions(), frame);
        let cpu = tess.update_cage(&cage).unwrap();
        let cage32: Vec<Vec3> = cage.iter().map(|p| p.as_vec3()).collect();
        if frame == 2 {
            // An application's frame: the write and the evaluation in its own submission.
            on_gpu.write_control_points(&gpu.queue, &cage32).unwrap();
            let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
            on_gpu.record(&mut encoder);
            gpu.queue.submit([encoder.finish()]);
        } else {
            on_gpu.update_control_points(gpu, &cage32).unwrap();
        }
        let (dp, dn) = compare(&on_gpu.read_vertices(gpu).unwrap(), cpu, diag);
        assert!(dp <= 1e-6 && dn <= normal_bound, "{name}, frame {frame}: position {dp:e}, normal {dn:e}");
        worst = (worst.0.max(dp), worst.1.max(dn));
    }
    worst
}

/// Creased meshes: the GPU's flat vertices (the crease vertices split, one per normal) are the
/// CPU's, extra normals included, over the animation frames too.
#[test]
fn split_normals_match_the_cpu() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let mut all_sharp = Mesh::build(shapes::cube()).unwrap();
    for e in all_sharp.edges().collect::<Vec<_>>() {
        all_sharp.set_edge_sharpness(e, subdiv_mesh::Tags::INFINITELY_SHARP);
    }
    let mut meshes = vec![("all-sharp cube".to_string(), all_sharp)];
    for file in ["opensubdiv/catmark_cube_creases2.obj", "opensubdiv/catmark_inf_crease1.obj"] {
        let Some(path) = subdiv_testkit::shared_mesh(file) else { break };
        meshes.push((file.to_string(), subdiv_io::load_mesh(&path, &Default::default()).unwrap()));
    }
    for (name, mesh) in meshes {
        for rates in [vec![4; mesh.face_count()], (0..mesh.face_count() as u32).map(|f| 1 + (f * 5) % 9).collect()] {
            let Case { tess, .. } = case(Builtin::CatmullClark, &mesh, &rates);
            assert!(!tess.mesh().normal_vertices.is_empty(), "{name}: no extra normals");
            let (dp, dn) = check(&gpu, &name, Builtin::CatmullClark, &mesh, &rates);
            assert!(dp <= 1e-6 && dn <= 1e-5, "{name}: position {dp:e} × bbox, normal {dn:e}");
        }
    }
}

/// A tolerance's rates: rings around extraordinary points and grids graded toward them, whose
/// cell points are explicit sites like the rings', go through the plan as any other point.
#[test]
fn graded_rings_match_the_cpu() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let cc = Builtin::CatmullClark.scheme();
    for (name, soup) in [("cube", shapes::cube()), ("pentagonal prism", shapes::ngon_prism(5))] {
        let mesh = Mesh::build(soup).unwrap();
        let bounds = QuadtreeTessellator::new(cc, &mesh).unwrap();
        let rates = ErrorRates::new(Tolerance::Relative(1e-2)).rates(&bounds, &mesh).unwrap();
        assert!(rates.rings.graded.iter().any(Option::is_some), "{name}: nothing graded");
        let mut tess = DualTessellator::new(cc, &mesh, &DualOptions::default()).unwrap();
        tess.tessellate_with_rings(&rates.faces, &rates.rings).unwrap();
        let mut flat = FlatMesh::default();
        tess.write_flat(&mut flat);
        let plan = tess.evaluation_plan();
        let on_gpu =
            GpuTessellation::new(&gpu, &plan, &flat.indices, mesh.positions(), &GpuEvalOptions::default()).unwrap();
        let (dp, dn) = compare(&on_gpu.read_vertices(&gpu).unwrap(), tess.mesh(), diagonal(&mesh));
        eprintln!("{name}, graded at 1e-2: position {dp:.1e} × bbox, normal {dn:.1e}");
        assert!(dp <= 1e-6 && dn <= 1e-5, "{name}: position {dp:e}, normal {dn:e}");
    }
}

#[test]
fn procedural_meshes_match_the_cpu() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    eprintln!("adapter: {}", gpu.adapter_name());
    for (builtin, name, soup) in [
        (Builtin::CatmullClark, "cube", shapes::cube()),
        (Builtin::CatmullClark, "pentagonal prism", shapes::ngon_prism(5)),
        (Builtin::CatmullClark, "torus", shapes::quad_torus(8, 6)),
        (Builtin::CatmullClark, "open grid", shapes::quad_grid(4, 3)),
        (Builtin::CatmullClark, "default model", shapes::default_model()),
        (Builtin::Loop, "icosahedron", shapes::icosahedron()),
        // Patches around face corners, on levels 1 and 2.
        (Builtin::DooSabin, "Doo-Sabin pentagonal prism", shapes::ngon_prism(5)),
        (Builtin::Midedge, "mid-edge default model", shapes::default_model()),
        // Ternary levels (two √3 steps of the whole mesh each).
        (Builtin::Sqrt3, "√3 icosahedron", shapes::icosahedron()),
    ] {
        let mesh = Mesh::build(soup).unwrap();
        for rate in [1, 5, 16] {
            check(&gpu, name, builtin, &mesh, &vec![rate; mesh.face_count()]);
        }
        // Independent rates per face.
        let rates: Vec<u32> = (0..mesh.face_count() as u32).map(|f| 1 + (f * 7) % 12).collect();
        check(&gpu, name, builtin, &mesh, &rates);
    }
    // √3 on an open mesh (Kobbelt's boundary rule). Its boundary vertices are irregular points
    // (the boundary's cubic B-spline beside a non-polynomial interior): their normals come from
    // tangent directions — at the grid's corners the eigenvectors of 1/3 and 1/9, the second a
    // curvature-sized term — which the GPU crosses in f32: 1.3e-5 measured on the cage, 6.3e-5
    // on its third twisted frame.
    let open = Mesh::build(shapes::triangulated(shapes::jittered(shapes::quad_grid(4, 3), 0.3))).unwrap();
    for rate in [1, 5, 16] {
        check_to(&gpu, "√3 open grid", Builtin::Sqrt3, &open, &vec![rate; open.face_count()], 1e-4);
    }
    // The dual splits on an open mesh (Chaikin's boundary rule, boundary quads' pieces stretched
    // across them): the boundary's points are irregular too (¾ across it, ½ along), their normals
    // from the boundary curve's tangent and a direction across it.
    let open = Mesh::build(shapes::jittered(shapes::quad_grid(4, 3), 0.3)).unwrap();
    for (builtin, name) in [(Builtin::DooSabin, "Doo-Sabin open grid"), (Builtin::Midedge, "mid-edge open grid")] {
        for rate in [1, 5, 16] {
            check_to(&gpu, name, builtin, &open, &vec![rate; open.face_count()], 1e-4);
        }
    }
}

/// [`check_to`] on shared meshes, each at its three uniform rates.
fn check_shared(gpu: &Gpu, cases: &[(&str, Builtin, [u32; 3])], normal_bound: f64) {
    for &(file, builtin, rates) in cases {
        let Some(path) = subdiv_testkit::shared_mesh(file) else { return };
        let mesh = subdiv_io::load_mesh(&path, &Default::default()).unwrap();
        for rate in rates {
            check_to(gpu, file, builtin, &mesh, &vec![rate; mesh.face_count()], normal_bound);
        }
    }
}

#[test]
fn shared_meshes_match_the_cpu() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let cases = [
        ("opensubdiv/catmark_cube.obj", Builtin::CatmullClark, [4, 8, 32]),
        ("keenan/spot_control_mesh.obj", Builtin::CatmullClark, [2, 8, 16]),
        ("opensubdiv/catmark_nonquads.obj", Builtin::CatmullClark, [3, 8, 12]),
        ("opensubdiv/catmark_hole_test1.obj", Builtin::CatmullClark, [2, 6, 9]),
        ("opensubdiv/loop_cube.obj", Builtin::Loop, [2, 7, 12]),
    ];
    check_shared(&gpu, &cases, 1e-5);
}

/// Creases, corners, semi-sharp creases (refined locally: their plans run through levels) and
/// Chaikin creasing.
#[test]
fn creased_meshes_match_the_cpu() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let cases = [
        ("opensubdiv/catmark_car.obj", Builtin::CatmullClark, [2, 5, 8]),
        ("opensubdiv/catmark_cubes_semisharp.obj", Builtin::CatmullClark, [3, 8, 16]),
        ("opensubdiv/catmark_pyramid_creases0.obj", Builtin::CatmullClark, [3, 8, 16]),
        ("opensubdiv/catmark_chaikin1.obj", Builtin::CatmullClark, [2, 7, 12]),
        ("opensubdiv/loop_cubes_infsharp.obj", Builtin::Loop, [2, 7, 12]),
    ];
    check_shared(&gpu, &cases, 1e-4);
}

/// Tiny buffers split the stencil data over many dispatches; the output is the same, bit for
/// bit (each vertex is computed alone, from the same data).
#[test]
fn split_buffers_give_the_same_bits() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let mesh = Mesh::build(shapes::default_model()).unwrap();
    let Case { plan, flat, .. } = case(Builtin::CatmullClark, &mesh, &vec![6; mesh.face_count()]);
    let whole = GpuTessellation::new(&gpu, &plan, &flat.indices, mesh.positions(), &GpuEvalOptions::default()).unwrap();
    let small = GpuEvalOptions { max_buffer_bytes: 16 << 10, ..GpuEvalOptions::default() };
    let split = GpuTessellation::new(&gpu, &plan, &flat.indices, mesh.positions(), &small).unwrap();
    assert!(split.dispatch_count() > whole.dispatch_count() + 4, "{} dispatches", split.dispatch_count());
    assert_eq!(whole.read_vertices(&gpu).unwrap(), split.read_vertices(&gpu).unwrap());
}

#[test]
fn the_rate_cache_switches_configurations() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let mesh = Mesh::build(shapes::ngon_prism(5)).unwrap();
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default()).unwrap();
    let mut cache = RateCache::new(2);
    let diag = diagonal(&mesh);
    let mut made = 0;
    for (step, rate) in [3u32, 7, 3, 7, 11, 3].into_iter().enumerate() {
        let rates = vec![rate; mesh.face_count()];
        let cage = twisted(mesh.positions(), step);
        let t = cache
            .get(&gpu, &rates, &cage, &GpuEvalOptions::default(), || {
                made += 1;
                let mut flat = FlatMesh::default();
                tess.tessellate_flat(&rates, &mut flat)?;
                Ok((tess.evaluation_plan(), flat.indices))
            })
            .unwrap();
        let vertices = t.read_vertices(&gpu).unwrap();
        let mut cpu = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default()).unwrap();
        cpu.tessellate(&rates).unwrap();
        let (dp, dn) = compare(&vertices, cpu.update_cage(&cage).unwrap(), diag);
        assert!(dp <= 1e-5 && dn <= 1e-5, "step {step}: position {dp:e}, normal {dn:e}");
    }
    // 3 and 7 made once each, 11 made, then 3 again (evicted by 11 with capacity 2).
    assert_eq!(made, 4);
    assert_eq!(cache.len(), 2);
}

#[test]
fn bad_input_is_a_typed_error() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let mesh = Mesh::build(shapes::cube()).unwrap();
    let Case { plan, flat, .. } = case(Builtin::CatmullClark, &mesh, &vec![2; mesh.face_count()]);
    let options = GpuEvalOptions::default();
    let short = &mesh.positions()[..3];
    assert!(matches!(
        GpuTessellation::new(&gpu, &plan, &flat.indices, short, &options),
        Err(GpuError::Tessellation(TessError::CageLength { expected: 8, got: 3 }))
    ));
    let t = GpuTessellation::new(&gpu, &plan, &flat.indices, mesh.positions(), &options).unwrap();
    let mut cage: Vec<Vec3> = mesh.positions().iter().map(|p| p.as_vec3()).collect();
    cage[5].y = f32::NAN;
    assert!(matches!(
        t.update_control_points(&gpu, &cage),
        Err(GpuError::Tessellation(TessError::CagePosition { vertex: 5, .. }))
    ));
    assert!(matches!(
        t.write_control_points(&gpu.queue, &cage),
        Err(GpuError::Tessellation(TessError::CagePosition { vertex: 5, .. }))
    ));
    let bad = [0, 1, u32::MAX];
    assert!(matches!(
        GpuTessellation::new(&gpu, &plan, &bad, mesh.positions(), &options),
        Err(GpuError::Indices { index: u32::MAX, .. })
    ));
}

/// A plan from elsewhere that breaks its rules is refused before anything indexes it (the
/// upload composes and splits the plan, and the shader would read past its buffers).
#[test]
fn malformed_plans_are_refused_by_the_upload() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let mesh = Mesh::build(shapes::ngon_prism(5)).unwrap();
    let Case { plan, flat, .. } = case(Builtin::CatmullClark, &mesh, &vec![3; mesh.face_count()]);
    let options = GpuEvalOptions::default();
    let upload = |change: &dyn Fn(&mut subdiv_tess::dual::PlanParts)| {
        let mut parts = plan.clone().into_parts();
        change(&mut parts);
        let broken = EvaluationPlan::from_parts_unchecked(parts).expect("entries that name records");
        GpuTessellation::new(&gpu, &broken, &flat.indices, mesh.positions(), &options)
    };
    let past = plan.point_count() as u32;
    match upload(&|p| p.points[4] = past) {
        Err(GpuError::Tessellation(TessError::Plan(PlanError::OutOfRange { at: PlanItem::PatchPoint(4), .. }))) => {}
        other => panic!("a point index past the points: {other:?}"),
    }
    match upload(&|p| p.weights[0] = f64::INFINITY) {
        Err(GpuError::Tessellation(TessError::Plan(PlanError::NonFinite { at: PlanItem::Weight(0), .. }))) => {}
        other => panic!("an infinite weight: {other:?}"),
    }
    match upload(&|p| p.general[2].len = 1 << 20) {
        Err(GpuError::Tessellation(TessError::Plan(PlanError::PastEnd { at: PlanItem::General(2), .. }))) => {}
        other => panic!("a stencil past its patch: {other:?}"),
    }
    // The plan itself uploads.
    assert!(GpuTessellation::new(&gpu, &plan, &flat.indices, mesh.positions(), &options).is_ok());
}

/// Texture coordinates on the GPU: each carried channel's plan over its own control values,
/// evaluated as positions are, equals the CPU's exact values (f32 against f64) to 1e-6 at every
/// flat vertex (the seams' second sides included), on spot, blub and `catmark_fvar_bound0..4`
/// at rates 3 and 8.
#[test]
fn texture_coordinates_match_the_cpu() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let mut files = vec!["keenan/spot_control_mesh.obj".to_string(), "keenan/blub_control_mesh.obj".to_string()];
    files.extend((0..5).map(|k| format!("opensubdiv/catmark_fvar_bound{k}.obj")));
    let mut compared = 0;
    for file in &files {
        let Some(path) = subdiv_testkit::shared_mesh(file) else { return };
        let mesh = subdiv_io::load_mesh(&path, &Default::default()).unwrap();
        let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default()).unwrap();
        for rate in [3, 8] {
            let out = tess.tessellate(&vec![rate; mesh.face_count()]).unwrap().clone();
            let (plan, values) = tess.channel_plan("uv").expect("the texture coordinates are carried");
            let on_gpu =
                GpuTessellation::new(&gpu, &plan, &out.flat_indices(), values, &GpuEvalOptions::default()).unwrap();
            let vertices = on_gpu.read_vertices(&gpu).unwrap();
            assert_eq!(vertices.len(), 6 * out.flat_vertex_count());
            let uv = out.channels.find("uv").unwrap();
            let mut worst = 0.0f64;
            for (k, v) in vertices.chunks_exact(6).enumerate() {
                let cpu = &out.channels.point(k)[uv.clone()];
                worst = worst.max((f64::from(v[0]) - cpu[0]).abs()).max((f64::from(v[1]) - cpu[1]).abs());
            }
            eprintln!("{file} at rate {rate}: texture coordinates within {worst:.2e} of the CPU's");
            assert!(worst <= 1e-6, "{file} at rate {rate}: {worst:e}");
            compared += 1;
        }
    }
    assert_eq!(compared, 14);
}
