//! Anderson acceleration of a fixed-point iteration `u <- G(u)` (Walker and Ni 2011; for
//! projective dynamics, Peng et al. 2018).
//!
//! With `f_k = G(u_k) - u_k` and the last `m` differences `dF_j = f_{j+1} - f_j`,
//! `dG_j = G(u_{j+1}) - G(u_j)`, the next iterate is
//!
//! `u_{k+1} = G(u_k) - sum_j theta_j dG_j`, `theta = argmin |f_k - sum_j theta_j dF_j|^2`.
//!
//! On a linear map this is GMRES: a slow mode (an eigenvalue of `G` near 1) costs one vector of
//! history instead of thousands of iterations. Projective dynamics has such modes: a cloth lying
//! on a face slides against the contact weight (a proximal term), which lets it move a fraction
//! `m / (h^2 w)` of the way per iteration. The caller keeps the energy safeguard: an
//! accelerated iterate that raises the objective is replaced by the plain one (`reset`).
//!
//! The least-squares problem is `m x m` (normal equations with a relative ridge of 1e-10);
//! every sum runs in a fixed order, so results do not depend on the thread count.

use crate::math::{Point3, Vec3};
use nalgebra::{DMatrix, DVector};

/// The history of an Anderson-accelerated iteration.
#[derive(Debug, Default)]
pub struct Anderson {
    depth: usize,
    /// Ring buffers of the last differences (`len` of them valid, the newest at `head`).
    d_f: Vec<Vec<Vec3>>,
    d_g: Vec<Vec<Vec3>>,
    len: usize,
    head: usize,
    last_f: Vec<Vec3>,
    last_g: Vec<Point3>,
    f: Vec<Vec3>,
    started: bool,
}

fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}

impl Anderson {
    /// An empty history of `depth` vectors.
    pub fn new(depth: usize) -> Anderson {
        Anderson {
            depth,
            d_f: vec![Vec::new(); depth],
            d_g: vec![Vec::new(); depth],
            ..Anderson::default()
        }
    }

    /// Forgets the history (a new step, or a rejected iterate).
    pub fn reset(&mut self) {
        self.len = 0;
        self.started = false;
    }

    /// Given the iterate `u` and its image `g = G(u)`, writes the accelerated iterate into
    /// `out` (`g` itself while the history is empty). Returns whether it was accelerated.
    pub fn next(&mut self, u: &[Point3], g: &[Point3], out: &mut Vec<Point3>) -> bool {
        if self.depth == 0 {
            out.clone_from(&g.to_vec());
            return false;
        }
        self.f.clear();
        self.f.extend(g.iter().zip(u).map(|(a, b)| a - b));
        if self.started {
            self.head = (self.head + 1) % self.depth;
            let (df, dg) = (&mut self.d_f[self.head], &mut self.d_g[self.head]);
            df.clear();
            df.extend(self.f.iter().zip(&self.last_f).map(|(a, b)| a - b));
            dg.clear();
            dg.extend(g.iter().zip(&self.last_g).map(|(a, b)| a - b));
            self.len = (self.len + 1).min(self.depth);
        }
        self.started = true;
        std::mem::swap(&mut self.last_f, &mut self.f);
        self.last_g.clear();
        self.last_g.extend_from_slice(g);
        out.clear();
        out.extend_from_slice(g);
        let m = self.len;
        if m == 0 {
            return false;
        }
        // The valid slots, oldest first.
        let slot = |j: usize| (self.head + self.depth + 1 - m + j) % self.depth;
        let mut a = DMatrix::<f64>::zeros(m, m);
        let mut b = DVector::<f64>::zeros(m);
        for i in 0..m {
            for j in 0..=i {
                let v = dot(&self.d_f[slot(i)], &self.d_f[slot(j)]);
                a[(i, j)] = v;
                a[(j, i)] = v;
            }
            b[i] = dot(&self.d_f[slot(i)], &self.last_f);
        }
        let ridge = 1e-10 * a.trace().max(f64::MIN_POSITIVE);
        for i in 0..m {
            a[(i, i)] += ridge;
        }
        let Some(theta) = a.cholesky().map(|c| c.solve(&b)) else {
            return false;
        };
        if !theta.iter().all(|t| t.is_finite()) {
            return false;
        }
        for j in 0..m {
            for (o, d) in out.iter_mut().zip(&self.d_g[slot(j)]) {
                *o -= d * theta[j];
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slow_linear_mode_converges_in_a_few_iterations() {
        // G(u) = c + diag(0.9999, 0.5, 0.1) (u - c): plain iteration needs ~10^5 steps for the
        // first coordinate; Anderson with 3 vectors of history finishes in a handful.
        let c = Point3::new(1.0, 2.0, 3.0);
        let rates = Vec3::new(0.9999, 0.5, 0.1);
        let g = |u: &Point3| c + (u - c).component_mul(&rates);
        let mut aa = Anderson::new(3);
        let mut u = vec![Point3::origin()];
        let mut next = Vec::new();
        for _ in 0..8 {
            let gu = vec![g(&u[0])];
            aa.next(&u, &gu, &mut next);
            u.clone_from(&next);
        }
        assert!((u[0] - c).norm() < 1e-9, "{:?}", u[0]);
        // Without acceleration, 8 iterations leave the slow coordinate almost where it began.
        let mut p = Point3::origin();
        for _ in 0..8 {
            p = g(&p);
        }
        assert!((p - c).x.abs() > 0.99);
    }
}
