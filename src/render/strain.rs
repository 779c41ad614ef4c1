//! Strain of a draped cloth against its flat pattern, per vertex.
//!
//! Each triangle edge `(i, j)` has strain `e_ij = |x_i - x_j| / |X_i - X_j| - 1`, where `x` are
//! the draped positions and `X` the rest (flat pattern) positions: 0 at rest, positive when
//! stretched, negative when compressed. A vertex takes the strain of largest magnitude among
//! its edges, with its sign, so a colour map shows the worst stretch (or compression) at each
//! point. drapekit's drape and garment OBJ files carry `X` as per-vertex `vt` coordinates, in
//! the unit of `v` (see `io::obj::write_with_rest`).

use crate::math::Point3;
use crate::mesh::TriMesh;

/// What stops a strain computation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StrainError {
    /// Rest coordinates are not one per vertex.
    #[error("{rest} rest points for {vertices} vertices: strain needs one per vertex")]
    Count {
        /// Rest points given.
        rest: usize,
        /// Vertices of the mesh.
        vertices: usize,
    },
    /// An edge of zero rest length (its strain has no value).
    #[error("edge {a}-{b} (0-based vertices) has zero rest length: the rest coordinates are not a flat pattern")]
    ZeroRest {
        /// One end.
        a: u32,
        /// The other.
        b: u32,
    },
    /// A rest coordinate is NaN or infinite.
    #[error("rest point of vertex {vertex} is not finite")]
    NonFinite {
        /// The vertex.
        vertex: usize,
    },
}

/// The strain of largest magnitude over each vertex's edges (0 for a vertex on no face).
///
/// ```
/// use drapekit::math::Point3;
/// use drapekit::mesh::TriMesh;
/// use drapekit::render::strain::vertex_strain;
/// // A right triangle stretched 10% along x and squeezed 5% along y.
/// let mesh = TriMesh::new(
///     vec![Point3::origin(), Point3::new(1.1, 0.0, 0.0), Point3::new(0.0, 0.95, 0.0)],
///     vec![[0, 1, 2]],
/// );
/// let s = vertex_strain(&mesh, &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
/// assert!((s[0] - 0.1).abs() < 1e-12 && (s[1] - 0.1).abs() < 1e-12);
/// // Vertex 2: its edges have -0.05 and |(-1.1, 0.95)| / sqrt 2 - 1 = 0.0274; -0.05 is larger.
/// assert!((s[2] + 0.05).abs() < 1e-12);
/// ```
pub fn vertex_strain(mesh: &TriMesh, rest: &[[f64; 2]]) -> Result<Vec<f64>, StrainError> {
    if rest.len() != mesh.positions.len() {
        return Err(StrainError::Count {
            rest: rest.len(),
            vertices: mesh.positions.len(),
        });
    }
    if let Some(vertex) = rest.iter().position(|r| !r.iter().all(|c| c.is_finite())) {
        return Err(StrainError::NonFinite { vertex });
    }
    let mut out = vec![0.0f64; mesh.positions.len()];
    for face in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (face[k], face[(k + 1) % 3]);
            let e = edge_strain(&mesh.positions, rest, a, b)?;
            for v in [a, b] {
                let s = &mut out[v as usize];
                if e.abs() > s.abs() {
                    *s = e;
                }
            }
        }
    }
    Ok(out)
}

/// `|x_a - x_b| / |X_a - X_b| - 1`.
fn edge_strain(x: &[Point3], rest: &[[f64; 2]], a: u32, b: u32) -> Result<f64, StrainError> {
    let (ra, rb) = (rest[a as usize], rest[b as usize]);
    let rest_len = (ra[0] - rb[0]).hypot(ra[1] - rb[1]);
    if rest_len == 0.0 {
        return Err(StrainError::ZeroRest { a, b });
    }
    Ok((x[a as usize] - x[b as usize]).norm() / rest_len - 1.0)
}

/// Strain values as glTF vertex colours: viridis of `|strain| / top` (clamped), opaque.
pub fn strain_colours(values: &[f64], top: f64) -> Vec<[f32; 4]> {
    values
        .iter()
        .map(|s| {
            let [r, g, b] = super::colormap::viridis((s.abs() / top).min(1.0));
            [
                f32::from(r) / 255.0,
                f32::from(g) / 255.0,
                f32::from(b) / 255.0,
                1.0,
            ]
        })
        .collect()
}

/// The top of a strain colour scale: the largest `|strain|`, at least 0.1%.
pub fn strain_top(values: impl Iterator<Item = f64>) -> f64 {
    values.fold(1e-3, |a, s| a.max(s.abs()))
}
