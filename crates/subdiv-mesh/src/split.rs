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

use crate::mesh::{Links, Mesh, NONE};
use crate::{EdgeId, FaceId, HalfEdgeId, Tags, VertexId};

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

    /// The number of faces of the split of `mesh`.
    pub fn child_face_count(self, mesh: &Mesh) -> usize {
        match self {
            Self::Quads => mesh.half_edge_count(),
            Self::Triangles => 4 * mesh.face_count(),
        }
    }

    /// The id of the child vertex of parent face `face` (quad splits; triangle splits have none).
    pub fn face_point(self, mesh: &Mesh, face: FaceId) -> Option<VertexId> {
        (self == Self::Quads).then(|| VertexId::new((mesh.vertex_count() + face.index()) as u32))
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

    fn face_point_count(self, mesh: &Mesh) -> usize {
        match self {
            Self::Quads => mesh.face_count(),
            Self::Triangles => 0,
        }
    }
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

/// The half-edge after `h` in its face, and the one before.
#[inline]
fn neighbours_in_face(links: &Links, h: u32) -> (u32, u32) {
    let f = links.he_face[h as usize].index();
    let (start, end) = (links.face_offsets[f], links.face_offsets[f + 1]);
    let next = if h + 1 == end { start } else { h + 1 };
    let prev = if h == start { end - 1 } else { h - 1 };
    (next, prev)
}

impl Mesh {
    /// The split of this mesh's topology by `split`, with the child vertices at `positions`
    /// (numbered as the [module docs](PrimalSplit) say). Child faces of holes are holes; the
    /// child has no sharpness and no channels (the scheme that refines sets them) and the
    /// parent's authored rule tags (boundary, crease method, triangle rule, face-varying
    /// mode), not its per-element tags.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, DVec3, Mesh, PrimalSplit};
    ///
    /// let cube = Mesh::build(shapes::cube())?;
    /// let count = PrimalSplit::Quads.child_vertex_count(&cube);
    /// let child = cube.split(PrimalSplit::Quads, vec![DVec3::ZERO; count]);
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
    pub fn split(&self, split: PrimalSplit, positions: Vec<DVec3>) -> Mesh {
        assert_eq!(positions.len(), split.child_vertex_count(self), "one position per child vertex");
        let links = match split {
            PrimalSplit::Quads => split_quads(&self.links, self.vertex_count(), self.face_count()),
            PrimalSplit::Triangles => {
                assert!(self.links.face_offsets.iter().enumerate().all(|(f, &o)| o as usize == 3 * f));
                split_triangles(&self.links, self.vertex_count())
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

/// Numbers the child edges in the order of their first half-edge (as the build does), in one
/// forward pass: a half-edge after its twin takes the twin's edge, numbered already.
fn number_edges(he_twin: &[u32]) -> (Vec<EdgeId>, Vec<HalfEdgeId>) {
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

fn split_quads(p: &Links, nv: usize, nf: usize) -> Links {
    let nh = p.he_origin.len();
    let (face_base, edge_base) = (nv as u32, (nv + nf) as u32);
    // Filled in order: the children of half-edge h are 4h..4h + 4, and h runs through the faces.
    let mut he_origin = Vec::with_capacity(4 * nh);
    let mut he_twin = Vec::with_capacity(4 * nh);
    for f in 0..nf {
        let (start, end) = (p.face_offsets[f], p.face_offsets[f + 1]);
        let quad = end - start == 4;
        for h in start..end {
            let rotation = if quad { h - start } else { 0 };
            let next = if h + 1 == end { start } else { h + 1 };
            let prev = if h == start { end - 1 } else { h - 1 };
            let corners = [
                p.he_origin[h as usize],
                VertexId::new(edge_base + p.he_edge[h as usize].raw()),
                VertexId::new(face_base + f as u32),
                VertexId::new(edge_base + p.he_edge[prev as usize].raw()),
            ];
            let twin = |x: u32, k: u32| -> u32 {
                let t = p.he_twin[x as usize];
                if t == NONE { NONE } else { quad_child(p, k_target(p, t, k), k) }
            };
            // Local edge k's twin: 0 and 3 cross the parent's edges, 1 and 2 stay inside.
            let twins = [twin(h, 3), quad_child(p, next, 2), quad_child(p, prev, 1), twin(prev, 0)];
            let (mut origins, mut links) = ([VertexId::new(0); 4], [NONE; 4]);
            for k in 0..4 {
                origins[(k + rotation as usize) & 3] = corners[k];
                links[(k + rotation as usize) & 3] = twins[k];
            }
            he_origin.extend_from_slice(&origins);
            he_twin.extend_from_slice(&links);
        }
    }
    let he_face = (0..4 * nh).map(|c| FaceId::new((c / 4) as u32)).collect();
    let face_offsets = (0..=nh as u32).map(|c| 4 * c).collect();
    let (he_edge, edge_he) = number_edges(&he_twin);

    let child_count = nv + nf + p.edge_he.len();
    let mut vertex_he = Vec::with_capacity(child_count);
    let mut valence = Vec::with_capacity(child_count);
    // Vertex points: the child of the parent's first outgoing half-edge (its boundary one, or
    // its lowest), which stays first: children of `h` are numbered from 4h.
    vertex_he.extend(p.vertex_he.iter().map(|&h| if h == NONE { NONE } else { quad_child(p, h, 0) }));
    valence.extend_from_slice(&p.valence);
    for f in 0..nf {
        let (start, end) = (p.face_offsets[f], p.face_offsets[f + 1]);
        vertex_he.push(quad_child(p, start, 2));
        valence.push(end - start);
    }
    for &h in &p.edge_he {
        let h = h.raw();
        let (next, _) = neighbours_in_face(p, h);
        let t = p.he_twin[h as usize];
        if t == NONE {
            // The boundary half-edge runs along the parent's boundary, to dest(h).
            vertex_he.push(quad_child(p, next, 3));
            valence.push(3);
        } else {
            let (t_next, _) = neighbours_in_face(p, t);
            let around = [quad_child(p, h, 1), quad_child(p, next, 3), quad_child(p, t, 1), quad_child(p, t_next, 3)];
            vertex_he.push(around.into_iter().min().unwrap_or(NONE));
            valence.push(4);
        }
    }
    Links { face_offsets, he_origin, he_face, he_twin, he_edge, edge_he, vertex_he, valence }
}

/// The parent half-edge whose quad child holds the twin of local edge 0 or 3 across the parent
/// half-edge whose twin is `t`: edge 0's twin is edge 3 of `next(t)`'s child; edge 3's twin is
/// edge 0 of `t`'s child.
#[inline]
fn k_target(p: &Links, t: u32, k: u32) -> u32 {
    if k == 3 { neighbours_in_face(p, t).0 } else { t }
}

fn split_triangles(p: &Links, nv: usize) -> Links {
    let nf = p.face_offsets.len() - 1;
    let edge_base = nv as u32;
    // Filled in order, a face's twelve child half-edges at a time.
    let mut he_origin = Vec::with_capacity(12 * nf);
    let mut he_twin = Vec::with_capacity(12 * nf);
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
    let he_face = (0..12 * nf).map(|c| FaceId::new((c / 3) as u32)).collect();
    let face_offsets = (0..=4 * nf as u32).map(|c| 3 * c).collect();
    let (he_edge, edge_he) = number_edges(&he_twin);

    let child_count = nv + p.edge_he.len();
    let mut vertex_he = Vec::with_capacity(child_count);
    let mut valence = Vec::with_capacity(child_count);
    vertex_he.extend(p.vertex_he.iter().map(|&h| if h == NONE { NONE } else { triangle_child(h, 0) }));
    valence.extend_from_slice(&p.valence);
    for &h in &p.edge_he {
        let h = h.raw();
        let next = 3 * (h / 3) + (h % 3 + 1) % 3;
        let t = p.he_twin[h as usize];
        if t == NONE {
            vertex_he.push(triangle_child(next, 2));
            valence.push(4);
        } else {
            // Around the edge point: each side's two corner children and its middle child.
            let side = |x: u32| {
                let x_next = 3 * (x / 3) + (x % 3 + 1) % 3;
                let middle = 3 * (4 * (x / 3) + 3) + (x % 3 + 2) % 3;
                [triangle_child(x, 1), triangle_child(x_next, 2), middle]
            };
            vertex_he.push(side(h).into_iter().chain(side(t)).min().unwrap_or(NONE));
            valence.push(6);
        }
    }
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
        let child = mesh.split(split, positions);
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
    }

    #[test]
    fn quad_splits_equal_the_build_of_their_faces() {
        let soups = [shapes::cube(), shapes::quad_grid(3, 2), shapes::quad_torus(5, 4), shapes::default_model()];
        for soup in soups.into_iter().chain([shapes::ngon_prism(7), shapes::pole(5)]) {
            let mesh = Mesh::build(soup).unwrap();
            assert_split_equals_build(&mesh, PrimalSplit::Quads);
            let once = mesh.split(PrimalSplit::Quads, vec![DVec3::ZERO; PrimalSplit::Quads.child_vertex_count(&mesh)]);
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
    fn holes_pass_to_the_children() {
        let mut mesh = Mesh::build(shapes::quad_grid(2, 2)).unwrap();
        mesh.set_hole(FaceId::new(3), true);
        let child = mesh.split(PrimalSplit::Quads, vec![DVec3::ZERO; PrimalSplit::Quads.child_vertex_count(&mesh)]);
        let holes: Vec<u32> = child.face_ids().filter(|&f| child.is_hole(f)).map(|f| f.raw()).collect();
        assert_eq!(holes, vec![12, 13, 14, 15]);
    }
}
