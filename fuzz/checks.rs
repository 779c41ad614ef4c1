//! The readers under fuzzing: one check per fuzz target, shared by the cargo-fuzz targets
//! (`fuzz/fuzz_targets/*.rs`) and the main crate's seeded mutation pass
//! (`tests/fuzz_mutation.rs`), both of which include this file with `#[path]`, so the two can
//! never test different things.
//!
//! A check feeds untrusted bytes to one reader exactly as the command line does after reading
//! the file (text readers get the bytes as UTF-8, like `read_to_string`; bytes that are not
//! UTF-8 are that reader's "cannot read" error and are skipped). It accepts `Ok` and `Err`
//! alike. It panics when the reader panics, and when an `Ok` result breaks an invariant the
//! rest of drapekit relies on:
//!
//! * a mesh: every face index is below the vertex count, every coordinate is finite, the
//!   reported vertex count is the mesh's, texture coordinates (if any) are one finite pair per
//!   vertex;
//! * a scene: every length, scale and position finite, spacings and scales positive, seams'
//!   pieces in range; outlines and holes are checked when the cloth is built
//!   (`cloth::pattern::clean_outline`), so that check runs too, and what it accepts is finite;
//! * sections: the normalised sections (`fit::section::normalize`, the fitter's first step)
//!   have at least 3 finite points each and strictly increasing finite heights;
//! * measurements: the shape model's sections (`fit::measurements::sections`) are finite and
//!   its girth targets finite and positive;
//! * a pattern: every edge's vertices exist, each panel's edges form one closed loop, every
//!   stitch names an existing panel and edge, coordinates and units are finite;
//! * a batch plan: job ids are unique and are their axis values' names joined by `.`, every
//!   axis index is in range.
//!
//! Mesh files are read under a path in a folder that does not exist, so a glTF's buffer URI
//! never opens a file (relative paths, `..` included, fail on the missing folder); scenes and
//! plans are read as if they sat in `fixtures/` (`fixtures/scenes/` for scenes), so the meshes
//! and scenes the seeds name are found and validation goes on past "does not exist". Nothing is
//! ever written.

#![allow(dead_code)]

use drapekit::cloth::pattern::clean_outline;
use drapekit::io::{read_bytes, Format, ReadOptions, ReadOutput};
use drapekit::mesh::polygon::QuadSplit;
use std::path::{Path, PathBuf};

/// A check: feeds bytes to one reader; panics on a reader's panic or a broken invariant. Returns
/// whether the reader accepted the bytes (every seed must be accepted).
pub type Check = fn(&[u8]) -> bool;

/// Every fuzz target by name (the file `fuzz/fuzz_targets/<name>.rs` and the seed folder
/// `fuzz/corpus/<name>/`), with its check.
pub const TARGETS: &[(&str, Check)] = &[
    ("mesh_triples", |d| mesh(d, Format::Triples)),
    ("mesh_obj", |d| mesh(d, Format::Obj)),
    ("mesh_stl", |d| mesh(d, Format::Stl)),
    ("mesh_ply", |d| mesh(d, Format::Ply)),
    ("mesh_gltf", |d| mesh(d, Format::Gltf)),
    ("mesh_glb", |d| mesh(d, Format::Glb)),
    ("scene", scene),
    ("sections_json", |d| sections(d, "fuzz.json")),
    ("sections_csv", |d| sections(d, "fuzz.csv")),
    ("measurements_toml", |d| measurements(d, "fuzz.toml")),
    ("measurements_json", |d| measurements(d, "fuzz.json")),
    ("measurements_yaml", |d| measurements(d, "fuzz.yaml")),
    ("pattern", pattern),
    ("plan", plan),
];

/// The check called `name`.
pub fn check(name: &str) -> Option<Check> {
    TARGETS.iter().find(|(n, _)| *n == name).map(|&(_, c)| c)
}

/// Runs the check called `name` on `data` (what each fuzz target does).
pub fn run(name: &str, data: &[u8]) {
    let check = check(name).unwrap_or_else(|| panic!("no check is called {name}"));
    check(data);
}

/// A folder that does not exist: mesh files are "read" from it.
const NOWHERE: &str = "/nonexistent-drapekit-fuzz";

/// The repository's `fixtures/`. `CARGO_MANIFEST_DIR` is that of the crate including this
/// file: the repository (the mutation test) or its `fuzz/` (the fuzz targets).
pub fn fixtures() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    if dir.ends_with("fuzz") {
        dir.join("../fixtures")
    } else {
        dir.join("fixtures")
    }
}

// ---- Meshes ----------------------------------------------------------------------------

/// Reads `data` as `format` (named by its extension, split the paper's way), then with no
/// format known (told by the content, the path without an extension) and quads split along
/// the shorter diagonal; checks every mesh read.
fn mesh(data: &[u8], format: Format) -> bool {
    let named = Path::new(NOWHERE).join(format!("fuzz.{format}"));
    let read = read_bytes(&named, data, &ReadOptions::default());
    if let Ok(out) = &read {
        check_mesh(out, format);
    }
    let sniffed = ReadOptions {
        format: None,
        quad_split: QuadSplit::Shortest,
    };
    if let Ok(out) = read_bytes(&Path::new(NOWHERE).join("fuzz"), data, &sniffed) {
        check_mesh(&out, format);
    }
    read.is_ok()
}

/// The invariants of a mesh as read (module docs).
fn check_mesh(out: &ReadOutput, format: Format) {
    let m = &out.mesh;
    let n = m.positions.len();
    for (f, face) in m.faces.iter().enumerate() {
        assert!(
            face.iter().all(|&i| (i as usize) < n),
            "{format}: face {f} {face:?} indexes past the {n} vertices"
        );
    }
    for (v, p) in m.positions.iter().enumerate() {
        assert!(
            p.iter().all(|c| c.is_finite()),
            "{format}: vertex {v} is {p:?}"
        );
    }
    assert_eq!(
        out.info.vertices_in_file, n,
        "{format}: info.vertices_in_file against the mesh's vertices"
    );
    if let Some(t) = &out.texcoords {
        assert_eq!(t.len(), n, "{format}: texture coordinates per vertex");
        assert!(
            t.iter().flatten().all(|c| c.is_finite()),
            "{format}: texture coordinates finite"
        );
    }
}

// ---- Scenes ----------------------------------------------------------------------------

/// A scene file's bytes through `scene::parse`, as if in `fixtures/scenes/`.
fn scene(data: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    let path = fixtures().join("scenes").join("fuzz.toml");
    let Ok(s) = drapekit::scene::parse(text, &path) else {
        return false;
    };
    let finite = |what: &str, v: &[f64]| {
        assert!(v.iter().all(|x| x.is_finite()), "scene: {what} {v:?}");
    };
    finite("gravity", s.gravity.as_slice());
    assert!(
        s.solver.dt.is_finite() && s.solver.dt > 0.0,
        "scene: dt {}",
        s.solver.dt
    );
    for o in &s.objects {
        assert!(o.scale.is_finite() && o.scale > 0.0, "scene: scale {o:?}");
        finite("translate", o.translate.as_slice());
    }
    for p in &s.pieces {
        assert!(p.outline.len() >= 3, "scene: piece {} outline", p.name);
        assert!(
            p.spacing.is_finite() && p.spacing > 0.0,
            "scene: spacing {}",
            p.spacing
        );
        finite("position", p.position.as_slice());
        finite("rotation", &p.rotation);
        // Outlines and holes are checked when the cloth is built (`sim::load`), by these.
        for outline in std::iter::once(&p.outline).chain(&p.holes) {
            if let Ok(clean) = clean_outline(outline) {
                assert!(clean.len() >= 3, "scene: piece {} outline", p.name);
                for q in &clean {
                    finite("outline", q.coords.as_slice());
                }
            }
        }
    }
    for seam in &s.seams {
        for side in [&seam.a, &seam.b] {
            assert!(side.piece < s.pieces.len(), "scene: seam piece {seam:?}");
        }
    }
    true
}

// ---- Fit inputs ------------------------------------------------------------------------

/// A sections file through `fit::input::parse`, then normalised as the fitter does first.
fn sections(data: &[u8], name: &str) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    let Ok(file) = drapekit::fit::input::parse(text, Path::new(name)) else {
        return false;
    };
    assert_eq!(
        file.names.len(),
        file.sections.len(),
        "{name}: one name each"
    );
    let Ok((sections, _)) = drapekit::fit::section::normalize(file.sections) else {
        return false;
    };
    check_sections(&sections, name);
    for w in sections.windows(2) {
        assert!(
            w[0].height < w[1].height,
            "{name}: heights {} then {}",
            w[0].height,
            w[1].height
        );
    }
    true
}

/// At least 3 finite points in each section, finite heights.
fn check_sections(sections: &[drapekit::fit::section::Section], what: &str) {
    for (i, s) in sections.iter().enumerate() {
        assert!(s.height.is_finite(), "{what}: section {i} height");
        assert!(
            s.points.len() >= 3,
            "{what}: section {i} has {} points",
            s.points.len()
        );
        assert!(
            s.points.iter().all(|p| p.x.is_finite() && p.y.is_finite()),
            "{what}: section {i} has a non-finite point"
        );
    }
}

/// Sections of the shape model `measurements` asks for (the default level count).
const LEVELS: usize = 41;

/// A measurement set through `fit::foreign::parse_any` (the format told by content, then by
/// `name`'s extension), then the shape model's sections and girth targets.
fn measurements(data: &[u8], name: &str) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    let path = Path::new(name);
    let Ok(imported) = drapekit::fit::foreign::parse_any(text, path) else {
        return false;
    };
    let Ok((sections, targets, _)) =
        drapekit::fit::measurements::sections(&imported.measurements, path, LEVELS)
    else {
        return false;
    };
    check_sections(&sections, name);
    for t in &targets {
        assert!(
            t.height.is_finite() && t.requested.is_finite() && t.requested > 0.0,
            "{name}: girth target {t:?}"
        );
    }
    true
}

// ---- Patterns --------------------------------------------------------------------------

/// A GarmentCode specification through `garment::spec::parse`.
fn pattern(data: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    let Ok(p) = drapekit::garment::spec::parse(text, Path::new("fuzz.json")) else {
        return false;
    };
    assert!(
        p.units_in_meter.is_finite() && p.units_in_meter > 0.0,
        "pattern: units_in_meter {}",
        p.units_in_meter
    );
    for panel in &p.panels {
        let (nv, ne) = (panel.vertices.len(), panel.edges.len());
        assert!(ne >= 1, "pattern: panel {} has no edges", panel.name);
        for (k, e) in panel.edges.iter().enumerate() {
            assert!(
                e.start < nv && e.end < nv,
                "pattern: panel {} edge {k} {e:?} past {nv} vertices",
                panel.name
            );
            let next = &panel.edges[(k + 1) % ne];
            assert_eq!(
                e.end, next.start,
                "pattern: panel {} edges {k} and the next do not meet",
                panel.name
            );
        }
        assert!(
            panel
                .vertices
                .iter()
                .all(|v| v.x.is_finite() && v.y.is_finite())
                && panel.translation.iter().all(|c| c.is_finite())
                && panel.rotation_deg.iter().all(|c| c.is_finite()),
            "pattern: panel {} has a non-finite number",
            panel.name
        );
    }
    for s in &p.stitches {
        for r in [s.a, s.b] {
            assert!(
                r.panel < p.panels.len() && r.edge < p.panels[r.panel].edges.len(),
                "pattern: stitch {s:?} names a missing edge"
            );
        }
    }
    true
}

// ---- Batch plans -----------------------------------------------------------------------

/// A batch plan through `batch::plan::parse`, as if in `fixtures/`.
fn plan(data: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    let Ok(p) = drapekit::batch::plan::parse(text, &fixtures().join("fuzz_plan.toml")) else {
        return false;
    };
    let mut ids = std::collections::HashSet::new();
    for j in &p.jobs {
        assert!(ids.insert(j.id.as_str()), "plan: job id {} twice", j.id);
        assert!(j.garment < p.garments.len(), "plan: {j:?}");
        let mut names = vec![p.garments[j.garment].name.as_str()];
        let axis = |i: Option<usize>, n: usize| {
            assert!(i.is_none_or(|i| i < n), "plan: {j:?}");
            i
        };
        names.extend(axis(j.body, p.bodies.len()).map(|i| p.bodies[i].name.as_str()));
        names.extend(axis(j.fabric, p.fabrics.len()).map(|i| p.fabrics[i].name.as_str()));
        names.extend(axis(j.size, p.sizes.len()).map(|i| p.sizes[i].name.as_str()));
        assert_eq!(
            j.id,
            names.join("."),
            "plan: a job's id and its axis values"
        );
    }
    true
}
