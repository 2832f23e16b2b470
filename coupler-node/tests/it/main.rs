//! Integration tests of `coupler-node`, one test binary: the MCAP record (read back, cut,
//! recovered, damaged, exported) and the report figures.

mod peak;
mod record;
mod report;
