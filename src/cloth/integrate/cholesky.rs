//! Sparse Cholesky `A = P^T L L^T P` with three right-hand sides solved together.
//!
//! The ordering, the symbolic analysis and the numeric factorisation are faer's (AMD ordering,
//! simplicial or supernodal as faer decides). The solves are ours: the global step of
//! projective dynamics solves for x, y and z with one matrix, and faer's supernodal solve spends
//! most of its time dispatching small dense kernels (a cloth's supernodes are a few columns
//! wide). Here the three coordinates of a row sit together (`[f64; 3]`), each entry of `L` is
//! read once per sweep for all three, and the loops are plain: forward `L z = P b`, then
//! backward `L^T w = z`, `x = P^T w`.
//!
//! ```
//! use drapekit::cloth::integrate::cholesky::Cholesky;
//! // A = [[4, 2], [2, 3]] (lower triangle), b = A [1, -1] per coordinate.
//! let mut c = Cholesky::analyse(2, &[(0, 0), (1, 0), (1, 1)]);
//! c.factor(&[4.0, 2.0, 3.0]).unwrap();
//! let mut b = [[2.0, 4.0, -2.0], [-1.0, 2.0, 1.0]];
//! c.solve(&mut b);
//! assert!((b[0][0] - 1.0).abs() < 1e-14 && (b[1][0] + 1.0).abs() < 1e-14);
//! assert!((b[0][1] - 1.0).abs() < 1e-14 && (b[1][1] - 0.0).abs() < 1e-14);
//! ```

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Par, Side};

/// The matrix is not positive definite (a pivot was not positive).
#[derive(Debug, thiserror::Error)]
#[error("the matrix is not positive definite")]
pub struct NotPositiveDefinite;

/// A symmetric positive definite pattern, analysed once, factored for each set of values.
pub struct Cholesky {
    /// The node of each column (`forward_unit`).
    node_of: Vec<u32>,
    pattern: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    symbolic: SymbolicCholesky<usize>,
    /// `L`'s values (faer's layout for the symbolic kind).
    l: Vec<f64>,
    mem: MemBuffer,
    /// The permuted right-hand side, a row per unknown (padded to four for vector units).
    work: Vec<[f64; 4]>,
}

impl Cholesky {
    /// Analyses the lower-triangle pattern `entries` (`(row, col)`, `row >= col`; repeats are
    /// summed) of an `n x n` matrix.
    pub fn analyse(n: usize, entries: &[(usize, usize)]) -> Cholesky {
        let pairs: Vec<Pair<usize, usize>> =
            entries.iter().map(|&(r, c)| Pair::new(r, c)).collect();
        let (pattern, argsort) =
            SymbolicSparseColMat::try_new_from_indices(n, n, &pairs).expect("valid indices");
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .expect("symbolic Cholesky");
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        Cholesky {
            node_of: node_of(&symbolic, n),
            l: vec![0.0; symbolic.len_val()],
            mem: MemBuffer::new(req),
            work: vec![[0.0; 4]; n],
            pattern,
            argsort,
            symbolic,
        }
    }

    /// Factors the matrix whose entries (in the order given to [`Cholesky::analyse`]) are
    /// `values`.
    pub fn factor(&mut self, values: &[f64]) -> Result<(), NotPositiveDefinite> {
        let a = SparseColMat::new_from_argsort(self.pattern.clone(), &self.argsort, values)
            .expect("the pattern's values");
        self.symbolic
            .factorize_numeric_llt(
                &mut self.l,
                a.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .map(|_| ())
            .map_err(|_| NotPositiveDefinite)
    }

    /// The number of unknowns.
    pub fn len(&self) -> usize {
        self.work.len()
    }

    /// Whether the matrix has no unknowns.
    pub fn is_empty(&self) -> bool {
        self.work.is_empty()
    }

    /// Solves `A x = b` in place for the three columns of `b`'s rows.
    pub fn solve(&mut self, b: &mut [[f64; 3]]) {
        self.solve_with(b, |_| {});
    }

    /// Solves `A x = b` with `mid` applied between the sweeps: to `y = L^-1 P b`, a row per
    /// unknown in the factor's order (padded to four). A low-rank update of the matrix is a
    /// change of `y` there (`lowrank`).
    pub fn solve_with(&mut self, b: &mut [[f64; 3]], mid: impl FnOnce(&mut [Row])) {
        let perm = self.symbolic.perm().map(|p| p.arrays());
        let work = &mut self.work;
        let pad = |r: &[f64; 3]| [r[0], r[1], r[2], 0.0];
        match perm {
            Some((fwd, _)) => work.iter_mut().zip(fwd).for_each(|(w, &f)| *w = pad(&b[f])),
            None => work.iter_mut().zip(b.iter()).for_each(|(w, r)| *w = pad(r)),
        }
        sweeps(self.symbolic.raw(), &self.l, work, Sweep::Forward);
        mid(work);
        sweeps(self.symbolic.raw(), &self.l, work, Sweep::Backward);
        let cut = |r: &[f64; 4]| [r[0], r[1], r[2]];
        match perm {
            Some((_, inv)) => b.iter_mut().zip(inv).for_each(|(x, &i)| *x = cut(&work[i])),
            None => b.iter_mut().zip(work.iter()).for_each(|(x, r)| *x = cut(r)),
        }
    }

    /// `L^-1 P e_u`, the forward sweep of unknown `u`'s unit vector, as `(row, value)` in the
    /// factor's order: non-zero only on the rows of the elimination tree's path from `u`'s
    /// column to the root, so it costs that path, not a solve. `scratch` holds `n` zeros and is
    /// left so.
    pub fn forward_unit(&self, u: usize, scratch: &mut [f64]) -> Vec<(u32, f64)> {
        let r0 = match self.symbolic.perm() {
            Some(p) => p.arrays().1[u],
            None => u,
        };
        scratch[r0] = 1.0;
        let mut out = Vec::new();
        let mut s = self.node_of[r0] as usize;
        loop {
            let (start, size, pattern, v) = self.node(s);
            let rows = size + pattern.len();
            for j in 0..size {
                let c = &v[j * rows..(j + 1) * rows];
                scratch[start + j] /= c[j];
                let xj = scratch[start + j];
                if xj == 0.0 {
                    continue;
                }
                for i in j + 1..size {
                    scratch[start + i] -= c[i] * xj;
                }
                for (k, &r) in pattern.iter().enumerate() {
                    scratch[r] -= c[size + k] * xj;
                }
            }
            for r in start..start + size {
                if scratch[r] != 0.0 {
                    out.push((r as u32, scratch[r]));
                    scratch[r] = 0.0;
                }
            }
            match pattern.first() {
                Some(&r) => s = self.node_of[r] as usize,
                None => return out,
            }
        }
    }

    /// Node `s` of the factor: its first column, its number of columns, the rows below them,
    /// and its values (column-major, the columns' triangle then the rows below). A simplicial
    /// factor's nodes are its columns.
    fn node(&self, s: usize) -> (usize, usize, &[usize], &[f64]) {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(f) => {
                let f = f.factor();
                let (lo, hi) = (f.col_ptr()[s], f.col_ptr()[s + 1]);
                (s, 1, &f.row_idx()[lo + 1..hi], &self.l[lo..hi])
            }
            SymbolicCholeskyRaw::Supernodal(sym) => {
                let start = sym.supernode_begin()[s];
                let size = sym.supernode_end()[s] - start;
                let vals = &self.l[sym.col_ptr_for_val()[s]..sym.col_ptr_for_val()[s + 1]];
                (start, size, sym.supernode(s).pattern(), vals)
            }
        }
    }
}

/// The node of each column of the factor (see [`Cholesky::node`]).
fn node_of(symbolic: &SymbolicCholesky<usize>, n: usize) -> Vec<u32> {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(_) => (0..n as u32).collect(),
        SymbolicCholeskyRaw::Supernodal(sym) => {
            let mut of = vec![0; n];
            for s in 0..sym.n_supernodes() {
                of[sym.supernode_begin()[s]..sym.supernode_end()[s]].fill(s as u32);
            }
            of
        }
    }
}

/// Which triangular sweep: `L z = b`, or `L^T x = z`.
#[derive(Clone, Copy, PartialEq)]
enum Sweep {
    Forward,
    Backward,
}

/// A row of the right-hand side in the sweeps: x, y, z and a zero (for vector units).
pub type Row = [f64; 4];

/// Both sweeps, with 256-bit vector instructions where the processor has them (the same
/// arithmetic either way: no fused multiply-adds).
fn sweeps(raw: &SymbolicCholeskyRaw<usize>, l: &[f64], x: &mut [Row], dir: Sweep) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the processor has AVX (checked just above).
        unsafe { sweeps_avx(raw, l, x, dir) };
        return;
    }
    sweeps_inline(raw, l, x, dir);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn sweeps_avx(raw: &SymbolicCholeskyRaw<usize>, l: &[f64], x: &mut [Row], dir: Sweep) {
    sweeps_inline(raw, l, x, dir);
}

#[inline(always)]
fn sweeps_inline(raw: &SymbolicCholeskyRaw<usize>, l: &[f64], x: &mut [Row], dir: Sweep) {
    match raw {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let f = s.factor();
            simplicial(f.col_ptr(), f.row_idx(), l, x, dir);
        }
        SymbolicCholeskyRaw::Supernodal(s) => supernodal(s, l, x, dir),
    }
}

#[inline(always)]
fn axpy(x: &mut Row, a: f64, y: &Row) {
    for k in 0..4 {
        x[k] -= a * y[k];
    }
}

#[inline(always)]
fn scale(x: &mut Row, d: f64) {
    let r = 1.0 / d;
    for v in x.iter_mut() {
        *v *= r;
    }
}

/// Both sweeps with a simplicial factor (each column's first entry is its diagonal).
#[inline(always)]
fn simplicial(col: &[usize], row: &[usize], l: &[f64], x: &mut [Row], dir: Sweep) {
    let n = x.len();
    if dir == Sweep::Forward {
        for j in 0..n {
            let (lo, hi) = (col[j], col[j + 1]);
            scale(&mut x[j], l[lo]);
            let xj = x[j];
            for p in lo + 1..hi {
                axpy(&mut x[row[p]], l[p], &xj);
            }
        }
        return;
    }
    for j in (0..n).rev() {
        let (lo, hi) = (col[j], col[j + 1]);
        let mut xj = x[j];
        for p in lo + 1..hi {
            axpy(&mut xj, l[p], &x[row[p]]);
        }
        scale(&mut xj, l[lo]);
        x[j] = xj;
    }
}

/// Both sweeps with a supernodal factor: supernode `s` holds columns `start..end` as a dense
/// column-major block of `end - start + |pattern|` rows (the triangle, then the pattern's rows).
#[inline(always)]
fn supernodal(
    sym: &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>,
    l: &[f64],
    x: &mut [Row],
    dir: Sweep,
) {
    let ns = sym.n_supernodes();
    let node = |s: usize| {
        let start = sym.supernode_begin()[s];
        let size = sym.supernode_end()[s] - start;
        let pattern = sym.supernode(s).pattern();
        let vals = &l[sym.col_ptr_for_val()[s]..sym.col_ptr_for_val()[s + 1]];
        (start, size, pattern, vals, size + pattern.len())
    };
    if dir == Sweep::Forward {
        for s in 0..ns {
            let (start, size, pattern, v, rows) = node(s);
            for j in 0..size {
                let c = &v[j * rows..(j + 1) * rows];
                scale(&mut x[start + j], c[j]);
                let xj = x[start + j];
                for i in j + 1..size {
                    axpy(&mut x[start + i], c[i], &xj);
                }
                for (k, &r) in pattern.iter().enumerate() {
                    axpy(&mut x[r], c[size + k], &xj);
                }
            }
        }
        return;
    }
    for s in (0..ns).rev() {
        let (start, size, pattern, v, rows) = node(s);
        for j in (0..size).rev() {
            let c = &v[j * rows..(j + 1) * rows];
            // Two sums: one dependency chain would wait on each addition.
            let (mut xj, mut odd) = (x[start + j], [0.0; 4]);
            let below = &c[size..];
            let pairs = pattern.len() / 2;
            for k in 0..pairs {
                axpy(&mut xj, below[2 * k], &x[pattern[2 * k]]);
                axpy(&mut odd, below[2 * k + 1], &x[pattern[2 * k + 1]]);
            }
            if pattern.len() % 2 == 1 {
                let k = pattern.len() - 1;
                axpy(&mut xj, below[k], &x[pattern[k]]);
            }
            for k in 0..4 {
                xj[k] += odd[k];
            }
            for i in j + 1..size {
                axpy(&mut xj, c[i], &x[start + i]);
            }
            scale(&mut xj, c[j]);
            x[start + j] = xj;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2-D grid Laplacian plus a diagonal: large enough for supernodes.
    fn grid(side: usize) -> (usize, Vec<(usize, usize)>, Vec<f64>) {
        let n = side * side;
        let (mut e, mut v) = (Vec::new(), Vec::new());
        for i in 0..side {
            for j in 0..side {
                let a = i * side + j;
                e.push((a, a));
                v.push(6.5 + (a % 7) as f64 * 0.1);
                for b in [a + 1, a + side, a + side + 1] {
                    let adjacent = (b == a + 1 && j + 1 < side)
                        || (b == a + side && i + 1 < side)
                        || (b == a + side + 1 && i + 1 < side && j + 1 < side);
                    if adjacent {
                        e.push((b, a));
                        v.push(-1.0 + (b % 3) as f64 * 0.1);
                    }
                }
            }
        }
        (n, e, v)
    }

    fn multiply(n: usize, e: &[(usize, usize)], v: &[f64], x: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let mut y = vec![[0.0; 3]; n];
        for (&(r, c), &a) in e.iter().zip(v) {
            for k in 0..3 {
                y[r][k] += a * x[c][k];
                if r != c {
                    y[c][k] += a * x[r][k];
                }
            }
        }
        y
    }

    #[test]
    fn solves_three_columns_of_a_grid_system() {
        // Small: a simplicial factor; large: a supernodal one. Both sweeps are checked.
        for (side, supernodal) in [(3, false), (128, true)] {
            let (n, e, v) = grid(side);
            let mut c = Cholesky::analyse(n, &e);
            let kind = matches!(c.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_));
            assert_eq!(kind, supernodal, "side {side}");
            c.factor(&v).unwrap();
            let x: Vec<[f64; 3]> = (0..n)
                .map(|i| [(i as f64).sin(), 1.0, (i % 5) as f64])
                .collect();
            let mut b = multiply(n, &e, &v, &x);
            c.solve(&mut b);
            let err = b
                .iter()
                .zip(&x)
                .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
                .fold(0.0, f64::max);
            assert!(err < 1e-12, "side {side}: error {err}");
        }
    }

    #[test]
    fn forward_unit_is_the_forward_sweep_of_a_unit_vector_along_a_path() {
        for side in [3, 128] {
            let (n, e, v) = grid(side);
            let mut c = Cholesky::analyse(n, &e);
            c.factor(&v).unwrap();
            let mut scratch = vec![0.0; n];
            for u in [0, n / 3, n - 1] {
                let sparse = c.forward_unit(u, &mut scratch);
                assert!(scratch.iter().all(|&x| x == 0.0), "scratch left as zeros");
                let mut b = vec![[0.0; 3]; n];
                b[u][1] = 1.0;
                let mut dense = Vec::new();
                c.solve_with(&mut b, |y| dense = y.iter().map(|r| r[1]).collect());
                let mut got = vec![0.0; n];
                sparse.iter().for_each(|&(r, x)| got[r as usize] = x);
                let err = (got.iter().zip(&dense)).fold(0.0, |m: f64, (a, b)| m.max((a - b).abs()));
                assert!(err < 1e-15, "side {side}, unknown {u}: error {err}");
                let nonzero = dense.iter().filter(|&&x| x != 0.0).count();
                assert_eq!(sparse.len(), nonzero, "side {side}, unknown {u}");
                if side == 128 {
                    eprintln!("unknown {u}: {} of {n} rows", sparse.len());
                    assert!(sparse.len() < n / 10, "a path, not the whole factor");
                }
            }
        }
    }

    #[test]
    fn refuses_an_indefinite_matrix() {
        let mut c = Cholesky::analyse(2, &[(0, 0), (1, 0), (1, 1)]);
        assert!(c.factor(&[1.0, 2.0, 1.0]).is_err());
    }
}
