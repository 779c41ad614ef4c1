//! Sampling a pattern's outlines for the cloth. Every edge gets `ceil(length / spacing)`
//! segments at equal arc length; the two edges of a stitch get the same count, the larger of
//! theirs (the reference pipeline's rule: the longer edge's), so their samples pair one to one
//! and the shorter edge's samples sit closer (a gathered edge). A stitch pairs the start of one
//! edge with the end of the other (they run in opposite directions), or start with start when
//! it is marked `right_wrong`.

use super::spec::{Panel, Pattern, Stitch};
use crate::math::Point2;

/// A panel's sampled outline: a closed loop (the first point is not repeated); edge `k`'s
/// samples are the `segments[k] + 1` points from `edge_start[k]` on, cyclically.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledPanel {
    /// The outline's points, in panel coordinates.
    pub points: Vec<Point2>,
    /// Index of each edge's first point.
    pub edge_start: Vec<usize>,
    /// Segments of each edge.
    pub segments: Vec<usize>,
}

/// Segments per edge of every panel at `spacing` (panel units), stitched edges matched.
///
/// # Panics
/// When `spacing` is not a positive finite number.
pub fn edge_segments(pattern: &Pattern, spacing: f64) -> Vec<Vec<usize>> {
    assert!(
        spacing > 0.0 && spacing.is_finite(),
        "sample spacing must be positive, got {spacing}"
    );
    let mut counts: Vec<Vec<usize>> = pattern
        .panels
        .iter()
        .map(|p| {
            (0..p.edges.len())
                .map(|k| ((p.edges[k].length(&p.vertices) / spacing).ceil() as usize).max(1))
                .collect()
        })
        .collect();
    for st in &pattern.stitches {
        let n = counts[st.a.panel][st.a.edge].max(counts[st.b.panel][st.b.edge]);
        counts[st.a.panel][st.a.edge] = n;
        counts[st.b.panel][st.b.edge] = n;
    }
    counts
}

/// The outline of `panel` with `segments[k]` segments on edge `k`.
pub fn sample_panel(panel: &Panel, segments: &[usize]) -> SampledPanel {
    let mut points = Vec::new();
    let mut edge_start = Vec::with_capacity(panel.edges.len());
    for (k, edge) in panel.edges.iter().enumerate() {
        let (s, e) = panel.endpoints(k);
        let samples = edge.curve.sample_segments(&s, &e, segments[k]);
        edge_start.push(points.len());
        // The last sample is the next edge's first.
        points.extend_from_slice(&samples[..samples.len() - 1]);
    }
    SampledPanel {
        points,
        edge_start,
        segments: segments.iter().map(|&n| n.max(1)).collect(),
    }
}

/// Every panel of `pattern` sampled with `counts` (from [`edge_segments`]).
pub fn sample_all(pattern: &Pattern, counts: &[Vec<usize>]) -> Vec<SampledPanel> {
    pattern
        .panels
        .iter()
        .zip(counts)
        .map(|(panel, c)| sample_panel(panel, c))
        .collect()
}

/// The sample pairs a stitch joins: `(i, j)` with `i` a point of the first edge's panel and `j`
/// of the second's, in order along the first edge.
pub fn stitch_pairs(sampled: &[SampledPanel], stitch: &Stitch) -> Vec<(usize, usize)> {
    let (pa, pb) = (&sampled[stitch.a.panel], &sampled[stitch.b.panel]);
    let n = pa.segments[stitch.a.edge];
    debug_assert_eq!(
        n, pb.segments[stitch.b.edge],
        "stitched edges share a count"
    );
    let (sa, sb) = (pa.edge_start[stitch.a.edge], pb.edge_start[stitch.b.edge]);
    (0..=n)
        .map(|t| {
            let tb = if stitch.right_wrong { t } else { n - t };
            ((sa + t) % pa.points.len(), (sb + tb) % pb.points.len())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::garment::spec::parse;
    use std::path::Path;

    /// Two squares side by side (10 and 8 units tall), A's right edge sewn to B's left edge.
    const TWO: &str = r#"{"pattern": {"panels": {
        "a": {"vertices": [[0, 0], [10, 0], [10, 10], [0, 10]],
              "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}],
              "translation": [0, 0, 0], "rotation": [0, 0, 0]},
        "b": {"vertices": [[20, 0], [30, 0], [30, 8], [20, 8]],
              "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}],
              "translation": [0, 0, 0], "rotation": [0, 0, 0]}},
      "stitches": [[{"panel": "a", "edge": 1}, {"panel": "b", "edge": 3}]]},
      "parameters": {}, "parameter_order": [],
      "properties": {"curvature_coords": "relative", "units_in_meter": 100}}"#;

    #[test]
    fn stitched_edges_share_the_longer_edges_count_and_pair_start_to_end() {
        let p = parse(TWO, Path::new("two.json")).unwrap();
        let counts = edge_segments(&p, 1.0);
        // A's right edge is 10 long, B's left edge 8: both get 10 segments; B's right edge,
        // unstitched, keeps its 8.
        assert_eq!(counts[0], vec![10, 10, 10, 10]);
        assert_eq!(counts[1], vec![10, 8, 10, 10]);
        let sampled = sample_all(&p, &counts);
        assert_eq!(sampled[0].points.len(), 40);
        let pairs = stitch_pairs(&sampled, &p.stitches[0]);
        assert_eq!(pairs.len(), 11);
        // A's edge 1 runs up x = 10 from (10, 0); B's edge 3 runs down x = 20 from (20, 8):
        // A's start meets B's end.
        let (i, j) = pairs[0];
        assert_eq!(sampled[0].points[i], Point2::new(10.0, 0.0));
        assert_eq!(sampled[1].points[j], Point2::new(20.0, 0.0));
        let (i, j) = pairs[10];
        assert_eq!(sampled[0].points[i], Point2::new(10.0, 10.0));
        assert_eq!(sampled[1].points[j], Point2::new(20.0, 8.0));
        // The gathered edge's samples are 0.8 apart, the other's 1.0.
        let (i, j) = pairs[5];
        assert!((sampled[0].points[i].y - 5.0).abs() < 1e-12);
        assert!((sampled[1].points[j].y - 4.0).abs() < 1e-12);
    }

    #[test]
    fn every_stitch_of_the_real_patterns_pairs_equal_counts() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/realdata/patterns");
        if !dir.exists() {
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "{} is missing",
                dir.display()
            );
            eprintln!("skipped: {} is missing", dir.display());
            return;
        }
        for name in ["dress_pencil", "hoody_mean", "js_mean_all", "shirt_mean"] {
            let p = crate::garment::read(&dir.join(format!("{name}_specification.json"))).unwrap();
            let counts = edge_segments(&p, 1.0);
            let sampled = sample_all(&p, &counts);
            for st in &p.stitches {
                let pairs = stitch_pairs(&sampled, st);
                assert_eq!(pairs.len(), counts[st.a.panel][st.a.edge] + 1, "{name}");
                // The ends of the pairs are the edges' end vertices.
                let (pa, pb) = (&p.panels[st.a.panel], &p.panels[st.b.panel]);
                let (i, j) = pairs[0];
                assert_eq!(sampled[st.a.panel].points[i], pa.endpoints(st.a.edge).0);
                let b_end = pb.endpoints(st.b.edge);
                let expect = if st.right_wrong { b_end.0 } else { b_end.1 };
                assert_eq!(sampled[st.b.panel].points[j], expect, "{name}");
            }
            // Every panel's outline: as many points as segments.
            for (s, c) in sampled.iter().zip(&counts) {
                assert_eq!(s.points.len(), c.iter().sum::<usize>());
            }
        }
    }
}
