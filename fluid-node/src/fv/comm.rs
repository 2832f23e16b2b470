//! The ranks a decomposed grid is spread over, as the solver sees them: a small [`Comm`] trait
//! (halo exchange between neighbouring blocks, all-gather, gather, broadcast) with the
//! single-rank [`Serial`] implementation here. The MPI one (`crate::ranks::mpi`, feature
//! `mpi`) and an in-process one over threads (`crate::ranks::threads`, for tests) live outside
//! the pure core, which only calls this trait.
//!
//! Every collective is called by every rank in the same order with the same sizes known to the
//! receivers; payloads are opaque bytes or `f64` planes, so the trait stays object-safe and the
//! bits of what crosses it are the bits that were sent (no reduction happens inside a `Comm`:
//! the solver sums what it gathers in a fixed order, so results do not depend on the ranks).

/// Halo planes one rank sends and receives before a sweep along the decomposed axis: its
/// lowest and highest planes go to its neighbours, theirs come back into `from_lo`/`from_hi`.
/// `None` where there is no neighbour on that side (a domain face).
pub struct HaloExchange<'a> {
    /// The rank below and the planes it gets (this rank's lowest ones).
    pub to_lo: Option<(usize, &'a [f64])>,
    /// The rank above and the planes it gets (this rank's highest ones).
    pub to_hi: Option<(usize, &'a [f64])>,
    /// The rank below and where its highest planes land.
    pub from_lo: Option<(usize, &'a mut [f64])>,
    /// The rank above and where its lowest planes land.
    pub from_hi: Option<(usize, &'a mut [f64])>,
}

/// Tag of halo planes travelling up (to the rank above, landing in its `from_lo`).
pub const TAG_UP: i32 = 1;
/// Tag of halo planes travelling down (to the rank below, landing in its `from_hi`).
pub const TAG_DOWN: i32 = 2;

/// Communication between the ranks of one decomposed grid (see the module doc).
pub trait Comm: Send {
    /// This rank, `0..size()`.
    fn rank(&self) -> usize;
    /// Number of ranks.
    fn size(&self) -> usize;
    /// Sends and receives the halo planes of `halo` (all four transfers at once, so that
    /// neighbours do not wait for each other). Two ranks with periodic sides are each other's
    /// neighbour on both sides; the tags [`TAG_UP`] and [`TAG_DOWN`] keep the two apart.
    fn exchange_halo(&self, halo: HaloExchange<'_>);
    /// Every rank's `mine`, in rank order, on every rank, into `out` (what it held replaced,
    /// its allocation kept from call to call).
    fn all_gather_into(&self, mine: &[u8], out: &mut Gathered);
    /// Every rank's `mine`, in rank order, on every rank.
    fn all_gather(&self, mine: &[u8]) -> Gathered {
        let mut out = Gathered::default();
        self.all_gather_into(mine, &mut out);
        out
    }
    /// Every rank's `mine`, in rank order, one after the other in `out` (its length set to their
    /// total, what it held overwritten, its allocation kept from call to call); returns how
    /// many values each rank gave. The same values as [`Comm::all_gather`] of their bytes.
    fn all_gather_f64_into(&self, mine: &[f64], out: &mut Vec<f64>) -> Vec<usize> {
        let parts = self.all_gather(&f64_bytes(mine));
        out.clear();
        let mut counts = Vec::with_capacity(parts.len());
        for part in parts.iter() {
            counts.push(part.len() / 8);
            out.extend(bytes_f64(part));
        }
        counts
    }
    /// Every rank's `mine`, in rank order, on `root` (`None` elsewhere).
    fn gather(&self, root: usize, mine: &[u8]) -> Option<Vec<Vec<u8>>>;
    /// `root`'s `buf` on every rank (other ranks' `buf` is replaced).
    fn broadcast(&self, root: usize, buf: &mut Vec<u8>);
}

/// One rank: nothing to exchange, gathers return the caller's own bytes.
#[derive(Clone, Copy, Debug, Default)]
pub struct Serial;

impl Comm for Serial {
    fn rank(&self) -> usize {
        0
    }

    fn size(&self) -> usize {
        1
    }

    fn exchange_halo(&self, halo: HaloExchange<'_>) {
        assert!(
            halo.to_lo.is_none()
                && halo.to_hi.is_none()
                && halo.from_lo.is_none()
                && halo.from_hi.is_none(),
            "a single rank has no neighbours"
        );
    }

    fn all_gather_into(&self, mine: &[u8], out: &mut Gathered) {
        out.set(&[mine]);
    }

    fn gather(&self, root: usize, mine: &[u8]) -> Option<Vec<Vec<u8>>> {
        assert_eq!(root, 0, "a single rank is rank 0");
        Some(vec![mine.to_vec()])
    }

    fn broadcast(&self, root: usize, _buf: &mut Vec<u8>) {
        assert_eq!(root, 0, "a single rank is rank 0");
    }
}

/// The bytes of every rank, in rank order, of one all-gather: one buffer, each rank's part a
/// slice of it ([`Gathered::iter`], `gathered[rank]`).
#[derive(Clone, Debug, Default)]
pub struct Gathered {
    bytes: Vec<u8>,
    /// Where each rank's part ends in `bytes`.
    ends: Vec<usize>,
}

impl Gathered {
    /// The parts, in rank order.
    pub fn iter(&self) -> Parts<'_> {
        Parts {
            gathered: self,
            next: 0,
        }
    }

    /// Number of parts (ranks).
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// Whether there is no part.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// Heap bytes held (capacities).
    pub fn capacity_bytes(&self) -> usize {
        self.bytes.capacity() + self.ends.capacity() * std::mem::size_of::<usize>()
    }

    /// `parts` one after the other (buffers reused).
    pub fn set(&mut self, parts: &[&[u8]]) {
        self.bytes.clear();
        self.ends.clear();
        for p in parts {
            self.bytes.extend_from_slice(p);
            self.ends.push(self.bytes.len());
        }
    }

    /// The buffer, `total` bytes long (what it held is to be overwritten: only what it grows
    /// by is zeroed), for parts of `counts` bytes, and records where each ends.
    pub fn receive(&mut self, counts: impl IntoIterator<Item = usize>) -> &mut [u8] {
        self.ends.clear();
        let mut end = 0;
        for n in counts {
            end += n;
            self.ends.push(end);
        }
        self.bytes.resize(end, 0);
        &mut self.bytes[..]
    }
}

impl std::ops::Index<usize> for Gathered {
    type Output = [u8];

    fn index(&self, rank: usize) -> &[u8] {
        let start = if rank == 0 { 0 } else { self.ends[rank - 1] };
        &self.bytes[start..self.ends[rank]]
    }
}

impl<'a> IntoIterator for &'a Gathered {
    type Item = &'a [u8];
    type IntoIter = Parts<'a>;

    fn into_iter(self) -> Parts<'a> {
        self.iter()
    }
}

/// The parts of a [`Gathered`], in rank order.
pub struct Parts<'a> {
    gathered: &'a Gathered,
    next: usize,
}

impl<'a> Iterator for Parts<'a> {
    type Item = &'a [u8];

    fn next(&mut self) -> Option<&'a [u8]> {
        let g = self.gathered;
        (self.next < g.len()).then(|| {
            self.next += 1;
            &g[self.next - 1]
        })
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.gathered.len() - self.next;
        (n, Some(n))
    }
}

impl ExactSizeIterator for Parts<'_> {}

/// `f64` values as little-endian bytes (bit for bit).
pub fn f64_bytes(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The inverse of [`f64_bytes`].
pub fn bytes_f64(bytes: &[u8]) -> Vec<f64> {
    debug_assert!(bytes.len().is_multiple_of(8));
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect()
}

/// Byte strings packed into one: a `u64` count, then each length and its bytes (the wire of
/// gathers over transports that move one buffer).
pub fn pack(parts: &[Vec<u8>]) -> Vec<u8> {
    let mut out = (parts.len() as u64).to_le_bytes().to_vec();
    for p in parts {
        out.extend((p.len() as u64).to_le_bytes());
        out.extend(p);
    }
    out
}

/// The inverse of [`pack`].
pub fn unpack(bytes: &[u8]) -> Vec<Vec<u8>> {
    let read = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
    let n = read(0) as usize;
    let mut at = 8;
    (0..n)
        .map(|_| {
            let len = read(at) as usize;
            at += 8;
            let part = bytes[at..at + len].to_vec();
            at += len;
            part
        })
        .collect()
}
