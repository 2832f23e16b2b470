//! The solid node's loop: receive → convert → advance → convert → send (DESIGN §3 from the
//! solid's side). Written against [`protocol::transport::Transport`] and [`SolidModel`], so the
//! same loop runs the DEM and the prescribed double, over the bus or in memory.

use std::path::Path;

use protocol::session::{fail, propose, unexpected};
use protocol::transport::Link;
use protocol::wire::{
    Checkpoint, ConservedTotals, Decision, Hello, InterfaceLoads, Message, NodeKind,
    PROTOCOL_VERSION, SolidState, Stamp, StepPlan,
};

/// What the loop needs from a solid implementation.
pub trait SolidModel {
    /// `"real"` or the double's name, sent in the hello.
    fn implementation(&self) -> &'static str;
    /// Largest stable step and what limits it.
    fn dt_max(&self) -> (f64, String);
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
    /// Conserved totals after the last commit.
    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals;
    /// Node-private state bytes.
    fn checkpoint(&self) -> Vec<u8>;
    /// Restores a checkpoint.
    fn restore(&mut self, bytes: &[u8]) -> Result<(), String>;
    /// Writes output `k` at time `t` into `out`.
    fn write_output(&mut self, k: u32, t: f64, out: &Path) -> std::io::Result<()>;
    /// Appends one row to each probe after a step ending at `t`.
    fn record_probes(&mut self, t: f64);
    /// Writes the probe files into `out`.
    fn write_probes(&self, out: &Path) -> std::io::Result<()>;
}

pub use protocol::session::{LoopConfig, NodeError};

/// Runs the solid side of the handshake until the coupler's shutdown.
pub fn run(
    model: &mut dyn SolidModel,
    link: &mut Link<'_>,
    cfg: &LoopConfig,
) -> Result<(), NodeError> {
    link.greet(Hello {
        node: NodeKind::Solid,
        protocol_version: PROTOCOL_VERSION,
        scene_hash: cfg.scene_hash,
        implementation: model.implementation().to_string(),
        capabilities: vec!["checkpoint".into()],
    })?;
    link.send(&Message::ConservedTotals(model.totals(Stamp::step(0), 0.0)))?;
    if cfg.coupled {
        let mut initial = model.state();
        initial.stamp = Stamp::step(0);
        link.send(&Message::SolidState(initial))?;
    }
    let mut step = 0;
    propose(link, step, model.dt_max())?;
    loop {
        match link.recv()? {
            Message::Shutdown(_) => break,
            Message::CheckpointRequest(r) => {
                let bytes = model.checkpoint();
                link.send(&Message::Checkpoint(Checkpoint {
                    stamp: r.stamp,
                    node: NodeKind::Solid,
                    bytes,
                }))?;
            }
            Message::Checkpoint(c) => {
                model
                    .restore(&c.bytes)
                    .map_err(|e| fail(link, c.stamp, e))?;
                step = c.stamp.step;
                propose(link, step, model.dt_max())?;
            }
            Message::StepPlan(plan) => {
                step = plan.stamp.step;
                model
                    .begin_step(&plan)
                    .map_err(|e| fail(link, plan.stamp, e))?;
                if cfg.coupled {
                    loop {
                        let loads = match link.recv()? {
                            Message::InterfaceLoads(l) => l,
                            other => return Err(unexpected(&other, "InterfaceLoads")),
                        };
                        let mut trial = model
                            .trial(&plan, Some(&loads))
                            .map_err(|e| fail(link, loads.stamp, e))?;
                        trial.stamp = loads.stamp;
                        link.send(&Message::SolidState(trial))?;
                        match link.recv()? {
                            Message::FixedPointDecision(d) if d.decision == Decision::Accept => {
                                break;
                            }
                            Message::FixedPointDecision(_) => {}
                            other => return Err(unexpected(&other, "a FixedPointDecision")),
                        }
                    }
                } else {
                    model
                        .trial(&plan, None)
                        .map_err(|e| fail(link, plan.stamp, e))?;
                }
                model.commit(&plan).map_err(|e| fail(link, plan.stamp, e))?;
                let t_end = plan.t + plan.dt;
                model.record_probes(t_end);
                if let (Some(k), Some(out)) = (plan.output, &cfg.out) {
                    model
                        .write_output(k, t_end, out)
                        .map_err(|source| NodeError::output(out, source))?;
                }
                link.send(&Message::ConservedTotals(
                    model.totals(Stamp::step(step), t_end),
                ))?;
                step += 1;
                propose(link, step, model.dt_max())?;
            }
            other => {
                return Err(unexpected(
                    &other,
                    "StepPlan, CheckpointRequest or Shutdown",
                ));
            }
        }
    }
    if let Some(out) = &cfg.out {
        model
            .write_probes(out)
            .map_err(|source| NodeError::output(out, source))?;
    }
    Ok(())
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
