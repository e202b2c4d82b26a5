//! A part of a mesh as a mesh of its own: what local refinement works on.

use hashbrown::HashMap;

use crate::{CornerTag, CreaseTag, FaceId, Mesh, MeshError, PolygonSoup, Tags, VertexId};

/// A mesh made of some faces of another, with the maps back: [`Mesh::region`].
#[derive(Clone, Debug)]
pub struct Region {
    /// The faces as a mesh: their vertices (positions copied), the sharpness of their edges and
    /// vertices and their holes as tags, and the source's rules (boundary interpolation,
    /// crease method, triangle rule).
    pub mesh: Mesh,
    /// The source's vertex of each of the region's vertices.
    pub vertices: Vec<VertexId>,
    /// The source's face of each of the region's faces, in the source's order.
    pub faces: Vec<FaceId>,
}

impl Region {
    /// The region's face of the source's `face`, if it holds it.
    pub fn face_of(&self, face: FaceId) -> Option<FaceId> {
        self.faces.binary_search(&face).ok().map(|i| FaceId::new(i as u32))
    }
}

impl Mesh {
    /// The faces within `rings` rings of `faces` (every face touching a vertex within `rings`
    /// rings of faces of theirs), with each vertex's fan completed where the faces found
    /// around it do not form one fan, so that the region is a manifold mesh: the part of the
    /// mesh whose refinement near `faces` equals the whole mesh's. Rings count as
    /// [`vertices_within`](Self::vertices_within) does.
    ///
    /// ```
    /// use subdiv_mesh::{shapes, FaceId, Mesh};
    ///
    /// let grid = Mesh::build(shapes::quad_grid(9, 9))?;
    /// // The centre face and one ring of faces around its corners: a 5 × 5 block.
    /// let region = grid.region(&[FaceId::new(40)], 1)?;
    /// assert_eq!(region.faces.len(), 25);
    /// assert_eq!(region.mesh.face_count(), 25);
    /// assert_eq!(region.face_of(FaceId::new(40)).map(|f| region.faces[f.index()]), Some(FaceId::new(40)));
    /// # Ok::<(), subdiv_mesh::MeshError>(())
    /// ```
    ///
    /// # Errors
    /// None for a valid mesh; the region is built with [`Mesh::build`], whose errors would
    /// mean a bug here.
    pub fn region(&self, faces: &[FaceId], rings: usize) -> Result<Region, MeshError> {
        let mut corners: Vec<VertexId> = faces.iter().flat_map(|&f| self.face_vertices(f).iter().copied()).collect();
        corners.sort_unstable();
        corners.dedup();
        let mut inside = vec![false; self.face_count()];
        for v in self.vertices_within(&corners, rings) {
            for f in self.vertex_faces(v) {
                inside[f.index()] = true;
            }
        }
        // A vertex whose faces inside are not one contiguous fan would be non-manifold in the
        // region: take its whole fan, until every vertex is fine. Only the corners of faces
        // inside can be split (a small region of a large level is checked at its own cost).
        let mut faces: Vec<FaceId> = self.face_ids().filter(|f| inside[f.index()]).collect();
        let mut check: Vec<VertexId> = faces.iter().flat_map(|&f| self.face_vertices(f).iter().copied()).collect();
        while let Some(v) = check.pop() {
            if self.fan_is_split(v, &inside) {
                for f in self.vertex_faces(v) {
                    if !std::mem::replace(&mut inside[f.index()], true) {
                        faces.push(f);
                        check.extend_from_slice(self.face_vertices(f));
                    }
                }
            }
        }
        faces.sort_unstable();
        self.region_of(faces)
    }

    /// Whether the faces of `v` marked `inside` are more than one run of its fan.
    fn fan_is_split(&self, v: VertexId, inside: &[bool]) -> bool {
        let fan: Vec<bool> = self.outgoing(v).map(|h| inside[self.face(h).index()]).collect();
        // Runs of faces inside, by their first faces; an interior vertex's fan wraps around.
        let closed = !self.is_boundary_vertex(v);
        let before = |i: usize| if i > 0 { fan[i - 1] } else { closed && fan[fan.len() - 1] };
        (0..fan.len()).filter(|&i| fan[i] && !before(i)).count() > 1
    }

    fn region_of(&self, faces: Vec<FaceId>) -> Result<Region, MeshError> {
        let mut local: HashMap<VertexId, VertexId> = HashMap::new();
        let mut vertices = Vec::new();
        let mut soup = PolygonSoup::new();
        for &f in &faces {
            let corners: Vec<VertexId> = self
                .face_vertices(f)
                .iter()
                .map(|&v| {
                    *local.entry(v).or_insert_with(|| {
                        vertices.push(v);
                        soup.push_vertex(self.position(v))
                    })
                })
                .collect();
            let id = soup.push_face(corners);
            if self.is_hole(f) {
                soup.tags.holes.push(id);
            }
        }
        let mut tags = Tags {
            boundary_interpolation: self.tags().boundary_interpolation,
            face_varying_interpolation: self.tags().face_varying_interpolation,
            crease_method: self.tags().crease_method,
            triangle_subdivision: self.tags().triangle_subdivision,
            holes: std::mem::take(&mut soup.tags.holes),
            ..Tags::default()
        };
        // The region's sharp edges, in the source's order (the edges of its faces: a small
        // region of a large level is read at its own cost).
        let mut sharp: Vec<_> = faces
            .iter()
            .flat_map(|&f| self.face_half_edges(f).map(|h| self.edge(h)))
            .filter(|&e| self.edge_sharpness(e) > 0.0)
            .collect();
        sharp.sort_unstable();
        sharp.dedup();
        for e in sharp {
            let [a, b] = self.edge_vertices(e).map(|v| local[&v]);
            tags.creases.push(CreaseTag { vertices: [a, b], sharpness: self.edge_sharpness(e) });
        }
        for (&v, &l) in &local {
            if self.vertex_sharpness(v) > 0.0 {
                tags.corners.push(CornerTag { vertex: l, sharpness: self.vertex_sharpness(v) });
            }
        }
        tags.corners.sort_by_key(|c| c.vertex);
        soup.tags = tags;
        Ok(Region { mesh: Mesh::build(soup)?, vertices, faces })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    #[test]
    fn regions_keep_sharpness_holes_and_rules() {
        let mut soup = shapes::quad_grid(6, 6);
        soup.tags.creases.push(CreaseTag { vertices: [VertexId::new(15), VertexId::new(16)], sharpness: 2.5 });
        soup.tags.corners.push(CornerTag { vertex: VertexId::new(16), sharpness: 10.0 });
        soup.tags.holes.push(FaceId::new(14));
        soup.tags.crease_method = Some(crate::CreaseMethod::Chaikin);
        let mesh = Mesh::build(soup).unwrap();
        let region = mesh.region(&[FaceId::new(14)], 1).unwrap();
        let r = &region.mesh;
        let local = |v: u32| VertexId::new(region.vertices.iter().position(|&x| x == VertexId::new(v)).unwrap() as u32);
        let e = r.find_edge(local(15), local(16)).unwrap();
        assert_eq!(r.edge_sharpness(e), 2.5);
        assert_eq!(r.vertex_sharpness(local(16)), 10.0);
        assert!(r.is_hole(region.face_of(FaceId::new(14)).unwrap()));
        assert_eq!(r.tags().crease_method, Some(crate::CreaseMethod::Chaikin));
        for v in r.vertices() {
            assert_eq!(r.position(v), mesh.position(region.vertices[v.index()]));
        }
    }

    #[test]
    fn pinched_fans_are_split() {
        // Cells (0, 0) and (1, 1) of an 8 × 8 grid touch at vertex (1, 1) only: two runs of
        // its fan, which a region must complete.
        let grid = Mesh::build(shapes::quad_grid(8, 8)).unwrap();
        let mut inside = vec![false; grid.face_count()];
        inside[0] = true;
        inside[9] = true;
        assert!(grid.fan_is_split(VertexId::new(10), &inside));
        inside[1] = true;
        assert!(!grid.fan_is_split(VertexId::new(10), &inside));
        // Far apart faces make two pieces, each manifold.
        let region = grid.region(&[FaceId::new(0), FaceId::new(63)], 0).unwrap();
        assert_eq!((region.mesh.face_count(), region.faces.len()), (8, 8));
    }
}
