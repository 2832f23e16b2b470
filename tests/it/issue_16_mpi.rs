//! Issue 16 through the binaries and MPI: `coupler-node run --fluid-ranks K` starts the fluid
//! with `mpirun -n K` (oversubscribed on 2 cores), and the record's frames and every output
//! file are those of one rank, bit for bit, for K = 2 and 4; a checkpoint written with 2 ranks
//! restores with 2; a rank killed mid-run ends the run naming the rank, and no rank is left.
//!
//! Built only with `--features mpi` (the test shim's fluid-node is then built with MPI):
//! `cargo test -p cosim-tests --features mpi --test it issue_16` (`.ci/run` runs it).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::e2e::{
    coupler, frames_by_topic, kill_and_wait, out_dir, run_scene_with, shared_start, summary,
};

/// Open MPI as root (CI runs as root) and in containers without ptrace between processes.
pub(crate) fn mpi_env(cmd: &mut Command) -> &mut Command {
    cmd.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_btl_vader_single_copy_mechanism", "none")
}

/// A 3-D blast of 24³ cells, 4 steps, outputs in every format, a probe, checkpoints.
fn blast_scene(dir: &Path, max_steps: u64, t_end: f64, output: &str) -> PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let path = dir.join("blast.toml");
    std::fs::write(
        &path,
        format!(
            r#"name = "mpiblast"
[run]
t_end = {t_end}
max_steps = {max_steps}
record = "all"
checkpoint_every = 2
[fluid]
flux = {{ scheme = "osmp", order = 5 }}
lower = [0.0, 0.0, 0.0]
upper = [1.0, 1.0, 1.0]
cells = [24, 22, 24]
boundary = {{ x = ["wall", "outflow"], y = ["wall", "wall"], z = ["outflow", "wall"] }}
[[fluid.init]]
region = "all"
rho = 1.4
p = 1.0
[[fluid.init]]
region = {{ ball = {{ center = [0.45, 0.5, 0.52], radius = 0.2 }} }}
rho = 8.0
p = 116.5
velocity = [0.3, -0.2, 0.1]
[output]
{output}
formats = ["csv", "vtk", "vtk-legacy"]
[[output.probes]]
name = "upper"
point = [0.5, 0.5, 0.8]
"#
        ),
    )
    .expect("scene");
    path
}

pub(crate) fn run(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut cmd = coupler();
    mpi_env(&mut cmd);
    run_scene_with(cmd, scene, out, extra)
}

/// Every file of a run but the two that hold wall-clock times or the rank count
/// (`summary.json`, `scene.toml`) and the record (compared frame by frame).
pub(crate) fn files(out: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(out)
        .expect("out")
        .map(|e| e.expect("entry").path())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            !matches!(name, "summary.json" | "scene.toml" | "exchange.mcap")
        })
        .map(|p| {
            let name = p.file_name().expect("name").to_string_lossy().into_owned();
            (name, std::fs::read(&p).expect("file"))
        })
        .collect();
    files.sort();
    files
}

#[test]
fn blast_3d_payloads_and_outputs_are_bit_identical_on_1_2_and_4_ranks() {
    let dir = out_dir("mpi-blast");
    let scene = blast_scene(&dir, 4, 1.0, "every = 0.004");
    let one = dir.join("one");
    run(&scene, &one, &[]);
    let frames = frames_by_topic(&one.join("exchange.mcap"));
    let outputs = files(&one);
    let names: Vec<&str> = outputs.iter().map(|(n, _)| n.as_str()).collect();
    for expected in [
        "fluid_0.csv",
        "fluid_0.vti",
        "fluid_0.vtk",
        "fluid.pvd",
        "probe_upper.csv",
    ] {
        assert!(names.contains(&expected), "{expected} in {names:?}");
    }
    assert!(
        frames.iter().any(|(t, _)| t.contains("checkpoint")),
        "checkpoints recorded"
    );
    for ranks in ["2", "4"] {
        let out = dir.join(format!("ranks{ranks}"));
        run(&scene, &out, &["--fluid-ranks", ranks]);
        let s = summary(&out);
        assert_eq!(s["status"], summary(&one)["status"], "{s}");
        assert_eq!(s["steps"], 4, "{s}");
        assert!(
            frames == frames_by_topic(&out.join("exchange.mcap")),
            "record frames of 1 and {ranks} ranks differ"
        );
        let many = files(&out);
        assert_eq!(
            outputs.iter().map(|(n, _)| n).collect::<Vec<_>>(),
            many.iter().map(|(n, _)| n).collect::<Vec<_>>()
        );
        for ((name, a), (_, b)) in outputs.iter().zip(&many) {
            assert!(a == b, "{name} of 1 and {ranks} ranks differs");
        }
    }
    // A checkpoint of the 2-rank run restores with 2 ranks and ends in the same files.
    let restarted = dir.join("restart2");
    let record = dir.join("ranks2").join("exchange.mcap");
    run(
        &scene,
        &restarted,
        &[
            "--fluid-ranks",
            "2",
            "--restart",
            record.to_str().expect("utf-8"),
            "--step",
            "2",
        ],
    );
    let after: Vec<(String, Vec<u8>)> = files(&restarted)
        .into_iter()
        .filter(|(n, _)| n.starts_with("fluid_") && n.ends_with(".csv"))
        .collect();
    assert!(!after.is_empty(), "the restarted run writes outputs");
    for (name, bytes) in &after {
        let straight = outputs
            .iter()
            .find(|(n, _)| n == name)
            .expect("same output");
        assert!(*bytes == straight.1, "{name} after a restart on 2 ranks");
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Processes whose command line holds `needle`.
fn pids_with(needle: &str) -> Vec<u32> {
    std::fs::read_dir("/proc")
        .expect("/proc")
        .filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| {
            std::fs::read(format!("/proc/{pid}/cmdline"))
                .map(|c| {
                    String::from_utf8_lossy(&c)
                        .replace('\0', " ")
                        .contains(needle)
                })
                .unwrap_or(false)
        })
        .collect()
}

fn mpi_rank(pid: u32) -> Option<u32> {
    let env = std::fs::read(format!("/proc/{pid}/environ")).ok()?;
    String::from_utf8_lossy(&env)
        .split('\0')
        .find_map(|kv| kv.strip_prefix("OMPI_COMM_WORLD_RANK="))
        .and_then(|r| r.parse().ok())
}

#[test]
fn a_killed_rank_is_named_and_no_rank_is_left() {
    killed_rank_is_named(out_dir("mpi-kill"), None);
}

/// The same kill, with a launcher that reports its exit 1 s late: the coupler finds the fluid
/// gone on the bus and stops before its supervisor sees the launcher end, and the rank must be
/// named on that path too (it was not, and `.ci/run` failed once on the race).
#[test]
fn a_killed_rank_is_named_when_the_bus_sees_it_gone_first() {
    let dir = out_dir("mpi-kill-late");
    std::fs::create_dir_all(&dir).expect("dir");
    let launcher = dir.join("late-mpirun.sh");
    std::fs::write(
        &launcher,
        "#!/bin/sh\nmpirun \"$@\"; rc=$?; sleep 1; exit $rc\n",
    )
    .expect("launcher");
    let executable = std::os::unix::fs::PermissionsExt::from_mode(0o755);
    std::fs::set_permissions(&launcher, executable).expect("chmod");
    killed_rank_is_named(dir, Some(&launcher));
}

/// Kills rank 1 of a 2-rank blast a few steps in (through `launcher` as `COSIM_MPIRUN` when
/// given) and checks the summary names the rank and no process of the run is left.
fn killed_rank_is_named(dir: PathBuf, launcher: Option<&Path>) {
    let scene = blast_scene(&dir, 1_000_000, 1e6, "times = [1e6]");
    // A million steps of checkpoints would not fit the disk (issue 38 warns of it, or refuses
    // an uncompressed record): capped; the run is killed after a few steps anyway.
    let text = std::fs::read_to_string(&scene).expect("scene");
    std::fs::write(
        &scene,
        text.replacen("[run]\n", "[run]\nrecord_max_bytes = 1000000000\n", 1),
    )
    .expect("scene");
    let out = dir.join("out");
    let start = shared_start();
    let mut cmd = coupler();
    if let Some(launcher) = launcher {
        cmd.env("COSIM_MPIRUN", launcher);
    }
    let mut child = mpi_env(&mut cmd)
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .args(["--fluid-ranks", "2"])
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .expect("coupler starts");
    let run_id = format!("mpiblast{}", child.id());
    let needle = format!("--run-id {run_id} ");
    // Wait for both ranks and a few steps.
    let deadline = Instant::now() + Duration::from_secs(60);
    let rank1 = loop {
        let ranks: Vec<u32> = pids_with(&needle)
            .into_iter()
            .filter(|&p| mpi_rank(p) == Some(1))
            .collect();
        // A few steps done (the record, zstd by default, no longer measures them: the blast's
        // checkpoints compress to little).
        let steps = std::fs::read_to_string(out.join("ledger.csv"))
            .map_or(0, |t| t.lines().count().saturating_sub(1));
        if let (Some(&pid), true) = (ranks.first(), steps >= 4) {
            break pid;
        }
        assert!(
            Instant::now() < deadline,
            "the run did not start on 2 ranks"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    drop(start);
    let (status, took, stderr) =
        kill_and_wait(&rank1.to_string(), &mut child, Duration::from_secs(20));
    eprintln!("the coupler ended {took:?} after rank 1 was killed");
    assert!(!status.success());
    let s = summary(&out);
    let status = s["status"].as_str().expect("status");
    assert!(status.contains("fluid node"), "{status}");
    assert!(
        status.contains("rank 1"),
        "the dead rank is named: {status}\n{stderr}"
    );
    // No rank, mpirun or orted of this run is left.
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let left = pids_with(&needle);
        if left.is_empty() {
            break;
        }
        assert!(Instant::now() < deadline, "processes left: {left:?}");
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = std::fs::remove_dir_all(dir);
}
