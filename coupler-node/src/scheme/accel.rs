//! The fixed point's acceleration: the input of each iteration from its trial (Aitken's Δ²,
//! IQN-ILS) and from the earlier steps (the predictors), on flattened solid states. Pure
//! arithmetic, apart from the handshake's state machine; what it carries from step to step is
//! [`AccelerationState`], part of the coupler's checkpoint.

use protocol::scene::{Predictor, Relaxation};
use protocol::wire::{SolidState, Stamp};
use serde::{Deserialize, Serialize};

use crate::iqn::{IqnColumns, IqnIls};

use crate::scheme::config::CouplerConfig;
use crate::scheme::error::RestoreError;

/// What the acceleration carries between steps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AccelerationState {
    /// Accepted solid state at `t^n`.
    pub accepted: Option<SolidState>,
    /// Accepted state at `t^{n−1}` and the step that led from it to `t^n` (linear predictor).
    pub previous: Option<(SolidState, f64)>,
    /// Last step's accepted state minus its first trial, flattened (correction predictor).
    pub correction: Option<Vec<f64>>,
    /// IQN-ILS's columns (absent with another relaxation).
    pub iqn: Option<IqnColumns>,
}

/// This step's account of the acceleration, for the diagnostics.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct StepAccount {
    /// Aitken's factors, one per relaxed iteration.
    pub(super) omegas: Vec<f64>,
    /// IQN-ILS columns used after each trial.
    pub(super) columns: Vec<u32>,
    /// IQN-ILS columns dropped by the filter.
    pub(super) columns_dropped: u32,
    /// An input came from a predictor.
    pub(super) predicted: bool,
}

/// The acceleration's state.
#[derive(Debug)]
pub(super) struct Acceleration {
    relaxation: Relaxation,
    relaxation_initial: f64,
    predictor: Predictor,
    /// This step's size.
    dt: f64,
    account: StepAccount,
    aitken: Option<(Vec<f64>, f64)>,
    iqn: Option<IqnIls>,
    accepted: Option<SolidState>,
    previous: Option<(SolidState, f64)>,
    /// This step's first trial, flattened (correction predictor).
    first_trial: Option<Vec<f64>>,
    correction: Option<Vec<f64>>,
}

impl Acceleration {
    /// No accepted state yet, no columns.
    pub(super) fn new(cfg: &CouplerConfig) -> Acceleration {
        Acceleration {
            relaxation: cfg.relaxation,
            relaxation_initial: cfg.relaxation_initial,
            predictor: cfg.predictor,
            dt: 0.0,
            account: StepAccount::default(),
            aitken: None,
            iqn: (cfg.relaxation == Relaxation::IqnIls)
                .then(|| IqnIls::new(cfg.iqn_reuse, cfg.iqn_filter, cfg.relaxation_initial)),
            accepted: None,
            previous: None,
            first_trial: None,
            correction: None,
        }
    }

    /// The solid's initial state `F^0`.
    pub(super) fn set_initial(&mut self, state: SolidState) {
        self.accepted = Some(state);
    }

    /// A semi-implicit (`iterated`) or explicit step `step` of size `dt` begins: iteration 0's
    /// input (`None` without a solid) and whether the linear predictor made it (else it is the
    /// accepted `F^n`).
    pub(super) fn start_step(
        &mut self,
        step: u64,
        dt: f64,
        iterated: bool,
    ) -> Option<(SolidState, bool)> {
        self.dt = dt;
        self.account = StepAccount::default();
        self.aitken = None;
        if let Some(iqn) = self.iqn.as_mut() {
            iqn.start_step();
        }
        let accepted = self.accepted.as_ref()?;
        // The linear predictor replaces `F^n` once two accepted states are known.
        let predicted = match (iterated, self.predictor) {
            (true, Predictor::Linear) => self.extrapolate(flatten(accepted).len()).map(|p| {
                let mut s = unflatten(accepted, &p);
                s.stamp = Stamp::step(step);
                s
            }),
            _ => None,
        };
        self.account.predicted = predicted.is_some();
        Some(match predicted {
            Some(p) => (p, true),
            None => (accepted.clone(), false),
        })
    }

    /// The input of the next iteration after `trial` (computed on `input`): the trial itself,
    /// its relaxation (Aitken, IQN-ILS), or after iteration 0 the `correction` predictor's
    /// (this trial plus the last step's converged correction).
    pub(super) fn next_input(&mut self, input: &SolidState, trial: &SolidState) -> SolidState {
        let x = flatten(input);
        let gx = flatten(trial);
        if trial.stamp.iteration == 0 {
            self.first_trial = Some(gx.clone());
        }
        let predicted = match self.predictor {
            _ if trial.stamp.iteration > 0 => None,
            Predictor::None | Predictor::Linear => None,
            Predictor::Correction => self
                .correction
                .as_ref()
                .filter(|c| c.len() == gx.len())
                .map(|c| gx.iter().zip(c).map(|(g, c)| g + c).collect::<Vec<f64>>()),
        };
        self.account.predicted |= predicted.is_some();
        match self.relaxation {
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
                    None => self.relaxation_initial,
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
                self.account.omegas.push(omega);
                let relaxed: Vec<f64> = x.iter().zip(&r).map(|(x, r)| x + omega * r).collect();
                self.aitken = Some((r, omega));
                unflatten(trial, &relaxed)
            }
            Relaxation::IqnIls => {
                let r = unknowns_residual(input, trial, self.dt);
                let iqn = self.iqn.as_mut().expect("IQN-ILS has its model");
                if let Some(p) = predicted {
                    iqn.observe(&r, &gx);
                    self.account.columns.push(0);
                    return unflatten(trial, &p);
                }
                let (next, used) = iqn.next(&r, &x, &gx);
                self.account.columns.push(used);
                unflatten(trial, &next)
            }
        }
    }

    /// `trial` (computed on `input`) is accepted: it becomes `F^{n+1}`.
    pub(super) fn accept(&mut self, input: &SolidState, trial: SolidState) {
        if let Some(iqn) = self.iqn.as_mut() {
            // The accepted trial's secant column is as good as any: keep it for the next steps,
            // which would otherwise reuse nothing from a step accepted at once (as preCICE does).
            iqn.observe(&unknowns_residual(input, &trial, self.dt), &flatten(&trial));
        }
        self.previous = self.accepted.take().map(|a| (a, self.dt));
        let acc = flatten(&trial);
        self.correction = Some(match self.first_trial.take() {
            Some(f) if f.len() == acc.len() => acc.iter().zip(&f).map(|(a, b)| a - b).collect(),
            _ => vec![0.0; acc.len()],
        });
        self.accepted = Some(trial);
    }

    /// This step's account (taken: the next step starts a new one).
    pub(super) fn take_account(&mut self) -> StepAccount {
        let mut account = std::mem::take(&mut self.account);
        account.columns_dropped = self.iqn.as_ref().map_or(0, IqnIls::dropped);
        account
    }

    /// What is carried to the next step (between steps).
    pub(super) fn state(&self) -> AccelerationState {
        AccelerationState {
            accepted: self.accepted.clone(),
            previous: self.previous.clone(),
            correction: self.correction.clone(),
            iqn: self.iqn.as_ref().map(IqnIls::columns),
        }
    }

    /// Takes back what [`Acceleration::state`] gave.
    pub(super) fn restore(&mut self, state: &AccelerationState) -> Result<(), RestoreError> {
        match (self.iqn.as_mut(), &state.iqn) {
            (Some(iqn), Some(columns)) => iqn.restore(columns),
            (None, None) => {}
            _ => return Err(RestoreError::Relaxation),
        }
        self.accepted = state.accepted.clone();
        self.previous = state.previous.clone();
        self.correction = state.correction.clone();
        self.first_trial = None;
        Ok(())
    }

    /// Linear extrapolation `X^n + dt^n / dt^{n−1} (X^n − X^{n−1})` of the accepted states,
    /// flattened, when two are known with `len` values.
    fn extrapolate(&self, len: usize) -> Option<Vec<f64>> {
        let (prev, dt_prev) = self.previous.as_ref()?;
        let now = flatten(self.accepted.as_ref()?);
        let prev = flatten(prev);
        if now.len() != len || prev.len() != len || !dt_prev.is_finite() || *dt_prev <= 0.0 {
            return None;
        }
        let ratio = self.dt / dt_prev;
        Some(
            now.iter()
                .zip(&prev)
                .map(|(a, b)| a + ratio * (a - b))
                .collect(),
        )
    }
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
