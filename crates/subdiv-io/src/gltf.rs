//! glTF 2.0 and GLB reading: [`load_gltf`] and [`parse_gltf`] read triangle meshes into a
//! polygon soup (the writer is `glb.rs`).
//!
//! The reader parses the JSON with `gltf::json` and reads the GLB container and every accessor
//! itself, checking every index and byte range, so that a truncated or corrupt file is an error
//! naming its place, never a panic. (`gltf`'s own validation indexes `accessors` with unchecked
//! POSITION references, so it is not used.)

use std::borrow::Cow;
use std::fs::{self, File};
use std::io::Read as _;
use std::path::Path;

use ::gltf::json::{
    self, Root,
    accessor::{ComponentType, GenericComponentType, Type},
    mesh::{Mode, Semantic},
    validation::Checked,
};
use base64::Engine as _;
use glam::Vec3;
use serde_json::Value;
use subdiv_mesh::{Channel, PolygonSoup, VertexId};

use crate::IoError;

/// The GLB container's magic and chunk types (the reader's and the writer's).
pub(crate) const GLB_MAGIC: &[u8; 4] = b"glTF";
pub(crate) const CHUNK_JSON: u32 = 0x4E4F_534A;
pub(crate) const CHUNK_BIN: u32 = 0x004E_4942;

/// Limits and permissions of the glTF reader ([`load_gltf_with`], [`parse_gltf_with`]): what a
/// hostile file may make it read or allocate.
///
/// ```
/// let options = subdiv_io::GltfOptions::DEFAULT.with_max_vertices(1 << 20);
/// assert!(!options.allow_outside_uris);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GltfOptions {
    /// Whether buffer URIs may name files outside the glTF file's folder (`../`, absolute
    /// paths, symlinks that lead out). Default `false`: such a URI is
    /// [`IoError::UriOutsideFolder`].
    pub allow_outside_uris: bool,
    /// The most vertices all primitives together may have (the sum of their POSITION
    /// counts), checked before anything is allocated. Default 2^26 (about 67 million).
    pub max_vertices: u64,
    /// The most vertex indices all primitives together may have (the sum of their index
    /// counts, or vertex counts where they have none), checked before anything is allocated.
    /// Default 2^28 (about 268 million, 89 million triangles).
    pub max_indices: u64,
    /// Weld vertices with equal positions into one cage vertex, keeping each corner's texture
    /// coordinates: exporters split a vertex wherever its normal or texture coordinate differs,
    /// and without welding such a cage comes apart into pieces along those seams. Default
    /// `false`: vertices are read as they are.
    pub weld: bool,
}

impl GltfOptions {
    /// The defaults: buffers inside the glTF's folder only, at most 2^26 vertices and 2^28
    /// indices.
    pub const DEFAULT: Self =
        Self { allow_outside_uris: false, max_vertices: 1 << 26, max_indices: 1 << 28, weld: false };

    /// With [`allow_outside_uris`](Self::allow_outside_uris) set to `allow`.
    #[must_use]
    pub const fn with_allow_outside_uris(self, allow: bool) -> Self {
        Self { allow_outside_uris: allow, ..self }
    }

    /// With [`max_vertices`](Self::max_vertices) set to `max`.
    #[must_use]
    pub const fn with_max_vertices(self, max: u64) -> Self {
        Self { max_vertices: max, ..self }
    }

    /// With [`max_indices`](Self::max_indices) set to `max`.
    #[must_use]
    pub const fn with_max_indices(self, max: u64) -> Self {
        Self { max_indices: max, ..self }
    }

    /// With [`weld`](Self::weld) set to `weld`.
    #[must_use]
    pub const fn with_weld(self, weld: bool) -> Self {
        Self { weld, ..self }
    }
}

impl Default for GltfOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Reads the glTF 2.0 file at `path` with [`GltfOptions::DEFAULT`]; see [`load_gltf_with`].
///
/// # Errors
/// As [`load_gltf_with`].
pub fn load_gltf(path: impl AsRef<Path>) -> Result<PolygonSoup, IoError> {
    load_gltf_with(path, &GltfOptions::DEFAULT)
}

/// Reads the glTF 2.0 file at `path`: a `.glb`, or a `.gltf` whose buffers are data URIs or
/// files in its folder. See [`parse_gltf_with`] for what is read.
///
/// # Errors
/// As [`parse_gltf_with`]; reading the file or an external buffer fails as [`IoError::Io`].
pub fn load_gltf_with(path: impl AsRef<Path>, options: &GltfOptions) -> Result<PolygonSoup, IoError> {
    let path = path.as_ref();
    let io = |source| IoError::Io { path: path.to_owned(), source };
    let file = File::open(path).map_err(io)?;
    if !file.metadata().map_err(io)?.is_file() {
        return Err(io(std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a regular file")));
    }
    let mut bytes = Vec::new();
    std::io::BufReader::new(file).read_to_end(&mut bytes).map_err(io)?;
    let dir = path.parent().map(|d| if d.as_os_str().is_empty() { Path::new(".") } else { d });
    parse_gltf_with(&bytes, &crate::error::shown(path), dir, options)
}

/// [`parse_gltf_with`] with [`GltfOptions::DEFAULT`].
///
/// # Errors
/// As [`parse_gltf_with`].
pub fn parse_gltf(bytes: &[u8], name: &str, base_dir: Option<&Path>) -> Result<PolygonSoup, IoError> {
    parse_gltf_with(bytes, name, base_dir, &GltfOptions::DEFAULT)
}

/// Reads glTF 2.0 from memory: GLB when `name` ends in `.glb` or the bytes start with the GLB
/// magic, JSON otherwise. External buffer URIs are resolved against `base_dir` and must stay
/// inside it (after canonicalisation) unless [`GltfOptions::allow_outside_uris`]; they must
/// name regular files, of which at most `byteLength` bytes are read. Without `base_dir`, only
/// GLB and data-URI buffers can be read.
///
/// Every primitive of every mesh, in file order, must be TRIANGLES with a `VEC3`/`FLOAT`
/// POSITION and optional `u8`/`u16`/`u32` indices (none: consecutive vertex triples). The
/// result is one soup of triangles; each primitive's vertices are appended as they are, so
/// vertices that an exporter split along normal or UV seams stay split (those seams are then
/// boundaries) unless [`GltfOptions::weld`] welds equal positions. `TEXCOORD_n` (`VEC2` of
/// `FLOAT`, or normalized unsigned bytes or shorts) becomes the channel `uv` (n = 0) or `uvN`,
/// one value per glTF vertex, as stored (glTF's `v` runs down the image; nothing is flipped);
/// when some primitives have it and others not, the channel would be incomplete, which is an
/// error. Node transforms and instancing are ignored: each mesh appears once, in its own
/// coordinates, which is the cage as modelled. Other attributes, materials and animation are
/// ignored.
///
/// Before any buffer is read, the accessor, buffer view and buffer numbers are checked as
/// `u64`s against the document ([`IoError::GltfIndex`]), and the vertex and index counts of all
/// primitives are summed and checked against [`GltfOptions::max_vertices`] and
/// [`GltfOptions::max_indices`] ([`IoError::GltfTooLarge`]).
///
/// # Errors
/// [`IoError::Gltf`] naming the place and the rule: a truncated or malformed GLB container, bad
/// JSON, a required extension, a primitive mode other than TRIANGLES, a missing or non-float
/// POSITION, a non-finite position, an index out of range, an accessor or buffer view outside
/// its buffer, a sparse accessor. [`IoError::GltfIndex`], [`IoError::GltfTooLarge`],
/// [`IoError::UriOutsideFolder`], [`IoError::NotARegularFile`], [`IoError::BufferTooShort`] as
/// above. [`IoError::NoGeometry`] when no primitive has a vertex.
pub fn parse_gltf_with(
    bytes: &[u8],
    name: &str,
    base_dir: Option<&Path>,
    options: &GltfOptions,
) -> Result<PolygonSoup, IoError> {
    let error =
        |location: &str, rule: String| IoError::Gltf { file: name.to_owned(), location: location.to_owned(), rule };
    let is_glb = bytes.starts_with(GLB_MAGIC) || name.to_ascii_lowercase().ends_with(".glb");
    let (json_bytes, bin) = if is_glb { split_glb(bytes, &error)? } else { (bytes, None) };
    let json_at = if is_glb { "GLB chunk 0 (JSON)" } else { "JSON" };
    let raw: Value = serde_json::from_slice(json_bytes).map_err(|e| error(json_at, e.to_string()))?;
    check_raw_indices(&raw, name)?;
    let root = Root::from_slice(json_bytes).map_err(|e| error(json_at, e.to_string()))?;
    if let Some(extension) = root.extensions_required.first() {
        return Err(error("extensionsRequired", format!("requires {extension}, which this reader does not support")));
    }
    check_totals(&root, name, options)?;
    let buffers = root
        .buffers
        .iter()
        .enumerate()
        .map(|(i, buffer)| load_buffer(i, buffer, bin, base_dir, name, options, &error))
        .collect::<Result<Vec<_>, _>>()?;
    let reader = Reader { root: &root, buffers, error: &error };

    let mut soup = PolygonSoup::new();
    let (mut texcoord_sets, mut texcoords): (Option<Vec<u32>>, Vec<Vec<f64>>) = (None, Vec::new());
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let at = format!("meshes[{m}].primitives[{p}]");
            match primitive.mode {
                Checked::Valid(Mode::Triangles) => {}
                Checked::Valid(mode) => {
                    let rule = format!("mode {} ({mode:?}) is not supported; only TRIANGLES (4)", mode.as_gl_enum());
                    return Err(error(&format!("{at}.mode"), rule));
                }
                Checked::Invalid => return Err(error(&format!("{at}.mode"), "is not a glTF primitive mode".into())),
            }
            let Some(position) = primitive.attributes.get(&Checked::Valid(Semantic::Positions)) else {
                return Err(error(
                    &format!("{at}.attributes"),
                    "has no POSITION; a mesh needs vertex positions".into(),
                ));
            };
            let base = soup.vertex_count();
            let count = reader.positions(position.value(), &format!("{at}.attributes.POSITION"), &mut soup)?;
            // Texture coordinates, per vertex; primitives must agree on which sets they have.
            let mut sets: Vec<(u32, usize)> = primitive
                .attributes
                .iter()
                .filter_map(|(k, a)| match k {
                    Checked::Valid(Semantic::TexCoords(n)) => Some((*n, a.value())),
                    _ => None,
                })
                .collect();
            sets.sort_unstable();
            let names: Vec<u32> = sets.iter().map(|s| s.0).collect();
            match &texcoord_sets {
                None => {
                    texcoord_sets = Some(names);
                    texcoords = vec![Vec::new(); sets.len()];
                }
                Some(known) if *known != names => {
                    let rule = format!(
                        "has TEXCOORD sets {names:?}, but the primitives before it {known:?}; a channel needs a value \
                         at every vertex"
                    );
                    return Err(error(&format!("{at}.attributes"), rule));
                }
                Some(_) => {}
            }
            for ((n, accessor), values) in sets.iter().zip(&mut texcoords) {
                reader.texcoords(*accessor, &format!("{at}.attributes.TEXCOORD_{n}"), count, values)?;
            }
            let indices = match primitive.indices {
                Some(index) => reader.indices(index.value(), &format!("{at}.indices"), count)?,
                None => (0..count).collect(),
            };
            if indices.len() % 3 != 0 {
                let rule = format!(
                    "{} vertex indices do not make whole triangles (TRIANGLES needs a multiple of 3)",
                    indices.len()
                );
                return Err(error(&at, rule));
            }
            for triangle in indices.chunks_exact(3) {
                let id = |i: usize| {
                    VertexId::from_usize(base + i)
                        .ok_or_else(|| error(&at, "more vertices than 32-bit vertex ids can address".into()))
                };
                soup.push_face([id(triangle[0])?, id(triangle[1])?, id(triangle[2])?]);
            }
        }
    }
    if soup.vertex_count() == 0 {
        return Err(IoError::NoGeometry { file: name.to_owned() });
    }
    // One value per glTF vertex, so each corner's index is its vertex's (before any welding).
    let corners: Vec<u32> = soup.raw_faces().1.iter().map(|v| v.raw()).collect();
    for (n, values) in texcoord_sets.unwrap_or_default().into_iter().zip(texcoords) {
        let name = if n == 0 { Channel::UV.to_owned() } else { format!("{}{n}", Channel::UV) };
        soup.channels.push(Channel::new(name, 2, values, corners.clone()));
    }
    Ok(if options.weld { welded(soup) } else { soup })
}

/// `soup` with vertices of equal positions made one (the first of them), faces and tags
/// renumbered; channels keep their per-corner values.
fn welded(soup: PolygonSoup) -> PolygonSoup {
    let mut first: std::collections::HashMap<[u64; 3], VertexId> = std::collections::HashMap::new();
    let mut out = PolygonSoup::with_capacity(soup.vertex_count(), soup.face_count(), soup.corner_count());
    let to: Vec<VertexId> = soup
        .positions()
        .iter()
        .map(|p| *first.entry(p.to_array().map(f64::to_bits)).or_insert_with(|| out.push_vertex(*p)))
        .collect();
    for face in soup.faces() {
        out.push_face(face.iter().map(|v| to[v.index()]));
    }
    out.channels = soup.channels;
    out.tags = soup.tags;
    out
}

type ErrorFn<'a> = dyn Fn(&str, String) -> IoError + 'a;

/// Checks every accessor, buffer view and buffer number the reader follows as a `u64` on the raw
/// JSON: `gltf::json` 1.4 reads them as `u32`, and an index of 2^32 wraps to 0.
fn check_raw_indices(raw: &Value, name: &str) -> Result<(), IoError> {
    let len = |key: &str| raw.get(key).and_then(Value::as_array).map_or(0, Vec::len);
    let check = |value: Option<&Value>, location: String, what: &'static str| {
        let count = len(what);
        match value.and_then(Value::as_u64) {
            Some(index) if index >= count as u64 => {
                Err(IoError::GltfIndex { file: name.to_owned(), location, what, index, count })
            }
            // In range, absent, or not an unsigned integer (which `gltf::json` reports).
            _ => Ok(()),
        }
    };
    let items = |key: &str| raw.get(key).and_then(Value::as_array).into_iter().flatten().enumerate();
    for (m, mesh) in items("meshes") {
        let primitives = mesh.get("primitives").and_then(Value::as_array).into_iter().flatten();
        for (p, primitive) in primitives.enumerate() {
            let at = format!("meshes[{m}].primitives[{p}]");
            if let Some(attributes) = primitive.get("attributes").and_then(Value::as_object) {
                for (semantic, value) in attributes {
                    check(Some(value), format!("{at}.attributes.{semantic}"), "accessors")?;
                }
            }
            check(primitive.get("indices"), format!("{at}.indices"), "accessors")?;
        }
    }
    for (a, accessor) in items("accessors") {
        check(accessor.get("bufferView"), format!("accessors[{a}].bufferView"), "bufferViews")?;
    }
    for (v, view) in items("bufferViews") {
        check(view.get("buffer"), format!("bufferViews[{v}].buffer"), "buffers")?;
    }
    Ok(())
}

/// Sums the vertex and index counts of all primitives and checks them against the limits,
/// before any buffer is read or any vertex allocated: primitives may share one accessor, so a
/// small file can ask for a great many vertices.
fn check_totals(root: &Root, name: &str, options: &GltfOptions) -> Result<(), IoError> {
    let count = |index: usize| root.accessors.get(index).map_or(0, |a| a.count.0);
    let (mut vertices, mut indices) = (0u64, 0u64);
    for primitive in root.meshes.iter().flat_map(|mesh| &mesh.primitives) {
        let n = primitive.attributes.get(&Checked::Valid(Semantic::Positions)).map_or(0, |a| count(a.value()));
        vertices = vertices.saturating_add(n);
        indices = indices.saturating_add(primitive.indices.map_or(n, |i| count(i.value())));
    }
    let too_large = |what, requested, limit| IoError::GltfTooLarge { file: name.to_owned(), what, requested, limit };
    if vertices > options.max_vertices {
        return Err(too_large("vertices", vertices, options.max_vertices));
    }
    if indices > options.max_indices {
        return Err(too_large("indices", indices, options.max_indices));
    }
    Ok(())
}

/// Splits a GLB container into its JSON chunk and its BIN chunk (if any).
fn split_glb<'b>(bytes: &'b [u8], error: &ErrorFn<'_>) -> Result<(&'b [u8], Option<&'b [u8]>), IoError> {
    let word = |bytes: &[u8], at: usize| bytes.get(at..at + 4).and_then(|w| w.try_into().ok()).map(u32::from_le_bytes);
    let header = "GLB header";
    if !bytes.starts_with(GLB_MAGIC) {
        let magic = bytes[..bytes.len().min(4)].escape_ascii();
        return Err(error(header, format!("bad magic \"{magic}\"; a GLB file starts with \"glTF\"")));
    }
    let (Some(version), Some(length)) = (word(bytes, 4), word(bytes, 8)) else {
        return Err(error(header, format!("truncated: the file has {} bytes, a GLB header needs 12", bytes.len())));
    };
    if version != 2 {
        return Err(error(header, format!("version {version}; only glTF 2 is supported")));
    }
    let length = length as usize;
    let Some(mut rest) = bytes.get(12..length) else {
        return Err(error(header, format!("declares {length} bytes but the file has {} (truncated)", bytes.len())));
    };
    let (mut json, mut bin) = (None, None);
    for chunk in 0.. {
        if rest.is_empty() {
            break;
        }
        let location = format!("GLB chunk {chunk}");
        let (Some(chunk_length), Some(kind)) = (word(rest, 0), word(rest, 4)) else {
            return Err(error(&location, format!("truncated: {} bytes left, a chunk header needs 8", rest.len())));
        };
        let end = 8 + chunk_length as usize;
        let Some(data) = rest.get(8..end) else {
            let rule = format!("declares {chunk_length} bytes but {} remain (truncated)", rest.len() - 8);
            return Err(error(&location, rule));
        };
        match (chunk, kind) {
            (0, CHUNK_JSON) => json = Some(data),
            (0, _) => return Err(error(&location, "is not a JSON chunk; the first GLB chunk must be JSON".into())),
            (1, CHUNK_BIN) => bin = Some(data),
            // The spec asks readers to skip chunks of unknown types.
            _ => {}
        }
        rest = &rest[end..];
    }
    let json = json.ok_or_else(|| error("GLB chunk 0", "missing: a GLB file needs a JSON chunk".into()))?;
    Ok((json, bin))
}

/// The bytes of buffer `index`: the GLB BIN chunk, a base64 data URI, or a file in the glTF's
/// folder (see [`parse_gltf_with`]).
fn load_buffer<'b>(
    index: usize,
    buffer: &json::Buffer,
    bin: Option<&'b [u8]>,
    base_dir: Option<&Path>,
    name: &str,
    options: &GltfOptions,
    error: &ErrorFn<'_>,
) -> Result<Cow<'b, [u8]>, IoError> {
    let location = format!("buffers[{index}]");
    let declared = buffer.byte_length.0;
    let data = match (buffer.uri.as_deref(), bin) {
        (None, Some(bin)) if index == 0 => Cow::Borrowed(bin),
        (None, _) => {
            return Err(error(
                &location,
                "has no uri, and only buffers[0] of a GLB with a BIN chunk may omit it".into(),
            ));
        }
        (Some(uri), _) if uri.starts_with("data:") => {
            let Some((_, data)) = uri.split_once(";base64,") else {
                return Err(error(
                    &location,
                    "is a data URI without base64 data; only base64 data URIs are supported".into(),
                ));
            };
            base64::engine::general_purpose::STANDARD
                .decode(data)
                .map(Cow::Owned)
                .map_err(|e| error(&location, format!("data URI is not valid base64: {e}")))?
        }
        (Some(uri), _) => {
            let decoded = percent_decode(uri);
            let absolute = Path::new(&decoded).is_absolute();
            if uri.contains(':') || (absolute && !options.allow_outside_uris) {
                if !uri.contains(':') {
                    let file = name.to_owned();
                    return Err(IoError::UriOutsideFolder { file, location, uri: uri.to_owned() });
                }
                return Err(error(
                    &location,
                    format!("uri {uri:?} is not relative; only relative file URIs and data URIs are supported"),
                ));
            }
            let Some(dir) = base_dir else {
                return Err(error(
                    &location,
                    format!("refers to the file {uri:?}, but no directory was given to find it in"),
                ));
            };
            let path = dir.join(&decoded);
            let io = |path: &Path| {
                let path = path.to_owned();
                move |source| IoError::Io { path, source }
            };
            let canonical = path.canonicalize().map_err(io(&path))?;
            if !options.allow_outside_uris {
                let dir = dir.canonicalize().map_err(io(dir))?;
                if !canonical.starts_with(&dir) {
                    return Err(IoError::UriOutsideFolder { file: name.to_owned(), location, uri: uri.to_owned() });
                }
            }
            // Checked before opening, as opening a FIFO blocks; and again on the open file.
            let not_regular = || IoError::NotARegularFile {
                file: name.to_owned(),
                location: location.clone(),
                uri: uri.to_owned(),
                path: path.clone(),
            };
            if !fs::metadata(&canonical).map_err(io(&path))?.is_file() {
                return Err(not_regular());
            }
            let file = File::open(&canonical).map_err(io(&path))?;
            let metadata = file.metadata().map_err(io(&path))?;
            if !metadata.is_file() {
                return Err(not_regular());
            }
            if metadata.len() < declared {
                let (file, actual) = (name.to_owned(), metadata.len());
                return Err(IoError::BufferTooShort { file, location, declared, actual });
            }
            let mut data = Vec::new();
            file.take(declared).read_to_end(&mut data).map_err(io(&path))?;
            Cow::Owned(data)
        }
    };
    if (data.len() as u64) < declared {
        let actual = data.len() as u64;
        return Err(IoError::BufferTooShort { file: name.to_owned(), location, declared, actual });
    }
    Ok(data)
}

/// Decodes `%XX` escapes of a URI path (a space is written `%20`).
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (bytes[i], hex) {
            (b'%', Some(byte)) => {
                out.push(byte);
                i += 3;
            }
            (byte, _) => {
                out.push(byte);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The parsed document and its loaded buffers.
struct Reader<'a> {
    root: &'a Root,
    buffers: Vec<Cow<'a, [u8]>>,
    error: &'a ErrorFn<'a>,
}

/// The elements of an accessor: `count` elements of `size` bytes, `stride` bytes apart, all
/// inside `data` (checked when made).
struct Elements<'a> {
    data: &'a [u8],
    stride: usize,
    size: usize,
    count: usize,
}

impl<'a> Elements<'a> {
    fn iter(&self) -> impl Iterator<Item = &'a [u8]> + '_ {
        // In bounds: `data` holds (count - 1) * stride + size bytes.
        (0..self.count).map(|i| &self.data[i * self.stride..i * self.stride + self.size])
    }
}

impl Reader<'_> {
    /// Checks accessor `index` (referred to from `referrer`): its type (`ok`, else the error says
    /// `expected`) and its place in its buffer. Returns its component type and elements.
    fn accessor(
        &self,
        index: usize,
        referrer: &str,
        expected: &str,
        ok: impl Fn(ComponentType, Type) -> bool,
    ) -> Result<(ComponentType, Elements<'_>), IoError> {
        let error = self.error;
        let root = self.root;
        let accessor = root.accessors.get(index).ok_or_else(|| {
            error(
                referrer,
                format!("refers to accessors[{index}], but the file has {} accessors", root.accessors.len()),
            )
        })?;
        let at = format!("accessors[{index}]");
        if accessor.sparse.is_some() {
            return Err(error(&at, "is sparse; sparse accessors are not supported".into()));
        }
        let (Checked::Valid(GenericComponentType(component)), Checked::Valid(kind)) =
            (accessor.component_type, accessor.type_)
        else {
            return Err(error(&at, "has an invalid componentType or type".into()));
        };
        if !ok(component, kind) {
            return Err(error(&at, format!("{expected}; this is {kind:?} of {component:?}")));
        }
        let Some(view_index) = accessor.buffer_view.map(|v| v.value()) else {
            return Err(error(&at, "has no bufferView; accessors without data are not supported".into()));
        };
        let view = root.buffer_views.get(view_index).ok_or_else(|| {
            let rule = format!("refers to bufferViews[{view_index}], but the file has {}", root.buffer_views.len());
            error(&format!("{at}.bufferView"), rule)
        })?;
        let view_at = format!("bufferViews[{view_index}]");
        let buffer_index = view.buffer.value();
        let (Some(buffer), Some(data)) = (root.buffers.get(buffer_index), self.buffers.get(buffer_index)) else {
            let rule = format!("refers to buffers[{buffer_index}], but the file has {}", root.buffers.len());
            return Err(error(&format!("{view_at}.buffer"), rule));
        };
        let view_start = view.byte_offset.map_or(0, |o| o.0);
        let view_length = view.byte_length.0;
        if view_start.checked_add(view_length).is_none_or(|end| end > buffer.byte_length.0) {
            let rule = format!(
                "bytes {view_start}..+{view_length} lie outside buffers[{buffer_index}] ({} bytes)",
                buffer.byte_length.0
            );
            return Err(error(&view_at, rule));
        }
        let size = component.size() * kind.multiplicity();
        let stride = view.byte_stride.map_or(size, |s| s.0);
        if stride < size {
            return Err(error(&view_at, format!("byteStride {stride} is less than the {size}-byte elements of {at}")));
        }
        let offset = accessor.byte_offset.map_or(0, |o| o.0);
        let count = accessor.count.0;
        // The bytes the accessor reads: the last element starts (count - 1) strides in.
        let needed = count
            .checked_sub(1)
            .map_or(Some(0), |last| last.checked_mul(stride as u64)?.checked_add(size as u64))
            .and_then(|n| n.checked_add(offset));
        if needed.is_none_or(|n| n > view_length) {
            let rule = format!(
                "{count} elements of {size} bytes, {stride} apart, from byte {offset}, overrun {view_at} ({view_length} bytes)"
            );
            return Err(error(&at, rule));
        }
        // Every bound was checked above against the buffer's declared length, which is at most
        // its actual length (see `load_buffer`), so these conversions and the slice are exact.
        let start = (view_start + offset) as usize;
        let end = (view_start + needed.unwrap_or(0)) as usize;
        let elements = Elements { data: &data[start..end], stride, size, count: count as usize };
        Ok((component, elements))
    }

    /// Appends the positions of accessor `index` to `soup`; returns how many.
    fn positions(&self, index: usize, referrer: &str, soup: &mut PolygonSoup) -> Result<usize, IoError> {
        let expected = "POSITION must be VEC3 of FLOAT (5126)";
        let (_, elements) =
            self.accessor(index, referrer, expected, |c, k| (c, k) == (ComponentType::F32, Type::Vec3))?;
        let at = format!("accessors[{index}]");
        for (i, bytes) in elements.iter().enumerate() {
            let c = |k: usize| f32::from_le_bytes([bytes[4 * k], bytes[4 * k + 1], bytes[4 * k + 2], bytes[4 * k + 3]]);
            let p = Vec3::new(c(0), c(1), c(2));
            if !p.is_finite() {
                return Err((self.error)(&at, format!("element {i} = {p} is not finite; positions must be finite")));
            }
            soup.push_vertex(p.as_dvec3());
        }
        Ok(elements.count)
    }

    /// Appends the texture coordinates of accessor `index` (one `u v` per vertex of a primitive
    /// with `vertex_count` vertices) to `values`.
    fn texcoords(
        &self,
        index: usize,
        referrer: &str,
        vertex_count: usize,
        values: &mut Vec<f64>,
    ) -> Result<(), IoError> {
        let expected = "TEXCOORD must be VEC2 of FLOAT, or of normalized unsigned bytes or shorts";
        let (component, elements) = self.accessor(index, referrer, expected, |c, k| {
            k == Type::Vec2 && matches!(c, ComponentType::F32 | ComponentType::U8 | ComponentType::U16)
        })?;
        if elements.count != vertex_count {
            let rule = format!("has {} elements, but POSITION has {vertex_count}", elements.count);
            return Err((self.error)(&format!("accessors[{index}]"), rule));
        }
        let read: fn(&[u8], usize) -> f64 = match component {
            ComponentType::F32 => {
                |b, k| f64::from(f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]))
            }
            ComponentType::U8 => |b, k| f64::from(b[k]) / 255.0,
            _ => |b, k| f64::from(u16::from_le_bytes([b[2 * k], b[2 * k + 1]])) / 65535.0,
        };
        for (i, bytes) in elements.iter().enumerate() {
            let (u, v) = (read(bytes, 0), read(bytes, 1));
            if !(u.is_finite() && v.is_finite()) {
                return Err((self.error)(&format!("accessors[{index}]"), format!("element {i} is not finite")));
            }
            values.extend([u, v]);
        }
        Ok(())
    }

    /// The vertex indices of accessor `index`, each checked against `vertex_count`.
    fn indices(&self, index: usize, referrer: &str, vertex_count: usize) -> Result<Vec<usize>, IoError> {
        let expected = "indices must be SCALAR of u8, u16 or u32";
        let (component, elements) = self.accessor(index, referrer, expected, |c, k| {
            k == Type::Scalar && matches!(c, ComponentType::U8 | ComponentType::U16 | ComponentType::U32)
        })?;
        let read: fn(&[u8]) -> u32 = match component {
            ComponentType::U8 => |b| u32::from(b[0]),
            ComponentType::U16 => |b| u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        };
        elements
            .iter()
            .map(read)
            .enumerate()
            .map(|(i, v)| {
                if (v as usize) < vertex_count {
                    Ok(v as usize)
                } else {
                    let rule =
                        format!("element {i} is {v}, but POSITION has {vertex_count} vertices (accessors[{index}])");
                    Err((self.error)(referrer, rule))
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;

    /// A one-triangle glTF whose buffer is the file `uri`, of `byte_length` bytes.
    fn gltf_with_buffer(uri: &str, byte_length: usize) -> Value {
        json!({
            "asset": { "version": "2.0" },
            "buffers": [{ "uri": uri, "byteLength": byte_length }],
            "bufferViews": [{ "buffer": 0, "byteLength": 36 }],
            "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3" }],
            "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        })
    }

    fn triangle_bytes() -> Vec<u8> {
        [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].iter().flatten().flat_map(|x| x.to_le_bytes()).collect()
    }

    /// Writes `json` as `dir/name` and loads it with `options`.
    fn load_json(dir: &Path, name: &str, json: &Value, options: &GltfOptions) -> Result<PolygonSoup, IoError> {
        let path = dir.join(name);
        fs::write(&path, json.to_string()).unwrap();
        load_gltf_with(&path, options)
    }

    /// A unit square as two triangles whose shared vertices are split, as an exporter splits
    /// them along a UV seam: six vertices, positions then texture coordinates in one buffer.
    fn split_square(with_uv_on_second: bool) -> Value {
        let p =
            [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let t = [[0.0f32, 0.0], [0.5, 0.0], [0.5, 0.5], [0.6, 0.0], [1.0, 0.5], [0.6, 0.5]];
        let mut bytes: Vec<u8> = p.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        bytes.extend(t.iter().flatten().flat_map(|x| x.to_le_bytes()));
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bytes)
        );
        let second =
            if with_uv_on_second { json!({ "POSITION": 1, "TEXCOORD_0": 3 }) } else { json!({ "POSITION": 1 }) };
        json!({
            "asset": { "version": "2.0" },
            "buffers": [{ "uri": uri, "byteLength": bytes.len() }],
            "bufferViews": [{ "buffer": 0, "byteLength": 72 }, { "buffer": 0, "byteOffset": 72, "byteLength": 48 }],
            "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3" },
                { "bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3" },
                { "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2" },
                { "bufferView": 1, "byteOffset": 24, "componentType": 5126, "count": 3, "type": "VEC2" },
            ],
            "meshes": [{ "primitives": [
                { "attributes": { "POSITION": 0, "TEXCOORD_0": 2 } },
                { "attributes": second },
            ] }],
        })
    }

    #[test]
    fn texcoords_become_the_uv_channel_and_welding_joins_split_vertices() {
        let dir = tempfile::tempdir().unwrap();
        let split = load_json(dir.path(), "square.gltf", &split_square(true), &GltfOptions::DEFAULT).unwrap();
        assert_eq!((split.vertex_count(), split.channels.len()), (6, 1));
        let welded =
            load_json(dir.path(), "square.gltf", &split_square(true), &GltfOptions::DEFAULT.with_weld(true)).unwrap();
        assert_eq!(welded.vertex_count(), 4);
        let mesh = subdiv_mesh::Mesh::build(welded).unwrap();
        assert_eq!(mesh.boundary_edge_count(), 4, "one piece: the diagonal is shared");
        let uv = mesh.channel(Channel::UV).unwrap();
        // Each corner keeps its own coordinate: the diagonal is a seam of the channel.
        let diagonal = mesh.find_edge(VertexId::new(0), VertexId::new(2)).unwrap();
        assert!(mesh.is_seam(uv, diagonal));
        assert_eq!(
            uv.value(uv.corner_value(mesh.face_half_edges(subdiv_mesh::FaceId::new(1)).next().unwrap())),
            [0.6, 0.0].map(|x: f32| f64::from(x))
        );
        // A primitive without the set the others have: an error naming it.
        let error = load_json(dir.path(), "square.gltf", &split_square(false), &GltfOptions::DEFAULT).unwrap_err();
        assert!(error.to_string().contains("meshes[0].primitives[1].attributes"), "{error}");
    }

    #[test]
    fn buffer_uris_outside_the_gltf_folder_are_refused_unless_allowed() {
        let root = tempfile::tempdir().unwrap();
        let folder = root.path().join("model");
        fs::create_dir(&folder).unwrap();
        fs::write(root.path().join("secret.bin"), triangle_bytes()).unwrap();
        let escape = gltf_with_buffer("../secret.bin", 36);
        let error = load_json(&folder, "a.gltf", &escape, &GltfOptions::DEFAULT).unwrap_err();
        assert!(matches!(error, IoError::UriOutsideFolder { .. }), "{error:?}");
        let text = error.to_string();
        assert!(
            text.ends_with(
                "a.gltf: buffers[0].uri '../secret.bin': outside the glTF's folder; pass --allow-outside-uris to allow"
            ),
            "{text}"
        );
        let allowed = GltfOptions::DEFAULT.with_allow_outside_uris(true);
        assert_eq!(load_json(&folder, "a.gltf", &escape, &allowed).unwrap().vertex_count(), 3);
        let absolute = gltf_with_buffer(root.path().join("secret.bin").to_str().unwrap(), 36);
        let error = load_json(&folder, "b.gltf", &absolute, &GltfOptions::DEFAULT).unwrap_err();
        assert!(matches!(error, IoError::UriOutsideFolder { .. }), "{error:?}");
        // A file inside the folder is read as before.
        fs::write(folder.join("inside.bin"), triangle_bytes()).unwrap();
        let inside = gltf_with_buffer("inside.bin", 36);
        assert_eq!(load_json(&folder, "c.gltf", &inside, &GltfOptions::DEFAULT).unwrap().vertex_count(), 3);
    }

    #[cfg(unix)]
    #[test]
    fn only_regular_files_are_read_and_at_most_byte_length_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let allowed = GltfOptions::DEFAULT.with_allow_outside_uris(true);
        // /dev/zero would be read until memory runs out.
        let error = load_json(dir.path(), "zero.gltf", &gltf_with_buffer("/dev/zero", 36), &allowed).unwrap_err();
        assert!(matches!(error, IoError::NotARegularFile { .. }), "{error:?}");
        fs::create_dir(dir.path().join("sub")).unwrap();
        let error = load_json(dir.path(), "dir.gltf", &gltf_with_buffer("sub", 36), &allowed).unwrap_err();
        assert!(matches!(error, IoError::NotARegularFile { .. }), "{error:?}");
        // Shorter than byteLength: a typed error; longer: only byteLength bytes are kept.
        fs::write(dir.path().join("short.bin"), &triangle_bytes()[..20]).unwrap();
        let error = load_json(dir.path(), "short.gltf", &gltf_with_buffer("short.bin", 36), &allowed).unwrap_err();
        assert!(matches!(error, IoError::BufferTooShort { declared: 36, actual: 20, .. }), "{error:?}");
        let mut long = triangle_bytes();
        long.resize(4096, 7);
        fs::write(dir.path().join("long.bin"), long).unwrap();
        let soup = load_json(dir.path(), "long.gltf", &gltf_with_buffer("long.bin", 36), &allowed).unwrap();
        assert_eq!(soup.vertex_count(), 3);
    }

    #[test]
    fn indices_of_2_pow_32_are_errors_not_index_0() {
        let bytes = triangle_bytes();
        let data = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bytes)
        );
        let valid = gltf_with_buffer(&data, 36);
        assert!(parse_gltf(valid.to_string().as_bytes(), "t.gltf", None).is_ok());
        let edits = [
            ("meshes[0].primitives[0].attributes.POSITION", "/meshes/0/primitives/0/attributes/POSITION"),
            ("accessors[0].bufferView", "/accessors/0/bufferView"),
            ("bufferViews[0].buffer", "/bufferViews/0/buffer"),
        ];
        for (location, pointer) in edits {
            let mut json = valid.clone();
            *json.pointer_mut(pointer).unwrap() = json!(1u64 << 32);
            let error = parse_gltf(json.to_string().as_bytes(), "t.gltf", None).unwrap_err();
            assert!(
                matches!(&error, IoError::GltfIndex { location: at, index, .. } if at == location && *index == 1 << 32),
                "{error:?}"
            );
        }
    }

    #[test]
    fn primitives_sharing_one_big_accessor_are_counted_before_anything_is_read() {
        // 1,000 primitives × 100,000 vertices: 10^8 > 2^26, refused before the (absent) buffer
        // file is even opened.
        let primitive = json!({ "attributes": { "POSITION": 0 } });
        let json = json!({
            "asset": { "version": "2.0" },
            "buffers": [{ "uri": "missing.bin", "byteLength": 1_200_000 }],
            "bufferViews": [{ "buffer": 0, "byteLength": 1_200_000 }],
            "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 100_000, "type": "VEC3" }],
            "meshes": [{ "primitives": vec![primitive; 1000] }],
        });
        let error = parse_gltf(json.to_string().as_bytes(), "big.gltf", Some(Path::new("."))).unwrap_err();
        assert!(
            matches!(error, IoError::GltfTooLarge { what: "vertices", requested: 100_000_000, limit: 67_108_864, .. }),
            "{error:?}"
        );
        let options = GltfOptions::DEFAULT.with_max_vertices(u64::MAX).with_max_indices(1000);
        let error = parse_gltf_with(json.to_string().as_bytes(), "big.gltf", None, &options).unwrap_err();
        assert!(matches!(error, IoError::GltfTooLarge { what: "indices", .. }), "{error:?}");
    }
}
