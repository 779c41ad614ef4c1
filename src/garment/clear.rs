//! Panels placed through the body, moved out before sewing.
//!
//! GarmentCode places each panel flat, a fixed distance in front of or behind the body it was
//! made for (`translation`): a body with a fuller seat, bust or belly than that one pokes
//! through it (`flare_skirt`'s back panel, flat at z = -12.5 cm, on `mean_all`, whose seat
//! reaches z = -14.7 cm at 0.90 m). Sewn where it is, the part of the panel inside the body
//! is pushed out by the contact through whichever face is nearest, and the panel ends wrapped
//! on both sides of the body's surface: particles inside and cloth edges through the body
//! that no drape undoes.
//!
//! So before sewing, each panel with a particle inside the body is moved rigidly along its
//! outward normal `n = R (0, 0, sign A)` (the one `facing` judges: away from the body) by
//! [`STEP`] at a time until none of its particles is inside, then one step more (the cloth
//! keeps its thickness and the clearance off the body, well under a step). The panel keeps
//! its shape and its stitches; its seams then have a little further to close. A panel not
//! clear within [`REACH`] stays where it was placed (a body that big is not the pattern's),
//! and the report says so. A panel wholly outside the body is not moved: on the bodies a
//! pattern was made for, nothing changes. `garment::drape::garment_world` clears the panels
//! of a closed body only: an open one (a seat's shell) has no inside to speak of.
//!
//! ```
//! use drapekit::garment::clear::{clear_panels, STEP};
//! use drapekit::math::{Point3, Vec3};
//! use drapekit::mesh::generate;
//! use drapekit::collide::Collider;
//! // A ball of radius 0.1 m at the origin (a polyhedron between radii 0.0989 and 0.1 m), a
//! // flat panel at x = 0.0525 m facing +x: the particles near its middle are inside it.
//! let mesh = generate::uv_sphere(Point3::origin(), 0.1, 24, 48);
//! let ball = Collider::new("ball".into(), mesh, [16, 16, 16], 0.0, None);
//! let mut panels = vec![(0..121)
//!     .map(|k| Point3::new(0.0525, -0.1 + 0.02 * (k % 11) as f64, -0.1 + 0.02 * (k / 11) as f64))
//!     .collect::<Vec<_>>()];
//! let moved = clear_panels(&mut panels, &[Vec3::x()], &ball);
//! assert_eq!(moved.len(), 1);
//! assert!(moved[0].cleared && moved[0].inside > 0);
//! // The middle particle is inside after nine steps (x = 0.0975 m), out after ten
//! // (0.1025 m); then one step more.
//! assert!((moved[0].distance - 11.0 * STEP).abs() < 1e-12);
//! assert!(panels[0].iter().all(|p| (p.x - (0.0525 + 11.0 * STEP)).abs() < 1e-12));
//! ```

use super::assemble::Placement;
use super::spec::Pattern;
use crate::collide::inside::inside;
use crate::collide::Collider;
use crate::math::{Point3, Vec3};
use crate::mesh::transform::{change_up_vector, Up};
use rayon::prelude::*;

/// How far a panel is moved at a time, m.
pub const STEP: f64 = 0.005;

/// The farthest a panel is moved, m.
pub const REACH: f64 = 0.3;

/// A panel that was placed through the body.
#[derive(Debug, Clone, PartialEq)]
pub struct MovedOut {
    /// The panel's index in the pattern.
    pub index: usize,
    /// Its particles inside the body as placed.
    pub inside: usize,
    /// How far it was moved along its outward normal, m (0 when not cleared).
    pub distance: f64,
    /// Whether it was clear of the body within [`REACH`]; if not, it stays where it was.
    pub cleared: bool,
}

/// How many of `points`, moved by `shift`, are inside `body`.
fn count_inside(points: &[Point3], shift: Vec3, body: &Collider) -> usize {
    points
        .par_iter()
        .with_min_len(256)
        .filter(|p| inside(body, &(*p + shift)))
        .count()
}

/// Moves each panel (`panels[k]`, its particles as placed) with a particle inside `body`
/// along its unit outward normal `normals[k]` until none is (module docs); returns what it did
/// for each such panel, in panel order.
pub fn clear_panels<P: AsMut<[Point3]>>(
    panels: &mut [P],
    normals: &[Vec3],
    body: &Collider,
) -> Vec<MovedOut> {
    let mut out = Vec::new();
    for (index, (points, n)) in panels.iter_mut().zip(normals).enumerate() {
        let points = points.as_mut();
        let first = count_inside(points, Vec3::zeros(), body);
        if first == 0 {
            continue;
        }
        let steps = (REACH / STEP).round() as usize;
        let clear = (1..=steps).find(|&k| count_inside(points, n * (k as f64 * STEP), body) == 0);
        let distance = clear.map_or(0.0, |k| (k + 1) as f64 * STEP);
        for p in points.iter_mut() {
            *p += n * distance;
        }
        out.push(MovedOut {
            index,
            inside: first,
            distance,
            cleared: clear.is_some(),
        });
    }
    out
}

/// Each panel's unit outward normal in drapekit's frame (z up) after `placement`: its
/// `R (0, 0, sign A)` (`facing`), the zero vector for a panel of no area.
pub fn outward_normals(pattern: &Pattern, placement: &Placement) -> Vec<Vec3> {
    (pattern.panels.iter())
        .map(|p| {
            let n = p.rotation() * Vec3::new(0.0, 0.0, p.signed_area().signum());
            let n = change_up_vector(n, Up::Y, Up::Z);
            placement.apply_vector(n) * f64::from(u8::from(p.signed_area() != 0.0))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    fn ball(r: f64) -> Collider {
        let mesh = generate::uv_sphere(Point3::origin(), r, 24, 48);
        Collider::new("ball".into(), mesh, [16, 16, 16], 0.0, None)
    }

    fn sheet(x: f64) -> Vec<Point3> {
        (0..121)
            .map(|k| {
                let (i, j) = ((k % 11) as f64, (k / 11) as f64);
                Point3::new(x, -0.1 + 0.02 * i, -0.1 + 0.02 * j)
            })
            .collect()
    }

    #[test]
    fn a_panel_outside_is_left_and_one_too_deep_stays_where_placed() {
        let b = ball(0.1);
        // Beside the ball: not moved, not listed.
        let mut panels = vec![sheet(0.15), sheet(0.0)];
        let before = panels.clone();
        // The second sheet cuts a ball of radius 1 m through its centre: 0.3 m along its
        // normal is not enough.
        let big = ball(1.0);
        let moved = clear_panels(&mut panels[..1], &[Vec3::x()], &b);
        assert!(moved.is_empty());
        let moved = clear_panels(&mut panels[1..], &[Vec3::x()], &big);
        assert_eq!(moved.len(), 1);
        assert_eq!(moved[0].inside, 121);
        assert!(!moved[0].cleared && moved[0].distance == 0.0);
        assert_eq!(panels, before);
    }

    #[test]
    fn each_panel_goes_its_own_way_and_ends_clear() {
        // Two sheets through the ball from either side, facing away from it.
        let b = ball(0.1);
        let mut panels = vec![sheet(0.06), sheet(-0.03)];
        let normals = [Vec3::x(), -Vec3::x()];
        let moved = clear_panels(&mut panels, &normals, &b);
        assert_eq!(moved.iter().map(|m| m.index).collect::<Vec<_>>(), [0, 1]);
        for (m, p) in moved.iter().zip(&panels) {
            assert!(m.cleared);
            assert!(p.iter().all(|q| !inside(&b, q)));
            // Within a step and one more of the ball's surface along the normal.
            let out = p[60].x.abs();
            assert!(out > 0.1 && out <= 0.1 + 2.0 * STEP, "{out}");
        }
        // Each moved rigidly by its distance along its normal.
        assert!((panels[0][60].x - moved[0].distance - 0.06).abs() < 1e-15);
        assert!((panels[1][60].x + moved[1].distance + 0.03).abs() < 1e-15);
    }
}
