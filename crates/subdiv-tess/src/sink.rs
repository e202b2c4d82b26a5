//! Output sinks: where a tessellation goes (lyon's `GeometryBuilder` in spirit).
//!
//! A tessellator does not choose the caller's vertex type. It hands its output to a
//! [`TessSink`]: first [`begin`](TessSink::begin) with the counts (so that the sink reserves or
//! resizes once, and no call after it allocates), then every vertex in index order, every
//! extra normal in index order (the further normals of crease vertices, see [`TessMesh`]'s
//! split normals), every triangle in output order, the polygons in output order if the sink
//! [wants them](TessSink::wants_polygons), and [`end`](TessSink::end). Three sinks come with
//! the crate:
//!
//! - [`TessMesh`]: everything, in f64 (what [`QuadtreeTessellator::tessellate`] and
//!   [`DualTessellator::tessellate`] return);
//! - [`FlatMesh`]: `px py pz nx ny nz` as f32 and `u32` triangle indices, the bytes
//!   [`DualTessellator::write_flat`] writes;
//! - [`BuffersBuilder`]: a caller's own [`bytemuck::Pod`] vertex type, made by a closure from
//!   each [`TessVertex`], into [`VertexBuffers`] that a renderer uploads as they are
//!   (`bytemuck::cast_slice(&buffers.vertices)`).
//!
//! The last two are **flat**: one normal per vertex, so a vertex with extra normals is split,
//! the vertices followed by one copy per extra normal (its vertex's position and parameter,
//! that normal), and each triangle indexes them by [`TessTriangle::normals`].
//!
//! Both tessellators write into a sink ([`DualTessellator::tessellate_into`],
//! [`QuadtreeTessellator::tessellate_into`]), and any [`TessMesh`] can be replayed into one
//! ([`TessMesh::write_to`]). A sink is called only when the tessellation succeeded: on an
//! error it is left as it was.
//!
//! ```
//! use subdiv_mesh::{shapes, Mesh};
//! use subdiv_schemes::Builtin;
//! use subdiv_tess::{BuffersBuilder, DualOptions, DualTessellator, TessVertex, VertexBuffers};
//!
//! /// The vertex a renderer wants: position and the face's parameters, 20 bytes.
//! #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
//! #[repr(C)]
//! struct Vertex {
//!     position: [f32; 3],
//!     uv: [f32; 2],
//! }
//!
//! let mesh = Mesh::build(shapes::cube())?;
//! let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::DEFAULT)?;
//! let mut buffers: VertexBuffers<Vertex> = VertexBuffers::new();
//! let rates = vec![4; mesh.face_count()];
//! tess.tessellate_into(&rates, &mut BuffersBuilder::new(&mut buffers, |v: &TessVertex<'_>| Vertex {
//!     position: v.position.as_vec3().to_array(),
//!     uv: [v.parameter.u as f32, v.parameter.v as f32],
//! }))?;
//! let bytes: &[u8] = bytemuck::cast_slice(&buffers.vertices);
//! assert_eq!(bytes.len(), 20 * buffers.vertices.len());
//! assert_eq!(buffers.indices.len(), 3 * tess.mesh().triangles.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! [`QuadtreeTessellator::tessellate`]: crate::QuadtreeTessellator::tessellate
//! [`QuadtreeTessellator::tessellate_into`]: crate::QuadtreeTessellator::tessellate_into
//! [`DualTessellator::tessellate`]: crate::DualTessellator::tessellate
//! [`DualTessellator::tessellate_into`]: crate::DualTessellator::tessellate_into
//! [`DualTessellator::write_flat`]: crate::DualTessellator::write_flat

use glam::DVec3;
use subdiv_mesh::FaceId;

use crate::dual::flat_vertex;
use crate::{FlatMesh, SurfaceParameter, TessMesh};

/// How much a tessellation will hand to a sink, given to [`TessSink::begin`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TessCounts {
    /// The number of vertices.
    pub vertices: usize,
    /// The number of extra normals (further normals of crease vertices, see [`TessMesh`]):
    /// [`TessSink::normal`] is called for indices `vertices..vertices + extra_normals`.
    pub extra_normals: usize,
    /// The number of triangles.
    pub triangles: usize,
    /// The number of polygons the sink will get (0 unless it
    /// [wants them](TessSink::wants_polygons) and the tessellation has them).
    pub polygons: usize,
    /// The number of vertex indices over those polygons.
    pub polygon_vertices: usize,
    /// The number of channel values per point ([`TessVertex::channels`]' length: every
    /// channel's components, see [`TessChannels`](crate::TessChannels)).
    pub channels: usize,
    /// Whether the vertices have [texture coordinates](TessVertex::texcoords).
    pub texcoords: bool,
}

/// An output vertex: a limit point of the surface, evaluated once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TessVertex<'a> {
    /// The position.
    pub position: DVec3,
    /// The unit normal from the exact tangents (at an extraordinary vertex from its limit
    /// tangent directions).
    pub normal: DVec3,
    /// The face and `Bfr` parameters the vertex was evaluated at.
    pub parameter: SurfaceParameter,
    /// Its face-varying channels' values there, channel after channel ([`TessCounts::channels`]
    /// of them; empty without channels).
    pub channels: &'a [f64],
    /// Its texture coordinates, if the tessellation carries them: the `"uv"` channel's first
    /// two components (also in [`channels`](Self::channels)), what GLB's `TEXCOORD_0` and a
    /// renderer take.
    pub texcoords: Option<[f64; 2]>,
}

/// An output triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TessTriangle {
    /// Its vertices, counter-clockwise as the input faces.
    pub vertices: [u32; 3],
    /// Its corners' normals: the vertex's own (the same index), or an extra normal's index
    /// (at least the vertex count), as [`TessMesh::triangle_normals`]. A flat sink's indices.
    pub normals: [u32; 3],
    /// Its input face.
    pub face: FaceId,
    /// Its corners' `Bfr` parameters `[u, v]` in its own face (see
    /// [`TessMesh::triangle_parameters`]).
    pub parameters: [[f64; 2]; 3],
}

/// Receives a tessellation: [`begin`](Self::begin), then every vertex (indices `0..`
/// in order), every extra normal (indices from the vertex count on, in order), every triangle
/// in output order, the polygons in output order if
/// [`wants_polygons`](Self::wants_polygons), and [`end`](Self::end).
///
/// Implement it to put the output straight into one's own buffers (see the [module
/// docs](self)); [`BuffersBuilder`] covers the common case of a `Pod` vertex type.
pub trait TessSink {
    /// Called first, once, with the counts of what follows: reserve or resize here.
    fn begin(&mut self, counts: &TessCounts);

    /// Vertex `index` (called for `0, 1, 2, …` in order).
    fn vertex(&mut self, index: u32, vertex: &TessVertex<'_>);

    /// Extra normal `index` (called for `V, V + 1, …` in order after the `V` vertices): a
    /// further normal of vertex `vertex`, on an infinitely sharp crease, in another smooth
    /// sector around it. `split` is the vertex with that normal (its position and parameter),
    /// the split copy a flat sink appends. The default ignores it (one normal per vertex).
    fn normal(&mut self, index: u32, vertex: u32, split: &TessVertex<'_>) {
        let _ = (index, vertex, split);
    }

    /// Triangle `index` (called for `0, 1, 2, …` in order).
    fn triangle(&mut self, index: u32, triangle: &TessTriangle);

    /// Whether the sink takes polygons (the dual tessellator's quads, where its options list
    /// them; the quadtree's leaves with their hanging vertices). Default: `false`.
    fn wants_polygons(&self) -> bool {
        false
    }

    /// Polygon `index` of input face `face`: its vertices, counter-clockwise. Only called
    /// when [`wants_polygons`](Self::wants_polygons); the default ignores it.
    fn polygon(&mut self, index: u32, vertices: &[u32], face: FaceId) {
        let _ = (index, vertices, face);
    }

    /// Called last, once. The default does nothing.
    fn end(&mut self) {}
}

impl<S: TessSink + ?Sized> TessSink for &mut S {
    fn begin(&mut self, counts: &TessCounts) {
        (**self).begin(counts);
    }

    fn vertex(&mut self, index: u32, vertex: &TessVertex<'_>) {
        (**self).vertex(index, vertex);
    }

    fn normal(&mut self, index: u32, vertex: u32, split: &TessVertex<'_>) {
        (**self).normal(index, vertex, split);
    }

    fn triangle(&mut self, index: u32, triangle: &TessTriangle) {
        (**self).triangle(index, triangle);
    }

    fn wants_polygons(&self) -> bool {
        (**self).wants_polygons()
    }

    fn polygon(&mut self, index: u32, vertices: &[u32], face: FaceId) {
        (**self).polygon(index, vertices, face);
    }

    fn end(&mut self) {
        (**self).end();
    }
}

/// Everything: the mesh is cleared (keeping its allocations) and refilled, equal to the
/// tessellator's own [`TessMesh`] output.
impl TessSink for TessMesh {
    fn begin(&mut self, counts: &TessCounts) {
        self.clear();
        self.positions.reserve(counts.vertices);
        self.normals.reserve(counts.vertices + counts.extra_normals);
        self.normal_vertices.reserve(counts.extra_normals);
        self.parameters.reserve(counts.vertices);
        self.normal_parameters.reserve(counts.extra_normals);
        self.channels.values.reserve(counts.channels * (counts.vertices + counts.extra_normals));
        self.triangles.reserve(counts.triangles);
        self.triangle_normals.reserve(counts.triangles);
        self.triangle_faces.reserve(counts.triangles);
        self.triangle_parameters.reserve(counts.triangles);
        self.polygon_offsets.reserve(counts.polygons + 1);
        self.polygon_offsets.push(0);
        self.polygon_vertices.reserve(counts.polygon_vertices);
        self.polygon_faces.reserve(counts.polygons);
    }

    #[inline]
    fn vertex(&mut self, _: u32, vertex: &TessVertex<'_>) {
        self.positions.push(vertex.position);
        self.normals.push(vertex.normal);
        self.parameters.push(vertex.parameter);
        self.channels.values.extend_from_slice(vertex.channels);
    }

    fn normal(&mut self, _: u32, vertex: u32, split: &TessVertex<'_>) {
        self.normals.push(split.normal);
        self.normal_vertices.push(vertex);
        self.normal_parameters.push(split.parameter);
        self.channels.values.extend_from_slice(split.channels);
    }

    #[inline]
    fn triangle(&mut self, _: u32, triangle: &TessTriangle) {
        self.triangles.push(triangle.vertices);
        self.triangle_normals.push(triangle.normals);
        self.triangle_faces.push(triangle.face);
        self.triangle_parameters.push(triangle.parameters);
    }

    fn wants_polygons(&self) -> bool {
        true
    }

    fn polygon(&mut self, _: u32, vertices: &[u32], face: FaceId) {
        self.polygon_vertices.extend_from_slice(vertices);
        self.polygon_offsets.push(self.polygon_vertices.len() as u32);
        self.polygon_faces.push(face);
    }
}

/// `px py pz nx ny nz` in f32 per flat vertex (the vertices, then one split copy per extra
/// normal), the texture coordinates if the tessellation has them, and three `u32` indices per
/// triangle ([`TessTriangle::normals`]), the buffers cleared (keeping their allocations) and
/// refilled: the bytes of [`DualTessellator::write_flat`](crate::DualTessellator::write_flat).
impl TessSink for FlatMesh {
    fn begin(&mut self, counts: &TessCounts) {
        let points = counts.vertices + counts.extra_normals;
        self.vertices.clear();
        self.vertices.reserve(6 * points);
        self.texcoords.clear();
        if counts.texcoords {
            self.texcoords.reserve(2 * points);
        }
        self.indices.clear();
        self.indices.reserve(3 * counts.triangles);
    }

    #[inline]
    fn vertex(&mut self, _: u32, vertex: &TessVertex<'_>) {
        self.vertices.extend_from_slice(&flat_vertex(vertex.position, vertex.normal));
        self.texcoords.extend(vertex.texcoords.into_iter().flatten().map(|x| x as f32));
    }

    fn normal(&mut self, _: u32, _: u32, split: &TessVertex<'_>) {
        self.vertices.extend_from_slice(&flat_vertex(split.position, split.normal));
        self.texcoords.extend(split.texcoords.into_iter().flatten().map(|x| x as f32));
    }

    #[inline]
    fn triangle(&mut self, _: u32, triangle: &TessTriangle) {
        self.indices.extend_from_slice(&triangle.normals);
    }
}

/// Receives a flat tessellation in chunks, as [`DualTessellator::tessellate_stream`] makes
/// it: [`begin`](Self::begin) with the number of flat vertices, then chunks of vertices and of
/// triangles (each kind in increasing order, without gaps; the two kinds interleaved), then
/// [`end`](Self::end) with the counts. The bytes are those of a [`FlatMesh`]: `px py pz nx ny
/// nz` in f32 per flat vertex (the vertices, then one per extra normal), `s t` per vertex if
/// the tessellation has texture coordinates, three `u32` indices per triangle. A sink that
/// writes a file keeps its first error and ignores the rest (as `std::fmt::Write`'s adapter
/// over `std::io::Write` does); its caller asks it after the call.
///
/// ```
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::Builtin;
/// use subdiv_tess::{DualOptions, DualTessellator, FlatMesh};
///
/// let mesh = Mesh::build(shapes::ngon_prism(5))?;
/// let options = DualOptions::DEFAULT.with_chunk(64); // tiny chunks, for the example
/// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &options)?;
/// let rates = vec![4; mesh.face_count()];
/// let (mut streamed, mut whole) = (FlatMesh::default(), FlatMesh::default());
/// tess.tessellate_stream(&rates, &mut streamed)?;
/// tess.tessellate_flat(&rates, &mut whole)?;
/// assert_eq!(streamed, whole);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// [`DualTessellator::tessellate_stream`]: crate::DualTessellator::tessellate_stream
pub trait FlatStream {
    /// Called first, once: the number of flat vertices to come, and whether they have
    /// texture coordinates.
    fn begin(&mut self, vertices: usize, texcoords: bool);

    /// Flat vertices `first..first + vertices.len() / 6`, six values each, with their texture
    /// coordinates (two each; empty without).
    fn vertices(&mut self, first: usize, vertices: &[f32], texcoords: &[f32]);

    /// Triangles `first..first + indices.len() / 3`: three indices into the flat vertices
    /// each, counter-clockwise.
    fn triangles(&mut self, first: usize, indices: &[u32]);

    /// Called last, once, with the numbers of flat vertices and triangles.
    fn end(&mut self, vertices: usize, triangles: usize);
}

/// The chunks appended: the same buffers as [`DualTessellator::tessellate_flat`]'s.
///
/// [`DualTessellator::tessellate_flat`]: crate::DualTessellator::tessellate_flat
impl FlatStream for FlatMesh {
    fn begin(&mut self, vertices: usize, texcoords: bool) {
        self.vertices.clear();
        self.vertices.reserve(6 * vertices);
        self.texcoords.clear();
        if texcoords {
            self.texcoords.reserve(2 * vertices);
        }
        self.indices.clear();
    }

    fn vertices(&mut self, first: usize, vertices: &[f32], texcoords: &[f32]) {
        debug_assert_eq!(6 * first, self.vertices.len(), "vertex chunks in order");
        self.vertices.extend_from_slice(vertices);
        self.texcoords.extend_from_slice(texcoords);
    }

    fn triangles(&mut self, first: usize, indices: &[u32]) {
        debug_assert_eq!(3 * first, self.indices.len(), "triangle chunks in order");
        self.indices.extend_from_slice(indices);
    }

    fn end(&mut self, _: usize, _: usize) {}
}

impl<S: FlatStream + ?Sized> FlatStream for &mut S {
    fn begin(&mut self, vertices: usize, texcoords: bool) {
        (**self).begin(vertices, texcoords);
    }

    fn vertices(&mut self, first: usize, vertices: &[f32], texcoords: &[f32]) {
        (**self).vertices(first, vertices, texcoords);
    }

    fn triangles(&mut self, first: usize, indices: &[u32]) {
        (**self).triangles(first, indices);
    }

    fn end(&mut self, vertices: usize, triangles: usize) {
        (**self).end(vertices, triangles);
    }
}

/// Vertices of the caller's type and `u32` triangle indices (three per triangle), filled by
/// a [`BuffersBuilder`]: lyon's `VertexBuffers`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct VertexBuffers<V> {
    /// The flat vertices, in output order: the vertices, then one split copy per extra normal.
    pub vertices: Vec<V>,
    /// Three indices per triangle, counter-clockwise.
    pub indices: Vec<u32>,
}

impl<V> VertexBuffers<V> {
    /// Empty buffers.
    pub fn new() -> Self {
        Self { vertices: Vec::new(), indices: Vec::new() }
    }
}

/// A [`TessSink`] that fills [`VertexBuffers`] with vertices made by `constructor` from each
/// [`TessVertex`] (lyon's `BuffersBuilder`), flat: a vertex with extra normals is split (one
/// more vertex per extra normal, made from its `split` vertex), the indices are
/// [`TessTriangle::normals`]. The buffers are cleared first, keeping their
/// allocations; with a [`bytemuck::Pod`] vertex type, `bytemuck::cast_slice(&buffers.vertices)`
/// is what a GPU vertex buffer takes. See the [module docs](self) for an example.
#[derive(Debug)]
pub struct BuffersBuilder<'a, V, F> {
    buffers: &'a mut VertexBuffers<V>,
    constructor: F,
}

impl<'a, V: bytemuck::Pod, F: Fn(&TessVertex<'_>) -> V> BuffersBuilder<'a, V, F> {
    /// A sink into `buffers` making each vertex with `constructor`.
    pub fn new(buffers: &'a mut VertexBuffers<V>, constructor: F) -> Self {
        Self { buffers, constructor }
    }
}

impl<V: bytemuck::Pod, F: Fn(&TessVertex<'_>) -> V> TessSink for BuffersBuilder<'_, V, F> {
    fn begin(&mut self, counts: &TessCounts) {
        self.buffers.vertices.clear();
        self.buffers.vertices.reserve(counts.vertices + counts.extra_normals);
        self.buffers.indices.clear();
        self.buffers.indices.reserve(3 * counts.triangles);
    }

    #[inline]
    fn vertex(&mut self, _: u32, vertex: &TessVertex<'_>) {
        self.buffers.vertices.push((self.constructor)(vertex));
    }

    fn normal(&mut self, _: u32, _: u32, split: &TessVertex<'_>) {
        self.buffers.vertices.push((self.constructor)(split));
    }

    #[inline]
    fn triangle(&mut self, _: u32, triangle: &TessTriangle) {
        self.buffers.indices.extend_from_slice(&triangle.normals);
    }
}

impl TessMesh {
    /// Replays this mesh into `sink`, as the tessellator that made it would have written it
    /// (polygons included when the sink wants them).
    ///
    /// ```
    /// use subdiv_mesh::{shapes, Mesh};
    /// use subdiv_schemes::Builtin;
    /// use subdiv_tess::{DualOptions, DualTessellator, FlatMesh, TessMesh};
    ///
    /// let mesh = Mesh::build(shapes::ngon_prism(5))?;
    /// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::DEFAULT)?;
    /// let out = tess.tessellate(&vec![3; mesh.face_count()])?;
    /// let (mut copy, mut flat) = (TessMesh::default(), FlatMesh::default());
    /// out.write_to(&mut copy);
    /// out.write_to(&mut flat);
    /// assert_eq!(&copy, out);
    /// assert_eq!(flat.vertices.len(), 6 * out.positions.len());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn write_to<S: TessSink + ?Sized>(&self, sink: &mut S) {
        let polygons = sink.wants_polygons();
        sink.begin(&TessCounts {
            vertices: self.positions.len(),
            extra_normals: self.normal_vertices.len(),
            triangles: self.triangles.len(),
            polygons: if polygons { self.polygon_count() } else { 0 },
            polygon_vertices: if polygons { self.polygon_vertices.len() } else { 0 },
            channels: self.channels.stride(),
            texcoords: self.channels.texcoords().is_some(),
        });
        let uv = self.channels.texcoords();
        let point = |k: usize| {
            let channels = self.channels.point(k);
            (channels, uv.map(|s| [channels[s], channels[s + 1]]))
        };
        let vertices = self.positions.iter().zip(&self.normals).zip(&self.parameters);
        for (k, ((&position, &normal), &parameter)) in vertices.enumerate() {
            let (channels, texcoords) = point(k);
            sink.vertex(k as u32, &TessVertex { position, normal, parameter, channels, texcoords });
        }
        let extra = self.normal_vertices.iter().zip(&self.normals[self.positions.len()..]).zip(&self.normal_parameters);
        for (k, ((&vertex, &normal), &parameter)) in extra.enumerate() {
            let (position, index) = (self.positions[vertex as usize], self.positions.len() + k);
            let (channels, texcoords) = point(index);
            sink.normal(index as u32, vertex, &TessVertex { position, normal, parameter, channels, texcoords });
        }
        let triangles = self.triangles.iter().zip(&self.triangle_normals);
        let triangles = triangles.zip(&self.triangle_faces).zip(&self.triangle_parameters);
        for (k, (((&vertices, &normals), &face), &parameters)) in triangles.enumerate() {
            sink.triangle(k as u32, &TessTriangle { vertices, normals, face, parameters });
        }
        if polygons {
            for (k, &face) in self.polygon_faces.iter().enumerate() {
                sink.polygon(k as u32, self.polygon(k), face);
            }
        }
        sink.end();
    }
}

#[cfg(test)]
mod tests {
    use subdiv_mesh::{Mesh, PolygonSoup, shapes};
    use subdiv_schemes::Builtin;

    use super::*;
    use crate::rates::ErrorRates;
    use crate::{DualOptions, DualTessellator, QuadtreeOptions, QuadtreeTessellator, Tolerance};

    fn meshes() -> Vec<(&'static str, Mesh)> {
        let soups: [(&str, PolygonSoup); 4] = [
            ("cube", shapes::cube()),
            ("pentagonal prism", shapes::ngon_prism(5)),
            ("built-in model", shapes::default_model()),
            ("3 × 2 grid", shapes::quad_grid(3, 2)),
        ];
        soups.into_iter().map(|(name, soup)| (name, Mesh::build(soup).expect("a shape builds"))).collect()
    }

    /// The cube with every edge infinitely sharp (split normals; the quadtree refuses it).
    fn sharp_cube() -> Mesh {
        let mut mesh = Mesh::build(shapes::cube()).expect("a shape builds");
        for e in mesh.edges().collect::<Vec<_>>() {
            mesh.set_edge_sharpness(e, subdiv_mesh::Tags::INFINITELY_SHARP);
        }
        mesh
    }

    /// The flat buffers of `mesh`, as [`DualTessellator::write_flat`] makes them: the vertices,
    /// then one per extra normal at its vertex's position, indexed by the triangles' normals.
    fn flat_of(mesh: &TessMesh) -> FlatMesh {
        let extra = mesh.normal_vertices.iter().map(|&v| mesh.positions[v as usize]);
        let positions = mesh.positions.iter().copied().chain(extra);
        let vertices = positions.zip(&mesh.normals).flat_map(|(p, n)| flat_vertex(p, *n)).collect();
        FlatMesh { vertices, indices: mesh.triangle_normals.as_flattened().to_vec(), ..FlatMesh::default() }
    }

    /// A sink that checks the call order and counts against `begin`'s.
    #[derive(Default)]
    struct Checker {
        counts: TessCounts,
        seen: TessCounts,
        polygons: bool,
        ended: bool,
    }

    impl TessSink for Checker {
        fn begin(&mut self, counts: &TessCounts) {
            assert_eq!(self.seen, TessCounts::default(), "begin comes first");
            self.counts = *counts;
        }

        fn vertex(&mut self, index: u32, vertex: &TessVertex<'_>) {
            assert_eq!(index as usize, self.seen.vertices);
            assert!((vertex.normal.length() - 1.0).abs() < 1e-12 || vertex.normal == DVec3::ZERO);
            self.seen.vertices += 1;
        }

        fn normal(&mut self, index: u32, vertex: u32, split: &TessVertex<'_>) {
            assert_eq!(self.seen.vertices, self.counts.vertices, "vertices before extra normals");
            assert_eq!(index as usize, self.counts.vertices + self.seen.extra_normals);
            assert!((vertex as usize) < self.counts.vertices);
            assert!((split.normal.length() - 1.0).abs() < 1e-12);
            self.seen.extra_normals += 1;
        }

        fn triangle(&mut self, index: u32, triangle: &TessTriangle) {
            assert_eq!(self.seen.vertices, self.counts.vertices, "vertices before triangles");
            assert_eq!(self.seen.extra_normals, self.counts.extra_normals, "extra normals before triangles");
            assert_eq!(index as usize, self.seen.triangles);
            assert!(triangle.vertices.iter().all(|&v| (v as usize) < self.counts.vertices));
            let normals = self.counts.vertices + self.counts.extra_normals;
            assert!(triangle.normals.iter().all(|&n| (n as usize) < normals));
            self.seen.triangles += 1;
        }

        fn wants_polygons(&self) -> bool {
            self.polygons
        }

        fn polygon(&mut self, index: u32, vertices: &[u32], _: FaceId) {
            assert!(self.polygons, "polygons only when asked for");
            assert_eq!(self.seen.triangles, self.counts.triangles, "triangles before polygons");
            assert_eq!(index as usize, self.seen.polygons);
            self.seen.polygons += 1;
            self.seen.polygon_vertices += vertices.len();
        }

        fn end(&mut self) {
            assert_eq!(self.seen, self.counts, "every call announced by begin");
            self.ended = true;
        }
    }

    #[test]
    fn dual_sinks_give_the_tessellators_output() {
        let cc = Builtin::CatmullClark.scheme();
        for (name, mesh) in meshes().into_iter().chain([("all-sharp cube", sharp_cube())]) {
            let mut tess = DualTessellator::new(cc, &mesh, &DualOptions::DEFAULT).unwrap();
            let rates: Vec<u32> = (0..mesh.face_count() as u32).map(|f| 1 + f % 5).collect();
            let expected = tess.tessellate(&rates).unwrap().clone();
            // Split exactly at the crease points.
            assert_eq!(expected.normal_vertices.is_empty(), name != "all-sharp cube", "{name}");
            let mut written = FlatMesh::default();
            tess.write_flat(&mut written);
            assert_eq!(written, flat_of(&expected), "{name}");

            // Sinks that already hold another output are cleared first.
            let (mut mesh_sink, mut flat) =
                (expected.clone(), FlatMesh { vertices: vec![1.0; 7], indices: vec![9], ..FlatMesh::default() });
            mesh_sink.positions.push(DVec3::ONE);
            tess.tessellate_into(&rates, &mut mesh_sink).unwrap();
            tess.tessellate_into(&rates, &mut flat).unwrap();
            assert_eq!(mesh_sink, expected, "{name}: TessMesh");
            assert_eq!(flat, written, "{name}: FlatMesh");
            assert_eq!(tess.mesh(), &expected, "{name}: the output is kept");
            for polygons in [false, true] {
                let mut checker = Checker { polygons, ..Checker::default() };
                tess.tessellate_into(&rates, &mut checker).unwrap();
                assert!(checker.ended);
                let listed = if polygons { expected.polygon_count() } else { 0 };
                assert_eq!(checker.seen.polygons, listed, "{name}");
                assert_eq!(checker.seen.extra_normals, expected.normal_vertices.len(), "{name}");
            }
        }
    }

    #[test]
    fn dual_sinks_with_rings() {
        let cc = Builtin::CatmullClark.scheme();
        for (name, mesh) in meshes().into_iter().take(3) {
            let bounds = QuadtreeTessellator::new(cc, &mesh).unwrap();
            let rates = ErrorRates::new(Tolerance::Relative(2e-2)).rates(&bounds, &mesh).unwrap();
            let mut tess = DualTessellator::new(cc, &mesh, &DualOptions::DEFAULT.with_quads(false)).unwrap();
            let expected = tess.tessellate_with_rings(&rates.faces, &rates.rings).unwrap().clone();
            let (mut mesh_sink, mut flat) = (TessMesh::default(), FlatMesh::default());
            tess.tessellate_with_rings_into(&rates.faces, &rates.rings, &mut mesh_sink).unwrap();
            tess.tessellate_with_rings_into(&rates.faces, &rates.rings, &mut flat).unwrap();
            assert_eq!(mesh_sink, expected, "{name}");
            assert_eq!(flat, flat_of(&expected), "{name}");
        }
    }

    #[test]
    fn quadtree_sinks_give_its_output_and_reuse_buffers() {
        let cc = Builtin::CatmullClark.scheme();
        for (name, mesh) in meshes() {
            let mut tess = QuadtreeTessellator::new(cc, &mesh).unwrap();
            for tolerance in [1e-2, 3e-3, 1e-2] {
                let options = QuadtreeOptions::DEFAULT.with_tolerance(Tolerance::Relative(tolerance));
                let (expected, stats) = tess.tessellate_with_stats(&options).unwrap();
                // No channels carried: one normal per vertex.
                assert!(expected.normal_vertices.is_empty() && expected.triangle_normals == expected.triangles);
                let (mut mesh_sink, mut flat) = (TessMesh::default(), FlatMesh::default());
                assert_eq!(tess.tessellate_into(&options, &mut mesh_sink).unwrap(), stats);
                assert_eq!(tess.tessellate_into(&options, &mut flat).unwrap(), stats);
                assert_eq!(mesh_sink, expected, "{name} at {tolerance}");
                assert_eq!(flat, flat_of(&expected), "{name} at {tolerance}");
                let mut checker = Checker { polygons: true, ..Checker::default() };
                tess.tessellate_into(&options, &mut checker).unwrap();
                assert!(checker.ended);
                assert_eq!(checker.seen.polygons, expected.polygon_count());
            }
            // A failed call leaves the sink alone.
            let mut untouched = Checker::default();
            let options = QuadtreeOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-4)).with_max_polygons(10);
            assert!(tess.tessellate_into(&options, &mut untouched).is_err());
            assert_eq!(untouched.counts, TessCounts::default());
        }
    }

    /// A renderer's vertex: position and normal in f32, the layout of [`FlatMesh`].
    #[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
    #[repr(C)]
    struct Vertex {
        position: [f32; 3],
        normal: [f32; 3],
    }

    #[test]
    fn pod_vertices_are_the_flat_bytes() {
        let cc = Builtin::CatmullClark.scheme();
        let make =
            |v: &TessVertex<'_>| Vertex { position: v.position.as_vec3().into(), normal: v.normal.as_vec3().into() };
        let mut buffers = VertexBuffers::new();
        for (name, mesh) in meshes().into_iter().chain([("all-sharp cube", sharp_cube())]) {
            let mut tess = DualTessellator::new(cc, &mesh, &DualOptions::DEFAULT).unwrap();
            let rates = vec![3; mesh.face_count()];
            tess.tessellate_into(&rates, &mut BuffersBuilder::new(&mut buffers, make)).unwrap();
            let mut flat = FlatMesh::default();
            tess.write_flat(&mut flat);
            let bytes: &[u8] = bytemuck::cast_slice(&buffers.vertices);
            assert_eq!(bytes, bytemuck::cast_slice::<f32, u8>(&flat.vertices), "{name}");
            assert_eq!(buffers.indices, flat.indices, "{name}");
        }
        // Any vertex type: the parameters alone.
        let mesh = Mesh::build(shapes::cube()).unwrap();
        let mut tess = DualTessellator::new(cc, &mesh, &DualOptions::DEFAULT).unwrap();
        let mut uv = VertexBuffers::<[f32; 2]>::new();
        let builder =
            &mut BuffersBuilder::new(&mut uv, |v: &TessVertex<'_>| [v.parameter.u as f32, v.parameter.v as f32]);
        tess.tessellate_into(&[2; 6], builder).unwrap();
        let out = tess.mesh();
        assert_eq!(uv.vertices.len(), out.positions.len());
        assert!(uv.vertices.iter().zip(&out.parameters).all(|(a, p)| *a == [p.u as f32, p.v as f32]));
    }

    #[test]
    fn polygons_are_opt_in() {
        let cc = Builtin::CatmullClark.scheme();
        let mesh = Mesh::build(shapes::ngon_prism(5)).unwrap();
        let rates = vec![4; mesh.face_count()];
        for quads in [false, true] {
            let mut tess = DualTessellator::new(cc, &mesh, &DualOptions::DEFAULT.with_quads(quads)).unwrap();
            let (mut plain, mut asking) = (Checker::default(), Checker { polygons: true, ..Checker::default() });
            tess.tessellate_into(&rates, &mut plain).unwrap();
            tess.tessellate_into(&rates, &mut asking).unwrap();
            assert_eq!(plain.seen.polygons, 0);
            // The dual tessellator's polygons are its quads, listed when its options say so.
            assert_eq!(asking.seen.polygons > 0, quads);
            assert_eq!(asking.seen.polygon_vertices, 4 * asking.seen.polygons);
            assert_eq!(plain.seen.triangles, asking.seen.triangles);
        }
        // The quadtree always has its leaves; a sink gets them only when it asks.
        let mut tess = QuadtreeTessellator::new(cc, &mesh).unwrap();
        let options = QuadtreeOptions::DEFAULT.with_tolerance(Tolerance::Relative(1e-2));
        let (mut plain, mut asking) = (Checker::default(), Checker { polygons: true, ..Checker::default() });
        tess.tessellate_into(&options, &mut plain).unwrap();
        tess.tessellate_into(&options, &mut asking).unwrap();
        assert_eq!(plain.seen.polygons, 0);
        assert!(asking.seen.polygon_vertices >= 4 * asking.seen.polygons && asking.seen.polygons > 0);
        // Hanging vertices: the leaves' polygons have as many corners as their fans' triangles.
        assert_eq!(asking.seen.polygon_vertices, asking.seen.triangles);
    }
}
