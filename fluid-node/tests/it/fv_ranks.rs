//! Issue 16: the grid decomposed into slabs over K ranks gives the bits of one rank. The ranks
//! here are threads joined by channels (`fluid_node::ranks::threads`), so the decomposition
//! itself (halo depth, the neighbours' extra cells for the positivity fix, the fixed-order sums,
//! the CFL reduction, troubles named by their global cell, gathered checkpoints, and the
//! embedded solid with its wet surface across the cuts) is pinned without an MPI library;
//! `tests/it/issue_16_mpi.rs` runs the same through MPI processes.

use fluid_node::embedded::{Embedded, NEAR_RADIUS, SolidFrame};
use fluid_node::fv::{BoundaryKind, FluidParams, FluidSolver, FluidState, FluxKind, StepReport};
use fluid_node::grid::Grid;
use fluid_node::ranks::threads::{ThreadComm, ThreadRanks};

use crate::embedded_support;
use crate::fv_common;

/// `f` on each of `ranks` connected thread ranks, one thread each; the results in rank order.
pub(crate) fn on_thread_ranks<T: Send>(ranks: usize, f: impl Fn(ThreadComm) -> T + Sync) -> Vec<T> {
    std::thread::scope(|scope| {
        let f = &f;
        let handles: Vec<_> = ThreadRanks::new(ranks)
            .into_iter()
            .map(|comm| scope.spawn(move || f(comm)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("rank thread"))
            .collect()
    })
}

/// The 2-D process grids (`[kx, ky, 1]`) the block tests run on: slabs along each axis, a
/// split in three, and blocks.
pub(crate) const PROCESS_GRIDS_2D: [[usize; 3]; 6] = [
    [1, 2, 1],
    [1, 4, 1],
    [2, 2, 1],
    [3, 1, 1],
    [2, 4, 1],
    [1, 3, 1],
];

/// The 3-D process grids the block tests run on (x is never cut in 3-D).
pub(crate) const PROCESS_GRIDS_3D: [[usize; 3]; 6] = [
    [1, 1, 2],
    [1, 1, 4],
    [1, 2, 2],
    [1, 2, 1],
    [1, 1, 3],
    [1, 2, 4],
];

/// A blast off-centre with a swirl on `cells`: the ball sits across the middle of the last
/// axis, where 2 and 4 ranks cut it.
pub(crate) fn blast(cells: &[usize]) -> (Grid, FluidState) {
    fv_common::blast_state(cells, 0.47)
}

pub(crate) fn params(order: u32, boundary: [[BoundaryKind; 2]; 3]) -> FluidParams {
    FluidParams {
        gamma: 1.4,
        cfl: 0.5,
        flux: FluxKind::Osmp(order),
        boundary,
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
    }
}

/// What rank 0 sees after the steps: every report, the gathered state and checkpoint, the
/// totals, all as bits.
#[derive(Debug, PartialEq)]
pub(crate) struct Run {
    pub(crate) reports: Vec<String>,
    pub(crate) state: Vec<u64>,
    totals: String,
    pub(crate) checkpoint: Vec<u8>,
    limiting_cell: usize,
}

/// `steps` CFL steps of `(grid, state)` on `ranks` thread ranks (2 rayon threads each), cut
/// as `protocol::decomp::choose` cuts it.
pub(crate) fn run(
    ranks: usize,
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    steps: usize,
    restore: Option<&[u8]>,
) -> Run {
    run_on(ranks, None, grid, state, params, steps, restore)
}

/// [`run`] with the process grid `dims` (`None`: the chosen one).
pub(crate) fn run_on(
    ranks: usize,
    dims: Option<[usize; 3]>,
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    steps: usize,
    restore: Option<&[u8]>,
) -> Run {
    let mut runs: Vec<Option<Run>> = on_thread_ranks(ranks, |comm| {
        let (grid, state, params) = (grid.clone(), state.clone(), params.clone());
        let mut s = FluidSolver::decomposed_as(grid, params, state, 2, Box::new(comm), dims)
            .expect("solver");
        if let Some(bytes) = restore {
            s.restore_checkpoint(bytes).expect("restores");
        }
        let mut reports = Vec::new();
        for _ in 0..steps {
            let dt = s.max_dt();
            let report = s.advance(dt);
            assert!(report.ok(), "{:?}", report.troubles);
            reports.push(bits(&report));
        }
        let limiting_cell = s.limiting_cell();
        let totals = format!("{:?}", s.totals());
        let state = s
            .gather_state()
            .map(|g| g.u.iter().map(|x| x.to_bits()).collect());
        let checkpoint = s.to_checkpoint();
        state.map(|state| Run {
            reports,
            state,
            totals,
            checkpoint,
            limiting_cell,
        })
    });
    assert!(runs[1..].iter().all(Option::is_none), "only rank 0 gathers");
    runs[0].take().expect("rank 0 gathers")
}

/// A report with every float as its bits (`{:?}` of f64 round-trips, so equal text is equal bits).
fn bits(r: &StepReport) -> String {
    format!("{r:?}")
}

fn assert_same_for_ranks(
    name: &str,
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    steps: usize,
    ranks: &[usize],
) {
    let decomps: Vec<_> = ranks.iter().map(|&k| (k, None)).collect();
    assert_same_on(name, grid, state, params, steps, &decomps);
}

/// [`assert_same_for_ranks`] on `(ranks, process grid)` pairs.
pub(crate) fn assert_same_on(
    name: &str,
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    steps: usize,
    decomps: &[(usize, Option<[usize; 3]>)],
) {
    let one = run(1, grid, state, params, steps, None);
    for &(k, dims) in decomps {
        let many = run_on(k, dims, grid, state, params, steps, None);
        let k = format!("{k} {dims:?}");
        assert_eq!(
            one.reports, many.reports,
            "{name}: reports of 1 and {k} ranks"
        );
        assert!(
            one.state == many.state,
            "{name}: state of 1 and {k} ranks differs"
        );
        assert_eq!(one.totals, many.totals, "{name}: totals of 1 and {k} ranks");
        assert!(
            one.checkpoint == many.checkpoint,
            "{name}: checkpoints of 1 and {k} ranks"
        );
        assert_eq!(one.limiting_cell, many.limiting_cell, "{name}");
    }
}

#[test]
fn blast_3d_walls_is_bit_identical_on_1_2_and_4_ranks() {
    let (grid, state) = blast(&[20, 18, 28]);
    let walls = [[BoundaryKind::Wall; 2]; 3];
    // Six steps: every sweep permutation, so each axis is swept first, between and last.
    for order in [5, 7] {
        assert_same_for_ranks(
            &format!("osmp{order} walls"),
            &grid,
            &state,
            &params(order, walls),
            6,
            &[2, 4],
        );
    }
}

#[test]
fn periodic_outflow_and_characteristic_sides_are_bit_identical() {
    let (grid, state) = blast(&[16, 16, 24]);
    let periodic = [[BoundaryKind::Periodic; 2]; 3];
    // Two ranks: each is the other's neighbour on both sides.
    assert_same_for_ranks("periodic", &grid, &state, &params(5, periodic), 4, &[2, 3]);
    let characteristic = BoundaryKind::Characteristic {
        p_far: 1.0,
        sigma: 0.25,
    };
    let open = [
        [BoundaryKind::Outflow, BoundaryKind::Wall],
        [BoundaryKind::Wall, BoundaryKind::Outflow],
        [BoundaryKind::Outflow, characteristic],
    ];
    assert_same_for_ranks("open", &grid, &state, &params(3, open), 6, &[2, 4]);
}

#[test]
fn two_and_one_dimensional_grids_are_bit_identical() {
    let (grid, state) = blast(&[40, 33]);
    let b = [
        [BoundaryKind::Wall, BoundaryKind::Outflow],
        [BoundaryKind::Outflow, BoundaryKind::Wall],
        [BoundaryKind::Wall; 2],
    ];
    assert_same_for_ranks("2-D", &grid, &state, &params(7, b), 6, &[2, 4]);
    let (grid, state) = blast(&[101]);
    assert_same_for_ranks("1-D", &grid, &state, &params(5, b), 8, &[4]);
}

/// Toro's test 3 (p ratio 1e5) and the 123 problem with the discontinuity on the cut between
/// two ranks: the HLLE fallback and the positivity fix act on the cells beside the cut, and
/// the counters and states still match one rank.
#[test]
fn fixes_at_a_rank_boundary_are_those_of_one_rank() {
    let grid = Grid::new(&[0.0], &[1.0], &[64]).expect("grid");
    let mut exercised = Vec::new();
    for (left, right) in [
        ((1.0, 0.0, 1000.0), (1.0, 0.0, 0.01)),
        ((1.0, -2.0, 0.4), (1.0, 2.0, 0.4)),
        ((1.0, -19.6, 1e-6), (1.0, 19.6, 1e-6)),
        ((1.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
        ((1.0, 200.0, 1e-6), (1e-3, -200.0, 1e-6)),
        ((1e3, 0.0, 1e5), (1e-6, 0.0, 1e-9)),
    ] {
        let mut state = FluidState::zeros(1, 64);
        for i in 0..64 {
            let (rho, u, p) = if i < 32 { left } else { right };
            state.set_primitive(i, rho, [u, 0.0, 0.0], p, 1.4);
        }
        let outflow = [[BoundaryKind::Outflow; 2]; 3];
        let p = params(7, outflow);
        let one = run(1, &grid, &state, &p, 12, None);
        let count = |key: &str| {
            one.reports
                .iter()
                .filter(|r| !r.contains(&format!("{key}: 0,")))
                .count()
        };
        let used = [
            count("hlle_faces"),
            count("positivity_fixes"),
            count("lax_friedrichs_faces"),
        ];
        eprintln!("{left:?} | {right:?}: steps with hlle, fixes, lf {used:?}");
        exercised.push(used);
        for k in [2, 4] {
            let many = run(k, &grid, &state, &p, 12, None);
            assert_eq!(one, many, "{left:?} | {right:?} on {k} ranks");
        }
    }
    for kind in 0..3 {
        assert!(
            exercised.iter().any(|used| used[kind] > 0),
            "fallback {kind} exercised: {exercised:?}"
        );
    }
}

#[test]
fn a_checkpoint_of_2_ranks_restores_on_2_and_4_ranks_and_continues_the_same() {
    let (grid, state) = blast(&[16, 16, 24]);
    let p = params(5, [[BoundaryKind::Wall; 2]; 3]);
    let straight = run(1, &grid, &state, &p, 5, None);
    let first = run(2, &grid, &state, &p, 2, None);
    for k in [2, 4] {
        let rest = run(k, &grid, &state, &p, 3, Some(&first.checkpoint));
        assert!(rest.state == straight.state, "restored on {k} ranks");
        assert_eq!(
            rest.reports[..],
            straight.reports[2..],
            "restored on {k} ranks"
        );
    }
}

/// A negative pressure in cell (3, 5, 17), on rank 1 of 2 (the CFL step reads it as silent
/// gas): the sweeps leave it bad, and every rank reports the troubles one rank does, naming
/// the global cells.
#[test]
fn trouble_on_rank_1_names_its_global_cell() {
    let (grid, mut state) = blast(&[12, 12, 24]);
    let bad = grid.index(3, 5, 17);
    state.set_primitive(bad, 1.4, [0.0; 3], -5.0, 1.4);
    let p = params(5, [[BoundaryKind::Wall; 2]; 3]);
    let out: Vec<(String, Option<[usize; 3]>)> = ThreadRanks::new(2)
        .into_iter()
        .map(|comm| {
            let (grid, state, p) = (grid.clone(), state.clone(), p.clone());
            std::thread::spawn(move || {
                let mut s =
                    FluidSolver::decomposed(grid, p, state, 1, Box::new(comm)).expect("solver");
                let own = s.check_state().map(|t| t.cell);
                let dt = s.max_dt();
                (bits(&s.advance(dt)), own)
            })
        })
        .collect::<Vec<_>>()
        .into_iter()
        .map(|h| h.join().expect("rank"))
        .collect();
    let mut one = FluidSolver::new(grid.clone(), p, state, 1).expect("solver");
    let report = one.advance(one.max_dt());
    assert!(!report.ok(), "the bad cell is reported");
    let t = &report.troubles[0];
    assert!(report.refused.is_none(), "{report:?}");
    assert!(t.cell[2] >= 12, "{t:?} lies on rank 1");
    for (rank, (report_bits, _)) in out.iter().enumerate() {
        assert_eq!(
            *report_bits,
            bits(&report),
            "rank {rank} reports what one rank does"
        );
    }
    assert_eq!(out[0].1, None, "rank 0's planes are clean");
    assert_eq!(out[1].1, Some([3, 5, 17]), "rank 1 names the global cell");
}

#[test]
fn too_many_ranks_for_the_halo_is_refused() {
    let (grid, state) = blast(&[8, 8, 24]);
    let p = params(7, [[BoundaryKind::Wall; 2]; 3]);
    let errs: Vec<String> = ThreadRanks::new(4)
        .into_iter()
        .map(|comm| {
            FluidSolver::decomposed(grid.clone(), p.clone(), state.clone(), 1, Box::new(comm))
                .err()
                .expect("refused")
                .to_string()
        })
        .collect();
    assert!(errs[0].contains("fluid.ranks = 4"), "{}", errs[0]);
    assert!(
        errs[0].contains("7 cells along each cut axis"),
        "{}",
        errs[0]
    );
}

/// Several rigid bodies as the particles of one frame.
pub(crate) fn bodies(frames: &[SolidFrame]) -> SolidFrame {
    let mut all = SolidFrame {
        dim: frames[0].dim,
        ..SolidFrame::default()
    };
    for f in frames {
        let first = (all.vertices.len() / f.dim) as u32;
        let particles = all.n_particles() as u32;
        all.position.extend_from_slice(&f.position);
        all.velocity.extend_from_slice(&f.velocity);
        all.angular_velocity.extend_from_slice(&f.angular_velocity);
        all.vertices.extend_from_slice(&f.vertices);
        all.elements.extend(f.elements.iter().map(|v| v + first));
        all.element_particle
            .extend(f.element_particle.iter().map(|p| p + particles));
        all.wet.extend_from_slice(&f.wet);
    }
    all
}

/// What rank 0 sees of a coupled run: per step the predict report, the loads on `F^n` and on
/// the trial `F^{n+1}`, the correct's report, the fluid totals and the interface budget (as
/// `{:?}` text, which round-trips every f64), and the gathered state's bits at the end.
#[derive(Debug, PartialEq)]
struct CoupledRun {
    steps: Vec<String>,
    state: Vec<u64>,
    mixed: usize,
    uncovered: usize,
    /// Steps that mixed cells and merged or widened no group (the mixing by root takes them).
    unmerged: usize,
}

/// `steps` coupled steps of the bodies `solid` moving at their velocities through the blast of
/// `(grid, state)`, on `ranks` thread ranks; odd steps take the explicit scheme's solid flux.
/// `jump`: the accepted surface of each step is moved `jump` cells (`jump` times the
/// one-cell step at its velocity) instead of its velocity times the fluid's step. `by_root`:
/// the mixing's groups by their roots' ranks (`Embedded::set_mixing_by_root`, on by default).
#[allow(clippy::too_many_arguments)]
fn coupled_run(
    dims: [usize; 3],
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    solid: &SolidFrame,
    steps: u64,
    jump: Option<f64>,
    by_root: bool,
) -> CoupledRun {
    let ranks = dims.iter().product();
    let mut runs: Vec<Option<CoupledRun>> = on_thread_ranks(ranks, |comm| {
        let (grid, state, params) = (grid.clone(), state.clone(), params.clone());
        let dims = (ranks > 1).then_some(dims);
        let mut s = FluidSolver::decomposed_as(grid, params, state, 2, Box::new(comm), dims)
            .expect("solver");
        let mut e = Embedded::new(&s, solid.clone()).expect("embedded");
        e.set_mixing_by_root(by_root);
        let mut out = Vec::new();
        let (mut mixed, mut uncovered, mut unmerged) = (0, 0, 0);
        for n in 0..steps {
            let dt = s.max_dt().min(0.5 * e.one_cell_dt());
            let predicted = e.predict(&mut s, dt);
            assert!(predicted.ok(), "step {n}: {:?}", predicted.troubles);
            let current = e.surface().clone();
            let moved = jump.map_or(dt, |j| j * e.one_cell_dt());
            let next = embedded_support::translated(&current, moved);
            let on_current = e.loads(&s, &current).expect("loads on F^n");
            let on_next = e.loads(&s, &next).expect("loads on the trial");
            let report = e
                .correct(&mut s, dt, next, n, n % 2 == 1)
                .unwrap_or_else(|err| panic!("step {n}: {err}"));
            mixed += report.mixed_cells;
            uncovered += report.uncovered_cells;
            if report.mixed_cells > 0 && report.merged_groups + report.widened_groups == 0 {
                unmerged += 1;
            }
            out.push(format!(
                "{predicted:?} {on_current:?} {on_next:?} {report:?} {:?} {:?} {:?}",
                e.totals(&s),
                e.budget(),
                e.last_loads()
            ));
        }
        let state = s
            .gather_state()
            .map(|g| g.u.iter().map(|x| x.to_bits()).collect());
        state.map(|state| CoupledRun {
            steps: out,
            state,
            mixed,
            uncovered,
            unmerged,
        })
    });
    runs[0].take().expect("rank 0 gathers")
}

pub(crate) fn assert_coupled_same_for_ranks(
    name: &str,
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    solid: &SolidFrame,
    steps: u64,
    decomps: &[[usize; 3]],
) {
    assert_jumping_same_for_ranks(name, grid, state, params, solid, steps, None, decomps);
}

/// [`assert_coupled_same_for_ranks`] with the accepted surface moved `jump` cells per step
/// (see [`coupled_run`]).
#[allow(clippy::too_many_arguments)]
fn assert_jumping_same_for_ranks(
    name: &str,
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    solid: &SolidFrame,
    steps: u64,
    jump: Option<f64>,
    decomps: &[[usize; 3]],
) {
    let one = coupled_run([1; 3], grid, state, params, solid, steps, jump, true);
    eprintln!(
        "{name}: {} cells mixed, {} uncovered over {steps} steps",
        one.mixed, one.uncovered
    );
    assert!(one.mixed > 0 && one.uncovered > 0, "{name}: mixing happens");
    for &k in decomps {
        let many = coupled_run(k, grid, state, params, solid, steps, jump, true);
        for (n, (a, b)) in one.steps.iter().zip(&many.steps).enumerate() {
            assert_eq!(a, b, "{name}: step {n} on 1 rank and {k:?}");
        }
        assert!(
            one.state == many.state,
            "{name}: state of 1 rank and {k:?} differs"
        );
    }
}

/// A one-rank solver of `grid` with walls on every side and a zero state: what the geometry of a
/// body on `grid` needs.
fn walls_solver(grid: &Grid) -> FluidSolver {
    FluidSolver::new(
        grid.clone(),
        params(5, [[BoundaryKind::Wall; 2]; 3]),
        FluidState::zeros(grid.dim, grid.n_cells()),
        1,
    )
    .expect("solver")
}

/// Covered cells (Λ = 1) of `solid` on both sides of the plane `cut` of the last axis, in one
/// pencil along it: a wall run across the cut.
pub(crate) fn covers_across(grid: &Grid, solid: &SolidFrame, cut: usize) -> bool {
    let s = walls_solver(grid);
    let e = Embedded::new(&s, solid.clone()).expect("embedded");
    let lambda = e.solid_fraction();
    let axis = grid.dim - 1;
    (0..grid.n_cells()).any(|c| {
        let ijk = grid.ijk(c);
        let mut up = ijk;
        up[axis] = cut;
        let mut down = ijk;
        down[axis] = cut - 1;
        ijk[axis] == 0
            && lambda[grid.index(up[0], up[1], up[2])] == 1.0
            && lambda[grid.index(down[0], down[1], down[2])] == 1.0
    })
}

/// Whether `solid` moved `jump` cells (as [`coupled_run`] moves it) puts solid into a cell of
/// plane `cut − 1` along `axis` whose neighbour in plane `cut` is no near cell of `solid`
/// (farther than `NEAR_RADIUS` from each of its cut cells): a cell the correct updates below a
/// block boundary, across which the block above holds no near cell.
fn jumps_past_the_near_cells(
    grid: &Grid,
    solid: &SolidFrame,
    jump: f64,
    axis: usize,
    cut: usize,
) -> bool {
    let s = walls_solver(grid);
    let before = Embedded::new(&s, solid.clone()).expect("embedded");
    let moved = embedded_support::translated(solid, jump * before.one_cell_dt());
    let after = Embedded::new(&s, moved).expect("embedded");
    let cut_cells: Vec<[usize; 3]> = (before.geometry().cut_cells.iter())
        .map(|&c| grid.ijk(c as usize))
        .collect();
    let near = |ijk: [usize; 3]| {
        cut_cells
            .iter()
            .any(|q| (0..3).all(|a| q[a].abs_diff(ijk[a]) <= NEAR_RADIUS))
    };
    (0..grid.n_cells()).any(|c| {
        let ijk = grid.ijk(c);
        let mut up = ijk;
        up[axis] = cut;
        ijk[axis] == cut - 1 && after.solid_fraction()[c] > 0.0 && near(ijk) && !near(up)
    })
}

/// Issue 40 item 1, step 2 (the taps by block): a rank keeps the faces of its own near cells and,
/// along a cut axis, the face on its block's low side of each near cell just below it, whose flux
/// it computes (the face is its own) and sends to the block below. That second rule matters when
/// the cell across the face is no near cell, so that the block above would not keep the face for
/// its own cells: here plates jump 1.6 cells in one step towards the cuts (up along each cut axis,
/// their top rows two cells below a cut), so that the correct updates cells just below the cuts
/// whose neighbours above are no near cells. Every step's reports, loads, totals and the final
/// state are one rank's, 2-D and 3-D, on slabs and blocks (without that rule the block below
/// reads 0 for those faces).
#[test]
fn a_surface_jumping_towards_a_cut_is_bit_identical_on_slabs_and_blocks() {
    let jump = 1.6;
    // 2-D, 40 × 48: the top at y = 21.5 cells (the cut at 24), the right side at x = 17.5 cells
    // (the cut at 20), moving as many cells along both.
    let (grid, state) = blast(&[40, 48]);
    let plate = embedded_support::polygon_2d(
        &[
            [0.2, 0.3],
            [17.5 / 40.0, 0.3],
            [17.5 / 40.0, 21.5 / 48.0],
            [0.2, 21.5 / 48.0],
        ],
        [0.4, 0.4 * 40.0 / 48.0],
        0.0,
    );
    assert!(jumps_past_the_near_cells(&grid, &plate, jump, 1, 24));
    assert!(jumps_past_the_near_cells(&grid, &plate, jump, 0, 20));
    assert_jumping_same_for_ranks(
        "2-D jump",
        &grid,
        &state,
        &params(5, [[BoundaryKind::Wall; 2]; 3]),
        &plate,
        3,
        Some(jump),
        &[[1, 2, 1], [2, 1, 1], [2, 2, 1], [2, 4, 1]],
    );
    // 3-D, 16 × 16 × 24: the top at y = 5.5 cells (the cut at 8) and z = 9.5 cells (the cut at
    // 12).
    let (grid, state) = blast(&[16, 16, 24]);
    let flat = embedded_support::rotation([1.0, 0.0, 0.0], 0.0);
    let plate = embedded_support::box_3d(
        [0.5, 4.0 / 16.0, 7.0 / 24.0],
        [0.2, 1.5 / 16.0, 2.5 / 24.0],
        flat,
        [0.0, 0.4, 0.4 * 16.0 / 24.0],
    );
    assert!(jumps_past_the_near_cells(&grid, &plate, jump, 1, 8));
    assert!(jumps_past_the_near_cells(&grid, &plate, jump, 2, 12));
    assert_jumping_same_for_ranks(
        "3-D jump",
        &grid,
        &state,
        &params(5, [[BoundaryKind::Wall; 2]; 3]),
        &plate,
        3,
        Some(jump),
        &[[1, 1, 2], [1, 2, 1], [1, 2, 2]],
    );
}

/// Issue 16 item 3 in 2-D: a tilted block and a plate two cells thick (a wall run that cuts
/// the pencils along y) lie across the cut between ranks and move through it, so that the
/// cut cells, swept amounts, ghost states, wall runs and mixing meet the cut; every step's
/// reports, loads and totals and the final state are those of one rank. Issue 40: the same on
/// blocks (2 × 2, 3 × 1, 2 × 4: cuts along x through the block and the plates as well).
#[test]
fn a_moving_body_across_the_cuts_2d_is_bit_identical_on_slabs_and_blocks() {
    let (grid, state) = blast(&[40, 48]);
    let solid = moving_bodies_2d();
    assert!(covers_across(&grid, &solid, 24), "the plate covers the cut");
    let walls = [[BoundaryKind::Wall; 2]; 3];
    for order in [5, 7] {
        assert_coupled_same_for_ranks(
            &format!("2-D osmp{order}"),
            &grid,
            &state,
            &params(order, walls),
            &solid,
            10,
            &[[1, 2, 1], [1, 4, 1], [2, 2, 1], [3, 1, 1], [2, 4, 1]],
        );
    }
    // Periodic along y, with a plate on planes 1–2 beside the seam between the last rank and
    // rank 0 (each the other's neighbour there).
    let solid = bodies(&[solid, seam_plate_2d()]);
    let periodic = [
        [BoundaryKind::Wall; 2],
        [BoundaryKind::Periodic; 2],
        [BoundaryKind::Wall; 2],
    ];
    assert_coupled_same_for_ranks(
        "2-D periodic",
        &grid,
        &state,
        &params(5, periodic),
        &solid,
        10,
        &[[1, 2, 1], [1, 4, 1], [2, 2, 1], [1, 3, 1]],
    );
}

/// The same in 3-D: a rotated box and a plate two cells thick across the cut at z = 0.5,
/// moving through it; eight steps visit every sweep order. Slabs of 2, 3 and 4, and blocks
/// 1 × 2 × 2, 1 × 2 × 1 and 1 × 2 × 4 (y cut at 0.5 through both bodies; x is not cut in
/// 3-D, `protocol::decomp`).
#[test]
fn a_moving_body_across_the_cuts_3d_is_bit_identical_on_slabs_and_blocks() {
    let (grid, state) = blast(&[16, 16, 24]);
    let solid = moving_bodies_3d();
    assert!(covers_across(&grid, &solid, 12), "the plate covers the cut");
    let open = [
        [BoundaryKind::Wall, BoundaryKind::Outflow],
        [BoundaryKind::Wall; 2],
        [BoundaryKind::Outflow, BoundaryKind::Wall],
    ];
    let p = params(5, open);
    let decomps = PROCESS_GRIDS_3D;
    assert_coupled_same_for_ranks("3-D osmp5", &grid, &state, &p, &solid, 8, &decomps);
}

/// The mixing's groups summed by the ranks of their roots, in the steps where no group merges
/// or widens (`Embedded::set_mixing_by_root`, on by default), give the bits of the whole
/// mixing (every group merged and mixed on every rank), on one rank and on blocks: the moving
/// bodies of the 2-D and 3-D tests above, whose mixings take both paths (the 2-D body merges
/// or widens groups in some steps).
#[test]
fn the_mixing_by_root_gives_the_whole_mixings_bits() {
    let walls = [[BoundaryKind::Wall; 2]; 3];
    let (grid, state) = blast(&[40, 48]);
    let two = (
        grid,
        state,
        params(5, walls),
        moving_bodies_2d(),
        10,
        [2, 2, 1],
    );
    let (grid, state) = blast(&[16, 16, 24]);
    let three = (
        grid,
        state,
        params(5, walls),
        moving_bodies_3d(),
        8,
        [1, 2, 2],
    );
    for (grid, state, p, solid, steps, blocks) in [two, three] {
        for dims in [[1, 1, 1], blocks] {
            let run = |by_root| coupled_run(dims, &grid, &state, &p, &solid, steps, None, by_root);
            let (whole, by_root) = (run(false), run(true));
            let name = format!("{}-D on {dims:?}", grid.dim);
            assert!(by_root.unmerged > 0, "{name}: no step mixes by root");
            for (n, (a, b)) in whole.steps.iter().zip(&by_root.steps).enumerate() {
                assert_eq!(a, b, "{name}: step {n}, whole mixing and by root");
            }
            assert!(whole == by_root, "{name}: whole mixing and by root differ");
        }
    }
}

/// The bodies of the 2-D test on the 40 × 48 blast: a tilted block, a plate two cells thick
/// across the cut at y = 0.5, and two plates just beyond the lines of the ranks beside the cut at
/// y = 0.25 on 4 ranks.
pub(crate) fn moving_bodies_2d() -> SolidFrame {
    let block = embedded_support::polygon_2d(
        &[[0.70, 0.38], [0.90, 0.44], [0.84, 0.64], [0.66, 0.58]],
        [-1.0, 2.5],
        0.0,
    );
    let plate = embedded_support::polygon_2d(
        &[[0.08, 0.47], [0.30, 0.47], [0.30, 0.53], [0.08, 0.53]],
        [0.3, -0.6],
        0.0,
    );
    // Two more plates whose covered cells lie just beyond the lines of the ranks beside the cut
    // at y = 0.25 on 4 ranks (planes 16–17 above rank 0's line, which ends at plane 15;
    // planes 6–7 below rank 1's, which starts at plane 9): their segments' mirror ghosts fall
    // into the lines' ghost cells. (Own cells see those ghosts only through the positivity fix
    // of the overlap cells, which this flow does not trigger there: the path runs here, and
    // `fv::tests::wall_runs_in_a_decomposed_lines_ghost_cells_give_one_rank_fluxes` pins it.)
    let above = embedded_support::polygon_2d(
        &[[0.55, 0.332], [0.75, 0.332], [0.75, 0.377], [0.55, 0.377]],
        [0.0, -0.4],
        0.0,
    );
    let below = embedded_support::polygon_2d(
        &[[0.30, 0.124], [0.50, 0.124], [0.50, 0.169], [0.30, 0.169]],
        [0.2, 0.3],
        0.0,
    );
    bodies(&[block, plate, above, below])
}

/// A plate on planes 1–2 of the 40 × 48 blast, beside the periodic seam along y.
pub(crate) fn seam_plate_2d() -> SolidFrame {
    embedded_support::polygon_2d(
        &[[0.55, 0.0205], [0.75, 0.0205], [0.75, 0.063], [0.55, 0.063]],
        [0.0, 0.5],
        0.0,
    )
}

/// The bodies of the 3-D test on the 16 × 16 × 24 blast: a rotated box and a plate two cells
/// thick across the cut at z = 0.5.
pub(crate) fn moving_bodies_3d() -> SolidFrame {
    let tilt = embedded_support::rotation([0.6, 0.0, 0.8], 0.5);
    let block =
        embedded_support::box_3d([0.74, 0.5, 0.5], [0.12, 0.1, 0.15], tilt, [-1.0, 0.5, 2.5]);
    let flat = embedded_support::rotation([1.0, 0.0, 0.0], 0.0);
    let plate =
        embedded_support::box_3d([0.25, 0.3, 0.5], [0.12, 0.12, 0.05], flat, [0.0, 0.2, -0.6]);
    bodies(&[block, plate])
}
