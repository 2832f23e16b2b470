//! The solver's grid, parameters and initial state built from the scene's `[fluid]` table:
//! validation, `[[fluid.init]]` regions or an analytic profile, and the far-field pressures of
//! characteristic sides.

use protocol::scene::{Boundary, FluidConfig, Profile};

use crate::fv::init;
use crate::fv::line::FluxKind;
use crate::fv::state::{BoundaryKind, FluidParams, FluidState};
use crate::grid::{Grid, GridError};

/// Why the scene's `[fluid]` table cannot be run (each with the values found).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// Bad corners or cell counts.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// γ not above 1 (or not finite).
    #[error("fluid.gamma must be > 1, got {gamma}")]
    Gamma {
        /// The ratio of specific heats given [-].
        gamma: f64,
    },
    /// CFL number outside (0, 1].
    #[error("fluid.cfl must be in (0, 1], got {cfl}")]
    Cfl {
        /// The CFL number given [-].
        cfl: f64,
    },
    /// An OSMP order other than 3, 5 or 7.
    #[error("fluid.flux.order must be 3, 5 or 7, got {order}")]
    FluxOrder {
        /// The order given.
        order: u32,
    },
    /// A negative vacuum threshold.
    #[error("fluid.vacuum thresholds must be >= 0, got rho {rho} p {p}")]
    Vacuum {
        /// Density threshold given [kg/m³].
        rho: f64,
        /// Pressure threshold given \[Pa\].
        p: f64,
    },
    /// Periodic on one side of an axis only.
    #[error("axis {axis}: periodic on both sides or on neither, got [{lo:?}, {hi:?}]")]
    PeriodicOneSide {
        /// The axis (0, 1, 2).
        axis: usize,
        /// Its low side.
        lo: Boundary,
        /// Its high side.
        hi: Boundary,
    },
    /// A `[[fluid.init]]` velocity of neither 0 nor `dim` entries.
    #[error("fluid.init[{entry}].velocity: expected 0 or {dim} entries, got {got}")]
    InitVelocityLength {
        /// Index of the `[[fluid.init]]` entry.
        entry: usize,
        /// The grid's dimension.
        dim: usize,
        /// Entries given.
        got: usize,
    },
    /// A `[[fluid.init]]` state with ρ < 0, p < 0 or a non-finite value.
    #[error(
        "fluid.init[{entry}]: need finite rho >= 0, p >= 0, velocity, got rho {rho} p {p} \
         velocity {velocity:?}"
    )]
    InitNotPhysical {
        /// Index of the `[[fluid.init]]` entry.
        entry: usize,
        /// Density given [kg/m³].
        rho: f64,
        /// Pressure given \[Pa\].
        p: f64,
        /// Velocity given [m/s].
        velocity: Vec<f64>,
    },
    /// The isentropic vortex profile on a grid that is not 2-D.
    #[error("the isentropic vortex is 2-D, the grid is {dim}-D")]
    VortexNot2d {
        /// The grid's dimension.
        dim: usize,
    },
    /// A cell whose centre no `[[fluid.init]]` region holds.
    #[error("cell {cell:?} at {position:?} is covered by no [[fluid.init]] entry")]
    Uncovered {
        /// The cell `(i, j, k)`.
        cell: [usize; 3],
        /// Its centre (active axes) \[m\].
        position: Vec<f64>,
    },
}

/// Validates `cfg` and builds the grid, the parameters and the initial state: every
/// `[[fluid.init]]` entry, in order, sets the cells whose centre lies in its region.
///
/// Errors (lowercase, with values): bad dimension or counts, γ ≤ 1, CFL outside (0, 1],
/// order not 3/5/7, periodic on one side only, wrong velocity length, a cell no entry covers,
/// a non-physical initial state (ρ < 0, p < 0 or non-finite).
pub fn from_scene(cfg: &FluidConfig) -> Result<(Grid, FluidParams, FluidState), ConfigError> {
    let (grid, params) = validated(cfg)?;
    let dim = grid.dim;
    if let Some(profile) = &cfg.profile {
        let mut state = FluidState::zeros(dim, grid.n_cells());
        let to3 = |v: &[f64]| std::array::from_fn(|a| v.get(a).copied().unwrap_or(0.0));
        match profile {
            Profile::DensityWave {
                amplitude,
                wave,
                velocity,
                p,
            } => init::density_wave(
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
                    return Err(ConfigError::VortexNot2d { dim });
                }
                init::isentropic_vortex(
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
    let state = regions_of_block(cfg, &grid, params.gamma, ([0; 3], grid.cells))?;
    let mut params = params;
    set_far_pressures(&grid, &mut params, &state, cfg);
    Ok((grid, params, state))
}

/// Whether a block's initial state from the `[[fluid.init]]` regions
/// ([`regions_of_block`]) is all that [`from_scene`] gives a rank of that block: no analytic
/// profile, and no characteristic side (whose far-field pressure may be the mean of the
/// initial pressures along that side, which other blocks hold).
pub fn init_by_block(cfg: &FluidConfig) -> bool {
    let characteristic = (0..3).any(|a| cfg.boundary.axis(a).contains(&Boundary::Characteristic));
    cfg.profile.is_none() && !characteristic
}

/// The grid and the parameters of the scene's `[fluid]` table, validated (everything
/// [`from_scene`] checks but the cells' initial states).
pub fn validated(cfg: &FluidConfig) -> Result<(Grid, FluidParams), ConfigError> {
    let cells: Vec<usize> = cfg.cells.iter().map(|&n| n as usize).collect();
    let grid = Grid::new(&cfg.lower, &cfg.upper, &cells)?;
    let dim = grid.dim;
    if !(cfg.gamma > 1.0 && cfg.gamma.is_finite()) {
        return Err(ConfigError::Gamma { gamma: cfg.gamma });
    }
    if !(cfg.cfl > 0.0 && cfg.cfl <= 1.0) {
        return Err(ConfigError::Cfl { cfl: cfg.cfl });
    }
    if ![3, 5, 7].contains(&cfg.flux.order) {
        return Err(ConfigError::FluxOrder {
            order: cfg.flux.order,
        });
    }
    let vacuum = cfg.vacuum();
    if !(vacuum.rho >= 0.0 && vacuum.p >= 0.0) {
        return Err(ConfigError::Vacuum {
            rho: vacuum.rho,
            p: vacuum.p,
        });
    }
    let mut boundary = [[BoundaryKind::Outflow; 2]; 3];
    for (axis, b) in boundary.iter_mut().enumerate().take(dim) {
        let [lo, hi] = cfg.boundary.axis(axis);
        if (lo == Boundary::Periodic) != (hi == Boundary::Periodic) {
            return Err(ConfigError::PeriodicOneSide { axis, lo, hi });
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
        vacuum_rho: vacuum.rho,
        vacuum_p: vacuum.p,
    };
    for (k, entry) in cfg.init.iter().enumerate() {
        if !(entry.velocity.is_empty() || entry.velocity.len() == dim) {
            return Err(ConfigError::InitVelocityLength {
                entry: k,
                dim,
                got: entry.velocity.len(),
            });
        }
        let vel_ok = entry.velocity.iter().all(|v| v.is_finite());
        let finite = entry.rho.is_finite() && entry.p.is_finite() && vel_ok;
        if !(entry.rho >= 0.0 && entry.p >= 0.0 && finite) {
            return Err(ConfigError::InitNotPhysical {
                entry: k,
                rho: entry.rho,
                p: entry.p,
                velocity: entry.velocity.clone(),
            });
        }
    }
    Ok((grid, params))
}

/// The initial state of the cells of the block `(first, own)` of `grid` (its first cell and
/// its cells per axis, [`crate::fv::Slab::block_of_rank`]; `([0; 3], grid.cells)`: the whole
/// grid) from the `[[fluid.init]]` regions, x fastest over the block: every entry, in order,
/// sets the cells whose centre lies in its region. Errors: the block's first cell that no entry
/// covers, in the grid's order.
pub fn regions_of_block(
    cfg: &FluidConfig,
    grid: &Grid,
    gamma: f64,
    (first, own): ([usize; 3], [usize; 3]),
) -> Result<FluidState, ConfigError> {
    let dim = grid.dim;
    let mut state = FluidState::zeros(dim, own.iter().product());
    let mut idx = 0;
    for k in first[2]..first[2] + own[2] {
        for j in first[1]..first[1] + own[1] {
            for i in first[0]..first[0] + own[0] {
                let ijk = [i, j, k];
                let x = grid.cell_center(ijk);
                let entry = cfg.init.iter().rev().find(|e| e.region.contains(&x[..dim]));
                let Some(entry) = entry else {
                    return Err(ConfigError::Uncovered {
                        cell: ijk,
                        position: x[..dim].to_vec(),
                    });
                };
                let mut vel = [0.0; 3];
                vel[..entry.velocity.len()].copy_from_slice(&entry.velocity);
                state.set_primitive(idx, entry.rho, vel, entry.p, gamma);
                idx += 1;
            }
        }
    }
    Ok(state)
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
