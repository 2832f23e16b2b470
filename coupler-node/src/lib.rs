//! The coupler: the time loop, the handshake, the conservation ledger, the MCAP record, replay
//! and inspection, and the launcher that starts and supervises the nodes.
//!
//! - [`scheme`]: the handshake as a sans-IO state machine; [`dt`]: time-step agreement;
//!   [`ledger`]: the conservation balance; [`iqn`]: the IQN-ILS acceleration of the fixed point.
//! - [`driver`]: the loop that feeds the state machine from a transport and records every frame;
//!   [`progress`]: its progress line.
//! - [`launch`]: `coupler-node run` (scene validation, child processes, supervision, outputs);
//!   [`restart`]: a run resumed from a record's checkpoints; [`out_folder`]: the output folder
//!   (refused when not empty unless `--overwrite`, which clears an earlier run's files).
//! - [`record`], [`sink`]: the MCAP record; [`inspect`], [`replay`], [`coupler_replay`]: reading
//!   it back; [`frame_diff`]: the first difference a replay finds.
//! - [`report`]: the papers' figures from a run's outputs.
//! - [`check`]: `coupler-node check` (a scene validated without running it); [`preflight`]: what
//!   `run`, `check` and `replay` look up and check before any process starts.
//! - [`cli`]: the command line.

#![warn(missing_docs)]

pub mod check;
pub mod cli;
pub mod coupler_replay;
pub mod driver;
pub mod dt;
pub mod frame_diff;
pub mod inspect;
pub mod iqn;
pub mod launch;
pub mod ledger;
pub mod mpi_launch;
pub mod out_folder;
pub mod preflight;
pub mod progress;
pub mod record;
pub mod replay;
pub mod report;
pub mod restart;
pub mod scheme;
pub mod sink;
