//! A coupler from a checkpoint: the one a replay resumes, and the one a restarted run greets
//! fresh nodes with.

use protocol::wire::NodeKind;

use crate::scheme::checkpoint::{CouplerCheckpoint, Resume};
use crate::scheme::config::CouplerConfig;
use crate::scheme::coupler::{Coupler, Phase};
use crate::scheme::error::RestoreError;

impl Coupler {
    /// The coupler's state between steps (see [`CouplerCheckpoint`]).
    pub fn checkpoint(&self) -> CouplerCheckpoint {
        CouplerCheckpoint {
            step: self.step,
            t: self.t,
            next_output: self.next_output,
            plan: self.plan.clone(),
            acceleration: self.acceleration.state(),
            ledger: self.ledger.clone(),
            iteration_total: self.iteration_total,
            iteration_max: self.iteration_max,
            queue: self.queue.iter().cloned().collect(),
        }
    }

    /// A coupler resumed from `checkpoint`, waiting for the nodes' checkpoints of its step as
    /// the original was when it took it.
    pub fn restore(
        cfg: CouplerConfig,
        checkpoint: &CouplerCheckpoint,
    ) -> Result<Coupler, RestoreError> {
        let mut c = Coupler::new(cfg);
        c.apply(checkpoint)?;
        c.plan = checkpoint.plan.clone();
        c.queue = checkpoint.queue.iter().cloned().collect();
        c.phase = Phase::Checkpoints(Vec::new());
        Ok(c)
    }

    /// A coupler that restarts a run at the step of `resume`: it greets fresh nodes, sends each
    /// its checkpoint (a node restores and proposes for that step), takes back its own state
    /// and goes on from there as the original run did. Proposals the nodes make for step 0
    /// before they are restored are dropped.
    pub fn resuming(cfg: CouplerConfig, resume: Resume) -> Result<Coupler, RestoreError> {
        // Checked now rather than after the greeting.
        Coupler::new(cfg.clone()).apply(&resume.coupler)?;
        let mut c = Coupler::new(cfg);
        let nodes: Vec<NodeKind> = resume.nodes.iter().map(|n| n.node).collect();
        if nodes != c.cfg.nodes() {
            return Err(RestoreError::Nodes {
                checkpoints: nodes,
                scene: c.cfg.nodes(),
            });
        }
        c.resume = Some(resume);
        Ok(c)
    }

    /// Takes the state of a checkpoint (not the plan, the queue or the phase).
    pub(super) fn apply(&mut self, checkpoint: &CouplerCheckpoint) -> Result<(), RestoreError> {
        self.acceleration.restore(&checkpoint.acceleration)?;
        self.step = checkpoint.step;
        self.t = checkpoint.t;
        self.next_output = checkpoint.next_output;
        self.ledger = checkpoint.ledger.clone();
        self.iteration_total = checkpoint.iteration_total;
        self.iteration_max = checkpoint.iteration_max;
        Ok(())
    }
}
