//! `drapekit drape SCENE.toml -o OUT_DIR`: a validation drape.

use crate::io::gltf::{self, Frame, Part, Surface};
use crate::io::{self, WriteOptions};
use crate::mesh::transform::{change_up, Units, Up};
use crate::mesh::TriMesh;
use crate::scene;
use crate::sim::{self, World};
use clap::Args;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Arguments of `drapekit drape`.
#[derive(Debug, Args)]
pub struct DrapeArgs {
    /// The scene file (TOML; see the README).
    pub scene: PathBuf,
    /// The output directory (created if needed): one OBJ per piece and per object as placed,
    /// frames/ on request.
    #[arg(short, long, value_name = "OUT_DIR")]
    pub output: PathBuf,
    /// Also write OUT_DIR/<scene>.glb: the pieces and the objects as placed (metres, y up, as
    /// glTF wants), the frames as an animation when the scene writes frames.
    #[arg(long)]
    pub glb: bool,
    /// Write the JSON report here.
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// Print the JSON report instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Also write `OUT_DIR/preview.png`: the cloth on the objects, from the front, right and
    /// above.
    #[arg(long)]
    pub preview: bool,
    /// Continue the run that Ctrl-C or SIGTERM interrupted, from its checkpoint
    /// (`OUT_DIR/<scene>.checkpoint`), to the outputs of a run never stopped.
    #[arg(long)]
    pub resume: bool,
}

/// One object in the report.
#[derive(Debug, Serialize)]
pub struct ObjectReport {
    /// Name.
    pub name: String,
    /// Faces after preparation.
    pub faces: usize,
    /// Grid cells along x, y, z.
    pub cells: [usize; 3],
    /// Step the grid was first needed (`null`: the cloth never came near).
    pub grid_built_at: Option<u64>,
    /// Watertight (inside tests apply).
    pub closed: bool,
    /// Particles inside it at the end (`null` for open objects).
    pub particles_inside: Option<usize>,
    /// Smallest particle distance to it at the end (length units).
    pub min_clearance: f64,
    /// The object as placed in the scene (scene units and frame), in the pieces' formats.
    pub files: Vec<String>,
}

/// One piece in the report.
#[derive(Debug, Serialize)]
pub struct PieceReport {
    /// Name.
    pub name: String,
    /// Its fabric.
    pub fabric: String,
    /// Particles.
    pub particles: usize,
    /// Triangles.
    pub triangles: usize,
    /// Flat area (length units squared).
    pub area: f64,
    /// Drape coefficient (with `[report] disc_radius`).
    pub drape_coefficient: Option<f64>,
    /// Output files.
    pub files: Vec<String>,
}

/// Where the time of a run went.
#[derive(Debug, Serialize)]
pub struct Phases {
    /// Predict (external forces, inertial positions), s.
    pub predict_seconds: f64,
    /// Solve (the integrator), s; includes the factorisation.
    pub solve_seconds: f64,
    /// Collide, s.
    pub collision_seconds: f64,
    /// Measure (energy watch, rest test), s.
    pub measure_seconds: f64,
    /// Factoring the projective-dynamics matrix and its low-rank updates, s (implicit Euler with
    /// the direct solver: its factorisations and solves, one per Newton step).
    pub factor_seconds: f64,
    /// Numeric factorisations (projective dynamics refactors when more than `low_rank_max`
    /// particles' contacts changed; implicit Euler's direct solver once per Newton step).
    pub factorisations: u64,
    /// Columns computed for low-rank updates instead of refactoring (each a path of the
    /// elimination tree).
    pub low_rank_columns: u64,
    /// Conjugate-gradient iterations (implicit Euler).
    pub cg_iterations: u64,
    /// Local/global iterations (projective dynamics).
    pub pd_iterations: u64,
}

/// The JSON report of `drape`. Lengths are in the scene's units.
#[derive(Debug, Serialize)]
pub struct DrapeReport {
    /// The scene file.
    pub scene: String,
    /// The output directory.
    pub output_dir: String,
    /// Units of every length here.
    pub units: Units,
    /// Particles.
    pub particles: usize,
    /// Springs and bending elements (the paper's stretch, shear and bend connections).
    pub springs: usize,
    /// Of which stretch springs, shear springs, bending elements.
    pub springs_by_kind: [usize; 3],
    /// Faces of all objects.
    pub object_faces: usize,
    /// Grid cells of each object.
    pub cells: Vec<[usize; 3]>,
    /// Every solver setting (integrator, step, iterations, tolerances).
    pub solver: crate::cloth::integrate::SolverSettings,
    /// Integrator.
    pub integrator: crate::cloth::Integrator,
    /// Time step, s.
    pub dt: f64,
    /// The scene gave no `dt` for an explicit integrator: `dt` is
    /// `scene::EXPLICIT_STEP_FRACTION` of `stable_step_estimate`.
    pub dt_from_estimate: bool,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Whether the run stopped at rest (`until_rest`).
    pub at_rest: bool,
    /// Wall time of the stepping loop, s.
    pub wall_seconds: f64,
    /// Of which collision, s.
    pub collision_seconds: f64,
    /// Wall time of each phase of the step, s, and the solver's work.
    pub phases: Phases,
    /// Particles in contact with an object at the end.
    pub contacts_end: usize,
    /// Particles inside closed objects at the end (`null` when every object is open: no inside
    /// test applies to an open surface).
    pub particles_inside: Option<usize>,
    /// Objects with no inside test (open surfaces).
    pub open_objects: Vec<String>,
    /// Smallest particle distance to any object at the end.
    pub min_clearance: Option<f64>,
    /// Largest strain (edge length over rest length, minus one).
    pub max_strain: f64,
    /// Mean strain.
    pub mean_strain: f64,
    /// Kinetic energy at the end, J.
    pub kinetic_energy_end: f64,
    /// Every number finite.
    pub finite: bool,
    /// Highest eigenfrequency of the springs at rest, rad/s.
    pub max_frequency: f64,
    /// Largest stable step estimated for this integrator, s.
    pub stable_step_estimate: f64,
    /// Per object.
    pub objects: Vec<ObjectReport>,
    /// Per piece.
    pub pieces: Vec<PieceReport>,
    /// What looked wrong before the run (an object far larger or smaller than the cloth,
    /// cloth starting inside an object), also printed as warnings.
    pub warnings: Vec<String>,
    /// The glTF file (`--glb`).
    pub glb: Option<String>,
    /// The preview picture (`--preview`).
    pub preview: Option<String>,
    /// Wall time of the whole command, s.
    pub command_seconds: f64,
}

/// Whether the output directory and its `frames/` existed before the run.
#[derive(Debug, Clone, Copy)]
struct Existed {
    out: bool,
    frames: bool,
}

/// After a failed run: removes the staged temporary files, and the directories the run created
/// (when empty). Files of an earlier run were never touched.
fn abandon(staged: Vec<io::Staged>, out: &Path, existed: Existed) {
    drop(staged);
    if !existed.frames {
        let _ = std::fs::remove_dir(out.join("frames"));
    }
    if !existed.out {
        let _ = std::fs::remove_dir(out);
    }
}

/// Stages each piece's mesh (`OUT/<piece>.obj`, and `.ply` on request) into `staged`; returns
/// the pieces' reports.
fn stage_pieces(
    sc: &scene::Scene,
    world: &World,
    out: &Path,
    inputs: &[&Path],
    staged: &mut Vec<io::Staged>,
) -> anyhow::Result<Vec<PieceReport>> {
    std::fs::create_dir_all(out)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", out.display()))?;
    let to_units = Units::factor(Units::M, sc.units);
    let exts: &[&str] = if sc.ply { &["obj", "ply"] } else { &["obj"] };
    let mut pieces = Vec::new();
    for (i, p) in sc.pieces.iter().enumerate() {
        let mesh = piece_mesh(world, i, to_units);
        let mut files = Vec::new();
        let rest = piece_rest(world, i, to_units);
        for ext in exts {
            let path = out.join(format!("{}.{ext}", p.name));
            let f = if *ext == "obj" {
                io::stage_obj_with_rest(&path, &mesh, &rest, &[], inputs)?
            } else {
                io::stage_mesh(&path, &mesh, &WriteOptions::default(), inputs)?.0
            };
            staged.push(f);
            files.push(path.display().to_string());
        }
        let r = &world.model.pieces[i];
        pieces.push(PieceReport {
            name: p.name.clone(),
            fabric: p.fabric_name.clone(),
            particles: r.count,
            triangles: r.triangles,
            area: r.area * to_units * to_units,
            drape_coefficient: sc.disc_radius.map(|d| sim::drape_coefficient(world, i, d)),
            files,
        });
    }
    Ok(pieces)
}

fn piece_mesh(world: &World, piece: usize, to_units: f64) -> TriMesh {
    piece_mesh_at(world, &world.state.x, piece, to_units)
}

/// A piece's mesh with the cloth at `x`.
fn piece_mesh_at(world: &World, x: &[crate::math::Point3], piece: usize, to_units: f64) -> TriMesh {
    let r = &world.model.pieces[piece];
    let positions = x[r.first..r.first + r.count]
        .iter()
        .map(|p| p * to_units)
        .collect();
    let faces = world.model.triangles[r.first_triangle..r.first_triangle + r.triangles]
        .iter()
        .map(|t| t.map(|v| v - r.first as u32))
        .collect();
    TriMesh::new(positions, faces)
}

/// The file names of the objects as placed: each object's file stem, made unique against the
/// pieces (or the garment), the other objects, and the inputs that sit in the output folder.
pub(super) fn object_names(sc: &scene::Scene, out: &Path) -> Vec<String> {
    let stem = |p: &Path| p.file_stem().map(|s| s.to_string_lossy().into_owned());
    let wanted: Vec<String> = sc
        .objects
        .iter()
        .map(|o| stem(&o.mesh).unwrap_or_else(|| o.name.clone()))
        .collect();
    let mut taken: Vec<String> = sc.pieces.iter().map(|p| p.name.clone()).collect();
    taken.extend(sc.garment.iter().map(|g| g.name.clone()));
    let garment = sc.garment.iter().map(|g| &g.path);
    let inputs = std::iter::once(&sc.path)
        .chain(sc.objects.iter().map(|o| &o.mesh))
        .chain(garment);
    let beside = inputs.filter(|i| i.parent().is_some_and(|d| io::same_file(d, out)));
    taken.extend(beside.filter_map(|i| stem(i)));
    io::unique_file_names(&wanted, &taken, "object")
}

/// The object as placed: the collider's mesh (prepared, turned to z up, scaled, translated) in
/// the scene's units.
fn object_mesh(world: &World, i: usize, to_units: f64) -> TriMesh {
    let mut mesh = world.colliders[i].mesh.clone();
    crate::mesh::transform::scale(&mut mesh, to_units);
    mesh
}

/// Stages each object as placed (`OUT/<name>.obj`, and `.ply` when the pieces get one);
/// returns each object's files.
pub(super) fn stage_objects(
    sc: &scene::Scene,
    world: &World,
    names: &[String],
    out: &Path,
    inputs: &[&Path],
    staged: &mut Vec<io::Staged>,
) -> anyhow::Result<Vec<Vec<String>>> {
    let to_units = Units::factor(Units::M, sc.units);
    let exts: &[&str] = if sc.ply { &["obj", "ply"] } else { &["obj"] };
    let mut files = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let mesh = object_mesh(world, i, to_units);
        let mut mine = Vec::new();
        for ext in exts {
            let path = out.join(format!("{name}.{ext}"));
            let (f, _) = io::stage_mesh(&path, &mesh, &WriteOptions::default(), inputs)?;
            staged.push(f);
            mine.push(path.display().to_string());
        }
        files.push(mine);
    }
    Ok(files)
}

/// Metres, z up (the simulation's frame) to glTF's metres, y up.
fn to_gltf(mut mesh: TriMesh) -> TriMesh {
    change_up(&mut mesh, Up::Z, Up::Y);
    mesh
}

/// The pieces with the cloth at `x`, in metres and z up.
fn piece_meshes(world: &World, x: &[crate::math::Point3]) -> Vec<TriMesh> {
    (0..world.model.pieces.len())
        .map(|i| piece_mesh_at(world, x, i, 1.0))
        .collect()
}

/// The glTF scene of a drape: the objects as placed, and the pieces (at the end, or as frames
/// at `step * dt` s with the end last).
fn gltf_scene(
    sc: &scene::Scene,
    world: &World,
    names: &[String],
    frames: Vec<(u64, Vec<TriMesh>)>,
    steps: u64,
) -> gltf::Scene {
    let objects = (0..world.colliders.len()).map(|i| {
        Part::new(
            &names[i],
            to_gltf(object_mesh(world, i, 1.0)),
            Surface::Solid,
        )
    });
    // Each piece coloured by its strain (viridis, one scale for every frame: from 0 to the
    // largest |strain| at the end, at least 0.1%).
    let rest: Vec<Vec<[f64; 2]>> = (0..sc.pieces.len())
        .map(|i| piece_rest(world, i, 1.0))
        .collect();
    let strain = |i: usize, m: &TriMesh| {
        crate::render::strain::vertex_strain(m, &rest[i])
            .unwrap_or_else(|_| vec![0.0; m.positions.len()])
    };
    let end = piece_meshes(world, &world.state.x);
    let top =
        crate::render::strain::strain_top((end.iter().enumerate()).flat_map(|(i, m)| strain(i, m)));
    let pieces = |meshes: Vec<TriMesh>| -> Vec<Part> {
        let named = sc.pieces.iter().zip(meshes).enumerate();
        named
            .map(|(i, (p, m))| {
                let colours = crate::render::strain::strain_colours(&strain(i, &m), top);
                let mut part = Part::new(&p.name, to_gltf(m), Surface::Cloth);
                part.colors = Some(colours);
                part
            })
            .collect()
    };
    let mut scene = gltf::Scene {
        parts: objects.collect(),
        frames: Vec::new(),
    };
    if frames.is_empty() {
        scene.parts.extend(pieces(end));
        return scene;
    }
    let dt = sc.solver.dt;
    let last = frames.last().map(|f| f.0);
    for (step, meshes) in frames {
        let time = step as f64 * dt;
        scene.frames.push(Frame {
            time,
            parts: pieces(meshes),
        });
    }
    if last != Some(steps) {
        let time = steps as f64 * dt;
        scene.frames.push(Frame {
            time,
            parts: pieces(end),
        });
    }
    scene
}

/// A piece's flat pattern coordinates (its rest geometry), in the output's units.
fn piece_rest(world: &World, piece: usize, to_units: f64) -> Vec<[f64; 2]> {
    let r = &world.model.pieces[piece];
    world.model.rest[r.first..r.first + r.count]
        .iter()
        .map(|q| [q.x * to_units, q.y * to_units])
        .collect()
}

/// Stages `OUT/preview.png`: every piece in the cloth's colour on the objects (grey), in the
/// output's units, from the iso view. Returns its path.
pub(super) fn stage_preview(
    world: &World,
    out: &Path,
    to_units: f64,
    inputs: &[&Path],
    staged: &mut Vec<io::Staged>,
) -> anyhow::Result<String> {
    use super::render::{CLOTH, OBJECT};
    let pieces: Vec<TriMesh> = (0..world.model.pieces.len())
        .map(|i| piece_mesh(world, i, to_units))
        .collect();
    let objects: Vec<TriMesh> = (0..world.colliders.len())
        .map(|i| object_mesh(world, i, to_units))
        .collect();
    use crate::render::{default_lift, Item};
    let lift = default_lift(pieces.iter().chain(&objects).flat_map(|m| &m.positions));
    let items: Vec<_> = pieces
        .iter()
        .map(|m| Item::cloth(m, CLOTH, None, lift))
        .chain(objects.iter().map(|m| Item::object(m, OBJECT)))
        .collect();
    let path = out.join("preview.png");
    staged.push(super::render::stage_preview(
        &path,
        &items,
        crate::render::View::Iso,
        crate::mesh::transform::Up::Z,
        inputs,
    )?);
    Ok(path.display().to_string())
}

/// What every phase of a run reads: its arguments, its scene, the inputs (never written over)
/// and the factor from metres to the scene's units.
struct Ctx<'a> {
    args: &'a DrapeArgs,
    sc: &'a scene::Scene,
    inputs: Vec<&'a Path>,
    to_units: f64,
}

/// Where a run keeps its checkpoint, the checkpoint it continues from, and what existed in the
/// output before it.
struct Prepared {
    checkpoint: PathBuf,
    fingerprint: sim::checkpoint::Fingerprint,
    resume: Option<sim::Checkpoint>,
    existed: Existed,
}

/// A finished stepping loop: its statistics, the frames staged, and the frames kept for the
/// glTF file (metres, z up).
struct Stepped {
    stats: sim::RunStats,
    staged: Vec<io::Staged>,
    glb_frames: Vec<(u64, Vec<crate::math::Point3>)>,
}

/// What the end of a run staged and put in place.
struct Written {
    pieces: Vec<PieceReport>,
    object_files: Vec<Vec<String>>,
    preview: Option<String>,
    glb: Option<PathBuf>,
}

/// Runs `drapekit drape`.
pub fn run(args: DrapeArgs) -> anyhow::Result<()> {
    let start = std::time::Instant::now();
    let mut sc = scene::read(&args.scene)?;
    let inputs: Vec<&Path> = (std::iter::once(sc.path.as_path()))
        .chain(sc.objects.iter().map(|o| o.mesh.as_path()))
        .chain(sc.garment.iter().map(|g| g.path.as_path()))
        .collect();
    super::check_report(args.report.as_deref(), &args.output, &inputs)?;
    if sc.garment.is_some() {
        return super::drape_garment::run(&args, sc, start);
    }
    let mut world = sim::load(&sc)?;
    sc.choose_step(world.stable_step)?;
    let placement = sim::placement_warnings(&world);
    super::warn(&placement);
    super::refuse_file_output(&args.output)?;
    let mut prepared = prepare(&args, &sc)?;
    let ctx = Ctx {
        args: &args,
        sc: &sc,
        inputs: std::iter::once(sc.path.as_path())
            .chain(sc.objects.iter().map(|o| o.mesh.as_path()))
            .collect(),
        to_units: Units::factor(Units::M, sc.units),
    };
    let Stepped {
        stats,
        staged,
        glb_frames,
    } = step(&ctx, &mut world, &mut prepared)?;
    let existed = prepared.existed;
    let written = write_outputs(&ctx, &world, existed, staged, glb_frames, stats.steps)?;
    remove_checkpoint(&prepared.checkpoint);
    let report = drape_report(&ctx, &world, &stats, written, placement, start);
    super::finish(
        &report,
        args.report.as_deref(),
        &ctx.inputs,
        &args.output,
        args.json,
        print_summary,
    )
}

/// Readies the output directory before any work: the temporary files of killed runs removed,
/// the checkpoint read (`--resume`) or noted, and what exists there recorded. Nothing is
/// created until there is something to write.
fn prepare(args: &DrapeArgs, sc: &scene::Scene) -> anyhow::Result<Prepared> {
    let out = &args.output;
    super::remove_stale_temps(&[out, &out.join("frames")]);
    let checkpoint = out.join(format!("{}.checkpoint", scene_stem(sc)));
    let fingerprint = sim::checkpoint::fingerprint(sc, &format!("glb={}", args.glb))?;
    let resume = read_checkpoint(&checkpoint, &fingerprint, args.resume)?;
    // Every output (frames, pieces) is staged in a temporary file and renamed into place only
    // when the run has succeeded: a failed run leaves an earlier run's files as they were.
    let existed = Existed {
        out: out.exists(),
        frames: out.join("frames").exists(),
    };
    Ok(Prepared {
        checkpoint,
        fingerprint,
        resume,
        existed,
    })
}

/// The progress bar over `total` steps (on a terminal only).
fn progress_bar(total: u64) -> Option<indicatif::ProgressBar> {
    super::interactive().then(|| {
        let b = indicatif::ProgressBar::new(total);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} steps, {per_sec}, {eta} left",
            )
            .unwrap(),
        );
        b
    })
}

/// Stages each piece of `w` at `step` as `frames/<piece>_<step>.obj` into `staged`.
fn stage_frame(
    ctx: &Ctx,
    w: &World,
    step: u64,
    staged: &mut Vec<io::Staged>,
) -> Result<(), sim::SimError> {
    let frames_dir = ctx.args.output.join("frames");
    let failed = |e: &dyn std::fmt::Display| sim::SimError::Frame {
        step,
        message: e.to_string(),
    };
    std::fs::create_dir_all(&frames_dir).map_err(|e| failed(&e))?;
    for (i, p) in ctx.sc.pieces.iter().enumerate() {
        let path = frames_dir.join(format!("{}_{step:07}.obj", p.name));
        let f = io::stage_obj_with_rest(
            &path,
            &piece_mesh(w, i, ctx.to_units),
            &piece_rest(w, i, ctx.to_units),
            &[],
            &ctx.inputs,
        )
        .map_err(|e| failed(&e))?;
        staged.push(f);
    }
    Ok(())
}

/// Steps the world to the scene's stop (from the checkpoint with `--resume`), staging the
/// frames. Interrupted, it puts the frames in place and keeps a checkpoint; failed, it
/// abandons what it staged; both return the error.
fn step(ctx: &Ctx, world: &mut World, prepared: &mut Prepared) -> anyhow::Result<Stepped> {
    let sc = ctx.sc;
    let staged = std::cell::RefCell::new(Vec::<io::Staged>::new());
    let total = sc.stop.max_steps();
    let bar = progress_bar(total);
    // The frames kept for the glTF file: the positions, in metres and z up.
    let kept = (prepared.resume.as_mut()).map(|c| std::mem::take(&mut c.frames));
    let glb_frames = std::cell::RefCell::new(kept.unwrap_or_default());
    let mut frame = |step: u64, w: &World| -> Result<bool, sim::SimError> {
        if ctx.args.glb {
            glb_frames.borrow_mut().push((step, w.state.x.clone()));
        }
        stage_frame(ctx, w, step, &mut staged.borrow_mut())?;
        Ok(false)
    };
    let progress = |step: u64| {
        if let Some(b) = &bar {
            b.set_position(step);
        }
    };
    if let (Some(b), Some(c)) = (&bar, &prepared.resume) {
        b.set_position(c.step);
    }
    let signals = super::interrupt::install()?;
    let control = sim::Control {
        cancel: Some(signals.cancel()),
        resume: prepared.resume.as_ref(),
        ..sim::Control::default()
    };
    let stats = sim::run(
        world, &sc.solver, sc.stop, sc.frames, &mut frame, &progress, control,
    );
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let staged = staged.into_inner();
    match stats {
        Ok(stats) => Ok(Stepped {
            stats,
            staged,
            glb_frames: glb_frames.into_inner(),
        }),
        Err(sim::SimError::Interrupted(mut c)) => {
            c.fingerprint = prepared.fingerprint.clone();
            c.frames = glb_frames.take();
            let path = &prepared.checkpoint;
            Err(keep_checkpoint(
                *c,
                staged,
                path,
                total,
                &ctx.inputs,
                signals,
            ))
        }
        Err(e) => {
            abandon(staged, &ctx.args.output, prepared.existed);
            Err(e.into())
        }
    }
}

/// Stages the pieces, the objects as placed, the preview and the glTF file (its frames from
/// `frames`, the run having taken `steps`) beside the staged frames, and puts them all in
/// place; after a failure abandons them all.
fn write_outputs(
    ctx: &Ctx,
    world: &World,
    existed: Existed,
    mut staged: Vec<io::Staged>,
    frames: Vec<(u64, Vec<crate::math::Point3>)>,
    steps: u64,
) -> anyhow::Result<Written> {
    let (sc, out, inputs) = (ctx.sc, ctx.args.output.as_path(), &ctx.inputs);
    let object_names = object_names(sc, out);
    let glb = (ctx.args.glb).then(|| out.join(format!("{}.glb", scene_stem(sc))));
    let written = (|| -> anyhow::Result<Written> {
        let pieces = stage_pieces(sc, world, out, inputs, &mut staged)?;
        let object_files = stage_objects(sc, world, &object_names, out, inputs, &mut staged)?;
        let preview = (ctx.args.preview)
            .then(|| stage_preview(world, out, ctx.to_units, inputs, &mut staged))
            .transpose()?;
        if let Some(path) = &glb {
            let frames = frames
                .into_iter()
                .map(|(s, x)| (s, piece_meshes(world, &x)));
            let scene = gltf_scene(sc, world, &object_names, frames.collect(), steps);
            staged.push(gltf::stage_scene(path, &scene, inputs)?);
        }
        io::commit(std::mem::take(&mut staged))?;
        Ok(Written {
            pieces,
            object_files,
            preview,
            glb: glb.clone(),
        })
    })();
    if written.is_err() {
        abandon(staged, out, existed);
    }
    written
}

/// Removes the checkpoint of an interrupted run once this run is complete, and says so.
fn remove_checkpoint(checkpoint: &Path) {
    if checkpoint.exists() && std::fs::remove_file(checkpoint).is_ok() {
        eprintln!(
            "note: removed {}: the run is complete",
            checkpoint.display()
        );
    }
}

/// The report of a finished run: the world at the end, the run's statistics, the files
/// written, the placement's warnings; `start` is when the command started.
fn drape_report(
    ctx: &Ctx,
    world: &World,
    stats: &sim::RunStats,
    written: Written,
    warnings: Vec<String>,
    start: std::time::Instant,
) -> DrapeReport {
    let sc = ctx.sc;
    let inside = sim::particles_inside(world);
    let objects = object_reports(world, ctx.to_units, written.object_files);
    let (max_strain, mean_strain) = sim::strain(&world.model, &world.state.x);
    let m = &world.model;
    DrapeReport {
        scene: sc.path.display().to_string(),
        output_dir: ctx.args.output.display().to_string(),
        units: sc.units,
        particles: m.len(),
        springs: m.springs.len() + m.bends(),
        springs_by_kind: [
            m.count(crate::cloth::pattern::SpringKind::Stretch),
            m.count(crate::cloth::pattern::SpringKind::Shear),
            m.bends(),
        ],
        object_faces: world.colliders.iter().map(|c| c.mesh.faces.len()).sum(),
        cells: world.colliders.iter().map(|c| c.dims).collect(),
        solver: sc.solver,
        integrator: sc.solver.integrator,
        dt: sc.solver.dt,
        dt_from_estimate: sc.step_from_estimate,
        steps: stats.steps,
        time: stats.time,
        at_rest: stats.at_rest,
        wall_seconds: stats.wall_seconds,
        collision_seconds: stats.collision_seconds,
        phases: phases(stats),
        contacts_end: world.state.contact.iter().filter(|c| c.is_some()).count(),
        particles_inside: inside_total(&inside),
        open_objects: (objects.iter().filter(|o| !o.closed))
            .map(|o| o.name.clone())
            .collect(),
        min_clearance: objects.iter().map(|o| o.min_clearance).reduce(f64::min),
        max_strain,
        mean_strain,
        kinetic_energy_end: crate::cloth::forces::kinetic_energy(m, &world.state.v),
        finite: (world.state.x.iter()).all(|p| p.iter().all(|c| c.is_finite())),
        max_frequency: world.max_frequency,
        stable_step_estimate: world.stable_step,
        objects,
        pieces: written.pieces,
        warnings,
        glb: written.glb.map(|p| p.display().to_string()),
        preview: written.preview,
        command_seconds: start.elapsed().as_secs_f64(),
    }
}

/// Where the time of a run's steps went, and the solver's work.
fn phases(stats: &sim::RunStats) -> Phases {
    Phases {
        predict_seconds: stats.predict_seconds,
        solve_seconds: stats.solve_seconds,
        collision_seconds: stats.collision_seconds,
        measure_seconds: stats.measure_seconds,
        factor_seconds: stats.solver.factor_seconds,
        factorisations: stats.solver.factorisations,
        low_rank_columns: stats.solver.low_rank_columns,
        cg_iterations: stats.solver.cg_iterations,
        pd_iterations: stats.solver.pd_iterations,
    }
}

/// Each object's report at the end of a run (lengths times `to_units`, from metres), with its
/// files.
pub(super) fn object_reports(
    world: &World,
    to_units: f64,
    mut files: Vec<Vec<String>>,
) -> Vec<ObjectReport> {
    let inside = sim::particles_inside(world);
    let clearance = sim::min_clearance(world);
    (world.colliders.iter().enumerate())
        .map(|(i, c)| ObjectReport {
            name: c.name.clone(),
            faces: c.mesh.faces.len(),
            cells: c.dims,
            grid_built_at: world.grid_built_at[i],
            closed: c.closed,
            particles_inside: inside[i],
            min_clearance: clearance[i] * to_units,
            files: std::mem::take(&mut files[i]),
        })
        .collect()
}

/// The stem of the scene file: the name of the checkpoint and of the glTF file.
pub(super) fn scene_stem(sc: &scene::Scene) -> String {
    sc.path
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned())
}

/// The checkpoint to continue from: with `--resume`, the one at `path`, which must belong to
/// this scene and these options; without, none (a checkpoint there is said to be left, and is
/// replaced when this run stops or removed when it completes).
fn read_checkpoint(
    path: &Path,
    now: &sim::checkpoint::Fingerprint,
    resume: bool,
) -> anyhow::Result<Option<sim::Checkpoint>> {
    if !resume {
        if path.exists() {
            eprintln!(
                "note: {} holds an interrupted run; this run starts over (--resume continues it)",
                path.display()
            );
        }
        return Ok(None);
    }
    if !path.exists() {
        anyhow::bail!(
            "--resume: there is no checkpoint {} to continue from (a run interrupted by Ctrl-C or SIGTERM writes it there); run without --resume to start",
            path.display()
        );
    }
    let c = sim::Checkpoint::read(path)?;
    c.check(now, path)?;
    Ok(Some(c))
}

/// After an interrupt: the finished frames put into place, the checkpoint written (atomically)
/// to `path`; the error that says where it is and how to resume.
fn keep_checkpoint(
    c: sim::Checkpoint,
    staged: Vec<io::Staged>,
    path: &Path,
    total: u64,
    inputs: &[&Path],
    signals: &super::interrupt::Signals,
) -> anyhow::Error {
    let kept = (|| -> anyhow::Result<()> {
        io::commit(staged)?;
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        c.write(path, inputs)?;
        Ok(())
    })();
    if let Err(e) = kept {
        return e.context("the run was interrupted, and its checkpoint could not be written");
    }
    let message = format!(
        "after step {} of {total} (t = {} s): its state is in {}; resume with: {}",
        c.step,
        crate::math::short(c.time),
        path.display(),
        super::interrupt::resume_command()
    );
    signals.interrupted(message).into()
}

/// Particles inside the closed objects, from each object's count (`None` for an open one);
/// `None` when there are objects and none is closed.
fn inside_total(per_object: &[Option<usize>]) -> Option<usize> {
    if !per_object.is_empty() && per_object.iter().all(Option::is_none) {
        return None;
    }
    Some(per_object.iter().flatten().sum())
}

/// The summary's count of particles inside objects, with the open objects (no inside test) named.
fn inside_text(r: &DrapeReport) -> String {
    let open = r.open_objects.join(", ");
    match r.particles_inside {
        None => format!("particles inside objects n/a (open: {open})"),
        Some(n) if open.is_empty() => format!("particles inside objects {n}"),
        Some(n) => format!("particles inside closed objects {n} (n/a for open: {open})"),
    }
}

/// The step for the summary: as the scene gave it, or chosen from the estimate (and said so).
fn step_text(r: &DrapeReport) -> String {
    if r.dt_from_estimate {
        format!(
            "{:.3e} s (no dt in the scene: {} of the stability estimate)",
            r.dt,
            crate::scene::EXPLICIT_STEP_FRACTION
        )
    } else {
        format!("{} s", crate::math::short(r.dt))
    }
}

fn print_summary(r: &DrapeReport) {
    println!(
        "{} -> {}: {} particles, {} springs, {} object faces; {} steps of {} ({}, {:.3} s simulated{})",
        r.scene,
        r.output_dir,
        r.particles,
        r.springs,
        r.object_faces,
        r.steps,
        step_text(r),
        r.integrator,
        r.time,
        if r.at_rest { ", came to rest" } else { "" }
    );
    println!(
        "  wall {:.3} s, collision {:.3} s; {} particles in contact at the end",
        r.wall_seconds, r.collision_seconds, r.contacts_end
    );
    println!(
        "  strain max {:.4} mean {:.4}; kinetic energy {:.3e} J; {}; min clearance {}",
        r.max_strain,
        r.mean_strain,
        r.kinetic_energy_end,
        inside_text(r),
        r.min_clearance.map_or("-".into(), |c| format!("{c:.4e}"))
    );
    for p in &r.pieces {
        if let Some(dc) = p.drape_coefficient {
            println!("  {}: drape coefficient {:.3}", p.name, dc);
        }
    }
}
