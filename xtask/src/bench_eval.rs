//! `cargo xtask bench eval --mode cold [--mesh M]... [--grid N] [--method M]...`: what a
//! user's first `subdiv eval MESH --grid N` meets. Each sample is a new process of the release
//! CLI on one thread: its whole wall time (what `/usr/bin/time` says, the measure) and
//! its own `in T s` (after the mesh is read). With `SUBDIV_OSD_LIMIT` naming the peer harness's
//! `osd_limit`, one `osd_limit MESH --grid N` process (Bfr per face, exact vertex limits) is
//! timed the same way in each round, alternated with ours. Medians of [`COLD_ROUNDS`].
//!
//! Without `--mode cold` the criterion eval bench runs (`benches/`), as before.

use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use crate::bench_args::median;

/// Rounds per mesh and method.
const COLD_ROUNDS: usize = 5;

/// The default meshes (`../shared/testdata/meshes`), besides the built-in model: the two the
/// issue names for 50 ms, the car for 150 ms, and Loop on a triangulated mesh for 1 s.
const MESHES: [&str; 3] =
    ["keenan/spot_control_mesh.obj", "opensubdiv/catmark_car.obj", "keenan/spot_triangulated.obj"];

const METHODS: [&str; 3] = ["auto", "eigen", "stencil"];

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    let usage = "usage: cargo xtask bench eval [--mode cold [--mesh M]... [--grid N] [--method auto|eigen|stencil]...]";
    let (mut cold, mut meshes, mut grid, mut methods) = (false, Vec::new(), 4u32, Vec::new());
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        let mut value = || rest.next().ok_or_else(|| format!("{a} needs a value; {usage}"));
        match a.as_str() {
            "--mode" => match value()?.as_str() {
                "cold" => cold = true,
                other => return Err(format!("unknown mode {other:?}; {usage}")),
            },
            "--mesh" => meshes.push(PathBuf::from(value()?)),
            "--grid" => grid = value()?.parse().map_err(|e| format!("--grid: {e}"))?,
            "--method" => {
                let m = value()?;
                if !METHODS.contains(&m.as_str()) {
                    return Err(format!("unknown method {m:?}; {usage}"));
                }
                methods.push(m.clone());
            }
            other => return Err(format!("unknown option {other:?}; {usage}")),
        }
    }
    if !cold {
        if meshes.is_empty() && methods.is_empty() {
            return crate::bench(Some("eval"));
        }
        return Err(format!("--mesh and --method go with --mode cold; {usage}"));
    }
    if meshes.is_empty() {
        let dir = crate::shared_dir().join("testdata/meshes");
        meshes = MESHES.iter().map(|m| dir.join(m)).collect();
    }
    if methods.is_empty() {
        methods = METHODS.iter().map(|m| m.to_string()).collect();
    }
    let peer = std::env::var_os("SUBDIV_OSD_LIMIT").map(PathBuf::from);
    let work = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    let cli = crate::release_cli(work.path())?;
    let builtin = work.path().join("built-in.obj");
    subdiv::io::write_obj(&builtin, &subdiv::mesh::shapes::default_model()).map_err(|e| e.to_string())?;
    let out = work.path().join("out.csv");
    for path in std::iter::once(&builtin).chain(&meshes) {
        let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
        // The scheme the comparisons and the sweep give the mesh (Loop for all-triangle ones).
        let soup = subdiv::io::load(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let scheme = subdiv_testkit::opensubdiv::scheme_of(&name, &soup).0.name();
        let loop_ = scheme == "loop";
        'methods: for method in &methods {
            let (mut wall, mut own, mut theirs) = (Vec::new(), Vec::new(), Vec::new());
            for _ in 0..COLD_ROUNDS {
                let mut ours = Command::new(&cli);
                ours.arg("eval").arg(path).args(["--grid", &grid.to_string(), "--method", method, "--scheme", scheme]);
                // A method may refuse a mesh by design (`eigen` and boundary patches): said, and
                // the next method.
                let (seconds, stderr) = match timed(ours.arg("-o").arg(&out).env("RAYON_NUM_THREADS", "1"), &name) {
                    Ok(run) => run,
                    Err(refusal) => {
                        let last = refusal.lines().last().unwrap_or_default().replace('"', "'");
                        println!("bench=eval mode=cold mesh={name} grid={grid} method={method} refused=\"{last}\"");
                        continue 'methods;
                    }
                };
                wall.push(seconds);
                let t = crate::bench_args::cli_seconds(&stderr);
                own.push(t.ok_or_else(|| format!("subdiv eval {name}: no `in T s` in {stderr}"))?);
                if let Some(osd) = &peer {
                    let mut limit = Command::new(osd);
                    limit.arg(path).args(["--grid", &grid.to_string(), "--out"]).arg(work.path().join("osd.csv"));
                    if loop_ {
                        limit.args(["--scheme", "loop"]);
                    }
                    theirs.push(timed(limit.env("OMP_NUM_THREADS", "1"), &name)?.0);
                }
            }
            let theirs =
                if theirs.is_empty() { String::new() } else { format!(" osd_limit_process_s={:.4}", median(&theirs)) };
            println!(
                "bench=eval mode=cold mesh={name} grid={grid} method={method} threads=1 rounds={COLD_ROUNDS} \
                 process_s={:.4} own_s={:.4}{theirs}",
                median(&wall),
                median(&own)
            );
        }
    }
    Ok(())
}

/// Runs `command`, its wall time and standard error; an error if it fails.
fn timed(command: &mut Command, name: &str) -> Result<(f64, String), String> {
    let start = Instant::now();
    let run = command.output().map_err(|e| format!("{name}: {e}"))?;
    let seconds = start.elapsed().as_secs_f64();
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    if !run.status.success() {
        return Err(format!("{name}: {stderr}"));
    }
    Ok((seconds, stderr))
}
