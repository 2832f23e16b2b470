//! [`Comm`] over MPI (feature `mpi`): rsmpi on the system's Open MPI or MPICH. The world
//! communicator of `mpirun -n K fluid-node ...` holds the fluid's ranks; rank 0 also holds the
//! bus (`ranks::node`).

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use mpi::Count;
use mpi::datatype::PartitionMut;
use mpi::environment::Universe;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::fv::comm::{Comm, Gathered, HaloExchange, TAG_DOWN, TAG_UP};

/// Wall time spent in halo exchanges and the bytes they moved, shared with whoever measures
/// (the scaling benchmark reads the halo share of a step from it).
#[derive(Debug, Default)]
pub struct HaloClock {
    /// Nanoseconds inside [`Comm::exchange_halo`].
    pub nanos: AtomicU64,
    /// Bytes sent by this rank in halo exchanges.
    pub bytes: AtomicU64,
}

/// This process's rank of the MPI world.
pub struct MpiComm {
    world: SimpleCommunicator,
    clock: Arc<HaloClock>,
}

/// Why MPI could not be set up for the fluid.
#[derive(Debug, thiserror::Error)]
pub enum MpiInitError {
    /// `MPI_Init` ran before in this process.
    #[error("MPI was already initialised")]
    AlreadyInitialised,
    /// The library's thread level (its name) is below `Serialized`.
    #[error("the MPI library gives thread level {0}, the fluid needs Serialized")]
    ThreadLevel(String),
}

// SAFETY: the communicator handle is only used through `&self` by one thread at a time (the
// node loop owns the solver that owns this `Comm`; `MpiComm` is not `Sync`), and MPI is
// initialised with at least `Threading::Serialized` (checked in `MpiComm::init`), which allows
// calls from any thread as long as they are not concurrent.
unsafe impl Send for MpiComm {}

impl MpiComm {
    /// Initialises MPI (once per process) and returns the universe (MPI is finalised when it
    /// drops: keep it until the end of `main`) and this rank's communicator.
    pub fn init() -> Result<(Universe, MpiComm), MpiInitError> {
        let (universe, threading) = mpi::initialize_with_threading(mpi::Threading::Serialized)
            .ok_or(MpiInitError::AlreadyInitialised)?;
        if threading < mpi::Threading::Serialized {
            return Err(MpiInitError::ThreadLevel(format!("{threading:?}")));
        }
        let world = universe.world();
        Ok((
            universe,
            MpiComm {
                world,
                clock: Arc::default(),
            },
        ))
    }

    /// A second communicator over the same ranks (collective): messages on one never meet
    /// those of the other.
    pub fn duplicate(&self) -> MpiComm {
        MpiComm {
            world: self.world.duplicate(),
            clock: Arc::default(),
        }
    }

    /// The halo timer of this rank.
    pub fn clock(&self) -> Arc<HaloClock> {
        self.clock.clone()
    }

    /// Ends every rank of the job (after a rank's fatal error that the others cannot see).
    pub fn abort(&self, code: i32) -> ! {
        self.world.abort(code)
    }

    fn counts(&self, mine: usize) -> Vec<Count> {
        let mine = Count::try_from(mine).expect("a message under 2 GiB");
        let mut counts = vec![0 as Count; self.size()];
        self.world.all_gather_into(&mine, &mut counts[..]);
        counts
    }
}

fn displacements(counts: &[Count]) -> Vec<Count> {
    counts
        .iter()
        .scan(0, |acc, &n| {
            let at = *acc;
            *acc += n;
            Some(at)
        })
        .collect()
}

fn split(buf: &[u8], counts: &[Count]) -> Vec<Vec<u8>> {
    let mut at = 0;
    counts
        .iter()
        .map(|&n| {
            let part = buf[at..at + n as usize].to_vec();
            at += n as usize;
            part
        })
        .collect()
}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.world.rank() as usize
    }

    fn size(&self) -> usize {
        self.world.size() as usize
    }

    fn exchange_halo(&self, halo: HaloExchange<'_>) {
        let start = std::time::Instant::now();
        let world = &self.world;
        let mut sent = 0u64;
        mpi::request::scope(|scope| {
            let (from_lo, from_hi) = (halo.from_lo, halo.from_hi);
            let recv_lo = from_lo.map(|(r, into)| {
                world
                    .process_at_rank(r as i32)
                    .immediate_receive_into_with_tag(scope, into, TAG_UP)
            });
            let recv_hi = from_hi.map(|(r, into)| {
                world
                    .process_at_rank(r as i32)
                    .immediate_receive_into_with_tag(scope, into, TAG_DOWN)
            });
            sent += [halo.to_lo, halo.to_hi]
                .iter()
                .flatten()
                .map(|(_, p)| 8 * p.len() as u64)
                .sum::<u64>();
            let down = halo.to_lo.map(|(r, planes)| {
                world
                    .process_at_rank(r as i32)
                    .immediate_send_with_tag(scope, planes, TAG_DOWN)
            });
            let up = halo.to_hi.map(|(r, planes)| {
                world
                    .process_at_rank(r as i32)
                    .immediate_send_with_tag(scope, planes, TAG_UP)
            });
            for r in [recv_lo, recv_hi, down, up].into_iter().flatten() {
                r.wait();
            }
        });
        self.clock
            .nanos
            .fetch_add(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
        self.clock.bytes.fetch_add(sent, Ordering::Relaxed);
    }

    fn all_gather_into(&self, mine: &[u8], out: &mut Gathered) {
        let counts = self.counts(mine.len());
        // NOTE: received in place into one buffer, kept by the caller where it gathers often:
        // a fresh zeroed buffer, then split into one fresh vector per rank, copied every
        // gathered byte twice (the largest a step: the shares of the blocks' geometry).
        let buf = out.receive(counts.iter().map(|&n| n as usize));
        // NOTE: Open MPI refuses an all-gather of nothing at all (MPI_ERR_ARG for the empty
        // receive buffer); every rank knows the counts, so every rank skips it.
        if buf.is_empty() {
            return;
        }
        let displs = displacements(&counts);
        let mut partition = PartitionMut::new(buf, &counts[..], &displs[..]);
        self.world.all_gather_varcount_into(mine, &mut partition);
    }

    fn all_gather_f64_into(&self, mine: &[f64], out: &mut Vec<f64>) -> Vec<usize> {
        let counts = self.counts(mine.len());
        let total = counts.iter().map(|&n| n as usize).sum();
        // NOTE: received in place, into the caller's kept allocation: only what it grows by is
        // zeroed first. A fresh buffer, split into one vector per rank and then copied again
        // into the caller's, was four copies and three fresh allocations of every near cell's
        // state a step (`FluidSolver::gather_owned_into`).
        out.resize(total, 0.0);
        if total > 0 {
            let displs = displacements(&counts);
            let mut partition = PartitionMut::new(&mut out[..], &counts[..], &displs[..]);
            self.world.all_gather_varcount_into(mine, &mut partition);
        }
        counts.iter().map(|&n| n as usize).collect()
    }

    fn gather(&self, root: usize, mine: &[u8]) -> Option<Vec<Vec<u8>>> {
        // Every rank learns the counts (one small all-gather), so that only the root allocates.
        let counts = self.counts(mine.len());
        if counts.iter().all(|&n| n == 0) {
            return (self.rank() == root).then(|| vec![Vec::new(); counts.len()]);
        }
        let process = self.world.process_at_rank(root as i32);
        if self.rank() != root {
            process.gather_varcount_into(mine);
            return None;
        }
        let displs = displacements(&counts);
        let mut buf = vec![0u8; counts.iter().map(|&n| n as usize).sum()];
        {
            let mut partition = PartitionMut::new(&mut buf[..], &counts[..], &displs[..]);
            process.gather_varcount_into_root(mine, &mut partition);
        }
        Some(split(&buf, &counts))
    }

    fn broadcast(&self, root: usize, buf: &mut Vec<u8>) {
        // NOTE: the length goes by a non-blocking broadcast polled every 200 µs on every rank
        // (a non-blocking collective matches only non-blocking ones): the broadcasts carry rank
        // 0's next call, which may be long in coming while rank 0 waits on the coupler, and a
        // blocking one spins; polled, waiting ranks leave the cores to the coupler and the solid.
        let process = self.world.process_at_rank(root as i32);
        let mut len = buf.len() as u64;
        mpi::request::scope(|scope| {
            let mut request = process.immediate_broadcast_into(scope, &mut len);
            loop {
                match request.test() {
                    Ok(_) => break,
                    Err(pending) => {
                        request = pending;
                        std::thread::sleep(std::time::Duration::from_micros(200));
                    }
                }
            }
        });
        buf.resize(len as usize, 0);
        process.broadcast_into(&mut buf[..]);
    }
}
