//! `subdiv render`: the limit surface tessellated on the CPU (dual grid: topology and stencils),
//! its vertices evaluated on the GPU from the control points (one compute dispatch), drawn
//! offscreen and written as PNG; optionally its wireframe and the control cage, and an animated
//! sequence of a twisted cage (only the control points change per frame).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use subdiv::mesh::shapes::twist;
use subdiv::tess::rates::ScreenSpace;
use subdiv::tess::{DualOptions, DualTessellator, FlatMesh, MAX_DUAL_RATE};
use subdiv_gpu::{
    Gpu, GpuCage, GpuEvalOptions, GpuOptions, GpuTessellation, GpuTexcoords, MAX_IMAGE_SIDE, RenderOptions, Renderer,
    Texture, TextureImage, View,
};

use crate::UserError;
use crate::args::parse_size;
use crate::input::{InputArgs, LoadedMesh, write_error};
use crate::scheme_arg::SchemeArgs;
use crate::tessellate::DEFAULT_RATE;

/// The output file when `-o` is not given.
const DEFAULT_OUTPUT: &str = "render.png";

/// The uniform rate of the tessellation whose bounding box frames the camera (for every rate
/// policy, so that `--rate` and `--pixels` frame a mesh alike, and before `--pixels` needs the
/// camera).
const FRAMING_RATE: u32 = 4;

/// The twist of the last frame of `--frames`, top against bottom, in degrees.
const TWIST_DEGREES: f64 = 90.0;

/// Arguments of `subdiv render`.
#[derive(Debug, clap::Args)]
pub(crate) struct RenderArgs {
    /// Mesh file (.obj, .gltf, .glb); the built-in model when omitted.
    mesh: Option<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
    #[command(flatten)]
    scheme: SchemeArgs,
    /// Output PNG; written atomically. With --frames, numbered next to it: OUT_0000.png, …
    #[arg(short, long, value_name = "OUT.png", default_value = DEFAULT_OUTPUT)]
    output: PathBuf,
    /// The image size in pixels (sides from 1 to 16384).
    #[arg(long, value_name = "W,H", default_value = "800,600")]
    size: String,
    /// Every face at this rate (1 to 1024). The default policy, at 8.
    #[arg(long, value_name = "N", conflicts_with = "pixels")]
    rate: Option<u32>,
    /// Screen-space rates: output edges about P pixels long in the image, from the automatic
    /// framing's camera.
    #[arg(long, value_name = "P", allow_negative_numbers = true)]
    pixels: Option<f64>,
    /// The most vertices the tessellation may have (counted from the rates before any work).
    #[arg(long, value_name = "N", default_value_t = subdiv::DEFAULT_MAX_TESS_VERTICES)]
    max_vertices: usize,
    /// Draw the tessellation's edges over the surface.
    #[arg(long)]
    wireframe: bool,
    /// Draw the control cage (orange; hidden parts faint).
    #[arg(long)]
    cage: bool,
    /// Render K frames of a built-in animation (the cage twisted about its vertical axis,
    /// frame 0 undeformed) as a numbered PNG sequence.
    #[arg(long, value_name = "K")]
    frames: Option<u32>,
    /// Texture the surface through its texture coordinates (exact at every vertex, split at
    /// seams): `checker` (16 squares per unit, to check the mapping), `checker:N` (N squares per
    /// unit, 1 to 4096), or an image file (PNG, JPEG, …; `t` runs up the image).
    #[arg(long, value_name = "checker[:N]|IMAGE", value_parser = parse_texture)]
    texture: Option<TextureArg>,
}

/// `--texture`.
#[derive(Clone, Debug, PartialEq)]
enum TextureArg {
    /// A checker of this many squares per unit of texture coordinates.
    Checker(u32),
    /// An image file.
    Image(PathBuf),
}

/// The checker's squares per unit when `--texture checker` says no number.
const DEFAULT_CHECKER: u32 = 16;

/// `--texture checker[:N]|IMAGE`.
fn parse_texture(text: &str) -> Result<TextureArg, String> {
    let squares = match text.split_once(':') {
        None if text == "checker" => DEFAULT_CHECKER,
        Some(("checker", n)) => n.parse().map_err(|_| format!("checker:{n}: N must be an integer"))?,
        _ => return Ok(TextureArg::Image(PathBuf::from(text))),
    };
    if !(1..=subdiv_gpu::MAX_CHECKER).contains(&squares) {
        return Err(format!("checker:{squares}: squares per unit are 1 to {}", subdiv_gpu::MAX_CHECKER));
    }
    Ok(TextureArg::Checker(squares))
}

/// The image `--texture` asks for.
fn texture_image(texture: &TextureArg, surface: [u8; 3]) -> Result<TextureImage, UserError> {
    match texture {
        TextureArg::Checker(squares) => Ok(TextureImage::checker(*squares, surface)?),
        TextureArg::Image(path) => {
            let failed = |e: &dyn std::fmt::Display| UserError(format!("{}: --texture: {e}", path.display()));
            let image = image::open(path).map_err(|e| failed(&e))?.to_rgba8();
            let (width, height) = image.dimensions();
            TextureImage::rgba(width, height, image.into_raw()).map_err(|e| failed(&e))
        }
    }
}

/// Checks every argument that needs no mesh and no device, so that bad input fails before any
/// work and before anything is written.
fn check(args: &RenderArgs) -> Result<([u32; 2], Option<u32>), UserError> {
    let is_png = args.output.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(UserError(format!("{}: the output must end in .png", args.output.display())));
    }
    let size = parse_size(&args.size, "--size", MAX_IMAGE_SIDE)?;
    if let Some(rate) = args.rate
        && !(1..=MAX_DUAL_RATE).contains(&rate)
    {
        return Err(UserError(format!("--rate {rate}: rates are integers from 1 to {MAX_DUAL_RATE}")));
    }
    if let Some(pixels) = args.pixels
        && !(pixels.is_finite() && pixels > 0.0)
    {
        return Err(UserError(format!("--pixels {pixels}: pixels per edge must be a positive finite number")));
    }
    if args.frames == Some(0) {
        return Err(UserError("--frames 0: the number of frames must be at least 1".to_string()));
    }
    Ok((size, args.frames))
}

pub(crate) fn run(args: &RenderArgs, _out: &mut impl Write) -> Result<(), UserError> {
    let ([width, height], frames) = check(args)?;
    let options = RenderOptions { wireframe: args.wireframe, ..RenderOptions::default().with_size(width, height) };
    // The image first: a missing file fails before any work.
    let image = args.texture.as_ref().map(|t| texture_image(t, options.surface)).transpose()?;
    let (input_name, mesh) = LoadedMesh::read_and_build(args.mesh.as_deref(), &args.input)?;
    let scheme = args.scheme.resolve()?;
    let located = |error: &dyn std::fmt::Display| UserError(format!("{}: {error}", input_name));
    if args.texture.is_some() && mesh.channel(subdiv::mesh::Channel::UV).is_none_or(|c| c.dimension() < 2) {
        return Err(located(&"--texture: the mesh has no texture coordinates (OBJ `vt`, glTF TEXCOORD_0)"));
    }
    let start = Instant::now();
    let budget = |rates: &[u32]| {
        subdiv::check_vertex_budget(&mesh, &scheme, rates, None, args.max_vertices).map_err(|e| located(&e))
    };
    let framing = vec![FRAMING_RATE; mesh.face_count()];
    budget(&framing)?;
    // The texture coordinates only when they are drawn: carrying them cuts the seams.
    let dual = DualOptions { quads: false, channels: args.texture.is_some(), ..DualOptions::default() };
    let mut tess = DualTessellator::new(&scheme, &mesh, &dual).map_err(|e| located(&e))?;
    let mut flat = FlatMesh::default();

    // The camera, from the undeformed surface (so that frames do not jump).
    tess.tessellate_flat(&framing, &mut flat).map_err(|e| located(&e))?;
    let [lo, hi] =
        subdiv_gpu::bounds(&flat.vertices).ok_or_else(|| located(&"the surface is empty (every face a hole)"))?;
    let view = View::framing(lo, hi, options.aspect());

    let (rates, policy) = match args.pixels {
        Some(pixels) => {
            let policy = ScreenSpace::new(view.camera(), [width, height], pixels);
            (policy.face_rates(&mesh).map_err(|e| located(&e))?, format!("{pixels} pixels per edge"))
        }
        None => {
            let rate = args.rate.unwrap_or(DEFAULT_RATE);
            (vec![rate; mesh.face_count()], format!("uniform rate {rate}"))
        }
    };
    budget(&rates)?;
    tess.tessellate_flat(&rates, &mut flat).map_err(|e| located(&e))?;
    let tessellated = start.elapsed();

    let gpu = Gpu::new(&GpuOptions::default())?;
    let renderer = Renderer::new(&gpu, &options)?;
    let eval_options = GpuEvalOptions { edges: args.wireframe, ..GpuEvalOptions::default() };
    let surface = GpuTessellation::new(&gpu, &tess.evaluation_plan(), &flat.indices, mesh.positions(), &eval_options)?;
    let cage = if args.cage { Some(GpuCage::upload(&gpu, &mesh)?) } else { None };
    let texture = match &image {
        Some(image) => Some((GpuTexcoords::upload(&gpu, &flat.texcoords)?, renderer.texture(&gpu, image)?)),
        None => None,
    };
    let scene = |view| subdiv_gpu::Scene {
        cage: cage.as_ref().map(GpuCage::lines),
        texture: texture.as_ref().map(|(t, image)| Texture { texcoords: &t.buffer, image }),
        ..surface.scene(view)
    };

    let drawing = Instant::now();
    let written = match frames {
        None => {
            write_png(&input_name, &args.output, &renderer.render(&gpu, &scene(view))?)?;
            args.output.display().to_string()
        }
        Some(frames) => {
            let paths: Vec<PathBuf> = (0..frames).map(|k| numbered(&args.output, k)).collect();
            for (k, path) in (0..frames).zip(&paths) {
                let moved = twist(mesh.positions(), TWIST_DEGREES.to_radians() * f64::from(k) / f64::from(frames));
                // The animation path: new control points, one dispatch re-evaluates the vertices.
                surface.update_control_points_f64(&gpu, &moved).map_err(|e| located(&e))?;
                if let Some(cage) = &cage {
                    cage.write_positions(&gpu, &moved)?;
                }
                write_png(&input_name, path, &renderer.render(&gpu, &scene(view))?)?;
            }
            format!("{} … {}", paths[0].display(), paths[paths.len() - 1].display())
        }
    };
    let per_image = drawing.elapsed().as_secs_f64() * 1e3 / f64::from(frames.unwrap_or(1));
    let (rate_lo, rate_hi) = rates.iter().fold((u32::MAX, 0), |(lo, hi), &r| (lo.min(r), hi.max(r)));
    let frames_note = frames.map_or(String::new(), |k| format!(", {k} frames"));
    let _ = writeln!(
        std::io::stderr(),
        "subdiv render: {} with {scheme} ({policy}, rates {rate_lo}..={rate_hi}): {} faces, {} vertices, {} triangles \
         tessellated in {:.1} ms; {width}×{height} on {}{frames_note}, {per_image:.1} ms per image -> {written}",
        input_name,
        mesh.face_count(),
        surface.vertex_count(),
        surface.index_count() / 3,
        tessellated.as_secs_f64() * 1e3,
        gpu.adapter_name(),
    );
    Ok(())
}

/// `OUT.png` as `OUT_0007.png` for frame 7, in the same folder.
fn numbered(output: &Path, frame: u32) -> PathBuf {
    let stem = output.file_stem().map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let extension = output.extension().map_or_else(String::new, |e| e.to_string_lossy().into_owned());
    output.with_file_name(format!("{stem}_{frame:04}.{extension}"))
}

/// The image as an RGB PNG, written atomically ([`subdiv::io::write_atomic`]).
/// An error names `input` (the mesh) and `path`.
fn write_png(input: &str, path: &Path, image: &subdiv_gpu::Image) -> Result<(), UserError> {
    let png = image.encode_png().map_err(|e| write_error(input, path, e))?;
    subdiv::io::write_atomic(path, |writer| writer.write_all(&png)).map_err(|e| write_error(input, path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_numbered_next_to_the_output() {
        assert_eq!(numbered(Path::new("out/spin.png"), 7), Path::new("out/spin_0007.png"));
        assert_eq!(numbered(Path::new("render.png"), 12), Path::new("render_0012.png"));
    }
}
