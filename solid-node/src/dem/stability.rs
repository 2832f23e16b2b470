//! Elastic stability bound of the explicit scheme.
//!
//! Verlet/RATTLE is stable for the linearised system when `dt ω_max < 2`, `ω_max²` the largest
//! eigenvalue of `M^{-1/2} K M^{-1/2}` (M: masses and principal moments, K: Hessian of the
//! potential at rest). Derivation of the bound used here:
//!
//! - A link's shear/compression energy is `½ k |Δu|²` with `Δu = B_I y_I + B_J y_J`,
//!   `y = M^{1/2} (X, θ)`, `‖B_I‖² ≤ 1/m_I + |r_I|²/I_min,I` (`r_I = G − X_I`). Cauchy–Schwarz
//!   gives `|Δu|² ≤ 2 (‖B_I‖²|y_I|² + ‖B_J‖²|y_J|²)`.
//! - The volumetric energy `Σ_I ½ λ V'_I (Σ_J c_IJ g_IJ)²`, `c_IJ = S_IJ/(2V'_I)`, `g = Δu·n`,
//!   is bounded the same way (Cauchy–Schwarz on the sum) by a link stiffness
//!   `k_v = λ S (C_I + C_J) / 2`, `C_I = Σ_J c_IJ`.
//! - Flexion–torsion `c_k (1 − a_I·a_J) ≤ ½ c_k |δθ_I − δθ_J|² ≤ c_k (|δθ_I|² + |δθ_J|²)`.
//!
//! Summing, `ω_max² ≤ max_I 2 Σ_{J} [(k + k_v)(1/m_I + |r_I|²/I_min,I) + Σ_k |c_k| / I_min,I]`
//! (Gershgorin-like, per particle). A spring link (`[[solid.bodies]] links`) has no lever arm
//! and no volumetric part: its Hessian is `k n nᵀ + k (1 − D⁰/D)(1 − n nᵀ)`, at most `k`, so it
//! adds `2 k / m_I` (and `2 c / I_min,I` for its rotational spring), i.e. `ω = sqrt(2k/m)` per
//! link; a chain particle with two springs gets `4k/m`, the exact `ω_max²` of a long chain.
//!
//! The bound is sharp for the shear–rotation mode of two equal
//! particles without flexion and is conservative otherwise; `dt_limit = 2/ω_max`.

use crate::dem::model::{LinkLaw, Model, ParticleMotion};

/// `(2/ω_max bound, particle that sets it)`; `(∞, 0)` without links.
pub fn elastic_limit(model: &Model, broken: &[bool]) -> (f64, u32) {
    let lambda = model.material.lambda();
    let n = model.particles.len();
    // C_I = Σ_J S_IJ / (2 V'_I).
    let mut c_sum = vec![0.0; n];
    for (l, link) in model.links.iter().enumerate() {
        if broken[l] || link.law != LinkLaw::Elastic {
            continue;
        }
        c_sum[link.i as usize] += link.area * model.particles[link.i as usize].vol_weight;
        c_sum[link.j as usize] += link.area * model.particles[link.j as usize].vol_weight;
    }
    let mut omega2 = vec![0.0; n];
    for (l, link) in model.links.iter().enumerate() {
        if broken[l] {
            continue;
        }
        let (k, arms) = match link.law {
            LinkLaw::Elastic => (
                link.k_shear
                    + 0.5 * lambda * link.area * (c_sum[link.i as usize] + c_sum[link.j as usize]),
                1.0,
            ),
            LinkLaw::Spring { k, .. } => (k, 0.0),
        };
        let flex = if model.dim == 3 {
            link.flex.iter().map(|c| c.abs()).sum::<f64>()
        } else {
            (link.flex[0] + link.flex[1]).abs()
        };
        for (p, r) in [(link.i, &link.r_i), (link.j, &link.r_j)] {
            let part = &model.particles[p as usize];
            let i_min = if model.dim == 3 {
                part.inertia.iter().copied().fold(f64::INFINITY, f64::min)
            } else {
                part.inertia[0]
            };
            let r2 = arms
                * if model.dim == 3 {
                    r.norm_squared()
                } else {
                    r.x * r.x + r.y * r.y
                };
            omega2[p as usize] += 2.0 * (k * (1.0 / part.mass + r2 / i_min) + flex / i_min);
        }
    }
    let mut best = (f64::INFINITY, 0u32);
    for (p, w2) in omega2.iter().enumerate() {
        if model.particles[p].motion != ParticleMotion::Free || *w2 <= 0.0 {
            continue;
        }
        let dt = 2.0 / w2.sqrt();
        if dt < best.0 {
            best = (dt, p as u32);
        }
    }
    best
}
