//! The exact evaluators against refinement at the dyadic points of level `L` (to 4 for the
//! interpolating schemes, 3 for the approximating ones, 2 for √3's ternary levels;
//! extraordinary vertices and boundaries included): an independent check, the refinement
//! engine's points and closed forms on one side, the sub-patch matrices' eigenvectors and the
//! descent on the other.
//!
//! - Interpolating schemes pass through every refined vertex: the limit at the dyadic points is
//!   the level-`L` vertices — Butterfly's extraordinary rule, Kobbelt's virtual points at
//!   valences other than 4 (whose patches reach past three rings), both schemes' boundary
//!   rules, the four- and six-point curves.
//! - Approximating schemes are refinement followed by the limit mask (the dominant left
//!   eigenvector of the local subdivision matrix), in closed form where one is known
//!   (Catmull-Clark's `(k² v + 4 Σ e + Σ f) / (k (k + 5))`, Loop's `(1 − k χ) v + χ Σ n` with
//!   `χ = 1 / (3 / (8 β) + k)`, √3's, and the cubic B-spline's `(p + 4 v + n) / 6` along a
//!   boundary) and derived for every approximating scheme ([`LimitMask`]: Catmull-Clark, Loop,
//!   √3, sw-quad, bilinear, and the faces of Doo-Sabin and mid-edge).

use std::collections::HashMap;

use glam::DVec3;
use subdiv_mesh::shapes::jittered;
use subdiv_mesh::{CornerTag, CreaseTag, Mesh, PolygonSoup, Tags, VertexId, shapes};
use subdiv_schemes::{
    Builtin, Centre, CurveScheme, LimitMask, PolygonKind, RefineOptions, Scheme, Split, refine_uniform,
};
use subdiv_stencil::curve::basis_grid;
use subdiv_stencil::{FaceDomain, LimitEvaluator};

/// Two apexes of valence `k` over a ring of `k` vertices of valence 4, triangles.
fn bipyramid(k: usize) -> PolygonSoup {
    let mut soup = PolygonSoup::new();
    for i in 0..k {
        let a = std::f64::consts::TAU * i as f64 / k as f64;
        soup.push_vertex(DVec3::new(a.cos(), a.sin(), 0.0));
    }
    soup.push_vertex(DVec3::Z);
    soup.push_vertex(-DVec3::Z);
    let ring = |i: usize| VertexId::new((i % k) as u32);
    let (top, bottom) = (VertexId::new(k as u32), VertexId::new(k as u32 + 1));
    for i in 0..k {
        soup.push_face([top, ring(i), ring(i + 1)]);
        soup.push_face([bottom, ring(i + 1), ring(i)]);
    }
    soup
}

/// The same surface split once into quads (bilinearly): the triangles' vertices keep their
/// valences, so a quad scheme meets valence `k`.
fn quads_of(soup: PolygonSoup) -> PolygonSoup {
    let mesh = Mesh::build(soup).unwrap();
    refine_uniform(&mesh, Builtin::Bilinear.scheme(), 1, &RefineOptions::DEFAULT).unwrap().to_soup()
}

/// Looks points up by position, within `tolerance`.
struct Points {
    cells: HashMap<[i64; 3], Vec<DVec3>>,
    size: f64,
}

impl Points {
    fn new(points: &[DVec3], size: f64) -> Self {
        let mut cells: HashMap<[i64; 3], Vec<DVec3>> = HashMap::new();
        for &p in points {
            cells.entry(Self::cell(p, size)).or_default().push(p);
        }
        Self { cells, size }
    }

    fn cell(p: DVec3, size: f64) -> [i64; 3] {
        (p / size).floor().to_array().map(|x| x as i64)
    }

    /// The distance from `p` to the nearest point within one cell of it.
    fn distance(&self, p: DVec3) -> f64 {
        let [x, y, z] = Self::cell(p, self.size);
        let mut best = f64::INFINITY;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    for q in self.cells.get(&[x + dx, y + dy, z + dz]).into_iter().flatten() {
                        best = best.min((*q - p).length());
                    }
                }
            }
        }
        best
    }
}

/// Every grid point `(i, j) / 2^L` of every face (an N-gon's sub-faces are its quarters:
/// `(i, j) / 2^(L-1)` of each; √3's ternary faces `(i, j) / 3^L`) is one of the level-`L` images (`images` of the mesh refined `L`
/// times by the scheme's cycle: the vertices for an interpolating scheme, the limit mask's
/// points for an approximating one), and every image is such a grid point's limit.
fn grid_is_refinement(
    scheme: &Scheme,
    name: &str,
    soup: PolygonSoup,
    levels: usize,
    images: impl Fn(&Mesh) -> Vec<DVec3>,
) {
    let mesh = Mesh::build(soup).unwrap();
    let eval = LimitEvaluator::new(scheme, &mesh, &RefineOptions::DEFAULT).unwrap();
    for level in 1..=levels {
        let steps = level * scheme.steps_per_cycle();
        let refined = refine_uniform(&mesh, scheme, steps, &RefineOptions::DEFAULT).unwrap();
        let images = images(&refined);
        let vertices = Points::new(&images, 1e-6);
        let mut limit = Vec::new();
        for f in mesh.face_ids() {
            let rate = match eval.domain(f).unwrap() {
                FaceDomain::SubFaces { .. } => 1 << (level - 1),
                FaceDomain::Ternary => 3u32.pow(level as u32),
                _ => 1 << level,
            };
            for (g, point) in eval.grid(f, rate).unwrap() {
                let gap = vertices.distance(point.position);
                assert!(gap < 1e-12, "{scheme} {name} level {level} face {f} at {g:?}: {gap:e} from every image");
                limit.push(point.position);
            }
        }
        let limit = Points::new(&limit, 1e-6);
        for (v, &p) in images.iter().enumerate() {
            let gap = limit.distance(p);
            assert!(gap < 1e-12, "{scheme} {name} level {level}: image {v} is {gap:e} from every grid point");
        }
    }
}

/// [`grid_is_refinement`] for an interpolating scheme: the vertices themselves.
fn passes_through_refined_vertices(scheme: &Scheme, name: &str, soup: PolygonSoup, levels: usize) {
    grid_is_refinement(scheme, name, soup, levels, |mesh| mesh.vertices().map(|v| mesh.position(v)).collect());
}

#[test]
fn butterfly_passes_through_its_refined_vertices_at_valences_3_to_8() {
    let butterfly = Builtin::Butterfly.scheme();
    for k in 3..=8 {
        passes_through_refined_vertices(butterfly, &format!("bipyramid {k}"), jittered(bipyramid(k), 0.1), 4);
    }
    passes_through_refined_vertices(butterfly, "icosahedron", jittered(shapes::icosahedron(), 0.1), 4);
    // Boundaries (its four-point boundary rule): a grid of triangles (corners of one and two
    // faces), a bipyramid without its lower half (boundary vertices of two faces around an
    // interior apex of valence k), an icosahedron without one vertex's faces.
    let triangles = shapes::triangulated(shapes::quad_grid(4, 3));
    passes_through_refined_vertices(butterfly, "open triangle grid", jittered(triangles, 0.1), 4);
    for k in [3, 5, 8] {
        let cap = without_faces(bipyramid(k), |i| i % 2 == 1);
        passes_through_refined_vertices(butterfly, &format!("half bipyramid {k}"), jittered(cap, 0.1), 4);
    }
    let icosahedron = shapes::icosahedron();
    let hole: Vec<bool> = icosahedron.faces().map(|f| f.contains(&VertexId::new(0))).collect();
    let open = without_faces(icosahedron, |i| hole[i]);
    passes_through_refined_vertices(butterfly, "open icosahedron", jittered(open, 0.1), 4);
    // Infinitely sharp creases (the boundary rule on each side): the loop around vertex 0 of
    // the icosahedron with a corner on it, and a dart (one sharp edge ending at a smooth vertex).
    let mut soup = shapes::icosahedron();
    let ring = Mesh::build(soup.clone()).unwrap().one_ring(VertexId::new(0)).to_vec();
    for (i, &v) in ring.iter().enumerate() {
        soup.tags
            .creases
            .push(CreaseTag { vertices: [v, ring[(i + 1) % ring.len()]], sharpness: Tags::INFINITELY_SHARP });
    }
    soup.tags.corners.push(CornerTag { vertex: ring[2], sharpness: Tags::INFINITELY_SHARP });
    let far = Mesh::build(soup.clone()).unwrap().one_ring(VertexId::new(11)).to_vec();
    soup.tags.creases.push(CreaseTag { vertices: [VertexId::new(11), far[0]], sharpness: Tags::INFINITELY_SHARP });
    passes_through_refined_vertices(butterfly, "creased icosahedron", jittered(soup, 0.1), 4);
}

/// `soup` without the faces `drop` picks (by index), and without the vertices left unused.
fn without_faces(soup: PolygonSoup, drop: impl Fn(usize) -> bool) -> PolygonSoup {
    let kept: Vec<&[VertexId]> = soup.faces().enumerate().filter(|&(i, _)| !drop(i)).map(|(_, f)| f).collect();
    let mut index = vec![None; soup.positions().len()];
    let mut out = PolygonSoup::new();
    for face in &kept {
        for v in face.iter() {
            if index[v.index()].is_none() {
                index[v.index()] = Some(out.push_vertex(soup.positions()[v.index()]));
            }
        }
    }
    for face in kept {
        out.push_face(face.iter().map(|v| index[v.index()].expect("numbered above")));
    }
    out
}

#[test]
fn kobbelt_passes_through_its_refined_vertices_at_valences_3_to_8() {
    let kobbelt = Builtin::Kobbelt.scheme();
    passes_through_refined_vertices(kobbelt, "cube", jittered(shapes::cube(), 0.1), 4);
    for k in 3..=8 {
        let soup = jittered(quads_of(bipyramid(k)), 0.1);
        passes_through_refined_vertices(kobbelt, &format!("bipyramid {k} in quads"), soup, 4);
    }
    // Boundaries (its four-point boundary rule): an open grid (corners of one face), and the
    // cube without a face (boundary vertices of two faces, interior ones of valence 3).
    passes_through_refined_vertices(kobbelt, "open grid", jittered(shapes::quad_grid(4, 3), 0.1), 4);
    let open_cube = without_faces(shapes::cube(), |i| i == 0);
    passes_through_refined_vertices(kobbelt, "open cube", jittered(open_cube, 0.1), 4);
    // Infinitely sharp creases: the loop around the cube's face 0, one of its corners tagged.
    let mut creased = shapes::cube();
    let face: Vec<VertexId> = creased.faces().next().unwrap().to_vec();
    for (i, &v) in face.iter().enumerate() {
        let vertices = [v, face[(i + 1) % face.len()]];
        creased.tags.creases.push(CreaseTag { vertices, sharpness: Tags::INFINITELY_SHARP });
    }
    creased.tags.corners.push(CornerTag { vertex: face[1], sharpness: Tags::INFINITELY_SHARP });
    passes_through_refined_vertices(kobbelt, "creased cube", jittered(creased, 0.1), 4);
}

/// The curves: `Σ p_i φ(m / 2^L − i)` on a closed polygon is the level-`L` point `m`.
#[test]
fn four_and_six_point_curves_pass_through_their_refined_points() {
    let points: Vec<DVec3> = (0..9)
        .map(|i| {
            let a = std::f64::consts::TAU * f64::from(i) / 9.0;
            DVec3::new(a.cos() * (1.0 + 0.3 * f64::from(i % 3)), a.sin(), 0.1 * f64::from(i * i % 5))
        })
        .collect();
    let n = points.len() as i64;
    for name in ["four-point", "six-point"] {
        let scheme = CurveScheme::builtin(name).unwrap();
        for level in 1..=4 {
            let rate = 1u32 << level;
            let grid = basis_grid(&scheme, rate).unwrap();
            let refined = scheme.refine_levels(&points, level, PolygonKind::Closed);
            assert_eq!(refined.len() as i64, n << level, "{name}");
            for (m, &r) in refined.iter().enumerate() {
                let mut p = DVec3::ZERO;
                for (k, phi) in grid.phi.iter().enumerate() {
                    // φ at (first + k) / rate, weighting p_i with first + k = m − i·rate.
                    let offset = grid.first + k as i64;
                    let shifted = m as i64 - offset;
                    if shifted % i64::from(rate) == 0 {
                        p += phi.to_f64() * points[(shifted / i64::from(rate)).rem_euclid(n) as usize];
                    }
                }
                assert!((p - r).length() < 1e-12, "{name} level {level} point {m}: {p} vs {r}");
            }
        }
    }
}

/// The limit position of `v` under Catmull-Clark (quads) or Loop (triangles).
fn limit_position(mesh: &Mesh, v: VertexId, loop_: bool) -> DVec3 {
    let p = mesh.position(v);
    if mesh.is_boundary_vertex(v) {
        // The boundary is the cubic B-spline of the boundary polygon (edge-only rule).
        let ring = mesh.one_ring(v);
        let (first, last) = (ring[0], ring[ring.len() - 1]);
        return (mesh.position(first) + 4.0 * p + mesh.position(last)) / 6.0;
    }
    let k = mesh.valence(v) as f64;
    if loop_ {
        let c = 3.0 / 8.0 + (std::f64::consts::TAU / k).cos() / 4.0;
        let beta = (5.0 / 8.0 - c * c) / k;
        let chi = 1.0 / (3.0 / (8.0 * beta) + k);
        let sum: DVec3 = mesh.one_ring(v).iter().map(|&n| mesh.position(n)).sum();
        return (1.0 - k * chi) * p + chi * sum;
    }
    let (mut edges, mut faces) = (DVec3::ZERO, DVec3::ZERO);
    for h in mesh.outgoing(v) {
        edges += mesh.position(mesh.dest(h));
        faces += mesh.position(mesh.origin(mesh.next(mesh.next(h))));
    }
    (k * k * p + 4.0 * edges + faces) / (k * (k + 5.0))
}

/// [`grid_is_refinement`] for Catmull-Clark or Loop: each vertex moved by its limit mask.
fn limit_masks_give_the_grid(scheme: &Scheme, name: &str, soup: PolygonSoup, levels: usize) {
    let loop_ = scheme.regular_valence() == 6;
    grid_is_refinement(scheme, name, soup, levels, |mesh| {
        mesh.vertices().map(|v| limit_position(mesh, v, loop_)).collect()
    });
}

#[test]
fn catmull_clark_is_refinement_then_its_limit_mask() {
    let cc = Builtin::CatmullClark.scheme();
    limit_masks_give_the_grid(cc, "cube", jittered(shapes::cube(), 0.1), 3);
    limit_masks_give_the_grid(cc, "default model", jittered(shapes::default_model(), 0.05), 2);
    limit_masks_give_the_grid(cc, "open grid", jittered(shapes::quad_grid(3, 2), 0.1), 3);
}

#[test]
fn loop_is_refinement_then_its_limit_mask() {
    let lp = Builtin::Loop.scheme();
    limit_masks_give_the_grid(lp, "tetrahedron", jittered(shapes::tetrahedron(), 0.1), 3);
    limit_masks_give_the_grid(lp, "octahedron", jittered(shapes::octahedron(), 0.1), 3);
    limit_masks_give_the_grid(lp, "icosahedron", jittered(shapes::icosahedron(), 0.1), 3);
}

/// The limit of every vertex of `mesh` (every face, under a dual split) by the scheme's mask
/// derived at its valence ([`LimitMask`]: the local matrix's dominant left eigenvector, read
/// off the refinement engine), one mask per kind of centre.
fn derived_limits(scheme: &Scheme, mesh: &Mesh) -> Vec<DVec3> {
    let mut masks: HashMap<Centre, LimitMask> = HashMap::new();
    let mut limit = |centre: Centre, at: &dyn Fn(&LimitMask) -> Option<DVec3>, what: String| {
        let mask = masks.entry(centre).or_insert_with(|| LimitMask::at(scheme, centre).unwrap());
        at(mask).unwrap_or_else(|| panic!("{scheme}: {what}'s neighbourhood is not the canonical one"))
    };
    if matches!(scheme.split(), Split::Dual | Split::Midedge) {
        let centre = |f| Centre::Interior(mesh.face_size(f));
        return mesh.face_ids().map(|f| limit(centre(f), &|m| m.limit_at_face(mesh, f), format!("{f}"))).collect();
    }
    let centre = |v| match mesh.is_boundary_vertex(v) {
        true => Centre::Boundary(mesh.vertex_faces(v).count()),
        false => Centre::Interior(mesh.valence(v)),
    };
    mesh.vertices().map(|v| limit(centre(v), &|m| m.limit_at_vertex(mesh, v), format!("{v}"))).collect()
}

/// Every approximating scheme that refines dyadically is refinement followed by its derived
/// limit mask at every grid point of levels 1 to 3, at valences
/// 3 to 8 (the quad bipyramids' apexes; for the dual splits the faces those vertices become),
/// N-gons (the pentagonal prism's and the dodecahedron's faces) and boundaries (the open grid's
/// vertices of one and two faces, for the schemes that evaluate open meshes).
#[test]
fn approximating_schemes_are_refinement_then_their_derived_limit_masks() {
    let closed = |k: usize| (format!("quad bipyramid {k}"), jittered(quads_of(bipyramid(k)), 0.05));
    let mut meshes: Vec<(String, PolygonSoup)> = (3..=8).map(closed).collect();
    meshes.push(("cube".into(), jittered(shapes::cube(), 0.1)));
    let ngons = [("pentagonal prism", shapes::ngon_prism(5)), ("dodecahedron", shapes::dodecahedron())];
    let open = ("open grid".to_string(), jittered(shapes::quad_grid(3, 2), 0.1));
    for builtin in [Builtin::CatmullClark, Builtin::SwQuad, Builtin::Bilinear, Builtin::DooSabin, Builtin::Midedge] {
        let scheme = builtin.scheme();
        let mut cases = meshes.clone();
        cases.extend(ngons.iter().map(|(n, s)| (n.to_string(), jittered(s.clone(), 0.05))));
        if !matches!(scheme.split(), Split::Dual | Split::Midedge) {
            cases.push(open.clone());
        }
        for (name, soup) in cases {
            grid_is_refinement(scheme, &name, soup, 3, |mesh| derived_limits(scheme, mesh));
        }
    }
    let lp = Builtin::Loop.scheme();
    for k in 3..=8 {
        grid_is_refinement(lp, &format!("bipyramid {k}"), jittered(bipyramid(k), 0.05), 3, |mesh| {
            derived_limits(lp, mesh)
        });
    }
    let open_triangles = jittered(shapes::triangulated(shapes::quad_grid(3, 2)), 0.1);
    grid_is_refinement(lp, "triangulated grid", open_triangles, 3, |mesh| derived_limits(lp, mesh));
}

/// √3 through its ternary levels: every grid point `(i, j) / 3^L` of every face is the limit of
/// a vertex of `2L` √3 steps, moved by Kobbelt's limit mask `(p + 3kβ q̄) / (1 + 3kβ)` (`q̄` the
/// mean of its `k` neighbours, β the vertex rule's weight) and by the mask derived from the
/// local matrix, and every such vertex's limit is a grid point, `L = 1, 2`: vertices of
/// valences 3-8 (the bipyramids' apexes and rings), on jittered cages.
#[test]
fn sqrt3_grid_points_are_refined_vertices_moved_to_their_limits() {
    // A grid of `m × n` squares, each split along a diagonal, domed.
    let triangulated_grid = |m: usize, n: usize| {
        let mut soup = shapes::triangulated(shapes::quad_grid(m, n));
        for p in soup.positions_mut() {
            p.z = 0.2 * (p.x * p.y).sin();
        }
        soup
    };
    // The lower half of a bipyramid: a fan of `k` triangles around its apex, whose rim is the
    // boundary (vertices of two faces).
    let open_bipyramid = |k: usize| {
        let closed = bipyramid(k);
        let mut soup = PolygonSoup::default();
        for &p in &closed.positions()[..k] {
            soup.push_vertex(p);
        }
        soup.push_vertex(closed.positions()[k + 1]);
        let (top, bottom) = (VertexId::new(k as u32), VertexId::new(k as u32 + 1));
        for face in closed.faces().filter(|f| !f.contains(&top)) {
            soup.push_face(face.iter().map(|&v| if v == bottom { top } else { v }));
        }
        soup
    };
    let sqrt3 = Builtin::Sqrt3.scheme();
    // Kobbelt's limit at an interior vertex; at a boundary vertex the boundary's cubic B-spline
    // (the ternary cubic rule along the boundary), over its two boundary neighbours.
    let limit = |mesh: &Mesh, v: VertexId| {
        let ring = mesh.one_ring(v);
        if mesh.is_boundary_vertex(v) {
            let (p, q) = (mesh.position(ring[0]), mesh.position(ring[ring.len() - 1]));
            return (p + 4.0 * mesh.position(v) + q) / 6.0;
        }
        let k = ring.len() as f64;
        let beta = (4.0 - 2.0 * (std::f64::consts::TAU / k).cos()) / (9.0 * k);
        let mean = ring.iter().map(|&w| mesh.position(w)).sum::<DVec3>() / k;
        (mesh.position(v) + 3.0 * k * beta * mean) / (1.0 + 3.0 * k * beta)
    };
    let cages = [
        ("bipyramid 3", jittered(bipyramid(3), 0.1)),
        ("bipyramid 5", jittered(bipyramid(5), 0.1)),
        ("bipyramid 8", jittered(bipyramid(8), 0.1)),
        ("icosahedron", jittered(shapes::icosahedron(), 0.1)),
        // Open: Kobbelt's boundary rule, boundary vertices of one to four faces.
        ("triangulated grid", jittered(triangulated_grid(4, 3), 0.1)),
        ("open bipyramid", jittered(open_bipyramid(5), 0.1)),
    ];
    for (name, soup) in cages {
        grid_is_refinement(sqrt3, name, soup.clone(), 2, |m| m.vertices().map(|v| limit(m, v)).collect());
        grid_is_refinement(sqrt3, name, soup.clone(), 2, |m| derived_limits(sqrt3, m));
        let mesh = Mesh::build(soup).unwrap();
        let eval = LimitEvaluator::new(sqrt3, &mesh, &RefineOptions::DEFAULT).unwrap();
        // The derivatives (×±3 per ternary level) are the positions' central differences.
        let h = 1.0 / 65536.0;
        for f in mesh.face_ids() {
            for (u, v) in [(0.3, 0.2), (0.1, 0.6), (0.05, 0.05)] {
                let p = eval.eval(f, u, v).unwrap();
                let du =
                    (eval.eval(f, u + h, v).unwrap().position - eval.eval(f, u - h, v).unwrap().position) / (2.0 * h);
                let dv =
                    (eval.eval(f, u, v + h).unwrap().position - eval.eval(f, u, v - h).unwrap().position) / (2.0 * h);
                assert!(p.exact_derivatives, "{name} face {f} at ({u}, {v})");
                assert!(
                    (p.du - du).length() < 1e-6 * p.du.length().max(1.0),
                    "{name} {f} ({u}, {v}): {} vs {du}",
                    p.du
                );
                assert!(
                    (p.dv - dv).length() < 1e-6 * p.dv.length().max(1.0),
                    "{name} {f} ({u}, {v}): {} vs {dv}",
                    p.dv
                );
            }
        }
    }
}
