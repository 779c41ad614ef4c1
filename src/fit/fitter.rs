//! From sections to a form: nodes, fit, error estimates, node choice by tolerance, mesh, girths.
//!
//! **Nodes.** Every section is resampled to `N` points by arc length (`section`); the `K`
//! sections (every `stride`-th of those given) are the nodes along.
//!
//! **Estimated error** (input units), reported and used by `--tolerance`:
//! * *around*: each section's `N`-node trigonometric interpolant against the section itself,
//!   sampled at `max(4N, 1024)` arc-length positions between the nodes (held out): the largest
//!   distance over all sections;
//! * *along*: for a stride `s > 1`, the fit through every `s`-th section against the sections
//!   it leaves out (held out); for `s = 1` there is nothing left out, so the fit through every
//!   other section is measured against the ones it leaves out and divided by `2^(2m+1)`, the
//!   convergence the Lanczos correction of order `m` guarantees (smooth data converge faster,
//!   so this errs high); with fewer than 5 sections it cannot be estimated;
//! * the total is their sum.
//!
//! **Tolerance** (`--tolerance`): the smallest `N` whose around error is at most half the
//! tolerance, then the fewest sections (largest stride dividing `K - 1`) and lowest order whose
//! along error is at most the other half. "Model only what the scene requires."
//!
//! **Girths**: the output mesh is sliced at each requested height and the convex-hull perimeter
//! of the section (the tape-measure girth) compared with the requested value.

use super::error::FitError;
use super::lanczos;
use super::section::{self, Section, SectionNotes};
use super::surface::{self, Surface};
use super::trig;
use crate::math::{Point2, Point3};
use crate::mesh::diagnose::{diagnose, ShellState};
use crate::mesh::slice::{girth, Slicer};
use crate::mesh::TriMesh;
use rayon::prelude::*;
use realfft::RealFftPlanner;
use serde::Serialize;

/// The most nodes around a section (`--nodes`): each section is resampled to this many points
/// and sampled at four times as many for the error estimate.
pub const MAX_NODES_AROUND: usize = 1 << 16;

/// The most node points in all (nodes around times sections used): the fit holds a complex
/// coefficient (16 bytes) and more per node, 2^24 of them about 270 MB each.
pub const MAX_NODE_POINTS: usize = 1 << 24;

/// The most vertices of the output form (`--around` times `--along`): 2^24 vertices take about
/// 400 MB and their triangles 800 MB more.
pub const MAX_OUTPUT_VERTICES: usize = 1 << 24;

/// The most sections a scan is sliced into or a measurement model gives (`--levels`): the
/// error estimate's cost grows as their square.
pub const MAX_LEVELS: usize = 10_000;

/// Refuses `count` (given by `flag`) above `limit`, before anything is allocated for it.
pub fn check_count(flag: &str, count: usize, limit: usize, what: &str) -> Result<(), FitError> {
    if count > limit {
        return Err(FitError::TooLarge {
            flag: flag.to_string(),
            value: count as u64,
            limit: limit as u64,
            what: what.to_string(),
        });
    }
    Ok(())
}

/// How to fit and tessellate. `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Points per section used as nodes around (default 128).
    pub nodes_around: usize,
    /// Lanczos order along the height: 0, 1 or 2 (default 1).
    pub lanczos: usize,
    /// Use every `stride`-th section as a node (default 1: all).
    pub stride: usize,
    /// Rings of the output mesh along the height, at least (default 129): rounded up to
    /// `(K - 1) s + 1` so that every section used is a ring.
    pub along: usize,
    /// Points of each output ring (default 128).
    pub around: usize,
    /// Close the top and bottom (default true).
    pub caps: bool,
    /// Choose nodes and order for this largest error, in input units (default none).
    pub tolerance: Option<f64>,
}

impl FitOptions {
    /// Refuses counts out of range, naming each flag and listing every problem: `--nodes` 3 to
    /// [`MAX_NODES_AROUND`], `--around` at least 3, `--along` at least 2, `--stride` at least
    /// 1, `--around` times `--along` at most [`MAX_OUTPUT_VERTICES`].
    ///
    /// ```
    /// use drapekit::fit::fitter::FitOptions;
    /// let opts = FitOptions { nodes_around: 0, stride: 0, ..FitOptions::default() };
    /// let e = opts.check_counts().unwrap_err().to_string();
    /// assert!(e.starts_with("2 problems:") && e.contains("--nodes 0: at least 3"), "{e}");
    /// assert!(e.contains("--stride 0: at least 1"), "{e}");
    /// ```
    pub fn check_counts(&self) -> Result<(), FitError> {
        let low = [
            ("--nodes", self.nodes_around, 3, "nodes around each section"),
            ("--around", self.around, 3, "points around each ring"),
            ("--along", self.along, 2, "rings along the height"),
            ("--stride", self.stride, 1, "(1: every section)"),
        ];
        let mut problems: Vec<FitError> = (low.iter())
            .filter(|(_, v, min, _)| v < min)
            .map(|&(flag, value, min, what)| FitError::TooSmall {
                flag: flag.into(),
                value: value as u64,
                min: min as u64,
                what: what.into(),
            })
            .collect();
        let high = [
            check_count(
                "--nodes",
                self.nodes_around,
                MAX_NODES_AROUND,
                "nodes around each section",
            ),
            check_count(
                "--around x --along",
                self.around.saturating_mul(self.along),
                MAX_OUTPUT_VERTICES,
                "vertices of the form",
            ),
        ];
        problems.extend(high.into_iter().filter_map(Result::err));
        FitError::from_problems(problems)
    }
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            nodes_around: 128,
            lanczos: 1,
            stride: 1,
            along: 129,
            around: 128,
            caps: true,
            tolerance: None,
        }
    }
}

/// A girth the form should have.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GirthTarget {
    /// Its name (`bust`, `section 3`, ...).
    pub name: String,
    /// Height of the level.
    pub height: f64,
    /// Requested girth.
    pub requested: f64,
}

/// A requested girth and the girth measured on the output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GirthCheck {
    /// Its name.
    pub name: String,
    /// Height of the level.
    pub height: f64,
    /// Requested girth.
    pub requested: f64,
    /// Convex-hull perimeter of the output's section at that height.
    pub measured: f64,
    /// (measured - requested) / requested.
    pub deviation: f64,
}

/// The estimated error of a fit, in input units.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorEstimate {
    /// Around the sections (held-out points between the nodes).
    pub around: f64,
    /// Along the height (held-out sections, or the half-density extrapolation).
    pub along: Option<f64>,
    /// For stride 1: the measured error of the half-density fit behind `along`.
    pub along_half_density: Option<f64>,
    /// `around + along`.
    pub total: Option<f64>,
}

/// What `--tolerance` chose.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Choice {
    /// The tolerance, input units.
    pub tolerance: f64,
    /// Nodes around chosen.
    pub nodes_around: usize,
    /// Stride chosen (sections used = (given - 1) / stride + 1).
    pub stride: usize,
    /// Lanczos order chosen.
    pub lanczos: usize,
    /// The error it expects.
    pub expected_error: Option<f64>,
    /// Whether the tolerance is met.
    pub met: bool,
}

/// The output mesh.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputInfo {
    /// Rings along.
    pub along: usize,
    /// Points per ring.
    pub around: usize,
    /// Capped top and bottom.
    pub caps: bool,
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub faces: usize,
    /// Shell state (closed when capped).
    pub shell_state: ShellState,
    /// Enclosed volume (capped forms).
    pub volume: f64,
}

/// The fit report (the library part; the CLI adds paths, units and time).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitReport {
    /// Sections given.
    pub sections_given: usize,
    /// Sections used as nodes along.
    pub nodes_along: usize,
    /// Stride through the given sections.
    pub stride: usize,
    /// Points per section used as nodes around.
    pub nodes_around: usize,
    /// Lanczos order asked for.
    pub lanczos_requested: usize,
    /// Lanczos order used (lowered when there are too few sections).
    pub lanczos: usize,
    /// Estimated error.
    pub estimated_error: ErrorEstimate,
    /// What the tolerance chose, when one was given.
    pub tolerance: Option<Choice>,
    /// Requested girths against the output.
    pub girths: Vec<GirthCheck>,
    /// Largest |deviation| of the girths.
    pub max_girth_deviation: f64,
    /// The output mesh.
    pub output: OutputInfo,
    /// What normalising the sections did.
    pub sections: SectionNotes,
    /// Things to know.
    pub warnings: Vec<String>,
}

/// A fitted form.
#[derive(Debug, Clone)]
pub struct Fitted {
    /// The tessellated form.
    pub mesh: TriMesh,
    /// The surface.
    pub surface: Surface,
    /// The report.
    pub report: FitReport,
}

/// The `K x N` node grid of sections (row after row).
pub fn node_grid(sections: &[Section], n: usize) -> Vec<Point3> {
    sections
        .iter()
        .flat_map(|s| {
            section::resample(&s.points, n)
                .into_iter()
                .map(move |p| Point3::new(p.x, p.y, s.height))
        })
        .collect()
}

/// Around error: each section's `n`-node interpolant against the section at held-out points.
pub fn around_error(sections: &[Section], n: usize) -> f64 {
    let mut planner = RealFftPlanner::new();
    let fine_n = (4 * n).max(1024);
    let mut worst: f64 = 0.0;
    for s in sections {
        let nodes = section::resample(&s.points, n);
        let fine = section::resample(&s.points, fine_n);
        let xs: Vec<f64> = nodes.iter().map(|p| p.x).collect();
        let ys: Vec<f64> = nodes.iter().map(|p| p.y).collect();
        let cx = trig::coefficients(&mut planner, &xs);
        let cy = trig::coefficients(&mut planner, &ys);
        let fx = trig::resample(&mut planner, &cx, n, fine_n);
        let fy = trig::resample(&mut planner, &cy, n, fine_n);
        for (i, p) in fine.iter().enumerate() {
            worst = worst.max((Point2::new(fx[i], fy[i]) - p).norm());
        }
    }
    worst
}

/// Along error of the fit through every `stride`-th section, measured at the others; with
/// `stride == 1`, the half-density extrapolation (see the module docs). Returns
/// (estimate, measured half-density error).
pub fn along_error(
    sections: &[Section],
    n: usize,
    stride: usize,
    m: usize,
) -> (Option<f64>, Option<f64>) {
    let k = sections.len();
    if stride > 1 {
        return (Some(held_out_error(sections, n, stride, m)), None);
    }
    // Every other section of an odd count (dropping the last one if the count is even).
    let usable = if k % 2 == 1 { k } else { k - 1 };
    if usable < 5 {
        return (None, None);
    }
    let half = held_out_error(&sections[..usable], n, 2, m);
    let m_full = lanczos::order_for(k, m);
    (Some(half / 2f64.powi(2 * m_full as i32 + 1)), Some(half))
}

/// The fit through every `stride`-th section (count - 1 divisible by stride) against the others.
fn held_out_error(sections: &[Section], n: usize, stride: usize, m: usize) -> f64 {
    let k = sections.len();
    let used: Vec<Section> = sections.iter().step_by(stride).cloned().collect();
    let ks = used.len();
    let s = surface::fit(&node_grid(&used, n), ks, n, m);
    // Each held-out section costs a pass over all the nodes along, so they run in parallel; a
    // maximum is the same in any order.
    (0..k - 1)
        .into_par_iter()
        .filter(|idx| idx % stride != 0)
        .map(|idx| {
            let sec = &sections[idx];
            let v = idx as f64 / stride as f64 / (ks - 1) as f64;
            let truth = section::resample(&sec.points, n);
            let ring = s.eval_ring(v, n);
            (truth.iter().zip(&ring))
                .map(|(t, p)| (Point3::new(t.x, t.y, sec.height) - p).norm())
                .fold(0.0, f64::max)
        })
        .reduce(|| 0.0, f64::max)
}

const AROUND_CANDIDATES: [usize; 16] = [
    8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256, 384, 512, 768, 1024, 2048,
];

/// Fits a form through `sections` (see the module docs).
pub fn fit_sections(
    sections: Vec<Section>,
    targets: &[GirthTarget],
    opts: &FitOptions,
) -> Result<Fitted, FitError> {
    check_options(opts)?;
    let given = sections.len();
    let (sections, notes) = section::normalize(sections)?;
    let mut warnings = Vec::new();
    if notes.merged_duplicates > 0 {
        warnings.push(format!(
            "{} section(s) given twice at one height were merged",
            notes.merged_duplicates
        ));
    }
    let plan = plan(&sections, opts, &mut warnings)?;
    let k = plan.used.len();
    let surface = surface::fit(&node_grid(&plan.used, plan.n), k, plan.n, plan.m);
    let estimated_error = estimate_error(&sections, &plan, &mut warnings);
    let (mesh, output) = form(&surface, k, opts, &mut warnings);
    let girths = measure_girths(&mesh, targets);
    let max_girth_deviation = girths.iter().map(|g| g.deviation.abs()).fold(0.0, f64::max);
    let report = FitReport {
        sections_given: given,
        nodes_along: k,
        stride: plan.stride,
        nodes_around: plan.n,
        lanczos_requested: plan.m_req,
        lanczos: plan.m,
        estimated_error,
        tolerance: plan.choice,
        girths,
        max_girth_deviation,
        output,
        sections: notes,
        warnings,
    };
    Ok(Fitted {
        mesh,
        surface,
        report,
    })
}

/// The options' counts and order within what the fit supports.
fn check_options(opts: &FitOptions) -> Result<(), FitError> {
    opts.check_counts()?;
    if opts.lanczos > lanczos::MAX_ORDER {
        return Err(FitError::Options(format!(
            "Lanczos order {} is not supported: use 0, 1 or 2",
            opts.lanczos
        )));
    }
    Ok(())
}

/// What the fit uses: nodes around, the stride and the sections it keeps, the Lanczos order
/// asked and the one the sections allow, and the tolerance's choice when one was given.
struct Plan {
    n: usize,
    stride: usize,
    used: Vec<Section>,
    m_req: usize,
    m: usize,
    choice: Option<Choice>,
}

/// The plan for `sections` (normalized) under `opts`: the nodes, stride and order given, or
/// chosen for the tolerance; refused when the stride does not divide the sections, fewer
/// than 3 are kept, more than [`MAX_LEVELS`] are given, or the node points or the form's
/// vertices would be too many.
fn plan(
    sections: &[Section],
    opts: &FitOptions,
    warnings: &mut Vec<String>,
) -> Result<Plan, FitError> {
    let k_all = sections.len();
    if k_all > MAX_LEVELS {
        return Err(FitError::TooManySections {
            found: k_all,
            limit: MAX_LEVELS,
        });
    }
    let (n, stride, m_req, choice) = match opts.tolerance {
        None => (opts.nodes_around, opts.stride, opts.lanczos, None),
        Some(tol) => choose(sections, tol, warnings),
    };
    if !(k_all - 1).is_multiple_of(stride) {
        return Err(FitError::Options(format!(
            "stride {stride} does not divide the {} intervals between {k_all} sections",
            k_all - 1
        )));
    }
    let used: Vec<Section> = sections.iter().step_by(stride).cloned().collect();
    let k = used.len();
    if k < 3 {
        return Err(FitError::TooFewSections { found: k });
    }
    check_count(
        "--nodes x sections",
        n.saturating_mul(k),
        MAX_NODE_POINTS,
        "node points (nodes around times sections used; use --stride or fewer --nodes)",
    )?;
    check_count(
        "--around x rings",
        opts.around
            .saturating_mul((k - 1) * (opts.along.max(2) - 1).div_ceil(k - 1) + 1),
        MAX_OUTPUT_VERTICES,
        "vertices of the form (--along is rounded up to a multiple of the sections)",
    )?;
    let m = lanczos::order_for(k, m_req);
    if m < m_req {
        warnings.push(format!(
            "Lanczos order lowered from {m_req} to {m}: order {m_req} needs at least {} sections, there are {k}",
            lanczos::nodes_needed(m_req)
        ));
    }
    Ok(Plan {
        n,
        stride,
        used,
        m_req,
        m,
        choice,
    })
}

/// The error estimates of the plan: around (from the nodes), along (from the sections left
/// out, at the plan's and at half its density), and their sum.
fn estimate_error(sections: &[Section], plan: &Plan, warnings: &mut Vec<String>) -> ErrorEstimate {
    let around = around_error(&plan.used, plan.n);
    let (along, along_half) = along_error(sections, plan.n, plan.stride, plan.m);
    if along.is_none() {
        warnings.push("too few sections to estimate the error along the height".into());
    }
    ErrorEstimate {
        around,
        along,
        along_half_density: along_half,
        total: along.map(|a| a + around),
    }
}

/// The form: the surface of `k` node rings tessellated (every section a ring, so the output
/// passes through the nodes, where the girths are), with what it is; a warning when caps were
/// asked and it is not closed.
fn form(
    surface: &surface::Surface,
    k: usize,
    opts: &FitOptions,
    warnings: &mut Vec<String>,
) -> (TriMesh, OutputInfo) {
    let per = (opts.along.max(2) - 1).div_ceil(k - 1);
    let along = (k - 1) * per + 1;
    let mesh = surface.tessellate(along, opts.around, opts.caps);
    let d = diagnose(&mesh);
    if opts.caps && d.shell_state != ShellState::Closed {
        warnings.push(format!(
            "the form is not closed (shell state {}): check the sections for self-intersections",
            d.shell_state
        ));
    }
    let output = OutputInfo {
        along,
        around: opts.around,
        caps: opts.caps,
        vertices: mesh.positions.len(),
        faces: mesh.faces.len(),
        shell_state: d.shell_state,
        volume: d.total_volume,
    };
    (mesh, output)
}

/// The tolerance choice: (nodes around, stride, order, report).
fn choose(
    sections: &[Section],
    tol: f64,
    warnings: &mut Vec<String>,
) -> (usize, usize, usize, Option<Choice>) {
    let half = tol / 2.0;
    let mut n = *AROUND_CANDIDATES.last().unwrap();
    let mut around_best = f64::INFINITY;
    for &cand in &AROUND_CANDIDATES {
        let e = around_error(sections, cand);
        if e < around_best {
            around_best = e;
            n = cand;
        }
        if e <= half {
            n = cand;
            around_best = e;
            break;
        }
    }
    let k = sections.len();
    let mut best: Option<(usize, usize, f64)> = None;
    let mut chosen = None;
    'strides: for stride in (1..k)
        .rev()
        .filter(|&s| (k - 1).is_multiple_of(s) && (k - 1) / s + 1 >= 3)
    {
        for m in 0..=lanczos::MAX_ORDER {
            let ks = (k - 1) / stride + 1;
            if lanczos::order_for(ks, m) < m {
                continue;
            }
            let (e, _) = along_error(sections, n, stride, m);
            let Some(e) = e else { continue };
            if best.is_none_or(|(_, _, b)| e < b) {
                best = Some((stride, m, e));
            }
            if e <= half {
                chosen = Some((stride, m, e));
                break 'strides;
            }
        }
    }
    let met = chosen.is_some() && around_best <= half;
    let (stride, m, along) = chosen.or(best).unwrap_or((1, 1, f64::NAN));
    if !met {
        warnings.push(format!("tolerance {tol} is not reachable with these sections: the best expected error is {:.3e}", around_best + along));
    }
    let expected = (around_best + along)
        .is_finite()
        .then_some(around_best + along);
    (
        n,
        stride,
        m,
        Some(Choice {
            tolerance: tol,
            nodes_around: n,
            stride,
            lanczos: m,
            expected_error: expected,
            met,
        }),
    )
}

/// Slices `mesh` at each target height and measures the convex-hull girth.
pub fn measure_girths(mesh: &TriMesh, targets: &[GirthTarget]) -> Vec<GirthCheck> {
    let Some(b) = mesh.bbox() else {
        return Vec::new();
    };
    let eps = 1e-9 * (b.max.z - b.min.z).max(f64::MIN_POSITIVE);
    let slicer = Slicer::new(mesh);
    targets
        .iter()
        .map(|t| {
            let h = t.height.clamp(b.min.z + eps, b.max.z - eps);
            let pts: Vec<Point2> = slicer.slice(h).iter().flat_map(|l| l.xy()).collect();
            let measured = if pts.len() >= 3 {
                girth(&pts)
            } else {
                f64::NAN
            };
            GirthCheck {
                name: t.name.clone(),
                height: t.height,
                requested: t.requested,
                measured,
                deviation: (measured - t.requested) / t.requested,
            }
        })
        .collect()
}

/// The girth targets of sections themselves: each section's convex-hull perimeter.
pub fn section_targets(sections: &[Section], label: &str) -> Vec<GirthTarget> {
    sections
        .iter()
        .enumerate()
        .map(|(i, s)| GirthTarget {
            name: format!("{label} {}", i + 1),
            height: s.height,
            requested: girth(&s.points),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Elliptic sections with radius varying non-periodically along the height.
    fn sections(k: usize, pts: usize) -> Vec<Section> {
        (0..k)
            .map(|i| {
                let z = 0.3 + 1.2 * i as f64 / (k - 1) as f64;
                let r = 0.2 + 0.05 * (3.0 * z).sin() + 0.02 * z * z;
                let points = (0..pts)
                    .map(|l| {
                        let t = std::f64::consts::TAU * l as f64 / pts as f64;
                        Point2::new(r * t.cos(), 0.7 * r * t.sin())
                    })
                    .collect();
                Section { height: z, points }
            })
            .collect()
    }

    #[test]
    fn fit_reports_girths_and_closes() {
        let s = sections(21, 400);
        let targets = section_targets(&s, "section");
        let f = fit_sections(s, &targets, &FitOptions::default()).unwrap();
        assert_eq!(f.report.output.shell_state, ShellState::Closed);
        assert!(
            f.report.max_girth_deviation < 1e-3,
            "{}",
            f.report.max_girth_deviation
        );
        let e = &f.report.estimated_error;
        assert!(e.around < 1e-4 && e.along.unwrap() < 1e-3, "{e:?}");
    }

    #[test]
    fn tolerance_models_only_what_is_required() {
        let s = sections(41, 400);
        let loose = FitOptions {
            tolerance: Some(5e-3),
            ..FitOptions::default()
        };
        let tight = FitOptions {
            tolerance: Some(1e-5),
            ..FitOptions::default()
        };
        let a = fit_sections(s.clone(), &[], &loose).unwrap().report;
        let b = fit_sections(s, &[], &tight).unwrap().report;
        let (ca, cb) = (a.tolerance.unwrap(), b.tolerance.unwrap());
        assert!(ca.met && cb.met, "{ca:?} {cb:?}");
        assert!(ca.nodes_around < cb.nodes_around, "{ca:?} {cb:?}");
        assert!(a.nodes_along <= b.nodes_along);
        assert!(ca.expected_error.unwrap() <= 5e-3 && cb.expected_error.unwrap() <= 1e-5);
    }
}
