//! What `run`, `check` and `replay` look up and check before any process starts: the scene
//! with the `--fluid`/`--solid`/`--fluid-ranks` choices applied, the memory the machine has,
//! the records of `replay:FILE` nodes, and where the node binaries are.
//!
//! Below [`crate::launch`], [`crate::check`] and [`crate::replay`], which all use it.

use std::path::{Path, PathBuf};

use anyhow::Context;
use protocol::scene::{RecordCompression, Scene};
use protocol::wire::NodeKind;

/// Reads and validates a scene, applying implementation overrides; returns it with its path.
pub fn load_scene(path: &Path, fluid: Option<&str>, solid: Option<&str>) -> anyhow::Result<Scene> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading scene {}", path.display()))?;
    let name = path.display().to_string();
    let mut scene = Scene::from_toml_str(&text, &name)?;
    if let Some(choice) = fluid {
        let f = scene.fluid.as_mut().with_context(|| {
            format!("{name}: --fluid {choice} but the scene has no [fluid] section")
        })?;
        f.node = choice.to_string();
    }
    if let Some(choice) = solid {
        let s = scene.solid.as_mut().with_context(|| {
            format!("{name}: --solid {choice} but the scene has no [solid] section")
        })?;
        s.node = choice.to_string();
    }
    if fluid.is_some() || solid.is_some() {
        // Validate again with the choices applied (a real node needs more keys than a double).
        scene = Scene::from_toml_str(&scene.to_toml(), &name)?;
    }
    Ok(scene)
}

/// `scene` with `fluid.ranks = ranks`, validated again.
pub fn with_fluid_ranks(mut scene: Scene, ranks: u32, path: &Path) -> anyhow::Result<Scene> {
    let name = path.display().to_string();
    let f = scene
        .fluid
        .as_mut()
        .with_context(|| format!("{name}: --fluid-ranks {ranks} but the scene has no [fluid]"))?;
    f.ranks = ranks;
    Ok(Scene::from_toml_str(&scene.to_toml(), &name)?)
}

/// Memory the machine can give a run, in bytes: `MemAvailable` of `/proc/meminfo` (`MemTotal`
/// on kernels without it).
pub fn available_memory() -> anyhow::Result<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").context("reading /proc/meminfo")?;
    let field = |name: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|rest| {
                rest.trim()
                    .trim_end_matches("kB")
                    .trim()
                    .parse::<u64>()
                    .ok()
            })
            .map(|kib| kib * 1024)
    };
    field("MemAvailable:")
        .or_else(|| field("MemTotal:"))
        .context("/proc/meminfo has neither MemAvailable nor MemTotal")
}

/// Checks, before any process starts, that every `replay:FILE` node of `scene` names a record
/// that reads and holds messages of that node (the node reads `FILE` from the same directory).
pub fn check_replay_doubles(scene: &Scene) -> anyhow::Result<()> {
    let nodes = [
        (
            NodeKind::Fluid,
            scene.fluid.as_ref().map(|f| f.node.as_str()),
        ),
        (
            NodeKind::Solid,
            scene.solid.as_ref().map(|s| s.node.as_str()),
        ),
    ];
    for (node, choice) in nodes {
        let Some(file) = choice.and_then(|c| c.strip_prefix("replay:")) else {
            continue;
        };
        let key = format!("{node}.node = \"replay:{file}\"");
        let bytes =
            std::fs::read(file).with_context(|| format!("{key}: reading the record {file}"))?;
        protocol::replay::Script::from_mcap(&bytes, node)
            .with_context(|| format!("{key}: the record {file} cannot be replayed"))?;
    }
    Ok(())
}

/// Refuses `fluid.ranks` > 1 when the fluid binary that would run was built without MPI
/// (`fluid-node --features` does not list `mpi`), naming the key and the binary.
pub fn check_fluid_ranks(scene: &Scene, fluid_bin: Option<&Path>) -> anyhow::Result<()> {
    let Some(fluid) = scene
        .fluid
        .as_ref()
        .filter(|f| f.ranks > 1 && f.node == "real")
    else {
        return Ok(());
    };
    let bin = node_binary(NodeKind::Fluid, fluid_bin)?;
    let features = std::process::Command::new(&bin)
        .arg("--features")
        .output()
        .with_context(|| format!("asking {} for its features", bin.display()))?;
    let features = String::from_utf8_lossy(&features.stdout);
    anyhow::ensure!(
        features.lines().any(|l| l.trim() == "mpi"),
        "key `fluid.ranks`: {} ranks need a fluid-node built with MPI, and {} was built without \
         (cargo build --release -p fluid-node --features mpi)",
        fluid.ranks,
        bin.display()
    );
    Ok(())
}

/// Bytes free for an unprivileged user on the file system that holds `dir` (`statvfs`).
pub fn free_space(dir: &Path) -> std::io::Result<u64> {
    use std::os::unix::ffi::OsStrExt;
    let path = std::ffi::CString::new(dir.as_os_str().as_bytes())
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))?;
    let mut stat = std::mem::MaybeUninit::<libc::statvfs>::zeroed();
    // SAFETY: `path` is a NUL-terminated string that outlives the call, and `stat` points to
    // writable memory of the size `statvfs` fills.
    let rc = unsafe { libc::statvfs(path.as_ptr(), stat.as_mut_ptr()) };
    if rc != 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: `statvfs` returned 0, so it filled the struct.
    let stat = unsafe { stat.assume_init() };
    Ok(stat.f_bavail.saturating_mul(stat.f_frsize))
}

/// Compares the record's estimated size ([`Scene::record_estimate`]) with the free space of
/// `out`'s file system: refuses a run whose steps are known (`run.max_steps`, or `run.t_end`
/// over `run.dt_max`) and whose uncompressed record would not fit, unless
/// `run.record_max_bytes` caps it below the free space; warns, with the figures, when the free
/// space holds fewer than [`WARN_STEPS`] steps of an open-ended run, or when a compressed
/// record's estimate (uncompressed, an upper bound: `clamped-beam-2d`'s record is 12 times
/// smaller, its messages 3.4 times below the estimate and zstd's chunks 3.7 times below the
/// messages; a nearly uniform blast's far more) passes it. A disk that fills anyway stops the
/// run cleanly, the record cut back to its last complete step.
pub fn check_record_space(scene: &Scene, out: &Path) -> anyhow::Result<()> {
    let est = scene.record_estimate();
    if est.per_step == 0 {
        return Ok(());
    }
    let free = free_space(out)
        .with_context(|| format!("measuring the free space of {}", out.display()))?;
    let gb = |b: u64| {
        if b >= 1_000_000_000 {
            format!("{:.2} GB", b as f64 / 1e9)
        } else {
            format!("{:.1} MB", b as f64 / 1e6)
        }
    };
    if let Some(cap) = scene.run.record_max_bytes
        && cap <= free
    {
        return Ok(());
    }
    if let Some(steps) = est.steps {
        let total = steps.saturating_mul(est.per_step);
        if total > free && scene.run.record_compression != RecordCompression::None {
            tracing::warn!(
                "the record is estimated at up to {} uncompressed ({steps} steps x {} B: {}), more than the {} free on the file system of {}; compressed it may fit: set run.record_max_bytes to stop the run cleanly before the disk is full",
                gb(total),
                est.per_step,
                est.how,
                gb(free),
                out.display()
            );
            return Ok(());
        }
        anyhow::ensure!(
            total <= free,
            "the record is estimated at {} ({steps} steps x {} B: {}), more than the {} free on the file system of {}; lower run.max_steps, cap it with run.record_max_bytes, or record less (run.record = \"diagnostics\")",
            gb(total),
            est.per_step,
            est.how,
            gb(free),
            out.display()
        );
        return Ok(());
    }
    let fit = free / est.per_step;
    if fit < WARN_STEPS {
        tracing::warn!(
            "the record takes an estimated {} B per step ({}); the {} free on the file system of {} hold about {fit} steps: set run.record_max_bytes to stop the run cleanly before the disk is full",
            est.per_step,
            est.how,
            gb(free),
            out.display()
        );
    }
    Ok(())
}

/// An open-ended run whose record fits fewer steps than this in the free space is warned of:
/// more than the longest scene shipped takes (`thin-shell`, 21,005 steps with one solid step a
/// coupling step), so that a run of the shipped scenes is warned of only where such a run could
/// fill the disk. (It was 100,000: the README's main command, 394 steps of about 1 MB each at
/// the estimate, was warned of on any disk with less than 98 GB free.)
pub const WARN_STEPS: u64 = 25_000;

/// The binary of a node: explicit path, `COSIM_<NODE>_BIN`, or beside this executable.
pub fn node_binary(node: NodeKind, explicit: Option<&Path>) -> anyhow::Result<PathBuf> {
    if let Some(p) = explicit {
        return Ok(p.to_path_buf());
    }
    let var = format!("COSIM_{}_BIN", node.name().to_uppercase());
    if let Ok(p) = std::env::var(&var) {
        return Ok(PathBuf::from(p));
    }
    let exe = std::env::current_exe().context("locating this executable")?;
    let dir = exe.parent().context("this executable has no directory")?;
    let name = format!("{}-node{}", node.name(), std::env::consts::EXE_SUFFIX);
    let path = dir.join(&name);
    anyhow::ensure!(
        path.exists(),
        "{name} not found beside {} (build the workspace, or set {var})",
        exe.display()
    );
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of 10^12 steps of checkpoints: refused when its record is stored uncompressed
    /// (the estimate is its size), let through with a warning when compressed (the estimate
    /// is then an upper bound), and let through at any compression when capped.
    #[test]
    fn a_record_the_disk_cannot_hold_is_refused_only_when_its_size_is_known() {
        let scene = |extra: &str| {
            let text = std::fs::read_to_string(
                Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/sod.toml"),
            )
            .expect("scenes/sod.toml")
            .replacen(
                "[run]\n",
                &format!("[run]\nmax_steps = 1000000000000\nrecord = \"all\"\n{extra}"),
                1,
            );
            Scene::from_toml_str(&text, "sod.toml").expect("scene")
        };
        let out = std::env::temp_dir();
        let refused = check_record_space(&scene("record_compression = \"none\"\n"), &out)
            .expect_err("refused")
            .to_string();
        assert!(
            refused.contains("run.max_steps") && refused.contains("run.record_max_bytes"),
            "{refused}"
        );
        check_record_space(&scene("record_compression = \"zstd\"\n"), &out).expect("warned");
        check_record_space(&scene(""), &out).expect("zstd by default: warned");
        check_record_space(
            &scene("record_compression = \"none\"\nrecord_max_bytes = 1000000\n"),
            &out,
        )
        .expect("capped");
    }
}
