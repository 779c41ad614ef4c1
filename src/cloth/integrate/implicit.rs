//! Implicit (backward) Euler, solved as Baraff and Witkin (1998) do.
//!
//! The step solves `M (v+ - v) = h F(x + h v+, v+)` for `v+`, with `F` the springs, bending,
//! gravity and air damping `-c M v`. In the position change `dx = h v+`, Newton's method from
//! `dx = 0` takes steps `delta`:
//!
//! `(M (1 + h c) + h^2 H) delta = h^2 F(x + dx, dx / h) - M (dx - h v)`
//!
//! with `H` the Hessian of the springs and bending (the springs' kept positive semi-definite:
//! a compressed spring loses its negative transverse part). The first step is Baraff and
//! Witkin's linearised step `(M - h df/dv - h^2 df/dx) dv = h (f + h df/dx v)`, exactly; more
//! (`newton_iterations`) converge to the backward Euler step, the accuracy reference.
//!
//! Each linear system is solved by sparse Cholesky (`direct`, the default: the pattern is
//! analysed once, the numbers refactored each Newton step) or by conjugate gradients (`cg`),
//! matrix-free, with the inverse 3x3 diagonal blocks as preconditioner (cheap per iteration, but
//! a real fabric at a large step needs hundreds of iterations). Pinned particles are fixed unknowns (`delta = 0`). A
//! particle sliding on a face (`Contact`) is constrained to the face's plane (filter
//! `I - n n^T`): it neither sinks in nor lifts off during the solve. The constraint's force is
//! what the filtered residual leaves: if it pulls the particle toward the face, the contact
//! ends.
//!
//! **Friction is inside the solve**, so that the springs see it. A sliding particle gets the
//! kinetic friction force `-mu F_n t` (`t` its direction of slip, `F_n` the face's normal force
//! at the end of the last step, or the external force pressing a new contact on the face). A
//! sliding particle that friction stopped (its slip reversed, or was below `mu F_n h / m`)
//! loses what is left of its tangential velocity and sticks: in the next steps it is a fixed
//! unknown, until the constraint's tangential force exceeds `mu F_n` and it slides again.
//! Taken from the velocities after the solve instead, friction held particles the springs had
//! moved, and at real stiffness added far more spring energy than the kinetic energy it took:
//! real cotton landing on a sphere with friction 0.5 went unstable within 0.6 s.

use super::cg::{self, Filter, Scratch};
use super::direct::{BlockSystem, PENALTY};
use super::saved::{ImplicitKept, Kept, SolverState};
use super::{
    contact_friction, contact_normal, SolveStats, Solver, SolverSettings, StepIn, StepOut,
};
use super::{Analysis, LinearSolver, NotPositiveDefinite};
use crate::cloth::elements::bend;
use crate::cloth::forces;
use crate::cloth::model::ClothModel;
use crate::math::{Point3, Vec3};
use crate::par;
use nalgebra::Matrix3;
use rayon::prelude::*;

/// Backward Euler by Newton steps and preconditioned conjugate gradients.
pub struct ImplicitEuler {
    settings: SolverSettings,
    /// Per spring, its Hessian block at the current iterate.
    hess: Vec<Matrix3<f64>>,
    /// Per particle, the diagonal block.
    diag: Vec<Matrix3<f64>>,
    /// Per particle, the inverse diagonal block.
    precond: Vec<Matrix3<f64>>,
    /// The direct solver's pattern and factorisation (with `LinearSolver::Cholesky`).
    direct: Option<BlockSystem>,
    filter: Vec<Filter>,
    /// Per particle in contact: held by static friction this step (fixed in every direction).
    stuck: Vec<bool>,
    /// Per particle in contact: the face's normal force at the end of the last step, N.
    normal_force: Vec<f64>,
    /// Per particle: the direction of kinetic friction when it has no tangential velocity to
    /// oppose (it just broke free: the direction of the force that had held it).
    slip_dir: Vec<Vec3>,
    /// Per particle: the kinetic friction force of this step, N.
    fric: Vec<Vec3>,
    dx: Vec<Vec3>,
    xk: Vec<Point3>,
    rhs: Vec<Vec3>,
    delta: Vec<Vec3>,
    /// Per bending element, its vector of the CG direction (scratch of the product).
    bend_y: Vec<Vec3>,
    scratch: Scratch,
    stats: SolveStats,
}

impl ImplicitEuler {
    /// A solver for `model`, with the direct solver's analysis from `analysis` when it fits.
    pub fn new(
        settings: &SolverSettings,
        model: &ClothModel,
        analysis: &mut Analysis,
    ) -> ImplicitEuler {
        let n = model.len();
        ImplicitEuler {
            settings: *settings,
            hess: vec![Matrix3::zeros(); model.springs.len()],
            diag: vec![Matrix3::zeros(); n],
            precond: vec![Matrix3::zeros(); n],
            direct: (settings.linear_solver == LinearSolver::Cholesky).then(|| {
                (analysis.direct.take())
                    .filter(|sys| sys.fits(model, settings.bending_hessian))
                    .unwrap_or_else(|| BlockSystem::new(model, settings.bending_hessian))
            }),
            filter: vec![Filter::Free; n],
            stuck: vec![false; n],
            normal_force: vec![0.0; n],
            slip_dir: vec![Vec3::zeros(); n],
            fric: vec![Vec3::zeros(); n],
            dx: vec![Vec3::zeros(); n],
            xk: Vec::new(),
            rhs: vec![Vec3::zeros(); n],
            delta: vec![Vec3::zeros(); n],
            bend_y: vec![Vec3::zeros(); model.bends()],
            scratch: Scratch::default(),
            stats: SolveStats::default(),
        }
    }
}

/// `out = A y` with `A = diag(a) + h^2 H`: `a[i] = m_i (1 + h c_i)`.
fn multiply(
    model: &ClothModel,
    hess: &[Matrix3<f64>],
    bend_y: &mut [Vec3],
    h2: f64,
    dt: f64,
    y: &[Vec3],
    out: &mut [Vec3],
) {
    par::for_chunks(256, bend_y, |base, bs| {
        for (k, b) in bs.iter_mut().enumerate() {
            let e = base + k;
            let (lo, hi) = (
                model.bend_start[e] as usize,
                model.bend_start[e + 1] as usize,
            );
            *b = model.bend_nodes[lo..hi]
                .iter()
                .zip(&model.bend_weights[lo..hi])
                .fold(Vec3::zeros(), |acc, (&v, &w)| acc + y[v as usize] * w);
        }
    });
    let bend_y = &*bend_y;
    par::for_chunks(256, out, |base, os| {
        for (k, o) in os.iter_mut().enumerate() {
            let i = base + k;
            let mut acc = Vec3::zeros();
            for &(j, s) in &model.adj[model.adj_start[i] as usize..model.adj_start[i + 1] as usize]
            {
                acc += hess[s as usize] * (y[i] - y[j as usize]);
            }
            for &(e, w) in &model.bend_adj
                [model.bend_adj_start[i] as usize..model.bend_adj_start[i + 1] as usize]
            {
                acc += bend_y[e as usize] * (model.bend_c[e as usize] * w);
            }
            *o = y[i] * (model.mass[i] * (1.0 + dt * model.damping[i])) + acc * h2;
        }
    });
}

impl ImplicitEuler {
    /// Spring Hessians at `xk` and the inverse diagonal blocks.
    fn linearise(&mut self, model: &ClothModel, h2: f64, dt: f64) {
        let xk = &self.xk;
        let par_springs = par::parallel(model.springs.len());
        let blocks = |s: &crate::cloth::elements::Spring| {
            s.hessian(&xk[s.a as usize], &xk[s.b as usize], true)
        };
        if par_springs {
            self.hess
                .par_iter_mut()
                .zip(&model.springs)
                .for_each(|(h, s)| *h = blocks(s));
        } else {
            self.hess
                .iter_mut()
                .zip(&model.springs)
                .for_each(|(h, s)| *h = blocks(s));
        }
        let hess = &self.hess;
        par::for_chunks3(
            256,
            model.len(),
            &mut self.diag[..],
            &mut self.precond[..],
            &mut self.filter[..],
            |base, ds, ps, fs| {
                for (k, p) in ps.iter_mut().enumerate() {
                    let i = base + k;
                    let mut d =
                        Matrix3::identity() * (model.mass[i] * (1.0 + dt * model.damping[i]));
                    for &(_, s) in
                        &model.adj[model.adj_start[i] as usize..model.adj_start[i + 1] as usize]
                    {
                        d += hess[s as usize] * h2;
                    }
                    for &(e, w) in &model.bend_adj
                        [model.bend_adj_start[i] as usize..model.bend_adj_start[i + 1] as usize]
                    {
                        d += Matrix3::identity()
                            * (h2 * bend::hessian(model.bend_c[e as usize], w, w));
                    }
                    // Only the direct solver reads it: the penalty that holds the particle on its
                    // face (or, stuck, where it is; pinned particles are not its unknowns).
                    ds[k] = match fs[k] {
                        Filter::Plane(nrm) => {
                            d + nrm * nrm.transpose() * (PENALTY * d.trace() / 3.0)
                        }
                        Filter::Fixed => d + Matrix3::identity() * (PENALTY * d.trace() / 3.0),
                        Filter::Free => d,
                    };
                    *p = d.try_inverse().unwrap_or_else(Matrix3::identity);
                }
            },
        );
    }
}

impl ImplicitEuler {
    /// The iterate `xk = x + dx` and the right-hand side of Newton step `it` (its `delta`
    /// zeroed after the first: the first starts from the warm start).
    fn newton_rhs(&mut self, input: &StepIn, it: u32) {
        let StepIn {
            model,
            x,
            v,
            f_ext,
            dt,
            ..
        } = *input;
        let h2 = dt * dt;
        self.xk.clear();
        self.xk.extend(x.iter().zip(&self.dx).map(|(p, d)| p + d));
        if it > 0 {
            self.delta.iter_mut().for_each(|d| *d = Vec3::zeros());
        }
        let (xk, dx, fric) = (&self.xk, &self.dx, &self.fric);
        par::for_chunks(256, &mut self.rhs, |base, rs| {
            for (k, r) in rs.iter_mut().enumerate() {
                let i = base + k;
                let m = model.mass[i];
                let f = forces::add_internal(
                    model,
                    xk,
                    i,
                    f_ext[i] + fric[i] - dx[i] * (model.damping[i] * m / dt),
                );
                *r = f * h2 - (dx[i] - v[i] * dt) * m;
            }
        });
    }

    /// Solves the linearised system of the Newton step for `delta` (filtered), by the direct
    /// solver or by conjugate gradients; `A delta`.
    fn newton_delta(
        &mut self,
        model: &ClothModel,
        h2: f64,
        dt: f64,
    ) -> Result<Vec<Vec3>, NotPositiveDefinite> {
        self.linearise(model, h2, dt);
        let (hess, bend_y) = (
            &self.hess,
            std::sync::Mutex::new(std::mem::take(&mut self.bend_y)),
        );
        let mul = |y: &[Vec3], o: &mut [Vec3]| {
            let mut b = bend_y.lock().unwrap();
            multiply(model, hess, &mut b, h2, dt, y, o)
        };
        let res = match &mut self.direct {
            Some(sys) => {
                let t = std::time::Instant::now();
                sys.solve(model, &self.diag, hess, h2, &self.rhs, &mut self.delta)?;
                for (d, f) in self.delta.iter_mut().zip(&self.filter) {
                    *d = f.apply(*d);
                }
                self.stats.factor_seconds += t.elapsed().as_secs_f64();
                self.stats.factorisations += 1;
                cg::CgResult {
                    iterations: 0,
                    converged: true,
                }
            }
            None => cg::solve(
                &mul,
                &self.rhs,
                &self.precond,
                &self.filter,
                &mut self.delta,
                self.settings.cg_tolerance,
                self.settings.cg_max_iterations,
                &mut self.scratch,
            ),
        };
        self.stats.cg_iterations += res.iterations as u64;
        let mut ad = vec![Vec3::zeros(); model.len()];
        mul(&self.delta, &mut ad);
        self.bend_y = bend_y.into_inner().unwrap();
        Ok(ad)
    }
}

impl Solver for ImplicitEuler {
    fn step(&mut self, input: &StepIn, out: &mut StepOut) -> Result<(), NotPositiveDefinite> {
        let StepIn { model, v, dt, .. } = *input;
        let n = model.len();
        let h2 = dt * dt;
        for i in 0..n {
            self.filter[i] = self.constrain(input, out, i);
            self.dx[i] = Vec3::zeros();
            // Warm start: the motion of the last step.
            self.delta[i] = v[i] * dt;
        }
        for it in 0..self.settings.newton_iterations.max(1) {
            self.newton_rhs(input, it);
            // The constraint force of particles on a face: A delta - rhs along n, over h^2.
            let mut ad = self.newton_delta(model, h2, dt)?;
            let alpha = self.line_search(input);
            for i in 0..n {
                self.delta[i] *= alpha;
                self.dx[i] += self.delta[i];
                // Kept in ad for the friction below: the constraint's force, N.
                ad[i] = (ad[i] - self.rhs[i]) / h2;
            }
            if it + 1 == self.settings.newton_iterations.max(1) {
                self.finish(input, out, &ad);
            }
        }
        Ok(())
    }

    fn stats(&self) -> SolveStats {
        self.stats
    }

    fn save(&self) -> SolverState {
        SolverState {
            stats: self.stats,
            kept: Kept::Implicit(ImplicitKept {
                stuck: self.stuck.clone(),
                normal_force: self.normal_force.clone(),
                slip_dir: self.slip_dir.clone(),
            }),
        }
    }

    fn restore(&mut self, state: &SolverState) {
        let Kept::Implicit(k) = &state.kept else {
            panic!("not an implicit Euler solver's state");
        };
        let n = self.stuck.len();
        assert!(k.stuck.len() == n && k.normal_force.len() == n && k.slip_dir.len() == n);
        self.stuck.clone_from(&k.stuck);
        self.normal_force.clone_from(&k.normal_force);
        self.slip_dir.clone_from(&k.slip_dir);
        self.stats = state.stats;
    }

    fn hand_over(&mut self, analysis: &mut Analysis) {
        analysis.direct = self.direct.take();
    }
}

impl ImplicitEuler {
    /// The incremental potential of a position change `dx` (its gradient is `-rhs / h^2`):
    /// `sum m |dx - h v|^2 / (2 h^2) + c m |dx|^2 / (2 h) - f_ext . dx + U(x + dx)`, J.
    fn potential(&mut self, input: &StepIn, dx: &[Vec3]) -> f64 {
        let StepIn {
            model,
            x,
            v,
            f_ext,
            dt,
            ..
        } = *input;
        let fric = &self.fric;
        self.xk.clear();
        self.xk.extend(x.iter().zip(dx).map(|(p, d)| p + d));
        par::sum(model.len(), |i| {
            if model.pinned(i) {
                return 0.0;
            }
            let m = model.mass[i];
            m * (dx[i] - v[i] * dt).norm_squared() / (2.0 * dt * dt)
                + model.damping[i] * m * dx[i].norm_squared() / (2.0 * dt)
                - (f_ext[i] + fric[i]).dot(&dx[i])
        }) + forces::spring_energy(model, &self.xk)
    }

    /// Backtracking on the Newton step `delta` from `dx`: the largest of 1, 1/2, ..., 1/64 that
    /// does not raise the incremental potential (a linearised step on a stiff, strongly
    /// deformed cloth can overshoot; converged backward Euler never does).
    fn line_search(&mut self, input: &StepIn) -> f64 {
        let dx = std::mem::take(&mut self.dx);
        let e0 = self.potential(input, &dx);
        let mut alpha = 1.0;
        let mut trial: Vec<Vec3> = Vec::with_capacity(dx.len());
        loop {
            trial.clear();
            trial.extend(dx.iter().zip(&self.delta).map(|(d, s)| d + s * alpha));
            let e = self.potential(input, &trial);
            if e <= e0 + 1e-12 * e0.abs() || alpha <= 1.0 / 64.0 {
                break;
            }
            alpha *= 0.5;
        }
        self.dx = dx;
        alpha
    }

    /// The constraint of particle `i` this step (module notes): none, pinned, held where it is
    /// by static friction, or sliding on its face with kinetic friction (set in `fric`) from
    /// the last step's normal force.
    fn constrain(&mut self, input: &StepIn, out: &StepOut, i: usize) -> Filter {
        let StepIn {
            model,
            v,
            f_ext,
            colliders,
            ..
        } = *input;
        self.fric[i] = Vec3::zeros();
        if model.pinned(i) {
            return Filter::Fixed;
        }
        let Some(ct) = out.contact[i] else {
            self.stuck[i] = false;
            self.normal_force[i] = 0.0;
            return Filter::Free;
        };
        if self.stuck[i] {
            return Filter::Fixed;
        }
        let nrm = contact_normal(colliders, &ct);
        let vt = v[i] - nrm * v[i].dot(&nrm);
        let mu = contact_friction(colliders, model, &ct, i);
        // A new contact's normal force: the external force pressing it on the face.
        if self.normal_force[i] == 0.0 {
            self.normal_force[i] = (-f_ext[i].dot(&nrm)).max(0.0);
        }
        let cut = mu * self.normal_force[i];
        let dir = vt.try_normalize(0.0).map_or(self.slip_dir[i], |t| -t);
        self.fric[i] = dir * cut;
        Filter::Plane(nrm)
    }

    /// New state from the position change; contacts released, stuck or sliding as Coulomb's
    /// law says with the constraint's force `contact_force`.
    fn finish(&mut self, input: &StepIn, out: &mut StepOut, contact_force: &[Vec3]) {
        let StepIn {
            model,
            x,
            colliders,
            dt,
            ..
        } = *input;
        for i in 0..model.len() {
            if model.pinned(i) {
                out.x[i] = x[i];
                out.v[i] = Vec3::zeros();
                continue;
            }
            let mut vi = self.dx[i] / dt;
            if let Some(ct) = out.contact[i] {
                let nrm = contact_normal(colliders, &ct);
                let fc = contact_force[i];
                let fn_ = fc.dot(&nrm);
                let mu = contact_friction(colliders, model, &ct, i);
                if fn_ < 0.0 {
                    out.contact[i] = None;
                    self.stuck[i] = false;
                    self.normal_force[i] = 0.0;
                } else if self.stuck[i] {
                    // Held: it breaks free next step when friction could not have held it.
                    let ft = fc - nrm * fn_;
                    if ft.norm() > mu * fn_ {
                        self.stuck[i] = false;
                        self.slip_dir[i] = ft.normalize();
                    }
                    self.normal_force[i] = fn_;
                } else {
                    // Sliding: it sticks when kinetic friction stopped it (or would within a
                    // step); the velocity loses what is left, the position stays the solve's.
                    let vt = vi - nrm * vi.dot(&nrm);
                    let stops =
                        vt.dot(&self.fric[i]) > 0.0 || vt.norm() * model.mass[i] <= mu * fn_ * dt;
                    if stops && mu > 0.0 {
                        self.stuck[i] = true;
                        vi -= vt;
                    }
                    self.normal_force[i] = fn_;
                }
            }
            out.v[i] = vi;
            out.x[i] = x[i] + self.dx[i];
        }
    }
}
