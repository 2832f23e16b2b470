//! What the node loops and the coupler need from a transport, and an in-memory one.
//!
//! [`Transport`] is implemented by the iceoryx2 bus (`bus::Bus`, feature `bus`) and by
//! [`MemoryTransport`], which runs all three roles in one process (tests, and the baseline the
//! cost of the bus is measured against). Frames are the bytes of [`crate::codec`].

use std::collections::VecDeque;
use std::sync::mpsc;
use std::time::Duration;

use crate::wire::NodeKind;

/// Why a send or receive failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum TransportError {
    /// Nothing arrived before the deadline.
    #[error("no message from {} within {waited:?}", peer.map_or("any peer", |p| p.name()))]
    Timeout {
        /// Who was waited for (`None`: any peer).
        peer: Option<NodeKind>,
        /// How long.
        waited: Duration,
    },
    /// The peer process is gone (crashed, killed, or closed its end).
    #[error("{0} node is gone (died or stopped answering)")]
    PeerDead(NodeKind),
    /// A termination signal arrived (Ctrl-C, SIGTERM).
    #[error("interrupted by a signal")]
    Interrupted,
    /// Anything else, with the transport's message.
    #[error("transport: {0}")]
    Other(String),
}

/// A message transport between the coupler and the nodes.
pub trait Transport {
    /// The role of this end.
    fn me(&self) -> NodeKind;

    /// Sends one frame to `to`.
    fn send(&mut self, to: NodeKind, frame: &[u8]) -> Result<(), TransportError>;

    /// [`Transport::send`], waiting at most `timeout` (not the transport's own send timeout) for
    /// `to` to take the frame: for a frame that matters less than ending on time, such as the
    /// shutdown of a run that failed, to a peer that may never have come or may be gone.
    fn send_within(
        &mut self,
        to: NodeKind,
        frame: &[u8],
        timeout: Duration,
    ) -> Result<(), TransportError> {
        let _ = timeout;
        self.send(to, frame)
    }

    /// Sends one frame to `to` that another [`Transport::send`] to `to` follows at once: a
    /// transport that wakes its receiver per frame may leave that to the frame that follows
    /// (the receiver takes both at its wake-up). Nothing is lost if none follows: the frame is
    /// taken at the receiver's next look.
    fn send_more(&mut self, to: NodeKind, frame: &[u8]) -> Result<(), TransportError> {
        self.send(to, frame)
    }

    /// Waits at most `timeout` for a frame from `from` (`None`: from any peer). Frames from other
    /// peers that arrive meanwhile are kept for later calls, never dropped.
    fn recv(
        &mut self,
        from: Option<NodeKind>,
        timeout: Duration,
    ) -> Result<(NodeKind, Vec<u8>), TransportError>;
}

/// Sending half of a link: frames tagged with their sender.
type FrameSender = mpsc::Sender<(NodeKind, Vec<u8>)>;

/// One end of an in-memory star: the coupler talks to each node, nodes talk to the coupler.
pub struct MemoryTransport {
    me: NodeKind,
    senders: Vec<(NodeKind, FrameSender)>,
    receiver: mpsc::Receiver<(NodeKind, Vec<u8>)>,
    pending: VecDeque<(NodeKind, Vec<u8>)>,
}

impl MemoryTransport {
    /// Builds the coupler's end and one end per node in `nodes`.
    pub fn star(nodes: &[NodeKind]) -> (MemoryTransport, Vec<MemoryTransport>) {
        let (coupler_tx, coupler_rx) = mpsc::channel();
        let mut coupler = MemoryTransport {
            me: NodeKind::Coupler,
            senders: Vec::new(),
            receiver: coupler_rx,
            pending: VecDeque::new(),
        };
        let mut ends = Vec::new();
        for &node in nodes {
            let (tx, rx) = mpsc::channel();
            coupler.senders.push((node, tx));
            ends.push(MemoryTransport {
                me: node,
                senders: vec![(NodeKind::Coupler, coupler_tx.clone())],
                receiver: rx,
                pending: VecDeque::new(),
            });
        }
        (coupler, ends)
    }
}

impl Transport for MemoryTransport {
    fn me(&self) -> NodeKind {
        self.me
    }

    fn send(&mut self, to: NodeKind, frame: &[u8]) -> Result<(), TransportError> {
        let (_, tx) = self
            .senders
            .iter()
            .find(|(peer, _)| *peer == to)
            .ok_or_else(|| TransportError::Other(format!("{} has no link to {to}", self.me)))?;
        tx.send((self.me, frame.to_vec()))
            .map_err(|_| TransportError::PeerDead(to))
    }

    fn recv(
        &mut self,
        from: Option<NodeKind>,
        timeout: Duration,
    ) -> Result<(NodeKind, Vec<u8>), TransportError> {
        let wanted = |peer: NodeKind| from.is_none_or(|f| f == peer);
        if let Some(pos) = self.pending.iter().position(|(p, _)| wanted(*p)) {
            return Ok(self.pending.remove(pos).expect("position is in range"));
        }
        let mut left = timeout;
        loop {
            // NOTE: `recv_timeout` is the only clock use here; it is the transport's deadline,
            // not part of any result.
            let started = std::time::Instant::now();
            match self.receiver.recv_timeout(left) {
                Ok((peer, frame)) if wanted(peer) => return Ok((peer, frame)),
                Ok(other) => self.pending.push_back(other),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    return Err(TransportError::Timeout {
                        peer: from,
                        waited: timeout,
                    });
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(TransportError::PeerDead(from.unwrap_or(NodeKind::Coupler)));
                }
            }
            left = left.saturating_sub(started.elapsed());
        }
    }
}

/// Why a node's exchange with the coupler ended.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The transport failed (timeout, dead coupler, signal).
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// A frame did not decode.
    #[error("undecodable frame from the coupler: {0}")]
    Decode(#[from] crate::codec::DecodeError),
    /// The coupler refused this node at hello.
    #[error("refused by the coupler: {0}")]
    Refused(String),
    /// The coupler sent something that does not fit the handshake.
    #[error("unexpected message from the coupler: {0}")]
    Unexpected(String),
    /// The coupler shut the run down before it welcomed this node (the other node failed to
    /// start): the node ends cleanly.
    #[error("shut down by the coupler before it welcomed this node")]
    ShutDown,
}

/// A node's typed view of its transport to the coupler.
pub struct Link<'a> {
    transport: &'a mut dyn Transport,
    timeout: Duration,
    buf: Vec<u8>,
}

impl<'a> Link<'a> {
    /// Wraps `transport`; every receive waits at most `timeout`.
    pub fn new(transport: &'a mut dyn Transport, timeout: Duration) -> Link<'a> {
        Link {
            transport,
            timeout,
            buf: Vec::new(),
        }
    }

    /// This end's role.
    pub fn me(&self) -> NodeKind {
        self.transport.me()
    }

    /// Encodes and sends `msg` to the coupler.
    pub fn send(&mut self, msg: &crate::wire::Message) -> Result<(), LinkError> {
        crate::codec::encode_into(self.transport.me(), msg, &mut self.buf);
        self.transport.send(NodeKind::Coupler, &self.buf)?;
        Ok(())
    }

    /// Waits for the coupler's next message.
    pub fn recv(&mut self) -> Result<crate::wire::Message, LinkError> {
        let (_, frame) = self.transport.recv(Some(NodeKind::Coupler), self.timeout)?;
        let (_, msg) = crate::codec::decode(&frame)?;
        Ok(msg)
    }

    /// Sends `hello` and waits for the coupler's welcome.
    pub fn greet(&mut self, hello: crate::wire::Hello) -> Result<(), LinkError> {
        self.send(&crate::wire::Message::Hello(hello))?;
        match self.recv()? {
            crate::wire::Message::Welcome(w) if w.accepted => Ok(()),
            crate::wire::Message::Welcome(w) => Err(LinkError::Refused(w.reason)),
            crate::wire::Message::Shutdown(_) => Err(LinkError::ShutDown),
            other => Err(LinkError::Unexpected(format!(
                "{:?} instead of Welcome",
                other.kind()
            ))),
        }
    }
}
