//! The step itself: the next phase once one is complete ([`Coupler::advance`]), the agreed step
//! announced, each solid trial judged by criterion (22), the step's totals booked.

use protocol::wire::{
    Checkpoint, CheckpointRequest, ConservedTotals, Decision, FixedPointDecision, Message,
    NodeKind, Scheme, Shutdown, ShutdownReason, SolidState, Stamp, StepPlan,
};

use protocol::scene::{AUTO_SUBSTEP_FRACTION, MAX_SOLID_SUBSTEPS, SolidSubsteps};

use crate::dt::{self, Agreed, Proposal};
use crate::scheme::action::{Action, Finish, StepReport};
use crate::scheme::coupler::{Coupler, Phase, stale};
use crate::scheme::criterion::criterion_22;
use crate::scheme::error::CouplerError;
use crate::scheme::fluid_view;

/// The end of solid sub-step `j` (1 to `k`) of the step from `t` of `dt` that ends at `end`:
/// `t + j (dt/k)`, and `end` itself for the last (`links_broken.csv`; at K = 1 every link
/// breaks at the step's end, as the coupler books it).
pub fn substep_end(t: f64, dt: f64, end: f64, j: u32, k: u32) -> f64 {
    if j >= k {
        end
    } else {
        t + f64::from(j) * (dt / f64::from(k))
    }
}

impl Coupler {
    /// Moves to the next phase when the current one is complete.
    pub(super) fn advance(&mut self, actions: &mut Vec<Action>) -> Result<(), CouplerError> {
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
                Phase::Proposals(mut got) => {
                    let bound = self.substep_bound.take();
                    // A fixed K: the coupling step is bounded by K solid steps.
                    if let (Some(SolidSubsteps::Fixed(k)), Some(b)) = (self.cfg.substeps, &bound) {
                        got.push(Proposal {
                            node: b.node,
                            dt_max: b.dt_max * f64::from(k),
                            limiter: format!("{} (x{k} sub-steps)", b.limiter),
                        });
                    }
                    let agreed = dt::agree(
                        self.t,
                        &got,
                        self.cfg.dt_cap,
                        &self.cfg.outputs,
                        self.next_output,
                    )
                    .ok_or_else(|| CouplerError::NoStep {
                        t: self.t,
                        proposals: dt::describe(&got),
                    })?;
                    self.substeps = self.substeps_of(agreed.dt, bound.as_ref())?;
                    self.plan = Some(agreed);
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

    /// The solid's sub-steps for the agreed step `dt` with its sub-step bound, as the solid
    /// computes them (`SolidSubsteps::for_step` on the same two numbers).
    fn substeps_of(&self, dt: f64, bound: Option<&Proposal>) -> Result<u32, CouplerError> {
        let (Some(setting), Some(bound)) = (self.cfg.substeps, bound) else {
            return Ok(1);
        };
        setting
            .for_step(dt, bound.dt_max)
            .map_err(|needed| CouplerError::TooManySubsteps {
                step: self.step,
                t: self.t,
                dt,
                // Only "auto" runs out: its sub-steps stay within this part of the bound.
                bound: bound.dt_max * AUTO_SUBSTEP_FRACTION,
                limiter: format!("{}:{}", bound.node.name(), bound.limiter),
                needed,
                max: MAX_SOLID_SUBSTEPS,
            })
    }

    pub(super) fn start_step(&mut self, actions: &mut Vec<Action>) {
        let Agreed { dt, output, .. } = self.plan.clone().expect("a plan precedes the step");
        let iterated = self.cfg.scheme == Scheme::SemiImplicit;
        let first = self.acceleration.start_step(self.step, dt, iterated);
        let predicted = first.as_ref().is_some_and(|(_, p)| *p);
        let plan = StepPlan {
            stamp: Stamp::step(self.step),
            t: self.t,
            dt,
            scheme: self.cfg.scheme,
            output,
            predicted,
        };
        for node in self.cfg.nodes() {
            actions.push(Action::Send(node, Message::StepPlan(plan.clone())));
            if let (NodeKind::Fluid, Some((state, true))) = (node, &first) {
                actions.push(Action::Send(
                    NodeKind::Fluid,
                    Message::SolidState(fluid_view::for_fluid(state)),
                ));
            }
        }
        self.residuals.clear();
        self.input = first.map(|(state, _)| state);
        self.phase = if self.cfg.fluid && self.cfg.solid {
            Phase::Loads(0)
        } else {
            Phase::Totals(Vec::new())
        };
    }

    pub(super) fn on_trial(
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
        // NOTE: a trial whose wet surface is of another revision than its input's (links broke
        // at the end of the last step: the solid now splits the crack's vertices and flags its
        // faces wet) is not the fixed point, however close its particles: the loads were taken
        // on the input's surface, which lacks the crack's faces, and the fluid's solid flux on
        // the accepted one has them, so accepting it would break the energy exchange (seen in
        // `opening-fracture-3d` on 75³: 1.9e-4 J, 4e-4 of the exchange, in the step after the
        // break). One more iteration takes the loads on the new surface.
        let same_surface = input.surface.revision == trial.surface.revision
            && input.surface.wet == trial.surface.wet;
        let accept =
            self.cfg.scheme == Scheme::Explicit || (residual <= self.cfg.tolerance && same_surface);
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
        let next_input = if accept {
            trial.clone()
        } else {
            self.acceleration.next_input(input, &trial)
        };
        // NOTE: the fluid first: its loads (or its correction) are the next work on the step's
        // path, the solid only waits for them.
        actions.push(Action::Send(
            NodeKind::Fluid,
            Message::SolidState(fluid_view::for_fluid(&next_input)),
        ));
        actions.push(Action::Send(
            NodeKind::Fluid,
            Message::FixedPointDecision(decision.clone()),
        ));
        actions.push(Action::Send(
            NodeKind::Solid,
            Message::FixedPointDecision(decision),
        ));
        if accept {
            let input = self
                .input
                .take()
                .expect("an input state precedes every trial");
            self.acceleration.accept(&input, trial);
            self.phase = Phase::Totals(Vec::new());
        } else {
            self.input = Some(next_input);
            self.phase = Phase::Loads(k + 1);
        }
        Ok(())
    }

    pub(super) fn finish_step(
        &mut self,
        got: Vec<ConservedTotals>,
        actions: &mut Vec<Action>,
    ) -> Result<(), CouplerError> {
        let fluid = got.iter().find(|t| t.node == NodeKind::Fluid);
        let solid = got.iter().find(|t| t.node == NodeKind::Solid);
        let mut entry = self.ledger.update(self.step, fluid, solid);
        entry.solid_substeps = self.substeps;
        let t_end_of_step = self.planned_end().expect("a plan precedes the totals");
        let Agreed {
            dt,
            output,
            limiter,
        } = self.plan.take().expect("a plan precedes the totals");
        let iterations = self.residuals.len() as u32;
        let account = self.acceleration.take_account();
        self.iteration_total += u64::from(iterations);
        self.iteration_max = self.iteration_max.max(iterations);
        actions.push(Action::StepDone(StepReport {
            step: self.step,
            t: t_end_of_step,
            dt,
            limiter,
            iterations,
            residuals: std::mem::take(&mut self.residuals),
            relaxation: account.omegas,
            columns: account.columns,
            columns_dropped: account.columns_dropped,
            predicted: account.predicted,
            output,
            ledger: entry.clone(),
            solid_substeps: self.cfg.substeps.map(|_| self.substeps),
            vacuum_cells: fluid.map_or(0, |f| f.vacuum_cells),
            broken_links: solid.map_or_else(Vec::new, |s| {
                s.broken_pairs
                    .chunks_exact(2)
                    .enumerate()
                    .map(|(i, p)| {
                        // A solid that sends no sub-step (a double) breaks at the step's end.
                        let j = s.broken_substeps.get(i).copied().unwrap_or(self.substeps);
                        let t = substep_end(self.t, dt, t_end_of_step, j, self.substeps);
                        (t, [p[0], p[1]])
                    })
                    .collect()
            }),
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
