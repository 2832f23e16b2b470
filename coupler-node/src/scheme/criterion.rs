//! Criterion (22) of paper 003, the fixed point's convergence measure.

use protocol::wire::SolidState;

/// Criterion (22) of paper 003: `max_I |ΔX_I| + max_I h_I ‖ΔQ_I‖` between two solid states, with
/// `‖·‖` the Frobenius norm of the difference of the rotation matrices.
pub fn criterion_22(a: &SolidState, b: &SolidState) -> f64 {
    let dim = a.dim as usize;
    let mut max_dx: f64 = 0.0;
    let mut max_dq: f64 = 0.0;
    for i in 0..a.n_particles() {
        let dx: f64 = (0..dim)
            .map(|d| (a.position[i * dim + d] - b.position[i * dim + d]).powi(2))
            .sum::<f64>()
            .sqrt();
        let dq = if dim == 2 {
            // ‖R(θa) − R(θb)‖_F = 2√2 |sin((θa − θb)/2)|.
            2.0 * std::f64::consts::SQRT_2
                * ((a.orientation[i] - b.orientation[i]) / 2.0).sin().abs()
        } else {
            let qa = &a.orientation[4 * i..4 * i + 4];
            let qb = &b.orientation[4 * i..4 * i + 4];
            let dot: f64 = qa.iter().zip(qb).map(|(x, y)| x * y).sum();
            let sign = if dot < 0.0 { -1.0 } else { 1.0 };
            // NOTE: |qa − qb| = 2 sin(θ/4) for unit quaternions, so sin(θ/2) = |qa − qb|
            // √(1 − |qa − qb|²/4) keeps full precision for tiny rotations, where 1 − dot² would
            // cancel; ‖Ra − Rb‖_F = 2√2 sin(θ/2).
            let d: f64 = qa
                .iter()
                .zip(qb)
                .map(|(x, y)| (x - sign * y).powi(2))
                .sum::<f64>()
                .sqrt();
            let sin_half = d * (1.0 - d * d / 4.0).max(0.0).sqrt();
            2.0 * std::f64::consts::SQRT_2 * sin_half
        };
        max_dx = max_dx.max(dx);
        max_dq = max_dq.max(a.diameter[i].max(b.diameter[i]) * dq);
    }
    max_dx + max_dq
}
