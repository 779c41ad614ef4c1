//! Line plots written as SVG, for the benchmarks (`bench fit --plot`, ...).
//!
//! A plot maps data `(x, y)` to the picture by `X = left + w (f(x) - f(x0)) / (f(x1) - f(x0))`
//! with `f = log10` on a logarithmic axis and the identity on a linear one (`Y` likewise, from
//! the bottom), over the range of the finite data (positive data on a log axis), widened to
//! whole decades on a log axis. Ticks: every decade on a log axis; steps of 1, 2 or 5 times a
//! power of ten, about five, on a linear one. Each series is a polyline with a marker per point;
//! a point a log axis cannot show (zero, negative, not finite) breaks its line.
//!
//! ```
//! use drapekit::plot::{Plot, Series};
//! let p = Plot {
//!     series: vec![Series::new("x^-2", (1..=4).map(|k| (10f64.powi(k), 10f64.powi(-2 * k))).collect())],
//!     log_x: true,
//!     log_y: true,
//!     ..Plot::default()
//! };
//! let svg = p.svg();
//! assert!(svg.starts_with("<svg") && svg.contains("x^-2"));
//! // The line falls two decades of y for each decade of x: pixel slope -2 x (width / height) of the
//! // decades shown (x: 10 to 10^4, y: 10^-8 to 10^-2).
//! let pts = p.polyline_points(0);
//! let slope = (pts[1].1 - pts[0].1) / (pts[1].0 - pts[0].0);
//! let (w, h) = p.plot_area();
//! assert!((slope - 2.0 * (h / 6.0) / (w / 3.0)).abs() < 1e-9);
//! ```

use std::fmt::Write as _;

/// A named line.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// A series from its name and points.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            name: name.into(),
            points,
        }
    }
}

/// A line plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
    /// Picture size, px (default 720 x 440).
    pub size: (f64, f64),
}

impl Default for Plot {
    fn default() -> Plot {
        Plot {
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            log_x: false,
            log_y: false,
            series: Vec::new(),
            size: (720.0, 440.0),
        }
    }
}

/// Margins: left, right (the legend), top, bottom, px.
const MARGIN: (f64, f64, f64, f64) = (80.0, 200.0, 40.0, 55.0);
/// Line colours, in order (Okabe-Ito: told apart with colour-blindness too).
const COLOURS: [&str; 7] = [
    "#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#000000",
];

/// One axis: its scale and range (in scaled units).
#[derive(Debug, Clone, Copy)]
struct Axis {
    log: bool,
    lo: f64,
    hi: f64,
}

impl Axis {
    fn scaled(&self, v: f64) -> Option<f64> {
        match self.log {
            true if v > 0.0 && v.is_finite() => Some(v.log10()),
            true => None,
            false => v.is_finite().then_some(v),
        }
    }

    fn of(values: impl Iterator<Item = f64>, log: bool) -> Axis {
        let mut a = Axis {
            log,
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
        };
        let probe = a;
        for s in values.filter_map(|v| probe.scaled(v)) {
            a.lo = a.lo.min(s);
            a.hi = a.hi.max(s);
        }
        if !a.lo.is_finite() {
            (a.lo, a.hi) = (0.0, 1.0);
        }
        if log {
            (a.lo, a.hi) = (a.lo.floor(), a.hi.ceil());
        }
        if a.hi - a.lo < 1e-12 {
            (a.lo, a.hi) = (a.lo - 0.5, a.hi + 0.5);
        }
        a
    }

    /// Tick positions in scaled units, with their labels.
    fn ticks(&self) -> Vec<(f64, String)> {
        if self.log {
            let (lo, hi) = (self.lo as i32, self.hi as i32);
            return (lo..=hi)
                .map(|k| (f64::from(k), format!("1e{k}")))
                .collect();
        }
        let raw = (self.hi - self.lo) / 5.0;
        let p = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * p)
            .find(|s| *s >= raw)
            .unwrap_or(10.0 * p);
        let first = (self.lo / step).ceil() as i64;
        let last = (self.hi / step).floor() as i64;
        (first..=last)
            .map(|k| (k as f64 * step, crate::math::short(k as f64 * step)))
            .collect()
    }
}

impl Plot {
    fn axes(&self) -> (Axis, Axis) {
        let pts = || self.series.iter().flat_map(|s| s.points.iter());
        (
            Axis::of(pts().map(|p| p.0), self.log_x),
            Axis::of(pts().map(|p| p.1), self.log_y),
        )
    }

    /// The plotting area's width and height, px.
    pub fn plot_area(&self) -> (f64, f64) {
        let (l, r, t, b) = MARGIN;
        (self.size.0 - l - r, self.size.1 - t - b)
    }

    fn map(&self, x: f64, y: f64, ax: &Axis, ay: &Axis) -> Option<(f64, f64)> {
        let (w, h) = self.plot_area();
        let (sx, sy) = (ax.scaled(x)?, ay.scaled(y)?);
        let px = MARGIN.0 + w * (sx - ax.lo) / (ax.hi - ax.lo);
        let py = MARGIN.2 + h * (1.0 - (sy - ay.lo) / (ay.hi - ay.lo));
        Some((px, py))
    }

    /// The picture coordinates of series `k`'s points (those the axes can show).
    pub fn polyline_points(&self, k: usize) -> Vec<(f64, f64)> {
        let (ax, ay) = self.axes();
        (self.series[k].points.iter())
            .filter_map(|&(x, y)| self.map(x, y, &ax, &ay))
            .collect()
    }

    /// The plot as an SVG document.
    pub fn svg(&self) -> String {
        let (ax, ay) = self.axes();
        let (w, h) = self.plot_area();
        let (l, _, t, _) = MARGIN;
        let mut s = String::new();
        let _ = write!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{}" height="{}" font-family="sans-serif" font-size="12">"#,
            self.size.0, self.size.1
        );
        let _ = write!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = write!(
            s,
            r##"<rect x="{l}" y="{t}" width="{w}" height="{h}" fill="none" stroke="#444"/>"##
        );
        self.ticks_svg(&mut s, &ax, &ay);
        for k in 0..self.series.len() {
            self.series_svg(&mut s, k, &ax, &ay);
        }
        let _ = write!(
            s,
            r#"<text x="{}" y="22" text-anchor="middle" font-size="14">{}</text>"#,
            l + w / 2.0,
            esc(&self.title)
        );
        let _ = write!(
            s,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
            l + w / 2.0,
            self.size.1 - 12.0,
            esc(&self.x_label)
        );
        let _ = write!(
            s,
            r#"<text transform="translate(16 {}) rotate(-90)" text-anchor="middle">{}</text>"#,
            t + h / 2.0,
            esc(&self.y_label)
        );
        s.push_str("</svg>\n");
        s
    }

    fn ticks_svg(&self, s: &mut String, ax: &Axis, ay: &Axis) {
        let (w, h) = self.plot_area();
        let (l, _, t, _) = MARGIN;
        for (v, label) in ax.ticks() {
            let x = l + w * (v - ax.lo) / (ax.hi - ax.lo);
            let _ = write!(
                s,
                r##"<line x1="{x}" y1="{t}" x2="{x}" y2="{}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle">{label}</text>"##,
                t + h,
                t + h + 16.0
            );
        }
        for (v, label) in ay.ticks() {
            let y = t + h * (1.0 - (v - ay.lo) / (ay.hi - ay.lo));
            let _ = write!(
                s,
                r##"<line x1="{l}" y1="{y}" x2="{}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">{label}</text>"##,
                l + w,
                l - 6.0,
                y + 4.0
            );
        }
    }

    fn series_svg(&self, s: &mut String, k: usize, ax: &Axis, ay: &Axis) {
        let colour = COLOURS[k % COLOURS.len()];
        // Past the colours, the lines are dashed.
        let dash = if k >= COLOURS.len() {
            r#" stroke-dasharray="6,3""#
        } else {
            ""
        };
        let mut run: Vec<(f64, f64)> = Vec::new();
        let flush = |run: &mut Vec<(f64, f64)>, s: &mut String| {
            if run.len() > 1 {
                let pts: Vec<String> = run.iter().map(|(x, y)| format!("{x:.2},{y:.2}")).collect();
                let _ = write!(
                    s,
                    r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="2"{dash}/>"#,
                    pts.join(" ")
                );
            }
            run.clear();
        };
        for &(x, y) in &self.series[k].points {
            match self.map(x, y, ax, ay) {
                Some(p) => {
                    let _ = write!(
                        s,
                        r#"<circle cx="{:.2}" cy="{:.2}" r="3" fill="{colour}"/>"#,
                        p.0, p.1
                    );
                    run.push(p);
                }
                None => flush(&mut run, s),
            }
        }
        flush(&mut run, s);
        let (l, _, t, _) = MARGIN;
        let (w, _) = self.plot_area();
        let y = t + 12.0 + 20.0 * k as f64;
        let x = l + w + 14.0;
        let _ = write!(
            s,
            r#"<line x1="{x}" y1="{y}" x2="{}" y2="{y}" stroke="{colour}" stroke-width="2"{dash}/><text x="{}" y="{}">{}</text>"#,
            x + 24.0,
            x + 30.0,
            y + 4.0,
            esc(&self.series[k].name)
        );
    }
}

/// Text for SVG (`&`, `<`, `>` escaped).
fn esc(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_a_log_axis_cannot_show_break_the_line() {
        let p = Plot {
            series: vec![Series::new(
                "a",
                vec![
                    (1.0, 1.0),
                    (2.0, 0.0),
                    (3.0, 10.0),
                    (4.0, 100.0),
                    (5.0, f64::NAN),
                ],
            )],
            log_y: true,
            ..Plot::default()
        };
        assert_eq!(p.polyline_points(0).len(), 3);
        let svg = p.svg();
        // One polyline (the run of two after the break), three markers.
        assert_eq!(svg.matches("<polyline").count(), 1);
        assert_eq!(svg.matches("<circle").count(), 3);
        // The y axis spans whole decades 1e0 to 1e2: the top point is at the top.
        let top = p.polyline_points(0)[2].1;
        assert!((top - MARGIN.2).abs() < 1e-9);
    }

    #[test]
    fn linear_ticks_are_round_numbers_inside_the_range() {
        let a = Axis {
            log: false,
            lo: 0.13,
            hi: 0.87,
        };
        let t: Vec<f64> = a.ticks().iter().map(|t| t.0).collect();
        assert_eq!(t.len(), 4);
        for (got, want) in t.iter().zip([0.2, 0.4, 0.6, 0.8]) {
            assert!((got - want).abs() < 1e-12, "{t:?}");
        }
    }
}
