//! The coupling handshake as a sans-IO state machine (DESIGN §3).
//!
//! [`Coupler::on_message`] takes one decoded message and returns the [`Action`]s to carry out:
//! messages to send, a finished step to record, the end of the run. It never blocks, reads no
//! clock and does no IO, so every path (explicit, semi-implicit converging or not, time-step
//! agreement, refusals) is unit-tested without shared memory, and the same machine drives both
//! the iceoryx2 bus and the in-memory transport.
//!
//! One step `n`, both sides present:
//! 1. both nodes send `DtProposal(n)`; the coupler sends `StepPlan(n)` (after a checkpoint
//!    round trip every `checkpoint_every` steps);
//! 2. the fluid sends `InterfaceLoads(n, k)` on the current trial surface (k = 0: `F^n`);
//! 3. the coupler forwards them to the solid, which answers `SolidState(n, k)`;
//! 4. the coupler measures criterion (22) of paper 003 between that trial and the surface the
//!    loads were computed on, decides, and sends `FixedPointDecision` to the solid and the
//!    (possibly relaxed) trial then the decision to the fluid; on `Iterate` go to 2 with k + 1;
//! 5. on `Accept` both nodes commit and send `ConservedTotals(n)`; the ledger is checked.
//!
//! Messages a node sends early (the fluid's next proposal while the solid still finishes its
//! step) are queued and handled when their phase comes.

mod accel;
mod action;
mod checkpoint;
mod config;
mod coupler;
mod criterion;
mod error;
mod fluid_view;
mod handle;
mod restore;
mod step;

pub use accel::AccelerationState;
pub use action::{Action, Finish, StepReport};
pub use checkpoint::{CouplerCheckpoint, Resume};
pub use config::CouplerConfig;
pub use coupler::Coupler;
pub use criterion::criterion_22;
pub use error::{CouplerError, RestoreError};
pub use step::substep_end;

#[cfg(test)]
mod tests;
