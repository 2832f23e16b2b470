//! Solid sub-cycling (`run.solid_substeps`, docs/subcycling.md), the real fluid and solid in one
//! process: a free particle in gas at rest stays at rest for any K; on a shocked free block the
//! work the fluid gives is the work the solid receives at every K, and the energy error against
//! the exchange stays below the K = 1 run's; K is on the diagnostics, and "auto" sub-cycles a
//! stiff block whose stable step is below the fluid's.

use cosim_tests::{InProcess, run_in_process};
use protocol::scene::SolidSubsteps;
use protocol::wire::NodeKind;

use crate::coupled::{REST_2D, completed, parse, solid_states, totals};

/// The `solid_substeps` of every step's diagnostics (`None` where absent).
fn substeps(run: &InProcess) -> Vec<Option<u64>> {
    run.sink
        .diagnostics
        .iter()
        .map(|d| {
            let v: serde_json::Value = serde_json::from_slice(d).expect("diagnostics JSON");
            v.get("solid_substeps").and_then(|k| k.as_u64())
        })
        .collect()
}

#[test]
fn a_free_particle_in_gas_at_rest_stays_for_any_k() {
    for setting in [
        SolidSubsteps::Fixed(1),
        SolidSubsteps::Fixed(7),
        SolidSubsteps::Fixed(64),
        SolidSubsteps::AUTO,
    ] {
        // coupled's particle at rest in gas at rest, to t = 0.1 s.
        let mut scene = parse(&REST_2D.replace("t_end = 0.25", "t_end = 0.1"));
        scene.run.solid_substeps = Some(setting);
        let run = run_in_process(&scene);
        completed(&run);
        let states = solid_states(&run);
        let (first, last) = (&states[0], states.last().expect("states"));
        let dx = first
            .position
            .iter()
            .zip(&last.position)
            .chain(first.orientation.iter().zip(&last.orientation))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let v = last
            .velocity
            .iter()
            .chain(&last.angular_velocity)
            .map(|v| v.abs())
            .fold(0.0, f64::max);
        let k = substeps(&run);
        println!(
            "{setting:?}: {} steps, moved {dx:e}, |v| {v:e}, K {:?}",
            k.len(),
            k[0]
        );
        assert!(run.summary.steps >= 5);
        assert!(dx <= 1e-12 * 0.3, "{setting:?}: the particle moved {dx:e}");
        assert!(v <= 1e-12, "{setting:?}: velocity {v:e}");
        // One rigid particle has no stable-step bound: "auto" takes one sub-step.
        let expected = match setting {
            SolidSubsteps::Fixed(k) => u64::from(k),
            SolidSubsteps::Auto(_) => 1,
        };
        assert!(k.iter().all(|&s| s == Some(expected)), "{k:?}");
    }
}

const SHOCKED_BLOCK: &str = r#"
    name = "shocked-block"
    [run]
    t_end = 0.2
    dt_max = 1e-3
    scheme = "semi-implicit"
    tolerance = 1e-12
    max_iterations = 30
    record = "none"
    [fluid]
    lower = [0.0, 0.0]
    upper = [2.0, 1.0]
    cells = [80, 40]
    boundary = { x = ["wall", "wall"], y = ["wall", "wall"] }
    [[fluid.init]]
    region = "all"
    rho = 1.4
    p = 1.0
    [[fluid.init]]
    region = { box = { lower = [0.0, 0.0], upper = [0.5, 1.0] } }
    rho = 5.6
    p = 10.0
    [solid]
    density = 100.0
    young = 7000.0
    poisson = 0.0
    [[solid.bodies]]
    shape = { box = { center = [1.0, 0.45], size = [0.3, 0.3] } }
    divisions = [6, 6]
"#;

/// The shocked block with `setting`: checks the books and returns the energy error against the
/// exchange and the diagnostics' K of each step.
fn shocked_block(young: f64, setting: Option<SolidSubsteps>) -> (f64, Vec<Option<u64>>) {
    let mut scene = parse(SHOCKED_BLOCK);
    scene.solid.as_mut().expect("solid").young = Some(young);
    scene.run.solid_substeps = setting;
    if setting == Some(SolidSubsteps::AUTO) {
        scene.run.dt_max = None;
    }
    let run = run_in_process(&scene);
    completed(&run);
    let (fluid, solid) = (totals(&run, NodeKind::Fluid), totals(&run, NodeKind::Solid));
    let (f0, f1) = (&fluid[0], fluid.last().expect("totals"));
    let s1 = solid.last().expect("totals");
    let s = &run.summary;
    assert!(s.mass_rel_err <= 1e-12, "mass error {:e}", s.mass_rel_err);
    let de = f1.energy - f0.energy;
    assert!((de + f1.interface_work).abs() <= 1e-12 * f0.energy);
    // The fixed point's tolerance separates the surface the solid's loads were taken on from
    // the accepted one the fluid's solid flux uses; the face velocity is the sub-steps' mean
    // motion, whose work is the solid's.
    assert!(
        (f1.interface_work - s1.interface_work).abs() <= 1e-9 * f1.interface_work.abs(),
        "{setting:?}: work given {:e}, received {:e}",
        f1.interface_work,
        s1.interface_work
    );
    let scale = f1
        .interface_impulse
        .iter()
        .map(|x| x.abs())
        .fold(0.0, f64::max);
    assert!(scale > 1e-3, "no impulse exchanged");
    for a in 0..2 {
        let (given, received) = (f1.interface_impulse[a], s1.interface_impulse[a]);
        assert!(
            (given - received).abs() <= 1e-9 * scale,
            "{given:e} {received:e}"
        );
    }
    println!(
        "young {young:e}, {setting:?}: {} steps, energy error / exchange {:e}, work {:e}, iterations max {}",
        s.steps, s.energy_err_vs_exchange, f1.interface_work, s.coupling_iterations.max
    );
    assert!(s.coupling_iterations.max < 7);
    (s.energy_err_vs_exchange, substeps(&run))
}

#[test]
fn the_shocked_block_balances_the_exchange_at_every_k_and_its_energy_error_stays_bounded() {
    let (reference, k) = shocked_block(7000.0, None);
    assert!(
        k.iter().all(Option::is_none),
        "no key, no K on the diagnostics"
    );
    assert!(reference > 0.0 && reference <= 1e-3, "{reference:e}");
    for k in [1, 8, 64] {
        let (error, on_diagnostics) = shocked_block(7000.0, Some(SolidSubsteps::Fixed(k)));
        assert!(on_diagnostics.iter().all(|&s| s == Some(u64::from(k))));
        // The solid's discrete energy error falls as (dt/K)²; the exchange adds none.
        assert!(
            error <= reference,
            "K = {k}: {error:e} against {reference:e}"
        );
    }
}

#[test]
fn auto_sub_cycles_a_stiff_block_within_twice_the_energy_error_of_k_1() {
    // Ten times stiffer: the solid's stable step (about 7e-4 s) is below the fluid's.
    let (one, _) = shocked_block(7e4, None);
    let (auto, k) = shocked_block(7e4, Some(SolidSubsteps::AUTO));
    let k: Vec<u64> = k
        .into_iter()
        .map(|k| k.expect("K on the diagnostics"))
        .collect();
    println!("auto: K from {:?} to {:?}", k.iter().min(), k.iter().max());
    assert!(k.iter().any(|&k| k > 1), "{k:?}");
    assert!(auto <= 2.0 * one, "auto {auto:e}, K = 1 {one:e}");
}

#[test]
fn a_link_broken_at_sub_step_j_of_k_has_the_time_of_that_sub_step() {
    // The pulled row of issue 14 (dt = 1.5e-4 s) with K = 4 sub-steps of h = 3.75e-5 s: the
    // links (0, 1) and (3, 4) open at 2 m/s, 7.5e-5 m a sub-step, and pass 1e-3 m at the 14th
    // sub-step (1.05e-3 m), the 2nd of step 3; (2, 3) opens at 1 m/s and passes it at the 27th
    // (1.0125e-3 m), the 3rd of step 6.
    let text = crate::issue_14::PULLED_ROW.replace("[run]\n", "[run]\nsolid_substeps = 4\n");
    let run = run_in_process(&parse(&text));
    assert_eq!(run.error, None);
    assert!(run.node_errors.is_empty(), "{:?}", run.node_errors);
    assert_eq!(substeps(&run), vec![Some(4); 8]);
    // t(n): the end of step n, the start of step n + 1, as the diagnostics give it.
    let t = |step: usize| {
        let v: serde_json::Value =
            serde_json::from_slice(&run.sink.diagnostics[step]).expect("diagnostics JSON");
        v["t"].as_f64().expect("t")
    };
    let h = 1.5e-4 / 4.0;
    let (t14, t27) = (t(2) + 2.0 * h, t(5) + 3.0 * h);
    let expected = format!("{t14:e},3,0,1\n{t14:e},3,3,4\n{t27:e},6,2,3\n");
    assert_eq!(run.sink.links_broken, expected);
    assert!((t14 - 14.0 * h).abs() < 1e-15 && (t27 - 27.0 * h).abs() < 1e-15);
}

#[test]
fn check_expects_the_k_and_the_step_the_first_step_of_auto_takes() {
    use coupler_node::check::{FirstSubsteps, first_substeps};
    // The stiff block of `auto_sub_cycles_a_stiff_block_within_twice_the_energy_error_of_k_1`.
    let mut scene = parse(SHOCKED_BLOCK);
    scene.solid.as_mut().expect("solid").young = Some(7e4);
    scene.run.solid_substeps = Some(SolidSubsteps::AUTO);
    scene.run.dt_max = None;
    scene.run.max_steps = Some(1);
    let Some(FirstSubsteps::Expected { k, dt, .. }) = first_substeps(&scene) else {
        panic!("{:?}", first_substeps(&scene));
    };
    let run = run_in_process(&scene);
    let first: serde_json::Value =
        serde_json::from_slice(&run.sink.diagnostics[0]).expect("diagnostics JSON");
    println!("check: K {k}, dt {dt:e}; the run: {first}");
    assert!(k > 1, "the stiff block sub-cycles: K = {k}");
    assert_eq!(first["solid_substeps"].as_u64(), Some(u64::from(k)));
    assert_eq!(
        first["dt"].as_f64(),
        Some(dt),
        "the same first step, to the bit"
    );
}
