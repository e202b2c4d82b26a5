//! Edge coverage on stable Rust, from LLVM's SanitizerCoverage: built with
//! [`RUSTFLAGS`] (what `cargo xtask fuzz --coverage` passes, for an explicit `--target` so that
//! build scripts and procedural macros stay plain), every edge of the instrumented code
//! increments a byte counter of its own, and each object's constructor hands its counters'
//! section to `__sanitizer_cov_8bit_counters_init`, which the fuzz binary defines and forwards
//! to [`register`]. Without the flags nothing registers and [`Coverage::available`] is false;
//! the driver then keeps inputs by their outcome alone.
//!
//! An input is new when some counter reaches a hit-count class (AFL's buckets: 1, 2, 3, 4–7,
//! 8–15, 16–31, 32–127, 128+) it never reached before.

// The counters are raw memory that the instrumentation owns: read and zeroed through pointers.
#![allow(unsafe_code)]

use std::sync::Mutex;

/// The flags that instrument a build for [`Coverage`].
pub const RUSTFLAGS: &str = "-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=3 \
                             -Cllvm-args=-sanitizer-coverage-inline-8bit-counters";

/// The counters' sections, as `(start, end)` addresses, in the order they registered.
static REGIONS: Mutex<Vec<(usize, usize)>> = Mutex::new(Vec::new());

/// Records a section of counters, `[start, end)`: the fuzz binary's
/// `__sanitizer_cov_8bit_counters_init` calls it from each instrumented object's constructor.
/// The addresses must be those the instrumentation passes: live for the whole process.
pub fn register(start: usize, end: usize) {
    if start < end {
        REGIONS.lock().unwrap_or_else(std::sync::PoisonError::into_inner).push((start, end));
    }
}

/// The counters seen so far, as one bit per hit-count class per counter.
#[derive(Debug, Default)]
pub struct Coverage {
    regions: Vec<(usize, usize)>,
    seen: Vec<u8>,
    edges: usize,
}

impl Coverage {
    /// The registered counters (none in a build without [`RUSTFLAGS`]).
    pub fn new() -> Self {
        let regions = REGIONS.lock().unwrap_or_else(std::sync::PoisonError::into_inner).clone();
        let total = regions.iter().map(|(a, b)| b - a).sum();
        Self { regions, seen: vec![0; total], edges: 0 }
    }

    /// Whether the build is instrumented.
    pub fn available(&self) -> bool {
        !self.seen.is_empty()
    }

    /// Counters that ever fired.
    pub fn edges(&self) -> usize {
        self.edges
    }

    /// Zeroes every counter (before an input runs).
    pub fn reset(&self) {
        for &(start, end) in &self.regions {
            for address in start..end {
                // SAFETY: `register` received these addresses from the instrumentation's
                // constructors: counters of static storage, live for the whole process, one
                // byte each. The instrumented code writes them without synchronisation, so they
                // are accessed byte by byte through volatile operations, never as a reference.
                unsafe { std::ptr::write_volatile(address as *mut u8, 0) };
            }
        }
    }

    /// Reads the counters after an input ran: whether any reached a hit-count class it never
    /// reached before (the input found new behaviour).
    pub fn observe(&mut self) -> bool {
        let mut new = false;
        let mut k = 0;
        for &(start, end) in &self.regions {
            for address in start..end {
                // SAFETY: as in `reset`.
                let hits = unsafe { std::ptr::read_volatile(address as *const u8) };
                if hits != 0 {
                    let class = bucket(hits);
                    if self.seen[k] & class == 0 {
                        if self.seen[k] == 0 {
                            self.edges += 1;
                        }
                        self.seen[k] |= class;
                        new = true;
                    }
                }
                k += 1;
            }
        }
        new
    }
}

/// AFL's hit-count class of a nonzero counter, as one bit.
fn bucket(hits: u8) -> u8 {
    match hits {
        1 => 1,
        2 => 2,
        3 => 4,
        4..=7 => 8,
        8..=15 => 16,
        16..=31 => 32,
        32..=127 => 64,
        _ => 128,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_are_one_bit_each_and_grow_with_the_count() {
        let classes: Vec<u8> = [1u8, 2, 3, 4, 7, 8, 15, 16, 31, 32, 127, 128, 255].iter().map(|&h| bucket(h)).collect();
        assert!(classes.iter().all(|c| c.count_ones() == 1));
        assert!(classes.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn an_uninstrumented_build_has_no_coverage() {
        // The test build is not instrumented: nothing registered.
        let coverage = Coverage::new();
        assert!(!coverage.available() && coverage.edges() == 0);
    }
}
