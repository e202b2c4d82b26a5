//! Refined values without stencil rows, as `Far::PrimvarRefiner::Interpolate` computes them:
//! the scheme's masks applied to the parent's values directly, face points first (the edge and
//! vertex rules of the averaging quad schemes reuse them), then edge points, then vertex points.
//!
//! The direct path covers the averaging quad rules (Catmull-Clark, bilinear, scheme files of
//! that shape) and the triangle rules without wings or extraordinary edge masks (Loop). The
//! other primal rules (Kobbelt's four-point, the Butterfly) keep the stencil path
//! ([`supports`] says which). Vertices where a crease, corner or fading semi-sharp feature
//! changes the rule take the stencil row of [`vertex_row`](super::vertex_row), built over the
//! parent's vertices and the symbolic face points and applied at once: they are few.

use subdiv_mesh::par::{self, CHUNK};
use subdiv_mesh::{EdgeId, FaceId, HalfEdgeId, Mesh, VertexId};

use super::{EdgeRule, FacePoints, Kind, Masks, edge_rule, sharpness, vertex_row};
use crate::crease;
use crate::refine::Options;
use crate::stencil::Row;

/// A per-vertex value that refinement interpolates: positions, colours, any fixed number of
/// `f32` or `f64` components (`Far`'s `AddWithWeight`).
pub(crate) trait Primvar: Copy + Send + Sync {
    /// The value with every component 0.
    const ZERO: Self;
    /// `self += weight · other`.
    fn add_scaled(&mut self, other: Self, weight: f64);
}

impl Primvar for f64 {
    const ZERO: Self = 0.0;
    #[inline]
    fn add_scaled(&mut self, other: Self, weight: f64) {
        *self += weight * other;
    }
}

impl Primvar for f32 {
    const ZERO: Self = 0.0;
    #[inline]
    fn add_scaled(&mut self, other: Self, weight: f64) {
        *self += weight as f32 * other;
    }
}

impl Primvar for glam::DVec3 {
    const ZERO: Self = glam::DVec3::ZERO;
    #[inline]
    fn add_scaled(&mut self, other: Self, weight: f64) {
        *self += weight * other;
    }
}

impl Primvar for glam::Vec3 {
    const ZERO: Self = glam::Vec3::ZERO;
    #[inline]
    fn add_scaled(&mut self, other: Self, weight: f64) {
        *self += weight as f32 * other;
    }
}

impl<T: Primvar, const N: usize> Primvar for [T; N] {
    const ZERO: Self = [T::ZERO; N];
    #[inline]
    fn add_scaled(&mut self, other: Self, weight: f64) {
        for (a, b) in self.iter_mut().zip(other) {
            a.add_scaled(b, weight);
        }
    }
}

/// Whether [`refine`] takes `masks` (the others go through stencil rows).
pub(super) fn supports(masks: &Masks) -> bool {
    match &masks.kind {
        Kind::Quad { .. } => true,
        Kind::FourPoint { .. } => false,
        Kind::Triangle { wing, extraordinary, .. } => {
            *wing == 0.0 && extraordinary.is_none() && masks.vertex.iter().all(|&(_, _, face)| face == 0.0)
        }
    }
}

/// The child level's values of `parent` (one per parent vertex) in the child numbering, into
/// `out` (resized). `masks` must be [`supports`]ed; `sharp`: whether `mesh` has any sharpness.
pub(super) fn refine<T: Primvar>(
    mesh: &Mesh,
    masks: &Masks,
    options: Options,
    sharp: bool,
    parent: &[T],
    out: &mut Vec<T>,
) {
    let nv = mesh.vertex_count();
    let face_points = if masks.splits_into_quads() { mesh.face_count() } else { 0 };
    let parallel = options.parallelism.forks_for(mesh.edge_count());
    out.clear();
    // Zeroed on the threads too: the first touch of a level's pages is a large part of its cost.
    par::extend_range(parallel, out, 0..nv + face_points + mesh.edge_count(), |_| T::ZERO);
    let (vertices, rest) = out.split_at_mut(nv);
    let (faces, edges) = rest.split_at_mut(face_points);
    if let Kind::Quad { corners, .. } = &masks.kind {
        par::for_each_chunk(parallel, faces, CHUNK, |k, chunk| {
            for (i, slot) in chunk.iter_mut().enumerate() {
                let face = mesh.face_vertices(FaceId::new((k * CHUNK + i) as u32));
                let mut sum = T::ZERO;
                for (v, &w) in face.iter().zip(&corners[face.len()]) {
                    sum.add_scaled(parent[v.index()], w);
                }
                *slot = sum;
            }
        });
    }
    let faces: &[T] = faces;
    par::for_each_chunk(parallel, edges, CHUNK, |k, chunk| {
        for (i, slot) in chunk.iter_mut().enumerate() {
            *slot = edge_point(mesh, masks, options, parent, faces, EdgeId::new((k * CHUNK + i) as u32));
        }
    });
    let symbolic = FacePoints::Symbolic(nv as u32);
    // Without sharpness no vertex needs its edges' sharpness looked up.
    let creases = masks.crease.is_some() && sharp;
    par::for_each_chunk(parallel, vertices, CHUNK, |k, chunk| {
        for (i, slot) in chunk.iter_mut().enumerate() {
            let v = VertexId::new((k * CHUNK + i) as u32);
            *slot = match smooth_vertex_point(mesh, masks, creases, parent, faces, v) {
                Some(value) => value,
                None => {
                    let row = vertex_row(mesh, masks, symbolic, options.crease_method, v);
                    apply(&row, |i| if i < nv { parent[i] } else { faces[i - nv] })
                }
            };
        }
    });
}

fn apply<T: Primvar>(row: &Row, value: impl Fn(usize) -> T) -> T {
    let mut sum = T::ZERO;
    for &(i, w) in row.entries() {
        sum.add_scaled(value(i as usize), w);
    }
    sum
}

fn midpoint<T: Primvar>(a: T, b: T) -> T {
    let mut sum = T::ZERO;
    sum.add_scaled(a, 0.5);
    sum.add_scaled(b, 0.5);
    sum
}

/// The point of edge `e`: its smooth rule, the midpoint along a crease, or their blend where
/// the crease fades out ([`edge_rule`] decides, as for stencil rows).
fn edge_point<T: Primvar>(mesh: &Mesh, masks: &Masks, options: Options, parent: &[T], faces: &[T], e: EdgeId) -> T {
    let h = mesh.edge_half_edge(e);
    let (a, b) = (mesh.origin(h), mesh.dest(h));
    let middle = || midpoint(parent[a.index()], parent[b.index()]);
    let Some(t) = mesh.twin(h) else {
        return middle();
    };
    let smooth = || smooth_edge_point(mesh, masks, parent, faces, h, t);
    match edge_rule(mesh, masks, options, e) {
        EdgeRule::Smooth => smooth(),
        EdgeRule::Crease => middle(),
        EdgeRule::Blend(s) => {
            let mut sum = T::ZERO;
            sum.add_scaled(middle(), s);
            sum.add_scaled(smooth(), 1.0 - s);
            sum
        }
    }
}

/// The smooth point of the interior edge of `h` and its twin `t`.
fn smooth_edge_point<T: Primvar>(
    mesh: &Mesh,
    masks: &Masks,
    parent: &[T],
    faces: &[T],
    h: HalfEdgeId,
    t: HalfEdgeId,
) -> T {
    let (a, b) = (mesh.origin(h), mesh.dest(h));
    let mut sum = T::ZERO;
    match &masks.kind {
        Kind::Quad { endpoint, face, triangle_face, .. } => {
            let (g0, g1) = (mesh.face(h), mesh.face(t));
            let (vertex_weight, face_weight) = super::quad_edge_weights(mesh, *endpoint, *face, *triangle_face, g0, g1);
            sum.add_scaled(parent[a.index()], vertex_weight);
            sum.add_scaled(parent[b.index()], vertex_weight);
            if face_weight != 0.0 {
                sum.add_scaled(faces[g0.index()], face_weight);
                sum.add_scaled(faces[g1.index()], face_weight);
            }
        }
        Kind::Triangle { endpoint, opposite, .. } => {
            sum.add_scaled(parent[a.index()], *endpoint);
            sum.add_scaled(parent[b.index()], *endpoint);
            sum.add_scaled(parent[mesh.origin(mesh.prev(h)).index()], *opposite);
            sum.add_scaled(parent[mesh.origin(mesh.prev(t)).index()], *opposite);
        }
        Kind::FourPoint { .. } => unreachable!("the four-point rule takes stencil rows"),
    }
    sum
}

/// The smooth rule at an interior vertex without sharpness around it; `None` where the vertex
/// needs its stencil row (boundary, isolated, sharp, or next to a sharp edge when `creases`:
/// the scheme has crease rules and the mesh some sharpness).
fn smooth_vertex_point<T: Primvar>(
    mesh: &Mesh,
    masks: &Masks,
    creases: bool,
    parent: &[T],
    faces: &[T],
    v: VertexId,
) -> Option<T> {
    if mesh.is_isolated(v) || mesh.is_boundary_vertex(v) {
        return None;
    }
    if creases && crease::is_sharp(sharpness(mesh.vertex_sharpness(v))) {
        return None;
    }
    let (centre, spoke, face) = masks.vertex[mesh.valence(v)];
    let (mut spokes, mut face_sum) = (T::ZERO, T::ZERO);
    for h in mesh.outgoing(v) {
        if creases && crease::is_sharp(sharpness(mesh.edge_sharpness(mesh.edge(h)))) {
            return None;
        }
        spokes.add_scaled(parent[mesh.dest(h).index()], 1.0);
        if face != 0.0 {
            face_sum.add_scaled(faces[mesh.face(h).index()], 1.0);
        }
    }
    let mut sum = T::ZERO;
    sum.add_scaled(parent[v.index()], centre);
    if spoke != 0.0 {
        sum.add_scaled(spokes, spoke);
    }
    if face != 0.0 {
        sum.add_scaled(face_sum, face);
    }
    Some(sum)
}
