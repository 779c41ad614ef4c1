//! Polygons to triangles: the paper's quad split, the shorter-diagonal split, and ear clipping
//! for n-gons.
//!
//! A face record lists corner indices in winding order. Before splitting, a polygon is cleaned:
//! consecutive repeated corners go (an AutoCAD 3DFACE triangle repeats its third corner as the
//! fourth), and a corner list that repeats itself (`1 2 3 4 1 2 3 4 ...`) is cut to one period.
//!
//! * A quad `(r1, r2, r3, r4)` is split `(r1, r2, r3) + (r3, r4, r1)` as the paper's LISP export
//!   does ([`QuadSplit::Paper`]), or along its shorter diagonal ([`QuadSplit::Shortest`]). A
//!   concave quad is always split through its reflex corner, the only split without overlap.
//! * An n-gon (n >= 5) is projected on the plane of its Newell normal and ear-clipped: an ear is a
//!   convex corner whose triangle holds no reflex corner (in a simple polygon, no corner at all)
//!   and whose new diagonal crosses no edge of a reflex corner near it. Corners that coincide
//!   with the ear's own corners (the two sides of a bridge to a hole) do not block it. The reflex
//!   corners are kept in a grid, so a ring of 100,000 corners takes a fraction of a second. Every triangle keeps the polygon's winding, so the triangle areas sum to the
//!   polygon's area: no overlaps.

use crate::math::{newell_normal, orient2d, tol, Point2, Point3};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// How a four-corner face becomes two triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum QuadSplit {
    /// `(r1, r2, r3) + (r3, r4, r1)`, as the paper's LISP export writes it (default).
    #[default]
    Paper,
    /// Along the shorter diagonal (better-shaped triangles).
    Shortest,
}

impl FromStr for QuadSplit {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "paper" => Ok(QuadSplit::Paper),
            "shortest" => Ok(QuadSplit::Shortest),
            _ => Err(format!(
                "unknown quad split '{s}': expected 'paper' or 'shortest'"
            )),
        }
    }
}

impl fmt::Display for QuadSplit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            QuadSplit::Paper => "paper",
            QuadSplit::Shortest => "shortest",
        })
    }
}

/// What triangulation found and did, summed over all polygons of a file.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct PolygonStats {
    /// Face records read (any corner count).
    pub polygons: usize,
    /// Triangles produced.
    pub triangles: usize,
    /// Four-corner faces split in two.
    pub quads: usize,
    /// Quads whose fourth corner is off the plane of the first three.
    pub nonplanar_quads: usize,
    /// Quads split through their reflex corner (whatever the split rule).
    pub concave_quads: usize,
    /// Faces of five or more corners, ear-clipped.
    pub ngons: usize,
    /// Four-corner records with a repeated corner, read as one triangle (AutoCAD 3DFACE).
    pub collapsed_quads: usize,
    /// Records that listed their corners more than once around, cut to one period.
    pub periodic_polygons: usize,
    /// Records with fewer than three distinct corners (dropped).
    pub degenerate_polygons: usize,
    /// Self-intersecting polygons that could not be triangulated without overlap.
    pub overlapping_polygons: usize,
}

/// Face records as read: every record's corner indices, stored flat.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Polygons {
    corners: Vec<u32>,
    starts: Vec<usize>,
}

impl Polygons {
    /// Room for about `n` records of three corners.
    pub fn with_capacity(n: usize) -> Polygons {
        Polygons {
            corners: Vec::with_capacity(3 * n),
            starts: Vec::with_capacity(n),
        }
    }

    /// Appends a record.
    pub fn push(&mut self, corners: impl IntoIterator<Item = u32>) {
        self.starts.push(self.corners.len());
        self.corners.extend(corners);
    }

    /// Number of records.
    pub fn len(&self) -> usize {
        self.starts.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.starts.is_empty()
    }

    /// Corners in all records.
    pub fn corner_count(&self) -> usize {
        self.corners.len()
    }

    /// The records, in order.
    pub fn iter(&self) -> impl Iterator<Item = &[u32]> {
        (0..self.starts.len()).map(|k| {
            let end = self
                .starts
                .get(k + 1)
                .copied()
                .unwrap_or(self.corners.len());
            &self.corners[self.starts[k]..end]
        })
    }

    /// Triangulates every record (see [`triangulate`]).
    pub fn triangulate(
        &self,
        positions: &[Point3],
        split: QuadSplit,
    ) -> (Vec<[u32; 3]>, PolygonStats) {
        let mut faces = Vec::with_capacity(self.corners.len().saturating_sub(2 * self.len()));
        let mut stats = PolygonStats::default();
        for ring in self.iter() {
            triangulate(positions, ring, split, &mut faces, &mut stats);
        }
        (faces, stats)
    }
}

/// Triangulates one face record, appending triangles to `out`.
///
/// ```
/// use drapekit::math::Point3;
/// use drapekit::mesh::polygon::{triangulate, PolygonStats, QuadSplit};
/// let p = [Point3::new(0., 0., 0.), Point3::new(1., 0., 0.), Point3::new(1., 1., 0.), Point3::new(0., 1., 0.)];
/// let (mut out, mut st) = (Vec::new(), PolygonStats::default());
/// triangulate(&p, &[0, 1, 2, 3], QuadSplit::Paper, &mut out, &mut st);
/// assert_eq!(out, vec![[0, 1, 2], [2, 3, 0]]);
/// ```
pub fn triangulate(
    positions: &[Point3],
    corners: &[u32],
    split: QuadSplit,
    out: &mut Vec<[u32; 3]>,
    stats: &mut PolygonStats,
) {
    stats.polygons += 1;
    if corners.len() == 3 {
        // Triangles pass through untouched, degenerate or not: cleaning decides about them.
        out.push([corners[0], corners[1], corners[2]]);
        stats.triangles += 1;
        return;
    }
    let mut ring: Vec<u32> = corners.to_vec();
    ring.dedup();
    while ring.len() > 1 && ring.first() == ring.last() {
        ring.pop();
    }
    let had_repeats = ring.len() != corners.len();
    if let Some(period) = smallest_period(&ring) {
        ring.truncate(period);
        stats.periodic_polygons += 1;
    }
    let mut distinct = ring.clone();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() < 3 {
        stats.degenerate_polygons += 1;
        return;
    }
    if had_repeats && corners.len() == 4 && ring.len() == 3 {
        stats.collapsed_quads += 1;
    }
    let before = out.len();
    match ring.len() {
        3 => out.push([ring[0], ring[1], ring[2]]),
        4 => split_quad(
            positions,
            [ring[0], ring[1], ring[2], ring[3]],
            split,
            out,
            stats,
        ),
        _ => {
            stats.ngons += 1;
            ear_clip(positions, &ring, out, stats);
        }
    }
    stats.triangles += out.len() - before;
}

/// Triangulates a polygon with holes in the plane z = const: `outer` counter-clockwise, each
/// hole clockwise, all as indices into `positions`. Each hole is joined to the rest by a bridge
/// (a pair of coincident edges) from its rightmost corner to the nearest corner it can see, and
/// the bridged ring is ear-clipped. Returns triangles that keep the outer ring's winding.
pub fn triangulate_with_holes(
    positions: &[Point3],
    outer: &[u32],
    holes: &[Vec<u32>],
) -> Vec<[u32; 3]> {
    let mut ring: Vec<u32> = outer.to_vec();
    let mut holes: Vec<&Vec<u32>> = holes.iter().filter(|h| h.len() >= 3).collect();
    // Rightmost holes first, so later bridges can pass by earlier ones.
    let right = |h: &Vec<u32>| {
        h.iter()
            .map(|&i| positions[i as usize].x)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    holes.sort_by(|a, b| right(b).total_cmp(&right(a)));
    for (hi, hole) in holes.iter().enumerate() {
        let m = (0..hole.len())
            .max_by(|&a, &b| {
                positions[hole[a] as usize]
                    .x
                    .total_cmp(&positions[hole[b] as usize].x)
            })
            .unwrap();
        let pm = positions[hole[m] as usize];
        // Every edge a bridge must not cross: the ring so far and the holes not yet joined.
        let mut edges: Vec<(Point3, Point3)> = (0..ring.len())
            .map(|i| {
                (
                    positions[ring[i] as usize],
                    positions[ring[(i + 1) % ring.len()] as usize],
                )
            })
            .collect();
        for h in holes.iter().skip(hi) {
            edges.extend((0..h.len()).map(|i| {
                (
                    positions[h[i] as usize],
                    positions[h[(i + 1) % h.len()] as usize],
                )
            }));
        }
        let mut order: Vec<usize> = (0..ring.len()).collect();
        order.sort_by(|&a, &b| {
            (positions[ring[a] as usize] - pm)
                .norm_squared()
                .total_cmp(&(positions[ring[b] as usize] - pm).norm_squared())
        });
        let visible = |k: usize| {
            let pv = positions[ring[k] as usize];
            let (a, b) = (Point2::new(pm.x, pm.y), Point2::new(pv.x, pv.y));
            edges.iter().all(|(e0, e1)| {
                let (c, d) = (Point2::new(e0.x, e0.y), Point2::new(e1.x, e1.y));
                c == a || c == b || d == a || d == b || !segments_cross(&a, &b, &c, &d)
            })
        };
        let k = order
            .iter()
            .copied()
            .find(|&k| visible(k))
            .unwrap_or(order[0]);
        // ring[..=k], hole from m around back to m, ring[k..].
        let mut joined = Vec::with_capacity(ring.len() + hole.len() + 2);
        joined.extend_from_slice(&ring[..=k]);
        for j in 0..=hole.len() {
            joined.push(hole[(m + j) % hole.len()]);
        }
        joined.extend_from_slice(&ring[k..]);
        ring = joined;
    }
    let mut out = Vec::with_capacity(ring.len());
    let mut stats = PolygonStats::default();
    if ring.len() == 3 {
        out.push([ring[0], ring[1], ring[2]]);
    } else {
        ear_clip(positions, &ring, &mut out, &mut stats);
    }
    out
}

/// The smallest period `p < n` with `ring[i] == ring[i % p]`, if the ring repeats itself.
fn smallest_period(ring: &[u32]) -> Option<usize> {
    let n = ring.len();
    (3..n)
        .filter(|&p| n.is_multiple_of(p))
        .find(|&p| (p..n).all(|i| ring[i] == ring[i % p]))
}

fn split_quad(
    positions: &[Point3],
    q: [u32; 4],
    split: QuadSplit,
    out: &mut Vec<[u32; 3]>,
    stats: &mut PolygonStats,
) {
    stats.quads += 1;
    let p = q.map(|i| positions[i as usize]);
    let d02 = (p[2] - p[0]).norm();
    let d13 = (p[3] - p[1]).norm();
    let n012 = (p[1] - p[0]).cross(&(p[2] - p[0]));
    let nn = n012.norm();
    let off_plane = if nn > 0.0 {
        ((p[3] - p[0]).dot(&n012) / nn).abs()
    } else {
        0.0
    };
    if off_plane > tol::NONPLANAR_QUAD_REL * d02.max(d13) {
        stats.nonplanar_quads += 1;
    }
    // Convexity about the Newell normal: a reflex corner turns against it.
    let normal = newell_normal(p.iter().copied());
    let reflex: Vec<usize> = (0..4)
        .filter(|&i| {
            let a = p[(i + 3) % 4];
            let b = p[i];
            let c = p[(i + 1) % 4];
            (b - a).cross(&(c - b)).dot(&normal) < 0.0
        })
        .collect();
    let through = match reflex.as_slice() {
        [r] => {
            stats.concave_quads += 1;
            *r % 2
        }
        [] => match split {
            QuadSplit::Paper => 0,
            QuadSplit::Shortest => usize::from(d13 < d02),
        },
        _ => {
            // Two or more reflex corners: a bow-tie, which no split can mend.
            stats.overlapping_polygons += 1;
            0
        }
    };
    if through == 0 {
        out.push([q[0], q[1], q[2]]);
        out.push([q[2], q[3], q[0]]);
    } else {
        out.push([q[1], q[2], q[3]]);
        out.push([q[3], q[0], q[1]]);
    }
}

/// An ear candidate in the priority queue: best shape first, then lowest corner.
#[derive(PartialEq)]
struct Ear {
    quality: f64,
    corner: usize,
    version: u32,
}

impl Eq for Ear {}

impl PartialOrd for Ear {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ear {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.quality
            .total_cmp(&other.quality)
            .then(other.corner.cmp(&self.corner))
    }
}

/// Ear clipping of a cleaned ring of five or more corners. The best-shaped ear (area over the
/// squared longest edge) goes first, so near-collinear runs are not cut into slivers; after each
/// clip only the two neighbours are re-examined. An ear test looks only at the reflex corners
/// near the ear ([`EarRing`]): O(n log n) for typical polygons (a convex one has none).
fn ear_clip(positions: &[Point3], ring: &[u32], out: &mut Vec<[u32; 3]>, stats: &mut PolygonStats) {
    let Some(pts) = project(positions, ring) else {
        stats.degenerate_polygons += 1;
        return;
    };
    let n = ring.len();
    let mut r = EarRing::new(&pts);
    let mut version = vec![0u32; n];
    let mut heap = std::collections::BinaryHeap::new();
    for i in 0..n {
        if let Some(quality) = r.ear_quality(i) {
            heap.push(Ear {
                quality,
                corner: i,
                version: 0,
            });
        }
    }
    let mut overlapped = false;
    let mut last = 0;
    let mut tris: Vec<[usize; 3]> = Vec::with_capacity(n - 2);
    while r.remaining > 3 {
        let i = loop {
            match heap.pop() {
                Some(e) if r.alive[e.corner] && version[e.corner] == e.version => break e.corner,
                Some(_) => continue,
                None => break r.fallback_ear(&mut overlapped),
            }
        };
        let (a, c) = (r.prev[i], r.next[i]);
        tris.push([a, i, c]);
        r.clip(i);
        last = c;
        for j in [a, c] {
            version[j] += 1;
            if let Some(quality) = r.ear_quality(j) {
                heap.push(Ear {
                    quality,
                    corner: j,
                    version: version[j],
                });
            }
        }
    }
    tris.push([r.prev[last], last, r.next[last]]);
    flip_flat_triangles(&pts, &mut tris);
    out.extend(tris.iter().map(|t| t.map(|i| ring[i])));
    if overlapped {
        stats.overlapping_polygons += 1;
    }
}

/// The ring's corners projected on the plane of its Newell normal, counter-clockwise; `None`
/// when the normal is zero (no area).
fn project(positions: &[Point3], ring: &[u32]) -> Option<Vec<Point2>> {
    let normal = newell_normal(ring.iter().map(|&i| positions[i as usize]));
    let k = normal.iamax();
    if normal[k] == 0.0 || normal[k].is_nan() {
        return None;
    }
    // Drop axis k; the cyclic order of the other two keeps the winding counter-clockwise.
    let (u, v) = if normal[k] > 0.0 {
        ((k + 1) % 3, (k + 2) % 3)
    } else {
        ((k + 2) % 3, (k + 1) % 3)
    };
    Some(
        ring.iter()
            .map(|&i| {
                let p = positions[i as usize];
                Point2::new(p[u], p[v])
            })
            .collect(),
    )
}

/// The corners left in an ear clipping: a doubly linked ring, and its reflex (or flat) corners,
/// the only ones that can lie in an ear of a simple polygon, listed and in a grid.
struct EarRing<'a> {
    pts: &'a [Point2],
    next: Vec<usize>,
    prev: Vec<usize>,
    alive: Vec<bool>,
    remaining: usize,
    reflex: ReflexCorners,
}

impl<'a> EarRing<'a> {
    fn new(pts: &'a [Point2]) -> EarRing<'a> {
        let n = pts.len();
        let mut r = EarRing {
            pts,
            next: (0..n).map(|i| (i + 1) % n).collect(),
            prev: (0..n).map(|i| (i + n - 1) % n).collect(),
            alive: vec![true; n],
            remaining: n,
            reflex: ReflexCorners::new(pts),
        };
        for i in 0..n {
            r.classify(i);
        }
        r
    }

    /// Lists corner `i` with the reflex corners when it turns clockwise or not at all.
    fn classify(&mut self, i: usize) {
        let p = self.pts;
        let convex = orient2d(&p[self.prev[i]], &p[i], &p[self.next[i]]) > 0.0;
        self.reflex.set(i, &p[i], self.alive[i] && !convex);
    }

    /// Removes corner `b`: its neighbours become joined, and may stop being reflex.
    fn clip(&mut self, b: usize) {
        let (a, c) = (self.prev[b], self.next[b]);
        self.next[a] = c;
        self.prev[c] = a;
        self.alive[b] = false;
        self.remaining -= 1;
        for i in [a, b, c] {
            self.classify(i);
        }
    }

    /// The ear's shape (area over the squared longest edge) when corner `i` is a proper ear.
    fn ear_quality(&self, i: usize) -> Option<f64> {
        let (a, c) = (self.prev[i], self.next[i]);
        if !self.is_ear(a, i, c, false) {
            return None;
        }
        let p = self.pts;
        let area = orient2d(&p[a], &p[i], &p[c]);
        let longest = (p[i] - p[a])
            .norm_squared()
            .max((p[c] - p[i]).norm_squared())
            .max((p[a] - p[c]).norm_squared());
        Some(area / longest)
    }

    /// When no proper ear is left: a flat one, else the most convex corner (a self-intersecting
    /// ring, which sets `overlapped`).
    fn fallback_ear(&self, overlapped: &mut bool) -> usize {
        let live: Vec<usize> = (0..self.alive.len()).filter(|&j| self.alive[j]).collect();
        if let Some(j) = live
            .iter()
            .copied()
            .find(|&j| self.is_ear(self.prev[j], j, self.next[j], true))
        {
            return j;
        }
        *overlapped = true;
        let turn = |j: usize| {
            orient2d(
                &self.pts[self.prev[j]],
                &self.pts[j],
                &self.pts[self.next[j]],
            )
        };
        live.iter()
            .copied()
            .max_by(|&x, &y| turn(x).total_cmp(&turn(y)))
            .unwrap()
    }

    /// Whether (a, b, c) is an ear: it turns counter-clockwise (or is flat, when allowed), holds
    /// no reflex corner (corners that coincide with its own do not count), and no edge of a
    /// reflex corner near it crosses its new diagonal c -> a.
    fn is_ear(&self, a: usize, b: usize, c: usize, allow_flat: bool) -> bool {
        let (pa, pb, pc) = (self.pts[a], self.pts[b], self.pts[c]);
        let area = orient2d(&pa, &pb, &pc);
        if area < 0.0 || (area == 0.0 && !allow_flat) {
            return false;
        }
        let blocks = |j: usize| {
            let q = self.pts[j];
            let inside = area > 0.0
                && !(q == pa || q == pb || q == pc)
                && orient2d(&pa, &pb, &q) >= 0.0
                && orient2d(&pb, &pc, &q) >= 0.0
                && orient2d(&pc, &pa, &q) >= 0.0;
            inside
                || self.edge_crosses(j, self.next[j], &pc, &pa)
                || self.edge_crosses(self.prev[j], j, &pc, &pa)
        };
        let (lo, hi) = (pa.inf(&pb).inf(&pc), pa.sup(&pb).sup(&pc));
        !self.reflex.near(&lo, &hi).any(blocks)
    }

    /// Whether the edge `j -> k` crosses the segment `p0 -> p1` without sharing an end point.
    fn edge_crosses(&self, j: usize, k: usize, p0: &Point2, p1: &Point2) -> bool {
        let (q0, q1) = (self.pts[j], self.pts[k]);
        let shares = q0 == *p0 || q0 == *p1 || q1 == *p0 || q1 == *p1;
        !shares && segments_cross(p0, p1, &q0, &q1)
    }
}

/// The reflex corners of a projected ring, in a list and in a uniform grid of about one cell
/// per corner of the ring, so that the corners near a box are found by the cells it covers, or
/// by the list when that is shorter.
struct ReflexCorners {
    min: Point2,
    /// Cells per unit of half the coordinate (halves keep `max - min` finite for any input).
    scale: [f64; 2],
    dims: [usize; 2],
    cells: Vec<Vec<u32>>,
    list: Vec<u32>,
    /// Where each listed corner is in `list` (`usize::MAX`: not listed).
    slot: Vec<usize>,
}

impl ReflexCorners {
    fn new(pts: &[Point2]) -> ReflexCorners {
        let n = pts.len();
        let (lo, hi) = pts
            .iter()
            .fold((pts[0], pts[0]), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
        let half = [0, 1].map(|k| hi[k] * 0.5 - lo[k] * 0.5);
        let usable = half.iter().all(|h| h.is_finite() && *h > 0.0);
        let dims = if usable {
            let nx = ((n as f64 * half[0] / half[1]).sqrt().ceil() as usize).clamp(1, n);
            [nx, n.div_ceil(nx)]
        } else {
            [1, 1]
        };
        let scale = [0, 1].map(|k| {
            if usable {
                dims[k] as f64 / half[k]
            } else {
                0.0
            }
        });
        ReflexCorners {
            min: lo,
            scale,
            dims,
            cells: vec![Vec::new(); dims[0] * dims[1]],
            list: Vec::new(),
            slot: vec![usize::MAX; n],
        }
    }

    /// The cell of `p`, clamped into the grid (monotone in each coordinate).
    fn cell(&self, p: &Point2) -> [usize; 2] {
        [0, 1].map(|k| {
            let c = (p[k] * 0.5 - self.min[k] * 0.5) * self.scale[k];
            if c > 0.0 {
                (c as usize).min(self.dims[k] - 1)
            } else {
                0
            }
        })
    }

    /// Lists corner `i` at `p`, or takes it off the lists.
    fn set(&mut self, i: usize, p: &Point2, reflex: bool) {
        if reflex == (self.slot[i] != usize::MAX) {
            return;
        }
        let [x, y] = self.cell(p);
        let cell = &mut self.cells[x + self.dims[0] * y];
        if reflex {
            self.slot[i] = self.list.len();
            self.list.push(i as u32);
            cell.push(i as u32);
            return;
        }
        let at = self.slot[i];
        self.list.swap_remove(at);
        if let Some(&moved) = self.list.get(at) {
            self.slot[moved as usize] = at;
        }
        self.slot[i] = usize::MAX;
        if let Some(k) = cell.iter().position(|&j| j as usize == i) {
            cell.swap_remove(k);
        }
    }

    /// Reflex corners in the cells the box `lo..hi` covers (all of them when the box covers
    /// more cells than there are reflex corners).
    fn near(&self, lo: &Point2, hi: &Point2) -> Box<dyn Iterator<Item = usize> + '_> {
        let (a, b) = (self.cell(lo), self.cell(hi));
        if (b[0] - a[0] + 1) * (b[1] - a[1] + 1) > self.list.len() {
            return Box::new(self.list.iter().map(|&j| j as usize));
        }
        Box::new((a[1]..=b[1]).flat_map(move |y| {
            (a[0]..=b[0])
                .flat_map(move |x| self.cells[x + self.dims[0] * y].iter().map(|&j| j as usize))
        }))
    }
}

/// Triangles flatter than this (twice the area over the squared longest edge) are flipped away.
const FLAT: f64 = 1e-9;

/// Removes flat triangles (three nearly collinear corners, left where the ring has straight
/// runs) by flipping each one's longest edge with the triangle across it, when both new
/// triangles keep the winding. The triangle across an edge is found in a map of directed edges.
fn flip_flat_triangles(pts: &[Point2], tris: &mut [[usize; 3]]) {
    let flatness = |t: &[usize; 3]| {
        let (a, b, c) = (pts[t[0]], pts[t[1]], pts[t[2]]);
        let longest = (b - a)
            .norm_squared()
            .max((c - b).norm_squared())
            .max((a - c).norm_squared());
        if longest == 0.0 {
            0.0
        } else {
            orient2d(&a, &b, &c) / longest
        }
    };
    let mut across = EdgeOwners::default();
    for (t, tri) in tris.iter().enumerate() {
        across.insert(tri, t);
    }
    for _ in 0..tris.len() {
        let mut changed = false;
        for t in 0..tris.len() {
            if flatness(&tris[t]) > FLAT {
                continue;
            }
            // Rotate so the longest edge is (p, q), r opposite.
            let tri = tris[t];
            let len = |k: usize| (pts[tri[(k + 1) % 3]] - pts[tri[k]]).norm_squared();
            let k = (0..3).max_by(|&x, &y| len(x).total_cmp(&len(y))).unwrap();
            let (p, q, r) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let Some(u) = across.get(q, p).filter(|&u| u != t) else {
                continue;
            };
            let j = (0..3)
                .find(|&j| tris[u][j] == q && tris[u][(j + 1) % 3] == p)
                .unwrap();
            let s = tris[u][(j + 2) % 3];
            let (t1, t2) = ([r, p, s], [s, q, r]);
            if flatness(&t1) > FLAT && flatness(&t2) > FLAT {
                across.remove(&tris[t], t);
                across.remove(&tris[u], u);
                tris[t] = t1;
                tris[u] = t2;
                across.insert(&t1, t);
                across.insert(&t2, u);
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
}

/// Which triangle holds each directed edge.
#[derive(Default)]
struct EdgeOwners(std::collections::HashMap<(usize, usize), usize>);

impl EdgeOwners {
    fn edges(tri: &[usize; 3]) -> [(usize, usize); 3] {
        [0, 1, 2].map(|k| (tri[k], tri[(k + 1) % 3]))
    }

    fn insert(&mut self, tri: &[usize; 3], t: usize) {
        for e in Self::edges(tri) {
            self.0.entry(e).or_insert(t);
        }
    }

    fn remove(&mut self, tri: &[usize; 3], t: usize) {
        for e in Self::edges(tri) {
            if self.0.get(&e) == Some(&t) {
                self.0.remove(&e);
            }
        }
    }

    fn get(&self, a: usize, b: usize) -> Option<usize> {
        self.0.get(&(a, b)).copied()
    }
}

/// Whether segments (p0, p1) and (q0, q1) cross at a point interior to both.
fn segments_cross(p0: &Point2, p1: &Point2, q0: &Point2, q1: &Point2) -> bool {
    let d1 = orient2d(p0, p1, q0);
    let d2 = orient2d(p0, p1, q1);
    let d3 = orient2d(q0, q1, p0);
    let d4 = orient2d(q0, q1, p1);
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(p: &[Point3], ring: &[u32], split: QuadSplit) -> (Vec<[u32; 3]>, PolygonStats) {
        let mut out = Vec::new();
        let mut st = PolygonStats::default();
        triangulate(p, ring, split, &mut out, &mut st);
        (out, st)
    }

    fn pts2(xy: &[(f64, f64)]) -> Vec<Point3> {
        xy.iter().map(|&(x, y)| Point3::new(x, y, 0.0)).collect()
    }

    /// Sum of signed triangle areas along +z and the sum of their absolute values.
    fn areas(p: &[Point3], tris: &[[u32; 3]]) -> (f64, f64) {
        let mut s = 0.0;
        let mut a = 0.0;
        for t in tris {
            let [x, y, z] = t.map(|i| p[i as usize]);
            let ar = 0.5 * (y - x).cross(&(z - x)).z;
            s += ar;
            a += ar.abs();
        }
        (s, a)
    }

    #[test]
    fn paper_and_shortest_splits() {
        // A long thin quad: diagonal 1-3 is the shorter one.
        let p = pts2(&[(0.0, 0.0), (10.0, 0.0), (11.0, 1.0), (1.0, 1.0)]);
        let (paper, _) = run(&p, &[0, 1, 2, 3], QuadSplit::Paper);
        assert_eq!(paper, vec![[0, 1, 2], [2, 3, 0]]);
        let (short, _) = run(&p, &[0, 1, 2, 3], QuadSplit::Shortest);
        assert_eq!(short, vec![[1, 2, 3], [3, 0, 1]]);
    }

    #[test]
    fn concave_quad_splits_through_reflex_corner() {
        // Dart: corner 1 is reflex, so the paper diagonal 0-2 would overlap.
        let p = pts2(&[(0.0, 0.0), (1.0, 0.3), (2.0, 0.0), (1.0, 2.0)]);
        let p = vec![p[0], p[1], p[2], p[3]];
        let (t, st) = run(&p, &[0, 1, 2, 3], QuadSplit::Paper);
        assert_eq!(st.concave_quads, 1);
        let (signed, abs) = areas(&p, &t);
        assert!((signed - abs).abs() < 1e-12, "overlap: {t:?}");
    }

    #[test]
    fn autocad_triangle_with_repeated_corner() {
        let p = pts2(&[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]);
        let (t, st) = run(&p, &[0, 1, 2, 2], QuadSplit::Paper);
        assert_eq!(t, vec![[0, 1, 2]]);
        assert_eq!(st.collapsed_quads, 1);
        assert_eq!(st.quads, 0);
    }

    #[test]
    fn periodic_ring_is_cut_to_one_period() {
        let p = pts2(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
        let ring: Vec<u32> = (0..40).map(|i| i % 4).collect();
        let (t, st) = run(&p, &ring, QuadSplit::Paper);
        assert_eq!(t.len(), 2);
        assert_eq!(st.periodic_polygons, 1);
    }

    #[test]
    fn degenerate_record_is_dropped() {
        let p = pts2(&[(0.0, 0.0), (1.0, 0.0)]);
        let (t, st) = run(&p, &[0, 1, 1, 0], QuadSplit::Paper);
        assert!(t.is_empty());
        assert_eq!(st.degenerate_polygons, 1);
    }

    #[test]
    fn concave_ngon_has_no_overlap() {
        // A comb: 5 teeth, 22 corners, strongly concave.
        let mut xy = vec![(0.0, 0.0), (10.0, 0.0)];
        for t in (0..5).rev() {
            let x = 2.0 * t as f64;
            xy.push((x + 2.0, 5.0));
            xy.push((x + 1.0, 5.0));
            xy.push((x + 1.0, 1.0));
            xy.push((x, 1.0));
        }
        let p = pts2(&xy);
        let ring: Vec<u32> = (0..p.len() as u32).collect();
        let (t, st) = run(&p, &ring, QuadSplit::Paper);
        assert_eq!(t.len(), p.len() - 2);
        assert_eq!(st.overlapping_polygons, 0);
        let (signed, abs) = areas(&p, &t);
        let shoelace = 0.5 * newell_normal(p.iter().copied()).z;
        assert!((signed - shoelace).abs() < 1e-9 && (abs - shoelace).abs() < 1e-9);
    }

    #[test]
    fn clockwise_ngon_keeps_its_winding() {
        let xy: Vec<(f64, f64)> = (0..7)
            .map(|i| (-(i as f64) * 0.9).sin_cos())
            .map(|(s, c)| (c, s))
            .collect();
        let p = pts2(&xy);
        let ring: Vec<u32> = (0..7).collect();
        let (t, _) = run(&p, &ring, QuadSplit::Paper);
        for tri in &t {
            let [a, b, c] = tri.map(|i| p[i as usize]);
            assert!((b - a).cross(&(c - a)).z < 0.0);
        }
    }

    #[test]
    fn collinear_runs_leave_no_flat_triangle() {
        // A rectangle with many corners along its long sides (a subdivided CAD edge).
        let mut xy: Vec<(f64, f64)> = (0..=20).map(|i| (i as f64 * 0.5, 0.0)).collect();
        xy.extend((0..=20).rev().map(|i| (i as f64 * 0.5, 1.0)));
        let p = pts2(&xy);
        let ring: Vec<u32> = (0..p.len() as u32).collect();
        let (t, st) = run(&p, &ring, QuadSplit::Paper);
        assert_eq!((t.len(), st.overlapping_polygons), (p.len() - 2, 0));
        for tri in &t {
            let [a, b, c] = tri.map(|i| p[i as usize]);
            assert!((b - a).cross(&(c - a)).z > 0.1, "flat or flipped: {tri:?}");
        }
    }

    #[test]
    fn polygon_with_two_holes() {
        // A 10 x 4 rectangle with two 2 x 2 square holes.
        let mut xy = vec![(0.0, 0.0), (10.0, 0.0), (10.0, 4.0), (0.0, 4.0)];
        xy.extend([(1.0, 1.0), (1.0, 3.0), (3.0, 3.0), (3.0, 1.0)]);
        xy.extend([(6.0, 1.0), (6.0, 3.0), (8.0, 3.0), (8.0, 1.0)]);
        let p = pts2(&xy);
        let t = triangulate_with_holes(&p, &[0, 1, 2, 3], &[vec![4, 5, 6, 7], vec![8, 9, 10, 11]]);
        let (signed, abs) = areas(&p, &t);
        assert!(
            (signed - 32.0).abs() < 1e-12 && (abs - 32.0).abs() < 1e-12,
            "{signed} {abs}"
        );
        assert_eq!(t.len(), 12 + 2 * 2 - 2, "V + 2H - 2 triangles");
    }

    #[test]
    fn square_with_bridged_hole() {
        // Outer square CCW, a bridge to an inner square walked CW, back along the bridge.
        let p = pts2(&[
            (0.0, 0.0),
            (4.0, 0.0),
            (4.0, 4.0),
            (0.0, 4.0),
            (1.0, 1.0),
            (1.0, 3.0),
            (3.0, 3.0),
            (3.0, 1.0),
        ]);
        let ring = [0, 1, 2, 3, 0, 4, 5, 6, 7, 4];
        let (t, st) = run(&p, &ring, QuadSplit::Paper);
        assert_eq!(st.overlapping_polygons, 0);
        let (signed, abs) = areas(&p, &t);
        assert!((signed - 12.0).abs() < 1e-12, "area {signed}");
        assert!((abs - 12.0).abs() < 1e-12, "overlap: {abs}");
    }
    /// A ring of `n` corners at angle `2 pi i / n` and the radius `radius(i)`, and its area.
    fn big_ring(n: usize, radius: impl Fn(usize) -> f64) -> (Vec<Point3>, Vec<u32>) {
        let p: Vec<Point3> = (0..n)
            .map(|i| {
                let (s, c) = (std::f64::consts::TAU * i as f64 / n as f64).sin_cos();
                Point3::new(radius(i) * c, radius(i) * s, 0.0)
            })
            .collect();
        (p, (0..n as u32).collect())
    }

    fn assert_exact_cover(p: &[Point3], ring: &[u32]) {
        let (t, st) = run(p, ring, QuadSplit::Paper);
        assert_eq!((t.len(), st.overlapping_polygons), (ring.len() - 2, 0));
        let (signed, abs) = areas(p, &t);
        let shoelace = 0.5 * newell_normal(p.iter().copied()).z;
        assert!(
            (signed - shoelace).abs() < 1e-9 * shoelace,
            "{signed} {shoelace}"
        );
        assert!(
            (abs - shoelace).abs() < 1e-9 * shoelace,
            "overlap: {abs} {shoelace}"
        );
    }

    #[test]
    fn hostile_100k_corner_convex_polygon() {
        let (p, ring) = big_ring(100_000, |_| 1.0);
        assert_exact_cover(&p, &ring);
    }

    #[test]
    fn hostile_100k_corner_star_polygon() {
        let (p, ring) = big_ring(100_000, |i| if i % 2 == 0 { 1.0 } else { 0.6 });
        assert_exact_cover(&p, &ring);
    }
}
