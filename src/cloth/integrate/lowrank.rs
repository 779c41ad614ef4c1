//! Changed diagonal entries without refactoring: the Sherman-Morrison-Woodbury identity, in
//! the factor's space.
//!
//! With `A = P^T L L^T P` factored and `k` diagonal entries changed by `delta_j` at unknowns
//! `u_j` (`A' = A + U W U^T`, `U` the unit columns `e_(u_j)`, `W = diag(delta)`),
//! `A' = P^T L (I + V W V^T) L^T P` with `V = L^-1 P U`, so
//!
//! `A'^-1 b = P^T L^-T (I - V C^-1 V^T) L^-1 P b`, with `C = W^-1 + V^T V` (`k x k`).
//!
//! The correction sits between the two sweeps of a solve ([`Cholesky::solve_with`]). A column
//! of `V` is the forward sweep of a unit vector: non-zero only on the elimination tree's path
//! from its unknown to the root (a few hundred rows of a cloth's 16,000), so it costs that path
//! ([`Cholesky::forward_unit`]), once per changed entry, and each corrected solve costs
//! `2 nnz(V)` row operations and `C^-1`'s `k^2`, not the `3 k n` of a dense `A^-1 U`. So a
//! contact that lasts many steps is paid for once, and hundreds of particles may come into or
//! leave contact between refactorisations. Projective dynamics uses it
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
//! up.set(&c, &[(1, 5.0)]).unwrap();
//! // b = A' [1, -1]: [2, -6] in every column.
//! let mut b = [[2.0, 2.0, 2.0], [-6.0, -6.0, -6.0]];
//! c.solve_with(&mut b, |y| up.correct(y));
//! assert!((b[0][0] - 1.0).abs() < 1e-14 && (b[1][2] + 1.0).abs() < 1e-14);
//! ```

use super::cholesky::{Cholesky, Row};
use super::NotPositiveDefinite;
use nalgebra::DMatrix;

/// The changed diagonal entries of a factored matrix and what the correction needs.
#[derive(Default)]
pub struct DiagonalUpdate {
    /// The changed unknowns and their change.
    index: Vec<usize>,
    delta: Vec<f64>,
    /// The columns of `V = L^-1 P U` (module notes), sparse: `(row, value)`, rows in the
    /// factor's order.
    v: Vec<Vec<(u32, f64)>>,
    /// `V^T V`, `k x k`.
    gram: DMatrix<f64>,
    /// `C^-1` (module notes), `k x k`.
    c_inv: DMatrix<f64>,
    /// `n` zeros (scratch for the columns and their products).
    scratch: Vec<f64>,
    /// Columns of `V` computed so far (each a path of the elimination tree).
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
        self.v.clear();
        self.gram = DMatrix::zeros(0, 0);
        self.c_inv = DMatrix::zeros(0, 0);
    }

    /// Sets the changes to `changes` (`(unknown, delta)`, distinct unknowns, deltas non-zero,
    /// and `A + U W U^T` positive definite). Columns of unknowns already changed, and their
    /// products, are kept. An `A + U W U^T` that is singular (its `C` is) leaves no change set
    /// and is an error: the caller refactors instead.
    pub fn set(
        &mut self,
        chol: &Cholesky,
        changes: &[(usize, f64)],
    ) -> Result<(), NotPositiveDefinite> {
        self.scratch.resize(chol.len(), 0.0);
        let mut old: Vec<(usize, usize)> = self.index.iter().copied().zip(0..).collect();
        old.sort_unstable();
        let mut v_old: Vec<Option<Vec<(u32, f64)>>> =
            std::mem::take(&mut self.v).into_iter().map(Some).collect();
        let mut from = Vec::with_capacity(changes.len());
        for &(u, _) in changes {
            let kept = old.binary_search_by_key(&u, |&(w, _)| w).ok();
            let slot = kept.map(|at| old[at].1);
            let col = match slot.and_then(|s| v_old[s].take()) {
                Some(c) => c,
                None => {
                    self.columns_solved += 1;
                    chol.forward_unit(u, &mut self.scratch)
                }
            };
            self.v.push(col);
            from.push(slot);
        }
        self.index = changes.iter().map(|&(u, _)| u).collect();
        self.delta = changes.iter().map(|&(_, d)| d).collect();
        self.build_gram(&from);
        self.build_c()
    }

    /// The changes and the products `V^T V` (`saved`; the columns follow from the factor).
    pub fn saved(&self) -> super::saved::UpdateKept {
        super::saved::UpdateKept {
            index: self.index.iter().map(|&u| u as u32).collect(),
            delta: self.delta.clone(),
            gram: self.gram.as_slice().to_vec(),
        }
    }

    /// The correction `saved` from [`DiagonalUpdate::saved`] on the same factor `chol`: its
    /// columns recomputed, its products as they were (so the solves have the same bits).
    /// `columns_solved` is left to the caller. Saved products that do not fit together (sizes,
    /// an unknown beyond the factor, a singular `C`) leave no change set and are an error.
    pub fn restore(
        &mut self,
        chol: &Cholesky,
        saved: &super::saved::UpdateKept,
    ) -> Result<(), NotPositiveDefinite> {
        let k = saved.index.len();
        self.clear();
        if saved.delta.len() != k
            || saved.gram.len() != k * k
            || saved.index.iter().any(|&u| u as usize >= chol.len())
        {
            return Err(NotPositiveDefinite);
        }
        self.scratch.resize(chol.len(), 0.0);
        for &u in &saved.index {
            let col = chol.forward_unit(u as usize, &mut self.scratch);
            self.v.push(col);
        }
        self.index = saved.index.iter().map(|&u| u as usize).collect();
        self.delta.clone_from(&saved.delta);
        self.gram = DMatrix::from_column_slice(k, k, &saved.gram);
        self.build_c()
    }

    /// `V^T V`: products of two kept columns are copied (`from`: each slot's old slot).
    fn build_gram(&mut self, from: &[Option<usize>]) {
        let k = self.v.len();
        let mut gram = DMatrix::zeros(k, k);
        for j in 0..k {
            if let Some(fj) = from[j] {
                for l in 0..k {
                    if let Some(fl) = from[l] {
                        gram[(j, l)] = self.gram[(fj, fl)];
                    }
                }
                continue;
            }
            for &(r, x) in &self.v[j] {
                self.scratch[r as usize] = x;
            }
            for l in 0..k {
                let d: f64 = self.v[l]
                    .iter()
                    .map(|&(r, x)| x * self.scratch[r as usize])
                    .sum();
                gram[(j, l)] = d;
                gram[(l, j)] = d;
            }
            for &(r, _) in &self.v[j] {
                self.scratch[r as usize] = 0.0;
            }
        }
        self.gram = gram;
    }

    /// `C^-1` from the products and the deltas; a singular `C` (the updated matrix is
    /// singular) clears every change.
    fn build_c(&mut self) -> Result<(), NotPositiveDefinite> {
        let mut c = self.gram.clone();
        for (j, d) in self.delta.iter().enumerate() {
            c[(j, j)] += 1.0 / d;
        }
        match c.try_inverse() {
            Some(inv) if inv.iter().all(|v| v.is_finite()) => {
                self.c_inv = inv;
                Ok(())
            }
            _ => {
                self.clear();
                Err(NotPositiveDefinite)
            }
        }
    }

    /// Turns `y = L^-1 P b` into `(I - V C^-1 V^T) y` (the rows of a solve between its sweeps:
    /// [`Cholesky::solve_with`]).
    pub fn correct(&self, y: &mut [Row]) {
        let k = self.index.len();
        if k == 0 {
            return;
        }
        let t: Vec<Row> = (self.v.iter())
            .map(|col| {
                let mut s = [0.0; 4];
                for &(r, x) in col {
                    (0..4).for_each(|a| s[a] += x * y[r as usize][a]);
                }
                s
            })
            .collect();
        for (j, col) in self.v.iter().enumerate() {
            let mut c = [0.0; 4];
            for (l, tl) in t.iter().enumerate() {
                let m = self.c_inv[(j, l)];
                (0..4).for_each(|a| c[a] += m * tl[a]);
            }
            for &(r, x) in col {
                (0..4).for_each(|a| y[r as usize][a] -= x * c[a]);
            }
        }
    }
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
        up.set(&chol, changes).unwrap();
        let mut x = b.clone();
        chol.solve_with(&mut x, |y| up.correct(y));
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
        // A larger grid: a supernodal factor, hundreds of changes.
        let many: Vec<(usize, f64)> = (0..300)
            .map(|k| (11 * k + 5, 3.0 - k as f64 * 0.02))
            .collect();
        let mut up = DiagonalUpdate::default();
        assert!(both(90, &many, &mut up) < 1e-12);
    }

    #[test]
    fn an_update_that_makes_the_matrix_singular_is_refused_and_leaves_no_change() {
        // A = 4 I (2 x 2): V = e_0 / 2, V^T V = 1/4; a change of -4 gives C = -1/4 + 1/4 = 0
        // exactly, and A' = diag(0, 4).
        let mut chol = Cholesky::analyse(2, &[(0, 0), (1, 1)]);
        chol.factor(&[4.0, 4.0]).unwrap();
        let mut up = DiagonalUpdate::default();
        up.set(&chol, &[(1, 5.0)]).unwrap();
        assert_eq!(up.len(), 1);
        assert_eq!(up.set(&chol, &[(0, -4.0)]), Err(NotPositiveDefinite));
        assert!(
            up.is_empty(),
            "a refused update leaves the factored matrix as it is"
        );
        // Saved products that do not fit the factor are refused the same way.
        let bad = crate::cloth::integrate::saved::UpdateKept {
            index: vec![7],
            delta: vec![1.0],
            gram: vec![0.25],
        };
        assert_eq!(up.restore(&chol, &bad), Err(NotPositiveDefinite));
        let singular = crate::cloth::integrate::saved::UpdateKept {
            index: vec![0],
            delta: vec![-4.0],
            gram: vec![0.25],
        };
        assert_eq!(up.restore(&chol, &singular), Err(NotPositiveDefinite));
        assert!(up.is_empty());
    }
}
