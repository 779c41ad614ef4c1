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
//! The holding triangle is found through the body collision's uniform grid (`collide::Grid`)
//! over the panel's flat pattern, its cells about as wide as the triangles' boxes, each
//! listing in index order the triangles whose box meets it: a point reads its own cell, and
//! the first listed triangle that holds it is the lowest-numbered one that does, as a scan of
//! all of them would find.

use crate::cloth::model::ClothModel;
use crate::collide::grid::Grid;
use crate::math::{Point2, Point3, Vec3};
use crate::mesh::TriMesh;
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
        let grid = panel_grid(&from.rest, fp.first, fp.count, tris);
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

/// Cells a panel's grid may have per triangle (a few sliver triangles cannot make it huge).
const CELLS_PER_TRIANGLE: f64 = 4.0;

/// The panel's triangles `tris` (indices into `flat`, the panel's particles from `first`)
/// listed per cell of a `collide::Grid` over its flat pattern (at z = 0), the cells about as
/// wide as the triangles' boxes: face `t` of the grid is `tris[t]`.
fn panel_grid(flat: &[Point2], first: usize, count: usize, tris: &[[u32; 3]]) -> Grid {
    let positions: Vec<Point3> = (flat[first..first + count].iter())
        .map(|p| Point3::new(p.x, p.y, 0.0))
        .collect();
    let local = tris.iter().map(|t| t.map(|v| v - first as u32)).collect();
    let mesh = TriMesh::new(positions, local);
    let size = mesh.bbox().map_or(Vec3::zeros(), |b| b.size());
    let n = tris.len().max(1) as f64;
    let mean_side = (0..mesh.faces.len())
        .map(|f| {
            let c = mesh.corners(f);
            let span =
                |a: usize| c[0][a].max(c[1][a]).max(c[2][a]) - c[0][a].min(c[1][a]).min(c[2][a]);
            (span(0) + span(1)) / 2.0
        })
        .sum::<f64>()
        / n;
    let cap = CELLS_PER_TRIANGLE * n;
    let cell = (mean_side.max((size.x * size.y / cap).sqrt()))
        .max((size.x + size.y) / cap)
        .max(f64::MIN_POSITIVE);
    let along = |w: f64| ((w / cell).ceil() as usize).max(1);
    Grid::build(&mesh, [along(size.x), along(size.y), 1], 0.0)
}

/// The triangles listed in `q`'s cell of `grid` (`q` outside it: the nearest cell's).
fn near<'g>(grid: &'g Grid, q: &Point2) -> &'g [u32] {
    let [i, j, k] = grid.clamp_cell(&Point3::new(q.x, q.y, 0.0));
    grid.cell_faces(grid.linear(i, j, k))
}

/// The triangle of `tris` (indices into `flat`; `grid` from [`panel_grid`] on them) that
/// holds `q`, or the nearest, and the barycentric coordinates of `q` (or of its nearest point)
/// in it.
fn locate(flat: &[Point2], tris: &[[u32; 3]], grid: &Grid, q: &Point2) -> (usize, [f64; 3]) {
    let corners = |t: &[u32; 3]| t.map(|v| flat[v as usize]);
    for &n in near(grid, q) {
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
        let grid = panel_grid(&flat, 0, flat.len(), &tris);
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
        let grid = panel_grid(&p.flat, 0, p.flat.len(), &tris);
        assert!(grid.dims[0] * grid.dims[1] > 100, "{:?} cells", grid.dims);
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
