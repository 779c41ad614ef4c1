//! Particle-face contact (`method.md` s. 4): detection along the step, the push out to the
//! thickness, the velocity correction, sliding and friction.
//!
//! **Passing through** (the paper's test). The segment from a particle's previous position `p0`
//! to its new one `p1` is tested against every face listed in the cells it passes: the particle
//! passed through a face when the segment crosses the face's plane from the side of `p0` at a
//! point inside the triangle (with a small tolerance, so an edge belongs to both its faces). On
//! a closed surface no path from outside to inside avoids this test. The earliest crossing wins;
//! the particle is put on the face normal at distance `thickness` on the side of `p0` (at the
//! projection of `p1` if that is inside the face, keeping the motion along the face; else at the
//! crossing), and another search runs from `p0` to the corrected point.
//!
//! **Thickness.** Then every face within reach of the end point (the faces listed in its cell)
//! whose closest point lies nearer than `thickness` pushes the particle out to `thickness`:
//! along the face normal when the closest point is inside the face, away from the edge or
//! vertex otherwise (near a convex edge a particle projects onto neither face). A particle held
//! in front of a face whose neighbourhood is convex skips this: it is already that far from the
//! faces around.
//!
//! **Velocity.** The component into the face (or away from the push direction) is removed. The
//! particle then *slides* on the face.
//!
//! **Sliding.** While a particle slides, the force on it is projected on the face's plane when
//! it pushes into the face (a force pulling it off ends the contact), and friction resists with
//! the paper's magnitude, the fraction `friction` of that tangential force (`F = F_proj - F_fr`,
//! `|F_fr| = friction |F_proj|`). Two departures from the paper, both so that friction only takes
//! energy out: the resistance opposes the sliding motion rather than the force (opposing the force
//! pushes a particle that moves against it, and pumps energy into oscillations), and never
//! reverses the motion within a step; and Coulomb's static condition with the same coefficient
//! holds a particle whose tangential momentum plus one step of tangential force is within
//! `friction` times the pressing force (the paper's friction alone never holds cloth on a slope).
//! After the step the particle is kept at least `thickness` from the face (pushed out, never
//! pulled in) while its projection stays inside; if it leaves the face, only the faces around it
//! are tested, so it cannot slip inside at an edge; if none holds it, the full search resumes.

use super::collider::Collider;
use crate::cloth::state::Contact;
use crate::math::{Point3, Vec3};
use crate::mesh::closest::closest_on_triangle;

/// Barycentric tolerance of the inside-the-triangle test.
pub const INSIDE_TOL: f64 = 1e-7;

/// Whether the projection `q` (on the plane) of a point is inside face `f` of `c`.
#[inline]
pub fn inside_face(c: &Collider, f: usize, q: &Point3) -> bool {
    let [a, b, cc] = c.mesh.corners(f);
    let (v0, v1, v2) = (b - a, cc - a, q - a);
    let (d00, d01, d11) = (v0.dot(&v0), v0.dot(&v1), v1.dot(&v1));
    let (d20, d21) = (v2.dot(&v0), v2.dot(&v1));
    let den = d00 * d11 - d01 * d01;
    if den <= 0.0 {
        return false;
    }
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    v >= -INSIDE_TOL && w >= -INSIDE_TOL && v + w <= 1.0 + INSIDE_TOL
}

/// A segment crossing a face: where along the segment, and from which side.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Crossing {
    t: f64,
    object: usize,
    face: u32,
    side: f64,
}

/// Whether segment `p0 -> p1` crosses the plane of face `f` inside the face.
#[inline]
fn crossing(c: &Collider, f: usize, p0: &Point3, p1: &Point3) -> Option<(f64, f64)> {
    let (n, off) = c.plane(f);
    let (d0, d1) = (p0.coords.dot(&n) - off, p1.coords.dot(&n) - off);
    if (d0 > 0.0 && d1 >= 0.0)
        || (d0 < 0.0 && d1 <= 0.0)
        || (d0 == 0.0 && d1 == 0.0)
        || n == Vec3::zeros()
    {
        return None;
    }
    let side = if d0 != 0.0 { d0.signum() } else { -d1.signum() };
    let t = d0 / (d0 - d1);
    let r = p0 + (p1 - p0) * t;
    inside_face(c, f, &(r - n * (r.coords.dot(&n) - off))).then_some((t, side))
}

/// Removes the velocity component against direction `n` (unit, pointing away from the face).
#[inline]
fn stop_into(v: &mut Vec3, n: &Vec3) {
    let vn = v.dot(n);
    if vn < 0.0 {
        *v -= n * vn;
    }
}

/// Projects the force on a sliding particle of mass `m` for a step `dt` (see the module docs).
/// Returns false when the force pulls the particle off the face (the contact ends).
pub fn slide_force(
    c: &Collider,
    contact: &Contact,
    friction: f64,
    m: f64,
    dt: f64,
    f: &mut Vec3,
    v: &mut Vec3,
) -> bool {
    let n = c.plane(contact.face as usize).0 * contact.side;
    let fn_ = f.dot(&n);
    if fn_ > 0.0 {
        return false;
    }
    stop_into(v, &n);
    let ft = *f - n * fn_;
    let vt = *v - n * v.dot(&n);
    // Where the tangential motion would go in one step without friction.
    let trial = vt + ft * (dt / m);
    let momentum = trial.norm() * m / dt;
    if momentum <= friction * -fn_ {
        // Static: the friction the pressing force allows stops it.
        *f = Vec3::zeros();
        *v = Vec3::zeros();
        return true;
    }
    // Kinetic: the paper's magnitude, a fraction of the tangential force, against the motion,
    // and never more than stops it.
    let fr = (friction * ft.norm()).min(momentum);
    *f = ft - trial * (fr / trial.norm());
    true
}

/// Whether the segment's box comes within `m` of the object's box.
#[inline]
fn near(c: &Collider, p0: &Point3, p1: &Point3, m: f64) -> bool {
    let (lo, hi) = (p0.inf(p1), p0.sup(p1));
    (0..3).all(|k| hi[k] >= c.bbox.min[k] - m && lo[k] <= c.bbox.max[k] + m)
}

/// A face around `f` (its ring) behind whose plane `p` lies (on side `side`) and over which
/// it projects: where a particle that passed through `f` near its edge is pushed out along a
/// normal instead of back along its path (which would undo its whole slide of the step).
fn beside(c: &Collider, f: usize, side: f64, p: &Point3) -> Option<usize> {
    c.ring(f).iter().map(|&g| g as usize).find(|&g| {
        let (n, off) = c.plane(g);
        let d = p.coords.dot(&n) - off;
        side * d < 0.0 && inside_face(c, g, &(p - n * d))
    })
}

/// The objects a particle may meet: each one and whether it is reachable this step.
#[derive(Clone, Copy)]
struct Objects<'a> {
    colliders: &'a [Collider],
    reachable: &'a [bool],
}

impl Objects<'_> {
    /// The reachable objects, with their index.
    fn each(&self) -> impl Iterator<Item = (usize, &Collider)> {
        (self.colliders.iter().enumerate()).filter(|&(oi, _)| self.reachable[oi])
    }
}

/// A particle being corrected after a step: its new position and velocity (corrected in place),
/// its thickness, and its sliding state.
struct Particle<'a> {
    p1: &'a mut Point3,
    v: &'a mut Vec3,
    th: f64,
    contact: &'a mut Option<Contact>,
}

/// Collision of one particle with all objects after a step: `p0` its previous position, `p1` and
/// `v` its new position and velocity (corrected in place), `contact` its sliding state. Objects
/// whose `reachable` flag is false are skipped. Returns whether it touches an object.
#[allow(clippy::too_many_arguments)]
pub fn resolve(
    colliders: &[Collider],
    reachable: &[bool],
    p0: &Point3,
    p1: &mut Point3,
    v: &mut Vec3,
    th: f64,
    contact: &mut Option<Contact>,
) -> bool {
    let p = &mut Particle { p1, v, th, contact };
    let mut touched = match *p.contact {
        Some(ct) => slide(colliders, ct, p),
        None => false,
    };
    let objects = Objects {
        colliders,
        reachable,
    };
    if !touched {
        if meets_nothing(objects, p0, p.p1, th) {
            return false;
        }
        touched = pass_through(objects, p0, p);
    }
    // A particle held in front of a face where the surface is locally convex is at least the
    // thickness from every face around: nothing more to check.
    let convex_hold = matches!(*p.contact, Some(ct) if ct.side > 0.0 && colliders[ct.object as usize].convex[ct.face as usize]);
    if (th > 0.0 || colliders.iter().any(|c| c.clearance > 0.0)) && !convex_hold {
        touched |= keep_thickness(objects, p);
    }
    touched
}

/// Sliding on the face of `ct`: the particle stays on it, or moves to one around it, while its
/// projection is inside the face and it has not left it (pushed out to the thickness if it came
/// closer, never pulled in); else the contact ends. Whether it is still held.
#[inline]
fn slide(colliders: &[Collider], ct: Contact, p: &mut Particle) -> bool {
    let c = &colliders[ct.object as usize];
    let th = p.th + c.clearance;
    let keep = |f: usize, side: f64, p1: &Point3| -> Option<Point3> {
        let (n, off) = c.plane(f);
        let dp = p1.coords.dot(&n) - off;
        let d = side * dp;
        if d > 1.5 * th || d < -th {
            return None;
        }
        let q = p1 - n * dp;
        inside_face(c, f, &q).then(|| if d < th { q + n * (side * th) } else { *p1 })
    };
    let f = ct.face as usize;
    let mut held = keep(f, ct.side, p.p1).map(|q| (q, f, ct.side));
    if held.is_none() {
        // Objects are prepared with one winding, so the particle is on the same side of the
        // faces around (a side taken from its position would put it inside the object at a
        // convex edge, where it is behind the next face's plane).
        for &g in c.ring(f) {
            let g = g as usize;
            if let Some(q) = keep(g, ct.side, p.p1) {
                held = Some((q, g, ct.side));
                break;
            }
        }
    }
    let Some((q, g, side)) = held else {
        *p.contact = None;
        return false;
    };
    *p.p1 = q;
    stop_into(p.v, &(c.plane(g).0 * side));
    *p.contact = Some(Contact {
        object: ct.object,
        face: g as u32,
        side,
    });
    true
}

/// Whether the step from `p0` to `p1` starts and ends in one empty cell of every object it
/// comes near (then it meets nothing).
#[inline]
fn meets_nothing(objects: Objects, p0: &Point3, p1: &Point3, th: f64) -> bool {
    objects.each().all(|(_, c)| {
        if !near(c, p0, p1, th + c.clearance + c.margin) {
            return true;
        }
        let g = c.grid();
        let (a, b) = (g.clamp_cell(p0), g.clamp_cell(p1));
        a == b
            && c.bbox.contains(p0, c.margin)
            && c.bbox.contains(p1, c.margin)
            && g.cell_faces(g.linear(a[0], a[1], a[2])).is_empty()
    })
}

/// The earliest face the segment `p0`-`p1` crosses, of every reachable object near it (ties
/// to the lowest object, then face).
fn earliest_crossing(objects: Objects, p0: &Point3, p1: &Point3, th: f64) -> Option<Crossing> {
    let mut best: Option<Crossing> = None;
    for (oi, c) in objects.each() {
        if !near(c, p0, p1, th + c.clearance + c.margin) {
            continue;
        }
        let grid = c.grid();
        // A face listed in several cells may be tested twice: same answer, no harm.
        grid.traverse(p0, p1, |cell| {
            for &f in grid.cell_faces(cell) {
                if let Some((t, side)) = crossing(c, f as usize, p0, p1) {
                    let cand = Crossing {
                        t,
                        object: oi,
                        face: f,
                        side,
                    };
                    if best.is_none_or(|b| (t, oi, f) < (b.t, b.object, b.face)) {
                        best = Some(cand);
                    }
                }
            }
            true
        });
    }
    best
}

/// Passing through: the earliest crossing along the segment, corrected, again after each
/// correction (three at most). The particle is put on the crossed face's side at the
/// thickness: over the face, over a face around it, or where its path met the plane.
/// Whether it crossed anything.
fn pass_through(objects: Objects, p0: &Point3, p: &mut Particle) -> bool {
    let mut touched = false;
    for _ in 0..3 {
        let Some(h) = earliest_crossing(objects, p0, p.p1, p.th) else {
            break;
        };
        let c = &objects.colliders[h.object];
        let th = p.th + c.clearance;
        let f = h.face as usize;
        let (n, off) = c.plane(f);
        let p1 = *p.p1;
        let q1 = p1 - n * (p1.coords.dot(&n) - off);
        let (q, face) = if inside_face(c, f, &q1) {
            (q1 + n * (h.side * th), f)
        } else if let Some(g) = beside(c, f, h.side, &p1) {
            // Out over a face around: pushed out of it along its normal.
            let (ng, og) = c.plane(g);
            (p1 - ng * (p1.coords.dot(&ng) - og) + ng * (h.side * th), g)
        } else {
            let r = p0 + (p1 - p0) * h.t;
            (r - n * (r.coords.dot(&n) - off) + n * (h.side * th), f)
        };
        *p.p1 = q;
        stop_into(p.v, &(c.plane(face).0 * h.side));
        *p.contact = Some(Contact {
            object: h.object as u32,
            face: face as u32,
            side: h.side,
        });
        touched = true;
    }
    touched
}

/// Thickness: the particle pushed out of every face nearer than the thickness (plus the
/// object's clearance), along its normal or away from its edge, in two rounds at most.
/// Whether it was moved.
fn keep_thickness(objects: Objects, p: &mut Particle) -> bool {
    let mut touched = false;
    for _ in 0..2 {
        let mut moved = false;
        for (oi, c) in objects.each() {
            let th = p.th + c.clearance;
            if !c.bbox.contains(p.p1, th + c.margin) {
                continue;
            }
            let grid = c.grid();
            let cell = grid.clamp_cell(p.p1);
            for &f in grid.cell_faces(grid.linear(cell[0], cell[1], cell[2])) {
                if push_from_face(c, oi, f as usize, p.p1, p.v, th, p.contact) {
                    touched = true;
                    moved = true;
                }
            }
        }
        if !moved {
            break;
        }
    }
    touched
}

/// The particle pushed out to `th` from face `f` of object `oi` (`c`) when nearer: along the
/// normal over the face, away from the nearest point of its edge beside it. Whether it moved.
fn push_from_face(
    c: &Collider,
    oi: usize,
    f: usize,
    p1: &mut Point3,
    v: &mut Vec3,
    th: f64,
    contact: &mut Option<Contact>,
) -> bool {
    let (n, off) = c.plane(f);
    let dp = p1.coords.dot(&n) - off;
    if dp.abs() >= th || n == Vec3::zeros() {
        return false;
    }
    // Pass-throughs are resolved: the particle is on its side of the plane now.
    let side = if dp >= 0.0 { 1.0 } else { -1.0 };
    let proj = *p1 - n * dp;
    let interior = inside_face(c, f, &proj);
    let (q, d) = if interior {
        (proj, dp.abs())
    } else {
        let [fa, fb, fc] = c.mesh.corners(f);
        let q = closest_on_triangle(p1, &fa, &fb, &fc);
        (q, (*p1 - q).norm())
    };
    if d >= th {
        return false;
    }
    let dir = if interior || d == 0.0 {
        n * side
    } else {
        (*p1 - q) / d
    };
    *p1 = q + dir * th;
    stop_into(v, &dir);
    if interior || contact.is_none() {
        // Pushed away from an edge of a closed (outward) object, the particle is outside it
        // whatever side of this face's plane it is on (beside a square rim it is behind the
        // plane of the face below): a contact on the inner side would hold it inside the next
        // face round the rim.
        let side = if interior || !c.closed { side } else { 1.0 };
        *contact = Some(Contact {
            object: oi as u32,
            face: f as u32,
            side,
        });
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    fn unit_square() -> Collider {
        let p = vec![
            Point3::new(-1.0, -1.0, 0.0),
            Point3::new(1.0, -1.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(-1.0, 1.0, 0.0),
        ];
        let m = crate::mesh::TriMesh::new(p, vec![[0, 1, 2], [2, 3, 0]]);
        Collider::new("floor".into(), m, [4, 4, 1], 0.01, None)
    }

    #[test]
    fn a_particle_through_a_face_near_its_edge_is_pushed_out_of_the_next_face() {
        // The step crosses face 0 (x > y) and ends under face 1: it is pushed out along face
        // 1's normal where it ended, not put back where it crossed (that undid its slide).
        let objects = [unit_square()];
        let (p0, mut p, mut v) = (
            Point3::new(0.5, 0.1, 0.02),
            Point3::new(0.1, 0.5, -0.5),
            Vec3::new(-4.0, 4.0, -52.0),
        );
        let mut contact = None;
        assert!(resolve(
            &objects,
            &[true],
            &p0,
            &mut p,
            &mut v,
            0.01,
            &mut contact
        ));
        assert!((p - Point3::new(0.1, 0.5, 0.01)).norm() < 1e-12, "{p}");
        assert_eq!(contact.map(|c| c.face), Some(1));
        assert_eq!(v, Vec3::new(-4.0, 4.0, 0.0));
    }

    #[test]
    fn a_particle_beside_a_closed_objects_corner_is_in_contact_from_outside() {
        // 3 mm outside each face at a cube's bottom corner, behind the bottom face's plane's
        // far side: pushed away from the corner, and in contact from the outside (side +1). On
        // the inner side, the next step held it inside the face round the rim (the Cusick
        // disc's skirt ended inside the disc).
        let c = Collider::new("cube".into(), generate::cube(1.0), [2, 2, 2], 0.01, None);
        assert!(c.closed);
        let objects = [c];
        for corner in [[1.0, 1.0, -1.0], [-1.0, 1.0, 1.0], [1.0, -1.0, 1.0]] {
            let q = Vec3::from(corner) * 0.503;
            let q = Point3::from(q - Vec3::z() * (0.006 * corner[2]));
            let (mut p, mut v, mut contact) = (q, Vec3::zeros(), None);
            resolve(&objects, &[true], &q, &mut p, &mut v, 0.01, &mut contact);
            let ct = contact.expect("in contact");
            assert_eq!(ct.side, 1.0, "corner {corner:?}: face {}", ct.face);
            assert!(!crate::collide::inside::inside(&objects[0], &p), "{p}");
        }
    }

    #[test]
    fn an_objects_clearance_adds_to_the_thickness() {
        let mut c = unit_square();
        c.clearance = 0.004;
        let objects = [c];
        // Where a step from p0 to p1 ends, with thickness 0.01 m.
        let put = |p0: Point3, p1: Point3, contact: &mut Option<Contact>| {
            let (mut p, mut v) = (p1, Vec3::new(0.5, 0.0, -35.0));
            resolve(&objects, &[true], &p0, &mut p, &mut v, 0.01, contact);
            p.z
        };
        let mut contact = None;
        // Through the face: put at thickness + clearance.
        let through = Point3::new(0.25, 0.3, -3.0);
        assert!((put(Point3::new(0.2, 0.3, 0.5), through, &mut contact) - 0.014).abs() < 1e-12);
        assert!(contact.is_some());
        // Held in contact: a step towards the face stops at the same distance.
        let held = put(
            Point3::new(0.25, 0.3, 0.014),
            Point3::new(0.3, 0.3, 0.012),
            &mut contact,
        );
        assert!((held - 0.014).abs() < 1e-12, "{held}");
        // Arriving within the clearance (not through the face): pushed out too.
        let near = put(
            Point3::new(0.5, 0.5, 0.3),
            Point3::new(0.5, 0.5, 0.013),
            &mut None,
        );
        assert!((near - 0.014).abs() < 1e-12, "{near}");
    }

    #[test]
    fn fast_particle_is_caught_and_put_at_thickness() {
        let c = unit_square();
        let (p0, mut p1, mut v) = (
            Point3::new(0.2, 0.3, 0.5),
            Point3::new(0.25, 0.3, -3.0),
            Vec3::new(0.5, 0.0, -35.0),
        );
        let mut contact = None;
        assert!(resolve(
            &[c],
            &[true],
            &p0,
            &mut p1,
            &mut v,
            0.01,
            &mut contact
        ));
        assert!((p1 - Point3::new(0.25, 0.3, 0.01)).norm() < 1e-12, "{p1:?}");
        assert_eq!(v, Vec3::new(0.5, 0.0, 0.0));
        assert!(contact.is_some());
    }

    #[test]
    fn the_side_of_the_previous_position_is_kept() {
        let c = unit_square();
        let (p0, mut p1, mut v) = (
            Point3::new(0.2, 0.3, -0.5),
            Point3::new(0.2, 0.3, 0.5),
            Vec3::new(0.0, 0.0, 10.0),
        );
        let mut contact = None;
        resolve(&[c], &[true], &p0, &mut p1, &mut v, 0.01, &mut contact);
        assert!((p1.z + 0.01).abs() < 1e-12, "pushed back below: {p1:?}");
    }

    #[test]
    fn sliding_moves_across_an_edge_and_friction_scales_the_force() {
        let c = unit_square();
        let ct = Contact {
            object: 0,
            face: 0,
            side: 1.0,
        };
        let mut contact = Some(ct);
        // From face 0 across the diagonal into face 1.
        let (p0, mut p1, mut v) = (
            Point3::new(0.5, -0.5, 0.01),
            Point3::new(-0.5, 0.5, 0.005),
            Vec3::new(-1.0, 1.0, -0.1),
        );
        assert!(resolve(
            &[c],
            &[true],
            &p0,
            &mut p1,
            &mut v,
            0.01,
            &mut contact
        ));
        assert_eq!(contact.unwrap().face, 1);
        assert!((p1.z - 0.01).abs() < 1e-15);
        let c = unit_square();
        // Kinetic, moving along the force: 70% of the tangential force remains.
        let (mut f, mut v) = (Vec3::new(1.0, 0.0, -2.0), Vec3::new(1.0, 0.0, 0.0));
        assert!(slide_force(&c, &ct, 0.3, 1.0, 1e-3, &mut f, &mut v));
        assert!((f - Vec3::new(0.7, 0.0, 0.0)).norm() < 1e-12, "{f:?}");
        // Moving against the force: friction adds to the braking, it never pushes.
        let (mut f, mut v) = (Vec3::new(1.0, 0.0, -2.0), Vec3::new(-1.0, 0.0, 0.0));
        assert!(slide_force(&c, &ct, 0.3, 1.0, 1e-3, &mut f, &mut v));
        assert!((f - Vec3::new(1.3, 0.0, 0.0)).norm() < 1e-12, "{f:?}");
        // Static: at rest, 0.5 <= 0.3 x 2: held.
        let (mut f, mut v) = (Vec3::new(0.5, 0.0, -2.0), Vec3::zeros());
        assert!(slide_force(&c, &ct, 0.3, 1.0, 1e-3, &mut f, &mut v));
        assert_eq!((f, v), (Vec3::zeros(), Vec3::zeros()));
        let mut up = Vec3::new(0.0, 0.0, 1.0);
        assert!(
            !slide_force(&c, &ct, 0.3, 1.0, 1e-3, &mut up, &mut v),
            "a force off the face ends the contact"
        );
    }

    #[test]
    fn closed_sphere_collider() {
        let c = Collider::new("s".into(), generate::icosphere(2), [6, 6, 6], 0.0, None);
        assert!(c.closed);
        assert!(c.ring(0).len() >= 10);
    }
}
