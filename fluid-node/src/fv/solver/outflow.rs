//! What left through the domain faces in one sweep, summed in the one-rank order: on one rank
//! or slabs each rank sums its pencils; with blocks cut across the sweep's planes the pencils'
//! ends are gathered on rank 0, which sums them as one rank does (issue 40).

use rayon::prelude::*;

use crate::fv::euler::NQ;
use crate::fv::solver::FluidSolver;
use crate::fv::state::BoundaryKind;
use crate::fv::sweep::Pencils;
use crate::grid::Grid;

/// Outflow partial sums `area × flux` of a sweep along `axis` over the pencils of `grid`, each
/// a sum in pencil order: along the last axis one per side in `sides`; along another axis one
/// per plane of the last axis, of both ends of each pencil. `out(p)` is pencil `p`'s outflow
/// per side, `ends(p, side)` whether that end counts (its cell is gas).
pub(super) fn partials(
    grid: &Grid,
    axis: usize,
    area: f64,
    sides: [bool; 2],
    out: &(dyn Fn(usize) -> [[f64; NQ]; 2] + Sync),
    ends: &(dyn Fn(usize, usize) -> bool + Sync),
) -> Vec<[f64; NQ]> {
    let count = grid.n_cells() / grid.cells[axis];
    let last = grid.dim - 1;
    let mut partials = Vec::new();
    if axis == last {
        for side in (0..2).filter(|&s| sides[s]) {
            let mut acc = [0.0; NQ];
            for p in (0..count).filter(|&p| ends(p, side)) {
                let o = out(p)[side];
                for q in 0..NQ {
                    acc[q] += area * o[q];
                }
            }
            partials.push(acc);
        }
        return partials;
    }
    // NOTE: each plane's sum is its own, in pencil order, so the planes are summed in parallel
    // on the pool the call runs in (the same sums on any number of threads): on one thread,
    // while the other waited, these sums were most of the 0.2-0.3 ms between two sweeps of
    // the 128³ blast on 2 threads.
    let per_plane = count / grid.cells[last];
    (0..grid.cells[last])
        .into_par_iter()
        .with_max_len(super::items_per_task(per_plane))
        .map(|i| {
            let mut acc = [0.0; NQ];
            for p in i * per_plane..(i + 1) * per_plane {
                let o = out(p);
                let ends = [ends(p, 0), ends(p, 1)];
                for q in 0..NQ {
                    let out = |side: usize| if ends[side] { o[side][q] } else { 0.0 };
                    acc[q] += area * (out(0) + out(1));
                }
            }
            acc
        })
        .collect()
}

/// One end of a pencil at a domain face, as a block sends it: the global pencil, the side,
/// whether it counts, and its outflow.
type End = (u32, u8, bool, [f64; NQ]);

impl FluidSolver {
    /// This rank's outflow partials of the sweep along `axis` (`ends(p, side)` for its pencils):
    /// its own pencils' sums on one rank and with slabs; with blocks the whole grid's sums on
    /// rank 0 and none elsewhere (collective then).
    pub(super) fn outflow_partials(
        &self,
        axis: usize,
        area: f64,
        ends: &(dyn Fn(usize, usize) -> bool + Sync),
    ) -> Vec<[f64; NQ]> {
        let slab = &self.slab;
        let bc = self.params.boundary[axis];
        let reps = &self.pencil_out;
        if slab.slabs() {
            let sides = [
                bc[0] != BoundaryKind::Periodic && slab.lo[axis].is_none(),
                bc[1] != BoundaryKind::Periodic && slab.hi[axis].is_none(),
            ];
            let (grid, out) = (&self.grid, |p: usize| reps[p].outflow);
            return self.install(|| partials(grid, axis, area, sides, &out, ends));
        }
        let count = self.grid.n_cells() / self.grid.cells[axis];
        let at_face = [
            slab.coords[axis] == 0,
            slab.coords[axis] + 1 == slab.dims[axis],
        ];
        let mut mine: Vec<End> = Vec::new();
        for side in (0..2).filter(|&s| at_face[s] && bc[s] != BoundaryKind::Periodic) {
            for (p, rep) in reps[..count].iter().enumerate() {
                let gp = slab.global_pencil(axis, p) as u32;
                mine.push((gp, side as u8, ends(p, side), rep.outflow[side]));
            }
        }
        let Some(parts) = self.comm.gather(0, &protocol::codec::encode_blob(&mine)) else {
            return Vec::new();
        };
        let global = &slab.global;
        let n = Pencils::new(global, axis).count;
        let mut out = vec![[[0.0; NQ]; 2]; n];
        let mut counts = vec![[false; 2]; n];
        for bytes in &parts {
            let ends: Vec<End> =
                protocol::codec::decode_blob(bytes).expect("ranks send valid pencil ends");
            for (gp, side, counted, o) in ends {
                out[gp as usize][side as usize] = o;
                counts[gp as usize][side as usize] = counted;
            }
        }
        let sides = bc.map(|b| b != BoundaryKind::Periodic);
        let (out, ends) = (|p: usize| out[p], |p: usize, s: usize| counts[p][s]);
        self.install(|| partials(global, axis, area, sides, &out, &ends))
    }
}
