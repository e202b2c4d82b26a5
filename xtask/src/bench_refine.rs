//! `cargo xtask bench refine [--mesh M]… [--levels K]… [--threads T]… [--rounds R]`: uniform
//! refinement beside OpenSubdiv's `Far`, one `key=value` line per measurement.
//!
//! Ours, per mesh, level and thread count: `refine` (`refine_uniform`: topology and positions
//! from the cage, what `subdiv refine` runs), `topology` (the same levels' splits alone: no
//! positions, no sharpness), `stencils` (`Refiner::new`: every level's stencil rows),
//! `stencil_apply` (`Refiner::interpolate`: positions through those, level by level, the
//! animation loop), `stencil_table` (`Refiner::new` then `stencil_table`: the last level over the
//! cage, Far's `StencilTableFactory::Create` counterpart — which does not count the topology we
//! count) and `stencil_table_apply` (`StencilTable::apply`, Far's `UpdateValues`). With
//! `SUBDIV_OSD_BENCH` naming the peer harness's `osd_bench`, `osd_bench MESH refine K` runs in
//! the same rounds, alternated with ours, and its lines come out with `peer=osd`.
//!
//! Default meshes: the peer harness's `torus_big` and `torus_tri_big` (Loop) and the corpus'
//! `catmark_car` and `spot_control_mesh` (positions only: `osd_bench` drops texture
//! coordinates, so we drop them too; `--channels yes` keeps them), levels 3, one thread and all. Timing as `osd_bench`: a
//! warm-up, then per round one sample that repeats the work until it lasts ≥ 20 ms; the median
//! over the rounds (default 5). A debug build of xtask hands the work to a release build.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::bench_args::{self, median, one_of, yes_no};
use subdiv::io::load;
use subdiv::mesh::Mesh;
use subdiv::schemes::{Builtin, RefineOptions, Refiner, refine_uniform};

const USAGE: &str = "usage: cargo xtask bench refine [--mesh M]... [--levels K]... [--threads T]... [--mode MODE]... [--rounds R] [--channels yes|no]";

/// Our modes (see the module docs).
const MODES: [&str; 6] = ["refine", "topology", "stencils", "stencil_apply", "stencil_table", "stencil_table_apply"];

/// The default meshes: the peer harness's (`../shared/peers/osd/meshes`) and the corpus'
/// (`../shared/testdata/meshes`).
const PEER_MESHES: [&str; 2] = ["torus_big.obj", "torus_tri_big.obj"];
const CORPUS_MESHES: [&str; 2] = ["opensubdiv/catmark_car.obj", "keenan/spot_control_mesh.obj"];

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    if cfg!(debug_assertions) {
        let mut command = vec!["run", "--release", "--quiet", "-p", "xtask", "--", "bench", "refine"];
        command.extend(args.iter().map(String::as_str));
        return crate::cargo(&command);
    }
    let (mut meshes, mut levels, mut threads, mut rounds) = (Vec::new(), Vec::new(), Vec::new(), 5usize);
    let mut modes = Vec::new();
    let mut channels = false;
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        let value = rest.next().ok_or_else(|| format!("{a} needs a value; {USAGE}"))?;
        let count =
            || value.parse::<usize>().ok().filter(|&n| n > 0).ok_or_else(|| format!("{a} {value}: not a count"));
        match a.as_str() {
            "--mesh" => meshes.push(PathBuf::from(value)),
            "--levels" => levels.push(count()?),
            "--threads" => threads.push(count()?),
            "--rounds" => rounds = count()?,
            "--channels" => channels = yes_no(a, value, USAGE)?,
            "--mode" => modes.push(one_of(a, value, &MODES)?),
            _ => return Err(format!("unknown option {a:?}; {USAGE}")),
        }
    }
    if meshes.is_empty() {
        let peers = crate::shared_dir().join("peers/osd/meshes");
        let corpus = crate::shared_dir().join("testdata/meshes");
        meshes =
            PEER_MESHES.iter().map(|m| peers.join(m)).chain(CORPUS_MESHES.iter().map(|m| corpus.join(m))).collect();
    }
    if levels.is_empty() {
        levels.push(3);
    }
    if modes.is_empty() {
        modes = MODES.to_vec();
    }
    if threads.is_empty() {
        threads = vec![1, std::thread::available_parallelism().map_or(1, usize::from)];
        threads.dedup();
    }
    let peer = std::env::var_os("SUBDIV_OSD_BENCH").map(PathBuf::from);
    for path in &meshes {
        let soup = load(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
        let builtin = subdiv_testkit::opensubdiv::scheme_of(&name, &soup).0;
        let mut mesh = Mesh::build(soup).map_err(|e| format!("{}: {e}", path.display()))?;
        if !channels {
            mesh.clear_channels();
        }
        for &level in &levels {
            let mut ours: BTreeMap<(usize, &str), Vec<f64>> = BTreeMap::new();
            let mut theirs: BTreeMap<String, Vec<f64>> = BTreeMap::new();
            for _ in 0..rounds {
                for &t in &threads {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(t).build().map_err(|e| e.to_string())?;
                    for (mode, seconds) in pool.install(|| measure(&mesh, builtin, level, &modes))? {
                        ours.entry((t, mode)).or_default().push(seconds);
                    }
                }
                if let Some(osd) = &peer {
                    for (mode, seconds) in osd_bench(osd, path, builtin, level)? {
                        theirs.entry(mode).or_default().push(seconds);
                    }
                }
            }
            let faces = refine_uniform(&mesh, builtin.scheme(), level, &RefineOptions::DEFAULT)
                .map_err(|e| format!("{name}: {e}"))?
                .face_count();
            let common =
                format!("bench=refine mesh={name} scheme={builtin:?} level={level} faces={faces} rounds={rounds}");
            for ((t, mode), samples) in &ours {
                println!("{common} peer=subdiv threads={t} mode={mode} median_s={:.6}", median(samples));
            }
            for (mode, samples) in &theirs {
                println!("{common} peer=osd threads=1 mode={mode} median_s={:.6}", median(samples));
            }
        }
    }
    Ok(())
}

/// One sample of each of `modes` (see the module docs).
fn measure(
    mesh: &Mesh,
    builtin: Builtin,
    levels: usize,
    modes: &[&'static str],
) -> Result<Vec<(&'static str, f64)>, String> {
    let scheme = builtin.scheme();
    let options = RefineOptions::DEFAULT;
    let split = scheme.split().primal().ok_or_else(|| format!("{builtin:?} has no primal split"))?;
    let mut out = Vec::new();
    for &mode in modes {
        let seconds = match mode {
            "refine" => sample(|| refine_uniform(mesh, scheme, levels, &options).map(|m| m.face_count()))?,
            "topology" => sample(|| {
                let mut current = mesh.clone();
                for _ in 0..levels {
                    let count = split.child_vertex_count(&current);
                    current = current.split(split, vec![glam::DVec3::ZERO; count], subdiv::mesh::Parallelism::DEFAULT);
                }
                Ok::<_, String>(current.face_count())
            })?,
            "stencils" => sample(|| Refiner::new(mesh, scheme, levels, &options).map(|r| r.levels().len()))?,
            "stencil_table" => {
                sample(|| Refiner::new(mesh, scheme, levels, &options).map(|r| r.stencil_table().weight_count()))?
            }
            "stencil_table_apply" => {
                let table = Refiner::new(mesh, scheme, levels, &options).map_err(|e| e.to_string())?.stencil_table();
                let mut values = Vec::new();
                sample(|| {
                    table.apply(mesh.positions(), &mut values);
                    Ok::<_, String>(values.len())
                })?
            }
            _ => {
                let refiner = Refiner::new(mesh, scheme, levels, &options).map_err(|e| e.to_string())?;
                let (mut values, mut scratch) = (Vec::new(), Vec::new());
                sample(|| {
                    refiner.interpolate(mesh.positions(), &mut values, &mut scratch);
                    Ok::<_, String>(values.len())
                })?
            }
        };
        out.push((mode, seconds));
    }
    Ok(out)
}

/// One sample of fallible `work`, after a warm-up run (which also reports its error).
fn sample<T, E: std::fmt::Display>(mut work: impl FnMut() -> Result<T, E>) -> Result<f64, String> {
    std::hint::black_box(work().map_err(|e| e.to_string())?);
    // The warm-up succeeded, and the work is the same each time.
    Ok(bench_args::sample(|| {
        std::hint::black_box(work().ok());
    }))
}

/// OpenSubdiv's `Far` through the peer harness: `(mode, seconds)` of each line it prints.
fn osd_bench(osd: &Path, mesh: &Path, builtin: Builtin, level: usize) -> Result<Vec<(String, f64)>, String> {
    let scheme = if builtin == Builtin::Loop { "loop" } else { "catmark" };
    let out = Command::new(osd)
        .arg(mesh)
        .args(["--scheme", scheme, "--runs", "3", "refine", &level.to_string()])
        .output()
        .map_err(|e| format!("{}: {e}", osd.display()))?;
    if !out.status.success() {
        return Err(format!("{} on {}: {}", osd.display(), mesh.display(), String::from_utf8_lossy(&out.stderr)));
    }
    let field = |line: &str, key: &str| line.split_whitespace().find_map(|kv| kv.strip_prefix(key).map(str::to_string));
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|line| {
            let mode = field(line, "mode=")?;
            let seconds = field(line, "median_s=").or_else(|| field(line, "seconds="))?.parse().ok()?;
            Some((mode, seconds))
        })
        .collect())
}
