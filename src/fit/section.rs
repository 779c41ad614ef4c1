//! Horizontal sections: validation, orientation, start point, arc-length resampling.
//!
//! A section is a closed contour at one height, given by its corners (the closing point not
//! repeated). Before fitting, every section is
//! * checked: finite numbers, at least 3 distinct points, a non-zero area (collinear points are
//!   refused);
//! * cleaned: consecutive repeated points (and a repeated closing point) are dropped;
//! * oriented counter-clockwise seen from above (a clockwise section is reversed);
//! * started at the same place on every level: where the ray from the section's area centroid
//!   along +x leaves the section (the farthest crossing; the rightmost point if the ray misses);
//! * resampled to `n` points equally spaced in arc length, so `u = l / n` is arc length over
//!   perimeter, whatever the input spacing.
//!
//! Sections are sorted by height; a section given twice at one height is merged when identical
//! and refused otherwise. Arc-length parametrisation needs no star shape: any simple contour works.

use super::error::FitError;
use crate::math::Point2;

/// One horizontal section.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// Height (the up coordinate).
    pub height: f64,
    /// Corners in order, closing point not repeated.
    pub points: Vec<Point2>,
}

pub use crate::geom::{perimeter, signed_area2};

/// Area centroid of the closed polygon.
pub fn centroid(p: &[Point2]) -> Point2 {
    let n = p.len();
    let o = p[0];
    let (mut cx, mut cy, mut a) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (u, v) = (p[i] - o, p[(i + 1) % n] - o);
        let cr = u.x * v.y - u.y * v.x;
        a += cr;
        cx += (u.x + v.x) * cr;
        cy += (u.y + v.y) * cr;
    }
    if a == 0.0 {
        return o;
    }
    Point2::new(o.x + cx / (3.0 * a), o.y + cy / (3.0 * a))
}

/// What normalising the sections did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct SectionNotes {
    /// Sections reversed to counter-clockwise.
    pub reversed: usize,
    /// Repeated points dropped.
    pub repeated_points: usize,
    /// Identical sections given twice at one height, merged.
    pub merged_duplicates: usize,
    /// Whether the sections had to be sorted by height.
    pub sorted: bool,
}

/// Validates, cleans, orients and sorts sections (see the module docs). Section numbers in
/// Twice the signed area of a ring, and its absolute value over the squared perimeter. The
/// ratio is computed on the points moved to the first one, halved and scaled by a power of two
/// (`mesh::clean::unit_scale`), so coordinates of 1e200 do not make it overflow (nor 1e-200
/// underflow) into a false "collinear".
fn area_and_flatness(points: &[Point2]) -> (f64, f64) {
    let p0 = points[0];
    let extent = points
        .iter()
        .map(|p| (p * 0.5 - p0 * 0.5).amax())
        .fold(0.0, f64::max);
    let s = crate::mesh::clean::unit_scale(extent);
    let unit: Vec<Point2> = points
        .iter()
        .map(|p| Point2::from((p * 0.5 - p0 * 0.5) * s))
        .collect();
    let (a2, per) = (signed_area2(&unit), perimeter(&unit));
    (a2 * 4.0 / (s * s), a2.abs() / (per * per))
}

/// errors count from 1 in the order given.
pub fn normalize(sections: Vec<Section>) -> Result<(Vec<Section>, SectionNotes), FitError> {
    let mut notes = SectionNotes::default();
    let mut indexed: Vec<(usize, Section)> = Vec::with_capacity(sections.len());
    for (i, mut s) in sections.into_iter().enumerate() {
        let no = i + 1;
        if !s.height.is_finite() {
            return Err(FitError::NonFinite {
                section: no,
                what: "the height".into(),
            });
        }
        if let Some(k) = s
            .points
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(FitError::NonFinite {
                section: no,
                what: format!("point {}", k + 1),
            });
        }
        let before = s.points.len();
        s.points.dedup();
        while s.points.len() > 1 && s.points.first() == s.points.last() {
            s.points.pop();
        }
        notes.repeated_points += before - s.points.len();
        if s.points.len() < 3 {
            return Err(FitError::TooFewPoints {
                section: no,
                height: s.height,
                found: s.points.len(),
            });
        }
        let (a2, relative) = area_and_flatness(&s.points);
        if relative <= 1e-9 {
            return Err(FitError::Degenerate {
                section: no,
                height: s.height,
                area: a2 / 2.0,
            });
        }
        if a2 < 0.0 {
            s.points.reverse();
            notes.reversed += 1;
        }
        indexed.push((no, s));
    }
    notes.sorted = indexed.windows(2).any(|w| w[1].1.height < w[0].1.height);
    indexed.sort_by(|a, b| a.1.height.total_cmp(&b.1.height));
    let mut out: Vec<(usize, Section)> = Vec::with_capacity(indexed.len());
    for (no, s) in indexed {
        if let Some((prev_no, prev)) = out.last() {
            if prev.height == s.height {
                if same_contour(&prev.points, &s.points) {
                    notes.merged_duplicates += 1;
                    continue;
                }
                return Err(FitError::DuplicateHeight {
                    first: *prev_no.min(&no),
                    second: *prev_no.max(&no),
                    height: s.height,
                });
            }
        }
        out.push((no, s));
    }
    if out.len() < 3 {
        return Err(FitError::TooFewSections { found: out.len() });
    }
    Ok((out.into_iter().map(|(_, s)| s).collect(), notes))
}

/// Whether two counter-clockwise contours are the same up to the start point.
fn same_contour(a: &[Point2], b: &[Point2]) -> bool {
    a.len() == b.len() && (0..a.len()).any(|s| (0..a.len()).all(|i| a[(i + s) % a.len()] == b[i]))
}

/// The start of the resampled section: edge index and fraction along it.
fn start_point(p: &[Point2]) -> (usize, f64) {
    let c = centroid(p);
    let n = p.len();
    let mut best: Option<(f64, usize, f64)> = None;
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        if (a.y <= c.y) != (b.y <= c.y) {
            let t = (c.y - a.y) / (b.y - a.y);
            let x = a.x + t * (b.x - a.x);
            if x >= c.x && best.is_none_or(|(bx, _, _)| x > bx) {
                best = Some((x, i, t));
            }
        }
    }
    match best {
        Some((_, i, t)) => (i, t),
        None => {
            let i = (0..n)
                .max_by(|&a, &b| p[a].x.total_cmp(&p[b].x))
                .unwrap_or(0);
            (i, 0.0)
        }
    }
}

/// Resamples a counter-clockwise section to `n` points equally spaced in arc length, from the
/// start point (see the module docs).
pub fn resample(p: &[Point2], n: usize) -> Vec<Point2> {
    let m = p.len();
    let (e0, t0) = start_point(p);
    // The contour as a closed walk from the start point.
    let start = p[e0] + (p[(e0 + 1) % m] - p[e0]) * t0;
    let mut walk = Vec::with_capacity(m + 2);
    walk.push(start);
    for k in 1..=m {
        walk.push(p[(e0 + k) % m]);
    }
    walk.push(start);
    let mut cum = Vec::with_capacity(walk.len());
    cum.push(0.0);
    for w in walk.windows(2) {
        let last = *cum.last().unwrap();
        cum.push(last + (w[1] - w[0]).norm());
    }
    let total = *cum.last().unwrap();
    let mut out = Vec::with_capacity(n);
    let mut seg = 0;
    for j in 0..n {
        let s = total * j as f64 / n as f64;
        while seg + 2 < cum.len() && cum[seg + 1] < s {
            seg += 1;
        }
        let len = cum[seg + 1] - cum[seg];
        let t = if len > 0.0 { (s - cum[seg]) / len } else { 0.0 };
        out.push(walk[seg] + (walk[seg + 1] - walk[seg]) * t);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(r: f64, n: usize, phase: f64, cw: bool) -> Vec<Point2> {
        (0..n)
            .map(|i| {
                let t = phase
                    + std::f64::consts::TAU * i as f64 / n as f64 * if cw { -1.0 } else { 1.0 };
                Point2::new(r * t.cos(), r * t.sin())
            })
            .collect()
    }

    #[test]
    fn regular_polygon_starting_at_zero_is_reproduced() {
        let p = circle(2.0, 16, 0.0, false);
        let r = resample(&p, 16);
        for (a, b) in p.iter().zip(&r) {
            assert!((a - b).norm() < 1e-14);
        }
    }

    #[test]
    fn orientation_start_and_repeats_are_normalised() {
        let mut cw = circle(1.0, 40, 1.0, true);
        cw.push(cw[0]);
        cw.insert(5, cw[5]);
        let ccw = circle(1.0, 40, 0.0, false);
        let (s, notes) = normalize(vec![
            Section {
                height: 1.0,
                points: cw,
            },
            Section {
                height: 0.0,
                points: ccw.clone(),
            },
            Section {
                height: 2.0,
                points: ccw,
            },
        ])
        .unwrap();
        assert_eq!(
            (notes.reversed, notes.repeated_points, notes.sorted),
            (1, 2, true)
        );
        assert_eq!(s[1].height, 1.0);
        // All start on the +x axis (on the polygon's chord there) and run counter-clockwise.
        for sec in &s {
            let r = resample(&sec.points, 8);
            assert!(r[0].y.abs() < 1e-12 && r[0].x > 0.99, "{:?}", r[0]);
            assert!(r[2].y > 0.5);
        }
    }

    #[test]
    fn bad_sections_are_named() {
        let tri = vec![
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(0.0, 1.0),
        ];
        let line = vec![
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(2.0, 2.0),
        ];
        let sec = |h: f64, p: &Vec<Point2>| Section {
            height: h,
            points: p.clone(),
        };
        let e = normalize(vec![sec(0.0, &tri), sec(1.0, &line), sec(2.0, &tri)])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("section 2 (height 1) is degenerate: its points are collinear"),
            "{e}"
        );
        let shifted: Vec<Point2> = tri
            .iter()
            .map(|p| p + nalgebra::Vector2::new(0.1, 0.0))
            .collect();
        let e = normalize(vec![sec(0.0, &tri), sec(1.0, &tri), sec(1.0, &shifted)])
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "sections 2 and 3 are both at height 1 but differ: give one section per height"
        );
        let (s, n) = normalize(vec![
            sec(0.0, &tri),
            sec(1.0, &tri),
            sec(1.0, &tri),
            sec(2.0, &tri),
        ])
        .unwrap();
        assert_eq!((s.len(), n.merged_duplicates), (3, 1));
        let e = normalize(vec![sec(0.0, &tri), sec(1.0, &tri)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("2 section(s)"));
    }
}
