//! `cargo xtask`: the project's build system (rust-analyzer style).
//!
//! - `cargo xtask ci` runs what `.ci/run` runs after installing packages: `cargo fmt --check`,
//!   clippy with warnings denied, and the README's test command.
//! - `cargo xtask bench [NAME]` runs the criterion benches (all, or the one named: `topology`,
//!   `stencil` or `eval`) and prints one `key=value` line per measurement, in the units of DESIGN.md.
//! - `cargo xtask bench refine [--mesh M]… [--levels K]… [--threads T]… [--mode MODE]… [--rounds R]
//!   [--channels yes|no]` measures
//!   uniform refinement (topology and positions, topology alone, stencils, stencil application)
//!   beside OpenSubdiv's `Far` when `SUBDIV_OSD_BENCH` names the harness's `osd_bench`,
//!   alternated in the same rounds.
//! - `cargo xtask bench tess [--mesh M]… [--rate N]… [--threads T]… [--mode MODE]… [--channels yes|no]…`
//!   measures dual-grid tessellation into welded flat buffers (default: the peer harness's
//!   torus_big, cube and valence56 at rates 8, 16, 32, on one thread and on all, without the
//!   meshes' texture coordinates), beside OpenSubdiv's Bfr when `SUBDIV_OSD_BENCH` names the
//!   harness's `osd_bench`; `--mode cold` runs fresh processes of the release CLI instead (the
//!   built-in model, spot, blub, the car and the bishop at rate 8, Bfr's per-face path beside).
//! - `cargo xtask bench eval --mode cold [--mesh M]… [--grid N] [--method M]…` times fresh
//!   `subdiv eval MESH --grid N` processes (whole and the CLI's own time; default: the built-in
//!   model, spot, the car and spot_triangulated, grid 4, every method), beside whole
//!   `osd_limit` processes when `SUBDIV_OSD_LIMIT` names the harness's `osd_limit`.
//! - `cargo xtask bench gpu [--mesh M]… [--rate N]… [--frames K]` measures milliseconds per
//!   animation frame to re-evaluate a tessellation on the GPU (default: the built-in model and
//!   a 100 000-face torus at rates 8 and 16), beside the CPU's animation path, with the
//!   adapter's name.
//! - `cargo xtask osd-refine PATH/TO/osd_refine` compares our uniform refinement with
//!   OpenSubdiv's on the shared corpus (levels 1 to 3), through the peer harness.
//! - `cargo xtask same-output --before OLD/subdiv [--after NEW/subdiv]` runs the README's
//!   commands with both builds on the cube, valence56, spot_control_mesh and the built-in model
//!   and checks that every file they write is byte-identical.
//! - `cargo xtask sweep [--seconds S]` runs `subdiv eval MESH --grid 4` and `subdiv tessellate
//!   MESH --rate 8` on every valid shared mesh, each a fresh process of the release build on one
//!   thread, and prints the slowest ten of each and every run over S seconds (default 1).
//! - `cargo xtask paper` prints every number of paper 000 we reproduce beside the paper's.
//! - `cargo xtask adaptive [--samples N] [--all]` prints paper 002's Table 1 for the quadtree
//!   tessellator (adaptive against uniform polygons, with the measured worst distance / ε on an
//!   N × N grid per face, default 67; 0 skips it). Run it in release.
//! - `cargo xtask tolerance [--mesh M]... [--relative R]` tessellates to a relative tolerance
//!   (default 1e-3) by both methods and prints, per mesh and method, the worst distance from
//!   `osd_limit --grid 16`'s points (`SUBDIV_OSD_LIMIT`) over ε, the triangles, the time and the
//!   uniform tessellation the same bound asks for — or the refusal.
//! - `cargo xtask rates` prints rational against dyadic rates (paper 000 §6): triangles of the
//!   cheapest dual-grid tessellations whose per-face rates provably meet ε, rates free or powers
//!   of two, on closed Catmull-Clark meshes of the shared corpus.
//! - `cargo xtask tables [--check]` regenerates the committed default stencil tables (or checks
//!   that they are current).

#![allow(clippy::print_stdout, clippy::print_stderr)]

mod adaptive;
mod bench_args;
mod bench_eval;
mod bench_gpu;
mod bench_refine;
mod bench_schemes;
mod bench_tess;
mod fuzz;
mod osd;
mod paper;
mod rates_table;
mod same_output;
mod sweep;
mod tables;
mod tolerance;

use std::path::{Path, PathBuf};

const USAGE: &str = "usage: cargo xtask ci | cargo xtask bench [topology|stencil|eval] | cargo xtask bench eval --mode cold [--mesh M]... [--grid N] [--method M]... | cargo xtask bench refine [--mesh M]... [--levels K]... [--threads T]... [--mode MODE]... [--rounds R] [--channels yes|no] | cargo xtask bench tess [--mesh M]... [--rate N]... [--threads T]... [--mode MODE]... [--channels yes|no]... | cargo xtask bench gpu [--mesh M]... [--rate N]... [--frames K] | cargo xtask bench schemes [--quads M] [--triangles M] [--grid N] [--rate R] | cargo xtask same-output --before OLD/subdiv [--after NEW/subdiv] | cargo xtask sweep [--seconds S] | cargo xtask fuzz [--seconds N] [--target T]... [--seed S] [--debug] | cargo xtask paper | cargo xtask rates | cargo xtask tolerance [--mesh M]... [--relative R] | cargo xtask adaptive [--samples N] [--all] | cargo xtask tables [--check] | cargo xtask osd-refine PATH/TO/osd_refine";
use std::process::{Command, ExitCode};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("ci") => ci(),
        Some("bench") if args.get(1).is_some_and(|a| a == "tess") => bench_tess::run(&args[2..]),
        Some("bench") if args.get(1).is_some_and(|a| a == "gpu") => bench_gpu::run(&args[2..]),
        Some("bench") if args.get(1).is_some_and(|a| a == "refine") => bench_refine::run(&args[2..]),
        Some("bench") if args.get(1).is_some_and(|a| a == "eval") => bench_eval::run(&args[2..]),
        Some("bench") if args.get(1).is_some_and(|a| a == "schemes") => bench_schemes::run(&args[2..]),
        Some("bench") => bench(args.get(1).map(String::as_str)),
        Some("same-output") => same_output::run(&args[1..]),
        Some("sweep") => sweep::run(&args[1..]),
        Some("fuzz") => fuzz::run(&args[1..]),
        Some("paper") => paper::run(),
        Some("rates") => rates_table::run(),
        Some("tolerance") => tolerance::run(&args[1..]),
        Some("adaptive") => {
            let mut samples = 67;
            let mut all = false;
            let mut rest = args[1..].iter();
            let mut bad = None;
            while let Some(a) = rest.next() {
                match (a.as_str(), rest.clone().next().map(|n| n.parse::<u32>())) {
                    ("--all", _) => all = true,
                    ("--samples", Some(Ok(n))) => {
                        samples = n;
                        rest.next();
                    }
                    _ => bad = Some(a.clone()),
                }
            }
            match bad {
                None => adaptive::run(samples, all),
                Some(a) => Err(format!("unknown option {a:?}; usage: cargo xtask adaptive [--samples N] [--all]")),
            }
        }
        Some("tables") => match args.get(1).map(String::as_str) {
            None => tables::run(false),
            Some("--check") => tables::run(true),
            Some(other) => Err(format!("unknown option {other:?}; usage: cargo xtask tables [--check]")),
        },
        Some("osd-refine") => match args.get(1) {
            Some(osd) => osd::run(Path::new(osd), &shared_dir().join("testdata/meshes"), &[1, 2, 3]),
            None => Err("usage: cargo xtask osd-refine PATH/TO/osd_refine".to_string()),
        },
        _ => Err(USAGE.to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("xtask: {message}");
            ExitCode::FAILURE
        }
    }
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("xtask lives in the workspace root").to_path_buf()
}

/// The shared folder: `SUBDIV_SHARED`, else `../shared` beside the workspace.
fn shared_dir() -> PathBuf {
    std::env::var_os("SUBDIV_SHARED").map_or_else(|| root().join("../shared"), PathBuf::from)
}

/// This checkout's release build of `subdiv`, built first (into `CARGO_TARGET_DIR` if set)
/// and copied into `folder` at once: a target folder shared with other checkouts may get
/// another build of it while the caller runs it.
fn release_cli(folder: &Path) -> Result<PathBuf, String> {
    cargo(&["build", "--release", "--quiet", "-p", "subdiv-cli"])?;
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root().join("target"), PathBuf::from);
    let built = target.join("release/subdiv");
    let copy = folder.join("subdiv-release");
    std::fs::copy(&built, &copy).map_err(|e| format!("{}: {e}", built.display()))?;
    Ok(copy)
}

fn cargo(args: &[&str]) -> Result<(), String> {
    eprintln!("$ cargo {}", args.join(" "));
    let status = Command::new(env!("CARGO"))
        .args(args)
        .current_dir(root())
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if status.success() { Ok(()) } else { Err(format!("`cargo {}` failed ({status})", args.join(" "))) }
}

fn ci() -> Result<(), String> {
    cargo(&["fmt", "--all", "--", "--check"])?;
    cargo(&["clippy", "--workspace", "--all-targets", "--", "-D", "warnings"])?;
    cargo(&["test", "--workspace"])
}

/// What each bench measures, for its `key=value` line: (bench target, criterion group).
const BENCHES: &[(&str, &str)] = &[("topology", "topology"), ("stencil", "stencil"), ("eval", "eval")];

fn bench(only: Option<&str>) -> Result<(), String> {
    let selected: Vec<_> = BENCHES.iter().filter(|(name, _)| only.is_none_or(|o| o == *name)).collect();
    if selected.is_empty() {
        return Err(format!("unknown bench {:?}; known: {:?}", only.unwrap_or_default(), BENCHES));
    }
    for (name, group) in selected {
        cargo(&["bench", "-p", "subdiv-benches", "--bench", name])?;
        report(group)?;
    }
    Ok(())
}

/// Prints `bench=… id=… median_s=…` for every measurement criterion saved for `group`.
fn report(group: &str) -> Result<(), String> {
    let dir = root().join("target/criterion").join(group);
    let mut ids: Vec<_> = std::fs::read_dir(&dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("new/estimates.json").is_file())
        .collect();
    ids.sort();
    for id in ids {
        let text = std::fs::read_to_string(id.join("new/estimates.json")).map_err(|e| e.to_string())?;
        let estimates: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
        let median_ns = estimates["median"]["point_estimate"].as_f64().ok_or("estimates.json has no median")?;
        let name = id.file_name().unwrap_or_default().to_string_lossy();
        let line = format!("bench={group} id={name} median_s={:.6} threads=1", median_ns * 1e-9);
        // Benches that set a throughput in elements report it per second too.
        let bench = std::fs::read_to_string(id.join("new/benchmark.json")).ok();
        let elements = bench
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .and_then(|b| b["throughput"]["Elements"].as_f64());
        match elements {
            Some(n) => println!("{line} elements_per_s={:.0}", n / (median_ns * 1e-9)),
            None => println!("{line}"),
        }
    }
    Ok(())
}
