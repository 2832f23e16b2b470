//! `coupler-node check SCENE.toml`: everything `run` checks before it starts a process, without
//! starting one (like `precice-config-validate`).
//!
//! The scene is parsed and validated with the same errors `run` gives (file, key path, line and
//! caret), its memory estimate is compared with what the machine has, and each `replay:FILE`
//! node's record is opened and must hold that node's channels.

use std::path::Path;

use anyhow::Context;
use protocol::scene::{RecordLevel, Scene, Shape};

/// What a valid scene runs, for the summary `check` prints.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckSummary {
    /// Scene name.
    pub name: String,
    /// Dimensions (1, 2 or 3).
    pub dim: usize,
    /// Fluid implementation (`real`, `pressure`, `replay:FILE`) and cells per axis; `None`: no
    /// fluid.
    pub fluid: Option<(String, Vec<u32>)>,
    /// Solid implementation and particle count (`None` for doubles, which have no particles of
    /// their own); `None`: no solid.
    pub solid: Option<(String, Option<u64>)>,
    /// `run.record`.
    pub record: RecordLevel,
    /// `run.t_end` \[s\].
    pub t_end: f64,
    /// Estimated memory \[bytes\] ([`Scene::memory_estimate`]).
    pub memory_bytes: u64,
}

/// Checks the scene at `path` as `run` would with the `--fluid`/`--solid` overrides given
/// (`None`: the scene's own), without starting anything.
pub fn check(
    path: &Path,
    fluid: Option<&str>,
    solid: Option<&str>,
) -> anyhow::Result<CheckSummary> {
    let scene = crate::preflight::load_scene(path, fluid, solid)?;
    scene
        .check_memory(crate::preflight::available_memory()?)
        .with_context(|| path.display().to_string())?;
    crate::preflight::check_replay_doubles(&scene)?;
    crate::preflight::check_fluid_ranks(&scene, None)?;
    Ok(summarize(&scene))
}

/// The summary of a valid scene (pure).
pub fn summarize(scene: &Scene) -> CheckSummary {
    let solid = scene.solid.as_ref().map(|s| {
        let n_particles = (s.node == "real").then(|| {
            s.bodies
                .iter()
                .map(|body| match &body.shape {
                    Shape::Particles(list) => list.len() as u64,
                    _ => body
                        .divisions
                        .iter()
                        .fold(1u64, |acc, &n| acc.saturating_mul(u64::from(n))),
                })
                .sum()
        });
        (s.node.clone(), n_particles)
    });
    CheckSummary {
        name: scene.name.clone(),
        dim: scene.dim(),
        fluid: scene
            .fluid
            .as_ref()
            .map(|f| (f.node.clone(), f.cells.clone())),
        solid,
        record: scene.run.record,
        t_end: scene.run.t_end,
        memory_bytes: scene.memory_estimate().total_bytes(),
    }
}

impl std::fmt::Display for CheckSummary {
    /// `NAME: ok, DIM-D, fluid real 400 cells, solid real 120 particles, record exchange, t_end
    /// 2.000e-1 s, memory 1.2 MiB`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: ok, {}-D", self.name, self.dim)?;
        match &self.fluid {
            Some((node, cells)) => {
                let n_cells = cells.iter().fold(1u64, |acc, &n| acc * u64::from(n));
                let axes: Vec<String> = cells.iter().map(u32::to_string).collect();
                write!(f, ", fluid {node} {n_cells} cells ({})", axes.join("x"))?;
            }
            None => write!(f, ", no fluid")?,
        }
        match &self.solid {
            Some((node, Some(n))) => write!(f, ", solid {node} {n} particles")?,
            Some((node, None)) => write!(f, ", solid {node}")?,
            None => write!(f, ", no solid")?,
        }
        let record = match self.record {
            RecordLevel::All => "all",
            RecordLevel::Exchange => "exchange",
            RecordLevel::Diagnostics => "diagnostics",
            RecordLevel::None => "none",
        };
        write!(
            f,
            ", record {record}, t_end {:.3e} s, memory {:.1} MiB",
            self.t_end,
            self.memory_bytes as f64 / f64::from(1u32 << 20)
        )
    }
}
