//! Dual-grid stitching with rings of exact points around extraordinary points
//! (`tessellate_with_rings`): watertight, each triangle in the region the tolerance bound
//! covers, no folds, the radii as specified, borders left alone, on the cage after it moves,
//! within the tolerance, and typed errors.

#![allow(clippy::print_stderr)]

mod dual_support;

use std::collections::HashMap;

use glam::DVec3;
use proptest::prelude::*;
use subdiv_mesh::{FaceId, Mesh, PolygonSoup, shapes};
use subdiv_schemes::{Builtin, RefineOptions, Split};
use subdiv_stencil::LimitEvaluator;
use subdiv_tess::check::MeshDistance;
use subdiv_tess::dual::{MAX_DUAL_RING_DEPTH, predicted_vertex_count_with_rings};
use subdiv_tess::rates::{ErrorRates, RingDepths};
use subdiv_tess::{DualOptions, DualTessellator, FlatMesh, QuadtreeTessellator, TessError, TessMesh, Tolerance};

use dual_support::*;

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
    assert_eq!(out.positions.len(), predicted_vertex_count_with_rings(mesh, Split::Quad, rates, rings));
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
        let none = RingDepths {
            vertices: vec![0; mesh.vertex_count()],
            centres: vec![0; mesh.face_count()],
            graded: Vec::new(),
        };
        assert_eq!(tessellate_rings(&mesh, &rates, &none), tessellate(Builtin::CatmullClark, &mesh, &rates));
    }
}

/// Open meshes: rings around interior extraordinary points (a pole's centre, a prism's cap
/// centre beside a hole) and around border vertices in open runs keep the border where it was —
/// every border vertex of the output without rings is still one, the others are ring points on
/// the mesh's border edges (the border curve sampled more finely near the vertex) — watertight
/// inside, with the predicted count.
#[test]
fn rings_keep_borders_on_the_border() {
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
            assert_eq!(out.positions.len(), predicted_vertex_count_with_rings(&mesh, Split::Quad, &rates, &rings));
            let plain = tessellate(Builtin::CatmullClark, &mesh, &rates);
            let key = |m: &TessMesh, v: u32| m.positions[v as usize].to_array().map(f64::to_bits);
            let with: std::collections::HashSet<_> = border.iter().flat_map(|&(a, b)| [a, b]).collect();
            let with_keys: std::collections::HashSet<_> = with.iter().map(|&v| key(&out, v)).collect();
            for (a, b) in check(&plain) {
                for v in [a, b] {
                    assert!(with_keys.contains(&key(&plain, v)), "seed {seed}: border vertex {v} left the border");
                }
            }
            let plain_keys: std::collections::HashSet<_> =
                check(&plain).iter().flat_map(|&(a, b)| [key(&plain, a), key(&plain, b)]).collect();
            for &v in with.iter().filter(|&&v| !plain_keys.contains(&key(&out, v))) {
                let p = out.parameters[v as usize];
                let on_side = [p.u, p.v].iter().any(|&t| t == 0.0 || t == 1.0);
                assert!(on_side, "seed {seed}: new border vertex {v} at {p:?} is not on a face's side");
            }
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
            graded: Vec::new(),
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
    let good =
        RingDepths { vertices: vec![1; mesh.vertex_count()], centres: vec![0; mesh.face_count()], graded: Vec::new() };
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
/// the octahedron's 4, the tetrahedron's 3; none on the regular torus), and open rings around
/// the border vertices of an open octahedron and a holed icosahedron, watertight (inside),
/// counted, every vertex on the limit surface, at random rates and depths.
#[test]
fn loop_rings_are_watertight_and_on_the_surface() {
    let scheme = Builtin::Loop.scheme();
    let octahedron = shapes::octahedron();
    let open = PolygonSoup::from_indices(
        octahedron.positions().to_vec(),
        octahedron.faces().skip(1).map(|f| f.iter().map(|v| v.index() as u32).collect::<Vec<_>>()),
    );
    let mut holed = shapes::icosahedron();
    holed.tags.holes.push(FaceId::new(0));
    for (name, soup) in [
        ("icosahedron", shapes::icosahedron()),
        ("octahedron", shapes::octahedron()),
        ("tetrahedron", shapes::tetrahedron()),
        ("torus", shapes::triangle_torus(6, 4)),
        ("open octahedron", open),
        ("holed icosahedron", holed),
    ] {
        let closed = !name.starts_with("open") && !name.starts_with("holed");
        let mesh = Mesh::build(soup).unwrap();
        let evaluator = LimitEvaluator::new(scheme, &mesh, &RefineOptions::DEFAULT).unwrap();
        for seed in 0..4 {
            let rates = rates_for(&mesh, seed, 9);
            let rings = random_rings(&mesh, seed, 10);
            let mut tess = DualTessellator::new(scheme, &mesh, &DualOptions::default()).unwrap();
            let out = tess.tessellate_with_rings(&rates, &rings).unwrap().clone();
            let plain = tess.tessellate(&rates).unwrap().clone();
            check_facing(&out, &mesh);
            let border = check(&out);
            assert_eq!(border.is_empty(), closed, "{name}: {} border edges", border.len());
            assert_eq!(euler(&out), input_euler(&mesh));
            assert_eq!(out.positions.len(), predicted_vertex_count_with_rings(&mesh, Split::Triangle, &rates, &rings));
            let regular = name == "torus";
            assert_eq!(out.positions.len() == plain.positions.len(), regular, "{name}: rings only where irregular");
            let d = diagonal(&mesh);
            let mut worst: f64 = 0.0;
            for (i, p) in out.parameters.iter().enumerate() {
                // Rounding may put a point of a triangle's third side (at a non-dyadic border
                // point, just outside): a hair inside instead, far below the tolerance.
                let sum = p.u + p.v;
                let (u, v) =
                    if sum > 1.0 - 1e-15 { (p.u * (1.0 - 1e-15) / sum, p.v * (1.0 - 1e-15) / sum) } else { (p.u, p.v) };
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

/// Limit points sampled on `mesh`: each face's 33 × 33 grid (each N-gon sub-face's), and grids
/// shrinking towards every corner of every face and sub-face down to 2^−30; then, apart, the
/// samples within 2^−8 of a corner (where the rings are).
fn limit_samples(mesh: &Mesh, evaluator: &LimitEvaluator) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut samples: Vec<DVec3> = Vec::new();
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
    (samples, near)
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
        let (samples, near) = limit_samples(&mesh, &evaluator);
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

/// Graded grids (`ErrorRates`' default): every face around an extraordinary point — quads at
/// such a corner, N-gons — takes a grid graded toward it, with far fewer points than the
/// uniform rates that meet the same bound; the output is watertight where the mesh is closed
/// (sharp edges and texture seams included), counted as predicted, on the surface, and every
/// sampled limit point is within ε of it, open meshes too.
#[test]
fn graded_grids_are_watertight_smaller_and_within_tolerance() {
    let builtin = Builtin::CatmullClark;
    let sharp = creased_meshes().into_iter().find(|(name, ..)| name.contains("sharp loop")).unwrap().2;
    for (name, mesh, closed) in [
        ("cube", Mesh::build(shapes::cube()).unwrap(), true),
        ("pentagonal prism", Mesh::build(shapes::ngon_prism(5)).unwrap(), true),
        ("default model", Mesh::build(shapes::default_model()).unwrap(), true),
        ("cube, sharp loop and corner", sharp, true),
        ("cube, a chart per face", Mesh::build(shapes::face_charts(shapes::cube())).unwrap(), true),
        ("open valence-5 pole", Mesh::build(shapes::pole(5)).unwrap(), false),
    ] {
        let bounds = QuadtreeTessellator::new(builtin.scheme(), &mesh).unwrap();
        let r = 1e-3;
        let graded = ErrorRates::new(Tolerance::Relative(r)).rates(&bounds, &mesh).unwrap();
        let uniform = ErrorRates { max_rate: 1 << 16, ..ErrorRates::new(Tolerance::Relative(r)) }
            .with_graded(false)
            .rates(&bounds, &mesh)
            .unwrap();
        assert!(uniform.rings.graded.is_empty(), "{name}: graded grids without grading");
        // Graded exactly where a face has an extraordinary point (a ring depth) of its own.
        for f in mesh.face_ids() {
            let ringed =
                mesh.face_vertices(f).iter().any(|v| graded.rings.vertices[v.index()] > 0) || mesh.face_size(f) != 4;
            assert_eq!(graded.rings.graded[f.index()].is_some(), ringed, "{name}: face {f:?}");
        }
        let count = |rates: &subdiv_tess::rates::DualRates| {
            predicted_vertex_count_with_rings(&mesh, Split::Quad, &rates.faces, &rates.rings)
        };
        let (graded_points, uniform_points) = (count(&graded), count(&uniform));
        eprintln!(
            "{name}, ε = {r} × bbox: graded {graded_points} points (largest rate {:?}), uniform {uniform_points} ({:?})",
            graded.faces.iter().max(),
            uniform.faces.iter().max()
        );
        assert!(3 * graded_points < uniform_points, "{name}: {graded_points} points graded, {uniform_points} uniform");
        let out = if closed {
            ring_checks(&mesh, &graded.faces, &graded.rings, true)
        } else {
            let out = tessellate_rings(&mesh, &graded.faces, &graded.rings);
            assert_eq!(out.positions.len(), graded_points, "{name}");
            out
        };
        let evaluator = LimitEvaluator::new(builtin.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
        let epsilon = Tolerance::Relative(r).absolute(bounds.diagonal()).unwrap();
        let (samples, _) = limit_samples(&mesh, &evaluator);
        let buckets = MeshDistance::new(&out, epsilon);
        let worst = samples.iter().map(|&p| buckets.distance(&out, p)).fold(0.0, f64::max);
        eprintln!("  {} triangles, worst distance / ε = {:.4}", out.triangles.len(), worst / epsilon);
        assert!(worst <= epsilon, "{name}: a limit point {worst:e} from the output (ε = {epsilon:e})");
    }
}

/// A graded grid that does not fit its face is a typed error, not a topology.
#[test]
fn bad_graded_grids_are_typed_errors() {
    let mesh = Mesh::build(shapes::ngon_prism(5)).unwrap();
    let bounds = QuadtreeTessellator::new(Builtin::CatmullClark.scheme(), &mesh).unwrap();
    let good = ErrorRates::new(Tolerance::Relative(1e-2)).rates(&bounds, &mesh).unwrap();
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default()).unwrap();
    assert!(tess.tessellate_with_rings(&good.faces, &good.rings).is_ok());
    let (pentagon, quad) = {
        let f = |size: usize| mesh.face_ids().find(|&f| mesh.face_size(f) == size).unwrap().index();
        (f(5), f(4))
    };
    let mut cases: Vec<(&str, RingDepths)> = Vec::new();
    let mut short = good.rings.clone();
    short.graded.pop();
    cases.push(("one grid too few", short));
    let mut unequal = good.rings.clone();
    if let Some(grid) = unequal.graded[pentagon].as_mut() {
        let d = subdiv_tess::rates::GRID_DENOMINATOR;
        grid.axes[1][1] = (grid.axes[1][1] + grid.axes[1][2]) / 2 + u32::from(grid.axes[1][1] == d / 4);
    }
    cases.push(("an N-gon's unequal axes", unequal));
    let mut decreasing = good.rings.clone();
    if let Some(grid) = decreasing.graded[quad].as_mut() {
        grid.axes[0].swap(1, 2);
    }
    cases.push(("boundaries that do not increase", decreasing));
    let mut counted = good.rings.clone();
    if let Some(grid) = counted.graded[quad].as_mut() {
        grid.axes[0].remove(1);
        grid.axes[1].remove(1);
    }
    cases.push(("a cell count not the rate", counted));
    for (what, rings) in cases {
        let err = tess.tessellate_with_rings(&good.faces, &rings);
        assert!(matches!(err, Err(TessError::RingCount { .. } | TessError::Grading { .. })), "{what}: {err:?}");
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

/// Rings at extraordinary vertices on edges cut between two faces — an infinitely sharp edge
/// (Catmull-Clark and Loop), a texture seam on every edge (one chart per face): the open runs on
/// the two sides share their ring points on the cut edge, so the output is watertight and
/// counted as predicted, every vertex on the surface, and each side's extra entry there is the
/// same point seen from its own face, with that side's normal and exact channel values.
#[test]
fn rings_on_cut_edges_share_their_points() {
    let sharp_edge = |mut soup: PolygonSoup| {
        let [a, b] = [soup.face(FaceId::new(0))[0], soup.face(FaceId::new(0))[1]];
        soup.tags.creases.push(subdiv_mesh::CreaseTag { vertices: [a, b], sharpness: 10.0 });
        soup
    };
    for (name, soup, builtin) in [
        ("cube, a sharp edge", sharp_edge(shapes::cube()), Builtin::CatmullClark),
        ("cube, a chart per face", shapes::face_charts(shapes::cube()), Builtin::CatmullClark),
        ("icosahedron, a sharp edge", sharp_edge(shapes::icosahedron()), Builtin::Loop),
        ("icosahedron, a chart per face", shapes::face_charts(shapes::icosahedron()), Builtin::Loop),
    ] {
        let mesh = Mesh::build(soup).unwrap();
        let triangle = builtin == Builtin::Loop;
        let scheme = builtin.scheme();
        let evaluator = LimitEvaluator::new(scheme, &mesh, &RefineOptions::DEFAULT).unwrap();
        // The channel's values: linear in mode `all` (the default here), as the tessellator's.
        let channel = mesh.channels().first().map(|c| {
            let surface = subdiv_schemes::ChannelSurface::new(&mesh, c, scheme, &RefineOptions::DEFAULT).unwrap();
            subdiv_stencil::LinearEvaluator::new(&surface).unwrap().expect("mode all is linear")
        });
        let d = diagonal(&mesh);
        for seed in 0..3 {
            let rates = rates_for(&mesh, seed, 9);
            let mut rings = random_rings(&mesh, seed, 9);
            rings.vertices.iter_mut().for_each(|r| *r = (*r).max(1));
            let mut tess = DualTessellator::new(scheme, &mesh, &DualOptions::default()).unwrap();
            let out = tess.tessellate_with_rings(&rates, &rings).unwrap().clone();
            assert!(check(&out).is_empty(), "{name}: border edges on a closed mesh");
            assert_eq!(euler(&out), input_euler(&mesh), "{name}");
            assert_eq!(
                out.positions.len(),
                predicted_vertex_count_with_rings(&mesh, builtin.scheme().split(), &rates, &rings)
            );
            let on_surface = |p: &subdiv_tess::SurfaceParameter| {
                let sum = p.u + p.v;
                let (u, v) = if triangle && sum > 1.0 - 1e-15 {
                    (p.u * (1.0 - 1e-15) / sum, p.v * (1.0 - 1e-15) / sum)
                } else {
                    (p.u, p.v)
                };
                evaluator.eval(p.face, u, v).unwrap()
            };
            for (i, p) in out.parameters.iter().enumerate() {
                let want = on_surface(p).position;
                assert!((want - out.positions[i]).length() < 1e-12 * d, "{name}: vertex {i} off the surface");
            }
            assert!(!out.normal_vertices.is_empty(), "{name}: nothing split");
            let vertices = out.positions.len();
            for (e, (&v, p)) in out.normal_vertices.iter().zip(&out.normal_parameters).enumerate() {
                let want = on_surface(p);
                assert!(
                    (want.position - out.positions[v as usize]).length() < 1e-12 * d,
                    "{name}: extra {e} elsewhere"
                );
                let normal = want.du.cross(want.dv).normalize();
                let got = out.normals[vertices + e];
                assert!((normal - got).length() < 1e-9, "{name}: extra {e}'s normal at {p:?}: {got}, not {normal}");
                if let Some(channel) = &channel {
                    let value = channel.eval(p.face, p.u, p.v).unwrap().position;
                    let got = &out.channels.values[2 * (vertices + e)..2 * (vertices + e) + 2];
                    assert!((got[0] - value.x).abs() < 1e-12 && (got[1] - value.y).abs() < 1e-12, "{name}: extra {e}");
                }
            }
        }
    }
}
