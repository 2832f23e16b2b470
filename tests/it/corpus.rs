//! Generated scenes (issue 35, `cosim_tests::corpus`): seeds that once failed, kept as
//! regression tests, each checked against every invariant of `corpus::check`.

use cosim_tests::corpus::{self, Outcome};

/// Runs the case of `seed` in a folder of its own and returns its outcome.
fn outcome(seed: u64) -> (Outcome, String) {
    // NOTE: two tests may run the same seed at once (2003 is in the fixed sample too); the
    // folder of one was removed under the other ("writing outputs to ...: No such file").
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let case = corpus::generate(seed);
    let dir = std::env::temp_dir().join(format!(
        "cosim-it-corpus-{}-{seed}-{run}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    let outcome = corpus::check(&case, &dir);
    let _ = std::fs::remove_dir_all(&dir);
    (outcome, case.toml)
}

/// Bodies at Mach 1.4 to 4.5 inside the box, at the step the nodes propose: they stopped in
/// their first steps on a negative pressure after a sweep beside the body, while the step did
/// not see the speed of the ghost states (2-D: a convex particle, balls, a box, a lattice).
#[test]
fn fast_bodies_at_the_step_the_nodes_propose_keep_every_invariant() {
    for seed in [102, 107, 362, 778, 869, 892, 924] {
        let (outcome, toml) = outcome(seed);
        assert!(outcome.passed(), "seed {seed}: {outcome:?}\n{toml}");
    }
}

/// Bodies that reach the box's walls or corners (issue 35 items 3 and 5): they lost mass (1e-9
/// to 1.6e-6 of it) where a body leaving through a wall uncovered boundary cells from beyond
/// it, or stopped on a closed pocket of gas squeezed against the wall (seed 262, a 3-D box;
/// 2-D: a flush box, a box in a corner, a lattice with fracture).
///
/// Since the walls hold the solid (`solid.walls`), the lattice with fracture (seed 220) lands on
/// the wall particle by particle, each stopped dead while its links still push, and its solid
/// energy balance is off by Verlet's error: 1.28 % of its energies against the corpus's 1 %,
/// which the same run with every step halved divides by about 4 ([`Outcome::Converging`]).
#[test]
fn bodies_reaching_the_walls_keep_every_invariant() {
    for seed in [44, 155, 220, 262, 527, 984] {
        let (outcome, toml) = outcome(seed);
        assert!(outcome.passed(), "seed {seed}: {outcome:?}\n{toml}");
    }
}

/// Rigid boxes at rest flush against walls or in corners, 2-D and 3-D (issue 35 item 6, the
/// rest state kept): the gas pushed them into the walls, whose flush faces take no pressure,
/// and nothing held them (drift 3.5 % to 52 % of the state); the walls now hold the solid
/// (`solid.walls`, `solid_node::dem::walls`). In a 3-D corner the box's faces lay within
/// round-off of the sides, split across them, and the part beyond was lost to the flush faces:
/// the gas moved at 0.24 c in the first step (seed 2003, `cutcell::clip::slab_range`).
#[test]
fn bodies_at_rest_flush_against_walls_and_in_corners_keep_the_gas_at_rest() {
    for seed in [19, 147, 176, 2003] {
        let (outcome, toml) = outcome(seed);
        assert!(outcome.passed(), "seed {seed}: {outcome:?}\n{toml}");
    }
}

/// A fixed sample of the generator, seeds nobody looked at while the fixes were made (2000 to
/// 2063): every case keeps every invariant (measured: 64 of 64; 62 before the walls held the
/// solid, 2 drifting).
#[test]
fn a_fixed_sample_of_generated_scenes_keeps_every_invariant() {
    let mut failed = Vec::new();
    for seed in 2000..2064 {
        let (outcome, _) = outcome(seed);
        if !outcome.passed() {
            failed.push((seed, outcome));
        }
    }
    assert!(
        failed.is_empty(),
        "{} cases failed: {failed:?}",
        failed.len()
    );
}

/// Two touching lattices, with and without fracture, at rest or moving: the gap between them
/// opens and closes again, and the gas it took in is squeezed to no volume. That closed pocket
/// of covered cells stopped the run ("no fluid volume to mix"); it now goes to the nearest gas
/// across the solid, as the gas would have escaped along the closing gap. (Seed 227 of the same
/// kind now runs to its end too, but its solid's energy balance drifts by 1.5 % of its energies,
/// the contact springs' time error: open, `docs/corpus.md`.)
#[test]
fn touching_bodies_closing_a_gap_keep_every_invariant() {
    let mut failed = Vec::new();
    for seed in [29, 38, 67, 261, 379, 565, 593, 643, 712, 729, 906, 2048] {
        let (outcome, _) = outcome(seed);
        println!("seed {seed}: {outcome:?}");
        if !outcome.passed() {
            failed.push((seed, outcome));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}

/// Lattices of boxes in 3-D, with and without fracture: edge-adjacent boxes, whose true overlap
/// is 0, stopped the run on a "deep contact" (a third of a box's volume, from step 0): the clip
/// of the contact's overlap extrapolated a cut point behind an end within its tolerance.
#[test]
fn lattices_of_touching_boxes_keep_every_invariant() {
    for seed in [42, 70, 116, 181, 488, 688, 765] {
        let (outcome, toml) = outcome(seed);
        assert!(outcome.passed(), "seed {seed}: {outcome:?}\n{toml}");
    }
}

/// A lattice at rest in a corner, pushed into it by the gas (seed 908): its links vibrate at
/// about 20 steps a period (`ω Δt ≈ 0.31`), and Verlet's bounded energy error of order
/// `(ω Δt)²/4` is 2.9 % of the solid's energies, above the corpus's 1 %. Halving every step
/// divides it by 4.0 (measured 0.0287, 0.0070, 0.0018 at Δt, Δt/2, Δt/4): the integrator's
/// error, not a missing term, which is what [`Outcome::Converging`] asks.
#[test]
fn a_lattice_pushed_into_a_corner_has_verlets_second_order_energy_error() {
    let (outcome, toml) = outcome(908);
    match outcome {
        Outcome::Converging(error, halved) => {
            assert!((0.025..0.032).contains(&error), "{error}\n{toml}");
            let ratio = halved / error;
            assert!((0.22..0.28).contains(&ratio), "{ratio}\n{toml}");
        }
        other => panic!("seed 908: {other:?}\n{toml}"),
    }
}

/// A 3-D shell with fracture at Mach 3.9 (4.6 m/s, 0.24 of the material's wave speed) whose
/// fragments pile against a wall (seed 339): the penalty contact let neighbours overlap by more
/// than a quarter of a particle and the solid stopped at step 81 ("deep contact"). Pairs past
/// 10 % now hold (`solid_node::dem::contact::hold`).
#[test]
fn fragments_piling_on_a_wall_faster_than_the_contact_can_stop_hold() {
    let (outcome, toml) = outcome(339);
    assert!(outcome.passed(), "seed 339: {outcome:?}\n{toml}");
}
