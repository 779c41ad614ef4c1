//! Measurement sets from other tools, mapped to drapekit's ISO 8559-1 keys.
//!
//! `fit --measurements` reads three formats, told apart by their content (then the extension):
//!
//! * drapekit's own TOML ([`super::measurements`]);
//! * **FreeSewing** JSON, in millimetres: an object `measurements` or `measurements_mm` of
//!   FreeSewing's names (camelCase);
//! * **GarmentCode** body YAML, in centimetres: a mapping `body` of GarmentCode's names
//!   (`../shared/realdata/bodies/*.yaml`).
//!
//! | drapekit (ISO 8559-1) | FreeSewing | GarmentCode |
//! |---|---|---|
//! | `stature` (5.1.1) | estimated: `(waistToFloor + hpsToWaistBack) / 0.845` (the neck base's default level), else `waistToFloor / 0.631` | `height` |
//! | `bust_girth` (5.3.4) | `chest` (its fullest girth) | `bust` |
//! | `underbust_girth` (5.3.5) | `underbust` | `underbust` |
//! | `waist_girth` (5.3.10) | `waist` | `waist` |
//! | `top_hip_girth` (5.3.12) | `hips` (taken `waistToHips` below the waist) | |
//! | `hip_girth` (5.3.13) | `seat` (fullest buttocks) | `hips` |
//! | `neck_base_girth` (5.3.2) | `neck` | |
//! | `waist_height` (5.1.6) | `waistToFloor` | `height - head_l - waist_line` |
//! | `top_hip_height` | `waistToFloor - waistToHips` | |
//! | `hip_height` | `waistToFloor - waistToSeat` | the waist's `- hips_line` |
//! | `underbust_height` | `waistToFloor + waistToUnderbust` | |
//! | `bust_height` | the underbust's + `bustPointToUnderbust` | `height - head_l - vert_bust_line` |
//! | `shoulder_width` (5.4.2) | `shoulderToShoulder` | `shoulder_w` |
//!
//! Every other key is listed as not used; the estimated stature is reported. A GarmentCode
//! `hips` is the fullest hip girth (its bodies' hip level), FreeSewing's `hips` the upper hip.
//!
//! ```
//! use drapekit::fit::foreign::from_freesewing;
//! let json = r#"{"measurements": {"chest": 925, "waist": 750, "seat": 1010,
//!                "waistToFloor": 1050, "hpsToWaistBack": 395}}"#;
//! let got = from_freesewing(&serde_json::from_str(json).unwrap(), "m.json".as_ref()).unwrap();
//! let m = &got.measurements;
//! assert_eq!((m.bust_girth, m.hip_girth, m.waist_height), (Some(92.5), Some(101.0), Some(105.0)));
//! assert!((m.stature.unwrap() - 171.0).abs() < 0.05); // (1050 + 395) / 0.845 mm, in cm
//! ```

use super::error::FitError;
use super::measurements::Measurements;
use std::collections::BTreeMap;
use std::path::Path;

/// A measurement set read from any of the formats, with what was assumed on the way.
#[derive(Debug, Clone, PartialEq)]
pub struct Imported {
    pub measurements: Measurements,
    /// The format read: `toml`, `freesewing` or `garmentcode`.
    pub format: &'static str,
    /// What was estimated or left out, for the report.
    pub notes: Vec<String>,
}

/// The neck base's default level as a fraction of the stature (the shape model's table).
const NECK_BASE_LEVEL: f64 = 0.845;
/// The waist's default level as a fraction of the stature.
const WAIST_LEVEL: f64 = 0.631;

/// What the formats say when a file is none of them.
const FORMATS: &str = "measurement sets are read as drapekit TOML (its own ISO 8559-1 keys), \
FreeSewing JSON (an object 'measurements' in mm) or GarmentCode body YAML (a mapping 'body' in cm)";

/// Reads a measurement set in any of the formats (module notes).
pub fn read_any(path: &Path) -> Result<Imported, FitError> {
    let text = std::fs::read_to_string(path).map_err(|source| FitError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_any(&text, path)
}

/// A measurement set's `text` in any of the formats, told apart as by [`read_any`] (`path`
/// names it in errors, and its extension is the second clue).
pub fn parse_any(text: &str, path: &Path) -> Result<Imported, FitError> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    let ext = ext.to_ascii_lowercase();
    let trimmed = text.trim_start_matches('\u{feff}').trim_start();
    if trimmed.starts_with('{') || ext == "json" {
        let json_error = |e: serde_json::Error| FitError::Json {
            path: path.to_path_buf(),
            line: e.line(),
            column: e.column(),
            message: format!("{} ({FORMATS})", super::input::json_message(&e)),
        };
        serde_json::from_str::<Unique>(text).map_err(json_error)?;
        let value: serde_json::Value = serde_json::from_str(text).map_err(json_error)?;
        return from_freesewing(&value, path);
    }
    if ext == "yaml" || ext == "yml" || trimmed.starts_with("body:") {
        return from_garmentcode(text, path);
    }
    let measurements = super::measurements::read_str(text, path)?;
    Ok(Imported {
        measurements,
        format: "toml",
        notes: Vec::new(),
    })
}

/// Any JSON or YAML value whose mappings give each key once (serde_json and the YAML reader
/// kept one of a key given twice without a word: `{"waist": 700, "waist": 800}` was a waist
/// of 800).
struct Unique;

impl<'de> serde::Deserialize<'de> for Unique {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Unique, D::Error> {
        d.deserialize_any(UniqueVisitor)
    }
}

struct UniqueVisitor;

impl<'de> serde::de::Visitor<'de> for UniqueVisitor {
    type Value = Unique;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON or YAML value")
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut a: A) -> Result<Unique, A::Error> {
        let mut keys = std::collections::BTreeSet::new();
        while let Some(k) = a.next_key::<String>()? {
            if !keys.insert(k.clone()) {
                let e = format!("the key '{k}' is given twice in one object");
                return Err(serde::de::Error::custom(e));
            }
            a.next_value::<Unique>()?;
        }
        Ok(Unique)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<Unique, A::Error> {
        while a.next_element::<Unique>()?.is_some() {}
        Ok(Unique)
    }
    fn visit_bool<E>(self, _: bool) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_i64<E>(self, _: i64) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_u64<E>(self, _: u64) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_f64<E>(self, _: f64) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_str<E>(self, _: &str) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_unit<E>(self) -> Result<Unique, E> {
        Ok(Unique)
    }
}

/// The numbers of a FreeSewing object, in mm; every non-number named.
fn numbers(
    map: &serde_json::Map<String, serde_json::Value>,
    path: &Path,
    at: &str,
) -> Result<BTreeMap<String, f64>, FitError> {
    let mut out = BTreeMap::new();
    for (k, v) in map {
        match v.as_f64() {
            Some(x) if x.is_finite() => {
                out.insert(k.clone(), x);
            }
            _ => {
                return Err(FitError::Key {
                    path: path.to_path_buf(),
                    key: format!("{at}.{k}"),
                    message: format!("expected a number (mm), found {v}"),
                })
            }
        }
    }
    Ok(out)
}

/// A FreeSewing measurement set (JSON, mm) as drapekit's measurements, in cm.
pub fn from_freesewing(value: &serde_json::Value, path: &Path) -> Result<Imported, FitError> {
    let found = ["measurements_mm", "measurements"]
        .iter()
        .find_map(|k| value.get(*k).and_then(|v| v.as_object()).map(|m| (*k, m)));
    let Some((at, map)) = found else {
        return Err(FitError::Key {
            path: path.to_path_buf(),
            key: "measurements".into(),
            message: format!("no FreeSewing object 'measurements' in this JSON file: {FORMATS}"),
        });
    };
    let mm = numbers(map, path, at)?;
    let mut m = freesewing_cm(&mm);
    let mut notes = Vec::new();
    let hps_to_waist_back = mm.get("hpsToWaistBack").map(|v| v / 10.0);
    m.stature = estimated_stature(m.waist_height, hps_to_waist_back, &mut notes);
    const USED: [&str; 13] = [
        "neck",
        "chest",
        "underbust",
        "waist",
        "hips",
        "seat",
        "shoulderToShoulder",
        "waistToFloor",
        "waistToHips",
        "waistToSeat",
        "waistToUnderbust",
        "bustPointToUnderbust",
        "hpsToWaistBack",
    ];
    unused(&mut notes, mm.keys(), &USED);
    Ok(Imported {
        measurements: m,
        format: "freesewing",
        notes,
    })
}

/// A FreeSewing set's values (mm) as drapekit's measurements in cm: girths, and heights
/// from the floor measured from the waist.
fn freesewing_cm(mm: &BTreeMap<String, f64>) -> Measurements {
    let cm = |k: &str| mm.get(k).map(|v| v / 10.0);
    let mut m = Measurements {
        units: Some("cm".into()),
        bust_girth: cm("chest"),
        underbust_girth: cm("underbust"),
        waist_girth: cm("waist"),
        top_hip_girth: cm("hips"),
        hip_girth: cm("seat"),
        neck_base_girth: cm("neck"),
        shoulder_width: cm("shoulderToShoulder"),
        waist_height: cm("waistToFloor"),
        ..Measurements::default()
    };
    if let Some(w) = m.waist_height {
        m.top_hip_height = cm("waistToHips").map(|d| w - d);
        m.hip_height = cm("waistToSeat").map(|d| w - d);
        m.underbust_height = cm("waistToUnderbust").map(|d| w + d);
        m.bust_height = (m.underbust_height.zip(cm("bustPointToUnderbust"))).map(|(u, d)| u + d);
    }
    m
}

/// The stature from the waist height and the neck base above it (or the waist alone), with
/// the note that says how; `None` without a waist height.
fn estimated_stature(
    waist_height: Option<f64>,
    hps_to_waist_back: Option<f64>,
    notes: &mut Vec<String>,
) -> Option<f64> {
    match (waist_height, hps_to_waist_back) {
        (Some(w), Some(b)) => {
            let s = (w + b) / NECK_BASE_LEVEL;
            notes.push(format!("stature estimated from waistToFloor + hpsToWaistBack (the neck base, at {NECK_BASE_LEVEL} of the stature): {s:.1} cm"));
            Some(s)
        }
        (Some(w), None) => {
            let s = w / WAIST_LEVEL;
            notes.push(format!("stature estimated from waistToFloor (the waist, at {WAIST_LEVEL} of the stature): {s:.1} cm"));
            Some(s)
        }
        _ => None,
    }
}

/// A GarmentCode body (YAML, cm) as drapekit's measurements.
pub fn from_garmentcode(text: &str, path: &Path) -> Result<Imported, FitError> {
    #[derive(serde::Deserialize)]
    struct File {
        body: BTreeMap<String, f64>,
    }
    let yaml_error = |e: yaml_serde::Error| FitError::Key {
        path: path.to_path_buf(),
        key: "body".into(),
        message: match e.location() {
            Some(l) => format!("line {}: {e} ({FORMATS})", l.line()),
            None => format!("{e} ({FORMATS})"),
        },
    };
    yaml_serde::from_str::<Unique>(text).map_err(yaml_error)?;
    let file: File = yaml_serde::from_str(text).map_err(yaml_error)?;
    let b = &file.body;
    if let Some((k, v)) = b.iter().find(|(_, v)| !v.is_finite()) {
        return Err(FitError::Key {
            path: path.to_path_buf(),
            key: format!("body.{k}"),
            message: format!("expected a finite number (cm), found {v}"),
        });
    }
    let get = |k: &str| b.get(k).copied();
    // GarmentCode's levels: the waist and bust lines are measured down from the head's bottom,
    // the hip line down from the waist.
    let below_head = |k: &str| Some(get("height")? - get("head_l")? - get(k)?);
    let waist_height = below_head("waist_line");
    let m = Measurements {
        units: Some("cm".into()),
        stature: b.get("height").copied(),
        waist_height,
        bust_height: below_head("vert_bust_line"),
        hip_height: waist_height.zip(get("hips_line")).map(|(w, d)| w - d),
        bust_girth: b.get("bust").copied(),
        underbust_girth: b.get("underbust").copied(),
        waist_girth: b.get("waist").copied(),
        hip_girth: b.get("hips").copied(),
        shoulder_width: b.get("shoulder_w").copied(),
        ..Measurements::default()
    };
    let mut notes = Vec::new();
    const USED: [&str; 10] = [
        "height",
        "bust",
        "underbust",
        "waist",
        "hips",
        "shoulder_w",
        "head_l",
        "waist_line",
        "vert_bust_line",
        "hips_line",
    ];
    unused(&mut notes, b.keys(), &USED);
    Ok(Imported {
        measurements: m,
        format: "garmentcode",
        notes,
    })
}

/// Adds a note listing the keys not in `used`.
fn unused<'a>(notes: &mut Vec<String>, keys: impl Iterator<Item = &'a String>, used: &[&str]) {
    let left: Vec<&str> = keys
        .map(String::as_str)
        .filter(|k| !used.contains(k))
        .collect();
    if !left.is_empty() {
        notes.push(format!(
            "not used (no ISO 8559-1 level in the shape model): {}",
            left.join(", ")
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn garmentcode_keys_map_to_iso_names() {
        let yaml = "body:\n  height: 171.99\n  bust: 99.8\n  waist: 84.3\n  hips: 103.5\n  \
                    neck_w: 18.9\n  head_l: 26.0\n  waist_line: 37.0\n  hips_line: 23.5\n";
        let got = from_garmentcode(yaml, "b.yaml".as_ref()).unwrap();
        let m = &got.measurements;
        assert_eq!(m.stature, Some(171.99));
        assert_eq!(
            (m.bust_girth, m.waist_girth, m.hip_girth),
            (Some(99.8), Some(84.3), Some(103.5))
        );
        assert_eq!(
            m.top_hip_girth, None,
            "GarmentCode's hips is the full hip girth"
        );
        assert!(got.notes[0].contains("neck_w"), "{:?}", got.notes);
    }

    #[test]
    fn a_garmentcode_key_given_twice_is_refused() {
        // It was read without a word, one of the two values kept.
        let yaml = "body:\n  height: 170\n  waist: 70\n  bust: 90\n  height: 180\n";
        let e = from_garmentcode(yaml, "b.yaml".as_ref())
            .unwrap_err()
            .to_string();
        assert!(e.contains("the key 'height' is given twice"), "{e}");
    }

    #[test]
    fn a_freesewing_key_given_twice_is_refused() {
        // It was read without a word, the last value kept.
        let json = "{\"measurements\": {\"waist\": 700,\n \"waist\": 800}}";
        let e = parse_any(json, "m.json".as_ref()).unwrap_err().to_string();
        assert!(e.starts_with("m.json:2:"), "{e}");
        assert!(e.contains("the key 'waist' is given twice"), "{e}");
    }

    #[test]
    fn freesewing_lengths_become_levels() {
        let json = serde_json::json!({"measurements_mm": {"waist": 750, "hips": 900, "seat": 1010,
            "waistToFloor": 1050, "waistToHips": 125, "waistToSeat": 250, "waistToUnderbust": 80,
            "bustPointToUnderbust": 100, "underbust": 780, "chest": 925, "head": 565}});
        let got = from_freesewing(&json, "m.json".as_ref()).unwrap();
        let m = &got.measurements;
        assert_eq!(
            m.top_hip_girth,
            Some(90.0),
            "FreeSewing's hips is the upper hip"
        );
        assert_eq!(m.hip_girth, Some(101.0));
        assert_eq!((m.top_hip_height, m.hip_height), (Some(92.5), Some(80.0)));
        assert_eq!(
            (m.underbust_height, m.bust_height),
            (Some(113.0), Some(123.0))
        );
        assert!((m.stature.unwrap() - 105.0 / 0.631).abs() < 1e-9);
        assert!(
            got.notes.iter().any(|n| n.contains("head")),
            "{:?}",
            got.notes
        );
    }

    #[test]
    fn a_json_file_without_measurements_says_which_formats_are_read() {
        let json = serde_json::json!({"sections": []});
        let e = from_freesewing(&json, "x.json".as_ref())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("x.json") && e.contains("TOML") && e.contains("FreeSewing"),
            "{e}"
        );
        let bad = serde_json::json!({"measurements": {"waist": "big"}});
        let e = from_freesewing(&bad, "x.json".as_ref())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("measurements.waist") && e.contains("expected a number"),
            "{e}"
        );
    }
}
