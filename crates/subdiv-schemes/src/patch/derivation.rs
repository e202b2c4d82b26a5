//! The shape closure: a patch type's shapes and sub-patch matrices, derived by refining a mesh
//! around a starting patch (a canonical one, or a face's own neighbourhood for a derived
//! configuration) level by level until no new shape appears.

use std::collections::{HashMap, VecDeque};

use faer::Mat;
use faer::linalg::solvers::SolveLstsq;
use subdiv_mesh::{FaceId, HalfEdgeId, Mesh, Patch, VertexId};

use faer::c64;

use super::{ChildDomain, Frequency, PatchMatrices, PatchShape, PatchType, SubPatch, ZERO_WEIGHT, sub_patch_starts};
use crate::{LocalRefinement, RefineOptions, Scheme, SchemeError, Split};

/// A shape whose children are still to be found: where its patch lies.
struct Pending {
    shape: usize,
    level: usize,
    start: HalfEdgeId,
    vertices: Vec<VertexId>,
}

/// The canonical mesh refined level by level, and the shapes found so far.
///
/// A level refines only the faces of the patches still waiting for their children and the
/// rings around them that those children's patches and rules reach (as `PatchLevels` does for
/// real meshes), so a level costs a few dozen faces instead of four times the last: the whole
/// canonical mesh at the third level was most of a first call's time (the built-in model's
/// first tessellation spent 13 of its 17 ms deriving two valences' matrices).
pub(super) struct Derivation<'a> {
    scheme: &'a Scheme,
    radius: usize,
    /// Levels after which the shapes must have closed up.
    max_levels: usize,
    /// The options each level is refined with.
    options: RefineOptions,
    /// Level 0: the canonical mesh.
    base: Mesh,
    /// Level `l + 1`: the part of level `l` refined, with its rows over level `l`.
    refined: Vec<LocalRefinement>,
    shapes: Vec<PatchShape>,
    by_signature: HashMap<Vec<u32>, usize>,
}

impl<'a> Derivation<'a> {
    pub(super) fn new(
        scheme: &'a Scheme,
        mesh: Mesh,
        radius: usize,
        max_levels: usize,
        options: RefineOptions,
    ) -> Self {
        Self {
            scheme,
            radius,
            max_levels,
            options,
            base: mesh,
            refined: Vec::new(),
            shapes: Vec::new(),
            by_signature: HashMap::new(),
        }
    }

    /// The matrices from the patch at `start` (shape 0), or `None` if the radius is too small.
    pub(super) fn run(
        mut self,
        start: HalfEdgeId,
        patch_type: PatchType,
    ) -> Result<Option<PatchMatrices>, SchemeError> {
        let mut pending = VecDeque::new();
        self.register(self.base.patch(start, self.radius), 0, start, &mut pending);
        while let Some(Pending { shape, level, start, vertices }) = pending.pop_front() {
            if level == self.max_levels {
                return Err(SchemeError::Internal(format!(
                    "{}: the sub-patch shapes do not close up within {} levels",
                    self.scheme, self.max_levels
                )));
            }
            if self.refined.len() == level {
                // The first patch of its level: every patch of the level is queued by now
                // (breadth first), and their faces are what the next level refines.
                let mesh = self.mesh(level);
                let mut faces: Vec<FaceId> = std::iter::once(start)
                    .chain(pending.iter().filter(|p| p.level == level).map(|p| p.start))
                    .map(|h| mesh.face(h))
                    .collect();
                faces.sort_unstable();
                faces.dedup();
                self.refine_next(&faces)?;
            }
            let Some(children) = self.children(level, start, &vertices, &mut pending)? else {
                return Ok(None);
            };
            self.shapes[shape].children = children;
        }
        let face_size = if self.scheme.split() == Split::Triangle { 3 } else { 4 };
        let influence = influence_sets(&self.shapes, face_size);
        for (shape, influence) in self.shapes.iter_mut().zip(influence) {
            shape.influence = influence;
        }
        // A derived configuration's shapes before its features are spent reach every shape
        // below them: their systems are large, and nothing reads their parameters (a cycle's
        // shape's, for derivatives at its fixed point, and a bicubic shape's, are those of
        // stationary shapes). Only the shapes some cycle reaches get them there.
        let stationary = match patch_type {
            PatchType::Derived { .. } => reached_from_cycles(&self.shapes),
            _ => vec![true; self.shapes.len()],
        };
        let rotation = super::has_rotation(self.scheme, patch_type)
            .then(|| super::ring::patch_rotation(&self.base, start, self.radius))
            .flatten();
        let mut matrices = PatchMatrices {
            scheme: self.scheme.name.clone(),
            patch_type,
            radius: self.radius,
            face_size,
            shapes: self.shapes,
            by_signature: self.by_signature,
            identity: self.scheme.identity(),
            rotation,
        };
        for (s, stationary) in stationary.into_iter().enumerate() {
            if !stationary {
                continue;
            }
            if let Some(found) = ring_parameters(&matrices, s) {
                matrices.shapes[s].parameters = found;
                continue;
            }
            // A derived configuration's stationary shape that an interior type has (equal
            // signatures, equal matrices) takes its parameters from there, solved once.
            let canonical = match patch_type {
                PatchType::Derived { .. } => {
                    PatchMatrices::interior_shape(self.scheme, &matrices.shapes[s].signature, matrices.shapes[s].size)
                }
                _ => None,
            };
            matrices.shapes[s].parameters = match canonical {
                Some((m, shape)) => m.shapes[shape].parameters.clone(),
                None => parameter_coordinates(&matrices.shapes, s),
            };
        }
        Ok(Some(matrices))
    }

    /// Refines the last level's `faces` and the rings around them that their children's
    /// patches (radius rings of the next level) and those points' rules (one ring more) reach.
    /// Schemes without crease rules refine the whole level (a region's boundary needs rules).
    fn refine_next(&mut self, faces: &[FaceId]) -> Result<(), SchemeError> {
        let current = self.mesh(self.refined.len());
        let next = LocalRefinement::new(self.scheme, current, faces, self.radius + 1, &self.options)?;
        self.refined.push(next);
        Ok(())
    }

    /// The mesh of `level`.
    fn mesh(&self, level: usize) -> &Mesh {
        if level == 0 { &self.base } else { &self.refined[level - 1].mesh }
    }

    /// The shape of `patch` (starting at `start` on `level`): a known one, or a new one queued
    /// in `pending` for its own children.
    fn register(&mut self, patch: Patch, level: usize, start: HalfEdgeId, pending: &mut VecDeque<Pending>) -> usize {
        if let Some(&s) = self.by_signature.get(&patch.signature) {
            return s;
        }
        let mirrored = self.mesh(level).mirrored_patch(start, self.radius);
        let mirror = (mirrored.signature == patch.signature).then(|| {
            let place: HashMap<VertexId, u32> =
                patch.vertices.iter().enumerate().map(|(k, &v)| (v, k as u32)).collect();
            mirrored.vertices.iter().map(|v| place[v]).collect()
        });
        let s = self.shapes.len();
        self.by_signature.insert(patch.signature.clone(), s);
        self.shapes.push(PatchShape {
            size: patch.vertices.len(),
            signature: patch.signature,
            children: Vec::new(),
            influence: Vec::new(),
            parameters: None,
            mirror,
        });
        pending.push_back(Pending { shape: s, level, start, vertices: patch.vertices });
        s
    }

    /// The sub-patches of the patch with vertices `parent` starting at `start` on `level`,
    /// registering new shapes in `pending`; `None` if a child's row leaves the parent patch.
    fn children(
        &mut self,
        level: usize,
        start: HalfEdgeId,
        parent: &[VertexId],
        pending: &mut VecDeque<Pending>,
    ) -> Result<Option<Vec<SubPatch>>, SchemeError> {
        let (parent_mesh, next) = (self.mesh(level), &self.refined[level]);
        let child_mesh = &next.mesh;
        let column: HashMap<usize, usize> = parent.iter().enumerate().map(|(c, v)| (v.index(), c)).collect();
        // The split's parent (the refined region), where the face has the same corners.
        let missing = || SchemeError::Internal("a patch's face is outside the refined region".to_string());
        let (split_parent, face) = next.split_parent(parent_mesh, parent_mesh.face(start)).ok_or_else(missing)?;
        let split_start = split_parent.face_half_edges(face).nth(parent_mesh.corner(start)).ok_or_else(missing)?;
        let starts = sub_patch_starts(self.scheme, split_parent, split_start, child_mesh)?;
        let domains = ChildDomain::of_face(parent_mesh.face_size(parent_mesh.face(start)));
        let stencils = &next.stencils;
        let columns = parent.len();
        // The rows first (they borrow the meshes), then the shapes.
        let mut found = Vec::new();
        for (&domain, &child_start) in domains.iter().zip(&starts) {
            let patch = child_mesh.patch(child_start, self.radius);
            let mut rows = Vec::with_capacity(patch.vertices.len());
            for v in &patch.vertices {
                let mut row: Vec<(usize, f64)> = Vec::new();
                for (p, w) in stencils.row(v.index()) {
                    match column.get(&p) {
                        Some(&c) => row.push((c, w)),
                        None if w.abs() > ZERO_WEIGHT => return Ok(None),
                        None => {}
                    }
                }
                // A parent point once per row (as the dense matrix's sum of its weights).
                row.sort_by_key(|e| e.0);
                row.dedup_by(|later, first| {
                    let same = later.0 == first.0;
                    if same {
                        first.1 += later.1;
                    }
                    same
                });
                // `0.0 + w` as the dense sum began: a lone `-0.0` is no entry.
                row.iter_mut().for_each(|e| e.1 += 0.0);
                rows.push(row);
            }
            found.push((domain, child_start, patch, rows));
        }
        let mut children = Vec::new();
        for (domain, child_start, patch, rows) in found {
            let shape = self.register(patch, level + 1, child_start, pending);
            children.push(SubPatch::from_rows(shape, domain, columns, rows));
        }
        Ok(Some(children))
    }
}

/// The shapes found so far, by signature, and those whose children are still to be found,
/// breadth first: the closure of the dual and ternary derivations (their patches are found by
/// dependency, without mirrors).
#[derive(Default)]
pub(super) struct ShapeQueue {
    pub(super) shapes: Vec<PatchShape>,
    by_signature: HashMap<Vec<u32>, usize>,
    pending: VecDeque<(usize, usize, HalfEdgeId, Vec<VertexId>)>,
}

impl ShapeQueue {
    /// The shape of `patch` (on `level`, starting at `start`): a known one, or a new one queued
    /// for its children.
    pub(super) fn register(&mut self, patch: Patch, level: usize, start: HalfEdgeId) -> usize {
        if let Some(&s) = self.by_signature.get(&patch.signature) {
            return s;
        }
        let s = self.shapes.len();
        self.by_signature.insert(patch.signature.clone(), s);
        self.shapes.push(PatchShape {
            size: patch.vertices.len(),
            signature: patch.signature,
            children: Vec::new(),
            influence: Vec::new(),
            parameters: None,
            mirror: None,
        });
        self.pending.push_back((s, level, start, patch.vertices));
        s
    }

    /// The next shape whose children are to be found: its index, level, start and vertices.
    pub(super) fn next(&mut self) -> Option<(usize, usize, HalfEdgeId, Vec<VertexId>)> {
        self.pending.pop_front()
    }
}

/// The canonical patch's start: its face at the centre, vertex 0, in sector `index` (see
/// `canonical`).
pub(super) fn canonical_start(mesh: &Mesh, patch_type: PatchType) -> HalfEdgeId {
    let index = match patch_type {
        PatchType::Boundary { index, .. } => index,
        PatchType::Interior { .. } | PatchType::Derived { .. } => 0,
    };
    mesh.face_ids()
        .map(|f| mesh.face_half_edges(f).next().expect("faces have corners"))
        .filter(|&h| mesh.origin(h).index() == 0)
        .nth(index)
        .expect("the canonical mesh has a face at its centre in every sector")
}

/// Per shape, whether a shape that reaches itself through its children (a cycle) reaches it.
fn reached_from_cycles(shapes: &[PatchShape]) -> Vec<bool> {
    let reach = |from: usize| {
        let mut seen = vec![false; shapes.len()];
        let mut stack: Vec<usize> = shapes[from].children.iter().map(|c| c.shape).collect();
        while let Some(s) = stack.pop() {
            if !std::mem::replace(&mut seen[s], true) {
                stack.extend(shapes[s].children.iter().map(|c| c.shape));
            }
        }
        seen
    };
    let mut reached = vec![false; shapes.len()];
    for s in 0..shapes.len() {
        let from = reach(s);
        if from[s] {
            reached.iter_mut().zip(from).for_each(|(r, f)| *r |= f);
        }
    }
    reached
}

/// Each shape's [`PatchShape::influence`]: the least fixed point of "the first `seeds` control
/// points influence it (a primal face's corners, a dual quad's centre: the points whose
/// descendants converge to the patch's surface), and so does every point that a child's matrix
/// reads (with a weight above [`ZERO_WEIGHT`]) into a point that influences the child".
pub(super) fn influence_sets(shapes: &[PatchShape], seeds: usize) -> Vec<Vec<u32>> {
    let mut inside: Vec<Vec<bool>> = shapes.iter().map(|s| (0..s.size).map(|k| k < seeds).collect()).collect();
    let mut changed = true;
    while changed {
        changed = false;
        for (s, shape) in shapes.iter().enumerate() {
            for child in &shape.children {
                for r in 0..child.rows() {
                    if !inside[child.shape][r] {
                        continue;
                    }
                    for (c, w) in child.row(r) {
                        if w.abs() > ZERO_WEIGHT && !inside[s][c] {
                            inside[s][c] = true;
                            changed = true;
                        }
                    }
                }
            }
        }
    }
    inside.iter().map(|set| (0..set.len() as u32).filter(|&k| set[k as usize]).collect()).collect()
}

/// [`parameter_coordinates`] of a shape with a ring spectrum ([`PatchMatrices::ring_spectrum`])
/// in `O(N)` at valence `N` (the dense system's SVD was 20 % of a tessellation at valence 1000);
/// `None` where the spectrum leaves it to the dense system.
///
/// Parameters `U` satisfy `A U = U / s` on the influencing points under the child that keeps the
/// shape and its corner 0 (offset 0, scale `s`), so they lie in the eigenspace of `1/s`, and are
/// not zero there (the face's corners are among the points): without that eigenvalue there are
/// none. With a two-dimensional eigenspace (Catmull-Clark's frequency `N/4` at a valence that 4
/// divides, whose vectors turn a quarter turn from face to face as the parameters do) the face's
/// corners 1 and `face_size − 1` single out `u` and `v` in it, the children's equations carry
/// them to every shape below (`U_child = ±(s A U − o)`), and they are the parameters if every
/// equation holds (to the dense system's 1e-9) and the system has no other solution: no
/// combination of the eigenspace's vectors, carried down without the offsets, meets every
/// equation.
fn ring_parameters(matrices: &PatchMatrices, shape: usize) -> Option<Option<[Vec<f64>; 2]>> {
    let ring = matrices.ring_spectrum(shape)?;
    let scale = f64::from(matrices.scale());
    let half = c64::new(1.0 / scale, 0.0);
    let mut holding = ring.eigenvalues().filter(|(_, z)| (z - half).norm() < super::ring::CLUSTER).peekable();
    if holding.peek().is_none() {
        return Some(None);
    }
    let mut omegas = Vec::new();
    for (f, _) in holding {
        match f {
            Frequency::Ring(w) => omegas.push(w),
            Frequency::Rest => return None,
        }
    }
    omegas.sort_unstable();
    omegas.dedup();
    let basis = ring.real_eigenspace(&omegas, &[half], false)?;
    let shapes = &matrices.shapes;
    let influence = &shapes[shape].influence;
    // Corners 1 and `face_size − 1` among the influencing points.
    let at = |corner: u32| influence.iter().position(|&k| k == corner);
    let (Some(c1), Some(c2), [e1, e2]) = (at(1), at(matrices.face_size as u32 - 1), basis.as_slice()) else {
        return None;
    };
    let det = e1[c1] * e2[c2] - e2[c1] * e1[c2];
    if det.abs() < 1e-9 {
        return None;
    }
    // u = 1, 0 and v = 0, 1 at the two corners.
    let combine = |a: f64, b: f64| -> Vec<f64> {
        let (x, y) = ((a * e2[c2] - b * e2[c1]) / det, (b * e1[c1] - a * e1[c2]) / det);
        e1.iter().zip(e2).map(|(p, q)| x * p + y * q).collect()
    };
    let (u, residual) = carried(shapes, shape, &combine(1.0, 0.0), Some(0));
    let (v, residual_v) = carried(shapes, shape, &combine(0.0, 1.0), Some(1));
    if residual.max(residual_v) > 1e-9 {
        return Some(None);
    }
    // Unique: the homogeneous system's solutions on the eigenspace, `a·e₁ + b·e₂` with
    // `a r₁ + b r₂ = 0` for the residuals of each carried down without offsets.
    let (r1, r2) = (homogeneous_residuals(shapes, shape, e1), homogeneous_residuals(shapes, shape, e2));
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let (g11, g22, g12) = (dot(&r1, &r1), dot(&r2, &r2), dot(&r1, &r2));
    // The smaller eigenvalue of the residuals' Gram matrix: their smaller singular value squared.
    let smallest = (g11 + g22) / 2.0 - (((g11 - g22) / 2.0).powi(2) + g12 * g12).sqrt();
    if smallest < 1e-18 {
        return Some(None);
    }
    let widen = |values: &[Vec<f64>]| -> Vec<f64> {
        let mut out = vec![0.0; shapes[shape].size];
        influence.iter().zip(&values[shape]).for_each(|(&k, &x)| out[k as usize] = x);
        out
    };
    Some(Some([widen(&u), widen(&v)]))
}

/// The values of one parameter (`axis` 0 for `u`, 1 for `v`; `None`: without the offsets) on the
/// influencing points of every shape reachable from `shape`, carried down from its values
/// `start` by the children's equations `U_child = ±(s A U − o)`, breadth first; and the largest
/// difference from an equation whose child has values already.
fn carried(shapes: &[PatchShape], shape: usize, start: &[f64], axis: Option<usize>) -> (Vec<Vec<f64>>, f64) {
    let mut values: Vec<Vec<f64>> = vec![Vec::new(); shapes.len()];
    let mut known = vec![false; shapes.len()];
    values[shape] = start.to_vec();
    known[shape] = true;
    let mut queue = VecDeque::from([shape]);
    let mut residual = 0.0f64;
    let mut place = vec![usize::MAX; shapes.iter().map(|s| s.size).max().unwrap_or(0)];
    while let Some(s) = queue.pop_front() {
        shapes[s].influence.iter().enumerate().for_each(|(i, &k)| place[k as usize] = i);
        let mut children = Vec::new();
        for child in &shapes[s].children {
            let sign = if child.domain.flipped { -1.0 } else { 1.0 };
            let scale = f64::from(child.domain.scale);
            let offset = axis.map_or(0.0, |a| f64::from(child.domain.offset[a]));
            let image: Vec<f64> = shapes[child.shape]
                .influence
                .iter()
                .map(|&r| {
                    let au: f64 = child
                        .row(r as usize)
                        .filter(|&(c, _)| place[c] != usize::MAX)
                        .map(|(c, w)| w * values[s][place[c]])
                        .sum();
                    sign * (scale * au - offset)
                })
                .collect();
            children.push((child.shape, image));
        }
        shapes[s].influence.iter().for_each(|&k| place[k as usize] = usize::MAX);
        for (c, image) in children {
            if known[c] {
                residual = values[c].iter().zip(&image).map(|(a, b)| (a - b).abs()).fold(residual, f64::max);
            } else {
                values[c] = image;
                known[c] = true;
                queue.push_back(c);
            }
        }
    }
    (values, residual)
}

/// The differences of every equation met twice when `start` is carried down without offsets
/// (see [`carried`]), as one vector.
fn homogeneous_residuals(shapes: &[PatchShape], shape: usize, start: &[f64]) -> Vec<f64> {
    // Carried once, then each equation compared with what it gives.
    let (values, _) = carried(shapes, shape, start, None);
    let mut out = Vec::new();
    for (s, parent) in shapes.iter().enumerate().filter(|(s, _)| !values[*s].is_empty() || *s == shape) {
        let place: HashMap<u32, usize> = parent.influence.iter().enumerate().map(|(i, &k)| (k, i)).collect();
        for child in &parent.children {
            let sign = if child.domain.flipped { -1.0 } else { 1.0 };
            let scale = f64::from(child.domain.scale);
            for (i, &r) in shapes[child.shape].influence.iter().enumerate() {
                let au: f64 =
                    child.row(r as usize).filter_map(|(c, w)| Some(w * values[s][*place.get(&(c as u32))?])).sum();
                out.push(sign * scale * au - values[child.shape][i]);
            }
        }
    }
    out
}

/// The parameters `(u, v)` of the control points of `shape` in its face's frame, if the
/// matrices reproduce linear functions of the parameters from `shape` on: the solution of
/// `A_c · U_s = (±U_child + o_c) / 2` over every shape reachable from `shape` and each child,
/// on the points that influence the faces. The others have no weight in any stencil, so their
/// parameters are free (a point across an infinitely sharp edge, or beyond a bilinear face's
/// corners, would make the whole system singular): they are given 0. The rows of influencing
/// points read no other points, so the restricted system is closed.
/// `None` next to an irregular vertex that is part of the shape's own domain, or where the
/// influencing points' parameters are not unique.
pub(super) fn parameter_coordinates(shapes: &[PatchShape], shape: usize) -> Option<[Vec<f64>; 2]> {
    // The shapes reachable from `shape`, and where each one's unknowns start.
    let mut reach = vec![shape];
    let mut i = 0;
    while i < reach.len() {
        for child in &shapes[reach[i]].children {
            if !reach.contains(&child.shape) {
                reach.push(child.shape);
            }
        }
        i += 1;
    }
    // The unknown of each influencing control point of each reachable shape.
    let mut unknown: Vec<Vec<Option<usize>>> = shapes.iter().map(|s| vec![None; s.size]).collect();
    let mut unknowns = 0;
    for &s in &reach {
        for &k in &shapes[s].influence {
            unknown[s][k as usize] = Some(unknowns);
            unknowns += 1;
        }
    }
    let equations: usize =
        reach.iter().map(|&s| shapes[s].children.iter().map(|c| shapes[c.shape].influence.len()).sum::<usize>()).sum();
    let mut a = Mat::<f64>::zeros(equations, unknowns);
    let mut b = Mat::<f64>::zeros(equations, 2);
    let mut row = 0;
    for &s in &reach {
        for child in &shapes[s].children {
            let sign = if child.domain.flipped { -1.0 } else { 1.0 };
            let scale = f64::from(child.domain.scale);
            for &r in &shapes[child.shape].influence {
                let r = r as usize;
                // An influencing point's row reads influencing points only (and `ZERO_WEIGHT`s).
                for (c, w) in child.row(r) {
                    if let Some(u) = unknown[s][c] {
                        a[(row, u)] += w;
                    }
                }
                a[(row, unknown[child.shape][r].expect("an influencing point"))] -= sign / scale;
                b[(row, 0)] = f64::from(child.domain.offset[0]) / scale;
                b[(row, 1)] = f64::from(child.domain.offset[1]) / scale;
                row += 1;
            }
        }
    }
    let x = a.qr().solve_lstsq(&b);
    if (&a * &x - &b).norm_max() > 1e-9 || a.singular_values().ok()?.iter().any(|&s| s < 1e-9) {
        return None;
    }
    let value = |k: usize, axis: usize| unknown[shape][k].map_or(0.0, |i| x[(i, axis)]);
    let size = shapes[shape].size;
    Some([(0..size).map(|k| value(k, 0)).collect(), (0..size).map(|k| value(k, 1)).collect()])
}

#[cfg(test)]
mod tests {
    use subdiv_mesh::BoundaryInterpolation;

    use super::*;
    use crate::{Builtin, Split};

    /// Where the ring's frequency blocks decide a smooth vertex's parameters, they are the dense
    /// system's: none, or the same to 1e-12 (Catmull-Clark at the valences 4 divides; Kobbelt's
    /// systems of 300 points round to 1.4e-13), for the
    /// binary splits' built-ins at valences 3 to 40.
    #[test]
    fn the_ring_parameters_are_the_dense_systems() {
        let mut found = 0;
        for builtin in Builtin::ALL {
            let scheme = builtin.scheme();
            if !matches!(scheme.split(), Split::Quad | Split::Triangle) {
                continue;
            }
            let top = if matches!(builtin, Builtin::CatmullClark | Builtin::Loop) { 40 } else { 12 };
            for valence in (3..=top).filter(|&v| v != scheme.regular_valence()) {
                let Ok(m) =
                    PatchMatrices::compute(scheme, PatchType::interior(valence), BoundaryInterpolation::EdgeOnly)
                else {
                    continue;
                };
                let Some(ring) = ring_parameters(&m, 0) else { continue };
                let dense = parameter_coordinates(&m.shapes, 0);
                let what = format!("{builtin} at valence {valence}");
                match (ring, dense) {
                    (Some([u, v]), Some([p, q])) => {
                        found += 1;
                        let worst = u.iter().chain(&v).zip(p.iter().chain(&q)).map(|(x, y)| (x - y).abs());
                        let worst = worst.fold(0.0, f64::max);
                        assert!(worst <= 1e-12, "{what}: {worst:e}");
                    }
                    (None, None) => {}
                    (a, b) => panic!("{what}: the blocks say {:?}, the system {:?}", a.is_some(), b.is_some()),
                }
                assert_eq!(m.shapes[0].parameters.is_some(), parameter_coordinates(&m.shapes, 0).is_some(), "{what}");
            }
        }
        // Catmull-Clark at 8, 12, …, 40.
        assert!(found >= 9, "{found} valences with parameters");
    }
}
