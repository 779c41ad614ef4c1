//! Forces: springs, gravity, air damping (`method.md` s. 2):
//! `m_i r_i'' = -c_i r_i' + m_i g + sum_j k_ij (|r_j - r_i| - l0_ij) (r_j - r_i) / |r_j - r_i|`
//! plus bending. Each element's force is minus the gradient of its energy (`cloth::elements`).
//!
//! Each particle gathers its own springs (every spring is evaluated from both ends), so the
//! loop runs in parallel over fixed chunks of particles without atomics, and the result does
//! not depend on the number of threads.

use super::elements::bend;
use super::model::ClothModel;
use crate::math::{Point3, Vec3};

/// The internal force (springs and bending) on particle `i` at positions `x`, added to `acc`.
#[inline(always)]
pub fn add_internal(model: &ClothModel, x: &[Point3], i: usize, mut acc: Vec3) -> Vec3 {
    let xi = x[i];
    for &(j, s) in &model.adj[model.adj_start[i] as usize..model.adj_start[i + 1] as usize] {
        acc += model.springs[s as usize].force_on_a(&xi, &x[j as usize]);
    }
    for &(e, w) in
        &model.bend_adj[model.bend_adj_start[i] as usize..model.bend_adj_start[i + 1] as usize]
    {
        let e = e as usize;
        acc += bend::force(model.bend_c[e], w, &model.bend_vector(e, x));
    }
    acc
}

/// The force on particle `i` at positions `x`, velocities `v`, with external force `f_ext[i]`
/// (gravity) and explicit air damping.
#[inline]
pub fn force_on(model: &ClothModel, x: &[Point3], v: &[Vec3], f_ext: &[Vec3], i: usize) -> Vec3 {
    let m = model.mass[i];
    add_internal(model, x, i, f_ext[i] - v[i] * (model.damping[i] * m))
}

/// Energy in the springs and bending elements, J (summed over fixed chunks: the same for any
/// thread count).
pub fn spring_energy(model: &ClothModel, x: &[Point3]) -> f64 {
    let springs = crate::par::sum(model.springs.len(), |s| {
        let s = &model.springs[s];
        s.energy(&x[s.a as usize], &x[s.b as usize])
    });
    springs
        + crate::par::sum(model.bends(), |e| {
            bend::energy(model.bend_c[e], &model.bend_vector(e, x))
        })
}

/// Kinetic energy, J.
pub fn kinetic_energy(model: &ClothModel, v: &[Vec3]) -> f64 {
    v.iter()
        .zip(&model.mass)
        .map(|(v, m)| 0.5 * m * v.norm_squared())
        .sum()
}

/// Gravitational potential energy of positions `x` relative to positions `x0`, J: zero at `x0`,
/// whatever the height of the scene.
pub fn gravity_energy(model: &ClothModel, x: &[Point3], x0: &[Point3]) -> f64 {
    -x.iter()
        .zip(x0)
        .zip(&model.mass)
        .map(|((p, q), m)| m * model.gravity.dot(&(p - q)))
        .sum::<f64>()
}
