//! A pattern made cloth. Each panel's outline, sampled with the stitched edges paired
//! ([`super::sample`]), becomes a piece: the paper's warp/weft grid inside, the band to the
//! outline triangulated (`cloth::pattern::build`), the outline samples kept as its boundary
//! particles. The panel's placement `R (x, y, 0) + t` puts it in 3D; the pattern's units become
//! metres (`units_in_meter`) and its y-up frame drapekit's z-up one.
//!
//! Each stitch's sample pairs become **seam springs** (`SpringKind::Seam`) of rest length 0
//! between the two sides' particles: `k_s / 2 |x_a - x_b|^2`, quadratic, so projective dynamics
//! keeps them in its prefactored matrix and needs no projection for them. `k_s` is
//! [`SEAM_STIFFNESS`] times the fabric's stretch constant: stiff enough to hold the two sides
//! together like the thread does, a closed seam acting as one particle (the reference
//! pipeline merges the pairs outright), while the sides still start apart and are pulled
//! together during sewing. Pairs that land on one particle (the corner shared by two stitches
//! of one panel, a dart's tip) get no spring.
//!
//! A seam **carries bending across itself**: each pair gets the over-one-node element of the
//! grid (`cloth::pattern`), `(B / h^2) |x_a' - x_a - x_b + x_b'|^2 / 2` with `x_a'` and `x_b'`
//! the particles one step inside either panel (the sample's spring neighbour nearest the
//! outline's inward normal). Closed and flat (`x_a = x_b` midway between the two), it vanishes;
//! folded at the seam, it costs what the fabric's bending rigidity `B` says. Without it a seam
//! is a free hinge (outline particles get no bending), and a sewn tube stays a flat lens.
//!
//! **The rim bends too** (`AssembleOptions::rim_bending`, on by default): every interior edge
//! of a panel with an outline particle among its four nodes gets a hinge
//! (`cloth::elements::hinge`) of the fabric's mean rigidity, so the band along the outline
//! does not fold freely where its outline particles have no element. Measured over perturbed
//! starts (README, `bench garment`).

use super::drape::SPACING_RANGE;
use super::sample::{edge_segments, sample_all, stitch_pairs};
use super::spec::Pattern;
use crate::cloth::elements::hinge::rim_hinges;
use crate::cloth::elements::{Bend, Spring, SpringKind};
use crate::cloth::fabric::Fabric;
use crate::cloth::pattern::{self, PatternError, Piece, Pins};
use crate::math::{Point2, Point3, Vec2, Vec3};
use crate::mesh::transform::{change_up_point, Up};
use nalgebra::{Rotation3, Vector3};
use std::collections::HashMap;

/// Seam springs' constant relative to the fabric's stretch constant (warp and weft's larger).
pub const SEAM_STIFFNESS: f64 = 10.0;

/// How a pattern is made cloth.
#[derive(Debug, Clone, PartialEq)]
pub struct AssembleOptions {
    /// Particle spacing, m (default 0.01: the reference pipeline's 1 cm).
    pub spacing: f64,
    /// The fabric of every panel (default cotton).
    pub fabric: Fabric,
    /// Where the whole pattern goes (default: where its panels' placements put it).
    pub placement: Placement,
    /// Hinge bending over the band along each panel's outline (`cloth::elements::hinge::
    /// rim_hinges`; default true): without it the band folds freely where its particles on the
    /// outline have no bending element (see the README's `bench garment`).
    pub rim_bending: bool,
}

impl Default for AssembleOptions {
    fn default() -> Self {
        AssembleOptions {
            spacing: 0.01,
            fabric: Fabric::cotton(),
            placement: Placement::default(),
            rim_bending: true,
        }
    }
}

/// A rigid motion of the whole pattern in drapekit's frame (metres, z up), after its panels'
/// own placements: `p -> Rz(turn) p + translation`, a turn about the vertical axis through the
/// origin, then a shift. The default leaves the pattern where its file puts it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Placement {
    /// The turn about the z axis, degrees, counter-clockwise seen from above.
    pub turn_deg: f64,
    /// The shift, m.
    pub translation: Vec3,
}

impl Placement {
    fn rotation(&self) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&Vector3::z_axis(), self.turn_deg.to_radians())
    }

    /// Where `p` goes.
    pub fn apply(&self, p: Point3) -> Point3 {
        if *self == Placement::default() {
            return p;
        }
        self.rotation() * p + self.translation
    }

    /// Where the direction `v` turns to.
    pub fn apply_vector(&self, v: Vec3) -> Vec3 {
        self.rotation() * v
    }

    /// Where `p` came from.
    pub fn unapply(&self, p: Point3) -> Point3 {
        if *self == Placement::default() {
            return p;
        }
        self.rotation().inverse() * (p - self.translation)
    }
}

/// One seam spring's ends (model particles) and the stitch it sews (0-based).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeamPair {
    /// Particle on the stitch's first edge.
    pub a: u32,
    /// Particle on the stitch's second edge.
    pub b: u32,
    /// The stitch.
    pub stitch: usize,
}

/// A pattern as pieces ready for `ClothModel::assemble` (name, piece, fabric, placed
/// particles, in metres, z up) and its seams.
#[derive(Debug, Clone)]
pub struct Assembled {
    /// The panels' pieces, in the pattern's order.
    pub pieces: Vec<(String, Piece, Fabric, Vec<Point3>)>,
    /// Seam springs' ends (indices into the assembled model's particles).
    pub seams: Vec<SeamPair>,
    /// The seam springs' constant, N/m.
    pub seam_k: f64,
    /// Bending elements across the seams.
    pub seam_bends: Vec<Bend>,
    /// The particles of the edges labelled `waist::WAIST_LABEL` (a skirt's or trousers' top),
    /// held at the body's waist while sewing; sorted, each once.
    pub waist: Vec<u32>,
    /// Each panel edge's particles from its start to its end, `[panel][edge]`.
    pub edge_particles: Vec<Vec<Vec<u32>>>,
}

/// What stops a pattern from becoming cloth.
#[derive(Debug, thiserror::Error)]
pub enum AssembleError {
    /// A panel's sampled outline is not a piece.
    #[error("panel '{panel}': {error}")]
    Panel { panel: String, error: PatternError },
    /// The spacing is not a positive length.
    #[error("spacing {spacing} m must be a positive number")]
    Spacing { spacing: f64 },
    /// A panel's outline takes far more particles than its perimeter needs at the spacing
    /// ([`MAX_CROWDED_SAMPLES`]).
    #[error("panel '{panel}': its outline takes {samples} particles where its {perimeter:.3} m at spacing {spacing} m needs about {needed}: every edge takes at least one, and an edge stitched to a longer one takes the longer one's count; at most twice the need plus 1000: join the short edges (a curve is one edge with a curvature) or stitch edges of like lengths")]
    Crowded {
        panel: String,
        samples: usize,
        perimeter: f64,
        needed: f64,
        spacing: f64,
    },
    /// A panel narrower than the cloth at this spacing takes ([`THIN_FRACTION`] of the
    /// spacing, and a width times spacing of [`THIN_WIDTH_SPACING`]); `spacings`: the range of
    /// spacings within [`SPACING_RANGE`] that would take it, if any.
    #[error("panel '{panel}' is {} mm wide (twice its area over its perimeter) at spacing {spacing} m; cloth at this spacing needs a panel at least {} mm wide ({THIN_FRACTION} of the spacing, and width times spacing at least {THIN_WIDTH_SPACING:e} m^2): a narrower one has particles too light for its springs and seams, and the solver fails (an unstable step, or a matrix not positive definite); {}", crate::math::short(width * 1e3), crate::math::short(thin_limit(*spacing) * 1e3), match spacings { Some([a, b]) => format!("a spacing from {a} to {b} m would take it (garment --spacing, or spacing in a scene's [[garment]])"), None => format!("no spacing from {} to {} m takes it: is it meant to be a panel?", SPACING_RANGE[0], SPACING_RANGE[1]) })]
    Thin {
        panel: String,
        width: f64,
        spacing: f64,
        spacings: Option<[f64; 2]>,
    },
    /// The panels together would give more than [`pattern::MAX_PARTICLES`] particles (each
    /// panel's estimate, and at least its outline's samples, summed before any is built).
    #[error("the pattern's {panels} panel(s) give about {estimate} particles at spacing {spacing} m; a garment has at most {limit}: use a larger spacing, or fewer or smaller panels")]
    TooManyParticles {
        panels: usize,
        estimate: f64,
        spacing: f64,
        limit: usize,
    },
}

/// The outline samples beyond twice what a panel's perimeter needs at the spacing that a
/// panel may have (edges shorter than the spacing each take one; a short edge stitched to a
/// long one takes its count). A panel of 100,000 edges of 0.1 mm put that many particles
/// within centimetres of each other, and the solver's blocks between them took 8 GB.
pub const MAX_CROWDED_SAMPLES: usize = 1000;

/// The least width of a panel, in particle spacings (the width: twice the area over the
/// perimeter, `w L / (w + L)` for a `w` by `L` strip). Measured with the tube fixture's front
/// made a 60 cm strip `w` wide, its short ends sewn to the back, cotton, `garment` on
/// mean_all: at 1 cm spacing 0.4 mm failed (an unstable step) and 0.5 mm draped; at 2 cm 0.7
/// mm failed and 1 mm draped; at 4 cm 0.2 mm failed and 0.5 mm draped. 0.045 spacings
/// refuses every failure seen and takes the narrowest drapes at 1 and 2 cm; at 4 cm it is
/// conservative (1.8 mm).
pub const THIN_FRACTION: f64 = 0.045;

/// The least width times spacing of a panel, m^2. The stiffest spring's `k dt^2 / m` of such
/// a strip grows as `1 / (w h)^2` (9.8e13 at 0.02 mm by 1 cm, 6.1e12 at 0.2 mm by 4 mm, the
/// latter within [`THIN_FRACTION`]) and the solver refuses it above 1e12 (not positive
/// definite): at about `w h = 2e-6` m^2; twice that here. At spacings of 1 cm and more
/// [`THIN_FRACTION`] implies it; finer, it is the bound that bites.
pub const THIN_WIDTH_SPACING: f64 = 4e-6;

/// The least width a panel may have at spacing `h`, m.
fn thin_limit(h: f64) -> f64 {
    (THIN_FRACTION * h).max(THIN_WIDTH_SPACING / h)
}

/// Twice the area over the perimeter of a closed outline: a strip's width.
fn width(outline: &[Point2]) -> f64 {
    let n = outline.len();
    let (mut area, mut perimeter) = (0.0, 0.0);
    for i in 0..n {
        let (p, q) = (outline[i], outline[(i + 1) % n]);
        area += p.coords.perp(&q.coords) / 2.0;
        perimeter += (q - p).norm();
    }
    if perimeter > 0.0 {
        2.0 * area.abs() / perimeter
    } else {
        0.0
    }
}

/// Refuses each panel narrower than [`thin_limit`] at spacing `h` (outlines in metres), with
/// the spacings within [`SPACING_RANGE`] that would take it: from `THIN_WIDTH_SPACING / w`
/// to `w / THIN_FRACTION`, rounded inwards to a tenth of a millimetre.
fn check_thin(pattern: &Pattern, outlines: &[Vec<Point2>], h: f64) -> Vec<AssembleError> {
    let mut errors = Vec::new();
    for (panel, outline) in pattern.panels.iter().zip(outlines) {
        let w = width(outline);
        if w >= thin_limit(h) {
            continue;
        }
        let lo = ((THIN_WIDTH_SPACING / w).max(SPACING_RANGE[0]) * 1e4).ceil() / 1e4;
        let hi = ((w / THIN_FRACTION).min(SPACING_RANGE[1]) * 1e4).floor() / 1e4;
        errors.push(AssembleError::Thin {
            panel: panel.name.clone(),
            width: w,
            spacing: h,
            spacings: (lo <= hi && w > 0.0).then_some([lo, hi]),
        });
    }
    errors
}

/// Each panel the cloth cannot be made of at spacing `h`, m, for want of width
/// ([`AssembleError::Thin`]), before any is sampled for a piece: the check [`assemble`]
/// makes, for a caller to make before other work.
pub fn thin_panels(pattern: &Pattern, h: f64) -> Vec<AssembleError> {
    if !(h.is_finite() && h > 0.0) {
        return vec![AssembleError::Spacing { spacing: h }];
    }
    check_thin(pattern, &metre_outlines(pattern, h).1, h)
}

/// Each panel's outline sampled at spacing `h`, m, with the stitched edges paired (in the
/// pattern's units), and the same outlines in metres.
fn metre_outlines(
    pattern: &Pattern,
    h: f64,
) -> (Vec<super::sample::SampledPanel>, Vec<Vec<Point2>>) {
    let to_m = 1.0 / pattern.units_in_meter;
    let counts = edge_segments(pattern, h / to_m);
    let sampled = sample_all(pattern, &counts);
    let outlines = (sampled.iter())
        .map(|s| {
            s.points
                .iter()
                .map(|q| Point2::from(q.coords * to_m))
                .collect()
        })
        .collect();
    (sampled, outlines)
}

/// Refuses each panel whose outline has more than twice the samples its perimeter needs at
/// spacing `h`, plus [`MAX_CROWDED_SAMPLES`].
fn check_crowding(pattern: &Pattern, outlines: &[Vec<Point2>], h: f64) -> Vec<AssembleError> {
    let mut errors = Vec::new();
    for (panel, outline) in pattern.panels.iter().zip(outlines) {
        let n = outline.len();
        let perimeter: f64 = (0..n)
            .map(|i| (outline[(i + 1) % n] - outline[i]).norm())
            .sum();
        let needed = (perimeter / h).ceil();
        if n as f64 > 2.0 * needed + MAX_CROWDED_SAMPLES as f64 {
            errors.push(AssembleError::Crowded {
                panel: panel.name.clone(),
                samples: n,
                perimeter,
                needed,
                spacing: h,
            });
        }
    }
    errors
}

/// Refuses panels that together would give more than [`pattern::MAX_PARTICLES`] particles:
/// each panel alone is checked as it is built, but ten thousand panels of a few hundred
/// particles each would all be built, and their solver would not fit in memory.
fn check_total(outlines: &[Vec<Point2>], h: f64) -> Result<(), AssembleError> {
    let estimate: f64 = (outlines.iter())
        .map(|o| pattern::particle_estimate(o, h).0.max(o.len() as f64))
        .sum();
    if estimate > pattern::MAX_PARTICLES as f64 {
        return Err(AssembleError::TooManyParticles {
            panels: outlines.len(),
            estimate: estimate.round(),
            spacing: h,
            limit: pattern::MAX_PARTICLES,
        });
    }
    Ok(())
}

/// The pattern's units per metre, its y-up frame, a panel's placement and the whole
/// pattern's, as one map from panel coordinates (metres) to drapekit's frame.
fn placer(
    pattern: &Pattern,
    panel: usize,
    placement: Placement,
) -> impl Fn(&Point2) -> Point3 + '_ {
    let p = &pattern.panels[panel];
    let (r, t) = (p.rotation(), p.translation / pattern.units_in_meter);
    move |q: &Point2| {
        let placed = change_up_point(r * Point3::new(q.x, q.y, 0.0) + t, Up::Y, Up::Z);
        placement.apply(placed)
    }
}

/// Makes cloth of `pattern`: every panel a piece, every stitch seam springs. Every panel's
/// problem is reported together.
pub fn assemble(
    pattern: &Pattern,
    opts: &AssembleOptions,
) -> Result<Assembled, Vec<AssembleError>> {
    let h = opts.spacing;
    if !(h.is_finite() && h > 0.0) {
        return Err(vec![AssembleError::Spacing { spacing: h }]);
    }
    let to_m = 1.0 / pattern.units_in_meter;
    let (sampled, outlines) = metre_outlines(pattern, h);
    let crowded = check_crowding(pattern, &outlines, h);
    if !crowded.is_empty() {
        return Err(crowded);
    }
    let thin = check_thin(pattern, &outlines, h);
    if !thin.is_empty() {
        return Err(thin);
    }
    check_total(&outlines, h).map_err(|e| vec![e])?;
    let (mut pieces, mut errors, mut outline_particle) = (Vec::new(), Vec::new(), Vec::new());
    let mut first = 0u32;
    for (k, (panel, outline)) in pattern.panels.iter().zip(outlines).enumerate() {
        match pattern::build(&outline, h, &opts.fabric, &Pins::default()) {
            Ok(mut piece) => {
                if opts.rim_bending {
                    let b = 0.5 * (opts.fabric.bend[0] + opts.fabric.bend[1]);
                    if b > 0.0 {
                        let rim =
                            rim_hinges(&piece.flat, &piece.triangles, piece.grid_particles, b);
                        piece.bends.extend(rim);
                    }
                }
                outline_particle.push(sample_particles(&piece, &outline, first));
                first += piece.flat.len() as u32;
                let place = placer(pattern, k, opts.placement);
                let placed = piece.flat.iter().map(&place).collect();
                pieces.push((panel.name.clone(), piece, opts.fabric.clone(), placed));
            }
            Err(error) => errors.push(AssembleError::Panel {
                panel: panel.name.clone(),
                error,
            }),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    let mut seams = Vec::new();
    let mut seam_bends = Vec::new();
    let bend = 0.5 * (opts.fabric.bend[0] + opts.fabric.bend[1]) / (h * h);
    for (i, st) in pattern.stitches.iter().enumerate() {
        for (sa, sb) in stitch_pairs(&sampled, st) {
            let a = outline_particle[st.a.panel][sa];
            let b = outline_particle[st.b.panel][sb];
            if a == b {
                continue;
            }
            seams.push(SeamPair { a, b, stitch: i });
            let ia = inner_neighbour(&pieces[st.a.panel].1, st.a.panel, sa, &sampled, to_m);
            let ib = inner_neighbour(&pieces[st.b.panel].1, st.b.panel, sb, &sampled, to_m);
            if let (Some(ia), Some(ib), true) = (ia, ib, bend > 0.0) {
                let (fa, fb) = (first_of(&pieces, st.a.panel), first_of(&pieces, st.b.panel));
                seam_bends.push(Bend {
                    nodes: vec![a, b, fa + ia, fb + ib],
                    weights: vec![-1.0, -1.0, 1.0, 1.0],
                    c: bend,
                });
            }
        }
    }
    let seam_k = SEAM_STIFFNESS * opts.fabric.stretch[0].max(opts.fabric.stretch[1]);
    let edge_particles = edge_particles(&sampled, &outline_particle);
    let waist = labelled(pattern, &edge_particles, super::waist::WAIST_LABEL);
    Ok(Assembled {
        pieces,
        seams,
        seam_k,
        seam_bends,
        waist,
        edge_particles,
    })
}

/// Each panel edge's particles, from its start to its end, `[panel][edge]`.
fn edge_particles(
    sampled: &[super::sample::SampledPanel],
    outline_particle: &[Vec<u32>],
) -> Vec<Vec<Vec<u32>>> {
    sampled
        .iter()
        .zip(outline_particle)
        .map(|(s, particle)| {
            let n = s.points.len();
            (s.edge_start.iter().zip(&s.segments))
                .map(|(&first, &count)| (0..=count).map(|j| particle[(first + j) % n]).collect())
                .collect()
        })
        .collect()
}

/// The particles of every edge labelled `label`, sorted, each once.
fn labelled(pattern: &Pattern, edge_particles: &[Vec<Vec<u32>>], label: &str) -> Vec<u32> {
    let mut out = Vec::new();
    for (panel, edges) in pattern.panels.iter().zip(edge_particles) {
        for (l, particles) in panel.labels.iter().zip(edges) {
            if l.as_deref() == Some(label) {
                out.extend(particles);
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// The first model particle of panel `k`.
fn first_of(pieces: &[(String, Piece, Fabric, Vec<Point3>)], k: usize) -> u32 {
    pieces[..k].iter().map(|p| p.1.flat.len() as u32).sum()
}

/// The particle of `piece` one step inside the outline from sample `s` of panel `k`: the
/// spring neighbour of the sample's particle most nearly along the outline's inward normal
/// there (within 45 degrees), as a piece index.
fn inner_neighbour(
    piece: &Piece,
    k: usize,
    s: usize,
    sampled: &[super::sample::SampledPanel],
    to_m: f64,
) -> Option<u32> {
    let pts = &sampled[k].points;
    let n = pts.len();
    let (prev, next) = (pts[(s + n - 1) % n], pts[(s + 1) % n]);
    let t = (next - prev) * to_m;
    let area: f64 = (0..n)
        .map(|i| pts[i].coords.perp(&pts[(i + 1) % n].coords))
        .sum();
    // Inside is to the left of the direction of travel of a counter-clockwise outline.
    let inward = if area > 0.0 {
        Vec2::new(-t.y, t.x)
    } else {
        Vec2::new(t.y, -t.x)
    };
    let inward = inward.try_normalize(0.0)?;
    let here = Point2::from(pts[s].coords * to_m);
    let me = piece.flat.iter().position(|q| *q == here)? as u32;
    piece
        .springs
        .iter()
        .filter_map(|sp| match (sp.a == me, sp.b == me) {
            (true, _) => Some(sp.b),
            (_, true) => Some(sp.a),
            _ => None,
        })
        .map(|o| {
            let d = (piece.flat[o as usize] - here).normalize();
            (o, d.dot(&inward))
        })
        .filter(|&(_, c)| c > std::f64::consts::FRAC_1_SQRT_2)
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(o, _)| o)
}

/// The model particle (piece particles numbered from `first`) of each outline sample. `build`
/// keeps every sample as an outline particle at exactly its position (it only adds points on
/// segments longer than the spacing), though a coordinate of -0 may come back as +0 (`a + 0 (b
/// - a)`): the key adds 0 to each, which makes -0 +0 and leaves every other value as it is.
fn sample_particles(piece: &Piece, outline: &[Point2], first: u32) -> Vec<u32> {
    let key = |q: &Point2| ((q.x + 0.0).to_bits(), (q.y + 0.0).to_bits());
    let at: HashMap<(u64, u64), u32> = piece
        .flat
        .iter()
        .enumerate()
        .skip(piece.grid_particles)
        .map(|(i, q)| (key(q), i as u32))
        .collect();
    outline
        .iter()
        .map(|q| {
            first
                + *at
                    .get(&key(q))
                    .expect("every sample is an outline particle")
        })
        .collect()
}

/// The seam springs of `assembled` (to append to the model's springs).
pub fn seam_springs(assembled: &Assembled) -> Vec<Spring> {
    assembled
        .seams
        .iter()
        .map(|s| Spring {
            a: s.a,
            b: s.b,
            rest: 0.0,
            k: assembled.seam_k,
            kind: SpringKind::Seam,
        })
        .collect()
}

/// The largest and mean seam gap at `x`, m (0 without seams).
pub fn seam_gaps(seams: &[SeamPair], x: &[Point3]) -> (f64, f64) {
    if seams.is_empty() {
        return (0.0, 0.0);
    }
    let gaps = seams
        .iter()
        .map(|s| (x[s.a as usize] - x[s.b as usize]).norm());
    let (max, sum) = gaps.fold((0.0f64, 0.0), |(m, t), g| (m.max(g), t + g));
    (max, sum / seams.len() as f64)
}
