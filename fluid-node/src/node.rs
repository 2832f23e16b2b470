//! The fluid node's loop: receive → convert → advance → convert → send (DESIGN §3 from the
//! fluid's side). Written against [`protocol::transport::Transport`] and [`FluidModel`], so the
//! same loop runs the real solver and the pressure double, over the bus or in memory.

use std::path::Path;

use protocol::session::{NodeModel, StepLimit, fail, run_node, unexpected};
use protocol::transport::Link;
use protocol::wire::{ConservedTotals, Decision, Message, NodeKind, SolidState, Stamp, StepPlan};

use crate::model::FluidModel;

pub use protocol::session::{LoopConfig, NodeError};

/// A fluid model with the loop's own state: the last accepted wet surface, which travels with
/// the model's bytes in checkpoints.
struct FluidSide<'m> {
    model: &'m mut dyn FluidModel,
    surface: Option<SolidState>,
}

impl NodeModel for FluidSide<'_> {
    fn implementation(&self) -> &'static str {
        self.model.implementation()
    }

    fn dt_max(&self) -> StepLimit {
        self.model.dt_max()
    }

    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals {
        self.model.totals(stamp, t)
    }

    fn checkpoint(&self) -> Vec<u8> {
        let frame = self
            .surface
            .as_ref()
            .map(|s| protocol::codec::encode(NodeKind::Fluid, &Message::SolidState(s.clone())));
        protocol::codec::encode_blob(&(self.model.checkpoint(), frame))
    }

    fn restore(&mut self, bytes: &[u8]) -> Result<(), String> {
        let (bytes, frame): (Vec<u8>, Option<Vec<u8>>) = protocol::codec::decode_blob(bytes)?;
        self.model.restore(&bytes)?;
        self.surface = match frame.map(|f| protocol::codec::decode(&f)) {
            Some(Ok((_, Message::SolidState(s)))) => Some(s),
            Some(_) => return Err("checkpoint holds a bad surface".into()),
            None => None,
        };
        if let Some(s) = &self.surface {
            // The wire boundary: `NodeModel` is the protocol's trait and takes the text.
            self.model
                .set_initial_surface(s)
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    fn write_output(&mut self, k: u32, t: f64, out: &Path) -> std::io::Result<()> {
        self.model.write_output(k, t, out)
    }

    fn record_probes(&mut self, t: f64) {
        self.model.record_probes(t);
    }

    fn write_probes(&mut self, out: &Path, end: bool) -> std::io::Result<()> {
        self.model.write_probes(out, end)
    }
}

impl FluidSide<'_> {
    /// The fluid's side of one step: predict, then (coupled) loads on each trial surface until
    /// the coupler accepts one, then correct. Iteration 0's surface is the accepted `F^n`, or
    /// the predicted state the coupler sends after a plan that says so.
    fn advance(
        &mut self,
        link: &mut Link<'_>,
        plan: &StepPlan,
        coupled: bool,
    ) -> Result<(), NodeError> {
        let step = plan.stamp.step;
        self.model
            .predict(plan)
            .map_err(|e| fail(link, plan.stamp, e.to_string()))?;
        if !coupled {
            return self
                .model
                .correct(plan, None)
                .map_err(|e| fail(link, plan.stamp, e.to_string()));
        }
        let accepted = self
            .surface
            .take()
            .expect("a surface precedes every coupled step");
        let mut trial = if plan.predicted {
            match link.recv()? {
                Message::SolidState(s) => s,
                other => return Err(unexpected(&other, "the predicted SolidState")),
            }
        } else {
            accepted
        };
        let mut iteration = 0;
        loop {
            let mut loads = self
                .model
                .loads(plan, &trial)
                .map_err(|e| fail(link, Stamp { step, iteration }, e.to_string()))?;
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
            tracing::trace!(
                "step {step} iteration {iteration}: loads sent, {:?} at residual {:.3e}",
                decision.decision,
                decision.residual
            );
            if decision.decision == Decision::Accept {
                break;
            }
            iteration = decision.stamp.iteration + 1;
        }
        self.model
            .correct(plan, Some(&trial))
            .map_err(|e| fail(link, plan.stamp, e.to_string()))?;
        self.surface = Some(trial);
        Ok(())
    }
}

/// Runs the fluid side of the handshake until the coupler's shutdown.
pub fn run(
    model: &mut dyn FluidModel,
    link: &mut Link<'_>,
    cfg: &LoopConfig,
) -> Result<(), NodeError> {
    let mut side = FluidSide {
        model,
        surface: None,
    };
    let coupled = cfg.coupled;
    run_node(
        NodeKind::Fluid,
        &mut side,
        link,
        cfg,
        |side, link| match link.recv()? {
            Message::SolidState(s) => {
                side.model
                    .set_initial_surface(&s)
                    .map_err(|e| fail(link, s.stamp, e.to_string()))?;
                side.surface = Some(s);
                Ok(())
            }
            other => Err(unexpected(&other, "the initial SolidState")),
        },
        |side, link, plan| side.advance(link, plan, coupled),
    )
}
