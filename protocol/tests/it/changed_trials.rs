//! A trial sent as the particles that changed since the step's first trial
//! (`SolidState::changes_from`) and put back onto it (`SolidState::merged_onto`): the whole
//! trial comes back bit for bit, the changes hold exactly the particles with a differing bit,
//! and malformed changes are refused with the reason.

use proptest::prelude::*;
use protocol::wire::{SolidState, Stamp, WetSurface, n_orientation, n_rot};

/// A whole state of `n` particles in `dim`-D whose values come from `seed`.
fn whole(dim: u32, n: usize, seed: u64, iteration: u32) -> SolidState {
    let mut x = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((x >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let mut values = |k: usize| (0..n * k).map(|_| next()).collect::<Vec<f64>>();
    let d = dim as usize;
    SolidState {
        stamp: Stamp { step: 7, iteration },
        dim,
        position: values(d),
        orientation: values(n_orientation(dim)),
        velocity: values(d),
        angular_velocity: values(n_rot(dim)),
        diameter: values(1),
        surface: WetSurface {
            revision: 1,
            dim,
            vertices: values(d),
            elements: Vec::new(),
            element_particle: Vec::new(),
            wet: Vec::new(),
        },
        particles: Vec::new(),
        changed_only: false,
    }
}

/// The arrays of `s` with their strides.
fn arrays(s: &mut SolidState) -> [(&mut Vec<f64>, usize); 5] {
    let d = s.dim as usize;
    let (o, r) = (n_orientation(s.dim), n_rot(s.dim));
    [
        (&mut s.position, d),
        (&mut s.orientation, o),
        (&mut s.velocity, d),
        (&mut s.angular_velocity, r),
        (&mut s.diameter, 1),
    ]
}

/// Bits of every value of a state, to compare states as bits (NaN and −0 included).
fn bits(s: &SolidState) -> Vec<u64> {
    [
        &s.position,
        &s.orientation,
        &s.velocity,
        &s.angular_velocity,
        &s.diameter,
        &s.surface.vertices,
    ]
    .iter()
    .flat_map(|v| v.iter().map(|x| x.to_bits()))
    .collect()
}

/// Values a changed particle may take: ordinary ones, a sign of zero, NaN, infinities, the
/// next float.
fn new_value(old: f64, how: u8) -> f64 {
    match how % 6 {
        0 => old * 1.5 + 0.25,
        1 => -0.0,
        2 => f64::NAN,
        3 => f64::INFINITY,
        4 => f64::from_bits(old.to_bits() ^ 1),
        _ => 0.0,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn a_trial_comes_back_whole_bit_for_bit(
        dim in 2u32..=3,
        n in 0usize..40,
        seed in any::<u64>(),
        edits in proptest::collection::vec((any::<usize>(), 0usize..5, any::<usize>(), any::<u8>()), 0..30),
    ) {
        let first = whole(dim, n, seed, 0);
        let mut trial = first.clone();
        trial.stamp.iteration = 3;
        trial.surface.vertices.iter_mut().for_each(|v| *v += 1.0);
        for &(p, array, k, how) in &edits {
            if n == 0 {
                break;
            }
            let p = p % n;
            let (v, stride) = &mut arrays(&mut trial)[array];
            if *stride == 0 {
                continue;
            }
            let at = p * *stride + k % *stride;
            v[at] = new_value(v[at], how);
        }
        let changes = trial.changes_from(&first);
        prop_assert!(changes.changed_only);
        // Exactly the particles with a differing bit, ascending.
        let mut a = trial.clone();
        let mut b = first.clone();
        let (ta, tb) = (arrays(&mut a), arrays(&mut b));
        let differs: Vec<u32> = (0..n)
            .filter(|&p| {
                ta.iter().zip(&tb).any(|((x, k), (y, _))| {
                    (p * k..(p + 1) * k).any(|i| x[i].to_bits() != y[i].to_bits())
                })
            })
            .map(|p| p as u32)
            .collect();
        prop_assert_eq!(&changes.particles, &differs);
        prop_assert_eq!(changes.position.len(), differs.len() * dim as usize);
        prop_assert_eq!(changes.diameter.len(), differs.len());
        let back = changes.merged_onto(&first).expect("well-formed changes");
        prop_assert!(!back.changed_only && back.particles.is_empty());
        prop_assert_eq!(back.stamp, trial.stamp);
        prop_assert_eq!(bits(&back), bits(&trial));
        prop_assert_eq!(back.surface.revision, trial.surface.revision);
        // Through the codec as well: what the record holds decodes to the same changes.
        let frame = protocol::codec::encode(
            protocol::wire::NodeKind::Solid,
            &protocol::wire::Message::SolidState(changes.clone()),
        );
        let decoded = match protocol::codec::decode(&frame).expect("decodes").1 {
            protocol::wire::Message::SolidState(s) => s,
            other => panic!("{other:?}"),
        };
        prop_assert_eq!(bits(&decoded.merged_onto(&first).expect("merges")), bits(&trial));
    }
}

#[test]
fn an_unchanged_trial_is_no_particles_and_comes_back_whole() {
    let first = whole(3, 5, 11, 0);
    let mut trial = first.clone();
    trial.stamp.iteration = 1;
    let changes = trial.changes_from(&first);
    assert!(changes.changed_only);
    assert!(changes.particles.is_empty() && changes.position.is_empty());
    assert_eq!(
        bits(&changes.merged_onto(&first).expect("merges")),
        bits(&trial)
    );
}

#[test]
fn states_of_other_particles_are_sent_whole() {
    let first = whole(2, 4, 1, 0);
    // Another count, another dimension, a partial state: the trial goes whole.
    for other in [whole(2, 5, 2, 1), whole(3, 4, 2, 1), {
        let mut s = whole(2, 4, 2, 1);
        s.particles = vec![0, 1, 2, 3];
        s
    }] {
        let sent = other.changes_from(&first);
        assert!(!sent.changed_only);
        assert_eq!(sent, other);
        // And a whole state merges to itself.
        assert_eq!(sent.merged_onto(&first), Ok(other));
    }
}

#[test]
fn malformed_changes_are_refused_with_the_reason() {
    let first = whole(2, 6, 3, 0);
    let mut trial = first.clone();
    trial.stamp.iteration = 1;
    trial.position[2] += 1.0; // particle 1
    trial.velocity[8] += 1.0; // particle 4
    let good = trial.changes_from(&first);
    assert_eq!(good.particles, vec![1, 4]);
    let refused = |s: &SolidState, base: &SolidState, what: &str| {
        let err = s.merged_onto(base).expect_err("refused");
        assert!(err.contains(what), "{err:?} should say {what:?}");
    };
    let mut s = good.clone();
    s.particles = vec![4, 1];
    refused(&s, &first, "not ascending (4 then 1)");
    s.particles = vec![1, 1];
    refused(&s, &first, "not ascending (1 then 1)");
    s.particles = vec![1, 6];
    refused(
        &s,
        &first,
        "changed particle 6 beyond the first trial's 6 particles",
    );
    let mut s = good.clone();
    s.diameter.pop();
    refused(
        &s,
        &first,
        "array lengths do not match 2 changed particles in 2-D",
    );
    let mut s = good.clone();
    s.dim = 3;
    refused(&s, &first, "changes in 3-D onto a first trial in 2-D");
    refused(&good, &good, "not a whole state");
    let mut partial = first.clone();
    partial.particles = (0..6).collect();
    refused(&good, &partial, "not a whole state");
}
