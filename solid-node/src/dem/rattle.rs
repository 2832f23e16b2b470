//! RATTLE for the rotation of a rigid body (003 eq. (6)–(11)), solved as the discrete
//! Moser–Veselov map with the quaternion fixed point of Hairer & Vilmart (notes/numerics.md §3).
//!
//! With the body angular momentum `m = I ω` (principal frame) and the body torque `τ`:
//! `m½ = m + h/2 τⁿ`; find the orthogonal `Ω` with `Ω D − D Ωᵀ = h ĵ(m½)`;
//! `Qⁿ⁺¹ = Qⁿ Ω`; `m⁻ = Ωᵀ m½`; then `mⁿ⁺¹ = m⁻ + h/2 τⁿ⁺¹`. This is RATTLE with the Lagrange
//! multipliers eliminated (verified against the matrix form in `notes/ref/rattle_matrix_check.py`).

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// Result of the rotation drift.
#[derive(Clone, Copy, Debug)]
pub struct RotationDrift {
    /// Body-frame increment `Ω` as a unit quaternion `(1, c)/√(1+|c|²)`.
    pub increment: UnitQuaternion<f64>,
    /// `m⁻ = Ωᵀ m½` (body frame).
    pub momentum: Vector3<f64>,
    /// Mean angular velocity over the step in the body frame \[rad/s\]:
    /// the rotation vector of `Ω` divided by `h`.
    pub mean_omega_body: Vector3<f64>,
    /// Fixed-point iterations used.
    pub iterations: u32,
    /// Last fixed-point correction `Σ|Δc|` (converged when below `1e-15 (1 + |c|)`).
    pub residual: f64,
}

/// Iterations allowed in the fixed point; far more than needed while the rotation per step
/// stays below π/8 (the contraction factor is then about |c|² ≤ 0.04).
pub const DMV_MAX_ITERATIONS: u32 = 60;

/// Solves `Ω D − D Ωᵀ = h ĵ(m_half)` for the principal moments `inertia` and returns `Ω`, `Ωᵀ m½`.
pub fn dmv_drift(m_half: &Vector3<f64>, inertia: &[f64; 3], h: f64) -> RotationDrift {
    let [i1, i2, i3] = *inertia;
    let a = [
        0.5 * h * m_half.x / i1,
        0.5 * h * m_half.y / i2,
        0.5 * h * m_half.z / i3,
    ];
    let f = [(i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3];
    let mut c = [a[0] + f[0] * a[1] * a[2], 0.0, 0.0];
    c[1] = a[1] + f[1] * c[0] * a[2];
    c[2] = a[2] + f[2] * c[0] * c[1];
    let mut iterations = 0;
    let mut residual = f64::INFINITY;
    // NOTE: Gauss–Seidel order as in DMV2 (Hairer & Vilmart); the tolerance is relative to the
    // size of c so that tiny rotations also converge to round-off.
    while iterations < DMV_MAX_ITERATIONS {
        iterations += 1;
        let prev = c;
        let alpha = 1.0 + c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
        c[0] = alpha * a[0] + f[0] * c[1] * c[2];
        c[1] = alpha * a[1] + f[1] * c[0] * c[2];
        c[2] = alpha * a[2] + f[2] * c[0] * c[1];
        residual = (c[0] - prev[0]).abs() + (c[1] - prev[1]).abs() + (c[2] - prev[2]).abs();
        let size = c[0].abs() + c[1].abs() + c[2].abs();
        if residual <= 1e-15 * size || residual == 0.0 {
            break;
        }
    }
    let increment = UnitQuaternion::new_normalize(Quaternion::new(1.0, c[0], c[1], c[2]));
    let momentum = increment.inverse_transform_vector(m_half);
    let cv = Vector3::new(c[0], c[1], c[2]);
    let norm_c = cv.norm();
    let mean_omega_body = if norm_c > 0.0 {
        cv * (2.0 * norm_c.atan() / (norm_c * h))
    } else {
        Vector3::zeros()
    };
    RotationDrift {
        increment,
        momentum,
        mean_omega_body,
        iterations,
        residual,
    }
}

/// `Qⁿ⁺¹ = Qⁿ Ω` as quaternions, renormalised (keeps `Q` orthogonal to round-off).
#[inline]
pub fn compose(q: &UnitQuaternion<f64>, increment: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::new_normalize(q.into_inner() * increment.into_inner())
}
