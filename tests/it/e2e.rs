//! The real binaries over iceoryx2: runs, records, replays, killed nodes, bad scenes.
//!
//! Each test has its own output folder; run ids derive from the coupler's process id, so tests
//! run in parallel without seeing each other.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::{RwLock, RwLockReadGuard};
use std::time::{Duration, Instant};

use coupler_node::record::{self, Recorder};
use protocol::codec;
use protocol::scene::{RecordCompression, RecordLevel};
use protocol::wire::{Message, NodeKind};

mod coupled;
mod replay;

pub(crate) fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub(crate) fn out_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cosim-it-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The coupler binary, with the test shims as its nodes and no `RUST_LOG` (stderr is what the
/// flags give; a test that wants `RUST_LOG` sets it).
pub(crate) fn coupler() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_it-coupler-node"));
    cmd.env("COSIM_FLUID_BIN", env!("CARGO_BIN_EXE_it-fluid-node"))
        .env("COSIM_SOLID_BIN", env!("CARGO_BIN_EXE_it-solid-node"))
        .env_remove("RUST_LOG");
    cmd
}

/// Every `coupler-node run` sweeps the leftovers of crashed runs as it starts. Tests that start
/// runs hold this lock shared until their runs have started; the crashed-run test holds it
/// exclusively, so that no other start sweeps its leftovers before it has counted them.
static STARTS: RwLock<()> = RwLock::new(());

pub(crate) fn shared_start() -> RwLockReadGuard<'static, ()> {
    STARTS
        .read()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

pub(crate) fn run_scene(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    run_scene_with(coupler(), scene, out, extra)
}

/// [`run_scene`] with a `coupler-node` command prepared by the caller (its environment).
pub(crate) fn run_scene_with(mut cmd: Command, scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let _start = shared_start();
    let output = cmd
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .output()
        .expect("coupler-node starts");
    assert!(
        output.status.success(),
        "run {extra:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// A Python interpreter with the `mcap` package (the independent reader of the records):
/// `$COSIM_PYTHON`, or a venv under the target folder made on first use
/// (`tests/py/python-with-mcap.sh`).
pub(crate) fn python() -> String {
    let out = Command::new("sh")
        .arg(workspace().join("tests/py/python-with-mcap.sh"))
        .arg(env!("CARGO_TARGET_TMPDIR"))
        .output()
        .expect("sh runs");
    assert!(
        out.status.success(),
        "setting up a Python with the mcap package: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .expect("a path")
        .trim()
        .to_string()
}

/// `coupler-node replay FILE --step STEP --node NODE` prints `identical` and succeeds.
fn assert_replays_identically(file: &Path, step: &str, node: &str) {
    let r = coupler()
        .args(["replay", "--step", step, "--node", node])
        .arg(file)
        .output()
        .expect("replay starts");
    assert_eq!(
        String::from_utf8_lossy(&r.stdout).trim(),
        "identical",
        "{node} step {step}: {}",
        String::from_utf8_lossy(&r.stderr)
    );
    assert!(r.status.success());
}

pub(crate) fn summary(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary is JSON")
}

pub(crate) fn frames_by_topic(path: &Path) -> Vec<(String, Vec<Vec<u8>>)> {
    let rec = record::read_recording(&std::fs::read(path).expect("record")).expect("readable");
    let mut topics: Vec<(String, Vec<Vec<u8>>)> = Vec::new();
    for m in rec
        .messages
        .iter()
        .filter(|m| m.topic != record::DIAGNOSTICS_TOPIC)
    {
        match topics.iter_mut().find(|(t, _)| *t == m.topic) {
            Some((_, v)) => v.push(m.data.clone()),
            None => topics.push((m.topic.clone(), vec![m.data.clone()])),
        }
    }
    topics.sort();
    topics
}

/// What is deterministic in a record besides the frames: the log times (simulated time) per
/// topic, and the diagnostics without their wall-clock `busy_s`.
fn times_and_diagnostics(path: &Path) -> (Vec<(String, Vec<u64>)>, Vec<serde_json::Value>) {
    let rec = record::read_recording(&std::fs::read(path).expect("record")).expect("readable");
    let mut times: Vec<(String, Vec<u64>)> = Vec::new();
    for m in &rec.messages {
        match times.iter_mut().find(|(t, _)| *t == m.topic) {
            Some((_, v)) => v.push(m.log_time),
            None => times.push((m.topic.clone(), vec![m.log_time])),
        }
    }
    times.sort();
    let diagnostics = rec
        .topic(record::DIAGNOSTICS_TOPIC)
        .map(|m| {
            let mut v: serde_json::Value = serde_json::from_slice(&m.data).expect("json");
            v.as_object_mut().expect("an object").remove("busy_s");
            v
        })
        .collect();
    (times, diagnostics)
}

/// Issue 15, items 5 and 6 on a finished run: `ledger.csv` has the exact header and one row
/// per step, its last row is the run's last ledger entry (the record's diagnostics) and its
/// maxima are the summary's errors; the record's log time is simulated time; `inspect` counts
/// the run's steps.
fn check_ledger_csv_and_record(out: &Path) {
    let scene = std::fs::read_to_string(out.join("scene.toml")).expect("scene.toml");
    let mass_tolerance = protocol::scene::Scene::from_toml_str(&scene, "the run's scene")
        .expect("scene")
        .run
        .mass_tolerance;
    let s = summary(out);
    let steps = s["steps"].as_u64().expect("steps");
    let text = std::fs::read_to_string(out.join("ledger.csv")).expect("ledger.csv");
    assert_eq!(
        text.lines().next(),
        Some(
            "t,step,fluid_mass,fluid_energy,solid_kinetic,solid_elastic,solid_dissipated,interface_work,mass_rel_err,energy_rel_err,solid_substeps"
        )
    );
    let rows = cosim_tests::read_table(&out.join("ledger.csv")).rows;
    assert_eq!(rows.len() as u64, steps, "one row per step");
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), 11);
        assert_eq!(
            row[10], 1.0,
            "one solid step per coupling step without the key"
        );
        assert_eq!(
            row[1], k as f64,
            "steps count from 0, as the diagnostics' step"
        );
    }
    let last = rows.last().expect("rows");
    // Same numbers as the run (printed in shortest round-trip form: equal to 1e-15).
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-15 * a.abs().max(b.abs()).max(1e-300);
    assert!(
        close(last[0], s["t_end"].as_f64().expect("t_end")),
        "{last:?} {s}"
    );
    let max = |col: usize| rows.iter().map(|r| r[col]).fold(0.0, f64::max);
    assert!(
        close(max(8), s["mass_rel_err"].as_f64().expect("mass")),
        "{s}"
    );
    assert!(
        close(max(9), s["energy_rel_err"].as_f64().expect("energy")),
        "{s}"
    );
    assert!(
        max(8) < mass_tolerance,
        "mass error {} vs tolerance {mass_tolerance}",
        max(8)
    );
    let rec = record::read_recording(&std::fs::read(out.join("exchange.mcap")).expect("record"))
        .expect("readable");
    let diag = rec
        .topic(record::DIAGNOSTICS_TOPIC)
        .last()
        .expect("diagnostics");
    let d: serde_json::Value = serde_json::from_slice(&diag.data).expect("json");
    let ledger = &d["ledger"];
    assert_eq!(d["step"], ledger["step"], "one step numbering: {d}");
    assert_eq!(d["step"].as_u64(), Some(steps - 1));
    for (col, key) in [
        (2, "fluid_mass"),
        (3, "fluid_energy"),
        (4, "solid_kinetic"),
        (8, "mass_rel_err"),
    ] {
        assert!(
            close(last[col], ledger[key].as_f64().expect(key)),
            "{key}: {last:?} {ledger}"
        );
    }
    // The ledger's solid energy is the rounded sum of the kinetic and elastic parts, so the
    // elastic part taken back out of it is exact to the rounding of that sum, not of itself
    // (the beam at 0.2 s: 1.9e-4 J of 1.75e-3 J, off by 1.2 units of 1e-15 of itself).
    let solid = ledger["solid_energy"].as_f64().expect("e");
    let elastic = solid - ledger["solid_kinetic"].as_f64().expect("k");
    assert!(
        (last[5] - elastic).abs() <= 1e-15 * solid.abs(),
        "{last:?} {ledger}"
    );
    // Log time = simulated time in ns: the last diagnostics at t_end, to the ns.
    let t_end_ns = s["t_end"].as_f64().expect("t_end") * 1e9;
    assert!(
        (diag.log_time as f64 - t_end_ns).abs() <= 1.0,
        "{} vs {t_end_ns}",
        diag.log_time
    );
    assert!(rec.messages.iter().all(|m| m.topic.starts_with('/')));
    // `inspect` counts the steps the run did.
    let r = coupler()
        .arg("inspect")
        .arg(out.join("exchange.mcap"))
        .output()
        .expect("inspect");
    let table = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(
        table.contains(&format!("\n{steps} steps completed, ")),
        "{table}"
    );
    // And its tidy export has one `ledger.step` row per step.
    let r = coupler()
        .args(["inspect", "--export", "csv"])
        .arg(out.join("exchange.mcap"))
        .output()
        .expect("inspect --export csv");
    let csv = String::from_utf8_lossy(&r.stdout);
    assert!(
        csv.starts_with("step,iteration,channel,field,index,value\n"),
        "{}",
        &csv[..200.min(csv.len())]
    );
    let ledger_rows = csv
        .lines()
        .filter(|l| l.contains(",/diagnostics,ledger.step,0,"))
        .count();
    assert_eq!(ledger_rows as u64, steps);
}

#[test]
fn doubles_over_the_bus_are_recorded_and_deterministic() {
    let scene = workspace().join("scenes/backbone-doubles.toml");
    let a = out_dir("det-a");
    let b = out_dir("det-b");
    run_scene(&scene, &a, &[]);
    run_scene(&scene, &b, &[]);
    let s = summary(&a);
    assert_eq!(s["status"], "completed");
    assert!(s["steps"].as_u64().expect("steps") >= 100, "{s}");
    let (fa, fb) = (
        frames_by_topic(&a.join("exchange.mcap")),
        frames_by_topic(&b.join("exchange.mcap")),
    );
    let topics: Vec<&str> = fa.iter().map(|(t, _)| t.as_str()).collect();
    assert_eq!(
        topics,
        [
            "/checkpoint/coupler",
            "/checkpoint/fluid",
            "/checkpoint/solid",
            "/coupler-to-fluid",
            "/coupler-to-solid",
            "/fluid-to-coupler",
            "/solid-to-coupler"
        ]
    );
    assert!(fa == fb, "two runs recorded different payload bytes");
    // The bus carries exactly what the in-process run exchanges.
    let scene = cosim_tests::scene("backbone-doubles.toml");
    let mem = cosim_tests::run_in_process(&scene);
    let mem_solid: Vec<&Vec<u8>> = mem
        .sink
        .frames
        .iter()
        .filter(|f| f.0 == NodeKind::Solid && f.1 == NodeKind::Coupler)
        .map(|f| &f.2)
        .filter(|f| {
            codec::decode_header(f).is_ok_and(|h| h.kind != protocol::wire::MessageKind::Checkpoint)
        })
        .collect();
    let bus_solid = &fa
        .iter()
        .find(|(t, _)| t == "/solid-to-coupler")
        .expect("topic")
        .1;
    assert_eq!(mem_solid.len(), bus_solid.len());
    assert!(
        mem_solid.iter().zip(bus_solid).all(|(m, b)| *m == b),
        "bus and memory differ"
    );
    for dir in [a, b] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// Process ids of the nodes of a run (`--` so pgrep does not read the pattern as an option).
pub(crate) fn node_pids(run_id: &str) -> String {
    let out = Command::new("pgrep")
        .args(["-f", "--", &format!("--run-id {run_id} ")])
        .output()
        .expect("pgrep");
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

pub(crate) fn long_doubles_scene(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let text = std::fs::read_to_string(workspace().join("scenes/backbone-doubles.toml"))
        .expect("scene")
        .replace("t_end = 1.0", "t_end = 1000.0")
        .replace("every = 0.25", "every = 500.0");
    let path = dir.join("long.toml");
    std::fs::write(&path, text).expect("write scene");
    path
}

/// Starts the coupler on a long scene and waits (bounded) until it has recorded `bytes`.
pub(crate) fn start_long_run(
    scene: &Path,
    out: &Path,
    bytes: u64,
    stderr: bool,
    own_group: bool,
) -> (std::process::Child, String) {
    let _start = shared_start();
    spawn_long_run(scene, out, bytes, stderr, own_group)
}

/// [`start_long_run`] without taking [`STARTS`] (for the test that holds it exclusively). With
/// `own_group` the coupler leads a process group of its own (its nodes join it), as a job of an
/// interactive shell does.
fn spawn_long_run(
    scene: &Path,
    out: &Path,
    bytes: u64,
    stderr: bool,
    own_group: bool,
) -> (std::process::Child, String) {
    let mut cmd = coupler();
    if own_group {
        std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    }
    let child = cmd
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .stderr(if stderr {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .spawn()
        .expect("coupler starts");
    let record = out.join("exchange.mcap");
    let deadline = Instant::now() + Duration::from_secs(30);
    while std::fs::metadata(&record).map_or(0, |m| m.len()) < bytes {
        assert!(Instant::now() < deadline, "the run did not start recording");
        std::thread::sleep(Duration::from_millis(20));
    }
    let run_id = format!("backbonedoub{}", child.id());
    (child, run_id)
}

fn kill_node_and_time_the_coupler(node: &str) {
    let dir = out_dir(&format!("kill-{node}"));
    let scene = long_doubles_scene(&dir);
    let out = dir.join("out");
    let (mut child, run_id) = start_long_run(&scene, &out, 200_000, true, false);
    let bin = if node == "fluid" {
        "it-fluid-node"
    } else {
        "it-solid-node"
    };
    let pids = Command::new("pgrep")
        .args(["-f", &format!("{bin} --scene .* --run-id {run_id} ")])
        .output()
        .expect("pgrep");
    let pid = String::from_utf8_lossy(&pids.stdout).trim().to_string();
    assert!(
        !pid.is_empty(),
        "no {node} node process found for run {run_id}"
    );
    let (status, took, stderr) = kill_and_wait(&pid, &mut child, Duration::from_secs(10));
    assert!(!status.success());
    // NOTE: a generous bound (a loaded 2-core machine stretches the 0.1-0.2 s it takes); the
    // figure itself is measured by `cargo bench -p cosim-tests --bench kill_detection`.
    assert!(
        took < Duration::from_secs(8),
        "coupler took {took:?} to notice"
    );
    assert!(stderr.contains(&format!("{node} node")), "{stderr}");
    let s = summary(&out);
    assert!(
        s["status"]
            .as_str()
            .expect("status")
            .contains(&format!("{node} node")),
        "{s}"
    );
    let rec = record::read_recording(&std::fs::read(out.join("exchange.mcap")).expect("record"))
        .expect("readable");
    assert!(rec.messages.len() > 100, "{} messages", rec.messages.len());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn killed_fluid_node_is_named_promptly() {
    kill_node_and_time_the_coupler("fluid");
}

#[test]
fn killed_solid_node_is_named_promptly() {
    kill_node_and_time_the_coupler("solid");
}

#[test]
fn bad_scene_is_refused_before_any_process_starts() {
    let dir = out_dir("bad-scene");
    std::fs::create_dir_all(&dir).expect("dir");
    let text = std::fs::read_to_string(workspace().join("scenes/sod.toml"))
        .expect("scene")
        .lines()
        .map(|l| {
            if l.starts_with("cfl =") {
                "cfl = 2.5"
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let path = dir.join("bad.toml");
    std::fs::write(&path, text).expect("write");
    let out = dir.join("out");
    let r = coupler()
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("starts");
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("bad.toml") && stderr.contains("fluid.cfl"),
        "{stderr}"
    );
    assert!(
        stderr.contains("expected a number in (0, 1], found 2.5"),
        "{stderr}"
    );
    assert!(!out.exists(), "the run created its output folder");
    // A type error names the key path too.
    std::fs::write(
        &path,
        "name = \"x\"\n[fluid]\nlower = [0.0]\nupper = [1.0]\ncells = [\"ten\"]\n",
    )
    .expect("write");
    let r = coupler()
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("starts");
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("fluid.cells"), "{stderr}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn sod_runs_end_to_end_and_matches_the_exact_solution() {
    let out = out_dir("sod");
    run_scene(&workspace().join("scenes/sod.toml"), &out, &[]);
    let s = summary(&out);
    assert_eq!(s["status"], "completed");
    assert!(s["mass_rel_err"].as_f64().expect("mass") < 1e-12, "{s}");
    let outputs = std::fs::read_to_string(out.join("outputs.csv")).expect("outputs.csv");
    assert_eq!(outputs.lines().collect::<Vec<_>>(), ["k,t", "0,2e-1"]);
    let csv = cosim_tests::read_table(&out.join("fluid_0.csv"));
    assert_eq!(csv.header, ["x", "rho", "u", "p", "alpha"]);
    use fluid_node::fv::exact_riemann::{ExactRiemann, Prim1};
    let exact = ExactRiemann::new(
        Prim1 {
            rho: 1.0,
            u: 0.0,
            p: 1.0,
        },
        Prim1 {
            rho: 0.125,
            u: 0.0,
            p: 0.1,
        },
        1.4,
    )
    .expect("exact solution");
    let mut l1 = 0.0;
    let mut n = 0;
    for v in &csv.rows {
        let h = 1.0 / 400.0;
        let rho = exact.cell_average(v[0] - h / 2.0, v[0] + h / 2.0, 0.5, 0.2)[0];
        l1 += (v[1] - rho).abs() / 400.0;
        n += 1;
    }
    assert_eq!(n, 400);
    // The same number as the in-process OSMP5 study at N = 400 and the scene's cfl = 0.7
    // (6.0828e-4, docs/cfl_study.csv), through the bus and the CSV (12 significant digits).
    assert!(
        (l1 - 6.0828e-4).abs() < 0.0001e-4,
        "L1 density error {l1:e}"
    );
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn python_mcap_reads_the_record() {
    let out = out_dir("python");
    run_scene(&workspace().join("scenes/backbone-doubles.toml"), &out, &[]);
    let python = python();
    let r = Command::new(&python)
        .arg(workspace().join("tests/py/check_mcap.py"))
        .arg(out.join("exchange.mcap"))
        .output()
        .unwrap_or_else(|e| panic!("running {python}: {e}"));
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(
        r.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&r.stderr)
    );
    assert!(
        stdout.starts_with("ok ") && stdout.contains("messages"),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn sigterm_ends_every_process_and_finishes_the_record() {
    let dir = out_dir("sigterm");
    let scene = long_doubles_scene(&dir);
    let out = dir.join("out");
    let (mut child, run_id) = start_long_run(&scene, &out, 100_000, true, false);
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(status.success());
    let sent = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        assert!(
            sent.elapsed() < Duration::from_secs(10),
            "coupler still running 10 s after SIGTERM"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    assert!(!status.success());
    let s = summary(&out);
    assert!(
        s["status"]
            .as_str()
            .expect("status")
            .contains("interrupted"),
        "{s}"
    );
    // The record is complete (summary and footer), not just readable.
    let rec = record::read_recording(&std::fs::read(out.join("exchange.mcap")).expect("record"))
        .expect("readable");
    assert!(!rec.truncated(), "the record was not finished");
    // No node of the run is left.
    assert!(node_pids(&run_id).is_empty(), "nodes left running");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_solid_only_scene_runs_through_the_coupler() {
    let dir = out_dir("solid-only");
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("bar.toml");
    std::fs::write(
        &path,
        r#"name = "bar"
[run]
t_end = 0.01
[solid]
density = 1000.0
young = 1.0e6
poisson = 0.0
gravity = [0.0, -9.81]
[[solid.bodies]]
shape = { box = { center = [0.5, 0.0], size = [1.0, 0.1] } }
divisions = [10, 1]
[[solid.constraints]]
region = { box = { lower = [-1.0, -1.0], upper = [0.1, 1.0] } }
motion = "fixed"
[[output.probes]]
name = "tip"
particle_at = [0.95, 0.0]
"#,
    )
    .expect("write");
    let out = dir.join("out");
    run_scene(&path, &out, &[]);
    let s = summary(&out);
    assert_eq!(s["status"], "completed");
    assert!(s["energy_rel_err"].as_f64().expect("energy") < 1e-2, "{s}");
    let csv = std::fs::read_to_string(out.join("solid_0.csv")).expect("solid_0.csv");
    assert_eq!(csv.lines().count(), 11, "{csv}");
    assert!(csv.starts_with("id,x,y,vx,vy,"), "{csv}");
    let probe = std::fs::read_to_string(out.join("probe_tip.csv")).expect("probe");
    assert!(probe.starts_with("t,x,y,vx,vy,sigma_n\n"), "{probe}");
    // The tip falls under gravity: its last y is below its first.
    let ys = cosim_tests::csv_column(&out.join("probe_tip.csv"), "y");
    assert!(ys.len() as u64 == s["steps"].as_u64().expect("steps"));
    assert!(ys.last() < ys.first(), "{:?} {:?}", ys.first(), ys.last());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn density_wave_scene_returns_to_its_initial_state() {
    let out = out_dir("density-wave");
    run_scene(&workspace().join("scenes/density-wave.toml"), &out, &[]);
    let rows = cosim_tests::read_table(&out.join("fluid_0.csv")).rows;
    let h = 1.0 / rows.len() as f64;
    let two_pi = 2.0 * std::f64::consts::PI;
    // After one period the exact cell averages are the initial ones.
    let l1: f64 = rows
        .iter()
        .map(|r| {
            let (a, b) = (r[0] - h / 2.0, r[0] + h / 2.0);
            let exact = 1.0 - 0.2 * ((two_pi * b).cos() - (two_pi * a).cos()) / (two_pi * h);
            (r[1] - exact).abs() * h
        })
        .sum();
    assert_eq!(rows.len(), 200);
    // OSMP5, N = 200, one period: 3.57e-10 measured.
    assert!(l1 < 5e-10, "L1 density error {l1:e}");
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn leftovers_of_a_crashed_run_are_cleaned_at_the_next_start() {
    let dir = out_dir("crashed");
    let scene = long_doubles_scene(&dir);
    let out = dir.join("out");
    // No other run may start (and sweep) until this test has counted the leftovers.
    let _exclusive = STARTS
        .write()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let (mut child, run_id) = spawn_long_run(&scene, &out, 100_000, false, false);
    assert!(
        !node_pids(&run_id).is_empty(),
        "no nodes found for {run_id}"
    );
    // SIGKILL: no cleanup runs in the coupler; its nodes see it gone and exit.
    child.kill().expect("kill");
    child.wait().expect("reaped");
    let deadline = Instant::now() + Duration::from_secs(10);
    while !node_pids(&run_id).is_empty() {
        assert!(
            Instant::now() < deadline,
            "nodes of the killed coupler still run"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let prefix = format!("cosim_{run_id}_");
    let leftovers = || {
        std::fs::read_dir("/dev/shm")
            .expect("/dev/shm")
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
            .count()
    };
    assert!(leftovers() > 0, "the crash left nothing to clean");
    let next = dir.join("next");
    let r = coupler()
        .arg("run")
        .arg(workspace().join("scenes/backbone-doubles.toml"))
        .arg("--out")
        .arg(&next)
        .output()
        .expect("coupler starts");
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{stderr}");
    assert_eq!(leftovers(), 0, "leftovers of {run_id} survived: {stderr}");
    let _ = std::fs::remove_dir_all(dir);
}

/// SIGKILLs `pid`, then waits for the coupler `child` to exit, at most `limit`: its status, the
/// time it took after the kill, and its stderr.
pub(crate) fn kill_and_wait(
    pid: &str,
    child: &mut std::process::Child,
    limit: Duration,
) -> (std::process::ExitStatus, Duration, String) {
    let killed = Instant::now();
    let kill = Command::new("kill")
        .args(["-9", pid])
        .status()
        .expect("kill");
    assert!(kill.success(), "kill -9 {pid}");
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        assert!(
            killed.elapsed() < limit,
            "coupler still running {limit:?} after the kill"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    let took = killed.elapsed();
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().expect("stderr"), &mut stderr)
        .expect("read");
    (status, took, stderr)
}
