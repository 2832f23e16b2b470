//! `coupler-node check SCENE.toml`: everything `run` checks before it starts a process, without
//! starting one (like `precice-config-validate`).
//!
//! The scene is parsed and validated with the same errors `run` gives (file, key path, line and
//! caret), its memory estimate is compared with what the machine has, and each `replay:FILE`
//! node's record is opened and must hold that node's channels. With `run.solid_substeps =
//! "auto"` the real nodes are built in-process to compute their first proposals, and the K of
//! the first step follows as the coupler would agree it ([`first_substeps`]).

use std::path::Path;

use anyhow::Context;
use protocol::scene::{MAX_SOLID_SUBSTEPS, RecordLevel, Scene, Shape, SolidSubsteps};
use protocol::wire::NodeKind;

use crate::dt::Proposal;

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
    /// A fixed K is the K of every step, the first included; `"auto"` chooses it per step.
    pub solid_substeps: Option<SolidSubsteps>,
    /// With `"auto"`: the K of the first step ([`first_substeps`]).
    pub first_substeps: Option<FirstSubsteps>,
}

/// The solid sub-steps of the first step with `run.solid_substeps = "auto"`.
#[derive(Clone, Debug, PartialEq)]
pub enum FirstSubsteps {
    /// The first step `dt` \[s\] (and who limits it) takes K sub-steps within the solid's
    /// stable step `bound` \[s\].
    Expected {
        /// Sub-steps.
        k: u32,
        /// The first step \[s\].
        dt: f64,
        /// Who limits it (`"fluid:cfl at cell ..."`, `"scene"`, `"output"`).
        limiter: String,
        /// The solid's stable step \[s\].
        bound: f64,
    },
    /// The first step would need more than `run.solid_substeps` allows: the run stops at
    /// step 0, naming the particle of the bound (`limiter`).
    TooMany {
        /// Sub-steps needed.
        needed: u64,
        /// The first step \[s\].
        dt: f64,
        /// The solid's stable step \[s\] and what sets it.
        bound: f64,
        /// What sets the bound (`"dem elastic bound at particle 36"`).
        limiter: String,
    },
    /// Not computed in-process, and why (a node that is not `real`, a node that cannot be
    /// built).
    Unknown(String),
}

/// The K of the first step with `run.solid_substeps = "auto"` (`None` otherwise): the real
/// solid and fluid are built from the scene as the nodes build them, the fluid given the
/// solid's initial surface, and their first proposals agreed on as the coupler agrees them
/// (`dt::agree` with the scene's cap and output times, then `SolidSubsteps::for_step` with the
/// solid's stable step).
pub fn first_substeps(scene: &Scene) -> Option<FirstSubsteps> {
    use fluid_node::model::FluidModel;
    use protocol::session::NodeModel;
    use solid_node::model::SolidModel;
    let cfg = crate::scheme::CouplerConfig::from_scene(scene);
    let setting @ SolidSubsteps::Auto(_) = cfg.substeps? else {
        return None;
    };
    let unknown = |why: String| Some(FirstSubsteps::Unknown(why));
    let solid_cfg = scene.solid.as_ref()?;
    if solid_cfg.node != "real" {
        return unknown(format!("the solid is {}", solid_cfg.node));
    }
    let solid = match solid_node::exchange::RealSolid::from_scene(scene) {
        Ok(s) => s,
        Err(e) => return unknown(format!("the solid cannot be built: {e}")),
    };
    let mut proposals = Vec::new();
    if let Some(f) = &scene.fluid {
        if f.node != "real" {
            return unknown(format!("the fluid is {}", f.node));
        }
        let mut fluid = match fluid_node::exchange::RealFluid::from_scene(scene) {
            Ok(f) => f,
            Err(e) => return unknown(format!("the fluid cannot be built: {e}")),
        };
        if let Err(e) = fluid.set_initial_surface(&solid.state()) {
            return unknown(format!("the fluid refuses the solid's surface: {e}"));
        }
        let limit = fluid.dt_max();
        proposals.push(Proposal {
            node: NodeKind::Fluid,
            dt_max: limit.dt_max,
            limiter: limit.limiter,
        });
    }
    let limit = solid.dt_max();
    proposals.push(Proposal {
        node: NodeKind::Solid,
        dt_max: limit.dt_max,
        limiter: limit.limiter,
    });
    let bound = solid.substep_bound()?;
    let Some(agreed) = crate::dt::agree(0.0, &proposals, cfg.dt_cap, &cfg.outputs, 0) else {
        return unknown("no first step can be agreed".into());
    };
    Some(match setting.for_step(agreed.dt, bound.dt_max) {
        Ok(k) => FirstSubsteps::Expected {
            k,
            dt: agreed.dt,
            limiter: agreed.limiter,
            bound: bound.dt_max,
        },
        Err(needed) => FirstSubsteps::TooMany {
            needed,
            dt: agreed.dt,
            bound: bound.dt_max,
            limiter: bound.limiter,
        },
    })
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
        first_substeps: first_substeps(scene),
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
            Some(SolidSubsteps::Auto(_)) => {
                write!(
                    f,
                    ", solid sub-steps auto (per step: dt over half the solid's stable step, at most {MAX_SOLID_SUBSTEPS}"
                )?;
                match &self.first_substeps {
                    Some(FirstSubsteps::Expected {
                        k,
                        dt,
                        limiter,
                        bound,
                    }) => write!(
                        f,
                        "; the first step {k}: dt {dt:.3e} s ({limiter}) over {bound:.3e} s)"
                    )?,
                    Some(FirstSubsteps::TooMany {
                        needed,
                        dt,
                        bound,
                        limiter,
                    }) => write!(
                        f,
                        "; the first step needs {needed}: dt {dt:.3e} s over {bound:.3e} s ({limiter}), \
                         the run stops at step 0)"
                    )?,
                    Some(FirstSubsteps::Unknown(why)) => {
                        write!(f, "; the first step's K not computed: {why})")?;
                    }
                    None => write!(f, ")")?,
                }
            }
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
