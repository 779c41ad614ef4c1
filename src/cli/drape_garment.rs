//! `drapekit drape SCENE.toml -o OUT_DIR` for a scene with a `[[garment]]`: the pattern sewn
//! on the scene's objects and draped as `drapekit garment` sews and drapes it on a body
//! (`garment::drape::sew_and_drape`); the garment (one OBJ, a group per panel) and the objects
//! as placed are written in the scene's units and frame, with the garment's report.

use super::drape::{object_reports, stage_objects, DrapeArgs, ObjectReport};
use super::garment::{
    fit_options, garment_mesh, outcome, print_fit_check, print_outcome, stage_glb, warn_too_short,
    GarmentOutcome,
};
use crate::collide::Collider;
use crate::garment::drape as gd;
use crate::garment::fit_check::{fit_check, FitCheck};
use crate::garment::frame;
use crate::io::{self, WriteOptions};
use crate::math::{short, Aabb, Point3};
use crate::mesh::transform::{change_up_point, Units, Up};
use crate::mesh::TriMesh;
use crate::scene::Scene;
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
    let Some(spec) = &sc.garment else {
        bail!("{}: the scene has no [[garment]]", sc.path.display());
    };
    if args.resume {
        bail!(
            "--resume: {} sews a [[garment]], and a garment's run keeps no checkpoint (an interrupted one writes nothing); run it without --resume",
            sc.path.display()
        );
    }
    let out = &args.output;
    if out.is_file() {
        bail!(
            "{} is a file: the output must be a directory",
            out.display()
        );
    }
    let bodies = sim::load_objects(&sc)?;
    let settings = &spec.settings;
    let fit = scene_fit_check(&spec.pattern, &bodies, settings)?;
    if let Some(f) = &fit {
        warn_too_short(f);
    }
    let warnings: Vec<String> = placement_warning(&spec.pattern, &bodies, settings)
        .into_iter()
        .collect();
    for w in &warnings {
        eprintln!("warning: {}: {w}", sc.path.display());
    }
    super::remove_stale_temps(&[out]);
    let progress = |t: f64| {
        if super::interactive() {
            eprint!("\rsewing: {t:.2} s simulated");
        }
    };
    let signals = super::interrupt::install()?;
    let cancel = Some(signals.cancel());
    let g = match gd::sew_and_drape(&spec.pattern, bodies, settings, &progress, cancel) {
        Err(gd::GarmentError::Sim(sim::SimError::Interrupted(_))) => {
            let what = "during the garment run: a garment keeps no checkpoint; nothing was written";
            return Err(signals.interrupted(what).into());
        }
        // The pattern against the objects (panels facing into the body, panels that make no
        // cloth): before any simulation, under the pattern's key.
        Err(e @ (gd::GarmentError::FacingIn(_) | gd::GarmentError::Assemble(_))) => {
            bail!("{}: key 'garment.pattern': {e}", sc.path.display())
        }
        Err(e) => bail!("{}: {e}", sc.path.display()),
        Ok(g) => g,
    };
    if super::interactive() {
        eprintln!();
    }
    let to_units = Units::factor(Units::M, sc.units);
    let (outcome, world) = outcome(g, &spec.pattern, Up::Z, to_units);
    let inputs: Vec<&Path> = [sc.path.as_path(), spec.path.as_path()]
        .into_iter()
        .chain(sc.objects.iter().map(|o| o.mesh.as_path()))
        .collect();
    let names = super::drape::object_names(&sc, out);
    let existed = out.exists();
    let mut staged = Vec::new();
    let written = (|| -> anyhow::Result<(Vec<String>, Vec<Vec<String>>)> {
        std::fs::create_dir_all(out)
            .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", out.display()))?;
        let (mesh, groups) = garment_mesh(&world, Up::Z, to_units);
        let rest: Vec<[f64; 2]> = (world.model.rest.iter())
            .map(|q| [q.x * to_units, q.y * to_units])
            .collect();
        let mut files = Vec::new();
        let path = out.join(format!("{}.obj", spec.name));
        staged.push(io::stage_obj_with_rest(
            &path, &mesh, &rest, &groups, &inputs,
        )?);
        files.push(path.display().to_string());
        if sc.ply {
            let path = out.join(format!("{}.ply", spec.name));
            staged.push(io::stage_mesh(&path, &mesh, &WriteOptions::default(), &inputs)?.0);
            files.push(path.display().to_string());
        }
        let objects = stage_objects(&sc, &world, &names, out, &inputs, &mut staged)?;
        if args.glb {
            // glTF's own frame: metres, y up.
            let (mesh, groups) = garment_mesh(&world, Up::Y, 1.0);
            let placed: Vec<_> = (world.colliders.iter())
                .map(|c| {
                    let mut m = c.mesh.clone();
                    crate::mesh::transform::change_up(&mut m, Up::Z, Up::Y);
                    m
                })
                .collect();
            let bodies: Vec<(&str, &crate::mesh::TriMesh)> =
                names.iter().map(String::as_str).zip(&placed).collect();
            let path = out.join(format!("{}.glb", super::drape::scene_stem(&sc)));
            let rest = &world.model.rest;
            staged.push(stage_glb(&path, &mesh, rest, &groups, &bodies, &inputs)?);
            files.push(path.display().to_string());
        }
        if args.preview {
            files.push(super::drape::stage_preview(
                &world,
                out,
                to_units,
                &inputs,
                &mut staged,
            )?);
        }
        io::commit(std::mem::take(&mut staged))?;
        Ok((files, objects))
    })();
    let (files, object_files) = match written {
        Ok(w) => w,
        Err(e) => {
            drop(staged);
            if !existed {
                let _ = std::fs::remove_dir(out);
            }
            return Err(e);
        }
    };
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
