//! Helpers shared by the DEM verification tests: scene builders, seeded noise, zero crossings.

#![allow(dead_code, unreachable_pub)]

use protocol::scene::{
    BodyConfig, Boundary, BoundaryConfig, ConstraintConfig, FractureConfig, Motion, Region, Shape,
    SolidConfig,
};
use solid_node::dem::Solid;

/// Whether the long versions of the verification runs are wanted (`COSIM_SLOW_TESTS=1`).
pub fn slow() -> bool {
    std::env::var("COSIM_SLOW_TESTS").is_ok_and(|v| v == "1")
}

/// A material and one box body.
pub fn box_config(
    center: Vec<f64>,
    size: Vec<f64>,
    divisions: Vec<u32>,
    young: f64,
    poisson: f64,
    density: f64,
) -> SolidConfig {
    SolidConfig {
        node: "real".into(),
        density: Some(density),
        young: Some(young),
        poisson: Some(poisson),
        face_inertia: None,
        fracture: None,
        gravity: None,
        bodies: vec![BodyConfig {
            shape: Shape::Box { center, size },
            divisions,
            motion: Motion::Free,
            links: None,
        }],
        constraints: vec![],
        init: vec![],
        prescribed: None,
        contact: None,
        walls: None,
    }
}

/// Adds a constraint on the particles whose centre lies in the box `[lower, upper]`.
pub fn constrain(cfg: &mut SolidConfig, lower: Vec<f64>, upper: Vec<f64>, motion: Motion) {
    cfg.constraints.push(ConstraintConfig {
        region: Region::Box { lower, upper },
        motion,
    });
}

/// Turns fracture on.
pub fn with_fracture(cfg: &mut SolidConfig, elongation_at_break: f64) {
    cfg.fracture = Some(FractureConfig {
        elongation_at_break,
    });
}

/// Builds a solid, panicking with the message on a bad scene (a test bug).
pub fn build(cfg: &SolidConfig, dim: usize, threads: usize) -> Solid {
    Solid::from_scene(cfg, dim, threads).expect("test scene builds")
}

/// Seeded xorshift noise in [-1, 1).
pub struct Noise(pub u64);

impl Noise {
    /// Next value.
    pub fn next(&mut self) -> f64 {
        let s = &mut self.0;
        *s ^= *s << 13;
        *s ^= *s >> 7;
        *s ^= *s << 17;
        (*s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// Times of the upward zero crossings of a sampled signal (linear interpolation).
pub fn upward_crossings(t: &[f64], y: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 1..y.len() {
        if y[k - 1] < 0.0 && y[k] >= 0.0 {
            let s = -y[k - 1] / (y[k] - y[k - 1]);
            out.push(t[k - 1] + s * (t[k] - t[k - 1]));
        }
    }
    out
}

/// Mean period from upward crossings (first to last).
pub fn mean_period(crossings: &[f64]) -> f64 {
    assert!(
        crossings.len() >= 2,
        "need two crossings, got {}",
        crossings.len()
    );
    (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
}

/// Walls on every side of the box `[0, 1]^dim`.
pub fn walled(solid: &mut Solid, dim: usize) {
    let walls = Some([Boundary::Wall, Boundary::Wall]);
    let boundary = BoundaryConfig {
        x: walls,
        y: walls,
        z: if dim == 3 { walls } else { None },
    };
    solid.set_walls(&vec![0.0; dim], &vec![1.0; dim], &boundary);
}
