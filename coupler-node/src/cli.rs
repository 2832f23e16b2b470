//! Command line of the `coupler-node` binary: `run`, `check`, `replay`, `inspect`, `report`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use clap::{Parser, Subcommand, ValueEnum};
use protocol::logs::Verbosity;
use protocol::wire::NodeKind;

use crate::launch::{self, RunOptions};

/// Couples a fluid node and a solid node over shared memory, records the exchange, replays it.
#[derive(Debug, Parser)]
#[command(name = "coupler-node", version, after_long_help = AFTER_LONG_HELP)]
pub struct Args {
    /// -v/-q.
    #[command(flatten)]
    pub log: protocol::logs::Verbosity,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

impl Args {
    /// The `-v`/`-q` counts.
    pub fn verbosity(&self) -> Verbosity {
        self.log
    }
}

/// Examples and exit codes, at the end of `coupler-node --help`.
const AFTER_LONG_HELP: &str = "\
Examples:
  coupler-node check scenes/sod.toml
  coupler-node run scenes/sod.toml --out out/sod
  coupler-node run scenes/clamped-beam-2d.toml --solid prescribed --quiet
  coupler-node run scenes/backbone-doubles.toml -v       (debug lines of all three processes)
  RUST_LOG=coupler_node=trace coupler-node run scenes/sod.toml
  coupler-node inspect out/sod/exchange.mcap --step 10 --export json
  coupler-node replay out/sod/exchange.mcap --node fluid --step 10
  coupler-node report figures out/sod

Logs:
  stderr, one line per event, prefixed with the process: `coupler  INFO ...`, `fluid   DEBUG ...`;
  the level is info, -v debug, -vv trace, -q warn, -qq error, or RUST_LOG's when it is set.

Exit codes:
  0    success (a replay: identical)
  1    a replay differs from the record
  2    an error: bad arguments, a bad scene or record, a failed run
  130  a run interrupted by SIGINT, SIGTERM or SIGHUP (its summary is written)";

/// `replay --node`: which process is re-run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum NodeArg {
    /// The fluid node.
    Fluid,
    /// The solid node.
    Solid,
    /// The coupler's state machine on the recorded node messages, from its checkpoint.
    Coupler,
}

impl From<NodeArg> for NodeKind {
    fn from(node: NodeArg) -> NodeKind {
        match node {
            NodeArg::Fluid => NodeKind::Fluid,
            NodeArg::Solid => NodeKind::Solid,
            NodeArg::Coupler => NodeKind::Coupler,
        }
    }
}

/// `--fluid VALUE`: a fluid node implementation, checked where it is given (a misspelt one was
/// blamed on the scene's `fluid.node`).
fn parse_fluid_node(value: &str) -> Result<String, String> {
    protocol::scene::node_impl(value, &protocol::scene::FLUID_NODES)
        .map(|()| value.to_string())
        .map_err(|e| format!("expected {e}"))
}

/// `--solid VALUE`: a solid node implementation (see [`parse_fluid_node`]).
fn parse_solid_node(value: &str) -> Result<String, String> {
    protocol::scene::node_impl(value, &protocol::scene::SOLID_NODES)
        .map(|()| value.to_string())
        .map_err(|e| format!("expected {e}"))
}

/// `--export VALUE`, with the nearest format suggested (clap's own suggestion misses a
/// transposition such as `cvs`).
fn parse_export(value: &str) -> Result<ExportArg, String> {
    ExportArg::from_str(value, true).map_err(|_| {
        let names = ["json", "csv"];
        format!(
            "expected one of {names:?}{}",
            protocol::suggest::did_you_mean(value, &names)
        )
    })
}

/// `inspect --export`: the export format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExportArg {
    /// One step's messages as one JSON document.
    Json,
    /// One tidy table, `step,iteration,channel,field,index,value`, one row per number.
    Csv,
}

impl From<ExportArg> for crate::inspect::ExportFormat {
    fn from(format: ExportArg) -> crate::inspect::ExportFormat {
        match format {
            ExportArg::Json => crate::inspect::ExportFormat::Json,
            ExportArg::Csv => crate::inspect::ExportFormat::Csv,
        }
    }
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scene end to end: start the nodes it needs, couple them, write OUT.
    Run {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Output directory (default `out/<scene name>`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace the files of an earlier run in the output directory (without it, a
        /// non-empty output directory is refused; entries no run writes are never removed).
        #[arg(long)]
        overwrite: bool,
        /// Fluid implementation: `real`, `pressure` or `replay:FILE.mcap` (default: the scene's).
        #[arg(long, value_parser = parse_fluid_node)]
        fluid: Option<String>,
        /// Solid implementation: `real`, `prescribed` or `replay:FILE.mcap` (default: the scene's).
        #[arg(long, value_parser = parse_solid_node)]
        solid: Option<String>,
        /// Deadline for any one message, in seconds.
        #[arg(long, default_value = "120", value_parser = protocol::session::parse_timeout_s, allow_negative_numbers = true)]
        timeout_s: Duration,
        /// Resume from the checkpoints this record holds at `--step` (a run of the same scene;
        /// its steps from there are those of the recorded run, bit for bit).
        #[arg(long, requires = "step")]
        restart: Option<PathBuf>,
        /// The step to restart at (one with checkpoints: a multiple of `run.checkpoint_every`).
        #[arg(long, requires = "restart")]
        step: Option<u64>,
        /// Run the fluid on this many MPI ranks (overrides `fluid.ranks`; needs mpirun and a
        /// fluid-node built with `--features mpi`).
        #[arg(long)]
        fluid_ranks: Option<u32>,
        /// Host file for `mpirun --hostfile` (a fluid of several ranks on several machines).
        #[arg(long)]
        hostfile: Option<PathBuf>,
    },
    /// Check a scene without running it: parse and validate it (the errors `run` gives), compare
    /// its memory estimate with the machine, open each `replay:FILE` record it names; print a
    /// one-line summary. Exit 0 when `run` would start, 2 otherwise.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Check with this fluid implementation (as `run --fluid`).
        #[arg(long, value_parser = parse_fluid_node)]
        fluid: Option<String>,
        /// Check with this solid implementation (as `run --solid`).
        #[arg(long, value_parser = parse_solid_node)]
        solid: Option<String>,
    },
    /// Re-run one node (or the coupler) on the recorded inputs up to step N and compare its
    /// outputs.
    Replay {
        /// The record.
        file: PathBuf,
        /// Last step to replay.
        #[arg(long)]
        step: u64,
        /// Which node.
        #[arg(long, value_enum)]
        node: NodeArg,
        /// Implementation to run (default: the one recorded in its hello).
        #[arg(long)]
        double: Option<String>,
        /// Deadline for any one message, in seconds.
        #[arg(long, default_value = "120", value_parser = protocol::session::parse_timeout_s, allow_negative_numbers = true)]
        timeout_s: Duration,
    },
    /// List the steps of a record, export one step's arrays, export every number as one tidy
    /// CSV table, or recover a killed run's file.
    Inspect {
        /// The record.
        file: PathBuf,
        /// Step to export (`--export json` needs it; `--export csv` without it exports every
        /// step).
        #[arg(long)]
        step: Option<u64>,
        /// Export format, `json` or `csv` (default with `--step`: json).
        #[arg(long, value_parser = parse_export)]
        export: Option<ExportArg>,
        /// `--export csv`: only these steps, `FROM..TO` (both included), `FROM..` or `..TO`.
        #[arg(long, value_parser = parse_steps, conflicts_with = "step")]
        steps: Option<std::ops::RangeInclusive<u64>>,
        /// `--export csv`: only this channel (`/fluid-to-coupler`, `/diagnostics`, ...;
        /// repeat for several).
        #[arg(long)]
        channel: Vec<String>,
        /// Rewrite a killed or damaged record into FILE.recovered.mcap: keeps every chunk that
        /// verifies, says what it dropped, and lists the recovered record.
        #[arg(long)]
        recover: bool,
    },
    /// Draw the papers' figures from a run's outputs.
    #[command(subcommand)]
    Report(Report),
}

/// `coupler-node report` subcommands.
#[derive(Debug, Subcommand)]
pub enum Report {
    /// Every figure a run's outputs allow: energy error, probes, fields (PNG), SVG + CSV.
    Figures {
        /// The run's output folder.
        run: PathBuf,
        /// Where the figures and their page, index.html, go (default RUN/report).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Also the normal stress against the azimuthal angle about the solid's centroid.
        #[arg(long)]
        polar: bool,
    },
    /// The energy errors of several runs on one chart, each times its scale (paper 003 Fig. 7).
    Energy {
        /// The runs' output folders.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// One factor per run, comma-separated (for example 1,4,16).
        #[arg(long, value_delimiter = ',')]
        scale: Vec<f64>,
        /// The SVG to write (its numbers go beside it as CSV).
        #[arg(long)]
        out: PathBuf,
    },
    /// Error against wall time of coupled runs: the energy error and the probed particle's x
    /// against a reference run (for example on a grid twice as fine).
    WorkPrecision {
        /// The runs' output folders.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// The reference run's output folder.
        #[arg(long)]
        reference: PathBuf,
        /// The particle probe compared.
        #[arg(long, default_value = "tip")]
        probe: String,
        /// The SVG to write (energy error beside it as `*_energy.svg`, the table as CSV).
        #[arg(long)]
        out: PathBuf,
    },
    /// The largest pressure deviation over the fluid cells of each output against time, one
    /// curve per run (paper 003 Fig. 5).
    Pressure {
        /// The runs' output folders.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// The pressure the gas should keep.
        #[arg(long)]
        reference: f64,
        /// The SVG to write (its numbers go beside it as CSV).
        #[arg(long)]
        out: PathBuf,
    },
}

/// Entry point: exit 0 on success, 1 when a replay differs, 2 on errors,
/// [`launch::EXIT_INTERRUPTED`] (130) when SIGINT, SIGTERM or SIGHUP interrupted a run.
pub fn main() -> ExitCode {
    let args = Args::parse();
    protocol::logs::init_with_writer(
        "coupler",
        args.verbosity(),
        crate::progress::LogLines::new(),
    );
    match dispatch(args) {
        Ok(code) => code,
        Err(err) => {
            protocol::logs::print_report(&format!("coupler-node: {err:#}"));
            if err.downcast_ref::<launch::Interrupted>().is_some() {
                ExitCode::from(launch::EXIT_INTERRUPTED)
            } else {
                ExitCode::from(2)
            }
        }
    }
}

fn dispatch(args: Args) -> anyhow::Result<ExitCode> {
    let verbosity = args.verbosity();
    match args.command {
        Command::Run {
            scene,
            out,
            overwrite,
            fluid,
            solid,
            timeout_s,
            restart,
            step,
            fluid_ranks,
            hostfile,
        } => run(RunOptions {
            out: out.unwrap_or_else(|| default_out(&scene)),
            scene,
            overwrite,
            fluid,
            solid,
            timeout: timeout_s,
            progress: verbosity.quiet == 0,
            verbosity,
            fluid_bin: None,
            solid_bin: None,
            restart: restart.zip(step),
            fluid_ranks,
            hostfile,
        }),
        Command::Check {
            scene,
            fluid,
            solid,
        } => {
            let summary = crate::check::check(&scene, fluid.as_deref(), solid.as_deref())?;
            println!("{summary}");
            Ok(ExitCode::SUCCESS)
        }
        Command::Replay {
            file,
            step,
            node,
            double,
            timeout_s,
        } => replay(&crate::replay::ReplayOptions {
            file,
            step,
            node: NodeKind::from(node),
            implementation: double,
            timeout: timeout_s,
            bin: None,
            verbosity,
        }),
        Command::Report(report) => self::report(report),
        Command::Inspect {
            file,
            step,
            export,
            steps,
            channel,
            recover,
        } => {
            end_quietly_on_a_closed_pipe();
            if export == Some(ExportArg::Csv) && !recover {
                let steps = step.map(|s| s..=s).or(steps).unwrap_or(0..=u64::MAX);
                let filter = crate::inspect::TableFilter {
                    steps,
                    channels: channel,
                };
                return export_csv(&file, step, &filter);
            }
            if steps.is_some() || !channel.is_empty() {
                anyhow::bail!("--steps and --channel filter --export csv");
            }
            inspect(&file, step, export, recover)
        }
    }
}

/// `inspect` piped into `head` ends when its reader does, silently, as Unix tools do: Rust
/// ignores SIGPIPE, so `print!` panicked on the closed pipe ("failed printing to stdout") and a
/// streamed export reported a write error. Only for `inspect`, which writes nothing but its
/// output: `run` keeps ignoring SIGPIPE and finishes its record whoever reads its progress.
fn end_quietly_on_a_closed_pipe() {
    // SAFETY: `signal` with SIG_DFL installs no handler; this runs on the main thread before
    // any other thread of this command exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// `out/<scene name>`, or `out/run` when the scene does not read (`run` then reports why).
fn default_out(scene: &std::path::Path) -> PathBuf {
    // The scene is read twice (here for its name); errors surface in `run`.
    let name = crate::preflight::load_scene(scene, None, None)
        .map(|s| s.name)
        .unwrap_or_else(|_| "run".into());
    PathBuf::from("out").join(name)
}

/// `coupler-node run`.
fn run(options: RunOptions) -> anyhow::Result<ExitCode> {
    let summary = launch::run(&options)?;
    tracing::info!(
        "{}: {} in {} steps, t = {:.6e} s, wall {:.2} s, iterations mean {:.2} max {}, mass err {:.2e}, energy err {:.2e}; outputs in {}",
        summary.scene,
        summary.status,
        summary.steps,
        summary.t_end,
        summary.wall_s,
        summary.coupling_iterations.mean,
        summary.coupling_iterations.max,
        summary.mass_rel_err,
        summary.energy_rel_err,
        options.out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// `coupler-node replay`: 0 when identical, 1 when the replay differs.
fn replay(options: &crate::replay::ReplayOptions) -> anyhow::Result<ExitCode> {
    match crate::replay::replay(options)? {
        crate::replay::Outcome::Identical {
            compared,
            from_step,
        } => {
            println!("identical");
            tracing::info!(
                "{compared} {} messages compared, steps {from_step} to {}",
                options.node,
                options.step
            );
            Ok(ExitCode::SUCCESS)
        }
        crate::replay::Outcome::Differs(diff) => {
            println!("differs: {diff}");
            Ok(ExitCode::from(1))
        }
    }
}

/// `coupler-node report ...`.
fn report(report: Report) -> anyhow::Result<ExitCode> {
    match report {
        Report::Figures { run, out, polar } => {
            let out = out.unwrap_or_else(|| run.join("report"));
            for path in crate::report::figures(&run, &out, polar)? {
                println!("{}", path.display());
            }
        }
        Report::Pressure {
            runs,
            reference,
            out,
        } => {
            crate::report::pressure(&runs, reference, &out)?;
            println!("{}", out.display());
        }
        Report::WorkPrecision {
            runs,
            reference,
            probe,
            out,
        } => {
            println!("run,group,wall_s,steps,energy_error,displacement_error");
            for p in crate::report::work_precision(&runs, &reference, &probe, &out)? {
                println!(
                    "{},{},{:.3},{},{:.3e},{:.3e}",
                    p.run, p.group, p.wall_s, p.steps, p.energy_error, p.displacement_error
                );
            }
        }
        Report::Energy { runs, scale, out } => {
            crate::report::energy(&runs, &scale, &out)?;
            println!("{}", out.display());
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `coupler-node inspect`.
fn inspect(
    file: &std::path::Path,
    step: Option<u64>,
    export: Option<ExportArg>,
    recover: bool,
) -> anyhow::Result<ExitCode> {
    let rec = read_for_inspection(file, recover)?;
    let format = export.map(crate::inspect::ExportFormat::from);
    match (step, format) {
        (Some(step), format) => {
            let format = format.unwrap_or(crate::inspect::ExportFormat::Json);
            print!("{}", crate::inspect::export_step(&rec, step, format)?);
        }
        (None, Some(crate::inspect::ExportFormat::Csv)) => {
            print!("{}", crate::inspect::export_table(&rec, None)?);
        }
        (None, Some(crate::inspect::ExportFormat::Json)) => {
            anyhow::bail!(
                "--export json exports one step: add --step N (--export csv without --step exports them all)"
            )
        }
        (None, None) => {
            if !recover && let Some(end) = crate::inspect::describe_end(&rec.end) {
                tracing::warn!("{}: {end}; --recover rewrites it whole", file.display());
            }
            print!("{}", crate::inspect::list_steps(&rec)?);
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `inspect FILE --export csv`: the tidy table of the messages `filter` keeps, streamed from the
/// file to standard output in bounded memory; `step`: the one step asked for, which must be
/// there.
fn export_csv(
    file: &std::path::Path,
    step: Option<u64>,
    filter: &crate::inspect::TableFilter,
) -> anyhow::Result<ExitCode> {
    let input =
        std::fs::File::open(file).with_context(|| format!("reading record {}", file.display()))?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let summary = crate::inspect::stream_table(input, filter, &mut out).with_context(|| {
        format!(
            "exporting record {} (--recover keeps what verifies)",
            file.display()
        )
    })?;
    if let Some(end) = crate::inspect::describe_end(&summary.end) {
        tracing::warn!("{}: {end}", file.display());
    }
    if summary.messages == 0 {
        let held = summary.steps.map_or_else(
            || "no steps".to_string(),
            |(first, last)| format!("steps {first} to {last}"),
        );
        match step {
            Some(step) => anyhow::bail!("step {step} is not in the recording (it holds {held})"),
            None => tracing::warn!("no message matched the filter (the record holds {held})"),
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `--steps FROM..TO` (both included), `FROM..`, `..TO`.
fn parse_steps(value: &str) -> Result<std::ops::RangeInclusive<u64>, String> {
    let (from, to) = value
        .split_once("..")
        .ok_or_else(|| format!("expected FROM..TO, FROM.. or ..TO, found {value:?}"))?;
    let bound = |text: &str, default: u64| -> Result<u64, String> {
        let text = text.trim_start_matches('=');
        if text.is_empty() {
            Ok(default)
        } else {
            text.parse()
                .map_err(|e| format!("{text:?} is not a step number: {e}"))
        }
    };
    let (from, to) = (bound(from, 0)?, bound(to, u64::MAX)?);
    if from > to {
        return Err(format!("the range {value:?} is empty ({from} > {to})"));
    }
    Ok(from..=to)
}

/// The record `file`; with `recover`, what of it verifies, also written beside it as
/// `*.recovered.mcap`.
fn read_for_inspection(
    file: &std::path::Path,
    recover: bool,
) -> anyhow::Result<crate::record::Recording> {
    let bytes =
        std::fs::read(file).with_context(|| format!("reading record {}", file.display()))?;
    if !recover {
        return crate::record::read_recording(&bytes).with_context(|| {
            format!(
                "reading record {} (--recover keeps what verifies)",
                file.display()
            )
        });
    }
    let fixed =
        crate::record::recover(&bytes).with_context(|| format!("recovering {}", file.display()))?;
    let target = file.with_extension("recovered.mcap");
    std::fs::write(&target, &fixed.bytes)
        .with_context(|| format!("writing {}", target.display()))?;
    for dropped in &fixed.dropped {
        tracing::warn!("dropped {dropped}");
    }
    tracing::info!(
        "wrote {}: {} messages kept, {} damaged part{} dropped",
        target.display(),
        fixed.recording.messages.len(),
        fixed.dropped.len(),
        if fixed.dropped.len() == 1 { "" } else { "s" }
    );
    Ok(fixed.recording)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The error clap prints for `args`.
    fn refusal(args: &[&str]) -> String {
        let err = Args::try_parse_from(args).expect_err("refused");
        err.to_string()
    }

    #[test]
    fn misspelt_values_name_the_option_and_the_nearest_value() {
        let e = refusal(&["coupler-node", "inspect", "x.mcap", "--export", "cvs"]);
        assert!(
            e.contains("invalid value 'cvs' for '--export <EXPORT>'")
                && e.contains("(did you mean `csv`?)"),
            "{e}"
        );
        let e = refusal(&["coupler-node", "run", "s.toml", "--fluid", "pressur"]);
        assert!(
            e.contains("invalid value 'pressur' for '--fluid <FLUID>'")
                && e.contains("(did you mean `pressure`?)"),
            "{e}"
        );
        let e = refusal(&["coupler-node", "check", "s.toml", "--solid", "prescibed"]);
        assert!(
            e.contains("'--solid <SOLID>'") && e.contains("(did you mean `prescribed`?)"),
            "{e}"
        );
        // Valid values still parse, replay records included.
        for ok in [
            vec!["coupler-node", "inspect", "x.mcap", "--export", "csv"],
            vec!["coupler-node", "run", "s.toml", "--fluid", "replay:f.mcap"],
            vec!["coupler-node", "run", "s.toml", "--solid", "prescribed"],
        ] {
            assert!(Args::try_parse_from(&ok).is_ok(), "{ok:?}");
        }
    }
}
