//! One message the current phase takes: the greeting, the proposals, checkpoints, loads, trial
//! states and totals, each checked before it is used.

use protocol::PROTOCOL_VERSION;
use protocol::wire::{Message, NodeKind, SolidState, Welcome};

use crate::dt::Proposal;
use crate::scheme::action::Action;
use crate::scheme::coupler::{Coupler, Phase};
use crate::scheme::error::CouplerError;
use crate::scheme::fluid_view;

impl Coupler {
    pub(super) fn handle(
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
                if state.changed_only {
                    return Err(CouplerError::Invalid {
                        from,
                        what: "the initial SolidState holds only changed particles".into(),
                    });
                }
                check_state(from, &state)?;
                if let Phase::Greeting { surface, .. } = &mut self.phase {
                    *surface = true;
                }
                actions.push(Action::Send(
                    NodeKind::Fluid,
                    Message::SolidState(fluid_view::for_fluid(&state)),
                ));
                self.acceleration.set_initial(state);
            }
            Message::DtProposal(p) => {
                if p.dt_max.is_nan() || p.dt_max <= 0.0 {
                    return Err(CouplerError::Invalid {
                        from,
                        what: format!("time step proposal {} ({})", p.dt_max, p.limiter),
                    });
                }
                if p.stamp.iteration == protocol::session::SUBSTEP_BOUND_ITERATION {
                    self.substep_bound = Some(Proposal::from_wire(from, p));
                    return self.advance(actions);
                }
                match &mut self.phase {
                    Phase::Proposals(got) => got.push(Proposal::from_wire(from, p)),
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
                let state = self.whole_trial(from, state)?;
                check_state(from, &state)?;
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
}

impl Coupler {
    /// The whole trial of a `SolidState` from the solid: a trial of changes only put back onto
    /// the step's first trial, which is kept when it arrives.
    fn whole_trial(
        &mut self,
        from: NodeKind,
        state: SolidState,
    ) -> Result<SolidState, CouplerError> {
        let stamp = state.stamp;
        if !state.changed_only {
            if stamp.iteration == 0 {
                self.first_trial = Some(state.clone());
            }
            return Ok(state);
        }
        let invalid = |what: String| CouplerError::Invalid {
            from,
            what: format!(
                "SolidState at step {} iteration {} (changed particles only): {what}",
                stamp.step, stamp.iteration
            ),
        };
        let first = self
            .first_trial
            .as_ref()
            .filter(|f| f.stamp.step == stamp.step && stamp.iteration > 0)
            .ok_or_else(|| invalid("the step's first trial did not come whole".into()))?;
        state.merged_onto(first).map_err(invalid)
    }
}

/// A solid state whose arrays fit its particle count and dimension, and whose wet surface refers
/// to vertices and particles it has.
fn check_state(from: NodeKind, s: &SolidState) -> Result<(), CouplerError> {
    let invalid = |what: String| CouplerError::Invalid { from, what };
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
        return Err(invalid(format!(
            "SolidState at step {} iteration {}: array lengths do not match {n} particles in {dim}-D",
            s.stamp.step, s.stamp.iteration
        )));
    }
    let n_vertices = s.surface.n_vertices() as u32;
    if let Some(bad) = s.surface.elements.iter().find(|&&v| v >= n_vertices) {
        return Err(invalid(format!(
            "wet surface element refers to vertex {bad} of {n_vertices}"
        )));
    }
    if let Some(bad) = s
        .surface
        .element_particle
        .iter()
        .find(|&&p| p as usize >= n)
    {
        return Err(invalid(format!(
            "wet surface element refers to particle {bad} of {n}"
        )));
    }
    Ok(())
}
