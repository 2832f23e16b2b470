//! Step 2 of paper 003 §3.4, once per fixed-point iteration: force and torque per particle from
//! `p̄` over the wet sub-faces of a trial surface (eq. 23–25).

use protocol::sum::OddSum;

use super::cells::{domain_face, pressure_cell, touches_gas};
use super::error::Reach;
use super::levers::Levers;
use super::{Embedded, EmbeddedError, SolidFrame};
use crate::cutcell::compute;

/// Force and torque per particle on one trial surface (eq. 23–25 of paper 003).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Loads {
    /// Force \[N\] (2-D: per unit depth), `dim` per particle.
    pub force: Vec<f64>,
    /// Torque about the particle's centre of mass [N m], 1 (2-D) or 3 (3-D) per particle.
    pub torque: Vec<f64>,
}

impl Embedded {
    /// Force and torque per particle from `p̄` over the wet sub-faces of a trial surface
    /// (eq. 23–25 of paper 003; torques about the trial centres of mass, with the lever arms
    /// of `embedded::levers`). The error names no step: the caller adds it
    /// ([`EmbeddedError::at_step`]).
    pub fn loads(&mut self, trial: &SolidFrame) -> Result<Loads, EmbeddedError> {
        let grid = &self.config.grid;
        let d = grid.dim;
        let nr = if d == 2 { 1 } else { 3 };
        let np = trial.n_particles();
        compute(grid, &trial.surface(), &mut self.scratch.trial);
        let geom = &self.scratch.trial;
        let levers = Levers::new(self.config.start_levers, &self.state.current, trial);
        let mut loads = Loads {
            force: vec![0.0; np * d],
            torque: vec![0.0; np * nr],
        };
        // Forces in slots `0..np d`, torques after them; summed apart from the sub-faces' order.
        let mut sum = std::mem::take(&mut self.scratch.odd);
        sum.clear();
        for s in &geom.subfaces {
            if !trial.wet[s.element as usize]
                || domain_face(grid, s).is_some()
                || self.opening(s, trial)
                || !touches_gas(grid, &geom.solid_fraction, s)
            {
                continue;
            }
            let mut f = [0.0; 3];
            let pc = pressure_cell(grid, &self.state.geom.solid_fraction, s) as u32;
            let Some(p) = self.near.pressure_of(pc) else {
                self.scratch.odd = sum;
                return Err(self.outside_near(None, Reach::TrialSurface, pc));
            };
            for a in 0..d {
                f[a] = -p * s.normal[a] * s.area;
            }
            let p = s.particle as usize;
            for a in 0..d {
                sum.push(p * d + a, f[a]);
            }
            let r = levers.lever(s);
            push_moment(&mut sum, np * d, d, p, r, f);
        }
        add_loads(&mut sum, &mut loads, np * d);
        self.scratch.odd = sum;
        Ok(loads)
    }

    /// The error for `what` reaching `cell`, outside the near cells.
    pub(super) fn outside_near(&self, step: Option<u64>, what: Reach, cell: u32) -> EmbeddedError {
        let grid = &self.config.grid;
        let ijk = grid.ijk(cell as usize);
        EmbeddedError::OutsideNear {
            step,
            what,
            cell: ijk,
            center: grid.cell_center(ijk),
        }
    }
}

/// Pushes the moment `r × f` of a force about particle `p`'s centre into the torque slots, which
/// start at `base` (2-D: the z component, one per particle; 3-D: three per particle).
pub(super) fn push_moment(
    sum: &mut OddSum,
    base: usize,
    dim: usize,
    p: usize,
    r: [f64; 3],
    f: [f64; 3],
) {
    if dim == 2 {
        sum.push(base + p, r[0] * f[1] - r[1] * f[0]);
    } else {
        sum.push(base + 3 * p, r[1] * f[2] - r[2] * f[1]);
        sum.push(base + 3 * p + 1, r[2] * f[0] - r[0] * f[2]);
        sum.push(base + 3 * p + 2, r[0] * f[1] - r[1] * f[0]);
    }
}

/// Adds the force slots (`0..n_force`) and torque slots (after them) of `sum` into `loads`.
pub(super) fn add_loads(sum: &mut OddSum, loads: &mut Loads, n_force: usize) {
    let mut all = std::mem::take(&mut loads.force);
    all.append(&mut loads.torque);
    sum.add_into(&mut all);
    loads.torque = all.split_off(n_force);
    loads.force = all;
}
