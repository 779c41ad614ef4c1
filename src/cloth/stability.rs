//! The largest stable step of the explicit integrators, estimated before a run.
//!
//! Linearised, the springs and bending elements give a stiffness matrix `K`; a step `h` is
//! stable when, for the highest eigenfrequency `w` of `M^-1 K` (pinned particles held),
//! * leapfrog: `h < 2 / w`;
//! * explicit Euler with air damping rate `c`: `h < c / (c^2 / 4 + w^2)` (zero without damping:
//!   explicit Euler then grows every oscillation).
//!
//! [`max_frequency`] estimates `w` at rest by power iteration, from below: a step just under
//! its `2 / w` can still blow up (the iteration has not converged, or the cloth stretched).
//! [`frequency_bound`] bounds it from above (Gershgorin) at any stretch, so the estimate a run
//! uses (`sim::World::stable_step`) is conservative. The energy watch during a run is in
//! `sim::watch`.

use super::model::ClothModel;
use crate::math::{Point3, Vec3};

/// The highest eigenfrequency (rad/s) of the springs at rest, by power iteration.
pub fn max_frequency(model: &ClothModel, x: &[Point3]) -> f64 {
    let n = model.len();
    if (model.springs.is_empty() && model.bends() == 0) || n == 0 {
        return 0.0;
    }
    let mut y = random_start(model);
    let mut lambda = 0.0;
    let mut ky = vec![Vec3::zeros(); n];
    for _ in 0..200 {
        minus_stiffness_times(model, x, &y, &mut ky);
        // z = M^-1 K y (with K y = -ky as gathered above), pinned rows held at zero.
        let mut norm2 = 0.0;
        let mut dot = 0.0;
        for i in 0..n {
            let z = -ky[i] * model.inv_mass[i];
            dot += z.dot(&y[i]) * model.mass[i];
            norm2 += y[i].norm_squared() * model.mass[i];
            ky[i] = z;
        }
        let new_lambda = if norm2 > 0.0 { dot / norm2 } else { 0.0 };
        let scale = ky
            .iter()
            .zip(&model.mass)
            .map(|(z, m)| z.norm_squared() * m)
            .sum::<f64>()
            .sqrt();
        if scale == 0.0 {
            return 0.0;
        }
        for (yi, zi) in y.iter_mut().zip(&ky) {
            *yi = zi / scale;
        }
        if (new_lambda - lambda).abs() <= 1e-6 * new_lambda.abs() {
            lambda = new_lambda;
            break;
        }
        lambda = new_lambda;
    }
    lambda.max(0.0).sqrt()
}

/// The power iteration's start: a fixed pseudo-random vector, orthogonal to nothing in
/// particular, zero at the pinned particles.
fn random_start(model: &ClothModel) -> Vec<Vec3> {
    let mut rng = crate::math::SplitMix(7);
    (0..model.len())
        .map(|i| {
            if model.pinned(i) {
                Vec3::zeros()
            } else {
                Vec3::new(
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                )
            }
        })
        .collect()
}

/// `ky = -K y`: the springs (linearised at `x`) and the bending elements' stiffness times `y`,
/// negated.
fn minus_stiffness_times(model: &ClothModel, x: &[Point3], y: &[Vec3], ky: &mut [Vec3]) {
    for k in ky.iter_mut() {
        *k = Vec3::zeros();
    }
    for s in &model.springs {
        let d = x[s.b as usize] - x[s.a as usize];
        let l = d.norm();
        if l == 0.0 {
            continue;
        }
        let u = d / l;
        let rel = y[s.b as usize] - y[s.a as usize];
        let f = u * (s.k * u.dot(&rel));
        ky[s.a as usize] += f;
        ky[s.b as usize] -= f;
    }
    for e in 0..model.bends() {
        let (lo, hi) = (
            model.bend_start[e] as usize,
            model.bend_start[e + 1] as usize,
        );
        let b = (lo..hi).fold(Vec3::zeros(), |acc, k| {
            acc + y[model.bend_nodes[k] as usize] * model.bend_weights[k]
        });
        for k in lo..hi {
            ky[model.bend_nodes[k] as usize] -= b * (model.bend_c[e] * model.bend_weights[k]);
        }
    }
}

/// A bound on the highest eigenfrequency (rad/s) of the springs and bending elements at any
/// stretch (compressed by less than half): Gershgorin's, `w^2 <= max_i (2 sum_s k_s +
/// sum_e c_e |w_ie| sum_k |w_ke|) / m_i` over the free particles, from the 3x3 blocks of the
/// stiffness matrix (a spring's block has norm `k` unless compressed below half its rest
/// length). It is never below the power iteration's estimate, so an explicit step under
/// `2 / w` is stable for the linearised cloth, stretched or not.
pub fn frequency_bound(model: &ClothModel) -> f64 {
    let mut worst: f64 = 0.0;
    for i in 0..model.len() {
        if model.pinned(i) {
            continue;
        }
        let springs: f64 = model.adj[model.adj_start[i] as usize..model.adj_start[i + 1] as usize]
            .iter()
            .map(|&(_, s)| model.springs[s as usize].k)
            .sum();
        let bends: f64 = model.bend_adj
            [model.bend_adj_start[i] as usize..model.bend_adj_start[i + 1] as usize]
            .iter()
            .map(|&(e, w)| {
                let e = e as usize;
                let (lo, hi) = (
                    model.bend_start[e] as usize,
                    model.bend_start[e + 1] as usize,
                );
                let sum: f64 = model.bend_weights[lo..hi].iter().map(|w| w.abs()).sum();
                model.bend_c[e] * w.abs() * sum
            })
            .sum();
        worst = worst.max((2.0 * springs + bends) / model.mass[i]);
    }
    worst.sqrt()
}

/// The smallest air damping rate of the model's particles, 1/s (0 without particles).
pub fn min_damping(model: &ClothModel) -> f64 {
    let c = model.damping.iter().copied().fold(f64::INFINITY, f64::min);
    if c.is_finite() {
        c
    } else {
        0.0
    }
}
