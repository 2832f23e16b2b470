//! [`Comm`] between threads of one process: K "ranks" as threads joined by channels, so that
//! the decomposition is tested bit for bit against one rank without an MPI library (the MPI
//! implementation is `ranks::mpi`, feature `mpi`).

use std::sync::Mutex;
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::time::Duration;

use crate::fv::comm::{Comm, Gathered, HaloExchange, TAG_DOWN, TAG_UP};

/// How long a rank waits for a peer's message before it panics naming both (a bug: every
/// collective is called by every rank).
pub const DEADLINE: Duration = Duration::from_secs(60);

/// Tag of the collectives' messages.
const TAG_COLLECTIVE: i32 = 0;

type Envelope = (usize, i32, Vec<u8>);

/// One rank's end of a [`ThreadRanks::new`] group.
pub struct ThreadComm {
    rank: usize,
    to: Vec<Sender<Envelope>>,
    from: Mutex<Inbox>,
}

struct Inbox {
    rx: Receiver<Envelope>,
    /// Messages that arrived before they were asked for.
    early: Vec<Envelope>,
}

/// A group of thread ranks.
pub struct ThreadRanks;

impl ThreadRanks {
    /// `size` connected ranks, rank `r` at index `r` (move each to its thread).
    #[allow(clippy::new_ret_no_self)]
    pub fn new(size: usize) -> Vec<ThreadComm> {
        let (txs, rxs): (Vec<_>, Vec<_>) = (0..size).map(|_| channel::<Envelope>()).unzip();
        rxs.into_iter()
            .enumerate()
            .map(|(rank, rx)| ThreadComm {
                rank,
                to: txs.clone(),
                from: Mutex::new(Inbox {
                    rx,
                    early: Vec::new(),
                }),
            })
            .collect()
    }
}

impl ThreadComm {
    fn send(&self, to: usize, tag: i32, bytes: Vec<u8>) {
        self.to[to]
            .send((self.rank, tag, bytes))
            .unwrap_or_else(|_| panic!("rank {}: rank {to} has gone", self.rank));
    }

    fn recv(&self, from: usize, tag: i32) -> Vec<u8> {
        let mut inbox = self.from.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(k) = inbox
            .early
            .iter()
            .position(|(f, t, _)| *f == from && *t == tag)
        {
            return inbox.early.remove(k).2;
        }
        loop {
            match inbox.rx.recv_timeout(DEADLINE) {
                Ok((f, t, bytes)) if f == from && t == tag => return bytes,
                Ok(other) => inbox.early.push(other),
                Err(RecvTimeoutError::Timeout) => panic!(
                    "rank {}: no message from rank {from} (tag {tag}) within {DEADLINE:?}",
                    self.rank
                ),
                Err(RecvTimeoutError::Disconnected) => {
                    panic!("rank {}: rank {from} has gone", self.rank)
                }
            }
        }
    }
}

impl Comm for ThreadComm {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.to.len()
    }

    fn exchange_halo(&self, halo: HaloExchange<'_>) {
        let bytes = |v: &[f64]| crate::fv::comm::f64_bytes(v);
        if let Some((r, planes)) = halo.to_lo {
            self.send(r, TAG_DOWN, bytes(planes));
        }
        if let Some((r, planes)) = halo.to_hi {
            self.send(r, TAG_UP, bytes(planes));
        }
        if let Some((r, into)) = halo.from_lo {
            let v = crate::fv::comm::bytes_f64(&self.recv(r, TAG_UP));
            into.copy_from_slice(&v);
        }
        if let Some((r, into)) = halo.from_hi {
            let v = crate::fv::comm::bytes_f64(&self.recv(r, TAG_DOWN));
            into.copy_from_slice(&v);
        }
    }

    fn all_gather_into(&self, mine: &[u8], out: &mut Gathered) {
        let all = self.gather(0, mine);
        let mut flat = all
            .map(|parts| crate::fv::comm::pack(&parts))
            .unwrap_or_default();
        self.broadcast(0, &mut flat);
        let parts = crate::fv::comm::unpack(&flat);
        out.set(&parts.iter().map(Vec::as_slice).collect::<Vec<_>>());
    }

    fn gather(&self, root: usize, mine: &[u8]) -> Option<Vec<Vec<u8>>> {
        if self.rank != root {
            self.send(root, TAG_COLLECTIVE, mine.to_vec());
            return None;
        }
        Some(
            (0..self.size())
                .map(|r| {
                    if r == root {
                        mine.to_vec()
                    } else {
                        self.recv(r, TAG_COLLECTIVE)
                    }
                })
                .collect(),
        )
    }

    fn broadcast(&self, root: usize, buf: &mut Vec<u8>) {
        if self.rank == root {
            for r in (0..self.size()).filter(|&r| r != root) {
                self.send(r, TAG_COLLECTIVE, buf.clone());
            }
        } else {
            *buf = self.recv(root, TAG_COLLECTIVE);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ThreadRanks;
    use crate::fv::comm::Comm;

    /// Ranks giving 2, 0 and 3 values: every rank receives them one after the other with their
    /// counts, as bits, into a buffer that held more values than that and into one that held
    /// fewer.
    #[test]
    fn the_f64_all_gather_puts_every_ranks_values_in_rank_order() {
        let values = |r: usize| -> Vec<f64> {
            match r {
                0 => vec![1.5, -0.0],
                1 => vec![],
                _ => vec![f64::MIN_POSITIVE, 3e300, -7.25],
            }
        };
        let expected: Vec<u64> = (0..3).flat_map(values).map(f64::to_bits).collect();
        let handles: Vec<_> = (ThreadRanks::new(3).into_iter())
            .map(|comm| {
                std::thread::spawn(move || {
                    let mine = values(comm.rank());
                    let mut longer = vec![9.0; 11];
                    let counts = comm.all_gather_f64_into(&mine, &mut longer);
                    let mut shorter = vec![9.0; 1];
                    comm.all_gather_f64_into(&mine, &mut shorter);
                    (counts, longer, shorter)
                })
            })
            .collect();
        for h in handles {
            let (counts, longer, shorter) = h.join().expect("rank");
            assert_eq!(counts, [2, 0, 3]);
            for out in [longer, shorter] {
                assert_eq!(
                    out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    expected
                );
            }
        }
    }
}
