//! Frames in and out: [`Transport`] for [`Bus`], and the publish with its back-pressure.

use std::time::{Duration, Instant};

use iceoryx2::port::SendError;
use iceoryx2::prelude::*;

use crate::bus::end::Bus;
use crate::bus::limits::{EV_SAMPLE, MAX_FRAME_LEN, SPIN, YIELD_SPIN};
use crate::bus::run::other;
use crate::transport::{Transport, TransportError};
use crate::wire::NodeKind;

impl Transport for Bus {
    fn me(&self) -> NodeKind {
        self.me
    }

    fn send(&mut self, to: NodeKind, frame: &[u8]) -> Result<(), TransportError> {
        self.publish(to, frame, true, self.send_timeout)
    }

    fn send_within(
        &mut self,
        to: NodeKind,
        frame: &[u8],
        timeout: Duration,
    ) -> Result<(), TransportError> {
        self.publish(to, frame, true, timeout.min(self.send_timeout))
    }

    fn send_more(&mut self, to: NodeKind, frame: &[u8]) -> Result<(), TransportError> {
        // NOTE: each notification is a datagram and a wake-up of the receiver (about 0.15 ms of
        // the sender's time on the project's machine); the frame that follows brings both.
        self.publish(to, frame, false, self.send_timeout)
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
    /// [`Transport::send`], with the receiver's notification only if `notify`, waiting at most
    /// `timeout` for the receiver.
    fn publish(
        &mut self,
        to: NodeKind,
        frame: &[u8],
        notify: bool,
        timeout: Duration,
    ) -> Result<(), TransportError> {
        let idx = self.link_index(to)?;
        if frame.len() > MAX_FRAME_LEN {
            return Err(TransportError::Other(format!(
                "frame of {} bytes to {to} exceeds the bus limit of {MAX_FRAME_LEN} bytes",
                frame.len()
            )));
        }
        let started = Instant::now();
        let deadline = started + timeout;
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
