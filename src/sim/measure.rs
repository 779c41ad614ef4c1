//! What a run measures at its end: strain, particles inside objects, clearance, the drape
//! coefficient.

use super::World;
use crate::cloth::elements::SpringKind;
use crate::cloth::model::ClothModel;
use crate::collide::Collider;
use crate::math::{Point3, Vec3};
use rayon::prelude::*;

/// Largest and mean strain (edge length over rest length, minus one) of the stretch springs.
pub fn strain(model: &ClothModel, x: &[Point3]) -> (f64, f64) {
    let s: Vec<f64> = model
        .springs
        .iter()
        .filter(|s| s.kind == SpringKind::Stretch)
        .map(|s| (x[s.b as usize] - x[s.a as usize]).norm() / s.rest - 1.0)
        .collect();
    if s.is_empty() {
        return (0.0, 0.0);
    }
    (
        s.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        s.iter().sum::<f64>() / s.len() as f64,
    )
}

/// Whether `p` is inside the surface of `c`: its winding number is positive. Closed objects
/// count the crossings of a ray through the object's grid (exact, O(cells along the ray)); open
/// ones, and points on the surface to rounding, use the generalized winding number (above 1/2:
/// robust to small holes). See `collide::inside`.
pub fn inside(c: &Collider, p: &Point3) -> bool {
    crate::collide::inside::inside(c, p)
}

/// Particles inside a closed object, per object (`None` for open objects).
pub fn particles_inside(world: &World) -> Vec<Option<usize>> {
    world
        .colliders
        .iter()
        .map(|c| {
            c.closed
                .then(|| world.state.x.par_iter().filter(|p| inside(c, p)).count())
        })
        .collect()
}

/// How many times larger (or smaller) than the cloth an object may be across (box diagonals)
/// before its placement is suspect. A body in centimetres in a metre scene is 100 times too
/// large, which makes it 60 to 200 times a garment; real scenes stay below 20 (a 30 cm
/// specimen on a 3 m floor: 10).
pub const SCALE_WARN: f64 = 50.0;

/// What looks wrong with a scene before it runs: an object [`SCALE_WARN`] times larger or
/// smaller than the cloth across (units), and cloth that starts inside a closed object (no
/// collision can push it out: it is behind the faces). A message per finding, for the user.
pub fn placement_warnings(world: &World) -> Vec<String> {
    let Some(cloth) = crate::math::Aabb::of_points(&world.state.x) else {
        return Vec::new();
    };
    let across = cloth.diagonal();
    let short = crate::math::short;
    let mut out = Vec::new();
    let inside = particles_inside(world);
    for (c, n) in world.colliders.iter().zip(inside) {
        let Some(b) = crate::math::Aabb::of_points(&c.mesh.positions) else {
            continue;
        };
        let ratio = b.diagonal() / across;
        if !(1.0 / SCALE_WARN..=SCALE_WARN).contains(&ratio) {
            out.push(format!(
                "object '{}' is {} times the cloth's size ({} m across against {} m): are both in the scene's units? An object in centimetres in a metre scene is 100 times too large (set its scale)",
                c.name, short(ratio), short(b.diagonal()), short(across)
            ));
        }
        if let Some(n @ 1..) = n {
            out.push(format!(
                "{n} of {} particles start inside object '{}': no collision can push them out (they are behind its faces); move the piece or check the object's scale and placement",
                world.state.x.len(), c.name
            ));
        }
    }
    out
}

/// The smallest distance of a particle to each object.
pub fn min_clearance(world: &World) -> Vec<f64> {
    world
        .colliders
        .iter()
        .map(|c| {
            let q = crate::mesh::closest::ClosestPoints::new(&c.mesh);
            world
                .state
                .x
                .par_iter()
                .map(|p| q.closest(p).distance)
                .reduce(|| f64::INFINITY, f64::min)
        })
        .collect()
}

/// The drape coefficient of a piece (Cusick): its shadow area on the plane across gravity,
/// less the disc's area, over its flat area less the disc's. The shadow is the union of its
/// projected triangles, rasterised at 1/400 of the piece's size.
pub fn drape_coefficient(world: &World, piece: usize, disc_radius: f64) -> f64 {
    let m = &world.model;
    let r = &m.pieces[piece];
    let g = m.gravity.normalize();
    let e1 = g
        .cross(&Vec3::x())
        .try_normalize(1e-9)
        .unwrap_or_else(|| g.cross(&Vec3::y()).normalize());
    let e2 = g.cross(&e1);
    let pts: Vec<(f64, f64)> = world.state.x[r.first..r.first + r.count]
        .iter()
        .map(|p| (p.coords.dot(&e1), p.coords.dot(&e2)))
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in &pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let px = r.area.sqrt() / 400.0;
    let (nx, ny) = (
        ((x1 - x0) / px).ceil() as usize + 1,
        ((y1 - y0) / px).ceil() as usize + 1,
    );
    let mut covered = vec![false; nx * ny];
    for t in &m.triangles[r.first_triangle..r.first_triangle + r.triangles] {
        let [a, b, c] = t.map(|v| pts[v as usize - r.first]);
        let (tx0, tx1) = (a.0.min(b.0).min(c.0), a.0.max(b.0).max(c.0));
        let (ty0, ty1) = (a.1.min(b.1).min(c.1), a.1.max(b.1).max(c.1));
        let cross = |p: (f64, f64), q: (f64, f64), s: (f64, f64)| {
            (q.0 - p.0) * (s.1 - p.1) - (q.1 - p.1) * (s.0 - p.0)
        };
        let area = cross(a, b, c);
        if area == 0.0 {
            continue;
        }
        for j in
            ((ty0 - y0) / px).floor() as usize..=(((ty1 - y0) / px).ceil() as usize).min(ny - 1)
        {
            for i in
                ((tx0 - x0) / px).floor() as usize..=(((tx1 - x0) / px).ceil() as usize).min(nx - 1)
            {
                let p = (x0 + (i as f64 + 0.5) * px, y0 + (j as f64 + 0.5) * px);
                let (w0, w1, w2) = (cross(b, c, p), cross(c, a, p), cross(a, b, p));
                if (w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 && area > 0.0)
                    || (w0 <= 0.0 && w1 <= 0.0 && w2 <= 0.0 && area < 0.0)
                {
                    covered[j * nx + i] = true;
                }
            }
        }
    }
    let shadow = covered.iter().filter(|&&c| c).count() as f64 * px * px;
    let disc = std::f64::consts::PI * disc_radius * disc_radius;
    (shadow - disc) / (r.area - disc)
}
