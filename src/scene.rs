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

use crate::cloth::fabric::{Fabric, Kes};
use crate::cloth::integrate::{Integrator, SolverSettings};
use crate::cloth::pattern::{self, Pins};
use crate::collide::grid::MAX_CELLS;
use crate::garment::assemble::Placement;
use crate::garment::drape::{
    GarmentSettings, WaistHold, GARMENT_BENDING_HESSIAN, GARMENT_INTEGRATOR, SEW_ITERATIONS,
};
use crate::garment::Pattern;
use crate::math::{short, Point2, Vec3};
use crate::mesh::transform::{Units, Up};
use crate::sim::settings::{Cells, Stop};
use serde::Deserialize;
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
    #[error("{}: {} problems:{}", path.display(), problems.len(), problems.iter().map(|(k, m)| format!("\n  key '{k}': {m}")).collect::<String>())]
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
    let problems = std::cell::RefCell::new(Vec::<(String, String)>::new());
    // Records a problem with a key; validation goes on with a stand-in value.
    let bad = |k: &str, m: String| problems.borrow_mut().push((k.to_string(), m));
    let finite = |k: &str, v: &[f64]| {
        if !v.iter().all(|x| x.is_finite()) {
            bad(k, "must be finite numbers".into());
        }
    };
    let positive = |k: &str, v: f64, stand_in: f64| -> f64 {
        if v.is_finite() && v > 0.0 {
            v
        } else {
            bad(k, format!("must be a positive number, got {}", short(v)));
            stand_in
        }
    };
    let units: Units = match f.units.as_deref() {
        None => Units::M,
        Some(u @ ("m" | "cm" | "mm")) => u.parse().unwrap(),
        Some(u) => {
            bad("units", format!("unknown unit '{u}': expected m, cm or mm"));
            Units::M
        }
    };
    let to_m = Units::factor(units, Units::M);
    let gravity = match f.gravity {
        Some(g) => {
            finite("gravity", &g);
            Vec3::from(g) * to_m
        }
        None => Vec3::new(0.0, 0.0, -9.81),
    };
    let integrator: Integrator = f
        .solver
        .integrator
        .as_deref()
        .map(|name| {
            name.parse().unwrap_or_else(|m| {
                bad("solver.integrator", m);
                Integrator::default()
            })
        })
        .unwrap_or_default();
    let mut solver = SolverSettings::new(integrator);
    if let Some(dt) = f.solver.dt {
        solver.dt = positive("solver.dt", dt, solver.dt);
        if solver.dt < DT_MIN {
            bad(
                "solver.dt",
                format!("{} s is below {DT_MIN:e} s (a drape would need more than a billion steps per simulated second, and at 1e-154 s and below dt^2 underflows to 0)", short(dt)),
            );
        }
    }
    let dt = solver.dt;
    // A count of iterations: 1 to `most`.
    let count = |k: &str, v: Option<u32>, most: u32, to: &mut u32| {
        if let Some(v) = v {
            if v == 0 {
                bad(k, "must be at least 1".into());
            } else if v > most {
                bad(k, format!("{v} iterations: at most {most}"));
            } else {
                *to = v;
            }
        }
    };
    count(
        "solver.newton_iterations",
        f.solver.newton_iterations,
        MAX_NEWTON_ITERATIONS,
        &mut solver.newton_iterations,
    );
    count(
        "solver.cg_max_iterations",
        f.solver.cg_max_iterations,
        MAX_CG_ITERATIONS,
        &mut solver.cg_max_iterations,
    );
    count(
        "solver.iterations",
        f.solver.iterations,
        MAX_ITERATIONS,
        &mut solver.iterations,
    );
    if let Some(t) = f.solver.cg_tolerance {
        if t.is_finite() && t > 0.0 && t < 1.0 {
            solver.cg_tolerance = t;
        } else {
            bad(
                "solver.cg_tolerance",
                format!("must be a number in (0, 1), got {}", short(t)),
            );
        }
    }
    if let Some(h) = &f.solver.bending_hessian {
        match h.parse() {
            Ok(h) => solver.bending_hessian = h,
            Err(m) => bad("solver.bending_hessian", m),
        }
    }
    if let Some(b) = f.solver.strain_band {
        if b.is_finite() && (0.0..1.0).contains(&b) {
            solver.strain_band = Some(b);
        } else {
            bad(
                "solver.strain_band",
                format!("must be a strain in [0, 1), got {}", short(b)),
            );
        }
    }
    if let Some(t) = f.solver.strain_tolerance {
        if t.is_finite() && t > 0.0 && t < 1.0 {
            solver.strain_tolerance = Some(t);
        } else {
            bad(
                "solver.strain_tolerance",
                format!("must be a strain in (0, 1), got {}", short(t)),
            );
        }
    }
    count(
        "solver.max_iterations",
        f.solver.max_iterations,
        MAX_ITERATIONS,
        &mut solver.max_iterations,
    );
    if let Some(c) = f.solver.corrections {
        if c <= MAX_CORRECTIONS {
            solver.corrections = c;
        } else {
            bad(
                "solver.corrections",
                format!("must be 0 (none) to {MAX_CORRECTIONS} rounds, got {c}"),
            );
        }
    }
    if let Some(m) = f.solver.anderson {
        if m <= MAX_ANDERSON {
            solver.anderson = m;
        } else {
            bad(
                "solver.anderson",
                format!("must be 0 (off) to {MAX_ANDERSON} vectors of history, got {m}"),
            );
        }
    }
    // (With another integrator the key is refused below, as not its own.)
    if let Some(r) = f
        .solver
        .chebyshev
        .filter(|_| integrator == Integrator::ProjectiveDynamics)
    {
        if solver.anderson > 0 {
            bad(
                "solver.chebyshev",
                "needs anderson = 0: the two accelerations do not combine (Anderson is on by default)".into(),
            );
        } else if r.is_finite() && r > 0.0 && r < 1.0 {
            solver.chebyshev = Some(r);
        } else {
            bad(
                "solver.chebyshev",
                format!("must be a spectral radius in (0, 1), got {}", short(r)),
            );
        }
    }
    // Each key given for another integrator than the scene's, by its own name.
    let (implicit, projective) = (Integrator::ImplicitEuler, Integrator::ProjectiveDynamics);
    let s = &f.solver;
    let owned = [
        (
            "solver.newton_iterations",
            s.newton_iterations.is_some(),
            implicit,
        ),
        ("solver.cg_tolerance", s.cg_tolerance.is_some(), implicit),
        (
            "solver.bending_hessian",
            s.bending_hessian.is_some(),
            implicit,
        ),
        (
            "solver.cg_max_iterations",
            s.cg_max_iterations.is_some(),
            implicit,
        ),
        ("solver.iterations", s.iterations.is_some(), projective),
        ("solver.chebyshev", s.chebyshev.is_some(), projective),
        ("solver.anderson", s.anderson.is_some(), projective),
        ("solver.strain_band", s.strain_band.is_some(), projective),
        (
            "solver.strain_tolerance",
            s.strain_tolerance.is_some(),
            projective,
        ),
        (
            "solver.max_iterations",
            s.max_iterations.is_some(),
            projective,
        ),
        ("solver.corrections", s.corrections.is_some(), projective),
    ];
    // A [[garment]] scene that names no integrator runs the garments' own.
    let integrator = if !f.garment.is_empty() && f.solver.integrator.is_none() {
        GARMENT_INTEGRATOR
    } else {
        integrator
    };
    for (key, given, owner) in owned {
        if given && integrator != owner {
            bad(
                key,
                format!("applies to integrator = \"{owner}\" only (this scene uses {integrator})"),
            );
        }
    }
    let s = &f.solver;
    let garment_stop =
        !f.garment.is_empty() && (s.steps, s.duration, s.until_rest) == (None, None, None);
    let stop = match (s.steps, s.duration, s.until_rest) {
        // A garment's stages end its run (`garment.sew_max`, `garment.settle_max`).
        _ if garment_stop => Stop::Steps(1),
        (Some(n), None, None) => {
            if n == 0 {
                bad("solver.steps", "must be at least 1".into());
            } else if n > MAX_STEPS {
                bad("solver.steps", format!("{n} steps: at most {MAX_STEPS}"));
            }
            Stop::Steps(n.clamp(1, MAX_STEPS))
        }
        (None, Some(t), None) => {
            let t = positive("solver.duration", t, dt);
            let steps = (t / dt).round().max(1.0);
            if steps > MAX_STEPS as f64 {
                bad(
                    "solver.duration",
                    format!("{} s at solver.dt = {dt:e} s is {steps:.3e} steps: at most {MAX_STEPS}; give a larger solver.dt or a shorter solver.duration", short(t)),
                );
            }
            Stop::Steps(steps.min(MAX_STEPS as f64) as u64)
        }
        (None, None, Some(e)) => {
            if !(e.is_finite() && e >= 0.0) {
                bad(
                    "solver.until_rest",
                    format!("must be a kinetic energy >= 0 (J), got {}", short(e)),
                );
            }
            Stop::UntilRest {
                energy: e,
                max_steps: s.max_steps.unwrap_or(1_000_000).clamp(1, MAX_STEPS),
            }
        }
        _ => {
            bad(
                "solver",
                "give exactly one of steps, duration or until_rest".into(),
            );
            Stop::Steps(1)
        }
    };
    if s.max_steps.is_some() && s.until_rest.is_none() && f.garment.is_empty() {
        bad("solver.max_steps", "goes with until_rest".into());
    }
    if let Some(n) = s.max_steps.filter(|&n| n > MAX_STEPS) {
        bad(
            "solver.max_steps",
            format!("{n} steps: at most {MAX_STEPS}"),
        );
    }
    let cells = match f.collision.as_ref().and_then(|c| c.cells.as_ref()) {
        None => Cells::Auto,
        Some(CellsFile::Word(w)) if w == "auto" => Cells::Auto,
        Some(CellsFile::Word(w)) => {
            bad(
                "collision.cells",
                format!("'{w}' is neither \"auto\" nor [nx, ny, nz]"),
            );
            Cells::Auto
        }
        Some(CellsFile::Dims(d)) if !d.iter().all(|&n| (1..=4096).contains(&n)) => {
            bad(
                "collision.cells",
                format!("{d:?}: each count must be within 1..4096"),
            );
            Cells::Auto
        }
        Some(CellsFile::Dims(d)) if d.iter().product::<usize>() > MAX_CELLS => {
            bad(
                "collision.cells",
                format!(
                    "{d:?} is {} cells: at most {MAX_CELLS} (2^24; each cell takes memory before any face is listed)",
                    d.iter().product::<usize>()
                ),
            );
            Cells::Auto
        }
        Some(CellsFile::Dims(d)) => Cells::Fixed(*d),
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut objects = Vec::new();
    for (i, o) in f.object.iter().enumerate() {
        let k = |field: &str| format!("object[{}].{field}", i + 1);
        let mesh = dir.join(&o.mesh);
        if !mesh.is_file() {
            bad(&k("mesh"), format!("{} does not exist", mesh.display()));
        }
        let up: Up = o.up.as_deref().unwrap_or("z").parse().unwrap_or_else(|m| {
            bad(&k("up"), m);
            Up::Z
        });
        let scale = positive(&k("scale"), o.scale.unwrap_or(1.0), 1.0);
        let translate = o.translate.unwrap_or([0.0; 3]);
        finite(&k("translate"), &translate);
        if let Some(fr) = o.friction {
            if !(0.0..=1.0).contains(&fr) {
                bad(
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
        objects.push(ObjectSpec {
            name,
            mesh,
            up,
            scale,
            translate: Vec3::from(translate) * to_m,
            friction: o.friction,
        });
    }
    // Fabrics: tables first, so pieces can use them.
    let mut fabrics: BTreeMap<String, Fabric> = BTreeMap::new();
    for (name, t) in &f.fabric {
        let k = |field: &str| format!("fabric.{name}.{field}");
        let mut fab = match (&t.base, &t.kes) {
            (Some(_), Some(_)) => {
                bad(
                    &format!("fabric.{name}"),
                    "give base or kes, not both".into(),
                );
                Fabric::cotton()
            }
            (Some(b), None) => Fabric::preset(b).unwrap_or_else(|| {
                bad(&k("base"), unknown_preset(b));
                Fabric::cotton()
            }),
            (None, Some(kes)) => Fabric::from_kes(
                &Kes {
                    w: kes.w,
                    b: kes.b.get(),
                    g: kes.g,
                    emt: kes.emt.get(),
                    t: kes.t,
                    miu: kes.miu,
                },
                0.5,
            ),
            (None, None) => Fabric::cotton(),
        };
        let full = t.base.is_some() || t.kes.is_some();
        let need = |v: Option<f64>, field: &str| {
            if v.is_none() && !full {
                bad(
                    &k(field),
                    "is required (or start from a preset with base = \"...\")".into(),
                );
            }
            v
        };
        if let Some(v) = need(t.density, "density") {
            fab.density = v;
        }
        if need(t.stretch.map(|p| p.get()[0]), "stretch").is_some() {
            fab.stretch = t.stretch.map(|p| p.get()).unwrap_or(fab.stretch);
        }
        if let Some(v) = need(t.shear, "shear") {
            fab.shear = v;
        }
        if need(t.bend.map(|p| p.get()[0]), "bend").is_some() {
            fab.bend = t.bend.map(|p| p.get()).unwrap_or(fab.bend);
        }
        if let Some(v) = t.damping {
            fab.damping = v;
        }
        if let Some(v) = t.thickness {
            fab.thickness = v;
        }
        if let Some(v) = t.friction {
            fab.friction = v;
        }
        for (field, m) in fab.problems() {
            bad(&k(field), m);
        }
        fabrics.insert(name.clone(), fab);
    }
    if f.piece.is_empty() && f.garment.is_empty() {
        bad(
            "piece",
            "a scene needs at least one [[piece]] (or a [[garment]])".into(),
        );
    }
    let mut pieces = Vec::new();
    for (i, p) in f.piece.iter().enumerate() {
        let k = |field: &str| format!("piece[{}].{field}", i + 1);
        let spacing = positive(&k("spacing"), p.spacing, 0.01) * to_m;
        let fabric_name = p.fabric.clone().unwrap_or_else(|| "cotton".into());
        let fabric = match fabrics.get(&fabric_name) {
            Some(fb) => fb.clone(),
            None => Fabric::preset(&fabric_name).unwrap_or_else(|| {
                bad(&k("fabric"), unknown_preset(&fabric_name));
                Fabric::cotton()
            }),
        };
        let position = p.position.unwrap_or([0.0; 3]);
        finite(&k("position"), &position);
        let reach = position
            .iter()
            .chain(p.outline.iter().flatten())
            .map(|v| v.abs())
            .fold(0.0, f64::max)
            * to_m;
        if let Some(m) = too_far(reach, spacing) {
            bad(&k("position"), m);
        }
        let rotation = p.rotation.unwrap_or([0.0; 3]);
        finite(&k("rotation"), &rotation);
        let outline: Vec<Point2> = p
            .outline
            .iter()
            .map(|q| Point2::new(q[0] * to_m, q[1] * to_m))
            .collect();
        if outline.len() < 3 {
            bad(
                &k("outline"),
                format!("a polygon needs at least 3 points, got {}", outline.len()),
            );
        } else if let Err(e) = pattern::check_particle_count(&outline, spacing) {
            bad(&k("spacing"), e.to_string());
        }
        let holes: Vec<Vec<Point2>> = p
            .holes
            .iter()
            .map(|h| {
                h.iter()
                    .map(|q| Point2::new(q[0] * to_m, q[1] * to_m))
                    .collect()
            })
            .collect();
        for q in &p.pin {
            finite(&k("pin"), q);
        }
        for q in &p.pin_segments {
            finite(&k("pin_segments"), &q.concat());
        }
        let pin_radius = match p.pin_radius {
            None => 0.0,
            Some(r) if r.is_finite() && r >= 0.0 => r * to_m,
            Some(r) => {
                bad(
                    &k("pin_radius"),
                    format!("must be a length >= 0, got {}", short(r)),
                );
                0.0
            }
        };
        let name = p.name.clone().unwrap_or_else(|| format!("piece{}", i + 1));
        if !crate::io::is_safe_file_name(&name) {
            bad(
                &k("name"),
                format!(
                    "{name:?} cannot be a file name in the output folder (the piece is written as <name>.obj): {}",
                    crate::io::FILE_NAME_RULE
                ),
            );
        }
        pieces.push(PieceSpec {
            name,
            outline,
            holes,
            spacing,
            position: Vec3::from(position) * to_m,
            rotation,
            fabric,
            fabric_name,
            pins: Pins {
                points: p
                    .pin
                    .iter()
                    .map(|q| Point2::new(q[0] * to_m, q[1] * to_m))
                    .collect(),
                radius: pin_radius,
                segments: p
                    .pin_segments
                    .iter()
                    .map(|s| s.map(|q| Point2::new(q[0] * to_m, q[1] * to_m)))
                    .collect(),
            },
        });
    }
    let mut names: Vec<&str> = pieces.iter().map(|p| p.name.as_str()).collect();
    names.sort_unstable();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        bad("piece.name", format!("two pieces are named '{}'", w[0]));
    }
    let mut seams = Vec::new();
    for (i, sf) in f.seam.iter().enumerate() {
        let side = |s: &SeamSideFile, which: &str| -> Option<SeamSide> {
            let key = format!("seam[{}].{which}", i + 1);
            finite(&format!("{key}.from"), &s.from);
            finite(&format!("{key}.to"), &s.to);
            let Some(piece) = pieces.iter().position(|p| p.name == s.piece) else {
                bad(
                    &format!("{key}.piece"),
                    format!("no piece is named '{}'", s.piece),
                );
                return None;
            };
            let pt = |q: [f64; 2]| Point2::new(q[0] * to_m, q[1] * to_m);
            Some(SeamSide {
                piece,
                from: pt(s.from),
                to: pt(s.to),
            })
        };
        if let (Some(a), Some(b)) = (side(&sf.a, "a"), side(&sf.b, "b")) {
            seams.push(SeamSpec { a, b });
        }
    }
    let garment = match f.garment.as_slice() {
        [] => None,
        [g] => {
            let context = GarmentContext {
                dir,
                to_m,
                fabrics: &fabrics,
                solver,
                solver_file: &f.solver,
            };
            garment_spec(g, &context, &bad)
        }
        [_, more @ ..] => {
            bad(
                "garment",
                format!(
                    "{} [[garment]] tables: a scene sews one garment (run a scene per garment)",
                    more.len() + 1
                ),
            );
            None
        }
    };
    if !f.garment.is_empty() {
        garment_limits(&f, &bad);
    }
    let out = f.output.unwrap_or(OutputFile {
        ply: None,
        frames: None,
    });
    let frames = out.frames.filter(|&k| k > 0);
    if let Some(m) = frames.and_then(|k| too_many_frames(k, stop.max_steps())) {
        bad("output.frames", m);
    }
    let disc_radius = f
        .report
        .and_then(|r| r.disc_radius)
        .map(|r| positive("report.disc_radius", r, 0.09) * to_m);
    let mut problems = problems.into_inner();
    match problems.len() {
        0 => Ok(Scene {
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
            ply: out.ply.unwrap_or(false),
            frames,
            disc_radius,
        }),
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

/// The finest relative step of f64 coordinates a piece needs: the gap between neighbouring
/// numbers where the piece reaches must be at most this fraction of its spacing.
pub const COORDINATE_RESOLUTION: f64 = 1e-6;

/// Why a piece of `spacing` reaching `reach` m from the origin (its position plus its
/// outline) is too far: there, neighbouring f64 numbers are more than
/// [`COORDINATE_RESOLUTION`] of the spacing apart, and the cloth's shape is lost to rounding.
fn too_far(reach: f64, spacing: f64) -> Option<String> {
    let gap = reach * f64::EPSILON;
    (gap.is_finite() && gap > COORDINATE_RESOLUTION * spacing).then(|| {
        format!(
            "reaches {} m from the origin, where coordinates are {} m apart: more than a millionth of the spacing ({} m), so rounding would break the cloth; place it within {} m of the origin",
            short(reach),
            short(gap),
            short(spacing),
            short(COORDINATE_RESOLUTION * spacing / f64::EPSILON)
        )
    })
}

fn unknown_preset(name: &str) -> String {
    let names: Vec<&str> = Fabric::presets().iter().map(|(n, _)| *n).collect();
    format!(
        "unknown fabric '{name}': the presets are {}, or define it in a [fabric.{name}] table",
        names.join(", ")
    )
}

/// What a `[[garment]]` reads from the rest of the scene.
struct GarmentContext<'a> {
    /// The scene file's folder (the pattern is relative to it).
    dir: &'a Path,
    /// Metres per unit of the file.
    to_m: f64,
    /// The scene's `[fabric.NAME]` tables.
    fabrics: &'a BTreeMap<String, Fabric>,
    /// The scene's solver.
    solver: SolverSettings,
    /// The solver table as written (which keys were given).
    solver_file: &'a SolverFile,
}

/// The scene's `[[garment]]`: the pattern read and checked, the settings validated, every
/// problem given to `bad` by key. `None` when the pattern cannot be read.
fn garment_spec(
    g: &GarmentFile,
    cx: &GarmentContext,
    bad: &dyn Fn(&str, String),
) -> Option<GarmentSpec> {
    let k = |field: &str| format!("garment.{field}");
    let mut settings = GarmentSettings::default();
    let fabric_name = g.fabric.clone().unwrap_or_else(|| "cotton".into());
    settings.assemble.fabric = match cx.fabrics.get(&fabric_name) {
        Some(fb) => fb.clone(),
        None => Fabric::preset(&fabric_name).unwrap_or_else(|| {
            bad(&k("fabric"), unknown_preset(&fabric_name));
            Fabric::cotton()
        }),
    };
    let length = |v: Option<f64>| v.map(|v| v * cx.to_m);
    if let Some(h) = length(g.spacing) {
        settings.assemble.spacing = h;
    }
    let translation = g.translation.unwrap_or([0.0; 3]);
    if !translation.iter().all(|v| v.is_finite()) {
        bad(&k("translation"), "must be finite numbers".into());
    }
    let turn = g.rotation.unwrap_or(0.0);
    if !turn.is_finite() {
        bad(
            &k("rotation"),
            format!("must be a finite angle in degrees, got {}", short(turn)),
        );
    }
    settings.assemble.placement = Placement {
        turn_deg: turn,
        translation: Vec3::from(translation) * cx.to_m,
    };
    settings.friction = g.friction.unwrap_or(settings.friction);
    settings.sew_max = g.sew_max.unwrap_or(settings.sew_max);
    settings.settle_max = g.settle_max.unwrap_or(settings.settle_max);
    settings.body_clearance = length(g.body_clearance);
    settings.hold_waist = match &g.hold_waist {
        None => settings.hold_waist,
        Some(HoldWaistFile::Height(z)) => WaistHold::Level(z * cx.to_m),
        Some(HoldWaistFile::Word(w)) => match w.as_str() {
            "off" => WaistHold::Off,
            "auto" => WaistHold::Auto,
            _ => {
                let m =
                    format!("expected \"off\", \"auto\" or a height (scene units), got \"{w}\"");
                bad(&k("hold_waist"), m);
                WaistHold::Off
            }
        },
    };
    settings.perturb = g.perturb;
    settings.clear_panels = !g.keep_placement.unwrap_or(false);
    settings.sew_spacing = length(g.sew_spacing);
    settings.seam_ramp = g.seam_ramp;
    if g.self_collision == Some(false) {
        settings.self_collision = None;
    }
    if let (Some(opts), Some(f)) = (&mut settings.self_collision, g.cloth_friction) {
        opts.friction = f;
    }
    settings.solver = cx.solver;
    if cx.solver_file.integrator.is_none() {
        settings.solver.integrator = GARMENT_INTEGRATOR;
    }
    if cx.solver_file.iterations.is_none() {
        settings.solver.iterations = SEW_ITERATIONS;
    }
    if cx.solver_file.bending_hessian.is_none() {
        settings.solver.bending_hessian = GARMENT_BENDING_HESSIAN;
    }
    for p in settings.problems() {
        let key = match p.field {
            "integrator" => "solver.integrator".to_string(),
            "cloth_friction" if g.self_collision == Some(false) => k("self_collision"),
            field => k(field),
        };
        if p.field == "integrator" {
            bad(&key, p.message);
        } else {
            bad(&key, format!("{}, got {}", p.message, short(p.value)));
        }
    }
    let path = cx.dir.join(&g.pattern);
    if !path.is_file() {
        bad(
            &k("pattern"),
            format!(
                "{} does not exist (a GarmentCode specification JSON, relative to the scene file)",
                path.display()
            ),
        );
        return None;
    }
    let pattern = match crate::garment::read(&path) {
        Ok(p) => p,
        Err(e) => {
            bad(&k("pattern"), e.to_string());
            return None;
        }
    };
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "garment".into());
    let name = stem
        .strip_suffix("_specification")
        .unwrap_or(&stem)
        .to_string();
    let name = if crate::io::is_safe_file_name(&name) {
        name
    } else {
        "garment".into()
    };
    Some(GarmentSpec {
        path,
        pattern,
        name,
        fabric_name,
        settings,
    })
}

/// Refuses, by key, what a scene with a `[[garment]]` does not support.
fn garment_limits(f: &File, bad: &dyn Fn(&str, String)) {
    let with = "is not supported with a [[garment]]";
    if !f.piece.is_empty() {
        bad(
            "piece",
            format!("{with}: the garment's panels are the scene's cloth (drape pieces in a scene of their own)"),
        );
    }
    if !f.seam.is_empty() {
        bad(
            "seam",
            format!("{with}: the pattern's stitches are its seams"),
        );
    }
    if f.object.is_empty() {
        bad(
            "object",
            "a [[garment]] is sewn on the scene's objects: give at least one [[object]] (the first is the body)".into(),
        );
    }
    if f.gravity.is_some() {
        bad(
            "gravity",
            format!("{with}: a garment hangs under 9.81 m/s^2 down z (turn the body with its object's `up`)"),
        );
    }
    let s = &f.solver;
    for (key, given) in [
        ("solver.steps", s.steps.is_some()),
        ("solver.duration", s.duration.is_some()),
        ("solver.until_rest", s.until_rest.is_some()),
        ("solver.max_steps", s.max_steps.is_some()),
    ] {
        if given {
            bad(
                key,
                format!("{with}: the garment's stages end its run (garment.sew_max, garment.settle_max)"),
            );
        }
    }
    if f.output.as_ref().is_some_and(|o| o.frames.is_some()) {
        bad(
            "output.frames",
            format!("{with}: a garment's run writes no frames"),
        );
    }
    if f.report.as_ref().is_some_and(|r| r.disc_radius.is_some()) {
        bad(
            "report.disc_radius",
            format!("{with}: the Cusick coefficient is for a single piece"),
        );
    }
}
