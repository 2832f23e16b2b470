//! The iceoryx2 transport: one publish–subscribe service of `[u8]` frames per direction and peer,
//! each paired with an event service of the same name for blocking waits (DESIGN §4).
//!
//! Layout of a run `r1` between the coupler and the fluid node:
//!
//! ```text
//! fsi/r1/fluid-to-coupler   pub/sub [u8] (fluid publishes, coupler subscribes) + event service
//! fsi/r1/coupler-to-fluid   pub/sub [u8] (coupler publishes, fluid subscribes) + event service
//! ```
//!
//! - **Isolation.** Every run gets its own iceoryx2 domain: the config prefix `cosim_<run-id>_`,
//!   so shm segments are `/dev/shm/cosim_<run-id>_*` and node listings only see the run's nodes.
//! - **Waiting.** A receive polls the subscribers, spins for a few microseconds, then blocks on a
//!   `WaitSet` with the listeners attached (the publisher notifies after every send). Every wait
//!   ends at the caller's deadline; none busy-loops.
//! - **Liveness.** During any wait the peers are checked at least every
//!   [`LIVENESS_PERIOD`]: dead nodes of the run's domain (`Node::list`) are cleaned up and
//!   reported as [`TransportError::PeerDead`](crate::transport::TransportError::PeerDead); so is a peer that was seen and then left. A peer
//!   that has not shown up yet is not dead (startup). Cleanups fire the `notifier_dead_event`,
//!   which wakes every waiter at once. A receive from one peer reports only that peer's death
//!   (so a coupler can still collect the last words of one node after the other left); a
//!   receive from any peer, and [`Bus::check_peers`], report any. Frames a peer sent before it
//!   died are delivered first, provided this end had received from it before (iceoryx2 keeps a
//!   departed publisher's queued samples only for subscribers already connected to it).
//! - **Sharing.** A `Bus` is `Send` (iceoryx2's thread-safe service flavour), not meant to be
//!   shared: one thread drives it.
//! - **Lossless.** Overflow is disabled; a full subscriber queue back-pressures the sender in
//!   slices of [`LIVENESS_PERIOD`], between which the peers and signals are checked, until the
//!   send timeout ([`Bus::set_send_timeout`]). A send never blocks forever. A frame sent before
//!   the peer's subscriber exists waits for it (same timeout), so nothing is lost at startup.
//! - **Signals.** SIGINT/SIGTERM during a wait end it with [`TransportError::Interrupted`](crate::transport::TransportError::Interrupted).
//! - **Files.** [`cleanup_run`] removes what a run leaves behind (dead nodes, the
//!   `global_mgmt` segment that iceoryx2 keeps by design, listener sockets of crashed processes).
//! - **Ownership.** Every process with a `Bus` of a run holds that run's lock file
//!   (`<iceoryx2 root>/cosim-runs/<run-id>.lock`) shared, from before its first iceoryx2 file
//!   exists until after its last port is gone; [`cleanup_run`] removes files only while it holds
//!   the lock exclusively. The kernel drops a dead process's lock, so "locked" means "a process
//!   of the run is alive", whatever iceoryx2's node list says while a node is being created: a
//!   sweep never touches a live run, and a run never starts inside a sweep of its files.

mod end;
mod frames;
mod limits;
mod run;
mod wait;

pub use end::Bus;
pub use limits::{
    DEFAULT_SEND_TIMEOUT, LIVENESS_PERIOD, MAX_FRAME_LEN, MAX_RUN_ID_LEN, OPEN_RETRY_DEADLINE,
    SAMPLES_PER_SEGMENT, SUBSCRIBER_BUFFER,
};
pub use run::{cleanup_run, locked_run_ids, run_config, service_name, validate_run_id};

/// Asks the kernel to end this process with SIGKILL when the thread that started it ends (Linux
/// `PR_SET_PDEATHSIG`; the coupler sets it in its children too), so that a node never outlives a
/// coupler killed by anything, busy or waiting. Returns an error when the parent is already gone.
pub fn die_with_parent() -> std::io::Result<()> {
    let parent = std::os::unix::process::parent_id();
    // SAFETY: prctl with PR_SET_PDEATHSIG reads only its integer arguments.
    let rc = unsafe { libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL, 0, 0, 0) };
    if rc != 0 {
        return Err(std::io::Error::last_os_error());
    }
    // The parent died before the prctl: no signal will come.
    if std::os::unix::process::parent_id() != parent {
        return Err(std::io::Error::other(
            "the process that started this node is gone",
        ));
    }
    Ok(())
}
