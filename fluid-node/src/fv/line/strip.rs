//! The regular (OSMP) faces of a line, strip by strip, and the special faces after them.
//!
//! A line longer than [`SHORT_RUN`] faces is cut into strips of one of the
//! [`STRIP_LENGTHS`]. Each strip runs every pass of the scheme over its part of the
//! line in a [`Strip`]'s buffers,
//! which the strips reuse and which stay in L1: the cell pass (primitive variables, Roe sides,
//! physical fluxes, vacuum flags), the interface pass (Roe averages, speeds, strengths), the
//! speeds' and waves' coefficients, OSMP's `Ψ` per wave (into an array on the stack of the
//! line's update), and the regular flux at the strip's faces (a function of its own for each
//! instruction set, [`face_loop_on`]). What a strip's faces read below its own cells and
//! interfaces (the stencils reach `R = stencil_radius` interfaces before a face) it takes from
//! the strip before, which computed it ([`Strip::carry`]): every cell and interface is computed
//! once, as before.
//!
//! Every loop of a strip runs over a number of entries fixed at compile time and a multiple of
//! 8 (the lanes of AVX-512), so that none has a scalar remainder: a strip is short, and a
//! remainder of up to 7 entries done one by one cost more than the strip saved (a first
//! version with strips of 26–33 faces was slower than the whole line). The entries beyond the
//! line's end (the last strip's) are computed on what an earlier strip left there, and are
//! never read by the line's own. A short line is one strip of its own length (loops of run-time
//! length): strips of fixed length would compute more faces than it has.
//!
//! NOTE: before, each pass ran over the whole line and wrote arrays that the next pass read:
//! about 80 arrays of `n + 2 ng` values, 90 kB for a 128-cell line, twice the 48 kB L1 of this
//! machine's cores, so every pass read and wrote its arrays in L2 (2.7 MB for the 1-D line of
//! 4096 cells, beyond the L2). The arrays a strip of 48 faces touches (OSMP5, 3-D) are about
//! 40 kB. Every value is computed from the same inputs by the same operations, so the line's
//! result is the same to the bit. Measured gain (CPU time a step, docs/performance.md): 1.23×
//! on the 1-D line of 4096 cells, 1.06× on 2-D 512², none on 3-D 64³ and 128³ (within the
//! machine's noise, ±5 %): lines whose arrays fit the L2 stream them from there as fast, so
//! the kernel was not bound by its scratch traffic except beyond the L2.

use super::{LineScratch, LineSetup, n_waves, special_faces};
use crate::fv::euler::{
    NQ, RoeAverage, RoeSide, State, physical_flux, primitive_floored, roe_strengths,
};
use crate::fv::isa::FixedVec;
use crate::fv::osmp::{
    INTERFACE_PAD, SpeedLine, Upwind, WaveLine, n_coefficients, psi_line, stencil_radius,
};
use face::{FaceInputs, face_loop_on};

mod face;

/// An array over the cells (and faces) of a strip: entry `CARRY`, where the cell pass starts,
/// and entry 0, where the face loop writes, start cache lines (`isa::FixedVec`, all of a
/// strip's arrays in its one allocation).
type CellVec = FixedVec<0, STRIP_LINES>;
/// An array over the interfaces of a strip: entry `CARRY − 1`, where the interface pass, the
/// speeds and the products start, starts a cache line (not `CARRY / 2 + R`, where `Ψ` reads).
type InterfaceVec = FixedVec<INTERFACE_PAD, STRIP_LINES>;
/// The cache lines of each strip array: `STRIP_LEN` entries.
const STRIP_LINES: usize = STRIP_LEN / 8 + 1;
/// The entries of each strip array: the most a strip uses (the longest strip's and its carry).
const STRIP_LEN: usize = LONGEST_STRIP + CARRY;
const _: () = assert!(CellVec::LEN == STRIP_LEN && InterfaceVec::LEN == STRIP_LEN);

/// The lengths a line's strips may have, in faces: a strip of `nc` faces computes `nc` cells
/// from its first one on, the interfaces one before them and the curvatures two before
/// (`strip_faces`). A line takes strips of one of these lengths, the one that computes the
/// fewest faces in all (the longest on a tie), unless it is short (`SHORT_RUN`).
///
/// NOTE: a 3-D line of 128 cells (137 faces counted from `CARRY / 2` before its first) takes
/// two strips of 72 faces, not three of 48 (144 faces either way): one carry and one set-up of
/// every pass less a line: 3.8 % fewer kernel instructions on 128³ (AVX2, callgrind), the CPU
/// time a step within the 2-core Zen 4 machine's noise (docs/performance.md, hP). A line of
/// 100 cells (109 faces) takes two of 56 (112 faces, against 144 when the strips were of 48 or
/// 72 only); a line of 53 cells (a 100-cell pencil cut in two with its overlap, or a 53³ grid)
/// one of 64, and one of 64 cells one of 80; a 2-D line of 518 cells strips of 48 (528 faces
/// against 576).
const STRIP_LENGTHS: [usize; 5] = [48, 56, 64, 72, 80];
/// A line of up to this many faces (plus `CARRY / 2`) is one strip of its own length (loops of
/// run-time length): strips of the lengths above would compute more faces than it has.
const SHORT_RUN: usize = 40;
/// The most faces a strip computes, counted from its first entry.
const PSI_FACES: usize = LONGEST_STRIP;
/// The entries a strip takes from the strip before: its first cells, interfaces and curvatures
/// (see `strip_faces`).
const CARRY: usize = 16;
/// The lowest entry of a strip that its stencils read: its first face's interface is
/// `CARRY / 2 + R` (`strip_faces`), and `Ψ` reads `R` interfaces below it (`R ≤ 3`); the cell,
/// interface and curvature passes start at `CARRY − 1`, `CARRY − 1` and `CARRY − 3`.
const FIRST_READ: usize = CARRY / 2;
/// The longest strip, in faces.
const LONGEST_STRIP: usize = 80;
const _: () = {
    let mut k = 0;
    while k < STRIP_LENGTHS.len() {
        let nc = STRIP_LENGTHS[k];
        assert!(nc.is_multiple_of(8) && nc >= CARRY && nc <= LONGEST_STRIP && nc > SHORT_RUN);
        k += 1;
    }
};

/// `Ψ` of each wave at the faces of a strip (`osmp_faces`).
pub(super) type Psi = [[f64; PSI_FACES]; NQ];

/// A [`Psi`] of zeros, on the heap.
pub(super) fn new_psi() -> Box<Psi> {
    Box::new([[0.0; PSI_FACES]; NQ])
}

/// The buffers of one strip: its cells, interfaces and faces (structure of arrays), each of
/// `STRIP_LEN` entries, in one allocation (`LineScratch` holds it boxed).
#[derive(Clone, Debug, Default)]
pub(super) struct Strip {
    cells: CellLine,
    roe: RoeLine,
    speeds: [SpeedLine<InterfaceVec>; 3],
    waves: [WaveLine<InterfaceVec>; NQ],
    /// Whether each cell is vacuum, each interface's average valid.
    vacuum: Flags,
    valid: Flags,
}

/// A flag for each entry of a strip.
#[derive(Clone, Copy, Debug)]
struct Flags([bool; STRIP_LEN]);

impl Default for Flags {
    fn default() -> Flags {
        Flags([false; STRIP_LEN])
    }
}

impl std::ops::Deref for Flags {
    type Target = [bool];

    #[inline(always)]
    fn deref(&self) -> &[bool] {
        &self.0
    }
}

impl std::ops::DerefMut for Flags {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [bool] {
        &mut self.0
    }
}

impl Strip {
    /// Moves the entries `shift + FIRST_READ .. shift + CARRY` of what the next strip reads
    /// below the part it computes to `FIRST_READ .. CARRY` (the next strip starts `shift ≥
    /// CARRY` cells further along the line), for `nw` waves and the `nd` arrays of `d` the order
    /// fills.
    ///
    /// NOTE: copies of a length fixed at compile time (one 64-byte move an array); a
    /// `copy_within` of a run-time range was a `memmove` call per array, ~90 a strip, which
    /// cost more than the strip saved. The entries below `FIRST_READ` are not moved: no stencil
    /// reads them (the moves were 2 % of the kernel's instructions).
    #[inline(always)]
    fn carry(&mut self, shift: usize, nw: usize, nd: usize) {
        assert!(shift >= CARRY, "strips of {shift} cells (at least {CARRY})");
        const N: usize = CARRY - FIRST_READ;
        let mv = |v: &mut [f64]| {
            let (head, tail) = v.split_at_mut(shift);
            let src: &[f64; N] = tail[FIRST_READ..CARRY].try_into().expect("N entries");
            let dst: &mut [f64; N] = (&mut head[FIRST_READ..CARRY])
                .try_into()
                .expect("N entries");
            *dst = *src;
        };
        // NOTE: plain loops: over chained iterators of the arrays the moves were a call of
        // `Chain::fold` a strip, out of the kernel (168 of 2,626 samples of a 128³ run).
        let c = &mut self.cells;
        for v in &mut c.q {
            mv(v);
        }
        for v in &mut c.vel {
            mv(v);
        }
        for v in &mut c.flux {
            mv(v);
        }
        for v in [&mut c.sqrt_rho, &mut c.h, &mut c.side_ok] {
            mv(v);
        }
        for v in [&mut self.roe.h, &mut self.roe.c] {
            mv(v);
        }
        for v in &mut self.roe.vel {
            mv(v);
        }
        for sp in &mut self.speeds {
            for v in [&mut sp.lam, &mut sp.nu, &mut sp.inv_nu, &mut sp.inv_lam] {
                mv(v);
            }
        }
        for w in &mut self.waves[..nw] {
            for v in [&mut w.alpha, &mut w.dm4] {
                mv(v);
            }
            for v in &mut w.d[..nd] {
                mv(v);
            }
        }
        for v in [&mut self.vacuum, &mut self.valid] {
            let (head, tail) = v.split_at_mut(shift);
            let src: &[bool; N] = tail[FIRST_READ..CARRY].try_into().expect("N entries");
            let dst: &mut [bool; N] = (&mut head[FIRST_READ..CARRY])
                .try_into()
                .expect("N entries");
            *dst = *src;
        }
    }
}

/// What the cells of a line give the interfaces, one array per quantity (structure of arrays,
/// so that the loops over the line vectorise): the conserved state, the velocity and the
/// other Roe-average side quantities, the physical flux.
#[derive(Clone, Debug, Default)]
struct CellLine {
    q: [CellVec; NQ],
    vel: [CellVec; 3],
    sqrt_rho: CellVec,
    h: CellVec,
    flux: [CellVec; NQ],
    /// All bits set where the cell can side a Roe average (not vacuum, ρ > 0), else 0.
    ///
    /// NOTE: a mask of the width of the values, not a `bool` a cell: the interface loop took
    /// ~17 instructions a vector of 4 to widen two cells' vacuum bytes and compare two ρ.
    side_ok: CellVec,
}

impl CellLine {
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
}

/// The Roe averages of a strip's interfaces, one array per field (whether each is valid is in
/// the line's [`LineScratch`], which the special faces read).
#[derive(Clone, Debug, Default)]
struct RoeLine {
    vel: [InterfaceVec; 3],
    h: InterfaceVec,
    c: InterfaceVec,
}

impl RoeLine {
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

/// Conserved states, velocities, Roe-average sides, physical fluxes (into `c`) and vacuum flags
/// of the `len` cells of a strip from `lo` on, whose states are `u` first (at most `len`).
#[inline(always)]
fn cell_loop(
    u: &[State],
    (lo, len): (usize, usize),
    c: &mut CellLine,
    vacuum: &mut [bool],
    setup: &LineSetup,
) {
    // NOTE: one pass over the cells, each copied whole into the five arrays: a pass per
    // component (`cq[i] = u[i][q]`) became a gather of every fifth value on AVX-512.
    let m = u.len();
    let [q0, q1, q2, q3, q4] = &mut c.q;
    let (q0, q1, q2) = (
        &mut q0[lo..lo + m],
        &mut q1[lo..lo + m],
        &mut q2[lo..lo + m],
    );
    let (q3, q4) = (&mut q3[lo..lo + m], &mut q4[lo..lo + m]);
    for (i, ui) in u.iter().enumerate() {
        [q0[i], q1[i], q2[i], q3[i], q4[i]] = *ui;
    }
    let r = lo..lo + len;
    let q: [&[f64]; NQ] = std::array::from_fn(|k| &c.q[k][r.clone()]);
    let [v0, v1, v2] = &mut c.vel;
    let [f0, f1, f2, f3, f4] = &mut c.flux;
    cell_pass(
        q,
        &mut v0[r.clone()],
        &mut v1[r.clone()],
        &mut v2[r.clone()],
        &mut c.sqrt_rho[r.clone()],
        &mut c.h[r.clone()],
        [
            &mut f0[r.clone()],
            &mut f1[r.clone()],
            &mut f2[r.clone()],
            &mut f3[r.clone()],
            &mut f4[r.clone()],
        ],
        &mut vacuum[r.clone()],
        &mut c.side_ok[r],
        setup,
    );
}

/// The loop of [`cell_loop`] over its cells `q` (their conserved values): velocities, Roe
/// sides, physical fluxes and vacuum flags. Its outputs are separate `&mut` arguments (see
/// [`interface_loop`]; the flux's five in one array), each cut to the loop's length.
///
/// NOTE: with its outputs cut from one `&mut CellLine` the loop checked them against its
/// inputs at run time; with the arrays aligned (`CellVec`) it then ran on its scalar copy.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn cell_pass(
    q: [&[f64]; NQ],
    vel0: &mut [f64],
    vel1: &mut [f64],
    vel2: &mut [f64],
    sqrt_rho: &mut [f64],
    h: &mut [f64],
    [f0, f1, f2, f3, f4]: [&mut [f64]; NQ],
    vacuum: &mut [bool],
    side_ok: &mut [f64],
    setup: &LineSetup,
) {
    let len = h.len();
    let side_ok = &mut side_ok[..len];
    let q = cut5(q, len);
    let (vel0, vel1, vel2) = (&mut vel0[..len], &mut vel1[..len], &mut vel2[..len]);
    let (sqrt_rho, vacuum) = (&mut sqrt_rho[..len], &mut vacuum[..len]);
    let (f0, f1, f2, f3, f4) = (
        &mut f0[..len],
        &mut f1[..len],
        &mut f2[..len],
        &mut f3[..len],
        &mut f4[..len],
    );
    for i in 0..len {
        let ui: State = std::array::from_fn(|k| q[k][i]);
        let w = primitive_floored(&ui, setup.gamma, setup.vacuum_rho);
        // NaN or infinite where ρ ≤ 0: such interfaces are marked invalid before use.
        let side = RoeSide::new(&ui, &w);
        let flux = physical_flux(&ui, &w);
        [vel0[i], vel1[i], vel2[i]] = side.vel;
        sqrt_rho[i] = side.sqrt_rho;
        h[i] = side.h;
        [f0[i], f1[i], f2[i], f3[i], f4[i]] = flux;
        let vac = !(w.rho >= setup.vacuum_rho && w.p >= setup.vacuum_p);
        vacuum[i] = vac;
        side_ok[i] = f64::from_bits(u64::from(!vac & (ui[0] > 0.0)).wrapping_neg());
    }
}

/// Roe averages, wave speeds and strengths at the `nint` interfaces of the strip `st` from `lo`
/// on (their cells filled), and whether each average is valid. An interface beside a vacuum
/// cell or with a non-physical average (c² ≤ 0, non-finite) is marked invalid and gets
/// λ = α = 0.
#[inline(always)]
fn interface_pass(st: &mut Strip, (lo, nint): (usize, usize), gamma: f64) {
    let cells = st.cells.view(lo, nint + 1);
    let [rv0, rv1, rv2] = &mut st.roe.vel;
    let [s0, s1, s2] = &mut st.speeds;
    let [w0, w1, w2, w3, w4] = &mut st.waves;
    let r = lo..lo + nint;
    interface_loop(
        &cells,
        &st.cells.side_ok[lo..lo + nint + 1],
        gamma,
        &mut rv0[r.clone()],
        &mut rv1[r.clone()],
        &mut rv2[r.clone()],
        &mut st.roe.h[r.clone()],
        &mut st.roe.c[r.clone()],
        &mut st.valid[r.clone()],
        &mut s0.lam[r.clone()],
        &mut s1.lam[r.clone()],
        &mut s2.lam[r.clone()],
        &mut w0.alpha[r.clone()],
        &mut w1.alpha[r.clone()],
        &mut w2.alpha[r.clone()],
        &mut w3.alpha[r.clone()],
        &mut w4.alpha[r],
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
    side_ok: &[f64],
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
    let side_ok = &side_ok[..nint + 1];
    // NOTE: every input cut to the loop's length too (as in `face_loop`): with the cells'
    // arrays 64-byte aligned (`CellVec`) the loop otherwise ran on its scalar copy with the
    // bounds checks (6 % of the kernel's samples).
    let cells = CellView {
        q: cut5(cells.q, nint + 1),
        vel: cut3(cells.vel, nint + 1),
        sqrt_rho: &cells.sqrt_rho[..nint + 1],
        h: &cells.h[..nint + 1],
        flux: cells.flux,
    };
    for l in 0..nint {
        // Neither side vacuum, both ρ > 0 (`CellLine::side_ok`).
        let sides_ok = (side_ok[l].to_bits() & side_ok[l + 1].to_bits()) != 0;
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

/// The regular (OSMP) flux of every face of the line, strip by strip (see the module doc),
/// then the special faces.
#[inline(always)]
pub(super) fn osmp_faces<const ORDER: u32>(s: &mut LineScratch, setup: &LineSetup, psi: &mut Psi) {
    let radius = stencil_radius(ORDER);
    assert_eq!(
        setup.ng,
        radius + 1,
        "OSMP{ORDER} lines have {} ghosts",
        radius + 1
    );
    let nf = setup.n + 1;
    // The faces computed, counted from CARRY / 2 faces before the line's first.
    let todo = nf + CARRY / 2;
    // `Ψ` of each wave at a strip's faces (`psi`, which the compiler knows no other array of
    // the kernel overlaps, `line::advance_line`): each active wave's at the faces the face
    // loop reads, written by the strip before it reads them; the inactive waves' are 0, set
    // here (none in 3-D), as the scratch may have served lines of more waves.
    // NOTE: written into the strip's buffers, each wave's loop first compared its output's
    // addresses with those of its ~35 inputs at run time (~160 instructions a wave a strip).
    for row in &mut psi[n_waves(setup)..] {
        row.fill(0.0);
    }
    // Strips of one length, so that each line runs one copy of the strip's code (see the
    // NOTE below): the length of STRIP_LENGTHS whose strips compute the fewest faces in all
    // (the longest on a tie); a line of up to SHORT_RUN faces is one strip of its own length.
    // The entries of the last strip beyond the line's end are computed on what is there, and
    // not kept.
    // NOTE: one call site a length, so that each is inlined with its length a constant:
    // every loop of a strip then runs a number of entries known at compile time, a multiple of
    // 8, with no scalar remainder. A line takes all its strips from one call site: two copies
    // of the strip's code hot in a line (strips of 72 and a last one of its own length) did
    // not fit the instruction cache and cost 1.3-1.5x the time a cell on 128^3.
    let strips = |nc: usize| todo.div_ceil(nc);
    let nc = if todo <= SHORT_RUN {
        todo
    } else {
        STRIP_LENGTHS
            .into_iter()
            .rev()
            .min_by_key(|&nc| strips(nc) * nc)
            .expect("strip lengths")
    };
    macro_rules! strips_of {
        ($nc:expr) => {
            for k in 0..strips($nc) {
                strip_faces::<ORDER>(s, setup, k * $nc, $nc, psi);
            }
        };
    }
    match nc {
        48 => strips_of!(48),
        56 => strips_of!(56),
        64 => strips_of!(64),
        72 => strips_of!(72),
        80 => strips_of!(80),
        _ => strip_faces::<ORDER>(s, setup, 0, todo, psi),
    }
    special_faces(s, setup, radius);
}

/// A strip of `nc` cells from the line's cell `a` on: the regular flux of those of its faces
/// (`0 .. nc`) that are the line's into [`LineScratch::face`], whether
/// their linearised star states are physical, the vacuum flags of its cells and the validity of
/// its interfaces, those on the line.
///
/// A strip's entry `i` is the line's cell `a + i − CARRY` and interface `a + i − CARRY` (between
/// cells `a + i − CARRY` and `a + i − CARRY + 1`); it computes the cells `CARRY .. CARRY + NF`,
/// the interfaces one before, and the curvatures two before. The entries below come from the
/// strip before (the first strip's are left over, and only its faces before the line's first
/// read them): its `a + i` is this strip's `i`.
#[inline(always)]
fn strip_faces<const ORDER: u32>(
    s: &mut LineScratch,
    setup: &LineSetup,
    a: usize,
    nc: usize,
    psi: &mut Psi,
) {
    let r = stencil_radius(ORDER);
    let (len, sigma) = (s.u.len(), setup.sigma);
    let st = &mut s.strip;
    if a > 0 {
        st.carry(a - s.last_a, n_waves(setup), 1 + n_coefficients(ORDER));
    }
    s.last_a = a;
    // The strip's cells on the line.
    let own = a.min(len)..(a + nc).min(len);
    cell_loop(
        &s.u[own.clone()],
        (CARRY, nc),
        &mut st.cells,
        &mut st.vacuum,
        setup,
    );
    interface_pass(st, (CARRY - 1, nc), setup.gamma);
    let inv_sigma = 1.0 / sigma;
    for sp in &mut st.speeds {
        sp.fill_range(CARRY - 1, nc, ORDER, sigma, inv_sigma);
    }
    // Face j of the strip is its interface CARRY / 2 + r + j: the line's face a − CARRY / 2 + j.
    // Only the strip's faces that are the line's are computed from `Ψ` on: the faces `first ..
    // first + faces.len()` (the line's `faces`), whose first one is the interface `f0`.
    // NOTE: the faces before the line's first (the first strip's `CARRY / 2`) and past its last
    // (the last strip's) are kept by nothing: their `Ψ` and fluxes were computed for nothing
    // (15 of the 144 faces of a 3-D 128-cell line).
    let nf = setup.n + 1;
    let faces = a.max(CARRY / 2) - CARRY / 2..(a + nc - CARRY / 2).min(nf);
    let first = faces.start + CARRY / 2 - a;
    let f0 = CARRY / 2 + r + first;
    // Wave k travels at speed [u−c, u+c, u, u, u][k] (`Ψ` into `psi`, whose inactive waves'
    // entries stay 0).
    let nw = n_waves(setup);
    let sides = (st.speeds.each_ref()).map(|sp| Upwind::of(&sp.lam[f0..f0 + faces.len()]));
    for k in 0..nw {
        let speed = &st.speeds[k.min(2)];
        st.waves[k].fill_products_curvatures(CARRY - 1, nc, ORDER, speed);
        psi_line::<ORDER, true, _>(
            speed,
            &st.waves[k],
            f0,
            &mut psi[k][first..first + faces.len()],
            sides[k.min(2)],
        );
    }
    // Regular (OSMP) flux at those faces, and whether their linearised star states are
    // physical, straight into the line's arrays.
    // NOTE: computed into the strip's own arrays and copied, the copy of the faces was a
    // `memcpy` call a strip (≈ 0.5 % of a 3-D step's samples).
    let inputs = FaceInputs {
        cells: &st.cells,
        roe: &st.roe,
        valid: &st.valid,
        speeds: &st.speeds,
        waves: &st.waves,
        psi,
        f0,
        j0: first,
        count: faces.len(),
    };
    face_loop_on(
        s.isa,
        &inputs,
        &mut s.face[faces.clone()],
        &mut s.star_ok[faces],
    );
    // What is on the line of the strip's cells and interfaces (a − 1 ..).
    // (The line's cell or interface i is the strip's entry i + CARRY − a.)
    let at = |i: usize| i + CARRY - a;
    s.vacuum[own.clone()].copy_from_slice(&st.vacuum[at(own.start)..at(own.end)]);
    let ints = a.saturating_sub(1)..(a + nc - 1).min(len - 1);
    if !ints.is_empty() {
        s.valid[ints.clone()].copy_from_slice(&st.valid[at(ints.start)..at(ints.end)]);
    }
}

/// The first `len` entries of each of three arrays.
#[inline(always)]
fn cut3(x: [&[f64]; 3], len: usize) -> [&[f64]; 3] {
    [&x[0][..len], &x[1][..len], &x[2][..len]]
}

/// The first `len` entries of each of five arrays.
#[inline(always)]
fn cut5(x: [&[f64]; 5], len: usize) -> [&[f64]; 5] {
    [
        &x[0][..len],
        &x[1][..len],
        &x[2][..len],
        &x[3][..len],
        &x[4][..len],
    ]
}
