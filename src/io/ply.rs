//! PLY: ASCII, binary little-endian and binary big-endian.
//!
//! Header: `ply`, a `format` line, then `element NAME COUNT` lines each followed by its
//! `property TYPE NAME` or `property list COUNT_TYPE ITEM_TYPE NAME` lines, `comment` and
//! `obj_info` lines anywhere, and `end_header`. Types: `char uchar short ushort int uint float
//! double` and their sized names (`int8` ... `float64`). Header lines end in LF or CRLF; a header
//! line that is none of these (Blender 2.47 writes a bare "Created by ..." line) is skipped with
//! a warning. The binary body starts right after the line end of `end_header`, even if its first
//! byte is a newline.
//!
//! Geometry comes from the `vertex` element's `x y z` (any numeric type) and the `face` element's
//! `vertex_indices` (or `vertex_index`) list. Every other element and property, list properties
//! on the vertex element included, is read past. Faces of four or more corners are triangulated
//! (see `mesh::polygon`).
//!
//! Written: `double` coordinates and `uchar`-counted `int` index lists, binary little-endian by
//! default, ASCII on request (shortest exact numbers).

use super::error::{malformed, IoError, Location, ProblemKind, Problems};
use super::text::{self, show};
use super::{ReadInfo, ReadOptions, ReadOutput};
use crate::math::Point3;
use crate::mesh::polygon::Polygons;
use crate::mesh::TriMesh;
use std::io::Write;
use std::path::Path;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &[u8]) -> Option<Scalar> {
        Some(match s {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    fn range(self) -> (f64, f64) {
        match self {
            Scalar::I8 => (i8::MIN as f64, i8::MAX as f64),
            Scalar::U8 => (0.0, u8::MAX as f64),
            Scalar::I16 => (i16::MIN as f64, i16::MAX as f64),
            Scalar::U16 => (0.0, u16::MAX as f64),
            Scalar::I32 => (i32::MIN as f64, i32::MAX as f64),
            Scalar::U32 => (0.0, u32::MAX as f64),
            Scalar::F32 | Scalar::F64 => (f64::NEG_INFINITY, f64::INFINITY),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum PropType {
    Scalar(Scalar),
    List(Scalar, Scalar),
}

#[derive(Debug, Clone)]
struct Property {
    name: String,
    ty: PropType,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    body: usize,
    lines: u64,
    warnings: Vec<String>,
}

/// A header problem: where, and what.
type HeaderError = (Location, ProblemKind);

/// Parses the header: the magic line, then its lines up to `end_header`; a format line is
/// required.
fn parse_header(bytes: &[u8]) -> Result<Header, HeaderError> {
    let mut lines = HeaderLines {
        bytes,
        // A UTF-8 byte order mark before `ply` (some Windows tools write one) is read past.
        pos: if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
            3
        } else {
            0
        },
        line_no: 0,
    };
    match lines.next_line() {
        Some((_, l)) if l.trim_ascii() == b"ply" => {}
        _ => return Err((Location::Line(1), ProblemKind::PlyMagic)),
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut warnings = Vec::new();
    loop {
        let Some((ln, line)) = lines.next_line() else {
            return Err((Location::File, ProblemKind::PlyNoEnd));
        };
        let w: Vec<&[u8]> = text::words(line).collect();
        match w.first().copied() {
            None => {}
            Some(b"end_header") => break,
            Some(b"comment") | Some(b"obj_info") => {}
            Some(b"format") => encoding = Some(format_line(ln, line, &w)?),
            Some(b"element") => {
                let el = element_line(ln, line, &w)?;
                if matches!(el.name.as_str(), "vertex" | "face")
                    && elements.iter().any(|e| e.name == el.name)
                {
                    let what = "a second element of this name: one 'vertex' and one 'face' element are read";
                    return Err(header_err(ln, line, what));
                }
                elements.push(el);
            }
            Some(b"property") => property_line(ln, line, &w, elements.last_mut())?,
            Some(_) => warnings.push(format!(
                "header line {ln} skipped: '{}' is not a PLY header keyword",
                show(line)
            )),
        }
    }
    let Some(encoding) = encoding else {
        // No line holds it: the file is named, not a line.
        return Err((
            Location::File,
            ProblemKind::PlyFormat {
                found: "(no format line)".into(),
            },
        ));
    };
    Ok(Header {
        encoding,
        elements,
        body: lines.pos,
        lines: lines.line_no,
        warnings,
    })
}

/// The header's lines, numbered from 1, without their LF or CRLF.
struct HeaderLines<'a> {
    bytes: &'a [u8],
    /// Where the next line starts.
    pos: usize,
    /// The number of the line last read.
    line_no: u64,
}

impl<'a> HeaderLines<'a> {
    /// The next line and its number; `None` at the end of the bytes.
    fn next_line(&mut self) -> Option<(u64, &'a [u8])> {
        if self.pos >= self.bytes.len() {
            return None;
        }
        let rest = &self.bytes[self.pos..];
        let end = rest.iter().position(|&b| b == b'\n');
        let (line, adv) = match end {
            Some(e) => (&rest[..e], e + 1),
            None => (rest, rest.len()),
        };
        self.pos += adv;
        self.line_no += 1;
        Some((self.line_no, line.strip_suffix(b"\r").unwrap_or(line)))
    }
}

/// The header error at line `ln` (whose text is `line`) for `reason`.
fn header_err(ln: u64, line: &[u8], reason: &str) -> HeaderError {
    let kind = ProblemKind::PlyHeader {
        line: show(line),
        reason: reason.into(),
    };
    (Location::Line(ln), kind)
}

/// The encoding a `format` line (line `ln`, split into the words `w`) names, version 1.0.
fn format_line(ln: u64, line: &[u8], w: &[&[u8]]) -> Result<Encoding, HeaderError> {
    match (w.get(1).copied(), w.get(2).copied()) {
        (Some(b"ascii"), Some(b"1.0")) => Ok(Encoding::Ascii),
        (Some(b"binary_little_endian"), Some(b"1.0")) => Ok(Encoding::Little),
        (Some(b"binary_big_endian"), Some(b"1.0")) => Ok(Encoding::Big),
        _ => Err((
            Location::Line(ln),
            ProblemKind::PlyFormat { found: show(line) },
        )),
    }
}

/// The element an `element NAME COUNT` line declares, without properties yet.
fn element_line(ln: u64, line: &[u8], w: &[&[u8]]) -> Result<Element, HeaderError> {
    if w.len() != 3 {
        return Err(header_err(ln, line, "expected 'element NAME COUNT'"));
    }
    let count = std::str::from_utf8(w[2])
        .ok()
        .and_then(|s| s.parse::<u64>().ok());
    let Some(count) = count else {
        return Err(header_err(
            ln,
            line,
            "the element count is not a whole number",
        ));
    };
    Ok(Element {
        name: String::from_utf8_lossy(w[1]).into_owned(),
        count,
        props: Vec::new(),
    })
}

/// Adds the property a `property` line declares (scalar or list) to `el`, the element
/// declared last (an error when there is none yet).
fn property_line(
    ln: u64,
    line: &[u8],
    w: &[&[u8]],
    el: Option<&mut Element>,
) -> Result<(), HeaderError> {
    let Some(el) = el else {
        return Err(header_err(ln, line, "a property before any element"));
    };
    let (ty, name) = if w.get(1).copied() == Some(b"list") {
        if w.len() != 5 {
            let reason = "expected 'property list COUNT_TYPE ITEM_TYPE NAME'";
            return Err(header_err(ln, line, reason));
        }
        let c = scalar_type(ln, w[2])?;
        let i = scalar_type(ln, w[3])?;
        if c.is_float() {
            let reason = "a list count must have an integer type";
            return Err(header_err(ln, line, reason));
        }
        (PropType::List(c, i), w[4])
    } else {
        if w.len() != 3 {
            return Err(header_err(ln, line, "expected 'property TYPE NAME'"));
        }
        (PropType::Scalar(scalar_type(ln, w[1])?), w[2])
    };
    el.props.push(Property {
        name: String::from_utf8_lossy(name).into_owned(),
        ty,
    });
    Ok(())
}

/// The scalar type named by `word` on line `ln`.
fn scalar_type(ln: u64, word: &[u8]) -> Result<Scalar, HeaderError> {
    Scalar::parse(word).ok_or((
        Location::Line(ln),
        ProblemKind::PlyType { found: show(word) },
    ))
}

/// The roles of an element's properties for geometry.
struct Roles {
    xyz: Option<[usize; 3]>,
    indices: Option<usize>,
}

fn roles(el: &Element) -> Roles {
    let find = |n: &str| {
        el.props
            .iter()
            .position(|p| p.name == n && matches!(p.ty, PropType::Scalar(_)))
    };
    let xyz = match (el.name.as_str(), find("x"), find("y"), find("z")) {
        ("vertex", Some(x), Some(y), Some(z)) => Some([x, y, z]),
        _ => None,
    };
    let indices = if el.name == "face" {
        let list = |n: &str| {
            el.props
                .iter()
                .position(|p| p.name == n && matches!(p.ty, PropType::List(..)))
        };
        list("vertex_indices").or_else(|| list("vertex_index"))
    } else {
        None
    };
    Roles { xyz, indices }
}

const FMT: &str = "PLY";

/// Reads PLY from `bytes` (`path` names the file in messages). Every problem of the records
/// is listed (a coordinate that is not finite, a face index that is not a vertex, a face of
/// fewer than three corners); reading stops only where the records can no longer be counted
/// (the file ends early, a line has too few values, a list length is not a count).
pub fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<ReadOutput, IoError> {
    let header = parse_header(bytes).map_err(|(at, kind)| malformed(path, FMT, at, kind))?;
    let mut warnings = header_warnings(path, &header)?;
    let mut body = BodyReader::new(path, &header, bytes);
    for el in &header.elements {
        body.element(el)?;
    }
    warnings.extend(body.notes());
    let BodyReader {
        records: r,
        mut problems,
        ..
    } = body;
    let n = r.positions.len();
    for (ring, at) in r.polys.iter().zip(&r.face_at) {
        for &c in ring.iter().filter(|&&c| c as usize >= n) {
            let kind = ProblemKind::IndexOutOfRange {
                index: i64::from(c),
                count: n as u64,
            };
            problems.push(at.clone(), kind);
        }
    }
    problems.check(path, FMT)?;
    super::check_vertex_count(path, n)?;
    let (faces, stats) = r.polys.triangulate(&r.positions, opts.quad_split);
    let info = ReadInfo {
        format: match header.encoding {
            Encoding::Ascii => "ply-ascii",
            Encoding::Little => "ply-binary-le",
            Encoding::Big => "ply-binary-be",
        }
        .into(),
        vertices_in_file: n,
        polygons: stats,
        warnings,
        ..ReadInfo::default()
    };
    Ok(ReadOutput {
        texcoords: None,
        mesh: TriMesh::new(r.positions, faces),
        info,
    })
}

/// The header's warnings (elements skipped, faces without indices); an error when the vertex
/// element lacks a scalar `x`, `y` or `z`.
fn header_warnings(path: &Path, header: &Header) -> Result<Vec<String>, IoError> {
    let mut warnings = header.warnings.clone();
    for el in &header.elements {
        if el.name == "vertex" {
            for c in ["x", "y", "z"] {
                let scalar = |p: &Property| p.name == c && matches!(p.ty, PropType::Scalar(_));
                if !el.props.iter().any(scalar) {
                    let kind = ProblemKind::PlyMissingProperty { name: c.into() };
                    return Err(malformed(path, FMT, Location::File, kind));
                }
            }
        }
        if el.name == "face" && el.count > 0 && roles(el).indices.is_none() {
            warnings.push("the face element has no 'vertex_indices' list: faces skipped".into());
        }
        if !matches!(el.name.as_str(), "vertex" | "face") && el.count > 0 {
            warnings.push(format!("{} '{}' element(s) skipped", el.count, el.name));
        }
    }
    Ok(warnings)
}

/// What the records give.
#[derive(Default)]
struct Records {
    positions: Vec<Point3>,
    polys: Polygons,
    /// Where each polygon's record starts.
    face_at: Vec<Location>,
    /// Records (ASCII lines) with values beyond the header's properties.
    extra_lines: u64,
    /// Records (ASCII lines) that end where their trailing lists begin.
    missing_lists: u64,
}

/// Reads the body's records, element by element, collecting the problems it can read past.
struct BodyReader<'a> {
    path: &'a Path,
    source: Box<dyn ValueSource + 'a>,
    /// Whether the body is ASCII.
    ascii: bool,
    /// The body's length in bytes (a bound on what a count may allocate).
    len: usize,
    records: Records,
    problems: Problems,
    /// The current face's corners.
    ring: Vec<u32>,
}

/// A record's values: read so far, and needed at least (each property one, and each list's
/// items once its length is read).
#[derive(Default)]
struct Tally {
    found: usize,
    needed: usize,
}

/// The record being read: its element, number and where it starts.
struct Record<'e> {
    el: &'e Element,
    roles: Roles,
    index: u64,
    at: Location,
}

impl<'a> BodyReader<'a> {
    fn new(path: &'a Path, header: &Header, bytes: &'a [u8]) -> BodyReader<'a> {
        let body = &bytes[header.body..];
        let source: Box<dyn ValueSource + 'a> = match header.encoding {
            Encoding::Ascii => Box::new(AsciiSource {
                text: body,
                pos: 0,
                line: header.lines,
                tokens: Vec::new(),
                next: 0,
            }),
            e => Box::new(BinarySource {
                bytes: body,
                pos: 0,
                base: header.body as u64,
                big: e == Encoding::Big,
            }),
        };
        BodyReader {
            path,
            source,
            ascii: header.encoding == Encoding::Ascii,
            len: body.len(),
            records: Records::default(),
            problems: Problems::default(),
            ring: Vec::new(),
        }
    }

    /// The error that stops reading: the problems so far and this one.
    fn fatal(&mut self, at: Location, kind: ProblemKind) -> IoError {
        let mut problems = std::mem::take(&mut self.problems);
        problems.push(at, kind);
        match problems.check(self.path, FMT) {
            Err(e) => e,
            Ok(()) => unreachable!("a problem was just recorded"),
        }
    }

    /// Reads every record of `el`.
    fn element(&mut self, el: &Element) -> Result<(), IoError> {
        // A binary record of no properties holds no bytes: there is nothing to read, however
        // large the count (2^64 - 1 would otherwise loop for ever over empty records).
        if el.props.is_empty() && !self.ascii {
            return Ok(());
        }
        let roles = roles(el);
        // Don't trust the count for allocation beyond what the file could hold.
        let cap = (el.count as usize).min(self.len / 2 + 1);
        if roles.xyz.is_some() {
            self.records.positions.reserve(cap);
        }
        if roles.indices.is_some() {
            self.records.polys = Polygons::with_capacity(cap);
            self.records.face_at.reserve(cap);
        }
        let mut rec = Record {
            el,
            roles,
            index: 0,
            at: Location::File,
        };
        for index in 0..el.count {
            rec.index = index;
            rec.at = self.source.location(&el.name, index);
            self.record(&rec)?;
        }
        Ok(())
    }

    /// The error of a record cut short: the file ended, or its line did after `found` values.
    fn short(&mut self, rec: &Record, e: ValueError, tally: &Tally) -> IoError {
        let (el, index) = (rec.el.name.clone(), rec.index);
        match e {
            ValueError::End => {
                let count = rec.el.count;
                let kind = ProblemKind::PlyShort {
                    element: el,
                    index,
                    count,
                };
                self.fatal(rec.at.clone(), kind)
            }
            ValueError::LineEnd => {
                let kind = ProblemKind::PlyValueCount {
                    element: el,
                    index,
                    found: tally.found,
                    needed: tally.needed,
                };
                self.fatal(rec.at.clone(), kind)
            }
            ValueError::Bad(at, kind) => self.fatal(at, kind),
        }
    }

    /// Reads one record: its scalars (the vertex's coordinates kept) and its lists (the face's
    /// corners kept).
    fn record(&mut self, rec: &Record) -> Result<(), IoError> {
        if !self.source.begin_record() {
            let tally = Tally::default();
            return Err(self.short(rec, ValueError::End, &tally));
        }
        let mut tally = Tally {
            found: 0,
            needed: rec.el.props.len(),
        };
        let mut xyz = [0.0f64; 3];
        for (k, p) in rec.el.props.iter().enumerate() {
            match p.ty {
                PropType::Scalar(t) => {
                    let v = self.scalar(rec, t, &mut tally)?;
                    let c = rec.roles.xyz.and_then(|r| r.iter().position(|&x| x == k));
                    if let (Some(c), Some(v)) = (c, v) {
                        if let Err(kind) = coordinate(v, t) {
                            self.problems.push(rec.at.clone(), kind);
                        }
                        xyz[c] = v;
                    }
                }
                PropType::List(ct, it) => {
                    let rest_are_lists =
                        (rec.el.props[k..].iter()).all(|q| matches!(q.ty, PropType::List(..)));
                    match self.source.value(ct) {
                        Ok(n) => {
                            tally.found += 1;
                            self.list(rec, n, it, rec.roles.indices == Some(k), &mut tally)?;
                        }
                        // A line that stops exactly where trailing lists begin: read them as empty.
                        Err(ValueError::LineEnd) if rest_are_lists => {
                            self.records.missing_lists += 1;
                            break;
                        }
                        Err(e) => return Err(self.short(rec, e, &tally)),
                    }
                }
            }
        }
        self.records.extra_lines += u64::from(self.source.end_record());
        if rec.roles.xyz.is_some() {
            self.records
                .positions
                .push(Point3::new(xyz[0], xyz[1], xyz[2]));
        }
        Ok(())
    }

    /// The next scalar of type `t`: `None` (the problem recorded) when it is not of its type.
    fn scalar(
        &mut self,
        rec: &Record,
        t: Scalar,
        tally: &mut Tally,
    ) -> Result<Option<f64>, IoError> {
        match self.source.value(t) {
            Ok(v) => {
                tally.found += 1;
                Ok(Some(v))
            }
            Err(ValueError::Bad(at, kind)) => {
                tally.found += 1;
                self.problems.push(at, kind);
                Ok(None)
            }
            Err(e) => Err(self.short(rec, e, tally)),
        }
    }

    /// A list of `n` items of type `it` (`n` as read; it must be a count); a face's corners
    /// when `is_faces`.
    fn list(
        &mut self,
        rec: &Record,
        n: f64,
        it: Scalar,
        is_faces: bool,
        tally: &mut Tally,
    ) -> Result<(), IoError> {
        let (el, index) = (&rec.el.name, rec.index);
        if let Err(kind) = whole_number(n, "list length", el, index) {
            return Err(self.fatal(rec.at.clone(), kind));
        }
        if n < 0.0 {
            let kind = ProblemKind::NegativeCount { count: n as i64 };
            return Err(self.fatal(rec.at.clone(), kind));
        }
        let n = n as usize;
        tally.needed += n;
        self.ring.clear();
        let mut usable = true;
        for _ in 0..n {
            let v = self.scalar(rec, it, tally)?;
            if !is_faces {
                continue;
            }
            match v.map(|v| corner(v, el, index, self.records.positions.len())) {
                Some(Ok(c)) => self.ring.push(c),
                Some(Err(kind)) => {
                    self.problems.push(rec.at.clone(), kind);
                    usable = false;
                }
                None => usable = false,
            }
        }
        if is_faces && n < 3 {
            let kind = ProblemKind::TooFewCorners { found: n };
            self.problems.push(rec.at.clone(), kind);
        } else if is_faces && usable {
            self.records.polys.push(self.ring.iter().copied());
            self.records.face_at.push(rec.at.clone());
        }
        Ok(())
    }

    /// The warnings of the records read: lines with values beyond or short of the
    /// properties, and anything after the last element.
    fn notes(&mut self) -> Vec<String> {
        let mut notes = Vec::new();
        let r = &self.records;
        if r.extra_lines > 0 {
            notes.push(format!(
                "{} line(s) hold values beyond the header's properties (ignored)",
                r.extra_lines
            ));
        }
        if r.missing_lists > 0 {
            notes.push(format!(
                "{} line(s) end before the header's trailing list properties (read as empty lists)",
                r.missing_lists
            ));
        }
        notes.extend(self.source.leftover());
        notes
    }
}

/// A face's corner `v`: a whole number within `u32` (whether it names a vertex is checked once
/// all are read; `vertices` so far are named in the problem).
fn corner(v: f64, element: &str, index: u64, vertices: usize) -> Result<u32, ProblemKind> {
    whole_number(v, "vertex index", element, index)?;
    if v < 0.0 || v >= f64::from(u32::MAX) {
        return Err(ProblemKind::IndexOutOfRange {
            index: v as i64,
            count: vertices as u64,
        });
    }
    Ok(v as u32)
}

/// A coordinate `v` read as type `t`: finite, and within the range of a `float` (f32) when
/// declared so (an ASCII `1e39` would otherwise pass as an f64).
fn coordinate(v: f64, t: Scalar) -> Result<(), ProblemKind> {
    if !v.is_finite() {
        return Err(ProblemKind::BinaryNonFinite { value: v });
    }
    super::text::within(v)?;
    if t == Scalar::F32 && v.abs() > f64::from(f32::MAX) {
        return Err(ProblemKind::PlyFloatRange {
            value: v,
            ty: t.name(),
            max: f64::from(f32::MAX),
        });
    }
    Ok(())
}

/// A list length or face index must be a whole number (a `float` one may hold 1.7 or NaN).
fn whole_number(
    value: f64,
    what: &'static str,
    element: &str,
    index: u64,
) -> Result<(), ProblemKind> {
    if value.is_finite() && value.fract() == 0.0 {
        return Ok(());
    }
    Err(ProblemKind::PlyNotInteger {
        element: element.to_string(),
        index,
        what,
        value,
    })
}

enum ValueError {
    /// The file ended.
    End,
    /// The record's line ended (ASCII).
    LineEnd,
    /// A value that is not of its type.
    Bad(Location, ProblemKind),
}

/// Where property values come from: ASCII lines (one element per line) or binary bytes.
trait ValueSource {
    /// Starts the next element record; false at the end of the file.
    fn begin_record(&mut self) -> bool;
    /// The next value of type `t`.
    fn value(&mut self, t: Scalar) -> Result<f64, ValueError>;
    /// Ends a record; true when it held values beyond the properties (ASCII).
    fn end_record(&mut self) -> bool;
    /// Where the next record starts.
    fn location(&self, element: &str, index: u64) -> Location;
    /// A note on anything after the last element.
    fn leftover(&mut self) -> Option<String>;
}

struct AsciiSource<'a> {
    text: &'a [u8],
    pos: usize,
    /// Line number of the current record.
    line: u64,
    tokens: Vec<(usize, usize)>,
    next: usize,
}

impl AsciiSource<'_> {
    /// The next non-blank line: its number and token spans; advances past it.
    fn next_line(&mut self) -> Option<(u64, Vec<(usize, usize)>)> {
        let t = self.text;
        let mut line = self.line;
        while self.pos < t.len() {
            line += 1;
            let start = self.pos;
            let end = t[start..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(t.len(), |e| start + e);
            self.pos = (end + 1).min(t.len());
            let mut spans = Vec::new();
            let mut i = start;
            while i < end {
                while i < end && t[i].is_ascii_whitespace() {
                    i += 1;
                }
                let s0 = i;
                while i < end && !t[i].is_ascii_whitespace() {
                    i += 1;
                }
                if i > s0 {
                    spans.push((s0, i));
                }
            }
            if !spans.is_empty() {
                return Some((line, spans));
            }
        }
        self.line = line;
        None
    }
}

impl ValueSource for AsciiSource<'_> {
    fn begin_record(&mut self) -> bool {
        match self.next_line() {
            Some((line, tokens)) => {
                self.line = line;
                self.tokens = tokens;
                self.next = 0;
                true
            }
            None => false,
        }
    }

    fn value(&mut self, t: Scalar) -> Result<f64, ValueError> {
        let Some(&(a, b)) = self.tokens.get(self.next) else {
            return Err(ValueError::LineEnd);
        };
        self.next += 1;
        let tok = &self.text[a..b];
        let at = Location::Line(self.line);
        if t.is_float() {
            // Non-finite values are caught by the caller where they matter (coordinates).
            return std::str::from_utf8(tok)
                .ok()
                .and_then(|x| x.parse::<f64>().ok())
                .ok_or_else(|| ValueError::Bad(at, ProblemKind::NotANumber { token: show(tok) }));
        }
        let v = std::str::from_utf8(tok).ok().and_then(|x| {
            x.parse::<i64>()
                .ok()
                .map(|i| i as f64)
                .or_else(|| x.parse::<f64>().ok().filter(|f| f.fract() == 0.0))
        });
        let (lo, hi) = t.range();
        match v {
            Some(v) if v >= lo && v <= hi => Ok(v),
            _ => Err(ValueError::Bad(
                at,
                ProblemKind::BadInteger {
                    token: show(tok),
                    ty: t.name().into(),
                },
            )),
        }
    }

    fn end_record(&mut self) -> bool {
        self.next < self.tokens.len()
    }

    fn location(&self, _: &str, _: u64) -> Location {
        // The line of the next record.
        let mut line = self.line;
        let mut at_line_start = true;
        for &b in &self.text[self.pos..] {
            if at_line_start {
                line += 1;
                at_line_start = false;
            }
            if b == b'\n' {
                at_line_start = true;
            } else if !b.is_ascii_whitespace() {
                return Location::Line(line);
            }
        }
        Location::Line(line + u64::from(at_line_start))
    }

    fn leftover(&mut self) -> Option<String> {
        let mut n = 0;
        while self.next_line().is_some() {
            n += 1;
        }
        (n > 0).then(|| format!("{n} line(s) after the last element ignored"))
    }
}

struct BinarySource<'a> {
    bytes: &'a [u8],
    pos: usize,
    base: u64,
    big: bool,
}

impl ValueSource for BinarySource<'_> {
    fn begin_record(&mut self) -> bool {
        true
    }

    fn end_record(&mut self) -> bool {
        false
    }

    #[inline]
    fn value(&mut self, t: Scalar) -> Result<f64, ValueError> {
        let n = t.size();
        if self.pos + n > self.bytes.len() {
            return Err(ValueError::End);
        }
        let b = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        macro_rules! get {
            ($ty:ty) => {{
                let a = b.try_into().unwrap();
                if self.big {
                    <$ty>::from_be_bytes(a) as f64
                } else {
                    <$ty>::from_le_bytes(a) as f64
                }
            }};
        }
        Ok(match t {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => get!(i16),
            Scalar::U16 => get!(u16),
            Scalar::I32 => get!(i32),
            Scalar::U32 => get!(u32),
            Scalar::F32 => get!(f32),
            Scalar::F64 => get!(f64),
        })
    }

    fn location(&self, element: &str, index: u64) -> Location {
        Location::Byte {
            offset: self.base + self.pos as u64,
            record: format!("element '{element}' {index}"),
        }
    }

    fn leftover(&mut self) -> Option<String> {
        let rest = self.bytes.len() - self.pos;
        (rest > 0).then(|| format!("{rest} byte(s) after the last element ignored"))
    }
}

/// Writes PLY: binary little-endian, or ASCII.
pub fn write(w: &mut impl Write, mesh: &TriMesh, ascii: bool) -> std::io::Result<()> {
    let index_type = if mesh.positions.len() > i32::MAX as usize {
        "uint"
    } else {
        "int"
    };
    write!(
        w,
        "ply\nformat {} 1.0\ncomment drapekit\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement face {}\nproperty list uchar {index_type} vertex_indices\nend_header\n",
        if ascii { "ascii" } else { "binary_little_endian" },
        mesh.positions.len(),
        mesh.faces.len()
    )?;
    if ascii {
        for p in &mesh.positions {
            writeln!(w, "{:?} {:?} {:?}", p.x, p.y, p.z)?;
        }
        for f in &mesh.faces {
            writeln!(w, "3 {} {} {}", f[0], f[1], f[2])?;
        }
    } else {
        let mut buf = Vec::with_capacity(1 << 16);
        for p in &mesh.positions {
            for k in 0..3 {
                buf.extend_from_slice(&p[k].to_le_bytes());
            }
            if buf.len() >= 1 << 16 {
                w.write_all(&buf)?;
                buf.clear();
            }
        }
        for f in &mesh.faces {
            buf.push(3);
            for &v in f {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            if buf.len() >= 1 << 16 {
                w.write_all(&buf)?;
                buf.clear();
            }
        }
        w.write_all(&buf)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_bytes(b: &[u8]) -> Result<ReadOutput, IoError> {
        read(Path::new("p.ply"), b, &ReadOptions::default())
    }

    #[test]
    fn round_trip_both_encodings() {
        let m = crate::mesh::generate::icosphere(1);
        for ascii in [false, true] {
            let mut buf = Vec::new();
            write(&mut buf, &m, ascii).unwrap();
            assert_eq!(read_bytes(&buf).unwrap().mesh, m);
        }
    }

    #[test]
    fn a_byte_order_mark_before_ply_is_read_past_in_both_encodings() {
        let m = crate::mesh::generate::icosphere(1);
        for ascii in [false, true] {
            let mut buf = b"\xEF\xBB\xBF".to_vec();
            write(&mut buf, &m, ascii).unwrap();
            assert_eq!(read_bytes(&buf).unwrap().mesh, m);
        }
    }

    #[test]
    fn big_endian_with_extra_properties_and_odd_header() {
        let mut b = b"ply\r\nformat binary_big_endian 1.0\r\nCreated by hand\r\nelement vertex 3\r\ncomment between\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\nproperty list uchar int junk\r\nelement face 1\r\nproperty list uchar uint vertex_index\r\nend_header\r\n".to_vec();
        for (i, p) in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]]
            .iter()
            .enumerate()
        {
            for v in p {
                b.extend_from_slice(&v.to_be_bytes());
            }
            b.push(1);
            b.extend_from_slice(&(i as i32).to_be_bytes());
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend_from_slice(&i.to_be_bytes());
        }
        let r = read_bytes(&b).unwrap();
        assert_eq!(r.mesh.faces, vec![[0, 1, 2]]);
        assert_eq!(r.mesh.positions[1], Point3::new(1.0, 0.0, 0.0));
        assert!(r.info.warnings[0].contains("header line 3 skipped"));
    }

    #[test]
    fn every_problem_of_the_records_is_listed_and_a_short_line_counts_its_lists() {
        let head = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n";
        let e = read_bytes(
            format!("{head}0 0 nan\n1 0 x\n0 1e39 0\n0 0 1\n3 0 1 9\n3 0 1.5 2\n2 0 1\n")
                .as_bytes(),
        )
        .unwrap_err()
        .to_string();
        let lines: Vec<&str> = e.lines().collect();
        assert_eq!(
            lines,
            [
                "p.ply: 6 problems in this PLY file:",
                "p.ply:10: non-finite coordinate NaN",
                "p.ply:11: 'x' is not a number",
                "p.ply:12: coordinate 1e39 does not fit the declared type float (at most 3.4028234663852886e38 in magnitude)",
                "p.ply:15: '1.5' is not a valid int",
                "p.ply:16: a face needs at least 3 corners, found 2",
                "p.ply:14: vertex index 9 is out of range: the file has 4 vertices",
            ],
            "{e}"
        );
        // Reading stops where the records can no longer be counted, with what was found
        // before: a face line with 2 of its 3 corners needs 4 values.
        let e = read_bytes(format!("{head}0 0 nan\n1 0 0\n0 1 0\n0 0 1\n3 0 1\n").as_bytes())
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "p.ply: 2 problems in this PLY file:\np.ply:10: non-finite coordinate NaN\np.ply:14: element 'face' 0 has 3 values on its line; its properties need at least 4"
        );
    }

    #[test]
    fn a_second_vertex_or_face_element_is_refused_at_its_line() {
        // A second face element replaced the first's faces (and misplaced their lines).
        for (name, second) in [("vertex", 5), ("face", 9)] {
            let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n";
            let mut lines: Vec<&str> = head.lines().collect();
            let extra = format!("element {name} 1");
            lines.insert(second - 1, &extra);
            let text = format!("{}\nend_header\n", lines.join("\n"));
            let e = read_bytes(text.as_bytes()).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("p.ply:{second}: "))
                    && e.contains("a second element of this name"),
                "{name}: {e}"
            );
        }
    }

    #[test]
    fn short_body_and_bad_index() {
        let e = read_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n").unwrap_err().to_string();
        assert_eq!(
            e,
            "p.ply:10: the file ends in element 'vertex' 2 of 3: the header promises 3"
        );
        let e = read_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").unwrap_err().to_string();
        assert_eq!(
            e,
            "p.ply:13: vertex index 7 is out of range: the file has 3 vertices"
        );
    }
}
