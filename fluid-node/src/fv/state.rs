//! Solver parameters, the conserved state of the grid, and their construction from the scene.
//!
//! The state holds the interior cells only, `nvar = dim + 2` conserved values per cell in
//! x-fastest order (`ρ, ρu_x[, ρu_y[, ρu_z]], E`): a 2-D scene allocates 2-D data with 4
//! values per cell. Ghost layers, `ng = R + 1` cells deep (`R` the stencil radius of the
//! flux, so `ng` = 3 for OSMP3/5, 4 for OSMP7, 2 for MUSCL–Hancock), live in each pencil's
//! scratch line
//! and are filled from the boundary conditions at every sweep (`sweep.rs`).

use protocol::scene::{Boundary, FluidConfig, Profile};

use crate::fv::euler::{Primitive, conserved};
use crate::fv::line::FluxKind;
use crate::grid::Grid;

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
        /// Poinsot–Lele relaxation coefficient σ [-] (default `sweep::CHARACTERISTIC_SIGMA`, or `fluid.characteristic.sigma`;
        /// 0 gives the zero-gradient outflow).
        sigma: f64,
    },
}

impl From<Boundary> for BoundaryKind {
    /// The scene's kind; a characteristic side gets σ = `CHARACTERISTIC_SIGMA` (the scene's
    /// `fluid.characteristic.sigma` replaces it in [`from_scene`]) and
    /// `p_far = 0` here, set from the initial state by [`from_scene`].
    fn from(b: Boundary) -> Self {
        match b {
            Boundary::Wall => BoundaryKind::Wall,
            Boundary::Periodic => BoundaryKind::Periodic,
            Boundary::Outflow => BoundaryKind::Outflow,
            Boundary::Characteristic => BoundaryKind::Characteristic {
                p_far: 0.0,
                sigma: crate::fv::sweep::CHARACTERISTIC_SIGMA,
            },
        }
    }
}

/// Sets the far-field pressure of every characteristic side: `fluid.characteristic.p_far`
/// when the scene gives it, else the mean initial pressure of the cells along that side (the
/// layer of cells touching it), summed in index order.
pub fn set_far_pressures(
    grid: &Grid,
    params: &mut FluidParams,
    state: &FluidState,
    cfg: &FluidConfig,
) {
    let given = cfg.characteristic.as_ref().and_then(|c| c.p_far);
    for axis in 0..grid.dim {
        for side in 0..2 {
            if let BoundaryKind::Characteristic { p_far, .. } = &mut params.boundary[axis][side] {
                if let Some(p) = given {
                    *p_far = p;
                    continue;
                }
                let layer = if side == 0 { 0 } else { grid.cells[axis] - 1 };
                let (mut sum, mut count) = (0.0, 0usize);
                for idx in 0..grid.n_cells() {
                    if grid.ijk(idx)[axis] == layer {
                        sum += state.primitive(idx, params.gamma).2;
                        count += 1;
                    }
                }
                *p_far = sum / count.max(1) as f64;
            }
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
        let dim = self.nvar - 2;
        let cell = self.cell(idx);
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
}

/// Validates `cfg` and builds the grid, the parameters and the initial state: every
/// `[[fluid.init]]` entry, in order, sets the cells whose centre lies in its region.
///
/// Errors (lowercase, with values): bad dimension or counts, γ ≤ 1, CFL outside (0, 1],
/// order not 3/5/7, periodic on one side only, wrong velocity length, a cell no entry covers,
/// a non-physical initial state (ρ < 0, p < 0 or non-finite).
pub fn from_scene(cfg: &FluidConfig) -> Result<(Grid, FluidParams, FluidState), String> {
    let cells: Vec<usize> = cfg.cells.iter().map(|&n| n as usize).collect();
    let grid = Grid::new(&cfg.lower, &cfg.upper, &cells).map_err(|e| e.to_string())?;
    let dim = grid.dim;
    if !(cfg.gamma > 1.0 && cfg.gamma.is_finite()) {
        return Err(format!("fluid.gamma must be > 1, got {}", cfg.gamma));
    }
    if !(cfg.cfl > 0.0 && cfg.cfl <= 1.0) {
        return Err(format!("fluid.cfl must be in (0, 1], got {}", cfg.cfl));
    }
    if ![3, 5, 7].contains(&cfg.flux.order) {
        return Err(format!(
            "fluid.flux.order must be 3, 5 or 7, got {}",
            cfg.flux.order
        ));
    }
    if !(cfg.vacuum.rho >= 0.0 && cfg.vacuum.p >= 0.0) {
        return Err(format!(
            "fluid.vacuum thresholds must be >= 0, got rho {} p {}",
            cfg.vacuum.rho, cfg.vacuum.p
        ));
    }
    let mut boundary = [[BoundaryKind::Outflow; 2]; 3];
    for (axis, b) in boundary.iter_mut().enumerate().take(dim) {
        let [lo, hi] = cfg.boundary.axis(axis);
        if (lo == Boundary::Periodic) != (hi == Boundary::Periodic) {
            return Err(format!(
                "axis {axis}: periodic on both sides or on neither, got [{lo:?}, {hi:?}]"
            ));
        }
        *b = [lo.into(), hi.into()];
        if let Some(ch) = &cfg.characteristic {
            for side in b.iter_mut() {
                if let BoundaryKind::Characteristic { sigma, .. } = side {
                    *sigma = ch.sigma;
                }
            }
        }
    }
    let params = FluidParams {
        gamma: cfg.gamma,
        cfl: cfg.cfl,
        flux: FluxKind::Osmp(cfg.flux.order),
        boundary,
        vacuum_rho: cfg.vacuum.rho,
        vacuum_p: cfg.vacuum.p,
    };
    for (k, entry) in cfg.init.iter().enumerate() {
        if !(entry.velocity.is_empty() || entry.velocity.len() == dim) {
            return Err(format!(
                "fluid.init[{k}].velocity: expected 0 or {dim} entries, got {}",
                entry.velocity.len()
            ));
        }
        let vel_ok = entry.velocity.iter().all(|v| v.is_finite());
        let finite = entry.rho.is_finite() && entry.p.is_finite() && vel_ok;
        if !(entry.rho >= 0.0 && entry.p >= 0.0 && finite) {
            return Err(format!(
                "fluid.init[{k}]: need finite rho >= 0, p >= 0, velocity, got rho {} p {} velocity {:?}",
                entry.rho, entry.p, entry.velocity
            ));
        }
    }
    let mut state = FluidState::zeros(dim, grid.n_cells());
    if let Some(profile) = &cfg.profile {
        let to3 = |v: &[f64]| std::array::from_fn(|a| v.get(a).copied().unwrap_or(0.0));
        match profile {
            Profile::DensityWave {
                amplitude,
                wave,
                velocity,
                p,
            } => crate::fv::init::density_wave(
                &mut state,
                &grid,
                *amplitude,
                to3(wave),
                to3(velocity),
                *p,
                params.gamma,
                0.0,
            ),
            Profile::IsentropicVortex {
                beta,
                center,
                velocity,
            } => {
                if dim != 2 {
                    return Err(format!("the isentropic vortex is 2-D, the grid is {dim}-D"));
                }
                crate::fv::init::isentropic_vortex(
                    &mut state,
                    &grid,
                    *beta,
                    [center[0], center[1]],
                    [velocity[0], velocity[1]],
                    params.gamma,
                    0.0,
                );
            }
        }
        let mut params = params;
        set_far_pressures(&grid, &mut params, &state, cfg);
        return Ok((grid, params, state));
    }
    for idx in 0..grid.n_cells() {
        let ijk = grid.ijk(idx);
        let x = grid.cell_center(ijk);
        let entry = cfg.init.iter().rev().find(|e| e.region.contains(&x[..dim]));
        let Some(entry) = entry else {
            return Err(format!(
                "cell {ijk:?} at {:?} is covered by no [[fluid.init]] entry",
                &x[..dim]
            ));
        };
        let mut vel = [0.0; 3];
        vel[..entry.velocity.len()].copy_from_slice(&entry.velocity);
        state.set_primitive(idx, entry.rho, vel, entry.p, params.gamma);
    }
    let mut params = params;
    set_far_pressures(&grid, &mut params, &state, cfg);
    Ok((grid, params, state))
}
