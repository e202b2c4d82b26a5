//! One primal split of a mesh's topology, computed by construction: every child array is an
//! index expression of the parent's, in linear passes over flat arrays, with no polygon soup,
//! no twin search and no re-validation (a split of a valid mesh is valid).
//!
//! The layout follows from the half-edge numbering (half-edges contiguous per face), as in the
//! halfedge refinement rules of Dupuy and Vanhoey:
//!
//! - child vertices: the parent's vertices (same ids), then one per face ([`PrimalSplit::Quads`]
//!   only), then one per edge — the order of OpenSubdiv's `Far` levels;
//! - [`PrimalSplit::Quads`]: the child of parent half-edge `h` is the quad `h` (an n-gon's
//!   children are the quads of its n half-edges, in order); its corners are `origin(h)`, the
//!   point of `h`'s edge, the face point and the point of `prev(h)`'s edge, rotated so that a
//!   quad's child at corner `j` starts at position `j` (as `Far` orders them);
//! - [`PrimalSplit::Triangles`] (every face a triangle): the children of face `f` are `4f + j`
//!   at corner `j` (rotated the same way) and `4f + 3` in the middle;
//! - child edges are numbered in the order of their first half-edge, as [`Mesh::build`] numbers
//!   them, so a split equals the build of the same faces, id for id.

use std::sync::Arc;

use glam::DVec3;

use crate::build::{next_in_face, prev_in_face};
use crate::mesh::{Links, Mesh, NONE};
use crate::par::{self, CHUNK};
use crate::{EdgeId, FaceId, HalfEdgeId, Parallelism, Tags, VertexId};

/// How a primal refinement level splits faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrimalSplit {
    /// Every n-gon into n quads, through a new point per face and per edge (Catmull-Clark,
    /// bilinear, Kobbelt).
    Quads,
    /// Every triangle into four, through a new point per edge (Loop, Butterfly).
    Triangles,
}

impl PrimalSplit {
    /// The number of vertices of the split of `mesh`.
    pub fn child_vertex_count(self, mesh: &Mesh) -> usize {
        mesh.vertex_count() + self.face_point_count(mesh) + mesh.edge_count()
    }

    /// The id of the child vertex of parent edge `edge`.
    pub fn edge_point(self, mesh: &Mesh, edge: EdgeId) -> VertexId {
        VertexId::new((mesh.vertex_count() + self.face_point_count(mesh) + edge.index()) as u32)
    }

    /// The child faces of parent face `face`, in order (a quad split's children of an n-gon
    /// start at its first corner; a triangle's middle child comes last).
    pub fn face_children(self, mesh: &Mesh, face: FaceId) -> std::ops::Range<u32> {
        match self {
            Self::Quads => {
                let first = mesh.face_half_edges(face).next().map_or(0, |h| h.raw());
                first..first + mesh.face_size(face) as u32
            }
            Self::Triangles => 4 * face.raw()..4 * face.raw() + 4,
        }
    }

    /// The two child edges of parent edge `edge` in `child`, the split of `parent`: the one at
    /// `origin(edge_half_edge(edge))` first.
    pub fn edge_children(self, parent: &Mesh, child: &Mesh, edge: EdgeId) -> [EdgeId; 2] {
        let h = parent.edge_half_edge(edge);
        let links = &parent.links;
        let [first, second] = match self {
            Self::Quads => [quad_child(links, h.raw(), 0), quad_child(links, parent.next(h).raw(), 3)],
            Self::Triangles => [triangle_child(h.raw(), 0), triangle_child(parent.next(h).raw(), 2)],
        };
        [child.edge(HalfEdgeId::new(first)), child.edge(HalfEdgeId::new(second))]
    }

    /// Where the origin of child half-edge `child` (of the split of `parent`) comes from, with
    /// the parent corner it lies in: what a face-varying channel needs to pick a child corner's
    /// value without searching the parent's faces.
    pub fn child_origin(self, parent: &Mesh, child: HalfEdgeId) -> ChildOrigin {
        let p = &parent.links;
        let c = child.raw();
        match self {
            Self::Quads => {
                let (h, role) = quad_role(p, c);
                match role {
                    0 => ChildOrigin::Vertex(HalfEdgeId::new(h)),
                    1 => ChildOrigin::Edge(HalfEdgeId::new(h)),
                    2 => ChildOrigin::Face(p.he_face[h as usize]),
                    _ => ChildOrigin::Edge(HalfEdgeId::new(prev_in_face(&p.face_offsets, &p.he_face, h))),
                }
            }
            Self::Triangles => match triangle_role(c) {
                TriangleRole::Middle(h) => ChildOrigin::Edge(HalfEdgeId::new(h)),
                TriangleRole::Corner { h, role: 0, .. } => ChildOrigin::Vertex(HalfEdgeId::new(h)),
                TriangleRole::Corner { h, role: 1, .. } => ChildOrigin::Edge(HalfEdgeId::new(h)),
                TriangleRole::Corner { prev, .. } => ChildOrigin::Edge(HalfEdgeId::new(prev)),
            },
        }
    }

    /// Child half-edge `k` of the child face at parent corner `corner` (the child that holds
    /// the corner's vertex), counted from the corner: 0 leaves the corner's vertex point, 1 the
    /// point of `corner`'s edge, the last (3 for quads, 2 for triangles) the point of the
    /// previous edge, and a quad's 2 the face point.
    pub fn corner_child(self, parent: &Mesh, corner: HalfEdgeId, k: u32) -> HalfEdgeId {
        HalfEdgeId::new(match self {
            Self::Quads => quad_child(&parent.links, corner.raw(), k),
            Self::Triangles => triangle_child(corner.raw(), k),
        })
    }

    /// The number of sides of a child face of a regular split: 4 or 3.
    pub fn child_face_size(self) -> u32 {
        match self {
            Self::Quads => 4,
            Self::Triangles => 3,
        }
    }

    fn face_point_count(self, mesh: &Mesh) -> usize {
        match self {
            Self::Quads => mesh.face_count(),
            Self::Triangles => 0,
        }
    }
}

/// Where a child half-edge's origin comes from in the parent ([`PrimalSplit::child_origin`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChildOrigin {
    /// The parent vertex at the origin of this parent half-edge (the child lies in its face).
    Vertex(HalfEdgeId),
    /// The point of this parent half-edge's edge, on its side (the child lies in its face).
    Edge(HalfEdgeId),
    /// The point of this parent face.
    Face(FaceId),
}

/// The parent half-edge of child half-edge `c` of a quad split and the child's role in the
/// child face, from its corner (0 the corner, 1 `h`'s edge point, 2 the face point, 3 the
/// previous edge's point): the quad child of an n-gon's half-edge `h` is face `h`, rotated
/// as `Far` rotates the children of a quad.
#[inline]
fn quad_role(p: &Links, c: u32) -> (u32, u32) {
    let h = c / 4;
    let f = p.he_face[h as usize].index();
    let (start, end) = (p.face_offsets[f], p.face_offsets[f + 1]);
    let rotation = if end - start == 4 { h - start } else { 0 };
    (h, (c + 4 - rotation) & 3)
}

/// The role of child half-edge `c` of a triangle split: `12f..12f + 12`, corner child `j` at
/// `12f + 3j` (rotated so that corner `j` starts at position `j`), the middle child at `12f + 9`.
#[derive(Clone, Copy)]
enum TriangleRole {
    /// Position `j` of the middle child, from the point of edge `h = corner(j + 1)`.
    Middle(u32),
    /// In the corner child at parent half-edge `h` (whose previous is `prev`): 0 leaves the
    /// corner, 1 `h`'s edge point, 2 `prev`'s edge point.
    Corner { h: u32, prev: u32, role: u32 },
}

#[inline]
fn triangle_role(c: u32) -> TriangleRole {
    let (f, local) = (c / 12, c % 12);
    let corner = |j: u32| 3 * f + j % 3;
    if local >= 9 {
        return TriangleRole::Middle(corner(local - 9 + 1));
    }
    let j = local / 3;
    TriangleRole::Corner { h: corner(j), prev: corner(j + 2), role: (local % 3 + 3 - j) % 3 }
}

/// Child half-edge `k` of the quad split's child of parent half-edge `h` (unrotated local edge
/// `k`: 0 corner → edge point, 1 → face point, 2 → previous edge's point, 3 → back).
#[inline]
fn quad_child(links: &Links, h: u32, k: u32) -> u32 {
    let f = links.he_face[h as usize].index();
    let start = links.face_offsets[f];
    let rotation = if links.face_offsets[f + 1] - start == 4 { h - start } else { 0 };
    4 * h + ((k + rotation) & 3)
}

/// Child half-edge `k` of the triangle split's corner child at parent half-edge `h` (unrotated
/// local edge `k`: 0 corner → edge point, 1 → previous edge's point, 2 → back). Faces are
/// triangles, so `h = 3f + j`.
#[inline]
fn triangle_child(h: u32, k: u32) -> u32 {
    let (f, j) = (h / 3, h % 3);
    3 * (4 * f + j) + (k + j) % 3
}

impl Mesh {
    /// The split of this mesh's topology by `split`, with the child vertices at `positions`
    /// (numbered as the [module docs](PrimalSplit) say), on rayon's threads if `parallelism`
    /// says so (the same mesh either way). Child faces of holes are holes; the
    /// child has no sharpness and no channels (the scheme that refines sets them) and the
    /// parent's authored rule tags (boundary, crease method, triangle rule, face-varying
    /// mode), not its per-element tags.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, DVec3, Mesh, Parallelism, PrimalSplit};
    ///
    /// let cube = Mesh::build(shapes::cube())?;
    /// let count = PrimalSplit::Quads.child_vertex_count(&cube);
    /// let child = cube.split(PrimalSplit::Quads, vec![DVec3::ZERO; count], Parallelism::DEFAULT);
    /// assert_eq!((child.vertex_count(), child.edge_count(), child.face_count()), (26, 48, 24));
    /// // The same faces through the validating build give the same mesh.
    /// let rebuilt = Mesh::build(child.to_soup())?;
    /// assert!(child.faces().eq(rebuilt.faces()));
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// When `positions` does not have [`PrimalSplit::child_vertex_count`] entries, or when
    /// `split` is [`PrimalSplit::Triangles`] and a face is not a triangle.
    pub fn split(&self, split: PrimalSplit, positions: Vec<DVec3>, parallelism: Parallelism) -> Mesh {
        assert_eq!(positions.len(), split.child_vertex_count(self), "one position per child vertex");
        let parallel = parallelism.forks_for(4 * self.half_edge_count());
        let links = match split {
            PrimalSplit::Quads => split_quads(&self.links, self.vertex_count(), self.face_count(), parallel),
            PrimalSplit::Triangles => {
                assert!(self.links.face_offsets.iter().enumerate().all(|(f, &o)| o as usize == 3 * f));
                split_triangles(&self.links, self.vertex_count(), parallel)
            }
        };
        let mut hole = vec![false; links.face_offsets.len() - 1];
        for f in self.face_ids().filter(|&f| self.is_hole(f)) {
            for c in split.face_children(self, f) {
                hole[c as usize] = true;
            }
        }
        let tags = Tags {
            boundary_interpolation: self.tags.boundary_interpolation,
            crease_method: self.tags.crease_method,
            triangle_subdivision: self.tags.triangle_subdivision,
            face_varying_interpolation: self.tags.face_varying_interpolation,
            ..Tags::default()
        };
        Mesh {
            edge_sharpness: vec![0.0; links.edge_he.len()],
            vertex_sharpness: vec![0.0; positions.len()],
            positions,
            links: Arc::new(links),
            hole,
            tags,
            channels: Arc::new([]),
        }
    }
}

/// Numbers the child edges in the order of their first half-edge (as the build does): each
/// chunk ranks its first half-edges, the chunks' counts are summed in order, and a half-edge
/// after its twin takes its twin's number.
fn number_edges(parallel: bool, he_twin: &[u32]) -> (Vec<EdgeId>, Vec<HalfEdgeId>) {
    if !parallel {
        return number_edges_in_order(he_twin);
    }
    let n = he_twin.len();
    let is_first = |h: usize| he_twin[h] == NONE || (h as u32) < he_twin[h];
    let mut rank = vec![0u32; n];
    par::for_each_chunk(parallel, &mut rank, CHUNK, |k, chunk| {
        let mut r = 0;
        for (i, slot) in chunk.iter_mut().enumerate() {
            *slot = r;
            r += u32::from(is_first(k * CHUNK + i));
        }
    });
    let mut base = Vec::with_capacity(n.div_ceil(CHUNK) + 1);
    base.push(0u32);
    for k in 0..n.div_ceil(CHUNK) {
        let last = ((k + 1) * CHUNK).min(n) - 1;
        base.push(base[k] + rank[last] + u32::from(is_first(last)));
    }
    let id = |h: usize| base[h / CHUNK] + rank[h];
    let mut he_edge = Vec::with_capacity(n);
    par::extend_range(parallel, &mut he_edge, 0..n, |h| {
        EdgeId::new(if is_first(h) { id(h) } else { id(he_twin[h] as usize) })
    });
    let parts = par::map(parallel, (0..n.div_ceil(CHUNK)).collect(), |k: usize| {
        (k * CHUNK..((k + 1) * CHUNK).min(n))
            .filter(|&h| is_first(h))
            .map(|h| HalfEdgeId::new(h as u32))
            .collect::<Vec<_>>()
    });
    (he_edge, parts.concat())
}

/// [`number_edges`] on one thread: one forward pass, no rank array (whose first touch costs a
/// fresh process more than the pass: the peers' torus to level 3 in `subdiv refine` took 60 ms
/// with it, 50 without).
fn number_edges_in_order(he_twin: &[u32]) -> (Vec<EdgeId>, Vec<HalfEdgeId>) {
    let mut he_edge: Vec<EdgeId> = Vec::with_capacity(he_twin.len());
    let mut edge_he = Vec::with_capacity(he_twin.len() / 2 + 1);
    for (h, &t) in he_twin.iter().enumerate() {
        if t == NONE || (h as u32) < t {
            he_edge.push(EdgeId::new(edge_he.len() as u32));
            edge_he.push(HalfEdgeId::new(h as u32));
        } else {
            he_edge.push(he_edge[t as usize]);
        }
    }
    (he_edge, edge_he)
}

/// The half-edge after `h` in its face.
#[inline]
fn next_of(p: &Links, h: u32) -> u32 {
    next_in_face(&p.face_offsets, &p.he_face, h)
}

/// Child half-edge `c` of a quad split: its origin and twin.
#[inline]
fn quad_corner(p: &Links, face_base: u32, edge_base: u32, c: usize) -> (VertexId, u32) {
    let (h, role) = quad_role(p, c as u32);
    let edge_point = |x: u32| VertexId::new(edge_base + p.he_edge[x as usize].raw());
    let prev = || prev_in_face(&p.face_offsets, &p.he_face, h);
    // Local edge k's twin: 0 and 3 cross the parent's edges, 1 and 2 stay inside.
    match role {
        0 => {
            let t = p.he_twin[h as usize];
            (p.he_origin[h as usize], if t == NONE { NONE } else { quad_child(p, next_of(p, t), 3) })
        }
        1 => (edge_point(h), quad_child(p, next_of(p, h), 2)),
        2 => (VertexId::new(face_base + p.he_face[h as usize].raw()), quad_child(p, prev(), 1)),
        _ => {
            let t = p.he_twin[prev() as usize];
            (edge_point(prev()), if t == NONE { NONE } else { quad_child(p, t, 0) })
        }
    }
}

fn split_quads(p: &Links, nv: usize, nf: usize, parallel: bool) -> Links {
    let nh = p.he_origin.len();
    let (face_base, edge_base) = (nv as u32, (nv + nf) as u32);
    let (mut he_origin, mut he_twin) = (Vec::new(), Vec::new());
    par::unzip_range(parallel, &mut he_origin, &mut he_twin, 0..4 * nh, |c| quad_corner(p, face_base, edge_base, c));
    let mut he_face = Vec::with_capacity(4 * nh);
    par::extend_range(parallel, &mut he_face, 0..4 * nh, |c| FaceId::new((c / 4) as u32));
    let mut face_offsets = Vec::with_capacity(nh + 1);
    par::extend_range(parallel, &mut face_offsets, 0..nh + 1, |c| 4 * c as u32);
    let (he_edge, edge_he) = number_edges(parallel, &he_twin);

    // Vertex points: the child of the parent's first outgoing half-edge (its boundary one, or
    // its lowest), which stays first: children of `h` are numbered from 4h.
    let (mut vertex_he, mut valence) = (Vec::new(), Vec::new());
    par::unzip_range(parallel, &mut vertex_he, &mut valence, 0..nv + nf + p.edge_he.len(), |v| {
        if v < nv {
            let h = p.vertex_he[v];
            (if h == NONE { NONE } else { quad_child(p, h, 0) }, p.valence[v])
        } else if v < nv + nf {
            let (start, end) = (p.face_offsets[v - nv], p.face_offsets[v - nv + 1]);
            (quad_child(p, start, 2), end - start)
        } else {
            let h = p.edge_he[v - nv - nf].raw();
            let next = next_of(p, h);
            let t = p.he_twin[h as usize];
            if t == NONE {
                // The boundary half-edge runs along the parent's boundary, to dest(h).
                (quad_child(p, next, 3), 3)
            } else {
                let t_next = next_of(p, t);
                let around =
                    [quad_child(p, h, 1), quad_child(p, next, 3), quad_child(p, t, 1), quad_child(p, t_next, 3)];
                (around.into_iter().min().unwrap_or(NONE), 4)
            }
        }
    });
    Links { face_offsets, he_origin, he_face, he_twin, he_edge, edge_he, vertex_he, valence }
}

/// Child half-edge `c` of a triangle split ([`triangle_role`] says where it lies): its origin
/// and twin.
#[inline]
fn triangle_corner(p: &Links, edge_base: u32, c: usize) -> (VertexId, u32) {
    let f = c as u32 / 12;
    let edge_point = |h: u32| VertexId::new(edge_base + p.he_edge[h as usize].raw());
    match triangle_role(c as u32) {
        TriangleRole::Middle(h) => {
            // Position j runs from the point of edge j + 1 to that of j + 2.
            (edge_point(h), triangle_child(3 * f + (h + 1) % 3, 1))
        }
        TriangleRole::Corner { h, role: 0, .. } => {
            let t = p.he_twin[h as usize];
            (p.he_origin[h as usize], if t == NONE { NONE } else { triangle_child(3 * (t / 3) + (t % 3 + 1) % 3, 2) })
        }
        TriangleRole::Corner { h, role: 1, .. } => (edge_point(h), 3 * (4 * f + 3) + (h % 3 + 1) % 3),
        TriangleRole::Corner { prev, .. } => {
            let t = p.he_twin[prev as usize];
            (edge_point(prev), if t == NONE { NONE } else { triangle_child(t, 0) })
        }
    }
}

fn split_triangles(p: &Links, nv: usize, parallel: bool) -> Links {
    let nf = p.face_offsets.len() - 1;
    let edge_base = nv as u32;
    let (mut he_origin, mut he_twin) = (Vec::new(), Vec::new());
    if parallel {
        par::unzip_range(parallel, &mut he_origin, &mut he_twin, 0..12 * nf, |c| triangle_corner(p, edge_base, c));
    } else {
        // On one thread a face's twelve children at a time, as one block: the peers' triangle
        // torus to level 3 refines in 65 ms this way and in 98 ms through `triangle_corner` per
        // child (`cargo xtask bench refine --threads 1`, 5 rounds). The tests hold the two equal.
        he_origin.reserve(12 * nf);
        he_twin.reserve(12 * nf);
        let edge_point = |h: u32| VertexId::new(edge_base + p.he_edge[h as usize].raw());
        for f in 0..nf as u32 {
            let middle = 3 * (4 * f + 3);
            let (mut origins, mut links) = ([VertexId::new(0); 12], [NONE; 12]);
            for j in 0..3u32 {
                let h = 3 * f + j;
                let next = 3 * f + (j + 1) % 3;
                let prev = 3 * f + (j + 2) % 3;
                let corners = [p.he_origin[h as usize], edge_point(h), edge_point(prev)];
                let across = |x: u32| p.he_twin[x as usize];
                let t = across(h);
                let tp = across(prev);
                let twins = [
                    if t == NONE { NONE } else { triangle_child(3 * (t / 3) + (t % 3 + 1) % 3, 2) },
                    middle + (j + 1) % 3,
                    if tp == NONE { NONE } else { triangle_child(tp, 0) },
                ];
                for k in 0..3u32 {
                    let c = (triangle_child(h, k) - 12 * f) as usize;
                    origins[c] = corners[k as usize];
                    links[c] = twins[k as usize];
                }
                // The middle child: position j runs from the point of edge j + 1 to that of j + 2.
                origins[9 + j as usize] = edge_point(next);
                links[9 + j as usize] = triangle_child(3 * f + (j + 2) % 3, 1);
            }
            he_origin.extend_from_slice(&origins);
            he_twin.extend_from_slice(&links);
        }
    }
    let mut he_face = Vec::with_capacity(12 * nf);
    par::extend_range(parallel, &mut he_face, 0..12 * nf, |c| FaceId::new((c / 3) as u32));
    let mut face_offsets = Vec::with_capacity(4 * nf + 1);
    par::extend_range(parallel, &mut face_offsets, 0..4 * nf + 1, |c| 3 * c as u32);
    let (he_edge, edge_he) = number_edges(parallel, &he_twin);

    let (mut vertex_he, mut valence) = (Vec::new(), Vec::new());
    par::unzip_range(parallel, &mut vertex_he, &mut valence, 0..nv + p.edge_he.len(), |v| {
        if v < nv {
            let h = p.vertex_he[v];
            return (if h == NONE { NONE } else { triangle_child(h, 0) }, p.valence[v]);
        }
        let h = p.edge_he[v - nv].raw();
        let next = 3 * (h / 3) + (h % 3 + 1) % 3;
        let t = p.he_twin[h as usize];
        if t == NONE {
            return (triangle_child(next, 2), 4);
        }
        // Around the edge point: each side's two corner children and its middle child.
        let side = |x: u32| {
            let x_next = 3 * (x / 3) + (x % 3 + 1) % 3;
            let middle = 3 * (4 * (x / 3) + 3) + (x % 3 + 2) % 3;
            [triangle_child(x, 1), triangle_child(x_next, 2), middle]
        };
        (side(h).into_iter().chain(side(t)).min().unwrap_or(NONE), 6)
    });
    Links { face_offsets, he_origin, he_face, he_twin, he_edge, edge_he, vertex_he, valence }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BuildOptions, PolygonSoup, shapes};

    /// The split must equal the validating build of the same faces, array for array.
    fn assert_split_equals_build(mesh: &Mesh, split: PrimalSplit) {
        let count = split.child_vertex_count(mesh);
        let positions: Vec<DVec3> = (0..count).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect();
        let child = mesh.split(split, positions.clone(), Parallelism::Rayon);
        let serial = mesh.split(split, positions, Parallelism::Serial);
        assert_eq!(format!("{:?}", child.links), format!("{:?}", serial.links), "threads change nothing");
        let mut soup = PolygonSoup::with_capacity(count, child.face_count(), child.half_edge_count());
        for &p in child.positions() {
            soup.push_vertex(p);
        }
        for face in child.faces() {
            soup.push_face(face.iter().copied());
        }
        let built = Mesh::build_with(soup, &BuildOptions::DEFAULT).expect("a split is a valid mesh");
        let (a, b) = (&child.links, &built.links);
        assert_eq!(a.face_offsets, b.face_offsets);
        assert_eq!(a.he_origin, b.he_origin);
        assert_eq!(a.he_face, b.he_face);
        assert_eq!(a.he_twin, b.he_twin);
        assert_eq!(a.he_edge, b.he_edge);
        assert_eq!(a.edge_he, b.edge_he);
        assert_eq!(a.vertex_he, b.vertex_he);
        assert_eq!(a.valence, b.valence);
        for e in mesh.edges() {
            let [first, second] = split.edge_children(mesh, &child, e);
            let [a, b] = mesh.edge_vertices(e);
            let point = split.edge_point(mesh, e);
            assert_eq!(child.edge_vertices(first), [a, point]);
            assert_eq!(child.edge_vertices(second), [point, b]);
        }
        // Every child corner's parent, and back.
        let face_point = |f: FaceId| VertexId::new(mesh.vertex_count() as u32 + f.raw());
        for c in (0..child.half_edge_count() as u32).map(HalfEdgeId::new) {
            let (origin, face) = match split.child_origin(mesh, c) {
                ChildOrigin::Vertex(h) => {
                    assert_eq!(split.corner_child(mesh, h, 0), c);
                    (mesh.origin(h), mesh.face(h))
                }
                ChildOrigin::Edge(h) => (split.edge_point(mesh, mesh.edge(h)), mesh.face(h)),
                ChildOrigin::Face(f) => (face_point(f), f),
            };
            assert_eq!(child.origin(c), origin, "child half-edge {c:?}");
            assert!(split.face_children(mesh, face).contains(&child.face(c).raw()));
        }
        for h in (0..mesh.half_edge_count() as u32).map(HalfEdgeId::new) {
            let last = split.child_face_size() - 1;
            let point = split.edge_point(mesh, mesh.edge(h));
            assert_eq!(child.origin(split.corner_child(mesh, h, 1)), point);
            assert_eq!(child.origin(split.corner_child(mesh, mesh.next(h), last)), point);
        }
    }

    #[test]
    fn quad_splits_equal_the_build_of_their_faces() {
        let soups = [shapes::cube(), shapes::quad_grid(3, 2), shapes::quad_torus(5, 4), shapes::default_model()];
        for soup in soups.into_iter().chain([shapes::ngon_prism(7), shapes::pole(5)]) {
            let mesh = Mesh::build(soup).unwrap();
            assert_split_equals_build(&mesh, PrimalSplit::Quads);
            let count = PrimalSplit::Quads.child_vertex_count(&mesh);
            let once = mesh.split(PrimalSplit::Quads, vec![DVec3::ZERO; count], Parallelism::DEFAULT);
            assert_split_equals_build(&once, PrimalSplit::Quads);
        }
    }

    #[test]
    fn triangle_splits_equal_the_build_of_their_faces() {
        // An open triangle mesh: a 3 × 2 grid with every quad cut along a diagonal.
        let strip = PolygonSoup::from_indices(
            (0..12).map(|i| DVec3::new(f64::from(i % 4), f64::from(i / 4), 0.0)).collect(),
            (0..2u32)
                .flat_map(|r| (0..3u32).map(move |c| 4 * r + c))
                .flat_map(|a| [[a, a + 1, a + 5], [a, a + 5, a + 4]]),
        );
        for soup in [shapes::icosahedron(), shapes::octahedron(), shapes::triangle_torus(5, 4), strip] {
            let mesh = Mesh::build(soup).unwrap();
            assert_split_equals_build(&mesh, PrimalSplit::Triangles);
            // Triangles also split into quads.
            assert_split_equals_build(&mesh, PrimalSplit::Quads);
        }
    }

    #[test]
    fn splits_of_many_chunks_equal_the_build_of_their_faces() {
        // Past `MIN_PARALLEL_ITEMS` child half-edges the passes fork, in several chunks each.
        let quads = Mesh::build(shapes::quad_torus(128, 64)).unwrap();
        assert!(4 * quads.half_edge_count() >= par::MIN_PARALLEL_ITEMS.max(3 * CHUNK));
        assert_split_equals_build(&quads, PrimalSplit::Quads);
        let triangles = Mesh::build(shapes::triangle_torus(96, 48)).unwrap();
        assert!(4 * triangles.half_edge_count() >= par::MIN_PARALLEL_ITEMS);
        assert_split_equals_build(&triangles, PrimalSplit::Triangles);
    }

    #[test]
    fn holes_pass_to_the_children() {
        let mut mesh = Mesh::build(shapes::quad_grid(2, 2)).unwrap();
        mesh.set_hole(FaceId::new(3), true);
        let count = PrimalSplit::Quads.child_vertex_count(&mesh);
        let child = mesh.split(PrimalSplit::Quads, vec![DVec3::ZERO; count], Parallelism::DEFAULT);
        let holes: Vec<u32> = child.face_ids().filter(|&f| child.is_hole(f)).map(|f| f.raw()).collect();
        assert_eq!(holes, vec![12, 13, 14, 15]);
    }
}
