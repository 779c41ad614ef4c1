//! Hinge bending over one edge (Bergou, Wardetzky, Harmon, Zorin and Grinspun 2006, *A
//! quadratic bending model for inextensible surfaces*), as a [`Bend`] element.
//!
//! For an edge `x0 x1` between the triangles `x0 x1 x2` and `x1 x0 x3` of a flat piece, with
//! `e0 = x1 - x0`, `e1 = x2 - x0`, `e2 = x3 - x0`, `e3 = x2 - x1`, `e4 = x3 - x1` and `c_jk` the
//! cotangent of the angle between `e_j` and `e_k` (`-e0` for `c03` and `c04`: the angles at
//! `x1`), the weights are
//!
//! ```text
//! K = (c03 + c04, c01 + c02, -c01 - c03, -c02 - c04)
//! ```
//!
//! and the energy `(3 B / (A0 + A1)) |sum_i K_i x_i|^2 / 2`, `A0`, `A1` the triangles' rest
//! areas, `B` the bending rigidity. The weights sum to zero and `sum K_i x_i` vanishes on the
//! flat piece (it is the cotangent Laplacian of the hinge, zero on any linear map); folded
//! isometrically by a small dihedral angle `theta`, `|sum K_i x_i| = |e0| theta` to first order,
//! so the energy is `3 B |e0|^2 theta^2 / (2 (A0 + A1))`, the discrete mean curvature squared
//! over the hinge's third of the two triangles.
//!
//! [`rim_hinges`] puts one on every interior edge of a piece that has an outline particle among
//! its four nodes: the particles on the outline get no over-one-node element (`cloth::pattern`),
//! so the band along a piece's rim would otherwise fold freely there.

use super::Bend;
use crate::math::{Point2, Vec2};
use std::collections::HashMap;

/// Cotangent weights above this mark a sliver triangle: its hinges are left out.
pub const MAX_COT: f64 = 1e3;

fn cot(u: Vec2, v: Vec2) -> f64 {
    u.dot(&v) / (u.x * v.y - u.y * v.x).abs()
}

/// The hinge over edge `p[0] p[1]` with opposite corners `p[2]` and `p[3]` (flat, m) for nodes
/// `nodes` and rigidity `b` (N m); `None` for a sliver or a degenerate pair of triangles.
///
/// ```
/// use drapekit::cloth::elements::hinge::hinge;
/// use drapekit::math::Point2;
/// // Two right triangles on the unit square's diagonal-free edge x0 = (0,0), x1 = (1,0).
/// let p = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, -1.0)].map(|(x, y)| Point2::new(x, y));
/// let h = hinge([0, 1, 2, 3], &p, 1e-5).unwrap();
/// assert_eq!(h.weights, vec![1.0, 1.0, -1.0, -1.0]);
/// assert!((h.c - 3e-5).abs() < 1e-18); // 3 B / (1/2 + 1/2)
/// ```
pub fn hinge(nodes: [u32; 4], p: &[Point2; 4], b: f64) -> Option<Bend> {
    let (e0, e1, e2) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
    let (e3, e4) = (p[2] - p[1], p[3] - p[1]);
    let (c01, c02, c03, c04) = (cot(e0, e1), cot(e0, e2), cot(-e0, e3), cot(-e0, e4));
    let weights = vec![c03 + c04, c01 + c02, -c01 - c03, -c02 - c04];
    let area = 0.5 * ((e0.x * e1.y - e0.y * e1.x).abs() + (e0.x * e2.y - e0.y * e2.x).abs());
    if weights.iter().any(|w| !w.is_finite() || w.abs() > MAX_COT) || area <= 0.0 {
        return None;
    }
    Some(Bend {
        nodes: nodes.to_vec(),
        weights,
        c: 3.0 * b / area,
    })
}

/// Hinges of rigidity `b` over every edge of `triangles` (over `flat`) shared by two triangles
/// and with a particle at or after `outline_from` (the outline's) among its four nodes, in the
/// order of their edges' lowest and highest node.
pub fn rim_hinges(
    flat: &[Point2],
    triangles: &[[u32; 3]],
    outline_from: usize,
    b: f64,
) -> Vec<Bend> {
    let mut opposite: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for t in triangles {
        for e in 0..3 {
            let (a, c, o) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
            opposite.entry((a.min(c), a.max(c))).or_default().push(o);
        }
    }
    let mut edges: Vec<((u32, u32), Vec<u32>)> = opposite.into_iter().collect();
    edges.sort_unstable_by_key(|e| e.0);
    edges
        .into_iter()
        .filter_map(|((a, c), o)| {
            let nodes = [a, c, *o.first()?, *o.get(1)?];
            let rim = nodes.iter().any(|&v| v as usize >= outline_from);
            (o.len() == 2 && rim).then(|| hinge(nodes, &nodes.map(|v| flat[v as usize]), b))?
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::elements::bend;
    use crate::math::{Point3, Vec3};

    /// An irregular pair of triangles on edge (0,0)-(0.012,0.001).
    fn pair() -> [Point2; 4] {
        [(0.0, 0.0), (0.012, 0.001), (0.004, 0.009), (0.007, -0.011)]
            .map(|(x, y)| Point2::new(x, y))
    }

    #[test]
    fn a_flat_or_moved_hinge_stores_nothing_and_a_fold_stores_the_mean_curvature() {
        let p = pair();
        let h = hinge([0, 1, 2, 3], &p, 2e-5).unwrap();
        assert!(h.weights.iter().sum::<f64>().abs() < 1e-12);
        let flat: Vec<Point3> = p.iter().map(|q| Point3::new(q.x, q.y, 0.0)).collect();
        assert!(bend::vector(&h.nodes, &h.weights, &flat).norm() < 1e-15);
        // A rigid motion.
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        let moved: Vec<Point3> = flat
            .iter()
            .map(|q| r * q + Vec3::new(1.0, 2.0, 3.0))
            .collect();
        assert!(bend::vector(&h.nodes, &h.weights, &moved).norm() < 1e-14);
        // Folded about the edge by theta: triangle 1's corner x3 turned out of the plane.
        let e = (p[1] - p[0]).normalize();
        let axis = nalgebra::Unit::new_normalize(Vec3::new(e.x, e.y, 0.0));
        for theta in [1e-3, 1e-2] {
            let turn = nalgebra::Rotation3::from_axis_angle(&axis, theta);
            let mut x = flat.clone();
            x[3] = Point3::from(turn * x[3].coords);
            let b = bend::vector(&h.nodes, &h.weights, &x).norm();
            let e0 = (p[1] - p[0]).norm();
            assert!(
                (b / (e0 * theta) - 1.0).abs() < theta,
                "{theta}: {b} {}",
                e0 * theta
            );
        }
    }

    #[test]
    fn rim_hinges_cover_the_interior_edges_that_touch_the_outline() {
        // A square of four triangles round a centre (node 4, the only inner particle): its
        // four spokes are interior edges, the rim's four edges have one triangle each.
        let flat = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.5, 0.5)]
            .map(|(x, y)| Point2::new(x, y));
        let tris = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        // Node 4 is the grid (index 0 after reordering is simpler: outline from 0 counts all).
        let all = rim_hinges(&flat, &tris, 0, 1e-5);
        assert_eq!(all.len(), 4);
        let spokes: Vec<(u32, u32)> = all.iter().map(|h| (h.nodes[0], h.nodes[1])).collect();
        assert_eq!(spokes, [(0, 4), (1, 4), (2, 4), (3, 4)]);
        // No particle at or after 5 is on the outline: no hinge.
        assert!(rim_hinges(&flat, &tris, 5, 1e-5).is_empty());
        // Edge 0-1 whose only outline particle (3) is an opposite corner: all four nodes
        // count, so it has a hinge (hinges only over edges ending on the outline were tried
        // and not kept: `docs/notebook-garments.md`, 2026-12-06).
        let pair =
            [(0.0, 0.0), (1.0, 0.0), (0.5, 0.8), (0.5, -0.8)].map(|(x, y)| Point2::new(x, y));
        let tris = [[0, 1, 2], [1, 0, 3]];
        assert_eq!(rim_hinges(&pair, &tris, 3, 1e-5).len(), 1);
        assert!(rim_hinges(&pair, &tris, 4, 1e-5).is_empty());
    }
}
