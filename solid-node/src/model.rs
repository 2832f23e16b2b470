//! What the solid node's loop needs from an implementation (the DEM, the prescribed double):
//! [`SolidModel`], beyond what every node gives ([`NodeModel`]).

use protocol::session::NodeModel;
use protocol::wire::{InterfaceLoads, SolidState, StepPlan};

use crate::error::StepError;

/// What the loop needs from a solid implementation, beyond what every node gives
/// ([`NodeModel`]).
pub trait SolidModel: NodeModel {
    /// Start of a step (internal forces at `X^n`).
    fn begin_step(&mut self, plan: &StepPlan) -> Result<(), StepError>;
    /// A trial of the step under the given loads (`None`: no fluid); may be called repeatedly.
    fn trial(
        &mut self,
        plan: &StepPlan,
        loads: Option<&InterfaceLoads>,
    ) -> Result<SolidState, StepError>;
    /// Accepts the last trial.
    fn commit(&mut self, plan: &StepPlan) -> Result<(), StepError>;
    /// The current state and wet surface (at `t^0` before any step).
    fn state(&self) -> SolidState;
}
