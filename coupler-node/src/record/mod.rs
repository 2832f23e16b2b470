//! The MCAP record of a run (DESIGN §4–5): every bus frame exactly as it crossed the bus, node
//! checkpoints, and a JSON diagnostics channel; a bounded, CRC-checked reader that reads the
//! record of a killed run up to where it stopped; and a recovery that keeps what verifies.
//!
//! # Channels
//!
//! | topic | message encoding | schema (name, encoding) |
//! |---|---|---|
//! | `/fluid-to-coupler`, `/coupler-to-fluid`, `/solid-to-coupler`, `/coupler-to-solid` | `bincode` | `protocol::wire::Message`, `bincode-serde` |
//! | `/checkpoint/fluid`, `/checkpoint/solid` | `bincode` | `protocol::wire::Message`, `bincode-serde` |
//! | `/diagnostics` | `json` | `cosim.Diagnostics`, `jsonschema` ([`diagnostics_schema`], derived from [`Diagnostics`]) |
//! | `/checkpoint/coupler` | `bincode` | `protocol::wire::Message`, `bincode-serde` (a `Checkpoint` whose bytes are a `CouplerCheckpoint`) |
//! | `/foxglove/solid` | `json` | `foxglove.SceneUpdate`, `jsonschema` (at each output: the particles coloured by `sigma_n`, broken links; [`foxglove`]) |
//! | `/foxglove/fluid` | `json` | `foxglove.Grid`, `jsonschema` (at each output: `rho` and `p`, 2-D or the mid-plane slice) |
//!
//! Frames are the bytes of `protocol::codec` (24-byte header + bincode payload), so a reader
//! decodes them with `protocol::codec::decode`. Channel ids are fixed (1 to 10 in the order of the
//! table; `/diagnostics` and the two Foxglove channels, 1 to 3, at level `Diagnostics`),
//! sequence numbers count per channel from 0. The Foxglove channels are views of the output
//! files (written only with VTK outputs): their log and publish times are the output's
//! simulated time, and the readers here ([`read_recording`], `inspect`, `replay`) leave them
//! out.
//! Log time is the simulated time in ns ([`protocol::topics::log_time`]): a frame or checkpoint
//! has the start time of its step, a diagnostics message the end time of its step, so
//! Foxglove's timeline is the simulation's. Publish time is the wall clock in ns since the UNIX
//! epoch given by the caller. The coupling step is in every payload (the frame header's step,
//! the diagnostics' `step`), read back as [`Recorded::step`]. Everything but `publish_time`
//! (and the wall-clock `busy_s` of the diagnostics) is a function of the recorded run.
//!
//! Metadata records: `scene` {`name`, `toml`} and `run` {`protocol_version`, `record_layout`,
//! `record_level`, `recorder`}. Records of layout 1 (topics without `/`, log time = step,
//! protocol version 2) are refused with an error naming both versions
//! ([`RecordError::Layout`]): their frames would not decode with this protocol version anyway.
//!
//! # Diagnostics JSON
//!
//! One object per completed step, a serialized [`Diagnostics`]:
//!
//! ```json
//! {"step": 12, "t": 0.0012, "dt": 1e-4, "limiter": "fluid:cfl at cell 40", "iterations": 3,
//!  "residuals": [1e-3, 2e-7, 4e-13], "relaxation": [0.5, 0.4, 0.4], "columns": [0, 1, 2],
//!  "columns_dropped": 0, "predicted": true, "converged": true, "output": null,
//!  "ledger": {"step": 12, "t": 0.0012, "fluid_mass": 1.2, "fluid_energy": 250.0, ...},
//!  "busy_s": {"fluid": 0.010, "solid": 0.002, "coupler": 0.0001}}
//! ```
//!
//! `step` and `ledger.step` are the same number. A step that failed to converge has
//! `converged: false` and no `ledger`; readers fill missing fields with defaults.
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
//! writes the real data end, summary and footer over the provisional end. In a run the
//! recorder works on a thread of its own ([`Background`]): the coupler copies each message into
//! the open step and hands the step over whole at its end; the thread builds, compresses (zstd
//! level -5 by default) and writes the chunk. The record may fall behind the run by up to
//! [`MAX_LAG_STEPS`] steps and [`MAX_LAG_BYTES`] bytes (then the coupler waits for it), so a
//! killed run loses at most the steps still in flight; with `run.record_max_bytes` it keeps up
//! step by step.
//!
//! # Reading
//!
//! [`read_recording`] reads every message with bounded sizes and checked CRCs
//! ([`protocol::mcap_read`]): damage is an error naming the chunk and byte offset, a killed run
//! reads up to where it stopped. [`recover`] keeps what verifies, says what it dropped, and
//! rewrites it as a complete file.

mod background;
mod channels;
mod error;
pub mod foxglove;
mod reader;
mod recover;
mod writer;

pub use background::{Background, MAX_LAG_BYTES, MAX_LAG_STEPS};
pub use channels::{
    BusySeconds, DIAGNOSTICS_SCHEMA_NAME, DIAGNOSTICS_TOPIC, Diagnostics, FRAME_MESSAGE_ENCODING,
    FRAME_SCHEMA_ENCODING, FRAME_SCHEMA_NAME, checkpoint_topic, diagnostics_schema, frame_topic,
};
pub use error::RecordError;
pub(crate) use reader::recorded;
pub use reader::{FOXGLOVE_PREFIX, Recorded, Recording, read_recording};
pub use recover::{Recovered, recover};
pub use writer::{Recorder, cut_back};
