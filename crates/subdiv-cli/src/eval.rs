//! `subdiv eval`: exact limit positions and derivatives at face parameters, as CSV in the
//! columns, parameterization and row order of OpenSubdiv's `osd_limit` (the peer harness).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use subdiv::mesh::{BoundaryInterpolation, Channel, FaceId};
use subdiv::{EvalMethod, EvalOptions, GridPoint, LimitPoint, MAX_GRID, Surface};

use crate::UserError;
use crate::input::{InputArgs, LoadedMesh, check_output, write_error};
use crate::scheme_arg::SchemeArgs;

/// Arguments of `subdiv eval`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("points").required(true).args(["grid", "samples"])))]
pub(crate) struct EvalArgs {
    /// Mesh file (.obj, .gltf, .glb); the built-in model when omitted.
    mesh: Option<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
    #[command(flatten)]
    scheme: SchemeArgs,
    /// Every face at the grid (i/N, j/N): quads (N+1)² points, j outer, i inner; triangles of
    /// triangle schemes i + j ≤ N; other faces of quad schemes the (N+1)² grid of every
    /// sub-face, as OpenSubdiv's Bfr lays them out.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_GRID)))]
    grid: Option<u32>,
    /// Points from a file: one `face u v` per line (Bfr parameters; commas or spaces; `#`
    /// starts a comment). f64 parameters are used exactly (rounded to a multiple of 2^-60 only
    /// when they have more binary digits).
    #[arg(long, value_name = "FILE")]
    samples: Option<PathBuf>,
    /// Boundary interpolation; default: the file's `interpolateboundary` tag, else edge-only.
    #[arg(long, value_enum)]
    boundary: Option<Boundary>,
    /// Evaluation method: `eigen` (eigenbasis, Stam / Lai-Cheng; faces it cannot take are
    /// errors), `stencil` (exact stencils) or `auto` (eigenbasis where the face's patches are
    /// interior Catmull-Clark or Loop-like ones, exact stencils elsewhere).
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
    method: MethodArg,
    /// How texture coordinates are interpolated (none, corners-only, corners-plus1,
    /// corners-plus2, boundaries, all); default: the mesh's `facevaryinginterpolateboundary`
    /// tag, else all. When the mesh has texture coordinates, the columns `s,t,dsu,dtu,dsv,dtv`
    /// (their exact values and derivatives) follow the position's.
    #[arg(long, value_name = "MODE", value_parser = crate::refine::parse_face_varying)]
    fvar_interpolation: Option<subdiv::mesh::FaceVaryingInterpolation>,
    /// The most points `--grid` may evaluate (a larger request is refused before any work).
    #[arg(long, value_name = "POINTS", default_value_t = subdiv::DEFAULT_MAX_POINTS)]
    max_points: u64,
    /// Output CSV file (written atomically); standard output when omitted.
    #[arg(short, long)]
    output: Option<PathBuf>,
}

/// `--boundary`, in OpenSubdiv's words.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Boundary {
    EdgeOnly,
    EdgeAndCorner,
    None,
}

/// `--method`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum MethodArg {
    Eigen,
    Stencil,
    Auto,
}

pub(crate) fn run(args: &EvalArgs, out: &mut impl Write) -> Result<(), UserError> {
    if let Some(output) = &args.output {
        let inputs: Vec<&std::path::Path> = args.mesh.iter().chain(&args.samples).map(PathBuf::as_path).collect();
        check_output(&inputs, output)?;
    }
    let (input_name, mesh) = LoadedMesh::read_and_build(args.mesh.as_deref(), &args.input)?;
    let scheme = args.scheme.resolve()?;
    let method = match args.method {
        MethodArg::Eigen => EvalMethod::Eigen,
        MethodArg::Stencil => EvalMethod::Stencil,
        MethodArg::Auto => EvalMethod::Auto,
    };
    let mut options = EvalOptions::DEFAULT.with_method(method).with_max_points(args.max_points);
    if let Some(boundary) = args.boundary {
        options = options.with_boundary(match boundary {
            Boundary::EdgeOnly => BoundaryInterpolation::EdgeOnly,
            Boundary::EdgeAndCorner => BoundaryInterpolation::EdgeAndCorner,
            Boundary::None => BoundaryInterpolation::None,
        });
    }
    options.refine.face_varying = args.fvar_interpolation;
    let start = Instant::now();
    let named = |error: subdiv::Error| UserError(format!("{}: {error}", input_name));
    let has_uv = mesh.channel(Channel::UV).is_some();
    let surface = Surface::new(mesh, &scheme).with_refine_options(options.refine);
    let dropped = crate::scheme_arg::channels_dropped(&surface);
    let has_uv = has_uv && !dropped;
    let evaluator = surface.evaluator(&options).map_err(named)?;
    let mut skipped = 0;
    let rows = match (args.grid, &args.samples) {
        (Some(n), _) => {
            let grid = evaluator.grid(n).map_err(named)?;
            skipped = grid.holes;
            grid.points
        }
        (None, Some(path)) => {
            let samples = read_samples(path)?;
            let mut rows = Vec::with_capacity(samples.len());
            for (line, face, u, v) in samples {
                match evaluator.evaluate(face, u, v) {
                    Ok(point) => rows.push(GridPoint { face, u, v, point }),
                    // Checked after the point's domain: a hole skips only valid samples.
                    Err(error) if error.is_hole() => skipped += 1,
                    Err(error) => return Err(UserError(format!("{}:{line}: {error}", path.display()))),
                }
            }
            rows
        }
        (None, None) => return Err(UserError("give --grid N or --samples FILE".to_string())),
    };
    // The texture coordinates at the same points.
    let uv = if has_uv {
        let channel = surface.channel_evaluator(Channel::UV, &options).map_err(named)?;
        let at = |r: &GridPoint| channel.evaluate(r.face, r.u, r.v);
        Some(rows.iter().map(at).collect::<Result<Vec<_>, _>>().map_err(named)?)
    } else {
        None
    };
    let seconds = start.elapsed().as_secs_f64();
    // Everything is evaluated before anything is written, so a failure writes nothing.
    let write = |w: &mut dyn Write| write_csv(w, &rows, uv.as_deref());
    match &args.output {
        Some(path) => subdiv::io::write_atomic(path, write).map_err(|e| write_error(&input_name, path, e))?,
        None => write(out).map_err(|e| UserError(format!("{}: writing standard output: {e}", input_name)))?,
    }
    let mut stderr = std::io::stderr();
    let at_vertices = rows.iter().filter(|r| !r.point.exact_derivatives).count();
    let _ = writeln!(
        stderr,
        "subdiv eval: {} with {}: {} points in {seconds:.3} s ({:.0} points/s)",
        input_name,
        scheme,
        rows.len(),
        rows.len() as f64 / seconds.max(1e-9),
    );
    if at_vertices > 0 {
        let _ = writeln!(
            stderr,
            "subdiv eval: {at_vertices} points lie on extraordinary vertices: their du, dv are tangent directions \
             (the parameterization has no derivative there; du x dv is the normal)"
        );
    }
    if skipped > 0 {
        let _ = writeln!(stderr, "subdiv eval: {skipped} points or faces without limit surface (holes) skipped");
    }
    if dropped {
        let _ = writeln!(stderr, "subdiv eval: {}", crate::scheme_arg::CHANNELS_DROPPED);
    }
    Ok(())
}

/// The samples of `path`: `(line, face, u, v)`.
fn read_samples(path: &Path) -> Result<Vec<(usize, FaceId, f64, f64)>, UserError> {
    let text = std::fs::read_to_string(path).map_err(|e| UserError(format!("{}: {e}", path.display())))?;
    let mut samples = Vec::new();
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let content = raw.split('#').next().unwrap_or_default();
        let fields: Vec<&str> = content.split([',', ' ', '\t']).filter(|s| !s.is_empty()).collect();
        if fields.is_empty() {
            continue;
        }
        let bad = || {
            UserError(format!(
                "{}:{line}: expected `face u v` (a face index and two numbers), got `{}`",
                path.display(),
                raw.trim()
            ))
        };
        let [face, u, v] = fields[..] else { return Err(bad()) };
        let face: u32 = face.parse().map_err(|_| bad())?;
        let (u, v): (f64, f64) = (u.parse().map_err(|_| bad())?, v.parse().map_err(|_| bad())?);
        samples.push((line, FaceId::new(face), u, v));
    }
    Ok(samples)
}

/// `osd_limit`'s CSV: `face,u,v,px,py,pz,dux,duy,duz,dvx,dvy,dvz`, and with texture
/// coordinates (one per row) `s,t,dsu,dtu,dsv,dtv` (`osd_limit --fvar`'s), shortest
/// round-trip f64s.
fn write_csv(w: &mut dyn Write, rows: &[GridPoint], uv: Option<&[LimitPoint]>) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(w);
    write!(w, "face,u,v,px,py,pz,dux,duy,duz,dvx,dvy,dvz")?;
    writeln!(w, "{}", if uv.is_some() { ",s,t,dsu,dtu,dsv,dtv" } else { "" })?;
    for (k, GridPoint { face, u, v, point: p }) in rows.iter().enumerate() {
        let (x, du, dv) = (p.position, p.du, p.dv);
        write!(
            w,
            "{},{u:?},{v:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
            face.index(),
            x.x,
            x.y,
            x.z,
            du.x,
            du.y,
            du.z,
            dv.x,
            dv.y,
            dv.z
        )?;
        if let Some(t) = uv.and_then(|uv| uv.get(k)) {
            let (x, du, dv) = (t.position, t.du, t.dv);
            write!(w, ",{:?},{:?},{:?},{:?},{:?},{:?}", x.x, x.y, du.x, du.y, dv.x, dv.y)?;
        }
        writeln!(w)?;
    }
    w.flush()
}
