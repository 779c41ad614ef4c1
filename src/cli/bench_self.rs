//! `drapekit bench self-contact`: what cloth against cloth costs per step.
//!
//! A 1 m square sheet of `side x side` particles (118 gives 13,924 particles and 27,378
//! triangles, 8.5 mm edges, the size of a garment at 1 cm), 3 mm thick, in three scenes:
//! **dense** (folded in five, layers 2 mm apart: every particle in contact), **resting** (layers
//! 3.2 mm apart, as a solver leaves them: contacts where the jitter brings them together) and
//! **garment** (one layer round a cylinder, overlapping itself by a tenth, 3.2 mm out). A step
//! moves every particle 1 mm down, give or take 0.5 mm. Timed with one and with two threads:
//! `resolve_self` (rebuilding the hash, finding the pairs, two position and two velocity
//! iterations), a rebuild without margins, and the self-crossing count. Medians over `--runs`;
//! every run's result is checked to be the same.

use super::bench::median;
use crate::collide::cloth::{
    resolve_self, self_crossing_edges, ClothHash, SelfCloth, SelfCollisionOptions, SelfStats,
};
use crate::collide::sheets::{crumpled, wrapped};
use crate::math::{Point3, SplitMix, Vec3};
use anyhow::ensure;
use serde::Serialize;
use std::time::Instant;

/// Arguments of `drapekit bench self-contact`.
#[derive(Debug, clap::Args)]
pub struct SelfContactBench {
    /// Particles along each side of the sheet.
    #[arg(long, default_value_t = 118, value_parser = clap::value_parser!(u32).range(8..=1000))]
    pub side: u32,
    /// Timed runs of each measurement (the median is reported).
    #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u32).range(1..=super::bench::MAX_RUNS))]
    pub runs: u32,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
}

/// One scene at one thread count.
#[derive(Debug, Serialize)]
struct Row {
    scene: &'static str,
    threads: usize,
    particles: usize,
    triangles: usize,
    resolve_ms: f64,
    rebuild_ms: f64,
    crossings_ms: f64,
    stats: SelfStats,
    crossing_edges: usize,
}

/// The step of every scene: `x0`, the moved `x1` and `v1`.
type Step = (Vec<Point3>, Vec<[u32; 3]>, Vec<Point3>, Vec<Vec3>);

fn scene(name: &str, side: usize) -> Step {
    let (x0, t) = match name {
        "dense" => crumpled(side, 1.0, 1, 0.002),
        "resting" => crumpled(side, 1.0, 1, 0.0032),
        _ => wrapped(side, 1.0, 1, 0.0032),
    };
    let mut rng = SplitMix(2);
    let x1 = x0
        .iter()
        .map(|p| p + Vec3::new(0.0, 0.0, -1e-3 + 1e-3 * (rng.next_f64() - 0.5)))
        .collect();
    let v1 = vec![Vec3::new(0.0, 0.0, -0.3); x0.len()];
    (x0, t, x1, v1)
}

/// Times `runs` calls of each operation on `step` with `threads` threads.
fn measure(name: &'static str, step: &Step, threads: usize, runs: u32) -> anyhow::Result<Row> {
    let (x0, t, x1, v1) = step;
    let n = x0.len();
    let (th, im) = (vec![0.003; n], vec![1.0 / 2e-5; n]);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    pool.install(|| {
        let mut h = ClothHash::new(n, t, &[]);
        let opts = SelfCollisionOptions::default();
        let (mut times, mut first) = ([vec![], vec![], vec![]], None);
        for _ in 0..runs {
            let (mut x, mut v) = (x1.clone(), v1.clone());
            let c = Instant::now();
            let mut st = resolve_self(
                x0,
                &mut x,
                &mut v,
                SelfCloth::new(t, &th, &im),
                &mut h,
                &opts,
                1e-3,
            );
            times[0].push(c.elapsed().as_secs_f64());
            let (c, cell) = (Instant::now(), h.cell());
            h.rebuild(&x, t, cell, 0.0);
            times[1].push(c.elapsed().as_secs_f64());
            let c = Instant::now();
            let crossing = self_crossing_edges(&x, t, &h);
            times[2].push(c.elapsed().as_secs_f64());
            st.seconds = 0.0;
            let result = (x, st, crossing);
            ensure!(
                first.as_ref().is_none_or(|f| *f == result),
                "{name}: runs differ"
            );
            first = Some(result);
        }
        let (_, stats, crossing_edges) = first.expect("at least one run");
        let ms = |k: usize| median(&times[k]) * 1e3;
        Ok(Row {
            scene: name,
            threads,
            particles: n,
            triangles: t.len(),
            resolve_ms: ms(0),
            rebuild_ms: ms(1),
            crossings_ms: ms(2),
            stats,
            crossing_edges,
        })
    })
}

/// Runs the benchmark.
pub fn run(args: SelfContactBench) -> anyhow::Result<()> {
    let mut rows = Vec::new();
    for name in ["dense", "resting", "garment"] {
        let step = scene(name, args.side as usize);
        for threads in [1, 2] {
            rows.push(measure(name, &step, threads, args.runs)?);
        }
        let k = rows.len();
        ensure!(
            rows[k - 1].stats == rows[k - 2].stats,
            "{name}: one and two threads differ"
        );
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    println!(
        "{:<8} {:>7} {:>9} {:>9} {:>11} {:>10} {:>12} {:>9} {:>9}",
        "scene",
        "threads",
        "particles",
        "contacts",
        "resolve ms",
        "rebuild ms",
        "crossings ms",
        "crossing",
        "remaining"
    );
    for r in &rows {
        println!(
            "{:<8} {:>7} {:>9} {:>9} {:>11.2} {:>10.2} {:>12.2} {:>9} {:>9}",
            r.scene,
            r.threads,
            r.particles,
            r.stats.contacts,
            r.resolve_ms,
            r.rebuild_ms,
            r.crossings_ms,
            r.crossing_edges,
            r.stats.remaining
        );
    }
    Ok(())
}
