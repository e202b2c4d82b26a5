//! Image tests: shared meshes tessellated on the CPU (dual grid, rate 8), their vertices
//! evaluated on the GPU (`GpuTessellation`, the path `subdiv render` takes), rendered offscreen at
//! a fixed camera and compared with reference PNGs under the repository's `testdata/render/`
//! (mean absolute difference over RGB below 1% of 255), plus structural checks that a broken
//! renderer fails whatever the references say.
//!
//! The references are made on Mesa's lavapipe (as CI runs) and regenerated only on request:
//! `SUBDIV_BLESS=1 cargo test -p subdiv-gpu --test images`. A failed comparison writes the
//! actual image and a difference image next to the test's temporary folder and names them.

#![allow(clippy::print_stderr)]

use std::path::{Path, PathBuf};

use glam::Vec3;
use image::{Rgba, RgbaImage};
use subdiv_gpu::{Gpu, GpuEvalOptions, GpuMesh, GpuTessellation, RenderOptions, Renderer, View};
use subdiv_mesh::BuildOptions;
use subdiv_schemes::Builtin;
use subdiv_tess::{DualOptions, DualTessellator, EvaluationPlan, FlatMesh};
use subdiv_testkit::shared_mesh;

const WIDTH: u32 = 320;
const HEIGHT: u32 = 240;
const RATE: u32 = 8;

/// The largest mean absolute difference over RGB, as a fraction of 255.
const TOLERANCE: f64 = 0.01;

/// A shared mesh tessellated at [`RATE`]: its cage, the evaluation plan, and the CPU's flat
/// buffers (f64 values rounded to f32).
struct Tessellated {
    cage: Vec<glam::DVec3>,
    plan: EvaluationPlan,
    flat: FlatMesh,
}

fn tessellate(relative: &str) -> Option<Tessellated> {
    let path = shared_mesh(relative)?;
    let mesh = subdiv_io::load_mesh(&path, &BuildOptions::default()).expect("the shared mesh loads");
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default())
        .expect("Catmull-Clark takes the mesh");
    let mut flat = FlatMesh::default();
    tess.tessellate_flat(&vec![RATE; mesh.face_count()], &mut flat).expect("rate 8 is valid");
    Some(Tessellated { cage: mesh.positions().to_vec(), plan: tess.evaluation_plan(), flat })
}

/// A render as the `image` crate's image (for its pixel access and PNG files).
fn rgba(image: subdiv_gpu::Image) -> RgbaImage {
    let (width, height) = image.dimensions();
    RgbaImage::from_raw(width, height, image.into_pixels()).expect("4 bytes per pixel")
}

/// The surface evaluated on the GPU, drawn.
fn render(gpu: &Gpu, t: &Tessellated, view: View, wireframe: bool) -> RgbaImage {
    let options = RenderOptions::default().with_size(WIDTH, HEIGHT).with_wireframe(wireframe);
    let renderer = Renderer::new(gpu, &options).expect("a renderer");
    let eval = GpuEvalOptions { edges: wireframe, ..GpuEvalOptions::default() };
    let surface = GpuTessellation::new(gpu, &t.plan, &t.flat.indices, &t.cage, &eval).expect("the plan uploads");
    rgba(renderer.render(gpu, &surface.scene(view)).expect("the scene renders"))
}

/// The CPU's values uploaded and drawn: the GPU evaluation must look the same.
fn render_cpu(gpu: &Gpu, t: &Tessellated, view: View) -> RgbaImage {
    let options = RenderOptions::default().with_size(WIDTH, HEIGHT);
    let renderer = Renderer::new(gpu, &options).expect("a renderer");
    let mesh = GpuMesh::upload(gpu, &t.flat).expect("the mesh uploads");
    rgba(renderer.render(gpu, &mesh.scene(view)).expect("the scene renders"))
}

/// The mean absolute difference over RGB as a fraction of 255.
fn mean_difference(a: &RgbaImage, b: &RgbaImage) -> f64 {
    let total: u64 =
        a.pixels().zip(b.pixels()).map(|(p, q)| (0..3).map(|c| u64::from(p[c].abs_diff(q[c]))).sum::<u64>()).sum();
    total as f64 / (3.0 * f64::from(a.width() * a.height()) * 255.0)
}

/// A fixed camera looking at the origin with y up (not the automatic framing, so that a change
/// there does not move the references).
fn camera(eye: [f32; 3], near: f32, far: f32) -> View {
    View { eye: Vec3::from(eye), target: Vec3::ZERO, up: Vec3::Y, fovy_degrees: 30.0, near, far }
}

fn reference_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/render").join(format!("{name}.png"))
}

fn luminance(p: &Rgba<u8>) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

fn is_background(p: &Rgba<u8>) -> bool {
    let [r, g, b] = RenderOptions::DEFAULT.background;
    p[0].abs_diff(r) <= 1 && p[1].abs_diff(g) <= 1 && p[2].abs_diff(b) <= 1
}

/// Checks what any correct render of a closed object in the middle of the image shows: the
/// corners are the background, the centre is not, and the left (towards the key light) is
/// brighter than the right.
fn check_structure(name: &str, image: &RgbaImage) {
    let (w, h) = image.dimensions();
    for (x, y) in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)] {
        assert!(is_background(image.get_pixel(x, y)), "{name}: corner ({x}, {y}) is {:?}", image.get_pixel(x, y));
    }
    assert!(!is_background(image.get_pixel(w / 2, h / 2)), "{name}: the centre is background");
    let object: Vec<(u32, f64)> =
        image.enumerate_pixels().filter(|(_, _, p)| !is_background(p)).map(|(x, _, p)| (x, luminance(p))).collect();
    let covered = object.len() as f64 / f64::from(w * h);
    assert!((0.1..0.8).contains(&covered), "{name}: the object covers {covered:.2} of the image");
    let centre_x = object.iter().map(|&(x, _)| f64::from(x)).sum::<f64>() / object.len() as f64;
    let mean = |left: bool| {
        let side: Vec<f64> =
            object.iter().filter(|&&(x, _)| (f64::from(x) < centre_x) == left).map(|&(_, l)| l).collect();
        side.iter().sum::<f64>() / side.len() as f64
    };
    let (left, right) = (mean(true), mean(false));
    assert!(left > right + 5.0, "{name}: the lit side (left, {left:.1}) is not brighter than the right ({right:.1})");
}

/// Compares with the reference, or writes it under `SUBDIV_BLESS=1`.
fn compare(name: &str, image: &RgbaImage) {
    let path = reference_path(name);
    if std::env::var("SUBDIV_BLESS").is_ok_and(|v| v == "1") {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        image.save(&path).expect("the reference is written");
        eprintln!("blessed {}", path.display());
        return;
    }
    let reference = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (make it with SUBDIV_BLESS=1)", path.display()))
        .to_rgba8();
    assert_eq!(reference.dimensions(), image.dimensions(), "{name}: size differs from the reference");
    let mut total = 0u64;
    let diff = RgbaImage::from_fn(image.width(), image.height(), |x, y| {
        let (a, b) = (image.get_pixel(x, y), reference.get_pixel(x, y));
        let d = [0, 1, 2].map(|c| a[c].abs_diff(b[c]));
        total += d.iter().map(|&v| u64::from(v)).sum::<u64>();
        // Differences amplified eight times, on black.
        Rgba([d[0].saturating_mul(8), d[1].saturating_mul(8), d[2].saturating_mul(8), 255])
    });
    let mean = total as f64 / (3.0 * f64::from(image.width() * image.height()) * 255.0);
    if mean >= TOLERANCE {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("images");
        std::fs::create_dir_all(&dir).unwrap();
        let (actual, difference) = (dir.join(format!("{name}.actual.png")), dir.join(format!("{name}.diff.png")));
        image.save(&actual).unwrap();
        diff.save(&difference).unwrap();
        panic!(
            "{name}: mean absolute difference {:.3}% of 255 ≥ {:.1}%; actual {}, difference {}, reference {}",
            100.0 * mean,
            100.0 * TOLERANCE,
            actual.display(),
            difference.display(),
            path.display()
        );
    }
}

#[test]
fn catmark_cube_shaded_and_wireframe() {
    let Some(t) = tessellate("opensubdiv/catmark_cube.obj") else { return };
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let view = camera([3.3, 2.7, 4.7], 2.0, 10.0);
    let shaded = render(&gpu, &t, view, false);
    check_structure("catmark_cube", &shaded);
    compare("catmark_cube", &shaded);
    let cpu = render_cpu(&gpu, &t, view);
    let d = mean_difference(&shaded, &cpu);
    assert!(d < 1e-3, "catmark_cube: GPU and CPU evaluation differ by {:.4}% of 255", 100.0 * d);

    let wired = render(&gpu, &t, view, true);
    check_structure("catmark_cube_wireframe", &wired);
    compare("catmark_cube_wireframe", &wired);
    // The lines darken the surface under them, and only there: many pixels darker, none lighter.
    let (mut darker, mut lighter) = (0, 0);
    for (a, b) in wired.pixels().zip(shaded.pixels()) {
        let d = luminance(a) - luminance(b);
        darker += usize::from(d < -20.0);
        lighter += usize::from(d > 20.0);
    }
    assert!(darker > 2000 && lighter == 0, "the wireframe made {darker} pixels darker and {lighter} lighter");
}

#[test]
fn spot_shaded() {
    let Some(t) = tessellate("keenan/spot_control_mesh.obj") else { return };
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let view = View { target: Vec3::new(0.0, 0.1, 0.15), ..camera([3.2, 1.9, -2.6], 2.0, 7.5) };
    let image = render(&gpu, &t, view, false);
    check_structure("spot_control_mesh", &image);
    compare("spot_control_mesh", &image);
    let d = mean_difference(&image, &render_cpu(&gpu, &t, view));
    assert!(d < 1e-3, "spot: GPU and CPU evaluation differ by {:.4}% of 255", 100.0 * d);
}

/// Infinitely sharp and semi-sharp creases: each side of a sharp crease shaded with its own
/// normal (the split vertices), the GPU's evaluation as the CPU's.
#[test]
fn creased_cube_shaded() {
    let Some(t) = tessellate("opensubdiv/catmark_cube_creases2.obj") else { return };
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let positions: std::collections::HashSet<[u32; 3]> =
        t.flat.vertices.chunks_exact(6).map(|v| [v[0].to_bits(), v[1].to_bits(), v[2].to_bits()]).collect();
    assert!(positions.len() < t.flat.vertices.len() / 6, "no crease vertex is split");
    let view = camera([-4.0, 3.2, 5.6], 2.0, 12.0);
    let image = render(&gpu, &t, view, false);
    check_structure("catmark_cube_creases2", &image);
    compare("catmark_cube_creases2", &image);
    let d = mean_difference(&image, &render_cpu(&gpu, &t, view));
    assert!(d < 1e-3, "catmark_cube_creases2: GPU and CPU evaluation differ by {:.4}% of 255", 100.0 * d);
}
