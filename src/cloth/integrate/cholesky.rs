//! Sparse Cholesky `A = P^T L L^T P` with three right-hand sides solved together.
//!
//! The ordering, the symbolic analysis and the numeric factorisation are faer's (AMD ordering,
//! simplicial or supernodal as faer decides). The solves are ours: the global step of
//! projective dynamics solves for x, y and z with one matrix, and faer's supernodal solve spends
//! most of its time dispatching small dense kernels (a cloth's supernodes are a few columns
//! wide). Here the three coordinates of a row sit together (`[f64; 3]`), each entry of `L` is
//! read once per sweep for all three, and the loops are plain: forward `L z = P b`, then
//! backward `L^T w = z`, `x = P^T w`. A supernodal factor whose elimination tree splits into
//! two sets of subtrees of about equal work (`etree`) is swept on two threads: the subtrees at
//! once, then the rest (forward), or the rest, then the subtrees (backward); the same arithmetic
//! on one thread, so the solution does not depend on the thread count. On a 128 x 128 grid the
//! two threads' work is 0.53 of one thread's (test below).
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
use std::ops::Range;

use super::etree::{self, Split};

/// The matrix is not positive definite (a pivot was not positive).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
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
    /// Two subtrees swept at once (`etree`), and two rows per column of the rest.
    split: Option<Split>,
    buf: [Vec<Row>; 2],
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
        let split = split(&symbolic);
        let top = split.as_ref().map_or(0, |s| s.top_cols.len());
        Cholesky {
            split,
            buf: [vec![[0.0; 4]; top], vec![[0.0; 4]; top]],
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
        let (raw, l) = (self.symbolic.raw(), &self.l[..]);
        match (raw, &self.split) {
            (SymbolicCholeskyRaw::Supernodal(sym), Some(sp)) => {
                split_sweeps(sym, l, sp, work, &mut self.buf, Sweep::Forward);
                mid(work);
                split_sweeps(sym, l, sp, work, &mut self.buf, Sweep::Backward);
            }
            _ => {
                sweeps(raw, l, work, Sweep::Forward);
                mid(work);
                sweeps(raw, l, work, Sweep::Backward);
            }
        }
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
            SymbolicCholeskyRaw::Supernodal(sym) => supernode(sym, &self.l, s),
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

/// The split of a supernodal factor's elimination tree (`etree`), if one pays.
fn split(symbolic: &SymbolicCholesky<usize>) -> Option<Split> {
    let SymbolicCholeskyRaw::Supernodal(sym) = symbolic.raw() else {
        return None;
    };
    let ns = sym.n_supernodes();
    let mut begin: Vec<usize> = (0..ns).map(|s| sym.supernode_begin()[s]).collect();
    begin.push(if ns == 0 {
        0
    } else {
        sym.supernode_end()[ns - 1]
    });
    let of = node_of(symbolic, begin[ns]);
    let (mut parent, mut work) = (Vec::with_capacity(ns), Vec::with_capacity(ns));
    for s in 0..ns {
        let pattern = sym.supernode(s).pattern();
        let size = (begin[s + 1] - begin[s]) as f64;
        parent.push(pattern.first().map_or(etree::NONE, |&r| of[r]));
        work.push(size * (size + 1.0) / 2.0 + size * pattern.len() as f64);
    }
    Split::find(&parent, &work, &begin)
}

/// Which triangular sweep: `L z = b`, or `L^T x = z`.
#[derive(Clone, Copy, PartialEq)]
enum Sweep {
    Forward,
    Backward,
}

/// A row of the right-hand side in the sweeps: x, y, z and a zero (for vector units).
pub type Row = [f64; 4];

type Supernodal = faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>;

/// Both sweeps of a whole factor.
fn sweeps(raw: &SymbolicCholeskyRaw<usize>, l: &[f64], x: &mut [Row], dir: Sweep) {
    match raw {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let f = s.factor();
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx") {
                // SAFETY: the processor has AVX (checked just above).
                unsafe { simplicial_avx(f.col_ptr(), f.row_idx(), l, x, dir) };
                return;
            }
            simplicial(f.col_ptr(), f.row_idx(), l, x, dir);
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let nodes = 0..s.n_supernodes();
            match dir {
                Sweep::Forward => forward(s, l, nodes, Part::whole(x), &mut []),
                Sweep::Backward => backward(s, l, nodes, Part::whole(x), &[]),
            }
        }
    }
}

/// Both sweeps on two threads where the factor splits into subtrees (`etree`): the two
/// parts at once, the rest after them (forward) or before (backward). `buf` holds two rows per
/// column of the rest.
fn split_sweeps(
    sym: &Supernodal,
    l: &[f64],
    sp: &Split,
    x: &mut [Row],
    buf: &mut [Vec<Row>; 2],
    dir: Sweep,
) {
    let threads = crate::par::parallel(x.len());
    let [b0, b1] = buf;
    let parts = |k: usize| sp.parts[k].iter().zip(&sp.part_cols[k]);
    if dir == Sweep::Forward {
        b0.fill([0.0; 4]);
        b1.fill([0.0; 4]);
        let [x0, x1] = carve(x, &sp.part_cols);
        let run = |k: usize, xs: Vec<&mut [Row]>, out: &mut [Row]| {
            for ((nodes, cols), xk) in parts(k).zip(xs) {
                forward(sym, l, nodes.clone(), Part::at(xk, cols, sp), out);
            }
        };
        both(threads, || run(0, x0, b0), || run(1, x1, b1));
        for (k, &c) in sp.top_cols.iter().enumerate() {
            let row = &mut x[c as usize];
            for i in 0..4 {
                row[i] += b0[k][i];
                row[i] += b1[k][i];
            }
        }
        for r in &sp.top {
            forward(sym, l, r.clone(), Part::whole(x), &mut []);
        }
        return;
    }
    for r in sp.top.iter().rev() {
        backward(sym, l, r.clone(), Part::whole(x), &[]);
    }
    for (k, &c) in sp.top_cols.iter().enumerate() {
        b0[k] = x[c as usize];
    }
    let top = &b0[..];
    let [x0, x1] = carve(x, &sp.part_cols);
    let run = |k: usize, xs: Vec<&mut [Row]>| {
        for ((nodes, cols), xk) in parts(k).zip(xs) {
            backward(sym, l, nodes.clone(), Part::at(xk, cols, sp), top);
        }
    };
    both(threads, || run(0, x0), || run(1, x1));
}

/// Runs `a` and `b`, at once when `threads`.
fn both(threads: bool, a: impl FnOnce() + Send, b: impl FnOnce() + Send) {
    if threads {
        rayon::join(a, b);
    } else {
        a();
        b();
    }
}

/// The rows of each part's column ranges (disjoint), mutable at once, in the ranges' order.
fn carve<'x>(x: &'x mut [Row], cols: &[Vec<Range<usize>>; 2]) -> [Vec<&'x mut [Row]>; 2] {
    let mut order: Vec<(usize, usize)> = (0..2)
        .flat_map(|k| (0..cols[k].len()).map(move |i| (k, i)))
        .collect();
    order.sort_by_key(|&(k, i)| cols[k][i].start);
    let mut out: [Vec<Option<&mut [Row]>>; 2] = [
        (0..cols[0].len()).map(|_| None).collect(),
        (0..cols[1].len()).map(|_| None).collect(),
    ];
    let (mut rest, mut at) = (x, 0);
    for (k, i) in order {
        let r = &cols[k][i];
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(r.start - at);
        let (mid, tail) = tail.split_at_mut(r.len());
        out[k][i] = Some(mid);
        (rest, at) = (tail, r.end);
    }
    out.map(|v| {
        v.into_iter()
            .map(|s| s.expect("every range carved"))
            .collect()
    })
}

/// The rows a range of supernodes sweeps: its own columns `x` (the first is column `offset`);
/// a row beyond them is one of the rest's, at index `pos[row]` of a buffer.
struct Part<'x> {
    x: &'x mut [Row],
    offset: usize,
    pos: &'x [u32],
}

impl<'x> Part<'x> {
    /// The rows of columns `cols` of a part of `split`.
    fn at(x: &'x mut [Row], cols: &Range<usize>, split: &'x Split) -> Part<'x> {
        Part {
            x,
            offset: cols.start,
            pos: &split.top_pos,
        }
    }

    /// All the rows.
    fn whole(x: &'x mut [Row]) -> Part<'x> {
        Part {
            x,
            offset: 0,
            pos: &[],
        }
    }
}

/// The forward sweep of supernodes `nodes`, with 256-bit vector instructions where the
/// processor has them (the same arithmetic either way: no fused multiply-adds). Updates of
/// rows beyond the part go to `out`.
fn forward(sym: &Supernodal, l: &[f64], nodes: Range<usize>, p: Part, out: &mut [Row]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the processor has AVX (checked just above).
        unsafe { forward_avx(sym, l, nodes, p, out) };
        return;
    }
    forward_nodes(sym, l, nodes, p, out);
}

/// The backward sweep of supernodes `nodes` (as [`forward`]); rows beyond the part are read
/// from `top`.
fn backward(sym: &Supernodal, l: &[f64], nodes: Range<usize>, p: Part, top: &[Row]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the processor has AVX (checked just above).
        unsafe { backward_avx(sym, l, nodes, p, top) };
        return;
    }
    backward_nodes(sym, l, nodes, p, top);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn forward_avx(sym: &Supernodal, l: &[f64], nodes: Range<usize>, p: Part, out: &mut [Row]) {
    forward_nodes(sym, l, nodes, p, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn backward_avx(sym: &Supernodal, l: &[f64], nodes: Range<usize>, p: Part, top: &[Row]) {
    backward_nodes(sym, l, nodes, p, top);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn simplicial_avx(col: &[usize], row: &[usize], l: &[f64], x: &mut [Row], dir: Sweep) {
    simplicial(col, row, l, x, dir);
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

/// Supernode `s` of a supernodal factor: its first column, its number of columns, the rows
/// below them, and its values: a dense column-major block of `size + |pattern|` rows (the
/// triangle, then the pattern's rows).
#[inline(always)]
fn supernode<'l>(
    sym: &'l Supernodal,
    l: &'l [f64],
    s: usize,
) -> (usize, usize, &'l [usize], &'l [f64]) {
    let start = sym.supernode_begin()[s];
    let size = sym.supernode_end()[s] - start;
    let vals = &l[sym.col_ptr_for_val()[s]..sym.col_ptr_for_val()[s + 1]];
    (start, size, sym.supernode(s).pattern(), vals)
}

/// The forward sweep `L z = b` over supernodes `nodes` (see [`Part`]).
#[inline(always)]
fn forward_nodes(sym: &Supernodal, l: &[f64], nodes: Range<usize>, p: Part, out: &mut [Row]) {
    let (x, off, pos) = (p.x, p.offset, p.pos);
    let end = off + x.len();
    for s in nodes {
        let (start, size, pattern, v) = supernode(sym, l, s);
        let (start, rows) = (start - off, size + pattern.len());
        let inside = pattern.partition_point(|&r| r < end);
        let (near, far) = pattern.split_at(inside);
        for j in 0..size {
            let c = &v[j * rows..(j + 1) * rows];
            scale(&mut x[start + j], c[j]);
            let xj = x[start + j];
            for i in j + 1..size {
                axpy(&mut x[start + i], c[i], &xj);
            }
            let (cn, cf) = c[size..].split_at(inside);
            for (&a, &r) in cn.iter().zip(near) {
                axpy(&mut x[r - off], a, &xj);
            }
            for (&a, &r) in cf.iter().zip(far) {
                axpy(&mut out[pos[r] as usize], a, &xj);
            }
        }
    }
}

/// The backward sweep `L^T x = z` over supernodes `nodes`, last first (see [`Part`]).
#[inline(always)]
fn backward_nodes(sym: &Supernodal, l: &[f64], nodes: Range<usize>, p: Part, top: &[Row]) {
    let (x, off, pos) = (p.x, p.offset, p.pos);
    let end = off + x.len();
    for s in nodes.rev() {
        let (start, size, pattern, v) = supernode(sym, l, s);
        let (start, rows) = (start - off, size + pattern.len());
        let inside = pattern.partition_point(|&r| r < end);
        let (near, far) = pattern.split_at(inside);
        for j in (0..size).rev() {
            let c = &v[j * rows..(j + 1) * rows];
            let (cn, cf) = c[size..].split_at(inside);
            let mut xj = x[start + j];
            gather(&mut xj, cn, near, |r| &x[r - off]);
            gather(&mut xj, cf, far, |r| &top[pos[r] as usize]);
            for i in j + 1..size {
                axpy(&mut xj, c[i], &x[start + i]);
            }
            scale(&mut xj, c[j]);
            x[start + j] = xj;
        }
    }
}

/// `acc -= sum_k coef[k] row(rows[k])`, in two sums (one dependency chain would wait on each
/// addition).
#[inline(always)]
fn gather<'r>(acc: &mut Row, coef: &[f64], rows: &[usize], row: impl Fn(usize) -> &'r Row) {
    let mut odd = [0.0; 4];
    let pairs = rows.len() / 2;
    for k in 0..pairs {
        axpy(acc, coef[2 * k], row(rows[2 * k]));
        axpy(&mut odd, coef[2 * k + 1], row(rows[2 * k + 1]));
    }
    if rows.len() % 2 == 1 {
        let k = rows.len() - 1;
        axpy(acc, coef[k], row(rows[k]));
    }
    for k in 0..4 {
        acc[k] += odd[k];
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
    fn a_grid_factor_sweeps_two_subtrees_at_once_to_the_same_bits_on_any_thread_count() {
        let (n, e, v) = grid(128);
        let mut c = Cholesky::analyse(n, &e);
        let sp = c.split.clone().expect("a grid's factor splits");
        let total: f64 = {
            let mut whole = Cholesky::analyse(n, &e);
            whole.split = None;
            whole.factor(&v).unwrap();
            let x: Vec<[f64; 3]> = (0..n).map(|i| [(i as f64).cos(), -1.0, 0.5]).collect();
            let mut b = multiply(n, &e, &v, &x);
            whole.solve(&mut b);
            // Unsplit, the same solution (to rounding: the sums of the rest's rows differ).
            c.factor(&v).unwrap();
            let mut b2 = multiply(n, &e, &v, &x);
            c.solve(&mut b2);
            let diff = (b.iter().zip(&b2))
                .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
                .fold(0.0, f64::max);
            assert!(diff < 1e-12, "split against whole: {diff}");
            assert!(diff > 0.0 || sp.top_cols.is_empty(), "the split path ran");
            let SymbolicCholeskyRaw::Supernodal(sym) = c.symbolic.raw() else {
                unreachable!()
            };
            (0..sym.n_supernodes())
                .map(|s| {
                    let size = (sym.supernode_end()[s] - sym.supernode_begin()[s]) as f64;
                    size * (size + 1.0) / 2.0 + size * sym.supernode(s).pattern().len() as f64
                })
                .sum()
        };
        eprintln!(
            "split: {} and {} of {n} columns, {} in the rest; cost {:.3} of the serial work",
            sp.part_cols[0].iter().map(|r| r.len()).sum::<usize>(),
            sp.part_cols[1].iter().map(|r| r.len()).sum::<usize>(),
            sp.top_cols.len(),
            sp.cost / total
        );
        assert!(sp.cost <= (1.0 - etree::MIN_SAVING) * total);
        let cols = |k: usize| sp.part_cols[k].iter().map(|r| r.len()).sum::<usize>();
        assert!(cols(0).min(cols(1)) > n / 5, "both parts substantial");
        let mut solve_on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let x: Vec<[f64; 3]> = (0..n).map(|i| [(i as f64).sin(), 2.0, 1.5]).collect();
            let mut b = multiply(n, &e, &v, &x);
            pool.install(|| c.solve(&mut b));
            b
        };
        assert_eq!(solve_on(1), solve_on(2));
    }

    #[test]
    fn refuses_an_indefinite_matrix() {
        let mut c = Cholesky::analyse(2, &[(0, 0), (1, 0), (1, 1)]);
        assert!(c.factor(&[1.0, 2.0, 1.0]).is_err());
    }
}
