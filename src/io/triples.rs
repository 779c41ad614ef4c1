//! Vertex triples: the AutoCAD-LISP export of the paper. A face is its corner points in order.
//!
//! Layouts read (and mixed within a file):
//! * one point per line, three lines a triangle (the paper's own export);
//! * faces between blank lines: a block of 3 points is a triangle, of 4 a quad;
//! * a whole face per line: 9 numbers a triangle, 12 a quad.
//!
//! Points may be written as LISP lists `(1.0 2.0 3.0)`; numbers are separated by spaces, tabs,
//! commas or semicolons. A line starting with `;` or `#` is a comment, `#` ends a line, and so
//! does a `;` followed by text that is not a number. Line ends may be LF, CRLF or CR.
//!
//! Which layout: when the file has several blank-line-separated blocks of points and most have
//! 3 or 4 points, every block is a face; otherwise each run of points is read three lines a
//! triangle (so a file of one run of 4 points is a triangle and a leftover point, an error: a
//! lone quad is written as 12 numbers on a line). A 4-point face with a repeated corner (an AutoCAD 3DFACE triangle) is one
//! triangle; other quads are split as `--quad-split` says (see `mesh::polygon`).
//!
//! Written: one point per line, three lines a triangle, each number in the shortest form that
//! reads back to the same `f64` bit for bit.

use super::error::{IoError, ProblemKind, Problems};
use super::text::{self, show};
use super::{ReadInfo, ReadOptions, ReadOutput};
use crate::math::Point3;
use crate::mesh::polygon::Polygons;
use crate::mesh::weld::ExactIndexer;
use crate::mesh::TriMesh;
use std::io::{BufRead, Write};
use std::path::Path;

const FORMAT: &str = "vertex-triples";

struct Block {
    points: Vec<(u64, Point3)>,
}

enum Item {
    Block(Block),
    Face(Vec<Point3>),
}

/// Reads vertex triples from `bytes` (`path` names the file in messages).
pub fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<ReadOutput, IoError> {
    read_from(path, &text::decode_file(path, FORMAT, bytes)?[..], opts)
}

/// Reads vertex triples (UTF-8) line by line from `reader`: memory grows with the points, not
/// with the lines.
pub fn read_from(
    path: &Path,
    reader: impl BufRead,
    opts: &ReadOptions,
) -> Result<ReadOutput, IoError> {
    let scan = scan_lines(path, reader)?;
    // Layout problems would only echo the lines already reported: stop here if there are any.
    scan.problems.check(path, FORMAT)?;
    let block_mode = is_block_mode(&scan.items);
    layout_problems(&scan.items, block_mode).check(path, FORMAT)?;
    let total_points: usize = scan.point_lines
        + scan
            .items
            .iter()
            .map(|i| if let Item::Face(p) = i { p.len() } else { 0 })
            .sum::<usize>();
    let (positions, polys) = polygons(&scan.items, block_mode, total_points);
    let (faces, stats) = polys.triangulate(&positions, opts.quad_split);
    let layout = layout_name(scan.point_lines > 0, scan.face_lines > 0, block_mode);
    let info = ReadInfo {
        format: FORMAT.into(),
        layout: Some(layout.into()),
        points: Some(total_points),
        vertices_in_file: positions.len(),
        polygons: stats,
        ..ReadInfo::default()
    };
    Ok(ReadOutput {
        texcoords: None,
        mesh: TriMesh::new(positions, faces),
        info,
    })
}

/// What the pass over the lines found: the blocks and faces in file order, and the problems
/// of the lines.
struct Scan {
    problems: Problems,
    items: Vec<Item>,
    /// The block of point lines being read.
    current: Option<Block>,
    /// The numbers of the line being read.
    nums: Vec<f64>,
    face_lines: usize,
    point_lines: usize,
}

/// Reads every line of `reader` into a [`Scan`].
fn scan_lines(path: &Path, reader: impl BufRead) -> Result<Scan, IoError> {
    let mut scan = Scan {
        problems: Problems::default(),
        items: Vec::new(),
        current: None,
        nums: Vec::with_capacity(12),
        face_lines: 0,
        point_lines: 0,
    };
    let mut lines = text::LineReader::new(reader);
    let io = text::line_error(path, FORMAT);
    while let Some((ln, line)) = lines.next_line().map_err(io)? {
        scan.line(ln, line.trim_ascii());
    }
    scan.end_block();
    Ok(scan)
}

impl Scan {
    /// Takes in line `ln` (trimmed): a blank line ends a block, a comment is skipped, 3 numbers
    /// are a point, 9 or 12 a face; any other count of numbers is a problem.
    fn line(&mut self, ln: u64, trimmed: &[u8]) {
        if trimmed.is_empty() {
            self.end_block();
            return;
        }
        if trimmed[0] == b';' || trimmed[0] == b'#' {
            return;
        }
        self.nums.clear();
        if let Err(kind) = numbers_of(trimmed, &mut self.nums) {
            self.problems.line(ln, kind);
            return;
        }
        match self.nums.len() {
            0 => {}
            3 => {
                self.point_lines += 1;
                let p = Point3::new(self.nums[0], self.nums[1], self.nums[2]);
                self.current
                    .get_or_insert_with(|| Block { points: Vec::new() })
                    .points
                    .push((ln, p));
            }
            9 | 12 => {
                self.face_lines += 1;
                self.end_block();
                let points = self.nums.chunks_exact(3);
                let face = points.map(|c| Point3::new(c[0], c[1], c[2])).collect();
                self.items.push(Item::Face(face));
            }
            n => self
                .problems
                .line(ln, ProblemKind::TriplesNumberCount { found: n }),
        }
    }

    /// Ends the block being read, if any.
    fn end_block(&mut self) {
        if let Some(b) = self.current.take() {
            self.items.push(Item::Block(b));
        }
    }
}

/// Whether every block is a face: several blocks, most of them of 3 or 4 points.
fn is_block_mode(items: &[Item]) -> bool {
    let sizes: Vec<usize> = items
        .iter()
        .filter_map(|i| match i {
            Item::Block(b) => Some(b.points.len()),
            Item::Face(_) => None,
        })
        .collect();
    let face_like = sizes.iter().filter(|&&s| s == 3 || s == 4).count();
    sizes.len() > 1 && 2 * face_like > sizes.len()
}

/// The blocks that do not fit the layout: in block mode those not of 3 or 4 points, else
/// those whose points are not whole triangles (at the first leftover point).
fn layout_problems(items: &[Item], block_mode: bool) -> Problems {
    let mut problems = Problems::default();
    for item in items {
        if let Item::Block(b) = item {
            let n = b.points.len();
            let first = b.points[0].0;
            let last = b.points[n - 1].0;
            if block_mode && n != 3 && n != 4 {
                problems.line(
                    first,
                    ProblemKind::TriplesBlock {
                        found: n,
                        first,
                        last,
                    },
                );
            } else if !block_mode && n % 3 != 0 {
                problems.line(
                    b.points[n - n % 3].0,
                    ProblemKind::TriplesLeftover { count: n % 3 },
                );
            }
        }
    }
    problems
}

/// The distinct points (by exact equality) and the polygons over them, in file order: each
/// face, each block in block mode, else each three points of a block.
fn polygons(items: &[Item], block_mode: bool, total_points: usize) -> (Vec<Point3>, Polygons) {
    let mut ix = ExactIndexer::with_capacity(total_points / 2 + 8);
    let mut polys = Polygons::with_capacity(total_points / 3);
    for item in items {
        match item {
            Item::Face(pts) => polys.push(pts.iter().map(|p| ix.index(*p))),
            Item::Block(b) if block_mode => polys.push(b.points.iter().map(|(_, p)| ix.index(*p))),
            Item::Block(b) => {
                for tri in b.points.chunks_exact(3) {
                    polys.push(tri.iter().map(|(_, p)| ix.index(*p)));
                }
            }
        }
    }
    (ix.into_positions(), polys)
}

/// The layout the report names, from whether there were point lines and face lines.
fn layout_name(point_lines: bool, face_lines: bool, block_mode: bool) -> &'static str {
    match (point_lines, face_lines, block_mode) {
        (true, true, _) => "mixed",
        (false, true, _) => "face per line",
        (true, false, true) => "faces between blank lines",
        (true, false, false) => "one point per line",
        (false, false, _) => "empty",
    }
}

/// The numbers on one line of vertex triples.
fn numbers_of(line: &[u8], out: &mut Vec<f64>) -> Result<(), ProblemKind> {
    let mut depth: i64 = 0;
    let mut i = 0;
    let n = line.len();
    while i < n {
        let c = line[i];
        match c {
            b'#' => break,
            b';' => {
                let rest = line[i + 1..].trim_ascii_start();
                let numeric = rest
                    .first()
                    .is_none_or(|&r| r.is_ascii_digit() || matches!(r, b'+' | b'-' | b'.' | b'('));
                if !numeric {
                    break;
                }
                i += 1;
            }
            b'(' => {
                depth += 1;
                i += 1;
            }
            b')' => {
                depth -= 1;
                if depth < 0 {
                    return Err(ProblemKind::UnbalancedParens);
                }
                i += 1;
            }
            b',' | b'\'' => i += 1,
            c if c.is_ascii_whitespace() => i += 1,
            _ => {
                let start = i;
                while i < n
                    && !matches!(line[i], b'(' | b')' | b',' | b';' | b'#' | b'\'')
                    && !line[i].is_ascii_whitespace()
                {
                    i += 1;
                }
                let tok = &line[start..i];
                out.push(text::coordinate(tok).map_err(|k| match k {
                    ProblemKind::NotANumber { .. } => ProblemKind::NotANumber { token: show(tok) },
                    k => k,
                })?);
            }
        }
    }
    if depth != 0 {
        return Err(ProblemKind::UnbalancedParens);
    }
    Ok(())
}

/// Writes `mesh` as vertex triples: one point per line, three lines a triangle.
pub fn write(w: &mut impl Write, mesh: &TriMesh) -> std::io::Result<()> {
    for f in &mesh.faces {
        for &v in f {
            let p = mesh.positions[v as usize];
            writeln!(w, "{:?} {:?} {:?}", p.x, p.y, p.z)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::polygon::QuadSplit;

    fn read_str(s: &str) -> Result<ReadOutput, IoError> {
        read(Path::new("t.txt"), s.as_bytes(), &ReadOptions::default())
    }

    #[test]
    fn layouts_agree() {
        let per_point = "0 0 0\n1 0 0\n0 1 0\n";
        let per_line = "0,0,0, 1,0,0, 0,1,0\n";
        let lisp = "; exported\r\n(0.0 0.0 0.0)\r\n(1.0 0.0 0.0)\r\n(0.0 1.0 0.0)\r\n";
        let semis = "0;0;0\n+1;-0.;.0e0\n0;1;0 ; corner three\n";
        let a = read_str(per_point).unwrap().mesh;
        for s in [per_line, lisp, semis] {
            assert_eq!(read_str(s).unwrap().mesh, a, "{s}");
        }
    }

    #[test]
    fn blocks_of_three_and_four() {
        let s = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n\n0 0 1\n1 0 1\n1 1 1\n\n";
        let r = read_str(s).unwrap();
        assert_eq!(r.mesh.faces.len(), 3);
        assert_eq!(r.info.polygons.quads, 1);
        let r = read(
            Path::new("t"),
            s.as_bytes(),
            &ReadOptions {
                quad_split: QuadSplit::Shortest,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(r.mesh.faces.len(), 3);
    }

    #[test]
    fn autocad_3dface_triangle() {
        let r = read_str("0 0 0 1 0 0 0 1 0 0 1 0\n").unwrap();
        assert_eq!(r.mesh.faces.len(), 1);
        assert_eq!(r.info.polygons.collapsed_quads, 1);
    }

    #[test]
    fn errors_name_lines() {
        let e = read_str("0 0 0\n1 0 0\n0 1 0\n5 5 5\n")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "t.txt:4: 1 point(s) left over at the end of a run of points (three lines a triangle): the last triangle is incomplete");
        let e = read_str("0 0 0\n1 0\n").unwrap_err().to_string();
        assert!(e.contains("t.txt:2: expected 3 numbers"), "{e}");
        let e = read_str("0 0 0\n1 0 x\n0 1 nan\n").unwrap_err().to_string();
        assert!(
            e.contains("t.txt:2: 'x' is not a number")
                && e.contains("t.txt:3: 'nan' is not a finite number"),
            "{e}"
        );
        let e = read_str("(0 0 0\n").unwrap_err().to_string();
        assert!(e.contains("t.txt:1: unbalanced parentheses"), "{e}");
    }

    #[test]
    fn write_round_trips_bit_exactly() {
        let mut m = crate::mesh::generate::icosphere(1);
        m.positions[0].x = 0.1 + 0.2;
        m.positions[1].y = -1e-300;
        let mut buf = Vec::new();
        write(&mut buf, &m).unwrap();
        let back = read_str(std::str::from_utf8(&buf).unwrap()).unwrap().mesh;
        assert_eq!(back.faces.len(), m.faces.len());
        for (f, g) in m.faces.iter().zip(&back.faces) {
            for k in 0..3 {
                assert_eq!(m.positions[f[k] as usize], back.positions[g[k] as usize]);
            }
        }
    }
}
