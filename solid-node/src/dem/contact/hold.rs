//! Contacts that hold: a pair whose overlap has passed [`HOLD_OVERLAP`] of the smaller
//! particle's volume stops approaching, as the domain's walls hold a particle
//! ([`crate::dem::walls`]).
//!
//! The penalty law of [`super`] stores `½ κ V²`; a pair meeting at a relative normal speed `w`
//! needs a depth of about `w / (c √s)` of a particle's size to store its kinetic energy (`c =
//! √(E/ρ)` the material's wave speed, `s` the stiffness factor). Fragments thrown together or
//! piled against a wall at a quarter of `c` reach the deep contact the step stops on
//! ([`super::DEEP_OVERLAP`]; issue 35: a 3-D shell at Mach 3.9 whose fragments pile against a
//! wall stopped at step 81).
//!
//! So at each half kick (both, like the walls), the pairs past [`HOLD_OVERLAP`] at the
//! configuration of that kick become constraints on the velocities: the relative velocity at
//! the overlap's centroid `G`, along the direction `n` of the elastic force on B, may not
//! bring B further towards A,
//!
//! ```text
//! n · [(V_B + Ω_B × (G − X_B)) − (V_A + Ω_A × (G − X_A))] ≥ 0,
//! ```
//!
//! held by frictionless, perfectly inelastic impulses `±λ n` at `G`, `λ ≥ 0`, found by projected
//! Gauss–Seidel over the pairs in their order (deterministic; accumulated impulses, so an impulse
//! that an earlier pair's made too large is taken back). Fixed and driven particles take no
//! impulse. The energy the impulses take is counted as the walls' is, from Verlet's discrete
//! identity (`solid/commit.rs`, `wall_loss`), so the ledger stays closed. A pair that separates
//! or slides is left alone: the elastic force still pushes the two apart.
//!
//! Below [`HOLD_OVERLAP`] nothing changes: scenes whose contacts stay shallower compute the same
//! bits as without holds.

use nalgebra::Vector3;

use super::Contact;
use crate::dem::model::{Model, ParticleMotion};

/// Overlap, as a fraction of the smaller particle's volume, past which a pair holds.
pub const HOLD_OVERLAP: f64 = 0.1;

/// Sweeps of the projected Gauss–Seidel at most.
const MAX_SWEEPS: usize = 500;

/// One pair that holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairHold {
    /// Particle A (the smaller index).
    pub a: usize,
    /// Particle B.
    pub b: usize,
    /// Centroid of the overlap \[m\].
    pub centroid: Vector3<f64>,
    /// Unit direction of the elastic force on B (from A to B).
    pub normal: Vector3<f64>,
}

impl Contact {
    /// The pairs of the last evaluation whose overlap is past [`HOLD_OVERLAP`], in pair order.
    pub fn holds(&self, model: &Model) -> Vec<PairHold> {
        let mut holds = Vec::new();
        for pair in &self.pairs {
            let (a, b) = (pair.a as usize, pair.b as usize);
            let volume = model.particles[a].volume.min(model.particles[b].volume);
            let norm = pair.force_b.norm();
            if pair.overlap.volume > HOLD_OVERLAP * volume && norm > 0.0 {
                holds.push(PairHold {
                    a,
                    b,
                    centroid: pair.overlap.centroid,
                    normal: pair.force_b / norm,
                });
            }
        }
        holds
    }
}

/// One particle's side of the projection: its centre, orientation (`turn`: body to space, and
/// back) and velocities in the state's convention (`ang`: 3-D body-frame angular momentum
/// `I ω`; 2-D `[0, 0, ω]`).
pub struct Kinematics<'a> {
    /// Space dimension.
    pub dim: usize,
    /// Centres.
    pub x: &'a [[f64; 3]],
    /// Body vector of particle `p` turned into space.
    pub turn: &'a dyn Fn(usize, &Vector3<f64>) -> Vector3<f64>,
    /// Space vector turned into particle `p`'s body frame.
    pub to_body: &'a dyn Fn(usize, &Vector3<f64>) -> Vector3<f64>,
}

/// Projects the velocities `v` and `ang` of the particles in `holds` so that no pair approaches
/// further (see the module docs); `touched[p]` is set for every particle an impulse changed.
/// Returns the number of sweeps.
pub fn project(
    model: &Model,
    k: &Kinematics<'_>,
    holds: &[PairHold],
    v: &mut [Vector3<f64>],
    ang: &mut [Vector3<f64>],
    touched: &mut [bool],
) -> usize {
    let free = |p: usize| model.particles[p].motion == ParticleMotion::Free;
    // Per hold and side: lever arm, `r × n` in the body frame (3-D) or about z (2-D), and the
    // inverse effective mass of the pair along `n`.
    struct Row {
        r: [Vector3<f64>; 2],
        c: [Vector3<f64>; 2],
        inv_mass: f64,
    }
    let rows: Vec<Row> = holds
        .iter()
        .map(|h| {
            let mut row = Row {
                r: [Vector3::zeros(); 2],
                c: [Vector3::zeros(); 2],
                inv_mass: 0.0,
            };
            for (s, p) in [h.a, h.b].into_iter().enumerate() {
                row.r[s] = h.centroid - Vector3::from(k.x[p]);
                if !free(p) {
                    continue;
                }
                let part = &model.particles[p];
                let rn = row.r[s].cross(&h.normal);
                row.inv_mass += 1.0 / part.mass;
                if k.dim == 3 {
                    let c = (k.to_body)(p, &rn);
                    row.inv_mass += (0..3).map(|a| c[a] * c[a] / part.inertia[a]).sum::<f64>();
                    row.c[s] = c;
                } else {
                    row.inv_mass += rn.z * rn.z / part.inertia[0];
                    row.c[s] = Vector3::new(0.0, 0.0, rn.z);
                }
            }
            row
        })
        .collect();
    let omega = |p: usize, ang: &[Vector3<f64>]| -> Vector3<f64> {
        let part = &model.particles[p];
        if k.dim == 3 {
            let w_body = Vector3::new(
                ang[p][0] / part.inertia[0],
                ang[p][1] / part.inertia[1],
                ang[p][2] / part.inertia[2],
            );
            (k.turn)(p, &w_body)
        } else {
            Vector3::new(0.0, 0.0, ang[p][2])
        }
    };
    let mut lambda = vec![0.0f64; holds.len()];
    let mut sweeps = 0;
    while sweeps < MAX_SWEEPS {
        sweeps += 1;
        let mut largest: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for (i, (h, row)) in holds.iter().zip(&rows).enumerate() {
            if row.inv_mass <= 0.0 {
                continue;
            }
            let point = |s: usize, p: usize, v: &[Vector3<f64>], ang: &[Vector3<f64>]| {
                v[p] + omega(p, ang).cross(&row.r[s])
            };
            let w = h
                .normal
                .dot(&(point(1, h.b, v, ang) - point(0, h.a, v, ang)));
            let next = (lambda[i] - w / row.inv_mass).max(0.0);
            let dl = next - lambda[i];
            lambda[i] = next;
            scale = scale.max(next);
            if dl == 0.0 {
                continue;
            }
            largest = largest.max(dl.abs());
            for (s, p, sign) in [(0, h.a, -1.0), (1, h.b, 1.0)] {
                if !free(p) {
                    continue;
                }
                let part = &model.particles[p];
                v[p] += h.normal * (sign * dl / part.mass);
                if k.dim == 3 {
                    // Angular momentum about the centre, in the body frame: `c = R^T (r × n)`.
                    ang[p] += row.c[s] * (sign * dl);
                } else {
                    ang[p].z += sign * dl * row.c[s].z / part.inertia[0];
                }
                touched[p] = true;
            }
        }
        if largest <= 1e-14 * scale {
            break;
        }
    }
    sweeps
}
