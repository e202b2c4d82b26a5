//! Helpers of the dual-grid tests (`dual.rs`, `dual_rings.rs`): tessellations with their
//! watertightness, orientation and boundary checks, limit-surface checks, random meshes and
//! rates.

// Each test file uses its own subset of the helpers.
#![allow(dead_code)]

use std::collections::HashMap;

use glam::DVec3;
use subdiv_eval::Method;
use subdiv_mesh::{FaceId, Mesh, PolygonSoup, VertexId, shapes};
use subdiv_schemes::{Builtin, RefineOptions};
use subdiv_stencil::LimitEvaluator;
use subdiv_tess::dual::predicted_vertex_count;
use subdiv_tess::rates::RingDepths;
use subdiv_tess::{DualOptions, DualTessellator, TessMesh};

/// The tessellation of `mesh` at `rates`, without the mesh's channels (whose seams would add
/// extra normals equal to their vertices'; `subdiv/tests/channels.rs` tests them).
pub(crate) fn tessellate(builtin: Builtin, mesh: &Mesh, rates: &[u32]) -> TessMesh {
    let mut tess = DualTessellator::new(builtin.scheme(), mesh, &DualOptions::default().with_channels(false)).unwrap();
    tess.tessellate(rates).unwrap().clone()
}

/// `mesh` without its channels, as [`tessellate`] cuts it (the vertex count's prediction
/// counts the seams of the mesh's channels).
pub(crate) fn without_channels(mesh: &Mesh) -> Mesh {
    let mut bare = mesh.clone();
    bare.clear_channels();
    bare
}

/// Each directed edge once; returns the directed edges without an opposite (the border).
pub(crate) fn directed_edges(out: &TessMesh) -> HashMap<(u32, u32), usize> {
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
pub(crate) fn check(out: &TessMesh) -> Vec<(u32, u32)> {
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

pub(crate) fn euler(out: &TessMesh) -> i64 {
    let directed = directed_edges(out);
    let edges = directed.keys().filter(|&&(a, b)| a < b || !directed.contains_key(&(b, a))).count();
    out.positions.len() as i64 - edges as i64 + out.triangles.len() as i64
}

/// The input's χ, without hole faces.
pub(crate) fn input_euler(mesh: &Mesh) -> i64 {
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
pub(crate) fn check_facing(out: &TessMesh, mesh: &Mesh) {
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

pub(crate) fn closed_checks(builtin: Builtin, mesh: &Mesh, rates: &[u32]) -> TessMesh {
    let out = tessellate(builtin, mesh, rates);
    check_facing(&out, mesh);
    let border = check(&out);
    assert!(border.is_empty(), "{} border edges on a closed mesh", border.len());
    assert_eq!(euler(&out), input_euler(mesh));
    assert_eq!(out.positions.len(), predicted_vertex_count(&without_channels(mesh), builtin.scheme().split(), rates));
    out
}

/// The cycles of a successor map (each key's chain back to itself), from the least key up.
pub(crate) fn cycles<T: Copy + Ord + std::hash::Hash>(next: &HashMap<T, T>) -> Vec<Vec<T>> {
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
pub(crate) fn loops(border: &[(u32, u32)]) -> Vec<Vec<u32>> {
    let next: HashMap<u32, u32> = border.iter().copied().collect();
    assert_eq!(next.len(), border.len(), "a vertex starts two border edges");
    cycles(&next)
}

/// Open input: the output's boundary loops are the input's, through the limit points of the
/// input's boundary vertices in order.
pub(crate) fn open_checks(builtin: Builtin, mesh: &Mesh, rates: &[u32]) {
    let out = tessellate(builtin, mesh, rates);
    let border = check(&out);
    assert_eq!(euler(&out), input_euler(mesh));
    assert_eq!(out.positions.len(), predicted_vertex_count(&without_channels(mesh), builtin.scheme().split(), rates));
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
        let c = mesh.corner(h);
        let domain = evaluator.domain(f).unwrap();
        let p = match domain {
            subdiv_stencil::FaceDomain::Quad => [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)][c],
            subdiv_stencil::FaceDomain::Triangle | subdiv_stencil::FaceDomain::Ternary => {
                [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)][c]
            }
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
pub(crate) fn refined_cube() -> Mesh {
    let cube = Mesh::build(shapes::cube()).unwrap();
    subdiv_schemes::refine_uniform(&cube, Builtin::CatmullClark.scheme(), 2, &RefineOptions::DEFAULT).unwrap()
}

pub(crate) fn diagonal(mesh: &Mesh) -> f64 {
    mesh.bounding_box().map_or(1.0, |(lo, hi)| lo.distance(hi))
}

/// Every output vertex equals the exact limit point at its parameter (1e-12 × bbox), normals
/// to 1e-10.
pub(crate) fn on_limit_surface(builtin: Builtin, mesh: &Mesh, rates: &[u32]) {
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
    // Its normals come through its own eigenbasis solves: measured up to 1.1e-10 (the bishop).
    assert!(worst_n < 1e-9, "normal off the eigenbasis route by {worst_n:e}");
}

pub(crate) fn rates_for(mesh: &Mesh, seed: u64, max: u32) -> Vec<u32> {
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

pub(crate) fn quad_meshes() -> Vec<(&'static str, Mesh)> {
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
pub(crate) fn random_closed(seed: u64) -> Mesh {
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

/// The proptests' case count: 24 by default; `PROPTEST_CASES` sets another (a long run).
pub(crate) fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(24)
}

/// A closed quad-split test mesh: a random one, an N-gon prism, or the built-in model.
pub(crate) fn closed_mesh(seed: u64, which: usize) -> Mesh {
    match which {
        0 => random_closed(seed),
        1 => Mesh::build(shapes::ngon_prism(3 + (seed % 6) as usize)).unwrap(),
        _ => Mesh::build(shapes::default_model()).unwrap(),
    }
}

pub(crate) fn tessellate_rings(mesh: &Mesh, rates: &[u32], rings: &RingDepths) -> TessMesh {
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), mesh, &DualOptions::default()).unwrap();
    tess.tessellate_with_rings(rates, rings).unwrap().clone()
}

/// Random depths in `0..=max` per vertex and per face (most entries are ignored: regular
/// vertices, quads).
pub(crate) fn random_rings(mesh: &Mesh, seed: u64, max: u32) -> RingDepths {
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
    RingDepths {
        vertices: depths(mesh.vertex_count(), 0x5151),
        centres: depths(mesh.face_count(), 0xC3C3),
        graded: Vec::new(),
    }
}

/// Meshes with sharp features: infinitely sharp crease loops and paths (straight, turning,
/// ending in darts), corners, and semi-sharp edges and corners, Catmull-Clark and Loop.
pub(crate) fn creased_meshes() -> Vec<(&'static str, Builtin, Mesh)> {
    use subdiv_mesh::{CornerTag, CreaseTag};
    let crease = |soup: &mut PolygonSoup, path: &[u32], sharpness: f64| {
        for w in path.windows(2) {
            soup.tags.creases.push(CreaseTag { vertices: [VertexId::new(w[0]), VertexId::new(w[1])], sharpness });
        }
    };
    let corner = |soup: &mut PolygonSoup, v: u32, sharpness: f64| {
        soup.tags.corners.push(CornerTag { vertex: VertexId::new(v), sharpness });
    };
    let mut out = Vec::new();
    // The cube's top face ringed by sharp edges, one of its corners a corner.
    let mut cube = shapes::cube();
    let top: Vec<u32> = cube.face(FaceId::new(0)).iter().map(|v| v.index() as u32).collect();
    crease(&mut cube, &[top[0], top[1], top[2], top[3], top[0]], 10.0);
    corner(&mut cube, top[2], 10.0);
    out.push(("cube, sharp loop and corner", Builtin::CatmullClark, Mesh::build(cube).unwrap()));
    // Semi-sharp: an edge of sharpness 2.5 beside one of 1.2, a corner of 1.5.
    let mut cube = shapes::cube();
    crease(&mut cube, &[top[0], top[1], top[2]], 2.5);
    corner(&mut cube, top[3], 1.5);
    out.push(("cube, semi-sharp", Builtin::CatmullClark, Mesh::build(cube).unwrap()));
    // A torus with a straight sharp ring (regular crease vertices) and a dart path.
    let (m, n) = (6u32, 5u32);
    let mut torus = shapes::quad_torus(m as usize, n as usize);
    let ring: Vec<u32> = (0..=m).map(|i| (i % m) * n).collect();
    crease(&mut torus, &ring, 10.0);
    crease(&mut torus, &[2, 3], 10.0);
    out.push(("torus, sharp ring and dart", Builtin::CatmullClark, Mesh::build(torus).unwrap()));
    // Loop: an icosahedron with a sharp path ending in darts, and a semi-sharp edge.
    let mut ico = shapes::icosahedron();
    let f0: Vec<u32> = ico.face(FaceId::new(0)).iter().map(|v| v.index() as u32).collect();
    crease(&mut ico, &[f0[0], f0[1], f0[2]], 10.0);
    let f5: Vec<u32> = ico.face(FaceId::new(5)).iter().map(|v| v.index() as u32).collect();
    crease(&mut ico, &[f5[0], f5[1]], 1.5);
    out.push(("icosahedron, sharp path and semi-sharp edge", Builtin::Loop, Mesh::build(ico).unwrap()));
    out
}
