//! `coupler-node run`: validate the scene, start the nodes it needs, couple them, supervise them.
//!
//! The scene is validated before any process starts. The resolved scene (defaults filled in,
//! `--fluid`/`--solid` choices applied) is written to `OUT/scene.toml` and every node reads that
//! file, so all three hash the same text. Children run beside this executable; a child that
//! exits early, or stops answering, ends the run with its name in the status. Ctrl-C, SIGTERM or
//! SIGHUP interrupt the run: the nodes are told to shut down, the record is finished, the files
//! of the run are removed, the summary's status starts with "interrupted" and the coupler exits
//! with [`EXIT_INTERRUPTED`]. The nodes run in a process group of their own, so a signal to the
//! coupler's group (Ctrl-C or a hangup of its terminal) reaches the coupler only, which ends them.
//!
//! The output folder must be missing or empty; `--overwrite` clears the files of an earlier run
//! there first ([`crate::out_folder`]), so no stale output is left beside the new ones.
//!
//! A scene whose estimated memory ([`Scene::memory_estimate`]) exceeds what the machine has
//! available is refused before any process starts.
//!
//! The nodes inherit the coupler's stderr and environment, so their log lines (prefixed `fluid`
//! and `solid`) join the coupler's, and a `RUST_LOG` reaches them; the coupler's `-v`/`-q` is
//! passed on as their own.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Context;
use protocol::logs::Verbosity;
use protocol::scene::Scene;
use protocol::transport::{Transport, TransportError};
use protocol::wire::NodeKind;

use crate::driver::{self, Abort, DriverConfig, RecordSink, Summary};
use crate::preflight::{available_memory, load_scene, node_binary, with_fluid_ranks};
use crate::scheme::{Coupler, CouplerConfig, Resume};
use crate::sink::RunSink;

/// Options of `coupler-node run`.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// Output directory.
    pub out: PathBuf,
    /// Replace the files of an earlier run in `out` (otherwise a non-empty `out` is refused).
    pub overwrite: bool,
    /// Fluid implementation override (`real`, `pressure`, `replay:FILE`).
    pub fluid: Option<String>,
    /// Solid implementation override (`real`, `prescribed`, `replay:FILE`).
    pub solid: Option<String>,
    /// Deadline for any one message \[s\].
    pub timeout: Duration,
    /// Progress line on stderr.
    pub progress: bool,
    /// `-v`/`-q` of the nodes' logs (the coupler's own).
    pub verbosity: Verbosity,
    /// Explicit node binaries (default: beside this executable).
    pub fluid_bin: Option<PathBuf>,
    /// Explicit solid binary.
    pub solid_bin: Option<PathBuf>,
    /// Resume from the checkpoints of this record at this step.
    pub restart: Option<(PathBuf, u64)>,
    /// `fluid.ranks` override (`--fluid-ranks`).
    pub fluid_ranks: Option<u32>,
    /// Host file passed to `mpirun --hostfile` for a fluid of several ranks.
    pub hostfile: Option<PathBuf>,
}

/// Exit status of `coupler-node run` when SIGINT, SIGTERM or SIGHUP interrupted the run (the
/// shell's 128 + SIGINT).
pub const EXIT_INTERRUPTED: u8 = 130;

/// The run was interrupted by a signal and ended cleanly; the text is the summary's status.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Interrupted(pub String);

/// A short run id for the shared-memory prefix: scene name and process id.
pub fn run_id(scene: &Scene) -> String {
    let short: String = scene
        .name
        .chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .take(12)
        .collect();
    format!("{short}{}", std::process::id())
}

/// Cleans the leftovers of earlier runs that crashed: every run id with files under
/// `/dev/shm/cosim_<id>_*` (or a lock file left) and no live process. Runs still alive are left
/// alone ([`protocol::bus::cleanup_run`] refuses them). Returns the run ids cleaned.
pub fn sweep_stale_runs() -> Vec<String> {
    let mut ids = protocol::bus::locked_run_ids();
    if let Ok(entries) = std::fs::read_dir("/dev/shm") {
        ids.extend(entries.filter_map(|e| e.ok()).filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let rest = name.strip_prefix("cosim_")?;
            Some(rest.split('_').next()?.to_string())
        }));
    }
    ids.retain(|id| !id.is_empty() && protocol::bus::validate_run_id(id).is_ok());
    ids.sort();
    ids.dedup();
    ids.into_iter()
        .filter(|id| match protocol::bus::cleanup_run(id) {
            Ok(removed) => !removed.is_empty(),
            Err(err) => {
                // A run still alive (a parallel run) is left alone; say so for the others.
                if !err.to_string().contains("is live") {
                    tracing::warn!("could not clean the leftovers of run {id}: {err}");
                }
                false
            }
        })
        .collect()
}

/// Runs a scene end to end; returns the summary (also written to `OUT/summary.json`). An
/// interrupted run returns [`Interrupted`] (after writing the summary).
pub fn run(opts: &RunOptions) -> anyhow::Result<Summary> {
    let (scene, resume) = resolve(opts)?;
    let mut nodes = Vec::new();
    if let Some(f) = &scene.fluid {
        nodes.push((NodeKind::Fluid, f.node.clone()));
    }
    if let Some(s) = &scene.solid {
        nodes.push((NodeKind::Solid, s.node.clone()));
    }
    let binaries = nodes
        .iter()
        .map(|(node, _)| {
            let explicit = match node {
                NodeKind::Fluid => opts.fluid_bin.as_deref(),
                _ => opts.solid_bin.as_deref(),
            };
            node_binary(*node, explicit)
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    // Before anything is written there, and held to the end of the run.
    let _out_lock = crate::out_folder::lock(&opts.out)?;
    crate::out_folder::prepare(
        &opts.out,
        opts.overwrite,
        opts.restart.as_ref().map(|(file, _)| file.as_path()),
    )?;
    crate::preflight::check_record_space(&scene, &opts.out)?;
    reserve_summary(&scene, &opts.out)?;
    let mut written = false;
    let result = run_reserved(opts, &scene, resume, &nodes, &binaries, &mut written);
    if let Err(err) = &result
        && !written
    {
        // A run that failed before its end still leaves a summary that says why.
        let summary = Summary {
            scene: scene.name.clone(),
            status: format!("{err:#}"),
            ..Summary::default()
        };
        if let Err(lost) = write_summary(&summary, &opts.out) {
            tracing::error!("{lost:#}");
        }
    }
    result
}

/// [`run`] once the output folder is locked, prepared and its summary reserved; `written` is
/// set once the final summary is written.
fn run_reserved(
    opts: &RunOptions,
    scene: &Scene,
    resume: Option<Resume>,
    nodes: &[(NodeKind, String)],
    binaries: &[PathBuf],
    written: &mut bool,
) -> anyhow::Result<Summary> {
    let scene = scene.clone();
    let nodes = nodes.to_vec();
    let resolved = opts.out.join("scene.toml");
    std::fs::write(&resolved, scene.to_toml())
        .with_context(|| format!("writing {}", resolved.display()))?;
    let run_id = run_id(&scene);
    let swept = sweep_stale_runs();
    if !swept.is_empty() {
        tracing::info!("cleaned the leftovers of crashed runs {swept:?}");
    }
    tracing::debug!(
        "run {run_id}: scene {}, out {}, {}",
        scene.name,
        opts.out.display(),
        nodes
            .iter()
            .map(|(node, implementation)| format!("{node} {implementation}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    protocol::bus::cleanup_run(&run_id).context("cleaning leftovers of an earlier run")?;
    let peers: Vec<NodeKind> = nodes.iter().map(|(n, _)| *n).collect();
    let mut bus = protocol::bus::Bus::open(&run_id, NodeKind::Coupler, &peers)
        .with_context(|| format!("opening the bus for run {run_id}"))?;

    let children = node_commands(opts, &scene, &nodes, binaries, &resolved, &run_id)?;
    let abort = Abort::default();
    let hung_up = Arc::new(AtomicBool::new(false));
    let supervisor = Supervisor::start(children, abort.clone(), hung_up.clone())?;

    let mut run_sink = RunSink::create(&opts.out, &scene, resume.is_some())?;
    let sink: &mut dyn RecordSink = &mut run_sink;
    let cfg = CouplerConfig::from_scene(&scene);
    let mut coupler = match resume {
        Some(resume) => Coupler::resuming(cfg, resume)?,
        None => Coupler::new(cfg),
    };
    let cfg = DriverConfig {
        timeout: opts.timeout,
        progress: opts.progress,
        name: scene.name.clone(),
        t_end: scene.run.t_end,
        dt_min: scene.run.dt_min,
    };
    let transport: &mut dyn Transport = &mut bus;
    let (mut summary, error) = driver::drive(transport, &mut coupler, sink, &cfg, &abort);
    let finished = run_sink.finish();
    let exits = supervisor.stop(Duration::from_secs(2));
    for (node, exit) in &exits {
        tracing::debug!("the {node} node ended: {}", exit.text);
    }
    let last_words = last_words(&mut bus);
    drop(bus);
    let _ = protocol::bus::cleanup_run(&run_id);
    let interrupted = hung_up.load(Ordering::SeqCst)
        || matches!(
            error,
            Some(driver::DriverError::Transport(TransportError::Interrupted))
        );
    // A node that died explains a lost peer better than the transport does (but a node that
    // ended after the coupler was interrupted is no cause, nor one the coupler killed at the
    // end, nor one that only lost its exchange with the coupler: exit code 4).
    if !interrupted
        && matches!(
            error,
            Some(driver::DriverError::Transport(_) | driver::DriverError::Aborted(_))
        )
        && let Some((node, status)) = exits.iter().find(|(_, s)| is_cause(s))
    {
        summary.status = format!("{node} node died ({}): {}", status.text, summary.status);
    }
    let mut failed = error.is_some();
    let mut fail = |summary: &mut Summary, status: String| {
        if failed {
            tracing::error!("{status}");
        } else {
            summary.status = status;
            failed = true;
        }
    };
    if !interrupted && error.is_none() {
        // A node that failed after the last step (its probe files): its report, else its exit.
        if let Some((node, report)) = last_words.first() {
            fail(
                &mut summary,
                format!("{node} node failed at the end of the run: {report}"),
            );
        } else if let Some((node, status)) = exits.iter().find(|(_, s)| !s.success) {
            fail(
                &mut summary,
                format!(
                    "{node} node failed at the end of the run ({}): its outputs may be incomplete (its report is on stderr)",
                    status.text
                ),
            );
        }
    }
    if let Err(err) = finished {
        fail(&mut summary, format!("finishing the record: {err:#}"));
    }
    for (node, implementation) in &nodes {
        summary
            .nodes
            .insert(node.name().to_string(), implementation.clone());
    }
    if let Err(err) = write_outputs_table(&scene, &summary, &opts.out) {
        fail(&mut summary, format!("{err:#}"));
    }
    write_summary(&summary, &opts.out)?;
    *written = true;
    if interrupted {
        return Err(Interrupted(summary.status).into());
    }
    if failed {
        anyhow::bail!("{}", summary.status);
    }
    Ok(summary)
}

/// Whether a node's end explains a lost peer: not a success, not killed by the coupler after
/// the grace period, not exit code 4 (its exchange with the coupler failed: a consequence).
fn is_cause(exit: &ExitInfo) -> bool {
    !exit.success && !exit.text.starts_with("killed after") && exit.text != "exit code 4"
}

/// The failure reports the nodes sent after the coupler stopped listening (a probe file that
/// could not be written at the end), read from the bus after they exited.
fn last_words(bus: &mut protocol::bus::Bus) -> Vec<(NodeKind, String)> {
    let mut words = Vec::new();
    while let Ok((from, frame)) = bus.recv(None, Duration::ZERO) {
        if let Ok((_, protocol::wire::Message::Failure(f))) = protocol::codec::decode(&frame) {
            words.push((from, f.report));
        }
    }
    words
}

/// Bytes kept for `summary.json` from the start of the run, so that it can be written on a
/// full disk at the end.
const SUMMARY_RESERVE: usize = 64 << 10;

/// Writes `OUT/summary.json` with status `running`, padded to [`SUMMARY_RESERVE`] bytes with
/// spaces (JSON whitespace): the final summary overwrites it in place.
fn reserve_summary(scene: &Scene, out: &Path) -> anyhow::Result<()> {
    let path = out.join("summary.json");
    let mut text = serde_json::to_string_pretty(&Summary {
        scene: scene.name.clone(),
        status: "running".into(),
        ..Summary::default()
    })
    .expect("summary serializes");
    text.push('\n');
    let pad = SUMMARY_RESERVE.saturating_sub(text.len());
    text.extend(std::iter::repeat_n(' ', pad));
    std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
}

/// `OUT/summary.json`, over the space [`reserve_summary`] kept (a status too long for it is
/// shortened), then cut to its length.
fn write_summary(summary: &Summary, out: &Path) -> anyhow::Result<()> {
    use std::io::{Seek, Write};
    let path = out.join("summary.json");
    let mut summary = summary.clone();
    if summary.status.len() > SUMMARY_RESERVE / 2 {
        let cut = (0..=SUMMARY_RESERVE / 2)
            .rev()
            .find(|&i| summary.status.is_char_boundary(i))
            .unwrap_or(0);
        summary.status.truncate(cut);
        summary.status.push_str("...");
    }
    let json = serde_json::to_string_pretty(&summary).expect("summary serializes") + "\n";
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .with_context(|| format!("opening {}", path.display()))?;
    file.seek(std::io::SeekFrom::Start(0))
        .and_then(|_| file.write_all(json.as_bytes()))
        .and_then(|()| file.set_len(json.len() as u64))
        .with_context(|| format!("writing {}", path.display()))
}

/// `OUT/outputs.csv`: the output times.
fn write_outputs_table(scene: &Scene, summary: &Summary, out: &Path) -> anyhow::Result<()> {
    let mut table = String::from("k,t\n");
    // Output 0 is the initial state when the scene asks for t = 0; the steps' outputs follow.
    let first_planned = u32::from(scene.initial_output());
    if scene.initial_output() {
        table.push_str(&format!("0,{:e}\n", 0.0));
    }
    for (k, t) in &summary.outputs {
        table.push_str(&format!("{},{t:e}\n", k + first_planned));
    }
    let path = out.join("outputs.csv");
    if let Err(err) = std::fs::write(&path, table) {
        // Nothing half-written is left: a table without its last rows would read as complete.
        let _ = std::fs::remove_file(&path);
        return Err(err).with_context(|| format!("writing {}", path.display()));
    }
    Ok(())
}

/// The scene as the run will use it (overrides applied, memory and `replay:FILE` records
/// checked) and, for `--restart`, what the run resumes from.
fn resolve(opts: &RunOptions) -> anyhow::Result<(Scene, Option<Resume>)> {
    let mut scene = load_scene(&opts.scene, opts.fluid.as_deref(), opts.solid.as_deref())?;
    if let Some(ranks) = opts.fluid_ranks {
        scene = with_fluid_ranks(scene, ranks, &opts.scene)?;
    }
    scene
        .check_memory(available_memory()?)
        .with_context(|| opts.scene.display().to_string())?;
    crate::preflight::check_replay_doubles(&scene)?;
    crate::preflight::check_fluid_ranks(&scene, opts.fluid_bin.as_deref())?;
    let resume = match &opts.restart {
        Some((file, step)) => Some(crate::restart::load(file, *step, &scene)?),
        None => None,
    };
    Ok((scene, resume))
}

/// The command of each node (`mpirun` for a fluid of several ranks), with the ranks it runs.
fn node_commands(
    opts: &RunOptions,
    scene: &Scene,
    nodes: &[(NodeKind, String)],
    binaries: &[PathBuf],
    resolved: &Path,
    run_id: &str,
) -> anyhow::Result<Vec<(NodeKind, tokio::process::Command, u32)>> {
    let fluid_ranks = scene.fluid.as_ref().map_or(1, |f| f.ranks);
    let mpirun = if fluid_ranks > 1 {
        let fluid_bin = &binaries[0];
        Some(crate::mpi_launch::MpiLaunch::find(
            fluid_bin,
            fluid_ranks,
            opts.hostfile.as_deref(),
        )?)
    } else {
        anyhow::ensure!(
            opts.hostfile.is_none(),
            "--hostfile is for a fluid of several ranks (fluid.ranks or --fluid-ranks > 1)"
        );
        None
    };
    let mut children = Vec::new();
    for ((node, implementation), binary) in nodes.iter().zip(binaries) {
        let mut cmd = match (&mpirun, node) {
            (Some(mpi), NodeKind::Fluid) => mpi.command(binary),
            _ => tokio::process::Command::new(binary),
        };
        cmd.arg("--scene")
            .arg(resolved)
            .arg("--run-id")
            .arg(run_id)
            .arg("--out")
            .arg(&opts.out)
            .arg("--double")
            .arg(implementation)
            .arg("--timeout-s")
            .arg(node_timeout(opts.timeout).as_secs_f64().to_string())
            .args(opts.verbosity.to_args())
            .stdin(Stdio::null())
            // NOTE: a group of its own, so that Ctrl-C or a terminal hangup reaches the coupler
            // only, which shuts the node down cleanly (a node killed by the signal would read
            // as a node death).
            .process_group(0)
            .kill_on_drop(true);
        die_with_coupler(&mut cmd);
        let ranks = match node {
            NodeKind::Fluid if mpirun.is_some() => {
                // The launcher's report names a rank that died (read from its stderr).
                cmd.stderr(Stdio::piped());
                fluid_ranks
            }
            _ => 1,
        };
        children.push((*node, cmd, ranks));
    }
    Ok(children)
}

/// The deadline the nodes get: the coupler's, plus a quarter of it and at least 1 s, so that
/// the coupler, which sees which node is silent, speaks first when a node stops answering (a
/// node waiting for the coupler then is not the one to blame).
pub fn node_timeout(timeout: Duration) -> Duration {
    let longer = timeout + (timeout / 4).max(Duration::from_secs(1));
    longer.min(Duration::from_secs_f64(protocol::session::MAX_TIMEOUT_S))
}

/// Makes the kernel SIGKILL the child when the coupler's thread that starts it ends
/// (`PR_SET_PDEATHSIG`, set between fork and exec, so `mpirun` gets it too), whatever ended the
/// coupler; a child whose coupler is already gone does not start.
fn die_with_coupler(cmd: &mut tokio::process::Command) {
    let coupler = std::process::id();
    // SAFETY: the closure runs in the child between fork and exec; it calls only
    // async-signal-safe functions (prctl with integer arguments, getppid) and allocates
    // nothing.
    unsafe {
        cmd.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL, 0, 0, 0) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            // The coupler died between the fork and the prctl: no signal will come.
            if std::os::unix::process::parent_id() != coupler {
                return Err(std::io::Error::from_raw_os_error(libc::ESRCH));
            }
            Ok(())
        });
    }
}

/// How a child ended.
#[derive(Clone, Debug)]
pub struct ExitInfo {
    /// Exit code 0.
    pub success: bool,
    /// `exit code N`, `killed by signal N`, or `killed after the grace period`.
    pub text: String,
}

/// Starts the children and watches them on a tokio runtime of its own thread.
struct Supervisor {
    stop: tokio::sync::oneshot::Sender<Duration>,
    thread: std::thread::JoinHandle<Vec<(NodeKind, ExitInfo)>>,
}

fn describe(status: std::process::ExitStatus) -> ExitInfo {
    use std::os::unix::process::ExitStatusExt;
    let text = match (status.code(), status.signal()) {
        (Some(code), _) => format!("exit code {code}"),
        (None, Some(sig)) => format!("killed by signal {sig}"),
        _ => "ended".to_string(),
    };
    ExitInfo {
        success: status.success(),
        text,
    }
}

impl Supervisor {
    fn start(
        children: Vec<(NodeKind, tokio::process::Command, u32)>,
        abort: Abort,
        hung_up: Arc<AtomicBool>,
    ) -> anyhow::Result<Supervisor> {
        let (started_tx, started_rx) = std::sync::mpsc::channel();
        let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<Duration>();
        let thread = std::thread::Builder::new()
            .name("supervisor".into())
            .spawn(move || {
                let rt = tokio::runtime::Builder::new_current_thread()
                    .enable_all()
                    .build()
                    .expect("a current-thread runtime builds");
                rt.block_on(supervise(children, abort, hung_up, started_tx, stop_rx))
            })
            .context("starting the supervisor thread")?;
        match started_rx.recv() {
            Ok(Ok(())) => Ok(Supervisor {
                stop: stop_tx,
                thread,
            }),
            Ok(Err(err)) => {
                let _ = thread.join();
                Err(err)
            }
            Err(_) => anyhow::bail!("the supervisor thread ended before starting the nodes"),
        }
    }

    /// Lets the children exit within `grace`, kills the rest, and returns how each ended.
    fn stop(self, grace: Duration) -> Vec<(NodeKind, ExitInfo)> {
        let _ = self.stop.send(grace);
        self.thread.join().unwrap_or_default()
    }
}

async fn supervise(
    commands: Vec<(NodeKind, tokio::process::Command, u32)>,
    abort: Abort,
    hung_up: Arc<AtomicBool>,
    started: std::sync::mpsc::Sender<anyhow::Result<()>>,
    stop: tokio::sync::oneshot::Receiver<Duration>,
) -> Vec<(NodeKind, ExitInfo)> {
    // NOTE: SIGHUP is handled here, like SIGINT and SIGTERM are by iceoryx2 in the bus waits:
    // it raises the abort the loop checks every 100 ms.
    use tokio::signal::unix::{SignalKind, signal};
    let mut hangup = match signal(SignalKind::hangup()) {
        Ok(stream) => stream,
        Err(err) => {
            let _ = started.send(Err(anyhow::Error::new(err).context("handling SIGHUP")));
            return Vec::new();
        }
    };
    let mut children = Vec::new();
    let mut rank_reports = Vec::new();
    for (node, mut cmd, ranks) in commands {
        match cmd.spawn() {
            Ok(mut child) => {
                if ranks > 1
                    && let Some(stderr) = child.stderr.take()
                {
                    rank_reports.push((node, crate::mpi_launch::watch_stderr(stderr)));
                }
                tracing::debug!(
                    "started the {node} node: {} (pid {})",
                    cmd.as_std().get_program().to_string_lossy(),
                    child.id().unwrap_or(0)
                );
                children.push((node, child));
            }
            Err(err) => {
                let _ = started.send(Err(
                    anyhow::Error::new(err).context(format!("starting the {node} node"))
                ));
                return Vec::new();
            }
        }
    }
    let _ = started.send(Ok(()));
    let mut exits: Vec<(NodeKind, ExitInfo)> = Vec::new();
    let mut stop = stop;
    // Watch until the coupler says stop; an early exit of any child aborts the run.
    let grace = loop {
        let waits = children
            .iter_mut()
            .filter(|(node, _)| !exits.iter().any(|(n, _)| n == node))
            .map(|(node, child)| {
                let node = *node;
                Box::pin(async move { (node, child.wait().await) })
            })
            .collect::<Vec<_>>();
        if waits.is_empty() {
            break (&mut stop).await.unwrap_or(Duration::ZERO);
        }
        tokio::select! {
            grace = &mut stop => break grace.unwrap_or(Duration::ZERO),
            Some(()) = hangup.recv() => {
                hung_up.store(true, Ordering::SeqCst);
                abort.raise("interrupted by a signal (SIGHUP)".to_string());
            }
            ((node, status), _, _) = futures_select_all(waits) => {
                let mut info = match status {
                    Ok(s) => describe(s),
                    Err(e) => ExitInfo { success: false, text: format!("wait failed: {e}") },
                };
                if let Some((_, report)) = rank_reports.iter_mut().find(|(n, _)| *n == node) {
                    crate::mpi_launch::name_rank(&mut info.text, report).await;
                }
                let reason = format!("{node} node exited before the end of the run ({})", info.text);
                exits.push((node, info));
                abort.node_exited(node, reason);
            }
        }
    };
    for (node, child) in children.iter_mut() {
        if exits.iter().any(|(n, _)| n == node) {
            continue;
        }
        let report = rank_reports.iter().find(|(n, _)| n == node).map(|(_, r)| r);
        let mpi = report.is_some();
        let waited = tokio::time::timeout(grace, child.wait()).await;
        let ended_itself = matches!(waited, Ok(Ok(_)));
        let mut info = match waited {
            Ok(Ok(status)) => describe(status),
            Ok(Err(e)) => ExitInfo {
                success: false,
                text: format!("wait failed: {e}"),
            },
            Err(_) => {
                if mpi {
                    // The ranks share mpirun's process group: none is left behind.
                    crate::mpi_launch::kill_group(child.id());
                }
                let _ = child.kill().await;
                ExitInfo {
                    success: false,
                    text: format!("killed after the {grace:?} grace period"),
                }
            }
        };
        // NOTE: a rank that dies can end the run two ways: the watch above sees mpirun exit, or
        // the coupler first finds the fluid gone on the bus and says stop. The launcher's line
        // naming the rank is wanted on both (issue_16_mpi's killed rank went unnamed in one CI
        // run of four, when the bus spoke first).
        if let Some(report) = report
            && ended_itself
            && !info.success
        {
            crate::mpi_launch::name_rank(&mut info.text, report).await;
        }
        exits.push((*node, info));
    }
    exits
}

/// Waits for the first of several futures (a small `select_all` without another crate).
async fn futures_select_all<F, T>(futures: Vec<std::pin::Pin<Box<F>>>) -> (T, usize, ())
where
    F: std::future::Future<Output = T>,
{
    let mut futures = futures;
    std::future::poll_fn(move |cx| {
        for (i, f) in futures.iter_mut().enumerate() {
            if let std::task::Poll::Ready(out) = f.as_mut().poll(cx) {
                return std::task::Poll::Ready((out, i, ()));
            }
        }
        std::task::Poll::Pending
    })
    .await
}
