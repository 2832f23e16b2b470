//! What `run`, `check` and `replay` look up and check before any process starts: the scene
//! with the `--fluid`/`--solid`/`--fluid-ranks` choices applied, the memory the machine has,
//! the records of `replay:FILE` nodes, and where the node binaries are.
//!
//! Below [`crate::launch`], [`crate::check`] and [`crate::replay`], which all use it.

use std::path::{Path, PathBuf};

use anyhow::Context;
use protocol::scene::Scene;
use protocol::wire::NodeKind;

/// Reads and validates a scene, applying implementation overrides; returns it with its path.
pub fn load_scene(path: &Path, fluid: Option<&str>, solid: Option<&str>) -> anyhow::Result<Scene> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading scene {}", path.display()))?;
    let name = path.display().to_string();
    let mut scene = Scene::from_toml_str(&text, &name)?;
    if let Some(choice) = fluid {
        let f = scene.fluid.as_mut().with_context(|| {
            format!("{name}: --fluid {choice} but the scene has no [fluid] section")
        })?;
        f.node = choice.to_string();
    }
    if let Some(choice) = solid {
        let s = scene.solid.as_mut().with_context(|| {
            format!("{name}: --solid {choice} but the scene has no [solid] section")
        })?;
        s.node = choice.to_string();
    }
    if fluid.is_some() || solid.is_some() {
        // Validate again with the choices applied (a real node needs more keys than a double).
        scene = Scene::from_toml_str(&scene.to_toml(), &name)?;
    }
    Ok(scene)
}

/// `scene` with `fluid.ranks = ranks`, validated again.
pub fn with_fluid_ranks(mut scene: Scene, ranks: u32, path: &Path) -> anyhow::Result<Scene> {
    let name = path.display().to_string();
    let f = scene
        .fluid
        .as_mut()
        .with_context(|| format!("{name}: --fluid-ranks {ranks} but the scene has no [fluid]"))?;
    f.ranks = ranks;
    Ok(Scene::from_toml_str(&scene.to_toml(), &name)?)
}

/// Memory the machine can give a run, in bytes: `MemAvailable` of `/proc/meminfo` (`MemTotal`
/// on kernels without it).
pub fn available_memory() -> anyhow::Result<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").context("reading /proc/meminfo")?;
    let field = |name: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|rest| {
                rest.trim()
                    .trim_end_matches("kB")
                    .trim()
                    .parse::<u64>()
                    .ok()
            })
            .map(|kib| kib * 1024)
    };
    field("MemAvailable:")
        .or_else(|| field("MemTotal:"))
        .context("/proc/meminfo has neither MemAvailable nor MemTotal")
}

/// Checks, before any process starts, that every `replay:FILE` node of `scene` names a record
/// that reads and holds messages of that node (the node reads `FILE` from the same directory).
pub fn check_replay_doubles(scene: &Scene) -> anyhow::Result<()> {
    let nodes = [
        (
            NodeKind::Fluid,
            scene.fluid.as_ref().map(|f| f.node.as_str()),
        ),
        (
            NodeKind::Solid,
            scene.solid.as_ref().map(|s| s.node.as_str()),
        ),
    ];
    for (node, choice) in nodes {
        let Some(file) = choice.and_then(|c| c.strip_prefix("replay:")) else {
            continue;
        };
        let key = format!("{node}.node = \"replay:{file}\"");
        let bytes =
            std::fs::read(file).with_context(|| format!("{key}: reading the record {file}"))?;
        protocol::replay::Script::from_mcap(&bytes, node)
            .with_context(|| format!("{key}: the record {file} cannot be replayed"))?;
    }
    Ok(())
}

/// The binary of a node: explicit path, `COSIM_<NODE>_BIN`, or beside this executable.
pub fn node_binary(node: NodeKind, explicit: Option<&Path>) -> anyhow::Result<PathBuf> {
    if let Some(p) = explicit {
        return Ok(p.to_path_buf());
    }
    let var = format!("COSIM_{}_BIN", node.name().to_uppercase());
    if let Ok(p) = std::env::var(&var) {
        return Ok(PathBuf::from(p));
    }
    let exe = std::env::current_exe().context("locating this executable")?;
    let dir = exe.parent().context("this executable has no directory")?;
    let name = format!("{}-node{}", node.name(), std::env::consts::EXE_SUFFIX);
    let path = dir.join(&name);
    anyhow::ensure!(
        path.exists(),
        "{name} not found beside {} (build the workspace, or set {var})",
        exe.display()
    );
    Ok(path)
}
