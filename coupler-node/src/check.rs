//! `coupler-node check SCENE.toml`: everything `run` checks before it starts a process, without
//! starting one (like `precice-config-validate`).
//!
//! The scene is parsed and validated with the same errors `run` gives (file, key path, line and
//! caret), its memory estimate is compared with what the machine has, and each `replay:FILE`
//! node's record is opened and must hold that node's channels.

use std::path::Path;

use anyhow::Context;
use protocol::scene::{RecordLevel, Scene, Shape, SolidSubsteps};

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
    /// `run.solid_substeps` of a solid that sub-steps (`None`: absent, or a prescribed double).
    /// A fixed K is the K of every step, the first included; `"auto"` chooses it per step from
    /// the solid's stable step and the fluid's first step, which only the nodes compute.
    pub solid_substeps: Option<SolidSubsteps>,
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
        solid_substeps: crate::scheme::CouplerConfig::from_scene(scene).substeps,
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
        match self.solid_substeps {
            Some(SolidSubsteps::Fixed(k)) => write!(f, ", solid sub-steps {k} (every step)")?,
            Some(SolidSubsteps::Auto(_)) => write!(
                f,
                ", solid sub-steps auto (per step: dt over the solid's stable step, at most 256)"
            )?,
            None => {}
        }
        write!(
            f,
            ", record {record}, t_end {:.3e} s, memory {:.1} MiB",
            self.t_end,
            self.memory_bytes as f64 / f64::from(1u32 << 20)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(substeps: &str, node: &str) -> Scene {
        let text = format!(
            "name = \"k\"\n[run]\n{substeps}\n[solid]\nnode = \"{node}\"\ndensity = 1.0\nyoung = 1.0\n\
             poisson = 0.0\n[solid.prescribed]\nmotion = \"fixed\"\nbox = {{ center = [0.0, 0.0], size = [1.0, 1.0] }}\n[[solid.bodies]]\n\
             shape = {{ box = {{ center = [0.0, 0.0], size = [1.0, 1.0] }} }}\ndivisions = [1, 1]\n"
        );
        Scene::from_toml_str(&text, "k.toml").unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn check_reports_the_solid_sub_steps() {
        let fixed = summarize(&scene("solid_substeps = 4", "real")).to_string();
        assert!(
            fixed.contains(", solid sub-steps 4 (every step),"),
            "{fixed}"
        );
        let auto = summarize(&scene("solid_substeps = \"auto\"", "real")).to_string();
        assert!(auto.contains(", solid sub-steps auto (per step"), "{auto}");
        for (key, node) in [("", "real"), ("solid_substeps = 4", "prescribed")] {
            let none = summarize(&scene(key, node)).to_string();
            assert!(!none.contains("sub-steps"), "{none}");
        }
    }
}
