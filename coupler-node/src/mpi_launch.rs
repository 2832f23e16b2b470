//! Starting a fluid of several MPI ranks (issue 16 item 4): `mpirun -n K [--hostfile F]
//! fluid-node ...`, with the checks that make a wrong setup fail before anything starts (no
//! MPI launcher on `PATH`, a fluid-node built without the `mpi` feature), the rank a dead job
//! names, and a kill that leaves no rank behind.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::Context;
use tokio::io::AsyncBufReadExt;
use tokio::process::ChildStderr;

/// How the fluid's ranks are started.
#[derive(Clone, Debug)]
pub struct MpiLaunch {
    /// `mpirun` or `mpiexec`.
    pub program: PathBuf,
    /// Its arguments before the fluid binary.
    pub args: Vec<OsString>,
}

impl MpiLaunch {
    /// The launcher for `ranks` ranks of `fluid_bin`: `COSIM_MPIRUN`, else `mpirun` or
    /// `mpiexec` on `PATH`; errors when there is none or `fluid_bin` was built without MPI.
    /// Open MPI gets `--oversubscribe` when the ranks outnumber the cores here.
    pub fn find(fluid_bin: &Path, ranks: u32, hostfile: Option<&Path>) -> anyhow::Result<Self> {
        let program = match std::env::var_os("COSIM_MPIRUN") {
            Some(p) => PathBuf::from(p),
            None => ["mpirun", "mpiexec"]
                .iter()
                .find_map(|name| on_path(name))
                .with_context(|| {
                    format!(
                        "fluid.ranks = {ranks} needs an MPI launcher: neither mpirun nor mpiexec \
                         is on PATH (Debian: apt-get install openmpi-bin; or set COSIM_MPIRUN)"
                    )
                })?,
        };
        let features = std::process::Command::new(fluid_bin)
            .arg("--features")
            .output()
            .with_context(|| format!("asking {} for its features", fluid_bin.display()))?;
        let features = String::from_utf8_lossy(&features.stdout);
        anyhow::ensure!(
            features.lines().any(|l| l.trim() == "mpi"),
            "fluid.ranks = {ranks} needs a fluid-node built with MPI, and {} was built without \
             (cargo build --release -p fluid-node --features mpi)",
            fluid_bin.display()
        );
        let version = std::process::Command::new(&program)
            .arg("--version")
            .output()
            .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
            .unwrap_or_default();
        let open_mpi = version.contains("Open MPI") || version.contains("OpenRTE");
        if let Some(file) = hostfile {
            anyhow::ensure!(file.is_file(), "host file {} not found", file.display());
        }
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let pml_chosen = std::env::var_os("OMPI_MCA_pml").is_some();
        let args = launcher_args(ranks, hostfile, open_mpi, cores, pml_chosen);
        Ok(MpiLaunch { program, args })
    }

    /// The command that starts the ranks of `fluid_bin` (its own arguments follow).
    pub fn command(&self, fluid_bin: &Path) -> tokio::process::Command {
        let mut cmd = tokio::process::Command::new(&self.program);
        cmd.args(&self.args).arg(fluid_bin);
        cmd
    }
}

/// The launcher's arguments before the fluid binary: `-n ranks`, the host file, and for Open
/// MPI on this host alone `--oversubscribe` when the ranks outnumber its `cores`, and `--mca
/// pml ob1` unless the user chose a PML (`pml_chosen`: `OMPI_MCA_pml` is set).
///
/// NOTE: on one host Open MPI's default PML selection tries `cm` and its MTLs (ofi, psm, psm2),
/// which probe for network hardware before `ob1` is taken: `MPI_Init` and `MPI_Finalize` of two
/// ranks took 0.32 s against 0.11 s with `ob1` (Open MPI 4.1.4, the project's machine), a fixed
/// cost of every run on ranks. `ob1` with its shared-memory transport is what the ranks used
/// anyway. With a host file the interconnect is the user's to pick (UCX, `cm`).
fn launcher_args(
    ranks: u32,
    hostfile: Option<&Path>,
    open_mpi: bool,
    cores: usize,
    pml_chosen: bool,
) -> Vec<OsString> {
    let mut args: Vec<OsString> = vec!["-n".into(), ranks.to_string().into()];
    if let Some(file) = hostfile {
        args.push("--hostfile".into());
        args.push(file.as_os_str().to_owned());
    }
    if open_mpi && hostfile.is_none() {
        if ranks as usize > cores {
            tracing::info!("{ranks} fluid ranks on {cores} cores: mpirun --oversubscribe");
            args.push("--oversubscribe".into());
        }
        if !pml_chosen {
            args.extend(["--mca", "pml", "ob1"].map(OsString::from));
        }
    }
    args
}

fn on_path(name: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|dir| dir.join(name))
        .find(|p| p.is_file())
}

/// The first line of the MPI launcher's stderr that names a rank that ended the job, filled
/// in by [`watch_stderr`].
pub type RankReport = Arc<Mutex<Option<String>>>;

/// Forwards the MPI launcher's stderr to ours line by line and keeps the first line that names
/// a rank that ended the job (Open MPI: "... process rank 1 with PID ... exited on signal 9";
/// MPICH: "... rank 1 PID ... KILLED BY SIGNAL: 9").
pub fn watch_stderr(stderr: ChildStderr) -> RankReport {
    let named = RankReport::default();
    let report = named.clone();
    tokio::spawn(async move {
        let mut lines = tokio::io::BufReader::new(stderr).lines();
        while let Ok(Some(line)) = lines.next_line().await {
            eprintln!("{line}");
            let mut named = named.lock().unwrap_or_else(|p| p.into_inner());
            if named.is_none() && names_rank(&line) {
                *named = Some(line.trim().to_string());
            }
        }
    });
    report
}

/// Whether a launcher's line names a rank that died.
pub fn names_rank(line: &str) -> bool {
    let lower = line.to_lowercase();
    lower.contains("rank")
        && (lower.contains("signal")
            || lower.contains("exited")
            || lower.contains("killed")
            || lower.contains("non-zero"))
}

/// Appends the rank the launcher named to a dead fluid's exit text, waiting up to 1 s for
/// the launcher's line (it prints it as it exits).
pub async fn name_rank(text: &mut String, report: &RankReport) {
    let deadline = tokio::time::Instant::now() + Duration::from_secs(1);
    loop {
        let line = report.lock().unwrap_or_else(|p| p.into_inner()).clone();
        if let Some(line) = line {
            text.push_str(": ");
            text.push_str(&line);
            return;
        }
        if tokio::time::Instant::now() >= deadline {
            return;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

/// SIGKILL to the process group `pid` leads (the launcher and its ranks).
///
/// NOTE: through `kill(1)`, so that the coupler needs no `unsafe` call of its own.
pub fn kill_group(pid: Option<u32>) {
    if let Some(pid) = pid {
        let _ = std::process::Command::new("kill")
            .args(["-KILL", "--", &format!("-{pid}")])
            .status();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(ranks: u32, hostfile: Option<&str>, open_mpi: bool, pml_chosen: bool) -> String {
        let args = launcher_args(ranks, hostfile.map(Path::new), open_mpi, 2, pml_chosen);
        let args: Vec<String> = args.iter().map(|a| a.to_string_lossy().into()).collect();
        args.join(" ")
    }

    /// Open MPI on this host alone gets the `ob1` PML (and `--oversubscribe` past the cores);
    /// not with a host file, not when the user chose a PML, not another MPI's launcher.
    #[test]
    fn open_mpi_on_one_host_starts_with_ob1() {
        assert_eq!(args(2, None, true, false), "-n 2 --mca pml ob1");
        assert_eq!(
            args(4, None, true, false),
            "-n 4 --oversubscribe --mca pml ob1"
        );
        assert_eq!(args(4, None, true, true), "-n 4 --oversubscribe");
        assert_eq!(args(4, Some("hosts"), true, false), "-n 4 --hostfile hosts");
        assert_eq!(args(4, None, false, false), "-n 4");
    }
}
