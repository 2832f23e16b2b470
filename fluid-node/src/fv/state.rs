//! Solver parameters and the conserved state of the grid (built from the scene in `scene.rs`).
//!
//! The state holds the interior cells only, `nvar = dim + 2` conserved values per cell in
//! x-fastest order (`ρ, ρu_x[, ρu_y[, ρu_z]], E`): a 2-D scene allocates 2-D data with 4
//! values per cell. Ghost layers, `ng = R + 1` cells deep (`R` the stencil radius of the
//! flux, so `ng` = 3 for OSMP3/5, 4 for OSMP7, 2 for MUSCL–Hancock), live in each pencil's
//! scratch line
//! and are filled from the boundary conditions at every sweep (`sweep.rs`).

use protocol::scene::Boundary;

use crate::fv::euler::{Primitive, conserved};
use crate::fv::line::FluxKind;

/// Poinsot–Lele relaxation coefficient σ a characteristic side gets unless the scene's
/// `fluid.characteristic.sigma` sets one: small enough that the side stays nearly
/// non-reflecting, non-zero so that the mean pressure cannot drift away from the far field.
pub const CHARACTERISTIC_SIGMA: f64 = protocol::scene::DEFAULT_CHARACTERISTIC_SIGMA;

/// Parameters of the finite-volume solver, validated.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FluidParams {
    /// Ratio of specific heats γ [-] (default 1.4).
    pub gamma: f64,
    /// CFL number of each directional sweep [-] (default 0.5).
    pub cfl: f64,
    /// Regular face flux (default OSMP order 5).
    pub flux: FluxKind,
    /// Boundary condition per axis and side `[low, high]` (inactive axes: ignored).
    pub boundary: [[BoundaryKind; 2]; 3],
    /// Vacuum density threshold [kg/m³] (default 1e-10).
    pub vacuum_rho: f64,
    /// Vacuum pressure threshold \[Pa\] (default 1e-10).
    pub vacuum_p: f64,
}

/// One side of the domain (mirror of `protocol::scene::Boundary`, kept serializable here).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum BoundaryKind {
    /// Reflecting slip wall: mirror ghosts, normal momentum negated.
    Wall,
    /// Periodic.
    Periodic,
    /// Zero-gradient outflow.
    Outflow,
    /// Non-reflecting characteristic outflow relaxed toward the far-field pressure
    /// (`sweep::characteristic_ghost`).
    Characteristic {
        /// Far-field pressure \[Pa\] the incoming characteristic relaxes toward.
        p_far: f64,
        /// Poinsot–Lele relaxation coefficient σ [-] (default [`CHARACTERISTIC_SIGMA`], or
        /// `fluid.characteristic.sigma`;
        /// 0 gives the zero-gradient outflow).
        sigma: f64,
    },
}

impl BoundaryKind {
    /// Whether gas may leave through the side (outflow, characteristic): what crosses it is
    /// counted as leaving the domain.
    pub fn is_open(self) -> bool {
        !matches!(self, BoundaryKind::Wall | BoundaryKind::Periodic)
    }
}

impl From<Boundary> for BoundaryKind {
    /// The scene's kind; a characteristic side gets σ = `CHARACTERISTIC_SIGMA` (the scene's
    /// `fluid.characteristic.sigma` replaces it in [`from_scene`](crate::fv::from_scene)) and
    /// `p_far = 0` here, set from the initial state by [`from_scene`](crate::fv::from_scene).
    fn from(b: Boundary) -> Self {
        match b {
            Boundary::Wall => BoundaryKind::Wall,
            Boundary::Periodic => BoundaryKind::Periodic,
            Boundary::Outflow => BoundaryKind::Outflow,
            Boundary::Characteristic => BoundaryKind::Characteristic {
                p_far: 0.0,
                sigma: CHARACTERISTIC_SIGMA,
            },
        }
    }
}

impl FluidParams {
    /// Ghost cells per side needed by the flux.
    pub fn ghost_cells(&self) -> usize {
        self.flux.ghost_cells()
    }
}

/// Conserved variables of every cell: `nvar` values per cell, x-fastest.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FluidState {
    /// Values per cell: `dim + 2`.
    pub nvar: usize,
    /// `ρ` [kg/m³], momentum per axis [kg/(m² s)], total energy `E` [J/m³] per cell.
    pub u: Vec<f64>,
}

/// Appends one cell's conserved values `src` (3 to 5 of them, `nvar`) to `out`.
///
/// NOTE: the copy of a slice whose length is known only at run time is a call of `memcpy`;
/// one such call per near cell, 40 bytes each, in the gathers of the near cells' states was
/// about 1 % of a rank's time at 128³ on 2 ranks (issue 40 item 4). Matched on the length, each
/// copy is a few moves inlined.
#[inline(always)]
pub(crate) fn extend_cell(out: &mut Vec<f64>, src: &[f64]) {
    match *src {
        [a, b, c, d, e] => out.extend_from_slice(&[a, b, c, d, e]),
        [a, b, c, d] => out.extend_from_slice(&[a, b, c, d]),
        [a, b, c] => out.extend_from_slice(&[a, b, c]),
        _ => out.extend_from_slice(src),
    }
}

/// `dst.copy_from_slice(src)` for one cell's conserved values (3 to 5 of them), the copy
/// inlined (see [`extend_cell`]).
#[inline(always)]
pub(crate) fn copy_cell(dst: &mut [f64], src: &[f64]) {
    assert_eq!(dst.len(), src.len(), "a cell's values");
    match src.len() {
        5 => dst[..5].copy_from_slice(&src[..5]),
        4 => dst[..4].copy_from_slice(&src[..4]),
        3 => dst[..3].copy_from_slice(&src[..3]),
        _ => dst.copy_from_slice(src),
    }
}

impl FluidState {
    /// A state of `n_cells` cells of dimension `dim`, all zero.
    pub fn zeros(dim: usize, n_cells: usize) -> FluidState {
        FluidState {
            nvar: dim + 2,
            u: vec![0.0; (dim + 2) * n_cells],
        }
    }

    /// The conserved values of cell `idx`.
    pub fn cell(&self, idx: usize) -> &[f64] {
        &self.u[idx * self.nvar..(idx + 1) * self.nvar]
    }

    /// Sets cell `idx` from density [kg/m³], velocity [m/s] (first `dim` entries used) and
    /// pressure \[Pa\].
    pub fn set_primitive(&mut self, idx: usize, rho: f64, vel: [f64; 3], p: f64, gamma: f64) {
        let dim = self.nvar - 2;
        let w = Primitive { rho, vel, p };
        let full = conserved(&w, gamma);
        let cell = &mut self.u[idx * self.nvar..(idx + 1) * self.nvar];
        cell[0] = full[0];
        cell[1..=dim].copy_from_slice(&full[1..=dim]);
        // Kinetic energy of the active components only.
        let ke: f64 = (0..dim).map(|a| 0.5 * rho * vel[a] * vel[a]).sum();
        cell[dim + 1] = p / (gamma - 1.0) + ke;
    }

    /// Density [kg/m³], velocity [m/s] (inactive axes 0) and pressure \[Pa\] of cell `idx`.
    pub fn primitive(&self, idx: usize, gamma: f64) -> (f64, [f64; 3], f64) {
        primitive_of(self.cell(idx), gamma)
    }
}

/// Density [kg/m³], velocity [m/s] (inactive axes 0) and pressure \[Pa\] of the conserved
/// `cell` (`dim + 2` values): [`FluidState::primitive`] of a cell already at hand.
#[inline]
pub fn primitive_of(cell: &[f64], gamma: f64) -> (f64, [f64; 3], f64) {
    let dim = cell.len() - 2;
    let rho = cell[0];
    let inv = if rho > 0.0 { 1.0 / rho } else { 0.0 };
    let mut vel = [0.0; 3];
    let mut ke = 0.0;
    for a in 0..dim {
        vel[a] = cell[1 + a] * inv;
        ke += 0.5 * cell[1 + a] * vel[a];
    }
    (rho, vel, (gamma - 1.0) * (cell[dim + 1] - ke))
}
