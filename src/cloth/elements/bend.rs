//! A bending element over a few particles (`cloth::pattern` builds them): weights `w_k` that sum
//! to zero and whose weighted sum `b = sum_k w_k x_k` vanishes on the flat piece.
//!
//! * energy `E = c |b|^2 / 2`;
//! * force on particle `k`: `f_k = -c w_k b`;
//! * Hessian: `d2E/dx_k dx_j = c w_k w_j I`, constant (the element is quadratic), so it enters
//!   implicit systems and projective dynamics' global matrix exactly, with nothing to project.

use crate::math::{Point3, Vec3};

/// A bending element: energy `c |sum_k w_k x_k|^2 / 2` (J) over a few particles whose weights
/// sum to zero and whose weighted sum vanishes on the flat piece.
#[derive(Debug, Clone, PartialEq)]
pub struct Bend {
    /// The particles; the first is the node the element bends over.
    pub nodes: Vec<u32>,
    /// Their weights.
    pub weights: Vec<f64>,
    /// The constant, N/m.
    pub c: f64,
}

/// The weighted sum `b = sum_k w_k x_k` of an element's `nodes` and `weights`.
#[inline(always)]
pub fn vector(nodes: &[u32], weights: &[f64], x: &[Point3]) -> Vec3 {
    nodes
        .iter()
        .zip(weights)
        .fold(Vec3::zeros(), |acc, (&v, &w)| {
            acc + x[v as usize].coords * w
        })
}

/// Energy `c |b|^2 / 2` for the element's vector `b`, J.
#[inline]
pub fn energy(c: f64, b: &Vec3) -> f64 {
    0.5 * c * b.norm_squared()
}

/// Force on the node of weight `w`, N.
#[inline(always)]
pub fn force(c: f64, w: f64, b: &Vec3) -> Vec3 {
    -(b * (c * w))
}

/// The Hessian block between nodes of weights `wk` and `wj`: `c wk wj` times the identity.
#[inline]
pub fn hessian(c: f64, wk: f64, wj: f64) -> f64 {
    c * wk * wj
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn force_and_hessian_match_finite_differences() {
        let nodes = [0u32, 1, 2, 3];
        let weights = [-2.5, 1.0, 0.75, 0.75];
        let c = 3.7;
        let x = vec![
            Point3::new(0.0, 0.0, 0.01),
            Point3::new(0.1, 0.0, 0.0),
            Point3::new(-0.05, 0.09, -0.02),
            Point3::new(-0.05, -0.09, 0.03),
        ];
        let e = |x: &[Point3]| energy(c, &vector(&nodes, &weights, x));
        let f = |x: &[Point3], k: usize| force(c, weights[k], &vector(&nodes, &weights, x));
        let h = 1e-6;
        for k in 0..4 {
            for a in 0..3 {
                let (mut p, mut m) = (x.clone(), x.clone());
                p[k][a] += h;
                m[k][a] -= h;
                let g = (e(&p) - e(&m)) / (2.0 * h);
                assert!((f(&x, k)[a] + g).abs() < 1e-8, "{k} {a}");
                // Column (k, a) of the Hessian: minus the change of every force.
                for j in 0..4 {
                    let col = -(f(&p, j) - f(&m, j)) / (2.0 * h);
                    let expect = hessian(c, weights[j], weights[k]);
                    for r in 0..3 {
                        let want = if r == a { expect } else { 0.0 };
                        assert!((col[r] - want).abs() < 1e-6, "{k} {j} {a} {r}");
                    }
                }
            }
        }
        // Zero on a flat, evenly spaced stencil and under a translation.
        let flat = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(-1.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
        ];
        let b = vector(&[0, 1, 2], &[-2.0, 1.0, 1.0], &flat);
        assert_eq!(b, Vec3::zeros());
    }
}
