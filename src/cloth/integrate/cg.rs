//! Filtered, block-Jacobi preconditioned conjugate gradients (Baraff and Witkin 1998, s. 5.3).
//!
//! Solves `A x = b` for a symmetric positive (semi-)definite `A` given as a product, with each
//! particle's unknown restricted to a subspace by a filter `S_i` (the identity for a free
//! particle, `I - n n^T` for one held on a surface, zero for a pinned one): the iterates stay in
//! the filtered space, and the residual is filtered before use, so the constrained directions
//! keep their starting values. The preconditioner is the inverse of the 3x3 diagonal blocks of
//! `A`, filtered on both sides (symmetric). Stops when `r^T P r <= tol^2 b^T P b`.
//! Reductions run over fixed chunks (`par::sum`), so results do not depend on the thread count.

use crate::math::Vec3;
use crate::par;
use nalgebra::Matrix3;

/// A particle's filter: what part of its unknown is free.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Filter {
    /// All three directions.
    Free,
    /// The plane across this unit normal.
    Plane(Vec3),
    /// None (pinned).
    Fixed,
}

impl Filter {
    /// `S v`.
    #[inline(always)]
    pub fn apply(&self, v: Vec3) -> Vec3 {
        match self {
            Filter::Free => v,
            Filter::Plane(n) => v - n * n.dot(&v),
            Filter::Fixed => Vec3::zeros(),
        }
    }
}

/// Scratch vectors of one solve, kept between steps.
#[derive(Debug, Default)]
pub struct Scratch {
    r: Vec<Vec3>,
    c: Vec<Vec3>,
    q: Vec<Vec3>,
    s: Vec<Vec3>,
}

/// Outcome of a solve.
#[derive(Debug, Clone, Copy)]
pub struct CgResult {
    /// Iterations taken.
    pub iterations: u32,
    /// Whether the tolerance was reached.
    pub converged: bool,
}

fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    par::sum(a.len(), |i| a[i].dot(&b[i]))
}

/// Solves `A x = b` from the start `x` (filtered on entry), `mul(y, out)` writing `A y`,
/// `precond[i]` the inverse diagonal block of particle `i`.
#[allow(clippy::too_many_arguments)]
pub fn solve(
    mul: &(dyn Fn(&[Vec3], &mut [Vec3]) + Sync),
    b: &[Vec3],
    precond: &[Matrix3<f64>],
    filter: &[Filter],
    x: &mut [Vec3],
    tol: f64,
    max_iterations: u32,
    scratch: &mut Scratch,
) -> CgResult {
    let n = b.len();
    for v in [
        &mut scratch.r,
        &mut scratch.c,
        &mut scratch.q,
        &mut scratch.s,
    ] {
        v.resize(n, Vec3::zeros());
    }
    let pre = |i: usize, v: Vec3| filter[i].apply(precond[i] * filter[i].apply(v));
    let target = tol * tol * start(mul, b, &pre, filter, x, scratch);
    let mut delta = dot(&scratch.r, &scratch.c);
    let mut it = 0;
    while delta > target && it < max_iterations {
        let Some(d) = iterate(mul, &pre, filter, x, delta, scratch) else {
            break;
        };
        delta = d;
        it += 1;
    }
    CgResult {
        iterations: it,
        converged: delta <= target,
    }
}

/// The start: `x` filtered, the residual `r = S (b - A x)`, `c = P r` and `s = P b`; `b^T P b`.
fn start(
    mul: &(dyn Fn(&[Vec3], &mut [Vec3]) + Sync),
    b: &[Vec3],
    pre: &(impl Fn(usize, Vec3) -> Vec3 + Sync),
    filter: &[Filter],
    x: &mut [Vec3],
    scratch: &mut Scratch,
) -> f64 {
    let n = b.len();
    let Scratch { r, c, q, s } = scratch;
    par::for_chunks(256, x, |base, xs| {
        for (k, xi) in xs.iter_mut().enumerate() {
            *xi = filter[base + k].apply(*xi);
        }
    });
    mul(x, q);
    par::for_chunks3(
        256,
        n,
        &mut r[..],
        &mut c[..],
        &mut s[..],
        |base, rs, cs, ss| {
            for k in 0..rs.len() {
                let i = base + k;
                rs[k] = filter[i].apply(b[i] - q[i]);
                cs[k] = pre(i, rs[k]);
                ss[k] = pre(i, b[i]);
            }
        },
    );
    dot(b, s)
}

/// One iteration from `delta = r^T P r`: `x` and the residual updated along the direction `c`,
/// and `c` to the next direction; the new `delta`, or `None` when `c^T A c` is not positive.
fn iterate(
    mul: &(dyn Fn(&[Vec3], &mut [Vec3]) + Sync),
    pre: &(impl Fn(usize, Vec3) -> Vec3 + Sync),
    filter: &[Filter],
    x: &mut [Vec3],
    delta: f64,
    scratch: &mut Scratch,
) -> Option<f64> {
    let Scratch { r, c, q, s } = scratch;
    let n = r.len();
    mul(c, q);
    par::for_chunks(256, &mut q[..], |base, qs| {
        for (k, qi) in qs.iter_mut().enumerate() {
            *qi = filter[base + k].apply(*qi);
        }
    });
    let cq = dot(c, q);
    if cq <= 0.0 {
        return None;
    }
    let alpha = delta / cq;
    par::for_chunks3(
        256,
        n,
        &mut *x,
        &mut r[..],
        &mut s[..],
        |base, xs, rs, ss| {
            for k in 0..xs.len() {
                let i = base + k;
                xs[k] += c[i] * alpha;
                rs[k] -= q[i] * alpha;
                ss[k] = pre(i, rs[k]);
            }
        },
    );
    let new = dot(r, s);
    let beta = new / delta;
    par::for_chunks(256, &mut c[..], |base, cs| {
        for (k, ci) in cs.iter_mut().enumerate() {
            *ci = s[base + k] + *ci * beta;
        }
    });
    Some(new)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_chain_laplacian_with_fixed_and_plane_filters() {
        // A = diag(2) + chain Laplacian, 20 particles; particle 0 fixed, particle 5 held to z = 0.
        let n = 20;
        let mul = |y: &[Vec3], out: &mut [Vec3]| {
            for i in 0..n {
                let mut a = y[i] * 2.0;
                if i > 0 {
                    a += y[i] - y[i - 1];
                }
                if i + 1 < n {
                    a += y[i] - y[i + 1];
                }
                out[i] = a;
            }
        };
        let b: Vec<Vec3> = (0..n).map(|i| Vec3::new(1.0, i as f64, -0.5)).collect();
        let pre = vec![Matrix3::identity() * 0.25; n];
        let mut filter = vec![Filter::Free; n];
        filter[0] = Filter::Fixed;
        filter[5] = Filter::Plane(Vec3::z());
        let mut x = vec![Vec3::new(9.0, 9.0, 9.0); n];
        let res = solve(
            &mul,
            &b,
            &pre,
            &filter,
            &mut x,
            1e-12,
            200,
            &mut Scratch::default(),
        );
        assert!(res.converged);
        assert_eq!(x[0], Vec3::zeros());
        assert_eq!(x[5].z, 0.0);
        // The filtered residual vanishes.
        let mut ax = vec![Vec3::zeros(); n];
        mul(&x, &mut ax);
        for i in 0..n {
            let r = filter[i].apply(b[i] - ax[i]);
            assert!(r.norm() < 1e-9, "{i} {r:?}");
        }
    }
}
