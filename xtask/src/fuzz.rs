//! `cargo xtask fuzz [--seconds N] [--target T]... [--seed S] [--debug | --coverage]`: every fuzz
//! target (or those named) for N seconds each (default 60; a release build unless `--debug`,
//! which CI's short pass takes because its tests have built the debug dependencies already, or
//! `--coverage`: a release build instrumented for edge coverage, `subdiv_fuzz::coverage`, in
//! `target/fuzz-coverage`, whose runs keep the inputs that reach new edges), each in a child
//! process whose watchdog ends an input
//! running past 10 s and whose resident memory this process watches (killed past 2 GiB; an
//! address-space limit does not work: faer reserves a large gemm buffer per thread).
//! A finding is reduced (each candidate run in a fresh child) and kept as
//! `crates/subdiv-fuzz/reproducers/<target>/<hash>`, which `cargo test -p subdiv-fuzz` replays.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use subdiv_fuzz::Target;

/// The most resident memory a fuzz child may hold.
const MEMORY_LIMIT_KIB: u64 = 2 << 20;

/// How long the reducer may work on one finding.
const REDUCE_BUDGET: Duration = Duration::from_secs(120);

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    let mut seconds = 60u64;
    let mut seed = 1u64;
    let mut targets = Vec::new();
    let mut debug = false;
    let mut coverage = false;
    let mut rest = args.iter();
    while let Some(arg) = rest.next() {
        if arg == "--debug" || arg == "--coverage" {
            debug |= arg == "--debug";
            coverage |= arg == "--coverage";
            continue;
        }
        let value = rest.next().ok_or_else(|| format!("{arg} needs a value"))?;
        match arg.as_str() {
            "--seconds" => seconds = value.parse().map_err(|_| format!("--seconds {value}: not a number"))?,
            "--seed" => seed = value.parse().map_err(|_| format!("--seed {value}: not a number"))?,
            "--target" => targets.push(Target::from_name(value).ok_or_else(|| {
                let known: Vec<&str> = Target::ALL.iter().map(|t| t.name()).collect();
                format!("unknown target {value:?}; known: {}", known.join(", "))
            })?),
            _ => return Err(format!("unknown argument {arg:?}")),
        }
    }
    if targets.is_empty() {
        targets = Target::ALL.to_vec();
    }
    if debug && coverage {
        return Err("--debug and --coverage are two different builds: pick one".into());
    }
    let binary = if coverage {
        instrumented_build()?
    } else {
        let (profile, build): (&str, &[&str]) = if debug {
            ("debug", &["build", "-p", "subdiv-fuzz"])
        } else {
            ("release", &["build", "--release", "-p", "subdiv-fuzz"])
        };
        crate::cargo(build)?;
        crate::root().join("target").join(profile).join("subdiv-fuzz")
    };
    let scratch = std::env::temp_dir().join(format!("subdiv-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).map_err(|e| format!("{}: {e}", scratch.display()))?;
    let mut findings = Vec::new();
    for target in targets {
        let current = scratch.join(format!("{}.current", target.name()));
        let started = Instant::now();
        let mut command = child(&binary);
        command.args(["run", target.name(), &seconds.to_string(), &seed.to_string()]).arg(&current);
        let run = watched(command)?;
        println!(
            "{} ({:.0} s, peak {} MiB, {}): {}",
            target.name(),
            started.elapsed().as_secs_f64(),
            run.peak_kib >> 10,
            run.status,
            run.stdout.trim()
        );
        if run.ok {
            continue;
        }
        let why = run.why();
        let input = std::fs::read(&current).map_err(|e| format!("{}: {e}", current.display()))?;
        let reduced = reduce(&binary, target, &input, &scratch)?;
        let kept = keep(target, &reduced)?;
        println!("  finding ({why}), reduced from {} to {} bytes: {}", input.len(), reduced.len(), kept.display());
        findings.push(kept);
    }
    let _ = std::fs::remove_dir_all(&scratch);
    if findings.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} finding(s), kept as reproducers: fix them, and commit the files as regression tests",
            findings.len()
        ))
    }
}

/// The fuzz binary instrumented for edge coverage: built for the host named as an explicit
/// target (so that `RUSTFLAGS` reach the binary and its crates, not build scripts or procedural
/// macros, which rustc loads without the instrumentation's entry point), in a target folder of
/// its own (the flags rebuild every crate).
fn instrumented_build() -> Result<PathBuf, String> {
    let version = Command::new("rustc").arg("-vV").output().map_err(|e| format!("cannot run rustc: {e}"))?;
    let version = String::from_utf8_lossy(&version.stdout).into_owned();
    let host =
        version.lines().find_map(|l| l.strip_prefix("host: ")).ok_or("`rustc -vV` names no host")?.trim().to_string();
    let folder = crate::root().join("target").join("fuzz-coverage");
    let args = ["build", "--release", "-p", "subdiv-fuzz", "--target", &host];
    eprintln!("$ RUSTFLAGS=\"{}\" cargo {}", subdiv_fuzz::coverage::RUSTFLAGS, args.join(" "));
    let status = Command::new(env!("CARGO"))
        .args(args)
        .env("RUSTFLAGS", subdiv_fuzz::coverage::RUSTFLAGS)
        .env("CARGO_TARGET_DIR", &folder)
        .current_dir(crate::root())
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err(format!("the instrumented build failed ({status})"));
    }
    Ok(folder.join(host).join("release").join("subdiv-fuzz"))
}

/// The fuzz binary, on one thread, without backtraces.
fn child(binary: &Path) -> Command {
    let mut command = Command::new(binary);
    command.env("RAYON_NUM_THREADS", "1").env("RUST_BACKTRACE", "0");
    command
}

/// How a watched child ended.
struct Run {
    ok: bool,
    status: String,
    stdout: String,
    stderr: String,
    peak_kib: u64,
    over_memory: bool,
}

impl Run {
    fn why(&self) -> String {
        if self.over_memory {
            return format!("resident memory past {} MiB", MEMORY_LIMIT_KIB >> 10);
        }
        let last = self.stderr.lines().last().unwrap_or_default();
        format!("{}: {last}", self.status)
    }
}

/// Runs `command`, polling its resident memory (Linux's `/proc`) and killing it past
/// [`MEMORY_LIMIT_KIB`].
fn watched(mut command: Command) -> Result<Run, String> {
    use std::io::Read;
    use std::process::Stdio;
    let mut process = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot run the fuzz binary: {e}"))?;
    let (mut out, mut err) = (process.stdout.take().expect("piped"), process.stderr.take().expect("piped"));
    let reader = std::thread::spawn(move || {
        let (mut o, mut e) = (String::new(), String::new());
        let _ = out.read_to_string(&mut o);
        let _ = err.read_to_string(&mut e);
        (o, e)
    });
    let status_file = format!("/proc/{}/status", process.id());
    let (mut peak_kib, mut over_memory) = (0, false);
    let status = loop {
        if let Some(status) = process.try_wait().map_err(|e| e.to_string())? {
            break status;
        }
        let rss = std::fs::read_to_string(&status_file).ok().and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmRSS:"))
                .and_then(|v| v.split_whitespace().next()?.parse::<u64>().ok())
        });
        peak_kib = peak_kib.max(rss.unwrap_or(0));
        if peak_kib > MEMORY_LIMIT_KIB && !over_memory {
            over_memory = true;
            let _ = process.kill();
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let (stdout, stderr) = reader.join().map_err(|_| "the output reader failed".to_string())?;
    Ok(Run { ok: status.success() && !over_memory, status: status.to_string(), stdout, stderr, peak_kib, over_memory })
}

/// The smallest input found that still fails in a fresh child, within [`REDUCE_BUDGET`].
fn reduce(binary: &Path, target: Target, input: &[u8], scratch: &Path) -> Result<Vec<u8>, String> {
    let candidate = scratch.join(format!("{}.candidate", target.name()));
    let started = Instant::now();
    let reduced = subdiv_fuzz::reduce::reduce(input, |bytes| {
        if started.elapsed() > REDUCE_BUDGET || std::fs::write(&candidate, bytes).is_err() {
            return false;
        }
        let mut command = child(binary);
        command.args(["exec", target.name()]).arg(&candidate);
        watched(command).is_ok_and(|run| !run.ok)
    });
    Ok(reduced)
}

/// Writes `input` as a reproducer of `target`, named by its hash.
fn keep(target: Target, input: &[u8]) -> Result<PathBuf, String> {
    let folder = crate::root().join("crates/subdiv-fuzz/reproducers").join(target.name());
    std::fs::create_dir_all(&folder).map_err(|e| format!("{}: {e}", folder.display()))?;
    let path = folder.join(format!("{:016x}", subdiv_fuzz::driver::hash(input)));
    std::fs::write(&path, input).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}
