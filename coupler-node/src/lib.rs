//! The coupler: the time loop, the handshake, the conservation ledger, the MCAP record, replay
//! and inspection, and the launcher that starts and supervises the nodes.

#![warn(missing_docs)]

pub mod inspect;
pub mod record;
