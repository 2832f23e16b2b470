//! Elements beyond the domain: the pieces, in domain cells, of the swept prisms of sub-faces
//! that lie beyond it (a beam clamped beyond a wall, its shared vertices moving; a body leaving
//! by an open side), and the stop of a surface that reaches a periodic side.

use super::{EmbeddedError, NEAR_RADIUS};
use crate::cutcell::{CutGeometry, SubfaceSwept, Surface, compute, subface_swept_volumes};
use crate::fv::BoundaryKind;
use crate::grid::Grid;

/// NOTE: the geometry does not wrap across a periodic side: the faces of its two sides would get
/// different apertures and the flux the sweeps share across them would no longer be shared (a
/// body crossing one lost up to 3e-5 of the mass in the generated corpus). So a surface with a
/// vertex at or beyond a periodic side stops the run, before the step changes anything. Walls
/// may be touched and crossed ([`sweep_beyond`]), open sides too (the gas a body pushes out
/// counted as leaving: `Embedded::fluid_fluxes`, `Mixing::mix_group`).
pub(super) fn outside_domain(
    grid: &Grid,
    boundary: &[[BoundaryKind; 2]; 3],
    after: &Surface,
) -> Result<(), EmbeddedError> {
    const SIDES: [[&str; 2]; 3] = [["x-", "x+"], ["y-", "y+"], ["z-", "z+"]];
    let dim = grid.dim;
    for (e, nodes) in after.elements.chunks_exact(dim).enumerate() {
        for &i in nodes {
            let mut x = [0.0; 3];
            x[..dim].copy_from_slice(&after.vertices[i as usize * dim..(i as usize + 1) * dim]);
            for a in 0..dim {
                for side in 0..2 {
                    let reached = if side == 0 {
                        x[a] <= grid.lower[a]
                    } else {
                        x[a] >= grid.upper[a]
                    };
                    if reached && boundary[a][side] == BoundaryKind::Periodic {
                        return Err(EmbeddedError::OutsideDomain {
                            step: None,
                            side: SIDES[a][side],
                            particle: after.element_particle.get(e).copied().unwrap_or(0),
                            vertex: x,
                        });
                    }
                }
            }
        }
    }
    Ok(())
}

/// NOTE: sub-faces, and so swept prisms, exist only inside the domain, so where part of an
/// element moves across the domain's boundary (a beam whose clamped particle lies beyond a
/// wall, the mean vertices it shares moving) the prisms of the domain's sub-faces alone do
/// not add up to the change of Λ in the boundary cells (1.3e-10 of a cell in the 3-D beam
/// centred on y = 0, issue 13, and mass lost when let through). The elements that move and
/// have a vertex beyond the domain, at `t^n` or `t^{n+1}`, are clipped again on the grid grown
/// by `NEAR_RADIUS + 1` cells on every side; the pieces, in domain cells, of the prisms of
/// their sub-faces beyond the domain go into `beyond`, by cell. Nothing is done (and nothing
/// changes) while the surface stays inside the domain.
pub(super) fn sweep_beyond(
    grid: &Grid,
    before: &Surface,
    after: &Surface,
    geom: &mut CutGeometry,
    swept: &mut SubfaceSwept,
    beyond: &mut Vec<(u32, f64)>,
) {
    beyond.clear();
    let dim = grid.dim;
    let out = |v: &[f64], i: u32| {
        let x = &v[i as usize * dim..(i as usize + 1) * dim];
        (0..dim).any(|a| x[a] < grid.lower[a] || x[a] > grid.upper[a])
    };
    let mut elements = Vec::new();
    let mut particles = Vec::new();
    let moved = |i: u32| {
        let r = i as usize * dim..(i as usize + 1) * dim;
        before.vertices[r.clone()] != after.vertices[r]
    };
    for (e, nodes) in after.elements.chunks_exact(dim).enumerate() {
        // (An element that does not move has empty prisms: fixed clamps beyond a wall cost
        // nothing.)
        if nodes
            .iter()
            .any(|&i| out(before.vertices, i) || out(after.vertices, i))
            && nodes.iter().any(|&i| moved(i))
        {
            elements.extend_from_slice(nodes);
            particles.push(after.element_particle.get(e).copied().unwrap_or(0));
        }
    }
    if elements.is_empty() {
        return;
    }
    let g = NEAR_RADIUS + 1;
    let (mut lower, mut upper, mut cells) = ([0.0; 3], [0.0; 3], [0usize; 3]);
    for a in 0..dim {
        lower[a] = grid.lower[a] - g as f64 * grid.dx[a];
        upper[a] = grid.upper[a] + g as f64 * grid.dx[a];
        cells[a] = grid.cells[a] + 2 * g;
    }
    let ext = Grid::new(&lower[..dim], &upper[..dim], &cells[..dim])
        .expect("a grown grid of a valid grid is valid");
    let before = Surface {
        dim,
        vertices: before.vertices,
        elements: &elements,
        element_particle: &particles,
    };
    let after = Surface {
        dim,
        vertices: after.vertices,
        elements: &elements,
        element_particle: &particles,
    };
    compute(&ext, &after, geom);
    subface_swept_volumes(&ext, &before, &after, geom, swept);
    let inside = |c: u32| -> Option<u32> {
        let ijk = ext.ijk(c as usize);
        let mut d = [0usize; 3];
        for a in 0..3 {
            if a < dim {
                d[a] = ijk[a].checked_sub(g).filter(|&i| i < grid.cells[a])?;
            }
        }
        Some(grid.index(d[0], d[1], d[2]) as u32)
    };
    for e in &swept.entries {
        let face_cell = geom.subfaces[e.subface as usize].cell;
        if inside(face_cell).is_some() {
            continue;
        }
        if let Some(c) = inside(e.cell) {
            beyond.push((c, e.volume));
        }
    }
    beyond.sort_unstable_by_key(|b| b.0);
}
