//! `drapekit garment PATTERN.json --body BODY.obj -o OUT_DIR`: sew a GarmentCode pattern on a
//! body and let it hang, with no scene file.

use crate::cloth::fabric::Fabric;
use crate::collide::cloth::{SelfCollisionOptions, SelfStats};
use crate::garment::drape::{self as gd, GarmentSettings, StageReport};
use crate::garment::fit_check::{fit_check, FitCheck, FitCheckOptions, Ring};
use crate::garment::frame;
use crate::garment::measure::{self, Measures, Thresholds};
use crate::garment::spec::Pattern;
use crate::garment::spots::{spots, Spot, SpotKind};
use crate::io::{self, ReadOptions};
use crate::math::{short, Vec3};
use crate::mesh::prepare::{prepare, PrepareOptions};
use crate::mesh::transform::{change_up, change_up_point, Units, Up};
use crate::mesh::TriMesh;
use crate::sim;
use anyhow::{bail, Context};
use clap::Args;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Arguments of `drapekit garment`.
#[derive(Debug, Args)]
pub struct GarmentArgs {
    /// The sewing pattern (GarmentCode specification JSON).
    pub pattern: PathBuf,
    /// The body (a closed mesh, y up, in the pattern's frame: feet at y = 0, centred on x = 0 and
    /// z = 0; a body that is not under the panels is moved there, and the summary says so).
    #[arg(long, value_name = "BODY")]
    pub body: PathBuf,
    /// The output directory: the garment (one OBJ, a group per panel) and the body as placed.
    #[arg(short, long, value_name = "OUT_DIR")]
    pub output: PathBuf,
    /// Write the JSON report here.
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// Print the JSON report instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// The fabric preset (see the README's table).
    #[arg(long, default_value = "cotton")]
    pub fabric: String,
    /// Particle spacing, m.
    #[arg(long, default_value_t = 0.01)]
    pub spacing: f64,
    /// Friction between the garment and the body.
    #[arg(long, default_value_t = 0.5)]
    pub friction: f64,
    /// The body's units (`auto`: from its height, a standing person being 0.5 to 2.5 m tall).
    #[arg(long, default_value = "auto")]
    pub body_units: String,
    /// Longest sewing stage, simulated s.
    #[arg(long, default_value_t = 4.0)]
    pub sew_max: f64,
    /// Longest drape after sewing, simulated s.
    #[arg(long, default_value_t = 8.0)]
    pub settle_max: f64,
    /// Extra distance kept between the cloth and the body, m (default: an eighth of the
    /// spacing; edges between resting particles then stay out of a curved or faceted body).
    #[arg(long, value_name = "M")]
    pub body_clearance: Option<f64>,
    /// Turn cloth-against-cloth contact off (faster; panels may pass through each other).
    #[arg(long)]
    pub no_self_collision: bool,
    /// Turn the hinges over each panel's rim band off (on by default; the README's `bench
    /// garment` measures both).
    #[arg(long)]
    pub no_rim_bending: bool,
    /// Friction between layers of cloth (Coulomb, a fraction of the normal impulse).
    #[arg(long, default_value_t = 0.0)]
    pub cloth_friction: f64,
    /// The integrator: implicit-euler (default: contacts constrain the motion, and a drape
    /// settles in about a simulated second) or projective-dynamics. The explicit ones would
    /// need steps far below 10 ms.
    #[arg(long, default_value_t = crate::garment::drape::GARMENT_INTEGRATOR)]
    pub integrator: crate::cloth::integrate::Integrator,
    /// Implicit Euler's bending Hessian: exact (the default: the linearised backward Euler
    /// step) or lumped (the bending pairs no spring joins moved onto the diagonal: the same
    /// forces and states at rest, a factor half the size, 0.46 to 0.94 of the wall time;
    /// sewing goes on exact once it slows; the README's `bench garment` measures both)
    #[arg(long, default_value_t = crate::garment::drape::GARMENT_BENDING_HESSIAN, value_name = "exact|lumped")]
    pub bending_hessian: crate::cloth::integrate::direct::BendingHessian,
    /// Also write each panel alone, as `OUT_DIR/panels/<panel>.obj`.
    #[arg(long)]
    pub panels: bool,
    /// Also write OUT_DIR/<garment>.glb: each panel and the body as placed (metres, y up).
    #[arg(long)]
    pub glb: bool,
    /// Also write `OUT_DIR/<garment>.png`: the garment on the body, from the front.
    #[arg(long)]
    pub preview: bool,
    /// Hold the edges the pattern labels `lower_interface` (a skirt's or trousers' top) while
    /// sewing: `off`, `auto` (at the body's natural waist: the torso section deepest between
    /// wider ones, 35% to 80% of its height up) or a height in metres in the pattern's frame
    /// (y up)
    #[arg(long, default_value = "off", value_name = "off|auto|M")]
    pub hold_waist: String,
    /// Start with every particle moved by up to a tenth of a micron, from this seed: runs with
    /// a few seeds show how much of the outcome is chance (`garment::perturb`)
    #[arg(long, value_name = "SEED")]
    pub perturb: Option<u64>,
    /// Sew the panels where the pattern puts them even when one passes through the body (by
    /// default such a panel is first moved out along its normal: `garment::clear`)
    #[arg(long)]
    pub keep_placement: bool,
    /// Sew at this coarser spacing, m, then carry the sewn cloth onto `--spacing` for the
    /// drape (`garment::transfer`), or `off`: sew at `--spacing` (the README's `bench
    /// garment` measures both)
    #[arg(long, default_value = "off", value_name = "M|off")]
    pub sew_spacing: String,
    /// The drape's seams stiffen from the sewing's pull to their full constant by this factor
    /// every 0.02 s (2 is the one measured), or `off`: at once (the README's `garment
    /// --seam-ramp` says what each does)
    #[arg(long, default_value = "off", value_name = "F|off")]
    pub seam_ramp: String,
}

/// The edges of `pattern` labelled as a waist (`garment::waist::WAIST_LABEL`).
fn waist_edges(pattern: &Pattern) -> usize {
    let label = Some(crate::garment::waist::WAIST_LABEL);
    (pattern.panels.iter().flat_map(|p| &p.labels))
        .filter(|l| l.as_deref() == label)
        .count()
}

/// `--hold-waist`'s value.
pub(super) fn hold_waist(value: &str) -> anyhow::Result<crate::garment::drape::WaistHold> {
    use crate::garment::drape::WaistHold;
    match value {
        "off" => Ok(WaistHold::Off),
        "auto" => Ok(WaistHold::Auto),
        v => match v.parse::<f64>() {
            Ok(z) if z.is_finite() => Ok(WaistHold::Level(z)),
            _ => bail!("--hold-waist {v}: expected off, auto or a height in metres"),
        },
    }
}

/// `off` as `None`, or a number, for `flag` (`expected`: what else it takes).
fn off_or_number(flag: &str, value: &str, expected: &str) -> anyhow::Result<Option<f64>> {
    match value {
        "off" => Ok(None),
        v => match v.parse::<f64>() {
            Ok(x) => Ok(Some(x)),
            _ => bail!("{flag} {v}: expected off or {expected}"),
        },
    }
}

/// `--sew-spacing`'s value.
pub(super) fn sew_spacing(value: &str) -> anyhow::Result<Option<f64>> {
    off_or_number("--sew-spacing", value, "a spacing in metres")
}

/// `--seam-ramp`'s value (checked with the other settings: `GarmentSettings::problems`).
pub(super) fn seam_ramp(value: &str) -> anyhow::Result<Option<f64>> {
    off_or_number("--seam-ramp", value, "a factor above 1")
}

/// Refuses a stage's longest simulated time (`--sew-max`, `--settle-max`) that is not
/// positive or is over [`gd::MAX_STAGE_SECONDS`], naming the flag.
pub fn check_stage(flag: &str, seconds: f64) -> anyhow::Result<()> {
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= gd::MAX_STAGE_SECONDS) {
        bail!(
            "{flag} {}: must be a positive number of simulated seconds, at most {}",
            crate::math::short(seconds),
            gd::MAX_STAGE_SECONDS
        );
    }
    Ok(())
}

/// The report of `drapekit garment`.
#[derive(Debug, Serialize)]
pub struct GarmentReport {
    /// The pattern file.
    pub pattern: String,
    /// The body file.
    pub body: String,
    /// What was assumed about units and frames.
    pub assumed: Vec<String>,
    /// How far the body was moved to stand under the panels (`garment::frame`), m, in the
    /// pattern's frame (y up); `None` when it stood there already.
    pub body_moved_m: Option<[f64; 3]>,
    /// The fabric preset.
    pub fabric: String,
    /// Particle spacing, m.
    pub spacing: f64,
    /// The integrator (`--integrator`).
    pub integrator: crate::cloth::integrate::Integrator,
    /// Implicit Euler's bending Hessian (`--bending-hessian`).
    pub bending_hessian: crate::cloth::integrate::direct::BendingHessian,
    /// The drape's seam ramp, a factor a check (`--seam-ramp`), or `null`: off.
    pub seam_ramp: Option<f64>,
    /// Whether the body is closed (inside tests, and moving seams out of it, need it).
    pub body_closed: bool,
    /// Each closed ring of the pattern against the body's girth where it sits, checked before
    /// the simulation (`garment::fit_check`).
    pub fit_check: FitCheck,
    /// The sewn and draped garment, measured and judged.
    #[serde(flatten)]
    pub outcome: GarmentOutcome,
    /// Files written.
    pub files: Vec<String>,
    /// Wall time of the whole command, s.
    pub wall_seconds: f64,
}

/// The tips pass of a garment's run (`collide::body_points`): what it found and corrected, and
/// its wall time.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct TipsReport {
    /// Tips found through a triangle, and corrected.
    #[serde(flatten)]
    pub pushed: crate::collide::body_points::Pushed,
    /// Wall time of the pass over both stages, s (not in `self_contact.seconds`).
    pub seconds: f64,
}

/// A panel placed through the body (`garment::clear`).
#[derive(Debug, Clone, Serialize)]
pub struct PanelMoved {
    /// The panel.
    pub panel: String,
    /// Its particles inside the body as placed.
    pub particles_inside: usize,
    /// How far it was moved along its outward normal, in the garment output's units (m for
    /// `drapekit garment`); 0 when it could not be cleared.
    pub distance: f64,
    /// Whether it was cleared of the body (within `garment::clear::REACH`); if not, it was
    /// sewn where the pattern puts it.
    pub cleared: bool,
    /// `distance` in metres, for the summary.
    #[serde(skip)]
    pub distance_m: f64,
}

/// A sewn and draped garment as both `drapekit garment` and a scene's `[[garment]]` report it.
#[derive(Debug, Serialize)]
pub struct GarmentOutcome {
    /// Particles.
    pub particles: usize,
    /// Triangles.
    pub triangles: usize,
    /// Seam springs.
    pub seam_springs: usize,
    /// Cloth-against-cloth contact over both stages (`null`: off; its `seconds` are the self
    /// pass's alone).
    pub self_contact: Option<SelfStats>,
    /// The body's tips found through the cloth, and corrected, over both stages, and the
    /// pass's wall time (`collide::body_points`; `null`: off, with cloth against cloth).
    pub tips: Option<TipsReport>,
    /// The panels placed through the body and moved out along their normals before sewing
    /// (`garment::clear`; empty when none was, or with `--keep-placement`).
    pub panels_moved_out: Vec<PanelMoved>,
    /// The waist held while sewing (`--hold-waist`; `null`: not held): heights (the
    /// simulation's z, m: above the floor for the `garment` command) and the girth, m.
    pub held_waist: Option<gd::HoldReport>,
    /// Stage 1.
    pub sew: StageReport,
    /// The particle spacing sewing ran at, in the output's units (m for the `garment`
    /// command; coarser than the drape's with `--sew-spacing`).
    pub sew_spacing: f64,
    /// The particles of the cloth that was sewn (the drape's `particles` unless
    /// `--sew-spacing` sewed a coarser cloth).
    pub sew_particles: usize,
    /// The stitches sewing left open (wider than its 1 mm goal), widest first, as
    /// `open_seams`: where the drape's stiff seams had to pull them shut.
    pub sew_open_seams: Vec<measure::OpenSeam>,
    /// Stage 2.
    pub drape: StageReport,
    /// Fraction of particles that moved more than 0.3 mm over the drape's last 1/60 s (1 when
    /// the drape was shorter than a frame).
    pub moving_fraction: f64,
    /// The whole garment's measures.
    pub garment: Measures,
    /// Per panel.
    pub panels: Vec<Measures>,
    /// The stitches whose seams are not closed (gap above the verdict's limit), widest first.
    pub open_seams: Vec<measure::OpenSeam>,
    /// Where each failed measure fails (`garment::spots`): per kind the largest spots first,
    /// `at` in the garment output's frame and units.
    pub spots: Vec<Spot>,
    /// Spots left out of `spots` (more than `garment::spots::SPOTS_PER_KIND` of a kind).
    pub spots_left_out: usize,
    /// The stitches that gather a longer edge into a shorter one (`garment::gathers`).
    pub gathers: Vec<crate::garment::gathers::Gather>,
    /// How each ring (a hem, a neckline, a waist seam; the fit check's) hangs at the end: its
    /// length against its flat length, its heights and how far it rose (`garment::hang`;
    /// heights are the simulation's z, m).
    pub hang: Vec<crate::garment::hang::RingHang>,
    /// The limits of the verdict.
    pub thresholds: Thresholds,
    /// `pass`, or `fail`.
    pub verdict: String,
    /// Why it failed.
    pub failed: Vec<String>,
}

/// `g`, sewn from `pattern`, measured and judged for the report; positions in the frame of
/// the garment's output mesh (`up` up, lengths times `to_units`, as [`garment_mesh`]).
pub(super) fn outcome(
    g: gd::Garment,
    pattern: &Pattern,
    up: Up,
    to_units: f64,
) -> (GarmentOutcome, sim::World) {
    let Judged {
        moving,
        panels,
        whole,
        thresholds,
        failed,
        mut spots,
        spots_left_out,
    } = judge(&g);
    let to_mesh =
        |at: &mut [f64; 3]| *at = (change_up_point((*at).into(), Up::Z, up) * to_units).into();
    for s in &mut spots {
        to_mesh(&mut s.at);
    }
    let o = GarmentOutcome {
        particles: g.world.model.len(),
        triangles: g.world.model.triangles.len(),
        seam_springs: g.seams.len(),
        self_contact: g.world.self_contact.as_ref().map(|s| s.totals),
        tips: (g.world.self_contact.as_ref()).map(|s| TipsReport {
            pushed: s.tips_pushed,
            seconds: s.tips_seconds,
        }),
        moving_fraction: moving,
        garment: whole,
        panels,
        open_seams: open_seams(pattern, &g, thresholds.seam_gap_max_mm, to_mesh),
        gathers: crate::garment::gathers::gathers(pattern),
        hang: g.rings,
        thresholds,
        verdict: if failed.is_empty() { "pass" } else { "fail" }.into(),
        failed,
        spots,
        spots_left_out,
        panels_moved_out: (g.moved_out.iter())
            .map(|m| PanelMoved {
                panel: pattern.panels[m.index].name.clone(),
                particles_inside: m.inside,
                distance: m.distance * to_units,
                cleared: m.cleared,
                distance_m: m.distance,
            })
            .collect(),
        held_waist: g.hold,
        sew: g.sew,
        sew_spacing: g.sew_spacing * to_units,
        sew_particles: g.sew_particles,
        sew_open_seams: in_mesh(g.sew_open, to_mesh),
        drape: g.drape,
    };
    (o, g.world)
}

/// A body read for a pattern: the mesh (metres, z up), what was assumed, and how far it was
/// moved (m, y up).
pub(super) struct Body {
    pub mesh: TriMesh,
    pub note: String,
    pub moved: Option<Vec3>,
}

/// The body read, prepared, in metres (units from `spec`, or guessed from its height), moved
/// under `pattern`'s panels when it is elsewhere (`garment::frame`), and z up.
pub(super) fn read_body(path: &Path, spec: &str, pattern: &Pattern) -> anyhow::Result<Body> {
    let read = io::read_mesh(path, &ReadOptions::default())?;
    let mut mesh = read.mesh;
    prepare(&mut mesh, &PrepareOptions::default());
    let Some(b) = mesh.bbox() else {
        bail!("{}: the body has no vertices", path.display());
    };
    let height = b.size().y;
    let (units, how) = if spec == "auto" {
        let u = [Units::M, Units::Cm, Units::Mm]
            .into_iter()
            .find(|u| (0.5..=2.5).contains(&(height * u.metres())))
            .with_context(|| {
                format!(
                    "{}: the body is {height:.4} units tall along y, a person in no unit \
                     drapekit knows (m, cm, mm): give --body-units, and check that y is up",
                    path.display()
                )
            })?;
        (u, "guessed from its height")
    } else {
        let u: Units = spec
            .parse()
            .map_err(|e| anyhow::anyhow!("--body-units {spec}: {e}"))?;
        (u, "given")
    };
    let f = units.metres();
    for p in &mut mesh.positions {
        *p = crate::math::Point3::from(p.coords * f);
    }
    let shift = frame::placed_box(pattern)
        .zip(mesh.bbox())
        .and_then(|(panels, body)| frame::body_offset(&panels, &body));
    let frame_note = match shift {
        None => "in the pattern's frame".to_string(),
        Some(d) => {
            for p in &mut mesh.positions {
                *p += d;
            }
            format!(
                "moved into the pattern's frame by ({}, {}, {}) m (feet to y = 0, centred on x \
                 and z: it was not under the panels)",
                short(d.x),
                short(d.y),
                short(d.z)
            )
        }
    };
    change_up(&mut mesh, Up::Y, Up::Z);
    let note = format!(
        "the body is in {} ({how}: {:.3} m tall), y up, {frame_note}",
        format!("{units:?}").to_lowercase(),
        height * f
    );
    Ok(Body {
        mesh,
        note,
        moved: shift,
    })
}

/// Checks the flags and builds the settings.
pub(super) fn settings(args: &GarmentArgs) -> anyhow::Result<GarmentSettings> {
    let fabric = Fabric::preset(&args.fabric).with_context(|| {
        let names: Vec<&str> = Fabric::presets().iter().map(|(n, _)| *n).collect();
        format!(
            "--fabric {}: not a preset (one of {})",
            args.fabric,
            names.join(", ")
        )
    })?;
    let mut s = GarmentSettings::default();
    s.solver.integrator = args.integrator;
    s.solver.bending_hessian = args.bending_hessian;
    s.assemble.spacing = args.spacing;
    s.assemble.fabric = fabric;
    s.friction = args.friction;
    s.sew_max = args.sew_max;
    s.settle_max = args.settle_max;
    s.body_clearance = args.body_clearance;
    s.hold_waist = hold_waist(&args.hold_waist)?;
    s.perturb = args.perturb;
    s.clear_panels = !args.keep_placement;
    s.sew_spacing = sew_spacing(&args.sew_spacing)?;
    s.seam_ramp = seam_ramp(&args.seam_ramp)?;
    s.assemble.rim_bending = !args.no_rim_bending;
    s.self_collision = (!args.no_self_collision).then(|| SelfCollisionOptions {
        friction: args.cloth_friction,
        ..SelfCollisionOptions::default()
    });
    if let Some(p) = s.problems().into_iter().next() {
        let flag = format!("--{}", p.field.replace('_', "-"));
        if p.field == "integrator" {
            bail!("{flag} {}", p.message);
        }
        bail!("{flag} {}: {}", crate::math::short(p.value), p.message);
    }
    Ok(s)
}

/// The garment as one mesh with `up` up (the pattern's frame: y; a scene's: z), its lengths
/// times `to_units` (from metres), and its panels' face ranges.
pub(super) fn garment_mesh(
    world: &sim::World,
    up: Up,
    to_units: f64,
) -> (TriMesh, Vec<(String, usize, usize)>) {
    let positions = world
        .state
        .x
        .iter()
        .map(|p| change_up_point(*p, Up::Z, up) * to_units)
        .collect();
    let m = &world.model;
    let groups = m
        .pieces
        .iter()
        .map(|p| (p.name.clone(), p.first_triangle, p.triangles))
        .collect();
    (TriMesh::new(positions, m.triangles.clone()), groups)
}

/// Refuses, before any work, panel names that cannot be file names inside the output
/// folder (`--panels`): empty, `.` or `..`, or holding a path separator or a control character.
/// Refuses the panels too thin for cloth at the spacing (and at the sewing's coarser one),
/// naming the file, before the body is read.
fn check_thin(pattern: &Pattern, path: &Path, settings: &GarmentSettings) -> anyhow::Result<()> {
    let h = settings.assemble.spacing;
    let coarse = settings.sew_spacing.filter(|&s| s > h);
    for h in std::iter::once(h).chain(coarse) {
        let thin = crate::garment::assemble::thin_panels(pattern, h);
        if !thin.is_empty() {
            let lines: Vec<String> = thin.iter().map(ToString::to_string).collect();
            bail!("{}: {}", path.display(), lines.join("\n"));
        }
    }
    Ok(())
}

fn check_panel_names(pattern: &crate::garment::spec::Pattern, path: &Path) -> anyhow::Result<()> {
    let bad: Vec<String> = pattern
        .panels
        .iter()
        .map(|p| &p.name)
        .filter(|n| !crate::io::is_safe_file_name(n))
        .map(|n| format!("{n:?}"))
        .collect();
    if !bad.is_empty() {
        bail!(
            "{}: panel names {} cannot be file names for --panels: {}",
            path.display(),
            bad.join(", "),
            crate::io::FILE_NAME_RULE
        );
    }
    Ok(())
}

/// Each panel alone (its vertices renumbered), with its name.
fn panel_meshes(
    mesh: &TriMesh,
    groups: &[(String, usize, usize)],
) -> Vec<(String, TriMesh, Vec<u32>)> {
    let mut panels = Vec::new();
    for (name, first, count) in groups {
        let mut index = vec![u32::MAX; mesh.positions.len()];
        let (mut positions, mut of) = (Vec::new(), Vec::new());
        let mut faces = Vec::with_capacity(*count);
        for f in &mesh.faces[*first..first + count] {
            faces.push(f.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = positions.len() as u32;
                    positions.push(mesh.positions[v as usize]);
                    of.push(v);
                }
                index[v as usize]
            }));
        }
        panels.push((name.clone(), TriMesh::new(positions, faces), of));
    }
    panels
}

/// Stages each panel alone into `dir` (`<panel>.obj`; the folder made if need be). Returns
/// their paths.
fn stage_panels(
    dir: &Path,
    mesh: &TriMesh,
    groups: &[(String, usize, usize)],
    inputs: &[&Path],
    staged: &mut Vec<io::Staged>,
) -> anyhow::Result<Vec<String>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut files = Vec::new();
    for (name, panel, _) in panel_meshes(mesh, groups) {
        let path = dir.join(format!("{name}.obj"));
        staged.push(io::stage_mesh(&path, &panel, &io::WriteOptions::default(), inputs)?.0);
        files.push(path.display().to_string());
    }
    Ok(files)
}

/// Stages the glTF file: the bodies as placed, then each panel as cloth coloured by its strain
/// against the flat pattern `rest` (one scale for the garment), as the OBJ files have them
/// (glTF's metres, y up).
pub(super) fn stage_glb(
    path: &Path,
    mesh: &TriMesh,
    rest: &[crate::math::Point2],
    groups: &[(String, usize, usize)],
    bodies: &[(&str, &TriMesh)],
    inputs: &[&Path],
) -> anyhow::Result<io::Staged> {
    use crate::io::gltf::{Part, Scene, Surface};
    use crate::render::strain::{strain_colours, strain_top, vertex_strain};
    let rest: Vec<[f64; 2]> = rest.iter().map(|q| [q.x, q.y]).collect();
    let strain = vertex_strain(mesh, &rest).unwrap_or_else(|_| vec![0.0; mesh.positions.len()]);
    let top = strain_top(strain.iter().copied());
    let mut parts: Vec<Part> = (bodies.iter())
        .map(|(name, m)| Part::new(*name, (*m).clone(), Surface::Solid))
        .collect();
    for (name, m, of) in panel_meshes(mesh, groups) {
        let values: Vec<f64> = of.iter().map(|&v| strain[v as usize]).collect();
        let mut part = Part::new(name, m, Surface::Cloth);
        part.colors = Some(strain_colours(&values, top));
        parts.push(part);
    }
    let scene = Scene {
        parts,
        frames: Vec::new(),
    };
    Ok(crate::io::gltf::stage_scene(path, &scene, inputs)?)
}

/// Stages `OUT_DIR/<garment>.png`: the garment on the body, y up, from the front.
fn stage_preview(
    path: &Path,
    garment: &TriMesh,
    body: &TriMesh,
    inputs: &[&Path],
) -> anyhow::Result<io::Staged> {
    use super::render::{CLOTH, OBJECT};
    use crate::render::{default_lift, Item};
    let lift = default_lift(garment.positions.iter().chain(&body.positions));
    let items = [
        Item::cloth(garment, CLOTH, None, lift),
        Item::object(body, OBJECT),
    ];
    let view = crate::render::View::Front;
    super::render::stage_preview(path, &items, view, Up::Y, inputs)
}

/// A sewn and draped garment measured and judged.
pub(super) struct Judged {
    /// The fraction still moving (the drape's last frame).
    pub moving: f64,
    /// Per panel.
    pub panels: Vec<Measures>,
    /// The whole garment.
    pub whole: Measures,
    /// The verdict's limits.
    pub thresholds: Thresholds,
    /// What failed (empty: pass).
    pub failed: Vec<String>,
    /// Where (the simulation's frame).
    pub spots: Vec<Spot>,
    /// Spots beyond `SPOTS_PER_KIND` of a kind.
    pub spots_left_out: usize,
}

/// The stitches open wider than `limit_mm`, placed in the mesh's frame by `to_mesh`.
fn open_seams(
    pattern: &Pattern,
    g: &gd::Garment,
    limit_mm: f64,
    to_mesh: impl Fn(&mut [f64; 3]),
) -> Vec<measure::OpenSeam> {
    let open = measure::open_seams(pattern, &g.seams, &g.world.state.x, limit_mm);
    in_mesh(open, to_mesh)
}

/// `open`, placed in the mesh's frame by `to_mesh`.
fn in_mesh(
    mut open: Vec<measure::OpenSeam>,
    to_mesh: impl Fn(&mut [f64; 3]),
) -> Vec<measure::OpenSeam> {
    for o in &mut open {
        to_mesh(&mut o.at);
    }
    open
}

/// Measures `g` and judges it by the default thresholds (inside: in any closed body).
pub(super) fn judge(g: &gd::Garment) -> Judged {
    // The drape's last frame (1/60 s); a drape too short for one frame counts as moving.
    let moving = g.drape.moving_fraction.unwrap_or(1.0);
    let closed: Vec<_> = g.world.colliders.iter().filter(|c| c.closed).collect();
    let inside: Vec<bool> = (g.world.state.x.iter())
        .map(|p| closed.iter().any(|c| sim::inside(c, p)))
        .collect();
    let crossings = measure::crossings(&g.world, &g.seams);
    let mut panels = measure::measures_of(&g.world, &g.seams, &inside, &crossings);
    let whole = panels.pop().expect("the whole garment");
    let thresholds = Thresholds::default();
    let failed = measure::verdict(&whole, moving, &thresholds);
    let (spots, spots_left_out) = spots(&g.world, &inside, &crossings, &thresholds);
    Judged {
        moving,
        panels,
        whole,
        thresholds,
        failed,
        spots,
        spots_left_out,
    }
}

/// Runs `drapekit garment`.
pub fn run(args: GarmentArgs) -> anyhow::Result<()> {
    let start = std::time::Instant::now();
    let settings = settings(&args)?;
    let inputs = [args.pattern.as_path(), args.body.as_path()];
    super::check_report(args.report.as_deref(), &args.output, &inputs)?;
    let pattern = crate::garment::read(&args.pattern)?;
    check_thin(&pattern, &args.pattern, &settings)?;
    if args.panels {
        check_panel_names(&pattern, &args.pattern)?;
    }
    let Body {
        mesh: body,
        note: body_note,
        moved,
    } = read_body(&args.body, &args.body_units, &pattern)?;
    super::refuse_file_output(&args.output)?;
    let fit = fit_check(&pattern, &body, &fit_options(&settings))?;
    warn_too_short(&fit);
    super::remove_stale_temps(&[&args.output, &args.output.join("panels")]);
    let g = sew_interruptibly(&pattern, vec![gd::body_collider(body)], &settings)??;
    let (outcome, world) = outcome(g, &pattern, Up::Y, 1.0);
    let files = write_outputs(&args, &world, &inputs)?;
    let report = GarmentReport {
        pattern: args.pattern.display().to_string(),
        body: args.body.display().to_string(),
        assumed: assumed(&args, &pattern, body_note),
        body_moved_m: moved.map(|d| [d.x, d.y, d.z]),
        fabric: args.fabric.clone(),
        spacing: args.spacing,
        integrator: args.integrator,
        bending_hessian: args.bending_hessian,
        seam_ramp: settings.seam_ramp,
        body_closed: world.colliders[0].closed,
        fit_check: fit,
        outcome,
        files,
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    super::finish(
        &report,
        args.report.as_deref(),
        &inputs,
        &args.output,
        args.json,
        print_summary,
    )
}

/// Sews and drapes `pattern` on `bodies` with `settings`, a line of progress on a terminal.
/// An interrupt is the outer error (a garment keeps no checkpoint: nothing was written); the
/// garment's own errors are left to the caller to name.
pub(super) fn sew_interruptibly(
    pattern: &Pattern,
    bodies: Vec<crate::collide::Collider>,
    settings: &GarmentSettings,
) -> anyhow::Result<Result<gd::Garment, gd::GarmentError>> {
    let progress = |t: f64| {
        if super::interactive() {
            eprint!("\rsewing: {t:.2} s simulated");
        }
    };
    let signals = super::interrupt::install()?;
    let cancel = Some(signals.cancel());
    match gd::sew_and_drape(pattern, bodies, settings, &progress, cancel) {
        Err(gd::GarmentError::Sim(sim::SimError::Interrupted(_))) => {
            let what = "during the garment run: a garment keeps no checkpoint; nothing was written";
            Err(signals.interrupted(what).into())
        }
        sewn => {
            if sewn.is_ok() && super::interactive() {
                eprintln!();
            }
            Ok(sewn)
        }
    }
}

/// A file's stem, if it has one.
fn file_stem(p: &Path) -> Option<String> {
    p.file_stem().map(|s| s.to_string_lossy().into_owned())
}

/// Writes the garment (`<garment>.obj`, a group per panel), each panel alone (`--panels`),
/// the body as placed, the glTF file (`--glb`) and the preview (`--preview`) into the output
/// directory, in the pattern's frame (m, y up); returns the files written.
fn write_outputs(
    args: &GarmentArgs,
    world: &sim::World,
    inputs: &[&Path],
) -> anyhow::Result<Vec<String>> {
    let out = &args.output;
    let existed = (out.exists(), out.join("panels").exists());
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut staged = Vec::new();
    let files = stage_outputs(args, world, inputs, &mut staged).and_then(|files| {
        io::commit(std::mem::take(&mut staged))?;
        Ok(files)
    });
    if files.is_err() {
        // Nothing of this run is left: its temporary files go, and the folders it made.
        drop(staged);
        if !existed.1 {
            let _ = std::fs::remove_dir(out.join("panels"));
        }
        if !existed.0 {
            let _ = std::fs::remove_dir(out);
        }
    }
    files
}

/// Stages every output into `staged`: the garment (`<garment>.obj`), each panel alone on
/// request, the body as placed, and the glTF file and the preview on request; returns their
/// paths. Nothing is in place until they are committed together.
fn stage_outputs(
    args: &GarmentArgs,
    world: &sim::World,
    inputs: &[&Path],
    staged: &mut Vec<io::Staged>,
) -> anyhow::Result<Vec<String>> {
    let name = file_stem(&args.pattern).unwrap_or_else(|| "garment".into());
    let name = name
        .strip_suffix("_specification")
        .unwrap_or(&name)
        .to_string();
    let (mesh, groups) = garment_mesh(world, Up::Y, 1.0);
    let garment_path = args.output.join(format!("{name}.obj"));
    let rest = &world.model.rest;
    let flat: Vec<[f64; 2]> = rest.iter().map(|q| [q.x, q.y]).collect();
    staged.push(io::stage_obj_with_rest(
        &garment_path,
        &mesh,
        &flat,
        &groups,
        inputs,
    )?);
    let mut files = vec![garment_path.display().to_string()];
    if args.panels {
        let dir = args.output.join("panels");
        files.extend(stage_panels(&dir, &mesh, &groups, inputs, staged)?);
    }
    let (body_name, body_mesh, body_path) = stage_body(args, world, &name, inputs, staged)?;
    files.push(body_path);
    if args.glb {
        let path = args.output.join(format!("{name}.glb"));
        let bodies = [(body_name.as_str(), &body_mesh)];
        staged.push(stage_glb(&path, &mesh, rest, &groups, &bodies, inputs)?);
        files.push(path.display().to_string());
    }
    if args.preview {
        let p = args.output.join(format!("{name}.png"));
        staged.push(stage_preview(&p, &mesh, &body_mesh, inputs)?);
        files.push(p.display().to_string());
    }
    Ok(files)
}

/// Stages the body as placed (y up) as `<body>.obj`, named after its file unless the garment
/// (`garment`) has that name; returns its name, its mesh and its path.
fn stage_body(
    args: &GarmentArgs,
    world: &sim::World,
    garment: &str,
    inputs: &[&Path],
    staged: &mut Vec<io::Staged>,
) -> anyhow::Result<(String, TriMesh, String)> {
    let mut body_mesh = world.colliders[0].mesh.clone();
    change_up(&mut body_mesh, Up::Z, Up::Y);
    let body_name = file_stem(&args.body).unwrap_or_else(|| "body".into());
    let taken = [garment.to_string()];
    let body_name = io::unique_file_names(&[body_name], &taken, "body").remove(0);
    let body_path = args.output.join(format!("{body_name}.obj"));
    let options = io::WriteOptions::default();
    staged.push(io::stage_mesh(&body_path, &body_mesh, &options, inputs)?.0);
    Ok((body_name, body_mesh, body_path.display().to_string()))
}

/// What the report says was assumed: the body's units and frame (`body_note`), the pattern's
/// units, the perturbation, and waist edges left free.
fn assumed(args: &GarmentArgs, pattern: &Pattern, body_note: String) -> Vec<String> {
    let mut assumed = vec![body_note];
    assumed.push(if pattern.units_assumed {
        format!(
            "the pattern gives no units_in_meter: GarmentCode's default, {}, is assumed (units of 1/{} m, centimetres)",
            pattern.units_in_meter, pattern.units_in_meter
        )
    } else {
        format!(
            "the pattern is in units of 1/{} m (its units_in_meter)",
            pattern.units_in_meter
        )
    });
    if let Some(seed) = args.perturb {
        assumed.push(format!(
            "the panels start moved by up to {} m per coordinate (--perturb {seed})",
            crate::garment::perturb::PERTURB_M
        ));
    }
    let waist_edges = waist_edges(pattern);
    if waist_edges > 0 && args.hold_waist == "off" {
        assumed.push(format!(
            "the pattern's {waist_edges} waist edges (labelled {}) are not held while sewing \
             (--hold-waist auto holds them at the body's natural waist)",
            crate::garment::waist::WAIST_LABEL
        ));
    }
    assumed
}

/// One line on a ring too short for the body where it sits.
/// The fit check's options for a garment run's settings: the cloth keeps the fabric's
/// thickness and the body clearance off the body.
pub(super) fn fit_options(settings: &GarmentSettings) -> FitCheckOptions {
    let clearance = settings.assemble.fabric.thickness
        + settings
            .body_clearance
            .unwrap_or(gd::AUTO_CLEARANCE * settings.assemble.spacing);
    FitCheckOptions::with_clearance(clearance)
}

/// A warning on stderr, at once, for each ring too short for the body.
pub(super) fn warn_too_short(fit: &FitCheck) {
    for r in fit.rings.iter().filter(|r| r.fits == Some(false)) {
        eprintln!("warning: {}", too_short(r));
    }
}

/// The summary's lines of the fit check.
pub(super) fn print_fit_check(f: &FitCheck) {
    println!(
        "  fit check (before the drape): {} rings, {} judged, {} too short for the body",
        f.rings.len(),
        f.rings.iter().filter(|r| r.judged).count(),
        f.too_short
    );
    for ring in f.rings.iter().filter(|r| r.fits == Some(false)) {
        println!("    {}", too_short(ring));
    }
}

fn too_short(r: &Ring) -> String {
    let cm = |m: f64| format!("{:.1} cm", m * 100.0);
    let at = |z: Option<f64>| z.map_or("nowhere".to_string(), |z| format!("at {z:.3} m"));
    let g = r.body_girth_m.unwrap_or([0.0; 2]);
    format!(
        "fit check: the {} ring {} is {} long ({} with {:.0}% strain) at {:.3}-{:.3} m, where the \
         body is {}-{} round ({} needed with the clearance); the body is narrow enough {} above, \
         {} below",
        match r.kind {
            crate::garment::fit_check::RingKind::Seam => "seam",
            crate::garment::fit_check::RingKind::Opening => "opening",
        },
        r.edges.join(" "),
        cm(r.length_m),
        cm(r.available_m),
        (r.available_m / r.length_m - 1.0) * 100.0,
        r.height_m[0],
        r.height_m[1],
        cm(g[0]),
        cm(g[1]),
        cm(r.needed_m.unwrap_or(0.0)),
        at(r.narrow_enough_above_m),
        at(r.narrow_enough_below_m)
    )
}

fn print_summary(r: &GarmentReport) {
    println!(
        "{}: {} particles, {} seam springs, {} on {}, {}{}",
        r.pattern,
        r.outcome.particles,
        r.outcome.seam_springs,
        r.fabric,
        r.body,
        r.integrator,
        if r.integrator == crate::cloth::integrate::Integrator::ImplicitEuler {
            format!(" ({} bending Hessian)", r.bending_hessian)
        } else {
            String::new()
        }
    );
    for a in &r.assumed {
        println!("  assumed: {a}");
    }
    print_fit_check(&r.fit_check);
    print_outcome(&r.outcome, r.wall_seconds);
}

/// The summary's line on how a ring hangs: its first edges, its heights, how far it rose, its
/// length against its flat length.
fn hang_line(h: &crate::garment::hang::RingHang) -> String {
    let kind = match h.kind {
        crate::garment::fit_check::RingKind::Seam => "seam",
        crate::garment::fit_check::RingKind::Opening => "opening",
    };
    let mut edges = h
        .edges
        .iter()
        .take(3)
        .cloned()
        .collect::<Vec<_>>()
        .join(" ");
    if h.edges.len() > 3 {
        edges += &format!(" and {} more", h.edges.len() - 3);
    }
    format!(
        "ring ({kind} {edges}): {:.3} to {:.3} m up, rose {:.1} cm; {:.1} cm long ({:.1} cm flat)",
        h.height_m[0],
        h.height_m[1],
        h.rise_m * 100.0,
        h.length_m * 100.0,
        h.rest_length_m * 100.0
    )
}

/// The summary's lines on the sewing, the drape, the measures and the verdict.
pub(super) fn print_outcome(r: &GarmentOutcome, wall_seconds: f64) {
    print_moved_out(&r.panels_moved_out);
    print_sewing(r);
    print_drape(r);
    print_verdict(r, wall_seconds);
}

/// The summary's lines on the panels placed through the body.
fn print_moved_out(moved: &[PanelMoved]) {
    for m in moved {
        let what = if m.cleared {
            format!("moved {:.1} cm out along its normal", m.distance_m * 100.0)
        } else {
            format!(
                "not clear within {} m along its normal: sewn where placed",
                crate::garment::clear::REACH
            )
        };
        println!(
            "  placed through the body: panel {} ({} particles inside), {what}",
            m.panel, m.particles_inside
        );
    }
}

/// The summary's lines on the sewing: its spacing, time, seam gap, the waist held, the
/// stitches left open.
fn print_sewing(r: &GarmentOutcome) {
    let coarse = (r.sew_particles != r.particles).then(|| {
        format!(
            " at {} cm ({} particles, then carried onto the drape's cloth)",
            crate::math::short(r.sew_spacing * 100.0),
            r.sew_particles
        )
    });
    println!(
        "  sewing{}: {:.2} s simulated ({}), largest seam gap {:.2} mm, seams at {} m/h^2",
        coarse.unwrap_or_default(),
        r.sew.time,
        if r.sew.done { "closed" } else { "NOT closed" },
        r.sew.seam_gap_max * 1e3,
        r.sew.sew_weight
    );
    if let Some(t) = r.sew.exact_from {
        println!("    sewing slowed at {t:.2} s: went on with the exact bending Hessian");
    }
    if let Some(h) = &r.held_waist {
        let body = h.girth.map_or(String::new(), |c| {
            format!(", the body's natural waist, {:.1} cm round", c * 100.0)
        });
        println!(
            "    waist held: {} particles pulled from {:.3} to {:.3} m up (level {:.3} m{body})",
            h.particles, h.from, h.to, h.level
        );
    }
    for o in r.sew_open_seams.iter().take(3) {
        println!(
            "    left open: stitch {} ({} to {}), {:.1} mm, {:.2} m up",
            o.stitch, o.edges[0], o.edges[1], o.gap_max_mm, o.height_m
        );
    }
}

/// The summary's lines on the drape: its time, the seams, the crossings, how the rings hang.
fn print_drape(r: &GarmentOutcome) {
    println!(
        "  drape: {:.2} s simulated ({}), {:.1}% still moving",
        r.drape.time,
        if r.drape.done {
            "at rest"
        } else {
            "NOT at rest"
        },
        r.moving_fraction * 100.0
    );
    let w = &r.garment;
    println!(
        "  seams: largest gap {:.2} mm, mean {:.2} mm; inside the body: {}; strain {:.2}%",
        w.seam_gap_max_mm,
        w.seam_gap_mean_mm,
        w.particles_inside,
        w.max_strain * 100.0
    );
    println!(
        "  crossing edges: {} through the body, {} through the cloth{}",
        w.body_crossing_edges,
        w.self_crossing_edges,
        if r.self_contact.is_none() {
            " (self-collision off)"
        } else {
            ""
        }
    );
    for h in &r.hang {
        println!("  {}", hang_line(h));
    }
}

/// The summary's lines on the verdict: what failed and where, the open seams, the gathers.
fn print_verdict(r: &GarmentOutcome, wall_seconds: f64) {
    println!("  verdict: {} in {:.1} s", r.verdict, wall_seconds);
    for f in &r.failed {
        println!("    failed: {f}");
    }
    for s in largest_spots(&r.spots) {
        println!("    where: {}", spot_line(s));
    }
    for o in r.open_seams.iter().take(5) {
        println!(
            "    open seam: stitch {} ({} to {}), gap {:.1} mm, {:.2} m up",
            o.stitch, o.edges[0], o.edges[1], o.gap_max_mm, o.height_m
        );
    }
    if let Some(g) = r.gathers.iter().max_by(|a, b| a.ratio.total_cmp(&b.ratio)) {
        println!(
            "  gathers: {} stitches join edges of different lengths, up to {:.0}% (stitch {}: \
             {} of {:.1} mm and {} of {:.1} mm)",
            r.gathers.len(),
            (g.ratio - 1.0) * 100.0,
            g.stitch,
            g.edges[0],
            g.lengths_mm[0],
            g.edges[1],
            g.lengths_mm[1]
        );
    }
}

/// The largest spot of each kind, in the report's order.
fn largest_spots(spots: &[Spot]) -> Vec<&Spot> {
    let mut out: Vec<&Spot> = Vec::new();
    for s in spots {
        if out.iter().all(|o| o.kind != s.kind) {
            out.push(s);
        }
    }
    out
}

/// One summary line for a spot: `9 springs strained up to 9.4% on right_ftorso, 1.31 m up`.
fn spot_line(s: &Spot) -> String {
    let what = match s.kind {
        SpotKind::BodyCrossing => format!("{} edges through the body", s.count),
        SpotKind::SelfCrossing => format!("{} edges through the cloth", s.count),
        SpotKind::Inside => format!("{} particles inside the body", s.count),
        SpotKind::Strain => format!(
            "{} springs strained up to {:.1}%",
            s.count,
            s.worst.unwrap_or(0.0) * 100.0
        ),
    };
    format!("{what} on {}, {:.2} m up", s.panel, s.height_m)
}
