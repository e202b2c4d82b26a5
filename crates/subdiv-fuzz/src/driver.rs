//! Running a target on mutations of its corpus: an input joins the corpus when it reaches an
//! outcome no input reached before (the target's label of what happened), or, in a build
//! instrumented for [`Coverage`], a hit-count class of an edge counter that no input reached.

use std::collections::HashSet;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::{Duration, Instant};

use crate::Target;
use crate::coverage::Coverage;

/// What a fuzz run did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Report {
    /// Inputs run.
    pub executions: u64,
    /// Inputs kept: the seeds and those that reached a new outcome.
    pub corpus: usize,
    /// Distinct outcomes reached (counted again after the set is forgotten at
    /// [`MAX_OUTCOMES`]).
    pub outcomes: usize,
    /// Edge counters that fired (0 in a build without coverage instrumentation).
    pub edges: usize,
    /// The slowest input's wall time (on a busy machine more than its processor time).
    pub slowest: Duration,
    /// The most processor time one input took (Linux; zero elsewhere): what the fuzz binary's
    /// watchdog limits.
    pub slowest_cpu: Duration,
    /// The first input that panicked, with the panic's message.
    pub finding: Option<(Vec<u8>, String)>,
}

/// Runs `target` for `duration` on mutations of its seeds, from the random `seed`, calling
/// `before(input, cpu)` before each run, `cpu` being the process's [`processor_time`] then (the
/// fuzz binary records the input there, so that a crash
/// or a time-out it cannot catch is still reported). Stops at the first panic.
pub fn fuzz(target: Target, duration: Duration, seed: u64, mut before: impl FnMut(&[u8], Option<Duration>)) -> Report {
    let mut random = Random(seed ^ 0x9e37_79b9_7f4a_7c15);
    let mut corpus = target.seeds();
    let seeds = corpus.len();
    // Outcomes by hash: a fuzz run reaches millions.
    let mut outcomes: HashSet<u64> = HashSet::new();
    let mut outcomes_seen = 0usize;
    let mut report = Report::default();
    let mut coverage = Coverage::new();
    let start = Instant::now();
    let mut next = 0usize;
    while start.elapsed() < duration {
        // The seeds as they are first, then mutations.
        let input = if next < corpus.len() {
            next += 1;
            corpus[next - 1].clone()
        } else {
            let base = &corpus[random.below(corpus.len())];
            mutate(&mut random, base, &corpus)
        };
        let cpu = processor_time();
        before(&input, cpu);
        coverage.reset();
        let run = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| target.run(&input)));
        let new_edges = coverage.observe();
        report.slowest = report.slowest.max(run.elapsed());
        if let (Some(before), Some(after)) = (cpu, processor_time()) {
            report.slowest_cpu = report.slowest_cpu.max(after.saturating_sub(before));
        }
        report.executions += 1;
        match outcome {
            Ok(label) => {
                if outcomes.len() == MAX_OUTCOMES {
                    // Forget them all: the corpus stays, and its inputs are new again.
                    outcomes_seen += outcomes.len();
                    outcomes.clear();
                }
                let new_outcome = outcomes.insert(hash(label.as_bytes()));
                if (new_outcome || new_edges) && next >= corpus.len() {
                    if corpus.len() < MAX_CORPUS {
                        corpus.push(input);
                    } else {
                        // Full: the new input takes a random place after the seeds.
                        let at = seeds + random.below(MAX_CORPUS - seeds);
                        corpus[at] = input;
                    }
                    next = corpus.len();
                }
            }
            Err(panic) => {
                let message = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_string()))
                    .unwrap_or_else(|| "a panic without a message".into());
                report.finding = Some((input, message));
                break;
            }
        }
    }
    report.corpus = corpus.len();
    report.outcomes = outcomes_seen + outcomes.len();
    report.edges = coverage.edges();
    report
}

/// The most inputs a corpus keeps (at most [`MAX_INPUT`] bytes each, so 16 MiB in all: the
/// fuzzer's own memory must stay far below the limit it watches for).
pub const MAX_CORPUS: usize = 1024;

/// The most outcomes remembered at once (8 bytes each, with the table's overhead about 32
/// MiB): past it the set starts again, so that a long run's memory stays flat (a 600 s run of
/// the parameter target reached 250 MiB before this bound).
pub const MAX_OUTCOMES: usize = 1 << 20;

/// The longest input a mutation makes.
pub const MAX_INPUT: usize = 1 << 14;

/// FNV-1a of `bytes`: a stable 64-bit name (outcomes, reproducer files).
pub fn hash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

/// This process's processor time (user and system), from Linux's `/proc/self/stat` (fields
/// 14 and 15, in the kernel ABI's fixed 100 Hz ticks); `None` elsewhere.
pub fn processor_time() -> Option<Duration> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: count after it.
    let mut fields = stat.get(stat.rfind(')')? + 2..)?.split_whitespace().skip(11);
    let user: u64 = fields.next()?.parse().ok()?;
    let system: u64 = fields.next()?.parse().ok()?;
    Some(Duration::from_millis((user + system) * 10))
}

/// Whether `target` panics on `input` (for the reducer).
pub fn panics(target: Target, input: &[u8]) -> bool {
    catch_unwind(AssertUnwindSafe(|| target.run(input))).is_err()
}

/// splitmix64: small, fast, and the same sequence for the same seed.
pub struct Random(pub u64);

impl Random {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// Tokens that break parsers: limits of integer and float types, separators, nesting.
const INTERESTING: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "4294967296",
    "4294967297",
    "18446744073709551616",
    "9223372036854775807",
    "-9223372036854775808",
    "2147483648",
    "65536",
    "/",
    ",",
    "(",
    ")",
    "\n",
    "\"",
    "[",
    "]",
    "{",
    "}",
    "=",
    "..",
    "../",
    "\u{feff}",
    "f 1 2 3\n",
    "v 0 0 0\n",
    "1/0",
    "0/0",
];

/// `base` with one to four random edits: bit flips, interesting tokens, insertions, deletions,
/// repeated runs (nesting, long lists) and splices from another input of the corpus.
pub fn mutate(random: &mut Random, base: &[u8], corpus: &[Vec<u8>]) -> Vec<u8> {
    let mut data = base.to_vec();
    for _ in 0..1 + random.below(4) {
        let at = if data.is_empty() { 0 } else { random.below(data.len() + 1) };
        match random.below(7) {
            0 if !data.is_empty() => {
                let i = random.below(data.len());
                data[i] ^= 1 << random.below(8);
            }
            1 => {
                let token = INTERESTING[random.below(INTERESTING.len())].as_bytes();
                data.splice(at..at, token.iter().copied());
            }
            2 if !data.is_empty() => {
                // A number replaced by an interesting token.
                let i = random.below(data.len());
                let end = (i..data.len()).find(|&j| !data[j].is_ascii_digit() && data[j] != b'.').unwrap_or(data.len());
                let token = INTERESTING[random.below(INTERESTING.len())].as_bytes();
                data.splice(i..end, token.iter().copied());
            }
            3 if !data.is_empty() => {
                let end = (at + 1 + random.below(16)).min(data.len());
                data.drain(at.min(end)..end);
            }
            4 if !data.is_empty() => {
                // A run repeated up to 2^12 times.
                let start = random.below(data.len());
                let end = (start + 1 + random.below(8)).min(data.len());
                let run = data[start..end].to_vec();
                let times = 1usize << random.below(13);
                data.splice(end..end, run.iter().copied().cycle().take(run.len() * times));
            }
            5 => {
                let other = &corpus[random.below(corpus.len())];
                if !other.is_empty() {
                    let start = random.below(other.len());
                    let end = (start + 1 + random.below(64)).min(other.len());
                    data.splice(at..at, other[start..end].iter().copied());
                }
            }
            _ => data.insert(at, random.next_u64() as u8),
        }
        // Inputs stay small enough that time is spent on structure, not bulk.
        data.truncate(MAX_INPUT);
    }
    data
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_short_run_finds_nothing_and_grows_the_corpus() {
        let report = fuzz(Target::Parameter, Duration::from_millis(300), 1, |_, _| {});
        assert_eq!(report.finding, None);
        assert!(report.executions > 10 && report.corpus >= Target::Parameter.seeds().len(), "{report:?}");
        assert!(report.outcomes > 1, "{report:?}");
    }

    #[test]
    fn mutation_is_deterministic() {
        let corpus = Target::Obj.seeds();
        let a = mutate(&mut Random(7), &corpus[0], &corpus);
        let b = mutate(&mut Random(7), &corpus[0], &corpus);
        assert_eq!(a, b);
    }
}
