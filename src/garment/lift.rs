//! Seams whose straight path crosses the body: where their sides meet instead.
//!
//! A seam spring pulls its two sides `p`, `q` straight at each other. When the segment `pq`
//! crosses the body (a shoulder seam of a dress whose front and back panels hang in front of and
//! behind the shoulder, below its top), the body's contact holds both sides where they are and
//! sewing stalls. The reference pipeline merges the two sides at their mean position and lets
//! the body push the merged particle out; drapekit keeps the sides apart and sews them over the
//! body instead: both sides are pulled towards a *meeting point* `w` outside the body, chosen
//! so that neither `pw` nor `wq` crosses the body and the path `|pw| + |wq|` is shortest among
//! the candidates
//!
//! ```text
//! w = m + t d(θ),   m = (p + q) / 2,   d(θ) = cos θ u + sin θ v,   u, v ⊥ q - p,
//! ```
//!
//! for [`DIRECTIONS`] angles `θ` and `t` in steps of [`STEP`] up to [`REACH`], plus
//! [`CLEARANCE`] further along `d` (the meeting point sits off the skin). Over a shoulder the
//! shortest clear path goes up and over; under an arm, down. Once `pq` no longer crosses the
//! body the seam spring alone closes it.

use crate::collide::cloth::segment_crosses_body;
use crate::collide::Collider;
use crate::math::{Point3, Vec3};

/// Directions tried around the seam's axis.
pub const DIRECTIONS: usize = 16;

/// Step along each direction, m.
pub const STEP: f64 = 0.01;

/// Farthest a meeting point is looked for from the midpoint, m.
pub const REACH: f64 = 0.3;

/// How far off the body the meeting point is moved, m.
pub const CLEARANCE: f64 = 0.01;

/// Whether segment `pq` properly crosses a face of `body`.
pub fn crosses_body(body: &Collider, p: &Point3, q: &Point3) -> bool {
    segment_crosses_body(body, p, q, &mut Vec::new())
}

/// Two unit vectors perpendicular to `d` and to each other.
fn frame(d: &Vec3) -> (Vec3, Vec3) {
    let a = if d.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let u = d.cross(&a).normalize();
    (u, d.cross(&u).normalize())
}

/// The meeting point of sides `p` and `q` (module docs), or `None` when `pq` does not cross the
/// body or no clear path was found within [`REACH`].
pub fn meeting_point(body: &Collider, p: &Point3, q: &Point3) -> Option<Point3> {
    if !crosses_body(body, p, q) {
        return None;
    }
    let d = q - p;
    if d.norm() == 0.0 {
        return None;
    }
    let (u, v) = frame(&d.normalize());
    let m = p + d * 0.5;
    let mut best: Option<(f64, Point3)> = None;
    for k in 0..DIRECTIONS {
        let th = std::f64::consts::TAU * k as f64 / DIRECTIONS as f64;
        let dir = u * th.cos() + v * th.sin();
        let steps = (REACH / STEP).round() as usize;
        for s in 1..=steps {
            let w = m + dir * (s as f64 * STEP);
            let cost = (w - p).norm() + (q - w).norm();
            if best.is_some_and(|(c, _)| c <= cost) {
                break;
            }
            if !crosses_body(body, p, &w) && !crosses_body(body, &w, q) {
                best = Some((cost, w + dir * CLEARANCE));
                break;
            }
        }
    }
    best.map(|(_, w)| w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    fn ball() -> Collider {
        // A sphere of radius 0.1 m (a shoulder's scale) at the origin.
        let mesh = generate::uv_sphere(Point3::origin(), 0.1, 24, 48);
        Collider::new("ball".into(), mesh, [16, 16, 16], 0.0, None)
    }

    #[test]
    fn a_seam_across_a_ball_meets_over_it() {
        let c = ball();
        // Sides in front of and behind the ball, a little above its centre: the shortest path
        // goes over the top (+z side), not below.
        let (p, q) = (Point3::new(0.0, -0.12, 0.03), Point3::new(0.0, 0.12, 0.03));
        assert!(crosses_body(&c, &p, &q));
        let w = meeting_point(&c, &p, &q).expect("a path over the ball");
        // Straight up, the path clears the ball from z = 0.130 m on (the line from p at
        // distance 0.1 from the centre): length 2 sqrt(0.12^2 + 0.1^2) = 0.312 m. The search
        // finds a path that short to within its steps, over the top.
        let cost = (w - p).norm() + (q - w).norm();
        assert!(cost < 0.3124 + 2.0 * (STEP + CLEARANCE), "{w} {cost}");
        assert!(w.z > 0.1 && w.y.abs() < 1e-12, "{w}");
        assert!(!crosses_body(&c, &p, &w) && !crosses_body(&c, &w, &q));
        // Below the centre, it goes under.
        let (p, q) = (
            Point3::new(0.0, -0.12, -0.03),
            Point3::new(0.0, 0.12, -0.03),
        );
        assert!(meeting_point(&c, &p, &q).unwrap().z < -0.1);
    }

    #[test]
    fn a_seam_beside_the_ball_needs_no_meeting_point() {
        let c = ball();
        let (p, q) = (Point3::new(0.11, -0.12, 0.0), Point3::new(0.11, 0.12, 0.0));
        assert!(!crosses_body(&c, &p, &q));
        assert!(meeting_point(&c, &p, &q).is_none());
    }
}
