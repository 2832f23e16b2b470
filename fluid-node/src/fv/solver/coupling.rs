//! What the split sweeps do for a coupled step ([`SplitHooks`]), on one rank or on one slab of
//! a decomposed grid: the halo exchange, ghost states and vacuum written before a sweep, the
//! pressures recorded, and the kept fluxes and pressures gathered on every rank (issue 16).

use crate::fv::comm::{HaloExchange, bytes_f64, f64_bytes};
use crate::fv::euler::NQ;
use crate::fv::solver::FluidSolver;
use crate::fv::solver::cell::cell_primitive;
use crate::fv::solver::hooks::{GhostFill, SplitHooks};
use crate::fv::sweep::{frame, from_local, mirror, to_local};

/// What one rank sends of the hooks' outputs: the pressures of its slots (one list per axis)
/// and its kept fluxes `(slot, flux)` per axis.
#[derive(Default, serde::Serialize, serde::Deserialize)]
struct HookOutputs {
    pressure_start: u64,
    pressures: Vec<Vec<f64>>,
    fluxes: Vec<Vec<(u32, [f64; NQ])>>,
}

impl FluidSolver {
    /// Sends this rank's boundary planes to its neighbours and receives theirs into the halo
    /// (collective between neighbours).
    pub(super) fn exchange_halo(&mut self) {
        let slab = &self.slab;
        let u = &self.state.u;
        let d = self.halo[0].len().max(self.halo[1].len());
        let [lo, hi] = &mut self.halo;
        self.comm.exchange_halo(HaloExchange {
            to_lo: slab.lo.map(|r| (r, &u[..d])),
            to_hi: slab.hi.map(|r| (r, &u[u.len() - d..])),
            from_lo: slab.lo.map(|r| (r, &mut lo[..])),
            from_hi: slab.hi.map(|r| (r, &mut hi[..])),
        });
    }

    /// Sets the cells of `cells` (whole grid) on this rank to vacuum (every conserved
    /// quantity zero).
    pub fn apply_vacuum(&mut self, cells: &[u32]) {
        self.sums_cache = std::sync::OnceLock::new();
        let nvar = self.state.nvar;
        let range = self.slab.global_range();
        for &c in cells {
            if range.contains(&(c as usize)) {
                let c = (c as usize - range.start) * nvar;
                self.state.u[c..c + nvar].fill(0.0);
            }
        }
    }

    /// Writes the ghost states of `fills` (see [`GhostFill`]) on this rank's cells for a sweep
    /// along `axis`. Along the slab axis of a decomposed grid the halo is exchanged first, since
    /// a ghost may mirror a neighbour's cell (collective then).
    pub fn apply_ghosts(&mut self, axis: usize, fills: &[GhostFill]) {
        self.sums_cache = std::sync::OnceLock::new();
        let decomposed = axis == self.slab.axis && self.slab.decomposed();
        if decomposed {
            self.exchange_halo();
        }
        let nvar = self.state.nvar;
        let dim = self.grid.dim;
        let fr = frame(dim, axis);
        let slab = &self.slab;
        let range = slab.global_range();
        let plane = slab.plane();
        let (below, above) = (
            (slab.offset - slab.depth.min(slab.offset)) * plane,
            range.end,
        );
        for g in fills {
            let dst = g.cell as usize;
            if !range.contains(&dst) {
                continue;
            }
            let src = g.mirror_of as usize;
            let cell: &[f64] = if range.contains(&src) {
                let s = (src - range.start) * nvar;
                &self.state.u[s..s + nvar]
            } else {
                // NOTE: a ghost mirrors a cell at most `2 ng − 1` cells away along the sweep,
                // within the `ng + 3` planes of the halo.
                assert!(
                    decomposed
                        && ((below..range.start).contains(&src)
                            || (above..above + slab.depth * plane).contains(&src)),
                    "ghost of cell {dst} mirrors cell {src}, outside rank {}'s cells and halo",
                    slab.rank
                );
                let (halo, first) = if src < range.start {
                    (&self.halo[0], range.start - slab.depth * plane)
                } else {
                    (&self.halo[1], above)
                };
                let s = (src - first) * nvar;
                &halo[s..s + nvar]
            };
            let local = to_local(cell, dim, &fr);
            let ghost = mirror(&local, &g.wall.in_frame(&fr));
            let d = (dst - range.start) * nvar;
            from_local(&ghost, dim, &fr, &mut self.state.u[d..d + nvar]);
        }
    }

    /// `p̄` of this rank's cells of `cells` (whole grid, ascending) into `out` (zero for the
    /// other ranks' cells until [`FluidSolver::gather_hook_outputs`]).
    pub(super) fn record_pressures_at(&mut self, cells: &[u32], out: &mut Vec<f64>) {
        let nvar = self.state.nvar;
        let dim = self.grid.dim;
        let gamma = self.params.gamma;
        let range = self.slab.global_range();
        let lo = cells.partition_point(|&c| (c as usize) < range.start);
        let hi = cells.partition_point(|&c| (c as usize) < range.end);
        self.local.pressure_range = lo..hi;
        out.clear();
        out.resize(cells.len(), 0.0);
        for (k, &c) in cells.iter().enumerate().take(hi).skip(lo) {
            let c = (c as usize - range.start) * nvar;
            out[k] = cell_primitive(&self.state.u[c..c + nvar], dim, gamma).p;
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
        let range = self.local.pressure_range.clone();
        let mine = HookOutputs {
            pressure_start: range.start as u64,
            pressures: (0..3)
                .map(|a| {
                    hooks.pressures[a]
                        .get(range.clone())
                        .map_or_else(Vec::new, <[f64]>::to_vec)
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
        for bytes in &all {
            let part: HookOutputs =
                protocol::codec::decode_blob(bytes).expect("ranks send valid hook outputs");
            let start = part.pressure_start as usize;
            for (a, values) in part.pressures.iter().enumerate() {
                if !values.is_empty() {
                    hooks.pressures[a][start..start + values.len()].copy_from_slice(values);
                }
            }
            for (a, fluxes) in part.fluxes.iter().enumerate() {
                for &(slot, f) in fluxes {
                    hooks.taps[a].flux[slot as usize] = f;
                }
            }
        }
    }

    /// The conserved values (`dim + 2` each) of `cells` (whole grid, ascending), from the ranks
    /// that hold them, on every rank (collective on several ranks).
    pub fn cells_at(&self, cells: &[u32]) -> Vec<f64> {
        debug_assert!(cells.is_sorted());
        let nvar = self.state.nvar;
        let range = self.slab.global_range();
        let lo = cells.partition_point(|&c| (c as usize) < range.start);
        let hi = cells.partition_point(|&c| (c as usize) < range.end);
        let mut mine = Vec::with_capacity((hi - lo) * nvar);
        for &c in &cells[lo..hi] {
            let c = (c as usize - range.start) * nvar;
            mine.extend_from_slice(&self.state.u[c..c + nvar]);
        }
        if self.slab.ranks == 1 || cells.is_empty() {
            return mine;
        }
        // Ranks hold consecutive ranges of cells: rank order is the order of `cells`.
        let all: Vec<f64> = self
            .comm
            .all_gather(&f64_bytes(&mine))
            .iter()
            .flat_map(|b| bytes_f64(b))
            .collect();
        assert_eq!(all.len(), cells.len() * nvar, "every cell on one rank");
        all
    }

    /// Writes `values` (the first `dim + 2` of each) into the cells of the whole grid they
    /// name that lie on this rank, in order (a later write of a cell wins).
    pub fn set_cells(&mut self, values: &[(u32, [f64; NQ])]) {
        let nvar = self.state.nvar;
        let range = self.slab.global_range();
        for (c, v) in values {
            if range.contains(&(*c as usize)) {
                let c = (*c as usize - range.start) * nvar;
                self.state.u[c..c + nvar].copy_from_slice(&v[..nvar]);
            }
        }
        self.dt_cache = std::sync::OnceLock::new();
        self.sums_cache = std::sync::OnceLock::new();
    }
}
