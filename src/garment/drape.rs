//! Sewing a garment on a body and letting it hang (`method.md` s. 0 and 5).
//!
//! The panels start where the pattern places them around the body. **Stage 1, sewing**:
//! gravity off, no friction, the seam springs (`assemble`) pull each stitch's two sides
//! together while the body collides. Their constant is then [`SEW_WEIGHT`] times the mean
//! particle's `m / h^2`: each step moves a free side about half way. (At ten times that, the
//! rows along the seams ran ahead of the stiff cloth behind them: 165% strain after two steps
//! of `dress_pencil`; at this weight 2.6% after 2 s.) A seam whose straight path crosses the
//! body (a shoulder seam) has its sides pulled over it instead, towards a meeting point
//! outside the body, with their pieces following as a whole (`lift`, [`LIFT_WEIGHT`],
//! [`PIECE_LIFT_WEIGHT`]). When the widest or the mean seam gap closes by less than a tenth
//! over ten checks, or so slowly that at that rate the widest would still be open at
//! `sew_max`, the seams pull twice as hard (up to [`SEW_WEIGHT_MAX`]): the gaps are
//! small by then, and a strong pull over a small gap moves the rows little. Stage 1 ends when
//! every seam gap is at most `seam_closed`, when the gaps close that slowly at the strongest
//! pull, or at `sew_max`. With `hold_waist`, the edges a pattern labels as a waist are pulled
//! up or down to a level (the body's natural waist, `waist`) while sewing, as the reference
//! pipeline's attachment does, and sewing also waits until they are within [`HOLD_REACHED`].
//! **Stage 2, drape**: gravity on, friction back, the seams at their full constant (stiff
//! springs of rest length 0, `SEAM_STIFFNESS`), which closes what sewing left; it ends
//! when the cloth is at rest (at most [`REST_FRACTION`] of the particles moving faster than
//! [`REST_SPEED`] over [`REST_FRAMES`] frames of 1/60 s in a row) or at `settle_max`. Cloth against cloth
//! is on in both stages (`self_collision`).
//!
//! The body is a fixed collider in drapekit's frame (metres, z up): the `garment` command
//! turns a GarmentCode body (y up) there, a scene's `[[object]]`s are placed by the scene
//! (`[[garment]]`, with the whole pattern placed by `assemble::Placement`). With several
//! bodies, the first is the one the garment is sewn on (facing, meeting points).

use super::assemble::{
    assemble, seam_gaps, seam_springs, AssembleError, AssembleOptions, Assembled, Placement,
    SeamPair,
};
use super::clear::MovedOut;
use super::spec::Pattern;
use crate::cloth::elements::SpringKind;
use crate::cloth::integrate::direct::BendingHessian;
use crate::cloth::integrate::SolverSettings;
use crate::cloth::model::ClothModel;
use crate::collide::cloth::SelfCollisionOptions;
use crate::collide::Collider;
use crate::math::{Point3, Vec3};
use crate::mesh::transform::{change_up_point, Up};
use crate::mesh::TriMesh;
use crate::sim::{self, Control, SelfContact, SimError, Stop, World};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::AtomicBool;

/// A particle moving slower than this is at rest, m/s: the reference pipeline's 0.3 mm per
/// 1/60 s frame.
pub const REST_SPEED: f64 = 0.018;

/// The longest sewing or settling stage (`--sew-max`, `--settle-max`), simulated s: an hour,
/// 360,000 steps of 10 ms (a garment sews and settles in seconds).
pub const MAX_STAGE_SECONDS: f64 = 3600.0;

/// The drape is at rest when at most this fraction of the particles moved faster than
/// [`REST_SPEED`] over each of [`REST_FRAMES`] frames of 1/60 s in a row: the verdict's test
/// (`measure::Thresholds::moving_fraction`), so a drape that stops at rest passes it. (A
/// kinetic-energy test stopped `shirt_mean` "at rest" after 0.35 s with 93% of the particles
/// moving more than 0.3 mm a frame: the collide phase's corrections move particles that the
/// velocities do not show.)
pub const REST_FRACTION: f64 = 0.015;

/// Frames in a row that must be at rest (see [`REST_FRACTION`]).
pub const REST_FRAMES: u32 = 5;

/// A held waist has reached its level when its particles are on average this close to it, m.
pub const HOLD_REACHED: f64 = 0.005;

/// The farthest a held particle is pulled towards its level in one step's force, m: the
/// waist rises in quasi-static steps (a skirt already sewn round the hips, pulled its whole
/// 19 cm up at once, gained energy from the body's contacts and stopped the run).
pub const HOLD_STEP: f64 = 0.01;

/// The sewing seams' weight relative to the mean particle's `m / h^2` (module notes).
pub const SEW_WEIGHT: f64 = 1.0;

/// The pull towards a seam's meeting point over the body, relative to the particle's
/// `m / dt^2`: each step moves a free side about this fraction of the way.
pub const LIFT_WEIGHT: f64 = 0.3;

/// The default body clearance, in particle spacings: the dip of a spacing-long edge across a
/// ridge of 14 degrees, or on a curve of radius one spacing.
pub const AUTO_CLEARANCE: f64 = 0.125;

/// The pull on a whole piece whose seam sides have meeting points: a uniform acceleration that
/// moves it by this fraction of those sides' mean distance to them per step (a translation:
/// no strain). Without it a stiff panel barely follows a few pulled particles: the shoulder
/// seams of `dress_pencil` on `mean_all` stayed 144 mm open after 2 s of sewing; with it they
/// close, and every seam of the garment closes to 0.4 mm after the drape.
pub const PIECE_LIFT_WEIGHT: f64 = 0.1;

/// Checks over which sewing must make progress.
const STALL: usize = 10;

/// The fraction of the mean seam gap that must close over `STALL` checks before the seams pull
/// harder.
const SLOW: f64 = 0.1;

/// The strongest sewing seams, relative to the mean particle's `m / h^2`.
pub const SEW_WEIGHT_MAX: f64 = 16.0;

/// Projective dynamics' iterations per step for a garment (the solver's default is 5): sewing
/// pulls the seams' rows through stiff cloth in quasi-static steps, and with 5 iterations a
/// two-panel tube round a cylinder and two panels over a bar did not close their seams within
/// `sew_max` (`tests/garment.rs`).
pub const SEW_ITERATIONS: u32 = 10;

/// A garment's integrator unless asked otherwise: implicit Euler. On the issue's five
/// garments at 1 cm in cotton (README, `bench garment`) it brings every one to rest within 8 s
/// (projective dynamics: three of five) with far fewer edges through the body and the cloth:
/// its contacts constrain the motion where projective dynamics pulls with a weight, and its
/// damping settles a drape in about a simulated second.
pub const GARMENT_INTEGRATOR: crate::cloth::integrate::Integrator =
    crate::cloth::integrate::Integrator::ImplicitEuler;

/// A garment's bending Hessian in implicit Euler's factored matrix unless asked otherwise:
/// exact. Lumped (`cloth::integrate::direct`; while sewing, until sewing slows: [`sew`]) has
/// the same forces and states at rest and a factor about half the size, and takes 0.46 to
/// 0.94 of the wall time on the issue's garments, but the hoody, the one garment that
/// passes, passed from one start of three with it against two of three (README, `bench
/// garment --bending-hessian exact,lumped`).
pub const GARMENT_BENDING_HESSIAN: crate::cloth::integrate::direct::BendingHessian =
    crate::cloth::integrate::direct::BendingHessian::Exact;

/// Gravity in drapekit's frame, m/s^2.
pub const GRAVITY: Vec3 = Vec3::new(0.0, 0.0, -9.81);

/// How a garment is sewn and draped.
#[derive(Debug, Clone, PartialEq)]
pub struct GarmentSettings {
    /// Spacing and fabric.
    pub assemble: AssembleOptions,
    /// The solver (default: [`GARMENT_INTEGRATOR`], implicit Euler, at 10 ms).
    pub solver: SolverSettings,
    /// Friction between the garment and the body (default 0.5, the reference pipeline's).
    pub friction: f64,
    /// Sewing ends when every seam gap is at most this, m (default 1 mm).
    pub seam_closed: f64,
    /// Longest sewing, simulated s (default 4).
    pub sew_max: f64,
    /// Longest drape after sewing, simulated s (default 8).
    pub settle_max: f64,
    /// Simulated time between seam checks while sewing, s (default 0.02).
    pub check_every: f64,
    /// Extra distance kept between the cloth's particles and the body, m, on top of the
    /// fabric's thickness; `None` (default): [`AUTO_CLEARANCE`] times the particle spacing.
    /// A straight cloth edge between two particles resting on a curved or faceted body dips
    /// below them (by `L^2 / 8R` on a radius `R`, by about `L/2` times the angle at a ridge of
    /// the body's mesh): without the clearance, edges pass through the body though no particle
    /// does.
    pub body_clearance: Option<f64>,
    /// Cloth against cloth (default on, with `SelfCollisionOptions::default()`); `None` turns
    /// it off (faster; panels may then pass through each other).
    pub self_collision: Option<SelfCollisionOptions>,
    /// Where the edges labelled `lower_interface` (a skirt's or trousers' top) are held while
    /// sewing (`waist`); default [`WaistHold::Off`] (see the README's measurements).
    pub hold_waist: WaistHold,
    /// Start from the placed panels moved by a tenth of a micron, with this seed
    /// (`perturb::perturb`, `perturb::PERTURB_M`): runs with several seeds give the spread of
    /// a garment's measures. `None` (default): the placement exactly.
    pub perturb: Option<u64>,
    /// Move each panel placed through the first body out along its normal before sewing
    /// (`clear`; default on). Off: the panels are sewn where the pattern puts them.
    pub clear_panels: bool,
    /// Sew at this particle spacing, m, then carry the sewn cloth onto the pattern at
    /// `assemble.spacing` for the drape (`transfer`), when it is coarser than that spacing;
    /// `None` (default): sew and drape at the same spacing.
    pub sew_spacing: Option<f64>,
    /// The drape's seams stiffen from the sewing's strongest pull to their full constant by
    /// this factor every `check_every`, gravity and friction on ([`SEAM_RAMP`], 2: 16 checks,
    /// 0.32 s, for cotton at 1 cm, counted in the drape). `None` (default): at their full
    /// constant at once, which shuts the gaps sewing left in one step and stretches the cloth
    /// beside them (README, `garment --seam-ramp`: what each does to the issue's garments).
    pub seam_ramp: Option<f64>,
}

/// The factor a check by which the drape's seams stiffen when ramped
/// ([`GarmentSettings::seam_ramp`]; measured in the README).
pub const SEAM_RAMP: f64 = 2.0;

/// Where a garment's waist edges are held while sewing (`waist`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum WaistHold {
    /// At the first body's natural waist (`waist::natural_waist`), when the pattern labels
    /// waist edges.
    Auto,
    /// Not held.
    #[default]
    Off,
    /// At this height in the simulation's frame (z up; metres for the `garment` command).
    Level(f64),
}

/// A waist held while sewing: its particles and the height they are pulled to.
#[derive(Debug, Clone, PartialEq)]
pub struct Hold {
    /// The held particles (the edges labelled `waist::WAIST_LABEL`).
    pub particles: Vec<u32>,
    /// The height, in the simulation's frame.
    pub level: f64,
    /// The body's girth there when the level is its natural waist (`WaistHold::Auto`).
    pub girth: Option<f64>,
    /// Per piece, the piece with held particles it follows, if it has none of its own but
    /// hangs from one through seams that are not at the held edges (a skirt sewn to a held
    /// waistband follows the band; a bodice sewn to a held skirt top does not follow it).
    pub followers: Vec<Option<usize>>,
}

/// What a held waist did while sewing.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HoldReport {
    /// Held particles.
    pub particles: usize,
    /// The height they were pulled to, in the simulation's frame.
    pub level: f64,
    /// The body's natural-waist girth there, when the level was found on the body.
    pub girth: Option<f64>,
    /// Their mean height when sewing began and ended.
    pub from: f64,
    /// See `from`.
    pub to: f64,
}

impl Default for GarmentSettings {
    fn default() -> Self {
        GarmentSettings {
            assemble: AssembleOptions::default(),
            solver: SolverSettings {
                integrator: GARMENT_INTEGRATOR,
                iterations: SEW_ITERATIONS,
                bending_hessian: GARMENT_BENDING_HESSIAN,
                ..SolverSettings::default()
            },
            friction: 0.5,
            seam_closed: 1e-3,
            sew_max: 4.0,
            settle_max: 8.0,
            check_every: 0.02,
            self_collision: Some(SelfCollisionOptions::default()),
            body_clearance: None,
            hold_waist: WaistHold::Off,
            perturb: None,
            clear_panels: true,
            sew_spacing: None,
            seam_ramp: None,
        }
    }
}

/// A garment setting out of range.
#[derive(Debug, Clone, PartialEq)]
pub struct SettingProblem {
    /// The setting: `spacing`, `friction`, `cloth_friction`, `body_clearance`, `sew_max`,
    /// `settle_max` or `integrator`.
    pub field: &'static str,
    /// Its value (NaN for the integrator).
    pub value: f64,
    /// What it must be.
    pub message: String,
}

/// The finest and the coarsest particle spacing of a garment, m.
pub const SPACING_RANGE: [f64; 2] = [0.002, 0.1];

impl GarmentSettings {
    /// Every setting out of range, before any work: the spacing within [`SPACING_RANGE`],
    /// frictions and the body clearance 0 or more, each stage positive and at most
    /// [`MAX_STAGE_SECONDS`], an integrator that steps at 10 ms (not an explicit one).
    pub fn problems(&self) -> Vec<SettingProblem> {
        let mut out = Vec::new();
        let mut bad = |field, value, message: String| {
            out.push(SettingProblem {
                field,
                value,
                message,
            })
        };
        let h = self.assemble.spacing;
        let [lo, hi] = SPACING_RANGE;
        if !(h.is_finite() && (lo..=hi).contains(&h)) {
            bad("spacing", h, format!("must be {lo} to {hi} m"));
        }
        if let Some(s) = self.sew_spacing {
            if !(s.is_finite() && (lo..=hi).contains(&s)) {
                bad("sew_spacing", s, format!("must be {lo} to {hi} m"));
            } else if s < h {
                let m = format!("must be at least the spacing ({h} m): sewing is the coarse stage");
                bad("sew_spacing", s, m);
            }
        }
        let cloth_friction = self.self_collision.map_or(0.0, |o| o.friction);
        let clearance = self.body_clearance.unwrap_or(0.0);
        for (field, v) in [
            ("friction", self.friction),
            ("cloth_friction", cloth_friction),
            ("body_clearance", clearance),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                bad(field, v, "must be a number, 0 or more".into());
            }
        }
        if let Some(f) = self.seam_ramp {
            if !(f.is_finite() && f > 1.0) {
                bad("seam_ramp", f, "must be a factor above 1 (or off)".into());
            }
        }
        if let WaistHold::Level(z) = self.hold_waist {
            if !z.is_finite() {
                bad("hold_waist", z, "must be a finite height, m".into());
            }
        }
        for (field, t) in [("sew_max", self.sew_max), ("settle_max", self.settle_max)] {
            if !(t.is_finite() && t > 0.0 && t <= MAX_STAGE_SECONDS) {
                let m = format!(
                    "must be a positive number of simulated seconds, at most {MAX_STAGE_SECONDS}"
                );
                bad(field, t, m);
            }
        }
        if self.solver.integrator.is_explicit() {
            let m = format!(
                "{}: garments step at 10 ms; use projective-dynamics or implicit-euler",
                self.solver.integrator
            );
            bad("integrator", f64::NAN, m);
        }
        out
    }
}

/// What one stage did.
#[derive(Debug, Clone, Default, Serialize)]
pub struct StageReport {
    /// Simulated time, s.
    pub time: f64,
    /// Steps.
    pub steps: u64,
    /// Wall time, s.
    pub wall_seconds: f64,
    /// Largest seam gap at its end, m.
    pub seam_gap_max: f64,
    /// Whether it reached its goal (seams closed; at rest).
    pub done: bool,
    /// Sewing: the seams' weight at the end, in mean `m / h^2` (0 for the drape).
    pub sew_weight: f64,
    /// Sewing with a lumped bending Hessian: the simulated time, s, at which it slowed and
    /// went on with the exact one (`None`: it did not, or the Hessian was exact throughout).
    pub exact_from: Option<f64>,
    /// Drape: the fraction of particles that moved more than [`REST_SPEED`] times 1/60 s over
    /// the last frame of 1/60 s (the verdict's test, measured in the run itself: a new run
    /// would rebuild the solver, whose contact weights start afresh, and jolt the cloth);
    /// `None` for sewing, or for a drape shorter than a frame.
    pub moving_fraction: Option<f64>,
    /// Drape: the checks the seams were ramped over ([`GarmentSettings::seam_ramp`]; 0 when
    /// off, and for sewing).
    pub ramp_checks: usize,
}

/// A sewn and draped garment.
#[derive(Debug)]
pub struct Garment {
    /// The cloth and the body at the end.
    pub world: World,
    /// The seam springs' ends.
    pub seams: Vec<SeamPair>,
    /// The panels placed through the body and moved out before sewing (`clear`).
    pub moved_out: Vec<MovedOut>,
    /// The waist held while sewing, if any.
    pub hold: Option<HoldReport>,
    /// Stage 1.
    pub sew: StageReport,
    /// The particle spacing the garment was sewn at, m (coarser than the drape's with
    /// `GarmentSettings::sew_spacing`).
    pub sew_spacing: f64,
    /// The particles of the cloth that was sewn.
    pub sew_particles: usize,
    /// The stitches still open wider than `seam_closed` when sewing ended (before the drape's
    /// stiff seams pulled them shut), widest first; in the simulation's frame.
    pub sew_open: Vec<super::measure::OpenSeam>,
    /// Stage 2.
    pub drape: StageReport,
    /// How each ring of the garment (a hem, a neckline, a waist seam) hangs at the end
    /// (`garment::hang`).
    pub rings: Vec<super::hang::RingHang>,
}

/// What stops a garment.
#[derive(Debug, thiserror::Error)]
pub enum GarmentError {
    /// The pattern does not make cloth.
    #[error("{}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"))]
    Assemble(Vec<AssembleError>),
    /// There is no body, or it has no faces.
    #[error("the body has no faces")]
    EmptyBody,
    /// Panels whose outline faces into the body (`facing`): each name and the angle between
    /// its normal and the way out, degrees.
    #[error("{} facing into the body (the outline's normal, counter-clockwise seen from outside, points toward the body's axis): {}; reverse the outline or fix the rotation", if .0.len() == 1 { "a panel is" } else { "panels are" }, .0.iter().map(|(n, a)| format!("{n} ({a:.0} degrees from outward)")).collect::<Vec<_>>().join(", "))]
    FacingIn(Vec<(String, f64)>),
    /// The simulation failed.
    #[error(transparent)]
    Sim(#[from] SimError),
}

/// The body of the `garment` command as a collider: its mesh (metres, z up), the automatic
/// grid, no friction of its own (the garment's `friction` applies).
pub fn body_collider(body: TriMesh) -> Collider {
    let dims = Collider::auto_dims(&body);
    Collider::new("body".into(), body, dims, 0.0, None)
}

/// A garment ready to sew (`garment_world`).
#[derive(Debug)]
pub struct GarmentWorld {
    /// The cloth (gravity off) and the bodies.
    pub world: World,
    /// The seam springs' ends.
    pub seams: Vec<SeamPair>,
    /// The seams' full constant, N/m.
    pub seam_k: f64,
    /// The waist held while sewing, if any (`GarmentSettings::hold_waist`).
    pub hold: Option<Hold>,
    /// Each panel edge's particles (`Assembled::edge_particles`).
    pub edge_particles: Vec<Vec<Vec<u32>>>,
    /// The panels that were placed through the body and moved out (`clear`).
    pub moved_out: Vec<MovedOut>,
}

/// The world of a garment on `bodies` (metres, z up; the first is the body the garment is
/// sewn on: the panels' facing is judged against its vertical axis, the seams' meeting
/// points go round it and its natural waist holds the waist edges; the others only collide):
/// the pattern assembled with its seams, gravity off (sewing comes first). Every body keeps the
/// cloth its fabric's thickness and the body clearance off, and gets the garment's friction
/// unless it has its own.
pub fn garment_world(
    pattern: &Pattern,
    mut bodies: Vec<Collider>,
    settings: &GarmentSettings,
) -> Result<GarmentWorld, GarmentError> {
    if bodies.first().is_none_or(|b| b.mesh.faces.is_empty()) {
        return Err(GarmentError::EmptyBody);
    }
    // The margins first: a collider builds its grid, with its margin, the first time it is
    // asked (the panels' inside test below), and a grid built without the cloth's margin would
    // list other faces to the contact.
    let fabric = &settings.assemble.fabric;
    let clearance = settings
        .body_clearance
        .unwrap_or(AUTO_CLEARANCE * settings.assemble.spacing);
    for b in &mut bodies {
        b.margin = fabric.thickness + clearance;
        b.clearance = clearance;
        b.friction = Some(b.friction.unwrap_or(settings.friction));
    }
    let body = &bodies[0];
    // The body's vertical axis in the pattern's own frame (y up) and units: the pattern's
    // placement undone.
    let centre = settings.assemble.placement.unapply(body.bbox.center());
    let c = change_up_point(centre, Up::Z, Up::Y).coords * pattern.units_in_meter;
    let facing = super::facing::facing_in(pattern, [c.x, c.z]);
    if !facing.is_empty() {
        return Err(GarmentError::FacingIn(facing));
    }
    let mut assembled = assemble(pattern, &settings.assemble).map_err(GarmentError::Assemble)?;
    // Only a closed body has an inside to be cleared of (an open one, a seat's shell, would
    // also cost a generalized winding number per particle).
    let moved_out = if settings.clear_panels && body.closed {
        clear_placed(pattern, &mut assembled, body, &settings.assemble.placement)
    } else {
        Vec::new()
    };
    let mut hold = waist_hold(&assembled.waist, &body.mesh, settings.hold_waist);
    let (mut model, x) = ClothModel::assemble(&assembled.pieces, Vec3::zeros());
    if let Some(h) = &mut hold {
        h.followers = followers(&model, &assembled.seams, &h.particles);
    }
    model.add_springs(&seam_springs(&assembled));
    model.add_bends(&assembled.seam_bends);
    let mut world = World::new(model, x, bodies, settings.solver.integrator);
    if let Some(opts) = settings.self_collision {
        let pairs: Vec<[u32; 2]> = assembled.seams.iter().map(|s| [s.a, s.b]).collect();
        world.self_contact = Some(SelfContact::new(&world.model, &pairs, opts));
    }
    Ok(GarmentWorld {
        world,
        seams: assembled.seams,
        seam_k: assembled.seam_k,
        hold,
        edge_particles: assembled.edge_particles,
        moved_out,
    })
}

/// The panels of `assembled` placed through `body`, moved out along their normals
/// (`clear::clear_panels`).
fn clear_placed(
    pattern: &Pattern,
    assembled: &mut Assembled,
    body: &Collider,
    placement: &Placement,
) -> Vec<MovedOut> {
    let normals = super::clear::outward_normals(pattern, placement);
    let mut placed: Vec<&mut Vec<Point3>> =
        (assembled.pieces.iter_mut()).map(|p| &mut p.3).collect();
    super::clear::clear_panels(&mut placed, &normals, body)
}

/// The hold of the waist `particles` on `body` by `how`: none when there are no such
/// particles, when it is off, or when the body has no natural waist.
fn waist_hold(particles: &[u32], body: &TriMesh, how: WaistHold) -> Option<Hold> {
    if particles.is_empty() {
        return None;
    }
    let (level, girth) = match how {
        WaistHold::Off => return None,
        WaistHold::Level(z) => (z, None),
        WaistHold::Auto => {
            let w = super::waist::natural_waist(body)?;
            (w.level, Some(w.girth))
        }
    };
    Some(Hold {
        particles: particles.to_vec(),
        level,
        girth,
        followers: Vec::new(),
    })
}

/// For each piece of `m` without `held` particles, the held piece it hangs from through the
/// `seams` whose ends are not held (the lowest-numbered one if several), if any.
fn followers(m: &ClothModel, seams: &[SeamPair], held: &[u32]) -> Vec<Option<usize>> {
    let n = m.pieces.len();
    let is_held = |i: u32| held.binary_search(&i).is_ok();
    let mut parent: Vec<usize> = (0..n).collect();
    let root = crate::math::uf_root;
    for s in seams.iter().filter(|s| !is_held(s.a) && !is_held(s.b)) {
        let (a, b) = (piece_of(m, s.a as usize), piece_of(m, s.b as usize));
        if let (Some(a), Some(b)) = (a, b) {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    let mut lead = vec![None; n];
    let mut has_held = vec![false; n];
    for &i in held {
        if let Some(p) = piece_of(m, i as usize) {
            has_held[p] = true;
            let r = root(&mut parent, p);
            lead[r] = Some(lead[r].map_or(p, |q: usize| q.min(p)));
        }
    }
    (0..n)
        .map(|p| {
            let r = root(&mut parent, p);
            lead[r].filter(|_| !has_held[p])
        })
        .collect()
}

/// The mean particle mass of `model`, kg: the scale of the seams' pull (`m / h^2`).
fn mean_mass(model: &ClothModel) -> f64 {
    model.mass.iter().sum::<f64>() / model.len().max(1) as f64
}

/// Sets the constant of every seam spring, N/m.
pub fn set_seam_k(model: &mut ClothModel, k: f64) {
    for s in model
        .springs
        .iter_mut()
        .filter(|s| s.kind == SpringKind::Seam)
    {
        s.k = k;
    }
}

/// Stage 1: sews until every seam gap is at most `seam_closed` or `sew_max` has passed.
/// `progress(simulated seconds)` after each check.
pub fn sew(
    world: &mut World,
    seams: &[SeamPair],
    hold: Option<&Hold>,
    settings: &GarmentSettings,
    progress: &dyn Fn(f64),
    cancel: Option<&AtomicBool>,
) -> Result<StageReport, SimError> {
    let mut weight = SEW_WEIGHT;
    // The settings of the steps: a lumped bending Hessian gives way to the exact one when
    // sewing slows (below).
    let mut stage = settings.clone();
    let dt = settings.solver.dt;
    let chunk = ((settings.check_every / dt).round() as u64).max(1);
    world.model.gravity = Vec3::zeros();
    // Sides drawn together slide over the body where their straight path meets it (a shoulder
    // seam goes over the shoulder): no friction while sewing.
    let friction: Vec<Option<f64>> = world.colliders.iter().map(|c| c.friction).collect();
    for c in &mut world.colliders {
        c.friction = Some(0.0);
    }
    let mean_mass = mean_mass(&world.model);
    set_seam_k(&mut world.model, weight * mean_mass / (dt * dt));
    let mut report = StageReport::default();
    let gaps = seam_gaps(seams, &world.state.x);
    report.seam_gap_max = gaps.0;
    let mut history = vec![gaps];
    let held = |w: &World| hold.is_none_or(|h| held_off(h, &w.state.x) <= HOLD_REACHED);
    while (report.seam_gap_max > settings.seam_closed || !held(world))
        && report.time < settings.sew_max
    {
        let stats = sew_chunk(world, seams, hold, &stage, Stop::Steps(chunk), cancel)?;
        report.time += stats.time;
        report.steps += stats.steps;
        report.wall_seconds += stats.wall_seconds;
        let gaps = seam_gaps(seams, &world.state.x);
        report.seam_gap_max = gaps.0;
        progress(report.time);
        history.push(gaps);
        if !sewing_slowed(&history, settings, report.time) {
            continue;
        }
        history.drain(..history.len() - 1);
        if stage.solver.bending_hessian == BendingHessian::Lumped {
            // The lumped matrix damps the bending modes that the last centimetres of a
            // close need (on the jumpsuit, sewing with it alone stalled 61 to 98 mm open
            // in two starts of three): go on with the exact one before pulling harder.
            stage.solver.bending_hessian = BendingHessian::Exact;
            report.exact_from = Some(report.time);
            continue;
        }
        if weight >= SEW_WEIGHT_MAX {
            break;
        }
        weight = (2.0 * weight).min(SEW_WEIGHT_MAX);
        set_seam_k(&mut world.model, weight * mean_mass / (dt * dt));
    }
    report.sew_weight = weight;
    world.model.external.clear();
    for (c, f) in world.colliders.iter_mut().zip(friction) {
        c.friction = f;
    }
    report.done = report.seam_gap_max <= settings.seam_closed && held(world);
    Ok(report)
}

/// One check's worth of sewing (`stop`): the seams' sides lifted towards each other, the held
/// particles pulled to their level, the steps run, and the velocities zeroed after them.
fn sew_chunk(
    world: &mut World,
    seams: &[SeamPair],
    hold: Option<&Hold>,
    stage: &GarmentSettings,
    stop: Stop,
    cancel: Option<&AtomicBool>,
) -> Result<sim::RunStats, SimError> {
    let dt = stage.solver.dt;
    world.model.external.clear();
    lift(world, seams, dt);
    if let Some(h) = hold {
        pull_waist(world, h, dt);
    }
    let quiet = &mut |_: u64, _: &World| Ok(false);
    let stats = run_stage(world, stage, stop, None, quiet, cancel)?;
    // Sewing is quasi-static: what the seams' pull gave the panels is taken away, so they
    // do not fly on past where they meet.
    world.state.v.iter_mut().for_each(|v| *v = Vec3::zeros());
    Ok(stats)
}

/// Whether sewing has slowed, from the seam gaps `(widest, mean)` at each check since the
/// last change (`history`) and the simulated `time` so far.
///
/// Slow: the widest or the mean gap shrank by less than SLOW over the last STALL checks. The
/// seams pull harder (the gaps are smaller now: the rows along them no longer run ahead of the
/// cloth), up to SEW_WEIGHT_MAX; slow at the most, sewing has stalled.
/// Also slow: at the widest gap's rate over those checks it would not close before `sew_max`
/// (a gap shrinking steadily but too slowly, by 11% per ten checks, say).
fn sewing_slowed(history: &[(f64, f64)], settings: &GarmentSettings, time: f64) -> bool {
    let k = history.len();
    let slow = |now: f64, then: f64| now > (1.0 - SLOW) * then;
    let late = |now: f64, then: f64| {
        let left = settings.sew_max - time;
        let checks = STALL as f64 * (settings.seam_closed / now).ln() / (now / then).ln();
        now > settings.seam_closed && checks * settings.check_every > left
    };
    k > STALL
        && (slow(history[k - 1].0, history[k - 1 - STALL].0)
            || slow(history[k - 1].1, history[k - 1 - STALL].1)
            || late(history[k - 1].0, history[k - 1 - STALL].0))
}

/// The held particles' mean vertical distance from their level.
pub fn held_off(hold: &Hold, x: &[Point3]) -> f64 {
    let sum: f64 = hold
        .particles
        .iter()
        .map(|&i| (x[i as usize].z - hold.level).abs())
        .sum();
    sum / hold.particles.len().max(1) as f64
}

/// The held particles' mean height.
pub fn held_mean(hold: &Hold, x: &[Point3]) -> f64 {
    let sum: f64 = hold.particles.iter().map(|&i| x[i as usize].z).sum();
    sum / hold.particles.len().max(1) as f64
}

/// Pulls the held particles vertically towards their level by [`LIFT_WEIGHT`] times each
/// particle's `m / dt^2` times the distance, and their pieces as a whole by
/// [`PIECE_LIFT_WEIGHT`] of the pieces' held particles' mean distance per step (a vertical
/// translation: no strain), through `model.external` (the reference pipeline's vertical
/// attachment, `waist`).
fn pull_waist(world: &mut World, hold: &Hold, dt: f64) {
    let n = world.model.len();
    let x = &world.state.x;
    let m = &mut world.model;
    if m.external.is_empty() {
        m.external.resize(n, Vec3::zeros());
    }
    let mut shift = vec![(Vec3::zeros(), 0usize); m.pieces.len()];
    for &i in &hold.particles {
        let i = i as usize;
        let dz = (hold.level - x[i].z).clamp(-HOLD_STEP, HOLD_STEP);
        m.external[i].z += dz * (LIFT_WEIGHT * m.mass[i] / (dt * dt));
        if let Some(p) = piece_of(m, i) {
            shift[p].0.z += dz;
            shift[p].1 += 1;
        }
    }
    for (p, f) in hold.followers.iter().enumerate() {
        if let Some(q) = f {
            shift[p] = shift[*q];
        }
    }
    follow(m, &shift, dt);
}

/// Each piece with pulled particles follows them as a whole: a uniform acceleration that moves
/// it by [`PIECE_LIFT_WEIGHT`] of their mean displacement per step (no strain). `shift[p]` is
/// piece `p`'s sum of displacements and their count.
fn follow(m: &mut ClothModel, shift: &[(Vec3, usize)], dt: f64) {
    for (p, &(d, c)) in m.pieces.iter().zip(shift) {
        if c > 0 {
            let a = d * (PIECE_LIFT_WEIGHT / c as f64 / (dt * dt));
            for i in p.first..p.first + p.count {
                m.external[i] += a * m.mass[i];
            }
        }
    }
}

/// The piece particle `i` belongs to.
fn piece_of(m: &ClothModel, i: usize) -> Option<usize> {
    m.pieces
        .iter()
        .position(|p| i >= p.first && i < p.first + p.count)
}

/// Pulls both sides of every seam whose straight path crosses the body towards their meeting
/// point (`lift`), by [`LIFT_WEIGHT`] times each particle's `m / dt^2` times its distance, and
/// their pieces as a whole ([`PIECE_LIFT_WEIGHT`]), through `model.external`.
fn lift(world: &mut World, seams: &[SeamPair], dt: f64) {
    let n = world.model.len();
    let Some(body) = world.colliders.first() else {
        return;
    };
    let x = &world.state.x;
    let points: Vec<Option<Point3>> = seams
        .par_iter()
        .map(|s| super::lift::meeting_point(body, &x[s.a as usize], &x[s.b as usize]))
        .collect();
    let m = &mut world.model;
    if points.iter().all(Option::is_none) {
        // No extra force: the step loop skips it.
        return;
    }
    if m.external.is_empty() {
        m.external.resize(n, Vec3::zeros());
    }
    // Per piece: the sum of its sides' displacements to their meeting points, and their count.
    let mut shift = vec![(Vec3::zeros(), 0usize); m.pieces.len()];
    for (s, w) in seams.iter().zip(points) {
        if let Some(w) = w {
            for i in [s.a as usize, s.b as usize] {
                m.external[i] += (w - x[i]) * (LIFT_WEIGHT * m.mass[i] / (dt * dt));
                if let Some(p) = piece_of(m, i) {
                    shift[p].0 += w - x[i];
                    shift[p].1 += 1;
                }
            }
        }
    }
    // The whole piece follows its sides.
    follow(m, &shift, dt);
}

/// Stage 2: gravity on, until at rest or `settle_max`.
pub fn settle(
    world: &mut World,
    seams: &[SeamPair],
    seam_k: f64,
    settings: &GarmentSettings,
    cancel: Option<&AtomicBool>,
) -> Result<StageReport, SimError> {
    let dt = settings.solver.dt;
    world.model.gravity = GRAVITY;
    // The seams stiffen from the sewing's strongest pull to their full constant (`seam_ramp`).
    let mut ramp = (0.0, 0u64, 0.0, 0usize);
    if let Some(factor) = settings.seam_ramp {
        let from = SEW_WEIGHT_MAX * mean_mass(&world.model) / (dt * dt);
        let chunk = ((settings.check_every / dt).round() as u64).max(1);
        let max_steps = ((settings.settle_max / dt).round() as u64).max(1);
        for k in ramp_levels(from, seam_k, factor) {
            if ramp.1 + chunk >= max_steps {
                break;
            }
            set_seam_k(&mut world.model, k);
            let quiet = &mut |_: u64, _: &World| Ok(false);
            let stats = run_stage(world, settings, Stop::Steps(chunk), None, quiet, cancel)?;
            ramp = (
                ramp.0 + stats.time,
                ramp.1 + stats.steps,
                ramp.2 + stats.wall_seconds,
                ramp.3 + 1,
            );
        }
    }
    set_seam_k(&mut world.model, seam_k);
    // One run (the solver and its factorisation kept), the rest test at every frame.
    let frame = ((1.0 / 60.0 / dt).round() as u64).max(1);
    let limit = REST_SPEED * frame as f64 * dt;
    let max_steps = ((settings.settle_max / dt).round() as u64).max(1) - ramp.1;
    let mut before = world.state.x.clone();
    let (mut quiet, mut last) = (0, None);
    let mut at_rest = |_: u64, w: &World| -> Result<bool, SimError> {
        let moving = moved_fraction(&before, &w.state.x, limit);
        before.clone_from(&w.state.x);
        last = Some(moving);
        quiet = if moving <= REST_FRACTION {
            quiet + 1
        } else {
            0
        };
        Ok(quiet >= REST_FRAMES)
    };
    let stop = Stop::Steps(max_steps);
    let stats = run_stage(world, settings, stop, Some(frame), &mut at_rest, cancel)?;
    Ok(StageReport {
        time: ramp.0 + stats.time,
        steps: ramp.1 + stats.steps,
        wall_seconds: ramp.2 + stats.wall_seconds,
        seam_gap_max: seam_gaps(seams, &world.state.x).0,
        done: stats.at_rest,
        sew_weight: 0.0,
        exact_from: None,
        moving_fraction: last,
        ramp_checks: ramp.3,
    })
}

/// The seam constants of the drape's first checks ([`GarmentSettings::seam_ramp`]): from the
/// sewing's strongest pull `from`, N/m, times `factor` a check, up to `to`, the full constant
/// (the last level; none if `from` is already `to` or more).
///
/// ```
/// # use drapekit::garment::drape::ramp_levels;
/// assert_eq!(ramp_levels(1.0, 10.0, 2.0), vec![2.0, 4.0, 8.0, 10.0]);
/// assert!(ramp_levels(10.0, 10.0, 2.0).is_empty());
/// ```
pub fn ramp_levels(from: f64, to: f64, factor: f64) -> Vec<f64> {
    let mut levels = Vec::new();
    let mut k = from;
    while k < to && factor > 1.0 {
        k = (k * factor).min(to);
        levels.push(k);
    }
    levels
}

/// One stage's run: `frame` every `frames` steps (`true`: at rest), ended by `cancel`.
fn run_stage(
    world: &mut World,
    settings: &GarmentSettings,
    stop: Stop,
    frames: Option<u64>,
    frame: &mut dyn FnMut(u64, &World) -> Result<bool, SimError>,
    cancel: Option<&AtomicBool>,
) -> Result<sim::RunStats, SimError> {
    let control = Control {
        cancel,
        ..Control::default()
    };
    sim::run(
        world,
        &settings.solver,
        stop,
        frames,
        frame,
        &|_| {},
        control,
    )
}

/// The fraction of particles that moved more than `limit` (m) from `before` to `after`.
fn moved_fraction(before: &[Point3], after: &[Point3], limit: f64) -> f64 {
    let moving = before
        .iter()
        .zip(after)
        .filter(|(a, b)| (*b - *a).norm() > limit)
        .count();
    moving as f64 / before.len().max(1) as f64
}

/// A garment after sewing: its world, seams and what the sewing did.
struct Sewn {
    world: World,
    seams: Vec<SeamPair>,
    seam_k: f64,
    edge_particles: Vec<Vec<Vec<u32>>>,
    moved_out: Vec<MovedOut>,
    hold: Option<HoldReport>,
    sew: StageReport,
    sew_open: Vec<super::measure::OpenSeam>,
    /// The particles where they were placed (after `clear`), before any perturbation.
    placed: Vec<Point3>,
    /// The spacing sewn at, m, and the sewn cloth's particles.
    sewn_at: (f64, usize),
}

/// Stage 1 of [`sew_and_drape`] at `settings.assemble.spacing`.
fn sew_garment(
    pattern: &Pattern,
    bodies: Vec<Collider>,
    settings: &GarmentSettings,
    progress: &dyn Fn(f64),
    cancel: Option<&AtomicBool>,
) -> Result<Sewn, GarmentError> {
    let GarmentWorld {
        mut world,
        seams,
        seam_k,
        hold,
        edge_particles,
        moved_out,
    } = garment_world(pattern, bodies, settings)?;
    let placed = world.state.x.clone();
    if let Some(seed) = settings.perturb {
        super::perturb::perturb(&mut world.state.x, seed, super::perturb::PERTURB_M);
    }
    let from = hold.as_ref().map(|h| held_mean(h, &world.state.x));
    let sew_report = sew(
        &mut world,
        &seams,
        hold.as_ref(),
        settings,
        progress,
        cancel,
    )?;
    let hold = hold.zip(from).map(|(h, from)| HoldReport {
        particles: h.particles.len(),
        level: h.level,
        girth: h.girth,
        from,
        to: held_mean(&h, &world.state.x),
    });
    let limit_mm = settings.seam_closed * 1e3;
    let sew_open = super::measure::open_seams(pattern, &seams, &world.state.x, limit_mm);
    let sewn_at = (settings.assemble.spacing, world.model.len());
    Ok(Sewn {
        sewn_at,
        world,
        seams,
        seam_k,
        edge_particles,
        moved_out,
        hold,
        sew: sew_report,
        sew_open,
        placed,
    })
}

/// Stage 1 at the coarser `spacing`, then the sewn cloth carried onto the pattern at
/// `settings.assemble.spacing` (`transfer`), at rest, ready for the drape. What the sewing
/// reports (its seams still open, the hold, the panels moved out) is the coarse cloth's.
fn sew_coarse(
    pattern: &Pattern,
    bodies: Vec<Collider>,
    spacing: f64,
    settings: &GarmentSettings,
    progress: &dyn Fn(f64),
    cancel: Option<&AtomicBool>,
) -> Result<Sewn, GarmentError> {
    let mut coarse = settings.clone();
    coarse.assemble.spacing = spacing;
    let sewn = sew_garment(pattern, bodies.clone(), &coarse, progress, cancel)?;
    let fine = GarmentSettings {
        hold_waist: WaistHold::Off,
        ..settings.clone()
    };
    let GarmentWorld {
        mut world,
        seams,
        seam_k,
        edge_particles,
        ..
    } = garment_world(pattern, bodies, &fine)?;
    let placed = world.state.x.clone();
    world.state.x = super::transfer::transfer(&sewn.world.model, &sewn.world.state.x, &world.model);
    Ok(Sewn {
        world,
        seams,
        seam_k,
        edge_particles,
        placed,
        ..sewn
    })
}

/// Sews and drapes `pattern` on `bodies` (as [`garment_world`]). Once `cancel` is set, the run
/// ends after the step it is in with `SimError::Interrupted` (a garment keeps no checkpoint).
pub fn sew_and_drape(
    pattern: &Pattern,
    bodies: Vec<Collider>,
    settings: &GarmentSettings,
    progress: &dyn Fn(f64),
    cancel: Option<&AtomicBool>,
) -> Result<Garment, GarmentError> {
    let coarse = (settings.sew_spacing).filter(|&s| s > settings.assemble.spacing);
    let Sewn {
        mut world,
        seams,
        seam_k,
        edge_particles,
        moved_out,
        hold,
        sew,
        sew_open,
        placed,
        sewn_at,
    } = match coarse {
        Some(s) => sew_coarse(pattern, bodies, s, settings, progress, cancel)?,
        None => sew_garment(pattern, bodies, settings, progress, cancel)?,
    };
    let drape = settle(&mut world, &seams, seam_k, settings, cancel)?;
    let rings = super::hang::hang(pattern, &edge_particles, &placed, &world.state.x);
    Ok(Garment {
        world,
        seams,
        moved_out,
        hold,
        sew,
        sew_spacing: sewn_at.0,
        sew_particles: sewn_at.1,
        sew_open,
        drape,
        rings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moved_fraction_counts_the_particles_past_the_limit() {
        let before = vec![Point3::origin(); 4];
        let after = [0.0, 0.2e-3, 0.4e-3, 1e-3].map(|d| Point3::new(d, 0.0, 0.0));
        // 0.3 mm in a frame: two of the four moved more.
        let f = moved_fraction(&before, &after, REST_SPEED / 60.0);
        assert!((f - 0.5).abs() < 1e-12, "{f}");
    }

    #[test]
    fn the_drape_stops_at_rest_by_the_verdicts_own_test() {
        // A drape that stops at rest must not then fail the verdict's moving test.
        let t = crate::garment::measure::Thresholds::default();
        assert_eq!(t.moving_fraction, REST_FRACTION);
    }
}
