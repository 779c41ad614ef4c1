//! Seams of a scene (`[[seam]]`): two stretches of piece outlines sewn particle to particle.
//!
//! A side is the stretch of a piece's outline from corner `from` to corner `to`,
//! counter-clockwise (the order `pattern::build` samples the outline in); side `a`'s `from`
//! meets side `b`'s `to` (two pieces' outlines run opposite ways along a seam). Each outline particle
//! of one side is sewn to the particle of the other side nearest the same fraction of its
//! arc length, and the other way round, so every particle of both sides is sewn and sides of
//! different lengths gather evenly (matched fractions; the garment pipeline pairs samples the
//! same way). The seams are springs of rest length 0 and constant
//! `garment::assemble::SEAM_STIFFNESS` times the stiffer fabric's stretch constant.
//!
//! ```
//! use drapekit::sim::seams::pair_by_fraction;
//! // Three particles sewn to five: the ends to the ends, the middle to the middle.
//! let pairs = pair_by_fraction(&[0.0, 0.5, 1.0], &[0.0, 0.25, 0.5, 0.75, 1.0]);
//! assert!(pairs.contains(&(0, 0)) && pairs.contains(&(1, 2)) && pairs.contains(&(2, 4)));
//! // Every particle of both sides is sewn.
//! for j in 0..5 { assert!(pairs.iter().any(|p| p.1 == j)); }
//! ```

use crate::cloth::pattern::Piece;
use crate::math::Point2;

/// A seam side that is not a stretch of its piece's outline.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SeamError {
    /// `from` or `to` is not a particle of the outline.
    #[error("({x}, {y}) is not on the outline of piece '{piece}' (nearest outline particle {distance:.3e} m away): seam ends must be outline corners")]
    NotOnOutline {
        piece: String,
        x: f64,
        y: f64,
        distance: f64,
    },
    /// `from` and `to` are the same particle.
    #[error("from and to are the same point of piece '{piece}'")]
    Empty { piece: String },
}

/// The particles of `piece` (its own numbering) from the outline particle at `from` to the one
/// at `to`, counter-clockwise, and each one's fraction of the stretch's arc length.
pub fn stretch(
    piece: &Piece,
    name: &str,
    from: &Point2,
    to: &Point2,
) -> Result<(Vec<u32>, Vec<f64>), SeamError> {
    let ring = &piece.outline_particles;
    let at = |q: &Point2| -> Result<usize, SeamError> {
        let (k, d) = ring
            .iter()
            .enumerate()
            .map(|(k, &v)| (k, (piece.flat[v as usize] - q).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("an outline has particles");
        let scale = piece.area.sqrt().max(f64::MIN_POSITIVE);
        if d > 1e-6 * scale {
            return Err(SeamError::NotOnOutline {
                piece: name.into(),
                x: q.x,
                y: q.y,
                distance: d,
            });
        }
        Ok(k)
    };
    let (start, end) = (at(from)?, at(to)?);
    if start == end {
        return Err(SeamError::Empty { piece: name.into() });
    }
    let n = ring.len();
    let mut ids = vec![ring[start]];
    let mut len = vec![0.0];
    let mut k = start;
    while k != end {
        let next = (k + 1) % n;
        let step = (piece.flat[ring[next] as usize] - piece.flat[ring[k] as usize]).norm();
        len.push(len.last().unwrap() + step);
        ids.push(ring[next]);
        k = next;
    }
    let total = *len.last().unwrap();
    Ok((ids, len.iter().map(|l| l / total).collect()))
}

/// Pairs two sides by their particles' arc-length fractions (module notes): `(i, j)` with `i`
/// an index into `a`, `j` into `b`, each pair once, sorted.
pub fn pair_by_fraction(a: &[f64], b: &[f64]) -> Vec<(usize, usize)> {
    let nearest = |t: f64, s: &[f64]| {
        (0..s.len())
            .min_by(|&x, &y| (s[x] - t).abs().total_cmp(&(s[y] - t).abs()))
            .expect("a side has particles")
    };
    let mut pairs: Vec<(usize, usize)> = (0..a.len()).map(|i| (i, nearest(a[i], b))).collect();
    pairs.extend((0..b.len()).map(|j| (nearest(b[j], a), j)));
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}
