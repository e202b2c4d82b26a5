//! The tessellators' output.

use glam::DVec3;
use subdiv_mesh::FaceId;

/// Where an output vertex lies on the surface: an input face and its `Bfr` parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceParameter {
    /// The input face (the first, in face order, of the faces sharing the point).
    pub face: FaceId,
    /// `u` in the face's `Bfr` parameterization.
    pub u: f64,
    /// `v` in the face's `Bfr` parameterization.
    pub v: f64,
}

/// A tessellation of a limit surface: every vertex is a point of the surface, evaluated once;
/// vertices are shared wherever their parameter points are (watertight by construction).
///
/// **Split normals.** The topology is welded (one vertex per position), but a vertex on an
/// infinitely sharp crease has one normal per smooth *sector* around it (the faces between two
/// consecutive sharp edges): `normals[v]` (`v < positions.len()`) is its first sector's, and each
/// further sector's is an *extra normal* `normals[positions.len() + k]`, whose vertex is
/// [`normal_vertices[k]`](Self::normal_vertices). Each triangle corner names its normal in
/// [`triangle_normals`](Self::triangle_normals). Outputs with one normal per vertex (GLB, GPU
/// buffers, [`FlatMesh`](crate::FlatMesh)) split exactly those vertices: the flat vertices are the
/// vertices, then one copy per extra normal, and the flat triangles are `triangle_normals`.
/// Without sharp creases there are no extra normals and `triangle_normals == triangles`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TessMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Unit normals from the exact tangents (at an extraordinary vertex from its limit tangent
    /// directions): one per vertex, then the extra normals (see the type's docs), each from the
    /// one-sided derivatives of a face of its sector.
    pub normals: Vec<DVec3>,
    /// Per extra normal `normals[positions.len() + k]`, the vertex it belongs to.
    pub normal_vertices: Vec<u32>,
    /// Per vertex, its parameter point.
    pub parameters: Vec<SurfaceParameter>,
    /// Triangles, counter-clockwise as the input faces.
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle, its corners' normals: indices into [`normals`](Self::normals), equal to
    /// the corners' vertices but where a corner lies on a crease in a further sector (then an
    /// extra normal of that vertex). The triangles of the flat outputs.
    pub triangle_normals: Vec<[u32; 3]>,
    /// Per triangle, its input face.
    pub triangle_faces: Vec<FaceId>,
    /// Per triangle, its corners' `Bfr` parameters `[u, v]` in its own face (a vertex shared
    /// with another face lists that face's parameters in [`parameters`](Self::parameters)).
    pub triangle_parameters: Vec<[[f64; 2]; 3]>,
    /// Polygons: `polygon_offsets[k]..polygon_offsets[k + 1]` indexes
    /// [`polygon_vertices`](Self::polygon_vertices). The polygons do not use the centre vertices
    /// that the triangles fan around.
    pub polygon_offsets: Vec<u32>,
    /// The polygons' vertices.
    pub polygon_vertices: Vec<u32>,
    /// Per polygon, its input face.
    pub polygon_faces: Vec<FaceId>,
}

impl TessMesh {
    /// The number of polygons.
    pub fn polygon_count(&self) -> usize {
        self.polygon_faces.len()
    }

    /// The vertices of polygon `k`.
    pub fn polygon(&self, k: usize) -> &[u32] {
        &self.polygon_vertices[self.polygon_offsets[k] as usize..self.polygon_offsets[k + 1] as usize]
    }

    /// Empties every list, keeping their allocations.
    pub fn clear(&mut self) {
        // Destructured, so that a new field cannot be forgotten here.
        let Self {
            positions,
            normals,
            normal_vertices,
            parameters,
            triangles,
            triangle_normals,
            triangle_faces,
            triangle_parameters,
            polygon_offsets,
            polygon_vertices,
            polygon_faces,
        } = self;
        positions.clear();
        normals.clear();
        normal_vertices.clear();
        parameters.clear();
        triangles.clear();
        triangle_normals.clear();
        triangle_faces.clear();
        triangle_parameters.clear();
        polygon_offsets.clear();
        polygon_vertices.clear();
        polygon_faces.clear();
    }

    /// The triangles as a flat index list into the flat vertices (the vertices, then one per
    /// extra normal: see the type's docs), for GPU buffers and GLB: [`triangle_normals`](Self::triangle_normals),
    /// flattened.
    pub fn flat_indices(&self) -> Vec<u32> {
        self.triangle_normals.as_flattened().to_vec()
    }

    /// The number of flat vertices: the vertices and the extra normals (`normals.len()`).
    pub fn flat_vertex_count(&self) -> usize {
        self.positions.len() + self.normal_vertices.len()
    }
}
