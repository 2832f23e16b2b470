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
//!   reported as [`TransportError::PeerDead`]; so is a peer that was seen and then left. A peer
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
//! - **Signals.** SIGINT/SIGTERM during a wait end it with [`TransportError::Interrupted`].
//! - **Files.** [`cleanup_run`] removes what a run leaves behind (dead nodes, the
//!   `global_mgmt` segment that iceoryx2 keeps by design, listener sockets of crashed processes).
//! - **Ownership.** Every process with a `Bus` of a run holds that run's lock file
//!   (`<iceoryx2 root>/cosim-runs/<run-id>.lock`) shared, from before its first iceoryx2 file
//!   exists until after its last port is gone; [`cleanup_run`] removes files only while it holds
//!   the lock exclusively. The kernel drops a dead process's lock, so "locked" means "a process
//!   of the run is alive", whatever iceoryx2's node list says while a node is being created: a
//!   sweep never touches a live run, and a run never starts inside a sweep of its files.

use std::collections::VecDeque;
use std::fs::{File, TryLockError};
use std::os::unix::fs::MetadataExt;
use std::path::{Path as StdPath, PathBuf};
use std::sync::Once;
use std::time::{Duration, Instant};

use iceoryx2::config::Config;
use iceoryx2::node::NodeView;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::{BackpressureAction, BackpressureInfo, SendError};
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use iceoryx2::waitset::WaitSetRunResult;

use crate::transport::{Transport, TransportError};
use crate::wire::NodeKind;

/// Longest accepted run id, in bytes (shm and socket names must stay under the OS limits).
pub const MAX_RUN_ID_LEN: usize = 32;

/// Largest frame the bus carries, in bytes (128 MiB).
///
/// NOTE: iceoryx2 zeroes every data segment it creates and a segment holds
/// [`SAMPLES_PER_SEGMENT`] slots of the largest frame so far, so this caps the shared memory one
/// publisher can take at about 1.25 GiB.
pub const MAX_FRAME_LEN: usize = 128 << 20;

/// Longest time between two liveness checks of the peers during a wait.
pub const LIVENESS_PERIOD: Duration = Duration::from_millis(200);

/// Default send timeout: how long a send waits for the peer to appear or to make room.
pub const DEFAULT_SEND_TIMEOUT: Duration = Duration::from_secs(30);

/// Queue depth per subscriber, in frames.
///
/// NOTE: the protocol's worst burst is about three frames to one node before it reads (step
/// plan, decision, checkpoint request); eight leaves room, and more only back-pressures.
pub const SUBSCRIBER_BUFFER: usize = 8;

/// Slots in a publisher's data segment: queue + one borrowed by the subscriber + one loaned.
pub const SAMPLES_PER_SEGMENT: usize = SUBSCRIBER_BUFFER + 2;

/// Initial slot size of a publisher's data segment; it grows by powers of two.
const INITIAL_SLICE_LEN: usize = 64 << 10;

/// How long [`Bus::open`] retries the transient failures of a run whose files are being created
/// or removed by another process at the same moment.
pub const OPEN_RETRY_DEADLINE: Duration = Duration::from_secs(10);

/// How long a receive spins on the subscribers before it blocks.
const SPIN: Duration = Duration::from_micros(20);

/// How long a receive then keeps looking, yielding the core between looks, before it blocks.
///
/// NOTE: a frame that finds its receiver asleep costs the sender a wake-up of the receiver's
/// core, which on the project's virtual machine was most of the coupler's time in a coupled
/// step (the replies of the fixed point come within a millisecond). Looking for 0.5 ms first,
/// yielding to whatever else is runnable, took the coupled 2-D beam from 1.36 to 1.25 times
/// the fluid-only run (medians of 40 and 35 pairs); 2 ms gave 1.24.
const YIELD_SPIN: Duration = Duration::from_micros(500);

/// Event ids on the event service paired with each data service.
const EV_SAMPLE: EventId = EventId::new(1);
const EV_NOTIFIER_CREATED: EventId = EventId::new(2);
const EV_NOTIFIER_DROPPED: EventId = EventId::new(3);
const EV_NOTIFIER_DEAD: EventId = EventId::new(4);

/// Ports are `Send + Sync`, so a `Bus` may move between threads.
type Svc = ipc_threadsafe::Service;

/// A data service carrying frames.
type FrameService = PubSubFactory<Svc, [u8], ()>;

/// One process's end of the bus.
pub struct Bus {
    me: NodeKind,
    run_id: String,
    links: Vec<Link>,
    /// Frames received but not yet asked for, in arrival order.
    pending: VecDeque<(NodeKind, Vec<u8>)>,
    last_check: Instant,
    send_timeout: Duration,
    /// Dropped after every port.
    node: Node<Svc>,
    /// Declared last: released after the node, so a sweep never sees the run unowned while its
    /// files still change.
    _lock: RunLock,
}

/// A run's lock file, held shared by each process of the run and exclusively by a cleanup.
struct RunLock {
    file: File,
    path: PathBuf,
}

/// The two directions between this end and one peer.
struct Link {
    peer: NodeKind,
    out_service: FrameService,
    publisher: Publisher<Svc, [u8], ()>,
    notifier: Notifier<Svc>,
    in_service: FrameService,
    subscriber: Subscriber<Svc, [u8], ()>,
    listener: Listener<Svc>,
    /// The peer's node has been seen alive in the run's node list.
    seen_node: bool,
    /// The peer's publisher towards us has been seen.
    seen_publisher: bool,
    /// The peer is known to be gone; sticky.
    dead: bool,
}

impl Bus {
    /// Opens this process's end. `run_id` isolates the run (iceoryx2 config prefix
    /// `cosim_<run_id>_`; at most [`MAX_RUN_ID_LEN`] bytes of `A-Z a-z 0-9 _ -`), `me` is this
    /// role, `peers` the roles it talks to (coupler: `[Fluid, Solid]` or a subset; a node:
    /// `[Coupler]`).
    ///
    /// The run's lock is taken shared first (waiting out a cleanup of the run's files that is
    /// under way); failures that a concurrent creation or removal of the run's iceoryx2 files
    /// can cause are retried until [`OPEN_RETRY_DEADLINE`].
    pub fn open(run_id: &str, me: NodeKind, peers: &[NodeKind]) -> Result<Bus, TransportError> {
        static LOG_LEVEL: Once = Once::new();
        LOG_LEVEL.call_once(|| set_log_level_from_env_or(LogLevel::Warn));
        let config = run_config(run_id)?;
        let deadline = Instant::now() + OPEN_RETRY_DEADLINE;
        let mut pause = Duration::from_millis(5);
        loop {
            let lock = RunLock::shared(&config, run_id, deadline)?;
            match Bus::open_locked(run_id, me, peers, &config, lock) {
                Err(err) if is_transient(&err) && Instant::now() < deadline => {
                    // NOTE: a pause that grows and differs per process, so that runs started
                    // together do not retry in lockstep.
                    let jitter = Duration::from_micros(u64::from(std::process::id() % 997));
                    std::thread::sleep(pause + jitter);
                    pause = (pause * 2).min(Duration::from_millis(200));
                }
                other => return other,
            }
        }
    }

    fn open_locked(
        run_id: &str,
        me: NodeKind,
        peers: &[NodeKind],
        config: &Config,
        lock: RunLock,
    ) -> Result<Bus, TransportError> {
        for (i, peer) in peers.iter().enumerate() {
            if *peer == me || peers[..i].contains(peer) {
                return Err(TransportError::Other(format!(
                    "bus of {me}: peer {peer} listed twice or as itself"
                )));
            }
        }
        let node_name: NodeName = me
            .name()
            .try_into()
            .map_err(|e| other(format!("node name {me}"), e))?;
        // NOTE: node creation also removes the dead nodes of the domain, so a dead node named
        // after a peer found later died after this point.
        let node = NodeBuilder::new()
            .name(&node_name)
            .config(config)
            .create::<Svc>()
            .map_err(|e| other(format!("creating iceoryx2 node {me} of run {run_id}"), e))?;
        // Installs iceoryx2's SIGINT/SIGTERM handlers now, not at the first wait (pitfall 7).
        if node.wait(Duration::ZERO).is_err() {
            return Err(TransportError::Interrupted);
        }
        // Incoming ends first: a peer that sees our notifier appear can send at once.
        let mut incoming = Vec::new();
        for &peer in peers {
            let name = service_name(run_id, peer, me);
            let (in_service, event) = open_channel(&node, &name)?;
            let subscriber = in_service
                .subscriber_builder()
                .buffer_size(SUBSCRIBER_BUFFER)
                .create()
                .map_err(|e| other(format!("subscriber on {name}"), e))?;
            let listener = event
                .listener_builder()
                .create()
                .map_err(|e| other(format!("listener on {name}"), e))?;
            incoming.push((in_service, subscriber, listener));
        }
        let mut links = Vec::new();
        for (&peer, (in_service, subscriber, listener)) in peers.iter().zip(incoming) {
            let name = service_name(run_id, me, peer);
            let (out_service, event) = open_channel(&node, &name)?;
            let publisher = out_service
                .publisher_builder()
                .max_loaned_samples(1)
                .initial_max_slice_len(INITIAL_SLICE_LEN)
                .allocation_strategy(AllocationStrategy::PowerOfTwo)
                .backpressure_strategy(BackpressureStrategy::RetryUntilDelivered)
                // NOTE: give up after one liveness period; `send` checks peers and signals and
                // tries again until its own deadline (pitfall 4: never block forever).
                .set_backpressure_handler(|info: &BackpressureInfo| {
                    if info.elapsed_time >= LIVENESS_PERIOD {
                        BackpressureAction::DiscardDataAndFail
                    } else {
                        BackpressureAction::Retry
                    }
                })
                .create()
                .map_err(|e| other(format!("publisher on {name}"), e))?;
            let notifier = event
                .notifier_builder()
                .create()
                .map_err(|e| other(format!("notifier on {name}"), e))?;
            links.push(Link {
                peer,
                out_service,
                publisher,
                notifier,
                in_service,
                subscriber,
                listener,
                seen_node: false,
                seen_publisher: false,
                dead: false,
            });
        }
        let mut bus = Bus {
            me,
            run_id: run_id.to_string(),
            links,
            pending: VecDeque::new(),
            last_check: Instant::now(),
            send_timeout: DEFAULT_SEND_TIMEOUT,
            node,
            _lock: lock,
        };
        bus.refresh_liveness()?;
        Ok(bus)
    }

    /// Checks every peer's liveness now (`PeerDead` if a peer node is dead, or gone after having
    /// been seen).
    pub fn check_peers(&mut self) -> Result<(), TransportError> {
        self.refresh_liveness()?;
        match self.links.iter().find(|l| l.dead) {
            Some(link) => Err(TransportError::PeerDead(link.peer)),
            None => Ok(()),
        }
    }

    /// Sets how long a send waits for the peer to appear or to make room (default
    /// [`DEFAULT_SEND_TIMEOUT`]).
    pub fn set_send_timeout(&mut self, timeout: Duration) {
        self.send_timeout = timeout;
    }

    /// The run id this end was opened with.
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    fn link_index(&self, peer: NodeKind) -> Result<usize, TransportError> {
        self.links
            .iter()
            .position(|l| l.peer == peer)
            .ok_or_else(|| TransportError::Other(format!("{} has no link to {peer}", self.me)))
    }

    /// Moves every frame waiting in the subscribers into `pending`.
    fn drain(&mut self) -> Result<bool, TransportError> {
        let mut any = false;
        for link in &mut self.links {
            loop {
                let sample = link
                    .subscriber
                    .receive()
                    .map_err(|e| other(format!("receiving from {}", link.peer), e))?;
                let Some(sample) = sample else { break };
                self.pending
                    .push_back((link.peer, sample.payload().to_vec()));
                link.seen_publisher = true;
                any = true;
            }
        }
        Ok(any)
    }

    fn take_pending(&mut self, from: Option<NodeKind>) -> Option<(NodeKind, Vec<u8>)> {
        let pos = self
            .pending
            .iter()
            .position(|(p, _)| from.is_none_or(|f| f == *p))?;
        self.pending.remove(pos)
    }

    /// Updates `seen` and `dead` of every link from the node list of the run's domain.
    fn refresh_liveness(&mut self) -> Result<(), TransportError> {
        self.last_check = Instant::now();
        // Frames a peer sent before it died are still readable: keep them.
        self.drain()?;
        let mut alive = [false; 3];
        let mut dead = [false; 3];
        let mut dead_nodes = Vec::new();
        let config = self.node.config().clone();
        Node::<Svc>::list(&config, |state| {
            match state {
                NodeState::Alive(view) => {
                    if let Some(kind) = role_of(view.details()) {
                        alive[kind.code() as usize] = true;
                    }
                }
                NodeState::Dead(view) => {
                    if let Some(kind) = role_of(view.details()) {
                        dead[kind.code() as usize] = true;
                    }
                    dead_nodes.push(view);
                }
                NodeState::Inaccessible(_) | NodeState::Undefined(_) => {}
            }
            CallbackProgression::Continue
        })
        .map_err(|e| other("listing the nodes of the run".to_string(), e))?;
        // NOTE: removing a dead node's ports fires `notifier_dead_event` on every listener of
        // its services, which wakes the other waiters of the run at once.
        for view in dead_nodes {
            let _ = view.try_remove_stale_resources();
        }
        for link in &mut self.links {
            let code = link.peer.code() as usize;
            let publishers = link.in_service.dynamic_config().number_of_publishers();
            link.seen_node |= alive[code];
            link.seen_publisher |= publishers > 0;
            // A crashed publisher still counts until its node is cleaned up (pitfall 5), so
            // `publishers == 0` after one was seen means the peer closed its end.
            if dead[code]
                || (link.seen_node && !alive[code])
                || (link.seen_publisher && publishers == 0)
            {
                link.dead = true;
            }
        }
        Ok(())
    }

    /// Returns `Interrupted` if SIGINT/SIGTERM arrived since the last check.
    fn check_signal(&self) -> Result<(), TransportError> {
        self.node
            .wait(Duration::ZERO)
            .map_err(|_| TransportError::Interrupted)
    }

    /// Blocks until a listener fires or `timeout` passes; consumes the notifications. Returns
    /// whether a liveness check is due now (a peer's notifier was dropped or died).
    ///
    /// Waiting for one `peer`, only its listener is watched: the other peers' frames stay in
    /// their queues until a later call drains them, and their deaths reach the coupler through
    /// its supervisor. A wait set built per wait cost the coupler about 90 µs a wait.
    fn block(&mut self, peer: Option<NodeKind>, timeout: Duration) -> Result<bool, TransportError> {
        let one = peer
            .and_then(|p| self.links.iter().position(|l| l.peer == p))
            .or_else(|| (self.links.len() == 1).then_some(0));
        if let Some(idx) = one {
            return block_on_one(&mut self.links[idx], timeout, &self.node);
        }
        let waitset = WaitSetBuilder::new()
            .create::<Svc>()
            .map_err(|e| other("creating a wait set".to_string(), e))?;
        let mut guards = Vec::with_capacity(self.links.len());
        for link in &self.links {
            guards.push(
                waitset
                    .attach_notification(&link.listener)
                    .map_err(|e| other(format!("attaching the listener of {}", link.peer), e))?,
            );
        }
        let mut check_now = false;
        let mut seen = [false; 3];
        let mut failure = None;
        let result = waitset
            .wait_and_process_once_with_timeout(
                |_id| {
                    // Drain every listener: an undrained one keeps the wait set awake (pitfall 3).
                    for link in &self.links {
                        let drained = link.listener.try_wait(|event| {
                            if event.id == EV_NOTIFIER_DROPPED || event.id == EV_NOTIFIER_DEAD {
                                check_now = true;
                            } else if event.id == EV_NOTIFIER_CREATED || event.id == EV_SAMPLE {
                                seen[link.peer.code() as usize] = true;
                            }
                        });
                        if let Err(e) = drained {
                            failure = Some(other(format!("listener of {}", link.peer), e));
                        }
                    }
                    CallbackProgression::Stop
                },
                timeout,
            )
            .map_err(|e| other("waiting on the wait set".to_string(), e))?;
        drop(guards);
        if let Some(err) = failure {
            return Err(err);
        }
        for link in &mut self.links {
            link.seen_publisher |= seen[link.peer.code() as usize];
        }
        match result {
            WaitSetRunResult::TerminationRequest => Err(TransportError::Interrupted),
            // NOTE: a signal during the wait shows as `Interrupt` whatever it was (pitfall 7);
            // only SIGINT/SIGTERM set iceoryx2's flag, other signals (SIGCHLD ...) do not.
            WaitSetRunResult::Interrupt => {
                self.check_signal()?;
                Ok(check_now)
            }
            WaitSetRunResult::StopRequest | WaitSetRunResult::AllEventsHandled => Ok(check_now),
        }
    }

    /// One waiting round shared by send and receive: signals, liveness, deadline, then a block
    /// of at most `cap`.
    fn wait_round(
        &mut self,
        peer: Option<NodeKind>,
        deadline: Instant,
        waited: Duration,
        cap: Duration,
    ) -> Result<(), TransportError> {
        self.check_signal()?;
        if self.last_check.elapsed() >= LIVENESS_PERIOD {
            self.refresh_liveness()?;
        }
        self.dead_peer(peer)?;
        let now = Instant::now();
        if now >= deadline {
            return Err(TransportError::Timeout { peer, waited });
        }
        let until_check = LIVENESS_PERIOD.saturating_sub(self.last_check.elapsed());
        let slice = (deadline - now).min(until_check).min(cap);
        if self.block(peer, slice)? {
            self.refresh_liveness()?;
        }
        Ok(())
    }

    /// `PeerDead` if the peer waited for (any peer for `None`) is dead and has nothing queued.
    fn dead_peer(&mut self, peer: Option<NodeKind>) -> Result<(), TransportError> {
        let Some(dead) = self
            .links
            .iter()
            .find(|l| l.dead && peer.is_none_or(|p| p == l.peer))
            .map(|l| l.peer)
        else {
            return Ok(());
        };
        // Last words that arrived while the liveness check ran come first.
        self.drain()?;
        if self.pending.iter().any(|(p, _)| *p == dead) {
            return Ok(());
        }
        Err(TransportError::PeerDead(dead))
    }
}

impl Transport for Bus {
    fn me(&self) -> NodeKind {
        self.me
    }

    fn send(&mut self, to: NodeKind, frame: &[u8]) -> Result<(), TransportError> {
        self.publish(to, frame, true)
    }

    fn send_more(&mut self, to: NodeKind, frame: &[u8]) -> Result<(), TransportError> {
        // NOTE: each notification is a datagram and a wake-up of the receiver (about 0.15 ms of
        // the sender's time on the project's machine); the frame that follows brings both.
        self.publish(to, frame, false)
    }

    fn recv(
        &mut self,
        from: Option<NodeKind>,
        timeout: Duration,
    ) -> Result<(NodeKind, Vec<u8>), TransportError> {
        if let Some(idx) = from.map(|f| self.link_index(f)).transpose()? {
            debug_assert_eq!(Some(self.links[idx].peer), from);
        }
        let started = Instant::now();
        let deadline = started + timeout;
        let mut spun = false;
        loop {
            if let Some(found) = self.take_pending(from) {
                return Ok(found);
            }
            if self.drain()? {
                continue;
            }
            if !spun {
                spun = true;
                let start = Instant::now();
                let spin_end = start + SPIN;
                let yield_end = start + YIELD_SPIN;
                loop {
                    let now = Instant::now();
                    if now >= yield_end || now >= deadline {
                        break;
                    }
                    if now < spin_end {
                        std::hint::spin_loop();
                    } else {
                        std::thread::yield_now();
                    }
                    if self.drain()? {
                        break;
                    }
                }
                continue;
            }
            self.wait_round(from, deadline, timeout, Duration::MAX)?;
        }
    }
}

impl Bus {
    /// [`Transport::send`], with the receiver's notification only if `notify`.
    fn publish(&mut self, to: NodeKind, frame: &[u8], notify: bool) -> Result<(), TransportError> {
        let idx = self.link_index(to)?;
        if frame.len() > MAX_FRAME_LEN {
            return Err(TransportError::Other(format!(
                "frame of {} bytes to {to} exceeds the bus limit of {MAX_FRAME_LEN} bytes",
                frame.len()
            )));
        }
        let started = Instant::now();
        let deadline = started + self.send_timeout;
        loop {
            if self.links[idx].dead {
                return Err(TransportError::PeerDead(to));
            }
            let link = &self.links[idx];
            if link.out_service.dynamic_config().number_of_subscribers() > 0 {
                let sample = link
                    .publisher
                    .loan_slice_uninit(frame.len())
                    .map_err(|e| other(format!("loaning {} bytes for {to}", frame.len()), e))?;
                match sample.write_from_slice(frame).send() {
                    Ok(0) => {} // The subscriber is registered but not yet connected.
                    Ok(_) => {
                        if notify {
                            link.notifier
                                .notify_with_custom_event_id(EV_SAMPLE)
                                .map_err(|e| other(format!("notifying {to}"), e))?;
                        }
                        return Ok(());
                    }
                    // The queue stayed full for one liveness period (backpressure handler).
                    Err(SendError::UnableToDeliver) => {}
                    Err(e) => return Err(other(format!("sending to {to}"), e)),
                }
            }
            // NOTE: the cap keeps the startup wait responsive: a new subscriber fires no event.
            self.wait_round(
                Some(to),
                deadline,
                started.elapsed(),
                Duration::from_millis(2),
            )?;
        }
    }
}

/// [`Bus::block`] for an end with a single peer (a node): waits on the listener itself, which
/// saves building a wait set per wait.
fn block_on_one(
    link: &mut Link,
    timeout: Duration,
    node: &Node<Svc>,
) -> Result<bool, TransportError> {
    let mut check_now = false;
    let mut seen = false;
    let waited = link.listener.timed_wait(
        |event| {
            if event.id == EV_NOTIFIER_DROPPED || event.id == EV_NOTIFIER_DEAD {
                check_now = true;
            } else if event.id == EV_NOTIFIER_CREATED || event.id == EV_SAMPLE {
                seen = true;
            }
        },
        timeout,
    );
    match waited {
        Ok(_) => {}
        // NOTE: any signal interrupts the wait; only SIGINT/SIGTERM set iceoryx2's flag.
        Err(ListenerWaitError::InterruptSignal) => {
            node.wait(Duration::ZERO)
                .map_err(|_| TransportError::Interrupted)?;
        }
        Err(e) => {
            return Err(other(
                format!("waiting on the listener of {}", link.peer),
                e,
            ));
        }
    }
    link.seen_publisher |= seen;
    Ok(check_now)
}

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

fn run_prefix(run_id: &str) -> String {
    format!("cosim_{run_id}_")
}

/// Opens (or creates) the data service and its event service with the settings every process
/// must share (pitfall 16).
fn open_channel(
    node: &Node<Svc>,
    name: &str,
) -> Result<(FrameService, EventFactory<Svc>), TransportError> {
    let service_name: ServiceName = name
        .try_into()
        .map_err(|e| other(format!("service name {name}"), e))?;
    let pubsub = node
        .service_builder(&service_name)
        .publish_subscribe::<[u8]>()
        .max_publishers(1)
        .max_subscribers(1)
        .subscriber_max_buffer_size(SUBSCRIBER_BUFFER)
        .subscriber_max_borrowed_samples(1)
        .history_size(0)
        .enable_safe_overflow(false)
        .open_or_create()
        .map_err(|e| other(format!("opening service {name}"), e))?;
    let event = node
        .service_builder(&service_name)
        .event()
        .notifier_created_event(EV_NOTIFIER_CREATED)
        .notifier_dropped_event(EV_NOTIFIER_DROPPED)
        .notifier_dead_event(EV_NOTIFIER_DEAD)
        .open_or_create()
        .map_err(|e| other(format!("opening event service {name}"), e))?;
    Ok((pubsub, event))
}

fn role_of(details: &Option<iceoryx2::node::NodeDetails>) -> Option<NodeKind> {
    let name = details.as_ref()?.name().to_string();
    [NodeKind::Coupler, NodeKind::Fluid, NodeKind::Solid]
        .into_iter()
        .find(|k| k.name() == name)
}

fn node_label(details: &Option<iceoryx2::node::NodeDetails>) -> String {
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
fn remove_prefixed(
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
fn iceoryx2_root(config: &Config) -> PathBuf {
    PathBuf::from(config.global.root_path().to_string())
}

impl RunLock {
    fn path(config: &Config, run_id: &str) -> PathBuf {
        iceoryx2_root(config)
            .join("cosim-runs")
            .join(format!("{run_id}.lock"))
    }

    fn open(path: &StdPath) -> Result<File, TransportError> {
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
    fn still_current(file: &File, path: &StdPath) -> bool {
        match (file.metadata(), std::fs::metadata(path)) {
            (Ok(held), Ok(now)) => held.ino() == now.ino() && held.dev() == now.dev(),
            _ => false,
        }
    }

    /// The lock of a process of the run; waits (until `deadline`) while a cleanup holds it.
    fn shared(config: &Config, run_id: &str, deadline: Instant) -> Result<RunLock, TransportError> {
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
    fn exclusive(config: &Config, run_id: &str) -> Result<Option<RunLock>, TransportError> {
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
    fn remove(self) {
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
fn is_transient(err: &TransportError) -> bool {
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

fn other(context: String, err: impl std::fmt::Debug) -> TransportError {
    TransportError::Other(format!("{context}: {err:?}"))
}
