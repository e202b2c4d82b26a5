//! The renderer's seam and its errors: a scene of raw buffers in the `FlatMesh` layout (as a
//! compute pass writes them) draws like an uploaded mesh, the animation path changes the image,
//! and bad scenes are typed errors after which the renderer still works.

use glam::Vec3;
use subdiv_gpu::{GpuError, GpuMesh, GpuTexcoords, Lines, RenderOptions, Renderer, Scene, Texture, TextureImage, View};
use subdiv_mesh::{Channel, Mesh, shapes};
use subdiv_schemes::Builtin;
use subdiv_tess::{DualOptions, DualTessellator, FlatMesh};
use wgpu::util::DeviceExt;

fn cube(rate: u32) -> (DualTessellator, Mesh, FlatMesh) {
    let mesh = Mesh::build(shapes::cube()).unwrap();
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default()).unwrap();
    let mut flat = FlatMesh::default();
    tess.tessellate_flat(&vec![rate; mesh.face_count()], &mut flat).unwrap();
    (tess, mesh, flat)
}

fn options() -> RenderOptions {
    RenderOptions::default().with_size(96, 72)
}

fn framing(flat: &FlatMesh) -> View {
    let [lo, hi] = subdiv_gpu::bounds(&flat.vertices).unwrap();
    View::framing(lo, hi, options().aspect())
}

#[test]
fn raw_buffers_draw_like_an_uploaded_mesh_and_frames_move() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let (mut tess, mesh, flat) = cube(6);
    let renderer = Renderer::new(&gpu, &options().with_wireframe(true)).unwrap();
    let uploaded = GpuMesh::upload_with_edges(&gpu, &flat).unwrap();
    let view = framing(&flat);
    let reference = renderer.render(&gpu, &uploaded.scene(view)).unwrap();

    // The buffers a compute pass would write: STORAGE | VERTEX | COPY_SRC, no GpuMesh involved.
    let init = |contents: &[u8], usage| {
        gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents, usage })
    };
    let vertices = init(
        bytemuck::cast_slice(&flat.vertices),
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC,
    );
    let triangles = init(bytemuck::cast_slice(&flat.indices), wgpu::BufferUsages::INDEX);
    let edges = subdiv_gpu::unique_edges(&flat.indices);
    let lines = init(bytemuck::cast_slice(&edges), wgpu::BufferUsages::INDEX);
    let scene = Scene {
        vertices: &vertices,
        vertex_count: (flat.vertices.len() / 6) as u32,
        triangles: &triangles,
        index_count: flat.indices.len() as u32,
        wireframe: Some(Lines { indices: &lines, index_count: edges.len() as u32 }),
        texture: None,
        cage: None,
        view,
    };
    assert_eq!(renderer.render(&gpu, &scene).unwrap(), reference);

    // The animation path: a moved cage re-evaluated and written into the same buffer.
    let moved: Vec<_> = mesh.positions().iter().map(|p| *p * glam::DVec3::new(1.3, 0.8, 1.0)).collect();
    let mut moved_flat = FlatMesh::default();
    tess.update_cage_flat(&moved, &mut moved_flat).unwrap();
    uploaded.write_vertices(&gpu, &moved_flat.vertices).unwrap();
    assert_ne!(renderer.render(&gpu, &uploaded.scene(view)).unwrap(), reference);
    uploaded.write_vertices(&gpu, &flat.vertices).unwrap();
    assert_eq!(renderer.render(&gpu, &uploaded.scene(view)).unwrap(), reference);
    assert!(matches!(uploaded.write_vertices(&gpu, &flat.vertices[6..]), Err(GpuError::Scene(_))));
}

#[test]
fn bad_scenes_are_errors_and_the_renderer_survives_them() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let (_, _, flat) = cube(3);
    let renderer = Renderer::new(&gpu, &options()).unwrap();
    let mesh = GpuMesh::upload(&gpu, &flat).unwrap();
    let good = mesh.scene(framing(&flat));
    let scene_error = |scene: &Scene<'_>, renderer: &Renderer| match renderer.render(&gpu, scene) {
        Err(GpuError::Scene(message)) => message,
        other => panic!("expected a scene error, got {other:?}"),
    };
    let message = scene_error(&Scene { index_count: good.index_count - 1, ..good }, &renderer);
    assert!(message.contains("not a multiple of 3"), "{message}");
    let message = scene_error(&Scene { vertex_count: good.vertex_count + 1, ..good }, &renderer);
    assert!(message.contains("do not fit"), "{message}");
    let message = scene_error(&Scene { view: View { eye: good.view.target, ..good.view }, ..good }, &renderer);
    assert!(message.contains("eye is on the target"), "{message}");
    let wired = Renderer::new(&gpu, &options().with_wireframe(true)).unwrap();
    let message = scene_error(&good, &wired);
    assert!(message.contains("no line indices"), "{message}");

    // A buffer without the VERTEX usage: wgpu's validation error, returned, not a panic.
    let storage_only = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: mesh.vertices.size(),
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    match renderer.render(&gpu, &Scene { vertices: &storage_only, ..good }) {
        Err(GpuError::Wgpu { message, .. }) => assert!(!message.is_empty()),
        other => panic!("expected a wgpu error, got {other:?}"),
    }
    // Still usable afterwards.
    let image = renderer.render(&gpu, &good).unwrap();
    assert_eq!(image.dimensions(), (96, 72));

    // Mesh data that breaks the layout.
    let broken = FlatMesh { vertices: flat.vertices.clone(), indices: vec![0, 1, u32::MAX], ..FlatMesh::default() };
    assert!(matches!(GpuMesh::upload(&gpu, &broken), Err(GpuError::Scene(m)) if m.contains("not below")));
    let broken = FlatMesh { vertices: vec![0.0; 7], indices: vec![], ..FlatMesh::default() };
    assert!(matches!(GpuMesh::upload(&gpu, &broken), Err(GpuError::Scene(_))));
    // Sizes.
    for (w, h) in [(0, 10), (10, 0), (16385, 10)] {
        assert!(matches!(
            Renderer::new(&gpu, &options().with_size(w, h)),
            Err(GpuError::ImageSize { width, height, .. }) if (width, height) == (w, h)
        ));
    }
}

#[test]
fn the_cage_is_drawn_in_orange() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let (_, mesh, flat) = cube(4);
    let renderer = Renderer::new(&gpu, &options()).unwrap();
    let surface = GpuMesh::upload(&gpu, &flat).unwrap();
    let cage = subdiv_gpu::GpuCage::upload(&gpu, &mesh).unwrap();
    // Framed on the cage, which is larger than the surface.
    let [lo, hi] = [Vec3::splat(-0.5), Vec3::splat(0.5)];
    let view = View::framing(lo, hi, options().aspect());
    let plain = renderer.render(&gpu, &surface.scene(view)).unwrap();
    let caged = renderer.render(&gpu, &Scene { cage: Some(cage.lines()), ..surface.scene(view) }).unwrap();
    let orange = |image: &subdiv_gpu::Image| {
        image.pixels().chunks_exact(4).filter(|p| p[0] > 200 && p[1] < 170 && p[2] < 80).count()
    };
    assert_eq!(orange(&plain), 0);
    assert!(orange(&caged) > 40, "{} orange pixels", orange(&caged));
}

#[test]
fn images_are_rows_of_rgba_bytes() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let (_, _, flat) = cube(4);
    let renderer = Renderer::new(&gpu, &options()).unwrap();
    let mesh = GpuMesh::upload(&gpu, &flat).unwrap();
    let image = renderer.render(&gpu, &mesh.scene(framing(&flat))).unwrap();
    assert_eq!((image.width(), image.height()), (96, 72));
    assert_eq!(image.pixels().len(), 4 * 96 * 72);
    // Pixel (x, y) is bytes 4 (y w + x) ..; none outside.
    let (x, y) = (48, 36);
    let at = 4 * (y * 96 + x) as usize;
    assert_eq!(image.pixel(x, y).unwrap().as_slice(), &image.pixels()[at..at + 4]);
    assert_ne!(image.pixel(x, y), image.pixel(0, 0), "the centre shows the cube, the corner the background");
    assert_eq!(image.pixel(96, 0), None);
    assert_eq!(image.pixel(0, 72), None);
    assert_eq!(format!("{image:?}"), "Image { width: 96, height: 72, .. }");

    #[cfg(feature = "png")]
    {
        // The PNG holds the colours (alpha dropped); the image crate's image holds the bytes.
        let png = image.encode_png().unwrap();
        let decoded = image::load_from_memory_with_format(&png, image::ImageFormat::Png).unwrap();
        assert_eq!(decoded.color(), image::ColorType::Rgb8);
        let rgb: Vec<u8> = image.pixels().chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        assert_eq!(decoded.into_rgb8().into_raw(), rgb);
        assert_eq!(image.clone().into_rgba_image().into_raw(), image.into_pixels());
    }
}

/// Textures through texture coordinates: a cube whose faces each map the unit square, with a
/// checker, shows dark squares (the plain surface hardly any dark pixels), more edges between
/// squares for a finer checker, the same image for the same texture; an image texture's colour
/// shows; bad coordinates, checkers and images are typed errors.
#[test]
fn textures_draw_through_the_texture_coordinates() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    let mut soup = shapes::cube();
    let square = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
    soup.channels.push(Channel::new("uv", 2, square.repeat(6), (0..24).map(|i| i % 4).collect()));
    let mesh = Mesh::build(soup).unwrap();
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default()).unwrap();
    let mut flat = FlatMesh::default();
    tess.tessellate_flat(&[8; 6], &mut flat).unwrap();
    assert_eq!(flat.texcoords.len(), 2 * (flat.vertices.len() / 6));
    let uploaded = GpuMesh::upload(&gpu, &flat).unwrap();
    let texcoords = GpuTexcoords::upload(&gpu, &flat.texcoords).unwrap();
    let renderer = Renderer::new(&gpu, &options()).unwrap();
    let surface = options().surface;
    let coarse = renderer.texture(&gpu, &TextureImage::checker(2, surface).unwrap()).unwrap();
    let fine = renderer.texture(&gpu, &TextureImage::checker(8, surface).unwrap()).unwrap();
    let plain = uploaded.scene(framing(&flat));
    let with = |image| Scene { texture: Some(Texture { texcoords: &texcoords.buffer, image }), ..plain };
    let dark = |image: &subdiv_gpu::Image| image.pixels().chunks_exact(4).filter(|p| p[0] < 90).count();
    let none = dark(&renderer.render(&gpu, &plain).unwrap());
    let two = renderer.render(&gpu, &with(&coarse)).unwrap();
    // The plain surface has few dark pixels (its least lit rims), the checker hundreds.
    assert!(dark(&two) > none + 200, "{} dark pixels against {none}", dark(&two));
    assert_eq!(renderer.render(&gpu, &with(&coarse)).unwrap(), two);
    // Edges between dark and light squares: more of them for the finer checker.
    let edges = |image: &subdiv_gpu::Image| {
        let p = image.pixels();
        (0..p.len() / 4 - 1).filter(|&k| (p[4 * k] < 90) != (p[4 * k + 4] < 90)).count()
    };
    assert!(edges(&renderer.render(&gpu, &with(&fine)).unwrap()) > edges(&two));
    // A pure red image: the surface turns red (green and blue only from the highlight).
    let red = renderer.texture(&gpu, &TextureImage::rgba(1, 1, vec![255, 0, 0, 255]).unwrap()).unwrap();
    let image = renderer.render(&gpu, &with(&red)).unwrap();
    let reddish = image.pixels().chunks_exact(4).filter(|p| p[0] > 120 && p[1] < 60 && p[2] < 60).count();
    assert!(reddish > 1000, "{reddish} red pixels");

    assert!(matches!(GpuTexcoords::upload(&gpu, &[0.0; 3]), Err(GpuError::Scene(_))));
    assert!(matches!(GpuTexcoords::upload(&gpu, &[0.0, f32::NAN]), Err(GpuError::Scene(m)) if m.contains("vertex 0")));
    let short = GpuTexcoords::upload(&gpu, &flat.texcoords[..4]).unwrap();
    match renderer.render(&gpu, &Scene { texture: Some(Texture { texcoords: &short.buffer, image: &coarse }), ..plain })
    {
        Err(GpuError::Scene(m)) => assert!(m.contains("texture coordinates"), "{m}"),
        other => panic!("expected a scene error, got {other:?}"),
    }
    for squares in [0, subdiv_gpu::MAX_CHECKER + 1] {
        assert!(matches!(TextureImage::checker(squares, surface), Err(GpuError::Scene(_))));
    }
    assert!(matches!(TextureImage::rgba(2, 2, vec![0; 15]), Err(GpuError::Scene(_))));
    assert!(matches!(TextureImage::rgba(0, 2, vec![]), Err(GpuError::ImageSize { .. })));
}
