//! Mesh files for `subdiv`: control cages in, tessellations out.
//!
//! - **OBJ** ([`read_obj`], [`load_obj`], [`ObjFile`]) reads polygons of any size with every
//!   face index form, and OpenSubdiv's tag lines (`t crease`, `t corner`, `t hole`,
//!   `t interpolateboundary`, …) into [`Tags`](subdiv_mesh::Tags). [`write_obj`] writes a soup
//!   back, tags included, with exact coordinates: reading the file gives the same soup.
//! - **glTF 2.0 / GLB** ([`load_gltf`], [`parse_gltf`]; [`load_gltf_with`], [`parse_gltf_with`]
//!   with [`GltfOptions`]) reads every TRIANGLES primitive into one soup. A hostile file cannot
//!   make it read outside the glTF's folder (unless [`GltfOptions::allow_outside_uris`]), read a
//!   device or FIFO, read past a buffer's `byteLength`, mistake an index of 2^32 for 0, or
//!   allocate more than [`GltfOptions::max_vertices`] / [`GltfOptions::max_indices`] allow (all
//!   checked before anything is read). [`write_glb`] writes a triangle mesh (positions, normals,
//!   indices) as GLB, refusing meshes that f32 cannot hold ([`MIN_GLB_EXTENT`]).
//! - [`load`] and [`load_mesh`] pick the format from the file extension; [`load_mesh`] also builds
//!   the half-edge [`Mesh`] and reports a [`MeshError`](subdiv_mesh::MeshError) at the OBJ line
//!   of the face, vertex or tag it is about.
//!
//! No input panics. Every error is an [`IoError`] naming the place (`file:line`, or a glTF JSON
//! path such as `meshes[0].primitives[1].attributes.POSITION`) and the rule broken. Writers
//! write a fresh `<name>.<16 hex>.tmp` beside the output (created with `O_EXCL`, so a file or
//! symlink planted there is never followed) and rename it over the output, so a failure never
//! leaves a half-written file; [`remove_temporary_files`] deletes those being written, for a
//! program's SIGINT/SIGTERM handler.
//!
//! ```
//! use subdiv_io::read_obj;
//! use subdiv_mesh::{FaceId, Mesh, VertexId};
//!
//! let text = "\
//! v 0 0 0
//! v 1 0 0
//! v 1 1 0
//! v 0 1 0
//! f 1 2 3 4
//! t crease 3/1/0 0 1 2 10
//! ";
//! let soup = read_obj(text.as_bytes(), "quad.obj")?;
//! assert_eq!(soup.face(FaceId::new(0)), [0, 1, 2, 3].map(VertexId::new));
//! // The crease chain 0-1-2 becomes two sharp edges.
//! let creases = &soup.tags.creases;
//! assert_eq!(creases.len(), 2);
//! assert_eq!(creases[1].vertices, [VertexId::new(1), VertexId::new(2)]);
//! assert_eq!(creases[1].sharpness, 10.0);
//! let mesh = Mesh::build(soup).expect("a quad is a valid mesh");
//! assert_eq!(mesh.boundary_edge_count(), 4);
//! # Ok::<(), subdiv_io::IoError>(())
//! ```

mod atomic;
mod error;
mod glb;
mod gltf;
mod obj;

use std::path::Path;

use subdiv_mesh::{BuildOptions, Mesh, PolygonSoup};

pub use crate::atomic::remove_temporary_files;
pub use crate::error::IoError;
pub use crate::glb::{
    GlbMesh, GlbWriter, MIN_GLB_EXTENT, check_glb_positions, encode_glb, write_glb, write_glb_interleaved,
};
pub use crate::gltf::{GltfOptions, load_gltf, load_gltf_with, parse_gltf, parse_gltf_with};
pub use crate::obj::{ObjFile, ObjLines, load_obj, read_obj, write_obj, write_obj_to};

/// The formats [`load`] reads.
enum Format {
    Obj,
    Gltf,
}

impl Format {
    /// From the extension of `path`, ignoring case.
    fn of(path: &Path) -> Result<Self, IoError> {
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("obj") => Ok(Self::Obj),
            Some("gltf" | "glb") => Ok(Self::Gltf),
            _ => Err(IoError::UnknownFormat { path: path.to_owned() }),
        }
    }
}

/// Reads the mesh file at `path` into a polygon soup: `.obj`, `.gltf` or `.glb` (any case).
///
/// # Errors
/// [`IoError::UnknownFormat`] for another extension; otherwise as [`load_obj`] or [`load_gltf`].
pub fn load(path: impl AsRef<Path>) -> Result<PolygonSoup, IoError> {
    let path = path.as_ref();
    match Format::of(path)? {
        Format::Obj => load_obj(path),
        Format::Gltf => load_gltf(path),
    }
}

/// Writes `path` atomically through `write`: to a fresh `<name>.<16 hex>.tmp` beside it, synced, then renamed
/// over `path`, so a failure (in `write` too) leaves no half-written file and `path` as it was.
/// For outputs other than meshes, e.g. the CSV of `subdiv eval`.
///
/// ```
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("out.csv");
/// subdiv_io::write_atomic(&path, |w| w.write_all(b"face,u,v\n"))?;
/// assert_eq!(std::fs::read_to_string(&path)?, "face,u,v\n");
/// // A failing writer leaves the previous file alone.
/// let failed = subdiv_io::write_atomic(&path, |_| Err(std::io::Error::other("no")));
/// assert!(failed.is_err());
/// assert_eq!(std::fs::read_to_string(&path)?, "face,u,v\n");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`IoError::Io`] naming `path` when creating, writing, syncing or renaming fails.
pub fn write_atomic(
    path: impl AsRef<Path>,
    write: impl FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    atomic::write_file(path.as_ref(), |w| write(w))
}

/// Reads the mesh file at `path` (as [`load`]) and builds its half-edge mesh.
///
/// # Errors
/// As [`load`]; a soup that is no valid mesh gives [`IoError::Mesh`], with the line of the face,
/// vertex or tag at fault for OBJ files.
pub fn load_mesh(path: impl AsRef<Path>, options: &BuildOptions) -> Result<Mesh, IoError> {
    let path = path.as_ref();
    match Format::of(path)? {
        Format::Obj => ObjFile::load(path)?.build(options),
        Format::Gltf => Mesh::build_with(load_gltf(path)?, options).map_err(|source| IoError::Mesh {
            file: crate::error::shown(path),
            line: None,
            source,
        }),
    }
}
