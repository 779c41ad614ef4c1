//! Analytic meshes for tests, benchmarks and scenes: a cube, a box, a subdivided icosphere,
//! a UV sphere, a solid of revolution (`lathe`). All are closed and wound outward.

use super::TriMesh;
use crate::math::{Point3, Vec3};
use std::collections::HashMap;

/// An axis-aligned cube of edge `size` centred on the origin: 8 vertices, 12 faces.
pub fn cube(size: f64) -> TriMesh {
    boxed(Vec3::new(size, size, size))
}

/// An axis-aligned box with edge lengths `size`, centred on the origin.
pub fn boxed(size: Vec3) -> TriMesh {
    let h = size / 2.0;
    let positions = (0..8)
        .map(|i| {
            Point3::new(
                if i & 1 == 0 { -h.x } else { h.x },
                if i & 2 == 0 { -h.y } else { h.y },
                if i & 4 == 0 { -h.z } else { h.z },
            )
        })
        .collect();
    let quads = [
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
    ];
    let faces = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[2], q[3], q[0]]])
        .collect();
    TriMesh::new(positions, faces)
}

/// A unit-radius icosphere: the icosahedron subdivided `level` times (each face into four),
/// vertices projected on the sphere. `20 * 4^level` faces, `10 * 4^level + 2` vertices.
///
/// ```
/// let s = drapekit::mesh::generate::icosphere(2);
/// assert_eq!((s.faces.len(), s.positions.len()), (320, 162));
/// ```
pub fn icosphere(level: u32) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<Point3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Point3::from(Vec3::new(x, y, z).normalize()))
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::with_capacity(faces.len() * 3 / 2);
        let mut next = Vec::with_capacity(faces.len() * 4);
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Point3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                let m = (positions[a as usize].coords + positions[b as usize].coords).normalize();
                positions.push(Point3::from(m));
                (positions.len() - 1) as u32
            })
        };
        for &[a, b, c] in &faces {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    TriMesh::new(positions, faces)
}

/// A closed solid of revolution about the z axis: for each `(z, r)` of `profile` (z rising), a
/// ring of `sides` vertices of radius `r` at height `z`, joined ring to ring, and capped. Its
/// section at a ring's height is that `sides`-gon, of perimeter `2 sides r sin(pi / sides)`.
///
/// ```
/// let m = drapekit::mesh::generate::lathe(&[(0.0, 1.0), (1.0, 0.5), (2.0, 1.0)], 16);
/// assert_eq!((m.positions.len(), m.faces.len()), (3 * 16 + 2, 2 * 2 * 16 + 2 * 16));
/// // A cylinder of radius 1 and height 2 as 64-gons: volume 2 x 32 sin(2 pi / 64), outward.
/// let c = drapekit::mesh::generate::lathe(&[(0.0, 1.0), (2.0, 1.0)], 64);
/// let v = 2.0 * 32.0 * (std::f64::consts::TAU / 64.0).sin();
/// assert!((c.signed_volume() - v).abs() < 1e-12);
/// ```
pub fn lathe(profile: &[(f64, f64)], sides: usize) -> TriMesh {
    assert!(profile.len() >= 2 && sides >= 3);
    let n = sides as u32;
    let mut positions = Vec::new();
    for &(z, r) in profile {
        for k in 0..sides {
            let a = std::f64::consts::TAU * k as f64 / sides as f64;
            positions.push(Point3::new(r * a.cos(), r * a.sin(), z));
        }
    }
    let mut faces = Vec::new();
    for i in 0..profile.len() as u32 - 1 {
        for k in 0..n {
            let (a, b) = (i * n + k, i * n + (k + 1) % n);
            faces.push([a, b, b + n]);
            faces.push([a, b + n, a + n]);
        }
    }
    let (bottom, top) = (positions.len() as u32, positions.len() as u32 + 1);
    let (z0, z1) = (profile[0].0, profile[profile.len() - 1].0);
    positions.push(Point3::new(0.0, 0.0, z0));
    positions.push(Point3::new(0.0, 0.0, z1));
    let last = (profile.len() as u32 - 1) * n;
    for k in 0..n {
        faces.push([bottom, (k + 1) % n, k]);
        faces.push([top, last + k, last + (k + 1) % n]);
    }
    TriMesh::new(positions, faces)
}

/// A UV sphere of radius `radius` about `center`: `rings` latitude bands, `segments` longitudes.
pub fn uv_sphere(center: Point3, radius: f64, rings: usize, segments: usize) -> TriMesh {
    assert!(rings >= 2 && segments >= 3);
    let mut positions = vec![center + Vec3::new(0.0, 0.0, radius)];
    for r in 1..rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..segments {
            let phi = 2.0 * std::f64::consts::PI * s as f64 / segments as f64;
            positions.push(
                center
                    + radius
                        * Vec3::new(
                            theta.sin() * phi.cos(),
                            theta.sin() * phi.sin(),
                            theta.cos(),
                        ),
            );
        }
    }
    positions.push(center + Vec3::new(0.0, 0.0, -radius));
    let south = (positions.len() - 1) as u32;
    let ring = |r: usize, s: usize| (1 + (r - 1) * segments + s % segments) as u32;
    let mut faces = Vec::new();
    for s in 0..segments {
        faces.push([0, ring(1, s), ring(1, s + 1)]);
        faces.push([south, ring(rings - 1, s + 1), ring(rings - 1, s)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (
                ring(r, s),
                ring(r + 1, s),
                ring(r + 1, s + 1),
                ring(r, s + 1),
            );
            faces.push([a, b, c]);
            faces.push([c, d, a]);
        }
    }
    TriMesh::new(positions, faces)
}
