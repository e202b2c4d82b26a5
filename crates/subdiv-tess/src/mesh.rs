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
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TessMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Unit normals from the exact tangents (at an extraordinary vertex from its limit tangent
    /// directions).
    pub normals: Vec<DVec3>,
    /// Per vertex, its parameter point.
    pub parameters: Vec<SurfaceParameter>,
    /// Triangles, counter-clockwise as the input faces.
    pub triangles: Vec<[u32; 3]>,
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
            parameters,
            triangles,
            triangle_faces,
            triangle_parameters,
            polygon_offsets,
            polygon_vertices,
            polygon_faces,
        } = self;
        positions.clear();
        normals.clear();
        parameters.clear();
        triangles.clear();
        triangle_faces.clear();
        triangle_parameters.clear();
        polygon_offsets.clear();
        polygon_vertices.clear();
        polygon_faces.clear();
    }

    /// The triangles as a flat index list (for GPU buffers and GLB).
    pub fn triangle_indices(&self) -> Vec<u32> {
        self.triangles.iter().flatten().copied().collect()
    }
}
