//! Step 2 of paper 003 §3.4, once per fixed-point iteration: force and torque per particle from
//! `p̄` over the wet sub-faces of a trial surface (eq. 23–25).

use protocol::sum::OddSum;

use super::cells::{domain_face, pressure_cell, touches_gas_with};
use super::error::Reach;
use super::levers::Levers;
use super::pool_sum::add_shared;
use super::{Embedded, EmbeddedError, SolidFrame};
use crate::cutcell::{SubFace, Surface, compute, compute_block_cells_reusing};
use crate::fv::FluidSolver;

/// Whether two surfaces are the same, bit for bit (so their geometries are).
fn same_surface(a: &Surface, b: &Surface) -> bool {
    a.dim == b.dim
        && a.elements == b.elements
        && a.element_particle == b.element_particle
        && a.vertices.len() == b.vertices.len()
        && (a.vertices.iter().zip(b.vertices)).all(|(x, y)| x.to_bits() == y.to_bits())
}

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
    ///
    /// Collective on a decomposed grid: each rank takes the sub-faces of its own block only
    /// (the trial geometry of the block and one cell around it, `cutcell::compute_block_cells`;
    /// on `F^n`, the whole grid's geometry it holds, as one rank does), and
    /// the terms of every rank are gathered on every rank, each rank adds up a share of the
    /// slots as one rank adds them ([`OddSum`]: the sums do not depend on the terms' order;
    /// `add_loads`) and one all-gather of the sums gives every rank the loads of one
    /// rank.
    pub fn loads(
        &mut self,
        solver: &FluidSolver,
        trial: &SolidFrame,
    ) -> Result<Loads, EmbeddedError> {
        let d = self.config.grid.dim;
        let nr = if d == 2 { 1 } else { 3 };
        let np = trial.n_particles();
        let levers = Levers::new(self.config.start_levers, &self.state.current, trial);
        // Forces in slots `0..np d`, torques after them; summed apart from the sub-faces' order.
        let mut sum = std::mem::take(&mut self.scratch.odd);
        sum.clear();
        let failed = match self.config.block {
            None => {
                let grid = &self.config.grid;
                // NOTE: the explicit scheme's loads come from `F^n`, whose geometry the last
                // correct computed (`compute` is pure): it is taken as it is where the trial
                // surface is `F^n`'s, bit for bit. Computed again, it was 2 % of the fluid
                // node's time in `cube-mobile-walls` on 50^3, on one thread.
                let geom = if same_surface(&trial.surface(), &self.state.current.surface()) {
                    &self.state.geom
                } else {
                    let geom = &mut self.scratch.trial.cut;
                    solver.install(|| compute(grid, &trial.surface(), geom));
                    &self.scratch.trial
                };
                let lambda = |c: usize| geom.lambda(c);
                geom.subfaces
                    .iter()
                    .find_map(|s| self.push_load(s, trial, &levers, lambda, &mut sum).err())
            }
            Some(block) => {
                let grid = &self.config.grid;
                let reuse = std::mem::take(&mut self.scratch.block);
                let mut terms = |subfaces: &[SubFace], lambda: &dyn Fn(usize) -> f64| {
                    (self.own_subfaces(subfaces)).find_map(|(_, s)| {
                        let pc = self.push_load(s, trial, &levers, lambda, &mut sum).err()?;
                        Some((s.cell, s.element, pc))
                    })
                };
                // NOTE: as on one rank, loads on `F^n` take the geometry of `F^n` the last
                // correct computed, which every rank holds whole: Λ and the sub-faces of the
                // block and one cell around it, all the terms read, are those of the block's
                // own geometry, bit for bit (`cutcell::compute_block_cells`). In an explicit
                // scene every trial surface is `F^n`, and computing it again on every rank
                // was work one rank does not do.
                let mine = if same_surface(&trial.surface(), &self.state.current.surface()) {
                    let geom = &self.state.geom;
                    let mine = terms(&geom.subfaces, &|c| geom.lambda(c));
                    self.scratch.block = reuse;
                    mine
                } else {
                    let geom = compute_block_cells_reusing(grid, &trial.surface(), block, 1, reuse);
                    let mine = terms(&geom.subfaces, &|c| geom.solid_fraction_at(grid.ijk(c)));
                    self.scratch.block = geom;
                    mine
                };
                gather_terms(solver, mine, &mut sum).map(|(_, _, pc)| pc)
            }
        };
        if let Some(pc) = failed {
            sum.clear();
            self.scratch.odd = sum;
            return Err(self.outside_near(None, Reach::TrialSurface, pc));
        }
        let mut loads = Loads {
            force: vec![0.0; np * d],
            torque: vec![0.0; np * nr],
        };
        add_loads(solver, &mut sum, &mut loads, np * d);
        self.scratch.odd = sum;
        Ok(loads)
    }

    /// Pushes the force and moment of wet sub-face `s` of `trial` (solid fractions of the trial
    /// surface read through `lambda`) into `sum`; skips a sub-face that carries none. Errs
    /// with the cell whose `p̄` it needs when that cell is not a near cell.
    fn push_load(
        &self,
        s: &SubFace,
        trial: &SolidFrame,
        levers: &Levers,
        lambda: impl Fn(usize) -> f64,
        sum: &mut OddSum,
    ) -> Result<(), u32> {
        let grid = &self.config.grid;
        let d = grid.dim;
        if !trial.wet[s.element as usize]
            || domain_face(grid, s).is_some()
            || self.opening(s, trial)
            || !touches_gas_with(grid, lambda, s)
        {
            return Ok(());
        }
        let mut f = [0.0; 3];
        let pc = pressure_cell(grid, &self.state.geom, s) as u32;
        let p = self.near.pressure_of(pc).ok_or(pc)?;
        for a in 0..d {
            f[a] = -p * s.normal[a] * s.area;
        }
        let p = s.particle as usize;
        for a in 0..d {
            sum.push(p * d + a, f[a]);
        }
        let r = levers.lever(s);
        push_moment(sum, trial.n_particles() * d, d, p, r, f);
        Ok(())
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

/// Adds the force slots (`0..n_force`) and torque slots (after them) of `sum` into `loads`
/// ([`add_shared`]: on the solver's pool; on a decomposed grid each rank sums a share of the
/// slots and one all-gather gives every rank every slot's sum, collective), the bits of one
/// rank's [`OddSum::add_into`].
pub(super) fn add_loads(solver: &FluidSolver, sum: &mut OddSum, loads: &mut Loads, n_force: usize) {
    let mut all = std::mem::take(&mut loads.force);
    all.append(&mut loads.torque);
    add_shared(solver, sum, &mut all);
    loads.torque = all.split_off(n_force);
    loads.force = all;
}

/// Every rank's load terms (and the first sub-face `(cell, element, p̄ cell)` whose `p̄` it
/// lacked) on every rank (collective): `sum` gets all the terms, in rank order; returns the
/// failure of the lowest sub-face in the one-rank order (cell, then element), the one one rank
/// stops at.
fn gather_terms(
    solver: &FluidSolver,
    mine: Option<(u32, u32, u32)>,
    sum: &mut OddSum,
) -> Option<(u32, u32, u32)> {
    let none = (u32::MAX, u32::MAX, u32::MAX);
    let (cell, element, pc) = mine.unwrap_or(none);
    let mut bytes = Vec::with_capacity(12 + 12 * sum.terms().len());
    for x in [cell, element, pc] {
        bytes.extend(x.to_le_bytes());
    }
    for &(slot, value) in sum.terms() {
        bytes.extend(slot.to_le_bytes());
        bytes.extend(value.to_bits().to_le_bytes());
    }
    sum.clear();
    let u32_at = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().expect("4"));
    let mut first = none;
    for part in &solver.comm().all_gather(&bytes) {
        let failed = (u32_at(part, 0), u32_at(part, 4), u32_at(part, 8));
        first = first.min(failed);
        sum.extend(part[12..].chunks_exact(12).map(|t| {
            let bits = u64::from_le_bytes(t[4..12].try_into().expect("8 bytes"));
            (u32_at(t, 0), f64::from_bits(bits))
        }));
    }
    (first != none).then_some(first)
}
