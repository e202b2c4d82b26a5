//! subdiv-gpu in an application's own wgpu device: the application makes its instance,
//! adapter, device and queue, wraps clones with `Gpu::from_parts`, and evaluates the
//! tessellation in its own command encoder and submission.
//!
//! The built-in model is tessellated on the CPU (Catmull-Clark, dual grid, rate 8: topology and
//! stencils), uploaded once, then one frame of a twisted cage is written with
//! `write_control_points`, evaluated by `record` in the application's encoder, copied to the
//! application's staging buffer in the same encoder, submitted and read back, and compared with
//! the CPU tessellator's f64 values on the same cage. Prints one line; exits non-zero on a
//! mismatch or without an adapter.
//!
//! `cargo run -p subdiv-gpu --example own_device` (also run by `tests/own_device.rs`).

#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::fmt;
use std::process::ExitCode;

use glam::DVec3;
use subdiv_gpu::{Gpu, GpuEvalOptions, GpuTessellation, VERTEX_STRIDE};
use subdiv_mesh::{Mesh, shapes};
use subdiv_schemes::Builtin;
use subdiv_tess::{DualOptions, DualTessellator, FlatMesh};

/// Every face's rate.
const RATE: u32 = 8;
/// The largest position error, as a fraction of the bounding box's diagonal (f32 against f64).
const POSITION_TOLERANCE: f64 = 1e-5;
/// The largest normal error (unit vectors).
const NORMAL_TOLERANCE: f64 = 1e-5;

fn main() -> ExitCode {
    match run() {
        Ok(report) => {
            println!("{report}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("own_device: {e}");
            ExitCode::FAILURE
        }
    }
}

/// What the check found.
#[derive(Debug)]
pub(crate) struct Report {
    /// The adapter's name and backend.
    pub(crate) adapter: String,
    /// The vertices compared.
    pub(crate) vertices: usize,
    /// The worst position error over the bounding box's diagonal.
    pub(crate) position: f64,
    /// The worst normal error.
    pub(crate) normal: f64,
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "own_device: {} vertices evaluated in the application's encoder on {} match the CPU \
             (positions within {:.1e} of the bounding box, normals within {:.1e})",
            self.vertices, self.adapter, self.position, self.normal
        )
    }
}

/// The whole path; an error for a missing adapter or device, a wgpu failure, or values that
/// differ from the CPU's by more than the tolerances.
pub(crate) fn run() -> Result<Report, Box<dyn std::error::Error>> {
    // The application's device, with what subdiv-gpu asks for.
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("application"),
        required_limits: Gpu::required_limits(),
        ..Default::default()
    }))?;
    // Clones: the application keeps its own handles.
    let gpu = Gpu::from_parts(device.clone(), queue.clone())?;

    // The CPU's part, once: topology, triangles and stencils.
    let mesh = Mesh::build(shapes::default_model())?;
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), &mesh, &DualOptions::default())?;
    let mut flat = FlatMesh::default();
    tess.tessellate_flat(&vec![RATE; mesh.face_count()], &mut flat)?;
    let plan = tess.evaluation_plan();
    let surface = GpuTessellation::new(&gpu, &plan, &flat.indices, mesh.positions(), &GpuEvalOptions::default())?;

    // One frame in the application's submission: the new cage (a queue write), the
    // evaluation and a copy of the vertex buffer (the application's encoder).
    let cage = shapes::twist(mesh.positions(), 0.6);
    surface.write_control_points_f64(&queue, &cage)?;
    let bytes = VERTEX_STRIDE * u64::from(surface.vertex_count());
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("application readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
    surface.record(&mut encoder);
    encoder.copy_buffer_to_buffer(surface.vertex_buffer(), 0, &staging, 0, bytes);
    queue.submit([encoder.finish()]);

    let (send, receive) = std::sync::mpsc::channel();
    staging.slice(..).map_async(wgpu::MapMode::Read, move |result| {
        // The receiver waits below.
        let _ = send.send(result);
    });
    device.poll(wgpu::PollType::wait_indefinitely())?;
    receive.recv()??;
    let vertices: Vec<f32> = bytemuck::cast_slice(&staging.slice(..).get_mapped_range()?).to_vec();
    staging.unmap();

    // The CPU on the same cage, in f64.
    let cpu = tess.update_cage(&cage)?;
    if vertices.len() != 6 * cpu.positions.len() {
        return Err(format!("{} floats read back for {} vertices", vertices.len(), cpu.positions.len()).into());
    }
    let (lo, hi) = mesh.bounding_box().ok_or("the model has no vertices")?;
    let diagonal = (hi - lo).length();
    let (mut position, mut normal) = (0.0f64, 0.0f64);
    for (k, v) in vertices.chunks_exact(6).enumerate() {
        let p = DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
        let n = DVec3::new(f64::from(v[3]), f64::from(v[4]), f64::from(v[5]));
        // NaN compares false: a NaN vertex is a mismatch, not a pass.
        let (dp, dn) = (p.distance(cpu.positions[k]) / diagonal, n.distance(cpu.normals[k]));
        if !(dp <= POSITION_TOLERANCE && dn <= NORMAL_TOLERANCE) {
            return Err(format!(
                "vertex {k}: GPU {p} {n} against CPU {} {} (position {dp:.1e} of the bounding box, normal {dn:.1e})",
                cpu.positions[k], cpu.normals[k]
            )
            .into());
        }
        (position, normal) = (position.max(dp), normal.max(dn));
    }
    Ok(Report { adapter: gpu.adapter_name(), vertices: cpu.positions.len(), position, normal })
}
