//! Forces: springs, gravity, air damping (`method.md` s. 2):
//! `m_i r_i'' = -c_i r_i' + m_i g + sum_j k_ij (|r_j - r_i| - l0_ij) (r_j - r_i) / |r_j - r_i|`
//! plus bending.
//!
//! Bending (`cloth::pattern`): each element over a node stores `c |sum_k w_k x_k|^2 / 2`, so
//! its force on particle `k` is `-c w_k sum_j w_j x_j`: linear in the positions, zero on the flat
//! piece and under rigid motions.
//!
//! Each particle gathers its own springs (every spring is evaluated from both ends), so the
//! loop runs in parallel over fixed chunks of particles without atomics, and the result does
//! not depend on the number of threads.

use super::model::ClothModel;
use crate::math::{Point3, Vec3};

/// The force on particle `i` at positions `x`, velocities `v`.
#[inline]
pub fn force_on(model: &ClothModel, x: &[Point3], v: &[Vec3], i: usize) -> Vec3 {
    let m = model.mass[i];
    let mut acc = model.gravity * m - v[i] * (model.damping[i] * m);
    let xi = x[i];
    for &(j, s) in &model.adj[model.adj_start[i] as usize..model.adj_start[i + 1] as usize] {
        let spring = &model.springs[s as usize];
        let d = x[j as usize] - xi;
        let len = d.norm();
        if len > 0.0 {
            acc += d * (spring.k * (len - spring.rest) / len);
        }
    }
    for &(e, w) in
        &model.bend_adj[model.bend_adj_start[i] as usize..model.bend_adj_start[i + 1] as usize]
    {
        acc -= model.bend_vector(e as usize, x) * (model.bend_c[e as usize] * w);
    }
    acc
}

/// Energy in the springs and bending elements, J.
pub fn spring_energy(model: &ClothModel, x: &[Point3]) -> f64 {
    model
        .springs
        .iter()
        .map(|s| {
            let e = (x[s.b as usize] - x[s.a as usize]).norm() - s.rest;
            0.5 * s.k * e * e
        })
        .sum::<f64>()
        + (0..model.bends())
            .map(|e| 0.5 * model.bend_c[e] * model.bend_vector(e, x).norm_squared())
            .sum::<f64>()
}

/// Kinetic energy, J.
pub fn kinetic_energy(model: &ClothModel, v: &[Vec3]) -> f64 {
    v.iter()
        .zip(&model.mass)
        .map(|(v, m)| 0.5 * m * v.norm_squared())
        .sum()
}

/// Gravitational potential energy (zero at the origin), J.
pub fn gravity_energy(model: &ClothModel, x: &[Point3]) -> f64 {
    -x.iter()
        .zip(&model.mass)
        .map(|(p, m)| m * model.gravity.dot(&p.coords))
        .sum::<f64>()
}
