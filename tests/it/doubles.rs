//! The two doubles coupled in one process over the in-memory transport.

use cosim_tests::{run_in_process, scene};
use protocol::scene::Relaxation;
use protocol::wire::{Message, NodeKind};

#[test]
fn doubles_converge_and_balance_the_interface_work() {
    let scene = scene("backbone-doubles.toml");
    let run = run_in_process(&scene);
    assert_eq!(run.error, None);
    assert!(run.node_errors.is_empty(), "{:?}", run.node_errors);
    let s = &run.summary;
    assert_eq!(s.status, "completed");
    assert!(s.steps >= 60, "{} steps", s.steps);
    assert!((s.t_end - scene.run.t_end).abs() < 1e-12);
    // The impedance makes each trial depend on the last: several iterations, bounded by the limit.
    assert!(
        s.coupling_iterations.mean > 3.0,
        "{:?}",
        s.coupling_iterations
    );
    assert!(s.coupling_iterations.max < scene.run.max_iterations);
    // The work the pressure double gives is the work the spring receives, to round-off; the
    // spring's own energy error is velocity Verlet's, small against what was exchanged.
    let last: serde_json::Value =
        serde_json::from_slice(run.sink.diagnostics.last().expect("diagnostics")).expect("json");
    let wf = last["ledger"]["work_fluid"].as_f64().expect("work_fluid");
    let ws = last["ledger"]["work_solid"].as_f64().expect("work_solid");
    assert!(wf.abs() > 1.0, "work {wf}");
    assert!((wf - ws).abs() <= 1e-12 * wf.abs(), "{wf} vs {ws}");
    assert!(
        s.energy_err_vs_exchange < 1e-3,
        "{}",
        s.energy_err_vs_exchange
    );
}

#[test]
fn in_process_runs_are_bit_identical() {
    let scene = scene("backbone-doubles.toml");
    let a = run_in_process(&scene);
    let b = run_in_process(&scene);
    // Each channel carries the same bytes in the same order (channels interleave as the
    // threads happen to run, which is not part of the contract).
    for from in [NodeKind::Fluid, NodeKind::Solid, NodeKind::Coupler] {
        for to in [NodeKind::Fluid, NodeKind::Solid, NodeKind::Coupler] {
            let pick = |r: &cosim_tests::InProcess| -> Vec<Vec<u8>> {
                r.sink
                    .frames
                    .iter()
                    .filter(|f| f.0 == from && f.1 == to)
                    .map(|f| f.2.clone())
                    .collect()
            };
            let (fa, fb) = (pick(&a), pick(&b));
            assert_eq!(fa.len(), fb.len(), "{from} -> {to}");
            assert!(
                fa == fb,
                "payload bytes differ between two runs on {from} -> {to}"
            );
        }
    }
    assert!(a.sink.frames.len() > 1000, "{} frames", a.sink.frames.len());
}

#[test]
fn record_all_checkpoints_every_node_at_every_step() {
    let mut scene = scene("backbone-doubles.toml");
    scene.run.record = protocol::scene::RecordLevel::All;
    scene.run.checkpoint_every = 0;
    let run = run_in_process(&scene);
    assert_eq!(run.error, None);
    let steps = run.summary.steps;
    for node in [NodeKind::Fluid, NodeKind::Solid] {
        let checkpoints: Vec<u64> = run
            .sink
            .frames
            .iter()
            .filter(|f| f.0 == node)
            .filter_map(|f| match protocol::codec::decode(&f.2) {
                Ok((_, Message::Checkpoint(c))) => Some(c.stamp.step),
                _ => None,
            })
            .collect();
        // Before every step but the first (the initial state is the scene's).
        let expected: Vec<u64> = (1..steps).collect();
        assert_eq!(checkpoints, expected, "{node}");
    }
}

#[test]
fn iqn_ils_needs_fewer_iterations_than_aitken_on_the_doubles() {
    let mut scene = scene("backbone-doubles.toml");
    let mut mean = |relaxation| {
        scene.run.relaxation = relaxation;
        let run = run_in_process(&scene);
        assert_eq!(run.error, None, "{relaxation:?}");
        assert_eq!(run.summary.status, "completed");
        run.summary.coupling_iterations.mean
    };
    let aitken = mean(Relaxation::Aitken);
    let iqn = mean(Relaxation::IqnIls);
    // Measured: Aitken 6.42, IQN-ILS 2.60 (2 or 3 trials a step: the unknowns hold the
    // velocities the double's impedance reads, so the reused columns model the map exactly).
    assert!(iqn < aitken, "IQN-ILS {iqn} vs Aitken {aitken}");
    assert!(iqn <= 3.0, "IQN-ILS mean {iqn}");
}

#[test]
fn exceeding_max_iterations_stops_with_the_residual_history_in_the_record() {
    let mut scene = scene("backbone-doubles.toml");
    scene.run.max_iterations = 3;
    let run = run_in_process(&scene);
    let error = run.error.expect("3 trials are too few");
    assert!(
        error.contains("fixed point not converged at step 0") && error.contains("residual history"),
        "{error}"
    );
    let last: serde_json::Value =
        serde_json::from_slice(run.sink.diagnostics.last().expect("diagnostics")).expect("json");
    assert_eq!(last["converged"], false, "{last}");
    assert_eq!(last["step"], 0);
    assert_eq!(
        last["residuals"].as_array().map(Vec::len),
        Some(3),
        "{last}"
    );
}
