//! Section files: JSON and CSV.
//!
//! JSON (keys beyond these are an error that names them):
//! ```json
//! {"units": "m", "sections": [{"height": 0.95, "points": [[0.1, 0.0], [0.0, 0.08], [-0.1, 0.0]]}]}
//! ```
//! `units` is `mm`, `cm`, `m` or `in` (default `m`); z is up; each section is a horizontal closed
//! contour at its height, its points the (x, y) corners in order, the closing point not
//! repeated; an optional `"name"` labels it in the report.
//!
//! CSV: rows `height,x,y` (an optional header row `height,x,y`, `#` comments, blank lines);
//! consecutive rows with the same height make one section. Units come from `--units`.

use super::error::FitError;
use super::section::Section;
use crate::math::Point2;
use crate::mesh::transform::Units;
use serde::Deserialize;
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonFile {
    units: Option<String>,
    sections: Vec<JsonSection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonSection {
    height: f64,
    points: Vec<[f64; 2]>,
    #[serde(default)]
    name: Option<String>,
}

/// Sections read from a file, their units and optional names.
#[derive(Debug, Clone, PartialEq)]
pub struct SectionsFile {
    /// The sections, in file order.
    pub sections: Vec<Section>,
    /// Names given to sections (same order; `None` when not named).
    pub names: Vec<Option<String>>,
    /// Units of the file (JSON), or `None` (CSV).
    pub units: Option<Units>,
}

/// Reads a JSON or CSV sections file (by extension: `.csv` is CSV, anything else JSON).
pub fn read(path: &Path) -> Result<SectionsFile, FitError> {
    let text = std::fs::read_to_string(path).map_err(|source| FitError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path)
}

/// Parses a sections file's `text`, CSV or JSON by `path`'s extension as [`read`] (`path` names
/// it in errors).
pub fn parse(text: &str, path: &Path) -> Result<SectionsFile, FitError> {
    let csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if csv {
        read_csv(path, text)
    } else {
        read_json(path, text)
    }
}

/// A serde_json error's message without the " at line L column C" it ends with (the location
/// goes in front instead).
pub(crate) fn json_message(e: &serde_json::Error) -> String {
    let msg = e.to_string();
    msg.rsplit_once(" at line ")
        .map_or(msg.clone(), |(m, _)| m.to_string())
}

fn read_json(path: &Path, text: &str) -> Result<SectionsFile, FitError> {
    let f: JsonFile = serde_json::from_str(text).map_err(|e| FitError::Json {
        path: path.to_path_buf(),
        line: e.line(),
        column: e.column(),
        message: json_message(&e),
    })?;
    let units = match f.units {
        Some(u) => Some(u.parse::<Units>().map_err(|m| FitError::Key {
            path: path.to_path_buf(),
            key: "units".into(),
            message: m,
        })?),
        None => Some(Units::M),
    };
    let names = f.sections.iter().map(|s| s.name.clone()).collect();
    let sections = f
        .sections
        .into_iter()
        .map(|s| Section {
            height: s.height,
            points: s.points.iter().map(|p| Point2::new(p[0], p[1])).collect(),
        })
        .collect();
    Ok(SectionsFile {
        sections,
        names,
        units,
    })
}

fn read_csv(path: &Path, text: &str) -> Result<SectionsFile, FitError> {
    let err = |line: usize, message: String| FitError::Csv {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut sections: Vec<Section> = Vec::new();
    let mut seen_data = false;
    for (i, raw) in text.lines().enumerate() {
        let ln = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if !seen_data && fields.len() == 3 && fields[0].eq_ignore_ascii_case("height") {
            continue;
        }
        if fields.len() != 3 {
            return Err(err(
                ln,
                format!("expected 3 fields height,x,y, found {}", fields.len()),
            ));
        }
        let mut v = [0.0; 3];
        for (k, f) in fields.iter().enumerate() {
            v[k] = f
                .parse::<f64>()
                .map_err(|_| err(ln, format!("'{f}' is not a number")))?;
            if !v[k].is_finite() {
                return Err(err(ln, format!("'{f}' is not a finite number")));
            }
        }
        seen_data = true;
        match sections.last_mut() {
            Some(s) if s.height == v[0] => s.points.push(Point2::new(v[1], v[2])),
            _ => sections.push(Section {
                height: v[0],
                points: vec![Point2::new(v[1], v[2])],
            }),
        }
    }
    let names = vec![None; sections.len()];
    Ok(SectionsFile {
        sections,
        names,
        units: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join(name);
        std::fs::write(&p, text).unwrap();
        (d, p)
    }

    #[test]
    fn json_and_csv_agree() {
        let (_d, j) = write(
            "s.json",
            r#"{"units": "cm", "sections": [{"height": 1, "points": [[0,0],[1,0],[0,1]]}, {"height": 2, "points": [[0,0],[2,0],[0,2]], "name": "top"}]}"#,
        );
        let (_e, c) = write(
            "s.csv",
            "height,x,y\n1,0,0\n1,1,0\n1,0,1\n# next\n2,0,0\n2,2,0\n2,0,2\n",
        );
        let a = read(&j).unwrap();
        let b = read(&c).unwrap();
        assert_eq!(a.sections, b.sections);
        assert_eq!(a.units, Some(Units::Cm));
        assert_eq!(a.names[1].as_deref(), Some("top"));
    }

    #[test]
    fn errors_name_line_and_key() {
        let (_d, j) = write(
            "s.json",
            "{\"units\": \"m\",\n \"sections\": [{\"hieght\": 1, \"points\": []}]}",
        );
        let e = read(&j).unwrap_err().to_string();
        assert!(
            e.contains("s.json:2:") && e.contains("unknown field `hieght`"),
            "{e}"
        );
        let (_d, j) = write("t.json", "{\"units\": \"furlongs\", \"sections\": []}");
        assert!(read(&j)
            .unwrap_err()
            .to_string()
            .ends_with("t.json: key 'units': unknown unit 'furlongs': expected mm, cm, m or in"));
        let (_d, c) = write("s.csv", "1,0,0\n1,x,0\n");
        assert!(read(&c)
            .unwrap_err()
            .to_string()
            .ends_with("s.csv:2: 'x' is not a number"));
        let (_d, c) = write("t.csv", "1,0,0\n1,0\n");
        assert!(read(&c)
            .unwrap_err()
            .to_string()
            .ends_with("t.csv:2: expected 3 fields height,x,y, found 2"));
    }
}
