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

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use protocol::PROTOCOL_VERSION;
use protocol::scene::{Predictor, RecordLevel, Relaxation, Scene, SchemeName};
use protocol::wire::{
    Checkpoint, CheckpointRequest, ConservedTotals, Decision, FixedPointDecision, Message,
    NodeKind, Scheme, Shutdown, ShutdownReason, SolidState, Stamp, StepPlan, Welcome,
};

use crate::dt;
use crate::iqn::{IqnColumns, IqnIls};
use crate::ledger::{Ledger, LedgerEntry};

/// What the coupler needs from the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct CouplerConfig {
    /// A fluid node takes part.
    pub fluid: bool,
    /// A solid node takes part.
    pub solid: bool,
    /// Coupling scheme (explicit when one side is absent).
    pub scheme: Scheme,
    /// Fixed-point tolerance ε of criterion (22) \[m\].
    pub tolerance: f64,
    /// Fixed-point iterations allowed per step.
    pub max_iterations: u32,
    /// Relaxation of the solid trial states.
    pub relaxation: Relaxation,
    /// First relaxation factor of Aitken and IQN-ILS.
    pub relaxation_initial: f64,
    /// IQN-ILS: earlier steps whose columns are reused.
    pub iqn_reuse: u32,
    /// IQN-ILS: QR2 filter limit.
    pub iqn_filter: f64,
    /// Predictor of a semi-implicit step's first inputs.
    pub predictor: Predictor,
    /// Steps between checkpoints (0: none).
    pub checkpoint_every: u64,
    /// Scene cap on the step \[s\].
    pub dt_cap: Option<f64>,
    /// Output times, increasing, the last one is `t_end`.
    pub outputs: Vec<f64>,
    /// Optional cap on the number of steps.
    pub max_steps: Option<u64>,
    /// Hash of the resolved scene the nodes must have read.
    pub scene_hash: u64,
    /// Largest relative mass error accepted.
    pub mass_tolerance: f64,
    /// Largest relative energy error accepted, if checked.
    pub energy_tolerance: Option<f64>,
}

impl CouplerConfig {
    /// The coupler's view of a validated scene.
    pub fn from_scene(scene: &Scene) -> CouplerConfig {
        let both = scene.fluid.is_some() && scene.solid.is_some();
        CouplerConfig {
            fluid: scene.fluid.is_some(),
            solid: scene.solid.is_some(),
            scheme: match scene.run.scheme {
                SchemeName::SemiImplicit if both => Scheme::SemiImplicit,
                _ => Scheme::Explicit,
            },
            tolerance: scene.run.tolerance,
            max_iterations: scene.run.max_iterations,
            relaxation: scene.run.relaxation,
            relaxation_initial: scene.run.relaxation_initial,
            iqn_reuse: scene.run.iqn_reuse,
            iqn_filter: scene.run.iqn_filter,
            predictor: scene.run.predictor,
            checkpoint_every: match scene.run.record {
                RecordLevel::All => 1,
                _ => scene.run.checkpoint_every,
            },
            dt_cap: scene.run.dt_max,
            outputs: scene.output_times(),
            max_steps: scene.run.max_steps,
            scene_hash: scene.hash(),
            mass_tolerance: scene.run.mass_tolerance,
            energy_tolerance: scene.run.energy_tolerance,
        }
    }

    fn nodes(&self) -> Vec<NodeKind> {
        let mut nodes = Vec::new();
        if self.fluid {
            nodes.push(NodeKind::Fluid);
        }
        if self.solid {
            nodes.push(NodeKind::Solid);
        }
        nodes
    }
}

/// Something the driver must do.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Send this message to that node.
    Send(NodeKind, Message),
    /// A step is complete: record its diagnostics, update progress.
    StepDone(StepReport),
    /// A node's checkpoint arrived: record it.
    Checkpoint(Checkpoint),
    /// The coupler's own checkpoint (node `coupler`, bytes: a [`CouplerCheckpoint`]), taken
    /// when it asks the nodes for theirs: record it.
    CouplerCheckpoint(Checkpoint),
    /// The run is over (the shutdown messages were emitted just before).
    Finished(Finish),
}

/// How a run ended normally.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Finish {
    /// `t_end` reached.
    Completed,
    /// `run.max_steps` reached before `t_end`.
    MaxSteps,
}

/// What happened in one coupling step.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StepReport {
    /// Step index.
    pub step: u64,
    /// Time at the end of the step \[s\].
    pub t: f64,
    /// Step size \[s\].
    pub dt: f64,
    /// Who limited the step.
    pub limiter: String,
    /// Solid trials in this step (0 without a coupled solid).
    pub iterations: u32,
    /// Residual of criterion (22) after each trial.
    pub residuals: Vec<f64>,
    /// Relaxation factors used after each non-final trial (Aitken), empty otherwise.
    pub relaxation: Vec<f64>,
    /// IQN-ILS: columns the quasi-Newton update used after each non-final trial (0: the
    /// constant first relaxation or the predictor), empty otherwise.
    pub columns: Vec<u32>,
    /// IQN-ILS: columns the QR2 filter dropped in this step.
    pub columns_dropped: u32,
    /// The predictor gave the input of iteration 1.
    pub predicted: bool,
    /// Output index written at the end of the step.
    pub output: Option<u32>,
    /// The balance.
    pub ledger: LedgerEntry,
}

/// Why the coupler stops a run.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CouplerError {
    /// A node was refused at hello.
    #[error("{node} node refused at hello: {reason}")]
    Refused {
        /// The node.
        node: NodeKind,
        /// Why.
        reason: String,
    },
    /// A message that does not fit the handshake.
    #[error("{from} node sent {got} at step {} iteration {} while the coupler expected {expected}", stamp.step, stamp.iteration)]
    Unexpected {
        /// Sender.
        from: NodeKind,
        /// Kind of message.
        got: String,
        /// Its stamp.
        stamp: Stamp,
        /// What was expected.
        expected: String,
    },
    /// The fixed point did not converge.
    #[error(
        "fixed point not converged at step {step} (t = {t:e}) after {iterations} iterations (tolerance {tolerance:e}); residual history {residuals:?}"
    )]
    NotConverged {
        /// Step.
        step: u64,
        /// Time at the start of the step.
        t: f64,
        /// Iterations done.
        iterations: u32,
        /// Tolerance.
        tolerance: f64,
        /// Residual after each trial.
        residuals: Vec<f64>,
    },
    /// A node reported numerical trouble.
    #[error("{node} node failed at step {} iteration {}: {report}", stamp.step, stamp.iteration)]
    NodeFailure {
        /// The node.
        node: NodeKind,
        /// Where.
        stamp: Stamp,
        /// Its report.
        report: String,
    },
    /// A node ended the run.
    #[error("{node} node shut down: {reason}")]
    NodeShutdown {
        /// The node.
        node: NodeKind,
        /// Its reason.
        reason: String,
    },
    /// The ledger found a balance out of tolerance.
    #[error(
        "conservation ledger at step {step} (t = {t:e}): {what} = {value:e} exceeds the tolerance {tolerance:e}"
    )]
    Ledger {
        /// Step.
        step: u64,
        /// Time.
        t: f64,
        /// Which balance.
        what: String,
        /// Its value.
        value: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// No positive step could be agreed.
    #[error("no finite positive time step can be agreed at t = {t:e} (proposals {proposals})")]
    NoStep {
        /// Time.
        t: f64,
        /// The proposals.
        proposals: String,
    },
    /// A message whose content is inconsistent.
    #[error("{from} node sent an invalid {what}")]
    Invalid {
        /// Sender.
        from: NodeKind,
        /// What is wrong.
        what: String,
    },
}

#[derive(Clone, Debug)]
enum Phase {
    Greeting {
        hello: Vec<NodeKind>,
        totals: Vec<NodeKind>,
        surface: bool,
    },
    Proposals(Vec<(NodeKind, f64, String)>),
    Checkpoints(Vec<NodeKind>),
    Loads(u32),
    Trial(u32),
    Totals(Vec<ConservedTotals>),
    /// The last step is done: collect the proposals the nodes send after every step, so the
    /// record holds the same messages whatever the timing, then shut down.
    Closing(Vec<NodeKind>, Finish),
    Done,
}

/// What the coupler carries from one step to the next, taken when it asks the nodes for their
/// checkpoints (the step's plan agreed, the requests sent): the accepted states the predictors
/// extrapolate, IQN-ILS's secant columns, the ledger. Restored with the nodes' checkpoints, the
/// coupler iterates the next steps exactly as the original run did. Aitken's factor restarts
/// from `run.relaxation_initial` every step, so it carries nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CouplerCheckpoint {
    /// The step whose plan is agreed.
    pub step: u64,
    /// Its start time \[s\].
    pub t: f64,
    next_output: usize,
    plan: Option<(f64, Option<u32>, String)>,
    accepted: Option<SolidState>,
    previous: Option<(SolidState, f64)>,
    first_trial: Option<Vec<f64>>,
    correction: Option<Vec<f64>>,
    /// IQN-ILS's columns (absent with another relaxation).
    pub iqn: Option<IqnColumns>,
    ledger: Ledger,
    iteration_total: u64,
    iteration_max: u32,
    queue: Vec<(NodeKind, Message)>,
}

/// The coupler's state.
#[derive(Debug)]
pub struct Coupler {
    cfg: CouplerConfig,
    phase: Phase,
    queue: VecDeque<(NodeKind, Message)>,
    step: u64,
    t: f64,
    next_output: usize,
    plan: Option<(f64, Option<u32>, String)>,
    /// Accepted solid state at `t^n` (and relaxed input of the current iteration).
    accepted: Option<SolidState>,
    input: Option<SolidState>,
    residuals: Vec<f64>,
    omegas: Vec<f64>,
    aitken: Option<(Vec<f64>, f64)>,
    iqn: Option<IqnIls>,
    columns: Vec<u32>,
    predicted: bool,
    /// Accepted solid state at `t^{n−1}` and the step that led from it to `t^n` (predictor).
    previous: Option<(SolidState, f64)>,
    /// This step's first trial, flattened (predictor).
    first_trial: Option<Vec<f64>>,
    /// Last step's accepted state minus its first trial, flattened (predictor).
    correction: Option<Vec<f64>>,
    ledger: Ledger,
    initial_totals: Vec<ConservedTotals>,
    iteration_total: u64,
    iteration_max: u32,
    /// A restart waiting for the greeting to end.
    resume: Option<Resume>,
    /// Proposals for steps before this one are dropped (a restart's, from before the restore).
    stale_before: u64,
}

/// What a restarted run resumes from: the coupler's checkpoint and the nodes' of the same step.
#[derive(Clone, Debug)]
pub struct Resume {
    /// The coupler's.
    pub coupler: CouplerCheckpoint,
    /// One per node of the scene, fluid first.
    pub nodes: Vec<Checkpoint>,
}

impl Coupler {
    /// A coupler waiting for the nodes' hellos.
    pub fn new(cfg: CouplerConfig) -> Coupler {
        let iqn = (cfg.relaxation == Relaxation::IqnIls)
            .then(|| IqnIls::new(cfg.iqn_reuse, cfg.iqn_filter, cfg.relaxation_initial));
        Coupler {
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
            accepted: None,
            input: None,
            residuals: Vec::new(),
            omegas: Vec::new(),
            aitken: None,
            iqn,
            columns: Vec::new(),
            predicted: false,
            previous: None,
            first_trial: None,
            correction: None,
            ledger: Ledger::default(),
            initial_totals: Vec::new(),
            iteration_total: 0,
            iteration_max: 0,
            resume: None,
            stale_before: 0,
        }
    }

    /// The coupler's state between steps (see [`CouplerCheckpoint`]).
    pub fn checkpoint(&self) -> CouplerCheckpoint {
        CouplerCheckpoint {
            step: self.step,
            t: self.t,
            next_output: self.next_output,
            plan: self.plan.clone(),
            accepted: self.accepted.clone(),
            previous: self.previous.clone(),
            first_trial: self.first_trial.clone(),
            correction: self.correction.clone(),
            iqn: self.iqn.as_ref().map(IqnIls::columns),
            ledger: self.ledger.clone(),
            iteration_total: self.iteration_total,
            iteration_max: self.iteration_max,
            queue: self.queue.iter().cloned().collect(),
        }
    }

    /// A coupler resumed from `checkpoint`, waiting for the nodes' checkpoints of its step as
    /// the original was when it took it.
    pub fn restore(cfg: CouplerConfig, checkpoint: &CouplerCheckpoint) -> Result<Coupler, String> {
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
    pub fn resuming(cfg: CouplerConfig, resume: Resume) -> Result<Coupler, String> {
        // Checked now rather than after the greeting.
        Coupler::new(cfg.clone()).apply(&resume.coupler)?;
        let mut c = Coupler::new(cfg);
        let nodes: Vec<NodeKind> = resume.nodes.iter().map(|n| n.node).collect();
        if nodes != c.cfg.nodes() {
            return Err(format!(
                "the restart has checkpoints of {nodes:?}, the scene runs {:?}",
                c.cfg.nodes()
            ));
        }
        c.resume = Some(resume);
        Ok(c)
    }

    /// Takes the state of a checkpoint (not the plan, the queue or the phase).
    fn apply(&mut self, checkpoint: &CouplerCheckpoint) -> Result<(), String> {
        match (self.iqn.as_mut(), &checkpoint.iqn) {
            (Some(iqn), Some(columns)) => iqn.restore(columns),
            (None, None) => {}
            _ => {
                return Err(
                    "the checkpoint's relaxation is not the scene's (IQN-ILS columns present in one only)"
                        .into(),
                );
            }
        }
        let cp = checkpoint.clone();
        self.step = cp.step;
        self.t = cp.t;
        self.next_output = cp.next_output;
        self.accepted = cp.accepted;
        self.previous = cp.previous;
        self.first_trial = cp.first_trial;
        self.correction = cp.correction;
        self.ledger = cp.ledger;
        self.iteration_total = cp.iteration_total;
        self.iteration_max = cp.iteration_max;
        Ok(())
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

    /// The nodes the coupler is waiting for now (for deadline messages).
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
            Phase::Proposals(got) => self.missing(got.iter().map(|g| g.0)),
            Phase::Checkpoints(got) => self.missing(got.iter().copied()),
            Phase::Loads(_) => vec![NodeKind::Fluid],
            Phase::Trial(_) => vec![NodeKind::Solid],
            Phase::Totals(got) => self.missing(got.iter().map(|g| g.node)),
            Phase::Closing(got, _) => self.missing(got.iter().copied()),
            Phase::Done => Vec::new(),
        }
    }

    /// Whether the run is over.
    pub fn is_done(&self) -> bool {
        matches!(self.phase, Phase::Done)
    }

    fn missing(&self, got: impl Iterator<Item = NodeKind> + Clone) -> Vec<NodeKind> {
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

    fn expected(&self) -> String {
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
            (Phase::Proposals(got), Message::DtProposal(_)) => {
                stamp.step == self.step && !got.iter().any(|g| g.0 == from)
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

    fn handle(
        &mut self,
        from: NodeKind,
        msg: Message,
        actions: &mut Vec<Action>,
    ) -> Result<(), CouplerError> {
        match msg {
            Message::Hello(hello) => {
                let refusal = if hello.protocol_version != PROTOCOL_VERSION {
                    Some(format!(
                        "protocol version mismatch: coupler speaks version {PROTOCOL_VERSION}, {from} node speaks version {}",
                        hello.protocol_version
                    ))
                } else if hello.node != from {
                    Some(format!("it says it is the {} node", hello.node))
                } else if hello.scene_hash != self.cfg.scene_hash {
                    Some(format!(
                        "scene hash {:016x} differs from the coupler's {:016x}: the nodes read different scenes",
                        hello.scene_hash, self.cfg.scene_hash
                    ))
                } else if !self.cfg.nodes().contains(&from) {
                    Some(format!("the scene has no [{from}] section"))
                } else {
                    None
                };
                actions.push(Action::Send(
                    from,
                    Message::Welcome(Welcome {
                        accepted: refusal.is_none(),
                        reason: refusal.clone().unwrap_or_default(),
                    }),
                ));
                if let Some(reason) = refusal {
                    return Err(CouplerError::Refused { node: from, reason });
                }
                if let Phase::Greeting { hello, .. } = &mut self.phase {
                    hello.push(from);
                }
            }
            Message::ConservedTotals(totals) if matches!(self.phase, Phase::Greeting { .. }) => {
                if totals.node != from {
                    return Err(CouplerError::Invalid {
                        from,
                        what: format!("ConservedTotals claiming to come from {}", totals.node),
                    });
                }
                if let Phase::Greeting { totals: got, .. } = &mut self.phase {
                    got.push(from);
                }
                self.initial_totals.push(totals);
            }
            Message::SolidState(state) if matches!(self.phase, Phase::Greeting { .. }) => {
                check_state(&state).map_err(|what| CouplerError::Invalid { from, what })?;
                if let Phase::Greeting { surface, .. } = &mut self.phase {
                    *surface = true;
                }
                actions.push(Action::Send(
                    NodeKind::Fluid,
                    Message::SolidState(state.clone()),
                ));
                self.accepted = Some(state);
            }
            Message::DtProposal(p) => {
                if p.dt_max.is_nan() || p.dt_max <= 0.0 {
                    return Err(CouplerError::Invalid {
                        from,
                        what: format!("time step proposal {} ({})", p.dt_max, p.limiter),
                    });
                }
                match &mut self.phase {
                    Phase::Proposals(got) => got.push((from, p.dt_max, p.limiter)),
                    Phase::Closing(got, _) => got.push(from),
                    _ => {}
                }
            }
            Message::Checkpoint(c) => {
                if let Phase::Checkpoints(got) = &mut self.phase {
                    got.push(from);
                }
                actions.push(Action::Checkpoint(c));
            }
            Message::InterfaceLoads(loads) => {
                actions.push(Action::Send(
                    NodeKind::Solid,
                    Message::InterfaceLoads(loads),
                ));
                if let Phase::Loads(k) = self.phase {
                    self.phase = Phase::Trial(k);
                }
            }
            Message::SolidState(state) => {
                check_state(&state).map_err(|what| CouplerError::Invalid { from, what })?;
                self.on_trial(state, actions)?;
            }
            Message::ConservedTotals(totals) => {
                if totals.node != from {
                    return Err(CouplerError::Invalid {
                        from,
                        what: format!("ConservedTotals claiming to come from {}", totals.node),
                    });
                }
                if let Phase::Totals(got) = &mut self.phase {
                    got.push(totals);
                }
            }
            other => {
                return Err(CouplerError::Unexpected {
                    from,
                    got: format!("{:?}", other.kind()),
                    stamp: other.stamp(),
                    expected: self.expected(),
                });
            }
        }
        self.advance(actions)
    }

    /// Moves to the next phase when the current one is complete.
    fn advance(&mut self, actions: &mut Vec<Action>) -> Result<(), CouplerError> {
        loop {
            let complete = self.waiting_for().is_empty();
            if !complete {
                return Ok(());
            }
            match std::mem::replace(&mut self.phase, Phase::Done) {
                Phase::Greeting { .. } => {
                    let initial = std::mem::take(&mut self.initial_totals);
                    if let Some(resume) = self.resume.take() {
                        for c in resume.nodes {
                            actions.push(Action::Send(c.node, Message::Checkpoint(c)));
                        }
                        self.apply(&resume.coupler)
                            .expect("checked by Coupler::resuming");
                        self.stale_before = self.step;
                        self.queue.retain(|(_, m)| !stale(m, self.stale_before));
                    } else {
                        let fluid = initial.iter().find(|t| t.node == NodeKind::Fluid);
                        let solid = initial.iter().find(|t| t.node == NodeKind::Solid);
                        self.ledger.update(0, fluid, solid);
                    }
                    self.phase = Phase::Proposals(Vec::new());
                }
                Phase::Proposals(got) => {
                    let proposals: Vec<(&str, f64, &str)> = got
                        .iter()
                        .map(|(n, dt, why)| (n.name(), *dt, why.as_str()))
                        .collect();
                    let agreed = dt::agree(
                        self.t,
                        &proposals,
                        self.cfg.dt_cap,
                        &self.cfg.outputs,
                        self.next_output,
                    )
                    .ok_or_else(|| CouplerError::NoStep {
                        t: self.t,
                        proposals: format!("{proposals:?}"),
                    })?;
                    self.plan = Some((agreed.dt, agreed.output, agreed.limiter));
                    let every = self.cfg.checkpoint_every;
                    if every > 0 && self.step > 0 && self.step.is_multiple_of(every) {
                        for node in self.cfg.nodes() {
                            actions.push(Action::Send(
                                node,
                                Message::CheckpointRequest(CheckpointRequest {
                                    stamp: Stamp::step(self.step),
                                }),
                            ));
                        }
                        self.phase = Phase::Checkpoints(Vec::new());
                        actions.push(Action::CouplerCheckpoint(Checkpoint {
                            stamp: Stamp::step(self.step),
                            node: NodeKind::Coupler,
                            bytes: protocol::codec::encode_blob(&self.checkpoint()),
                        }));
                    } else {
                        self.start_step(actions);
                    }
                }
                Phase::Checkpoints(_) => self.start_step(actions),
                Phase::Closing(_, finish) => {
                    for node in self.cfg.nodes() {
                        actions.push(Action::Send(
                            node,
                            Message::Shutdown(Shutdown {
                                stamp: Stamp::step(self.step),
                                reason: ShutdownReason::Completed,
                            }),
                        ));
                    }
                    actions.push(Action::Finished(finish));
                    self.phase = Phase::Done;
                }
                Phase::Totals(got) => self.finish_step(got, actions)?,
                other @ (Phase::Loads(_) | Phase::Trial(_) | Phase::Done) => {
                    self.phase = other;
                    return Ok(());
                }
            }
        }
    }

    fn start_step(&mut self, actions: &mut Vec<Action>) {
        let (dt, output, _) = self.plan.clone().expect("a plan precedes the step");
        // The linear predictor replaces `F^n` as iteration 0's input of a semi-implicit step
        // once two accepted states are known.
        let predicted = match (self.cfg.scheme, self.cfg.predictor, &self.accepted) {
            (Scheme::SemiImplicit, Predictor::Linear, Some(accepted)) => {
                self.predict(flatten(accepted).len()).map(|p| {
                    let mut s = unflatten(accepted, &p);
                    s.stamp = Stamp::step(self.step);
                    s
                })
            }
            _ => None,
        };
        let plan = StepPlan {
            stamp: Stamp::step(self.step),
            t: self.t,
            dt,
            scheme: self.cfg.scheme,
            output,
            predicted: predicted.is_some(),
        };
        for node in self.cfg.nodes() {
            actions.push(Action::Send(node, Message::StepPlan(plan.clone())));
        }
        if let Some(p) = &predicted {
            actions.push(Action::Send(
                NodeKind::Fluid,
                Message::SolidState(p.clone()),
            ));
        }
        self.residuals.clear();
        self.omegas.clear();
        self.aitken = None;
        self.columns.clear();
        self.predicted = predicted.is_some();
        if let Some(iqn) = self.iqn.as_mut() {
            iqn.start_step();
        }
        self.input = predicted.or_else(|| self.accepted.clone());
        self.phase = if self.cfg.fluid && self.cfg.solid {
            Phase::Loads(0)
        } else {
            Phase::Totals(Vec::new())
        };
    }

    fn on_trial(
        &mut self,
        trial: SolidState,
        actions: &mut Vec<Action>,
    ) -> Result<(), CouplerError> {
        let k = trial.stamp.iteration;
        let input = self
            .input
            .as_ref()
            .expect("an input state precedes every trial");
        if input.position.len() != trial.position.len()
            || input.orientation.len() != trial.orientation.len()
            || input.surface.vertices.len() != trial.surface.vertices.len()
        {
            return Err(CouplerError::Invalid {
                from: NodeKind::Solid,
                what: format!(
                    "SolidState at step {} iteration {k}: {} particles and {} surface values, the previous state had {} and {}",
                    self.step,
                    trial.n_particles(),
                    trial.surface.vertices.len(),
                    input.n_particles(),
                    input.surface.vertices.len()
                ),
            });
        }
        let residual = criterion_22(input, &trial);
        self.residuals.push(residual);
        let accept = self.cfg.scheme == Scheme::Explicit || residual <= self.cfg.tolerance;
        let decision = FixedPointDecision {
            stamp: trial.stamp,
            residual,
            decision: if accept {
                Decision::Accept
            } else {
                Decision::Iterate
            },
        };
        if !accept && k + 1 >= self.cfg.max_iterations {
            return Err(CouplerError::NotConverged {
                step: self.step,
                t: self.t,
                iterations: k + 1,
                tolerance: self.cfg.tolerance,
                residuals: self.residuals.clone(),
            });
        }
        actions.push(Action::Send(
            NodeKind::Solid,
            Message::FixedPointDecision(decision.clone()),
        ));
        let next_input = if accept {
            trial.clone()
        } else {
            self.relax(&trial)
        };
        actions.push(Action::Send(
            NodeKind::Fluid,
            Message::SolidState(next_input.clone()),
        ));
        actions.push(Action::Send(
            NodeKind::Fluid,
            Message::FixedPointDecision(decision),
        ));
        if accept {
            let dt = self.plan.as_ref().map_or(0.0, |p| p.0);
            if let (Some(iqn), Some(input)) = (self.iqn.as_mut(), self.input.as_ref()) {
                // The accepted trial's secant column is as good as any: keep it for the next
                // steps, which would otherwise reuse nothing from a step accepted at once.
                iqn.observe(&unknowns_residual(input, &trial, dt), &flatten(&trial));
            }
            self.previous = self.accepted.take().map(|a| (a, dt));
            let acc = flatten(&trial);
            self.correction = Some(match self.first_trial.take() {
                Some(f) if f.len() == acc.len() => acc.iter().zip(&f).map(|(a, b)| a - b).collect(),
                _ => vec![0.0; acc.len()],
            });
            self.accepted = Some(trial);
            self.input = None;
            self.phase = Phase::Totals(Vec::new());
        } else {
            self.input = Some(next_input);
            self.phase = Phase::Loads(k + 1);
        }
        Ok(())
    }

    /// The input of the next iteration: the trial itself, its relaxation (Aitken, IQN-ILS), or
    /// after iteration 0 the `correction` predictor's (this trial plus the last step's converged
    /// correction). The `linear` predictor acts before iteration 0 ([`Coupler::start_step`]).
    fn relax(&mut self, trial: &SolidState) -> SolidState {
        let input = self
            .input
            .as_ref()
            .expect("an input state precedes every trial");
        let x = flatten(input);
        let gx = flatten(trial);
        if trial.stamp.iteration == 0 {
            self.first_trial = Some(gx.clone());
        }
        let predicted = match self.cfg.predictor {
            _ if trial.stamp.iteration > 0 => None,
            Predictor::None | Predictor::Linear => None,
            Predictor::Correction => self
                .correction
                .as_ref()
                .filter(|c| c.len() == gx.len())
                .map(|c| gx.iter().zip(c).map(|(g, c)| g + c).collect::<Vec<f64>>()),
        };
        self.predicted |= predicted.is_some();
        match self.cfg.relaxation {
            Relaxation::None => match predicted {
                Some(p) => unflatten(trial, &p),
                None => trial.clone(),
            },
            Relaxation::Aitken => {
                if let Some(p) = predicted {
                    // NOTE: Aitken's recursion assumes x_k − x_{k−1} = ω_{k−1} r_{k−1}; a
                    // predicted input breaks it, so the recursion restarts after it.
                    self.aitken = None;
                    return unflatten(trial, &p);
                }
                let r: Vec<f64> = gx.iter().zip(&x).map(|(g, x)| g - x).collect();
                // NOTE: Aitken's Δ² (Küttler & Wall 2008): ω_k = −ω_{k−1} r_{k−1}·(r_k − r_{k−1})
                // / |r_k − r_{k−1}|², starting from ω_0 = `run.relaxation_initial` and kept in
                // [0.05, 2] so a stagnating pair of residuals cannot stall or throw the iteration.
                let omega = match &self.aitken {
                    None => self.cfg.relaxation_initial,
                    Some((r_prev, w_prev)) => {
                        let (mut num, mut den) = (0.0, 0.0);
                        for (rk, rp) in r.iter().zip(r_prev) {
                            let d = rk - rp;
                            num += rp * d;
                            den += d * d;
                        }
                        if den > 0.0 {
                            (-w_prev * num / den).clamp(0.05, 2.0)
                        } else {
                            *w_prev
                        }
                    }
                };
                self.omegas.push(omega);
                let relaxed: Vec<f64> = x.iter().zip(&r).map(|(x, r)| x + omega * r).collect();
                self.aitken = Some((r, omega));
                unflatten(trial, &relaxed)
            }
            Relaxation::IqnIls => {
                let dt = self.plan.as_ref().map_or(0.0, |p| p.0);
                let r = unknowns_residual(input, trial, dt);
                let iqn = self.iqn.as_mut().expect("IQN-ILS has its model");
                if let Some(p) = predicted {
                    iqn.observe(&r, &gx);
                    self.columns.push(0);
                    return unflatten(trial, &p);
                }
                let (next, used) = iqn.next(&r, &x, &gx);
                self.columns.push(used);
                unflatten(trial, &next)
            }
        }
    }

    /// Linear extrapolation `X^n + dt^n / dt^{n−1} (X^n − X^{n−1})` of the accepted states,
    /// flattened, when two are known with the shapes of this trial.
    fn predict(&self, len: usize) -> Option<Vec<f64>> {
        let (prev, dt_prev) = self.previous.as_ref()?;
        let now = flatten(self.accepted.as_ref()?);
        let prev = flatten(prev);
        let dt = self.plan.as_ref()?.0;
        if now.len() != len || prev.len() != len || !dt_prev.is_finite() || *dt_prev <= 0.0 {
            return None;
        }
        let ratio = dt / dt_prev;
        Some(
            now.iter()
                .zip(&prev)
                .map(|(a, b)| a + ratio * (a - b))
                .collect(),
        )
    }

    fn finish_step(
        &mut self,
        got: Vec<ConservedTotals>,
        actions: &mut Vec<Action>,
    ) -> Result<(), CouplerError> {
        let fluid = got.iter().find(|t| t.node == NodeKind::Fluid);
        let solid = got.iter().find(|t| t.node == NodeKind::Solid);
        let entry = self.ledger.update(self.step + 1, fluid, solid);
        let (dt, output, limiter) = self.plan.take().expect("a plan precedes the totals");
        let t_end_of_step = match output {
            Some(k) => self.cfg.outputs[k as usize],
            None => self.t + dt,
        };
        let iterations = self.residuals.len() as u32;
        self.iteration_total += u64::from(iterations);
        self.iteration_max = self.iteration_max.max(iterations);
        actions.push(Action::StepDone(StepReport {
            step: self.step,
            t: t_end_of_step,
            dt,
            limiter,
            iterations,
            residuals: std::mem::take(&mut self.residuals),
            relaxation: std::mem::take(&mut self.omegas),
            columns: std::mem::take(&mut self.columns),
            columns_dropped: self.iqn.as_ref().map_or(0, IqnIls::dropped),
            predicted: self.predicted,
            output,
            ledger: entry.clone(),
        }));
        if entry.mass_rel_err > self.cfg.mass_tolerance {
            return Err(CouplerError::Ledger {
                step: self.step,
                t: t_end_of_step,
                what: "relative mass error".into(),
                value: entry.mass_rel_err,
                tolerance: self.cfg.mass_tolerance,
            });
        }
        if let Some(tol) = self.cfg.energy_tolerance
            && entry.energy_rel_err > tol
        {
            return Err(CouplerError::Ledger {
                step: self.step,
                t: t_end_of_step,
                what: "relative energy error".into(),
                value: entry.energy_rel_err,
                tolerance: tol,
            });
        }
        self.t = t_end_of_step;
        self.step += 1;
        if output.is_some() {
            self.next_output += 1;
        }
        let finish = if self.next_output >= self.cfg.outputs.len() {
            Some(Finish::Completed)
        } else if self.cfg.max_steps.is_some_and(|m| self.step >= m) {
            Some(Finish::MaxSteps)
        } else {
            None
        };
        if let Some(finish) = finish {
            self.phase = Phase::Closing(Vec::new(), finish);
        } else {
            self.phase = Phase::Proposals(Vec::new());
        }
        Ok(())
    }
}

/// A step proposal older than the step a restarted run resumes at.
fn stale(msg: &Message, before: u64) -> bool {
    matches!(msg, Message::DtProposal(p) if p.stamp.step < before)
}

fn check_state(s: &SolidState) -> Result<(), String> {
    let n = s.n_particles();
    let dim = s.dim;
    let rot = protocol::wire::n_rot(dim);
    let ori = protocol::wire::n_orientation(dim);
    let ok = (dim == 2 || dim == 3)
        && s.position.len() == n * dim as usize
        && s.orientation.len() == n * ori
        && s.velocity.len() == n * dim as usize
        && s.angular_velocity.len() == n * rot
        && s.diameter.len() == n
        && s.surface.dim == dim
        && s.surface.vertices.len().is_multiple_of(dim as usize)
        && s.surface.elements.len() == s.surface.n_elements() * dim as usize
        && s.surface.wet.len() == s.surface.n_elements();
    if !ok {
        return Err(format!(
            "SolidState at step {} iteration {}: array lengths do not match {n} particles in {dim}-D",
            s.stamp.step, s.stamp.iteration
        ));
    }
    let n_vertices = s.surface.n_vertices() as u32;
    if let Some(bad) = s.surface.elements.iter().find(|&&v| v >= n_vertices) {
        return Err(format!(
            "wet surface element refers to vertex {bad} of {n_vertices}"
        ));
    }
    if let Some(bad) = s
        .surface
        .element_particle
        .iter()
        .find(|&&p| p as usize >= n)
    {
        return Err(format!(
            "wet surface element refers to particle {bad} of {n}"
        ));
    }
    Ok(())
}

/// Criterion (22) of paper 003: `max_I |ΔX_I| + max_I h_I ‖ΔQ_I‖` between two solid states, with
/// `‖·‖` the Frobenius norm of the difference of the rotation matrices.
pub fn criterion_22(a: &SolidState, b: &SolidState) -> f64 {
    let dim = a.dim as usize;
    let mut max_dx: f64 = 0.0;
    let mut max_dq: f64 = 0.0;
    for i in 0..a.n_particles() {
        let dx: f64 = (0..dim)
            .map(|d| (a.position[i * dim + d] - b.position[i * dim + d]).powi(2))
            .sum::<f64>()
            .sqrt();
        let dq = if dim == 2 {
            // ‖R(θa) − R(θb)‖_F = 2√2 |sin((θa − θb)/2)|.
            2.0 * std::f64::consts::SQRT_2
                * ((a.orientation[i] - b.orientation[i]) / 2.0).sin().abs()
        } else {
            let qa = &a.orientation[4 * i..4 * i + 4];
            let qb = &b.orientation[4 * i..4 * i + 4];
            let dot: f64 = qa.iter().zip(qb).map(|(x, y)| x * y).sum();
            let sign = if dot < 0.0 { -1.0 } else { 1.0 };
            // NOTE: |qa − qb| = 2 sin(θ/4) for unit quaternions, so sin(θ/2) = |qa − qb|
            // √(1 − |qa − qb|²/4) keeps full precision for tiny rotations, where 1 − dot² would
            // cancel; ‖Ra − Rb‖_F = 2√2 sin(θ/2).
            let d: f64 = qa
                .iter()
                .zip(qb)
                .map(|(x, y)| (x - sign * y).powi(2))
                .sum::<f64>()
                .sqrt();
            let sin_half = d * (1.0 - d * d / 4.0).max(0.0).sqrt();
            2.0 * std::f64::consts::SQRT_2 * sin_half
        };
        max_dx = max_dx.max(dx);
        max_dq = max_dq.max(a.diameter[i].max(b.diameter[i]) * dq);
    }
    max_dx + max_dq
}

/// The unknowns of IQN-ILS, as a residual `trial − input`: the positions, and the orientations
/// weighted by the particle diameter as in criterion (22) (2-D: angle; 3-D: quaternion, with the
/// sign that brings the trial nearest the input).
fn unknowns_residual(input: &SolidState, trial: &SolidState, dt: f64) -> Vec<f64> {
    let mut r: Vec<f64> = trial
        .position
        .iter()
        .zip(&input.position)
        .map(|(t, x)| t - x)
        .collect();
    let ori = trial.orientation.len() / trial.n_particles().max(1);
    for i in 0..trial.n_particles() {
        let h = trial.diameter[i].max(input.diameter[i]);
        let a = &input.orientation[ori * i..ori * (i + 1)];
        let b = &trial.orientation[ori * i..ori * (i + 1)];
        let dot: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
        let sign = if ori == 4 && dot < 0.0 { -1.0 } else { 1.0 };
        r.extend(a.iter().zip(b).map(|(x, y)| h * (sign * y - x)));
    }
    // Velocities times dt: a fluid whose loads read the velocity (an impedance) sees them.
    r.extend(
        trial
            .velocity
            .iter()
            .zip(&input.velocity)
            .map(|(t, x)| dt * (t - x)),
    );
    let rot = trial.angular_velocity.len() / trial.n_particles().max(1);
    for i in 0..trial.n_particles() {
        let h = trial.diameter[i].max(input.diameter[i]);
        let a = &input.angular_velocity[rot * i..rot * (i + 1)];
        let b = &trial.angular_velocity[rot * i..rot * (i + 1)];
        r.extend(a.iter().zip(b).map(|(x, y)| h * dt * (y - x)));
    }
    r
}

fn flatten(s: &SolidState) -> Vec<f64> {
    let mut v = Vec::with_capacity(
        s.position.len()
            + s.orientation.len()
            + s.velocity.len()
            + s.angular_velocity.len()
            + s.surface.vertices.len(),
    );
    v.extend_from_slice(&s.position);
    v.extend_from_slice(&s.orientation);
    v.extend_from_slice(&s.velocity);
    v.extend_from_slice(&s.angular_velocity);
    v.extend_from_slice(&s.surface.vertices);
    v
}

fn unflatten(template: &SolidState, v: &[f64]) -> SolidState {
    let mut s = template.clone();
    let mut at = 0;
    for field in [
        &mut s.position,
        &mut s.orientation,
        &mut s.velocity,
        &mut s.angular_velocity,
        &mut s.surface.vertices,
    ] {
        let n = field.len();
        field.copy_from_slice(&v[at..at + n]);
        at += n;
    }
    if s.dim == 3 {
        for q in s.orientation.chunks_exact_mut(4) {
            let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            q.iter_mut().for_each(|x| *x /= norm);
        }
    }
    s
}

#[cfg(test)]
mod tests;
