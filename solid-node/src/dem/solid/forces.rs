//! Evaluation of all link forces and torques at a configuration (fixed partition, serial
//! reductions: bit-identical for any thread count).

use nalgebra::{Matrix3, Vector2, Vector3};

use crate::dem::link_force::{
    LinkOut, link_force_2d, link_force_3d, link_gap_2d, link_gap_3d, spring_force_2d,
    spring_force_3d,
};
use crate::dem::model::Model;
use crate::dem::parallel::par_fill;
use crate::dem::solid::orientation::quat;

/// Scratch buffers of the force evaluation (allocated once).
#[derive(Clone, Debug, Default)]
pub(super) struct ForceScratch {
    /// `Δu·n` per link.
    pub(super) gaps: Vec<f64>,
    /// ε^v per particle.
    pub(super) eps: Vec<f64>,
    /// Per-link results.
    pub(super) link_out: Vec<LinkOut>,
    /// Body-to-space rotation matrix per particle (3-D).
    pub(super) rotation: Vec<Matrix3<f64>>,
    /// Gathered (force, torque) per particle.
    pub(super) loads: Vec<[[f64; 3]; 2]>,
}

/// Internal forces of all unbroken links at a configuration; returns the elastic energy.
#[allow(clippy::too_many_arguments)]
pub(super) fn internal_forces(
    model: &Model,
    pool: Option<&rayon::ThreadPool>,
    x: &[[f64; 3]],
    rot: &[[f64; 4]],
    broken: &[bool],
    scratch: &mut ForceScratch,
    force: &mut [[f64; 3]],
    torque: &mut [[f64; 3]],
) -> f64 {
    let dim = model.dim;
    let ForceScratch {
        gaps,
        eps,
        link_out,
        rotation,
        loads,
    } = scratch;
    if dim == 3 {
        par_fill(pool, rotation, |p| {
            quat(&rot[p]).to_rotation_matrix().into_inner()
        });
    }
    let rotation: &[Matrix3<f64>] = rotation;
    let with_volume = model.material.poisson != 0.0;
    if with_volume {
        par_fill(pool, gaps, |l| {
            let link = &model.kernels[l];
            if broken[l] || link.spring != 0.0 {
                return 0.0;
            }
            let (i, j) = (link.i as usize, link.j as usize);
            if dim == 3 {
                link_gap_3d(
                    link,
                    &Vector3::from(x[i]),
                    &rotation[i],
                    &Vector3::from(x[j]),
                    &rotation[j],
                )
            } else {
                link_gap_2d(
                    link,
                    &Vector2::new(x[i][0], x[i][1]),
                    rot[i][0],
                    &Vector2::new(x[j][0], x[j][1]),
                    rot[j][0],
                )
            }
        });
        let gaps_ro: &[f64] = gaps;
        par_fill(pool, eps, |p| {
            let range = model.incidence_start[p] as usize..model.incidence_start[p + 1] as usize;
            let mut acc = 0.0;
            for &(l, _) in &model.incidence[range] {
                acc += model.kernels[l as usize].area * gaps_ro[l as usize];
            }
            acc * model.particles[p].vol_weight
        });
    }
    let eps_ro: &[f64] = eps;
    par_fill(pool, link_out, |l| {
        if broken[l] {
            return LinkOut::default();
        }
        let link = &model.kernels[l];
        let (i, j) = (link.i as usize, link.j as usize);
        let e = if with_volume {
            eps_ro[i] + eps_ro[j]
        } else {
            0.0
        };
        if link.spring != 0.0 {
            if dim == 3 {
                spring_force_3d(
                    link,
                    &Vector3::from(x[i]),
                    &rotation[i],
                    &Vector3::from(x[j]),
                    &rotation[j],
                )
            } else {
                spring_force_2d(
                    link,
                    &Vector2::new(x[i][0], x[i][1]),
                    rot[i][0],
                    &Vector2::new(x[j][0], x[j][1]),
                    rot[j][0],
                )
            }
        } else if dim == 3 {
            link_force_3d(
                link,
                &Vector3::from(x[i]),
                &rotation[i],
                &Vector3::from(x[j]),
                &rotation[j],
                e,
            )
        } else {
            link_force_2d(
                link,
                &Vector2::new(x[i][0], x[i][1]),
                rot[i][0],
                &Vector2::new(x[j][0], x[j][1]),
                rot[j][0],
                e,
            )
        }
    });
    let out_ro: &[LinkOut] = link_out;
    let gather = |p: usize| {
        let range = model.incidence_start[p] as usize..model.incidence_start[p + 1] as usize;
        let mut f = Vector3::zeros();
        let mut t = Vector3::zeros();
        for &(l, is_i) in &model.incidence[range] {
            let o = &out_ro[l as usize];
            if is_i {
                f += o.force_i;
                t += o.torque_i;
            } else {
                f -= o.force_i;
                t += o.torque_j;
            }
        }
        [f.into(), t.into()]
    };
    par_fill(pool, loads, gather);
    for (p, [f, t]) in loads.iter().enumerate() {
        force[p] = *f;
        torque[p] = *t;
    }
    // Serial reductions in index order (bit-reproducible).
    let mut energy = 0.0;
    for o in out_ro {
        energy += o.energy;
    }
    if with_volume {
        for (p, e) in eps.iter().enumerate() {
            energy += model.particles[p].vol_energy_coef * e * e;
        }
    }
    energy
}
