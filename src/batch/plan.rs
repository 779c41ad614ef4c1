//! The plan file (TOML): the axes and the jobs they make.
//!
//! ```toml
//! fabrics = ["cotton", "silk", "soft"]   # presets, or [fabric.NAME] tables (scene jobs)
//! [solver]                 # every scene job's [solver] keys replaced by these (dt, iterations,
//! duration = 0.3           # integrator, anderson, newton_iterations; a stop: steps, duration,
//!                          # until_rest, max_steps; a stop given here replaces the scene's)
//! [garment_solver]         # pattern jobs: sew_max, settle_max (simulated s), integrator
//! [resources]              # per job: cpus (1), mem_mb (2048), minutes (60, also the local
//!                          # time limit); throttle: most array tasks at once under Slurm (0: no limit)
//! [[garment]]              # the first axis: scenes or patterns
//! name = "square"
//! scene = "scenes/cotton_on_sphere.toml"   # relative to the plan
//! body_object = "sphere"   # the object a body replaces and a size scales (default: the first)
//! [[garment]]
//! name = "dress"
//! pattern = "dress.json"   # a GarmentCode specification; spacing = 0.01 (m, the resolution)
//! [[body]]                 # mesh = "body.obj" (up = "z" or "y"), or measurements = "m.toml"
//! name = "size38"          # (fitted once into OUT/bodies/, metres, y up)
//! measurements = "measurements_size38.toml"
//! [[size]]
//! name = "s"
//! scale = 0.95             # the body scaled about its origin
//! [[job]]                  # optional: these jobs instead of the product of the axes
//! garment = "square"       # body, fabric, size: required when the plan has that axis
//! ```
//!
//! Jobs: the product garments x bodies x fabrics x sizes (an absent axis counts once, as
//! "the scene's own"), garments outermost, or the `[[job]]` list in its order. A job's id is
//! its axis values' names joined by `.` (`square.cotton.s`): it depends on nothing else, so
//! adding a value to an axis keeps every id. Names are 1 to 64 of `A-Z a-z 0-9 _ -`. A plan
//! makes at most [`MAX_JOBS`] jobs (by its product or its list), refused by key beyond.

use super::BatchError;
use serde::Deserialize;
use sha2::{Digest, Sha256};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanFile {
    fabrics: Option<Vec<String>>,
    solver: Option<SolverFile>,
    garment_solver: Option<GarmentSolverFile>,
    resources: Option<ResourcesFile>,
    #[serde(default)]
    garment: Vec<GarmentFile>,
    #[serde(default)]
    body: Vec<BodyFile>,
    #[serde(default)]
    fabric: BTreeMap<String, toml::Table>,
    #[serde(default)]
    size: Vec<SizeFile>,
    #[serde(default)]
    job: Vec<JobFile>,
}

/// The scene keys a plan may set for every scene job (`[solver]`), as in a scene file.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct SolverOverrides {
    /// Integrator name (the scene's `solver.integrator`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub integrator: Option<String>,
    /// Step, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// Projective dynamics: iterations per step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<u32>,
    /// Projective dynamics: Anderson history.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anderson: Option<u32>,
    /// Implicit Euler: Newton steps per step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub newton_iterations: Option<u32>,
    /// Stop after this many steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
    /// Stop after this simulated time, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
    /// Stop at rest (kinetic energy below this, J).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub until_rest: Option<f64>,
    /// With `until_rest`: give up after this many steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_steps: Option<u64>,
}

impl SolverOverrides {
    /// Whether a stop condition is given (it then replaces the scene's).
    pub fn has_stop(&self) -> bool {
        self.steps.is_some() || self.duration.is_some() || self.until_rest.is_some()
    }
}

type SolverFile = SolverOverrides;

/// Settings of pattern (`garment`) jobs.
#[derive(Debug, Clone, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct GarmentSolver {
    /// Longest sewing stage, simulated s (default 4).
    #[serde(default = "default_sew")]
    pub sew_max: f64,
    /// Longest drape after sewing, simulated s (default 8).
    #[serde(default = "default_settle")]
    pub settle_max: f64,
    /// Integrator (default: projective-dynamics).
    #[serde(default)]
    pub integrator: Option<String>,
}

fn default_sew() -> f64 {
    4.0
}
fn default_settle() -> f64 {
    8.0
}

impl Default for GarmentSolver {
    fn default() -> Self {
        GarmentSolver {
            sew_max: default_sew(),
            settle_max: default_settle(),
            integrator: None,
        }
    }
}

type GarmentSolverFile = GarmentSolver;

/// What each job may use: the sbatch script's resources, and the local time limit.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Resources {
    /// Cores per job under a scheduler (default 1).
    #[serde(default = "one")]
    pub cpus: u32,
    /// Memory per job, MB (default 2048).
    #[serde(default = "default_mem")]
    pub mem_mb: u64,
    /// Wall-time limit per job, minutes (default 60); a local job past it is killed and failed.
    #[serde(default = "default_minutes")]
    pub minutes: u64,
    /// Most array tasks running at once under Slurm (0: no limit; default 0).
    #[serde(default)]
    pub throttle: u32,
}

fn one() -> u32 {
    1
}
fn default_mem() -> u64 {
    2048
}
fn default_minutes() -> u64 {
    60
}

impl Default for Resources {
    fn default() -> Self {
        Resources {
            cpus: 1,
            mem_mb: default_mem(),
            minutes: default_minutes(),
            throttle: 0,
        }
    }
}

type ResourcesFile = Resources;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GarmentFile {
    name: String,
    scene: Option<String>,
    pattern: Option<String>,
    spacing: Option<f64>,
    body_object: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BodyFile {
    name: String,
    mesh: Option<String>,
    measurements: Option<String>,
    up: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SizeFile {
    name: String,
    scale: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JobFile {
    garment: String,
    body: Option<String>,
    fabric: Option<String>,
    size: Option<String>,
}

/// A value of the first axis: what is draped.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Garment {
    /// Its name (in job ids).
    pub name: String,
    /// A scene or a pattern.
    pub kind: GarmentKind,
}

/// A scene file, or a sewing pattern.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GarmentKind {
    /// `drapekit drape` on the scene, its fabrics and solver overridden.
    Scene {
        /// The scene file (absolute).
        file: PathBuf,
        /// The object a body replaces and a size scales (`None`: the first).
        body_object: Option<String>,
    },
    /// `drapekit garment` on the pattern.
    Pattern {
        /// The GarmentCode specification (absolute).
        file: PathBuf,
        /// Particle spacing, m.
        spacing: f64,
    },
}

/// A body: a mesh, or measurements fitted into a form.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Body {
    /// Its name.
    pub name: String,
    /// Where it comes from.
    pub source: BodySource,
}

/// A body's source.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BodySource {
    /// A mesh file and its up axis.
    Mesh {
        /// The file (absolute).
        file: PathBuf,
        /// Its up axis: `y` or `z`.
        up: crate::mesh::transform::Up,
    },
    /// A measurements TOML file, fitted by `drapekit fit`.
    Measurements {
        /// The file (absolute).
        file: PathBuf,
    },
}

/// A fabric: a preset, or a table of the plan (scene jobs only).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FabricChoice {
    /// Its name.
    pub name: String,
    /// The plan's `[fabric.NAME]` table (`None`: a preset).
    pub table: Option<toml::Table>,
}

/// A size: the body scaled about its origin.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Size {
    /// Its name.
    pub name: String,
    /// The scale factor.
    pub scale: f64,
}

/// One job: an index into each axis (`None`: the plan has no such axis).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Job {
    /// The id (the names joined by `.`).
    pub id: String,
    /// Garment.
    pub garment: usize,
    /// Body.
    pub body: Option<usize>,
    /// Fabric.
    pub fabric: Option<usize>,
    /// Size.
    pub size: Option<usize>,
}

/// A validated plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The plan file.
    pub path: PathBuf,
    /// Garments and scenes.
    pub garments: Vec<Garment>,
    /// Bodies.
    pub bodies: Vec<Body>,
    /// Fabrics.
    pub fabrics: Vec<FabricChoice>,
    /// Sizes.
    pub sizes: Vec<Size>,
    /// Scene jobs' solver keys.
    pub solver: SolverOverrides,
    /// Pattern jobs' settings.
    pub garment_solver: GarmentSolver,
    /// Per-job resources.
    pub resources: Resources,
    /// The jobs, in the plan's order.
    pub jobs: Vec<Job>,
}

/// The keys a `[fabric.NAME]` table may hold (a scene's fabric table).
const FABRIC_KEYS: [&str; 9] = [
    "base",
    "kes",
    "density",
    "stretch",
    "shear",
    "bend",
    "damping",
    "thickness",
    "friction",
];

/// The most jobs a plan may make, by the product of its axes or by its `[[job]]` list: each is
/// a folder of outputs, a status and a row of the table (and a task of a scheduler's array).
pub const MAX_JOBS: usize = 100_000;

/// Collects problems as (key, message).
#[derive(Default)]
struct Problems(Vec<(String, String)>);

impl Problems {
    fn add(&mut self, key: impl Into<String>, message: impl Into<String>) {
        self.0.push((key.into(), message.into()));
    }
}

/// Whether `s` is a valid axis-value name.
pub fn valid_name(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= 64
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

/// Reads and validates a plan; every problem found is reported, each with its key.
pub fn read(path: &Path) -> Result<Plan, BatchError> {
    let text = std::fs::read_to_string(path).map_err(|source| BatchError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path)
}

/// Parses and validates a plan's `text`, as [`read`]: `path` names it in errors, and the files
/// the plan names are looked for relative to its folder.
pub fn parse(text: &str, path: &Path) -> Result<Plan, BatchError> {
    let f: PlanFile = toml::from_str(text).map_err(|e| BatchError::Toml {
        path: path.to_path_buf(),
        message: crate::scene::toml_message(text, &e),
    })?;
    let dir = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let mut p = Problems::default();
    let garments = garments(&f.garment, &dir, &mut p);
    let bodies = bodies(&f.body, &dir, &mut p);
    let fabrics = fabrics(f.fabrics.as_deref(), &f.fabric, &mut p);
    let sizes = sizes(&f.size, &mut p);
    let solver = f.solver.unwrap_or_default();
    check_solver(&solver, &mut p);
    let garment_solver = f.garment_solver.unwrap_or_default();
    check_garment_solver(&garment_solver, &mut p);
    let resources = f.resources.unwrap_or_default();
    check_resources(&resources, &mut p);
    let mut plan = Plan {
        path: path.to_path_buf(),
        garments,
        bodies,
        fabrics,
        sizes,
        solver,
        garment_solver,
        resources,
        jobs: Vec::new(),
    };
    plan.jobs = if !f.job.is_empty() {
        if f.job.len() > MAX_JOBS {
            p.add(
                "job",
                format!(
                    "{} [[job]] entries: at most {MAX_JOBS}; split the plan",
                    f.job.len()
                ),
            );
            Vec::new()
        } else {
            plan.listed(&f.job, &mut p)
        }
    } else {
        match plan.product_count() {
            Ok(_) => plan.product(),
            Err(message) => {
                p.add("garment x body x fabrics x size", message);
                Vec::new()
            }
        }
    };
    plan.check_jobs(&mut p);
    if p.0.is_empty() {
        Ok(plan)
    } else {
        Err(BatchError::Plan {
            path: path.to_path_buf(),
            problems: p.0,
        })
    }
}

fn check_name<'a>(key: &str, name: &'a str, seen: &mut HashSet<&'a str>, p: &mut Problems) {
    if !valid_name(name) {
        p.add(
            key,
            format!("'{name}' is not a name: 1 to 64 of A-Z a-z 0-9 _ - (it goes into job ids and folder names)"),
        );
    } else if !seen.insert(name) {
        p.add(key, format!("'{name}' is given twice"));
    }
}

/// An axis's names for a message: all of a short axis, the first ten of a long one.
fn names_listed(names: &[&str]) -> String {
    const SHOWN: usize = 10;
    if names.len() <= SHOWN {
        names.join(", ")
    } else {
        format!(
            "{}, ... ({} in all)",
            names[..SHOWN].join(", "),
            names.len()
        )
    }
}

/// An axis's values by name: each name's index, and the names as a problem lists them.
type Axis = (HashMap<String, usize>, String);

/// The axis of `names`, in order.
fn axis_index(names: Vec<&str>) -> Axis {
    let index = names
        .iter()
        .enumerate()
        .map(|(k, n)| (n.to_string(), k))
        .collect();
    (index, names_listed(&names))
}

/// Job `i`'s value `v` of the axis `key`: its index (`None`: no value, and the plan has no
/// such axis), or `Err` with the problem added to `p`.
fn listed_value(
    p: &mut Problems,
    i: usize,
    key: &str,
    v: Option<&String>,
    (index, names): &Axis,
) -> Result<Option<usize>, ()> {
    match (v, index.is_empty()) {
        (None, true) => Ok(None),
        (Some(v), false) => match index.get(v) {
            Some(&k) => Ok(Some(k)),
            None => {
                p.add(
                    format!("job[{i}].{key}"),
                    format!("'{v}' is not one of {names}"),
                );
                Err(())
            }
        },
        (None, false) => {
            p.add(
                format!("job[{i}].{key}"),
                format!("missing: the plan's {key}s are {names}"),
            );
            Err(())
        }
        (Some(_), true) => {
            p.add(
                format!("job[{i}].{key}"),
                format!("the plan has no {key} axis"),
            );
            Err(())
        }
    }
}

/// A file named by the plan, relative to the plan's folder: absolute, and checked to exist.
fn input(dir: &Path, key: &str, file: &str, p: &mut Problems) -> PathBuf {
    let f = dir.join(file);
    match f.canonicalize() {
        Ok(a) if a.is_file() => a,
        _ => {
            p.add(key, format!("{} is not a file", f.display()));
            f
        }
    }
}

fn garments(files: &[GarmentFile], dir: &Path, p: &mut Problems) -> Vec<Garment> {
    if files.is_empty() {
        p.add(
            "garment",
            "the plan needs at least one [[garment]] (a scene or a pattern)",
        );
    }
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for (i, g) in files.iter().enumerate() {
        let k = |s: &str| format!("garment[{i}].{s}");
        check_name(&k("name"), &g.name, &mut seen, p);
        let kind = match (&g.scene, &g.pattern) {
            (Some(s), None) => {
                if g.spacing.is_some() {
                    p.add(k("spacing"), "a scene gives its own spacing (per piece)");
                }
                GarmentKind::Scene {
                    file: input(dir, &k("scene"), s, p),
                    body_object: g.body_object.clone(),
                }
            }
            (None, Some(pat)) => {
                if g.body_object.is_some() {
                    p.add(k("body_object"), "only a scene has objects");
                }
                let spacing = g.spacing.unwrap_or(0.01);
                if !(spacing.is_finite() && spacing > 0.0) {
                    p.add(
                        k("spacing"),
                        format!(
                            "must be a positive length in m, got {}",
                            crate::math::short(spacing)
                        ),
                    );
                }
                GarmentKind::Pattern {
                    file: input(dir, &k("pattern"), pat, p),
                    spacing,
                }
            }
            _ => {
                p.add(
                    k("scene"),
                    "give exactly one of scene = \"...\" and pattern = \"...\"",
                );
                continue;
            }
        };
        out.push(Garment {
            name: g.name.clone(),
            kind,
        });
    }
    out
}

fn bodies(files: &[BodyFile], dir: &Path, p: &mut Problems) -> Vec<Body> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for (i, b) in files.iter().enumerate() {
        let k = |s: &str| format!("body[{i}].{s}");
        check_name(&k("name"), &b.name, &mut seen, p);
        let source = match (&b.mesh, &b.measurements) {
            (Some(m), None) => {
                let up = match b.up.as_deref() {
                    None | Some("z") => crate::mesh::transform::Up::Z,
                    Some("y") => crate::mesh::transform::Up::Y,
                    Some(u) => {
                        p.add(k("up"), format!("'{u}': expected y or z"));
                        crate::mesh::transform::Up::Z
                    }
                };
                BodySource::Mesh {
                    file: input(dir, &k("mesh"), m, p),
                    up,
                }
            }
            (None, Some(m)) => {
                if b.up.is_some() {
                    p.add(k("up"), "a fitted form is written y up, in metres");
                }
                BodySource::Measurements {
                    file: input(dir, &k("measurements"), m, p),
                }
            }
            _ => {
                p.add(
                    k("mesh"),
                    "give exactly one of mesh = \"...\" and measurements = \"...\"",
                );
                continue;
            }
        };
        out.push(Body {
            name: b.name.clone(),
            source,
        });
    }
    out
}

fn fabrics(
    names: Option<&[String]>,
    tables: &BTreeMap<String, toml::Table>,
    p: &mut Problems,
) -> Vec<FabricChoice> {
    let names = names.unwrap_or_default();
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for (i, n) in names.iter().enumerate() {
        let key = format!("fabrics[{i}]");
        check_name(&key, n, &mut seen, p);
        let table = tables.get(n).cloned();
        if table.is_none() && crate::cloth::fabric::Fabric::preset(n).is_none() {
            let presets: Vec<_> = crate::cloth::fabric::Fabric::presets()
                .iter()
                .map(|(n, _)| *n)
                .collect();
            p.add(
                key,
                format!(
                    "'{n}' is neither a preset ({}) nor a [fabric.{n}] table",
                    presets.join(", ")
                ),
            );
        }
        out.push(FabricChoice {
            name: n.clone(),
            table,
        });
    }
    let listed: HashSet<&str> = names.iter().map(String::as_str).collect();
    for (name, t) in tables {
        if !listed.contains(name.as_str()) {
            p.add(
                format!("fabric.{name}"),
                "defined but not listed in fabrics = [...]",
            );
        }
        for key in t.keys() {
            if !FABRIC_KEYS.contains(&key.as_str()) {
                p.add(
                    format!("fabric.{name}.{key}"),
                    format!("unknown key: expected one of {}", FABRIC_KEYS.join(", ")),
                );
            }
        }
    }
    out
}

fn sizes(files: &[SizeFile], p: &mut Problems) -> Vec<Size> {
    let mut seen = HashSet::new();
    files
        .iter()
        .enumerate()
        .map(|(i, s)| {
            check_name(&format!("size[{i}].name"), &s.name, &mut seen, p);
            let scale = s.scale.unwrap_or(1.0);
            if !(scale.is_finite() && (0.1..=10.0).contains(&scale)) {
                p.add(
                    format!("size[{i}].scale"),
                    format!(
                        "must be a factor from 0.1 to 10, got {}",
                        crate::math::short(scale)
                    ),
                );
            }
            Size {
                name: s.name.clone(),
                scale,
            }
        })
        .collect()
}

fn positive(p: &mut Problems, key: &str, v: Option<f64>) {
    if let Some(v) = v {
        if !(v.is_finite() && v > 0.0) {
            p.add(
                key,
                format!("must be a positive number, got {}", crate::math::short(v)),
            );
        }
    }
}

fn integrator(p: &mut Problems, key: &str, v: Option<&str>) {
    if let Some(v) = v {
        if v.parse::<crate::cloth::Integrator>().is_err() {
            p.add(
                key,
                format!("'{v}': expected projective-dynamics, implicit-euler, leapfrog or explicit-euler"),
            );
        }
    }
}

/// A count of 1 to `most` (the scene file's limits).
fn count(p: &mut Problems, key: &str, v: Option<u64>, most: u64, what: &str) {
    match v {
        Some(0) => p.add(key, "must be at least 1"),
        Some(v) if v > most => p.add(key, format!("{v} {what}: at most {most}")),
        _ => {}
    }
}

fn check_solver(s: &SolverOverrides, p: &mut Problems) {
    use crate::scene;
    let wide = |v: Option<u32>| v.map(u64::from);
    count(
        p,
        "solver.iterations",
        wide(s.iterations),
        scene::MAX_ITERATIONS.into(),
        "iterations",
    );
    count(
        p,
        "solver.newton_iterations",
        wide(s.newton_iterations),
        scene::MAX_NEWTON_ITERATIONS.into(),
        "iterations",
    );
    count(p, "solver.steps", s.steps, scene::MAX_STEPS, "steps");
    count(
        p,
        "solver.max_steps",
        s.max_steps,
        scene::MAX_STEPS,
        "steps",
    );
    if let Some(m) = s.anderson.filter(|&m| m > scene::MAX_ANDERSON) {
        p.add(
            "solver.anderson",
            format!(
                "must be 0 (off) to {} vectors of history, got {m}",
                scene::MAX_ANDERSON
            ),
        );
    }
    positive(p, "solver.dt", s.dt);
    if let Some(dt) = s.dt.filter(|&dt| dt > 0.0 && dt < scene::DT_MIN) {
        let dt = crate::math::short(dt);
        p.add(
            "solver.dt",
            format!("{dt} s is below {:e} s", scene::DT_MIN),
        );
    }
    positive(p, "solver.duration", s.duration);
    positive(p, "solver.until_rest", s.until_rest);
    integrator(p, "solver.integrator", s.integrator.as_deref());
    let stops = [
        s.steps.is_some(),
        s.duration.is_some(),
        s.until_rest.is_some(),
    ];
    if stops.iter().filter(|b| **b).count() > 1 {
        p.add("solver", "give one stop: steps, duration or until_rest");
    }
}

fn check_garment_solver(s: &GarmentSolver, p: &mut Problems) {
    use crate::garment::drape::MAX_STAGE_SECONDS;
    for (key, v) in [
        ("garment_solver.sew_max", s.sew_max),
        ("garment_solver.settle_max", s.settle_max),
    ] {
        positive(p, key, Some(v));
        if v > MAX_STAGE_SECONDS {
            p.add(
                key,
                format!("{} s: at most {MAX_STAGE_SECONDS} s", crate::math::short(v)),
            );
        }
    }
    integrator(p, "garment_solver.integrator", s.integrator.as_deref());
}

fn check_resources(r: &Resources, p: &mut Problems) {
    if r.cpus == 0 {
        p.add("resources.cpus", "must be at least 1");
    }
    if r.mem_mb == 0 {
        p.add("resources.mem_mb", "must be at least 1");
    }
    if r.minutes == 0 {
        p.add("resources.minutes", "must be at least 1");
    }
}

impl Plan {
    /// The number of jobs the product of the axes makes, or why it is too many.
    fn product_count(&self) -> Result<usize, String> {
        let lengths = [
            self.garments.len(),
            self.bodies.len().max(1),
            self.fabrics.len().max(1),
            self.sizes.len().max(1),
        ];
        let count = lengths
            .iter()
            .try_fold(1usize, |n, &l| n.checked_mul(l))
            .filter(|&n| n <= MAX_JOBS);
        count.ok_or_else(|| {
            let product: u128 = lengths.iter().map(|&l| l as u128).product();
            format!(
                "{} x {} x {} x {} is {product} jobs: at most {MAX_JOBS}; list the jobs wanted with [[job]] or split the plan",
                lengths[0], lengths[1], lengths[2], lengths[3]
            )
        })
    }

    /// Every combination of the axes, garments outermost, sizes innermost.
    fn product(&self) -> Vec<Job> {
        let axis = |n: usize| -> Vec<Option<usize>> {
            if n == 0 {
                vec![None]
            } else {
                (0..n).map(Some).collect()
            }
        };
        let mut jobs = Vec::new();
        for g in 0..self.garments.len() {
            for &b in &axis(self.bodies.len()) {
                for &f in &axis(self.fabrics.len()) {
                    for &s in &axis(self.sizes.len()) {
                        jobs.push(self.job(g, b, f, s));
                    }
                }
            }
        }
        jobs
    }

    fn job(
        &self,
        garment: usize,
        body: Option<usize>,
        fabric: Option<usize>,
        size: Option<usize>,
    ) -> Job {
        let mut parts = vec![self.garments[garment].name.as_str()];
        parts.extend(body.map(|i| self.bodies[i].name.as_str()));
        parts.extend(fabric.map(|i| self.fabrics[i].name.as_str()));
        parts.extend(size.map(|i| self.sizes[i].name.as_str()));
        Job {
            id: parts.join("."),
            garment,
            body,
            fabric,
            size,
        }
    }

    /// The `[[job]]` list, each value looked up by name.
    fn listed(&self, files: &[JobFile], p: &mut Problems) -> Vec<Job> {
        let garments = axis_index(self.garments.iter().map(|g| g.name.as_str()).collect());
        let bodies = axis_index(self.bodies.iter().map(|b| b.name.as_str()).collect());
        let fabrics = axis_index(self.fabrics.iter().map(|f| f.name.as_str()).collect());
        let sizes = axis_index(self.sizes.iter().map(|s| s.name.as_str()).collect());
        let mut jobs = Vec::new();
        let mut ids = HashSet::new();
        for (i, j) in files.iter().enumerate() {
            let g = listed_value(p, i, "garment", Some(&j.garment), &garments);
            let b = listed_value(p, i, "body", j.body.as_ref(), &bodies);
            let f = listed_value(p, i, "fabric", j.fabric.as_ref(), &fabrics);
            let s = listed_value(p, i, "size", j.size.as_ref(), &sizes);
            if let (Ok(Some(g)), Ok(b), Ok(f), Ok(s)) = (g, b, f, s) {
                let job = self.job(g, b, f, s);
                if !ids.insert(job.id.clone()) {
                    p.add(
                        format!("job[{i}]"),
                        format!("job {} is listed twice", job.id),
                    );
                } else {
                    jobs.push(job);
                }
            }
        }
        jobs
    }

    /// What every job needs: a body for a pattern, an object for a scene's body or size, presets
    /// for a pattern's fabric.
    fn check_jobs(&self, p: &mut Problems) {
        let mut by_garment: Vec<Vec<&Job>> = vec![Vec::new(); self.garments.len()];
        for j in &self.jobs {
            by_garment[j.garment].push(j);
        }
        for ((gi, g), jobs) in self.garments.iter().enumerate().zip(by_garment) {
            let key = format!("garment[{gi}]");
            match &g.kind {
                GarmentKind::Pattern { .. } => {
                    if jobs.iter().any(|j| j.body.is_none()) {
                        p.add(
                            &key,
                            format!("'{}' is a pattern: its jobs need a [[body]]", g.name),
                        );
                    }
                    if let Some(f) = jobs
                        .iter()
                        .filter_map(|j| j.fabric)
                        .find(|f| self.fabrics[*f].table.is_some())
                    {
                        p.add(&key, format!("'{}' is a pattern: its fabric must be a preset, not the table [fabric.{}]", g.name, self.fabrics[f].name));
                    }
                }
                GarmentKind::Scene { file, body_object } => {
                    let needs = jobs.iter().any(|j| j.body.is_some() || j.size.is_some());
                    // A scene that is not a file is reported once, by its own key.
                    if needs && file.is_file() {
                        if let Err(m) = scene_object(file, body_object.as_deref()) {
                            p.add(format!("{key}.body_object"), m);
                        }
                    }
                }
            }
        }
    }

    /// The axis values of a job, by name.
    pub fn axes(&self, job: &Job) -> Axes {
        Axes {
            garment: self.garments[job.garment].name.clone(),
            body: job.body.map(|i| self.bodies[i].name.clone()),
            fabric: job.fabric.map(|i| self.fabrics[i].name.clone()),
            size: job.size.map(|i| self.sizes[i].name.clone()),
        }
    }

    /// A hash of everything that defines a job (its axis values' definitions, the settings of
    /// its kind): a done job whose hash changed runs again.
    pub fn spec_hash(&self, job: &Job) -> String {
        let g = &self.garments[job.garment];
        let settings = match g.kind {
            GarmentKind::Scene { .. } => serde_json::to_value(&self.solver),
            GarmentKind::Pattern { .. } => serde_json::to_value(&self.garment_solver),
        };
        let spec = serde_json::json!({
            "garment": g,
            "body": job.body.map(|i| &self.bodies[i]),
            "fabric": job.fabric.map(|i| &self.fabrics[i]),
            "size": job.size.map(|i| &self.sizes[i]),
            "settings": settings.unwrap_or_default(),
        });
        short_hash(spec.to_string().as_bytes())
    }
}

/// The first 16 hex digits of the SHA-256 of `bytes`.
pub fn short_hash(bytes: &[u8]) -> String {
    let d = Sha256::digest(bytes);
    d[..8].iter().map(|b| format!("{b:02x}")).collect()
}

/// A job's axis values by name (`None`: the plan has no such axis).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Axes {
    /// Garment or scene.
    pub garment: String,
    /// Body.
    pub body: Option<String>,
    /// Fabric.
    pub fabric: Option<String>,
    /// Size.
    pub size: Option<String>,
}

/// The index of the scene's object that a body replaces and a size scales: the one named, or
/// the first. An error message when the scene has none (or not that one).
pub fn scene_object(scene: &Path, name: Option<&str>) -> Result<usize, String> {
    let text = std::fs::read_to_string(scene)
        .map_err(|e| format!("cannot read {}: {e}", scene.display()))?;
    let t: toml::Table = toml::from_str(&text).map_err(|e| format!("{}: {e}", scene.display()))?;
    let objects = t
        .get("object")
        .and_then(|o| o.as_array())
        .cloned()
        .unwrap_or_default();
    let names: Vec<String> = objects
        .iter()
        .map(|o| {
            let stem = || {
                let mesh = o.get("mesh").and_then(|m| m.as_str()).unwrap_or_default();
                Path::new(mesh)
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            };
            o.get("name")
                .and_then(|n| n.as_str())
                .map(str::to_string)
                .unwrap_or_else(stem)
        })
        .collect();
    match name {
        None if names.is_empty() => Err(format!(
            "{} has no [[object]] for a body to replace or a size to scale",
            scene.display()
        )),
        None => Ok(0),
        Some(n) => names.iter().position(|x| x == n).ok_or_else(|| {
            format!(
                "{} has no object '{n}' (its objects: {})",
                scene.display(),
                names.join(", ")
            )
        }),
    }
}
