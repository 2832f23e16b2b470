//! Messages exchanged between the co-simulation nodes, their encoding, the scene schema, and
//! (feature `bus`) the iceoryx2 transport that carries them.
//!
//! - [`wire`]: message types, pure data.
//! - [`codec`]: a 24-byte header plus the bincode 2 payload; version checks.
//! - [`scene`]: the scene file schema and its validation.
//! - [`session`]: what the two node loops share (config, errors, proposals, failure reports).
//! - [`transport`]: the transport trait the loops are written against, and an in-memory one.
//! - [`sum`]: order-independent, mirror-exact sums (both nodes' numerics).
//! - [`suggest`]: "did you mean" for misspelt keys and values.
//! - [`topics`]: topic names and log-time convention of the MCAP record.
//! - [`vtk`]: VTK XML files for ParaView (`.vti`, `.vtp`, `.pvd`) built in memory, and read back.
//! - `bus` (feature `bus`): the only module that touches iceoryx2.
//! - `mcap_read` (feature `replay`): bounded, CRC-checked reading of MCAP bytes.
//! - `replay` (feature `replay`): a node's recorded messages read back from MCAP bytes, and the
//!   replay double that plays them in step with the coupler.
//! - `serve` (features `bus` and `replay`): what both node binaries run.
//! - `logs` (feature `logs`): the binaries' stderr subscriber (level from `RUST_LOG` or
//!   `-v`/`-q`, lines prefixed with the node's name).
//!
//! Invariant: apart from `bus`, `serve` and `logs`, this crate does no IO: no files, sockets,
//! threads, clocks or environment variables (the in-memory transport's deadline is its only use
//! of time). The node loop emits `tracing` events, which write nothing unless a binary installs
//! a subscriber.

#![deny(missing_docs)]

pub mod codec;
pub mod decomp;
pub mod scene;
pub mod session;
pub mod suggest;
pub mod sum;
pub mod topics;
pub mod transport;
pub mod vtk;
pub mod wire;

#[cfg(feature = "bus")]
pub mod bus;
#[cfg(feature = "logs")]
pub mod logs;
#[cfg(feature = "replay")]
pub mod mcap_read;
#[cfg(feature = "replay")]
pub mod replay;
#[cfg(all(feature = "bus", feature = "replay"))]
pub mod serve;

pub use wire::PROTOCOL_VERSION;
