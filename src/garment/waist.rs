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
//! The level is the body's **natural waist**: the height, between [`BAND`] of the body's
//! height above its lowest point, where the torso's section has the shortest tape-measure
//! girth (its convex hull's perimeter); the torso is the largest section there (arms and hands
//! are smaller loops). Sections every [`STEP`] of the height.

use crate::geom::signed_area2;
use crate::math::Point2;
use crate::mesh::slice::{girth, slice};
use crate::mesh::TriMesh;

/// The label GarmentCode gives the edges held at the waist.
pub const WAIST_LABEL: &str = "lower_interface";

/// Where the natural waist is looked for, as fractions of the body's height above its lowest
/// point (GarmentCode's `mean_all`: 0.633; ISO 8559's shape model: 0.631): a whole standing
/// body's (on a torso alone, such as a dress form, the band falls elsewhere: give the level).
pub const BAND: (f64, f64) = (0.55, 0.72);

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
/// // A box 1 m tall from z = -0.5: every section has the same girth, 4 x 0.2 m, and the
/// // lowest of the band wins.
/// let b = generate::boxed(Vec3::new(0.2, 0.2, 1.0));
/// let w = natural_waist(&b).unwrap();
/// assert!((w.girth - 0.8).abs() < 1e-9 && (w.level - 0.05).abs() < 1e-9);
/// ```
pub fn natural_waist(body: &TriMesh) -> Option<Waist> {
    let b = body.bbox()?;
    let height = b.max.z - b.min.z;
    if height.is_nan() || height <= 0.0 {
        return None;
    }
    let (lo, hi) = BAND;
    let n = ((hi - lo) / STEP).round() as usize;
    let mut best: Option<Waist> = None;
    for i in 0..=n {
        let level = b.min.z + (lo + (hi - lo) * i as f64 / n as f64) * height;
        let torso = slice(body, level)
            .into_iter()
            .filter(|l| l.closed && l.points.len() >= 3)
            .map(|l| l.xy())
            .max_by(|a, c| area(a).total_cmp(&area(c)));
        if let Some(t) = torso {
            let g = girth(&t);
            if best.is_none_or(|w| g < w.girth) {
                best = Some(Waist { level, girth: g });
            }
        }
    }
    best
}

fn area(p: &[Point2]) -> f64 {
    signed_area2(p).abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Point3;

    /// A closed body of revolution about the z axis, `rings` levels from z = 0 to `height`,
    /// radius `r(z)`, 64 sides, capped.
    fn lathe(height: f64, rings: usize, r: impl Fn(f64) -> f64) -> TriMesh {
        let sides = 64u32;
        let mut positions = Vec::new();
        for i in 0..rings {
            let z = height * i as f64 / (rings - 1) as f64;
            for k in 0..sides {
                let a = std::f64::consts::TAU * k as f64 / sides as f64;
                positions.push(Point3::new(r(z) * a.cos(), r(z) * a.sin(), z));
            }
        }
        let mut faces = Vec::new();
        for i in 0..rings as u32 - 1 {
            for k in 0..sides {
                let (a, b) = (i * sides + k, i * sides + (k + 1) % sides);
                faces.push([a, b, b + sides]);
                faces.push([a, b + sides, a + sides]);
            }
        }
        let (bottom, top) = (positions.len() as u32, positions.len() as u32 + 1);
        positions.push(Point3::new(0.0, 0.0, 0.0));
        positions.push(Point3::new(0.0, 0.0, height));
        let last = (rings as u32 - 1) * sides;
        for k in 0..sides {
            faces.push([bottom, (k + 1) % sides, k]);
            faces.push([top, last + k, last + (k + 1) % sides]);
        }
        TriMesh::new(positions, faces)
    }

    #[test]
    fn the_natural_waist_is_the_narrowest_torso_section_in_the_band() {
        // An hourglass 1.7 m tall, narrowest (radius 0.13 m) at 1.1 m: 0.647 of its height.
        let body = lathe(1.7, 341, |z| 0.13 + 0.5 * (z - 1.1) * (z - 1.1));
        let w = natural_waist(&body).unwrap();
        // Sections every 1.7 mm, rings every 5 mm (one at 1.1 m): the narrowest section within
        // one section's spacing of 1.1 m, its girth that of a 64-gon of radius 0.13 m to within
        // the radius's rise there (0.5 x 2.5 mm squared between rings: 3 micrometres).
        let polygon = 64.0 * 2.0 * 0.13 * (std::f64::consts::PI / 64.0).sin();
        assert!((w.level - 1.1).abs() <= STEP * 1.7 + 1e-9, "{w:?}");
        assert!((w.girth - polygon).abs() < 1e-4, "{w:?} {polygon}");
    }

    #[test]
    fn the_torso_is_the_largest_loop_not_an_arm() {
        // The hourglass with a thin "arm" (a box 4 cm across) beside it over the whole band:
        // the arm's small girth must not be taken for the waist.
        let mut body = lathe(1.7, 341, |z| 0.13 + 0.5 * (z - 1.1) * (z - 1.1));
        let arm = crate::mesh::generate::boxed(crate::math::Vec3::new(0.04, 0.04, 1.6));
        let base = body.positions.len() as u32;
        body.positions.extend(
            arm.positions
                .iter()
                .map(|p| p + crate::math::Vec3::new(0.4, 0.0, 0.85)),
        );
        body.faces
            .extend(arm.faces.iter().map(|f| f.map(|v| v + base)));
        let w = natural_waist(&body).unwrap();
        assert!((w.level - 1.1).abs() <= STEP * 1.7 + 1e-9, "{w:?}");
        assert!(w.girth > 0.8, "{w:?}");
    }
}
