//! A linear spring between particles `a` and `b` (`method.md` s. 2), with `d = x_b - x_a`,
//! `L = |d|`, `u = d / L`:
//!
//! * energy `E = k (L - l)^2 / 2`;
//! * force on `a` (minus the gradient in `x_a`): `f_a = k (L - l) u`, and `f_b = -f_a`;
//! * Hessian: `d2E/dx_a^2 = d2E/dx_b^2 = -d2E/dx_a dx_b = H` with
//!   `H = k [u u^T + (1 - l / L) (I - u u^T)]`. Compressed (`L < l`) the transverse part is
//!   negative; [`Spring::hessian`] with `psd = true` drops it (Baraff and Witkin's remedy, so
//!   the implicit system stays positive definite).
//! * projection (projective dynamics): the nearest `d` of length `l` is `l u`, and
//!   `E = k |d - l u|^2 / 2` there, the same energy.

use crate::math::{Point3, Vec3};
use nalgebra::Matrix3;
use serde::Serialize;

/// What a spring models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SpringKind {
    /// Along a thread (or a band edge within 22.5 degrees of one).
    Stretch,
    /// A cell diagonal (or a band edge on the bias).
    Shear,
    /// A seam: rest length 0 between the two sides' particles of a stitch.
    Seam,
}

/// A linear spring `F = k (|d| - rest) d / |d|`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length, m.
    pub rest: f64,
    /// Constant, N/m.
    pub k: f64,
    /// Kind.
    pub kind: SpringKind,
}

impl Spring {
    /// Energy at `xa`, `xb`, J.
    #[inline]
    pub fn energy(&self, xa: &Point3, xb: &Point3) -> f64 {
        let e = (xb - xa).norm() - self.rest;
        0.5 * self.k * e * e
    }

    /// Force on `a` (on `b` it is the opposite), N; zero when the ends meet.
    #[inline(always)]
    pub fn force_on_a(&self, xa: &Point3, xb: &Point3) -> Vec3 {
        let d = xb - xa;
        let len = d.norm();
        if len > 0.0 {
            d * (self.k * (len - self.rest) / len)
        } else {
            Vec3::zeros()
        }
    }

    /// The block `H = d2E/dx_a^2` (N/m); `psd` drops the negative transverse part of a compressed
    /// spring.
    #[inline]
    pub fn hessian(&self, xa: &Point3, xb: &Point3, psd: bool) -> Matrix3<f64> {
        let d = xb - xa;
        let len = d.norm();
        if len == 0.0 {
            return Matrix3::identity() * self.k;
        }
        let u = d / len;
        let uu = u * u.transpose();
        let mut t = 1.0 - self.rest / len;
        if psd {
            t = t.max(0.0);
        }
        (uu + (Matrix3::identity() - uu) * t) * self.k
    }

    /// The projection of `d = x_b - x_a` on the constraint `|d| = rest` (projective dynamics),
    /// with the strain held within `[-limit, limit]` instead when `limit` is given (zero energy
    /// inside the band). A zero `d` keeps its direction undefined: it projects to zero.
    #[inline]
    pub fn project(&self, xa: &Point3, xb: &Point3, limit: Option<f64>) -> Vec3 {
        self.project_measured(xa, xb, limit).0
    }

    /// [`Spring::project`] and the spring's strain `|x_b - x_a| / rest - 1` at the same time
    /// (one length for both: the adaptive iterations of projective dynamics read the strain).
    #[inline]
    pub fn project_measured(&self, xa: &Point3, xb: &Point3, limit: Option<f64>) -> (Vec3, f64) {
        let d = xb - xa;
        let len = d.norm();
        let strain = len / self.rest - 1.0;
        if len == 0.0 {
            return (Vec3::zeros(), strain);
        }
        let target = match limit {
            None => self.rest,
            Some(s) => len.clamp(self.rest * (1.0 - s), self.rest * (1.0 + s)),
        };
        (d * (target / len), strain)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spring() -> Spring {
        Spring {
            a: 0,
            b: 1,
            rest: 0.3,
            k: 1234.0,
            kind: SpringKind::Stretch,
        }
    }

    fn ends(stretch: f64) -> (Point3, Point3) {
        let dir = Vec3::new(0.3, -0.5, 0.8).normalize();
        let a = Point3::new(0.1, 0.2, -0.05);
        (a, a + dir * (0.3 * stretch))
    }

    #[test]
    fn force_is_minus_the_gradient_of_the_energy() {
        let s = spring();
        for stretch in [0.6, 0.97, 1.0, 1.3] {
            let (a, b) = ends(stretch);
            let f = s.force_on_a(&a, &b);
            let h = 1e-6;
            for k in 0..3 {
                let mut ap = a;
                let mut am = a;
                ap[k] += h;
                am[k] -= h;
                let g = (s.energy(&ap, &b) - s.energy(&am, &b)) / (2.0 * h);
                let scale = s.k * 0.3;
                assert!(
                    (f[k] + g).abs() < 1e-6 * scale,
                    "{stretch} {k}: {} {g}",
                    f[k]
                );
            }
        }
    }

    #[test]
    fn hessian_is_the_derivative_of_the_gradient() {
        let s = spring();
        for stretch in [0.6, 1.0, 1.3] {
            let (a, b) = ends(stretch);
            let hm = s.hessian(&a, &b, false);
            let h = 1e-6;
            for k in 0..3 {
                let mut ap = a;
                let mut am = a;
                ap[k] += h;
                am[k] -= h;
                // d(grad_a E)/dx_a = -d f_a / dx_a
                let col = -(s.force_on_a(&ap, &b) - s.force_on_a(&am, &b)) / (2.0 * h);
                for r in 0..3 {
                    assert!((hm[(r, k)] - col[r]).abs() < 1e-5 * s.k, "{stretch}");
                }
            }
            // The psd version differs only when compressed, and then it has no negative eigenvalue.
            let p = s.hessian(&a, &b, true);
            let min = p.symmetric_eigenvalues().min();
            assert!(min >= -1e-9 * s.k, "{min}");
            if stretch >= 1.0 {
                assert_eq!(p, hm);
            } else {
                assert!(hm.symmetric_eigenvalues().min() < 0.0);
            }
        }
    }

    #[test]
    fn projection_has_the_rest_length_and_keeps_the_energy() {
        let s = spring();
        let (a, b) = ends(1.25);
        let p = s.project(&a, &b, None);
        assert!((p.norm() - 0.3).abs() < 1e-15);
        let d = b - a;
        assert!((0.5 * s.k * (d - p).norm_squared() - s.energy(&a, &b)).abs() < 1e-12);
        let band = s.project(&a, &b, Some(0.1));
        assert!((band.norm() - 0.33).abs() < 1e-15);
        let (a, b) = ends(1.05);
        assert!((s.project(&a, &b, Some(0.1)) - (b - a)).norm() < 1e-15);
    }
}
