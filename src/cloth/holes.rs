//! Holes in a pattern piece: closed outlines inside the piece's outline, cut out of the cloth.
//!
//! Each hole is cleaned like the outline (`pattern::clean_outline`: repeats dropped, no
//! self-crossing, an area, counter-clockwise). It must lie inside the outline and apart from
//! the other holes: no edge of it meets an edge of the outline or of another hole, its
//! corners are inside the outline, and no hole has a corner inside another. The grid's
//! particles keep out of the holes as they keep inside the outline, and the hole's edge is
//! sampled like the outline's (its particles are outline particles: no bending element, half
//! a strip's stretch along the edge).
//!
//! ```
//! use drapekit::cloth::holes::check_holes;
//! use drapekit::math::Point2;
//! let square = |c: f64, r: f64| vec![
//!     Point2::new(c - r, -r), Point2::new(c + r, -r), Point2::new(c + r, r), Point2::new(c - r, r)];
//! let outline = square(0.0, 1.0);
//! assert!(check_holes(&outline, &[square(0.0, 0.2)]).is_ok());
//! // Half outside the outline: refused, naming hole 1.
//! let e = check_holes(&outline, &[square(1.0, 0.2)]).unwrap_err();
//! assert!(e.to_string().starts_with("hole 1"));
//! ```

use super::pattern::{clean_outline, PatternError};
use crate::math::Point2;

/// Checks and cleans `holes` against the (clean, counter-clockwise) `outline`: each hole
/// counter-clockwise, in the order given.
pub fn check_holes(
    outline: &[Point2],
    holes: &[Vec<Point2>],
) -> Result<Vec<Vec<Point2>>, PatternError> {
    let mut clean: Vec<Vec<Point2>> = Vec::with_capacity(holes.len());
    for (k, h) in holes.iter().enumerate() {
        let bad = |reason: String| PatternError::Hole {
            hole: k + 1,
            reason,
        };
        let h = clean_outline(h).map_err(|e| bad(e.to_string()))?;
        if crosses(&h, outline) || !h.iter().all(|p| inside(outline, p)) {
            return Err(bad("is not inside the outline".into()));
        }
        for (j, g) in clean.iter().enumerate() {
            if crosses(&h, g) || inside(g, &h[0]) || inside(&h, &g[0]) {
                return Err(bad(format!("meets hole {}", j + 1)));
            }
        }
        clean.push(h);
    }
    Ok(clean)
}

/// Whether `q` is inside any of `holes`.
pub fn in_any(holes: &[Vec<Point2>], q: &Point2) -> bool {
    holes.iter().any(|h| inside(h, q))
}

fn inside(poly: &[Point2], q: &Point2) -> bool {
    crate::geom::contains(poly, q)
}

/// Whether an edge of closed polygon `a` meets an edge of closed polygon `b`.
fn crosses(a: &[Point2], b: &[Point2]) -> bool {
    let edges = |p: &[Point2]| {
        let n = p.len();
        (0..n)
            .map(move |i| (p[i], p[(i + 1) % n]))
            .collect::<Vec<_>>()
    };
    let eb = edges(b);
    edges(a).iter().any(|(p, q)| {
        eb.iter()
            .any(|(r, s)| crate::geom::segments_meet(p, q, r, s))
    })
}
