//! Every instruction set the line kernel is compiled for gives the same bits (`isa.rs`): a line
//! with every kind of face, and 3-D steps on one and two threads, on each ISA this CPU has; a
//! face's flux does not depend on how long its line is, whatever strips the line is cut into;
//! and the CFL step a step's totals pass takes is `max_dt`'s own to the bit.

use crate::fv::euler::{NQ, State};
use crate::fv::isa::Isa;
use crate::fv::line::{FluxKind, LineScratch, LineSetup, LineStats, advance_line};
use crate::fv::{BoundaryKind, FluidParams, FluidSolver, FluidState};
use crate::grid::Grid;

const GAMMA: f64 = 1.4;

fn conserved(rho: f64, vel: [f64; 3], p: f64) -> State {
    let ke = 0.5 * rho * (vel[0] * vel[0] + vel[1] * vel[1] + vel[2] * vel[2]);
    [
        rho,
        rho * vel[0],
        rho * vel[1],
        rho * vel[2],
        p / (GAMMA - 1.0) + ke,
    ]
}

/// A line with every kind of face: smooth flow, Sod's and Toro's 123 and blast states, and
/// a gap of vacuum and near-vacuum cells (Lax–Friedrichs, HLLE fallback, positivity fix).
fn line_states(len: usize) -> Vec<State> {
    (0..len)
        .map(|i| {
            let x = i as f64 / len as f64;
            let (rho, u, p) = match i * 8 / len {
                0 | 1 => (
                    1.0 + 0.2 * (6.0 * x).sin(),
                    0.3 * (9.0 * x).cos(),
                    1.0 + 0.1 * (4.0 * x).sin(),
                ),
                2 => (1.0, 0.75, 1.0),
                3 => (0.125, 0.0, 0.1),
                4 => (1.0, -2.0, 0.4),
                5 => (1.0, 2.0, 0.4),
                6 if i % 3 == 0 => (0.0, 0.0, 0.0),
                6 => (1e-9, 1.0, 1e-9),
                _ => (5.99924, 19.5975, 460.894),
            };
            conserved(rho, [u, 0.1 * (3.0 * x).sin(), -0.2 * x], p)
        })
        .collect()
}

/// The line kernel on `isa`: the bits of the new states and the face fluxes, and the counters.
fn run_line(isa: Isa, flux: FluxKind, u: &[State]) -> (Vec<u64>, LineStats) {
    run_line_walls(isa, flux, u, [false, true])
}

/// [`run_line`] with the line's ends walls or not.
fn run_line_walls(isa: Isa, flux: FluxKind, u: &[State], wall: [bool; 2]) -> (Vec<u64>, LineStats) {
    let ng = flux.ghost_cells();
    let n = u.len() - 2 * ng;
    let setup = LineSetup {
        n,
        ng,
        flux,
        sigma: 0.02,
        gamma: GAMMA,
        n_shear: 2,
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
        wall,
        own: [0, n],
        end_face: true,
    };
    let mut s = LineScratch::default();
    s.set_isa(isa);
    s.resize(n, ng);
    s.u.copy_from_slice(u);
    let stats = advance_line(&mut s, &setup);
    let bits = s.new.iter().chain(&s.face).flatten().map(|x| x.to_bits());
    (bits.collect(), stats)
}

/// Every instruction set this CPU has gives the line kernel's states, fluxes and counters
/// to the bit, on regular faces and on each special one (vacuum, HLLE fallback).
#[test]
fn isa_paths_give_the_same_line_to_the_bit() {
    let isas = Isa::available();
    assert_eq!(isas[0], Isa::Baseline);
    for flux in [
        FluxKind::Osmp(3),
        FluxKind::Osmp(5),
        FluxKind::Osmp(7),
        FluxKind::MusclHancock,
    ] {
        let u = line_states(203);
        let (reference, stats) = run_line(Isa::Baseline, flux, &u);
        assert!(
            stats.lax_friedrichs > 0,
            "{flux:?}: no vacuum face in {stats:?}"
        );
        if let FluxKind::Osmp(_) = flux {
            assert!(stats.hlle > 0, "{flux:?}: no HLLE face in {stats:?}");
        }
        for &isa in &isas[1..] {
            let (bits, other) = run_line(isa, flux, &u);
            assert_eq!(other, stats, "{flux:?} on {isa:?}");
            let first = bits.iter().zip(&reference).position(|(a, b)| a != b);
            assert_eq!(first, None, "{flux:?} on {isa:?}: first differing value");
        }
    }
}

/// A face's flux reads only the cells of its stencil, so every line that holds those cells
/// gives it the same bits, however long the line and whatever strips `line/strip.rs` cuts it
/// into (one of its own length, one or more of each fixed length, the last one past the
/// line's end): each line of 1 to 300 cells of a smooth flow (regular faces only, no fix)
/// against the longest, for OSMP 3, 5 and 7, on every instruction set.
#[test]
fn a_faces_flux_does_not_depend_on_its_lines_length() {
    const LONGEST: usize = 300;
    // The bits of the new states and of the face fluxes, apart.
    let run = |isa: Isa, flux: FluxKind, u: &[State]| {
        let n = u.len() - 2 * flux.ghost_cells();
        let (mut bits, stats) = run_line_walls(isa, flux, u, [false, false]);
        assert_eq!(stats, LineStats::default(), "{flux:?} on {isa:?}: n = {n}");
        let face = bits.split_off(n * NQ);
        (bits, face)
    };
    for isa in Isa::available() {
        for flux in [FluxKind::Osmp(3), FluxKind::Osmp(5), FluxKind::Osmp(7)] {
            let ng = flux.ghost_cells();
            let u: Vec<State> = (0..LONGEST + 2 * ng)
                .map(|i| {
                    let x = i as f64 / 37.0;
                    let vel = [0.3 * x.sin(), 0.1 * (2.0 * x).cos(), -0.05];
                    conserved(1.0 + 0.2 * (1.7 * x).sin(), vel, 1.0 + 0.3 * x.cos())
                })
                .collect();
            let (new, face) = run(isa, flux, &u);
            for n in 1..=LONGEST {
                let (new_n, face_n) = run(isa, flux, &u[..n + 2 * ng]);
                assert!(
                    new_n == new[..new_n.len()] && face_n == face[..face_n.len()],
                    "{flux:?} on {isa:?}: a line of {n} cells against one of {LONGEST}"
                );
            }
        }
    }
}

/// A 3-D blast (blocks of pencils cut short at the grid's ends along every axis) gives the
/// same bits on every instruction set and with one or two threads.
#[test]
fn isa_paths_and_threads_give_the_same_3d_steps_to_the_bit() {
    let cells = [11, 13, 9];
    let grid = Grid::new(&[0.0; 3], &[1.1, 1.3, 0.9], &cells).expect("grid");
    let mut state = FluidState::zeros(3, grid.n_cells());
    for idx in 0..grid.n_cells() {
        let x = grid.cell_center(grid.ijk(idx));
        let r2: f64 = (0..3).map(|a| (x[a] - 0.4).powi(2)).sum();
        let (rho, p) = if r2 < 0.09 { (4.0, 50.0) } else { (1.0, 1.0) };
        let vel = [0.3 * x[1], -0.2 * x[2], 0.1 * x[0]];
        state.set_primitive(idx, rho, vel, p, GAMMA);
    }
    let params = FluidParams {
        gamma: GAMMA,
        cfl: 0.8,
        flux: crate::fv::FluxKind::Osmp(5),
        boundary: [
            [BoundaryKind::Wall; 2],
            [BoundaryKind::Periodic; 2],
            [BoundaryKind::Outflow, BoundaryKind::Wall],
        ],
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
    };
    let run = |isa: Isa, threads: usize| {
        let mut solver =
            FluidSolver::new(grid.clone(), params.clone(), state.clone(), threads).expect("solver");
        solver.set_isa(isa);
        for _ in 0..4 {
            let rep = solver.advance(solver.max_dt());
            assert!(rep.ok(), "{rep:?}");
        }
        solver
            .state()
            .u
            .iter()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    let reference = run(Isa::Baseline, 1);
    for isa in Isa::available() {
        for threads in [1, 2] {
            let bits = run(isa, threads);
            let first = bits.iter().zip(&reference).position(|(a, b)| a != b);
            assert_eq!(
                first, None,
                "{isa:?}, {threads} threads: first differing value"
            );
        }
    }
}

/// The CFL step [`FluidSolver::advance`] takes in the pass of its totals (for the next step)
/// is `max_dt`'s own pass to the bit, with the same limiting cell: on gas with one and two
/// threads, and on a state with a non-finite cell (NaN, the first such cell); and the totals
/// it keeps for the state are those summed again.
#[test]
fn the_cfl_step_of_the_totals_pass_is_max_dts_own() {
    let cells = [10, 7, 12];
    let grid = Grid::new(&[0.0; 3], &[1.0, 0.7, 1.2], &cells).expect("grid");
    let mut state = FluidState::zeros(3, grid.n_cells());
    for idx in 0..grid.n_cells() {
        let x = grid.cell_center(grid.ijk(idx));
        let r2: f64 = (0..3).map(|a| (x[a] - 0.5).powi(2)).sum();
        let (rho, p) = if r2 < 0.04 { (6.0, 80.0) } else { (1.2, 1.0) };
        state.set_primitive(idx, rho, [0.2 * x[2], 0.4 * x[0], -0.3 * x[1]], p, GAMMA);
    }
    let params = FluidParams {
        gamma: GAMMA,
        cfl: 0.7,
        flux: crate::fv::FluxKind::Osmp(5),
        boundary: [[BoundaryKind::Wall; 2]; 3],
        vacuum_rho: 1e-10,
        vacuum_p: 1e-10,
    };
    for threads in [1, 2] {
        let mut solver =
            FluidSolver::new(grid.clone(), params.clone(), state.clone(), threads).expect("solver");
        for step in 0..4 {
            if step == 3 {
                // Non-finite cells from here: the step reports them, the CFL step is NaN.
                let nvar = solver.state().nvar;
                solver.state_mut().u[(333 * nvar)..(334 * nvar)].fill(f64::NAN);
            }
            let dt = if step == 3 { 1e-4 } else { solver.max_dt() };
            let rep = solver.advance(dt);
            assert_eq!(rep.ok(), step < 3, "step {step}: {rep:?}");
            let taken = (solver.max_dt(), solver.limiting_cell());
            let kept = totals_bits(&solver.totals());
            let _ = solver.state_mut(); // forgets the step and the sums taken with the totals
            let own = (solver.max_dt(), solver.limiting_cell());
            assert_eq!(
                kept,
                totals_bits(&solver.totals()),
                "{threads} threads, step {step}"
            );
            // A changed state is summed again, not read from what was kept (NaN at step 3).
            solver.state_mut().u[0] += 1.0;
            assert_eq!(
                step == 3,
                kept == totals_bits(&solver.totals()),
                "step {step}"
            );
            solver.state_mut().u[0] -= 1.0;
            assert_eq!(
                taken.0.to_bits(),
                own.0.to_bits(),
                "{threads} threads, step {step}"
            );
            assert_eq!(taken.1, own.1, "{threads} threads, step {step}");
            assert_eq!(step == 3, own.0.is_nan(), "step {step}: {own:?}");
        }
    }
}

fn totals_bits(t: &crate::fv::Totals) -> [u64; 5] {
    [
        t.mass.to_bits(),
        t.momentum[0].to_bits(),
        t.momentum[1].to_bits(),
        t.momentum[2].to_bits(),
        t.energy.to_bits(),
    ]
}
