//! Issue 40: the grid cut into blocks along the last two axes (2-D 2 × 2, 3 × 1, 4 × 2, ...;
//! 3-D 1 × 2 × 2, 1 × 3 × 1, 1 × 2 × 4) gives the bits of one rank: every report, the totals
//! (each plane's compensated sums continued block after block), the gathered state and
//! checkpoint and the CFL step's limiting cell. Thread ranks, as in `fv_ranks`.

use fluid_node::fv::{BoundaryKind, FluidSolver};
use fluid_node::ranks::threads::ThreadRanks;

use crate::fv_ranks::{assert_same_on, blast, params, run, run_on};

#[test]
fn blocks_3d_are_bit_identical_to_one_rank() {
    let (grid, state) = blast(&[20, 18, 28]);
    let walls = [[BoundaryKind::Wall; 2]; 3];
    // Six steps: every sweep permutation.
    let blocks = [
        (4, Some([1, 2, 2])),
        (2, Some([1, 2, 1])),
        (3, Some([1, 3, 1])),
        (8, Some([1, 2, 4])),
    ];
    assert_same_on("osmp5 walls", &grid, &state, &params(5, walls), 6, &blocks);
    let blocks = [(4, Some([1, 2, 2])), (8, Some([1, 2, 4]))];
    assert_same_on("osmp7 walls", &grid, &state, &params(7, walls), 6, &blocks);
}

#[test]
fn blocks_with_periodic_outflow_and_characteristic_sides_are_bit_identical() {
    let (grid, state) = blast(&[16, 16, 24]);
    let periodic = [[BoundaryKind::Periodic; 2]; 3];
    // Two blocks along y: each is the other's neighbour on both sides there.
    let blocks = [(4, Some([1, 2, 2])), (8, Some([1, 2, 4]))];
    assert_same_on("periodic", &grid, &state, &params(5, periodic), 4, &blocks);
    let characteristic = BoundaryKind::Characteristic {
        p_far: 1.0,
        sigma: 0.25,
    };
    let open = [
        [BoundaryKind::Outflow, BoundaryKind::Wall],
        [BoundaryKind::Wall, BoundaryKind::Outflow],
        [BoundaryKind::Outflow, characteristic],
    ];
    let blocks = [(4, Some([1, 2, 2])), (2, Some([1, 2, 1]))];
    assert_same_on("open", &grid, &state, &params(3, open), 6, &blocks);
}

#[test]
fn blocks_2d_are_bit_identical_to_one_rank() {
    let (grid, state) = blast(&[40, 33]);
    let b = [
        [BoundaryKind::Wall, BoundaryKind::Outflow],
        [BoundaryKind::Outflow, BoundaryKind::Wall],
        [BoundaryKind::Wall; 2],
    ];
    let blocks = [
        (4, Some([2, 2, 1])),
        (3, Some([3, 1, 1])),
        (3, Some([1, 3, 1])),
        (8, Some([4, 2, 1])),
        (8, Some([2, 4, 1])),
    ];
    assert_same_on("2-D", &grid, &state, &params(7, b), 6, &blocks);
}

#[test]
fn a_checkpoint_of_blocks_restores_on_slabs_and_other_blocks() {
    let (grid, state) = blast(&[16, 16, 24]);
    let p = params(5, [[BoundaryKind::Wall; 2]; 3]);
    let straight = run(1, &grid, &state, &p, 5, None);
    let first = run_on(4, Some([1, 2, 2]), &grid, &state, &p, 2, None);
    for (k, dims) in [(2, [1, 2, 1]), (4, [1, 1, 4]), (8, [1, 2, 4])] {
        let rest = run_on(k, Some(dims), &grid, &state, &p, 3, Some(&first.checkpoint));
        assert!(rest.state == straight.state, "restored on {dims:?}");
        assert_eq!(
            rest.reports[..],
            straight.reports[2..],
            "restored on {dims:?}"
        );
    }
}

#[test]
fn a_process_grid_that_cuts_x_in_3d_or_does_not_fit_is_refused() {
    let (grid, state) = blast(&[16, 16, 24]);
    let p = params(5, [[BoundaryKind::Wall; 2]; 3]);
    for (dims, expected) in [
        ([2, 2, 1], "cuts axis 0 of a 3-D grid"),
        ([1, 4, 1], "a block 4 cells along axis 1"),
        ([1, 2, 1], "gives 2 blocks for 4 ranks"),
    ] {
        let errs: Vec<String> = ThreadRanks::new(4)
            .into_iter()
            .map(|comm| {
                let (g, s) = (grid.clone(), state.clone());
                FluidSolver::decomposed_as(g, p.clone(), s, 1, Box::new(comm), Some(dims))
                    .err()
                    .expect("refused")
                    .to_string()
            })
            .collect();
        assert!(errs[0].contains(expected), "{dims:?}: {}", errs[0]);
        assert!(errs[0].contains("fluid.ranks = 4"), "{}", errs[0]);
    }
}

/// Negative pressures in two cells of different blocks of `1 × 2 × 2`, one of them on the
/// pencil along y of a cell bad in the block below as well: every rank reports the troubles
/// one rank does (the first of each pencil, by global cell), in the same order.
#[test]
fn troubles_on_blocks_are_those_of_one_rank() {
    let (grid, mut state) = blast(&[12, 14, 24]);
    for (i, j, k) in [(3, 11, 17), (3, 2, 17), (8, 9, 4)] {
        state.set_primitive(grid.index(i, j, k), 1.4, [0.0; 3], -5.0, 1.4);
    }
    let p = params(5, [[BoundaryKind::Wall; 2]; 3]);
    let mut one = FluidSolver::new(grid.clone(), p.clone(), state.clone(), 1).expect("solver");
    let report = one.advance(one.max_dt());
    assert!(report.troubles.len() >= 3, "{:?}", report.troubles);
    let reports: Vec<String> = ThreadRanks::new(4)
        .into_iter()
        .map(|comm| {
            let (grid, state, p) = (grid.clone(), state.clone(), p.clone());
            std::thread::spawn(move || {
                let dims = Some([1, 2, 2]);
                let mut s = FluidSolver::decomposed_as(grid, p, state, 1, Box::new(comm), dims)
                    .expect("solver");
                let dt = s.max_dt();
                format!("{:?}", s.advance(dt))
            })
        })
        .collect::<Vec<_>>()
        .into_iter()
        .map(|h| h.join().expect("rank"))
        .collect();
    for (rank, r) in reports.iter().enumerate() {
        assert_eq!(*r, format!("{report:?}"), "rank {rank}");
    }
}
