//! Cracks (paper 000 §3.2): the cells a crack opens in a step hold vacuum, and the faces
//! between them and the fluid take the Lax–Friedrichs flux of that fluid against vacuum.

use super::cells::{across, domain_face, dominant_axis, fluid_part, full_state, shifted};
use super::{COVERED_TOLERANCE, Embedded, SolidFrame};
use crate::cutcell::{CutGeometry, SubFace};
use crate::fv::FluidSolver;
use crate::fv::euler::NQ;

impl Embedded {
    /// Whether a sub-face of `frame` belongs to a face that becomes wet in this step (a link
    /// broke) and lies in a cell covered at `t^n`: the crack behind it is vacuum, and the state
    /// the sweeps left in that cell is not the fluid's, so it carries no pressure.
    ///
    /// So is a sub-face in a [sealed](Embedded::sealed) cell: whatever the solid uncovers
    /// there is vacuum.
    pub(super) fn opening(&self, s: &SubFace, frame: &SolidFrame) -> bool {
        let e = s.element as usize;
        let c = s.cell as usize;
        self.sealed(c)
            || (frame.wet[e]
                && !self.state.current.wet.get(e).copied().unwrap_or(true)
                && self.state.geom.lambda(c) >= 1.0 - COVERED_TOLERANCE)
    }

    /// Whether cell `c` was covered at t^n with no gas beside it: each face neighbour (across a
    /// periodic side too) covered as well, or beyond a wall or an open side. Nothing can have
    /// reached such a cell during the step, so the part of it the solid uncovers is vacuum
    /// (paper 000 §3.2 for a crack; the same holds for a body leaving a wall it was flush
    /// against, or uncovering a cell of its interior). Its ghost state mirrors gas it has no
    /// contact with, and carries no pressure.
    pub(super) fn sealed(&self, c: usize) -> bool {
        let geom = &self.state.geom;
        let covered = |q: usize| geom.lambda(q) >= 1.0 - COVERED_TOLERANCE;
        let grid = &self.config.grid;
        covered(c)
            && (0..grid.dim).all(|a| {
                (0..2)
                    .all(|side| across(grid, &self.config.boundary, c, a, side).is_none_or(covered))
            })
    }

    /// The near cells (by slot) in which a crack opens in this step, with the accepted surface
    /// `accepted` in the trial geometry; their `U^n` becomes vacuum.
    ///
    /// Cells covered at t^n in which a crack opens in this step (a link broke): no fluid was
    /// there, so their `U^n` is vacuum, and the faces between them and the fluid take the
    /// Lax–Friedrichs flux of that fluid against vacuum (paper 000 §3.2), not the sweeps' flux
    /// against a ghost state.
    ///
    /// Collective on a decomposed grid: each rank finds the opening cells among its own near
    /// cells (what decides a cell, its sub-faces, its neighbours' and Λ, is the same on every
    /// rank), and one all-gather of their slots gives every rank the list of one rank.
    pub(super) fn opening_cells(
        &mut self,
        solver: &FluidSolver,
        accepted: &SolidFrame,
    ) -> Vec<bool> {
        let nvar = self.config.grid.dim + 2;
        let mut opening = vec![false; self.near.cells.len()];
        for (_, s) in self.own_subfaces(&self.scratch.trial.subfaces) {
            if self.opening(s, accepted)
                && let Some(k) = self.near.slot(s.cell as usize)
            {
                opening[k] = true;
            }
        }
        // NOTE: where cracks may open, a cell covered at t^n that a crack between two bodies
        // uncovers in this step (walls pressed together, then parted) is opening too: the
        // sweeps gave it a ghost state, the mirror of the gas beyond the wall, and its faces
        // to the crack carried that state's pressure into a cell with no mass (-5e-6 of y
        // momentum per unit volume in a cell 8e-5 open, the flush cube at 100^3).
        if self.config.fracture {
            for k in self.crack_cells(&self.scratch.trial, accepted) {
                let c = self.near.cells[k] as usize;
                if self.state.geom.lambda(c) >= 1.0 - COVERED_TOLERANCE
                    && fluid_part(self.scratch.trial.lambda(c)) > COVERED_TOLERANCE
                {
                    opening[k] = true;
                }
            }
        }
        // A sealed cell the solid uncovers holds vacuum, as a crack does.
        for k in self.near.own.iter() {
            let c = self.near.cells[k] as usize;
            if !opening[k]
                && fluid_part(self.scratch.trial.lambda(c)) > COVERED_TOLERANCE
                && self.sealed(c)
            {
                opening[k] = true;
            }
        }
        if self.config.block.is_some() {
            gather_opening(solver, &mut opening);
        }
        for (k, _) in opening.iter().enumerate().filter(|(_, o)| **o) {
            self.near.saved[k * nvar..(k + 1) * nvar].fill(0.0);
        }
        opening
    }

    /// This rank's near cells (by slot, ascending) between two faces of a crack in `geom`: a
    /// wet sub-face of one particle and, in the same cell or in the cell it faces along its
    /// normal's largest component, a wet sub-face of another particle facing back along that
    /// axis (the tie rule puts the two faces of a crack on a grid plane into two cells).
    ///
    /// NOTE: the faces are listed for the cells that hold wet sub-faces only, grouped by slot
    /// in the sub-faces' order (by cell, so by slot: the near cells are ascending), each face
    /// once (a list per near cell was an array of every near cell and an allocation for each
    /// cell with a face, a step).
    fn crack_cells(&self, geom: &CutGeometry, frame: &SolidFrame) -> Vec<usize> {
        let grid = &self.config.grid;
        let near = &self.near;
        // (particle, 2 axis + side) of the wet sub-faces, side 1 for ν_a < 0; and each slot's
        // `(slot, first, end)` of them, ascending.
        let mut faces: Vec<(u32, usize)> = Vec::new();
        let mut slots: Vec<(usize, usize, usize)> = Vec::new();
        for s in &geom.subfaces {
            let k = near.slot_of[s.cell as usize] as usize;
            if k == 0 || !frame.wet[s.element as usize] || domain_face(grid, s).is_some() {
                continue;
            }
            let a = dominant_axis(grid.dim, s.normal);
            let key = (s.particle, 2 * a + usize::from(s.normal[a] < 0.0));
            match slots.last_mut() {
                Some(last) if last.0 == k - 1 => {
                    if !faces[last.1..last.2].contains(&key) {
                        faces.push(key);
                        last.2 += 1;
                    }
                }
                last => {
                    debug_assert!(last.is_none_or(|l| l.0 < k - 1), "sub-faces by cell");
                    slots.push((k - 1, faces.len(), faces.len() + 1));
                    faces.push(key);
                }
            }
        }
        let of = |k: usize| match slots.binary_search_by_key(&k, |s| s.0) {
            Ok(i) => &faces[slots[i].1..slots[i].2],
            Err(_) => &[],
        };
        let mut crack: Vec<usize> = Vec::new();
        for &(k, first, end) in slots.iter().filter(|s| self.own_slot(s.0)) {
            let ijk = grid.ijk(near.cells[k] as usize);
            let cracked = faces[first..end].iter().any(|&(p, f)| {
                let (a, back) = (f / 2, f ^ 1);
                let faces_back = |slot: usize| of(slot).iter().any(|&(q, g)| q != p && g == back);
                let mut d = [0isize; 3];
                d[a] = if f % 2 == 1 { -1 } else { 1 };
                faces_back(k)
                    || shifted(grid, ijk, d).is_some_and(|q| {
                        let kq = near.slot_of[grid.index(q[0], q[1], q[2])] as usize;
                        kq > 0 && faces_back(kq - 1)
                    })
            });
            if cracked {
                crack.push(k);
            }
        }
        crack
    }

    /// The flux along `axis` through the face between cells `left` and `right` when a crack
    /// opens on either side of it (`opening`, by near slot): the Lax–Friedrichs flux of the
    /// fluid on the other side against vacuum, with the sweeps' `sigma = Δt/Δx`, or zero if
    /// the other side held no fluid at `t^n` either (the sweeps' flux there came from ghost or
    /// stale states, not from the fluid).
    pub(super) fn crack_flux(
        &self,
        axis: usize,
        left: usize,
        right: usize,
        opening: &[bool],
        sigma: f64,
    ) -> Option<[f64; NQ]> {
        let dim = self.config.grid.dim;
        let nvar = dim + 2;
        let slot_of = &self.near.slot_of;
        let (kl, kr) = (slot_of[left] as usize, slot_of[right] as usize);
        if kl == 0 || kr == 0 || !(opening[kl - 1] || opening[kr - 1]) {
            return None;
        }
        let empty = |c: usize, k: usize| {
            opening[k - 1] || self.state.geom.lambda(c) >= 1.0 - COVERED_TOLERANCE
        };
        if empty(left, kl) && empty(right, kr) {
            return Some([0.0; NQ]);
        }
        let state = |k: usize| -> [f64; NQ] {
            if opening[k - 1] {
                return [0.0; NQ];
            }
            let mut u = full_state(&self.near.saved[(k - 1) * nvar..k * nvar], dim, 1.0);
            u.swap(1, 1 + axis);
            u
        };
        let mut f = crate::fv::euler::flux_lax_friedrichs(
            &state(kl),
            &state(kr),
            sigma,
            self.config.gamma,
            self.config.vacuum.0,
        );
        f.swap(1, 1 + axis);
        Some(f)
    }
}

/// Every rank's opening cells (its own near slots marked in `opening`) marked on every rank
/// (collective). Traffic: 4 bytes per opening cell.
fn gather_opening(solver: &FluidSolver, opening: &mut [bool]) {
    let mut bytes = Vec::new();
    for (k, _) in opening.iter().enumerate().filter(|(_, o)| **o) {
        bytes.extend((k as u32).to_le_bytes());
    }
    for part in &solver.comm().all_gather(&bytes) {
        for k in part.chunks_exact(4) {
            opening[u32::from_le_bytes(k.try_into().expect("4")) as usize] = true;
        }
    }
}
