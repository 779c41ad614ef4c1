//! The body meshes in `../shared/realdata/bodies` (GarmentCode's mean bodies, MakeHuman's): closed
//! as read, still closed after `prepare` with the defaults (the weld must not pinch the lips
//! shut), and the fast inside test agrees with the generalized winding number around them.

mod common;
use common::realdata;
use drapekit::collide::Collider;
use drapekit::io::{read_mesh, ReadOptions};
use drapekit::math::{Point3, Vec3};
use drapekit::mesh::diagnose::ShellState;
use drapekit::mesh::orient::solid_angle;
use drapekit::mesh::prepare::{prepare, PrepareOptions, PrepareReport};
use drapekit::mesh::TriMesh;
use drapekit::sim::inside;
use rayon::prelude::*;
use std::path::PathBuf;

const BODIES: [&str; 4] = [
    "mean_all",
    "mean_female",
    "mean_male",
    "makehuman_hm08_body_only_m",
];

fn bodies() -> Option<PathBuf> {
    realdata().map(|r| r.join("bodies"))
}

/// The body as read, prepared with the defaults, and its collider (cells by the `auto` rule, a
/// 2 mm margin, as a drape would build it).
fn load(name: &str) -> Option<(TriMesh, PrepareReport, Collider)> {
    let path = bodies()?.join(format!("{name}.obj"));
    let read = read_mesh(&path, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .mesh;
    let mut mesh = read.clone();
    let report = prepare(&mut mesh, &PrepareOptions::default());
    let dims = Collider::auto_dims(&mesh);
    let c = Collider::new(name.into(), mesh, dims, 0.002, None);
    Some((read, report, c))
}

/// The reference: generalized winding number above 1/2 (what `sim::inside` computed before).
fn inside_by_winding(m: &TriMesh, p: &Point3) -> bool {
    let w: f64 = (0..m.faces.len())
        .map(|f| {
            let [a, b, c] = m.corners(f);
            solid_angle(p, &a, &b, &c)
        })
        .sum();
    w / (4.0 * std::f64::consts::PI) > 0.5
}

/// Points on a 10 x 20 x 8 lattice over the body's box grown by a tenth, and, at 300 faces, 200
/// vertices and 200 edges spread over the body, points 1 mm and 0.1 mm off the surface on both
/// sides (along the face normal, or the sum of the normals around). Returns them with the side
/// each near point is meant to be on.
fn probes(c: &Collider) -> Vec<(Point3, Option<bool>)> {
    let m = &c.mesh;
    let (lo, size) = (c.bbox.min - c.bbox.size() * 0.1, c.bbox.size() * 1.2);
    let mut out = Vec::new();
    for i in 0..10 {
        for j in 0..20 {
            for k in 0..8 {
                let t = Vec3::new(
                    (i as f64 + 0.5) / 10.0,
                    (j as f64 + 0.5) / 20.0,
                    (k as f64 + 0.5) / 8.0,
                );
                out.push((lo + size.component_mul(&t), None));
            }
        }
    }
    let normal = |f: usize| m.face_cross(f).normalize();
    let mut near = |q: Point3, n: Vec3| {
        for d in [1e-3, 1e-4] {
            out.push((q - n * d, Some(true)));
            out.push((q + n * d, Some(false)));
        }
    };
    let nf = m.faces.len();
    for f in (0..nf).step_by(nf / 300) {
        let [a, b, cc] = m.corners(f);
        near(
            Point3::from((a.coords + b.coords + cc.coords) / 3.0),
            normal(f),
        );
    }
    for f in (0..nf).step_by(nf / 200) {
        // The edge from corner 0 to corner 1: its midpoint, along the sum of the normals of the
        // faces on it.
        let [a, b] = [m.faces[f][0], m.faces[f][1]];
        let n: Vec3 = (0..nf)
            .filter(|&g| m.faces[g].contains(&a) && m.faces[g].contains(&b))
            .map(normal)
            .sum();
        let mid = (m.positions[a as usize].coords + m.positions[b as usize].coords) / 2.0;
        near(Point3::from(mid), n.normalize());
        let v = m.faces[f][2];
        let n: Vec3 = (0..nf)
            .filter(|&g| m.faces[g].contains(&v))
            .map(normal)
            .sum();
        near(m.positions[v as usize], n.normalize());
    }
    out
}

#[test]
fn bodies_stay_closed_after_preparation() {
    for name in BODIES {
        let Some((read, r, c)) = load(name) else {
            return;
        };
        assert_eq!(r.after.shell_state, ShellState::Closed, "{name}");
        assert!(c.closed, "{name}: the collider is not closed");
        // Nothing to weld, drop or flip: the mesh comes out as it went in.
        assert_eq!(
            (r.welded_vertices, r.degenerate_faces, r.duplicate_faces),
            (0, 0, 0),
            "{name}"
        );
        assert_eq!(c.mesh, read, "{name}: preparation changed the mesh");
        // The GarmentCode bodies' lips touch: 13 vertex pairs 0 to 0.3 micrometres apart, under
        // the default weld distance (about 2.2 micrometres), kept apart.
        let kept = r.weld.as_ref().map_or(0, |w| w.kept_apart);
        let expected = if name.starts_with("mean_") { 13 } else { 0 };
        assert_eq!(kept, expected, "{name}");
    }
}

#[test]
fn fast_inside_test_agrees_with_the_winding_number() {
    for name in BODIES {
        let Some((_, _, c)) = load(name) else {
            return;
        };
        let points = probes(&c);
        let results: Vec<(bool, bool)> = points
            .par_iter()
            .map(|(p, _)| (inside(&c, p), inside_by_winding(&c.mesh, p)))
            .collect();
        let mut meant = 0;
        for ((p, side), (fast, slow)) in points.iter().zip(&results) {
            assert_eq!(fast, slow, "{name}: at {p:?}");
            meant += usize::from(side.is_none_or(|s| s == *fast));
        }
        // Near points land on their side, except where another part of the body is nearer than
        // 1 mm (the lips, between the fingers).
        assert!(
            meant * 100 >= points.len() * 99,
            "{name}: {meant} of {}",
            points.len()
        );
        let inner = results.iter().filter(|r| r.0).count();
        assert!(inner > points.len() / 4, "{name}: {inner} inside");
    }
}
