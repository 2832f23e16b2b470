//! [`NearWall`]: the wet surface of `F^n` inside one near cell, as the ghost states and the
//! crack test see it; built from order-independent sums (the `NW_*` slots).

use crate::fv::Wall;

/// The wet surface of `F^n` inside one near cell, as its ghost states see it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct NearWall {
    /// Area of its sub-faces.
    pub(super) area: f64,
    /// Area-averaged velocity of its sub-faces [m/s].
    pub(super) velocity: [f64; 3],
    /// Per sweep axis `a`: `Σ A |ν_a| ν` over its sub-faces (unnormalised), the normal the sweep
    /// along `a` sees: sub-faces parallel to the axis do not count, so a box's corner cell
    /// shows each sweep the face across it.
    pub(super) normal: [[f64; 3]; 3],
    /// Per sweep axis `a` and side (0: `ν_a > 0`, the solid below along `a`; 1: `ν_a < 0`):
    /// `Σ A`, `Σ A w` and `Σ A |ν_a| ν` of the sub-faces facing that way. A run of covered cells
    /// seen across the axis sees only the faces turned towards the fluid: a gap between two
    /// walls (a crack) has a different wall on each side.
    pub(super) facing: [[Facing; 2]; 3],
    /// Area of its wet sub-faces.
    pub(super) wet_area: f64,
    /// `Σ A ν` over its wet sub-faces.
    pub(super) wet_normal: [f64; 3],
}

/// The [`NearWall`]s of a window's near cells, by slot (the near cells' order): stored only for
/// the cells that hold sub-faces, a wall of no area for the others.
///
/// NOTE: a dense vector of one `NearWall` (472 bytes) per near cell was allocated and zeroed
/// by every call of the hooks, though most near cells hold no sub-face. The cells without
/// sub-faces read [`NearWall::NONE`], the value they held there, so the hooks see the same
/// walls.
#[derive(Clone, Debug, Default)]
pub(super) struct NearWalls {
    /// The walls of the cells' runs of sub-faces, in the runs' order.
    pub(super) runs: Vec<NearWall>,
    /// Per slot: 1 + the index in `runs` of the cell's wall (its last run), 0 without one.
    pub(super) run_of: Vec<u32>,
}

impl NearWalls {
    /// The wall of the near cell in slot `k`.
    #[inline]
    pub(super) fn get(&self, k: usize) -> &NearWall {
        match self.run_of[k] {
            0 => &NearWall::NONE,
            r => &self.runs[r as usize - 1],
        }
    }
}

/// The sub-faces of a near cell turned one way along one axis (see [`NearWall::facing`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Facing {
    area: f64,
    velocity: [f64; 3],
    normal: [f64; 3],
}

/// Slots of the sums per near cell that make a [`NearWall`] (see [`NearWall::from_sums`]).
pub(super) const NW_VELOCITY: usize = 0;
pub(super) const NW_NORMAL: usize = 3;
pub(super) const NW_AREA: usize = 12;
/// Per axis `a` and side, at `NW_FACING + NW_FACING_LEN (2 a + side)`: area, velocity, normal.
pub(super) const NW_FACING: usize = 13;
pub(super) const NW_FACING_LEN: usize = 7;
pub(super) const NW_WET_AREA: usize = NW_FACING + 6 * NW_FACING_LEN;
pub(super) const NW_WET_NORMAL: usize = NW_WET_AREA + 1;
pub(super) const NEAR_WALL_SUMS: usize = NW_WET_NORMAL + 3;

impl NearWall {
    /// The wall of a near cell without sub-faces: `NearWall::default()`.
    pub(super) const NONE: NearWall = NearWall {
        area: 0.0,
        velocity: [0.0; 3],
        normal: [[0.0; 3]; 3],
        facing: [[Facing {
            area: 0.0,
            velocity: [0.0; 3],
            normal: [0.0; 3],
        }; 2]; 3],
        wet_area: 0.0,
        wet_normal: [0.0; 3],
    };

    /// From its sums: `Σ A w` (3), `Σ A |ν_a| ν_b` (9, `a` major), `Σ A`, then per axis `a` and
    /// side `(2 a + side)` the facing sums `Σ A`, `Σ A w` (3), `Σ A |ν_a| ν` (3), then the wet
    /// area and `Σ A ν` over the wet sub-faces (3).
    pub(super) fn from_sums(v: &[f64]) -> NearWall {
        let v3 = |i: usize| [v[i], v[i + 1], v[i + 2]];
        let mut facing = [[Facing::default(); 2]; 3];
        for (a, sides) in facing.iter_mut().enumerate() {
            for (side, f) in sides.iter_mut().enumerate() {
                let base = NW_FACING + NW_FACING_LEN * (2 * a + side);
                *f = Facing {
                    area: v[base],
                    velocity: v3(base + 1),
                    normal: v3(base + 4),
                };
            }
        }
        NearWall {
            area: v[NW_AREA],
            velocity: v3(NW_VELOCITY),
            normal: [v3(NW_NORMAL), v3(NW_NORMAL + 3), v3(NW_NORMAL + 6)],
            facing,
            wet_area: v[NW_WET_AREA],
            wet_normal: v3(NW_WET_NORMAL),
        }
    }

    /// Whether a covered cell with this wall is a crack (or two bodies touching): wet faces of
    /// opposite normals, so no fluid between them yet. A single wet face on a grid plane, which
    /// the tie rule gives to the covered cell behind it, is not one: its `Σ A ν` is its area.
    pub(super) fn is_crack(&self) -> bool {
        let n = self.wet_normal;
        self.wet_area > 0.0
            && (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() <= 0.5 * self.wet_area
    }
}

impl NearWall {
    /// The wall a sweep along `axis` sees across a covered run on side `dir` (±1) of the fluid:
    /// the sub-faces turned towards the fluid, if any.
    pub(super) fn facing(&self, axis: usize, dir: isize) -> Option<Wall> {
        let f = &self.facing[axis][usize::from(dir > 0)];
        if f.area <= 0.0 {
            return None;
        }
        let n = f.normal;
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let mut wall = Wall::at_rest(axis);
        wall.velocity = f.velocity.map(|v| v / f.area);
        if len > 0.0 {
            wall.normal = n.map(|x| x / len);
        }
        Some(wall)
    }

    /// The wall a sweep along `axis` sees; normal to the axis if no sub-face faces it.
    pub(super) fn along(&self, axis: usize) -> Wall {
        let n = self.normal[axis];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let mut wall = Wall::at_rest(axis);
        wall.velocity = self.velocity;
        if len > 0.0 {
            wall.normal = n.map(|x| x / len);
        }
        wall
    }
}

#[cfg(test)]
mod tests {
    use super::{NearWall, NearWalls};

    /// The cells without sub-faces read `NONE`: it must be the dense vector's old fill value,
    /// to the bit (a `-0.0` would compare equal and change a sign downstream).
    #[test]
    fn a_cell_without_sub_faces_reads_the_default_wall_to_the_bit() {
        assert_eq!(
            format!("{:?}", NearWall::NONE),
            format!("{:?}", NearWall::default())
        );
        let wall = NearWall {
            area: 2.0,
            ..NearWall::default()
        };
        let walls = NearWalls {
            runs: vec![NearWall::default(), wall],
            run_of: vec![0, 2, 0],
        };
        assert_eq!(walls.get(0), &NearWall::NONE);
        assert_eq!(walls.get(1).area, 2.0);
        assert_eq!(walls.get(2), &NearWall::NONE);
    }
}
