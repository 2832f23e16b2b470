//! Ideal-gas Euler kernels in the frame of one sweep: equation of state, physical flux, Roe
//! average and characteristic decomposition, and the first-order fallback fluxes (HLLE, HLLC,
//! Lax–Friedrichs, and the local Lax–Friedrichs flux of the faces beside vacuum).
//!
//! A state is `[f64; 5]` in the *sweep frame*: `(ρ, ρ u_n, ρ u_t1, ρ u_t2, E)` where `n` is the
//! sweep axis and `t1`, `t2` the other axes (inactive axes last, so their components stay 0).
//! Units are SI: ρ [kg/m³], velocities [m/s], E and p \[Pa\].

/// Number of components of a sweep-frame state.
pub const NQ: usize = 5;

/// A conserved state in the sweep frame.
pub type State = [f64; NQ];

/// Primitive variables of a sweep-frame state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Primitive {
    /// Density ρ [kg/m³].
    pub rho: f64,
    /// Velocity `(u_n, u_t1, u_t2)` [m/s].
    pub vel: [f64; 3],
    /// Pressure p \[Pa\].
    pub p: f64,
}

/// Primitive variables of `u` (`γ` the ratio of specific heats).
///
/// Vacuum-safe: with ρ ≤ 0 the velocity is taken as 0, so no division by zero happens.
#[inline]
pub fn primitive(u: &State, gamma: f64) -> Primitive {
    primitive_floored(u, gamma, 0.0)
}

/// [`primitive`] with the velocity of a cell below the vacuum density `rho_floor` taken as
/// `ρu / rho_floor`: there ρ and ρu are round-off of the neighbours' content (a crack cell
/// that a Lax–Friedrichs step emptied keeps ~1e-18 of momentum, and the next step may give it
/// ρ ~ 1e-32), so `ρu / ρ` would be a velocity of 1e14 m/s and `E − ½ρ|u|²` a pressure of
/// −1e-4. Identical to [`primitive`] where ρ ≥ `rho_floor`.
#[inline(always)]
pub fn primitive_floored(u: &State, gamma: f64, rho_floor: f64) -> Primitive {
    let rho = u[0];
    // NOTE: a vacuum cell (ρ = 0) has no velocity; taking 0 keeps the Lax–Friedrichs flux of
    // paper 000 §3.2 free of divisions by ρ, as the paper requires.
    let inv = if rho > 0.0 {
        1.0 / rho.max(rho_floor)
    } else {
        0.0
    };
    let vel = [u[1] * inv, u[2] * inv, u[3] * inv];
    let kinetic = 0.5 * (u[1] * vel[0] + u[2] * vel[1] + u[3] * vel[2]);
    Primitive {
        rho,
        vel,
        p: (gamma - 1.0) * (u[4] - kinetic),
    }
}

/// Conserved state from primitive variables.
#[inline]
pub fn conserved(w: &Primitive, gamma: f64) -> State {
    let kinetic = 0.5 * w.rho * (w.vel[0] * w.vel[0] + w.vel[1] * w.vel[1] + w.vel[2] * w.vel[2]);
    [
        w.rho,
        w.rho * w.vel[0],
        w.rho * w.vel[1],
        w.rho * w.vel[2],
        w.p / (gamma - 1.0) + kinetic,
    ]
}

/// Physical flux along the sweep axis, `F(U) = (ρu, ρu²+p, ρu v, ρu w, u(E+p))`.
#[inline(always)]
pub fn physical_flux(u: &State, w: &Primitive) -> State {
    let un = w.vel[0];
    [
        u[1],
        u[1] * un + w.p,
        u[2] * un,
        u[3] * un,
        un * (u[4] + w.p),
    ]
}

/// Sound speed `c = sqrt(γ p / ρ)` [m/s], 0 for non-physical or vacuum states.
#[inline]
pub fn sound_speed(w: &Primitive, gamma: f64) -> f64 {
    if w.rho > 0.0 && w.p > 0.0 {
        (gamma * w.p / w.rho).sqrt()
    } else {
        0.0
    }
}

/// Roe average between two cells and its eigenstructure along the sweep axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RoeAverage {
    /// Averaged velocity `(u_n, u_t1, u_t2)` [m/s].
    pub vel: [f64; 3],
    /// Averaged total specific enthalpy H [J/kg].
    pub h: f64,
    /// Averaged sound speed c [m/s] (0 if the average is not physical).
    pub c: f64,
    /// Whether `c² > 0` and everything is finite.
    pub valid: bool,
}

/// Wave order used everywhere: `u-c`, `u+c`, entropy `u`, shear `t1`, shear `t2`.
pub const WAVE_MINUS: usize = 0;
/// Index of the `u + c` wave.
pub const WAVE_PLUS: usize = 1;
/// Index of the entropy wave.
pub const WAVE_ENTROPY: usize = 2;

/// Roe average of two states with primitives `wl`, `wr` (Toro 2009, eq. 11.60).
#[inline]
pub fn roe_average(
    ul: &State,
    wl: &Primitive,
    ur: &State,
    wr: &Primitive,
    gamma: f64,
) -> RoeAverage {
    RoeSide::average(
        &RoeSide::new(ul, wl),
        &RoeSide::new(ur, wr),
        gamma,
        wl.rho > 0.0 && wr.rho > 0.0,
    )
}

/// What one side contributes to a Roe average: `√ρ`, velocity and total enthalpy `H`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RoeSide {
    /// `√ρ` (NaN for ρ < 0).
    pub sqrt_rho: f64,
    /// Velocity `(u_n, u_t1, u_t2)` [m/s].
    pub vel: [f64; 3],
    /// Total specific enthalpy `(E + p)/ρ` [J/kg] (not finite for ρ = 0).
    pub h: f64,
}

impl RoeSide {
    /// The side of state `u` with primitives `w`.
    #[inline(always)]
    pub fn new(u: &State, w: &Primitive) -> RoeSide {
        RoeSide {
            sqrt_rho: w.rho.sqrt(),
            vel: w.vel,
            h: (u[4] + w.p) / w.rho,
        }
    }

    /// Roe average of sides `l` and `r`; valid only if `sides_ok` (both densities positive,
    /// no vacuum) and the average is physical (`c² > 0`, finite). An invalid average is all
    /// zeros. Branch-free, so that the line kernel's loop over interfaces vectorises.
    #[inline(always)]
    pub fn average(l: &RoeSide, r: &RoeSide, gamma: f64, sides_ok: bool) -> RoeAverage {
        let (sl, sr) = (l.sqrt_rho, r.sqrt_rho);
        let inv = 1.0 / (sl + sr);
        let vel: [f64; 3] = std::array::from_fn(|k| (sl * l.vel[k] + sr * r.vel[k]) * inv);
        let h = (sl * l.h + sr * r.h) * inv;
        let q2 = vel[0] * vel[0] + vel[1] * vel[1] + vel[2] * vel[2];
        let c2 = (gamma - 1.0) * (h - 0.5 * q2);
        let valid = sides_ok & (c2 > 0.0) & c2.is_finite() & h.is_finite();
        let keep = |x: f64| if valid { x } else { 0.0 };
        RoeAverage {
            vel: vel.map(keep),
            h: keep(h),
            c: keep(c2.sqrt()),
            valid,
        }
    }
}

/// Eigenvalues of the Roe matrix in the wave order (`u-c`, `u+c`, `u`, `u`, `u`).
#[inline]
pub fn roe_eigenvalues(roe: &RoeAverage) -> [f64; NQ] {
    let u = roe.vel[0];
    [u - roe.c, u + roe.c, u, u, u]
}

/// Wave strengths `α = L ΔU` (Toro 2009, eqs. 11.68–11.70), in the wave order.
#[inline(always)]
pub fn roe_strengths(roe: &RoeAverage, du: &State, gamma: f64) -> [f64; NQ] {
    let [u, v, w] = roe.vel;
    let c = roe.c;
    let a_t1 = du[2] - v * du[0];
    let a_t2 = du[3] - w * du[0];
    let de = du[4] - a_t1 * v - a_t2 * w;
    let inv_c = 1.0 / c;
    let a_ent = (gamma - 1.0) * inv_c * inv_c * (du[0] * (roe.h - u * u) + u * du[1] - de);
    // NOTE: both acoustic strengths in closed form (Toro takes α₊ = Δρ − α₋ − α_ent): a
    // mirror image of the interface swaps them with a change of sign, to the last bit only
    // when their formulas are each other's mirror images (the integration test `fv_mirror`).
    let a_minus = (du[0] * (u + c) - du[1] - c * a_ent) * (0.5 * inv_c);
    let a_plus = (du[0] * (c - u) + du[1] - c * a_ent) * (0.5 * inv_c);
    [a_minus, a_plus, a_ent, a_t1, a_t2]
}

/// Right eigenvector `k` (wave order) of the Roe matrix.
#[inline(always)]
pub fn roe_eigenvector(roe: &RoeAverage, k: usize) -> State {
    let [u, v, w] = roe.vel;
    let c = roe.c;
    match k {
        WAVE_MINUS => [1.0, u - c, v, w, roe.h - u * c],
        WAVE_PLUS => [1.0, u + c, v, w, roe.h + u * c],
        WAVE_ENTROPY => [1.0, u, v, w, 0.5 * (u * u + v * v + w * w)],
        3 => [0.0, 0.0, 1.0, 0.0, v],
        _ => [0.0, 0.0, 0.0, 1.0, w],
    }
}

/// Whether the two star states of the linearised Roe solution have ρ > 0 and p > 0.
///
/// They are `U_L + α₋ r₋` and `U_R − α₊ r₊` (the states on either side of the contact).
#[inline(always)]
pub fn roe_star_states_positive(
    ul: &State,
    ur: &State,
    roe: &RoeAverage,
    alpha: &[f64; NQ],
) -> bool {
    let rm = roe_eigenvector(roe, WAVE_MINUS);
    let rp = roe_eigenvector(roe, WAVE_PLUS);
    let mut sl = *ul;
    let mut sr = *ur;
    for q in 0..NQ {
        sl[q] += alpha[WAVE_MINUS] * rm[q];
        sr[q] -= alpha[WAVE_PLUS] * rp[q];
    }
    // p > 0 ⇔ 2ρE > |ρu|² when ρ > 0 (no division).
    let p_pos = |s: &State| 2.0 * s[0] * s[4] > s[1] * s[1] + s[2] * s[2] + s[3] * s[3];
    // Branch-free (`&`, not `&&`: every comparison is made, the answer is the same), so that
    // the line kernel's face loop vectorises.
    (sl[0] > 0.0) & (sr[0] > 0.0) & p_pos(&sl) & p_pos(&sr)
}

/// Einfeldt's HLLE flux with Roe-average signal speeds (Einfeldt et al. 1991): positively
/// conservative, first order. Falls back to Rusanov speeds if the Roe average is not physical.
pub fn flux_hlle(ul: &State, ur: &State, gamma: f64) -> State {
    let wl = primitive(ul, gamma);
    let wr = primitive(ur, gamma);
    let cl = sound_speed(&wl, gamma);
    let cr = sound_speed(&wr, gamma);
    let roe = roe_average(ul, &wl, ur, &wr, gamma);
    let (mut bl, mut br) = (wl.vel[0] - cl, wr.vel[0] + cr);
    if roe.valid {
        bl = bl.min(roe.vel[0] - roe.c);
        br = br.max(roe.vel[0] + roe.c);
    } else {
        let s = (wl.vel[0].abs() + cl).max(wr.vel[0].abs() + cr);
        bl = bl.min(-s);
        br = br.max(s);
    }
    let bl = bl.min(0.0);
    let br = br.max(0.0);
    let fl = physical_flux(ul, &wl);
    let fr = physical_flux(ur, &wr);
    let mut out = [0.0; NQ];
    if br - bl <= 0.0 {
        for q in 0..NQ {
            out[q] = 0.5 * (fl[q] + fr[q]);
        }
        return out;
    }
    let inv = 1.0 / (br - bl);
    for q in 0..NQ {
        out[q] = (br * fl[q] - bl * fr[q] + bl * br * (ur[q] - ul[q])) * inv;
    }
    out
}

/// HLLC flux (Toro 2009, §10.4) with Einfeldt (Roe-average) signal speeds.
pub fn flux_hllc(ul: &State, ur: &State, gamma: f64) -> State {
    let wl = primitive(ul, gamma);
    let wr = primitive(ur, gamma);
    let cl = sound_speed(&wl, gamma);
    let cr = sound_speed(&wr, gamma);
    let roe = roe_average(ul, &wl, ur, &wr, gamma);
    if !roe.valid || wl.rho <= 0.0 || wr.rho <= 0.0 {
        return flux_hlle(ul, ur, gamma);
    }
    let sl = (wl.vel[0] - cl).min(roe.vel[0] - roe.c);
    let sr = (wr.vel[0] + cr).max(roe.vel[0] + roe.c);
    let fl = physical_flux(ul, &wl);
    if sl >= 0.0 {
        return fl;
    }
    let fr = physical_flux(ur, &wr);
    if sr <= 0.0 {
        return fr;
    }
    let (ml, mr) = (wl.rho * (sl - wl.vel[0]), wr.rho * (sr - wr.vel[0]));
    let s_star = (wr.p - wl.p + wl.vel[0] * ml - wr.vel[0] * mr) / (ml - mr);
    let star = |u: &State, w: &Primitive, s: f64| -> State {
        let k = w.rho * (s - w.vel[0]) / (s - s_star);
        [
            k,
            k * s_star,
            k * w.vel[1],
            k * w.vel[2],
            k * (u[4] / w.rho + (s_star - w.vel[0]) * (s_star + w.p / (w.rho * (s - w.vel[0])))),
        ]
    };
    let mut out = [0.0; NQ];
    if s_star >= 0.0 {
        let us = star(ul, &wl, sl);
        for q in 0..NQ {
            out[q] = fl[q] + sl * (us[q] - ul[q]);
        }
    } else {
        let us = star(ur, &wr, sr);
        for q in 0..NQ {
            out[q] = fr[q] + sr * (us[q] - ur[q]);
        }
    }
    out
}

/// Lax–Friedrichs flux `½(F_L + F_R) − Δx/(2Δt) (U_R − U_L)` (paper 000 §3.2), the last
/// fallback of the sweeps and the vacuum faces' flux where the local one's speed is not
/// resolved ([`flux_local_lax_friedrichs`]); `sigma = Δt/Δx` [s/m], velocities of cells below `rho_floor` as in
/// [`primitive_floored`].
#[inline]
pub fn flux_lax_friedrichs(
    ul: &State,
    ur: &State,
    sigma: f64,
    gamma: f64,
    rho_floor: f64,
) -> State {
    let fl = physical_flux(ul, &primitive_floored(ul, gamma, rho_floor));
    let fr = physical_flux(ur, &primitive_floored(ur, gamma, rho_floor));
    let k = 0.5 / sigma;
    let mut out = [0.0; NQ];
    for q in 0..NQ {
        out[q] = 0.5 * (fl[q] + fr[q]) - k * (ur[q] - ul[q]);
    }
    out
}

/// Local Lax–Friedrichs (Rusanov) flux `½(F_L + F_R) − ½ α (U_R − U_L)`, used at faces beside
/// vacuum cells; `sigma = Δt/Δx` [s/m]. The speed `α = max(|u_L| + c_L, |u_R| + c_R)` is read
/// from the states as they are ([`primitive`]: no velocity where ρ ≤ 0, no sound where ρ or p
/// is not positive). Where `σ α > 1` (or α is not finite: a cell of round-off content whose
/// `ρu/ρ` no step resolves) it is the classical [`flux_lax_friedrichs`] (`α = 1/σ`), bit for
/// bit, with its floored velocities.
///
/// Why (docs/cut-cells.md §4): with admissible states (ρ ≥ 0, p ≥ 0) and `α ≥ |u| + c`, both
/// `U ± F(U)/α` are admissible (Perthame & Shu 1996; Zhang & Shu 2010), and a cell whose two
/// faces carry this flux is updated to the convex combination
/// `(1 − σ(α_l + α_r)/2) U_i + (σ α_l/2)(U_{i−1} + F_{i−1}/α_l) + (σ α_r/2)(U_{i+1} − F_{i+1}/α_r)`:
/// positivity preserving for `σ α ≤ 1`, as the classical flux is. Unlike the classical flux it
/// diffuses only as fast as the gas moves: the classical flux damps nothing of an odd–even mode
/// (it flips its sign each step), and in a cut cell that the solid opens during the step (eq. 12
/// with the fluxes weighted by the apertures of `F^{n+1}`) such a mode then grows by
/// `2 − (1 − Λ^n)/(1 − Λ^{n+1})` per step; with `α` the gas's speed the factor is
/// `(1 − Λ^n)/(1 − Λ^{n+1}) − 2 σ α`, at most 1 in modulus near vacuum.
#[inline]
pub fn flux_local_lax_friedrichs(
    ul: &State,
    ur: &State,
    sigma: f64,
    gamma: f64,
    rho_floor: f64,
) -> State {
    let wl = primitive(ul, gamma);
    let wr = primitive(ur, gamma);
    let speed = |w: &Primitive| w.vel[0].abs() + sound_speed(w, gamma);
    let (al, ar) = (speed(&wl), speed(&wr));
    // NOTE: written so that a NaN speed (ρ subnormal, `0 · ∞`) takes the classical flux too.
    if !(al * sigma <= 1.0 && ar * sigma <= 1.0) {
        return flux_lax_friedrichs(ul, ur, sigma, gamma, rho_floor);
    }
    let alpha = al.max(ar);
    let fl = physical_flux(ul, &wl);
    let fr = physical_flux(ur, &wr);
    let mut out = [0.0; NQ];
    for q in 0..NQ {
        out[q] = 0.5 * (fl[q] + fr[q]) - 0.5 * alpha * (ur[q] - ul[q]);
    }
    out
}
