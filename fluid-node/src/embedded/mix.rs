//! The conservative mixing of paper 000 §3.3 (recursive): small cells (`Λ > 1/2`), cells the
//! solid uncovers, covered cells left with content and cut cells whose update is not physical
//! are mixed into a large neighbour, their targets found by walking along the wall normal.
//! Groups whose mixture is not physical merge with the groups beside them, then widen into
//! rings of free cells. Every sum over a group's members is independent of their order.

use rayon::prelude::*;

use super::cells::{
    CellKind, cells_around, face_neighbours, face_neighbours_of, fluid_part, max_abs, offsets,
    oriented, part_of, shifted,
};
use super::held::Held;
use super::slots::SlotOf;
use super::state::{Config, NearCells, OwnSlots};
use super::{COVERED_TOLERANCE, Embedded, EmbeddedError, MIX_BELOW, WIDEN_RINGS};
use crate::cutcell::face_index;
use crate::fv::FluidSolver;
use crate::fv::euler::NQ;
use crate::grid::Grid;

use super::CorrectReport;
use super::gather::{gather_roots, gather_sources};

mod by_root;
mod groups;
mod predicted;
mod widen;

/// What [`Embedded::mix`] wrote.
pub(super) struct Mixed {
    /// Cells mixed into a neighbour.
    pub(super) cells: usize,
    /// The values written, one per cell (the last), by cell: every written cell of the grid
    /// with [`WrittenCheck::Whole`], else this rank's and the groups' cells.
    pub(super) written: Vec<(u32, [f64; NQ])>,
    /// What left through open sides from pockets of covered cells there \[kg, kg m/s, J\].
    pub(super) leaving: [f64; NQ],
    /// How the written cells are checked (see [`WrittenCheck`]).
    pub(super) check: WrittenCheck,
}

/// The first written cell found not physical, if any: the cell and the state written.
pub(super) type Failure = Option<(u32, [f64; NQ])>;

/// How [`Embedded::check_written`] checks the cells the mixing wrote.
pub(super) enum WrittenCheck {
    /// [`Mixed::written`] holds every written cell of the grid: check them all.
    Whole,
    /// [`Mixed::written`] holds this rank's cells and the groups' only, and the ranks have
    /// checked the cells that could fail and agreed on the first that does, if any (cell,
    /// written state; see [`Mixing::first_failure`]).
    Agreed(Failure),
}

/// Where the walk to a target looks without a large neighbour, within this many cells.
const MAX_SEARCH: usize = 1024;

/// The cells a [`Mixing::search`] has seen: an open-addressed set of `cell + 1` (0 empty),
/// kept at most half full (it starts small: most searches end within a few cells).
struct Seen {
    slots: Vec<u32>,
    len: usize,
}

impl Seen {
    fn new() -> Seen {
        Seen {
            slots: vec![0; 64],
            len: 0,
        }
    }

    /// Adds `cell`; false if it was there already.
    #[inline]
    fn insert(&mut self, cell: usize) -> bool {
        let key = u32::try_from(cell + 1).expect("a grid's cells are numbered in u32");
        if 2 * (self.len + 1) > self.slots.len() {
            let grown = vec![0; 4 * self.slots.len()];
            let old = std::mem::replace(&mut self.slots, grown);
            for k in old.into_iter().filter(|&k| k != 0) {
                self.place(k);
            }
        }
        let new = self.place(key);
        self.len += usize::from(new);
        new
    }

    /// Puts `key` in its slot (Fibonacci hashing, then the next free slot); false if there.
    #[inline]
    fn place(&mut self, key: u32) -> bool {
        let mask = self.slots.len() - 1;
        let shift = 64 - self.slots.len().trailing_zeros();
        let mut at = (u64::from(key).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize;
        loop {
            match self.slots[at] {
                0 => {
                    self.slots[at] = key;
                    return true;
                }
                k if k == key => return false,
                _ => at = (at + 1) & mask,
            }
        }
    }
}

/// What the mixing reads: the geometry of both surfaces and the near cells' contents after
/// eq. (12) (none of it changes while groups form).
struct Mixing<'a> {
    config: &'a Config,
    grid: &'a Grid,
    slot_of: &'a SlotOf,
    near: &'a [u32],
    own: &'a OwnSlots,
    /// The geometry of `F^{n+1}` (Λ, λ) and of `F^n` (Λ).
    new: &'a Held,
    old: &'a Held,
    content: &'a [[f64; NQ]],
    /// Near slots to mix, ascending.
    sources: &'a [usize],
    /// Wall normal `Σ A ν` of each source's sub-faces at t^{n+1}, in the sources' order.
    normal: &'a [[f64; 3]],
    /// Offsets of the neighbours within one cell.
    span: Vec<[isize; 3]>,
    nvar: usize,
}

/// The predicted states the groups read: none of these cells is written before it is read
/// (roots, sources and claimed cells are never taken into another group).
struct Predicted {
    reads: Vec<u32>,
    values: Vec<f64>,
    nvar: usize,
}

/// The groups: `(root, source slot)` by root, the roots, and the roots of merged groups that
/// joined another group as members, `(new root, old root)`, with their parts.
struct Groups {
    groups: Vec<(usize, usize)>,
    roots: Vec<usize>,
    merged: Vec<(usize, usize)>,
    merged_parts: Vec<[f64; NQ]>,
}

/// What the groups write, and the cells they took in.
#[derive(Default)]
struct Writes {
    writes: Vec<(u32, [f64; NQ])>,
    /// Cells taken into a widened group (ascending).
    claimed: Vec<usize>,
    /// Source cells mixed.
    mixed: usize,
    /// What left through open sides (see [`Mixed::leaving`]).
    leaving: [f64; NQ],
}

impl Embedded {
    /// Writes `U^{n+1}` of the updated near cells into the solver, mixing the small, uncovered
    /// and covered-with-content cells into their targets.
    ///
    /// Collective. Each rank finds the sources among its own updated cells, and the sources of
    /// every rank are gathered ([`gather_sources`]); each rank walks from its own sources to
    /// their roots, and the pairs are gathered with the sources' contents ([`gather_roots`]).
    /// Each rank then sums the groups whose roots it holds, and every group's mixture is
    /// gathered ([`Mixing::mixtures`]); every rank writes them all and the unmixed updated
    /// cells of its own, and the solver keeps the writes of its own cells. If a group's mixture
    /// is not physical, groups merge and widen into rings that may lie on other ranks: then the
    /// contents of every updated cell ([`Embedded::gather_contents`]) and the predicted states
    /// the groups read (each root and the cells within [`WIDEN_RINGS`] of a group's members)
    /// are gathered, and every rank merges and mixes every group.
    pub(super) fn mix(
        &mut self,
        solver: &mut FluidSolver,
        report: &mut CorrectReport,
    ) -> Result<Mixed, EmbeddedError> {
        let near_scale = max_abs(&self.near.saved);
        let sources = self.mix_sources(solver, report, near_scale);
        let normal = self.wall_normals(&sources);
        let nvar = self.config.grid.dim + 2;
        // The mixing's view of the state, taken anew after each step that changes the contents
        // (the fields, not `self`, are borrowed, so that `scratch.kind` stays writable).
        macro_rules! mixing {
            () => {
                Mixing::new(
                    &self.config,
                    &self.near,
                    &self.scratch.trial,
                    &self.state.geom,
                    &self.scratch.content,
                    &sources,
                    &normal,
                )
            };
        }
        // NOTE: each source's walk to its root reads only what the mixing reads (none of it
        // changes while groups form), so the walks run in parallel on the fluid's pool and are
        // collected in the sources' order: the same groups on any number of threads. On a
        // decomposed grid each rank walks from its own sources (what the walks read is the same
        // on every rank: the geometry, the wall normals and the sources, which every rank
        // gathers), and the pairs of every rank are gathered with the sources' contents
        // (`gather_roots`): the same sorted list as one rank's.
        let mut groups: Vec<(usize, usize)> = {
            let m = mixing!();
            solver.install(|| {
                (sources.par_iter())
                    .filter(|&&k| m.own(k))
                    .map(|&k| (m.root(k), k))
                    .collect()
            })
        };
        if self.config.block.is_some() {
            groups = gather_roots(solver, &groups, &mut self.scratch.content, nvar);
        }
        groups.sort_unstable();
        // NOTE: the groups are mixed by their roots' ranks, and every mixture gathered
        // (`mixtures`), unless a group's mixture is not physical: then groups merge and widen,
        // which reads cells around them, and every rank mixes every group as before.
        {
            let m = mixing!();
            let kind = &mut self.scratch.kind;
            let mut out = Writes::default();
            m.unmixed(kind, &mut out, true);
            let failure = m.first_failure(kind, &groups, &out.writes);
            if let Some((mixtures, failure)) = m.mixtures(solver, &groups, kind, failure) {
                m.write_mixtures(&groups, &mixtures, kind, &mut out);
                return Ok(m.written(solver, out, WrittenCheck::Agreed(failure)));
            }
        }
        // The contents of every updated cell, which the merge and the rings read.
        if self.config.block.is_some() {
            self.gather_contents(solver);
        }
        let m = mixing!();
        let kind = &mut self.scratch.kind;
        let mut out = Writes::default();
        let mut predicted = m.predicted(solver, &groups);
        let groups = m.merge(groups, kind, &predicted, report);
        m.unmixed(kind, &mut out, false);
        // NOTE: a group that has taken in every cell no other group holds and is still not
        // physical may fail while the gas as a whole is physical, the other groups keeping
        // their surplus (a 0.24 m square at Mach 250 on 24² cells stopped at step 0 so). Then
        // every group is mixed again as one: the mixture is the whole gas's, physical unless the
        // gas as a whole is not.
        // (The groups only append to `out`, which holds no claimed cell yet.)
        let (kind_before, report_before) = (kind.clone(), *report);
        let (writes_before, mixed_before, leaving_before) =
            (out.writes.len(), out.mixed, out.leaving);
        let mut i = 0;
        let mut exhausted = false;
        while i < groups.groups.len() {
            let root = groups.groups[i].0;
            let j = i + groups.groups[i..].partition_point(|g| g.0 == root);
            let physical = m.mix_group(
                &groups,
                i..j,
                kind,
                (&mut predicted, solver),
                &mut out,
                report,
            )?;
            if !physical {
                exhausted = true;
                break;
            }
            i = j;
        }
        if exhausted && groups.roots.len() > 1 {
            kind.copy_from_slice(&kind_before);
            *report = report_before;
            out.writes.truncate(writes_before);
            out.claimed.clear();
            (out.mixed, out.leaving) = (mixed_before, leaving_before);
            let one = m.as_one(&groups, kind, &predicted);
            report.merged_groups += groups.roots.len() - 1;
            let n = one.groups.len();
            m.mix_group(&one, 0..n, kind, (&mut predicted, solver), &mut out, report)?;
        }
        Ok(m.written(solver, out, WrittenCheck::Whole))
    }

    /// The near slots to mix, ascending: covered cells left with content, cells the solid
    /// uncovers, small cells and cells whose update is not physical. A cell of a crack that
    /// nothing has reached yet is left vacuum.
    ///
    /// Collective on a decomposed grid: each rank finds those of its own cells, from their
    /// contents, and the sources, the uncovered cells' count and the largest residue dropped
    /// of every rank are gathered ([`gather_sources`]).
    fn mix_sources(
        &mut self,
        solver: &FluidSolver,
        report: &mut CorrectReport,
        near_scale: f64,
    ) -> Vec<usize> {
        let uncovered_before = report.uncovered_cells;
        let nvar = self.config.grid.dim + 2;
        let block = self.config.block;
        let (new, old) = (&self.scratch.trial, &self.state.geom);
        let alpha = |c: usize| fluid_part(new.lambda(c));
        let saved = &self.near.saved;
        let content = &mut self.scratch.content;
        let mut sources: Vec<usize> = Vec::new();
        for k in self.near.own.iter() {
            let c = self.near.cells[k] as usize;
            if self.scratch.kind[k] != CellKind::Updated {
                continue;
            }
            let a = alpha(c);
            let uncovered = old.lambda(c) >= 1.0 - COVERED_TOLERANCE && a > COVERED_TOLERANCE;
            if uncovered {
                report.uncovered_cells += 1;
            }
            let covered = a <= COVERED_TOLERANCE;
            if covered {
                // NOTE: a covered cell keeps only round-off from fluxes of (nearly) covered faces;
                // below 1e-13 of its state's scale (or of the near cells', for a cell whose
                // `U^n` is vacuum) it is dropped (a covered cell beside a wall may have no fluid
                // to mix into). What is dropped is reported.
                let scale = max_abs(&saved[k * nvar..(k + 1) * nvar]);
                let scale = if scale > 0.0 { scale } else { near_scale };
                let residue = max_abs(&content[k][..nvar]);
                if residue <= 1e-13 * scale {
                    report.dropped = report.dropped.max(residue);
                    continue;
                }
            }
            // A cell of a crack that nothing has reached yet holds vacuum (000 §3.2): nothing
            // to stabilise, and mixing it would spread the gas of the crack's mouth through the
            // whole crack at once (the nearest target through open faces is at the mouth).
            // NOTE: the swept prisms of a crack between two pressed walls reach 1e-12 of a cell
            // into the gas beside it, and bring it round-off of either sign (-1e-12 of mass per
            // unit volume in a cell 9e-5 open: rho = -7e-9, the flush cube at 100^3). A cell
            // that held vacuum at t^n and holds at most 1e-13 of the near cells' scale is still
            // vacuum; what is dropped is reported, as for the covered cells.
            if !covered {
                let was_vacuum = saved[k * nvar..(k + 1) * nvar].iter().all(|&x| x == 0.0);
                let residue = max_abs(&content[k][..nvar]);
                if residue == 0.0 || (was_vacuum && residue <= 1e-13 * near_scale) {
                    report.dropped = report.dropped.max(residue);
                    content[k] = [0.0; NQ];
                    continue;
                }
            }
            // NOTE: a large cut cell whose update is not physical is mixed too: eq. (12) sums
            // the split sweeps' fluxes unsplit, so a cell of fluid fraction near 1/2 at a corner
            // sees up to twice the Courant number of the sweeps. Mixing keeps conservation.
            if covered || a < MIX_BELOW || uncovered || !self.config.physical(&content[k], a) {
                sources.push(k);
            }
        }
        if block.is_some() {
            let uncovered = report.uncovered_cells - uncovered_before;
            let (all, uncovered, dropped) =
                gather_sources(solver, &sources, uncovered, report.dropped);
            report.uncovered_cells = uncovered_before + uncovered;
            report.dropped = dropped;
            sources = all;
        }
        sources
    }

    /// Wall normal of each source (`Σ A ν` of its cell's sub-faces at t^{n+1}), apart from
    /// their order, in the order of `sources` (ascending slots).
    ///
    /// NOTE: the walks read the normals of sources only (`Mixing::direction`); every near
    /// cell's, on every rank, was a sort of every sub-face's three terms and an array of every
    /// near cell a step. Each source's sum takes the same terms, so the same bits.
    fn wall_normals(&mut self, sources: &[usize]) -> Vec<[f64; 3]> {
        let mut normal = vec![[0.0f64; 3]; sources.len()];
        let mut terms = std::mem::take(&mut self.scratch.odd);
        terms.clear();
        for s in &self.scratch.trial.subfaces {
            let k = self.near.slot_of[s.cell as usize] as usize - 1;
            if let Ok(i) = sources.binary_search(&k) {
                for a in 0..3 {
                    terms.push(3 * i + a, s.area * s.normal[a]);
                }
            }
        }
        terms.add_into(normal.as_flattened_mut());
        self.scratch.odd = terms;
        normal
    }
}

impl<'a> Mixing<'a> {
    /// What the mixing reads, with the sources and wall normals found.
    fn new(
        config: &'a Config,
        near: &'a NearCells,
        trial: &'a Held,
        old: &'a Held,
        content: &'a [[f64; NQ]],
        sources: &'a [usize],
        normal: &'a [[f64; 3]],
    ) -> Self {
        let grid = &config.grid;
        Mixing {
            config,
            grid,
            slot_of: &near.slot_of,
            near: &near.cells,
            own: &near.own,
            new: trial,
            old,
            content,
            sources,
            normal,
            span: offsets(grid.dim, 1),
            nvar: grid.dim + 2,
        }
    }
}

impl Mixing<'_> {
    fn alpha(&self, c: usize) -> f64 {
        fluid_part(self.new.lambda(c))
    }

    /// Whether near slot `k` is a cell of this rank (every slot on one rank).
    fn own(&self, k: usize) -> bool {
        self.own.contains(k)
    }

    /// Whether cell `c` (whole grid) is a cell of this rank (every cell on one rank).
    fn own_cell(&self, c: usize) -> bool {
        (self.config.block).is_none_or(|b| b.contains(self.grid.ijk(c)))
    }

    /// Large enough to take others in, and holding fluid at t^n.
    fn big(&self, c: usize) -> bool {
        self.alpha(c) >= MIX_BELOW && self.old.lambda(c) < 1.0 - COVERED_TOLERANCE
    }

    /// The near slot of `c` if it is a source.
    fn is_source(&self, c: usize) -> Option<usize> {
        let k = self.slot_of[c];
        (k > 0 && self.sources.binary_search(&(k as usize - 1)).is_ok()).then(|| k as usize - 1)
    }

    /// A target takes the content of the cells mixed into it, so it must not be mixed itself.
    fn target(&self, c: usize) -> bool {
        self.big(c) && self.is_source(c).is_none()
    }

    /// One step of the walk from `c` along `g`: the best aligned large neighbour (final), else
    /// the face neighbour with the largest aperture, else `c` itself.
    fn hop(&self, c: usize, g: [f64; 3]) -> (usize, bool) {
        let grid = self.grid;
        let ijk = grid.ijk(c);
        let mut best: Option<(f64, usize)> = None;
        for d in &self.span {
            let d = &oriented(grid, ijk, *d);
            let Some(q) = shifted(grid, ijk, *d) else {
                continue;
            };
            let q = grid.index(q[0], q[1], q[2]);
            if !self.target(q) {
                continue;
            }
            let len = ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) as f64).sqrt();
            let score = (d[0] as f64 * g[0] + d[1] as f64 * g[1] + d[2] as f64 * g[2]) / len;
            if best.is_none_or(|(b, _)| score > b) {
                best = Some((score, q));
            }
        }
        if let Some((_, q)) = best {
            return (q, true);
        }
        // No large neighbour: the face neighbour with the largest aperture.
        let mut best: Option<(f64, usize)> = None;
        for (a, q, f) in face_neighbours(grid, ijk) {
            let qi = grid.index(q[0], q[1], q[2]);
            if self.alpha(qi) <= COVERED_TOLERANCE {
                continue;
            }
            let aperture = fluid_part(self.new.face(a, face_index(grid, a, f)));
            if best.is_none_or(|(b, _)| aperture > b) {
                best = Some((aperture, qi));
            }
        }
        best.map_or((c, false), |(_, q)| (q, false))
    }

    /// The direction of the walk from near slot `k`: its wall normal, else the fluid fractions
    /// of its neighbours, weighted.
    fn direction(&self, k: usize) -> [f64; 3] {
        let i = (self.sources.binary_search(&k)).expect("a walk's direction is a source's");
        let g = self.normal[i];
        if g != [0.0; 3] {
            return g;
        }
        let grid = self.grid;
        let c = self.near[k] as usize;
        let ijk = grid.ijk(c);
        let mut g = [0.0; 3];
        for d in &self.span {
            let d = &oriented(grid, ijk, *d);
            if let Some(q) = shifted(grid, ijk, *d) {
                let w = self.alpha(grid.index(q[0], q[1], q[2]));
                for a in 0..3 {
                    g[a] += w * d[a] as f64;
                }
            }
        }
        g
    }

    /// The nearest target through open faces (breadth first, faces in axis order), for a walk
    /// that cycles between small cells: a thin crack, a cell cut on two sides (paper 000 §3.3,
    /// recursive mixing). `None` for a pocket with no target within [`MAX_SEARCH`] cells.
    /// `across`: through every face, the solid's too (see [`Mixing::covered`]).
    fn search(&self, from: usize, across: bool) -> Option<usize> {
        // NOTE: the cells are queued by their `ijk` (no division to find it again), their face
        // neighbours listed into an array, and those seen marked in `Seen`: the same cells
        // visited in the same order as with `face_neighbours` and a `BTreeSet`, which took a
        // third of the search's time. In `embedded_ranks` (the boxes moving, 96³) the walks of
        // the sources they leave behind them cycle about 1,750 times a step, and each search
        // visits about 190 cells before it finds a target: 10.9 % of that bench's samples
        // before, 6.0 % after.
        let grid = self.grid;
        let mut queue = vec![grid.ijk(from)];
        let mut seen = Seen::new();
        seen.insert(from);
        let mut next = 0;
        while next < queue.len() && queue.len() < MAX_SEARCH {
            let ijk = queue[next];
            next += 1;
            let (faces, n) = face_neighbours_of(grid, ijk);
            for &(a, q, f) in &faces[..n] {
                let qi = grid.index(q[0], q[1], q[2]);
                let shut = self.new.face(a, face_index(grid, a, f)) >= 1.0
                    || self.alpha(qi) <= COVERED_TOLERANCE;
                if (shut && !across) || !seen.insert(qi) {
                    continue;
                }
                if self.target(qi) {
                    return Some(qi);
                }
                queue.push(q);
            }
        }
        None
    }

    /// NOTE: a closed pocket of covered cells (no open face leads out of it) holds gas the solid
    /// squeezed to no volume: between two bodies pressed together (fragments colliding, a
    /// crack closing, touching lattices), against the domain's boundary (a face moving out
    /// through a wall sweeps the gas before it into the boundary cell it covers), or round-off
    /// left by fluxes through faces open by less than `COVERED_TOLERANCE` of a cell. It goes to
    /// the nearest target across the solid, as the gas would have escaped along the closing gap:
    /// conservative, and the group's mixture is checked as any other. Before, only a pocket of
    /// round-off (1e-9 of its scale) or one on the domain's boundary went across; the others
    /// stopped the run (the burst of `burst-shell-2d` at a pressure ratio of 1e2: step 121,
    /// 4.8e-4 of a cell of the inner gas between two fragments; 12 of 1,000 corpus cases with
    /// two touching lattices). A pocket with fluid volume (a cavity of small cells) stays a
    /// group of its own while its mixture is physical (one that is not steps over the cells
    /// around it, see [`Mixing::border`]).
    fn covered(&self, p: usize) -> bool {
        self.alpha(p) <= COVERED_TOLERANCE
    }

    /// Root of source `k`: follow hops to a large cell; a walk that cycles goes to the nearest
    /// target through open faces, or, in a closed pocket, to the cycle's smallest cell (across
    /// the solid for a pocket of covered cells, see [`Mixing::covered`]).
    fn root(&self, k: usize) -> usize {
        let mut path = vec![self.near[k] as usize];
        let mut g = self.direction(k);
        loop {
            let here = *path.last().expect("non-empty");
            let (next, final_) = self.hop(here, g);
            if final_ {
                return next;
            }
            if let Some(pos) = path.iter().position(|&p| p == next) {
                // From the walk's first cell with an open way out (a covered source has
                // none: searching only from it put a 2e-12 cell of a thin gap at the root).
                let open = path.iter().find_map(|&p| self.search(p, false));
                let across = || {
                    path.iter()
                        .all(|&p| self.covered(p))
                        .then(|| self.search(path[0], true))
                        .flatten()
                };
                return open
                    .or_else(across)
                    .unwrap_or_else(|| *path[pos..].iter().min().expect("non-empty cycle"));
            }
            if self.is_source(next).is_none() || path.len() > 64 {
                return next;
            }
            path.push(next);
            g = self.direction(self.is_source(next).expect("checked"));
        }
    }

    /// The predicted states the groups can read: each root and source and the cells within
    /// [`WIDEN_RINGS`] of them (collective).
    fn predicted(&self, solver: &mut FluidSolver, groups: &[(usize, usize)]) -> Predicted {
        let grid = self.grid;
        // NOTE: the cells are marked in a bit set, a row of each neighbourhood at a time, and
        // read out in order (`cells_around`): the ascending list without duplicates that
        // sorting them all gave (the sort of the 125 cells around each of them was 6 % of the
        // fluid node's time in `cube-mobile-walls` on 50³).
        let centres: Vec<[usize; 3]> = (groups.iter())
            .flat_map(|&(root, k)| [root, self.near[k] as usize])
            .map(|c| grid.ijk(c))
            .collect();
        let reads = cells_around(grid, &centres, WIDEN_RINGS);
        let values = solver.cells_at(&reads);
        Predicted {
            reads,
            values,
            nvar: self.nvar,
        }
    }

    /// A cell's content as a part of a mixture (see [`part_of`]), read as the cell is now.
    fn part(&self, kind: &[CellKind], predicted: &Predicted, c: usize) -> [f64; NQ] {
        part_of(
            self.slot_of,
            self.content,
            kind,
            c,
            self.alpha(c),
            |q| predicted.u(c, q),
            self.nvar,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::{MAX_SEARCH, Seen};
    use proptest::prelude::*;

    proptest! {
        /// `Seen` is a set: an insert is new exactly when a `BTreeSet`'s is, for as many cells
        /// as a search holds, near each other (as a search's are) or anywhere in a large grid.
        #[test]
        fn seen_is_a_set(
            start in 0usize..(1 << 31),
            steps in prop::collection::vec(
                prop_oneof![0usize..8, Just(1usize << 20), 0usize..(1 << 24)],
                1..MAX_SEARCH + 6,
            ),
        ) {
            let mut seen = Seen::new();
            let mut set = std::collections::BTreeSet::new();
            let mut c = start;
            for (k, d) in steps.iter().enumerate() {
                c = if k % 2 == 0 { c + d } else { c.saturating_sub(*d) };
                let c = c % (u32::MAX as usize);
                prop_assert_eq!(seen.insert(c), set.insert(c), "cell {}", c);
            }
        }
    }
}
