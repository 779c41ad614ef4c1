//! Lawson's edge flips: a triangulation of a plane region made (constrained) Delaunay.
//!
//! An edge `ab` shared by triangles `abc` and `bad` (both counter-clockwise) is *locally
//! Delaunay* when `d` is not inside the circle through `a`, `b`, `c`:
//!
//! ```text
//! incircle(a, b, c, d) = | ax-dx  ay-dy  (ax-dx)^2 + (ay-dy)^2 |
//!                        | bx-dx  by-dy  (bx-dx)^2 + (by-dy)^2 |  <= 0
//!                        | cx-dx  cy-dy  (cx-dx)^2 + (cy-dy)^2 |
//! ```
//!
//! An edge that is not is flipped to `cd` (triangles `adc` and `dbc`) when the quad `a d b c`
//! is strictly convex. Flipping until every shared edge is locally Delaunay ends (each flip
//! lowers a bounded measure of the triangulation) in the constrained Delaunay triangulation of
//! the region: among all triangulations with its boundary edges, the one that maximises the
//! smallest angle. Edges with one triangle (the region's boundary) are never flipped, so an
//! outline and the edges shared with the cells of a grid stay. An ear-clipped polygon is a
//! fan of long slivers where its boundary runs along a straight row; flipped, its edges join
//! nearby corners.
//!
//! Cocircular corners (a grid's squares) are ties: an edge is flipped only when `incircle`
//! exceeds [`INCIRCLE_REL`] times the fourth power of the quad's longest side, so no tie is
//! flipped back and forth.

use crate::math::{orient2d, Point2};
use std::collections::HashMap;

/// `incircle` values at most this times the quad's longest side to the fourth are ties.
pub const INCIRCLE_REL: f64 = 1e-9;

/// The incircle determinant of `d` against the counter-clockwise triangle `abc` (module docs):
/// positive when `d` is inside its circumcircle.
///
/// ```
/// use drapekit::math::Point2;
/// use drapekit::mesh::delaunay::incircle;
/// let (a, b, c) = (Point2::new(1.0, 0.0), Point2::new(0.0, 1.0), Point2::new(-1.0, 0.0));
/// assert!(incircle(&a, &b, &c, &Point2::new(0.0, 0.5)) > 0.0);
/// assert!(incircle(&a, &b, &c, &Point2::new(0.0, -2.0)) < 0.0);
/// assert_eq!(incircle(&a, &b, &c, &Point2::new(0.0, -1.0)), 0.0);
/// ```
pub fn incircle(a: &Point2, b: &Point2, c: &Point2, d: &Point2) -> f64 {
    let row = |p: &Point2| {
        let (x, y) = (p.x - d.x, p.y - d.y);
        (x, y, x * x + y * y)
    };
    let (ax, ay, a2) = row(a);
    let (bx, by, b2) = row(b);
    let (cx, cy, c2) = row(c);
    ax * (by * c2 - b2 * cy) - ay * (bx * c2 - b2 * cx) + a2 * (bx * cy - by * cx)
}

/// The corner of `t` after `v` (counter-clockwise) and the one after that.
fn after(t: &[u32; 3], v: u32) -> (u32, u32) {
    let k = t
        .iter()
        .position(|&x| x == v)
        .expect("a corner of the triangle");
    (t[(k + 1) % 3], t[(k + 2) % 3])
}

/// Flips the shared edges of the counter-clockwise triangles `tris` (corners index `pts`)
/// longer than `longer_than` until each is locally Delaunay (module docs; 0: every edge).
/// Returns the number of flips.
pub fn flip_to_delaunay(pts: &[Point2], tris: &mut [[u32; 3]], longer_than: f64) -> usize {
    let mut owner: HashMap<(u32, u32), usize> = HashMap::new();
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            owner.insert((tri[k], tri[(k + 1) % 3]), t);
        }
    }
    let mut stack: Vec<(u32, u32)> = owner.keys().copied().filter(|&(a, b)| a < b).collect();
    stack.sort_unstable();
    let mut flips = 0;
    // Lawson's flips end after O(n^2) at most; the cap only guards against rounding.
    let cap = tris.len().saturating_mul(tris.len()).max(16);
    while let Some((a, b)) = stack.pop() {
        let (Some(&t1), Some(&t2)) = (owner.get(&(a, b)), owner.get(&(b, a))) else {
            continue;
        };
        let c = after(&tris[t1], b).0;
        let d = after(&tris[t2], a).0;
        let p = |v: u32| &pts[v as usize];
        let short = (p(b) - p(a)).norm() <= longer_than;
        if short || c == d || owner.contains_key(&(c, d)) || flips >= cap {
            continue;
        }
        let longest = [(a, d), (d, b), (b, c), (c, a)]
            .iter()
            .map(|&(u, v)| (p(v) - p(u)).norm_squared())
            .fold(0.0, f64::max);
        let convex = orient2d(p(a), p(d), p(c)) > 0.0 && orient2d(p(d), p(b), p(c)) > 0.0;
        if !convex || incircle(p(a), p(b), p(c), p(d)) <= INCIRCLE_REL * longest * longest {
            continue;
        }
        for (u, v) in [(a, b), (b, c), (c, a), (b, a), (a, d), (d, b)] {
            owner.remove(&(u, v));
        }
        tris[t1] = [a, d, c];
        tris[t2] = [d, b, c];
        for (t, tri) in [(t1, tris[t1]), (t2, tris[t2])] {
            for k in 0..3 {
                owner.insert((tri[k], tri[(k + 1) % 3]), t);
            }
        }
        stack.extend([(a, d), (d, b), (b, c), (c, a)].map(|(u, v)| (u.min(v), u.max(v))));
        flips += 1;
    }
    flips
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan from one corner of a convex polygon: every triangle shares the hub.
    fn fan(n: usize) -> Vec<[u32; 3]> {
        (1..n as u32 - 1).map(|i| [0, i, i + 1]).collect()
    }

    fn min_angle(pts: &[Point2], tris: &[[u32; 3]]) -> f64 {
        let mut m = f64::INFINITY;
        for t in tris {
            for k in 0..3 {
                let (o, u, v) = (
                    pts[t[k] as usize],
                    pts[t[(k + 1) % 3] as usize],
                    pts[t[(k + 2) % 3] as usize],
                );
                let (e, f) = (u - o, v - o);
                m = m.min((e.dot(&f) / (e.norm() * f.norm())).clamp(-1.0, 1.0).acos());
            }
        }
        m.to_degrees()
    }

    #[test]
    fn a_fan_in_a_regular_polygon_becomes_delaunay_and_keeps_its_area() {
        // A regular 12-gon: every triangulation is Delaunay up to ties (its corners are
        // cocircular), so nothing is flipped.
        let n = 12;
        let ring: Vec<Point2> = (0..n)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                Point2::new(t.cos(), t.sin())
            })
            .collect();
        let mut tris = fan(n);
        assert_eq!(flip_to_delaunay(&ring, &mut tris, 0.0), 0);
        // A strip 10 long and 1 high, its lower side one edge and its upper side ten: the fan
        // from a lower corner has slivers reaching 10.05 across. The Delaunay triangle on the
        // lower side has its apex where the side subtends the largest angle, the upper
        // middle (5, 1); the other triangles fan from the two lower corners to it.
        let mut strip = vec![Point2::new(0.0, 0.0), Point2::new(10.0, 0.0)];
        strip.extend((0..=10).rev().map(|i| Point2::new(i as f64, 1.0)));
        let mut tris = fan(strip.len());
        let area = |t: &[[u32; 3]]| -> f64 {
            t.iter()
                .map(|t| {
                    orient2d(
                        &strip[t[0] as usize],
                        &strip[t[1] as usize],
                        &strip[t[2] as usize],
                    )
                })
                .sum()
        };
        let (before_area, before_angle) = (area(&tris), min_angle(&strip, &tris));
        assert!(flip_to_delaunay(&strip, &mut tris, 0.0) > 0);
        assert!(
            (area(&tris) - before_area).abs() < 1e-9,
            "no overlap, no gap"
        );
        assert!(tris.iter().all(|t| orient2d(
            &strip[t[0] as usize],
            &strip[t[1] as usize],
            &strip[t[2] as usize]
        ) > 0.0));
        let longest = tris
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .map(|(u, v)| (strip[v as usize] - strip[u as usize]).norm())
            .fold(0.0, f64::max);
        // The lower side (10 long) stays: it is the boundary; every other edge is short.
        assert_eq!(longest, 10.0);
        let inner = tris
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .filter(|&(u, v)| !(u.min(v) == 0 && u.max(v) == 1))
            .map(|(u, v)| (strip[v as usize] - strip[u as usize]).norm())
            .fold(0.0, f64::max);
        assert!((inner - 5.0_f64.hypot(1.0)).abs() < 1e-12, "{inner}");
        assert!(min_angle(&strip, &tris) >= before_angle, "{before_angle}");
    }

    #[test]
    fn every_shared_edge_is_locally_delaunay_after_flipping() {
        // Points of a jittered grid, triangulated as a fan from a corner of each row pair
        // (valid but poor), then flipped.
        let mut pts = Vec::new();
        for j in 0..4 {
            for i in 0..6 {
                let jitter = 0.1 * (((i * 7 + j * 3) % 5) as f64 / 5.0 - 0.4);
                pts.push(Point2::new(i as f64 + jitter, j as f64 - jitter));
            }
        }
        let id = |i: u32, j: u32| j * 6 + i;
        let mut tris = Vec::new();
        for j in 0..3 {
            for i in 0..5 {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        flip_to_delaunay(&pts, &mut tris, 0.0);
        let mut owner = HashMap::new();
        for (t, tri) in tris.iter().enumerate() {
            for k in 0..3 {
                owner.insert((tri[k], tri[(k + 1) % 3]), t);
            }
        }
        for (&(a, b), &t1) in &owner {
            if let Some(&t2) = owner.get(&(b, a)) {
                let c = after(&tris[t1], b).0;
                let d = after(&tris[t2], a).0;
                let p = |v: u32| &pts[v as usize];
                assert!(incircle(p(a), p(b), p(c), p(d)) <= 1e-6, "edge {a}-{b}");
            }
        }
    }
}
