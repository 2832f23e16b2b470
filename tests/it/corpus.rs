//! Generated scenes (issue 35, `cosim_tests::corpus`): seeds that once failed, kept as
//! regression tests, each checked against every invariant of `corpus::check`.

use cosim_tests::corpus::{self, Outcome};

/// Runs the case of `seed` in a folder of its own and returns its outcome.
fn outcome(seed: u64) -> (Outcome, String) {
    let case = corpus::generate(seed);
    let dir = std::env::temp_dir().join(format!("cosim-it-corpus-{}-{seed}", std::process::id()));
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
        assert_eq!(outcome, Outcome::Ok, "seed {seed}:\n{toml}");
    }
}

/// Bodies that reach the box's walls or corners (issue 35 items 3 and 5): they lost mass (1e-9
/// to 1.6e-6 of it) where a body leaving through a wall uncovered boundary cells from beyond
/// it, or stopped on a closed pocket of gas squeezed against the wall (seed 262, a 3-D box;
/// 2-D: a flush box, a box in a corner, a lattice with fracture).
#[test]
fn bodies_reaching_the_walls_keep_every_invariant() {
    for seed in [44, 155, 220, 262, 527, 984] {
        let (outcome, toml) = outcome(seed);
        assert_eq!(outcome, Outcome::Ok, "seed {seed}:\n{toml}");
    }
}

/// What the sample tolerates today (issue 35, open, `docs/corpus.md`): a rigid body at rest flush
/// against walls drifts into them (its flush faces take no pressure and nothing holds it
/// there). Every other outcome is a failure.
fn open_defect(case: &corpus::Case, outcome: &Outcome) -> bool {
    use corpus::{Kept, Placement};
    matches!(outcome, Outcome::Drift(_))
        && case.kept == Kept::Rest
        && matches!(case.placement, Placement::Wall | Placement::Corner)
}

/// A fixed sample of the generator, seeds nobody looked at while the fixes were made (2000 to
/// 2063): no case stops on a non-physical state, loses mass or breaks an energy balance, and
/// every case keeps every invariant but for the open defects of [`open_defect`] (measured: 62
/// of 64 keep every invariant; 2 drift).
#[test]
fn a_fixed_sample_of_generated_scenes_keeps_every_invariant() {
    let (mut ok, mut open, mut failed) = (0, Vec::new(), Vec::new());
    for seed in 2000..2064 {
        let (outcome, _) = outcome(seed);
        let case = corpus::generate(seed);
        if outcome == Outcome::Ok {
            ok += 1;
        } else if open_defect(&case, &outcome) {
            open.push((seed, outcome));
        } else {
            failed.push((seed, outcome));
        }
    }
    println!("{ok} of 64 keep every invariant; open defects: {open:?}");
    assert!(
        failed.is_empty(),
        "{} cases failed: {failed:?}",
        failed.len()
    );
    assert!(ok >= 62, "{ok} of 64 keep every invariant");
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
        if outcome != Outcome::Ok {
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
        assert_eq!(outcome, Outcome::Ok, "seed {seed}:\n{toml}");
    }
}
