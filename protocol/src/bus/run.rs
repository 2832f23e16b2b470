//! A run's files: its names, its iceoryx2 config, its lock, and the cleanup of what a run leaves
//! behind.

use std::fs::{File, TryLockError};
use std::os::unix::fs::MetadataExt;
use std::path::{Path as StdPath, PathBuf};
use std::time::{Duration, Instant};

use iceoryx2::config::Config;
use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;

use crate::bus::limits::{MAX_RUN_ID_LEN, OPEN_RETRY_DEADLINE, Svc};
use crate::transport::TransportError;
use crate::wire::NodeKind;

/// Removes leftovers (stale nodes, services, `/dev/shm/<prefix>*` and `/tmp/iceoryx2` files) of
/// a run id; called by the launcher at start (for a crashed earlier run with the same id, and
/// for the stale-run sweep) and after all processes ended.
///
/// Refuses, without removing anything, while a process of the run is alive (it holds the run's
/// lock), or while a node of the run is alive or in a state that cannot be read (a run of a
/// binary from before the lock). Returns what it removed: `node <name>` for each dead node,
/// then the file paths.
pub fn cleanup_run(run_id: &str) -> Result<Vec<String>, TransportError> {
    let config = run_config(run_id)?;
    let Some(lock) = RunLock::exclusive(&config, run_id)? else {
        return Err(TransportError::Other(format!(
            "run {run_id} is live (a process of the run holds its lock); not removing its files"
        )));
    };
    let mut alive = Vec::new();
    let mut removed = Vec::new();
    Node::<Svc>::list(&config, |state| {
        match state {
            NodeState::Alive(view) => alive.push(node_label(view.details())),
            NodeState::Dead(view) => {
                let label = node_label(view.details());
                if view.try_remove_stale_resources().is_ok() {
                    removed.push(format!("node {label}"));
                }
            }
            // NOTE: a node whose state cannot be read may be one still being created; its
            // run is left alone like a live one (a sweep must never break a starting run).
            NodeState::Inaccessible(id) | NodeState::Undefined(id) => {
                alive.push(format!("{id:?} (state unknown)"));
            }
        }
        CallbackProgression::Continue
    })
    .map_err(|e| other(format!("listing the nodes of run {run_id}"), e))?;
    if !alive.is_empty() {
        return Err(TransportError::Other(format!(
            "run {run_id} is live ({} node(s): {}); not removing its files",
            alive.len(),
            alive.join(", ")
        )));
    }
    let prefix = run_prefix(run_id);
    let shm_dir = StdPath::new("/dev/shm");
    let root = iceoryx2_root(&config);
    remove_prefixed(shm_dir, &prefix, 0, &mut removed)?;
    remove_prefixed(&root, &prefix, 0, &mut removed)?;
    lock.remove();
    Ok(removed)
}

/// Run ids that have a lock file (live runs, and runs whose files a cleanup has not removed).
pub fn locked_run_ids() -> Vec<String> {
    let Ok(config) = run_config("x") else {
        return Vec::new();
    };
    let Ok(entries) = std::fs::read_dir(iceoryx2_root(&config).join("cosim-runs")) else {
        return Vec::new();
    };
    entries
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            Some(name.strip_suffix(".lock")?.to_string())
        })
        .collect()
}

/// Service name of a channel: `fsi/<run-id>/<from>-to-<to>` (e.g. `fsi/r1/fluid-to-coupler`).
pub fn service_name(run_id: &str, from: NodeKind, to: NodeKind) -> String {
    format!("fsi/{run_id}/{from}-to-{to}")
}

/// The iceoryx2 config of a run: defaults (no config file is read) with the prefix
/// `cosim_<run_id>_`.
pub fn run_config(run_id: &str) -> Result<Config, TransportError> {
    validate_run_id(run_id)?;
    let mut config = Config::default();
    config.global.prefix = FileName::new(run_prefix(run_id).as_bytes())
        .map_err(|e| other(format!("prefix of run id {run_id:?}"), e))?;
    Ok(config)
}

/// Checks that a run id is 1 to [`MAX_RUN_ID_LEN`] bytes of `A-Z a-z 0-9 _ -`.
pub fn validate_run_id(run_id: &str) -> Result<(), TransportError> {
    let ok_chars = run_id
        .bytes()
        .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-');
    if run_id.is_empty() || run_id.len() > MAX_RUN_ID_LEN || !ok_chars {
        return Err(TransportError::Other(format!(
            "run id {run_id:?} must be 1 to {MAX_RUN_ID_LEN} bytes of A-Z a-z 0-9 _ - ({} bytes given)",
            run_id.len()
        )));
    }
    Ok(())
}

pub(super) fn run_prefix(run_id: &str) -> String {
    format!("cosim_{run_id}_")
}

pub(super) fn role_of(details: &Option<iceoryx2::node::NodeDetails>) -> Option<NodeKind> {
    let name = details.as_ref()?.name().to_string();
    [NodeKind::Coupler, NodeKind::Fluid, NodeKind::Solid]
        .into_iter()
        .find(|k| k.name() == name)
}

pub(super) fn node_label(details: &Option<iceoryx2::node::NodeDetails>) -> String {
    match details {
        Some(d) => format!("{} (pid {})", d.name(), d.process_id()),
        None => "unnamed".to_string(),
    }
}

/// Removes the files under `dir` whose name starts with `prefix` (in subdirectories too when
/// `dir` is the iceoryx2 root), then the directories below the root's own (`nodes/<id>/`) left
/// empty by that.
///
/// NOTE: the root's subdirectories (`nodes/`, `services/`, `cosim-runs/`) are shared by every
/// run and stay, even when empty: removing one while another run creates its node there made
/// that run fail ("creating iceoryx2 node ...: InternalError").
pub(super) fn remove_prefixed(
    dir: &StdPath,
    prefix: &str,
    depth: usize,
    removed: &mut Vec<String>,
) -> Result<(), TransportError> {
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(other(format!("reading {}", dir.display()), e)),
    };
    let recurse = dir != StdPath::new("/dev/shm");
    for entry in entries.flatten() {
        let path = entry.path();
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        if is_dir {
            if recurse && depth < 3 {
                let before = removed.len();
                remove_prefixed(&path, prefix, depth + 1, removed)?;
                if depth >= 1 && removed.len() > before {
                    // Fails, harmlessly, when the directory still holds another run's files.
                    let _ = std::fs::remove_dir(&path);
                }
            }
        } else if entry.file_name().to_string_lossy().starts_with(prefix) {
            match std::fs::remove_file(&path) {
                Ok(()) => removed.push(path.display().to_string()),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(other(format!("removing {}", path.display()), e)),
            }
        }
    }
    Ok(())
}

/// The directory of iceoryx2's files (nodes, services, listener sockets): `/tmp/iceoryx2/`.
pub(super) fn iceoryx2_root(config: &Config) -> PathBuf {
    PathBuf::from(config.global.root_path().to_string())
}

/// A run's lock file, held shared by each process of the run and exclusively by a cleanup.
pub(super) struct RunLock {
    pub(super) file: File,
    pub(super) path: PathBuf,
}

impl RunLock {
    pub(super) fn path(config: &Config, run_id: &str) -> PathBuf {
        iceoryx2_root(config)
            .join("cosim-runs")
            .join(format!("{run_id}.lock"))
    }

    pub(super) fn open(path: &StdPath) -> Result<File, TransportError> {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)
                .map_err(|e| other(format!("creating {}", dir.display()), e))?;
        }
        File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .map_err(|e| other(format!("opening the run lock {}", path.display()), e))
    }

    /// Whether the locked file is still the one at `path` (a cleanup removes the file after
    /// its work, and a lock on the removed file would guard nothing).
    pub(super) fn still_current(file: &File, path: &StdPath) -> bool {
        match (file.metadata(), std::fs::metadata(path)) {
            (Ok(held), Ok(now)) => held.ino() == now.ino() && held.dev() == now.dev(),
            _ => false,
        }
    }

    /// The lock of a process of the run; waits (until `deadline`) while a cleanup holds it.
    pub(super) fn shared(
        config: &Config,
        run_id: &str,
        deadline: Instant,
    ) -> Result<RunLock, TransportError> {
        let path = RunLock::path(config, run_id);
        loop {
            let file = RunLock::open(&path)?;
            match file.try_lock_shared() {
                Ok(()) if RunLock::still_current(&file, &path) => {
                    return Ok(RunLock { file, path });
                }
                Ok(()) | Err(TryLockError::WouldBlock) => {}
                Err(TryLockError::Error(e)) => {
                    return Err(other(format!("locking {}", path.display()), e));
                }
            }
            if Instant::now() >= deadline {
                return Err(TransportError::Other(format!(
                    "run {run_id}: its files were still being removed by another process after {OPEN_RETRY_DEADLINE:?} ({})",
                    path.display()
                )));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    /// The lock of a cleanup, or `None` while a process of the run holds it.
    pub(super) fn exclusive(
        config: &Config,
        run_id: &str,
    ) -> Result<Option<RunLock>, TransportError> {
        let path = RunLock::path(config, run_id);
        loop {
            let file = RunLock::open(&path)?;
            match file.try_lock() {
                Ok(()) if RunLock::still_current(&file, &path) => {
                    return Ok(Some(RunLock { file, path }));
                }
                // Another cleanup removed the file meanwhile: take the new one.
                Ok(()) => {}
                Err(TryLockError::WouldBlock) => return Ok(None),
                Err(TryLockError::Error(e)) => {
                    return Err(other(format!("locking {}", path.display()), e));
                }
            }
        }
    }

    /// Removes the lock file, then releases the lock (a cleanup's last act).
    pub(super) fn remove(self) {
        let _ = std::fs::remove_file(&self.path);
        drop(self.file);
    }
}

/// Whether `Bus::open` failed in a way that a concurrent creation or removal of the run's
/// iceoryx2 files explains, so that trying again can succeed.
///
/// NOTE: iceoryx2 0.10's variants for "created or removed by someone else at this moment"
/// (node creation's `InternalError`, the service builders' `SystemInFlux`,
/// `IsMarkedForDestruction`, `ServiceInCorruptedState`, `HangsInCreation`, `InternalFailure`,
/// `IsBeingCreatedByAnotherInstance`, `UnableToCreateServiceTag`); the errors reach here as text.
pub(super) fn is_transient(err: &TransportError) -> bool {
    const TRANSIENT: [&str; 8] = [
        "InternalError",
        "SystemInFlux",
        "IsMarkedForDestruction",
        "ServiceInCorruptedState",
        "HangsInCreation",
        "InternalFailure",
        "IsBeingCreatedByAnotherInstance",
        "UnableToCreateServiceTag",
    ];
    match err {
        TransportError::Other(text) => TRANSIENT.iter().any(|t| text.contains(t)),
        _ => false,
    }
}

pub(super) fn other(context: String, err: impl std::fmt::Debug) -> TransportError {
    TransportError::Other(format!("{context}: {err:?}"))
}
