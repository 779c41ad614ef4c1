//! The largest stable step, estimated before a run, and the energy watch during it.
//!
//! Linearised at rest, the springs give a stiffness matrix `K` (each spring adds `k u u^T`
//! blocks along its direction `u`); the highest eigenfrequency `w` of `M^-1 K` (pinned particles
//! held) comes from power iteration. A step `h` is stable when
//! * leapfrog: `h < 2 / w`;
//! * explicit Euler with air damping rate `c`: `h < c / (c^2 / 4 + w^2)` (zero without damping:
//!   explicit Euler then grows every oscillation).
//!
//! During a run the mechanical energy (kinetic + springs + gravity) can only fall (damping and
//! collisions take energy out, nothing puts it in), up to the bounded error of a stable
//! integrator. A run whose energy rises by more than the scene's energy scale, or that produces a
//! non-finite number, is unstable and stops.

use super::integrate::Integrator;
use super::model::ClothModel;
use crate::math::{Point3, Vec3};

/// The highest eigenfrequency (rad/s) of the springs at rest, by power iteration.
pub fn max_frequency(model: &ClothModel, x: &[Point3]) -> f64 {
    let n = model.len();
    if (model.springs.is_empty() && model.bends() == 0) || n == 0 {
        return 0.0;
    }
    // A fixed pseudo-random start, orthogonal to nothing in particular.
    let mut rng = crate::cli::SplitMix(7);
    let mut y: Vec<Vec3> = (0..n)
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
        .collect();
    let mut lambda = 0.0;
    let mut ky = vec![Vec3::zeros(); n];
    for _ in 0..200 {
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

/// The largest stable step (s) of `integrator` for frequency `w` and damping rate `c`.
pub fn stable_step(integrator: Integrator, w: f64, c: f64) -> f64 {
    if w == 0.0 {
        return f64::INFINITY;
    }
    match integrator {
        Integrator::Leapfrog => 2.0 / w,
        Integrator::ExplicitEuler => c / (c * c / 4.0 + w * w),
    }
}
