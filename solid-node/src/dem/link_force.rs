//! Link forces and torques of eq. (29)–(30) of paper 003 (App. A), 2-D and 3-D kernels.
//!
//! The link potential is
//! `U_IJ = ½ k |Δu|² + Σ_k c_k (1 − (Q_I a_k)·(Q_J a_k))`, `k = S/D⁰ · E/(1+ν)`,
//! `c_k = S/D⁰ · α_k`, `a_k ∈ {n⁰, s, t}`, plus per particle `U_I = ½ λ V'_I (ε^v_I)²` with
//! `V'_I = V_I + 3ν/(1−2ν) V^f_I` and `ε^v_I = Σ_J S_IJ/(2 V'_I) Δu_IJ·n_IJ`.
//! Forces and torques are the exact negative gradients, which reproduces (29)–(30) term by term.
//!
//! NOTE (reading of the machine-extracted formulas, 000 vs 003):
//! - Both papers print `Δu_IJ = X_I − X_J + Q_J (G − X⁰_J) − Q_I (G − X⁰_I)`, which is
//!   `2 (X_I − X_J) ≠ 0` at rest. 000 describes it as "the difference of the displacement
//!   vectors of interface point G_IJ driven by particles I and J", so we use
//!   `Δu_IJ = (X_I + Q_I (G − X⁰_I)) − (X_J + Q_J (G − X⁰_J))`, zero at rest.
//! - `n_IJ` in the volumetric terms is read as the current unit vector `(X_I − X_J)/D_IJ`: its
//!   derivative is exactly the printed correction `(Δu − (Δu·n)n)/D_IJ`, so with this reading
//!   (29)–(30) derive from the potential above and energy is conserved, as the papers claim.
//! - With that `Δu`, the printed `F_IJ` and `M^t_IJ` are `+∂U/∂X_I` and `+∂U/∂θ_I` (the action
//!   of `I` on `J`): the force and torque on `I` are their opposites (otherwise a stretched link
//!   would push its particles apart). The printed flexion torque `c_k Q_I a ∧ Q_J a` is already
//!   the torque on `I` for the potential `c_k (1 − Q_I a · Q_J a)` (minimum when aligned). All
//!   signs are fixed by the potential and checked against it by finite differences.
//! - The volumetric force is printed `S λ ε_IJ (…)` with `ε_IJ = ε^v_I + ε^v_J` (the sum). With
//!   ε^v_I as printed (= div u in the interior) that is the gradient of `Σ λ V' (ε^v)²`, twice
//!   the elastic energy `½ λ (tr ε)²`: in a cubic lattice it gives σ = 2με + 2λ tr(ε) 1
//!   (ν = 0.3: E_eff = 1.06 E, ν_eff = 0.375) and a one-particle-thick bar gets 1.23 E. We use
//!   `U_I = ½ λ V'_I (ε^v_I)²`, i.e. the force `S λ (ε^v_I + ε^v_J)/2` (the mean); then the
//!   interior gives λ tr(ε) exactly and a one-particle-thick bar gets exactly E, which is what
//!   the free-volume weight `V + 3ν/(1−2ν) V^f` is built for (checked by `dem_wave.rs` at ν = 0.3).
//! - 000 prints `V_I + 3ν/(1−2ν) V_I` in ε^v_I; 003 prints `V^f_I` for the second term and
//!   defines the free volume just after, so 003 is used.

use nalgebra::{Matrix3, Vector2, Vector3};

use crate::dem::model::LinkKernel;

/// What one link contributes, written once per link then gathered per particle.
#[derive(Clone, Copy, Debug, Default)]
pub struct LinkOut {
    /// Force on `i` \[N\] (the force on `j` is its opposite). 2-D: z = 0.
    pub force_i: Vector3<f64>,
    /// Torque on `i` about its centre \[N m\]. 2-D: only z.
    pub torque_i: Vector3<f64>,
    /// Torque on `j` about its centre \[N m\].
    pub torque_j: Vector3<f64>,
    /// Link energy `½ k |Δu|² + flexion` \[J\] (volumetric energy is per particle).
    pub energy: f64,
    /// `Δu·n` \[m\], input of ε^v.
    pub gap: f64,
    /// Current centre distance D_IJ \[m\].
    pub distance: f64,
}

/// Displacement jump `Δu`, unit vector `n = (X_I − X_J)/D`, `D`, lever arms `Q_I r_I`, `Q_J r_J`.
#[inline]
fn geometry_3d(
    link: &LinkKernel,
    xi: &Vector3<f64>,
    qi: &Matrix3<f64>,
    xj: &Vector3<f64>,
    qj: &Matrix3<f64>,
) -> (Vector3<f64>, Vector3<f64>, f64, Vector3<f64>, Vector3<f64>) {
    let arm_i = qi * link.r_i;
    let arm_j = qj * link.r_j;
    let d = xi - xj;
    let dist = d.norm();
    // NOTE: `d + (arm_i − arm_j)`: swapping I and J negates it bit for bit (the mirror image of
    // a symmetric body lists its links the other way round).
    let du = d + (arm_i - arm_j);
    (du, d / dist, dist, arm_i, arm_j)
}

/// `Δu·n` of a 3-D link (first pass, needed for ε^v when ν ≠ 0).
#[inline]
pub fn link_gap_3d(
    link: &LinkKernel,
    xi: &Vector3<f64>,
    qi: &Matrix3<f64>,
    xj: &Vector3<f64>,
    qj: &Matrix3<f64>,
) -> f64 {
    let (du, n, _, _, _) = geometry_3d(link, xi, qi, xj, qj);
    du.dot(&n)
}

/// Force and torques of a 3-D link, `eps_link = ε^v_I + ε^v_J` (0 when ν = 0); `qi`, `qj` are
/// the body-to-space rotation matrices of the particles.
#[inline]
pub fn link_force_3d(
    link: &LinkKernel,
    xi: &Vector3<f64>,
    qi: &Matrix3<f64>,
    xj: &Vector3<f64>,
    qj: &Matrix3<f64>,
    eps_link: f64,
) -> LinkOut {
    let (du, n, dist, arm_i, arm_j) = geometry_3d(link, xi, qi, xj, qj);
    let gap = du.dot(&n);
    let vol = link.k_vol * eps_link;
    // P = ∂U/∂Δu (elastic + volumetric through Δu·n).
    let p = du * link.k_shear + n * vol;
    let force_i = -(p + (du - n * gap) * (vol / dist));
    let mut torque_i = p.cross(&arm_i);
    let mut torque_j = arm_j.cross(&p);
    let mut energy = 0.5 * link.k_shear * du.norm_squared();
    add_flexure_3d(link, qi, qj, &mut torque_i, &mut torque_j, &mut energy);
    LinkOut {
        force_i,
        torque_i,
        torque_j,
        energy,
        gap,
        distance: dist,
    }
}

#[inline]
fn rotate_2d(theta: f64, v: &Vector3<f64>) -> Vector2<f64> {
    let (s, c) = theta.sin_cos();
    Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

#[inline]
fn cross_2d(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

#[inline]
fn geometry_2d(
    link: &LinkKernel,
    xi: &Vector2<f64>,
    ti: f64,
    xj: &Vector2<f64>,
    tj: f64,
) -> (Vector2<f64>, Vector2<f64>, f64, Vector2<f64>, Vector2<f64>) {
    let arm_i = rotate_2d(ti, &link.r_i);
    let arm_j = rotate_2d(tj, &link.r_j);
    let d = xi - xj;
    let dist = d.norm();
    (d + (arm_i - arm_j), d / dist, dist, arm_i, arm_j)
}

/// `Δu·n` of a 2-D link.
#[inline]
pub fn link_gap_2d(
    link: &LinkKernel,
    xi: &Vector2<f64>,
    ti: f64,
    xj: &Vector2<f64>,
    tj: f64,
) -> f64 {
    let (du, n, _, _, _) = geometry_2d(link, xi, ti, xj, tj);
    du.dot(&n)
}

/// Force and torques of a 2-D link (prisms of unit depth moving in the plane).
///
/// In the plane every in-plane unit vector turns with the particle, so
/// `(Q_I a)·(Q_J a) = cos(θ_J − θ_I)` for `a = n⁰, s` and 1 for `a = t = e_z`: the flexion term
/// reduces to `(c_n + c_s) sin(θ_J − θ_I)` on `I`.
#[inline]
pub fn link_force_2d(
    link: &LinkKernel,
    xi: &Vector2<f64>,
    ti: f64,
    xj: &Vector2<f64>,
    tj: f64,
    eps_link: f64,
) -> LinkOut {
    let (du, n, dist, arm_i, arm_j) = geometry_2d(link, xi, ti, xj, tj);
    let gap = du.dot(&n);
    let vol = link.k_vol * eps_link;
    let p = du * link.k_shear + n * vol;
    let force = -(p + (du - n * gap) * (vol / dist));
    let bend = link.flex[0] + link.flex[1];
    let rel = tj - ti;
    let flex_torque = bend * rel.sin();
    LinkOut {
        force_i: Vector3::new(force.x, force.y, 0.0),
        torque_i: Vector3::new(0.0, 0.0, cross_2d(&p, &arm_i) + flex_torque),
        torque_j: Vector3::new(0.0, 0.0, cross_2d(&arm_j, &p) - flex_torque),
        energy: 0.5 * link.k_shear * du.norm_squared() + bend * (1.0 - rel.cos()),
        gap,
        distance: dist,
    }
}

/// Axial part of a spring link: force on `i` and energy `½ k (|d| − D⁰)²`, `d = X_I − X_J`.
#[inline]
fn spring_axial(link: &LinkKernel, d: &Vector3<f64>) -> (Vector3<f64>, f64, f64) {
    let dist = d.norm();
    let stretch = dist - link.d0;
    (
        d * (-link.spring * stretch / dist),
        0.5 * link.spring * stretch * stretch,
        dist,
    )
}

/// Force and torques of a 3-D spring link (`[[solid.bodies]] links`): the central spring
/// `½ k (|d| − D⁰)²` exerts no torque; the rotational spring `Σ_k c_k (1 − Q_I a_k · Q_J a_k)`,
/// `c_k = c/2`, is the flexion term of [`link_force_3d`] and gives `c (1 − cos φ)` for a
/// relative rotation φ about any axis. No volumetric part (`gap` = 0).
#[inline]
pub fn spring_force_3d(
    link: &LinkKernel,
    xi: &Vector3<f64>,
    qi: &Matrix3<f64>,
    xj: &Vector3<f64>,
    qj: &Matrix3<f64>,
) -> LinkOut {
    let (force_i, mut energy, dist) = spring_axial(link, &(xi - xj));
    let mut torque_i = Vector3::zeros();
    let mut torque_j = Vector3::zeros();
    add_flexure_3d(link, qi, qj, &mut torque_i, &mut torque_j, &mut energy);
    LinkOut {
        force_i,
        torque_i,
        torque_j,
        energy,
        gap: 0.0,
        distance: dist,
    }
}

/// Force and torques of a 2-D spring link: central spring plus `c (1 − cos(θ_J − θ_I))`,
/// `c = flex[0] + flex[1]`, as in [`link_force_2d`].
#[inline]
pub fn spring_force_2d(
    link: &LinkKernel,
    xi: &Vector2<f64>,
    ti: f64,
    xj: &Vector2<f64>,
    tj: f64,
) -> LinkOut {
    let d = xi - xj;
    let (force_i, axial, dist) = spring_axial(link, &Vector3::new(d.x, d.y, 0.0));
    let bend = link.flex[0] + link.flex[1];
    let rel = tj - ti;
    let flex_torque = bend * rel.sin();
    LinkOut {
        force_i,
        torque_i: Vector3::new(0.0, 0.0, flex_torque),
        torque_j: Vector3::new(0.0, 0.0, -flex_torque),
        energy: axial + bend * (1.0 - rel.cos()),
        gap: 0.0,
        distance: dist,
    }
}

/// Adds the flexural-torsional part of a 3-D link (its axes' misalignment) to the torques and
/// the energy, in place so the sums keep their order (the Monasse–Mariotti and spring links
/// share it).
fn add_flexure_3d(
    link: &LinkKernel,
    qi: &Matrix3<f64>,
    qj: &Matrix3<f64>,
    torque_i: &mut Vector3<f64>,
    torque_j: &mut Vector3<f64>,
    energy: &mut f64,
) {
    for k in 0..3 {
        let a_i = qi * link.axes_i[k];
        let a_j = qj * link.axes_j[k];
        let t = a_i.cross(&a_j) * link.flex[k];
        *torque_i += t;
        *torque_j -= t;
        *energy += link.flex[k] * (1.0 - a_i.dot(&a_j));
    }
}
