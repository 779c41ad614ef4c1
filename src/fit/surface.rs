//! The fitted surface: a trigonometric interpolation sum around, Lanczos-corrected along.
//!
//! The nodes are a `K x N` grid: `K` sections (the height direction `v`, node `k` at
//! `v = k / (K - 1)` whatever its height) of `N` points each (the direction around, node `l` at
//! `u = l / N`). Each coordinate `x, y, z` is a function of `(u, v)` fitted on its own: the
//! height is a coordinate like the others, so uneven levels need no special case.
//!
//! Around, the data is periodic: each section's samples become Fourier coefficients `c_j`
//! (`trig`). Along, the coefficient of each frequency `j` is a complex function of `v`, fitted by
//! a Lanczos-corrected sine series of order `m` (`lanczos`). In two dimensions the correction is
//! built one direction at a time, and the periodic direction needs none, so
//! `h = W_v psi` and `Psi = h + sum_j sum_n b_nj sin(pi n v) e^(2 pi i j u)`.
//!
//! Evaluating a ring at height parameter `v` sums the sine series of every frequency, then one
//! zero-padded inverse FFT gives any number of points around. Rings are independent and are
//! computed in parallel.

use super::lanczos::{self, Series};
use super::trig;
use crate::math::Point3;
use crate::mesh::polygon::{triangulate, PolygonStats, QuadSplit};
use crate::mesh::TriMesh;
use rayon::prelude::*;
use realfft::num_complex::Complex64;
use realfft::RealFftPlanner;
use rustfft::FftPlanner;

/// Fitted coefficients of one coordinate.
#[derive(Debug, Clone)]
struct Coord {
    /// `sine[n * h + j]`: coefficient of `sin(pi (n+1) v)` for frequency `j`.
    sine: Vec<Complex64>,
    /// `ends0[d * h + j]`, `ends1[d * h + j]`: `psi^(2d)` at `v = 0` and `v = 1`.
    ends0: Vec<Complex64>,
    ends1: Vec<Complex64>,
}

/// A fitted closed surface.
#[derive(Debug, Clone)]
pub struct Surface {
    /// Nodes around (`N`).
    pub nodes_around: usize,
    /// Nodes along (`K`, the sections).
    pub nodes_along: usize,
    /// Lanczos order used.
    pub lanczos: usize,
    coords: [Coord; 3],
}

/// Fits the surface through a `K x N` grid of points (row `k` is section `k`, ring order), with
/// Lanczos order `m` (lowered to what `K` supports: see `lanczos::order_for`).
pub fn fit(grid: &[Point3], k: usize, n: usize, m: usize) -> Surface {
    assert!(k >= 3 && n >= 3 && grid.len() == k * n);
    let m = lanczos::order_for(k, m);
    let h = n / 2 + 1;
    let mut rplan = RealFftPlanner::new();
    let mut cplan = FftPlanner::new();
    let weights = lanczos::end_weights(k, m);
    let coords = [0usize, 1, 2].map(|c| {
        // Fourier coefficients of every section.
        let spectra: Vec<Vec<Complex64>> = (0..k)
            .map(|row| {
                let s: Vec<f64> = grid[row * n..(row + 1) * n].iter().map(|p| p[c]).collect();
                trig::coefficients(&mut rplan, &s)
            })
            .collect();
        let mut sine = vec![Complex64::new(0.0, 0.0); (k - 2) * h];
        let mut ends0 = vec![Complex64::new(0.0, 0.0); (m + 1) * h];
        let mut ends1 = ends0.clone();
        let mut column = vec![Complex64::new(0.0, 0.0); k];
        for j in 0..h {
            for (row, v) in column.iter_mut().enumerate() {
                *v = spectra[row][j];
            }
            let Series {
                ends0: e0,
                ends1: e1,
                sine: b,
                ..
            } = lanczos::fit(&mut cplan, &column, m, &weights);
            for d in 0..=m {
                ends0[d * h + j] = e0[d];
                ends1[d * h + j] = e1[d];
            }
            for (nn, bn) in b.iter().enumerate() {
                sine[nn * h + j] = *bn;
            }
        }
        Coord { sine, ends0, ends1 }
    });
    Surface {
        nodes_around: n,
        nodes_along: k,
        lanczos: m,
        coords,
    }
}

impl Surface {
    fn harmonics(&self) -> usize {
        self.nodes_around / 2 + 1
    }

    /// The Fourier coefficients around at height parameter `v`, for coordinate `c`.
    fn spectrum(&self, c: usize, v: f64, sines: &[f64], out: &mut [Complex64]) {
        let h = self.harmonics();
        let co = &self.coords[c];
        out.fill(Complex64::new(0.0, 0.0));
        for d in 0..=self.lanczos {
            let (p0, p1) = (lanczos::p_odd(d, 1.0 - v), lanczos::p_odd(d, v));
            let (e0, e1) = (&co.ends0[d * h..(d + 1) * h], &co.ends1[d * h..(d + 1) * h]);
            for (o, (a, b)) in out.iter_mut().zip(e0.iter().zip(e1)) {
                *o += a * p0 + b * p1;
            }
        }
        for (nn, s) in sines.iter().enumerate() {
            for (o, b) in out.iter_mut().zip(&co.sine[nn * h..(nn + 1) * h]) {
                *o += b * *s;
            }
        }
    }

    fn sines(&self, v: f64) -> Vec<f64> {
        let w = std::f64::consts::PI * v;
        (1..self.nodes_along - 1)
            .map(|nn| (w * nn as f64).sin())
            .collect()
    }

    /// The point at `(u, v)`: `u` around (period 1), `v` along in `[0, 1]`.
    pub fn eval(&self, u: f64, v: f64) -> Point3 {
        let sines = self.sines(v);
        let mut spec = vec![Complex64::new(0.0, 0.0); self.harmonics()];
        let mut p = Point3::origin();
        for c in 0..3 {
            self.spectrum(c, v, &sines, &mut spec);
            p[c] = trig::eval(&spec, self.nodes_around, u);
        }
        p
    }

    /// The ring at height parameter `v`: `around` points at `u = l / around`.
    pub fn eval_ring(&self, v: f64, around: usize) -> Vec<Point3> {
        let plan = RealFftPlanner::<f64>::new().plan_fft_inverse(around);
        let mut ring = vec![Point3::origin(); around];
        self.ring_into(
            v,
            &plan,
            &mut RingScratch::new(self.harmonics(), around),
            &mut ring,
        );
        ring
    }

    fn ring_into(&self, v: f64, plan: &Plan, scratch: &mut RingScratch, ring: &mut [Point3]) {
        let around = ring.len();
        let sines = self.sines(v);
        for c in 0..3 {
            self.spectrum(c, v, &sines, &mut scratch.spec);
            if around >= self.nodes_around {
                trig::inverse_padded(plan, &scratch.spec, self.nodes_around, &mut scratch.vals);
            } else {
                for (l, x) in scratch.vals.iter_mut().enumerate() {
                    *x = trig::eval(&scratch.spec, self.nodes_around, l as f64 / around as f64);
                }
            }
            for (p, x) in ring.iter_mut().zip(scratch.vals.iter()) {
                p[c] = *x;
            }
        }
    }

    /// Points on `along` rings (`v = i / (along - 1)`) of `around` points (`u = l / around`),
    /// ring after ring.
    pub fn eval_grid(&self, along: usize, around: usize) -> Vec<Point3> {
        assert!(along >= 2 && around >= 3);
        let mut out = vec![Point3::origin(); along * around];
        let plan = RealFftPlanner::<f64>::new().plan_fft_inverse(around);
        out.par_chunks_mut(around).enumerate().for_each_init(
            || RingScratch::new(self.harmonics(), around),
            |scratch, (i, ring)| {
                self.ring_into(i as f64 / (along - 1) as f64, &plan, scratch, ring)
            },
        );
        out
    }

    /// A closed (or, without `caps`, open) triangle mesh of the surface: `along` rings of
    /// `around` points, wound outward for counter-clockwise sections stacked upward. Caps are
    /// fans from the ring's centroid when every fan triangle keeps the ring's turning sense, and
    /// ear-clipped otherwise (a section that is not star-shaped).
    pub fn tessellate(&self, along: usize, around: usize, caps: bool) -> TriMesh {
        let positions = self.eval_grid(along, around);
        tessellate_rings(positions, along, around, caps)
    }
}

type Plan = trig::InversePlan;

/// Per-thread buffers for evaluating rings.
struct RingScratch {
    spec: Vec<Complex64>,
    vals: Vec<f64>,
}

impl RingScratch {
    fn new(harmonics: usize, around: usize) -> RingScratch {
        RingScratch {
            spec: vec![Complex64::new(0.0, 0.0); harmonics],
            vals: vec![0.0; around],
        }
    }
}

/// Triangulates `along` rings of `around` points (ring after ring) into a tube, with caps.
pub fn tessellate_rings(
    mut positions: Vec<Point3>,
    along: usize,
    around: usize,
    caps: bool,
) -> TriMesh {
    let idx = |i: usize, l: usize| (i * around + l % around) as u32;
    let mut faces = Vec::with_capacity(2 * along * around + 2 * around);
    for i in 0..along - 1 {
        for l in 0..around {
            let (a, b, c, d) = (idx(i, l), idx(i, l + 1), idx(i + 1, l + 1), idx(i + 1, l));
            faces.push([a, b, c]);
            faces.push([c, d, a]);
        }
    }
    if caps {
        for (ring, top) in [(0, false), (along - 1, true)] {
            let ids: Vec<u32> = (0..around).map(|l| idx(ring, l)).collect();
            cap(&mut positions, &mut faces, &ids, top);
        }
    }
    TriMesh::new(positions, faces)
}

/// Closes a ring (counter-clockwise seen from above): upward for the top, downward for the bottom.
///
/// A ring that is star-shaped about its centroid gets concentric rings shrunk towards the
/// centroid (as many as the cap's mean radius over twice the ring's mean edge, 1 to 8) and a
/// small fan in the middle, so its triangles are about as large as the surface's; other rings
/// are ear-clipped.
fn cap(positions: &mut Vec<Point3>, faces: &mut Vec<[u32; 3]>, ring: &[u32], top: bool) {
    let n = ring.len();
    let c = ring.iter().fold(Point3::origin().coords, |s, &i| {
        s + positions[i as usize].coords
    }) / n as f64;
    let star = (0..n).all(|l| {
        let (a, b) = (
            positions[ring[l] as usize],
            positions[ring[(l + 1) % n] as usize],
        );
        (a.x - c.x) * (b.y - c.y) - (a.y - c.y) * (b.x - c.x) > 0.0
    });
    if !star {
        let order: Vec<u32> = if top {
            ring.to_vec()
        } else {
            ring.iter().rev().copied().collect()
        };
        triangulate(
            positions,
            &order,
            QuadSplit::Paper,
            faces,
            &mut PolygonStats::default(),
        );
        return;
    }
    let radius = ring
        .iter()
        .map(|&i| (positions[i as usize].coords - c).norm())
        .sum::<f64>()
        / n as f64;
    let edge = (0..n)
        .map(|l| (positions[ring[(l + 1) % n] as usize] - positions[ring[l] as usize]).norm())
        .sum::<f64>()
        / n as f64;
    let rings = ((radius / (2.0 * edge)).round() as usize).clamp(1, 8);
    let mut outer: Vec<u32> = ring.to_vec();
    for k in 1..rings {
        let s = 1.0 - k as f64 / rings as f64;
        let inner: Vec<u32> = ring
            .iter()
            .map(|&i| {
                positions.push(Point3::from(c + (positions[i as usize].coords - c) * s));
                (positions.len() - 1) as u32
            })
            .collect();
        for l in 0..n {
            let (a, b, cc, d) = (outer[l], outer[(l + 1) % n], inner[(l + 1) % n], inner[l]);
            if top {
                faces.push([a, b, cc]);
                faces.push([cc, d, a]);
            } else {
                faces.push([a, cc, b]);
                faces.push([cc, a, d]);
            }
        }
        outer = inner;
    }
    positions.push(Point3::from(c));
    let ci = (positions.len() - 1) as u32;
    for l in 0..n {
        let (a, b) = (outer[l], outer[(l + 1) % n]);
        faces.push(if top { [ci, a, b] } else { [ci, b, a] });
    }
}

/// The analytic reference surface of `bench fit` and the tests: closed and smooth around (u in
/// 0..1, exactly 32-node band-limited), not periodic along the height (v in 0..1):
/// `x = r cos t (1 + 0.1 cos 2t)`, `y = 0.8 r sin t`, `z = 0.5 + 1.7 v + 0.2 v^2`,
/// `r = 1 + 0.3 v + 0.2 sin 2v + 0.1 e^v`, `t = 2 pi u`.
pub fn reference_surface(u: f64, v: f64) -> Point3 {
    let t = std::f64::consts::TAU * u;
    let r = 1.0 + 0.3 * v + 0.2 * (2.0 * v).sin() + 0.1 * v.exp();
    Point3::new(
        r * t.cos() * (1.0 + 0.1 * (2.0 * t).cos()),
        0.8 * r * t.sin(),
        0.5 + 1.7 * v + 0.2 * v * v,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::diagnose::{diagnose, ShellState};

    use super::reference_surface as analytic;

    fn grid_of(f: impl Fn(f64, f64) -> Point3, k: usize, n: usize) -> Vec<Point3> {
        (0..k)
            .flat_map(|i| (0..n).map(move |l| (i, l)))
            .map(|(i, l)| f(l as f64 / n as f64, i as f64 / (k - 1) as f64))
            .collect()
    }

    fn max_error(s: &Surface, f: impl Fn(f64, f64) -> Point3) -> f64 {
        let mut e: f64 = 0.0;
        for i in 0..=40 {
            for l in 0..37 {
                let (u, v) = (l as f64 / 37.0, i as f64 / 40.0);
                e = e.max((s.eval(u, v) - f(u, v)).norm());
            }
        }
        e
    }

    #[test]
    fn nodes_are_interpolated() {
        let (k, n) = (9, 16);
        let g = grid_of(analytic, k, n);
        let s = fit(&g, k, n, 1);
        for i in 0..k {
            for l in 0..n {
                let p = s.eval(l as f64 / n as f64, i as f64 / (k - 1) as f64);
                assert!((p - g[i * n + l]).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn band_limited_around_polynomial_along_is_exact() {
        // Degree 2 around, cubic along: order 1 reproduces it to round-off everywhere.
        let f = |u: f64, v: f64| {
            let t = std::f64::consts::TAU * u;
            let r = 1.0 + 0.5 * v - 0.3 * v * v * v;
            Point3::new(r * t.cos() + 0.1 * (2.0 * t).cos(), r * t.sin(), 2.0 * v)
        };
        let s = fit(&grid_of(f, 8, 8), 8, 8, 1);
        assert!(max_error(&s, f) < 1e-12, "{}", max_error(&s, f));
    }

    #[test]
    fn grid_evaluation_matches_pointwise_and_mesh_is_closed() {
        let s = fit(&grid_of(analytic, 12, 32), 12, 32, 2);
        for around in [20, 32, 100] {
            let g = s.eval_grid(7, around);
            for i in 0..7 {
                for l in 0..around {
                    let p = s.eval(l as f64 / around as f64, i as f64 / 6.0);
                    assert!((p - g[i * around + l]).norm() < 1e-12, "around {around}");
                }
            }
        }
        let m = s.tessellate(30, 48, true);
        let d = diagnose(&m);
        assert_eq!(d.shell_state, ShellState::Closed);
        assert!(d.total_volume > 0.0);
    }
}
