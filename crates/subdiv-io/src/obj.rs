//! Wavefront OBJ with OpenSubdiv's tag lines: [`ObjFile`], [`read_obj`], [`load_obj`],
//! [`write_obj`], [`write_obj_to`].
//!
//! Read: `v x y z [w | r g b]` (only x y z are kept), `vt u [v [w]]` (u and v are kept; v is 0
//! when absent), `f` with every index form (`v`, `v/vt`, `v//vn`, `v/vt/vn`, negative = relative
//! to the last vertex or `vt` defined), `t` tag lines, and `\` line continuation. Faces that
//! refer to texture coordinates make the soup's [`Channel::UV`] channel; then every corner of
//! every face must have one ([`IoError::TexCoordsIncomplete`] names the first that has none).
//! Normals, groups, materials, smoothing groups, lines, comments and any other keyword are
//! skipped, as OBJ readers do; a line that starts with no keyword at all (binary data, a bare
//! number) is an error.
//!
//! Tag lines read `t NAME nints/nfloats/nstrings ints… floats… strings…` with 0-based vertex and
//! face indices:
//! - `t crease n/1/0 v0 … vn-1 s` or `t crease n/(n-1)/0 v0 … vn-1 s0 … sn-2` — a chain of
//!   `n >= 2` vertices; one sharpness for every edge, or one per edge. Each edge becomes one
//!   [`CreaseTag`].
//! - `t corner n/1/0 v… s` or `t corner n/n/0 v… s…` — sharp vertices.
//! - `t hole n/0/0 f…` — hole faces.
//! - `t interpolateboundary 1/0/0 k` (0 none, 1 edge-and-corner, 2 edge-only),
//!   `t facevaryinginterpolateboundary 1/0/0 k` (0..=5), `t creasemethod 0/0/1 normal|chaikin`,
//!   `t smoothtriangles 0/0/1 catmark|smooth`.
//! - Any other name (OpenSubdiv 2's `vertexedit`, `edgeedit`, `faceedit`, …) is checked for
//!   well-formed counts and recorded by name in [`Tags::unsupported`].

use std::fs::File;
use std::io::{self, BufRead, BufReader, Write};
use std::num::IntErrorKind;
use std::path::Path;

use subdiv_mesh::{
    BoundaryInterpolation, BuildOptions, Channel, CornerTag, CreaseMethod, CreaseTag, DVec3, FaceId,
    FaceVaryingInterpolation, Mesh, MeshError, PolygonSoup, Tags, TriangleSubdivision, VertexId,
};

use crate::{IoError, atomic};

/// The UTF-8 byte-order mark, accepted (and skipped) at the start of a file.
const UTF8_BOM: &[u8] = b"\xEF\xBB\xBF";

/// Tag names this reader interprets; any other is recorded in [`Tags::unsupported`].
const KNOWN_TAGS: [&str; 7] = [
    "crease",
    "corner",
    "hole",
    "interpolateboundary",
    "facevaryinginterpolateboundary",
    "creasemethod",
    "smoothtriangles",
];

/// An OBJ file read into a [`PolygonSoup`], with the line every vertex, face and tag came from,
/// so that errors found later (by [`Mesh::build`]) can point into the file.
///
/// ```
/// use subdiv_io::ObjFile;
/// use subdiv_mesh::BuildOptions;
///
/// // Two triangles sharing the edge 1-3, but with the same orientation.
/// let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 4\nf 2 4 3\n";
/// let obj = ObjFile::read(text.as_bytes(), "bad.obj")?;
/// let error = obj.build(&BuildOptions::DEFAULT).unwrap_err();
/// assert_eq!(error.line(), Some(5));
/// assert!(error.to_string().starts_with("bad.obj:5: inconsistent orientation"));
/// # Ok::<(), subdiv_io::IoError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ObjFile {
    /// The file name errors are reported with.
    pub name: String,
    /// The polygons, positions and tags.
    pub soup: PolygonSoup,
    /// Where each element of [`soup`](Self::soup) was written.
    pub lines: ObjLines,
}

/// The 1-based line of each element of an [`ObjFile`]'s soup, indexed like the soup's lists.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ObjLines {
    /// The `v` line of each vertex.
    pub vertices: Vec<usize>,
    /// The `f` line of each face.
    pub faces: Vec<usize>,
    /// The `t crease` line of each entry of [`Tags::creases`] (a chain gives several entries).
    pub creases: Vec<usize>,
    /// The `t corner` line of each entry of [`Tags::corners`].
    pub corners: Vec<usize>,
    /// The `t hole` line of each entry of [`Tags::holes`].
    pub holes: Vec<usize>,
}

impl ObjLines {
    /// The line a [`MeshError`] is about: its face's, its vertex's or its tag's, when it names one.
    pub fn of_error(&self, error: &MeshError) -> Option<usize> {
        if let Some(face) = error.face() {
            return self.faces.get(face.index()).copied();
        }
        if let Some(vertex) = error.vertex() {
            return self.vertices.get(vertex.index()).copied();
        }
        let (lines, index) = match *error {
            MeshError::CreaseNotAnEdge { index, .. }
            | MeshError::TagVertexOutOfRange { tag: "crease", index, .. }
            | MeshError::InvalidSharpness { tag: "crease", index, .. } => (&self.creases, index),
            MeshError::TagVertexOutOfRange { index, .. } | MeshError::InvalidSharpness { index, .. } => {
                (&self.corners, index)
            }
            MeshError::HoleOutOfRange { index, .. } => (&self.holes, index),
            _ => return None,
        };
        lines.get(index).copied()
    }
}

impl ObjFile {
    /// Reads OBJ text from `reader`; `name` is the file name errors carry.
    ///
    /// # Errors
    /// The first rule the text breaks, with its line (see [`IoError`]); reading failures as
    /// [`IoError::Io`] with `name` as the path.
    pub fn read(mut reader: impl BufRead, name: &str) -> Result<Self, IoError> {
        // Not `PolygonSoup::default()`: subdiv-mesh derives it with no face offsets at all.
        let obj = Self { name: name.to_owned(), soup: PolygonSoup::new(), lines: ObjLines::default() };
        let mut parser = Parser { obj, tag_refs: Vec::new(), face: Vec::new(), uv: TexCoords::default() };
        let mut record = Vec::new();
        let mut line = 0;
        while let Some(first_line) = next_record(&mut reader, &mut record, &mut line)
            .map_err(|source| IoError::Io { path: name.into(), source })?
        {
            // A UTF-8 byte-order mark, as Windows editors write, is no part of the first record.
            let text = if first_line == 1 { record.strip_prefix(UTF8_BOM).unwrap_or(&record) } else { &record };
            parser.record(text, first_line)?;
        }
        parser.finish()
    }

    /// Reads the OBJ file at `path`.
    ///
    /// # Errors
    /// As [`read`](Self::read); opening or reading the file fails as [`IoError::Io`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self, IoError> {
        let path = path.as_ref();
        let file = File::open(path).map_err(|source| IoError::Io { path: path.to_owned(), source })?;
        Self::read(BufReader::new(file), &crate::error::shown(path))
    }

    /// Turns a [`MeshError`] about this file's soup into an [`IoError::Mesh`] that names its line.
    pub fn locate(&self, error: MeshError) -> IoError {
        IoError::Mesh { file: self.name.clone(), line: self.lines.of_error(&error), source: error }
    }

    /// Builds the half-edge mesh of the soup; an error names the line of the face, vertex or tag
    /// it is about.
    ///
    /// # Errors
    /// [`IoError::Mesh`] with the first rule the soup breaks.
    pub fn build(self, options: &BuildOptions) -> Result<Mesh, IoError> {
        let Self { name, soup, lines } = self;
        Mesh::build_with(soup, options).map_err(|source| IoError::Mesh {
            line: lines.of_error(&source),
            file: name,
            source,
        })
    }
}

/// Reads OBJ text into a polygon soup; `name` is the file name errors carry. See [`ObjFile::read`]
/// to keep the line numbers.
///
/// # Errors
/// As [`ObjFile::read`].
pub fn read_obj(reader: impl BufRead, name: &str) -> Result<PolygonSoup, IoError> {
    ObjFile::read(reader, name).map(|obj| obj.soup)
}

/// Reads the OBJ file at `path` into a polygon soup.
///
/// # Errors
/// As [`ObjFile::load`].
pub fn load_obj(path: impl AsRef<Path>) -> Result<PolygonSoup, IoError> {
    ObjFile::load(path).map(|obj| obj.soup)
}

/// Reads the next record into `record` (continuation lines joined, line ending removed) and
/// returns its first line number, or `None` at the end of the input.
fn next_record(reader: &mut impl BufRead, record: &mut Vec<u8>, line: &mut usize) -> io::Result<Option<usize>> {
    record.clear();
    let first_line = *line + 1;
    loop {
        if reader.read_until(b'\n', record)? == 0 {
            return Ok((!record.is_empty()).then_some(first_line));
        }
        *line += 1;
        while let Some(b'\n' | b'\r') = record.last() {
            record.pop();
        }
        match record.last_mut() {
            Some(last @ b'\\') => *last = b' ',
            _ => return Ok(Some(first_line)),
        }
    }
}

/// Reader state: the file read so far, and the references checked once the whole file is known
/// (a face or tag may name a vertex defined further down).
struct Parser {
    obj: ObjFile,
    /// Vertex or face references of `t` lines, checked in [`Parser::finish`].
    tag_refs: Vec<TagRef>,
    /// The vertices of the face being read, each with its `vt` index as written.
    face: Vec<(VertexId, Option<i64>)>,
    uv: TexCoords,
}

/// The texture coordinates read so far and the faces' references to them.
#[derive(Default)]
struct TexCoords {
    /// `u v` of each `vt` line.
    values: Vec<f64>,
    /// One 1-based (or relative, resolved) index per face corner, for the faces read so far
    /// with texture coordinates; 0 where a face has none (checked in [`Parser::finish`]).
    indices: Vec<u64>,
    /// The line of the first face with texture coordinates and of the first without.
    first_with: Option<usize>,
    first_without: Option<usize>,
}

struct TagRef {
    line: usize,
    tag: &'static str,
    face: bool,
    index: i64,
}

impl Parser {
    fn syntax(&self, line: usize, rule: String) -> IoError {
        IoError::ObjSyntax { file: self.obj.name.clone(), line, rule }
    }

    fn record(&mut self, record: &[u8], line: usize) -> Result<(), IoError> {
        let record = record.trim_ascii_start();
        let end = record.iter().position(u8::is_ascii_whitespace).unwrap_or(record.len());
        let (keyword, args) = record.split_at(end);
        let text =
            |bytes| std::str::from_utf8(bytes).map_err(|_| IoError::NotUtf8 { file: self.obj.name.clone(), line });
        match keyword {
            b"v" => self.vertex(text(args)?, line),
            b"vt" => self.texcoord(text(args)?, line),
            b"f" => self.face(text(args)?, line),
            b"t" => self.tag(text(args)?, line),
            // Comments, and every other record (vn, g, o, s, usemtl, mtllib, l, curves, …):
            // skipped unread, so that e.g. a Latin-1 comment or group name is no error.
            [] | [b'#', ..] => Ok(()),
            [first, rest @ ..]
                if (first.is_ascii_alphabetic() || *first == b'_')
                    && rest.iter().all(|b| b.is_ascii_alphanumeric() || *b == b'_') =>
            {
                Ok(())
            }
            _ => {
                let start: String = text(keyword)?.chars().take(20).collect();
                Err(self
                    .syntax(line, format!("{start:?} is not an OBJ record; records start with a keyword (v, f, t, …)")))
            }
        }
    }

    /// The numbers of a `v` or `vt` record (`what` names them in errors): the first `N`, kept,
    /// must be finite (else `non_finite` of the value); any after them (a `w`, vertex colours)
    /// just need to be numbers. Returns the kept ones and how many numbers there were.
    fn numbers<const N: usize>(
        &self,
        args: &str,
        line: usize,
        what: &str,
        non_finite: impl Fn(f64) -> IoError,
    ) -> Result<([f64; N], usize), IoError> {
        let mut kept = [0.0; N];
        let mut count = 0;
        for token in args.split_ascii_whitespace() {
            let value: f64 = token
                .parse()
                .map_err(|_| self.syntax(line, format!("{what} {} {:?} is not a number", count + 1, clip(token))))?;
            if let Some(slot) = kept.get_mut(count) {
                if !value.is_finite() {
                    return Err(non_finite(value));
                }
                *slot = value;
            }
            count += 1;
        }
        Ok((kept, count))
    }

    fn vertex(&mut self, args: &str, line: usize) -> Result<(), IoError> {
        let file = &self.obj.name;
        let non_finite = |value| IoError::NonFiniteCoordinate { file: file.clone(), line, value };
        let (xyz, count) = self.numbers::<3>(args, line, "vertex coordinate", non_finite)?;
        if count < 3 {
            return Err(self.syntax(line, format!("a vertex needs 3 coordinates (v x y z); this one has {count}")));
        }
        self.obj.soup.push_vertex(DVec3::from_array(xyz));
        self.obj.lines.vertices.push(line);
        Ok(())
    }

    fn texcoord(&mut self, args: &str, line: usize) -> Result<(), IoError> {
        let non_finite = |value| self.syntax(line, format!("texture coordinate {value} is not finite"));
        // u and v are kept (v is 0 when absent); a w just needs to be a number.
        let (uv, count) = self.numbers::<2>(args, line, "texture coordinate", non_finite)?;
        if count == 0 {
            return Err(self.syntax(line, "a texture coordinate needs at least u (vt u [v [w]])".into()));
        }
        self.uv.values.extend(uv);
        Ok(())
    }

    fn face(&mut self, args: &str, line: usize) -> Result<(), IoError> {
        self.face.clear();
        for token in args.split_ascii_whitespace() {
            let corner = self.face_vertex(token, line)?;
            self.face.push(corner);
        }
        if self.face.len() < 3 {
            return Err(IoError::FaceTooSmall { file: self.obj.name.clone(), line, count: self.face.len() });
        }
        let with = self.face.iter().filter(|(_, t)| t.is_some()).count();
        let uv = &mut self.uv;
        if with == 0 {
            uv.first_without.get_or_insert(line);
            uv.indices.extend(std::iter::repeat_n(0, self.face.len()));
        } else if with < self.face.len() {
            let rule = format!(
                "the face has texture coordinates at {with} of its {} corners; give every corner one (v/vt) or none",
                self.face.len()
            );
            return Err(IoError::TexCoordsIncomplete { file: self.obj.name.clone(), line, rule });
        } else {
            uv.first_with.get_or_insert(line);
            let defined = uv.values.len() / 2;
            for &(_, t) in &self.face {
                let t = t.unwrap_or_default();
                // Relative indices count back from the texture coordinates defined so far.
                let one_based = if t > 0 {
                    t.unsigned_abs()
                } else {
                    (defined as u64 + 1).checked_sub(t.unsigned_abs()).filter(|&i| i > 0).ok_or_else(|| {
                        IoError::TexCoordOutOfRange { file: self.obj.name.clone(), line, index: t, count: defined }
                    })?
                };
                uv.indices.push(one_based);
            }
        }
        self.obj.soup.push_face(self.face.drain(..).map(|(v, _)| v));
        self.obj.lines.faces.push(line);
        Ok(())
    }

    /// One face vertex `v`, `v/vt`, `v//vn` or `v/vt/vn`, as the vertex and the `vt` index as
    /// written (the normal is not kept). Positive vertex indices are range-checked in
    /// [`finish`](Self::finish), negative ones here (they count back from the vertices defined
    /// so far).
    fn face_vertex(&self, token: &str, line: usize) -> Result<(VertexId, Option<i64>), IoError> {
        let file = || self.obj.name.clone();
        let mut parts = token.split('/');
        let vertex = parts.next().unwrap_or_default();
        let is_index = |s: &str| s.strip_prefix('-').unwrap_or(s).bytes().all(|b| b.is_ascii_digit());
        let texcoord = parts.clone().next().filter(|t| !t.is_empty());
        if vertex.is_empty() || parts.clone().count() > 2 || !parts.all(is_index) {
            return Err(self.syntax(line, format!("face vertex {:?} is not v, v/vt, v//vn or v/vt/vn", clip(token))));
        }
        let texcoord = match texcoord {
            None => None,
            Some(t) => Some(t.parse::<i64>().map_err(|e| match e.kind() {
                IntErrorKind::PosOverflow | IntErrorKind::NegOverflow => {
                    IoError::TexCoordOutOfRange { file: file(), line, index: i64::MAX, count: self.uv.values.len() / 2 }
                }
                _ => self.syntax(line, format!("texture-coordinate index {:?} is not an integer", clip(t))),
            })?),
        };
        if texcoord == Some(0) {
            return Err(IoError::IndexZero { file: file(), line });
        }
        let overflow = || IoError::IndexOverflow { file: file(), line, token: vertex.to_owned() };
        let index: i64 = vertex.parse().map_err(|e: std::num::ParseIntError| match e.kind() {
            IntErrorKind::PosOverflow | IntErrorKind::NegOverflow => overflow(),
            _ => self.syntax(line, format!("face vertex index {vertex:?} is not an integer")),
        })?;
        let defined = self.obj.soup.vertex_count();
        let zero_based = match index {
            0 => return Err(IoError::IndexZero { file: file(), line }),
            1.. => index.unsigned_abs() - 1,
            _ => (defined as u64).checked_sub(index.unsigned_abs()).ok_or_else(|| IoError::IndexOutOfRange {
                file: file(),
                line,
                index,
                vertex_count: defined,
            })?,
        };
        let vertex = u32::try_from(zero_based).map(VertexId::new).map_err(|_| overflow())?;
        Ok((vertex, texcoord))
    }

    fn tag(&mut self, args: &str, line: usize) -> Result<(), IoError> {
        // Closures below borrow only the file name, so the tags can be filled meanwhile.
        let file = self.obj.name.as_str();
        let syntax = |rule: String| IoError::ObjSyntax { file: file.to_owned(), line, rule };
        let mut tokens = args.split_ascii_whitespace();
        let (Some(name), Some(counts)) = (tokens.next(), tokens.next()) else {
            return Err(syntax("a tag needs a name and counts: t NAME nints/nfloats/nstrings …".into()));
        };
        let [ni, nf, ns] = counts.split('/').map(str::parse).collect::<Result<Vec<usize>, _>>().unwrap_or_default()[..]
        else {
            return Err(syntax(format!("t {name}: {counts:?} is not nints/nfloats/nstrings")));
        };
        let args: Vec<&str> = tokens.collect();
        if ni.checked_add(nf).and_then(|n| n.checked_add(ns)) != Some(args.len()) {
            let rule = format!("t {name} declares {ni}/{nf}/{ns} arguments but has {}", args.len());
            return Err(syntax(rule));
        }
        let ints = args[..ni]
            .iter()
            .map(|s| s.parse::<i64>().map_err(|_| syntax(format!("t {name}: {:?} is not an integer", clip(s)))))
            .collect::<Result<Vec<_>, _>>()?;
        let floats = args[ni..ni + nf]
            .iter()
            .map(|s| s.parse::<f64>().map_err(|_| syntax(format!("t {name}: {:?} is not a number", clip(s)))))
            .collect::<Result<Vec<_>, _>>()?;
        let strings = &args[ni + nf..];
        let shape = |ok: bool, expected: &str| {
            if ok { Ok(()) } else { Err(syntax(format!("t {name} takes {expected}; this one has {ni}/{nf}/{ns}"))) }
        };
        // Tag indices are range-checked once the file is read; until then an index that fits no
        // id is stored as u32::MAX, which is out of range of every soup.
        let id = |index: i64| u32::try_from(index).unwrap_or(u32::MAX);
        let tag_refs = &mut self.tag_refs;
        let mut refer = |tag, face, index| tag_refs.push(TagRef { line, tag, face, index });
        let tags = &mut self.obj.soup.tags;
        let lines = &mut self.obj.lines;
        match name {
            "crease" => {
                shape(ni >= 2 && (nf == 1 || nf == ni - 1) && ns == 0, "n/1/0 or n/(n-1)/0 with n >= 2")?;
                for (edge, pair) in ints.windows(2).enumerate() {
                    refer("crease", false, pair[0]);
                    refer("crease", false, pair[1]);
                    let sharpness = floats[if nf == 1 { 0 } else { edge }];
                    tags.creases
                        .push(CreaseTag { vertices: [pair[0], pair[1]].map(|v| VertexId::new(id(v))), sharpness });
                    lines.creases.push(line);
                }
            }
            "corner" => {
                shape(ni >= 1 && (nf == 1 || nf == ni) && ns == 0, "n/1/0 or n/n/0 with n >= 1")?;
                for (i, &vertex) in ints.iter().enumerate() {
                    refer("corner", false, vertex);
                    let sharpness = floats[if nf == 1 { 0 } else { i }];
                    tags.corners.push(CornerTag { vertex: VertexId::new(id(vertex)), sharpness });
                    lines.corners.push(line);
                }
            }
            "hole" => {
                shape(nf == 0 && ns == 0, "n/0/0")?;
                for &face in &ints {
                    refer("hole", true, face);
                    tags.holes.push(FaceId::new(id(face)));
                    lines.holes.push(line);
                }
            }
            "interpolateboundary" => {
                shape((ni, nf, ns) == (1, 0, 0), "1/0/0")?;
                tags.boundary_interpolation = Some(BoundaryInterpolation::from_code(ints[0]).ok_or_else(|| {
                    syntax(format!("t {name} {}: expected 0 (none), 1 (edge and corner) or 2 (edge only)", ints[0]))
                })?);
            }
            "facevaryinginterpolateboundary" => {
                shape((ni, nf, ns) == (1, 0, 0), "1/0/0")?;
                tags.face_varying_interpolation = Some(
                    FaceVaryingInterpolation::from_code(ints[0])
                        .ok_or_else(|| syntax(format!("t {name} {}: expected 0..=5", ints[0])))?,
                );
            }
            "creasemethod" => {
                shape((ni, nf, ns) == (0, 0, 1), "0/0/1")?;
                tags.crease_method = Some(match strings[0] {
                    "normal" => CreaseMethod::Uniform,
                    "chaikin" => CreaseMethod::Chaikin,
                    other => return Err(syntax(format!("t {name} {other:?}: expected normal or chaikin"))),
                });
            }
            "smoothtriangles" => {
                shape((ni, nf, ns) == (0, 0, 1), "0/0/1")?;
                tags.triangle_subdivision = Some(match strings[0] {
                    "catmark" => TriangleSubdivision::Catmark,
                    "smooth" => TriangleSubdivision::Smooth,
                    other => return Err(syntax(format!("t {name} {other:?}: expected catmark or smooth"))),
                });
            }
            _ => tags.unsupported.push(name.to_owned()),
        }
        Ok(())
    }

    /// Checks what needed the whole file: some geometry, and every face and tag reference.
    fn finish(self) -> Result<ObjFile, IoError> {
        let mut obj = self.obj;
        let uv = self.uv;
        if let Some(first_with) = uv.first_with {
            if let Some(line) = uv.first_without {
                let rule = format!(
                    "the face has no texture coordinates, but the face on line {first_with} has; give every face's \
                     corners one (v/vt) or none"
                );
                return Err(IoError::TexCoordsIncomplete { file: obj.name.clone(), line, rule });
            }
            let count = uv.values.len() / 2;
            let (offsets, _) = obj.soup.raw_faces();
            if let Some(h) = uv.indices.iter().position(|&i| i as usize > count) {
                let face = offsets.partition_point(|&o| o as usize <= h) - 1;
                let index = i64::try_from(uv.indices[h]).unwrap_or(i64::MAX);
                return Err(IoError::TexCoordOutOfRange {
                    file: obj.name.clone(),
                    line: obj.lines.faces[face],
                    index,
                    count,
                });
            }
            let indices = uv.indices.iter().map(|&i| (i - 1) as u32).collect();
            obj.soup.channels.push(Channel::new(Channel::UV, 2, uv.values, indices));
        }
        let obj = obj;
        let file = || obj.name.clone();
        let (vertex_count, face_count) = (obj.soup.vertex_count(), obj.soup.face_count());
        if vertex_count == 0 && face_count == 0 {
            return Err(IoError::NoGeometry { file: file() });
        }
        for (face, &line) in obj.soup.faces().zip(&obj.lines.faces) {
            if let Some(vertex) = face.iter().find(|v| v.index() >= vertex_count) {
                let index = i64::from(vertex.raw()) + 1;
                return Err(IoError::IndexOutOfRange { file: file(), line, index, vertex_count });
            }
        }
        for r in &self.tag_refs {
            let (what, count) = if r.face { ("face", face_count) } else { ("vertex", vertex_count) };
            if !usize::try_from(r.index).is_ok_and(|i| i < count) {
                return Err(IoError::TagOutOfRange {
                    file: file(),
                    line: r.line,
                    tag: r.tag,
                    what,
                    index: r.index,
                    count,
                });
            }
        }
        Ok(obj)
    }
}

/// Writes `soup` as an OBJ file at `path`: `v` lines with every coordinate's shortest exact
/// decimal form (so reading it back gives the same `f64`s), the [`Channel::UV`] channel as `vt`
/// lines, 1-based `f` lines (`f v/vt` with the channel), and the tags as `t` lines ([`read_obj`]
/// of the file gives `soup` back). OBJ has room for one face-varying channel: other channels are
/// not written. Unsupported tags are written by name only (`t vertexedit 0/0/0`), as that is all
/// the reader keeps of them.
///
/// The file is written to a fresh `<name>.<16 hex>.tmp` and renamed, so a failure leaves `path` untouched.
///
/// # Errors
/// [`IoError::Unwritable`] when the soup cannot be read back (a face with fewer than 3
/// vertices, an index out of range, a non-finite coordinate, a tag out of range, a
/// [`Channel::UV`] channel that is not 2-dimensional or not one valid index per corner);
/// [`IoError::Io`] when writing fails.
pub fn write_obj(path: impl AsRef<Path>, soup: &PolygonSoup) -> Result<(), IoError> {
    check_writable(soup)?;
    atomic::write_file(path.as_ref(), |w| write_records(w, soup))
}

/// Writes `soup` as OBJ text to `writer` (see [`write_obj`] for the format). Wrap a file or
/// socket in a [`BufWriter`](std::io::BufWriter); this writes record by record.
///
/// # Errors
/// What `writer` reports; a soup that [`write_obj`] refuses gives an error of kind
/// [`InvalidInput`](io::ErrorKind::InvalidInput) wrapping the [`IoError::Unwritable`].
pub fn write_obj_to(mut writer: impl Write, soup: &PolygonSoup) -> io::Result<()> {
    check_writable(soup).map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
    write_records(&mut writer, soup)?;
    writer.flush()
}

fn check_writable(soup: &PolygonSoup) -> Result<(), IoError> {
    let n = soup.vertex_count();
    let in_range = |v: VertexId| v.index() < n;
    let rule = if let Some((v, p)) = soup.positions().iter().enumerate().find(|(_, p)| !p.is_finite()) {
        format!("vertex {v} = {p} is not finite")
    } else if let Some((f, face)) = soup.faces().enumerate().find(|(_, face)| face.len() < 3) {
        format!("face {f} has {} vertices; OBJ faces need at least 3", face.len())
    } else if let Some((f, v)) =
        soup.faces().enumerate().find_map(|(f, face)| face.iter().find(|&&v| !in_range(v)).map(|v| (f, v)))
    {
        format!("face {f} refers to {v}, but the soup has {n} vertices")
    } else if let Some(uv) = uv_channel(soup).filter(|uv| {
        uv.dimension() != 2
            || uv.values().iter().any(|x| !x.is_finite())
            || uv.indices().len() != soup.corner_count()
            || uv.indices().iter().any(|&i| i as usize >= uv.value_count())
    }) {
        format!(
            "channel {:?} ({} components, {} values, {} indices for {} corners) is not 2-dimensional texture \
             coordinates with one valid index per face corner",
            uv.name(),
            uv.dimension(),
            uv.value_count(),
            uv.indices().len(),
            soup.corner_count()
        )
    } else {
        let Tags { creases, corners, holes, unsupported, .. } = &soup.tags;
        if let Some(c) = creases.iter().find(|c| !c.vertices.into_iter().all(in_range)) {
            format!("crease {:?} refers to a vertex out of range 0..{n}", c.vertices)
        } else if let Some(c) = corners.iter().find(|c| !in_range(c.vertex)) {
            format!("corner tag refers to {}, out of range 0..{n}", c.vertex)
        } else if let Some(h) = holes.iter().find(|h| h.index() >= soup.face_count()) {
            format!("hole tag refers to {h}, out of range 0..{}", soup.face_count())
        } else if let Some(name) = unsupported
            .iter()
            .find(|s| s.is_empty() || s.contains(char::is_whitespace) || KNOWN_TAGS.contains(&s.as_str()))
        {
            format!("unsupported tag name {name:?} cannot be written as one tag-name token")
        } else {
            return Ok(());
        }
    };
    Err(IoError::Unwritable { format: "OBJ", rule })
}

/// The channel the OBJ formats write as `vt`.
fn uv_channel(soup: &PolygonSoup) -> Option<&Channel> {
    soup.channels.iter().find(|c| c.name() == Channel::UV)
}

fn write_records(w: &mut impl Write, soup: &PolygonSoup) -> io::Result<()> {
    writeln!(w, "# subdiv-io; t (tag) lines use 0-based vertex and face indices")?;
    for p in soup.positions() {
        writeln!(w, "v {} {} {}", Num(p.x), Num(p.y), Num(p.z))?;
    }
    let uv = uv_channel(soup);
    if let Some(uv) = uv {
        for t in uv.values().chunks_exact(2) {
            writeln!(w, "vt {} {}", Num(t[0]), Num(t[1]))?;
        }
    }
    let mut corners = uv.map(|uv| uv.indices().iter());
    for face in soup.faces() {
        w.write_all(b"f")?;
        for v in face {
            write!(w, " {}", u64::from(v.raw()) + 1)?;
            if let Some(t) = corners.as_mut().and_then(Iterator::next) {
                write!(w, "/{}", u64::from(*t) + 1)?;
            }
        }
        writeln!(w)?;
    }
    let tags = &soup.tags;
    for c in &tags.creases {
        writeln!(w, "t crease 2/1/0 {} {} {}", c.vertices[0].raw(), c.vertices[1].raw(), Num(c.sharpness))?;
    }
    for c in &tags.corners {
        writeln!(w, "t corner 1/1/0 {} {}", c.vertex.raw(), Num(c.sharpness))?;
    }
    if !tags.holes.is_empty() {
        write!(w, "t hole {}/0/0", tags.holes.len())?;
        for h in &tags.holes {
            write!(w, " {}", h.raw())?;
        }
        writeln!(w)?;
    }
    if let Some(b) = tags.boundary_interpolation {
        writeln!(w, "t interpolateboundary 1/0/0 {}", b.code())?;
    }
    if let Some(k) = tags.face_varying_interpolation {
        writeln!(w, "t facevaryinginterpolateboundary 1/0/0 {}", k.code())?;
    }
    if let Some(m) = tags.crease_method {
        let name = match m {
            CreaseMethod::Uniform => "normal",
            CreaseMethod::Chaikin => "chaikin",
        };
        writeln!(w, "t creasemethod 0/0/1 {name}")?;
    }
    if let Some(t) = tags.triangle_subdivision {
        let name = match t {
            TriangleSubdivision::Catmark => "catmark",
            TriangleSubdivision::Smooth => "smooth",
        };
        writeln!(w, "t smoothtriangles 0/0/1 {name}")?;
    }
    for name in &tags.unsupported {
        writeln!(w, "t {name} 0/0/0")?;
    }
    Ok(())
}

/// A token as an error message quotes it: its first 40 characters (a hostile file's token may
/// be megabytes long).
fn clip(token: &str) -> String {
    match token.char_indices().nth(40) {
        Some((end, _)) => format!("{}…", &token[..end]),
        None => token.to_owned(),
    }
}

/// An `f64` in its shortest decimal form that parses back to the same value; exponent notation
/// for very small and very large magnitudes, where plain notation would print hundreds of digits.
struct Num(f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let magnitude = self.0.abs();
        if magnitude != 0.0 && !(1e-5..1e16).contains(&magnitude) {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_short_and_exact() {
        for (x, text) in [(1.0, "1"), (-0.5, "-0.5"), (0.1, "0.1"), (1e-300, "1e-300"), (2.5e20, "2.5e20"), (0.0, "0")]
        {
            assert_eq!(Num(x).to_string(), text);
        }
        for x in [std::f64::consts::PI, 1.0 / 3.0, f64::MIN_POSITIVE, f64::MAX, -123456.789e-7] {
            assert_eq!(Num(x).to_string().parse::<f64>(), Ok(x));
        }
    }

    #[test]
    fn records_join_continuation_lines_and_keep_their_first_line() {
        let mut input = "v 1 \\\n 2 3\r\n\nf 1 2 3".as_bytes();
        let (mut record, mut line) = (Vec::new(), 0);
        let mut records = Vec::new();
        while let Some(first) = next_record(&mut input, &mut record, &mut line).unwrap() {
            records.push((first, String::from_utf8(record.clone()).unwrap()));
        }
        assert_eq!(records, [(1, "v 1   2 3".into()), (3, String::new()), (4, "f 1 2 3".into())]);
    }

    #[test]
    fn texture_coordinates_make_the_uv_channel_in_every_face_form() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1 0.5\nvt 0 1\n\
                    vn 0 0 1\nf 1/1 2/2/1 -2/-2/1\nf 1/1 3/3 4/-1\n";
        let soup = read_obj(text.as_bytes(), "uv.obj").unwrap();
        let uv = &soup.channels[0];
        assert_eq!((uv.name(), uv.dimension(), uv.value_count()), (Channel::UV, 2, 4));
        assert_eq!(uv.indices(), [0, 1, 2, 0, 2, 3]);
        assert_eq!(uv.value(2), [1.0, 1.0]);
        // Written and read back: the same soup.
        let mut bytes = Vec::new();
        write_obj_to(&mut bytes, &soup).unwrap();
        assert_eq!(read_obj(&bytes[..], "back.obj").unwrap(), soup);
        assert!(String::from_utf8(bytes).unwrap().contains("f 1/1 2/2 3/3\n"));
    }

    #[test]
    fn incomplete_or_dangling_texture_coordinates_are_errors_on_their_face_line() {
        let head = "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\n";
        for (faces, rule, line) in [
            ("f 1/1 2 3\n", "texcoords-incomplete", 5),
            ("f 1/1 2/1 3/1\nf 1 2 3\n", "texcoords-incomplete", 6),
            ("f 1 2 3\nf 1/1 2/1 3/1\n", "texcoords-incomplete", 5),
            ("f 1/1 2/1 3/2\n", "texcoord-out-of-range", 5),
            ("f 1/1 2/1 3/-2\n", "texcoord-out-of-range", 5),
            ("f 1/0 2/1 3/1\n", "index-zero", 5),
        ] {
            let error = read_obj(format!("{head}{faces}").as_bytes(), "t.obj").unwrap_err();
            assert_eq!((error.rule(), error.line()), (rule, Some(line)), "{faces}: {error}");
        }
    }

    #[test]
    fn a_utf8_byte_order_mark_at_the_start_is_skipped() {
        let text = "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let soup = read_obj(text.as_bytes(), "bom.obj").expect("a BOM is accepted");
        assert_eq!((soup.vertex_count(), soup.face_count()), (3, 1));
    }

    #[test]
    fn mesh_errors_map_to_the_line_of_their_face_vertex_or_tag() {
        let lines =
            ObjLines { vertices: vec![1, 2], faces: vec![5], creases: vec![7, 7], corners: vec![8], holes: vec![9] };
        let face = MeshError::TooFewVertices { face: FaceId::new(0), count: 2 };
        let vertex = MeshError::NonManifoldVertex { vertex: VertexId::new(1), fans: 2 };
        let crease = MeshError::CreaseNotAnEdge { index: 1, a: VertexId::new(0), b: VertexId::new(1) };
        let corner = MeshError::InvalidSharpness { tag: "corner", index: 0, sharpness: -1.0 };
        let hole = MeshError::HoleOutOfRange { index: 0, face: 3, face_count: 1 };
        let lines_of: Vec<_> = [face, vertex, crease, corner, hole].iter().map(|e| lines.of_error(e)).collect();
        assert_eq!(lines_of, [Some(5), Some(2), Some(7), Some(8), Some(9)]);
    }
}
