//! Two threads on one small call: the calling thread does the call's serial work while one of
//! rayon's threads starts on jobs that do not depend on it, then both share what is left.
//!
//! Rayon shares work by forks. A fork made after a few microseconds of serial work (the full
//! path's topology build) finds the other threads gone to sleep, and in a virtual machine
//! waking one costs tens of microseconds, as much as a small call's whole work. Forked at the
//! start of the call instead, while the other thread is still awake from the previous call,
//! the helper works through the serial part. The jobs are all known at the fork, so nobody
//! waits for them: the caller, once done with its serial work, takes them from the front, the
//! helper from the back, and they stop where they meet.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Mutex, PoisonError};

/// The helper's states in [`serial_beside_jobs`].
const WAITING: u8 = 0;
const RUNNING: u8 = 1;
const DONE: u8 = 2;

/// Stores its value into its atomic when dropped.
struct SetOnDrop<'a>(&'a AtomicU8, u8);

impl Drop for SetOnDrop<'_> {
    fn drop(&mut self) {
        self.0.store(self.1, Ordering::Release);
    }
}

/// Runs `serial` on this thread and then `run` on `jobs` from the first, while one of rayon's
/// threads (if it takes the fork in time; else this thread alone) runs `run` on them from the
/// last. Each job runs once, with a scratch that `scratch` makes once per thread. Returns
/// `serial`'s result when every job has run.
pub(super) fn serial_beside_jobs<J: Send, W, R: Send>(
    jobs: impl IntoIterator<Item = J>,
    serial: impl FnOnce() -> R + Send,
    scratch: impl Fn() -> W + Sync,
    run: impl Fn(J, &mut W) + Sync,
) -> R {
    // A job is taken by emptying its slot: each side goes its own way and stops at the first
    // slot the other side has emptied, past which the other side has taken every job. The
    // locks are uncontended but where the two sides meet.
    let slots: Vec<Mutex<Option<J>>> = jobs.into_iter().map(|j| Mutex::new(Some(j))).collect();
    let take = |slot: &Mutex<Option<J>>| slot.lock().unwrap_or_else(PoisonError::into_inner).take();
    // The helper's state: a helper that comes after this thread has finished takes nothing
    // (`DONE` first), and this thread, done with its jobs, waits for a running helper's last
    // job here, spinning, rather than in rayon's join, whose wait starts with a look for other
    // work and a `sched_yield` (a few tenths of a microsecond).
    let helper = AtomicU8::new(WAITING);
    let (result, ()) = rayon::join(
        || {
            let result = serial();
            let mut w = scratch();
            for job in slots.iter().map_while(take) {
                run(job, &mut w);
            }
            if helper.compare_exchange(WAITING, DONE, Ordering::AcqRel, Ordering::Acquire).is_err() {
                while helper.load(Ordering::Acquire) != DONE {
                    std::hint::spin_loop();
                }
            }
            result
        },
        || {
            if helper.compare_exchange(WAITING, RUNNING, Ordering::AcqRel, Ordering::Acquire).is_err() {
                return;
            }
            // Set on the way out, panics included (this thread would otherwise wait for ever).
            let _done = SetOnDrop(&helper, DONE);
            let mut w = None;
            for job in slots.iter().rev().map_while(take) {
                run(job, w.get_or_insert_with(&scratch));
            }
        },
    );
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every job runs exactly once, whichever thread takes it, on one thread or two.
    #[test]
    fn every_job_runs_once() {
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for jobs in [0, 1, 2, 7, 100] {
                let ran = Mutex::new(Vec::new());
                let serial = pool.install(|| {
                    serial_beside_jobs(
                        0..jobs,
                        || std::hint::black_box((0..1000u64).sum::<u64>()),
                        || 0usize,
                        |job: u32, count: &mut usize| {
                            *count += 1;
                            ran.lock().unwrap().push(job);
                        },
                    )
                });
                assert_eq!(serial, 499_500);
                let mut ran = ran.into_inner().unwrap();
                ran.sort_unstable();
                assert_eq!(ran, (0..jobs).collect::<Vec<_>>(), "{threads} threads, {jobs} jobs");
            }
        }
    }
}
