//! Waiting for frames: the subscribers drained, the peers' liveness checked at least every
//! [`LIVENESS_PERIOD`], the signals, and the blocking wait on the listeners.

use std::time::{Duration, Instant};

use iceoryx2::node::NodeView;
use iceoryx2::port::listener::ListenerWaitError;
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;

use crate::bus::end::{Bus, Link};
use crate::bus::limits::Svc;
use crate::bus::limits::{
    EV_NOTIFIER_CREATED, EV_NOTIFIER_DEAD, EV_NOTIFIER_DROPPED, EV_SAMPLE, LIVENESS_PERIOD,
};
use crate::bus::run::{other, role_of};
use crate::transport::TransportError;
use crate::wire::NodeKind;

/// The shortest wait [`Bus::block`] hands the listener (see the note there).
const MIN_BLOCK: Duration = Duration::from_micros(1);

impl Bus {
    /// Moves every frame waiting in the subscribers into `pending`.
    pub(super) fn drain(&mut self) -> Result<bool, TransportError> {
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

    pub(super) fn take_pending(&mut self, from: Option<NodeKind>) -> Option<(NodeKind, Vec<u8>)> {
        let pos = self
            .pending
            .iter()
            .position(|(p, _)| from.is_none_or(|f| f == *p))?;
        self.pending.remove(pos)
    }

    /// Updates `seen` and `dead` of every link from the node list of the run's domain.
    pub(super) fn refresh_liveness(&mut self) -> Result<(), TransportError> {
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
    pub(super) fn check_signal(&self) -> Result<(), TransportError> {
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
    pub(super) fn block(
        &mut self,
        peer: Option<NodeKind>,
        timeout: Duration,
    ) -> Result<bool, TransportError> {
        // NOTE: iceoryx2 0.10's listener sets the timeout as `SO_RCVTIMEO` in whole microseconds
        // (`AsTimeval` drops the nanoseconds), and there 0 means no timeout: a slice under 1 µs
        // (a deadline or a liveness check falling due within it) blocked until the next
        // notification, which a peer that never came, or a dead one, never sends. A coupler
        // shutting a run down after its fluid node failed to start waited so for 11 minutes
        // and more, past a 60 s `--timeout-s`.
        let timeout = timeout.max(MIN_BLOCK);
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
    pub(super) fn wait_round(
        &mut self,
        peer: Option<NodeKind>,
        deadline: Instant,
        waited: Duration,
        cap: Duration,
    ) -> Result<(), TransportError> {
        self.check_signal()?;
        if let Some(parent) = self.parent
            && std::os::unix::process::parent_id() != parent
        {
            // The process that started this node is gone (whatever killed it).
            for link in &mut self.links {
                link.dead = true;
            }
            return Err(TransportError::PeerDead(NodeKind::Coupler));
        }
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
    pub(super) fn dead_peer(&mut self, peer: Option<NodeKind>) -> Result<(), TransportError> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus::{Bus, cleanup_run};

    /// A wait shorter than a microsecond on a silent peer returns (at once), as any bounded
    /// wait must: without [`MIN_BLOCK`] the listener got no timeout and blocked for good.
    #[test]
    fn a_wait_under_a_microsecond_returns() {
        let run = format!("tsubus{}", std::process::id());
        let mut coupler = Bus::open(&run, NodeKind::Coupler, &[NodeKind::Fluid]).expect("open");
        let fluid = Bus::open(&run, NodeKind::Fluid, &[NodeKind::Coupler]).expect("open");
        let (tell, told) = std::sync::mpsc::channel();
        let waiter = std::thread::spawn(move || {
            for nanos in [0, 1, 500, 999] {
                let waited = coupler.block(Some(NodeKind::Fluid), Duration::from_nanos(nanos));
                tell.send((nanos, waited.is_ok())).expect("the test waits");
            }
            coupler
        });
        for _ in 0..4 {
            let (nanos, ok) = told
                .recv_timeout(Duration::from_secs(10))
                .expect("a wait under a microsecond did not return within 10 s");
            assert!(ok, "the wait of {nanos} ns failed");
        }
        drop((waiter.join().expect("the waiter"), fluid));
        let _ = cleanup_run(&run);
    }
}
