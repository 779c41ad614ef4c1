//! The explicit integrators: explicit Euler and leapfrog, one particle at a time.
//!
//! The force on a particle (`cloth::forces::force_on`) is gathered from the start-of-step state
//! only, so particles advance independently, in parallel over fixed chunks; sliding particles
//! get their force projected and friction applied first (`collide::contact::slide_force`).

use super::{Integrator, NotPositiveDefinite, SolveStats, Solver, StepIn, StepOut};
use crate::cloth::forces;
use crate::collide::contact;
use crate::math::{Point3, Vec3};

/// Particles per work unit.
pub const CHUNK: usize = 64;

/// One step of `integrator` for one particle of inverse mass `w` (0: pinned, it stays) from
/// position `x`, velocity `v` and force `f`: the new position and velocity.
#[inline]
pub fn advance(
    integrator: Integrator,
    dt: f64,
    w: f64,
    x: Point3,
    v: Vec3,
    f: Vec3,
) -> (Point3, Vec3) {
    if w == 0.0 {
        return (x, Vec3::zeros());
    }
    let a = f * w;
    match integrator {
        Integrator::ExplicitEuler => (x + v * dt, v + a * dt),
        _ => {
            let v1 = v + a * dt;
            (x + v1 * dt, v1)
        }
    }
}

/// Explicit Euler or leapfrog.
pub struct Explicit {
    integrator: Integrator,
    /// Counters given back by `restore` (an explicit step counts nothing itself).
    stats: SolveStats,
}

impl Explicit {
    /// The solver of an explicit `integrator`.
    pub fn new(integrator: Integrator) -> Explicit {
        assert!(integrator.is_explicit());
        Explicit {
            integrator,
            stats: SolveStats::default(),
        }
    }
}

impl Solver for Explicit {
    fn step(&mut self, input: &StepIn, out: &mut StepOut) -> Result<(), NotPositiveDefinite> {
        let StepIn {
            model,
            x,
            v,
            f_ext,
            colliders,
            dt,
            ..
        } = *input;
        let integrator = self.integrator;
        crate::par::for_chunks3(
            CHUNK,
            model.len(),
            &mut *out.x,
            &mut *out.v,
            &mut *out.contact,
            |base, xs, vs, cs| {
                for k in 0..xs.len() {
                    let i = base + k;
                    let mut fi = forces::force_on(model, x, v, f_ext, i);
                    let mut vi = v[i];
                    if let Some(ct) = cs[k] {
                        let col = &colliders[ct.object as usize];
                        let mu = col.friction.unwrap_or(model.friction[i]);
                        if !contact::slide_force(col, &ct, mu, model.mass[i], dt, &mut fi, &mut vi)
                        {
                            cs[k] = None;
                        }
                    }
                    (xs[k], vs[k]) = advance(integrator, dt, model.inv_mass[i], x[i], vi, fi);
                }
            },
        );
        Ok(())
    }

    fn stats(&self) -> SolveStats {
        self.stats
    }

    fn restore(&mut self, state: &super::saved::SolverState) {
        assert_eq!(
            state.kept,
            super::saved::Kept::Nothing,
            "an explicit solver's state"
        );
        self.stats = state.stats;
    }
}
