//! Command line of the `fluid-node` binary: args → validated config → the node loop.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use clap::{Parser, Subcommand};
use protocol::scene::Scene;
use protocol::serve::{ServeError, ServeOptions, serve};
use protocol::wire::NodeKind;

use crate::node;

/// The fluid node of the co-simulation (normally started by `coupler-node run`).
#[derive(Debug, Parser)]
#[command(name = "fluid-node", version, args_conflicts_with_subcommands = true)]
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
    /// Run a test double instead of the solver: `pressure` or `replay:FILE.mcap`.
    #[arg(long)]
    pub double: Option<String>,
    /// Deadline for each message from the coupler, in seconds.
    #[arg(long, default_value = "120", value_parser = protocol::session::parse_timeout_s, allow_negative_numbers = true)]
    pub timeout_s: Duration,
    /// Print the optional features this binary was built with, one per line (`mpi`), and
    /// exit (the launcher asks before it starts a fluid of several ranks).
    #[arg(long)]
    pub features: bool,
    /// -v/-q.
    #[command(flatten)]
    pub log: protocol::logs::Verbosity,
    /// Tools.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// Tools of the fluid node.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Cut-cell geometry of a surface in a scene's grid: Λ, λ, sub-faces (VTK, CSV) and a JSON
    /// line with volumes, areas, timings and (with --to) swept volumes.
    CutCells(crate::cutcell_cmd::CutCellsArgs),
    /// Studies of the flow solver.
    #[command(subcommand)]
    Report(Report),
}

/// Reports.
#[derive(Debug, Subcommand)]
pub enum Report {
    /// L1 density error against wall time for several resolutions and orders of a 1-D Riemann
    /// scene, with a second-order TVD reference; writes a CSV table and an SVG plot.
    WorkPrecision {
        /// A 1-D scene with two constant states (e.g. scenes/sod.toml).
        scene: PathBuf,
        /// Cell counts.
        #[arg(long, value_delimiter = ',', default_value = "100,200,400,800,1600")]
        cells: Vec<u32>,
        /// OSMP orders.
        #[arg(long, value_delimiter = ',', default_value = "3,5,7")]
        orders: Vec<u32>,
        /// Output directory.
        #[arg(long, default_value = "out/report")]
        out: PathBuf,
    },
}

/// Optional features of this build (`--features`).
pub const FEATURES: &[&str] = &[
    #[cfg(feature = "mpi")]
    "mpi",
];

/// `fluid.ranks` of a scene file (1 when it has no `[fluid]`; a bad scene is reported by the
/// node loop as usual).
fn fluid_ranks(scene: &std::path::Path) -> anyhow::Result<u32> {
    let text = std::fs::read_to_string(scene)
        .with_context(|| format!("reading scene {}", scene.display()))?;
    Ok(Scene::from_toml_str(&text, &scene.display().to_string())
        .ok()
        .and_then(|s| s.fluid.map(|f| f.ranks))
        .unwrap_or(1))
}

/// Entry point of the binary: installs the logs ([`protocol::logs`], lines prefixed `fluid`),
/// runs, prints `fluid-node: error` and exits 2 on bad input, 3 on
/// numerical failure, 4 when the exchange with the coupler fails.
pub fn main() -> ExitCode {
    let args = Args::parse();
    protocol::logs::init("fluid", args.log);
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            protocol::logs::print_report(&format!("fluid-node: {err:#}"));
            ExitCode::from(
                err.downcast_ref::<ServeError>()
                    .map_or(2, ServeError::exit_code),
            )
        }
    }
}

fn run(args: Args) -> anyhow::Result<()> {
    if let Some(command) = args.command {
        return match command {
            Command::CutCells(args) => crate::cutcell_cmd::run(&args),
            Command::Report(Report::WorkPrecision {
                scene,
                cells,
                orders,
                out,
            }) => {
                let text = std::fs::read_to_string(&scene)
                    .with_context(|| format!("reading scene {}", scene.display()))?;
                let scene = Scene::from_toml_str(&text, &scene.display().to_string())?;
                let rows = crate::report::work_precision(&scene, &cells, &orders, &out)?;
                print!("{}", crate::report::to_csv(&rows));
                tracing::info!(
                    "wrote {0}/work_precision_{1}.csv and {0}/work_precision_{1}.svg",
                    out.display(),
                    scene.name
                );
                Ok(())
            }
        };
    }
    if args.features {
        for feature in FEATURES {
            println!("{feature}");
        }
        return Ok(());
    }
    let opts = ServeOptions {
        scene: args.scene.context("--scene is required")?,
        run_id: args.run_id.context("--run-id is required")?,
        double: args.double,
        timeout: args.timeout_s,
        out: args.out,
    };
    let ranks = fluid_ranks(&opts.scene)?;
    if ranks > 1 {
        #[cfg(feature = "mpi")]
        return crate::ranks::launch::serve_ranks(&opts, ranks);
        #[cfg(not(feature = "mpi"))]
        anyhow::bail!(
            "fluid.ranks = {ranks} but this fluid-node was built without MPI (build it with \
             `cargo build --release -p fluid-node --features mpi`)"
        );
    }
    serve(
        NodeKind::Fluid,
        &opts,
        |scene, implementation| {
            // The wire boundary: `serve` reports the text to the coupler.
            model_from_scene(scene, implementation).map_err(|e| e.to_string())
        },
        |mut model, link, cfg| node::run(model.as_mut(), link, cfg),
    )?;
    Ok(())
}

/// Builds the fluid implementation named `implementation` (`real` or `pressure`) for a scene.
pub fn model_from_scene(
    scene: &protocol::scene::Scene,
    implementation: &str,
) -> Result<Box<dyn crate::model::FluidModel + Send>, crate::Error> {
    let fluid = scene.fluid.as_ref().ok_or(crate::Error::NoFluid)?;
    match implementation {
        "pressure" => Ok(Box::new(crate::double::PressureDouble::new(
            scene.dim(),
            fluid
                .pressure
                .clone()
                .ok_or(crate::Error::NoPressureField)?,
        ))),
        "real" => Ok(Box::new(crate::exchange::RealFluid::from_scene(scene)?)),
        other => Err(crate::Error::UnknownImplementation {
            implementation: other.to_string(),
        }),
    }
}
