//! Issue 15 item 1 through the real binaries: the logs of the three processes. A good run with
//! `-q` prints nothing, by default one info line (the summary), with `-v` the debug lines of the
//! coupler and of the nodes it starts; `RUST_LOG` decides over the flags and reaches the nodes;
//! every line a launched run writes on stderr is a progress line or a log line that starts with
//! its process's name; and the final error reports are the same text at every level.

use std::path::{Path, PathBuf};
use std::process::Stdio;

use crate::e2e::{coupler, out_dir, shared_start, workspace};

/// `scenes/NAME` with each `(from, to)` replaced once, written into `dir`.
fn edited(dir: &Path, name: &str, edits: &[(&str, &str)]) -> PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let mut text = std::fs::read_to_string(workspace().join("scenes").join(name)).expect("scene");
    for (from, to) in edits {
        assert!(text.contains(from), "{name} has {from:?}");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write");
    path
}

/// Sod on 60 cells (a run of a second).
fn small_sod(dir: &Path) -> PathBuf {
    edited(dir, "sod.toml", &[("cells = [400]", "cells = [60]")])
}

/// `coupler-node run SCENE --out OUT FLAGS` with `RUST_LOG` set to `rust_log` (unset for
/// `None`): exit code and stderr.
fn run(scene: &Path, out: &Path, flags: &[&str], rust_log: Option<&str>) -> (Option<i32>, String) {
    let _start = shared_start();
    let _ = std::fs::remove_dir_all(out);
    let mut cmd = coupler();
    cmd.arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(flags)
        .stdin(Stdio::null());
    if let Some(value) = rust_log {
        cmd.env("RUST_LOG", value);
    }
    let r = cmd.output().expect("coupler starts");
    (
        r.status.code(),
        String::from_utf8_lossy(&r.stderr).into_owned(),
    )
}

/// A log line split into process, level and the rest, or `None` for any other line.
fn log_line(line: &str) -> Option<(&str, &str, &str)> {
    let (node, level, rest) = (line.get(..8)?, line.get(8..14)?, line.get(14..)?);
    let node = ["coupler ", "fluid   ", "solid   "]
        .contains(&node)
        .then(|| node.trim_end())?;
    let level = ["TRACE ", "DEBUG ", " INFO ", " WARN ", "ERROR "]
        .contains(&level)
        .then(|| level.trim())?;
    Some((node, level, rest))
}

/// The log lines of `stderr` from `node` at `level`.
fn logs<'a>(stderr: &'a str, node: &str, level: &str) -> Vec<&'a str> {
    stderr
        .lines()
        .filter_map(log_line)
        .filter(|(n, l, _)| *n == node && *l == level)
        .map(|(_, _, rest)| rest)
        .collect()
}

fn is_progress(line: &str) -> bool {
    line.contains(" ETA ")
}

/// Whether `line` is iceoryx2's own log output: `<n> [W] "origin" ` and the `| message` lines
/// under it. iceoryx2 warns once per process, at warn level, the first time anything looks up its
/// global config ("No config file was loaded"); whether a run does depends on the shutdown path,
/// so such a line comes and goes between runs of one scene. It is a log line, not a report.
fn iceoryx2_line(line: &str) -> bool {
    let digits = line.bytes().take_while(u8::is_ascii_digit).count();
    line.starts_with("| ")
        || (digits > 0
            && ["[T]", "[D]", "[I]", "[W]", "[E]", "[F]"]
                .iter()
                .any(|tag| line[digits..].starts_with(&format!(" {tag} "))))
}

/// The lines of `stderr` that are neither log nor progress lines: the error reports.
fn reports(stderr: &str) -> Vec<&str> {
    stderr
        .lines()
        .filter(|l| log_line(l).is_none() && !iceoryx2_line(l) && !is_progress(l))
        .collect()
}

#[test]
fn issue_15_logs_q_is_silent_default_is_the_summary_v_adds_the_debug_lines_of_all() {
    let dir = out_dir("issue15-logs-levels");
    let scene = small_sod(&dir);
    let out = dir.join("out");

    let (code, quiet) = run(&scene, &out, &["-q"], None);
    assert_eq!(code, Some(0), "{quiet}");
    assert_eq!(quiet, "", "a good run with -q prints nothing");

    let (code, default) = run(&scene, &out, &[], None);
    assert_eq!(code, Some(0), "{default}");
    let info = logs(&default, "coupler", "INFO");
    assert_eq!(info.len(), 1, "{default}");
    assert!(info[0].starts_with("sod: completed in "), "{default}");
    assert!(
        default
            .lines()
            .all(|l| is_progress(l) || log_line(l).is_some_and(|(_, level, _)| level == "INFO")),
        "{default}"
    );
    assert!(default.lines().any(is_progress), "{default}");

    let (code, verbose) = run(&scene, &out, &["-v"], None);
    assert_eq!(code, Some(0), "{verbose}");
    let coupler_debug = logs(&verbose, "coupler", "DEBUG");
    assert!(
        coupler_debug
            .iter()
            .any(|l| l.starts_with("coupler_node::driver: the fluid node greeted: real")),
        "{verbose}"
    );
    assert!(
        coupler_debug
            .iter()
            .any(|l| l.starts_with("coupler_node::driver: step 0 done: t = ")),
        "{verbose}"
    );
    // The coupler's -v reaches the fluid node it starts.
    let fluid_debug = logs(&verbose, "fluid", "DEBUG");
    for start in [
        "protocol::serve: started: real fluid",
        "protocol::session: greeted the coupler: real fluid",
        "protocol::session: step 0 done: t = ",
        "protocol::session: shutdown at step ",
    ] {
        assert!(
            fluid_debug.iter().any(|l| l.starts_with(start)),
            "{start}: {verbose}"
        );
    }
    assert!(logs(&verbose, "fluid", "TRACE").is_empty(), "{verbose}");
    assert_eq!(logs(&verbose, "coupler", "INFO").len(), 1, "{verbose}");
    assert!(verbose.lines().any(is_progress), "{verbose}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn issue_15_logs_rust_log_decides_over_the_flags_and_reaches_the_nodes() {
    let dir = out_dir("issue15-logs-rust-log");
    let scene = small_sod(&dir);
    let out = dir.join("out");

    // One module at debug; the others at the flags' level (info: the summary stays).
    let (code, err) = run(&scene, &out, &[], Some("coupler_node::driver=debug"));
    assert_eq!(code, Some(0), "{err}");
    let debug = logs(&err, "coupler", "DEBUG");
    assert!(!debug.is_empty(), "{err}");
    assert!(
        debug
            .iter()
            .all(|l| l.starts_with("coupler_node::driver: ")),
        "{err}"
    );
    assert!(logs(&err, "fluid", "DEBUG").is_empty(), "{err}");
    assert_eq!(logs(&err, "coupler", "INFO").len(), 1, "{err}");

    // RUST_LOG wins over -q in every process; -q still turns the progress line off.
    let (code, err) = run(&scene, &out, &["-q"], Some("debug"));
    assert_eq!(code, Some(0), "{err}");
    assert!(!logs(&err, "coupler", "DEBUG").is_empty(), "{err}");
    assert!(!logs(&err, "fluid", "DEBUG").is_empty(), "{err}");
    assert!(!err.lines().any(is_progress), "{err}");

    // RUST_LOG=warn is -q for the logs, not for the progress line.
    let (code, err) = run(&scene, &out, &[], Some("warn"));
    assert_eq!(code, Some(0), "{err}");
    assert!(err.lines().all(is_progress), "{err}");

    // A value that does not parse is said, once by each process, and the flags decide.
    let (code, err) = run(&scene, &out, &[], Some("coupler_node=loud"));
    assert_eq!(code, Some(0), "{err}");
    for node in ["coupler", "fluid"] {
        let warned = logs(&err, node, "WARN");
        assert_eq!(warned.len(), 1, "{node}: {err}");
        assert!(
            warned[0].starts_with("RUST_LOG=\"coupler_node=loud\" is not a filter: ")
                && warned[0].ends_with("; using the -v/-q level"),
            "{err}"
        );
    }
    assert_eq!(logs(&err, "coupler", "INFO").len(), 1, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn issue_15_logs_every_line_of_a_coupled_run_names_its_process() {
    let dir = out_dir("issue15-logs-coupled");
    let scene = workspace().join("scenes/backbone-doubles.toml");
    let out = dir.join("out");
    let (code, err) = run(&scene, &out, &["-vv"], None);
    assert_eq!(code, Some(0), "{err}");
    let strays: Vec<&str> = err
        .lines()
        .filter(|l| log_line(l).is_none() && !l.starts_with("backbone-doubles ["))
        .collect();
    assert!(strays.is_empty(), "lines of no process: {strays:?}");
    for node in ["coupler", "fluid", "solid"] {
        for level in ["DEBUG", "TRACE"] {
            assert!(!logs(&err, node, level).is_empty(), "{node} {level}");
        }
    }
    // The fixed point of step 0, iteration by iteration, from the three sides; checkpoints.
    for (node, level, start) in [
        (
            "coupler",
            "TRACE",
            "coupler_node::driver: step 0 iteration 0: residual ",
        ),
        (
            "fluid",
            "TRACE",
            "fluid_node::node: step 0 iteration 0: loads sent, ",
        ),
        (
            "solid",
            "TRACE",
            "solid_node::node: step 0 iteration 0: trial sent, ",
        ),
        (
            "solid",
            "DEBUG",
            "protocol::session: checkpoint of step 20: ",
        ),
    ] {
        assert!(
            logs(&err, node, level).iter().any(|l| l.starts_with(start)),
            "{node} {level} {start}"
        );
    }
    let accepted = logs(&err, "solid", "TRACE")
        .iter()
        .filter(|l| l.contains(", Accept at residual "))
        .count();
    let steps = logs(&err, "coupler", "DEBUG")
        .iter()
        .filter(|l| l.contains(": step ") && l.contains(" done: t = "))
        .count();
    assert!(steps > 10, "{steps} steps");
    assert_eq!(accepted, steps, "one accepted trial a step");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn issue_15_logs_leave_the_error_reports_as_they_were_at_every_level() {
    let dir = out_dir("issue15-logs-errors");
    let levels: [&[&str]; 5] = [&["-qq"], &["-q"], &[], &["-v"], &["-vv"]];

    // A bad key: `run` at any level gives `check`'s stderr, byte for byte.
    let bad = edited(&dir, "sod.toml", &[("t_end = ", "t_ned = ")]);
    let checked = coupler()
        .arg("check")
        .arg(&bad)
        .output()
        .expect("coupler starts");
    assert_eq!(checked.status.code(), Some(2));
    let checked = String::from_utf8_lossy(&checked.stderr).into_owned();
    assert!(
        checked.starts_with("coupler-node: ") && checked.contains("t_ned"),
        "{checked}"
    );
    for flags in levels {
        let (code, err) = run(&bad, &dir.join("bad-out"), flags, None);
        assert_eq!(code, Some(2), "{flags:?}: {err}");
        assert_eq!(err, checked, "{flags:?}");
    }

    // Numerical trouble: a time step the fluid limits below run.dt_min (names step and cell),
    // and a fixed point that does not converge (names the step and the residual history).
    let collapse = edited(
        &dir,
        "sod.toml",
        &[
            ("cells = [400]", "cells = [60]"),
            ("[run]\n", "[run]\ndt_min = 0.1\n"),
        ],
    );
    let stalled = edited(
        &dir,
        "backbone-doubles.toml",
        &[("max_iterations = 60", "max_iterations = 3")],
    );
    for (scene, start, named) in [
        (
            &collapse,
            "coupler-node: the time step collapsed at step 0, t = ",
            "(cfl at cell [",
        ),
        (
            &stalled,
            "coupler-node: fixed point not converged at step 0",
            "residual history",
        ),
    ] {
        let (code, silent) = run(scene, &dir.join("out"), &["-qq"], None);
        assert_eq!(code, Some(2), "{silent}");
        assert!(
            silent
                .lines()
                .any(|l| l.starts_with(start) && l.contains(named)),
            "{start}: {silent}"
        );
        assert_eq!(reports(&silent), silent.lines().collect::<Vec<_>>());
        for flags in levels {
            let (code, err) = run(scene, &dir.join("out"), flags, None);
            assert_eq!(code, Some(2), "{flags:?}: {err}");
            assert_eq!(reports(&err), reports(&silent), "{flags:?}: {err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
