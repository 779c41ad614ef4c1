//! `drapekit bench drape`: the paper's timing table on its scene class, and integrator accuracy
//! against step size.
//!
//! **Scene** (`method.md` s. 4, the first paper's table). A torso of 4,800 faces, fitted from
//! the GarmentCode mean female body (`fit`: 33 slices between 0.48 and 0.74 of the height,
//! 64 nodes around, tessellated 60 around x 33 rings, capped by concentric rings), and a square
//! of cloth of 4,761 particles (69 x 69 at 1 cm), 3 mm above the torso's top, centred on it. 1000 iterations of
//! leapfrog at half the estimated largest stable step, for each cell grid of the paper's table;
//! the collision and total seconds are medians of `--runs` runs, printed beside the paper's (an
//! i7-4770, one thread, 2017). The final state with 1 thread and with 2 is compared bit for bit.
//!
//! **Integrators.** A 30 cm square pinned at two corners swings for 0.1 s; each integrator and
//! step is compared with a leapfrog run at a step 16 times smaller than the smallest tried
//! (largest particle distance at the end), with its wall time. Unstable runs are reported as such.

use super::bench::median;
use crate::cloth::fabric::Fabric;
use crate::cloth::integrate::SolverSettings;
use crate::cloth::model::ClothModel;
use crate::cloth::pattern;
use crate::cloth::Integrator;
use crate::collide::Collider;
use crate::fit::fitter::{fit_sections, FitOptions};
use crate::fit::scan::{torso_sections, ScanOptions};
use crate::io::{read_mesh, ReadOptions};
use crate::math::{Point2, Point3, Vec3};
use crate::mesh::prepare::{prepare, PrepareOptions};
use crate::mesh::transform::{change_up, Up};
use crate::mesh::TriMesh;
use crate::sim::Stop;
use crate::sim::{self, World};
use anyhow::{ensure, Context};
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `drapekit bench drape`.
#[derive(Debug, clap::Args)]
pub struct DrapeBench {
    /// The body the torso is fitted from (Y-up, metres).
    #[arg(long, value_name = "MESH")]
    pub body: Option<PathBuf>,
    /// Timed runs of each configuration (the median is reported).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=super::bench::MAX_RUNS))]
    pub runs: u32,
    /// Iterations per run (at most 100,000,000, a scene's limit).
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(1..=crate::scene::MAX_STEPS))]
    pub steps: u64,
    /// Skip the slowest grid (1 x 1 x 1): every particle in the torso's box tests every face.
    #[arg(long)]
    pub skip_one_cell: bool,
    /// Also draw the measurements as SVG into this folder: `grid_cells.svg` (collision and
    /// total time against the number of cells, ours and the paper's) and `integrators.svg`
    /// (error against wall time per integrator: the Pareto of the step).
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The paper's table: cells, collision seconds, total seconds.
const PAPER: [([usize; 3], f64, f64); 5] = [
    ([1, 1, 1], 612.28, 618.07),
    ([5, 5, 5], 12.78, 18.58),
    ([15, 23, 7], 3.44, 9.29),
    ([50, 70, 30], 1.10, 6.93),
    ([100, 250, 50], 1.25, 7.07),
];

/// The bench fabric: cotton with a softer tensile stiffness (as the validation scenes).
pub fn bench_fabric() -> Fabric {
    Fabric {
        stretch: [1000.0, 1000.0],
        damping: 3.0,
        thickness: 0.002,
        ..Fabric::cotton()
    }
}

/// The 4,800-face torso of the bench, Z-up, metres.
pub fn bench_torso(body: &std::path::Path) -> anyhow::Result<TriMesh> {
    let mut m = read_mesh(body, &ReadOptions::default())
        .with_context(|| format!("the bench needs the body {}", body.display()))?
        .mesh;
    prepare(&mut m, &PrepareOptions::default());
    change_up(&mut m, Up::Y, Up::Z);
    let (sections, _) = torso_sections(
        &m,
        &ScanOptions {
            levels: 33,
            from: None,
            to: None,
        },
    )?;
    let f = fit_sections(
        sections,
        &[],
        &FitOptions {
            nodes_around: 64,
            along: 33,
            around: 60,
            ..FitOptions::default()
        },
    )?;
    Ok(f.mesh)
}

/// The bench world: the torso and a square of about `particles` particles above its top.
fn bench_world(torso: &TriMesh, cells: [usize; 3]) -> (World, f64) {
    torso_world(torso, cells, bench_fabric(), Integrator::Leapfrog)
}

/// The torso scene with `fabric`: the world, and half the stable step of `integrator`.
fn torso_world(
    torso: &TriMesh,
    cells: [usize; 3],
    fabric: Fabric,
    integrator: Integrator,
) -> (World, f64) {
    let b = torso.bbox().unwrap();
    let side = 0.675;
    let outline = [
        (-side / 2.0, -side / 2.0),
        (side / 2.0, -side / 2.0),
        (side / 2.0, side / 2.0),
        (-side / 2.0, side / 2.0),
    ]
    .map(|(x, y)| Point2::new(x, y));
    let piece =
        pattern::build(&outline, 0.01, &fabric, &pattern::Pins::default()).expect("a square");
    let c = b.center();
    let placed: Vec<Point3> = piece
        .flat
        .iter()
        .map(|q| Point3::new(c.x + q.x, c.y + q.y, b.max.z + 0.003))
        .collect();
    let (model, x) = ClothModel::assemble(
        &[("cloth".into(), piece, fabric.clone(), placed)],
        Vec3::new(0.0, 0.0, -9.81),
    );
    let collider = Collider::new(
        "torso".into(),
        torso.clone(),
        cells,
        fabric.thickness,
        Some(0.3),
    );
    let w = World::new(model, x, vec![collider], integrator);
    let dt = 0.5 * w.stable_step;
    (w, dt)
}

/// Wall seconds per simulated second on the torso scene with real cotton: the default solver
/// over one simulated second, and leapfrog at half its stable step over `steps` steps
/// (extrapolated to a second: it would take hundreds of thousands of steps).
#[derive(Debug, Serialize)]
struct TorsoRow {
    default_wall_per_second: f64,
    default_inside: usize,
    default_max_strain: f64,
    leapfrog_dt: f64,
    leapfrog_wall_per_second: f64,
}

fn torso_per_second(a: &DrapeBench, torso: &TriMesh) -> anyhow::Result<TorsoRow> {
    let settings = SolverSettings::default();
    let mut walls = Vec::new();
    let mut last = None;
    for _ in 0..a.runs {
        let (mut w, _) = torso_world(torso, [50, 70, 30], Fabric::cotton(), settings.integrator);
        let st = sim::run_quiet(&mut w, &settings, Stop::Steps((1.0 / settings.dt) as u64))?;
        walls.push(st.wall_seconds);
        last = Some(w);
    }
    let w = last.expect("a run");
    let mut lf = Vec::new();
    let mut dt = 0.0;
    for _ in 0..a.runs {
        let (mut w, h) = torso_world(torso, [50, 70, 30], Fabric::cotton(), Integrator::Leapfrog);
        dt = h;
        let st = sim::run_quiet(
            &mut w,
            &SolverSettings::new(Integrator::Leapfrog).with_dt(h),
            Stop::Steps(a.steps),
        )?;
        lf.push(st.wall_seconds / (a.steps as f64 * h));
    }
    Ok(TorsoRow {
        default_wall_per_second: median(&walls),
        default_inside: sim::particles_inside(&w)[0].unwrap_or(0),
        default_max_strain: sim::strain(&w.model, &w.state.x).0,
        leapfrog_dt: dt,
        leapfrog_wall_per_second: median(&lf),
    })
}

#[derive(Debug, Serialize)]
struct Row {
    cells: [usize; 3],
    collision_seconds: f64,
    total_seconds: f64,
    paper_collision_seconds: Option<f64>,
    paper_total_seconds: Option<f64>,
    contacts_end: usize,
}

#[derive(Debug, Serialize)]
struct IntegratorRow {
    /// The configuration (integrator and its iterations).
    label: String,
    integrator: Integrator,
    dt: f64,
    error: Option<f64>,
    wall_seconds: f64,
    stable_step_estimate: f64,
}

#[derive(Debug, Serialize)]
struct Report {
    particles: usize,
    faces: usize,
    steps: u64,
    dt: f64,
    rows: Vec<Row>,
    threads_identical: bool,
    torso: TorsoRow,
    integrators: Vec<IntegratorRow>,
}

/// Draws the grid-cell curve and the integrators' Pareto into `dir`.
fn write_plots(dir: &std::path::Path, rows: &[Row], ints: &[IntegratorRow]) -> anyhow::Result<()> {
    use crate::plot::{Plot, Series};
    std::fs::create_dir_all(dir)?;
    let cells = |r: &Row| r.cells.iter().product::<usize>() as f64;
    // The paper's grids as lines; the `auto` rule's grid (no paper figure) as its own points.
    let line = |name: &str, auto: bool, f: &dyn Fn(&Row) -> Option<f64>| {
        let of = rows
            .iter()
            .filter(|r| r.paper_total_seconds.is_none() == auto);
        Series::new(name, of.filter_map(|r| Some((cells(r), f(r)?))).collect())
    };
    let grid = Plot {
        title: "bench drape: time against the collision grid's cells".into(),
        x_label: "cells".into(),
        y_label: "seconds".into(),
        log_x: true,
        log_y: true,
        series: vec![
            line("collision", false, &|r| Some(r.collision_seconds)),
            line("total", false, &|r| Some(r.total_seconds)),
            line("paper: collision", false, &|r| r.paper_collision_seconds),
            line("paper: total", false, &|r| r.paper_total_seconds),
            line("auto rule: collision", true, &|r| Some(r.collision_seconds)),
            line("auto rule: total", true, &|r| Some(r.total_seconds)),
        ],
        ..Plot::default()
    };
    let mut names: Vec<&str> = Vec::new();
    for r in ints {
        if !names.contains(&r.label.as_str()) {
            names.push(&r.label);
        }
    }
    let pareto = Plot {
        title: "bench drape: error against wall time (each point a step)".into(),
        x_label: "wall seconds".into(),
        y_label: "error against the reference, m".into(),
        log_x: true,
        log_y: true,
        series: (names.iter())
            .map(|n| {
                let pts = (ints.iter().filter(|r| r.label == *n))
                    .filter_map(|r| Some((r.wall_seconds, r.error?)));
                Series::new(*n, pts.collect())
            })
            .collect(),
        ..Plot::default()
    };
    for (name, plot) in [("grid_cells.svg", grid), ("integrators.svg", pareto)] {
        let svg = plot.svg();
        crate::io::write_atomic(&dir.join(name), &[], |w| {
            std::io::Write::write_all(w, svg.as_bytes())
        })?;
    }
    Ok(())
}

/// Runs the benchmark.
pub fn run(a: DrapeBench) -> anyhow::Result<()> {
    let body = a.body.clone().unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/realdata/bodies/mean_female.obj")
    });
    let torso = bench_torso(&body)?;
    let (probe, dt) = bench_world(&torso, [1, 1, 1]);
    let say = |s: String| {
        if !a.json {
            println!("{s}");
        }
    };
    say(format!(
        "bench drape: {} particles falling on a torso of {} faces, {} iterations of leapfrog, dt = {:.2e} s (half the estimated stable step)",
        probe.model.len(),
        torso.faces.len(),
        a.steps,
        dt
    ));
    say("  cells           collision s   total s   | paper collision s   total s   | contacts at the end".into());
    let rows = grid_table(&a, &torso, &say)?;
    let identical = threads_identical(&a, &torso)?;
    say(format!("  final positions with 1 and 2 threads identical: {identical}; the same for every grid: true"));
    let torso_row = torso_per_second(&a, &torso)?;
    say(format!(
        "  real cotton on the torso, wall s per simulated second: default ({} at {} s) {:.2} (inside {}, max strain {:.2e}); leapfrog at {:.2e} s {:.1} (from {} steps)",
        SolverSettings::default().integrator,
        SolverSettings::default().dt,
        torso_row.default_wall_per_second,
        torso_row.default_inside,
        torso_row.default_max_strain,
        torso_row.leapfrog_dt,
        torso_row.leapfrog_wall_per_second,
        a.steps
    ));
    let integrators = integrator_table(&a, &say)?;
    if let Some(dir) = &a.plot {
        write_plots(dir, &rows, &integrators)?;
    }
    if a.json {
        let rep = Report {
            particles: probe.model.len(),
            faces: torso.faces.len(),
            steps: a.steps,
            dt,
            rows,
            threads_identical: identical,
            torso: torso_row,
            integrators,
        };
        println!("{}", serde_json::to_string_pretty(&rep)?);
    }
    Ok(())
}

/// The grid table: the paper's grids, then the `auto` rule's, each timed and printed; an error
/// when any two give different drapes.
fn grid_table(a: &DrapeBench, torso: &TriMesh, say: &dyn Fn(String)) -> anyhow::Result<Vec<Row>> {
    let mut rows = Vec::new();
    let mut finals: Vec<Vec<Point3>> = Vec::new();
    let auto = Collider::auto_dims(torso);
    let grids = PAPER
        .iter()
        .map(|&(c, pc, pt)| (c, Some((pc, pt))))
        .chain(std::iter::once((auto, None)));
    for (cells, paper) in grids {
        if cells == [1, 1, 1] && a.skip_one_cell {
            continue;
        }
        let row = grid_row(a, torso, cells, paper, &mut finals)?;
        let name = format!("{}x{}x{}", cells[0], cells[1], cells[2]);
        say(format!(
            "  {:<14}  {:>11.4}  {:>8.4}   | {:>17}  {:>8}   | {}",
            if paper.is_some() {
                name
            } else {
                format!("{name} auto")
            },
            row.collision_seconds,
            row.total_seconds,
            paper.map_or("-".into(), |(c, _)| format!("{c:.2}")),
            paper.map_or("-".into(), |(_, t)| format!("{t:.2}")),
            row.contacts_end
        ));
        rows.push(row);
    }
    ensure!(
        finals.windows(2).all(|w| w[0] == w[1]),
        "the grids gave different drapes: collision must not depend on the cells"
    );
    Ok(rows)
}

/// The bench scene with `cells`, `a.runs` times: its row (beside the paper's figures), each
/// run's final positions pushed onto `finals`.
fn grid_row(
    a: &DrapeBench,
    torso: &TriMesh,
    cells: [usize; 3],
    paper: Option<(f64, f64)>,
    finals: &mut Vec<Vec<Point3>>,
) -> anyhow::Result<Row> {
    let mut col = Vec::new();
    let mut tot = Vec::new();
    let mut contacts = 0;
    for _ in 0..a.runs {
        let (mut w, dt) = bench_world(torso, cells);
        let st = sim::run_quiet(
            &mut w,
            &SolverSettings::new(Integrator::Leapfrog).with_dt(dt),
            Stop::Steps(a.steps),
        )?;
        col.push(st.collision_seconds);
        tot.push(st.wall_seconds);
        contacts = w.state.contact.iter().filter(|c| c.is_some()).count();
        finals.push(w.state.x.clone());
    }
    Ok(Row {
        cells,
        collision_seconds: median(&col),
        total_seconds: median(&tot),
        paper_collision_seconds: paper.map(|p| p.0),
        paper_total_seconds: paper.map(|p| p.1),
        contacts_end: contacts,
    })
}

/// Whether the bench scene ends bit for bit the same with one thread and with two.
fn threads_identical(a: &DrapeBench, torso: &TriMesh) -> anyhow::Result<bool> {
    let mut by_threads = Vec::new();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let x = pool.install(|| {
            let (mut w, dt) = bench_world(torso, [50, 70, 30]);
            sim::run_quiet(
                &mut w,
                &SolverSettings::new(Integrator::Leapfrog).with_dt(dt),
                Stop::Steps(a.steps),
            )
            .map(|_| w.state.x)
        })?;
        by_threads.push(x);
    }
    Ok(by_threads[0] == by_threads[1])
}

/// The configurations of the speed-against-accuracy table: (label, settings).
fn configurations() -> Vec<(String, SolverSettings)> {
    let mut c = Vec::new();
    for dt in [1e-5, 2e-5, 4e-5] {
        for i in [Integrator::ExplicitEuler, Integrator::Leapfrog] {
            c.push((i.to_string(), SolverSettings::new(i).with_dt(dt)));
        }
    }
    for dt in [1e-4, 1e-3, 5e-3, 1e-2, 1.0 / 30.0] {
        c.push((
            "implicit-euler".into(),
            SolverSettings::new(Integrator::ImplicitEuler).with_dt(dt),
        ));
    }
    for dt in [1e-3, 5e-3] {
        let s = SolverSettings {
            newton_iterations: 4,
            ..SolverSettings::new(Integrator::ImplicitEuler).with_dt(dt)
        };
        c.push(("implicit-euler newton 4".into(), s));
    }
    for dt in [1e-3, 5e-3, 1e-2] {
        for it in [5, 10, 40] {
            let s = SolverSettings {
                iterations: it,
                ..SolverSettings::new(Integrator::ProjectiveDynamics).with_dt(dt)
            };
            c.push((format!("projective {it} it"), s));
            c.push((
                format!("projective {it} it plain"),
                SolverSettings { anderson: 0, ..s },
            ));
        }
        let s = SolverSettings {
            iterations: 10,
            anderson: 0,
            chebyshev: Some(0.9),
            ..SolverSettings::new(Integrator::ProjectiveDynamics).with_dt(dt)
        };
        c.push(("projective 10 it cheb 0.9".into(), s));
    }
    c
}

fn integrator_table(a: &DrapeBench, say: &dyn Fn(String)) -> anyhow::Result<Vec<IntegratorRow>> {
    let duration = 0.5;
    let dt_ref = 2e-6;
    let mut reference = super::bench_solver::swinging_square(Integrator::Leapfrog);
    sim::run_quiet(
        &mut reference,
        &SolverSettings::new(Integrator::Leapfrog).with_dt(dt_ref),
        Stop::Steps((duration / dt_ref).round() as u64),
    )?;
    say(format!("  integrators: a 30 cm square of real cotton (2 cm spacing) held by two corners falls and swings for {duration} s; largest particle distance to leapfrog at dt = {dt_ref:.1e} s"));
    say(
        "  integrator                    dt         error m      wall s   (stable step estimate)"
            .into(),
    );
    let mut rows = Vec::new();
    for (label, settings) in configurations() {
        let (integrator, dt) = (settings.integrator, settings.dt);
        {
            let mut times = Vec::new();
            let mut error = None;
            let mut estimate = 0.0;
            for _ in 0..a.runs {
                let mut w = super::bench_solver::swinging_square(integrator);
                estimate = w.stable_step;
                let r = sim::run_quiet(
                    &mut w,
                    &settings,
                    Stop::Steps((duration / dt).round() as u64),
                );
                match r {
                    Ok(st) => {
                        times.push(st.wall_seconds);
                        error = Some(
                            w.state
                                .x
                                .iter()
                                .zip(&reference.state.x)
                                .map(|(p, q)| (p - q).norm())
                                .fold(0.0, f64::max),
                        );
                    }
                    Err(_) => {
                        error = None;
                        times.push(f64::NAN);
                        break;
                    }
                }
            }
            let wall = median(&times);
            say(format!(
                "  {:<28} {:>8.1e}   {:>10}   {:>8}   ({:.2e}){}",
                label,
                dt,
                error.map_or("unstable".into(), |e| format!("{e:.3e}")),
                if wall.is_nan() {
                    "-".into()
                } else {
                    format!("{wall:.4}")
                },
                estimate,
                if error.is_some() && dt > estimate {
                    "  beyond the estimate: its fastest modes grow, too slowly to show in this run"
                } else {
                    ""
                }
            ));
            rows.push(IntegratorRow {
                label: label.clone(),
                integrator,
                dt,
                error,
                wall_seconds: wall,
                stable_step_estimate: estimate,
            });
        }
    }
    Ok(rows)
}

/// Runs the bench scene once with the given cells: (collision s, total s, contacts).
pub fn probe(body: &std::path::Path, cells: [usize; 3], steps: u64) -> (f64, f64, usize) {
    let torso = bench_torso(body).expect("the body");
    let (mut w, dt) = bench_world(&torso, cells);
    let st = sim::run_quiet(
        &mut w,
        &SolverSettings::new(Integrator::Leapfrog).with_dt(dt),
        Stop::Steps(steps),
    )
    .expect("stable");
    (
        st.collision_seconds,
        st.wall_seconds,
        w.state.contact.iter().filter(|c| c.is_some()).count(),
    )
}
