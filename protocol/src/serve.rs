//! The part of a node binary that both nodes share: read the scene, open the bus, then either
//! play a recorded node back (`replay:FILE.mcap`) or build the node's model and run its loop.
//! The exit codes are decided here too, so that both binaries report failures alike.

use std::path::PathBuf;
use std::time::Duration;

use crate::bus::Bus;
use crate::replay::{Script, play};
use crate::scene::Scene;
use crate::session::{LoopConfig, NodeError};
use crate::transport::{Link, LinkError, Transport, TransportError};
use crate::wire::NodeKind;

/// Exit status of a process interrupted by SIGINT, SIGTERM (or, for the coupler, SIGHUP) that
/// ended cleanly: the shell's 128 + SIGINT.
pub const EXIT_INTERRUPTED: u8 = 130;

/// What a node binary was asked to run.
#[derive(Clone, Debug)]
pub struct ServeOptions {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Run id shared by the three processes.
    pub run_id: String,
    /// Implementation replacing the scene's `node` key (`real`, a double's name, or
    /// `replay:FILE.mcap`).
    pub double: Option<String>,
    /// Deadline for each message from the coupler.
    pub timeout: Duration,
    /// Output directory (`None`: write nothing).
    pub out: Option<PathBuf>,
}

/// How a node binary failed.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// Bad input (scene, options, record) or a replay that could not be played.
    #[error("{0}")]
    Input(String),
    /// The node loop ended in error.
    #[error(transparent)]
    Node(#[from] NodeError),
}

impl ServeError {
    /// Exit code of a node binary: 3 numerical failure, 4 exchange with the coupler failed,
    /// [`EXIT_INTERRUPTED`] interrupted by SIGINT or SIGTERM, 2 otherwise (bad input, outputs not
    /// written).
    pub fn exit_code(&self) -> u8 {
        match self {
            ServeError::Node(NodeError::Numerical { .. }) => 3,
            ServeError::Node(NodeError::Link(LinkError::Transport(
                TransportError::Interrupted,
            ))) => EXIT_INTERRUPTED,
            ServeError::Node(NodeError::Link(_)) => 4,
            _ => 2,
        }
    }
}

/// Runs node `kind` as `opts` says: `build` makes the model from the scene and the
/// implementation's name, `run` drives it over the bus.
pub fn serve<M>(
    kind: NodeKind,
    opts: &ServeOptions,
    build: impl FnOnce(&Scene, &str) -> Result<M, String>,
    run: impl FnOnce(M, &mut Link<'_>, &LoopConfig) -> Result<(), NodeError>,
) -> Result<(), ServeError> {
    let input = ServeError::Input;
    crate::bus::die_with_parent().map_err(|e| input(format!("starting: {e}")))?;
    let text = std::fs::read_to_string(&opts.scene)
        .map_err(|e| input(format!("reading scene {}: {e}", opts.scene.display())))?;
    let scene = Scene::from_toml_str(&text, &opts.scene.display().to_string())
        .map_err(|e| input(e.to_string()))?;
    let (node, coupled) = match kind {
        NodeKind::Fluid => (
            scene.fluid.as_ref().map(|f| f.node.clone()),
            scene.solid.is_some(),
        ),
        NodeKind::Solid => (
            scene.solid.as_ref().map(|s| s.node.clone()),
            scene.fluid.is_some(),
        ),
        NodeKind::Coupler => return Err(input("the coupler is not served as a node".into())),
    };
    let node = node.ok_or_else(|| input(format!("the scene has no [{kind}] section")))?;
    let implementation = opts.double.clone().unwrap_or(node);
    tracing::debug!(
        "started: {implementation} {kind}, scene {}, run {}, pid {}",
        opts.scene.display(),
        opts.run_id,
        std::process::id()
    );
    let mut bus = Bus::open(&opts.run_id, kind, &[NodeKind::Coupler])
        .map_err(|e| input(format!("opening the bus for run {}: {e}", opts.run_id)))?;
    if let Some(file) = implementation.strip_prefix("replay:") {
        let bytes =
            std::fs::read(file).map_err(|e| input(format!("reading record {file}: {e}")))?;
        let script = Script::from_mcap(&bytes, kind)
            .map_err(|e| input(format!("reading record {file}: {e}")))?;
        tracing::debug!(
            "playing the {kind} node of record {file}: {} frames{}",
            script.frames.len(),
            if script.truncated { " (cut short)" } else { "" }
        );
        play(&mut bus, &script, opts.timeout).map_err(|e| input(e.to_string()))?;
        tracing::debug!("played record {file} to its end");
        return Ok(());
    }
    let model = build(&scene, &implementation).map_err(input)?;
    if let Some(out) = &opts.out {
        std::fs::create_dir_all(out)
            .map_err(|e| input(format!("creating {}: {e}", out.display())))?;
    }
    let cfg = LoopConfig {
        scene_hash: scene.hash(),
        coupled,
        out: opts.out.clone(),
        initial_output: scene.initial_output(),
    };
    let transport: &mut dyn Transport = &mut bus;
    let mut link = Link::new(transport, opts.timeout);
    run(model, &mut link, &cfg)?;
    tracing::debug!("finished");
    Ok(())
}
