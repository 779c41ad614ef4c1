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
    /// Edges of zero rest length (their strain has no value).
    #[error("{count} edge(s) of zero rest length, the first {a}-{b} (0-based vertices): the rest coordinates are not a flat pattern")]
    ZeroRest {
        /// One end of the first.
        a: u32,
        /// The other.
        b: u32,
        /// How many.
        count: usize,
    },
    /// An edge whose strain is beyond the range of numbers (a rest length of 1e-250 under a
    /// draped length of 1e90).
    #[error("edge {a}-{b} (0-based vertices): draped length {draped:e} over rest length {rest:e} is a strain beyond the range of numbers")]
    Overflow {
        /// One end.
        a: u32,
        /// The other.
        b: u32,
        /// Its draped length.
        draped: f64,
        /// Its rest length.
        rest: f64,
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
    let mut zero: Vec<(u32, u32)> = Vec::new();
    for face in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (face[k], face[(k + 1) % 3]);
            let Some(e) = edge_strain(&mesh.positions, rest, a, b)? else {
                zero.push((a.min(b), a.max(b)));
                continue;
            };
            for v in [a, b] {
                let s = &mut out[v as usize];
                if e.abs() > s.abs() {
                    *s = e;
                }
            }
        }
    }
    if let Some(&(a, b)) = zero.first() {
        zero.sort_unstable();
        zero.dedup();
        let count = zero.len();
        return Err(StrainError::ZeroRest { a, b, count });
    }
    Ok(out)
}

/// `|x_a - x_b| / |X_a - X_b| - 1`; `None` for a zero rest length.
fn edge_strain(
    x: &[Point3],
    rest: &[[f64; 2]],
    a: u32,
    b: u32,
) -> Result<Option<f64>, StrainError> {
    let (ra, rb) = (rest[a as usize], rest[b as usize]);
    let rest_len = (ra[0] - rb[0]).hypot(ra[1] - rb[1]);
    if rest_len == 0.0 {
        return Ok(None);
    }
    let draped = (x[a as usize] - x[b as usize]).norm();
    let e = draped / rest_len - 1.0;
    if !e.is_finite() {
        let rest = rest_len;
        return Err(StrainError::Overflow { a, b, draped, rest });
    }
    Ok(Some(e))
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

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle(x1: f64) -> TriMesh {
        let p = vec![
            Point3::origin(),
            Point3::new(x1, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        TriMesh::new(p, vec![[0, 1, 2]])
    }

    #[test]
    fn strain_beyond_the_numbers_is_an_error_not_infinity() {
        // 1e90 over 1e-250 is 1e340: it gave an infinite strain, refused by the renderer as
        // 'mesh 0: the value of vertex 0 is not finite'.
        let e = vertex_strain(&triangle(1e90), &[[0.0, 0.0], [1e-250, 0.0], [0.0, 1.0]]);
        assert!(
            matches!(e, Err(StrainError::Overflow { a: 0, b: 1, .. })),
            "{e:?}"
        );
    }

    #[test]
    fn every_edge_of_zero_rest_length_is_counted() {
        let quad = TriMesh::new(
            vec![
                Point3::origin(),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        // Vertices 0 and 2 at one rest point: the diagonal 0-2, shared by both faces, counted
        // once. Then 0, 1 and 2 at one point: three edges.
        let rest = [[0.0, 0.0], [1.0, 0.0], [0.0, 0.0], [1.0, 0.0]];
        let e = vertex_strain(&quad, &rest).unwrap_err();
        assert_eq!(
            e,
            StrainError::ZeroRest {
                a: 0,
                b: 2,
                count: 1
            }
        );
        let flat = [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [1.0, 1.0]];
        let e = vertex_strain(&quad, &flat).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("3 edge(s) of zero rest length, the first 0-1"),
            "{e}"
        );
    }
}
