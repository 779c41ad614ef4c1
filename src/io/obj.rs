//! Wavefront OBJ: `v` positions and `f` faces; everything else is read past.
//!
//! Read: `v x y z [w | r g b]` (the first three numbers), `f` corners as `v`, `v/vt`, `v/vt/vn`
//! or `v//vn`, with 1-based indices; a negative index counts back from the vertices read so far
//! (`-1` is the last one); a positive index may refer to a vertex defined later in the file.
//! Lines ending in `\` continue on the next. Texture coordinates, normals, groups, objects,
//! smoothing groups and materials (`usemtl` with any name, even none) are skipped; `l` and `p`
//! elements and free-form geometry are skipped with a warning. UTF-8 (with or without a
//! byte-order mark) and UTF-16 files are read. N-gons, concave ones included, are ear-clipped
//! (see `mesh::polygon`).
//!
//! Written: `v x y z` with each number in its shortest exact form, then `f a b c` (1-based).

use super::error::{IoError, ProblemKind, Problems};
use super::text::{self, show, words};
use super::{ReadInfo, ReadOptions, ReadOutput};
use crate::math::Point3;
use crate::mesh::polygon::Polygons;
use crate::mesh::TriMesh;
use std::collections::BTreeMap;
use std::io::{BufRead, Write};
use std::path::Path;

const FORMAT: &str = "OBJ";

/// Statements skipped without comment.
const SKIPPED: &[&[u8]] = &[
    b"vn",
    b"vp",
    b"o",
    b"g",
    b"s",
    b"usemtl",
    b"mtllib",
    b"usemap",
    b"maplib",
    b"lod",
    b"bevel",
    b"c_interp",
    b"d_interp",
    b"shadow_obj",
    b"trace_obj",
    b"mg",
];
/// Free-form geometry statements, skipped with a warning.
const FREEFORM: &[&[u8]] = &[
    b"cstype", b"deg", b"bmat", b"step", b"curv", b"curv2", b"surf", b"parm", b"trim", b"hole",
    b"scrv", b"sp", b"end", b"con", b"ctech", b"stech",
];

/// Reads OBJ from `bytes` (`path` names the file in messages).
pub fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<ReadOutput, IoError> {
    read_from(path, &text::decode_file(path, FORMAT, bytes)?[..], opts)
}

/// Reads OBJ (UTF-8) line by line from `reader`: memory grows with the mesh, not the file.
pub fn read_from(
    path: &Path,
    reader: impl BufRead,
    opts: &ReadOptions,
) -> Result<ReadOutput, IoError> {
    let mut st = State::default();
    let mut lines = text::LineReader::new(reader);
    let io = text::line_error(path, FORMAT);
    let mut logical: Vec<u8> = Vec::new();
    while let Some((ln, raw)) = lines.next_line().map_err(io)? {
        if !continues(raw) {
            st.statement(ln, raw);
            continue;
        }
        // Join continuation lines; the statement keeps the number of its first line.
        logical.clear();
        push_continued(&mut logical, raw);
        while let Some((_, part)) = lines.next_line().map_err(io)? {
            let last = !continues(part);
            if last {
                logical.extend_from_slice(part);
            } else {
                push_continued(&mut logical, part);
            }
            if logical.len() > text::MAX_LINE {
                return Err(io(text::LineError::TooLong { line: ln }));
            }
            if last {
                break;
            }
        }
        st.statement(ln, &logical);
    }
    st.finish(path, opts)
}

/// Whether a line ends in `\\` (continues on the next).
fn continues(line: &[u8]) -> bool {
    line.trim_ascii_end().ends_with(b"\\")
}

/// Appends a continued line without its `\\`, and a blank in its place.
fn push_continued(logical: &mut Vec<u8>, part: &[u8]) {
    let t = part.trim_ascii_end();
    logical.extend_from_slice(&t[..t.len() - 1]);
    logical.push(b' ');
}

/// What the statements read so far hold.
struct State {
    problems: Problems,
    positions: Vec<Point3>,
    /// Faces: corner indices (0-based, maybe past the end until checked) and their lines.
    polys: Polygons,
    face_lines: Vec<u64>,
    ring: Vec<u32>,
    skipped: BTreeMap<String, (usize, u64)>,
    /// Texture coordinates (`vt`) read, and whether they can still be per-vertex: every one
    /// readable and every face corner naming a `vt` naming its vertex's own index.
    texcoords: Vec<[f64; 2]>,
    texcoords_per_vertex: bool,
}

impl Default for State {
    fn default() -> State {
        State {
            problems: Problems::default(),
            positions: Vec::new(),
            polys: Polygons::default(),
            face_lines: Vec::new(),
            ring: Vec::new(),
            skipped: BTreeMap::new(),
            texcoords: Vec::new(),
            texcoords_per_vertex: true,
        }
    }
}

impl State {
    /// Reads one statement (continuations joined) of line `ln`.
    fn statement(&mut self, ln: u64, line: &[u8]) {
        let line = match line.iter().position(|&b| b == b'#') {
            Some(i) => &line[..i],
            None => line,
        };
        let mut w = words(line);
        let Some(key) = w.next() else { return };
        match key {
            b"v" => self.vertex(ln, w),
            b"f" | b"fo" => self.face(ln, w),
            b"vt" => self.texcoord(w),
            k if SKIPPED.contains(&k) => {}
            k => {
                let name = if FREEFORM.contains(&k) {
                    "free-form geometry".to_string()
                } else {
                    format!("'{}'", show(k))
                };
                let e = self.skipped.entry(name).or_insert((0, ln));
                e.0 += 1;
            }
        }
    }

    fn vertex<'a>(&mut self, ln: u64, w: impl Iterator<Item = &'a [u8]>) {
        let mut xyz = [0.0; 3];
        let mut found = 0;
        let mut bad = false;
        for tok in w.take(3) {
            match text::coordinate(tok) {
                Ok(v) => xyz[found] = v,
                Err(k) => {
                    self.problems.line(ln, k);
                    bad = true;
                }
            }
            found += 1;
        }
        if found < 3 {
            self.problems
                .line(ln, ProblemKind::TooFewCoordinates { found });
        } else if !bad {
            self.positions.push(Point3::new(xyz[0], xyz[1], xyz[2]));
        } else {
            self.positions.push(Point3::origin());
        }
    }

    /// A `vt u [v [w]]` line: kept as `[u, v]`. Texture coordinates never stop a read: one
    /// that is unreadable only means the file has no per-vertex coordinates.
    fn texcoord<'a>(&mut self, mut w: impl Iterator<Item = &'a [u8]>) {
        let mut uv = [0.0; 2];
        for c in &mut uv {
            match w.next().map(text::number) {
                Some(Ok(v)) => *c = v,
                Some(Err(_)) => self.texcoords_per_vertex = false,
                None => {}
            }
        }
        self.texcoords.push(uv);
    }

    /// Whether face corner `tok` (`v/vt/vn`) names a `vt` other than its vertex `v` (0-based).
    fn corner_texcoord_differs(&self, tok: &[u8], v: u32) -> bool {
        let Some(t) = tok.split(|&b| b == b'/').nth(1).filter(|t| !t.is_empty()) else {
            return false;
        };
        let count = self.texcoords.len() as i64;
        match std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse::<i64>().ok())
        {
            Some(i) if i > 0 => i - 1 != i64::from(v),
            Some(i) if i < 0 => count + i != i64::from(v),
            _ => true,
        }
    }

    fn face<'a>(&mut self, ln: u64, w: impl Iterator<Item = &'a [u8]>) {
        self.ring.clear();
        let count = self.positions.len() as i64;
        let before = self.problems.count();
        for tok in w {
            let idx = tok.split(|&b| b == b'/').next().unwrap_or(tok);
            match std::str::from_utf8(idx)
                .ok()
                .and_then(|s| s.parse::<i64>().ok())
            {
                Some(0) => self.problems.line(ln, ProblemKind::ZeroIndex),
                Some(i) if (i < 0 && count + i < 0) || i > i64::from(u32::MAX) => {
                    self.problems.line(
                        ln,
                        ProblemKind::IndexOutOfRange {
                            index: i,
                            count: count as u64,
                        },
                    )
                }
                Some(i) => {
                    let v = if i < 0 { count + i } else { i - 1 } as u32;
                    if self.corner_texcoord_differs(tok, v) {
                        self.texcoords_per_vertex = false;
                    }
                    self.ring.push(v);
                }
                None => self
                    .problems
                    .line(ln, ProblemKind::BadIndex { token: show(tok) }),
            }
        }
        if self.problems.count() == before {
            if self.ring.len() < 3 {
                self.problems.line(
                    ln,
                    ProblemKind::TooFewCorners {
                        found: self.ring.len(),
                    },
                );
            } else {
                self.polys.push(self.ring.iter().copied());
                self.face_lines.push(ln);
            }
        }
    }

    /// Checks forward references now that every vertex is known, and triangulates.
    fn finish(self, path: &Path, opts: &ReadOptions) -> Result<ReadOutput, IoError> {
        self.problems.check(path, FORMAT)?;
        let n = self.positions.len();
        let mut problems = Problems::default();
        for (ring, &ln) in self.polys.iter().zip(&self.face_lines) {
            for &c in ring.iter().filter(|&&c| c as usize >= n) {
                problems.line(
                    ln,
                    ProblemKind::IndexOutOfRange {
                        index: i64::from(c) + 1,
                        count: n as u64,
                    },
                );
            }
        }
        problems.check(path, FORMAT)?;
        super::check_vertex_count(path, n)?;
        let (faces, stats) = self.polys.triangulate(&self.positions, opts.quad_split);
        let warnings = self
            .skipped
            .iter()
            .map(|(name, (count, line))| match name.as_str() {
                "'l'" => format!("{count} line element(s) (l) skipped, first at line {line}"),
                "'p'" => format!("{count} point element(s) (p) skipped, first at line {line}"),
                _ => format!("{count} unknown statement(s) {name} skipped, first at line {line}"),
            })
            .collect();
        let info = ReadInfo {
            format: FORMAT.to_lowercase(),
            vertices_in_file: n,
            polygons: stats,
            warnings,
            ..ReadInfo::default()
        };
        let texcoords = (self.texcoords_per_vertex && self.texcoords.len() == n && n > 0)
            .then_some(self.texcoords);
        Ok(ReadOutput {
            mesh: TriMesh::new(self.positions, faces),
            info,
            texcoords,
        })
    }
}

/// Writes `mesh` as OBJ with `rest[i]` as vertex `i`'s texture coordinates (`vt u v`, one per
/// vertex, each number in its shortest exact form) and faces `f a/a b/b c/c`. drapekit puts
/// each particle's flat pattern place there, in the unit of `v`: `render --color strain` reads
/// the rest lengths back from them. `rest` must have one entry per vertex.
pub fn write_with_rest(
    w: &mut impl Write,
    mesh: &TriMesh,
    rest: &[[f64; 2]],
    groups: &[(String, usize, usize)],
) -> std::io::Result<()> {
    assert_eq!(
        rest.len(),
        mesh.positions.len(),
        "one rest point per vertex"
    );
    writeln!(
        w,
        "# drapekit: {} vertices, {} triangles; vt = flat pattern (rest) coordinates",
        mesh.positions.len(),
        mesh.faces.len()
    )?;
    for p in &mesh.positions {
        writeln!(w, "v {:?} {:?} {:?}", p.x, p.y, p.z)?;
    }
    for t in rest {
        writeln!(w, "vt {:?} {:?}", t[0], t[1])?;
    }
    let whole = [(String::new(), 0, mesh.faces.len())];
    let groups = if groups.is_empty() {
        &whole[..]
    } else {
        groups
    };
    for (name, first, count) in groups {
        if !name.is_empty() {
            writeln!(w, "g {name}")?;
        }
        for f in &mesh.faces[*first..first + count] {
            let [a, b, c] = f.map(|v| v + 1);
            writeln!(w, "f {a}/{a} {b}/{b} {c}/{c}")?;
        }
    }
    Ok(())
}

/// Writes `mesh` as OBJ.
pub fn write(w: &mut impl Write, mesh: &TriMesh) -> std::io::Result<()> {
    writeln!(
        w,
        "# drapekit: {} vertices, {} triangles",
        mesh.positions.len(),
        mesh.faces.len()
    )?;
    for p in &mesh.positions {
        writeln!(w, "v {:?} {:?} {:?}", p.x, p.y, p.z)?;
    }
    for f in &mesh.faces {
        writeln!(w, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_str(s: &str) -> Result<ReadOutput, IoError> {
        read(Path::new("m.obj"), s.as_bytes(), &ReadOptions::default())
    }

    #[test]
    fn negative_and_forward_indices() {
        let r = read_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nf 1 2 4\nv 1 1 0\n").unwrap();
        assert_eq!(r.mesh.faces, vec![[0, 1, 2], [0, 1, 3]]);
    }

    #[test]
    fn continuation_and_slashes() {
        let r = read_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1 \\\n 2//2 3/3\n").unwrap();
        assert_eq!(r.mesh.faces, vec![[0, 1, 2]]);
    }

    #[test]
    fn rest_coordinates_round_trip_per_vertex() {
        let mesh = TriMesh::new(
            vec![
                Point3::new(0.0, 0.0, 0.5),
                Point3::new(1.0, 0.0, 0.5),
                Point3::new(0.0, 1.0, 0.5),
            ],
            vec![[0, 1, 2]],
        );
        let rest = [[0.0, 0.0], [0.9, 0.0], [0.1, 0.95]];
        let mut buf = Vec::new();
        write_with_rest(&mut buf, &mesh, &rest, &[("front".into(), 0, 1)]).unwrap();
        let r = read(Path::new("m.obj"), &buf, &ReadOptions::default()).unwrap();
        assert_eq!(r.mesh, mesh);
        assert_eq!(r.texcoords.as_deref(), Some(&rest[..]));
        // Coordinates that are not one per vertex are not per-vertex coordinates.
        let r =
            read_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/3 3/2\n").unwrap();
        assert_eq!(r.texcoords, None);
        let r = read_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nf 1/1 2/2 3\n").unwrap();
        assert_eq!(r.texcoords, None);
        let r = read_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt x 1\nf 1 2 3\n").unwrap();
        assert_eq!(
            r.texcoords, None,
            "an unreadable vt is no error, and no coordinates"
        );
    }

    #[test]
    fn all_problems_reported() {
        let e = read_str("v 0 0 0\nv 1 0\nf 1 2 9\nf 0 1 2\nf 1 2\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("m.obj:2: a vertex needs 3 coordinates, found 2"),
            "{e}"
        );
        assert!(e.contains("m.obj:4: vertex index 0 is invalid"), "{e}");
        assert!(
            e.contains("m.obj:5: a face needs at least 3 corners, found 2"),
            "{e}"
        );
        let e = read_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "m.obj:4: vertex index 9 is out of range: the file has 3 vertices"
        );
    }
}
