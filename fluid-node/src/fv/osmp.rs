//! Scalar kernel of the one-step monotonicity-preserving scheme OSMP of Daru & Tenaud (JCP 193,
//! 2004), orders 3, 5 and 7, in the division-free form of numerics.md §1.5.
//!
//! For one characteristic wave with speeds `λ_l`, strengths `α_l` and Courant numbers
//! `ν_l = Δt/Δx |λ_l|` at the interfaces `l` of a line, the kernel returns `Ψ` such that the
//! wave's share of the interface flux is `−½ |λ_0| (α_0 − Ψ) r_0` (`Ψ = 0`: Roe/upwind,
//! `Ψ = (1−ν)α`: Lax–Wendroff).

/// Courant numbers and speeds below this are treated as zero in the bounds (avoids 0/0) [-].
const EPS: f64 = 1e-12;

/// Half width `R` of the interface stencil of order `order`: a face needs the interfaces
/// `f−R ..= f+R` (the MP curvatures alone need `R = 2`).
pub const fn stencil_radius(order: u32) -> usize {
    if order >= 7 { 3 } else { 2 }
}

/// Ghost cells per side needed by order `order` (`R + 1`).
pub const fn ghost_cells(order: u32) -> usize {
    stencil_radius(order) + 1
}

/// Coefficients `c_1..c_5` of the accuracy function at Courant number `nu`.
///
/// NOTE: recursion `c_q = c_{q−1} (ν + a_q)/b_q` with `(a_q, b_q)` = (1,3), (−2,4), (−3,5),
/// (2,6), (3,7): exactly Tenaud's `co7_1..co7_5` in `osmp7.f90` (numerics.md §1.3), verified
/// order by order in `fv::tests::scalar_os_orders`.
#[inline]
pub fn accuracy_coefficients(nu: f64) -> [f64; 5] {
    // Multiplications by the reciprocals (divisions by constants are not folded by the
    // compiler under IEEE semantics).
    let c1 = (nu + 1.0) * (1.0 / 3.0);
    let c2 = c1 * (nu - 2.0) * 0.25;
    let c3 = c2 * (nu - 3.0) * 0.2;
    let c4 = c3 * (nu + 2.0) * (1.0 / 6.0);
    let c5 = c4 * (nu + 3.0) * (1.0 / 7.0);
    [c1, c2, c3, c4, c5]
}

/// `minmod(a, b)`: 0 if the signs differ, else the argument of smaller magnitude.
#[inline]
pub fn minmod(a: f64, b: f64) -> f64 {
    if a * b <= 0.0 {
        0.0
    } else if a.abs() < b.abs() {
        a
    } else {
        b
    }
}

/// Suresh–Huynh curvature `d^{M4}_{l+1/2} = minmod(4d_l − d_{l+1}, 4d_{l+1} − d_l, d_l, d_{l+1})`
/// (JCP 136, 1997, eq. 2.19) from the curvatures `d_l`, `d_{l+1}` of the two adjacent cells.
#[inline]
pub fn curvature_m4(d_l: f64, d_r: f64) -> f64 {
    minmod(minmod(4.0 * d_l - d_r, 4.0 * d_r - d_l), minmod(d_l, d_r))
}

/// What depends only on a wave's speed at one interface.
#[derive(Clone, Copy, Debug, Default)]
pub struct WaveSpeed {
    /// Eigenvalue λ [m/s].
    pub lam: f64,
    /// Courant number ν = σ|λ| [-].
    pub nu: f64,
    /// `1 / max(|λ|, EPS)` [s/m].
    pub inv_lam: f64,
    /// `1 / max(ν, EPS)` [-].
    pub inv_nu: f64,
    /// `c_1 .. c_5` at ν.
    pub c: [f64; 5],
}

impl WaveSpeed {
    /// Speed data of `lam` for `sigma = Δt/Δx` [s/m] (`inv_sigma = 1/sigma`).
    #[inline]
    pub fn new(lam: f64, sigma: f64, inv_sigma: f64) -> WaveSpeed {
        let nu = sigma * lam.abs();
        // One division: 1/ν = (1/|λ|)/σ; the EPS floors keep both finite where a wave is
        // absent.
        let inv_lam = 1.0 / lam.abs().max(EPS);
        WaveSpeed {
            lam,
            nu,
            inv_lam,
            inv_nu: if nu > EPS {
                inv_lam * inv_sigma
            } else {
                1.0 / EPS
            },
            c: accuracy_coefficients(nu),
        }
    }
}

/// Per-wave data of a line, one entry per interface (`l` = interface between cells `l`, `l+1`).
#[derive(Clone, Debug, Default)]
pub struct WaveLine {
    /// Eigenvalue λ [m/s].
    pub lam: Vec<f64>,
    /// Strength α (units of the conserved variables).
    pub alpha: Vec<f64>,
    /// Courant number ν = σ|λ| [-].
    pub nu: Vec<f64>,
    /// `1 / max(ν, EPS)` [-].
    pub inv_nu: Vec<f64>,
    /// `1 / max(|λ|, EPS)` [s/m].
    pub inv_lam: Vec<f64>,
    /// `(1−ν) α` and `c_q(ν) (1−ν) α` for q = 1..5: `d[l][0]` is `(1−ν)α`, `d[l][q]` the
    /// product with `c_q`.
    pub d: Vec<[f64; 6]>,
    /// `d^{M4}` at each interface (curvature of `λα`).
    pub dm4: Vec<f64>,
}

impl WaveLine {
    /// Resizes every array to `n_interfaces` entries (keeps the capacity).
    pub fn resize(&mut self, n_interfaces: usize) {
        self.lam.resize(n_interfaces, 0.0);
        self.alpha.resize(n_interfaces, 0.0);
        self.nu.resize(n_interfaces, 0.0);
        self.inv_nu.resize(n_interfaces, 0.0);
        self.inv_lam.resize(n_interfaces, 0.0);
        self.d.resize(n_interfaces, [0.0; 6]);
        self.dm4.resize(n_interfaces, 0.0);
    }

    /// Fills `nu`, `d` at interface `l` from `lam`, `alpha` (`sigma = Δt/Δx` [s/m],
    /// `inv_sigma = 1/sigma`).
    #[inline]
    pub fn set(&mut self, l: usize, lam: f64, alpha: f64, sigma: f64, inv_sigma: f64) {
        let speed = WaveSpeed::new(lam, sigma, inv_sigma);
        self.set_with(l, &speed, alpha);
    }

    /// Fills interface `l` from a precomputed [`WaveSpeed`] (shared by the entropy and shear
    /// waves, which travel at the same speed) and the strength `alpha`.
    #[inline]
    pub fn set_with(&mut self, l: usize, speed: &WaveSpeed, alpha: f64) {
        let d0 = (1.0 - speed.nu) * alpha;
        let c = &speed.c;
        self.lam[l] = speed.lam;
        self.alpha[l] = alpha;
        self.nu[l] = speed.nu;
        self.inv_lam[l] = speed.inv_lam;
        self.inv_nu[l] = speed.inv_nu;
        self.d[l] = [d0, c[0] * d0, c[1] * d0, c[2] * d0, c[3] * d0, c[4] * d0];
    }

    /// Computes `dm4` on interfaces `2 ..= n−3` from `lam·alpha` (the others are set to 0).
    pub fn compute_curvatures(&mut self) {
        let n = self.lam.len();
        self.dm4.iter_mut().for_each(|x| *x = 0.0);
        if n < 4 {
            return;
        }
        // d_c = λα(c) − λα(c−1): curvature of cell c, between interfaces c−1 and c.
        let mut la_prev = self.lam[0] * self.alpha[0];
        let mut la_here = self.lam[1] * self.alpha[1];
        let mut d_left = la_here - la_prev;
        for l in 1..n - 1 {
            la_prev = la_here;
            la_here = self.lam[l + 1] * self.alpha[l + 1];
            let d_right = la_here - la_prev;
            self.dm4[l] = curvature_m4(d_left, d_right);
            d_left = d_right;
        }
    }
}

/// The limited correction `Ψ` of one wave at interface `f` of `wave` (needs interfaces
/// `f−R ..= f+R`, `R = stencil_radius(order)`).
///
/// Accuracy function (numerics.md §1.3, upwind-oriented index `m`, `D_m = (1−ν)α` and
/// `c_q(m)` at interface `f + s·m`, `s = sign λ_f`, `λ = 0` counting as negative):
/// ```text
/// P = D0 − (c1 D0 − c1 D−1)                                              order 3
///        + (c2 D0 − 2c2 D−1 + c2 D−2) − (c3 D1 − 3c3 D0 + 3c3 D−1 − c3 D−2)   order 5
///        + (c4 D2 − 4c4 D1 + 6c4 D0 − 4c4 D−1 + c4 D−2)
///        − (c5 D2 − 5c5 D1 + 10c5 D0 − 10c5 D−1 + 5c5 D−2 − c5 D−3)     order 7
/// ```
/// then `Ψ = median(P, Ψ_min, Ψ_max)` with the TVD and MP bounds of §1.5.
///
/// NOTE (readings chosen): (a) the *division-free* form (numerics.md §1.5) instead of Tenaud's
/// ratio form with `zero = 1e−12`, which clips the correction where `α_0 ≈ 0` and loses order
/// at smooth extrema; (b) the MD/LC curvatures normalised by `|λ_0|` (Tenaud's signed `λ_0`
/// breaks mirror symmetry, numerics.md Note 1); (c) the LC bound normalised by the upwind
/// strength (Suresh–Huynh/MITgcm form, Note 2), which needs no division by `α_0`. Orders are
/// checked numerically in `fv::tests` (scalar) and `tests/fv_accuracy.rs` (Euler).
#[inline]
pub fn osmp_psi(order: u32, wave: &WaveLine, f: usize) -> f64 {
    let p = os_unlimited(order, wave, f);
    let up = if wave.lam[f] > 0.0 { f - 1 } else { f + 1 };
    let nu_up = wave.nu[up];
    let w0 = wave.alpha[f];
    let w_up = wave.alpha[up];
    let inv_a0 = wave.inv_lam[f];
    // Bounds in Ψ space (numerics.md §1.5): 0 ↔ u_j, 2α0 ↔ u_{j+1}, b_md ↔ u^MD, b_ul ↔ u^UL,
    // b_lc ↔ u^LC.
    let b_max = 2.0 * w0;
    let b_ul = 2.0 * (1.0 - nu_up) * w_up * wave.inv_nu[up];
    let b_md = w0 - wave.dm4[f] * inv_a0;
    let b_lc = (1.0 - nu_up) * wave.inv_nu[f] * (w_up + wave.dm4[up] * inv_a0);
    let lo1 = 0.0_f64.min(b_max).min(b_md);
    let hi1 = 0.0_f64.max(b_max).max(b_md);
    let lo2 = 0.0_f64.min(b_ul).min(b_lc);
    let hi2 = 0.0_f64.max(b_ul).max(b_lc);
    let psi_min = lo1.max(lo2);
    let psi_max = hi1.min(hi2);
    psi_min.max(p.min(psi_max))
}

/// Unlimited accuracy function `P` (same as [`osmp_psi`] without the TVD/MP bounds); used by
/// the order tests of the linear scheme.
#[inline]
pub fn os_unlimited(order: u32, wave: &WaveLine, f: usize) -> f64 {
    // Fetch the oriented stencil once (D_m = d[f + s m]); m = −3 only for order 7.
    let up_pos = wave.lam[f] > 0.0;
    let at = |m: isize| -> [f64; 6] {
        let l = if up_pos {
            f as isize + m
        } else {
            f as isize - m
        };
        wave.d[l as usize]
    };
    let (dm2, dm1, d0, d1) = (at(-2), at(-1), at(0), at(1));
    let mut p = d0[0] - (d0[1] - dm1[1]);
    if order >= 5 {
        p += d0[2] - 2.0 * dm1[2] + dm2[2];
        p -= d1[3] - 3.0 * d0[3] + 3.0 * dm1[3] - dm2[3];
    }
    if order >= 7 {
        let (dm3, d2) = (at(-3), at(2));
        p += d2[4] - 4.0 * d1[4] + 6.0 * d0[4] - 4.0 * dm1[4] + dm2[4];
        p -= d2[5] - 5.0 * d1[5] + 10.0 * d0[5] - 10.0 * dm1[5] + 5.0 * dm2[5] - dm3[5];
    }
    p
}
