//! A scene's `[solver]` table: the integrator and its settings, the keys that belong to
//! another integrator, and the stop rule (`steps`, `duration` or `until_rest`).

use super::{
    File, Problems, SolverFile, DT_MIN, MAX_ANDERSON, MAX_CG_ITERATIONS, MAX_CORRECTIONS,
    MAX_ITERATIONS, MAX_NEWTON_ITERATIONS, MAX_STEPS,
};
use crate::cloth::integrate::{Integrator, SolverSettings};
use crate::garment::drape::GARMENT_INTEGRATOR;
use crate::math::short;
use crate::sim::settings::Stop;

/// The solver's settings: the integrator (default projective dynamics), its step `dt` (s),
/// iteration counts, tolerances (relative residual; strains) and accelerations, each key's
/// problem recorded under its name.
pub(super) fn settings(s: &SolverFile, p: &Problems) -> SolverSettings {
    let mut solver = SolverSettings::new(integrator(s.integrator.as_deref(), p));
    if let Some(dt) = s.dt {
        solver.dt = step(dt, solver.dt, p);
    }
    count(
        "solver.newton_iterations",
        s.newton_iterations,
        MAX_NEWTON_ITERATIONS,
        &mut solver.newton_iterations,
        p,
    );
    count(
        "solver.cg_max_iterations",
        s.cg_max_iterations,
        MAX_CG_ITERATIONS,
        &mut solver.cg_max_iterations,
        p,
    );
    count(
        "solver.iterations",
        s.iterations,
        MAX_ITERATIONS,
        &mut solver.iterations,
        p,
    );
    tolerances(s, &mut solver, p);
    count(
        "solver.max_iterations",
        s.max_iterations,
        MAX_ITERATIONS,
        &mut solver.max_iterations,
        p,
    );
    accelerations(s, &mut solver, p);
    solver
}

/// `solver.integrator` by name (default: projective dynamics).
fn integrator(name: Option<&str>, p: &Problems) -> Integrator {
    name.map(|name| {
        name.parse().unwrap_or_else(|m| {
            p.bad("solver.integrator", m);
            Integrator::default()
        })
    })
    .unwrap_or_default()
}

/// `solver.dt`, s: a positive step of at least [`DT_MIN`] (`stand_in` when it is not
/// positive).
fn step(dt: f64, stand_in: f64, p: &Problems) -> f64 {
    let step = p.positive("solver.dt", dt, stand_in);
    if step < DT_MIN {
        p.bad(
            "solver.dt",
            format!("{} s is below {DT_MIN:e} s (a drape would need more than a billion steps per simulated second, and at 1e-154 s and below dt^2 underflows to 0)", short(dt)),
        );
    }
    step
}

/// A count of iterations `v` given for `key`, into `to`: 1 to `most`.
fn count(key: &str, v: Option<u32>, most: u32, to: &mut u32, p: &Problems) {
    if let Some(v) = v {
        if v == 0 {
            p.bad(key, "must be at least 1".into());
        } else if v > most {
            p.bad(key, format!("{v} iterations: at most {most}"));
        } else {
            *to = v;
        }
    }
}

/// `cg_tolerance` (a relative residual in (0, 1)) and `bending_hessian` of implicit Euler,
/// `strain_band` (a strain in [0, 1)) and `strain_tolerance` (a strain in (0, 1)) of
/// projective dynamics.
fn tolerances(s: &SolverFile, solver: &mut SolverSettings, p: &Problems) {
    if let Some(t) = s.cg_tolerance {
        if t.is_finite() && t > 0.0 && t < 1.0 {
            solver.cg_tolerance = t;
        } else {
            p.bad(
                "solver.cg_tolerance",
                format!("must be a number in (0, 1), got {}", short(t)),
            );
        }
    }
    if let Some(h) = &s.bending_hessian {
        match h.parse() {
            Ok(h) => solver.bending_hessian = h,
            Err(m) => p.bad("solver.bending_hessian", m),
        }
    }
    if let Some(b) = s.strain_band {
        if b.is_finite() && (0.0..1.0).contains(&b) {
            solver.strain_band = Some(b);
        } else {
            p.bad(
                "solver.strain_band",
                format!("must be a strain in [0, 1), got {}", short(b)),
            );
        }
    }
    if let Some(t) = s.strain_tolerance {
        if t.is_finite() && t > 0.0 && t < 1.0 {
            solver.strain_tolerance = Some(t);
        } else {
            p.bad(
                "solver.strain_tolerance",
                format!("must be a strain in (0, 1), got {}", short(t)),
            );
        }
    }
}

/// Projective dynamics' `corrections` (0 to [`MAX_CORRECTIONS`] rounds), `anderson` (0 to
/// [`MAX_ANDERSON`] vectors of history) and `chebyshev` (a spectral radius in (0, 1), with
/// `anderson = 0` only).
fn accelerations(s: &SolverFile, solver: &mut SolverSettings, p: &Problems) {
    if let Some(c) = s.corrections {
        if c <= MAX_CORRECTIONS {
            solver.corrections = c;
        } else {
            p.bad(
                "solver.corrections",
                format!("must be 0 (none) to {MAX_CORRECTIONS} rounds, got {c}"),
            );
        }
    }
    if let Some(m) = s.anderson {
        if m <= MAX_ANDERSON {
            solver.anderson = m;
        } else {
            p.bad(
                "solver.anderson",
                format!("must be 0 (off) to {MAX_ANDERSON} vectors of history, got {m}"),
            );
        }
    }
    // (With another integrator the key is refused by `foreign_keys`, as not its own.)
    if let Some(r) = s
        .chebyshev
        .filter(|_| solver.integrator == Integrator::ProjectiveDynamics)
    {
        if solver.anderson > 0 {
            p.bad(
                "solver.chebyshev",
                "needs anderson = 0: the two accelerations do not combine (Anderson is on by default)".into(),
            );
        } else if r.is_finite() && r > 0.0 && r < 1.0 {
            solver.chebyshev = Some(r);
        } else {
            p.bad(
                "solver.chebyshev",
                format!("must be a spectral radius in (0, 1), got {}", short(r)),
            );
        }
    }
}

/// Refuses, each by its own name, the `[solver]` keys given for another integrator than the
/// scene's: `integrator` as the file names it, or a `[[garment]]`'s own when it names none.
pub(super) fn foreign_keys(f: &File, integrator: Integrator, p: &Problems) {
    let (implicit, projective) = (Integrator::ImplicitEuler, Integrator::ProjectiveDynamics);
    let s = &f.solver;
    let owned = [
        (
            "solver.newton_iterations",
            s.newton_iterations.is_some(),
            implicit,
        ),
        ("solver.cg_tolerance", s.cg_tolerance.is_some(), implicit),
        (
            "solver.bending_hessian",
            s.bending_hessian.is_some(),
            implicit,
        ),
        (
            "solver.cg_max_iterations",
            s.cg_max_iterations.is_some(),
            implicit,
        ),
        ("solver.iterations", s.iterations.is_some(), projective),
        ("solver.chebyshev", s.chebyshev.is_some(), projective),
        ("solver.anderson", s.anderson.is_some(), projective),
        ("solver.strain_band", s.strain_band.is_some(), projective),
        (
            "solver.strain_tolerance",
            s.strain_tolerance.is_some(),
            projective,
        ),
        (
            "solver.max_iterations",
            s.max_iterations.is_some(),
            projective,
        ),
        ("solver.corrections", s.corrections.is_some(), projective),
    ];
    // A [[garment]] scene that names no integrator runs the garments' own.
    let integrator = if !f.garment.is_empty() && s.integrator.is_none() {
        GARMENT_INTEGRATOR
    } else {
        integrator
    };
    for (key, given, owner) in owned {
        if given && integrator != owner {
            p.bad(
                key,
                format!("applies to integrator = \"{owner}\" only (this scene uses {integrator})"),
            );
        }
    }
}

/// When the run stops: after `steps`, after `duration` (s, counted in steps of `dt` s), or
/// once the kinetic energy is below `until_rest` (J) within `max_steps`; a `[[garment]]`'s
/// stages end its run when none is given.
pub(super) fn stop(f: &File, dt: f64, p: &Problems) -> Stop {
    let s = &f.solver;
    let garment_stop =
        !f.garment.is_empty() && (s.steps, s.duration, s.until_rest) == (None, None, None);
    let stop = match (s.steps, s.duration, s.until_rest) {
        // A garment's stages end its run (`garment.sew_max`, `garment.settle_max`).
        _ if garment_stop => Stop::Steps(1),
        (Some(n), None, None) => steps(n, p),
        (None, Some(t), None) => duration(t, dt, p),
        (None, None, Some(e)) => {
            if !(e.is_finite() && e >= 0.0) {
                p.bad(
                    "solver.until_rest",
                    format!("must be a kinetic energy >= 0 (J), got {}", short(e)),
                );
            }
            Stop::UntilRest {
                energy: e,
                max_steps: s.max_steps.unwrap_or(1_000_000).clamp(1, MAX_STEPS),
            }
        }
        _ => {
            p.bad(
                "solver",
                "give exactly one of steps, duration or until_rest".into(),
            );
            Stop::Steps(1)
        }
    };
    if s.max_steps.is_some() && s.until_rest.is_none() && f.garment.is_empty() {
        p.bad("solver.max_steps", "goes with until_rest".into());
    }
    if let Some(n) = s.max_steps.filter(|&n| n > MAX_STEPS) {
        p.bad(
            "solver.max_steps",
            format!("{n} steps: at most {MAX_STEPS}"),
        );
    }
    stop
}

/// `solver.steps`: 1 to [`MAX_STEPS`] steps.
fn steps(n: u64, p: &Problems) -> Stop {
    if n == 0 {
        p.bad("solver.steps", "must be at least 1".into());
    } else if n > MAX_STEPS {
        p.bad("solver.steps", format!("{n} steps: at most {MAX_STEPS}"));
    }
    Stop::Steps(n.clamp(1, MAX_STEPS))
}

/// `solver.duration`, s: a positive time of at most [`MAX_STEPS`] steps of `dt` s.
fn duration(t: f64, dt: f64, p: &Problems) -> Stop {
    let t = p.positive("solver.duration", t, dt);
    let steps = (t / dt).round().max(1.0);
    if steps > MAX_STEPS as f64 {
        p.bad(
            "solver.duration",
            format!("{} s at solver.dt = {dt:e} s is {steps:.3e} steps: at most {MAX_STEPS}; give a larger solver.dt or a shorter solver.duration", short(t)),
        );
    }
    Stop::Steps(steps.min(MAX_STEPS as f64) as u64)
}
