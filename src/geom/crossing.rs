//! Whether a closed polygon crosses or touches itself, in O(n log n): the Shamos-Hoey sweep.
//!
//! Edge `i` runs from `p[i]` to `p[i + 1]` (the last back to `p[0]`). Two edges *meet* when
//! they cross or touch ([`segments_meet`]); adjacent edges share a corner and may meet there.
//! The answer is a pair of non-adjacent edges that meet, or none: the same verdict as testing
//! every pair, in O(n log n) instead of O(n^2).
//!
//! * **Repeated corners** (sorted by x, then y, equal neighbours) and **fold-backs** (an edge
//!   that turns back along the one before it) are found first, in O(n log n) and O(n): both
//!   mean non-adjacent edges meet. After them every corner is a distinct point, and adjacent
//!   edges meet only at their shared corner.
//! * **The sweep** visits the corners in (x, y) order (a vertical line swept left to right,
//!   tilted infinitesimally so points of one x come bottom to top). The edges the line
//!   crosses are kept in order from bottom to top in a treap; at each corner its edges that
//!   end there are removed (their two neighbours become adjacent and are tested), then those
//!   that start there are inserted (and tested against their two neighbours). Until the
//!   sweep passes the leftmost point where two non-adjacent edges meet (a crossing, or a
//!   corner on another edge), no two edges in the order have met, so the order is the true
//!   one; just before that point two edges meeting there are neighbours and have been
//!   tested (Shamos and Hoey 1976). Insertion compares the new edge only at the current
//!   corner, and removal unlinks a node without comparing, so rounding can give a wrong
//!   answer in a near-degenerate case but never a broken order.

use super::segments_meet;
use crate::math::{orient2d, Point2};
use std::cmp::Ordering;

/// A pair `(i, j)`, `i < j`, of non-adjacent edges of the closed polygon `p` that meet, or
/// `None` when the polygon is simple. `p` holds finite points, no two consecutive ones equal
/// (the last not equal to the first), at least three of them.
pub fn self_crossing(p: &[Point2]) -> Option<(usize, usize)> {
    self_crossing_counted(p).0
}

/// [`self_crossing`] and its work: orientation tests and segment tests done.
pub fn self_crossing_counted(p: &[Point2]) -> (Option<(usize, usize)>, u64) {
    let mut order: Vec<u32> = (0..p.len() as u32).collect();
    order.sort_by(|&a, &b| lex(&p[a as usize], &p[b as usize]));
    if let Some(pair) = repeated_corner(p, &order).or_else(|| fold_back(p)) {
        return (Some(pair), p.len() as u64);
    }
    let mut s = Sweep::new(p);
    let found = order.iter().find_map(|&k| s.corner(k as usize));
    (found, s.work)
}

/// Points in sweep order: by x, then by y (`-0.0` equals `0.0`).
fn lex(a: &Point2, b: &Point2) -> Ordering {
    a.x.partial_cmp(&b.x)
        .unwrap_or(Ordering::Equal)
        .then(a.y.partial_cmp(&b.y).unwrap_or(Ordering::Equal))
}

/// The pair ordered, smaller first.
fn pair(a: usize, b: usize) -> (usize, usize) {
    (a.min(b), a.max(b))
}

/// Two corners at one point, found among the `order`ed corners: the edges that start there
/// meet (they are not adjacent: consecutive corners differ).
fn repeated_corner(p: &[Point2], order: &[u32]) -> Option<(usize, usize)> {
    order
        .windows(2)
        .find(|w| p[w[0] as usize] == p[w[1] as usize])
        .map(|w| pair(w[0] as usize, w[1] as usize))
}

/// An edge that turns straight back along the one before it (corners `a`, `v`, `b` collinear,
/// `a` and `b` on one side of `v`): the nearer of `a` and `b` lies on the other's edge, which
/// meets the edge starting (or ending) there. Only with four corners or more (a triangle
/// folded back has no area, which is the caller's test).
fn fold_back(p: &[Point2]) -> Option<(usize, usize)> {
    let n = p.len();
    if n < 4 {
        return None;
    }
    (0..n).find_map(|k| {
        let (a, v, b) = (p[(k + n - 1) % n], p[k], p[(k + 1) % n]);
        let side = lex(&a, &v);
        if orient2d(&a, &v, &b) != 0.0 || lex(&b, &v) != side {
            return None;
        }
        // Edge k-1 runs a -> v, edge k runs v -> b.
        Some(if lex(&b, &a) == side.reverse() {
            // b lies on edge k-1 and starts edge k+1.
            pair((k + n - 1) % n, (k + 1) % n)
        } else {
            // a lies on edge k and ends edge k-2.
            pair((k + n - 2) % n, k)
        })
    })
}

/// No node.
const NIL: u32 = u32::MAX;

/// The sweep's state: the polygon, the order of the edges the sweep line crosses (a treap
/// with parent links, and the in-order neighbours), the work done.
struct Sweep<'a> {
    p: &'a [Point2],
    left: Vec<u32>,
    right: Vec<u32>,
    parent: Vec<u32>,
    below: Vec<u32>,
    above: Vec<u32>,
    root: u32,
    work: u64,
}

impl<'a> Sweep<'a> {
    fn new(p: &'a [Point2]) -> Sweep<'a> {
        let n = p.len();
        Sweep {
            p,
            left: vec![NIL; n],
            right: vec![NIL; n],
            parent: vec![NIL; n],
            below: vec![NIL; n],
            above: vec![NIL; n],
            root: NIL,
            work: 0,
        }
    }

    /// Edge `e`'s corners, first in sweep order first.
    fn ends(&self, e: u32) -> (Point2, Point2) {
        let n = self.p.len();
        let (a, b) = (self.p[e as usize], self.p[(e as usize + 1) % n]);
        if lex(&a, &b) == Ordering::Less {
            (a, b)
        } else {
            (b, a)
        }
    }

    /// Which side of edge `e` the point `q` is on: positive above (to the left of its first
    /// corner to its last), zero on its line.
    fn side(&mut self, e: u32, q: &Point2) -> f64 {
        self.work += 1;
        let (l, r) = self.ends(e);
        orient2d(&l, &r, q)
    }

    /// Handles the corner `k`: its edges that end there, then those that start there.
    fn corner(&mut self, k: usize) -> Option<(usize, usize)> {
        let n = self.p.len();
        let q = self.p[k];
        let edges = [((k + n - 1) % n) as u32, k as u32];
        for e in edges {
            if self.ends(e).1 == q {
                if let Some(found) = self.remove(e) {
                    return Some(found);
                }
            }
        }
        for e in edges {
            if self.ends(e).0 == q {
                if let Some(found) = self.insert(e) {
                    return Some(found);
                }
            }
        }
        None
    }

    fn adjacent(&self, a: u32, b: u32) -> bool {
        let n = self.p.len() as u32;
        a == b || (a + 1) % n == b || (b + 1) % n == a
    }

    /// Whether edges `a` and `b` (either may be [`NIL`]) are non-adjacent and meet.
    fn test(&mut self, a: u32, b: u32) -> Option<(usize, usize)> {
        if a == NIL || b == NIL || self.adjacent(a, b) {
            return None;
        }
        self.work += 1;
        let ((a0, a1), (b0, b1)) = (self.ends(a), self.ends(b));
        segments_meet(&a0, &a1, &b0, &b1).then(|| pair(a as usize, b as usize))
    }

    /// Inserts edge `e` at its first corner and tests it against its new neighbours.
    fn insert(&mut self, e: u32) -> Option<(usize, usize)> {
        let (l, r) = self.ends(e);
        let (mut x, mut low, mut high, mut last) = (self.root, NIL, NIL, NIL);
        let mut went_right = false;
        while x != NIL {
            // Edges in the order start before the corner (the side of the corner decides; on
            // the edge, a touch, the new edge goes below it, next to it), or at it (the
            // corner's other edge: their last corners decide, as the two cannot be collinear).
            let o = if self.ends(x).0 == l {
                self.side(x, &r)
            } else {
                self.side(x, &l)
            };
            last = x;
            went_right = o > 0.0;
            if went_right {
                low = x;
                x = self.right[x as usize];
            } else {
                high = x;
                x = self.left[x as usize];
            }
        }
        let ei = e as usize;
        self.parent[ei] = last;
        if last == NIL {
            self.root = e;
        } else if went_right {
            self.right[last as usize] = e;
        } else {
            self.left[last as usize] = e;
        }
        self.below[ei] = low;
        self.above[ei] = high;
        if low != NIL {
            self.above[low as usize] = e;
        }
        if high != NIL {
            self.below[high as usize] = e;
        }
        while self.parent[ei] != NIL && priority(e) > priority(self.parent[ei]) {
            self.rotate_up(e);
        }
        self.test(low, e).or_else(|| self.test(e, high))
    }

    /// Removes edge `e` at its last corner and tests its two neighbours, now adjacent.
    fn remove(&mut self, e: u32) -> Option<(usize, usize)> {
        let ei = e as usize;
        loop {
            let (l, r) = (self.left[ei], self.right[ei]);
            let child = match (l, r) {
                (NIL, NIL) => break,
                (c, NIL) | (NIL, c) => c,
                (l, r) if priority(l) > priority(r) => l,
                (_, r) => r,
            };
            self.rotate_up(child);
        }
        let up = self.parent[ei];
        if up == NIL {
            self.root = NIL;
        } else if self.left[up as usize] == e {
            self.left[up as usize] = NIL;
        } else {
            self.right[up as usize] = NIL;
        }
        self.parent[ei] = NIL;
        let (low, high) = (self.below[ei], self.above[ei]);
        if low != NIL {
            self.above[low as usize] = high;
        }
        if high != NIL {
            self.below[high as usize] = low;
        }
        self.test(low, high)
    }

    /// Rotates node `x` above its parent, keeping the in-order sequence.
    fn rotate_up(&mut self, x: u32) {
        let (xi, y) = (x as usize, self.parent[x as usize]);
        let yi = y as usize;
        if self.left[yi] == x {
            let b = self.right[xi];
            self.left[yi] = b;
            if b != NIL {
                self.parent[b as usize] = y;
            }
            self.right[xi] = y;
        } else {
            let b = self.left[xi];
            self.right[yi] = b;
            if b != NIL {
                self.parent[b as usize] = y;
            }
            self.left[xi] = y;
        }
        let g = self.parent[yi];
        self.parent[xi] = g;
        self.parent[yi] = x;
        if g == NIL {
            self.root = x;
        } else if self.left[g as usize] == y {
            self.left[g as usize] = x;
        } else {
            self.right[g as usize] = x;
        }
    }
}

/// A node's treap priority: a fixed hash of its edge, so the run is repeatable.
fn priority(e: u32) -> u64 {
    crate::math::mix(u64::from(e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::mix;

    /// The reference: every pair of non-adjacent edges.
    fn pairwise(p: &[Point2]) -> Option<(usize, usize)> {
        let n = p.len();
        for i in 0..n {
            for j in i + 1..n {
                if j == i + 1 || (i == 0 && j == n - 1) {
                    continue;
                }
                if segments_meet(&p[i], &p[(i + 1) % n], &p[j], &p[(j + 1) % n]) {
                    return Some((i, j));
                }
            }
        }
        None
    }

    /// A seeded generator (SplitMix64's mixing, iterated), so a failure can be repeated.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 = mix(self.0);
            self.0
        }
        fn below(&mut self, n: u64) -> u64 {
            self.next() % n
        }
    }

    /// A random polygon of `n` corners on a `grid` x `grid` lattice (many touches, collinear
    /// overlaps and vertical edges), consecutive corners distinct.
    fn lattice_polygon(rng: &mut Rng, n: usize, grid: u64) -> Vec<Point2> {
        let mut p: Vec<Point2> = Vec::new();
        while p.len() < n {
            let q = Point2::new(rng.below(grid) as f64, rng.below(grid) as f64);
            if p.last() != Some(&q) {
                p.push(q);
            }
        }
        while p.len() > 3 && p.first() == p.last() {
            p.pop();
        }
        p
    }

    fn check_against_pairwise(p: &[Point2]) {
        let (want, got) = (pairwise(p), self_crossing(p));
        assert_eq!(want.is_some(), got.is_some(), "{p:?}: {want:?} {got:?}");
        if let Some((i, j)) = got {
            let n = p.len();
            assert!(
                i < j && j != i + 1 && !(i == 0 && j == n - 1),
                "{p:?}: {i} {j}"
            );
            assert!(
                segments_meet(&p[i], &p[(i + 1) % n], &p[j], &p[(j + 1) % n]),
                "{p:?}: edges {i} and {j} do not meet"
            );
        }
    }

    #[test]
    fn random_lattice_polygons_agree_with_the_pairwise_test() {
        let mut rng = Rng(9);
        let mut crossing = 0;
        for case in 0..60_000 {
            let n = 3 + (case % 9);
            let grid = [3, 4, 6, 50][case % 4];
            let p = lattice_polygon(&mut rng, n, grid);
            if p.first() == p.last() || p.len() < 3 {
                continue;
            }
            check_against_pairwise(&p);
            crossing += usize::from(pairwise(&p).is_some());
        }
        // Both verdicts were exercised.
        assert!(crossing > 10_000 && crossing < 55_000, "{crossing}");
    }

    #[test]
    fn random_star_polygons_agree_with_the_pairwise_test() {
        // Corners at increasing angles (simple) with some swapped (crossing), at real
        // coordinates.
        let mut rng = Rng(17);
        let mut simple = 0;
        for case in 0..5_000 {
            let n = 4 + case % 40;
            let mut p: Vec<Point2> = (0..n)
                .map(|i| {
                    let t = std::f64::consts::TAU * (i as f64 + 0.5) / n as f64;
                    let r = 0.2 + (rng.below(1000) as f64) / 1000.0;
                    Point2::new(r * t.cos(), r * t.sin())
                })
                .collect();
            if case % 2 == 1 {
                let (a, b) = (rng.below(n as u64) as usize, rng.below(n as u64) as usize);
                p.swap(a, b);
            }
            simple += usize::from(pairwise(&p).is_none());
            check_against_pairwise(&p);
        }
        assert!(simple > 2_500 && simple < 4_900, "{simple}");
    }

    #[test]
    fn random_touches_of_simple_lattice_polygons_agree_with_the_pairwise_test() {
        // A simple polygon (lattice points sorted by angle about a centre off the lattice),
        // then one corner moved onto another edge's midpoint or corner (or left where it is):
        // many touches without a crossing.
        let mut rng = Rng(23);
        let mut touching = 0;
        for case in 0..40_000 {
            let grid = [4, 6, 10][case % 3];
            let mut p: Vec<(f64, Point2)> = (0..4 + case % 8)
                .map(|_| {
                    let q = Point2::new(rng.below(grid) as f64, rng.below(grid) as f64);
                    let c = grid as f64 / 2.0 - 0.25;
                    ((q.y - c).atan2(q.x - c), q)
                })
                .collect();
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            p.dedup_by(|a, b| a.0 == b.0);
            let mut p: Vec<Point2> = p.into_iter().map(|e| e.1).collect();
            let n = p.len();
            if n < 4 {
                continue;
            }
            let (k, j) = (rng.below(n as u64) as usize, rng.below(n as u64) as usize);
            let (a, b) = (p[j], p[(j + 1) % n]);
            p[k] = match rng.below(3) {
                0 => Point2::from((a.coords + b.coords) / 2.0),
                1 => a,
                _ => p[k],
            };
            let simple = (0..n).all(|i| p[i] != p[(i + 1) % n]);
            if simple {
                touching += usize::from(pairwise(&p).is_some());
                check_against_pairwise(&p);
            }
        }
        assert!(touching > 5_000, "{touching}");
    }

    /// A comb: `teeth` long horizontal teeth on a spine, 4 corners a tooth. Every tooth's
    /// edges span the whole width, so an x-sweep with a plain list of the edges it crosses,
    /// or a grid of cells, does O(n^2) work.
    fn comb(teeth: usize) -> Vec<Point2> {
        let mut p = vec![Point2::new(0.0, 0.0)];
        for t in 0..teeth {
            let y = t as f64;
            p.push(Point2::new(1000.0, y));
            p.push(Point2::new(1000.0, y + 0.5));
            p.push(Point2::new(1.0, y + 0.5));
            p.push(Point2::new(1.0, y + 1.0));
        }
        p.push(Point2::new(0.0, teeth as f64));
        p
    }

    #[test]
    fn a_comb_of_100000_corners_takes_n_log_n_work() {
        let p = comb(25_000);
        let n = p.len() as f64;
        assert!(n > 100_000.0);
        let (found, work) = self_crossing_counted(&p);
        assert_eq!(found, None);
        // One treap descent per edge, about 1.4 log2 n deep (a random treap's 2 ln n), and a
        // few segment tests: this comb takes about 1.5 n log2 n. A list of the edges the sweep crosses would take about n^2 / 8
        // here (half the teeth at once), the pairwise test n^2 / 2.
        let bound = 4.0 * n * n.log2();
        assert!(
            (work as f64) < bound,
            "{work} tests for {n} corners (bound {bound})"
        );
        // One tooth pushed through the next: found.
        let mut bent = p.clone();
        bent[4 * 1000 + 2].y += 0.7;
        let (i, j) = self_crossing(&bent).expect("the bent tooth crosses");
        let m = bent.len();
        assert!(segments_meet(
            &bent[i],
            &bent[(i + 1) % m],
            &bent[j],
            &bent[(j + 1) % m]
        ));
    }

    #[test]
    fn repeated_corners_and_fold_backs_are_named() {
        let pts = |v: &[(f64, f64)]| {
            v.iter()
                .map(|&(x, y)| Point2::new(x, y))
                .collect::<Vec<_>>()
        };
        // A figure eight through (1, 1): corners 0 and 3 at one point.
        let eight = pts(&[
            (1.0, 1.0),
            (2.0, 0.0),
            (2.0, 2.0),
            (1.0, 1.0),
            (0.0, 2.0),
            (0.0, 0.0),
        ]);
        assert_eq!(self_crossing(&eight), Some((0, 3)));
        // A spike: (2, 0) -> (3, 0) -> back to (2.5, 0), on edge 0's line.
        let spike = pts(&[(0.0, 0.0), (3.0, 0.0), (2.5, 0.0), (2.0, 2.0)]);
        assert_eq!(self_crossing(&spike), Some((0, 2)));
        check_against_pairwise(&spike);
    }
}
