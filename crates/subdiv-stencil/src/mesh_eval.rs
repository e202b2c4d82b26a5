//! The limit surface of a whole mesh at any face's rational (or f64) parameter, in OpenSubdiv's
//! `Bfr` parameterization, from exact surface stencils.
//!
//! A face whose patch has a shape in the scheme's [`PatchMatrices`] is evaluated directly: its
//! point is carried into the patch's frame (the patch may start at another corner of the face)
//! and weighted by [`surface_stencil`]. A face without one — an N-gon under a quad split, or a
//! face whose patch holds two irregular vertices — is refined once and the point descends into
//! the child face that holds it, as often as needed. The maps between a face's parameters, its
//! children's and its patch's are integer affine maps, so a rational point stays exact all the
//! way down.
//!
//! Children follow the refinement engine's (and OpenSubdiv's `Far`) numbering: the children of
//! face `f` are consecutive; a quad's child `j` sits at corner `j` of the domain with the
//! parent's axes ([`ChildDomain::of_face`]); a triangle's children 0..2 sit at its corners and
//! child 3 is the middle one, turned by half a turn; an N-gon's child `j` is `Bfr`'s sub-face `j`
//! (it starts at corner `j`, so its own parameters are the normalized sub-face coordinates).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

use subdiv_mesh::{DVec3, FaceId, Mesh};
use subdiv_schemes::{PatchMatrices, RefineOptions, Scheme};

use crate::patch_levels::internal;
use crate::{Dyadic, FaceDomain, GridParameter, PatchLevels, Resolved, StencilError, StencilEvaluator, SurfaceStencil};

/// A point of the limit surface with its derivatives in the face's `Bfr` parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitPoint {
    /// The position.
    pub position: DVec3,
    /// ∂/∂u.
    pub du: DVec3,
    /// ∂/∂v.
    pub dv: DVec3,
    /// Whether `du` and `dv` are the parameter derivatives. `false` at an extraordinary vertex
    /// itself, where the parameterization has none: there they are tangent directions whose
    /// cross product points along the normal (see [`SurfaceStencil::exact_derivatives`]).
    pub exact_derivatives: bool,
}

/// The limit surface of a mesh under a primal scheme, at any face's parameter in OpenSubdiv's
/// `Bfr` parameterization: quads `(0, 0)` at corner 0, `u` toward corner 1, `v` toward corner 3;
/// triangles of triangle schemes `(0, 0)`, `(1, 0)`, `(0, 1)` at corners 0, 1, 2; other faces
/// of quad schemes as `Bfr`'s tiled quad sub-faces ([`FaceDomain::SubFaces`]).
///
/// Positions and derivatives are exact up to f64 rounding (no approximation near extraordinary
/// vertices). Each set of sub-patch matrices has one [`StencilEvaluator`], so faces of equal
/// shape share their stencils (all regular faces of a torus sampled on a grid cost one set) and
/// points share the work of their addresses.
///
/// ```
/// use subdiv_mesh::{shapes, FaceId, Mesh};
/// use subdiv_schemes::{Builtin, RefineOptions};
/// use subdiv_stencil::{Dyadic, LimitEvaluator};
///
/// let cube = Mesh::build(shapes::cube())?;
/// let eval = LimitEvaluator::new(Builtin::CatmullClark.scheme(), &cube, &RefineOptions::DEFAULT)?;
/// // Face centres, exact (1/2, 1/2) or as f64: by symmetry all as far from the cube's centre.
/// let a = eval.eval_exact(FaceId::new(0), Dyadic::new(1, 1, 2))?;
/// let b = eval.eval(FaceId::new(3), 0.5, 0.5)?;
/// assert!((a.position.length() - b.position.length()).abs() < 1e-14);
/// // The derivatives there are exact; their cross product is the outward normal.
/// assert!(a.exact_derivatives && a.du.cross(a.dv).dot(a.position) > 0.0);
/// // Corner 0 of every face is an extraordinary vertex (valence 3): tangent directions only.
/// assert!(!eval.eval(FaceId::new(0), 0.0, 0.0)?.exact_derivatives);
/// // A --grid 2 face has 9 points.
/// assert_eq!(eval.grid(FaceId::new(0), 2)?.len(), 9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct LimitEvaluator {
    patches: PatchLevels,
    /// One stencil evaluator per set of sub-patch matrices, by the matrices' address.
    evaluators: Mutex<HashMap<usize, StencilEvaluator<Arc<PatchMatrices>>>>,
}

impl LimitEvaluator {
    /// Prepares `mesh` under `scheme` with the boundary rule and options of refinement
    /// (`options`, else the mesh's tags): see [`PatchLevels::new`].
    ///
    /// # Errors
    /// As [`PatchLevels::new`].
    pub fn new(scheme: &Scheme, mesh: &Mesh, options: &RefineOptions) -> Result<Self, StencilError> {
        Ok(Self { patches: PatchLevels::new(scheme, mesh, options)?, evaluators: Mutex::default() })
    }

    /// The faces' patches, level by level.
    pub fn patches(&self) -> &PatchLevels {
        &self.patches
    }

    /// The number of faces of the mesh.
    pub fn face_count(&self) -> usize {
        self.patches.face_count()
    }

    /// Whether `face` has a limit surface (it is not a hole).
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn has_surface(&self, face: FaceId) -> Result<bool, StencilError> {
        self.patches.has_surface(face)
    }

    /// The domain of `face`.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`] for a face the mesh does not have.
    pub fn domain(&self, face: FaceId) -> Result<FaceDomain, StencilError> {
        self.patches.domain(face)
    }

    /// Checks that `point` is a parameter of `face` with a surface, as [`eval_exact`](Self::eval_exact)
    /// would, without evaluating.
    ///
    /// # Errors
    /// As [`eval_exact`](Self::eval_exact), for input errors.
    pub fn check(&self, face: FaceId, point: Dyadic) -> Result<(), StencilError> {
        self.patches.check(face, point)
    }

    /// The limit point of `face` at f64 parameters, used exactly (see [`FaceDomain::exact_point`]).
    ///
    /// # Errors
    /// As [`eval_exact`](Self::eval_exact); [`StencilError::OutsideFace`] also for a non-finite
    /// parameter.
    pub fn eval(&self, face: FaceId, u: f64, v: f64) -> Result<LimitPoint, StencilError> {
        let point = self.domain(face)?.exact_point(u, v).ok_or_else(|| StencilError::OutsideFace {
            face: face.index(),
            u: format!("{u:?}"),
            v: format!("{v:?}"),
            domain: self.domain(face).map_or_else(|_| String::new(), FaceDomain::describe),
        })?;
        self.eval_exact(face, point)
    }

    /// The limit point of `face` at the rational parameter `point`.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`], [`StencilError::OutsideFace`] for a point outside the
    /// face's domain, [`StencilError::NoSurface`] for a hole, [`StencilError::Eigen`] if a
    /// stencil's eigenvector is not unique.
    pub fn eval_exact(&self, face: FaceId, point: Dyadic) -> Result<LimitPoint, StencilError> {
        self.check(face, point)?;
        let (mut f, mut p) = (face, point.reduced());
        // (∂/∂u, ∂/∂v) of the face = j · (the same of the current level's face or patch).
        let mut j = [[1.0, 0.0], [0.0, 1.0]];
        for level in 0..self.patches.level_count() {
            let resolved =
                self.patches.resolve(level, f).ok_or_else(|| internal(face, "a child face was not prepared"))?;
            match resolved {
                Resolved::Hole => return Err(StencilError::NoSurface { face: face.index() }),
                Resolved::Children { children, layout } => {
                    let (child, at, [fu, fv]) = layout.child_of(p);
                    f = FaceId::new((children.start + child) as u32);
                    p = at;
                    j = [[j[0][0] * fu, j[0][1] * fv], [j[1][0] * fu, j[1][1] * fv]];
                }
                Resolved::Patch { mesh, patch: found, frame } => {
                    let apply = |w: &[f64]| -> DVec3 {
                        w.iter().zip(&found.vertices).map(|(&w, &v)| w * mesh.position(v)).sum()
                    };
                    let (position, ds, dt, exact_derivatives) =
                        self.with_stencil(&found.matrices, found.shape, frame.to_patch(p), |s| {
                            (apply(&s.position), apply(&s.du), apply(&s.dv), s.exact_derivatives)
                        })?;
                    let (ju, jv) = frame.chain(j);
                    return Ok(LimitPoint {
                        position,
                        du: ju[0] * ds + ju[1] * dt,
                        dv: jv[0] * ds + jv[1] * dt,
                        exact_derivatives,
                    });
                }
            }
        }
        Err(internal(face, "the descent ran past the last prepared level"))
    }

    /// The points of `osd_limit --grid n` on `face` ([`FaceDomain::grid`]) with their limit
    /// points; empty for a hole.
    ///
    /// # Errors
    /// [`StencilError::FaceOutOfRange`], [`StencilError::Rate`] for `n = 0`, and as
    /// [`eval_exact`](Self::eval_exact).
    pub fn grid(&self, face: FaceId, n: u32) -> Result<Vec<(GridParameter, LimitPoint)>, StencilError> {
        if n == 0 {
            return Err(StencilError::Rate { rate: 0, reason: "a grid needs at least one step per side" });
        }
        if !self.has_surface(face)? {
            return Ok(Vec::new());
        }
        self.domain(face)?.grid(n).into_iter().map(|g| Ok((g, self.eval_exact(face, g.point)?))).collect()
    }

    /// `f` of the stencil of `shape` of `matrices` at `point`, from the evaluator of those
    /// matrices, which shares work between points (and whose results do not depend on their
    /// order). Evaluations through one `LimitEvaluator` take turns on its lock.
    fn with_stencil<R>(
        &self,
        matrices: &Arc<PatchMatrices>,
        shape: usize,
        point: Dyadic,
        f: impl FnOnce(&SurfaceStencil) -> R,
    ) -> Result<R, StencilError> {
        // The matrices are shared per process and kept alive by the evaluators, so the address
        // identifies them.
        let mut evaluators = self.evaluators.lock().unwrap_or_else(PoisonError::into_inner);
        let evaluator =
            evaluators.entry(Arc::as_ptr(matrices) as usize).or_insert_with(|| StencilEvaluator::new(matrices.clone()));
        Ok(f(evaluator.stencil(shape, point)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use subdiv_mesh::shapes;
    use subdiv_schemes::{Builtin, Split, child_faces, refine};

    #[test]
    fn other_primal_schemes_meet_their_known_values() {
        // Bilinear: the face's bilinear interpolant, with its derivatives.
        let torus = Mesh::build(shapes::quad_torus(6, 4)).unwrap();
        let eval = LimitEvaluator::new(Builtin::Bilinear.scheme(), &torus, &RefineOptions::DEFAULT).unwrap();
        let c: Vec<DVec3> = torus.face_vertices(FaceId::new(0)).iter().map(|&v| torus.position(v)).collect();
        let (u, v) = (0.5, 0.25);
        let got = eval.eval(FaceId::new(0), u, v).unwrap();
        let want = c[0] * (1.0 - u) * (1.0 - v) + c[1] * u * (1.0 - v) + c[2] * u * v + c[3] * (1.0 - u) * v;
        let du = (c[1] - c[0]) * (1.0 - v) + (c[2] - c[3]) * v;
        let dv = (c[3] - c[0]) * (1.0 - u) + (c[2] - c[1]) * u;
        assert!(got.exact_derivatives);
        for (a, b) in [(got.position, want), (got.du, du), (got.dv, dv)] {
            assert!((a - b).length() < 1e-12, "bilinear: {a} vs {b}");
        }
        // Interpolating schemes pass through the cage's vertices: butterfly on the icosahedron,
        // Kobbelt on the cube (valence 3).
        for (scheme, soup) in [(Builtin::Butterfly, shapes::icosahedron()), (Builtin::Kobbelt, shapes::cube())] {
            let mesh = Mesh::build(soup).unwrap();
            let eval = LimitEvaluator::new(scheme.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
            for f in mesh.face_ids() {
                let p = eval.eval(f, 0.0, 0.0).unwrap().position;
                assert!((p - mesh.position(mesh.face_vertices(f)[0])).length() < 1e-12, "{scheme:?} {f}");
            }
        }
    }

    #[test]
    fn infinitely_sharp_creases_are_the_crease_polygon_s_b_spline() {
        // A ring of edges of a torus (j = 0), infinitely sharp: the limit along it is the
        // uniform cubic B-spline of the ring's vertices, and the two sides' normals differ.
        let (m, n) = (8, 6);
        let mut soup = shapes::quad_torus(m, n);
        let id = |i: usize| subdiv_mesh::VertexId::new(((i % m) * n) as u32);
        for i in 0..m {
            soup.tags.creases.push(subdiv_mesh::CreaseTag { vertices: [id(i), id(i + 1)], sharpness: 10.0 });
        }
        let mesh = Mesh::build(soup).unwrap();
        let p = |i: usize| mesh.position(id(i + m));
        let eval = LimitEvaluator::new(Builtin::CatmullClark.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
        for i in 0..m {
            // Face (i, 0) has the crease as its first side; face (i, n − 1) as its last side's
            // opposite, v = 1.
            let (above, below) = (FaceId::new((i * n) as u32), FaceId::new((i * n + n - 1) as u32));
            for u in [0.0, 0.25, 0.5, 0.75] {
                let b = [
                    (1.0f64 - u).powi(3) / 6.0,
                    (3.0 * u.powi(3) - 6.0 * u * u + 4.0) / 6.0,
                    (-3.0 * u.powi(3) + 3.0 * u * u + 3.0 * u + 1.0) / 6.0,
                    u.powi(3) / 6.0,
                ];
                let want = p(i + m - 1) * b[0] + p(i) * b[1] + p(i + 1) * b[2] + p(i + 2) * b[3];
                let (a, c) = (eval.eval(above, u, 0.0).unwrap(), eval.eval(below, u, 1.0).unwrap());
                assert!((a.position - want).length() < 1e-13, "face {above} at {u}: {:?} vs {want:?}", a.position);
                assert!((c.position - want).length() < 1e-13, "face {below} at {u}");
                let (na, nc) = (a.du.cross(a.dv).normalize(), c.du.cross(c.dv).normalize());
                assert!(na.dot(nc) < 0.999, "the crease at {u} is smooth: {na:?} {nc:?}");
                // Along the crease both sides have the curve's tangent.
                assert!(a.du.normalize().dot(c.du.normalize()) > 1.0 - 1e-12);
            }
        }
    }

    #[test]
    fn semi_sharp_features_equal_the_refined_mesh_s_surface() {
        // An edge of sharpness 2.5 and a corner of sharpness 1.5 are spent after 3 levels: the
        // surface of the cage over face f's corner square [0, 1/8]² is the surface of the
        // 3 times refined mesh over child 0 of child 0 of child 0 of f.
        let cc = Builtin::CatmullClark.scheme();
        let (mesh, _) = creased_cube(2.5, Some(1.5));
        let refined = refine_uniform_n(&mesh, cc, 3);
        let coarse = LimitEvaluator::new(cc, &mesh, &RefineOptions::DEFAULT).unwrap();
        let fine = LimitEvaluator::new(cc, &refined.0, &RefineOptions::DEFAULT).unwrap();
        for f in mesh.face_ids() {
            let mut child = f;
            for level in &refined.1 {
                child = FaceId::new(child_faces(Split::Quad, level, child).unwrap().start as u32);
            }
            for (u, v) in [(0.0, 0.0), (1.0 / 16.0, 0.0), (0.0, 1.0 / 32.0), (1.0 / 8.0, 1.0 / 8.0), (0.05, 0.1)] {
                let (x, y) = (coarse.eval(f, u, v).unwrap(), fine.eval(child, 8.0 * u, 8.0 * v).unwrap());
                assert!((x.position - y.position).length() < 1e-13, "{f} at ({u}, {v})");
                if x.exact_derivatives && y.exact_derivatives {
                    assert!((x.du - y.du * 8.0).length() < 1e-11, "{f} at ({u}, {v}): {:?} {:?}", x.du, y.du * 8.0);
                    assert!((x.dv - y.dv * 8.0).length() < 1e-11);
                }
            }
        }
    }

    /// The cube with its face 0's first side (corners 0 to 1) of `sharpness`, corner 1 a corner
    /// of `corner`; and face 0's corner 0.
    fn creased_cube(sharpness: f64, corner: Option<f64>) -> (Mesh, subdiv_mesh::VertexId) {
        let mut soup = shapes::cube();
        let [a, b] = [soup.face(FaceId::new(0))[0], soup.face(FaceId::new(0))[1]];
        soup.tags.creases.push(subdiv_mesh::CreaseTag { vertices: [a, b], sharpness });
        if let Some(sharpness) = corner {
            soup.tags.corners.push(subdiv_mesh::CornerTag { vertex: b, sharpness });
        }
        (Mesh::build(soup).unwrap(), a)
    }

    /// At a dart (one infinitely sharp edge ends at a smooth vertex) the limit is the dominant
    /// left eigenvector of the dart's local matrix, not the smooth vertex's limit mask (which
    /// OpenSubdiv applies there): the vertex's refined positions converge to ours, geometrically.
    #[test]
    fn refined_darts_converge_to_the_limit_point() {
        let cc = Builtin::CatmullClark.scheme();
        let (mesh, a) = creased_cube(10.0, None);
        let limit = LimitEvaluator::new(cc, &mesh, &RefineOptions::DEFAULT).unwrap().eval(FaceId::new(0), 0.0, 0.0);
        let limit = limit.unwrap().position;
        // Vertex points keep their vertex's index under refinement.
        let (refined, _) = refine_uniform_n(&mesh, cc, 9);
        let mut current = mesh.clone();
        let mut distances = Vec::new();
        for _ in 0..9 {
            current = refine(&current, cc, &RefineOptions::DEFAULT).unwrap();
            distances.push((current.position(a) - limit).length());
        }
        assert_eq!(current.position(a), refined.position(a));
        // Each level shrinks the distance (by at least the subdominant eigenvalue's ½ or so),
        // to 2^-9-ish of the first level's.
        for w in distances.windows(2) {
            assert!(w[1] < 0.8 * w[0], "{distances:?}");
        }
        assert!(distances[8] < 1e-2 * distances[0], "{distances:?}");
    }

    /// `mesh` refined `levels` times, with the mesh of every level before the last.
    fn refine_uniform_n(mesh: &Mesh, scheme: &Scheme, levels: usize) -> (Mesh, Vec<Mesh>) {
        let mut all = vec![mesh.clone()];
        for _ in 0..levels {
            all.push(refine(all.last().unwrap(), scheme, &RefineOptions::DEFAULT).unwrap());
        }
        let last = all.pop().unwrap();
        (last, all)
    }

    #[test]
    fn holes_and_bad_points_are_typed_errors() {
        let cc = Builtin::CatmullClark.scheme();
        let mut soup = shapes::cube();
        soup.tags.holes.push(FaceId::new(1));
        let mesh = Mesh::build(soup).unwrap();
        let eval = LimitEvaluator::new(cc, &mesh, &RefineOptions::DEFAULT).unwrap();
        assert!(eval.grid(FaceId::new(1), 2).unwrap().is_empty());
        assert_eq!(eval.eval(FaceId::new(1), 0.5, 0.5), Err(StencilError::NoSurface { face: 1 }));
        assert_eq!(eval.grid(FaceId::new(0), 2).unwrap().len(), 9);
        assert_eq!(eval.eval(FaceId::new(6), 0.0, 0.0), Err(StencilError::FaceOutOfRange { face: 6, faces: 6 }));
        assert!(matches!(eval.eval(FaceId::new(0), 1.0, 1.5), Err(StencilError::OutsideFace { face: 0, .. })));
        assert!(matches!(eval.eval(FaceId::new(0), f64::INFINITY, 0.0), Err(StencilError::OutsideFace { .. })));

        // The dual split takes no holes; √3 takes triangles only.
        let doo_sabin = LimitEvaluator::new(Builtin::DooSabin.scheme(), &mesh, &RefineOptions::DEFAULT);
        assert!(matches!(
            doo_sabin,
            Err(StencilError::Scheme(subdiv_schemes::SchemeError::FeatureNotSupported { .. }))
        ));
        let sqrt3 = LimitEvaluator::new(Builtin::Sqrt3.scheme(), &mesh, &RefineOptions::DEFAULT);
        assert!(matches!(sqrt3, Err(StencilError::Scheme(_))), "{sqrt3:?}");
    }

    /// `k` sectors of a `rings`-ring grid (quads, or triangles) over a half-disk around vertex 0,
    /// which is on the boundary with `k` faces; gently curved so that normals vary.
    fn open_fan(k: usize, rings: usize, triangles: bool) -> subdiv_mesh::PolygonSoup {
        let mut soup = subdiv_mesh::PolygonSoup::new();
        let direction = |s: usize| {
            let a = std::f64::consts::PI * s as f64 / k as f64;
            DVec3::new(a.cos(), a.sin(), 0.0)
        };
        let inside = |i: usize, j: usize| if triangles { i + j <= rings } else { i.max(j) <= rings };
        let centre = soup.push_vertex(DVec3::new(0.0, 0.0, 0.3));
        let mut ids = HashMap::new();
        for s in 0..=k {
            for i in 1..=rings {
                for j in 0..=if s < k { rings } else { 0 } {
                    if inside(i, j) {
                        let p = direction(s) * i as f64 + direction(s + 1) * j as f64;
                        let p = p + DVec3::new(0.0, 0.0, 0.3 - 0.05 * p.length_squared() + 0.1 * p.x);
                        ids.insert((s, i, j), soup.push_vertex(p));
                    }
                }
            }
        }
        let id = |s: usize, i: usize, j: usize| match (i, j) {
            (0, 0) => centre,
            (0, j) => ids[&(s + 1, j, 0)],
            _ => ids[&(s, i, j)],
        };
        for s in 0..k {
            for i in 0..rings {
                for j in 0..rings {
                    if !triangles {
                        soup.push_face([id(s, i, j), id(s, i + 1, j), id(s, i + 1, j + 1), id(s, i, j + 1)]);
                        continue;
                    }
                    if i + j < rings {
                        soup.push_face([id(s, i, j), id(s, i + 1, j), id(s, i, j + 1)]);
                    }
                    if i + j + 1 < rings {
                        soup.push_face([id(s, i + 1, j), id(s, i + 1, j + 1), id(s, i, j + 1)]);
                    }
                }
            }
        }
        soup
    }

    #[test]
    fn tangents_at_boundary_vertices_span_each_faces_own_plane() {
        // Catmull-Clark's ½ is defective at four faces (a Jordan block under 0.61), and at six
        // the two leading modes vanish on the boundary; Loop's eight faces make a thin wedge.
        for (scheme, k) in
            [(Builtin::CatmullClark, 4), (Builtin::CatmullClark, 6), (Builtin::Loop, 4), (Builtin::Loop, 8)]
        {
            let triangles = scheme == Builtin::Loop;
            let mesh = Mesh::build(open_fan(k, 3, triangles)).unwrap();
            let eval = LimitEvaluator::new(scheme.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
            let corners: &[(f64, f64)] = if triangles {
                &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
            } else {
                &[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            };
            let centre = if triangles { (1.0 / 3.0, 1.0 / 3.0) } else { (0.5, 0.5) };
            let mut seen = 0;
            for f in mesh.face_ids() {
                let Some(c) = mesh.face_vertices(f).iter().position(|v| v.index() == 0) else { continue };
                seen += 1;
                let (u0, v0) = corners[c];
                // Towards the face's centre by h.
                let near = |h: f64| eval.eval(f, u0 + h * (centre.0 - u0), v0 + h * (centre.1 - v0)).unwrap();
                let at = eval.eval(f, u0, v0).unwrap();
                let what = format!("{scheme:?} k = {k} face {f}");
                assert!(!at.exact_derivatives, "{what}");
                let angle = at.du.angle_between(at.dv).to_degrees();
                assert!(angle > 1.0 && angle < 179.0, "{what}: du and dv {angle}° apart");
                let normal = at.du.cross(at.dv).normalize();
                for h in [0.5f64.powi(3), 0.5f64.powi(10), 0.5f64.powi(20)] {
                    let p = near(h);
                    assert!(p.exact_derivatives, "{what}");
                    let dot = normal.dot(p.du.cross(p.dv).normalize());
                    assert!(dot > 0.9, "{what}: the normal at h = {h} is {dot} off");
                }
                // Lengths like the exact derivatives next to the vertex (not 1e7 of them).
                let p = near(0.125);
                let exact = p.du.length().max(p.dv.length());
                for d in [at.du, at.dv] {
                    assert!(
                        d.length() < 20.0 * exact && d.length() > exact / 20.0,
                        "{what}: {} vs {exact}",
                        d.length()
                    );
                }
            }
            assert_eq!(seen, k, "{scheme:?}");
        }
    }

    /// Catmull-Clark at `vertex` of `soup`, per quad around it: the tangents there, and the
    /// limit points approaching it along the face's diagonal at distances `hs` (in the face's
    /// parameters, towards its centre).
    fn tangents_and_nearby_normals(
        soup: subdiv_mesh::PolygonSoup,
        vertex: usize,
        hs: &[f64],
    ) -> Vec<(String, LimitPoint, Vec<LimitPoint>)> {
        let mesh = Mesh::build(soup).unwrap();
        let eval = LimitEvaluator::new(Builtin::CatmullClark.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
        let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        mesh.face_ids()
            .filter_map(|f| {
                let c = mesh.face_vertices(f).iter().position(|v| v.index() == vertex)?;
                let (u0, v0) = corners[c];
                let at = eval.eval(f, u0, v0).unwrap();
                let near = hs
                    .iter()
                    .map(|&h| {
                        let p = eval.eval(f, u0 + h * (0.5 - u0), v0 + h * (0.5 - v0)).unwrap();
                        assert!(p.exact_derivatives, "face {f} at {h}");
                        p
                    })
                    .collect();
                Some((format!("face {f}"), at, near))
            })
            .collect()
    }

    /// `pole(k)` with the spokes `sharp` (whole spokes, both edges) infinitely sharp.
    fn creased_pole(k: usize, sharp: &[usize]) -> subdiv_mesh::PolygonSoup {
        let mut soup = shapes::pole(k);
        for &s in sharp {
            let (a, b) = (subdiv_mesh::VertexId::new(1 + 6 * s as u32), subdiv_mesh::VertexId::new(2 + 6 * s as u32));
            for vertices in [[subdiv_mesh::VertexId::new(0), a], [a, b]] {
                soup.tags
                    .creases
                    .push(subdiv_mesh::CreaseTag { vertices, sharpness: subdiv_mesh::Tags::INFINITELY_SHARP });
            }
        }
        soup
    }

    /// Tangents that are directions (not parallel) of about the exact derivatives' lengths
    /// next to the vertex, `near` (not 1e7 of them).
    fn assert_sane_tangents(what: &str, at: &LimitPoint, near: &LimitPoint) {
        assert!(!at.exact_derivatives, "{what}");
        let angle = at.du.angle_between(at.dv).to_degrees();
        assert!(angle > 1.0 && angle < 179.0, "{what}: du and dv {angle}° apart");
        let exact = near.du.length().max(near.dv.length());
        for d in [at.du, at.dv] {
            assert!(d.length() < 20.0 * exact && d.length() > exact / 20.0, "{what}: {} vs {exact}", d.length());
        }
    }

    #[test]
    fn tangents_at_infinitely_sharp_creases_and_corners_are_the_limit_of_nearby_normals() {
        let hs: Vec<f64> = [3, 10, 20, 40].iter().map(|&k| 0.5f64.powi(k)).collect();
        // A crease with four faces on one side, whose ½ is a 2 × 2 Jordan block beside the two
        // faces' own ½ (below 0.61); four and four (two blocks on the crease's ½); a corner of
        // three creases whose sector of two faces has 0.58 above the creases' ½; a dart.
        for (k, sharp) in [(6, vec![0, 4]), (8, vec![0, 4]), (6, vec![0, 1, 3]), (5, vec![0])] {
            let points = tangents_and_nearby_normals(creased_pole(k, &sharp), 0, &hs);
            assert_eq!(points.len(), k);
            for (what, at, near) in points {
                let what = format!("k = {k}, sharp spokes {sharp:?}, {what}");
                // The side of two faces of a crease has derivatives: the regular crease's.
                if !at.exact_derivatives {
                    assert_sane_tangents(&what, &at, &near[0]);
                }
                let normal = at.du.cross(at.dv).normalize();
                for (p, h) in near[1..].iter().zip(&hs[1..]) {
                    let dot = normal.dot(p.du.cross(p.dv).normalize());
                    assert!(dot > 0.999, "{what}: the normal at h = {h} is {dot} off");
                }
            }
        }
        // Corners of three creases whose sectors of two faces have the creases' ½ as a 2 × 2
        // block beside a simple ½: the block's top (the creases' mean tangent, growing as
        // n 2⁻ⁿ) and the simple one (their difference) span the plane, which the normals near
        // the vertex reach only as 1/n (at 2⁻ⁿ), the part of the block's eigenvector fading.
        for (k, sharp, lowered) in [(4, vec![1, 2, 3], 0.6), (5, vec![0, 2, 3], 0.0), (5, vec![0, 2, 3], 0.6)] {
            let mut soup = creased_pole(k, &sharp);
            soup.positions_mut()[0].z -= lowered;
            let mut seen = 0;
            for (what, at, near) in tangents_and_nearby_normals(soup, 0, &hs) {
                let what = format!("k = {k}, sharp spokes {sharp:?}, centre lowered by {lowered}, {what}");
                if at.exact_derivatives {
                    continue; // A sector of one face: a regular corner.
                }
                seen += 1;
                assert_sane_tangents(&what, &at, &near[0]);
                let normal = at.du.cross(at.dv).normalize();
                let angles: Vec<f64> =
                    near[1..].iter().map(|p| normal.angle_between(p.du.cross(p.dv)).to_degrees()).collect();
                assert!(angles[0] < 20.0, "{what}: {angles:?}");
                assert!(angles[1] < 0.7 * angles[0] && angles[2] < 0.7 * angles[1], "{what}: {angles:?}");
            }
            assert_eq!(seen, 2 * (k - 3), "k = {k}");
        }
    }

    /// Two quads glued along two edges, around a vertex of valence 2 (the last) in the middle of
    /// a 3 × 3 grid, whose middle quad they replace; domed, the vertex lowered by `lowered`.
    fn valence_two(lowered: f64) -> subdiv_mesh::PolygonSoup {
        let grid = shapes::quad_grid(3, 3);
        let mut soup = subdiv_mesh::PolygonSoup::new();
        let dome =
            |p: DVec3| p + DVec3::Z * (0.3 - 0.1 * (p - DVec3::new(1.5, 1.5, 0.0)).length_squared() + 0.05 * p.x);
        for &p in grid.positions() {
            soup.push_vertex(dome(p));
        }
        let centre = soup.push_vertex(dome(DVec3::new(1.5, 1.5, -lowered)));
        let id = |i: usize, j: usize| subdiv_mesh::VertexId::new((j * 4 + i) as u32);
        for j in 0..3 {
            for i in 0..3 {
                let corners = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                if (i, j) == (1, 1) {
                    soup.push_face([corners[0], corners[1], corners[2], centre]);
                    soup.push_face([corners[0], centre, corners[2], corners[3]]);
                } else {
                    soup.push_face(corners);
                }
            }
        }
        soup
    }

    #[test]
    fn tangents_at_a_vertex_of_valence_two_run_along_the_first_side_and_into_the_face() {
        // Each face covers half a turn of the characteristic map, so its sides are opposite:
        // dv points into the face instead, and both faces get one normal. The normals nearby
        // differ from it a little, by the direction of approach and the level's parity (−¼
        // beside the ¼ pair).
        let hs: Vec<f64> = [3, 10, 11, 20, 21].iter().map(|&k| 0.5f64.powi(k)).collect();
        for lowered in [0.0, 0.5] {
            let points = tangents_and_nearby_normals(valence_two(lowered), 16, &hs);
            assert_eq!(points.len(), 2);
            let normals: Vec<DVec3> = points.iter().map(|(_, at, _)| at.du.cross(at.dv).normalize()).collect();
            assert!(normals[0].dot(normals[1]) > 1.0 - 1e-9, "lowered by {lowered}: {normals:?}");
            for ((what, at, near), normal) in points.iter().zip(normals) {
                let what = format!("lowered by {lowered}, {what}");
                assert_sane_tangents(&what, at, &near[0]);
                assert!(normal.z > 0.9, "{what}: the dome's normal points up: {normal}");
                for (p, h) in near[1..].iter().zip(&hs[1..]) {
                    let dot = normal.dot(p.du.cross(p.dv).normalize());
                    assert!(dot > 0.99, "{what}: the normal at h = {h} is {dot} off");
                }
            }
        }
    }

    #[test]
    fn bilinear_is_each_faces_interpolant_with_exact_derivatives() {
        // Valence 3 (the cube), 5 (the pole) and a boundary vertex of four faces.
        for soup in [shapes::cube(), shapes::pole(5), open_fan(4, 2, false)] {
            let mesh = Mesh::build(soup).unwrap();
            let eval = LimitEvaluator::new(Builtin::Bilinear.scheme(), &mesh, &RefineOptions::DEFAULT).unwrap();
            for f in mesh.face_ids() {
                let c: Vec<DVec3> = mesh.face_vertices(f).iter().map(|&v| mesh.position(v)).collect();
                for j in 0..=4 {
                    for i in 0..=4 {
                        let (u, v) = (f64::from(i) / 4.0, f64::from(j) / 4.0);
                        let got = eval.eval(f, u, v).unwrap();
                        let want =
                            c[0] * (1.0 - u) * (1.0 - v) + c[1] * u * (1.0 - v) + c[2] * u * v + c[3] * (1.0 - u) * v;
                        let du = (c[1] - c[0]) * (1.0 - v) + (c[2] - c[3]) * v;
                        let dv = (c[3] - c[0]) * (1.0 - u) + (c[2] - c[1]) * u;
                        assert!(got.exact_derivatives, "{f} ({u}, {v})");
                        for (a, b) in [(got.position, want), (got.du, du), (got.dv, dv)] {
                            assert!((a - b).length() < 1e-12, "{f} ({u}, {v}): {a} vs {b}");
                        }
                    }
                }
            }
        }
    }

    /// A semi-sharp feature shapes only the faces at it (a semi-sharp corner's faces, those at
    /// either end of a semi-sharp edge): the faces one ring further out, whose patches hold
    /// it, are evaluated through their patches on level 0. The faces at it descend two levels,
    /// where the rest of their sharpness is a configuration derived once (`PatchType::Derived`)
    /// instead of two more levels. Every face's points equal those of the mesh refined until
    /// the sharpness is spent (no semi-sharp feature left, every patch on that level),
    /// descended to by hand (the cube's test above has no face one ring out).
    #[test]
    fn semi_sharp_features_reach_only_the_faces_at_them() {
        use subdiv_mesh::{CornerTag, CreaseTag, VertexId};
        use subdiv_schemes::PatchType;
        let cc = Builtin::CatmullClark.scheme();
        let mut soup = shapes::quad_grid(7, 6);
        let at = |x: u32, y: u32| VertexId::new(y * 8 + x);
        soup.tags.creases.push(CreaseTag { vertices: [at(2, 3), at(3, 3)], sharpness: 4.0 });
        soup.tags.creases.push(CreaseTag { vertices: [at(3, 3), at(4, 3)], sharpness: 3.5 });
        soup.tags.corners.push(CornerTag { vertex: at(5, 2), sharpness: 3.0 });
        let mesh = Mesh::build(soup).unwrap();
        let eval = LimitEvaluator::new(cc, &mesh, &RefineOptions::DEFAULT).unwrap();
        let patches = eval.patches();
        let on_level_0 = mesh.face_ids().filter(|&f| matches!(patches.resolve(0, f), Some(Resolved::Patch { .. })));
        // 42 faces; 8 at the edges' ends and 4 at the corner (one shared with them) descend.
        assert_eq!(on_level_0.count(), 42 - 11);
        assert_eq!(patches.level_count(), 3);
        let derived = patches.mesh(2).face_ids().filter(|&f| {
            matches!(patches.resolve(2, f), Some(Resolved::Patch { patch, .. })
                if matches!(patch.matrices.patch_type, PatchType::Derived { .. }))
        });
        assert!(derived.count() > 0);
        let levels = 4;
        let spent = subdiv_schemes::refine_uniform(&mesh, cc, levels, &RefineOptions::DEFAULT).unwrap();
        let fine = LimitEvaluator::new(cc, &spent, &RefineOptions::DEFAULT).unwrap();
        assert!(fine.patches().level_count() == 1, "sharpness spent after {levels} levels");
        let mut meshes = vec![mesh.clone()];
        for _ in 1..levels {
            meshes.push(refine(meshes.last().unwrap(), cc, &RefineOptions::DEFAULT).unwrap());
        }
        let mut worst = 0.0f64;
        for f in mesh.face_ids() {
            for g in FaceDomain::Quad.grid(4) {
                let (mut face, mut u, mut v, mut scale) = (f, g.u, g.v, 1.0);
                for level in &meshes {
                    let (c, cu, cv, factor) = FaceDomain::Quad.child_of_f64(u, v);
                    face = FaceId::new((child_faces(Split::Quad, level, face).unwrap().start + c) as u32);
                    (u, v, scale) = (cu, cv, scale * factor);
                }
                let (got, want) = (eval.eval(f, g.u, g.v).unwrap(), fine.eval(face, u, v).unwrap());
                worst = worst.max(got.position.distance(want.position));
                // (At the grid's corners, tangent directions of either length.)
                if !got.exact_derivatives || !want.exact_derivatives {
                    continue;
                }
                for (a, b) in [(got.du, scale * want.du), (got.dv, scale * want.dv)] {
                    worst = worst.max(a.distance(b));
                }
            }
        }
        assert!(worst < 1e-11, "off by {worst:e}");
    }
}
