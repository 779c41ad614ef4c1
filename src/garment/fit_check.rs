//! The pattern's fit on the body, checked before any simulation: does each closed ring of the
//! sewn garment go round the body where the pattern places it?
//!
//! **Rings.** Sewing identifies the panels' corners: a stitch joins the start of one edge with
//! the end of the other (start with start when `right_wrong`), and union-find over those pairs
//! gives the sewn garment's corners (a dart's two legs meet at its opening, so the dart closes).
//! Every stitch is then one *seam edge* between two sewn corners and every unstitched panel
//! edge one *open edge*. Two kinds of ring close round a body:
//! - **seam rings**: the seam edges between different panels that run more horizontally than
//!   vertically (slope under 45 degrees, both sides), with dangling chains pruned (a shoulder
//!   seam, a horizontal dart), leaving the components whose every corner joins exactly two of
//!   them: a waist seam. Its length counts each stitch once, by its **shorter side**: a gathered
//!   side can be no longer than the side it is sewn to;
//! - **openings**: the open edges chained corner to corner (a hem, a neckline, a cuff, an
//!   armhole). A vent's two sides are part of its hem's ring: the ring can open no wider than
//!   its whole length, so the check is a necessary condition there.
//!
//! Darts are closed in both: their legs are stitches, never part of a ring's length.
//!
//! **Where a ring sits.** The panels' placement puts the ring's samples (each edge at
//! [`RING_SAMPLE`]) in 3D; the ring sits over their height span `[z_lo, z_hi]` (both sides of a
//! seam). Its tilt is the angle between its Newell normal and the vertical. A ring tilted more
//! than [`MAX_TILT_DEG`] (a cuff on a lowered arm) is judged **in its own plane**:
//! the body and the ring are turned so that the ring's normal is vertical, and the rule below
//! is applied there (the body's section across the arm, not a horizontal slice through it);
//! the nearest heights where the body is narrow enough are then not given (they would be
//! along the ring's axis). A ring tilted more than [`MAX_JUDGED_TILT_DEG`] is listed, not
//! judged: an armhole as laid out (its panels flat in front of and behind the body, before
//! sewing brings them round the shoulder) has a plane that cuts the shoulder obliquely, and
//! the section there is no armhole's measure (the hoody's 46 cm armholes, 64 degrees, would
//! need 58 cm of that section, the dress's 53.4 cm ones 58 cm, at 65 degrees); a hood's face has a plane
//! along the head, which the opening does not go round.
//!
//! **The body's girth there.** The body is sliced horizontally every [`STEP`] over the span
//! (and at its ends). Of each slice's loops, those whose area centroid lies inside the ring's
//! horizontal projection are the ones the ring goes round: both legs for a skirt's hem, one leg
//! for a trouser's, the torso but not the arms for a waist seam. Their girth is the perimeter of
//! the convex hull of those loops, the tape measure's girth: cloth bridges every hollow of the
//! body (between the legs, under the bust, the small of the back), so a ring must be at least
//! that long to go round. The narrowest such girth over the span, `g`, judges the ring (the
//! pattern's most favourable reading of where it sits); the widest is reported beside it.
//!
//! **The verdict.** A ring of length `L` fits when `L (1 + s) >= g + 2 pi c`: `s` the strain the
//! garment verdict allows ([`STRAIN_ALLOWANCE`], `measure::Thresholds::max_strain`), `c` the
//! distance the cloth is kept off the body (the fabric's thickness plus the body clearance: a
//! ring at distance `c` outside a convex section is `2 pi c` longer). A ring that does not fit
//! gets the nearest heights above `z_hi` and below `z_lo` where it would (the same rule, slices
//! every [`STEP`] up to the body's top and down to its bottom; none when there is none). It is
//! a warning: the drape still runs, and shows what the pattern does there.

use super::spec::{EdgeRef, Pattern};
use crate::geom::contains;
use crate::math::{newell_normal, uf_root, Point2, Point3, Vec3};
use crate::mesh::slice::{girth, slice};
use crate::mesh::transform::{change_up_point, Up};
use crate::mesh::TriMesh;
use nalgebra::Rotation3;
use serde::Serialize;
use std::collections::HashMap;

/// The strain a ring may take to go round the body: the garment verdict's 5%
/// (`measure::Thresholds::max_strain`).
pub const STRAIN_ALLOWANCE: f64 = 0.05;

/// Rings tilted more than this from horizontal are judged in their own plane, degrees.
pub const MAX_TILT_DEG: f64 = 30.0;

/// Rings tilted more than this from horizontal are not judged, degrees: an armhole (64 and 65
/// degrees in the real patterns) as laid out, its panels flat in front of and behind the body,
/// has a plane that cuts the shoulder obliquely, and a hood's face (88) one along the head.
pub const MAX_JUDGED_TILT_DEG: f64 = 60.0;

/// Height between the body's slices, m.
pub const STEP: f64 = 0.005;

/// Spacing of a ring's samples, m.
pub const RING_SAMPLE: f64 = 0.01;

/// How the fit is checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitCheckOptions {
    /// Distance kept between the cloth and the body, m: the fabric's thickness plus the body
    /// clearance (no default: the garment's settings give it).
    pub clearance: f64,
    /// Strain allowed, a fraction (default [`STRAIN_ALLOWANCE`]).
    pub strain: f64,
    /// Height between slices, m (default [`STEP`]).
    pub step: f64,
}

impl FitCheckOptions {
    /// The defaults with `clearance` (m).
    pub fn with_clearance(clearance: f64) -> Self {
        FitCheckOptions {
            clearance,
            strain: STRAIN_ALLOWANCE,
            step: STEP,
        }
    }
}

/// A bad option.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FitCheckError {
    /// An option out of its range.
    #[error("fit check: {name} {value} must be {rule}")]
    Option {
        /// The option.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        rule: &'static str,
    },
}

/// What a ring is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RingKind {
    /// A chain of stitches between panels (a waist seam).
    Seam,
    /// A chain of open edges (a hem, a neckline, a cuff).
    Opening,
}

/// One ring and the body where it sits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ring {
    /// Seam or opening.
    pub kind: RingKind,
    /// Its edges, `panel:edge` (0-based, as in the file); a seam's as `a:i+b:j` per stitch.
    pub edges: Vec<String>,
    /// The panels it runs along, in the order met.
    pub panels: Vec<String>,
    /// Its length, m (darts closed; a gathered stitch by its shorter side).
    pub length_m: f64,
    /// The heights it spans as placed, m (lowest, highest).
    pub height_m: [f64; 2],
    /// Angle between its plane and the horizontal, degrees.
    pub tilt_deg: f64,
    /// Whether it was judged (see `note` when not).
    pub judged: bool,
    /// Why it was not judged, or how a tilted ring was.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// The body's girth where it sits, m: the narrowest and the widest over its span.
    pub body_girth_m: Option<[f64; 2]>,
    /// What it needs to go round: the narrowest girth plus `2 pi` times the clearance, m.
    pub needed_m: Option<f64>,
    /// What it can give: its length times one plus the strain allowed, m.
    pub available_m: f64,
    /// Whether it goes round (`null`: not judged).
    pub fits: Option<bool>,
    /// When it does not: the nearest height above its span where the body is narrow enough, m
    /// (not given for a ring judged in its own plane).
    pub narrow_enough_above_m: Option<f64>,
    /// ... and below it.
    pub narrow_enough_below_m: Option<f64>,
}

/// The fit check of a pattern on a body.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitCheck {
    /// The strain allowed.
    pub strain_allowance: f64,
    /// The distance kept off the body, m.
    pub clearance_m: f64,
    /// The slices' spacing, m.
    pub step_m: f64,
    /// Every ring found.
    pub rings: Vec<Ring>,
    /// The judged rings that do not go round the body where they sit.
    pub too_short: usize,
}

/// A garment edge between two sewn corners: an open panel edge (one side) or a stitch (two).
struct GEdge {
    from: usize,
    to: usize,
    sides: Vec<EdgeRef>,
    /// A stitch sewn start to start (its second side runs from `from` to `to` too).
    right_wrong: bool,
}

/// A panel edge's samples placed in drapekit's frame (m, z up), from its start to its end.
fn placed(pattern: &Pattern, e: &EdgeRef) -> Vec<Point3> {
    let p = &pattern.panels[e.panel];
    let u = pattern.units_in_meter;
    p.edges[e.edge]
        .sample(&p.vertices, RING_SAMPLE * u)
        .into_iter()
        .map(|q| change_up_point(Point3::from(p.place(q).coords / u), Up::Y, Up::Z))
        .collect()
}

fn length_m(pattern: &Pattern, e: &EdgeRef) -> f64 {
    let p = &pattern.panels[e.panel];
    p.edges[e.edge].length(&p.vertices) / pattern.units_in_meter
}

fn name(pattern: &Pattern, e: &EdgeRef) -> String {
    format!("{}:{}", pattern.panels[e.panel].name, e.edge)
}

/// A garment edge's name: its sides' `panel:edge`, joined by `+`.
fn joined_name(pattern: &Pattern, sides: &[EdgeRef]) -> String {
    let names: Vec<String> = sides.iter().map(|s| name(pattern, s)).collect();
    names.join("+")
}

/// The side that measures a garment edge: a stitch's shorter side (a gathered side can be no
/// longer than the side it is sewn to), an open edge's only one.
fn short_side(pattern: &Pattern, sides: &[EdgeRef]) -> usize {
    let lens: Vec<f64> = sides.iter().map(|s| length_m(pattern, s)).collect();
    usize::from(lens.len() == 2 && lens[1] < lens[0])
}

/// A ring of the sewn garment, as the fit check finds them and in its order, by its edges.
#[derive(Debug, Clone, PartialEq)]
pub struct RingEdges {
    /// Seam or opening.
    pub kind: RingKind,
    /// Its edges' names, as [`Ring::edges`].
    pub names: Vec<String>,
    /// Per garment edge, the panel edge that measures it (a stitch's shorter side).
    pub sides: Vec<EdgeRef>,
}

/// The rings of the sewn garment `pattern` (as [`fit_check`] lists them), by their edges.
pub fn ring_edges(pattern: &Pattern) -> Vec<RingEdges> {
    let (edges, found) = rings(pattern);
    found
        .into_iter()
        .map(|(kind, walk)| {
            let sides = walk.iter().map(|&(e, _)| &edges[e].sides);
            RingEdges {
                kind,
                names: sides.clone().map(|s| joined_name(pattern, s)).collect(),
                sides: sides.map(|s| s[short_side(pattern, s)]).collect(),
            }
        })
        .collect()
}

/// A ring's garment edges in order, each with the direction walked (true: `from` to `to`).
type Walk = Vec<(usize, bool)>;

/// The garment edges of `pattern` and its rings.
fn rings(pattern: &Pattern) -> (Vec<GEdge>, Vec<(RingKind, Walk)>) {
    let (mut corners, stitched) = sew_corners(pattern);
    let mut edges = Vec::new();
    let seam = stitch_edges(pattern, &mut corners, &mut edges);
    let open = open_edges(pattern, &mut corners, &stitched, &mut edges);
    let mut out: Vec<(RingKind, Walk)> = (seam_rings(&edges, seam).into_iter())
        .map(|ring| (RingKind::Seam, ring))
        .collect();
    for ring in chain(&edges, &open) {
        out.push((RingKind::Opening, ring));
    }
    (edges, out)
}

/// The panels' corners, numbered panel after panel, and which of them sewing joins.
struct Corners {
    /// Each panel's first corner.
    first: Vec<usize>,
    /// Union-find over the corners.
    parent: Vec<usize>,
}

impl Corners {
    /// The corners at the start and the end of a panel edge.
    fn ends(&self, pattern: &Pattern, e: &EdgeRef) -> (usize, usize) {
        let edge = &pattern.panels[e.panel].edges[e.edge];
        (
            self.first[e.panel] + edge.start,
            self.first[e.panel] + edge.end,
        )
    }

    /// The sewn corner a corner is part of.
    fn root(&mut self, x: usize) -> usize {
        uf_root(&mut self.parent, x)
    }
}

/// The corners of `pattern` joined by its stitches, and per panel edge whether it is stitched.
fn sew_corners(pattern: &Pattern) -> (Corners, Vec<Vec<bool>>) {
    let first: Vec<usize> = pattern
        .panels
        .iter()
        .scan(0, |s, p| {
            let f = *s;
            *s += p.vertices.len();
            Some(f)
        })
        .collect();
    let total = first
        .last()
        .map_or(0, |f| f + pattern.panels.last().unwrap().vertices.len());
    let mut c = Corners {
        first,
        parent: (0..total).collect(),
    };
    let mut stitched = vec![Vec::new(); pattern.panels.len()];
    for (k, p) in pattern.panels.iter().enumerate() {
        stitched[k] = vec![false; p.edges.len()];
    }
    for st in &pattern.stitches {
        let (a0, a1) = c.ends(pattern, &st.a);
        let (b0, b1) = c.ends(pattern, &st.b);
        let pairs = if st.right_wrong {
            [(a0, b0), (a1, b1)]
        } else {
            [(a0, b1), (a1, b0)]
        };
        for (x, y) in pairs {
            let (x, y) = (c.root(x), c.root(y));
            c.parent[x] = y;
        }
        stitched[st.a.panel][st.a.edge] = true;
        stitched[st.b.panel][st.b.edge] = true;
    }
    (c, stitched)
}

/// A garment edge per stitch, pushed onto `edges`; those that may be part of a seam ring
/// (between different panels, more horizontal than vertical on both sides).
fn stitch_edges(pattern: &Pattern, c: &mut Corners, edges: &mut Vec<GEdge>) -> Vec<usize> {
    let mut seam = Vec::new();
    for st in &pattern.stitches {
        let (a0, a1) = c.ends(pattern, &st.a);
        let horizontal = [&st.a, &st.b].iter().all(|e| {
            let pts = placed(pattern, e);
            let d = pts[pts.len() - 1] - pts[0];
            d.z.abs() < d.xy().norm()
        });
        if st.a.panel != st.b.panel && horizontal {
            seam.push(edges.len());
        }
        edges.push(GEdge {
            from: c.root(a0),
            to: c.root(a1),
            sides: vec![st.a, st.b],
            right_wrong: st.right_wrong,
        });
    }
    seam
}

/// A garment edge per panel edge not `stitched`, pushed onto `edges`; their indices.
fn open_edges(
    pattern: &Pattern,
    c: &mut Corners,
    stitched: &[Vec<bool>],
    edges: &mut Vec<GEdge>,
) -> Vec<usize> {
    let mut open = Vec::new();
    for (k, sewn) in stitched.iter().enumerate() {
        for (j, done) in sewn.iter().enumerate() {
            if !done {
                let e = EdgeRef { panel: k, edge: j };
                let (s, t) = c.ends(pattern, &e);
                open.push(edges.len());
                edges.push(GEdge {
                    from: c.root(s),
                    to: c.root(t),
                    sides: vec![e],
                    right_wrong: false,
                });
            }
        }
    }
    open
}

/// Seam rings: dangling chains of `seam` pruned, the components whose every corner has degree
/// 2 kept.
fn seam_rings(edges: &[GEdge], mut alive: Vec<usize>) -> Vec<Walk> {
    loop {
        let mut degree: HashMap<usize, usize> = HashMap::new();
        for &e in &alive {
            *degree.entry(edges[e].from).or_default() += 1;
            *degree.entry(edges[e].to).or_default() += 1;
        }
        let before = alive.len();
        alive.retain(|&e| degree[&edges[e].from] > 1 && degree[&edges[e].to] > 1);
        if alive.len() == before {
            let two = |e: &usize| degree[&edges[*e].from] == 2 && degree[&edges[*e].to] == 2;
            return (chain(edges, &alive).into_iter())
                .filter(|ring| ring.iter().all(|(e, _)| two(e)))
                .collect();
        }
    }
}

/// Closed chains of `subset` (edges met at shared corners), each edge once.
fn chain(edges: &[GEdge], subset: &[usize]) -> Vec<Walk> {
    let mut at: HashMap<usize, Vec<usize>> = HashMap::new();
    for &e in subset {
        at.entry(edges[e].from).or_default().push(e);
        at.entry(edges[e].to).or_default().push(e);
    }
    let mut used: HashMap<usize, bool> = subset.iter().map(|&e| (e, false)).collect();
    let mut out = Vec::new();
    for &start in subset {
        if used[&start] {
            continue;
        }
        used.insert(start, true);
        let mut ring = vec![(start, true)];
        let home = edges[start].from;
        let mut here = edges[start].to;
        let mut closed = here == home;
        while !closed {
            let next = at[&here].iter().copied().find(|e| !used[e]);
            let Some(e) = next else { break };
            used.insert(e, true);
            let forward = edges[e].from == here;
            here = if forward { edges[e].to } else { edges[e].from };
            ring.push((e, forward));
            closed = here == home;
        }
        if closed {
            out.push(ring);
        }
    }
    out
}

/// The convex-hull girth of the loops of `body` at height `z` whose area centroid lies inside
/// `outline` (the ring's horizontal projection); `None` when the ring goes round none.
fn girth_inside(body: &TriMesh, z: f64, outline: &[Point2]) -> Option<f64> {
    let mut pts = Vec::new();
    for l in slice(body, z)
        .iter()
        .filter(|l| l.closed && l.points.len() >= 3)
    {
        let xy = l.xy();
        if let Some(c) = centroid(&xy) {
            if contains(outline, &c) {
                pts.extend(xy);
            }
        }
    }
    (!pts.is_empty()).then(|| girth(&pts))
}

/// Area centroid of a closed polygon (`None` without area).
fn centroid(p: &[Point2]) -> Option<Point2> {
    let o = p[0];
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for i in 0..p.len() {
        let (u, v) = (p[i] - o, p[(i + 1) % p.len()] - o);
        let w = u.x * v.y - v.x * u.y;
        a += w;
        cx += (u.x + v.x) * w;
        cy += (u.y + v.y) * w;
    }
    (a.abs() > 0.0).then(|| Point2::new(o.x + cx / (3.0 * a), o.y + cy / (3.0 * a)))
}

/// Checks every ring of `pattern` against `body` (metres, z up: drapekit's frame; the
/// pattern's own frame, y up, is turned the same way).
pub fn fit_check(
    pattern: &Pattern,
    body: &TriMesh,
    opts: &FitCheckOptions,
) -> Result<FitCheck, FitCheckError> {
    check_options(opts)?;
    let (edges, found) = rings(pattern);
    let span = body.bbox().map_or((0.0, 0.0), |b| (b.min.z, b.max.z));
    let out: Vec<Ring> = (found.into_iter())
        .map(|(kind, ring)| judge(kind, trace(pattern, &edges, &ring), body, opts, span))
        .collect();
    let too_short = out.iter().filter(|r| r.fits == Some(false)).count();
    Ok(FitCheck {
        strain_allowance: opts.strain,
        clearance_m: opts.clearance,
        step_m: opts.step,
        rings: out,
        too_short,
    })
}

/// Refuses a negative or non-finite clearance or strain, or a step that is not positive.
fn check_options(opts: &FitCheckOptions) -> Result<(), FitCheckError> {
    let bad = |name, value, rule| Err(FitCheckError::Option { name, value, rule });
    if !(opts.clearance.is_finite() && opts.clearance >= 0.0) {
        return bad("clearance", opts.clearance, "0 or more, m");
    }
    if !(opts.strain.is_finite() && opts.strain >= 0.0) {
        return bad("strain", opts.strain, "0 or more");
    }
    if !(opts.step.is_finite() && opts.step > 0.0) {
        return bad("step", opts.step, "a positive length, m");
    }
    Ok(())
}

/// A ring traced through the pattern as placed.
struct Traced {
    /// Its outline: each garment edge's shorter side, in the ring's order (m, z up).
    poly: Vec<Point3>,
    /// The lowest height of every side's samples, m.
    lo: f64,
    /// ... and the highest.
    hi: f64,
    /// Its length, m: each garment edge by its shorter side.
    length: f64,
    /// Its edges' names.
    names: Vec<String>,
    /// The panels it runs along, in the order met.
    panels: Vec<String>,
}

/// Traces `ring` (garment edges of `edges`, each walked forward or not) through the pattern
/// as placed.
fn trace(pattern: &Pattern, edges: &[GEdge], ring: &Walk) -> Traced {
    let mut poly: Vec<Point3> = Vec::new();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut length, mut names, mut panels) = (0.0, Vec::new(), Vec::<String>::new());
    for &(e, forward) in ring {
        let sides = &edges[e].sides;
        let short = short_side(pattern, sides);
        length += length_m(pattern, &sides[short]);
        names.push(joined_name(pattern, sides));
        for (k, s) in sides.iter().enumerate() {
            let pname = &pattern.panels[s.panel].name;
            if !panels.contains(pname) {
                panels.push(pname.clone());
            }
            let mut pts = placed(pattern, s);
            for p in &pts {
                lo = lo.min(p.z);
                hi = hi.max(p.z);
            }
            if k == short {
                // The garment edge runs from `from` to `to` along side 0; side 1 of a
                // stitch runs the other way unless `right_wrong`.
                let reversed = k == 1 && !edges[e].right_wrong;
                if forward == reversed {
                    pts.reverse();
                }
                poly.extend(pts);
            }
        }
    }
    Traced {
        poly,
        lo,
        hi,
        length,
        names,
        panels,
    }
}

/// The Newell normal of `poly` and its angle from the vertical, degrees (90 when it has none).
fn tilt_of(poly: &[Point3]) -> (Vec3, f64) {
    let n = newell_normal(poly.iter().copied());
    let tilt = if n.norm() > 0.0 {
        (n.z.abs() / n.norm()).clamp(-1.0, 1.0).acos().to_degrees()
    } else {
        90.0
    };
    (n, tilt)
}

/// The ring `t` judged against `body` (whose lowest and highest heights are `span`): listed
/// only when tilted past [`MAX_JUDGED_TILT_DEG`], judged in its own plane past
/// [`MAX_TILT_DEG`], else as it sits.
fn judge(
    kind: RingKind,
    t: Traced,
    body: &TriMesh,
    opts: &FitCheckOptions,
    span: (f64, f64),
) -> Ring {
    let (n, tilt) = tilt_of(&t.poly);
    let mut r = Ring {
        kind,
        edges: t.names,
        panels: t.panels,
        length_m: t.length,
        height_m: [t.lo, t.hi],
        tilt_deg: tilt,
        judged: false,
        note: None,
        body_girth_m: None,
        needed_m: None,
        available_m: t.length * (1.0 + opts.strain),
        fits: None,
        narrow_enough_above_m: None,
        narrow_enough_below_m: None,
    };
    if tilt > MAX_JUDGED_TILT_DEG {
        r.note = Some(format!(
            "tilted {tilt:.0} degrees from horizontal (over {MAX_JUDGED_TILT_DEG}): its plane \
             does not cut what it goes round"
        ));
        return r;
    }
    if tilt > MAX_TILT_DEG {
        judge_tilted(&mut r, body, &t.poly, n, opts);
        return r;
    }
    let outline: Vec<Point2> = t.poly.iter().map(|p| Point2::new(p.x, p.y)).collect();
    judge_girth(&mut r, body, &outline, [t.lo, t.hi], opts, Some(span));
    r
}

/// Judges the ring `r` (its outline `poly`, its normal `n`) in its own plane: the body and
/// the ring turned so that `n` is vertical.
fn judge_tilted(r: &mut Ring, body: &TriMesh, poly: &[Point3], n: Vec3, opts: &FitCheckOptions) {
    let up = if n.z < 0.0 { -n } else { n };
    let turn = Rotation3::rotation_between(&up, &Vec3::z()).unwrap_or_else(Rotation3::identity);
    r.note = Some(format!(
        "tilted {:.0} degrees from horizontal: judged in its own plane",
        r.tilt_deg
    ));
    let positions = body.positions.iter().map(|p| turn * p).collect();
    let body = TriMesh::new(positions, body.faces.clone());
    let q: Vec<Point3> = poly.iter().map(|p| turn * p).collect();
    let (lo, hi) = q
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.z), h.max(p.z))
        });
    let outline: Vec<Point2> = q.iter().map(|p| Point2::new(p.x, p.y)).collect();
    judge_girth(r, &body, &outline, [lo, hi], opts, None);
}

/// Judges `r` by the girths of `body` inside `outline` over the heights `lo_hi`, every
/// `opts.step`. A ring judged as it sits (`span`: the body's lowest and highest heights)
/// that does not fit gets the nearest heights above and below where the body is narrow
/// enough.
fn judge_girth(
    r: &mut Ring,
    body: &TriMesh,
    outline: &[Point2],
    [lo, hi]: [f64; 2],
    opts: &FitCheckOptions,
    span: Option<(f64, f64)>,
) {
    let extra = std::f64::consts::TAU * opts.clearance;
    let available = r.available_m;
    let steps = ((hi - lo) / opts.step).ceil().max(0.0) as usize;
    let girths: Vec<f64> = (0..=steps)
        .map(|i| (lo + i as f64 * opts.step).min(hi))
        .filter_map(|z| girth_inside(body, z, outline))
        .collect();
    if girths.is_empty() {
        r.note = Some("goes round no part of the body at its height".into());
        return;
    }
    let g_min = girths.iter().copied().fold(f64::INFINITY, f64::min);
    let g_max = girths.iter().copied().fold(0.0, f64::max);
    let needed = g_min + extra;
    let fits = available >= needed;
    r.judged = true;
    r.body_girth_m = Some([g_min, g_max]);
    r.needed_m = Some(needed);
    r.fits = Some(fits);
    let Some((bottom, top)) = span.filter(|_| !fits) else {
        return;
    };
    let narrow = |z: f64| girth_inside(body, z, outline).is_some_and(|g| g + extra <= available);
    let up = ((top - hi) / opts.step).floor().max(0.0) as usize;
    r.narrow_enough_above_m = (1..=up)
        .map(|i| hi + i as f64 * opts.step)
        .find(|&z| narrow(z));
    let down = ((lo - bottom) / opts.step).floor().max(0.0) as usize;
    r.narrow_enough_below_m = (1..=down)
        .map(|i| lo - i as f64 * opts.step)
        .find(|&z| narrow(z));
}
