//! [`SolidFrame`]: the solid as the fluid's core sees it (particle kinematics and the wet
//! surface). The wire's `SolidState` becomes one in `crate::exchange`; the core imports no wire
//! type.

use serde::{Deserialize, Serialize};

use super::EmbeddedError;
use crate::cutcell::Surface;

/// The solid as the fluid sees it: particle kinematics and the wet surface.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SolidFrame {
    /// Spatial dimension, 2 or 3.
    pub dim: usize,
    /// Centres of mass \[m\], `dim` per particle.
    pub position: Vec<f64>,
    /// Velocities [m/s] (mid-step `V^{n+1/2}` of the step that produced the frame), `dim` each.
    pub velocity: Vec<f64>,
    /// Angular velocities [rad/s] in the global frame, 1 (2-D) or 3 (3-D) per particle.
    pub angular_velocity: Vec<f64>,
    /// Surface vertices \[m\], `dim` each.
    pub vertices: Vec<f64>,
    /// Elements, `dim` vertex indices each (normals out of the solid).
    pub elements: Vec<u32>,
    /// Particle of each element.
    pub element_particle: Vec<u32>,
    /// Whether each element touches the fluid.
    pub wet: Vec<bool>,
}

impl SolidFrame {
    /// The surface for the geometry.
    pub fn surface(&self) -> Surface<'_> {
        Surface {
            dim: self.dim,
            vertices: &self.vertices,
            elements: &self.elements,
            element_particle: &self.element_particle,
        }
    }

    /// The vertex positions of this frame on the connectivity of `next` (same elements, vertices
    /// renumbered, e.g. split where links broke): vertex `v` of `next` gets the position this
    /// frame's element had at the same corner.
    pub fn on_connectivity(&self, next: &SolidFrame) -> Result<Vec<f64>, EmbeddedError> {
        let d = self.dim;
        if next.elements.len() != self.elements.len()
            || next.element_particle != self.element_particle
        {
            return Err(EmbeddedError::ElementsChanged {
                step: None,
                before: self.elements.len(),
                after: next.elements.len(),
            });
        }
        let mut out = vec![f64::NAN; next.vertices.len()];
        for (&new, &old) in next.elements.iter().zip(&self.elements) {
            let (new, old) = (new as usize * d, old as usize * d);
            let src = &self.vertices[old..old + d];
            let dst = &mut out[new..new + d];
            if dst[0].is_nan() {
                dst.copy_from_slice(src);
            } else if dst != src {
                return Err(EmbeddedError::VertexFromTwo {
                    step: None,
                    vertex: new / d,
                });
            }
        }
        Ok(out)
    }

    /// Number of particles.
    pub fn n_particles(&self) -> usize {
        self.position.len() / self.dim
    }

    /// Centre of mass of particle `p` (third coordinate 0 in 2-D).
    pub fn center(&self, p: usize) -> [f64; 3] {
        let mut x = [0.0; 3];
        x[..self.dim].copy_from_slice(&self.position[p * self.dim..(p + 1) * self.dim]);
        x
    }

    /// Velocity of the point `x` moving with particle `p`: `V + Ω × (x − X)`.
    pub fn point_velocity(&self, p: usize, x: [f64; 3]) -> [f64; 3] {
        let c = self.center(p);
        self.rigid_velocity(p, [x[0] - c[0], x[1] - c[1], x[2] - c[2]])
    }

    /// Velocity `V + Ω × r` of the point at `r` from the centre of particle `p`.
    pub fn rigid_velocity(&self, p: usize, r: [f64; 3]) -> [f64; 3] {
        let d = self.dim;
        let mut v = [0.0; 3];
        v[..d].copy_from_slice(&self.velocity[p * d..(p + 1) * d]);
        if d == 2 {
            let w = self.angular_velocity[p];
            v[0] -= w * r[1];
            v[1] += w * r[0];
        } else {
            let w = &self.angular_velocity[3 * p..3 * p + 3];
            v[0] += w[1] * r[2] - w[2] * r[1];
            v[1] += w[2] * r[0] - w[0] * r[2];
            v[2] += w[0] * r[1] - w[1] * r[0];
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(vertices: Vec<f64>, elements: Vec<u32>) -> SolidFrame {
        let ne = elements.len() / 2;
        SolidFrame {
            dim: 2,
            position: vec![0.5, 0.5, 1.5, 0.5],
            velocity: vec![0.0; 4],
            angular_velocity: vec![0.0; 2],
            vertices,
            elements,
            element_particle: vec![0, 0, 1, 1][..ne].to_vec(),
            wet: vec![true; ne],
        }
    }

    #[test]
    fn a_split_vertex_starts_where_the_shared_one_was() {
        // Two segments sharing vertex 1 at t^n; at t^{n+1} the second starts at a new vertex 2.
        let before = frame(vec![0.0, 0.0, 1.0, 0.0, 2.0, 0.0], vec![0, 1, 1, 2]);
        let after = frame(
            vec![0.0, 0.1, 1.0, 0.1, 2.0, 0.1, 1.0, 0.2],
            vec![0, 1, 3, 2],
        );
        let remapped = before.on_connectivity(&after).unwrap();
        assert_eq!(remapped, [0.0, 0.0, 1.0, 0.0, 2.0, 0.0, 1.0, 0.0]);
        // One new vertex cannot come from two old ones.
        let merged = frame(vec![0.0, 0.0, 1.0, 0.0, 2.0, 0.0], vec![0, 1, 0, 2]);
        assert!(matches!(
            before.on_connectivity(&merged),
            Err(EmbeddedError::VertexFromTwo { vertex: 0, .. })
        ));
        // Other elements: refused.
        let fewer = frame(vec![0.0, 0.0, 1.0, 0.0], vec![0, 1]);
        assert!(matches!(
            before.on_connectivity(&fewer),
            Err(EmbeddedError::ElementsChanged {
                before: 4,
                after: 2,
                ..
            })
        ));
    }
}
