//! One directional update of one pencil (a line of cells along the sweep axis): the kernel
//! every sweep runs, with its reusable scratch.
//!
//! The caller fills [`LineScratch::u`] with `n + 2 ng` sweep-frame states (ghosts included,
//! see `sweep.rs`) and calls [`advance_line`]; the `n` updated interior states land in
//! [`LineScratch::new`] and the `n + 1` face fluxes in [`LineScratch::face`].
//!
//! Face flux choice, in this order:
//! 1. a vacuum cell on either side (ρ or p below the thresholds): Lax–Friedrichs (paper 000
//!    §3.2), which divides by neither ρ nor p; between two vacuum cells its local form
//!    (`euler::flux_local_lax_friedrichs`, the classical flux where a side's speed exceeds
//!    `Δx/Δt`): positivity preserving under the step's CFL condition as the classical flux is,
//!    but it diffuses at the gas's speed rather than at `Δx/Δt`, so that an odd–even mode of
//!    round-off in near-vacuum cells does not grow in the cut cells a withdrawing solid opens
//!    (docs/cut-cells.md §4);
//! 2. a non-physical Roe average (c² ≤ 0) anywhere in the stencil, or negative linearised star
//!    states at the face: HLLE (numerics.md §1.8, not in Daru–Tenaud);
//! 3. otherwise the scheme's flux (OSMP, or the MUSCL–Hancock/HLLC reference).
//!
//! After the update a cell with ρ ≤ 0 or p ≤ 0 (or non-finite) has its two faces recomputed
//! with HLLE, then Lax–Friedrichs (a local Lax–Friedrichs face: Lax–Friedrichs at once), at most
//! [`MAX_FIXES`] rounds (a-posteriori positivity safeguard of numerics.md §1.8). What is still
//! wrong is reported by the caller.
//!
//! Layout: the passes run over one array per quantity along the line (cells, interfaces,
//! waves, face components) without branches, so that each vectorises on the instruction set
//! the line runs on (`isa.rs`); the scheme's flux is computed at every face, and the special
//! faces (vacuum, HLLE fallback, positivity fix) overwrite theirs afterwards, one by one, on the
//! slower scalar path.

use crate::fv::euler::{
    NQ, Primitive, RoeAverage, RoeSide, State, flux_hlle, flux_lax_friedrichs,
    flux_local_lax_friedrichs, physical_flux, primitive_floored, roe_eigenvector,
    roe_star_states_positive, roe_strengths,
};
use crate::fv::isa::Isa;
use crate::fv::osmp::{SpeedLine, WaveLine, psi_line, stencil_radius};

mod muscl;

/// Rounds of the a-posteriori positivity fix.
pub const MAX_FIXES: usize = 3;

/// The numerical flux of the regular faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum FluxKind {
    /// OSMP of Daru & Tenaud of the given order (3, 5 or 7).
    Osmp(u32),
    /// Second-order TVD reference: MUSCL–Hancock on primitive variables with the
    /// monotonized-central limiter and the HLLC solver (Toro 2009, §14.4), used for
    /// work–precision comparisons.
    MusclHancock,
}

impl FluxKind {
    /// Ghost cells per side this flux needs.
    pub fn ghost_cells(self) -> usize {
        match self {
            FluxKind::Osmp(order) => crate::fv::osmp::ghost_cells(order),
            FluxKind::MusclHancock => 2,
        }
    }
}

/// Constant inputs of one line update.
#[derive(Clone, Copy, Debug)]
pub struct LineSetup {
    /// Interior cells of the line.
    pub n: usize,
    /// Ghost cells on each side.
    pub ng: usize,
    /// Regular flux.
    pub flux: FluxKind,
    /// `Δt/Δx` [s/m].
    pub sigma: f64,
    /// Ratio of specific heats γ [-].
    pub gamma: f64,
    /// Active shear waves (dimension − 1).
    pub n_shear: usize,
    /// Vacuum density threshold [kg/m³].
    pub vacuum_rho: f64,
    /// Vacuum pressure threshold \[Pa\].
    pub vacuum_p: f64,
    /// Whether the low / high end of the line is a wall face.
    pub wall: [bool; 2],
    /// The cells `own[0]..own[1]` this line reports on (`0..n` unless a decomposed pencil
    /// also updates cells of its neighbours, `slab.rs`): the counters, the fixes and the first
    /// bad cell count these cells, and the faces `own[0]..own[1]` (plus face `n` when
    /// `own[1] == n` and `end_face`), so that a face shared by two ranks is counted once.
    pub own: [usize; 2],
    /// Whether face `n` is this line's to count when `own[1] == n`: true for a whole line; false
    /// for a segment of a decomposed pencil that ends at the first cell of the rank above
    /// (`sweep.rs`, a wall run starting there), whose face that rank counts.
    pub end_face: bool,
}

/// Which flux a face used.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FaceFlux {
    /// The regular flux (OSMP or MUSCL–Hancock).
    #[default]
    Regular,
    /// HLLE fallback.
    Hlle,
    /// Local Lax–Friedrichs (between two vacuum cells).
    LocalLaxFriedrichs,
    /// Lax–Friedrichs (beside vacuum, and the last fallback).
    LaxFriedrichs,
}

/// Counters of one line update.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LineStats {
    /// Faces that used Lax–Friedrichs, local (between vacuum cells) or classical.
    pub lax_friedrichs: u32,
    /// Faces that used the HLLE fallback.
    pub hlle: u32,
    /// Cells whose faces were recomputed by the positivity fix.
    pub positivity_fixes: u32,
    /// First interior cell still non-physical after the fixes (counted from `own[0]`).
    pub first_bad: Option<u32>,
}

/// Reusable buffers of one line update (one per worker thread).
///
/// Cell and interface quantities are kept as one array each (structure of arrays), so that the
/// loops over a line vectorise.
#[derive(Clone, Debug, Default)]
pub struct LineScratch {
    /// Input states, `n + 2 ng` (filled by the caller).
    pub u: Vec<State>,
    /// Output: updated interior states, `n`.
    pub new: Vec<State>,
    /// Output: face fluxes, `n + 1` (face `i` is the left face of interior cell `i`).
    pub face: Vec<State>,
    cells: CellLine,
    vacuum: Vec<bool>,
    roe: RoeLine,
    /// The regular face fluxes, one array per component (written by the vectorised loop,
    /// then copied into [`LineScratch::face`]).
    face_q: [Vec<f64>; NQ],
    bad_prefix: Vec<u32>,
    speeds: [SpeedLine; 3],
    waves: [WaveLine; NQ],
    psi: [Vec<f64>; NQ],
    star_ok: Vec<bool>,
    kind: Vec<FaceFlux>,
    left: Vec<State>,
    right: Vec<State>,
    /// A whole pencil's input, states and faces while its segments are updated one by one
    /// (pencils cut at thin walls, `sweep.rs`).
    pub(crate) pencil: Vec<State>,
    pub(crate) pencil_new: Vec<State>,
    pub(crate) pencil_face: Vec<State>,
    /// The interior cells of a block of pencils, in and out (`block.rs`).
    pub(crate) tile: Vec<State>,
    /// The instruction set [`advance_line`] runs on ([`Isa::best`] unless set).
    isa: Isa,
}

/// What the cells of a line give the interfaces, one array per quantity (structure of arrays,
/// so that the loops over the line vectorise): the conserved state, the velocity and the
/// other Roe-average side quantities, the pressure, the physical flux; and the primitives as
/// structs for MUSCL–Hancock.
#[derive(Clone, Debug, Default)]
struct CellLine {
    prim: Vec<Primitive>,
    q: [Vec<f64>; NQ],
    vel: [Vec<f64>; 3],
    sqrt_rho: Vec<f64>,
    h: Vec<f64>,
    flux: [Vec<f64>; NQ],
}

impl CellLine {
    fn resize(&mut self, len: usize) {
        self.prim.resize(len, Primitive::default());
        let arrays = self.q.iter_mut().chain(&mut self.vel).chain(&mut self.flux);
        for v in arrays.chain([&mut self.sqrt_rho, &mut self.h]) {
            v.resize(len, 0.0);
        }
    }

    /// The cells `lo .. lo + len` as slices of one length, so that a loop over them has no
    /// bounds checks left and vectorises.
    #[inline(always)]
    fn view(&self, lo: usize, len: usize) -> CellView<'_> {
        let r = lo..lo + len;
        CellView {
            q: std::array::from_fn(|k| &self.q[k][r.clone()]),
            vel: std::array::from_fn(|k| &self.vel[k][r.clone()]),
            sqrt_rho: &self.sqrt_rho[r.clone()],
            h: &self.h[r.clone()],
            flux: std::array::from_fn(|k| &self.flux[k][r.clone()]),
        }
    }
}

/// Slices of a [`CellLine`], all of one length.
struct CellView<'a> {
    q: [&'a [f64]; NQ],
    vel: [&'a [f64]; 3],
    sqrt_rho: &'a [f64],
    h: &'a [f64],
    flux: [&'a [f64]; NQ],
}

impl CellView<'_> {
    /// The Roe-average side of cell `i` (as [`RoeSide::new`] gives it).
    #[inline(always)]
    fn side(&self, i: usize) -> RoeSide {
        RoeSide {
            sqrt_rho: self.sqrt_rho[i],
            vel: [self.vel[0][i], self.vel[1][i], self.vel[2][i]],
            h: self.h[i],
        }
    }

    /// The conserved state of cell `i`.
    #[inline(always)]
    fn state(&self, i: usize) -> State {
        std::array::from_fn(|q| self.q[q][i])
    }
}

/// The Roe averages of a line's interfaces, one array per field.
#[derive(Clone, Debug, Default)]
struct RoeLine {
    vel: [Vec<f64>; 3],
    h: Vec<f64>,
    c: Vec<f64>,
    valid: Vec<bool>,
}

impl RoeLine {
    fn resize(&mut self, len: usize) {
        for v in self.vel.iter_mut().chain([&mut self.h, &mut self.c]) {
            v.resize(len, 0.0);
        }
        self.valid.resize(len, false);
    }

    /// The average of interface `l` of slices `vel, h, c, valid` of a `RoeLine` (of one
    /// length, so that no bounds check stays in a loop).
    #[inline(always)]
    fn get(vel: [&[f64]; 3], h: &[f64], c: &[f64], valid: &[bool], l: usize) -> RoeAverage {
        RoeAverage {
            vel: [vel[0][l], vel[1][l], vel[2][l]],
            h: h[l],
            c: c[l],
            valid: valid[l],
        }
    }
}

impl LineScratch {
    /// The instruction set [`advance_line`] runs on.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// Runs [`advance_line`] on `isa` from now on (the results are the same bits on every
    /// ISA; this is for the tests that check it and for benchmarks).
    ///
    /// # Panics
    /// If this CPU does not have `isa` ([`Isa::supported`]).
    pub fn set_isa(&mut self, isa: Isa) {
        assert!(isa.supported(), "this CPU has no {isa:?}");
        self.isa = isa;
    }

    /// Sizes the buffers for `n` interior and `ng` ghost cells per side.
    pub fn resize(&mut self, n: usize, ng: usize) {
        let len = n + 2 * ng;
        self.u.resize(len, [0.0; NQ]);
        self.new.resize(n, [0.0; NQ]);
        self.face.resize(n + 1, [0.0; NQ]);
        self.cells.resize(len);
        self.vacuum.resize(len, false);
        self.roe.resize(len - 1);
        for v in &mut self.face_q {
            v.resize(n + 1, 0.0);
        }
        self.bad_prefix.resize(len, 0);
        for sp in &mut self.speeds {
            sp.resize(len - 1);
        }
        for w in &mut self.waves {
            w.resize(len - 1);
        }
        for p in &mut self.psi {
            p.resize(n + 1, 0.0);
        }
        self.star_ok.resize(n + 1, false);
        self.kind.resize(n + 1, FaceFlux::Regular);
        self.left.resize(len, [0.0; NQ]);
        self.right.resize(len, [0.0; NQ]);
    }
}

/// Whether an updated state is acceptable: finite, and either a gas (ρ and p at or above the
/// vacuum thresholds) or a vacuum cell (ρ or p below them) whose ρ and p are above minus the
/// thresholds.
///
/// A vacuum cell holds ρ = p = 0 and a velocity (paper 000 §3.2). What a crack cell holds once
/// the cut-cell sums and fluxes have cancelled is round-off of the neighbours' content, of
/// either sign: ρ ~ ±1e-18 beside gas of ρ ~ 1, or ρ ~ 1e-19 moving at a few m/s with p ~ −1e-18
/// from `E − ½ρ|u|²`. That still reads as vacuum: `primitive` gives no velocity where ρ ≤ 0, the
/// sound speed is 0 where p ≤ 0, the faces beside it take the Lax–Friedrichs flux, which
/// divides by neither, and the vacuum count counts it. Below minus the thresholds it is
/// numerical trouble (the default thresholds, 1e-10, pass round-off only).
#[inline(always)]
pub fn state_ok(u: &State, gamma: f64, vacuum_rho: f64, vacuum_p: f64) -> bool {
    let w = primitive_floored(u, gamma, vacuum_rho);
    let finite = u.iter().all(|x| x.is_finite()) && w.p.is_finite();
    let gas = w.rho >= vacuum_rho && w.p >= vacuum_p;
    finite && (gas || (w.rho > -vacuum_rho && w.p > -vacuum_p))
}

/// Advances one line by `Δt = sigma Δx` (see the module doc), on the instruction set of
/// [`LineScratch::isa`] (the same bits on each, `isa.rs`).
pub fn advance_line(s: &mut LineScratch, setup: &LineSetup) -> LineStats {
    match s.isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if Isa::Avx512.supported() => {
            // SAFETY: the CPU has AVX-512F (checked on the line above).
            unsafe { advance_line_avx512(s, setup) }
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if Isa::Avx2.supported() => {
            // SAFETY: the CPU has AVX2 (checked on the line above).
            unsafe { advance_line_avx2(s, setup) }
        }
        _ => advance_line_body(s, setup),
    }
}

/// [`advance_line_body`] compiled for AVX2 (without FMA, `isa.rs`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn advance_line_avx2(s: &mut LineScratch, setup: &LineSetup) -> LineStats {
    advance_line_body(s, setup)
}

/// [`advance_line_body`] compiled for AVX-512F (without FMA, `isa.rs`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn advance_line_avx512(s: &mut LineScratch, setup: &LineSetup) -> LineStats {
    advance_line_body(s, setup)
}

/// The body of [`advance_line`]: inlined, with the passes it calls, into each ISA's copy.
#[inline(always)]
fn advance_line_body(s: &mut LineScratch, setup: &LineSetup) -> LineStats {
    let LineSetup { n, ng, .. } = *setup;
    let gamma = setup.gamma;
    let len = n + 2 * ng;
    debug_assert!(s.u.len() == len && s.face.len() == n + 1);
    let mut stats = LineStats::default();
    cell_pass(s, setup);
    match setup.flux {
        FluxKind::Osmp(3) => osmp_faces::<3>(s, setup),
        FluxKind::Osmp(5) => osmp_faces::<5>(s, setup),
        FluxKind::Osmp(7) => osmp_faces::<7>(s, setup),
        FluxKind::Osmp(order) => panic!("osmp order {order} (3, 5 or 7; checked at setup)"),
        FluxKind::MusclHancock => muscl::muscl_faces(s, setup),
    }
    for side in 0..2 {
        if setup.wall[side] {
            let f = if side == 0 { 0 } else { n };
            wall_face(&mut s.face[f]);
        }
    }
    update_cells(s, setup, 0, n);
    // A-posteriori positivity safeguard.
    let mut clean = false;
    for _round in 0..MAX_FIXES {
        let mut changed = false;
        clean = true;
        for m in 0..n {
            if state_ok(&s.new[m], gamma, setup.vacuum_rho, setup.vacuum_p) {
                continue;
            }
            clean = false;
            if (setup.own[0]..setup.own[1]).contains(&m) {
                stats.positivity_fixes += 1;
            }
            for f in [m, m + 1] {
                let (ul, ur) = (s.u[ng - 1 + f], s.u[ng + f]);
                let (flux, kind) = match s.kind[f] {
                    FaceFlux::Regular => (flux_hlle(&ul, &ur, gamma), FaceFlux::Hlle),
                    _ => (
                        flux_lax_friedrichs(&ul, &ur, setup.sigma, gamma, setup.vacuum_rho),
                        FaceFlux::LaxFriedrichs,
                    ),
                };
                if kind != s.kind[f] {
                    changed = true;
                }
                s.face[f] = flux;
                s.kind[f] = kind;
                if (f == 0 && setup.wall[0]) || (f == n && setup.wall[1]) {
                    wall_face(&mut s.face[f]);
                }
            }
        }
        if !changed {
            break;
        }
        update_cells(s, setup, 0, n);
        clean = false;
    }
    let [own_lo, own_hi] = setup.own;
    stats.first_bad = (own_lo..own_hi)
        .filter(|_| !clean)
        .find(|&m| !state_ok(&s.new[m], gamma, setup.vacuum_rho, setup.vacuum_p))
        .map(|m| (m - own_lo) as u32);
    let last_face = if own_hi == n && setup.end_face {
        n + 1
    } else {
        own_hi
    };
    for k in &s.kind[own_lo..last_face] {
        match k {
            FaceFlux::Hlle => stats.hlle += 1,
            FaceFlux::LocalLaxFriedrichs | FaceFlux::LaxFriedrichs => stats.lax_friedrichs += 1,
            FaceFlux::Regular => {}
        }
    }
    stats
}

/// A wall face carries only the normal momentum flux (the wall pressure).
///
/// NOTE: with mirror ghosts the scheme gives zero mass, tangential-momentum and energy fluxes
/// only up to round-off; zeroing them makes conservation in a closed box exact.
#[inline]
fn wall_face(f: &mut State) {
    *f = [0.0, f[1], 0.0, 0.0, 0.0];
}

#[inline(always)]
fn update_cells(s: &mut LineScratch, setup: &LineSetup, lo: usize, hi: usize) {
    let sigma = setup.sigma;
    for m in lo..hi {
        let u = &s.u[setup.ng + m];
        let (fl, fr) = (&s.face[m], &s.face[m + 1]);
        let out = &mut s.new[m];
        for q in 0..NQ {
            out[q] = u[q] - sigma * (fr[q] - fl[q]);
        }
    }
}

/// Number of waves processed: acoustic pair, entropy, and the active shear waves.
#[inline]
fn n_waves(setup: &LineSetup) -> usize {
    3 + setup.n_shear
}

/// Primitive variables, Roe-average sides, physical fluxes and vacuum flags of every cell of
/// the line (the primitives as structs only for MUSCL–Hancock).
#[inline(always)]
fn cell_pass(s: &mut LineScratch, setup: &LineSetup) {
    let len = s.u.len();
    let u = &s.u[..len];
    let c = &mut s.cells;
    for (q, cq) in c.q.iter_mut().enumerate() {
        let cq = &mut cq[..len];
        for i in 0..len {
            cq[i] = u[i][q];
        }
    }
    let q: [&[f64]; NQ] = std::array::from_fn(|k| &c.q[k][..len]);
    let [v0, v1, v2] = &mut c.vel;
    let vel = [&mut v0[..len], &mut v1[..len], &mut v2[..len]];
    let [f0, f1, f2, f3, f4] = &mut c.flux;
    let flux_q = [
        &mut f0[..len],
        &mut f1[..len],
        &mut f2[..len],
        &mut f3[..len],
        &mut f4[..len],
    ];
    let (sqrt_rho, h) = (&mut c.sqrt_rho[..len], &mut c.h[..len]);
    let vacuum = &mut s.vacuum[..len];
    for i in 0..len {
        let ui: State = std::array::from_fn(|k| q[k][i]);
        let w = primitive_floored(&ui, setup.gamma, setup.vacuum_rho);
        // NaN or infinite where ρ ≤ 0: such interfaces are marked invalid before use.
        let side = RoeSide::new(&ui, &w);
        let flux = physical_flux(&ui, &w);
        for k in 0..3 {
            vel[k][i] = side.vel[k];
        }
        sqrt_rho[i] = side.sqrt_rho;
        h[i] = side.h;
        for k in 0..NQ {
            flux_q[k][i] = flux[k];
        }
        vacuum[i] = !(w.rho >= setup.vacuum_rho && w.p >= setup.vacuum_p);
    }
    if setup.flux == FluxKind::MusclHancock {
        for i in 0..len {
            c.prim[i] = primitive_floored(&u[i], setup.gamma, setup.vacuum_rho);
        }
    }
}

/// Roe averages, wave speeds and strengths at every interface of the line. An interface beside
/// a vacuum cell or with a non-physical average (c² ≤ 0, non-finite) is marked invalid and
/// gets λ = α = 0.
#[inline(always)]
fn interface_pass(s: &mut LineScratch, setup: &LineSetup) {
    let nint = s.u.len() - 1;
    let cells = s.cells.view(0, nint + 1);
    let [rv0, rv1, rv2] = &mut s.roe.vel;
    let [s0, s1, s2] = &mut s.speeds;
    let [w0, w1, w2, w3, w4] = &mut s.waves;
    interface_loop(
        &cells,
        &s.vacuum[..nint + 1],
        setup.gamma,
        &mut rv0[..nint],
        &mut rv1[..nint],
        &mut rv2[..nint],
        &mut s.roe.h[..nint],
        &mut s.roe.c[..nint],
        &mut s.roe.valid[..nint],
        &mut s0.lam[..nint],
        &mut s1.lam[..nint],
        &mut s2.lam[..nint],
        &mut w0.alpha[..nint],
        &mut w1.alpha[..nint],
        &mut w2.alpha[..nint],
        &mut w3.alpha[..nint],
        &mut w4.alpha[..nint],
    );
}

/// The loop of [`interface_pass`]. Its outputs are separate `&mut` arguments: they reach the
/// compiler as `noalias` (also once inlined), which the loop needs to vectorise with sixteen
/// output arrays (slices cut from one `&mut LineScratch` in one function body do not, and the
/// loop stayed scalar).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn interface_loop(
    cells: &CellView<'_>,
    vacuum: &[bool],
    gamma: f64,
    roe_v0: &mut [f64],
    roe_v1: &mut [f64],
    roe_v2: &mut [f64],
    roe_h: &mut [f64],
    roe_c: &mut [f64],
    roe_valid: &mut [bool],
    lam0: &mut [f64],
    lam1: &mut [f64],
    lam2: &mut [f64],
    a0: &mut [f64],
    a1: &mut [f64],
    a2: &mut [f64],
    a3: &mut [f64],
    a4: &mut [f64],
) {
    let nint = roe_h.len();
    let (roe_v0, roe_v1, roe_v2) = (
        &mut roe_v0[..nint],
        &mut roe_v1[..nint],
        &mut roe_v2[..nint],
    );
    let (roe_c, roe_valid) = (&mut roe_c[..nint], &mut roe_valid[..nint]);
    let (lam0, lam1, lam2) = (&mut lam0[..nint], &mut lam1[..nint], &mut lam2[..nint]);
    let (a0, a1, a2) = (&mut a0[..nint], &mut a1[..nint], &mut a2[..nint]);
    let (a3, a4) = (&mut a3[..nint], &mut a4[..nint]);
    let vacuum = &vacuum[..nint + 1];
    let rho = &cells.q[0][..nint + 1];
    for l in 0..nint {
        let sides_ok = !vacuum[l] & !vacuum[l + 1] & (rho[l] > 0.0) & (rho[l + 1] > 0.0);
        let average = RoeSide::average(&cells.side(l), &cells.side(l + 1), gamma, sides_ok);
        let du: State = std::array::from_fn(|q| cells.q[q][l + 1] - cells.q[q][l]);
        // An invalid average is all zeros (so λ = 0), but its strengths divide by c = 0.
        let alpha =
            roe_strengths(&average, &du, gamma).map(|a| if average.valid { a } else { 0.0 });
        [roe_v0[l], roe_v1[l], roe_v2[l]] = average.vel;
        roe_h[l] = average.h;
        roe_c[l] = average.c;
        roe_valid[l] = average.valid;
        let (un, c) = (average.vel[0], average.c);
        [lam0[l], lam1[l], lam2[l]] = [un - c, un + c, un];
        [a0[l], a1[l], a2[l], a3[l], a4[l]] = alpha;
    }
}

#[inline(always)]
fn osmp_faces<const ORDER: u32>(s: &mut LineScratch, setup: &LineSetup) {
    let LineSetup {
        n,
        ng,
        gamma,
        sigma,
        ..
    } = *setup;
    let radius = stencil_radius(ORDER);
    let nw = n_waves(setup);
    let inv_sigma = 1.0 / sigma;
    interface_pass(s, setup);
    for sp in &mut s.speeds {
        sp.fill(ORDER, sigma, inv_sigma);
    }
    // Wave k travels at speed [u−c, u+c, u, u, u][k].
    for k in 0..nw {
        let speed = &s.speeds[k.min(2)];
        s.waves[k].fill(ORDER, speed);
        psi_line::<ORDER, true>(speed, &s.waves[k], ng - 1, &mut s.psi[k]);
    }
    for k in nw..NQ {
        s.psi[k].fill(0.0);
    }
    // Regular (OSMP) flux at every face, and whether its linearised star states are
    // physical.
    {
        let nf = n + 1;
        let f0 = ng - 1;
        let cells = s.cells.view(f0, nf + 1);
        let r = &s.roe;
        let roe_vel: [&[f64]; 3] = std::array::from_fn(|k| &r.vel[k][f0..f0 + nf]);
        let (roe_h, roe_c) = (&r.h[f0..f0 + nf], &r.c[f0..f0 + nf]);
        let roe_valid = &r.valid[f0..f0 + nf];
        let lam: [&[f64]; 3] = std::array::from_fn(|k| &s.speeds[k].lam[f0..f0 + nf]);
        let alpha: [&[f64]; NQ] = std::array::from_fn(|k| &s.waves[k].alpha[f0..f0 + nf]);
        let psi: [&[f64]; NQ] = std::array::from_fn(|k| &s.psi[k][..nf]);
        let [fq0, fq1, fq2, fq3, fq4] = &mut s.face_q;
        let roe = (roe_vel, roe_h, roe_c, roe_valid);
        face_loop(
            &cells,
            roe,
            (lam, alpha, psi),
            &mut s.star_ok[..nf],
            &mut fq0[..nf],
            &mut fq1[..nf],
            &mut fq2[..nf],
            &mut fq3[..nf],
            &mut fq4[..nf],
        );
        for (j, face) in s.face[..nf].iter_mut().enumerate() {
            *face = std::array::from_fn(|q| s.face_q[q][j]);
        }
    }
    // Faces beside vacuum: Lax–Friedrichs (local between two); an invalid average in the stencil or
    // non-physical star states: HLLE.
    // NOTE: the usual line has no invalid average and no vacuum cell; it then skips the
    // prefix count and the per-face calls (the same choice for every face, made faster: the
    // two were 3 % of a 3-D step).
    let all_valid = s.roe.valid.iter().fold(true, |acc, &v| acc & v);
    if !all_valid {
        s.bad_prefix[0] = 0;
        for l in 0..s.roe.valid.len() {
            s.bad_prefix[l + 1] = s.bad_prefix[l] + u32::from(!s.roe.valid[l]);
        }
    }
    for fi in 0..=n {
        let f = ng - 1 + fi;
        let regular = !(s.vacuum[f] | s.vacuum[f + 1]) & s.star_ok[fi];
        if regular && all_valid {
            s.kind[fi] = FaceFlux::Regular;
            continue;
        }
        if vacuum_face(s, setup, fi, f) {
            continue;
        }
        let bad_stencil = !all_valid && s.bad_prefix[f + radius + 1] > s.bad_prefix[f - radius];
        if bad_stencil || !s.star_ok[fi] {
            s.face[fi] = flux_hlle(&s.u[f], &s.u[f + 1], gamma);
            s.kind[fi] = FaceFlux::Hlle;
        } else {
            s.kind[fi] = FaceFlux::Regular;
        }
    }
}

/// The flux of face `fi` (between the line's cells `f` and `f + 1`) when either side is a
/// vacuum cell: Lax–Friedrichs (paper 000 §3.2), in its local form between two vacuum cells
/// (docs/cut-cells.md §4). Returns whether it was such a face.
fn vacuum_face(s: &mut LineScratch, setup: &LineSetup, fi: usize, f: usize) -> bool {
    let (l, r) = (s.vacuum[f], s.vacuum[f + 1]);
    let (ul, ur, sigma, gamma) = (&s.u[f], &s.u[f + 1], setup.sigma, setup.gamma);
    (s.face[fi], s.kind[fi]) = match (l, r) {
        (false, false) => return false,
        (true, true) => (
            flux_local_lax_friedrichs(ul, ur, sigma, gamma, setup.vacuum_rho),
            FaceFlux::LocalLaxFriedrichs,
        ),
        _ => (
            flux_lax_friedrichs(ul, ur, sigma, gamma, setup.vacuum_rho),
            FaceFlux::LaxFriedrichs,
        ),
    };
    true
}

/// The regular flux of every face `j` of `cells` (faces between cells `j` and `j + 1`) into
/// `fq0..fq4`, and whether its linearised star states are physical. The outputs are separate
/// `&mut` arguments so that the loop vectorises (see [`interface_loop`]).
#[inline(always)]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn face_loop(
    cells: &CellView<'_>,
    (roe_vel, roe_h, roe_c, roe_valid): ([&[f64]; 3], &[f64], &[f64], &[bool]),
    (lam, alpha, psi): ([&[f64]; 3], [&[f64]; NQ], [&[f64]; NQ]),
    star_ok: &mut [bool],
    fq0: &mut [f64],
    fq1: &mut [f64],
    fq2: &mut [f64],
    fq3: &mut [f64],
    fq4: &mut [f64],
) {
    let nf = star_ok.len();
    let (fq0, fq1, fq2, fq3, fq4) = (
        &mut fq0[..nf],
        &mut fq1[..nf],
        &mut fq2[..nf],
        &mut fq3[..nf],
        &mut fq4[..nf],
    );
    let phys = cells.flux;
    for j in 0..nf {
        let roe = RoeLine::get(roe_vel, roe_h, roe_c, roe_valid, j);
        let mut flux = [0.0; NQ];
        for q in 0..NQ {
            flux[q] = 0.5 * (phys[q][j] + phys[q][j + 1]);
        }
        let mut a = [0.0; NQ];
        let mut coef = [0.0; NQ];
        for k in 0..NQ {
            a[k] = alpha[k][j];
            coef[k] = 0.5 * lam[k.min(2)][j].abs() * (a[k] - psi[k][j]);
        }
        // NOTE: the two acoustic waves are summed first: a mirror image of the line swaps
        // them (u − c ↔ u + c) and maps the others onto themselves, so the flux of a mirror
        // image is the mirror image of the flux to the last bit (a problem symmetric about
        // a plane stays symmetric, the integration test `fv_mirror`), whatever the order of the others.
        let (r0, r1) = (roe_eigenvector(&roe, 0), roe_eigenvector(&roe, 1));
        for q in 0..NQ {
            flux[q] -= coef[0] * r0[q] + coef[1] * r1[q];
        }
        for k in 2..NQ {
            let r = roe_eigenvector(&roe, k);
            for q in 0..NQ {
                flux[q] -= coef[k] * r[q];
            }
        }
        [fq0[j], fq1[j], fq2[j], fq3[j], fq4[j]] = flux;
        let (ul, ur) = (cells.state(j), cells.state(j + 1));
        star_ok[j] = roe_star_states_positive(&ul, &ur, &roe, &a);
    }
}
