//! The regular (OSMP) flux at a strip's faces, and whether their linearised star states are
//! physical: a function of its own for each instruction set ([`face_loop_on`]).

use super::{CellLine, Flags, InterfaceVec, PSI_FACES, RoeLine, cut3, cut5};
use crate::fv::euler::{NQ, State, roe_eigenvector, roe_star_states_positive};
use crate::fv::isa::Isa;
use crate::fv::osmp::{SpeedLine, WaveLine};

/// What [`face_loop`] reads: a strip's cells, Roe averages, validity flags, speeds, waves and
/// `Ψ` (the strip's arrays themselves, not slices of them), and which faces: `count` faces from
/// the strip's face `j0` (its interface `f0`, between its cells `f0` and `f0 + 1`).
///
/// NOTE: passed as slices (~35 of them, each a pointer and a length), the loop kept reloading
/// their pointers from the stack (≈ 20 of its ~175 instructions a vector of 8 faces on
/// AVX-512, docs/performance.md, hP); the strip's arrays lie at fixed offsets from a few bases.
pub(super) struct FaceInputs<'a> {
    pub cells: &'a CellLine,
    pub roe: &'a RoeLine,
    pub valid: &'a Flags,
    pub speeds: &'a [SpeedLine<InterfaceVec>; 3],
    pub waves: &'a [WaveLine<InterfaceVec>; NQ],
    pub psi: &'a [[f64; PSI_FACES]; NQ],
    pub f0: usize,
    pub j0: usize,
    pub count: usize,
}

/// [`face_loop`] on the instruction set `isa`: a function of its own for each (`isa.rs`).
///
/// NOTE: inlined into the line kernel, the face loop stayed scalar on every instruction set:
/// LLVM asked for more run-time checks of overlap among its ~30 input and 6 output arrays than
/// it makes ("too many memory checks needed"). In a function of its own the outputs are
/// `noalias` arguments, and it vectorises. One call a strip.
#[inline(always)]
pub(super) fn face_loop_on(
    isa: Isa,
    inputs: &FaceInputs<'_>,
    face: &mut [State],
    star_ok: &mut [bool],
) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if Isa::Avx512.supported() => {
            // SAFETY: the CPU has AVX-512F (checked on the line above).
            unsafe { face_loop_avx512(inputs, face, star_ok) }
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if Isa::Avx2.supported() => {
            // SAFETY: the CPU has AVX2 (checked on the line above).
            unsafe { face_loop_avx2(inputs, face, star_ok) }
        }
        _ => face_loop_baseline(inputs, face, star_ok),
    }
}

/// [`face_loop`] for the baseline (`face_loop_on`).
#[inline(never)]
fn face_loop_baseline(inputs: &FaceInputs<'_>, face: &mut [State], star_ok: &mut [bool]) {
    face_loop(inputs, face, star_ok);
}

/// [`face_loop`] for AVX2 (without FMA, `isa.rs`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline(never)]
fn face_loop_avx2(inputs: &FaceInputs<'_>, face: &mut [State], star_ok: &mut [bool]) {
    face_loop(inputs, face, star_ok);
}

/// [`face_loop`] for AVX-512F (without FMA, `isa.rs`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline(never)]
fn face_loop_avx512(inputs: &FaceInputs<'_>, face: &mut [State], star_ok: &mut [bool]) {
    face_loop(inputs, face, star_ok);
}

/// The regular flux of the faces `j0 .. j0 + count` of `inputs` (face `j0 + j` between the
/// strip's cells `f0 + j` and `f0 + j + 1`) into `face[j]` (the line's faces), and whether their
/// linearised star states are physical into `star_ok[j]`.
#[inline(always)]
fn face_loop(inputs: &FaceInputs<'_>, face: &mut [State], star_ok: &mut [bool]) {
    let FaceInputs {
        cells,
        roe,
        valid,
        speeds,
        waves,
        psi,
        f0,
        j0,
        count: nf,
    } = *inputs;
    let w = f0..f0 + nf;
    let star_ok = &mut star_ok[..nf];
    let face = &mut face[..nf];
    // NOTE: every input cut to the loop's length, so that no bounds check is left in the loop:
    // with them the loop stayed scalar. The cuts are arrays written out (`cut3`, `cut5`): cut
    // with `array::map`, the lengths were lost to the compiler, and the last vector's faces
    // ran on a scalar loop with the checks.
    let roe_vel = cut3(
        [&roe.vel[0][f0..], &roe.vel[1][f0..], &roe.vel[2][f0..]],
        nf,
    );
    let (roe_h, roe_c, roe_valid) = (&roe.h[w.clone()], &roe.c[w.clone()], &valid[w.clone()]);
    let [s0, s1, s2] = speeds;
    let lam = cut3([&s0.lam[f0..], &s1.lam[f0..], &s2.lam[f0..]], nf);
    let [w0, w1, w2, w3, w4] = waves;
    let alpha = [&w0.alpha, &w1.alpha, &w2.alpha, &w3.alpha, &w4.alpha];
    let alpha = cut5(
        [
            &alpha[0][f0..],
            &alpha[1][f0..],
            &alpha[2][f0..],
            &alpha[3][f0..],
            &alpha[4][f0..],
        ],
        nf,
    );
    let psi = cut5(
        [
            &psi[0][j0..],
            &psi[1][j0..],
            &psi[2][j0..],
            &psi[3][j0..],
            &psi[4][j0..],
        ],
        nf,
    );
    let [p0, p1, p2, p3, p4] = &cells.flux;
    let phys = cut5(
        [&p0[f0..], &p1[f0..], &p2[f0..], &p3[f0..], &p4[f0..]],
        nf + 1,
    );
    let [c0, c1, c2, c3, c4] = &cells.q;
    let q_cells = cut5(
        [&c0[f0..], &c1[f0..], &c2[f0..], &c3[f0..], &c4[f0..]],
        nf + 1,
    );
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
        face[j] = flux;
        let (ul, ur): (State, State) = (
            std::array::from_fn(|q| q_cells[q][j]),
            std::array::from_fn(|q| q_cells[q][j + 1]),
        );
        star_ok[j] = roe_star_states_positive(&ul, &ur, &roe, &a);
    }
}
