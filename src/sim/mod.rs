//! The drape driver: the world of a scene, the one stepping loop, and what a run measures.
//!
//! Each step runs in four phases, each a function with a clear input and output:
//! 1. **predict** ([`predict`]): the external force (gravity) on each particle and its inertial
//!    position `y = x + h v + h^2 g` (pinned particles stay);
//! 2. **solve**: the integrator's [`Solver`] turns the state into new positions and velocities
//!    (explicit: one particle at a time; implicit Euler: Newton and conjugate gradients;
//!    projective dynamics: local/global iterations on a prefactored matrix);
//! 3. **collide** ([`collide`]): each particle's segment from its old to its new position is
//!    tested against the objects it can reach (`collide::contact`: the paper's test, thickness,
//!    sliding); the cloth's box, grown by twice the largest distance a particle moved in the last
//!    step, decides which objects are reachable, and an object's grid is built the first time;
//! 4. **measure**: every [`CHECK_EVERY`] steps the energy watch (`watch`) and the rest test.
//!
//! With `until_rest`, the cloth is at rest when its kinetic energy stays below the threshold over
//! a window of at least 0.05 s and does not rise over it. Parallel loops work on fixed chunks of
//! particles (`par`), so results do not depend on the number of threads.

pub mod checkpoint;
pub mod measure;
pub mod reference;
pub mod seams;
pub mod settings;
pub mod watch;

pub use checkpoint::{Checkpoint, CheckpointError};
pub use measure::{
    drape_coefficient, inside, min_clearance, particles_inside, placement_warnings, strain,
};
pub use settings::{Cells, Stop};
pub use watch::{Instability, StabilityCheck};

use crate::cloth::elements::{Spring, SpringKind};
use crate::cloth::fabric::Fabric;
use crate::cloth::integrate::{
    self, Integrator, SolveStats, Solver, SolverSettings, StepIn, StepOut,
};
use crate::cloth::model::ClothModel;
use crate::cloth::pattern;
use crate::cloth::stability;
use crate::cloth::state::{ClothState, Contact};
use crate::collide::body_points::{self, BodyPoints, Pushed};
use crate::collide::cloth::{resolve_self, ClothHash, SelfCloth, SelfCollisionOptions, SelfStats};
use crate::collide::contact;
use crate::collide::Collider;
use crate::math::{Aabb, Point3, Vec3};
use crate::mesh::prepare::{prepare, PrepareOptions};
use crate::mesh::transform::{change_up, Up};
use crate::mesh::TriMesh;
use crate::par;
use crate::scene::{Scene, SceneError};
use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Steps between stability checks (and progress updates) at small steps.
pub const CHECK_EVERY: u64 = 16;

/// Steps between checks at step `dt`: [`CHECK_EVERY`] below 1 ms, every step from there (a
/// large step is expensive enough, and an unstable one must be caught early).
pub fn check_every(dt: f64) -> u64 {
    if dt >= 1e-3 {
        1
    } else {
        CHECK_EVERY
    }
}

/// Particles per work unit of the collide phase: small, because the particles in contact (the
/// expensive ones) are neighbours in the numbering, and work stealing must spread them.
pub const COLLISION_CHUNK: usize = 64;

/// The largest `k dt^2 / m` (a spring's constant times the step squared over its lighter
/// particle's mass) the implicit integrators accept: their matrices are `M + dt^2 K`, whose
/// conditioning grows with it, and beyond about `1e15` the masses vanish in the rounding of
/// 16 digits (a free piece's matrix is then singular). Real fabrics give 1e5 (cotton, 1 cm,
/// 10 ms) to 1e7 (1 mm); a scene beyond this is refused before its first step.
pub const RATIO_MAX: f64 = 1e12;

/// The `k dt^2 / m` that [`SimError::Singular`]'s advice aims at.
pub const RATIO_HINT: f64 = 1e10;

/// The stiffest spring's `k / m` (over its lighter particle), 1/s^2, and its piece's name:
/// times `dt^2`, the ratio [`RATIO_MAX`] bounds.
pub fn stiffest(model: &ClothModel) -> (f64, String) {
    let (k_m, a) = (model.springs.iter())
        .map(|s| {
            let m = model.mass[s.a as usize].min(model.mass[s.b as usize]);
            (s.k / m, s.a as usize)
        })
        .fold((0.0, 0), |best, r| if r.0 > best.0 { r } else { best });
    let piece = (model.pieces.iter())
        .find(|p| (p.first..p.first + p.count).contains(&a))
        .map_or_else(String::new, |p| p.name.clone());
    (k_m, piece)
}

/// The error of a step whose matrix was not positive definite (step `step`, 1-based; 0:
/// refused before the first).
fn singular(model: &ClothModel, integrator: Integrator, dt: f64, step: u64) -> SimError {
    let (k_m, piece) = stiffest(model);
    let ratio = k_m * dt * dt;
    SimError::Singular {
        step,
        time: step as f64 * dt,
        integrator,
        dt,
        piece,
        ratio,
        // From k / m, not the ratio: a step of 1e300 s squares to infinity.
        hint: (RATIO_HINT / k_m).sqrt().min(dt),
    }
}

/// Where a run stopped, for [`SimError::Singular`]: step 0 is before the first.
fn when(step: u64, time: f64) -> String {
    if step == 0 {
        "before its first step".into()
    } else {
        format!("at step {step} (t = {} s)", crate::math::short(time))
    }
}

/// Errors of a run.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The run went unstable.
    #[error(
        "the simulation went unstable at step {step} (t = {} s, {reason}) with {integrator} and dt = {dt:e} s; the largest stable step estimated for these fabrics and spacings is {estimate:.3e} s: {advice}",
        crate::math::short(*time)
    )]
    Unstable {
        step: u64,
        time: f64,
        reason: Instability,
        integrator: Integrator,
        dt: f64,
        estimate: f64,
        advice: String,
    },
    /// The solver's matrix was not positive definite in double precision, or would not be
    /// (`ratio` above [`RATIO_MAX`]: refused at step 0): a fabric far too stiff for the step
    /// (`ratio`: the stiffest spring's `k dt^2 / m`).
    #[error(
        "the {integrator} step's matrix is not positive definite in double precision {}: the stiffest spring (piece '{piece}') has k dt^2 / m = {ratio:.1e}, too many orders of magnitude above the particles' inertia for 16 digits; use a smaller dt (dt <= {hint:.1e} s brings it to {RATIO_HINT:.0e}) or a softer fabric",
        when(*step, *time)
    )]
    Singular {
        step: u64,
        time: f64,
        integrator: Integrator,
        dt: f64,
        piece: String,
        ratio: f64,
        hint: f64,
    },
    /// Writing a frame failed.
    #[error("writing frame {step}: {message}")]
    Frame { step: u64, message: String },
    /// The run was cancelled ([`Control::cancel`]); it ended after step `checkpoint.step`,
    /// whose state the checkpoint holds.
    #[error("interrupted after step {}", .0.step)]
    Interrupted(Box<Checkpoint>),
    /// A checkpoint to continue from does not fit the run.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
}

/// Everything a run needs.
#[derive(Debug)]
pub struct World {
    /// The cloth model.
    pub model: ClothModel,
    /// The cloth state.
    pub state: ClothState,
    /// The objects.
    pub colliders: Vec<Collider>,
    /// Highest eigenfrequency of the springs at rest, rad/s (an upper bound).
    pub max_frequency: f64,
    /// Largest stable step of the scene's integrator, s.
    pub stable_step: f64,
    /// Step at which each object's grid was first needed (`None`: never).
    pub grid_built_at: Vec<Option<u64>>,
    /// Cloth against cloth, when the scene needs it (`None`: off, the default).
    pub self_contact: Option<SelfContact>,
    /// What the last run's solver left for the next (`integrate::Analysis`).
    pub analysis: integrate::Analysis,
}

/// Cloth-against-cloth contact in the step loop: its options and the hash it keeps between
/// steps (`collide::cloth`).
#[derive(Debug)]
pub struct SelfContact {
    /// The options.
    pub options: SelfCollisionOptions,
    /// The triangles' hash, with the seams welded.
    pub hash: ClothHash,
    /// Totals over the steps run so far (`seconds` the wall time; `remaining` is the last
    /// step's).
    pub totals: SelfStats,
    /// Per object, its vertices' normals and neighbours for the tips pass
    /// (`collide::body_points`), built when the cloth first reaches it.
    pub tips: Vec<Option<BodyPoints>>,
    /// Whether the tips pass runs (default true; off only to measure what it does).
    pub tips_on: bool,
    /// Tips of the objects found through the cloth, and corrected, over the steps run so far.
    pub tips_pushed: Pushed,
    /// Wall time of the tips pass over the steps run so far, s (its hash rebuild included;
    /// not counted in `totals.seconds`, which is the self pass's).
    pub tips_seconds: f64,
    /// The cloth's mean edge length at rest, m.
    pub edge: f64,
    /// The cloth's largest thickness, m.
    pub thickness_max: f64,
}

impl SelfContact {
    /// Self-contact for `model`, the particle pairs of `seams` welded (sewn sides do not push
    /// each other apart).
    pub fn new(model: &ClothModel, seams: &[[u32; 2]], options: SelfCollisionOptions) -> Self {
        let hash = ClothHash::new(model.len(), &model.triangles, seams);
        let rest: Vec<Point3> = (model.rest.iter())
            .map(|q| Point3::new(q.x, q.y, 0.0))
            .collect();
        let edge = crate::collide::cloth::mean_edge_length(&rest, hash.edges());
        SelfContact {
            options,
            hash,
            totals: SelfStats::default(),
            tips: Vec::new(),
            tips_on: true,
            tips_pushed: Pushed::default(),
            tips_seconds: 0.0,
            edge,
            thickness_max: model.thickness.iter().copied().fold(0.0, f64::max),
        }
    }

    /// The tips pass (`collide::body_points`): the vertices of the reachable objects that poke
    /// through the cloth at `x` push it past them, velocities `v` with it.
    pub fn push_tips(
        &mut self,
        model: &ClothModel,
        colliders: &[Collider],
        reach: &[bool],
        x: &mut [Point3],
        v: &mut [Vec3],
    ) {
        if !self.tips_on || !reach.iter().any(|&r| r) || model.triangles.is_empty() {
            return;
        }
        let start = Instant::now();
        self.tips.resize_with(colliders.len(), || None);
        let c_max = colliders.iter().map(|c| c.clearance).fold(0.0, f64::max);
        let grow = body_points::reach(self.thickness_max + c_max, self.edge);
        let cell = crate::collide::cloth::AUTO_CELL * self.edge;
        self.hash.rebuild(x, &model.triangles, cell.max(grow), grow);
        for (k, c) in colliders.iter().enumerate().filter(|(k, _)| reach[*k]) {
            let points = self.tips[k].get_or_insert_with(|| {
                let others: Vec<&Collider> = (colliders.iter().enumerate())
                    .filter_map(|(j, o)| (j != k).then_some(o))
                    .collect();
                BodyPoints::new(c).without_buried(c, &others, self.thickness_max + c_max)
            });
            let cloth = body_points::Cloth {
                triangles: &model.triangles,
                thickness: &model.thickness,
                thickness_max: self.thickness_max,
                clearance: c.clearance,
                inv_mass: &model.inv_mass,
                edge: self.edge,
            };
            let done = body_points::push_cloth(c, points, &cloth, &self.hash, x, v);
            self.tips_pushed.pairs += done.pairs;
            self.tips_pushed.corrected += done.corrected;
        }
        self.tips_seconds += start.elapsed().as_secs_f64();
    }

    /// The self-contact phase of a step from `x0` to `x1` (velocities `v1`), corrected in place.
    pub fn apply(
        &mut self,
        model: &ClothModel,
        x0: &[Point3],
        x1: &mut [Point3],
        v1: &mut [Vec3],
        dt: f64,
    ) {
        let cloth = SelfCloth::new(&model.triangles, &model.thickness, &model.inv_mass);
        let s = resolve_self(x0, x1, v1, cloth, &mut self.hash, &self.options, dt);
        let t = &mut self.totals;
        t.candidates += s.candidates;
        t.contacts += s.contacts;
        t.corrected += s.corrected;
        t.approaching += s.approaching;
        t.remaining = s.remaining;
        t.seconds += s.seconds;
    }
}

/// The rotation of `deg` degrees about x, then y, then z.
pub fn rotation(deg: [f64; 3]) -> nalgebra::Rotation3<f64> {
    let [a, b, c] = deg.map(f64::to_radians);
    nalgebra::Rotation3::from_axis_angle(&Vec3::z_axis(), c)
        * nalgebra::Rotation3::from_axis_angle(&Vec3::y_axis(), b)
        * nalgebra::Rotation3::from_axis_angle(&Vec3::x_axis(), a)
}

/// Builds the world of a validated scene: objects read, prepared and placed; pieces built and
/// placed; the model assembled.
pub fn load(scene: &Scene) -> Result<World, SceneError> {
    // Every piece and every mesh is checked, and all their problems reported together.
    let mut errors: Vec<SceneError> = Vec::new();
    let mut pieces = Vec::new();
    for (i, p) in scene.pieces.iter().enumerate() {
        match pattern::build_with_holes(&p.outline, &p.holes, p.spacing, &p.fabric, &p.pins) {
            Ok(built) => {
                let r = rotation(p.rotation);
                let placed: Vec<Point3> = built
                    .flat
                    .iter()
                    .map(|q| Point3::from(p.position + r * Vec3::new(q.x, q.y, 0.0)))
                    .collect();
                pieces.push((p.name.clone(), built, p.fabric.clone(), placed));
            }
            Err(error) => errors.push(SceneError::Piece {
                path: scene.path.clone(),
                key: format!(
                    "piece[{}].{}",
                    i + 1,
                    match error {
                        pattern::PatternError::Hole { .. } => "holes",
                        _ => "outline",
                    }
                ),
                error,
            }),
        }
    }
    let meshes = read_objects(scene, &mut errors);
    let sewn = if errors.is_empty() {
        scene_seams(scene, &pieces, &mut errors)
    } else {
        Vec::new()
    };
    if !errors.is_empty() {
        return Err(SceneError::combine(&scene.path, errors));
    }
    let (mut model, x) = ClothModel::assemble(&pieces, scene.gravity);
    let springs: Vec<Spring> = sewn
        .iter()
        .map(|&([a, b], k)| Spring {
            a,
            b,
            rest: 0.0,
            k,
            kind: SpringKind::Seam,
        })
        .collect();
    model.add_springs(&springs);
    let margin = scene
        .pieces
        .iter()
        .map(|p| p.fabric.thickness)
        .fold(0.0, f64::max);
    let colliders = colliders(scene, meshes, margin);
    let pairs: Vec<[u32; 2]> = sewn.iter().map(|s| s.0).collect();
    let mut world = World::new(model, x, colliders, scene.solver.integrator);
    if !pairs.is_empty() {
        // Sewn pieces fold against each other: cloth against cloth, as for garments.
        world.self_contact = Some(SelfContact::new(
            &world.model,
            &pairs,
            crate::collide::cloth::SelfCollisionOptions::default(),
        ));
    }
    Ok(world)
}

/// The scene's objects read, prepared and placed (metres, z up); each problem goes into
/// `errors`.
fn read_objects(scene: &Scene, errors: &mut Vec<SceneError>) -> Vec<TriMesh> {
    let to_m = crate::mesh::transform::Units::factor(scene.units, crate::mesh::transform::Units::M);
    let mut meshes = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        let key = format!("object[{}].mesh", i + 1);
        match crate::io::read_mesh(&o.mesh, &crate::io::ReadOptions::default()) {
            Ok(read) => {
                let mut mesh = read.mesh;
                prepare(&mut mesh, &PrepareOptions::default());
                if mesh.faces.is_empty() {
                    errors.push(SceneError::Key {
                        path: scene.path.clone(),
                        key,
                        message: format!(
                            "{}: no faces remain after cleaning: not a surface to collide with",
                            o.mesh.display()
                        ),
                    });
                    continue;
                }
                change_up(&mut mesh, o.up, Up::Z);
                for p in &mut mesh.positions {
                    *p = Point3::from(p.coords * (o.scale * to_m) + o.translate);
                }
                meshes.push(mesh);
            }
            Err(error) => errors.push(SceneError::Mesh {
                path: scene.path.clone(),
                key,
                error,
            }),
        }
    }
    meshes
}

/// The objects' colliders (grid cells as the scene says), keeping the cloth `margin` (m) off.
fn colliders(scene: &Scene, meshes: Vec<TriMesh>, margin: f64) -> Vec<Collider> {
    scene
        .objects
        .iter()
        .zip(meshes)
        .map(|(o, mesh)| {
            let dims = match scene.cells {
                Cells::Fixed(d) => d,
                Cells::Auto => Collider::auto_dims(&mesh),
            };
            Collider::new(o.name.clone(), mesh, dims, margin, o.friction)
        })
        .collect()
}

/// The scene's objects as colliders, every mesh's problem reported together: what a
/// `[[garment]]` is sewn on (`garment::drape::garment_world` sets their margins).
pub fn load_objects(scene: &Scene) -> Result<Vec<Collider>, SceneError> {
    let mut errors = Vec::new();
    let meshes = read_objects(scene, &mut errors);
    if !errors.is_empty() {
        return Err(SceneError::combine(&scene.path, errors));
    }
    Ok(colliders(scene, meshes, 0.0))
}

/// The scene's seams (`seams`) as particle pairs of the assembled cloth (pieces in order) with
/// their spring constant; each bad side is reported in `errors`.
fn scene_seams(
    scene: &Scene,
    pieces: &[(String, pattern::Piece, Fabric, Vec<Point3>)],
    errors: &mut Vec<SceneError>,
) -> Vec<([u32; 2], f64)> {
    let mut first = vec![0u32];
    for p in pieces {
        first.push(first.last().unwrap() + p.1.flat.len() as u32);
    }
    let mut out = Vec::new();
    for (i, s) in scene.seams.iter().enumerate() {
        let side = |side: &crate::scene::SeamSide, which: &str| {
            let (name, piece, ..) = &pieces[side.piece];
            seams::stretch(piece, name, &side.from, &side.to).map_err(|e| SceneError::Key {
                path: scene.path.clone(),
                key: format!("seam[{}].{which}", i + 1),
                message: e.to_string(),
            })
        };
        match (side(&s.a, "a"), side(&s.b, "b")) {
            (Ok((ia, ta)), Ok((ib, tb))) => {
                let stiff = |k: usize| {
                    let f = &pieces[k].2;
                    f.stretch[0].max(f.stretch[1])
                };
                let k = crate::garment::assemble::SEAM_STIFFNESS
                    * stiff(s.a.piece).max(stiff(s.b.piece));
                // a's `from` meets b's `to`: the sides run opposite ways.
                let tb: Vec<f64> = tb.iter().map(|t| 1.0 - t).collect();
                for (x, y) in seams::pair_by_fraction(&ta, &tb) {
                    let a = first[s.a.piece] + ia[x];
                    let b = first[s.b.piece] + ib[y];
                    out.push(([a, b], k));
                }
            }
            (a, b) => errors.extend(a.err().into_iter().chain(b.err())),
        }
    }
    out
}

impl World {
    /// A world at rest at `x`, with the stability estimate for `integrator`.
    pub fn new(
        model: ClothModel,
        x: Vec<Point3>,
        colliders: Vec<Collider>,
        integrator: Integrator,
    ) -> World {
        let max_frequency = stability::frequency_bound(&model);
        let stable_step = integrator.stable_step(max_frequency, stability::min_damping(&model));
        let n = colliders.len();
        World {
            model,
            state: ClothState::at_rest(x),
            colliders,
            max_frequency,
            stable_step,
            grid_built_at: vec![None; n],
            self_contact: None,
            analysis: integrate::Analysis::default(),
        }
    }
}

/// What a run measured.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RunStats {
    /// Steps taken.
    pub steps: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Wall time of the loop, s (the phases below, and building the solver).
    pub wall_seconds: f64,
    /// Wall time of the predict phase, s.
    pub predict_seconds: f64,
    /// Wall time of the solve phase, s.
    pub solve_seconds: f64,
    /// Wall time of the collide phase, s.
    pub collision_seconds: f64,
    /// Wall time of the measure phase, s.
    pub measure_seconds: f64,
    /// The solver's counters (factorisation time, iterations).
    pub solver: SolveStats,
    /// Whether it stopped because the cloth came to rest.
    pub at_rest: bool,
}

/// Scratch of the predict phase: external forces and inertial positions.
#[derive(Debug, Default)]
pub struct Predicted {
    /// External force per particle, N.
    pub f_ext: Vec<Vec3>,
    /// Inertial position per particle, m.
    pub y: Vec<Point3>,
}

/// The predict phase: gravity and the model's extra forces on each particle, and where it would
/// go without internal forces.
pub fn predict(model: &ClothModel, state: &ClothState, dt: f64, out: &mut Predicted) {
    let n = model.len();
    out.f_ext.resize(n, Vec3::zeros());
    out.y.resize(n, Point3::origin());
    let (x, v) = (&state.x, &state.v);
    let mut dummy = vec![(); n];
    par::for_chunks3(
        256,
        n,
        &mut out.f_ext[..],
        &mut out.y[..],
        &mut dummy[..],
        |base, fs, ys, _| {
            for k in 0..fs.len() {
                let i = base + k;
                let extra = model.external.get(i).copied().unwrap_or_else(Vec3::zeros);
                fs[k] = model.gravity * model.mass[i] + extra;
                ys[k] = if model.pinned(i) {
                    x[i]
                } else {
                    x[i] + v[i] * dt + (model.gravity + extra * model.inv_mass[i]) * (dt * dt)
                };
            }
        },
    );
}

/// Which objects the cloth can reach this step: its box grown by twice the last step's largest
/// travel (conservative).
pub fn reachable(x: &[Point3], colliders: &[Collider], travel: f64) -> Vec<bool> {
    let bx = Aabb::of_points(x).unwrap();
    let grow = 2.0 * travel + 0.01;
    colliders
        .iter()
        .map(|c| {
            let m = c.margin * 2.0 + grow;
            (0..3).all(|k| bx.min[k] <= c.bbox.max[k] + m && bx.max[k] >= c.bbox.min[k] - m)
        })
        .collect()
}

/// The collide phase: every particle's step from `x0` to `x1` (velocity `v1`) against the
/// reachable objects, contacts kept in `contact`; with `friction`, Coulomb friction from the
/// normal velocity each contact removed. Returns the largest distance a particle moved.
#[allow(clippy::too_many_arguments)]
pub fn collide(
    model: &ClothModel,
    colliders: &[Collider],
    reach: &[bool],
    friction: bool,
    dt: f64,
    x0: &[Point3],
    x1: &mut [Point3],
    v1: &mut [Vec3],
    contact: &mut [Option<Contact>],
) -> f64 {
    let any_reach = reach.iter().any(|&r| r);
    let moved = std::sync::Mutex::new(0.0f64);
    par::for_chunks3(
        COLLISION_CHUNK,
        model.len(),
        x1,
        v1,
        contact,
        |base, xs, vs, cs| {
            let mut far: f64 = 0.0;
            for k in 0..xs.len() {
                let i = base + k;
                if any_reach && !model.pinned(i) {
                    let before = vs[k];
                    contact::resolve(
                        colliders,
                        reach,
                        &x0[i],
                        &mut xs[k],
                        &mut vs[k],
                        model.thickness[i],
                        &mut cs[k],
                    );
                    if let (true, Some(ct)) = (friction, cs[k]) {
                        let n = integrate::contact_normal(colliders, &ct);
                        let jn = (vs[k] - before).dot(&n);
                        let mu = integrate::contact_friction(colliders, model, &ct, i);
                        let v_in = vs[k];
                        integrate::coulomb(&mut vs[k], &n, jn, mu);
                        // The position follows the velocity friction took away.
                        xs[k] += (vs[k] - v_in) * dt;
                    }
                } else if !any_reach {
                    cs[k] = None;
                }
                far = far.max((xs[k] - x0[i]).norm_squared());
            }
            let mut m = moved.lock().unwrap();
            *m = m.max(far);
        },
    );
    moved.into_inner().unwrap().sqrt()
}

/// How a run is steered from outside: cancelled, continued from a checkpoint, or run without
/// its stability check.
#[derive(Debug, Clone, Copy, Default)]
pub struct Control<'a> {
    /// Checked before each step: once set (a signal handler sets it), the run ends after the
    /// last finished step with [`SimError::Interrupted`] holding its checkpoint. `None`: never.
    pub cancel: Option<&'a AtomicBool>,
    /// Continue from this checkpoint (of the same world and settings, `Checkpoint::fits`)
    /// instead of the world's state: the run goes on from the step after it, to the same bits
    /// as a run that was never stopped.
    pub resume: Option<&'a Checkpoint>,
    /// Whether the energy watch stops an unstable run (default [`StabilityCheck::On`]; `Off`
    /// is for experiments that show what the watch prevents, never the command line's).
    pub stability: StabilityCheck,
}

/// What the stepping loop keeps besides the world and the solver.
struct Loop {
    watch: watch::Watch,
    rest: watch::Rest,
    stats: RunStats,
    /// Largest distance a particle moved in the last step (for the reach test).
    travel: f64,
}

impl Loop {
    /// The checkpoint after `step`.
    fn checkpoint(&self, world: &World, solver: &dyn Solver, step: u64, dt: f64) -> Checkpoint {
        Checkpoint {
            fingerprint: checkpoint::Fingerprint {
                scene: [0; 32],
                options: String::new(),
            },
            step,
            time: step as f64 * dt,
            state: world.state.clone(),
            travel: self.travel,
            grid_built_at: world.grid_built_at.clone(),
            watch: self.watch.saved(),
            rest: self.rest.saved(),
            stats: RunStats {
                time: step as f64 * dt,
                solver: solver.stats(),
                ..self.stats.clone()
            },
            solver: solver.save(),
            self_contact: world.self_contact.as_ref().map(|s| s.totals),
            frames: Vec::new(),
        }
    }

    /// Puts `c` back into the world, the solver and the loop.
    fn restore(&mut self, c: &Checkpoint, world: &mut World, solver: &mut dyn Solver) {
        world.state.clone_from(&c.state);
        world.grid_built_at.clone_from(&c.grid_built_at);
        if let (Some(sc), Some(t)) = (&mut world.self_contact, c.self_contact) {
            sc.totals = t;
        }
        solver.restore(&c.solver);
        self.watch.restore(&c.watch);
        self.rest.restore(&c.rest);
        self.stats = c.stats.clone();
        self.travel = c.travel;
    }
}

/// A step's scratch: the positions and velocities it makes, and the predict phase's output.
struct Next {
    x: Vec<Point3>,
    v: Vec<Vec3>,
    pred: Predicted,
}

/// Which objects the particles can reach this step (`travel`: the last step's largest move),
/// each object's grid marked as first needed at `step`.
fn reach_phase(world: &mut World, travel: f64, step: u64) -> Vec<bool> {
    let reach = reachable(&world.state.x, &world.colliders, travel);
    for (i, r) in reach.iter().enumerate() {
        if *r && world.grid_built_at[i].is_none() {
            world.grid_built_at[i] = Some(step);
        }
    }
    reach
}

impl Loop {
    /// Step `step`: the prediction, the solve and the collisions (each phase timed), the new
    /// state put in place.
    fn advance(
        &mut self,
        world: &mut World,
        solver: &mut dyn Solver,
        next: &mut Next,
        settings: &SolverSettings,
        step: u64,
    ) -> Result<(), SimError> {
        let t = Instant::now();
        predict(&world.model, &world.state, settings.dt, &mut next.pred);
        self.stats.predict_seconds += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let reach = reach_phase(world, self.travel, step);
        self.solve(world, solver, next, &reach, settings, step)?;
        self.stats.solve_seconds += t.elapsed().as_secs_f64();
        let t = Instant::now();
        self.collide(world, solver, next, &reach, settings);
        if reach.iter().any(|&r| r) || world.self_contact.is_some() {
            self.stats.collision_seconds += t.elapsed().as_secs_f64();
        }
        std::mem::swap(&mut world.state.x, &mut next.x);
        std::mem::swap(&mut world.state.v, &mut next.v);
        self.stats.steps = step;
        Ok(())
    }

    /// The solve phase: the integrator's step from the state to `next` (with the objects in
    /// `reach` for the contacts it handles itself).
    fn solve(
        &mut self,
        world: &mut World,
        solver: &mut dyn Solver,
        next: &mut Next,
        reach: &[bool],
        settings: &SolverSettings,
        step: u64,
    ) -> Result<(), SimError> {
        let dt = settings.dt;
        let World {
            model,
            state,
            colliders,
            ..
        } = &mut *world;
        let input = StepIn {
            model,
            x: &state.x,
            v: &state.v,
            f_ext: &next.pred.f_ext,
            y: &next.pred.y,
            colliders,
            reach,
            dt,
        };
        let mut out = StepOut {
            x: &mut next.x,
            v: &mut next.v,
            contact: &mut state.contact,
        };
        match solver.step(&input, &mut out) {
            Ok(_) => Ok(()),
            Err(_) => Err(singular(model, settings.integrator, dt, step)),
        }
    }

    /// The collide phase on `next`: cloth against cloth first (the body pass has the last
    /// word, so the self pass never leaves a particle inside the body: a particle that starts
    /// a step inside is not caught by the body's segment test), then the objects, then the
    /// objects' tips through the cloth; the work it puts in is counted by the energy watch.
    fn collide(
        &mut self,
        world: &mut World,
        solver: &dyn Solver,
        next: &mut Next,
        reach: &[bool],
        settings: &SolverSettings,
    ) {
        let dt = settings.dt;
        let World {
            model,
            state,
            colliders,
            self_contact,
            ..
        } = &mut *world;
        let (x_new, v_new) = (&mut next.x, &mut next.v);
        // The work the collide phase does on the cloth (its projections can stretch springs
        // at large steps) is counted as work put in; explicit steps are too small to need it.
        let before = (!settings.integrator.is_explicit())
            .then(|| watch::mechanical(model, x_new, v_new, &state.x));
        if let Some(sc) = self_contact {
            sc.apply(model, &state.x, x_new, v_new, dt);
        }
        self.travel = collide(
            model,
            colliders,
            reach,
            solver.friction_in_collide(),
            dt,
            &state.x,
            x_new,
            v_new,
            &mut state.contact,
        );
        if let Some(sc) = self_contact {
            sc.push_tips(model, colliders, reach, x_new, v_new);
        }
        if let Some(e) = before {
            self.watch
                .add_work(watch::mechanical(model, x_new, v_new, &state.x) - e);
        }
        if !model.external.is_empty() {
            let w = par::sum(x_new.len(), |i| {
                model.external[i].dot(&(x_new[i] - state.x[i]))
            });
            self.watch.add_work(w);
        }
    }

    /// The measure phase at a check: the stability check (an error when the run went
    /// unstable), the progress report, and whether the cloth is at rest.
    fn measure(
        &mut self,
        world: &World,
        settings: &SolverSettings,
        step: u64,
        progress: &dyn Fn(u64),
    ) -> Result<bool, SimError> {
        let (integrator, dt) = (settings.integrator, settings.dt);
        if let Err(reason) = self.watch.check(world) {
            return Err(SimError::Unstable {
                step,
                time: step as f64 * dt,
                reason,
                integrator,
                dt,
                estimate: world.stable_step,
                advice: integrator.advice(world.stable_step, world.max_frequency),
            });
        }
        progress(step);
        Ok(self.rest.at_rest(world))
    }
}

/// Runs the world with `settings`. `frame(step, world)` is called every `frames` steps; when
/// it returns `true` the cloth is at rest and the run ends there. `progress(step)` at every
/// check. `control` cancels it or continues it from a checkpoint (`Control::default()`:
/// neither).
pub fn run(
    world: &mut World,
    settings: &SolverSettings,
    stop: Stop,
    frames: Option<u64>,
    frame: &mut dyn FnMut(u64, &World) -> Result<bool, SimError>,
    progress: &dyn Fn(u64),
    control: Control,
) -> Result<RunStats, SimError> {
    let start = Instant::now();
    let dt = settings.dt;
    let integrator = settings.integrator;
    if !integrator.is_explicit() && stiffest(&world.model).0 * dt * dt > RATIO_MAX {
        return Err(singular(&world.model, integrator, dt, 0));
    }
    // Built from the world as loaded (a checkpoint's pinned particles are where they were).
    let mut solver: Box<dyn Solver> =
        integrate::make(settings, &world.model, &world.state.x, &mut world.analysis);
    let mut lp = Loop {
        watch: watch::Watch::new(world).checking(control.stability),
        rest: watch::Rest::new(stop, dt),
        stats: RunStats::default(),
        travel: 0.0,
    };
    let mut first = 1;
    if let Some(c) = control.resume {
        c.fits(world, integrator)?;
        lp.restore(c, world, &mut *solver);
        first = c.step + 1;
    }
    let wall_before = lp.stats.wall_seconds;
    let mut next = Next {
        x: world.state.x.clone(),
        v: world.state.v.clone(),
        pred: Predicted::default(),
    };
    for step in first..=stop.max_steps() {
        if control.cancel.is_some_and(|c| c.load(Ordering::SeqCst)) {
            lp.stats.wall_seconds = wall_before + start.elapsed().as_secs_f64();
            let c = lp.checkpoint(world, &*solver, step - 1, dt);
            return Err(SimError::Interrupted(Box::new(c)));
        }
        lp.advance(world, &mut *solver, &mut next, settings, step)?;
        if step % check_every(dt) == 0 || step == stop.max_steps() {
            let t = Instant::now();
            let done = lp.measure(world, settings, step, progress)?;
            lp.stats.measure_seconds += t.elapsed().as_secs_f64();
            if done {
                lp.stats.at_rest = true;
                break;
            }
        }
        if let Some(k) = frames {
            if step % k == 0 && frame(step, world)? {
                lp.stats.at_rest = true;
                break;
            }
        }
    }
    lp.stats.time = lp.stats.steps as f64 * dt;
    lp.stats.wall_seconds = wall_before + start.elapsed().as_secs_f64();
    lp.stats.solver = solver.stats();
    solver.hand_over(&mut world.analysis);
    Ok(lp.stats)
}

/// Runs the world without frames or progress reports.
pub fn run_quiet(
    world: &mut World,
    settings: &SolverSettings,
    stop: Stop,
) -> Result<RunStats, SimError> {
    let control = Control::default();
    run(
        world,
        settings,
        stop,
        None,
        &mut |_, _| Ok(false),
        &|_| {},
        control,
    )
}

/// A fabric's largest stable step at a spacing, for a lone flat square piece (the README's
/// preset table). The leapfrog step is proportional to the spacing (the springs keep their
/// constants, the masses go with its square):
///
/// ```
/// use drapekit::cloth::{fabric::Fabric, Integrator};
/// use drapekit::sim::stable_step_for;
/// let at_1cm = stable_step_for(&Fabric::cotton(), 0.01, Integrator::Leapfrog);
/// let at_2cm = stable_step_for(&Fabric::cotton(), 0.02, Integrator::Leapfrog);
/// // Conservative: 1.90e-5 s, below the power iteration's 2.95e-5 s (Gershgorin bound).
/// assert!((at_1cm - 1.904e-5).abs() < 0.005e-5, "{at_1cm}");
/// assert!((at_2cm / at_1cm - 2.0).abs() < 0.01);
/// ```
pub fn stable_step_for(fabric: &Fabric, spacing: f64, integrator: Integrator) -> f64 {
    let s = 10.0 * spacing;
    let outline = [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| crate::math::Point2::new(x, y));
    let p = pattern::build(&outline, spacing, fabric, &pattern::Pins::default())
        .expect("a square piece");
    let placed = p.flat.iter().map(|q| Point3::new(q.x, q.y, 0.0)).collect();
    let (m, _) = ClothModel::assemble(
        &[("probe".into(), p, fabric.clone(), placed)],
        Vec3::zeros(),
    );
    integrator.stable_step(stability::frequency_bound(&m), fabric.damping)
}
