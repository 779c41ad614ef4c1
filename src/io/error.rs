//! The error type of reading and writing mesh files, with where in the file each problem is.

use std::fmt;
use std::path::PathBuf;

/// Where in a file a problem is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// A 1-based line of a text file.
    Line(u64),
    /// A byte offset of a binary file, and the record (e.g. `triangle 3`) there.
    Byte { offset: u64, record: String },
    /// A place in a glTF file's JSON, e.g. `meshes[0].primitives[1].indices`, with what is there.
    Key(String),
    /// The whole file.
    File,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(n) => write!(f, "line {n}"),
            Location::Byte { offset, record } if record.is_empty() => write!(f, "byte {offset}"),
            Location::Byte { offset, record } => write!(f, "byte {offset} ({record})"),
            Location::Key(k) => f.write_str(k),
            Location::File => Ok(()),
        }
    }
}

/// What is wrong at a location.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProblemKind {
    /// A token that should be a number is not one.
    #[error("'{token}' is not a number")]
    NotANumber { token: String },
    /// NaN or infinity where a coordinate belongs.
    #[error("'{token}' is not a finite number: NaN and infinity are not coordinates")]
    NonFinite { token: String },
    /// A coordinate too large for the mesh's volumes to be computed (`text::COORDINATE_MAX`).
    #[error("coordinate {value:e} is larger than {max:e} in magnitude: the mesh's volumes would overflow double precision (rescale it)")]
    TooLarge { value: f64, max: f64 },
    /// A vertex-triples line with the wrong number of numbers.
    #[error(
        "expected 3 numbers (a point), 9 (a triangle) or 12 (a quad) on a line, found {found}"
    )]
    TriplesNumberCount { found: usize },
    /// A blank-line-separated block of points that is not a face.
    #[error("a block of {found} points (lines {first}-{last}): a face between blank lines has 3 points (a triangle) or 4 (a quad)")]
    TriplesBlock { found: usize, first: u64, last: u64 },
    /// Points left after the last whole triangle.
    #[error("{count} point(s) left over at the end of a run of points (three lines a triangle): the last triangle is incomplete")]
    TriplesLeftover { count: usize },
    /// Parentheses that do not pair up.
    #[error("unbalanced parentheses")]
    UnbalancedParens,
    /// A vertex statement with too few coordinates.
    #[error("a vertex needs 3 coordinates, found {found}")]
    TooFewCoordinates { found: usize },
    /// A face with fewer than three corners.
    #[error("a face needs at least 3 corners, found {found}")]
    TooFewCorners { found: usize },
    /// A face index outside the vertex list.
    #[error("vertex index {index} is out of range: the file has {count} vertices")]
    IndexOutOfRange { index: i64, count: u64 },
    /// OBJ index zero.
    #[error("vertex index 0 is invalid: OBJ indices start at 1 (negative ones count back from the last vertex)")]
    ZeroIndex,
    /// A face corner that is not an index.
    #[error("'{token}' is not a vertex index")]
    BadIndex { token: String },
    /// A keyword or token other than the one the grammar wants.
    #[error("expected {expected}, found '{found}'")]
    Expected { expected: String, found: String },
    /// The file ends too early.
    #[error("unexpected end of file: expected {expected}")]
    UnexpectedEof { expected: String },
    /// A file too short to be binary STL and not ASCII STL.
    #[error("{size} bytes is too short for a binary STL (an 80-byte header and a 4-byte count) and the file does not start with 'solid'")]
    StlTooShort { size: u64 },
    /// A binary STL cut short.
    #[error("truncated binary STL: the header promises {count} triangles ({needed} bytes) but the file has {size} bytes; triangle {first_missing} is incomplete")]
    StlTruncated {
        count: u64,
        needed: u64,
        size: u64,
        first_missing: u64,
    },
    /// A binary STL longer than its count says.
    #[error("binary STL triangle count {count} disagrees with the file size: {count} triangles take {needed} bytes, the file has {size}")]
    StlCountMismatch { count: u64, needed: u64, size: u64 },
    /// A non-finite coordinate in binary data.
    #[error("non-finite coordinate {value}")]
    BinaryNonFinite { value: f64 },
    /// A PLY file without the `ply` magic line.
    #[error("not a PLY file: the first line is not 'ply'")]
    PlyMagic,
    /// An unknown PLY format line.
    #[error("unknown PLY format '{found}': expected 'format ascii 1.0', 'format binary_little_endian 1.0' or 'format binary_big_endian 1.0'")]
    PlyFormat { found: String },
    /// An unknown PLY scalar type.
    #[error("unknown PLY property type '{found}'")]
    PlyType { found: String },
    /// A PLY header line that cannot be parsed.
    #[error("malformed PLY header line '{line}': {reason}")]
    PlyHeader { line: String, reason: String },
    /// A PLY header without `end_header`.
    #[error("the PLY header has no 'end_header' line")]
    PlyNoEnd,
    /// A PLY body with fewer elements than the header promises.
    #[error(
        "the file ends in element '{element}' {index} of {count}: the header promises {count}"
    )]
    PlyShort {
        element: String,
        index: u64,
        count: u64,
    },
    /// An ASCII PLY record line with too few values.
    #[error("element '{element}' {index} has {found} values on its line; its properties need at least {needed}")]
    PlyValueCount {
        element: String,
        index: u64,
        found: usize,
        needed: usize,
    },
    /// The PLY vertex element lacks a coordinate.
    #[error("the PLY vertex element has no property '{name}'")]
    PlyMissingProperty { name: String },
    /// A negative list length.
    #[error("list length {count} is negative")]
    NegativeCount { count: i64 },
    /// A PLY list length or face index that is not a whole number.
    #[error(
        "element '{element}' {index}: {what} {value} is not a whole number: expected an integer"
    )]
    PlyNotInteger {
        element: String,
        index: u64,
        what: &'static str,
        value: f64,
    },
    /// A coordinate beyond the range of its declared PLY type.
    #[error(
        "coordinate {value:e} does not fit the declared type {ty} (at most {max:e} in magnitude)"
    )]
    PlyFloatRange {
        value: f64,
        ty: &'static str,
        max: f64,
    },
    /// A value out of range for its integer type.
    #[error("'{token}' is not a valid {ty}")]
    BadInteger { token: String, ty: String },
    /// A line (an OBJ statement with its continuation lines) past the text readers' limit.
    #[error("the line is longer than {limit} bytes (the text readers' limit, 1 MiB; an OBJ statement counts its continuation lines): no mesh statement is that long; is this a text mesh file?")]
    LineTooLong { limit: usize },
    /// Text that is not valid in its declared encoding.
    #[error("{reason}")]
    Encoding { reason: String },
    /// A binary glTF without the `glTF` magic.
    #[error("not a binary glTF: the file starts with {found}, expected the magic 'glTF'")]
    GlbMagic { found: String },
    /// A binary glTF of another version.
    #[error("binary glTF version {version}: drapekit reads version 2")]
    GlbVersion { version: u32 },
    /// A binary glTF cut short, or whose header disagrees with its size.
    #[error("truncated binary glTF: {what} needs {needed} bytes, the file has {size}")]
    GlbTruncated {
        what: String,
        needed: u64,
        size: u64,
    },
    /// A binary glTF whose chunks are not JSON then (optionally) BIN.
    #[error("{reason}")]
    GlbChunk { reason: String },
    /// JSON that is not a glTF document.
    #[error("the glTF JSON cannot be read: {message}")]
    GltfJson { message: String },
    /// An index into one of the file's arrays that is out of range.
    #[error("{what} {index} does not exist: the file has {count}")]
    GltfMissing {
        what: String,
        index: u64,
        count: u64,
    },
    /// Data that reaches past the end of its buffer or buffer view.
    #[error("{what} needs {needed} bytes, but {within} holds {available}")]
    GltfShort {
        what: String,
        needed: u64,
        within: String,
        available: u64,
    },
    /// A buffer's external file that cannot be read.
    #[error("buffer file '{file}' cannot be read: {reason}")]
    GltfBufferFile { file: String, reason: String },
    /// A primitive that is not triangles.
    #[error("primitive mode {mode}: drapekit reads triangles (mode 4, TRIANGLES) only")]
    GltfMode { mode: String },
    /// A triangle list whose length is not a multiple of three.
    #[error("{count} vertices do not make whole triangles: a triangle list has a multiple of 3")]
    GltfTriangleCount { count: u64 },
    /// Something valid glTF that drapekit does not read.
    #[error("{what} is not supported by drapekit's glTF reader")]
    GltfUnsupported { what: String },
    /// Instancing that would make the mesh larger than drapekit reads.
    #[error("the scene places {vertices} vertices (meshes used by several nodes are copied), more than the {limit} drapekit reads")]
    GltfTooLarge { vertices: u64, limit: u64 },
}

/// One problem and where it is.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    /// Where.
    pub at: Location,
    /// What.
    pub kind: ProblemKind,
}

/// Errors of reading and writing mesh files.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The file has no bytes.
    #[error("{}: the file is empty (0 bytes): expected a mesh", path.display())]
    Empty { path: PathBuf },
    /// Neither the extension nor the content tells the format.
    #[error("{}: cannot tell the mesh format: {reason}; give --from triples|obj|stl|ply|gltf", path.display())]
    UnknownFormat { path: PathBuf, reason: String },
    /// The content is malformed; every problem found is listed.
    #[error("{}", list_problems(path, format, problems, *more))]
    Malformed {
        path: PathBuf,
        format: &'static str,
        problems: Vec<Problem>,
        more: usize,
    },
    /// More vertices than 32-bit indices hold.
    #[error("{}: {count} vertices is more than drapekit's 32-bit indices hold", path.display())]
    TooLarge { path: PathBuf, count: u64 },
    /// The output could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The output path is an input file.
    #[error("refusing to write {}: it is the input file {}; an input is never overwritten", path.display(), input.display())]
    WouldOverwriteInput { path: PathBuf, input: PathBuf },
    /// A non-finite coordinate reached a writer.
    #[error("cannot write {}: vertex {vertex} has a non-finite coordinate", path.display())]
    NonFinite { path: PathBuf, vertex: usize },
    /// A coordinate too large for 32-bit float (binary STL).
    #[error("cannot write {}: vertex {vertex} has coordinate {value:e}, beyond 32-bit float range (binary STL and glTF store 32-bit floats); write PLY, OBJ or --ascii STL", path.display())]
    OutOfFloatRange {
        path: PathBuf,
        vertex: usize,
        value: f64,
    },
    /// A mesh too small for 32-bit floats (binary STL, glTF): `value` is its largest coordinate.
    #[error("cannot write {}: the mesh's largest coordinate is {value:e}, below 32-bit floats' normal range ({:e}): binary STL and glTF would round its shape away; write PLY, OBJ or --ascii STL, or rescale it (--to-units)", path.display(), f32::MIN_POSITIVE)]
    TooSmallForFloat { path: PathBuf, value: f64 },
    /// Vertex colours that do not fit their mesh (glTF writer).
    #[error("cannot write {}: {reason}", path.display())]
    BadColors { path: PathBuf, reason: String },
    /// Frames that cannot be an animation (glTF writer).
    #[error("cannot write {}: {reason}", path.display())]
    BadAnimation { path: PathBuf, reason: String },
    /// The output format is not known.
    #[error("cannot write {}: unknown output format for extension '{ext}'; give --to triples|obj|stl|ply|glb|gltf", path.display())]
    UnknownOutputFormat { path: PathBuf, ext: String },
}

/// At most this many problems are listed; the rest are counted.
pub const MAX_PROBLEMS: usize = 20;

fn list_problems(
    path: &std::path::Path,
    format: &str,
    problems: &[Problem],
    more: usize,
) -> String {
    let p = path.display();
    let mut lines: Vec<String> = problems
        .iter()
        .map(|pr| match &pr.at {
            Location::Line(n) => format!("{p}:{n}: {}", pr.kind),
            Location::File => format!("{p}: {}", pr.kind),
            at => format!("{p}: {at}: {}", pr.kind),
        })
        .collect();
    if problems.len() > 1 || more > 0 {
        lines.insert(
            0,
            format!(
                "{p}: {} problems in this {format} file:",
                problems.len() + more
            ),
        );
    }
    if more > 0 {
        lines.push(format!("... and {more} more"));
    }
    lines.join("\n")
}

/// Collects problems, keeping the first [`MAX_PROBLEMS`].
#[derive(Debug, Default)]
pub struct Problems {
    list: Vec<Problem>,
    more: usize,
}

impl Problems {
    /// Records a problem.
    pub fn push(&mut self, at: Location, kind: ProblemKind) {
        if self.list.len() < MAX_PROBLEMS {
            self.list.push(Problem { at, kind });
        } else {
            self.more += 1;
        }
    }

    /// Records a problem on a line.
    pub fn line(&mut self, line: u64, kind: ProblemKind) {
        self.push(Location::Line(line), kind);
    }

    /// How many were recorded (listed or counted).
    pub fn count(&self) -> usize {
        self.list.len() + self.more
    }

    /// Whether none was recorded.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// `Ok(())` when empty, else the error listing them.
    pub fn check(self, path: &std::path::Path, format: &'static str) -> Result<(), IoError> {
        if self.list.is_empty() {
            Ok(())
        } else {
            Err(IoError::Malformed {
                path: path.to_path_buf(),
                format,
                problems: self.list,
                more: self.more,
            })
        }
    }
}

/// A one-problem error.
pub fn malformed(
    path: &std::path::Path,
    format: &'static str,
    at: Location,
    kind: ProblemKind,
) -> IoError {
    IoError::Malformed {
        path: path.to_path_buf(),
        format,
        problems: vec![Problem { at, kind }],
        more: 0,
    }
}
