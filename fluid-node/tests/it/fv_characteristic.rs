//! The characteristic (non-reflecting) outflow side: reflection of an acoustic pulse against
//! the zero-gradient outflow, a uniform state at rest and a uniform supersonic outflow left
//! unchanged bit for bit, the pressure relaxing toward the far field, the outflow ledger
//! closing the balance, and the same bits for 1 and 2 threads.

use crate::fv_common;

use fluid_node::fv::{BoundaryKind, FluidSolver, FluidState, FluxKind};
use fluid_node::grid::Grid;
use fv_common::*;

const GAMMA: f64 = 1.4;

fn characteristic(p_far: f64) -> BoundaryKind {
    BoundaryKind::Characteristic {
        p_far,
        sigma: fluid_node::fv::CHARACTERISTIC_SIGMA,
    }
}

fn run_to(s: &mut FluidSolver, t_end: f64) {
    while s.time() < t_end {
        let dt = s.max_dt().min(t_end - s.time());
        let rep = s.advance(dt);
        assert!(rep.ok(), "{:?}", rep.troubles);
    }
}

/// Largest `|p − p0| / eps` left in [0, 1] at time `t_end` after a right-going Gaussian simple
/// wave of amplitude `eps` (centre 0.5, width 0.05, over ρ0 = 1, p0 = 1, mean velocity `u0`)
/// has crossed the right side (both sides of kind `bc`; the reflected wave does not reach the
/// left one).
fn pulse_residual(bc: BoundaryKind, u0: f64, eps: f64, n: usize, order: u32) -> f64 {
    let grid = Grid::new(&[0.0], &[1.0], &[n]).expect("grid");
    let c0 = GAMMA.sqrt();
    let mut state = FluidState::zeros(1, n);
    for i in 0..n {
        let x = grid.cell_center([i, 0, 0])[0];
        let dp = eps * (-((x - 0.5) / 0.05).powi(2)).exp();
        state.set_primitive(
            i,
            1.0 + dp / (c0 * c0),
            [u0 + dp / c0, 0.0, 0.0],
            1.0 + dp,
            GAMMA,
        );
    }
    let b = [[bc; 2]; 3];
    let mut s =
        FluidSolver::new(grid, params(1, FluxKind::Osmp(order), b), state, 1).expect("solver");
    // The pulse (half-width ~0.15) leaves by t = 0.65 / (c0 + u0); a reflection from x = 1
    // travels left at c0 − u0 and is still inside at the end.
    let t_end = 0.65 / (c0 + u0) + 0.3 / (c0 - u0);
    run_to(&mut s, t_end);
    (0..n)
        .map(|i| (s.primitive(i).2 - 1.0).abs() / eps)
        .fold(0.0, f64::max)
}

#[test]
fn acoustic_pulse_leaves_without_reflection() {
    for (u0, order) in [(0.0, 5), (0.0, 7), (0.3, 5)] {
        let zero_gradient = pulse_residual(BoundaryKind::Outflow, u0, 1e-3, 200, order);
        let mut r = Vec::new();
        for sigma in [0.25, 0.05, 0.0] {
            let bc = BoundaryKind::Characteristic { p_far: 1.0, sigma };
            r.push(pulse_residual(bc, u0, 1e-3, 200, order));
        }
        eprintln!(
            "u0 {u0} osmp{order}: residual / incident amplitude: outflow {zero_gradient:.3e}, characteristic σ 0.25 / 0.05 / 0: {r:?}"
        );
        // σ = 0 is the zero-gradient outflow; both leave < 0.1 % behind.
        assert!(
            zero_gradient < 1e-3,
            "zero gradient reflects {zero_gradient}"
        );
        assert!((r[2] - zero_gradient).abs() < 1e-12, "{r:?}");
        // The relaxation reflects the low frequencies, R ~ K T: in proportion to σ.
        assert!(r[0] < 2e-2, "σ = 0.25 reflects {}", r[0]);
        assert!(r[1] < 5e-3, "σ = 0.05 reflects {}", r[1]);
    }
}

fn uniform(dim: usize, n: usize, rho: f64, vel: [f64; 3], p: f64, bc: BoundaryKind) -> FluidSolver {
    let lower = vec![0.0; dim];
    let upper = vec![1.0; dim];
    let cells = vec![n; dim];
    let grid = Grid::new(&lower, &upper, &cells).expect("grid");
    let mut state = FluidState::zeros(dim, grid.n_cells());
    for idx in 0..grid.n_cells() {
        state.set_primitive(idx, rho, vel, p, GAMMA);
    }
    FluidSolver::new(grid, params(dim, FluxKind::Osmp(5), [[bc; 2]; 3]), state, 2).expect("solver")
}

#[test]
fn uniform_state_at_rest_stays_at_rest_exactly() {
    for dim in [1, 2, 3] {
        let mut s = uniform(dim, 12, 1.18, [0.0; 3], 101325.0, characteristic(101325.0));
        let before = s.state().u.clone();
        for _ in 0..40 {
            let dt = s.max_dt();
            assert!(s.advance(dt).ok());
        }
        assert_eq!(s.state().u, before, "{dim}-D");
        assert_eq!(s.totals().outflow_mass, 0.0);
    }
}

#[test]
fn uniform_supersonic_outflow_leaves_unchanged_and_is_counted() {
    // Mach 2 along the diagonal of the box: every side is supersonic outflow or inflow.
    let c = (GAMMA * 1.0 / 1.0f64).sqrt();
    let u = 2.0 * c;
    let mut s = uniform(2, 16, 1.0, [u, u, 0.0], 1.0, characteristic(0.5));
    let before = s.state().u.clone();
    let mut t = 0.0;
    for _ in 0..30 {
        let dt = s.max_dt();
        assert!(s.advance(dt).ok());
        t += dt;
    }
    assert_eq!(s.state().u, before);
    // What enters through the low sides (supersonic inflow: ghost = cell) leaves through the
    // high sides: the ledger (out − in) stays at zero to round-off of ρ u t per side.
    let tot = s.totals();
    assert!(
        tot.outflow_mass.abs() <= 1e-12 * u * t,
        "{}",
        tot.outflow_mass
    );
}

#[test]
fn pressure_relaxes_toward_the_far_field() {
    // At rest at p = 1.1 with a far field at 1: the zero-gradient box stays at 1.1, the
    // characteristic one relaxes toward 1 (K = σ c / L at rest).
    let mean_p = |s: &FluidSolver| {
        let n = s.grid().n_cells();
        (0..n).map(|i| s.primitive(i).2).sum::<f64>() / n as f64
    };
    let t_end = 8.0 / GAMMA.sqrt();
    let mut zg = uniform(1, 100, 1.0, [0.0; 3], 1.1, BoundaryKind::Outflow);
    run_to(&mut zg, t_end);
    let mut ch = uniform(1, 100, 1.0, [0.0; 3], 1.1, characteristic(1.0));
    let mut history = Vec::new();
    for k in 1..=8 {
        run_to(&mut ch, k as f64 / GAMMA.sqrt());
        history.push(mean_p(&ch) - 1.0);
    }
    eprintln!(
        "excess pressure every L/c: {history:?}; zero gradient {}",
        mean_p(&zg) - 1.0
    );
    assert!((mean_p(&zg) - 1.1).abs() < 1e-12);
    assert!(
        history.windows(2).all(|w| w[1] < w[0] && w[1] > 0.0),
        "{history:?}"
    );
    assert!(history[7] < 0.5 * 0.1, "{history:?}");
}

#[test]
fn ledger_closes_and_threads_agree() {
    // An off-centre blast in a 2-D box with characteristic sides: what is inside plus what left
    // is what was there, to round-off; 1 and 2 threads give the same bits.
    let build = |threads: usize| {
        let grid = Grid::new(&[0.0, 0.0], &[1.0, 1.0], &[40, 40]).expect("grid");
        let mut state = FluidState::zeros(2, grid.n_cells());
        for idx in 0..grid.n_cells() {
            let x = grid.cell_center(grid.ijk(idx));
            let r2 = (x[0] - 0.6).powi(2) + (x[1] - 0.45).powi(2);
            let (rho, p) = if r2 < 0.15 * 0.15 {
                (4.0, 20.0)
            } else {
                (1.0, 1.0)
            };
            state.set_primitive(idx, rho, [0.1, -0.2, 0.0], p, GAMMA);
        }
        let bc = [[characteristic(1.0); 2]; 3];
        FluidSolver::new(grid, params(2, FluxKind::Osmp(5), bc), state, threads).expect("solver")
    };
    let mut a = build(1);
    let mut b = build(2);
    let t0 = a.totals();
    run_to(&mut a, 0.4);
    run_to(&mut b, 0.4);
    assert_eq!(a.state().u, b.state().u);
    let t1 = a.totals();
    assert!(
        t1.outflow_mass > 1e-2 * t0.mass,
        "nothing left: {}",
        t1.outflow_mass
    );
    let close =
        |now: f64, out: f64, start: f64, scale: f64| (now + out - start).abs() <= 1e-13 * scale;
    assert!(
        close(t1.mass, t1.outflow_mass, t0.mass, t0.mass),
        "{t1:?} vs {t0:?}"
    );
    assert!(
        close(t1.energy, t1.outflow_energy, t0.energy, t0.energy),
        "{t1:?} vs {t0:?}"
    );
    for ax in 0..2 {
        assert!(
            close(
                t1.momentum[ax],
                t1.outflow_momentum[ax],
                t0.momentum[ax],
                t0.mass
            ),
            "axis {ax}: {t1:?} vs {t0:?}"
        );
    }
}

#[test]
fn cylinder_explosion_scene_starts_coarse_fluid_only() {
    // scenes/cylinder-explosion.toml at 200 x 100 cells, the fluid alone (no cylinder) for 40
    // steps: every side is characteristic with p_far = 101325 Pa, the state stays physical and
    // the ledger closes.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let text = std::fs::read_to_string(dir.join("cylinder-explosion.toml")).expect("scene");
    let scene = protocol::scene::Scene::from_toml_str(&text, "cylinder-explosion").expect("valid");
    let mut fluid = scene.fluid.clone().expect("fluid");
    fluid.cells = vec![200, 100];
    let mut s = FluidSolver::from_scene(&fluid, 2).expect("solver");
    for axis in 0..2 {
        for side in 0..2 {
            match s.params().boundary[axis][side] {
                BoundaryKind::Characteristic { p_far, .. } => {
                    assert!((p_far - 101325.0).abs() < 1e-9 * 101325.0, "{p_far}")
                }
                other => panic!("axis {axis} side {side}: {other:?}"),
            }
        }
    }
    let t0 = s.totals();
    for _ in 0..40 {
        let dt = s.max_dt();
        let rep = s.advance(dt);
        assert!(rep.ok(), "{:?}", rep.troubles);
    }
    assert!(s.check_state().is_none());
    let t1 = s.totals();
    assert!((t1.mass + t1.outflow_mass - t0.mass).abs() <= 1e-13 * t0.mass);
    assert!((t1.energy + t1.outflow_energy - t0.energy).abs() <= 1e-13 * t0.energy);
    eprintln!(
        "cylinder-explosion 200x100, 40 steps: t = {:.3e} s",
        s.time()
    );
}

#[test]
fn the_scene_sets_sigma_and_the_far_field_pressure() {
    // `fluid.characteristic`: absent, each side gets σ = 0.25 and its mean initial pressure;
    // given, its σ and p_far on every characteristic side, and the other sides are left alone.
    let scene = |table: &str| {
        let text = format!(
            r#"
            name = "far"
            [fluid]
            lower = [0.0, 0.0]
            upper = [1.0, 1.0]
            cells = [8, 8]
            boundary = {{ x = ["characteristic", "characteristic"], y = ["wall", "wall"] }}
            {table}
            [[fluid.init]]
            region = "all"
            rho = 1.0
            p = 1.0
            [[fluid.init]]
            region = {{ box = {{ lower = [0.5, 0.0], upper = [1.0, 1.0] }} }}
            rho = 1.0
            p = 3.0
        "#
        );
        let scene = protocol::scene::Scene::from_toml_str(&text, "far").expect("valid");
        FluidSolver::from_scene(scene.fluid.as_ref().expect("fluid"), 1)
            .expect("solver")
            .params()
            .boundary
    };
    let default = scene("");
    assert_eq!(
        default[0],
        [
            BoundaryKind::Characteristic {
                p_far: 1.0,
                sigma: 0.25
            },
            BoundaryKind::Characteristic {
                p_far: 3.0,
                sigma: 0.25
            }
        ]
    );
    let given = scene("characteristic = { sigma = 0.1, p_far = 2.0 }");
    assert_eq!(
        given[0],
        [BoundaryKind::Characteristic {
            p_far: 2.0,
            sigma: 0.1
        }; 2]
    );
    assert_eq!(given[1], [BoundaryKind::Wall; 2]);
    let sigma_only = scene("characteristic = { sigma = 0.0 }");
    assert_eq!(
        sigma_only[0][1],
        BoundaryKind::Characteristic {
            p_far: 3.0,
            sigma: 0.0
        }
    );
}
