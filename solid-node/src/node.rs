//! The solid node's loop: receive → convert → advance → convert → send (DESIGN §3 from the
//! solid's side). Written against [`protocol::transport::Transport`] and [`SolidModel`], so the
//! same loop runs the DEM and the prescribed double, over the bus or in memory.

use protocol::session::{NodeModel, fail, run_node, unexpected};
use protocol::transport::Link;
use protocol::wire::{Decision, InterfaceLoads, Message, NodeKind, SolidState, Stamp, StepPlan};

/// What the loop needs from a solid implementation, beyond what every node gives
/// ([`NodeModel`]).
pub trait SolidModel: NodeModel {
    /// Start of a step (internal forces at `X^n`).
    fn begin_step(&mut self, plan: &StepPlan) -> Result<(), String>;
    /// A trial of the step under the given loads (`None`: no fluid); may be called repeatedly.
    fn trial(
        &mut self,
        plan: &StepPlan,
        loads: Option<&InterfaceLoads>,
    ) -> Result<SolidState, String>;
    /// Accepts the last trial.
    fn commit(&mut self, plan: &StepPlan) -> Result<(), String>;
    /// The current state and wet surface (at `t^0` before any step).
    fn state(&self) -> SolidState;
}

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
        .map_err(|e| fail(link, plan.stamp, e))?;
    if coupled {
        loop {
            let loads = match link.recv()? {
                Message::InterfaceLoads(l) => l,
                other => return Err(unexpected(&other, "InterfaceLoads")),
            };
            let mut trial = model
                .trial(plan, Some(&loads))
                .map_err(|e| fail(link, loads.stamp, e))?;
            trial.stamp = loads.stamp;
            link.send(&Message::SolidState(trial))?;
            match link.recv()? {
                Message::FixedPointDecision(d) if d.decision == Decision::Accept => break,
                Message::FixedPointDecision(_) => {}
                other => return Err(unexpected(&other, "a FixedPointDecision")),
            }
        }
    } else {
        model
            .trial(plan, None)
            .map_err(|e| fail(link, plan.stamp, e))?;
    }
    model.commit(plan).map_err(|e| fail(link, plan.stamp, e))
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

/// Builds the solid implementation named `implementation` (`real` or `prescribed`) for a scene.
pub fn model_from_scene(
    scene: &protocol::scene::Scene,
    implementation: &str,
) -> Result<Box<dyn SolidModel + Send>, String> {
    let solid = scene
        .solid
        .as_ref()
        .ok_or("the scene has no [solid] section")?;
    match implementation {
        "prescribed" => Ok(Box::new(crate::double::PrescribedDouble::new(
            scene.dim(),
            solid
                .prescribed
                .as_ref()
                .ok_or("the prescribed double needs a [solid.prescribed] table in the scene")?,
        ))),
        "real" => Ok(Box::new(crate::exchange::RealSolid::from_scene(scene)?)),
        other => Err(format!(
            "unknown solid implementation {other:?} (expected real, prescribed or replay:FILE.mcap)"
        )),
    }
}
