//! `drapekit bench speed`: the peers' scene, timed.
//!
//! **Scene.** A 1 m square of real cotton, `side x side` particles (64 x 64 by default), dropped
//! from 0.2 m above an icosphere of radius 0.3 m (5,120 faces), friction 0.5, one simulated
//! second. Taichi's mass-spring, Blender's cloth and Newton's XPBD take about 36, 36 and 72 s for
//! this second on this 2-core machine (issue 7). Each configuration runs `--runs` times; the
//! median wall time of the whole run (solver built, every phase) is reported with the phases,
//! and every run is checked: no particle inside the sphere (winding number), largest strain of
//! the thread springs, smallest clearance to the faces.
//!
//! The goals: at most 1.0 s for 64 x 64, at most 5 s for 128 x 128, and a 50,000-face sphere at
//! most 1.3 times the 5,120-face time.

use super::bench::median;
use crate::cloth::fabric::Fabric;
use crate::cloth::integrate::SolverSettings;
use crate::cloth::model::ClothModel;
use crate::cloth::pattern;
use crate::cloth::Integrator;
use crate::collide::Collider;
use crate::math::{Point2, Point3, Vec3};
use crate::mesh::generate;
use crate::mesh::TriMesh;
use crate::sim::{self, Stop, World};
use serde::Serialize;

/// Arguments of `drapekit bench speed`.
#[derive(Debug, clap::Args)]
pub struct SpeedBench {
    /// Timed runs of each configuration (the median is reported).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=super::bench::MAX_RUNS))]
    pub runs: u32,
    /// Particles per side of the square (default: 64, then 128; 2 to 1000).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=1000))]
    pub side: Vec<u32>,
    /// Only the 5,120-face sphere (skip the 50,000-face one).
    #[arg(long)]
    pub small_sphere_only: bool,
    /// The integrator (default: the default one).
    #[arg(long)]
    pub integrator: Option<Integrator>,
    /// The step, s (default: the integrator's default).
    #[arg(long)]
    pub dt: Option<f64>,
    /// Projective dynamics: iterations per step (at most a scene's 1000).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(crate::scene::MAX_ITERATIONS)))]
    pub iterations: Option<u32>,
    /// Projective dynamics: go on iterating past `--iterations` while a stretch spring is
    /// strained more than this (0.01 is 1%; 0 turns it off).
    #[arg(long, value_name = "STRAIN")]
    pub strain_tolerance: Option<f64>,
    /// Projective dynamics: the most iterations a step takes with the strain tolerance.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=i64::from(crate::scene::MAX_ITERATIONS)))]
    pub max_iterations: Option<u32>,
    /// Projective dynamics: rounds of contact corrections after the iterations (0: none).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=i64::from(crate::scene::MAX_CORRECTIONS)))]
    pub corrections: Option<u32>,
    /// Projective dynamics: Anderson acceleration's history (0: off; at most 20).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=i64::from(crate::scene::MAX_ANDERSON)))]
    pub anderson: Option<u32>,
    /// Implicit Euler: Newton iterations per step (at most a scene's 100).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(crate::scene::MAX_NEWTON_ITERATIONS)))]
    pub newton: Option<u32>,
    /// Projective dynamics: Chebyshev spectral radius (0 turns it off).
    #[arg(long)]
    pub chebyshev: Option<f64>,
    /// Projective dynamics: particles of changed contact corrected by a low-rank update before
    /// the matrix is refactored (0: refactor at every change; at most 4096, whose `k x k`
    /// inverse takes 128 MB).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=4096))]
    pub low_rank_max: Option<u32>,
    /// Friction between the cloth and the sphere.
    #[arg(long, default_value_t = 0.5)]
    pub friction: f64,
    /// Simulated seconds.
    #[arg(long, default_value_t = 1.0)]
    pub duration: f64,
    /// Print the largest strain, the kinetic energy and the contacts every this many steps of
    /// the last run.
    #[arg(long, value_name = "STEPS")]
    pub trace: Option<u64>,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
}

/// One configuration's result.
#[derive(Debug, Serialize)]
struct Row {
    particles: usize,
    faces: usize,
    settings: SolverSettings,
    wall_seconds: f64,
    solve_seconds: f64,
    collision_seconds: f64,
    factor_seconds: f64,
    factorisations: u64,
    low_rank_columns: u64,
    /// Projective dynamics: local/global iterations per step, on average.
    iterations_per_step: f64,
    inside: usize,
    max_strain: f64,
    /// The largest strain over the second half of the run.
    settled_strain: f64,
    min_clearance: f64,
}

/// The sphere of the scene: radius 0.3 m at the origin, about `faces` faces.
fn sphere(faces: usize) -> TriMesh {
    let mut m = if faces <= 5120 {
        generate::icosphere(4)
    } else {
        // 2 segments (rings - 1) faces: 200 x 125 gives 49,600.
        generate::uv_sphere(Point3::origin(), 1.0, 125, 200)
    };
    for p in &mut m.positions {
        *p = Point3::from(p.coords * 0.3);
    }
    m
}

/// The scene's world: the square 0.2 m above the sphere's top.
fn world(side: usize, mesh: &TriMesh, settings: &SolverSettings, friction: f64) -> World {
    let fabric = Fabric::cotton();
    let h = 0.5;
    let outline = [(-h, -h), (h, -h), (h, h), (-h, h)].map(|(x, y)| Point2::new(x, y));
    // A hair over 1 / (side - 1), so that rounding keeps `side` particles per side.
    let spacing = 1.0 / (side as f64 - 1.0) * (1.0 + 1e-9);
    let piece =
        pattern::build(&outline, spacing, &fabric, &pattern::Pins::default()).expect("a square");
    let placed: Vec<Point3> = piece
        .flat
        .iter()
        .map(|q| Point3::new(q.x, q.y, 0.5))
        .collect();
    let (model, x) = ClothModel::assemble(
        &[("square".into(), piece, fabric.clone(), placed)],
        Vec3::new(0.0, 0.0, -9.81),
    );
    let dims = Collider::auto_dims(mesh);
    let c = Collider::new(
        "sphere".into(),
        mesh.clone(),
        dims,
        fabric.thickness,
        Some(friction),
    );
    World::new(model, x, vec![c], settings.integrator)
}

/// Prints a line of the trace.
fn trace(step: u64, w: &World) -> Result<(), sim::SimError> {
    let (max, mean) = sim::strain(&w.model, &w.state.x);
    let ke = crate::cloth::forces::kinetic_energy(&w.model, &w.state.v);
    let contacts = w.state.contact.iter().filter(|c| c.is_some()).count();
    let over = w
        .model
        .springs
        .iter()
        .filter(|s| s.kind == crate::cloth::elements::SpringKind::Stretch)
        .filter(|s| (w.state.x[s.b as usize] - w.state.x[s.a as usize]).norm() > 1.01 * s.rest)
        .count();
    println!(
        "    step {step:>5}: strain max {max:.3e} mean {mean:.2e}, springs over 1% {over}, kinetic {ke:.3e} J, contacts {contacts}"
    );
    Ok(())
}

/// Particles inside the (convex, outward-wound) sphere: behind every face's plane. Exact for a
/// convex mesh, and linear in its faces without the winding number's trigonometry.
fn inside_convex(w: &World) -> usize {
    use rayon::prelude::*;
    let c = &w.colliders[0];
    w.state
        .x
        .par_iter()
        .filter(|p| {
            (0..c.mesh.faces.len()).all(|f| {
                let (n, off) = c.plane(f);
                p.coords.dot(&n) < off
            })
        })
        .count()
}

/// The settings of the run from the flags.
fn settings(a: &SpeedBench) -> SolverSettings {
    let mut s = SolverSettings::new(a.integrator.unwrap_or_default());
    if let Some(dt) = a.dt {
        s.dt = dt;
    }
    if let Some(it) = a.iterations {
        s.iterations = it;
    }
    if let Some(m) = a.anderson {
        s.anderson = m;
    }
    if let Some(t) = a.strain_tolerance {
        s.strain_tolerance = (t > 0.0).then_some(t);
    }
    if let Some(c) = a.corrections {
        s.corrections = c;
    }
    if let Some(m) = a.max_iterations {
        s.max_iterations = m;
    }
    if let Some(k) = a.low_rank_max {
        s.low_rank_max = k;
    }
    if let Some(n) = a.newton {
        s.newton_iterations = n;
    }
    if let Some(r) = a.chebyshev {
        s.chebyshev = (r > 0.0).then_some(r);
    }
    s
}

/// Runs the benchmark.
pub fn run(a: SpeedBench) -> anyhow::Result<()> {
    let s = settings(&a);
    let sides: Vec<usize> = if a.side.is_empty() {
        vec![64, 128]
    } else {
        a.side.iter().map(|&n| n as usize).collect()
    };
    let steps = a.duration / s.dt;
    if !(steps.is_finite() && steps > 0.0 && steps <= crate::scene::MAX_STEPS as f64) {
        anyhow::bail!(
            "--duration {} s at dt = {:e} s is {} steps: give 1 to {} (positive numbers)",
            crate::math::short(a.duration),
            s.dt,
            crate::math::short(steps),
            crate::scene::MAX_STEPS
        );
    }
    let say = |t: String| {
        if !a.json {
            println!("{t}");
        }
    };
    say(format!(
        "bench speed: a 1 m square of real cotton dropped from 0.2 m onto a sphere of radius 0.3 m, friction 0.5, {} s simulated; {} at dt = {:.3e} s{}",
        a.duration,
        s.integrator,
        s.dt,
        if s.integrator == Integrator::ProjectiveDynamics {
            format!(
                ", {} iterations, Anderson {}, Chebyshev {:?}",
                s.iterations, s.anderson, s.chebyshev
            )
        } else {
            String::new()
        }
    ));
    say("  particles  faces    wall s   solve s  collide s  factor s (count, low-rank columns) it/step | inside  max strain  2nd half max  min clearance mm".into());
    let mut rows = Vec::new();
    let mut faces_list = vec![5120];
    if !a.small_sphere_only {
        faces_list.push(50_000);
    }
    for &side in &sides {
        for &faces in &faces_list {
            let row = speed_row(&a, &s, side, &sphere(faces))?;
            say(row_line(&row));
            rows.push(row);
        }
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    }
    Ok(())
}

/// The scene with a square of `side` particles a side on `mesh`, `a.runs` times: its row (the
/// median wall time; the rest of the last run, which also records the largest strain of its
/// second half and prints the trace if asked).
fn speed_row(
    a: &SpeedBench,
    s: &SolverSettings,
    side: usize,
    mesh: &TriMesh,
) -> anyhow::Result<Row> {
    let mut walls = Vec::new();
    let mut last = None;
    let mut settled: f64 = 0.0;
    for run in 0..a.runs {
        let mut w = world(side, mesh, s, a.friction);
        let stop = Stop::Steps((a.duration / s.dt).round() as u64);
        // The last run also records the largest strain of its second half (about 0.5%
        // of its time), and prints the trace if asked.
        let half = stop.max_steps() / 2;
        let mut record = |step: u64, w: &World| {
            if a.trace.is_some_and(|k| step.is_multiple_of(k)) {
                trace(step, w)?;
            }
            if step > half {
                settled = settled.max(sim::strain(&w.model, &w.state.x).0);
            }
            Ok(false)
        };
        let st = if run + 1 == a.runs {
            sim::run(
                &mut w,
                s,
                stop,
                Some(1),
                &mut record,
                &|_| {},
                Default::default(),
            )?
        } else {
            sim::run_quiet(&mut w, s, stop)?
        };
        walls.push(st.wall_seconds);
        last = Some((w, st));
    }
    let (w, st) = last.expect("one run at least");
    Ok(Row {
        particles: w.model.len(),
        faces: mesh.faces.len(),
        settings: *s,
        wall_seconds: median(&walls),
        solve_seconds: st.solve_seconds,
        collision_seconds: st.collision_seconds,
        factor_seconds: st.solver.factor_seconds,
        factorisations: st.solver.factorisations,
        low_rank_columns: st.solver.low_rank_columns,
        iterations_per_step: st.solver.pd_iterations as f64 / st.steps.max(1) as f64,
        inside: inside_convex(&w),
        max_strain: sim::strain(&w.model, &w.state.x).0,
        settled_strain: settled,
        min_clearance: sim::min_clearance(&w)[0],
    })
}

/// A row of the printed table.
fn row_line(row: &Row) -> String {
    format!(
        "  {:>9}  {:>6}  {:>8.3}  {:>8.3}  {:>9.3}  {:>8.3} ({:>5}, {:>6}) {:>7.2} | {:>6}  {:>10.2e}  {:>13.2e}  {:>8.3}",
        row.particles,
        row.faces,
        row.wall_seconds,
        row.solve_seconds,
        row.collision_seconds,
        row.factor_seconds,
        row.factorisations,
        row.low_rank_columns,
        row.iterations_per_step,
        row.inside,
        row.max_strain,
        row.settled_strain,
        row.min_clearance * 1e3
    )
}
