//! Time integration (`method.md` s. 3 and 6): one settings struct, one [`Solver`] trait, four
//! integrators.
//!
//! A step of the simulation runs in phases (`sim::run`): *predict* (external forces and the
//! inertial position `y = x + h v + h^2 M^-1 f_ext`), *solve* (this module: the integrator turns
//! the state into new positions and velocities), *collide* (`collide::contact`), *measure*. The
//! integrators differ only in the solve phase:
//!
//! * explicit Euler: `x+ = x + h v`, `v+ = v + h F/m`, stable below `c / (c^2/4 + w^2)` for
//!   air damping `c` and highest eigenfrequency `w`;
//! * leapfrog (symplectic Euler, the papers' default): `v+ = v + h F/m`, `x+ = x + h v+`,
//!   stable below `2 / w`;
//! * implicit (backward) Euler as Baraff and Witkin solve it (`implicit.rs`): Newton steps on
//!   `M (v+ - v) = h F(x + h v+, v+)`, each a linear system solved by preconditioned conjugate
//!   gradients, with contact as constraint filtering;
//! * projective dynamics (`projective.rs`): the same backward Euler step as a minimisation,
//!   solved by local projections and a global solve with a matrix factored once.
//!
//! The two explicit methods are only conditionally stable: [`Integrator::stable_step`] gives
//! their largest step, [`Integrator::advice`] what to do above it. The implicit ones are stable
//! at any step; their price is numerical damping, measured in `drapekit bench drape`.

// Index loops read best in this numerical code (several arrays per particle).
#![allow(clippy::needless_range_loop)]

pub mod anderson;
pub mod cg;
pub mod cholesky;
pub mod direct;
pub use cholesky::NotPositiveDefinite;
pub mod etree;
pub mod explicit;
pub mod implicit;
pub mod lowrank;
pub mod projective;
pub mod saved;

use super::model::ClothModel;
use super::state::Contact;
use crate::collide::Collider;
use crate::math::{Point3, Vec3};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// The time integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Integrator {
    /// Explicit (forward) Euler.
    ExplicitEuler,
    /// Leapfrog / symplectic Euler.
    Leapfrog,
    /// Implicit (backward) Euler, Baraff-Witkin.
    ImplicitEuler,
    /// Projective dynamics (local/global; the default).
    ProjectiveDynamics,
}

impl Default for Integrator {
    /// Projective dynamics: on a real fabric dropped on an object (`drapekit bench speed`) it is
    /// the fastest at a 10 ms step and the only one whose strain stays bounded after the impact.
    fn default() -> Self {
        Integrator::ProjectiveDynamics
    }
}

impl Integrator {
    /// Every integrator, in the order of the docs.
    pub const ALL: [Integrator; 4] = [
        Integrator::ExplicitEuler,
        Integrator::Leapfrog,
        Integrator::ImplicitEuler,
        Integrator::ProjectiveDynamics,
    ];

    /// Whether the integrator is stable only below a step ([`Integrator::stable_step`]).
    pub fn is_explicit(self) -> bool {
        matches!(self, Integrator::ExplicitEuler | Integrator::Leapfrog)
    }

    /// The largest stable step (s) for highest eigenfrequency `w` (rad/s) and air damping rate
    /// `c` (1/s); infinite for the implicit integrators.
    pub fn stable_step(self, w: f64, c: f64) -> f64 {
        if w == 0.0 {
            return f64::INFINITY;
        }
        match self {
            Integrator::Leapfrog => 2.0 / w,
            Integrator::ExplicitEuler => c / (c * c / 4.0 + w * w),
            Integrator::ImplicitEuler | Integrator::ProjectiveDynamics => f64::INFINITY,
        }
    }

    /// What to do when a run with this integrator went unstable, for the scene's estimated
    /// largest stable step `estimate` and highest frequency `w`.
    /// A step estimate that is zero, negative or not a number (a fabric with a non-finite or
    /// zero stiffness or mass) gives no step to advise: the advice says to check the fabric.
    pub fn advice(self, estimate: f64, w: f64) -> String {
        let usable = |dt: f64| dt.is_finite() && dt > 0.0;
        let leapfrog = Integrator::Leapfrog.stable_step(w, 0.0);
        if self.is_explicit() && !(usable(estimate) && usable(leapfrog)) {
            return format!(
                "no stable step can be estimated for this cloth (estimate {} s): check the \
                 fabric's stiffness and mass, or use the default projective-dynamics integrator",
                crate::math::short(estimate)
            );
        }
        match self {
            Integrator::Leapfrog => format!(
                "use dt <= {:.2e} s, or a larger spacing, or the default projective-dynamics integrator (stable at any step)",
                0.9 * estimate
            ),
            Integrator::ExplicitEuler => format!(
                "use dt <= {:.2e} s, or the leapfrog integrator (stable up to {:.2e} s here), or more damping",
                0.9 * estimate,
                0.9 * leapfrog
            ),
            Integrator::ImplicitEuler => "raise newton_iterations or lower cg_tolerance, and report the scene: implicit Euler should not go unstable".into(),
            Integrator::ProjectiveDynamics => "raise iterations or turn chebyshev off, and report the scene: projective dynamics should not go unstable".into(),
        }
    }

    /// A step (s) that drapes well with this integrator. Scene files without `dt` take it for
    /// the implicit integrators; for the explicit ones they step at a fraction of the cloth's
    /// stability estimate instead (`scene::Scene::choose_step`), which 1e-5 s can exceed.
    pub fn default_dt(self) -> f64 {
        match self {
            Integrator::ExplicitEuler | Integrator::Leapfrog => 1e-5,
            Integrator::ImplicitEuler | Integrator::ProjectiveDynamics => DEFAULT_DT,
        }
    }
}

/// The step of the default integrator, s.
pub const DEFAULT_DT: f64 = 1.0 / 100.0;

impl FromStr for Integrator {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Integrator::ALL
            .into_iter()
            .find(|i| i.to_string() == s)
            .ok_or_else(|| {
                format!("unknown integrator '{s}': expected 'implicit-euler', 'projective-dynamics', 'leapfrog' or 'explicit-euler'")
            })
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Integrator::ExplicitEuler => "explicit-euler",
            Integrator::Leapfrog => "leapfrog",
            Integrator::ImplicitEuler => "implicit-euler",
            Integrator::ProjectiveDynamics => "projective-dynamics",
        })
    }
}

/// How implicit Euler solves its linear systems.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LinearSolver {
    /// Sparse Cholesky of the assembled matrix (pattern analysed once).
    Cholesky,
    /// Block-Jacobi preconditioned conjugate gradients, matrix-free.
    Cg,
}

/// Everything that sets up a solver. Units are SI.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SolverSettings {
    /// The integrator (default projective dynamics).
    pub integrator: Integrator,
    /// Time step, s (default [`Integrator::default_dt`]).
    pub dt: f64,
    /// Implicit Euler: Newton iterations per step (default 1, Baraff and Witkin's linearised
    /// step; more converge the backward Euler step, the accuracy reference).
    pub newton_iterations: u32,
    /// Implicit Euler: how each Newton step's linear system is solved (default sparse
    /// Cholesky).
    pub linear_solver: LinearSolver,
    /// Implicit Euler with sparse Cholesky: the bending pairs no spring joins in the factored
    /// matrix, or moved onto its diagonal (`direct::BendingHessian`; default exact).
    pub bending_hessian: direct::BendingHessian,
    /// Implicit Euler: conjugate gradients stop when the preconditioned residual has fallen by
    /// this factor (default 1e-6).
    pub cg_tolerance: f64,
    /// Implicit Euler: at most this many conjugate-gradient iterations per Newton step (default
    /// 1000).
    pub cg_max_iterations: u32,
    /// Projective dynamics: local/global iterations per step (default 5).
    pub iterations: u32,
    /// Projective dynamics: after `iterations`, go on iterating while the largest strain of a
    /// stretch spring exceeds this (a fraction: 0.01 is 1%), up to `max_iterations` in all;
    /// `None`: exactly `iterations` per step.
    pub strain_tolerance: Option<f64>,
    /// Projective dynamics: the most iterations a step takes with `strain_tolerance`.
    pub max_iterations: u32,
    /// Projective dynamics: after the iterations, at most this many rounds of contact
    /// corrections, each followed by the iterations again: particles whose solved path meets
    /// a face the step did not foresee get a contact, and particles left sunk behind their
    /// face more than half the thickness get a stiffer one (default
    /// [`projective::CORRECTIONS`]; 0: none, the collide phase alone puts them back).
    pub corrections: u32,
    /// Projective dynamics: Chebyshev acceleration (Wang 2015) with this spectral radius
    /// estimate in (0, 1); `None` (default): plain iterations. Ignored with `anderson`.
    pub chebyshev: Option<f64>,
    /// Projective dynamics: each spring projects to the nearest length within this strain of
    /// its rest length (zero energy inside the band), `None` (default): to its rest length.
    pub strain_band: Option<f64>,
    /// Projective dynamics: Anderson acceleration with this many vectors of history (0: off;
    /// default [`ANDERSON_DEPTH`]), each accelerated iterate kept only if it lowers the step's
    /// objective.
    pub anderson: u32,
    /// Projective dynamics: while at most this many particles have a contact weight the
    /// factored matrix lacks (or no longer has), the solves are corrected exactly by a
    /// low-rank update instead of refactoring (default [`projective::LOW_RANK_MAX`]; 0:
    /// refactor at every change). Speed only: the iterates are the same to rounding.
    pub low_rank_max: u32,
}

/// The default history of Anderson acceleration.
pub const ANDERSON_DEPTH: u32 = 5;

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings::new(Integrator::default())
    }
}

impl SolverSettings {
    /// The defaults of `integrator` (its default step included).
    pub fn new(integrator: Integrator) -> SolverSettings {
        SolverSettings {
            integrator,
            dt: integrator.default_dt(),
            newton_iterations: 1,
            linear_solver: LinearSolver::Cholesky,
            bending_hessian: direct::BendingHessian::Exact,
            cg_tolerance: 1e-6,
            cg_max_iterations: 1000,
            iterations: 5,
            strain_tolerance: None,
            max_iterations: 20,
            corrections: projective::CORRECTIONS,
            chebyshev: None,
            strain_band: None,
            anderson: ANDERSON_DEPTH,
            low_rank_max: projective::LOW_RANK_MAX,
        }
    }

    /// The same settings at step `dt`.
    pub fn with_dt(self, dt: f64) -> SolverSettings {
        SolverSettings { dt, ..self }
    }
}

/// What the solve phase reads: the model, the state at the start of the step and what the
/// predict phase made of it.
pub struct StepIn<'a> {
    /// The model.
    pub model: &'a ClothModel,
    /// Positions at the start of the step, m.
    pub x: &'a [Point3],
    /// Velocities at the start of the step, m/s.
    pub v: &'a [Vec3],
    /// External forces (gravity), N.
    pub f_ext: &'a [Vec3],
    /// The inertial positions `x + h v + h^2 f_ext / m` (pinned: `x`), m.
    pub y: &'a [Point3],
    /// The objects (contact normals and friction).
    pub colliders: &'a [Collider],
    /// Which objects the cloth can reach this step (`sim::reachable`).
    pub reach: &'a [bool],
    /// The step, s.
    pub dt: f64,
}

/// What the solve phase writes: the new positions and velocities, and the contacts (released
/// when the cloth pulls away).
pub struct StepOut<'a> {
    /// New positions, m.
    pub x: &'a mut [Point3],
    /// New velocities, m/s.
    pub v: &'a mut [Vec3],
    /// Each particle's sliding contact.
    pub contact: &'a mut [Option<Contact>],
}

/// Counters of the solve phase, summed over a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct SolveStats {
    /// Wall time spent factoring matrices, s.
    pub factor_seconds: f64,
    /// Numeric factorisations.
    pub factorisations: u64,
    /// Columns computed for low-rank corrections instead of refactoring (projective dynamics:
    /// particles coming into or leaving contact), each a path of the elimination tree.
    pub low_rank_columns: u64,
    /// Conjugate-gradient iterations (implicit Euler).
    pub cg_iterations: u64,
    /// Local/global iterations (projective dynamics).
    pub pd_iterations: u64,
}

/// An integrator with what it keeps between steps (a factorisation, scratch vectors).
pub trait Solver: Send {
    /// One solve phase from `input` into `out`; fails when the step's matrix is not positive
    /// definite in double precision (a fabric far too stiff for the step: `sim::run` says so).
    fn step(&mut self, input: &StepIn, out: &mut StepOut) -> Result<(), NotPositiveDefinite>;
    /// Whether the collide phase should apply friction from the normal velocity it removes
    /// (integrators whose solve phase knows no contact).
    fn friction_in_collide(&self) -> bool {
        false
    }
    /// Counters so far.
    fn stats(&self) -> SolveStats;
    /// What it keeps between steps, and its counters (`saved`).
    fn save(&self) -> saved::SolverState {
        saved::SolverState {
            stats: self.stats(),
            kept: saved::Kept::Nothing,
        }
    }
    /// Continues from `state`, saved from a solver of the same settings and model after the
    /// same number of steps. Panics when its arrays do not fit the model (`sim::checkpoint`
    /// checks them first).
    fn restore(&mut self, state: &saved::SolverState);
    /// Leaves what the next run on the same model can use in `analysis` (the solver is done).
    fn hand_over(&mut self, analysis: &mut Analysis) {
        let _ = analysis;
    }
}

/// What a finished run's solver leaves to the next run on the same world
/// (`sim::World::analysis`): the direct solver's analysis of its matrix's pattern (the
/// ordering, the factor's structure, its buffers). The pattern depends only on which particles
/// the springs and bending join and which are pinned, not on the constants: sewing, which runs
/// a few steps at a time with seams of changing stiffness, analyses it once. A new solver takes
/// it only when its model has the same pattern (`direct::BlockSystem::fits`), so the results
/// are the same bits either way.
#[derive(Default)]
pub struct Analysis {
    direct: Option<direct::BlockSystem>,
}

impl Analysis {
    /// Whether nothing is kept.
    pub fn is_empty(&self) -> bool {
        self.direct.is_none()
    }

    /// Which direct analysis is kept (`direct::BlockSystem::serial`), if any.
    pub fn serial(&self) -> Option<u64> {
        self.direct.as_ref().map(|d| d.serial())
    }
}

impl std::fmt::Debug for Analysis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kept = if self.direct.is_some() {
            "a direct system"
        } else {
            "nothing"
        };
        write!(f, "Analysis({kept})")
    }
}

/// The solver of `settings` for a model whose pinned particles sit at `x`, taking what fits
/// from `analysis`.
pub fn make(
    settings: &SolverSettings,
    model: &ClothModel,
    x: &[Point3],
    analysis: &mut Analysis,
) -> Box<dyn Solver> {
    match settings.integrator {
        Integrator::ExplicitEuler | Integrator::Leapfrog => {
            Box::new(explicit::Explicit::new(settings.integrator))
        }
        Integrator::ImplicitEuler => {
            Box::new(implicit::ImplicitEuler::new(settings, model, analysis))
        }
        Integrator::ProjectiveDynamics => {
            Box::new(projective::ProjectiveDynamics::new(settings, model, x))
        }
    }
}

/// The outward unit normal of a particle's contact face.
#[inline]
pub fn contact_normal(colliders: &[Collider], ct: &Contact) -> Vec3 {
    colliders[ct.object as usize].plane(ct.face as usize).0 * ct.side
}

/// The friction coefficient between particle `i` and its contact's object.
#[inline]
pub fn contact_friction(colliders: &[Collider], model: &ClothModel, ct: &Contact, i: usize) -> f64 {
    colliders[ct.object as usize]
        .friction
        .unwrap_or(model.friction[i])
}

/// Coulomb friction on a velocity `v` against a face of outward normal `n`, for a normal impulse
/// per unit mass `jn` (m/s) and coefficient `mu`: the tangential velocity loses `mu jn`, and
/// stops if it had less (static friction).
#[inline]
pub fn coulomb(v: &mut Vec3, n: &Vec3, jn: f64, mu: f64) {
    if jn <= 0.0 || mu <= 0.0 {
        return;
    }
    let vn = n * v.dot(n);
    let vt = *v - vn;
    let s = vt.norm();
    let cut = mu * jn;
    *v = if s <= cut {
        vn
    } else {
        vn + vt * (1.0 - cut / s)
    };
}

/// Contacts found before the solve (speculative): each free particle's inertial path from `x`
/// to `y` is put through the collision test (`collide::contact::resolve`: the paper's segment
/// test, the thickness). A particle whose path meets a face starts the solve in contact with it,
/// so the solve can hold it there. At a large step this is what stops a falling cloth where it
/// lands: found after the solve only, the particles that hit are put back while their
/// neighbours have fallen a whole step further.
pub fn speculate(input: &StepIn, contact: &mut [Option<Contact>]) {
    contacts_along(input, input.y, contact);
}

/// The paper's segment test from `x` to `ends` for every free particle not yet in contact:
/// one whose path meets a face gets its contact in `contact`. Returns whether any did.
pub fn contacts_along(input: &StepIn, ends: &[Point3], contact: &mut [Option<Contact>]) -> bool {
    let StepIn {
        model,
        x,
        colliders,
        reach,
        ..
    } = *input;
    if !reach.iter().any(|&r| r) {
        return false;
    }
    let found = std::sync::atomic::AtomicBool::new(false);
    crate::par::for_chunks(crate::sim::COLLISION_CHUNK, contact, |base, cs| {
        for k in 0..cs.len() {
            let i = base + k;
            if model.pinned(i) || cs[k].is_some() {
                continue;
            }
            let (mut p, mut v) = (ends[i], Vec3::zeros());
            crate::collide::contact::resolve(
                colliders,
                reach,
                &x[i],
                &mut p,
                &mut v,
                model.thickness[i],
                &mut cs[k],
            );
            if cs[k].is_some() {
                found.store(true, std::sync::atomic::Ordering::Relaxed);
            }
        }
    });
    found.into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn advice_without_a_usable_estimate_names_the_fabric_not_a_zero_step() {
        for i in [Integrator::Leapfrog, Integrator::ExplicitEuler] {
            for (estimate, w) in [(0.0, f64::INFINITY), (f64::NAN, f64::NAN), (-1.0, 1.0)] {
                let a = i.advice(estimate, w);
                assert!(a.contains("no stable step can be estimated"), "{i}: {a}");
                assert!(!a.contains("use dt <="), "{i}: {a}");
            }
        }
        // A usable estimate gives a step: nine tenths of it.
        let a = Integrator::Leapfrog.advice(1e-4, 2e4);
        assert!(a.contains("use dt <= 9.00e-5 s"), "{a}");
    }
}
