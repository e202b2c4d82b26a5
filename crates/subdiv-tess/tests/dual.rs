//! Dual-grid stitching: watertightness and topology at random per-face rates, boundaries, every
//! vertex on the exact limit surface, the animation path, evaluation plans, thread counts, and
//! typed errors. Rings around extraordinary points: `dual_rings.rs`.

#![allow(clippy::print_stderr)]

mod dual_support;

use std::collections::HashMap;

use glam::DVec3;
use proptest::prelude::*;
use subdiv_mesh::{FaceId, Mesh, PolygonSoup, shapes};
use subdiv_schemes::{Builtin, RefineOptions};
use subdiv_tess::dual::PlanEntry;
use subdiv_tess::{DualOptions, DualTessellator, FlatMesh, Parallelism, TessError, TessMesh};

use dual_support::*;

#[test]
fn closed_quad_meshes_are_watertight_at_random_rates() {
    for (name, mesh) in quad_meshes() {
        for seed in 0..4 {
            let rates = rates_for(&mesh, seed, 12);
            eprintln!("{name}, seed {seed}");
            closed_checks(Builtin::CatmullClark, &mesh, &rates);
        }
        let ones = vec![1; mesh.face_count()];
        closed_checks(Builtin::CatmullClark, &mesh, &ones);
    }
    // Other quad splits: Kobbelt (valences 3 and 5: its patches there reach four rings); bilinear
    // away from extraordinary vertices (some of its exact stencils there are not unique: a typed
    // error from the stencils, `TessError::Surface`); the dual splits, whose patches are the
    // faces' corners (Doo-Sabin, and mid-edge by its two steps).
    let cube = Mesh::build(shapes::cube()).unwrap();
    closed_checks(Builtin::Kobbelt, &cube, &rates_for(&cube, 5, 9));
    let model = Mesh::build(shapes::default_model()).unwrap();
    closed_checks(Builtin::Kobbelt, &model, &rates_for(&model, 3, 4));
    let prism = Mesh::build(shapes::ngon_prism(5)).unwrap();
    closed_checks(Builtin::DooSabin, &prism, &rates_for(&prism, 4, 7));
    closed_checks(Builtin::Midedge, &model, &rates_for(&model, 2, 5));
    let torus = Mesh::build(shapes::quad_torus(4, 3)).unwrap();
    closed_checks(Builtin::Bilinear, &torus, &rates_for(&torus, 6, 9));
}

#[test]
fn triangle_schemes_are_watertight_at_random_rates() {
    for soup in [shapes::icosahedron(), shapes::triangle_torus(6, 4), shapes::octahedron(), shapes::tetrahedron()] {
        let mesh = Mesh::build(soup).unwrap();
        for seed in 0..4 {
            let rates = rates_for(&mesh, seed, 12);
            closed_checks(Builtin::Loop, &mesh, &rates);
        }
        closed_checks(Builtin::Butterfly, &mesh, &rates_for(&mesh, 9, 6));
    }
}

#[test]
fn open_meshes_keep_their_boundary_loops() {
    let grid = Mesh::build(shapes::quad_grid(4, 3)).unwrap();
    for seed in 0..4 {
        open_checks(Builtin::CatmullClark, &grid, &rates_for(&grid, seed, 9));
    }
    let pole = Mesh::build(shapes::pole(5)).unwrap();
    open_checks(Builtin::CatmullClark, &pole, &rates_for(&pole, 3, 9));
    // An open triangle grid (each unit quad of a domed grid cut at a diagonal) under Loop.
    let quads = shapes::quad_grid(4, 3);
    let mut soup = PolygonSoup::default();
    for p in quads.positions() {
        soup.push_vertex(*p + DVec3::Z * 0.1 * (p.x * p.y).sin());
    }
    for f in quads.faces() {
        soup.push_face([f[0], f[1], f[2]]);
        soup.push_face([f[0], f[2], f[3]]);
    }
    let triangles = Mesh::build(soup).unwrap();
    for seed in 0..3 {
        open_checks(Builtin::Loop, &triangles, &rates_for(&triangles, seed, 9));
    }
    on_limit_surface(Builtin::Loop, &triangles, &rates_for(&triangles, 7, 5));
    // A closed triangle mesh with a hole.
    let mut soup = shapes::icosahedron();
    soup.tags.holes.push(FaceId::new(0));
    let holed = Mesh::build(soup).unwrap();
    open_checks(Builtin::Loop, &holed, &rates_for(&holed, 5, 9));
    // Holes in a quad mesh: one face of the cube, and a face of the pentagonal prism.
    let mut soup = shapes::cube();
    soup.tags.holes.push(FaceId::new(2));
    let cube = Mesh::build(soup).unwrap();
    open_checks(Builtin::CatmullClark, &cube, &rates_for(&cube, 1, 9));
    let mut soup = shapes::ngon_prism(5);
    soup.tags.holes.push(FaceId::new(0));
    let prism = Mesh::build(soup).unwrap();
    open_checks(Builtin::CatmullClark, &prism, &rates_for(&prism, 2, 9));
}

#[test]
fn vertices_are_on_the_limit_surface() {
    let cube = Mesh::build(shapes::cube()).unwrap();
    on_limit_surface(Builtin::CatmullClark, &cube, &rates_for(&cube, 1, 7));
    let refined = refined_cube();
    on_limit_surface(Builtin::CatmullClark, &refined, &rates_for(&refined, 11, 9));
    let prism = Mesh::build(shapes::ngon_prism(5)).unwrap();
    on_limit_surface(Builtin::CatmullClark, &prism, &rates_for(&prism, 2, 7));
    let torus = Mesh::build(shapes::quad_torus(5, 4)).unwrap();
    on_limit_surface(Builtin::CatmullClark, &torus, &rates_for(&torus, 3, 7));
    let model = Mesh::build(shapes::default_model()).unwrap();
    on_limit_surface(Builtin::CatmullClark, &model, &rates_for(&model, 4, 5));
    let grid = Mesh::build(shapes::quad_grid(3, 3)).unwrap();
    on_limit_surface(Builtin::CatmullClark, &grid, &rates_for(&grid, 5, 7));
    on_limit_surface(Builtin::Bilinear, &torus, &rates_for(&torus, 8, 5));
    on_limit_surface(Builtin::Kobbelt, &cube, &rates_for(&cube, 9, 5));
    on_limit_surface(Builtin::Kobbelt, &model, &rates_for(&model, 3, 4));
    let prism = Mesh::build(shapes::ngon_prism(5)).unwrap();
    on_limit_surface(Builtin::DooSabin, &prism, &rates_for(&prism, 7, 4));
    on_limit_surface(Builtin::Midedge, &model, &rates_for(&model, 5, 3));
    let ico = Mesh::build(shapes::icosahedron()).unwrap();
    on_limit_surface(Builtin::Loop, &ico, &rates_for(&ico, 6, 6));
    on_limit_surface(Builtin::Butterfly, &ico, &rates_for(&ico, 10, 4));
    let tri_torus = Mesh::build(shapes::triangle_torus(6, 4)).unwrap();
    on_limit_surface(Builtin::Loop, &tri_torus, &rates_for(&tri_torus, 7, 5));
}

#[test]
fn shared_meshes_are_on_the_limit_surface_and_watertight() {
    for (file, builtin) in [
        ("opensubdiv/catmark_cube.obj", Builtin::CatmullClark),
        ("keenan/spot_control_mesh.obj", Builtin::CatmullClark),
        ("opensubdiv/loop_cube.obj", Builtin::Loop),
        ("opensubdiv/catmark_hole_test1.obj", Builtin::CatmullClark),
        ("opensubdiv/catmark_quadstrips.obj", Builtin::CatmullClark),
        ("opensubdiv/catmark_nonquads.obj", Builtin::CatmullClark),
    ] {
        let Some(path) = subdiv_testkit::shared_mesh(file) else { return };
        let mesh = subdiv_io::load_mesh(&path, &Default::default()).unwrap();
        let rates = rates_for(&mesh, 11, 4);
        let out = tessellate(builtin, &mesh, &rates);
        let border = check(&out);
        if mesh.boundary_edge_count() == 0 && !mesh.face_ids().any(|f| mesh.is_hole(f)) {
            assert!(border.is_empty(), "{file}: cracks");
        } else {
            open_checks(builtin, &mesh, &rates);
        }
        eprintln!("{file}");
        on_limit_surface(builtin, &mesh, &rates);
    }
}

#[test]
fn creased_meshes_are_watertight_and_on_the_limit_surface() {
    for (name, builtin, mesh) in creased_meshes() {
        for rates in [vec![3; mesh.face_count()], vec![8; mesh.face_count()], rates_for(&mesh, 17, 7)] {
            let out = tessellate(builtin, &mesh, &rates);
            check_facing(&out, &mesh);
            assert!(check(&out).is_empty(), "{name}: cracks");
            assert_eq!(euler(&out), input_euler(&mesh), "{name}");
            // One vertex per position: welded along the creases too.
            let mut seen: HashMap<[u64; 3], usize> = HashMap::new();
            for (i, p) in out.positions.iter().enumerate() {
                let key = p.to_array().map(f64::to_bits);
                assert!(seen.insert(key, i).is_none(), "{name}: vertex {i} repeats a position");
            }
        }
        eprintln!("{name}");
        on_limit_surface(builtin, &mesh, &rates_for(&mesh, 19, 6));
    }
}

/// The points a tessellation puts on an infinitely sharp edge lie on the crease curve: on a
/// torus's sharp ring of regular crease vertices, the cubic B-spline of the ring's vertices.
#[test]
fn crease_points_are_on_the_crease_curve() {
    let (name, builtin, mesh) = creased_meshes().swap_remove(2);
    let out = tessellate(builtin, &mesh, &vec![5; mesh.face_count()]);
    let (m, n) = (6usize, 5usize);
    let ring: Vec<DVec3> = (0..m).map(|i| mesh.position(subdiv_mesh::VertexId::new((i * n) as u32))).collect();
    let mut on_ring = 0;
    for (s, p) in out.parameters.iter().zip(&out.positions) {
        // Face (i, 0) has the ring as its first side (v = 0).
        let (f, i) = (s.face.index(), s.face.index() / n);
        if f % n != 0 || s.v != 0.0 {
            continue;
        }
        let u = s.u;
        let b = [
            (1.0 - u).powi(3) / 6.0,
            (3.0 * u.powi(3) - 6.0 * u * u + 4.0) / 6.0,
            (-3.0 * u.powi(3) + 3.0 * u * u + 3.0 * u + 1.0) / 6.0,
            u.powi(3) / 6.0,
        ];
        let want: DVec3 = (0..4).map(|k| ring[(i + m + k - 1) % m] * b[k]).sum();
        assert!((*p - want).length() < 1e-13, "{name}: face {f} at u = {u}: {p:?} vs {want:?}");
        on_ring += 1;
    }
    assert!(on_ring >= m * 4, "{name}: {on_ring} points on the ring");
}

#[test]
fn update_cage_equals_a_fresh_tessellation() {
    for (builtin, mesh) in [
        (Builtin::CatmullClark, shapes::cube()),
        (Builtin::CatmullClark, shapes::ngon_prism(5)),
        (Builtin::CatmullClark, shapes::quad_torus(5, 4)),
        (Builtin::CatmullClark, shapes::quad_grid(3, 2)),
        (Builtin::Loop, shapes::icosahedron()),
    ]
    .into_iter()
    .map(|(builtin, soup)| (builtin, Mesh::build(soup).unwrap()))
    .chain(creased_meshes().into_iter().map(|(_, builtin, mesh)| (builtin, mesh)))
    {
        let rates = rates_for(&mesh, 21, 9);
        let mut tess = DualTessellator::new(builtin.scheme(), &mesh, &DualOptions::default()).unwrap();
        tess.tessellate(&rates).unwrap();
        let moved: Vec<DVec3> = mesh
            .positions()
            .iter()
            .enumerate()
            .map(|(i, p)| *p * 1.5 + DVec3::new((i as f64).sin(), (i as f64 * 0.7).cos(), 0.25 * i as f64))
            .collect();
        let animated = tess.update_cage(&moved).unwrap().clone();
        let mut moved_mesh = mesh.clone();
        moved_mesh.positions_mut().copy_from_slice(&moved);
        let mut fresh_tess = DualTessellator::new(builtin.scheme(), &moved_mesh, &DualOptions::default()).unwrap();
        let fresh = fresh_tess.tessellate(&rates).unwrap();
        assert_eq!(animated.triangles, fresh.triangles);
        assert_eq!(animated.positions, fresh.positions, "{builtin:?}: positions differ");
        // The extra normals of crease points too.
        assert_eq!(animated.normals, fresh.normals);
        assert_eq!(animated.normal_vertices, fresh.normal_vertices);
        assert_eq!(animated.triangle_normals, fresh.triangle_normals);
        // Straight into f32: the same as the f64 output written flat.
        let (mut direct, mut written) = (FlatMesh::default(), FlatMesh::default());
        fresh_tess.write_flat(&mut written);
        tess.update_cage_flat(&moved, &mut direct).unwrap();
        assert_eq!(direct, written, "{builtin:?}: update_cage_flat");
        // The flat-only tessellation: the same buffers, and the same animation after it.
        let mut flat_tess = DualTessellator::new(builtin.scheme(), &moved_mesh, &DualOptions::default()).unwrap();
        let mut stale = FlatMesh { vertices: vec![7.0; 5], indices: vec![3; 2], ..FlatMesh::default() };
        flat_tess.tessellate_flat(&rates, &mut stale).unwrap();
        assert_eq!(stale, written, "{builtin:?}: tessellate_flat");
        assert_eq!(flat_tess.mesh(), &TessMesh::default(), "{builtin:?}: the mesh is left empty");
        flat_tess.update_cage_flat(&moved, &mut stale).unwrap();
        assert_eq!(stale, written, "{builtin:?}: update_cage_flat after tessellate_flat");
        // The first `update_cage` after it makes the whole mesh, as `tessellate` does.
        assert_eq!(flat_tess.update_cage(&moved).unwrap(), fresh_tess.mesh(), "{builtin:?}: update_cage after it");
        assert_eq!(flat_tess.update_cage(&moved).unwrap(), fresh_tess.mesh(), "{builtin:?}: and the next one");
        // New rates: the animation copies the new indices, not those of the last rates.
        let other = rates_for(&mesh, 5, 9);
        flat_tess.tessellate_flat(&other, &mut stale).unwrap();
        flat_tess.update_cage_flat(&moved, &mut stale).unwrap();
        fresh_tess.tessellate(&other).unwrap();
        fresh_tess.write_flat(&mut written);
        assert_eq!(stale, written, "{builtin:?}: update_cage_flat after tessellate_flat at new rates");
    }
}

/// A tessellation streamed in chunks is the flat tessellation, bit for bit, at any chunk size:
/// quads, N-gons, triangles (Loop's and √3's), boundaries, holes, infinitely sharp creases
/// (extra normals, made in one chunk for a vertex of an earlier one) and texture coordinates
/// with seams, on one thread and on rayon's. (The stream numbers the extra normals after the
/// predicted vertex count, which √3's triangle cells once missed.)
#[test]
fn streamed_tessellations_are_the_flat_ones_at_any_chunk_size() {
    let mut uv = shapes::cube();
    let square = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
    uv.channels.push(subdiv_mesh::Channel::new("uv", 2, square.repeat(6), (0..24).map(|i| i % 4).collect()));
    let mut holed = shapes::quad_torus(5, 4);
    holed.tags.holes.push(FaceId::new(3));
    let cases = [
        (Builtin::CatmullClark, Mesh::build(uv).unwrap()),
        (Builtin::CatmullClark, Mesh::build(shapes::ngon_prism(5)).unwrap()),
        (Builtin::CatmullClark, Mesh::build(shapes::quad_grid(4, 3)).unwrap()),
        (Builtin::CatmullClark, Mesh::build(holed).unwrap()),
        (Builtin::CatmullClark, Mesh::build(shapes::default_model()).unwrap()),
        (Builtin::Loop, Mesh::build(shapes::triangle_torus(6, 4)).unwrap()),
        (Builtin::Loop, Mesh::build(shapes::icosahedron()).unwrap()),
        (Builtin::DooSabin, Mesh::build(shapes::ngon_prism(5)).unwrap()),
        (Builtin::Sqrt3, Mesh::build(shapes::icosahedron()).unwrap()),
    ]
    .into_iter()
    .chain(creased_meshes().into_iter().map(|(_, builtin, mesh)| (builtin, mesh)));
    for (k, (builtin, mesh)) in cases.enumerate() {
        let rates = rates_for(&mesh, 31 + k as u64, 7);
        let mut whole = FlatMesh::default();
        let mut tess = DualTessellator::new(builtin.scheme(), &mesh, &DualOptions::DEFAULT).unwrap();
        tess.tessellate_flat(&rates, &mut whole).unwrap();
        for (chunk, parallelism) in [
            (1, Parallelism::Serial),
            (37, Parallelism::Rayon),
            (500, Parallelism::Serial),
            (1 << 20, Parallelism::Rayon),
        ] {
            let options = DualOptions::DEFAULT.with_chunk(chunk).with_parallelism(parallelism);
            tess.set_options(&options);
            let mut streamed = FlatMesh { vertices: vec![1.0; 3], ..FlatMesh::default() };
            let counts = tess.tessellate_stream(&rates, &mut streamed).unwrap();
            assert_eq!(counts, (whole.vertices.len() / 6, whole.indices.len() / 3), "{builtin:?} {k}: counts");
            assert_eq!(streamed, whole, "{builtin:?} {k}: chunks of {chunk}");
            assert!(tess.rates().is_empty() && tess.mesh().triangles.is_empty(), "nothing kept");
        }
    }
}

/// The plan's f64 evaluation against the tessellator's own, on a moved cage: one entry per
/// flat vertex (the vertices, then the extra normals at their vertices' positions).
fn check_plan(name: &str, tess: &DualTessellator, cage: &[DVec3], out: &TessMesh) {
    let plan = tess.evaluation_plan();
    assert_eq!(plan.vertex_count(), out.flat_vertex_count(), "{name}: one entry per flat vertex");
    assert_eq!(plan.entries().len(), out.flat_vertex_count(), "{name}: one entry per flat vertex");
    plan.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
    let (mut positions, mut normals) = (Vec::new(), Vec::new());
    plan.evaluate(cage, &mut positions, &mut normals);
    // Over the cage's own points: the same values.
    let flat = plan.over_cage();
    assert!(flat.levels().is_empty() && flat.point_count() == cage.len(), "{name}: refined points left");
    flat.validate().unwrap_or_else(|e| panic!("{name}: over the cage: {e}"));
    let (mut flat_positions, mut flat_normals) = (Vec::new(), Vec::new());
    flat.evaluate(cage, &mut flat_positions, &mut flat_normals);
    positions.iter().zip(&flat_positions).chain(normals.iter().zip(&flat_normals)).for_each(|(a, b)| {
        assert!(a.distance(*b) <= 1e-12 * (1.0 + a.length()), "{name}: over the cage {a} vs {b}");
    });
    let scale = cage.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    for (k, (p, n)) in positions.iter().zip(&normals).enumerate() {
        let v = k.checked_sub(out.positions.len()).map_or(k, |e| out.normal_vertices[e] as usize);
        assert!(p.distance(out.positions[v]) <= 1e-12 * scale, "{name}: vertex {k} {p} vs {}", out.positions[v]);
        assert!(n.distance(out.normals[k]) <= 1e-10, "{name}: normal {k} {n} vs {}", out.normals[k]);
    }
}

#[test]
fn evaluation_plans_reproduce_the_tessellator() {
    for (name, builtin, mesh) in [
        (Builtin::CatmullClark, "cube", shapes::cube()),
        (Builtin::CatmullClark, "pentagonal prism", shapes::ngon_prism(5)),
        (Builtin::CatmullClark, "torus", shapes::quad_torus(5, 4)),
        (Builtin::CatmullClark, "grid", shapes::quad_grid(3, 2)),
        (Builtin::CatmullClark, "default model", shapes::default_model()),
        (Builtin::Loop, "icosahedron", shapes::icosahedron()),
    ]
    .into_iter()
    .map(|(builtin, name, soup)| (name, builtin, Mesh::build(soup).unwrap()))
    .chain(creased_meshes())
    {
        let rates = rates_for(&mesh, 5, 9);
        let mut tess = DualTessellator::new(builtin.scheme(), &mesh, &DualOptions::default()).unwrap();
        let out = tess.tessellate(&rates).unwrap().clone();
        check_plan(name, &tess, mesh.positions(), &out);
        let plan = tess.evaluation_plan();
        let mut kinds = [0; 3];
        for entry in plan.entries() {
            kinds[match entry {
                PlanEntry::Block(_) => 0,
                PlanEntry::Bicubic(_) => 1,
                PlanEntry::General(_) => 2,
            }] += 1;
        }
        eprintln!(
            "{name}: {} vertices: {} block, {} bicubic, {} general; {} refined points",
            plan.vertex_count(),
            kinds[0],
            kinds[1],
            kinds[2],
            plan.point_count() - mesh.vertex_count()
        );
        // The plan is linear in the cage: it follows a moved one, rings included.
        let moved: Vec<DVec3> = mesh
            .positions()
            .iter()
            .enumerate()
            .map(|(i, p)| *p * 1.5 + DVec3::new(0.1 * i as f64, 0.0, -0.2))
            .collect();
        let out = tess.update_cage(&moved).unwrap().clone();
        check_plan(name, &tess, &moved, &out);
        let rings = random_rings(&mesh, 3, 3);
        let out = tess.tessellate_with_rings(&rates, &rings).unwrap().clone();
        check_plan(&format!("{name} with rings"), &tess, &moved, &out);
    }
}

#[test]
fn thread_count_does_not_change_the_bits() {
    let mesh = Mesh::build(shapes::default_model()).unwrap();
    let rates = rates_for(&mesh, 8, 16);
    let parallel = tessellate(Builtin::CatmullClark, &mesh, &rates);
    let mut tess = DualTessellator::new(
        Builtin::CatmullClark.scheme(),
        &mesh,
        &DualOptions::DEFAULT.with_parallelism(Parallelism::Serial),
    )
    .unwrap();
    let sequential = tess.tessellate(&rates).unwrap().clone();
    assert_eq!(parallel, sequential);
    // Large enough for every parallel step: the evaluation's pieces among threads (from 1024
    // vertices) and the flat paths' indices beside it (from 4097 triangles).
    assert!(sequential.positions.len() > 4096 && sequential.triangles.len() > 4096);
    let mut flat = FlatMesh::default();
    tess.write_flat(&mut flat);
    assert_eq!(flat.vertices.len(), 6 * sequential.positions.len());
    assert_eq!(flat.indices.len(), 3 * sequential.triangles.len());
    // With rings too (their points are prepared by the same chunks).
    let rings = random_rings(&mesh, 8, 10);
    let parallel = tessellate_rings(&mesh, &rates, &rings);
    assert_eq!(parallel, tess.tessellate_with_rings(&rates, &rings).unwrap().clone());
    // The flat paths too (after the rings: the last step moves the cage).
    let mut threads = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default()).unwrap();
    let (mut a, mut b) = (FlatMesh::default(), FlatMesh::default());
    threads.tessellate_flat(&rates, &mut a).unwrap();
    tess.tessellate_flat(&rates, &mut b).unwrap();
    assert_eq!(a, flat, "tessellate_flat on all threads against write_flat");
    assert_eq!(a, b, "tessellate_flat on all threads against one");
    let moved: Vec<DVec3> = mesh.positions().iter().map(|p| *p * 0.5 + DVec3::X).collect();
    threads.update_cage_flat(&moved, &mut a).unwrap();
    tess.update_cage_flat(&moved, &mut b).unwrap();
    assert_eq!(a, b, "update_cage_flat on all threads against one");
}

/// The flat path with [`Parallelism::Rayon`] on two threads gives the bits of
/// [`Parallelism::Serial`], on the calls after the first (which makes the templates) too, at
/// equal and mixed rates, with N-gons, borders, and after a moved cage.
#[test]
fn small_flat_calls_on_two_threads_equal_one() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let cc = Builtin::CatmullClark.scheme();
    for (name, soup) in [
        ("cube", shapes::cube()),
        ("prism", shapes::ngon_prism(5)),
        ("grid", shapes::quad_grid(3, 2)),
        ("torus", shapes::quad_torus(5, 4)),
    ] {
        let mesh = Mesh::build(soup).unwrap();
        let faces = mesh.face_count();
        let mut one = DualTessellator::new(
            cc,
            &mesh,
            &DualOptions::DEFAULT.with_quads(false).with_parallelism(Parallelism::Serial),
        )
        .unwrap();
        let mut two = DualTessellator::new(cc, &mesh, &DualOptions::DEFAULT.with_quads(false)).unwrap();
        let moved: Vec<DVec3> = mesh.positions().iter().map(|p| *p * 1.25 + DVec3::new(0.5, -1.0, 2.0)).collect();
        let (mut expected, mut got) = (FlatMesh::default(), FlatMesh::default());
        for rates in [vec![8; faces], rates_for(&mesh, 3, 12), vec![16; faces]] {
            one.tessellate_flat(&rates, &mut expected).unwrap();
            pool.install(|| {
                for call in 0..3 {
                    two.tessellate_flat(&rates, &mut got).unwrap();
                    assert_eq!(got, expected, "{name} at {rates:?}, call {call}");
                }
            });
        }
        one.update_cage_flat(&moved, &mut expected).unwrap();
        one.tessellate_flat(&vec![8; faces], &mut expected).unwrap();
        pool.install(|| {
            two.update_cage_flat(&moved, &mut got).unwrap();
            two.tessellate_flat(&vec![8; faces], &mut got).unwrap();
        });
        assert_eq!(got, expected, "{name} on a moved cage");
    }
}

#[test]
fn extreme_rates_side_by_side_are_watertight() {
    // The largest rate is taken (a million points on one face)...
    let max = subdiv_tess::MAX_DUAL_RATE;
    let square = Mesh::build(shapes::quad_grid(1, 1)).unwrap();
    let out = tessellate(Builtin::CatmullClark, &square, &[max]);
    assert_eq!(
        out.positions.len(),
        subdiv_tess::dual::predicted_vertex_count(&square, subdiv_schemes::Split::Quad, &[max])
    );
    // ... and the contrast between neighbours is what stitching has to bear.
    let max = 256;
    let cube = Mesh::build(shapes::cube()).unwrap();
    closed_checks(Builtin::CatmullClark, &cube, &[1, max, 1, max, 2, 3]);
    let prism = Mesh::build(shapes::ngon_prism(5)).unwrap();
    let rates: Vec<u32> = (0..prism.face_count()).map(|f| if f % 2 == 0 { max } else { 1 }).collect();
    closed_checks(Builtin::CatmullClark, &prism, &rates);
}

#[test]
fn equal_rates_give_quads() {
    let torus = Mesh::build(shapes::quad_torus(4, 4)).unwrap();
    let out = tessellate(Builtin::CatmullClark, &torus, &[6; 16]);
    // A regular torus at one rate n is an (4n) × (4n) quad grid.
    assert_eq!(out.polygon_count(), 24 * 24);
    assert_eq!(out.triangles.len(), 2 * 24 * 24);
    assert_eq!(out.positions.len(), 24 * 24);
}

/// New options on a prepared tessellator give what a tessellator made with them gives.
#[test]
fn set_options_equals_a_fresh_tessellator() {
    let mesh = Mesh::build(shapes::default_model()).unwrap();
    let cc = Builtin::CatmullClark.scheme();
    let rates = rates_for(&mesh, 7, 9);
    let mut kept = DualTessellator::new(cc, &mesh, &DualOptions::DEFAULT).unwrap();
    assert!(kept.tessellate(&rates).unwrap().polygon_count() > 0);
    for options in [
        DualOptions::DEFAULT.with_quads(false).with_parallelism(Parallelism::Serial),
        DualOptions::DEFAULT.with_quads(true).with_parallelism(Parallelism::Rayon),
    ] {
        kept.set_options(&options);
        assert_eq!(kept.options(), &options);
        let mut fresh = DualTessellator::new(cc, &mesh, &options).unwrap();
        assert_eq!(kept.tessellate(&rates).unwrap(), fresh.tessellate(&rates).unwrap(), "{options:?}");
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let cube = Mesh::build(shapes::cube()).unwrap();
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &cube, &DualOptions::default()).unwrap();
    assert_eq!(tess.face_count(), 6);
    assert!(matches!(tess.tessellate(&[1; 5]), Err(TessError::RateCount { expected: 6, got: 5 })));
    assert!(matches!(tess.tessellate(&[1, 1, 0, 1, 1, 1]), Err(TessError::Rate { face: 2, rate: 0, .. })));
    let too_big = subdiv_tess::MAX_DUAL_RATE + 1;
    assert!(matches!(tess.tessellate(&[1, 1, 1, 1, too_big, 1]), Err(TessError::Rate { face: 4, .. })));
    // The flat path: the same errors, and the caller's buffers untouched.
    let mut flat = FlatMesh { vertices: vec![7.0; 5], indices: vec![3; 2], ..FlatMesh::default() };
    let kept = flat.clone();
    assert!(matches!(tess.tessellate_flat(&[1; 7], &mut flat), Err(TessError::RateCount { expected: 6, got: 7 })));
    assert!(matches!(tess.tessellate_flat(&[0; 6], &mut flat), Err(TessError::Rate { face: 0, rate: 0, .. })));
    assert_eq!(flat, kept);
    tess.tessellate(&[2; 6]).unwrap();
    let mut cage = cube.positions().to_vec();
    assert!(matches!(tess.update_cage(&cage[1..]), Err(TessError::CageLength { expected: 8, got: 7 })));
    cage[3].y = f64::NAN;
    assert!(matches!(tess.update_cage(&cage), Err(TessError::CagePosition { vertex: 3, .. })));
    let error = TessError::CagePosition { vertex: 3, value: "x".into() }.to_string();
    assert!(error.contains("vertex 3"), "{error}");
    // √3 takes closed meshes of triangles: the patch levels' typed error for a quad.
    let sqrt3 = DualTessellator::new(Builtin::Sqrt3.scheme(), &cube, &DualOptions::default());
    assert!(matches!(sqrt3, Err(TessError::Surface(_))), "{sqrt3:?}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn random_meshes_and_rates_are_watertight(seed in 0u64..1_000_000, which in 0usize..3, max in 1u32..40) {
        let mesh = closed_mesh(seed, which);
        let rates = rates_for(&mesh, seed, max);
        closed_checks(Builtin::CatmullClark, &mesh, &rates);
    }

    #[test]
    fn random_open_meshes_keep_their_boundaries(seed in 0u64..1_000_000, which in 0usize..3, max in 1u32..40) {
        let (builtin, mesh) = match which {
            0 => {
                let (m, n) = (1 + (seed % 4) as usize, 1 + (seed / 4 % 3) as usize);
                (Builtin::CatmullClark, Mesh::build(shapes::quad_grid(m, n)).unwrap())
            }
            1 => (Builtin::CatmullClark, Mesh::build(shapes::pole(3 + (seed % 5) as usize)).unwrap()),
            _ => {
                let mut soup = shapes::ngon_prism(3 + (seed % 5) as usize);
                soup.tags.holes.push(FaceId::new((seed % 3) as u32));
                (Builtin::CatmullClark, Mesh::build(soup).unwrap())
            }
        };
        open_checks(builtin, &mesh, &rates_for(&mesh, seed, max));
    }

    #[test]
    fn random_triangle_meshes_are_watertight(seed in 0u64..1_000_000, max in 1u32..40) {
        let mesh = Mesh::build(shapes::icosahedron()).unwrap();
        closed_checks(Builtin::Loop, &mesh, &rates_for(&mesh, seed, max));
    }
}

/// At rates fine for the curvature, every triangle's facet normal agrees with its corners'
/// limit normals: strips and rings do not fold over, also between unequal rates.
#[test]
fn fine_triangles_face_the_way_the_surface_does() {
    for (builtin, soup, seed) in [
        (Builtin::CatmullClark, shapes::default_model(), 1),
        (Builtin::CatmullClark, shapes::ngon_prism(5), 2),
        (Builtin::CatmullClark, shapes::cube(), 3),
        (Builtin::Loop, shapes::icosahedron(), 4),
    ] {
        let mesh = Mesh::build(soup).unwrap();
        let rates: Vec<u32> = rates_for(&mesh, seed, 7).into_iter().map(|r| r + 5).collect();
        let out = tessellate(builtin, &mesh, &rates);
        let mut flipped = 0;
        for t in &out.triangles {
            let [a, b, c] = t.map(|v| out.positions[v as usize]);
            let normal: DVec3 = t.iter().map(|&v| out.normals[v as usize]).sum();
            if (b - a).cross(c - a).dot(normal) <= 0.0 {
                flipped += 1;
            }
        }
        assert_eq!(flipped, 0, "{builtin:?}: {flipped} of {} triangles face away", out.triangles.len());
    }
}

/// The committed default tables (Catmull-Clark, valences 3 to 8, rates 1 to 24) seed the
/// tessellator, and give the same output, bit for bit, as tables computed on demand.
#[test]
fn committed_tables_seed_the_tessellator() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../subdiv-stencil/tables/catmull-clark.stencils");
    let bytes = std::fs::read(&path).unwrap();
    let scheme = Builtin::CatmullClark.scheme();
    let tables = subdiv_stencil::StencilTables::from_bytes(&bytes, scheme).unwrap();
    // The cube refined twice (valence-3 patches on level 0), and a pentagonal prism refined
    // twice (valence 5 at the caps' centres, valence 3 at their corners).
    let prism = Mesh::build(shapes::ngon_prism(5)).unwrap();
    let prism = subdiv_schemes::refine_uniform(&prism, scheme, 2, &RefineOptions::DEFAULT).unwrap();
    for mesh in [refined_cube(), prism] {
        let rates = rates_for(&mesh, 12, 20);
        let mut seeded = DualTessellator::new(scheme, &mesh, &DualOptions::default()).unwrap();
        let taken = seeded.seed_tables(&tables).unwrap();
        assert!(taken > 0, "no table taken");
        let seeded = seeded.tessellate(&rates).unwrap().clone();
        let fresh = tessellate(Builtin::CatmullClark, &mesh, &rates);
        assert_eq!(seeded, fresh);
    }
    // Another scheme's tables are refused.
    let mut loop_tess = DualTessellator::new(
        Builtin::Loop.scheme(),
        &Mesh::build(shapes::icosahedron()).unwrap(),
        &DualOptions::default(),
    )
    .unwrap();
    assert!(matches!(loop_tess.seed_tables(&tables), Err(TessError::Scheme { .. })));
}

/// The cube with every edge infinitely sharp: each face a flat square, each edge point two
/// normals 90° apart, each corner three.
fn all_sharp_cube() -> Mesh {
    let mut mesh = Mesh::build(shapes::cube()).unwrap();
    for e in mesh.edges().collect::<Vec<_>>() {
        mesh.set_edge_sharpness(e, subdiv_mesh::Tags::INFINITELY_SHARP);
    }
    mesh
}

/// The split normals' structure (every corner's normal is its vertex's own or one of its extra
/// normals, each extra normal used), the flat outputs (one vertex per normal, the extra ones at
/// their vertices' positions, indexed by `triangle_normals`), and each extra normal against
/// the exact limit normal of a face whose boundary holds its vertex (a fan around a crease
/// vertex spans its sector's faces, so the triangles' faces do not say which one), and unless
/// the creases are flat (`flat_creases`: the cage flat across them) the normals at one vertex pairwise apart
/// (each sector once). Returns per extra normal the angle to its vertex's own normal.
fn split_normal_checks(builtin: Builtin, mesh: &Mesh, out: &TessMesh, name: &str, flat_creases: bool) -> Vec<f64> {
    let vertices = out.positions.len();
    assert_eq!(out.normals.len(), vertices + out.normal_vertices.len(), "{name}");
    assert_eq!(out.triangle_normals.len(), out.triangles.len(), "{name}");
    let mut used = vec![false; out.normal_vertices.len()];
    for (t, (tri, normals)) in out.triangles.iter().zip(&out.triangle_normals).enumerate() {
        for c in 0..3 {
            let n = normals[c] as usize;
            match n.checked_sub(vertices) {
                None => assert_eq!(n, tri[c] as usize, "{name}: triangle {t} corner {c}"),
                Some(e) => {
                    assert_eq!(out.normal_vertices[e], tri[c], "{name}: triangle {t} corner {c}");
                    used[e] = true;
                }
            }
        }
    }
    assert!(used.iter().all(|&u| u), "{name}: an extra normal no triangle uses");
    // Flat: the vertices, then one split copy per extra normal.
    let mut flat = FlatMesh::default();
    out.write_to(&mut flat);
    assert_eq!(flat.vertices.len(), 6 * out.flat_vertex_count(), "{name}");
    assert_eq!(flat.indices, out.flat_indices(), "{name}");
    for (e, &v) in out.normal_vertices.iter().enumerate() {
        let (k, v) = (6 * (vertices + e), 6 * v as usize);
        assert_eq!(flat.vertices[k..k + 3], flat.vertices[v..v + 3], "{name}: extra normal {e}'s position");
        assert_eq!(flat.vertices[k + 3..k + 6], out.normals[vertices + e].as_vec3().to_array(), "{name}");
    }
    let evaluator = subdiv_stencil::LimitEvaluator::new(builtin.scheme(), mesh, &RefineOptions::DEFAULT).unwrap();
    let d = diagonal(mesh);
    let mut per_vertex: HashMap<u32, Vec<DVec3>> = HashMap::new();
    let mut angles = Vec::new();
    for (e, &v) in out.normal_vertices.iter().enumerate() {
        let (p, n) = (out.positions[v as usize], out.normals[vertices + e]);
        let own = out.parameters[v as usize];
        // The points of each face's boundary at the parameters of the vertex's own point (or
        // their complements) along a side, or at a corner: those at `p` are in the faces
        // around it, one-sided there.
        let ts = [own.u, own.v, 1.0 - own.u, 1.0 - own.v, 0.0, 1.0];
        let normals: Vec<DVec3> = mesh
            .face_ids()
            .flat_map(|face| {
                let sides: Vec<fn(f64) -> (f64, f64)> = match evaluator.domain(face).unwrap() {
                    subdiv_stencil::FaceDomain::Quad => vec![|t| (t, 0.0), |t| (1.0, t), |t| (t, 1.0), |t| (0.0, t)],
                    subdiv_stencil::FaceDomain::Triangle | subdiv_stencil::FaceDomain::Ternary => {
                        vec![|t| (t, 0.0), |t| (0.0, t), |t| (t, 1.0 - t)]
                    }
                    subdiv_stencil::FaceDomain::SubFaces { .. } => panic!("{name}: no N-gons in these meshes"),
                };
                let points: Vec<(f64, f64)> = sides.iter().flat_map(|side| ts.iter().map(|&t| side(t))).collect();
                points.into_iter().map(move |(a, b)| (face, a, b))
            })
            // A point (t, 1 − t) may round outside a triangle: the side's other end has it.
            .filter_map(|(face, a, b)| evaluator.eval(face, a, b).ok())
            .filter(|want| want.position.distance(p) <= 1e-10 * d)
            .map(|want| want.du.cross(want.dv).normalize())
            .collect();
        assert!(
            normals.iter().any(|want| want.distance(n) <= 1e-9),
            "{name}: extra normal {e} (vertex {v}) is {n}; the faces around it have {normals:?}"
        );
        per_vertex.entry(v).or_insert_with(|| vec![out.normals[v as usize]]).push(n);
        angles.push(out.normals[v as usize].angle_between(n));
    }
    for (v, normals) in per_vertex.iter().filter(|_| !flat_creases) {
        for (i, a) in normals.iter().enumerate() {
            assert!(normals[..i].iter().all(|b| a.angle_between(*b) > 1e-4), "{name}: vertex {v}: {normals:?}");
        }
    }
    angles
}

#[test]
fn crease_points_have_each_sides_normal() {
    let cube = all_sharp_cube();
    for rate in [1, 3, 6] {
        let out = tessellate(Builtin::CatmullClark, &cube, &[rate; 6]);
        let angles = split_normal_checks(Builtin::CatmullClark, &cube, &out, "all-sharp cube", false);
        // Every edge's `rate` points once more, every corner twice more.
        assert_eq!(out.normal_vertices.len(), 12 * rate as usize + 8 * 2);
        assert!(angles.iter().all(|&a| a >= std::f64::consts::FRAC_PI_4), "all-sharp cube at {rate}: {angles:?}");
        assert!(check(&out).is_empty(), "all-sharp cube: cracks");
    }
    let mut meshes: Vec<(String, Builtin, Mesh, bool)> =
        creased_meshes().into_iter().map(|(name, b, mesh)| (name.to_string(), b, mesh, false)).collect();
    // A flat grid with sharp edges across it: split, with equal normals on both sides.
    for (file, flat) in [("opensubdiv/catmark_cube_creases2.obj", false), ("opensubdiv/catmark_inf_crease0.obj", true)]
    {
        let Some(path) = subdiv_testkit::shared_mesh(file) else { break };
        let mesh = subdiv_io::load_mesh(&path, &Default::default()).unwrap();
        meshes.push((file.to_string(), Builtin::CatmullClark, mesh, flat));
    }
    for (name, builtin, mesh, flat) in meshes {
        let sharp = mesh.edges().any(|e| mesh.edge_sharpness(e) >= subdiv_mesh::Tags::INFINITELY_SHARP);
        for rates in [vec![3; mesh.face_count()], rates_for(&mesh, 23, 7)] {
            let out = tessellate(builtin, &mesh, &rates);
            let angles = split_normal_checks(builtin, &mesh, &out, &name, flat);
            let smallest = angles.iter().copied().reduce(f64::min);
            eprintln!("{name}: {} extra normals, smallest angle {smallest:?}", angles.len());
            // Every point of a sharp edge is split; a semi-sharp feature splits nothing (the
            // surface is smooth there).
            assert_eq!(!angles.is_empty(), sharp, "{name}");
            assert!(flat || angles.iter().all(|&a| a > 1e-4), "{name}: {angles:?}");
        }
    }
}

#[test]
fn smooth_meshes_have_no_extra_normals() {
    let semi = creased_meshes().swap_remove(1);
    for (name, mesh) in quad_meshes().into_iter().chain([(semi.0, semi.2)]) {
        let out = tessellate(Builtin::CatmullClark, &mesh, &rates_for(&mesh, 29, 6));
        assert!(out.normal_vertices.is_empty(), "{name}");
        assert_eq!(out.normals.len(), out.positions.len(), "{name}");
        assert_eq!(out.triangle_normals, out.triangles, "{name}");
    }
}

/// Every shared mesh with sharp features, at rates 3, 8 and screen-space: consistently
/// oriented, watertight and welded, the Euler characteristic kept, and (at rate 3) every
/// vertex on the limit surface with its normal.
#[test]
fn shared_creased_meshes_are_watertight_and_on_the_limit_surface() {
    use subdiv_tess::rates::{Camera, ScreenSpace};
    if subdiv_testkit::meshes_dir().is_none() {
        return;
    }
    let mut compared = 0;
    for (path, builtin, mesh) in subdiv_testkit::creased_meshes() {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let (lo, hi) = mesh.bounding_box().unwrap();
        let camera =
            Camera::look_at((lo + hi) * 0.5 + (hi - lo) * DVec3::new(0.9, 0.7, 1.3), (lo + hi) * 0.5, DVec3::Y);
        let screen = ScreenSpace::new(camera, [640, 480], 12.0).face_rates(&mesh).unwrap();
        for rates in [vec![3; mesh.face_count()], vec![8; mesh.face_count()], screen] {
            let out = tessellate(builtin, &mesh, &rates);
            if mesh.edges().all(|e| !mesh.is_boundary_edge(e)) && mesh.face_ids().all(|f| !mesh.is_hole(f)) {
                check_facing(&out, &mesh);
            }
            // Welded (one vertex per position), no edge used twice one way; only open meshes
            // have a border.
            let border = check(&out);
            assert!(
                border.is_empty()
                    || mesh.edges().any(|e| mesh.is_boundary_edge(e))
                    || mesh.face_ids().any(|f| mesh.is_hole(f)),
                "{name}: cracks"
            );
            assert_eq!(euler(&out), input_euler(&mesh), "{name}");
        }
        eprintln!("{name}");
        on_limit_surface(builtin, &mesh, &vec![3; mesh.face_count()]);
        compared += 1;
    }
    assert!(compared >= 45, "{compared} creased meshes");
}
