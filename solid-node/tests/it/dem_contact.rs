//! Contact between particles that are not linked (`[solid.contact]`, issue 10): two blocks
//! meeting head-on (momentum, penetration, elastic return of the kinetic energy converging with
//! dt, dissipation equal to what the ledger reports), a block dropped on a fixed floor coming to
//! rest, a bar broken in the middle whose halves are pushed back and stop against each other,
//! in 2-D and 3-D; same bits for 1 and 2 threads; checkpoint/restore keeps the contact loads.

use crate::dem_support;

use dem_support::*;
use protocol::scene::{BodyConfig, ContactConfig, Motion, Shape, SolidConfig};
use solid_node::dem::{CheckpointError, Diagnostic, ParticleId, Solid};

const A: f64 = 0.1;

fn contact(restitution: f64, friction: f64) -> Option<ContactConfig> {
    Some(ContactConfig {
        stiffness: 1.0,
        restitution,
        friction,
    })
}

fn body(center: Vec<f64>, size: Vec<f64>, divisions: Vec<u32>, motion: Motion) -> BodyConfig {
    BodyConfig {
        shape: Shape::Box { center, size },
        divisions,
        motion,
        links: None,
    }
}

fn on_axis(dim: usize, x: f64, y: f64) -> Vec<f64> {
    let mut v = vec![0.0; dim];
    v[0] = x;
    v[1] = y;
    v
}

/// Two one-particle cubes (squares) of side `A`, `gap` apart along x, never linked.
fn two_blocks(dim: usize, gap: f64, restitution: f64, friction: f64) -> SolidConfig {
    let mut cfg = box_config(
        on_axis(dim, 0.0, 0.0),
        vec![A; dim],
        vec![1; dim],
        1e6,
        0.0,
        1000.0,
    );
    let c = 0.5 * (A + gap);
    cfg.bodies = vec![
        body(
            on_axis(dim, -c, 0.0),
            vec![A; dim],
            vec![1; dim],
            Motion::Free,
        ),
        body(
            on_axis(dim, c, 0.0),
            vec![A; dim],
            vec![1; dim],
            Motion::Free,
        ),
    ];
    cfg.contact = contact(restitution, friction);
    cfg
}

struct HeadOn {
    /// max |Σ m V| over the run / Σ m |V₀|.
    momentum_err: f64,
    /// Largest `A − (x_B − x_A)` over the run, as a fraction of `A`.
    penetration: f64,
    /// `(KE₀ − KE_end − Δdissipated)/KE₀` once apart (the energy balance).
    closure: f64,
    /// `KE_end / KE₀`.
    ke_ratio: f64,
    /// Dissipated by contact \[J\] and KE₀.
    dissipated: f64,
    ke0: f64,
}

fn head_on(dim: usize, restitution: f64, dt_fraction: f64, threads: usize) -> HeadOn {
    let speed = 0.5;
    let mut solid = build(&two_blocks(dim, 0.01, restitution, 0.0), dim, threads);
    solid.set_velocity(ParticleId(0), &on_axis(dim, speed, 0.0));
    solid.set_velocity(ParticleId(1), &on_axis(dim, -speed, 0.0));
    let dt = dt_fraction * solid.max_dt(f64::INFINITY);
    let mass = solid.model().particles[0].mass;
    let scale = 2.0 * mass * speed;
    let e0 = solid.energies();
    let ke0 = e0.kinetic_translation + e0.kinetic_rotation;
    let (mut momentum_err, mut penetration) = (0.0f64, 0.0f64);
    let t_end = 0.06;
    let mut report = None;
    while solid.time() < t_end {
        let r = solid.step_free(dt);
        assert!(r.diagnostics.is_empty(), "{:?}", r.diagnostics);
        let p = solid.momentum().linear;
        momentum_err = momentum_err.max(p.iter().map(|v| v.abs()).fold(0.0, f64::max) / scale);
        let gap = solid.position(ParticleId(1))[0] - solid.position(ParticleId(0))[0];
        penetration = penetration.max((A - gap) / A);
        report = Some(r);
    }
    let e = report.expect("steps ran").energies;
    assert_eq!(e.contact, 0.0, "apart at the end");
    assert!(
        solid.velocity(ParticleId(0))[0] < 0.0,
        "the blocks bounced back"
    );
    let ke = e.kinetic_translation + e.kinetic_rotation;
    HeadOn {
        momentum_err,
        penetration,
        closure: (ke0 - ke - (e.dissipated - e0.dissipated)) / ke0,
        ke_ratio: ke / ke0,
        dissipated: e.dissipated - e0.dissipated,
        ke0,
    }
}

#[test]
fn head_on_blocks_conserve_momentum_and_stay_apart() {
    for dim in [2usize, 3] {
        for restitution in [1.0, 0.5] {
            let r = head_on(dim, restitution, 0.5, 1);
            println!(
                "{dim}-D e = {restitution}: momentum err {:.2e}, penetration {:.4} A, KE ratio {:.6}",
                r.momentum_err, r.penetration, r.ke_ratio
            );
            assert!(r.momentum_err < 1e-12, "{dim}-D: {}", r.momentum_err);
            // Face-to-face: δ = v_rel √(m*/k); 2-D 3.2 %, 3-D 5.1 % of A at 0.5 m/s (measured
            // 3.3 % and 5.7 %).
            assert!(
                r.penetration > 0.01 && r.penetration < 0.08,
                "{dim}-D: {}",
                r.penetration
            );
        }
    }
}

#[test]
fn elastic_contact_returns_the_kinetic_energy_with_an_error_shrinking_with_dt() {
    for dim in [2usize, 3] {
        let errs: Vec<f64> = [0.5, 0.25, 0.125]
            .iter()
            .map(|&f| (head_on(dim, 1.0, f, 1).ke_ratio - 1.0).abs())
            .collect();
        println!("{dim}-D e = 1: |KE_end/KE_0 - 1| at dt/dt_max = 0.5, 0.25, 0.125: {errs:?}");
        // Measured: 2-D 3.5e-3, 7.1e-4, 1.9e-4; 3-D 1.2e-4, 9.0e-5, 1.9e-5 (the error after one
        // collision depends on the phase at exit, so it is only bounded by a rate over dt/4).
        assert!(errs[0] < 1e-2, "{dim}-D: {errs:?}");
        assert!(errs[2] < 0.25 * errs[0], "{dim}-D: {errs:?}");
        // The step the solid proposes (contact springs included) is stable: measured 1.0e-2
        // (2-D) and 6.4e-4 (3-D) at dt = max_dt.
        let at_max = (head_on(dim, 1.0, 1.0, 1).ke_ratio - 1.0).abs();
        println!("{dim}-D e = 1 at dt = max_dt: |KE_end/KE_0 - 1| = {at_max:.2e}");
        assert!(at_max < 3e-2, "{dim}-D: {at_max}");
    }
}

#[test]
fn inelastic_contact_dissipates_what_the_ledger_reports() {
    for dim in [2usize, 3] {
        let mut closures = Vec::new();
        for f in [0.5, 0.25, 0.125] {
            let r = head_on(dim, 0.5, f, 1);
            let e_eff = r.ke_ratio.sqrt();
            println!(
                "{dim}-D e = 0.5, dt/dt_max = {f}: dissipated {:.4e} J of KE0 {:.4e} J, \
                 closure {:.2e}, effective restitution {e_eff:.4}",
                r.dissipated, r.ke0, r.closure
            );
            assert!(
                r.dissipated > 0.5 * r.ke0,
                "{dim}-D: most of the energy goes"
            );
            // Linear spring–dashpot: e = 0.5 for a flat contact; the clamp that keeps the
            // normal force from pulling dissipates less near separation (measured 0.53–0.56).
            assert!(e_eff > 0.5 && e_eff < 0.6, "{dim}-D: {e_eff}");
            closures.push(r.closure.abs());
        }
        // Measured: 2-D 1.3e-3, 9.6e-4, 3.2e-4; 3-D 5.9e-4, 1.3e-5, 1.9e-5: the trapezoidal work
        // of the dashpot and the Verlet error of the contact spring, no longer cancelled by time
        // reversibility as in the elastic case.
        assert!(closures[0] < 3e-3, "{dim}-D: {closures:?}");
        assert!(closures[2] < 0.5 * closures[0], "{dim}-D: {closures:?}");
    }
}

/// A fixed floor of three particles (top at y = 0) and a one-particle block of side `A` whose
/// bottom starts `drop` above it, off the centre of the middle floor particle.
fn block_on_floor(dim: usize, drop: f64) -> SolidConfig {
    let mut cfg = two_blocks(dim, 0.0, 0.5, 0.3);
    let mut floor_size = vec![0.9; dim];
    floor_size[1] = A;
    let mut floor_div = vec![3; dim];
    floor_div[1] = 1;
    if dim == 3 {
        floor_size[2] = 0.3;
        floor_div[2] = 1;
    }
    cfg.bodies = vec![
        body(
            on_axis(dim, 0.0, -0.5 * A),
            floor_size,
            floor_div,
            Motion::Fixed,
        ),
        body(
            on_axis(dim, 0.037, 0.5 * A + drop),
            vec![A; dim],
            vec![1; dim],
            Motion::Free,
        ),
    ];
    let mut g = vec![0.0; dim];
    g[1] = -9.81;
    cfg.gravity = Some(g);
    cfg
}

/// Drops the block and runs `steps` steps.
struct Drop {
    /// The block's centre at the end.
    x: [f64; 3],
    /// Its largest displacement over the second half of the run \[m\].
    late_motion: f64,
    /// Its largest speed over the last tenth of the run \[m/s\].
    late_speed: f64,
    /// Largest |total energy − initial| over the run, relative to `m g drop`.
    energy_err: f64,
}

fn drop_block(dim: usize, steps: usize) -> Drop {
    let mut solid = build(&block_on_floor(dim, 0.02), dim, 1);
    let block = ParticleId(solid.n_particles() as u32 - 1);
    let dt = 0.5 * solid.max_dt(f64::INFINITY);
    let e0 = solid.energies().total();
    let drop_work = solid.model().particles[block.0 as usize].mass * 9.81 * 0.02;
    let (mut late_speed, mut energy_err, mut late_motion) = (0.0f64, 0.0f64, 0.0f64);
    let mut half = [0.0; 3];
    for k in 0..steps {
        let r = solid.step_free(dt);
        assert!(r.diagnostics.is_empty(), "step {k}: {:?}", r.diagnostics);
        energy_err = energy_err.max((r.energies.total() - e0).abs() / drop_work);
        let x = solid.position(block);
        if k == steps / 2 {
            half = x;
        }
        if k > steps / 2 {
            let d: f64 = (0..3).map(|a| (x[a] - half[a]).powi(2)).sum();
            late_motion = late_motion.max(d.sqrt());
        }
        if k >= steps - steps / 10 {
            let v = solid.velocity(block);
            late_speed = late_speed.max(v.iter().map(|c| c * c).sum::<f64>().sqrt());
        }
    }
    Drop {
        x: solid.position(block),
        late_motion,
        late_speed,
        energy_err,
    }
}

#[test]
fn block_dropped_on_a_fixed_floor_comes_to_rest_on_it() {
    // COSIM_SLOW_TESTS=1 runs the 10^5 steps of the issue; the default run is 2·10^4 steps
    // (≈ 5 s of simulated time; the bounces are over in ≈ 0.3 s).
    let steps = if slow() { 100_000 } else { 20_000 };
    for dim in [2usize, 3] {
        let d = drop_block(dim, steps);
        // Static sinking: m g / k with k = κ S² (S = A^(dim−1), κ = E/h^dim).
        let h = A * (dim as f64).sqrt();
        let k = 1e6 / h.powi(dim as i32) * A.powi(2 * (dim as i32 - 1));
        let mass = 1000.0 * A.powi(dim as i32);
        let sink = mass * 9.81 / k;
        let y_rest = 0.5 * A - sink;
        println!(
            "{dim}-D after {steps} steps: y - y_rest = {:.3e} m (static sink {sink:.3e} m), \
             x shift {:.3e} m, motion over the second half {:.3e} m, late speed {:.3e} m/s, \
             energy err {:.3e} of m g drop",
            d.x[1] - y_rest,
            d.x[0] - 0.037,
            d.late_motion,
            d.late_speed,
            d.energy_err
        );
        // Measured: y − y_rest = −0.6 % (2-D), −3 % (3-D) of the sinking, x shift ≤ 1e-17 m.
        assert!(
            (d.x[1] - y_rest).abs() < 0.05 * sink,
            "{dim}-D: y {}",
            d.x[1]
        );
        assert!((d.x[0] - 0.037).abs() < 1e-12, "{dim}-D: x {}", d.x[0]);
        assert!(d.late_motion < 1e-9, "{dim}-D: drift {}", d.late_motion);
        assert!(d.late_speed < 1e-9, "{dim}-D: {}", d.late_speed);
        assert!(d.energy_err < 1e-2, "{dim}-D: {}", d.energy_err);
    }
}

/// A bar of four particles of side `A` along x, fracture at 1 % elongation.
fn bar(dim: usize) -> SolidConfig {
    let mut size = vec![A; dim];
    size[0] = 4.0 * A;
    let mut div = vec![1; dim];
    div[0] = 4;
    let mut cfg = box_config(vec![0.0; dim], size, div, 1e6, 0.0, 1000.0);
    with_fracture(&mut cfg, 0.01);
    cfg.contact = contact(0.5, 0.3);
    cfg
}

/// Loads on the right half of the bar (particles 2 and 3), `f` per particle along x.
fn right_half_loads(dim: usize, f: f64) -> Vec<f64> {
    let mut out = vec![0.0; dim * 4];
    out[2 * dim] = f;
    out[3 * dim] = f;
    out
}

#[test]
fn broken_bar_halves_pushed_back_touch_and_stop() {
    for dim in [2usize, 3] {
        let mut cfg = bar(dim);
        // The left half is fixed: a free bar under opposite dead loads is unstable to a rigid
        // rotation once compressed (the loads' couple grows with the angle; seen in 3-D).
        let mut upper = vec![1.0; dim];
        upper[0] = 0.0;
        constrain(&mut cfg, vec![-1.0; dim], upper, Motion::Fixed);
        let mut solid = build(&cfg, dim, 1);
        assert_eq!(solid.n_particles(), 4);
        let dt = 0.5 * solid.max_dt(f64::INFINITY);
        let torque = vec![0.0; if dim == 3 { 12 } else { 4 }];
        // Pull the right half with F per particle: the middle link carries 2F, the last F.
        let pull = 0.3 * 1e6 * A.powi(dim as i32 - 1) * 0.01;
        let mut broke = None;
        for k in 0..20_000 {
            let r = solid.step(dt, &right_half_loads(dim, pull), &torque);
            assert!(r.diagnostics.is_empty(), "{:?}", r.diagnostics);
            if !r.broken_links.is_empty() {
                broke = Some((k, r.broken_links.clone()));
                break;
            }
        }
        let (k_break, links) = broke.expect("the bar breaks");
        assert_eq!(links.len(), 1, "{links:?}");
        assert_eq!(links[0].particles, [ParticleId(1), ParticleId(2)]);
        // Push the right half back with a tenth of the pull and keep pushing.
        let push = 0.1 * pull;
        let gap = |s: &Solid| s.position(ParticleId(2))[0] - s.position(ParticleId(1))[0] - A;
        let closing =
            |s: &Solid| 0.5 * (s.velocity(ParticleId(2))[0] + s.velocity(ParticleId(3))[0]);
        let (mut max_gap, mut min_gap, mut max_speed) = (0.0f64, f64::INFINITY, 0.0f64);
        let (mut touched, mut late_speed) = (false, 0.0f64);
        let steps = 60_000;
        for k in 0..steps {
            let r = solid.step(dt, &right_half_loads(dim, -push), &torque);
            assert!(r.diagnostics.is_empty(), "{:?}", r.diagnostics);
            max_gap = max_gap.max(gap(&solid));
            min_gap = min_gap.min(gap(&solid));
            max_speed = max_speed.max(closing(&solid).abs());
            touched |= r.energies.contact > 0.0;
            if k >= steps - steps / 10 {
                late_speed = late_speed.max(closing(&solid).abs());
            }
        }
        // Static compression of the contact under 2F: δ = 2F/k, k = κ S².
        let h = A * (dim as f64).sqrt();
        let k = 1e6 / h.powi(dim as i32) * A.powi(2 * (dim as i32 - 1));
        let static_gap = -2.0 * push / k;
        let end_gap = gap(&solid);
        println!(
            "{dim}-D: broke at step {k_break}, opened to {max_gap:.3e} m, deepest {:.4} A, \
             end gap {end_gap:.4e} m vs static {static_gap:.4e} m, closing speed max \
             {max_speed:.3e}, late {late_speed:.3e} m/s",
            -min_gap / A
        );
        assert!(
            touched && max_gap > 1e-3,
            "{dim}-D: the halves separated, then touched"
        );
        assert!(min_gap > -0.05 * A, "{dim}-D: passed through? {min_gap}");
        assert!(
            (end_gap - static_gap).abs() < 0.1 * static_gap.abs(),
            "{dim}-D: {end_gap}"
        );
        assert!(
            late_speed < 0.02 * max_speed,
            "{dim}-D: {late_speed} vs {max_speed}"
        );
    }
}

/// Off-centre impact of a spinning block: the blocks turn in the contact (where a force put at
/// the overlap centroid would not conserve energy, module doc of `solid_node::dem::contact`):
/// the energy error after the contact, `|E_end/E_0 − 1|` with every energy counted.
fn oblique(dim: usize, dt_fraction: f64) -> f64 {
    let mut solid = build(&two_blocks(dim, 0.01, 1.0, 0.0), dim, 1);
    let rot = if dim == 3 {
        vec![0.0, 0.0, 3.0]
    } else {
        vec![3.0]
    };
    solid.set_velocity(ParticleId(0), &on_axis(dim, 0.5, 0.1));
    solid.set_velocity(ParticleId(1), &on_axis(dim, -0.5, -0.1));
    solid.set_angular_velocity(ParticleId(0), &rot);
    let dt = dt_fraction * solid.max_dt(f64::INFINITY);
    let e0 = solid.energies().total();
    let mut touched = false;
    while solid.time() < 0.06 {
        let r = solid.step_free(dt);
        assert!(r.diagnostics.is_empty(), "{:?}", r.diagnostics);
        touched |= r.energies.contact > 0.0;
    }
    assert!(touched);
    let e = solid.energies();
    assert_eq!(e.contact, 0.0, "apart at the end");
    (e.total() / e0 - 1.0).abs()
}

#[test]
fn oblique_elastic_impact_keeps_the_energy_within_the_stated_bound() {
    for dim in [2usize, 3] {
        let errs: Vec<f64> = [0.5, 0.25, 0.125]
            .iter()
            .map(|&f| oblique(dim, f))
            .collect();
        println!(
            "{dim}-D oblique e = 1: |E_end/E_0 - 1| at dt/dt_max = 0.5, 0.25, 0.125: {errs:?}"
        );
        // Measured: 2-D 9.9e-4, 1.9e-4, 6.1e-5; 3-D 2.3e-5, 1.1e-5, 2.6e-6.
        assert!(errs[0] < 3e-3, "{dim}-D: {errs:?}");
        assert!(errs[2] < 0.25 * errs[0], "{dim}-D: {errs:?}");
    }
}

/// A fragmenting 3-D lattice with contact on (defaults: damping and friction, so the contact
/// loads are state), big enough that pairs span several rayon chunks (256 items).
fn fragmenting(threads: usize) -> Solid {
    let mut cfg = box_config(
        vec![0.0; 3],
        vec![1.2, 0.6, 0.4],
        vec![12, 6, 4],
        1e6,
        0.25,
        1000.0,
    );
    cfg.gravity = Some(vec![0.0, 0.0, -9.81]);
    with_fracture(&mut cfg, 0.002);
    cfg.contact = Some(ContactConfig::default());
    let mut solid = build(&cfg, 3, threads);
    let mut noise = Noise(777);
    for p in 0..solid.n_particles() {
        let v = [noise.next(), noise.next(), noise.next()];
        solid.set_velocity(ParticleId(p as u32), &v);
        let w = [5.0 * noise.next(), 5.0 * noise.next(), 5.0 * noise.next()];
        solid.set_angular_velocity(ParticleId(p as u32), &w);
    }
    solid
}

fn bits(solid: &Solid) -> Vec<u64> {
    let mut out = Vec::new();
    for p in 0..solid.n_particles() {
        let id = ParticleId(p as u32);
        out.extend(solid.position(id).iter().map(|v| v.to_bits()));
        out.extend(solid.velocity(id).iter().map(|v| v.to_bits()));
        out.extend(solid.orientation(id).iter().map(|v| v.to_bits()));
        out.extend(solid.angular_velocity(id).iter().map(|v| v.to_bits()));
    }
    let e = solid.energies();
    out.extend(
        [e.elastic, e.contact, e.dissipated, e.kinetic_rotation]
            .iter()
            .map(|v| v.to_bits()),
    );
    out
}

/// Steps; returns (links broken, largest contact energy seen, most overlapping pairs).
fn advance(solid: &mut Solid, steps: usize, dt: f64) -> (usize, f64, usize) {
    let (mut broken, mut contact, mut overlapping) = (0, 0.0f64, 0);
    for _ in 0..steps {
        let r = solid.step_free(dt);
        assert!(r.diagnostics.is_empty(), "{:?}", r.diagnostics);
        broken += r.broken_links.len();
        contact = contact.max(r.energies.contact);
        let c = solid.contact().expect("contact on");
        overlapping = overlapping.max(c.pairs().iter().filter(|p| p.energy > 0.0).count());
    }
    (broken, contact, overlapping)
}

#[test]
fn contact_gives_the_same_bits_for_one_and_two_threads() {
    let mut one = fragmenting(1);
    let mut two = fragmenting(2);
    let dt = 0.5 * one.max_dt(f64::INFINITY);
    let r1 = advance(&mut one, 40, dt);
    let r2 = advance(&mut two, 40, dt);
    let n_pairs = one.contact().expect("contact on").pairs().len();
    println!(
        "fragmenting lattice: {n_pairs} pairs examined, (broken, max contact J, overlapping) {r1:?}"
    );
    assert!(n_pairs > 512, "{n_pairs} pairs");
    assert!(
        r1.0 > 0 && r1.1 > 0.0 && r1.2 > 0,
        "fracture and contact exercised: {r1:?}"
    );
    assert_eq!(r1, r2);
    assert_eq!(bits(&one), bits(&two));
}

#[test]
fn checkpoint_restore_keeps_the_contact_state() {
    let mut straight = fragmenting(1);
    let dt = 0.5 * straight.max_dt(f64::INFINITY);
    advance(&mut straight, 20, dt);
    assert!(
        straight.energies().contact > 0.0,
        "in contact at the checkpoint"
    );
    let bytes = straight.to_checkpoint();
    advance(&mut straight, 20, dt);
    let mut restored = fragmenting(2);
    restored.restore_checkpoint(&bytes).expect("restores");
    advance(&mut restored, 20, dt);
    assert_eq!(bits(&straight), bits(&restored));
    // A checkpoint without contact state does not restore into a solid with contact.
    let mut cfg = box_config(
        vec![0.0; 3],
        vec![1.2, 0.6, 0.4],
        vec![12, 6, 4],
        1e6,
        0.25,
        1000.0,
    );
    with_fracture(&mut cfg, 0.002);
    let plain = build(&cfg, 3, 1).to_checkpoint();
    let err = fragmenting(1).restore_checkpoint(&plain).unwrap_err();
    assert!(
        matches!(err, CheckpointError::ContactLoads { found: 0, expected } if expected > 0),
        "{err:?}"
    );
    assert!(err.to_string().contains("contact"), "{err}");
}

#[test]
fn deep_overlap_is_reported_naming_the_particles() {
    // Blocks thrown together at 750 m/s: one step of 2e-5 s carries them from 1 mm apart to
    // an overlap of 29 % of a block, past a quarter before any hold can act (the holds of
    // `contact::hold` stop slower pairs at 10 %, `dem_holds`).
    let mut cfg = two_blocks(2, 0.001, 1.0, 0.0);
    cfg.contact.as_mut().expect("contact").stiffness = 1e-3;
    let mut solid = build(&cfg, 2, 1);
    solid.set_velocity(ParticleId(0), &[750.0, 0.0]);
    solid.set_velocity(ParticleId(1), &[-750.0, 0.0]);
    let dt = 2e-5;
    let mut found = None;
    for _ in 0..200 {
        let r = solid.step_free(dt);
        if let Some(d) = r.diagnostics.first() {
            found = Some(d.clone());
            break;
        }
    }
    match found {
        Some(Diagnostic::DeepContact {
            particles,
            overlap,
            volume,
        }) => {
            assert_eq!(particles, [ParticleId(0), ParticleId(1)]);
            assert!(overlap > 0.25 * volume, "{overlap} of {volume}");
        }
        other => panic!("expected a deep contact report, got {other:?}"),
    }
}

#[test]
fn contact_leaves_the_wet_surface_shape_unchanged() {
    let mut with = fragmenting(1);
    let mut cfg = box_config(
        vec![0.0; 3],
        vec![1.2, 0.6, 0.4],
        vec![12, 6, 4],
        1e6,
        0.25,
        1000.0,
    );
    cfg.gravity = Some(vec![0.0, 0.0, -9.81]);
    with_fracture(&mut cfg, 0.002);
    let without = build(&cfg, 3, 1);
    let (a, b) = (with.wet_surface(), without.wet_surface());
    assert_eq!(a.vertices.len(), b.vertices.len());
    assert_eq!(a.elements, b.elements);
    assert_eq!(a.wet, b.wet);
    let dt = 0.5 * with.max_dt(f64::INFINITY);
    advance(&mut with, 10, dt);
    let after = with.wet_surface();
    assert_eq!(after.vertices.len(), b.vertices.len());
    assert_eq!(after.n_elements(), b.n_elements());
}

/// The block of `block_on_floor` resting on the floor (μ = 0.3) under gravity tilted by `α`
/// from −y towards +x (a slope); returns (x displacement over [t₁, t₂], mean acceleration
/// along x over [t₁, t₂]).
fn on_slope(dim: usize, tan_alpha: f64, t1: f64, t2: f64) -> (f64, f64) {
    let mut cfg = block_on_floor(dim, 0.0);
    let alpha = tan_alpha.atan();
    let mut g = vec![0.0; dim];
    g[0] = 9.81 * alpha.sin();
    g[1] = -9.81 * alpha.cos();
    cfg.gravity = Some(g);
    let mut solid = build(&cfg, dim, 1);
    let block = ParticleId(solid.n_particles() as u32 - 1);
    let dt = 0.5 * solid.max_dt(f64::INFINITY);
    let mut marks = Vec::new();
    for t_mark in [t1, t2] {
        while solid.time() < t_mark {
            let r = solid.step_free(dt);
            assert!(r.diagnostics.is_empty(), "{:?}", r.diagnostics);
        }
        marks.push((
            solid.time(),
            solid.position(block)[0],
            solid.velocity(block)[0],
        ));
    }
    let (t1, x1, v1) = marks[0];
    let (t2, x2, v2) = marks[1];
    (x2 - x1, (v2 - v1) / (t2 - t1))
}

#[test]
fn friction_slides_a_block_at_the_coulomb_rate_and_creeps_below_the_limit() {
    for dim in [2usize, 3] {
        let alpha = 0.5f64.atan();
        let (_, accel) = on_slope(dim, 0.5, 0.1, 0.2);
        let expected = 9.81 * (alpha.sin() - 0.3 * alpha.cos());
        // FIXME(issue 10): the friction is regularised, so below the Coulomb limit the block
        // creeps at F_t / c_t instead of sticking (c_t = 2 √(k m), k = κ S²); a tangential
        // spring (Cundall–Strack) would hold it (tried: it held, but without torsional friction
        // the pushed 3-D bar half then twisted about the contact normal and kept spinning).
        let (creep, _) = on_slope(dim, 0.2, 0.5, 1.0);
        let mass = 1000.0 * A.powi(dim as i32);
        let h = A * (dim as f64).sqrt();
        let k = 1e6 / h.powi(dim as i32) * A.powi(2 * (dim as i32 - 1));
        let beta = 0.2f64.atan();
        let predicted = mass * 9.81 * beta.sin() / (2.0 * (k * mass).sqrt()) * 0.5;
        println!(
            "{dim}-D slope: tan α = 0.5 slides at {accel:.4} m/s² (Coulomb {expected:.4}); \
             tan α = 0.2 creeps {creep:.3e} m from 0.5 to 1 s (F_t/c_t predicts {predicted:.3e})"
        );
        assert!(
            (accel / expected - 1.0).abs() < 0.05,
            "{dim}-D: {accel} vs {expected}"
        );
        assert!(
            (creep / predicted - 1.0).abs() < 0.2,
            "{dim}-D: {creep} vs {predicted}"
        );
    }
}
