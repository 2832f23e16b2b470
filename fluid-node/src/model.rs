//! What the fluid node's loop needs from an implementation (the solver, the pressure double):
//! [`FluidModel`], beyond what every node gives ([`NodeModel`]).

use protocol::session::NodeModel;
use protocol::wire::{InterfaceLoads, SolidState, StepPlan};

use crate::Error;

/// What the loop needs from a fluid implementation, beyond what every node gives
/// ([`NodeModel`]).
pub trait FluidModel: NodeModel {
    /// Spatial dimension.
    fn dim(&self) -> usize;
    /// Receives the accepted wet surface and kinematics at the start of a step (coupled runs):
    /// `F^0` before the first step, or the checkpoint's surface after a restore.
    fn set_initial_surface(&mut self, _state: &SolidState) -> Result<(), Error> {
        Ok(())
    }
    /// Start of a step: fluxes over the grid ignoring the solid, and the directional pressures.
    fn predict(&mut self, plan: &StepPlan) -> Result<(), Error>;
    /// Force and torque per particle on a trial solid state (eq. 23–25 of paper 003).
    fn loads(&mut self, plan: &StepPlan, state: &SolidState) -> Result<InterfaceLoads, Error>;
    /// End of a step: the final solid state (`None` without a solid) is applied.
    fn correct(&mut self, plan: &StepPlan, state: Option<&SolidState>) -> Result<(), Error>;
}
