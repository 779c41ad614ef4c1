//! Every job's status and report in one table: `OUT/results.csv` and `OUT/results.json`, a row
//! per job in position order.
//!
//! Columns: position, id, the axes (garment, body, fabric, size; empty when the plan has no
//! such axis), kind, state, verdict, seam_gap_max_mm, body_crossings, self_crossings,
//! max_strain, mean_strain, particles_inside, seconds (the job's command, wall), mesh (its main
//! mesh, relative to OUT), error. A pattern job's verdict, seam gap, crossings and strain are
//! its `garment` report's (the whole garment's measures); a scene job's verdict is `pass` when
//! every number of its drape report is finite and no particle ended inside a closed object, and
//! it has no seams or crossing counts (empty). Only `done` jobs have report values.
//!
//! The contact-sheet hook: `OUT/contact_sheet.tsv` lists each done job's id and main mesh (tab
//! separated, position order), the input a `render` command turns into a contact sheet.

use super::status::{self, State, Status};
use super::{order, BatchError};
use serde::Serialize;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// One row of the table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// Position (`--index`).
    pub position: usize,
    /// Job id.
    pub id: String,
    /// Garment or scene.
    pub garment: String,
    /// Body.
    pub body: Option<String>,
    /// Fabric.
    pub fabric: Option<String>,
    /// Size.
    pub size: Option<String>,
    /// `scene` or `pattern`.
    pub kind: String,
    /// `done`, `failed`, or `running` (unfinished).
    pub state: State,
    /// `pass` or `fail` (see the module docs).
    pub verdict: Option<String>,
    /// Widest seam gap, mm (patterns).
    pub seam_gap_max_mm: Option<f64>,
    /// Cloth edges crossing the body (patterns).
    pub body_crossings: Option<u64>,
    /// Cloth edges crossing the cloth (patterns).
    pub self_crossings: Option<u64>,
    /// Largest strain.
    pub max_strain: Option<f64>,
    /// Mean strain (scenes).
    pub mean_strain: Option<f64>,
    /// Particles inside the body or objects.
    pub particles_inside: Option<u64>,
    /// Wall time of the job's command, s.
    pub seconds: Option<f64>,
    /// Main mesh, relative to the output folder.
    pub mesh: Option<String>,
    /// Why it failed.
    pub error: Option<String>,
}

/// Every status under `out/jobs`, in position order.
pub fn statuses(out: &Path) -> Result<Vec<Status>, BatchError> {
    let jobs = out.join("jobs");
    let entries = std::fs::read_dir(&jobs).map_err(|_| BatchError::Empty {
        path: out.to_path_buf(),
    })?;
    let mut v = Vec::new();
    for e in entries.flatten() {
        if let Some(s) = status::read_file(&e.path().join("status.json"))? {
            v.push(s);
        }
    }
    if v.is_empty() {
        return Err(BatchError::Empty {
            path: out.to_path_buf(),
        });
    }
    let ids = order::load(out)?;
    let positions = order::positions(&ids);
    let pos = |s: &Status| positions.get(s.id.as_str()).copied().unwrap_or(s.position);
    v.sort_by(|a, b| pos(a).cmp(&pos(b)).then(a.id.cmp(&b.id)));
    Ok(v)
}

/// The table of `out`.
pub fn collect(out: &Path) -> Result<Vec<Row>, BatchError> {
    statuses(out)?.into_iter().map(|s| row(out, s)).collect()
}

fn row(out: &Path, s: Status) -> Result<Row, BatchError> {
    let mut r = Row {
        position: s.position,
        id: s.id,
        garment: s.axes.garment,
        body: s.axes.body,
        fabric: s.axes.fabric,
        size: s.axes.size,
        kind: s.kind,
        state: s.state,
        verdict: None,
        seam_gap_max_mm: None,
        body_crossings: None,
        self_crossings: None,
        max_strain: None,
        mean_strain: None,
        particles_inside: None,
        seconds: s.seconds,
        mesh: s.mesh,
        error: s.error,
    };
    if s.state == State::Done {
        if let Some(rep) = &s.report {
            let v = report(&out.join(rep))?;
            fill(&mut r, &v);
        }
    }
    Ok(r)
}

fn report(p: &Path) -> Result<Value, BatchError> {
    let text = std::fs::read_to_string(p).map_err(|source| BatchError::Read {
        path: p.to_path_buf(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|e| BatchError::Json {
        path: p.to_path_buf(),
        message: e.to_string(),
    })
}

/// The report's values into the row.
fn fill(r: &mut Row, v: &Value) {
    let f = |p: &str| v.pointer(p).and_then(Value::as_f64);
    let u = |p: &str| v.pointer(p).and_then(Value::as_u64);
    if r.kind == "pattern" {
        r.verdict = v
            .pointer("/verdict")
            .and_then(Value::as_str)
            .map(str::to_string);
        r.seam_gap_max_mm = f("/garment/seam_gap_max_mm");
        r.body_crossings = u("/garment/body_crossing_edges");
        r.self_crossings = u("/garment/self_crossing_edges");
        r.max_strain = f("/garment/max_strain");
        r.particles_inside = u("/garment/particles_inside");
    } else {
        r.max_strain = f("/max_strain");
        r.mean_strain = f("/mean_strain");
        r.particles_inside = u("/particles_inside");
        let finite = v.pointer("/finite").and_then(Value::as_bool) == Some(true);
        let pass = finite && r.particles_inside.unwrap_or(0) == 0;
        r.verdict = Some(if pass { "pass" } else { "fail" }.into());
    }
}

/// The files `write` writes.
pub fn paths(out: &Path) -> [PathBuf; 3] {
    [
        out.join("results.csv"),
        out.join("results.json"),
        out.join("contact_sheet.tsv"),
    ]
}

/// Writes the table (CSV and JSON) and the contact-sheet list, each atomically.
pub fn write(out: &Path, rows: &[Row]) -> Result<(), BatchError> {
    let [csv_path, json_path, sheet] = paths(out);
    crate::io::write_atomic(&csv_path, &[], |w| {
        let mut c = csv::Writer::from_writer(w);
        for r in rows {
            c.serialize(r).map_err(std::io::Error::other)?;
        }
        c.flush()
    })?;
    crate::io::write_atomic(&json_path, &[], |w| {
        serde_json::to_writer_pretty(&mut *w, rows)?;
        std::io::Write::write_all(w, b"\n")
    })?;
    crate::io::write_atomic(&sheet, &[], |w| {
        for r in rows.iter().filter(|r| r.state == State::Done) {
            if let Some(m) = &r.mesh {
                writeln!(w, "{}\t{m}", r.id)?;
            }
        }
        Ok(())
    })?;
    Ok(())
}

use std::io::Write as _;
