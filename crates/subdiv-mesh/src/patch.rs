//! Patch gathering: the control vertices around a face in a canonical, purely topological order,
//! and a signature that tells two patches of the same shape apart from different ones.

use hashbrown::HashMap;

use crate::{FaceId, HalfEdgeId, Mesh, Sharpness, VertexId};

/// The control vertices within `radius` rings of a face, gathered by [`Mesh::patch`].
///
/// The order is a breadth-first walk over the faces of the patch that starts at the given
/// half-edge and, in each face, visits the corners from the half-edge it entered by. It uses
/// the connectivity alone, so two patches with the same [`signature`](Self::signature) list
/// corresponding vertices at the same places, whatever the meshes and positions.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Patch {
    /// The patch's vertices, in canonical order; the face's own corners come first, starting
    /// at the origin of the start half-edge.
    pub vertices: Vec<VertexId>,
    /// The patch's shape: per face of the walk its size and, per side, the corner's place in
    /// [`vertices`](Self::vertices) and what lies across (a boundary, a face outside the patch
    /// or which face of the walk); then per vertex its valence and whether it is on a
    /// boundary; then, only where the patch has any, its sharp features: every interior side
    /// and every vertex whose sharpness is not 0, by place, with the class of its sharpness
    /// (infinitely sharp or semi-sharp). Equal signatures mean equal shapes, down to the
    /// valences of the outermost ring. A semi-sharp feature carries its sharpness (its bits):
    /// the committed sub-patch matrices hold stationary features only (sharpness 0 or
    /// infinite), and a configuration with semi-sharp features has its own matrices, derived
    /// from a mesh with it, whose shapes are told apart by the sharpness left at each level
    /// of refinement. In a patch of radius 1 only the
    /// semi-sharp features that can shape the face's surface are listed, at its corners and
    /// on the edges at them ([`Mesh::near_semi_sharp`] says why); further out the patch has
    /// the shape it would have without them.
    pub signature: Vec<u32>,
}

impl Patch {
    /// The vertices' records in a signature of a patch of `size` vertices: per vertex, in
    /// order, its valence and whether it is on a boundary.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, FaceId, Mesh, Patch};
    ///
    /// let grid = Mesh::build(shapes::quad_grid(7, 7))?;
    /// let start = grid.face_half_edges(FaceId::new(24)).next().unwrap();
    /// let patch = grid.patch(start, 1);
    /// let vertices: Vec<(u32, bool)> = Patch::signature_vertices(&patch.signature, 16).collect();
    /// assert!(vertices.iter().all(|&v| v == (4, false)));
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    pub fn signature_vertices(signature: &[u32], size: usize) -> impl Iterator<Item = (u32, bool)> + '_ {
        let end = signature.iter().position(|&x| x == SHARP_FEATURES).unwrap_or(signature.len());
        signature[end.saturating_sub(2 * size)..end].chunks_exact(2).map(|v| (v[0], v[1] == 1))
    }

    /// Whether a signature lists sharp features (infinitely sharp or semi-sharp).
    pub fn signature_has_sharp_features(signature: &[u32]) -> bool {
        signature.contains(&SHARP_FEATURES)
    }
}

/// Codes in a signature for what lies across a side; faces of the walk follow as `2 + index`.
const ACROSS_BOUNDARY: u32 = 0;
const ACROSS_OUTSIDE: u32 = 1;

/// Marks the start of a signature's sharp features (no count or place of the smooth part
/// reaches it), so that smooth patches keep the signature they had without the section.
const SHARP_FEATURES: u32 = u32::MAX;

/// The code of a sharpness class in a signature.
fn sharpness_code(sharpness: f64) -> u32 {
    match Sharpness::of(sharpness) {
        Sharpness::Smooth => 0,
        Sharpness::Infinite => 1,
        Sharpness::SemiSharp => SEMI_SHARP,
    }
}

/// The code of a semi-sharp feature in a signature; its sharpness's bits follow
/// ([`bits`]).
const SEMI_SHARP: u32 = 2;

/// A semi-sharp feature's sharpness in a signature: its bits, high word first.
fn bits(sharpness: f64) -> [u32; 2] {
    let b = sharpness.to_bits();
    [(b >> 32) as u32, b as u32]
}

impl Mesh {
    /// The rings of faces around `centre`, up to `radius`: ring 0 is `centre`, ring `r` the
    /// other vertices of the faces touching ring `r − 1`. Vertices beyond are absent.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh, VertexId};
    ///
    /// let grid = Mesh::build(shapes::quad_grid(4, 4))?;
    /// // Vertex (2, 2) of the 5 × 5 vertex grid: its faces hold the 3 × 3 block around it.
    /// let rings = grid.face_rings(&[VertexId::new(12)], 1);
    /// assert_eq!(rings.len(), 9);
    /// assert_eq!(rings[&VertexId::new(6)], 1); // (1, 1), diagonally across a face
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    pub fn face_rings(&self, centre: &[VertexId], radius: usize) -> HashMap<VertexId, usize> {
        let mut ring: HashMap<VertexId, usize> = centre.iter().map(|&v| (v, 0)).collect();
        let mut reached = centre.to_vec();
        self.grow_face_rings(&mut reached, radius, |w, r| match ring.entry(w) {
            hashbrown::hash_map::Entry::Vacant(e) => {
                e.insert(r);
                true
            }
            hashbrown::hash_map::Entry::Occupied(_) => false,
        });
        ring
    }

    /// The growth of [`face_rings`](Self::face_rings), with the caller's marks: `reached`
    /// holds ring 0 (marked), and each vertex of the faces touching ring `r − 1` that
    /// `mark(vertex, r)` newly marks is appended as ring `r`, up to `radius`.
    fn grow_face_rings(
        &self,
        reached: &mut Vec<VertexId>,
        radius: usize,
        mut mark: impl FnMut(VertexId, usize) -> bool,
    ) {
        let mut from = 0;
        for r in 1..=radius {
            let to = reached.len();
            for k in from..to {
                for f in self.vertex_faces(reached[k]) {
                    for &w in self.face_vertices(f) {
                        if mark(w, r) {
                            reached.push(w);
                        }
                    }
                }
            }
            if reached.len() == to {
                break;
            }
            from = to;
        }
    }

    /// The vertices within `radius` rings of faces of `centre` (counted as
    /// [`face_rings`](Self::face_rings) counts them), ascending: marks over the whole mesh
    /// instead of a map, for large centres (a refined level's every corner near a crease:
    /// a map of hundreds of thousands of vertices rehashed as it grew).
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh, VertexId};
    ///
    /// let grid = Mesh::build(shapes::quad_grid(4, 4))?;
    /// let near = grid.vertices_within(&[VertexId::new(12)], 1);
    /// assert_eq!(near, [6, 7, 8, 11, 12, 13, 16, 17, 18].map(VertexId::new));
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    pub fn vertices_within(&self, centre: &[VertexId], radius: usize) -> Vec<VertexId> {
        let mut marked = vec![false; self.vertex_count()];
        let mut reached: Vec<VertexId> =
            centre.iter().copied().filter(|v| !std::mem::replace(&mut marked[v.index()], true)).collect();
        self.grow_face_rings(&mut reached, radius, |w, _| !std::mem::replace(&mut marked[w.index()], true));
        reached.sort_unstable();
        reached
    }

    /// Whether a semi-sharp feature can shape the limit surface over `face`: a semi-sharp
    /// corner, or a semi-sharp edge at one of its corners. Such a face's patch (radius 1)
    /// matches no stationary shape, and this answers it without walking the patch. Features
    /// further out cannot: one refinement's points over the face (its corners' vertex points,
    /// the edge points of the edges at its corners, the face points around its corners) are
    /// made by rules that read only those features, and so are the children's, so their
    /// sharpness never reaches the face's surface (a patch's signature leaves them out).
    ///
    /// ```
    /// use subdiv_mesh::{shapes, CreaseTag, FaceId, Mesh, VertexId};
    ///
    /// let mut soup = shapes::quad_grid(4, 4);
    /// // A semi-sharp edge inside the grid, from vertex (1, 1) to (2, 1).
    /// soup.tags.creases.push(CreaseTag { vertices: [VertexId::new(6), VertexId::new(7)], sharpness: 2.0 });
    /// let grid = Mesh::build(soup)?;
    /// assert!(grid.near_semi_sharp(FaceId::new(0)));
    /// // Face (1, 2) touches the edge's faces, not the edge: its surface is the smooth one.
    /// assert!(!grid.near_semi_sharp(FaceId::new(9)));
    /// assert!(!grid.near_semi_sharp(FaceId::new(15)));
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    pub fn near_semi_sharp(&self, face: FaceId) -> bool {
        let semi = |s: f64| Sharpness::of(s) == Sharpness::SemiSharp;
        self.face_half_edges(face).any(|corner| {
            semi(self.vertex_sharpness(self.origin(corner)))
                || self
                    .outgoing(self.origin(corner))
                    .any(|h| self.twin(h).is_some() && semi(self.edge_sharpness(self.edge(h))))
        })
    }

    /// The patch of `start`'s face: every vertex within `radius` rings of faces of it (radius
    /// 0: the face's corners; 1: the corners of every face touching one of them, the 16
    /// control points of a regular Catmull-Clark patch), in canonical order.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, FaceId, Mesh};
    ///
    /// let grid = Mesh::build(shapes::quad_grid(7, 7))?;
    /// // The centre face of a 7×7 grid of quads.
    /// let face = FaceId::new(24);
    /// let start = grid.face_half_edges(face).next().unwrap();
    /// let patch = grid.patch(start, 1);
    /// assert_eq!(patch.vertices.len(), 16);
    /// assert_eq!(&patch.vertices[..4], grid.face_vertices(face));
    /// // Faces whose patches stay clear of the grid's boundary have patches of the same shape.
    /// let other = grid.face_half_edges(FaceId::new(16)).next().unwrap();
    /// assert_eq!(grid.patch(other, 1).signature, patch.signature);
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    pub fn patch(&self, start: HalfEdgeId, radius: usize) -> Patch {
        let mut patch = Patch::default();
        self.patch_into(start, radius, &mut patch);
        patch
    }

    /// [`patch`](Self::patch) into `out`, reusing its allocations: for a search over many
    /// rotations and faces, most of whose patches are looked up and dropped.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, FaceId, Mesh, Patch};
    ///
    /// let grid = Mesh::build(shapes::quad_grid(7, 7))?;
    /// let mut reused = Patch::default();
    /// for start in grid.face_half_edges(FaceId::new(24)) {
    ///     grid.patch_into(start, 1, &mut reused);
    ///     assert_eq!(reused, grid.patch(start, 1));
    /// }
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    pub fn patch_into(&self, start: HalfEdgeId, radius: usize, out: &mut Patch) {
        self.walk_patch(start, radius, false, out);
    }

    /// The patch of `start`'s face as its mirror image sees it: the same walk with every face
    /// turned over, starting along the face's last side (from `start`'s origin to the previous
    /// corner), so that the face's `u` and `v` trade places. When the signature equals
    /// [`patch`](Self::patch)'s, the patch is symmetric under that reflection, and the two
    /// vertex lists say which control point maps to which.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, FaceId, Mesh};
    ///
    /// let grid = Mesh::build(shapes::quad_grid(7, 7))?;
    /// let start = grid.face_half_edges(FaceId::new(24)).next().unwrap();
    /// let (patch, mirrored) = (grid.patch(start, 1), grid.mirrored_patch(start, 1));
    /// assert_eq!(patch.signature, mirrored.signature);
    /// // Corner 0 stays; corners 1 and 3 trade places.
    /// assert_eq!(mirrored.vertices[..4], [patch.vertices[0], patch.vertices[3], patch.vertices[2], patch.vertices[1]]);
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    pub fn mirrored_patch(&self, start: HalfEdgeId, radius: usize) -> Patch {
        let mut patch = Patch::default();
        self.walk_patch(self.prev(start), radius, true, &mut patch);
        patch
    }

    /// The walk of [`patch`](Self::patch); `mirrored` walks each face backwards, entering at
    /// the destination of the entry half-edge (see [`mirrored_patch`](Self::mirrored_patch)).
    fn walk_patch(&self, start: HalfEdgeId, radius: usize, mirrored: bool, out: &mut Patch) {
        WALK.with_borrow_mut(|scratch| scratch.walk(self, start, radius, mirrored, out));
    }
}

thread_local! {
    /// [`Mesh::walk_patch`]'s marks, per thread (the walks of one level's faces run in
    /// parallel).
    static WALK: std::cell::RefCell<WalkScratch> = std::cell::RefCell::default();
}

/// Not a place or a walk index: a vertex or face the walk has not reached.
const UNSEEN: u32 = u32::MAX;

/// Marks over a mesh's vertices and faces for one walk at a time, every one [`UNSEEN`]
/// between walks (each walk resets what it marked): a patch holds a few dozen vertices, and
/// maps keyed by them cost more in hashing than the walk itself (the car's first
/// tessellation spent 40 % of its time in the walks, most of it in their maps).
#[derive(Debug, Default)]
struct WalkScratch {
    /// Per vertex: its ring (during the rings), then its place in the patch's vertices.
    ring: Vec<u32>,
    place: Vec<u32>,
    /// Per face, its index in the walk.
    walk_index: Vec<u32>,
    ringed: Vec<VertexId>,
    walked: Vec<(FaceId, HalfEdgeId)>,
    sharp: Vec<u32>,
}

impl WalkScratch {
    fn walk(&mut self, mesh: &Mesh, start: HalfEdgeId, radius: usize, mirrored: bool, out: &mut Patch) {
        if self.ring.len() < mesh.vertex_count() {
            self.ring.resize(mesh.vertex_count(), UNSEEN);
            self.place.resize(mesh.vertex_count(), UNSEEN);
        }
        if self.walk_index.len() < mesh.face_count() {
            self.walk_index.resize(mesh.face_count(), UNSEEN);
        }
        out.vertices.clear();
        out.signature.clear();
        self.walk_marked(mesh, start, radius, mirrored, out);
        for v in self.ringed.drain(..) {
            self.ring[v.index()] = UNSEEN;
        }
        for &v in &out.vertices {
            self.place[v.index()] = UNSEEN;
        }
        for (f, _) in self.walked.drain(..) {
            self.walk_index[f.index()] = UNSEEN;
        }
    }

    /// The walk of [`Mesh::walk_patch`], leaving its marks for [`walk`](Self::walk) to reset.
    fn walk_marked(&mut self, mesh: &Mesh, start: HalfEdgeId, radius: usize, mirrored: bool, out: &mut Patch) {
        let start_face = mesh.face(start);
        // The rings of faces around the face's corners, as `Mesh::face_rings` counts them.
        for &v in mesh.face_vertices(start_face) {
            self.ring[v.index()] = 0;
            self.ringed.push(v);
        }
        let ring = &mut self.ring;
        mesh.grow_face_rings(&mut self.ringed, radius, |w, r| {
            let seen = ring[w.index()] != UNSEEN;
            if !seen {
                ring[w.index()] = r as u32;
            }
            !seen
        });
        let ring = &self.ring;
        // The patch's faces touch a vertex of ring < radius (the face itself when radius is 0).
        let in_patch =
            |f: FaceId| f == start_face || mesh.face_vertices(f).iter().any(|v| ring[v.index()] < radius as u32);

        let Patch { vertices, signature } = out;
        // (side number in walk order, class) of the sharp interior sides; boundary sides are
        // told by `ACROSS_BOUNDARY` (refinement makes them infinitely sharp anyway).
        let sharp = &mut self.sharp;
        sharp.clear();
        let mut side = 0u32;
        self.walk_index[start_face.index()] = 0;
        // The faces in the order the walk reaches them, with their entry half-edges: the
        // walk's queue, breadth first.
        self.walked.push((start_face, start));
        let mut next = 0;
        while let Some(&(_, entry)) = self.walked.get(next) {
            next += 1;
            let size = mesh.face_size(mesh.face(entry));
            signature.push(size as u32);
            let mut h = entry;
            for _ in 0..size {
                let v = if mirrored { mesh.dest(h) } else { mesh.origin(h) };
                let p = &mut self.place[v.index()];
                if *p == UNSEEN {
                    *p = vertices.len() as u32;
                    vertices.push(v);
                }
                signature.push(*p);
                let sharpness = mesh.edge_sharpness(mesh.edge(h));
                let class = sharpness_code(sharpness);
                let at_corner = ring[mesh.origin(h).index()] == 0 || ring[mesh.dest(h).index()] == 0;
                if class != 0 && mesh.twin(h).is_some() && (class != SEMI_SHARP || at_corner || radius > 1) {
                    sharp.extend([side, class]);
                    if class == SEMI_SHARP {
                        sharp.extend(bits(sharpness));
                    }
                }
                side += 1;
                signature.push(match mesh.twin(h) {
                    None => ACROSS_BOUNDARY,
                    Some(t) if !in_patch(mesh.face(t)) => ACROSS_OUTSIDE,
                    Some(t) => {
                        let index = &mut self.walk_index[mesh.face(t).index()];
                        if *index == UNSEEN {
                            *index = self.walked.len() as u32;
                            self.walked.push((mesh.face(t), t));
                        }
                        2 + *index
                    }
                });
                h = if mirrored { mesh.prev(h) } else { mesh.next(h) };
            }
        }
        for &v in vertices.iter() {
            signature.push(mesh.valence(v) as u32);
            signature.push(u32::from(mesh.is_boundary_vertex(v)));
        }
        let corners_at = signature.len();
        for (p, &v) in vertices.iter().enumerate() {
            let sharpness = mesh.vertex_sharpness(v);
            let class = sharpness_code(sharpness);
            if class != 0 && (class != SEMI_SHARP || ring[v.index()] == 0 || radius > 1) {
                signature.extend([p as u32, class]);
                if class == SEMI_SHARP {
                    signature.extend(bits(sharpness));
                }
            }
        }
        if !sharp.is_empty() || signature.len() > corners_at {
            // Sides, then vertices, each after a mark: a side count is never `SHARP_FEATURES`.
            let corners = signature.len() - corners_at;
            signature.splice(corners_at..corners_at, std::iter::once(SHARP_FEATURES).chain(sharp.iter().copied()));
            signature.insert(signature.len() - corners, SHARP_FEATURES);
        }
    }
}
