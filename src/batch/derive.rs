//! A scene job's own scene: the plan's scene file with the job's axis values applied.
//!
//! The scene is read as a TOML table and changed in four places: `[solver]` takes the plan's
//! keys (a stop given by the plan first removes the scene's `steps`, `duration`, `until_rest`
//! and `max_steps`); every `[[object]]`'s mesh path and every `[[garment]]`'s pattern path is
//! made absolute (the job's scene lives in `OUT/jobs/<id>/`); the body object's mesh and `up`
//! become the body's and its `scale` is multiplied by the size's; every `[[piece]]` and
//! `[[garment]]` takes the fabric, and the plan's `[fabric.NAME]` table (if any) is copied into
//! the scene. `drape` then validates the result as any scene.

use super::body::BodyMesh;
use super::plan::{Plan, SolverOverrides};
use super::BatchError;
use crate::mesh::transform::Up;
use std::path::Path;
use toml::{Table, Value};

/// What a scene job changes in its scene.
#[derive(Debug, Clone, Default)]
pub struct SceneChanges<'a> {
    /// The body replacing the body object's mesh.
    pub body: Option<BodyMesh>,
    /// The size's scale factor for the body object.
    pub scale: Option<f64>,
    /// The body object's index.
    pub object: usize,
    /// The fabric's name and its table (`None`: a preset).
    pub fabric: Option<(&'a str, Option<&'a Table>)>,
}

/// The scene `file` with `changes` and the plan's solver keys applied, as TOML text.
pub fn scene(plan: &Plan, file: &Path, changes: &SceneChanges) -> Result<String, BatchError> {
    let text = std::fs::read_to_string(file).map_err(|source| BatchError::Read {
        path: file.to_path_buf(),
        source,
    })?;
    let mut t: Table = toml::from_str(&text).map_err(|e| BatchError::Toml {
        path: file.to_path_buf(),
        message: crate::scene::toml_message(&text, &e),
    })?;
    solver(&mut t, &plan.solver);
    let dir = file.parent().unwrap_or(Path::new("."));
    objects(&mut t, dir, changes);
    garments(&mut t, dir);
    if let Some((name, table)) = changes.fabric {
        fabric(&mut t, name, table);
    }
    Ok(toml::to_string(&t).expect("a TOML table serialises"))
}

fn solver(t: &mut Table, o: &SolverOverrides) {
    let s = t
        .entry("solver")
        .or_insert_with(|| Value::Table(Table::new()));
    let Some(s) = s.as_table_mut() else { return };
    if o.has_stop() {
        for k in ["steps", "duration", "until_rest", "max_steps"] {
            s.remove(k);
        }
    }
    if let Ok(Value::Table(over)) = Value::try_from(o) {
        s.extend(over);
    }
}

fn objects(t: &mut Table, dir: &Path, c: &SceneChanges) {
    let Some(Value::Array(objs)) = t.get_mut("object") else {
        return;
    };
    for (i, o) in objs.iter_mut().enumerate() {
        let Some(o) = o.as_table_mut() else { continue };
        if let Some(Value::String(m)) = o.get("mesh") {
            let abs = dir.join(m);
            o.insert("mesh".into(), Value::String(abs.display().to_string()));
        }
        if i != c.object {
            continue;
        }
        if let Some(b) = &c.body {
            o.insert("mesh".into(), Value::String(b.file.display().to_string()));
            let up = if b.up == Up::Y { "y" } else { "z" };
            o.insert("up".into(), Value::String(up.into()));
        }
        if let Some(k) = c.scale {
            let old = o
                .get("scale")
                .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
                .unwrap_or(1.0);
            o.insert("scale".into(), Value::Float(old * k));
        }
    }
}

/// Every `[[garment]]`'s pattern path made absolute (relative to the scene's folder `dir`).
fn garments(t: &mut Table, dir: &Path) {
    let Some(Value::Array(garments)) = t.get_mut("garment") else {
        return;
    };
    for g in garments.iter_mut().filter_map(Value::as_table_mut) {
        if let Some(Value::String(p)) = g.get("pattern") {
            let abs = dir.join(p);
            g.insert("pattern".into(), Value::String(abs.display().to_string()));
        }
    }
}

fn fabric(t: &mut Table, name: &str, table: Option<&Table>) {
    for cloth in ["piece", "garment"] {
        if let Some(Value::Array(items)) = t.get_mut(cloth) {
            for p in items.iter_mut().filter_map(Value::as_table_mut) {
                p.insert("fabric".into(), Value::String(name.into()));
            }
        }
    }
    if let Some(tb) = table {
        let f = t
            .entry("fabric")
            .or_insert_with(|| Value::Table(Table::new()));
        if let Some(f) = f.as_table_mut() {
            f.insert(name.into(), Value::Table(tb.clone()));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_garment_scene_keeps_its_pattern_and_takes_the_fabric() {
        let mut t: Table = toml::from_str(
            "[[object]]\nmesh = \"body.obj\"\n[[garment]]\npattern = \"skirt.json\"\nfabric = \"silk\"\n",
        )
        .unwrap();
        let dir = Path::new("/plans/scenes");
        garments(&mut t, dir);
        fabric(&mut t, "denim", None);
        let g = &t["garment"].as_array().unwrap()[0];
        assert_eq!(g["pattern"].as_str(), Some("/plans/scenes/skirt.json"));
        assert_eq!(g["fabric"].as_str(), Some("denim"));
    }
}
