//! The fluid domain's walls as the solid sees them (`solid.walls = "hold"`, the default): rigid
//! planes, frictionless and perfectly inelastic, that a particle's vertices may touch but not
//! move further into.
//!
//! At each half kick of Verlet (both, so that the committed velocities keep the constraint too),
//! a free particle whose vertices lie on or beyond a wall plane (within [`TOUCH`] of its size)
//! has its velocities `u = (V, ω)` projected onto the cone of motions that take none of those
//! vertices further into the wall, in the metric of its mass matrix `M`:
//!
//! ```text
//! min ½ (u − u*)ᵀ M (u − u*)   subject to   J_i u = ν_i · (V + ω × r_i) ≥ 0   for each contact i
//! ```
//!
//! (`ν_i` the wall's inward normal, `r_i` the vertex relative to the centre). This is the
//! impulse of a frictionless, perfectly inelastic contact; the multipliers `λ ≥ 0` solve the
//! non-negative least-squares problem `min ‖B λ − d‖` with `B = M^{-1/2} Jᵀ`, `d = −M^{1/2} u*`
//! (Lawson & Hanson 1974, ch. 23), which terminates and tolerates the rank-deficient sets of
//! coplanar contacts that a face flush against a wall gives.
//!
//! The energy the walls take is counted as dissipated, per step and particle (`commit.rs`): what
//! Verlet's discrete identity gives for the other loads, `½ (F₁ + F₂)·ΔX + Δt²/(8m) (|F₂|² −
//! |F₁|²)`, less the change of kinetic energy. Counting the kinetic energy each projection
//! removes (`½ ‖B λ‖²`) would be wrong: a body held at rest loses the half kick's velocity twice
//! a step, which is no energy at all (the loads did no work), and that count grows as Δt².
//!
//! What it gives: a body resting flush against a wall under the gas's pressure stays at rest
//! (its load into the wall lies in the cone of the contact impulses; the projection returns
//! zero velocity to round-off), and a body thrown at a wall stops its motion into it and slides
//! along it. A particle whose velocities already satisfy every contact is left untouched, to the
//! bit.

use nalgebra::{DMatrix, DVector, Vector3};
use protocol::scene::{Boundary, BoundaryConfig};

use crate::dem::model::Model;

/// A vertex within `TOUCH × size` of a wall plane (or beyond it) touches the wall.
pub const TOUCH: f64 = 1e-9;

/// One wall plane: `axis`, the side (`upper`), and the plane's coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Plane {
    axis: usize,
    upper: bool,
    at: f64,
}

impl Plane {
    /// Inward normal (into the domain).
    fn normal(&self) -> Vector3<f64> {
        let mut n = Vector3::zeros();
        n[self.axis] = if self.upper { -1.0 } else { 1.0 };
        n
    }

    /// Signed distance of `y` from the plane, positive inside the domain.
    fn distance(&self, y: &Vector3<f64>) -> f64 {
        if self.upper {
            self.at - y[self.axis]
        } else {
            y[self.axis] - self.at
        }
    }
}

/// The wall planes and every particle's vertices (body frame, relative to its centre).
#[derive(Clone, Debug, Default)]
pub struct Walls {
    planes: Vec<Plane>,
    /// Per particle, range into `vertices` (CSR).
    start: Vec<u32>,
    vertices: Vec<Vector3<f64>>,
}

/// A particle's velocities after the walls acted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Held {
    /// Velocity of the centre \[m/s\].
    pub v: Vector3<f64>,
    /// 3-D: body-frame angular momentum `I ω`; 2-D: `[0, 0, ω]` (the state's convention).
    pub ang: Vector3<f64>,
}

impl Walls {
    /// The `wall` sides of the box `[lower, upper]` (the fluid's domain and boundary), for the
    /// particles of `model`. No plane: every query returns `None` at once.
    pub fn new(model: &Model, lower: &[f64], upper: &[f64], boundary: &BoundaryConfig) -> Walls {
        let dim = model.dim;
        let mut planes = Vec::new();
        for a in 0..dim {
            let sides = boundary.axis(a);
            for (s, side) in sides.iter().enumerate() {
                if *side == Boundary::Wall {
                    let at = if s == 0 { lower[a] } else { upper[a] };
                    planes.push(Plane {
                        axis: a,
                        upper: s == 1,
                        at,
                    });
                }
            }
        }
        let n = model.particles.len();
        let mut count = vec![0u32; n];
        for slot in &model.slots {
            count[slot.particle as usize] += 1;
        }
        let mut start = Vec::with_capacity(n + 1);
        start.push(0u32);
        for c in &count {
            start.push(start.last().unwrap() + c);
        }
        let mut fill = start.clone();
        let mut vertices = vec![Vector3::zeros(); model.slots.len()];
        for slot in &model.slots {
            let p = slot.particle as usize;
            vertices[fill[p] as usize] = slot.body;
            fill[p] += 1;
        }
        Walls {
            planes,
            start,
            vertices,
        }
    }

    /// Whether there is any wall.
    pub fn is_empty(&self) -> bool {
        self.planes.is_empty()
    }

    /// The velocities of particle `p` (centre `x`, mass `mass`, principal moments `inertia`,
    /// diameter `size`, body vectors turned into space by `turn`) after the walls acted on
    /// `(v, ang)`; `None` where no vertex touches a wall or no contact is violated (the
    /// particle is left as it is).
    #[allow(clippy::too_many_arguments)]
    pub fn hold(
        &self,
        dim: usize,
        p: usize,
        x: &Vector3<f64>,
        turn: &dyn Fn(&Vector3<f64>) -> Vector3<f64>,
        to_body: &dyn Fn(&Vector3<f64>) -> Vector3<f64>,
        (mass, inertia, size): (f64, [f64; 3], f64),
        (v, ang): (Vector3<f64>, Vector3<f64>),
    ) -> Option<Held> {
        if self.planes.is_empty() {
            return None;
        }
        let range = self.start[p] as usize..self.start[p + 1] as usize;
        // Generalised velocities u = (V, ω) with ω in the body frame (3-D) or about z (2-D),
        // and the square roots of the mass matrix's diagonal.
        let nr = if dim == 3 { 3 } else { 1 };
        let n = dim + nr;
        let mut sqrt_m = vec![mass.sqrt(); n];
        let mut u = DVector::zeros(n);
        for a in 0..dim {
            u[a] = v[a];
        }
        if dim == 3 {
            for a in 0..3 {
                sqrt_m[3 + a] = inertia[a].sqrt();
                u[3 + a] = ang[a] / inertia[a];
            }
        } else {
            sqrt_m[2] = inertia[0].sqrt();
            u[2] = ang[2];
        }
        let mut rows: Vec<DVector<f64>> = Vec::new();
        let mut violated = false;
        for plane in &self.planes {
            let normal = plane.normal();
            for r_body in &self.vertices[range.clone()] {
                let r = turn(r_body);
                if plane.distance(&(x + r)) > TOUCH * size {
                    continue;
                }
                let mut row = DVector::zeros(n);
                for a in 0..dim {
                    row[a] = normal[a];
                }
                if dim == 3 {
                    let arm = r_body.cross(&to_body(&normal));
                    for a in 0..3 {
                        row[3 + a] = arm[a];
                    }
                } else {
                    row[2] = r.x * normal.y - r.y * normal.x;
                }
                violated |= row.dot(&u) < 0.0;
                rows.push(row);
            }
        }
        if !violated {
            return None;
        }
        // B = M^{-1/2} Jᵀ (columns: contacts), d = −M^{1/2} u*.
        let m = rows.len();
        let b = DMatrix::from_fn(n, m, |i, j| rows[j][i] / sqrt_m[i]);
        let d = DVector::from_fn(n, |i, _| -sqrt_m[i] * u[i]);
        let lambda = nnls(&b, &d);
        let push = &b * &lambda;
        let mut held_v = v;
        let mut held_ang = ang;
        for i in 0..n {
            let du = push[i] / sqrt_m[i];
            if i < dim {
                held_v[i] = u[i] + du;
            } else if dim == 3 {
                held_ang[i - 3] = inertia[i - 3] * (u[i] + du);
            } else {
                held_ang[2] = u[i] + du;
            }
        }
        Some(Held {
            v: held_v,
            ang: held_ang,
        })
    }
}

/// Non-negative least squares, `argmin_{λ ≥ 0} ‖B λ − d‖` (Lawson & Hanson 1974, algorithm
/// NNLS): the active-set method, each passive set's least squares by SVD (the coplanar contacts
/// of a flush face are rank-deficient).
pub fn nnls(b: &DMatrix<f64>, d: &DVector<f64>) -> DVector<f64> {
    let (n, m) = b.shape();
    let mut x = DVector::zeros(m);
    let mut passive = vec![false; m];
    let scale = b.norm() * d.norm();
    let tol = 1e-14 * scale;
    let eps = 1e-12 * b.norm().max(f64::MIN_POSITIVE);
    for _ in 0..3 * m + 3 {
        let w = b.transpose() * (d - b * &x);
        let Some(t) = (0..m)
            .filter(|&j| !passive[j] && w[j] > tol)
            .max_by(|&i, &j| w[i].total_cmp(&w[j]))
        else {
            break;
        };
        passive[t] = true;
        for _ in 0..3 * m + 3 {
            let cols: Vec<usize> = (0..m).filter(|&j| passive[j]).collect();
            let sub = DMatrix::from_fn(n, cols.len(), |i, k| b[(i, cols[k])]);
            let z_sub = sub
                .svd(true, true)
                .solve(d, eps)
                .unwrap_or_else(|_| DVector::zeros(cols.len()));
            let mut z = DVector::zeros(m);
            for (k, &j) in cols.iter().enumerate() {
                z[j] = z_sub[k];
            }
            if cols.iter().all(|&j| z[j] > 0.0) {
                x = z;
                break;
            }
            let mut alpha = f64::INFINITY;
            for &j in &cols {
                if z[j] <= 0.0 {
                    alpha = alpha.min(x[j] / (x[j] - z[j]));
                }
            }
            x += (z - &x) * alpha;
            for &j in &cols {
                if x[j] <= 0.0 {
                    x[j] = 0.0;
                    passive[j] = false;
                }
            }
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The projection of a known case: min ‖λ₁ (1, 0) + λ₂ (1, 1) − (2, −1)‖ over λ ≥ 0 has
    /// λ = (2, 0) (the unconstrained optimum (3, −1) is infeasible).
    #[test]
    fn nnls_finds_the_constrained_optimum() {
        let b = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 0.0, 1.0]);
        let d = DVector::from_vec(vec![2.0, -1.0]);
        let x = nnls(&b, &d);
        assert!((x[0] - 2.0).abs() < 1e-15 && x[1] == 0.0, "{x}");
    }

    /// Two identical columns (coplanar contacts): any split is optimal, and the fit is exact.
    #[test]
    fn nnls_tolerates_dependent_columns() {
        let b = DMatrix::from_row_slice(2, 3, &[1.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        let d = DVector::from_vec(vec![3.0, 2.0]);
        let x = nnls(&b, &d);
        assert!(x.iter().all(|&v| v >= 0.0), "{x}");
        let r = &b * &x - &d;
        assert!(r.norm() < 1e-14, "residual {r}");
    }
}
