//! `subdiv tessellate`: a watertight tessellation of the limit surface — dual-grid stitching at
//! per-face rates (uniform, to a tolerance, or from the screen), or paper 002's error-driven
//! quadtree — written as GLB or OBJ, with each vertex's face and parameters on request.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use subdiv::mesh::{DVec3, Mesh};
use subdiv::tess::rates::{Camera, DEFAULT_MAX_RATE};
use subdiv::tess::{DualOptions, DualTessellator};
use subdiv::{FaceRates, Rates, Surface, TessInfo, TessOptions, Tessellation, Tolerance};

use crate::UserError;
use crate::args::{parse_list, parse_size};
use crate::input::{InputArgs, LoadedMesh, check_output, write_error};
use crate::scheme_arg::SchemeArgs;

/// The output file when `-o` is not given.
pub(crate) const DEFAULT_OUTPUT: &str = "tessellation.glb";

/// The rate of every face when no rate policy is given.
pub(crate) const DEFAULT_RATE: u32 = 8;

/// Arguments of `subdiv tessellate`.
#[derive(Debug, clap::Args)]
pub(crate) struct TessellateArgs {
    /// Mesh file (.obj, .gltf, .glb); the built-in model when omitted.
    mesh: Option<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
    #[command(flatten)]
    scheme: SchemeArgs,
    /// How the surface is cut: dual-grid stitching at per-face rates (any primal scheme with
    /// sub-patch matrices, open meshes and holes too), or the error-driven quadtree
    /// (Catmull-Clark meshes, --tolerance). Default: the quadtree with --tolerance (it adapts
    /// inside each face, where the dual method's one rate per face must be as fine as the
    /// finest spot needs) unless --gpu is given, the dual method otherwise.
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Every face at this rate (dual): n × n samples per quad. The default policy, at 8.
    #[arg(long, value_name = "N", conflicts_with_all = ["tolerance", "pixels"])]
    rate: Option<u32>,
    /// Every limit point within this distance of the output (model units, or a fraction of the
    /// bounding-box diagonal with --relative): the rates (dual) or leaves (quadtree) that prove
    /// it. Catmull-Clark meshes; the dual method not yet at extraordinary border vertices (the
    /// quadtree takes them).
    #[arg(long, value_name = "E", allow_negative_numbers = true, conflicts_with = "pixels")]
    tolerance: Option<f64>,
    /// Read --tolerance as a fraction of the control mesh's bounding-box diagonal.
    #[arg(long, requires = "tolerance")]
    relative: bool,
    /// Screen-space rates (dual): output edges about P pixels long on the screen (needs --camera).
    #[arg(long, value_name = "P", allow_negative_numbers = true, requires = "camera")]
    pixels: Option<f64>,
    /// Quadtree: every limit point within P pixels of the output on the screen (a screen-space
    /// error bound, each piece of surface to its own ε; needs --camera).
    #[arg(
        long,
        value_name = "P",
        allow_negative_numbers = true,
        requires = "camera",
        conflicts_with_all = ["rate", "tolerance", "pixels"]
    )]
    pixel_error: Option<f64>,
    /// The camera for --pixels and --pixel-error: eye, target and up, and optionally the
    /// vertical field of view in degrees (default 45).
    #[arg(long, value_name = "EX,EY,EZ,TX,TY,TZ,UX,UY,UZ[,FOVY_DEG]", allow_negative_numbers = true)]
    camera: Option<String>,
    /// The image size for --pixels and --pixel-error.
    #[arg(long, value_name = "W,H", default_value = "1920,1080")]
    viewport: String,
    /// The largest rate --tolerance and --pixels may give a face.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_RATE)]
    max_rate: u32,
    /// The most vertices the output may have (the dual method's count is known from the rates
    /// before any work; the quadtree, with twice the memory per vertex, stops at a quarter this many polygons).
    #[arg(long, value_name = "N", default_value_t = subdiv::DEFAULT_MAX_TESS_VERTICES)]
    max_vertices: usize,
    /// OBJ only: write polygons — the dual tessellation's quads (triangles where there are
    /// none), or the quadtree's leaves with their hanging vertices — instead of triangles.
    #[arg(long)]
    polygons: bool,
    /// Output file, .glb (triangles with normals) or .obj; written atomically.
    #[arg(short, long, default_value = DEFAULT_OUTPUT)]
    output: PathBuf,
    /// Also write `vertex,face,u,v` per output vertex, in output order (Bfr parameters), as CSV:
    /// the GLB's vertices, a crease's or seam's split copies after the others, and with
    /// texture coordinates their `s,t`.
    #[arg(long, value_name = "OUT.csv")]
    params: Option<PathBuf>,
    /// How texture coordinates are interpolated (none, corners-only, corners-plus1,
    /// corners-plus2, boundaries, all); default: the mesh's `facevaryinginterpolateboundary`
    /// tag, else all. Both methods carry them (exact at every vertex, seams split; GLB
    /// `TEXCOORD_0`, OBJ `vt`).
    #[arg(long, value_name = "MODE", value_parser = crate::refine::parse_face_varying)]
    fvar_interpolation: Option<subdiv::mesh::FaceVaryingInterpolation>,
    /// Dual: write only the part of the tessellation that faces A..B (from A, before B) own —
    /// their cells, strips and vertex polygons — as a job of a batch: the points on the part's
    /// border are the same bits as the neighbouring part's, and `subdiv merge` joins the parts
    /// into the whole tessellation. OBJ output (what merge reads).
    #[arg(long, value_name = "A..B", conflicts_with = "gpu")]
    faces: Option<String>,
    /// Dual: evaluate the vertices on the GPU (wgpu, any Vulkan adapter) in f32 instead of on
    /// the CPU in f64; the same tessellation, positions, normals and texture coordinates to f32
    /// precision.
    #[arg(long)]
    gpu: bool,
}

/// `--method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Method {
    /// Dual-grid stitching at per-face rates (Schaefer-Warren §5.5).
    Dual,
    /// Error-driven quadtree with global vertex ids and polyline replacement (Lai-Cheng).
    Quadtree,
}

/// The output format, from the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Glb,
    Obj,
}

impl TessellateArgs {
    /// `--method`, or its default: the quadtree for `--pixel-error`, and for `--tolerance`
    /// without `--gpu`; else dual.
    fn method(&self) -> Method {
        let quadtree = self.pixel_error.is_some() || (self.tolerance.is_some() && !self.gpu);
        let default = if quadtree { Method::Quadtree } else { Method::Dual };
        self.method.unwrap_or(default)
    }
}

pub(crate) fn run(args: &TessellateArgs, _out: &mut impl Write) -> Result<(), UserError> {
    let format = match args.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("glb") => Format::Glb,
        Some("obj") => Format::Obj,
        _ => return Err(UserError(format!("{}: the output must end in .glb or .obj", args.output.display()))),
    };
    if args.polygons && format == Format::Glb {
        return Err(UserError("--polygons needs an .obj output (GLB holds triangles)".to_string()));
    }
    if args.gpu && args.method() == Method::Quadtree {
        return Err(UserError(
            "--gpu evaluates the dual method's vertices; --method quadtree has no GPU path".to_string(),
        ));
    }
    if args.method() == Method::Quadtree && (args.rate.is_some() || args.pixels.is_some()) {
        return Err(UserError(
            "--method quadtree takes --tolerance or --pixel-error, not --rate or --pixels".to_string(),
        ));
    }
    if args.method() == Method::Dual && args.pixel_error.is_some() {
        return Err(UserError(
            "--pixel-error bounds the quadtree's pieces; the dual method takes --pixels (edge length) or --tolerance"
                .to_string(),
        ));
    }
    if args.camera.is_some() && args.pixels.is_none() && args.pixel_error.is_none() {
        return Err(UserError("--camera goes with --pixels or --pixel-error".to_string()));
    }
    let part = args.faces.as_deref().map(parse_face_range).transpose()?;
    if part.is_some() && format != Format::Obj {
        return Err(UserError("--faces writes a part for `subdiv merge`, which reads OBJ: write .obj".to_string()));
    }
    let inputs: Vec<&std::path::Path> = args.mesh.as_deref().into_iter().collect();
    check_output(&inputs, &args.output)?;
    if let Some(params) = &args.params {
        check_output(&inputs, params)?;
    }
    let (input_name, mesh) = LoadedMesh::read_and_build(args.mesh.as_deref(), &args.input)?;
    let scheme = args.scheme.resolve()?;
    let located = |error: &dyn std::fmt::Display| UserError(format!("{}: {error}", input_name));
    let options = options(args)?;
    let refine = subdiv::schemes::RefineOptions {
        face_varying: args.fvar_interpolation,
        ..subdiv::schemes::RefineOptions::DEFAULT
    };
    let mut surface = Surface::new(mesh, &scheme).with_refine_options(refine);
    let start = Instant::now();
    let bar = Spinner::new(surface.mesh().face_count());
    // GLB without --params needs neither the f64 output nor the parameters: the flat f32
    // buffers are streamed to the file chunk by chunk, never held whole (docs/perf-log.md).
    let lean = format == Format::Glb && args.params.is_none() && !args.gpu;
    let (result, gpu_detail) = if let Some(faces) = part {
        bar.say("dual-grid stitching, one part");
        let result = surface.tessellate_part(&options, faces).map_err(|e| located(&e))?;
        (Output::Mesh(Box::new(result)), String::new())
    } else if args.gpu {
        let (result, detail) = gpu_tessellate(&mut surface, &options, args.fvar_interpolation, &bar, located)?;
        (Output::Mesh(Box::new(result)), detail)
    } else {
        bar.say(if args.method() == Method::Quadtree { "quadtree" } else { "dual-grid stitching" });
        if lean {
            // The check the f64 writer makes on the output, made on the cage: f32 buffers can no
            // longer tell a coordinate flushed to 0 from a 0.
            subdiv::io::check_glb_positions(surface.mesh().positions().iter().copied())
                .map_err(|e| write_error(&input_name, &args.output, e))?;
            let (info, vertices, triangles) =
                surface.write_glb_stream(&options, &args.output).map_err(|e| match e {
                    subdiv::Error::Io(e) => write_error(&input_name, &args.output, e),
                    e => located(&e),
                })?;
            (Output::Streamed(info, vertices, triangles), String::new())
        } else {
            (Output::Mesh(Box::new(surface.tessellate(&options).map_err(|e| located(&e))?)), String::new())
        }
    };
    let info = result.info();
    let detail = match (&info.quadtree, info.epsilon, &options.rates) {
        (Some(stats), Some(epsilon), _) => format!("ε = {epsilon:.3e}, depth ≤ {}", stats.max_depth),
        (Some(stats), None, Rates::ScreenError { pixels, .. }) => {
            format!("{pixels} pixels of error on the screen, depth ≤ {}", stats.max_depth)
        }
        _ => {
            let policy = match (info.epsilon, &options.rates) {
                (Some(epsilon), _) => format!("ε = {epsilon:.3e}"),
                (None, Rates::Screen { pixels_per_edge, .. }) => format!("{pixels_per_edge} pixels per edge"),
                (None, Rates::Uniform(rate)) => format!("uniform rate {rate}"),
                (None, _) => "per-face rates".to_string(),
            };
            let rates = &info.rates;
            let (lo, hi) = rates.iter().fold((u32::MAX, 0), |(lo, hi), &r| (lo.min(r), hi.max(r)));
            format!("{policy}, rates {lo}..={hi}{gpu_detail}")
        }
    };
    // Said, not silent: the output has no texture coordinates although the input has some.
    let detail = if crate::scheme_arg::channels_dropped(&surface) {
        format!("{detail}; {}", crate::scheme_arg::CHANNELS_DROPPED)
    } else {
        detail
    };
    let seconds = start.elapsed().as_secs_f64();
    bar.say("writing");
    let written = match (&result, format) {
        (Output::Streamed(..), _) => Ok(()),
        (Output::Mesh(result), Format::Glb) => result.write_glb(&args.output),
        (Output::Mesh(result), Format::Obj) => result.write_obj(&args.output, args.polygons),
    };
    written.map_err(|e| write_error(&input_name, &args.output, e))?;
    if let (Some(path), Output::Mesh(result)) = (&args.params, &result) {
        result.write_params(path).map_err(|e| write_error(&input_name, path, e))?;
    }
    bar.finish();
    let (vertices, triangles) = result.counts();
    let _ = writeln!(
        std::io::stderr(),
        "subdiv tessellate: {} with {scheme} ({:?}, {detail}): {} faces, {vertices} vertices, {triangles} triangles in \
         {seconds:.3} s ({:.2} M triangles/s) -> {}",
        input_name,
        args.method(),
        surface.mesh().face_count(),
        triangles as f64 / seconds.max(1e-9) / 1e6,
        args.output.display(),
    );
    Ok(())
}

/// A tessellation as the output needs it.
enum Output {
    /// The whole f64 output with parameters (OBJ, --params, --gpu).
    Mesh(Box<Tessellation>),
    /// Written already, streamed as flat f32 buffers (GLB): flat vertices, triangles.
    Streamed(TessInfo, usize, usize),
}

impl Output {
    fn info(&self) -> &TessInfo {
        match self {
            Self::Mesh(t) => &t.info,
            Self::Streamed(info, ..) => info,
        }
    }

    /// The vertices (welded; flat buffers count a crease vertex once per normal) and triangles.
    fn counts(&self) -> (usize, usize) {
        match self {
            Self::Mesh(t) => (t.mesh.positions.len(), t.mesh.triangles.len()),
            Self::Streamed(_, vertices, triangles) => (*vertices, *triangles),
        }
    }
}

/// The facade's options from the arguments: the rate policy (uniform at [`DEFAULT_RATE`]
/// unless one is given), the method and the limits.
/// `--faces A..B`: faces A to B − 1.
fn parse_face_range(text: &str) -> Result<std::ops::Range<usize>, UserError> {
    let bad = || UserError(format!("--faces {text:?}: expected A..B, the faces from A up to (not including) B"));
    let (a, b) = text.split_once("..").ok_or_else(bad)?;
    let (a, b): (usize, usize) = (a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?);
    if a >= b {
        return Err(bad());
    }
    Ok(a..b)
}

fn options(args: &TessellateArgs) -> Result<TessOptions, UserError> {
    let rates = if let Some(t) = args.tolerance {
        Rates::Tolerance(if args.relative { Tolerance::Relative(t) } else { Tolerance::Absolute(t) })
    } else if let Some(pixels_per_edge) = args.pixels {
        let camera = parse_camera(args.camera.as_deref().unwrap_or_default())?;
        let viewport = parse_size(&args.viewport, "--viewport", u32::MAX)?;
        Rates::Screen { camera, viewport, pixels_per_edge }
    } else if let Some(pixels) = args.pixel_error {
        let camera = parse_camera(args.camera.as_deref().unwrap_or_default())?;
        let viewport = parse_size(&args.viewport, "--viewport", u32::MAX)?;
        Rates::ScreenError { camera, viewport, pixels }
    } else if args.method() == Method::Quadtree {
        return Err(UserError("--method quadtree needs --tolerance or --pixel-error".to_string()));
    } else {
        Rates::Uniform(args.rate.unwrap_or(DEFAULT_RATE))
    };
    let method = match args.method() {
        Method::Dual => subdiv::Method::Dual,
        Method::Quadtree => subdiv::Method::Quadtree,
    };
    Ok(TessOptions {
        rates,
        method,
        max_rate: args.max_rate,
        polygons: args.polygons,
        max_vertices: args.max_vertices,
        ..TessOptions::DEFAULT
    })
}

/// `--gpu`: the dual tessellation at the facade's rates, its vertices evaluated on the GPU
/// (f32) in place of the CPU's (f64); the detail names the adapter. Errors of the surface's
/// work are `located`.
fn gpu_tessellate(
    surface: &mut Surface,
    options: &TessOptions,
    face_varying: Option<subdiv::mesh::FaceVaryingInterpolation>,
    bar: &Spinner,
    located: impl Fn(&dyn std::fmt::Display) -> UserError,
) -> Result<(Tessellation, String), UserError> {
    let FaceRates { faces, rings, epsilon } = surface.face_rates(options).map_err(|e| located(&e))?;
    let dual = DualOptions {
        quads: options.polygons,
        channels: surface.takes_channels(),
        face_varying,
        ..DualOptions::default()
    };
    let mut tess = DualTessellator::new(surface.scheme(), surface.mesh(), &dual).map_err(|e| located(&e))?;
    bar.say("dual-grid stitching");
    match &rings {
        Some(rings) => tess.tessellate_with_rings(&faces, rings),
        None => tess.tessellate(&faces),
    }
    .map_err(|e| located(&e))?;
    bar.say("evaluating on the GPU");
    let (vertices, channels, adapter) = gpu_evaluate(&tess, surface.mesh())?;
    let mut mesh = tess.into_mesh();
    // Each channel's values too: per flat vertex the first components of its plan's output.
    let stride = mesh.channels.stride();
    for (name, values) in channels {
        let range = mesh.channels.find(&name).expect("a carried channel");
        for (point, v) in mesh.channels.values.chunks_exact_mut(stride).zip(values.chunks_exact(6)) {
            for (x, &g) in point[range.clone()].iter_mut().zip(v) {
                *x = f64::from(g);
            }
        }
    }
    // The GPU's f32 values replace the CPU's f64 ones: per flat vertex its normal (a crease
    // vertex's extra normals past the vertices) and, for the vertices, the position.
    for (k, v) in vertices.chunks_exact(6).enumerate() {
        let wide = |a: usize| DVec3::new(f64::from(v[a]), f64::from(v[a + 1]), f64::from(v[a + 2]));
        mesh.normals[k] = wide(3);
        if let Some(p) = mesh.positions.get_mut(k) {
            *p = wide(0);
        }
    }
    let info = TessInfo { method: subdiv::Method::Dual, rates: faces, epsilon, quadtree: None };
    Ok((Tessellation { mesh, info }, format!(", evaluated on {adapter}")))
}

/// A channel's values evaluated on the GPU: its name, and per flat vertex six floats (the
/// value padded to three, then the value surface's normal).
type GpuChannel = (String, Vec<f32>);

/// Evaluates `tess`'s last tessellation on the GPU: per flat vertex (the vertices, then one
/// per extra normal) `px py pz nx ny nz` (f32), each carried channel through its own plan, and
/// the adapter's name.
fn gpu_evaluate(tess: &DualTessellator, mesh: &Mesh) -> Result<(Vec<f32>, Vec<GpuChannel>, String), UserError> {
    use subdiv_gpu::{Gpu, GpuEvalOptions, GpuOptions, GpuTessellation};
    let gpu_error = |e: subdiv_gpu::GpuError| UserError(format!("--gpu: {e}"));
    let gpu = Gpu::new(&GpuOptions::default()).map_err(gpu_error)?;
    let indices = tess.mesh().flat_indices();
    let options = GpuEvalOptions::default();
    let on_gpu =
        GpuTessellation::new(&gpu, &tess.evaluation_plan(), &indices, mesh.positions(), &options).map_err(gpu_error)?;
    let vertices = on_gpu.read_vertices(&gpu).map_err(gpu_error)?;
    let mut channels = Vec::new();
    for name in &tess.mesh().channels.names {
        let (plan, values) = tess.channel_plan(name).expect("a carried channel");
        let on_gpu = GpuTessellation::new(&gpu, &plan, &indices, values, &options).map_err(gpu_error)?;
        channels.push((name.clone(), on_gpu.read_vertices(&gpu).map_err(gpu_error)?));
    }
    Ok((vertices, channels, gpu.adapter_name()))
}

/// `--camera EX,EY,EZ,TX,TY,TZ,UX,UY,UZ[,FOVY_DEG]`.
fn parse_camera(text: &str) -> Result<Camera, UserError> {
    let v = parse_list(text, "--camera", 9, 10)?;
    let camera =
        Camera::look_at(DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]), DVec3::new(v[6], v[7], v[8]));
    Ok(v.get(9).map_or(camera, |&fovy| camera.with_fovy_degrees(fovy)))
}

/// A spinner on stderr for long jobs (indicatif draws nothing when stderr is not a terminal).
struct Spinner(indicatif::ProgressBar);

impl Spinner {
    fn new(faces: usize) -> Self {
        let bar = if faces > 20_000 { indicatif::ProgressBar::new_spinner() } else { indicatif::ProgressBar::hidden() };
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        Self(bar)
    }

    fn say(&self, step: &str) {
        self.0.set_message(format!("subdiv tessellate: {step}"));
    }

    fn finish(&self) {
        self.0.finish_and_clear();
    }
}
