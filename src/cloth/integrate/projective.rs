//! Projective dynamics (`method.md` s. 6; Bouaziz et al. 2014): the backward Euler step as the
//! minimisation of
//!
//! `g(p) = sum_i m_i |p_i - y_i|^2 / (2 h^2) + sum_i c_i m_i |p_i - x_i|^2 / (2 h)
//!         + sum_springs k/2 |p_b - p_a - d|^2 + sum_bends c/2 |sum_k w_k p_k|^2`
//!
//! over the new positions `p` and the springs' projections `d` (`|d| = rest`), with
//! `y = x + h v + h^2 g` the inertial positions; the second term is the air damping, taken
//! implicitly. Minimised over `d` for fixed `p`, `g` is exactly the backward Euler objective.
//!
//! * **Local step**: every spring's `d` is the projection of `p_b - p_a` on its rest length
//!   (`Spring::project`), in parallel. The bending elements are quadratic: nothing to project.
//! * **Global step**: for fixed `d`, `g` is quadratic in `p`: solve
//!   `(M (1/h^2 + c/h) + sum k G_s + sum c w w^T) p = M y / h^2 + c M x / h + sum k G_s^T d`
//!   (`G_s p = p_b - p_a`). Pinned particles are not unknowns: their terms move to the right-hand
//!   side. The matrix does not change while the step and pins do not: it is factored once
//!   (sparse Cholesky, `faer`) when the solver is built, and x, y and z are solved in parallel.
//!
//! Each iteration never raises `g` (both steps minimise it exactly). **Chebyshev acceleration**
//! (Wang 2015) extrapolates the iterates with weights from an estimate `rho` of the plain
//! iteration's convergence rate: `p <- w (p - p_prev2) + p_prev2` with `w_1 = 1`,
//! `w_2 = 2 / (2 - rho^2)`, `w_k = 4 / (4 - rho^2 w_(k-1))`; it gives up monotonicity for speed.
//!
//! With few iterations a step can end with more energy than it began with; the velocities are
//! then scaled back (`energy_budget`), so the energy never grows beyond the work put in.
//!
//! **Contact as constraints.** Before the iterations, the particles in contact are those the
//! step began with and those whose inertial path meets a face (`speculate`, the paper's segment
//! test). Each gets the fourth paper's inequality constraint, the energy `w/2 |p - t|^2` with
//! `t` the projection of `p` on the half-space in front of its face at the thickness (so it
//! pushes, never pulls), and `w` as stiff as the springs at the particle ([`CONTACT_WEIGHT`]
//! times their sum). The local step projects, the global step sees `w` on the diagonal: the
//! matrix changes only when the set of particles in contact does, and is then refactored
//! numerically (the symbolic analysis is kept). Without it (contact found after the step only),
//! the particles that hit are held while their neighbours fall a whole step further, and a real
//! fabric's springs stretch far beyond what a few iterations recover.
//!
//! **Friction** acts after the iterations, with the contact force `w (t - p)` of each
//! constraint: its normal part gives the impulse `h f.n / m` of Coulomb's law (`coulomb`); a
//! particle the face does not push is released.

use super::{contact_friction, contact_normal, coulomb};
use super::{SolveStats, Solver, SolverSettings, StepIn, StepOut};
use crate::cloth::model::ClothModel;
use crate::cloth::state::Contact;
use crate::math::{Point3, Vec3};
use crate::par;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Side};
use rayon::prelude::*;

/// The contact weight relative to the sum of the spring constants at the particle.
pub const CONTACT_WEIGHT: f64 = 0.01;

/// Local/global projective dynamics with a prefactored global matrix.
pub struct ProjectiveDynamics {
    settings: SolverSettings,
    /// The particle of each unknown.
    particle: Vec<u32>,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    llt_symbolic: Option<SymbolicLlt<usize>>,
    /// The matrix's values without contacts, in the order of the pattern's pairs (the
    /// diagonal of unknown `u` first, at `u`).
    base: Vec<f64>,
    values: Vec<f64>,
    llt: Option<Llt<usize, f64>>,
    /// Per particle, the contact weight of the factored matrix.
    factored: Vec<f64>,
    /// Per particle, the contact weight of this step.
    weight: Vec<f64>,
    /// Per particle, the contact constraint's projection.
    target: Vec<Point3>,
    /// Per particle, the contact weight it would get (`CONTACT_WEIGHT` times its springs).
    stiffness: Vec<f64>,
    /// Right-hand side from the pinned particles (constant).
    pinned_rhs: Vec<Vec3>,
    /// Per spring, its projection.
    d: Vec<Vec3>,
    p: Vec<Point3>,
    prev: Vec<Point3>,
    prev2: Vec<Point3>,
    rhs: Mat<f64>,
    /// The contacts of the step.
    contact: Vec<Option<Contact>>,
    stats: SolveStats,
    /// When set, the objective after each iteration of the last step is recorded here (tests,
    /// the benchmark's convergence table).
    pub trace: Option<Vec<f64>>,
}

impl ProjectiveDynamics {
    /// Builds and factors the global matrix of `model` at step `settings.dt`, pinned particles at
    /// `x`.
    pub fn new(settings: &SolverSettings, model: &ClothModel, x: &[Point3]) -> ProjectiveDynamics {
        let start = std::time::Instant::now();
        let n = model.len();
        let h = settings.dt;
        let (index, particle) = model.free_unknowns();
        let nu = particle.len();
        let mut pairs: Vec<Pair<usize, usize>> = Vec::with_capacity(nu + 4 * model.springs.len());
        let mut base = Vec::with_capacity(pairs.capacity());
        let mut pinned_rhs = vec![Vec3::zeros(); n];
        let mut stiffness = vec![0.0; n];
        for (u, &i) in particle.iter().enumerate() {
            let i = i as usize;
            pairs.push(Pair::new(u, u));
            base.push(model.mass[i] * (1.0 / (h * h) + model.damping[i] / h));
        }
        // One linear element: weight w, nodes with coefficients (lower triangle only).
        let mut element = |nodes: &[(usize, f64)], w: f64| {
            for &(a, ca) in nodes {
                let ia = index[a];
                if ia == u32::MAX {
                    continue;
                }
                for &(b, cb) in nodes {
                    let ib = index[b];
                    if ib == u32::MAX {
                        pinned_rhs[a] -= x[b].coords * (w * ca * cb);
                    } else if ib <= ia {
                        pairs.push(Pair::new(ia as usize, ib as usize));
                        base.push(w * ca * cb);
                    }
                }
            }
        };
        for s in &model.springs {
            element(&[(s.a as usize, -1.0), (s.b as usize, 1.0)], s.k);
            stiffness[s.a as usize] += CONTACT_WEIGHT * s.k;
            stiffness[s.b as usize] += CONTACT_WEIGHT * s.k;
        }
        for e in 0..model.bends() {
            let (lo, hi) = (
                model.bend_start[e] as usize,
                model.bend_start[e + 1] as usize,
            );
            let nodes: Vec<(usize, f64)> = (lo..hi)
                .map(|k| (model.bend_nodes[k] as usize, model.bend_weights[k]))
                .collect();
            element(&nodes, model.bend_c[e]);
        }
        let (symbolic, argsort) =
            SymbolicSparseColMat::try_new_from_indices(nu, nu, &pairs).expect("valid indices");
        let llt_symbolic = (nu > 0).then(|| {
            SymbolicLlt::try_new(symbolic.as_ref(), Side::Lower).expect("symbolic Cholesky")
        });
        let mut pd = ProjectiveDynamics {
            settings: *settings,
            particle,
            symbolic,
            argsort,
            llt_symbolic,
            values: base.clone(),
            base,
            llt: None,
            factored: vec![0.0; n],
            weight: vec![0.0; n],
            target: vec![Point3::origin(); n],
            stiffness,
            pinned_rhs,
            d: vec![Vec3::zeros(); model.springs.len()],
            p: Vec::new(),
            prev: Vec::new(),
            prev2: Vec::new(),
            rhs: Mat::zeros(nu, 3),
            contact: Vec::new(),
            stats: SolveStats::default(),
            trace: None,
        };
        pd.factor();
        pd.stats.factor_seconds = start.elapsed().as_secs_f64();
        pd
    }

    /// Factors the matrix with the contact weights `weight` (numerically: the symbolic analysis
    /// is kept).
    fn factor(&mut self) {
        let Some(symbolic) = &self.llt_symbolic else {
            return;
        };
        self.values.clone_from(&self.base);
        for (u, &i) in self.particle.iter().enumerate() {
            self.values[u] += self.weight[i as usize];
        }
        let mat =
            SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, &self.values)
                .expect("the pattern's values");
        self.llt = Some(
            Llt::try_new_with_symbolic(symbolic.clone(), mat.as_ref(), Side::Lower)
                .expect("the global matrix is positive definite: masses are positive"),
        );
        self.factored.clone_from(&self.weight);
        self.stats.factorisations += 1;
    }

    /// The objective `g(p)` of the step (module notes), J.
    pub fn objective(input: &StepIn, p: &[Point3]) -> f64 {
        let StepIn {
            model, x, y, dt, ..
        } = *input;
        let inertia = par::sum(model.len(), |i| {
            if model.pinned(i) {
                return 0.0;
            }
            let m = model.mass[i];
            m * (p[i] - y[i]).norm_squared() / (2.0 * dt * dt)
                + model.damping[i] * m * (p[i] - x[i]).norm_squared() / (2.0 * dt)
        });
        inertia + crate::cloth::forces::spring_energy(model, p)
    }

    /// The local step: every spring's projection at `p`.
    fn local(&mut self, model: &ClothModel) {
        let p = &self.p;
        let proj = |(d, s): (&mut Vec3, &crate::cloth::elements::Spring)| {
            *d = s.project(&p[s.a as usize], &p[s.b as usize], None)
        };
        if par::parallel(model.springs.len()) {
            self.d.par_iter_mut().zip(&model.springs).for_each(proj);
        } else {
            self.d.iter_mut().zip(&model.springs).for_each(proj);
        }
    }

    /// The global step: `p` from the projections.
    fn global(&mut self, input: &StepIn) {
        let StepIn {
            model, x, y, dt, ..
        } = *input;
        let Some(llt) = &self.llt else { return };
        let d = &self.d;
        let rows: Vec<Vec3> = self
            .particle
            .par_iter()
            .map(|&i| {
                let i = i as usize;
                let m = model.mass[i];
                let mut r = y[i].coords * (m / (dt * dt))
                    + x[i].coords * (model.damping[i] * m / dt)
                    + self.pinned_rhs[i]
                    + self.target[i].coords * self.weight[i];
                for &(_, s) in
                    &model.adj[model.adj_start[i] as usize..model.adj_start[i + 1] as usize]
                {
                    let sp = &model.springs[s as usize];
                    let sign = if sp.a as usize == i { -1.0 } else { 1.0 };
                    r += d[s as usize] * (sp.k * sign);
                }
                r
            })
            .collect();
        for (u, r) in rows.iter().enumerate() {
            for c in 0..3 {
                self.rhs[(u, c)] = r[c];
            }
        }
        // x, y and z at once: the three columns are independent solves.
        let (c0, rest) = self.rhs.as_mut().split_at_col_mut(1);
        let (c1, c2) = rest.split_at_col_mut(1);
        [c0, c1, c2]
            .into_par_iter()
            .for_each(|c| llt.solve_in_place(c));
        for (u, &i) in self.particle.iter().enumerate() {
            self.p[i as usize] = Point3::new(self.rhs[(u, 0)], self.rhs[(u, 1)], self.rhs[(u, 2)]);
        }
    }
}

impl ProjectiveDynamics {
    /// The contacts of the step: those it began with, and those its inertial paths meet
    /// (`speculate`); their particles get their weights.
    fn begin_contacts(&mut self, input: &StepIn, start: &[Option<Contact>]) {
        let n = input.model.len();
        self.contact.clear();
        self.contact.extend_from_slice(start);
        super::speculate(input, &mut self.contact);
        for i in 0..n {
            self.weight[i] = if self.contact[i].is_some() {
                self.stiffness[i]
            } else {
                0.0
            };
        }
    }

    /// The local step of the contact constraints: each particle in contact projected on the
    /// half-space in front of its face, at the thickness.
    fn project_contacts(&mut self, input: &StepIn) {
        let StepIn {
            model, colliders, ..
        } = *input;
        for (i, c) in self.contact.iter().enumerate() {
            let Some(ct) = c else { continue };
            let (n, off) = colliders[ct.object as usize].plane(ct.face as usize);
            let d = ct.side * (self.p[i].coords.dot(&n) - off);
            let th = model.thickness[i];
            self.target[i] = if d < th {
                self.p[i] + n * (ct.side * (th - d))
            } else {
                self.p[i]
            };
        }
    }

    /// Coulomb friction from the force `w (t - p)` of each contact constraint at the end of the
    /// step (module notes); a contact that does not push is released.
    fn friction(&self, input: &StepIn, out: &mut StepOut) {
        let StepIn {
            model,
            x,
            colliders,
            dt,
            ..
        } = *input;
        let (p, t, w) = (&self.p, &self.target, &self.weight);
        par::for_chunks3(
            crate::sim::COLLISION_CHUNK,
            model.len(),
            &mut out.x[..],
            &mut out.v[..],
            &mut out.contact[..],
            |base, xs, vs, cs| {
                for k in 0..xs.len() {
                    let i = base + k;
                    let Some(ct) = cs[k] else { continue };
                    let n = contact_normal(colliders, &ct);
                    let fn_ = (t[i] - p[i]).dot(&n) * w[i];
                    if fn_ <= 0.0 {
                        cs[k] = None;
                        continue;
                    }
                    let m = model.mass[i];
                    let mu = contact_friction(colliders, model, &ct, i);
                    coulomb(&mut vs[k], &n, fn_ * dt / m, mu);
                    xs[k] = x[i] + vs[k] * dt;
                }
            },
        );
    }
}

/// The energy safeguard: a few iterations stop short of the minimum, and then the step can end
/// with more mechanical energy (kinetic + springs + gravity) than it began with. The velocities
/// are then scaled down so that the kinetic energy makes up no more than the difference (the
/// positions are kept). Converged steps never need it.
fn energy_budget(input: &StepIn, out: &mut StepOut) {
    use crate::cloth::forces::{gravity_energy, kinetic_energy, spring_energy};
    let StepIn { model, x, v, .. } = *input;
    let before = kinetic_energy(model, v) + spring_energy(model, x);
    let potential = spring_energy(model, out.x) + gravity_energy(model, out.x, x);
    let kinetic = kinetic_energy(model, out.v);
    if potential + kinetic <= before || kinetic == 0.0 {
        return;
    }
    let scale = ((before - potential).max(0.0) / kinetic).sqrt();
    for vi in out.v.iter_mut() {
        *vi *= scale;
    }
}

impl Solver for ProjectiveDynamics {
    fn step(&mut self, input: &StepIn, out: &mut StepOut) {
        let StepIn { model, x, dt, .. } = *input;
        // From the free flight `x + h v`, not from `y`: near a pin, `y`'s fall of `h^2 g` can
        // stretch the springs far more than the step ever will.
        self.p.clear();
        self.p.extend((0..model.len()).map(|i| {
            if model.pinned(i) {
                x[i]
            } else {
                x[i] + input.v[i] * dt
            }
        }));
        let touching = input.reach.iter().any(|&r| r);
        if touching {
            let start = out.contact.to_vec();
            self.begin_contacts(input, &start);
        } else {
            self.weight.iter_mut().for_each(|w| *w = 0.0);
        }
        if self.weight != self.factored {
            let t = std::time::Instant::now();
            self.factor();
            self.stats.factor_seconds += t.elapsed().as_secs_f64();
        }
        let iterations = self.settings.iterations.max(1);
        let rho = self.settings.chebyshev;
        let mut omega = 1.0;
        if let Some(t) = &mut self.trace {
            t.clear();
            t.push(Self::objective(input, &self.p));
        }
        for k in 0..iterations {
            if rho.is_some() {
                self.prev2.clone_from(&self.prev);
                self.prev.clone_from(&self.p);
            }
            self.local(model);
            if touching {
                self.project_contacts(input);
            }
            self.global(input);
            if let Some(rho) = rho {
                omega = match k {
                    0 => 1.0,
                    1 => 2.0 / (2.0 - rho * rho),
                    _ => 4.0 / (4.0 - rho * rho * omega),
                };
                if k > 0 {
                    for i in 0..model.len() {
                        self.p[i] = Point3::from(
                            (self.p[i] - self.prev2[i]) * omega + self.prev2[i].coords,
                        );
                    }
                }
            }
            self.stats.pd_iterations += 1;
            if self.trace.is_some() {
                let g = Self::objective(input, &self.p);
                if let Some(t) = &mut self.trace {
                    t.push(g);
                }
            }
        }
        for i in 0..model.len() {
            if model.pinned(i) {
                out.x[i] = x[i];
                out.v[i] = Vec3::zeros();
            } else {
                out.x[i] = self.p[i];
                out.v[i] = (self.p[i] - x[i]) / dt;
            }
        }
        if touching {
            self.project_contacts(input);
            out.contact.copy_from_slice(&self.contact);
            self.friction(input, out);
        } else {
            energy_budget(input, out);
        }
    }

    fn stats(&self) -> SolveStats {
        self.stats
    }
}
