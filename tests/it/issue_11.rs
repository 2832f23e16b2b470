//! Issue 11 through the real binaries: signals end a run cleanly (items 5), bad `--timeout-s`
//! values are refused (item 7), a scene larger than the machine is refused before any process
//! starts (item 6), an output time of 0 writes the initial state (item 9) and a collapsing time
//! step stops the run naming what limits it (item 10).

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use coupler_node::record;

use crate::e2e::{
    coupler, long_doubles_scene, node_pids, out_dir, shared_start, start_long_run, summary,
    workspace,
};

/// Exit status of `coupler-node run` stopped by SIGINT, SIGTERM or SIGHUP (docs/usage.md, "Deadlines, exit status, signals").
const INTERRUPTED: i32 = 130;

/// Files of run `run_id` left in /dev/shm.
fn shm_leftovers(run_id: &str) -> Vec<String> {
    let prefix = format!("cosim_{run_id}_");
    std::fs::read_dir("/dev/shm")
        .expect("/dev/shm")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&prefix))
        .collect()
}

/// Sends `signal` to the coupler of a long run (to its whole process group, as Ctrl-C in a
/// terminal does, when `group`), then checks that the run ended as an interrupted run: the
/// documented exit status, `interrupted` in the summary, a finished record, no node and no
/// shared-memory file left.
fn signal_ends_the_run_cleanly(signal: &str, group: bool) {
    let tag = format!(
        "signal-{signal}-{}",
        if group { "group" } else { "coupler" }
    );
    let dir = out_dir(&tag);
    let scene = long_doubles_scene(&dir);
    let out = dir.join("out");
    let (mut child, run_id) = start_long_run(&scene, &out, 100_000, true, group);
    let target = if group {
        format!("-{}", child.id())
    } else {
        child.id().to_string()
    };
    // The shell's builtin `kill` (dash reads `-SIG -PGID` as a signal and a process group).
    let sent = Command::new("sh")
        .args(["-c", &format!("kill -{signal} {target}")])
        .status()
        .expect("kill");
    assert!(sent.success());
    let sent = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        assert!(
            sent.elapsed() < Duration::from_secs(20),
            "coupler still running 20 s after SIG{signal}"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().expect("stderr"), &mut stderr)
        .expect("read");
    assert_eq!(status.code(), Some(INTERRUPTED), "SIG{signal}: {stderr}");
    let s = summary(&out);
    let status = s["status"].as_str().expect("status");
    assert!(status.starts_with("interrupted"), "SIG{signal}: {s}");
    assert!(!status.contains("died"), "SIG{signal}: {s}");
    let rec = record::read_recording(&std::fs::read(out.join("exchange.mcap")).expect("record"))
        .expect("readable");
    assert!(!rec.truncated(), "SIG{signal}: the record was not finished");
    let deadline = Instant::now() + Duration::from_secs(10);
    while !node_pids(&run_id).is_empty() {
        assert!(Instant::now() < deadline, "SIG{signal}: nodes left running");
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(shm_leftovers(&run_id), Vec::<String>::new(), "SIG{signal}");
    let _ = std::fs::remove_dir_all(dir);
}

/// `coupler-node run scene --out out --timeout-s timeout_s` with `fluid` as the fluid node.
fn run_with_fluid(
    fluid: &std::ffi::OsStr,
    scene: &Path,
    out: &Path,
    timeout_s: &str,
) -> std::process::Output {
    let _start = shared_start();
    coupler()
        .env("COSIM_FLUID_BIN", fluid)
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(["--quiet", "--timeout-s", timeout_s])
        .output()
        .expect("coupler-node starts")
}

/// A node whose process fails before it joins the bus (`false` here; `mpirun` refusing to run
/// as root, or a missing library, in a user's run): the coupler names it and ends at once, the
/// node that did start ends cleanly on its shutdown, and no node is left. Before, the shutdown
/// the coupler sent the failed node waited for it for the transport's send timeout
/// (`--timeout-s`, 60 s here), and the other node complained of a shutdown instead of a welcome.
#[test]
fn a_node_that_fails_before_it_joins_ends_the_run_at_once() {
    let dir = out_dir("node-fails-at-start");
    let scene = long_doubles_scene(&dir);
    let out = dir.join("out");
    let started = Instant::now();
    let output = run_with_fluid("false".as_ref(), &scene, &out, "60");
    let took = started.elapsed();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    assert!(
        took < Duration::from_secs(20),
        "the run ended {took:?} after it started: {stderr}"
    );
    let s = summary(&out);
    let status = s["status"].as_str().expect("status");
    assert!(status.starts_with("fluid node died"), "{s}");
    assert!(!stderr.contains("unexpected message"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let _ = std::fs::remove_dir_all(dir);
}

/// A node that starts and never greets (a process that hangs at its start): the run stops at
/// the deadline naming that node alone. Before, the status named "fluid and solid": the solid,
/// which had greeted, waited for the step plan that comes once both have, and was blamed too.
#[test]
fn a_node_that_never_greets_is_named_alone() {
    let dir = out_dir("node-never-greets");
    let scene = long_doubles_scene(&dir);
    let out = dir.join("out");
    let hang = dir.join("hang.sh");
    std::fs::write(&hang, "#!/bin/sh\nexec sleep 60\n").expect("write");
    std::fs::set_permissions(&hang, std::os::unix::fs::PermissionsExt::from_mode(0o755))
        .expect("chmod");
    let output = run_with_fluid(hang.as_os_str(), &scene, &out, "2");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    let s = summary(&out);
    let status = s["status"].as_str().expect("status");
    assert!(
        status.starts_with("fluid node stopped answering: no message within 2s at step 0"),
        "{s}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn sigterm_to_the_coupler_ends_the_run_as_interrupted() {
    signal_ends_the_run_cleanly("TERM", false);
}

#[test]
fn sigint_to_the_coupler_ends_the_run_as_interrupted() {
    signal_ends_the_run_cleanly("INT", false);
}

#[test]
fn sighup_to_the_coupler_ends_the_run_as_interrupted() {
    signal_ends_the_run_cleanly("HUP", false);
}

#[test]
fn ctrl_c_to_the_process_group_ends_the_run_as_interrupted() {
    signal_ends_the_run_cleanly("INT", true);
}

#[test]
fn sighup_to_the_process_group_ends_the_run_as_interrupted() {
    signal_ends_the_run_cleanly("HUP", true);
}

/// Runs a command to its end and returns (exit code, stderr).
fn outcome(cmd: &mut Command) -> (Option<i32>, String) {
    let r = cmd.stdin(Stdio::null()).output().expect("starts");
    (
        r.status.code(),
        String::from_utf8_lossy(&r.stderr).into_owned(),
    )
}

#[test]
fn bad_timeouts_are_refused_with_a_clear_error() {
    let scene = workspace().join("scenes/backbone-doubles.toml");
    let dir = out_dir("bad-timeout");
    let node_bins = [
        env!("CARGO_BIN_EXE_it-fluid-node"),
        env!("CARGO_BIN_EXE_it-solid-node"),
    ];
    for value in ["-1", "nan", "inf", "1e30", "0"] {
        let arg = format!("--timeout-s={value}");
        let (code, stderr) = outcome(
            coupler()
                .arg("run")
                .arg(&scene)
                .arg("--out")
                .arg(&dir)
                .arg(&arg),
        );
        assert_eq!(code, Some(2), "run {arg}: {stderr}");
        assert!(
            stderr.contains("--timeout-s") && !stderr.contains("panicked"),
            "run {arg}: {stderr}"
        );
        let (code, stderr) = outcome(
            coupler()
                .args(["replay", "x.mcap", "--step", "1"])
                .args(["--node", "fluid", &arg]),
        );
        assert_eq!(code, Some(2), "replay {arg}: {stderr}");
        assert!(
            stderr.contains("--timeout-s") && !stderr.contains("panicked"),
            "replay {arg}: {stderr}"
        );
        for bin in node_bins {
            let (code, stderr) =
                outcome(Command::new(bin).args(["--scene", "x.toml", "--run-id", "x", &arg]));
            assert_eq!(code, Some(2), "{bin} {arg}: {stderr}");
            assert!(
                stderr.contains("--timeout-s") && !stderr.contains("panicked"),
                "{bin} {arg}: {stderr}"
            );
        }
    }
    assert!(!dir.exists(), "a refused run created its output folder");
}

#[test]
fn a_scene_larger_than_the_machine_is_refused_before_any_process_starts() {
    let dir = out_dir("oversized");
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("huge.toml");
    std::fs::write(
        &path,
        r#"name = "huge"
[fluid]
lower = [0.0, 0.0, 0.0]
upper = [1.0, 1.0, 1.0]
cells = [2000, 2000, 2000]
[[fluid.init]]
region = "all"
rho = 1.0
p = 1.0
"#,
    )
    .expect("write");
    let out = dir.join("out");
    let started = Instant::now();
    let (code, stderr) = outcome(coupler().arg("run").arg(&path).arg("--out").arg(&out));
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("fluid.cells") && stderr.contains("memory") && stderr.contains("GiB"),
        "{stderr}"
    );
    assert!(!out.exists(), "the run created its output folder");
    // Refused from the estimate, not after an allocation: well under the time a start takes.
    assert!(started.elapsed() < Duration::from_secs(30));
    let _ = std::fs::remove_dir_all(dir);
}

/// The sod scene with `edit` applied to its text, run through the coupler into `out`.
fn run_edited_sod(dir: &Path, edit: impl Fn(String) -> String) -> (Option<i32>, String) {
    std::fs::create_dir_all(dir).expect("dir");
    let text = edit(std::fs::read_to_string(workspace().join("scenes/sod.toml")).expect("scene"));
    let path = dir.join("sod.toml");
    std::fs::write(&path, text).expect("write");
    let _start = shared_start();
    outcome(
        coupler()
            .arg("run")
            .arg(&path)
            .arg("--out")
            .arg(dir.join("out"))
            .arg("--quiet"),
    )
}

#[test]
fn an_output_time_of_zero_writes_the_initial_state_as_output_zero() {
    let dir = out_dir("output-zero");
    let (code, stderr) = run_edited_sod(&dir, |t| t + "\n[output]\ntimes = [0.0, 0.1]\n");
    assert_eq!(code, Some(0), "{stderr}");
    let out = dir.join("out");
    let outputs = std::fs::read_to_string(out.join("outputs.csv")).expect("outputs.csv");
    let ts = cosim_tests::csv_column(&out.join("outputs.csv"), "t");
    assert_eq!(ts.len(), 3, "{outputs}");
    assert_eq!(ts[0], 0.0, "{outputs}");
    assert!((ts[1] - 0.1).abs() < 1e-12, "{outputs}");
    // Output 0 is the initial Sod state: density 1 on the left, 0.125 on the right.
    let rho = cosim_tests::csv_column(&out.join("fluid_0.csv"), "rho");
    assert_eq!(rho.first(), Some(&1.0), "{rho:?}");
    assert_eq!(rho.last(), Some(&0.125));
    assert!(out.join("fluid_2.csv").exists());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_collapsing_time_step_stops_the_run_naming_the_cell() {
    let dir = out_dir("dt-min");
    // An absolute floor the first step already breaks: the report names node, limiter and cell.
    let (code, stderr) = run_edited_sod(&dir, |t| t.replace("[run]\n", "[run]\ndt_min = 0.1\n"));
    assert_eq!(code, Some(2), "{stderr}");
    let s = summary(&dir.join("out"));
    let status = s["status"].as_str().expect("status");
    assert!(
        status.contains("run.dt_min") && status.contains("fluid") && status.contains("cell"),
        "{status}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_near_vacuum_scene_is_stopped_by_the_default_dt_min() {
    let dir = out_dir("dt-min-default");
    // The issue's case: 1e-300 kg/m³ beside the gas (without a floor: 1e-8 s steps for hours).
    let (code, stderr) = run_edited_sod(&dir, |t| t.replace("rho = 0.125", "rho = 1e-300"));
    assert_eq!(code, Some(2), "{stderr}");
    let s = summary(&dir.join("out"));
    let status = s["status"].as_str().expect("status");
    assert!(
        status.contains("run.dt_min") && status.contains("default") && status.contains("cell"),
        "{status}"
    );
    assert!(s["steps"].as_u64().expect("steps") < 10, "{s}");
    let _ = std::fs::remove_dir_all(dir);
}
