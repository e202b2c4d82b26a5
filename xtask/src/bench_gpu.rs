//! `cargo xtask bench gpu [--mesh M]… [--rate N]… [--frames K]`: milliseconds per animation
//! frame to re-evaluate every tessellation vertex's position and normal on the GPU (the cage
//! uploaded, one compute dispatch, waited for), beside the CPU's animation path
//! (`update_cage_flat` on every core). Default meshes: the built-in model and a 400 × 250
//! quad torus (100 000 faces); default rates 8 and 16. One `key=value` line per measurement,
//! with the adapter's name. A debug build of xtask hands the work to a release build of itself.

use std::path::PathBuf;
use std::time::Instant;

use subdiv::io::load_mesh;
use subdiv::mesh::{DVec3, Mesh, shapes};
use subdiv::schemes::Builtin;
use subdiv::tess::{DualOptions, DualTessellator, FlatMesh};
use subdiv_gpu::{Gpu, GpuEvalOptions, GpuOptions, GpuTessellation};

const USAGE: &str = "usage: cargo xtask bench gpu [--mesh M]... [--rate N]... [--frames K]";

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    if cfg!(debug_assertions) {
        let mut command = vec!["run", "--release", "--quiet", "-p", "xtask", "--", "bench", "gpu"];
        command.extend(args.iter().map(String::as_str));
        return crate::cargo(&command);
    }
    let mut meshes: Vec<(String, Mesh)> = Vec::new();
    let mut rates: Vec<u32> = Vec::new();
    let mut frames = 8usize;
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        let value = rest.next().ok_or_else(|| format!("{a} needs a value; {USAGE}"))?;
        match a.as_str() {
            "--mesh" => {
                let path = PathBuf::from(value);
                let mesh = load_mesh(&path, &Default::default()).map_err(|e| format!("{value}: {e}"))?;
                meshes.push((path.file_name().map_or(value.clone(), |n| n.to_string_lossy().into_owned()), mesh));
            }
            "--rate" => rates.push(value.parse().map_err(|_| format!("--rate {value}: not a rate; {USAGE}"))?),
            "--frames" => {
                frames = value.parse().ok().filter(|&k| k > 0).ok_or_else(|| format!("--frames {value}; {USAGE}"))?;
            }
            _ => return Err(format!("unknown option {a:?}; {USAGE}")),
        }
    }
    if meshes.is_empty() {
        let build = |soup| Mesh::build(soup).map_err(|e| e.to_string());
        meshes.push(("built-in".to_string(), build(shapes::default_model())?));
        meshes.push(("torus_400x250".to_string(), build(shapes::quad_torus(400, 250))?));
    }
    if rates.is_empty() {
        rates = vec![8, 16];
    }
    let gpu = Gpu::new(&GpuOptions::default()).map_err(|e| e.to_string())?;
    let adapter = gpu.adapter_name();
    for (name, mesh) in &meshes {
        for &rate in &rates {
            measure(&gpu, &adapter, name, mesh, rate, frames)?;
        }
    }
    Ok(())
}

fn median(mut samples: Vec<f64>) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

fn measure(gpu: &Gpu, adapter: &str, name: &str, mesh: &Mesh, rate: u32, frames: usize) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("{name} at rate {rate}: {e}");
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), mesh, &DualOptions::DEFAULT.with_quads(false))
        .map_err(|e| err(&e))?;
    let mut flat = FlatMesh::default();
    tess.tessellate_flat(&vec![rate; mesh.face_count()], &mut flat).map_err(|e| err(&e))?;
    let start = Instant::now();
    let plan = tess.evaluation_plan();
    let on_gpu = GpuTessellation::new(gpu, &plan, &flat.indices, mesh.positions(), &GpuEvalOptions::default())
        .map_err(|e| err(&e))?;
    on_gpu.wait(gpu).map_err(|e| err(&e))?;
    let setup = start.elapsed().as_secs_f64();
    let cages: Vec<Vec<DVec3>> = (0..frames).map(|k| shapes::twist(mesh.positions(), 0.02 * (k + 1) as f64)).collect();
    let cages32: Vec<Vec<glam::Vec3>> = cages.iter().map(|c| c.iter().map(|p| p.as_vec3()).collect()).collect();
    let mut gpu_ms = Vec::with_capacity(frames);
    for (k, cage) in cages32.iter().enumerate() {
        let start = Instant::now();
        on_gpu.update_control_points(gpu, cage).map_err(|e| err(&e))?;
        on_gpu.wait(gpu).map_err(|e| err(&e))?;
        // The first two frames warm up.
        if k >= 2.min(frames - 1) {
            gpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    let mut cpu_ms = Vec::with_capacity(frames);
    for (k, cage) in cages.iter().enumerate() {
        let start = Instant::now();
        tess.update_cage_flat(cage, &mut flat).map_err(|e| err(&e))?;
        std::hint::black_box(flat.vertices.len());
        if k >= 2.min(frames - 1) {
            cpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    println!(
        "bench=gpu adapter=\"{adapter}\" mesh={name} faces={} rate={rate} vertices={} tris={} dispatches={} \
         setup_s={setup:.3} frame_ms={:.3} cpu_frame_ms={:.3} cpu_threads={}",
        mesh.face_count(),
        on_gpu.vertex_count(),
        on_gpu.index_count() / 3,
        on_gpu.dispatch_count(),
        median(gpu_ms),
        median(cpu_ms),
        rayon::current_num_threads(),
    );
    Ok(())
}
