//! The body's vertices against the cloth's triangles: sharp features of a body (an ear, a
//! shoulder joint, a finger) poke through a cloth whose particles all rest outside it, because
//! the particle pass (`contact`) keeps particles off the body, not the cloth between them.
//!
//! For each convex body vertex `v` (no edge from it rises in front of its tangent plane by
//! more than [`CONVEX_TOL`] of its length: a saddle or a hollow, the armpit, holds no tip) with
//! `n_v` the body's outward normal there (the area-weighted mean of its faces' normals), and
//! each cloth triangle `t = abc` whose box (grown by [`reach`])
//! holds it: with `n` the unit normal of `t` turned to `v`'s outside (`n . n_v > 0`; a triangle
//! within [`MIN_FACING`] of edge-on is skipped: which side is out is not clear), `(α, β, γ)`
//! the barycentric coordinates of `v`'s projection on `t`'s plane (all `>= -FACE_TOL`),
//! `q = α a + β b + γ c` and `d = n . (v - q)`, `v` has poked through `t` when
//!
//! * `0 < d <= MAX_DEPTH (c + e)`: `v` is beyond `t` on its own outside, but not far (`c` the
//!   distance the cloth keeps from the body, the particles' thickness plus the body's
//!   clearance; `e` the cloth's mean edge length: a body part further beyond is a layer of the
//!   body the cloth lies under, not a tip through it), and
//! * a body edge at `v` properly crosses `t` (the body's surface passes through the cloth
//!   there: the vertices of an ear's back face lie beyond a cloth over its front by their own
//!   normals, but nothing of the ear crosses that cloth).
//!
//! The triangle then moves along `n` towards `c` past the tip (the body does not move), by
//! `s = min(d + c, MAX_PUSH e)` at once (capped, it stops where the tip no longer pokes
//! through, touching it; the particle pass keeps the clearance at its corners): `Δa = w_a α λ n` (and `b`, `c` alike) with
//! `λ = s / (w_a α² + w_b β² + w_c γ²)`, `w` the inverse masses (0 for a pin), which moves `q`
//! by `s` along `n`; the corners' velocities lose their part towards the body (`n . u < 0`).
//! (A whole push at once, `d + c` up to an edge length, stretched the armholes of a hoody over
//! the shoulders to 32%; the solver spreads a tenth of an edge per step over the cloth.)
//!
//! *Several objects:* a vertex buried in another object of the scene is no tip
//! ([`BodyPoints::without_buried`]): `v + c n_v` (one contact distance out along its normal)
//! inside another object means the cloth cannot pass the vertex on that side. An ear modelled
//! as its own mesh sunk into the head: its base corners point into the head, and they would
//! push the cloth down through it while the apex pushes it up.
//!
//! *Limit:* a body part thinner than the reach `MAX_DEPTH (c + e)` can be taken for a tip from
//! both sides (a pyramid 4.7 cm high under a 5 cm cloth triangle: its apex pushes the cloth
//! up, its base corners down); at 1 cm cloth that is a part under 1.2 cm thick crossing the
//! cloth, an ear's rim at worst.
//!
//! Pairs are found at the positions after the particle pass, in parallel over fixed chunks of
//! the body's vertices, then corrected one after the other in vertex order, each evaluated
//! again at the positions its predecessors left (Gauss-Seidel): the same bits for any thread
//! count.

use super::cloth::{segment_crosses_triangle, ClothHash};
use super::inside::inside;
use super::Collider;
use crate::math::{Aabb, Point3, Vec3};
use crate::par;
use rayon::prelude::*;

/// A triangle closer to edge-on than this (`|n . n_v|`) is left alone.
pub const MIN_FACING: f64 = 0.3;

/// How far beyond a cloth triangle a body vertex may be and still count as a tip through it,
/// in units of the contact distance plus the cloth's mean edge length.
pub const MAX_DEPTH: f64 = 1.0;

/// The most a triangle moves at once, in units of the cloth's mean edge length.
pub const MAX_PUSH: f64 = 0.1;

/// A vertex is convex when no edge from it rises in front of its tangent plane by more than
/// this fraction of the edge's length.
pub const CONVEX_TOL: f64 = 1e-3;

/// Barycentric slack of "projects inside the triangle".
const FACE_TOL: f64 = 1e-9;

/// Body vertices per chunk of the parallel search.
const CHUNK: usize = 4096;

/// What the pass needs of a body, built once: its vertices' outward unit normals
/// (area-weighted; zero where undefined) and their neighbours along the faces' edges.
#[derive(Debug, Clone)]
pub struct BodyPoints {
    /// Per vertex, its unit normal; zero where undefined or where the surface is not convex
    /// (those vertices are left out).
    pub normals: Vec<Vec3>,
    start: Vec<u32>,
    next: Vec<u32>,
}

impl BodyPoints {
    /// The normals and neighbours of `c`'s mesh.
    pub fn new(c: &Collider) -> BodyPoints {
        let m = &c.mesh;
        let mut n = vec![Vec3::zeros(); m.positions.len()];
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(m.faces.len() * 6);
        for (f, tri) in m.faces.iter().enumerate() {
            let a = m.face_cross(f);
            for k in 0..3 {
                n[tri[k] as usize] += a;
                pairs.push((tri[k], tri[(k + 1) % 3]));
                pairs.push((tri[(k + 1) % 3], tri[k]));
            }
        }
        for v in &mut n {
            let l = v.norm();
            *v = if l > 0.0 { *v / l } else { Vec3::zeros() };
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut start = vec![0u32; n.len() + 1];
        for &(a, _) in &pairs {
            start[a as usize + 1] += 1;
        }
        for i in 0..n.len() {
            start[i + 1] += start[i];
        }
        let next: Vec<u32> = pairs.into_iter().map(|(_, b)| b).collect();
        // Only convex vertices poke through: none of their neighbours lies in front of their
        // tangent plane (a saddle or a hollow, the armpit, is left to the particle pass).
        for (i, nv) in n.iter_mut().enumerate() {
            let p = m.positions[i];
            let around = &next[start[i] as usize..start[i + 1] as usize];
            if around.iter().any(|&u| {
                let e = m.positions[u as usize] - p;
                nv.dot(&e) > CONVEX_TOL * e.norm()
            }) {
                *nv = Vec3::zeros();
            }
        }
        BodyPoints {
            normals: n,
            start,
            next,
        }
    }

    /// `self` without the tips buried in another object of the scene: a vertex `v` of `c` whose
    /// probe point `v + probe n_v` lies inside one of `others` is no tip (the cloth cannot be
    /// pushed past it into that object). An ear sunk into a head made of another mesh, a body
    /// pressed into a seat: the base corners of the ear point into the head, and a cloth cut by
    /// the ear would otherwise be pushed down through the head by them and up by the apex.
    pub fn without_buried(mut self, c: &Collider, others: &[&Collider], probe: f64) -> Self {
        for (p, nv) in c.mesh.positions.iter().zip(&mut self.normals) {
            if *nv != Vec3::zeros() && others.iter().any(|o| inside(o, &(p + *nv * probe))) {
                *nv = Vec3::zeros();
            }
        }
        self
    }

    /// The neighbours of vertex `i`.
    fn around(&self, i: usize) -> &[u32] {
        &self.next[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// The cloth of a pass: triangles, per-particle thickness and inverse mass, the body's
/// clearance.
pub struct Cloth<'a> {
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
    /// Per particle, its thickness, m.
    pub thickness: &'a [f64],
    /// The largest thickness, m.
    pub thickness_max: f64,
    /// The body's clearance, m (kept on top of the thickness).
    pub clearance: f64,
    /// Per particle, 1 / mass (0: pinned).
    pub inv_mass: &'a [f64],
    /// The cloth's mean edge length, m.
    pub edge: f64,
}

/// What a pass did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Pushed {
    /// Tips found through a triangle.
    pub pairs: usize,
    /// Pairs corrected (still through when their turn came).
    pub corrected: usize,
}

/// How far a triangle's box must be grown for the pass to find every tip through it, m.
pub fn reach(distance: f64, edge: f64) -> f64 {
    MAX_DEPTH * (distance + edge)
}

/// One pass of `collider`'s vertices (`points`, built from it) against the cloth at `x`, `hash`
/// built over the cloth's triangles at `x` with boxes grown by at least [`reach`] of the
/// largest contact distance.
pub fn push_cloth(
    collider: &Collider,
    points: &BodyPoints,
    cloth: &Cloth,
    hash: &ClothHash,
    x: &mut [Point3],
    v: &mut [Vec3],
) -> Pushed {
    let body = &collider.mesh.positions;
    let xs: &[Point3] = x;
    // Only the body's vertices within the hash's reach of the cloth can be in a box.
    let Some(near) = Aabb::of_points(xs) else {
        return Pushed::default();
    };
    let grow = reach(cloth.thickness_max + cloth.clearance, cloth.edge);
    let search = |r: std::ops::Range<usize>| {
        let mut out = Vec::new();
        for i in r {
            if points.normals[i] == Vec3::zeros() || !near.contains(&body[i], grow) {
                continue;
            }
            hash.for_point(&body[i], |t| {
                if through(cloth, xs, t, body, points, i).is_some() {
                    out.push((i as u32, t));
                }
            });
        }
        out
    };
    let chunks = body.len().div_ceil(CHUNK);
    let part = |k: usize| search(k * CHUNK..((k + 1) * CHUNK).min(body.len()));
    let found: Vec<Vec<(u32, u32)>> = if par::parallel(body.len()) {
        (0..chunks).into_par_iter().map(part).collect()
    } else {
        (0..chunks).map(part).collect()
    };
    let mut done = Pushed::default();
    for (i, t) in found.into_iter().flatten() {
        done.pairs += 1;
        if let Some((push, w, n)) = through(cloth, x, t, body, points, i as usize) {
            correct(cloth, t, push, w, &n, x, v);
            done.corrected += 1;
        }
    }
    done
}

/// `(push, barycentrics, n)` when body vertex `i` has poked through cloth triangle `t`.
fn through(
    cloth: &Cloth,
    x: &[Point3],
    t: u32,
    body: &[Point3],
    points: &BodyPoints,
    i: usize,
) -> Option<(f64, [f64; 3], Vec3)> {
    let (p, nv) = (&body[i], &points.normals[i]);
    let tri = cloth.triangles[t as usize];
    let [a, b, c] = tri.map(|k| x[k as usize]);
    let cross = (b - a).cross(&(c - a));
    let area2 = cross.norm_squared();
    if area2 == 0.0 {
        return None;
    }
    let mut n = cross / area2.sqrt();
    let facing = n.dot(nv);
    if facing.abs() < MIN_FACING {
        return None;
    }
    if facing < 0.0 {
        n = -n;
    }
    let ap = p - a;
    let beta = ap.cross(&(c - a)).dot(&cross) / area2;
    let gamma = (b - a).cross(&ap).dot(&cross) / area2;
    let w = [1.0 - beta - gamma, beta, gamma];
    if w.iter().any(|&u| u < -FACE_TOL) {
        return None;
    }
    let dist = tri
        .iter()
        .map(|&k| cloth.thickness[k as usize])
        .sum::<f64>()
        / 3.0
        + cloth.clearance;
    let d = n.dot(&(p - (a + (b - a) * beta + (c - a) * gamma)));
    if !(d > 0.0 && d <= reach(dist, cloth.edge)) {
        return None;
    }
    let crossed = (points.around(i).iter())
        .any(|&u| segment_crosses_triangle(p, &body[u as usize], &a, &b, &c));
    crossed.then_some(((d + dist).min(MAX_PUSH * cloth.edge), w, n))
}

/// Moves triangle `t` along `n` by `push` at its barycentric point `w`, by inverse mass.
fn correct(
    cloth: &Cloth,
    t: u32,
    push: f64,
    w: [f64; 3],
    n: &Vec3,
    x: &mut [Point3],
    v: &mut [Vec3],
) {
    let tri = cloth.triangles[t as usize];
    let im = tri.map(|k| cloth.inv_mass[k as usize]);
    let denom: f64 = (0..3).map(|j| im[j] * w[j] * w[j]).sum();
    if denom <= 0.0 {
        return;
    }
    let lambda = push / denom;
    for j in 0..3 {
        let k = tri[j] as usize;
        x[k] += n * (im[j] * w[j] * lambda);
        if im[j] > 0.0 && w[j] > 0.0 {
            let un = n.dot(&v[k]);
            if un < 0.0 {
                v[k] -= n * un;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;

    /// A steep pyramid (base 4 cm square at z = 0, apex at z = 0.05 m) and one cloth triangle
    /// lying flat at height `z`, much larger than the pyramid's top.
    fn setup(z: f64) -> (Collider, Vec<Point3>, Vec<[u32; 3]>) {
        let s = 0.02;
        let positions = vec![
            Point3::new(-s, -s, 0.0),
            Point3::new(s, -s, 0.0),
            Point3::new(s, s, 0.0),
            Point3::new(-s, s, 0.0),
            Point3::new(0.0, 0.0, 0.05),
        ];
        let faces = vec![
            [0, 1, 4],
            [1, 2, 4],
            [2, 3, 4],
            [3, 0, 4],
            [0, 2, 1],
            [0, 3, 2],
        ];
        let mesh = TriMesh::new(positions, faces);
        let body = Collider::new("pyramid".into(), mesh, [4, 4, 4], 0.001, None);
        let x = vec![
            Point3::new(-0.05, -0.05, z),
            Point3::new(0.05, -0.05, z),
            Point3::new(0.0, 0.08, z),
        ];
        (body, x, vec![[0, 1, 2]])
    }

    /// One pass over the triangle at `x` (contact distance 1 mm, mean edge `edge`).
    fn pass_with(
        body: &Collider,
        x: &mut [Point3],
        v: &mut [Vec3],
        tris: &[[u32; 3]],
        edge: f64,
    ) -> Pushed {
        let points = BodyPoints::new(body);
        let (dist, inv) = (vec![0.001; 3], vec![1.0; 3]);
        let cloth = Cloth {
            triangles: tris,
            thickness: &dist,
            thickness_max: 0.001,
            clearance: 0.0,
            inv_mass: &inv,
            edge,
        };
        let mut hash = ClothHash::new(3, tris, &[]);
        hash.rebuild(x, tris, 0.05, reach(0.001, edge));
        push_cloth(body, &points, &cloth, &hash, x, v)
    }

    /// [`pass_with`] a 1 cm edge (pushes of at most 1 mm at once).
    fn pass(body: &Collider, x: &mut [Point3], v: &mut [Vec3], tris: &[[u32; 3]]) -> Pushed {
        pass_with(body, x, v, tris, 0.01)
    }

    #[test]
    fn a_tip_through_the_cloth_lifts_it_to_the_contact_distance_past_the_tip() {
        // The apex pokes 3 mm through the triangle.
        let (body, mut x, tris) = setup(0.047);
        let points = BodyPoints::new(&body);
        // The apex's normal is straight up (its four faces are symmetric).
        assert!((points.normals[4] - Vec3::z()).norm() < 1e-12);
        let mut v = vec![Vec3::new(0.0, 0.0, -1.0); 3];
        // A 4 cm edge: the 4 mm push at once (at most 4 mm; the base's corners are further
        // below the cloth than 1 mm + 4 cm).
        let done = pass_with(&body, &mut x, &mut v, &tris, 0.04);
        assert_eq!(
            done,
            Pushed {
                pairs: 1,
                corrected: 1
            }
        );
        // The triangle's point over the apex is now the contact distance above it: the
        // corners moved up by 4 mm times their weight over the sum of the squared weights.
        // The corners moved straight up, so the apex's barycentric coordinates in the
        // triangle are those of (0, 0) in its flat outline: (4, 4, 5) / 13.
        let w = [4.0 / 13.0, 4.0 / 13.0, 5.0 / 13.0];
        let height: f64 = (0..3).map(|k| w[k] * x[k].z).sum();
        assert!((height - 0.051).abs() < 1e-12, "{height}");
        assert!(x.iter().all(|p| p.z > 0.047 && p.x.abs() <= 0.05));
        // No corner approaches the body any more.
        assert!(v.iter().all(|u| u.z == 0.0), "{v:?}");
        // A second pass finds nothing through.
        assert_eq!(pass_with(&body, &mut x, &mut v, &tris, 0.04).pairs, 0);
    }

    #[test]
    fn a_push_is_at_most_a_tenth_of_the_edge_at_once() {
        // 3 mm through with a 1 cm edge: 1 mm a pass; after three the cloth touches the tip,
        // which no longer pokes through it.
        let (body, mut x, tris) = setup(0.047);
        let mut v = vec![Vec3::zeros(); 3];
        let w = [4.0 / 13.0, 4.0 / 13.0, 5.0 / 13.0];
        for k in 1..=3 {
            assert_eq!(pass(&body, &mut x, &mut v, &tris).corrected, 1, "pass {k}");
            // Tilted by the first push, the triangle's later pushes move its corners a little
            // sideways too: the apex's barycentric coordinates drift by parts in 1e6.
            let height: f64 = (0..3).map(|j| w[j] * x[j].z).sum();
            assert!((height - 0.047 - 0.001 * k as f64).abs() < 1e-7, "{height}");
        }
        assert_eq!(pass(&body, &mut x, &mut v, &tris).pairs, 0);
    }

    #[test]
    fn a_triangle_over_the_tip_far_below_it_or_edge_on_is_left_alone() {
        let mut v = vec![Vec3::zeros(); 3];
        // 2 mm above the apex: nothing pokes through.
        let (body, mut x, tris) = setup(0.052);
        assert_eq!(pass(&body, &mut x, &mut v, &tris).pairs, 0);
        // 2 cm below it: deeper than MAX_DEPTH (1 mm + 1 cm) of body beyond the cloth.
        let (body, mut x, tris) = setup(0.03);
        let before = x.clone();
        assert_eq!(pass(&body, &mut x, &mut v, &tris).pairs, 0);
        assert_eq!(x, before);
        // Edge-on: the triangle stood up through the apex.
        let mut x = vec![
            Point3::new(-0.05, 0.0, 0.0),
            Point3::new(0.05, 0.0, 0.0),
            Point3::new(0.0, 0.0, 0.1),
        ];
        assert_eq!(pass(&body, &mut x, &mut v, &tris).pairs, 0);
    }

    /// The cloth of `tris` with a 1 mm thickness `dist`, inverse masses `inv` and a 4 cm edge.
    fn cloth_04<'a>(tris: &'a [[u32; 3]], dist: &'a [f64], inv: &'a [f64]) -> Cloth<'a> {
        Cloth {
            triangles: tris,
            thickness: dist,
            thickness_max: 0.001,
            clearance: 0.0,
            inv_mass: inv,
            edge: 0.04,
        }
    }

    #[test]
    fn a_pinned_corner_stays_and_the_others_take_the_push() {
        let (body, mut x, tris) = setup(0.047);
        let points = BodyPoints::new(&body);
        let (dist, inv) = (vec![0.001; 3], vec![0.0, 1.0, 1.0]);
        let cloth = cloth_04(&tris, &dist, &inv);
        let mut hash = ClothHash::new(3, &tris, &[]);
        hash.rebuild(&x, &tris, 0.05, reach(0.001, 0.04));
        let a0 = x[0];
        let mut v = vec![Vec3::zeros(); 3];
        let done = push_cloth(&body, &points, &cloth, &hash, &mut x, &mut v);
        assert_eq!(done.corrected, 1);
        assert_eq!(x[0], a0);
        // The plane through the corners now passes 1 mm above the apex (tilted).
        let n = (x[1] - x[0]).cross(&(x[2] - x[0])).normalize();
        let over = n.dot(&(x[0] - Point3::new(0.0, 0.0, 0.05)));
        assert!(over > 0.0009, "{over}");
    }

    #[test]
    fn a_pyramid_sunk_in_a_slab_pushes_the_cloth_only_up() {
        // The pyramid's base 1 mm into a 10 cm slab below it; the triangle cuts the pyramid
        // 3 cm up. Alone, the base corners 0 and 2 (their normals point down: each lies in both
        // base faces) are tips through it as well as the apex, and the corners come first: the
        // triangle goes down twice (4 mm at each corner's point) and up once. Beside the slab they are buried.
        let (body, x0, tris) = setup(0.03);
        let mut slab = crate::mesh::generate::boxed(Vec3::new(0.2, 0.2, 0.1));
        for p in &mut slab.positions {
            p.z += 0.001 - 0.05;
        }
        let slab = Collider::new("slab".into(), slab, [4, 4, 4], 0.001, None);
        let alone = BodyPoints::new(&body);
        let beside = BodyPoints::new(&body).without_buried(&body, &[&slab], 0.001);
        assert_eq!(beside.normals[4], alone.normals[4]);
        for i in 0..4 {
            assert!(alone.normals[i] != Vec3::zeros());
            assert_eq!(beside.normals[i], Vec3::zeros(), "corner {i}");
        }
        let (dist, inv) = (vec![0.001; 3], vec![1.0; 3]);
        let cloth = cloth_04(&tris, &dist, &inv);
        let mut hash = ClothHash::new(3, &tris, &[]);
        hash.rebuild(&x0, &tris, 0.05, reach(0.001, 0.04));
        let run = |points: &BodyPoints| {
            let (mut x, mut v) = (x0.clone(), vec![Vec3::zeros(); 3]);
            let done = push_cloth(&body, points, &cloth, &hash, &mut x, &mut v);
            let w = [4.0 / 13.0, 4.0 / 13.0, 5.0 / 13.0];
            (done.corrected, (0..3).map(|k| w[k] * x[k].z).sum::<f64>())
        };
        let (n, z) = run(&alone);
        assert_eq!(n, 3);
        assert!(z < 0.03, "{z}: net down, towards the slab");
        let (n, z) = run(&beside);
        assert_eq!(n, 1);
        assert!((z - 0.034).abs() < 1e-9, "{z}");
    }
}
