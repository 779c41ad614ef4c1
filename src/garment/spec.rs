//! Reading and validating a GarmentCode specification JSON file into a [`Pattern`].
//!
//! A relative control point `(u, v)` of an edge from `s` to `e` sits at
//! `s + u d + v perp(d)` with `d = e - s`, `perp(d) = (-d.y, d.x)`; with
//! `curvature_coords: "absolute"` it is already in panel coordinates. Both are stored
//! absolute. A panel point `(x, y)` is placed in 3D at `R (x, y, 0) + t` with
//! `R = Rz Ry Rx` from the panel's Euler angles in degrees, in the file's units
//! (`units_in_meter` per metre; 100 means centimetres).
//!
//! Validation collects every problem before failing, so one run names them all.

use super::curve::{Curve, DENSE_SEGMENTS};
use crate::math::{Point2, Point3, Vec2, Vec3};
use nalgebra::{Rotation3, Vector3};
use serde::Deserialize;
use serde_json::Value;
use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::path::{Path, PathBuf};

/// Segments per curved edge of the polyline the self-crossing test uses.
const CROSSING_SEGMENTS: usize = 32;

/// The longest outline (segments) whose every pair of segments is tested for a crossing, so
/// that each pair of edges crossing is named; beyond it the sweep names one pair.
const PAIRWISE_SEGMENTS: usize = 4096;

/// A whole sewing pattern: panels in a fixed order and the stitches between their edges.
#[derive(Debug, Clone, PartialEq)]
pub struct Pattern {
    /// Panels, in `panel_order` when the file gives one, else sorted by name.
    pub panels: Vec<Panel>,
    /// Stitches, in file order.
    pub stitches: Vec<Stitch>,
    /// Panel units per metre (100: centimetres).
    pub units_in_meter: f64,
    /// Whether the file gives no `units_in_meter` and GarmentCode's default, 100, is assumed.
    pub units_assumed: bool,
}

/// One flat piece of cloth: a closed loop of edges through its vertices, and its 3D placement.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// The panel's name in the file.
    pub name: String,
    /// 2D vertices, panel units.
    pub vertices: Vec<Point2>,
    /// Edges; edge k ends where edge k+1 starts, the last ends where the first starts.
    pub edges: Vec<Edge>,
    /// Translation `t` of the placement.
    pub translation: Vec3,
    /// Euler angles (x, y, z) in degrees of the placement's rotation `R = Rz Ry Rx`.
    pub rotation_deg: [f64; 3],
    /// Each edge's `label` in the file (`lower_interface`: a skirt's or trousers' top, held at
    /// the body's waist while sewing, `waist`), `None` when it has none.
    pub labels: Vec<Option<String>>,
}

/// One edge of a panel: vertex indices and curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    /// Index of the start vertex.
    pub start: usize,
    /// Index of the end vertex.
    pub end: usize,
    /// The curve, control points in panel coordinates.
    pub curve: Curve,
}

/// An edge of a panel, by indices into [`Pattern::panels`] and [`Panel::edges`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EdgeRef {
    /// Panel index.
    pub panel: usize,
    /// Edge index within the panel.
    pub edge: usize,
}

/// A seam joining two edges. Without `right_wrong` the edges run opposite ways (a's start
/// meets b's end); with it, start meets start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stitch {
    /// First edge.
    pub a: EdgeRef,
    /// Second edge.
    pub b: EdgeRef,
    /// The file's third element `"right_wrong"`.
    pub right_wrong: bool,
}

/// Everything that stops a pattern from being read.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// JSON syntax error, or the text ends early.
    #[error("{}:{line}:{column}: {message}", path.display())]
    Json {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    /// Valid JSON of the wrong shape (a missing key, a string where a number belongs).
    #[error("{}:{line}:{column}: {message}", path.display())]
    Shape {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    /// Well-formed but invalid: every problem found.
    #[error("{}: {} problem(s):{}", path.display(), problems.len(), problems.iter().map(|p| format!("\n  {p}")).collect::<String>())]
    Invalid {
        path: PathBuf,
        problems: Vec<Problem>,
    },
}

/// One thing wrong with a well-formed pattern. Panels are named; edges and stitches are
/// 0-based indices as in the file.
#[derive(Debug, Clone, PartialEq)]
pub enum Problem {
    /// `properties.units_in_meter` is not a positive finite number.
    BadUnits { value: f64 },
    /// `properties.curvature_coords` is neither "relative" nor "absolute".
    UnknownCurvatureCoords { value: String },
    /// `panel_order` names a panel that does not exist.
    UnknownPanelInOrder { name: String },
    /// A panel's name holds a control character (a line break would split the line that
    /// names its group in the garment's OBJ, and what follows it would be read as data).
    ControlInName { panel: String },
    /// A panel's name is empty or only white space.
    EmptyName { panel: String },
    /// A number of a panel is NaN or infinite.
    NonFinite { panel: String, what: String },
    /// A rotation angle beyond [`ROTATION_MAX_DEG`] (axis 0: x, 1: y, 2: z).
    RotationTooLarge {
        panel: String,
        axis: usize,
        degrees: f64,
    },
    /// Fewer than 3 edges.
    TooFewEdges { panel: String, count: usize },
    /// An edge names a vertex index past the end of the vertex list.
    VertexOutOfRange {
        panel: String,
        edge: usize,
        vertex: usize,
        count: usize,
    },
    /// Edge `edge` ends at vertex `end` but edge `next` starts at vertex `next_start`.
    BrokenLoop {
        panel: String,
        edge: usize,
        end: usize,
        next: usize,
        next_start: usize,
    },
    /// Edges `first` and `second` both start at `vertex`: the loop passes it twice.
    VertexTwice {
        panel: String,
        vertex: usize,
        first: usize,
        second: usize,
    },
    /// An unknown `curvature.type`.
    UnknownCurvature {
        panel: String,
        edge: usize,
        kind: String,
    },
    /// `curvature.params` of the wrong shape for its type.
    BadCurvatureParams {
        panel: String,
        edge: usize,
        message: String,
    },
    /// A circular arc whose radius is below half its chord.
    ArcTooSmall {
        panel: String,
        edge: usize,
        radius: f64,
        half_chord: f64,
    },
    /// An edge of zero length: both ends the same vertex, or at the same point.
    ZeroLength { panel: String, edge: usize },
    /// The sampled outline crosses itself between these two edges (`edge_a <= edge_b`).
    SelfCrossing {
        panel: String,
        edge_a: usize,
        edge_b: usize,
    },
    /// A stitch is not two edge references plus an optional "right_wrong".
    MalformedStitch { stitch: usize, message: String },
    /// A stitch names a panel that does not exist.
    MissingPanel { stitch: usize, panel: String },
    /// A stitch names an edge index the panel does not have.
    MissingEdge {
        stitch: usize,
        panel: String,
        edge: usize,
        count: usize,
    },
    /// A stitch joins an edge to itself.
    StitchToItself {
        stitch: usize,
        panel: String,
        edge: usize,
    },
    /// An edge appears in two stitches.
    EdgeInTwoStitches {
        panel: String,
        edge: usize,
        first: usize,
        second: usize,
    },
    /// The pattern has no panels.
    NoPanels,
    /// A panel's size (the larger of its vertices' box diagonal and its longest edge, curves
    /// included), in metres, outside [`PANEL_SIZE`].
    PanelSize { panel: String, metres: f64 },
    /// A panel whose outline encloses less than [`PANEL_AREA_MIN`], m^2.
    NoArea { panel: String, square_metres: f64 },
    /// A panel placed (its translation, or a vertex) farther than [`PANEL_REACH`] from the
    /// pattern's origin, in metres.
    PanelFar {
        panel: String,
        what: String,
        metres: f64,
    },
}

/// The sizes a garment panel may have, m: from a 1 mm tab to a 100 m awning. Beyond them
/// the units or the coordinates are wrong (a pattern in metres read as centimetres is 100
/// times too small, not this), and sampling its outline would not fit in memory.
pub const PANEL_SIZE: [f64; 2] = [1e-3, 100.0];

/// The least area a garment panel encloses, m^2: a tenth of the square of the least size (a
/// square of the least size across, corner to corner, encloses half of that square).
pub const PANEL_AREA_MIN: f64 = 0.1 * PANEL_SIZE[0] * PANEL_SIZE[0];

/// The largest rotation angle a panel may give, degrees: a thousand turns. An angle counts
/// modulo 360, and a file's angles are within a turn or two; at 3.6e5 one unit in the last
/// place is 6e-11 degrees (1e-12 rad: below a nanometre on a panel of the largest
/// [`PANEL_SIZE`]), while at 1e300 it is 1e284 degrees, and the angle used is whatever the
/// rounding of `1e300 mod 360` makes it: a number that has lost its meaning.
pub const ROTATION_MAX_DEG: f64 = 3.6e5;

/// How far from the pattern's origin a panel's translation or vertex may be, m. A garment
/// is placed round a body at the origin; a panel a kilometre away is a wrong translation,
/// and at 1e200 m its particles' positions would lose every digit of the cloth's spacing.
pub const PANEL_REACH: f64 = 1e3;

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use Problem::*;
        match self {
            BadUnits { value } => write!(f, "properties.units_in_meter is {value}; it must be a positive number"),
            UnknownCurvatureCoords { value } => {
                write!(f, "properties.curvature_coords is '{value}'; expected 'relative' or 'absolute'")
            }
            UnknownPanelInOrder { name } => write!(f, "panel_order names panel '{name}', which does not exist"),
            ControlInName { panel } => write!(
                f,
                "panel {panel:?}: its name holds a control character (a line break, a tab, a NUL); the garment's OBJ names each panel's group on one line"
            ),
            EmptyName { panel } => write!(
                f,
                "panel {panel:?}: its name is empty (or only white space); each panel needs a name: stitches, the garment's OBJ groups and the report name panels by it"
            ),
            NonFinite { panel, what } => write!(f, "panel '{panel}': {what} is not a finite number"),
            RotationTooLarge { panel, axis, degrees } => write!(
                f,
                "panel '{panel}': rotation[{axis}] (about {}) is {degrees:e} degrees; a panel's angle is within {ROTATION_MAX_DEG:e} degrees (a thousand turns) either way: beyond that its last digit is worth more than a millionth of a degree, and at 1e300 it is no angle at all",
                ["x", "y", "z"][*axis]
            ),
            TooFewEdges { panel, count } => {
                write!(f, "panel '{panel}' has {count} edge(s); a panel needs at least 3")
            }
            VertexOutOfRange {
                panel,
                edge,
                vertex,
                count,
            } => write!(f, "panel '{panel}' edge {edge} names vertex {vertex}, but the panel has {count} vertices"),
            BrokenLoop {
                panel,
                edge,
                end,
                next,
                next_start,
            } => write!(
                f,
                "panel '{panel}': edge {edge} ends at vertex {end} but the next edge {next} starts at vertex {next_start}; the edges must form one closed loop in order"
            ),
            VertexTwice {
                panel,
                vertex,
                first,
                second,
            } => write!(
                f,
                "panel '{panel}': edges {first} and {second} both start at vertex {vertex}; the edges must go once round the outline, each vertex starting one edge"
            ),
            UnknownCurvature { panel, edge, kind } => {
                write!(f, "panel '{panel}' edge {edge}: unknown curvature type '{kind}'")
            }
            BadCurvatureParams { panel, edge, message } => {
                write!(f, "panel '{panel}' edge {edge}: curvature params: {message}")
            }
            ArcTooSmall {
                panel,
                edge,
                radius,
                half_chord,
            } => write!(
                f,
                "panel '{panel}' edge {edge}: arc radius {radius} is smaller than half its chord ({half_chord}), so no circle passes through both ends"
            ),
            ZeroLength { panel, edge } => {
                write!(f, "panel '{panel}' edge {edge} has zero length: its ends coincide")
            }
            SelfCrossing { panel, edge_a, edge_b } => {
                write!(f, "panel '{panel}': the outline crosses itself between edges {edge_a} and {edge_b}")
            }
            MalformedStitch { stitch, message } => write!(f, "stitch {stitch}: {message}"),
            MissingPanel { stitch, panel } => write!(f, "stitch {stitch} names panel '{panel}', which does not exist"),
            MissingEdge {
                stitch,
                panel,
                edge,
                count,
            } => write!(f, "stitch {stitch} names edge {edge} of panel '{panel}', which has {count} edge(s)"),
            StitchToItself { stitch, panel, edge } => {
                write!(f, "stitch {stitch} joins edge {edge} of panel '{panel}' to itself")
            }
            EdgeInTwoStitches {
                panel,
                edge,
                first,
                second,
            } => write!(f, "panel '{panel}' edge {edge} is in two stitches, {first} and {second}; an edge may be in one"),
            NoPanels => write!(f, "pattern.panels is empty; a garment needs at least one panel"),
            PanelSize { panel, metres } => write!(
                f,
                "panel '{panel}' is {} m across (its vertices' box or its longest edge, curves included, in metres by units_in_meter); a garment panel is {} m to {} m: check units_in_meter and the coordinates",
                crate::math::short(*metres),
                PANEL_SIZE[0],
                PANEL_SIZE[1]
            ),
            NoArea { panel, square_metres } => write!(
                f,
                "panel '{panel}' encloses {} m^2 (its outline's area, in metres by units_in_meter); a garment panel encloses at least {PANEL_AREA_MIN} m^2: are its vertices on a line?",
                crate::math::short(*square_metres)
            ),
            PanelFar { panel, what, metres } => write!(
                f,
                "panel '{panel}' {what} is {} m from the origin (in metres by units_in_meter); a garment panel is placed within {PANEL_REACH} m of the body: check the translation and units_in_meter",
                crate::math::short(*metres),
            ),
        }
    }
}

// ---- File shape ------------------------------------------------------------------------

#[derive(Deserialize)]
struct RawSpec {
    pattern: RawPattern,
    #[serde(default)]
    properties: RawProperties,
}

#[derive(Deserialize)]
struct RawPattern {
    #[serde(deserialize_with = "unique_panels")]
    panels: BTreeMap<String, RawPanel>,
    #[serde(default)]
    stitches: Vec<Vec<RawStitchPart>>,
    #[serde(default)]
    panel_order: Option<Vec<String>>,
}

#[derive(Deserialize)]
#[serde(default)]
struct RawProperties {
    curvature_coords: String,
    /// `None` when the file does not give it: GarmentCode's default [`DEFAULT_UNITS`].
    units_in_meter: Option<f64>,
}

/// The `units_in_meter` GarmentCode assumes when a file gives none: centimetres.
pub const DEFAULT_UNITS: f64 = 100.0;

impl Default for RawProperties {
    fn default() -> Self {
        RawProperties {
            curvature_coords: "relative".into(),
            units_in_meter: None,
        }
    }
}

#[derive(Deserialize)]
struct RawPanel {
    #[serde(deserialize_with = "vertices")]
    vertices: Vec<[f64; 2]>,
    edges: Vec<RawEdge>,
    #[serde(default, deserialize_with = "exact")]
    translation: [f64; 3],
    #[serde(default, deserialize_with = "exact")]
    rotation: [f64; 3],
}

#[derive(Deserialize)]
struct RawEdge {
    #[serde(deserialize_with = "exact")]
    endpoints: [usize; 2],
    #[serde(default, deserialize_with = "unique_optional")]
    curvature: Option<Value>,
    #[serde(default)]
    label: Option<String>,
}

enum RawStitchPart {
    End { panel: String, edge: usize },
    Flag(String),
}

/// A list of exactly `N` items, refused with how many it has (serde's own error for a longer
/// list is "trailing characters").
fn exact<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    let items: Vec<T> = Vec::deserialize(d)?;
    let n = items.len();
    let m = format!("expected a list of {N} numbers here, got {n}");
    items.try_into().map_err(|_| serde::de::Error::custom(m))
}

/// A panel's `vertices`, each `[x, y]`, refused by the first that is not, with its index.
fn vertices<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<[f64; 2]>, D::Error> {
    let raw: Vec<Vec<f64>> = Vec::deserialize(d)?;
    (raw.into_iter().enumerate())
        .map(|(i, v)| {
            let n = v.len();
            let m = format!("vertex {i} has {n} coordinate(s); a panel's vertex is [x, y] (2D)");
            <[f64; 2]>::try_from(v).map_err(|_| serde::de::Error::custom(m))
        })
        .collect()
}

/// `pattern.panels`, refusing a name given twice (a JSON object would keep the last panel of
/// that name and silently drop the others).
fn unique_panels<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<BTreeMap<String, RawPanel>, D::Error> {
    struct Panels;
    impl<'de> serde::de::Visitor<'de> for Panels {
        type Value = BTreeMap<String, RawPanel>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("an object of panels by name")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut map: A,
        ) -> Result<Self::Value, A::Error> {
            let mut out = BTreeMap::new();
            while let Some(name) = map.next_key::<String>()? {
                if out.contains_key(&name) {
                    let m = format!("panel '{name}' is given twice in pattern.panels; each panel needs a name of its own");
                    return Err(serde::de::Error::custom(m));
                }
                let panel = map.next_value()?;
                out.insert(name, panel);
            }
            Ok(out)
        }
    }
    d.deserialize_map(Panels)
}

/// A JSON value whose objects give each key once: serde_json's `Value` keeps the last of
/// two and drops the other without a word (`{"type": "circle", "type": "cubic"}` was a
/// cubic). The structs' own keys are refused twice by serde; these are the values read as
/// `Value` (a curvature, a stitch element).
struct UniqueValue(Value);

impl<'de> Deserialize<'de> for UniqueValue {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(UniqueVisitor).map(UniqueValue)
    }
}

struct UniqueVisitor;

impl<'de> serde::de::Visitor<'de> for UniqueVisitor {
    type Value = Value;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        Ok(serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number))
    }
    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.into()))
    }
    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_some<D: serde::Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        UniqueValue::deserialize(d).map(|v| v.0)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut out = Vec::new();
        while let Some(UniqueValue(v)) = seq.next_element()? {
            out.push(v);
        }
        Ok(Value::Array(out))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut out = serde_json::Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                let m = format!("key '{key}' is given twice in this object; JSON would keep the last and drop the other, so each key may be given once");
                return Err(serde::de::Error::custom(m));
            }
            let UniqueValue(v) = map.next_value()?;
            out.insert(key, v);
        }
        Ok(Value::Object(out))
    }
}

/// An optional value read as [`UniqueValue`]; `null` is none, as serde reads an `Option`.
fn unique_optional<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Value>, D::Error> {
    Ok(Some(UniqueValue::deserialize(d)?.0).filter(|v| !v.is_null()))
}

/// A stitch element: `{"panel": NAME, "edge": INDEX}` or a flag such as `"right_wrong"`, with
/// an error that says so (not serde's "did not match any variant").
impl<'de> Deserialize<'de> for RawStitchPart {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let UniqueValue(v) = UniqueValue::deserialize(d)?;
        if let Some(flag) = v.as_str() {
            return Ok(RawStitchPart::Flag(flag.into()));
        }
        let panel = v.get("panel").and_then(Value::as_str);
        let edge = (v.get("edge").and_then(Value::as_u64)).and_then(|e| usize::try_from(e).ok());
        match (panel, edge) {
            (Some(panel), Some(edge)) => Ok(RawStitchPart::End {
                panel: panel.into(),
                edge,
            }),
            _ => {
                let mut text = v.to_string();
                if text.chars().count() > 60 {
                    text = text.chars().take(57).chain("...".chars()).collect();
                }
                Err(serde::de::Error::custom(format!(
                    "a stitch element is {{\"panel\": NAME, \"edge\": INDEX}} (an edge index from 0) or \"right_wrong\", not {text}"
                )))
            }
        }
    }
}

/// A curvature as written: control points still in the file's coordinates.
enum RawCurve {
    Quadratic([f64; 2]),
    Cubic([f64; 2], [f64; 2]),
    Circle {
        radius: f64,
        large: bool,
        right: bool,
    },
}

// ---- Reading ---------------------------------------------------------------------------

/// Reads and validates the pattern in `path`.
pub fn read(path: &Path) -> Result<Pattern, SpecError> {
    let text = std::fs::read_to_string(path).map_err(|source| SpecError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path)
}

/// Parses and validates pattern JSON `text`; `path` only names it in errors.
pub fn parse(text: &str, path: &Path) -> Result<Pattern, SpecError> {
    let raw: RawSpec = serde_json::from_str(text).map_err(|e| json_error(e, path))?;
    let mut problems = Vec::new();
    let pattern = build(raw, &mut problems);
    if problems.is_empty() {
        Ok(pattern)
    } else {
        Err(SpecError::Invalid {
            path: path.to_path_buf(),
            problems,
        })
    }
}

fn json_error(e: serde_json::Error, path: &Path) -> SpecError {
    let (path, line, column) = (path.to_path_buf(), e.line(), e.column());
    // serde's text ends with its place, which the error already leads with (`p.json:8:82:`).
    let text = e.to_string();
    let place = format!(" at line {line} column {column}");
    let message = text.strip_suffix(&place).unwrap_or(&text).to_string();
    match e.classify() {
        serde_json::error::Category::Data => SpecError::Shape {
            path,
            line,
            column,
            message,
        },
        _ => SpecError::Json {
            path,
            line,
            column,
            message,
        },
    }
}

fn build(raw: RawSpec, problems: &mut Vec<Problem>) -> Pattern {
    let units_assumed = raw.properties.units_in_meter.is_none();
    let units = raw.properties.units_in_meter.unwrap_or(DEFAULT_UNITS);
    if !(units.is_finite() && units > 0.0) {
        problems.push(Problem::BadUnits { value: units });
    }
    let relative = match raw.properties.curvature_coords.as_str() {
        "relative" => true,
        "absolute" => false,
        other => {
            problems.push(Problem::UnknownCurvatureCoords {
                value: other.into(),
            });
            true
        }
    };
    let order = panel_order(&raw.pattern, problems);
    for name in order.iter().filter(|n| n.trim().is_empty()) {
        problems.push(Problem::EmptyName {
            panel: name.clone(),
        });
    }
    for name in order.iter().filter(|n| n.chars().any(char::is_control)) {
        problems.push(Problem::ControlInName {
            panel: name.clone(),
        });
    }
    let mut by_name = raw.pattern.panels;
    let panels: Vec<Panel> = order
        .iter()
        .filter_map(|name| {
            by_name
                .remove(name)
                .map(|p| build_panel(name, p, relative, units, problems))
        })
        .collect();
    if panels.is_empty() {
        problems.push(Problem::NoPanels);
    }
    let stitches = build_stitches(&raw.pattern.stitches, &panels, problems);
    Pattern {
        panels,
        stitches,
        units_in_meter: units,
        units_assumed,
    }
}

/// `panel_order` (unknown names reported, duplicates dropped) then any unlisted panels by name.
fn panel_order(raw: &RawPattern, problems: &mut Vec<Problem>) -> Vec<String> {
    let mut order: Vec<String> = Vec::new();
    for name in raw.panel_order.iter().flatten() {
        if !raw.panels.contains_key(name) {
            problems.push(Problem::UnknownPanelInOrder { name: name.clone() });
        } else if !order.contains(name) {
            order.push(name.clone());
        }
    }
    let rest: Vec<String> = raw
        .panels
        .keys()
        .filter(|n| !order.contains(n))
        .cloned()
        .collect();
    order.extend(rest);
    order
}

fn build_panel(
    name: &str,
    raw: RawPanel,
    relative: bool,
    units: f64,
    problems: &mut Vec<Problem>,
) -> Panel {
    let before = problems.len();
    let vertices: Vec<Point2> = raw
        .vertices
        .iter()
        .map(|v| Point2::new(v[0], v[1]))
        .collect();
    check_finite(name, &raw, problems);
    let edges: Vec<Edge> = raw
        .edges
        .iter()
        .enumerate()
        .map(|(k, e)| build_edge(name, k, e, &vertices, relative, problems))
        .collect();
    check_loop(name, &edges, problems);
    let panel = Panel {
        name: name.to_string(),
        vertices,
        edges,
        translation: Vec3::from(raw.translation),
        rotation_deg: raw.rotation,
        labels: raw.edges.iter().map(|e| e.label.clone()).collect(),
    };
    if problems.len() == before {
        check_arcs(&panel, problems);
        check_lengths(&panel, problems);
    }
    if problems.len() == before && units.is_finite() && units > 0.0 {
        check_size(&panel, units, problems);
    }
    if problems.len() == before && units.is_finite() && units > 0.0 {
        check_reach(&panel, units, problems);
    }
    if problems.len() == before {
        check_self_crossing(&panel, problems);
    }
    if problems.len() == before && units.is_finite() && units > 0.0 {
        check_area(&panel, units, problems);
    }
    panel
}

/// A panel whose outline encloses less than [`PANEL_AREA_MIN`]: its vertices (nearly) on a
/// line, a sliver no cloth can be made of (the solver's smallest triangles would be too light
/// for its stiffest springs).
fn check_area(panel: &Panel, units: f64, problems: &mut Vec<Problem>) {
    let square_metres = (panel.signed_area() / units / units).abs();
    if square_metres.is_nan() || square_metres < PANEL_AREA_MIN {
        problems.push(Problem::NoArea {
            panel: panel.name.clone(),
            square_metres,
        });
    }
}

/// A panel whose size in metres is outside [`PANEL_SIZE`] (before anything samples it).
fn check_size(panel: &Panel, units: f64, problems: &mut Vec<Problem>) {
    let (lo, hi) = panel.vertices.iter().fold(
        (
            Point2::new(f64::MAX, f64::MAX),
            Point2::new(f64::MIN, f64::MIN),
        ),
        |(lo, hi), v| (lo.inf(v), hi.sup(v)),
    );
    let mut size = (hi - lo).norm();
    for edge in &panel.edges {
        let length = edge.length(&panel.vertices);
        size = if length.is_finite() {
            size.max(length)
        } else {
            f64::INFINITY
        };
    }
    let metres = size / units;
    if !(PANEL_SIZE[0]..=PANEL_SIZE[1]).contains(&metres) {
        problems.push(Problem::PanelSize {
            panel: panel.name.clone(),
            metres,
        });
    }
}

/// A panel whose translation or a vertex is farther than [`PANEL_REACH`] from the origin.
fn check_reach(panel: &Panel, units: f64, problems: &mut Vec<Problem>) {
    let mut far = |what: String, length: f64| {
        let metres = length / units;
        if metres > PANEL_REACH {
            problems.push(Problem::PanelFar {
                panel: panel.name.clone(),
                what,
                metres,
            });
        }
    };
    far("translation".into(), length(panel.translation.as_slice()));
    let farthest = (panel.vertices.iter().map(|v| length(v.coords.as_slice())))
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1));
    if let Some((k, d)) = farthest {
        far(format!("vertex {k}"), d);
    }
}

/// The Euclidean length of `c`, scaled so that 1e200 does not overflow when squared.
fn length(c: &[f64]) -> f64 {
    let s = c.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if s == 0.0 {
        return 0.0;
    }
    s * c.iter().map(|x| (x / s).powi(2)).sum::<f64>().sqrt()
}

fn check_finite(name: &str, raw: &RawPanel, problems: &mut Vec<Problem>) {
    let mut report = |what: String| {
        problems.push(Problem::NonFinite {
            panel: name.into(),
            what,
        })
    };
    for (i, v) in raw.vertices.iter().enumerate() {
        if !v.iter().all(|x| x.is_finite()) {
            report(format!("vertex {i}"));
        }
    }
    if !raw.translation.iter().all(|x| x.is_finite()) {
        report("translation".into());
    }
    if !raw.rotation.iter().all(|x| x.is_finite()) {
        report("rotation".into());
    }
    for (axis, &degrees) in raw.rotation.iter().enumerate() {
        if degrees.is_finite() && degrees.abs() > ROTATION_MAX_DEG {
            problems.push(Problem::RotationTooLarge {
                panel: name.into(),
                axis,
                degrees,
            });
        }
    }
}

fn build_edge(
    name: &str,
    k: usize,
    raw: &RawEdge,
    vertices: &[Point2],
    relative: bool,
    problems: &mut Vec<Problem>,
) -> Edge {
    let [start, end] = raw.endpoints;
    for vertex in [start, end] {
        if vertex >= vertices.len() {
            problems.push(Problem::VertexOutOfRange {
                panel: name.into(),
                edge: k,
                vertex,
                count: vertices.len(),
            });
        }
    }
    let curve = match (&raw.curvature, vertices.get(start), vertices.get(end)) {
        (Some(value), Some(s), Some(e)) => match raw_curve(name, k, value) {
            Ok(rc) => to_curve(rc, s, e, relative),
            Err(p) => {
                problems.push(p);
                Curve::Straight
            }
        },
        _ => Curve::Straight,
    };
    if !curve_is_finite(&curve) {
        problems.push(Problem::NonFinite {
            panel: name.into(),
            what: format!("edge {k} curvature"),
        });
    }
    Edge { start, end, curve }
}

fn curve_is_finite(c: &Curve) -> bool {
    match c {
        Curve::Straight => true,
        Curve::Quadratic(p) => p.iter().all(|x| x.is_finite()),
        Curve::Cubic(p, q) => p.iter().chain(q.iter()).all(|x| x.is_finite()),
        Curve::Arc { radius, .. } => radius.is_finite(),
    }
}

/// Control points to panel coordinates: `s + u d + v perp(d)` when relative.
fn to_curve(rc: RawCurve, s: &Point2, e: &Point2, relative: bool) -> Curve {
    let d = e - s;
    let place = |[u, v]: [f64; 2]| {
        if relative {
            s + d * u + Vec2::new(-d.y, d.x) * v
        } else {
            Point2::new(u, v)
        }
    };
    match rc {
        RawCurve::Quadratic(c) => Curve::Quadratic(place(c)),
        RawCurve::Cubic(c1, c2) => Curve::Cubic(place(c1), place(c2)),
        RawCurve::Circle {
            radius,
            large,
            right,
        } => Curve::Arc {
            radius,
            large_arc: large,
            right,
        },
    }
}

/// Reads a `curvature` value: a bare `[u, v]`, or `{"type": ..., "params": ...}`.
fn raw_curve(panel: &str, edge: usize, value: &Value) -> Result<RawCurve, Problem> {
    let bad = |message: &str| Problem::BadCurvatureParams {
        panel: panel.into(),
        edge,
        message: message.into(),
    };
    if let Some(p) = pair(value) {
        return Ok(RawCurve::Quadratic(p));
    }
    let kind = value
        .get("type")
        .and_then(Value::as_str)
        .ok_or_else(|| bad("expected [u, v] or an object with 'type' and 'params'"))?;
    let params = value
        .get("params")
        .and_then(Value::as_array)
        .ok_or_else(|| bad("'params' must be a list"))?;
    match kind {
        "quadratic" => match params.as_slice() {
            [p] => pair(p).map(RawCurve::Quadratic),
            [_, _] => pair(value.get("params").unwrap_or(&Value::Null)).map(RawCurve::Quadratic),
            _ => None,
        }
        .ok_or_else(|| bad("a quadratic needs [[u, v]]")),
        "cubic" => match params.as_slice() {
            [p, q] => pair(p).zip(pair(q)).map(|(p, q)| RawCurve::Cubic(p, q)),
            _ => None,
        }
        .ok_or_else(|| bad("a cubic needs [[u1, v1], [u2, v2]]")),
        "circle" => match params.as_slice() {
            [r, l, s] => r
                .as_f64()
                .zip(flag(l))
                .zip(flag(s))
                .map(|((radius, large), right)| RawCurve::Circle {
                    radius,
                    large,
                    right,
                }),
            _ => None,
        }
        .ok_or_else(|| bad("a circle needs [radius, large_arc, right]")),
        other => Err(Problem::UnknownCurvature {
            panel: panel.into(),
            edge,
            kind: other.into(),
        }),
    }
}

fn pair(v: &Value) -> Option<[f64; 2]> {
    match v.as_array()?.as_slice() {
        [a, b] => Some([a.as_f64()?, b.as_f64()?]),
        _ => None,
    }
}

/// A 0/1 number or a boolean.
fn flag(v: &Value) -> Option<bool> {
    v.as_bool().or_else(|| v.as_f64().map(|x| x != 0.0))
}

// ---- Panel checks ----------------------------------------------------------------------

fn check_loop(name: &str, edges: &[Edge], problems: &mut Vec<Problem>) {
    let before = problems.len();
    if edges.len() < 3 {
        problems.push(Problem::TooFewEdges {
            panel: name.into(),
            count: edges.len(),
        });
    }
    for (k, e) in edges.iter().enumerate() {
        let next = (k + 1) % edges.len();
        if e.end != edges[next].start {
            problems.push(Problem::BrokenLoop {
                panel: name.into(),
                edge: k,
                end: e.end,
                next,
                next_start: edges[next].start,
            });
        }
    }
    if problems.len() == before {
        check_once_round(name, edges, problems);
    }
}

/// Edges that start at a vertex an earlier edge starts at: the loop passes it twice (goes
/// round the outline twice, or pinches into a figure of eight).
fn check_once_round(name: &str, edges: &[Edge], problems: &mut Vec<Problem>) {
    let mut first_from: HashMap<usize, usize> = HashMap::new();
    for (k, e) in edges.iter().enumerate() {
        if let Some(&first) = first_from.get(&e.start) {
            problems.push(Problem::VertexTwice {
                panel: name.into(),
                vertex: e.start,
                first,
                second: k,
            });
        } else {
            first_from.insert(e.start, k);
        }
    }
}

/// Edges whose ends coincide (relative to the size of the outline's vertices; a vertex no
/// edge uses, however far, does not make every edge a point): a point, not a seam line.
fn check_lengths(panel: &Panel, problems: &mut Vec<Problem>) {
    let scale = (panel.edges.iter())
        .map(|e| panel.vertices[e.start].coords.norm())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    for (k, edge) in panel.edges.iter().enumerate() {
        let (s, e) = panel.endpoints(k);
        if edge.start == edge.end || (e - s).norm() <= 1e-12 * scale {
            problems.push(Problem::ZeroLength {
                panel: panel.name.clone(),
                edge: k,
            });
        }
    }
}

fn check_arcs(panel: &Panel, problems: &mut Vec<Problem>) {
    for (k, edge) in panel.edges.iter().enumerate() {
        if let Curve::Arc { radius, .. } = edge.curve {
            let (s, e) = panel.endpoints(k);
            let half_chord = (e - s).norm() / 2.0;
            if radius < half_chord * (1.0 - 1e-9) {
                problems.push(Problem::ArcTooSmall {
                    panel: panel.name.clone(),
                    edge: k,
                    radius,
                    half_chord,
                });
            }
        }
    }
}

/// Finds the outline's crossings: first by the O(n log n) sweep (`geom::crossing`), which
/// finds one pair of segments that cross or touch, or says there is none; then, when it found
/// one in an outline of at most [`PAIRWISE_SEGMENTS`] segments, by testing every pair (each
/// pair of edges that properly crosses named once). A longer outline is named by the sweep's
/// pair alone: testing every pair of a 1e6-vertex panel would not end.
fn check_self_crossing(panel: &Panel, problems: &mut Vec<Problem>) {
    let (points, owner) = panel.crossing_polyline();
    let Some((i, j)) = sweep_crossing(&points, &owner) else {
        return;
    };
    if points.len() <= PAIRWISE_SEGMENTS {
        pairwise_crossings(panel, &points, &owner, problems);
    } else {
        problems.push(Problem::SelfCrossing {
            panel: panel.name.clone(),
            edge_a: i.min(j),
            edge_b: i.max(j),
        });
    }
}

/// The edges of a pair of segments of the closed outline `points` that cross or touch, found
/// by the sweep after consecutive repeated points are dropped (`owner`: each segment's edge).
fn sweep_crossing(points: &[Point2], owner: &[usize]) -> Option<(usize, usize)> {
    let mut kept: Vec<(Point2, usize)> = Vec::with_capacity(points.len());
    for (p, &o) in points.iter().zip(owner) {
        if kept.last().is_none_or(|q| q.0 != *p) {
            kept.push((*p, o));
        }
    }
    while kept.len() > 1 && kept.first().map(|q| q.0) == kept.last().map(|q| q.0) {
        kept.pop();
    }
    if kept.len() < 3 {
        return Some((0, 0));
    }
    let unique: Vec<Point2> = kept.iter().map(|q| q.0).collect();
    crate::geom::crossing::self_crossing(&unique).map(|(a, b)| (kept[a].1, kept[b].1))
}

/// Tests every pair of segments of the sampled closed outline for a proper crossing (each
/// segment's ends strictly on opposite sides of the other's line); reports each pair of
/// edges once.
fn pairwise_crossings(
    panel: &Panel,
    points: &[Point2],
    owner: &[usize],
    problems: &mut Vec<Problem>,
) {
    let n = points.len();
    let mut seen = Vec::new();
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (a, b, c, d) = (
                &points[i],
                &points[(i + 1) % n],
                &points[j],
                &points[(j + 1) % n],
            );
            if crosses(a, b, c, d) {
                let pair = (owner[i].min(owner[j]), owner[i].max(owner[j]));
                if !seen.contains(&pair) {
                    seen.push(pair);
                    problems.push(Problem::SelfCrossing {
                        panel: panel.name.clone(),
                        edge_a: pair.0,
                        edge_b: pair.1,
                    });
                }
            }
        }
    }
}

fn orient(a: &Point2, b: &Point2, c: &Point2) -> f64 {
    (b - a).perp(&(c - a))
}

fn crosses(a: &Point2, b: &Point2, c: &Point2, d: &Point2) -> bool {
    orient(a, b, c) * orient(a, b, d) < 0.0 && orient(c, d, a) * orient(c, d, b) < 0.0
}

// ---- Geometry --------------------------------------------------------------------------

impl Edge {
    /// The point at parameter `t` of this edge of `panel`'s vertices.
    pub fn point(&self, vertices: &[Point2], t: f64) -> Point2 {
        self.curve
            .point(&vertices[self.start], &vertices[self.end], t)
    }

    /// Arc length of this edge.
    pub fn length(&self, vertices: &[Point2]) -> f64 {
        self.curve
            .length(&vertices[self.start], &vertices[self.end])
    }

    /// Points at equal arc length, see [`Curve::sample`].
    pub fn sample(&self, vertices: &[Point2], spacing: f64) -> Vec<Point2> {
        self.curve
            .sample(&vertices[self.start], &vertices[self.end], spacing)
    }
}

impl Panel {
    /// Start and end points of edge `k`.
    pub fn endpoints(&self, k: usize) -> (Point2, Point2) {
        let e = &self.edges[k];
        (self.vertices[e.start], self.vertices[e.end])
    }

    /// The closed outline: every edge sampled at `spacing` (see [`Curve::sample`]), each
    /// edge's last point dropped as the next edge's first, the first point not repeated.
    pub fn outline(&self, spacing: f64) -> Vec<Point2> {
        self.edges
            .iter()
            .flat_map(|e| {
                let mut pts = e.sample(&self.vertices, spacing);
                pts.pop();
                pts
            })
            .collect()
    }

    /// Signed area (positive: counter-clockwise) by the shoelace formula
    /// `½ Σ (x_i y_{i+1} - x_{i+1} y_i)` over the outline with every curved edge as a
    /// [`DENSE_SEGMENTS`]-segment polyline (exact for straight edges).
    pub fn signed_area(&self) -> f64 {
        let pts: Vec<Point2> = self
            .edges
            .iter()
            .flat_map(|e| {
                let (s, t) = (&self.vertices[e.start], &self.vertices[e.end]);
                let n = if e.curve == Curve::Straight {
                    1
                } else {
                    DENSE_SEGMENTS
                };
                let mut p = e.curve.polyline(s, t, n);
                p.pop();
                p
            })
            .collect();
        let n = pts.len();
        (0..n)
            .map(|i| pts[i].coords.perp(&pts[(i + 1) % n].coords))
            .sum::<f64>()
            / 2.0
    }

    /// The rotation `R = Rz Ry Rx` of the placement.
    pub fn rotation(&self) -> Rotation3<f64> {
        let [x, y, z] = self.rotation_deg.map(f64::to_radians);
        Rotation3::from_axis_angle(&Vector3::z_axis(), z)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), y)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), x)
    }

    /// A panel point placed in 3D: `R (x, y, 0) + t`, in the file's units.
    pub fn place(&self, p: Point2) -> Point3 {
        self.rotation() * Point3::new(p.x, p.y, 0.0) + self.translation
    }

    /// The closed outline for the self-crossing test, and the edge each segment belongs to.
    fn crossing_polyline(&self) -> (Vec<Point2>, Vec<usize>) {
        let mut points = Vec::new();
        let mut owner = Vec::new();
        for (k, e) in self.edges.iter().enumerate() {
            let (s, t) = self.endpoints(k);
            let n = if e.curve == Curve::Straight {
                1
            } else {
                CROSSING_SEGMENTS
            };
            let mut p = e.curve.polyline(&s, &t, n);
            p.pop();
            owner.extend(std::iter::repeat_n(k, p.len()));
            points.extend(p);
        }
        (points, owner)
    }
}

impl Pattern {
    /// Index of the panel called `name`.
    pub fn panel_index(&self, name: &str) -> Option<usize> {
        self.panels.iter().position(|p| p.name == name)
    }
}

// ---- Stitches --------------------------------------------------------------------------

fn build_stitches(
    raw: &[Vec<RawStitchPart>],
    panels: &[Panel],
    problems: &mut Vec<Problem>,
) -> Vec<Stitch> {
    let index: HashMap<&str, usize> = panels
        .iter()
        .enumerate()
        .map(|(i, p)| (p.name.as_str(), i))
        .collect();
    let mut stitches = Vec::new();
    let mut used: HashMap<EdgeRef, usize> = HashMap::new();
    for (i, parts) in raw.iter().enumerate() {
        let Some((ends, right_wrong)) = stitch_parts(i, parts, problems) else {
            continue;
        };
        let a = resolve(i, ends[0], &index, panels, problems);
        let b = resolve(i, ends[1], &index, panels, problems);
        for r in [a, b].into_iter().flatten() {
            note_use(i, r, &mut used, panels, problems);
        }
        if let (Some(a), Some(b)) = (a, b) {
            if a == b {
                problems.push(Problem::StitchToItself {
                    stitch: i,
                    panel: panels[a.panel].name.clone(),
                    edge: a.edge,
                });
            }
            stitches.push(Stitch { a, b, right_wrong });
        }
    }
    stitches
}

/// The two edge ends and the `right_wrong` flag of stitch `i`.
fn stitch_parts<'a>(
    i: usize,
    parts: &'a [RawStitchPart],
    problems: &mut Vec<Problem>,
) -> Option<([(&'a str, usize); 2], bool)> {
    let mut ends = Vec::new();
    let mut right_wrong = false;
    for part in parts {
        match part {
            RawStitchPart::End { panel, edge } => ends.push((panel.as_str(), *edge)),
            RawStitchPart::Flag(f) if f == "right_wrong" && right_wrong => {
                problems.push(Problem::MalformedStitch {
                    stitch: i,
                    message: "\"right_wrong\" is given twice; it may be given once".into(),
                });
                return None;
            }
            RawStitchPart::Flag(f) if f == "right_wrong" => right_wrong = true,
            RawStitchPart::Flag(f) => {
                problems.push(Problem::MalformedStitch {
                    stitch: i,
                    message: format!(
                        "unknown element '{f}'; only \"right_wrong\" may follow the two edges"
                    ),
                });
                return None;
            }
        }
    }
    match ends.as_slice() {
        [a, b] => Some(([*a, *b], right_wrong)),
        _ => {
            problems.push(Problem::MalformedStitch {
                stitch: i,
                message: format!("{} edge reference(s); a stitch joins exactly 2", ends.len()),
            });
            None
        }
    }
}

fn resolve(
    i: usize,
    (name, edge): (&str, usize),
    index: &HashMap<&str, usize>,
    panels: &[Panel],
    problems: &mut Vec<Problem>,
) -> Option<EdgeRef> {
    let Some(&panel) = index.get(name) else {
        problems.push(Problem::MissingPanel {
            stitch: i,
            panel: name.into(),
        });
        return None;
    };
    let count = panels[panel].edges.len();
    if edge >= count {
        problems.push(Problem::MissingEdge {
            stitch: i,
            panel: name.into(),
            edge,
            count,
        });
        return None;
    }
    Some(EdgeRef { panel, edge })
}

/// Records that stitch `i` uses `r`; reports it when another stitch already does.
fn note_use(
    i: usize,
    r: EdgeRef,
    used: &mut HashMap<EdgeRef, usize>,
    panels: &[Panel],
    problems: &mut Vec<Problem>,
) {
    match used.get(&r) {
        Some(&first) if first != i => problems.push(Problem::EdgeInTwoStitches {
            panel: panels[r.panel].name.clone(),
            edge: r.edge,
            first,
            second: i,
        }),
        Some(_) => {}
        None => {
            used.insert(r, i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE_EDGES: &str = r#"[{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]"#;
    const SQUARE_VERTICES: &str = "[[0, 0], [10, 0], [10, 10], [0, 10]]";

    fn panel_json(vertices: &str, edges: &str) -> String {
        format!(
            r#"{{"vertices": {vertices}, "edges": {edges}, "translation": [1, 2, 3], "rotation": [0, 0, 0]}}"#
        )
    }

    fn square() -> String {
        panel_json(SQUARE_VERTICES, SQUARE_EDGES)
    }

    /// A file with these `"name": panel` entries, stitches and extra pattern keys.
    fn file(panels: &[(&str, String)], stitches: &str, extra: &str) -> String {
        let panels: Vec<String> = panels
            .iter()
            .map(|(n, p)| format!("\"{n}\": {p}"))
            .collect();
        format!(
            r#"{{"pattern": {{"panels": {{{}}}, "stitches": {stitches}{extra}}},
 "parameters": {{}}, "parameter_order": [],
 "properties": {{"curvature_coords": "relative", "units_in_meter": 100}}}}"#,
            panels.join(", ")
        )
    }

    fn problems(text: &str) -> Vec<Problem> {
        match parse(text, Path::new("test.json")) {
            Err(SpecError::Invalid { problems, .. }) => problems,
            other => panic!("expected invalid, got {other:?}"),
        }
    }

    #[test]
    fn a_valid_pattern_reads_with_absolute_control_points_and_placement() {
        let edges = r#"[{"endpoints": [0, 1], "curvature": {"type": "quadratic", "params": [[0.5, -0.2]]}},
            {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]"#;
        let text = file(
            &[("b", panel_json(SQUARE_VERTICES, edges)), ("a", square())],
            r#"[[{"panel": "a", "edge": 1}, {"panel": "b", "edge": 3}, "right_wrong"]]"#,
            "",
        );
        let p = parse(&text, Path::new("t.json")).unwrap();
        assert_eq!(
            p.panels.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(),
            ["a", "b"]
        );
        assert_eq!(p.units_in_meter, 100.0);
        assert_eq!(
            p.stitches,
            [Stitch {
                a: EdgeRef { panel: 0, edge: 1 },
                b: EdgeRef { panel: 1, edge: 3 },
                right_wrong: true
            }]
        );
        // s + 0.5 d - 0.2 perp(d) with s = (0,0), d = (10,0), perp(d) = (0,10).
        assert_eq!(
            p.panels[1].edges[0].curve,
            Curve::Quadratic(Point2::new(5.0, -2.0))
        );
        assert!((p.panels[0].signed_area() - 100.0).abs() < 1e-12);
        assert_eq!(
            p.panels[0].place(Point2::new(1.0, 1.0)),
            Point3::new(2.0, 3.0, 3.0)
        );
        assert_eq!(p.panels[0].outline(2.5).len(), 16);
    }

    #[test]
    fn placement_rotates_z_after_y_after_x() {
        let mut panel = Panel {
            name: "p".into(),
            vertices: vec![],
            edges: vec![],
            translation: Vec3::new(0.0, 0.0, 10.0),
            rotation_deg: [0.0, 90.0, 0.0],
            labels: vec![],
        };
        // About y by 90°: (1, 0, 0) -> (0, 0, -1).
        assert!((panel.place(Point2::new(1.0, 0.0)) - Point3::new(0.0, 0.0, 9.0)).norm() < 1e-12);
        // Rx(90) first takes (0,1,0) to (0,0,1); then Rz(90) leaves it.
        panel.rotation_deg = [90.0, 0.0, 90.0];
        panel.translation = Vec3::zeros();
        assert!((panel.place(Point2::new(0.0, 1.0)) - Point3::new(0.0, 0.0, 1.0)).norm() < 1e-12);
        // (1,0,0): Rx leaves it, Rz(90) takes it to (0,1,0).
        assert!((panel.place(Point2::new(1.0, 0.0)) - Point3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn panel_order_is_used_when_given() {
        let text = file(
            &[("a", square()), ("b", square())],
            "[]",
            r#", "panel_order": ["b", "a"]"#,
        );
        let p = parse(&text, Path::new("t.json")).unwrap();
        assert_eq!(p.panel_index("b"), Some(0));
        assert_eq!(p.panel_index("a"), Some(1));
    }

    #[test]
    fn absolute_coordinates_and_bare_quadratics_are_read() {
        let edges = r#"[{"endpoints": [0, 1], "curvature": [5, -3]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]"#;
        let text = file(&[("a", panel_json(SQUARE_VERTICES, edges))], "[]", "")
            .replace("\"relative\"", "\"absolute\"");
        let p = parse(&text, Path::new("t.json")).unwrap();
        assert_eq!(
            p.panels[0].edges[0].curve,
            Curve::Quadratic(Point2::new(5.0, -3.0))
        );
    }

    #[test]
    fn a_broken_loop_and_a_bad_vertex_are_reported_together() {
        let broken = r#"[{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [2, 0]}]"#;
        let out_of_range =
            r#"[{"endpoints": [0, 1]}, {"endpoints": [1, 7]}, {"endpoints": [7, 0]}]"#;
        let text = file(
            &[
                ("a", panel_json(SQUARE_VERTICES, broken)),
                ("b", panel_json(SQUARE_VERTICES, out_of_range)),
            ],
            "[]",
            "",
        );
        let found = problems(&text);
        assert_eq!(
            found,
            [
                Problem::BrokenLoop {
                    panel: "a".into(),
                    edge: 2,
                    end: 3,
                    next: 3,
                    next_start: 2
                },
                Problem::VertexOutOfRange {
                    panel: "b".into(),
                    edge: 1,
                    vertex: 7,
                    count: 4
                },
                Problem::VertexOutOfRange {
                    panel: "b".into(),
                    edge: 2,
                    vertex: 7,
                    count: 4
                },
            ]
        );
        assert!(found[0]
            .to_string()
            .contains("edge 2 ends at vertex 3 but the next edge 3 starts at vertex 2"));
    }

    #[test]
    fn stitch_problems_are_all_reported() {
        let stitches = r#"[
            [{"panel": "a", "edge": 1}, {"panel": "b", "edge": 3}],
            [{"panel": "b", "edge": 3}, {"panel": "a", "edge": 2}],
            [{"panel": "a", "edge": 0}, {"panel": "zz", "edge": 0}],
            [{"panel": "a", "edge": 9}, {"panel": "b", "edge": 0}],
            [{"panel": "b", "edge": 1}, {"panel": "b", "edge": 1}]
        ]"#;
        let text = file(&[("a", square()), ("b", square())], stitches, "");
        let found = problems(&text);
        assert_eq!(
            found,
            [
                Problem::EdgeInTwoStitches {
                    panel: "b".into(),
                    edge: 3,
                    first: 0,
                    second: 1
                },
                Problem::MissingPanel {
                    stitch: 2,
                    panel: "zz".into()
                },
                Problem::MissingEdge {
                    stitch: 3,
                    panel: "a".into(),
                    edge: 9,
                    count: 4
                },
                Problem::StitchToItself {
                    stitch: 4,
                    panel: "b".into(),
                    edge: 1
                },
            ]
        );
        let err = parse(&text, Path::new("t.json")).unwrap_err().to_string();
        assert!(err.starts_with("t.json: 4 problem(s):"), "{err}");
        assert!(
            err.contains("panel 'b' edge 3 is in two stitches, 0 and 1"),
            "{err}"
        );
    }

    #[test]
    fn a_self_crossing_outline_and_a_too_small_arc_are_reported() {
        let bowtie = panel_json("[[0, 0], [2, 2], [2, 0], [0, 2]]", SQUARE_EDGES);
        let arc_edges = r#"[{"endpoints": [0, 1], "curvature": {"type": "circle", "params": [4, 0, 1]}}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]"#;
        let text = file(
            &[
                ("bow", bowtie),
                ("round", panel_json(SQUARE_VERTICES, arc_edges)),
            ],
            "[]",
            "",
        );
        assert_eq!(
            problems(&text),
            [
                Problem::SelfCrossing {
                    panel: "bow".into(),
                    edge_a: 0,
                    edge_b: 2
                },
                Problem::ArcTooSmall {
                    panel: "round".into(),
                    edge: 0,
                    radius: 4.0,
                    half_chord: 5.0
                },
            ]
        );
    }

    #[test]
    fn a_zero_length_edge_is_reported() {
        // Vertices 1 and 2 coincide: edge 1 is a point.
        let text = file(
            &[(
                "flat",
                panel_json("[[0, 0], [10, 0], [10, 0], [0, 10]]", SQUARE_EDGES),
            )],
            "[]",
            "",
        );
        assert_eq!(
            problems(&text),
            [Problem::ZeroLength {
                panel: "flat".into(),
                edge: 1
            }]
        );
    }

    #[test]
    fn a_curve_bulging_across_the_outline_crosses_it() {
        // Edge 0's quadratic bulges far up through edge 2 at y = 10.
        let edges = r#"[{"endpoints": [0, 1], "curvature": {"type": "quadratic", "params": [[0.5, 3.0]]}}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]"#;
        let text = file(&[("a", panel_json(SQUARE_VERTICES, edges))], "[]", "");
        assert_eq!(
            problems(&text),
            [Problem::SelfCrossing {
                panel: "a".into(),
                edge_a: 0,
                edge_b: 2
            }]
        );
    }

    #[test]
    fn a_syntax_error_gives_line_and_column() {
        let text = "{\n  \"pattern\": {\n    \"panels\": {,\n  }\n}";
        match parse(text, Path::new("bad.json")) {
            Err(SpecError::Json {
                line, column, path, ..
            }) => {
                assert_eq!((line, column), (3, 16));
                assert_eq!(path, Path::new("bad.json"));
            }
            other => panic!("expected a JSON error, got {other:?}"),
        }
    }

    #[test]
    fn a_wrong_shape_is_a_shape_error() {
        let text = r#"{"pattern": {"panels": {"a": {"vertices": "none", "edges": []}}}}"#;
        assert!(matches!(
            parse(text, Path::new("t.json")),
            Err(SpecError::Shape { line: 1, .. })
        ));
    }

    #[test]
    fn real_patterns_parse_and_validate() {
        let dir = Path::new("/work/shared/realdata/patterns");
        if !dir.is_dir() {
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "{} is missing",
                dir.display()
            );
            eprintln!(
                "note: {} is missing; real-pattern test skipped",
                dir.display()
            );
            return;
        }
        let expected = [
            ("dress_pencil", 6, 23),
            ("hoody_mean", 6, 12),
            ("js_mean_all", 12, 57),
            ("shirt_mean", 8, 18),
        ];
        for (name, panels, stitches) in expected {
            let path = dir.join(format!("{name}_specification.json"));
            let p = read(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(
                (p.panels.len(), p.stitches.len()),
                (panels, stitches),
                "{name}"
            );
            for panel in &p.panels {
                let outline = panel.outline(1.0);
                assert!(outline.len() >= panel.edges.len(), "{name}/{}", panel.name);
                assert!(panel.signed_area().abs() > 1.0, "{name}/{}", panel.name);
                for (k, e) in panel.edges.iter().enumerate() {
                    let (s, t) = panel.endpoints(k);
                    assert!(e.length(&panel.vertices) >= (t - s).norm() - 1e-9);
                }
            }
        }
    }

    #[test]
    fn panels_of_absurd_size_and_patterns_without_panels_are_refused_before_any_sampling() {
        // The 10 x 10 unit square is 14.14 units across: at 100 units a metre, 0.1414 m.
        let size = |units: f64| {
            let text = file(&[("a", square())], "[]", "").replace(
                r#""units_in_meter": 100"#,
                &format!(r#""units_in_meter": {units:e}"#),
            );
            parse(&text, Path::new("t.json"))
                .err()
                .map(|_| problems(&text))
        };
        assert_eq!(size(100.0), None);
        for units in [1e-300, 1e-5, 1e300, 5e-324] {
            let found = size(units).unwrap_or_else(|| panic!("units {units}: accepted"));
            let expected = 200f64.sqrt() / units;
            assert!(
                matches!(&found[..], [Problem::PanelSize { panel, metres }]
                    if panel == "a" && (*metres == expected || (metres - expected).abs() <= 1e-12 * expected)),
                "units {units}: {found:?}"
            );
        }
        // Just inside and just outside the bounds (units chosen so the square is that size).
        for (metres, refused) in [
            (1.01e-3, false),
            (0.99e-3, true),
            (99.0, false),
            (101.0, true),
        ] {
            let units = 200f64.sqrt() / metres;
            assert_eq!(size(units).is_some(), refused, "{metres} m");
        }
        // A curve can be far longer than its chord: a large arc of radius 1e10 units on a
        // 10-unit chord, and a quadratic whose control point is 1e200 units out.
        for curve in [
            r#"{"type": "circle", "params": [1e10, 1, 1]}"#,
            r#"{"type": "quadratic", "params": [[0.5, 1e200]]}"#,
        ] {
            let edges = SQUARE_EDGES.replacen(
                r#"{"endpoints": [0, 1]}"#,
                &format!(r#"{{"endpoints": [0, 1], "curvature": {curve}}}"#),
                1,
            );
            let found = problems(&file(
                &[("a", panel_json(SQUARE_VERTICES, &edges))],
                "[]",
                "",
            ));
            assert!(
                matches!(&found[..], [Problem::PanelSize { metres, .. }] if *metres > 100.0),
                "{curve}: {found:?}"
            );
        }
        let found = problems(&file(&[], "[]", ""));
        assert_eq!(found, vec![Problem::NoPanels]);
        assert!(found[0].to_string().contains("at least one panel"));
    }

    #[test]
    fn panels_placed_beyond_a_kilometre_are_refused_by_translation_or_vertex() {
        // At 100 units a metre, 1 km is 1e5 units.
        let placed = |translation: &str, vertices: &str| {
            let panel = panel_json(vertices, SQUARE_EDGES).replace("[1, 2, 3]", translation);
            let text = file(&[("a", panel)], "[]", "");
            parse(&text, Path::new("t.json"))
                .err()
                .map(|_| problems(&text))
        };
        // A 10-unit square with its first corner at (x, x) units.
        let square_at = |x: f64| {
            let c = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
                .map(|(a, b)| format!("[{}, {}]", x + a, x + b));
            format!("[{}]", c.join(", "))
        };
        assert_eq!(placed("[0, 0, 99000]", SQUARE_VERTICES), None);
        assert_eq!(placed("[0, 0, 0]", &square_at(-7e4)), None); // 990 m
        for (translation, metres) in [("[0, 0, 101000]", 1010.0), ("[1e200, 0, 0]", 1e198)] {
            let found = placed(translation, SQUARE_VERTICES).expect(translation);
            assert!(
                matches!(&found[..], [Problem::PanelFar { panel, what, metres: m }]
                    if panel == "a" && what == "translation" && (m - metres).abs() <= 1e-9 * metres),
                "{translation}: {found:?}"
            );
            assert!(found[0].to_string().contains("within 1000 m of the body"));
        }
        // A small panel whose vertices are all far out (its box is 14 cm across): the
        // farthest vertex is named.
        let found = placed("[0, 0, 0]", &square_at(1e8)).expect("far vertices");
        assert!(
            matches!(&found[..], [Problem::PanelFar { what, .. }] if what == "vertex 2"),
            "{found:?}"
        );
    }
}
