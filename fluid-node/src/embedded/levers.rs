//! Lever arms of the semi-implicit loads and of the solid flux's face velocity (issue 37).
//!
//! A sub-face's load `f` turns its particle by `r × f` and the solid flux gives the fluid the
//! power `(V + Ω × r) · (−f)`: the same `r` in both keeps the exchange exact. Paper 003 takes
//! `r = X_f − X`, both on `F^{n+1}` (the end levers). With the loads held over a long coupling
//! step (`run.solid_substeps`, docs/subcycling.md) that reading leads the motion by `dt/2`: on
//! the mean-vertex wet surface the faces of particles turning together stay parallel and slide
//! along themselves, so a pressure torques the particles in the sense they turn (a negative
//! stiffness `s`), and a torque `s θ^{n+1}` held over the step gives the mode `s Δθ²/2` more
//! than the `s (θ^n + θ^{n+1})/2 · Δθ` of the motion, every step: the thin shell's slowest
//! rotational mode grows. The mid-step levers take `r` between the mid-step positions of the
//! face point and of the centre,
//!
//! ```text
//! r = ½ [(X_f − X^{n+1}) + (X_f^n − X^n)],
//! ```
//!
//! `X_f^n` the preimage of the sub-face's centroid on its element at `t^n` (same barycentric
//! coordinates, as the swept prisms take it): the torque is the trapezoid's,
//! `s (θ^n + θ^{n+1})/2`, whose work over the step, `s (θ^{n+1}² − θ^n²)/2`, telescopes, and
//! `V̄ + Ω̄ × r` is the face point's mean velocity over the step to O(φ³) for a rigid motion
//! (`V̄`, `Ω̄` the step's mean motion the solid sends).

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
    /// The levers of the sub-faces of `frame` (`F^{n+1}`): at mid-step from `current` (`F^n`)
    /// when `mid`, at the end otherwise. Mid-step levers need `F^n` on `frame`'s connectivity;
    /// where it has none (other elements or particles) they are the end levers, for the loads
    /// and the solid flux alike.
    pub(super) fn new(mid: bool, current: &'a SolidFrame, frame: &'a SolidFrame) -> Levers<'a> {
        let before = if !mid || current.n_particles() != frame.n_particles() {
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
        let mut r = [0.0; 3];
        for a in 0..3 {
            r[a] = 0.5 * (end[a] + (c0[a] - x0[a]));
        }
        r
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
