//! `drapekit bench fit`: the speed/accuracy trade of the fitter, measured.
//!
//! The analytic surface is closed around and not periodic along the height:
//! `x = r(v) cos t (1 + 0.1 cos 2t)`, `y = 0.8 r(v) sin t`, `z = 0.5 + 1.7 v + 0.2 v^2`,
//! `r(v) = 1 + 0.3 v + 0.2 sin 2v + 0.1 e^v`, `t = 2 pi u`. Around it has degree 3, so 32 nodes
//! reproduce it exactly and every error measured comes from the height direction. For each
//! number of node intervals `K - 1` the table gives the largest error over 401 heights at the
//! nodes around, for a plain periodic interpolation (no correction: the Gibbs error) and for
//! Lanczos orders 0, 1, 2, with the fit time; then the measured convergence order.

use super::bench::median;
use super::bench::FitBench;
use crate::fit::fitter::{fit_sections, FitOptions};
use crate::fit::section::Section;
use crate::fit::surface;
use crate::fit::trig;
use crate::math::{Point2, Point3};
use realfft::RealFftPlanner;
use serde::Serialize;
use std::time::Instant;

use crate::fit::surface::reference_surface as analytic;

const AROUND: usize = 32;
const HEIGHTS: usize = 401;

fn grid(k: usize) -> Vec<Point3> {
    (0..k)
        .flat_map(|i| {
            (0..AROUND).map(move |l| analytic(l as f64 / AROUND as f64, i as f64 / (k - 1) as f64))
        })
        .collect()
}

/// Largest error of the Lanczos fit of order m with k nodes along.
fn lanczos_error(k: usize, m: usize) -> f64 {
    let s = surface::fit(&grid(k), k, AROUND, m);
    let mut e: f64 = 0.0;
    for i in 0..HEIGHTS {
        let v = i as f64 / (HEIGHTS - 1) as f64;
        for (l, p) in s.eval_ring(v, AROUND).iter().enumerate() {
            e = e.max((p - analytic(l as f64 / AROUND as f64, v)).norm());
        }
    }
    e
}

/// Largest error of a plain periodic interpolation along (nodes 0..k-1, period 1: no correction).
fn plain_error(k: usize) -> f64 {
    let mut planner = RealFftPlanner::new();
    let n = k - 1;
    let mut e: f64 = 0.0;
    for l in 0..AROUND {
        let u = l as f64 / AROUND as f64;
        let coef: Vec<_> = (0..3)
            .map(|c| {
                let s: Vec<f64> = (0..n)
                    .map(|i| analytic(u, i as f64 / n as f64)[c])
                    .collect();
                trig::coefficients(&mut planner, &s)
            })
            .collect();
        for i in 0..HEIGHTS {
            let v = i as f64 / (HEIGHTS - 1) as f64;
            let p = Point3::new(
                trig::eval(&coef[0], n, v),
                trig::eval(&coef[1], n, v),
                trig::eval(&coef[2], n, v),
            );
            e = e.max((p - analytic(u, v)).norm());
        }
    }
    e
}

fn timed<T>(runs: u32, mut f: impl FnMut() -> T) -> f64 {
    let times: Vec<f64> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(f());
            t.elapsed().as_secs_f64()
        })
        .collect();
    median(&times)
}

#[derive(Debug, Serialize)]
struct Row {
    intervals: usize,
    error_none: f64,
    error: [f64; 3],
    fit_ms: [f64; 3],
}

#[derive(Debug, Serialize)]
struct Report {
    rows: Vec<Row>,
    order_none: f64,
    order: [f64; 3],
    speed_fit_tessellate_ms: f64,
    speed_with_estimates_ms: f64,
    scan: ScanSpeed,
    runs: u32,
}

/// A scan's slicing, both ways, median ms.
#[derive(Debug, Serialize)]
struct ScanSpeed {
    faces: usize,
    levels: usize,
    full_pass_ms: f64,
    banded_ms: f64,
}

/// Slices a lathed body (a profile of 400 rings, 120 sides) at 1,000 levels, each level by a
/// pass over all faces and through one [`Slicer`] built in the timed run; checks the loops
/// agree.
fn scan_speed(runs: u32) -> ScanSpeed {
    use crate::mesh::slice::{slice, Slicer};
    let profile: Vec<(f64, f64)> = (0..400)
        .map(|i| {
            let z = i as f64 / 399.0 * 1.7;
            (0.15 + 0.03 * (z * 9.0).sin() + 0.02 * (z * 23.0).cos(), z)
        })
        .collect();
    let body = crate::mesh::generate::lathe(&profile, 120);
    let levels: Vec<f64> = (0..1000)
        .map(|i| 0.001 + i as f64 * 1.698 / 999.0)
        .collect();
    let full = || levels.iter().map(|&h| slice(&body, h)).collect::<Vec<_>>();
    let banded = || {
        let s = Slicer::new(&body);
        levels.iter().map(|&h| s.slice(h)).collect::<Vec<_>>()
    };
    assert!(
        full() == banded(),
        "the banded slices differ from full passes"
    );
    ScanSpeed {
        faces: body.faces.len(),
        levels: levels.len(),
        full_pass_ms: 1e3 * timed(runs, full),
        banded_ms: 1e3 * timed(runs, banded),
    }
}

/// Draws the error against the node intervals, a line per correction.
fn write_plot(path: &std::path::Path, rows: &[Row]) -> anyhow::Result<()> {
    use crate::plot::{Plot, Series};
    let line = |name: &str, e: &dyn Fn(&Row) -> f64| {
        Series::new(
            name,
            rows.iter().map(|r| (r.intervals as f64, e(r))).collect(),
        )
    };
    let plot = Plot {
        title: "bench fit: largest error against nodes along (analytic surface)".into(),
        x_label: "node intervals along (K - 1)".into(),
        y_label: "largest error".into(),
        log_x: true,
        log_y: true,
        series: vec![
            line("no correction", &|r| r.error_none),
            line("Lanczos m = 0", &|r| r.error[0]),
            line("Lanczos m = 1", &|r| r.error[1]),
            line("Lanczos m = 2", &|r| r.error[2]),
        ],
        ..Plot::default()
    };
    let svg = plot.svg();
    crate::io::write_atomic(path, &[], |w| std::io::Write::write_all(w, svg.as_bytes()))?;
    Ok(())
}

/// The node intervals along of the accuracy table.
const INTERVALS: [usize; 6] = [8, 16, 32, 64, 128, 256];

/// Runs the benchmark.
pub fn run(a: FitBench) -> anyhow::Result<()> {
    if !a.json {
        println!("bench fit: analytic surface, {AROUND} nodes around (exact), largest error over {HEIGHTS} heights");
        println!("  K-1   no correction      m=0          m=1          m=2       fit ms (m=0/1/2)");
    }
    let rows: Vec<Row> = INTERVALS.iter().map(|&n| accuracy_row(&a, n)).collect();
    let order = [0, 1, 2].map(|m| order_of(rows.iter().map(|r| r.error[m]).collect()));
    let order_none = order_of(rows.iter().map(|r| r.error_none).collect());
    if let Some(path) = &a.plot {
        write_plot(path, &rows)?;
    }
    if !a.json {
        println!(
            "  measured order: none {:.2}, m=0 {:.2}, m=1 {:.2}, m=2 {:.2} (theory: N^-(2m+1) or better: 1, 3, 5)",
            order_none, order[0], order[1], order[2]
        );
    }
    let (core, full) = fit_speed(a.runs);
    let scan = scan_speed(a.runs);
    if !a.json {
        println!("  60 sections x 256 points, fit + tessellate 256 x 256: median {core:.1} ms (goal <= 50 ms); with error estimates and diagnosis: {full:.1} ms");
        println!(
            "  scan slicing, {} levels of a {}-face lathed body, one thread: a pass over every face per level {:.1} ms, faces banded by height (mesh::slice::Slicer) {:.1} ms: {:.1}x, the same loops",
            scan.levels, scan.faces, scan.full_pass_ms, scan.banded_ms, scan.full_pass_ms / scan.banded_ms
        );
    } else {
        let rep = Report {
            rows,
            order_none,
            order,
            speed_fit_tessellate_ms: core,
            speed_with_estimates_ms: full,
            scan,
            runs: a.runs,
        };
        println!("{}", serde_json::to_string_pretty(&rep)?);
    }
    Ok(())
}

/// The errors and fit times with `n` node intervals along, printed unless `--json`.
fn accuracy_row(a: &FitBench, n: usize) -> Row {
    let k = n + 1;
    let error = [0, 1, 2].map(|m| lanczos_error(k, m));
    let g = grid(k);
    let fit_ms = [0, 1, 2].map(|m| 1e3 * timed(a.runs, || surface::fit(&g, k, AROUND, m)));
    let row = Row {
        intervals: n,
        error_none: plain_error(k),
        error,
        fit_ms,
    };
    if !a.json {
        println!(
            "  {:>4}   {:>10.3e}   {:>10.3e}   {:>10.3e}   {:>10.3e}    {:.2}/{:.2}/{:.2}",
            n,
            row.error_none,
            row.error[0],
            row.error[1],
            row.error[2],
            fit_ms[0],
            fit_ms[1],
            fit_ms[2]
        );
    }
    row
}

/// The convergence order of `errs` (one per [`INTERVALS`]), from the last three where the error
/// is still above round-off.
fn order_of(errs: Vec<f64>) -> f64 {
    let pts: Vec<(f64, f64)> = INTERVALS
        .iter()
        .zip(errs)
        .filter(|(_, e)| *e > 1e-12)
        .map(|(n, e)| ((*n as f64).ln(), e.ln()))
        .collect();
    let tail = &pts[pts.len().saturating_sub(3)..];
    if tail.len() < 2 {
        return f64::NAN;
    }
    -(tail[tail.len() - 1].1 - tail[0].1) / (tail[tail.len() - 1].0 - tail[0].0)
}

/// Speed: 60 sections of 256 points, tessellated 256 x 256, median ms over `runs`: the core fit
/// and tessellation, and the whole fit with its error estimates and diagnosis.
fn fit_speed(runs: u32) -> (f64, f64) {
    let sections: Vec<Section> = (0..60)
        .map(|i| {
            let v = i as f64 / 59.0;
            let points = (0..256)
                .map(|l| analytic(l as f64 / 256.0, v))
                .map(|p| Point2::new(p.x, p.y))
                .collect();
            Section {
                height: analytic(0.0, v).z,
                points,
            }
        })
        .collect();
    let opts = FitOptions {
        nodes_around: 256,
        along: 256,
        around: 256,
        ..FitOptions::default()
    };
    let core = 1e3
        * timed(runs, || {
            let (s, _) = crate::fit::section::normalize(sections.clone()).unwrap();
            let g = crate::fit::fitter::node_grid(&s, 256);
            surface::fit(&g, 60, 256, 1).tessellate(256, 256, true)
        });
    let full = 1e3 * timed(runs, || fit_sections(sections.clone(), &[], &opts).unwrap());
    (core, full)
}
