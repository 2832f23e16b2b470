//! The regular (OSMP) faces of a line, strip by strip, and the special faces after them.
//!
//! A line's faces are cut into strips of at most [`STRIP_FACES`] consecutive faces. Each strip
//! runs every pass of the scheme over its own cells and interfaces (the faces' stencils:
//! `R = stencil_radius` interfaces beyond each end, recomputed by the strips on either side) in
//! a [`Strip`]'s buffers, which a strip reuses and which stay in L1: the cell pass (primitive
//! variables, Roe sides, physical fluxes, vacuum flags), the interface pass (Roe averages,
//! speeds, strengths), the speeds' and waves' coefficients, OSMP's `Ψ` per wave, and the
//! regular flux at the strip's faces.
//!
//! NOTE: before, each pass ran over the whole line and wrote arrays that the next pass read:
//! about 80 arrays of `n + 2 ng` values, 90 kB for a 128-cell line, twice the 48 kB L1 of this
//! machine's cores, so every pass read and wrote its arrays in L2. The arrays a strip of 48
//! faces touches (OSMP5, 3-D) are about 37 kB. An interface or face that two strips share is
//! computed twice from the same inputs by the same operations, so every value, and the line's
//! result, is the same to the bit.

use super::{FaceFlux, LineScratch, LineSetup, n_waves, vacuum_face};
use crate::fv::euler::{
    NQ, RoeAverage, RoeSide, State, flux_hlle, physical_flux, primitive_floored, roe_eigenvector,
    roe_star_states_positive, roe_strengths,
};
use crate::fv::osmp::{SpeedLine, WaveLine, psi_line, stencil_radius};

/// Faces a strip computes.
///
/// Every loop of a strip runs over a number of entries fixed at compile time and a multiple of
/// 8 (the lanes of AVX-512), so that none has a scalar remainder (a strip is short, and a
/// remainder of up to 7 entries done one by one cost more than the strip saved). The entries
/// beyond the strip's own (beyond the line's end, in a line shorter than a strip) hold what an
/// earlier strip left there: computed on, never read by an entry of the strip's own.
pub(super) const STRIP_FACES: usize = 48;
/// Interfaces a strip computes: its faces and `R ≤ 3` beyond each end, rounded up to 8.
const STRIP_INTERFACES: usize = STRIP_FACES + 8;
/// Cells a strip computes (at least one more than its interfaces), and the length of every
/// buffer of a strip (the curvatures read `λ` and `α` two interfaces beyond the last one).
const STRIP_CELLS: usize = STRIP_INTERFACES + 8;

/// The buffers of one strip: its cells, interfaces and faces (structure of arrays).
#[derive(Clone, Debug, Default)]
pub(super) struct Strip {
    cells: CellLine,
    roe: RoeLine,
    speeds: [SpeedLine; 3],
    waves: [WaveLine; NQ],
    /// `Ψ` of each wave at the strip's faces.
    psi: [Vec<f64>; NQ],
    /// The regular face fluxes, one array per component.
    face_q: [Vec<f64>; NQ],
    /// Whether each cell is vacuum, each interface's average valid, each face's linearised
    /// star states physical.
    vacuum: Vec<bool>,
    valid: Vec<bool>,
    star_ok: Vec<bool>,
}

impl Strip {
    /// Sizes the buffers ([`STRIP_CELLS`] entries each; a no-op once done).
    fn resize(&mut self) {
        let len = STRIP_CELLS;
        self.cells.resize(len);
        self.roe.resize(len);
        for sp in &mut self.speeds {
            sp.resize(len);
        }
        for w in &mut self.waves {
            w.resize(len);
        }
        for v in self.psi.iter_mut().chain(&mut self.face_q) {
            v.resize(len, 0.0);
        }
        for v in [&mut self.vacuum, &mut self.valid, &mut self.star_ok] {
            v.resize(len, false);
        }
    }
}

/// What the cells of a line give the interfaces, one array per quantity (structure of arrays,
/// so that the loops over the line vectorise): the conserved state, the velocity and the
/// other Roe-average side quantities, the physical flux.
#[derive(Clone, Debug, Default)]
struct CellLine {
    q: [Vec<f64>; NQ],
    vel: [Vec<f64>; 3],
    sqrt_rho: Vec<f64>,
    h: Vec<f64>,
    flux: [Vec<f64>; NQ],
}

impl CellLine {
    fn resize(&mut self, len: usize) {
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

/// The Roe averages of a strip's interfaces, one array per field (whether each is valid is in
/// the line's [`LineScratch`], which the special faces read).
#[derive(Clone, Debug, Default)]
struct RoeLine {
    vel: [Vec<f64>; 3],
    h: Vec<f64>,
    c: Vec<f64>,
}

impl RoeLine {
    fn resize(&mut self, len: usize) {
        for v in self.vel.iter_mut().chain([&mut self.h, &mut self.c]) {
            v.resize(len, 0.0);
        }
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

/// Conserved states, velocities, Roe-average sides, physical fluxes (into `c`) and vacuum flags
/// of a strip's cells, `u` first (at most [`STRIP_CELLS`]).
#[inline(always)]
fn cell_loop(u: &[State], c: &mut CellLine, vacuum: &mut [bool], setup: &LineSetup) {
    for (q, cq) in c.q.iter_mut().enumerate() {
        let cq = &mut cq[..u.len()];
        for i in 0..u.len() {
            cq[i] = u[i][q];
        }
    }
    let len = STRIP_CELLS;
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
    let vacuum = &mut vacuum[..len];
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
}

/// Roe averages, wave speeds and strengths at the [`STRIP_INTERFACES`] interfaces of the strip
/// `st` (its cells filled), and whether each average is valid. An interface beside a vacuum
/// cell or with a non-physical average (c² ≤ 0, non-finite) is marked invalid and gets
/// λ = α = 0.
#[inline(always)]
fn interface_pass(st: &mut Strip, gamma: f64) {
    let nint = STRIP_INTERFACES;
    let cells = st.cells.view(0, nint + 1);
    let [rv0, rv1, rv2] = &mut st.roe.vel;
    let [s0, s1, s2] = &mut st.speeds;
    let [w0, w1, w2, w3, w4] = &mut st.waves;
    interface_loop(
        &cells,
        &st.vacuum[..nint + 1],
        gamma,
        &mut rv0[..nint],
        &mut rv1[..nint],
        &mut rv2[..nint],
        &mut st.roe.h[..nint],
        &mut st.roe.c[..nint],
        &mut st.valid[..nint],
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

/// The regular (OSMP) flux of every face of the line, strip by strip (see the module doc),
/// then the special faces.
#[inline(always)]
pub(super) fn osmp_faces<const ORDER: u32>(s: &mut LineScratch, setup: &LineSetup) {
    let radius = stencil_radius(ORDER);
    assert_eq!(
        setup.ng,
        radius + 1,
        "OSMP{ORDER} lines have {} ghosts",
        radius + 1
    );
    s.strip.resize();
    let nf = setup.n + 1;
    // Strips of STRIP_FACES faces; the last one ends at the line's last face (it computes
    // again some faces of the one before, to the same bits), unless the line is shorter.
    for k in 0..nf.div_ceil(STRIP_FACES) {
        let a = (k * STRIP_FACES).min(nf.saturating_sub(STRIP_FACES));
        strip_faces::<ORDER>(s, setup, a, STRIP_FACES.min(nf));
    }
    special_faces(s, setup, radius);
}

/// The regular flux of the faces `a .. a + sn` of the line into [`LineScratch::face`], and
/// whether their linearised star states are physical; the vacuum flags of the cells of the
/// strip and the validity of its interfaces (`R` beyond each end too).
#[inline(always)]
fn strip_faces<const ORDER: u32>(s: &mut LineScratch, setup: &LineSetup, a: usize, sn: usize) {
    const NF: usize = STRIP_FACES;
    const NI: usize = STRIP_INTERFACES;
    let LineSetup { ng, sigma, .. } = *setup;
    let r = stencil_radius(ORDER);
    // The strip's first interface and cell along the line (face `a` is interface `ng − 1 + a`,
    // which is the strip's interface `r`), and its cells on the line.
    let g0 = ng - 1 + a - r;
    let nc = STRIP_CELLS.min(s.u.len() - g0);
    let st = &mut s.strip;
    cell_loop(&s.u[g0..g0 + nc], &mut st.cells, &mut st.vacuum, setup);
    interface_pass(st, setup.gamma);
    let inv_sigma = 1.0 / sigma;
    for sp in &mut st.speeds {
        sp.fill_first(NI, ORDER, sigma, inv_sigma);
    }
    // Wave k travels at speed [u−c, u+c, u, u, u][k].
    let nw = n_waves(setup);
    for k in 0..nw {
        let speed = &st.speeds[k.min(2)];
        st.waves[k].fill_products(NI, ORDER, speed);
        st.waves[k].fill_curvatures(NI, speed);
        psi_line::<ORDER, true>(speed, &st.waves[k], r, &mut st.psi[k][..NF]);
    }
    for k in nw..NQ {
        st.psi[k][..NF].fill(0.0);
    }
    // Regular (OSMP) flux at the strip's faces, and whether its linearised star states are
    // physical.
    let cells = st.cells.view(r, NF + 1);
    let w = r..r + NF;
    let roe_vel: [&[f64]; 3] = std::array::from_fn(|k| &st.roe.vel[k][w.clone()]);
    let (roe_h, roe_c) = (&st.roe.h[w.clone()], &st.roe.c[w.clone()]);
    let roe_valid = &st.valid[w.clone()];
    let lam: [&[f64]; 3] = std::array::from_fn(|k| &st.speeds[k].lam[w.clone()]);
    let alpha: [&[f64]; NQ] = std::array::from_fn(|k| &st.waves[k].alpha[w.clone()]);
    let psi: [&[f64]; NQ] = std::array::from_fn(|k| &st.psi[k][..NF]);
    let [fq0, fq1, fq2, fq3, fq4] = &mut st.face_q;
    face_loop(
        &cells,
        (roe_vel, roe_h, roe_c, roe_valid),
        (lam, alpha, psi),
        &mut st.star_ok[..NF],
        &mut fq0[..NF],
        &mut fq1[..NF],
        &mut fq2[..NF],
        &mut fq3[..NF],
        &mut fq4[..NF],
    );
    // The strip's own cells, interfaces and faces to the line.
    s.vacuum[g0..g0 + nc].copy_from_slice(&st.vacuum[..nc]);
    s.valid[g0..g0 + nc - 1].copy_from_slice(&st.valid[..nc - 1]);
    s.star_ok[a..a + sn].copy_from_slice(&st.star_ok[..sn]);
    for (j, face) in s.face[a..a + sn].iter_mut().enumerate() {
        *face = std::array::from_fn(|q| st.face_q[q][j]);
    }
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
