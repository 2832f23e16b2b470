//! The handshake without shared memory: fake nodes answer the coupler's actions.

use std::collections::VecDeque;

use protocol::PROTOCOL_VERSION;
use protocol::scene::{Predictor, Relaxation};
use protocol::wire::{
    ConservedTotals, Decision, DtProposal, Hello, InterfaceLoads, Message, NodeKind, Scheme,
    SolidState, Stamp, WetSurface,
};

use super::*;

/// A 2-D single-particle world: the fluid's load is `-c x_surface`, the solid's trial position is
/// `a + d n + b F` at step `n`, so the fixed point is `x*_n = (a + d n) / (1 + b c)` and plain
/// iteration contracts by `b c`.
struct World {
    a: f64,
    /// Drift `d` of the solid's answer per step.
    drift: f64,
    b: f64,
    c: f64,
    fluid_dt: f64,
    solid_dt: f64,
    surface_x: f64,
    /// From this step on the solid's answers carry wet surface revision 1 (links broke).
    revision_from: Option<u64>,
    /// With `run.solid_substeps`: the solid's stable step, its second proposal (iteration 1).
    substep_bound: Option<f64>,
    /// A second particle that never moves (inside the solid), in every state.
    interior: bool,
    /// `Some(false)`: the solid sends its trials after a step's first as their changes
    /// (`SolidState::changes_from`); `Some(true)`: every trial, the first as well.
    changes: Option<bool>,
    /// The solid's whole first trial of the current step.
    first: Option<SolidState>,
    sent: Vec<(NodeKind, Message)>,
}

fn cfg(scheme: Scheme, relaxation: Relaxation, outputs: Vec<f64>) -> CouplerConfig {
    CouplerConfig {
        fluid: true,
        solid: true,
        scheme,
        tolerance: 1e-12,
        max_iterations: 50,
        relaxation,
        relaxation_initial: 0.5,
        iqn_reuse: 4,
        iqn_filter: 1e-2,
        predictor: Predictor::None,
        checkpoint_every: 0,
        dt_cap: None,
        outputs,
        max_steps: None,
        scene_hash: 7,
        mass_tolerance: 1e-9,
        energy_tolerance: None,
        substeps: None,
    }
}

fn hello(node: NodeKind) -> Message {
    Message::Hello(Hello {
        node,
        protocol_version: PROTOCOL_VERSION,
        scene_hash: 7,
        implementation: "test".into(),
        capabilities: vec![],
    })
}

fn totals(node: NodeKind, step: u64, mass: f64) -> Message {
    Message::ConservedTotals(ConservedTotals {
        stamp: Stamp::step(step),
        node,
        t: 0.0,
        mass,
        momentum: vec![0.0, 0.0],
        energy: 1.0,
        dissipated: 0.0,
        interface_work: 0.0,
        interface_impulse: vec![0.0, 0.0],
        boundary_mass_out: 0.0,
        boundary_energy_out: 0.0,
        links_broken: 0,
        broken_pairs: Vec::new(),
        broken_substeps: Vec::new(),
        swept_mass: 0.0,
        vacuum_cells: 0,
        kinetic: 0.0,
        energy_scale: 1.0,
    })
}

fn state(stamp: Stamp, x: f64) -> SolidState {
    SolidState {
        stamp,
        dim: 2,
        position: vec![x, 0.0],
        orientation: vec![0.0],
        velocity: vec![0.0, 0.0],
        angular_velocity: vec![0.0],
        diameter: vec![1.0],
        surface: WetSurface {
            revision: 0,
            dim: 2,
            vertices: vec![x, 0.0, x + 1.0, 0.0],
            elements: vec![0, 1],
            element_particle: vec![0],
            wet: vec![true],
        },
        particles: Vec::new(),
        changed_only: false,
    }
}

fn proposal(step: u64, dt: f64) -> Message {
    Message::DtProposal(DtProposal {
        stamp: Stamp::step(step),
        dt_max: dt,
        limiter: "test".into(),
    })
}

impl World {
    fn new(a: f64, b: f64, c: f64) -> World {
        World {
            a,
            drift: 0.0,
            b,
            c,
            fluid_dt: 0.1,
            solid_dt: 0.3,
            surface_x: 0.0,
            revision_from: None,
            substep_bound: None,
            interior: false,
            changes: None,
            first: None,
            sent: Vec::new(),
        }
    }

    /// `s` with the interior particle at (5, 0) when the world has one.
    fn with_interior(&self, mut s: SolidState) -> SolidState {
        if self.interior {
            s.position.extend([5.0, 0.0]);
            s.orientation.push(0.25);
            s.velocity.extend([0.0, 0.0]);
            s.angular_velocity.push(0.0);
            s.diameter.push(1.0);
        }
        s
    }

    /// A trial as the solid sends it (see [`World::changes`]).
    fn as_sent(&mut self, trial: SolidState) -> SolidState {
        let Some(always) = self.changes else {
            return trial;
        };
        if trial.stamp.iteration == 0 {
            self.first = Some(trial.clone());
        }
        let first = self.first.as_ref().expect("a first trial");
        if trial.stamp.iteration > 0 || always {
            trial.changes_from(first)
        } else {
            trial
        }
    }

    /// Runs the coupler until it finishes or fails; returns step reports.
    fn run(&mut self, coupler: &mut Coupler) -> Result<(Vec<StepReport>, Finish), CouplerError> {
        let mut inbox: VecDeque<(NodeKind, Message)> = VecDeque::new();
        inbox.push_back((NodeKind::Fluid, hello(NodeKind::Fluid)));
        inbox.push_back((NodeKind::Fluid, totals(NodeKind::Fluid, 0, 1.0)));
        inbox.push_back((NodeKind::Solid, hello(NodeKind::Solid)));
        inbox.push_back((NodeKind::Solid, totals(NodeKind::Solid, 0, 0.0)));
        inbox.push_back((
            NodeKind::Solid,
            Message::SolidState(self.with_interior(state(Stamp::step(0), 0.0))),
        ));
        // The fluid proposes before the coupler has seen the solid: it must be queued.
        inbox.push_back((NodeKind::Fluid, proposal(0, self.fluid_dt)));
        // The sub-step bound before the solid's first proposal: it must be queued too.
        if let Some(bound) = self.substep_bound {
            inbox.push_back((NodeKind::Solid, bound_proposal(0, bound)));
        }
        inbox.push_back((NodeKind::Solid, proposal(0, self.solid_dt)));
        let mut reports = Vec::new();
        let mut pending_decision_x = 0.0;
        let mut awaiting_prediction = None;
        while let Some((from, msg)) = inbox.pop_front() {
            for action in coupler.on_message(from, msg)? {
                match action {
                    Action::Send(to, msg) => {
                        self.sent.push((to, msg.clone()));
                        match (to, msg) {
                            (NodeKind::Fluid, Message::StepPlan(p)) if p.predicted => {
                                awaiting_prediction = Some(p.stamp);
                            }
                            (NodeKind::Fluid, Message::StepPlan(p)) => {
                                let f = -self.c * self.surface_x;
                                inbox.push_back((NodeKind::Fluid, loads(p.stamp, f)));
                            }
                            (NodeKind::Fluid, Message::SolidState(s)) => {
                                match awaiting_prediction.take() {
                                    // Iteration 0's loads on the predicted surface.
                                    Some(stamp) => {
                                        let f = -self.c * s.position[0];
                                        inbox.push_back((NodeKind::Fluid, loads(stamp, f)));
                                    }
                                    None => pending_decision_x = s.position[0],
                                }
                            }
                            (NodeKind::Fluid, Message::FixedPointDecision(d)) => {
                                self.surface_x = pending_decision_x;
                                let step = d.stamp.step;
                                match d.decision {
                                    Decision::Iterate => {
                                        let stamp = Stamp {
                                            step,
                                            iteration: d.stamp.iteration + 1,
                                        };
                                        let f = -self.c * self.surface_x;
                                        inbox.push_back((NodeKind::Fluid, loads(stamp, f)));
                                    }
                                    Decision::Accept => {
                                        inbox.push_back((
                                            NodeKind::Fluid,
                                            totals(NodeKind::Fluid, step, 1.0),
                                        ));
                                        inbox.push_back((
                                            NodeKind::Fluid,
                                            proposal(step + 1, self.fluid_dt),
                                        ));
                                    }
                                }
                            }
                            (NodeKind::Solid, Message::InterfaceLoads(l)) => {
                                let x =
                                    self.a + self.drift * l.stamp.step as f64 + self.b * l.force[0];
                                let mut answer = self.with_interior(state(l.stamp, x));
                                if self.revision_from.is_some_and(|from| l.stamp.step >= from) {
                                    answer.surface.revision = 1;
                                }
                                let answer = self.as_sent(answer);
                                inbox.push_back((NodeKind::Solid, Message::SolidState(answer)));
                            }
                            (NodeKind::Solid, Message::FixedPointDecision(d))
                                if d.decision == Decision::Accept =>
                            {
                                let step = d.stamp.step;
                                inbox.push_back((
                                    NodeKind::Solid,
                                    totals(NodeKind::Solid, step, 0.0),
                                ));
                                inbox.push_back((
                                    NodeKind::Solid,
                                    proposal(step + 1, self.solid_dt),
                                ));
                                if let Some(bound) = self.substep_bound {
                                    inbox.push_back((
                                        NodeKind::Solid,
                                        bound_proposal(step + 1, bound),
                                    ));
                                }
                            }
                            _ => {}
                        }
                    }
                    Action::StepDone(r) => reports.push(r),
                    Action::Checkpoint(_) | Action::CouplerCheckpoint(_) => {}
                    Action::Finished(f) => return Ok((reports, f)),
                }
            }
        }
        panic!("the fake nodes ran out of messages before the coupler finished");
    }
}

fn bound_proposal(step: u64, dt: f64) -> Message {
    Message::DtProposal(DtProposal {
        stamp: Stamp {
            step,
            iteration: protocol::session::SUBSTEP_BOUND_ITERATION,
        },
        dt_max: dt,
        limiter: "bound".into(),
    })
}

#[test]
fn solid_substeps_agree_on_k_from_the_second_proposal() {
    use protocol::scene::SolidSubsteps;
    let outputs = vec![0.25, 0.5];
    // A fixed K: the coupling step is bounded by K times the bound, K on every report.
    let mut world = World::new(1.0, 0.5, 0.5);
    world.substep_bound = Some(0.02);
    let mut config = cfg(Scheme::SemiImplicit, Relaxation::None, outputs.clone());
    config.substeps = Some(SolidSubsteps::Fixed(4));
    let (reports, finish) = world
        .run(&mut Coupler::new(config.clone()))
        .expect("the run completes");
    assert_eq!(finish, Finish::Completed);
    assert!((reports[0].dt - 0.08).abs() < 1e-15, "{}", reports[0].dt);
    assert_eq!(reports[0].limiter, "solid:bound (x4 sub-steps)");
    assert!(reports.iter().all(|r| r.solid_substeps == Some(4)));
    assert!(reports.iter().all(|r| r.ledger.solid_substeps == 4));
    // "auto": the fluid's step, and the smallest K within half the bound (0.1/7 ≤ 0.015 < 0.1/6;
    // the step of 0.05 to the output at 0.25 takes 4).
    world = World::new(1.0, 0.5, 0.5);
    world.substep_bound = Some(0.03);
    config.substeps = Some(SolidSubsteps::AUTO);
    let (reports, _) = world
        .run(&mut Coupler::new(config.clone()))
        .expect("the run completes");
    let got: Vec<(f64, Option<u32>)> = reports.iter().map(|r| (r.dt, r.solid_substeps)).collect();
    assert_eq!(reports[0].limiter, "fluid:test");
    assert_eq!(got[0].1, Some(7), "{got:?}");
    assert_eq!(got[2].1, Some(4), "{got:?}");
    // More than 256: the run stops, naming what sets the bound.
    world = World::new(1.0, 0.5, 0.5);
    world.substep_bound = Some(1e-4);
    match world.run(&mut Coupler::new(config)) {
        Err(CouplerError::TooManySubsteps {
            needed, limiter, ..
        }) => {
            assert_eq!(needed, 2000);
            assert_eq!(limiter, "solid:bound");
        }
        other => panic!("{other:?}"),
    }
}

fn loads(stamp: Stamp, f: f64) -> Message {
    Message::InterfaceLoads(InterfaceLoads {
        stamp,
        dim: 2,
        force: vec![f, 0.0],
        torque: vec![0.0],
        particles: Vec::new(),
    })
}

#[test]
fn explicit_does_one_pass_per_step_and_agrees_on_dt() {
    let mut world = World::new(1.0, 0.5, 0.5);
    let mut coupler = Coupler::new(cfg(Scheme::Explicit, Relaxation::None, vec![0.25, 0.5]));
    let (reports, finish) = world.run(&mut coupler).expect("the run completes");
    assert_eq!(finish, Finish::Completed);
    // dt = min(0.1, 0.3) = 0.1; 0.2 then output at 0.25 (dt 0.05); then 0.35, 0.45, 0.5.
    let dts: Vec<f64> = reports.iter().map(|r| r.dt).collect();
    let expected = [0.1, 0.1, 0.05, 0.1, 0.1, 0.05];
    assert_eq!(dts.len(), expected.len(), "{dts:?}");
    for (dt, e) in dts.iter().zip(expected) {
        assert!((dt - e).abs() < 1e-15, "{dts:?}");
    }
    assert_eq!(reports[2].output, Some(0));
    assert_eq!(reports[2].t, 0.25);
    assert_eq!(reports[5].t, 0.5);
    assert!(reports.iter().all(|r| r.iterations == 1));
    assert_eq!(reports[0].limiter, "fluid:test");
}

#[test]
fn semi_implicit_converges_to_the_fixed_point() {
    let (a, b, c) = (1.0, 0.5, 0.5);
    let mut world = World::new(a, b, c);
    let mut coupler = Coupler::new(cfg(Scheme::SemiImplicit, Relaxation::None, vec![0.1]));
    let (reports, _) = world.run(&mut coupler).expect("the run completes");
    let r = &reports[0];
    // Plain iteration contracts by b c = 0.25 per trial from |x* − 0| = 0.8.
    let x_star = a / (1.0 + b * c);
    assert!(
        (world.surface_x - x_star).abs() < 1e-12,
        "{}",
        world.surface_x
    );
    assert!(r.residuals.last().copied().unwrap_or(1.0) <= 1e-12);
    // Residual k is |x_{k+1} − x_k| = 0.8 · 0.25^k · (1 − 0.25) roughly: ratio 0.25.
    for w in r.residuals.windows(2).take(10) {
        assert!((w[1] / w[0] - 0.25).abs() < 1e-6, "{:?}", r.residuals);
    }
    assert!(
        (19..=22).contains(&r.iterations),
        "{} iterations",
        r.iterations
    );
}

#[test]
fn aitken_needs_fewer_iterations() {
    let (a, b, c) = (1.0, 0.9, 1.0);
    let mut plain = World::new(a, b, c);
    let mut plain_cfg = cfg(Scheme::SemiImplicit, Relaxation::None, vec![0.1]);
    plain_cfg.max_iterations = 500;
    let mut coupler = Coupler::new(plain_cfg);
    let (plain_reports, _) = plain.run(&mut coupler).expect("plain converges");
    let mut relaxed = World::new(a, b, c);
    let mut coupler = Coupler::new(cfg(Scheme::SemiImplicit, Relaxation::Aitken, vec![0.1]));
    let (aitken_reports, _) = relaxed.run(&mut coupler).expect("aitken converges");
    let x_star = a / (1.0 + b * c);
    assert!((relaxed.surface_x - x_star).abs() < 1e-12);
    assert!(
        plain_reports[0].iterations >= 2 * aitken_reports[0].iterations,
        "plain {} vs aitken {}",
        plain_reports[0].iterations,
        aitken_reports[0].iterations
    );
}

#[test]
fn iqn_ils_solves_the_affine_world_in_rank_plus_two_trials() {
    // Rank 1 (only x moves): trial 0, the relaxed trial 1, then the secant's exact answer.
    let (a, b, c) = (1.0, 0.9, 1.0);
    let mut world = World::new(a, b, c);
    world.drift = 0.1;
    let mut coupler = Coupler::new(cfg(Scheme::SemiImplicit, Relaxation::IqnIls, vec![0.3]));
    let (reports, _) = world.run(&mut coupler).expect("IQN-ILS converges");
    let last = reports.last().expect("steps").step as f64;
    let x_star = (a + 0.1 * last) / (1.0 + b * c);
    assert!(
        (world.surface_x - x_star).abs() < 1e-12,
        "{}",
        world.surface_x
    );
    assert!(reports[0].iterations <= 3, "{:?}", reports[0].residuals);
    assert_eq!(reports[0].columns, vec![0, 1]);
    // Later steps reuse the column: the first update is already the answer.
    for r in &reports[1..] {
        assert!(r.iterations <= 2, "step {}: {:?}", r.step, r.residuals);
    }
    let mut plain = World::new(a, b, c);
    plain.drift = 0.1;
    let mut plain_cfg = cfg(Scheme::SemiImplicit, Relaxation::None, vec![0.3]);
    plain_cfg.max_iterations = 500;
    let mut coupler = Coupler::new(plain_cfg);
    plain.run(&mut coupler).expect("plain converges");
    assert!((plain.surface_x - world.surface_x).abs() <= 1e-12);
}

#[test]
fn iqn_ils_without_reuse_starts_each_step_relaxed() {
    let mut world = World::new(1.0, 0.9, 1.0);
    world.drift = 0.1;
    let mut c = cfg(Scheme::SemiImplicit, Relaxation::IqnIls, vec![0.3]);
    c.iqn_reuse = 0;
    let mut coupler = Coupler::new(c);
    let (reports, _) = world.run(&mut coupler).expect("IQN-ILS converges");
    for r in &reports {
        assert_eq!(r.columns.first(), Some(&0), "step {}", r.step);
        assert!(r.iterations <= 3, "step {}: {:?}", r.step, r.residuals);
    }
}

#[test]
fn linear_predictor_gives_iteration_zero_from_the_accepted_states() {
    let (a, b, c, d) = (1.0, 0.5, 0.5, 0.1);
    let mut world = World::new(a, b, c);
    world.drift = d;
    let mut config = cfg(Scheme::SemiImplicit, Relaxation::None, vec![0.3]);
    config.predictor = Predictor::Linear;
    let mut coupler = Coupler::new(config);
    let (reports, _) = world.run(&mut coupler).expect("converges");
    assert!(!reports[0].predicted, "no earlier step to extrapolate from");
    assert!(reports[1..].iter().all(|r| r.predicted));
    // Step n's answer x*_n is linear in n: from step 2 on (step 1 extrapolates from the
    // initial state, which is off that line) the extrapolation, sent right after the plan as
    // iteration 0's input, is the answer, and its one trial confirms it.
    let x_star = |n: f64| (a + d * n) / (1.0 + b * c);
    let plans: Vec<bool> = world
        .sent
        .iter()
        .filter_map(|(to, m)| match (to, m) {
            (NodeKind::Fluid, Message::StepPlan(p)) => Some(p.predicted),
            _ => None,
        })
        .collect();
    assert_eq!(plans[..3], [false, true, true]);
    let step_2: Vec<&Message> = world
        .sent
        .iter()
        .filter(|(to, m)| *to == NodeKind::Fluid && m.stamp().step == 2)
        .map(|(_, m)| m)
        .collect();
    match step_2[..2] {
        [Message::StepPlan(_), Message::SolidState(s)] => {
            assert_eq!(s.stamp, Stamp::step(2));
            assert!((s.position[0] - x_star(2.0)).abs() < 1e-12, "{s:?}");
        }
        ref other => panic!("expected the plan then the prediction, got {other:?}"),
    }
    for r in &reports[2..] {
        assert_eq!(r.iterations, 1, "step {}: {:?}", r.step, r.residuals);
    }
    let last = reports.last().expect("steps").step as f64;
    assert!((world.surface_x - x_star(last)).abs() < 1e-12);
}

/// A solid whose answer does not depend on the loads (a prescribed motion) meets the linear
/// predictor's input exactly, so each step is accepted on its first trial; but in the step where
/// its wet surface changes revision (links broke at the end of the last step) that trial was
/// computed on loads of the old surface, and one more iteration must take them on the new one.
#[test]
fn a_trial_on_a_new_surface_revision_is_not_accepted() {
    let (a, d) = (1.0, 0.1);
    let mut world = World::new(a, 0.0, 0.5);
    world.drift = d;
    world.revision_from = Some(3);
    let mut config = cfg(Scheme::SemiImplicit, Relaxation::IqnIls, vec![0.6]);
    config.predictor = Predictor::Linear;
    let mut coupler = Coupler::new(config);
    let (reports, _) = world.run(&mut coupler).expect("converges");
    let iterations: Vec<u32> = reports.iter().map(|r| r.iterations).collect();
    println!("iterations per step: {iterations:?}");
    assert_eq!(iterations.len(), 6);
    // Step 0 has no prediction and step 1 extrapolates from off the line; from step 2 the first
    // trial is the answer, but step 3's is on revision 1 and its input on revision 0.
    assert_eq!(iterations[2..], [1, 2, 1, 1]);
    assert!(
        reports[3].residuals[0] <= 1e-12,
        "{:?}",
        reports[3].residuals
    );
    let accepted: Vec<u64> = world
        .sent
        .iter()
        .filter_map(|(to, m)| match (to, m) {
            (NodeKind::Fluid, Message::SolidState(s)) if s.stamp.step == 3 => {
                Some(s.surface.revision)
            }
            _ => None,
        })
        .collect();
    // The prediction (revision 0), the input of iteration 1 and the accepted state (revision 1).
    assert_eq!(accepted, [0, 1, 1]);
}

#[test]
fn divergent_fixed_point_stops_with_a_report() {
    let mut world = World::new(1.0, 1.5, 1.0);
    let mut coupler = Coupler::new(cfg(Scheme::SemiImplicit, Relaxation::None, vec![0.1]));
    let err = world.run(&mut coupler).expect_err("b c = 1.5 diverges");
    match &err {
        CouplerError::NotConverged {
            step,
            iterations,
            residuals,
            ..
        } => {
            assert_eq!((*step, *iterations), (0, 50));
            assert_eq!(residuals.len(), 50);
            assert!(residuals[49] > residuals[0]);
        }
        other => panic!("expected NotConverged, got {other}"),
    }
    assert!(
        err.to_string()
            .contains("fixed point not converged at step 0"),
        "{err}"
    );
}

#[test]
fn version_mismatch_is_refused_at_hello() {
    let mut coupler = Coupler::new(cfg(Scheme::Explicit, Relaxation::None, vec![1.0]));
    let msg = Message::Hello(Hello {
        node: NodeKind::Fluid,
        protocol_version: PROTOCOL_VERSION + 1,
        scene_hash: 7,
        implementation: "test".into(),
        capabilities: vec![],
    });
    let err = coupler
        .on_message(NodeKind::Fluid, msg)
        .expect_err("refused");
    let text = err.to_string();
    assert!(
        text.contains(&format!("version {PROTOCOL_VERSION}")),
        "{text}"
    );
    assert!(
        text.contains(&format!("version {}", PROTOCOL_VERSION + 1)),
        "{text}"
    );
}

#[test]
fn scene_hash_mismatch_is_refused() {
    let mut coupler = Coupler::new(cfg(Scheme::Explicit, Relaxation::None, vec![1.0]));
    let msg = Message::Hello(Hello {
        node: NodeKind::Solid,
        protocol_version: PROTOCOL_VERSION,
        scene_hash: 8,
        implementation: "test".into(),
        capabilities: vec![],
    });
    let err = coupler
        .on_message(NodeKind::Solid, msg)
        .expect_err("refused");
    assert!(
        matches!(
            err,
            CouplerError::Refused {
                node: NodeKind::Solid,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn out_of_order_message_is_an_error() {
    let mut coupler = Coupler::new(cfg(Scheme::Explicit, Relaxation::None, vec![1.0]));
    let err = coupler
        .on_message(NodeKind::Fluid, loads(Stamp::step(0), 1.0))
        .expect_err("loads before hello");
    assert!(err.to_string().contains("InterfaceLoads"), "{err}");
}

#[test]
fn criterion_22_weights_rotation_by_diameter() {
    let a = state(Stamp::step(0), 0.0);
    let mut b = state(Stamp::step(0), 3e-13);
    assert!((criterion_22(&a, &b) - 3e-13).abs() < 1e-25);
    b.orientation[0] = 1e-13;
    b.diameter[0] = 2.0;
    // 2 · 2√2 sin(0.5e-13) = 2√2 · 1e-13.
    let expected = 3e-13 + 2.0 * std::f64::consts::SQRT_2 * 1e-13;
    assert!(
        (criterion_22(&a, &b) - expected).abs() < 1e-24,
        "{}",
        criterion_22(&a, &b)
    );
}

#[test]
fn trials_sent_as_their_changes_couple_as_the_whole_trials() {
    let run = |changes: Option<bool>| {
        let mut world = World::new(1.0, 0.9, 1.0);
        world.drift = 0.1;
        world.interior = true;
        world.changes = changes;
        let mut coupler = Coupler::new(cfg(Scheme::SemiImplicit, Relaxation::IqnIls, vec![0.3]));
        let reports = world.run(&mut coupler).map(|(r, _)| r);
        (reports, world)
    };
    let (whole, whole_world) = run(None);
    let (changed, changed_world) = run(Some(false));
    let (whole, changed) = (whole.expect("converges"), changed.expect("converges"));
    // The same steps, residuals and relaxation to the bit, and the same messages to the fluid.
    let key = |r: &StepReport| {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        (
            r.step,
            r.dt.to_bits(),
            bits(&r.residuals),
            bits(&r.relaxation),
            r.columns.clone(),
        )
    };
    assert_eq!(
        whole.iter().map(key).collect::<Vec<_>>(),
        changed.iter().map(key).collect::<Vec<_>>()
    );
    let to_fluid = |w: &World| {
        w.sent
            .iter()
            .filter(|(to, _)| *to == NodeKind::Fluid)
            .map(|(_, m)| format!("{m:?}"))
            .collect::<Vec<_>>()
    };
    assert_eq!(to_fluid(&whole_world), to_fluid(&changed_world));
    assert!(
        whole.iter().any(|r| r.iterations > 1),
        "no second trial to send as changes"
    );
    // A first trial sent as changes has nothing to put them onto: refused with the reason.
    match run(Some(true)).0 {
        Err(CouplerError::Invalid { from, what }) => {
            assert_eq!(from, NodeKind::Solid);
            assert!(
                what.contains("the step's first trial did not come whole"),
                "{what}"
            );
        }
        other => panic!("{other:?}"),
    }
}
