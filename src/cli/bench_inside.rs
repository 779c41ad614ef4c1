//! `drapekit bench inside BODY`: the inside test's two ways on a body.
//!
//! `--points` random points in the body's box (fixed seed), counted inside by the generalized
//! winding number (O(faces) per point, the reference) and by ray crossings through the grid
//! (`collide::inside`); both counts must agree. Medians over `--runs`; the ratio is measured in
//! the same run.

use super::bench::median;
use crate::collide::inside::{inside, inside_by_winding};
use crate::collide::Collider;
use crate::io::{read_mesh, ReadOptions};
use crate::math::{Point3, SplitMix, Vec3};
use crate::mesh::prepare::{prepare, PrepareOptions};
use anyhow::ensure;
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `drapekit bench inside`.
#[derive(Debug, clap::Args)]
pub struct InsideBench {
    /// A closed body (OBJ, STL or PLY), prepared as `garment` prepares it.
    pub body: PathBuf,
    /// Random points in the body's box (at most 10,000,000).
    #[arg(long, default_value_t = 14_000, value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    pub points: u32,
    /// Timed runs of each way (the median is reported).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=super::bench::MAX_RUNS))]
    pub runs: u32,
}

/// Runs the benchmark.
pub fn run(args: InsideBench) -> anyhow::Result<()> {
    let mut mesh = read_mesh(&args.body, &ReadOptions::default())?.mesh;
    prepare(&mut mesh, &PrepareOptions::default());
    let dims = Collider::auto_dims(&mesh);
    let c = Collider::new("body".into(), mesh, dims, 0.0, None);
    ensure!(c.closed, "{}: the body is not closed", args.body.display());
    let mut rng = SplitMix(2024);
    let size = c.bbox.size();
    let points: Vec<Point3> = (0..args.points)
        .map(|_| {
            let t = Vec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            c.bbox.min + size.component_mul(&t)
        })
        .collect();
    let t = Instant::now();
    c.grid();
    let grid_s = t.elapsed().as_secs_f64();
    let time = |count: &(dyn Fn(&Point3) -> bool + Sync)| {
        let runs: Vec<(f64, usize)> = (0..args.runs)
            .map(|_| {
                let t = Instant::now();
                let n = points.par_iter().filter(|p| count(p)).count();
                (t.elapsed().as_secs_f64(), n)
            })
            .collect();
        let secs: Vec<f64> = runs.iter().map(|r| r.0).collect();
        (median(&secs), runs[0].1)
    };
    let (old_s, old_n) = time(&|p| inside_by_winding(&c, p));
    let (new_s, new_n) = time(&|p| inside(&c, p));
    ensure!(old_n == new_n, "the counts differ: {old_n} against {new_n}");
    println!(
        "{}: {} points, {} faces, cells {:?}, {} threads: winding number {old_s:.3} s, ray \
         crossings {new_s:.4} s (grid built in {grid_s:.3} s): {:.0} times faster; {old_n} inside",
        args.body.display(),
        points.len(),
        c.mesh.faces.len(),
        c.dims,
        rayon::current_num_threads(),
        old_s / new_s
    );
    Ok(())
}
