//! A scene's cloth: the `[fabric.NAME]` tables, the `[[piece]]`s cut from them and the
//! `[[seam]]`s between the pieces.

use super::{
    fabric_named, unknown_preset, FabricFile, File, PieceFile, PieceSpec, Problems, SeamFile,
    SeamSide, SeamSideFile, SeamSpec, COORDINATE_RESOLUTION, THICKNESS_RESOLUTION,
};
use crate::cloth::fabric::{Fabric, Kes};
use crate::cloth::pattern::{self, Pins};
use crate::math::{short, Point2, Vec3};
use std::collections::BTreeMap;

/// The `[fabric.NAME]` tables, by name (SI units, whatever the file's `units`).
pub(super) fn fabrics(
    tables: &BTreeMap<String, FabricFile>,
    p: &Problems,
) -> BTreeMap<String, Fabric> {
    tables
        .iter()
        .map(|(name, t)| (name.clone(), fabric(name, t, p)))
        .collect()
}

/// The table `[fabric.NAME]`: its start (a preset `base`, KES measurements or nothing), then
/// its own values (SI units: kg/m^2, N/m, N m, m), checked. Without a start, density,
/// stretch, shear and bend are required.
fn fabric(name: &str, t: &FabricFile, p: &Problems) -> Fabric {
    let k = |field: &str| format!("fabric.{name}.{field}");
    let mut fab = fabric_start(name, t, p);
    let full = t.base.is_some() || t.kes.is_some();
    let need = |v: Option<f64>, field: &str| {
        if v.is_none() && !full {
            p.bad(
                &k(field),
                "is required (or start from a preset with base = \"...\")".into(),
            );
        }
        v
    };
    if let Some(v) = need(t.density, "density") {
        fab.density = v;
    }
    if need(t.stretch.map(|pair| pair.get()[0]), "stretch").is_some() {
        fab.stretch = t.stretch.map(|pair| pair.get()).unwrap_or(fab.stretch);
    }
    if let Some(v) = need(t.shear, "shear") {
        fab.shear = v;
    }
    if need(t.bend.map(|pair| pair.get()[0]), "bend").is_some() {
        fab.bend = t.bend.map(|pair| pair.get()).unwrap_or(fab.bend);
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
        p.bad(&k(field), m);
    }
    fab
}

/// What the table `[fabric.NAME]` starts from: its `base` preset or its `kes` measurements
/// (not both), else cotton.
fn fabric_start(name: &str, t: &FabricFile, p: &Problems) -> Fabric {
    match (&t.base, &t.kes) {
        (Some(_), Some(_)) => {
            p.bad(
                &format!("fabric.{name}"),
                "give base or kes, not both".into(),
            );
            Fabric::cotton()
        }
        (Some(b), None) => Fabric::preset(b).unwrap_or_else(|| {
            p.bad(&format!("fabric.{name}.base"), unknown_preset(b));
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
    }
}

/// The `[[piece]]`s (at least one, unless the scene has a `[[garment]]`; no two of one name),
/// lengths from the file's units to metres (`to_m` metres per unit), fabrics from `fabrics` or
/// the presets.
pub(super) fn pieces(
    f: &File,
    fabrics: &BTreeMap<String, Fabric>,
    to_m: f64,
    p: &Problems,
) -> Vec<PieceSpec> {
    if f.piece.is_empty() && f.garment.is_empty() {
        p.bad(
            "piece",
            "a scene needs at least one [[piece]] (or a [[garment]])".into(),
        );
    }
    let pieces: Vec<PieceSpec> = f
        .piece
        .iter()
        .enumerate()
        .map(|(i, pf)| piece(i, pf, fabrics, to_m, p))
        .collect();
    let mut names: Vec<&str> = pieces.iter().map(|pc| pc.name.as_str()).collect();
    names.sort_unstable();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        p.bad("piece.name", format!("two pieces are named '{}'", w[0]));
    }
    pieces
}

/// The `i`-th `[[piece]]` (from 0): spacing, fabric, placement (position in file units,
/// rotation in degrees), outline, holes, pins and name; lengths to metres (`to_m` metres per
/// unit).
fn piece(
    i: usize,
    pf: &PieceFile,
    fabrics: &BTreeMap<String, Fabric>,
    to_m: f64,
    p: &Problems,
) -> PieceSpec {
    let at = format!("piece[{}]", i + 1);
    let k = |field: &str| format!("{at}.{field}");
    let spacing = p.positive(&k("spacing"), pf.spacing, 0.01) * to_m;
    let fabric_name = pf.fabric.clone().unwrap_or_else(|| "cotton".into());
    let fabric = fabric_named(&fabric_name, fabrics, &k("fabric"), p);
    let position = pf.position.unwrap_or([0.0; 3]);
    p.finite(&k("position"), &position);
    let farthest = |v: &mut dyn Iterator<Item = &f64>| v.map(|v| v.abs()).fold(0.0, f64::max);
    let by_position = farthest(&mut position.iter());
    let by_outline = farthest(&mut pf.outline.iter().flatten());
    let reach = by_position.max(by_outline) * to_m;
    let far = too_far(reach, spacing, fabric.thickness);
    if let Some(m) = &far {
        // Named after what reaches that far.
        let key = if by_outline > by_position {
            "outline"
        } else {
            "position"
        };
        p.bad(&k(key), m.clone());
    }
    let rotation = pf.rotation.unwrap_or([0.0; 3]);
    p.finite(&k("rotation"), &rotation);
    let outline = points(&pf.outline, to_m);
    if outline.len() < 3 {
        p.bad(
            &k("outline"),
            format!("a polygon needs at least 3 points, got {}", outline.len()),
        );
    } else if let Err(e) = pattern::check_particle_count(&outline, spacing) {
        match e {
            // Said already, under `position`.
            pattern::PatternError::TooFar { .. } if far.is_some() => {}
            pattern::PatternError::TooFar { .. } => p.bad(&k("outline"), e.to_string()),
            e => p.bad(&k("spacing"), e.to_string()),
        }
    }
    let holes = pf.holes.iter().map(|h| points(h, to_m)).collect();
    let pins = pins(&at, pf, to_m, p);
    let name = piece_name(i, &at, pf, p);
    PieceSpec {
        name,
        outline,
        holes,
        spacing,
        position: Vec3::from(position) * to_m,
        rotation,
        fabric,
        fabric_name,
        pins,
    }
}

/// A point of the file (its units) in metres (`to_m` metres per unit).
fn point(q: [f64; 2], to_m: f64) -> Point2 {
    Point2::new(q[0] * to_m, q[1] * to_m)
}

/// Points of the file (its units) in metres (`to_m` metres per unit).
fn points(list: &[[f64; 2]], to_m: f64) -> Vec<Point2> {
    list.iter().map(|&q| point(q, to_m)).collect()
}

/// What holds the piece whose keys are `at.field`: its `pin` points, its `pin_segments` and
/// its `pin_radius` (a length >= 0), from the file's units to metres (`to_m` metres per unit).
fn pins(at: &str, pf: &PieceFile, to_m: f64, p: &Problems) -> Pins {
    for q in &pf.pin {
        p.finite(&format!("{at}.pin"), q);
    }
    for q in &pf.pin_segments {
        p.finite(&format!("{at}.pin_segments"), &q.concat());
    }
    let radius = match pf.pin_radius {
        None => 0.0,
        Some(r) if r.is_finite() && r >= 0.0 => r * to_m,
        Some(r) => {
            p.bad(
                &format!("{at}.pin_radius"),
                format!("must be a length >= 0, got {}", short(r)),
            );
            0.0
        }
    };
    Pins {
        points: points(&pf.pin, to_m),
        radius,
        segments: pf
            .pin_segments
            .iter()
            .map(|s| s.map(|q| point(q, to_m)))
            .collect(),
    }
}

/// The `i`-th piece's (from 0) name, keys `at.field`: its own or `piece<i + 1>`, which must
/// do for a file name.
fn piece_name(i: usize, at: &str, pf: &PieceFile, p: &Problems) -> String {
    let name = pf.name.clone().unwrap_or_else(|| format!("piece{}", i + 1));
    if !crate::io::is_safe_file_name(&name) {
        p.bad(
            &format!("{at}.name"),
            format!(
                "{name:?} cannot be a file name in the output folder (the piece is written as <name>.obj): {}",
                crate::io::FILE_NAME_RULE
            ),
        );
    }
    name
}

/// Why a piece of `spacing` and fabric `thickness` reaching `reach` m from the origin (its
/// position plus its outline) is too far: there, neighbouring f64 numbers are more than
/// [`COORDINATE_RESOLUTION`] of the spacing apart (the cloth's shape is lost to rounding), or
/// more than [`THICKNESS_RESOLUTION`] of the thickness (so are its contacts, and a step's fall
/// under gravity, about a millimetre).
fn too_far(reach: f64, spacing: f64, thickness: f64) -> Option<String> {
    let gap = reach * f64::EPSILON;
    let by_thickness = THICKNESS_RESOLUTION * thickness;
    let (what, length, least) = if thickness > 0.0 && by_thickness < COORDINATE_RESOLUTION * spacing
    {
        (
            "a thousandth of the fabric's thickness",
            thickness,
            by_thickness,
        )
    } else {
        (
            "a millionth of the spacing",
            spacing,
            COORDINATE_RESOLUTION * spacing,
        )
    };
    (gap.is_finite() && gap > least).then(|| {
        format!(
            "reaches {} m from the origin, where coordinates are {} m apart: more than {what} ({} m), so rounding would break the cloth; place it within {} m of the origin",
            short(reach),
            short(gap),
            short(length),
            short(least / f64::EPSILON)
        )
    })
}

/// The `[[seam]]`s: each side a stretch of a named piece's outline, corners from the file's
/// units to metres (`to_m` metres per unit). A seam naming no piece of `pieces` is left out.
pub(super) fn seams(
    list: &[SeamFile],
    pieces: &[PieceSpec],
    to_m: f64,
    p: &Problems,
) -> Vec<SeamSpec> {
    let mut seams = Vec::new();
    for (i, sf) in list.iter().enumerate() {
        let side = |s: &SeamSideFile, which: &str| {
            seam_side(&format!("seam[{}].{which}", i + 1), s, pieces, to_m, p)
        };
        if let (Some(a), Some(b)) = (side(&sf.a, "a"), side(&sf.b, "b")) {
            seams.push(SeamSpec { a, b });
        }
    }
    seams
}

/// One side of a seam, keys `key.field`: the piece it names among `pieces` and its corners
/// `from` and `to` (file units to metres, `to_m` metres per unit); `None` when no piece has
/// the name.
fn seam_side(
    key: &str,
    s: &SeamSideFile,
    pieces: &[PieceSpec],
    to_m: f64,
    p: &Problems,
) -> Option<SeamSide> {
    p.finite(&format!("{key}.from"), &s.from);
    p.finite(&format!("{key}.to"), &s.to);
    let Some(piece) = pieces.iter().position(|pc| pc.name == s.piece) else {
        p.bad(
            &format!("{key}.piece"),
            format!("no piece is named '{}'", s.piece),
        );
        return None;
    };
    Some(SeamSide {
        piece,
        from: point(s.from, to_m),
        to: point(s.to, to_m),
    })
}
