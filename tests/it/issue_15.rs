//! Issue 15 through the real binaries: `formats = ["vtk"]` writes VTK XML files and one `.pvd`
//! per kind naming each file's time (item 4), and a run into an `--out` folder that holds an
//! earlier run's files is refused unless `--overwrite`, which leaves no stale file (item 7).

use std::path::{Path, PathBuf};
use std::process::Stdio;

use protocol::vtk::read;

use crate::e2e::{coupler, out_dir, run_scene, shared_start, summary, workspace};

/// Sod on 60 cells with `output` as its `[output]` section, written into `dir`.
fn sod(dir: &Path, name: &str, output: &str) -> PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let text = std::fs::read_to_string(workspace().join("scenes/sod.toml"))
        .expect("scene")
        .replace("cells = [400]", "cells = [60]");
    assert!(text.contains("cells = [60]"));
    let path = dir.join(name);
    std::fs::write(&path, format!("{text}\n[output]\n{output}\n")).expect("write");
    path
}

/// `k,t` of `outputs.csv`.
fn output_times(out: &Path) -> Vec<(u32, f64)> {
    let table = cosim_tests::read_table(&out.join("outputs.csv"));
    let pairs = table.pairs("k", "t").expect("k,t");
    pairs.into_iter().map(|(k, t)| (k as u32, t)).collect()
}

/// Checks that `OUT/<kind>.pvd` lists `<kind>_<k>.<ext>` at each output's time, in order, and
/// that each file decodes; returns the decoded files.
fn series(out: &Path, kind: &str, ext: &str) -> Vec<read::VtkFile> {
    let text = std::fs::read_to_string(out.join(format!("{kind}.pvd"))).expect("pvd");
    let entries = read::pvd(&text).expect("a collection");
    let times = output_times(out);
    assert_eq!(entries.len(), times.len(), "{kind}.pvd: {text}");
    entries
        .iter()
        .zip(&times)
        .map(|((t, file), (k, t_out))| {
            assert_eq!(file, &format!("{kind}_{k}.{ext}"));
            // Both are written as the shortest text that reads back to the same double.
            assert_eq!(
                t.to_bits(),
                t_out.to_bits(),
                "{kind}.pvd time of output {k}"
            );
            read::parse(&std::fs::read(out.join(file)).expect("file")).expect("decodes")
        })
        .collect()
}

#[test]
fn issue_15_vtk_xml_files_and_their_series_hold_the_csv_outputs() {
    let dir = out_dir("issue15-fluid");
    let scene = sod(
        &dir,
        "sod.toml",
        "times = [0.0, 0.1]\nformats = [\"csv\", \"vtk\"]",
    );
    let out = dir.join("out");
    run_scene(&scene, &out, &[]);
    let files = series(&out, "fluid", "vti");
    assert_eq!(files.len(), 3);
    for (k, file) in files.iter().enumerate() {
        // A 1-D fluid is a line of cells: its inactive axes are flat (issue 39).
        assert_eq!(file.dataset["WholeExtent"], "0 60 0 0 0 0");
        let rho = file
            .array("CellData", "rho")
            .and_then(|a| a.as_f64())
            .expect("rho");
        let csv = cosim_tests::csv_column(&out.join(format!("fluid_{k}.csv")), "rho");
        assert_eq!(rho.len(), csv.len());
        // The CSV holds 13 significant digits.
        for (cell, (a, b)) in rho.iter().zip(&csv).enumerate() {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs(),
                "output {k} cell {cell}: {a} in the .vti, {b} in the CSV"
            );
        }
    }
    assert!(
        !out.join("fluid_0.vtk").exists(),
        "legacy files only with \"vtk-legacy\""
    );

    // A solid alone: particles, faces and wet surface, each with its series.
    let bar = dir.join("bar.toml");
    let text = std::fs::read_to_string(workspace().join("scenes/cantilever.toml")).expect("scene");
    assert!(text.contains("formats = [\"csv\", \"vtk\"]") && text.contains("t_end = 2.0"));
    std::fs::write(&bar, text.replace("t_end = 2.0", "t_end = 0.1")).expect("write");
    let out = dir.join("bar");
    run_scene(&bar, &out, &[]);
    let particles = series(&out, "particles", "vtp");
    for kind in ["solid", "wet"] {
        assert_eq!(series(&out, kind, "vtp").len(), particles.len(), "{kind}");
    }
    let (k, last) = (particles.len() - 1, particles.last().expect("an output"));
    let points = last
        .array("Points", "Points")
        .and_then(|a| a.as_f64())
        .expect("points");
    let csv = cosim_tests::read_table(&out.join(format!("solid_{k}.csv")));
    let dim = if csv.column("z").is_some() { 3 } else { 2 };
    assert_eq!(points.len(), 3 * csv.rows.len());
    for d in 0..dim {
        // The CSV writes `{:e}`, which reads back to the same double.
        for (p, row) in csv.rows.iter().enumerate() {
            let x = row[1 + d];
            assert_eq!(
                points[3 * p + d].to_bits(),
                x.to_bits(),
                "particle {p} axis {d}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

fn run_into(scene: &Path, out: &Path, extra: &[&str]) -> (Option<i32>, String) {
    let _start = shared_start();
    let r = coupler()
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .stdin(Stdio::null())
        .output()
        .expect("coupler starts");
    (
        r.status.code(),
        String::from_utf8_lossy(&r.stderr).into_owned(),
    )
}

#[test]
fn issue_15_a_run_into_a_used_out_is_refused_unless_overwrite_and_leaves_no_stale_file() {
    let dir = out_dir("issue15-overwrite");
    let formats = "formats = [\"csv\", \"vtk\"]";
    let many = sod(
        &dir,
        "many.toml",
        &format!("times = [0.05, 0.1, 0.15]\n{formats}"),
    );
    let few = sod(&dir, "few.toml", &format!("times = [0.1]\n{formats}"));
    let out = dir.join("out");
    run_scene(&many, &out, &[]);
    assert_eq!(output_times(&out).len(), 4);
    let before = std::fs::read(out.join("summary.json")).expect("summary");

    // Without --overwrite: refused, naming the folder and the flag, and nothing is touched.
    let (code, stderr) = run_into(&few, &out, &[]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("output directory {} is not empty", out.display()))
            && stderr.contains("--overwrite"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read(out.join("summary.json")).expect("summary"),
        before
    );
    assert!(out.join("fluid_3.vti").exists() && out.join("fluid_3.csv").exists());

    // With it: the earlier run's files are gone, the new run's are there.
    let (code, stderr) = run_into(&few, &out, &["--overwrite"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(output_times(&out).len(), 2);
    assert_eq!(series(&out, "fluid", "vti").len(), 2);
    for stale in ["fluid_2.csv", "fluid_2.vti", "fluid_3.csv", "fluid_3.vti"] {
        assert!(
            !out.join(stale).exists(),
            "{stale} of the earlier run is left"
        );
    }
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .expect("out")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "exchange.mcap",
            "fluid.pvd",
            "fluid_0.csv",
            "fluid_0.vti",
            "fluid_1.csv",
            "fluid_1.vti",
            "ledger.csv",
            "outputs.csv",
            "scene.toml",
            "summary.json"
        ]
    );
    assert_eq!(summary(&out)["status"], "completed");

    // A file no run writes is never removed: --overwrite refuses and names it.
    std::fs::write(out.join("notes.txt"), "mine").expect("write");
    let (code, stderr) = run_into(&few, &out, &["--overwrite"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("entries no run writes (notes.txt)") && stderr.contains("--overwrite"),
        "{stderr}"
    );
    assert!(out.join("notes.txt").exists() && out.join("summary.json").exists());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn issue_15_overwrite_keeps_the_record_a_restart_reads() {
    let dir = out_dir("issue15-restart");
    let run = dir.join("run");
    run_scene(&workspace().join("scenes/backbone-doubles.toml"), &run, &[]);
    let record = run.join("exchange.mcap");
    let size = std::fs::metadata(&record).expect("record").len();
    let (code, stderr) = run_into(
        &run.join("scene.toml"),
        &run,
        &[
            "--overwrite",
            "--restart",
            &record.to_string_lossy(),
            "--step",
            "20",
        ],
    );
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("the record to restart from") && stderr.contains("choose another --out"),
        "{stderr}"
    );
    assert_eq!(std::fs::metadata(&record).expect("record").len(), size);
    let _ = std::fs::remove_dir_all(dir);
}
