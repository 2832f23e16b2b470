//! The scene file (DESIGN §6): one TOML file describes a whole run; each node reads its part.
//!
//! Parsing is pure: [`Scene::from_toml_str`] takes the text and a name for error messages; only
//! binaries read files. A wrong scene is refused with the file, the key path, what was expected
//! and what was found ([`SceneError`]). Keys of DESIGN §6 are a contract: extend, never rename.
//!
//! One file per section, each with its validation beside its types: `run.rs` (`[run]`),
//! `fluid.rs` (`[fluid]`), `solid.rs` (`[solid]`), `output.rs` (`[output]`), `region.rs` (the
//! regions both sides use), `memory.rs` (what a scene needs before it starts) and `error.rs`
//! (errors and the helpers that word them).

mod error;
mod fluid;
mod limits;
mod memory;
mod output;
mod region;
mod run;
mod solid;

use serde::{Deserialize, Serialize};

pub use error::{FLUID_NODES, SOLID_NODES, SceneError, node_impl};
pub use fluid::{
    Boundary, BoundaryConfig, CharacteristicConfig, DEFAULT_CHARACTERISTIC_SIGMA, FluidConfig,
    FluxConfig, FluxScheme, InitEntry, PressureField, Profile, VacuumConfig,
};
pub use limits::{MAX_FRAME_BYTES, MAX_MAGNITUDE, MAX_NAME_LEN, MAX_OUTPUTS, MAX_PROBES};
pub use memory::{MemoryError, MemoryEstimate, RecordEstimate};
pub use output::{OutputConfig, OutputFormat, ProbeConfig};
pub use region::Region;
pub use run::{
    AUTO_SUBSTEP_FRACTION, DT_MIN_OF_T_END, DT_MIN_RELATIVE, MAX_SOLID_SUBSTEPS, Predictor,
    RECORD_MIN_BYTES, RecordCompression, RecordLevel, Relaxation, RunConfig, SchemeName,
    SolidSubsteps,
};
pub use solid::{
    BodyConfig, BoxSpec, ConstraintConfig, ContactConfig, FaceInertia, FractureConfig, LinksConfig,
    Motion, ParticleSpec, PrescribedConfig, PrescribedMotion, Shape, SolidConfig, SolidInit,
    SolidWalls,
};

use error::{Check, shorten_lines};
use fluid::default_node_impl;

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name used in output names.
    pub name: String,
    /// The time loop and the coupling.
    #[serde(default)]
    pub run: RunConfig,
    /// The fluid side; absent: no fluid process.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fluid: Option<FluidConfig>,
    /// The solid side; absent: no solid process.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solid: Option<SolidConfig>,
    /// What the run writes.
    #[serde(default)]
    pub output: OutputConfig,
}

impl Scene {
    /// Parses and validates a scene; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Scene, SceneError> {
        let de = toml::Deserializer::parse(text).map_err(|err| SceneError::Parse {
            file: file.to_string(),
            path: String::new(),
            message: shorten_lines(err.to_string().trim()),
        })?;
        let scene: Scene = serde_path_to_error::deserialize(de).map_err(|err| {
            let path = err.path().to_string();
            SceneError::Parse {
                file: file.to_string(),
                path: if path == "." { String::new() } else { path },
                message: shorten_lines(err.into_inner().to_string().trim()),
            }
        })?;
        scene.validate(file)?;
        Ok(scene)
    }

    /// Spatial dimension of the run: the fluid grid's, else the first body's.
    pub fn dim(&self) -> usize {
        if let Some(fluid) = &self.fluid {
            return fluid.lower.len();
        }
        let solid = self.solid.as_ref();
        let from_body = solid
            .and_then(|s| s.bodies.first())
            .map(|b| match &b.shape {
                Shape::Box { center, .. }
                | Shape::Ring { center, .. }
                | Shape::Tube { center, .. } => center.len(),
                Shape::Particles(p) => p
                    .first()
                    .and_then(|p| p.vertices.first())
                    .map_or(0, |v| v.len()),
            });
        let from_double = solid
            .and_then(|s| s.prescribed.as_ref())
            .map(|p| p.r#box.center.len());
        from_body.or(from_double).unwrap_or(0)
    }

    /// A stable 64-bit hash (FNV-1a) of the resolved scene, sent in hello messages. Which
    /// implementation runs a side (`fluid.node`, `solid.node`) is not part of it: a double or a
    /// replay stands in for a node of the same scene. Nor is `run.threads`: results do not depend
    /// on it.
    pub fn hash(&self) -> u64 {
        let mut physics = self.clone();
        // NOTE: results do not depend on the thread count, so neither does the hash.
        physics.run.threads = RunConfig::default().threads;
        if let Some(f) = physics.fluid.as_mut() {
            f.node = default_node_impl();
            // Nor on the rank count (issue 16: bit-identical on any number of ranks) or the
            // blocks (issue 40).
            f.ranks = 1;
            f.decomposition = None;
        }
        if let Some(s) = physics.solid.as_mut() {
            s.node = default_node_impl();
        }
        let text = physics.to_toml();
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in text.bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        h
    }

    /// The resolved scene (defaults filled in) as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scene always serializes")
    }

    /// Whether `output.times` holds 0: the initial state is then written as output 0, before
    /// the first step (as Clawpack does), and the outputs of [`Scene::output_times`] follow
    /// from 1.
    pub fn initial_output(&self) -> bool {
        self.output.times.contains(&0.0)
    }

    /// Times at which a step ends on an output, in increasing order, the end time always last
    /// (an output at t = 0 is not among them: see [`Scene::initial_output`]).
    pub fn output_times(&self) -> Vec<f64> {
        let t_end = self.run.t_end;
        let mut times: Vec<f64> = self
            .output
            .times
            .iter()
            .copied()
            .filter(|t| *t > 0.0 && *t < t_end)
            .collect();
        if let Some(every) = self.output.every {
            // NOTE: validation refuses more than `MAX_OUTPUTS`; the cap keeps an unvalidated
            // scene from allocating without bound.
            let n = ((t_end / every).floor() as u64).min(MAX_OUTPUTS);
            for k in 1..=n {
                let t = k as f64 * every;
                if t < t_end * (1.0 - 1e-12) {
                    times.push(t);
                }
            }
        }
        times.push(t_end);
        times.sort_by(f64::total_cmp);
        times.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * t_end.abs().max(1.0));
        times
    }
}

impl Scene {
    /// Checks the whole scene, section by section (each section's rules are beside its types).
    fn validate(&self, file: &str) -> Result<(), SceneError> {
        let c = Check {
            file,
            dim: self.dim(),
        };
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(c.invalid(
                "name",
                "a non-empty name of letters, digits, '-' and '_'",
                shorten_lines(&format!("{:?}", self.name)),
            ));
        }
        self.run.validate(&c)?;
        if self.fluid.is_none() && self.solid.is_none() {
            return Err(c.invalid(
                "fluid",
                "a [fluid] or a [solid] section (or both)",
                "neither".into(),
            ));
        }
        let dim = self.dim();
        if !(1..=3).contains(&dim) {
            return Err(c.invalid(
                if self.fluid.is_some() {
                    "fluid.lower"
                } else {
                    "solid.bodies"
                },
                "1, 2 or 3 coordinates",
                dim.to_string(),
            ));
        }
        if let Some(fluid) = &self.fluid {
            fluid.validate(&c)?;
        }
        if let Some(solid) = &self.solid {
            solid.validate(&c)?;
        }
        self.output
            .validate(&c, self.fluid.is_some(), self.solid.is_some())?;
        self.check_bounds(&c)
    }
}
