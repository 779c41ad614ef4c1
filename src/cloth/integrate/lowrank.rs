//! A few changed diagonal entries without refactoring: the Sherman-Morrison-Woodbury identity.
//!
//! With `A` factored and `k` diagonal entries changed by `delta_j` at unknowns `u_j`
//! (`A' = A + U W U^T`, `U` the unit columns `e_(u_j)`, `W = diag(delta)`),
//!
//! `A'^-1 b = z - Z C^-1 U^T z`, with `z = A^-1 b`, `Z = A^-1 U` and
//! `C = W^-1 + U^T A^-1 U` (`k x k`).
//!
//! `Z` costs a third of a solve per column (three columns per sweep), once per changed entry;
//! it is kept while the entry stays changed, so a contact that lasts many steps is paid for
//! once. Each corrected solve then costs `3 k n` multiply-adds. Projective dynamics uses it for
//! the particles that come into or leave contact between refactorisations
//! ([`LOW_RANK_MAX`](super::projective::LOW_RANK_MAX)): exact, so the iterates are those of a
//! refactored matrix (to rounding).
//!
//! ```
//! use drapekit::cloth::integrate::cholesky::Cholesky;
//! use drapekit::cloth::integrate::lowrank::DiagonalUpdate;
//! // A = [[4, 2], [2, 3]]; A' = A + 5 e_1 e_1^T = [[4, 2], [2, 8]].
//! let mut c = Cholesky::analyse(2, &[(0, 0), (1, 0), (1, 1)]);
//! c.factor(&[4.0, 2.0, 3.0]).unwrap();
//! let mut up = DiagonalUpdate::default();
//! up.set(&mut c, &[(1, 5.0)]);
//! // b = A' [1, -1]: [2, -6] in every column.
//! let mut b = [[2.0, 2.0, 2.0], [-6.0, -6.0, -6.0]];
//! c.solve(&mut b);
//! up.correct(&mut b);
//! assert!((b[0][0] - 1.0).abs() < 1e-14 && (b[1][2] + 1.0).abs() < 1e-14);
//! ```

use super::cholesky::Cholesky;
use nalgebra::DMatrix;

/// The changed diagonal entries of a factored matrix and what the correction needs.
#[derive(Default)]
pub struct DiagonalUpdate {
    /// The changed unknowns and their change.
    index: Vec<usize>,
    delta: Vec<f64>,
    /// `Z = A^-1 U`, row-major (`n x k`): a row's `k` entries side by side, so that the
    /// correction of a row is three dot products of length `k`.
    z: Vec<f64>,
    /// `C^-1` (module notes), `k x k`.
    c_inv: DMatrix<f64>,
    /// Columns solved for so far (each a third of a solve).
    pub columns_solved: u64,
}

impl DiagonalUpdate {
    /// The number of changed entries.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// Whether no entry is changed (the factored matrix is the matrix).
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// Whether the changes are exactly `changes` (nothing to do).
    pub fn matches(&self, changes: &[(usize, f64)]) -> bool {
        changes.len() == self.index.len()
            && changes
                .iter()
                .zip(self.index.iter().zip(&self.delta))
                .all(|(&(u, d), (&v, &e))| u == v && d == e)
    }

    /// Forgets every change (after a refactorisation).
    pub fn clear(&mut self) {
        self.index.clear();
        self.delta.clear();
        self.z.clear();
        self.c_inv = DMatrix::zeros(0, 0);
    }

    /// Sets the changes to `changes` (`(unknown, delta)`, distinct unknowns, deltas non-zero,
    /// and `A + U W U^T` positive definite). Columns of unknowns already changed are kept.
    pub fn set(&mut self, chol: &mut Cholesky, changes: &[(usize, f64)]) {
        let n = chol.len();
        let (k_old, k) = (self.index.len(), changes.len());
        let mut old: Vec<(usize, usize)> = self.index.iter().copied().zip(0..k_old).collect();
        old.sort_unstable();
        let mut z = vec![0.0; n * k];
        let mut missing = Vec::new();
        for (slot, &(u, _)) in changes.iter().enumerate() {
            match old.binary_search_by_key(&u, |&(v, _)| v) {
                Ok(at) => {
                    let from = old[at].1;
                    for r in 0..n {
                        z[r * k + slot] = self.z[r * k_old + from];
                    }
                }
                Err(_) => missing.push(slot),
            }
        }
        self.index = changes.iter().map(|&(u, _)| u).collect();
        self.delta = changes.iter().map(|&(_, d)| d).collect();
        self.z = z;
        self.solve_columns(chol, &missing);
        self.build_c();
    }

    /// `A^-1 e_u` for the slots `missing`, three per solve.
    fn solve_columns(&mut self, chol: &mut Cholesky, missing: &[usize]) {
        let (n, k) = (chol.len(), self.index.len());
        let mut rhs = vec![[0.0; 3]; n];
        for group in missing.chunks(3) {
            rhs.iter_mut().for_each(|r| *r = [0.0; 3]);
            for (c, &slot) in group.iter().enumerate() {
                rhs[self.index[slot]][c] = 1.0;
            }
            chol.solve(&mut rhs);
            for (c, &slot) in group.iter().enumerate() {
                for (r, row) in rhs.iter().enumerate() {
                    self.z[r * k + slot] = row[c];
                }
            }
            self.columns_solved += group.len() as u64;
        }
    }

    /// `C^-1` from the columns and the deltas.
    fn build_c(&mut self) {
        let k = self.index.len();
        let c = DMatrix::from_fn(k, k, |j, l| {
            let d = if j == l { 1.0 / self.delta[j] } else { 0.0 };
            d + self.z[self.index[j] * k + l]
        });
        self.c_inv = c
            .try_inverse()
            .expect("C is invertible when the updated matrix is positive definite");
    }

    /// Turns `z = A^-1 b` into `A'^-1 b` (three columns).
    pub fn correct(&self, z: &mut [[f64; 3]]) {
        let k = self.index.len();
        if k == 0 {
            return;
        }
        // y = C^-1 U^T z, one vector of length k per coordinate.
        let mut y = [vec![0.0; k], vec![0.0; k], vec![0.0; k]];
        for l in 0..k {
            for (j, &u) in self.index.iter().enumerate() {
                let c = self.c_inv[(l, j)];
                (0..3).for_each(|a| y[a][l] += c * z[u][a]);
            }
        }
        for (zr, a) in z.iter_mut().zip(self.z.chunks_exact(k)) {
            for c in 0..3 {
                zr[c] -= dot(a, &y[c]);
            }
        }
    }
}

/// `a . b` in four interleaved sums (the compiler vectorises them). Kept rather than
/// nalgebra's `dot`, which is as fast here but sums in another order: with it, the bar test of
/// `tests/garment.rs` ended its sewing at a 1.21 mm gap instead of under 1 mm (that test has
/// little margin; see the issue notes).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0; 4];
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ac
        .remainder()
        .iter()
        .zip(bc.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ac.zip(bc) {
        for i in 0..4 {
            s[i] += x[i] * y[i];
        }
    }
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `side x side` grid: 10 on the diagonal, -1 to each neighbour (strictly diagonally
    /// dominant, so any diagonal change above -5 keeps it positive definite).
    fn grid(side: usize) -> (usize, Vec<(usize, usize)>, Vec<f64>) {
        let n = side * side;
        let (mut e, mut v) = (Vec::new(), Vec::new());
        for a in 0..n {
            e.push((a, a));
            v.push(10.0 + (a % 5) as f64 * 0.3);
            let (i, j) = (a / side, a % side);
            if j > 0 {
                e.push((a, a - 1));
                v.push(-1.0);
            }
            if i > 0 {
                e.push((a, a - side));
                v.push(-1.0);
            }
        }
        (n, e, v)
    }

    /// `A' x = b` both ways: corrected through the update, and by refactoring `A'`.
    fn both(side: usize, changes: &[(usize, f64)], up: &mut DiagonalUpdate) -> f64 {
        let (n, e, v) = grid(side);
        let mut chol = Cholesky::analyse(n, &e);
        chol.factor(&v).unwrap();
        let b: Vec<[f64; 3]> = (0..n)
            .map(|i| [(i as f64).sin(), 1.0, (i % 7) as f64 - 3.0])
            .collect();
        up.set(&mut chol, changes);
        let mut x = b.clone();
        chol.solve(&mut x);
        up.correct(&mut x);
        let mut v2 = v.clone();
        for &(u, d) in changes {
            // The diagonal of unknown u is the first entry pushed for it.
            let at = e.iter().position(|&p| p == (u, u)).unwrap();
            v2[at] += d;
        }
        let mut refactored = Cholesky::analyse(n, &e);
        refactored.factor(&v2).unwrap();
        let mut y = b;
        refactored.solve(&mut y);
        x.iter()
            .zip(&y)
            .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
            .fold(0.0, f64::max)
    }

    #[test]
    fn corrected_solves_match_a_refactored_matrix() {
        let mut up = DiagonalUpdate::default();
        let first: Vec<(usize, f64)> = (0..10).map(|k| (37 * k + 3, 50.0 + k as f64)).collect();
        assert!(both(30, &first, &mut up) < 1e-13);
        assert_eq!(up.columns_solved, 10);
        // Some kept (one with a new delta), some dropped, some new, some lowered.
        let mut second: Vec<(usize, f64)> =
            (5..10).map(|k| (37 * k + 3, 50.0 + k as f64)).collect();
        second[0].1 = -4.0;
        second.extend((0..4).map(|k| (101 * k + 11, -4.5)));
        assert!(both(30, &second, &mut up) < 1e-13);
        assert_eq!(
            up.columns_solved,
            10 + 4,
            "kept columns are not solved again"
        );
        assert!(up.matches(&second) && !up.matches(&first));
        up.clear();
        assert!(up.is_empty());
    }
}
