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
///
/// **Channels.** Face-varying channels (texture coordinates) are carried by the dual
/// tessellator ([`DualOptions::channels`](crate::DualOptions::channels)): every point — vertex
/// and extra normal — has every channel's exact limit value in [`channels`](Self::channels).
/// A seam of a channel (an edge whose two faces use different values) is cut like a crease:
/// the output stays welded in positions, and a point on the seam has the first side's values
/// as a vertex and the second side's as an extra normal (its normal equals the vertex's, the
/// surface being smooth there), so the flat outputs split it into one vertex per side.
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
    /// Per extra normal `normals[positions.len() + k]`, the parameter point it was evaluated at:
    /// its vertex's point seen from a face of its own sector (or side of a seam).
    pub normal_parameters: Vec<SurfaceParameter>,
    /// The face-varying channels' values at every point (the vertices, then the extra normals);
    /// empty without channels.
    pub channels: TessChannels,
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
            normal_parameters,
            channels,
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
        normal_parameters.clear();
        channels.clear();
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

    /// The part of the tessellation whose triangles and polygons belong to the input faces
    /// `keep` takes, with the vertices and extra normals they use, in their order here (each
    /// point's values as they are: a point on the part's border is the same bits as in the
    /// other parts that use it).
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::Builtin;
    /// use subdiv_tess::{DualOptions, DualTessellator};
    ///
    /// let cube = Mesh::build(shapes::cube())?;
    /// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &cube, &DualOptions::default())?;
    /// let whole = tess.tessellate(&[4; 6])?;
    /// let (low, high) = (whole.part(|f| f.index() < 3), whole.part(|f| f.index() >= 3));
    /// assert_eq!(low.triangles.len() + high.triangles.len(), whole.triangles.len());
    /// // The points along the border between the halves are in both.
    /// assert!(low.positions.len() + high.positions.len() > whole.positions.len());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn part(&self, keep: impl Fn(FaceId) -> bool) -> TessMesh {
        let vertices = self.positions.len();
        let triangles: Vec<usize> = (0..self.triangles.len()).filter(|&t| keep(self.triangle_faces[t])).collect();
        let polygons: Vec<usize> = (0..self.polygon_count()).filter(|&k| keep(self.polygon_faces[k])).collect();
        // Old point (vertex, then extra normal) → new, `u32::MAX` where unused.
        let mut used = vec![false; self.normals.len().max(vertices)];
        for &t in &triangles {
            for &v in &self.triangles[t] {
                used[v as usize] = true;
            }
            for &n in &self.triangle_normals[t] {
                used[n as usize] = true;
            }
        }
        for &k in &polygons {
            for &v in self.polygon(k) {
                used[v as usize] = true;
            }
        }
        let mut new = vec![u32::MAX; used.len()];
        let mut out = TessMesh {
            channels: TessChannels {
                names: self.channels.names.clone(),
                dimensions: self.channels.dimensions.clone(),
                values: Vec::new(),
            },
            ..TessMesh::default()
        };
        let stride = self.channels.stride();
        let mut next = 0u32;
        for v in (0..vertices).filter(|&v| used[v]) {
            new[v] = next;
            next += 1;
            out.positions.push(self.positions[v]);
            out.normals.push(self.normals[v]);
            out.parameters.push(self.parameters[v]);
        }
        for k in (vertices..self.normals.len()).filter(|&k| used[k]) {
            new[k] = next;
            next += 1;
            out.normals.push(self.normals[k]);
            out.normal_vertices.push(new[self.normal_vertices[k - vertices] as usize]);
            out.normal_parameters.push(self.normal_parameters[k - vertices]);
        }
        if stride > 0 {
            let points = (0..vertices).filter(|&v| used[v]).chain((vertices..self.normals.len()).filter(|&k| used[k]));
            for k in points {
                out.channels.values.extend_from_slice(self.channels.point(k));
            }
        }
        let map = |corners: [u32; 3]| corners.map(|c| new[c as usize]);
        for &t in &triangles {
            out.triangles.push(map(self.triangles[t]));
            out.triangle_normals.push(map(self.triangle_normals[t]));
            out.triangle_faces.push(self.triangle_faces[t]);
            if let Some(&p) = self.triangle_parameters.get(t) {
                out.triangle_parameters.push(p);
            }
        }
        if !polygons.is_empty() {
            out.polygon_offsets.push(0);
            for &k in &polygons {
                out.polygon_vertices.extend(self.polygon(k).iter().map(|&v| new[v as usize]));
                out.polygon_offsets.push(out.polygon_vertices.len() as u32);
                out.polygon_faces.push(self.polygon_faces[k]);
            }
        }
        out
    }
}

/// Face-varying channels' values at a tessellation's points (see [`TessMesh`]'s channels).
///
/// ```
/// use subdiv_mesh::{shapes, Channel, Mesh};
/// use subdiv_schemes::Builtin;
/// use subdiv_tess::{DualOptions, DualTessellator};
///
/// // A cube whose six faces each map the whole unit square: every edge is a seam.
/// let mut soup = shapes::cube();
/// let square = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
/// soup.channels.push(Channel::new("uv", 2, square.repeat(6), (0..24).map(|i| i % 4).collect()));
/// let mesh = Mesh::build(soup)?;
/// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::DEFAULT)?;
/// let out = tess.tessellate(&[4; 6])?;
/// let uv = out.channels.find("uv").expect("the mesh's channel");
/// assert_eq!(out.channels.stride(), 2);
/// // One value per point: the vertices, then the seams' second sides.
/// assert_eq!(out.channels.values.len(), 2 * out.normals.len());
/// assert!(out.normals.len() > out.positions.len());
/// // Each face maps the square; its corners' points take its corners' values.
/// assert!(out.channels.values.iter().all(|x| (-1e-12..=1.0 + 1e-12).contains(x)));
/// assert_eq!(out.channels.point(0)[uv].len(), 2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TessChannels {
    /// The channels' names, in the mesh's order (`"uv"` for texture coordinates).
    pub names: Vec<String>,
    /// Per channel, its number of components.
    pub dimensions: Vec<usize>,
    /// Per point, every channel's components, channel after channel: [`stride`](Self::stride)
    /// numbers per point.
    pub values: Vec<f64>,
}

impl TessChannels {
    /// The number of channel components per point: the sum of the dimensions.
    pub fn stride(&self) -> usize {
        self.dimensions.iter().sum()
    }

    /// Whether there are no channels.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Where channel `name`'s components lie within a point's values, if there is one.
    pub fn find(&self, name: &str) -> Option<std::ops::Range<usize>> {
        let k = self.names.iter().position(|n| n == name)?;
        let start = self.dimensions[..k].iter().sum();
        Some(start..start + self.dimensions[k])
    }

    /// Where the texture coordinates start within a point's values: the channel named `"uv"`
    /// ([`Channel::UV`](subdiv_mesh::Channel::UV)), its first two components, if it has two
    /// or more.
    pub fn texcoords(&self) -> Option<usize> {
        self.find(subdiv_mesh::Channel::UV).filter(|r| r.len() >= 2).map(|r| r.start)
    }

    /// Point `k`'s values (every channel's; empty without channels).
    pub fn point(&self, k: usize) -> &[f64] {
        let stride = self.stride();
        &self.values[k * stride..(k + 1) * stride]
    }

    /// Empties the lists, keeping their allocations.
    pub fn clear(&mut self) {
        self.names.clear();
        self.dimensions.clear();
        self.values.clear();
    }
}
