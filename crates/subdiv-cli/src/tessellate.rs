//! `subdiv tessellate`: a watertight tessellation of the limit surface — dual-grid stitching at
//! per-face rates (uniform, to a tolerance, or from the screen), or paper 002's error-driven
//! quadtree — written as GLB or OBJ, with each vertex's face and parameters on request.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use subdiv::io::{GlbMesh, write_glb};
use subdiv::mesh::{DVec3, Mesh};
use subdiv::schemes::Scheme;
use subdiv::tess::rates::{Camera, DEFAULT_MAX_RATE, DualRates, ErrorRates, RingDepths, ScreenSpace};
use subdiv::tess::{DualOptions, DualTessellator, QuadtreeOptions, QuadtreeTessellator, TessMesh, Tolerance};

use crate::UserError;
use crate::args::{parse_list, parse_size};
use crate::input::LoadedMesh;
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
    scheme: SchemeArgs,
    /// How the surface is cut: dual-grid stitching at per-face rates (any primal scheme with
    /// sub-patch matrices, open meshes and holes too), or the error-driven quadtree (closed
    /// Catmull-Clark meshes, --tolerance).
    #[arg(long, value_enum, default_value_t = Method::Dual)]
    method: Method,
    /// Every face at this rate (dual): n × n samples per quad. The default policy, at 8.
    #[arg(long, value_name = "N", conflicts_with_all = ["tolerance", "pixels"])]
    rate: Option<u32>,
    /// Every limit point within this distance of the output (model units, or a fraction of the
    /// bounding-box diagonal with --relative): the rates (dual) or leaves (quadtree) that prove
    /// it. Dual: closed Catmull-Clark meshes.
    #[arg(long, value_name = "E", allow_negative_numbers = true, conflicts_with = "pixels")]
    tolerance: Option<f64>,
    /// Read --tolerance as a fraction of the control mesh's bounding-box diagonal.
    #[arg(long, requires = "tolerance")]
    relative: bool,
    /// Screen-space rates (dual): output edges about P pixels long on the screen (needs --camera).
    #[arg(long, value_name = "P", allow_negative_numbers = true, requires = "camera")]
    pixels: Option<f64>,
    /// The camera for --pixels: eye, target and up, and optionally the vertical field of view
    /// in degrees (default 45).
    #[arg(
        long,
        value_name = "EX,EY,EZ,TX,TY,TZ,UX,UY,UZ[,FOVY_DEG]",
        allow_negative_numbers = true,
        requires = "pixels"
    )]
    camera: Option<String>,
    /// The image size for --pixels.
    #[arg(long, value_name = "W,H", default_value = "1920,1080", requires = "pixels")]
    viewport: String,
    /// The largest rate --tolerance and --pixels may give a face.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_RATE)]
    max_rate: u32,
    /// OBJ only: write polygons — the dual tessellation's quads (triangles where there are
    /// none), or the quadtree's leaves with their hanging vertices — instead of triangles.
    #[arg(long)]
    polygons: bool,
    /// Output file, .glb (triangles with normals) or .obj; written atomically.
    #[arg(short, long, default_value = DEFAULT_OUTPUT)]
    output: PathBuf,
    /// Also write `vertex,face,u,v` per output vertex, in output order (Bfr parameters), as CSV.
    #[arg(long, value_name = "OUT.csv")]
    params: Option<PathBuf>,
    /// Dual: evaluate the vertices on the GPU (wgpu, any Vulkan adapter) in f32 instead of on
    /// the CPU in f64; the same tessellation, positions and normals to f32 precision.
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

pub(crate) fn run(args: &TessellateArgs, _out: &mut impl Write) -> Result<(), UserError> {
    let format = match args.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("glb") => Format::Glb,
        Some("obj") => Format::Obj,
        _ => return Err(UserError(format!("{}: the output must end in .glb or .obj", args.output.display()))),
    };
    if args.polygons && format == Format::Glb {
        return Err(UserError("--polygons needs an .obj output (GLB holds triangles)".to_string()));
    }
    let tolerance = args.tolerance.map(|t| if args.relative { Tolerance::Relative(t) } else { Tolerance::Absolute(t) });
    if args.gpu && args.method == Method::Quadtree {
        return Err(UserError(
            "--gpu evaluates the dual method's vertices; --method quadtree has no GPU path".to_string(),
        ));
    }
    if args.method == Method::Quadtree && (args.rate.is_some() || args.pixels.is_some()) {
        return Err(UserError("--method quadtree takes --tolerance, not --rate or --pixels".to_string()));
    }
    let (loaded, mesh) = LoadedMesh::read_and_build(args.mesh.as_deref())?;
    let scheme = args.scheme.resolve()?;
    let located = |error: &dyn std::fmt::Display| UserError(format!("{}: {error}", loaded.name));
    let start = Instant::now();
    let bar = Spinner::new(mesh.face_count());
    let (result, detail) = match args.method {
        Method::Quadtree => {
            let tolerance = tolerance.ok_or_else(|| UserError("--method quadtree needs --tolerance".to_string()))?;
            let tess = QuadtreeTessellator::new(&scheme, &mesh).map_err(|e| located(&e))?;
            let epsilon = tolerance.absolute(tess.diagonal()).map_err(|e| located(&e))?;
            bar.say("quadtree");
            let (result, stats) = tess
                .tessellate_with_stats(&QuadtreeOptions::DEFAULT.with_tolerance(tolerance))
                .map_err(|e| located(&e))?;
            (result, format!("ε = {epsilon:.3e}, depth ≤ {}", stats.max_depth))
        }
        Method::Dual => {
            let (rates, rings, policy) = dual_rates(args, tolerance, &scheme, &mesh, &loaded.name)?;
            let options = DualOptions { quads: args.polygons, ..DualOptions::default() };
            let mut tess = DualTessellator::new(&scheme, &mesh, &options).map_err(|e| located(&e))?;
            bar.say("dual-grid stitching");
            match &rings {
                Some(rings) => tess.tessellate_with_rings(&rates, rings),
                None => tess.tessellate(&rates),
            }
            .map_err(|e| located(&e))?;
            let gpu = if args.gpu {
                bar.say("evaluating on the GPU");
                Some(gpu_evaluate(&tess, &mesh)?)
            } else {
                None
            };
            let mut result = tess.into_mesh();
            let mut detail = String::new();
            if let Some((vertices, adapter)) = gpu {
                // The GPU's f32 values replace the CPU's f64 ones.
                for (k, v) in vertices.chunks_exact(6).enumerate() {
                    let wide = |a: usize| DVec3::new(f64::from(v[a]), f64::from(v[a + 1]), f64::from(v[a + 2]));
                    (result.positions[k], result.normals[k]) = (wide(0), wide(3));
                }
                detail = format!(", evaluated on {adapter}");
            }
            let (lo, hi) = rates.iter().fold((u32::MAX, 0), |(lo, hi), &r| (lo.min(r), hi.max(r)));
            (result, format!("{policy}, rates {lo}..={hi}{detail}"))
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    bar.say("writing");
    match format {
        Format::Glb => {
            let positions: Vec<_> = result.positions.iter().map(|p| p.as_vec3()).collect();
            let normals: Vec<_> = result.normals.iter().map(|n| n.as_vec3()).collect();
            let indices = result.triangle_indices();
            write_glb(&args.output, &GlbMesh { positions: &positions, normals: Some(&normals), indices: &indices })?;
        }
        Format::Obj => {
            let faces = match (args.polygons, args.method) {
                (false, _) => ObjFaces::Triangles,
                (true, Method::Quadtree) => ObjFaces::Polygons,
                (true, Method::Dual) => ObjFaces::PolygonsAndTriangles,
            };
            subdiv::io::write_atomic(&args.output, |w| write_obj(w, &result, faces))?;
        }
    }
    if let Some(path) = &args.params {
        write_params(path, &result)?;
    }
    bar.finish();
    let triangles = result.triangles.len();
    let _ = writeln!(
        std::io::stderr(),
        "subdiv tessellate: {} with {scheme} ({:?}, {detail}): {} faces, {} vertices, {triangles} triangles in \
         {seconds:.3} s ({:.2} M triangles/s) -> {}",
        loaded.name,
        args.method,
        mesh.face_count(),
        result.positions.len(),
        triangles as f64 / seconds.max(1e-9) / 1e6,
        args.output.display(),
    );
    Ok(())
}

/// Evaluates `tess`'s last tessellation on the GPU: per vertex `px py pz nx ny nz` (f32), and
/// the adapter's name.
fn gpu_evaluate(tess: &DualTessellator, mesh: &Mesh) -> Result<(Vec<f32>, String), UserError> {
    use subdiv_gpu::{Gpu, GpuEvalOptions, GpuOptions, GpuTessellation};
    let gpu_error = |e: subdiv_gpu::GpuError| UserError(format!("--gpu: {e}"));
    let gpu = Gpu::new(&GpuOptions::default()).map_err(gpu_error)?;
    let indices = tess.mesh().triangle_indices();
    let on_gpu =
        GpuTessellation::new(&gpu, &tess.evaluation_plan(), &indices, mesh.positions(), &GpuEvalOptions::default())
            .map_err(gpu_error)?;
    let vertices = on_gpu.read_vertices(&gpu).map_err(gpu_error)?;
    Ok((vertices, gpu.adapter_name()))
}

/// The per-face rates of the dual method, the rings around extraordinary points (for a
/// tolerance), and the policy in words.
fn dual_rates(
    args: &TessellateArgs,
    tolerance: Option<Tolerance>,
    scheme: &Scheme,
    mesh: &Mesh,
    name: &str,
) -> Result<(Vec<u32>, Option<RingDepths>, String), UserError> {
    let located = |error: subdiv::tess::TessError| UserError(format!("{name}: {error}"));
    if let Some(tolerance) = tolerance {
        let bounds =
            QuadtreeTessellator::new(scheme, mesh).map_err(|e| UserError(format!("{name}: --tolerance: {e}")))?;
        let policy = ErrorRates { tolerance, max_rate: args.max_rate };
        let DualRates { faces, rings } = policy.rates(&bounds, mesh).map_err(located)?;
        let epsilon = tolerance.absolute(bounds.diagonal())?;
        return Ok((faces, Some(rings), format!("ε = {epsilon:.3e}")));
    }
    if let Some(pixels) = args.pixels {
        let camera = parse_camera(args.camera.as_deref().unwrap_or_default())?;
        let viewport = parse_size(&args.viewport, "--viewport", u32::MAX)?;
        let policy = ScreenSpace { max_rate: args.max_rate, ..ScreenSpace::new(camera, viewport, pixels) };
        return Ok((policy.face_rates(mesh).map_err(located)?, None, format!("{pixels} pixels per edge")));
    }
    let rate = args.rate.unwrap_or(DEFAULT_RATE);
    Ok((vec![rate; mesh.face_count()], None, format!("uniform rate {rate}")))
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

/// `vertex,face,u,v` per output vertex, in output order, written atomically.
fn write_params(path: &Path, mesh: &TessMesh) -> Result<(), UserError> {
    subdiv::io::write_atomic(path, |w| {
        writeln!(w, "vertex,face,u,v")?;
        for (k, p) in mesh.parameters.iter().enumerate() {
            writeln!(w, "{k},{},{:?},{:?}", p.face.index(), p.u, p.v)?;
        }
        Ok(())
    })?;
    Ok(())
}

/// Which faces an OBJ output lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ObjFaces {
    Triangles,
    /// The polygons alone: they cover the surface (the quadtree's leaves; its triangles' fan
    /// centres stay unused).
    Polygons,
    /// The polygons and the triangles outside them (the dual tessellation's quads, and its
    /// strip and vertex triangles).
    PolygonsAndTriangles,
}

/// OBJ with `v` and `vn` lines, and faces as `f v//vn`.
fn write_obj(w: &mut dyn Write, mesh: &TessMesh, faces: ObjFaces) -> std::io::Result<()> {
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
    if faces == ObjFaces::Triangles {
        for t in &mesh.triangles {
            face(w, t)?;
        }
        return Ok(());
    }
    for k in 0..mesh.polygon_count() {
        face(w, mesh.polygon(k))?;
    }
    if faces == ObjFaces::PolygonsAndTriangles {
        // A dual quad `a b c d` is the triangles `a b c` and `a c d`.
        let mut covered = std::collections::HashSet::new();
        for k in 0..mesh.polygon_count() {
            let p = mesh.polygon(k);
            for i in 1..p.len().saturating_sub(1) {
                covered.insert(sorted([p[0], p[i], p[i + 1]]));
            }
        }
        for t in mesh.triangles.iter().filter(|t| !covered.contains(&sorted(**t))) {
            face(w, t)?;
        }
    }
    Ok(())
}

fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}
