//! How long the coupler takes to notice a killed node and end the run naming it: the figure the
//! "a node process that exits early ends the run within 1 s" (docs/performance.md, Liveness) rests on. The e2e test
//! only bounds it generously (a loaded 2-core machine stretches it); this measures it.
//!
//! `cargo bench -p cosim-tests --bench kill_detection` (`TRIALS=N`, default 5 per node) prints
//! each trial and the median and largest time from SIGKILL to the coupler's exit.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Starts a long doubles run, kills `node` once the record has grown, and times the coupler.
fn trial(node: &str, dir: &Path) -> Result<Duration, String> {
    std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    let text = std::fs::read_to_string(workspace().join("scenes/backbone-doubles.toml"))
        .map_err(|e| e.to_string())?
        .replace("t_end = 1.0", "t_end = 1000.0")
        .replace("every = 0.25", "every = 500.0");
    let scene = dir.join("long.toml");
    std::fs::write(&scene, text).map_err(|e| e.to_string())?;
    let out = dir.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_it-coupler-node"))
        .env("COSIM_FLUID_BIN", env!("CARGO_BIN_EXE_it-fluid-node"))
        .env("COSIM_SOLID_BIN", env!("CARGO_BIN_EXE_it-solid-node"))
        .args(["run", "--quiet", "--out"])
        .arg(&out)
        .arg(&scene)
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| e.to_string())?;
    let record = out.join("exchange.mcap");
    let deadline = Instant::now() + Duration::from_secs(60);
    while std::fs::metadata(&record).map_or(0, |m| m.len()) < 200_000 {
        if Instant::now() > deadline {
            let _ = child.kill();
            return Err("the run did not start recording".into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let run_id = format!("backbonedoub{}", child.id());
    let bin = format!("it-{node}-node");
    let pids = Command::new("pgrep")
        .args(["-f", &format!("{bin} --scene .* --run-id {run_id} ")])
        .output()
        .map_err(|e| e.to_string())?;
    let pid = String::from_utf8_lossy(&pids.stdout).trim().to_string();
    if pid.is_empty() {
        let _ = child.kill();
        return Err(format!("no {node} node found for run {run_id}"));
    }
    let killed = Instant::now();
    Command::new("kill")
        .args(["-9", &pid])
        .status()
        .map_err(|e| e.to_string())?;
    loop {
        if child.try_wait().map_err(|e| e.to_string())?.is_some() {
            return Ok(killed.elapsed());
        }
        if killed.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            return Err("the coupler did not end within 30 s".into());
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn main() {
    let trials: usize = std::env::var("TRIALS")
        .ok()
        .and_then(|t| t.parse().ok())
        .unwrap_or(5);
    for node in ["fluid", "solid"] {
        let mut times = Vec::new();
        for k in 0..trials {
            let dir = std::env::temp_dir().join(format!(
                "cosim-kill-bench-{node}-{k}-{}",
                std::process::id()
            ));
            match trial(node, &dir) {
                Ok(t) => {
                    println!("{node} trial {k}: {:.3} s", t.as_secs_f64());
                    times.push(t);
                }
                Err(e) => println!("{node} trial {k}: failed: {e}"),
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
        times.sort();
        if let (Some(median), Some(max)) = (times.get(times.len() / 2), times.last()) {
            println!(
                "{node}: median {:.3} s, largest {:.3} s over {} trials (docs/performance.md: within 1 s)",
                median.as_secs_f64(),
                max.as_secs_f64(),
                times.len()
            );
        }
    }
}
