//! What the split sweeps do for a coupled step ([`SplitHooks`]), on one rank or on one block of
//! a decomposed grid: the halo exchange, ghost states and vacuum written before a sweep, the
//! pressures recorded, and the kept fluxes of the faces on the blocks' low sides exchanged
//! (issue 16; issue 40 item 1: no longer every kept flux and pressure to every rank).

use crate::fv::comm::HaloExchange;
use crate::fv::euler::NQ;
use crate::fv::solver::FluidSolver;
use crate::fv::solver::cell::cell_primitive;
use crate::fv::solver::hooks::{GhostFill, SplitHooks};
use crate::fv::state::{copy_cell, extend_cell};
use crate::fv::sweep::{Pencils, frame, from_local, mirror, to_local};

impl FluidSolver {
    /// Sends this rank's boundary planes along `axis` to its neighbours and receives theirs
    /// into the halo of that axis (collective between neighbours). Planes normal to the last
    /// axis are contiguous; along another axis they are packed in the order of the pencils
    /// along it ([`Pencils`]).
    pub(super) fn exchange_halo(&mut self, axis: usize) {
        let slab = &self.slab;
        let u = &self.state.u;
        let nvar = self.state.nvar;
        let [lo, hi] = &mut self.halo[axis];
        let d = lo.len().max(hi.len());
        let (to_lo, to_hi) = if axis == self.grid.dim - 1 {
            (&u[..d], &u[u.len() - d..])
        } else {
            let pencils = Pencils::new(&self.grid, axis);
            for (side, send) in self.halo_send.iter_mut().enumerate() {
                send.clear();
                let first = side * (pencils.n - slab.depth);
                for t in first..first + slab.depth {
                    for p in 0..pencils.count {
                        let c = (pencils.base(p) + t * pencils.stride) * nvar;
                        send.extend_from_slice(&u[c..c + nvar]);
                    }
                }
            }
            (&self.halo_send[0][..], &self.halo_send[1][..])
        };
        self.comm.exchange_halo(HaloExchange {
            to_lo: slab.lo[axis].map(|r| (r, to_lo)),
            to_hi: slab.hi[axis].map(|r| (r, to_hi)),
            from_lo: slab.lo[axis].map(|r| (r, &mut lo[..])),
            from_hi: slab.hi[axis].map(|r| (r, &mut hi[..])),
        });
    }

    /// Sets the cells of `cells` (whole grid) on this rank to vacuum (every conserved
    /// quantity zero).
    pub fn apply_vacuum(&mut self, cells: &[u32]) {
        self.sums_cache = std::sync::OnceLock::new();
        let nvar = self.state.nvar;
        for &c in cells {
            if let Some(c) = self.slab.to_local(c as usize) {
                self.state.u[c * nvar..(c + 1) * nvar].fill(0.0);
            }
        }
    }

    /// Writes the ghost states of `fills` (see [`GhostFill`]) on this rank's cells for a sweep
    /// along `axis`. Along a cut axis of a decomposed grid the halo is exchanged first, since
    /// a ghost may mirror a neighbour's cell (collective then).
    pub fn apply_ghosts(&mut self, axis: usize, fills: &[GhostFill]) {
        self.sums_cache = std::sync::OnceLock::new();
        let decomposed = self.slab.cut(axis);
        if decomposed {
            self.exchange_halo(axis);
        }
        let nvar = self.state.nvar;
        let dim = self.grid.dim;
        let fr = frame(dim, axis);
        let slab = &self.slab;
        let pencils = Pencils::new(&self.grid, axis);
        for g in fills {
            let Some(d) = slab.to_local(g.cell as usize) else {
                continue;
            };
            let src = g.mirror_of as usize;
            let cell: &[f64] = if let Some(s) = slab.to_local(src) {
                &self.state.u[s * nvar..(s + 1) * nvar]
            } else {
                // NOTE: a ghost mirrors a cell of its own pencil at most `2 ng − 1` cells away
                // along the sweep, within the `ng + 3` planes of the halo.
                let at = self.halo_cell(axis, &pencils, d, src);
                assert!(
                    decomposed && at.is_some(),
                    "ghost of cell {} mirrors cell {src}, outside rank {}'s cells and halo",
                    g.cell,
                    slab.rank
                );
                let (side, s) = at.expect("checked");
                &self.halo[axis][side][s * nvar..(s + 1) * nvar]
            };
            let local = to_local(cell, dim, &fr);
            let ghost = mirror(&local, &g.wall.in_frame(&fr));
            from_local(
                &ghost,
                dim,
                &fr,
                &mut self.state.u[d * nvar..(d + 1) * nvar],
            );
        }
    }

    /// Where the global cell `src` on the pencil along `axis` through local cell `d` lies in
    /// the halo of that axis: `(side, cell of the halo)`, `None` beyond it.
    fn halo_cell(
        &self,
        axis: usize,
        pencils: &Pencils,
        d: usize,
        src: usize,
    ) -> Option<(usize, usize)> {
        let slab = &self.slab;
        let g = slab.global.ijk(src);
        let mut l = self.grid.ijk(d);
        let first = slab.offset[axis];
        for a in (0..3).filter(|&a| a != axis) {
            if g[a] != l[a] + slab.offset[a] {
                return None;
            }
        }
        l[axis] = 0;
        let base = self.grid.index(l[0], l[1], l[2]);
        let p = base % pencils.stride + (base / (pencils.stride * pencils.n)) * pencils.stride;
        let (side, t) = if g[axis] < first {
            (0, g[axis].checked_sub(first.checked_sub(slab.depth)?)?)
        } else {
            (1, g[axis] - (first + pencils.n))
        };
        (t < slab.depth && !self.halo[axis][side].is_empty())
            .then_some((side, t * pencils.count + p))
    }

    /// `p̄` of this rank's cells of `cells` (whole grid, ascending) into `out` (zero for the
    /// other ranks' cells).
    pub(super) fn record_pressures_at(&self, cells: &[u32], out: &mut Vec<f64>) {
        let nvar = self.state.nvar;
        let dim = self.grid.dim;
        let gamma = self.params.gamma;
        out.clear();
        out.resize(cells.len(), 0.0);
        for (k, &c) in cells.iter().enumerate() {
            if let Some(c) = self.slab.to_local(c as usize) {
                out[k] = cell_primitive(&self.state.u[c * nvar..(c + 1) * nvar], dim, gamma).p;
            }
        }
    }

    /// After the sweeps of `order`: the kept fluxes of this rank's faces into `hooks.taps`, and
    /// on several ranks those of the faces on each block's low side along a cut axis, which
    /// are the high faces of the cells of the block below it there, on every rank (collective),
    /// each put where the receiver keeps that face (its taps may be its own: every rank's taps
    /// name the faces of the whole grid, but need not be the same). So each rank holds the kept
    /// fluxes of every face of its own cells that it keeps and that the block above keeps too,
    /// as one rank computes them (a face belongs to the rank of the cell above it, the last face
    /// to the last block).
    ///
    /// NOTE: every rank used to receive every kept flux and pressure (all of the near cells'
    /// faces, 44 bytes each); what reads them, the correct's update of a rank's own near cells
    /// (`embedded`), reads the faces of its own cells only, and `p̄` is taken by rank there
    /// (issue 40 item 1). Traffic now: the kept faces on the blocks' low sides, 52 bytes each.
    pub(super) fn gather_hook_outputs(&mut self, hooks: &mut SplitHooks, order: &[usize]) {
        for &axis in order {
            let tap = &mut hooks.taps[axis];
            tap.flux.clear();
            tap.flux.resize(tap.positions.len(), [0.0; NQ]);
            let local = &self.local.taps[axis];
            for (k, &slot) in self.local.slots[axis].iter().enumerate() {
                tap.flux[slot as usize] = local.flux[k];
            }
        }
        if self.slab.ranks == 1 {
            return;
        }
        // (axis, global pencil, position along it, flux) of each kept face on the low sides.
        let mut bytes = Vec::new();
        for &axis in order {
            let first = self.slab.offset[axis];
            if first == 0 {
                continue;
            }
            let (tap, local) = (&hooks.taps[axis], &self.local.taps[axis]);
            let slots = &self.local.slots[axis];
            for p in 0..local.pencil_offsets.len().saturating_sub(1) {
                let (lo, hi) = (local.pencil_offsets[p], local.pencil_offsets[p + 1]);
                for &slot in &slots[lo as usize..hi as usize] {
                    let m = tap.positions[slot as usize];
                    if m as usize == first {
                        bytes.extend((axis as u32).to_le_bytes());
                        bytes.extend((self.slab.global_pencil(axis, p) as u32).to_le_bytes());
                        bytes.extend(m.to_le_bytes());
                        for v in tap.flux[slot as usize] {
                            bytes.extend(v.to_bits().to_le_bytes());
                        }
                    }
                }
            }
        }
        const ENTRY: usize = 12 + 8 * NQ;
        let u32_at = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().expect("4"));
        for part in &self.comm.all_gather(&bytes) {
            for e in part.chunks_exact(ENTRY) {
                let (axis, p, m) = (u32_at(e, 0) as usize, u32_at(e, 4) as usize, u32_at(e, 8));
                let tap = &mut hooks.taps[axis];
                if tap.pencil_offsets.len() <= p + 1 {
                    continue;
                }
                let (lo, hi) = (
                    tap.pencil_offsets[p] as usize,
                    tap.pencil_offsets[p + 1] as usize,
                );
                let Ok(k) = tap.positions[lo..hi].binary_search(&m) else {
                    continue;
                };
                for (q, v) in tap.flux[lo + k].iter_mut().enumerate() {
                    let at = 12 + 8 * q;
                    *v = f64::from_bits(u64::from_le_bytes(e[at..at + 8].try_into().expect("8")));
                }
            }
        }
    }

    /// The slots of `cells` (whole grid, ascending) each rank owns, in order (blocks other than
    /// slabs: on slabs each rank's slots are one range, see [`FluidSolver::gather_owned_into`]).
    fn slots_by_rank(&self, cells: &[u32]) -> Vec<Vec<u32>> {
        let slab = &self.slab;
        let mut out = vec![Vec::new(); slab.ranks];
        for (k, &c) in cells.iter().enumerate() {
            out[slab.owner(c as usize)].push(k as u32);
        }
        out
    }

    /// The conserved values (`dim + 2` each) of `cells` (whole grid, ascending), from the ranks
    /// that hold them, on every rank (collective on several ranks).
    pub fn cells_at(&self, cells: &[u32]) -> Vec<f64> {
        debug_assert!(cells.is_sorted());
        let mine = self.own_cells_at(cells);
        self.gather_owned(cells, mine)
    }

    /// The conserved values (`dim + 2` each) of this rank's cells among `cells` (whole grid),
    /// in order.
    pub fn own_cells_at(&self, cells: &[u32]) -> Vec<f64> {
        let nvar = self.state.nvar;
        let mut mine = Vec::new();
        for &c in cells {
            if let Some(c) = self.slab.to_local(c as usize) {
                extend_cell(&mut mine, &self.state.u[c * nvar..(c + 1) * nvar]);
            }
        }
        mine
    }

    /// `dim + 2` values per cell of `cells` (whole grid, ascending), on every rank, from the
    /// values `mine` each rank gives for its own cells among them, in order (collective on
    /// several ranks).
    pub fn gather_owned(&self, cells: &[u32], mine: Vec<f64>) -> Vec<f64> {
        self.gather_owned_by(cells, mine, self.state.nvar)
    }

    /// [`FluidSolver::gather_owned`] with `nvar` values per cell.
    pub fn gather_owned_by(&self, cells: &[u32], mine: Vec<f64>, nvar: usize) -> Vec<f64> {
        let mut all = Vec::new();
        self.gather_owned_into(cells, mine, nvar, &mut all);
        all
    }

    /// [`FluidSolver::gather_owned_by`] into `all` (what it held overwritten, its allocation
    /// kept from call to call).
    ///
    /// NOTE: on slabs each rank owns one range of the global numbering, in rank order, so the
    /// ranks' values one after the other are the cells' in order: they are received straight
    /// into `all` ([`crate::fv::comm::Comm::all_gather_f64_into`]). On other blocks they are received into a
    /// buffer and put at each rank's slots.
    pub fn gather_owned_into(
        &self,
        cells: &[u32],
        mine: Vec<f64>,
        nvar: usize,
        all: &mut Vec<f64>,
    ) {
        debug_assert!(cells.is_sorted());
        if self.slab.ranks == 1 || cells.is_empty() {
            *all = mine;
            return;
        }
        if self.slab.slabs() {
            let counts = self.comm.all_gather_f64_into(&mine, all);
            assert_eq!(
                all.len(),
                cells.len() * nvar,
                "the ranks' cells: {counts:?}"
            );
            return;
        }
        let slots = self.slots_by_rank(cells);
        let mut flat = Vec::new();
        let counts = self.comm.all_gather_f64_into(&mine, &mut flat);
        for (rank, slots) in slots.iter().enumerate() {
            assert_eq!(counts[rank], slots.len() * nvar, "rank {rank}'s cells");
        }
        all.resize(cells.len() * nvar, 0.0);
        let mut at = 0;
        for slots in &slots {
            for &k in slots {
                let k = k as usize;
                copy_cell(&mut all[k * nvar..(k + 1) * nvar], &flat[at..at + nvar]);
                at += nvar;
            }
        }
    }

    /// The cells (whole grid) any rank asks for in `wanted` (ascending), ascending, with their
    /// conserved values (`dim + 2` each), on every rank (collective on several ranks: each rank
    /// may ask for other cells).
    pub fn cells_asked(&self, wanted: &[u32]) -> (Vec<u32>, Vec<f64>) {
        debug_assert!(wanted.is_sorted());
        if self.slab.ranks == 1 {
            return (wanted.to_vec(), self.cells_at(wanted));
        }
        let mut all: Vec<u32> = self
            .comm
            .all_gather(&protocol::codec::encode_blob(&wanted.to_vec()))
            .iter()
            .flat_map(|b| {
                protocol::codec::decode_blob::<Vec<u32>>(b).expect("ranks send valid cells")
            })
            .collect();
        all.sort_unstable();
        all.dedup();
        let values = self.cells_at(&all);
        (all, values)
    }

    /// Writes `values` (the first `dim + 2` of each) into the cells of the whole grid they
    /// name that lie on this rank, in order (a later write of a cell wins).
    pub fn set_cells(&mut self, values: &[(u32, [f64; NQ])]) {
        let nvar = self.state.nvar;
        for (c, v) in values {
            if let Some(c) = self.slab.to_local(*c as usize) {
                self.state.u[c * nvar..(c + 1) * nvar].copy_from_slice(&v[..nvar]);
            }
        }
        self.dt_cache = std::sync::OnceLock::new();
        self.sums_cache = std::sync::OnceLock::new();
    }
}
