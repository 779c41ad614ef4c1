//! `drapekit bench solver`: what the implicit integrators trade, on real cotton.
//!
//! 1. **Convergence of one step** (the fourth paper's comparison). A 30 cm square of real cotton
//!    held by two corners swings for 0.2 s; from that state one step of 10 ms is solved by
//!    projective dynamics (plain and with Anderson acceleration) and by Newton's method
//!    (implicit Euler with 1 to 8 Newton steps, sparse Cholesky). The relative error of the
//!    backward Euler objective, `(g - g*) / (g0 - g*)` (`g*` from 30 Newton steps, `g0` at the
//!    free flight `x + h v`), is printed against iterations and wall time.
//! 2. **Numerical damping.** The same square swings for 1.5 s; the largest kinetic energy in the
//!    last 0.5 s is compared with leapfrog's at 1e-5 s (whose only damping is the fabric's air
//!    damping): the ratio is what the integrator's own damping left.
//! 3. **Statics at large steps.** A 1 m x 4 cm ribbon of real cotton (no bending: a cable) hung
//!    by its ends 0.8 m apart comes to rest; its midspan sag is compared with Irvine's elastic
//!    catenary. The square hung by two corners comes to rest; its centre-of-mass drop is
//!    compared with projective dynamics at 200 iterations. Both for projective dynamics at
//!    several iteration counts and implicit Euler, at 10 ms.

use super::bench::median;
use crate::cloth::fabric::Fabric;
use crate::cloth::integrate::projective::ProjectiveDynamics;
use crate::cloth::integrate::{self, Integrator, Solver, SolverSettings, StepIn, StepOut};
use crate::cloth::model::ClothModel;
use crate::cloth::pattern::{self, Pins};
use crate::math::{Point2, Point3, Vec3};
use crate::sim::reference::elastic_catenary;
use crate::sim::{self, Stop, World};
use serde::Serialize;
use std::time::Instant;

/// Arguments of `drapekit bench solver`.
#[derive(Debug, clap::Args)]
pub struct SolverBench {
    /// Timed runs of each measurement (the median is reported).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=super::bench::MAX_RUNS))]
    pub runs: u32,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The 30 cm square of real cotton (2 cm spacing) held flat by two corners.
pub fn swinging_square(integrator: Integrator) -> World {
    let fabric = Fabric::cotton();
    let s = 0.15;
    let outline = [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| Point2::new(x, y));
    let piece = pattern::build(
        &outline,
        0.02,
        &fabric,
        &Pins::at(&[Point2::new(-s, s), Point2::new(s, s)]),
    )
    .expect("a square");
    let placed: Vec<Point3> = piece
        .flat
        .iter()
        .map(|q| Point3::new(q.x, q.y, 0.0))
        .collect();
    let (model, x) = ClothModel::assemble(
        &[("square".into(), piece, fabric, placed)],
        Vec3::new(0.0, 0.0, -9.81),
    );
    World::new(model, x, Vec::new(), integrator)
}

#[derive(Debug, Serialize)]
struct ConvergenceRow {
    method: String,
    iterations: u32,
    relative_error: f64,
    wall_seconds: f64,
}

/// The predict phase's outputs for `w` at step `dt`: external forces and inertial positions.
fn predicted(w: &World, dt: f64) -> sim::Predicted {
    let mut p = sim::Predicted::default();
    sim::predict(&w.model, &w.state, dt, &mut p);
    p
}

/// The solve phase's input for a step of `dt` from `w` (no objects).
fn step_in<'a>(w: &'a World, pred: &'a sim::Predicted, dt: f64) -> StepIn<'a> {
    StepIn {
        model: &w.model,
        x: &w.state.x,
        v: &w.state.v,
        f_ext: &pred.f_ext,
        y: &pred.y,
        colliders: &[],
        reach: &[],
        dt,
    }
}

/// One solve phase of `settings` from `w`'s state: the new positions and the step's wall time
/// (the solver built beforehand).
fn one_step(
    w: &World,
    settings: &SolverSettings,
    trace: bool,
) -> anyhow::Result<(Vec<Point3>, f64, Vec<f64>)> {
    let pred = predicted(w, settings.dt);
    let input = step_in(w, &pred, settings.dt);
    let (mut x, mut v, mut c) = (
        w.state.x.clone(),
        w.state.v.clone(),
        w.state.contact.clone(),
    );
    let mut out = StepOut {
        x: &mut x,
        v: &mut v,
        contact: &mut c,
    };
    if settings.integrator == Integrator::ProjectiveDynamics {
        let mut pd = ProjectiveDynamics::new(settings, &w.model, &w.state.x);
        pd.trace = trace.then(Vec::new);
        let t = Instant::now();
        pd.step(&input, &mut out)?;
        let s = t.elapsed().as_secs_f64();
        Ok((x, s, pd.trace.take().unwrap_or_default()))
    } else {
        let fresh = &mut integrate::Analysis::default();
        let mut solver = integrate::make(settings, &w.model, &w.state.x, fresh);
        let t = Instant::now();
        solver.step(&input, &mut out)?;
        Ok((x, t.elapsed().as_secs_f64(), Vec::new()))
    }
}

/// The backward Euler objective of positions `p` for a step from `w`.
fn objective(w: &World, dt: f64, p: &[Point3]) -> f64 {
    let pred = predicted(w, dt);
    ProjectiveDynamics::objective(&step_in(w, &pred, dt), p)
}

fn convergence(a: &SolverBench, say: &dyn Fn(String)) -> anyhow::Result<Vec<ConvergenceRow>> {
    let dt = 0.01;
    let mut w = swinging_square(Integrator::ProjectiveDynamics);
    sim::run_quiet(&mut w, &SolverSettings::default(), Stop::Steps(20))?;
    let newton = |k: u32| SolverSettings {
        newton_iterations: k,
        ..SolverSettings::new(Integrator::ImplicitEuler).with_dt(dt)
    };
    let (best, ..) = one_step(&w, &newton(30), false)?;
    let g_star = objective(&w, dt, &best);
    let free: Vec<Point3> = w
        .state
        .x
        .iter()
        .zip(&w.state.v)
        .enumerate()
        .map(|(i, (x, v))| if w.model.pinned(i) { *x } else { x + v * dt })
        .collect();
    let g0 = objective(&w, dt, &free);
    let rel = |g: f64| (g - g_star) / (g0 - g_star);
    say("  one step of 10 ms from a swinging 30 cm square of real cotton: relative error of the backward Euler objective (g - g*) / (g0 - g*)".into());
    say("  method                      iterations   relative error   wall s".into());
    let mut rows = Vec::new();
    let iters = 40;
    for (label, anderson) in [("projective dynamics", 0), ("projective + Anderson 5", 5)] {
        let s = SolverSettings {
            iterations: iters,
            anderson,
            ..SolverSettings::new(Integrator::ProjectiveDynamics).with_dt(dt)
        };
        let mut times = Vec::new();
        let mut trace = Vec::new();
        for _ in 0..a.runs {
            let (_, t, tr) = one_step(&w, &s, true)?;
            times.push(t);
            trace = tr;
        }
        let per = median(&times) / iters as f64;
        for k in [1usize, 2, 5, 10, 20, 40] {
            let row = ConvergenceRow {
                method: label.into(),
                iterations: k as u32,
                relative_error: rel(trace[k]),
                wall_seconds: per * k as f64,
            };
            say(format!(
                "  {:<27} {:>10}   {:>14.2e}   {:>7.5}",
                row.method, row.iterations, row.relative_error, row.wall_seconds
            ));
            rows.push(row);
        }
    }
    for k in [1, 2, 3, 5, 8] {
        let mut times = Vec::new();
        let mut x = Vec::new();
        for _ in 0..a.runs {
            let (p, t, _) = one_step(&w, &newton(k), false)?;
            times.push(t);
            x = p;
        }
        let row = ConvergenceRow {
            method: "Newton (implicit Euler)".into(),
            iterations: k,
            relative_error: rel(objective(&w, dt, &x)),
            wall_seconds: median(&times),
        };
        say(format!(
            "  {:<27} {:>10}   {:>14.2e}   {:>7.5}",
            row.method, row.iterations, row.relative_error, row.wall_seconds
        ));
        rows.push(row);
    }
    Ok(rows)
}

#[derive(Debug, Serialize)]
struct DampingRow {
    settings: SolverSettings,
    /// Largest kinetic energy in the last 0.5 s over leapfrog's.
    energy_ratio: f64,
}

/// The largest kinetic energy between 1.0 and 1.5 s of the swinging square.
fn late_peak(settings: &SolverSettings) -> anyhow::Result<f64> {
    let mut w = swinging_square(settings.integrator);
    let steps = (1.5 / settings.dt).round() as u64;
    let from = (1.0 / settings.dt).round() as u64;
    let peak = std::cell::Cell::new(0.0f64);
    sim::run(
        &mut w,
        settings,
        Stop::Steps(steps),
        Some(1),
        &mut |step, w| {
            if step >= from {
                let e = crate::cloth::forces::kinetic_energy(&w.model, &w.state.v);
                peak.set(peak.get().max(e));
            }
            Ok(false)
        },
        &|_| {},
        Default::default(),
    )?;
    Ok(peak.get())
}

fn damping(say: &dyn Fn(String)) -> anyhow::Result<Vec<DampingRow>> {
    let reference = late_peak(&SolverSettings::new(Integrator::Leapfrog).with_dt(1e-5))?;
    say("  numerical damping: the swinging square's largest kinetic energy in 1.0..1.5 s over leapfrog's (1e-5 s)".into());
    say("  integrator                     dt s     energy ratio".into());
    let mut rows = Vec::new();
    for integrator in [Integrator::ImplicitEuler, Integrator::ProjectiveDynamics] {
        for dt in [1e-3, 5e-3, 1e-2, 1.0 / 30.0] {
            let s = SolverSettings::new(integrator).with_dt(dt);
            let row = DampingRow {
                settings: s,
                energy_ratio: late_peak(&s)? / reference,
            };
            say(format!(
                "  {:<28} {:>7.4}   {:>10.3}",
                integrator.to_string(),
                dt,
                row.energy_ratio
            ));
            rows.push(row);
        }
    }
    Ok(rows)
}

#[derive(Debug, Serialize)]
struct StaticsRow {
    label: String,
    ribbon_sag: f64,
    ribbon_error: f64,
    corners_drop: f64,
    corners_error: f64,
    wall_seconds: f64,
}

/// The ribbon of real cotton without bending (a cable), hung by its ends 0.8 m apart, starting
/// on a circular arc of its length.
fn ribbon(integrator: Integrator) -> (World, f64, usize) {
    let fabric = Fabric {
        bend: [0.0, 0.0],
        ..Fabric::cotton()
    };
    let l = 1.0;
    let outline =
        [(-0.5, -0.02), (0.5, -0.02), (0.5, 0.02), (-0.5, 0.02)].map(|(x, y)| Point2::new(x, y));
    let pins = Pins {
        segments: vec![
            [Point2::new(-0.5, -0.02), Point2::new(-0.5, 0.02)],
            [Point2::new(0.5, -0.02), Point2::new(0.5, 0.02)],
        ],
        ..Pins::default()
    };
    let piece = pattern::build(&outline, 0.02, &fabric, &pins).expect("a ribbon");
    // The arc of length 1 over the chord 0.8: 2 R sin(t / 2) = 0.8 with R t = 1.
    let mut t: f64 = 1.0;
    for _ in 0..100 {
        t -= (2.0 / t * (t / 2.0).sin() - 0.8)
            / ((t / 2.0).cos() / t - 2.0 * (t / 2.0).sin() / (t * t));
    }
    let r = l / t;
    let placed: Vec<Point3> = piece
        .flat
        .iter()
        .map(|q| {
            let phi = q.x / r;
            Point3::new(r * phi.sin(), q.y, -(r * phi.cos() - r * (t / 2.0).cos()))
        })
        .collect();
    let (model, x) = ClothModel::assemble(
        &[("ribbon".into(), piece, fabric.clone(), placed)],
        Vec3::new(0.0, 0.0, -9.81),
    );
    let mid = (0..x.len())
        .min_by(|&a, &b| {
            let d = |i: usize| x[i].x.abs() + x[i].y.abs();
            d(a).total_cmp(&d(b))
        })
        .expect("particles");
    let (e, g) = (fabric.stretch[0], fabric.shear);
    let ea = e * (e + 2.0 * g) / (e + g);
    let (_, sag) = elastic_catenary(l, 0.8, fabric.density * 9.81, ea);
    (World::new(model, x, Vec::new(), integrator), sag, mid)
}

/// Runs `w` to rest (at most 30 simulated seconds) with `s`.
fn to_rest(w: &mut World, s: &SolverSettings) -> anyhow::Result<f64> {
    let t = Instant::now();
    sim::run_quiet(
        w,
        s,
        Stop::UntilRest {
            energy: 1e-9,
            max_steps: (30.0 / s.dt) as u64,
        },
    )?;
    Ok(t.elapsed().as_secs_f64())
}

/// The centre-of-mass drop of the square hung by two corners, at rest.
fn corners_drop(s: &SolverSettings) -> anyhow::Result<(f64, f64)> {
    let mut w = swinging_square(s.integrator);
    let com = |w: &World| {
        w.state
            .x
            .iter()
            .zip(&w.model.mass)
            .map(|(p, m)| p.z * m)
            .sum::<f64>()
            / w.model.mass.iter().sum::<f64>()
    };
    let z0 = com(&w);
    let t = to_rest(&mut w, s)?;
    Ok((z0 - com(&w), t))
}

fn statics(say: &dyn Fn(String)) -> anyhow::Result<Vec<StaticsRow>> {
    let dt = 0.01;
    let pd = |it: u32, anderson: u32| SolverSettings {
        iterations: it,
        anderson,
        ..SolverSettings::new(Integrator::ProjectiveDynamics).with_dt(dt)
    };
    let (reference, _) = corners_drop(&pd(200, 5))?;
    say(format!("  statics at 10 ms, at rest: the ribbon's sag against Irvine, the corners' centre-of-mass drop against projective dynamics at 200 iterations ({:.3} mm)", reference * 1e3));
    say("  solver                          ribbon sag m   error    corners drop mm   error    wall s".into());
    let mut configs: Vec<(String, SolverSettings)> = [5, 10, 20, 40, 100]
        .into_iter()
        .map(|it| (format!("projective {it} it, Anderson"), pd(it, 5)))
        .collect();
    configs.push(("projective 10 it, plain".into(), pd(10, 0)));
    configs.push(("projective 40 it, plain".into(), pd(40, 0)));
    configs.push((
        "implicit Euler".into(),
        SolverSettings::new(Integrator::ImplicitEuler).with_dt(dt),
    ));
    let mut rows = Vec::new();
    for (label, s) in configs {
        let (mut w, sag_ref, mid) = ribbon(s.integrator);
        let z0 = 0.0;
        let t1 = to_rest(&mut w, &s)?;
        let sag = z0 - w.state.x[mid].z;
        let (drop, t2) = corners_drop(&s)?;
        let row = StaticsRow {
            label,
            ribbon_sag: sag,
            ribbon_error: sag / sag_ref - 1.0,
            corners_drop: drop,
            corners_error: drop / reference - 1.0,
            wall_seconds: t1 + t2,
        };
        say(format!(
            "  {:<30} {:>12.4}   {:>+6.2}%   {:>15.3}   {:>+6.2}%   {:>6.2}",
            row.label,
            row.ribbon_sag,
            row.ribbon_error * 100.0,
            row.corners_drop * 1e3,
            row.corners_error * 100.0,
            row.wall_seconds
        ));
        rows.push(row);
    }
    Ok(rows)
}

#[derive(Debug, Serialize)]
struct Report {
    convergence: Vec<ConvergenceRow>,
    damping: Vec<DampingRow>,
    statics: Vec<StaticsRow>,
}

/// Runs the benchmark.
pub fn run(a: SolverBench) -> anyhow::Result<()> {
    let say = |s: String| {
        if !a.json {
            println!("{s}");
        }
    };
    say("bench solver: the implicit integrators on real cotton".into());
    let convergence = convergence(&a, &say)?;
    let damping = damping(&say)?;
    let statics = statics(&say)?;
    if a.json {
        let r = Report {
            convergence,
            damping,
            statics,
        };
        println!("{}", serde_json::to_string_pretty(&r)?);
    }
    Ok(())
}
