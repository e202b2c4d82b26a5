//! The patches of a mesh under the dual split (Doo-Sabin, or a scheme file with `[rules.dual]`):
//! each face corner of the control mesh is a dual quad of the first refined level, split once
//! more where that quad holds two extraordinary faces.
//!
//! A face takes `Bfr`'s parameterization of quad schemes (quads `[0, 1]²`, other faces tiled
//! sub-faces), and its corner at vertex `w` — the quarter of a quad at that corner, or `Bfr`'s
//! sub-face of an N-gon — is the dual quad of the corner's point on the first level
//! ([`dual_corner_start`]): `(0, 0)` at the limit of `w`'s vertex face, `(1, 1)` at the limit
//! of the face's own, the sides' middles at the limits of the edge faces. Neighbouring faces
//! see the same points along a shared side, so the parameterization is continuous across
//! faces, as the primal schemes' is, and tessellations of it are watertight.
//!
//! On an open mesh (the boundary rule moves a corner on a boundary edge along the edge only) a
//! corner on a boundary side has no piece: its point is a boundary vertex of the first level,
//! whose dual quad is empty, and the face's centre and the boundary vertices' edge faces limit
//! onto the boundary curve. Such a quad lays the pieces of its other corners across it
//! ([`Layout::DualBoundaryQuad`]: one boundary side, two halves stretched across it; two sides
//! at a corner, the opposite corner's piece over the face), and the pieces with boundary faces
//! among their four take matrices derived from their own neighbourhoods
//! ([`derive_dual_configuration`]), one derivation per configuration. Next to a boundary
//! vertex of three faces or more the dual split leaves a train of triangle faces along the
//! boundary at every level, and boundary faces of other than four sides have no such layout:
//! both are refused by name ([`StencilError::DualBoundary`]), as are faces whose boundary sides
//! leave no interior corner (their limit is a curve).

use std::collections::HashMap;
use std::sync::Arc;

use subdiv_mesh::{HalfEdgeId, Mesh};
use subdiv_schemes::{
    FoundPatch, PatchMatrices, PatchType, RefineOptions, Refiner, Scheme, SchemeError, Split, Stencils,
    derive_dual_configuration, dual_child_starts, dual_corner_start, dual_patch, dual_quad_corners,
};

use crate::StencilError;
use crate::patch_levels::{Level, Resolution};

/// The levels of `mesh` under the dual `scheme`, and each level's stencils over the one
/// above; `name` is the scheme the user asked for (mid-edge runs as its dual form).
///
/// Level 0 is the input; each face's children are its corners (half-edges, in order), the
/// faces of level 1. A corner's face on level 1 has the face's axes when the face is a quad
/// (the quarter at the corner, as the quad split's children) and `Bfr`'s sub-face frame
/// otherwise; its patch is the corner point's dual quad, in the rotation that puts the quad's
/// extraordinary face (if any) at corner 0. A corner whose quad has two extraordinary faces (a
/// vertex of valence other than 4 at a face of other than 4 sides) is split once more: its
/// children `4h..4h + 4` on level 2, each with one such face at most. A corner whose quad has a
/// boundary face among its four takes its derived configuration's matrices (any number of
/// extraordinary faces), from corner 0; a corner on a boundary side has none.
///
/// # Errors
/// As refinement ([`StencilError::Scheme`]), [`SchemeError::ValenceNotSupported`] for a face
/// or vertex past [`RefineOptions::max_dense_patch_valence`], [`StencilError::DualBoundary`] for
/// the boundary configurations above.
pub(crate) fn dual_levels(
    scheme: &Scheme,
    name: &str,
    mesh: &Mesh,
    options: &RefineOptions,
) -> Result<(Vec<Level>, Vec<Stencils>), StencilError> {
    debug_assert_eq!(scheme.split(), Split::Dual);
    // The positions alone, as the primal levels.
    let mut base = Refiner::new(mesh, scheme, 0, options)?.into_mesh();
    base.clear_channels();
    let sides = boundary_sides(name, &base)?;
    let refiner = Refiner::new(&base, scheme, 1, options)?;
    let mut stencils = refiner.levels().to_vec();
    let first = refiner.into_mesh();
    let internal = |detail: &str| StencilError::Internal(format!("dual levels: {detail}"));
    // A dual quad's four half-edges around its centre, counter-clockwise from its start, and
    // its faces' sizes.
    let around = |m: &Mesh, start: HalfEdgeId| {
        dual_quad_corners(m, start).ok_or_else(|| internal("a dual quad without four faces"))
    };
    let sizes = |m: &Mesh, around: [HalfEdgeId; 4]| around.map(|h| m.face_size(m.face(h)));
    let extraordinary = |sizes: [usize; 4]| sizes.iter().filter(|&&n| n != 4).count();
    let open = |m: &Mesh, around: [HalfEdgeId; 4]| {
        around.iter().any(|&h| m.face_half_edges(m.face(h)).any(|k| m.twin(k).is_none()))
    };
    // Per corner of the input, its dual quad on level 1; none for a corner on a boundary side.
    let quads: Vec<Option<[HalfEdgeId; 4]>> = (0..base.half_edge_count() as u32)
        .map(|h| {
            let h = HalfEdgeId::new(h);
            if base.twin(h).is_none() || base.twin(base.prev(h)).is_none() {
                return Ok(None);
            }
            let start = dual_corner_start(&first, h).ok_or_else(|| internal("an open corner"))?;
            around(&first, start).map(Some)
        })
        .collect::<Result<_, _>>()?;
    let mut twice = false;
    for &quad in quads.iter().flatten() {
        let sizes = sizes(&first, quad);
        if let Some(&n) = sizes.iter().find(|&&n| n > options.max_dense_patch_valence) {
            return Err(StencilError::Scheme(SchemeError::ValenceNotSupported {
                scheme: scheme.name.clone(),
                valence: n,
                reason: "a face or vertex past the largest valence the refinement options allow \
                         (RefineOptions::max_dense_patch_valence)",
            }));
        }
        twice |= extraordinary(sizes) > 1 && !open(&first, quad);
    }
    let second = if twice {
        let refiner = Refiner::new(&first, scheme, 1, options)?;
        stencils.push(refiner.levels()[0].clone());
        Some(refiner.into_mesh())
    } else {
        None
    };
    // The patch of the dual quad `around` on `m`, and the corner of the quad it starts at.
    let patch = |m: &Mesh, around: [HalfEdgeId; 4]| -> Result<(Resolution, u8), StencilError> {
        let sizes = sizes(m, around);
        let rotation = (0..4).find(|&c| sizes[c] != 4).unwrap_or(0);
        let found = dual_patch(m, around[rotation]).ok_or_else(|| internal("a dual quad without four faces"))?;
        let matrices = PatchMatrices::of(
            scheme,
            PatchType::interior(sizes[rotation]),
            subdiv_mesh::BoundaryInterpolation::EdgeOnly,
        )?;
        let shape = matrices
            .find(&found.signature)
            .ok_or_else(|| internal(&format!("a dual quad at a {}-gon has no derived shape", sizes[rotation])))?;
        let found = FoundPatch { start: around[rotation], vertices: found.vertices.into(), matrices, shape };
        Ok((Resolution::Patch(found), rotation as u8))
    };
    // The patches of dual quads with boundary faces, by signature: every shape of each
    // configuration derived so far.
    let mut derived: HashMap<Vec<u32>, (Arc<PatchMatrices>, usize)> = HashMap::new();
    let mut boundary_patch = |m: &Mesh, start: HalfEdgeId| -> Result<Resolution, StencilError> {
        let found = dual_patch(m, start).ok_or_else(|| internal("a dual quad without four faces"))?;
        if !derived.contains_key(&found.signature) {
            let matrices = derive_dual_configuration(scheme, m, start)?
                .ok_or_else(|| internal("a boundary configuration's shapes do not close up"))?;
            let matrices = Arc::new(matrices);
            for (s, shape) in matrices.shapes.iter().enumerate() {
                derived.entry(shape.signature.clone()).or_insert_with(|| (matrices.clone(), s));
            }
        }
        let (matrices, shape) =
            derived.get(&found.signature).cloned().ok_or_else(|| internal("a derived configuration lost its shape"))?;
        Ok(Resolution::Patch(FoundPatch { start, vertices: found.vertices.into(), matrices, shape }))
    };
    let mut level0 = Level::new(base, None);
    let mut level1 = Level::new(first, Some(quads.len()));
    let mut level2 = second.map(|m| Level::new(m, Some(4 * quads.len())));
    for f in level0.mesh.face_ids() {
        let size = level0.mesh.face_size(f);
        // A face's corners are consecutive half-edges.
        let corner0 = level0.mesh.face_half_edges(f).next().ok_or_else(|| internal("a face without corners"))?;
        let corners = corner0.index()..corner0.index() + size;
        level0.faces[f.index()] = Some(match sides[f.index()] {
            0 => Resolution::Children(corners),
            sides => Resolution::DualBoundary(corners, sides),
        });
        for (j, h) in level0.mesh.face_half_edges(f).enumerate() {
            let Some(quad) = quads[h.index()] else { continue };
            // The dual quad's frame starts at the corner's vertex: corner j of a quad's child.
            let rho = if size == 4 { j } else { 0 };
            if open(&level1.mesh, quad) {
                let resolution = boundary_patch(&level1.mesh, quad[0])?;
                level1.set(h.index(), resolution, rho);
                continue;
            }
            if extraordinary(sizes(&level1.mesh, quad)) <= 1 {
                let (resolution, r) = patch(&level1.mesh, quad)?;
                level1.set(h.index(), resolution, (rho + usize::from(r)) % 4);
                continue;
            }
            let level2 = level2.as_mut().ok_or_else(|| internal("the second level was not refined"))?;
            let children =
                dual_child_starts(&level1.mesh, quad[0], &level2.mesh).ok_or_else(|| internal("an open child"))?;
            let first_child = 4 * h.index();
            level1.faces[h.index()] = Some(Resolution::Children(first_child..first_child + 4));
            // The face's child c, at its corner c (its own axes), is the dual quad's child at
            // the quad's corner c − rho.
            for c in 0..4 {
                let (resolution, r) = patch(&level2.mesh, around(&level2.mesh, children[(c + 4 - rho) % 4])?)?;
                level2.set(first_child + c, resolution, (rho + usize::from(r)) % 4);
            }
        }
    }
    let mut levels = vec![level0, level1];
    levels.extend(level2);
    Ok((levels, stencils))
}

/// Per face of `mesh`, its sides on the boundary (bit `k` for side `k`, from corner `k`), after
/// refusing (under the scheme `name`) what has no patches: a boundary vertex of three faces or
/// more, a boundary face of other than four sides, a face without an interior corner.
fn boundary_sides(name: &str, mesh: &Mesh) -> Result<Vec<u8>, StencilError> {
    let refuse =
        |place: String, reason: &'static str| StencilError::DualBoundary { scheme: name.to_string(), place, reason };
    if let Some(v) = mesh.vertices().find(|&v| mesh.is_boundary_vertex(v) && mesh.vertex_faces(v).count() > 2) {
        return Err(refuse(
            format!("at {v}, a boundary vertex of {} faces", mesh.vertex_faces(v).count()),
            "there the dual split leaves a train of triangle faces along the boundary at every level, which have no \
             sub-patch matrices yet (boundary vertices of one or two faces have them)",
        ));
    }
    let mut sides = vec![0u8; mesh.face_count()];
    for f in mesh.face_ids() {
        let open: u8 =
            mesh.face_half_edges(f).enumerate().filter(|&(_, h)| mesh.twin(h).is_none()).map(|(k, _)| 1 << k).sum();
        if open == 0 {
            continue;
        }
        if mesh.face_size(f) != 4 {
            return Err(refuse(
                format!("over {f}, a face of {} sides on the boundary", mesh.face_size(f)),
                "only a quad on the boundary has its corners' pieces laid across it",
            ));
        }
        // One side, or two meeting at a corner.
        if ![0b0001, 0b0010, 0b0100, 0b1000, 0b0011, 0b0110, 0b1100, 0b1001].contains(&open) {
            return Err(refuse(
                format!("over {f}, whose boundary sides leave no interior corner"),
                "its limit under the boundary rule is a curve, not a surface",
            ));
        }
        sides[f.index()] = open;
    }
    Ok(sides)
}

#[cfg(test)]
mod tests {
    use subdiv_mesh::{DVec3, FaceId, PolygonSoup, VertexId, shapes};
    use subdiv_schemes::{Builtin, refine};

    use crate::{Dyadic, FaceDomain, LimitEvaluator, LimitPoint};

    use super::*;

    /// `soup` with every vertex moved a little (`shapes::jittered`), built.
    fn jittered(soup: PolygonSoup, amount: f64) -> Mesh {
        Mesh::build(shapes::jittered(soup, amount)).unwrap()
    }

    fn doo_sabin(mesh: &Mesh) -> LimitEvaluator {
        LimitEvaluator::new(Builtin::DooSabin.scheme(), mesh, &RefineOptions::DEFAULT).unwrap()
    }

    /// The schemes whose patches are dual quads: Doo-Sabin, and mid-edge by its two steps.
    const DUAL_SCHEMES: [Builtin; 2] = [Builtin::DooSabin, Builtin::Midedge];

    /// The centred quadratic B-spline and its derivative.
    fn quadratic(t: f64) -> (f64, f64) {
        let a = t.abs();
        if a <= 0.5 {
            (0.75 - t * t, -2.0 * t)
        } else if a <= 1.5 {
            (0.5 * (1.5 - a).powi(2), -(1.5 - a) * t.signum())
        } else {
            (0.0, 0.0)
        }
    }

    #[test]
    fn on_a_regular_grid_doo_sabin_is_the_biquadratic_b_spline() {
        let (m, n) = (6, 5);
        let mesh = jittered(shapes::quad_torus(m, n), 0.3);
        let eval = doo_sabin(&mesh);
        for (face, u, v) in [(0, 0.0, 0.0), (7, 0.25, 0.75), (13, 0.5, 0.5), (29, 1.0 / 3.0, 0.9), (17, 0.8, 0.1)] {
            let (i, j) = (face / n, face % n);
            let (x, y) = (i as f64 + u, j as f64 + v);
            let mut expected =
                LimitPoint { position: DVec3::ZERO, du: DVec3::ZERO, dv: DVec3::ZERO, exact_derivatives: true };
            for a in (i as i64 - 2)..=(i as i64 + 3) {
                for b in (j as i64 - 2)..=(j as i64 + 3) {
                    let (bx, dbx) = quadratic(x - a as f64);
                    let (by, dby) = quadratic(y - b as f64);
                    let id = a.rem_euclid(m as i64) as usize * n + b.rem_euclid(n as i64) as usize;
                    let p = mesh.position(VertexId::new(id as u32));
                    expected.position += bx * by * p;
                    expected.du += dbx * by * p;
                    expected.dv += bx * dby * p;
                }
            }
            let got = eval.eval(FaceId::new(face as u32), u, v).unwrap();
            for (what, a, b) in [
                ("position", got.position, expected.position),
                ("du", got.du, expected.du),
                ("dv", got.dv, expected.dv),
            ] {
                assert!((a - b).length() < 1e-13, "face {face} ({u}, {v}) {what}: {a} vs {b}");
            }
        }
    }

    /// The Zwart-Powell element (the box spline of directions e1, e2, e1 + e2, e1 − e2), from
    /// the Courant element `M₃` (directions e1, e2, e1 + e2) by the box splines' recurrence
    /// `M(x, y) = ∫₀¹ M₃(x − t, y + t) dt`, integrated exactly between the integrand's kinks
    /// (it is linear between them). Support `[0, 3] × [−1, 2]`, centre `(3/2, 1/2)`.
    fn zwart_powell(x: f64, y: f64) -> f64 {
        let courant = |x: f64, y: f64| (x.min(y).min(1.0) - (x - 1.0).max(y - 1.0).max(0.0)).max(0.0);
        let g = |t: f64| courant(x - t, y + t);
        let mut kinks = vec![0.0, 1.0];
        for m in -3..=3 {
            let m = f64::from(m);
            kinks.extend([x - m, m - y, (x - y - m) / 2.0].into_iter().filter(|t| (0.0..=1.0).contains(t)));
        }
        kinks.sort_by(f64::total_cmp);
        kinks.windows(2).map(|w| (w[1] - w[0]) * (g(w[0]) + g(w[1])) / 2.0).sum()
    }

    /// Peters and Reif's mid-edge scheme on a regular grid is the Zwart-Powell box spline (their
    /// paper's §2), centred on the control points.
    #[test]
    fn on_a_regular_grid_mid_edge_is_the_zwart_powell_box_spline() {
        let (m, n) = (7, 6);
        let mesh = jittered(shapes::quad_torus(m, n), 0.3);
        let eval = LimitEvaluator::new(Builtin::Midedge.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
        for (face, u, v) in [(0, 0.0, 0.0), (8, 0.25, 0.75), (15, 0.5, 0.5), (29, 1.0 / 3.0, 0.9), (17, 0.8, 0.1)] {
            let (i, j) = (face / n, face % n);
            let (x, y) = (i as f64 + u, j as f64 + v);
            let mut expected = DVec3::ZERO;
            for a in (i as i64 - 3)..=(i as i64 + 3) {
                for b in (j as i64 - 3)..=(j as i64 + 3) {
                    let id = a.rem_euclid(m as i64) as usize * n + b.rem_euclid(n as i64) as usize;
                    let weight = zwart_powell(x - a as f64 + 1.5, y - b as f64 + 0.5);
                    expected += weight * mesh.position(VertexId::new(id as u32));
                }
            }
            let got = eval.eval(FaceId::new(face as u32), u, v).unwrap().position;
            assert!((got - expected).length() < 1e-13, "face {face} ({u}, {v}): {got} vs {expected}");
        }
    }

    /// Closed meshes with faces of 3 to 5 sides and vertices of valence 3 to 5.
    fn meshes() -> Vec<(&'static str, Mesh)> {
        vec![
            ("cube", jittered(shapes::cube(), 0.2)),
            ("pentagonal prism", jittered(shapes::ngon_prism(5), 0.2)),
            ("octahedron", jittered(shapes::octahedron(), 0.2)),
            ("icosahedron", jittered(shapes::icosahedron(), 0.1)),
            ("dodecahedron", jittered(shapes::dodecahedron(), 0.1)),
        ]
    }

    fn centroid(points: impl Iterator<Item = DVec3>) -> DVec3 {
        let (sum, count) = points.fold((DVec3::ZERO, 0.0), |(s, c), p| (s + p, c + 1.0));
        sum / count
    }

    /// A face's limit at the centre of its face of a refined level is that face's centroid
    /// (its points map onto its own next face by a circulant matrix, whose left eigenvector for
    /// 1 is uniform): the control face's centre, the middle of a side (the side's edge face of
    /// level 1) and a corner (the corner vertex's face of level 1) — independent of the stencils.
    #[test]
    fn face_centres_sides_and_corners_are_the_centroids_of_their_faces() {
        for ((name, mesh), builtin) in meshes().into_iter().flat_map(|m| DUAL_SCHEMES.map(|b| (m.clone(), b))) {
            let scheme = builtin.scheme();
            let eval = LimitEvaluator::new(scheme, &mesh, &RefineOptions::DEFAULT).unwrap();
            let dual = scheme.dual_form().unwrap();
            let first = refine(&mesh, &dual, &RefineOptions::DEFAULT).unwrap();
            // Level 1's vertex of corner h is h.
            let at = |h: HalfEdgeId| first.position(VertexId::new(h.raw()));
            for f in mesh.face_ids() {
                let domain = eval.domain(f).unwrap();
                // Sub-face (or quad corner) 0's corners: the face's centre, side 0's middle, corner 0.
                let point = |a, b, q| match domain {
                    FaceDomain::Quad => Dyadic::new(a, b, q),
                    _ => domain.from_sub_face(0, Dyadic::new(a, b, q)),
                };
                let (centre, middle, corner) = match domain {
                    FaceDomain::Quad => (point(1, 1, 2), point(1, 0, 2), point(0, 0, 1)),
                    _ => (point(1, 1, 1), point(1, 0, 1), point(0, 0, 1)),
                };
                let h = mesh.face_half_edges(f).next().unwrap();
                let t = mesh.twin(h).unwrap();
                let expected = [
                    ("centre", centre, centroid(mesh.face_vertices(f).iter().map(|&v| mesh.position(v)))),
                    ("side", middle, centroid([h, mesh.next(h), t, mesh.next(t)].into_iter().map(at))),
                    ("corner", corner, centroid(mesh.outgoing(mesh.origin(h)).map(at))),
                ];
                for (what, p, want) in expected {
                    let got = eval.eval_exact(f, p).unwrap().position;
                    assert!((got - want).length() < 1e-13, "{scheme} {name} face {f} {what}: {got} vs {want}");
                }
            }
        }
    }

    /// The corners of the unit square, in a quad's corner order.
    const CORNERS: [(f64, f64); 4] = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];

    /// The point at `t` along side `k` of the unit square (from corner `k` to corner `k + 1`).
    fn on_side(k: usize, t: f64) -> (f64, f64) {
        let (a, b) = (CORNERS[k % 4], CORNERS[(k + 1) % 4]);
        (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
    }

    /// On an open grid (boundary vertices of two faces, corners of one) both dual schemes'
    /// boundary is Chaikin's limit of the boundary polygon: away from the corners, the uniform
    /// quadratic B-spline `C(t) = Σ b(t − j) P_j` through the points `(P_{j−1} + 6 P_j + P_{j+1}) / 8`
    /// at the vertices and the edges' middles, a boundary face's side from `P_j` to `P_{j+1}` at
    /// `C(j + s)` — and its tangent there is the curve's, oriented as the face's parameter.
    /// Neighbouring faces meet along every side, boundary faces included, every normal faces
    /// the grid's way, and inside the faces the derivatives are exact and the positions' slopes.
    #[test]
    fn on_an_open_grid_the_boundary_is_the_quadratic_b_spline_and_faces_meet() {
        let mesh = jittered(shapes::quad_grid(10, 8), 0.25);
        let loops = mesh.boundary_loops();
        assert_eq!(loops.len(), 1);
        let polygon: Vec<DVec3> = loops[0].iter().map(|&h| mesh.position(mesh.origin(h))).collect();
        let n = polygon.len() as i64;
        let corner = |j: i64| mesh.vertex_faces(mesh.origin(loops[0][j.rem_euclid(n) as usize])).count() == 1;
        let curve = |t: f64| -> (DVec3, DVec3) {
            let mut c = (DVec3::ZERO, DVec3::ZERO);
            for j in (t.floor() as i64 - 2)..=(t.floor() as i64 + 3) {
                let (b, db) = quadratic(t - j as f64);
                let p = polygon[j.rem_euclid(n) as usize];
                c = (c.0 + b * p, c.1 + db * p);
            }
            c
        };
        for builtin in DUAL_SCHEMES {
            let eval = LimitEvaluator::new(builtin.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
            let mut checked = 0;
            for (j, &h) in loops[0].iter().enumerate() {
                let j = j as i64;
                // The curve over [j, j + 1] reads P_{j−1}..P_{j+2}; the corners' rule one more.
                if (j - 2..=j + 3).any(corner) {
                    continue;
                }
                let (f, k) = (mesh.face(h), mesh.corner(h));
                for s in [0.0, 0.125, 0.3, 0.5, 0.75, 1.0] {
                    let (u, v) = on_side(k, s);
                    let got = eval.eval(f, u, v).unwrap();
                    let (want, tangent) = curve(j as f64 + s);
                    let what = format!("{} face {f} side {k} at {s}", builtin.scheme());
                    assert!((got.position - want).length() < 1e-13, "{what}: {} vs {want}", got.position);
                    // Along side 0 or 2 the side runs along u, along 1 or 3 along v; sides 0 and
                    // 1 with the parameter, 2 and 3 against it.
                    let along = if k % 2 == 0 { got.du } else { got.dv };
                    let along = if k < 2 { along } else { -along };
                    let sine = along.cross(tangent).length() / (along.length() * tangent.length());
                    assert!(
                        sine < 1e-9 && along.dot(tangent) > 0.0,
                        "{what}: tangent {along} against the curve's {tangent}"
                    );
                    checked += 1;
                }
            }
            assert_eq!(checked, 6 * 12, "boundary points away from the corners");
            // Every interior side, and the inside of every face.
            for f in mesh.face_ids() {
                for (k, h) in mesh.face_half_edges(f).enumerate() {
                    let Some(t) = mesh.twin(h) else { continue };
                    let g = mesh.face(t);
                    for s in [0.0, 0.2, 0.5, 0.9] {
                        let (u, v) = on_side(k, s);
                        let (gu, gv) = on_side(mesh.corner(t), 1.0 - s);
                        let a = eval.eval(f, u, v).unwrap().position;
                        let b = eval.eval(g, gu, gv).unwrap().position;
                        assert!((a - b).length() < 1e-13, "faces {f} and {g} at {s}: {a} vs {b}");
                    }
                }
                // The grid faces up (+z, jittered by a quarter): so does every normal, at the
                // corners and on the sides too, where the derivatives are directions.
                for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.5, 0.0), (0.3, 1.0), (1.0, 0.7)] {
                    let p = eval.eval(f, u, v).unwrap();
                    let normal = p.du.cross(p.dv).normalize();
                    assert!(normal.z > 0.5, "face {f} at ({u}, {v}): normal {normal}");
                }
                let (u, v, e) = (0.3, 0.65, 1e-6);
                let at = eval.eval(f, u, v).unwrap();
                let du =
                    (eval.eval(f, u + e, v).unwrap().position - eval.eval(f, u - e, v).unwrap().position) / (2.0 * e);
                let dv =
                    (eval.eval(f, u, v + e).unwrap().position - eval.eval(f, u, v - e).unwrap().position) / (2.0 * e);
                assert!(at.exact_derivatives, "face {f}");
                assert!((at.du - du).length() < 1e-6 * du.length().max(1.0), "face {f} du: {} vs {du}", at.du);
                assert!((at.dv - dv).length() < 1e-6 * dv.length().max(1.0), "face {f} dv: {} vs {dv}", at.dv);
            }
        }
    }

    #[test]
    fn neighbouring_faces_meet_along_their_sides_and_derivatives_are_the_positions_slopes() {
        for ((name, mesh), builtin) in meshes().into_iter().flat_map(|m| DUAL_SCHEMES.map(|b| (m.clone(), b))) {
            let name = format!("{} {name}", builtin.scheme());
            let eval = LimitEvaluator::new(builtin.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
            let quads: Vec<FaceId> = mesh.face_ids().filter(|&f| mesh.face_size(f) == 4).collect();
            for &f in &quads {
                for (k, h) in mesh.face_half_edges(f).enumerate() {
                    let t = mesh.twin(h).unwrap();
                    let g = mesh.face(t);
                    if mesh.face_size(g) != 4 {
                        continue;
                    }
                    for s in [0.125, 0.375, 0.5, 0.8] {
                        let (u, v) = on_side(k, s);
                        let (gu, gv) = on_side(mesh.corner(t), 1.0 - s);
                        let a = eval.eval(f, u, v).unwrap().position;
                        let b = eval.eval(g, gu, gv).unwrap().position;
                        assert!((a - b).length() < 1e-13, "{name}: faces {f} and {g} at {s}: {a} vs {b}");
                    }
                }
            }
            let e = 1e-6;
            for f in mesh.face_ids() {
                let domain = eval.domain(f).unwrap();
                // Away from the pieces' borders (dyadic lines), where central differences of a
                // C1 surface lose their second order: sub-face 1's (0.3, 0.15) of an N-gon.
                let (u, v) = match domain {
                    FaceDomain::Quad => (0.3, 0.15),
                    _ => (1.15, 0.075),
                };
                let at = eval.eval(f, u, v).unwrap();
                let du =
                    (eval.eval(f, u + e, v).unwrap().position - eval.eval(f, u - e, v).unwrap().position) / (2.0 * e);
                let dv =
                    (eval.eval(f, u, v + e).unwrap().position - eval.eval(f, u, v - e).unwrap().position) / (2.0 * e);
                assert!(at.exact_derivatives);
                assert!((at.du - du).length() < 1e-7 * du.length().max(1.0), "{name} face {f} du: {} vs {du}", at.du);
                assert!((at.dv - dv).length() < 1e-7 * dv.length().max(1.0), "{name} face {f} dv: {} vs {dv}", at.dv);
            }
        }
    }
}
