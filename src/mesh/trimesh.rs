//! The triangle mesh every job passes around: positions and `[u32; 3]` faces.
//!
//! A face's corner order is its winding; its normal follows the right-hand rule
//! `(p1 - p0) x (p2 - p0)`. Nothing here repairs anything: see `weld`, `clean` and `orient`.

use crate::math::{Aabb, Point3, Vec3};

/// An indexed triangle mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<Point3>,
    /// Triangles as indices into `positions`, in winding order.
    pub faces: Vec<[u32; 3]>,
}

impl TriMesh {
    /// A mesh from positions and faces (not validated: see [`TriMesh::check`]).
    pub fn new(positions: Vec<Point3>, faces: Vec<[u32; 3]>) -> TriMesh {
        TriMesh { positions, faces }
    }

    /// Bounding box of all positions; `None` for an empty mesh.
    pub fn bbox(&self) -> Option<Aabb> {
        Aabb::of_points(&self.positions)
    }

    /// Bounding-box diagonal (0 for an empty mesh).
    pub fn diagonal(&self) -> f64 {
        self.bbox().map_or(0.0, |b| b.diagonal())
    }

    /// The three corner positions of face `f`.
    #[inline]
    pub fn corners(&self, f: usize) -> [Point3; 3] {
        let [a, b, c] = self.faces[f];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Unnormalised normal of face `f`: its length is twice the face area.
    #[inline]
    pub fn face_cross(&self, f: usize) -> Vec3 {
        let [a, b, c] = self.corners(f);
        (b - a).cross(&(c - a))
    }

    /// Area of face `f`.
    pub fn face_area(&self, f: usize) -> f64 {
        0.5 * self.face_cross(f).norm()
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.faces.len()).map(|f| self.face_area(f)).sum()
    }

    /// Signed volume enclosed by the faces (positive when a closed surface is wound outward),
    /// computed about `origin` for precision.
    pub fn signed_volume_about(&self, faces: impl Iterator<Item = usize>, origin: Point3) -> f64 {
        let mut v = 0.0;
        for f in faces {
            let [a, b, c] = self.corners(f);
            v += (a - origin).dot(&(b - origin).cross(&(c - origin)));
        }
        v / 6.0
    }

    /// Signed volume of the whole mesh, about its bounding-box centre.
    ///
    /// ```
    /// let cube = drapekit::mesh::generate::cube(2.0);
    /// assert!((cube.signed_volume() - 8.0).abs() < 1e-12);
    /// ```
    pub fn signed_volume(&self) -> f64 {
        let origin = self.bbox().map_or(Point3::origin(), |b| b.center());
        self.signed_volume_about(0..self.faces.len(), origin)
    }

    /// Reverses the winding of face `f` (keeps its first corner).
    #[inline]
    pub fn flip_face(&mut self, f: usize) {
        self.faces[f].swap(1, 2);
    }

    /// Whether every face index is in range and every coordinate finite: the first problem
    /// found, as text.
    pub fn check(&self) -> Result<(), String> {
        if let Some(i) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(format!("vertex {i} has a non-finite coordinate"));
        }
        let n = self.positions.len() as u64;
        for (f, face) in self.faces.iter().enumerate() {
            if let Some(&i) = face.iter().find(|&&i| u64::from(i) >= n) {
                return Err(format!(
                    "face {f} refers to vertex {i} but there are {n} vertices"
                ));
            }
        }
        Ok(())
    }

    /// Drops vertices no face refers to, keeping the order of the rest. Returns how many went.
    pub fn drop_unreferenced_vertices(&mut self) -> usize {
        let mut used = vec![false; self.positions.len()];
        for face in &self.faces {
            for &i in face {
                used[i as usize] = true;
            }
        }
        let mut remap = vec![u32::MAX; self.positions.len()];
        let mut kept = 0u32;
        let mut write = 0usize;
        for read in 0..self.positions.len() {
            if used[read] {
                remap[read] = kept;
                self.positions[write] = self.positions[read];
                write += 1;
                kept += 1;
            }
        }
        let dropped = self.positions.len() - write;
        self.positions.truncate(write);
        if dropped > 0 {
            for face in &mut self.faces {
                for i in face.iter_mut() {
                    *i = remap[*i as usize];
                }
            }
        }
        dropped
    }

    /// Keeps the faces for which `keep` is true, in order. Returns how many went.
    pub fn retain_faces(&mut self, keep: &[bool]) -> usize {
        let before = self.faces.len();
        let mut i = 0;
        self.faces.retain(|_| {
            let k = keep[i];
            i += 1;
            k
        });
        before - self.faces.len()
    }
}
