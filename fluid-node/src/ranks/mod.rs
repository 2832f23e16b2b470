//! The fluid grid on several ranks: implementations of [`crate::fv::Comm`] (threads of one
//! process for tests; MPI with the feature `mpi`) and the node's rank-0-leads loop.

#[cfg(feature = "mpi")]
pub mod launch;
#[cfg(feature = "mpi")]
pub mod mpi;
#[cfg(feature = "node")]
pub mod node;
pub mod threads;
