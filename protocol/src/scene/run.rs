//! `[run]`: the time loop and the coupling, and their validation.

use serde::{Deserialize, Serialize};

use super::error::{Check, SceneError};

/// `[run]`: the time loop and the coupling.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    /// End time \[s\] (default 1.0).
    pub t_end: f64,
    /// Coupling scheme (default semi-implicit; ignored when one side is absent).
    pub scheme: SchemeName,
    /// Fixed-point criterion of eq. (22) of paper 003 (default 1e-12).
    pub tolerance: f64,
    /// Fixed-point iterations allowed per step; exceeding it stops the run (default 50).
    pub max_iterations: u32,
    /// Relaxation of the solid positions in the fixed point (default none).
    pub relaxation: Relaxation,
    /// Constant relaxation factor of the first iteration of Aitken and IQN-ILS, when no
    /// earlier information is available (default 0.5).
    pub relaxation_initial: f64,
    /// IQN-ILS: steps whose secant columns are kept besides the current step's; 0 = only this
    /// step's (default 4).
    pub iqn_reuse: u32,
    /// IQN-ILS: QR2 filter limit; a column whose part orthogonal to the newer columns is
    /// shorter than this fraction of its own length is dropped (default 1e-2).
    pub iqn_filter: f64,
    /// Predictor of a semi-implicit step's first inputs (default none).
    pub predictor: Predictor,
    /// Recording level (default exchange).
    pub record: RecordLevel,
    /// Compression of the record's chunks (default zstd).
    pub record_compression: RecordCompression,
    /// Steps between node checkpoints in the record; 0 = none (default 0; `record = "all"`
    /// checkpoints every step).
    pub checkpoint_every: u64,
    /// Optional cap on the coupling step \[s\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_max: Option<f64>,
    /// Optional cap on the number of steps, at least 1 (the run stops with status
    /// "max_steps").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_steps: Option<u64>,
    /// Smallest coupling step a node may impose \[s\]: a step a node limits to less stops the
    /// run with a report naming the node and what limits it (cell or particle). Default: the
    /// larger of [`DT_MIN_RELATIVE`] times the smallest step the nodes proposed for the first
    /// step and [`DT_MIN_OF_T_END`] times `t_end`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_min: Option<f64>,
    /// Worker threads per node for the solver cores (default 1; results do not depend on it).
    pub threads: u32,
    /// Largest relative mass error the ledger accepts before it stops the run (default 1e-9;
    /// checked only when the initial mass is not zero).
    pub mass_tolerance: f64,
    /// Largest relative energy error the ledger accepts (default: recorded, not checked).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy_tolerance: Option<f64>,
    /// Optional cap on the size of the record `exchange.mcap` \[bytes\], at least
    /// [`RECORD_MIN_BYTES`]: the run stops cleanly, with status `record_max_bytes`, at the end of
    /// the last step whose successor would pass it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub record_max_bytes: Option<u64>,
    /// Solid sub-steps per coupling step: `K` (an integer ≥ 1) or `"auto"` (per step, the
    /// smallest K whose sub-step meets the solid's own stability bound). Absent: one step of the
    /// solid per coupling step, the coupling step limited by the solid's bound (K = 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub solid_substeps: Option<SolidSubsteps>,
}

/// Smallest `run.record_max_bytes` (the record's header and the first steps).
pub const RECORD_MIN_BYTES: u64 = 1 << 16;

impl Default for RunConfig {
    fn default() -> Self {
        RunConfig {
            t_end: 1.0,
            scheme: SchemeName::SemiImplicit,
            tolerance: 1e-12,
            max_iterations: 50,
            relaxation: Relaxation::None,
            relaxation_initial: 0.5,
            iqn_reuse: 4,
            iqn_filter: 1e-2,
            predictor: Predictor::None,
            record: RecordLevel::Exchange,
            record_compression: RecordCompression::Zstd,
            checkpoint_every: 0,
            dt_max: None,
            max_steps: None,
            dt_min: None,
            threads: 1,
            mass_tolerance: 1e-9,
            energy_tolerance: None,
            record_max_bytes: None,
            solid_substeps: None,
        }
    }
}

/// Most solid sub-steps one coupling step may take (`run.solid_substeps`); `"auto"` needing more
/// stops the run naming the particle that sets the solid's bound.
pub const MAX_SOLID_SUBSTEPS: u32 = 256;

/// The part of the solid's stable step that the sub-steps of `"auto"` stay within.
///
/// NOTE: K changes from step to step under `"auto"` (on the thin shell 7 and 8 in turn as the
/// fluid's step crosses 7 bounds), so the sub-step jumps by 1/K. Verlet near its edge (`ω h`
/// up to 1.8 for the stiffest mode at the bound) keeps a modified energy whose ellipse differs
/// from the energy's by `(ω h / 2)²`, and each jump of `h` moves the mode onto another ellipse:
/// a parametric pump. It grew the shell's 17th rotational mode tenfold in 0.03 s and the
/// solid's energy error with it (112 times K = 1's at t = 0.1 s; fixed K = 7 or 8 over the same
/// coupling steps: 2.6 and 1.2 times). At half the bound, `ω h ≤ 0.9`: 0.48 times K = 1's
/// (docs/subcycling.md). A power of two, so `bound * AUTO_SUBSTEP_FRACTION` rounds nothing.
pub const AUTO_SUBSTEP_FRACTION: f64 = 0.5;

/// `run.solid_substeps`: how many Verlet + RATTLE sub-steps of `dt/K` the solid takes per
/// coupling step `dt`, under the step's held loads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum SolidSubsteps {
    /// A fixed K: the coupling step is limited by K times the solid's bound.
    Fixed(u32),
    /// `"auto"`: the coupling step is not limited by the solid's bound; each step takes the
    /// smallest K with `dt/K` within [`AUTO_SUBSTEP_FRACTION`] of it.
    Auto(AutoWord),
}

/// The word `"auto"` of [`SolidSubsteps::Auto`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AutoWord {
    /// `"auto"`.
    Auto,
}

impl SolidSubsteps {
    /// `"auto"`.
    pub const AUTO: SolidSubsteps = SolidSubsteps::Auto(AutoWord::Auto);

    /// The sub-steps of a coupling step `dt` whose solid sub-step must stay within `bound`
    /// (the solid's stable step, safety factor included): the fixed K, or for `"auto"` the
    /// smallest K ≥ 1 with `dt / K ≤ bound · AUTO_SUBSTEP_FRACTION`. `Err(K)` when `"auto"`
    /// needs more than [`MAX_SOLID_SUBSTEPS`] (K as far as it was counted). Both the coupler
    /// and the solid node call it on the same numbers, so they agree on K to the bit.
    pub fn for_step(self, dt: f64, bound: f64) -> Result<u32, u64> {
        match self {
            SolidSubsteps::Fixed(k) => Ok(k),
            SolidSubsteps::Auto(_) => {
                let bound = bound * AUTO_SUBSTEP_FRACTION;
                let within = bound > 0.0 && dt / f64::from(MAX_SOLID_SUBSTEPS) <= bound;
                if !within {
                    let k = (dt / bound).ceil();
                    return Err(if k.is_finite() { k as u64 } else { u64::MAX });
                }
                // NOTE: the ceiling of the quotient, then the quotient itself checked: dt/K
                // rounds, and K is the smallest integer whose rounded sub-step is within bound.
                let mut k = ((dt / bound).ceil() as u32).clamp(1, MAX_SOLID_SUBSTEPS);
                while k > 1 && dt / f64::from(k - 1) <= bound {
                    k -= 1;
                }
                while dt / f64::from(k) > bound {
                    k += 1;
                }
                Ok(k)
            }
        }
    }
}

/// Default `run.dt_min` relative to the first step the nodes propose: a step that has collapsed
/// a millionfold is a run without progress.
///
/// NOTE: a shock reflecting from a wall or a body speeding up changes the step by factors of a
/// few; a millionfold collapse takes hours of steps for nothing.
pub const DT_MIN_RELATIVE: f64 = 1e-6;

/// Default `run.dt_min` relative to `run.t_end`: a step that would need more than a billion
/// steps to reach the end is a run without progress, even from the first step.
///
/// NOTE: Sod with ρ = 1e-300 on one side proposes 3e-153 s for its first step (the sound speed
/// of the near-vacuum cells), then 1e-8 s for hours; [`DT_MIN_RELATIVE`] alone, relative to
/// that first proposal, would never stop it.
pub const DT_MIN_OF_T_END: f64 = 1e-9;

/// `run.scheme`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SchemeName {
    /// One pass per step.
    Explicit,
    /// Fixed point on the wet-surface position.
    SemiImplicit,
}

/// `run.relaxation`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Relaxation {
    /// Plain fixed point.
    None,
    /// Aitken's dynamic relaxation of the solid positions.
    Aitken,
    /// Interface quasi-Newton with an inverse Jacobian from a least-squares model (Degroote et
    /// al. 2009), on the positions and orientations of the particles.
    IqnIls,
}

/// `run.predictor`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Predictor {
    /// Iteration 0 runs on the accepted surface `F^n`, iteration 1 on the relaxation of its
    /// trial.
    None,
    /// Iteration 0 runs on the linear extrapolation of the last two accepted states (sent to
    /// the fluid right after the step plan) instead of on `F^n`.
    Linear,
    /// Iteration 1 starts from iteration 0's trial plus the last step's correction (its
    /// accepted state minus its first trial).
    Correction,
}

/// `run.record`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RecordLevel {
    /// Every exchanged message, the diagnostics, and a checkpoint of each node at every step
    /// (so that a replay of any step starts at that step).
    All,
    /// Every exchanged message and the diagnostics (hello and welcome included).
    Exchange,
    /// The diagnostics channel only.
    Diagnostics,
    /// No MCAP file.
    None,
}

/// `run.record_compression`: how the chunks of `exchange.mcap` are compressed. Any value gives
/// the same messages back; it only trades file size against the coupler's time.
///
/// NOTE: `"zstd"` (the default, level -5, on the record's own thread) makes the record of
/// `clamped-beam-2d` 2.9 times smaller than `"none"` (99 MB to 34 MB; 297 MB before the
/// smaller messages of issue 39); `"lz4"` 1.9 times; `"none"` writes fastest, 1.5–2 GiB/s
/// into a file (docs/performance.md, "Recording").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RecordCompression {
    /// Chunks stored as they are (MCAP compression `""`).
    None,
    /// LZ4 frames (MCAP compression `"lz4"`).
    Lz4,
    /// Zstandard, level -5 (`--fast=5`), on the record's own thread (MCAP compression `"zstd"`).
    #[default]
    Zstd,
}

impl RecordCompression {
    /// The value as written in a scene.
    pub fn name(self) -> &'static str {
        match self {
            RecordCompression::None => "none",
            RecordCompression::Lz4 => "lz4",
            RecordCompression::Zstd => "zstd",
        }
    }
}

impl RunConfig {
    /// The `[run]` rules.
    pub(super) fn validate(&self, c: &Check<'_>) -> Result<(), SceneError> {
        let run = self;
        c.positive("run.t_end", run.t_end)?;
        c.positive("run.tolerance", run.tolerance)?;
        c.positive("run.mass_tolerance", run.mass_tolerance)?;
        if let Some(e) = run.energy_tolerance {
            c.positive("run.energy_tolerance", e)?;
        }
        if run.max_iterations == 0 {
            return Err(c.invalid("run.max_iterations", "at least 1", "0".into()));
        }
        if !(run.relaxation_initial > 0.0 && run.relaxation_initial <= 1.0) {
            return Err(c.invalid(
                "run.relaxation_initial",
                "a number in (0, 1]",
                format!("{}", run.relaxation_initial),
            ));
        }
        // NOTE: the filter compares G_jj − Σ R_ij² with filter² G_jj on the Gram matrix
        // (coupler-node's iqn.rs); below 1e-6 that difference is lost in round-off.
        if !(run.iqn_filter >= 1e-6 && run.iqn_filter < 1.0) {
            return Err(c.invalid(
                "run.iqn_filter",
                "a number in [1e-6, 1)",
                format!("{}", run.iqn_filter),
            ));
        }
        if run.iqn_reuse > 64 {
            return Err(c.invalid("run.iqn_reuse", "0 to 64", run.iqn_reuse.to_string()));
        }
        if let Some(dt) = run.dt_max {
            c.positive("run.dt_max", dt)?;
        }
        if run.threads == 0 || run.threads > 256 {
            return Err(c.invalid("run.threads", "1 to 256", run.threads.to_string()));
        }
        if let Some(cap) = run.record_max_bytes
            && cap < RECORD_MIN_BYTES
        {
            return Err(c.invalid(
                "run.record_max_bytes",
                &format!("at least {RECORD_MIN_BYTES} bytes"),
                cap.to_string(),
            ));
        }
        if run.max_steps == Some(0) {
            return Err(c.invalid("run.max_steps", "at least 1 step", "0".into()));
        }
        if let Some(SolidSubsteps::Fixed(k)) = run.solid_substeps
            && !(1..=MAX_SOLID_SUBSTEPS).contains(&k)
        {
            return Err(c.invalid(
                "run.solid_substeps",
                &format!("an integer from 1 to {MAX_SOLID_SUBSTEPS}, or \"auto\""),
                k.to_string(),
            ));
        }
        if let Some(dt_min) = run.dt_min {
            c.positive("run.dt_min", dt_min)?;
            if let Some(dt_max) = run.dt_max
                && dt_min >= dt_max
            {
                return Err(c.invalid(
                    "run.dt_min",
                    &format!("a step below run.dt_max = {dt_max:e}"),
                    format!("{dt_min:e}"),
                ));
            }
        }
        Ok(())
    }
}
