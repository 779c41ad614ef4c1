//! The implicit Euler system `(M (1 + h c) + h^2 H) delta = rhs` solved directly: the 3x3-block
//! sparse matrix is assembled every Newton step and factored by sparse Cholesky (`faer`). Its
//! pattern never changes during a run (every spring and bending pair has its block, every free
//! particle its diagonal block), so the symbolic analysis (ordering, elimination tree) is done
//! once and each step only refactors the numbers.
//!
//! With [`BendingHessian::Lumped`] a bending element's pair `(a, b)` whose particles no spring
//! joins (two apart along a thread) has no block of its own: its `w I` (`w = c w_a w_b`) is
//! moved onto the two diagonal blocks as `|w| I` each. The difference from the exact matrix is
//! `|w| (e_a - s e_b)(e_a - s e_b)^T` (`s` the sign of `w`), positive semidefinite, so the
//! matrix stays positive definite and is at least the exact one: the step is a damped Newton
//! step on the same forces, with the same fixed points (states at rest), and the factor has no
//! fill from those pairs (about half the values on a garment).
//!
//! Pinned particles are not unknowns. A particle held on a face gets a stiff penalty
//! `kappa n n^T` on its diagonal block (`kappa` = [`PENALTY`] times the block's scale), which
//! keeps its normal motion within `1e-8` of zero relative to the tangential one: the direct
//! equivalent of the conjugate gradients' filter.

use super::NotPositiveDefinite;
use crate::cloth::model::ClothModel;
use crate::math::Vec3;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymbolicCholesky};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Conj, Mat, Side};
use nalgebra::Matrix3;
use serde::Serialize;

/// The contact penalty relative to the diagonal block's scale.
pub const PENALTY: f64 = 1e8;

/// How the direct solver takes the bending elements' Hessian (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BendingHessian {
    /// Every pair of an element's particles has its block: the linearised backward Euler step.
    #[default]
    Exact,
    /// The pairs no spring joins are moved onto their diagonal blocks (an upper bound).
    Lumped,
}

impl std::str::FromStr for BendingHessian {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "exact" => Ok(BendingHessian::Exact),
            "lumped" => Ok(BendingHessian::Lumped),
            _ => Err(format!(
                "unknown bending Hessian '{s}': expected 'exact' or 'lumped'"
            )),
        }
    }
}

impl std::fmt::Display for BendingHessian {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BendingHessian::Exact => "exact",
            BendingHessian::Lumped => "lumped",
        })
    }
}

/// Every pair `(e, k, j)` of a bending element `e`'s nodes (`k > j`, indices into
/// `bend_nodes`), element by element: the order of [`BlockSystem::visit`]'s bending blocks.
fn bend_pairs(model: &ClothModel) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
    (0..model.bends()).flat_map(move |e| {
        let (lo, hi) = (
            model.bend_start[e] as usize,
            model.bend_start[e + 1] as usize,
        );
        (lo..hi).flat_map(move |k| (lo..k).map(move |j| (e, k, j)))
    })
}

/// Per bending pair of `model`, in the order [`BlockSystem::visit`] meets them, whether it is
/// moved onto the diagonal (`Lumped`: no spring joins its particles). Empty for `Exact`.
fn lumped_pairs(model: &ClothModel, hessian: BendingHessian) -> Vec<bool> {
    if hessian == BendingHessian::Exact {
        return Vec::new();
    }
    let joined: std::collections::HashSet<(u32, u32)> = (model.springs.iter())
        .map(|s| (s.a.min(s.b), s.a.max(s.b)))
        .collect();
    bend_pairs(model)
        .map(|(_, k, j)| {
            let (a, b) = (model.bend_nodes[k], model.bend_nodes[j]);
            !joined.contains(&(a.min(b), a.max(b)))
        })
        .collect()
}

/// Where a block of the pattern comes from.
#[derive(Clone, Copy)]
enum Block {
    /// A particle's diagonal block.
    Diagonal(usize),
    /// A spring's off-diagonal block (its Hessian).
    Spring(usize),
    /// A bending pair's off-diagonal block, `c w_k w_j I`.
    Bend(f64),
}

/// The fixed pattern, its symbolic factorisation and the scratch of the values.
pub struct BlockSystem {
    /// Which analysis this is (a number no other `BlockSystem` of the process has): tells a
    /// kept analysis from a new one.
    serial: u64,
    hessian: BendingHessian,
    /// Per bending pair, whether it is lumped ([`lumped_pairs`]).
    lump: Vec<bool>,
    /// The blocks `(a, b)` of the pattern in visiting order: what a model must give to reuse
    /// this system (`fits`).
    blocks: Vec<(u32, u32)>,
    /// Unknown of each particle (`u32::MAX`: pinned).
    index: Vec<u32>,
    particles: Vec<u32>,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    /// The ordering and the factor's structure.
    llt_symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    /// The factor's values, refactored in place each step: a factor allocated afresh each
    /// step cost the pages' faults (a sixth of a `dress_pencil` drape's wall time).
    factor: Vec<f64>,
    /// The scratch of the factorisation and of the solve, kept for the same reason.
    scratch: MemBuffer,
    rhs: Mat<f64>,
}

/// Lower-triangle entries of the block `(a, b)` (`a >= b`), row-major in the block.
fn block_pairs(a: usize, b: usize, out: &mut Vec<Pair<usize, usize>>) {
    for r in 0..3 {
        for c in 0..3 {
            if a > b || r >= c {
                out.push(Pair::new(3 * a + r, 3 * b + c));
            }
        }
    }
}

/// Pushes the values of block `m` at `(a, b)` in the order of [`block_pairs`].
#[inline]
fn block_values(a: usize, b: usize, m: &Matrix3<f64>, out: &mut Vec<f64>) {
    for r in 0..3 {
        for c in 0..3 {
            if a > b || r >= c {
                out.push(m[(r, c)]);
            }
        }
    }
}

impl BlockSystem {
    /// The pattern of `model`'s implicit system, its bending Hessian taken as `hessian`.
    pub fn new(model: &ClothModel, hessian: BendingHessian) -> BlockSystem {
        let (index, particles) = model.free_unknowns();
        let mut pairs = Vec::new();
        let lump = lumped_pairs(model, hessian);
        let blocks = Self::blocks(model, &index, &particles, &lump);
        for &(a, b) in &blocks {
            block_pairs(a as usize, b as usize, &mut pairs);
        }
        let nu = 3 * particles.len();
        let (symbolic, argsort) =
            SymbolicSparseColMat::try_new_from_indices(nu, nu, &pairs).expect("valid indices");
        let llt_symbolic = factorize_symbolic_cholesky(
            symbolic.as_ref(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .expect("symbolic Cholesky");
        let par = faer::get_global_parallelism();
        let scratch = MemBuffer::new(
            llt_symbolic
                .factorize_numeric_llt_scratch::<f64>(par, Default::default())
                .or(llt_symbolic.solve_in_place_scratch::<f64>(1, par)),
        );
        static SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        BlockSystem {
            serial: SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            hessian,
            lump,
            blocks,
            factor: vec![0.0; llt_symbolic.len_val()],
            scratch,
            index,
            particles,
            symbolic,
            argsort,
            llt_symbolic,
            values: Vec::with_capacity(pairs.len()),
            rhs: Mat::zeros(nu, 1),
        }
    }

    /// The blocks of `model`'s pattern, in visiting order.
    fn blocks(
        model: &ClothModel,
        index: &[u32],
        particles: &[u32],
        lump: &[bool],
    ) -> Vec<(u32, u32)> {
        let mut blocks = Vec::new();
        Self::visit(model, index, particles, lump, |a, b, _| {
            blocks.push((a as u32, b as u32))
        });
        blocks
    }

    /// Which analysis this is (unique in the process).
    pub fn serial(&self) -> u64 {
        self.serial
    }

    /// Whether `model` with `hessian` has this system's pattern (the same particles joined and
    /// pinned; the constants may differ): then this analysis serves its solver too.
    pub fn fits(&self, model: &ClothModel, hessian: BendingHessian) -> bool {
        if hessian != self.hessian {
            return false;
        }
        // This system's lumped pairs serve: blocks equal to its own mean the same springs and
        // bending elements, hence the same pairs lumped (no set of springs rebuilt per check).
        let (index, particles) = model.free_unknowns();
        index == self.index && Self::blocks(model, &index, &particles, &self.lump) == self.blocks
    }

    /// Calls `f(a, b, block)` (unknowns, `a >= b`) for every block of the pattern, in a fixed
    /// order: diagonal blocks, then springs, then bending pairs (a lumped pair, `lump[p]`, as
    /// two diagonal blocks).
    fn visit(
        model: &ClothModel,
        index: &[u32],
        particles: &[u32],
        lump: &[bool],
        mut f: impl FnMut(usize, usize, Block),
    ) {
        for (u, &i) in particles.iter().enumerate() {
            f(u, u, Block::Diagonal(i as usize));
        }
        for (k, s) in model.springs.iter().enumerate() {
            let (a, b) = (index[s.a as usize], index[s.b as usize]);
            if a != u32::MAX && b != u32::MAX {
                f(a.max(b) as usize, a.min(b) as usize, Block::Spring(k));
            }
        }
        for (pair, (e, k, j)) in bend_pairs(model).enumerate() {
            let (a, b) = (
                index[model.bend_nodes[k] as usize],
                index[model.bend_nodes[j] as usize],
            );
            if a == u32::MAX || b == u32::MAX || a == b {
                continue;
            }
            let w = model.bend_c[e] * model.bend_weights[k] * model.bend_weights[j];
            if lump.get(pair).copied().unwrap_or(false) {
                f(a as usize, a as usize, Block::Bend(w.abs()));
                f(b as usize, b as usize, Block::Bend(w.abs()));
            } else {
                f(a.max(b) as usize, a.min(b) as usize, Block::Bend(w));
            }
        }
    }

    /// Assembles `diag[i] + h^2 (springs + bending)`, factors it and solves for `rhs`; `delta`
    /// gets the solution (zero for pinned particles). `diag` includes the masses, the bending
    /// diagonal and the contact penalties.
    pub fn solve(
        &mut self,
        model: &ClothModel,
        diag: &[Matrix3<f64>],
        hess: &[Matrix3<f64>],
        h2: f64,
        rhs: &[Vec3],
        delta: &mut [Vec3],
    ) -> Result<(), NotPositiveDefinite> {
        let vals = &mut self.values;
        vals.clear();
        Self::visit(
            model,
            &self.index,
            &self.particles,
            &self.lump,
            |a, b, block| {
                let m = match block {
                    Block::Diagonal(i) => diag[i],
                    Block::Spring(s) => hess[s] * -h2,
                    Block::Bend(w) => Matrix3::identity() * (h2 * w),
                };
                block_values(a, b, &m, vals);
            },
        );
        let particles = &self.particles;
        let mat = SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, vals)
            .expect("the pattern's values");
        // What `Llt::try_new_with_symbolic` and its solve do, in the kept buffers. The factor is
        // not cleared first: the supernodal factorisation clears it, the simplicial one writes
        // every value (the tests below compare the bits with faer's `Llt` after a factorisation
        // of other values, in both). The scratch was sized for faer's global parallelism when
        // the system was built; drapekit never changes it.
        let par = faer::get_global_parallelism();
        let llt = (self.llt_symbolic)
            .factorize_numeric_llt(
                &mut self.factor,
                mat.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut self.scratch),
                Default::default(),
            )
            .map_err(|_| NotPositiveDefinite)?;
        for (u, &i) in particles.iter().enumerate() {
            for c in 0..3 {
                self.rhs[(3 * u + c, 0)] = rhs[i as usize][c];
            }
        }
        llt.solve_in_place_with_conj(
            Conj::No,
            self.rhs.as_mut(),
            par,
            MemStack::new(&mut self.scratch),
        );
        for d in delta.iter_mut() {
            *d = Vec3::zeros();
        }
        for (u, &i) in particles.iter().enumerate() {
            delta[i as usize] = Vec3::new(
                self.rhs[(3 * u, 0)],
                self.rhs[(3 * u + 1, 0)],
                self.rhs[(3 * u + 2, 0)],
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::elements::Spring;
    use crate::cloth::fabric::Fabric;
    use crate::cloth::pattern::{build, Pins};
    use crate::math::{Point2, Point3};

    /// A square of cotton `half` m from its centre to a side, particles `spacing` apart, flat,
    /// pinned at one corner or free; its positions.
    fn sheet(half: f64, spacing: f64, pinned: bool) -> (ClothModel, Vec<Point3>) {
        let s = half;
        let outline = [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| Point2::new(x, y));
        let pins = if pinned {
            Pins::at(&[Point2::new(-s, s)])
        } else {
            Pins::default()
        };
        let fabric = Fabric::cotton();
        let p = build(&outline, spacing, &fabric, &pins).unwrap();
        let placed: Vec<Point3> = p.flat.iter().map(|q| Point3::new(q.x, q.y, 0.0)).collect();
        ClothModel::assemble(&[("square".into(), p, fabric, placed)], Vec3::zeros())
    }

    /// A 6 cm square at 2 cm.
    fn square(pinned: bool) -> ClothModel {
        sheet(0.03, 0.02, pinned).0
    }

    #[test]
    fn a_kept_factor_solves_to_the_bits_of_faers_own_cholesky() {
        // faer factors a small system simplicially and a large one by supernodes; in both, a
        // factorisation into the kept (not cleared) factor of an earlier one gives the bits of
        // a fresh `Llt`.
        use faer::linalg::solvers::Solve;
        use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
        use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
        for (half, supernodal) in [(0.03, false), (0.3, true)] {
            let (model, x) = sheet(half, 0.01, false);
            let mut sys = BlockSystem::new(&model, BendingHessian::Exact);
            let raw = sys.llt_symbolic.raw();
            assert_eq!(
                matches!(raw, SymbolicCholeskyRaw::Supernodal(_)),
                supernodal
            );
            let hess: Vec<Matrix3<f64>> = (model.springs.iter())
                .map(|s| s.hessian(&x[s.a as usize], &x[s.b as usize], true))
                .collect();
            let diag = vec![Matrix3::identity() * 1e3; model.len()];
            let rhs: Vec<Vec3> = (0..model.len())
                .map(|i| Vec3::new(1.0, -0.5, (i % 7) as f64 - 3.0))
                .collect();
            let mut delta = vec![Vec3::zeros(); model.len()];
            sys.solve(&model, &diag, &hess, 3e-4, &rhs, &mut delta)
                .unwrap();
            sys.solve(&model, &diag, &hess, 1e-4, &rhs, &mut delta)
                .unwrap();
            let mat =
                SparseColMat::new_from_argsort(sys.symbolic.clone(), &sys.argsort, &sys.values)
                    .unwrap();
            let symbolic = SymbolicLlt::try_new(sys.symbolic.as_ref(), Side::Lower).unwrap();
            let llt = Llt::try_new_with_symbolic(symbolic, mat.as_ref(), Side::Lower).unwrap();
            let mut b = Mat::<f64>::zeros(3 * model.len(), 1);
            for (u, &i) in sys.particles.iter().enumerate() {
                for c in 0..3 {
                    b[(3 * u + c, 0)] = rhs[i as usize][c];
                }
            }
            llt.solve_in_place(b.as_mut());
            for (u, &i) in sys.particles.iter().enumerate() {
                for c in 0..3 {
                    assert_eq!(delta[i as usize][c].to_bits(), b[(3 * u + c, 0)].to_bits());
                }
            }
        }
    }

    #[test]
    fn an_analysis_fits_a_model_joined_and_pinned_alike_whatever_its_constants() {
        let model = square(false);
        let sys = BlockSystem::new(&model, BendingHessian::Exact);
        assert!(sys.fits(&model, BendingHessian::Exact));
        // Other constants: the same pattern.
        let mut stiffer = model.clone();
        stiffer.springs.iter_mut().for_each(|s| s.k *= 10.0);
        assert!(sys.fits(&stiffer, BendingHessian::Exact));
        // One more spring, one spring joining other particles, a pinned corner: other patterns.
        let mut more = model.clone();
        let last = *more.springs.last().unwrap();
        more.springs.push(Spring { a: 0, b: 5, ..last });
        let mut moved = model.clone();
        let first = &mut moved.springs[0];
        first.b = if first.b == 5 { 6 } else { 5 };
        for other in [&more, &moved, &square(true)] {
            assert!(!sys.fits(other, BendingHessian::Exact));
        }
    }

    /// `x^T A x` of the symmetric matrix whose lower triangle the system last assembled.
    fn quadratic(sys: &BlockSystem, x: &[f64]) -> f64 {
        let mat = SparseColMat::new_from_argsort(sys.symbolic.clone(), &sys.argsort, &sys.values)
            .unwrap();
        let (col_ptr, row_idx, val) = (
            mat.symbolic().col_ptr(),
            mat.symbolic().row_idx(),
            mat.val(),
        );
        let mut q = 0.0;
        for c in 0..x.len() {
            for k in col_ptr[c]..col_ptr[c + 1] {
                let r = row_idx[k];
                q += if r == c { 1.0 } else { 2.0 } * val[k] * x[r] * x[c];
            }
        }
        q
    }

    #[test]
    fn lumped_bending_is_the_exact_matrix_plus_each_unjoined_pair_as_a_square_and_factors_smaller()
    {
        let (model, x) = sheet(0.05, 0.01, false);
        let hess: Vec<Matrix3<f64>> = (model.springs.iter())
            .map(|s| s.hessian(&x[s.a as usize], &x[s.b as usize], true))
            .collect();
        let h2 = 1e-4;
        // The diagonal blocks of M + h^2 (springs + bending), as implicit Euler's.
        let mut diag = vec![Matrix3::identity() * 1e-3; model.len()];
        for (s, h) in model.springs.iter().zip(&hess) {
            diag[s.a as usize] += h * h2;
            diag[s.b as usize] += h * h2;
        }
        for e in 0..model.bends() {
            for k in model.bend_start[e] as usize..model.bend_start[e + 1] as usize {
                let w = model.bend_weights[k];
                diag[model.bend_nodes[k] as usize] +=
                    Matrix3::identity() * (h2 * model.bend_c[e] * w * w);
            }
        }
        let rhs = vec![Vec3::new(0.0, 0.0, 1e-3); model.len()];
        let mut delta = vec![Vec3::zeros(); model.len()];
        let mut exact = BlockSystem::new(&model, BendingHessian::Exact);
        let mut lumped = BlockSystem::new(&model, BendingHessian::Lumped);
        for sys in [&mut exact, &mut lumped] {
            sys.solve(&model, &diag, &hess, h2, &rhs, &mut delta)
                .unwrap();
        }
        // Which pairs are lumped: those of no spring, each a pair two apart along a thread.
        let lump = lumped_pairs(&model, BendingHessian::Lumped);
        assert!(lump.iter().filter(|&&l| l).count() >= model.len());
        assert!(lump.len() > lump.iter().filter(|&&l| l).count());
        // Any x: x^T (A_lumped - A_exact) x = sum over lumped pairs of h^2 |w| |x_a - s x_b|^2.
        let mut rng = crate::math::SplitMix(7);
        for _ in 0..5 {
            let v: Vec<f64> = (0..3 * model.len()).map(|_| rng.next_f64() - 0.5).collect();
            let u = |n: u32| exact.index[n as usize] as usize;
            let mut expected = 0.0;
            for (pair, (e, k, j)) in bend_pairs(&model).enumerate() {
                if lump[pair] {
                    let w = model.bend_c[e] * model.bend_weights[k] * model.bend_weights[j];
                    let (a, b) = (u(model.bend_nodes[k]), u(model.bend_nodes[j]));
                    let d: f64 = (0..3)
                        .map(|c| (v[3 * a + c] - w.signum() * v[3 * b + c]).powi(2))
                        .sum();
                    expected += h2 * w.abs() * d;
                }
            }
            let got = quadratic(&lumped, &v) - quadratic(&exact, &v);
            assert!(expected > 0.0);
            assert!(
                (got - expected).abs() <= 1e-9 * expected,
                "{got} against {expected}"
            );
        }
        // Fewer blocks, a smaller factor, and neither analysis serves the other.
        let off = |sys: &BlockSystem| sys.blocks.iter().filter(|(a, b)| a != b).count();
        assert!(off(&lumped) < off(&exact));
        let (nl, ne) = (lumped.llt_symbolic.len_val(), exact.llt_symbolic.len_val());
        assert!((nl as f64) < 0.9 * ne as f64, "{nl} against {ne}");
        assert!(!exact.fits(&model, BendingHessian::Lumped));
        assert!(!lumped.fits(&model, BendingHessian::Exact));
        assert!(lumped.fits(&model, BendingHessian::Lumped));
    }
}
