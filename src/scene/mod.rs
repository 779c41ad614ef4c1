//! Scene files (TOML), validated into typed options before any work starts.
//!
//! ```toml
//! units = "m"                      # all lengths of the file (not fabric tables): m, cm, mm
//! gravity = [0.0, 0.0, -9.81]      # length units per s^2 (default: 9.81 m/s^2 down z)
//! [solver]
//! integrator = "projective-dynamics" # (default; a [[garment]]'s: "implicit-euler") or
//!                                  # "implicit-euler", "leapfrog", "explicit-euler"
//! dt = 0.01                        # s (default: 0.01 s for the implicit integrators; for the
//!                                  # explicit ones, 0.9 of the cloth's stability estimate)
//! newton_iterations = 1            # implicit Euler: Newton steps per step (1: Baraff-Witkin; <= 100)
//! cg_tolerance = 1e-6              # implicit Euler: relative residual of conjugate gradients
//! cg_max_iterations = 1000         # implicit Euler (<= 100000)
//! bending_hessian = "exact"        # implicit Euler: or "lumped", the bending pairs no spring
//!                                  # joins moved onto the diagonal (faster; README)
//! iterations = 10                  # projective dynamics: local/global iterations per step (<= 1000)
//! anderson = 5                     # projective dynamics: Anderson acceleration's history (0: off)
//! strain_band = 0.01               # projective dynamics: springs free within 1% of rest length
//! strain_tolerance = 0.01          # projective dynamics: iterate on while a spring is over 1%
//! max_iterations = 20              # projective dynamics: ... up to this many in all
//! corrections = 1                  # projective dynamics: contact correction rounds (0: none)
//! chebyshev = 0.9                  # projective dynamics, with anderson = 0: Chebyshev's rho
//! steps = 10000                    # or duration = 1.0 (s), or until_rest = 1e-6 (J, kinetic)
//! max_steps = 1000000              # with until_rest: give up after this many
//! [collision]
//! cells = [50, 70, 30]             # per object, or "auto" (default)
//! [[object]]
//! mesh = "body.obj"                # any format drapekit reads, relative to this file; prepared
//! up = "y"                         # the mesh's up axis, rotated to z; also scale, translate
//! friction = 0.3                   # this object's friction (default: the fabric's)
//! [[piece]]
//! name = "skirt"                   # default piece1, piece2, ...; a file name (no / \ : ..)
//! outline = [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]
//! holes = [[[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]]  # optional cut-outs
//! spacing = 0.01
//! position = [0.0, 0.0, 0.5]       # where the piece's (0, 0) goes
//! rotation = [0.0, 0.0, 0.0]       # degrees about x, then y, then z
//! fabric = "cotton"                # a preset or a [fabric.NAME] table
//! pin = [[-0.5, 0.5], [0.5, 0.5]]  # outline points (or grid crossings) held fixed
//! pin_radius = 0.01                # also hold every particle this close to a pin (default 0)
//! pin_segments = [[[-0.5, 0.5], [0.5, 0.5]]]  # hold every particle on these segments
//! [fabric.soft]                    # SI units, whatever `units` says
//! base = "cotton"                  # start from a preset (optional), then override:
//! stretch = 2000                   # N/m, or [warp, weft]; also density, shear, bend, damping,
//!                                  # thickness, friction, or kes = {w, b, g, emt, t, miu}
//! [output]
//! ply = true                       # also write PLY
//! frames = 100                     # write every 100th step to frames/ (<= 10000 frames a run)
//! [report]
//! disc_radius = 0.09               # Cusick test: report the drape coefficient of each piece
//! ```
//! Any other key is an error that names it.

mod garment;
mod pieces;
mod solver;

use crate::cloth::fabric::Fabric;
use crate::cloth::integrate::SolverSettings;
use crate::cloth::pattern::Pins;
use crate::collide::grid::MAX_CELLS;
use crate::garment::drape::GarmentSettings;
use crate::garment::Pattern;
use crate::math::{short, Point2, Vec3};
use crate::mesh::transform::{Units, Up};
use crate::sim::settings::{Cells, Stop};
use serde::Deserialize;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Errors in a scene file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// TOML syntax, types, or unknown keys.
    #[error("{}: {message}", path.display())]
    Toml { path: PathBuf, message: String },
    /// A value that cannot be.
    #[error("{}: key '{key}': {message}", path.display())]
    Key {
        path: PathBuf,
        key: String,
        message: String,
    },
    /// Several values that cannot be: (key, message) each.
    #[error("{}: {}", path.display(), key_problems(problems))]
    Many {
        path: PathBuf,
        problems: Vec<(String, String)>,
    },
    /// An object's mesh (the mesh's own error, which names its file and line).
    #[error("{}: key '{key}': {error}", path.display())]
    Mesh {
        path: PathBuf,
        key: String,
        error: crate::io::IoError,
    },
    /// A piece's outline or pins.
    #[error("{}: key '{key}': {error}", path.display())]
    Piece {
        path: PathBuf,
        key: String,
        error: crate::cloth::pattern::PatternError,
    },
}

impl SceneError {
    /// One error for several: the error itself when alone, else [`SceneError::Many`] with each
    /// one's key and message.
    pub fn combine(path: &Path, mut errors: Vec<SceneError>) -> SceneError {
        if errors.len() == 1 {
            return errors.remove(0);
        }
        let problems = errors
            .into_iter()
            .flat_map(|e| match e {
                SceneError::Key { key, message, .. } => vec![(key, message)],
                SceneError::Mesh { key, error, .. } => vec![(key, error.to_string())],
                SceneError::Piece { key, error, .. } => vec![(key, error.to_string())],
                SceneError::Many { problems, .. } => problems,
                other => vec![(String::new(), other.to_string())],
            })
            .collect();
        SceneError::Many {
            path: path.to_path_buf(),
            problems,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    units: Option<String>,
    gravity: Option<[f64; 3]>,
    #[serde(default)]
    solver: SolverFile,
    collision: Option<CollisionFile>,
    #[serde(default)]
    object: Vec<ObjectFile>,
    #[serde(default)]
    piece: Vec<PieceFile>,
    #[serde(default)]
    garment: Vec<GarmentFile>,
    #[serde(default)]
    seam: Vec<SeamFile>,
    #[serde(default)]
    fabric: BTreeMap<String, FabricFile>,
    output: Option<OutputFile>,
    report: Option<ReportFile>,
}

/// The most rounds of contact corrections a scene may ask for (each costs a collision pass
/// and an iteration; two already leave no measurable sink).
pub const MAX_CORRECTIONS: u32 = 10;

/// The longest history of Anderson acceleration a scene may ask for (each vector is the
/// size of the cloth; more than a few stop paying).
pub const MAX_ANDERSON: u32 = 20;

/// The most projective-dynamics iterations per step (`solver.iterations`): each is a solve
/// with the factored matrix; the default is 10, and a few hundred converge any step.
pub const MAX_ITERATIONS: u32 = 1000;

/// The most Newton steps per step of implicit Euler (`solver.newton_iterations`; default 1).
pub const MAX_NEWTON_ITERATIONS: u32 = 100;

/// The most conjugate-gradient iterations per solve (`solver.cg_max_iterations`; default
/// 1000): CG converges in as many as there are unknowns in exact arithmetic, and a stiff
/// cloth needs a few thousand.
pub const MAX_CG_ITERATIONS: u32 = 100_000;

/// The most frames a run may write (`output.frames` against the run's most steps): each is a
/// mesh file per piece, and `--glb` holds them all in memory.
pub const MAX_FRAMES: u64 = 10_000;

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct SolverFile {
    integrator: Option<String>,
    dt: Option<f64>,
    newton_iterations: Option<u32>,
    cg_tolerance: Option<f64>,
    cg_max_iterations: Option<u32>,
    bending_hessian: Option<String>,
    iterations: Option<u32>,
    chebyshev: Option<f64>,
    anderson: Option<u32>,
    strain_band: Option<f64>,
    strain_tolerance: Option<f64>,
    max_iterations: Option<u32>,
    corrections: Option<u32>,
    steps: Option<u64>,
    duration: Option<f64>,
    until_rest: Option<f64>,
    max_steps: Option<u64>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum CellsFile {
    Dims([usize; 3]),
    Word(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CollisionFile {
    cells: Option<CellsFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectFile {
    mesh: String,
    name: Option<String>,
    up: Option<String>,
    scale: Option<f64>,
    translate: Option<[f64; 3]>,
    friction: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SeamFile {
    a: SeamSideFile,
    b: SeamSideFile,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SeamSideFile {
    piece: String,
    from: [f64; 2],
    to: [f64; 2],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PieceFile {
    name: Option<String>,
    outline: Vec<[f64; 2]>,
    #[serde(default)]
    holes: Vec<Vec<[f64; 2]>>,
    spacing: f64,
    position: Option<[f64; 3]>,
    rotation: Option<[f64; 3]>,
    fabric: Option<String>,
    #[serde(default)]
    pin: Vec<[f64; 2]>,
    pin_radius: Option<f64>,
    #[serde(default)]
    pin_segments: Vec<[[f64; 2]; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GarmentFile {
    pattern: String,
    fabric: Option<String>,
    spacing: Option<f64>,
    translation: Option<[f64; 3]>,
    rotation: Option<f64>,
    friction: Option<f64>,
    sew_max: Option<f64>,
    settle_max: Option<f64>,
    body_clearance: Option<f64>,
    self_collision: Option<bool>,
    cloth_friction: Option<f64>,
    hold_waist: Option<HoldWaistFile>,
    perturb: Option<u64>,
    keep_placement: Option<bool>,
    sew_spacing: Option<f64>,
    seam_ramp: Option<f64>,
}

/// `garment.hold_waist`: `"off"`, `"auto"` or a height in the scene's units.
#[derive(Deserialize)]
#[serde(untagged)]
enum HoldWaistFile {
    Word(String),
    Height(f64),
}

#[derive(Deserialize, Clone, Copy)]
#[serde(untagged)]
enum Pair {
    One(f64),
    Two([f64; 2]),
}

impl Pair {
    fn get(self) -> [f64; 2] {
        match self {
            Pair::One(v) => [v, v],
            Pair::Two(v) => v,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KesFile {
    w: f64,
    b: Pair,
    g: f64,
    emt: Pair,
    t: f64,
    miu: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FabricFile {
    base: Option<String>,
    kes: Option<KesFile>,
    density: Option<f64>,
    stretch: Option<Pair>,
    shear: Option<f64>,
    bend: Option<Pair>,
    damping: Option<f64>,
    thickness: Option<f64>,
    friction: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputFile {
    ply: Option<bool>,
    frames: Option<u64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ReportFile {
    disc_radius: Option<f64>,
}

/// An object, as the scene places it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectSpec {
    /// Name.
    pub name: String,
    /// The mesh file.
    pub mesh: PathBuf,
    /// Its up axis.
    pub up: Up,
    /// Scale applied first.
    pub scale: f64,
    /// Translation applied last, m.
    pub translate: Vec3,
    /// Friction, if the object has its own.
    pub friction: Option<f64>,
}

/// One side of a seam: the stretch of a piece's outline from corner `from` to corner `to`,
/// counter-clockwise (piece coordinates, metres).
#[derive(Debug, Clone, PartialEq)]
pub struct SeamSide {
    /// The piece's index in `Scene::pieces`.
    pub piece: usize,
    /// The corner the stretch starts at.
    pub from: Point2,
    /// The corner it ends at.
    pub to: Point2,
}

/// A seam of a scene: side `a` sewn to side `b`, `a`'s `from` to `b`'s `to` (two pieces'
/// counter-clockwise outlines run opposite ways along a seam between them).
#[derive(Debug, Clone, PartialEq)]
pub struct SeamSpec {
    /// One side.
    pub a: SeamSide,
    /// The other.
    pub b: SeamSide,
}

/// A piece, as the scene places it (lengths in metres).
#[derive(Debug, Clone, PartialEq)]
pub struct PieceSpec {
    /// Name.
    pub name: String,
    /// Outline in the piece's plane.
    pub outline: Vec<Point2>,
    /// Holes cut out of it (closed outlines inside it, apart from each other).
    pub holes: Vec<Vec<Point2>>,
    /// Particle spacing.
    pub spacing: f64,
    /// Where the piece's origin goes.
    pub position: Vec3,
    /// Degrees about x, then y, then z.
    pub rotation: [f64; 3],
    /// Its fabric.
    pub fabric: Fabric,
    /// The fabric's name.
    pub fabric_name: String,
    /// What holds it.
    pub pins: Pins,
}

/// A scene's garment: a GarmentCode pattern sewn on the scene's objects and draped
/// (`garment::drape`), as `drapekit garment` does on one body.
#[derive(Debug, Clone, PartialEq)]
pub struct GarmentSpec {
    /// The pattern file.
    pub path: PathBuf,
    /// The pattern, read and checked.
    pub pattern: Pattern,
    /// The garment's output name: the pattern file's stem without `_specification`.
    pub name: String,
    /// The fabric's name (a preset or a `[fabric.NAME]` table).
    pub fabric_name: String,
    /// Fabric, spacing, placement, friction, stages and solver (metres).
    pub settings: GarmentSettings,
}

/// A validated scene. Lengths in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// Units of the file (outputs are written in them).
    pub units: Units,
    /// Gravity, m/s^2.
    pub gravity: Vec3,
    /// The solver: integrator, step, iterations, tolerances.
    pub solver: SolverSettings,
    /// When to stop.
    pub stop: Stop,
    /// The file's `solver.duration`, s (the steps are recounted when the step is chosen later).
    pub duration: Option<f64>,
    /// The file gives no `dt` for an explicit integrator: the step is chosen from the cloth's
    /// stability estimate once it is built ([`Scene::choose_step`]).
    pub step_from_estimate: bool,
    /// Grid cells.
    pub cells: Cells,
    /// Objects.
    pub objects: Vec<ObjectSpec>,
    /// Pieces.
    pub pieces: Vec<PieceSpec>,
    /// Seams between pieces' outline stretches (`sim::seams`).
    pub seams: Vec<SeamSpec>,
    /// A garment sewn on the objects (then the scene has no pieces).
    pub garment: Option<GarmentSpec>,
    /// Also write PLY.
    pub ply: bool,
    /// Write every k-th step as a frame.
    pub frames: Option<u64>,
    /// Cusick disc radius, m.
    pub disc_radius: Option<f64>,
}

/// The shortest step a scene may ask for, s: the explicit integrators' stable steps for real
/// fabrics at 1 mm are about 1e-6 s; below about 1e-154 s `dt^2` underflows to 0 and the
/// implicit integrators' weights `m / dt^2` are infinite.
pub const DT_MIN: f64 = 1e-9;

/// The fraction of the cloth's stability estimate (conservative: Gershgorin's bound on the
/// highest frequency) an explicit integrator steps at when the scene gives no `dt`.
pub const EXPLICIT_STEP_FRACTION: f64 = 0.9;

/// The most steps a run may take, whether given (`solver.steps`, `solver.max_steps`) or counted
/// (`solver.duration / solver.dt`): 10^8 steps take days even for a small cloth, and a count from
/// a tiny `dt` would otherwise run for ever.
pub const MAX_STEPS: u64 = 100_000_000;

/// The most steps a scene without `dt` may be given by [`Scene::choose_step`]; beyond, the
/// integrator is the wrong one for the fabric and the spacing.
pub const MAX_CHOSEN_STEPS: u64 = 50_000_000;

impl Scene {
    /// For a scene without `dt` and an explicit integrator, the step: [`EXPLICIT_STEP_FRACTION`]
    /// of the cloth's stable-step estimate `stable_step` (s), the steps of a `duration`
    /// recounted. A no-op when the file gives `dt` or the integrator is implicit. An error
    /// (naming `solver.dt`) when the run would take more than [`MAX_CHOSEN_STEPS`] steps.
    pub fn choose_step(&mut self, stable_step: f64) -> Result<(), SceneError> {
        if !self.step_from_estimate {
            return Ok(());
        }
        let dt = EXPLICIT_STEP_FRACTION * stable_step;
        let steps = match self.duration {
            Some(t) => (t / dt).round().max(1.0),
            None => self.stop.max_steps() as f64,
        };
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(self.no_step(format!(
                "not given, and no stable step of {} can be estimated for this cloth (its stiffnesses and masses are out of range: check the fabric)",
                self.solver.integrator
            )));
        }
        if steps > MAX_CHOSEN_STEPS as f64 {
            return Err(self.no_step(format!(
                "not given, and {} is stable for this cloth only below {} s: {} steps for the run (at most {MAX_CHOSEN_STEPS}). Use the default integrator (projective dynamics), or give dt",
                self.solver.integrator,
                short(stable_step),
                short(steps)
            )));
        }
        self.solver.dt = dt;
        if self.duration.is_some() {
            self.stop = Stop::Steps(steps as u64);
        }
        if let Some(m) = self
            .frames
            .and_then(|k| too_many_frames(k, self.stop.max_steps()))
        {
            return Err(SceneError::Key {
                path: self.path.clone(),
                key: "output.frames".into(),
                message: m,
            });
        }
        Ok(())
    }
}

/// Why a frame every `every` steps over at most `steps` steps is too many frames (more than
/// [`MAX_FRAMES`]), or `None`.
fn too_many_frames(every: u64, steps: u64) -> Option<String> {
    let frames = steps / every.max(1);
    (frames > MAX_FRAMES).then(|| {
        format!(
            "a frame every {every} steps over up to {steps} steps is {frames} frames: at most {MAX_FRAMES}; give frames = {} or more, or stop sooner",
            steps.div_ceil(MAX_FRAMES)
        )
    })
}

impl Scene {
    /// The error of a scene whose step cannot be chosen.
    fn no_step(&self, message: String) -> SceneError {
        SceneError::Key {
            path: self.path.clone(),
            key: "solver.dt".into(),
            message,
        }
    }
}

/// Reads and validates a scene file (meshes are checked to exist, not read). Every problem of
/// the file is reported, not only the first: one is [`SceneError::Key`], several are
/// [`SceneError::Many`].
pub fn read(path: &Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path)
}

/// A TOML error of `text` for a message: its place and what is wrong on the first line
/// (`line 10, column 1: unknown field ...`), then the line quoted with a mark under the place.
/// (The `toml` crate's own text starts with a line that says only where.)
pub fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let what = e.message().trim_end();
    let Some(span) = e.span() else {
        return what.to_string();
    };
    let mut at = span.start.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line = text[..at].matches('\n').count() + 1;
    let column = text[start..at].chars().count() + 1;
    let quoted: Vec<String> = e
        .to_string()
        .lines()
        .skip(1)
        .take_while(|l| {
            l.trim_start()
                .starts_with(|c: char| c == '|' || c.is_ascii_digit())
        })
        .map(str::to_string)
        .collect();
    let mut m = format!("line {line}, column {column}: {what}");
    for q in quoted {
        m.push('\n');
        m.push_str(&q);
    }
    m
}

/// Parses and validates a scene file's `text`, as [`read`]: `path` names it in errors, and its
/// folder is where the objects' meshes are looked for.
pub fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let f: File = toml::from_str(text).map_err(|e| SceneError::Toml {
        path: path.to_path_buf(),
        message: toml_message(text, &e),
    })?;
    let p = Problems::default();
    let units = units(f.units.as_deref(), &p);
    let to_m = Units::factor(units, Units::M);
    let gravity = gravity(f.gravity, to_m, &p);
    let solver = solver::settings(&f.solver, &p);
    solver::foreign_keys(&f, solver.integrator, &p);
    let stop = solver::stop(&f, solver.dt, &p);
    let cells = collision_cells(f.collision.as_ref(), &p);
    let dir = path.parent().unwrap_or(Path::new("."));
    let objects = objects(&f.object, dir, to_m, &p);
    let fabrics = pieces::fabrics(&f.fabric, &p);
    let pieces = pieces::pieces(&f, &fabrics, to_m, &p);
    let seams = pieces::seams(&f.seam, &pieces, to_m, &p);
    let context = garment::GarmentContext {
        dir,
        to_m,
        fabrics: &fabrics,
        solver,
        solver_file: &f.solver,
    };
    let garment = garment::garment(&f, &context, &p);
    let (ply, frames) = output(f.output.as_ref(), stop, &p);
    let disc_radius = disc_radius(f.report.as_ref(), to_m, &p);
    p.verdict(
        path,
        Scene {
            path: path.to_path_buf(),
            units,
            gravity,
            step_from_estimate: f.solver.dt.is_none() && solver.integrator.is_explicit(),
            duration: f.solver.duration,
            solver,
            stop,
            cells,
            objects,
            pieces,
            seams,
            garment,
            ply,
            frames,
            disc_radius,
        },
    )
}

/// The problems of a scene file, by key, in the order they are found. Validation goes on after
/// a problem with a stand-in value, so that every problem of the file is reported, not only the
/// first.
#[derive(Default)]
struct Problems(RefCell<Vec<(String, String)>>);

impl Problems {
    /// Records a problem with `key`.
    fn bad(&self, key: &str, message: String) {
        self.0.borrow_mut().push((key.to_string(), message));
    }

    /// Records a problem with `key` unless every one of `values` is finite.
    fn finite(&self, key: &str, values: &[f64]) {
        if !values.iter().all(|x| x.is_finite()) {
            self.bad(key, "must be finite numbers".into());
        }
    }

    /// `value` (in whatever units the key has) if it is a finite number above 0, else
    /// `stand_in`, with a problem recorded for `key`.
    fn positive(&self, key: &str, value: f64, stand_in: f64) -> f64 {
        if value.is_finite() && value > 0.0 {
            value
        } else {
            self.bad(
                key,
                format!("must be a positive number, got {}", short(value)),
            );
            stand_in
        }
    }

    /// `scene` when no problem was found; else one problem as [`SceneError::Key`], several as
    /// [`SceneError::Many`], in the order found.
    fn verdict(self, path: &Path, scene: Scene) -> Result<Scene, SceneError> {
        let mut problems = self.0.into_inner();
        match problems.len() {
            0 => Ok(scene),
            1 => {
                let (key, message) = problems.remove(0);
                Err(SceneError::Key {
                    path: path.to_path_buf(),
                    key,
                    message,
                })
            }
            _ => Err(SceneError::Many {
                path: path.to_path_buf(),
                problems,
            }),
        }
    }
}

/// The file's `units` (m, cm or mm; default m).
fn units(units: Option<&str>, p: &Problems) -> Units {
    match units {
        None | Some("m") => Units::M,
        Some("cm") => Units::Cm,
        Some("mm") => Units::Mm,
        Some(u) => {
            p.bad("units", format!("unknown unit '{u}': expected m, cm or mm"));
            Units::M
        }
    }
}

/// `gravity`, in the file's length units per s^2, to m/s^2 (`to_m` metres per unit); default
/// 9.81 m/s^2 down z.
fn gravity(gravity: Option<[f64; 3]>, to_m: f64, p: &Problems) -> Vec3 {
    match gravity {
        Some(g) => {
            p.finite("gravity", &g);
            Vec3::from(g) * to_m
        }
        None => Vec3::new(0.0, 0.0, -9.81),
    }
}

/// `[collision] cells`: `"auto"` (default) or a count of grid cells along x, y and z (each
/// 1..4096, at most [`MAX_CELLS`] in all).
fn collision_cells(collision: Option<&CollisionFile>, p: &Problems) -> Cells {
    match collision.and_then(|c| c.cells.as_ref()) {
        None => Cells::Auto,
        Some(CellsFile::Word(w)) if w == "auto" => Cells::Auto,
        Some(CellsFile::Word(w)) => {
            p.bad(
                "collision.cells",
                format!("'{w}' is neither \"auto\" nor [nx, ny, nz]"),
            );
            Cells::Auto
        }
        Some(CellsFile::Dims(d)) if !d.iter().all(|&n| (1..=4096).contains(&n)) => {
            p.bad(
                "collision.cells",
                format!("{d:?}: each count must be within 1..4096"),
            );
            Cells::Auto
        }
        Some(CellsFile::Dims(d)) if d.iter().product::<usize>() > MAX_CELLS => {
            p.bad(
                "collision.cells",
                format!(
                    "{d:?} is {} cells: at most {MAX_CELLS} (2^24; each cell takes memory before any face is listed)",
                    d.iter().product::<usize>()
                ),
            );
            Cells::Auto
        }
        Some(CellsFile::Dims(d)) => Cells::Fixed(*d),
    }
}

/// The `[[object]]`s: meshes relative to `dir` (checked to exist, not read), translations in
/// the file's units to metres (`to_m` metres per unit).
fn objects(list: &[ObjectFile], dir: &Path, to_m: f64, p: &Problems) -> Vec<ObjectSpec> {
    list.iter()
        .enumerate()
        .map(|(i, o)| object(&format!("object[{}]", i + 1), o, dir, to_m, p))
        .collect()
}

/// One `[[object]]`, its keys named `at.field`: the mesh, its up axis, a scale (no unit), a
/// translation (file units, to metres) and a friction within 0..1.
fn object(at: &str, o: &ObjectFile, dir: &Path, to_m: f64, p: &Problems) -> ObjectSpec {
    let k = |field: &str| format!("{at}.{field}");
    let mesh = dir.join(&o.mesh);
    if !mesh.is_file() {
        p.bad(&k("mesh"), format!("{} does not exist", mesh.display()));
    }
    let up: Up = o.up.as_deref().unwrap_or("z").parse().unwrap_or_else(|m| {
        p.bad(&k("up"), m);
        Up::Z
    });
    let scale = p.positive(&k("scale"), o.scale.unwrap_or(1.0), 1.0);
    let translate = o.translate.unwrap_or([0.0; 3]);
    p.finite(&k("translate"), &translate);
    if let Some(fr) = o.friction {
        if !(0.0..=1.0).contains(&fr) {
            p.bad(
                &k("friction"),
                format!("must be within 0..1, got {}", short(fr)),
            );
        }
    }
    let name = o.name.clone().unwrap_or_else(|| {
        mesh.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    });
    ObjectSpec {
        name,
        mesh,
        up,
        scale,
        translate: Vec3::from(translate) * to_m,
        friction: o.friction,
    }
}

/// `[output]`: whether to also write PLY, and a frame every `frames` steps (0: none; at most
/// [`MAX_FRAMES`] over the run's most steps under `stop`).
fn output(out: Option<&OutputFile>, stop: Stop, p: &Problems) -> (bool, Option<u64>) {
    let (ply, frames) = out.map_or((None, None), |o| (o.ply, o.frames));
    let frames = frames.filter(|&k| k > 0);
    if let Some(m) = frames.and_then(|k| too_many_frames(k, stop.max_steps())) {
        p.bad("output.frames", m);
    }
    (ply.unwrap_or(false), frames)
}

/// `[report] disc_radius`: the Cusick disc's radius, file units to metres (`to_m` metres per
/// unit).
fn disc_radius(report: Option<&ReportFile>, to_m: f64, p: &Problems) -> Option<f64> {
    report
        .and_then(|r| r.disc_radius)
        .map(|r| p.positive("report.disc_radius", r, 0.09) * to_m)
}

/// Several problems by key, as every reader of keyed files (scenes, measurement sets) lists
/// them: "N problems:" then "key 'K': message" on a line each.
pub fn key_problems(problems: &[(String, String)]) -> String {
    let lines: String = (problems.iter())
        .map(|(k, m)| format!("\n  key '{k}': {m}"))
        .collect();
    format!("{} problems:{lines}", problems.len())
}

/// The finest relative step of f64 coordinates a piece needs: the gap between neighbouring
/// numbers where the piece reaches must be at most this fraction of its spacing.
pub const COORDINATE_RESOLUTION: f64 = 1e-6;

/// The same for the fabric's thickness (a contact's distance; a step's fall under gravity is of
/// that order): the gap between neighbouring numbers at most this fraction of it. A cotton
/// square 1e14 m from the origin, 0.02 m apart there, fell at every other step by rounding.
pub const THICKNESS_RESOLUTION: f64 = 1e-3;

/// The problem with a fabric named `name` that is neither a preset nor a `[fabric.NAME]` table.
fn unknown_preset(name: &str) -> String {
    let names: Vec<&str> = Fabric::presets().iter().map(|(n, _)| *n).collect();
    format!(
        "unknown fabric '{name}': the presets are {}, or define it in a [fabric.{name}] table",
        names.join(", ")
    )
}

/// The fabric named `name` (SI units): the scene's `[fabric.NAME]` table of that name, else the
/// preset; else cotton, with a problem recorded for `key`.
fn fabric_named(name: &str, fabrics: &BTreeMap<String, Fabric>, key: &str, p: &Problems) -> Fabric {
    match fabrics.get(name) {
        Some(fb) => fb.clone(),
        None => Fabric::preset(name).unwrap_or_else(|| {
            p.bad(key, unknown_preset(name));
            Fabric::cotton()
        }),
    }
}
