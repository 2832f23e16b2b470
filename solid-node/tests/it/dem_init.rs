//! `[[solid.init]]` in the real solid: the particles whose centre lies in a region start with the
//! entry's velocity and spin, entries apply in order, prescribed motions are kept, and the initial
//! `SolidState`, momentum and kinetic energy show it.

use nalgebra::{Matrix3, Rotation3, Vector3};
use protocol::scene::Scene;
use protocol::session::NodeModel;
use protocol::wire::Stamp;
use solid_node::dem::{ParticleId, ParticleMotion, Solid};
use solid_node::exchange::RealSolid;
use solid_node::model::SolidModel;

fn scene(text: &str) -> Scene {
    Scene::from_toml_str(text, "test").unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// A 4 × 10 box of 0.1 m squares, centres at y = 0.05, 0.15, …, 0.95.
const BOX_2D: &str = r#"
name = "spin-up"
[solid]
density = 1000.0
young = 1e6
poisson = 0.0
[[solid.bodies]]
shape = { box = { center = [2.0, 0.5], size = [0.4, 1.0] } }
divisions = [4, 10]
"#;

#[test]
fn upper_half_of_a_box_starts_at_the_init_velocity() {
    let text = format!(
        "{BOX_2D}
[[solid.init]]
region = {{ box = {{ lower = [1.8, 0.5], upper = [2.2, 1.0] }} }}
velocity = [0.25, 0.0]
"
    );
    let scene = scene(&text);
    let real = RealSolid::from_scene(&scene).expect("builds");
    let state = real.state();
    let solid = Solid::from_scene(scene.solid.as_ref().unwrap(), 2, 1).expect("builds");
    let n = solid.n_particles();
    assert_eq!(n, 40);
    assert_eq!(state.velocity.len(), 2 * n);
    let mut n_moving = 0;
    let mut expected = [0.0; 2];
    for p in 0..n {
        let x = solid.position(ParticleId(p as u32));
        let upper = x[1] > 0.5;
        let v = &state.velocity[2 * p..2 * p + 2];
        let want = if upper { [0.25, 0.0] } else { [0.0, 0.0] };
        assert!(
            close(v[0], want[0], 1e-15) && close(v[1], want[1], 1e-15),
            "particle {p} at {x:?}: v = {v:?}, expected {want:?}"
        );
        assert_eq!(solid.velocity(ParticleId(p as u32))[..2], want);
        assert_eq!(state.angular_velocity[p], 0.0);
        if upper {
            n_moving += 1;
            let m = solid.model().particles[p].mass;
            expected[0] += m * 0.25;
        }
    }
    assert_eq!(n_moving, 20, "the five upper rows");
    // Σ m v: 20 particles of 1000 kg/m³ × 0.01 m² (per unit depth) at 0.25 m/s = 50 kg m/s.
    assert!(close(expected[0], 50.0, 1e-12 * 50.0), "{}", expected[0]);
    let totals = real.totals(Stamp::step(0), 0.0);
    assert!(
        close(totals.momentum[0], expected[0], 1e-12 * expected[0]),
        "momentum {:?} vs {expected:?}",
        totals.momentum
    );
    assert!(close(totals.momentum[1], 0.0, 1e-12 * expected[0]));
    let p_lin = solid.momentum().linear;
    assert!(close(p_lin[0], expected[0], 1e-12 * expected[0]));
    // ½ m v² of the moving half: ½ × 200 kg × 0.0625 m²/s² = 6.25 J.
    let e = solid.energies();
    assert!(close(e.kinetic_translation, 6.25, 1e-12 * 6.25));
    // The committed wet surface moves with its particles.
    let wet = solid.wet_surface();
    for e in 0..wet.n_elements() {
        let p = wet.element_particle[e] as usize;
        let v = &wet.velocity[2 * e..2 * e + 2];
        let want = if solid.position(ParticleId(p as u32))[1] > 0.5 {
            0.25
        } else {
            0.0
        };
        assert!(close(v[0], want, 1e-15) && close(v[1], 0.0, 1e-15), "{v:?}");
    }
}

#[test]
fn later_init_entries_override_earlier_ones_but_not_prescribed_motions() {
    let text = format!(
        "{BOX_2D}
[[solid.bodies]]
shape = {{ box = {{ center = [3.0, 0.5], size = [0.2, 0.2] }} }}
divisions = [1, 1]
motion = {{ velocity = [0.0, 0.1] }}

[[solid.constraints]]
region = {{ box = {{ lower = [1.8, 0.0], upper = [2.2, 0.1] }} }}
motion = \"fixed\"

[[solid.init]]
region = \"all\"
velocity = [0.0, -1.0]
angular_velocity = [2.0]

[[solid.init]]
region = {{ half_space = {{ point = [0.0, 0.5], normal = [0.0, -1.0] }} }}
velocity = [0.25, 0.0]
"
    );
    let scene = scene(&text);
    let state = RealSolid::from_scene(&scene).expect("builds").state();
    let solid = Solid::from_scene(scene.solid.as_ref().unwrap(), 2, 1).expect("builds");
    let n = solid.n_particles();
    assert_eq!(n, 41);
    for p in 0..n {
        let x = solid.position(ParticleId(p as u32));
        let motion = solid.model().particles[p].motion;
        let (v_want, w_want) = match motion {
            ParticleMotion::Fixed => ([0.0, 0.0], 0.0),
            ParticleMotion::Velocity(v) => ([v[0], v[1]], 0.0),
            ParticleMotion::Free if x[1] > 0.5 => ([0.25, 0.0], 2.0),
            ParticleMotion::Free => ([0.0, -1.0], 2.0),
        };
        let v = &state.velocity[2 * p..2 * p + 2];
        assert!(
            close(v[0], v_want[0], 1e-15) && close(v[1], v_want[1], 1e-15),
            "particle {p} ({motion:?}) at {x:?}: v = {v:?}, expected {v_want:?}"
        );
        assert!(close(state.angular_velocity[p], w_want, 1e-15));
    }
    let n_fixed = (0..n)
        .filter(|&p| solid.model().particles[p].motion == ParticleMotion::Fixed)
        .count();
    assert_eq!(n_fixed, 4, "the bottom row");
    assert_eq!(state.velocity[2 * 40..], [0.0, 0.1], "the prescribed body");
}

#[test]
fn spinning_particle_in_2d_reports_its_angular_velocity_and_energy() {
    let omega = 3.0;
    let scene = scene(
        r#"
name = "spin"
[solid]
density = 1000.0
young = 1e6
poisson = 0.0
[[solid.bodies]]
shape = { box = { center = [0.0, 0.0], size = [0.3, 0.2] } }
divisions = [1, 1]
[[solid.init]]
region = { ball = { center = [0.0, 0.0], radius = 0.01 } }
angular_velocity = [3.0]
"#,
    );
    let real = RealSolid::from_scene(&scene).expect("builds");
    let state = real.state();
    assert_eq!(state.angular_velocity.len(), 1);
    assert!(close(state.angular_velocity[0], omega, 1e-12 * omega));
    assert_eq!(state.velocity, [0.0, 0.0]);
    // I = ρ a b (a² + b²)/12 = 1000 × 0.06 × 0.13 / 12 = 0.65 kg m² (per unit depth).
    let inertia = 1000.0 * 0.3 * 0.2 * (0.09 + 0.04) / 12.0;
    let e_want = 0.5 * inertia * omega * omega;
    let totals = real.totals(Stamp::step(0), 0.0);
    assert!(
        close(totals.energy, e_want, 1e-12 * e_want),
        "energy {} vs ½ I ω² = {e_want}",
        totals.energy
    );
    let mut solid = Solid::from_scene(scene.solid.as_ref().unwrap(), 2, 1).expect("builds");
    let e = solid.energies();
    assert!(close(e.kinetic_rotation, e_want, 1e-12 * e_want));
    assert!(close(e.kinetic_translation, 0.0, 1e-15));
    // A torque-free step turns it by ω dt exactly (2-D rotation about a fixed axis).
    let dt = 1e-3;
    let report = solid.step_free(dt);
    assert!(report.diagnostics.is_empty(), "{:?}", report.diagnostics);
    let angle = solid.orientation(ParticleId(0))[0];
    assert!(
        close(angle, omega * dt, 1e-12 * omega * dt),
        "angle {angle}"
    );
    assert!(close(
        solid.angular_velocity(ParticleId(0))[2],
        omega,
        1e-12 * omega
    ));
}

#[test]
fn spin_about_a_non_principal_axis_in_3d_sets_angular_momentum_from_the_inertia_tensor() {
    // One box particle of edges a, b, c turned by R, so that its principal axes are not the
    // coordinate axes, spun about ω = (1, 2, 3) rad/s: L = R diag(I) Rᵀ ω, E = ½ ω · L.
    let (a, b, c) = (0.3, 0.2, 0.1);
    let rot = Rotation3::from_euler_angles(0.3, -0.4, 0.7);
    let mut vertices = Vec::new();
    for sx in [-0.5, 0.5] {
        for sy in [-0.5, 0.5] {
            for sz in [-0.5, 0.5] {
                let v = rot * Vector3::new(sx * a, sy * b, sz * c);
                vertices.push(format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z));
            }
        }
    }
    let omega = Vector3::new(1.0, 2.0, 3.0);
    let scene = scene(&format!(
        r#"
name = "top"
[solid]
density = 1000.0
young = 1e6
poisson = 0.0
[[solid.bodies]]
shape = {{ particles = [{{ vertices = [{}] }}] }}
[[solid.init]]
region = "all"
angular_velocity = [1.0, 2.0, 3.0]
"#,
        vertices.join(", ")
    ));
    let mass = 1000.0 * a * b * c;
    let principal = Matrix3::from_diagonal(&Vector3::new(
        mass * (b * b + c * c) / 12.0,
        mass * (a * a + c * c) / 12.0,
        mass * (a * a + b * b) / 12.0,
    ));
    let tensor = rot.matrix() * principal * rot.matrix().transpose();
    let l_want = tensor * omega;
    let e_want = 0.5 * omega.dot(&l_want);

    let real = RealSolid::from_scene(&scene).expect("builds");
    let state = real.state();
    let w = Vector3::from_column_slice(&state.angular_velocity);
    assert!(
        (w - omega).norm() <= 1e-12 * omega.norm(),
        "state ω = {w:?}"
    );
    let solid = Solid::from_scene(scene.solid.as_ref().unwrap(), 3, 1).expect("builds");
    assert!(close(solid.model().particles[0].mass, mass, 1e-12 * mass));
    let w = Vector3::from(solid.angular_velocity(ParticleId(0)));
    assert!((w - omega).norm() <= 1e-12 * omega.norm(), "ω = {w:?}");
    let l = Vector3::from(solid.momentum().angular);
    assert!(
        (l - l_want).norm() <= 1e-12 * l_want.norm(),
        "L = {l:?}, expected {l_want:?}"
    );
    let e = solid.energies();
    assert!(
        close(e.kinetic_rotation, e_want, 1e-12 * e_want),
        "E = {}, expected {e_want}",
        e.kinetic_rotation
    );
    // ω is not an eigenvector of the tensor: L is not parallel to it.
    assert!(l_want.cross(&omega).norm() > 1e-3 * l_want.norm() * omega.norm());
}
