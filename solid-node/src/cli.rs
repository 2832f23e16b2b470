//! Command line of the `solid-node` binary: args → validated config → the node loop.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use clap::{Parser, Subcommand};
use protocol::scene::Scene;
use protocol::transport::{Link, Transport};
use protocol::wire::NodeKind;

use crate::node::{self, LoopConfig, NodeError};

/// The solid node of the co-simulation (normally started by `coupler-node run`).
#[derive(Debug, Parser)]
#[command(name = "solid-node", version, args_conflicts_with_subcommands = true)]
pub struct Args {
    /// Scene file (TOML).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Run id shared by the three processes (isolates their shared memory).
    #[arg(long)]
    pub run_id: Option<String>,
    /// Output directory for fields and probes.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run a test double instead of the solver: `prescribed` or `replay:FILE.mcap`.
    #[arg(long)]
    pub double: Option<String>,
    /// Deadline for each message from the coupler, in seconds.
    #[arg(long, default_value_t = 120.0)]
    pub timeout_s: f64,
    /// Tools.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// Tools of the solid node.
#[derive(Debug, Subcommand)]
pub enum Command {}

/// Entry point of the binary: prints `solid-node: error` and exits 2 on bad input, 3 on
/// numerical failure, 4 when the exchange with the coupler fails.
pub fn main() -> ExitCode {
    let args = Args::parse();
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("solid-node: {err:#}");
            let code = match err.downcast_ref::<NodeError>() {
                Some(NodeError::Numerical { .. }) => 3,
                Some(NodeError::Link(_)) => 4,
                _ => 2,
            };
            ExitCode::from(code)
        }
    }
}

fn run(args: Args) -> anyhow::Result<()> {
    if let Some(command) = args.command {
        match command {}
    }
    let scene_path = args.scene.context("--scene is required")?;
    let run_id = args.run_id.context("--run-id is required")?;
    let text = std::fs::read_to_string(&scene_path)
        .with_context(|| format!("reading scene {}", scene_path.display()))?;
    let scene = Scene::from_toml_str(&text, &scene_path.display().to_string())?;
    let solid = scene
        .solid
        .as_ref()
        .context("the scene has no [solid] section")?;
    let timeout = Duration::from_secs_f64(args.timeout_s);
    let double = args.double.unwrap_or_else(|| solid.node.clone());
    let mut bus = protocol::bus::Bus::open(&run_id, NodeKind::Solid, &[NodeKind::Coupler])
        .with_context(|| format!("opening the bus for run {run_id}"))?;
    if let Some(file) = double.strip_prefix("replay:") {
        let bytes = std::fs::read(file).with_context(|| format!("reading record {file}"))?;
        let script = protocol::replay::Script::from_mcap(&bytes, NodeKind::Solid)?;
        protocol::replay::play(&mut bus, &script, timeout)?;
        return Ok(());
    }
    let mut model = node::model_from_scene(&scene, &double).map_err(anyhow::Error::msg)?;
    if let Some(out) = &args.out {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    }
    let cfg = LoopConfig {
        scene_hash: scene.hash(),
        coupled: scene.fluid.is_some(),
        out: args.out.clone(),
    };
    let transport: &mut dyn Transport = &mut bus;
    let mut link = Link::new(transport, timeout);
    node::run(model.as_mut(), &mut link, &cfg)?;
    Ok(())
}
