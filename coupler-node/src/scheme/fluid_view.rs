//! What the fluid gets of a solid state (issue 39 item 4).
//!
//! The fluid reads the kinematics of the particles its surface's elements belong to, and loads
//! only those. A body's inner particles own no element when fracture is off (the wet surface
//! carries its boundary faces only), and they were most of every state the coupler sent the
//! fluid and of every load array it sent back: in `clamped-beam-2d` 124 of 728 particles own an
//! element. So the coupler sends the fluid those particles only, numbered in their order and
//! named in [`SolidState::particles`]; the fluid's loads name the same particles
//! (`InterfaceLoads::particles`) and go to the solid as they are, which puts them at their
//! particles with zeros elsewhere. Each particle's load is the fluid's sum over its own
//! sub-faces, whatever the numbering, so the solid takes the bits it took from the whole state's
//! loads; what shrinks is every state the fluid gets and every load array.

use protocol::wire::{SolidState, n_orientation, n_rot};

/// The particles the elements of `s` belong to, ascending, in the solid's numbering; `None`
/// when they are all of them (the state then goes to the fluid whole).
pub(super) fn owners(s: &SolidState) -> Option<Vec<u32>> {
    if !s.particles.is_empty() {
        // Already a view (a state the coupler made, or a double's): sent as it is.
        return None;
    }
    let n = s.n_particles();
    let mut owns = vec![false; n];
    for &p in &s.surface.element_particle {
        // (Checked on receipt: `check_state` refuses an element of a particle beyond `n`.)
        if let Some(o) = owns.get_mut(p as usize) {
            *o = true;
        }
    }
    if owns.iter().all(|&o| o) {
        return None;
    }
    Some((0..n as u32).filter(|&p| owns[p as usize]).collect())
}

/// The state the fluid gets: the particles the elements belong to, in their order (see the
/// module docs).
pub(super) fn for_fluid(s: &SolidState) -> SolidState {
    let Some(kept) = owners(s) else {
        return s.clone();
    };
    let dim = s.dim as usize;
    let (ori, rot) = (n_orientation(s.dim), n_rot(s.dim));
    let pick = |values: &[f64], width: usize| -> Vec<f64> {
        (kept.iter())
            .flat_map(|&p| &values[p as usize * width..(p as usize + 1) * width])
            .copied()
            .collect()
    };
    let mut index = vec![u32::MAX; s.n_particles()];
    for (i, &p) in kept.iter().enumerate() {
        index[p as usize] = i as u32;
    }
    let mut surface = s.surface.clone();
    for p in &mut surface.element_particle {
        *p = index[*p as usize];
    }
    SolidState {
        stamp: s.stamp,
        dim: s.dim,
        position: pick(&s.position, dim),
        orientation: pick(&s.orientation, ori),
        velocity: pick(&s.velocity, dim),
        angular_velocity: pick(&s.angular_velocity, rot),
        diameter: pick(&s.diameter, 1),
        surface,
        particles: kept,
        changed_only: false,
    }
}

#[cfg(test)]
mod tests {
    use protocol::wire::{Stamp, WetSurface};

    use super::*;

    /// Five particles in 3-D with distinct values everywhere; the elements belong to 4, 1 and
    /// 4 again (0, 2 and 3 own none).
    fn state() -> SolidState {
        let n = 5;
        let seq = |k: usize, base: f64| (0..k).map(|i| base + i as f64 * 0.25).collect();
        SolidState {
            stamp: Stamp {
                step: 3,
                iteration: 2,
            },
            dim: 3,
            position: seq(3 * n, 1.0),
            orientation: seq(4 * n, 10.0),
            velocity: seq(3 * n, 20.0),
            angular_velocity: seq(3 * n, 30.0),
            diameter: seq(n, 40.0),
            surface: WetSurface {
                revision: 7,
                dim: 3,
                vertices: seq(12, 50.0),
                elements: vec![0, 1, 2, 1, 2, 3, 2, 3, 0],
                element_particle: vec![4, 1, 4],
                wet: vec![true, false, true],
            },
            particles: Vec::new(),
            changed_only: false,
        }
    }

    #[test]
    fn the_fluid_gets_the_particles_the_elements_belong_to_with_their_values() {
        let s = state();
        let v = for_fluid(&s);
        assert_eq!(v.particles, vec![1, 4]);
        assert_eq!(v.n_particles(), 2);
        // Particle i of the view is particle `particles[i]` of the state, every value the same.
        for (i, &p) in v.particles.iter().enumerate() {
            let p = p as usize;
            assert_eq!(v.position[3 * i..3 * i + 3], s.position[3 * p..3 * p + 3]);
            assert_eq!(
                v.orientation[4 * i..4 * i + 4],
                s.orientation[4 * p..4 * p + 4]
            );
            assert_eq!(v.velocity[3 * i..3 * i + 3], s.velocity[3 * p..3 * p + 3]);
            let (w, ws) = (&v.angular_velocity, &s.angular_velocity);
            assert_eq!(w[3 * i..3 * i + 3], ws[3 * p..3 * p + 3]);
            assert_eq!(v.diameter[i], s.diameter[p]);
            assert_eq!(v.particle_id(i), p as u32);
        }
        // Each element keeps its particle, by the solid's number.
        let owners: Vec<u32> = (v.surface.element_particle.iter())
            .map(|&i| v.particle_id(i as usize))
            .collect();
        assert_eq!(owners, s.surface.element_particle);
        // The rest of the surface and the stamp go as they are.
        let (mut a, mut b) = (v.surface.clone(), s.surface.clone());
        a.element_particle.clear();
        b.element_particle.clear();
        assert_eq!(a, b);
        assert_eq!(v.stamp, s.stamp);
    }

    #[test]
    fn a_state_whose_particles_all_own_an_element_or_a_view_goes_as_it_is() {
        let mut s = state();
        s.surface.element_particle = vec![0, 1, 2];
        s.surface.elements.extend([0, 1, 3, 1, 2, 3]);
        s.surface.element_particle.extend([3, 4]);
        s.surface.wet.extend([true, true]);
        assert_eq!(owners(&s), None);
        assert_eq!(for_fluid(&s), s);
        let v = for_fluid(&state());
        assert_eq!(owners(&v), None);
        assert_eq!(for_fluid(&v), v);
    }
}
