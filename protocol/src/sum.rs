//! Sums whose value does not depend on the order of their terms and that are odd under negating
//! every term, bit for bit (pure: used by both nodes).
//!
//! A cut cell's or a particle's share of the interface is a sum over sub-faces, which the grid
//! visits in cell order; a particle's mass and centre are sums over its polygon's edges. The
//! mirror image of a scene visits the mirrored sub-faces in another order, and a floating-point
//! sum in another order differs in its last bits. In a flow that
//! amplifies perturbations (the shocked contacts of `cylinder-explosion`) such bits grow to
//! visible asymmetry. [`OddSum`] removes that seed: per slot, the positive terms are added from
//! the smallest to the largest, the negative ones likewise, and the two partial sums last. The
//! mirrored terms (the same set, with one component negated) then give the negated sum exactly:
//! the positives of one are the negatives of the other, in the same order.

/// Sum of `terms` independent of their order and odd under negating them all, bit for bit: the
/// positive and the negative terms each from the smallest magnitude up, then the two sums. The
/// terms are reordered. A NaN term makes the sum NaN.
pub fn odd_sum(terms: &mut [f64]) -> f64 {
    if terms.len() == 1 {
        return terms[0];
    }
    sort_by_magnitude(terms);
    signed_halves(terms.iter().copied())
}

/// The bits of an `f64` but its sign: the bits of `|x|`.
const MAGNITUDE: u64 = !(1 << 63);

/// Sorts `terms` by magnitude, as `sort_unstable_by(|a, b| a.abs().total_cmp(&b.abs()))`.
///
/// NOTE: the key is the bits without the sign: for `|x|` (sign clear, NaNs included) the order
/// of `total_cmp` is that of the bits as integers, so this is the same order, on integers
/// compared once instead of floats taken apart twice a comparison. Terms of equal magnitude
/// may come in another order than that sort's; they are equal or of opposite signs (different
/// halves of [`signed_halves`]; `+0` and `-0` add to the same), so the sums are the same bits.
/// Most slots hold a few terms: an insertion sort takes them (the sorts were 4 % of
/// `cube-mobile-walls` on 50³).
#[inline]
fn sort_by_magnitude(terms: &mut [f64]) {
    let key = |x: f64| x.to_bits() & MAGNITUDE;
    if terms.len() > 24 {
        terms.sort_unstable_by_key(|&x| key(x));
        return;
    }
    for i in 1..terms.len() {
        let x = terms[i];
        let k = key(x);
        let mut j = i;
        while j > 0 && key(terms[j - 1]) > k {
            terms[j] = terms[j - 1];
            j -= 1;
        }
        terms[j] = x;
    }
}

/// One slot's sum as [`OddSum::add_into`] takes it (to add it to the slot's value): the terms
/// sorted by magnitude (reordered), then the positive and the negative ones each from the
/// smallest up, then the two sums. Unlike [`odd_sum`], one term `-0` gives `+0`.
pub fn slot_sum(terms: &mut [f64]) -> f64 {
    sort_by_magnitude(terms);
    signed_halves(terms.iter().copied())
}

/// `Σ positives + Σ negatives` of terms sorted by magnitude, each half in the given order.
#[inline]
fn signed_halves(sorted: impl Iterator<Item = f64>) -> f64 {
    let (mut pos, mut neg) = (0.0, 0.0);
    for t in sorted {
        if t < 0.0 {
            neg += t;
        } else {
            pos += t;
        }
    }
    pos + neg
}

/// From this many terms on, [`OddSum::add_into`] counts them into their slots when there are at
/// most four times as many slots as terms (below it, sorting them all is as quick).
const BUCKETED_FROM: usize = 64;

/// Terms gathered per slot, summed by [`OddSum::add_into`].
#[derive(Clone, Debug, Default)]
pub struct OddSum {
    terms: Vec<(u32, f64)>,
    /// Scratch of [`OddSum::add_into`]'s bucketing: where each slot's terms start.
    starts: Vec<u32>,
    /// Scratch of [`OddSum::add_into`]'s bucketing: the terms' values, by slot.
    by_slot: Vec<f64>,
}

impl OddSum {
    /// Forgets the terms, keeping the buffer.
    pub fn clear(&mut self) {
        self.terms.clear();
    }

    /// Adds `value` to slot `slot`.
    #[inline]
    pub fn push(&mut self, slot: usize, value: f64) {
        self.terms.push((slot as u32, value));
    }

    /// The terms pushed so far, `(slot, value)` in the order they came (to send them to the
    /// rank that adds them: the sums do not depend on that order).
    pub fn terms(&self) -> &[(u32, f64)] {
        &self.terms
    }

    /// Pushes terms taken from [`OddSum::terms`] (of another rank), as if pushed one by one.
    pub fn extend(&mut self, terms: impl IntoIterator<Item = (u32, f64)>) {
        self.terms.extend(terms);
    }

    /// Adds every slot's sum to `out[slot]` and forgets the terms.
    ///
    /// `out[slot]` is added last, to the sum of the slot's terms, so that a slot receiving terms
    /// from several sub-faces gets the same bits whatever order they came in. A NaN term makes
    /// its slot NaN (it is never dropped).
    ///
    /// NOTE: where the slots are not many more than the terms, the terms are put into their
    /// slots by counting (two passes over them) and only each slot's few terms are sorted by
    /// magnitude; otherwise all the terms are sorted by slot and magnitude. Either way every
    /// slot sums the same terms in the same order of magnitude (terms of equal magnitude are
    /// equal or go to different halves), so the sums are the same bits. The sort of all the
    /// terms was 8 % of the fluid node's time in `cube-mobile-walls` on 50³.
    pub fn add_into(&mut self, out: &mut [f64]) {
        if self.terms.len() >= BUCKETED_FROM && out.len() <= 4 * self.terms.len() {
            self.add_bucketed(out);
        } else {
            self.add_sorted(out);
        }
        self.terms.clear();
    }

    /// [`OddSum::add_into`] by sorting all the terms by slot, then magnitude.
    ///
    /// NOTE: sorted by the slot and the magnitude's bits, the order of [`sort_by_magnitude`]
    /// within each slot (and the same sums, for the reason given there).
    fn add_sorted(&mut self, out: &mut [f64]) {
        self.terms
            .sort_unstable_by_key(|&(slot, x)| (slot, x.to_bits() & MAGNITUDE));
        for run in self.terms.chunk_by(|a, b| a.0 == b.0) {
            out[run[0].0 as usize] += signed_halves(run.iter().map(|t| t.1));
        }
    }

    /// [`OddSum::add_into`] by counting the terms into their slots (`out.len()` of them).
    fn add_bucketed(&mut self, out: &mut [f64]) {
        let (starts, by_slot) = self.by_slot(out.len());
        for (s, o) in out.iter_mut().enumerate() {
            let run = &mut by_slot[starts[s] as usize..starts[s + 1] as usize];
            if !run.is_empty() {
                // (One term too goes through the halves: `0 + -0` is `+0`.)
                *o += slot_sum(run);
            }
        }
    }

    /// The terms counted into `n` slots (two passes, no sort): slot `s`'s values are
    /// `values[starts[s]..starts[s + 1]]`, in the order they were pushed. The buffers are the
    /// sum's own scratch, kept from call to call; the terms stay.
    pub fn by_slot(&mut self, n: usize) -> (&[u32], &mut [f64]) {
        let starts = &mut self.starts;
        starts.clear();
        starts.resize(n + 1, 0);
        for t in &self.terms {
            starts[t.0 as usize + 1] += 1;
        }
        for s in 0..n {
            starts[s + 1] += starts[s];
        }
        let values = &mut self.by_slot;
        values.clear();
        values.resize(self.terms.len(), 0.0);
        // Each slot's next free place is its start, moved on as it fills; then each start is
        // the next slot's, and moving them back one slot restores them.
        for t in &self.terms {
            let s = t.0 as usize;
            values[starts[s] as usize] = t.1;
            starts[s] += 1;
        }
        starts.copy_within(..n, 1);
        starts[0] = 0;
        (starts, values)
    }

    /// Heap bytes held (the terms' buffer and the bucketing's scratch).
    pub fn capacity_bytes(&self) -> usize {
        self.terms.capacity() * std::mem::size_of::<(u32, f64)>()
            + self.starts.capacity() * std::mem::size_of::<u32>()
            + self.by_slot.capacity() * std::mem::size_of::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::{OddSum, odd_sum, signed_halves, slot_sum};

    fn summed(terms: &[(usize, f64)], n: usize) -> Vec<f64> {
        let mut s = OddSum::default();
        for &(k, v) in terms {
            s.push(k, v);
        }
        let mut out = vec![0.0; n];
        s.add_into(&mut out);
        out
    }

    #[test]
    fn the_sum_is_independent_of_order_and_odd_bit_for_bit() {
        // Terms whose plain left-to-right sums differ by order (1.4 forward, 4 backward: near
        // 1e16 the ulp is 2, so what survives of the small terms depends on when they come).
        let base = [1e16, 1.0, 0.1, -1e16, 0.7, 1.0, -0.3];
        let forward: Vec<(usize, f64)> = base.iter().map(|&v| (0, v)).collect();
        let backward: Vec<(usize, f64)> = base.iter().rev().map(|&v| (0, v)).collect();
        let negated: Vec<(usize, f64)> = base.iter().rev().map(|&v| (0, -v)).collect();
        let plain_f: f64 = base.iter().sum();
        let plain_b: f64 = base.iter().rev().sum();
        assert_ne!(
            plain_f.to_bits(),
            plain_b.to_bits(),
            "the terms must show the effect"
        );
        let f = summed(&forward, 1)[0];
        assert_eq!(f.to_bits(), summed(&backward, 1)[0].to_bits());
        assert_eq!((-f).to_bits(), summed(&negated, 1)[0].to_bits());
        // Exactly 2.5; the positives' partial sum 1e16 + 2.8 keeps 1e16 + 2 (ulp 2).
        assert_eq!(f, 2.0);
        let mut flat = base.to_vec();
        assert_eq!(odd_sum(&mut flat).to_bits(), f.to_bits());
    }

    #[test]
    fn counting_the_terms_into_slots_gives_the_sorted_sums_bit_for_bit() {
        // Terms of every sign, of equal magnitudes, zeros of both signs, a NaN, over slots of
        // zero, one, two and many terms, into sums that start at +0, -0 and other values.
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let n = 300;
        let mut terms: Vec<(u32, f64)> = Vec::new();
        for _ in 0..900 {
            let r = next();
            let slot = (r % 97) as u32 * 3 + u32::from(r % 5 == 0);
            let v = match (r >> 8) % 8 {
                0 => 0.0,
                1 => -0.0,
                2 => 0.5,
                3 => -0.5,
                _ => {
                    f64::from((r >> 16) as u32) * 1e-7 * if r & (1 << 40) != 0 { 1.0 } else { -1.0 }
                }
            };
            terms.push((slot, v));
        }
        terms.push((298, 1e300));
        terms.push((298, -1e300));
        terms.push((295, -0.0));
        terms.push((7, f64::NAN));
        let start: Vec<f64> = (0..n)
            .map(|i| match i % 3 {
                0 => 0.0,
                1 => -0.0,
                _ => i as f64 * 0.1,
            })
            .collect();
        let mut a = OddSum::default();
        a.extend(terms.iter().copied());
        let mut b = a.clone();
        let (mut sorted, mut bucketed) = (start.clone(), start);
        a.add_sorted(&mut sorted);
        b.add_bucketed(&mut bucketed);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        assert_eq!(bits(&sorted), bits(&bucketed));
        assert!(sorted[7].is_nan());
        assert_eq!(sorted[295].to_bits(), 0.0f64.to_bits(), "-0 + (+0 + -0)");
        // `add_into` takes the counting path here, and the sorted one with many more slots.
        let mut c = OddSum::default();
        c.extend(terms.iter().copied());
        let mut via = vec![0.0; n];
        c.add_into(&mut via);
        let mut wide = vec![0.0; 100 * n];
        c.extend(terms.iter().copied());
        c.add_into(&mut wide);
        assert_eq!(bits(&via), bits(&wide[..n]));
        assert!(c.terms().is_empty());
    }

    #[test]
    fn the_magnitude_sort_gives_the_sums_of_total_cmp_bit_for_bit() {
        // Slices of 1 to 60 terms (both sides of the insertion sort's bound) drawn from a few
        // magnitudes of both signs, zeros of both signs, infinities and NaNs, summed after the
        // sort by bits and after the sort it replaced.
        let mut x: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let pool = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            -0.1,
            3e-9,
            -3e-9,
            7e12,
            -7e12,
            f64::INFINITY,
        ];
        for round in 0..4000 {
            let len = 1 + round % 60;
            let terms: Vec<f64> = (0..len)
                .map(|_| {
                    let r = next();
                    match r % 16 {
                        0..=10 => pool[(r >> 8) as usize % pool.len()],
                        11 if round % 7 == 0 => f64::NAN,
                        _ => (r >> 11) as f64 * 1e-9 * if r & 1 == 0 { 1.0 } else { -1.0 },
                    }
                })
                .collect();
            let mut old = terms.clone();
            old.sort_unstable_by(|a, b| a.abs().total_cmp(&b.abs()));
            let expected = signed_halves(old.iter().copied());
            let mut new = terms.clone();
            assert_eq!(
                slot_sum(&mut new).to_bits(),
                expected.to_bits(),
                "{terms:?}"
            );
            let mut new = terms.clone();
            let expected_odd = if len == 1 { terms[0] } else { expected };
            assert_eq!(odd_sum(&mut new).to_bits(), expected_odd.to_bits());
            // The same terms over three slots, summed by `add_into`'s sort of all the terms
            // (many more slots than terms) against the sort by slot and `total_cmp`.
            let slotted: Vec<(u32, f64)> = (terms.iter().enumerate())
                .map(|(k, &v)| ((k % 3) as u32 * 7, v))
                .collect();
            let mut old = slotted.clone();
            old.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.abs().total_cmp(&b.1.abs())));
            let mut expected = vec![0.0; 300];
            for run in old.chunk_by(|a, b| a.0 == b.0) {
                expected[run[0].0 as usize] += signed_halves(run.iter().map(|t| t.1));
            }
            let mut sum = OddSum::default();
            sum.extend(slotted);
            let mut got = vec![0.0; 300];
            sum.add_into(&mut got);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
            assert_eq!(bits(&got), bits(&expected), "{terms:?}");
        }
    }

    #[test]
    fn slots_are_summed_apart_and_a_nan_is_kept() {
        let out = summed(&[(2, 1.5), (0, -1.0), (2, 0.25), (1, f64::NAN)], 3);
        assert_eq!(out[0], -1.0);
        assert!(out[1].is_nan());
        assert_eq!(out[2], 1.75);
    }
}
