//! [`Embedded`]: the fluid's side of the coupling, held as its four parts apart: the
//! configuration (fixed for a run), the state that persists between steps, the near-surface
//! data one step's predict leaves for its loads and correct, and the scratch of the stages.

use serde::{Deserialize, Serialize};

use super::beyond::outside_domain;
use super::cells::{CellKind, fluid_part, full_state, pencil_axes};
use super::{EmbeddedError, Loads, SolidFrame};
use std::borrow::Cow;

use super::gather::assemble_by_block;
use super::held::Held;
use super::slots::SlotOf;
use crate::cutcell::{BlockGeometry, CellBox, CutGeometry, SubfaceSwept, compute};
use crate::fv::euler::NQ;
use crate::fv::line::state_ok;
use crate::fv::{BoundaryKind, FluidSolver, SplitHooks};
use crate::grid::Grid;
use protocol::sum::OddSum;

/// What the interface gave the fluid since the start (node-private checkpoint part).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InterfaceBudget {
    /// Work the fluid gave the solid \[J\] (positive when the fluid lost energy).
    pub work_given: f64,
    /// Momentum the fluid gave the solid [kg m/s].
    pub impulse_given: [f64; 3],
    /// Fluid mass the solid displaced \[kg\]: `Σ_n Σ_cells ρⁿ max(0, Λ^{n+1} − Λⁿ) V`
    /// (`summary.json`'s `swept_mass`, the measure of paper 000's mass errors).
    pub swept_mass: f64,
}

/// The fluid's side of the coupling, beside a [`FluidSolver`] on the same grid.
pub struct Embedded {
    pub(super) config: Config,
    pub(super) state: State,
    pub(super) near: NearCells,
    pub(super) scratch: Scratch,
}

/// What a run fixes: the grid, the gas and whether cracks may open.
pub(super) struct Config {
    /// Whether cracks may open in the solid (`[solid] fracture`, or separate bodies that touch
    /// and part): faces between two cells covered at t^n then carry no flux in the correct.
    pub(super) fracture: bool,
    /// Whether the semi-implicit loads and solid flux take their lever arms on `F^n`
    /// (`levers.rs`; set with `run.solid_substeps` other than 1).
    pub(super) start_levers: bool,
    /// Whether the mixing's groups go by their roots' ranks when none merges or widens
    /// (`mix/by_root.rs`; on unless [`Embedded::set_mixing_by_root`] turns it off).
    pub(super) mixing_by_root: bool,
    pub(super) grid: Grid,
    /// Ghost cells of the sweeps' stencil.
    pub(super) ng: usize,
    pub(super) gamma: f64,
    /// The vacuum thresholds `(ρ, p)` of `fluid.vacuum`.
    pub(super) vacuum: (f64, f64),
    /// The domain's sides, `[axis][low, high]` (a body must stay off the periodic ones:
    /// `beyond::outside_domain`; the gas it pushes out of the open ones leaves).
    pub(super) boundary: [[BoundaryKind; 2]; 3],
    /// This rank's block on a grid decomposed over several ranks (`None` on one rank): the
    /// loads take the sub-faces of its cells only, the sweeps' ghost fills, wall runs and
    /// vacuum cells are those of its cells, and the correct clips the prisms of its cells'
    /// sub-faces and updates its near cells (issue 40 item 1, `loads.rs`, `hooks.rs`,
    /// `correct.rs`).
    pub(super) block: Option<CellBox>,
}

/// What persists from one step to the next (and what a checkpoint restores).
pub(super) struct State {
    /// The accepted surface and kinematics `F^n`.
    pub(super) current: SolidFrame,
    /// Its geometry, as this rank holds it (`held.rs`).
    pub(super) geom: Held,
    pub(super) budget: InterfaceBudget,
    /// Loads of the accepted surface of the last step (outputs).
    pub(super) last_loads: Loads,
}

/// The near-surface data one predict leaves for the loads and the correct of its step.
pub(super) struct NearCells {
    /// Cells near the wet surface of `F^n`, ascending.
    pub(super) cells: Vec<u32>,
    /// `slot + 1` of each cell in `cells`, 0 elsewhere (reset sparsely; dense over the held
    /// box only, `slots.rs`).
    pub(super) slot_of: SlotOf,
    /// `U^n` of the near cells, `nvar` each.
    pub(super) saved: Vec<f64>,
    /// What the sweeps take in (ghost fills, vacuum cells) and give back (directional
    /// pressures, face fluxes).
    pub(super) hooks: SplitHooks,
    /// `p̄` of each near cell: the one pressure of the wet faces it holds or faces, on every
    /// axis (see [`Embedded::predict`]).
    pub(super) wall_pressure: Vec<f64>,
    /// The slots of this rank's own cells.
    pub(super) own: OwnSlots,
}

/// The near slots of this rank's own cells, found once per list of near cells.
///
/// NOTE: the loops over the near cells that take this rank's own found each owner from the
/// cell's index (two divisions and a box test a slot, every slot, in some five loops a step);
/// the near cells being ascending, a block whose cells are one range of the grid's numbering
/// (a slab: every axis but the last whole) owns one range of slots, which those loops now run
/// over alone.
#[derive(Clone, Debug, Default)]
pub(super) struct OwnSlots {
    /// The slots from the first own one to the last (all of them on one rank).
    range: std::ops::Range<usize>,
    /// Whether each slot of `range` is own; empty when all of them are (a slab).
    marked: Vec<bool>,
}

impl OwnSlots {
    /// The own slots of `cells` (whole grid, ascending) on `block` (`None`: one rank).
    pub(super) fn of(grid: &Grid, cells: &[u32], block: Option<CellBox>) -> OwnSlots {
        let Some(b) = block else {
            return OwnSlots {
                range: 0..cells.len(),
                marked: Vec::new(),
            };
        };
        let last = grid.dim - 1;
        let (first, end) = (grid.index(b.lo[0], b.lo[1], b.lo[2]), {
            let hi = std::array::from_fn::<usize, 3, _>(|a| b.hi[a].max(1) - 1);
            grid.index(hi[0], hi[1], hi[2]) + 1
        });
        let range = cells.partition_point(|&c| (c as usize) < first)
            ..cells.partition_point(|&c| (c as usize) < end);
        let slab = (0..last).all(|a| b.lo[a] == 0 && b.hi[a] == grid.cells[a]);
        let marked = if slab {
            Vec::new()
        } else {
            (cells[range.clone()].iter())
                .map(|&c| b.contains(grid.ijk(c as usize)))
                .collect()
        };
        OwnSlots { range, marked }
    }

    /// The slots from the first own one to the last: every own slot lies in it.
    pub(super) fn range(&self) -> std::ops::Range<usize> {
        self.range.clone()
    }

    /// The own slots, ascending.
    pub(super) fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        self.range().filter(|&k| self.contains(k))
    }

    /// Whether slot `k` is a cell of this rank.
    #[inline]
    pub(super) fn contains(&self, k: usize) -> bool {
        self.range.contains(&k) && (self.marked.is_empty() || self.marked[k - self.range.start])
    }
}

/// Buffers of the stages, kept between steps only to reuse their allocations.
pub(super) struct Scratch {
    /// Geometry of the trial (loads, on one rank) or accepted (correct) surface, as this rank
    /// holds it.
    pub(super) trial: Held,
    pub(super) swept: SubfaceSwept,
    /// Pieces `(cell, volume)` of the prisms of the parts of elements beyond the domain that
    /// lie in domain cells (see [`super::beyond`]); empty while the surface stays in.
    pub(super) beyond: Vec<(u32, f64)>,
    pub(super) beyond_geom: CutGeometry,
    pub(super) beyond_swept: SubfaceSwept,
    /// Content `(1 − Λ) U` per near cell, and what the correct did to it.
    pub(super) content: Vec<[f64; NQ]>,
    pub(super) kind: Vec<CellKind>,
    /// Per-slot sums independent of the sub-faces' order (mirror-exact loads).
    pub(super) odd: OddSum,
    pub(super) odd_content: OddSum,
    /// The buffers of the last block geometry this rank computed (the loads' trial surfaces,
    /// the correct's block of `F^{n+1}`), for the next (`cutcell::compute_block_cells_reusing`,
    /// `BlockSweep::reusing`); empty on one rank.
    pub(super) block: BlockGeometry,
}

impl Config {
    /// The cells whose Λ and λ this rank holds dense (`held.rs`): its block and the halo the
    /// hooks read ([`super::hook_halo`]); the whole grid on one rank.
    pub(super) fn held_box(&self) -> CellBox {
        match self.block {
            None => CellBox::whole(&self.grid),
            Some(b) => b.grown(&self.grid, super::hook_halo(self.ng)),
        }
    }

    /// Whether the state `content / alpha` is acceptable (see [`state_ok`]).
    pub(super) fn physical(&self, content: &[f64; NQ], alpha: f64) -> bool {
        let full = full_state(&content[..self.grid.dim + 2], self.grid.dim, alpha);
        state_ok(&full, self.gamma, self.vacuum.0, self.vacuum.1)
    }

    /// Whether a state written into a cell (its first `dim + 2` values) is acceptable: what
    /// `Embedded::check_written` tests.
    pub(super) fn written_ok(&self, written: &[f64; NQ]) -> bool {
        self.physical(written, 1.0)
    }
}

impl NearCells {
    /// The slot of cell `c` among the near cells.
    pub(super) fn slot(&self, c: usize) -> Option<usize> {
        match self.slot_of[c] {
            0 => None,
            k => Some(k as usize - 1),
        }
    }

    /// `U^n` of the near cell in slot `k`.
    pub(super) fn saved(&self, k: usize, nvar: usize) -> &[f64] {
        &self.saved[k * nvar..(k + 1) * nvar]
    }

    /// The sweeps' flux through the face along `axis` at `ijk` (the low face of cell `ijk`;
    /// `ijk[axis]` up to the grid's cells along it), if kept: the faces this rank keeps, those of
    /// every near cell on one rank, and on a decomposed grid those of its own near cells and, on
    /// its block's low sides, of the near cells below (`Embedded::taps`).
    ///
    /// NOTE: found in its pencil's kept faces (a few), where the tap's offsets put it; a list of
    /// `(face index, slot)` of every kept face, searched by bisection twice a cell and axis, was
    /// about a fifth of the cell updates' time (`embedded_ranks` at 96³ on one rank), and its
    /// sort a half of the taps'.
    pub(super) fn face_flux(
        &self,
        grid: &Grid,
        axis: usize,
        ijk: [usize; 3],
    ) -> Option<&[f64; NQ]> {
        let (o1, o2) = pencil_axes(axis);
        let p = ijk[o1] + grid.cells[o1] * ijk[o2];
        let tap = &self.hooks.taps[axis];
        let (lo, hi) = (*tap.pencil_offsets.get(p)?, *tap.pencil_offsets.get(p + 1)?);
        let (lo, hi) = (lo as usize, hi as usize);
        let k = tap.positions[lo..hi]
            .binary_search(&(ijk[axis] as u32))
            .ok()?;
        Some(&tap.flux[lo + k])
    }

    /// `p̄` of a near cell.
    pub(super) fn pressure_of(&self, cell: u32) -> Option<f64> {
        self.slot(cell as usize).map(|k| self.wall_pressure[k])
    }
}

impl Embedded {
    /// The embedded solid on `solver`'s grid, with the surface and kinematics at `t^0`.
    pub fn new(solver: &FluidSolver, solid: SolidFrame) -> Result<Embedded, EmbeddedError> {
        // NOTE: every rank of a decomposed fluid holds the whole surface and runs the correct
        // on the whole grid (replicated, issue 16; the geometry by block, held by window, the loads, the
        // sweeps' ghost fills, wall runs and vacuum cells, and the correct's prisms and cell
        // updates are taken by block, issue 40): the
        // cut-cell data are surface-sized, and the same inputs give every rank the bits of one
        // rank. Only the states of cells near the surface cross ranks (`FluidSolver::cells_at`).
        let grid = solver.global_grid().clone();
        if grid.dim != solid.dim {
            return Err(EmbeddedError::Dimensions {
                fluid: grid.dim,
                solid: solid.dim,
            });
        }
        let params = solver.params();
        let config = Config {
            fracture: false,
            mixing_by_root: true,
            start_levers: false,
            ng: params.ghost_cells(),
            gamma: params.gamma,
            vacuum: (params.vacuum_rho, params.vacuum_p),
            boundary: params.boundary,
            block: (solver.slab().ranks > 1).then(|| {
                let slab = solver.slab();
                CellBox {
                    lo: slab.offset,
                    hi: std::array::from_fn(|a| slab.offset[a] + slab.local.cells[a]),
                }
            }),
            grid,
        };
        let slot_of = SlotOf::new(&config.grid, config.held_box());
        let mut e = Embedded {
            near: NearCells {
                cells: Vec::new(),
                slot_of,
                saved: Vec::new(),
                hooks: SplitHooks::default(),
                wall_pressure: Vec::new(),
                own: OwnSlots::default(),
            },
            config,
            state: State {
                current: SolidFrame::default(),
                geom: Held::default(),
                budget: InterfaceBudget::default(),
                last_loads: Loads::default(),
            },
            scratch: Scratch {
                trial: Held::default(),
                swept: SubfaceSwept::new(),
                beyond: Vec::new(),
                beyond_geom: CutGeometry::new(),
                beyond_swept: SubfaceSwept::new(),
                content: Vec::new(),
                kind: Vec::new(),
                odd: OddSum::default(),
                odd_content: OddSum::default(),
                block: BlockGeometry::default(),
            },
        };
        e.set_surface(solver, solid)?;
        Ok(e)
    }

    /// Declares that cracks may open in the solid: links break, or separate bodies touch and
    /// part (flush walls). Faces between two cells covered at t^n then carry no flux in the
    /// correct: beside a crack the sweeps' ghost states there can mirror the gas outside the
    /// particle's far side (a gap opening between two pressed walls took 10 kg/m^2/s through a
    /// face 2.6e-5 open, the mirror of the gas beyond the wall, and went negative).
    pub fn set_fracture(&mut self, fracture: bool) {
        self.config.fracture = fracture;
    }

    /// Declares that the semi-implicit loads and solid flux take their lever arms on `F^n`
    /// (`levers.rs`): the loads held over a long coupling step then damp the lever part of the
    /// fluid's stiffness instead of pumping it.
    pub fn set_start_levers(&mut self, start: bool) {
        self.config.start_levers = start;
    }

    /// Whether the mixing's groups are summed by the ranks of their roots, and their mixtures
    /// gathered, in a step where no group merges or widens (on by default). Off, every rank
    /// merges and mixes every group in every step, the path of a step where one does; both
    /// give the same bits (the test
    /// `fv_ranks::the_mixing_by_root_gives_the_whole_mixings_bits` pins it).
    pub fn set_mixing_by_root(&mut self, by_root: bool) {
        self.config.mixing_by_root = by_root;
    }

    /// Replaces the accepted surface and kinematics (start of a run, or after a restore), on
    /// `solver`'s ranks (collective on a decomposed grid).
    pub fn set_surface(
        &mut self,
        solver: &FluidSolver,
        solid: SolidFrame,
    ) -> Result<(), EmbeddedError> {
        let grid = &self.config.grid;
        if solid.dim != grid.dim {
            return Err(EmbeddedError::SurfaceDimension {
                surface: solid.dim,
                fluid: grid.dim,
            });
        }
        outside_domain(grid, &self.config.boundary, &solid.surface())?;
        // NOTE: a decomposed grid's rank computes the geometry of its block only and puts the
        // whole grid's together from the blocks' shares, as the correct does for `F^{n+1}`
        // (`assemble_by_block`, `held.rs`): computing the whole grid's geometry here and
        // taking its share (`HeldFractions::from_whole`) cost each rank of
        // `opening-fracture-3d` at 100³ on 2 ranks 235 M instructions at the start, more than
        // one rank's 63 M.
        let held = self.config.held_box();
        let geom = &mut self.state.geom;
        match self.config.block {
            None => compute(grid, &solid.surface(), &mut geom.cut),
            Some(block) => {
                let reuse = &mut self.scratch.block;
                assemble_by_block(geom, reuse, solver, &solid.surface(), block, held);
            }
        }
        self.state.current = solid;
        Ok(())
    }

    /// The accepted surface `F^n`.
    pub fn surface(&self) -> &SolidFrame {
        &self.state.current
    }

    /// Solid fraction Λ of this rank's cells for the accepted surface, in the order of its
    /// cells (`fv::Slab`: x fastest over its block; every cell of the grid on one rank).
    pub fn solid_fraction(&self) -> Cow<'_, [f64]> {
        let geom = &self.state.geom;
        match (self.config.block, &geom.fractions) {
            // NOTE: a held box with the block's x and y ranges (slabs along z) holds the block's
            // cells as one range, in their order: lent, not copied (4 MB a step at 100³ on 2
            // ranks).
            (Some(b), Some(f))
                if (0..2).all(|a| f.held.lo[a] == b.lo[a] && f.held.hi[a] == b.hi[a]) =>
            {
                let first = f.held.index(b.lo);
                Cow::Borrowed(&f.solid_fraction[first..first + b.n_cells()])
            }
            (Some(b), Some(f)) => {
                let mut own = Vec::with_capacity(b.n_cells());
                for k in b.lo[2]..b.hi[2] {
                    for j in b.lo[1]..b.hi[1] {
                        let row = f.held.index([b.lo[0], j, k]);
                        own.extend_from_slice(&f.solid_fraction[row..row + b.size(0)]);
                    }
                }
                Cow::Owned(own)
            }
            _ => Cow::Borrowed(&geom.solid_fraction),
        }
    }

    /// Fluid fraction `1 − Λ` of every cell of the grid (outputs; on a decomposed grid read
    /// from the runs this rank holds, `held.rs`).
    pub fn fluid_fraction(&self) -> Vec<f64> {
        let geom = &self.state.geom;
        (0..self.config.grid.n_cells())
            .map(|c| fluid_part(geom.lambda(c)))
            .collect()
    }

    /// Geometry of the accepted surface: the whole grid's sub-faces and cut cells; its dense
    /// Λ and λ on one rank only (empty on a decomposed grid, see [`Embedded::solid_fraction`]).
    pub fn geometry(&self) -> &CutGeometry {
        &self.state.geom
    }

    /// Force and torque per particle that the fluid applied over the last step (on the
    /// accepted surface `F^{n+1}`; zero before the first step).
    pub fn last_loads(&self) -> &Loads {
        &self.state.last_loads
    }

    /// What crossed the interface since the start.
    pub fn budget(&self) -> InterfaceBudget {
        self.state.budget
    }

    /// Restores the budget (checkpoint).
    pub fn set_budget(&mut self, budget: InterfaceBudget) {
        self.state.budget = budget;
    }

    /// Largest step that keeps every surface vertex from crossing more than one cell, at the
    /// velocities of the accepted frame (DESIGN §3 step 1) \[s\]; infinite for a solid at rest.
    pub fn one_cell_dt(&self) -> f64 {
        let s = &self.state.current;
        let d = s.dim;
        let mut rate: f64 = 0.0;
        for (e, nodes) in s.elements.chunks_exact(d).enumerate() {
            let p = s.element_particle[e] as usize;
            for &v in nodes {
                let mut x = [0.0; 3];
                x[..d].copy_from_slice(&s.vertices[v as usize * d..(v as usize + 1) * d]);
                let w = s.point_velocity(p, x);
                for a in 0..d {
                    rate = rate.max(w[a].abs() / self.config.grid.dx[a]);
                }
            }
        }
        1.0 / rate
    }

    /// Fluid totals weighted by the fluid fraction of the accepted surface (collective).
    pub fn totals(&self, solver: &FluidSolver) -> crate::fv::Totals {
        solver.totals_with_own_solid(&self.solid_fraction())
    }
}

#[cfg(test)]
mod tests {
    use super::OwnSlots;
    use crate::cutcell::CellBox;
    use crate::grid::Grid;
    use proptest::prelude::*;

    proptest! {
        /// Whatever the grid (2-D or 3-D), the block (a slab, cut along any axes, or the whole
        /// grid) and the near cells (any ascending subset): a slot is own exactly when its cell
        /// lies in the block, every own slot lies in the range, and on one rank every slot is.
        #[test]
        fn the_own_slots_are_those_whose_cells_lie_in_the_block(
            dim in 2usize..4,
            cells in prop::array::uniform3(1usize..7),
            lo in prop::array::uniform3(0usize..7),
            size in prop::array::uniform3(1usize..7),
            picks in prop::collection::vec(any::<bool>(), 216),
        ) {
            let cells = &cells[..dim];
            let grid = Grid::new(&vec![0.0; dim], &vec![1.0; dim], cells).expect("grid");
            let n = |a: usize| if a < dim { cells[a] } else { 1 };
            let block = CellBox {
                lo: std::array::from_fn(|a| lo[a].min(n(a) - 1)),
                hi: std::array::from_fn(|a| (lo[a].min(n(a) - 1) + size[a]).min(n(a))),
            };
            let near: Vec<u32> = (0..grid.n_cells() as u32).filter(|&c| picks[c as usize]).collect();
            let all = OwnSlots::of(&grid, &near, None);
            prop_assert_eq!(all.range(), 0..near.len());
            prop_assert!((0..near.len()).all(|k| all.contains(k)));
            let own = OwnSlots::of(&grid, &near, Some(block));
            for (k, &c) in near.iter().enumerate() {
                let inside = block.contains(grid.ijk(c as usize));
                prop_assert_eq!(own.contains(k), inside, "{:?}, cell {}", block, c);
                prop_assert!(!inside || own.range().contains(&k));
            }
        }
    }
}
