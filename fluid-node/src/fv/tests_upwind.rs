//! `Ψ` on one side of a run of faces (`osmp::Upwind`) against the blend of both sides, bit for
//! bit.

use super::osmp::{Upwind, psi_line, stencil_radius};
use super::tests::line;
use proptest::prelude::*;

/// `Ψ` of order `ORDER` on the speeds `lam` and strengths `alpha` (one per interface), taken
/// with the side `side`, as bits.
fn psi_bits<const ORDER: u32, const LIMITED: bool>(
    lam: &[f64],
    alpha: &[f64],
    side: Upwind,
) -> Vec<u64> {
    let n = lam.len();
    let (mut speed, mut wave) = line(n, 0.0, 0.45, ORDER);
    speed.lam.copy_from_slice(lam);
    wave.alpha.copy_from_slice(alpha);
    speed.fill(ORDER, 0.45, 1.0 / 0.45);
    wave.fill(ORDER, &speed);
    let r = stencil_radius(ORDER);
    let mut out = vec![0.0; n - 2 * r];
    psi_line::<ORDER, LIMITED, _>(&speed, &wave, r, &mut out, side);
    out.iter().map(|x| x.to_bits()).collect()
}

/// The side of the faces `psi_bits` computes, and `Ψ` with it against the blend of both
/// sides face by face (`Upwind::Mixed`), for every order.
fn check(lam: &[f64], alpha: &[f64]) -> Result<(), TestCaseError> {
    macro_rules! orders {
        ($($o:literal),*) => {$(
            let r = stencil_radius($o);
            let side = Upwind::of(&lam[r..lam.len() - r]);
            prop_assert_eq!(
                psi_bits::<$o, true>(lam, alpha, side),
                psi_bits::<$o, true>(lam, alpha, Upwind::Mixed),
                "order {} limited, side {:?}", $o, side
            );
            prop_assert_eq!(
                psi_bits::<$o, false>(lam, alpha, side),
                psi_bits::<$o, false>(lam, alpha, Upwind::Mixed),
                "order {}, side {:?}", $o, side
            );
        )*};
    }
    orders!(3, 5, 7);
    Ok(())
}

/// A speed: any sign, zeros of both signs, and (rarely) NaN, which counts as not positive.
fn speed() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => -3.0f64..3.0,
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => Just(f64::NAN),
    ]
}

proptest! {
    /// Whatever the speeds' signs along the run (all positive, none, or some of each, with
    /// signed zeros and NaN), `Ψ` taken on the side `Upwind::of` finds is the blend's, bit
    /// for bit; and that side is `Above` exactly when every speed is positive.
    #[test]
    fn psi_on_one_side_is_the_blend_of_both(
        lam in prop::collection::vec(speed(), 8..40),
        alpha in prop::collection::vec(-2.0f64..2.0, 40),
        flip in prop_oneof![Just(0u8), Just(1), Just(2)],
    ) {
        // Runs of one side as often as mixed ones: all made positive, all made not.
        let lam: Vec<f64> = match flip {
            1 => lam.iter().map(|l| if l.is_nan() { 1.0 } else { l.abs() + 1e-3 }).collect(),
            2 => lam.iter().map(|l| -l.abs()).collect(),
            _ => lam,
        };
        let side = Upwind::of(&lam);
        prop_assert_eq!(side == Upwind::Above, lam.iter().all(|&l| l > 0.0));
        prop_assert_eq!(side == Upwind::Below, lam.iter().all(|&l| l <= 0.0 || l.is_nan()));
        check(&lam, &alpha[..lam.len()])?;
    }
}
