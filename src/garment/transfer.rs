//! A garment sewn at one particle spacing carried onto the same pattern sampled at another
//! (`drape::GarmentSettings::sew_spacing`: sew coarse, drape fine).
//!
//! Both models come from the same pattern, so their pieces are the same panels in the same
//! order and each particle has a place `q` in its panel's flat pattern (`ClothModel::rest`).
//! A particle of the fine model finds the coarse triangle `(p0, p1, p2)` of its panel that
//! holds `q = b0 p0 + b1 p1 + b2 p2` (barycentric coordinates `b >= 0`, summing to 1) and
//! takes `x = b0 X0 + b1 X1 + b2 X2` of that triangle's sewn positions: the fine cloth then
//! lies on the coarse cloth's surface, through the same piecewise-linear map from the flat
//! pattern, so a fold or a closed seam of the coarse cloth is one of the fine cloth too. A
//! point outside every coarse triangle (a fine sample of a curved edge, outside the coarse
//! outline's chord by at most its sagitta) takes the nearest point of the nearest triangle.
//!
//! The holding triangle is found through a grid of square cells over the panel (edge: the
//! mean side of the triangles' boxes), each cell listing, in index order, the triangles whose
//! box meets it: a point reads its own cell, and the first listed triangle that holds it is
//! the lowest-numbered one that does, as a scan of all of them would find.

use crate::cloth::model::ClothModel;
use crate::math::{Point2, Point3};
use rayon::prelude::*;

/// How far outside a triangle, in barycentric terms, a point still counts as inside it
/// (rounding on a shared edge).
const INSIDE: f64 = 1e-9;

/// The positions of `to`'s particles on the surface of `from` at positions `from_x` (the
/// module's map). `to` and `from` are the same pattern's cloth: the same pieces, in order.
///
/// ```
/// use drapekit::cloth::model::ClothModel;
/// use drapekit::cloth::pattern::{build, Pins};
/// use drapekit::cloth::Fabric;
/// use drapekit::garment::transfer::transfer;
/// use drapekit::math::{Point2, Point3, Vec3};
/// let square = [(0.0, 0.0), (0.2, 0.0), (0.2, 0.2), (0.0, 0.2)].map(|(x, y)| Point2::new(x, y));
/// let model = |h: f64| {
///     let p = build(&square, h, &Fabric::cotton(), &Pins::default()).unwrap();
///     let x: Vec<Point3> = p.flat.iter().map(|q| Point3::new(q.x, q.y, 0.0)).collect();
///     ClothModel::assemble(&[("sq".into(), p, Fabric::cotton(), x)], Vec3::zeros())
/// };
/// let (coarse, flat) = model(0.05);
/// let (fine, _) = model(0.01);
/// // The coarse square bent into a cylinder's quarter of radius 0.2 / (pi / 2).
/// let r = 0.4 / std::f64::consts::PI;
/// let bent: Vec<Point3> = flat
///     .iter()
///     .map(|p| Point3::new(r * (p.x / r).sin(), p.y, r * (1.0 - (p.x / r).cos())))
///     .collect();
/// let x = transfer(&coarse, &bent, &fine);
/// // The fine cloth's corners are the coarse cloth's corners.
/// let far = x.iter().map(|p| p.x + p.z).fold(f64::MIN, f64::max);
/// assert!((far - (r + r)).abs() < 1e-9);
/// ```
pub fn transfer(from: &ClothModel, from_x: &[Point3], to: &ClothModel) -> Vec<Point3> {
    debug_assert_eq!(from.pieces.len(), to.pieces.len());
    let mut out = vec![Point3::origin(); to.len()];
    for (fp, tp) in from.pieces.iter().zip(&to.pieces) {
        let tris = &from.triangles[fp.first_triangle..fp.first_triangle + fp.triangles];
        let grid = TriGrid::new(&from.rest, tris);
        let range = tp.first..tp.first + tp.count;
        out[range.clone()]
            .par_iter_mut()
            .zip(&to.rest[range])
            .for_each(|(x, q)| {
                let (t, b) = locate(&from.rest, tris, &grid, q);
                let [i, j, k] = tris[t].map(|v| from_x[v as usize].coords);
                *x = Point3::from(i * b[0] + j * b[1] + k * b[2]);
            });
    }
    out
}

/// The triangles of a panel listed per cell of a square grid over their boxes (module docs).
struct TriGrid {
    lo: Point2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// Cell `c`'s triangles are `items[start[c]..start[c + 1]]`, in index order.
    start: Vec<u32>,
    items: Vec<u32>,
}

/// Cells a grid may have per triangle (a few sliver triangles cannot make it huge).
const CELLS_PER_TRIANGLE: usize = 4;

impl TriGrid {
    fn new(flat: &[Point2], tris: &[[u32; 3]]) -> TriGrid {
        let boxes: Vec<(Point2, Point2)> = (tris.iter())
            .map(|t| {
                let c = t.map(|v| flat[v as usize]);
                let lo = Point2::new(
                    c[0].x.min(c[1].x).min(c[2].x),
                    c[0].y.min(c[1].y).min(c[2].y),
                );
                let hi = Point2::new(
                    c[0].x.max(c[1].x).max(c[2].x),
                    c[0].y.max(c[1].y).max(c[2].y),
                );
                (lo, hi)
            })
            .collect();
        let mut lo = Point2::new(f64::INFINITY, f64::INFINITY);
        let mut hi = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        let mut side = 0.0;
        for (a, b) in &boxes {
            lo = Point2::new(lo.x.min(a.x), lo.y.min(a.y));
            hi = Point2::new(hi.x.max(b.x), hi.y.max(b.y));
            side += (b.x - a.x) + (b.y - a.y);
        }
        let n = boxes.len().max(1);
        let (w, h) = ((hi.x - lo.x).max(0.0), (hi.y - lo.y).max(0.0));
        let mut cell = (side / (2 * n) as f64).max(f64::MIN_POSITIVE);
        // No more than CELLS_PER_TRIANGLE cells per triangle.
        let cap = (CELLS_PER_TRIANGLE * n) as f64;
        if (w / cell + 1.0) * (h / cell + 1.0) > cap {
            cell = ((w * h / cap).sqrt()).max((w + h) / cap).max(cell);
        }
        let nx = ((w / cell) as usize + 1).min(CELLS_PER_TRIANGLE * n);
        let ny = ((h / cell) as usize + 1).min(CELLS_PER_TRIANGLE * n);
        let mut grid = TriGrid {
            lo: if boxes.is_empty() {
                Point2::origin()
            } else {
                lo
            },
            cell,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            items: Vec::new(),
        };
        let ranges: Vec<_> = (boxes.iter())
            .map(|(a, b)| (grid.index(a), grid.index(b)))
            .collect();
        let cells = |&(a, b): &((usize, usize), (usize, usize))| {
            (a.1..=b.1).flat_map(move |j| (a.0..=b.0).map(move |i| j * nx + i))
        };
        for r in &ranges {
            cells(r).for_each(|c| grid.start[c + 1] += 1);
        }
        for c in 0..nx * ny {
            grid.start[c + 1] += grid.start[c];
        }
        let mut fill = grid.start.clone();
        grid.items = vec![0; grid.start[nx * ny] as usize];
        for (t, r) in ranges.iter().enumerate() {
            for c in cells(r) {
                grid.items[fill[c] as usize] = t as u32;
                fill[c] += 1;
            }
        }
        grid
    }

    /// The cell `(i, j)` of `p`, clamped to the grid.
    fn index(&self, p: &Point2) -> (usize, usize) {
        let f = |v: f64, n: usize| (((v / self.cell).floor().max(0.0)) as usize).min(n - 1);
        (f(p.x - self.lo.x, self.nx), f(p.y - self.lo.y, self.ny))
    }

    /// The triangles listed in `q`'s cell (`q` outside the grid: the nearest cell's).
    fn near(&self, q: &Point2) -> &[u32] {
        let (i, j) = self.index(q);
        let c = j * self.nx + i;
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

/// The triangle of `tris` (indices into `flat`; `grid` built on them) that holds `q`, or the
/// nearest, and the barycentric coordinates of `q` (or of its nearest point) in it.
fn locate(flat: &[Point2], tris: &[[u32; 3]], grid: &TriGrid, q: &Point2) -> (usize, [f64; 3]) {
    let corners = |t: &[u32; 3]| t.map(|v| flat[v as usize]);
    for &n in grid.near(q) {
        let c = corners(&tris[n as usize]);
        let lo = |a: usize| c[0][a].min(c[1][a]).min(c[2][a]);
        let hi = |a: usize| c[0][a].max(c[1][a]).max(c[2][a]);
        if q.x < lo(0) || q.x > hi(0) || q.y < lo(1) || q.y > hi(1) {
            continue;
        }
        if let Some(b) = barycentric(&c, q) {
            if b.iter().all(|&w| w >= -INSIDE) {
                return (n as usize, b);
            }
        }
    }
    let mut best = (f64::INFINITY, 0, [1.0, 0.0, 0.0]);
    for (n, t) in tris.iter().enumerate() {
        let c = corners(t);
        for e in 0..3 {
            let (a, b) = (c[e], c[(e + 1) % 3]);
            let ab = b - a;
            let s = ((q - a).dot(&ab) / ab.norm_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            let d = (a + ab * s - q).norm_squared();
            if d < best.0 {
                let mut w = [0.0; 3];
                w[e] = 1.0 - s;
                w[(e + 1) % 3] = s;
                best = (d, n, w);
            }
        }
    }
    (best.1, best.2)
}

/// The barycentric coordinates of `q` in the triangle `c`; `None` for a triangle of no area.
fn barycentric(c: &[Point2; 3], q: &Point2) -> Option<[f64; 3]> {
    let (v0, v1, v2) = (c[1] - c[0], c[2] - c[0], q - c[0]);
    let den = v0.x * v1.y - v1.x * v0.y;
    if den == 0.0 {
        return None;
    }
    let b1 = (v2.x * v1.y - v1.x * v2.y) / den;
    let b2 = (v0.x * v2.y - v2.x * v0.y) / den;
    Some([1.0 - b1 - b2, b1, b2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_inside_gets_its_barycentric_coordinates_and_one_outside_the_nearest_edge() {
        let flat = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].map(|(x, y)| Point2::new(x, y));
        let tris = [[0, 1, 2], [1, 3, 2]];
        let grid = TriGrid::new(&flat, &tris);
        let locate = |q: &Point2| locate(&flat, &tris, &grid, q);
        let (t, b) = locate(&Point2::new(0.2, 0.3));
        assert_eq!(t, 0);
        for (w, e) in b.iter().zip([0.5, 0.2, 0.3]) {
            assert!((w - e).abs() < 1e-12, "{b:?}");
        }
        let (t, b) = locate(&Point2::new(0.75, 0.75));
        assert_eq!(t, 1);
        assert!(
            (b[0] - 0.25).abs() < 1e-12 && (b[1] - 0.5).abs() < 1e-12,
            "{b:?}"
        );
        // Below the bottom edge: its nearest point, a quarter of the way along.
        let (t, b) = locate(&Point2::new(0.25, -0.1));
        assert_eq!(t, 0);
        assert_eq!(b, [0.75, 0.25, 0.0]);
    }

    #[test]
    fn the_grid_finds_the_triangle_a_scan_of_all_of_them_finds() {
        // A disc of radius 0.3 m at 2 cm: a graded grid, a rim band, curved outline.
        let ring: Vec<Point2> = (0..60)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 60.0;
                Point2::new(0.3 * a.cos() + 0.1, 0.3 * a.sin() - 0.2)
            })
            .collect();
        let fabric = crate::cloth::Fabric::cotton();
        let p = crate::cloth::pattern::build(&ring, 0.02, &fabric, &Default::default()).unwrap();
        let tris = p.triangles.clone();
        let grid = TriGrid::new(&p.flat, &tris);
        assert!(grid.nx * grid.ny > 100, "{} x {} cells", grid.nx, grid.ny);
        let scan = |q: &Point2| {
            tris.iter().enumerate().find_map(|(n, t)| {
                let b = barycentric(&t.map(|v| p.flat[v as usize]), q)?;
                b.iter().all(|&w| w >= -INSIDE).then_some((n, b))
            })
        };
        let (mut inside, mut outside) = (0, 0);
        for k in 0..4000u32 {
            // Points over the disc's box and a little beyond, and every particle's own place.
            let h =
                |s: u32| ((k.wrapping_mul(2654435761).wrapping_add(s) % 10007) as f64) / 10007.0;
            let q = Point2::new(0.1 + 0.7 * (h(1) - 0.5), -0.2 + 0.7 * (h(7919) - 0.5));
            for q in [q, p.flat[k as usize % p.flat.len()]] {
                let found = locate(&p.flat, &tris, &grid, &q);
                match scan(&q) {
                    Some((n, b)) => {
                        inside += 1;
                        assert_eq!(found, (n, b), "at {q:?}");
                    }
                    None => {
                        outside += 1;
                        let b = found.1;
                        assert!(b.iter().all(|&w| (0.0..=1.0).contains(&w)), "{b:?}");
                    }
                }
            }
        }
        assert!(
            inside > 4000 && outside > 500,
            "{inside} inside, {outside} outside"
        );
    }
}
