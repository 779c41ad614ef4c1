//! A scene's `[[garment]]`: a GarmentCode pattern sewn on the scene's objects and draped, its
//! settings validated, and what a garment scene does not support refused by key.

use super::{fabric_named, File, GarmentFile, GarmentSpec, HoldWaistFile, Problems, SolverFile};
use crate::cloth::fabric::Fabric;
use crate::cloth::integrate::SolverSettings;
use crate::garment::assemble::Placement;
use crate::garment::drape::{
    GarmentSettings, WaistHold, GARMENT_BENDING_HESSIAN, GARMENT_INTEGRATOR, SEW_ITERATIONS,
};
use crate::garment::Pattern;
use crate::math::{short, Vec3};
use std::collections::BTreeMap;
use std::path::Path;

/// What a `[[garment]]` reads from the rest of the scene.
pub(super) struct GarmentContext<'a> {
    /// The scene file's folder (the pattern is relative to it).
    pub(super) dir: &'a Path,
    /// Metres per unit of the file.
    pub(super) to_m: f64,
    /// The scene's `[fabric.NAME]` tables.
    pub(super) fabrics: &'a BTreeMap<String, Fabric>,
    /// The scene's solver.
    pub(super) solver: SolverSettings,
    /// The solver table as written (which keys were given).
    pub(super) solver_file: &'a SolverFile,
}

/// The scene's garment, if it has one `[[garment]]` (more are refused), and the refusal of
/// what a garment scene does not support ([`garment_limits`]).
pub(super) fn garment(f: &File, cx: &GarmentContext, p: &Problems) -> Option<GarmentSpec> {
    let garment = match f.garment.as_slice() {
        [] => None,
        [g] => garment_spec(g, cx, p),
        [_, more @ ..] => {
            p.bad(
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
        garment_limits(f, p);
    }
    garment
}

/// The scene's `[[garment]]`: the settings validated, then the pattern read and checked, every
/// problem recorded by key. `None` when the pattern cannot be read.
fn garment_spec(g: &GarmentFile, cx: &GarmentContext, p: &Problems) -> Option<GarmentSpec> {
    let fabric_name = g.fabric.clone().unwrap_or_else(|| "cotton".into());
    let settings = garment_settings(g, &fabric_name, cx, p);
    let path = cx.dir.join(&g.pattern);
    let pattern = pattern(&path, p)?;
    Some(GarmentSpec {
        name: garment_name(&path),
        path,
        pattern,
        fabric_name,
        settings,
    })
}

/// The garment's settings: fabric `fabric_name`, spacing and clearances (file units to
/// metres), placement, friction, stages, self-collision and solver, each problem recorded
/// under its key.
fn garment_settings(
    g: &GarmentFile,
    fabric_name: &str,
    cx: &GarmentContext,
    p: &Problems,
) -> GarmentSettings {
    let mut settings = GarmentSettings::default();
    settings.assemble.fabric = fabric_named(fabric_name, cx.fabrics, "garment.fabric", p);
    let length = |v: Option<f64>| v.map(|v| v * cx.to_m);
    if let Some(h) = length(g.spacing) {
        settings.assemble.spacing = h;
    }
    settings.assemble.placement = placement(g, cx.to_m, p);
    settings.friction = g.friction.unwrap_or(settings.friction);
    settings.sew_max = g.sew_max.unwrap_or(settings.sew_max);
    settings.settle_max = g.settle_max.unwrap_or(settings.settle_max);
    settings.body_clearance = length(g.body_clearance);
    if let Some(h) = &g.hold_waist {
        settings.hold_waist = hold_waist(h, cx.to_m, p);
    }
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
    settings.solver = garment_solver(cx);
    settings_problems(&settings, g, p);
    settings
}

/// Where the garment goes: `translation` (file units to metres, `to_m` metres per unit) and
/// `rotation` (degrees about z).
fn placement(g: &GarmentFile, to_m: f64, p: &Problems) -> Placement {
    let translation = g.translation.unwrap_or([0.0; 3]);
    p.finite("garment.translation", &translation);
    let turn = g.rotation.unwrap_or(0.0);
    if !turn.is_finite() {
        p.bad(
            "garment.rotation",
            format!("must be a finite angle in degrees, got {}", short(turn)),
        );
    }
    Placement {
        turn_deg: turn,
        translation: Vec3::from(translation) * to_m,
    }
}

/// `garment.hold_waist`: `"off"`, `"auto"` or a height (file units to metres, `to_m` metres
/// per unit).
fn hold_waist(h: &HoldWaistFile, to_m: f64, p: &Problems) -> WaistHold {
    match h {
        HoldWaistFile::Height(z) => WaistHold::Level(z * to_m),
        HoldWaistFile::Word(w) => match w.as_str() {
            "off" => WaistHold::Off,
            "auto" => WaistHold::Auto,
            _ => {
                let m =
                    format!("expected \"off\", \"auto\" or a height (scene units), got \"{w}\"");
                p.bad("garment.hold_waist", m);
                WaistHold::Off
            }
        },
    }
}

/// The garment's solver: the scene's, with the garments' own integrator, iterations and
/// bending Hessian where the `[solver]` table gives none.
fn garment_solver(cx: &GarmentContext) -> SolverSettings {
    let mut solver = cx.solver;
    if cx.solver_file.integrator.is_none() {
        solver.integrator = GARMENT_INTEGRATOR;
    }
    if cx.solver_file.iterations.is_none() {
        solver.iterations = SEW_ITERATIONS;
    }
    if cx.solver_file.bending_hessian.is_none() {
        solver.bending_hessian = GARMENT_BENDING_HESSIAN;
    }
    solver
}

/// The problems of the garment's `settings`, each under the scene's key for it.
fn settings_problems(settings: &GarmentSettings, g: &GarmentFile, p: &Problems) {
    for problem in settings.problems() {
        let key = match problem.field {
            "integrator" => "solver.integrator".to_string(),
            "cloth_friction" if g.self_collision == Some(false) => {
                "garment.self_collision".to_string()
            }
            field => format!("garment.{field}"),
        };
        if problem.field == "integrator" {
            p.bad(&key, problem.message);
        } else {
            p.bad(
                &key,
                format!("{}, got {}", problem.message, short(problem.value)),
            );
        }
    }
}

/// The pattern at `path` (a GarmentCode specification JSON), read and checked; `None`, with
/// the problem recorded under `garment.pattern`, when it cannot be.
fn pattern(path: &Path, p: &Problems) -> Option<Pattern> {
    if !path.is_file() {
        p.bad(
            "garment.pattern",
            format!(
                "{} does not exist (a GarmentCode specification JSON, relative to the scene file)",
                path.display()
            ),
        );
        return None;
    }
    match crate::garment::read(path) {
        Ok(pattern) => Some(pattern),
        Err(e) => {
            p.bad("garment.pattern", e.to_string());
            None
        }
    }
}

/// The garment's output name: the pattern file's stem without `_specification`, or
/// `garment` when that cannot be a file name.
fn garment_name(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "garment".into());
    let name = stem
        .strip_suffix("_specification")
        .unwrap_or(&stem)
        .to_string();
    if crate::io::is_safe_file_name(&name) {
        name
    } else {
        "garment".into()
    }
}

/// Refuses, by key, what a scene with a `[[garment]]` does not support.
fn garment_limits(f: &File, p: &Problems) {
    let with = "is not supported with a [[garment]]";
    if !f.piece.is_empty() {
        p.bad(
            "piece",
            format!("{with}: the garment's panels are the scene's cloth (drape pieces in a scene of their own)"),
        );
    }
    if !f.seam.is_empty() {
        p.bad(
            "seam",
            format!("{with}: the pattern's stitches are its seams"),
        );
    }
    if f.object.is_empty() {
        p.bad(
            "object",
            "a [[garment]] is sewn on the scene's objects: give at least one [[object]] (the first is the body)".into(),
        );
    }
    if f.gravity.is_some() {
        p.bad(
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
            p.bad(
                key,
                format!("{with}: the garment's stages end its run (garment.sew_max, garment.settle_max)"),
            );
        }
    }
    if f.output.as_ref().is_some_and(|o| o.frames.is_some()) {
        p.bad(
            "output.frames",
            format!("{with}: a garment's run writes no frames"),
        );
    }
    if f.report.as_ref().is_some_and(|r| r.disc_radius.is_some()) {
        p.bad(
            "report.disc_radius",
            format!("{with}: the Cusick coefficient is for a single piece"),
        );
    }
}
