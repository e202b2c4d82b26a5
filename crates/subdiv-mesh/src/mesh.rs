//! [`Mesh`]: the half-edge structure and its queries.

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::DVec3;
use smallvec::SmallVec;

use crate::build::{ResolvedTags, Topology};
use crate::{Channel, CornerTag, CreaseTag, EdgeId, FaceId, HalfEdgeId, PolygonSoup, Tags, VertexId};

/// "No half-edge" in the `u32` link arrays.
pub(crate) const NONE: u32 = u32::MAX;

/// A validated half-edge mesh: manifold, consistently oriented, faces of any size ≥ 3, open or
/// closed, with per-edge and per-vertex sharpness and hole flags from its [`Tags`].
///
/// Half-edges are the face corners: half-edge `h` of face `f` runs from corner `i` to corner
/// `i + 1` of `f`, and the half-edges of a face are numbered contiguously. Boundary edges have
/// one half-edge and no twin. Faces are counter-clockwise seen from outside, so rotating
/// counter-clockwise around a vertex goes `h → twin(prev(h))`.
///
/// Build one with [`Mesh::build`]; see the crate docs for an example.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub(crate) positions: Vec<DVec3>,
    /// Never changed after the build, and shared by clones: a copy of a mesh with other
    /// sharpness (the boundary rule applied, as every evaluator's level 0 is) costs its tags,
    /// not its connectivity (110 MB for a million quads).
    pub(crate) links: Arc<Links>,
    pub(crate) edge_sharpness: Vec<f64>,
    pub(crate) vertex_sharpness: Vec<f64>,
    pub(crate) hole: Vec<bool>,
    pub(crate) tags: Tags,
    /// Face-varying channels, shared by clones as the connectivity is.
    pub(crate) channels: Arc<[Channel]>,
}

/// A [`Mesh`]'s connectivity (see its docs for the numbering).
#[derive(Debug)]
pub(crate) struct Links {
    pub(crate) face_offsets: Vec<u32>,
    pub(crate) he_origin: Vec<VertexId>,
    pub(crate) he_face: Vec<FaceId>,
    pub(crate) he_twin: Vec<u32>,
    pub(crate) he_edge: Vec<EdgeId>,
    pub(crate) edge_he: Vec<HalfEdgeId>,
    /// For a boundary vertex, its boundary half-edge (the start of its fan); for an interior
    /// vertex, its lowest outgoing half-edge; `NONE` for an isolated vertex.
    pub(crate) vertex_he: Vec<u32>,
    pub(crate) valence: Vec<u32>,
}

/// The valences that count as regular for [`Mesh::is_extraordinary`]: one for interior vertices
/// and one for boundary vertices (boundary vertices of valence 2, corners, are always regular).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RegularValence {
    /// Regular valence of an interior vertex.
    pub interior: u32,
    /// Regular valence of a boundary vertex.
    pub boundary: u32,
}

impl RegularValence {
    /// Quad meshes (and mixed meshes, which quad schemes take): 4 inside, 3 on the boundary.
    pub const QUADS: Self = Self { interior: 4, boundary: 3 };
    /// Triangle meshes: 6 inside, 4 on the boundary.
    pub const TRIANGLES: Self = Self { interior: 6, boundary: 4 };

    /// [`TRIANGLES`](Self::TRIANGLES) when every face of `mesh` is a triangle (and there is at
    /// least one face), [`QUADS`](Self::QUADS) otherwise.
    pub fn for_faces_of(mesh: &Mesh) -> Self {
        if mesh.face_count() > 0 && mesh.faces().all(|f| f.len() == 3) { Self::TRIANGLES } else { Self::QUADS }
    }
}

/// Connected components of a mesh's faces (faces sharing an edge are connected; isolated
/// vertices belong to no component).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Components {
    face_component: Vec<u32>,
    count: usize,
}

impl Components {
    /// Number of components.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The component of `face`, in `0..count()`, numbered in order of their lowest face.
    pub fn of_face(&self, face: FaceId) -> usize {
        self.face_component[face.index()] as usize
    }
}

/// A closed chain of boundary half-edges, in order (each one's end is the next one's start).
pub type BoundaryLoop = Vec<HalfEdgeId>;

impl Mesh {
    pub(crate) fn from_parts(
        positions: Vec<DVec3>,
        face_offsets: Vec<u32>,
        he_origin: Vec<VertexId>,
        tags: Tags,
        topology: Topology,
        resolved: ResolvedTags,
    ) -> Self {
        let Topology { he_face, he_twin, he_edge, edge_he, vertex_he, valence } = topology;
        let ResolvedTags { edge_sharpness, vertex_sharpness, holes: hole } = resolved;
        Self {
            positions,
            links: Arc::new(Links { face_offsets, he_origin, he_face, he_twin, he_edge, edge_he, vertex_he, valence }),
            edge_sharpness,
            vertex_sharpness,
            hole,
            tags,
            channels: Arc::new([]),
        }
    }

    // ---- counts -------------------------------------------------------------------------

    /// Number of vertices, isolated ones included.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.links.face_offsets.len() - 1
    }

    /// Number of undirected edges.
    pub fn edge_count(&self) -> usize {
        self.links.edge_he.len()
    }

    /// Number of half-edges (face corners).
    pub fn half_edge_count(&self) -> usize {
        self.links.he_origin.len()
    }

    /// Number of boundary edges (edges with one face).
    pub fn boundary_edge_count(&self) -> usize {
        self.links.he_twin.iter().filter(|&&t| t == NONE).count()
    }

    /// All vertex ids.
    pub fn vertices(&self) -> impl ExactSizeIterator<Item = VertexId> + use<> {
        (0..self.vertex_count() as u32).map(VertexId::new)
    }

    /// All face ids.
    pub fn face_ids(&self) -> impl ExactSizeIterator<Item = FaceId> + use<> {
        (0..self.face_count() as u32).map(FaceId::new)
    }

    /// All edge ids.
    pub fn edges(&self) -> impl ExactSizeIterator<Item = EdgeId> + use<> {
        (0..self.edge_count() as u32).map(EdgeId::new)
    }

    // ---- geometry and tags --------------------------------------------------------------

    /// The vertex positions.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// The vertex positions, to move them (the topology stays).
    pub fn positions_mut(&mut self) -> &mut [DVec3] {
        &mut self.positions
    }

    /// The position of `vertex`.
    pub fn position(&self, vertex: VertexId) -> DVec3 {
        self.positions[vertex.index()]
    }

    /// The tags the mesh was built with.
    pub fn tags(&self) -> &Tags {
        &self.tags
    }

    /// The face-varying channels (texture coordinates, …), each with one value index per
    /// half-edge (face corner).
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// The channel named `name`, if any.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        self.channels.iter().find(|c| c.name() == name)
    }

    /// Replaces the channels (refinement sets the refined ones on the child level), after the
    /// checks [`Mesh::build`] makes; on an error the mesh keeps its channels.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Channel, Mesh, MeshError};
    ///
    /// let mut quad = Mesh::build(shapes::quad_grid(1, 1))?;
    /// quad.set_channels(vec![Channel::new("uv", 2, vec![0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0], vec![0, 1, 2, 3])])?;
    /// // An index past the values is refused, naming the face and corner.
    /// let bad = Channel::new("uv", 2, vec![0.0, 0.0], vec![0, 0, 0, 1]);
    /// assert!(matches!(quad.set_channels(vec![bad]), Err(MeshError::ChannelIndexOutOfRange { .. })));
    /// assert_eq!(quad.channels().len(), 1);
    /// # Ok::<(), MeshError>(())
    /// ```
    ///
    /// # Errors
    /// [`MeshError::ChannelShape`], [`MeshError::ChannelIndexOutOfRange`] or
    /// [`MeshError::ChannelNonFinite`] for a channel that breaks a rule: one index per face
    /// corner, indices in range, finite values.
    pub fn set_channels(&mut self, channels: Vec<Channel>) -> Result<(), crate::MeshError> {
        if let Some(error) = channels.iter().find_map(|c| c.check(&self.links.face_offsets, self.half_edge_count())) {
            return Err(error);
        }
        self.channels = channels.into();
        Ok(())
    }

    /// Removes every channel.
    pub fn clear_channels(&mut self) {
        self.channels = Arc::new([]);
    }

    /// Sharpness of `edge` (0 smooth; ≥ [`Tags::INFINITELY_SHARP`] infinitely sharp).
    pub fn edge_sharpness(&self, edge: EdgeId) -> f64 {
        self.edge_sharpness[edge.index()]
    }

    /// Sharpness of `vertex` as a corner (0 smooth).
    pub fn vertex_sharpness(&self, vertex: VertexId) -> f64 {
        self.vertex_sharpness[vertex.index()]
    }

    /// Whether `face` is tagged as a hole.
    pub fn is_hole(&self, face: FaceId) -> bool {
        self.hole[face.index()]
    }

    /// Sets the sharpness of `edge` (refinement uses this to carry creases to the next level;
    /// [`tags`](Self::tags) keeps what was authored). A negative or NaN value is stored as 0.
    pub fn set_edge_sharpness(&mut self, edge: EdgeId, sharpness: f64) {
        self.edge_sharpness[edge.index()] = if sharpness > 0.0 { sharpness } else { 0.0 };
    }

    /// Sets the corner sharpness of `vertex`; a negative or NaN value is stored as 0.
    pub fn set_vertex_sharpness(&mut self, vertex: VertexId, sharpness: f64) {
        self.vertex_sharpness[vertex.index()] = if sharpness > 0.0 { sharpness } else { 0.0 };
    }

    /// Marks `face` as a hole, or not.
    pub fn set_hole(&mut self, face: FaceId, hole: bool) {
        self.hole[face.index()] = hole;
    }

    /// The axis-aligned bounding box `(min, max)` of the vertices used by faces, or `None`
    /// when there are none.
    pub fn bounding_box(&self) -> Option<(DVec3, DVec3)> {
        let mut used = self.vertices().filter(|&v| !self.is_isolated(v)).map(|v| self.position(v));
        let first = used.next()?;
        Some(used.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }

    /// The mesh as a soup again: positions, faces, channels, and tags that give the mesh's
    /// sharpness and holes as they are now (a refined level's, which has no authored tags, or
    /// a base mesh's after [`set_edge_sharpness`](Self::set_edge_sharpness) and the like): one
    /// crease per sharp edge in edge order, one corner per sharp vertex, the holes, and the
    /// authored rules (boundary, crease method, …) as they were. Building the soup gives a mesh
    /// equal to this one.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh, VertexId};
    ///
    /// let mut mesh = Mesh::build(shapes::cube())?;
    /// let edge = mesh.find_edge(VertexId::new(0), VertexId::new(1)).unwrap();
    /// mesh.set_edge_sharpness(edge, 2.5);
    /// let again = Mesh::build(mesh.to_soup())?;
    /// assert_eq!(again.edge_sharpness(edge), 2.5);
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    pub fn to_soup(&self) -> PolygonSoup {
        let mut soup = PolygonSoup::with_capacity(self.vertex_count(), self.face_count(), self.half_edge_count());
        for &p in &self.positions {
            soup.push_vertex(p);
        }
        for face in self.faces() {
            soup.push_face(face.iter().copied());
        }
        soup.tags = Tags {
            creases: self
                .edges()
                .filter(|&e| self.edge_sharpness(e) > 0.0)
                .map(|e| CreaseTag { vertices: self.edge_vertices(e), sharpness: self.edge_sharpness(e) })
                .collect(),
            corners: self
                .vertices()
                .filter(|&v| self.vertex_sharpness(v) > 0.0)
                .map(|v| CornerTag { vertex: v, sharpness: self.vertex_sharpness(v) })
                .collect(),
            holes: self.face_ids().filter(|&f| self.is_hole(f)).collect(),
            ..self.tags.clone()
        };
        soup.channels = self.channels.to_vec();
        soup
    }

    // ---- faces --------------------------------------------------------------------------

    /// The vertices of `face`, in order.
    pub fn face_vertices(&self, face: FaceId) -> &[VertexId] {
        &self.links.he_origin[self.face_range(face)]
    }

    /// Number of vertices (and edges) of `face`.
    pub fn face_size(&self, face: FaceId) -> usize {
        let f = face.index();
        (self.links.face_offsets[f + 1] - self.links.face_offsets[f]) as usize
    }

    /// The faces in order, each as its vertex list.
    pub fn faces(&self) -> impl ExactSizeIterator<Item = &[VertexId]> + '_ {
        self.links.face_offsets.windows(2).map(|w| &self.links.he_origin[w[0] as usize..w[1] as usize])
    }

    /// The half-edges of `face`, in order; the first starts at the face's first vertex.
    pub fn face_half_edges(&self, face: FaceId) -> impl ExactSizeIterator<Item = HalfEdgeId> + use<> {
        let f = face.index();
        (self.links.face_offsets[f]..self.links.face_offsets[f + 1]).map(HalfEdgeId::new)
    }

    /// The neighbours of `face` across each of its edges, in order (`None` across a boundary).
    pub fn face_neighbors(&self, face: FaceId) -> impl ExactSizeIterator<Item = Option<FaceId>> + '_ {
        self.face_half_edges(face).map(|h| self.twin(h).map(|t| self.face(t)))
    }

    /// How many faces have each size: `size → count`.
    pub fn face_size_histogram(&self) -> BTreeMap<usize, usize> {
        let mut histogram = BTreeMap::new();
        for face in self.face_ids() {
            *histogram.entry(self.face_size(face)).or_insert(0) += 1;
        }
        histogram
    }

    fn face_range(&self, face: FaceId) -> std::ops::Range<usize> {
        let f = face.index();
        self.links.face_offsets[f] as usize..self.links.face_offsets[f + 1] as usize
    }

    // ---- half-edges ---------------------------------------------------------------------

    /// Where `h` starts.
    #[inline]
    pub fn origin(&self, h: HalfEdgeId) -> VertexId {
        self.links.he_origin[h.index()]
    }

    /// Where `h` ends.
    #[inline]
    pub fn dest(&self, h: HalfEdgeId) -> VertexId {
        self.origin(self.next(h))
    }

    /// The face `h` belongs to.
    #[inline]
    pub fn face(&self, h: HalfEdgeId) -> FaceId {
        self.links.he_face[h.index()]
    }

    /// The position of `h` in its face: `k` where `h` is the `k`-th of
    /// [`face_half_edges`](Self::face_half_edges) (the corner at its origin).
    ///
    /// ```
    /// use subdiv_mesh::{Mesh, shapes};
    ///
    /// let cube = Mesh::build(shapes::cube()).unwrap();
    /// let face = cube.face_ids().nth(2).unwrap();
    /// for (k, h) in cube.face_half_edges(face).enumerate() {
    ///     assert_eq!(cube.corner(h), k);
    /// }
    /// ```
    #[inline]
    pub fn corner(&self, h: HalfEdgeId) -> usize {
        (h.raw() - self.links.face_offsets[self.face(h).index()]) as usize
    }

    /// The next half-edge around `h`'s face.
    #[inline]
    pub fn next(&self, h: HalfEdgeId) -> HalfEdgeId {
        let f = self.face(h).index();
        let raw = h.raw();
        HalfEdgeId::new(if raw + 1 == self.links.face_offsets[f + 1] { self.links.face_offsets[f] } else { raw + 1 })
    }

    /// The previous half-edge around `h`'s face.
    #[inline]
    pub fn prev(&self, h: HalfEdgeId) -> HalfEdgeId {
        let f = self.face(h).index();
        let raw = h.raw();
        HalfEdgeId::new(if raw == self.links.face_offsets[f] { self.links.face_offsets[f + 1] - 1 } else { raw - 1 })
    }

    /// The opposite half-edge of the neighbouring face, `None` on a boundary.
    #[inline]
    pub fn twin(&self, h: HalfEdgeId) -> Option<HalfEdgeId> {
        let t = self.links.he_twin[h.index()];
        (t != NONE).then_some(HalfEdgeId::new(t))
    }

    /// The undirected edge of `h`.
    #[inline]
    pub fn edge(&self, h: HalfEdgeId) -> EdgeId {
        self.links.he_edge[h.index()]
    }

    // ---- edges --------------------------------------------------------------------------

    /// A half-edge of `edge`: the one of the lower-numbered face corner.
    pub fn edge_half_edge(&self, edge: EdgeId) -> HalfEdgeId {
        self.links.edge_he[edge.index()]
    }

    /// The two end vertices of `edge`, in the direction of [`edge_half_edge`](Self::edge_half_edge).
    pub fn edge_vertices(&self, edge: EdgeId) -> [VertexId; 2] {
        let h = self.edge_half_edge(edge);
        [self.origin(h), self.dest(h)]
    }

    /// The faces on `edge`: one on a boundary, two inside.
    pub fn edge_faces(&self, edge: EdgeId) -> SmallVec<[FaceId; 2]> {
        let h = self.edge_half_edge(edge);
        let mut faces = SmallVec::new();
        faces.push(self.face(h));
        if let Some(t) = self.twin(h) {
            faces.push(self.face(t));
        }
        faces
    }

    /// Whether `edge` has one face.
    pub fn is_boundary_edge(&self, edge: EdgeId) -> bool {
        self.twin(self.edge_half_edge(edge)).is_none()
    }

    /// The half-edge from `a` to `b`, if there is one.
    pub fn find_half_edge(&self, a: VertexId, b: VertexId) -> Option<HalfEdgeId> {
        self.outgoing(a).find(|&h| self.dest(h) == b)
    }

    /// The edge between `a` and `b`, if there is one.
    pub fn find_edge(&self, a: VertexId, b: VertexId) -> Option<EdgeId> {
        self.find_half_edge(a, b).or_else(|| self.find_half_edge(b, a)).map(|h| self.edge(h))
    }

    // ---- vertices -----------------------------------------------------------------------

    /// Number of edges at `vertex` (0 for an isolated vertex).
    #[inline]
    pub fn valence(&self, vertex: VertexId) -> usize {
        self.links.valence[vertex.index()] as usize
    }

    /// Whether `vertex` is on a boundary edge.
    #[inline]
    pub fn is_boundary_vertex(&self, vertex: VertexId) -> bool {
        let h = self.links.vertex_he[vertex.index()];
        h != NONE && self.links.he_twin[h as usize] == NONE
    }

    /// Whether no face uses `vertex`.
    #[inline]
    pub fn is_isolated(&self, vertex: VertexId) -> bool {
        self.links.vertex_he[vertex.index()] == NONE
    }

    /// Whether `vertex` is extraordinary under `regular`: an interior vertex whose valence is
    /// not `regular.interior`, or a boundary vertex whose valence is neither `regular.boundary`
    /// nor 2. Isolated vertices are not.
    pub fn is_extraordinary(&self, vertex: VertexId, regular: RegularValence) -> bool {
        let valence = self.links.valence[vertex.index()];
        if self.is_isolated(vertex) {
            false
        } else if self.is_boundary_vertex(vertex) {
            valence != regular.boundary && valence != 2
        } else {
            valence != regular.interior
        }
    }

    /// The extraordinary vertices under `regular`, in id order.
    pub fn extraordinary_vertices(&self, regular: RegularValence) -> impl Iterator<Item = VertexId> + '_ {
        self.vertices().filter(move |&v| self.is_extraordinary(v, regular))
    }

    /// How many vertices have each valence, isolated vertices left out: `valence → count`.
    pub fn valence_histogram(&self) -> BTreeMap<usize, usize> {
        let mut histogram = BTreeMap::new();
        for v in self.vertices().filter(|&v| !self.is_isolated(v)) {
            *histogram.entry(self.valence(v)).or_insert(0) += 1;
        }
        histogram
    }

    /// The half-edges leaving `vertex`, counter-clockwise; for a boundary vertex the first one
    /// is its boundary edge (the one with no twin), so the fan is ordered from boundary to
    /// boundary.
    pub fn outgoing(&self, vertex: VertexId) -> OutgoingHalfEdges<'_> {
        let start = self.links.vertex_he[vertex.index()];
        OutgoingHalfEdges { mesh: self, start, current: start }
    }

    /// The faces around `vertex`, counter-clockwise, from the boundary for a boundary vertex.
    pub fn vertex_faces(&self, vertex: VertexId) -> impl Iterator<Item = FaceId> + '_ {
        self.outgoing(vertex).map(|h| self.face(h))
    }

    /// The ordered one-ring of `vertex`: its neighbours counter-clockwise. For a boundary vertex
    /// it runs from the far end of its leading boundary edge to the far end of its trailing
    /// boundary edge, so it has `valence` entries either way.
    pub fn one_ring(&self, vertex: VertexId) -> SmallVec<[VertexId; 8]> {
        let mut ring: SmallVec<[VertexId; 8]> = SmallVec::new();
        let mut last = None;
        for h in self.outgoing(vertex) {
            ring.push(self.dest(h));
            last = Some(h);
        }
        if let Some(h) = last
            && self.is_boundary_vertex(vertex)
        {
            ring.push(self.origin(self.prev(h)));
        }
        ring
    }

    /// The vertices at most `k` edges away from `vertex`, ring by ring: `rings[0] == [vertex]`,
    /// `rings[1]` the one-ring in fan order, and each further ring in the order it was reached.
    pub fn k_ring(&self, vertex: VertexId, k: usize) -> Vec<Vec<VertexId>> {
        let mut seen = std::collections::HashSet::from([vertex]);
        let mut rings = vec![vec![vertex]];
        for _ in 0..k {
            let mut ring = Vec::new();
            for &v in rings.last().into_iter().flatten() {
                for n in self.one_ring(v) {
                    if seen.insert(n) {
                        ring.push(n);
                    }
                }
            }
            if ring.is_empty() {
                break;
            }
            rings.push(ring);
        }
        rings
    }

    // ---- global structure ---------------------------------------------------------------

    /// The boundary loops, each as its half-edges in order, starting with the lowest half-edge.
    pub fn boundary_loops(&self) -> Vec<BoundaryLoop> {
        let mut seen = vec![false; self.half_edge_count()];
        let mut loops = Vec::new();
        for h in 0..self.half_edge_count() {
            if self.links.he_twin[h] != NONE || seen[h] {
                continue;
            }
            let mut current = h as u32;
            let mut chain = Vec::new();
            // In a manifold mesh the boundary half-edge leaving a boundary vertex is unique:
            // it is the vertex's fan start.
            while !seen[current as usize] {
                seen[current as usize] = true;
                chain.push(HalfEdgeId::new(current));
                current = self.links.vertex_he[self.dest(HalfEdgeId::new(current)).index()];
            }
            loops.push(chain);
        }
        loops
    }

    /// Connected components of the faces.
    pub fn components(&self) -> Components {
        let mut face_component = vec![NONE; self.face_count()];
        let mut count = 0u32;
        let mut stack = Vec::new();
        for seed in self.face_ids() {
            if face_component[seed.index()] != NONE {
                continue;
            }
            face_component[seed.index()] = count;
            stack.push(seed);
            while let Some(f) = stack.pop() {
                for g in self.face_neighbors(f).flatten() {
                    if face_component[g.index()] == NONE {
                        face_component[g.index()] = count;
                        stack.push(g);
                    }
                }
            }
            count += 1;
        }
        Components { face_component, count: count as usize }
    }

    /// χ = V − E + F, counting only vertices that faces use (isolated vertices left out).
    pub fn euler_characteristic(&self) -> i64 {
        let used = self.vertices().filter(|&v| !self.is_isolated(v)).count();
        used as i64 - self.edge_count() as i64 + self.face_count() as i64
    }

    /// The genus g of a connected mesh, from χ = 2 − 2g − b with b boundary loops; `None` when
    /// the mesh has no faces or several components (see [`component_genus`](Self::component_genus)).
    pub fn genus(&self) -> Option<u32> {
        let components = self.components();
        if components.count() != 1 {
            return None;
        }
        let doubled = 2 - self.boundary_loops().len() as i64 - self.euler_characteristic();
        u32::try_from(doubled / 2).ok()
    }

    /// The genus of every component, in component order.
    pub fn component_genus(&self) -> Vec<u32> {
        let components = self.components();
        let n = components.count();
        let (mut v, mut e, mut f, mut b) = (vec![0i64; n], vec![0i64; n], vec![0i64; n], vec![0i64; n]);
        for face in self.face_ids() {
            f[components.of_face(face)] += 1;
        }
        for edge in self.edges() {
            e[components.of_face(self.face(self.edge_half_edge(edge)))] += 1;
        }
        for vertex in self.vertices() {
            if let Some(h) = self.outgoing(vertex).next() {
                v[components.of_face(self.face(h))] += 1;
            }
        }
        for chain in self.boundary_loops() {
            b[components.of_face(self.face(chain[0]))] += 1;
        }
        (0..n).map(|c| u32::try_from((2 - b[c] - (v[c] - e[c] + f[c])) / 2).unwrap_or(0)).collect()
    }
}

/// Iterator over the half-edges leaving a vertex, counter-clockwise; see [`Mesh::outgoing`].
#[derive(Clone, Debug)]
pub struct OutgoingHalfEdges<'a> {
    mesh: &'a Mesh,
    start: u32,
    current: u32,
}

impl Iterator for OutgoingHalfEdges<'_> {
    type Item = HalfEdgeId;

    fn next(&mut self) -> Option<HalfEdgeId> {
        if self.current == NONE {
            return None;
        }
        let h = HalfEdgeId::new(self.current);
        let next = self.mesh.links.he_twin[self.mesh.prev(h).index()];
        self.current = if next == self.start { NONE } else { next };
        Some(h)
    }
}
