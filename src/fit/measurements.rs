//! Dress forms from body measurements: the shape model.
//!
//! Keys (TOML, after ISO 8559-1; lengths in `units`, default `cm`): `stature` and at least two of
//! the girths `neck_base_girth`, `bust_girth`, `underbust_girth`, `waist_girth`, `top_hip_girth`,
//! `hip_girth`. Optional: each girth's level as `<name>_height` (above the floor), each level's
//! `<name>_width` (left-right) and `<name>_depth` (front-back), `shoulder_width`,
//! `shoulder_height`, `bottom_height` (where the form ends below the hips).
//!
//! **Levels** (a fraction of the stature by default; a default level between given ones is
//! placed proportionally between them). **Sections** are superellipses
//! `|x/a|^p + |(y - c)/b|^p = 1`, front towards -y, with a depth/width ratio `b/a`, an exponent
//! `p` (2 is an ellipse, larger is boxier) and a front-back offset `c` per level. Defaults, as
//! fractions of the stature, were measured on the GarmentCode mean bodies
//! (`shared/realdata/bodies`, MIT) with `drapekit`'s own slicer:
//!
//! | level | height | girth | depth/width | p | offset |
//! |---|---|---|---|---|---|
//! | bottom | 0.465 | 0.600 | 0.62 | 2.2 | +0.006 |
//! | hip | 0.495 | 0.615 | 0.68 | 2.3 | +0.010 |
//! | top_hip | 0.557 | 0.580 | 0.75 | 2.2 | +0.002 |
//! | waist | 0.631 | 0.490 | 0.76 | 2.1 | -0.009 |
//! | underbust | 0.683 | 0.500 | 0.76 | 2.3 | -0.003 |
//! | bust | 0.721 | 0.580 | 0.76 | 2.7 | -0.006 |
//! | chest (armpit) | 0.745 | 0.585 | 0.72 | 2.6 | 0.000 |
//! | shoulder | 0.815 | width 0.220 | 0.40 | 2.8 | +0.012 |
//! | neck_base | 0.845 | 0.225 | 0.95 | 2.0 | +0.005 |
//! | neck_top | 0.875 | 0.215 | 0.95 | 2.0 | +0.002 |
//!
//! **Girths.** A given girth is kept exactly: each section is scaled so that its perimeter,
//! which for a convex section is its convex-hull girth, equals it. A missing girth is its
//! default times the ratio given/default of the nearest given girths (interpolated linearly in
//! height, constant beyond them); the shoulder width scales the same way. A given width or
//! depth sets the depth/width ratio at its level; the girth still decides the size.
//!
//! **Between the levels** the girth, ratio, exponent and offset follow monotone cubic (PCHIP)
//! interpolation in height, with no overshoot. Sections are generated at every level and at
//! even spacing in between, about `levels` in all.
//!
//! **Limits.** Every section must be finite numbers, so lengths whose products and quotients
//! leave the range of an f64 are refused by key: a stature outside 1e-100..1e100, a girth,
//! width or depth over 10 times the stature, a girth under 1e-6 of it, levels closer than 1e-6
//! of the stature.

use super::error::FitError;
use super::fitter::GirthTarget;
use super::section::{perimeter, Section};
use crate::math::{short, Point2};
use crate::mesh::transform::Units;
use serde::Deserialize;
use std::path::Path;

/// A measurements file.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct Measurements {
    /// Units of every length (default `cm`).
    pub units: Option<String>,
    /// Stature (required).
    pub stature: Option<f64>,
    pub neck_base_girth: Option<f64>,
    pub bust_girth: Option<f64>,
    pub underbust_girth: Option<f64>,
    pub waist_girth: Option<f64>,
    pub top_hip_girth: Option<f64>,
    pub hip_girth: Option<f64>,
    pub neck_base_height: Option<f64>,
    pub bust_height: Option<f64>,
    pub underbust_height: Option<f64>,
    pub waist_height: Option<f64>,
    pub top_hip_height: Option<f64>,
    pub hip_height: Option<f64>,
    pub bottom_height: Option<f64>,
    pub shoulder_height: Option<f64>,
    pub shoulder_width: Option<f64>,
    pub neck_base_width: Option<f64>,
    pub neck_base_depth: Option<f64>,
    pub bust_width: Option<f64>,
    pub bust_depth: Option<f64>,
    pub underbust_width: Option<f64>,
    pub underbust_depth: Option<f64>,
    pub waist_width: Option<f64>,
    pub waist_depth: Option<f64>,
    pub top_hip_width: Option<f64>,
    pub top_hip_depth: Option<f64>,
    pub hip_width: Option<f64>,
    pub hip_depth: Option<f64>,
}

/// A level of the shape model: defaults as fractions of the stature.
struct LevelDef {
    name: &'static str,
    height: f64,
    girth: f64,
    ratio: f64,
    exponent: f64,
    offset: f64,
}

const LEVELS: [LevelDef; 10] = [
    LevelDef {
        name: "bottom",
        height: 0.465,
        girth: 0.600,
        ratio: 0.62,
        exponent: 2.2,
        offset: 0.006,
    },
    LevelDef {
        name: "hip",
        height: 0.495,
        girth: 0.615,
        ratio: 0.68,
        exponent: 2.3,
        offset: 0.010,
    },
    LevelDef {
        name: "top_hip",
        height: 0.557,
        girth: 0.580,
        ratio: 0.75,
        exponent: 2.2,
        offset: 0.002,
    },
    LevelDef {
        name: "waist",
        height: 0.631,
        girth: 0.490,
        ratio: 0.76,
        exponent: 2.1,
        offset: -0.009,
    },
    LevelDef {
        name: "underbust",
        height: 0.683,
        girth: 0.500,
        ratio: 0.76,
        exponent: 2.3,
        offset: -0.003,
    },
    LevelDef {
        name: "bust",
        height: 0.721,
        girth: 0.580,
        ratio: 0.76,
        exponent: 2.7,
        offset: -0.006,
    },
    LevelDef {
        name: "chest",
        height: 0.745,
        girth: 0.585,
        ratio: 0.72,
        exponent: 2.6,
        offset: 0.000,
    },
    LevelDef {
        name: "shoulder",
        height: 0.815,
        girth: f64::NAN,
        ratio: 0.40,
        exponent: 2.8,
        offset: 0.012,
    },
    LevelDef {
        name: "neck_base",
        height: 0.845,
        girth: 0.225,
        ratio: 0.95,
        exponent: 2.0,
        offset: 0.005,
    },
    LevelDef {
        name: "neck_top",
        height: 0.875,
        girth: 0.215,
        ratio: 0.95,
        exponent: 2.0,
        offset: 0.002,
    },
];

/// Default shoulder width as a fraction of the stature.
const SHOULDER_WIDTH: f64 = 0.220;

/// Points sampled on each superellipse before resampling.
const SHAPE_POINTS: usize = 720;

/// The stature's range, in the file's units: far beyond it the shape model's products and
/// quotients of lengths (PCHIP's slopes and their harmonic means) leave the range of an f64
/// (at a stature of 1e-300 they underflow to an infinite slope).
const STATURE_RANGE: (f64, f64) = (1e-100, 1e100);

/// The most a girth, width or depth may be, as a multiple of the stature (a body's largest
/// girth is about 0.6 of it); beyond, the model's sections need not be finite.
const MAX_TO_STATURE: f64 = 10.0;

/// The least a girth may be, as a fraction of the stature: far below, its section is lost in
/// the rounding of the model's coordinates (a bust of 1e-20 cm on a 170 cm body collapsed to
/// a line, refused as 'section 26 is degenerate').
const MIN_GIRTH_TO_STATURE: f64 = 1e-6;

/// The least distance between two levels, as a fraction of the stature (the default levels are
/// 0.024 to 0.07 apart): closer levels give PCHIP slopes that overflow.
const MIN_LEVEL_GAP: f64 = 1e-6;

/// Reads a measurements file.
pub fn read(path: &Path) -> Result<Measurements, FitError> {
    let text = std::fs::read_to_string(path).map_err(|source| FitError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    read_str(&text, path)
}

/// Reads a measurements file's text (`path` names it in errors).
pub fn read_str(text: &str, path: &Path) -> Result<Measurements, FitError> {
    toml::from_str(text).map_err(|e| FitError::Toml {
        path: path.to_path_buf(),
        message: crate::scene::toml_message(text, &e),
    })
}

/// The superellipse of half-width `a`, depth/width `ratio`, exponent `p`, offset `c`, sampled
/// counter-clockwise.
fn superellipse(a: f64, ratio: f64, p: f64, c: f64) -> Vec<Point2> {
    let e = 2.0 / p;
    (0..SHAPE_POINTS)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / SHAPE_POINTS as f64;
            let (s, co) = t.sin_cos();
            Point2::new(
                a * co.signum() * co.abs().powf(e),
                c + a * ratio * s.signum() * s.abs().powf(e),
            )
        })
        .collect()
}

/// The superellipse with this girth (perimeter), ratio, exponent and offset.
fn section_with_girth(girth: f64, ratio: f64, p: f64, c: f64) -> Vec<Point2> {
    let unit = superellipse(1.0, ratio, p, 0.0);
    let a = girth / perimeter(&unit);
    superellipse(a, ratio, p, c)
}

/// The depth/width ratio giving a section of this girth the given width (or depth).
fn ratio_for(girth: f64, p: f64, width: Option<f64>, depth: Option<f64>) -> Option<f64> {
    match (width, depth) {
        (Some(w), Some(d)) => Some(d / w),
        (None, None) => None,
        (w, d) => {
            // Perimeter of the unit-width shape grows with the ratio: bisect on it.
            let target = match (w, d) {
                (Some(w), _) => girth / w,
                (_, Some(d)) => girth / d,
                _ => unreachable!(),
            };
            let per = |r: f64| {
                let s = superellipse(0.5, r, p, 0.0);
                match w {
                    Some(_) => perimeter(&s),
                    None => perimeter(&s) / r,
                }
            };
            let (mut lo, mut hi) = (0.05f64, 20.0f64);
            for _ in 0..100 {
                let mid = (lo * hi).sqrt();
                let grows = w.is_some();
                if (per(mid) < target) == grows {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            Some((lo * hi).sqrt())
        }
    }
}

/// Monotone cubic interpolation (Fritsch-Carlson) of `ys` over increasing `xs`, at `x`.
pub fn pchip(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let n = xs.len();
    if x <= xs[0] {
        return ys[0];
    }
    if x >= xs[n - 1] {
        return ys[n - 1];
    }
    let h: Vec<f64> = xs.windows(2).map(|w| w[1] - w[0]).collect();
    let d: Vec<f64> = (0..n - 1).map(|i| (ys[i + 1] - ys[i]) / h[i]).collect();
    let mut m = vec![0.0; n];
    m[0] = d[0];
    m[n - 1] = d[n - 2];
    for i in 1..n - 1 {
        if d[i - 1] * d[i] > 0.0 {
            let (w1, w2) = (2.0 * h[i] + h[i - 1], h[i] + 2.0 * h[i - 1]);
            m[i] = (w1 + w2) / (w1 / d[i - 1] + w2 / d[i]);
        }
    }
    let i = xs.windows(2).position(|w| x < w[1]).unwrap_or(n - 2);
    let t = (x - xs[i]) / h[i];
    let (t2, t3) = (t * t, t * t * t);
    ys[i] * (2.0 * t3 - 3.0 * t2 + 1.0)
        + m[i] * h[i] * (t3 - 2.0 * t2 + t)
        + ys[i + 1] * (-2.0 * t3 + 3.0 * t2)
        + m[i + 1] * h[i] * (t3 - t2)
}

/// Piecewise-linear interpolation, constant beyond the ends.
fn linear(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    if x <= xs[0] {
        return ys[0];
    }
    if x >= xs[xs.len() - 1] {
        return ys[ys.len() - 1];
    }
    let i = xs.windows(2).position(|w| x < w[1]).unwrap_or(xs.len() - 2);
    ys[i] + (ys[i + 1] - ys[i]) * (x - xs[i]) / (xs[i + 1] - xs[i])
}

/// The problems of a measurement set, by key, collected so that all are reported at once.
#[derive(Default)]
struct Problems(Vec<(String, String)>);

impl Problems {
    fn bad(&mut self, key: &str, message: String) {
        self.0.push((key.to_string(), message));
    }

    /// Whether `key` has a problem already.
    fn has(&self, key: &str) -> bool {
        self.0.iter().any(|(k, _)| k == key)
    }

    /// `v` when absent or a positive number; else a problem, and `None`.
    fn positive(&mut self, key: &str, v: Option<f64>) -> Option<f64> {
        match v {
            Some(x) if !(x.is_finite() && x > 0.0) => {
                self.bad(key, format!("must be a positive number, got {}", short(x)));
                None
            }
            _ => v,
        }
    }

    /// `Ok` when there is no problem; else the error naming each (emptied for the next checks).
    fn take(&mut self, path: &Path) -> Result<(), FitError> {
        FitError::from_keys(path, std::mem::take(&mut self.0))
    }
}

/// The girths: (key, level, value).
fn girth_keys(m: &Measurements) -> [(&'static str, &'static str, Option<f64>); 6] {
    [
        ("neck_base_girth", "neck_base", m.neck_base_girth),
        ("bust_girth", "bust", m.bust_girth),
        ("underbust_girth", "underbust", m.underbust_girth),
        ("waist_girth", "waist", m.waist_girth),
        ("top_hip_girth", "top_hip", m.top_hip_girth),
        ("hip_girth", "hip", m.hip_girth),
    ]
}

/// The lengths across the body (girths, widths, depths): (key, value).
fn across_keys(m: &Measurements) -> [(&'static str, Option<f64>); 19] {
    [
        ("neck_base_girth", m.neck_base_girth),
        ("bust_girth", m.bust_girth),
        ("underbust_girth", m.underbust_girth),
        ("waist_girth", m.waist_girth),
        ("top_hip_girth", m.top_hip_girth),
        ("hip_girth", m.hip_girth),
        ("shoulder_width", m.shoulder_width),
        ("neck_base_width", m.neck_base_width),
        ("neck_base_depth", m.neck_base_depth),
        ("bust_width", m.bust_width),
        ("bust_depth", m.bust_depth),
        ("underbust_width", m.underbust_width),
        ("underbust_depth", m.underbust_depth),
        ("waist_width", m.waist_width),
        ("waist_depth", m.waist_depth),
        ("top_hip_width", m.top_hip_width),
        ("top_hip_depth", m.top_hip_depth),
        ("hip_width", m.hip_width),
        ("hip_depth", m.hip_depth),
    ]
}

/// Each level's height key and value, in the order of `LEVELS` (the chest and the neck's top
/// have none: `""`).
fn height_keys(m: &Measurements) -> [(&'static str, Option<f64>); 10] {
    [
        ("bottom_height", m.bottom_height),
        ("hip_height", m.hip_height),
        ("top_hip_height", m.top_hip_height),
        ("waist_height", m.waist_height),
        ("underbust_height", m.underbust_height),
        ("bust_height", m.bust_height),
        ("", None),
        ("shoulder_height", m.shoulder_height),
        ("neck_base_height", m.neck_base_height),
        ("", None),
    ]
}

/// Each level's given width and depth, in the order of `LEVELS`.
fn width_keys(m: &Measurements) -> [(Option<f64>, Option<f64>); 10] {
    [
        (None, None),
        (m.hip_width, m.hip_depth),
        (m.top_hip_width, m.top_hip_depth),
        (m.waist_width, m.waist_depth),
        (m.underbust_width, m.underbust_depth),
        (m.bust_width, m.bust_depth),
        (None, None),
        (m.shoulder_width, None),
        (m.neck_base_width, m.neck_base_depth),
        (None, None),
    ]
}

/// The units and the stature, every problem of the keys given to `p` (stand-ins then:
/// centimetres, a stature of 1).
fn check_keys(m: &Measurements, p: &mut Problems) -> (Units, f64) {
    let units = m
        .units
        .as_deref()
        .unwrap_or("cm")
        .parse()
        .unwrap_or_else(|e| {
            p.bad("units", e);
            Units::Cm
        });
    let stature = match m.stature {
        None => {
            p.bad("stature", "is required".into());
            None
        }
        Some(s) => p.positive("stature", Some(s)).filter(|&s| {
            let inside = (STATURE_RANGE.0..=STATURE_RANGE.1).contains(&s);
            if !inside {
                let m = format!(
                    "{} is outside {:e}..{:e} (beyond, the shape model's arithmetic leaves the range of an f64)",
                    short(s), STATURE_RANGE.0, STATURE_RANGE.1
                );
                p.bad("stature", m);
            }
            inside
        }),
    };
    check_girths(m, stature, p);
    check_heights(m, stature, p);
    (units, stature.unwrap_or(1.0))
}

/// The girths positive, at least two of them, and no length across the body over
/// `MAX_TO_STATURE` statures (`stature`: `None` when it has a problem).
fn check_girths(m: &Measurements, stature: Option<f64>, p: &mut Problems) {
    let girths = girth_keys(m);
    for (k, _, v) in girths {
        let (Some(v), Some(s)) = (p.positive(k, v), stature) else {
            continue;
        };
        if v < MIN_GIRTH_TO_STATURE * s {
            let m = format!(
                "{} is less than {MIN_GIRTH_TO_STATURE:e} of the stature {}: no body is that thin",
                short(v),
                short(s)
            );
            p.bad(k, m);
        }
    }
    for (k, v) in across_keys(m) {
        let (Some(s), Some(v)) = (stature, v) else {
            continue;
        };
        if v > MAX_TO_STATURE * s && !p.has(k) {
            let m = format!(
                "{} is more than {MAX_TO_STATURE} times the stature {}: no body is that wide",
                short(v),
                short(s)
            );
            p.bad(k, m);
        }
    }
    let given = girths.iter().filter(|g| g.2.is_some()).count();
    if given < 2 {
        p.bad("*_girth", format!("at least two girths are required, {given} given (neck_base, bust, underbust, waist, top_hip, hip)"));
    }
}

/// The given heights positive and below the stature.
fn check_heights(m: &Measurements, stature: Option<f64>, p: &mut Problems) {
    for (k, v) in height_keys(m) {
        if let (Some(h), Some(s)) = (p.positive(k, v), stature) {
            if h >= s {
                p.bad(k, format!("{h} is not below the stature {s}"));
            }
        }
    }
}

/// The height of every level: given, or its default placed proportionally between the given
/// heights below and above it (the floor and the stature as the ends).
fn level_heights(m: &Measurements, stature: f64) -> Vec<f64> {
    let heights = height_keys(m);
    let mut anchors_f = vec![0.0];
    let mut anchors_h = vec![0.0];
    for (i, (_, v)) in heights.iter().enumerate() {
        if let Some(h) = v {
            anchors_f.push(LEVELS[i].height);
            anchors_h.push(*h);
        }
    }
    anchors_f.push(1.0);
    anchors_h.push(stature);
    LEVELS
        .iter()
        .enumerate()
        .map(|(i, l)| {
            heights[i]
                .1
                .unwrap_or_else(|| linear(&anchors_f, &anchors_h, l.height))
        })
        .collect()
}

/// Each level at least `MIN_LEVEL_GAP` statures above the one below (the problem under the
/// upper level's key when it was given, else the lower one's, else `stature`).
fn check_level_gaps(m: &Measurements, z: &[f64], stature: f64, p: &mut Problems) {
    let heights = height_keys(m);
    let given = |j: usize| heights[j].1.map(|_| heights[j].0);
    let name = |j: usize| match given(j) {
        Some(key) => key.to_string(),
        None => format!("the {} level (default)", LEVELS[j].name),
    };
    for i in 1..z.len() {
        if z[i] - z[i - 1] >= MIN_LEVEL_GAP * stature {
            continue;
        }
        let why = if z[i] <= z[i - 1] {
            String::new()
        } else {
            format!(" by {MIN_LEVEL_GAP:e} of the stature (levels closer than that make the model's slopes overflow)")
        };
        let key = given(i).or(given(i - 1)).unwrap_or("stature");
        let m = format!(
            "{} at {} is not above {} at {}{why}",
            name(i),
            z[i],
            name(i - 1),
            z[i - 1]
        );
        p.bad(key, m);
    }
}

/// The shape of every level: girth, depth/width ratio, exponent and front-back offset.
struct LevelShapes {
    girth: Vec<f64>,
    ratio: Vec<f64>,
    exponent: Vec<f64>,
    offset: Vec<f64>,
}

/// The levels' shapes: each girth given, or its default times the ratio given/default of the
/// given girths interpolated linearly in height at `z`; a given width or depth sets the ratio.
fn level_shapes(m: &Measurements, z: &[f64], stature: f64, p: &mut Problems) -> LevelShapes {
    let girths = girth_keys(m);
    let level_of = |name: &str| LEVELS.iter().position(|l| l.name == name).unwrap();
    let mut rz = Vec::new();
    let mut rr = Vec::new();
    for (_, name, v) in girths {
        if let Some(g) = v {
            let i = level_of(name);
            rz.push(z[i]);
            rr.push(g / (LEVELS[i].girth * stature));
        }
    }
    let mut order: Vec<usize> = (0..rz.len()).collect();
    order.sort_by(|&a, &b| rz[a].total_cmp(&rz[b]));
    let (rz, rr): (Vec<f64>, Vec<f64>) = order.iter().map(|&i| (rz[i], rr[i])).unzip();
    let scale_at = |h: f64| linear(&rz, &rr, h);
    let widths = width_keys(m);
    let n = LEVELS.len();
    let mut s = LevelShapes {
        girth: vec![0.0; n],
        ratio: LEVELS.iter().map(|l| l.ratio).collect(),
        exponent: LEVELS.iter().map(|l| l.exponent).collect(),
        offset: LEVELS.iter().map(|l| l.offset * stature).collect(),
    };
    for (i, l) in LEVELS.iter().enumerate() {
        if l.name == "shoulder" {
            let w = m
                .shoulder_width
                .unwrap_or(SHOULDER_WIDTH * stature * scale_at(z[i]));
            p.positive("shoulder_width", Some(w));
            s.girth[i] = w * perimeter(&superellipse(0.5, l.ratio, l.exponent, 0.0));
            continue;
        }
        let given = girths.iter().find(|g| g.1 == l.name).and_then(|g| g.2);
        s.girth[i] = given.unwrap_or(l.girth * stature * scale_at(z[i]));
        let (w, d) = widths[i];
        if let Some(r) = ratio_for(s.girth[i], l.exponent, w, d) {
            if !(r.is_finite() && r > 0.05 && r < 20.0) {
                let m = "the width and depth do not fit the girth".into();
                let side = if w.is_some() { "width" } else { "depth" };
                p.bad(&format!("{}_{side}", l.name), m);
            }
            s.ratio[i] = r;
        }
    }
    s
}

/// The section heights: every level, and even spacing in between, about `levels` in all.
fn section_heights(z: &[f64], levels: usize) -> Vec<f64> {
    let span = z[z.len() - 1] - z[0];
    let mut hs = vec![z[0]];
    for w in z.windows(2) {
        let parts = (((w[1] - w[0]) / span) * (levels.max(3) - 1) as f64)
            .round()
            .max(1.0) as usize;
        for p in 1..=parts {
            hs.push(w[0] + (w[1] - w[0]) * p as f64 / parts as f64);
        }
    }
    hs
}

/// The sections and girth targets of the shape model for `m`, about `levels` sections. Every
/// problem of the keys is reported at once (`FitError::Key` for one, `FitError::Keys` for
/// more).
pub fn sections(
    m: &Measurements,
    path: &Path,
    levels: usize,
) -> Result<(Vec<Section>, Vec<GirthTarget>, Units), FitError> {
    let mut p = Problems::default();
    let (units, stature) = check_keys(m, &mut p);
    p.take(path)?;
    let z = level_heights(m, stature);
    check_level_gaps(m, &z, stature, &mut p);
    p.take(path)?;
    let shapes = level_shapes(m, &z, stature, &mut p);
    p.take(path)?;
    let sections = section_heights(&z, levels)
        .into_iter()
        .map(|h| Section {
            height: h,
            points: section_with_girth(
                pchip(&z, &shapes.girth, h),
                pchip(&z, &shapes.ratio, h),
                pchip(&z, &shapes.exponent, h),
                pchip(&z, &shapes.offset, h),
            ),
        })
        .collect();
    let level_of = |name: &str| LEVELS.iter().position(|l| l.name == name).unwrap();
    let targets = girth_keys(m)
        .iter()
        .filter_map(|(_, name, v)| {
            v.map(|g| GirthTarget {
                name: name.to_string(),
                height: z[level_of(name)],
                requested: g,
            })
        })
        .collect();
    Ok((sections, targets, units))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::slice::girth;

    #[test]
    fn pchip_is_monotone_and_interpolates() {
        let xs = [0.0, 1.0, 2.0, 3.0];
        let ys = [0.0, 1.0, 1.0, 5.0];
        for (x, y) in xs.iter().zip(ys) {
            assert_eq!(pchip(&xs, &ys, *x), y);
        }
        // Flat between 1 and 2: no overshoot.
        for i in 0..=10 {
            assert!((pchip(&xs, &ys, 1.0 + i as f64 / 10.0) - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn sections_carry_the_given_girths_exactly() {
        let m = Measurements {
            stature: Some(166.0),
            bust_girth: Some(97.0),
            waist_girth: Some(80.0),
            hip_girth: Some(104.0),
            ..Default::default()
        };
        let (s, t, u) = sections(&m, Path::new("m.toml"), 41).unwrap();
        assert_eq!(u, Units::Cm);
        assert_eq!(t.len(), 3);
        for target in &t {
            let sec = s
                .iter()
                .find(|s| s.height == target.height)
                .expect("a section at every level");
            assert!((girth(&sec.points) - target.requested).abs() < 1e-9 * target.requested);
        }
        assert!(s.windows(2).all(|w| w[1].height > w[0].height));
        assert!((35..50).contains(&s.len()), "{}", s.len());
    }

    #[test]
    fn a_given_width_sets_the_ratio() {
        let r = ratio_for(90.0, 2.3, Some(32.0), None).unwrap();
        let s = section_with_girth(90.0, r, 2.3, 0.0);
        let w = s.iter().map(|p| p.x).fold(f64::MIN, f64::max)
            - s.iter().map(|p| p.x).fold(f64::MAX, f64::min);
        assert!((w - 32.0).abs() < 1e-3, "{w}");
    }

    #[test]
    fn errors_name_the_key() {
        let p = Path::new("m.toml");
        let one = Measurements {
            stature: Some(166.0),
            waist_girth: Some(80.0),
            ..Default::default()
        };
        assert!(sections(&one, p, 41)
            .unwrap_err()
            .to_string()
            .contains("at least two girths are required, 1 given"));
        let bad = Measurements {
            stature: Some(166.0),
            waist_girth: Some(80.0),
            hip_girth: Some(-3.0),
            ..Default::default()
        };
        assert_eq!(
            sections(&bad, p, 41).unwrap_err().to_string(),
            "m.toml: key 'hip_girth': must be a positive number, got -3"
        );
        // A huge negative or a tiny one in short numbers, never 300 digits.
        for (x, shown) in [(-1e300, "-1.000e300"), (-1.0 / 3.0, "-0.3333")] {
            let bad = Measurements {
                stature: Some(166.0),
                waist_girth: Some(80.0),
                hip_girth: Some(x),
                ..Default::default()
            };
            assert_eq!(
                sections(&bad, p, 41).unwrap_err().to_string(),
                format!("m.toml: key 'hip_girth': must be a positive number, got {shown}")
            );
        }
        let order = Measurements {
            stature: Some(166.0),
            waist_girth: Some(80.0),
            hip_girth: Some(100.0),
            waist_height: Some(70.0),
            hip_height: Some(80.0),
            ..Default::default()
        };
        let e = sections(&order, p, 41).unwrap_err().to_string();
        assert!(
            e.contains("key 'top_hip_height'") || e.contains("waist_height"),
            "{e}"
        );
        let none = Measurements {
            bust_girth: Some(90.0),
            waist_girth: Some(70.0),
            ..Default::default()
        };
        assert_eq!(
            sections(&none, p, 41).unwrap_err().to_string(),
            "m.toml: key 'stature': is required"
        );
    }

    /// The keys of the problems `sections` finds in the measurements file `text`.
    fn problem_keys(text: &str) -> Vec<String> {
        let p = Path::new("m.toml");
        match sections(&read_str(text, p).unwrap(), p, 41) {
            Err(FitError::Key { key, .. }) => vec![key],
            Err(FitError::Keys { problems, .. }) => problems.into_iter().map(|(k, _)| k).collect(),
            other => panic!("{text}: {:?}", other.map(|_| ())),
        }
    }

    #[test]
    fn every_problem_of_a_measurement_set_is_reported_at_once() {
        let keys = problem_keys(
            "stature = 170\nwaist_girth = 70\nbust_girth = -3\nhip_girth = 5000\nwaist_height = 200\n",
        );
        assert_eq!(keys, ["bust_girth", "hip_girth", "waist_height"]);
        let keys = problem_keys("units = \"cubits\"\nwaist_girth = 70\n");
        assert_eq!(keys, ["units", "stature", "*_girth"]);
        // An infinite girth is one problem, not also "more than 10 statures".
        assert_eq!(
            problem_keys("stature = 170\nwaist_girth = 70\nbust_girth = inf\n"),
            ["bust_girth"]
        );
        // A default level out of order is named by the given heights round it, never by an
        // empty key or the key of a height that was not given.
        let keys = problem_keys("stature = 170\nbust_girth = 90\nwaist_girth = 70\nshoulder_height = 120\nbust_height = 125\n");
        assert_eq!(keys, ["bust_height", "shoulder_height"]);
        let keys = problem_keys("stature = 170\nbust_girth = 90\nwaist_girth = 70\nbust_height = 100\nwaist_height = 110\n");
        assert_eq!(keys, ["waist_height", "bust_height"]);
        // A depth that cannot fit its girth is named as the depth.
        let keys = problem_keys("stature = 170\nbust_girth = 90\nwaist_girth = 70\nwaist_width = 1\nhip_girth = 95\nhip_depth = 0.5\n");
        assert_eq!(keys, ["hip_depth", "waist_width"]);
    }

    #[test]
    fn lengths_that_would_overflow_the_model_are_refused_by_key() {
        // Found by tests/fuzz_mutation.rs: each gave sections of inf or NaN, which the fitter
        // then refused as "section 26: point 1 is not a finite number".
        let p = Path::new("m.toml");
        let base = read_str("stature = 170\nbust_girth = 90\nwaist_girth = 70\n", p).unwrap();
        let err = |m: Measurements| sections(&m, p, 41).unwrap_err().to_string();
        let huge = err(Measurements {
            stature: Some(1e308),
            ..base.clone()
        });
        assert!(
            huge.starts_with("m.toml: key 'stature': 1.000e308 is outside 1e-100..1e100"),
            "{huge}"
        );
        let tiny = err(Measurements {
            stature: Some(1e-300),
            bust_girth: Some(1e-299),
            waist_girth: Some(1e-301),
            ..base.clone()
        });
        assert!(tiny.contains("key 'stature'"), "{tiny}");
        let wide = err(Measurements {
            shoulder_width: Some(1e308),
            ..base.clone()
        });
        assert!(
            wide.contains("key 'shoulder_width'") && wide.contains("more than 10 times"),
            "{wide}"
        );
        let girth = err(Measurements {
            waist_girth: Some(1701.0),
            ..base.clone()
        });
        assert!(girth.contains("key 'waist_girth'"), "{girth}");
        // A bust of 1e-20 cm was lost in the model's rounding: 'section 26 is degenerate'.
        let thin = err(Measurements {
            bust_girth: Some(1e-20),
            ..base.clone()
        });
        assert!(
            thin.contains("key 'bust_girth'") && thin.contains("no body is that thin"),
            "{thin}"
        );
        // The levels below the waist are placed between the floor and it: 1e-320 apart.
        let close = err(Measurements {
            waist_height: Some(1e-320),
            ..base.clone()
        });
        assert!(close.contains("by 1e-6 of the stature"), "{close}");
        // At the limits, every section is finite.
        for m in [
            Measurements {
                stature: Some(1e100),
                bust_girth: Some(1e101),
                waist_girth: Some(1e98),
                ..base.clone()
            },
            Measurements {
                stature: Some(1e-100),
                bust_girth: Some(1e-99),
                waist_girth: Some(1e-102),
                ..base.clone()
            },
            Measurements {
                waist_girth: Some(1700.0),
                ..base.clone()
            },
            Measurements {
                bust_girth: Some(170e-6),
                ..base.clone()
            },
            Measurements {
                waist_height: Some(107.0),
                top_hip_height: Some(107.0 - 1.5 * 170e-6),
                ..base.clone()
            },
        ] {
            let (s, _, _) = sections(&m, p, 41).unwrap();
            assert!(
                s.iter().all(|s| s.height.is_finite()
                    && s.points.iter().all(|q| q.x.is_finite() && q.y.is_finite())),
                "{m:?}"
            );
        }
    }
}
