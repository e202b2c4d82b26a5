//! `cargo xtask same-output --before OLD/subdiv [--after NEW/subdiv]`: runs the README's
//! commands with two builds of `subdiv` on the cube, valence56, spot_control_mesh and the
//! built-in model, and compares the files they write byte for byte (a refactoring must not
//! change a bit of them). `--after` defaults to this checkout's release build (built first, into
//! `CARGO_TARGET_DIR` if set, and copied before use).
//! Prints one line per command and fails naming the first file that differs.

use std::path::{Path, PathBuf};
use std::process::Command;

const USAGE: &str = "usage: cargo xtask same-output --before OLD/subdiv [--after NEW/subdiv]";

/// The meshes, relative to the shared folder (`None`: the built-in model).
const MESHES: [Option<&str>; 4] = [
    None,
    Some("peers/osd/meshes/cube.obj"),
    Some("peers/osd/meshes/valence56.obj"),
    Some("testdata/meshes/keenan/spot_control_mesh.obj"),
];

/// The commands after `subdiv` (the mesh goes after the subcommand), and the file each writes.
const COMMANDS: [(&[&str], &str); 6] = [
    (&["tessellate"], "default.glb"),
    (&["tessellate", "--rate", "16"], "rate16.obj"),
    (&["tessellate", "--pixels", "4", "--camera", "0,-5,2,0,0,0,0,0,1,45", "--viewport", "1920,1080"], "pixels.glb"),
    (&["tessellate", "--tolerance", "2e-2", "--relative"], "tolerance.glb"),
    (&["tessellate", "--method", "quadtree", "--tolerance", "1e-2", "--relative"], "quadtree.obj"),
    (&["eval", "--grid", "8"], "eval.csv"),
];

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    let (mut before, mut after) = (None, None);
    let mut rest = args.iter();
    while let Some(a) = rest.next() {
        let value = rest.next().ok_or_else(|| format!("{a} needs a value; {USAGE}"))?;
        match a.as_str() {
            "--before" => before = Some(PathBuf::from(value)),
            "--after" => after = Some(PathBuf::from(value)),
            _ => return Err(format!("unknown option {a:?}; {USAGE}")),
        }
    }
    let before = before.ok_or_else(|| USAGE.to_string())?;
    let work = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    let after = match after {
        Some(after) => after,
        None => crate::release_cli(work.path())?,
    };
    let shared = crate::shared_dir();
    let (mut compared, mut skipped) = (0, 0);
    for mesh in MESHES {
        let mesh_path = mesh.map(|m| shared.join(m));
        if let Some(path) = &mesh_path
            && !path.is_file()
        {
            return Err(format!("{}: missing (SUBDIV_SHARED names the shared folder)", path.display()));
        }
        let name = mesh.map_or("built-in", |m| m.rsplit('/').next().unwrap_or(m));
        for (command, file) in COMMANDS {
            let outputs: Vec<Result<Vec<u8>, String>> = [&before, &after]
                .iter()
                .enumerate()
                .map(|(k, bin)| output(bin, command, mesh_path.as_deref(), &work.path().join(format!("{k}-{file}"))))
                .collect();
            let line = format!("{name}: subdiv {} -o {file}", command.join(" "));
            match (&outputs[0], &outputs[1]) {
                (Ok(a), Ok(b)) if a == b => {
                    println!("same      {line} ({} bytes)", a.len());
                    compared += 1;
                }
                (Ok(a), Ok(b)) => {
                    return Err(format!(
                        "{line}: {} bytes before, {} after, first difference at byte {}",
                        a.len(),
                        b.len(),
                        first_difference(a, b)
                    ));
                }
                // A command the old build refuses must be refused by the new one too.
                (Err(a), Err(_)) => {
                    println!("refused   {line} (both: {a})");
                    skipped += 1;
                }
                (Err(e), Ok(_)) => return Err(format!("{line}: before failed ({e}), after succeeded")),
                (Ok(_), Err(e)) => return Err(format!("{line}: after failed ({e})")),
            }
        }
    }
    println!("same-output: {compared} outputs byte-identical, {skipped} refused by both builds");
    Ok(())
}

/// Runs `bin command [mesh] -o out` and reads `out`.
fn output(bin: &Path, command: &[&str], mesh: Option<&Path>, out: &Path) -> Result<Vec<u8>, String> {
    let mut cmd = Command::new(bin);
    cmd.arg(command[0]);
    if let Some(mesh) = mesh {
        cmd.arg(mesh);
    }
    cmd.args(&command[1..]).arg("-o").arg(out);
    let result = cmd.output().map_err(|e| format!("cannot run {}: {e}", bin.display()))?;
    if !result.status.success() {
        return Err(String::from_utf8_lossy(&result.stderr).trim().to_string());
    }
    std::fs::read(out).map_err(|e| format!("{}: {e}", out.display()))
}

fn first_difference(a: &[u8], b: &[u8]) -> usize {
    a.iter().zip(b).position(|(x, y)| x != y).unwrap_or(a.len().min(b.len()))
}
