//! The bus's sizes, periods and event ids, and the iceoryx2 service flavour it uses.

use std::time::Duration;

use iceoryx2::prelude::{EventId, ipc_threadsafe};

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
pub(super) const INITIAL_SLICE_LEN: usize = 64 << 10;

/// How long [`Bus::open`](crate::bus::Bus::open) retries the transient failures of a run whose files are being created
/// or removed by another process at the same moment.
pub const OPEN_RETRY_DEADLINE: Duration = Duration::from_secs(10);

/// How long a receive spins on the subscribers before it blocks.
pub(super) const SPIN: Duration = Duration::from_micros(20);

/// How long a receive then keeps looking, yielding the core between looks, before it blocks.
///
/// NOTE: a frame that finds its receiver asleep costs the sender a wake-up of the receiver's
/// core, which on the project's virtual machine was most of the coupler's time in a coupled
/// step (the replies of the fixed point come within a millisecond). Looking for 0.5 ms first,
/// yielding to whatever else is runnable, took the coupled 2-D beam from 1.36 to 1.25 times
/// the fluid-only run (medians of 40 and 35 pairs); 2 ms gave 1.24.
pub(super) const YIELD_SPIN: Duration = Duration::from_micros(500);

/// Event ids on the event service paired with each data service.
pub(super) const EV_SAMPLE: EventId = EventId::new(1);
pub(super) const EV_NOTIFIER_CREATED: EventId = EventId::new(2);
pub(super) const EV_NOTIFIER_DROPPED: EventId = EventId::new(3);
pub(super) const EV_NOTIFIER_DEAD: EventId = EventId::new(4);

/// Ports are `Send + Sync`, so a `Bus` may move between threads.
pub(super) type Svc = ipc_threadsafe::Service;
