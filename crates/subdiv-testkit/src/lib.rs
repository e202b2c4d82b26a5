//! Test support shared by the workspace's test suites (a dev-dependency only).
//!
//! The shared corpus (`../shared` beside the workspace) is found through the environment
//! variable `SUBDIV_SHARED`, which `.ci/run` sets. When it is set, the data must be there: a
//! missing folder or file fails the test instead of skipping it. When it is unset, `../shared`
//! beside the workspace is used if it exists, and otherwise the caller skips, saying so.
//!
//! With the `gpu` feature, [`gpu`] is the device of every GPU test: it skips the same way
//! without an adapter, unless `SUBDIV_REQUIRE_GPU=1` (which `.ci/run` sets) makes that a failure.

#![allow(clippy::print_stderr)]

pub mod opensubdiv;
pub mod refined;

use std::path::{Path, PathBuf};

/// The shared folder, or `None` (after saying so on stderr) when `SUBDIV_SHARED` is unset and
/// there is no `../shared` beside the workspace.
///
/// # Panics
/// When `SUBDIV_SHARED` is set but has no `testdata/meshes` folder.
pub fn shared_dir() -> Option<PathBuf> {
    match std::env::var_os("SUBDIV_SHARED") {
        Some(dir) => {
            let dir = PathBuf::from(dir);
            assert!(dir.join("testdata/meshes").is_dir(), "SUBDIV_SHARED={} has no testdata/meshes", dir.display());
            Some(dir)
        }
        None => {
            let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
            if dir.join("testdata/meshes").is_dir() {
                Some(dir)
            } else {
                eprintln!("SUBDIV_SHARED is unset and ../shared is missing: shared-corpus checks not run");
                None
            }
        }
    }
}

/// The device for a GPU test ([`subdiv_gpu::Gpu::new`] with the default options): `None`
/// (after saying so on stderr) when there is none, unless `SUBDIV_REQUIRE_GPU=1`, where it
/// panics instead, so that CI cannot pass by skipping.
///
/// ```no_run
/// let Some(gpu) = subdiv_testkit::gpu() else { return };
/// assert!(!gpu.adapter_name().is_empty());
/// ```
///
/// # Panics
/// When no device can be had and `SUBDIV_REQUIRE_GPU=1`.
#[cfg(feature = "gpu")]
pub fn gpu() -> Option<subdiv_gpu::Gpu> {
    match subdiv_gpu::Gpu::new(&subdiv_gpu::GpuOptions::default()) {
        Ok(gpu) => Some(gpu),
        Err(e) if std::env::var("SUBDIV_REQUIRE_GPU").is_ok_and(|v| v == "1") => {
            panic!("SUBDIV_REQUIRE_GPU=1 but {e}")
        }
        Err(e) => {
            eprintln!("skipping a GPU test: {e}");
            None
        }
    }
}

/// A peer harness program named by the environment variable `var` (`SUBDIV_OSD_REFINE`,
/// `SUBDIV_OSD_LIMIT`, which `.ci/run` sets): `None` (after saying so on stderr) when it is
/// unset.
///
/// # Panics
/// When the variable is set but names no file.
pub fn peer_program(var: &str) -> Option<PathBuf> {
    let path = std::env::var_os(var).map(PathBuf::from);
    match &path {
        Some(p) => assert!(p.is_file(), "{var}={} does not exist", p.display()),
        None => eprintln!("{var} is unset: comparison with OpenSubdiv not run"),
    }
    path
}

/// The shared meshes folder, `<shared>/testdata/meshes`; `None` as for [`shared_dir`].
pub fn meshes_dir() -> Option<PathBuf> {
    shared_dir().map(|dir| dir.join("testdata/meshes"))
}

/// A file of the shared meshes folder, e.g. `"keenan/spot_control_mesh.obj"`; `None` as for
/// [`shared_dir`].
///
/// # Panics
/// When the shared folder is there but the file is not.
pub fn shared_mesh(relative: &str) -> Option<PathBuf> {
    let path = meshes_dir()?.join(relative);
    assert!(path.is_file(), "{} is missing from the shared corpus", path.display());
    Some(path)
}

/// Every `.obj` file below `dir`, recursively, in sorted path order.
pub fn obj_files(dir: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        let mut entries: Vec<_> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "obj") {
                out.push(path);
            }
        }
    }
    let mut files = Vec::new();
    walk(dir, &mut files);
    files
}

/// The shared meshes with sharp features (a `t crease` or `t corner` tag) that load, with the
/// scheme each is meant for (Loop for the all-triangle `loop_*` shapes, else Catmull-Clark), in
/// path order; empty when the shared folder is not set.
///
/// # Panics
/// When the shared folder is set but a mesh file cannot be read.
pub fn creased_meshes() -> Vec<(PathBuf, subdiv_schemes::Builtin, subdiv_mesh::Mesh)> {
    let Some(dir) = meshes_dir() else { return Vec::new() };
    let mut out = Vec::new();
    for path in obj_files(&dir) {
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        if !text.lines().any(|l| l.starts_with("t crease") || l.starts_with("t corner")) {
            continue;
        }
        let Ok(mesh) = subdiv_io::load_mesh(&path, &Default::default()) else { continue };
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let builtin = if name.starts_with("loop_") {
            subdiv_schemes::Builtin::Loop
        } else {
            subdiv_schemes::Builtin::CatmullClark
        };
        out.push((path, builtin, mesh));
    }
    out
}

/// Every shared mesh that builds, with the scheme it is meant for (as
/// [`opensubdiv::compare_refinement`] picks it: `loop_` and other all-triangle meshes Loop,
/// `bilinear_` bilinear, else Catmull-Clark), in path order; empty when the shared folder is not
/// set.
///
/// # Panics
/// When the shared folder is set but a mesh file cannot be read.
pub fn shared_meshes() -> Vec<(PathBuf, subdiv_schemes::Builtin, subdiv_mesh::Mesh)> {
    let Some(dir) = meshes_dir() else { return Vec::new() };
    let mut out = Vec::new();
    for path in obj_files(&dir) {
        let soup = subdiv_io::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let (builtin, _) = opensubdiv::scheme_of(&name, &soup);
        let Ok(mesh) = subdiv_mesh::Mesh::build(soup) else { continue };
        out.push((path, builtin, mesh));
    }
    out
}

/// The [`shared_meshes`] with texture coordinates.
///
/// # Panics
/// As [`shared_meshes`].
pub fn textured_meshes() -> Vec<(PathBuf, subdiv_schemes::Builtin, subdiv_mesh::Mesh)> {
    shared_meshes().into_iter().filter(|(_, _, mesh)| !mesh.channels().is_empty()).collect()
}
