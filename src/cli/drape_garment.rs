//! `drapekit drape SCENE.toml -o OUT_DIR` for a scene with a `[[garment]]`: the pattern sewn
//! on the scene's objects and draped as `drapekit garment` sews and drapes it on a body
//! (`garment::drape::sew_and_drape`); the garment (one OBJ, a group per panel) and the objects
//! as placed are written in the scene's units and frame, with the garment's report.

use super::drape::{object_reports, stage_objects, DrapeArgs, ObjectReport};
use super::garment::{
    fit_options, garment_mesh, outcome, print_fit_check, print_outcome, sew_interruptibly,
    stage_glb, warn_too_short, GarmentOutcome,
};
use crate::collide::Collider;
use crate::garment::drape as gd;
use crate::garment::fit_check::{fit_check, FitCheck};
use crate::garment::frame;
use crate::io::{self, WriteOptions};
use crate::math::{short, Aabb, Point3};
use crate::mesh::transform::{change_up_point, Units, Up};
use crate::mesh::TriMesh;
use crate::scene::{GarmentSpec, Scene};
use crate::sim;
use anyhow::bail;
use serde::Serialize;
use std::path::Path;

/// The report of a garment scene. Lengths are in the scene's units, except the garment's
/// measures (seam gaps in mm, the stages' gaps in m), as `drapekit garment` reports them.
#[derive(Debug, Serialize)]
pub struct GarmentSceneReport {
    /// The scene file.
    pub scene: String,
    /// The output directory.
    pub output_dir: String,
    /// Units of the lengths here.
    pub units: Units,
    /// The pattern file.
    pub pattern: String,
    /// The fabric (a preset or a table of the scene).
    pub fabric: String,
    /// Particle spacing.
    pub spacing: f64,
    /// The drape's seam ramp, a factor a check (`seam_ramp`), or `null`: off.
    pub seam_ramp: Option<f64>,
    /// Per object: what `drape` reports of it.
    pub objects: Vec<ObjectReport>,
    /// Each closed ring of the pattern against the scene's closed objects where it sits,
    /// checked before the simulation (`garment::fit_check`; lengths in m, heights in m in the
    /// scene's frame; `null`: no closed object).
    pub fit_check: Option<FitCheck>,
    /// What looked wrong before the run, also printed: the pattern's panels not round the
    /// scene's objects (`garment::frame`: a wrong `translation` or `rotation`).
    pub warnings: Vec<String>,
    /// The sewn and draped garment, measured and judged.
    #[serde(flatten)]
    pub outcome: GarmentOutcome,
    /// Files written.
    pub files: Vec<String>,
    /// Wall time of the whole command, s.
    pub command_seconds: f64,
}

/// Runs the scene `sc`, which has a garment.
pub(super) fn run(args: &DrapeArgs, sc: Scene, start: std::time::Instant) -> anyhow::Result<()> {
    let spec = check_args(args, &sc)?;
    let out = &args.output;
    let bodies = sim::load_objects(&sc)?;
    let settings = &spec.settings;
    let (fit, warnings) = check_pattern(&sc, spec, &bodies)?;
    super::remove_stale_temps(&[out]);
    let g = sew(&sc, spec, bodies)?;
    let to_units = Units::factor(Units::M, sc.units);
    let (outcome, world) = outcome(g, &spec.pattern, Up::Z, to_units);
    let inputs: Vec<&Path> = [sc.path.as_path(), spec.path.as_path()]
        .into_iter()
        .chain(sc.objects.iter().map(|o| o.mesh.as_path()))
        .collect();
    let o = Out {
        args,
        sc: &sc,
        spec,
        world: &world,
        inputs: &inputs,
        to_units,
    };
    let (files, object_files) = write_outputs(&o)?;
    let report = GarmentSceneReport {
        scene: sc.path.display().to_string(),
        output_dir: out.display().to_string(),
        units: sc.units,
        pattern: spec.path.display().to_string(),
        fabric: spec.fabric_name.clone(),
        spacing: settings.assemble.spacing * to_units,
        seam_ramp: settings.seam_ramp,
        objects: object_reports(&world, to_units, object_files),
        fit_check: fit,
        warnings,
        outcome,
        files,
        command_seconds: start.elapsed().as_secs_f64(),
    };
    super::finish(
        &report,
        args.report.as_deref(),
        &inputs,
        out,
        args.json,
        print_summary,
    )
}

/// The scene's garment, once the flags are checked against it: a garment keeps no checkpoint
/// (no `--resume`), and the output must be a directory.
fn check_args<'a>(args: &DrapeArgs, sc: &'a Scene) -> anyhow::Result<&'a GarmentSpec> {
    let Some(spec) = &sc.garment else {
        bail!("{}: the scene has no [[garment]]", sc.path.display());
    };
    if args.resume {
        bail!(
            "--resume: {} sews a [[garment]], and a garment's run keeps no checkpoint (an interrupted one writes nothing); run it without --resume",
            sc.path.display()
        );
    }
    super::refuse_file_output(&args.output)?;
    Ok(spec)
}

/// The pattern against the scene's objects before any simulation: the fit check (each ring
/// too short a warning at once) and the placement's warning, printed and returned.
fn check_pattern(
    sc: &Scene,
    spec: &GarmentSpec,
    bodies: &[Collider],
) -> anyhow::Result<(Option<FitCheck>, Vec<String>)> {
    let settings = &spec.settings;
    let fit = scene_fit_check(&spec.pattern, bodies, settings)?;
    if let Some(f) = &fit {
        warn_too_short(f);
    }
    let units = (spec.pattern.units_assumed).then(|| {
        format!(
            "garment.pattern: the pattern gives no units_in_meter: GarmentCode's default, {}, is assumed (units of 1/{} m, centimetres)",
            spec.pattern.units_in_meter, spec.pattern.units_in_meter
        )
    });
    let warnings: Vec<String> = units
        .into_iter()
        .chain(placement_warning(&spec.pattern, bodies, settings))
        .collect();
    for w in &warnings {
        eprintln!("warning: {}: {w}", sc.path.display());
    }
    Ok((fit, warnings))
}

/// Sews and drapes the scene's garment on its objects; its errors are named after the scene
/// (the pattern against the objects under the pattern's key).
fn sew(sc: &Scene, spec: &GarmentSpec, bodies: Vec<Collider>) -> anyhow::Result<gd::Garment> {
    match sew_interruptibly(&spec.pattern, bodies, &spec.settings)? {
        // The pattern against the objects (panels facing into the body, panels that make no
        // cloth): before any simulation, under the pattern's key.
        Err(e @ (gd::GarmentError::FacingIn(_) | gd::GarmentError::Assemble(_))) => {
            bail!("{}: key 'garment.pattern': {e}", sc.path.display())
        }
        Err(e) => bail!("{}: {e}", sc.path.display()),
        Ok(g) => Ok(g),
    }
}

/// What writing a garment scene's outputs reads: the arguments, the scene and its garment, the
/// draped world, the inputs (never written over), the factor from metres to the scene's units.
struct Out<'a> {
    args: &'a DrapeArgs,
    sc: &'a Scene,
    spec: &'a GarmentSpec,
    world: &'a sim::World,
    inputs: &'a [&'a Path],
    to_units: f64,
}

/// Stages the garment (OBJ, and PLY on request), the objects as placed, the glTF file and
/// the preview, and puts them all in place; returns the files and each object's files. After
/// a failure nothing is left (the output directory removed if the run created it, when empty).
fn write_outputs(o: &Out) -> anyhow::Result<(Vec<String>, Vec<Vec<String>>)> {
    let out = o.args.output.as_path();
    let names = super::drape::object_names(o.sc, out);
    let existed = out.exists();
    let mut staged = Vec::new();
    let written = (|| -> anyhow::Result<(Vec<String>, Vec<Vec<String>>)> {
        std::fs::create_dir_all(out)
            .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", out.display()))?;
        let mut files = stage_garment(o, &mut staged)?;
        let objects = stage_objects(o.sc, o.world, &names, out, o.inputs, &mut staged)?;
        if o.args.glb {
            files.push(stage_scene_glb(o, &names, &mut staged)?);
        }
        if o.args.preview {
            let (world, to_units) = (o.world, o.to_units);
            let preview = super::drape::stage_preview(world, out, to_units, o.inputs, &mut staged);
            files.push(preview?);
        }
        io::commit(std::mem::take(&mut staged))?;
        Ok((files, objects))
    })();
    if written.is_err() {
        drop(staged);
        if !existed {
            let _ = std::fs::remove_dir(out);
        }
    }
    written
}

/// Stages the garment as `<garment>.obj` (a group per panel, the flat pattern as `vt`), and
/// `.ply` when the scene asks, in the scene's units and frame; returns their paths.
fn stage_garment(o: &Out, staged: &mut Vec<io::Staged>) -> anyhow::Result<Vec<String>> {
    let (spec, out, to_units) = (o.spec, &o.args.output, o.to_units);
    let (mesh, groups) = garment_mesh(o.world, Up::Z, to_units);
    let rest: Vec<[f64; 2]> = (o.world.model.rest.iter())
        .map(|q| [q.x * to_units, q.y * to_units])
        .collect();
    let mut files = Vec::new();
    let path = out.join(format!("{}.obj", spec.name));
    staged.push(io::stage_obj_with_rest(
        &path, &mesh, &rest, &groups, o.inputs,
    )?);
    files.push(path.display().to_string());
    if o.sc.ply {
        let path = out.join(format!("{}.ply", spec.name));
        staged.push(io::stage_mesh(&path, &mesh, &WriteOptions::default(), o.inputs)?.0);
        files.push(path.display().to_string());
    }
    Ok(files)
}

/// Stages `<scene>.glb`: the garment and the objects as placed (named `names`), in glTF's
/// own frame (metres, y up); returns its path.
fn stage_scene_glb(
    o: &Out,
    names: &[String],
    staged: &mut Vec<io::Staged>,
) -> anyhow::Result<String> {
    let (mesh, groups) = garment_mesh(o.world, Up::Y, 1.0);
    let placed: Vec<_> = (o.world.colliders.iter())
        .map(|c| {
            let mut m = c.mesh.clone();
            crate::mesh::transform::change_up(&mut m, Up::Z, Up::Y);
            m
        })
        .collect();
    let bodies: Vec<(&str, &TriMesh)> = names.iter().map(String::as_str).zip(&placed).collect();
    let path = o
        .args
        .output
        .join(format!("{}.glb", super::drape::scene_stem(o.sc)));
    let rest = &o.world.model.rest;
    staged.push(stage_glb(&path, &mesh, rest, &groups, &bodies, o.inputs)?);
    Ok(path.display().to_string())
}

fn print_summary(r: &GarmentSceneReport) {
    let objects: Vec<&str> = r.objects.iter().map(|o| o.name.as_str()).collect();
    println!(
        "{} -> {}: {} ({} particles, {} seam springs, {}) on {}",
        r.scene,
        r.output_dir,
        r.pattern,
        r.outcome.particles,
        r.outcome.seam_springs,
        r.fabric,
        objects.join(", ")
    );
    if let Some(f) = &r.fit_check {
        print_fit_check(f);
    }
    print_outcome(&r.outcome, r.command_seconds);
}

/// A warning when the scene's objects are not round the pattern's panels in the pattern's
/// frame (`garment::frame::under`: the garment would be sewn in the air beside them). A scene
/// places its objects itself: nothing is moved.
fn placement_warning(
    pattern: &crate::garment::Pattern,
    bodies: &[Collider],
    settings: &gd::GarmentSettings,
) -> Option<String> {
    let placement = &settings.assemble.placement;
    let points: Vec<Point3> = (bodies.iter())
        .flat_map(|c| c.mesh.positions.iter())
        .map(|p| change_up_point(placement.unapply(*p), Up::Z, Up::Y))
        .collect();
    let objects = Aabb::of_points(&points)?;
    let panels = frame::placed_box(pattern)?;
    if frame::under(&panels, &objects) {
        return None;
    }
    let span = |b: &Aabb| {
        let r = |k: usize| format!("{} to {}", short(b.min[k]), short(b.max[k]));
        format!("x {}, y {}, z {}", r(0), r(1), r(2))
    };
    Some(format!(
        "the garment's panels are not round the scene's objects: in the pattern's frame (m, y \
         up) the panels span {} and the objects {}; check [[garment]]'s translation and rotation",
        span(&panels),
        span(&objects)
    ))
}

/// The fit check of a scene's garment on the scene's closed objects (`None`: there are none):
/// the objects are brought into the pattern's frame (the garment's placement undone, a turn
/// about z and a shift) and judged as `drapekit garment` judges a body; the heights are given
/// back in the scene's frame.
fn scene_fit_check(
    pattern: &crate::garment::Pattern,
    bodies: &[Collider],
    settings: &gd::GarmentSettings,
) -> anyhow::Result<Option<FitCheck>> {
    let placement = &settings.assemble.placement;
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for c in bodies.iter().filter(|c| c.closed) {
        let first = positions.len() as u32;
        positions.extend(c.mesh.positions.iter().map(|p| placement.unapply(*p)));
        let shifted = c.mesh.faces.iter().map(|t| t.map(|v| v + first));
        triangles.extend(shifted);
    }
    if triangles.is_empty() {
        return Ok(None);
    }
    let mut fit = fit_check(
        pattern,
        &TriMesh::new(positions, triangles),
        &fit_options(settings),
    )?;
    let dz = placement.translation.z;
    for r in &mut fit.rings {
        r.height_m = r.height_m.map(|z| z + dz);
        for z in [&mut r.narrow_enough_above_m, &mut r.narrow_enough_below_m]
            .into_iter()
            .flatten()
        {
            *z += dz;
        }
    }
    Ok(Some(fit))
}
