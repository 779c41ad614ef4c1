//! Holding a skirt's or trousers' waist at the body's waist while sewing.
//!
//! GarmentCode marks the top edges of skirts and trousers with the label `lower_interface`
//! ([`WAIST_LABEL`]) and places those panels well below the waist (`dress_pencil`'s skirt top
//! at 0.79 m on `mean_all`, whose waist is at 1.09 m): its simulator pulls those edges' particles
//! vertically towards the body's waist level (`add_attachment`, stiffness 1000, for the first
//! 400 frames) and lets go. Sewn where it is placed, the skirt's waist (84.3 cm, the body's
//! waist girth) would close round the hips (100 cm): strained, it cannot hang right.
//!
//! drapekit does the same during sewing only (at rest nothing holds the garment but the body).
//! The level is the body's **natural waist**: with `g(z)` the tape-measure girth (convex
//! hull's perimeter) of the torso's section at height `z` (the largest loop there; legs, arms
//! and hands are smaller loops), sections every [`STEP`] of the height over [`BAND`] of it,
//! the waist is the section that sits deepest between wider ones: the level of greatest
//!
//! ```text
//! depth(z) = min( max_{z' <= z} g(z'), max_{z' >= z} g(z') ) - g(z)
//! ```
//!
//! (the lowest such level on a tie). On a whole body that is the narrowest
//! torso between the hips and the chest; the band is wide enough that a torso alone (a dress
//! form) has its waist in it too, and stops below the neck, whose depth between the shoulders
//! and the head would rival the waist's.

use crate::geom::signed_area2;
use crate::math::Point2;
use crate::mesh::slice::{girth, slice};
use crate::mesh::TriMesh;

/// The label GarmentCode gives the edges held at the waist.
pub const WAIST_LABEL: &str = "lower_interface";

/// Where the natural waist is looked for, as fractions of the height above the body's lowest
/// point (the waist of GarmentCode's `mean_all`: 0.633; of ISO 8559's shape model: 0.631):
/// from the thighs to below the neck on a whole body.
pub const BAND: (f64, f64) = (0.35, 0.8);

/// Spacing of the sections, as a fraction of the body's height (1.7 mm on a 1.72 m body).
pub const STEP: f64 = 0.001;

/// The body's natural waist (z up, the mesh's units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Waist {
    /// Its height.
    pub level: f64,
    /// The torso's convex-hull girth there.
    pub girth: f64,
}

/// The natural waist of a standing, z-up `body` (module docs), or `None` when no closed section
/// crosses the band.
///
/// ```
/// use drapekit::garment::waist::natural_waist;
/// use drapekit::mesh::generate;
/// use drapekit::math::Vec3;
/// // A box 1 m tall from z = -0.5: every section has the same girth, 4 x 0.2 m, no level is
/// // deeper than another, and the lowest of the band wins.
/// let b = generate::boxed(Vec3::new(0.2, 0.2, 1.0));
/// let w = natural_waist(&b).unwrap();
/// assert!((w.girth - 0.8).abs() < 1e-9 && (w.level + 0.15).abs() < 1e-9);
/// ```
pub fn natural_waist(body: &TriMesh) -> Option<Waist> {
    let b = body.bbox()?;
    let height = b.max.z - b.min.z;
    if height.is_nan() || height <= 0.0 {
        return None;
    }
    let (lo, hi) = BAND;
    let n = ((hi - lo) / STEP).round() as usize;
    let sections: Vec<Waist> = (0..=n)
        .filter_map(|i| {
            let level = b.min.z + (lo + (hi - lo) * i as f64 / n as f64) * height;
            torso_girth(body, level).map(|girth| Waist { level, girth })
        })
        .collect();
    let g: Vec<f64> = sections.iter().map(|w| w.girth).collect();
    let below: Vec<f64> = g
        .iter()
        .scan(0.0, |m: &mut f64, &x| {
            *m = m.max(x);
            Some(*m)
        })
        .collect();
    let mut above: Vec<f64> = g
        .iter()
        .rev()
        .scan(0.0, |m: &mut f64, &x| {
            *m = m.max(x);
            Some(*m)
        })
        .collect();
    above.reverse();
    let mut best: Option<(f64, Waist)> = None;
    for (k, w) in sections.iter().enumerate() {
        let depth = below[k].min(above[k]) - w.girth;
        if best.is_none_or(|(d, _)| depth > d) {
            best = Some((depth, *w));
        }
    }
    best.map(|(_, w)| w)
}

/// The convex-hull girth of the largest closed section of `body` at height `z`.
fn torso_girth(body: &TriMesh, z: f64) -> Option<f64> {
    slice(body, z)
        .into_iter()
        .filter(|l| l.closed && l.points.len() >= 3)
        .map(|l| l.xy())
        .max_by(|a, c| area(a).total_cmp(&area(c)))
        .map(|t| girth(&t))
}

fn area(p: &[Point2]) -> f64 {
    signed_area2(p).abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::mesh::generate;

    /// An hourglass from `z0` to `z1` (rings every 5 mm, 64 sides), narrowest at 1.1 m:
    /// radius `0.13 + 0.5 (z - 1.1)^2` m.
    fn hourglass(z0: f64, z1: f64) -> TriMesh {
        let rings = ((z1 - z0) / 0.005).round() as usize + 1;
        let profile: Vec<(f64, f64)> = (0..rings)
            .map(|i| z0 + (z1 - z0) * i as f64 / (rings - 1) as f64)
            .map(|z| (z, 0.13 + 0.5 * (z - 1.1) * (z - 1.1)))
            .collect();
        generate::lathe(&profile, 64)
    }

    /// `body` with a box of edges `size` centred at `at` added.
    fn with_box(mut body: TriMesh, size: Vec3, at: Vec3) -> TriMesh {
        let b = generate::boxed(size);
        let base = body.positions.len() as u32;
        body.positions.extend(b.positions.iter().map(|p| p + at));
        body.faces
            .extend(b.faces.iter().map(|f| f.map(|v| v + base)));
        body
    }

    #[test]
    fn the_natural_waist_is_the_narrowest_torso_section_in_the_band() {
        // An hourglass 1.7 m tall, narrowest (radius 0.13 m) at 1.1 m: 0.647 of its height.
        let w = natural_waist(&hourglass(0.0, 1.7)).unwrap();
        // Sections every 1.7 mm, rings every 5 mm (one at 1.1 m): the narrowest section within
        // one section's spacing of 1.1 m, its girth that of a 64-gon of radius 0.13 m to within
        // the radius's rise there (0.5 x 2.5 mm squared between rings: 3 micrometres).
        let polygon = 64.0 * 2.0 * 0.13 * (std::f64::consts::PI / 64.0).sin();
        assert!((w.level - 1.1).abs() <= STEP * 1.7 + 1e-9, "{w:?}");
        assert!((w.girth - polygon).abs() < 1e-4, "{w:?} {polygon}");
    }

    #[test]
    fn a_torso_alone_has_its_waist_found_too() {
        // A dress form: the hourglass from 0.8 to 1.5 m only (its band, 35% to 80% of its
        // height, is 1.045 to 1.36 m): the waist between the wider hips below and chest above.
        let w = natural_waist(&hourglass(0.8, 1.5)).unwrap();
        assert!((w.level - 1.1).abs() <= STEP * 0.7 + 1e-9, "{w:?}");
    }

    #[test]
    fn legs_narrower_than_the_waist_are_not_the_waist() {
        // The hourglass torso from 0.85 m up, on two legs (boxes 12 cm square, 0.48 m round)
        // from the floor: in the band (0.6 to 1.36 m) the legs' sections are narrower than
        // the waist's (0.82 m), but nothing wider lies below them.
        let mut body = hourglass(0.85, 1.5);
        for x in [-0.08, 0.08] {
            body = with_box(body, Vec3::new(0.12, 0.12, 0.86), Vec3::new(x, 0.0, 0.43));
        }
        let w = natural_waist(&body).unwrap();
        assert!((w.level - 1.1).abs() <= STEP * 1.5 + 1e-9, "{w:?}");
    }

    #[test]
    fn the_torso_is_the_largest_loop_not_an_arm() {
        // The hourglass with a thin "arm" (a box 4 cm across) beside it over the whole band:
        // the arm's small girth must not be taken for the waist.
        let arm = (Vec3::new(0.04, 0.04, 1.6), Vec3::new(0.4, 0.0, 0.85));
        let w = natural_waist(&with_box(hourglass(0.0, 1.7), arm.0, arm.1)).unwrap();
        assert!((w.level - 1.1).abs() <= STEP * 1.7 + 1e-9, "{w:?}");
        assert!(w.girth > 0.8, "{w:?}");
    }
}
