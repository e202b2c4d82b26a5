//! What the benches (`bench tess`, `bench refine`) share: their option values and their timed
//! samples (as `osd_bench` times: repeat the work until a sample lasts ≥ 20 ms).

use std::time::Instant;

/// `value` if it is one of `options`, else an error naming `flag` and the options.
pub(crate) fn one_of(flag: &str, value: &str, options: &[&'static str]) -> Result<&'static str, String> {
    options.iter().copied().find(|o| *o == value).ok_or_else(|| format!("{flag} {value}: not one of {options:?}"))
}

/// `yes` or `no` as a bool, else an error naming `flag`.
pub(crate) fn yes_no(flag: &str, value: &str, usage: &str) -> Result<bool, String> {
    match value {
        "yes" => Ok(true),
        "no" => Ok(false),
        _ => Err(format!("{flag} {value}: yes or no; {usage}")),
    }
}

/// One sample: `work` repeated until it lasts ≥ 20 ms, seconds per repetition.
pub(crate) fn sample(mut work: impl FnMut()) -> f64 {
    let start = Instant::now();
    let mut reps = 0u32;
    while reps == 0 || start.elapsed().as_secs_f64() < 0.02 {
        work();
        reps += 1;
    }
    start.elapsed().as_secs_f64() / f64::from(reps)
}

/// The median of `samples` (the upper one of an even count).
pub(crate) fn median(samples: &[f64]) -> f64 {
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted[sorted.len() / 2]
}

/// The CLI's own time in its summary line `… in T s (…)`: the first ` in ` followed by a
/// number and ` s` (a path may hold ` in ` too).
pub(crate) fn cli_seconds(stderr: &str) -> Option<f64> {
    stderr.split(" in ").skip(1).find_map(|rest| rest.split_once(" s ")?.0.parse::<f64>().ok())
}
