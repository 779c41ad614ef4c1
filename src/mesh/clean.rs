//! Dropping faces that carry no surface: degenerate ones (a repeated corner, or an area at most
//! [`tol::DEGENERATE_AREA_REL`] times the squared bounding-box diagonal) and duplicates (the same
//! three vertices as an earlier face, in either winding: the first one stays).

use super::topology::is_index_degenerate;
use super::TriMesh;
use crate::math::{tol, Point3};

/// Which faces are degenerate, and how many.
///
/// The test is relative to the mesh's own size, so it gives the same answer for the mesh scaled
/// by any power of ten: the corners are moved to the box's corner, halved and scaled by a power
/// of two ([`unit_scale`]) before the cross product, so coordinates of 1e200 do not overflow and
/// of 1e-200 do not underflow.
pub fn find_degenerate(mesh: &TriMesh) -> (Vec<bool>, usize) {
    let Some(b) = mesh.bbox() else {
        return (vec![false; mesh.faces.len()], 0);
    };
    let half = |p: &Point3| p * 0.5 - b.min * 0.5;
    let extent = half(&b.max);
    let s = unit_scale(extent.max());
    let d = (extent * s).norm();
    // Compare twice the area squared against the threshold, avoiding a square root per face.
    let limit = 2.0 * tol::DEGENERATE_AREA_REL * d * d;
    let limit2 = limit * limit;
    let mut n = 0;
    let flags = (0..mesh.faces.len())
        .map(|f| {
            let [p, q, r] = mesh.corners(f).map(|c| half(&c) * s);
            let bad = is_index_degenerate(&mesh.faces[f])
                || (q - p).cross(&(r - p)).norm_squared() <= limit2;
            n += usize::from(bad);
            bad
        })
        .collect();
    (flags, n)
}

/// A power of two `s` with `extent * s` in [1, 2): lengths times `s` are near 1, and their
/// products neither overflow nor underflow (the scaling is exact). 1 when `extent` is zero or
/// not finite.
pub fn unit_scale(extent: f64) -> f64 {
    if !(extent > 0.0 && extent.is_finite()) {
        return 1.0;
    }
    let e = extent.log2().floor() as i32;
    // Two steps: 2^-e alone overflows for the smallest subnormal extents.
    2f64.powi(-e / 2) * 2f64.powi(-e + e / 2)
}

/// Which faces repeat the vertex set of an earlier face, and how many.
///
/// O(n) without hashing: faces are bucketed by their smallest vertex (a counting sort), and
/// only faces within a bucket are compared.
pub fn find_duplicates(mesh: &TriMesh) -> (Vec<bool>, usize) {
    let nv = mesh.positions.len();
    let keys: Vec<[u32; 3]> = mesh
        .faces
        .iter()
        .map(|f| {
            let mut k = *f;
            k.sort_unstable();
            k
        })
        .collect();
    let mut start = vec![0u32; nv + 1];
    for k in &keys {
        start[k[0] as usize + 1] += 1;
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut bucket = vec![0u32; keys.len()];
    for (f, k) in keys.iter().enumerate() {
        let slot = &mut fill[k[0] as usize];
        bucket[*slot as usize] = f as u32;
        *slot += 1;
    }
    let mut dup = vec![false; keys.len()];
    let mut n = 0;
    for v in 0..nv {
        let b = &bucket[start[v] as usize..start[v + 1] as usize];
        // Faces are in increasing order within a bucket: the first of equal keys stays.
        for (i, &f) in b.iter().enumerate() {
            if b[..i].iter().any(|&g| keys[g as usize] == keys[f as usize]) {
                dup[f as usize] = true;
                n += 1;
            }
        }
    }
    (dup, n)
}

/// Drops degenerate faces; returns how many went.
pub fn drop_degenerate(mesh: &mut TriMesh) -> usize {
    let (bad, n) = find_degenerate(mesh);
    if n > 0 {
        let keep: Vec<bool> = bad.iter().map(|b| !b).collect();
        mesh.retain_faces(&keep);
    }
    n
}

/// Drops duplicate faces; returns how many went.
pub fn drop_duplicates(mesh: &mut TriMesh) -> usize {
    let (dup, n) = find_duplicates(mesh);
    if n > 0 {
        let keep: Vec<bool> = dup.iter().map(|b| !b).collect();
        mesh.retain_faces(&keep);
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drops_repeated_index_sliver_and_duplicates() {
        let p = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(2.0, 1e-15, 0.0),
        ];
        // A good face, its reverse (duplicate), a repeated corner, a collinear sliver.
        let mut m = TriMesh::new(p, vec![[0, 1, 2], [0, 2, 1], [0, 0, 1], [0, 1, 3]]);
        assert_eq!(drop_duplicates(&mut m), 1);
        assert_eq!(drop_degenerate(&mut m), 2);
        assert_eq!(m.faces, vec![[0, 1, 2]]);
    }
}
