//! `cargo xtask sweep [--seconds S]`: what a user meets on every shared mesh. Runs `subdiv eval
//! MESH --grid 4` and `subdiv tessellate MESH --rate 8` (`-o` into a temporary folder) on every
//! mesh of the shared corpus that builds, with the scheme the comparisons give it (`loop_` and
//! all-triangle meshes Loop, `bilinear_` bilinear, else Catmull-Clark), each in a fresh process
//! of this checkout's release build, on one thread (`RAYON_NUM_THREADS=1`). Prints the slowest
//! ten runs of each command (wall-clock seconds of the whole process), then every run that
//! failed or took longer than `S` seconds (default 1), and fails if there is one.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use subdiv::io::load;
use subdiv::mesh::Mesh;

const USAGE: &str = "usage: cargo xtask sweep [--seconds S]";

/// The commands after `subdiv` (the mesh comes after the subcommand) and their output file.
const COMMANDS: [(&[&str], &str); 2] =
    [(&["eval", "--grid", "4"], "eval.csv"), (&["tessellate", "--rate", "8"], "tess.glb")];

/// How many of the slowest runs of each command are printed.
const SLOWEST: usize = 10;

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    let mut limit = 1.0;
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        let value = rest.next().ok_or_else(|| format!("{a} needs a value; {USAGE}"))?;
        match a.as_str() {
            "--seconds" => {
                limit = value
                    .parse::<f64>()
                    .ok()
                    .filter(|s| *s > 0.0)
                    .ok_or_else(|| format!("--seconds {value}: not a duration"))?;
            }
            _ => return Err(format!("unknown option {a:?}; {USAGE}")),
        }
    }
    let work = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    let cli = crate::release_cli(work.path())?;
    let corpus = crate::shared_dir().join("testdata/meshes");
    let meshes = subdiv_testkit::obj_files(&corpus);
    if meshes.is_empty() {
        return Err(format!("{}: no meshes (SUBDIV_SHARED names the shared folder)", corpus.display()));
    }
    // (seconds, mesh, error) per command.
    let mut runs: Vec<Vec<(f64, String, Option<String>)>> = vec![Vec::new(); COMMANDS.len()];
    let mut skipped = 0;
    for path in &meshes {
        let name = path.strip_prefix(&corpus).unwrap_or(path).display().to_string();
        let Ok(soup) = load(path) else {
            skipped += 1;
            continue;
        };
        let file_name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let scheme = subdiv_testkit::opensubdiv::scheme_of(&file_name, &soup).0;
        if Mesh::build(soup).is_err() {
            // The corpus' invalid meshes are refused by design (the hostile-input tests).
            skipped += 1;
            continue;
        }
        for ((command, file), runs) in COMMANDS.iter().zip(&mut runs) {
            let (seconds, error) = timed(&cli, command, path, scheme.name(), &work.path().join(file))?;
            runs.push((seconds, name.clone(), error));
        }
    }
    let mut slow = Vec::new();
    for ((command, _), runs) in COMMANDS.iter().zip(&mut runs) {
        runs.sort_by(|a, b| b.0.total_cmp(&a.0));
        let total: f64 = runs.iter().map(|r| r.0).sum();
        println!(
            "subdiv {} MESH: {} meshes, {total:.1} s in all; the slowest {SLOWEST}:",
            command.join(" "),
            runs.len()
        );
        println!("| mesh | seconds |\n|---|---|");
        for (seconds, mesh, _) in runs.iter().take(SLOWEST) {
            println!("| {mesh} | {seconds:.3} |");
        }
        for (seconds, mesh, error) in runs.iter() {
            if error.is_some() || *seconds > limit {
                slow.push(format!(
                    "subdiv {} {mesh}: {seconds:.3} s{}",
                    command.join(" "),
                    error.as_deref().map_or(String::new(), |e| format!(", failed: {e}"))
                ));
            }
        }
    }
    println!("{} meshes, {skipped} skipped (not valid meshes)", meshes.len());
    if slow.is_empty() {
        println!("every run finished within {limit} s");
        Ok(())
    } else {
        Err(format!("{} runs failed or took longer than {limit} s:\n{}", slow.len(), slow.join("\n")))
    }
}

/// One fresh process of `cli COMMAND MESH --scheme SCHEME -o OUT`: its wall-clock seconds and,
/// if it failed, its last line of standard error.
fn timed(cli: &Path, command: &[&str], mesh: &Path, scheme: &str, out: &Path) -> Result<(f64, Option<String>), String> {
    let start = Instant::now();
    let output = Command::new(cli)
        .args(command)
        .arg(mesh)
        .args(["--scheme", scheme, "-o"])
        .arg(out)
        .env("RAYON_NUM_THREADS", "1")
        .output()
        .map_err(|e| format!("{}: {e}", cli.display()))?;
    let seconds = start.elapsed().as_secs_f64();
    let error = (!output.status.success()).then(|| {
        let stderr = String::from_utf8_lossy(&output.stderr);
        stderr.lines().last().unwrap_or("(no message)").to_string()
    });
    Ok((seconds, error))
}
