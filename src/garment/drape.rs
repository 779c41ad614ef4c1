//! Sewing a garment on a body and letting it hang (`method.md` s. 0 and 5).
//!
//! The panels start where the pattern places them around the body. **Stage 1, sewing**:
//! gravity off, no friction, the seam springs (`assemble`) pull each stitch's two sides
//! together while the body collides. Their constant is then [`SEW_WEIGHT`] times the mean
//! particle's `m / h^2`, a tenth of the body contacts' weight (`CONTACT_WEIGHT`): where a
//! seam's straight path crosses the body (a shoulder seam, a side piece sewn to a front one)
//! the contact holds and the sides slide round the body, instead of being pulled through it
//! (with the stiff seam constant they were: gaps of 150 mm stayed open at the shoulders of
//! `dress_pencil`). Stage 1 ends when every seam gap is at most `seam_closed`, when the
//! mean gap stops shrinking (by less than a hundredth over ten checks), or at `sew_max`.
//! **Stage 2, drape**: gravity on, friction back, the seams at their full constant (stiff
//! springs of rest length 0, `SEAM_STIFFNESS`), which closes what sewing left; it ends
//! when the cloth is at rest (kinetic energy below that of the whole garment moving at
//! [`REST_SPEED`] over a window, `sim::watch::Rest`) or at `settle_max`.
//!
//! The body is a fixed collider in drapekit's frame (metres, z up); `body_frame` brings a
//! GarmentCode body (y up) there.

use super::assemble::{
    assemble, seam_gaps, seam_springs, AssembleError, AssembleOptions, SeamPair,
};
use super::spec::Pattern;
use crate::cloth::elements::SpringKind;
use crate::cloth::integrate::SolverSettings;
use crate::cloth::model::ClothModel;
use crate::collide::Collider;
use crate::math::{Point3, Vec3};
use crate::mesh::TriMesh;
use crate::sim::{self, SimError, Stop, World};
use serde::Serialize;

/// A particle moving slower than this is at rest, m/s: the reference pipeline's 0.3 mm per
/// 1/60 s frame.
pub const REST_SPEED: f64 = 0.018;

/// The sewing seams' weight relative to the mean particle's `m / h^2` (module notes).
pub const SEW_WEIGHT: f64 = 10.0;

/// Checks over which sewing must make progress.
const STALL: usize = 10;

/// Gravity in drapekit's frame, m/s^2.
pub const GRAVITY: Vec3 = Vec3::new(0.0, 0.0, -9.81);

/// How a garment is sewn and draped.
#[derive(Debug, Clone, PartialEq)]
pub struct GarmentSettings {
    /// Spacing and fabric.
    pub assemble: AssembleOptions,
    /// The solver (default: projective dynamics at 10 ms).
    pub solver: SolverSettings,
    /// Friction between the garment and the body (default 0.5, the reference pipeline's).
    pub friction: f64,
    /// Sewing ends when every seam gap is at most this, m (default 1 mm).
    pub seam_closed: f64,
    /// Longest sewing, simulated s (default 2).
    pub sew_max: f64,
    /// Longest drape after sewing, simulated s (default 8).
    pub settle_max: f64,
    /// Simulated time between seam checks while sewing, s (default 0.02).
    pub check_every: f64,
}

impl Default for GarmentSettings {
    fn default() -> Self {
        GarmentSettings {
            assemble: AssembleOptions::default(),
            solver: SolverSettings::default(),
            friction: 0.5,
            seam_closed: 1e-3,
            sew_max: 2.0,
            settle_max: 8.0,
            check_every: 0.02,
        }
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
}

/// A sewn and draped garment.
#[derive(Debug)]
pub struct Garment {
    /// The cloth and the body at the end.
    pub world: World,
    /// The seam springs' ends.
    pub seams: Vec<SeamPair>,
    /// Stage 1.
    pub sew: StageReport,
    /// Stage 2.
    pub drape: StageReport,
}

/// What stops a garment.
#[derive(Debug, thiserror::Error)]
pub enum GarmentError {
    /// The pattern does not make cloth.
    #[error("{}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"))]
    Assemble(Vec<AssembleError>),
    /// The body has no faces.
    #[error("the body has no faces")]
    EmptyBody,
    /// The simulation failed.
    #[error(transparent)]
    Sim(#[from] SimError),
}

/// The world of a garment on a body (metres, z up): the pattern assembled with its seams,
/// gravity off (sewing comes first); and the seams' full constant, N/m.
pub fn garment_world(
    pattern: &Pattern,
    body: TriMesh,
    settings: &GarmentSettings,
) -> Result<(World, Vec<SeamPair>, f64), GarmentError> {
    if body.faces.is_empty() {
        return Err(GarmentError::EmptyBody);
    }
    let assembled = assemble(pattern, &settings.assemble).map_err(GarmentError::Assemble)?;
    let (mut model, x) = ClothModel::assemble(&assembled.pieces, Vec3::zeros());
    model.add_springs(&seam_springs(&assembled));
    model.add_bends(&assembled.seam_bends);
    let fabric = &settings.assemble.fabric;
    // Cells sized for what a particle travels in a step while it falls a body's height.
    let height = body.bbox().map_or(1.0, |b| b.diagonal());
    let travel = (2.0 * GRAVITY.norm() * height).sqrt() * settings.solver.dt;
    let dims = Collider::auto_dims(&body, travel);
    let collider = Collider::new(
        "body".into(),
        body,
        dims,
        fabric.thickness,
        Some(settings.friction),
    );
    let world = World::new(model, x, vec![collider], settings.solver.integrator);
    Ok((world, assembled.seams, assembled.seam_k))
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
    settings: &GarmentSettings,
    progress: &dyn Fn(f64),
) -> Result<StageReport, SimError> {
    let dt = settings.solver.dt;
    let chunk = ((settings.check_every / dt).round() as u64).max(1);
    world.model.gravity = Vec3::zeros();
    // Sides drawn together slide over the body where their straight path meets it (a shoulder
    // seam goes over the shoulder): no friction while sewing.
    let friction: Vec<Option<f64>> = world.colliders.iter().map(|c| c.friction).collect();
    for c in &mut world.colliders {
        c.friction = Some(0.0);
    }
    let m = &world.model;
    let mean_mass = m.mass.iter().sum::<f64>() / m.len().max(1) as f64;
    set_seam_k(&mut world.model, SEW_WEIGHT * mean_mass / (dt * dt));
    let mut report = StageReport::default();
    let gaps = seam_gaps(seams, &world.state.x);
    report.seam_gap_max = gaps.0;
    let mut means = vec![gaps.1];
    while report.seam_gap_max > settings.seam_closed && report.time < settings.sew_max {
        let stats = sim::run_quiet(world, &settings.solver, Stop::Steps(chunk))?;
        // Sewing is quasi-static: what the seams' pull gave the panels is taken away, so they
        // do not fly on past where they meet.
        world.state.v.iter_mut().for_each(|v| *v = Vec3::zeros());
        report.time += stats.time;
        report.steps += stats.steps;
        report.wall_seconds += stats.wall_seconds;
        let gaps = seam_gaps(seams, &world.state.x);
        report.seam_gap_max = gaps.0;
        progress(report.time);
        means.push(gaps.1);
        // Stalled: the mean gap shrank by less than a hundredth over the last STALL checks.
        if means.len() > STALL && means[means.len() - 1] > 0.99 * means[means.len() - 1 - STALL] {
            break;
        }
    }
    for (c, f) in world.colliders.iter_mut().zip(friction) {
        c.friction = f;
    }
    report.done = report.seam_gap_max <= settings.seam_closed;
    Ok(report)
}

/// Stage 2: gravity on, until at rest or `settle_max`.
pub fn settle(
    world: &mut World,
    seams: &[SeamPair],
    seam_k: f64,
    settings: &GarmentSettings,
) -> Result<StageReport, SimError> {
    let dt = settings.solver.dt;
    world.model.gravity = GRAVITY;
    set_seam_k(&mut world.model, seam_k);
    let mass: f64 = world.model.mass.iter().sum();
    let stop = Stop::UntilRest {
        energy: 0.5 * mass * REST_SPEED * REST_SPEED,
        max_steps: ((settings.settle_max / dt).round() as u64).max(1),
    };
    let stats = sim::run_quiet(world, &settings.solver, stop)?;
    Ok(StageReport {
        time: stats.time,
        steps: stats.steps,
        wall_seconds: stats.wall_seconds,
        seam_gap_max: seam_gaps(seams, &world.state.x).0,
        done: stats.at_rest,
    })
}

/// Sews and drapes `pattern` on `body` (metres, z up).
pub fn sew_and_drape(
    pattern: &Pattern,
    body: TriMesh,
    settings: &GarmentSettings,
    progress: &dyn Fn(f64),
) -> Result<Garment, GarmentError> {
    let (mut world, seams, seam_k) = garment_world(pattern, body, settings)?;
    let sew_report = sew(&mut world, &seams, settings, progress)?;
    let drape = settle(&mut world, &seams, seam_k, settings)?;
    Ok(Garment {
        world,
        seams,
        sew: sew_report,
        drape,
    })
}

/// The fraction of particles that move more than `REST_SPEED / 60` (0.3 mm) in the next
/// 1/60 s: the reference pipeline's test of rest. Runs that 1/60 s on `world`.
pub fn moving_fraction(world: &mut World, settings: &SolverSettings) -> Result<f64, SimError> {
    let before: Vec<Point3> = world.state.x.clone();
    let steps = ((1.0 / 60.0 / settings.dt).round() as u64).max(1);
    let stats = sim::run_quiet(world, settings, Stop::Steps(steps))?;
    let limit = REST_SPEED * stats.time;
    let moving = before
        .iter()
        .zip(&world.state.x)
        .filter(|(a, b)| (*b - *a).norm() > limit)
        .count();
    Ok(moving as f64 / before.len().max(1) as f64)
}
