//! End-to-end and cross-crate tests (one test binary).

mod corpus;
mod coupled;
mod doubles;
mod e2e;
mod issue_11;
mod issue_11_records;
mod issue_14;
mod issue_15;
mod issue_15_cli;
mod issue_15_logs;
#[cfg(feature = "mpi")]
mod issue_16_coupled;
#[cfg(feature = "mpi")]
mod issue_16_mpi;
mod issue_38;
mod issue_38_records;
mod issue_39;
mod issue_39_python;
mod issue_39_views;
mod subcycling;
mod tidy;
