//! The cells of a block of pencils, read from and written to the x-fastest state in one pass
//! each (`sweep.rs`).
//!
//! A block is [`BLOCK_PENCILS`] consecutive pencils; along y or z they are neighbours along x,
//! so the block's cells at one position `m` along the axis are one contiguous run of the state
//! (16 cells, 640 bytes in 3-D). [`gather_block`] reads
//! the block's interior cells run by run straight into the pencils' lines (sweep frame), which
//! the kernel then reads in cache; [`CellWriter::scatter_block`] writes the pencils' updated
//! cells back the same way from the lines the kernel wrote, straight into the x-fastest output.
//!
//! NOTE: before, each pencil read its cells one by one at the axis stride (a page apart along
//! z on 128³), wrote its cells pencil-major into a second buffer, and a transpose pass copied
//! that buffer back to the x-fastest layout: three passes over the state per y or z sweep
//! instead of two, and one 40-byte cell per page touched. Writing in place needs the blocks to
//! share the output: each cell lies on exactly one pencil, so the blocks' writes are disjoint
//! ([`CellWriter`]).

use std::marker::PhantomData;

use crate::fv::euler::{NQ, State};
use crate::fv::isa::prefetch_line;

/// Pencils per parallel block of a sweep (a fixed partition, `sweep.rs`).
pub const BLOCK_PENCILS: usize = 16;

/// The cells of one block: the first cell of each of its pencils, the cells a pencil and the
/// index distance between consecutive cells of a pencil.
pub(crate) struct Block {
    bases: [usize; BLOCK_PENCILS],
    count: usize,
    n: usize,
    stride: usize,
}

impl Block {
    /// The block of the pencils whose first cells are `bases` (at most [`BLOCK_PENCILS`]), of
    /// `n` cells `stride` apart.
    pub(crate) fn new(bases: impl Iterator<Item = usize>, n: usize, stride: usize) -> Block {
        let mut block = Block {
            bases: [0; BLOCK_PENCILS],
            count: 0,
            n,
            stride,
        };
        for base in bases {
            assert!(
                block.count < BLOCK_PENCILS,
                "more than {BLOCK_PENCILS} pencils"
            );
            block.bases[block.count] = base;
            block.count += 1;
        }
        block
    }

    /// One past the last stored value of the block's cells (`NV` a cell; 0 without cells).
    fn end<const NV: usize>(&self) -> usize {
        match self.bases[..self.count].iter().max() {
            Some(&last) if self.n > 0 => (last + (self.n - 1) * self.stride + 1) * NV,
            _ => 0,
        }
    }

    /// Whether the block's pencils are neighbours along the stored order (so that its cells at
    /// one position are one run of the state: along y or z).
    #[inline(always)]
    fn contiguous(&self) -> bool {
        self.count > 0 && self.bases[self.count - 1] == self.bases[0] + self.count - 1
    }

    /// Asks the CPU to bring the block's cells at position `m` along the axis into the cache
    /// (`u` the state, `NV` values a cell; a hint only, no access).
    ///
    /// NOTE: along y or z, a position's cells are a run of 640 bytes a row or a plane from the
    /// next (3-D, 16 pencils): ten cache lines, too short for the hardware's stream prefetcher
    /// to find before the run ends, so the gather waited on each run's loads (65 % of its
    /// samples on one load). Along x the pencils are sixteen streams the hardware follows, and
    /// a hint a cell costs little.
    #[inline(always)]
    fn prefetch<const NV: usize>(&self, u: *const f64, m: usize) {
        let along = m * self.stride;
        let bases = &self.bases[..self.count];
        if self.contiguous() {
            let first = (bases[0] + along) * NV;
            let last = (bases[0] + along + self.count) * NV - 1;
            let mut byte = (first * 8) & !63;
            while byte <= last * 8 {
                prefetch_line(u.wrapping_byte_add(byte));
                byte += 64;
            }
        } else {
            for &base in bases {
                let c = base + along;
                prefetch_line(u.wrapping_add(c * NV));
                prefetch_line(u.wrapping_add((c + 1) * NV - 1));
            }
        }
    }
}

/// Positions along the axis a block's gather and scatter hint ahead of their copy
/// ([`Block::prefetch`]).
const AHEAD: usize = 4;

/// Writes the cells of the pencils of `block` into the lines `tiles`, pencil `k`'s cell `m` at
/// `tiles[k][at + m]`, in the sweep frame `fr` (as `sweep::to_local` gives it).
///
/// NOTE: the lines are the buffers the kernel reads (`LineScratch::u`, swapped in pencil by
/// pencil), so that no pencil's cells are copied a second time from a tile into its line.
pub(crate) fn gather_block(
    tiles: &mut [Vec<State>],
    at: usize,
    u: &[f64],
    nvar: usize,
    block: &Block,
    fr: &[Option<usize>; 3],
) {
    let map = local_index(nvar, fr);
    match (nvar, map_3d(&map)) {
        (3, _) => gather_cells::<3, RUN_TIME>(tiles, at, u, block, &map),
        (4, _) => gather_cells::<4, RUN_TIME>(tiles, at, u, block, &map),
        (_, Some(0)) => gather_cells::<5, 0>(tiles, at, u, block, &map),
        (_, Some(1)) => gather_cells::<5, 1>(tiles, at, u, block, &map),
        (_, Some(2)) => gather_cells::<5, 2>(tiles, at, u, block, &map),
        (_, Some(3)) => gather_cells::<5, 3>(tiles, at, u, block, &map),
        (_, Some(4)) => gather_cells::<5, 4>(tiles, at, u, block, &map),
        (_, Some(5)) => gather_cells::<5, 5>(tiles, at, u, block, &map),
        _ => gather_cells::<5, RUN_TIME>(tiles, at, u, block, &map),
    }
}

/// The maps of a 3-D cell ([`local_index`] with five values): density and energy in place, the
/// three velocities in each of their orders.
///
/// NOTE: the gather and the scatter take the map as a constant where it is one of these (the
/// `P` of `gather_cells` and `scatter_cells`): a value's index read at run time was a bounds
/// check and an indexed load a value, ~32 instructions a cell in the gather.
const MAPS_3D: [[usize; NQ]; 6] = [
    [0, 1, 2, 3, 4],
    [0, 1, 3, 2, 4],
    [0, 2, 1, 3, 4],
    [0, 2, 3, 1, 4],
    [0, 3, 1, 2, 4],
    [0, 3, 2, 1, 4],
];

/// The `P` of `gather_cells` and `scatter_cells` that reads the map at run time.
const RUN_TIME: usize = MAPS_3D.len();

/// Which of [`MAPS_3D`] `map` is.
fn map_3d(map: &[usize; NQ]) -> Option<usize> {
    MAPS_3D.iter().position(|m| m == map)
}

/// [`MAPS_3D`]`[p]` (`map` for [`RUN_TIME`]).
#[inline(always)]
fn map_of<const P: usize>(map: &[usize; NQ]) -> [usize; NQ] {
    if P < RUN_TIME { MAPS_3D[P] } else { *map }
}

/// The sweep-frame component of each stored component of a cell (`sweep::to_local`: density
/// first, energy last, the velocity of storage axis `a` in the slot of `a` in `fr`).
fn local_index(nvar: usize, fr: &[Option<usize>; 3]) -> [usize; NQ] {
    let mut map = [0; NQ];
    map[nvar - 1] = NQ - 1;
    for (slot, a) in fr.iter().enumerate() {
        if let Some(a) = a {
            map[1 + a] = 1 + slot;
        }
    }
    map
}

/// [`gather_block`] for `NV` stored values per cell (copies of a fixed size, no branches).
///
/// NOTE: each sweep-frame value is loaded from the stored cell at its index (`src`) and the
/// state is built in registers. Storing the values one by one into a local array at indices
/// read at run time and copying that array into the tile (as before) made every cell wait on
/// a failed store-to-load forwarding (16-byte loads of 8-byte stores): 40 % of the samples
/// of the gather sat on that one load, and the gather was 13 % of a 3-D step.
///
/// `P`: the map, one of [`MAPS_3D`] (a constant), or [`RUN_TIME`] (`map`).
fn gather_cells<const NV: usize, const P: usize>(
    tiles: &mut [Vec<State>],
    at: usize,
    u: &[f64],
    block: &Block,
    map: &[usize; NQ],
) {
    let (src, keep) = source_index::<NV>(&map_of::<P>(map));
    let n = block.n;
    let bases = &block.bases[..block.count];
    // Each pencil's first cell in its line (`n` cells there, checked by the slicing): pointers,
    // so that the loop checks no bounds a cell (with slices, 15 M more instructions a 128³
    // step than with the one tile before).
    let mut lines = [std::ptr::null_mut::<State>(); BLOCK_PENCILS];
    for (line, tile) in lines.iter_mut().zip(&mut tiles[..block.count]) {
        *line = tile[at..at + n].as_mut_ptr();
    }
    assert!(
        block.end::<NV>() <= u.len(),
        "the block's cells lie in the state"
    );
    for m in 0..n {
        if m + AHEAD < n {
            block.prefetch::<NV>(u.as_ptr(), m + AHEAD);
        }
        let along = m * block.stride;
        for (&line, &base) in lines.iter().zip(bases) {
            let c = base + along;
            // SAFETY: in bounds: `c` is at most the block's last cell, whose values end at
            // `block.end()` ≤ `u.len()` (asserted above).
            // NOTE: through the pointer, not a slice of `u`: the slice's bounds checks (two a
            // cell) were a quarter of the gather's instructions.
            let cell = unsafe { &*u.as_ptr().add(c * NV).cast::<[f64; NV]>() };
            let state = if NV == NQ {
                std::array::from_fn(|q| cell[src[q]])
            } else {
                // The inactive velocity slots of a 1-D or 2-D state stay 0.
                std::array::from_fn(|q| if keep[q] { cell[src[q]] } else { 0.0 })
            };
            // SAFETY: m < n, and `line` points to `n` cells of a line of its own.
            unsafe { line.add(m).write(state) };
        }
    }
}

/// The inverse of `map` (stored component → sweep-frame component): the stored component each
/// sweep-frame component reads (`src`), and whether it reads one (`keep`; the inactive
/// velocity slots of a 1-D or 2-D state do not).
#[inline(always)]
fn source_index<const NV: usize>(map: &[usize; NQ]) -> ([usize; NQ], [bool; NQ]) {
    let (mut src, mut keep) = ([0; NQ], [false; NQ]);
    for (j, &q) in map[..NV].iter().enumerate() {
        src[q] = j;
        keep[q] = true;
    }
    (src, keep)
}

/// The output state of a sweep, which every block writes at the cells of its own pencils.
pub(crate) struct CellWriter<'a> {
    ptr: *mut f64,
    len: usize,
    _out: PhantomData<&'a mut [f64]>,
}

// SAFETY: a `CellWriter` is shared only by the blocks of one sweep, and they write disjoint
// cells (see `scatter_block`); nothing reads the output until the sweep is over.
unsafe impl Sync for CellWriter<'_> {}
// SAFETY: as for `Sync`: it is a `&mut [f64]` split by cells.
unsafe impl Send for CellWriter<'_> {}

impl<'a> CellWriter<'a> {
    /// Shares `out` (borrowed for the writer's life).
    pub(crate) fn new(out: &'a mut [f64]) -> CellWriter<'a> {
        CellWriter {
            ptr: out.as_mut_ptr(),
            len: out.len(),
            _out: PhantomData,
        }
    }

    /// Writes cell `m` of pencil `k` of `block` from `tiles[k][at + m]` (the lines the kernel
    /// wrote, `LineScratch::new`) into its cell of the state (as `sweep::from_local` does).
    ///
    /// # Safety
    /// No other thread accesses the cells of these pencils while this runs: each block of a
    /// sweep scatters its own pencils, and a cell lies on one pencil along an axis.
    pub(crate) unsafe fn scatter_block(
        &self,
        tiles: &[Vec<State>],
        at: usize,
        nvar: usize,
        block: &Block,
        fr: &[Option<usize>; 3],
    ) {
        let map = local_index(nvar, fr);
        // SAFETY: passed on from the caller.
        unsafe {
            match (nvar, map_3d(&map)) {
                (3, _) => self.scatter_cells::<3, RUN_TIME>(tiles, at, block, &map),
                (4, _) => self.scatter_cells::<4, RUN_TIME>(tiles, at, block, &map),
                (_, Some(0)) => self.scatter_cells::<5, 0>(tiles, at, block, &map),
                (_, Some(1)) => self.scatter_cells::<5, 1>(tiles, at, block, &map),
                (_, Some(2)) => self.scatter_cells::<5, 2>(tiles, at, block, &map),
                (_, Some(3)) => self.scatter_cells::<5, 3>(tiles, at, block, &map),
                (_, Some(4)) => self.scatter_cells::<5, 4>(tiles, at, block, &map),
                (_, Some(5)) => self.scatter_cells::<5, 5>(tiles, at, block, &map),
                _ => self.scatter_cells::<5, RUN_TIME>(tiles, at, block, &map),
            }
        }
    }

    /// [`CellWriter::scatter_block`] for `NV` stored values per cell.
    ///
    /// NOTE: non-temporal stores (`movnti`, no read of the lines written) for the runs of a y
    /// or z sweep were tried: 10 % fewer samples in the scatter, the same CPU time a step on
    /// 128³ and 64³ (3 alternated pairs each), so dropped.
    ///
    /// # Safety
    /// As for [`CellWriter::scatter_block`].
    unsafe fn scatter_cells<const NV: usize, const P: usize>(
        &self,
        tiles: &[Vec<State>],
        at: usize,
        block: &Block,
        map: &[usize; NQ],
    ) {
        // `P` as in `gather_cells`.
        let map = &map_of::<P>(map);
        let n = block.n;
        let bases = &block.bases[..block.count];
        // As in `gather_cells`: pointers to `n` cells each, checked by the slicing.
        let mut lines = [std::ptr::null::<State>(); BLOCK_PENCILS];
        for (line, tile) in lines.iter_mut().zip(&tiles[..block.count]) {
            *line = tile[at..at + n].as_ptr();
        }
        assert!(
            block.end::<NV>() <= self.len,
            "the block's cells lie in the state"
        );
        for m in 0..n {
            if m + AHEAD < n {
                block.prefetch::<NV>(self.ptr, m + AHEAD);
            }
            let along = m * block.stride;
            for (&line, &base) in lines.iter().zip(bases) {
                let c = base + along;
                // SAFETY: in bounds (the block's last cell is, asserted above); the caller
                // guarantees that no other thread touches this cell, and `_out` that the slice
                // outlives the writer.
                let cell = unsafe { &mut *self.ptr.add(c * NV).cast::<[f64; NV]>() };
                // SAFETY: m < n, `line` points to `n` cells.
                let local = unsafe { &*line.add(m) };
                for j in 0..NV {
                    cell[j] = local[map[j]];
                }
            }
        }
    }
}
