//! `cargo xtask bench tess [--mesh M]… [--rate N]… [--threads T]… [--mode MODE]… [--channels yes|no]…`:
//! dual-grid tessellation throughput into welded flat buffers (f32 positions and normals, u32
//! indices), one `key=value` line per measurement; with `SUBDIV_OSD_BENCH` pointing at the peer
//! harness's `osd_bench`, OpenSubdiv's Bfr on the same meshes and rates, side by side.
//! `--channels yes` carries the meshes' face-varying channels (texture coordinates: exact values,
//! seams split); the default `no` measures positions and normals alone, as `osd_bench` does.
//!
//! `cold` (alone, default meshes the built-in model, spot, blub, the car and the bishop at rate
//! 8): each sample a fresh process of the release CLI, Bfr's per-face path alternated with it
//! (see [`cold`]). `first`: a new tessellator and its first flat output in this process (whose
//! caches are warm after the first sample). Then two
//! modes, as `osd_bench` has: `full` (topology, stencil records, evaluation and flat
//! buffers from the cage: `tessellate_flat`, the whole job on a fresh rate set) and `animate`
//! (`update_cage_flat`: the same rates on a moved cage), both straight into the flat buffers;
//! and the same through the f64 [`TessMesh`](subdiv::tess::TessMesh) (with surface parameters)
//! then `write_flat`: `full_mesh` (`tessellate` + `write_flat`) and `animate_mesh`
//! (`update_cage` + `write_flat`). Timing as
//! `osd_bench`: one warm-up, then 5 samples, each repeating the work until it lasts ≥ 20 ms;
//! the median. A debug build of xtask (what `cargo xtask` runs) hands the work to a release
//! build of itself.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use crate::bench_args::{median, one_of, sample, yes_no};
use subdiv::io::load_mesh;
use subdiv::mesh::Mesh;
use subdiv::schemes::Builtin;
use subdiv::tess::{DualOptions, DualTessellator, FlatMesh, Parallelism};

/// The peer harness's benchmark meshes (`../shared/peers/osd/meshes`).
const PEER_MESHES: [&str; 3] = ["torus_big.obj", "cube.obj", "valence56.obj"];

/// Real meshes from the shared corpus (`../shared/testdata/meshes`) measured with them: the
/// car's 314 creases of sharpness 6 are refined locally, 6 levels deep.
const CORPUS_MESHES: [&str; 1] = ["opensubdiv/catmark_car.obj"];

/// The peer harness's rates.
const PEER_RATES: [u32; 3] = [8, 16, 32];

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    if cfg!(debug_assertions) {
        let mut command = vec!["run", "--release", "--quiet", "-p", "xtask", "--", "bench", "tess"];
        command.extend(args.iter().map(String::as_str));
        return crate::cargo(&command);
    }
    let mut meshes: Vec<PathBuf> = Vec::new();
    let mut rates: Vec<u32> = Vec::new();
    let mut threads: Vec<usize> = Vec::new();
    let mut modes: Vec<&'static str> = Vec::new();
    let mut channels: Vec<bool> = Vec::new();
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        let value = rest.next().ok_or_else(|| format!("{a} needs a value; {USAGE}"))?;
        match a.as_str() {
            "--mesh" => meshes.push(PathBuf::from(value)),
            "--rate" => rates.push(value.parse().map_err(|_| format!("--rate {value}: not a rate; {USAGE}"))?),
            "--threads" => threads.push(
                value
                    .parse()
                    .ok()
                    .filter(|&t| t > 0)
                    .ok_or_else(|| format!("--threads {value}: not a count; {USAGE}"))?,
            ),
            "--mode" => modes.push(one_of(a, value, &MODES)?),
            "--channels" => channels.push(yes_no(a, value, USAGE)?),
            _ => return Err(format!("unknown option {a:?}; {USAGE}")),
        }
    }
    if meshes.is_empty() && modes.contains(&"cold") {
        let corpus = crate::shared_dir().join("testdata/meshes");
        meshes = COLD_MESHES.iter().map(|m| corpus.join(m)).collect();
    } else if meshes.is_empty() {
        let dir = crate::shared_dir().join("peers/osd/meshes");
        meshes = PEER_MESHES.iter().map(|m| dir.join(m)).collect();
        let corpus = crate::shared_dir().join("testdata/meshes");
        meshes.extend(CORPUS_MESHES.iter().map(|m| corpus.join(m)));
    }
    if rates.is_empty() {
        rates = if modes.contains(&"cold") { vec![8] } else { PEER_RATES.to_vec() };
    }
    if threads.is_empty() {
        threads = vec![1, std::thread::available_parallelism().map_or(1, usize::from)];
        threads.dedup();
    }
    if modes.is_empty() {
        modes = MODES.to_vec();
    }
    if channels.is_empty() {
        channels.push(false);
    }
    let peer = std::env::var_os("SUBDIV_OSD_BENCH").map(PathBuf::from);
    if modes.contains(&"cold") {
        return cold(&meshes, &rates, peer.as_deref());
    }
    for path in &meshes {
        let mesh = load_mesh(path, &Default::default()).map_err(|e| format!("{}: {e}", path.display()))?;
        let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
        for &rate in &rates {
            for &t in &threads {
                for &with in &channels {
                    measure(&mesh, &name, rate, t, &modes, with)?;
                }
            }
            if let Some(osd) = &peer {
                osd_bench(osd, path, &name, rate)?;
            }
        }
    }
    Ok(())
}

const USAGE: &str = "usage: cargo xtask bench tess [--mesh M]... [--rate N]... [--threads T]... [--mode MODE]... [--channels yes|no]...";

/// What is measured (see the module docs).
const MODES: [&str; 6] = ["first", "full", "animate", "full_mesh", "animate_mesh", "cold"];

/// The meshes of `--mode cold` (`../shared/testdata/meshes`), besides the built-in model.
const COLD_MESHES: [&str; 4] = [
    "keenan/spot_control_mesh.obj",
    "keenan/blub_control_mesh.obj",
    "opensubdiv/catmark_car.obj",
    "opensubdiv/catmark_bishop.obj",
];

/// Rounds of `--mode cold`, each one process of ours and one run of the peer.
const COLD_ROUNDS: usize = 5;

/// `--mode cold`: what a user's first command meets. Per mesh (the built-in model first,
/// written to an OBJ file so that the peer reads the same mesh) and rate, [`COLD_ROUNDS`]
/// rounds of one fresh `subdiv tessellate MESH --rate N` process of the release build on one
/// thread (its own `in T s`, which starts after the mesh is read) and, with `peer`, one
/// `osd_bench MESH tess N` (Bfr's `surface_per_face` median); the medians.
fn cold(meshes: &[PathBuf], rates: &[u32], peer: Option<&Path>) -> Result<(), String> {
    let work = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    let cli = crate::release_cli(work.path())?;
    let builtin = work.path().join("built-in.obj");
    subdiv::io::write_obj(&builtin, &subdiv::mesh::shapes::default_model()).map_err(|e| e.to_string())?;
    let out = work.path().join("out.glb");
    for path in std::iter::once(&builtin).chain(meshes) {
        let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
        for &rate in rates {
            let (mut ours, mut theirs) = (Vec::new(), Vec::new());
            for _ in 0..COLD_ROUNDS {
                let run = Command::new(&cli)
                    .args(["tessellate"])
                    .arg(path)
                    .args(["--rate", &rate.to_string(), "-o"])
                    .arg(&out)
                    .env("RAYON_NUM_THREADS", "1")
                    .output()
                    .map_err(|e| format!("{}: {e}", cli.display()))?;
                let stderr = String::from_utf8_lossy(&run.stderr);
                let seconds = crate::bench_args::cli_seconds(&stderr)
                    .filter(|_| run.status.success())
                    .ok_or_else(|| format!("subdiv tessellate {name}: {stderr}"))?;
                ours.push(seconds);
                if let Some(osd) = peer {
                    let text = osd_tess(osd, path, &name, rate)?;
                    let per_face = text
                        .lines()
                        .filter(|l| l.contains("mode=surface_per_face"))
                        .find_map(|l| l.split_whitespace().find_map(|kv| kv.strip_prefix("median_s=")))
                        .and_then(|s| s.parse::<f64>().ok())
                        .ok_or_else(|| format!("{} on {name}: no surface_per_face line", osd.display()))?;
                    theirs.push(per_face);
                }
            }
            let theirs =
                if theirs.is_empty() { String::new() } else { format!(" osd_per_face_s={:.6}", median(&theirs)) };
            println!(
                "bench=tess mode=cold mesh={name} rate={rate} threads=1 rounds={COLD_ROUNDS} median_s={:.4}{theirs}",
                median(&ours)
            );
        }
    }
    Ok(())
}

/// Our lines for one mesh, rate and thread count, with or without the mesh's channels.
fn measure(mesh: &Mesh, name: &str, rate: u32, threads: usize, modes: &[&str], channels: bool) -> Result<(), String> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
    let options = DualOptions::DEFAULT.with_quads(false).with_channels(channels).with_parallelism(if threads > 1 {
        Parallelism::Rayon
    } else {
        Parallelism::Serial
    });
    let channels = if channels { "yes" } else { "no" };
    let rates = vec![rate; mesh.face_count()];
    if modes.contains(&"first") {
        // What a fresh process meets: the tessellator built (patch levels, stencil records)
        // and its first flat output; the median of 3, each on a new tessellator.
        let mut samples: Vec<f64> = (0..3)
            .map(|_| {
                let start = Instant::now();
                let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), mesh, &options)?;
                let mut flat = FlatMesh::default();
                pool.install(|| tess.tessellate_flat(&rates, &mut flat))?;
                std::hint::black_box(flat.indices.len());
                Ok(start.elapsed().as_secs_f64())
            })
            .collect::<Result<_, subdiv::tess::TessError>>()
            .map_err(|e| e.to_string())?;
        samples.sort_by(f64::total_cmp);
        println!(
            "bench=tess peer=subdiv mesh={name} mode=first rate={rate} threads={threads} channels={channels} \
             median_s={:.6}",
            samples[1]
        );
    }
    let mut tess = DualTessellator::new(Builtin::CatmullClark.scheme(), mesh, &options).map_err(|e| e.to_string())?;
    let cage = mesh.positions().to_vec();
    let mut flat = FlatMesh::default();
    pool.install(|| -> Result<(), String> {
        tess.tessellate(&rates).map_err(|e| e.to_string())?;
        tess.write_flat(&mut flat);
        let (vertices, tris) = (flat.vertices.len() / 6, flat.indices.len() / 3);
        let bytes_per_tri = (24 * vertices + 12 * tris) as f64 / tris as f64;
        for &mode in modes.iter().filter(|&&m| m != "first") {
            let seconds = median_seconds(|| {
                match mode {
                    "full" => tess.tessellate_flat(&rates, &mut flat),
                    "animate" => tess.update_cage_flat(&cage, &mut flat),
                    "full_mesh" => tess.tessellate(&rates).map(|_| ()),
                    _ => tess.update_cage(&cage).map(|_| ()),
                }
                .expect("checked by the first run");
                if mode.ends_with("_mesh") {
                    tess.write_flat(&mut flat);
                }
                std::hint::black_box(flat.indices.len());
            });
            println!(
                "bench=tess peer=subdiv mesh={name} mode={mode} rate={rate} threads={threads} channels={channels} \
                 tris={tris} vertices={vertices} median_s={seconds:.6} tris_per_s={:.0} bytes_per_tri={bytes_per_tri:.2}",
                tris as f64 / seconds
            );
        }
        Ok(())
    })
}

/// The median of 5 samples (after a warm-up), each repeating `work` until it lasts ≥ 20 ms,
/// per repetition.
fn median_seconds(mut work: impl FnMut()) -> f64 {
    work();
    let samples: Vec<f64> = (0..5).map(|_| sample(&mut work)).collect();
    median(&samples)
}

/// OpenSubdiv's Bfr through the peer harness (`osd_bench MESH tess N`), its lines as it prints
/// them with `peer=osd` in front.
fn osd_bench(osd: &Path, mesh: &Path, name: &str, rate: u32) -> Result<(), String> {
    for line in osd_tess(osd, mesh, name, rate)?.lines().filter(|l| l.contains('=')) {
        println!("bench=tess peer=osd {line}");
    }
    Ok(())
}

/// What `osd_bench MESH tess N` prints, on one thread.
fn osd_tess(osd: &Path, mesh: &Path, name: &str, rate: u32) -> Result<String, String> {
    let out = Command::new(osd)
        .arg(mesh)
        .args(["tess", &rate.to_string()])
        .env("OMP_NUM_THREADS", "1")
        .output()
        .map_err(|e| format!("{}: {e}", osd.display()))?;
    if !out.status.success() {
        return Err(format!("{} on {name}: {}", osd.display(), String::from_utf8_lossy(&out.stderr)));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}
