//! Analytic initial conditions and exact solutions for verification, set as exact (or
//! quadrature) cell averages of the conserved variables: planar Riemann problems, the smooth
//! density wave and the isentropic vortex.
//!
//! The scene schema only describes piecewise-constant regions; these profiles are what the
//! tests, benches and the work–precision study use for the smooth problems.

use crate::fv::exact_riemann::{ExactRiemann, GAUSS8};
use crate::fv::state::FluidState;
use crate::grid::Grid;

/// Sets `state` to the cell averages of the planar Riemann problem `ex` along the unit
/// `normal`, discontinuity on the plane `normal · x = xi0` \[m\], at time `t` \[s\].
///
/// Axis-aligned normals use the exact 1-D average; the 2-D diagonal `(1, 1)/√2` with square
/// cells uses the exact triangular weight of `ξ = n·x` over the cell; other normals use an
/// 8-point Gauss rule per axis.
pub fn riemann_planar(
    state: &mut FluidState,
    grid: &Grid,
    ex: &ExactRiemann,
    normal: [f64; 3],
    xi0: f64,
    t: f64,
) {
    let dim = grid.dim;
    let nvar = state.nvar;
    let axis_aligned = (0..dim).find(|&a| normal[a].abs() == 1.0);
    let diagonal = dim == 2
        && (normal[0] - normal[1]).abs() < 1e-15
        && (normal[0] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15
        && (grid.dx[0] - grid.dx[1]).abs() <= 1e-14 * grid.dx[0];
    for idx in 0..grid.n_cells() {
        let ijk = grid.ijk(idx);
        let xc = grid.cell_center(ijk);
        let avg = if let Some(a) = axis_aligned {
            let s = normal[a];
            let (lo, hi) = (xc[a] - 0.5 * grid.dx[a], xc[a] + 0.5 * grid.dx[a]);
            let v = if s > 0.0 {
                ex.cell_average(lo, hi, xi0, t)
            } else {
                ex.cell_average(-hi, -lo, xi0, t)
            };
            [v[0], v[1], v[2]]
        } else if diagonal {
            let xi_c = normal[0] * xc[0] + normal[1] * xc[1];
            let half = grid.dx[0] * std::f64::consts::FRAC_1_SQRT_2;
            tent_average(ex, xi_c, half, xi0, t)
        } else {
            gauss_average(grid, &xc, |x| {
                let xi: f64 = (0..dim).map(|a| normal[a] * x[a]).sum();
                ex.conserved_at(xi, xi0, t)
            })
        };
        let cell = &mut state.u[idx * nvar..(idx + 1) * nvar];
        cell[0] = avg[0];
        for a in 0..dim {
            cell[1 + a] = avg[1] * normal[a];
        }
        cell[dim + 1] = avg[2];
    }
}

/// Average of the exact state against the triangular weight on `[xi_c − half, xi_c + half]`.
fn tent_average(ex: &ExactRiemann, xi_c: f64, half: f64, xi0: f64, t: f64) -> [f64; 3] {
    let mut cuts = vec![xi_c - half, xi_c, xi_c + half];
    if t > 0.0 {
        for s in ex.wave_speeds() {
            cuts.push(xi0 + s * t);
        }
    } else {
        cuts.push(xi0);
    }
    cuts.retain(|x| *x >= xi_c - half && *x <= xi_c + half);
    cuts.sort_by(f64::total_cmp);
    let mut acc = [0.0; 3];
    for piece in cuts.windows(2) {
        let (a, b) = (piece[0], piece[1]);
        let (mid, h) = (0.5 * (a + b), 0.5 * (b - a));
        for (node, weight) in GAUSS8 {
            let xi = mid + h * node;
            let w = (half - (xi - xi_c).abs()) / (half * half);
            let v = ex.conserved_at(xi, xi0, t);
            for q in 0..3 {
                acc[q] += weight * h * w * v[q];
            }
        }
    }
    acc
}

/// Tensor 8-point Gauss average over the cell centred at `xc` of a 3-component function.
fn gauss_average(grid: &Grid, xc: &[f64; 3], f: impl Fn(&[f64; 3]) -> [f64; 3]) -> [f64; 3] {
    let dim = grid.dim;
    let n = 8usize.pow(dim as u32);
    let mut acc = [0.0; 3];
    for k in 0..n {
        let mut x = *xc;
        let mut w = 1.0;
        let mut rest = k;
        for a in 0..dim {
            let (node, weight) = GAUSS8[rest % 8];
            rest /= 8;
            x[a] += 0.5 * grid.dx[a] * node;
            w *= 0.5 * weight;
        }
        let v = f(&x);
        for q in 0..3 {
            acc[q] += w * v[q];
        }
    }
    acc
}

/// Smooth periodic density wave `ρ = 1 + A sin(2π Σ_a k_a (x_a − lower_a)/L_a)` carried by
/// the uniform velocity `vel` [m/s] at uniform pressure `p` \[Pa\], at time `t` \[s\]; exact cell
/// averages. `wave` holds the integer wave numbers `k_a` per axis.
#[allow(clippy::too_many_arguments)]
pub fn density_wave(
    state: &mut FluidState,
    grid: &Grid,
    amplitude: f64,
    wave: [f64; 3],
    vel: [f64; 3],
    p: f64,
    gamma: f64,
    t: f64,
) {
    let dim = grid.dim;
    let nvar = state.nvar;
    let two_pi = 2.0 * std::f64::consts::PI;
    for idx in 0..grid.n_cells() {
        let ijk = grid.ijk(idx);
        // Average of sin(Σ θ_a) = Im Π_a avg(exp(i θ_a)), θ_a linear in x_a.
        let (mut re, mut im) = (1.0, 0.0);
        for a in 0..dim {
            let len = grid.upper[a] - grid.lower[a];
            let kk = two_pi * wave[a] / len;
            let x0 = grid.lower[a] + ijk[a] as f64 * grid.dx[a] - vel[a] * t - grid.lower[a];
            let (t0, t1) = (kk * x0, kk * (x0 + grid.dx[a]));
            let (ar, ai) = if kk == 0.0 {
                (1.0, 0.0)
            } else {
                // (e^{i t1} − e^{i t0}) / (i Δθ)
                let d = t1 - t0;
                ((t1.sin() - t0.sin()) / d, -(t1.cos() - t0.cos()) / d)
            };
            let (nr, ni) = (re * ar - im * ai, re * ai + im * ar);
            re = nr;
            im = ni;
        }
        let rho = 1.0 + amplitude * im;
        let cell = &mut state.u[idx * nvar..(idx + 1) * nvar];
        cell[0] = rho;
        let mut q2 = 0.0;
        for a in 0..dim {
            cell[1 + a] = rho * vel[a];
            q2 += vel[a] * vel[a];
        }
        cell[dim + 1] = p / (gamma - 1.0) + 0.5 * rho * q2;
    }
}

/// Isentropic vortex of strength `beta` (Shu 1998; ρ∞ = p∞ = 1) centred at `center` \[m\] at
/// t = 0, carried by `vel` [m/s], at time `t` \[s\] on a periodic 2-D grid (nearest periodic
/// image); 8×8-point Gauss cell averages.
pub fn isentropic_vortex(
    state: &mut FluidState,
    grid: &Grid,
    beta: f64,
    center: [f64; 2],
    vel: [f64; 2],
    gamma: f64,
    t: f64,
) {
    let nvar = state.nvar;
    let pi = std::f64::consts::PI;
    let len = [grid.upper[0] - grid.lower[0], grid.upper[1] - grid.lower[1]];
    let wrap = |d: f64, l: f64| d - l * (d / l).round();
    for idx in 0..grid.n_cells() {
        let xc = grid.cell_center(grid.ijk(idx));
        let avg = gauss_average_n(grid, &xc, |x| {
            let dx = wrap(x[0] - center[0] - vel[0] * t, len[0]);
            let dy = wrap(x[1] - center[1] - vel[1] * t, len[1]);
            let r2 = dx * dx + dy * dy;
            let e = (0.5 * (1.0 - r2)).exp();
            let du = -beta / (2.0 * pi) * e * dy;
            let dv = beta / (2.0 * pi) * e * dx;
            let temp = 1.0 - (gamma - 1.0) * beta * beta / (8.0 * gamma * pi * pi) * e * e;
            let rho = temp.powf(1.0 / (gamma - 1.0));
            let p = rho * temp;
            let (u, v) = (vel[0] + du, vel[1] + dv);
            [
                rho,
                rho * u,
                rho * v,
                p / (gamma - 1.0) + 0.5 * rho * (u * u + v * v),
            ]
        });
        state.u[idx * nvar..(idx + 1) * nvar].copy_from_slice(&avg[..nvar]);
    }
}

fn gauss_average_n(grid: &Grid, xc: &[f64; 3], f: impl Fn(&[f64; 3]) -> [f64; 4]) -> [f64; 4] {
    let mut acc = [0.0; 4];
    for (n0, w0) in GAUSS8 {
        for (n1, w1) in GAUSS8 {
            let x = [
                xc[0] + 0.5 * grid.dx[0] * n0,
                xc[1] + 0.5 * grid.dx[1] * n1,
                0.0,
            ];
            let v = f(&x);
            for q in 0..4 {
                acc[q] += 0.25 * w0 * w1 * v[q];
            }
        }
    }
    acc
}

/// L1 norm of the density difference `Σ |ρ − ρ_ref| V` over the grid \[kg\] (per unit length
/// or area below 3-D).
pub fn l1_density(grid: &Grid, a: &FluidState, b: &FluidState) -> f64 {
    let nvar = a.nvar;
    let mut acc = 0.0;
    for idx in 0..grid.n_cells() {
        acc += (a.u[idx * nvar] - b.u[idx * nvar]).abs();
    }
    acc * grid.cell_volume()
}
