//! Parallelism as an option (faer's `Par` in spirit): the caller says whether a call may use
//! rayon's threads, and the few places that fork do it through the helpers here, which run
//! serially when the option says so or when the crate is built without its `rayon` feature
//! (`wasm32-unknown-unknown`, say). Every output is the same, bit for bit, either way.

/// Whether a call may spread its work over threads.
///
/// ```
/// use subdiv_tess::{DualOptions, Parallelism};
///
/// let options = DualOptions::DEFAULT.with_parallelism(Parallelism::Serial);
/// assert_eq!(options.parallelism, Parallelism::Serial);
/// // A thread count is a rayon pool's: run the calls inside `pool.install(|| …)`.
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Parallelism {
    /// Everything on the calling thread.
    Serial,
    /// Rayon's current thread pool (the global one, or the pool whose `install` the call runs
    /// in); small calls still run on the calling thread, where waking another costs more than
    /// it saves. Without the crate's `rayon` feature, the same as [`Serial`](Self::Serial).
    #[default]
    Rayon,
}

impl Parallelism {
    /// The default: [`Rayon`](Self::Rayon).
    pub const DEFAULT: Self = Self::Rayon;

    /// Whether this call forks: [`Rayon`](Self::Rayon) with the `rayon` feature, and a pool
    /// of more than one thread.
    pub(crate) fn forks(self) -> bool {
        #[cfg(feature = "rayon")]
        {
            self == Self::Rayon && rayon::current_num_threads() > 1
        }
        #[cfg(not(feature = "rayon"))]
        {
            false
        }
    }
}

/// `a` and `b`, on two threads if `parallel`, else one after the other.
pub(crate) fn join<A, B, RA, RB>(parallel: bool, a: A, b: B) -> (RA, RB)
where
    A: FnOnce() -> RA + Send,
    B: FnOnce() -> RB + Send,
    RA: Send,
    RB: Send,
{
    #[cfg(feature = "rayon")]
    if parallel {
        return rayon::join(a, b);
    }
    let _ = parallel;
    let ra = a();
    (ra, b())
}

/// `f` over `items`, results in order, on rayon's threads if `parallel`.
pub(crate) fn map<T, R, F>(parallel: bool, items: Vec<T>, f: F) -> Vec<R>
where
    T: Send,
    R: Send,
    F: Fn(T) -> R + Send + Sync,
{
    #[cfg(feature = "rayon")]
    if parallel {
        use rayon::prelude::*;
        return items.into_par_iter().map(f).collect();
    }
    let _ = parallel;
    items.into_iter().map(f).collect()
}

/// `f` over `items`, results in order, on rayon's threads if `parallel`; on failure one of
/// the errors (the first in order when serial).
pub(crate) fn try_map<'a, T, R, E, F>(parallel: bool, items: &'a [T], f: F) -> Result<Vec<R>, E>
where
    T: Sync,
    R: Send,
    E: Send,
    F: Fn(&'a T) -> Result<R, E> + Send + Sync,
{
    #[cfg(feature = "rayon")]
    if parallel {
        use rayon::prelude::*;
        return items.par_iter().map(f).collect();
    }
    let _ = parallel;
    items.iter().map(f).collect()
}

/// `f` over `items`, each thread with one `init()` scratch, on rayon's threads if `parallel`.
pub(crate) fn for_each_init<T, S, I, F>(parallel: bool, items: Vec<T>, init: I, f: F)
where
    T: Send,
    I: Fn() -> S + Send + Sync,
    F: Fn(&mut S, T) + Send + Sync,
{
    #[cfg(feature = "rayon")]
    if parallel {
        use rayon::prelude::*;
        items.into_par_iter().for_each_init(init, f);
        return;
    }
    let _ = parallel;
    let mut scratch = init();
    for item in items {
        f(&mut scratch, item);
    }
}

/// `out` extended by `f` over `items`, in order, on rayon's threads if `parallel`.
pub(crate) fn extend_map<T, R, F>(parallel: bool, out: &mut Vec<R>, items: &[T], f: F)
where
    T: Sync,
    R: Send,
    F: Fn(&T) -> R + Send + Sync,
{
    #[cfg(feature = "rayon")]
    if parallel {
        use rayon::prelude::*;
        out.par_extend(items.par_iter().map(f));
        return;
    }
    let _ = parallel;
    out.extend(items.iter().map(f));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serial_and_parallel_helpers_agree() {
        let items: Vec<u64> = (0..10_000).collect();
        for parallel in [false, true] {
            assert_eq!(map(parallel, items.clone(), |x| x * x), items.iter().map(|x| x * x).collect::<Vec<_>>());
            let r: Result<Vec<u64>, u64> = try_map(parallel, &items, |&x| if x == 777 { Err(x) } else { Ok(x) });
            assert_eq!(r, Err(777));
            let mut out = vec![1];
            extend_map(parallel, &mut out, &items, |x| x + 1);
            assert_eq!(out.len(), 10_001);
            assert_eq!(out[10_000], 10_000);
            assert_eq!(join(parallel, || 1, || 2), (1, 2));
            let sum = std::sync::atomic::AtomicU64::new(0);
            for_each_init(
                parallel,
                items.clone(),
                || 0u64,
                |_, x| {
                    sum.fetch_add(x, std::sync::atomic::Ordering::Relaxed);
                },
            );
            assert_eq!(sum.into_inner(), 10_000 * 9_999 / 2);
        }
    }
}
