//! Bringing a body into a pattern's frame. GarmentCode places its panels around a body standing
//! on the floor (`y = 0`, y up), centred on `x = 0` and `z = 0`; its own bodies are in that
//! frame. A body from elsewhere (MakeHuman's exports stand centred on the origin, feet at
//! `y = -0.82 m`) would leave the panels hanging in the air beside it.
//!
//! The body is left where it is when it is *under* the pattern: its height range meets the
//! placed panels', the panels' horizontal centre lies within its box, and it does not reach
//! more than [`FLOOR_TOL`] below the floor (a column or a form placed for the pattern, a
//! GarmentCode body). Otherwise it is moved by `(-c_x, -min_y, -c_z)` (`c` its box's centre):
//! feet on the floor, centred like the GarmentCode bodies. (The floor test matters: MakeHuman's
//! body reaches from -0.82 to 0.85 m, which meets a dress's 0.11 to 1.40 m.)
//!
//! ```
//! use drapekit::garment::frame::body_offset;
//! use drapekit::math::{Aabb, Point3};
//! // Panels from 1.0 to 1.4 m up around x = 0, z = 0.02; a body centred on the origin.
//! let panels = Aabb { min: Point3::new(-0.3, 1.0, -0.2), max: Point3::new(0.3, 1.4, 0.25) };
//! let body = Aabb { min: Point3::new(-0.5, -0.82, -0.1), max: Point3::new(0.5, 0.85, 0.32) };
//! let d = body_offset(&panels, &body).unwrap();
//! assert_eq!((d.x, d.y), (0.0, 0.82));
//! assert!((d.z + 0.11).abs() < 1e-12);
//! // One that meets the panels but reaches 0.82 m below the floor is moved too.
//! let body = Aabb { min: Point3::new(-0.5, -0.82, -0.1), max: Point3::new(0.5, 1.2, 0.32) };
//! assert_eq!(body_offset(&panels, &body).map(|d| d.y), Some(0.82));
//! // A body standing on the floor under the panels stays.
//! let body = Aabb { min: Point3::new(-0.6, 0.0, -0.15), max: Point3::new(0.6, 1.72, 0.15) };
//! assert!(body_offset(&panels, &body).is_none());
//! ```

use super::Pattern;
use crate::math::{Aabb, Point3, Vec3};

/// How far below the floor (`y = 0`) a body may reach and still be in the pattern's frame, m.
pub const FLOOR_TOL: f64 = 0.05;

/// The box of the pattern's placed panel vertices, in metres, in the pattern's frame (y up);
/// `None` without vertices.
pub fn placed_box(pattern: &Pattern) -> Option<Aabb> {
    let scale = 1.0 / pattern.units_in_meter;
    let points: Vec<Point3> = (pattern.panels.iter())
        .flat_map(|p| p.vertices.iter().map(move |v| p.place(*v)))
        .map(|q| Point3::from(q.coords * scale))
        .collect();
    Aabb::of_points(&points)
}

/// Whether a body with box `body` is round the panels with box `panels` (both y up): its height
/// range meets theirs and its box holds their horizontal centre.
pub fn under(panels: &Aabb, body: &Aabb) -> bool {
    let meets = body.min.y <= panels.max.y && panels.min.y <= body.max.y;
    let c = panels.center();
    meets && (body.min.x..=body.max.x).contains(&c.x) && (body.min.z..=body.max.z).contains(&c.z)
}

/// The shift that brings a body with box `body` under panels with box `panels` (both y up, in
/// metres), or `None` when it is there already (module notes).
pub fn body_offset(panels: &Aabb, body: &Aabb) -> Option<Vec3> {
    if under(panels, body) && body.min.y >= -FLOOR_TOL {
        return None;
    }
    let b = body.center();
    Some(Vec3::new(-b.x, -body.min.y, -b.z))
}
