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

/// Unit face normals (zero for a degenerate face).
pub fn face_normals(mesh: &TriMesh) -> Vec<Vec3> {
    (0..mesh.faces.len())
        .map(|f| {
            mesh.face_cross(f)
                .try_normalize(0.0)
                .unwrap_or_else(Vec3::zeros)
        })
        .collect()
}

/// Area-weighted vertex normals, unit (zero where the faces' normals cancel).
pub fn vertex_normals(mesh: &TriMesh) -> Vec<Vec3> {
    let mut n = vec![Vec3::zeros(); mesh.positions.len()];
    for (f, face) in mesh.faces.iter().enumerate() {
        let c = mesh.face_cross(f);
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
