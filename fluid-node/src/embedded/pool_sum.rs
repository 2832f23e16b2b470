//! [`add_on_pool`]: [`OddSum::add_into`] with the slots' sums taken in parallel on the pool the
//! call runs in, bit for bit the same.

use protocol::sum::{OddSum, slot_sum};
use rayon::prelude::*;

use crate::fv::FluidSolver;
use crate::fv::comm::Comm;

/// Terms one task of [`add_on_pool`] sums at least (any split gives the same sums); below it
/// the terms are summed on the calling thread.
const TERMS_PER_TASK: usize = 4096;

/// Adds every slot's sum of the terms of `sum` to `out[slot]` and forgets the terms, as
/// [`OddSum::add_into`] does, bit for bit.
///
/// NOTE: the terms are counted into their slots ([`OddSum::by_slot`]), then the slots are summed in
/// parallel on the pool the call runs in, each from its own terms alone ([`slot_sum`], the
/// sum `add_into` takes), into its own `out[slot]`: the same bits on any number of threads.
/// In `cube-mobile-walls` on 50³ the sums of the correct's contents and of the particles'
/// loads were 3 % of the fluid node's time, on one thread while the other waited.
pub(super) fn add_on_pool(sum: &mut OddSum, out: &mut [f64]) {
    let (n_terms, n) = (sum.terms().len(), out.len());
    if n_terms < TERMS_PER_TASK || n == 0 {
        sum.add_into(out);
        return;
    }
    let per_slot = n_terms.div_ceil(n);
    let (starts, by_slot) = sum.by_slot(n);
    let by_slot = &*by_slot;
    let slots_per_task = (TERMS_PER_TASK / per_slot).max(1);
    out.par_iter_mut()
        .enumerate()
        .with_min_len(slots_per_task)
        .with_max_len(4 * slots_per_task)
        .for_each_init(Vec::new, |run, (s, o)| {
            let terms = &by_slot[starts[s] as usize..starts[s + 1] as usize];
            if !terms.is_empty() {
                run.clear();
                run.extend_from_slice(terms);
                *o += slot_sum(run);
            }
        });
    sum.clear();
}

/// [`add_on_pool`] on the pool of `solver` (one rank), or with the slots shared out among its
/// ranks (collective): every rank holds the same terms (gathered from every rank), each sums
/// the slots of its share on its pool, and one all-gather of those sums gives every rank every
/// slot's sum, added to `out[slot]` as [`OddSum::add_into`] adds it: the same bits on any
/// number of ranks and threads, and each rank sorts about `1 / K` of the terms.
///
/// The shares are consecutive runs of slots that take about as many terms each (slot `s` is
/// rank `r`'s where `r` is the rank whose part of the terms its first term falls in), so that
/// no rank waits long for another; every rank finds them from the same counts.
pub(super) fn add_shared(solver: &FluidSolver, sum: &mut OddSum, out: &mut [f64]) {
    if solver.comm().size() == 1 {
        solver.install(|| add_on_pool(sum, out));
        return;
    }
    add_shared_with(solver.comm(), |f| solver.install(f), sum, out);
}

/// [`add_shared`] over `comm`, the slots' sums run by `install` (on a pool) and the all-gather
/// on the calling thread, as every collective.
fn add_shared_with(
    comm: &dyn Comm,
    install: impl FnOnce(&(dyn Fn() -> Vec<f64> + Sync)) -> Vec<f64>,
    sum: &mut OddSum,
    out: &mut [f64],
) {
    let n = out.len();
    let size = comm.size();
    let (starts, by_slot) = sum.by_slot(n);
    let by_slot = &*by_slot;
    let total = starts[n] as u64;
    let first_of = |r: usize| match r {
        0 => 0,
        r if r >= size => n,
        r => starts[..n].partition_point(|&t| (t as u64) * (size as u64) < (r as u64) * total),
    };
    let rank = comm.rank();
    let mine = first_of(rank)..first_of(rank + 1);
    let per_task = (TERMS_PER_TASK / (total as usize).div_ceil(n.max(1)).max(1)).max(1);
    let sums = install(&|| {
        (mine.clone())
            .into_par_iter()
            .with_min_len(per_task)
            .with_max_len(4 * per_task)
            .map_init(Vec::new, |run, s| {
                run.clear();
                run.extend_from_slice(&by_slot[starts[s] as usize..starts[s + 1] as usize]);
                if run.is_empty() { 0.0 } else { slot_sum(run) }
            })
            .collect()
    });
    let mut all = Vec::with_capacity(n);
    comm.all_gather_f64_into(&sums, &mut all);
    assert_eq!(
        all.len(),
        n,
        "the ranks' shares are every slot once, in order"
    );
    for (s, o) in out.iter_mut().enumerate() {
        // (An empty slot is left as it is, as `add_into` leaves it: `-0 + 0` would be `+0`.)
        if starts[s] < starts[s + 1] {
            *o += all[s];
        }
    }
    sum.clear();
}

#[cfg(test)]
mod tests {
    use super::{add_on_pool, add_shared_with};
    use crate::ranks::threads::ThreadRanks;
    use protocol::sum::OddSum;

    /// Sums of `n_slots` slots that start at +0, -0 and other values, and what
    /// `OddSum::add_into` of `terms` makes of them.
    fn start_and_add_into(terms: &[(u32, f64)], n_slots: usize) -> (Vec<f64>, Vec<f64>) {
        let start: Vec<f64> = (0..n_slots)
            .map(|i| [0.0, -0.0, i as f64 * 0.3][i % 3])
            .collect();
        let mut expected = start.clone();
        let mut serial = OddSum::default();
        serial.extend(terms.iter().copied());
        serial.add_into(&mut expected);
        (start, expected)
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// On pools of 1, 2 and 5 threads, over few slots of many terms (the particles' loads)
    /// and many slots of few (the cells' contents), with zeros of both signs, equal
    /// magnitudes of both signs and a NaN, into sums that start at +0, -0 and other values:
    /// the bits of `OddSum::add_into`.
    #[test]
    fn the_sums_are_add_intos_on_any_number_of_threads() {
        let mut x: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for (n_slots, n_terms) in [(36, 20_000), (30_000, 90_000), (50, 100)] {
            let mut terms: Vec<(u32, f64)> = Vec::new();
            for _ in 0..n_terms {
                let r = next();
                let slot = (r % n_slots as u64) as u32;
                let v = match (r >> 20) % 9 {
                    0 => 0.0,
                    1 => -0.0,
                    2 => 0.25,
                    3 => -0.25,
                    _ => {
                        let sign = if r & (1 << 50) != 0 { 1.0 } else { -1.0 };
                        sign * f64::from((r >> 24) as u32) * 1e-9
                    }
                };
                terms.push((slot, v));
            }
            terms.push((1, f64::NAN));
            let (start, expected) = start_and_add_into(&terms, n_slots);
            for threads in [1, 2, 5] {
                let mut got = start.clone();
                let mut sum = OddSum::default();
                sum.extend(terms.iter().copied());
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool")
                    .install(|| add_on_pool(&mut sum, &mut got));
                assert_eq!(
                    bits(&got),
                    bits(&expected),
                    "{n_slots} slots, {threads} threads"
                );
                assert!(sum.terms().is_empty());
            }
            assert!(expected[1].is_nan());
        }
    }

    /// On 1, 2, 3 and 5 thread ranks (more ranks than slots too), over few slots of many terms,
    /// many slots of few, and slots left empty, into sums that start at +0, -0 and other
    /// values: every rank gets the bits of `OddSum::add_into`.
    #[test]
    fn the_shared_sums_are_add_intos_on_any_number_of_ranks() {
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for (n_slots, n_terms, used) in [(12, 20_000, 12), (3, 500, 3), (5_000, 9_000, 4_000)] {
            let terms: Vec<(u32, f64)> = (0..n_terms)
                .map(|_| {
                    let r = next();
                    let slot = (r % used as u64) as u32;
                    let sign = if r & (1 << 50) != 0 { 1.0 } else { -1.0 };
                    let v = match (r >> 20) % 7 {
                        0 => -0.0,
                        1 => 0.5 * sign,
                        _ => sign * f64::from((r >> 24) as u32) * 1e-7,
                    };
                    (slot, v)
                })
                .collect();
            let (start, expected) = start_and_add_into(&terms, n_slots);
            for ranks in [1, 2, 3, 5] {
                let comms = ThreadRanks::new(ranks);
                let got: Vec<Vec<f64>> = std::thread::scope(|scope| {
                    let handles: Vec<_> = (comms.into_iter())
                        .map(|comm| {
                            let (terms, start) = (&terms, &start);
                            scope.spawn(move || {
                                let mut sum = OddSum::default();
                                sum.extend(terms.iter().copied());
                                let mut out = start.clone();
                                add_shared_with(&comm, |f| f(), &mut sum, &mut out);
                                assert!(sum.terms().is_empty());
                                out
                            })
                        })
                        .collect();
                    handles
                        .into_iter()
                        .map(|h| h.join().expect("rank"))
                        .collect()
                });
                for (r, out) in got.iter().enumerate() {
                    assert_eq!(
                        bits(out),
                        bits(&expected),
                        "{n_slots} slots, rank {r} of {ranks}"
                    );
                }
            }
        }
    }
}
