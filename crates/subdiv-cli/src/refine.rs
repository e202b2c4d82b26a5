//! `subdiv refine`: uniform refinement to OBJ.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use subdiv::Surface;
use subdiv::mesh::FaceVaryingInterpolation;
use subdiv::schemes::RefineOptions;

use crate::UserError;
use crate::input::{InputArgs, LoadedMesh, check_output, write_error};
use crate::scheme_arg::SchemeArgs;

/// Arguments of `subdiv refine`.
#[derive(Debug, clap::Args)]
pub(crate) struct RefineArgs {
    /// Mesh file (.obj, .gltf, .glb); the built-in model when omitted.
    mesh: Option<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
    #[command(flatten)]
    scheme: SchemeArgs,
    /// Number of refinement levels (each multiplies the face count by about 4).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=8))]
    levels: u32,
    /// How texture coordinates refine: none, corners-only, corners-plus1, corners-plus2,
    /// boundaries or all (OpenSubdiv's modes, from smooth everywhere to linear everywhere);
    /// default: the mesh's `facevaryinginterpolateboundary` tag, else all.
    #[arg(long, value_name = "MODE", value_parser = parse_face_varying)]
    fvar_interpolation: Option<FaceVaryingInterpolation>,
    /// The most faces the refinement may make (a larger request is refused before any work).
    #[arg(long, value_name = "FACES", default_value_t = subdiv::DEFAULT_MAX_REFINED_FACES)]
    max_faces: u64,
    /// Output OBJ file; standard output when omitted. The refined sharpness, holes (kept as
    /// faces with a `t hole` tag) and texture coordinates are written, so that refining the
    /// output again continues the same surface.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub(crate) fn run(args: &RefineArgs, out: &mut impl Write) -> Result<(), UserError> {
    if let Some(output) = &args.output {
        check_output(&args.mesh.as_deref().into_iter().collect::<Vec<_>>(), output)?;
    }
    let (input_name, mesh) = LoadedMesh::read_and_build(args.mesh.as_deref(), &args.input)?;
    let scheme = args.scheme.resolve()?;
    let levels = args.levels as usize;
    let start = Instant::now();
    // A progress bar on stderr when the run is long (indicatif draws nothing when stderr is not
    // a terminal).
    let options = RefineOptions { face_varying: args.fvar_interpolation, ..RefineOptions::DEFAULT };
    let surface = Surface::new(mesh, &scheme).with_max_refined_faces(args.max_faces).with_refine_options(options);
    let bar = if surface.refined_faces_at_least(levels) > 2_000_000 {
        indicatif::ProgressBar::new(levels as u64).with_message(format!("refining with {}", scheme.name()))
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] level {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let refined = surface
        .refine_with_progress(levels, |level| bar.set_position(level as u64))
        .map_err(|error| UserError(format!("{}: {error}", input_name)))?;
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    let soup = refined.to_soup();
    match &args.output {
        Some(path) => subdiv::io::write_obj(path, &soup).map_err(|e| write_error(&input_name, path, e))?,
        None => subdiv::io::write_obj_to(&mut *out, &soup)
            .map_err(|e| UserError(format!("{}: writing standard output: {e}", input_name)))?,
    }
    let faces = soup.face_count();
    let _ = writeln!(
        std::io::stderr(),
        "subdiv refine: {} with {} x{}: {} vertices, {faces} faces in {seconds:.3} s ({:.1} M faces/s)",
        input_name,
        scheme,
        args.levels,
        soup.vertex_count(),
        faces as f64 / seconds.max(1e-9) / 1e6,
    );
    Ok(())
}

/// A face-varying interpolation mode by its name (OpenSubdiv's, as `osd_refine` takes them).
pub(crate) fn parse_face_varying(name: &str) -> Result<FaceVaryingInterpolation, String> {
    FaceVaryingInterpolation::ALL_MODES.into_iter().find(|m| m.name() == name).ok_or_else(|| {
        let known: Vec<_> = FaceVaryingInterpolation::ALL_MODES.iter().map(|m| m.name()).collect();
        format!("unknown face-varying interpolation {name:?}; known: {}", known.join(", "))
    })
}
