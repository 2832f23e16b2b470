//! One process's end of the bus ([`Bus`]): its ports towards each peer, opened under the run's
//! lock.

use std::collections::VecDeque;
use std::sync::Once;
use std::time::{Duration, Instant};

use iceoryx2::config::Config;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::{BackpressureAction, BackpressureInfo};
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;

use crate::bus::limits::{
    DEFAULT_SEND_TIMEOUT, EV_NOTIFIER_CREATED, EV_NOTIFIER_DEAD, EV_NOTIFIER_DROPPED,
    INITIAL_SLICE_LEN, LIVENESS_PERIOD, OPEN_RETRY_DEADLINE, SUBSCRIBER_BUFFER, Svc,
};
use crate::bus::run::{RunLock, is_transient, other, run_config, service_name};
use crate::transport::TransportError;
use crate::wire::NodeKind;

/// A data service carrying frames.
pub(super) type FrameService = PubSubFactory<Svc, [u8], ()>;

/// One process's end of the bus.
pub struct Bus {
    pub(super) me: NodeKind,
    pub(super) run_id: String,
    pub(super) links: Vec<Link>,
    /// Frames received but not yet asked for, in arrival order.
    pub(super) pending: VecDeque<(NodeKind, Vec<u8>)>,
    pub(super) last_check: Instant,
    pub(super) send_timeout: Duration,
    /// A node's parent process at open (the coupler, or `mpirun` for MPI ranks): a wait that
    /// finds another parent (the coupler died and the node was re-parented) ends with the
    /// coupler gone. `None` for the coupler.
    pub(super) parent: Option<u32>,
    /// Dropped after every port.
    pub(super) node: Node<Svc>,
    /// Declared last: released after the node, so a sweep never sees the run unowned while its
    /// files still change.
    pub(super) _lock: RunLock,
}

/// The two directions between this end and one peer.
pub(super) struct Link {
    pub(super) peer: NodeKind,
    pub(super) out_service: FrameService,
    pub(super) publisher: Publisher<Svc, [u8], ()>,
    pub(super) notifier: Notifier<Svc>,
    pub(super) in_service: FrameService,
    pub(super) subscriber: Subscriber<Svc, [u8], ()>,
    pub(super) listener: Listener<Svc>,
    /// The peer's node has been seen alive in the run's node list.
    pub(super) seen_node: bool,
    /// The peer's publisher towards us has been seen.
    pub(super) seen_publisher: bool,
    /// The peer is known to be gone; sticky.
    pub(super) dead: bool,
}

impl Bus {
    /// Opens this process's end. `run_id` isolates the run (iceoryx2 config prefix
    /// `cosim_<run_id>_`; at most [`MAX_RUN_ID_LEN`](crate::bus::MAX_RUN_ID_LEN) bytes of `A-Z a-z 0-9 _ -`), `me` is this
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
            parent: (me != NodeKind::Coupler).then(std::os::unix::process::parent_id),
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

    pub(super) fn link_index(&self, peer: NodeKind) -> Result<usize, TransportError> {
        self.links
            .iter()
            .position(|l| l.peer == peer)
            .ok_or_else(|| TransportError::Other(format!("{} has no link to {peer}", self.me)))
    }
}

/// Opens (or creates) the data service and its event service with the settings every process
/// must share (pitfall 16).
pub(super) fn open_channel(
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
