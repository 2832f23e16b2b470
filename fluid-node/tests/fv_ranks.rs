//! Issue 16: the grid decomposed into slabs over K ranks gives the bits of one rank. The ranks
//! here are threads joined by channels (`fluid_node::ranks::threads`), so the decomposition
//! itself (halo depth, the neighbours' extra cells for the positivity fix, the fixed-order sums,
//! the CFL reduction, troubles named by their global cell, gathered checkpoints) is pinned
//! without an MPI library; `tests/it/issue_16_mpi.rs` runs the same through MPI processes.

use fluid_node::fv::{
    BoundaryKind, FluidParams, FluidSolver, FluidState, FluxKind, StepReport, TroubleKind,
};
use fluid_node::grid::Grid;
use fluid_node::ranks::threads::ThreadRanks;

mod fv_common;

/// A blast off-centre with a swirl on `cells`: the ball sits across the middle of the last
/// axis, where 2 and 4 ranks cut it.
fn blast(cells: &[usize]) -> (Grid, FluidState) {
    fv_common::blast_state(cells, 0.47)
}

fn params(order: u32, boundary: [[BoundaryKind; 2]; 3]) -> FluidParams {
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
struct Run {
    reports: Vec<String>,
    state: Vec<u64>,
    totals: String,
    checkpoint: Vec<u8>,
    limiting_cell: usize,
}

/// `steps` CFL steps of `(grid, state)` on `ranks` thread ranks (2 rayon threads each).
fn run(
    ranks: usize,
    grid: &Grid,
    state: &FluidState,
    params: &FluidParams,
    steps: usize,
    restore: Option<&[u8]>,
) -> Run {
    let handles: Vec<_> = ThreadRanks::new(ranks)
        .into_iter()
        .map(|comm| {
            let (grid, state, params) = (grid.clone(), state.clone(), params.clone());
            let restore = restore.map(<[u8]>::to_vec);
            std::thread::spawn(move || {
                let mut s = FluidSolver::decomposed(grid, params, state, 2, Box::new(comm))
                    .expect("solver");
                if let Some(bytes) = restore {
                    s.restore_checkpoint(&bytes).expect("restores");
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
            })
        })
        .collect();
    let mut runs: Vec<Option<Run>> = handles
        .into_iter()
        .map(|h| h.join().expect("rank thread"))
        .collect();
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
    let one = run(1, grid, state, params, steps, None);
    for &k in ranks {
        let many = run(k, grid, state, params, steps, None);
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
    assert_ne!(t.kind, TroubleKind::TimeStep, "{t:?}");
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
        })
        .collect();
    assert!(errs[0].contains("fluid.ranks = 4"), "{}", errs[0]);
    assert!(errs[0].contains("6 planes"), "{}", errs[0]);
}
