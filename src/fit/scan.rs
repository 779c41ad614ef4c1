//! Torso sections from a scanned body mesh.
//!
//! The body (Z-up, prepared: welded and oriented) is sliced at `levels` evenly spaced heights
//! between `from` and `to` (default: 0.48 and 0.74 of the body's height above its lowest point,
//! between the crotch and the armpits of a standing body). A slice holds several closed loops:
//! the torso, and the arms and legs (and fingers) as separate loops.
//!
//! **Which loop is the torso.** At the middle level, the loop of largest area. From there,
//! level by level up and down, the loop that contains the previous level's torso centroid
//! (arms and legs lie beside it and do not); if several do, the largest. The band must stay
//! inside the torso: a level where no loop contains that centroid (the torso splits into legs),
//! or whose torso loop swallows another loop of the level before it (an arm joining at the
//! armpit: any loop of at least 1% of the torso's area), stops the fit with an error naming the
//! level, so the user can narrow `--from`/`--to`.
//!
//! **The up axis.** Before slicing, [`check_up`] refuses a body clearly longer along another axis
//! than along the up axis it was given (a Y-up body read as Z-up would be sliced lengthwise).

use super::error::FitError;
use super::section::{centroid, signed_area2, Section};
use crate::math::Point2;
use crate::mesh::slice::Slicer;
use crate::mesh::transform::Up;
use crate::mesh::TriMesh;
use rayon::prelude::*;

/// Where to slice a scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanOptions {
    /// Number of slices (default 60).
    pub levels: usize,
    /// Lowest slice height (default: 0.48 of the body height above its lowest point).
    pub from: Option<f64>,
    /// Highest slice height (default: 0.74 of the body height above its lowest point).
    pub to: Option<f64>,
}

impl Default for ScanOptions {
    fn default() -> Self {
        ScanOptions {
            levels: 60,
            from: None,
            to: None,
        }
    }
}

/// Default band, as fractions of the body's height.
pub const DEFAULT_BAND: (f64, f64) = (0.48, 0.74);

pub use crate::geom::contains;

/// A standing body is tallest along its up axis: a body longer than this many times its extent
/// along the given up axis, along another axis, was given the wrong up axis (ratio of lengths).
pub const UP_AXIS_RATIO: f64 = 1.5;

/// Checks that `body` (as read, before any rotation) is not clearly taller along another axis than
/// along `up`: longer by more than [`UP_AXIS_RATIO`] means the up axis is wrong.
pub fn check_up(body: &TriMesh, up: Up, path: &std::path::Path) -> Result<(), FitError> {
    let Some(b) = body.bbox() else {
        return Ok(());
    };
    let size = b.size();
    let k = match up {
        Up::Y => 1,
        Up::Z => 2,
    };
    let longest = size.imax();
    let other = 3 - k;
    if longest != k && size[longest] > UP_AXIS_RATIO * size[k] {
        return Err(FitError::UpAxis {
            path: path.to_path_buf(),
            given: up,
            height: size[k],
            longest: ['x', 'y', 'z'][longest],
            extent: size[longest],
            other: (size[other] > UP_AXIS_RATIO * size[k]).then_some(['x', 'y', 'z'][other]),
        });
    }
    Ok(())
}

/// `x` in full, or in exponent form beyond a billion (`1e300`, not 301 digits).
fn number(x: f64) -> String {
    if x.abs() < 1e9 {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The torso sections of a Z-up body mesh, and the band `(from, to)` they span.
pub fn torso_sections(
    body: &TriMesh,
    opts: &ScanOptions,
) -> Result<(Vec<Section>, (f64, f64)), FitError> {
    let (from, to) = band(body, opts)?;
    let k = opts.levels;
    let heights: Vec<f64> = (0..k)
        .map(|i| from + (to - from) * i as f64 / (k - 1) as f64)
        .collect();
    let slicer = Slicer::new(body);
    let loops: Vec<Vec<Vec<Point2>>> = heights
        .par_iter()
        .map(|&h| {
            slicer
                .slice(h)
                .into_iter()
                .filter(|l| l.closed && l.points.len() >= 3)
                .map(|l| l.xy())
                .collect()
        })
        .collect();
    let mid = k / 2;
    let first = loops[mid]
        .iter()
        .max_by(|a, b| area(a).total_cmp(&area(b)))
        .ok_or_else(|| FitError::Scan {
            level: mid + 1,
            height: heights[mid],
            reason: "the slice is empty: the body does not reach this height".into(),
        })?;
    let mut torso: Vec<Option<Vec<Point2>>> = vec![None; k];
    torso[mid] = Some(first.clone());
    let order: Vec<(usize, usize)> = (mid + 1..k)
        .map(|i| (i, i - 1))
        .chain((0..mid).rev().map(|i| (i, i + 1)))
        .collect();
    for (i, prev) in order {
        let prev_torso = torso[prev].as_ref().unwrap();
        let l =
            next_torso(&loops[i], &loops[prev], prev_torso).map_err(|reason| FitError::Scan {
                level: i + 1,
                height: heights[i],
                reason,
            })?;
        torso[i] = Some(l.clone());
    }
    let sections = heights
        .iter()
        .zip(torso)
        .map(|(&h, t)| Section {
            height: h,
            points: t.unwrap(),
        })
        .collect();
    Ok((sections, (from, to)))
}

/// A loop's area.
fn area(p: &[Point2]) -> f64 {
    signed_area2(p).abs()
}

/// The slicing band `(from, to)` of `opts` on `body`, checked with the number of levels.
fn band(body: &TriMesh, opts: &ScanOptions) -> Result<(f64, f64), FitError> {
    let b = body
        .bbox()
        .ok_or_else(|| FitError::Options("the body mesh is empty".into()))?;
    let height = b.max.z - b.min.z;
    let from = opts.from.unwrap_or(b.min.z + DEFAULT_BAND.0 * height);
    let to = opts.to.unwrap_or(b.min.z + DEFAULT_BAND.1 * height);
    if from >= to || from <= b.min.z || to >= b.max.z || from.is_nan() || to.is_nan() {
        return Err(FitError::Options(format!(
            "the band --from {} --to {} must be increasing and inside the body's height range {} .. {}",
            number(from),
            number(to),
            number(b.min.z),
            number(b.max.z)
        )));
    }
    if opts.levels < 3 {
        return Err(FitError::Options(format!(
            "--levels {} : a surface needs at least 3 levels",
            opts.levels
        )));
    }
    Ok((from, to))
}

/// The torso loop of a level among its `loops`, next to the level of `prev_loops` whose torso
/// is `prev_torso`: the largest that contains that torso's centroid and swallows none of that
/// level's other loops (of 1% of its torso's area or more). Else why not.
fn next_torso<'a>(
    loops: &'a [Vec<Point2>],
    prev_loops: &[Vec<Point2>],
    prev_torso: &[Point2],
) -> Result<&'a Vec<Point2>, String> {
    let c = centroid(prev_torso);
    let pick = loops
        .iter()
        .filter(|l| contains(l, &c))
        .max_by(|a, b| area(a).total_cmp(&area(b)));
    let Some(l) = pick else {
        return Err(format!(
            "no loop contains the torso centre ({:.4}, {:.4}) of the level next to it: the torso splits here (crotch or armpits); choose --from/--to inside the torso",
            c.x, c.y
        ));
    };
    let limb = prev_loops
        .iter()
        .filter(|o| *o != prev_torso && area(o) >= 0.01 * area(prev_torso))
        .find(|o| contains(l, &centroid(o)));
    if let Some(o) = limb {
        let oc = centroid(o);
        return Err(format!(
            "the torso joins the loop at ({:.4}, {:.4}) of the level next to it (an arm or a leg): the torso splits here (crotch or armpits); choose --from/--to inside the torso",
            oc.x, oc.y
        ));
    }
    Ok(l)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Point3;

    /// A cube stretched to `x` by `y` by `z`.
    fn block(x: f64, y: f64, z: f64) -> TriMesh {
        let mut m = crate::mesh::generate::cube(1.0);
        for p in &mut m.positions {
            *p = Point3::new(p.x * x, p.y * y, p.z * z);
        }
        m
    }

    #[test]
    fn a_body_taller_along_another_axis_is_refused_naming_it() {
        let path = std::path::Path::new("b.obj");
        assert!(check_up(&block(0.4, 0.3, 1.7), Up::Z, path).is_ok());
        assert!(check_up(&block(0.4, 1.7, 0.3), Up::Y, path).is_ok());
        // Arms out (a T pose): wide, but not clearly wider than tall.
        assert!(check_up(&block(1.6, 0.3, 1.7), Up::Z, path).is_ok());
        let e = check_up(&block(0.4, 1.7, 0.3), Up::Z, path).unwrap_err();
        assert!(matches!(e, FitError::UpAxis { longest: 'y', .. }), "{e}");
        assert!(e.to_string().ends_with("give --up y"), "{e}");
        let e = check_up(&block(1.7, 0.3, 0.3), Up::Y, path).unwrap_err();
        assert!(e.to_string().contains("rotate it"), "{e}");
        // A T pose read with the wrong up axis: widest along x (the arm span), tall along y.
        let e = check_up(&block(1.77, 1.72, 0.31), Up::Z, path).unwrap_err();
        assert!(matches!(e, FitError::UpAxis { longest: 'x', .. }), "{e}");
        assert!(e.to_string().contains("give --up y (arms out"), "{e}");
        let e = check_up(&block(1.77, 0.31, 1.72), Up::Y, path).unwrap_err();
        assert!(e.to_string().contains("give --up z (arms out"), "{e}");
    }
}
