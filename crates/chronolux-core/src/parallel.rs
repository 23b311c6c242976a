//! Deterministic parallel loops: work is split into fixed chunks whose results are merged
//! in chunk order, so outputs never depend on the number of threads or on scheduling.

use rayon::prelude::*;

/// Runs `f` on every index range `[k*chunk, min((k+1)*chunk, n))` in parallel and returns
/// the per-chunk results in chunk order.
pub fn map_chunks<R: Send>(
    n: usize,
    chunk: usize,
    f: impl Fn(std::ops::Range<usize>) -> R + Sync,
) -> Vec<R> {
    let chunk = chunk.max(1);
    let count = n.div_ceil(chunk);
    (0..count)
        .into_par_iter()
        .map(|k| f(k * chunk..((k + 1) * chunk).min(n)))
        .collect()
}
