//! `subdiv tessellate`: a watertight tessellation of the limit surface whose every triangle is
//! within a tolerance of it (paper 002's error-driven quadtree), written as GLB or OBJ.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use subdiv::io::{GlbMesh, write_glb};
use subdiv::tess::{TessMesh, TessOptions, Tessellator, Tolerance};

use crate::UserError;
use crate::input::LoadedMesh;
use crate::scheme_arg::SchemeArgs;

/// Arguments of `subdiv tessellate`.
#[derive(Debug, clap::Args)]
pub(crate) struct TessellateArgs {
    /// Mesh file (.obj, .gltf, .glb), closed; the built-in model when omitted.
    mesh: Option<PathBuf>,
    #[command(flatten)]
    scheme: SchemeArgs,
    /// How the surface is cut into polygons.
    #[arg(long, value_enum, default_value_t = Method::Quadtree)]
    method: Method,
    /// Every output triangle lies within this distance of the limit surface (each parameter
    /// point of a triangle maps within it of the triangle's interpolant); model units, or a
    /// fraction of the bounding-box diagonal with --relative.
    #[arg(long, value_name = "E", allow_negative_numbers = true)]
    tolerance: f64,
    /// Read --tolerance as a fraction of the control mesh's bounding-box diagonal.
    #[arg(long)]
    relative: bool,
    /// Write polygons (the quadtree's leaves with their hanging vertices) instead of
    /// triangles; OBJ only. The bound holds for the triangles.
    #[arg(long)]
    polygons: bool,
    /// Output file, .glb (triangles with normals) or .obj; written atomically. Without it only
    /// the summary is printed.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

/// `--method`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Method {
    /// Error-driven quadtree with global vertex ids and polyline replacement (Lai-Cheng).
    Quadtree,
}

/// The output format, from the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Glb,
    Obj,
}

pub(crate) fn run(args: &TessellateArgs, _out: &mut impl Write) -> Result<(), UserError> {
    let format = match &args.output {
        None => None,
        Some(path) => match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("glb") => Some(Format::Glb),
            Some("obj") => Some(Format::Obj),
            _ => return Err(UserError(format!("{}: the output must end in .glb or .obj", path.display()))),
        },
    };
    if args.polygons && format == Some(Format::Glb) {
        return Err(UserError("--polygons needs an .obj output (GLB holds triangles)".to_string()));
    }
    let (loaded, mesh) = LoadedMesh::read_and_build(args.mesh.as_deref())?;
    let scheme = args.scheme.resolve()?;
    let tolerance =
        if args.relative { Tolerance::Relative(args.tolerance) } else { Tolerance::Absolute(args.tolerance) };
    let start = Instant::now();
    let tess = match args.method {
        Method::Quadtree => Tessellator::new(&scheme, &mesh),
    }
    .map_err(|error| UserError(format!("{}: {error}", loaded.name)))?;
    let (result, stats) = tess
        .tessellate_with_stats(&TessOptions::DEFAULT.with_tolerance(tolerance))
        .map_err(|error| UserError(format!("{}: {error}", loaded.name)))?;
    let seconds = start.elapsed().as_secs_f64();
    if let (Some(path), Some(format)) = (&args.output, format) {
        match format {
            Format::Glb => {
                let positions: Vec<_> = result.positions.iter().map(|p| p.as_vec3()).collect();
                let normals: Vec<_> = result.normals.iter().map(|n| n.as_vec3()).collect();
                let indices = result.triangle_indices();
                write_glb(path, &GlbMesh { positions: &positions, normals: Some(&normals), indices: &indices })?;
            }
            Format::Obj => subdiv::io::write_atomic(path, |w| write_obj(w, &result, args.polygons))?,
        }
    }
    let epsilon = tolerance.absolute(tess.diagonal()).map_err(|error| UserError(error.to_string()))?;
    let mut stderr = std::io::stderr();
    let _ = writeln!(
        stderr,
        "subdiv tessellate: {} with {scheme}: {} faces, ε = {epsilon:.3e}: {} vertices, {} polygons, {} triangles, \
         depth ≤ {}, in {seconds:.3} s",
        loaded.name,
        mesh.face_count(),
        result.positions.len(),
        result.polygon_count(),
        result.triangles.len(),
        stats.max_depth,
    );
    Ok(())
}

/// OBJ with `v` and `vn` lines, and faces as `f v//vn`: the triangles, or the polygons (which
/// leave the triangles' centre vertices unused).
fn write_obj(w: &mut dyn Write, mesh: &TessMesh, polygons: bool) -> std::io::Result<()> {
    writeln!(w, "# subdiv tessellate")?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for n in &mesh.normals {
        writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    let face = |w: &mut dyn Write, vertices: &[u32]| -> std::io::Result<()> {
        write!(w, "f")?;
        for &v in vertices {
            write!(w, " {0}//{0}", v + 1)?;
        }
        writeln!(w)
    };
    if polygons {
        for k in 0..mesh.polygon_count() {
            face(w, mesh.polygon(k))?;
        }
    } else {
        for t in &mesh.triangles {
            face(w, t)?;
        }
    }
    Ok(())
}
