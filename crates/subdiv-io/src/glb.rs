//! GLB writing: [`encode_glb`], [`write_glb`] and [`write_glb_interleaved`] write one triangle
//! mesh, checked whole first and then streamed, and [`check_glb_positions`] the f32 rule its
//! coordinates meet.

use std::path::Path;

use glam::{Vec2, Vec3};
use serde_json::{Value, json};

use crate::gltf::{CHUNK_BIN, CHUNK_JSON, GLB_MAGIC};
use std::io::Write as _;

use crate::IoError;
use crate::atomic::{self, Scratch};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// A triangle mesh to write as GLB: positions, optional normals and texture coordinates (one
/// per position), and three indices per triangle, counter-clockwise seen from outside.
#[derive(Clone, Copy, Debug)]
pub struct GlbMesh<'a> {
    /// Vertex positions.
    pub positions: &'a [Vec3],
    /// Vertex normals, one per position; written normalised.
    pub normals: Option<&'a [Vec3]>,
    /// Texture coordinates, one per position, written as `TEXCOORD_0` as given (glTF's `v`
    /// runs down the image).
    pub texcoords: Option<&'a [Vec2]>,
    /// Triangle vertex indices, three per triangle.
    pub indices: &'a [u32],
}

/// The smallest extent (largest coordinate magnitude) of a mesh the GLB writer accepts: 2^-102.
///
/// GLB stores f32s. A mesh whose coordinates all lie below f32's smallest normal number
/// (2^-126) would be written as subnormals or, converted from f64, as 0 — the mesh collapses to
/// a point — and GPUs flush subnormals to zero in any case. 2^-102 = 2^-126 · 2^24 leaves room
/// for f32's 24-bit significand: the differences between neighbouring coordinates of that size
/// (an edge, a derivative, one ulp apart) are still normal numbers, so the shape survives the
/// renderer too. A mesh this small is to be scaled up before it is written.
///
/// A single coordinate below this size in a larger mesh (rounding noise around 0, such as
/// `-4.8e-35` on a unit cube) is accepted when it is within f32's resolution of the mesh's
/// extent (at most `2^-24 ×` it): written as it is, or as 0 after a conversion or a GPU's flush,
/// it moves its vertex by less than f32 resolves at that scale.
pub const MIN_GLB_EXTENT: f64 = 1.0 / (1u128 << 102) as f64;

/// Checks that `positions` survive f32 ([`MIN_GLB_EXTENT`]): every coordinate finite and at
/// most `f32::MAX` in magnitude; the mesh's extent 0 or at least `MIN_GLB_EXTENT`; and a
/// coordinate below `MIN_GLB_EXTENT` only where it is within f32's resolution of the extent.
/// [`encode_glb`] calls it on its f32 input; a caller that converts f64 positions to f32 calls
/// it on the f64s first, where a coordinate that the conversion would flush to 0 is still seen.
///
/// # Errors
/// [`IoError::Unwritable`] naming the vertex, the coordinate and what to do (scale the mesh).
pub fn check_glb_positions(positions: impl IntoIterator<Item = glam::DVec3>) -> Result<(), IoError> {
    let mut check = PositionCheck::default();
    for p in positions {
        check.push(p)?;
    }
    check.finish()
}

/// [`check_glb_positions`] a position at a time: the largest magnitude, and the largest
/// non-zero one below [`MIN_GLB_EXTENT`], with their places.
#[derive(Clone, Copy, Debug, Default)]
struct PositionCheck {
    count: usize,
    largest: (usize, f64),
    tiny: Option<(usize, f64)>,
}

impl PositionCheck {
    fn refuse(i: usize, x: f64, rule: &str) -> IoError {
        IoError::Unwritable { format: "GLB", rule: format!("vertex {i} coordinate {x:e} {rule}") }
    }

    fn push(&mut self, p: glam::DVec3) -> Result<(), IoError> {
        let i = self.count;
        self.count += 1;
        for x in p.to_array() {
            if !x.is_finite() {
                return Err(Self::refuse(i, x, "is not finite"));
            }
            if x.abs() > f64::from(f32::MAX) {
                return Err(Self::refuse(i, x, "exceeds f32's range (3.4e38); scale the mesh down before writing GLB"));
            }
            if x.abs() > self.largest.1.abs() {
                self.largest = (i, x);
            }
            if x != 0.0 && x.abs() < MIN_GLB_EXTENT && self.tiny.is_none_or(|(_, t)| x.abs() > t.abs()) {
                self.tiny = (i, x).into();
            }
        }
        Ok(())
    }

    fn finish(&self) -> Result<(), IoError> {
        let too_small = "is too small for f32 (it would be written as 0 or a subnormal; the smallest \
                         mesh extent accepted is 2^-102 ≈ 2.0e-31); scale the mesh up before writing GLB";
        let largest = self.largest;
        if largest.1 != 0.0 && largest.1.abs() < MIN_GLB_EXTENT {
            return Err(Self::refuse(largest.0, largest.1, &format!("is the mesh's largest and {too_small}")));
        }
        match self.tiny {
            Some((i, x)) if x.abs() > largest.1.abs() * f64::from(f32::EPSILON) / 2.0 => {
                Err(Self::refuse(i, x, too_small))
            }
            _ => Ok(()),
        }
    }
}

/// Encodes `mesh` as a GLB file: one scene, one node, one mesh with one TRIANGLES primitive;
/// POSITION (with the `min`/`max` the spec requires), NORMAL and TEXCOORD_0 when given, `u32` indices, one
/// tightly packed buffer view per accessor with its target, 4-byte aligned and padded chunks,
/// `asset.generator = "subdiv"`. The same mesh always gives the same bytes.
///
/// # Errors
/// [`IoError::Unwritable`] for a mesh no valid GLB can hold: no triangle, an index count not a
/// multiple of 3, an index out of range, a coordinate that is not finite or is too small to be
/// a normal f32 (see [`check_glb_positions`]), a normal or texture-coordinate count that
/// differs from the position count, a zero or non-finite normal, a non-finite texture
/// coordinate, more than 4 GiB.
pub fn encode_glb(mesh: &GlbMesh<'_>) -> Result<Vec<u8>, IoError> {
    let vertices = Vertices::Split { positions: mesh.positions, normals: mesh.normals, texcoords: mesh.texcoords };
    let header = GlbHeader::of(vertices, mesh.indices)?;
    let mut glb = Vec::with_capacity(header.total as usize);
    header
        .write(vertices, mesh.indices, &mut glb)
        .map_err(|e| IoError::Unwritable { format: "GLB", rule: e.to_string() })?;
    Ok(glb)
}

/// Writes `mesh` as a GLB file at `path` (see [`encode_glb`]), through a fresh `<name>.<16 hex>.tmp` and a
/// rename, so a failure leaves `path` untouched. The mesh is checked whole first, then
/// streamed to the file: nothing the size of the output is allocated.
///
/// # Errors
/// As [`encode_glb`]; [`IoError::Io`] when writing fails.
pub fn write_glb(path: impl AsRef<Path>, mesh: &GlbMesh<'_>) -> Result<(), IoError> {
    let vertices = Vertices::Split { positions: mesh.positions, normals: mesh.normals, texcoords: mesh.texcoords };
    let header = GlbHeader::of(vertices, mesh.indices)?;
    atomic::write_file(path.as_ref(), |w| header.write(vertices, mesh.indices, w))
}

/// [`write_glb`] of interleaved vertices, `px py pz nx ny nz` each (a tessellator's flat
/// buffers, `subdiv-tess`'s `FlatMesh`), without splitting them into arrays first, with
/// texture coordinates if given (one per vertex): the same file as [`write_glb`] of their
/// positions, normals and texture coordinates.
///
/// # Errors
/// As [`write_glb`].
pub fn write_glb_interleaved(
    path: impl AsRef<Path>,
    vertices: &[[f32; 6]],
    texcoords: Option<&[Vec2]>,
    indices: &[u32],
) -> Result<(), IoError> {
    let vertices = Vertices::Interleaved { vertices, texcoords };
    let header = GlbHeader::of(vertices, indices)?;
    atomic::write_file(path.as_ref(), |w| header.write(vertices, indices, w))
}

/// A GLB file written as its data comes, for outputs too large to hold: interleaved vertices
/// (`px py pz nx ny nz`, as [`write_glb_interleaved`] takes them) with their texture
/// coordinates, and triangle indices, each in chunks of any size, in order; each kind goes to
/// a scratch file beside the output as it comes (checked on the way), and
/// [`finish`](Self::finish) writes the file through a temporary file and a rename, the bytes
/// of [`write_glb_interleaved`] of the whole. What it holds is a buffer per kind, not the
/// output; the disk holds the output twice until `finish` (the scratch files are removed then,
/// or when the writer is dropped).
///
/// ```
/// use subdiv_io::GlbWriter;
///
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("triangle.glb");
/// let mut glb = GlbWriter::create(&path, false)?;
/// glb.push_vertices(&[[0.0, 0.0, 0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0, 0.0, 1.0]], &[])?;
/// glb.push_vertices(&[[0.0, 1.0, 0.0, 0.0, 0.0, 1.0]], &[])?;
/// glb.push_indices(&[0, 1, 2])?;
/// glb.finish()?;
/// let whole = std::fs::read(&path)?;
/// subdiv_io::write_glb_interleaved(&path, &[[0.0, 0.0, 0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 0.0, 0.0, 1.0]], None, &[0, 1, 2])?;
/// assert_eq!(std::fs::read(&path)?, whole);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct GlbWriter {
    path: std::path::PathBuf,
    positions: Scratch,
    normals: Scratch,
    texcoords: Option<Scratch>,
    indices: Scratch,
    vertices: usize,
    index_count: usize,
    check: PositionCheck,
    bounds: [Vec3; 2],
    /// The largest index so far and its place (checked against the vertex count at the end).
    largest_index: Option<(usize, u32)>,
}

impl std::fmt::Debug for GlbWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GlbWriter")
            .field("path", &self.path)
            .field("vertices", &self.vertices)
            .field("indices", &self.index_count)
            .finish_non_exhaustive()
    }
}

impl GlbWriter {
    /// A writer of the file at `path` (written by [`finish`](Self::finish); untouched until
    /// then), with texture coordinates or without.
    ///
    /// # Errors
    /// [`IoError::Io`] if the scratch files cannot be made beside `path`.
    pub fn create(path: impl AsRef<Path>, texcoords: bool) -> Result<Self, IoError> {
        let path = path.as_ref().to_owned();
        let io = |source| IoError::Io { path: path.clone(), source };
        let scratch = || Scratch::beside(&path);
        Ok(Self {
            positions: scratch().map_err(io)?,
            normals: scratch().map_err(io)?,
            texcoords: if texcoords { Some(scratch().map_err(io)?) } else { None },
            indices: scratch().map_err(io)?,
            path: path.clone(),
            vertices: 0,
            index_count: 0,
            check: PositionCheck::default(),
            bounds: [Vec3::INFINITY, Vec3::NEG_INFINITY],
            largest_index: None,
        })
    }

    /// The next vertices, with their texture coordinates (one each if the writer was made with
    /// them, else none).
    ///
    /// # Errors
    /// As [`write_glb_interleaved`]'s checks of these vertices; [`IoError::Io`] when writing
    /// fails.
    pub fn push_vertices(&mut self, vertices: &[[f32; 6]], texcoords: &[Vec2]) -> Result<(), IoError> {
        let unwritable = |rule: String| IoError::Unwritable { format: "GLB", rule };
        let expected = if self.texcoords.is_some() { vertices.len() } else { 0 };
        if texcoords.len() != expected {
            return Err(unwritable(format!("{} texture coordinates for {expected} vertices", texcoords.len())));
        }
        let io = |source| IoError::Io { path: self.path.clone(), source };
        for (k, v) in vertices.iter().enumerate() {
            let (p, n) = (Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]));
            self.check.push(p.as_dvec3())?;
            let Some(unit) = n.try_normalize() else {
                return Err(unwritable(format!("normal {} = {n} has no direction", self.vertices + k)));
            };
            self.bounds = [self.bounds[0].min(p), self.bounds[1].max(p)];
            vec3(self.positions.writer(), p).map_err(io)?;
            // Normalised in f32 on the way, as the whole writer (`try_normalize` is `normalize`
            // with the check).
            vec3(self.normals.writer(), unit).map_err(io)?;
        }
        if let Some(scratch) = &mut self.texcoords {
            for (k, t) in texcoords.iter().enumerate() {
                if !t.is_finite() {
                    return Err(unwritable(format!("texture coordinate {} = {t} is not finite", self.vertices + k)));
                }
                let w = scratch.writer();
                w.write_all(&t.x.to_le_bytes()).and_then(|()| w.write_all(&t.y.to_le_bytes())).map_err(io)?;
            }
        }
        self.vertices += vertices.len();
        Ok(())
    }

    /// The next triangles' indices.
    ///
    /// # Errors
    /// [`IoError::Io`] when writing fails.
    pub fn push_indices(&mut self, indices: &[u32]) -> Result<(), IoError> {
        let io = |source| IoError::Io { path: self.path.clone(), source };
        let w = self.indices.writer();
        for (k, &i) in indices.iter().enumerate() {
            if self.largest_index.is_none_or(|(_, largest)| i > largest) {
                self.largest_index = Some((self.index_count + k, i));
            }
            w.write_all(&i.to_le_bytes()).map_err(io)?;
        }
        self.index_count += indices.len();
        Ok(())
    }

    /// Writes the file: the vertices and indices pushed, as [`write_glb_interleaved`] writes
    /// them.
    ///
    /// # Errors
    /// As [`write_glb_interleaved`]: no triangle, an index count not a multiple of 3, an index
    /// past the vertices, coordinates too small for f32, more than 4 GiB; [`IoError::Io`].
    pub fn finish(mut self) -> Result<(), IoError> {
        let unwritable = |rule: String| IoError::Unwritable { format: "GLB", rule };
        let (n, count) = (self.vertices, self.index_count);
        if count == 0 || !count.is_multiple_of(3) {
            return Err(unwritable(format!("{count} indices; a mesh needs whole triangles, at least one")));
        }
        self.check.finish()?;
        if let Some((i, v)) = self.largest_index.filter(|&(_, v)| v as usize >= n) {
            return Err(unwritable(format!("index {i} is {v}, but there are {n} vertices")));
        }
        let attributes = Attributes { normals: true, texcoords: self.texcoords.is_some() };
        let header = GlbHeader::layout(n, attributes, self.bounds, count)?;
        let Self { path, positions, normals, texcoords, indices, .. } = &mut self;
        atomic::write_file(path, |w| {
            header.write_prefix(w)?;
            positions.copy_into(w)?;
            normals.copy_into(w)?;
            if let Some(texcoords) = texcoords {
                texcoords.copy_into(w)?;
            }
            indices.copy_into(w)
        })
    }
}

/// The vertices the GLB writer takes.
#[derive(Clone, Copy)]
enum Vertices<'a> {
    Split { positions: &'a [Vec3], normals: Option<&'a [Vec3]>, texcoords: Option<&'a [Vec2]> },
    Interleaved { vertices: &'a [[f32; 6]], texcoords: Option<&'a [Vec2]> },
}

impl<'a> Vertices<'a> {
    fn len(self) -> usize {
        match self {
            Self::Split { positions, .. } => positions.len(),
            Self::Interleaved { vertices, .. } => vertices.len(),
        }
    }

    fn positions(self) -> impl Iterator<Item = Vec3> {
        // One iterator type for both layouts: the layout not in use is an empty slice.
        let (split, interleaved) = match self {
            Self::Split { positions, .. } => (positions, &[][..]),
            Self::Interleaved { vertices, .. } => (&[][..], vertices),
        };
        split.iter().copied().chain(interleaved.iter().map(|v| Vec3::new(v[0], v[1], v[2])))
    }

    /// The normals, if there are any: the same number as the positions for interleaved ones.
    fn normals(self) -> Option<impl Iterator<Item = Vec3>> {
        let (split, interleaved) = match self {
            Self::Split { normals: None, .. } => return None,
            Self::Split { normals: Some(normals), .. } => (normals, &[][..]),
            Self::Interleaved { vertices, .. } => (&[][..], vertices),
        };
        Some(split.iter().copied().chain(interleaved.iter().map(|v| Vec3::new(v[3], v[4], v[5]))))
    }

    fn texcoords(self) -> Option<&'a [Vec2]> {
        match self {
            Self::Split { texcoords, .. } | Self::Interleaved { texcoords, .. } => texcoords,
        }
    }
}

/// A checked [`GlbMesh`]'s JSON chunk and sizes: everything but the binary data, which
/// [`write`](Self::write) streams from the mesh.
struct GlbHeader {
    json: Vec<u8>,
    bin_len: usize,
    total: u32,
}

impl GlbHeader {
    /// Checks a mesh (see [`encode_glb`]) and lays out its file.
    fn of(vertices: Vertices<'_>, indices: &[u32]) -> Result<Self, IoError> {
        let unwritable = |rule: String| IoError::Unwritable { format: "GLB", rule };
        let n = vertices.len();
        if indices.is_empty() || !indices.len().is_multiple_of(3) {
            return Err(unwritable(format!("{} indices; a mesh needs whole triangles, at least one", indices.len())));
        }
        check_glb_positions(vertices.positions().map(|p| p.as_dvec3()))?;
        if let Some((i, v)) = indices.iter().enumerate().find(|&(_, &v)| v as usize >= n) {
            return Err(unwritable(format!("index {i} is {v}, but there are {n} vertices")));
        }
        if let Vertices::Split { normals: Some(normals), .. } = vertices
            && normals.len() != n
        {
            return Err(unwritable(format!("{} normals for {n} vertices", normals.len())));
        }
        if let Some((i, v)) = vertices.normals().and_then(|n| n.enumerate().find(|(_, v)| v.try_normalize().is_none()))
        {
            return Err(unwritable(format!("normal {i} = {v} has no direction")));
        }
        if let Some(texcoords) = vertices.texcoords() {
            if texcoords.len() != n {
                return Err(unwritable(format!("{} texture coordinates for {n} vertices", texcoords.len())));
            }
            if let Some((i, t)) = texcoords.iter().enumerate().find(|(_, t)| !t.is_finite()) {
                return Err(unwritable(format!("texture coordinate {i} = {t} is not finite")));
            }
        }
        let (min, max) =
            vertices.positions().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
        let attributes =
            Attributes { normals: vertices.normals().is_some(), texcoords: vertices.texcoords().is_some() };
        Self::layout(n, attributes, [min, max], indices.len())
    }

    /// The file of `n` vertices with `attributes`, positions within `bounds` (min, max), and
    /// `indices` indices.
    fn layout(n: usize, attributes: Attributes, bounds: [Vec3; 2], indices: usize) -> Result<Self, IoError> {
        let unwritable = |rule: String| IoError::Unwritable { format: "GLB", rule };
        let [min, max] = bounds;
        let Attributes { normals, texcoords } = attributes;
        let mut views = Vec::new();
        let mut accessors = Vec::new();
        let mut attributes = serde_json::Map::new();
        let mut bin_len = 0usize;
        let mut push_view = |bytes: usize, target: u32| {
            views.push(json!({ "buffer": 0, "byteOffset": bin_len, "byteLength": bytes, "target": target }));
            bin_len += bytes;
            views.len() - 1
        };
        // min/max as the exact f64 of each f32, so that they compare equal to the data in any reader.
        let exact = |v: Vec3| v.to_array().map(f64::from);
        let view = push_view(12 * n, ARRAY_BUFFER);
        attributes.insert("POSITION".into(), accessors.len().into());
        accessors.push(json!({
            "bufferView": view, "componentType": 5126, "count": n, "type": "VEC3", "min": exact(min), "max": exact(max)
        }));
        if normals {
            let view = push_view(12 * n, ARRAY_BUFFER);
            attributes.insert("NORMAL".into(), accessors.len().into());
            accessors.push(json!({ "bufferView": view, "componentType": 5126, "count": n, "type": "VEC3" }));
        }
        if texcoords {
            let view = push_view(8 * n, ARRAY_BUFFER);
            attributes.insert("TEXCOORD_0".into(), accessors.len().into());
            accessors.push(json!({ "bufferView": view, "componentType": 5126, "count": n, "type": "VEC2" }));
        }
        let view = push_view(4 * indices, ELEMENT_ARRAY_BUFFER);
        let index_accessor = accessors.len();
        accessors.push(json!({ "bufferView": view, "componentType": 5125, "count": indices, "type": "SCALAR" }));
        let root = json!({
            "asset": { "version": "2.0", "generator": "subdiv" },
            "scene": 0,
            "scenes": [{ "nodes": [0] }],
            "nodes": [{ "mesh": 0 }],
            "meshes": [{ "primitives": [{ "attributes": Value::Object(attributes), "indices": index_accessor, "mode": 4 }] }],
            "accessors": accessors,
            "bufferViews": views,
            "buffers": [{ "byteLength": bin_len }],
        });
        let mut json = root.to_string().into_bytes();
        json.resize(json.len().next_multiple_of(4), b' ');
        // Every part of the BIN chunk is a whole number of 4-byte values, so it needs no padding.
        let total = 12 + 8 + json.len() + 8 + bin_len;
        let total =
            u32::try_from(total).map_err(|_| unwritable(format!("{total} bytes exceed the 4 GiB a GLB can hold")))?;
        Ok(Self { json, bin_len, total })
    }

    /// Writes the file: the header, the JSON chunk, then the binary chunk from `vertices` and
    /// `indices` (those [`of`](Self::of) checked), normals normalised on the way.
    fn write(&self, vertices: Vertices<'_>, indices: &[u32], w: &mut impl std::io::Write) -> std::io::Result<()> {
        self.write_prefix(w)?;
        for p in vertices.positions() {
            vec3(w, p)?;
        }
        for n in vertices.normals().into_iter().flatten() {
            // Checked by `of`: every normal has a direction.
            vec3(w, n.normalize())?;
        }
        for t in vertices.texcoords().into_iter().flatten() {
            w.write_all(&t.x.to_le_bytes())?;
            w.write_all(&t.y.to_le_bytes())?;
        }
        for &i in indices {
            w.write_all(&i.to_le_bytes())?;
        }
        Ok(())
    }

    /// The file up to the binary chunk's data: the header, the JSON chunk, the binary
    /// chunk's header.
    fn write_prefix(&self, w: &mut impl std::io::Write) -> std::io::Result<()> {
        w.write_all(GLB_MAGIC)?;
        w.write_all(&2u32.to_le_bytes())?;
        w.write_all(&self.total.to_le_bytes())?;
        w.write_all(&(self.json.len() as u32).to_le_bytes())?;
        w.write_all(&CHUNK_JSON.to_le_bytes())?;
        w.write_all(&self.json)?;
        w.write_all(&(self.bin_len as u32).to_le_bytes())?;
        w.write_all(&CHUNK_BIN.to_le_bytes())
    }
}

/// `v` as three little-endian f32s.
fn vec3(w: &mut dyn std::io::Write, v: Vec3) -> std::io::Result<()> {
    let mut bytes = [0u8; 12];
    for (chunk, x) in bytes.chunks_exact_mut(4).zip(v.to_array()) {
        chunk.copy_from_slice(&x.to_le_bytes());
    }
    w.write_all(&bytes)
}

/// The vertex attributes a file has besides positions.
#[derive(Clone, Copy, Debug)]
struct Attributes {
    normals: bool,
    texcoords: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle(positions: &[Vec3]) -> Result<Vec<u8>, IoError> {
        encode_glb(&GlbMesh { positions, normals: None, texcoords: None, indices: &[0, 1, 2] })
    }

    #[test]
    fn coordinates_that_are_no_normal_f32_are_refused_with_what_to_do() {
        let tiny = 1e-40_f32; // subnormal
        let error = triangle(&[Vec3::ZERO, Vec3::X * tiny, Vec3::Y * tiny]).unwrap_err().to_string();
        assert!(error.contains("vertex 1") && error.contains("scale the mesh up"), "{error}");
        // f64 coordinates that f32 flushes to 0: caught before the conversion.
        let error = check_glb_positions([glam::DVec3::splat(1e-50)]).unwrap_err().to_string();
        assert!(error.contains("vertex 0") && error.contains("scale the mesh up"), "{error}");
        let error = check_glb_positions([glam::DVec3::new(0.0, 1e300, 0.0)]).unwrap_err().to_string();
        assert!(error.contains("scale the mesh down"), "{error}");
        // The bound itself and 0 are fine.
        let small = MIN_GLB_EXTENT as f32;
        assert_eq!(f64::from(small), MIN_GLB_EXTENT);
        triangle(&[Vec3::ZERO, Vec3::X * small, Vec3::Y * small]).unwrap();
    }

    /// Rounding noise around 0 in a mesh of ordinary size is no reason to refuse it (a quadtree
    /// tessellation of a unit cube has `-4.8e-35`); a tiny coordinate that f32 would resolve
    /// against the mesh's extent still is.
    #[test]
    fn noise_around_zero_is_kept_in_a_mesh_of_ordinary_size() {
        let unit = [glam::DVec3::new(-4.81482486096809e-35, 0.5, 1.0), glam::DVec3::ONE, glam::DVec3::ZERO];
        check_glb_positions(unit).unwrap();
        triangle(&[Vec3::new(-4.8e-35, 0.5, 1.0), Vec3::ONE, Vec3::ZERO]).unwrap();
        // Largest coordinate 2^-90: 2^-115 is below f32's resolution there (2^-114), 2^-105 is not.
        let extent = glam::DVec3::X * 2f64.powi(-90);
        check_glb_positions([extent, glam::DVec3::Y * 2f64.powi(-115)]).unwrap();
        let error = check_glb_positions([extent, glam::DVec3::Y * 2f64.powi(-105)]).unwrap_err().to_string();
        assert!(error.contains("vertex 1") && error.contains("scale the mesh up"), "{error}");
    }

    /// The streaming writer refuses what the whole writer refuses, names it, and leaves neither
    /// the target nor a scratch file behind.
    #[test]
    fn a_glb_written_in_chunks_is_refused_as_a_whole_one_and_leaves_nothing() {
        let _writing = crate::atomic::tests::WRITING.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.glb");
        let v = |x: f32| [x, 0.0, 0.0, 0.0, 0.0, 1.0];
        let refused = |push: &dyn Fn(&mut GlbWriter) -> Result<(), IoError>| {
            let mut glb = GlbWriter::create(&path, false).unwrap();
            let error = push(&mut glb).and_then(|()| glb.finish()).unwrap_err().to_string();
            let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
            assert!(left.is_empty(), "{error}: {left:?} left behind");
            error
        };
        let error =
            refused(&|w| w.push_vertices(&[v(0.0), v(1.0), v(2.0)], &[]).and_then(|()| w.push_indices(&[0, 1, 3])));
        assert!(error.contains("index 2 is 3, but there are 3 vertices"), "{error}");
        let error = refused(&|w| w.push_vertices(&[v(0.0)], &[]));
        assert!(error.contains("0 indices"), "{error}");
        let error = refused(&|w| w.push_vertices(&[[0.0, 0.0, 0.0, 0.0, 0.0, 0.0]], &[]));
        assert!(error.contains("normal 0") && error.contains("no direction"), "{error}");
        let error = refused(&|w| w.push_vertices(&[v(f32::NAN)], &[]));
        assert!(error.contains("vertex 0") && error.contains("not finite"), "{error}");
        let error = refused(&|w| w.push_vertices(&[v(0.0)], &[Vec2::ZERO]));
        assert!(error.contains("1 texture coordinates for 0 vertices"), "{error}");
        // Written in chunks, the bytes of the whole writer's file, texture coordinates included.
        let vertices = [v(0.0), v(1.0), [0.0, 1.0, 0.5, 0.0, 0.0, 2.0]];
        let texcoords = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let mut glb = GlbWriter::create(&path, true).unwrap();
        glb.push_vertices(&vertices[..1], &texcoords[..1]).unwrap();
        glb.push_indices(&[0]).unwrap();
        glb.push_vertices(&vertices[1..], &texcoords[1..]).unwrap();
        glb.push_indices(&[1, 2]).unwrap();
        glb.finish().unwrap();
        let streamed = std::fs::read(&path).unwrap();
        write_glb_interleaved(&path, &vertices, Some(&texcoords), &[0, 1, 2]).unwrap();
        assert_eq!(streamed, std::fs::read(&path).unwrap());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "the scratch files are gone");
    }
}
