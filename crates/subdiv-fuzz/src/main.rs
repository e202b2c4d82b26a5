//! `subdiv-fuzz`: the child process `cargo xtask fuzz` runs, which bounds what the library
//! cannot catch itself: time per input (a watchdog thread). Memory is bounded by the parent,
//! which polls the child's resident memory and kills it past its limit.
//!
//! `subdiv-fuzz run TARGET SECONDS SEED CURRENT` fuzzes and prints a one-line JSON report;
//! `subdiv-fuzz exec TARGET FILE` runs one input. `run` writes each input to `CURRENT` before
//! running it, so that the parent knows which input a crash or time-out was; status 3 on a
//! panic, 4 on a time-out.

// A command-line child process: its report goes to stdout, its reasons to stderr.
#![allow(clippy::print_stdout, clippy::print_stderr)]
// The coverage instrumentation's entry point (below) is the one unsafe item of the workspace.
#![allow(unsafe_code)]

use std::process::ExitCode;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use subdiv_fuzz::{Target, driver};

/// The most processor time one input may take. Processor time, not wall time, so that a
/// fuzz run sharing the machine with a build does not report the build's time as a hang.
const TIME_LIMIT: Duration = Duration::from_secs(10);

/// The most wall time one input may take (one that blocks instead of computing).
const WALL_LIMIT: Duration = Duration::from_secs(120);

/// When the current input started, in milliseconds of wall time since the watchdog's epoch
/// (0: none), and the process's processor time then.
static STARTED: AtomicU64 = AtomicU64::new(0);
static STARTED_CPU: AtomicU64 = AtomicU64::new(0);

/// This process's processor time in milliseconds ([`driver::processor_time`]).
fn cpu_millis() -> Option<u64> {
    driver::processor_time().map(|t| t.as_millis() as u64)
}

fn watchdog(epoch: Instant) {
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_millis(100));
            let started = STARTED.load(Ordering::Relaxed);
            if started == 0 {
                continue;
            }
            let wall = epoch.elapsed().as_millis() as u64 - started;
            // Without a processor clock, the wall clock is the measure.
            let cpu = cpu_millis().map_or(wall, |now| now.saturating_sub(STARTED_CPU.load(Ordering::Relaxed)));
            if cpu > TIME_LIMIT.as_millis() as u64 || wall > WALL_LIMIT.as_millis() as u64 {
                eprintln!("subdiv-fuzz: an input ran past {} s ({cpu} ms of processor time)", TIME_LIMIT.as_secs());
                std::process::exit(4);
            }
        }
    });
}

/// Marks the start of an input for the watchdog, at the process's processor time `cpu`.
fn start(epoch: Instant, cpu: Option<Duration>) {
    STARTED_CPU.store(cpu.map_or(0, |t| t.as_millis() as u64), Ordering::Relaxed);
    STARTED.store((epoch.elapsed().as_millis() as u64).max(1), Ordering::Relaxed);
}

/// SanitizerCoverage's registration of an object's 8-bit counters (`[start, stop)`), called
/// by the constructors of code built with `subdiv_fuzz::coverage::RUSTFLAGS`. It lives in the
/// binary, not the library, so that the linker finds it whichever archive refers to it.
#[unsafe(no_mangle)]
pub extern "C" fn __sanitizer_cov_8bit_counters_init(start: *mut u8, stop: *mut u8) {
    subdiv_fuzz::coverage::register(start as usize, stop as usize);
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let target = args.get(1).and_then(|t| Target::from_name(t));
    let (Some(command), Some(target)) = (args.first(), target) else {
        eprintln!("usage: subdiv-fuzz run TARGET SECONDS SEED CURRENT | exec TARGET FILE");
        return ExitCode::from(2);
    };
    // The panic message goes to stderr once, from the driver's report, not from the hook.
    std::panic::set_hook(Box::new(|_| {}));
    let epoch = Instant::now();
    watchdog(epoch);
    match (command.as_str(), &args[2..]) {
        ("run", [seconds, seed, current]) => {
            let (Ok(seconds), Ok(seed)) = (seconds.parse::<u64>(), seed.parse::<u64>()) else {
                eprintln!("subdiv-fuzz: SECONDS and SEED are integers");
                return ExitCode::from(2);
            };
            let file = Mutex::new(std::fs::File::create(current).expect("the CURRENT file can be created"));
            let report = driver::fuzz(target, Duration::from_secs(seconds), seed, |input, cpu| {
                use std::io::{Seek, Write};
                let mut file = file.lock().expect("one thread writes");
                let _ = file.set_len(0);
                let _ = file.rewind();
                let _ = file.write_all(input);
                start(epoch, cpu);
            });
            STARTED.store(0, Ordering::Relaxed);
            println!(
                "{{\"target\":\"{}\",\"executions\":{},\"corpus\":{},\"outcomes\":{},\"edges\":{},\"slowest_ms\":{},\"slowest_cpu_ms\":{},\"finding\":{}}}",
                target.name(),
                report.executions,
                report.corpus,
                report.outcomes,
                report.edges,
                report.slowest.as_millis(),
                report.slowest_cpu.as_millis(),
                report.finding.as_ref().map_or("null".to_string(), |(_, m)| format!("{m:?}")),
            );
            if report.finding.is_some() { ExitCode::from(3) } else { ExitCode::SUCCESS }
        }
        ("exec", [file]) => {
            let input = std::fs::read(file).expect("the input file can be read");
            start(epoch, driver::processor_time());
            if driver::panics(target, &input) { ExitCode::from(3) } else { ExitCode::SUCCESS }
        }
        _ => {
            eprintln!("usage: subdiv-fuzz run TARGET SECONDS SEED CURRENT | exec TARGET FILE");
            ExitCode::from(2)
        }
    }
}
