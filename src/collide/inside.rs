//! Whether a point is inside a closed object, by counting where a ray crosses its surface.
//!
//! **The winding number.** For a closed surface wound outward (as `mesh::prepare` leaves it)
//! the winding number `w(p)` is 1 inside, 0 outside (more inside nested or overlapping shells).
//! Two ways to compute it:
//!
//! * the *generalized winding number* `sum_f Omega_f(p) / 4 pi`, the solid angles of the faces
//!   seen from `p` (Van Oosterom and Strackee; Jacobson et al. 2013). It costs O(faces) per
//!   point, and it is the answer for open surfaces too (robust to holes): it is the reference
//!   (`inside_by_winding`, inside when above 1/2);
//! * *ray crossings*: a ray `p + t d`, `t > 0`, leaves the surface through the front of a face
//!   (`d . n > 0`) once more than it enters, so `w(p) = sum over crossings of sign(d . n)`. Only
//!   the faces near the ray matter: those listed in the grid cells the ray walks through
//!   ([`Grid::traverse`]); a face listed in several cells is tested once (the candidates are
//!   sorted and deduplicated). The cost is the cells along the ray and the faces in them.
//!
//! **One face, certified.** With `a' = a - p` (and `b'`, `c'`) the line of the ray passes each
//! edge on the side given by the sign of `s_ab = d . (a' x b')` (and `s_bc`, `s_ca`); it crosses
//! the triangle's interior exactly when the three signs agree, and as
//! `s_ab + s_bc + s_ca = d . n` with `n = (b - a) x (c - a)`, that sign is the sign of `d . n`.
//! The crossing is ahead of `p` (`t = V / (d . n) > 0`) when `V = (a - p) . n` has the same sign.
//! A sign is used only when the value exceeds [`CERTAIN`] times the product of the lengths that
//! bound it (`|d| |a'| |b'|` for `s_ab`; `|a'| |b - a| |c - a|` for `V`); rounding errors are a
//! few times 1e-16 of that product, so every sign used is the exact sign for the mesh as stored,
//! and the count is exact. Otherwise the ray is *ambiguous*: it passes within rounding of an edge or
//! a vertex (both faces of an edge see the same `|s|`, so an edge is never counted twice or
//! missed), or `p` lies within rounding of a face's plane where the line meets the face.
//!
//! **Directions.** The ray runs mostly along the grid axis with the fewest cells, towards the
//! nearer side of the box (the shortest walk), tilted by fixed irrational fractions so that it
//! does not run along the faces of axis-aligned meshes. An ambiguous ray is replaced by the next
//! of three such directions; a point whose three rays are all ambiguous (on the surface, to
//! rounding) is decided by the generalized winding number, and so is every point of an open
//! object (crossings mean nothing where the surface has holes). The answer depends only on the
//! point and the collider: not on the order of the queries or the number of threads.

use super::grid::Grid;
use super::Collider;
use crate::math::{Point3, Vec3};
use crate::mesh::orient::solid_angle;

/// Relative size below which a sign is not trusted (see the module docs).
pub const CERTAIN: f64 = 1e-10;

/// Off-axis components of the three ray directions: `(sqrt 2 - 1)/4`, `(sqrt 3 - 1)/4` and
/// `(sqrt 5 - 2)/4` in turn, with signs.
const TILTS: [[f64; 2]; 3] = [
    [0.103_553_390_593_273_77, 0.183_012_701_892_219_33],
    [-0.183_012_701_892_219_33, 0.059_016_994_374_947_42],
    [0.059_016_994_374_947_42, -0.103_553_390_593_273_77],
];

/// How one point was decided.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Decision {
    /// Outside the object's box.
    OutsideBox,
    /// By the crossings of ray `k` (0, 1 or 2): the winding number.
    Ray(usize, i64),
    /// By the generalized winding number.
    Winding,
}

/// What one face does to one ray.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Crossing {
    /// The ray misses it (or meets it behind `p`).
    Miss,
    /// The ray crosses it ahead of `p`: +1 leaving through its front, -1 entering.
    Cross(i64),
    /// Too close to an edge, a vertex, or `p` itself to tell.
    Ambiguous,
}

/// Whether `p` is inside the closed surface of `c` (its winding number is positive); for an open
/// object, whether its generalized winding number is above 1/2. See the module docs.
pub fn inside(c: &Collider, p: &Point3) -> bool {
    match decide(c, p) {
        Decision::OutsideBox => false,
        Decision::Ray(_, w) => w > 0,
        Decision::Winding => inside_by_winding(c, p),
    }
}

/// The reference: whether the generalized winding number of `c` about `p` is above 1/2
/// (O(faces) per point).
pub fn inside_by_winding(c: &Collider, p: &Point3) -> bool {
    c.bbox.contains(p, 0.0) && winding_number(c, p) > 0.5
}

/// The generalized winding number of `c`'s surface about `p`.
fn winding_number(c: &Collider, p: &Point3) -> f64 {
    let total: f64 = (0..c.mesh.faces.len())
        .map(|f| {
            let [a, b, cc] = c.mesh.corners(f);
            solid_angle(p, &a, &b, &cc)
        })
        .sum();
    total / (4.0 * std::f64::consts::PI)
}

/// How `p` is decided: outside the box; else by the first unambiguous ray (closed objects); else
/// by the generalized winding number.
fn decide(c: &Collider, p: &Point3) -> Decision {
    if !c.bbox.contains(p, 0.0) {
        return Decision::OutsideBox;
    }
    if c.closed {
        let grid = c.grid();
        for (k, tilt) in TILTS.iter().enumerate() {
            if let Some(w) = ray_winding(c, grid, p, &direction(grid, p, tilt)) {
                return Decision::Ray(k, w);
            }
        }
    }
    Decision::Winding
}

/// A ray direction from `p` (unit length): along the axis with the fewest cells, towards the
/// nearer side of the grid's box, with `tilt` along the other two axes.
fn direction(grid: &Grid, p: &Point3, tilt: &[f64; 2]) -> Vec3 {
    let k = (0..3).min_by_key(|&a| grid.dims[a]).unwrap_or(2);
    let b = &grid.bbox;
    let mut d = Vec3::zeros();
    d[k] = if p[k] - b.min[k] <= b.max[k] - p[k] {
        -1.0
    } else {
        1.0
    };
    d[(k + 1) % 3] = tilt[0];
    d[(k + 2) % 3] = tilt[1];
    d.normalize()
}

/// The winding number by the crossings of the ray from `p` along unit `d`, or `None` when the
/// ray is ambiguous.
fn ray_winding(c: &Collider, grid: &Grid, p: &Point3, d: &Vec3) -> Option<i64> {
    let far = p + d * (2.0 * grid.bbox.diagonal() + 1.0);
    let mut faces: Vec<u32> = Vec::new();
    grid.traverse(p, &far, |cell| {
        faces.extend_from_slice(grid.cell_faces(cell));
        true
    });
    faces.sort_unstable();
    faces.dedup();
    let mut w = 0;
    for &f in &faces {
        match crossing(p, d, &c.mesh.corners(f as usize)) {
            Crossing::Miss => {}
            Crossing::Cross(s) => w += s,
            Crossing::Ambiguous => return None,
        }
    }
    Some(w)
}

/// The certified sign of `value` against `bound2`, the square of the product of lengths that
/// bounds it: `Some(+-1)`, or `None` when it is too small to trust.
#[inline]
fn certain_sign(value: f64, bound2: f64) -> Option<i64> {
    if value * value > CERTAIN * CERTAIN * bound2 {
        Some(if value > 0.0 { 1 } else { -1 })
    } else {
        None
    }
}

/// What triangle `[a, b, c]` does to the ray from `p` along unit `d` (see the module docs).
fn crossing(p: &Point3, d: &Vec3, [a, b, c]: &[Point3; 3]) -> Crossing {
    let r = [a - p, b - p, c - p];
    let len2 = r.map(|v| v.norm_squared());
    let mut sign = 0;
    let mut unsure = false;
    for i in 0..3 {
        let j = (i + 1) % 3;
        match certain_sign(d.dot(&r[i].cross(&r[j])), len2[i] * len2[j]) {
            Some(s) if sign == -s => return Crossing::Miss,
            Some(s) => sign = s,
            None => unsure = true,
        }
    }
    if unsure {
        return Crossing::Ambiguous;
    }
    let (ab, ac) = (b - a, c - a);
    match certain_sign(
        r[0].dot(&ab.cross(&ac)),
        len2[0] * ab.norm_squared() * ac.norm_squared(),
    ) {
        Some(v) if v == sign => Crossing::Cross(sign),
        Some(_) => Crossing::Miss,
        None => Crossing::Ambiguous,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix;
    use crate::mesh::{generate, TriMesh};

    fn collider(mesh: TriMesh, dims: [usize; 3]) -> Collider {
        Collider::new("test".into(), mesh, dims, 0.0, None)
    }

    fn random_unit(rng: &mut SplitMix) -> Vec3 {
        loop {
            let v =
                Vec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - Vec3::repeat(1.0);
            let n = v.norm();
            if n > 0.1 && n <= 1.0 {
                return v / n;
            }
        }
    }

    /// The winding answer and the fast one agree, and both are `expected` (when given).
    fn check(c: &Collider, p: &Point3, expected: Option<bool>) {
        let fast = inside(c, p);
        assert_eq!(fast, inside_by_winding(c, p), "{p:?}: {:?}", decide(c, p));
        if let Some(e) = expected {
            assert_eq!(fast, e, "{p:?}: {:?}", decide(c, p));
        }
    }

    #[test]
    fn sphere_inside_and_outside_by_radius() {
        // Icosphere level 3: vertices on the unit sphere, faces at least 0.99 from the centre.
        let c = collider(generate::icosphere(3), [12, 12, 12]);
        let mut rng = SplitMix(7);
        for i in 0..3000 {
            let r = match i % 3 {
                0 => 0.98 * rng.next_f64(),
                1 => 0.98 - 1e-9,
                _ => 1.0 + 1e-9 + rng.next_f64() * 0.5,
            };
            let p = Point3::from(random_unit(&mut rng) * r);
            check(&c, &p, Some(r < 0.99));
            if r < 0.99 {
                assert!(matches!(decide(&c, &p), Decision::Ray(_, 1)));
            }
        }
    }

    #[test]
    fn cube_near_faces_edges_and_vertices() {
        // Edge 2: faces at +-1. Points 1e-9, 1e-6 and 0.3 inside every face, edge and vertex
        // (outside them is outside the box); 1e-9 is far above rounding, so a ray decides.
        let c = collider(generate::cube(2.0), [4, 5, 3]);
        for eps in [1e-9, 1e-6, 0.3] {
            for i in 0..27 {
                let base = Vec3::new((i % 3) as f64, (i / 3 % 3) as f64, (i / 9) as f64)
                    - Vec3::repeat(1.0);
                let p = Point3::from(base * (1.0 - eps));
                check(&c, &p, Some(true));
                assert!(matches!(decide(&c, &p), Decision::Ray(_, 1)), "{p:?}");
            }
        }
    }

    /// The regular octahedron with vertices at +-1 on the axes, wound outward.
    fn octahedron() -> TriMesh {
        let mut positions = Vec::new();
        for a in 0..3 {
            for s in [1.0, -1.0] {
                let mut v = Vec3::zeros();
                v[a] = s;
                positions.push(Point3::from(v));
            }
        }
        let faces = (0..8u32)
            .map(|k| {
                let [x, y, z] = [k & 1, (k >> 1) & 1, (k >> 2) & 1];
                // An odd number of negative axes reverses the winding.
                if (x + y + z) % 2 == 0 {
                    [x, 2 + y, 4 + z]
                } else {
                    [x, 4 + z, 2 + y]
                }
            })
            .collect();
        TriMesh::new(positions, faces)
    }

    #[test]
    fn octahedron_near_faces_and_edges_on_both_sides() {
        // Inside |x| + |y| + |z| < 1. Face centres and edge midpoints moved along the outward
        // normal by +-eps; vertices moved towards the centre.
        let c = collider(octahedron(), [3, 4, 5]);
        assert!(c.closed);
        for eps in [1e-9, 1e-6, 1e-3] {
            for k in 0..8 {
                let s = Vec3::new(
                    if k & 1 == 0 { 1.0 } else { -1.0 },
                    if k & 2 == 0 { 1.0 } else { -1.0 },
                    if k & 4 == 0 { 1.0 } else { -1.0 },
                );
                let centre = s / 3.0;
                let n = s / 3f64.sqrt();
                for a in 0..3 {
                    let mut mid = s / 2.0;
                    mid[a] = 0.0;
                    let out = mid * 2f64.sqrt();
                    for (q, dir) in [(centre, n), (mid, out)] {
                        check(&c, &Point3::from(q - dir * eps), Some(true));
                        check(&c, &Point3::from(q + dir * eps), Some(false));
                        assert!(matches!(
                            decide(&c, &Point3::from(q + dir * eps)),
                            Decision::Ray(_, 0)
                        ));
                    }
                    let mut v = Vec3::zeros();
                    v[a] = s[a] * (1.0 - eps);
                    check(&c, &Point3::from(v), Some(true));
                }
            }
        }
    }

    #[test]
    fn outside_the_box_is_outside_without_a_ray() {
        let c = collider(generate::cube(2.0), [4, 4, 4]);
        for p in [
            Point3::new(1.0 + 1e-12, 0.0, 0.0),
            Point3::new(0.0, -3.0, 0.0),
            Point3::new(5.0, 5.0, 5.0),
        ] {
            assert_eq!(decide(&c, &p), Decision::OutsideBox);
            check(&c, &p, Some(false));
        }
    }

    #[test]
    fn on_the_surface_the_winding_number_decides() {
        let c = collider(generate::cube(2.0), [4, 4, 4]);
        for p in [
            Point3::new(1.0, 0.2, 0.3),
            Point3::new(0.3, -1.0, 0.1),
            Point3::new(1.0, 1.0, 0.5),
        ] {
            assert!(
                decide(&c, &p) == Decision::Winding,
                "{p:?}: {:?}",
                decide(&c, &p)
            );
            assert_eq!(inside(&c, &p), inside_by_winding(&c, &p));
        }
    }

    /// The point on the line through `v` along the first ray direction of `from` nearest to
    /// `from`: its first ray runs through `v`.
    fn aimed_at(c: &Collider, v: Point3, from: Point3) -> Point3 {
        let d = direction(c.grid(), &from, &TILTS[0]);
        let t = (v - from).dot(&d);
        let p = v - d * t;
        assert!(t > 0.0);
        assert_eq!(direction(c.grid(), &p, &TILTS[0]), d);
        p
    }

    #[test]
    fn a_ray_through_a_vertex_or_an_edge_is_replaced() {
        // The icosphere's vertex farthest along x, and the midpoint of an edge of it, aimed at
        // from points towards the centre.
        let m = generate::icosphere(2);
        let v = (0..m.positions.len())
            .max_by(|&a, &b| m.positions[a].x.abs().total_cmp(&m.positions[b].x.abs()))
            .unwrap();
        let f = m.faces.iter().find(|f| f[0] as usize == v).unwrap();
        let (a, b) = (m.positions[f[0] as usize], m.positions[f[1] as usize]);
        let c = collider(m, [6, 6, 6]);
        for target in [a, Point3::from((a.coords + b.coords) / 2.0)] {
            let p = aimed_at(&c, target, Point3::from(target.coords * 0.3));
            let first = ray_winding(&c, c.grid(), &p, &direction(c.grid(), &p, &TILTS[0]));
            assert_eq!(first, None, "{p:?}");
            assert_eq!(decide(&c, &p), Decision::Ray(1, 1), "{p:?}");
            check(&c, &p, Some(true));
        }
    }

    #[test]
    fn overlapping_shells_count_twice_and_inward_shells_not_at_all() {
        // Two overlapping cubes (closed, every edge twice): 2 where they overlap, as the
        // generalized winding number; one cube turned inside out: -1, outside.
        let mut m = generate::cube(2.0);
        let n = m.positions.len() as u32;
        let second: Vec<Point3> = m.positions.iter().map(|p| p + Vec3::repeat(0.5)).collect();
        m.positions.extend(second);
        m.faces
            .extend(generate::cube(2.0).faces.iter().map(|f| f.map(|v| v + n)));
        let c = collider(m, [5, 5, 5]);
        assert!(c.closed);
        let p = Point3::new(0.7, 0.7, 0.7);
        assert_eq!(decide(&c, &p), Decision::Ray(0, 2));
        check(&c, &p, Some(true));
        let mut inverted = generate::cube(2.0);
        for f in &mut inverted.faces {
            f.swap(1, 2);
        }
        let c = collider(inverted, [3, 3, 3]);
        assert_eq!(decide(&c, &Point3::origin()), Decision::Ray(0, -1));
        check(&c, &Point3::origin(), Some(false));
    }

    #[test]
    fn open_objects_use_the_winding_number() {
        // A cube without its top: the centre is half wrapped (winding number above 1/2).
        let mut m = generate::cube(2.0);
        m.faces.truncate(10);
        let c = collider(m, [4, 4, 4]);
        assert!(!c.closed);
        let p = Point3::new(0.0, 0.0, -0.5);
        assert_eq!(decide(&c, &p), Decision::Winding);
        assert!(winding_number(&c, &p) > 0.5);
        check(&c, &p, Some(true));
    }

    #[test]
    fn the_answer_does_not_depend_on_the_grid() {
        let mut rng = SplitMix(11);
        let points: Vec<Point3> = (0..500)
            .map(|_| Point3::from(random_unit(&mut rng) * (1.2 * rng.next_f64())))
            .collect();
        let answers = |dims| {
            let c = collider(generate::uv_sphere(Point3::origin(), 1.0, 24, 48), dims);
            points.iter().map(|p| inside(&c, p)).collect::<Vec<_>>()
        };
        let one = answers([1, 1, 1]);
        assert_eq!(one, answers([7, 3, 11]));
        assert_eq!(one, answers([40, 40, 40]));
        assert!(one.iter().filter(|&&x| x).count() > 100);
    }
}
