//! How the garment's rings hang after the drape: every ring the fit check finds (a hem, a
//! neckline, an armhole, a waist seam; [`super::fit_check`]) measured on the particles of its
//! edges, so that a drape's shape can be checked with numbers.
//!
//! A ring's **length** is the polyline through each of its edges' particles, from the edge's
//! start to its end, summed over the ring's edges (a stitch by its shorter side, as the fit
//! check measures it); `rest_length_m` is the same polyline on the panels as placed, which
//! are flat: the sampled outline's length. `length_m / rest_length_m - 1` is the ring's mean
//! strain along itself (a ring stretched round the body is longer than its rest; a gathered
//! or crumpled one shorter).
//!
//! Its **heights** are over those particles (each once): `height_m = [lowest, highest]`,
//! `height_mean_m`, and `rise_m`, the mean's change from the placed panels' mean. A level hem
//! has `highest - lowest` near 0; a garment placed below where it hangs rises (GarmentCode
//! places a top's panels below the shoulders: the seams over the shoulders lift them).
//! Heights are the simulation's `z`, m (above the floor for `drapekit garment`).
//!
//! Two drapes of one pattern (at two resolutions, or from two perturbed starts) are compared
//! ring by ring ([`compare`]): the largest difference of a ring's mean height and of its
//! strain along itself, each against its own rest (`bench garment --spacing` measures what a
//! coarser cloth costs in shape this way).

use super::fit_check::{ring_edges, RingKind};
use super::spec::Pattern;
use crate::math::Point3;
use serde::Serialize;

/// One ring after the drape.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RingHang {
    /// Seam or opening.
    pub kind: RingKind,
    /// Its edges, as the fit check names them.
    pub edges: Vec<String>,
    /// Its length along its particles after the drape, m.
    pub length_m: f64,
    /// The same on the flat panels as placed, m.
    pub rest_length_m: f64,
    /// Its lowest and highest particle after the drape, m.
    pub height_m: [f64; 2],
    /// Its particles' mean height after the drape, m.
    pub height_mean_m: f64,
    /// How far that mean rose from where the pattern placed it, m (negative: it fell).
    pub rise_m: f64,
}

/// The length of the polyline through `path` at `x`.
fn polyline(x: &[Point3], path: &[u32]) -> f64 {
    path.windows(2)
        .map(|w| (x[w[1] as usize] - x[w[0] as usize]).norm())
        .sum()
}

/// The mean height of `particles` at `x`.
fn mean_height(x: &[Point3], particles: &[u32]) -> f64 {
    let sum: f64 = particles.iter().map(|&i| x[i as usize].z).sum();
    sum / particles.len().max(1) as f64
}

/// The rings of `pattern` measured at `x` against the placed panels `placed` (both indexed as
/// the assembled model's particles; `edge_particles` is `Assembled::edge_particles`).
pub fn hang(
    pattern: &Pattern,
    edge_particles: &[Vec<Vec<u32>>],
    placed: &[Point3],
    x: &[Point3],
) -> Vec<RingHang> {
    ring_edges(pattern)
        .into_iter()
        .map(|ring| {
            let paths: Vec<&[u32]> = (ring.sides.iter())
                .map(|e| edge_particles[e.panel][e.edge].as_slice())
                .collect();
            let mut particles: Vec<u32> = paths.concat();
            particles.sort_unstable();
            particles.dedup();
            let z = particles.iter().map(|&i| x[i as usize].z);
            let lo = z.clone().fold(f64::INFINITY, f64::min);
            let hi = z.fold(f64::NEG_INFINITY, f64::max);
            let mean = mean_height(x, &particles);
            RingHang {
                kind: ring.kind,
                edges: ring.names,
                length_m: paths.iter().map(|p| polyline(x, p)).sum(),
                rest_length_m: paths.iter().map(|p| polyline(placed, p)).sum(),
                height_m: [lo, hi],
                height_mean_m: mean,
                rise_m: mean - mean_height(placed, &particles),
            }
        })
        .collect()
}

/// How two drapes of one pattern differ in their rings (two resolutions, say): the largest
/// difference of a ring's mean height and of its strain along itself
/// (`length_m / rest_length_m - 1`, each against its own rest: a coarser sampling of a curve
/// is a little shorter), with the ring each is largest at.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HangDifference {
    /// The largest `|a.height_mean_m - b.height_mean_m|` over the rings, m.
    pub height_m: f64,
    /// The ring it is at (its first edge, as the fit check names it).
    pub height_ring: String,
    /// The largest difference of a ring's strain along itself (0.01: one point of percent).
    pub strain: f64,
    /// The ring it is at.
    pub strain_ring: String,
}

/// The difference between the rings `a` and `b` of one pattern ([`HangDifference`]); `None`
/// when they are not the same rings (another pattern) or there are none.
///
/// ```
/// use drapekit::garment::fit_check::RingKind;
/// use drapekit::garment::hang::{compare, RingHang};
/// let ring = |name: &str, mean: f64, length: f64| RingHang {
///     kind: RingKind::Opening,
///     edges: vec![name.into()],
///     length_m: length,
///     rest_length_m: 1.0,
///     height_m: [mean - 0.01, mean + 0.01],
///     height_mean_m: mean,
///     rise_m: 0.0,
/// };
/// let fine = [ring("hem", 0.40, 1.00), ring("neck", 1.40, 0.60)];
/// let coarse = [ring("hem", 0.43, 1.01), ring("neck", 1.39, 0.63)];
/// let d = compare(&coarse, &fine).unwrap();
/// assert!((d.height_m - 0.03).abs() < 1e-12 && d.height_ring == "hem");
/// assert!((d.strain - 0.03).abs() < 1e-12 && d.strain_ring == "neck");
/// ```
pub fn compare(a: &[RingHang], b: &[RingHang]) -> Option<HangDifference> {
    let same = |(r, s): &(&RingHang, &RingHang)| r.kind == s.kind && r.edges == s.edges;
    if a.is_empty() || a.len() != b.len() || !a.iter().zip(b).all(|p| same(&p)) {
        return None;
    }
    let strain = |r: &RingHang| r.length_m / r.rest_length_m - 1.0;
    let largest = |f: &dyn Fn(&RingHang, &RingHang) -> f64| {
        let (mut most, mut at) = (0.0, 0);
        for (k, (r, s)) in a.iter().zip(b).enumerate() {
            let d = f(r, s).abs();
            if d > most {
                (most, at) = (d, k);
            }
        }
        (most, a[at].edges.first().cloned().unwrap_or_default())
    };
    let (height_m, height_ring) = largest(&|r, s| r.height_mean_m - s.height_mean_m);
    let (strain, strain_ring) = largest(&|r, s| strain(r) - strain(s));
    Some(HangDifference {
        height_m,
        height_ring,
        strain,
        strain_ring,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::garment::assemble::{assemble, AssembleOptions};
    use crate::math::Vec3;

    /// The fixture's two-panel tube, assembled at 2 cm: its particles as placed and the
    /// assembly's edges.
    fn tube() -> (Pattern, Vec<Point3>, Vec<Vec<Vec<u32>>>) {
        let text = include_str!("../../fixtures/garments/tube_specification.json");
        let path = std::path::Path::new("tube_specification.json");
        let pattern = crate::garment::parse(text, path).expect("the fixture parses");
        let opts = AssembleOptions {
            spacing: 0.02,
            ..AssembleOptions::default()
        };
        let a = assemble(&pattern, &opts).expect("the tube assembles");
        let placed: Vec<Point3> = a.pieces.iter().flat_map(|p| p.3.clone()).collect();
        (pattern, placed, a.edge_particles)
    }

    #[test]
    fn a_ring_moved_up_rises_by_the_move_and_keeps_its_length() {
        let (pattern, placed, edges) = tube();
        let rings = hang(&pattern, &edges, &placed, &placed);
        // The tube: two panels sewn along both sides, open at the top and the bottom.
        let open = rings.iter().filter(|r| r.kind == RingKind::Opening).count();
        assert_eq!(open, 2, "{rings:?}");
        let up = Vec3::new(0.0, 0.0, 0.1);
        let moved: Vec<Point3> = placed.iter().map(|p| p + up).collect();
        for (r0, r) in rings.iter().zip(hang(&pattern, &edges, &placed, &moved)) {
            assert!((r.rise_m - 0.1).abs() < 1e-12, "{r:?}");
            assert!((r.height_m[0] - r0.height_m[0] - 0.1).abs() < 1e-12);
            assert!((r.length_m - r.rest_length_m).abs() < 1e-12);
            assert!(r.length_m > 0.0 && r.length_m == r0.length_m);
        }
    }

    #[test]
    fn drapes_of_other_rings_are_not_compared() {
        let (pattern, placed, edges) = tube();
        let rings = hang(&pattern, &edges, &placed, &placed);
        let same = compare(&rings, &rings).expect("the same rings");
        assert_eq!((same.height_m, same.strain), (0.0, 0.0));
        assert!(compare(&rings, &rings[1..]).is_none());
        let mut other = rings.clone();
        other[0].edges[0].push('x');
        assert!(compare(&rings, &other).is_none());
        assert!(compare(&[], &[]).is_none());
    }

    #[test]
    fn a_ring_scaled_across_is_longer_by_the_scale_and_does_not_rise() {
        let (pattern, placed, edges) = tube();
        // Every point 1.25 times as far from the vertical axis through the origin: each
        // horizontal polyline 1.25 times as long, each height kept.
        let wide: Vec<Point3> = (placed.iter())
            .map(|p| Point3::new(1.25 * p.x, 1.25 * p.y, p.z))
            .collect();
        for r in hang(&pattern, &edges, &placed, &wide) {
            if r.kind == RingKind::Opening {
                let ratio = r.length_m / r.rest_length_m;
                // The tube's openings are horizontal edges as placed: exactly 1.25.
                assert!((ratio - 1.25).abs() < 1e-9, "{r:?}");
                assert!(r.rise_m.abs() < 1e-12 && r.height_m[1] - r.height_m[0] < 1e-9);
            }
        }
    }
}
