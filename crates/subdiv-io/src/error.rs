//! [`IoError`]: every way reading or writing a mesh file can fail, each naming the place.

use std::path::PathBuf;

use subdiv_mesh::MeshError;

/// Why a mesh file could not be read or written.
///
/// Each variant displays as one line that names the place — `FILE:LINE` for OBJ, `FILE: LOCATION`
/// for glTF (a JSON path such as `meshes[0].primitives[1].attributes.POSITION`, or `GLB header`)
/// — and the rule the file breaks.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The operating system could not read or write a file.
    #[error("{}: {source}", shown(path))]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system reported.
        source: std::io::Error,
    },
    /// The file name has no extension this crate reads.
    #[error("{}: unknown mesh format; expected a .obj, .gltf or .glb file", shown(path))]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The file holds no vertex and no face.
    #[error("{file}: no geometry; a mesh file needs vertices and faces")]
    NoGeometry {
        /// The file.
        file: String,
    },
    /// An OBJ record that must be parsed (`v`, `f`, `t`, or a line that starts with no keyword)
    /// is not UTF-8 text.
    #[error("{file}:{line}: not UTF-8 text; OBJ records must be UTF-8")]
    NotUtf8 {
        /// The file.
        file: String,
        /// The 1-based line.
        line: usize,
    },
    /// A malformed OBJ record: a coordinate that is not a number, a face vertex that is not
    /// `v`, `v/vt`, `v//vn` or `v/vt/vn`, a tag whose counts do not match its arguments, …
    #[error("{file}:{line}: {rule}")]
    ObjSyntax {
        /// The file.
        file: String,
        /// The 1-based line.
        line: usize,
        /// The rule the record breaks.
        rule: String,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("{file}:{line}: coordinate {value} is not finite; vertex positions must be finite numbers")]
    NonFiniteCoordinate {
        /// The file.
        file: String,
        /// The 1-based line of the `v` record.
        line: usize,
        /// The offending value.
        value: f64,
    },
    /// A face uses vertex index 0, which OBJ does not have.
    #[error("{file}:{line}: vertex index 0; OBJ indices start at 1 (negative ones count back from the last vertex)")]
    IndexZero {
        /// The file.
        file: String,
        /// The 1-based line of the face.
        line: usize,
    },
    /// A face refers to a vertex that does not exist.
    #[error("{file}:{line}: {}", index_rule(*index, *vertex_count))]
    IndexOutOfRange {
        /// The file.
        file: String,
        /// The 1-based line of the face.
        line: usize,
        /// The index as written (1-based, or negative for relative indices).
        index: i64,
        /// How many vertices the file has; for a negative index, how many precede the face.
        vertex_count: usize,
    },
    /// A face vertex index does not fit a 32-bit vertex id.
    #[error("{file}:{line}: vertex index {token} is too large; vertex ids are 32-bit")]
    IndexOverflow {
        /// The file.
        file: String,
        /// The 1-based line of the face.
        line: usize,
        /// The index as written.
        token: String,
    },
    /// A face's texture-coordinate index names no `vt` line.
    #[error("{file}:{line}: {}", texcoord_rule(*index, *count))]
    TexCoordOutOfRange {
        /// The file.
        file: String,
        /// The 1-based line of the face.
        line: usize,
        /// The index as written (1-based, or negative for relative indices).
        index: i64,
        /// How many `vt` lines the file has; for a negative index, how many precede the face.
        count: usize,
    },
    /// Texture coordinates on some face corners but not on all: a face-varying channel needs
    /// one value at every corner of every face.
    #[error("{file}:{line}: {rule}")]
    TexCoordsIncomplete {
        /// The file.
        file: String,
        /// The 1-based line of the face.
        line: usize,
        /// What is missing, and where the file has them.
        rule: String,
    },
    /// A face lists fewer than three vertices.
    #[error("{file}:{line}: face has {count} vertices; a face needs at least 3")]
    FaceTooSmall {
        /// The file.
        file: String,
        /// The 1-based line of the face.
        line: usize,
        /// How many vertices it lists.
        count: usize,
    },
    /// A `t` tag refers to a vertex or face that does not exist.
    #[error("{file}:{line}: t {tag}: {what} {index} is out of range 0..{count} (tag indices are 0-based)")]
    TagOutOfRange {
        /// The file.
        file: String,
        /// The 1-based line of the tag.
        line: usize,
        /// The tag name (`crease`, `corner`, `hole`).
        tag: &'static str,
        /// `"vertex"` or `"face"`.
        what: &'static str,
        /// The index as written.
        index: i64,
        /// How many vertices (or faces) the file has.
        count: usize,
    },
    /// A glTF or GLB file breaks a rule of the format, or uses a feature this crate does not read.
    #[error("{file}: {location}: {rule}")]
    Gltf {
        /// The file.
        file: String,
        /// Where: a JSON path (`accessors[3]`, `meshes[0].primitives[1].indices`), or
        /// `GLB header` / `GLB chunk N`.
        location: String,
        /// The rule broken.
        rule: String,
    },
    /// A glTF index (an accessor, buffer view or buffer number) is not one of the document's.
    /// Checked as a `u64` on the raw JSON, so that an index of 2^32 is not read as 0.
    #[error("{file}: {location}: refers to {what}[{index}], but the file has {count}")]
    GltfIndex {
        /// The file.
        file: String,
        /// The JSON path of the reference, e.g. `meshes[0].primitives[0].indices`.
        location: String,
        /// `"accessors"`, `"bufferViews"` or `"buffers"`.
        what: &'static str,
        /// The index as written.
        index: u64,
        /// How many the file has.
        count: usize,
    },
    /// A glTF buffer URI leads out of the glTF file's folder (a `../` escape, an absolute path,
    /// a symlink), and [`GltfOptions::allow_outside_uris`](crate::GltfOptions) is off.
    #[error(
        "{file}: {location}.uri '{}': outside the glTF's folder; pass --allow-outside-uris to allow",
        one_line(uri)
    )]
    UriOutsideFolder {
        /// The glTF file.
        file: String,
        /// `buffers[N]`.
        location: String,
        /// The URI as written.
        uri: String,
    },
    /// A glTF buffer URI names something that is not a regular file (a device, FIFO, directory).
    #[error("{file}: {location}.uri '{}': {} is not a regular file", one_line(uri), shown(path))]
    NotARegularFile {
        /// The glTF file.
        file: String,
        /// `buffers[N]`.
        location: String,
        /// The URI as written.
        uri: String,
        /// The path it resolves to.
        path: PathBuf,
    },
    /// A glTF buffer holds fewer bytes than its `byteLength`.
    #[error("{file}: {location}: declares byteLength {declared} but holds {actual} bytes")]
    BufferTooShort {
        /// The glTF file.
        file: String,
        /// `buffers[N]`.
        location: String,
        /// Its `byteLength`.
        declared: u64,
        /// The bytes there are.
        actual: u64,
    },
    /// The primitives of a glTF file ask for more vertices or indices, in all, than the
    /// reader's limit ([`GltfOptions`](crate::GltfOptions)); checked before anything is read.
    #[error("{file}: its primitives have {requested} {what} in all; the limit is {limit} (GltfOptions::max_{what})")]
    GltfTooLarge {
        /// The file.
        file: String,
        /// `"vertices"` or `"indices"`.
        what: &'static str,
        /// The sum over all primitives.
        requested: u64,
        /// The limit.
        limit: u64,
    },
    /// The file was read but its polygons do not make a valid mesh.
    #[error("{}: {source}", at(file, *line))]
    Mesh {
        /// The file.
        file: String,
        /// The 1-based line of the face, vertex or tag the error is about, when known.
        line: Option<usize>,
        /// The rule broken.
        source: MeshError,
    },
    /// The data handed to a writer cannot be written as a valid file.
    #[error("cannot write {format}: {rule}")]
    Unwritable {
        /// `"OBJ"` or `"GLB"`.
        format: &'static str,
        /// The rule broken, naming the vertex, face or index.
        rule: String,
    },
}

impl IoError {
    /// The 1-based line of an OBJ file the error points at, when it points at one.
    pub fn line(&self) -> Option<usize> {
        match *self {
            Self::NotUtf8 { line, .. }
            | Self::ObjSyntax { line, .. }
            | Self::NonFiniteCoordinate { line, .. }
            | Self::IndexZero { line, .. }
            | Self::IndexOutOfRange { line, .. }
            | Self::IndexOverflow { line, .. }
            | Self::TexCoordOutOfRange { line, .. }
            | Self::TexCoordsIncomplete { line, .. }
            | Self::FaceTooSmall { line, .. }
            | Self::TagOutOfRange { line, .. } => Some(line),
            Self::Mesh { line, .. } => line,
            _ => None,
        }
    }

    /// A short stable name of the rule, e.g. `"index-out-of-range"`, for reports and JSON.
    /// Mesh errors give [`MeshError::rule`].
    pub fn rule(&self) -> &'static str {
        match self {
            Self::Io { .. } => "io",
            Self::UnknownFormat { .. } => "unknown-format",
            Self::NoGeometry { .. } => "no-geometry",
            Self::NotUtf8 { .. } => "not-utf8",
            Self::ObjSyntax { .. } => "obj-syntax",
            Self::NonFiniteCoordinate { .. } => "non-finite-coordinate",
            Self::IndexZero { .. } => "index-zero",
            Self::IndexOutOfRange { .. } => "index-out-of-range",
            Self::IndexOverflow { .. } => "index-overflow",
            Self::TexCoordOutOfRange { .. } => "texcoord-out-of-range",
            Self::TexCoordsIncomplete { .. } => "texcoords-incomplete",
            Self::FaceTooSmall { .. } => "face-too-small",
            Self::TagOutOfRange { .. } => "tag-out-of-range",
            Self::Gltf { .. } => "gltf",
            Self::GltfIndex { .. } => "gltf-index",
            Self::UriOutsideFolder { .. } => "uri-outside-folder",
            Self::NotARegularFile { .. } => "not-a-regular-file",
            Self::BufferTooShort { .. } => "buffer-too-short",
            Self::GltfTooLarge { .. } => "gltf-too-large",
            Self::Mesh { source, .. } => source.rule(),
            Self::Unwritable { .. } => "unwritable",
        }
    }
}

fn index_rule(index: i64, vertex_count: usize) -> String {
    if index < 0 {
        format!(
            "relative vertex index {index} reaches before the first vertex: {vertex_count} vertices precede this face"
        )
    } else {
        format!("vertex index {index} is out of range: the file has {vertex_count} vertices (OBJ indices are 1-based)")
    }
}

fn texcoord_rule(index: i64, count: usize) -> String {
    if index < 0 {
        format!("relative texture-coordinate index {index} reaches before the first vt: {count} precede this face")
    } else {
        format!("texture-coordinate index {index} is out of range: the file has {count} vt lines (1-based)")
    }
}

/// `text` on one line: control characters (a newline in a file name or a URI) written as their
/// escapes, so that every message stays one line whatever names it carries.
pub(crate) fn one_line(text: &str) -> std::borrow::Cow<'_, str> {
    if text.chars().any(char::is_control) {
        text.chars().map(|c| if c.is_control() { c.escape_default().to_string() } else { c.to_string() }).collect()
    } else {
        std::borrow::Cow::Borrowed(text)
    }
}

/// A path as a message shows it: [`one_line`] of its display.
pub(crate) fn shown(path: &std::path::Path) -> String {
    one_line(&path.display().to_string()).into_owned()
}

fn at(file: &str, line: Option<usize>) -> String {
    match line {
        Some(line) => format!("{file}:{line}"),
        None => file.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A newline in a URI or a file name (the fuzzer's glTF finding) stays one line, escaped;
    /// other text, non-ASCII included, is shown as it is.
    #[test]
    fn names_with_control_characters_stay_on_one_line() {
        let e = IoError::UriOutsideFolder { file: "a.gltf".into(), location: "buffers[0]".into(), uri: "x\ny".into() };
        assert_eq!(e.to_string().lines().count(), 1);
        assert!(e.to_string().contains(r"'x\ny'"), "{e}");
        let e = IoError::Io { path: PathBuf::from("dir/\tfile\r\n.bin"), source: std::io::ErrorKind::NotFound.into() };
        assert!(e.to_string().starts_with(r"dir/\tfile\r\n.bin: "), "{e}");
        assert_eq!(one_line("héllo wörld"), "héllo wörld");
    }
}
