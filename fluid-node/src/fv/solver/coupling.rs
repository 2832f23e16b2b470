//! What the split sweeps do for a coupled step ([`SplitHooks`]), on one rank or on one block of
//! a decomposed grid: the halo exchange, ghost states and vacuum written before a sweep, the
//! pressures recorded, and the kept fluxes and pressures gathered on every rank (issue 16).

use crate::fv::comm::{HaloExchange, bytes_f64, f64_bytes};
use crate::fv::euler::NQ;
use crate::fv::solver::FluidSolver;
use crate::fv::solver::cell::cell_primitive;
use crate::fv::solver::hooks::{GhostFill, SplitHooks};
use crate::fv::sweep::{Pencils, frame, from_local, mirror, to_local};

/// What one rank sends of the hooks' outputs: the pressures of the slots of its cells, in
/// order (one list per axis), and its kept fluxes `(slot, flux)` per axis.
#[derive(Default, serde::Serialize, serde::Deserialize)]
struct HookOutputs {
    pressures: Vec<Vec<f64>>,
    fluxes: Vec<Vec<(u32, [f64; NQ])>>,
}

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
    /// other ranks' cells until [`FluidSolver::gather_hook_outputs`]).
    pub(super) fn record_pressures_at(&mut self, cells: &[u32], out: &mut Vec<f64>) {
        let nvar = self.state.nvar;
        let dim = self.grid.dim;
        let gamma = self.params.gamma;
        let slots = &mut self.local.pressure_slots;
        slots.clear();
        out.clear();
        out.resize(cells.len(), 0.0);
        for (k, &c) in cells.iter().enumerate() {
            if let Some(c) = self.slab.to_local(c as usize) {
                slots.push(k as u32);
                out[k] = cell_primitive(&self.state.u[c * nvar..(c + 1) * nvar], dim, gamma).p;
            }
        }
    }

    /// After the sweeps of `order`: the kept fluxes of this rank into `hooks.taps`, then the
    /// pressures and fluxes of every rank on every rank (collective on several ranks).
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
        let slots = &self.local.pressure_slots;
        let mine = HookOutputs {
            pressures: (0..3)
                .map(|a| {
                    let p = &hooks.pressures[a];
                    if p.is_empty() {
                        Vec::new()
                    } else {
                        slots.iter().map(|&k| p[k as usize]).collect()
                    }
                })
                .collect(),
            fluxes: (0..3)
                .map(|a| {
                    let flux = &hooks.taps[a].flux;
                    self.local.slots[a]
                        .iter()
                        .filter(|_| order.contains(&a))
                        .map(|&slot| (slot, flux[slot as usize]))
                        .collect()
                })
                .collect(),
        };
        let all = self.comm.all_gather(&protocol::codec::encode_blob(&mine));
        let by_rank = self.slots_by_rank(&hooks.pressure_cells);
        for (rank, bytes) in all.iter().enumerate() {
            let part: HookOutputs =
                protocol::codec::decode_blob(bytes).expect("ranks send valid hook outputs");
            for (a, values) in part.pressures.iter().enumerate() {
                for (&k, &v) in by_rank[rank].iter().zip(values) {
                    hooks.pressures[a][k as usize] = v;
                }
            }
            for (a, fluxes) in part.fluxes.iter().enumerate() {
                for &(slot, f) in fluxes {
                    hooks.taps[a].flux[slot as usize] = f;
                }
            }
        }
    }

    /// The slots of `cells` (whole grid) each rank owns, in order.
    fn slots_by_rank(&self, cells: &[u32]) -> Vec<Vec<u32>> {
        let mut out = vec![Vec::new(); self.slab.ranks];
        for (k, &c) in cells.iter().enumerate() {
            out[self.slab.owner(c as usize)].push(k as u32);
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
                mine.extend_from_slice(&self.state.u[c * nvar..(c + 1) * nvar]);
            }
        }
        mine
    }

    /// `dim + 2` values per cell of `cells` (whole grid, ascending), on every rank, from the
    /// values `mine` each rank gives for its own cells among them, in order (collective on
    /// several ranks).
    pub fn gather_owned(&self, cells: &[u32], mine: Vec<f64>) -> Vec<f64> {
        debug_assert!(cells.is_sorted());
        if self.slab.ranks == 1 || cells.is_empty() {
            return mine;
        }
        let nvar = self.state.nvar;
        let parts: Vec<Vec<f64>> = self
            .comm
            .all_gather(&f64_bytes(&mine))
            .iter()
            .map(|b| bytes_f64(b))
            .collect();
        let mut all = vec![0.0; cells.len() * nvar];
        for (rank, slots) in self.slots_by_rank(cells).iter().enumerate() {
            assert_eq!(parts[rank].len(), slots.len() * nvar, "rank {rank}'s cells");
            for (i, &k) in slots.iter().enumerate() {
                let k = k as usize;
                all[k * nvar..(k + 1) * nvar]
                    .copy_from_slice(&parts[rank][i * nvar..(i + 1) * nvar]);
            }
        }
        all
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
