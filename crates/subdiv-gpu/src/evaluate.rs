//! GPU evaluation of a tessellation: the buffers of paper 003 §7.2 and one compute pass that
//! fills the vertex buffer a render pass draws from.
//!
//! The CPU tessellator hands over an [`EvaluationPlan`] (every output vertex as a fixed
//! combination of the cage's points, through the refined levels some patches need) and the
//! triangles. They are uploaded once per rate configuration:
//! - the **control points** buffer (rewritten every frame by
//!   [`GpuTessellation::write_control_points`] before the evaluation is
//!   [recorded](GpuTessellation::record) into the caller's encoder, or by
//!   [`GpuTessellation::update_control_points`], which submits both); every combination is
//!   taken over the cage's own points ([`EvaluationPlan::over_cage`]: the refined levels some
//!   patches live on are composed into the weights in f64), so one pass evaluates everything,
//!   and f32 refined points, whose error of the model's size × 2^-24 small patches' tangents
//!   would magnify, never exist;
//! - per range of output vertices, the **entries** (a vertex's kind and record), the records
//!   (bicubic faces' cell grids, bicubic points, exact-stencil points), the **patches** (their
//!   point indices) and the **combinations** (stencil weights), each a storage buffer of at most
//!   [`GpuEvalOptions::max_buffer_bytes`] (128 MiB by default): a range ends where one of them
//!   would outgrow it, and each range is one dispatch of `evaluate.wgsl`;
//! - the **vertex buffer** (interleaved `px py pz nx ny nz`, f32, the layout of
//!   [`FlatMesh`](subdiv_tess::FlatMesh)) and the **index buffer** (the CPU tessellator's
//!   triangles).
//!
//! Positions are f32 on the GPU; the control points are stored relative to the cage's centre
//! and each combination is summed relative to its first point, so the values agree with the
//! CPU's f64 ones to a few f32 roundings of the model's size (measured: positions within
//! 6e-8 of the bounding-box diagonal, normals within 1e-6 on the test meshes).

use glam::{DVec3, Vec3};
use hashbrown::HashMap;
use subdiv_tess::TessError;
use subdiv_tess::dual::{EvaluationPlan, PlanEntry, check_cage};
use wgpu::util::DeviceExt;

use crate::{Gpu, GpuError};

// The entries' encoding in `evaluate.wgsl`: `kind << KIND_SHIFT | record`, the record numbered
// within its range.
const KIND_SHIFT: u32 = 30;
const KIND_BLOCK: u32 = 0;
const KIND_BICUBIC: u32 = 1;
const KIND_GENERAL: u32 = 2;

/// Invocations per workgroup of both shaders.
const WORKGROUP: u32 = 64;
/// Bytes per output vertex: position and normal, f32.
const VERTEX_BYTES: u64 = 24;

/// Options of [`GpuTessellation`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuEvalOptions {
    /// The largest storage buffer made for the stencil data (entries, records, patches,
    /// weights, refinement rows); larger data is split over several buffers and dispatches.
    /// Clamped to the device's binding limit. Default: 128 MiB.
    pub max_buffer_bytes: u64,
    /// Also upload the wireframe's line list (each triangle edge once, built on the CPU), which
    /// [`GpuTessellation::scene`] then draws with [`RenderOptions::wireframe`](crate::RenderOptions::wireframe).
    /// Default: `false`.
    pub edges: bool,
}

impl Default for GpuEvalOptions {
    fn default() -> Self {
        Self { max_buffer_bytes: 128 << 20, edges: false }
    }
}

/// Per dispatch: where it writes and how the invocations are laid out (`Params` in the
/// shaders).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    first: u32,
    count: u32,
    stride: u32,
    pad: u32,
    origin: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuBlock {
    base: u32,
    rate: u32,
    points: u32,
    pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuBicubic {
    points: u32,
    s: f32,
    t: f32,
    pad: u32,
    ju: [f32; 2],
    jv: [f32; 2],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuGeneral {
    points: u32,
    len: u32,
    weights: u32,
    pad: u32,
    ju: [f32; 2],
    jv: [f32; 2],
}

/// One dispatch: its bind group and its workgroups along x and y (the shader's `stride` is
/// `x · WORKGROUP` invocations per row).
#[derive(Debug)]
struct Dispatch {
    bind_group: wgpu::BindGroup,
    groups: [u32; 2],
}

/// One range of output vertices with its own records, re-indexed.
#[derive(Debug, Default)]
struct Range {
    first: u32,
    count: u32,
    entries: Vec<u32>,
    blocks: Vec<GpuBlock>,
    bicubic: Vec<GpuBicubic>,
    general: Vec<GpuGeneral>,
    patches: Vec<u32>,
    weights: Vec<f32>,
}

impl Range {
    /// The largest of its buffers, in bytes.
    fn largest(&self) -> u64 {
        [
            4 * self.entries.len(),
            16 * self.blocks.len(),
            32 * self.bicubic.len(),
            32 * self.general.len(),
            4 * self.patches.len(),
            4 * self.weights.len(),
        ]
        .into_iter()
        .max()
        .unwrap_or(0) as u64
    }
}

/// A tessellation evaluated on the GPU: the plan's buffers, the vertex and index buffers, and
/// the dispatches that refill the vertex buffer from the control points.
///
/// ```no_run
/// use subdiv_gpu::{Gpu, GpuOptions, GpuTessellation, GpuEvalOptions};
/// use subdiv_mesh::{shapes, Mesh};
/// use subdiv_schemes::Builtin;
/// use subdiv_tess::{DualOptions, DualTessellator, FlatMesh};
///
/// let gpu = Gpu::new(&GpuOptions::default())?;
/// let mesh = Mesh::build(shapes::default_model())?;
/// let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default())?;
/// let mut flat = FlatMesh::default();
/// tess.tessellate_flat(&vec![8; mesh.face_count()], &mut flat)?;
/// let mut on_gpu =
///     GpuTessellation::new(&gpu, &tess.evaluation_plan(), &flat.indices, mesh.positions(), &GpuEvalOptions::default())?;
/// // Every frame: a moved cage, one dispatch per vertex range; the vertex buffer is ready to draw.
/// let cage: Vec<glam::Vec3> = mesh.positions().iter().map(|p| p.as_vec3() * 1.1).collect();
/// on_gpu.update_control_points(&gpu, &cage)?;
/// let vertices = on_gpu.read_vertices(&gpu)?; // px py pz nx ny nz per vertex
/// assert_eq!(vertices.len(), flat.vertices.len());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct GpuTessellation {
    cage_len: usize,
    origin: DVec3,
    points: wgpu::Buffer,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    vertex_count: u32,
    index_count: u32,
    /// The wireframe's line list and its index count, on request.
    edges: Option<(wgpu::Buffer, u32)>,
    pipeline: wgpu::ComputePipeline,
    dispatches: Vec<Dispatch>,
}

impl GpuTessellation {
    /// Uploads `plan` (from [`DualTessellator::evaluation_plan`](subdiv_tess::DualTessellator::evaluation_plan))
    /// and `indices` (its flat triangles, three per triangle: [`FlatMesh::indices`](subdiv_tess::FlatMesh::indices)
    /// or [`TessMesh::flat_indices`](subdiv_tess::TessMesh::flat_indices), which index a crease
    /// vertex's copy per normal), and evaluates every flat vertex on `cage`.
    ///
    /// # Errors
    /// [`GpuError::Tessellation`] for a cage that does not fit the plan, or for a plan that
    /// breaks a rule of [`EvaluationPlan::validate`](subdiv_tess::EvaluationPlan::validate)
    /// (`TessError::Plan`), [`GpuError::TooLarge`] when the points or the vertex buffer exceed what the device
    /// can bind or allocate, [`GpuError::Indices`] for an index past the vertices,
    /// [`GpuError::Wgpu`] when the device refuses a buffer or the shader.
    pub fn new(
        gpu: &Gpu,
        plan: &EvaluationPlan,
        indices: &[u32],
        cage: &[DVec3],
        options: &GpuEvalOptions,
    ) -> Result<Self, GpuError> {
        // A plan from elsewhere may break its rules: checked before anything indexes it.
        plan.validate().map_err(TessError::from)?;
        check_cage(plan.cage_len(), cage)?;
        // Every combination over the cage itself (composed in f64): f32 refined points would
        // carry errors of the model's size that small patches' tangents magnify.
        let plan = &*plan.over_cage();
        let vertex_count = plan.vertex_count();
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= vertex_count) {
            return Err(GpuError::Indices { index: bad, vertices: vertex_count });
        }
        let limits = gpu.limits();
        let binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let budget = options.max_buffer_bytes.min(binding).max(1 << 12);
        let points_bytes = 16 * plan.point_count() as u64;
        if points_bytes > binding {
            return Err(GpuError::TooLarge { what: "control points", bytes: points_bytes, limit: binding });
        }
        let vertex_bytes = VERTEX_BYTES * vertex_count as u64;
        if vertex_bytes > limits.max_buffer_size {
            return Err(GpuError::TooLarge {
                what: "vertex buffer",
                bytes: vertex_bytes,
                limit: limits.max_buffer_size,
            });
        }
        let device = &gpu.device;
        let scopes = crate::render::ErrorScopes::push(device, "uploading a tessellation");
        let (min, max) =
            cage.iter().fold((DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)), |(a, b), p| (a.min(*p), b.max(*p)));
        let origin = if cage.is_empty() { DVec3::ZERO } else { 0.5 * (min + max) };

        let storage = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
            // A binding may not be empty: one zero word stands for an empty array.
            let contents: &[u8] = if bytes.is_empty() { &[0; 32] } else { bytes };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let points = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("subdiv control points"),
            size: points_bytes.max(16),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let vertices = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("subdiv vertices"),
            size: vertex_bytes.max(VERTEX_BYTES),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let index_buffer = storage(
            "subdiv indices",
            bytemuck::cast_slice(indices),
            wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
        );

        let evaluate_pipeline = pipeline(device, "evaluate", include_str!("../shaders/evaluate.wgsl"));
        let origin32 = origin.as_vec3().extend(0.0).to_array();
        let max_groups = limits.max_compute_workgroups_per_dimension;
        // Workgroups in rows of at most the device's limit along x.
        let layout = |count: u32| {
            let groups = count.div_ceil(WORKGROUP).max(1);
            let x = groups.min(max_groups);
            [x, groups.div_ceil(x)]
        };
        let uniform = |p: &Params| storage("subdiv params", bytemuck::bytes_of(p), wgpu::BufferUsages::UNIFORM);

        // Evaluation: ranges of vertices whose buffers fit the budget, starting where the
        // vertex buffer may be bound (offsets aligned for storage bindings).
        let align = u64::from(limits.min_storage_buffer_offset_alignment);
        let step = (lcm(VERTEX_BYTES, align) / VERTEX_BYTES) as usize;
        let mut evaluate = Vec::new();
        for range in split(plan, budget, step) {
            let groups = layout(range.count);
            let p = Params {
                first: range.first,
                count: range.count,
                stride: groups[0] * WORKGROUP,
                pad: 0,
                origin: origin32,
            };
            let buffers = [
                storage("subdiv entries", bytemuck::cast_slice(&range.entries), wgpu::BufferUsages::STORAGE),
                storage("subdiv blocks", bytemuck::cast_slice(&range.blocks), wgpu::BufferUsages::STORAGE),
                storage("subdiv bicubic points", bytemuck::cast_slice(&range.bicubic), wgpu::BufferUsages::STORAGE),
                storage("subdiv stencil points", bytemuck::cast_slice(&range.general), wgpu::BufferUsages::STORAGE),
                storage("subdiv patches", bytemuck::cast_slice(&range.patches), wgpu::BufferUsages::STORAGE),
                storage("subdiv combinations", bytemuck::cast_slice(&range.weights), wgpu::BufferUsages::STORAGE),
                uniform(&p),
            ];
            let out = wgpu::BufferBinding {
                buffer: &vertices,
                offset: VERTEX_BYTES * u64::from(range.first),
                size: wgpu::BufferSize::new(VERTEX_BYTES * u64::from(range.count)),
            };
            let mut entries = vec![wgpu::BindGroupEntry { binding: 0, resource: points.as_entire_binding() }];
            entries.extend(
                buffers[..6]
                    .iter()
                    .enumerate()
                    .map(|(k, b)| wgpu::BindGroupEntry { binding: k as u32 + 1, resource: b.as_entire_binding() }),
            );
            entries.push(wgpu::BindGroupEntry { binding: 7, resource: wgpu::BindingResource::Buffer(out) });
            entries.push(wgpu::BindGroupEntry { binding: 8, resource: buffers[6].as_entire_binding() });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("subdiv evaluate"),
                layout: &evaluate_pipeline.get_bind_group_layout(0),
                entries: &entries,
            });
            evaluate.push(Dispatch { bind_group, groups });
        }

        let edges = options.edges.then(|| {
            let lines = crate::unique_edges(indices);
            let buffer = storage("subdiv edges", bytemuck::cast_slice(&lines), wgpu::BufferUsages::INDEX);
            (buffer, lines.len() as u32)
        });
        let this = Self {
            edges,
            cage_len: plan.cage_len(),
            origin,
            points,
            vertices,
            indices: index_buffer,
            vertex_count: vertex_count as u32,
            index_count: indices.len() as u32,
            pipeline: evaluate_pipeline,
            dispatches: evaluate,
        };
        this.write_cage(&gpu.queue, cage);
        this.submit(gpu);
        scopes.pop()?;
        Ok(this)
    }

    /// The animation path: a new cage (one finite position per control point), evaluated on
    /// the GPU and submitted; the vertex buffer holds the new surface when the queue gets to
    /// it. Indices and stencil data stay. [`write_control_points`](Self::write_control_points)
    /// and [`record`](Self::record) do the same in the caller's submission.
    ///
    /// # Errors
    /// [`GpuError::Tessellation`] with [`TessError::CageLength`](subdiv_tess::TessError::CageLength)
    /// or [`TessError::CagePosition`](subdiv_tess::TessError::CagePosition).
    pub fn update_control_points(&self, gpu: &Gpu, cage: &[Vec3]) -> Result<(), GpuError> {
        self.write_control_points(&gpu.queue, cage)?;
        self.submit(gpu);
        Ok(())
    }

    /// As [`update_control_points`](Self::update_control_points), from f64 positions.
    ///
    /// # Errors
    /// As [`update_control_points`](Self::update_control_points).
    pub fn update_control_points_f64(&self, gpu: &Gpu, cage: &[DVec3]) -> Result<(), GpuError> {
        self.write_control_points_f64(&gpu.queue, cage)?;
        self.submit(gpu);
        Ok(())
    }

    /// Checks a new cage and writes it into the control-point buffer with
    /// [`Queue::write_buffer`](wgpu::Queue::write_buffer): nothing is evaluated until
    /// [`record`](Self::record)ed commands run. wgpu applies the write at the queue's next
    /// submission, before that submission's command buffers, so the order is: write, record
    /// into an encoder, submit. Two writes before one submission: the last one wins.
    ///
    /// # Errors
    /// As [`update_control_points`](Self::update_control_points); nothing is written then.
    pub fn write_control_points(&self, queue: &wgpu::Queue, cage: &[Vec3]) -> Result<(), GpuError> {
        let wide: Vec<DVec3> = cage.iter().map(|p| p.as_dvec3()).collect();
        self.write_control_points_f64(queue, &wide)
    }

    /// As [`write_control_points`](Self::write_control_points), from f64 positions.
    ///
    /// # Errors
    /// As [`update_control_points`](Self::update_control_points); nothing is written then.
    pub fn write_control_points_f64(&self, queue: &wgpu::Queue, cage: &[DVec3]) -> Result<(), GpuError> {
        check_cage(self.cage_len, cage)?;
        self.write_cage(queue, cage);
        Ok(())
    }

    /// Records the evaluation into the caller's `encoder`: one compute pass with one dispatch
    /// per vertex range ([`dispatch_count`](Self::dispatch_count)), which refills the vertex
    /// buffer from the control-point buffer. Commands recorded after it in the same encoder
    /// (a render pass drawing [`vertex_buffer`](Self::vertex_buffer), a copy) see the new
    /// vertices: wgpu orders the passes' buffer uses.
    ///
    /// ```no_run
    /// # fn frame(gpu: &subdiv_gpu::Gpu, surface: &subdiv_gpu::GpuTessellation, cage: &[glam::Vec3])
    /// #     -> Result<(), subdiv_gpu::GpuError> {
    /// surface.write_control_points(&gpu.queue, cage)?;
    /// let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    /// surface.record(&mut encoder);
    /// // … the application's render pass, drawing surface.vertex_buffer() …
    /// gpu.queue.submit([encoder.finish()]);
    /// # Ok(())
    /// # }
    /// ```
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("subdiv evaluate"),
            timestamp_writes: None,
        });
        self.record_in_pass(&mut pass);
    }

    /// Records the evaluation's dispatches into the caller's compute `pass` (as
    /// [`record`](Self::record), without a pass of its own). It sets the pass's pipeline and
    /// bind group 0: dispatches of the caller's that follow set their own.
    pub fn record_in_pass(&self, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_pipeline(&self.pipeline);
        for d in &self.dispatches {
            pass.set_bind_group(0, &d.bind_group, &[]);
            pass.dispatch_workgroups(d.groups[0], d.groups[1], 1);
        }
    }

    /// Writes the cage, relative to the centre, into the control-point buffer.
    fn write_cage(&self, queue: &wgpu::Queue, cage: &[DVec3]) {
        let data: Vec<[f32; 4]> = cage.iter().map(|p| (*p - self.origin).as_vec3().extend(1.0).to_array()).collect();
        if !data.is_empty() {
            queue.write_buffer(&self.points, 0, bytemuck::cast_slice(&data));
        }
    }

    /// Records the evaluation into an encoder of its own and submits it.
    fn submit(&self, gpu: &Gpu) {
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("subdiv evaluate") });
        self.record(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
    }

    /// The vertex buffer: per vertex `px py pz nx ny nz` (f32, 24 bytes), usable as a vertex
    /// buffer and a storage buffer.
    pub fn vertex_buffer(&self) -> &wgpu::Buffer {
        &self.vertices
    }

    /// The index buffer: u32 triangles, counter-clockwise.
    pub fn index_buffer(&self) -> &wgpu::Buffer {
        &self.indices
    }

    /// A scene of the evaluated surface (with its wireframe when [`GpuEvalOptions::edges`] was
    /// set) seen by `view`, without a cage: the vertex buffer is drawn where the compute pass
    /// wrote it.
    pub fn scene(&self, view: crate::View) -> crate::Scene<'_> {
        crate::Scene {
            vertices: &self.vertices,
            vertex_count: self.vertex_count,
            triangles: &self.indices,
            index_count: self.index_count,
            wireframe: self
                .edges
                .as_ref()
                .map(|(indices, index_count)| crate::Lines { indices, index_count: *index_count }),
            texture: None,
            cage: None,
            view,
        }
    }

    /// The number of vertices.
    pub fn vertex_count(&self) -> u32 {
        self.vertex_count
    }

    /// The number of indices (three per triangle).
    pub fn index_count(&self) -> u32 {
        self.index_count
    }

    /// The number of compute dispatches per update: one per range of vertices whose stencil
    /// data fits [`GpuEvalOptions::max_buffer_bytes`] (usually one).
    pub fn dispatch_count(&self) -> usize {
        self.dispatches.len()
    }

    /// Waits for the GPU and copies the vertex buffer back: `6 ·` [`vertex_count`](Self::vertex_count)
    /// floats, the layout of [`FlatMesh::vertices`](subdiv_tess::FlatMesh::vertices).
    ///
    /// # Errors
    /// [`GpuError::Readback`] if the copy cannot be mapped.
    pub fn read_vertices(&self, gpu: &Gpu) -> Result<Vec<f32>, GpuError> {
        let bytes = VERTEX_BYTES * u64::from(self.vertex_count);
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("subdiv readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("subdiv readback") });
        encoder.copy_buffer_to_buffer(&self.vertices, 0, &staging, 0, bytes);
        gpu.queue.submit([encoder.finish()]);
        let (send, receive) = std::sync::mpsc::channel();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            // The receiver waits below; a closed channel means it gave up.
            let _ = send.send(r);
        });
        gpu.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::Readback(e.to_string()))?;
        receive
            .recv()
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let data = {
            let view = staging.slice(..).get_mapped_range().map_err(|e| GpuError::Readback(e.to_string()))?;
            bytemuck::cast_slice::<u8, f32>(&view).to_vec()
        };
        staging.unmap();
        Ok(data)
    }

    /// Waits until the GPU has done all submitted work (for timing).
    ///
    /// # Errors
    /// [`GpuError::Readback`] when the device is lost.
    pub fn wait(&self, gpu: &Gpu) -> Result<(), GpuError> {
        gpu.device.poll(wgpu::PollType::wait_indefinitely()).map(|_| ()).map_err(|e| GpuError::Readback(e.to_string()))
    }
}

fn pipeline(device: &wgpu::Device, entry: &str, source: &str) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(entry),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

fn lcm(a: u64, b: u64) -> u64 {
    let (mut x, mut y) = (a, b);
    while y != 0 {
        (x, y) = (y, x % y);
    }
    a / x * b
}

/// The plan's vertices in ranges of whole `step`s whose buffers stay within `budget` bytes,
/// each with its own records, patches and weights (shared ones copied once per range).
fn split(plan: &EvaluationPlan, budget: u64, step: usize) -> Vec<Range> {
    // The most one vertex can add to any buffer: a record, a patch, its weights.
    let widest = plan.general().iter().map(|g| u64::from(g.len)).max().unwrap_or(16).max(16);
    let per_vertex = (12 * widest).max(32);
    let reserve = per_vertex * step as u64;
    let output = |r: &Range| VERTEX_BYTES * u64::from(r.count);
    let mut ranges = Vec::new();
    let mut range = Range::default();
    let (mut patches, mut weights) = (HashMap::new(), HashMap::new());
    // A block's vertices are consecutive: the last block taken (by its base) is the only one
    // to look for.
    let mut last_block: Option<u32> = None;
    let mut entries = plan.entries().peekable();
    let mut v = 0;
    while entries.peek().is_some() {
        if range.count > 0
            && (range.largest() + reserve > budget || output(&range) + VERTEX_BYTES * step as u64 > budget)
        {
            ranges.push(std::mem::take(&mut range));
            range.first = v as u32;
            last_block = None;
            patches.clear();
            weights.clear();
        }
        for entry in entries.by_ref().take(step) {
            // Runs are shared by start and length: a valid plan may start two runs of
            // different lengths at one offset.
            let mut patch = |at: u32, len: u32, range: &mut Range| {
                *patches.entry((at, len)).or_insert_with(|| {
                    let local = range.patches.len() as u32;
                    range.patches.extend_from_slice(&plan.points()[at as usize..(at + len) as usize]);
                    local
                })
            };
            let (kind, local) = match entry {
                PlanEntry::Block(b) => {
                    if last_block != Some(b.base) {
                        let points = patch(b.points, 16, &mut range);
                        range.blocks.push(GpuBlock { base: b.base, rate: b.rate, points, pad: 0 });
                        last_block = Some(b.base);
                    }
                    (KIND_BLOCK, range.blocks.len() as u32 - 1)
                }
                PlanEntry::Bicubic(b) => {
                    let points = patch(b.points, 16, &mut range);
                    range.bicubic.push(GpuBicubic {
                        points,
                        s: b.s as f32,
                        t: b.t as f32,
                        pad: 0,
                        ju: b.ju.map(|x| x as f32),
                        jv: b.jv.map(|x| x as f32),
                    });
                    (KIND_BICUBIC, range.bicubic.len() as u32 - 1)
                }
                PlanEntry::General(g) => {
                    let points = patch(g.points, g.len, &mut range);
                    let w = *weights.entry((g.weights, g.len)).or_insert_with(|| {
                        let local = range.weights.len() as u32;
                        let rows = &plan.weights()[g.weights as usize..(g.weights + 3 * g.len) as usize];
                        range.weights.extend(rows.iter().map(|&x| x as f32));
                        local
                    });
                    range.general.push(GpuGeneral {
                        points,
                        len: g.len,
                        weights: w,
                        pad: 0,
                        ju: g.ju.map(|x| x as f32),
                        jv: g.jv.map(|x| x as f32),
                    });
                    (KIND_GENERAL, range.general.len() as u32 - 1)
                }
            };
            range.entries.push(kind << KIND_SHIFT | local);
            range.count += 1;
            v += 1;
        }
    }
    if range.count > 0 {
        ranges.push(range);
    }
    ranges
}

/// Several tessellations of one cage kept on the GPU, one per rate configuration (screen-space
/// rates that come back, level-of-detail steps): switching to a configuration seen before
/// re-uses its stencil data and index buffer and only re-evaluates.
#[derive(Debug)]
pub struct RateCache {
    capacity: usize,
    /// Most recently used last.
    entries: Vec<(Vec<u32>, GpuTessellation)>,
}

impl RateCache {
    /// A cache keeping at most `capacity` (at least 1) configurations.
    pub fn new(capacity: usize) -> Self {
        Self { capacity: capacity.max(1), entries: Vec::new() }
    }

    /// The tessellation at `rates` on `cage`: the cached one, re-evaluated on `cage`, or a new
    /// one made by `make` (which returns the plan and the triangles of a CPU tessellation at
    /// `rates`); the least recently used configuration goes when the cache is full.
    ///
    /// # Errors
    /// What `make` returns, and as [`GpuTessellation::new`].
    pub fn get(
        &mut self,
        gpu: &Gpu,
        rates: &[u32],
        cage: &[DVec3],
        options: &GpuEvalOptions,
        make: impl FnOnce() -> Result<(EvaluationPlan, Vec<u32>), GpuError>,
    ) -> Result<&mut GpuTessellation, GpuError> {
        if let Some(k) = self.entries.iter().position(|(r, _)| r == rates) {
            let entry = self.entries.remove(k);
            self.entries.push(entry);
            let t = &mut self.entries.last_mut().expect("just pushed").1;
            t.update_control_points_f64(gpu, cage)?;
            return Ok(t);
        }
        let (plan, indices) = make()?;
        let t = GpuTessellation::new(gpu, &plan, &indices, cage, options)?;
        if self.entries.len() == self.capacity {
            self.entries.remove(0);
        }
        self.entries.push((rates.to_vec(), t));
        Ok(&mut self.entries.last_mut().expect("just pushed").1)
    }

    /// The number of configurations held.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether none is held.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}
