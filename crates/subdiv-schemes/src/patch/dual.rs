//! Patches of the dual split (Doo-Sabin, or any scheme written with `[rules.dual]`), defined by
//! dependency rather than by rings.
//!
//! A dual step puts a point at every face corner, so after one step every vertex of a closed
//! mesh has valence 4, and the limit surface is a union of pieces, one per vertex `p`: the
//! *dual quad* of `p`, whose corners are the limits of the centres of `p`'s four faces
//! `g_0..g_3` (counter-clockwise from a starting face), and whose control points are those
//! faces' vertices ([`dual_patch`]). The next step puts a child at each corner of `p`, and the
//! children's dual quads are the quarters of `p`'s: the child in face `g_c` sits at corner `c`
//! with the parent's axes, and its own faces are `g_c`'s face (at corner `c`), the faces of
//! the two edges of `p` beside it, and `p`'s vertex face (at the centre). Their vertices are
//! corner points of `g_0..g_3`, each a combination of one face's vertices, so every child's
//! control points are rows over the parent's, whatever the scheme's weights: the patch is
//! closed under refinement by the support of its rows.
//!
//! The extraordinary places are the faces of the dual levels that are not quads (a face of the
//! control mesh, or a vertex's face, of `n` sides, stays an `n`-gon): the dual split's
//! [`PatchType::Interior`] of valence `n` is the dual quad with an `n`-gon at corner 0 and quads
//! at the others — the dual mesh's vertex of valence `n` — whose child 0 keeps the shape. A dual
//! quad with two such faces (the first level's, beside a vertex of valence `k` and a face of
//! `n` sides) is split once more: each child has one at most.
//!
//! On an open mesh, a dual quad at an interior vertex may have boundary faces among its four
//! (the boundary rule moves their corners on boundary edges along the edge alone); its
//! signature marks the half-edges on the boundary, which is all its refinement depends on
//! besides its points, and its matrices are derived from its own neighbourhood
//! ([`derive_dual_configuration`]). Its children are again dual quads at interior vertices, so
//! its domain splits in four as an interior one does; the children along a boundary side keep
//! a boundary shape, whose fixed points lie on the boundary curve.

use std::collections::HashMap;

use subdiv_mesh::{HalfEdgeId, Mesh, Patch, VertexId};

use super::derivation::{ShapeQueue, influence_sets, parameter_coordinates};
use super::{ChildDomain, PatchMatrices, PatchType, SharpFeatures, SubPatch, ZERO_WEIGHT};
use crate::{RefineOptions, Refiner, Scheme, SchemeError, Stencils};

/// The first word of a dual patch's signature, which no primal signature starts with.
const DUAL_SIGNATURE: u32 = u32::MAX;

/// Set on a vertex's place in a dual patch's signature when the face's side from that vertex
/// to the next lies on the boundary (no place reaches it: a patch has far fewer points).
const DUAL_BOUNDARY_SIDE: u32 = 1 << 31;

/// Levels after the first within which a boundary configuration's shapes must close up: the
/// boundary shapes repeat after one or two, the extraordinary faces' after two more.
const MAX_BOUNDARY_LEVELS: usize = 5;

/// Levels after the first after which the shapes must have closed up (they close after two).
const MAX_LEVELS: usize = 4;

/// The next half-edge counter-clockwise around `h`'s origin; `None` across a boundary.
fn counter_clockwise(mesh: &Mesh, h: HalfEdgeId) -> Option<HalfEdgeId> {
    mesh.twin(mesh.prev(h))
}

/// `h` turned `turns` times counter-clockwise around its origin; `None` across a boundary.
fn turned(mesh: &Mesh, h: HalfEdgeId, turns: usize) -> Option<HalfEdgeId> {
    (0..turns).try_fold(h, |h, _| counter_clockwise(mesh, h))
}

/// The four half-edges leaving `start`'s origin, counter-clockwise from `start`: `None` unless
/// the origin is an interior vertex of exactly four faces.
pub fn dual_quad_corners(mesh: &Mesh, start: HalfEdgeId) -> Option<[HalfEdgeId; 4]> {
    let mut around = [start; 4];
    for c in 1..4 {
        around[c] = counter_clockwise(mesh, around[c - 1])?;
        if around[c] == start {
            return None;
        }
    }
    (counter_clockwise(mesh, around[3])? == start).then_some(around)
}

/// The dual quad of `start`'s origin `p`, with corner 0 at the centre of `start`'s face: its
/// control points (`p` first, then each face's vertices from `p` on, counter-clockwise from
/// `start`'s face, each once) and its signature (the four faces, each as its size and its
/// vertices' places in the list, a place with its high bit set where the side from it is on
/// the boundary). `None` unless `p` is an interior vertex of four faces.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh, VertexId};
/// use subdiv_schemes::dual_patch;
///
/// // The centre of a 5 × 5 grid of quads on a torus: nine control points.
/// let torus = Mesh::build(shapes::quad_torus(5, 5))?;
/// let start = torus.outgoing(VertexId::new(12)).next().unwrap();
/// assert_eq!(dual_patch(&torus, start).unwrap().vertices.len(), 9);
/// # Ok::<(), subdiv_mesh::MeshError>(())
/// ```
pub fn dual_patch(mesh: &Mesh, start: HalfEdgeId) -> Option<Patch> {
    let around = dual_quad_corners(mesh, start)?;
    let size: usize = around.iter().map(|&h| mesh.face_size(mesh.face(h))).sum();
    let mut vertices = vec![mesh.origin(start)];
    let mut signature = Vec::with_capacity(size + 5);
    signature.push(DUAL_SIGNATURE);
    // Places by vertex: a scan for small patches, a map past a few dozen points (a patch at an
    // n-gon has n + 5, and an n-gon has n patches around it).
    let large = size > 64;
    let mut places: HashMap<VertexId, u32> = if large { HashMap::from([(vertices[0], 0)]) } else { HashMap::new() };
    for h in around {
        signature.push(mesh.face_size(mesh.face(h)) as u32);
        let mut k = h;
        loop {
            let v = mesh.origin(k);
            let found = if large { places.get(&v).map(|&p| p as usize) } else { vertices.iter().position(|&x| x == v) };
            let place = found.unwrap_or_else(|| {
                vertices.push(v);
                vertices.len() - 1
            });
            if large {
                places.entry(v).or_insert(place as u32);
            }
            let boundary = if mesh.twin(k).is_none() { DUAL_BOUNDARY_SIDE } else { 0 };
            signature.push(place as u32 | boundary);
            k = mesh.next(k);
            if k == h {
                break;
            }
        }
    }
    Some(Patch { vertices, signature })
}

/// The starts of the dual quads of the four children of the dual quad at `start` on `parent`,
/// on `child` (the parent refined by the dual split): child `c` is the corner point of the
/// `c`-th half-edge around (the split numbers a corner's point and, in the face made from the
/// parent face, its half-edge by the parent half-edge), and its dual quad, with the parent's
/// axes, starts `4 − c` turns on from that face (so the face made from `g_c` is at its corner
/// `c`). `None` unless `start`'s origin has four faces, all interior.
pub fn dual_child_starts(parent: &Mesh, start: HalfEdgeId, child: &Mesh) -> Option<[HalfEdgeId; 4]> {
    let around = dual_quad_corners(parent, start)?;
    let mut starts = [start; 4];
    for (c, h) in around.into_iter().enumerate() {
        let own = HalfEdgeId::new(h.raw());
        debug_assert_eq!(child.origin(own), VertexId::new(h.raw()), "the dual split's numbering");
        starts[c] = turned(child, own, (4 - c) % 4)?;
    }
    Some(starts)
}

/// The start of the dual quad, on `child` (the mesh refined once by the dual split), that
/// covers the corner of the parent's face at half-edge `h`: the corner point's dual quad with
/// corner 0 at the centre of the vertex face of `h`'s origin (two turns from the face made from
/// `h`'s), so that its parameters are the corner's: `(0, 0)` at the vertex, `(1, 0)` at the
/// middle of `h`'s side, `(1, 1)` at the face's centre and `(0, 1)` at the middle of the side
/// before. `None` on a boundary.
pub fn dual_corner_start(child: &Mesh, h: HalfEdgeId) -> Option<HalfEdgeId> {
    turned(child, HalfEdgeId::new(h.raw()), 2)
}

/// The levels of a dual derivation: `meshes[0]` the first refined level, `stencils[l]` the rows
/// of `meshes[l + 1]` over `meshes[l]`.
struct Levels<'a> {
    scheme: &'a Scheme,
    meshes: Vec<Mesh>,
    stencils: Vec<Stencils>,
}

impl Levels<'_> {
    fn refine(&mut self) -> Result<(), SchemeError> {
        let last = self.meshes.last().expect("the first level is refined first");
        let refiner = Refiner::new(last, self.scheme, 1, &RefineOptions::DEFAULT)?;
        self.stencils.push(refiner.levels()[0].clone());
        self.meshes.push(refiner.into_mesh());
        Ok(())
    }
}

/// Whether a dual patch's signature has a side on the boundary.
pub fn dual_signature_has_boundary(signature: &[u32]) -> bool {
    signature.first() == Some(&DUAL_SIGNATURE) && signature.iter().skip(1).any(|&w| w & DUAL_BOUNDARY_SIDE != 0)
}

/// The matrices of the dual split's interior type of `valence`: from the canonical pillow of
/// that valence refined once, where its centre's vertex face is a `valence`-gon, the dual quad
/// of the first face's corner point at the centre, started at that face (shape 0), and every
/// shape its children reach.
pub(super) fn derive(scheme: &Scheme, valence: usize) -> Result<PatchMatrices, SchemeError> {
    let internal = |e: String| SchemeError::Internal(format!("{}: dual patch derivation: {e}", scheme.name));
    let pillow = crate::canonical::pillow(valence, 2, false, SharpFeatures::SMOOTH);
    let base = Mesh::build(pillow).map_err(|e| internal(e.to_string()))?;
    let corner = super::derivation::canonical_start(&base, PatchType::interior(valence));
    let first = Refiner::new(&base, scheme, 1, &RefineOptions::DEFAULT)?.into_mesh();
    let start = dual_corner_start(&first, corner).ok_or_else(|| internal("the centre is open".into()))?;
    close_up(scheme, first, start, PatchType::interior(valence), MAX_LEVELS)?
        .ok_or_else(|| internal(format!("the shapes do not close up within {MAX_LEVELS} levels")))
}

/// The matrices of the dual quad at `start` on `first` (a mesh refined once or more by the
/// dual `scheme`, open), derived from its own neighbourhood as the interior types are from
/// the pillow: the quad (shape 0) and every shape its children
/// reach. The rows of its children read only its four faces' points, and their faces' sides on
/// the boundary follow from its own, so the faces around it (one ring) are all the
/// neighbourhood needs. `None` if the shapes do not close up within a few levels. Each call
/// is a new [`PatchType::Derived`]: callers keep one per signature.
///
/// # Errors
/// As refinement, of the neighbourhood; [`SchemeError::Internal`] if `start`'s origin is not
/// an interior vertex of four faces.
pub fn derive_dual_configuration(
    scheme: &Scheme,
    first: &Mesh,
    start: HalfEdgeId,
) -> Result<Option<PatchMatrices>, SchemeError> {
    let internal = |e: String| SchemeError::Internal(format!("{}: dual configuration: {e}", scheme.name));
    let around = dual_quad_corners(first, start).ok_or_else(|| internal("not a dual quad".into()))?;
    let region = first.region(&around.map(|h| first.face(h)), 1).map_err(|e| internal(e.to_string()))?;
    let inside = region.face_of(first.face(start)).ok_or_else(|| internal("a face outside its region".into()))?;
    let start = region.mesh.face_half_edges(inside).nth(first.corner(start)).expect("the face keeps its corners");
    close_up(scheme, region.mesh, start, PatchType::Derived { id: super::next_derived_id() }, MAX_BOUNDARY_LEVELS)
}

/// The shapes of the dual quad at `start` on `first` and of every dual quad its children
/// reach, refining `first` as far as they need, with influence sets and (the regular
/// biquadratic shape's) parameters. `None` if new shapes still appear after `max_levels`.
fn close_up(
    scheme: &Scheme,
    first: Mesh,
    start: HalfEdgeId,
    patch_type: PatchType,
    max_levels: usize,
) -> Result<Option<PatchMatrices>, SchemeError> {
    let internal = |e: String| SchemeError::Internal(format!("{}: dual patch derivation: {e}", scheme.name));
    let mut levels = Levels { scheme, meshes: vec![first], stencils: Vec::new() };
    let mut queue = ShapeQueue::default();
    let patch =
        dual_patch(&levels.meshes[0], start).ok_or_else(|| internal("the corner point is not a dual quad".into()))?;
    queue.register(patch, 0, start);
    while let Some((shape, level, start, vertices)) = queue.next() {
        if level == max_levels {
            return Ok(None);
        }
        if levels.meshes.len() == level + 1 {
            levels.refine()?;
        }
        let (parent, child, rows) = (&levels.meshes[level], &levels.meshes[level + 1], &levels.stencils[level]);
        let starts = dual_child_starts(parent, start, child).ok_or_else(|| internal("a child is open".into()))?;
        let column: HashMap<usize, usize> = vertices.iter().enumerate().map(|(c, v)| (v.index(), c)).collect();
        let mut children = Vec::with_capacity(4);
        for (c, &child_start) in starts.iter().enumerate() {
            let patch = dual_patch(child, child_start).ok_or_else(|| internal("a child is not a dual quad".into()))?;
            let mut entries = vec![0.0; patch.vertices.len() * vertices.len()];
            for (r, v) in patch.vertices.iter().enumerate() {
                for (p, w) in rows.row(v.index()) {
                    match column.get(&p) {
                        Some(&k) => entries[r * vertices.len() + k] += w,
                        None if w.abs() > ZERO_WEIGHT => {
                            return Err(internal("a child's row reads a point outside its parent".into()));
                        }
                        None => {}
                    }
                }
            }
            let domain = ChildDomain::of_face(4)[c];
            let rows = patch.vertices.len();
            let child_shape = queue.register(patch, level + 1, child_start);
            children.push(SubPatch::from_entries(child_shape, domain, rows, entries));
        }
        queue.shapes[shape].children = children;
    }
    let mut shapes = queue.shapes;
    // The surface over a dual quad is the limit of its centre's descendants.
    let influence = influence_sets(&shapes, 1);
    for (shape, influence) in shapes.iter_mut().zip(influence) {
        shape.influence = influence;
    }
    // Only a shape without an extraordinary face or a boundary side reproduces linear
    // functions of parameters (at an n-gon the solve fails, after a least-squares system of
    // 4n rows: most of a large n-gon's preparation; across a boundary the parameterization
    // shrinks by ¾ a level, not ½).
    for s in 0..shapes.len() {
        let signature = &shapes[s].signature;
        let regular = signature.len() == 1 + 4 * 5 && shapes[s].size == 9 && !dual_signature_has_boundary(signature);
        shapes[s].parameters = if regular { parameter_coordinates(&shapes, s) } else { None };
    }
    Ok(Some(PatchMatrices::from_shapes(scheme, patch_type, 1, 4, shapes)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Builtin;

    #[test]
    fn doo_sabin_types_close_up_with_the_regular_biquadratic_shape() {
        let ds = Builtin::DooSabin.scheme();
        for n in [3, 4, 5, 6, 8] {
            let m = PatchMatrices::compute(ds, PatchType::interior(n), subdiv_mesh::BoundaryInterpolation::EdgeOnly)
                .unwrap();
            // n + 5 control points: the n-gon's, two more per edge face, three more of the
            // opposite quad.
            assert_eq!(m.shapes[0].size, n + 5, "valence {n}");
            assert_eq!(m.shapes[0].children[0].shape, 0, "valence {n}: child 0 keeps the n-gon");
            let regular = m.shapes.iter().position(|s| s.size == 9).expect("the regular shape");
            assert!(m.shapes[regular].children.iter().all(|c| c.shape == regular));
            assert_eq!(m.shapes.len(), if n == 4 { 1 } else { 2 }, "valence {n}");
            // The regular shape reproduces its parameters (the biquadratic B-spline's, centre
            // at (1/2, 1/2)); the extraordinary one does not.
            let [u, v] = m.shapes[regular].parameters.clone().expect("regular parameters");
            assert!((u[0] - 0.5).abs() < 1e-12 && (v[0] - 0.5).abs() < 1e-12, "{u:?} {v:?}");
            assert_eq!(m.shapes[0].parameters.is_none(), n != 4);
            // Every row sums to 1.
            for shape in &m.shapes {
                for child in &shape.children {
                    for r in 0..child.rows() {
                        assert!((child.row(r).map(|e| e.1).sum::<f64>() - 1.0).abs() < 1e-13);
                    }
                }
            }
        }
    }

    /// On an open grid refined once, the dual quads at interior vertices next to the boundary
    /// derive from their own neighbourhoods: their signatures mark boundary sides, their shapes
    /// close up, every row sums to 1, and the regular boundary shape (quads, two of its faces
    /// on the boundary) keeps itself in exactly two children, the two along the boundary.
    #[test]
    fn boundary_configurations_close_up_along_the_boundary() {
        for builtin in [Builtin::DooSabin, Builtin::Midedge] {
            let scheme = builtin.scheme().dual_form().unwrap();
            let grid = Mesh::build(subdiv_mesh::shapes::quad_grid(6, 5)).unwrap();
            let first = Refiner::new(&grid, &scheme, 1, &RefineOptions::DEFAULT).unwrap().into_mesh();
            let mut derived = 0;
            for v in first.vertices() {
                let Some(start) = first.outgoing(v).next() else { continue };
                let Some(patch) = dual_patch(&first, start) else { continue };
                if !dual_signature_has_boundary(&patch.signature) {
                    continue;
                }
                let m = derive_dual_configuration(&scheme, &first, start).unwrap().expect("the shapes close up");
                derived += 1;
                assert_eq!(m.find(&patch.signature), Some(0));
                for shape in &m.shapes {
                    for child in &shape.children {
                        for r in 0..child.rows() {
                            assert!((child.row(r).map(|e| e.1).sum::<f64>() - 1.0).abs() < 1e-13, "{builtin:?}");
                        }
                    }
                }
                let line = m.shapes.iter().enumerate().find(|(s, shape)| {
                    dual_signature_has_boundary(&shape.signature)
                        && shape.children.iter().filter(|c| c.shape == *s).count() == 2
                });
                assert!(line.is_some(), "{builtin:?}: no boundary shape that keeps itself along the boundary");
            }
            // The vertices of level 1 beside the boundary faces: around each boundary face's
            // interior corners.
            assert!(derived > 20, "{builtin:?}: {derived} boundary configurations");
        }
    }
}
