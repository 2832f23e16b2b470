//! Command line of the `solid-node` binary: args → validated config → the node loop, and which
//! model (the DEM or the prescribed double) a scene's implementation name asks for.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use clap::{Parser, Subcommand};
use protocol::serve::{ServeError, ServeOptions, serve};
use protocol::wire::NodeKind;

use crate::error::BuildError;
use crate::node;

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
    #[arg(long, default_value = "120", value_parser = protocol::session::parse_timeout_s, allow_negative_numbers = true)]
    pub timeout_s: Duration,
    /// -v/-q.
    #[command(flatten)]
    pub log: protocol::logs::Verbosity,
    /// Tools.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// Tools of the solid node.
#[derive(Debug, Subcommand)]
pub enum Command {}

/// Entry point of the binary: installs the logs ([`protocol::logs`], lines prefixed `solid`),
/// runs, prints `solid-node: error` and exits 2 on bad input, 3 on
/// numerical failure, 4 when the exchange with the coupler fails.
pub fn main() -> ExitCode {
    let args = Args::parse();
    protocol::logs::init("solid", args.log);
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            protocol::logs::print_report(&format!("solid-node: {err:#}"));
            ExitCode::from(
                err.downcast_ref::<ServeError>()
                    .map_or(2, ServeError::exit_code),
            )
        }
    }
}

fn run(args: Args) -> anyhow::Result<()> {
    if let Some(command) = args.command {
        match command {}
    }
    let opts = ServeOptions {
        scene: args.scene.context("--scene is required")?,
        run_id: args.run_id.context("--run-id is required")?,
        double: args.double,
        timeout: args.timeout_s,
        out: args.out,
    };
    serve(
        NodeKind::Solid,
        &opts,
        |scene, implementation| model_from_scene(scene, implementation).map_err(|e| e.to_string()),
        |mut model, link, cfg| node::run(model.as_mut(), link, cfg),
    )?;
    Ok(())
}

/// Builds the solid implementation named `implementation` (`real` or `prescribed`) for a scene.
pub fn model_from_scene(
    scene: &protocol::scene::Scene,
    implementation: &str,
) -> Result<Box<dyn crate::model::SolidModel + Send>, BuildError> {
    let solid = scene.solid.as_ref().ok_or(BuildError::NoSolidSection)?;
    match implementation {
        "prescribed" => Ok(Box::new(crate::double::PrescribedDouble::new(
            scene.dim(),
            solid
                .prescribed
                .as_ref()
                .ok_or(BuildError::NoPrescribedTable)?,
        ))),
        "real" => Ok(Box::new(crate::exchange::RealSolid::from_scene(scene)?)),
        other => Err(BuildError::UnknownImplementation(other.to_string())),
    }
}
