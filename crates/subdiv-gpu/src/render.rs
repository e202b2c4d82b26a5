//! Offscreen rendering to an image: the surface shaded from its exact per-vertex normals, the
//! tessellation's wireframe, and the control cage.
//!
//! The renderer draws from **wgpu buffers**, so that a vertex buffer written on the device (the
//! GPU evaluation's output) is drawn without a copy. The layout is [`FlatMesh`]'s: per vertex
//! `px py pz nx ny nz` as `f32` ([`VERTEX_STRIDE`] bytes), triangles as `u32` indices,
//! counter-clockwise seen from the side the normals point to. [`GpuMesh::upload`] makes such
//! buffers from a CPU tessellation.
//!
//! Shading: Lambert and Blinn-Phong with a key and a fill light placed relative to the camera
//! (upper left and right), a light grey-blue material, both sides lit (the back of an open
//! surface too), depth-tested in `Depth32Float`, 4× MSAA. Wireframe lines are dark and pulled a
//! little towards the eye so that they win the depth test against their own triangles. Cage
//! lines are orange and depth-tested against the surface: visible parts solid, hidden parts
//! faint.

use std::sync::mpsc;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::scene::{Scene, View};
use crate::{Gpu, GpuError};

/// Bytes per vertex of a surface vertex buffer: `px py pz nx ny nz` as `f32`.
pub const VERTEX_STRIDE: u64 = 24;

/// Bytes per vertex of a cage position buffer: `x y z` as `f32`.
pub const CAGE_VERTEX_STRIDE: u64 = 12;

/// The bytes per texture coordinate of a [`Texture`]'s coordinates: `s t` as `f32`
/// ([`FlatMesh::texcoords`](subdiv_tess::FlatMesh::texcoords)).
pub const TEXCOORD_STRIDE: u64 = 8;

/// The largest image side [`Renderer::new`] takes (lower if the device's limit is lower).
pub const MAX_IMAGE_SIDE: u32 = 16384;

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// How lines are kept in front of the triangles they lie on: each line vertex moves this
/// fraction of its distance towards the eye.
const LINE_PULL: f32 = 2e-3;

/// What [`Renderer`] draws and how. Colours are sRGB bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels, `1..=`[`MAX_IMAGE_SIDE`]. Default: 800.
    pub width: u32,
    /// Image height in pixels, `1..=`[`MAX_IMAGE_SIDE`]. Default: 600.
    pub height: u32,
    /// Draw the scene's wireframe lines ([`Scene::wireframe`], which must then be given).
    /// Default: `false`.
    pub wireframe: bool,
    /// 4× multisampling (which WebGPU guarantees for the formats used). Default: `true`.
    pub msaa: bool,
    /// The background. Default: a very light grey, `[247, 247, 249]`.
    pub background: [u8; 3],
    /// The surface's colour. Default: a light grey-blue, `[176, 190, 212]`.
    pub surface: [u8; 3],
    /// The wireframe's colour and opacity (0–255). Default: `[28, 32, 44, 150]`.
    pub wire: [u8; 4],
    /// The cage's colour and opacity; hidden parts are drawn at a third of it. Default: orange,
    /// `[255, 128, 0, 255]`.
    pub cage: [u8; 4],
}

/// The most checker squares per unit of texture coordinates ([`TextureImage::checker`]).
pub const MAX_CHECKER: u32 = 4096;

/// An image to draw on the surface through its texture coordinates ([`Scene::texture`]):
/// RGBA8 sRGB pixels, rows from the top, sampled at `(s, 1 − t) · repeat` (texture coordinates
/// run up the image, as OBJ's `vt` and most atlases do) with the image repeated outside
/// `[0, 1]²`.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
    repeat: f32,
    nearest: bool,
}

impl TextureImage {
    /// An image of `width × height` RGBA8 sRGB pixels (rows from the top), filtered linearly.
    ///
    /// # Errors
    /// [`GpuError::ImageSize`] for a side of 0 or above [`MAX_IMAGE_SIDE`]; [`GpuError::Scene`]
    /// unless there are `4 · width · height` bytes.
    pub fn rgba(width: u32, height: u32, pixels: Vec<u8>) -> Result<Self, GpuError> {
        check_size(width, height, MAX_IMAGE_SIDE)?;
        if pixels.len() as u64 != 4 * u64::from(width) * u64::from(height) {
            return Err(GpuError::Scene(format!("texture: {} bytes for {width}×{height} RGBA pixels", pixels.len())));
        }
        Ok(Self { width, height, pixels, repeat: 1.0, nearest: false })
    }

    /// A checker of `squares` squares per unit of the texture coordinates (so a `[0, 1]²` atlas
    /// shows `squares²`), in `surface`'s colour and a dark shade of it: stretching, seams and
    /// flips of a mapping show.
    ///
    /// # Errors
    /// [`GpuError::Scene`] for `squares` outside `1..=`[`MAX_CHECKER`].
    pub fn checker(squares: u32, surface: [u8; 3]) -> Result<Self, GpuError> {
        if !(1..=MAX_CHECKER).contains(&squares) {
            return Err(GpuError::Scene(format!(
                "checker {squares}: squares per unit of texture coordinates are 1..={MAX_CHECKER}"
            )));
        }
        let light = [surface[0], surface[1], surface[2], 255];
        let dark = linear_rgb(surface).map(|c| srgb(0.22 * c));
        let dark = [dark[0], dark[1], dark[2], 255];
        let pixels = [light, dark, dark, light].concat();
        // Two squares per repetition of the 2 × 2 image, sampled nearest.
        Ok(Self { width: 2, height: 2, pixels, repeat: squares as f32 / 2.0, nearest: true })
    }
}

/// A [`TextureImage`] on the device, made by [`Renderer::texture`] for that renderer's
/// textured pipeline.
#[derive(Debug)]
pub struct GpuTexture {
    bind_group: wgpu::BindGroup,
    repeat: f32,
}

/// What [`Scene::texture`] draws: an image through the surface's texture coordinates.
#[derive(Clone, Copy, Debug)]
pub struct Texture<'a> {
    /// Per vertex its texture coordinates `s t` ([`TEXCOORD_STRIDE`] bytes; usage `VERTEX`,
    /// e.g. a [`GpuTexcoords`](crate::GpuTexcoords)).
    pub texcoords: &'a wgpu::Buffer,
    /// The image, on the device of the renderer that draws it.
    pub image: &'a GpuTexture,
}

impl RenderOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: Self = Self {
        width: 800,
        height: 600,
        wireframe: false,
        msaa: true,
        background: [247, 247, 249],
        surface: [176, 190, 212],
        wire: [28, 32, 44, 150],
        cage: [255, 128, 0, 255],
    };

    /// The options with another image size.
    #[must_use]
    pub fn with_size(self, width: u32, height: u32) -> Self {
        Self { width, height, ..self }
    }

    /// The options with the wireframe drawn or not.
    #[must_use]
    pub fn with_wireframe(self, wireframe: bool) -> Self {
        Self { wireframe, ..self }
    }

    /// Width over height.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height.max(1) as f32
    }

    /// Checks the image size against [`MAX_IMAGE_SIDE`] (no device needed).
    ///
    /// # Errors
    /// [`GpuError::ImageSize`] for a side of 0 or above [`MAX_IMAGE_SIDE`].
    pub fn check(&self) -> Result<(), GpuError> {
        check_size(self.width, self.height, MAX_IMAGE_SIDE)
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

fn check_size(width: u32, height: u32, max: u32) -> Result<(), GpuError> {
    if (1..=max).contains(&width) && (1..=max).contains(&height) {
        Ok(())
    } else {
        Err(GpuError::ImageSize { width, height, max })
    }
}

/// The uniform block of `shaders/render.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Uniforms {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    key: [f32; 4],
    fill: [f32; 4],
    surface: [f32; 4],
    wire: [f32; 4],
    cage: [f32; 4],
    specular: [f32; 4],
}

/// An sRGB byte as a linear intensity.
fn linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// A linear colour component as an sRGB byte.
fn srgb(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let encoded = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (encoded * 255.0).round() as u8
}

fn linear_rgb(c: [u8; 3]) -> [f32; 3] {
    c.map(linear)
}

impl Uniforms {
    /// The uniforms of one image; `repeat` is the texture's (1 without one).
    fn new(options: &RenderOptions, view: &View, frame: [Vec3; 3], repeat: f32) -> Self {
        let [right, up, back] = frame;
        // Lights fixed to the camera: the key from the upper left, the fill from the right.
        let key = (-0.45 * right + 0.6 * up + 0.65 * back).normalize();
        let fill = (0.7 * right - 0.1 * up + 0.7 * back).normalize();
        let [r, g, b] = linear_rgb(options.surface);
        let rgba = |c: [u8; 4]| {
            let [r, g, b] = linear_rgb([c[0], c[1], c[2]]);
            [r, g, b, f32::from(c[3]) / 255.0]
        };
        Self {
            view_proj: view.view_projection(options.aspect(), frame).to_cols_array_2d(),
            eye: view.eye.extend(LINE_PULL).to_array(),
            key: key.extend(0.78).to_array(),
            fill: fill.extend(0.3).to_array(),
            surface: [r, g, b, 0.16],
            wire: rgba(options.wire),
            cage: rgba(options.cage),
            specular: [0.22, 48.0, repeat, 0.0],
        }
    }
}

/// The bytes per row of a texture-to-buffer copy of `width` RGBA8 pixels: padded to
/// [`wgpu::COPY_BYTES_PER_ROW_ALIGNMENT`].
pub(crate) fn padded_bytes_per_row(width: u32) -> u32 {
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    (4 * width).div_ceil(align) * align
}

/// The `height` rows of `4 * width` bytes of a buffer with `padded` bytes per row.
pub(crate) fn unpad(data: &[u8], width: u32, height: u32, padded: u32) -> Vec<u8> {
    let row = 4 * width as usize;
    data.chunks(padded as usize).take(height as usize).flat_map(|r| &r[..row]).copied().collect()
}

/// Turns wgpu's captured errors into [`GpuError::Wgpu`].
pub(crate) struct ErrorScopes {
    // Pushed after `validation`, so declared first: fields drop in order, and scopes must be
    // popped in reverse order of their pushes (an early return drops both).
    memory: wgpu::ErrorScopeGuard,
    validation: wgpu::ErrorScopeGuard,
    during: &'static str,
}

impl ErrorScopes {
    pub(crate) fn push(device: &wgpu::Device, during: &'static str) -> Self {
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        Self { validation, memory, during }
    }

    pub(crate) fn pop(self) -> Result<(), GpuError> {
        // Reverse order of the pushes.
        let memory = pollster::block_on(self.memory.pop());
        let validation = pollster::block_on(self.validation.pop());
        match memory.or(validation) {
            Some(e) => Err(GpuError::Wgpu { during: self.during, message: e.to_string() }),
            None => Ok(()),
        }
    }
}

/// Renders [`Scene`]s into images of one size: the pipelines, targets and readback buffer are
/// made once, and each [`render`](Self::render) writes the camera and draws.
///
/// A CPU tessellation drawn in two calls (`no_run`: it needs an adapter):
///
/// ```no_run
/// use subdiv_gpu::{Gpu, GpuMesh, GpuOptions, RenderOptions, Renderer, View};
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::Builtin;
/// use subdiv_tess::{DualOptions, DualTessellator, FlatMesh};
///
/// let mesh = Mesh::build(shapes::default_model())?;
/// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default())?;
/// let mut flat = FlatMesh::default();
/// tess.tessellate_flat(&vec![8; mesh.face_count()], &mut flat)?;
///
/// let gpu = Gpu::new(&GpuOptions::default())?;
/// let options = RenderOptions::default().with_size(640, 480).with_wireframe(true);
/// let renderer = Renderer::new(&gpu, &options)?;
/// let surface = GpuMesh::upload_with_edges(&gpu, &flat)?;
/// let [lo, hi] = subdiv_gpu::bounds(&flat.vertices).expect("a surface");
/// let image = renderer.render(&gpu, &surface.scene(View::framing(lo, hi, options.aspect())))?;
/// assert_eq!(image.dimensions(), (640, 480));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct Renderer {
    options: RenderOptions,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    surface: wgpu::RenderPipeline,
    /// The surface with a texture (a second vertex buffer of texture coordinates, the image in
    /// bind group 1).
    textured: wgpu::RenderPipeline,
    texture_layout: wgpu::BindGroupLayout,
    wire: wgpu::RenderPipeline,
    cage: wgpu::RenderPipeline,
    cage_hidden: wgpu::RenderPipeline,
    /// The multisampled colour target (`None` without MSAA).
    multisampled: Option<wgpu::TextureView>,
    /// The single-sample colour target that is read back (the resolve target with MSAA).
    resolved: wgpu::Texture,
    resolved_view: wgpu::TextureView,
    depth: wgpu::TextureView,
    readback: wgpu::Buffer,
}

impl Renderer {
    /// Makes the pipelines and targets for `options`.
    ///
    /// # Errors
    /// [`GpuError::ImageSize`] for a side of 0 or above [`MAX_IMAGE_SIDE`] (or the device's
    /// texture limit); [`GpuError::Wgpu`] if the device refuses a resource.
    pub fn new(gpu: &Gpu, options: &RenderOptions) -> Result<Self, GpuError> {
        check_size(options.width, options.height, MAX_IMAGE_SIDE.min(gpu.limits().max_texture_dimension_2d))?;
        let device = &gpu.device;
        let scopes = ErrorScopes::push(device, "creating the renderer");
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("render.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../shaders/render.wgsl").into()),
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("render uniforms"),
            size: std::mem::size_of::<Uniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("render uniforms"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("render uniforms"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("render"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let texture_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("render texture"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let textured_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("render textured"),
            bind_group_layouts: &[Some(&layout), Some(&texture_layout)],
            immediate_size: 0,
        });
        let samples = if options.msaa { 4 } else { 1 };
        let pipelines = Pipelines { device, shader: &shader, layout: &pipeline_layout, samples };
        let surface = pipelines.surface(false);
        let textured = Pipelines { layout: &textured_layout, ..pipelines }.surface(true);
        let wire = pipelines.lines("wireframe", VERTEX_STRIDE, "fs_wire", wgpu::CompareFunction::LessEqual);
        let cage = pipelines.lines("cage", CAGE_VERTEX_STRIDE, "fs_cage", wgpu::CompareFunction::LessEqual);
        let cage_hidden =
            pipelines.lines("hidden cage", CAGE_VERTEX_STRIDE, "fs_cage_hidden", wgpu::CompareFunction::Greater);

        let size = wgpu::Extent3d { width: options.width, height: options.height, depth_or_array_layers: 1 };
        let texture = |label, format, sample_count, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let multisampled = options.msaa.then(|| {
            texture("colour (multisampled)", COLOR_FORMAT, samples, attachment)
                .create_view(&wgpu::TextureViewDescriptor::default())
        });
        let resolved = texture("colour", COLOR_FORMAT, 1, attachment | wgpu::TextureUsages::COPY_SRC);
        let resolved_view = resolved.create_view(&wgpu::TextureViewDescriptor::default());
        let depth =
            texture("depth", DEPTH_FORMAT, samples, attachment).create_view(&wgpu::TextureViewDescriptor::default());
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(padded_bytes_per_row(options.width)) * u64::from(options.height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        scopes.pop()?;
        Ok(Self {
            options: options.clone(),
            uniforms,
            bind_group,
            surface,
            textured,
            texture_layout,
            wire,
            cage,
            cage_hidden,
            multisampled,
            resolved,
            resolved_view,
            depth,
            readback,
        })
    }

    /// The options this renderer was made for.
    pub fn options(&self) -> &RenderOptions {
        &self.options
    }

    /// Puts `image` on the device for this renderer's textured surface ([`Scene::texture`]).
    ///
    /// # Errors
    /// [`GpuError::ImageSize`] for an image larger than the device's textures;
    /// [`GpuError::Wgpu`] if the device refuses it.
    pub fn texture(&self, gpu: &Gpu, image: &TextureImage) -> Result<GpuTexture, GpuError> {
        check_size(image.width, image.height, MAX_IMAGE_SIDE.min(gpu.limits().max_texture_dimension_2d))?;
        let device = &gpu.device;
        let scopes = ErrorScopes::push(device, "uploading a texture");
        let size = wgpu::Extent3d { width: image.width, height: image.height, depth_or_array_layers: 1 };
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("surface texture"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &image.pixels,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * image.width), rows_per_image: None },
            size,
        );
        let filter = if image.nearest { wgpu::FilterMode::Nearest } else { wgpu::FilterMode::Linear };
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("surface texture"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: filter,
            min_filter: filter,
            ..wgpu::SamplerDescriptor::default()
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("surface texture"),
            layout: &self.texture_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) },
            ],
        });
        scopes.pop()?;
        Ok(GpuTexture { bind_group, repeat: image.repeat })
    }

    /// Draws `scene` and reads the image back (waiting for the device).
    ///
    /// # Errors
    /// [`GpuError::Scene`] when a buffer is smaller than its count says, an index count is not a
    /// multiple of 3 (triangles) or 2 (lines), the wireframe is asked for without lines, or the
    /// view is degenerate; [`GpuError::Wgpu`] for an error wgpu reports (e.g. a buffer without
    /// the `VERTEX` or `INDEX` usage); [`GpuError::Readback`] if mapping the image fails.
    pub fn render(&self, gpu: &Gpu, scene: &Scene<'_>) -> Result<Image, GpuError> {
        let options = &self.options;
        scene.check(options)?;
        let frame = scene.view.frame()?;
        let (device, queue) = (&gpu.device, &gpu.queue);
        let scopes = ErrorScopes::push(device, "rendering");
        let repeat = scene.texture.map_or(1.0, |t| t.image.repeat);
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&Uniforms::new(options, &scene.view, frame, repeat)));
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("render") });
        {
            let [r, g, b] = linear_rgb(options.background).map(f64::from);
            let (view, resolve_target) = match &self.multisampled {
                Some(multisampled) => (multisampled, Some(&self.resolved_view)),
                None => (&self.resolved_view, None),
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("render"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a: 1.0 }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.set_vertex_buffer(0, scene.vertices.slice(..));
            match scene.texture {
                Some(texture) => {
                    pass.set_pipeline(&self.textured);
                    pass.set_bind_group(1, &texture.image.bind_group, &[]);
                    pass.set_vertex_buffer(1, texture.texcoords.slice(..));
                }
                None => pass.set_pipeline(&self.surface),
            }
            pass.set_index_buffer(scene.triangles.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..scene.index_count, 0, 0..1);
            if let (Some(wire), true) = (&scene.wireframe, options.wireframe) {
                pass.set_pipeline(&self.wire);
                pass.set_index_buffer(wire.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..wire.index_count, 0, 0..1);
            }
            if let Some(cage) = &scene.cage {
                pass.set_vertex_buffer(0, cage.positions.slice(..));
                pass.set_index_buffer(cage.lines.indices.slice(..), wgpu::IndexFormat::Uint32);
                for pipeline in [&self.cage_hidden, &self.cage] {
                    pass.set_pipeline(pipeline);
                    pass.draw_indexed(0..cage.lines.index_count, 0, 0..1);
                }
            }
        }
        let padded = padded_bytes_per_row(options.width);
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.resolved,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(options.height),
                },
            },
            wgpu::Extent3d { width: options.width, height: options.height, depth_or_array_layers: 1 },
        );
        queue.submit([encoder.finish()]);
        let (sender, receiver) = mpsc::channel();
        self.readback.map_async(wgpu::MapMode::Read, .., move |result| {
            // The receiver waits below; a failed send only means it is gone.
            let _ = sender.send(result);
        });
        let polled = device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::Readback(e.to_string()));
        // Unmapped on every path (even when wgpu reported an error), so that the next render can
        // map it again.
        let pixels = match receiver.try_recv() {
            Ok(Ok(())) => {
                let pixels =
                    self.readback.get_mapped_range(..).map(|data| unpad(&data, options.width, options.height, padded));
                self.readback.unmap();
                pixels.map_err(|e| GpuError::Readback(e.to_string()))
            }
            Ok(Err(e)) => Err(GpuError::Readback(e.to_string())),
            Err(e) => Err(GpuError::Readback(format!("the map callback did not run: {e}"))),
        };
        // wgpu's own error first: it explains a failed map.
        scopes.pop()?;
        polled?;
        let pixels = pixels?;
        if pixels.len() != 4 * options.width as usize * options.height as usize {
            return Err(GpuError::Readback("the image has the wrong length; please report".to_string()));
        }
        Ok(Image { width: options.width, height: options.height, pixels })
    }
}

/// An image read back by [`Renderer::render`]: `width × height` pixels of 4 bytes (RGBA, 8 bits
/// each, sRGB-encoded), rows from the top, no padding. The renderer draws over an opaque
/// background, so the colour channels are final; alpha is what blending left there.
///
/// With the `png` feature, [`encode_png`](Self::encode_png) and
/// [`into_rgba_image`](Self::into_rgba_image) hand it to the `image` crate.
#[derive(Clone, PartialEq, Eq)]
pub struct Image {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
}

impl Image {
    /// The width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// The height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// `(width, height)`.
    pub fn dimensions(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The pixels: `4 · width · height` bytes, RGBA per pixel, rows from the top.
    pub fn pixels(&self) -> &[u8] {
        &self.pixels
    }

    /// The pixels (as [`pixels`](Self::pixels)), without a copy.
    pub fn into_pixels(self) -> Vec<u8> {
        self.pixels
    }

    /// The pixel at column `x` and row `y` (from the top) as RGBA, `None` outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let at = 4 * (y as usize * self.width as usize + x as usize);
        let p = &self.pixels[at..at + 4];
        Some([p[0], p[1], p[2], p[3]])
    }

    /// The image as the `image` crate's RGBA image, without a copy.
    #[cfg(feature = "png")]
    pub fn into_rgba_image(self) -> image::RgbaImage {
        image::RgbaImage::from_raw(self.width, self.height, self.pixels)
            .expect("an Image holds 4 bytes per pixel (made only by the renderer)")
    }

    /// The image encoded as an 8-bit RGB PNG, in memory (alpha is dropped: the colours are
    /// already composed over the opaque background). Writing it to a file is the caller's.
    ///
    /// # Errors
    /// The encoder's error (none is expected for an image in memory).
    #[cfg(feature = "png")]
    pub fn encode_png(&self) -> image::ImageResult<Vec<u8>> {
        let rgb: Vec<u8> = self.pixels.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        let mut png = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut png),
            &rgb,
            self.width,
            self.height,
            image::ExtendedColorType::Rgb8,
        )?;
        Ok(png)
    }
}

impl std::fmt::Debug for Image {
    /// The size only (the pixels would fill a screen).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Image").field("width", &self.width).field("height", &self.height).finish_non_exhaustive()
    }
}

/// What the pipelines share.
struct Pipelines<'a> {
    device: &'a wgpu::Device,
    shader: &'a wgpu::ShaderModule,
    layout: &'a wgpu::PipelineLayout,
    samples: u32,
}

impl Pipelines<'_> {
    fn pipeline(
        &self,
        label: &str,
        vertex: (&str, &[Option<wgpu::VertexBufferLayout<'_>>]),
        fragment: (&str, Option<wgpu::BlendState>),
        topology: wgpu::PrimitiveTopology,
        depth: (bool, wgpu::CompareFunction),
    ) -> wgpu::RenderPipeline {
        self.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(self.layout),
            vertex: wgpu::VertexState {
                module: self.shader,
                entry_point: Some(vertex.0),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                buffers: vertex.1,
            },
            primitive: wgpu::PrimitiveState {
                topology,
                front_face: wgpu::FrontFace::Ccw,
                cull_mode: None,
                ..wgpu::PrimitiveState::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(depth.0),
                depth_compare: Some(depth.1),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState { count: self.samples, ..wgpu::MultisampleState::default() },
            fragment: Some(wgpu::FragmentState {
                module: self.shader,
                entry_point: Some(fragment.0),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOR_FORMAT,
                    blend: fragment.1,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// The shaded surface, `textured` through a second buffer of texture coordinates.
    fn surface(&self, textured: bool) -> wgpu::RenderPipeline {
        const ATTRIBUTES: [wgpu::VertexAttribute; 2] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
        const TEXCOORDS: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![2 => Float32x2];
        let layout = wgpu::VertexBufferLayout {
            array_stride: VERTEX_STRIDE,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &ATTRIBUTES,
        };
        let texcoords = wgpu::VertexBufferLayout {
            array_stride: TEXCOORD_STRIDE,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &TEXCOORDS,
        };
        let (label, vertex, fragment) = if textured {
            ("textured surface", "vs_textured", "fs_textured")
        } else {
            ("surface", "vs_surface", "fs_surface")
        };
        let buffers = [Some(layout), textured.then_some(texcoords)];
        self.pipeline(
            label,
            (vertex, &buffers[..if textured { 2 } else { 1 }]),
            (fragment, None),
            wgpu::PrimitiveTopology::TriangleList,
            (true, wgpu::CompareFunction::Less),
        )
    }

    /// Lines over positions at the start of each `stride`-byte vertex, blended, depth-tested
    /// with `compare` without writing depth.
    fn lines(&self, label: &str, stride: u64, fragment: &str, compare: wgpu::CompareFunction) -> wgpu::RenderPipeline {
        const ATTRIBUTES: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];
        let layout = wgpu::VertexBufferLayout {
            array_stride: stride,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &ATTRIBUTES,
        };
        self.pipeline(
            label,
            ("vs_line", &[Some(layout)]),
            (fragment, Some(wgpu::BlendState::ALPHA_BLENDING)),
            wgpu::PrimitiveTopology::LineList,
            (false, compare),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{bounds, unique_edges};

    #[test]
    fn unique_edges_lists_each_edge_once_and_all_of_them() {
        // Two triangles sharing the edge 1-2, and a third sharing 2-3 with the second.
        let triangles = [0, 1, 2, 2, 1, 3, 3, 4, 2];
        let edges = unique_edges(&triangles);
        let pairs: Vec<[u32; 2]> = edges.chunks_exact(2).map(|e| [e[0], e[1]]).collect();
        assert_eq!(pairs, [[0, 1], [0, 2], [1, 2], [1, 3], [2, 3], [2, 4], [3, 4]]);
        // Complete: every triangle side is there.
        for t in triangles.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                assert!(pairs.contains(&[a.min(b), a.max(b)]), "{a}-{b}");
            }
        }
        assert!(unique_edges(&[]).is_empty());
    }

    #[test]
    fn framing_contains_the_box() {
        for (lo, hi, aspect) in [
            (Vec3::new(-1.0, -1.0, -1.0), Vec3::ONE, 4.0 / 3.0),
            (Vec3::new(10.0, 0.0, -3.0), Vec3::new(12.0, 7.0, -2.5), 0.5),
            (Vec3::new(0.0, 0.0, 0.0), Vec3::new(100.0, 1.0, 1.0), 2.0),
        ] {
            let view = View::framing(lo, hi, aspect);
            let clip = view.view_projection(aspect, view.frame().unwrap());
            for corner in 0..8 {
                let p = Vec3::new(
                    if corner & 1 == 0 { lo.x } else { hi.x },
                    if corner & 2 == 0 { lo.y } else { hi.y },
                    if corner & 4 == 0 { lo.z } else { hi.z },
                );
                let q = clip.project_point3(p);
                assert!(
                    q.x.abs() <= View::FRAMING_FILL + 1e-4 && q.y.abs() <= View::FRAMING_FILL + 1e-4,
                    "{p} at {q} for {lo}..{hi}"
                );
                assert!(q.z > 0.0 && q.z < 1.0, "{p} at depth {}", q.z);
            }
            assert!(view.frame().is_ok());
            // The same camera for the rate policy.
            assert_eq!(view.camera().eye, view.eye.as_dvec3());
        }
        // Degenerate boxes still give a usable camera.
        for (lo, hi) in [(Vec3::ONE, Vec3::ZERO), (Vec3::ONE, Vec3::ONE), (Vec3::NAN, Vec3::ONE)] {
            assert!(View::framing(lo, hi, 1.0).frame().is_ok());
        }
    }

    #[test]
    fn rows_are_padded_and_unpadded() {
        assert_eq!(padded_bytes_per_row(1), 256);
        assert_eq!(padded_bytes_per_row(64), 256);
        assert_eq!(padded_bytes_per_row(65), 512);
        let (width, height) = (3, 2);
        let padded = padded_bytes_per_row(width);
        let mut data = vec![0xee; (padded * height) as usize];
        for y in 0..height as usize {
            for x in 0..4 * width as usize {
                data[y * padded as usize + x] = (10 * y + x) as u8;
            }
        }
        let pixels = unpad(&data, width, height, padded);
        assert_eq!(pixels.len(), (4 * width * height) as usize);
        assert_eq!(&pixels[..12], &(0..12).collect::<Vec<u8>>()[..]);
        assert_eq!(&pixels[12..], &(10..22).collect::<Vec<u8>>()[..]);
    }

    #[test]
    fn bounds_and_sizes() {
        assert_eq!(bounds(&[]), None);
        let b = bounds(&[1.0, 2.0, 3.0, 0.0, 0.0, 1.0, -1.0, 5.0, 0.0, 0.0, 1.0, 0.0]).unwrap();
        assert_eq!(b, [Vec3::new(-1.0, 2.0, 0.0), Vec3::new(1.0, 5.0, 3.0)]);
        assert!(RenderOptions::default().check().is_ok());
        for (w, h) in [(0, 10), (10, 0), (MAX_IMAGE_SIDE + 1, 1)] {
            assert!(matches!(RenderOptions::default().with_size(w, h).check(), Err(GpuError::ImageSize { .. })));
        }
    }

    #[test]
    fn srgb_to_linear_ends() {
        assert_eq!(linear(0), 0.0);
        assert!((linear(255) - 1.0).abs() < 1e-6);
        assert!((linear(188) - 0.5).abs() < 0.01);
    }
}
