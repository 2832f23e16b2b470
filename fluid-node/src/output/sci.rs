//! Scientific text of an `f64` as `format!("{v:.prec$e}")` writes it, byte for byte, from the
//! shortest digits (`ryu`) instead of the standard library's exact-digit search.

use std::io::Write as _;

/// Most digits after the point [`push_sci`] takes the fast path for; more go to `std`.
const FAST_PRECISION: usize = 13;

/// Appends the text of `format!("{v:.prec$e}")` to `out`: the same bytes.
///
/// NOTE: why the shortest digits give the same text. Let `s` be the shortest decimal that reads
/// back as `v` (Ryū, Adams 2018), `I` the interval of reals that round to `v`, and `D` the
/// decimals of `prec + 1` significant digits. Rounding `s` and `v` to `D` can differ only if a
/// midpoint `m` of `D` (`prec + 2` digits, the last a 5) lies between them, so in `I`. Then `s`,
/// the shortest in `I`, has at most `prec + 2` digits, and two such decimals differ by at least
/// a unit in their `prec + 2`-th digit, `1e-(prec + 2)` of `v` or more: far more than `I`'s width
/// (`2.2e-16` of `v`) for `prec + 2 <= 15`. So `s = m`: the only case where the two may round
/// apart is `s` itself a midpoint (`prec + 2` digits ending in 5), which (like zero,
/// subnormals, infinities and NaN, where `I` is wide or there are no digits) goes to `std`.
/// Otherwise `s` is rounded half up, a tie being impossible there. The test
/// `matches_std_on_random_and_edge_values` compares millions of values with `std`.
pub(crate) fn push_sci(out: &mut Vec<u8>, v: f64, prec: usize) {
    if prec > FAST_PRECISION || !v.is_normal() {
        write_std(out, v, prec);
        return;
    }
    let mut buffer = ryu::Buffer::new();
    let text = buffer.format_finite(v).as_bytes();
    // The significant digits of `text` (from the first non-zero one) and the power of ten of
    // the first one: `v = d0.d1d2... × 10^exp10`. Ryū writes `123.45`, `0.00012345`, `1e16` or
    // `1.2345e-7`.
    let mut digits = [0u8; 24];
    let mut n = 0usize;
    // Mantissa digits seen (zeros included), those before the point, and the first non-zero's.
    let (mut seen, mut before, mut first) = (0usize, None, None);
    let mut rest = text.iter();
    for &b in rest.by_ref() {
        match b {
            b'-' => {}
            b'.' => before = Some(seen),
            b'0'..=b'9' => {
                if first.is_none() && b != b'0' {
                    first = Some(seen);
                }
                if first.is_some() && n < digits.len() {
                    digits[n] = b - b'0';
                    n += 1;
                }
                seen += 1;
            }
            b'e' | b'E' => break,
            _ => {
                write_std(out, v, prec);
                return;
            }
        }
    }
    let (mut exp_part, mut exp_neg) = (0i32, false);
    for &b in rest {
        match b {
            b'-' => exp_neg = true,
            b'+' => {}
            b'0'..=b'9' => exp_part = exp_part * 10 + i32::from(b - b'0'),
            _ => {
                write_std(out, v, prec);
                return;
            }
        }
    }
    let Some(first) = first else {
        write_std(out, v, prec);
        return;
    };
    let before = before.unwrap_or(seen) as i32;
    let exp10 = before - 1 - first as i32 + if exp_neg { -exp_part } else { exp_part };
    while n > 1 && digits[n - 1] == 0 {
        n -= 1;
    }
    let keep = prec + 1;
    if n == keep + 1 && digits[keep] == 5 {
        // `s` is a midpoint of the kept digits: `std` decides from the exact value.
        write_std(out, v, prec);
        return;
    }
    let mut exp10 = exp10;
    if n > keep {
        if digits[keep] >= 5 {
            let mut k = keep;
            loop {
                if k == 0 {
                    // 9.99…9 rounded up: 1.00…0 at the next power.
                    digits[0] = 1;
                    exp10 += 1;
                    break;
                }
                k -= 1;
                if digits[k] == 9 {
                    digits[k] = 0;
                } else {
                    digits[k] += 1;
                    break;
                }
            }
        }
    } else {
        digits[n..keep].fill(0);
    }
    if v.is_sign_negative() {
        out.push(b'-');
    }
    out.push(b'0' + digits[0]);
    if prec > 0 {
        out.push(b'.');
        out.extend(digits[1..keep].iter().map(|d| b'0' + d));
    }
    out.push(b'e');
    if exp10 < 0 {
        out.push(b'-');
    }
    // At most 3 digits (|exp10| <= 308 for a normal value).
    let e = exp10.unsigned_abs();
    if e >= 100 {
        out.push(b'0' + (e / 100) as u8);
    }
    if e >= 10 {
        out.push(b'0' + (e / 10 % 10) as u8);
    }
    out.push(b'0' + (e % 10) as u8);
}

/// The standard library's text, for the cases [`push_sci`] leaves to it.
fn write_std(out: &mut Vec<u8>, v: f64, prec: usize) {
    write!(out, "{v:.prec$e}").expect("writing to a Vec does not fail");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(v: f64, prec: usize) {
        let mut out = Vec::new();
        push_sci(&mut out, v, prec);
        let expected = format!("{v:.prec$e}");
        assert_eq!(
            std::str::from_utf8(&out).expect("ascii"),
            expected,
            "{v:e} ({:#018x}) at precision {prec}",
            v.to_bits()
        );
    }

    /// A seeded xorshift, so the values are the same on every run.
    fn xorshift(state: &mut u64) -> u64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        *state
    }

    #[test]
    fn matches_std_on_random_and_edge_values() {
        let precisions = [0, 1, 5, 9, 12, 13, 14];
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        // Random bit patterns over the whole range (NaN, infinities, subnormals among them).
        for _ in 0..300_000 {
            let v = f64::from_bits(xorshift(&mut state));
            for prec in [9, 12] {
                check(v, prec);
            }
        }
        // Values near the scenes' (a state of 1.4 or 116.5 with small perturbations).
        for _ in 0..300_000 {
            let r = xorshift(&mut state);
            let base = [1.4, 116.5, 12.0, 1e-7, 0.02][(r % 5) as usize];
            let scale = 10f64.powi((r >> 8) as i32 % 17 - 16);
            let v = base * (1.0 + scale * ((r >> 32) as f64 / u32::MAX as f64 - 0.5));
            check(v, 12);
            check(-v, 12);
        }
        // Decimals of prec + 2 digits ending in 5 (the midpoints), and their neighbours, and
        // 9.99… at every precision (rounding up into the next power of ten).
        for prec in precisions {
            for _ in 0..20_000 {
                let r = xorshift(&mut state);
                let mantissa = 10u64.pow(prec as u32 + 1) + r % (9 * 10u64.pow(prec as u32 + 1));
                let exp = (r >> 48) as i32 % 40 - 20;
                let text = format!("{mantissa}5e{}", exp - prec as i32 - 1);
                let m: f64 = text.parse().expect("a number");
                for v in [m, m.next_up(), m.next_down()] {
                    check(v, prec);
                }
            }
            for exp in -300..300 {
                let nines = format!("9.{}e{exp}", "9".repeat(prec + 3));
                let v: f64 = nines.parse().expect("a number");
                for v in [v, v.next_up(), v.next_down(), 10f64.powi(exp)] {
                    check(v, prec);
                }
            }
        }
        // Zeros, integers, powers of two and ten, the extremes.
        let mut edges = vec![0.0, -0.0, 1.0, 0.5, 2.5, 1e16, 1e-5, 123456.0, 1e21, 1e22];
        edges.extend([f64::MAX, f64::MIN_POSITIVE, f64::EPSILON, 5e-324]);
        edges.extend((-1074..1024).map(|e| 2f64.powi(e)));
        edges.extend((0..=9007).map(|k| k as f64 * 1e12));
        for v in edges {
            for prec in precisions {
                check(v, prec);
                check(-v, prec);
            }
        }
    }
}
