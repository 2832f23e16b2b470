//! A trial after a step's first, sent as the particles that changed (issue 39 item 4).
//!
//! In the semi-implicit scheme the solid holds its internal forces through a step's fixed-point
//! iteration, so from one trial to the next only the particles the fluid pushes (those with wet
//! faces) move differently. The solid sends its first trial whole and each later one as the
//! particles whose kinematics differ from the first trial's, bit for bit
//! ([`SolidState::changes_from`]); the coupler puts them back onto the first trial
//! ([`SolidState::merged_onto`]) and reads only whole states. The whole state is the solid's
//! trial bit for bit, whatever the scheme: a particle is left out only when all of its values
//! have the first trial's bits, not because the scheme says it cannot have moved.

use super::{SolidState, n_orientation, n_rot};

/// The per-particle arrays of a state and their strides, in one order.
fn columns(s: &SolidState) -> [(&Vec<f64>, usize); 5] {
    let dim = s.dim as usize;
    [
        (&s.position, dim),
        (&s.orientation, n_orientation(s.dim)),
        (&s.velocity, dim),
        (&s.angular_velocity, n_rot(s.dim)),
        (&s.diameter, 1),
    ]
}

/// Whether every array of `s` holds `n` particles' values.
fn fits(s: &SolidState, n: usize) -> bool {
    columns(s).iter().all(|(v, stride)| v.len() == n * stride)
}

impl SolidState {
    /// This trial (every particle) as the particles whose values differ in any bit from
    /// `first`'s, the same step's first trial (every particle): the arrays hold those particles'
    /// values, `particles` their numbers, `changed_only` is set, and the surface is this trial's,
    /// whole. Where the two states do not describe the same particles (a partial state, another
    /// dimension or count), this trial whole.
    pub fn changes_from(&self, first: &SolidState) -> SolidState {
        let n = self.n_particles();
        let comparable = (2..=3).contains(&self.dim)
            && self.dim == first.dim
            && self.particles.is_empty()
            && first.particles.is_empty()
            && !self.changed_only
            && !first.changed_only
            && fits(self, n)
            && fits(first, n);
        if !comparable {
            return self.clone();
        }
        let (mine, theirs) = (columns(self), columns(first));
        let differs = |p: usize| {
            mine.iter().zip(&theirs).any(|((a, k), (b, _))| {
                a[p * k..(p + 1) * k]
                    .iter()
                    .zip(&b[p * k..(p + 1) * k])
                    .any(|(x, y)| x.to_bits() != y.to_bits())
            })
        };
        let changed: Vec<u32> = (0..n).filter(|&p| differs(p)).map(|p| p as u32).collect();
        let pick = |(v, k): (&Vec<f64>, usize)| -> Vec<f64> {
            let mut out = Vec::with_capacity(changed.len() * k);
            for &p in &changed {
                let p = p as usize;
                out.extend_from_slice(&v[p * k..(p + 1) * k]);
            }
            out
        };
        let [position, orientation, velocity, angular_velocity, diameter] = mine.map(pick);
        SolidState {
            stamp: self.stamp,
            dim: self.dim,
            position,
            orientation,
            velocity,
            angular_velocity,
            diameter,
            surface: self.surface.clone(),
            particles: changed,
            changed_only: true,
        }
    }

    /// The whole trial that this one (`changed_only`) describes: `first`'s particles with those
    /// listed here replaced by their values here, with this trial's stamp and surface. Refused,
    /// with what is wrong, when `first` is not a whole state of the same dimension, when the
    /// listed particles are not ascending and below `first`'s count, or when the arrays do not
    /// hold the listed particles' values. A state that is not `changed_only` comes back as it is.
    pub fn merged_onto(&self, first: &SolidState) -> Result<SolidState, String> {
        if !self.changed_only {
            return Ok(self.clone());
        }
        let n = first.n_particles();
        if first.changed_only || !first.particles.is_empty() || !fits(first, n) {
            return Err(format!(
                "the step's first trial (iteration {}) is not a whole state to put changes onto",
                first.stamp.iteration
            ));
        }
        if self.dim != first.dim {
            return Err(format!(
                "changes in {}-D onto a first trial in {}-D",
                self.dim, first.dim
            ));
        }
        let m = self.particles.len();
        if let Some(w) = self.particles.windows(2).find(|w| w[0] >= w[1]) {
            return Err(format!(
                "changed particles not ascending ({} then {})",
                w[0], w[1]
            ));
        }
        if let Some(&p) = self.particles.last().filter(|&&p| p as usize >= n) {
            return Err(format!(
                "changed particle {p} beyond the first trial's {n} particles"
            ));
        }
        if !fits(self, m) {
            return Err(format!(
                "array lengths do not match {m} changed particles in {}-D",
                self.dim
            ));
        }
        let put = |(base, k): (&Vec<f64>, usize), (vals, _): (&Vec<f64>, usize)| -> Vec<f64> {
            let mut out = base.clone();
            for (i, &p) in self.particles.iter().enumerate() {
                let p = p as usize;
                out[p * k..(p + 1) * k].copy_from_slice(&vals[i * k..(i + 1) * k]);
            }
            out
        };
        let (base, vals) = (columns(first), columns(self));
        Ok(SolidState {
            stamp: self.stamp,
            dim: self.dim,
            position: put(base[0], vals[0]),
            orientation: put(base[1], vals[1]),
            velocity: put(base[2], vals[2]),
            angular_velocity: put(base[3], vals[3]),
            diameter: put(base[4], vals[4]),
            surface: self.surface.clone(),
            particles: Vec::new(),
            changed_only: false,
        })
    }
}
