//! Closest points on a triangle mesh: the distance from a point to a surface.
//!
//! Faces are listed in the cells of a uniform grid their bounding boxes overlap (about two faces
//! per cell). A query visits shells of cells around the point's cell, nearest first, and stops
//! when the best distance found is below the distance to the next shell. The point-triangle
//! test is the Voronoi-region method of Ericson, *Real-Time Collision Detection*, 5.1.5.

use super::TriMesh;
use crate::math::{Aabb, Point3};

/// The closest point of triangle (a, b, c) to p.
pub fn closest_on_triangle(p: &Point3, a: &Point3, b: &Point3, c: &Point3) -> Point3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// A closest-point query structure over a mesh.
pub struct ClosestPoints<'a> {
    mesh: &'a TriMesh,
    bbox: Aabb,
    cell: f64,
    dims: [usize; 3],
    start: Vec<u32>,
    faces: Vec<u32>,
}

/// The closest point found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance.
    pub distance: f64,
    /// The point on the mesh.
    pub point: Point3,
    /// The face it is on.
    pub face: usize,
}

impl<'a> ClosestPoints<'a> {
    /// Builds the grid for `mesh` (which must have faces).
    pub fn new(mesh: &'a TriMesh) -> ClosestPoints<'a> {
        let bbox = mesh.bbox().expect("a mesh with vertices");
        let size = bbox.size();
        let target = (mesh.faces.len().max(1) as f64 / 2.0).max(1.0);
        let volume = size.x.max(1e-12) * size.y.max(1e-12) * size.z.max(1e-12);
        let mut cell = (volume / target).cbrt();
        let max_dim = size.max();
        if cell.is_nan() || cell <= 0.0 || max_dim / cell > 512.0 {
            cell = max_dim / 512.0;
        }
        let cell = cell.max(max_dim * 1e-9).max(f64::MIN_POSITIVE);
        let dims = [0, 1, 2].map(|k| ((size[k] / cell).floor() as usize + 1).min(1024));
        let cell_of = |x: f64, k: usize| {
            (((x - bbox.min[k]) / cell).floor().max(0.0) as usize).min(dims[k] - 1)
        };
        let lin = |i: usize, j: usize, k: usize| i + dims[0] * (j + dims[1] * k);
        let ncell = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; ncell + 1];
        let ranges: Vec<[usize; 6]> = (0..mesh.faces.len())
            .map(|f| {
                let c = mesh.corners(f);
                let mut r = [0usize; 6];
                for k in 0..3 {
                    let lo = c.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
                    let hi = c.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
                    r[k] = cell_of(lo, k);
                    r[k + 3] = cell_of(hi, k);
                }
                r
            })
            .collect();
        for r in &ranges {
            for k in r[2]..=r[5] {
                for j in r[1]..=r[4] {
                    for i in r[0]..=r[3] {
                        count[lin(i, j, k) + 1] += 1;
                    }
                }
            }
        }
        for c in 0..ncell {
            count[c + 1] += count[c];
        }
        let start = count.clone();
        let mut fill = count;
        let mut faces = vec![0u32; start[ncell] as usize];
        for (f, r) in ranges.iter().enumerate() {
            for k in r[2]..=r[5] {
                for j in r[1]..=r[4] {
                    for i in r[0]..=r[3] {
                        let c = lin(i, j, k);
                        faces[fill[c] as usize] = f as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        ClosestPoints {
            mesh,
            bbox,
            cell,
            dims,
            start,
            faces,
        }
    }

    /// The closest point of the mesh to `p`.
    ///
    /// The search starts at the cell nearest `p` (its projection on the grid's box when `p` is
    /// outside: no point of the box is nearer `p` than to that projection) and visits shells of
    /// cells around it until the next shell is farther than the best distance found.
    pub fn closest(&self, p: &Point3) -> Hit {
        let dims = self.dims;
        let clamped = Point3::new(
            p.x.clamp(self.bbox.min.x, self.bbox.max.x),
            p.y.clamp(self.bbox.min.y, self.bbox.max.y),
            p.z.clamp(self.bbox.min.z, self.bbox.max.z),
        );
        let outside = (p - clamped).norm();
        let home: [i64; 3] = [0, 1, 2].map(|k| {
            (((clamped[k] - self.bbox.min[k]) / self.cell).floor() as i64)
                .clamp(0, dims[k] as i64 - 1)
        });
        let mut best = Hit {
            distance: f64::INFINITY,
            point: *p,
            face: usize::MAX,
        };
        // The last shell that still holds a cell of the grid.
        let max_shell = (0..3)
            .map(|k| home[k].max(dims[k] as i64 - 1 - home[k]))
            .max()
            .unwrap_or(0);
        for shell in 0..=max_shell {
            // Cells of shell s are at least (s - 1) cells from the projection, hence from p.
            let reach = ((shell as f64 - 1.0).max(0.0) * self.cell).max(outside);
            // Nothing in this shell is nearer than `reach` (so none beats a best distance equal
            // to it: a point over a flat sheet, whose reach stays at its height for many shells);
            // an infinite reach (p at 1e308: its distance overflows) can find nothing nearer.
            if reach >= best.distance || reach == f64::INFINITY {
                break;
            }
            let s = shell;
            // The shell's offsets along axis a that stay in the grid.
            let span = |a: usize| (-s).max(-home[a])..=s.min(dims[a] as i64 - 1 - home[a]);
            for dk in span(2) {
                for dj in span(1) {
                    for di in span(0) {
                        if di.abs() != s && dj.abs() != s && dk.abs() != s {
                            continue;
                        }
                        let (i, j, k) = (home[0] + di, home[1] + dj, home[2] + dk);
                        let c = i as usize + dims[0] * (j as usize + dims[1] * k as usize);
                        for &f in &self.faces[self.start[c] as usize..self.start[c + 1] as usize] {
                            let [a, b, cc] = self.mesh.corners(f as usize);
                            let q = closest_on_triangle(p, &a, &b, &cc);
                            let d = (q - p).norm();
                            if d < best.distance {
                                best = Hit {
                                    distance: d,
                                    point: q,
                                    face: f as usize,
                                };
                            }
                        }
                    }
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn distance_to_a_sphere() {
        let m = generate::icosphere(4);
        let q = ClosestPoints::new(&m);
        for (p, expect) in [
            (Point3::new(0.0, 0.0, 0.0), 1.0),
            (Point3::new(3.0, 0.0, 0.0), 2.0),
            (Point3::new(0.1, 0.5, -0.2), 1.0 - 0.5477),
        ] {
            let h = q.closest(&p);
            assert!((h.distance - expect).abs() < 0.01, "{p:?}: {}", h.distance);
        }
    }

    #[test]
    fn grid_agrees_with_brute_force() {
        let m = generate::uv_sphere(Point3::new(0.2, -0.1, 0.3), 0.7, 9, 13);
        let q = ClosestPoints::new(&m);
        let mut rng = crate::math::SplitMix(5);
        for _ in 0..300 {
            let p = Point3::new(
                rng.next_f64() * 3.0 - 1.5,
                rng.next_f64() * 3.0 - 1.5,
                rng.next_f64() * 3.0 - 1.5,
            );
            let brute = (0..m.faces.len())
                .map(|f| {
                    let [a, b, c] = m.corners(f);
                    (closest_on_triangle(&p, &a, &b, &c) - p).norm()
                })
                .fold(f64::INFINITY, f64::min);
            assert!((q.closest(&p).distance - brute).abs() < 1e-12);
        }
    }
    /// A flat sheet in z = 0 of `nx` x `ny` squares of side `h`, two triangles each.
    fn flat_sheet(nx: u32, ny: u32, h: f64) -> TriMesh {
        let positions = (0..=ny)
            .flat_map(|j| (0..=nx).map(move |i| Point3::new(h * i as f64, h * j as f64, 0.0)))
            .collect();
        let v = |i: u32, j: u32| j * (nx + 1) + i;
        let faces = (0..ny)
            .flat_map(|j| {
                (0..nx).flat_map(move |i| {
                    [
                        [v(i, j), v(i + 1, j), v(i + 1, j + 1)],
                        [v(i, j), v(i + 1, j + 1), v(i, j + 1)],
                    ]
                })
            })
            .collect();
        TriMesh::new(positions, faces)
    }

    /// A point over a flat sheet (a grid one cell thick) is answered from the first shells: the
    /// search used to go on while the shells' reach equalled the point's height, visiting
    /// (2s+1)^3 offsets per shell out to the grid's edge (minutes for this 600 x 600 sheet).
    #[test]
    fn a_point_over_a_flat_sheet_ends_at_once() {
        let sheet = flat_sheet(600, 600, 1.0 / 600.0);
        let q = ClosestPoints::new(&sheet);
        assert_eq!(q.dims[2], 1, "{:?}", q.dims);
        assert!(q.dims[0] > 200, "{:?}", q.dims);
        for (x, y, h) in [(0.5, 0.5, 0.3), (0.01, 0.99, 2.0), (1.5, 0.5, 0.1)] {
            let hit = q.closest(&Point3::new(x, y, h));
            let dx: f64 = x - 1.0f64.min(x);
            assert!(
                (hit.distance - (h * h + dx * dx).sqrt()).abs() < 1e-12,
                "{x} {y} {h}: {hit:?}"
            );
        }
    }

    /// A point at 1e308 is infinitely far (its distance overflows): the answer comes at once,
    /// without visiting every shell of cells (on a 513-cell strip, 10^11 cells: a hang).
    #[test]
    fn hostile_point_at_1e308_ends() {
        let m = flat_sheet(1000, 60, 0.1);
        let q = ClosestPoints::new(&m);
        assert!(q.dims[0] > 500, "{:?}", q.dims);
        let h = q.closest(&Point3::new(1e308, 0.0, 0.0));
        assert_eq!(h.distance, f64::INFINITY);
        assert!((q.closest(&Point3::new(50.0, 3.0, 1.0)).distance - 1.0).abs() < 1e-12);
    }
}
