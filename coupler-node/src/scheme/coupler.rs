//! The coupler's state ([`Coupler`]), its phases, and the entry point [`Coupler::on_message`]:
//! which queued message the current phase takes, and what the coupler waits for.

use std::collections::VecDeque;

use protocol::session::SUBSTEP_BOUND_ITERATION;
use protocol::wire::{ConservedTotals, Message, NodeKind, ShutdownReason, SolidState, Stamp};

use crate::dt::{Agreed, Proposal};
use crate::ledger::Ledger;
use crate::scheme::accel::Acceleration;
use crate::scheme::action::{Action, Finish};
use crate::scheme::checkpoint::Resume;
use crate::scheme::config::CouplerConfig;
use crate::scheme::error::CouplerError;

/// The coupler's state.
#[derive(Debug)]
pub struct Coupler {
    pub(super) cfg: CouplerConfig,
    pub(super) phase: Phase,
    pub(super) queue: VecDeque<(NodeKind, Message)>,
    /// The current step.
    pub(super) step: u64,
    /// Its start time \[s\].
    pub(super) t: f64,
    /// Index of the first output time not yet written.
    pub(super) next_output: usize,
    /// The current step as agreed, from the proposals until its totals are booked.
    pub(super) plan: Option<Agreed>,
    /// Input of the current iteration (the accepted `F^n`, a prediction, a relaxed trial).
    pub(super) input: Option<SolidState>,
    pub(super) residuals: Vec<f64>,
    pub(super) acceleration: Acceleration,
    pub(super) ledger: Ledger,
    pub(super) initial_totals: Vec<ConservedTotals>,
    pub(super) iteration_total: u64,
    pub(super) iteration_max: u32,
    /// A restart waiting for the greeting to end.
    pub(super) resume: Option<Resume>,
    /// Proposals for steps before this one are dropped (a restart's, from before the restore).
    pub(super) stale_before: u64,
    /// With `run.solid_substeps`: the solid's stable step for the sub-steps of this step, its
    /// second proposal (until the step is agreed).
    pub(super) substep_bound: Option<Proposal>,
    /// Solid sub-steps of the agreed step (1 without `run.solid_substeps`).
    pub(super) substeps: u32,
    /// The current step's first trial, whole: the solid sends the later ones as the particles
    /// that changed (`SolidState::changed_only`).
    pub(super) first_trial: Option<SolidState>,
}

/// Where the handshake stands; each phase holds what it has collected so far.
#[derive(Clone, Debug)]
pub(super) enum Phase {
    Greeting {
        hello: Vec<NodeKind>,
        totals: Vec<NodeKind>,
        surface: bool,
    },
    Proposals(Vec<Proposal>),
    Checkpoints(Vec<NodeKind>),
    Loads(u32),
    Trial(u32),
    Totals(Vec<ConservedTotals>),
    /// The last step is done: collect the proposals the nodes send after every step, so the
    /// record holds the same messages whatever the timing, then shut down.
    Closing(Vec<NodeKind>, Finish),
    Done,
}

impl Coupler {
    /// A coupler waiting for the nodes' hellos.
    pub fn new(cfg: CouplerConfig) -> Coupler {
        Coupler {
            acceleration: Acceleration::new(&cfg),
            phase: Phase::Greeting {
                hello: Vec::new(),
                totals: Vec::new(),
                surface: !(cfg.fluid && cfg.solid),
            },
            cfg,
            queue: VecDeque::new(),
            step: 0,
            t: 0.0,
            next_output: 0,
            plan: None,
            input: None,
            residuals: Vec::new(),
            ledger: Ledger::default(),
            initial_totals: Vec::new(),
            iteration_total: 0,
            iteration_max: 0,
            resume: None,
            stale_before: 0,
            substep_bound: None,
            substeps: 1,
            first_trial: None,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &CouplerConfig {
        &self.cfg
    }

    /// Current step.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// Time at the start of the current step \[s\].
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Time at the end of the current step once its size is agreed \[s\] (`None` before).
    pub fn planned_end(&self) -> Option<f64> {
        self.plan
            .as_ref()
            .map(|agreed| agreed.end(self.t, &self.cfg.outputs))
    }

    /// The ledger so far.
    pub fn ledger(&self) -> &Ledger {
        &self.ledger
    }

    /// Mean and largest number of solid trials per coupled step.
    pub fn iteration_stats(&self) -> (f64, u32) {
        let mean = if self.step == 0 {
            0.0
        } else {
            self.iteration_total as f64 / self.step as f64
        };
        (mean, self.iteration_max)
    }

    /// The nodes to name when the wait for [`Coupler::waiting_for`] times out: at the greeting,
    /// those that have not said hello, if any (a node that has waits for what the coupler sends
    /// once every node has greeted, so it is not the silent one), else those waited for.
    pub fn silent(&self) -> Vec<NodeKind> {
        if let Phase::Greeting { hello, .. } = &self.phase {
            let unheard: Vec<NodeKind> = (self.cfg.nodes().into_iter())
                .filter(|n| !hello.contains(n))
                .collect();
            if !unheard.is_empty() {
                return unheard;
            }
        }
        self.waiting_for()
    }

    /// The nodes the coupler is waiting for now (the peers a receive takes frames from).
    pub fn waiting_for(&self) -> Vec<NodeKind> {
        match &self.phase {
            Phase::Greeting {
                hello,
                totals,
                surface,
            } => {
                let mut w: Vec<NodeKind> = self
                    .cfg
                    .nodes()
                    .into_iter()
                    .filter(|n| !hello.contains(n) || !totals.contains(n))
                    .collect();
                if !surface && !w.contains(&NodeKind::Solid) {
                    w.push(NodeKind::Solid);
                }
                w
            }
            Phase::Proposals(got) => self.proposals_missing(got.iter().map(|g| g.node)),
            Phase::Checkpoints(got) => self.missing(got.iter().copied()),
            Phase::Loads(_) => vec![NodeKind::Fluid],
            Phase::Trial(_) => vec![NodeKind::Solid],
            Phase::Totals(got) => self.missing(got.iter().map(|g| g.node)),
            Phase::Closing(got, _) => self.proposals_missing(got.iter().copied()),
            Phase::Done => Vec::new(),
        }
    }

    /// [`Coupler::missing`] for the proposals: with `run.solid_substeps`, the solid sends two.
    fn proposals_missing(&self, got: impl Iterator<Item = NodeKind> + Clone) -> Vec<NodeKind> {
        let mut missing = self.missing(got);
        if self.wants_substep_bound() && !missing.contains(&NodeKind::Solid) {
            missing.push(NodeKind::Solid);
        }
        missing
    }

    /// The solid's sub-step bound is still to come for this step.
    fn wants_substep_bound(&self) -> bool {
        self.cfg.solid && self.cfg.substeps.is_some() && self.substep_bound.is_none()
    }

    pub(super) fn missing(&self, got: impl Iterator<Item = NodeKind> + Clone) -> Vec<NodeKind> {
        self.cfg
            .nodes()
            .into_iter()
            .filter(|n| !got.clone().any(|g| g == *n))
            .collect()
    }

    /// Handles one message from a node.
    pub fn on_message(
        &mut self,
        from: NodeKind,
        msg: Message,
    ) -> Result<Vec<Action>, CouplerError> {
        let mut actions = Vec::new();
        match msg {
            Message::Failure(f) => {
                return Err(CouplerError::NodeFailure {
                    node: from,
                    stamp: f.stamp,
                    report: f.report,
                });
            }
            Message::Shutdown(s) => {
                return Err(CouplerError::NodeShutdown {
                    node: from,
                    reason: match s.reason {
                        ShutdownReason::Completed => "completed".into(),
                        ShutdownReason::Interrupted => "interrupted".into(),
                        ShutdownReason::Failure(why) => why,
                    },
                });
            }
            // A restarted node's proposal from before its restore.
            msg if stale(&msg, self.stale_before) => {}
            msg => self.queue.push_back((from, msg)),
        }
        // Handle queued messages in arrival order, as long as the current phase takes them.
        while let Some(pos) = self
            .queue
            .iter()
            .position(|(from, msg)| self.accepts(*from, msg))
        {
            let (from, msg) = self.queue.remove(pos).expect("position is in range");
            self.handle(from, msg, &mut actions)?;
        }
        // Anything left must belong to a later phase of a node that is done with this one.
        let greeting_kind = |m: &Message| {
            matches!(
                m,
                Message::Hello(_)
                    | Message::ConservedTotals(_)
                    | Message::SolidState(_)
                    | Message::DtProposal(_)
            )
        };
        if let Some((from, msg)) = self.queue.back()
            && self.waiting_for().contains(from)
            && !(matches!(self.phase, Phase::Greeting { .. }) && greeting_kind(msg))
        {
            return Err(CouplerError::Unexpected {
                from: *from,
                got: format!("{:?}", msg.kind()),
                stamp: msg.stamp(),
                expected: self.expected(),
            });
        }
        Ok(actions)
    }

    pub(super) fn expected(&self) -> String {
        match &self.phase {
            Phase::Greeting { .. } => {
                "Hello, initial ConservedTotals and (solid) the initial SolidState".into()
            }
            Phase::Proposals(_) => format!("DtProposal for step {}", self.step),
            Phase::Checkpoints(_) => format!("Checkpoint for step {}", self.step),
            Phase::Loads(k) => format!("InterfaceLoads for step {} iteration {k}", self.step),
            Phase::Trial(k) => format!("SolidState for step {} iteration {k}", self.step),
            Phase::Totals(_) => format!("ConservedTotals for step {}", self.step),
            Phase::Closing(..) => format!("DtProposal for step {}", self.step),
            Phase::Done => "nothing (the run is over)".into(),
        }
    }

    fn accepts(&self, from: NodeKind, msg: &Message) -> bool {
        let stamp = msg.stamp();
        match (&self.phase, msg) {
            (Phase::Greeting { hello, .. }, Message::Hello(_)) => !hello.contains(&from),
            (Phase::Greeting { hello, totals, .. }, Message::ConservedTotals(_)) => {
                hello.contains(&from) && !totals.contains(&from)
            }
            (Phase::Greeting { hello, surface, .. }, Message::SolidState(_)) => {
                // Forwarded to the fluid, which must have been welcomed first.
                from == NodeKind::Solid
                    && hello.contains(&from)
                    && hello.contains(&NodeKind::Fluid)
                    && !surface
            }
            (Phase::Proposals(_) | Phase::Closing(..), Message::DtProposal(_))
                if stamp.iteration == SUBSTEP_BOUND_ITERATION =>
            {
                stamp.step == self.step && from == NodeKind::Solid && self.wants_substep_bound()
            }
            (Phase::Proposals(got), Message::DtProposal(_)) => {
                stamp.step == self.step && !got.iter().any(|g| g.node == from)
            }
            (Phase::Closing(got, _), Message::DtProposal(_)) => {
                stamp.step == self.step && !got.contains(&from)
            }
            (Phase::Checkpoints(got), Message::Checkpoint(_)) => {
                stamp.step == self.step && !got.contains(&from)
            }
            (Phase::Loads(k), Message::InterfaceLoads(_)) => {
                from == NodeKind::Fluid
                    && stamp
                        == Stamp {
                            step: self.step,
                            iteration: *k,
                        }
            }
            (Phase::Trial(k), Message::SolidState(_)) => {
                from == NodeKind::Solid
                    && stamp
                        == Stamp {
                            step: self.step,
                            iteration: *k,
                        }
            }
            (Phase::Totals(got), Message::ConservedTotals(_)) => {
                stamp.step == self.step && !got.iter().any(|g| g.node == from)
            }
            _ => false,
        }
    }
}

/// A step proposal older than the step a restarted run resumes at.
pub(super) fn stale(msg: &Message, before: u64) -> bool {
    matches!(msg, Message::DtProposal(p) if p.stamp.step < before)
}
