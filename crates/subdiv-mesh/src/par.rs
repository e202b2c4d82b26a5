//! Parallelism as an option (faer's `Par` in spirit): the caller says whether a call may use
//! rayon's threads, and the places that fork, in this crate and the ones above it (refinement,
//! tessellation), do it through the helpers here, which run serially when the option says so or
//! when the crate is built without its `rayon` feature (`wasm32-unknown-unknown`, say). Every
//! output is the same, bit for bit, either way.

/// Whether a call may spread its work over threads.
///
/// ```
/// use subdiv_mesh::Parallelism;
///
/// // Options structs that take one (`DualOptions`, `RefineOptions`) default to `Rayon`; a thread
/// // count is a rayon pool's: run the calls inside `pool.install(|| …)`.
/// assert_eq!(Parallelism::DEFAULT, Parallelism::Rayon);
/// assert!(!Parallelism::Serial.forks());
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

    /// Whether a pass over `items` items forks: [`forks`](Self::forks), and at least
    /// [`MIN_PARALLEL_ITEMS`] of them.
    pub fn forks_for(self, items: usize) -> bool {
        self.forks() && items >= MIN_PARALLEL_ITEMS
    }

    /// Whether this call forks: [`Rayon`](Self::Rayon) with the `rayon` feature, and a pool
    /// of more than one thread.
    pub fn forks(self) -> bool {
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

/// The fewest items a pass of [`Parallelism::forks_for`] forks for: below it waking a second
/// thread costs more than it saves. Measured on refinement (`cargo xtask bench refine --mesh M`,
/// one and two threads, 5 rounds, three alternations of 0, 2¹³ and 2¹⁶): spot's three levels (at
/// most 47k child half-edges) took 1.24-1.26 ms on one thread, 1.34-1.53 ms on two when every
/// pass forked, 1.27-1.28 ms with this bound (in an earlier, quieter run 0.72 against 0.91 ms);
/// catmark_car (403k child half-edges at its third level) took 10.4-13.5 ms on two threads
/// either way, within the machine's noise.
pub const MIN_PARALLEL_ITEMS: usize = 1 << 16;

/// Items per task of the chunked passes ([`for_each_chunk`] callers): large enough that a task's
/// bookkeeping is noise, small enough that two threads share a refinement level of a few
/// thousand faces.
pub const CHUNK: usize = 1 << 13;

/// `a` and `b`, on two threads if `parallel`, else one after the other.
pub fn join<A, B, RA, RB>(parallel: bool, a: A, b: B) -> (RA, RB)
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
pub fn map<T, R, F>(parallel: bool, items: Vec<T>, f: F) -> Vec<R>
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
pub fn try_map<'a, T, R, E, F>(parallel: bool, items: &'a [T], f: F) -> Result<Vec<R>, E>
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
pub fn for_each_init<T, S, I, F>(parallel: bool, items: Vec<T>, init: I, f: F)
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
pub fn extend_map<T, R, F>(parallel: bool, out: &mut Vec<R>, items: &[T], f: F)
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

/// `out` extended by `f(i)` for `i` in `range`, in order, on rayon's threads if `parallel`
/// (rayon writes an indexed iterator's items in place: no second copy).
pub fn extend_range<R, F>(parallel: bool, out: &mut Vec<R>, range: std::ops::Range<usize>, f: F)
where
    R: Send,
    F: Fn(usize) -> R + Send + Sync,
{
    #[cfg(feature = "rayon")]
    if parallel {
        use rayon::prelude::*;
        out.par_extend(range.into_par_iter().map(f));
        return;
    }
    let _ = parallel;
    out.extend(range.map(f));
}

/// `a` and `b` extended by the pairs `f(i)` for `i` in `range`, in order, on rayon's threads if
/// `parallel`.
pub fn unzip_range<A, B, F>(parallel: bool, a: &mut Vec<A>, b: &mut Vec<B>, range: std::ops::Range<usize>, f: F)
where
    A: Send,
    B: Send,
    F: Fn(usize) -> (A, B) + Send + Sync,
{
    #[cfg(feature = "rayon")]
    if parallel {
        use rayon::prelude::*;
        let (mut left, mut right) = (Vec::new(), Vec::new());
        range.into_par_iter().map(f).unzip_into_vecs(&mut left, &mut right);
        if a.is_empty() && b.is_empty() {
            (*a, *b) = (left, right);
        } else {
            a.append(&mut left);
            b.append(&mut right);
        }
        return;
    }
    let _ = parallel;
    let (lower, _) = range.size_hint();
    a.reserve(lower);
    b.reserve(lower);
    for i in range {
        let (x, y) = f(i);
        a.push(x);
        b.push(y);
    }
}

/// `f` over `out`'s consecutive chunks of `size` items (the last may be shorter), each with its
/// chunk number, on rayon's threads if `parallel`.
pub fn for_each_chunk<T, F>(parallel: bool, out: &mut [T], size: usize, f: F)
where
    T: Send,
    F: Fn(usize, &mut [T]) + Send + Sync,
{
    #[cfg(feature = "rayon")]
    if parallel {
        use rayon::prelude::*;
        out.par_chunks_mut(size).enumerate().for_each(|(k, chunk)| f(k, chunk));
        return;
    }
    let _ = parallel;
    for (k, chunk) in out.chunks_mut(size).enumerate() {
        f(k, chunk);
    }
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
            let mut squares = vec![7];
            extend_range(parallel, &mut squares, 0..1000, |i| i * i);
            assert_eq!(squares[1..], (0..1000).map(|i| i * i).collect::<Vec<_>>());
            let (mut a, mut b) = (Vec::new(), vec![]);
            unzip_range(parallel, &mut a, &mut b, 0..1000, |i| (i, 2 * i));
            assert_eq!((a.len(), b[999]), (1000, 1998));
            let mut chunked = vec![0usize; 1000];
            for_each_chunk(parallel, &mut chunked, 64, |k, chunk| chunk.fill(k));
            assert_eq!((chunked[63], chunked[64], chunked[999]), (0, 1, 15));
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
