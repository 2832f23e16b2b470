//! Issue 15 items 2 and 3 through the real binary: `coupler-node check` passes every scene of
//! `scenes/`, refuses a bad key with `run`'s error and a replay record that is missing, damaged
//! or of the other node; an enumerated option's typo gets a suggestion and exit 2; and a run
//! whose stderr is piped prints plain progress lines (no `\r`) ending on 100 %.

use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};

use crate::e2e::{coupler, out_dir, shared_start, workspace};

fn check(scene: &Path, extra: &[&str]) -> Output {
    coupler()
        .arg("check")
        .arg(scene)
        .args(extra)
        .stdin(Stdio::null())
        .output()
        .expect("coupler starts")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `scenes/NAME` with `from` replaced by `to`, written into `dir`.
fn edited(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let text = std::fs::read_to_string(workspace().join("scenes").join(name)).expect("scene");
    assert!(text.contains(from), "{name} has {from:?}");
    let path = dir.join(name);
    std::fs::write(&path, text.replacen(from, to, 1)).expect("write");
    path
}

#[test]
fn issue_15_every_scene_passes_check() {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(workspace().join("scenes"))
        .expect("scenes/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 10, "{scenes:?}");
    for scene in &scenes {
        let out = check(scene, &[]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}: {}",
            scene.display(),
            stderr(&out)
        );
        let name = scene.file_stem().expect("stem").to_string_lossy();
        assert!(
            stdout.starts_with(&format!("{name}: ok, ")) && stdout.contains(" t_end "),
            "{stdout}"
        );
    }
    let sod = check(&workspace().join("scenes/sod.toml"), &[]);
    assert_eq!(
        String::from_utf8_lossy(&sod.stdout),
        "sod: ok, 1-D, fluid real 400 cells (400), no solid, record exchange, t_end 2.000e-1 s, memory 0.0 MiB\n"
    );
}

#[test]
fn issue_15_check_refuses_a_bad_key_with_the_error_run_gives() {
    let dir = out_dir("issue15-check-bad-key");
    let scene = edited(&dir, "sod.toml", "t_end = ", "t_ned = ");
    let checked = check(&scene, &[]);
    assert_eq!(checked.status.code(), Some(2));
    let err = stderr(&checked);
    assert!(err.contains("t_ned") && err.contains("sod.toml"), "{err}");
    let run = coupler()
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(dir.join("out"))
        .arg("--quiet")
        .stdin(Stdio::null())
        .output()
        .expect("coupler starts");
    assert_eq!(run.status.code(), Some(2));
    assert_eq!(stderr(&run), err);
    assert!(!dir.join("out").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn issue_15_check_refuses_a_missing_or_damaged_replay_record() {
    let dir = out_dir("issue15-check-replay");
    let missing = dir.join("missing.mcap");
    let scene = edited(
        &dir,
        "backbone-doubles.toml",
        "node = \"pressure\"",
        &format!("node = \"replay:{}\"", missing.display()),
    );
    let out = check(&scene, &[]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains(&format!("fluid.node = \"replay:{}\"", missing.display()))
            && err.contains("reading the record"),
        "{err}"
    );
    std::fs::write(&missing, b"not a record").expect("write");
    let out = check(&scene, &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("cannot be replayed"),
        "{}",
        stderr(&out)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn issue_15_a_typo_in_an_enumerated_option_gets_a_suggestion_and_exit_2() {
    let out = coupler()
        .args(["replay", "x.mcap", "--step", "1", "--node", "fluidd"])
        .output()
        .expect("coupler starts");
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains("[possible values: fluid, solid, coupler]")
            && err.contains("a similar value exists: 'fluid'"),
        "{err}"
    );
    let help = coupler().arg("--help").output().expect("coupler starts");
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("Exit codes:") && help.contains("130") && help.contains("coupler-node check"),
        "{help}"
    );
}

#[test]
fn issue_15_piped_progress_is_plain_lines_ending_at_100_percent_and_its_record_checks() {
    let dir = out_dir("issue15-progress");
    let scene = edited(&dir, "sod.toml", "cells = [400]", "cells = [60]");
    let out = dir.join("out");
    let run = {
        let _start = shared_start();
        coupler()
            .arg("run")
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .stdin(Stdio::null())
            .stderr(Stdio::piped())
            .output()
            .expect("coupler starts")
    };
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(0), "{err}");
    assert!(!err.contains('\r'), "{err:?}");
    let progress: Vec<&str> = err.lines().filter(|l| l.contains(" ETA ")).collect();
    let last = progress.last().expect("a progress line");
    assert!(
        last.starts_with("sod [########################] t = 2.0000e-1/2.0000e-1 s (100.0%)"),
        "{err}"
    );
    // The record is a fluid record: it checks as the fluid's double, and not as the solid's.
    let record = out.join("exchange.mcap");
    let fluid = format!("replay:{}", record.display());
    let ok = check(&scene, &["--fluid", &fluid]);
    assert_eq!(ok.status.code(), Some(0), "{}", stderr(&ok));
    let doubles = workspace().join("scenes/backbone-doubles.toml");
    let wrong = check(&doubles, &["--solid", &fluid]);
    assert_eq!(wrong.status.code(), Some(2));
    assert!(
        stderr(&wrong).contains("cannot be replayed"),
        "{}",
        stderr(&wrong)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
