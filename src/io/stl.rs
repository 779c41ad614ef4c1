//! STL, ASCII and binary.
//!
//! Binary or ASCII is decided by size, not by the first word: a file whose length is exactly
//! `84 + 50 * count` (the count read at byte 80) is binary, even when its 80-byte header starts
//! with `solid` (SolidWorks and others write that). Otherwise a file starting with `solid` is
//! ASCII; anything else of 84 bytes or more is a binary file whose size disagrees with its count,
//! which is an error (truncated, or with extra bytes), never a silent partial read.
//!
//! ASCII: every `solid ... endsolid` block of the file is read (multi-solid files), keywords in
//! any case, the name after `solid` may follow a tab; `facet normal` values are skipped unread
//! (NaN normals are harmless: the winding defines the normal); a facet's loop may hold more than
//! three vertices (a polygon, triangulated). Vertex coordinates must be finite.
//!
//! Both kinds index their vertices by exact equality (lossless). Written: binary (32-bit floats,
//! an 80-byte header that does not start with `solid`, the normal from the winding) or ASCII
//! (each number in its shortest exact `f64` form, so ASCII output round-trips bit for bit).

use super::error::{malformed, IoError, Location, ProblemKind, Problems};
use super::text::{self, show};
use super::{ReadInfo, ReadOptions, ReadOutput};
use crate::math::Point3;
use crate::mesh::polygon::{PolygonStats, Polygons};
use crate::mesh::weld::ExactIndexer;
use crate::mesh::TriMesh;
use std::borrow::Cow;
use std::io::Write;
use std::path::Path;

/// Whether `bytes` has the exact size of a binary STL with the count it declares.
pub fn is_binary(bytes: &[u8]) -> bool {
    is_binary_len(bytes, bytes.len() as u64)
}

/// Whether a file of `len` bytes that starts with `head` is a binary STL by its size.
pub fn is_binary_len(head: &[u8], len: u64) -> bool {
    head.len() >= 84
        && 84 + 50 * u64::from(u32::from_le_bytes([head[80], head[81], head[82], head[83]])) == len
}

/// Whether `bytes` starts, after blanks, with the word `solid`.
pub fn starts_with_solid(bytes: &[u8]) -> bool {
    let t = bytes.trim_ascii_start();
    t.len() >= 5
        && t[..5].eq_ignore_ascii_case(b"solid")
        && t.get(5).is_none_or(|c| c.is_ascii_whitespace())
}

/// Reads STL from `bytes` (`path` names the file in messages).
pub fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<ReadOutput, IoError> {
    if is_binary(bytes) {
        read_binary(path, bytes)
    } else if starts_with_solid(&super::text::decode(bytes).unwrap_or(Cow::Borrowed(bytes))) {
        // Seen after decoding: an ASCII STL may start with a byte order mark or be UTF-16.
        read_ascii(path, bytes, opts)
    } else {
        let size = bytes.len() as u64;
        if size < 84 {
            return Err(malformed(
                path,
                "binary STL",
                Location::File,
                ProblemKind::StlTooShort { size },
            ));
        }
        let count = u64::from(u32::from_le_bytes([
            bytes[80], bytes[81], bytes[82], bytes[83],
        ]));
        let needed = 84 + 50 * count;
        let kind = if size < needed {
            ProblemKind::StlTruncated {
                count,
                needed,
                size,
                first_missing: (size - 84) / 50,
            }
        } else {
            ProblemKind::StlCountMismatch {
                count,
                needed,
                size,
            }
        };
        let offset = if size < needed {
            84 + (size - 84) / 50 * 50
        } else {
            80
        };
        let record = if size < needed {
            format!("triangle {}", (size - 84) / 50)
        } else {
            "triangle count".into()
        };
        Err(malformed(
            path,
            "binary STL",
            Location::Byte { offset, record },
            kind,
        ))
    }
}

fn read_binary(path: &Path, bytes: &[u8]) -> Result<ReadOutput, IoError> {
    let count = (bytes.len() - 84) / 50;
    let mut ix = ExactIndexer::with_capacity(count / 2 + 8);
    let mut faces = Vec::with_capacity(count);
    let mut nan_normals = 0usize;
    for (t, rec) in bytes[84..].chunks_exact(50).enumerate() {
        let f = |k: usize| {
            f32::from_le_bytes([rec[4 * k], rec[4 * k + 1], rec[4 * k + 2], rec[4 * k + 3]])
        };
        if !(f(0).is_finite() && f(1).is_finite() && f(2).is_finite()) {
            nan_normals += 1;
        }
        let mut face = [0u32; 3];
        for (c, slot) in face.iter_mut().enumerate() {
            let p = [f(3 + 3 * c), f(4 + 3 * c), f(5 + 3 * c)];
            if let Some(k) = p.iter().position(|v| !v.is_finite()) {
                let offset = (84 + 50 * t + 12 + 12 * c + 4 * k) as u64;
                return Err(malformed(
                    path,
                    "binary STL",
                    Location::Byte {
                        offset,
                        record: format!("triangle {t}, corner {c}"),
                    },
                    ProblemKind::BinaryNonFinite {
                        value: f64::from(p[k]),
                    },
                ));
            }
            *slot = ix.index(Point3::new(
                f64::from(p[0]),
                f64::from(p[1]),
                f64::from(p[2]),
            ));
        }
        faces.push(face);
    }
    let positions = ix.into_positions();
    let mut warnings = Vec::new();
    if nan_normals > 0 {
        warnings.push(format!("{nan_normals} facet normal(s) are not finite (ignored: the winding defines the normal)"));
    }
    let info = ReadInfo {
        format: "stl-binary".into(),
        vertices_in_file: positions.len(),
        points: Some(count * 3),
        polygons: PolygonStats {
            polygons: count,
            triangles: count,
            ..Default::default()
        },
        warnings,
        ..ReadInfo::default()
    };
    Ok(ReadOutput {
        texcoords: None,
        mesh: TriMesh::new(positions, faces),
        info,
    })
}

/// Whitespace-separated tokens with their line numbers.
struct Tokens<'a> {
    text: &'a [u8],
    pos: usize,
    line: u64,
}

impl<'a> Tokens<'a> {
    fn next(&mut self) -> Option<(&'a [u8], u64)> {
        let t = self.text;
        while self.pos < t.len() && t[self.pos].is_ascii_whitespace() {
            if t[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= t.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < t.len() && !t[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some((&t[start..self.pos], self.line))
    }

    /// Skips the rest of the current line.
    fn skip_line(&mut self) {
        while self.pos < self.text.len() && self.text[self.pos] != b'\n' {
            self.pos += 1;
        }
    }
}

/// The name of ASCII STL in messages.
const ASCII_FMT: &str = "ASCII STL";

/// Reads ASCII STL: each `solid` block in turn, then the mesh.
fn read_ascii(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<ReadOutput, IoError> {
    let text = text::decode(bytes).map_err(|reason| {
        malformed(
            path,
            ASCII_FMT,
            Location::File,
            ProblemKind::Encoding { reason },
        )
    })?;
    let mut r = AsciiReader::new(path, &text);
    while r.solid_start()? {
        if !r.solid_body()? {
            break;
        }
    }
    std::mem::take(&mut r.problems).check(path, ASCII_FMT)?;
    Ok(r.finish(opts))
}

/// The state of an ASCII STL read: the tokens left, the points and polygons so far, the counts.
struct AsciiReader<'a> {
    path: &'a Path,
    tk: Tokens<'a>,
    ix: ExactIndexer,
    polys: Polygons,
    solids: usize,
    nan_normals: usize,
    warnings: Vec<String>,
    /// The problems read past (a coordinate or normal that is not a number, a loop of fewer
    /// than three corners); a structural one ends the read with them.
    problems: Problems,
}

impl<'a> AsciiReader<'a> {
    /// A reader at the start of `text`.
    fn new(path: &'a Path, text: &'a [u8]) -> AsciiReader<'a> {
        AsciiReader {
            path,
            tk: Tokens {
                text,
                pos: 0,
                line: 1,
            },
            ix: ExactIndexer::with_capacity(1024),
            polys: Polygons::default(),
            solids: 0,
            nan_normals: 0,
            warnings: Vec::new(),
            problems: Problems::default(),
        }
    }

    /// The error `kind` at `line` that ends the read, with the problems read past before it.
    fn err(&mut self, line: u64, kind: ProblemKind) -> IoError {
        let mut problems = std::mem::take(&mut self.problems);
        problems.push(Location::Line(line), kind);
        match problems.check(self.path, ASCII_FMT) {
            Err(e) => e,
            Ok(()) => unreachable!("a problem was just recorded"),
        }
    }

    /// The error of finding `found` at `line` where `expected` should be.
    fn expected(&mut self, line: u64, expected: &str, found: &[u8]) -> IoError {
        let kind = ProblemKind::Expected {
            expected: expected.into(),
            found: show(found),
        };
        self.err(line, kind)
    }

    /// The next token and its line; the file ending is an error naming what was `expected`.
    fn next_or(&mut self, expected: &str) -> Result<(&'a [u8], u64), IoError> {
        match self.tk.next() {
            Some(t) => Ok(t),
            None => {
                let kind = ProblemKind::UnexpectedEof {
                    expected: expected.into(),
                };
                Err(self.err(self.tk.line, kind))
            }
        }
    }

    /// Reads the keyword `word` (any case).
    fn expect_word(&mut self, word: &str) -> Result<(), IoError> {
        let expected = format!("'{word}'");
        match self.next_or(&expected)? {
            (t, _) if t.eq_ignore_ascii_case(word.as_bytes()) => Ok(()),
            (t, l) => Err(self.expected(l, &expected, t)),
        }
    }

    /// Reads the `solid` line that opens a block; false at the end of the file.
    fn solid_start(&mut self) -> Result<bool, IoError> {
        match self.tk.next() {
            None => Ok(false),
            Some((t, _)) if t.eq_ignore_ascii_case(b"solid") => {
                self.tk.skip_line();
                self.solids += 1;
                Ok(true)
            }
            Some((t, l)) => Err(self.expected(l, "'solid'", t)),
        }
    }

    /// Reads a block's facets and its `endsolid` line; false (with a warning) when the file
    /// ends before `endsolid`.
    fn solid_body(&mut self) -> Result<bool, IoError> {
        loop {
            let Some((t, l)) = self.tk.next() else {
                self.warnings.push(format!(
                    "solid {} has no 'endsolid' before the end of the file",
                    self.solids
                ));
                return Ok(false);
            };
            if t.eq_ignore_ascii_case(b"endsolid") {
                self.tk.skip_line();
                return Ok(true);
            }
            if !t.eq_ignore_ascii_case(b"facet") {
                return Err(self.expected(l, "'facet' or 'endsolid'", t));
            }
            self.facet()?;
        }
    }

    /// Reads one facet after its `facet` keyword: the optional normal, `outer loop`, the loop's
    /// vertices and `endfacet`; the loop becomes a polygon.
    fn facet(&mut self) -> Result<(), IoError> {
        let (mut t, mut l) = self.next_or("'outer loop'")?;
        if t.eq_ignore_ascii_case(b"normal") {
            self.normal()?;
            (t, l) = self.next_or("'outer loop'")?;
        }
        if !t.eq_ignore_ascii_case(b"outer") {
            return Err(self.expected(l, "'outer loop'", t));
        }
        self.expect_word("loop")?;
        let ring = self.ring()?;
        self.expect_word("endfacet")?;
        if let Some(ring) = ring {
            self.polys.push(ring);
        }
        Ok(())
    }

    /// Reads the three components after `normal`: they must be numbers, their values are not
    /// used; a normal with a component that is not finite is counted.
    fn normal(&mut self) -> Result<(), IoError> {
        let mut finite = true;
        for _ in 0..3 {
            let (v, vl) = self.next_or("a normal component")?;
            match text::number(v) {
                Ok(_) => {}
                Err(ProblemKind::NonFinite { .. }) => finite = false,
                Err(k) => self.problems.push(Location::Line(vl), k),
            }
        }
        self.nan_normals += usize::from(!finite);
        Ok(())
    }

    /// Reads a loop's `vertex` lines up to `endloop`; returns their indices, or `None` (the
    /// problem recorded) when a corner is not a point or there are fewer than three.
    fn ring(&mut self) -> Result<Option<Vec<u32>>, IoError> {
        let mut ring = Vec::with_capacity(3);
        let mut usable = true;
        loop {
            let (t, l) = self.next_or("'vertex' or 'endloop'")?;
            if t.eq_ignore_ascii_case(b"endloop") {
                if ring.len() < 3 && usable {
                    let kind = ProblemKind::TooFewCorners { found: ring.len() };
                    self.problems.push(Location::Line(l), kind);
                    usable = false;
                }
                return Ok(usable.then_some(ring));
            }
            if !t.eq_ignore_ascii_case(b"vertex") {
                return Err(self.expected(l, "'vertex' or 'endloop'", t));
            }
            match self.vertex()? {
                Some(p) => ring.push(self.ix.index(p)),
                None => usable = false,
            }
        }
    }

    /// Reads the three finite coordinates after `vertex`; `None` (the problems recorded) when
    /// one is not a finite number.
    fn vertex(&mut self) -> Result<Option<Point3>, IoError> {
        let mut p = [0.0; 3];
        let mut ok = true;
        for c in &mut p {
            let (v, vl) = self.next_or("a vertex coordinate")?;
            match text::coordinate(v) {
                Ok(x) => *c = x,
                Err(k) => {
                    self.problems.push(Location::Line(vl), k);
                    ok = false;
                }
            }
        }
        Ok(ok.then(|| Point3::new(p[0], p[1], p[2])))
    }

    /// The mesh (polygons triangulated) and the report, with the warning about non-finite
    /// normals last.
    fn finish(mut self, opts: &ReadOptions) -> ReadOutput {
        if self.nan_normals > 0 {
            self.warnings.push(format!(
                "{} facet normal(s) are not finite (ignored: the winding defines the normal)",
                self.nan_normals
            ));
        }
        let positions = self.ix.into_positions();
        let (faces, stats) = self.polys.triangulate(&positions, opts.quad_split);
        let info = ReadInfo {
            format: "stl-ascii".into(),
            vertices_in_file: positions.len(),
            points: Some(self.polys.corner_count()),
            solids: Some(self.solids),
            polygons: stats,
            warnings: self.warnings,
            ..ReadInfo::default()
        };
        ReadOutput {
            texcoords: None,
            mesh: TriMesh::new(positions, faces),
            info,
        }
    }
}

/// Unit normal of a face from its winding (zero when degenerate).
fn unit_normal(mesh: &TriMesh, f: usize) -> [f64; 3] {
    let n = mesh.face_cross(f);
    let l = n.norm();
    if l > 0.0 {
        (n / l).into()
    } else {
        [0.0; 3]
    }
}

/// Writes binary STL. Fails with `InvalidInput` naming the vertex when a coordinate is beyond
/// 32-bit float range.
pub fn write_binary(w: &mut impl Write, mesh: &TriMesh) -> std::io::Result<()> {
    if let Some((v, c)) = mesh.positions.iter().enumerate().find_map(|(i, p)| {
        p.iter()
            .find(|c| (**c as f32).is_infinite())
            .map(|c| (i, *c))
    }) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            OutOfRange {
                vertex: v,
                value: c,
                too_small: false,
            },
        ));
    }
    if let Some(value) = below_f32(mesh) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            OutOfRange {
                vertex: 0,
                value,
                too_small: true,
            },
        ));
    }
    let mut header = [b' '; 80];
    let tag = b"drapekit binary STL";
    header[..tag.len()].copy_from_slice(tag);
    w.write_all(&header)?;
    w.write_all(&(mesh.faces.len() as u32).to_le_bytes())?;
    let mut rec = [0u8; 50];
    for (f, face) in mesh.faces.iter().enumerate() {
        let n = unit_normal(mesh, f);
        for (k, v) in n.iter().enumerate() {
            rec[4 * k..4 * k + 4].copy_from_slice(&(*v as f32).to_le_bytes());
        }
        for (c, &vi) in face.iter().enumerate() {
            let p = mesh.positions[vi as usize];
            for k in 0..3 {
                let o = 12 + 12 * c + 4 * k;
                rec[o..o + 4].copy_from_slice(&(p[k] as f32).to_le_bytes());
            }
        }
        w.write_all(&rec)?;
    }
    Ok(())
}

/// The largest coordinate's magnitude of a mesh too small for 32-bit floats: nonzero and below
/// `f32::MIN_POSITIVE` (1.2e-38), where they keep less than their 24 bits (below it they are
/// multiples of 1.4e-45: a mesh 1e-44 across is rounded to a tenth of its size); `None` for
/// any other.
pub fn below_f32(mesh: &TriMesh) -> Option<f64> {
    let largest = (mesh.positions.iter())
        .flat_map(|p| p.iter().map(|c| c.abs()))
        .fold(0.0, f64::max);
    (largest > 0.0 && largest < f64::from(f32::MIN_POSITIVE)).then_some(largest)
}

/// A coordinate beyond 32-bit float range, or a mesh too small for them ([`below_f32`]), for
/// binary STL.
#[derive(Debug)]
pub struct OutOfRange {
    /// Vertex index (0 for a mesh too small).
    pub vertex: usize,
    /// The coordinate (the largest, for a mesh too small).
    pub value: f64,
    /// The whole mesh is too small, rather than one coordinate too large.
    pub too_small: bool,
}

impl std::fmt::Display for OutOfRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.too_small {
            return write!(
                f,
                "the mesh's largest coordinate {:e} is below 32-bit floats' normal range",
                self.value
            );
        }
        write!(
            f,
            "vertex {} coordinate {} is beyond 32-bit float range",
            self.vertex, self.value
        )
    }
}

impl std::error::Error for OutOfRange {}

/// Writes ASCII STL, one solid named `drapekit`.
pub fn write_ascii(w: &mut impl Write, mesh: &TriMesh) -> std::io::Result<()> {
    writeln!(w, "solid drapekit")?;
    for (f, face) in mesh.faces.iter().enumerate() {
        let n = unit_normal(mesh, f);
        writeln!(w, "  facet normal {:?} {:?} {:?}", n[0], n[1], n[2])?;
        writeln!(w, "    outer loop")?;
        for &v in face {
            let p = mesh.positions[v as usize];
            writeln!(w, "      vertex {:?} {:?} {:?}", p.x, p.y, p.z)?;
        }
        writeln!(w, "    endloop")?;
        writeln!(w, "  endfacet")?;
    }
    writeln!(w, "endsolid drapekit")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_ascii_stl_with_a_byte_order_mark_or_in_utf16_is_read_as_ascii() {
        // Its first bytes are not "solid": it was read as a binary STL promising 807,416,096
        // triangles.
        let s = "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n";
        let plain = read(Path::new("a.stl"), s.as_bytes(), &ReadOptions::default()).unwrap();
        let mut bom = b"\xEF\xBB\xBF".to_vec();
        bom.extend_from_slice(s.as_bytes());
        let mut utf16 = vec![0xFF, 0xFE];
        utf16.extend(s.encode_utf16().flat_map(|u| u.to_le_bytes()));
        for bytes in [bom, utf16] {
            let r = read(Path::new("a.stl"), &bytes, &ReadOptions::default()).unwrap();
            assert_eq!(r.mesh, plain.mesh);
            assert_eq!(r.info.format, "stl-ascii");
        }
    }

    #[test]
    fn every_problem_of_an_ascii_stl_is_listed_up_to_a_broken_structure() {
        let s = "solid t\n facet normal 0 0 x\n  outer loop\n   vertex 0 0 nan\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n  endloop\n endfacet\n facet\n  outer loop\n   vertex 0 0 0\n";
        let e = read(Path::new("a.stl"), s.as_bytes(), &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert_eq!(
            e.lines().collect::<Vec<_>>(),
            [
                "a.stl: 4 problems in this ASCII STL file:",
                "a.stl:2: 'x' is not a number",
                "a.stl:4: 'nan' is not a finite number: NaN and infinity are not coordinates",
                "a.stl:13: a face needs at least 3 corners, found 2",
                "a.stl:18: unexpected end of file: expected 'vertex' or 'endloop'",
            ],
            "{e}"
        );
    }

    #[test]
    fn multi_solid_tab_name_and_nan_normal() {
        let s = "solid\tfirst\n facet normal nan nan nan\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid first\n\
                 SOLID second\n FACET NORMAL 0 0 1\n  OUTER LOOP\n   VERTEX 0 0 1\n   VERTEX 1 0 1\n   VERTEX 0 1 1\n  ENDLOOP\n ENDFACET\nENDSOLID\n";
        let r = read(Path::new("a.stl"), s.as_bytes(), &ReadOptions::default()).unwrap();
        assert_eq!(r.mesh.faces.len(), 2);
        assert_eq!(r.info.solids, Some(2));
        assert_eq!(r.info.warnings.len(), 1);
    }

    #[test]
    fn binary_with_solid_header_round_trips() {
        let m = crate::mesh::generate::cube(2.0);
        let mut buf = Vec::new();
        write_binary(&mut buf, &m).unwrap();
        buf[..5].copy_from_slice(b"solid");
        let r = read(Path::new("b.stl"), &buf, &ReadOptions::default()).unwrap();
        assert_eq!(r.info.format, "stl-binary");
        // Same triangles, corner for corner (vertices are numbered in order of appearance).
        assert_eq!(r.mesh.faces.len(), m.faces.len());
        for f in 0..m.faces.len() {
            assert_eq!(r.mesh.corners(f), m.corners(f));
        }
    }

    #[test]
    fn truncated_and_oversized_binary() {
        let m = crate::mesh::generate::cube(2.0);
        let mut buf = Vec::new();
        write_binary(&mut buf, &m).unwrap();
        let e = read(
            Path::new("b.stl"),
            &buf[..84 + 50 * 5 + 20],
            &ReadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert_eq!(e, "b.stl: byte 334 (triangle 5): truncated binary STL: the header promises 12 triangles (684 bytes) but the file has 354 bytes; triangle 5 is incomplete");
        let mut long = buf.clone();
        long.extend_from_slice(&[0; 50]);
        let e = read(Path::new("b.stl"), &long, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("triangle count 12 disagrees with the file size: 12 triangles take 684 bytes, the file has 734"), "{e}");
    }
}
