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
//!   (`Spring::project`), or on the band of lengths within `strain_band` of it, in parallel. The bending elements are quadratic: nothing to project.
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
//! With few plain iterations a step can end with more energy than it began with; the velocities
//! are then scaled back (`energy_budget`), so the energy never grows beyond the work put in.
//! Not with Anderson acceleration, whose iterates are kept only when they lower the objective:
//! there the budget stalled a relaxing cloth (it zeroed the velocities of a square springing
//! back from a 1.5% stretch, which then stayed compressed by 0.5%).
//!
//! **Contact as constraints.** Before the iterations, the particles in contact are those the
//! step began with and those whose inertial path meets a face (`speculate`, the paper's segment
//! test). Each gets the fourth paper's inequality constraint, the energy `w/2 |p - t|^2` with
//! `t` the projection of `p` on the half-space in front of its face at the thickness (so it
//! pushes, never pulls), and `w` [`CONTACT_WEIGHT`] times the particle's `m / h^2`. The local
//! step projects, the global step sees `w` on the diagonal: the
//! matrix changes only when the set of particles in contact does, and is then refactored
//! numerically (the symbolic analysis is kept). Without it (contact found after the step only),
//! the particles that hit are held while their neighbours fall a whole step further, and a real
//! fabric's springs stretch far beyond what a few iterations recover.
//!
//! **A particle that sinks gets a stiffer constraint.** Relative to the particle's inertia,
//! `w` is soft against a real fabric's springs: where the cloth bends over an edge of the
//! contact region, its tension presses one row of particles into the face by millimetres
//! (`depth = F / w`, and `F` grows as the spacing shrinks while `m` falls with its square),
//! and the collide phase then puts them back alone, stretching their springs (a 1 m square of
//! real cotton at 128 per side on `bench speed`'s sphere: 1.7% after landing with 5 plain
//! iterations). A particle that ends a step sunk more than [`CONTACT_SINK`] of the thickness
//! behind it has its weight raised [`CONTACT_STIFFEN`] times (at most
//! [`CONTACT_STIFFEN_MAX`]) while it stays in contact: 0.7%. Only the sinking ones: raising
//! every weight 10 times slows sliding 3 times (the slope of `tests/implicit.rs`).
//!
//! The contact weight acts in every direction (x, y and z share one matrix), so along the face
//! it is a proximal term: a cloth lying on a face slides only a fraction `1 / (1 + 30)` of the
//! way per iteration. **Anderson acceleration** (`anderson`, on by default) removes that slow
//! mode: each accelerated iterate is kept when it does not raise the objective (with the
//! contacts' normal energy), else the plain one.
//!
//! **Corrections after the iterations** (`SolverSettings::corrections`, default 1 round). The
//! iterations end with some particles sunk millimetres behind their faces where the cloth bends
//! over the contact region's edge (the soft weight above), and the collide phase then puts them
//! back alone, stretching their springs (a 1 m square of real cotton at 128 per side on `bench
//! speed`'s sphere: 1.04% at the end). A round raises the weight of every particle sunk more
//! than [`CONTACT_SINK`] of the thickness at once (rather than at the next step), gives a
//! contact to every free particle whose solved path meets a face, and iterates once more:
//! 0.85% at the end, 5.6 instead of 5 iterations per step. Two rounds: 0.52% for 6.5.
//!
//! **Strain tolerance** (`strain_tolerance`, off by default): past `iterations`, the iterations
//! go on while a stretch spring is strained more than the tolerance, up to `max_iterations`.
//! The strain is measured by the local step, on the iterate, so it costs nothing extra. Measured
//! on `bench speed` at 128 per side: at 1% it ends at 0.76% but the largest strain of the
//! settled half rose from 1.04 to 1.49%, since the excess comes from the collide phase after
//! the solve (the corrections above), not from too few iterations.
//!
//! **Friction** is in the same projection ([`contact_target`]): the target also undoes the
//! particle's slip along the face since the step began, as far as Coulomb's law allows with
//! the constraint's normal force `w depth`. So the springs see friction while they settle
//! (applied after the iterations, it held particles where the solve had let them slide, and
//! stretched real cotton by 7%). A particle the face does not push at the end is released.

use super::cholesky::Cholesky;
use super::saved::{Kept, ProjectiveKept, SolverState};
use super::{contact_friction, contact_normal};
use super::{NotPositiveDefinite, SolveStats, Solver, SolverSettings, StepIn, StepOut};
use crate::cloth::elements::{Spring, SpringKind};
use crate::cloth::model::ClothModel;
use crate::cloth::state::Contact;
use crate::math::{Point3, Vec3};
use crate::par;
use rayon::prelude::*;

/// The contact weight relative to the particle's inertia `m / h^2`. Its weight presses a
/// particle `g h^2 / 30` into the face (0.03 mm at 10 ms; the collide phase puts it back), and
/// a cloth lying on a face still slides as Coulomb says within 10 iterations with Anderson
/// acceleration (measured on a 20-degree slope: 30 slides within 4% of backward Euler's answer;
/// 100 slides 35% short, 10 lets a cloth that friction holds creep 1.7 mm in 0.5 s; the
/// spring-based 0.01 of the springs' constants, 4,000 times `m / h^2` there, slid 4% of the way).
pub const CONTACT_WEIGHT: f64 = 30.0;

/// The default of `SolverSettings::corrections`: the most rounds of contact corrections a step
/// makes after its iterations.
pub const CORRECTIONS: u32 = 1;

/// How far a particle in contact may end a step behind the thickness, as a fraction of the
/// thickness, before its contact weight is raised by [`CONTACT_STIFFEN`] (module notes).
pub const CONTACT_SINK: f64 = 0.5;

/// The factor a sinking particle's contact weight is raised by at a time; it is raised up to
/// [`CONTACT_STIFFEN_MAX`] times [`CONTACT_WEIGHT`], and falls back when the contact ends.
pub const CONTACT_STIFFEN: f64 = 10.0;

/// The most a particle's contact weight is raised (see [`CONTACT_STIFFEN`]).
pub const CONTACT_STIFFEN_MAX: f64 = 100.0;

/// The most particles whose contact weight may differ from the factored matrix's before it is
/// refactored; up to it, the solves are corrected exactly (`lowrank`). Measured with `bench
/// speed` at 128 per side: 64, 128 and 192 took 0.82, 0.81 and 0.85 times the time of 32
/// (56 refactorisations down to 46, 35 and 31); beyond, the `k x k` inverse of each change of
/// the set costs more than the refactorisations it saves (1,000: 3 times slower).
pub const LOW_RANK_MAX: u32 = 128;

/// Local/global projective dynamics with a prefactored global matrix.
pub struct ProjectiveDynamics {
    settings: SolverSettings,
    /// The particle of each unknown.
    particle: Vec<u32>,
    /// The global matrix's factorisation (none without unknowns).
    chol: Option<Cholesky>,
    /// Whether the last factorisation failed (the matrix not positive definite in double
    /// precision: a fabric far too stiff for the step); the next step reports it.
    singular: bool,
    /// The matrix's values without contacts, in the order of the pattern's pairs (the
    /// diagonal of unknown `u` first, at `u`).
    base: Vec<f64>,
    values: Vec<f64>,
    /// Per particle, the contact weight of the factored matrix.
    factored: Vec<f64>,
    /// The particles whose weight differs from `factored`, as a low-rank correction.
    update: super::lowrank::DiagonalUpdate,
    /// Per particle, the contact weight of this step.
    weight: Vec<f64>,
    /// Per particle, what its contact weight is raised by (1 to `CONTACT_STIFFEN_MAX`).
    stiff: Vec<f64>,
    /// Per particle, the contact constraint's projection.
    target: Vec<Point3>,
    /// Right-hand side from the pinned particles (constant).
    pinned_rhs: Vec<Vec3>,
    /// Per spring, its projection.
    d: Vec<Vec3>,
    p: Vec<Point3>,
    prev: Vec<Point3>,
    prev2: Vec<Point3>,
    /// The global step's right-hand side, then its solution, per unknown.
    rhs: Vec<[f64; 3]>,
    /// The contacts of the step.
    contact: Vec<Option<Contact>>,
    /// Anderson acceleration's history, and scratch for the iterate and its acceleration.
    anderson: super::anderson::Anderson,
    u: Vec<Point3>,
    accelerated: Vec<Point3>,
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
        let mut pairs: Vec<(usize, usize)> = Vec::with_capacity(nu + 4 * model.springs.len());
        let mut base = Vec::with_capacity(pairs.capacity());
        let mut pinned_rhs = vec![Vec3::zeros(); n];
        for (u, &i) in particle.iter().enumerate() {
            let i = i as usize;
            pairs.push((u, u));
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
                        pairs.push((ia as usize, ib as usize));
                        base.push(w * ca * cb);
                    }
                }
            }
        };
        for s in &model.springs {
            element(&[(s.a as usize, -1.0), (s.b as usize, 1.0)], s.k);
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
        let chol = (nu > 0).then(|| Cholesky::analyse(nu, &pairs));
        let mut pd = ProjectiveDynamics {
            settings: *settings,
            particle,
            chol,
            values: base.clone(),
            base,
            factored: vec![0.0; n],
            update: Default::default(),
            weight: vec![0.0; n],
            stiff: vec![1.0; n],
            target: vec![Point3::origin(); n],
            pinned_rhs,
            d: vec![Vec3::zeros(); model.springs.len()],
            p: Vec::new(),
            prev: Vec::new(),
            prev2: Vec::new(),
            rhs: vec![[0.0; 3]; nu],
            contact: Vec::new(),
            anderson: super::anderson::Anderson::new(settings.anderson as usize),
            u: Vec::new(),
            accelerated: Vec::new(),
            stats: SolveStats::default(),
            singular: false,
            trace: None,
        };
        pd.factor();
        pd.stats.factor_seconds = start.elapsed().as_secs_f64();
        pd
    }

    /// Factors the matrix with the contact weights `weight` (numerically: the symbolic analysis
    /// is kept).
    fn factor(&mut self) {
        let Some(chol) = &mut self.chol else {
            return;
        };
        self.values.clone_from(&self.base);
        for (u, &i) in self.particle.iter().enumerate() {
            self.values[u] += self.weight[i as usize];
        }
        self.singular = chol.factor(&self.values).is_err();
        self.factored.clone_from(&self.weight);
        self.update.clear();
        self.stats.factorisations += 1;
    }

    /// Brings the solves to this step's contact weights: an exact low-rank correction while at
    /// most `low_rank_max` particles differ from the factored matrix, else a refactorisation.
    fn refresh_matrix(&mut self) {
        let Some(chol) = &self.chol else { return };
        let (weight, factored) = (&self.weight, &self.factored);
        let changes: Vec<(usize, f64)> = (self.particle.iter().enumerate())
            .filter_map(|(u, &i)| {
                let d = weight[i as usize] - factored[i as usize];
                (d != 0.0).then_some((u, d))
            })
            .collect();
        if self.update.matches(&changes) {
            return;
        }
        let t = std::time::Instant::now();
        // A change that leaves the matrix singular (which the weights, all >= 0, never make)
        // is refactored too: the factorisation then says so.
        let low_rank = changes.len() <= self.settings.low_rank_max as usize
            && self.update.set(chol, &changes).is_ok();
        if !low_rank {
            self.factor();
        }
        self.stats.factor_seconds += t.elapsed().as_secs_f64();
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

    /// The objective with the contacts' normal energy `w/2 depth^2` (the safeguard of Anderson
    /// acceleration), J.
    fn energy(&self, input: &StepIn, p: &[Point3]) -> f64 {
        let colliders = input.colliders;
        let mut e = Self::objective(input, p);
        for (i, c) in self.contact.iter().enumerate() {
            let Some(ct) = c else { continue };
            let c = &colliders[ct.object as usize];
            let (n, off) = c.plane(ct.face as usize);
            let th = input.model.thickness[i] + c.clearance;
            let depth = th - ct.side * (p[i].coords.dot(&n) - off);
            if depth > 0.0 {
                e += 0.5 * self.weight[i] * depth * depth;
            }
        }
        e
    }

    /// The local step: every spring's projection at `p`. Returns the largest strain of the
    /// stretch springs at `p` (the adaptive iterations' measure; `-inf` without any).
    fn local(&mut self, model: &ClothModel) -> f64 {
        let p = &self.p;
        let band = self.settings.strain_band;
        let proj = |(d, s): (&mut Vec3, &Spring)| {
            let (proj, strain) = s.project_measured(&p[s.a as usize], &p[s.b as usize], band);
            *d = proj;
            if s.kind == SpringKind::Stretch {
                strain
            } else {
                f64::NEG_INFINITY
            }
        };
        let none = f64::NEG_INFINITY;
        if par::parallel_light(model.springs.len()) {
            (self.d.par_iter_mut().zip(&model.springs))
                .map(proj)
                .reduce(|| none, f64::max)
        } else {
            (self.d.iter_mut().zip(&model.springs))
                .map(proj)
                .fold(none, f64::max)
        }
    }

    /// The global step: `p` from the projections.
    fn global(&mut self, input: &StepIn) {
        let StepIn {
            model, x, y, dt, ..
        } = *input;
        let Some(chol) = &mut self.chol else { return };
        let d = &self.d;
        let (pinned_rhs, target, weight) = (&self.pinned_rhs, &self.target, &self.weight);
        let row = |(out, &i): (&mut [f64; 3], &u32)| {
            let i = i as usize;
            let m = model.mass[i];
            let mut r = y[i].coords * (m / (dt * dt))
                + x[i].coords * (model.damping[i] * m / dt)
                + pinned_rhs[i]
                + target[i].coords * weight[i];
            for &(_, s) in &model.adj[model.adj_start[i] as usize..model.adj_start[i + 1] as usize]
            {
                let sp = &model.springs[s as usize];
                let sign = if sp.a as usize == i { -1.0 } else { 1.0 };
                r += d[s as usize] * (sp.k * sign);
            }
            *out = [r.x, r.y, r.z];
        };
        if par::parallel_light(self.particle.len()) {
            self.rhs.par_iter_mut().zip(&self.particle).for_each(row);
        } else {
            self.rhs.iter_mut().zip(&self.particle).for_each(row);
        }
        // x, y and z at once: one sweep of the factor serves the three columns.
        let update = &self.update;
        chol.solve_with(&mut self.rhs, |y| update.correct(y));
        for (r, &i) in self.rhs.iter().zip(&self.particle) {
            self.p[i as usize] = Point3::from(*r);
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
                self.contact_weight(input, i)
            } else {
                0.0
            };
        }
    }

    /// The local step of the contact constraints: each particle in contact projected on the
    /// half-space in front of its face, at the thickness.
    fn project_contacts(&mut self, input: &StepIn) {
        let StepIn {
            model,
            x,
            colliders,
            ..
        } = *input;
        for (i, c) in self.contact.iter().enumerate() {
            let Some(ct) = c else {
                self.target[i] = self.p[i];
                continue;
            };
            let c = &colliders[ct.object as usize];
            let th = model.thickness[i] + c.clearance;
            let face = nearest_front(c, ct, &self.p[i], th);
            let (n, off) = c.plane(face);
            self.target[i] = contact_target(
                &self.p[i],
                &x[i],
                &(n * ct.side),
                ct.side * off,
                th,
                contact_friction(colliders, model, ct, i),
            );
        }
    }

    /// Anderson acceleration of the iterate `u -> p`: the accelerated iterate replaces `p` when
    /// its energy is no higher than the last accepted one (`e_accepted`); else `p` stays and
    /// the history is forgotten. Returns the energy of the accepted iterate.
    fn accelerate(&mut self, input: &StepIn, e_accepted: f64) -> f64 {
        let mut acc = std::mem::take(&mut self.accelerated);
        let moved = self.anderson.next(&self.u, &self.p, &mut acc);
        let e_acc = if moved {
            self.energy(input, &acc)
        } else {
            f64::INFINITY
        };
        let e = if e_acc <= e_accepted {
            std::mem::swap(&mut self.p, &mut acc);
            e_acc
        } else {
            if moved {
                self.anderson.reset();
            }
            self.energy(input, &self.p)
        };
        self.accelerated = acc;
        e
    }

    /// Raises the contact weight of the particles that ended the step sunk more than
    /// [`CONTACT_SINK`] of the thickness behind it; a particle out of contact goes back to 1.
    fn stiffen(&mut self, input: &StepIn, contact: &[Option<Contact>]) {
        let StepIn {
            model, colliders, ..
        } = *input;
        for (i, c) in contact.iter().enumerate() {
            let Some(ct) = c else {
                self.stiff[i] = 1.0;
                continue;
            };
            let th = model.thickness[i] + colliders[ct.object as usize].clearance;
            let sunk = (self.target[i] - self.p[i]).dot(&contact_normal(colliders, ct));
            if sunk > CONTACT_SINK * th {
                self.stiff[i] = (self.stiff[i] * CONTACT_STIFFEN).min(CONTACT_STIFFEN_MAX);
            }
        }
    }

    /// Releases the contacts whose constraint does not push at the end of the step.
    fn release(&self, input: &StepIn, out: &mut StepOut) {
        let colliders = input.colliders;
        for (i, c) in out.contact.iter_mut().enumerate() {
            if let Some(ct) = c {
                let n = contact_normal(colliders, ct);
                if (self.target[i] - self.p[i]).dot(&n) * self.weight[i] <= 0.0 {
                    *c = None;
                }
            }
        }
    }
}

/// The face whose half-space constrains a particle in contact with `ct` at `p`. Where the
/// surface is locally convex (seen from the particle's side), the outside is the union of the
/// half-spaces of the faces around: the particle is free as soon as it is in front of one of
/// them, and else is pushed out of the one it is least behind. A lone face's plane, extended
/// past a convex edge, would hold a particle that goes round the edge (a cloth over a body's
/// shoulder) at the height of the face it left, stretching its springs by a third. Elsewhere
/// the contact's own face.
fn nearest_front(c: &crate::collide::Collider, ct: &Contact, p: &Point3, th: f64) -> usize {
    let f = ct.face as usize;
    if ct.side < 0.0 || !c.convex[f] {
        return f;
    }
    let depth = |g: usize| {
        let (n, off) = c.plane(g);
        th - (p.coords.dot(&n) - off)
    };
    c.ring(f)
        .iter()
        .map(|&g| g as usize)
        .min_by(|&a, &b| depth(a).total_cmp(&depth(b)))
        .unwrap_or(f)
}

/// The projection of a contact constraint (module notes): `p` pushed out of the face (outward
/// normal `n`, plane `n.q = off`) to the thickness `th`, and held against its slip since `x`
/// along the face as Coulomb's law allows: the whole slip is undone (sticking) while the force
/// that takes, `w |slip|`, is within `mu` times the normal force `w depth`; else the friction
/// force is `mu` times the normal force, against the slip.
///
/// ```
/// use drapekit::cloth::integrate::projective::contact_target;
/// use drapekit::math::{Point3, Vec3};
/// let n = Vec3::z();
/// // 1 mm into a face at z = 0 (thickness 0), slipped 0.5 mm: friction 0.5 holds it.
/// let t = contact_target(&Point3::new(0.5e-3, 0.0, -1e-3), &Point3::origin(), &n, 0.0, 0.0, 0.5);
/// assert!((t - Point3::origin()).norm() < 1e-15);
/// // Slipped 4 mm: friction takes back 0.5 x 1 mm of it.
/// let t = contact_target(&Point3::new(4e-3, 0.0, -1e-3), &Point3::origin(), &n, 0.0, 0.0, 0.5);
/// assert!((t - Point3::new(3.5e-3, 0.0, 0.0)).norm() < 1e-15);
/// ```
pub fn contact_target(p: &Point3, x: &Point3, n: &Vec3, off: f64, th: f64, mu: f64) -> Point3 {
    let depth = th - (p.coords.dot(n) - off);
    if depth <= 0.0 {
        return *p;
    }
    let moved = p - x;
    let slip = moved - n * moved.dot(n);
    let s = slip.norm();
    let hold = if s <= mu * depth { 1.0 } else { mu * depth / s };
    p + n * depth - slip * hold
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

impl ProjectiveDynamics {
    /// Local/global iterations from `self.p`: at least `min`, then on while the largest stretch
    /// strain exceeds `tolerance`, at most `most` in all; accelerated as the settings say.
    fn iterate(&mut self, input: &StepIn, min: u32, most: u32, tolerance: f64, touching: bool) {
        let model = input.model;
        let rho = self.settings.chebyshev;
        let mut omega = 1.0;
        let accelerate = self.settings.anderson > 0;
        if accelerate {
            self.contact.resize(model.len(), None);
            self.anderson.reset();
        }
        let mut e_accepted = if accelerate {
            self.energy(input, &self.p)
        } else {
            0.0
        };
        for k in 0..most {
            let strain = self.local(model);
            if k >= min && strain <= tolerance {
                break;
            }
            if accelerate {
                self.u.clone_from(&self.p);
            } else if rho.is_some() {
                self.prev2.clone_from(&self.prev);
                self.prev.clone_from(&self.p);
            }
            if touching {
                self.project_contacts(input);
            }
            self.global(input);
            if accelerate {
                e_accepted = self.accelerate(input, e_accepted);
            } else if let Some(rho) = rho {
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
    }

    /// Raises at once the contact weight of the particles the iterations left sunk more than
    /// [`CONTACT_SINK`] of the thickness behind their face (see `stiffen`). Returns whether any
    /// weight changed.
    fn stiffen_sunk(&mut self, input: &StepIn) -> bool {
        let StepIn {
            model, colliders, ..
        } = *input;
        self.project_contacts(input);
        let mut changed = false;
        for (i, c) in self.contact.iter().enumerate() {
            let Some(ct) = c else { continue };
            let th = model.thickness[i] + colliders[ct.object as usize].clearance;
            let sunk = (self.target[i] - self.p[i]).dot(&contact_normal(colliders, ct));
            if sunk > CONTACT_SINK * th && self.stiff[i] < CONTACT_STIFFEN_MAX {
                self.stiff[i] = (self.stiff[i] * CONTACT_STIFFEN).min(CONTACT_STIFFEN_MAX);
                self.weight[i] = self.contact_weight(input, i);
                changed = true;
            }
        }
        changed
    }

    /// The contacts the solved positions make that the step did not foresee: a free particle
    /// whose path from `x` to its solved position meets a face (the paper's segment test) gets
    /// its contact constraint. Returns whether any did.
    fn late_contacts(&mut self, input: &StepIn) -> bool {
        if !super::contacts_along(input, &self.p, &mut self.contact) {
            return false;
        }
        for i in 0..input.model.len() {
            if self.contact[i].is_some() && self.weight[i] == 0.0 {
                self.weight[i] = self.contact_weight(input, i);
            }
        }
        true
    }

    /// The contact weight of particle `i` (module notes), N/m.
    fn contact_weight(&self, input: &StepIn, i: usize) -> f64 {
        CONTACT_WEIGHT * self.stiff[i] * input.model.mass[i] / (input.dt * input.dt)
    }
}

impl Solver for ProjectiveDynamics {
    fn step(&mut self, input: &StepIn, out: &mut StepOut) -> Result<(), NotPositiveDefinite> {
        let StepIn { model, x, dt, .. } = *input;
        // From the free flight `x + h v`, not from `y`: near a pin, `y`'s fall of `h^2 g` can
        // stretch the springs far more than the step ever will. Particles in contact start
        // where they are: their velocities carry the slip of the last step's unconverged
        // friction, and extrapolating it started steps of the cloth lying on `bench speed`'s
        // sphere at 4 to 9% strain, of which 5 iterations left 1.5% (now 0.9%). Everywhere
        // else the free flight: starting all particles at `x` halved that strain but made a
        // swinging cloth lag (the trajectory error of `bench drape` at 1 ms went from 0.04 m
        // to 0.21 m with 10 iterations).
        self.p.clear();
        self.p.extend((0..model.len()).map(|i| {
            if model.pinned(i) || out.contact[i].is_some() {
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
        self.refresh_matrix();
        if self.singular {
            return Err(NotPositiveDefinite);
        }
        if let Some(t) = &mut self.trace {
            t.clear();
            t.push(Self::objective(input, &self.p));
        }
        let iterations = self.settings.iterations.max(1);
        // Past `iterations`, go on while a stretch spring is strained beyond the tolerance.
        let (most, tolerance) = match self.settings.strain_tolerance {
            Some(t) => (self.settings.max_iterations.max(iterations), t),
            None => (iterations, f64::INFINITY),
        };
        self.iterate(input, iterations, most, tolerance, touching);
        for _ in 0..self.settings.corrections {
            if !touching || !(self.late_contacts(input) | self.stiffen_sunk(input)) {
                break;
            }
            self.refresh_matrix();
            if self.singular {
                return Err(NotPositiveDefinite);
            }
            // One iteration spreads the change to the neighbours (3 iterations per round at 128
            // per side took 1.4 times the iterations for 0.1% less strain); the strain
            // tolerance, if any, asks for more.
            self.iterate(input, 1, most, tolerance, true);
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
            self.release(input, out);
        } else if self.settings.anderson == 0 {
            energy_budget(input, out);
        }
        self.stiffen(input, out.contact);
        Ok(())
    }

    fn stats(&self) -> SolveStats {
        SolveStats {
            low_rank_columns: self.update.columns_solved,
            ..self.stats
        }
    }

    fn save(&self) -> SolverState {
        SolverState {
            stats: self.stats(),
            kept: Kept::Projective(ProjectiveKept {
                stiff: self.stiff.clone(),
                target: self.target.clone(),
                contact: self.contact.clone(),
                factored: self.factored.clone(),
                update: self.update.saved(),
            }),
        }
    }

    fn restore(&mut self, state: &SolverState) {
        let Kept::Projective(k) = &state.kept else {
            panic!("not a projective-dynamics solver's state");
        };
        let n = self.stiff.len();
        assert!(k.stiff.len() == n && k.target.len() == n && k.factored.len() == n);
        self.stiff.clone_from(&k.stiff);
        self.target.clone_from(&k.target);
        self.contact.clone_from(&k.contact);
        // The matrix as it was factored (the same values, so the same factor), then the
        // correction on top of it.
        self.weight.clone_from(&k.factored);
        self.factor();
        // Products that do not fit the factor (a crafted checkpoint: its checksum holds) are
        // dropped; the next step's weights are then corrected from the factored matrix anew.
        if let Some(chol) = &self.chol {
            let _ = self.update.restore(chol, &k.update);
        }
        self.stats = state.stats;
        self.update.columns_solved = state.stats.low_rank_columns;
    }
}
