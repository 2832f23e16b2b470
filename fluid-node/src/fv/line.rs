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
//! Layout: the passes run over one array per quantity (cells, interfaces, waves, face
//! components) without branches, so that each vectorises on the instruction set the line runs
//! on (`isa.rs`), and over strips of 48 faces, so that their arrays stay in L1
//! (`line/strip.rs`); the scheme's flux is computed at every face, and the special faces
//! (vacuum, HLLE fallback, positivity fix) overwrite theirs afterwards, one by one, on the
//! slower scalar path.

use crate::fv::euler::{
    NQ, Primitive, State, flux_hlle, flux_lax_friedrichs, flux_local_lax_friedrichs,
    primitive_floored,
};
use crate::fv::isa::Isa;

mod muscl;
mod strip;

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
    /// The buffers of one strip of faces (`strip.rs`).
    strip: Box<strip::Strip>,
    /// `Ψ` of each wave at a strip's faces, lent to the kernel as an argument of its own
    /// (`advance_line`; `None` only while it is lent, or before the first line).
    psi: Option<Box<strip::Psi>>,
    /// Where the last strip started along the line (`strip.rs`).
    last_a: usize,
    /// Whether each cell is vacuum, `n + 2 ng`.
    vacuum: Vec<bool>,
    /// Whether the Roe average of each interface is valid, `n + 2 ng − 1`.
    valid: Vec<bool>,
    bad_prefix: Vec<u32>,
    star_ok: Vec<bool>,
    /// The primitive variables of every cell, for MUSCL–Hancock.
    prim: Vec<Primitive>,
    kind: Vec<FaceFlux>,
    left: Vec<State>,
    right: Vec<State>,
    /// A whole pencil's input, states and faces while its segments are updated one by one
    /// (pencils cut at thin walls, `sweep.rs`).
    pub(crate) pencil: Vec<State>,
    pub(crate) pencil_new: Vec<State>,
    pub(crate) pencil_face: Vec<State>,
    /// The lines of a block of pencils, in (`u`'s layout) and out (`new`'s), swapped with `u`
    /// and `new` pencil by pencil (`block.rs`, `sweep.rs`).
    pub(crate) tile_u: Vec<Vec<State>>,
    pub(crate) tile_new: Vec<Vec<State>>,
    /// The instruction set [`advance_line`] runs on ([`Isa::best`] unless set).
    isa: Isa,
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
        self.vacuum.resize(len, false);
        self.valid.resize(len - 1, false);
        self.bad_prefix.resize(len, 0);
        self.star_ok.resize(n + 1, false);
        self.kind.resize(n + 1, FaceFlux::Regular);
        self.prim.resize(len, Primitive::default());
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
    // Branch-free (`&` and `|` of every comparison, the same answer as `&&` and `||`), so that
    // the check of a whole line (`advance_line`) has no branch a cell.
    let w = primitive_floored(u, gamma, vacuum_rho);
    let finite = u.iter().fold(w.p.is_finite(), |all, x| all & x.is_finite());
    let gas = (w.rho >= vacuum_rho) & (w.p >= vacuum_p);
    finite & (gas | ((w.rho > -vacuum_rho) & (w.p > -vacuum_p)))
}

/// Advances one line by `Δt = sigma Δx` (see the module doc), on the instruction set of
/// [`LineScratch::isa`] (the same bits on each, `isa.rs`).
///
/// NOTE: `Ψ`'s array is the scratch's, taken out for the line and passed to each instruction
/// set's copy of the kernel as an argument of its own: a `&mut` argument reaches the compiler
/// as `noalias`, so the `Ψ` loops need no run-time check of their output against the strip's
/// arrays, and the array is not zeroed a line (a `memset` of 3.2 kB a line while it was a
/// local array; held in the scratch and borrowed inside the kernel, the loops went back to
/// the checks, docs/performance.md, hQ2).
pub fn advance_line(s: &mut LineScratch, setup: &LineSetup) -> LineStats {
    let mut psi = s.psi.take().unwrap_or_else(strip::new_psi);
    // The flux's order as a constant of each copy of the kernel (0: MUSCL–Hancock).
    let order = match setup.flux {
        FluxKind::Osmp(order @ (3 | 5 | 7)) => order,
        FluxKind::Osmp(order) => panic!("osmp order {order} (3, 5 or 7; checked at setup)"),
        FluxKind::MusclHancock => 0,
    };
    macro_rules! on_order {
        ($kernel:ident) => {
            match order {
                3 => $kernel::<3>(s, setup, &mut psi),
                5 => $kernel::<5>(s, setup, &mut psi),
                7 => $kernel::<7>(s, setup, &mut psi),
                _ => $kernel::<0>(s, setup, &mut psi),
            }
        };
    }
    let stats = match s.isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if Isa::Avx512.supported() => {
            // SAFETY: the CPU has AVX-512F (checked on the line above).
            unsafe { on_order!(advance_line_avx512) }
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if Isa::Avx2.supported() => {
            // SAFETY: the CPU has AVX2 (checked on the line above).
            unsafe { on_order!(advance_line_avx2) }
        }
        _ => on_order!(advance_line_baseline),
    };
    s.psi = Some(psi);
    stats
}

/// [`advance_line_body`] for the baseline (a function of its own, so that `psi` is `noalias`
/// there too), one for each order (`ORDER`: 3, 5 or 7 for OSMP, 0 for MUSCL–Hancock).
///
/// NOTE: one function per instruction set and order, not per instruction set: with the strips
/// of five lengths each order's kernel holds six copies of the strip's code, and with all three
/// orders in one function (18 copies, 212 kB on AVX-512) LLVM compiled the interface pass of
/// the 72-face strips with 2.6 % more instructions in the kernel of a 128³ step than before.
#[inline(never)]
fn advance_line_baseline<const ORDER: u32>(
    s: &mut LineScratch,
    setup: &LineSetup,
    psi: &mut strip::Psi,
) -> LineStats {
    advance_line_body::<ORDER>(s, setup, psi)
}

/// [`advance_line_body`] compiled for AVX2 (without FMA, `isa.rs`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn advance_line_avx2<const ORDER: u32>(
    s: &mut LineScratch,
    setup: &LineSetup,
    psi: &mut strip::Psi,
) -> LineStats {
    advance_line_body::<ORDER>(s, setup, psi)
}

/// [`advance_line_body`] compiled for AVX-512F (without FMA, `isa.rs`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn advance_line_avx512<const ORDER: u32>(
    s: &mut LineScratch,
    setup: &LineSetup,
    psi: &mut strip::Psi,
) -> LineStats {
    advance_line_body::<ORDER>(s, setup, psi)
}

/// The body of [`advance_line`]: inlined, with the passes it calls, into each ISA's copy
/// (`psi`: `Ψ`'s array, see [`advance_line`]).
#[inline(always)]
fn advance_line_body<const ORDER: u32>(
    s: &mut LineScratch,
    setup: &LineSetup,
    psi: &mut strip::Psi,
) -> LineStats {
    let LineSetup { n, ng, .. } = *setup;
    let gamma = setup.gamma;
    let len = n + 2 * ng;
    debug_assert!(s.u.len() == len && s.face.len() == n + 1);
    let mut stats = LineStats::default();
    match ORDER {
        0 => muscl::muscl_faces(s, setup),
        _ => strip::osmp_faces::<ORDER>(s, setup, psi),
    }
    for side in 0..2 {
        if setup.wall[side] {
            let f = if side == 0 { 0 } else { n };
            wall_face(&mut s.face[f]);
        }
    }
    update_cells(s, setup, 0, n);
    // A-posteriori positivity safeguard.
    // NOTE: nearly every line has no bad cell: one pass without a branch a cell says so, and
    // the rounds below (whose first one would find none and change nothing) are skipped.
    let bad = s.new[..n].iter().fold(0u32, |bad, u| {
        bad + u32::from(!state_ok(u, gamma, setup.vacuum_rho, setup.vacuum_p))
    });
    let all_ok = bad == 0;
    let mut clean = all_ok;
    for _round in 0..if all_ok { 0 } else { MAX_FIXES } {
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
    // Counted without a branch a face.
    for k in &s.kind[own_lo..last_face] {
        stats.hlle += u32::from(*k == FaceFlux::Hlle);
        stats.lax_friedrichs += u32::from(matches!(
            k,
            FaceFlux::LocalLaxFriedrichs | FaceFlux::LaxFriedrichs
        ));
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

/// `new[m] = u[m] − σ (face[m + 1] − face[m])` for the cells `lo .. hi`.
///
/// NOTE: one loop over the values of the cells (`NQ` a cell, states and faces laid out one
/// after the other), so that it vectorises: value `i` of a cell's state takes value `i + NQ` of
/// the faces (the same component of the face above) minus value `i`, the same operations as a
/// loop over cells and components. Over `[f64; NQ]` cells the loop stayed scalar.
#[inline(always)]
fn update_cells(s: &mut LineScratch, setup: &LineSetup, lo: usize, hi: usize) {
    let sigma = setup.sigma;
    let len = (hi - lo) * NQ;
    let u = &s.u.as_flattened()[(setup.ng + lo) * NQ..][..len];
    let face = &s.face.as_flattened()[lo * NQ..][..len + NQ];
    let (fl, fr) = (&face[..len], &face[NQ..]);
    let out = &mut s.new.as_flattened_mut()[lo * NQ..][..len];
    for i in 0..len {
        out[i] = u[i] - sigma * (fr[i] - fl[i]);
    }
}

/// Number of waves processed: acoustic pair, entropy, and the active shear waves.
#[inline]
fn n_waves(setup: &LineSetup) -> usize {
    3 + setup.n_shear
}

/// The special faces, over the regular flux: beside vacuum, Lax–Friedrichs (local between two
/// vacuum cells); an invalid average in the stencil (`radius` interfaces either side) or
/// non-physical star states, HLLE.
///
/// NOTE: the usual line has no invalid average and no vacuum cell; it then skips the
/// prefix count and the per-face calls (the same choice for every face, made faster: the
/// two were 3 % of a 3-D step).
#[inline(always)]
fn special_faces(s: &mut LineScratch, setup: &LineSetup, radius: usize) {
    let LineSetup { n, ng, gamma, .. } = *setup;
    let all_valid = s.valid.iter().fold(true, |acc, &v| acc & v);
    // NOTE: the usual line has no special face at all: one pass without a branch a face says
    // so (the vacuum flags of each face's two cells and its star-state check), and every face
    // is regular.
    // NOTE: a loop over slices of one length: the fold over `0..=n` was a call of
    // `RangeInclusive::fold` a line, out of the kernel and one face at a time (~600
    // instructions a 3-D 128-cell line, 1.4 % of the kernel's).
    let (left, right) = (&s.vacuum[ng - 1..ng + n], &s.vacuum[ng..ng + n + 1]);
    let star_ok = &s.star_ok[..n + 1];
    let mut all_regular = all_valid;
    for fi in 0..n + 1 {
        all_regular &= !(left[fi] | right[fi]) & star_ok[fi];
    }
    if all_regular {
        s.kind[..=n].fill(FaceFlux::Regular);
        return;
    }
    if !all_valid {
        s.bad_prefix[0] = 0;
        for l in 0..s.valid.len() {
            s.bad_prefix[l + 1] = s.bad_prefix[l] + u32::from(!s.valid[l]);
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
