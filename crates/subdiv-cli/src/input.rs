//! Reading the mesh a command works on: a file, or the built-in model.

use std::fmt::Display;
use std::path::Path;

use subdiv::io::{GltfOptions, IoError, ObjFile, ObjLines};
use subdiv::mesh::{BuildOptions, Mesh, MeshError, PolygonSoup, shapes};

use crate::UserError;

/// How input files are read, for every command that reads a mesh.
#[derive(Clone, Copy, Debug, Default, clap::Args)]
pub(crate) struct InputArgs {
    /// glTF: let buffer URIs name files outside the glTF file's folder (`../`, absolute paths,
    /// symlinks that lead out); refused by default.
    #[arg(long)]
    pub(crate) allow_outside_uris: bool,
    /// glTF: weld vertices with equal positions into one cage vertex (exporters split vertices
    /// along normal and texture seams; unwelded, such a cage comes apart there). Each corner
    /// keeps its texture coordinates.
    #[arg(long)]
    pub(crate) weld: bool,
    /// Take a non-manifold mesh apart into sheets, as OpenSubdiv refines it: an edge of more
    /// than two faces becomes an infinitely sharp crease where the sheets end, a vertex whose
    /// faces form several fans one vertex per fan (sharpened into a corner unless a crease of
    /// two such edges runs through it). Refused by default.
    #[arg(long)]
    pub(crate) split_sheets: bool,
}

impl InputArgs {
    fn gltf(self) -> GltfOptions {
        GltfOptions::DEFAULT.with_allow_outside_uris(self.allow_outside_uris).with_weld(self.weld)
    }
}

/// Refuses an output that is one of the inputs (the same canonical path, or the same file by
/// device and inode through another name), which the write would destroy.
pub(crate) fn check_output(inputs: &[&Path], output: &Path) -> Result<(), UserError> {
    let Ok(out) = std::fs::metadata(output) else { return Ok(()) };
    for input in inputs {
        let same_path = matches!((input.canonicalize(), output.canonicalize()), (Ok(a), Ok(b)) if a == b);
        let same_file = std::fs::metadata(input).is_ok_and(|meta| same_inode(&meta, &out));
        if same_path || same_file {
            return Err(UserError(format!(
                "{}: the output {} is this input file; write the output to another file",
                input.display(),
                output.display()
            )));
        }
    }
    Ok(())
}

#[cfg(unix)]
fn same_inode(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt as _;
    (a.dev(), a.ino()) == (b.dev(), b.ino())
}

#[cfg(not(unix))]
fn same_inode(_: &std::fs::Metadata, _: &std::fs::Metadata) -> bool {
    false
}

/// A failed write as one line naming the input and the output: `IN: writing OUT: why`.
pub(crate) fn write_error(input: &str, output: &Path, error: impl Display) -> UserError {
    let text = error.to_string();
    // An I/O error already starts with the output's name.
    let prefix = format!("{}: ", output.display());
    let why = text.strip_prefix(&prefix).unwrap_or(&text);
    UserError(format!("{input}: writing {}: {why}", output.display()))
}

/// A soup and what is needed to point at its lines in error messages.
pub(crate) struct LoadedMesh {
    /// The file name as given, or "built-in model".
    pub(crate) name: String,
    pub(crate) soup: PolygonSoup,
    /// Line numbers of the OBJ records (`None` for glTF and the built-in model).
    lines: Option<ObjLines>,
}

impl LoadedMesh {
    /// Reads `path` (OBJ, glTF or GLB).
    pub(crate) fn read(path: &Path, input: &InputArgs) -> Result<Self, IoError> {
        let name = path.display().to_string();
        let is_obj = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("obj"));
        if is_obj {
            let ObjFile { soup, lines, .. } = ObjFile::load(path)?;
            Ok(Self { name, soup, lines: Some(lines) })
        } else if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
        {
            Ok(Self { name, soup: subdiv::io::load_gltf_with(path, &input.gltf())?, lines: None })
        } else {
            Ok(Self { name, soup: subdiv::io::load(path)?, lines: None })
        }
    }

    /// The file at `path`, or the built-in model when there is none, built into a mesh (the
    /// first broken rule as the error, with its file and line), and its name for messages.
    pub(crate) fn read_and_build(path: Option<&Path>, input: &InputArgs) -> Result<(String, Mesh), UserError> {
        let loaded = match path {
            Some(path) => Self::read(path, input)?,
            None => Self::built_in(shapes::default_model()),
        };
        // The soup goes into the mesh, not a copy of it, and its line table only lives while an
        // error may need it: a large input is then held once, as its mesh.
        let Self { name, soup, lines } = loaded;
        let mesh = Mesh::build_with(soup, &BuildOptions::default().with_split_sheets(input.split_sheets))
            .map_err(|error| UserError(locate(&name, lines.as_ref(), &error)))?;
        Ok((name, mesh))
    }

    /// The built-in model.
    pub(crate) fn built_in(soup: PolygonSoup) -> Self {
        Self { name: "built-in model".to_string(), soup, lines: None }
    }

    /// `error` as one line: `FILE:LINE: rule`.
    pub(crate) fn locate(&self, error: &MeshError) -> String {
        locate(&self.name, self.lines.as_ref(), error)
    }
}

/// `error` in the file `name` with the record lines `lines`, as one line: `FILE:LINE: rule`.
fn locate(name: &str, lines: Option<&ObjLines>, error: &MeshError) -> String {
    let line = lines.and_then(|lines| lines.of_error(error));
    IoError::Mesh { file: name.to_string(), line, source: error.clone() }.to_string()
}
