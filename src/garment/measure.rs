//! What a garment run reports, per panel and for the whole garment: seam gaps, particles inside
//! the body, strain of the stretch springs, and the verdict against [`Thresholds`].

use super::assemble::SeamPair;
use crate::cloth::elements::SpringKind;
use crate::collide::cloth::{
    body_crossing_flags, mean_edge_length, self_crossings, ClothHash, AUTO_CELL,
};
use crate::sim::World;
use serde::Serialize;

/// The limits a draped garment is judged by.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Thresholds {
    /// Largest seam gap, mm (default 1).
    pub seam_gap_max_mm: f64,
    /// Particles inside the body (default 0).
    pub particles_inside: usize,
    /// Largest strain of a stretch spring (default 0.05).
    pub max_strain: f64,
    /// Fraction of particles still moving (default 0.015, the reference pipeline's).
    pub moving_fraction: f64,
    /// Cloth edges crossing the body (default 0; the reference pipeline fails above 35).
    pub body_crossing_edges: usize,
    /// Cloth edges crossing the cloth (default 10; the reference pipeline fails above 300).
    pub self_crossing_edges: usize,
}

impl Default for Thresholds {
    fn default() -> Self {
        Thresholds {
            seam_gap_max_mm: 1.0,
            particles_inside: 0,
            max_strain: 0.05,
            moving_fraction: super::drape::REST_FRACTION,
            body_crossing_edges: 0,
            self_crossing_edges: 10,
        }
    }
}

/// Measures of a panel or of the whole garment.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Measures {
    /// Panel name (`garment` for the whole).
    pub name: String,
    /// Particles.
    pub particles: usize,
    /// Largest gap of the seams touching it, mm.
    pub seam_gap_max_mm: f64,
    /// Mean gap of the seams touching it, mm.
    pub seam_gap_mean_mm: f64,
    /// Particles inside the body.
    pub particles_inside: usize,
    /// Largest strain of its stretch springs.
    pub max_strain: f64,
    /// Its cloth edges that cross the body.
    pub body_crossing_edges: usize,
    /// Its cloth edges that cross the cloth (any panel's; seams welded).
    pub self_crossing_edges: usize,
}

/// Per panel, then the whole garment (last). `inside[i]`: particle `i` is inside the body.
pub fn measures(world: &World, seams: &[SeamPair], inside: &[bool]) -> Vec<Measures> {
    measures_of(world, seams, inside, &crossings(world, seams))
}

/// The cloth edges that cross something: the body (any collider), then the cloth (each edge
/// once, seams welded). An edge's two ends are in one panel; `[lower, higher]` particle.
#[derive(Debug, Clone, Default)]
pub struct Crossings {
    /// Edges through the body.
    pub body: Vec<[u32; 2]>,
    /// Edges through a cloth triangle that shares no vertex with them.
    pub cloth: Vec<[u32; 2]>,
}

/// Finds the crossing edges of the garment in `world`.
pub fn crossings(world: &World, seams: &[SeamPair]) -> Crossings {
    let (m, x) = (&world.model, &world.state.x);
    let pairs: Vec<[u32; 2]> = seams.iter().map(|s| [s.a, s.b]).collect();
    let mut hash = ClothHash::new(m.len(), &m.triangles, &pairs);
    let cell = AUTO_CELL * mean_edge_length(x, hash.edges());
    hash.rebuild(x, &m.triangles, cell.max(1e-6), 0.0);
    let mut out = Crossings::default();
    for c in &world.colliders {
        let flags = body_crossing_flags(c, x, hash.edges());
        let crossing = hash.edges().iter().zip(flags).filter(|(_, f)| *f);
        out.body.extend(crossing.map(|(e, _)| *e));
    }
    for (e, _) in self_crossings(x, &m.triangles, &hash) {
        if out.cloth.last() != Some(&e) {
            out.cloth.push(e);
        }
    }
    out
}

/// [`measures`] with the crossing edges already found.
pub fn measures_of(
    world: &World,
    seams: &[SeamPair],
    inside: &[bool],
    crossings: &Crossings,
) -> Vec<Measures> {
    let m = &world.model;
    let x = &world.state.x;
    let mut out: Vec<Measures> = m
        .pieces
        .iter()
        .map(|p| Measures {
            name: p.name.clone(),
            particles: p.count,
            ..Measures::default()
        })
        .collect();
    out.push(Measures {
        name: "garment".into(),
        particles: m.len(),
        ..Measures::default()
    });
    let panel_of = |i: u32| panel_of(world, i);
    let whole = out.len() - 1;
    let mut gap_sum = vec![0.0; out.len()];
    let mut gap_count = vec![0usize; out.len()];
    for s in seams {
        let g = (x[s.a as usize] - x[s.b as usize]).norm() * 1e3;
        let mut panels = vec![panel_of(s.a), panel_of(s.b), whole];
        panels.dedup();
        for k in panels {
            out[k].seam_gap_max_mm = out[k].seam_gap_max_mm.max(g);
            gap_sum[k] += g;
            gap_count[k] += 1;
        }
    }
    for (k, o) in out.iter_mut().enumerate() {
        o.seam_gap_mean_mm = gap_sum[k] / gap_count[k].max(1) as f64;
    }
    for (i, &inn) in inside.iter().enumerate() {
        if inn {
            out[panel_of(i as u32)].particles_inside += 1;
            out[whole].particles_inside += 1;
        }
    }
    for s in m.springs.iter().filter(|s| s.kind == SpringKind::Stretch) {
        let e = (x[s.b as usize] - x[s.a as usize]).norm() / s.rest - 1.0;
        let k = panel_of(s.a);
        out[k].max_strain = out[k].max_strain.max(e);
        out[whole].max_strain = out[whole].max_strain.max(e);
    }
    for e in &crossings.body {
        out[panel_of(e[0])].body_crossing_edges += 1;
        out[whole].body_crossing_edges += 1;
    }
    for e in &crossings.cloth {
        out[panel_of(e[0])].self_crossing_edges += 1;
        out[whole].self_crossing_edges += 1;
    }
    out
}

/// The panel (piece) of particle `i`.
pub(crate) fn panel_of(world: &World, i: u32) -> usize {
    (world.model.pieces.iter())
        .position(|p| (i as usize) >= p.first && (i as usize) < p.first + p.count)
        .expect("every particle is in a piece")
}

/// The verdict: every failed limit, named (empty: passes).
pub fn verdict(whole: &Measures, moving_fraction: f64, t: &Thresholds) -> Vec<String> {
    let counts = [
        (
            whole.particles_inside,
            t.particles_inside,
            "particles inside the body",
        ),
        (
            whole.body_crossing_edges,
            t.body_crossing_edges,
            "cloth edges crossing the body",
        ),
        (
            whole.self_crossing_edges,
            t.self_crossing_edges,
            "cloth edges crossing the cloth",
        ),
    ];
    let mut failed = Vec::new();
    if whole.seam_gap_max_mm > t.seam_gap_max_mm {
        failed.push(format!(
            "a seam gap of {:.2} mm (at most {} mm)",
            whole.seam_gap_max_mm, t.seam_gap_max_mm
        ));
    }
    for (n, limit, what) in counts {
        if n > limit {
            failed.push(format!("{n} {what} (at most {limit})"));
        }
    }
    let percents = [
        (whole.max_strain, t.max_strain, "strain"),
        (moving_fraction, t.moving_fraction, "particles still moving"),
    ];
    for (v, limit, what) in percents {
        if v > limit {
            failed.push(format!(
                "{what}: {:.2}% (at most {}%)",
                v * 100.0,
                limit * 100.0
            ));
        }
    }
    failed
}

/// A stitch whose seam is not closed.
#[derive(Debug, Clone, Serialize)]
pub struct OpenSeam {
    /// The stitch (1-based, in the file's order).
    pub stitch: usize,
    /// Its two edges, `panel:edge` (edges 0-based, as in the file).
    pub edges: [String; 2],
    /// Its largest gap, mm.
    pub gap_max_mm: f64,
    /// The middle of that gap, in the simulation's frame (metres, z up) as measured; the
    /// `garment` command's report gives it in the garment mesh's frame and units.
    pub at: [f64; 3],
    /// The height of that middle along the up axis, m (on a body, above its feet).
    pub height_m: f64,
}

/// The stitches with a gap above `limit_mm`, widest first.
pub fn open_seams(
    pattern: &super::Pattern,
    seams: &[SeamPair],
    x: &[crate::math::Point3],
    limit_mm: f64,
) -> Vec<OpenSeam> {
    let mut widest = vec![(0.0f64, [0.0; 3]); pattern.stitches.len()];
    for s in seams {
        let (a, b) = (x[s.a as usize], x[s.b as usize]);
        let g = (a - b).norm() * 1e3;
        if g > widest[s.stitch].0 {
            widest[s.stitch] = (g, nalgebra::center(&a, &b).into());
        }
    }
    let name = |e: &super::EdgeRef| format!("{}:{}", pattern.panels[e.panel].name, e.edge);
    let mut open: Vec<OpenSeam> = widest
        .iter()
        .enumerate()
        .filter(|(_, &(g, _))| g > limit_mm)
        .map(|(i, &(g, at))| OpenSeam {
            stitch: i + 1,
            edges: [name(&pattern.stitches[i].a), name(&pattern.stitches[i].b)],
            gap_max_mm: g,
            at,
            height_m: at[2],
        })
        .collect();
    open.sort_by(|a, b| b.gap_max_mm.total_cmp(&a.gap_max_mm));
    open
}
