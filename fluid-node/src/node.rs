//! The fluid node's loop: receive → convert → advance → convert → send (DESIGN §3 from the
//! fluid's side). Written against [`protocol::transport::Transport`] and [`FluidModel`], so the
//! same loop runs the real solver and the pressure double, over the bus or in memory.

use std::path::Path;

use protocol::session::{fail, propose, unexpected};
use protocol::transport::Link;
use protocol::wire::{
    Checkpoint, ConservedTotals, Decision, Hello, InterfaceLoads, Message, NodeKind,
    PROTOCOL_VERSION, SolidState, Stamp, StepPlan,
};

/// What the loop needs from a fluid implementation.
pub trait FluidModel {
    /// `"real"` or the double's name, sent in the hello.
    fn implementation(&self) -> &'static str;
    /// Spatial dimension.
    fn dim(&self) -> usize;
    /// Receives the wet surface at `t^0` (coupled runs), before the first step.
    fn set_initial_surface(&mut self, _state: &SolidState) {}
    /// Largest stable step and what limits it.
    fn dt_max(&self) -> (f64, String);
    /// Start of a step: fluxes over the grid ignoring the solid, and the directional pressures.
    fn predict(&mut self, plan: &StepPlan) -> Result<(), String>;
    /// Force and torque per particle on a trial solid state (eq. 23–25 of paper 003).
    fn loads(&mut self, plan: &StepPlan, state: &SolidState) -> InterfaceLoads;
    /// End of a step: the final solid state (`None` without a solid) is applied.
    fn correct(&mut self, plan: &StepPlan, state: Option<&SolidState>) -> Result<(), String>;
    /// Conserved totals after the last step.
    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals;
    /// Node-private state bytes.
    fn checkpoint(&self) -> Vec<u8>;
    /// Restores a checkpoint.
    fn restore(&mut self, bytes: &[u8]) -> Result<(), String>;
    /// Writes output `k` at time `t` into `out` (fields, VTK).
    fn write_output(&mut self, k: u32, t: f64, out: &Path) -> std::io::Result<()>;
    /// Appends one row to each probe after a step ending at `t`.
    fn record_probes(&mut self, t: f64);
    /// Writes the probe files into `out`.
    fn write_probes(&self, out: &Path) -> std::io::Result<()>;
}

pub use protocol::session::{LoopConfig, NodeError};

/// Runs the fluid side of the handshake until the coupler's shutdown.
pub fn run(
    model: &mut dyn FluidModel,
    link: &mut Link<'_>,
    cfg: &LoopConfig,
) -> Result<(), NodeError> {
    link.greet(Hello {
        node: NodeKind::Fluid,
        protocol_version: PROTOCOL_VERSION,
        scene_hash: cfg.scene_hash,
        implementation: model.implementation().to_string(),
        capabilities: vec!["checkpoint".into()],
    })?;
    link.send(&Message::ConservedTotals(model.totals(Stamp::step(0), 0.0)))?;
    let mut surface = None;
    if cfg.coupled {
        match link.recv()? {
            Message::SolidState(s) => {
                model.set_initial_surface(&s);
                surface = Some(s);
            }
            other => return Err(unexpected(&other, "the initial SolidState")),
        }
    }
    let mut step = 0;
    propose(link, step, model.dt_max())?;
    loop {
        match link.recv()? {
            Message::Shutdown(_) => break,
            Message::CheckpointRequest(r) => {
                // The loop's own state (the current wet surface) travels with the model's.
                let frame = surface.as_ref().map(|s| {
                    protocol::codec::encode(NodeKind::Fluid, &Message::SolidState(s.clone()))
                });
                let bytes = protocol::codec::encode_blob(&(model.checkpoint(), frame));
                link.send(&Message::Checkpoint(Checkpoint {
                    stamp: r.stamp,
                    node: NodeKind::Fluid,
                    bytes,
                }))?;
            }
            Message::Checkpoint(c) => {
                let (bytes, frame): (Vec<u8>, Option<Vec<u8>>) =
                    protocol::codec::decode_blob(&c.bytes).map_err(|e| fail(link, c.stamp, e))?;
                model.restore(&bytes).map_err(|e| fail(link, c.stamp, e))?;
                surface = match frame.map(|f| protocol::codec::decode(&f)) {
                    Some(Ok((_, Message::SolidState(s)))) => Some(s),
                    Some(_) => {
                        return Err(fail(link, c.stamp, "checkpoint holds a bad surface".into()));
                    }
                    None => None,
                };
                step = c.stamp.step;
                propose(link, step, model.dt_max())?;
            }
            Message::StepPlan(plan) => {
                step = plan.stamp.step;
                model
                    .predict(&plan)
                    .map_err(|e| fail(link, plan.stamp, e))?;
                if cfg.coupled {
                    let mut trial = surface
                        .take()
                        .expect("a surface precedes every coupled step");
                    let mut iteration = 0;
                    loop {
                        let mut loads = model.loads(&plan, &trial);
                        loads.stamp = Stamp { step, iteration };
                        link.send(&Message::InterfaceLoads(loads))?;
                        trial = match link.recv()? {
                            Message::SolidState(s) => s,
                            other => return Err(unexpected(&other, "a trial SolidState")),
                        };
                        let decision = match link.recv()? {
                            Message::FixedPointDecision(d) => d,
                            other => return Err(unexpected(&other, "a FixedPointDecision")),
                        };
                        if decision.decision == Decision::Accept {
                            break;
                        }
                        iteration = decision.stamp.iteration + 1;
                    }
                    model
                        .correct(&plan, Some(&trial))
                        .map_err(|e| fail(link, plan.stamp, e))?;
                    surface = Some(trial);
                } else {
                    model
                        .correct(&plan, None)
                        .map_err(|e| fail(link, plan.stamp, e))?;
                }
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

/// Builds the fluid implementation named `implementation` (`real` or `pressure`) for a scene.
pub fn model_from_scene(
    scene: &protocol::scene::Scene,
    implementation: &str,
) -> Result<Box<dyn FluidModel + Send>, String> {
    let fluid = scene
        .fluid
        .as_ref()
        .ok_or("the scene has no [fluid] section")?;
    match implementation {
        "pressure" => Ok(Box::new(crate::double::PressureDouble::new(
            scene.dim(),
            fluid
                .pressure
                .clone()
                .ok_or("the pressure double needs a [fluid.pressure] table in the scene")?,
        ))),
        "real" => Ok(Box::new(crate::exchange::RealFluid::from_scene(scene)?)),
        other => Err(format!(
            "unknown fluid implementation {other:?} (expected real, pressure or replay:FILE.mcap)"
        )),
    }
}
