//! `subdiv refine`: uniform refinement to OBJ.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use subdiv::mesh::{BuildOptions, FaceId, Mesh, PolygonSoup, shapes};
use subdiv::schemes::{RefineOptions, Scheme, refine_uniform};

use crate::UserError;
use crate::input::LoadedMesh;

/// Arguments of `subdiv refine`.
#[derive(Debug, clap::Args)]
pub(crate) struct RefineArgs {
    /// Mesh file (.obj, .gltf, .glb); the built-in model when omitted.
    mesh: Option<PathBuf>,
    /// Subdivision scheme.
    #[arg(long, default_value = "catmull-clark", value_parser = parse_scheme)]
    scheme: Scheme,
    /// Number of refinement levels (each multiplies the face count by about 4).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=8))]
    levels: u32,
    /// Output OBJ file; standard output when omitted. Hole faces are left out.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub(crate) fn parse_scheme(name: &str) -> Result<Scheme, String> {
    Scheme::from_name(name).ok_or_else(|| {
        let known: Vec<_> = Scheme::ALL.iter().map(|s| s.name()).collect();
        format!("unknown scheme {name:?}; known: {}", known.join(", "))
    })
}

pub(crate) fn run(args: &RefineArgs, out: &mut impl Write) -> Result<(), UserError> {
    let loaded = match &args.mesh {
        Some(path) => LoadedMesh::read(path)?,
        None => LoadedMesh::built_in(shapes::default_model()),
    };
    let mesh = Mesh::build_with(loaded.soup.clone(), &BuildOptions::default())
        .map_err(|error| UserError(loaded.locate(&error)))?;
    let start = Instant::now();
    let refined = refine_uniform(&mesh, args.scheme, args.levels as usize, &RefineOptions::DEFAULT)
        .map_err(|error| UserError(format!("{}: {error}", loaded.name)))?;
    let seconds = start.elapsed().as_secs_f64();
    let soup = without_holes(&refined);
    match &args.output {
        Some(path) => subdiv::io::write_obj(path, &soup)?,
        None => subdiv::io::write_obj_to(&mut *out, &soup)?,
    }
    let faces = soup.face_count();
    let _ = writeln!(
        std::io::stderr(),
        "subdiv refine: {} with {} x{}: {} vertices, {faces} faces in {seconds:.3} s ({:.1} M faces/s)",
        loaded.name,
        args.scheme,
        args.levels,
        soup.vertex_count(),
        faces as f64 / seconds.max(1e-9) / 1e6,
    );
    Ok(())
}

/// The refined mesh as a soup, hole faces left out (their vertices stay, so numbering does not
/// change), as OpenSubdiv's refinement output does.
fn without_holes(mesh: &Mesh) -> PolygonSoup {
    let mut soup = PolygonSoup::with_capacity(mesh.vertex_count(), mesh.face_count(), mesh.half_edge_count());
    for &p in mesh.positions() {
        soup.push_vertex(p);
    }
    for f in mesh.face_ids().filter(|&f| !mesh.is_hole(f)) {
        soup.push_face(mesh.face_vertices(FaceId::new(f.raw())).iter().copied());
    }
    soup
}
