//! The Lanczos correction along the height, where the data is not periodic (`method.md` s. 7).
//!
//! Data `psi_k = psi(v_k)` at `K` uniform nodes `v_k = k / (K - 1)` of `[0, 1]`. A periodic
//! interpolant of `psi` itself would jump at the ends (Gibbs). Instead
//!
//! `Psi(v) = h(v) + sum_{n=1}^{K-2} b_n sin(pi n v)`,
//!
//! where `h(v) = sum_{k=0..m} [psi^(2k)(0) P_{2k+1}(1 - v) + psi^(2k)(1) P_{2k+1}(v)]` takes up the
//! end values and even derivatives, and the sine series interpolates `phi = psi - h` at the nodes.
//! `phi` vanishes with its even derivatives up to order 2m at both ends, so its odd periodic
//! extension to `[-1, 1]` is smooth to order 2m + 1 and the sine coefficients (a DST-I, computed
//! by FFT) decay fast: the error falls like `N^-(2m+1)` or better.
//!
//! The polynomials: `P_0 = 1`, `P_1 = u`, `P_k' = P_{k-1}`, `P_{2k+1}(0) = P_{2k+1}(1) = 0`:
//! `P_3 = (u^3 - u) / 6`, `P_5 = u^5/120 - u^3/36 + 7u/360`. The end derivatives are estimated
//! from the data by one-sided finite differences on the first (last) `2m + 4` nodes, with
//! Fornberg's weights, exact for polynomials of degree `2m + 3`.
//!
//! Coefficients are generic over real and complex data (the surface fits the Fourier
//! coefficients around each section, which are complex).

use realfft::num_complex::Complex64;
use rustfft::FftPlanner;

/// `P_{2k+1}(u)` for `k = 0, 1, 2`.
///
/// ```
/// use drapekit::fit::lanczos::p_odd;
/// assert_eq!(p_odd(1, 0.5), (0.125 - 0.5) / 6.0);
/// assert!(p_odd(2, 1.0).abs() < 1e-16 && p_odd(2, 0.0) == 0.0);
/// ```
pub fn p_odd(k: usize, u: f64) -> f64 {
    match k {
        0 => u,
        1 => (u * u * u - u) / 6.0,
        2 => {
            // u^5/120 - u^3/36 + 7u/360, written so that P_5(1) is exactly 0.
            let u2 = u * u;
            u * (3.0 * u2 * u2 - 10.0 * u2 + 7.0) / 360.0
        }
        _ => panic!("Lanczos order above 2 is not supported"),
    }
}

/// The highest Lanczos order drapekit supports.
pub const MAX_ORDER: usize = 2;

/// Nodes needed for order `m`: the finite-difference stencils use `2m + 4` nodes (order 0 needs
/// only the two ends, and three nodes make the smallest surface).
pub fn nodes_needed(m: usize) -> usize {
    if m == 0 {
        3
    } else {
        2 * m + 4
    }
}

/// The highest order `K` nodes support (at most `wanted`).
pub fn order_for(k: usize, wanted: usize) -> usize {
    (0..=wanted.min(MAX_ORDER))
        .rev()
        .find(|&m| nodes_needed(m) <= k)
        .unwrap_or(0)
}

/// Fornberg's finite-difference weights: the weights `w_i` with
/// `f^(d)(x0) ~ sum_i w_i f(x_i)`, exact for polynomials of degree `xs.len() - 1`.
pub fn fd_weights(x0: f64, xs: &[f64], d: usize) -> Vec<f64> {
    let n = xs.len();
    let mut c = vec![vec![0.0; d + 1]; n];
    let mut c1 = 1.0;
    let mut c4 = xs[0] - x0;
    c[0][0] = 1.0;
    for i in 1..n {
        let mn = i.min(d);
        let mut c2 = 1.0;
        let c5 = c4;
        c4 = xs[i] - x0;
        for j in 0..i {
            let c3 = xs[i] - xs[j];
            c2 *= c3;
            if j == i - 1 {
                for k in (1..=mn).rev() {
                    c[i][k] = c1 * (k as f64 * c[i - 1][k - 1] - c5 * c[i - 1][k]) / c2;
                }
                c[i][0] = -c1 * c5 * c[i - 1][0] / c2;
            }
            for k in (1..=mn).rev() {
                c[j][k] = (c4 * c[j][k] - k as f64 * c[j][k - 1]) / c3;
            }
            c[j][0] = c4 * c[j][0] / c3;
        }
        c1 = c2;
    }
    c.iter().map(|row| row[d]).collect()
}

/// The weights that estimate `psi^(2k)` at `v = 0` from the first `2m + 4` nodes spaced `1/(K-1)`
/// (the same weights on the reversed data give the derivative at `v = 1`).
pub fn end_weights(k_nodes: usize, m: usize) -> Vec<Vec<f64>> {
    let p = (2 * m + 4).min(k_nodes);
    let xs: Vec<f64> = (0..p).map(|i| i as f64).collect();
    let step = 1.0 / (k_nodes - 1) as f64;
    (0..=m)
        .map(|k| {
            let mut w = fd_weights(0.0, &xs, 2 * k);
            let s = step.powi(-2 * k as i32);
            for x in &mut w {
                *x *= s;
            }
            w
        })
        .collect()
}

/// A Lanczos-corrected sine series of complex data along `[0, 1]`.
#[derive(Debug, Clone)]
pub struct Series {
    /// Lanczos order.
    pub m: usize,
    /// `psi^(2k)(0)`, `k = 0..=m`.
    pub ends0: Vec<Complex64>,
    /// `psi^(2k)(1)`, `k = 0..=m`.
    pub ends1: Vec<Complex64>,
    /// `b_n`, `n = 1..=K-2` (stored from index 0).
    pub sine: Vec<Complex64>,
}

/// The correction polynomial `h` at `v` for the given end data.
pub fn h_at(ends0: &[Complex64], ends1: &[Complex64], v: f64) -> Complex64 {
    let mut h = Complex64::new(0.0, 0.0);
    for k in 0..ends0.len() {
        h += ends0[k] * p_odd(k, 1.0 - v) + ends1[k] * p_odd(k, v);
    }
    h
}

/// Fits the series of order `m` to `psi` at `K = psi.len() >= 3` uniform nodes. `weights` are
/// [`end_weights`]`(K, m)`.
pub fn fit(
    planner: &mut FftPlanner<f64>,
    psi: &[Complex64],
    m: usize,
    weights: &[Vec<f64>],
) -> Series {
    let k_nodes = psi.len();
    let last = k_nodes - 1;
    let mut ends0 = Vec::with_capacity(m + 1);
    let mut ends1 = Vec::with_capacity(m + 1);
    for (d, w) in weights.iter().enumerate().take(m + 1) {
        if d == 0 {
            ends0.push(psi[0]);
            ends1.push(psi[last]);
        } else {
            ends0.push(w.iter().enumerate().map(|(i, wi)| psi[i] * *wi).sum());
            ends1.push(
                w.iter()
                    .enumerate()
                    .map(|(i, wi)| psi[last - i] * *wi)
                    .sum(),
            );
        }
    }
    // phi = psi - h at the interior nodes, odd-extended to 2(K - 1) points.
    let len = 2 * last;
    let mut buf = vec![Complex64::new(0.0, 0.0); len];
    for k in 1..last {
        let v = k as f64 / last as f64;
        let phi = psi[k] - h_at(&ends0, &ends1, v);
        buf[k] = phi;
        buf[len - k] = -phi;
    }
    planner.plan_fft_forward(len).process(&mut buf);
    // b_n = i Y_n / (K - 1).
    let s = 1.0 / last as f64;
    let sine = (1..last)
        .map(|n| Complex64::new(-buf[n].im, buf[n].re) * s)
        .collect();
    Series {
        m,
        ends0,
        ends1,
        sine,
    }
}

impl Series {
    /// The value at `v` in `[0, 1]`.
    pub fn eval(&self, v: f64) -> Complex64 {
        let mut f = h_at(&self.ends0, &self.ends1, v);
        let w = std::f64::consts::PI * v;
        for (n, b) in self.sine.iter().enumerate() {
            f += *b * (w * (n + 1) as f64).sin();
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series_of(f: impl Fn(f64) -> f64, k: usize, m: usize) -> Series {
        let psi: Vec<Complex64> = (0..k)
            .map(|i| Complex64::new(f(i as f64 / (k - 1) as f64), 0.0))
            .collect();
        fit(&mut FftPlanner::new(), &psi, m, &end_weights(k, m))
    }

    fn max_err(f: impl Fn(f64) -> f64 + Copy, k: usize, m: usize) -> f64 {
        let s = series_of(f, k, m);
        (0..=2000)
            .map(|i| i as f64 / 2000.0)
            .map(|v| (s.eval(v).re - f(v)).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn polynomials_and_end_conditions() {
        // P_1 = u; the higher ones vanish at both ends.
        assert_eq!((p_odd(0, 0.0), p_odd(0, 1.0)), (0.0, 1.0));
        for k in 1..3 {
            for u in [0.0, 1.0] {
                assert_eq!(p_odd(k, u), 0.0);
            }
        }
        // P_3'' = P_1 and P_5'' = P_3, checked by central differences.
        let e = 1e-4;
        for u in [0.2, 0.7] {
            let d2 = |k: usize| (p_odd(k, u + e) - 2.0 * p_odd(k, u) + p_odd(k, u - e)) / (e * e);
            assert!((d2(1) - p_odd(0, u)).abs() < 1e-6);
            assert!((d2(2) - p_odd(1, u)).abs() < 1e-6);
        }
    }

    #[test]
    fn fornberg_weights() {
        // Second derivative from 0,1,2,3 (one-sided): 2, -5, 4, -1.
        let w = fd_weights(0.0, &[0.0, 1.0, 2.0, 3.0], 2);
        for (a, b) in w.iter().zip([2.0, -5.0, 4.0, -1.0]) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn nodes_are_interpolated_and_low_degree_polynomials_reproduced() {
        let f = |v: f64| 0.3 + 2.0 * v - 1.5 * v * v * v + 0.7 * v.powi(5);
        for m in 0..=2 {
            let s = series_of(f, 12, m);
            for i in 0..12 {
                let v = i as f64 / 11.0;
                assert!((s.eval(v).re - f(v)).abs() < 1e-12, "m={m} node {i}");
            }
        }
        // Degree 2m + 1 with exact end derivatives: psi - h is zero, reproduced everywhere.
        assert!(max_err(|v| 1.0 + 3.0 * v, 5, 0) < 1e-13);
        assert!(max_err(|v| 1.0 + 3.0 * v - 2.0 * v.powi(3), 8, 1) < 1e-12);
        assert!(max_err(|v| 1.0 + 3.0 * v - 2.0 * v.powi(3) + v.powi(5), 9, 2) < 1e-11);
    }

    #[test]
    fn order_rises_with_m() {
        let f = |v: f64| (2.3 * v + 0.4).exp() * (1.0 + 0.3 * (3.0 * v).sin());
        for m in 0..=2 {
            let e1 = max_err(f, 17, m);
            let e2 = max_err(f, 65, m);
            let order = (e1 / e2).ln() / (64.0f64 / 16.0).ln();
            eprintln!("m={m}: {e1:.3e} -> {e2:.3e}, order {order:.2}");
            assert!(
                order >= (2 * m + 1) as f64 - 0.1,
                "m={m}: order {order} ({e1} -> {e2})"
            );
        }
    }
}
