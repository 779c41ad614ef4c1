//! The drape driver: the world of a scene, the one stepping loop, and what a run measures.
//!
//! Each step (`method.md` s. 3-4):
//! 1. forces at the current positions and velocities (springs, gravity, air damping);
//! 2. sliding particles: the force projected on their face, friction applied (`collide::contact`);
//! 3. one step of the integrator (the only place integrators differ);
//! 4. collision, only against objects the cloth can reach this step (the cloth's box, grown by
//!    twice the largest distance a particle moved in the last step, overlaps the object's; an
//!    object's grid is built the first time). Each particle's segment from its previous to its
//!    new position is tested (`collide`).
//!
//! Steps 1-4 of a particle need only the old state and that particle's new state, so one pass
//! over chunks of particles does all four, in parallel for large cloths; `collision_seconds` is
//! the time the workers spent in step 4, over the number of workers.
//!
//! With `until_rest`, the cloth is at rest when its kinetic energy stays below the threshold over
//! a window of at least 0.05 s and does not rise over it.
//!
//! Every [`CHECK_EVERY`] steps the run checks that every number is finite and that the
//! mechanical energy has not grown (`cloth::stability`); if either fails it stops with
//! [`SimError::Unstable`], which names the step and the largest stable step estimated for the
//! scene. Parallel loops work on fixed chunks of particles, so results do not depend on the
//! number of threads.

use crate::cloth::fabric::Fabric;
use crate::cloth::forces;
use crate::cloth::integrate::{self, Integrator};
use crate::cloth::model::ClothModel;
use crate::cloth::pattern::{self, SpringKind};
use crate::cloth::stability;
use crate::cloth::state::ClothState;
use crate::collide::contact;
use crate::collide::Collider;
use crate::math::{Aabb, Point3, Vec3};
use crate::mesh::orient::solid_angle;
use crate::mesh::prepare::{prepare, PrepareOptions};
use crate::mesh::transform::{change_up, Up};
use crate::scene::{Cells, Scene, SceneError, Stop};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Steps between stability checks (and progress updates).
pub const CHECK_EVERY: u64 = 16;

/// Errors of a run.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The run went unstable.
    #[error(
        "the simulation went unstable at step {step} (t = {time:.4} s, {reason}) with {integrator} and dt = {dt:e} s; the largest stable step estimated for these fabrics and spacings is {estimate:.3e} s: {advice}"
    )]
    Unstable {
        step: u64,
        time: f64,
        reason: String,
        integrator: Integrator,
        dt: f64,
        estimate: f64,
        advice: String,
    },
    /// Writing a frame failed.
    #[error("writing frame {step}: {message}")]
    Frame { step: u64, message: String },
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
    /// Highest eigenfrequency of the springs at rest, rad/s.
    pub max_frequency: f64,
    /// Largest stable step of the scene's integrator, s.
    pub stable_step: f64,
    /// Step at which each object's grid was first needed (`None`: never).
    pub grid_built_at: Vec<Option<u64>>,
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
        match pattern::build(&p.outline, p.spacing, &p.fabric, &p.pins) {
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
                key: format!("piece[{}].outline", i + 1),
                error,
            }),
        }
    }
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
    if !errors.is_empty() {
        return Err(SceneError::combine(&scene.path, errors));
    }
    let (model, x) = ClothModel::assemble(&pieces, scene.gravity);
    let margin = scene
        .pieces
        .iter()
        .map(|p| p.fabric.thickness)
        .fold(0.0, f64::max);
    let cloth_box = Aabb::of_points(&x).expect("pieces have particles");
    let colliders = scene
        .objects
        .iter()
        .zip(meshes)
        .map(|(o, mesh)| {
            let dims = match scene.cells {
                Cells::Fixed(d) => d,
                Cells::Auto => {
                    let obj = mesh.bbox().unwrap();
                    let height = cloth_box.max.z.max(obj.max.z) - cloth_box.min.z.min(obj.min.z);
                    let speed = (2.0 * scene.gravity.norm() * height).sqrt();
                    Collider::auto_dims(&mesh, speed * scene.dt)
                }
            };
            Collider::new(o.name.clone(), mesh, dims, margin, o.friction)
        })
        .collect();
    Ok(World::new(model, x, colliders, scene.integrator))
}

impl World {
    /// A world at rest at `x`, with the stability estimate for `integrator`.
    pub fn new(
        model: ClothModel,
        x: Vec<Point3>,
        colliders: Vec<Collider>,
        integrator: Integrator,
    ) -> World {
        let max_frequency = stability::max_frequency(&model, &x);
        let damping = model.damping.iter().copied().fold(f64::INFINITY, f64::min);
        let stable_step = stability::stable_step(
            integrator,
            max_frequency,
            if damping.is_finite() { damping } else { 0.0 },
        );
        let n = colliders.len();
        World {
            model,
            state: ClothState::at_rest(x),
            colliders,
            max_frequency,
            stable_step,
            grid_built_at: vec![None; n],
        }
    }
}

/// What a run measured.
#[derive(Debug, Clone, Serialize)]
pub struct RunStats {
    /// Steps taken.
    pub steps: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Wall time of the loop, s.
    pub wall_seconds: f64,
    /// Time spent in collision, s: the time every worker spent in it, over the number of workers.
    pub collision_seconds: f64,
    /// Whether it stopped because the cloth came to rest.
    pub at_rest: bool,
}

/// Runs the world. `frame(step, world)` is called every `frames` steps; `progress(step)` at
/// every check.
#[allow(clippy::too_many_arguments)]
pub fn run(
    world: &mut World,
    integrator: Integrator,
    dt: f64,
    stop: Stop,
    frames: Option<u64>,
    frame: &mut dyn FnMut(u64, &World) -> Result<(), SimError>,
    progress: &dyn Fn(u64),
) -> Result<RunStats, SimError> {
    let max_steps = match stop {
        Stop::Steps(s) => s,
        Stop::UntilRest { max_steps, .. } => max_steps,
    };
    let mut x_new = world.state.x.clone();
    let mut v_new = world.state.v.clone();
    let energy = |w: &World| {
        forces::kinetic_energy(&w.model, &w.state.v)
            + forces::spring_energy(&w.model, &w.state.x)
            + forces::gravity_energy(&w.model, &w.state.x)
    };
    let e0 = energy(world);
    let scene_box =
        world
            .colliders
            .iter()
            .fold(Aabb::of_points(&world.state.x).unwrap(), |mut b, c| {
                b.include(&c.bbox.min);
                b.include(&c.bbox.max);
                b
            });
    let mass: f64 = world.model.mass.iter().sum();
    let budget = mass * world.model.gravity.norm() * (scene_box.diagonal() + 1.0)
        + e0.abs()
        + forces::spring_energy(&world.model, &world.state.x)
        + 1e-9;
    let start = Instant::now();
    let mut collision_seconds = 0.0;
    let threads = if world.model.len() >= PARALLEL_MIN {
        rayon::current_num_threads().max(1)
    } else {
        1
    };
    let mut at_rest = false;
    let mut steps = 0;
    // At rest: kinetic energy below the threshold at every check of a window of at least 0.05 s
    // (a swing passes through low energy only briefly), and not rising over it (a cloth let go
    // from rest starts with none).
    let window = ((0.05 / (dt * CHECK_EVERY as f64)).ceil() as usize).max(8);
    let mut low: std::collections::VecDeque<f64> = std::collections::VecDeque::new();
    let advice = |w: &World| {
        match integrator {
        Integrator::Leapfrog => format!(
            "use dt <= {:.2e} s, or a larger spacing, or a softer fabric (lower stretch)",
            0.9 * w.stable_step
        ),
        Integrator::ExplicitEuler => format!(
            "use dt <= {:.2e} s, or the leapfrog integrator (stable up to {:.2e} s here), or more damping",
            0.9 * w.stable_step,
            0.9 * 2.0 / w.max_frequency.max(f64::MIN_POSITIVE)
        ),
    }
    };
    // Largest distance a particle moved in the last step (for the reach test).
    let mut travel: f64 = 0.0;
    for step in 1..=max_steps {
        // Which objects the cloth can reach this step: its box grown by twice the last step's
        // largest travel (conservative); a grid is built the first time its object is reachable.
        let reach: Vec<bool> = {
            let bx = Aabb::of_points(&world.state.x).unwrap();
            let grow = 2.0 * travel + 0.01;
            world
                .colliders
                .iter()
                .map(|c| {
                    let m = c.margin * 2.0 + grow;
                    (0..3).all(|k| bx.min[k] <= c.bbox.max[k] + m && bx.max[k] >= c.bbox.min[k] - m)
                })
                .collect()
        };
        for (i, r) in reach.iter().enumerate() {
            if *r && world.grid_built_at[i].is_none() {
                world.grid_built_at[i] = Some(step);
            }
        }
        let any_reach = reach.iter().any(|&r| r);
        // One pass per step: forces, sliding and the integrator step for a chunk of particles,
        // then their collisions (each particle needs only its own new state and the old state).
        let collision_nanos = std::sync::atomic::AtomicU64::new(0);
        let moved = std::sync::Mutex::new(0.0f64);
        {
            let World {
                model,
                state,
                colliders,
                ..
            } = &mut *world;
            let (x, v) = (&state.x, &state.v);
            let (model, colliders, reach) = (&*model, &*colliders, &reach);
            for_chunks(
                COLLISION_CHUNK,
                &mut x_new,
                &mut v_new,
                &mut state.contact,
                |base, xs, vs, cs| {
                    for k in 0..xs.len() {
                        let i = base + k;
                        let mut fi = forces::force_on(model, x, v, i);
                        let mut vi = v[i];
                        if let Some(ct) = cs[k] {
                            let col = &colliders[ct.object as usize];
                            let mu = col.friction.unwrap_or(model.friction[i]);
                            if !contact::slide_force(
                                col,
                                &ct,
                                mu,
                                model.mass[i],
                                dt,
                                &mut fi,
                                &mut vi,
                            ) {
                                cs[k] = None;
                            }
                        }
                        (xs[k], vs[k]) =
                            integrate::advance(integrator, dt, model.inv_mass[i], x[i], vi, fi);
                    }
                    let t = Instant::now();
                    let mut far: f64 = 0.0;
                    for k in 0..xs.len() {
                        let i = base + k;
                        if any_reach && !model.pinned(i) {
                            contact::resolve(
                                colliders,
                                reach,
                                &x[i],
                                &mut xs[k],
                                &mut vs[k],
                                model.thickness[i],
                                &mut cs[k],
                            );
                        } else if !any_reach {
                            cs[k] = None;
                        }
                        far = far.max((xs[k] - x[i]).norm_squared());
                    }
                    if any_reach {
                        collision_nanos.fetch_add(
                            t.elapsed().as_nanos() as u64,
                            std::sync::atomic::Ordering::Relaxed,
                        );
                    }
                    let mut m = moved.lock().unwrap();
                    *m = m.max(far);
                },
            );
        }
        travel = moved.into_inner().unwrap().sqrt();
        collision_seconds += collision_nanos.into_inner() as f64 * 1e-9 / threads as f64;
        std::mem::swap(&mut world.state.x, &mut x_new);
        std::mem::swap(&mut world.state.v, &mut v_new);
        steps = step;
        if step % CHECK_EVERY == 0 || step == max_steps {
            let finite = world
                .state
                .x
                .iter()
                .all(|p| p.iter().all(|c| c.is_finite()))
                && world
                    .state
                    .v
                    .iter()
                    .all(|v| v.iter().all(|c| c.is_finite()));
            let e = if finite { energy(world) } else { f64::NAN };
            if !finite || !e.is_finite() || e - e0 > budget {
                let reason = if finite {
                    format!("the energy rose by {:.3e} J", e - e0)
                } else {
                    "non-finite positions or velocities".into()
                };
                return Err(SimError::Unstable {
                    step,
                    time: step as f64 * dt,
                    reason,
                    integrator,
                    dt,
                    estimate: world.stable_step,
                    advice: advice(world),
                });
            }
            progress(step);
            if let Stop::UntilRest { energy: rest, .. } = stop {
                let ke = forces::kinetic_energy(&world.model, &world.state.v);
                if ke < rest {
                    low.push_back(ke);
                    if low.len() > window {
                        low.pop_front();
                    }
                    if low.len() == window && ke <= low[0] {
                        at_rest = true;
                        break;
                    }
                } else {
                    low.clear();
                }
            }
        }
        if let Some(k) = frames {
            if step % k == 0 {
                frame(step, world)?;
            }
        }
    }
    Ok(RunStats {
        steps,
        time: steps as f64 * dt,
        wall_seconds: start.elapsed().as_secs_f64(),
        collision_seconds,
        at_rest,
    })
}

/// Runs the world without frames or progress reports.
pub fn run_quiet(
    world: &mut World,
    integrator: Integrator,
    dt: f64,
    stop: Stop,
) -> Result<RunStats, SimError> {
    run(
        world,
        integrator,
        dt,
        stop,
        None,
        &mut |_, _| Ok(()),
        &|_| {},
    )
}

/// Particles from which the per-step loops run in parallel (below, dispatch costs more than it
/// saves). Either way each particle computes the same numbers.
pub const PARALLEL_MIN: usize = 3000;

/// Particles per work unit of the step: small, because the particles in contact (the expensive
/// ones) are neighbours in the numbering, and work stealing must spread them.
pub const COLLISION_CHUNK: usize = 64;

/// Runs `body(first, xs, vs, cs)` over fixed chunks of `chunk` particles, in parallel for large
/// cloths. Each particle computes the same numbers whatever the chunking or thread count.
fn for_chunks<F>(
    chunk: usize,
    x: &mut [Point3],
    v: &mut [Vec3],
    c: &mut [Option<crate::cloth::state::Contact>],
    body: F,
) where
    F: Fn(usize, &mut [Point3], &mut [Vec3], &mut [Option<crate::cloth::state::Contact>]) + Sync,
{
    if x.len() >= PARALLEL_MIN && rayon::current_num_threads() > 1 {
        x.par_chunks_mut(chunk)
            .zip(v.par_chunks_mut(chunk))
            .zip(c.par_chunks_mut(chunk))
            .enumerate()
            .for_each(|(k, ((xs, vs), cs))| body(k * chunk, xs, vs, cs));
    } else {
        for (k, ((xs, vs), cs)) in x
            .chunks_mut(chunk)
            .zip(v.chunks_mut(chunk))
            .zip(c.chunks_mut(chunk))
            .enumerate()
        {
            body(k * chunk, xs, vs, cs);
        }
    }
}

/// Largest and mean strain (edge length over rest length, minus one) of the stretch springs.
pub fn strain(model: &ClothModel, x: &[Point3]) -> (f64, f64) {
    let s: Vec<f64> = model
        .springs
        .iter()
        .filter(|s| s.kind == SpringKind::Stretch)
        .map(|s| (x[s.b as usize] - x[s.a as usize]).norm() / s.rest - 1.0)
        .collect();
    if s.is_empty() {
        return (0.0, 0.0);
    }
    (
        s.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        s.iter().sum::<f64>() / s.len() as f64,
    )
}

/// Whether `p` is inside the closed surface of `c`: its generalized winding number is above 1/2
/// (robust to small holes and to particles near the surface).
pub fn inside(c: &Collider, p: &Point3) -> bool {
    if !c.bbox.contains(p, 0.0) {
        return false;
    }
    let w: f64 = (0..c.mesh.faces.len())
        .map(|f| {
            let [a, b, cc] = c.mesh.corners(f);
            solid_angle(p, &a, &b, &cc)
        })
        .sum();
    w / (4.0 * std::f64::consts::PI) > 0.5
}

/// Particles inside a closed object, per object (`None` for open objects).
pub fn particles_inside(world: &World) -> Vec<Option<usize>> {
    world
        .colliders
        .iter()
        .map(|c| {
            c.closed
                .then(|| world.state.x.par_iter().filter(|p| inside(c, p)).count())
        })
        .collect()
}

/// The smallest distance of a particle to each object.
pub fn min_clearance(world: &World) -> Vec<f64> {
    world
        .colliders
        .iter()
        .map(|c| {
            let q = crate::mesh::closest::ClosestPoints::new(&c.mesh);
            world
                .state
                .x
                .par_iter()
                .map(|p| q.closest(p).distance)
                .reduce(|| f64::INFINITY, f64::min)
        })
        .collect()
}

/// The drape coefficient of a piece (Cusick): its shadow area on the plane across gravity,
/// less the disc's area, over its flat area less the disc's. The shadow is the union of its
/// projected triangles, rasterised at 1/400 of the piece's size.
pub fn drape_coefficient(world: &World, piece: usize, disc_radius: f64) -> f64 {
    let m = &world.model;
    let r = &m.pieces[piece];
    let g = m.gravity.normalize();
    let e1 = g
        .cross(&Vec3::x())
        .try_normalize(1e-9)
        .unwrap_or_else(|| g.cross(&Vec3::y()).normalize());
    let e2 = g.cross(&e1);
    let pts: Vec<(f64, f64)> = world.state.x[r.first..r.first + r.count]
        .iter()
        .map(|p| (p.coords.dot(&e1), p.coords.dot(&e2)))
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in &pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let px = r.area.sqrt() / 400.0;
    let (nx, ny) = (
        ((x1 - x0) / px).ceil() as usize + 1,
        ((y1 - y0) / px).ceil() as usize + 1,
    );
    let mut covered = vec![false; nx * ny];
    for t in &m.triangles[r.first_triangle..r.first_triangle + r.triangles] {
        let [a, b, c] = t.map(|v| pts[v as usize - r.first]);
        let (tx0, tx1) = (a.0.min(b.0).min(c.0), a.0.max(b.0).max(c.0));
        let (ty0, ty1) = (a.1.min(b.1).min(c.1), a.1.max(b.1).max(c.1));
        let cross = |p: (f64, f64), q: (f64, f64), s: (f64, f64)| {
            (q.0 - p.0) * (s.1 - p.1) - (q.1 - p.1) * (s.0 - p.0)
        };
        let area = cross(a, b, c);
        if area == 0.0 {
            continue;
        }
        for j in
            ((ty0 - y0) / px).floor() as usize..=(((ty1 - y0) / px).ceil() as usize).min(ny - 1)
        {
            for i in
                ((tx0 - x0) / px).floor() as usize..=(((tx1 - x0) / px).ceil() as usize).min(nx - 1)
            {
                let p = (x0 + (i as f64 + 0.5) * px, y0 + (j as f64 + 0.5) * px);
                let (w0, w1, w2) = (cross(b, c, p), cross(c, a, p), cross(a, b, p));
                if (w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 && area > 0.0)
                    || (w0 <= 0.0 && w1 <= 0.0 && w2 <= 0.0 && area < 0.0)
                {
                    covered[j * nx + i] = true;
                }
            }
        }
    }
    let shadow = covered.iter().filter(|&&c| c).count() as f64 * px * px;
    let disc = std::f64::consts::PI * disc_radius * disc_radius;
    (shadow - disc) / (r.area - disc)
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
/// assert!((at_1cm - 2.95e-5).abs() < 0.05e-5, "{at_1cm}");
/// assert!((at_2cm / at_1cm - 2.0).abs() < 0.01);
/// ```
pub fn stable_step_for(fabric: &Fabric, spacing: f64, integrator: Integrator) -> f64 {
    let s = 10.0 * spacing;
    let outline = [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| crate::math::Point2::new(x, y));
    let p = pattern::build(&outline, spacing, fabric, &pattern::Pins::default())
        .expect("a square piece");
    let placed = p.flat.iter().map(|q| Point3::new(q.x, q.y, 0.0)).collect();
    let (m, x) = ClothModel::assemble(
        &[("probe".into(), p, fabric.clone(), placed)],
        Vec3::zeros(),
    );
    stability::stable_step(integrator, stability::max_frequency(&m, &x), fabric.damping)
}
