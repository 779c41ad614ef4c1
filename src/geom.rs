//! Plane geometry shared by the pattern pieces (`cloth`), the fitter (`fit`) and the slicer
//! (`mesh::slice`): closed polygons of [`Point2`] (the closing point not repeated) and
//! segments.
//!
//! * `signed_area2`: twice the signed area, `sum (p_i - p_0) x (p_(i+1) - p_0)` (positive
//!   counter-clockwise);
//! * `perimeter`: the sum of the edge lengths;
//! * `contains`: the even-odd rule (a horizontal ray's crossings);
//! * `segments_meet`: whether two segments cross or touch, from the signs of `orient2d`;
//! * `segment_distance`: the distance to the segment's nearest point;
//! * `segment_meets_box`: whether a segment meets a closed axis-aligned box (Liang and
//!   Barsky's clipping: the parameter range `[0, 1]` cut by each slab `lo <= a + t d <= hi`);
//! * [`crossing::self_crossing`]: two non-adjacent edges of a polygon that meet, in
//!   O(n log n) (a sweep).
//!
//! ```
//! use drapekit::geom::{contains, perimeter, signed_area2};
//! use drapekit::math::Point2;
//! let sq = [Point2::new(0.0, 0.0), Point2::new(2.0, 0.0), Point2::new(2.0, 2.0), Point2::new(0.0, 2.0)];
//! assert_eq!(signed_area2(&sq), 8.0);
//! assert_eq!(perimeter(&sq), 8.0);
//! assert!(contains(&sq, &Point2::new(1.0, 1.0)) && !contains(&sq, &Point2::new(3.0, 1.0)));
//! ```

use crate::math::{orient2d, Point2};

pub mod crossing;

/// Twice the signed area (positive counter-clockwise).
pub fn signed_area2(p: &[Point2]) -> f64 {
    let n = p.len();
    let o = p[0];
    (0..n)
        .map(|i| {
            let (a, b) = (p[i] - o, p[(i + 1) % n] - o);
            a.x * b.y - a.y * b.x
        })
        .sum()
}

/// Perimeter of the closed polygon.
pub fn perimeter(p: &[Point2]) -> f64 {
    (0..p.len())
        .map(|i| (p[(i + 1) % p.len()] - p[i]).norm())
        .sum()
}

/// Whether `p` is inside the closed polygon (even-odd rule).
pub fn contains(poly: &[Point2], p: &Point2) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

/// Distance from `p` to the segment `a b`.
pub fn segment_distance(p: &Point2, a: &Point2, b: &Point2) -> f64 {
    let d = b - a;
    let l2 = d.norm_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(&d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + d * t)).norm()
}

/// Whether the segment `a b` meets the closed box `lo..hi` (module docs).
///
/// ```
/// use drapekit::geom::segment_meets_box;
/// use drapekit::math::Point2;
/// let (lo, hi) = (Point2::new(0.0, 0.0), Point2::new(1.0, 1.0));
/// let p = |x, y| Point2::new(x, y);
/// // Through the box without an end inside it, and along a side.
/// assert!(segment_meets_box(&p(-1.0, 0.5), &p(2.0, 0.6), &lo, &hi));
/// assert!(segment_meets_box(&p(1.0, -1.0), &p(1.0, 2.0), &lo, &hi));
/// // Across the corner (1, 1) just inside it, and just beside it.
/// assert!(segment_meets_box(&p(1.9, 0.0), &p(0.0, 1.9), &lo, &hi));
/// assert!(!segment_meets_box(&p(2.1, 0.0), &p(0.0, 2.1), &lo, &hi));
/// // Short of the box.
/// assert!(!segment_meets_box(&p(-1.0, 0.5), &p(-0.1, 0.5), &lo, &hi));
/// ```
pub fn segment_meets_box(a: &Point2, b: &Point2, lo: &Point2, hi: &Point2) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for k in 0..2 {
        if d[k] == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (u, v) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Whether segments (a, b) and (c, d) cross or touch, beyond shared endpoints.
pub fn segments_meet(a: &Point2, b: &Point2, c: &Point2, d: &Point2) -> bool {
    let (d1, d2, d3, d4) = (
        orient2d(a, b, c),
        orient2d(a, b, d),
        orient2d(c, d, a),
        orient2d(c, d, b),
    );
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: &Point2, q: &Point2, r: &Point2| {
        orient2d(p, q, r) == 0.0
            && r.x >= p.x.min(q.x)
            && r.x <= p.x.max(q.x)
            && r.y >= p.y.min(q.y)
            && r.y <= p.y.max(q.y)
    };
    on(a, b, c) || on(a, b, d) || on(c, d, a) || on(c, d, b)
}
