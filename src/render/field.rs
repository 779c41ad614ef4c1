//! Per-vertex distances to other meshes: the fit map and contact.
//!
//! The fit map gives each vertex of a garment its distance to the nearest point of the body
//! (`mesh::closest`: a uniform grid of faces searched in shells), unsigned, in the meshes'
//! unit. Contact is that distance at most a threshold (the fabric's thickness, say): 1 in
//! contact, 0 out. Vertices are independent; they are computed in parallel and collected in
//! order, so the result does not depend on the thread count.

use crate::mesh::closest::ClosestPoints;
use crate::mesh::TriMesh;
use rayon::prelude::*;

/// The distance from each vertex of `mesh` to `target` (which must have faces).
///
/// ```
/// use drapekit::math::Point3;
/// use drapekit::mesh::{generate, TriMesh};
/// use drapekit::render::field::distances;
/// let body = generate::cube(2.0); // [-1, 1]^3
/// let cloth = TriMesh::new(vec![Point3::new(0.0, 0.0, 1.25), Point3::new(2.0, 0.0, 1.0)], vec![]);
/// let d = distances(&cloth, &body);
/// assert!((d[0] - 0.25).abs() < 1e-12 && (d[1] - 1.0).abs() < 1e-12);
/// ```
pub fn distances(mesh: &TriMesh, target: &TriMesh) -> Vec<f64> {
    let query = ClosestPoints::new(target);
    mesh.positions
        .par_iter()
        .map(|p| query.closest(p).distance)
        .collect()
}

/// 1 where `distance <= threshold`, else 0.
pub fn contact(distances: &[f64], threshold: f64) -> Vec<f64> {
    distances
        .iter()
        .map(|&d| if d <= threshold { 1.0 } else { 0.0 })
        .collect()
}

/// The meshes joined into one (faces renumbered).
pub fn join<'a>(meshes: impl IntoIterator<Item = &'a TriMesh>) -> TriMesh {
    let mut out = TriMesh::default();
    for m in meshes {
        let off = out.positions.len() as u32;
        out.positions.extend_from_slice(&m.positions);
        out.faces.extend(m.faces.iter().map(|f| f.map(|v| v + off)));
    }
    out
}
