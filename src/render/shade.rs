//! Shading: Lambert's law with an ambient term, flat or with vertex normals.
//!
//! A lit surface point of base colour `c` and unit normal `n` (turned towards the camera, so
//! both sides of a cloth are lit alike) shows `c (A + (1 - A) max(0, n·l))` with `A` =
//! [`AMBIENT`] and `l` the unit direction to the light, fixed to the camera: from behind the
//! viewer, above and to the left ([`light`]). Flat shading uses each face's normal; smooth
//! shading interpolates area-weighted vertex normals (the sum of the unnormalised normals
//! `(b - a) x (c - a)` of the faces at a vertex) with the fragment's barycentric coordinates.

use crate::math::Vec3;
use crate::mesh::TriMesh;

/// The ambient share of the light: the darkest a lit surface gets.
pub const AMBIENT: f64 = 0.3;

/// How normals are taken.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Shading {
    /// One normal per face: facets show.
    Flat,
    /// Vertex normals interpolated across faces (default).
    #[default]
    Smooth,
}

impl std::str::FromStr for Shading {
    type Err = String;
    fn from_str(s: &str) -> Result<Shading, String> {
        match s.to_ascii_lowercase().as_str() {
            "flat" => Ok(Shading::Flat),
            "smooth" => Ok(Shading::Smooth),
            _ => Err(format!("unknown shading '{s}': expected flat or smooth")),
        }
    }
}

/// The unit direction to the light for a camera with these axes: `2 (-forward) + up - right/2`,
/// normalised.
pub fn light(right: &Vec3, up: &Vec3, forward: &Vec3) -> Vec3 {
    (-2.0 * forward + up - 0.5 * right).normalize()
}

/// Meshes whose extent (their largest coordinate difference) lies outside `[1/R, R]` for this
/// `R = 2^200` have their edges scaled to about 1 before the cross products: at 1e-300 m every
/// cross product underflowed and the picture was ambient only; from about 1e77 m their squared
/// lengths overflow and the normals came out zero just the same.
const EXTENT_RANGE: f64 = ((1u128 << 100) as f64) * ((1u128 << 100) as f64);

/// The power of two that brings a mesh's extent to about 1 when it lies outside
/// [`EXTENT_RANGE`], and 1 for any other mesh. Scaling by a power of two is exact: the unit
/// normals are those of the mesh as it is.
fn edge_scale(mesh: &TriMesh) -> f64 {
    let extent = mesh.bbox().map_or(0.0, |b| (b.max - b.min).amax());
    if (1.0 / EXTENT_RANGE..=EXTENT_RANGE).contains(&extent) {
        1.0
    } else {
        crate::mesh::clean::unit_scale(extent)
    }
}

/// `(b - a) x (c - a)` of face `f`, its edges scaled by `s` (a power of two).
fn scaled_cross(mesh: &TriMesh, f: usize, s: f64) -> Vec3 {
    if s == 1.0 {
        return mesh.face_cross(f);
    }
    let [a, b, c] = mesh.corners(f);
    ((b - a) * s).cross(&((c - a) * s))
}

/// Unit face normals (zero for a degenerate face).
pub fn face_normals(mesh: &TriMesh) -> Vec<Vec3> {
    let s = edge_scale(mesh);
    (0..mesh.faces.len())
        .map(|f| {
            scaled_cross(mesh, f, s)
                .try_normalize(0.0)
                .unwrap_or_else(Vec3::zeros)
        })
        .collect()
}

/// Area-weighted vertex normals, unit (zero where the faces' normals cancel).
pub fn vertex_normals(mesh: &TriMesh) -> Vec<Vec3> {
    let s = edge_scale(mesh);
    let mut n = vec![Vec3::zeros(); mesh.positions.len()];
    for (f, face) in mesh.faces.iter().enumerate() {
        let c = scaled_cross(mesh, f, s);
        for &v in face {
            n[v as usize] += c;
        }
    }
    n.iter()
        .map(|v| v.try_normalize(0.0).unwrap_or_else(Vec3::zeros))
        .collect()
}

/// The brightness factor `A + (1 - A) max(0, n·l)` of a point with normal `n` (any length; zero
/// gives the ambient term alone) on a face with unit normal `face`, seen along `forward`.
///
/// ```
/// use drapekit::math::Vec3;
/// use drapekit::render::shade::{brightness, AMBIENT};
/// let (l, f) = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
/// // Facing the light: full brightness; at 60 degrees: half the diffuse share; either side.
/// assert_eq!(brightness(&Vec3::z(), &Vec3::z(), &f, &l), 1.0);
/// let n = Vec3::new(3f64.sqrt() / 2.0, 0.0, -0.5);
/// assert!((brightness(&n, &-Vec3::z(), &f, &l) - (AMBIENT + 0.5 * (1.0 - AMBIENT))).abs() < 1e-15);
/// ```
pub fn brightness(n: &Vec3, face: &Vec3, forward: &Vec3, light: &Vec3) -> f64 {
    let towards = if face.dot(forward) > 0.0 { -1.0 } else { 1.0 };
    let n = n.try_normalize(0.0).unwrap_or_else(Vec3::zeros) * towards;
    AMBIENT + (1.0 - AMBIENT) * n.dot(light).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn a_mesh_of_any_size_has_the_normals_of_its_shape() {
        // 1e-300 m: the edges' cross products underflowed to zero and every normal was zero.
        let m = generate::icosphere(2);
        let (f0, v0) = (face_normals(&m), vertex_normals(&m));
        for scale in [1e-300, 1e-150, 1e-60, 1e-3, 1e90] {
            let mut t = m.clone();
            t.positions.iter_mut().for_each(|p| *p *= scale);
            let (f, v) = (face_normals(&t), vertex_normals(&t));
            for (a, b) in f.iter().zip(&f0).chain(v.iter().zip(&v0)) {
                assert!((a - b).norm() < 1e-12, "{scale}: {a:?} against {b:?}");
            }
        }
    }
}
