//! Lever arms of the semi-implicit loads and of the solid flux's face velocity (issue 37).
//!
//! A sub-face's load `f` turns its particle by `r × f` and the solid flux gives the fluid the
//! power `(V + Ω × r) · (−f)`: the same `r` in both keeps the exchange exact, whatever `r` is.
//! Paper 003 takes `r = X_f − X`, both on `F^{n+1}` (the end levers). With the loads held over a
//! long coupling step (`run.solid_substeps`, docs/subcycling.md) the lever arms take the surface
//! at `t^n`,
//!
//! ```text
//! r = X_f^n − X^n,
//! ```
//!
//! `X_f^n` the preimage of the sub-face's centroid on its element at `t^n` (same barycentric
//! coordinates, as the swept prisms take it). What the choice of `r` moves is the lever part of
//! the fluid's stiffness, `(∂r/∂θ) × f` with the force held: for a face point moving with a
//! convex particle that holds its centre, it is `p A (r·n) ≥ 0` (2-D), a torque in the sense
//! the particle turns (a negative stiffness `s`; on the mean-vertex surface a face slides by the
//! mean of its two particles' rigid slides, the same sign). Held over the step, end levers give
//! a mode `s θ^{n+1} Δθ`, `s Δθ²/2` more than the potential `s (θ^{n+1}² − θ^n²)/2` (they pump
//! it), levers at `t^n` `s θ^n Δθ`, `s Δθ²/2` less (they damp it), mid-step ones exactly the
//! potential. The levers at `t^n` are taken because the fluid's torque on the thin shell's
//! rotational modes also has a part in phase with the step's motion that the levers do not
//! touch (from the pressures the held loads take: 4e-5 to 1.5e-4 N m/rad times `Δθ` on modes
//! 1 to 3, against a lever stiffness `s` of 3.2e-4 to 3.7e-4): mid-step levers leave it to
//! grow, those at `t^n` take `s/2` off it (docs/subcycling.md, "The levers at tⁿ"). In 3-D a
//! face whose centre of pressure is off the foot of its perpendicular has a restoring lever
//! stiffness about some axes, which these levers would pump; no 3-D case was measured.

use std::borrow::Cow;

use super::SolidFrame;
use crate::cutcell::{SubFace, Surface};

/// Where the lever arms of one surface's sub-faces start.
pub(super) struct Levers<'a> {
    frame: &'a SolidFrame,
    /// `F^n` on `frame`'s connectivity, and the frame of `X^n` (None: the end levers).
    before: Option<(Cow<'a, [f64]>, &'a SolidFrame)>,
}

impl<'a> Levers<'a> {
    /// The levers of the sub-faces of `frame` (`F^{n+1}`): on `current` (`F^n`) when `start`,
    /// on `frame` otherwise. Levers at `t^n` need `F^n` on `frame`'s connectivity; where it has
    /// none (other elements or particles) they are the end levers, for the loads and the solid
    /// flux alike.
    pub(super) fn new(start: bool, current: &'a SolidFrame, frame: &'a SolidFrame) -> Levers<'a> {
        let before = if !start || current.n_particles() != frame.n_particles() {
            None
        } else if current.elements == frame.elements {
            Some((Cow::Borrowed(&current.vertices[..]), current))
        } else {
            current
                .on_connectivity(frame)
                .ok()
                .map(|v| (Cow::Owned(v), current))
        };
        Levers { frame, before }
    }

    /// The lever of sub-face `s` of `frame` about its particle's centre.
    pub(super) fn lever(&self, s: &SubFace) -> [f64; 3] {
        let p = s.particle as usize;
        let x1 = self.frame.center(p);
        let c = s.centroid;
        let end = [c[0] - x1[0], c[1] - x1[1], c[2] - x1[2]];
        let Some((vertices, current)) = &self.before else {
            return end;
        };
        let before = Surface {
            dim: self.frame.dim,
            vertices,
            elements: &self.frame.elements,
            element_particle: &self.frame.element_particle,
        };
        let e = s.element as usize;
        let (Some(t1), Some(t0)) = (self.frame.surface().element(e), before.element(e)) else {
            return end;
        };
        let c0 = preimage(self.frame.dim, &t1, &t0, c);
        let x0 = current.center(p);
        [c0[0] - x0[0], c0[1] - x0[1], c0[2] - x0[2]]
    }
}

/// The point of element `t0` with the barycentric coordinates that `x` has in `t1` (2-D: the
/// parameter along the segment `t1[0] t1[1]`; 3-D: the triangle, `x` projected on its plane).
/// A degenerate `t1` maps every point to `t0[0]`.
pub(super) fn preimage(
    dim: usize,
    t1: &[[f64; 3]; 3],
    t0: &[[f64; 3]; 3],
    x: [f64; 3],
) -> [f64; 3] {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let q = sub(x, t1[0]);
    let e1 = sub(t1[1], t1[0]);
    let (u, v) = if dim == 2 {
        let l2 = dot(e1, e1);
        (if l2 > 0.0 { dot(q, e1) / l2 } else { 0.0 }, 0.0)
    } else {
        let e2 = sub(t1[2], t1[0]);
        let (a, b, c) = (dot(e1, e1), dot(e1, e2), dot(e2, e2));
        let det = a * c - b * b;
        if det > 0.0 {
            let (q1, q2) = (dot(q, e1), dot(q, e2));
            ((c * q1 - b * q2) / det, (a * q2 - b * q1) / det)
        } else {
            (0.0, 0.0)
        }
    };
    let mut out = [0.0; 3];
    for k in 0..3 {
        out[k] = t0[0][k] + u * (t0[1][k] - t0[0][k]) + v * (t0[2][k] - t0[0][k]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_preimage_keeps_the_barycentric_coordinates() {
        // 2-D: a quarter along a segment that doubled and moved.
        let t1 = [[1.0, 1.0, 0.0], [3.0, 1.0, 0.0], [0.0; 3]];
        let t0 = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0; 3]];
        assert_eq!(preimage(2, &t1, &t0, [1.5, 1.0, 0.0]), [0.0, 0.25, 0.0]);
        // 3-D: (u, v) = (0.25, 0.5) in a triangle, mapped onto a translated and scaled one.
        let t1 = [[0.0; 3], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0]];
        let t0 = [[1.0, 1.0, 1.0], [3.0, 1.0, 1.0], [1.0, 3.0, 1.0]];
        assert_eq!(preimage(3, &t1, &t0, [1.0, 2.0, 0.0]), [1.5, 2.0, 1.0]);
    }
}
