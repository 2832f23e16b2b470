//! What a step reports: the totals, the troubled cells and the refused time step, all as data
//! (the solver core never fails; the caller decides to stop).

use crate::fv::euler::NQ;

/// At most this many troubled cells are listed in one [`StepReport`].
pub const MAX_TROUBLES: usize = 16;

/// Conserved totals over the grid and what left through the domain faces.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Totals {
    /// Mass `Σ ρ V` \[kg\] (per unit length in 2-D, per unit area in 1-D).
    pub mass: f64,
    /// Momentum `Σ ρu V` per axis [kg m/s] (inactive axes 0).
    pub momentum: [f64; 3],
    /// Total energy `Σ E V` \[J\].
    pub energy: f64,
    /// Mass that left through the open (outflow) faces since the start \[kg\].
    pub outflow_mass: f64,
    /// Momentum that left through open and wall faces since the start (at walls: the wall
    /// pressure impulse) [kg m/s].
    pub outflow_momentum: [f64; 3],
    /// Energy that left through the open faces since the start \[J\].
    pub outflow_energy: f64,
}

/// What went wrong in a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TroubleKind {
    /// A value is NaN or infinite.
    NonFinite,
    /// ρ ≤ 0 outside a vacuum cell, or ρ < 0.
    Density,
    /// p ≤ 0 outside a vacuum cell, or p < 0.
    Pressure,
}

/// A cell left non-physical by a sweep (the caller stops the run).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Trouble {
    /// What is wrong.
    pub kind: TroubleKind,
    /// Sweep axis that produced it (0, 1, 2).
    pub axis: usize,
    /// Cell `(i, j, k)` of the whole grid (on any rank).
    pub cell: [usize; 3],
    /// Cell centre \[m\].
    pub position: [f64; 3],
    /// Density [kg/m³].
    pub rho: f64,
    /// Velocity [m/s].
    pub velocity: [f64; 3],
    /// Pressure \[Pa\].
    pub p: f64,
}

/// What one call of `FluidSolver::advance` (or `predict`) did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepReport {
    /// Step number (0 for the first step).
    pub step: u64,
    /// Time step \[s\].
    pub dt: f64,
    /// Time after the step \[s\].
    pub time: f64,
    /// Sweep axes in the order applied.
    pub sweeps: Vec<usize>,
    /// Faces that used Lax–Friedrichs (vacuum), summed over the sweeps.
    pub lax_friedrichs_faces: u64,
    /// Faces that used the HLLE fallback.
    pub hlle_faces: u64,
    /// Cells whose faces the positivity fix recomputed.
    pub positivity_fixes: u64,
    /// Amount that left through the domain faces during this step, `(mass, p_x, p_y, p_z,
    /// energy)` [kg, kg m/s, J].
    pub outflow: [f64; NQ],
    /// Non-physical cells after a sweep (at most [`MAX_TROUBLES`]); empty when all is well.
    pub troubles: Vec<Trouble>,
    /// The time step, when the solver refused it (see [`RefusedTimeStep`]): then no sweep ran
    /// and the state is untouched.
    pub refused: Option<RefusedTimeStep>,
    /// Conserved totals after the step, with the cumulative outflow (see [`Totals`]).
    pub totals: Totals,
}

/// A time step the solver refused to take: not finite and positive, or above the CFL step at
/// Courant number 1 (the one CFL check, in `FluidSolver::advance` and `FluidSolver::predict`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RefusedTimeStep {
    /// The time step asked for \[s\].
    pub dt: f64,
    /// The largest time step accepted \[s\]: the CFL step at Courant number 1,
    /// `FluidSolver::max_dt / cfl` (a relative slack of 1e-12 is allowed above it).
    pub limit: f64,
}

/// A step that failed, as the node reports it: the step refused, or the cells a sweep left
/// non-physical. Formatted once, where it is reported.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The time step was refused (see [`RefusedTimeStep`]).
    #[error(
        "step {step}: CFL violated: dt = {dt:e} s is not in (0, {limit:e}] s, the CFL step at \
         Courant number 1"
    )]
    TimeStep {
        /// Coupling step.
        step: u64,
        /// The time step asked for \[s\].
        dt: f64,
        /// The largest time step accepted \[s\].
        limit: f64,
    },
    /// Cells left non-physical by the sweeps (at most [`MAX_TROUBLES`]).
    #[error("step {step}: {}", list_troubles(troubles))]
    Troubles {
        /// Coupling step.
        step: u64,
        /// The troubled cells, in the report's order.
        troubles: Vec<Trouble>,
    },
}

impl StepReport {
    /// Whether the step was taken and produced no trouble.
    pub fn ok(&self) -> bool {
        self.troubles.is_empty() && self.refused.is_none()
    }

    /// The report as a result: `Ok` when [`StepReport::ok`], else the error, naming the
    /// coupling step `step`.
    pub fn check(&self, step: u64) -> Result<(), StepError> {
        if let Some(RefusedTimeStep { dt, limit }) = self.refused {
            return Err(StepError::TimeStep { step, dt, limit });
        }
        if !self.troubles.is_empty() {
            return Err(StepError::Troubles {
                step,
                troubles: self.troubles.clone(),
            });
        }
        Ok(())
    }
}

impl std::fmt::Display for Trouble {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:?} in cell {:?} at {:?} after the sweep along axis {}: rho = {:e}, p = {:e}, \
             velocity = {:?}",
            self.kind, self.cell, self.position, self.axis, self.rho, self.p, self.velocity
        )
    }
}

/// `troubles` joined with "; ".
fn list_troubles(troubles: &[Trouble]) -> String {
    let list: Vec<String> = troubles.iter().map(Trouble::to_string).collect();
    list.join("; ")
}
