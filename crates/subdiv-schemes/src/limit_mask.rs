//! Limit masks derived from the local subdivision matrix: the weights that move a vertex of a
//! refined mesh (for a dual scheme, a face) to its point on the limit surface, for any
//! stationary scheme, read on the analysis's canonical mesh and placed on a real mesh by
//! walking both meshes in step.

use std::collections::{HashMap, HashSet};

use subdiv_mesh::{DVec3, FaceId, HalfEdgeId, Mesh, VertexId};

use crate::analysis::{Canonical, MAX_RADIUS, first_spoke};
use crate::{Centre, Scheme, SchemeError, Split};

/// The limit mask of a scheme around one kind of centre: the dominant left eigenvector of the
/// [`LocalMatrix`](crate::LocalMatrix) (the eigenvalue 1), scaled to sum 1, over the smallest
/// neighbourhood that refinement maps into itself. A centre's limit is the mask applied to its
/// neighbourhood, on any level: the limit is the same point after every further refinement,
/// and the mask is the row that says so.
///
/// The centre is a vertex for primal schemes and a face (the face a vertex becomes) for the
/// dual splits (Doo-Sabin, mid-edge): `Centre::Interior(k)` is then a `k`-sided face.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh, VertexId};
/// use subdiv_schemes::{Builtin, Centre, LimitMask};
///
/// // Catmull-Clark at a vertex of valence 3: `(k² v + 4 Σ e + Σ f) / (k (k + 5))`.
/// let mask = LimitMask::at(Builtin::CatmullClark.scheme(), Centre::Interior(3))?;
/// assert_eq!(mask.weights().len(), 7);
/// assert!((mask.weights()[0] - 9.0 / 24.0).abs() < 1e-14);
/// // Placed on the cube [-1, 1]³: (9 p + 4 p − p) / 24, half-way to the centre.
/// let cube = Mesh::build(shapes::cube())?;
/// let corner = VertexId::new(0);
/// let limit = mask.limit_at_vertex(&cube, corner).expect("a cube's corner is the canonical one");
/// assert!((limit - cube.position(corner) / 2.0).length() < 1e-14);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct LimitMask {
    centre: Centre,
    centre_is_face: bool,
    /// The canonical mesh the mask was read on.
    mesh: Mesh,
    /// The canonical half-edge the placing walk starts from: the centre's first spoke.
    start: HalfEdgeId,
    /// The canonical faces whose arrangement the mask depends on.
    faces: HashSet<FaceId>,
    /// The canonical vertices inside the neighbourhood's outer ring (all of the centre face's
    /// at radius 0): the edges at them must be alike on a real mesh, the outer ring's edges
    /// may be a boundary there (no rule the mask reads looks at them).
    inner: HashSet<VertexId>,
    /// The canonical vertex under each weight.
    vertices: Vec<VertexId>,
    weights: Vec<f64>,
}

impl LimitMask {
    /// The mask of `scheme` at `centre`.
    ///
    /// # Errors
    /// As [`LocalMatrix::at`](crate::LocalMatrix::at); [`SchemeError::Eigen`] where the
    /// eigenvalue 1 has no eigenvector whose weights have a non-zero sum (a scheme that does
    /// not converge there).
    pub fn at(scheme: &Scheme, centre: Centre) -> Result<Self, SchemeError> {
        let canonical = Canonical::new(scheme, centre, MAX_RADIUS)?;
        let matrix = canonical.closed()?;
        let neighbourhood = canonical.neighbourhood(matrix.radius());
        // The left eigenvector of 1: the right one of the transpose.
        let vector = matrix
            .transposed()
            .eigenspace(1.0, 1)?
            .pop()
            .ok_or_else(|| SchemeError::Internal("an empty local matrix".into()))?;
        let sum: f64 = vector.iter().sum();
        if sum.abs() < 1e-9 {
            return Err(SchemeError::Eigen(format!(
                "{scheme} at {centre}: the eigenvector of 1 sums to {sum:e}, no limit mask"
            )));
        }
        let weights = vector.iter().map(|w| w / sum).collect();
        let centre_is_face = matches!(canonical.split(), Split::Dual | Split::Midedge);
        let mesh = canonical.parent().clone();
        let rings: HashMap<VertexId, usize> = neighbourhood.iter().copied().collect();
        let radius = matrix.radius();
        // The faces the neighbourhood's refinement reads: those at a vertex inside its outer
        // ring (radius 0: the centre face).
        let faces = mesh
            .face_ids()
            .filter(|&f| {
                let vs = mesh.face_vertices(f);
                if radius == 0 {
                    vs.iter().all(|v| rings.contains_key(v))
                } else {
                    vs.iter().any(|v| rings.get(v).is_some_and(|&r| r < radius))
                }
            })
            .collect();
        let inner = rings.iter().filter(|&(_, &r)| r < radius || radius == 0).map(|(&v, _)| v).collect();
        let start = first_spoke(&mesh, canonical.centre())
            .ok_or_else(|| SchemeError::Internal(format!("{scheme} at {centre}: no first spoke")))?;
        Ok(Self {
            centre,
            centre_is_face,
            mesh,
            start,
            faces,
            inner,
            vertices: neighbourhood.into_iter().map(|(v, _)| v).collect(),
            weights,
        })
    }

    /// The centre the mask is for.
    pub fn centre(&self) -> Centre {
        self.centre
    }

    /// The weights, the centre's vertices first, then ring by ring around it (the
    /// [`LocalMatrix`](crate::LocalMatrix)'s order).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The vertices of `mesh` under the weights, with the centre's first spoke at `start` (a
    /// half-edge out of the centre vertex, or of the centre face); `None` where `mesh` differs
    /// there from the canonical neighbourhood: other face sizes, a boundary or a missing one,
    /// a sharp edge or corner.
    pub fn place(&self, mesh: &Mesh, start: HalfEdgeId) -> Option<Vec<VertexId>> {
        let canonical = &self.mesh;
        let mut place: HashMap<VertexId, VertexId> = HashMap::new();
        let mut seen = HashSet::new();
        let mut stack = vec![(self.start, start)];
        while let Some((a, b)) = stack.pop() {
            let face = canonical.face(a);
            if !self.faces.contains(&face) || !seen.insert(face) {
                continue;
            }
            if canonical.face_size(face) != mesh.face_size(mesh.face(b)) || mesh.is_hole(mesh.face(b)) {
                return None;
            }
            let (mut x, mut y) = (a, b);
            loop {
                if *place.entry(canonical.origin(x)).or_insert(mesh.origin(y)) != mesh.origin(y)
                    || mesh.vertex_sharpness(mesh.origin(y)) > 0.0
                {
                    return None;
                }
                let inner = self.inner.contains(&canonical.origin(x)) || self.inner.contains(&canonical.dest(x));
                match (canonical.twin(x), mesh.twin(y)) {
                    (Some(p), Some(q)) => {
                        if inner && mesh.edge_sharpness(mesh.edge(y)) > 0.0 {
                            return None;
                        }
                        stack.push((p, q));
                    }
                    (None, None) => {}
                    _ if inner => return None,
                    _ => {}
                }
                (x, y) = (canonical.next(x), mesh.next(y));
                if x == a {
                    break;
                }
            }
        }
        let placed: Vec<VertexId> = self.vertices.iter().map(|v| place.get(v).copied()).collect::<Option<_>>()?;
        let distinct: HashSet<&VertexId> = placed.iter().collect();
        (distinct.len() == placed.len()).then_some(placed)
    }

    /// The mask applied at `start` ([`place`](Self::place)): the centre's limit point.
    pub fn limit(&self, mesh: &Mesh, start: HalfEdgeId) -> Option<DVec3> {
        let placed = self.place(mesh, start)?;
        Some(placed.iter().zip(&self.weights).map(|(&v, &w)| w * mesh.position(v)).sum())
    }

    /// The limit of vertex `vertex` of `mesh` (a primal scheme's centre), the first of its
    /// spokes that places the mask (at a boundary vertex, the one along the boundary).
    pub fn limit_at_vertex(&self, mesh: &Mesh, vertex: VertexId) -> Option<DVec3> {
        if self.centre_is_face {
            return None;
        }
        mesh.outgoing(vertex).find_map(|h| self.limit(mesh, h))
    }

    /// The limit of face `face` of `mesh` (a dual scheme's centre), from the first of its
    /// corners that places the mask.
    pub fn limit_at_face(&self, mesh: &Mesh, face: FaceId) -> Option<DVec3> {
        if !self.centre_is_face {
            return None;
        }
        mesh.face_half_edges(face).find_map(|h| self.limit(mesh, h))
    }
}

#[cfg(test)]
mod tests {
    use subdiv_mesh::shapes;

    use super::*;
    use crate::Builtin;

    /// The derived masks are the closed forms where those are known.
    #[test]
    fn masks_are_the_closed_forms() {
        for k in 3..=8 {
            let cc = LimitMask::at(Builtin::CatmullClark.scheme(), Centre::Interior(k)).unwrap();
            let kf = k as f64;
            assert!((cc.weights()[0] - kf / (kf + 5.0)).abs() < 1e-13, "valence {k}: {:?}", cc.weights());
            let lp = LimitMask::at(Builtin::Loop.scheme(), Centre::Interior(k)).unwrap();
            let c = 3.0 / 8.0 + (std::f64::consts::TAU / kf).cos() / 4.0;
            let beta = (5.0 / 8.0 - c * c) / kf;
            let chi = 1.0 / (3.0 / (8.0 * beta) + kf);
            assert!((lp.weights()[0] - (1.0 - kf * chi)).abs() < 1e-13, "valence {k}: {:?}", lp.weights());
            // Doo-Sabin's face: its centroid.
            let ds = LimitMask::at(Builtin::DooSabin.scheme(), Centre::Interior(k)).unwrap();
            assert_eq!(ds.weights().len(), k);
            assert!(ds.weights().iter().all(|w| (w - 1.0 / kf).abs() < 1e-13), "{:?}", ds.weights());
        }
        // The cubic B-spline along a boundary: (1, 4, 1) / 6 over the boundary neighbours.
        let boundary = LimitMask::at(Builtin::CatmullClark.scheme(), Centre::Boundary(2)).unwrap();
        let mesh = Mesh::build(shapes::quad_grid(2, 2)).unwrap();
        let v = mesh.vertices().find(|&v| mesh.is_boundary_vertex(v) && mesh.valence(v) == 3).unwrap();
        let ring = mesh.one_ring(v);
        let expected = (mesh.position(ring[0]) + 4.0 * mesh.position(v) + mesh.position(ring[ring.len() - 1])) / 6.0;
        let got = boundary.limit_at_vertex(&mesh, v).unwrap();
        assert!((got - expected).length() < 1e-14, "{got} vs {expected}");
    }

    /// A neighbourhood that is not the canonical one is not placed.
    #[test]
    fn other_neighbourhoods_are_not_placed() {
        let mask = LimitMask::at(Builtin::CatmullClark.scheme(), Centre::Interior(4)).unwrap();
        let cube = Mesh::build(shapes::cube()).unwrap();
        assert!(mask.limit_at_vertex(&cube, VertexId::new(0)).is_none());
        let mut creased = Mesh::build(shapes::quad_grid(2, 2)).unwrap();
        let middle = creased.vertices().find(|&v| !creased.is_boundary_vertex(v)).unwrap();
        assert!(mask.limit_at_vertex(&creased, middle).is_some());
        let spoke = creased.outgoing(middle).next().unwrap();
        let edge = creased.edge(spoke);
        creased.set_edge_sharpness(edge, 1.0);
        assert!(mask.limit_at_vertex(&creased, middle).is_none());
        // A face mask does not take a vertex, nor a vertex mask a face.
        let ds = LimitMask::at(Builtin::DooSabin.scheme(), Centre::Interior(4)).unwrap();
        assert!(ds.limit_at_vertex(&cube, VertexId::new(0)).is_none());
        assert!(mask.limit_at_face(&cube, FaceId::new(0)).is_none());
        assert!(ds.limit_at_face(&cube, FaceId::new(0)).is_some());
    }
}
