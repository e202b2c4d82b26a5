//! Maps over independent items: on rayon's threads with the `rayon` feature (on by default),
//! on the calling thread without it (wasm32 builds). The results come in the items' order
//! either way, so they are the same.

/// Where a [`map`] runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Threads {
    /// On rayon's threads with the `rayon` feature, on the calling thread without it.
    Any,
    /// On the calling thread, one item after the other (the tests compare it with `Any`).
    #[cfg(test)]
    Calling,
}

/// `f` of every item, in the items' order, on `threads`.
pub(crate) fn map<T: Sync, R: Send>(items: &[T], threads: Threads, f: impl Fn(&T) -> R + Sync + Send) -> Vec<R> {
    #[cfg(feature = "rayon")]
    if threads == Threads::Any {
        use rayon::prelude::*;
        return items.par_iter().map(f).collect();
    }
    #[cfg(not(feature = "rayon"))]
    let _ = threads;
    items.iter().map(f).collect()
}
