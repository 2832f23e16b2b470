//! Orientations as stored in the state: the quaternion `(w, x, y, z)` of the principal frame
//! (3-D) or the angle in `rot[0]` (2-D), and the rotation of a body vector into space.

use nalgebra::{UnitQuaternion, Vector3};

/// The unit quaternion of a stored orientation `(w, x, y, z)` (3-D).
pub(super) fn quat(r: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(r[0], r[1], r[2], r[3]))
}

/// The stored form `(w, x, y, z)` of a unit quaternion.
pub(super) fn quat_arr(q: &UnitQuaternion<f64>) -> [f64; 4] {
    [q.w, q.i, q.j, q.k]
}

/// A body vector `v` of a particle with stored orientation `rot` turned into space (2-D: the
/// rotation by the angle `rot[0]` about z).
pub(super) fn rotate_body(dim: usize, rot: &[f64; 4], v: &Vector3<f64>) -> Vector3<f64> {
    if dim == 3 {
        quat(rot) * v
    } else {
        let (s, c) = rot[0].sin_cos();
        Vector3::new(c * v.x - s * v.y, s * v.x + c * v.y, 0.0)
    }
}
