//! Horizontal sections of a triangle mesh (the plane `z = h`), and the tape-measure girth.
//!
//! A vertex counts as above the plane when `z >= h`, so a vertex exactly on it is moved up by an
//! infinitesimal (no special cases). Every face with corners on both sides yields one segment,
//! from the edge it crosses going down to the edge it crosses going up, in winding order: for an
//! outward-wound closed surface the loops run counter-clockwise seen from above. Segments are
//! chained through the mesh edges they end on (an edge is a pair of vertex indices), never by
//! comparing coordinates, so float noise cannot break or merge loops. A crossing point is
//! interpolated along its edge from the lower-numbered vertex, so both faces of an edge agree
//! bit for bit.

use super::TriMesh;
use crate::math::{Point2, Point3};
use std::collections::{HashMap, HashSet};

/// One chain of a section.
#[derive(Debug, Clone, PartialEq)]
pub struct Loop {
    /// Points in order (the closing point not repeated).
    pub points: Vec<Point3>,
    /// Whether the chain closes (it does on a closed mesh).
    pub closed: bool,
}

impl Loop {
    /// The points projected on the plane.
    pub fn xy(&self) -> Vec<Point2> {
        self.points.iter().map(|p| Point2::new(p.x, p.y)).collect()
    }
}

#[inline]
fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// A mesh edge, its ends in increasing order (see `key`).
type Edge = (u32, u32);

/// The section of `mesh` by the plane `z = h` (every face visited; for many planes of one mesh,
/// [`Slicer`] visits only the faces that reach each).
pub fn slice(mesh: &TriMesh, h: f64) -> Vec<Loop> {
    chain(mesh, h, segments(mesh, h, 0..mesh.faces.len() as u32))
}

/// The loops of the segments `(next, order)` of the section at `h`.
fn chain(mesh: &TriMesh, h: f64, (next, order): (HashMap<Edge, Edge>, Vec<Edge>)) -> Vec<Loop> {
    let cross = |(a, b): Edge| {
        let (lo, hi) = (a.min(b), a.max(b));
        let (p, q) = (mesh.positions[lo as usize], mesh.positions[hi as usize]);
        let t = (h - p.z) / (q.z - p.z);
        Point3::new(p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), h)
    };
    // Chain: start open chains at edges nothing leads to, then the closed loops.
    let targets: HashSet<Edge> = next.values().copied().collect();
    let mut used: HashSet<Edge> = HashSet::new();
    let starts: Vec<Edge> = order
        .iter()
        .filter(|e| !targets.contains(e))
        .copied()
        .chain(order.iter().copied())
        .collect();
    let mut loops = Vec::new();
    for s in starts {
        if used.contains(&s) {
            continue;
        }
        let (chain, closed) = follow(s, &next, &mut used);
        loops.push(Loop {
            points: chain.into_iter().map(cross).collect(),
            closed,
        });
    }
    loops
}

/// The segments of the section through the faces `faces` (in increasing order; the others
/// must not reach the plane): from-edge to to-edge (edges as `key`s), and the from-edges in the
/// order of the faces.
fn segments(
    mesh: &TriMesh,
    h: f64,
    faces: impl Iterator<Item = u32>,
) -> (HashMap<Edge, Edge>, Vec<Edge>) {
    let above = |v: u32| mesh.positions[v as usize].z >= h;
    let mut next: HashMap<Edge, Edge> = HashMap::new();
    let mut order: Vec<Edge> = Vec::new();
    for fi in faces {
        let f = &mesh.faces[fi as usize];
        let up: [bool; 3] = f.map(above);
        if up[0] == up[1] && up[1] == up[2] {
            continue;
        }
        let mut down_edge = None;
        let mut up_edge = None;
        for i in 0..3 {
            let (a, b) = (f[i], f[(i + 1) % 3]);
            match (up[i], up[(i + 1) % 3]) {
                (true, false) => down_edge = Some(key(a, b)),
                (false, true) => up_edge = Some(key(a, b)),
                _ => {}
            }
        }
        if let (Some(d), Some(u)) = (down_edge, up_edge) {
            if next.insert(d, u).is_none() {
                order.push(d);
            }
        }
    }
    (next, order)
}

/// Many sections of one mesh. The faces are sorted once into bands of height (about a face's
/// mean height each, so a face sits in one or two bands); a section then visits only its
/// band's faces, in increasing order, and gives the bits [`slice`] gives. Sixty sections of a
/// 47,000-face body cost a pass over the faces and the faces cut, not sixty passes.
///
/// ```
/// use drapekit::mesh::{generate, slice::{slice, Slicer}};
/// let m = generate::icosphere(3);
/// let s = Slicer::new(&m);
/// for h in [-1.5, -0.99, -0.3, 0.0, 0.42, 1.0, 2.0] {
///     assert_eq!(s.slice(h), slice(&m, h));
/// }
/// ```
pub struct Slicer<'a> {
    mesh: &'a TriMesh,
    /// The lowest vertex's height and the bands' height.
    lo: f64,
    band: f64,
    /// The faces reaching band `b`: `faces[start[b]..start[b + 1]]`, in increasing order.
    start: Vec<u32>,
    faces: Vec<u32>,
}

impl<'a> Slicer<'a> {
    /// The bands of `mesh`'s faces.
    pub fn new(mesh: &'a TriMesh) -> Slicer<'a> {
        let ranges: Vec<(f64, f64)> = (mesh.faces.iter())
            .map(|f| {
                let z = f.map(|v| mesh.positions[v as usize].z);
                (z[0].min(z[1]).min(z[2]), z[0].max(z[1]).max(z[2]))
            })
            .collect();
        let (lo, hi) = (ranges.iter())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &(l, h)| {
                (a.min(l), b.max(h))
            });
        let n = ranges.len().max(1);
        let mean = ranges.iter().map(|(l, h)| h - l).sum::<f64>() / n as f64;
        let bands = if hi > lo && mean > 0.0 {
            ((hi - lo) / mean).clamp(1.0, n as f64) as usize
        } else {
            1
        };
        let mut s = Slicer {
            mesh,
            lo,
            band: if hi > lo {
                (hi - lo) / bands as f64
            } else {
                1.0
            },
            start: vec![0; bands + 1],
            faces: Vec::new(),
        };
        s.fill(bands, &ranges);
        s
    }

    /// Band of height `z`, clamped to the bands.
    fn band_of(&self, z: f64, bands: usize) -> usize {
        let b = ((z - self.lo) / self.band).floor();
        if b.is_nan() || b < 0.0 {
            0
        } else {
            (b as usize).min(bands - 1)
        }
    }

    /// Counts, then lists each face in every band its heights `ranges` reach (faces in order).
    fn fill(&mut self, bands: usize, ranges: &[(f64, f64)]) {
        let spans: Vec<(usize, usize)> = (ranges.iter())
            .map(|&(l, h)| (self.band_of(l, bands), self.band_of(h, bands)))
            .collect();
        for &(a, b) in &spans {
            for c in &mut self.start[a + 1..=b + 1] {
                *c += 1;
            }
        }
        for b in 0..bands {
            self.start[b + 1] += self.start[b];
        }
        let mut at: Vec<u32> = self.start[..bands].to_vec();
        self.faces = vec![0; self.start[bands] as usize];
        for (fi, &(a, b)) in spans.iter().enumerate() {
            for slot in &mut at[a..=b] {
                self.faces[*slot as usize] = fi as u32;
                *slot += 1;
            }
        }
    }

    /// The section by the plane `z = h`: what [`slice`] gives, bit for bit.
    pub fn slice(&self, h: f64) -> Vec<Loop> {
        let bands = self.start.len() - 1;
        let b = self.band_of(h, bands);
        let faces = &self.faces[self.start[b] as usize..self.start[b + 1] as usize];
        chain(self.mesh, h, segments(self.mesh, h, faces.iter().copied()))
    }
}

/// The chain of edges from `s` along `next` (each marked `used`), and whether it closes.
fn follow(s: Edge, next: &HashMap<Edge, Edge>, used: &mut HashSet<Edge>) -> (Vec<Edge>, bool) {
    let mut chain = Vec::new();
    let mut e = s;
    loop {
        used.insert(e);
        chain.push(e);
        match next.get(&e) {
            Some(&n) if n == s => return (chain, true),
            Some(&n) if !used.contains(&n) => e = n,
            Some(&n) => {
                // An open chain ends on an edge with no segment leaving it.
                if !next.contains_key(&n) {
                    chain.push(n);
                }
                break;
            }
            None => break,
        }
    }
    if let Some(&n) = next.get(&e) {
        if !used.contains(&n) {
            chain.push(n);
        }
    }
    (chain, false)
}

/// The convex hull of points in the plane, counter-clockwise, without collinear points
/// (Andrew's monotone chain).
pub fn convex_hull(points: &[Point2]) -> Vec<Point2> {
    let mut p: Vec<Point2> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross =
        |o: &Point2, a: &Point2, b: &Point2| (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    let mut hull: Vec<Point2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Point2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for q in iter {
            while hull.len() >= start + 2
                && cross(&hull[hull.len() - 2], &hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(*q);
        }
        hull.pop();
    }
    hull
}

/// The tape-measure girth of a set of contours: the perimeter of their convex hull.
///
/// ```
/// use drapekit::math::Point2;
/// use drapekit::mesh::slice::girth;
/// let square_with_dent = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (1.0, 1.0), (0.0, 2.0)];
/// let p: Vec<Point2> = square_with_dent.iter().map(|&(x, y)| Point2::new(x, y)).collect();
/// assert_eq!(girth(&p), 8.0);
/// ```
pub fn girth(points: &[Point2]) -> f64 {
    let h = convex_hull(points);
    (0..h.len())
        .map(|i| (h[(i + 1) % h.len()] - h[i]).norm())
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn a_slicer_gives_the_bits_of_a_full_pass_at_every_height() {
        // A lathed body of bands of very unequal heights (one tall band among short ones, so a
        // face spans many bands of the slicer) and an icosphere; heights at the vertices
        // themselves (a face with a corner on the plane), between them, and outside the mesh.
        let profile: Vec<(f64, f64)> = (0..=40)
            .map(|i| {
                let z = if i < 20 {
                    i as f64 * 0.01
                } else {
                    0.2 + (i - 19) as f64 * 0.05
                };
                (0.3 + 0.1 * (i as f64 * 0.7).sin(), z)
            })
            .collect();
        for m in [generate::lathe(&profile, 37), generate::icosphere(4)] {
            let s = Slicer::new(&m);
            let b = m.bbox().unwrap();
            let mut heights: Vec<f64> = m.positions.iter().map(|p| p.z).collect();
            heights.extend(
                (0..=400).map(|i| b.min.z - 0.1 + (b.max.z - b.min.z + 0.2) * i as f64 / 400.0),
            );
            let mut cut = 0;
            for h in heights {
                let (a, full) = (s.slice(h), slice(&m, h));
                assert_eq!(a, full, "h = {h}");
                cut += full.len();
            }
            assert!(cut > 400, "the heights cut the mesh ({cut} loops)");
        }
    }

    #[test]
    fn sphere_section_is_one_ccw_circle() {
        let m = generate::icosphere(4);
        for h in [-0.7, 0.0, 0.31, 0.9] {
            let loops = slice(&m, h);
            assert_eq!(loops.len(), 1, "h={h}");
            let l = &loops[0];
            assert!(l.closed);
            let r = (1.0 - h * h).sqrt();
            for p in &l.points {
                let d = (p.x * p.x + p.y * p.y).sqrt();
                assert!(d <= r + 1e-12 && d > r * 0.99, "h={h} d={d} r={r}");
            }
            let xy = l.xy();
            assert!(crate::geom::signed_area2(&xy) > 0.0, "counter-clockwise");
            // Vertices sit on the sphere, so the section runs on chords just inside the circle.
            let g = girth(&xy);
            assert!(
                g < std::f64::consts::TAU * r && g > 0.995 * std::f64::consts::TAU * r,
                "h={h} {g}"
            );
        }
    }

    #[test]
    fn plane_through_vertices_and_two_bodies() {
        // The cube's vertices lie exactly on z = -0.5 and 0.5. A vertex on the plane counts as
        // above, so the plane z = 0.5 cuts just below the top and z = -0.5 just below the bottom.
        let mut m = generate::cube(1.0);
        let c2 = generate::cube(1.0);
        let n = m.positions.len() as u32;
        m.positions.extend(
            c2.positions
                .iter()
                .map(|p| p + crate::math::Vec3::new(3.0, 0.0, 0.0)),
        );
        m.faces.extend(c2.faces.iter().map(|f| f.map(|v| v + n)));
        for h in [0.5, 0.0, 0.2] {
            let loops = slice(&m, h);
            assert_eq!(loops.len(), 2, "h={h}");
            for l in &loops {
                assert!(l.closed);
                assert!((girth(&l.xy()) - 4.0).abs() < 1e-12);
            }
        }
        assert!(
            slice(&m, -0.5).is_empty(),
            "everything is above: nothing crosses"
        );
    }

    #[test]
    fn open_mesh_gives_open_chains() {
        let mut m = generate::icosphere(3);
        let keep: Vec<bool> = (0..m.faces.len())
            .map(|f| m.corners(f).iter().all(|p| p.x < 0.5))
            .collect();
        m.retain_faces(&keep);
        let loops = slice(&m, 0.0);
        assert_eq!(loops.len(), 1);
        assert!(!loops[0].closed);
    }
}
