//! The uniform grid of cells over an object's box (`method.md` s. 4a).
//!
//! The box is divided into `N_x x N_y x N_z` equal cells; the linear number of cell
//! `(n_x, n_y, n_z)` is `n_x + N_x (n_y + N_y n_z)`. Each cell lists every face whose bounding
//! box, grown by the largest cloth thickness, overlaps it (listing by vertices alone would miss
//! cells a large face crosses). A particle's segment from its previous to its new position is
//! walked through every cell it passes (Amanatides and Woo's traversal), so no face along the
//! way is missed however far the particle moves in one step.

use crate::math::{Aabb, Point3, Vec3};
use crate::mesh::TriMesh;

/// The most cells a grid may have (2^24, about 16.8 million): its cell table alone takes 4 bytes
/// a cell (64 MiB) before any face is listed. `collision.cells` of a scene is checked against it.
pub const MAX_CELLS: usize = 1 << 24;

/// A uniform grid of face lists.
#[derive(Debug, Clone)]
pub struct Grid {
    /// The box the cells divide (the object's box grown by the margin).
    pub bbox: Aabb,
    /// Cells along x, y, z.
    pub dims: [usize; 3],
    /// Cell edge lengths.
    pub cell: Vec3,
    inv_cell: Vec3,
    start: Vec<u32>,
    faces: Vec<u32>,
}

impl Grid {
    /// Lists the faces of `mesh` in a `dims` grid over its box grown by `margin`.
    pub fn build(mesh: &TriMesh, dims: [usize; 3], margin: f64) -> Grid {
        let b = mesh.bbox().expect("an object has vertices");
        let m = Vec3::repeat(margin);
        let bbox = Aabb {
            min: b.min - m,
            max: b.max + m,
        };
        let dims = dims.map(|d| d.max(1));
        let size = bbox.size();
        let cell = Vec3::new(
            size.x / dims[0] as f64,
            size.y / dims[1] as f64,
            size.z / dims[2] as f64,
        )
        .map(|c| if c > 0.0 { c } else { 1.0 });
        let mut g = Grid {
            bbox,
            dims,
            cell,
            inv_cell: cell.map(|c| 1.0 / c),
            start: Vec::new(),
            faces: Vec::new(),
        };
        let ncell = dims[0] * dims[1] * dims[2];
        let ranges: Vec<([usize; 3], [usize; 3])> = (0..mesh.faces.len())
            .map(|f| {
                let c = mesh.corners(f);
                let lo = Point3::new(
                    c[0].x.min(c[1].x).min(c[2].x),
                    c[0].y.min(c[1].y).min(c[2].y),
                    c[0].z.min(c[1].z).min(c[2].z),
                ) - m;
                let hi = Point3::new(
                    c[0].x.max(c[1].x).max(c[2].x),
                    c[0].y.max(c[1].y).max(c[2].y),
                    c[0].z.max(c[1].z).max(c[2].z),
                ) + m;
                (g.clamp_cell(&lo), g.clamp_cell(&hi))
            })
            .collect();
        let mut count = vec![0u32; ncell + 1];
        for (lo, hi) in &ranges {
            for k in lo[2]..=hi[2] {
                for j in lo[1]..=hi[1] {
                    for i in lo[0]..=hi[0] {
                        count[g.linear(i, j, k) + 1] += 1;
                    }
                }
            }
        }
        for c in 0..ncell {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut faces = vec![0u32; count[ncell] as usize];
        for (f, (lo, hi)) in ranges.iter().enumerate() {
            for k in lo[2]..=hi[2] {
                for j in lo[1]..=hi[1] {
                    for i in lo[0]..=hi[0] {
                        let c = g.linear(i, j, k);
                        faces[fill[c] as usize] = f as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        g.start = count;
        g.faces = faces;
        g
    }

    /// The linear cell number `n_x + N_x (n_y + N_y n_z)`.
    #[inline]
    pub fn linear(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// The cell of `p`, clamped into the grid.
    #[inline]
    pub fn clamp_cell(&self, p: &Point3) -> [usize; 3] {
        let axis = |a: usize| {
            let t = (p[a] - self.bbox.min[a]) * self.inv_cell[a];
            // Truncation is floor for t >= 0 (and avoids a libm call in the hot loop).
            if t > 0.0 {
                (t as usize).min(self.dims[a] - 1)
            } else {
                0
            }
        };
        [axis(0), axis(1), axis(2)]
    }

    /// Faces listed in cell `c`.
    #[inline]
    pub fn cell_faces(&self, c: usize) -> &[u32] {
        &self.faces[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// Total face entries (a face counts once per cell it is in).
    pub fn entries(&self) -> usize {
        self.faces.len()
    }

    /// Calls `visit` with the number of every cell the segment `p0 -> p1` passes through, in
    /// order; `visit` returns false to stop.
    pub fn traverse(&self, p0: &Point3, p1: &Point3, mut visit: impl FnMut(usize) -> bool) {
        let d = p1 - p0;
        // Clip the segment to the box (slabs).
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for a in 0..3 {
            if d[a] == 0.0 {
                if p0[a] < self.bbox.min[a] || p0[a] > self.bbox.max[a] {
                    return;
                }
            } else {
                let (mut ta, mut tb) = (
                    (self.bbox.min[a] - p0[a]) / d[a],
                    (self.bbox.max[a] - p0[a]) / d[a],
                );
                if ta > tb {
                    std::mem::swap(&mut ta, &mut tb);
                }
                t0 = t0.max(ta);
                t1 = t1.min(tb);
                if t0 > t1 {
                    return;
                }
            }
        }
        let start = p0 + d * t0;
        let mut cell = self.clamp_cell(&start);
        let end = self.clamp_cell(&(p0 + d * t1));
        let mut step = [0i64; 3];
        let mut t_max = [f64::INFINITY; 3];
        let mut t_delta = [f64::INFINITY; 3];
        for a in 0..3 {
            if d[a] > 0.0 {
                step[a] = 1;
                let boundary = self.bbox.min[a] + (cell[a] + 1) as f64 * self.cell[a];
                t_max[a] = (boundary - p0[a]) / d[a];
                t_delta[a] = self.cell[a] / d[a];
            } else if d[a] < 0.0 {
                step[a] = -1;
                let boundary = self.bbox.min[a] + cell[a] as f64 * self.cell[a];
                t_max[a] = (boundary - p0[a]) / d[a];
                t_delta[a] = -self.cell[a] / d[a];
            }
        }
        let max_steps = self.dims.iter().sum::<usize>() + 3;
        for _ in 0..max_steps {
            if !visit(self.linear(cell[0], cell[1], cell[2])) {
                return;
            }
            if cell == end {
                return;
            }
            let a = if t_max[0] < t_max[1] {
                if t_max[0] < t_max[2] {
                    0
                } else {
                    2
                }
            } else if t_max[1] < t_max[2] {
                1
            } else {
                2
            };
            if t_max[a] > t1 {
                return;
            }
            let next = cell[a] as i64 + step[a];
            if next < 0 || next >= self.dims[a] as i64 {
                return;
            }
            cell[a] = next as usize;
            t_max[a] += t_delta[a];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn every_face_is_in_the_cells_its_box_overlaps() {
        let m = generate::icosphere(2);
        let g = Grid::build(&m, [5, 6, 7], 0.0);
        for f in 0..m.faces.len() {
            let c = m.corners(f);
            for p in &c {
                let cell = g.clamp_cell(p);
                assert!(g
                    .cell_faces(g.linear(cell[0], cell[1], cell[2]))
                    .contains(&(f as u32)));
            }
        }
    }

    #[test]
    fn traversal_visits_contiguous_cells_along_the_segment() {
        let m = generate::cube(2.0);
        let g = Grid::build(&m, [10, 10, 10], 0.0);
        let (p0, p1) = (
            Point3::new(-3.0, -0.95, -0.37),
            Point3::new(3.0, 0.93, 0.41),
        );
        let mut cells = Vec::new();
        g.traverse(&p0, &p1, |c| {
            cells.push(c);
            true
        });
        // Every point sampled along the clipped segment lies in a visited cell.
        for s in 0..=1000 {
            let p = p0 + (p1 - p0) * (s as f64 / 1000.0);
            if g.bbox.contains(&p, 0.0) {
                let c = g.clamp_cell(&p);
                assert!(cells.contains(&g.linear(c[0], c[1], c[2])), "{p:?}");
            }
        }
        assert!(cells.len() <= 10 + 10 + 10);
        // A point segment visits its own cell.
        let mut one = Vec::new();
        g.traverse(
            &Point3::new(0.1, 0.1, 0.1),
            &Point3::new(0.1, 0.1, 0.1),
            |c| {
                one.push(c);
                true
            },
        );
        assert_eq!(one.len(), 1);
    }
}
