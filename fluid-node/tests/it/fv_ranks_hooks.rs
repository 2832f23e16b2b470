//! Issue 40 item 1: what a coupled predict (`FluidSolver::predict` with `SplitHooks`) leaves on
//! each rank of a decomposed grid. A rank no longer receives every rank's kept fluxes and
//! pressures: it keeps the pressures of its own cells and the fluxes of every face of its own
//! cells, those on its block's high sides coming from the block above. This pins, as bits
//! against one rank, exactly those on every rank of slabs and blocks, 2-D and 3-D, over steps
//! that visit every sweep order; the coupled `fv_ranks` tests pin what the embedded solid
//! computes from them.

use fluid_node::fv::{BoundaryKind, FaceTap, FluidParams, FluidSolver, FluidState, SplitHooks};
use fluid_node::grid::Grid;

use crate::fv_ranks::{blast, on_thread_ranks, params};

/// What one rank holds after each step: whether it owns each recorded cell, and the hooks'
/// pressures and kept fluxes.
struct RankOutputs {
    own: Vec<bool>,
    steps: Vec<SplitHooks>,
}

/// The faces of `cells` (both sides along each axis) as the taps of a coupled step: per axis,
/// grouped by pencil, ascending.
fn taps_of(grid: &Grid, cells: &[u32]) -> [FaceTap; 3] {
    let mut taps: [FaceTap; 3] = Default::default();
    for (axis, tap) in taps.iter_mut().enumerate().take(grid.dim) {
        let stride: usize = grid.cells[..axis].iter().product();
        let n = grid.cells[axis];
        let count = grid.n_cells() / n;
        let mut keys: Vec<(usize, usize)> = Vec::new();
        for &c in cells {
            let c = c as usize;
            let (m, p) = ((c / stride) % n, c % stride + (c / (stride * n)) * stride);
            keys.extend([(p, m), (p, m + 1)]);
        }
        keys.sort_unstable();
        keys.dedup();
        tap.clear(count);
        for &(p, m) in &keys {
            tap.pencil_offsets[p + 1] += 1;
            tap.positions.push(m as u32);
        }
        for p in 0..count {
            tap.pencil_offsets[p + 1] += tap.pencil_offsets[p];
        }
    }
    taps
}

/// The kept flux of face `m` of pencil `p` along `axis`.
fn flux_at(tap: &FaceTap, p: usize, m: usize) -> [f64; 5] {
    let (lo, hi) = (
        tap.pencil_offsets[p] as usize,
        tap.pencil_offsets[p + 1] as usize,
    );
    let k = tap.positions[lo..hi]
        .binary_search(&(m as u32))
        .expect("a kept face");
    tap.flux[lo + k]
}

/// `steps` CFL steps of a coupled predict (no ghosts, nothing covered) recording `cells` and
/// the faces of each, on the thread ranks of process grid `dims` (`None`: one rank).
fn outputs(
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    cells: &[u32],
    dims: Option<[usize; 3]>,
    steps: usize,
) -> Vec<RankOutputs> {
    let ranks = dims.map_or(1, |d| d.iter().product());
    on_thread_ranks(ranks, |comm| {
        let (state, params) = (state.clone(), params.clone());
        let cells = cells.to_vec();
        let mut s =
            FluidSolver::decomposed_as(grid.clone(), params, state, 1, Box::new(comm), dims)
                .expect("solver");
        let own = (cells.iter())
            .map(|&c| s.slab().to_local(c as usize).is_some())
            .collect();
        let mut out = RankOutputs {
            own,
            steps: Vec::new(),
        };
        for _ in 0..steps {
            let mut hooks = SplitHooks {
                pressure_cells: cells.clone(),
                taps: taps_of(grid, &cells),
                ..SplitHooks::default()
            };
            let dt = s.max_dt();
            let report = s.predict(dt, &mut hooks, &|_| false);
            assert!(report.ok(), "{:?}", report.troubles);
            out.steps.push(hooks);
        }
        out
    })
}

/// Every rank of each process grid of `decomps` holds one rank's pressures of its own cells
/// among `cells`, and one rank's fluxes of both faces of each of them along every axis, as bits.
fn assert_own_outputs_are_one_ranks(
    name: &str,
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    cells: &[u32],
    decomps: &[[usize; 3]],
) {
    let steps = 2 * grid.dim;
    let one = outputs(grid, state, params, cells, None, steps);
    let one = &one[0];
    for &dims in decomps {
        let many = outputs(grid, state, params, cells, Some(dims), steps);
        for (rank, r) in many.iter().enumerate() {
            assert!(
                r.own.iter().any(|&o| o),
                "{name} {dims:?}: rank {rank} owns cells"
            );
            for (step, (h1, hk)) in one.steps.iter().zip(&r.steps).enumerate() {
                let at = format!("{name} {dims:?}, rank {rank}, step {step}");
                for (k, &c) in cells.iter().enumerate() {
                    if !r.own[k] {
                        continue;
                    }
                    for axis in 0..grid.dim {
                        assert_eq!(
                            h1.pressures[axis][k].to_bits(),
                            hk.pressures[axis][k].to_bits(),
                            "{at}: pressure of cell {c} along {axis}"
                        );
                        let stride: usize = grid.cells[..axis].iter().product();
                        let n = grid.cells[axis];
                        let c = c as usize;
                        let (m, p) = ((c / stride) % n, c % stride + (c / (stride * n)) * stride);
                        for face in [m, m + 1] {
                            let (f1, fk) = (
                                flux_at(&h1.taps[axis], p, face),
                                flux_at(&hk.taps[axis], p, face),
                            );
                            assert_eq!(
                                f1.map(f64::to_bits),
                                fk.map(f64::to_bits),
                                "{at}: flux of face {face} of cell {c} along {axis}"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// Every third cell, so that cells lie on both sides of every cut and on every block's edges.
fn every_third_cell(grid: &Grid) -> Vec<u32> {
    (0..grid.n_cells() as u32).filter(|c| c % 3 == 0).collect()
}

#[test]
fn each_rank_keeps_one_ranks_fluxes_of_its_cells_faces_and_pressures_of_its_cells_3d() {
    let (grid, state) = blast(&[12, 18, 28]);
    let cells = every_third_cell(&grid);
    let walls = [[BoundaryKind::Wall; 2]; 3];
    assert_own_outputs_are_one_ranks(
        "3-D",
        &grid,
        &state,
        &params(5, walls),
        &cells,
        &[[1, 1, 2], [1, 2, 1], [1, 1, 3], [1, 2, 2], [1, 2, 4]],
    );
    let periodic = [
        [BoundaryKind::Wall; 2],
        [BoundaryKind::Periodic; 2],
        [BoundaryKind::Periodic; 2],
    ];
    assert_own_outputs_are_one_ranks(
        "3-D periodic",
        &grid,
        &state,
        &params(5, periodic),
        &cells,
        &[[1, 2, 2], [1, 1, 4]],
    );
}

#[test]
fn each_rank_keeps_one_ranks_fluxes_of_its_cells_faces_and_pressures_of_its_cells_2d() {
    let (grid, state) = blast(&[40, 33]);
    let cells = every_third_cell(&grid);
    let b = [
        [BoundaryKind::Wall, BoundaryKind::Outflow],
        [BoundaryKind::Outflow, BoundaryKind::Wall],
        [BoundaryKind::Wall; 2],
    ];
    assert_own_outputs_are_one_ranks(
        "2-D",
        &grid,
        &state,
        &params(7, b),
        &cells,
        &[[2, 1, 1], [1, 4, 1], [2, 2, 1], [3, 1, 1], [2, 4, 1]],
    );
}
