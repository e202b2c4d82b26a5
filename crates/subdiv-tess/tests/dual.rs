//! Dual-grid stitching: watertightness and topology at random per-face rates, boundaries, every
//! vertex on the exact limit surface, the animation path, and typed errors.

#![allow(clippy::print_stderr)]

use std::collections::HashMap;

use glam::DVec3;
use proptest::prelude::*;
use subdiv_eval::Method;
use subdiv_mesh::{FaceId, Mesh, PolygonSoup, VertexId, shapes};
use subdiv_schemes::{Builtin, RefineOptions};
use subdiv_stencil::LimitEvaluator;
use subdiv_tess::check::MeshDistance;
use subdiv_tess::dual::{MAX_DUAL_RING_DEPTH, PlanEntry, predicted_vertex_count, predicted_vertex_count_with_rings};
use subdiv_tess::rates::{ErrorRates, RingDepths};
use subdiv_tess::{
    DualOptions, DualTessellator, FlatMesh, Parallelism, QuadtreeTessellator, TessError, TessMesh, Tolerance,
};

fn tessellate(builtin: Builtin, mesh: &Mesh, rates: &[u32]) -> TessMesh {
    let mut tess = DualTessellator::new(builtin.scheme(), mesh, &DualOptions::default()).unwrap();
    tess.tessellate(rates).unwrap().clone()
}

/// Each directed edge once; returns the directed edges without an opposite (the border).
fn directed_edges(out: &TessMesh) -> HashMap<(u32, u32), usize> {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for (k, t) in out.triangles.iter().enumerate() {
        assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "triangle {k} is degenerate: {t:?}");
        for i in 0..3 {
            let e = (t[i], t[(i + 1) % 3]);
            assert!(directed.insert(e, k).is_none(), "edge {e:?} used twice in one direction");
        }
    }
    directed
}

/// Every vertex used, no two at one position, no edge in one direction twice, every edge's
/// opposite present unless it is a border edge; the border edges returned.
fn check(out: &TessMesh) -> Vec<(u32, u32)> {
    let directed = directed_edges(out);
    let border: Vec<(u32, u32)> = directed.keys().filter(|&&(a, b)| !directed.contains_key(&(b, a))).copied().collect();
    let mut used = vec![false; out.positions.len()];
    out.triangles.iter().flatten().for_each(|&v| used[v as usize] = true);
    assert!(used.iter().all(|&u| u), "an output vertex is in no triangle");
    let mut seen: HashMap<[u64; 3], usize> = HashMap::new();
    for (i, p) in out.positions.iter().enumerate() {
        assert!(p.is_finite());
        if let Some(j) = seen.insert([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()], i) {
            panic!("vertices {j} and {i} share the position {p}");
        }
    }
    // Polygons share their edges with triangles' directions.
    for k in 0..out.polygon_count() {
        let p = out.polygon(k);
        for i in 0..p.len() {
            assert!(directed.contains_key(&(p[i], p[(i + 1) % p.len()])), "polygon {k} edge not a triangle edge");
        }
    }
    border
}

fn euler(out: &TessMesh) -> i64 {
    let directed = directed_edges(out);
    let edges = directed.keys().filter(|&&(a, b)| a < b || !directed.contains_key(&(b, a))).count();
    out.positions.len() as i64 - edges as i64 + out.triangles.len() as i64
}

/// The input's χ, without hole faces.
fn input_euler(mesh: &Mesh) -> i64 {
    let faces: Vec<FaceId> = mesh.face_ids().filter(|&f| !mesh.is_hole(f)).collect();
    let mut edges = std::collections::HashSet::new();
    let mut vertices = std::collections::HashSet::new();
    for &f in &faces {
        let vs = mesh.face_vertices(f);
        for k in 0..vs.len() {
            let (a, b) = (vs[k], vs[(k + 1) % vs.len()]);
            edges.insert((a.min(b), a.max(b)));
            vertices.insert(a);
        }
    }
    vertices.len() as i64 - edges.len() as i64 + faces.len() as i64
}

/// The output faces the way the input does: on a closed mesh, the signed volumes enclosed by
/// the output's triangles and by the cage's faces (fanned) have the same sign. (A triangle by
/// triangle check of facet against limit normals would flag coarse rates on curved, saddle-shaped
/// regions, where a flat triangle through far-apart limit points legitimately tilts.)
fn check_facing(out: &TessMesh, mesh: &Mesh) {
    let volume = |t: [DVec3; 3]| t[0].dot(t[1].cross(t[2])) / 6.0;
    let output: f64 = out.triangles.iter().map(|t| volume(t.map(|v| out.positions[v as usize]))).sum();
    let cage: f64 = mesh
        .face_ids()
        .flat_map(|f| {
            let vs = mesh.face_vertices(f);
            (1..vs.len() - 1).map(move |k| [vs[0], vs[k], vs[k + 1]])
        })
        .map(|t| volume(t.map(|v| mesh.position(v))))
        .sum();
    assert!(output * cage > 0.0, "output volume {output} against the cage's {cage}: flipped");
}

fn closed_checks(builtin: Builtin, mesh: &Mesh, rates: &[u32]) -> TessMesh {
    let out = tessellate(builtin, mesh, rates);
    check_facing(&out, mesh);
    let border = check(&out);
    assert!(border.is_empty(), "{} border edges on a closed mesh", border.len());
    assert_eq!(euler(&out), input_euler(mesh));
    let triangle = builtin == Builtin::Loop || builtin == Builtin::Butterfly;
    assert_eq!(out.positions.len(), predicted_vertex_count(mesh, triangle, rates));
    out
}

/// The cycles of a successor map (each key's chain back to itself), from the least key up.
fn cycles<T: Copy + Ord + std::hash::Hash>(next: &HashMap<T, T>) -> Vec<Vec<T>> {
    let mut done = std::collections::HashSet::new();
    let mut out = Vec::new();
    let mut starts: Vec<T> = next.keys().copied().collect();
    starts.sort_unstable();
    for s in starts {
        if !done.insert(s) {
            continue;
        }
        let mut l = vec![s];
        let mut v = next[&s];
        while v != s {
            l.push(v);
            done.insert(v);
            v = next[&v];
        }
        out.push(l);
    }
    out
}

/// Output boundary loops (chains of border edges).
fn loops(border: &[(u32, u32)]) -> Vec<Vec<u32>> {
    let next: HashMap<u32, u32> = border.iter().copied().collect();
    assert_eq!(next.len(), border.len(), "a vertex starts two border edges");
    cycles(&next)
}

/// Open input: the output's boundary loops are the input's, through the limit points of the
/// input's boundary vertices in order.
fn open_checks(builtin: Builtin, mesh: &Mesh, rates: &[u32]) {
    let out = tessellate(builtin, mesh, rates);
    let border = check(&out);
    assert_eq!(euler(&out), input_euler(mesh));
    let triangle = builtin == Builtin::Loop || builtin == Builtin::Butterfly;
    assert_eq!(out.positions.len(), predicted_vertex_count(mesh, triangle, rates));
    let output_loops = loops(&border);
    // The input's border: boundary half-edges and the half-edges of faces next to holes.
    let mut next: HashMap<VertexId, VertexId> = HashMap::new();
    for f in mesh.face_ids().filter(|&f| !mesh.is_hole(f)) {
        for h in mesh.face_half_edges(f) {
            if mesh.twin(h).is_none_or(|t| mesh.is_hole(mesh.face(t))) {
                next.insert(mesh.origin(h), mesh.dest(h));
            }
        }
    }
    let input_loops = cycles(&next);
    assert_eq!(output_loops.len(), input_loops.len(), "boundary loop count");
    let evaluator = LimitEvaluator::new(builtin.scheme(), mesh, &RefineOptions::DEFAULT).unwrap();
    let diagonal = diagonal(mesh);
    // The limit point of each input border vertex, through one of its faces' corners.
    let limit = |v: VertexId| -> DVec3 {
        let h = mesh.outgoing(v).find(|&h| !mesh.is_hole(mesh.face(h))).unwrap();
        let f = mesh.face(h);
        let c = mesh.face_half_edges(f).position(|x| x == h).unwrap();
        let domain = evaluator.domain(f).unwrap();
        let p = match domain {
            subdiv_stencil::FaceDomain::Quad => [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)][c],
            subdiv_stencil::FaceDomain::Triangle => [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)][c],
            d @ subdiv_stencil::FaceDomain::SubFaces { .. } => {
                d.from_sub_face(c, subdiv_stencil::Dyadic::new(0, 0, 1)).to_f64()
            }
        };
        evaluator.eval(f, p.0, p.1).unwrap().position
    };
    for input in &input_loops {
        let corners: Vec<DVec3> = input.iter().map(|&v| limit(v)).collect();
        // The output loop holding the first corner, and the corners' places along it.
        let find = |p: DVec3| -> Option<(usize, usize)> {
            output_loops.iter().enumerate().find_map(|(l, lp)| {
                lp.iter().position(|&v| (out.positions[v as usize] - p).length() < 1e-12 * diagonal).map(|k| (l, k))
            })
        };
        let places: Vec<(usize, usize)> = corners.iter().map(|&p| find(p).expect("a boundary corner")).collect();
        assert!(places.iter().all(|p| p.0 == places[0].0), "corners of one input loop on several output loops");
        // In order along the loop: cyclically increasing positions.
        let len = output_loops[places[0].0].len();
        let steps: usize =
            (0..places.len()).map(|k| (places[(k + 1) % places.len()].1 + len - places[k].1) % len).sum();
        assert_eq!(steps, len, "the corners are not in the loop's order");
    }
}

/// The cube refined twice (Catmull-Clark): 96 quads whose extraordinary vertices (valence 3)
/// are isolated, so the faces at them are extraordinary patches on level 0 (the table route).
fn refined_cube() -> Mesh {
    let cube = Mesh::build(shapes::cube()).unwrap();
    subdiv_schemes::refine_uniform(&cube, Builtin::CatmullClark.scheme(), 2, &RefineOptions::DEFAULT).unwrap()
}

fn diagonal(mesh: &Mesh) -> f64 {
    mesh.bounding_box().map_or(1.0, |(lo, hi)| lo.distance(hi))
}

/// Every output vertex equals the exact limit point at its parameter (1e-12 × bbox), normals
/// to 1e-10.
fn on_limit_surface(builtin: Builtin, mesh: &Mesh, rates: &[u32]) {
    let out = tessellate(builtin, mesh, rates);
    let evaluator = LimitEvaluator::new(builtin.scheme(), mesh, &RefineOptions::DEFAULT).unwrap();
    let d = diagonal(mesh);
    let (mut worst_p, mut worst_n): (f64, f64) = (0.0, 0.0);
    // A point on a triangle's third side, (1 − t, t), may round to u + v > 1 in f64 (exactly
    // summed): the smaller moved back onto the side (by an ulp; 1 − the larger is exact).
    let params: Vec<(FaceId, f64, f64)> = out
        .parameters
        .iter()
        .map(|s| {
            let triangle = evaluator.domain(s.face).unwrap() == subdiv_stencil::FaceDomain::Triangle;
            match (triangle && s.u + s.v >= 1.0 - 1e-12, s.u >= s.v) {
                (true, true) => (s.face, s.u, s.v.min(1.0 - s.u)),
                (true, false) => (s.face, s.u.min(1.0 - s.v), s.v),
                _ => (s.face, s.u, s.v),
            }
        })
        .collect();
    for (i, &(face, u, v)) in params.iter().enumerate() {
        let want = evaluator.eval(face, u, v).unwrap();
        let n = want.du.cross(want.dv).normalize();
        worst_p = worst_p.max((want.position - out.positions[i]).length() / d);
        worst_n = worst_n.max((n - out.normals[i]).length());
        assert!((out.normals[i].length() - 1.0).abs() < 1e-12);
    }
    eprintln!(
        "{builtin:?}: {} vertices, worst position / bbox {worst_p:e}, worst normal {worst_n:e}",
        out.positions.len()
    );
    assert!(worst_p < 1e-12, "position off by {worst_p:e} × bbox");
    assert!(worst_n < 1e-10, "normal off by {worst_n:e}");
    // An independent route: the eigenbasis evaluator (Stam), where it takes the faces.
    let eigen =
        subdiv_eval::EigenEvaluator::new(builtin.scheme(), mesh, &RefineOptions::DEFAULT, Method::Auto).unwrap();
    let (mut worst_p, mut worst_n): (f64, f64) = (0.0, 0.0);
    for (i, &(face, u, v)) in params.iter().enumerate() {
        let want = eigen.eval(face, u, v).unwrap();
        worst_p = worst_p.max((want.position - out.positions[i]).length() / d);
        worst_n = worst_n.max((want.du.cross(want.dv).normalize() - out.normals[i]).length());
    }
    eprintln!("  eigenbasis route: worst position / bbox {worst_p:e}, worst normal {worst_n:e}");
    assert!(worst_p < 1e-12, "position off the eigenbasis route by {worst_p:e} × bbox");
    assert!(worst_n < 1e-10, "normal off the eigenbasis route by {worst_n:e}");
}

fn rates_for(mesh: &Mesh, seed: u64, max: u32) -> Vec<u32> {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..mesh.face_count())
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            1 + (state % u64::from(max)) as u32
        })
        .collect()
}

fn quad_meshes() -> Vec<(&'static str, Mesh)> {
    [
        ("cube", shapes::cube()),
        ("pentagonal prism", shapes::ngon_prism(5)),
        ("triangular prism", shapes::ngon_prism(3)),
        ("default model", shapes::default_model()),
        ("torus", shapes::quad_torus(5, 4)),
        ("tetrahedron", shapes::tetrahedron()),
        ("dodecahedron", shapes::dodecahedron()),
    ]
    .into_iter()
    .map(|(n, s)| (n, Mesh::build(s).unwrap()))
    .collect()
}

/// A closed mesh with random valences: a cube whose faces are each split into a random fan
/// (quads, triangles or left alone) — a different set of valences and N-gons per seed.
fn random_closed(seed: u64) -> Mesh {
    let cube = shapes::cube();
    let mut soup = PolygonSoup::default();
    for p in cube.positions() {
        soup.push_vertex(*p);
    }
    let mut state = seed | 1;
    let mut rnd = |m: u64| {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) % m
    };
    for f in cube.faces() {
        let vs: Vec<VertexId> = f.to_vec();
        let centre: DVec3 = vs.iter().map(|v| cube.positions()[v.index()]).sum::<DVec3>() * 0.25;
        match rnd(3) {
            0 => {
                soup.push_face(vs.clone());
            }
            1 => {
                // Four triangles around a raised centre.
                let c = VertexId::new(soup.positions().len() as u32);
                soup.push_vertex(centre * 1.3);
                for k in 0..4 {
                    soup.push_face([vs[k], vs[(k + 1) % 4], c]);
                }
            }
            _ => {
                // Two triangles at a diagonal: valences change at its ends.
                soup.push_face([vs[0], vs[1], vs[2]]);
                soup.push_face([vs[0], vs[2], vs[3]]);
            }
        }
    }
    Mesh::build(soup).unwrap()
}

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
    // Other quad splits: Kobbelt where its valences (3 and 4) allow; bilinear away from
    // extraordinary vertices (some of its exact stencils there are not unique: a typed error
    // from the stencils, `TessError::Surface`).
    let cube = Mesh::build(shapes::cube()).unwrap();
    closed_checks(Builtin::Kobbelt, &cube, &rates_for(&cube, 5, 9));
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
fn update_cage_equals_a_fresh_tessellation() {
    for (builtin, soup) in [
        (Builtin::CatmullClark, shapes::cube()),
        (Builtin::CatmullClark, shapes::ngon_prism(5)),
        (Builtin::CatmullClark, shapes::quad_torus(5, 4)),
        (Builtin::CatmullClark, shapes::quad_grid(3, 2)),
        (Builtin::Loop, shapes::icosahedron()),
    ] {
        let mesh = Mesh::build(soup).unwrap();
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
        assert_eq!(animated.normals, fresh.normals);
        // Straight into f32: the same as the f64 output written flat.
        let (mut direct, mut written) = (FlatMesh::default(), FlatMesh::default());
        fresh_tess.write_flat(&mut written);
        tess.update_cage_flat(&moved, &mut direct).unwrap();
        assert_eq!(direct, written, "{builtin:?}: update_cage_flat");
        // The flat-only tessellation: the same buffers, and the same animation after it.
        let mut flat_tess = DualTessellator::new(builtin.scheme(), &moved_mesh, &DualOptions::default()).unwrap();
        let mut stale = FlatMesh { vertices: vec![7.0; 5], indices: vec![3; 2] };
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

/// The plan's f64 evaluation against the tessellator's own, on a moved cage.
fn check_plan(name: &str, tess: &DualTessellator, cage: &[DVec3], out: &TessMesh) {
    let plan = tess.evaluation_plan();
    assert_eq!(plan.vertex_count(), out.positions.len(), "{name}: one entry per vertex");
    assert_eq!(plan.entries().len(), out.positions.len(), "{name}: one entry per vertex");
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
        assert!(p.distance(out.positions[k]) <= 1e-12 * scale, "{name}: vertex {k} {p} vs {}", out.positions[k]);
        assert!(n.distance(out.normals[k]) <= 1e-10, "{name}: normal {k} {n} vs {}", out.normals[k]);
    }
}

#[test]
fn evaluation_plans_reproduce_the_tessellator() {
    for (builtin, name, soup) in [
        (Builtin::CatmullClark, "cube", shapes::cube()),
        (Builtin::CatmullClark, "pentagonal prism", shapes::ngon_prism(5)),
        (Builtin::CatmullClark, "torus", shapes::quad_torus(5, 4)),
        (Builtin::CatmullClark, "grid", shapes::quad_grid(3, 2)),
        (Builtin::CatmullClark, "default model", shapes::default_model()),
        (Builtin::Loop, "icosahedron", shapes::icosahedron()),
    ] {
        let mesh = Mesh::build(soup).unwrap();
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
    let max = subdiv_tess::MAX_DUAL_RATE;
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
    let mut flat = FlatMesh { vertices: vec![7.0; 5], indices: vec![3; 2] };
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
    // √3 has no sub-patch matrices: the patch levels' typed error.
    let ico = Mesh::build(shapes::icosahedron()).unwrap();
    let sqrt3 = DualTessellator::new(Builtin::Sqrt3.scheme(), &ico, &DualOptions::default());
    assert!(matches!(sqrt3, Err(TessError::Surface(_))), "{sqrt3:?}");
}

/// The proptests' case count: 24 by default; `PROPTEST_CASES` sets another (a long run).
fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(24)
}

/// A closed quad-split test mesh: a random one, an N-gon prism, or the built-in model.
fn closed_mesh(seed: u64, which: usize) -> Mesh {
    match which {
        0 => random_closed(seed),
        1 => Mesh::build(shapes::ngon_prism(3 + (seed % 6) as usize)).unwrap(),
        _ => Mesh::build(shapes::default_model()).unwrap(),
    }
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

// ---------------------------------------------------------------------------------------------
// Rings around extraordinary points (`tessellate_with_rings`).

fn tessellate_rings(mesh: &Mesh, rates: &[u32], rings: &RingDepths) -> TessMesh {
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), mesh, &DualOptions::default()).unwrap();
    tess.tessellate_with_rings(rates, rings).unwrap().clone()
}

/// Random depths in `0..=max` per vertex and per face (most entries are ignored: regular
/// vertices, quads).
fn random_rings(mesh: &Mesh, seed: u64, max: u32) -> RingDepths {
    let depths = |count: usize, salt: u64| -> Vec<u32> {
        let mut state = (seed ^ salt).wrapping_mul(0x2545_F491_4F6C_DD1D) | 1;
        (0..count)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state % u64::from(max + 1)) as u32
            })
            .collect()
    };
    RingDepths { vertices: depths(mesh.vertex_count(), 0x5151), centres: depths(mesh.face_count(), 0xC3C3) }
}

/// A parameter in the frame of the nearest extraordinary-point corner of its face: the chart
/// corner (face, vertex corner `c` or N-gon centre of sub-face `s`) and `(s, t)` in face units
/// (an N-gon's sub-face coordinates halved). `None` in the middle of an N-gon's sides, where no
/// point is extraordinary.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Local {
    key: (u32, bool, usize),
    s: f64,
    t: f64,
}

impl Local {
    fn rho(self) -> f64 {
        self.s.max(self.t)
    }
    fn on_edge(self) -> bool {
        self.s == 0.0 || self.t == 0.0
    }
}

fn local(domain: subdiv_stencil::FaceDomain, p: &subdiv_tess::SurfaceParameter) -> Option<Local> {
    frames(domain, p).into_iter().next()
}

/// Every corner frame whose closed quarter (a quad's `[0, ½]²`, a sub-face's half towards its
/// corner) holds `p`: a point on the quarters' borders (a rate-1 quad's one dual point, in the
/// middle) is in several.
fn frames(domain: subdiv_stencil::FaceDomain, p: &subdiv_tess::SurfaceParameter) -> Vec<Local> {
    let (u, v, face) = (p.u, p.v, p.face.index() as u32);
    match domain {
        subdiv_stencil::FaceDomain::SubFaces { columns, .. } => {
            let (tu, tv) = (u.floor(), v.floor());
            let sub = tv as usize * columns + tu as usize;
            let (a, b) = (2.0 * (u - tu), 2.0 * (v - tv));
            let mut out = Vec::new();
            if a <= 0.5 && b <= 0.5 {
                out.push(Local { key: (face, false, sub), s: a / 2.0, t: b / 2.0 });
            }
            if a >= 0.5 && b >= 0.5 {
                out.push(Local { key: (face, true, sub), s: (1.0 - a) / 2.0, t: (1.0 - b) / 2.0 });
            }
            out
        }
        _ => [(u, v), (v, 1.0 - u), (1.0 - u, 1.0 - v), (1.0 - v, u)]
            .into_iter()
            .enumerate()
            .filter(|(_, (s, t))| *s <= 0.5 && *t <= 0.5)
            .map(|(c, (s, t))| Local { key: (face, false, c), s, t })
            .collect(),
    }
}

/// Every triangle with a ring point lies where the bound of `ErrorRates::rates` assumes:
/// band and fan triangles in one face's L-shaped region `[0, r]² \ [0, r/2)²` (their
/// off-edge corners in one face's corner frame, every radius `r` or `r/2`, `r` a power of two;
/// a fan's corners all at the last ring's `r`); outer-band triangles in one face (a dual point
/// and the diagonal point of its own corner) or across one edge (two faces' dual points and
/// the edge's point). Returns how many triangles were checked.
fn check_ring_regions(mesh: &Mesh, out: &TessMesh, rates: &[u32]) -> usize {
    let evaluator = LimitEvaluator::new(Builtin::CatmullClark.scheme(), mesh, &RefineOptions::DEFAULT).unwrap();
    let domains: Vec<_> = mesh.face_ids().map(|f| evaluator.domain(f).unwrap()).collect();
    let reach = |f: usize| if mesh.face_size(FaceId::new(f as u32)) == 4 { rates[f] } else { 2 * rates[f].div_ceil(2) };
    let locals: Vec<Option<Local>> = out.parameters.iter().map(|p| local(domains[p.face.index()], p)).collect();
    // A ring point: strictly inside its face's nearest dual points, and not the point itself.
    let ring = |v: u32| {
        let p = out.parameters[v as usize];
        // (Below the dual points by a margin: `½/n` itself is rounded in both.)
        locals[v as usize]
            .is_some_and(|l| l.rho() > 0.0 && l.rho() < 0.5 / f64::from(reach(p.face.index())) * (1.0 - 1e-9))
    };
    let mut checked = 0;
    for (k, t) in out.triangles.iter().enumerate() {
        if !t.iter().any(|&v| ring(v)) {
            continue;
        }
        checked += 1;
        let l: Vec<Local> = t.iter().map(|&v| locals[v as usize].expect("near a corner")).collect();
        let all_frames =
            |i: usize| frames(domains[out.parameters[t[i] as usize].face.index()], &out.parameters[t[i] as usize]);
        let inner: Vec<bool> =
            t.iter().map(|&v| ring(v) || locals[v as usize].is_some_and(|l| l.rho() == 0.0)).collect();
        let off_edge: Vec<&Local> = l.iter().filter(|l| !l.on_edge()).collect();
        if inner.iter().all(|&i| i) {
            let r = l.iter().map(|l| l.rho()).fold(0.0, f64::max);
            assert_eq!(r, 2f64.powi(r.log2().round() as i32), "triangle {k}: radius {r} not a power of two");
            let fan = l.iter().any(|l| l.rho() == 0.0);
            for x in &l {
                let ok = if fan { x.rho() == 0.0 || x.rho() == r } else { x.rho() == r || x.rho() == r / 2.0 };
                assert!(ok, "triangle {k}: corner at radius {} outside the band of {r}: {l:?}", x.rho());
            }
            assert!(off_edge.iter().all(|x| x.key == off_edge[0].key), "triangle {k} spans faces: {l:?}");
        } else {
            // The outer band: from the polygon's corners (dual points) to ring 1.
            let dual: Vec<usize> = (0..3).filter(|&i| !inner[i]).collect();
            let rings: Vec<&Local> = l.iter().zip(&inner).filter(|(_, i)| **i).map(|(l, _)| l).collect();
            match (dual.len(), rings.len()) {
                // Across an edge: the ring point is the edge's.
                (2, 1) => assert!(rings[0].on_edge(), "triangle {k}: {l:?}"),
                // In one face: the ring's diagonal point of the dual point's corner.
                (1, 2) => {
                    let q: Vec<&&Local> = rings.iter().filter(|x| !x.on_edge()).collect();
                    assert_eq!(q.len(), 1, "triangle {k}: {l:?}");
                    // The dual point in the diagonal point's corner quarter of the same face.
                    let same = all_frames(dual[0]).iter().any(|f| f.key == q[0].key);
                    assert!(same, "triangle {k} spans faces: {l:?}");
                    assert_eq!(rings[0].rho(), rings[1].rho(), "triangle {k}: two rings: {l:?}");
                }
                _ => panic!("triangle {k}: not an outer-band triangle: {l:?}"),
            }
        }
    }
    checked
}

/// Triangles whose facet faces away from their corners' summed limit normals.
fn flipped(out: &TessMesh) -> usize {
    out.triangles
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|v| out.positions[v as usize]);
            let normal: DVec3 = t.iter().map(|&v| out.normals[v as usize]).sum();
            (b - a).cross(c - a).dot(normal) <= 0.0
        })
        .count()
}

/// The closed checks with rings, every vertex on the limit surface, and the triangles' regions.
/// With `deep` (rings below about 2^−50, where neither the f64 parameters nor the positions
/// resolve neighbouring ring points any more) only the combinatorial checks and the surface.
fn ring_checks(mesh: &Mesh, rates: &[u32], rings: &RingDepths, deep: bool) -> TessMesh {
    let out = tessellate_rings(mesh, rates, rings);
    check_facing(&out, mesh);
    let border = if deep {
        let directed = directed_edges(&out);
        directed.keys().filter(|&&(a, b)| !directed.contains_key(&(b, a))).copied().collect()
    } else {
        check(&out)
    };
    assert!(border.is_empty(), "{} border edges on a closed mesh", border.len());
    assert_eq!(euler(&out), input_euler(mesh));
    assert_eq!(out.positions.len(), predicted_vertex_count_with_rings(mesh, false, rates, rings));
    let evaluator = LimitEvaluator::new(Builtin::CatmullClark.scheme(), mesh, &RefineOptions::DEFAULT).unwrap();
    let d = diagonal(mesh);
    let mut worst: f64 = 0.0;
    for (i, p) in out.parameters.iter().enumerate() {
        let want = evaluator.eval(p.face, p.u, p.v).unwrap();
        worst = worst.max((want.position - out.positions[i]).length() / d);
        assert!((out.normals[i].length() - 1.0).abs() < 1e-12, "vertex {i}: normal {}", out.normals[i]);
    }
    assert!(worst < 1e-12, "position off the limit surface by {worst:e} × bbox");
    if !deep {
        check_ring_regions(mesh, &out, rates);
        check_ring_radii(mesh, &out, rates, rings);
        check_ring_folds(mesh, &out, rates);
    }
    out
}

/// Where the rings fold: no band or fan triangle (nor any triangle away from the rings beyond
/// those the plain output already has) faces away from its corners' limit normals. The one
/// exception, counted and printed: the outer band's triangle across an edge, `(d_f, d_g, e)`,
/// whose edge point `e` at `r_1` (the largest power of two below the dual points' `½/n`, as the
/// bound fixes it) can lie, on the surface, just outside the chord `d_f d_g` when `r_1` is
/// close to `½/n` (seen only at valence-3 points, vertices and triangles' centres, where the
/// characteristic map opens each face to 120°, so the chord between two faces' points passes
/// closer to the point than in the parameters): a sliver, within ε like any other triangle, but
/// folded.
fn check_ring_folds(mesh: &Mesh, out: &TessMesh, rates: &[u32]) {
    let evaluator = LimitEvaluator::new(Builtin::CatmullClark.scheme(), mesh, &RefineOptions::DEFAULT).unwrap();
    let reach = |f: FaceId| if mesh.face_size(f) == 4 { rates[f.index()] } else { 2 * rates[f.index()].div_ceil(2) };
    let locals: Vec<Local> = out
        .parameters
        .iter()
        .map(|p| {
            frames(evaluator.domain(p.face).unwrap(), p).into_iter().next().unwrap_or(Local {
                key: (0, false, 0),
                s: 1.0,
                t: 1.0,
            })
        })
        .collect();
    let ring = |v: u32| {
        let (l, f) = (locals[v as usize], out.parameters[v as usize].face);
        l.rho() > 0.0 && l.rho() < 0.5 / f64::from(reach(f)) * (1.0 - 1e-9)
    };
    let (mut away, mut slivers) = (0, 0);
    for t in &out.triangles {
        let [a, b, c] = t.map(|v| out.positions[v as usize]);
        let normal: DVec3 = t.iter().map(|&v| out.normals[v as usize]).sum();
        if (b - a).cross(c - a).dot(normal) > 0.0 {
            continue;
        }
        let rings: Vec<u32> = t.iter().copied().filter(|&v| ring(v)).collect();
        let centre = t.iter().any(|&v| locals[v as usize].rho() == 0.0);
        match (rings.len(), centre) {
            (0, _) => away += 1,
            (1, false) if locals[rings[0] as usize].on_edge() => slivers += 1,
            _ => panic!("a ring triangle folds: {:?}", t.map(|v| locals[v as usize])),
        }
    }
    let plain = flipped(&tessellate(Builtin::CatmullClark, mesh, rates));
    assert!(away <= plain, "{away} triangles away from the rings face away, {plain} without rings");
    if slivers > 0 {
        eprintln!("  {slivers} outer-band slivers across an edge fold ({} triangles)", out.triangles.len());
    }
}

/// Each extraordinary point's rings are at exactly the radii the bound assumes: `2^−e` for
/// `e` from `d1` (the least with `2^−e` strictly below the nearest dual points' `½ / finest`)
/// to `max(depth, d1)`, with one diagonal point per face (sub-face) corner and radius; none
/// where the depth is 0 or the point is regular. Closed meshes.
fn check_ring_radii(mesh: &Mesh, out: &TessMesh, rates: &[u32], rings: &RingDepths) {
    let evaluator = LimitEvaluator::new(Builtin::CatmullClark.scheme(), mesh, &RefineOptions::DEFAULT).unwrap();
    let reach = |f: FaceId| {
        if mesh.face_size(f) == 4 { rates[f.index()] } else { 2 * rates[f.index()].div_ceil(2) }
    };
    let mut found: HashMap<(u32, bool, usize), Vec<f64>> = HashMap::new();
    for p in &out.parameters {
        let Some(l) = local(evaluator.domain(p.face).unwrap(), p) else { continue };
        let inside = l.rho() > 0.0 && l.rho() < 0.5 / f64::from(reach(p.face)) * (1.0 - 1e-9);
        if inside && l.s == l.t {
            found.entry(l.key).or_default().push(l.rho());
        }
    }
    for f in mesh.face_ids() {
        let size = mesh.face_size(f);
        let corners: Vec<(bool, usize)> =
            (0..size).map(|c| (false, c)).chain((0..if size == 4 { 0 } else { size }).map(|s| (true, s))).collect();
        for (centre, c) in corners {
            let (depth, finest) = if centre {
                (rings.centres[f.index()], reach(f))
            } else {
                let v = mesh.origin(mesh.face_half_edges(f).nth(c).unwrap());
                let faces: Vec<FaceId> = mesh.vertex_faces(v).collect();
                let extraordinary = faces.len() >= 3 && faces.len() != 4 && !mesh.is_boundary_vertex(v);
                let depth = if extraordinary { rings.vertices[v.index()] } else { 0 };
                (depth, faces.iter().map(|&g| reach(g)).max().unwrap())
            };
            let mut want = Vec::new();
            if depth > 0 {
                let mut first = 0;
                while (1u64 << first) <= 2 * u64::from(finest) {
                    first += 1;
                }
                want.extend((first..=depth.max(first)).map(|e| 0.5f64.powi(e as i32)));
            }
            let mut got = found.remove(&(f.index() as u32, centre, c)).unwrap_or_default();
            got.sort_by(|a, b| b.total_cmp(a));
            assert_eq!(got, want, "{f}, corner {c} (centre: {centre}), depth {depth}, finest reach {finest}");
        }
    }
    assert!(found.is_empty(), "diagonal ring points at no corner: {found:?}");
}

#[test]
fn rings_on_fixed_meshes_are_watertight_and_in_their_regions() {
    for (name, mesh) in quad_meshes() {
        for seed in 0..3 {
            let rates = rates_for(&mesh, seed, 9);
            let rings = random_rings(&mesh, seed, 6);
            let out = ring_checks(&mesh, &rates, &rings, false);
            // The torus is regular: nothing to ring.
            let ringed = check_ring_regions(&mesh, &out, &rates);
            assert_eq!(ringed > 0, name != "torus", "{name}: {ringed} ring triangles");
            let plain = tessellate(Builtin::CatmullClark, &mesh, &rates);
            eprintln!(
                "{name}, seed {seed}: {} vertices with rings, {} without",
                out.positions.len(),
                plain.positions.len()
            );
        }
        // Depth 0 everywhere: the plain output, bit for bit.
        let rates = rates_for(&mesh, 7, 9);
        let none = RingDepths { vertices: vec![0; mesh.vertex_count()], centres: vec![0; mesh.face_count()] };
        assert_eq!(tessellate_rings(&mesh, &rates, &none), tessellate(Builtin::CatmullClark, &mesh, &rates));
    }
}

/// Open meshes: rings around interior extraordinary points (a pole's centre, a prism's cap
/// centre beside a hole) leave the border alone — the same border edges, by position, as
/// without rings — and border vertices (whatever their depth) keep their fans.
#[test]
fn rings_leave_borders_alone() {
    let mut holed = shapes::ngon_prism(6);
    holed.tags.holes.push(FaceId::new(2));
    for soup in [shapes::pole(3), shapes::pole(5), shapes::pole(7), holed, shapes::quad_grid(3, 2)] {
        let mesh = Mesh::build(soup).unwrap();
        for seed in 0..3 {
            let rates = rates_for(&mesh, seed, 9);
            let rings = random_rings(&mesh, seed, 9);
            let out = tessellate_rings(&mesh, &rates, &rings);
            let border = check(&out);
            assert_eq!(euler(&out), input_euler(&mesh));
            assert_eq!(out.positions.len(), predicted_vertex_count_with_rings(&mesh, false, &rates, &rings));
            let plain = tessellate(Builtin::CatmullClark, &mesh, &rates);
            let key = |m: &TessMesh, (a, b): (u32, u32)| {
                let (p, q) = (m.positions[a as usize], m.positions[b as usize]);
                [p.x, p.y, p.z, q.x, q.y, q.z].map(f64::to_bits)
            };
            let mut with: Vec<_> = border.iter().map(|&e| key(&out, e)).collect();
            let mut without: Vec<_> = check(&plain).iter().map(|&e| key(&plain, e)).collect();
            with.sort_unstable();
            without.sort_unstable();
            assert_eq!(with, without, "seed {seed}: the border moved");
            check_ring_regions(&mesh, &out, &rates);
        }
    }
}

/// The deepest rings allowed (2^−60 face units): watertight, the predicted count, every point
/// on the limit surface (in f64 the innermost rings' positions coincide with the limit point,
/// so positions are not checked for distinctness here).
#[test]
fn deepest_rings_are_exact() {
    for soup in [shapes::cube(), shapes::ngon_prism(5), shapes::ngon_prism(7)] {
        let mesh = Mesh::build(soup).unwrap();
        let rates = rates_for(&mesh, 3, 5);
        let rings = RingDepths {
            vertices: vec![MAX_DUAL_RING_DEPTH; mesh.vertex_count()],
            centres: vec![MAX_DUAL_RING_DEPTH; mesh.face_count()],
        };
        ring_checks(&mesh, &rates, &rings, true);
    }
}

/// Rings are ordinary vertices for the animation path: a moved cage through `update_cage` and
/// `update_cage_flat` equals a fresh tessellation of the moved mesh.
#[test]
fn rings_follow_the_cage() {
    let mesh = Mesh::build(shapes::ngon_prism(5)).unwrap();
    let rates = rates_for(&mesh, 4, 6);
    let rings = random_rings(&mesh, 4, 8);
    let moved: Vec<DVec3> =
        mesh.positions().iter().enumerate().map(|(i, p)| *p * 1.5 + DVec3::new(0.1 * i as f64, 0.0, 0.2)).collect();
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default()).unwrap();
    tess.tessellate_with_rings(&rates, &rings).unwrap();
    let updated = tess.update_cage(&moved).unwrap().clone();
    let mut soup = shapes::ngon_prism(5);
    soup.positions_mut().copy_from_slice(&moved);
    let fresh = tessellate_rings(&Mesh::build(soup).unwrap(), &rates, &rings);
    assert_eq!(updated.triangles, fresh.triangles);
    for (a, b) in updated.positions.iter().zip(&fresh.positions) {
        assert!((*a - *b).length() < 1e-12, "{a} vs {b}");
    }
    let mut flat = FlatMesh::default();
    tess.update_cage_flat(&moved, &mut flat).unwrap();
    assert_eq!(flat.vertices.len(), 6 * fresh.positions.len());
    for (k, p) in fresh.positions.iter().enumerate() {
        assert!(
            (DVec3::new(
                f64::from(flat.vertices[6 * k]),
                f64::from(flat.vertices[6 * k + 1]),
                f64::from(flat.vertices[6 * k + 2])
            ) - *p)
                .length()
                < 1e-5
        );
    }
}

#[test]
fn bad_rings_are_typed_errors() {
    let mesh = Mesh::build(shapes::cube()).unwrap();
    let rates = vec![2; mesh.face_count()];
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default()).unwrap();
    let good = RingDepths { vertices: vec![1; mesh.vertex_count()], centres: vec![0; mesh.face_count()] };
    let short = RingDepths { vertices: vec![1; 3], ..good.clone() };
    assert!(matches!(tess.tessellate_with_rings(&rates, &short), Err(TessError::RingCount { what: "vertices", .. })));
    let long = RingDepths { centres: vec![0; 9], ..good.clone() };
    assert!(matches!(tess.tessellate_with_rings(&rates, &long), Err(TessError::RingCount { what: "centres", .. })));
    let mut deep = good.clone();
    deep.vertices[5] = MAX_DUAL_RING_DEPTH + 1;
    let err = tess.tessellate_with_rings(&rates, &deep);
    assert!(matches!(err, Err(TessError::RingDepth { depth: 61, max: 60, .. })), "{err:?}");
    let mut deep = good.clone();
    deep.centres[2] = 99;
    assert!(matches!(tess.tessellate_with_rings(&rates, &deep), Err(TessError::RingDepth { depth: 99, .. })));
    assert!(tess.tessellate_with_rings(&rates, &good).is_ok());
}

/// Triangle splits (Loop): rings around interior vertices of valence ≠ 6 (the icosahedron's 5,
/// the octahedron's 4, the tetrahedron's 3; none on the regular torus), watertight, counted,
/// every vertex on the limit surface, at random rates and depths.
#[test]
fn loop_rings_are_watertight_and_on_the_surface() {
    let scheme = Builtin::Loop.scheme();
    for (name, soup) in [
        ("icosahedron", shapes::icosahedron()),
        ("octahedron", shapes::octahedron()),
        ("tetrahedron", shapes::tetrahedron()),
        ("torus", shapes::triangle_torus(6, 4)),
    ] {
        let mesh = Mesh::build(soup).unwrap();
        let evaluator = LimitEvaluator::new(scheme, &mesh, &RefineOptions::DEFAULT).unwrap();
        for seed in 0..4 {
            let rates = rates_for(&mesh, seed, 9);
            let rings = random_rings(&mesh, seed, 10);
            let mut tess = DualTessellator::new(scheme, &mesh, &DualOptions::default()).unwrap();
            let out = tess.tessellate_with_rings(&rates, &rings).unwrap().clone();
            let plain = tess.tessellate(&rates).unwrap().clone();
            check_facing(&out, &mesh);
            assert!(check(&out).is_empty(), "{name}: border edges on a closed mesh");
            assert_eq!(euler(&out), input_euler(&mesh));
            assert_eq!(out.positions.len(), predicted_vertex_count_with_rings(&mesh, true, &rates, &rings));
            let regular = name == "torus";
            assert_eq!(out.positions.len() == plain.positions.len(), regular, "{name}: rings only where irregular");
            let d = diagonal(&mesh);
            let mut worst: f64 = 0.0;
            for (i, p) in out.parameters.iter().enumerate() {
                // Rounding may put a point of a triangle's third side just outside: back onto it.
                let (u, v) = if p.u + p.v > 1.0 { (p.u, 1.0 - p.u) } else { (p.u, p.v) };
                let want = evaluator.eval(p.face, u, v).unwrap();
                worst = worst.max((want.position - out.positions[i]).length() / d);
            }
            assert!(worst < 1e-12, "{name}: off the limit surface by {worst:e} × bbox");
            assert!(
                flipped(&out) <= flipped(&plain),
                "{name}: {} flipped, {} without rings",
                flipped(&out),
                flipped(&plain)
            );
            eprintln!(
                "{name}, seed {seed}: {} vertices with rings, {} without",
                out.positions.len(),
                plain.positions.len()
            );
        }
    }
}

/// The guarantee end to end: rates and ring depths from `ErrorRates::rates`, then every limit
/// point sampled — each face's 33 × 33 grid (each N-gon sub-face's), and grids shrinking
/// towards every corner of every face and sub-face down to 2^−30 — is within ε of the output.
#[test]
fn rings_keep_the_surface_within_tolerance() {
    let cc = Builtin::CatmullClark.scheme();
    for (name, soup) in [
        ("cube", shapes::cube()),
        ("default model", shapes::default_model()),
        ("pentagonal prism", shapes::ngon_prism(5)),
    ] {
        let mesh = Mesh::build(soup).unwrap();
        let bounds = QuadtreeTessellator::new(cc, &mesh).unwrap();
        let evaluator = LimitEvaluator::new(cc, &mesh, &RefineOptions::DEFAULT).unwrap();
        // The samples do not depend on the tolerance: evaluated once.
        let mut samples: Vec<DVec3> = Vec::new();
        // The samples within 2^−8 of a corner (where the rings are), counted apart below.
        let mut near: Vec<DVec3> = Vec::new();
        for f in mesh.face_ids() {
            let domain = evaluator.domain(f).unwrap();
            samples.extend(evaluator.grid(f, 32).unwrap().into_iter().map(|(_, p)| p.position));
            // Charts: the face, or each sub-face; chart point (x, y) in [0, 1]² is the face's
            // (origin + scale · (x, y)).
            let charts: Vec<((f64, f64), f64)> = match domain {
                subdiv_stencil::FaceDomain::SubFaces { size, columns } => {
                    (0..size).map(|s| (((s % columns) as f64, (s / columns) as f64), 0.5)).collect()
                }
                _ => vec![((0.0, 0.0), 1.0)],
            };
            for chart in &charts {
                for corner in 0..4 {
                    for k in 1..=30 {
                        let side = 0.5f64.powi(k);
                        for j in 0..=4 {
                            for i in 0..=4 {
                                let (a, b) = (side * f64::from(i) / 4.0, side * f64::from(j) / 4.0);
                                let (x, y) = [(a, b), (1.0 - a, b), (1.0 - a, 1.0 - b), (a, 1.0 - b)][corner];
                                let ((u0, v0), scale) = *chart;
                                let (u, v) = (u0 + scale * x, v0 + scale * y);
                                let p = evaluator.eval(f, u, v).unwrap().position;
                                samples.push(p);
                                if k >= 8 {
                                    near.push(p);
                                }
                            }
                        }
                    }
                }
            }
        }
        for r in [3e-2, 1e-2] {
            let rates = ErrorRates::new(Tolerance::Relative(r)).rates(&bounds, &mesh).unwrap();
            let epsilon = Tolerance::Relative(r).absolute(bounds.diagonal()).unwrap();
            let out = tessellate_rings(&mesh, &rates.faces, &rates.rings);
            check_ring_folds(&mesh, &out, &rates.faces);
            let buckets = MeshDistance::new(&out, epsilon);
            let worst = samples.iter().map(|&p| buckets.distance(&out, p)).fold(0.0, f64::max);
            eprintln!(
                "{name}, ε = {r} × bbox: {} triangles, rings {:?} / {:?}, {} samples, worst distance / ε = {:.4}",
                out.triangles.len(),
                rates.rings.vertices.iter().max(),
                rates.rings.centres.iter().max(),
                samples.len(),
                worst / epsilon
            );
            assert!(
                worst <= epsilon,
                "{name}, ε = {r} × bbox: a limit point {worst:e} from the output (ε = {epsilon:e})"
            );
            // For comparison (not asserted: the bound is a bound, the plain output may well be
            // within ε too): the same rates without rings.
            let plain = tessellate(Builtin::CatmullClark, &mesh, &rates.faces);
            let buckets = MeshDistance::new(&plain, epsilon);
            let plain_worst = samples.iter().map(|&p| buckets.distance(&plain, p)).fold(0.0, f64::max);
            let plain_near = near.iter().map(|&p| buckets.distance(&plain, p)).fold(0.0, f64::max);
            let buckets = MeshDistance::new(&out, epsilon);
            let ringed_near = near.iter().map(|&p| buckets.distance(&out, p)).fold(0.0, f64::max);
            eprintln!(
                "  within 2^−8 of a corner: worst / ε {:.4} with rings, {:.4} without; everywhere without rings: {:.4}",
                ringed_near / epsilon,
                plain_near / epsilon,
                plain_worst / epsilon
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn random_meshes_with_rings_are_watertight(seed in 0u64..1_000_000, which in 0usize..3, max in 1u32..24) {
        let mesh = closed_mesh(seed, which);
        let rates = rates_for(&mesh, seed, max);
        let rings = random_rings(&mesh, seed, 12);
        ring_checks(&mesh, &rates, &rings, false);
    }
}
