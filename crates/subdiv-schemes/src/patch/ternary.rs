//! Patches of the ternary split: √3 taken two steps at a time.
//!
//! One √3 step puts a point in every triangle and flips the old edges, so its triangles straddle
//! the old ones; two steps split every triangle `F` into nine with `F`'s orientation (Kobbelt
//! 2000, §2). Over `F`'s lattice of thirds — corners `(0, 0)`, `(3, 0)`, `(0, 3)` — the points
//! of the second level are `F`'s corners, its centre `c_F` (the first step's point of `F`) at
//! `(1, 1)`, and on each side `h` (from corner `a` to `b`) the second step's points of the two
//! first-level triangles across it: the one at `a` (`a`, the point of the face beyond `h`,
//! `c_F`) at a third of the way, the one at `b` at two thirds. The nine children are the
//! lattice's cells ([`ChildDomain::ternary`]), each found in the second level by its first
//! side; their control points are rows over the parent's, so patches are closed under the split
//! like the binary splits' (the smallest radius whose rows stay inside), and the evaluators take
//! them with base-3 addresses. On an open mesh (Kobbelt's boundary rule: the first step keeps
//! the boundary, the second splits each boundary edge in three and fans its triangle from the
//! far corner, flipping the fan's sides with the neighbours) a boundary side's thirds are the
//! split edge's two points and the nine cells are the same, so boundary patch types derive on
//! open fans as the interior ones on pillows.

use std::collections::HashMap;

use subdiv_mesh::{FaceId, HalfEdgeId, Mesh, VertexId};

use super::derivation::{ShapeQueue, canonical_start, influence_sets, parameter_coordinates};
use super::{ChildDomain, MAX_PATCH_RADIUS, PatchMatrices, PatchType, SharpFeatures, SubPatch, ZERO_WEIGHT};
use crate::refine::sqrt3_steps;
use crate::{RefineOptions, Scheme, SchemeError, Stencils};

/// Ternary levels after which the shapes must have closed up.
const MAX_LEVELS: usize = 4;

/// One ternary level: the mesh after one √3 step (`mid`) and after two (`mesh`), each with its
/// rows over the one before.
struct Level {
    mid: Mesh,
    mesh: Mesh,
    first: Stencils,
    second: Stencils,
}

impl Level {
    fn of(parent: &Mesh, scheme: &Scheme) -> Result<Self, SchemeError> {
        let [(mid, first), (mesh, second)] = sqrt3_steps(parent, scheme, &RefineOptions::DEFAULT)?;
        Ok(Self { mid, mesh, first, second })
    }

    /// The row of `vertex` of [`mesh`](Self::mesh) over the parent level's vertices.
    fn row(&self, vertex: usize) -> HashMap<usize, f64> {
        let mut row = HashMap::new();
        for (w, a) in self.second.row(vertex) {
            for (x, b) in self.first.row(w) {
                *row.entry(x).or_insert(0.0) += a * b;
            }
        }
        row
    }
}

/// The half-edge from `a` to `b` of `mesh`, if the two are joined that way.
fn half_edge(mesh: &Mesh, a: VertexId, b: VertexId) -> Option<HalfEdgeId> {
    mesh.outgoing(a).find(|&h| mesh.dest(h) == b)
}

/// The nine children's first half-edges (corner 0 to corner 1, in [`ChildDomain::ternary`]'s
/// order) in `level` of the triangle of `parent` that `start` begins at corner 0. The split's
/// numbering (`dual::sqrt3`): a level keeps its parent's vertices and appends one point per
/// parent face, in face order.
pub fn ternary_child_starts(
    parent: &Mesh,
    start: HalfEdgeId,
    level_mid: &Mesh,
    level: &Mesh,
) -> Option<[HalfEdgeId; 9]> {
    let face = parent.face(start);
    if parent.face_size(face) != 3 {
        return None;
    }
    let centre = |mesh: &Mesh, f: FaceId| VertexId::new((mesh.vertex_count() + f.index()) as u32);
    let h = [start, parent.next(start), parent.next(parent.next(start))];
    let c = centre(parent, face);
    // The second step's point a third of the way along side `h`: of the first-level triangle
    // at `origin(h)` across it; on a boundary side, the split boundary edge's point next to
    // `origin(h)`, numbered in the place of its first-level triangle's centre.
    let point_at = |h: HalfEdgeId| -> Option<VertexId> {
        let t = match parent.twin(h) {
            Some(twin) => half_edge(level_mid, parent.origin(h), centre(parent, parent.face(twin)))?,
            None => half_edge(level_mid, parent.origin(h), parent.dest(h))?,
        };
        Some(centre(level_mid, level_mid.face(t)))
    };
    // Two thirds of the way: a third from the other end; on a boundary side, the next point
    // along the boundary (a boundary vertex's fan starts at its boundary edge).
    let point_after = |h: HalfEdgeId| match parent.twin(h) {
        Some(twin) => point_at(twin),
        None => {
            let along = level.outgoing(point_at(h)?).next()?;
            level.twin(along).is_none().then(|| level.dest(along))
        }
    };
    let v = h.map(|h| parent.origin(h));
    // The lattice points (i, j) of thirds.
    let p10 = point_at(h[0])?;
    let p20 = point_after(h[0])?;
    let p21 = point_at(h[1])?;
    let p12 = point_after(h[1])?;
    let p02 = point_at(h[2])?;
    let p01 = point_after(h[2])?;
    let cells = [
        (v[0], p10, p01),
        (p10, p20, c),
        (p20, v[1], p21),
        (p01, c, p02),
        (c, p21, p12),
        (p02, p12, v[2]),
        (c, p01, p10),
        (p21, c, p20),
        (p12, p02, c),
    ];
    let mut starts = [start; 9];
    for (k, &(a, b, third)) in cells.iter().enumerate() {
        let e = half_edge(level, a, b)?;
        if level.dest(level.next(e)) != third {
            return None;
        }
        starts[k] = e;
    }
    Some(starts)
}

/// Two √3 steps of `mesh` (triangles; open meshes by the scheme's boundary rule) as one ternary split, numbered like the binary
/// splits' levels: the nine children of face `f` are faces `9f..9f + 9`, in
/// [`ChildDomain::ternary`]'s order, each starting at its corner 0 (so a child's parameters are
/// its domain's map of the parent's); the vertices as two steps of `refine` number them. With
/// the rows of the refined vertices over `mesh`'s.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::{Builtin, RefineOptions, ternary_refine};
///
/// let octahedron = Mesh::build(shapes::octahedron())?;
/// let (refined, rows) = ternary_refine(Builtin::Sqrt3.scheme(), &octahedron, &RefineOptions::DEFAULT)?;
/// assert_eq!(refined.face_count(), 9 * 8);
/// assert_eq!((rows.parent_count(), rows.child_count()), (6, refined.vertex_count()));
/// // Face 0's first child keeps its corner 0 (the vertex, moved twice).
/// assert_eq!(refined.face_vertices(subdiv_mesh::FaceId::new(0))[0], octahedron.face_vertices(subdiv_mesh::FaceId::new(0))[0]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As refinement (√3 takes triangles without sharpness, and boundaries by its rule);
/// [`SchemeError::SplitNotSupported`] for a scheme of another split.
pub fn ternary_refine(scheme: &Scheme, mesh: &Mesh, options: &RefineOptions) -> Result<(Mesh, Stencils), SchemeError> {
    if scheme.split() != crate::Split::Sqrt3 {
        return Err(SchemeError::SplitNotSupported {
            scheme: scheme.name.clone(),
            what: "ternary levels",
            split: "this",
            reason: "only √3's two steps split a triangle in nine",
        });
    }
    let [(mid, first), (fine, second)] = sqrt3_steps(mesh, scheme, options)?;
    let rows = first.then(&second);
    let mut soup =
        subdiv_mesh::PolygonSoup::with_capacity(fine.vertex_count(), fine.face_count(), 3 * fine.face_count());
    for v in fine.vertices() {
        soup.push_vertex(fine.position(v));
    }
    for f in mesh.face_ids() {
        let start = mesh.face_half_edges(f).next().expect("faces have corners");
        let starts = ternary_child_starts(mesh, start, &mid, &fine).ok_or_else(|| {
            SchemeError::Internal(format!("{}: the nine children of {f} were not found", scheme.name))
        })?;
        for h in starts {
            soup.push_face([fine.origin(h), fine.dest(h), fine.dest(fine.next(h))]);
        }
    }
    let refined = Mesh::build(soup).map_err(|e| SchemeError::Internal(e.to_string()))?;
    Ok((refined, rows))
}

/// The ternary split's matrices of a smooth type (an interior vertex of valence 3 or more, or a
/// boundary vertex of one face or more): the canonical pillow (open fan) of triangles refined two
/// √3 steps a level, at the smallest radius whose children's rows stay inside their parents.
pub(super) fn derive(scheme: &Scheme, patch_type: PatchType) -> Result<PatchMatrices, SchemeError> {
    let internal = |e: String| SchemeError::Internal(format!("{}: ternary patch derivation: {e}", scheme.name));
    for radius in 1..=MAX_PATCH_RADIUS {
        let rings = radius + 3;
        let soup = match patch_type {
            PatchType::Interior { valence, .. } => {
                crate::canonical::pillow(valence, rings, true, SharpFeatures::SMOOTH)
            }
            PatchType::Boundary { faces, .. } => crate::canonical::open_fan(faces, rings, true, SharpFeatures::SMOOTH),
            PatchType::Derived { .. } => return Err(internal("no derived configurations".into())),
        };
        let base = Mesh::build(soup).map_err(|e| internal(e.to_string()))?;
        let start = canonical_start(&base, patch_type);
        if let Some(found) = derive_at(scheme, base, start, radius, patch_type)? {
            return Ok(found);
        }
    }
    Err(SchemeError::ValenceNotSupported {
        scheme: scheme.name.clone(),
        valence: match patch_type {
            PatchType::Interior { valence, .. } => valence,
            PatchType::Boundary { faces, .. } => faces + 1,
            PatchType::Derived { .. } => 0,
        },
        reason: "the limit surface over a face near this vertex depends on vertices beyond every patch radius up \
                 to 4",
    })
}

/// [`derive`] at one radius; `None` where a child's row leaves its parent's patch.
fn derive_at(
    scheme: &Scheme,
    base: Mesh,
    start: HalfEdgeId,
    radius: usize,
    patch_type: PatchType,
) -> Result<Option<PatchMatrices>, SchemeError> {
    let internal = |e: &str| SchemeError::Internal(format!("{}: ternary patch derivation: {e}", scheme.name));
    let mut meshes = vec![base];
    let mut levels: Vec<Level> = Vec::new();
    let mut queue = ShapeQueue::default();
    queue.register(meshes[0].patch(start, radius), 0, start);
    while let Some((shape, level, start, vertices)) = queue.next() {
        if level == MAX_LEVELS {
            return Err(internal(&format!("the shapes do not close up within {MAX_LEVELS} levels")));
        }
        if levels.len() == level {
            let next = Level::of(&meshes[level], scheme)?;
            meshes.push(next.mesh.clone());
            levels.push(next);
        }
        let next = &levels[level];
        let starts = ternary_child_starts(&meshes[level], start, &next.mid, &next.mesh)
            .ok_or_else(|| internal("a face's nine children were not found"))?;
        let column: HashMap<usize, usize> = vertices.iter().enumerate().map(|(c, v)| (v.index(), c)).collect();
        let mut children = Vec::with_capacity(9);
        for (&domain, &child_start) in ChildDomain::ternary().iter().zip(&starts) {
            let patch = next.mesh.patch(child_start, radius);
            let mut entries = vec![0.0; patch.vertices.len() * vertices.len()];
            for (r, v) in patch.vertices.iter().enumerate() {
                for (p, w) in next.row(v.index()) {
                    match column.get(&p) {
                        Some(&k) => entries[r * vertices.len() + k] += w,
                        None if w.abs() > ZERO_WEIGHT => return Ok(None),
                        None => {}
                    }
                }
            }
            let rows = patch.vertices.len();
            let child_shape = queue.register(patch, level + 1, child_start);
            children.push(SubPatch::from_entries(child_shape, domain, rows, entries));
        }
        queue.shapes[shape].children = children;
    }
    let mut shapes = queue.shapes;
    let influence = influence_sets(&shapes, 3);
    for (shape, influence) in shapes.iter_mut().zip(influence) {
        shape.influence = influence;
    }
    for s in 0..shapes.len() {
        shapes[s].parameters = parameter_coordinates(&shapes, s);
    }
    Ok(Some(PatchMatrices::from_shapes(scheme, patch_type, radius, 3, shapes)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Builtin;

    #[test]
    fn sqrt3_types_close_up_with_a_regular_shape() {
        let sqrt3 = Builtin::Sqrt3.scheme();
        for k in [3, 4, 5, 6, 7, 8] {
            let m = derive(sqrt3, PatchType::interior(k)).unwrap();
            // Two rings: 3k + 9 control points at the vertex, 27 regular; ten shapes.
            assert_eq!((m.radius, m.shapes[0].size), (2, 3 * k + 9), "valence {k}");
            assert_eq!(m.shapes.len(), if k == 6 { 1 } else { 10 }, "valence {k}");
            assert!(m.shapes.iter().any(|s| s.size == 27), "valence {k}: the regular shape");
            assert_eq!(m.shapes[0].children[0].shape, 0, "valence {k}: child 0 keeps the vertex");
            for shape in &m.shapes {
                for child in &shape.children {
                    for r in 0..child.rows() {
                        assert!((child.row(r).map(|e| e.1).sum::<f64>() - 1.0).abs() < 1e-13);
                    }
                }
            }
        }
    }
}
