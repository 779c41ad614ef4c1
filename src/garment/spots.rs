//! Where a garment fails: the points behind each failed measure of the verdict, gathered into
//! spots a pattern maker can find on the body.
//!
//! The points are the midpoints of the cloth edges through the body and through the cloth,
//! the midpoints of the stretch springs strained past the verdict's limit, and the particles
//! inside the body. Each kind is gathered on its own, greedily in particle order: a point joins
//! the first spot whose first point lies within [`SPOT_RADIUS`], or starts a new one. A spot
//! reports its point count, its mean position (and height), its panel (the one most of its points are in,
//! the first such on a tie) and, for strain, its largest strain. The order is fixed, so the
//! spots do not depend on the thread count.

use super::measure::{panel_of, Crossings, Thresholds};
use crate::cloth::elements::SpringKind;
use crate::math::Point3;
use crate::sim::World;
use serde::Serialize;

/// A spot gathers the points of one kind within this distance of its first point, m.
pub const SPOT_RADIUS: f64 = 0.05;

/// The spots of each kind kept in a report, the largest first.
pub const SPOTS_PER_KIND: usize = 10;

/// What a spot is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpotKind {
    /// Cloth edges through the body.
    BodyCrossing,
    /// Cloth edges through the cloth.
    SelfCrossing,
    /// Stretch springs strained past the verdict's limit.
    Strain,
    /// Particles inside the body.
    Inside,
}

/// One spot, in the simulation's frame (metres, z up).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spot {
    /// What it is made of.
    pub kind: SpotKind,
    /// The panel most of its points are in.
    pub panel: String,
    /// Its points (edges, springs or particles).
    pub count: usize,
    /// Their mean position (the simulation's frame; a report gives it in its outputs' frame).
    pub at: [f64; 3],
    /// Its height along the up axis, m (the simulation's z: on a body, above its feet).
    pub height_m: f64,
    /// Strain spots: the largest strain in it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub worst: Option<f64>,
}

/// The spots of every failed kind, each kind's largest first (strain: its most strained
/// first), at most [`SPOTS_PER_KIND`] of each, and the number of spots left out.
pub fn spots(
    world: &World,
    inside: &[bool],
    crossings: &Crossings,
    t: &Thresholds,
) -> (Vec<Spot>, usize) {
    let x = &world.state.x;
    let mid = |e: &[u32; 2]| {
        let (a, b) = (x[e[0] as usize], x[e[1] as usize]);
        (e[0], a + (b - a) / 2.0, 0.0)
    };
    let mut kinds: Vec<(SpotKind, Vec<Point>)> = Vec::new();
    if crossings.body.len() > t.body_crossing_edges {
        kinds.push((
            SpotKind::BodyCrossing,
            crossings.body.iter().map(mid).collect(),
        ));
    }
    if crossings.cloth.len() > t.self_crossing_edges {
        kinds.push((
            SpotKind::SelfCrossing,
            crossings.cloth.iter().map(mid).collect(),
        ));
    }
    let strained: Vec<Point> = (world.model.springs.iter())
        .filter(|s| s.kind == SpringKind::Stretch)
        .filter_map(|s| {
            let e = (x[s.b as usize] - x[s.a as usize]).norm() / s.rest - 1.0;
            (e > t.max_strain).then(|| (s.a, mid(&[s.a, s.b]).1, e))
        })
        .collect();
    if !strained.is_empty() {
        kinds.push((SpotKind::Strain, strained));
    }
    let inner: Vec<Point> = (inside.iter().enumerate())
        .filter(|(_, &i)| i)
        .map(|(i, _)| (i as u32, x[i], 0.0))
        .collect();
    if inner.len() > t.particles_inside {
        kinds.push((SpotKind::Inside, inner));
    }
    let mut out = Vec::new();
    let mut left_out = 0;
    for (kind, mut points) in kinds {
        points.sort_by_key(|p| p.0);
        let found = gather(&points, SPOT_RADIUS);
        let mut made: Vec<Spot> = (found.iter())
            .map(|g| spot(world, kind, &points, &g.members))
            .collect();
        // Largest first (strain: the most strained first); a stable sort keeps particle order
        // on ties.
        if kind == SpotKind::Strain {
            made.sort_by(|a, b| b.worst.unwrap_or(0.0).total_cmp(&a.worst.unwrap_or(0.0)));
        } else {
            made.sort_by_key(|s| std::cmp::Reverse(s.count));
        }
        left_out += made.len().saturating_sub(SPOTS_PER_KIND);
        out.extend(made.into_iter().take(SPOTS_PER_KIND));
    }
    (out, left_out)
}

/// A point of a spot: its particle (an edge's or spring's first), position and value.
type Point = (u32, Point3, f64);

/// A spot under construction: its first point and its members (indices into the points).
struct Gathered {
    seed: Point3,
    members: Vec<usize>,
}

/// Greedy gathering: each point joins the first spot whose seed is within `radius`.
fn gather(points: &[Point], radius: f64) -> Vec<Gathered> {
    let mut found: Vec<Gathered> = Vec::new();
    for (k, p) in points.iter().enumerate() {
        match found.iter_mut().find(|g| (g.seed - p.1).norm() <= radius) {
            Some(g) => g.members.push(k),
            None => found.push(Gathered {
                seed: p.1,
                members: vec![k],
            }),
        }
    }
    found
}

/// The spot of `members` of `points`.
fn spot(world: &World, kind: SpotKind, points: &[Point], members: &[usize]) -> Spot {
    let n = members.len() as f64;
    let sum = members
        .iter()
        .fold(Point3::origin().coords, |s, &k| s + points[k].1.coords);
    let mut votes = vec![0usize; world.model.pieces.len()];
    for &k in members {
        votes[panel_of(world, points[k].0)] += 1;
    }
    let most = *votes.iter().max().unwrap_or(&0);
    let panel = votes.iter().position(|&v| v == most).unwrap_or(0);
    let worst = members
        .iter()
        .map(|&k| points[k].2)
        .fold(f64::MIN, f64::max);
    let at = sum / n;
    Spot {
        kind,
        panel: world.model.pieces[panel].name.clone(),
        count: members.len(),
        at: at.into(),
        height_m: at.z,
        worst: (kind == SpotKind::Strain).then_some(worst),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(i: u32, x: f64) -> Point {
        (i, Point3::new(x, 0.0, 0.0), 0.0)
    }

    #[test]
    fn points_within_the_radius_of_a_seed_share_its_spot() {
        // 0, 0.04 and 0.05 join the seed at 0; 0.08 is 0.08 from it: a new seed, which 0.12
        // joins (0.04 away).
        let pts = [p(0, 0.0), p(1, 0.04), p(2, 0.08), p(3, 0.05), p(4, 0.12)];
        let g = gather(&pts, SPOT_RADIUS);
        let members: Vec<Vec<usize>> = g.iter().map(|g| g.members.clone()).collect();
        assert_eq!(members, vec![vec![0, 1, 3], vec![2, 4]]);
    }
}
