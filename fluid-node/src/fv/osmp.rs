//! Kernel of the one-step monotonicity-preserving scheme OSMP of Daru & Tenaud (JCP 193, 2004),
//! orders 3, 5 and 7, in the division-free form of numerics.md §1.5, on whole lines.
//!
//! For one characteristic wave with speeds `λ_l`, strengths `α_l` and Courant numbers
//! `ν_l = Δt/Δx |λ_l|` at the interfaces `l` of a line, the kernel returns `Ψ` such that the
//! wave's share of the interface flux is `−½ |λ_0| (α_0 − Ψ) r_0` (`Ψ = 0`: Roe/upwind,
//! `Ψ = (1−ν)α`: Lax–Wendroff).
//!
//! Layout: one array per quantity over the interfaces of a line (structure of arrays), and
//! loops without branches (the upwind orientation is a select), so that the compiler
//! vectorises them. What depends only on a speed ([`SpeedLine`]) is computed once for the
//! entropy and shear waves, which travel together.

use crate::fv::isa::AlignedVec;

/// The padding of the interface arrays ([`SpeedLine`], [`WaveLine`]; `isa::AlignedVec`): the
/// line kernel's strips write them from entry 15 on (`CARRY − 1`, `line/strip.rs`), which then
/// starts a cache line.
pub const INTERFACE_PAD: usize = 1;

/// An array over the interfaces of a line.
type InterfaceVec = AlignedVec<INTERFACE_PAD>;

/// The arrays of a [`SpeedLine`] or [`WaveLine`]: slices of `f64` through `Deref`.
pub trait Line: std::ops::DerefMut<Target = [f64]> {}

impl<T: std::ops::DerefMut<Target = [f64]>> Line for T {}

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

/// Accuracy coefficients `c_q` order `order` uses (`c_1` for 3, `c_1..c_3` for 5, all five
/// for 7).
pub const fn n_coefficients(order: u32) -> usize {
    order as usize - 2
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

/// `min(a, b)` as one machine instruction (`f64::min` also handles NaN, which costs a compare
/// and a blend per call on x86 without AVX). For a NaN argument the result is `b`; the kernel
/// never meets one on a valid interface (non-finite states are flagged before use).
#[inline(always)]
fn fmin(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// `max(a, b)`, the counterpart of [`fmin`].
#[inline(always)]
fn fmax(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

/// `minmod` of four values: 0 unless all have one sign, else the one of smallest magnitude.
///
/// Branch-free: `max(min, 0) + min(max, 0)` is the smallest positive value when all are
/// positive, the largest negative one when all are negative, and 0 otherwise.
#[inline(always)]
pub fn minmod4(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let lo = fmin(fmin(a, b), fmin(c, d));
    let hi = fmax(fmax(a, b), fmax(c, d));
    fmax(lo, 0.0) + fmin(hi, 0.0)
}

/// Suresh–Huynh curvature `d^{M4}_{l+1/2} = minmod(4d_l − d_{l+1}, 4d_{l+1} − d_l, d_l, d_{l+1})`
/// (JCP 136, 1997, eq. 2.19) from the curvatures `d_l`, `d_{l+1}` of the two adjacent cells.
#[inline(always)]
pub fn curvature_m4(d_l: f64, d_r: f64) -> f64 {
    minmod4(4.0 * d_l - d_r, 4.0 * d_r - d_l, d_l, d_r)
}

/// What depends only on a wave speed, one entry per interface of a line (arrays `V`: a
/// growable `InterfaceVec`, or the fixed arrays of the line kernel's strips).
#[derive(Clone, Debug, Default)]
pub struct SpeedLine<V = InterfaceVec> {
    /// Eigenvalue λ [m/s] (filled by the caller).
    pub lam: V,
    /// Courant number ν = σ|λ| [-].
    pub nu: V,
    /// `1 / max(ν, EPS)` [-].
    pub inv_nu: V,
    /// `1 / max(|λ|, EPS)` [s/m].
    pub inv_lam: V,
    /// `c_q(ν)`, q = 1..5 (only the first [`n_coefficients`] are filled).
    pub c: [V; 5],
}

impl SpeedLine {
    /// Resizes every array to `n_interfaces` entries (keeps the capacity).
    pub fn resize(&mut self, n_interfaces: usize) {
        for v in [
            &mut self.lam,
            &mut self.nu,
            &mut self.inv_nu,
            &mut self.inv_lam,
        ] {
            v.resize(n_interfaces, 0.0);
        }
        for v in &mut self.c {
            v.resize(n_interfaces, 0.0);
        }
    }
}

impl<V: Line> SpeedLine<V> {
    /// Fills everything but `lam` from `lam` for order `order` and `sigma = Δt/Δx` [s/m]
    /// (`inv_sigma = 1/sigma`).
    #[inline(always)]
    pub fn fill(&mut self, order: u32, sigma: f64, inv_sigma: f64) {
        self.fill_range(0, self.lam.len(), order, sigma, inv_sigma);
    }

    /// [`SpeedLine::fill`] of the `n` interfaces from `lo` on.
    #[inline(always)]
    pub fn fill_range(&mut self, lo: usize, n: usize, order: u32, sigma: f64, inv_sigma: f64) {
        let r = lo..lo + n;
        let lam = &self.lam[r.clone()];
        let (nu, inv_nu, inv_lam) = (
            &mut self.nu[r.clone()],
            &mut self.inv_nu[r.clone()],
            &mut self.inv_lam[r.clone()],
        );
        let [c1, c2, c3, c4, c5] = &mut self.c;
        let (c1, c2, c3, c4, c5) = (
            &mut c1[r.clone()],
            &mut c2[r.clone()],
            &mut c3[r.clone()],
            &mut c4[r.clone()],
            &mut c5[r],
        );
        let nc = n_coefficients(order);
        for l in 0..n {
            let a = lam[l].abs();
            let v = sigma * a;
            // One division: 1/ν = (1/|λ|)/σ; the EPS floors keep both finite where a wave is
            // absent.
            let il = 1.0 / fmax(a, EPS);
            nu[l] = v;
            inv_lam[l] = il;
            inv_nu[l] = if v > EPS { il * inv_sigma } else { 1.0 / EPS };
            let c = accuracy_coefficients(v);
            c1[l] = c[0];
            if nc >= 3 {
                c2[l] = c[1];
                c3[l] = c[2];
            }
            if nc >= 5 {
                c4[l] = c[3];
                c5[l] = c[4];
            }
        }
    }
}

/// Per-wave data of a line, one entry per interface (`l` = interface between cells `l`, `l+1`;
/// arrays `V` as in [`SpeedLine`]).
#[derive(Clone, Debug, Default)]
pub struct WaveLine<V = InterfaceVec> {
    /// Strength α (units of the conserved variables; filled by the caller).
    pub alpha: V,
    /// `D = (1−ν) α` and its products with `c_1..c_5`: `d[0]` is `D`, `d[q]` is `c_q D`
    /// (only `1 + n_coefficients` arrays are filled).
    pub d: [V; 6],
    /// `d^{M4}` at each interface (curvature of `λα`).
    pub dm4: V,
}

impl WaveLine {
    /// Resizes every array to `n_interfaces` entries (keeps the capacity).
    pub fn resize(&mut self, n_interfaces: usize) {
        self.alpha.resize(n_interfaces, 0.0);
        for v in &mut self.d {
            v.resize(n_interfaces, 0.0);
        }
        self.dm4.resize(n_interfaces, 0.0);
    }
}

impl<V: Line> WaveLine<V> {
    /// Fills `d` and `dm4` for order `order` from `alpha` and the wave's `speed` (already
    /// filled).
    #[inline(always)]
    pub fn fill(&mut self, order: u32, speed: &SpeedLine<V>) {
        let n = self.alpha.len();
        self.fill_products(0, n, order, speed);
        self.dm4[..n].fill(0.0);
        if n >= 4 {
            self.fill_curvatures(0, n - 2, speed);
        }
    }

    /// `d` at the `n` interfaces from `lo` on.
    #[inline(always)]
    pub fn fill_products(&mut self, lo: usize, n: usize, order: u32, speed: &SpeedLine<V>) {
        let r = lo..lo + n;
        let (alpha, nu) = (&self.alpha[r.clone()], &speed.nu[r.clone()]);
        let [d0, d1, d2, d3, d4, d5] = &mut self.d;
        let (d0, d1, d2, d3, d4, d5) = (
            &mut d0[r.clone()],
            &mut d1[r.clone()],
            &mut d2[r.clone()],
            &mut d3[r.clone()],
            &mut d4[r.clone()],
            &mut d5[r.clone()],
        );
        let [c1, c2, c3, c4, c5] = &speed.c;
        let (c1, c2, c3) = (&c1[r.clone()], &c2[r.clone()], &c3[r.clone()]);
        let (c4, c5) = (&c4[r.clone()], &c5[r]);
        let nc = n_coefficients(order);
        for l in 0..n {
            let x = (1.0 - nu[l]) * alpha[l];
            d0[l] = x;
            d1[l] = c1[l] * x;
            if nc >= 3 {
                d2[l] = c2[l] * x;
                d3[l] = c3[l] * x;
            }
            if nc >= 5 {
                d4[l] = c4[l] * x;
                d5[l] = c5[l] * x;
            }
        }
    }

    /// `dm4` at the interfaces `lo + 1 ..= lo + m` (from `λ` and `α` at `lo .. lo + m + 2`).
    ///
    /// Interface l + 1 takes the curvatures of cells l + 1 and l + 2, `λα(l+1) − λα(l)` and
    /// `λα(l+2) − λα(l+1)`.
    /// NOTE: one pass from λ and α (each product formed where it is used, the same bits):
    /// the products stored first and differenced in place (`la[l] = la[l+1] − la[l]`) made
    /// two more passes over the line, and the in-place one did not vectorise (5 % of a 3-D
    /// step on its one line).
    #[inline(always)]
    pub fn fill_curvatures(&mut self, lo: usize, m: usize, speed: &SpeedLine<V>) {
        let (lam, alpha) = (&speed.lam[lo..], &self.alpha[lo..]);
        let (lam0, lam1, lam2) = (&lam[..m], &lam[1..m + 1], &lam[2..m + 2]);
        let (al0, al1, al2) = (&alpha[..m], &alpha[1..m + 1], &alpha[2..m + 2]);
        let out = &mut self.dm4[lo + 1..lo + m + 1];
        for l in 0..m {
            let (p0, p1, p2) = (lam0[l] * al0[l], lam1[l] * al1[l], lam2[l] * al2[l]);
            out[l] = curvature_m4(p1 - p0, p2 - p1);
        }
    }

    /// [`WaveLine::fill_products`] of the `n` interfaces from `lo` on and
    /// [`WaveLine::fill_curvatures`] of the `n` from `lo − 1` on (`lo ≥ 2`) in one loop: the
    /// same values by the same operations.
    ///
    /// NOTE: one pass, not two, for the line kernel's strips: one loop's counting and one load
    /// of `α` less for each vector of interfaces (two passes were 37 instructions a vector of 4
    /// on AVX2, a fifth of the per-wave work besides `Ψ`).
    #[inline(always)]
    pub fn fill_products_curvatures(
        &mut self,
        lo: usize,
        n: usize,
        order: u32,
        speed: &SpeedLine<V>,
    ) {
        assert!(
            lo >= 2,
            "curvatures from {lo} − 1 read two interfaces below"
        );
        let WaveLine { alpha, d, dm4 } = self;
        let r = lo..lo + n;
        let (nu, lam) = (&speed.nu[r.clone()], &speed.lam[lo - 2..]);
        let (lam0, lam1, lam2) = (&lam[..n], &lam[1..n + 1], &lam[2..n + 2]);
        let al = &alpha[lo - 2..];
        let (al0, al1, al2) = (&al[..n], &al[1..n + 1], &al[2..n + 2]);
        let [d0, d1, d2, d3, d4, d5] = d;
        let (d0, d1, d2) = (&mut d0[r.clone()], &mut d1[r.clone()], &mut d2[r.clone()]);
        let (d3, d4, d5) = (&mut d3[r.clone()], &mut d4[r.clone()], &mut d5[r.clone()]);
        let [c1, c2, c3, c4, c5] = &speed.c;
        let (c1, c2, c3) = (&c1[r.clone()], &c2[r.clone()], &c3[r.clone()]);
        let (c4, c5) = (&c4[r.clone()], &c5[r]);
        let out = &mut dm4[lo - 1..lo - 1 + n];
        let nc = n_coefficients(order);
        for l in 0..n {
            let x = (1.0 - nu[l]) * al2[l];
            d0[l] = x;
            d1[l] = c1[l] * x;
            if nc >= 3 {
                d2[l] = c2[l] * x;
                d3[l] = c3[l] * x;
            }
            if nc >= 5 {
                d4[l] = c4[l] * x;
                d5[l] = c5[l] * x;
            }
            let (p0, p1, p2) = (lam0[l] * al0[l], lam1[l] * al1[l], lam2[l] * al2[l]);
            out[l] = curvature_m4(p1 - p0, p2 - p1);
        }
    }
}

/// Which side is upwind at every interface of a run ([`psi_line`]).
///
/// NOTE: where every face of a strip has its upwind side on one side, each of `Ψ`'s ten
/// upwind values is one load of that side; elsewhere both sides are loaded and blended by a
/// mask. The acoustic waves of a subsonic flow, and the entropy and shear waves of gas at rest
/// or of a flow that does not turn back along the strip, have one side over whole strips: on
/// the 3-D blast this took 13 % of `osmp.rs`'s instructions off (AVX2, docs/performance.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Upwind {
    /// λ > 0 at every interface: the upwind values are at `f + m`.
    Above,
    /// λ > 0 at none (λ ≤ 0, or NaN): the upwind values are at `f − m`.
    Below,
    /// Some of each (right for any speeds: both sides are loaded and blended face by face).
    Mixed,
}

impl Upwind {
    /// The side of the speeds `lam` (the test `λ > 0` of each face, as `Ψ` takes it).
    #[inline(always)]
    pub fn of(lam: &[f64]) -> Upwind {
        let (mut all, mut any) = (true, false);
        for &l in lam {
            all &= l > 0.0;
            any |= l > 0.0;
        }
        match (all, any) {
            (true, _) if !lam.is_empty() => Upwind::Above,
            (_, false) => Upwind::Below,
            _ => Upwind::Mixed,
        }
    }
}

/// `nf` consecutive interfaces from `f0` on, read at offsets up to `r` either side.
#[derive(Clone, Copy)]
struct Window {
    f0: usize,
    nf: usize,
    r: usize,
}

impl Window {
    /// The entries of `x` at the window's interfaces shifted by `o` (`|o| ≤ r`).
    ///
    /// NOTE: cut from the window widened by `r` either side, so that only that cut is checked
    /// at run time: the offset's slice of it is in bounds for any `|o| ≤ r`, which the compiler
    /// sees once `o` is a constant. A check of each of the ~35 slices `Ψ` reads was ~300
    /// instructions a wave a strip, a fifth of `Ψ`'s.
    #[inline(always)]
    fn at(self, x: &[f64], o: isize) -> &[f64] {
        let wide = &x[self.f0 - self.r..self.f0 + self.nf + self.r];
        let start = self.r.wrapping_add_signed(o);
        &wide[start..][..self.nf]
    }
}

/// `Ψ` of one wave at the interfaces `f0 .. f0 + out.len()` (each needs interfaces `f−R ..=
/// f+R`, `R = stencil_radius(ORDER)`); `LIMITED = false` gives the unlimited accuracy
/// function `P` (order tests of the linear scheme).
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
/// strength (Suresh–Huynh/MITgcm form, Note 2), which needs no division by `α_0`; (d) the UL
/// bound `2 (1−ν_up) α_up / max(ν_up, ν_0)` (see the note in the loop). Orders are
/// checked numerically in `fv::tests` (scalar) and the integration test `fv_accuracy` (Euler).
///
/// `side` is [`Upwind::of`] the speeds at those interfaces (`speed.lam[f0 .. f0 + out.len()]`),
/// which the waves of one speed share.
#[inline(always)]
pub fn psi_line<const ORDER: u32, const LIMITED: bool, V: Line>(
    speed: &SpeedLine<V>,
    wave: &WaveLine<V>,
    f0: usize,
    out: &mut [f64],
    side: Upwind,
) {
    let nf = out.len();
    let win = Window {
        f0,
        nf,
        r: stencil_radius(ORDER),
    };
    let w = |x, o| win.at(x, o);
    let (lam, nu_m, nu_p) = (w(&speed.lam, 0), w(&speed.nu, -1), w(&speed.nu, 1));
    let (inv_nu, inv_nu_m, inv_nu_p) = (
        w(&speed.inv_nu, 0),
        w(&speed.inv_nu, -1),
        w(&speed.inv_nu, 1),
    );
    let inv_lam = w(&speed.inv_lam, 0);
    let (al, al_m, al_p) = (w(&wave.alpha, 0), w(&wave.alpha, -1), w(&wave.alpha, 1));
    let (dm4, dm4_m, dm4_p) = (w(&wave.dm4, 0), w(&wave.dm4, -1), w(&wave.dm4, 1));
    let d = &wave.d;
    // d[q] at offsets −1, 0, +1 (all orders), ±2 (order ≥ 5), ±3 (order 7); orders below
    // read arrays they do not use at offset 0 only.
    let o2 = if ORDER >= 5 { 2 } else { 0 };
    let o3 = if ORDER >= 7 { 3 } else { 0 };
    let at = |q: usize, o: isize| w(&d[q], o);
    let (d0, d1_0, d1_m, d1_p) = (at(0, 0), at(1, 0), at(1, -1), at(1, 1));
    let (d2_0, d2_m, d2_p, d2_mm, d2_pp) = (at(2, 0), at(2, -1), at(2, 1), at(2, -o2), at(2, o2));
    let (d3_0, d3_m, d3_p, d3_mm, d3_pp) = (at(3, 0), at(3, -1), at(3, 1), at(3, -o2), at(3, o2));
    let (d4_0, d4_m, d4_p, d4_mm, d4_pp) = (at(4, 0), at(4, -1), at(4, 1), at(4, -o2), at(4, o2));
    let (d5_0, d5_m, d5_p, d5_mm, d5_pp) = (at(5, 0), at(5, -1), at(5, 1), at(5, -o2), at(5, o2));
    let (d5_mmm, d5_ppp) = (at(5, -o3), at(5, o3));
    // `Ψ` at face `j`, its upwind values read through `$up` (`blend`, `above` or `below`,
    // below).
    macro_rules! face {
        ($j:expr, $up:ident) => {{
            let j = $j;
            let up = |a: &[f64], b: &[f64]| $up(a, b, j);
            let mut p = d0[j] - (d1_0[j] - up(d1_m, d1_p));
            if ORDER >= 5 {
                let (dm1, dm2) = (up(d2_m, d2_p), up(d2_mm, d2_pp));
                p += d2_0[j] - 2.0 * dm1 + dm2;
                let (dp1, dm1, dm2) = (up(d3_p, d3_m), up(d3_m, d3_p), up(d3_mm, d3_pp));
                p -= dp1 - 3.0 * d3_0[j] + 3.0 * dm1 - dm2;
            }
            if ORDER >= 7 {
                let (dp2, dp1) = (up(d4_pp, d4_mm), up(d4_p, d4_m));
                let (dm1, dm2) = (up(d4_m, d4_p), up(d4_mm, d4_pp));
                p += dp2 - 4.0 * dp1 + 6.0 * d4_0[j] - 4.0 * dm1 + dm2;
                let (dp2, dp1) = (up(d5_pp, d5_mm), up(d5_p, d5_m));
                let (dm1, dm2, dm3) = (up(d5_m, d5_p), up(d5_mm, d5_pp), up(d5_mmm, d5_ppp));
                p -= dp2 - 5.0 * dp1 + 10.0 * d5_0[j] - 10.0 * dm1 + 5.0 * dm2 - dm3;
            }
            if !LIMITED {
                out[j] = p;
            } else {
                let nu_up = up(nu_m, nu_p);
                let w0 = al[j];
                let w_up = up(al_m, al_p);
                let inv_a0 = inv_lam[j];
                // Bounds in Ψ space (numerics.md §1.5): 0 ↔ u_j, 2α0 ↔ u_{j+1}, b_md ↔ u^MD,
                // b_ul ↔ u^UL, b_lc ↔ u^LC.
                // NOTE: b_ul divides by max(ν_up, ν_0), not by ν_up alone: where a wave
                // stagnates at the upwind interface (λ_up → 0, a symmetry plane or a stagnation
                // point) α_up is round-off there and α_up/ν_up is round-off over round-off, which
                // let 1e-14 of noise move a face's flux by 2e-4 beside the cylinder's symmetry
                // axis (`fv::tests`, `osmp_bounds_are_well_conditioned_at_a_stagnation_point`).
                // The bound is tighter, so still TVD; where ν_up ≥ ν_0 (every scalar test) it is
                // Tenaud's.
                let b_max = 2.0 * w0;
                let b_ul = 2.0 * (1.0 - nu_up) * w_up * fmin(up(inv_nu_m, inv_nu_p), inv_nu[j]);
                let b_md = w0 - dm4[j] * inv_a0;
                let b_lc = (1.0 - nu_up) * inv_nu[j] * (w_up + up(dm4_m, dm4_p) * inv_a0);
                let lo1 = fmin(fmin(0.0, b_max), b_md);
                let hi1 = fmax(fmax(0.0, b_max), b_md);
                let lo2 = fmin(fmin(0.0, b_ul), b_lc);
                let hi2 = fmax(fmax(0.0, b_ul), b_lc);
                let psi_min = fmax(lo1, lo2);
                let psi_max = fmin(hi1, hi2);
                out[j] = fmax(psi_min, fmin(p, psi_max));
            }
        }};
    }
    // Upwind orientation: D_m is at f + m for λ > 0, at f − m otherwise. Where the speeds of
    // some faces are positive and of others not, both sides are loaded and their bits blended
    // by the mask of λ > 0: the value of `if λ > 0 { a } else { b }`, bit for bit.
    // NOTE: written as that `if`, the select of two loads became one load from a selected
    // address, which LLVM vectorised as a gather (`vgatherqpd`, 8 lanes loaded one by one, ten
    // a wave's face in AVX-512) and left scalar for AVX2 and SSE2; as a blend of bits it is
    // two contiguous loads (the second masked) in every instruction set.
    let blend = |a: &[f64], b: &[f64], j: usize| {
        let pos = u64::from(lam[j] > 0.0).wrapping_neg();
        let (x, y) = (a[j].to_bits(), b[j].to_bits());
        f64::from_bits((x & pos) | (y & !pos))
    };
    let above = |a: &[f64], _: &[f64], j: usize| a[j];
    let below = |_: &[f64], b: &[f64], j: usize| b[j];
    debug_assert!(
        side == Upwind::Mixed || side == Upwind::of(lam),
        "the side of other speeds"
    );
    match side {
        Upwind::Above => {
            for j in 0..nf {
                face!(j, above);
            }
        }
        Upwind::Below => {
            for j in 0..nf {
                face!(j, below);
            }
        }
        Upwind::Mixed => {
            for j in 0..nf {
                face!(j, blend);
            }
        }
    }
}

/// [`psi_line`] with the order chosen at run time (3, 5 or 7), for the scalar tests.
#[cfg(test)]
pub(crate) fn psi_line_dyn(
    order: u32,
    limited: bool,
    speed: &SpeedLine,
    wave: &WaveLine,
    f0: usize,
    out: &mut [f64],
) {
    let side = Upwind::of(&speed.lam[f0..f0 + out.len()]);
    match (order, limited) {
        (3, true) => psi_line::<3, true, _>(speed, wave, f0, out, side),
        (3, false) => psi_line::<3, false, _>(speed, wave, f0, out, side),
        (5, true) => psi_line::<5, true, _>(speed, wave, f0, out, side),
        (5, false) => psi_line::<5, false, _>(speed, wave, f0, out, side),
        (7, true) => psi_line::<7, true, _>(speed, wave, f0, out, side),
        (7, false) => psi_line::<7, false, _>(speed, wave, f0, out, side),
        _ => panic!("osmp order {order} (3, 5 or 7)"),
    }
}
