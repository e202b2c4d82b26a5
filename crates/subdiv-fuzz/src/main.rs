//! `subdiv-fuzz`: the child process `cargo xtask fuzz` runs, which bounds what the library
//! cannot catch itself: time per input (a watchdog thread). Memory is bounded by the parent,
//! which starts it under an address-space limit (`ulimit -v`), so that an allocation past it
//! fails and aborts the child.
//!
//! `subdiv-fuzz run TARGET SECONDS SEED CURRENT` fuzzes and prints a one-line JSON report;
//! `subdiv-fuzz exec TARGET FILE` runs one input. `run` writes each input to `CURRENT` before
//! running it, so that the parent knows which input a crash or time-out was; status 3 on a
//! panic, 4 on a time-out.

// A command-line child process: its report goes to stdout, its reasons to stderr.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::process::ExitCode;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use subdiv_fuzz::{Target, driver};

/// The longest one input may run.
const TIME_LIMIT: Duration = Duration::from_secs(10);

/// When the current input started, in milliseconds since the watchdog's epoch (0: none).
static STARTED: AtomicU64 = AtomicU64::new(0);

fn watchdog(epoch: Instant) {
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_millis(100));
            let started = STARTED.load(Ordering::Relaxed);
            if started != 0 && epoch.elapsed().as_millis() as u64 - started > TIME_LIMIT.as_millis() as u64 {
                eprintln!("subdiv-fuzz: an input ran past {} s", TIME_LIMIT.as_secs());
                std::process::exit(4);
            }
        }
    });
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
    let now = move || (epoch.elapsed().as_millis() as u64).max(1);
    match (command.as_str(), &args[2..]) {
        ("run", [seconds, seed, current]) => {
            let (Ok(seconds), Ok(seed)) = (seconds.parse::<u64>(), seed.parse::<u64>()) else {
                eprintln!("subdiv-fuzz: SECONDS and SEED are integers");
                return ExitCode::from(2);
            };
            let file = Mutex::new(std::fs::File::create(current).expect("the CURRENT file can be created"));
            let report = driver::fuzz(target, Duration::from_secs(seconds), seed, |input| {
                use std::io::{Seek, Write};
                let mut file = file.lock().expect("one thread writes");
                let _ = file.set_len(0);
                let _ = file.rewind();
                let _ = file.write_all(input);
                STARTED.store(now(), Ordering::Relaxed);
            });
            STARTED.store(0, Ordering::Relaxed);
            println!(
                "{{\"target\":\"{}\",\"executions\":{},\"corpus\":{},\"outcomes\":{},\"slowest_ms\":{},\"finding\":{}}}",
                target.name(),
                report.executions,
                report.corpus,
                report.outcomes,
                report.slowest.as_millis(),
                report.finding.as_ref().map_or("null".to_string(), |(_, m)| format!("{m:?}")),
            );
            if report.finding.is_some() { ExitCode::from(3) } else { ExitCode::SUCCESS }
        }
        ("exec", [file]) => {
            let input = std::fs::read(file).expect("the input file can be read");
            STARTED.store(now(), Ordering::Relaxed);
            if driver::panics(target, &input) { ExitCode::from(3) } else { ExitCode::SUCCESS }
        }
        _ => {
            eprintln!("usage: subdiv-fuzz run TARGET SECONDS SEED CURRENT | exec TARGET FILE");
            ExitCode::from(2)
        }
    }
}
