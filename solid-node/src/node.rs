//! The solid node's loop: receive → convert → advance → convert → send (DESIGN §3 from the
//! solid's side). Written against [`protocol::transport::Transport`] and [`SolidModel`], so the
//! same loop runs the DEM and the prescribed double, over the bus or in memory. The model trait
//! is in [`crate::model`]; which model a scene asks for is decided in `cli.rs`.

use protocol::session::{fail, run_node, unexpected};
use protocol::transport::Link;
use protocol::wire::{Decision, Message, NodeKind, SolidState, Stamp, StepPlan};

use crate::model::SolidModel;

pub use protocol::session::{LoopConfig, NodeError};

/// The solid's side of one step: begin, then (coupled) one trial per set of loads until the
/// coupler accepts one, then commit.
fn advance(
    model: &mut dyn SolidModel,
    link: &mut Link<'_>,
    plan: &StepPlan,
    coupled: bool,
) -> Result<(), NodeError> {
    model
        .begin_step(plan)
        .map_err(|e| fail(link, plan.stamp, e.to_string()))?;
    if coupled {
        // The step's first trial, whole: the later ones go out as the particles that differ
        // from it (`SolidState::changes_from`; issue 39 item 4).
        let mut first: Option<SolidState> = None;
        loop {
            let loads = match link.recv()? {
                Message::InterfaceLoads(l) => l,
                other => return Err(unexpected(&other, "InterfaceLoads")),
            };
            let mut trial = model
                .trial(plan, Some(&loads))
                .map_err(|e| fail(link, loads.stamp, e.to_string()))?;
            trial.stamp = loads.stamp;
            match &first {
                Some(first) => link.send(&Message::SolidState(trial.changes_from(first)))?,
                None => {
                    link.send(&Message::SolidState(trial.clone()))?;
                    first = Some(trial);
                }
            }
            let decision = match link.recv()? {
                Message::FixedPointDecision(d) => d,
                other => return Err(unexpected(&other, "a FixedPointDecision")),
            };
            tracing::trace!(
                "step {} iteration {}: trial sent, {:?} at residual {:.3e}",
                loads.stamp.step,
                loads.stamp.iteration,
                decision.decision,
                decision.residual
            );
            if decision.decision == Decision::Accept {
                break;
            }
        }
    } else {
        model
            .trial(plan, None)
            .map_err(|e| fail(link, plan.stamp, e.to_string()))?;
    }
    model
        .commit(plan)
        .map_err(|e| fail(link, plan.stamp, e.to_string()))
}

/// Runs the solid side of the handshake until the coupler's shutdown.
pub fn run(
    model: &mut dyn SolidModel,
    link: &mut Link<'_>,
    cfg: &LoopConfig,
) -> Result<(), NodeError> {
    let coupled = cfg.coupled;
    run_node(
        NodeKind::Solid,
        model,
        link,
        cfg,
        |model, link| {
            let mut initial = model.state();
            initial.stamp = Stamp::step(0);
            link.send(&Message::SolidState(initial))?;
            Ok(())
        },
        |model, link, plan| advance(model, link, plan, coupled),
    )
}
