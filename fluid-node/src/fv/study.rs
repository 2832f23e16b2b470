//! Pure parts of convergence and work–precision studies on 1-D Riemann scenes: the exact
//! reference read off the scene's initial data, solvers at a given resolution and flux, and
//! the L1 error. Timing and files are in `crate::report`.

use protocol::scene::FluidConfig;

use crate::fv::exact_riemann::RiemannError;
use crate::fv::exact_riemann::{ExactRiemann, Prim1};
use crate::fv::scene::from_scene;
use crate::fv::{FluidSolver, FluxKind, SolverError};

/// Why a scene cannot serve as the reference of the work–precision study.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StudyError {
    /// The scene is not 1-D.
    #[error("work-precision needs a 1-D scene, got {axes} axes")]
    NotOneD {
        /// Axes of the scene.
        axes: usize,
    },
    /// No `[[fluid.init]]` entry covers one end.
    #[error("no [[fluid.init]] entry covers the {side} end")]
    Uncovered {
        /// `"left"` or `"right"`.
        side: &'static str,
    },
    /// The two ends hold the same state.
    #[error("the scene is not a Riemann problem: equal states at both ends")]
    EqualStates,
    /// The exact solver does not take the two states.
    #[error(transparent)]
    Riemann(#[from] RiemannError),
}

/// The exact solution of a 1-D scene made of two constant states.
#[derive(Clone, Copy, Debug)]
pub struct RiemannReference {
    /// The solved problem.
    pub exact: ExactRiemann,
    /// Position of the initial discontinuity \[m\].
    pub x0: f64,
}

fn init_state(cfg: &FluidConfig, x: f64) -> Option<Prim1> {
    cfg.init
        .iter()
        .rev()
        .find(|e| e.region.contains(&[x]))
        .map(|e| Prim1 {
            rho: e.rho,
            u: e.velocity.first().copied().unwrap_or(0.0),
            p: e.p,
        })
}

impl RiemannReference {
    /// Reads the left and right states at the ends of a 1-D scene and locates the jump
    /// between them by bisection.
    pub fn from_config(cfg: &FluidConfig) -> Result<RiemannReference, StudyError> {
        if cfg.lower.len() != 1 || cfg.upper.len() != 1 {
            return Err(StudyError::NotOneD {
                axes: cfg.lower.len(),
            });
        }
        let (lo, hi) = (cfg.lower[0], cfg.upper[0]);
        let left = init_state(cfg, lo).ok_or(StudyError::Uncovered { side: "left" })?;
        let right = init_state(cfg, hi).ok_or(StudyError::Uncovered { side: "right" })?;
        if left == right {
            return Err(StudyError::EqualStates);
        }
        let (mut a, mut b) = (lo, hi);
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if init_state(cfg, m) == Some(left) {
                a = m;
            } else {
                b = m;
            }
        }
        let exact = ExactRiemann::new(left, right, cfg.gamma)?;
        Ok(RiemannReference {
            exact,
            x0: 0.5 * (a + b),
        })
    }

    /// L1 error of the density `Σ |ρ − ρ_exact| Δx` of `solver` at its current time against
    /// the exact cell averages.
    pub fn l1_density(&self, solver: &FluidSolver) -> f64 {
        let grid = solver.grid();
        let t = solver.time();
        let mut acc = 0.0;
        for i in 0..grid.cells[0] {
            let xa = grid.lower[0] + i as f64 * grid.dx[0];
            let avg = self.exact.cell_average(xa, xa + grid.dx[0], self.x0, t);
            acc += (solver.state().u[i * 3] - avg[0]).abs();
        }
        acc * grid.dx[0]
    }
}

/// A solver for the scene at `cells` cells with regular flux `flux`.
pub fn solver_for(
    cfg: &FluidConfig,
    flux: FluxKind,
    cells: u32,
    threads: usize,
) -> Result<FluidSolver, SolverError> {
    let mut cfg = cfg.clone();
    cfg.cells = vec![cells; cfg.lower.len()];
    if let FluxKind::Osmp(order) = flux {
        cfg.flux.order = order;
    }
    let (grid, mut params, state) = from_scene(&cfg)?;
    params.flux = flux;
    FluidSolver::new(grid, params, state, threads)
}
