//! The MCAP record of a run (DESIGN §4–5): every bus frame exactly as it crossed the bus, node
//! checkpoints, and a JSON diagnostics channel; a bounded, CRC-checked reader that reads the
//! record of a killed run up to where it stopped; and a recovery that keeps what verifies.
//!
//! # Channels
//!
//! | topic | message encoding | schema (name, encoding) |
//! |---|---|---|
//! | `fluid-to-coupler`, `coupler-to-fluid`, `solid-to-coupler`, `coupler-to-solid` | `bincode` | `protocol::wire::Message`, `bincode-serde` |
//! | `checkpoint/fluid`, `checkpoint/solid` | `bincode` | `protocol::wire::Message`, `bincode-serde` |
//! | `diagnostics` | `json` | `cosim.Diagnostics`, `jsonschema` ([`DIAGNOSTICS_SCHEMA`]) |
//! | `checkpoint/coupler` | `bincode` | `protocol::wire::Message`, `bincode-serde` (a `Checkpoint` whose bytes are a `CouplerCheckpoint`) |
//!
//! Frames are the bytes of `protocol::codec` (24-byte header + bincode payload), so a reader
//! decodes them with `protocol::codec::decode`. Channel ids are fixed (1 to 8 in the order of the
//! table; only `diagnostics` at level `Diagnostics`), sequence numbers count per channel from 0,
//! `log_time` is the coupling step and `publish_time` the wall clock in ns since the UNIX epoch
//! given by the caller. Everything but `publish_time` is a function of the recorded run.
//!
//! Metadata records: `scene` {`name`, `toml`} and `run` {`protocol_version`, `record_level`,
//! `recorder`}.
//!
//! # Diagnostics JSON
//!
//! One object per completed step, serialized by the coupler (see [`Diagnostics`]):
//!
//! ```json
//! {"step": 12, "t": 0.0012, "dt": 1e-4, "iterations": 3, "residuals": [1e-3, 2e-7, 4e-13],
//!  "converged": true,
//!  "ledger": {"fluid_mass": 1.2, "fluid_energy": 250.0, "solid_energy": 3.5,
//!             "mass_rel_err": 1e-15, "energy_rel_err": 2e-12},
//!  "busy_s": {"fluid": 0.010, "solid": 0.002, "coupler": 0.0001}}
//! ```
//!
//! `step` is required; every other field may be missing (readers must cope); more ledger keys
//! may be added.
//!
//! # Durability
//!
//! Chunks are built in memory and written whole. [`Recorder::end_step`] closes the open chunk
//! (so does a chunk passing 4 MiB), writes it, and after it the provisional end
//! [`protocol::mcap_read::PROVISIONAL_END`] (a data end, a footer without summary and the end
//! magic), which the next chunk overwrites. A run killed between two writes therefore leaves a
//! complete MCAP file without summary, which the standard readers (Python `mcap`'s
//! `make_reader`, the mcap crate's `MessageStream`) read up to the last completed step; only a
//! kill during the write itself leaves one unfinished record at the end. [`Recorder::finish`]
//! writes the real data end, summary and footer over the provisional end.
//!
//! # Reading
//!
//! [`read_recording`] reads every message with bounded sizes and checked CRCs
//! ([`protocol::mcap_read`]): damage is an error naming the chunk and byte offset, a killed run
//! reads up to where it stopped. [`recover`] keeps what verifies, says what it dropped, and
//! rewrites it as a complete file.

mod channels;
mod error;
mod reader;
mod recover;
mod writer;

pub use channels::{
    BusySeconds, DIAGNOSTICS_SCHEMA, DIAGNOSTICS_TOPIC, Diagnostics, FRAME_MESSAGE_ENCODING,
    FRAME_SCHEMA_ENCODING, FRAME_SCHEMA_NAME, checkpoint_topic, frame_topic,
};
pub use error::RecordError;
pub use reader::{Recorded, Recording, read_recording};
pub use recover::{Recovered, recover};
pub use writer::Recorder;
