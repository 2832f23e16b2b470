//! What a scene needs in memory, estimated before any process starts, and the refusal of a
//! scene that exceeds the machine.

use super::{RecordLevel, Scene, Shape};

/// Memory a scene's processes need, part by part, before anything runs ([`Scene::memory_estimate`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// `(key, bytes, how)`: the scene key that sets the part, its estimate, and how it was
    /// counted (for the error).
    pub parts: Vec<(String, u64, String)>,
}

impl MemoryEstimate {
    /// The whole estimate, in bytes (saturating).
    pub fn total_bytes(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |acc, (_, b, _)| acc.saturating_add(*b))
    }

    /// The largest part: its key and bytes (`("", 0)` for none).
    pub fn largest(&self) -> (&str, u64) {
        self.parts
            .iter()
            .max_by_key(|(_, b, _)| *b)
            .map_or(("", 0), |(k, b, _)| (k.as_str(), *b))
    }
}

/// A scene that needs more memory than the machine has ([`Scene::check_memory`]).
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error(
    "the scene needs an estimated {} of memory, more than the {} available; the largest part is `{key}`: {} ({how})",
    gib(*estimate), gib(*limit), gib(*part)
)]
pub struct MemoryError {
    /// Key of the largest part.
    pub key: String,
    /// Its bytes.
    pub part: u64,
    /// How it was counted.
    pub how: String,
    /// The whole estimate \[bytes\].
    pub estimate: u64,
    /// What the machine has \[bytes\].
    pub limit: u64,
}

fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / f64::from(1u32 << 30))
}

/// Bytes per fluid cell and conserved variable: the state and the split step's copy of it.
///
/// NOTE: measured, fluid-only 3-D 128³: 161 MiB for 2.1 M cells of 5 variables (2 copies of 8
/// bytes, README "Coupled step cost").
const FLUID_BYTES_PER_VARIABLE: u64 = 16;

/// Bytes per fluid cell of a coupled run: the dense Λ and λ of two geometries and the
/// near-surface data (README: 342 MiB against 161 MiB at 128³).
const FLUID_COUPLED_BYTES_PER_CELL: u64 = 96;

/// Bytes per solid particle: particle, links, wet surface, and the shared-memory slots of the
/// frames carrying them.
///
/// NOTE: an upper estimate from the data structures (a 3-D cuboid: 8 vertices, 12 wet
/// triangles, up to 26 links; every frame about it is held in 10 bus slots per direction).
const SOLID_BYTES_PER_PARTICLE: [u64; 3] = [1 << 10, 4 << 10, 16 << 10];

/// Slots of a publisher's data segment, each the size of its largest frame
/// (`bus::SAMPLES_PER_SEGMENT`): what one checkpoint frame costs in shared memory.
const BUS_SLOTS: u64 = 10;

impl Scene {
    /// Estimates the memory the scene's processes need: fluid cells × variables × copies (more
    /// with a solid), the shared-memory slots of checkpoint frames, solid particles. A lower
    /// bound of what a run takes, meant to refuse scenes that cannot start (issue 11).
    pub fn memory_estimate(&self) -> MemoryEstimate {
        let dim = self.dim().clamp(1, 3);
        let mut parts = Vec::new();
        let checkpoints = self.run.checkpoint_every > 0 || self.run.record == RecordLevel::All;
        if let Some(fluid) = &self.fluid
            && fluid.node == "real"
        {
            let n_cells = fluid
                .cells
                .iter()
                .fold(1u64, |acc, &n| acc.saturating_mul(u64::from(n)));
            let nvar = dim as u64 + 2;
            let mut per_cell = FLUID_BYTES_PER_VARIABLE * nvar;
            if self.solid.is_some() {
                per_cell += FLUID_COUPLED_BYTES_PER_CELL;
            }
            parts.push((
                "fluid.cells".to_string(),
                n_cells.saturating_mul(per_cell),
                format!("{n_cells} cells x {per_cell} B"),
            ));
            if checkpoints {
                let frame = n_cells.saturating_mul(nvar * 8);
                // (Named by the grid, which sets its size: an oversized grid was blamed on
                // `run.checkpoint_every`.)
                parts.push((
                    "fluid.cells".to_string(),
                    frame.saturating_mul(BUS_SLOTS),
                    format!(
                        "{BUS_SLOTS} shared-memory slots of a {frame} B fluid checkpoint, taken \
                         with `run.checkpoint_every` or `run.record = \"all\"`"
                    ),
                ));
            }
        }
        if let Some(solid) = &self.solid
            && solid.node == "real"
        {
            for (k, body) in solid.bodies.iter().enumerate() {
                let n_particles = match &body.shape {
                    Shape::Particles(list) => list.len() as u64,
                    _ => body
                        .divisions
                        .iter()
                        .fold(1u64, |acc, &n| acc.saturating_mul(u64::from(n))),
                };
                let per_particle = SOLID_BYTES_PER_PARTICLE[dim - 1];
                parts.push((
                    format!("solid.bodies[{k}].divisions"),
                    n_particles.saturating_mul(per_particle),
                    format!("{n_particles} particles x {per_particle} B"),
                ));
            }
        }
        MemoryEstimate { parts }
    }

    /// Refuses a scene whose [`Scene::memory_estimate`] exceeds `limit` bytes (what the machine
    /// has available), naming the largest part's key, the estimate and the limit.
    pub fn check_memory(&self, limit: u64) -> Result<(), MemoryError> {
        let est = self.memory_estimate();
        let total = est.total_bytes();
        if total <= limit {
            return Ok(());
        }
        let (key, part) = est.largest();
        let how = est
            .parts
            .iter()
            .find(|(k, _, _)| k == key)
            .map_or(String::new(), |(_, _, h)| h.clone());
        Err(MemoryError {
            key: key.to_string(),
            part,
            how,
            estimate: total,
            limit,
        })
    }
}

/// The record's estimated size ([`Scene::record_estimate`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RecordEstimate {
    /// Bytes per coupling step (0: no record).
    pub per_step: u64,
    /// Steps, when the scene bounds them (`run.max_steps`, or `run.t_end` over `run.dt_max`).
    pub steps: Option<u64>,
    /// How the bytes per step were counted (for the messages).
    pub how: String,
}

/// Bytes of a solid state per particle in a frame, 2-D and 3-D: centre, orientation,
/// velocities, diameter and its part of the wet surface.
///
/// NOTE: measured on `clamped-beam-2d` at 200 x 100 cells (728 particles): 935 kB per step at
/// 3.94 trials per step, 163 B per particle and trial for a state and its loads, of which the
/// loads are 24 B; 3-D from the same count of a cuboid's 8 vertices and 12 triangles. That was
/// every particle and every particle corner both ways, what a body with fracture still sends.
/// Without fracture only the vertices the elements use are carried, and the fluid gets and
/// loads only the particles that own an element (issue 39 item 4): the beam's record then
/// takes 292 kB a step, so for such a scene the estimate is an upper bound (3.4 times).
const STATE_BYTES_PER_PARTICLE: [u64; 2] = [140, 560];

/// Bytes of the loads per particle in a frame (force and torque), 2-D and 3-D.
const LOAD_BYTES_PER_PARTICLE: [u64; 2] = [24, 48];

/// Trials per step assumed for a semi-implicit coupled run (the beam's mean was 3.94).
const TRIALS_ASSUMED: u64 = 4;

/// Bytes per step of the small frames (plan, proposals, totals, decisions) and diagnostics.
const SMALL_BYTES_PER_STEP: u64 = 2 << 10;

impl Scene {
    /// Estimates the bytes `exchange.mcap` takes per step and, when the scene bounds them, the
    /// steps: the states and loads of every trial (each crosses the coupler twice), the
    /// checkpoints, the small frames and the diagnostics.
    pub fn record_estimate(&self) -> RecordEstimate {
        let level = self.run.record;
        let steps = self.run.max_steps.or_else(|| {
            self.run
                .dt_max
                .map(|dt| (self.run.t_end / dt).ceil().min(u64::MAX as f64) as u64)
        });
        let mut how = Vec::new();
        let mut per_step = match level {
            RecordLevel::None => {
                return RecordEstimate {
                    per_step: 0,
                    steps,
                    how: "no record".into(),
                };
            }
            RecordLevel::Diagnostics => 1 << 10,
            _ => SMALL_BYTES_PER_STEP,
        };
        let frames = matches!(level, RecordLevel::All | RecordLevel::Exchange);
        let d = usize::from(self.dim() >= 3);
        let particles: u64 = self
            .solid
            .as_ref()
            .filter(|s| s.node == "real")
            .map_or(0, |s| {
                s.bodies
                    .iter()
                    .map(|body| match &body.shape {
                        Shape::Particles(list) => list.len() as u64,
                        _ => body
                            .divisions
                            .iter()
                            .fold(1u64, |acc, &n| acc.saturating_mul(u64::from(n))),
                    })
                    .fold(0u64, u64::saturating_add)
            });
        if frames && self.fluid.is_some() && particles > 0 {
            let trials = match self.run.scheme {
                super::SchemeName::Explicit => 1,
                super::SchemeName::SemiImplicit => TRIALS_ASSUMED,
            };
            let per_trial =
                2 * particles * (STATE_BYTES_PER_PARTICLE[d] + LOAD_BYTES_PER_PARTICLE[d]);
            per_step = per_step.saturating_add(trials.saturating_mul(per_trial));
            how.push(format!(
                "{trials} trials x {per_trial} B of states and loads of {particles} particles"
            ));
        }
        let every = match level {
            RecordLevel::All => 1,
            RecordLevel::Exchange => self.run.checkpoint_every,
            _ => 0,
        };
        if let Some(nonzero) = std::num::NonZeroU64::new(every) {
            let cells = self
                .fluid
                .as_ref()
                .filter(|f| f.node == "real")
                .map_or(0, |f| {
                    f.cells
                        .iter()
                        .fold(1u64, |acc, &n| acc.saturating_mul(u64::from(n)))
                });
            let checkpoint = cells
                .saturating_mul((self.dim() as u64 + 2) * 8)
                .saturating_add(particles.saturating_mul(2 * STATE_BYTES_PER_PARTICLE[d]));
            per_step = per_step.saturating_add(checkpoint / nonzero);
            how.push(format!("a {checkpoint} B checkpoint every {every} steps"));
        }
        how.push("frames and diagnostics".into());
        RecordEstimate {
            per_step,
            steps,
            how: how.join(", "),
        }
    }
}
