//! One directional sweep over the whole grid: pencils along the sweep axis, gathered with their
//! ghost cells, advanced by `line::advance_line`, written back.
//!
//! Parallelism: pencils are cut into blocks of [`BLOCK_PENCILS`] (a fixed partition that does
//! not depend on the thread count) and blocks run on rayon. Each pencil's result depends only
//! on the input state, so the result is bit-identical for any number of threads. A block reads
//! its cells straight into its pencils' lines and writes its results from the lines the kernel
//! wrote, straight into a second buffer in the x-fastest layout (`block.rs`), which the caller
//! swaps with the state.

use std::sync::Mutex;

use rayon::prelude::*;

use crate::fv::block::{Block, CellWriter, gather_block};
use crate::fv::euler::{NQ, State, flux_hlle, flux_local_lax_friedrichs, primitive_floored};
use crate::fv::line::{LineScratch, LineSetup, LineStats, advance_line};
use crate::fv::state::{BoundaryKind, FluidParams};
use crate::grid::Grid;

pub use crate::fv::block::BLOCK_PENCILS;

/// The pencils along one axis.
#[derive(Clone, Copy, Debug)]
pub struct Pencils {
    /// Cells per pencil.
    pub n: usize,
    /// Index distance between consecutive cells of a pencil.
    pub stride: usize,
    /// Number of pencils.
    pub count: usize,
}

impl Pencils {
    /// Pencils of `grid` along `axis`.
    pub fn new(grid: &Grid, axis: usize) -> Pencils {
        let n = grid.cells[axis];
        let stride: usize = grid.cells[..axis].iter().product();
        Pencils {
            n,
            stride,
            count: grid.n_cells() / n,
        }
    }

    /// Linear index of the first cell of pencil `p`.
    #[inline]
    pub fn base(&self, p: usize) -> usize {
        let lo = p % self.stride;
        let hi = p / self.stride;
        lo + hi * self.stride * self.n
    }
}

/// Storage axis of each sweep-frame velocity slot `(n, t1, t2)`; `None` for inactive slots.
pub fn frame(dim: usize, axis: usize) -> [Option<usize>; 3] {
    let mut out = [None; 3];
    out[0] = Some(axis);
    let mut slot = 1;
    for a in 0..dim {
        if a != axis {
            out[slot] = Some(a);
            slot += 1;
        }
    }
    out
}

/// What one pencil reports back.
#[derive(Clone, Copy, Debug, Default)]
pub struct PencilOut {
    /// Flux leaving through the pencil's low and high domain faces during the sweep, per unit
    /// face area and per unit time, in the physical order `(mass, p_x, p_y, p_z, energy)`;
    /// periodic faces and faces between two ranks are not counted (zero).
    pub outflow: [[f64; NQ]; 2],
    /// Face counters.
    pub stats: LineStats,
    /// First cell of the pencil left non-physical after the update (linear index).
    pub trouble: Option<usize>,
}

#[inline]
pub(crate) fn to_local(cell: &[f64], dim: usize, fr: &[Option<usize>; 3]) -> State {
    let mut s = [0.0; NQ];
    s[0] = cell[0];
    for slot in 0..3 {
        if let Some(a) = fr[slot] {
            s[1 + slot] = cell[1 + a];
        }
    }
    s[4] = cell[dim + 1];
    s
}

#[inline]
pub(crate) fn from_local(s: &State, dim: usize, fr: &[Option<usize>; 3], cell: &mut [f64]) {
    cell[0] = s[0];
    for slot in 0..3 {
        if let Some(a) = fr[slot] {
            cell[1 + a] = s[1 + slot];
        }
    }
    cell[dim + 1] = s[4];
}

/// Ghost state of a characteristic outflow side, in the sweep frame, from the boundary cell
/// `s`; `sigma` is the relaxation coefficient σ, `outward` the sign of the outward normal (−1 low side, +1 high side), `n` the cells
/// along the axis (so the domain length is `L = n dx`).
///
/// Linearised about the boundary cell (ρ, u_n outward, p, c), the characteristic variables are
/// `w± = p ± ρc u_n` (speeds `u_n ± c`), the entropy `ρ − p/c²` and the tangential velocities.
/// Outgoing ones are extrapolated at zero order (ghost = cell). In subsonic outflow or inflow
/// the incoming `w−` gets a jump `Δw = −σ (1 + M) (p − p_far) / n`: the Riemann problem at the
/// boundary face then sends into the cell, per step, the pressure change of the LODI
/// relaxation `L_in = K (p − p_far)` with `K = σ (1 − M²) c / L` (Poinsot & Lele 1992, eq. 40),
/// since the incoming wave of speed `c − u_n` covers the fraction `(c − u_n) dt / dx` of the
/// cell. `Δw = 0` (p = p_far) or `|u_n| ≥ c` give the cell itself, bit for bit; so does a
/// non-physical or vacuum cell. With σ = 0 this is the zero-gradient outflow, which is already
/// non-reflecting for waves leaving along the axis in this characteristic-wise scheme
/// (LeVeque 2002 §7.3.1); the relaxation is what keeps the far-field pressure.
#[inline]
pub fn characteristic_ghost(
    s: &State,
    outward: f64,
    p_far: f64,
    sigma: f64,
    gamma: f64,
    n: usize,
) -> State {
    let rho = s[0];
    if rho.is_nan() || rho <= 0.0 {
        return *s;
    }
    let vel = [s[1] / rho, s[2] / rho, s[3] / rho];
    let ke = 0.5 * rho * (vel[0] * vel[0] + vel[1] * vel[1] + vel[2] * vel[2]);
    let p = (gamma - 1.0) * (s[4] - ke);
    if p.is_nan() || p <= 0.0 {
        return *s;
    }
    let c = (gamma * p / rho).sqrt();
    let un = outward * vel[0];
    let mach = un / c;
    if mach.is_nan() || mach.abs() >= 1.0 {
        return *s;
    }
    let dw = -sigma * (1.0 + mach) * (p - p_far) / n as f64;
    if dw == 0.0 {
        return *s;
    }
    let p_g = p + 0.5 * dw;
    let rho_g = rho + 0.5 * dw / (c * c);
    let un_g = un - 0.5 * dw / (rho * c);
    if !(p_g > 0.0 && rho_g > 0.0) {
        return *s;
    }
    let v_g = [outward * un_g, vel[1], vel[2]];
    let ke_g = 0.5 * rho_g * (v_g[0] * v_g[0] + v_g[1] * v_g[1] + v_g[2] * v_g[2]);
    [
        rho_g,
        rho_g * v_g[0],
        rho_g * v_g[1],
        rho_g * v_g[2],
        p_g / (gamma - 1.0) + ke_g,
    ]
}

/// The halo of a sweep along the decomposed axis (`slab.rs`): the neighbours' planes nearest
/// this rank, x-fastest within a plane, lowest plane first; `None` at a domain face.
#[derive(Clone, Copy, Debug)]
pub struct SlabHalo<'a> {
    /// `depth` planes of the rank below.
    pub lo: Option<&'a [f64]>,
    /// `depth` planes of the rank above.
    pub hi: Option<&'a [f64]>,
    /// Planes per side.
    pub depth: usize,
    /// Cells of a neighbour's side each pencil updates as well (`depth − ng`).
    pub overlap: usize,
    /// Cells along the axis over all ranks (the characteristic boundary's domain length, and
    /// the pencil length the [`WallRun`]s' segments are measured on).
    pub n_global: usize,
    /// Position along the whole pencil of the line's first updated cell (the rank's first
    /// plane less the overlap below it; negative on rank 0 with a periodic neighbour below).
    pub start: isize,
}

impl SlabHalo<'_> {
    /// No neighbours: a pencil of `n` cells is the whole line.
    pub fn none(n: usize) -> SlabHalo<'static> {
        SlabHalo {
            lo: None,
            hi: None,
            depth: 0,
            overlap: 0,
            n_global: n,
            start: 0,
        }
    }

    /// Extra cells updated below and above the rank's own.
    fn overlaps(&self) -> [usize; 2] {
        [
            if self.lo.is_some() { self.overlap } else { 0 },
            if self.hi.is_some() { self.overlap } else { 0 },
        ]
    }
}

/// Fills the ghosts of the line of pencil `p`, whose interior cells are in place (in the sweep
/// frame, [`gather_block`]), from the pencil's own cells and from the halo planes of `halo` where a neighbour rank
/// is: the line then holds `n + k_lo + k_hi` updated cells (`k` = [`SlabHalo::overlap`] on
/// each side with a neighbour) and `ng` ghosts beyond them.
#[allow(clippy::too_many_arguments)]
fn gather(
    line: &mut [State],
    nvar: usize,
    pencils: &Pencils,
    p: usize,
    ng: usize,
    fr: &[Option<usize>; 3],
    bc: [BoundaryKind; 2],
    gamma: f64,
    halo: &SlabHalo<'_>,
) {
    let dim = nvar - 2;
    let own = pencils.n;
    let [k_lo, k_hi] = halo.overlaps();
    let n = own + k_lo + k_hi;
    // The halo's planes hold the cells of each plane in the order of the pencils.
    let plane = pencils.count;
    let from_plane = |planes: &[f64], t: usize| {
        let c = (t * plane + p) * nvar;
        to_local(&planes[c..c + nvar], dim, fr)
    };
    if let Some(planes) = halo.lo {
        for t in 0..halo.depth {
            line[t] = from_plane(planes, t);
        }
    }
    if let Some(planes) = halo.hi {
        for t in 0..halo.depth {
            line[ng + k_lo + own + t] = from_plane(planes, t);
        }
    }
    let mirror = |mut s: State| {
        s[1] = -s[1];
        s
    };
    let far = |side: usize, s: State, outward: f64| match bc[side] {
        BoundaryKind::Characteristic { p_far, sigma } => {
            characteristic_ghost(&s, outward, p_far, sigma, gamma, halo.n_global)
        }
        _ => s,
    };
    let ghost_lo = far(0, line[ng], -1.0);
    let ghost_hi = far(1, line[ng + n - 1], 1.0);
    for g in 0..ng {
        // Low side: ghost ng−1−g (a neighbour's halo already sits there).
        if halo.lo.is_none() {
            line[ng - 1 - g] = match bc[0] {
                BoundaryKind::Periodic => line[ng + (n - 1 - g % n)],
                BoundaryKind::Outflow => line[ng],
                BoundaryKind::Characteristic { .. } => ghost_lo,
                BoundaryKind::Wall => mirror(line[ng + g.min(n - 1)]),
            };
        }
        // High side: ghost ng+n+g.
        if halo.hi.is_none() {
            line[ng + n + g] = match bc[1] {
                BoundaryKind::Periodic => line[ng + g % n],
                BoundaryKind::Outflow => line[ng + n - 1],
                BoundaryKind::Characteristic { .. } => ghost_hi,
                BoundaryKind::Wall => mirror(line[ng + n - 1 - g.min(n - 1)]),
            };
        }
    }
}

/// Faces of one sweep axis whose fluxes a coupled step keeps (paper 003 §3.4 step 1: the fluxes
/// of the faces near the wet surface, not of the whole grid).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FaceTap {
    /// `positions[pencil_offsets[p]..pencil_offsets[p + 1]]` are the faces kept in pencil `p`
    /// (`pencil_offsets.len()` = pencils + 1).
    pub pencil_offsets: Vec<u32>,
    /// Face positions along the gathered line, `0..=n` (face `m` is the low face of cell `m`);
    /// a decomposed sweep's line starts at [`SlabHalo::start`], so there face `m` of the line is
    /// face `m + start` of the whole pencil.
    pub positions: Vec<u32>,
    /// Output: the flux of each kept face in the physical order `(mass, p_x, p_y, p_z,
    /// energy)`, per unit area and time; filled by [`sweep_axis`].
    pub flux: Vec<State>,
}

impl FaceTap {
    /// An empty tap for `count` pencils.
    pub fn clear(&mut self, count: usize) {
        self.pencil_offsets.clear();
        self.pencil_offsets.resize(count + 1, 0);
        self.positions.clear();
        self.flux.clear();
    }
}

/// The solid wall a ghost state stands behind: its velocity and unit normal, in the storage
/// axes (`[x, y, z]`) or, after [`Wall::in_frame`], in a sweep's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wall {
    /// Wall velocity [m/s].
    pub velocity: [f64; 3],
    /// Unit normal (either sign).
    pub normal: [f64; 3],
}

impl Wall {
    /// A wall at rest normal to `axis`.
    pub fn at_rest(axis: usize) -> Wall {
        let mut normal = [0.0; 3];
        normal[axis] = 1.0;
        Wall {
            velocity: [0.0; 3],
            normal,
        }
    }

    /// The same wall in the frame `(n, t1, t2)` of a sweep (see [`frame`]).
    pub fn in_frame(&self, fr: &[Option<usize>; 3]) -> Wall {
        let pick = |v: &[f64; 3]| std::array::from_fn(|slot| fr[slot].map_or(0.0, |a| v[a]));
        Wall {
            velocity: pick(&self.velocity),
            normal: pick(&self.normal),
        }
    }
}

/// Ghost state of the sweep-frame state `s` behind `wall` (in the same frame): density,
/// pressure and the tangential velocity relative to the wall kept, the normal one reversed,
/// `u_g = u − 2 ((u − w)·n) n` (numerics notes §2.6).
///
/// NOTE: a wall normal to the sweep axis gives `m_n → 2 ρ w_n − m_n` exactly as the mirror
/// along the sweep line does. Mirroring only the axis component for an oblique wall put a
/// colliding stream into the stencils beside a wall swept by a tangential Mach-5 flow, and the
/// small cut cells there ended with more kinetic than total energy.
#[inline]
pub fn mirror(s: &State, wall: &Wall) -> State {
    let mut g = *s;
    let rho = s[0];
    let n = wall.normal;
    if n[1] == 0.0 && n[2] == 0.0 {
        let m = s[1];
        if rho > 0.0 {
            let mirrored = rho * 2.0 * wall.velocity[0] - m;
            g[1] = mirrored;
            g[4] += 0.5 * (mirrored * mirrored - m * m) / rho;
        } else {
            g[1] = -m;
        }
        return g;
    }
    let m = [s[1], s[2], s[3]];
    let w = if rho > 0.0 { wall.velocity } else { [0.0; 3] };
    let scale = if rho > 0.0 { rho } else { 1.0 };
    let vn: f64 = (0..3).map(|a| (m[a] / scale - w[a]) * n[a]).sum();
    let mut ke_change = 0.0;
    for a in 0..3 {
        let mirrored = m[a] - 2.0 * scale * vn * n[a];
        ke_change += mirrored * mirrored - m[a] * m[a];
        g[1 + a] = mirrored;
    }
    if rho > 0.0 {
        g[4] += 0.5 * ke_change / rho;
    }
    g
}

/// A short run of covered cells with fluid on both sides along one pencil: a wall thinner than
/// the two stencils that meet in it. The sweep cuts the pencil there and gives each fluid
/// segment its own mirror ghosts, so that no face's stencil reaches through the wall into the
/// fluid on its far side. Positions are along the whole pencil (all ranks); a decomposed sweep
/// gets every run of its pencils, also those outside its line, since a segment's mirror ghosts
/// depend on its length on one rank.
///
/// NOTE: a single state per covered cell cannot serve both sides once the run is shorter than
/// `2 ng`: the ghosts split the run between the two sides, and the third cell of an order-5
/// stencil then read the far side's gas (a 50:1 pressure jump across a 0.1 m cylinder wall
/// made the near cut cell's pressure negative).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallRun {
    /// Pencil along the sweep axis.
    pub pencil: u32,
    /// First covered cell of the run (position along the pencil, `> 0`).
    pub lo: u32,
    /// One past the last covered cell (`< n`).
    pub hi: u32,
    /// The wall seen from the fluid before `lo` and from the fluid at `hi` (storage axes).
    pub walls: [Wall; 2],
}

/// Splits the kept fluxes into one slice per block of [`BLOCK_PENCILS`] pencils, each with the
/// offsets of its pencils (empty without a tap), so that blocks fill them in parallel.
type TapBlock<'a> = (&'a [u32], &'a mut [State]);

fn tap_blocks<'a>(offsets: &'a [u32], flux: &'a mut [State], count: usize) -> Vec<TapBlock<'a>> {
    let n_blocks = count.div_ceil(BLOCK_PENCILS);
    if offsets.is_empty() {
        return (0..n_blocks).map(|_| (&[][..], &mut [][..])).collect();
    }
    debug_assert_eq!(offsets.len(), count + 1);
    let mut rest = flux;
    let mut blocks = Vec::with_capacity(n_blocks);
    for b in 0..n_blocks {
        let lo = offsets[b * BLOCK_PENCILS] as usize;
        let hi = offsets[((b + 1) * BLOCK_PENCILS).min(count)] as usize;
        let (mine, tail) = rest.split_at_mut(hi - lo);
        rest = tail;
        blocks.push((&offsets[b * BLOCK_PENCILS..], mine));
    }
    blocks
}

/// Blocks of pencils a task of the sweep takes at most.
///
/// NOTE: rayon splits a parallel loop into about four pieces a thread and splits a piece
/// further only when another thread steals it, so the piece a thread runs last is not split:
/// on 2 threads, 128³, that was a quarter of a sweep's 1,024 blocks (about 11 ms), and the
/// other thread slept up to that long at every sweep's end (5–16 ms a sweep in
/// `perf sched timehist` of `fv_blast3d`). A task is one block (16 pencils, ≈ 45 µs at 128³):
/// tasks of 4 blocks left small grids few tasks (the 2-D beam's 400 × 200 sweeps have 13 and 25
/// blocks), and one block a task ran `clamped-beam-2d` 2 % faster (mean of 32 alternated runs)
/// at no cost to the 128³ blast.
const BLOCKS_PER_TASK: usize = 1;

/// Sweeps `u_in` along `axis` with time step `dt` \[s\]; writes the new states into `out` (the
/// layout of `u_in`), one [`PencilOut`] per pencil, and the fluxes of the faces `tap` names. `halo` holds
/// the neighbours' planes of a sweep along the decomposed axis ([`SlabHalo::none`] otherwise).
#[allow(clippy::too_many_arguments)]
pub fn sweep_axis(
    grid: &Grid,
    params: &FluidParams,
    axis: usize,
    dt: f64,
    u_in: &[f64],
    out: &mut [f64],
    scratch: &[Mutex<LineScratch>],
    pencil_out: &mut [PencilOut],
    tap: Option<&mut FaceTap>,
    walls: &[WallRun],
    halo: &SlabHalo<'_>,
) {
    debug_assert!(walls.is_sorted_by_key(|w| (w.pencil, w.lo)));
    let [k_lo, k_hi] = halo.overlaps();
    let dim = grid.dim;
    let nvar = dim + 2;
    let pencils = Pencils::new(grid, axis);
    let n = pencils.n;
    let ng = params.ghost_cells();
    let fr = frame(dim, axis);
    let bc = params.boundary[axis];
    let n_line = n + k_lo + k_hi;
    let setup = LineSetup {
        n: n_line,
        ng,
        flux: params.flux,
        sigma: dt / grid.dx[axis],
        gamma: params.gamma,
        n_shear: dim - 1,
        vacuum_rho: params.vacuum_rho,
        vacuum_p: params.vacuum_p,
        wall: [
            bc[0] == BoundaryKind::Wall && halo.lo.is_none(),
            bc[1] == BoundaryKind::Wall && halo.hi.is_none(),
        ],
        own: [k_lo, k_lo + n],
        end_face: true,
    };
    let open = [
        bc[0] != BoundaryKind::Periodic && halo.lo.is_none(),
        bc[1] != BoundaryKind::Periodic && halo.hi.is_none(),
    ];
    let pencil_out = &mut pencil_out[..pencils.count];
    let (offsets, positions, flux): (&[u32], Option<&[u32]>, &mut [State]) = match tap {
        Some(t) => {
            t.flux.resize(t.positions.len(), [0.0; NQ]);
            (&t.pencil_offsets, Some(&t.positions), &mut t.flux)
        }
        None => (&[], None, &mut []),
    };
    let mut taps = tap_blocks(offsets, flux, pencils.count);
    let writer = CellWriter::new(&mut out[..u_in.len()]);
    pencil_out
        .par_chunks_mut(BLOCK_PENCILS)
        .zip(taps.par_iter_mut())
        .enumerate()
        .with_max_len(BLOCKS_PER_TASK)
        .for_each(|(block, (rep_block, (offsets, kept)))| {
            let thread = rayon::current_thread_index().unwrap_or(0) % scratch.len();
            let mut guard = scratch[thread]
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            let line = &mut *guard;
            line.resize(n_line, ng);
            let p0 = block * BLOCK_PENCILS;
            let bases = (p0..p0 + rep_block.len()).map(|p| pencils.base(p));
            let cells = Block::new(bases, pencils.n, pencils.stride);
            let count = rep_block.len();
            for tiles in [&mut line.tile_u, &mut line.tile_new] {
                tiles.resize_with(count.max(tiles.len()), Vec::new);
            }
            for t in &mut line.tile_u[..count] {
                t.resize(n_line + 2 * ng, [0.0; NQ]);
            }
            for t in &mut line.tile_new[..count] {
                t.resize(n_line, [0.0; NQ]);
            }
            // Pencil k's own cells go to its line's `u` at ng + k_lo, and come back from its
            // `new` at k_lo.
            gather_block(&mut line.tile_u, ng + k_lo, u_in, nvar, &cells, &fr);
            for (k, rep) in rep_block.iter_mut().enumerate() {
                let p = block * BLOCK_PENCILS + k;
                std::mem::swap(&mut line.u, &mut line.tile_u[k]);
                gather(
                    &mut line.u,
                    nvar,
                    &pencils,
                    p,
                    ng,
                    &fr,
                    bc,
                    params.gamma,
                    halo,
                );
                let lo = walls.partition_point(|w| w.pencil < p as u32);
                let hi = walls.partition_point(|w| w.pencil <= p as u32);
                let stats = if lo == hi {
                    advance_line(line, &setup)
                } else {
                    advance_segments(line, &setup, &walls[lo..hi], &fr, halo)
                };
                std::mem::swap(&mut line.new, &mut line.tile_new[k]);
                let base = pencils.base(p);
                if let Some(positions) = positions {
                    let (lo, hi) = (offsets[k] as usize, offsets[k + 1] as usize);
                    let first = offsets[0] as usize;
                    for slot in lo..hi {
                        let f = &line.face[positions[slot] as usize];
                        let phys = &mut kept[slot - first];
                        *phys = [f[0], 0.0, 0.0, 0.0, f[4]];
                        for q in 0..3 {
                            if let Some(a) = fr[q] {
                                phys[1 + a] = f[1 + q];
                            }
                        }
                    }
                }
                let trouble = stats.first_bad.map(|m| base + m as usize * pencils.stride);
                let mut outflow = [[0.0; NQ]; 2];
                for (side, sign, f) in [(0, -1.0, 0), (1, 1.0, n_line)] {
                    if open[side] {
                        let flux = &line.face[f];
                        let out = &mut outflow[side];
                        out[0] = sign * flux[0];
                        for slot in 0..3 {
                            if let Some(a) = fr[slot] {
                                out[1 + a] = sign * flux[1 + slot];
                            }
                        }
                        out[4] = sign * flux[4];
                    }
                }
                *rep = PencilOut {
                    outflow,
                    stats,
                    trouble,
                };
            }
            // SAFETY: this block alone writes the cells of its pencils (a cell lies on one
            // pencil along `axis`, a pencil in one block), and `u_in` is another buffer.
            unsafe { writer.scatter_block(&line.tile_new, k_lo, nvar, &cells, &fr) };
        });
}

/// [`advance_line`] of a gathered pencil cut at its [`WallRun`]s: each fluid segment is updated
/// as a line of its own, with mirror ghosts (relative to the wall velocity) at the walls and
/// the pencil's own ghosts at the domain ends. Covered cells keep their state; the faces inside
/// a run carry a two-point flux between its ghost states ([`run_faces`]), which no cell reads.
/// A segment's fluxes and states are those of a pencil that ended at the wall, so a run of
/// `2 ng` or more cells gives bit for bit what the uncut pencil gives its fluid.
///
/// The segments are those of the whole pencil (`halo.n_global` cells, `runs` at positions along
/// it); a decomposed line (`halo.start`) updates the part of each segment it holds, with the
/// segment's mirror ghosts where they fall inside its ghost cells and the neighbour's cells
/// elsewhere, so that its own cells see what they see on one rank (the overlap absorbs the
/// truncation, as for a line without walls).
fn advance_segments(
    line: &mut LineScratch,
    setup: &LineSetup,
    runs: &[WallRun],
    fr: &[Option<usize>; 3],
    halo: &SlabHalo<'_>,
) -> LineStats {
    let (n, ng) = (setup.n, setup.ng);
    let (start, n_pencil) = (halo.start, halo.n_global as isize);
    let [own_lo, own_hi] = setup.own;
    let mut full = std::mem::take(&mut line.pencil);
    let mut new = std::mem::take(&mut line.pencil_new);
    let mut face = std::mem::take(&mut line.pencil_face);
    full.clone_from(&line.u);
    new.clear();
    new.extend_from_slice(&full[ng..ng + n]);
    face.clear();
    face.resize(n + 1, [0.0; NQ]);
    // The line cell at position `p` (−ng ≤ p < n + ng) of the input.
    let at = |full: &[State], p: isize| full[(p + ng as isize) as usize];
    let mut stats = LineStats::default();
    let mut seg_lo = 0isize;
    for k in 0..=runs.len() {
        let seg_hi = runs.get(k).map_or(n_pencil, |r| r.lo as isize);
        let (w_lo, w_hi) = (
            k.checked_sub(1).map(|j| runs[j].walls[1].in_frame(fr)),
            runs.get(k).map(|r| r.walls[0].in_frame(fr)),
        );
        let (ls, le) = (seg_lo - start, seg_hi - start);
        let m_full = seg_hi - seg_lo;
        debug_assert!(m_full > 0, "wall runs of one pencil are separated by fluid");
        if let Some(r) = runs.get(k) {
            seg_lo = r.hi as isize;
        }
        if le <= 0 || ls >= n as isize {
            continue;
        }
        let (cs, ce) = (ls.max(0) as usize, le.min(n as isize) as usize);
        let m = ce - cs;
        let (lo, hi) = (own_lo.clamp(cs, ce), own_hi.clamp(cs, ce));
        let seg = LineSetup {
            n: m,
            wall: [cs == 0 && setup.wall[0], ce == n && setup.wall[1]],
            own: [lo - cs, hi - cs],
            end_face: (own_lo..own_hi).contains(&ce) || (ce == own_hi && ce == n && setup.end_face),
            ..*setup
        };
        line.resize(m, ng);
        line.u.copy_from_slice(&full[cs..ce + 2 * ng]);
        // Mirror ghosts where the whole segment's fall inside this line's ghost cells: ghost `g`
        // of the segment is the mirror of its cell `min(g, m_full − 1)`.
        if let Some(w) = w_lo {
            for p in (cs as isize - ng as isize)..(cs as isize).min(ls) {
                let g = ls - 1 - p;
                let src = at(&full, ls + g.min(m_full - 1));
                line.u[(p - cs as isize + ng as isize) as usize] = mirror(&src, &w);
            }
        }
        if let Some(w) = w_hi {
            for p in le.max(ce as isize)..(ce + ng) as isize {
                let g = p - le;
                let src = at(&full, le - 1 - g.min(m_full - 1));
                line.u[(p - cs as isize + ng as isize) as usize] = mirror(&src, &w);
            }
        }
        let s = advance_line(line, &seg);
        new[cs..ce].copy_from_slice(&line.new[..m]);
        face[cs..=ce].copy_from_slice(&line.face[..=m]);
        stats.lax_friedrichs += s.lax_friedrichs;
        stats.hlle += s.hlle;
        stats.positivity_fixes += s.positivity_fixes;
        if stats.first_bad.is_none() {
            stats.first_bad = s.first_bad.map(|b| b + (lo - own_lo) as u32);
        }
    }
    run_faces(&full, &mut face, setup, runs, start);
    line.resize(n, ng);
    line.new.copy_from_slice(&new);
    line.face.copy_from_slice(&face);
    line.pencil = full;
    line.pencil_new = new;
    line.pencil_face = face;
    stats
}

/// The fluxes of the faces inside the `runs` of a cut pencil (`full`: the gathered line, `face`:
/// its faces, `start`: its first cell along the pencil): a two-point flux between the ghost
/// states on either side, HLLE (the local Lax–Friedrichs flux beside vacuum: these faces lie
/// inside the solid at t^n, and the classical flux's diffusion `Δx/Δt` between a ghost state and
/// vacuum is no flux the gas makes; docs/cut-cells.md §4).
/// No cell reads them; they are kept for the correct, where a face between two cells covered
/// at t^n carries the sweep's flux once the solid uncovers part of it at t^{n+1} (eq. 13).
///
/// NOTE: zero there broke a uniform flow carried past a moving box by up to 6e-2 of its state
/// (a box 3–4 cells thick in 3-D, a face parallel to a grid plane uncovering a row of cells at
/// once: the face between two of them opened by 8 % with no flux through it). The ghost states
/// of a uniform flow at the wall's velocity are that flow, so these fluxes are its flux, and
/// the identity of eq. (12) holds to round-off (test `embedded_uniform`).
fn run_faces(
    full: &[State],
    face: &mut [State],
    setup: &LineSetup,
    runs: &[WallRun],
    start: isize,
) {
    let (n, ng) = (setup.n as isize, setup.ng as isize);
    let gas = |u: &State| {
        let w = primitive_floored(u, setup.gamma, setup.vacuum_rho);
        w.rho > 0.0 && w.p > 0.0 && w.rho >= setup.vacuum_rho && w.p >= setup.vacuum_p
    };
    for r in runs {
        for pf in (r.lo as isize + 1)..(r.hi as isize) {
            let f = pf - start;
            if !(0..=n).contains(&f) {
                continue;
            }
            let (ul, ur) = (&full[(f - 1 + ng) as usize], &full[(f + ng) as usize]);
            face[f as usize] = if gas(ul) && gas(ur) {
                flux_hlle(ul, ur, setup.gamma)
            } else {
                flux_local_lax_friedrichs(ul, ur, setup.sigma, setup.gamma, setup.vacuum_rho)
            };
        }
    }
}
