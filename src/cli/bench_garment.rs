//! `drapekit bench garment`: the real patterns sewn and draped on the real bodies, timed.
//!
//! The set: the four GarmentCode patterns of `realdata/patterns/` on `mean_all.obj`,
//! and `dress_pencil` also on `mean_female.obj`, at 1 cm in cotton with the `garment`
//! command's defaults. Each row: particles, the two stages (simulated and wall seconds, the
//! sewing's last seam gap, whether the drape came to rest), the whole wall time (sewing,
//! drape and the measures) and the verdict with what failed. The goal is each garment at
//! rest in at most 60 s of wall time. One run per garment by default (a garment takes tens of
//! seconds to minutes): quote it with the load average. With `--seeds N`, each garment also
//! runs from N - 1 starts perturbed by a tenth of a micron (`garment::perturb`), and a line
//! gives each measure's median and range: the spread that chance alone makes, against which a
//! change to the simulator is judged. With several `--spacing`s (`0.03,0.02,0.01`), each
//! garment runs at each, and a line per coarser spacing says what it costs in shape against
//! the finest (`garment::hang::compare`: the largest difference of a ring's mean height and
//! of its strain along itself) and what it saves in wall time.

use super::garment::{judge, read_body};
use crate::cloth::fabric::Fabric;
use crate::cloth::integrate::Integrator;
use crate::garment::drape::{self as gd, GarmentSettings};
use crate::garment::hang::{compare, HangDifference, RingHang};
use anyhow::Context;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `drapekit bench garment`.
#[derive(Debug, clap::Args)]
pub struct GarmentBench {
    /// The real data (its `patterns/` and `bodies/`); default: `../shared/realdata` beside the
    /// repository.
    #[arg(long, value_name = "DIR")]
    pub realdata: Option<PathBuf>,
    /// Only the runs whose pattern or body name contains this.
    #[arg(long)]
    pub only: Option<String>,
    /// Particle spacing, m; several, comma-separated (`0.03,0.02,0.01`): each garment at each,
    /// compared with the finest.
    #[arg(long, default_value = "0.01", value_delimiter = ',', num_args = 1..)]
    pub spacing: Vec<f64>,
    /// Longest drape after sewing, simulated s.
    #[arg(long, default_value_t = 8.0)]
    pub settle_max: f64,
    /// The fabric preset.
    #[arg(long, default_value = "cotton")]
    pub fabric: String,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
    /// Hold the patterns' waist edges while sewing, as `garment --hold-waist`.
    #[arg(long, default_value = "off", value_name = "off|auto|M")]
    pub hold_waist: String,
    /// Runs per garment: the first from the placement exactly, the others perturbed by a
    /// tenth of a micron with seeds 1, 2, ... (`garment --perturb`); with more than one, a
    /// line per garment gives each measure's median and range.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub seeds: u64,
    /// The integrator, as `garment --integrator` (implicit-euler, the default, or
    /// projective-dynamics).
    #[arg(long, default_value_t = crate::garment::drape::GARMENT_INTEGRATOR)]
    pub integrator: Integrator,
    /// No hinges over the panels' rim bands, as `garment --no-rim-bending` (to measure what
    /// they do: README, `bench garment`).
    #[arg(long)]
    pub no_rim_bending: bool,
    /// Sew at a coarser spacing and drape at `--spacing`, as `garment --sew-spacing`; several,
    /// comma-separated (`off,0.02`): each garment with each.
    #[arg(long, default_value = "off", value_delimiter = ',', num_args = 1..)]
    pub sew_spacing: Vec<String>,
    /// Implicit Euler's bending Hessian, as `garment --bending-hessian`; several,
    /// comma-separated (`exact,lumped`): each garment with each, one after the other.
    #[arg(long, default_values_t = [gd::GARMENT_BENDING_HESSIAN], value_delimiter = ',', num_args = 1..)]
    pub bending_hessian: Vec<crate::cloth::integrate::direct::BendingHessian>,
    /// The drape's seam ramp, as `garment --seam-ramp` (a factor a check, or `off`).
    #[arg(long, default_value = "off", value_name = "F|off")]
    pub seam_ramp: String,
}

/// The runs: (pattern, body).
pub const RUNS: [(&str, &str); 5] = [
    ("dress_pencil", "mean_all"),
    ("shirt_mean", "mean_all"),
    ("hoody_mean", "mean_all"),
    ("js_mean_all", "mean_all"),
    ("dress_pencil", "mean_female"),
];

/// One garment's row.
#[derive(Debug, Serialize)]
pub struct GarmentRow {
    /// The pattern's name.
    pub pattern: String,
    /// The body's name.
    pub body: String,
    /// Particle spacing, m.
    pub spacing: f64,
    /// Particles of the garment.
    pub particles: usize,
    /// Sewing: simulated s, and wall s.
    pub sew_seconds: f64,
    pub sew_wall_seconds: f64,
    /// The widest seam gap when sewing ended, mm.
    pub sew_gap_mm: f64,
    /// The drape: simulated s, and wall s.
    pub drape_seconds: f64,
    pub drape_wall_seconds: f64,
    /// Whether the drape came to rest (the verdict's test) before `--settle-max`.
    pub at_rest: bool,
    /// Sewing, drape and the measures, s.
    pub wall_seconds: f64,
    /// `pass` or `fail`, and what failed.
    pub verdict: String,
    pub failed: Vec<String>,
    /// The waist held while sewing (`--hold-waist`), or `null`.
    pub held_waist: Option<gd::HoldReport>,
    /// The perturbation's seed (`--seeds`), or `null`: the placement exactly.
    pub seed: Option<u64>,
    /// Whether the panels had hinges over their rim bands (`--no-rim-bending`: false).
    pub rim_bending: bool,
    /// The integrator (`--integrator`).
    pub integrator: Integrator,
    /// The spacing the garment was sewn at when coarser than `spacing` (`--sew-spacing`), m.
    pub sew_spacing: Option<f64>,
    /// Implicit Euler's bending Hessian (`--bending-hessian`).
    pub bending_hessian: crate::cloth::integrate::direct::BendingHessian,
    /// The drape's seam ramp (`--seam-ramp`), or `null`: off.
    pub seam_ramp: Option<f64>,
    /// The verdict's measures of the whole garment.
    pub body_crossing_edges: usize,
    pub self_crossing_edges: usize,
    pub max_strain: f64,
    pub seam_gap_max_mm: f64,
    /// How its rings hang (`garment::hang`).
    pub rings: Vec<RingHang>,
    /// Against the same garment and seed at the finest spacing (several `--spacing`s), or
    /// `null`.
    pub against_finest: Option<HangDifference>,
}

/// Runs the benchmark.
pub fn run(a: GarmentBench) -> anyhow::Result<()> {
    let dir = a
        .realdata
        .clone()
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/realdata"));
    let mut sweep = sweep(&a)?;
    let keep = |p: &str, b: &str| {
        a.only
            .as_ref()
            .is_none_or(|o| p.contains(o) || b.contains(o))
    };
    let mut rows = Vec::new();
    for (p, b) in RUNS.into_iter().filter(|(p, b)| keep(p, b)) {
        bench_pair(&a, &dir, (p, b), &mut sweep, &mut rows)?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    }
    Ok(())
}

/// What the flags ask for: the settings every run starts from, the spacings, the sew spacings.
struct Sweep {
    settings: GarmentSettings,
    spacings: Vec<f64>,
    sew_spacings: Vec<Option<f64>>,
}

/// Checks the flags, in order, into the sweep.
fn sweep(a: &GarmentBench) -> anyhow::Result<Sweep> {
    let fabric = Fabric::preset(&a.fabric).with_context(|| format!("--fabric {}", a.fabric))?;
    super::garment::check_stage("--settle-max", a.settle_max)?;
    let mut settings = GarmentSettings::default();
    let spacings = check_spacings(&a.spacing)?;
    settings.assemble.fabric = fabric;
    settings.settle_max = a.settle_max;
    settings.hold_waist = super::garment::hold_waist(&a.hold_waist)?;
    settings.assemble.rim_bending = !a.no_rim_bending;
    settings.solver.integrator = a.integrator;
    settings.seam_ramp = super::garment::seam_ramp(&a.seam_ramp)?;
    let sew_spacings = (a.sew_spacing.iter())
        .map(|v| super::garment::sew_spacing(v))
        .collect::<anyhow::Result<Vec<_>>>()?;
    if let Some(p) = settings
        .problems()
        .into_iter()
        .find(|p| p.field == "integrator" || p.field == "seam_ramp")
    {
        match p.field {
            "seam_ramp" => anyhow::bail!("--seam-ramp {}: {}", a.seam_ramp, p.message),
            _ => anyhow::bail!("--integrator {}", p.message),
        }
    }
    Ok(Sweep {
        settings,
        spacings,
        sew_spacings,
    })
}

/// Pattern `p` on body `b`: a row for each spacing, seed, sew spacing and bending Hessian
/// (printed as it comes unless `--json`), each spacing's spread over the seeds, and each
/// row against the finest spacing.
fn bench_pair(
    a: &GarmentBench,
    dir: &Path,
    (p, b): (&str, &str),
    sweep: &mut Sweep,
    rows: &mut Vec<GarmentRow>,
) -> anyhow::Result<()> {
    let pattern_path = dir.join(format!("patterns/{p}_specification.json"));
    let pattern = crate::garment::read(&pattern_path)?;
    let body = read_body(&dir.join(format!("bodies/{b}.obj")), "auto", &pattern)?.mesh;
    let (settings, spacings) = (&mut sweep.settings, &sweep.spacings);
    let first = rows.len();
    for &h in spacings {
        settings.assemble.spacing = h;
        let at = rows.len();
        for seed in (0..a.seeds).map(|k| (k > 0).then_some(k)) {
            settings.perturb = seed;
            for (&sew, &hessian) in (sweep.sew_spacings.iter())
                .flat_map(|s| a.bending_hessian.iter().map(move |h| (s, h)))
            {
                settings.sew_spacing = sew;
                settings.solver.bending_hessian = hessian;
                let row = run_one(&pattern, &body, (p, b), settings)?;
                if !a.json {
                    print_row(&row, spacings.len() > 1);
                }
                rows.push(row);
            }
        }
        if a.seeds > 1 && !a.json {
            print_spread(&rows[at..]);
        }
    }
    if spacings.len() > 1 || a.seeds > 1 {
        against_finest(&mut rows[first..]);
        if !a.json {
            print_against_finest(&rows[first..]);
        }
    }
    Ok(())
}

/// One garment sewn and draped with `settings`, as its row.
fn run_one(
    pattern: &crate::garment::Pattern,
    body: &crate::mesh::TriMesh,
    (p, b): (&str, &str),
    settings: &GarmentSettings,
) -> anyhow::Result<GarmentRow> {
    let t = Instant::now();
    let g = gd::sew_and_drape(
        pattern,
        vec![gd::body_collider(body.clone())],
        settings,
        &|_| {},
        None,
    )?;
    let j = judge(&g);
    Ok(GarmentRow {
        pattern: p.into(),
        body: b.into(),
        particles: g.world.model.len(),
        sew_seconds: g.sew.time,
        sew_wall_seconds: g.sew.wall_seconds,
        sew_gap_mm: g.sew.seam_gap_max * 1e3,
        drape_seconds: g.drape.time,
        drape_wall_seconds: g.drape.wall_seconds,
        at_rest: g.drape.done,
        wall_seconds: t.elapsed().as_secs_f64(),
        verdict: if j.failed.is_empty() { "pass" } else { "fail" }.into(),
        failed: j.failed,
        held_waist: g.hold,
        seed: settings.perturb,
        rim_bending: settings.assemble.rim_bending,
        integrator: settings.solver.integrator,
        sew_spacing: (settings.sew_spacing).filter(|&s| s > settings.assemble.spacing),
        bending_hessian: settings.solver.bending_hessian,
        seam_ramp: settings.seam_ramp,
        body_crossing_edges: j.whole.body_crossing_edges,
        self_crossing_edges: j.whole.self_crossing_edges,
        max_strain: j.whole.max_strain,
        seam_gap_max_mm: j.whole.seam_gap_max_mm,
        rings: g.rings,
        against_finest: None,
        spacing: settings.assemble.spacing,
    })
}

/// The `--spacing`s, finest last; every one out of range named before any work.
fn check_spacings(spacings: &[f64]) -> anyhow::Result<Vec<f64>> {
    let bad: Vec<String> = (spacings.iter())
        .filter(|&&h| {
            let mut s = GarmentSettings::default();
            s.assemble.spacing = h;
            s.problems().iter().any(|p| p.field == "spacing")
        })
        .map(|&h| crate::math::short(h))
        .collect();
    if !bad.is_empty() {
        let [lo, hi] = gd::SPACING_RANGE;
        anyhow::bail!("--spacing {}: each must be {lo} to {hi} m", bad.join(","));
    }
    let mut out = spacings.to_vec();
    out.sort_by(|a, b| b.total_cmp(a));
    out.dedup();
    Ok(out)
}

/// Each row of one garment against the row of its seed at the finest spacing (the last); a
/// perturbed row at the finest spacing against the unperturbed one (what chance alone moves).
fn against_finest(rows: &mut [GarmentRow]) {
    let finest = rows.last().map_or(0.0, |r| r.spacing);
    let reference: Vec<(Option<u64>, Vec<RingHang>)> = (rows.iter())
        .filter(|r| r.spacing == finest)
        .map(|r| (r.seed, r.rings.clone()))
        .collect();
    for r in rows.iter_mut() {
        let seed = if r.spacing == finest { None } else { r.seed };
        let same = r.spacing == finest && r.seed.is_none();
        let of_seed = reference.iter().find(|(s, _)| *s == seed).filter(|_| !same);
        r.against_finest = of_seed.and_then(|(_, rings)| compare(&r.rings, rings));
    }
}

/// One line per coarser spacing or perturbed start: its shape against the finest (the same
/// seed, or the placement exactly), and its wall time.
fn print_against_finest(rows: &[GarmentRow]) {
    let Some(finest) = rows.last() else {
        return;
    };
    let wall = |h: f64| {
        let w: Vec<f64> = (rows.iter().filter(|r| r.spacing == h))
            .map(|r| r.wall_seconds)
            .collect();
        super::bench::median(&w)
    };
    let fine_wall = wall(finest.spacing);
    for r in rows {
        let Some(d) = &r.against_finest else {
            continue;
        };
        let (seed, against) = match r.seed {
            Some(s) if r.spacing == finest.spacing => (format!(" (seed {s})"), " unperturbed"),
            Some(s) => (format!(" (seed {s})"), ""),
            None => (String::new(), ""),
        };
        println!(
            "    at {} cm{seed} against {} cm{against}: rings' heights within {:.1} cm ({}), their strain \
             within {:.1} points ({}); {:.2}x the wall time",
            crate::math::short(r.spacing * 100.0),
            crate::math::short(finest.spacing * 100.0),
            d.height_m * 100.0,
            d.height_ring,
            d.strain * 100.0,
            d.strain_ring,
            wall(r.spacing) / fine_wall
        );
    }
}

/// The median and the range of `v` (not empty).
fn spread(v: &[f64]) -> (f64, f64, f64) {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (super::bench::median(v), lo, hi)
}

/// One line: each measure's median and range over one garment's runs.
fn print_spread(rows: &[GarmentRow]) {
    let of = |f: &dyn Fn(&GarmentRow) -> f64| {
        let (m, lo, hi) = spread(&rows.iter().map(f).collect::<Vec<_>>());
        let short = crate::math::short;
        format!("{} ({} to {})", short(m), short(lo), short(hi))
    };
    let rest = rows.iter().filter(|r| r.at_rest).count();
    println!(
        "    over {} runs, median (range): through the body {}; through the cloth {}; \
         strain {} %; wall {} s; at rest {rest} of {}",
        rows.len(),
        of(&|r| r.body_crossing_edges as f64),
        of(&|r| r.self_crossing_edges as f64),
        of(&|r| (r.max_strain * 1e4).round() / 100.0),
        of(&|r| (r.wall_seconds * 10.0).round() / 10.0),
        rows.len()
    );
}

/// One line per garment (its spacing named when `spacing`; an integrator other than the
/// garments' default named), then what failed.
fn print_row(r: &GarmentRow, spacing: bool) {
    let at = if spacing {
        format!(" at {} cm", crate::math::short(r.spacing * 100.0))
    } else {
        String::new()
    };
    let label = at
        + &r.seed
            .map(|s| format!(" (perturbed, seed {s})"))
            .unwrap_or_default()
        + if r.rim_bending {
            ""
        } else {
            " (no rim hinges)"
        }
        + &if r.integrator == gd::GARMENT_INTEGRATOR {
            String::new()
        } else {
            format!(" ({})", r.integrator)
        }
        + &r.sew_spacing
            .map(|s| format!(" (sewn at {} cm)", crate::math::short(s * 100.0)))
            .unwrap_or_default()
        + &if r.bending_hessian == gd::GARMENT_BENDING_HESSIAN {
            String::new()
        } else {
            format!(" ({} bending Hessian)", r.bending_hessian)
        };
    println!(
        "{} on {}{label}: {} particles; sewing {:.2} s ({:.1} s wall, gap {:.1} mm); drape \
         {:.2} s ({:.1} s wall, {}); {:.1} s wall in all; {}",
        r.pattern,
        r.body,
        r.particles,
        r.sew_seconds,
        r.sew_wall_seconds,
        r.sew_gap_mm,
        r.drape_seconds,
        r.drape_wall_seconds,
        if r.at_rest { "at rest" } else { "NOT at rest" },
        r.wall_seconds,
        r.verdict
    );
    if let Some(h) = &r.held_waist {
        let (n, from, to, level) = (h.particles, h.from, h.to, h.level);
        println!("    waist held: {n} particles from {from:.3} to {to:.3} m (level {level:.3} m)");
    }
    for f in &r.failed {
        println!("    {f}");
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_spread_is_the_median_and_the_range() {
        assert_eq!(super::spread(&[3.0, 1.0, 10.0, 2.0]), (2.5, 1.0, 10.0));
        assert_eq!(super::spread(&[7.0]), (7.0, 7.0, 7.0));
    }
}
