//! The fixed partition every parallel loop of the DEM runs over: items are computed
//! independently in chunks of [`CHUNK`] and every reduction runs serially in index order, so
//! results do not depend on the thread count.

use rayon::prelude::*;

/// Items per rayon task. NOTE: a fixed partition; every item is computed independently and
/// every reduction runs serially in index order, so results do not depend on the thread count.
pub(crate) const CHUNK: usize = 256;

/// Chunks a rayon task takes at most. NOTE: rayon splits a loop into about four pieces a
/// thread and splits one further only when it is stolen, so without a bound the piece a
/// thread runs last (a quarter of the loop on 2 threads) is never split and the other thread
/// waits for it.
const CHUNKS_PER_TASK: usize = 4;

/// [`par_fill`] runs serially below this many items: waking the pool, and its workers'
/// spinning after the job, cost tens of µs per call, more than a few chunks of link or particle
/// updates take (a 2-D beam of 728 particles and 1390 links spent most of its trial in futex
/// wake-ups). Items are independent, so the bits are the same either way.
pub(crate) const SERIAL_BELOW: usize = 8 * CHUNK;

/// Fills `out\[k\] = f(k)` over a fixed partition (serially below [`SERIAL_BELOW`] items).
pub(crate) fn par_fill<T: Send>(
    pool: Option<&rayon::ThreadPool>,
    out: &mut [T],
    f: impl Fn(usize) -> T + Sync + Send,
) {
    match pool {
        Some(pool) if out.len() >= SERIAL_BELOW => pool.install(|| {
            out.par_chunks_mut(CHUNK)
                .enumerate()
                .with_max_len(CHUNKS_PER_TASK)
                .for_each(|(c, chunk)| {
                    for (k, o) in chunk.iter_mut().enumerate() {
                        *o = f(c * CHUNK + k);
                    }
                })
        }),
        _ => {
            for (k, o) in out.iter_mut().enumerate() {
                *o = f(k);
            }
        }
    }
}

/// `f(&mut items[k])` for every item over a fixed partition.
pub(crate) fn par_each<T: Send>(
    pool: Option<&rayon::ThreadPool>,
    items: &mut [T],
    f: impl Fn(&mut T) + Sync + Send,
) {
    match pool {
        Some(pool) => pool.install(|| {
            items
                .par_chunks_mut(CHUNK)
                .with_max_len(CHUNKS_PER_TASK)
                .for_each(|chunk| {
                    for item in chunk {
                        f(item);
                    }
                })
        }),
        None => items.iter_mut().for_each(f),
    }
}
