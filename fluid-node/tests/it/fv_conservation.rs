//! Conservation and determinism: totals constant to round-off with periodic and wall
//! boundaries (1-D, 2-D, 3-D), the outflow ledger closing the balance with open boundaries,
//! bit-identical results for 1 and 2 threads, checkpoint round trip, vacuum handled by
//! Lax–Friedrichs without negative states, trouble reported as data, and every scene file
//! parsing and building a solver.

use crate::fv_common;

use fluid_node::fv::exact_riemann::{ExactRiemann, Prim1};
use fluid_node::fv::{BoundaryKind, FluidSolver, FluidState, FluxKind, Totals, TroubleKind, init};
use fluid_node::grid::Grid;
use fv_common::*;

/// A blast (ρ = 8, p = 116.5 in a ball, ρ = 1.4, p = 1 outside) with a swirl, on an n^dim grid.
fn blast(dim: usize, n: usize, bc: BoundaryKind, order: u32, threads: usize) -> FluidSolver {
    let (grid, state) = blast_state(&vec![n; dim], 0.45);
    let mut b = [[bc; 2]; 3];
    if bc == BoundaryKind::Outflow {
        b = [[BoundaryKind::Outflow; 2]; 3];
    }
    FluidSolver::new(grid, params(dim, FluxKind::Osmp(order), b), state, threads).expect("solver")
}

fn close(a: f64, b: f64, scale: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * scale
}

fn run_steps(s: &mut FluidSolver, steps: usize) {
    for _ in 0..steps {
        let rep = s.advance(s.max_dt());
        assert!(rep.ok(), "{:?}", rep.troubles);
    }
}

#[test]
fn periodic_and_wall_boxes_conserve_to_round_off() {
    for dim in [1, 2, 3] {
        let n = [200, 40, 16][dim - 1];
        for bc in [BoundaryKind::Periodic, BoundaryKind::Wall] {
            for order in [3, 5, 7] {
                let mut s = blast(dim, n, bc, order, 2);
                let t0 = s.totals();
                run_steps(&mut s, 20);
                let t1 = s.totals();
                let tol = 1e-13;
                assert!(close(t1.mass, t0.mass, t0.mass, tol), "{dim}-D {bc:?} mass");
                assert!(
                    close(t1.energy, t0.energy, t0.energy, tol),
                    "{dim}-D {bc:?} energy {} vs {}",
                    t1.energy,
                    t0.energy
                );
                assert_eq!(t1.outflow_mass, 0.0);
                assert_eq!(t1.outflow_energy, 0.0);
                let p_scale = t0.mass * 10.0;
                for a in 0..dim {
                    // Periodic: momentum conserved; walls: changed by exactly the wall impulse.
                    let balance = t1.momentum[a] + t1.outflow_momentum[a];
                    assert!(
                        close(balance, t0.momentum[a], p_scale, tol),
                        "{dim}-D {bc:?} momentum {a}: {balance} vs {}",
                        t0.momentum[a]
                    );
                    if bc == BoundaryKind::Periodic {
                        assert_eq!(t1.outflow_momentum[a], 0.0);
                    }
                }
            }
        }
    }
}

#[test]
fn outflow_ledger_closes_the_balance() {
    // Sod with open ends, run until the waves have left: what left is accounted for.
    let mut s = blast(2, 40, BoundaryKind::Outflow, 5, 2);
    let t0 = s.totals();
    run_steps(&mut s, 60);
    let t1 = s.totals();
    assert!(t1.outflow_mass > 1e-3 * t0.mass, "nothing left the box");
    let check = |name: &str, now: f64, out: f64, start: f64| {
        assert!(
            close(now + out, start, start.abs().max(t0.mass), 1e-13),
            "{name}: {now} + {out} != {start}"
        );
    };
    check("mass", t1.mass, t1.outflow_mass, t0.mass);
    check("energy", t1.energy, t1.outflow_energy, t0.energy);
    for a in 0..2 {
        check(
            "momentum",
            t1.momentum[a],
            t1.outflow_momentum[a],
            t0.momentum[a],
        );
    }
}

fn bits(s: &FluidSolver) -> Vec<u64> {
    s.state().u.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn results_are_bit_identical_for_1_and_2_threads() {
    for (dim, n) in [(1, 300), (2, 48), (3, 20)] {
        for bc in [BoundaryKind::Wall, BoundaryKind::Outflow] {
            let mut a = blast(dim, n, bc, 5, 1);
            let mut b = blast(dim, n, bc, 5, 2);
            a.keep_directional_pressures(true);
            b.keep_directional_pressures(true);
            run_steps(&mut a, 8);
            run_steps(&mut b, 8);
            assert_eq!(bits(&a), bits(&b), "{dim}-D {bc:?}");
            let (ta, tb): (Totals, Totals) = (a.totals(), b.totals());
            assert_eq!(ta.mass.to_bits(), tb.mass.to_bits());
            assert_eq!(ta.energy.to_bits(), tb.energy.to_bits());
            assert_eq!(ta.outflow_energy.to_bits(), tb.outflow_energy.to_bits());
            for axis in 0..dim {
                let (pa, pb) = (
                    a.directional_pressures(axis).unwrap(),
                    b.directional_pressures(axis).unwrap(),
                );
                assert!(pa.iter().zip(pb).all(|(x, y)| x.to_bits() == y.to_bits()));
            }
        }
    }
}

#[test]
fn directional_pressures_are_the_sweep_start_pressures() {
    // 2-D: step 0 sweeps x then y, so p̄_x is the pressure at t^n.
    let mut s = blast(2, 24, BoundaryKind::Wall, 5, 1);
    assert_eq!(s.directional_pressures(0), None, "off by default");
    s.keep_directional_pressures(true);
    let before: Vec<f64> = (0..s.grid().n_cells()).map(|i| s.primitive(i).2).collect();
    let rep = s.advance(s.max_dt());
    assert_eq!(rep.sweeps, vec![0, 1]);
    assert_eq!(s.directional_pressures(0), Some(&before[..]));
    assert_ne!(s.directional_pressures(1), Some(&before[..]));
    let rep = s.advance(s.max_dt());
    assert_eq!(rep.sweeps, vec![1, 0]);
}

#[test]
fn checkpoint_round_trip_continues_identically() {
    let mut a = blast(3, 12, BoundaryKind::Wall, 7, 2);
    a.keep_directional_pressures(true);
    run_steps(&mut a, 3);
    let bytes = a.to_checkpoint();
    let mut b = blast(3, 12, BoundaryKind::Wall, 7, 1);
    b.keep_directional_pressures(true);
    b.restore_checkpoint(&bytes).expect("same grid");
    assert_eq!(b.steps(), 3);
    assert_eq!(a.directional_pressures(2), b.directional_pressures(2));
    run_steps(&mut a, 4);
    run_steps(&mut b, 4);
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.directional_pressures(1), b.directional_pressures(1));
    let mut other = blast(3, 10, BoundaryKind::Wall, 7, 1);
    let err = other.restore_checkpoint(&bytes).expect_err("other grid");
    assert!(err.to_string().contains("checkpoint for grid"), "{err}");
    assert!(other.restore_checkpoint(&bytes[..10]).is_err());
}

#[test]
fn vacuum_is_filled_with_lax_friedrichs_and_stays_positive() {
    // Gas (ρ = 1, p = 1) beside a vacuum (ρ = p = 0) in 1-D and 2-D: LF faces are used while
    // vacuum cells remain, no state goes negative, mass is conserved with walls.
    for dim in [1, 2] {
        let n = [200, 40][dim - 1];
        let grid = Grid::new(&vec![0.0; dim], &vec![1.0; dim], &vec![n; dim]).expect("grid");
        let mut state = FluidState::zeros(dim, grid.n_cells());
        for idx in 0..grid.n_cells() {
            let x = grid.cell_center(grid.ijk(idx));
            let gas = x[0] < 0.5;
            let (rho, p) = if gas { (1.0, 1.0) } else { (0.0, 0.0) };
            state.set_primitive(idx, rho, [0.0; 3], p, 1.4);
        }
        let bc = [[BoundaryKind::Wall; 2]; 3];
        let mut s = FluidSolver::new(grid.clone(), params(dim, FluxKind::Osmp(5), bc), state, 2)
            .expect("solver");
        let m0 = s.totals().mass;
        let mut lf_faces = 0;
        while s.time() < 0.1 {
            let rep = s.advance(s.max_dt().min(0.1 - s.time() + 1e-15));
            assert!(rep.ok(), "{dim}-D: {:?}", rep.troubles);
            lf_faces += rep.lax_friedrichs_faces;
            for idx in 0..grid.n_cells() {
                let (rho, _, p) = s.primitive(idx);
                assert!(
                    rho >= 0.0 && p >= 0.0,
                    "{dim}-D cell {idx}: rho {rho} p {p}"
                );
            }
        }
        assert!(lf_faces > 0, "no Lax-Friedrichs face used");
        assert!(close(s.totals().mass, m0, m0, 1e-13));
        // The gas front advanced into the vacuum (front speed 2c/(γ−1) ≈ 5.9; exact density
        // at x = 0.75, t = 0.1 is 0.026).
        let far = grid.index(n * 3 / 4, 0, 0);
        let prof: Vec<f64> = (n / 2 - 3..n)
            .step_by(5)
            .map(|i| s.primitive(grid.index(i, 0, 0)).0)
            .collect();
        assert!(
            s.primitive(far).0 > 1e-6,
            "{dim}-D: vacuum not filled {prof:?} t {}",
            s.time()
        );
    }
}

#[test]
fn trouble_is_reported_as_data() {
    let mut s = blast(2, 16, BoundaryKind::Wall, 5, 1);
    // A negative pressure injected in one cell is reported with its cell and position.
    let idx = s.grid().index(3, 5, 0);
    s.state_mut().set_primitive(idx, 1.0, [0.0; 3], -50.0, 1.4);
    let rep = s.advance(0.2 * s.max_dt().abs().min(1e-3));
    assert!(!rep.ok());
    let t = rep.troubles[0];
    assert!(matches!(
        t.kind,
        TroubleKind::Pressure | TroubleKind::NonFinite
    ));
    assert!(
        t.cell[0].abs_diff(3) <= 4 && t.cell[1].abs_diff(5) <= 4,
        "{t:?}"
    );
    // A time step above the CFL limit is refused without touching the state.
    let mut s = blast(2, 16, BoundaryKind::Wall, 5, 1);
    let before = bits(&s);
    let rep = s.advance(10.0 * s.max_dt());
    assert!(rep.refused.is_some(), "{rep:?}");
    assert_eq!(bits(&s), before);
    let rep = s.advance(f64::NAN);
    assert!(rep.refused.is_some(), "{rep:?}");
}

#[test]
fn exact_riemann_vacuum_generation() {
    // Strong rarefactions (u_R − u_L = 20) generate vacuum: ρ = p = 0 between the fronts.
    let ex = ExactRiemann::new(
        Prim1 {
            rho: 1.0,
            u: -10.0,
            p: 0.4,
        },
        Prim1 {
            rho: 1.0,
            u: 10.0,
            p: 0.4,
        },
        1.4,
    )
    .expect("physical");
    assert!(ex.vacuum);
    assert_eq!(ex.sample(0.0).rho, 0.0);
    assert_eq!(ex.sample(-20.0).rho, 1.0);
    let _ = init::l1_density;
}

#[test]
fn scenes_run_to_the_end_without_trouble() {
    // Every fluid scene runs to its t_end with ρ > 0 and p > 0 everywhere (blast-3d and the
    // vortex at reduced resolution in debug; the full blast-3d run is benches/fv_blast3d.rs).
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    for name in [
        "sod",
        "lax",
        "toro-123",
        "toro-3",
        "density-wave",
        "isentropic-vortex",
        "blast-3d",
    ] {
        let text = std::fs::read_to_string(dir.join(format!("{name}.toml"))).expect("scene");
        let scene = protocol::scene::Scene::from_toml_str(&text, name).expect("valid");
        let mut fluid = scene.fluid.clone().expect("fluid");
        if name == "blast-3d" {
            fluid.cells = vec![16; 3];
        }
        if name == "isentropic-vortex" {
            fluid.cells = vec![32; 2];
        }
        let mut s = FluidSolver::from_scene(&fluid, 2).expect("solver");
        let t0 = s.totals();
        let (steps, last) = s.run_until(scene.run.t_end, 1_000_000);
        assert!(last.ok(), "{name}: {:?}", last.troubles);
        assert!((s.time() - scene.run.t_end).abs() < 1e-12, "{name}");
        assert!(s.check_state().is_none(), "{name}");
        for idx in 0..s.grid().n_cells() {
            let (rho, _, p) = s.primitive(idx);
            assert!(rho > 0.0 && p > 0.0, "{name}: cell {idx} rho {rho} p {p}");
        }
        // The last report carries the totals; closed and periodic boxes conserve them.
        assert_eq!(last.totals, s.totals());
        let t1 = s.totals();
        assert!(
            close(t1.mass + t1.outflow_mass, t0.mass, t0.mass, 1e-13),
            "{name}: mass"
        );
        assert!(
            close(t1.energy + t1.outflow_energy, t0.energy, t0.energy, 1e-13),
            "{name}: energy"
        );
        println!("{name}: {steps} steps");
    }
}

#[test]
fn every_scene_parses_and_builds() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).expect("scenes/ exists") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).expect("readable");
            let name = path.display().to_string();
            let scene = protocol::scene::Scene::from_toml_str(&text, &name)
                .unwrap_or_else(|e| panic!("{e}"));
            if let Some(fluid) = scene.fluid.as_ref().filter(|f| f.node == "real") {
                let s = FluidSolver::from_scene(fluid, 1).unwrap_or_else(|e| panic!("{name}: {e}"));
                assert!(
                    s.check_state().is_none(),
                    "{name}: non-physical initial state"
                );
                n += 1;
            }
        }
    }
    assert!(n >= 7, "expected the 7 fluid scenes, found {n}");
}

/// A covered cell beside a crack between two pressed walls (the flush cube at 100³, step 5)
/// held the round-off ρ = 2.2e-30, ρu = 3.5e-18, E = 1.1e-16: a pressure of 4.4e-17 over that
/// density is a sound speed of 5.3e6 m/s, which collapsed the CFL step to 1.9e-9 s. Below the
/// vacuum density and pressure a cell's speeds are taken at the vacuum density, as its velocity
/// is: the step is that of the gas around it, bit for bit. (A real pressure at such a density
/// keeps its sound speed: issue 11's near-vacuum Sod is still stopped by `run.dt_min`.)
#[test]
fn round_off_below_the_vacuum_density_does_not_limit_the_step() {
    let grid = Grid::new(&[0.0, 0.0], &[1.0, 1.0], &[8, 8]).expect("grid");
    let mut state = FluidState::zeros(2, grid.n_cells());
    for idx in 0..grid.n_cells() {
        state.set_primitive(idx, 1.4, [0.3, 0.0, 0.0], 1.0, 1.4);
    }
    let wall = [[BoundaryKind::Wall; 2]; 3];
    let gas = FluidSolver::new(
        grid.clone(),
        params(2, FluxKind::Osmp(5), wall),
        state.clone(),
        1,
    )
    .expect("solver");
    let c = grid.index(3, 4, 0);
    state.u[c * 4..(c + 1) * 4].copy_from_slice(&[2.2e-30, 3.5e-18, 3.5e-18, 1.1e-16]);
    let round_off =
        FluidSolver::new(grid, params(2, FluxKind::Osmp(5), wall), state, 1).expect("solver");
    let (a, b) = (gas.max_dt(), round_off.max_dt());
    println!("CFL step {a:e} with the gas only, {b:e} with the round-off cell");
    assert_eq!(a.to_bits(), b.to_bits());
}
