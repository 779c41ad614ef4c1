//! Periodic trigonometric interpolation by FFT: the trigonometric interpolation sum (TIS) of
//! `method.md` section 7 in the direction around a closed section, where the data is periodic
//! and needs no correction.
//!
//! Samples `f_l = f(l / n)`, `l = 0..n`, give coefficients `c_j = (1/n) sum_l f_l e^(-2 pi i j l / n)`
//! for `j = 0..=n/2`, and the real interpolant
//!
//! `F(u) = c_0 + 2 sum_{0<j<n/2} Re(c_j e^(2 pi i j u)) + [n even] c_{n/2} cos(pi n u)`.
//!
//! The Nyquist term (n even) is a cosine alone: writing it as `e^(i pi n u)` would interpolate
//! the nodes but give a complex, wrong curve between them. `F` reproduces any trigonometric
//! polynomial of degree below n/2 exactly, and interpolates the nodes in every case.

use realfft::num_complex::Complex64;
use realfft::RealFftPlanner;

/// Forward real FFT of `samples`, scaled by `1/n`: the `n/2 + 1` coefficients `c_j`.
pub fn coefficients(planner: &mut RealFftPlanner<f64>, samples: &[f64]) -> Vec<Complex64> {
    let n = samples.len();
    let fft = planner.plan_fft_forward(n);
    let mut input = samples.to_vec();
    let mut out = fft.make_output_vec();
    fft.process(&mut input, &mut out)
        .expect("buffer sizes come from the plan");
    let s = 1.0 / n as f64;
    for c in &mut out {
        *c *= s;
    }
    out
}

/// Evaluates the interpolant of an `n`-sample series with coefficients `c` at `u` (period 1).
pub fn eval(c: &[Complex64], n: usize, u: f64) -> f64 {
    let half = n / 2;
    let mut f = c[0].re;
    let w = std::f64::consts::TAU * u;
    for (j, cj) in c.iter().enumerate().take(half + 1).skip(1) {
        let (s, co) = (w * j as f64).sin_cos();
        if n.is_multiple_of(2) && j == half {
            f += cj.re * co;
        } else {
            f += 2.0 * (cj.re * co - cj.im * s);
        }
    }
    f
}

/// A planned inverse real FFT, shareable between threads.
pub type InversePlan = std::sync::Arc<dyn realfft::ComplexToReal<f64>>;

/// Evaluates the interpolant of an `n`-sample series with coefficients `c` (length `n/2 + 1`)
/// at the `m` points `l / m`, by a zero-padded inverse FFT when `m >= n` (exact, O(m log m)),
/// directly otherwise.
pub fn resample(
    planner: &mut RealFftPlanner<f64>,
    c: &[Complex64],
    n: usize,
    m: usize,
) -> Vec<f64> {
    let mut out = vec![0.0; m];
    if m < n {
        for (l, o) in out.iter_mut().enumerate() {
            *o = eval(c, n, l as f64 / m as f64);
        }
    } else {
        inverse_padded(&planner.plan_fft_inverse(m), c, n, &mut out);
    }
    out
}

/// The interpolant of an `n`-sample series at the `out.len() >= n` points `l / out.len()`, with
/// an inverse plan of that length: the spectrum is zero-padded, the Nyquist cosine kept as one
/// term when it is also the output's Nyquist and split in two otherwise.
pub fn inverse_padded(plan: &InversePlan, c: &[Complex64], n: usize, out: &mut [f64]) {
    let m = out.len();
    debug_assert!(m >= n);
    let mut spec = vec![Complex64::new(0.0, 0.0); m / 2 + 1];
    let half = n / 2;
    spec[..=half].copy_from_slice(&c[..=half]);
    if n.is_multiple_of(2) && half > 0 {
        spec[half] = Complex64::new(if m == n { c[half].re } else { c[half].re / 2.0 }, 0.0);
    }
    spec[0].im = 0.0;
    if m.is_multiple_of(2) {
        spec[m / 2].im = 0.0;
    }
    plan.process(&mut spec, out)
        .expect("buffer sizes come from the plan");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn band_limited(u: f64, n: usize) -> f64 {
        // Degree up to n/2 - 1, plus the Nyquist cosine when n is even.
        let t = std::f64::consts::TAU * u;
        let mut f = 0.3 + (t).cos() * 1.7 - 0.4 * (2.0 * t).sin() + 0.05 * (3.0 * t + 0.3).cos();
        if n.is_multiple_of(2) {
            f += 0.25 * (std::f64::consts::PI * n as f64 * u).cos();
        }
        f
    }

    #[test]
    fn band_limited_series_reproduced_to_round_off() {
        let mut p = RealFftPlanner::new();
        for n in [8usize, 9, 16, 33] {
            let s: Vec<f64> = (0..n)
                .map(|l| band_limited(l as f64 / n as f64, n))
                .collect();
            let c = coefficients(&mut p, &s);
            for k in 0..97 {
                let u = k as f64 / 97.0 + 0.001;
                assert!(
                    (eval(&c, n, u) - band_limited(u, n)).abs() < 1e-13,
                    "n={n} u={u}"
                );
            }
            for m in [n, 2 * n + 1, 5 * n] {
                let r = resample(&mut p, &c, n, m);
                for (l, v) in r.iter().enumerate() {
                    let u = l as f64 / m as f64;
                    assert!(
                        (v - band_limited(u, n)).abs() < 1e-13,
                        "n={n} m={m} l={l}: {v}"
                    );
                }
            }
        }
    }

    #[test]
    fn nyquist_as_complex_exponential_would_be_wrong() {
        // The alternating sequence is cos(pi n u); between the nodes it must be that cosine.
        let mut p = RealFftPlanner::new();
        let n = 8;
        let s: Vec<f64> = (0..n)
            .map(|l| if l % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let c = coefficients(&mut p, &s);
        let u = 0.5 / n as f64;
        assert!(eval(&c, n, u).abs() < 1e-15);
        assert!(
            (eval(&c, n, u / 2.0) - (std::f64::consts::PI * n as f64 * u / 2.0).cos()).abs()
                < 1e-14
        );
    }
}
