//! Reading the mesh a command works on: a file, or the built-in model.

use std::path::Path;

use subdiv::io::{IoError, ObjFile, ObjLines};
use subdiv::mesh::{BuildOptions, Mesh, MeshError, PolygonSoup, shapes};

use crate::UserError;

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
    pub(crate) fn read(path: &Path) -> Result<Self, IoError> {
        let name = path.display().to_string();
        let is_obj = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("obj"));
        if is_obj {
            let ObjFile { soup, lines, .. } = ObjFile::load(path)?;
            Ok(Self { name, soup, lines: Some(lines) })
        } else {
            Ok(Self { name, soup: subdiv::io::load(path)?, lines: None })
        }
    }

    /// The file at `path`, or the built-in model when there is none, built into a mesh (the
    /// first broken rule as the error, with its file and line).
    pub(crate) fn read_and_build(path: Option<&Path>) -> Result<(Self, Mesh), UserError> {
        let loaded = match path {
            Some(path) => Self::read(path)?,
            None => Self::built_in(shapes::default_model()),
        };
        let mesh = Mesh::build_with(loaded.soup.clone(), &BuildOptions::default())
            .map_err(|error| UserError(loaded.locate(&error)))?;
        Ok((loaded, mesh))
    }

    /// The built-in model.
    pub(crate) fn built_in(soup: PolygonSoup) -> Self {
        Self { name: "built-in model".to_string(), soup, lines: None }
    }

    /// `error` as one line: `FILE:LINE: rule`.
    pub(crate) fn locate(&self, error: &MeshError) -> String {
        let line = self.lines.as_ref().and_then(|lines| lines.of_error(error));
        IoError::Mesh { file: self.name.clone(), line, source: error.clone() }.to_string()
    }
}
