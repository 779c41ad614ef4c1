//! Reading and writing meshes: vertex triples, OBJ, STL, PLY and glTF 2.0 (`.gltf`, `.glb`).
//!
//! [`read_mesh`] picks the format from `--from`, else the extension, else the content, and
//! returns an indexed [`TriMesh`] plus a [`ReadInfo`] of what the file held. Readers reject
//! non-finite coordinates and name the line (text) or byte offset (binary) of every problem.
//! [`write_mesh`] and [`write_atomic`] write to a temporary file beside the target and rename
//! it into place, so a failed write never leaves a half-written file, and refuse to overwrite
//! an input. [`stage_mesh`] and [`stage`] stop before the rename: [`commit`] renames several
//! outputs together at the end of a run, so a run that fails earlier changes none of them.
//! [`is_safe_file_name`] keeps names that become file names inside an output folder.
//!
//! The readers are drapekit's own: tobj 4.0.5, stl_io 0.10 and ply-rs fail or misread files
//! in `shared/realdata/meshes` (see `READER_PROBE.tsv` there and the README), and their errors
//! carry no line numbers. glTF's JSON is parsed by the `gltf-json` crate ([`gltf`]).

pub mod error;
pub mod gltf;
pub mod obj;
pub mod ply;
pub mod stl;
mod text;
pub mod triples;

pub use error::{IoError, Location, Problem, ProblemKind};

use crate::mesh::polygon::{PolygonStats, QuadSplit};
use crate::mesh::TriMesh;
use serde::Serialize;
use std::fmt;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// A mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// AutoCAD-LISP vertex triples (`.txt`, `.tri`).
    Triples,
    /// Wavefront OBJ.
    Obj,
    /// STL, ASCII or binary.
    Stl,
    /// PLY, ASCII or binary.
    Ply,
    /// glTF 2.0 as JSON (`.gltf`; written with the buffer in a `data:` URI).
    Gltf,
    /// glTF 2.0 binary (`.glb`).
    Glb,
}

impl FromStr for Format {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "triples" | "txt" | "tri" => Ok(Format::Triples),
            "obj" => Ok(Format::Obj),
            "stl" => Ok(Format::Stl),
            "ply" => Ok(Format::Ply),
            "gltf" => Ok(Format::Gltf),
            "glb" => Ok(Format::Glb),
            _ => Err(format!(
                "unknown format '{s}': expected triples, obj, stl, ply, gltf or glb"
            )),
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Triples => "triples",
            Format::Obj => "obj",
            Format::Stl => "stl",
            Format::Ply => "ply",
            Format::Gltf => "gltf",
            Format::Glb => "glb",
        })
    }
}

impl Format {
    /// The format an extension names (`.txt`, `.tri`, `.lsp.txt`, `.obj`, `.stl`, `.ply`,
    /// `.gltf`, `.glb`, any case).
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "txt" | "tri" => Some(Format::Triples),
            "obj" => Some(Format::Obj),
            "stl" => Some(Format::Stl),
            "ply" => Some(Format::Ply),
            "gltf" => Some(Format::Gltf),
            "glb" => Some(Format::Glb),
            _ => None,
        }
    }

    /// Whether the format is glTF, JSON or binary (one reader for both).
    pub fn is_gltf(self) -> bool {
        matches!(self, Format::Gltf | Format::Glb)
    }

    /// The format the content shows, if it is unmistakable.
    pub fn sniff(bytes: &[u8]) -> Option<Format> {
        Format::sniff_head(bytes, bytes.len() as u64)
    }

    /// The format shown by `bytes`, the start of a file of `len` bytes.
    pub fn sniff_head(bytes: &[u8], len: u64) -> Option<Format> {
        if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
            return Some(Format::Ply);
        }
        if bytes.starts_with(gltf::glb::MAGIC) {
            return Some(Format::Glb);
        }
        let json = bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]).unwrap_or(bytes);
        if json.trim_ascii_start().starts_with(b"{")
            && json.windows(7).take(1 << 16).any(|w| w == b"\"asset\"")
        {
            return Some(Format::Gltf);
        }
        if stl::is_binary_len(bytes, len) {
            return Some(Format::Stl);
        }
        let decoded = text::decode(bytes).ok()?;
        let t: &[u8] = &decoded;
        if stl::starts_with_solid(t)
            && t.windows(5)
                .take(4096)
                .any(|w| w.eq_ignore_ascii_case(b"facet") || w.eq_ignore_ascii_case(b"endso"))
        {
            return Some(Format::Stl);
        }
        for (_, line) in text::lines(t).take(1000) {
            let l = line.trim_ascii();
            if l.is_empty() || l[0] == b'#' || l[0] == b';' {
                continue;
            }
            let first = text::words(l).next().unwrap_or(l);
            return match first {
                b"v" | b"f" | b"vt" | b"vn" | b"o" | b"g" | b"s" | b"mtllib" | b"usemtl" => {
                    Some(Format::Obj)
                }
                _ if l[0].is_ascii_digit() || matches!(l[0], b'-' | b'+' | b'.' | b'(') => {
                    Some(Format::Triples)
                }
                _ => None,
            };
        }
        None
    }
}

/// How to read a mesh file.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReadOptions {
    /// The format; `None` decides from the extension, then the content (default).
    pub format: Option<Format>,
    /// How quads are split (default: the paper's way).
    pub quad_split: QuadSplit,
}

/// What a file held, as read.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ReadInfo {
    /// `triples`, `obj`, `stl-ascii`, `stl-binary`, `ply-ascii`, `ply-binary-le`, `ply-binary-be`, `gltf`, `glb`.
    pub format: String,
    /// Vertex-triples layout found.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layout: Option<String>,
    /// Points (face corners) read, for formats that list points per face.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub points: Option<usize>,
    /// Distinct vertices after reading (exact duplicates merged for index-free formats).
    pub vertices_in_file: usize,
    /// ASCII STL solids read.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub solids: Option<usize>,
    /// Face records and their triangulation.
    pub polygons: PolygonStats,
    /// What was skipped or odd but not fatal.
    pub warnings: Vec<String>,
}

/// A mesh and what its file held.
#[derive(Debug, Clone)]
pub struct ReadOutput {
    /// The mesh, as read (not welded, cleaned or oriented).
    pub mesh: TriMesh,
    /// What the file held.
    pub info: ReadInfo,
    /// Per-vertex texture coordinates (OBJ `vt`), when the file has exactly one per vertex and
    /// every face corner that names one names its vertex's own: drapekit's drape and garment
    /// outputs carry each particle's flat pattern place there (see `obj::write_with_rest`).
    pub texcoords: Option<Vec<[f64; 2]>>,
}

/// Bytes read from the start of a file to tell its format (sniffing reads up to 1000 lines).
const SNIFF_BYTES: u64 = 1 << 20;

/// Reads a mesh file. OBJ and vertex triples in UTF-8 are read line by line from the file
/// (memory grows with the mesh, not the file); other files are read whole.
pub fn read_mesh(path: &Path, opts: &ReadOptions) -> Result<ReadOutput, IoError> {
    let rerr = |source| IoError::Read {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(rerr)?;
    let len = file.metadata().map_err(rerr)?.len();
    let mut reader = std::io::BufReader::with_capacity(1 << 16, file);
    let mut head = Vec::new();
    (&mut reader)
        .take(SNIFF_BYTES)
        .read_to_end(&mut head)
        .map_err(rerr)?;
    if (head.len() as u64) < SNIFF_BYTES {
        return read_bytes(path, &head, opts);
    }
    let (format, note) = choose_format(path, opts, Format::sniff_head(&head, len))?;
    let utf8 = matches!(text::decode(&head), Ok(std::borrow::Cow::Borrowed(_)));
    if !(utf8 && matches!(format, Format::Obj | Format::Triples)) {
        reader.read_to_end(&mut head).map_err(rerr)?;
        return read_bytes(path, &head, opts);
    }
    let bom = if head.starts_with(&[0xEF, 0xBB, 0xBF]) {
        3
    } else {
        0
    };
    let stream = std::io::Cursor::new(&head[bom..]).chain(reader);
    let mut out = match format {
        Format::Obj => obj::read_from(path, stream, opts),
        _ => triples::read_from(path, stream, opts),
    }?;
    if let Some(n) = note {
        out.info.warnings.insert(0, n);
    }
    Ok(out)
}

/// Reads a mesh from bytes; `path` names it in messages and its extension may tell the format.
pub fn read_bytes(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<ReadOutput, IoError> {
    if bytes.is_empty() {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    let (format, note) = choose_format(path, opts, Format::sniff(bytes))?;
    let mut out = match format {
        Format::Triples => triples::read(path, bytes, opts),
        Format::Obj => obj::read(path, bytes, opts),
        Format::Stl => stl::read(path, bytes, opts),
        Format::Ply => ply::read(path, bytes, opts),
        Format::Gltf | Format::Glb => gltf::read(path, bytes),
    }?;
    if let Some(n) = note {
        out.info.warnings.insert(0, n);
    }
    Ok(out)
}

/// The format to read: `--from`, else the extension, else what the content shows (`sniffed`),
/// with a note when the content overrules the extension.
fn choose_format(
    path: &Path,
    opts: &ReadOptions,
    sniffed: Option<Format>,
) -> Result<(Format, Option<String>), IoError> {
    Ok(match (opts.format, Format::from_path(path), sniffed) {
        (Some(f), _, _) => (f, None),
        // Content that is unmistakably PLY, STL or glTF wins over a misleading extension.
        (None, Some(ext), Some(s))
            if ext != s
                && !(ext.is_gltf() && s.is_gltf())
                && matches!(s, Format::Ply | Format::Stl | Format::Gltf | Format::Glb) =>
        {
            (
            s,
            Some(format!(
                "the extension says {ext} but the content is {s}: read as {s}"
            )),
        )
        }
        (None, Some(ext), _) => (ext, None),
        (None, None, Some(s)) => (s, None),
        (None, None, None) => {
            return Err(IoError::UnknownFormat {
                path: path.to_path_buf(),
                reason: "the extension is not .txt/.tri/.obj/.stl/.ply/.gltf/.glb and the content is none of vertex triples, OBJ, STL, PLY or glTF".into(),
            })
        }
    })
}

/// Refuses meshes whose vertex count does not fit 32-bit indices.
fn check_vertex_count(path: &Path, n: usize) -> Result<(), IoError> {
    if n >= u32::MAX as usize {
        return Err(IoError::TooLarge {
            path: path.to_path_buf(),
            count: n as u64,
        });
    }
    Ok(())
}

/// How to write a mesh file.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WriteOptions {
    /// The format; `None` takes it from the extension (default).
    pub format: Option<Format>,
    /// ASCII instead of binary for STL and PLY (default false).
    pub ascii: bool,
}

/// The format `path` will be written in.
pub fn output_format(path: &Path, opts: &WriteOptions) -> Result<Format, IoError> {
    opts.format
        .or_else(|| Format::from_path(path))
        .ok_or_else(|| IoError::UnknownOutputFormat {
            path: path.to_path_buf(),
            ext: path
                .extension()
                .map(|e| e.to_string_lossy().into_owned())
                .unwrap_or_default(),
        })
}

/// Writes `mesh` to `path` atomically, refusing to overwrite any of `inputs`.
pub fn write_mesh(
    path: &Path,
    mesh: &TriMesh,
    opts: &WriteOptions,
    inputs: &[&Path],
) -> Result<Format, IoError> {
    let (staged, format) = stage_mesh(path, mesh, opts, inputs)?;
    staged.commit()?;
    Ok(format)
}

/// Writes `mesh` for `path` into a temporary file beside it, left [`Staged`] (see [`commit`]).
pub fn stage_mesh(
    path: &Path,
    mesh: &TriMesh,
    opts: &WriteOptions,
    inputs: &[&Path],
) -> Result<(Staged, Format), IoError> {
    let format = output_format(path, opts)?;
    if let Some(v) = mesh
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(IoError::NonFinite {
            path: path.to_path_buf(),
            vertex: v,
        });
    }
    if format.is_gltf() {
        let name = path
            .file_stem()
            .map_or("mesh".into(), |s| s.to_string_lossy());
        let staged = gltf::stage_scene(path, &gltf::single(&name, mesh), inputs)?;
        return Ok((staged, format));
    }
    let staged = stage(path, inputs, |w| match format {
        Format::Triples => triples::write(w, mesh),
        Format::Obj => obj::write(w, mesh),
        Format::Stl if opts.ascii => stl::write_ascii(w, mesh),
        Format::Stl => stl::write_binary(w, mesh),
        Format::Ply => ply::write(w, mesh, opts.ascii),
        Format::Gltf | Format::Glb => unreachable!("written above"),
    })
    .map_err(|e| match e {
        IoError::Write { path, source }
            if source.get_ref().is_some_and(|s| s.is::<stl::OutOfRange>()) =>
        {
            let r = source
                .into_inner()
                .unwrap()
                .downcast::<stl::OutOfRange>()
                .unwrap();
            if r.too_small {
                IoError::TooSmallForFloat {
                    path,
                    value: r.value,
                }
            } else {
                IoError::OutOfFloatRange {
                    path,
                    vertex: r.vertex,
                    value: r.value,
                }
            }
        }
        e => e,
    })?;
    Ok((staged, format))
}

/// Writes `mesh` as OBJ with one rest point per vertex (`obj::write_with_rest`, faces grouped
/// by `groups`: `(name, first face, faces)`, none for one group) for `path`, [`Staged`].
/// Refuses non-finite positions or rest points.
pub fn stage_obj_with_rest(
    path: &Path,
    mesh: &TriMesh,
    rest: &[[f64; 2]],
    groups: &[(String, usize, usize)],
    inputs: &[&Path],
) -> Result<Staged, IoError> {
    let bad = mesh
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
        .or_else(|| rest.iter().position(|r| !r.iter().all(|c| c.is_finite())));
    if let Some(v) = bad {
        return Err(IoError::NonFinite {
            path: path.to_path_buf(),
            vertex: v,
        });
    }
    stage(path, inputs, |w| {
        obj::write_with_rest(w, mesh, rest, groups)
    })
}

/// Whether two paths name the same existing file.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
    }
}

/// Whether `a` and `b` name one file: the same file now ([`same_file`]), or the same absolute
/// path (two outputs, neither written yet).
///
/// ```
/// use std::path::Path;
/// assert!(drapekit::io::same_target(Path::new("./out/a.json"), Path::new("out//a.json")));
/// assert!(!drapekit::io::same_target(Path::new("out/a.json"), Path::new("out/b.json")));
/// ```
pub fn same_target(a: &Path, b: &Path) -> bool {
    same_file(a, b)
        || matches!((std::path::absolute(a), std::path::absolute(b)), (Ok(x), Ok(y)) if x == y)
}

/// Writes through `body` into a temporary file beside `path`, then renames it to `path`. On any
/// error the temporary file is removed and `path` is untouched. Refuses when `path` is one of
/// `inputs`.
pub fn write_atomic<F>(path: &Path, inputs: &[&Path], body: F) -> Result<(), IoError>
where
    F: FnOnce(&mut BufWriter<&std::fs::File>) -> std::io::Result<()>,
{
    stage(path, inputs, body)?.commit()
}

/// An output written in full to a temporary file beside its target, not yet renamed into place.
/// Dropped uncommitted, the temporary file is removed and the target never changes; [`commit`]
/// puts several into place together, so a run that fails before then changes none of them.
#[derive(Debug)]
pub struct Staged {
    tmp: tempfile::TempPath,
    path: PathBuf,
}

impl Staged {
    /// The target.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Renames the temporary file to the target.
    pub fn commit(self) -> Result<(), IoError> {
        let path = self.path;
        self.tmp.persist(&path).map_err(|e| IoError::Write {
            path,
            source: e.error,
        })
    }
}

/// Puts every staged output into place, after checking that no target is a directory or another
/// non-file (the one way a rename fails that a check can foresee): a refused target leaves every
/// target as it was.
pub fn commit(staged: Vec<Staged>) -> Result<(), IoError> {
    for s in &staged {
        refuse_non_file(&s.path)?;
    }
    staged.into_iter().try_for_each(Staged::commit)
}

/// Refuses a target that exists and is a directory or another non-file.
fn refuse_non_file(path: &Path) -> Result<(), IoError> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.is_file() => Err(IoError::Write {
            path: path.to_path_buf(),
            source: std::io::Error::other("exists and is not a file"),
        }),
        _ => Ok(()),
    }
}

/// Refuses `path` as an output before any work is done: one of `inputs`, a directory or another
/// non-file, or in a folder that does not exist (each would fail only when the output is put
/// in place, after the work).
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let err = drapekit::io::check_target(dir.path(), &[]).unwrap_err();
/// assert!(err.to_string().ends_with("exists and is not a file"));
/// let err = drapekit::io::check_target(&dir.path().join("no/x.png"), &[]).unwrap_err();
/// assert!(err.to_string().contains("does not exist"));
/// assert!(drapekit::io::check_target(&dir.path().join("x.png"), &[]).is_ok());
/// ```
pub fn check_target(path: &Path, inputs: &[&Path]) -> Result<(), IoError> {
    refuse_inputs(path, inputs)?;
    refuse_non_file(path)?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(IoError::Write {
            path: path.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("the folder {} does not exist", dir.display()),
            ),
        });
    }
    Ok(())
}

/// Refuses `path` when it is one of `inputs`.
fn refuse_inputs(path: &Path, inputs: &[&Path]) -> Result<(), IoError> {
    match inputs.iter().find(|i| same_file(path, i)) {
        Some(input) => Err(IoError::WouldOverwriteInput {
            path: path.to_path_buf(),
            input: input.to_path_buf(),
        }),
        None => Ok(()),
    }
}

/// Writes through `body` into a temporary file beside `path` (closed when done) and returns it
/// staged. Refuses when `path` is one of `inputs`.
pub fn stage<F>(path: &Path, inputs: &[&Path], body: F) -> Result<Staged, IoError>
where
    F: FnOnce(&mut BufWriter<&std::fs::File>) -> std::io::Result<()>,
{
    refuse_inputs(path, inputs)?;
    let werr = |source: std::io::Error| IoError::Write {
        path: path.to_path_buf(),
        source,
    };
    let dir: PathBuf = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = tempfile::Builder::new()
        .prefix(&format!("{TEMP_PREFIX}{}-{name}.", std::process::id()))
        .suffix(TEMP_SUFFIX)
        .tempfile_in(&dir)
        // Without the temporary file's name (tempfile adds it): the output's path is the one
        // a user gave.
        .map_err(|e| werr(std::io::Error::from(e.kind())))?;
    {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.as_file());
        body(&mut w).map_err(werr)?;
        w.flush().map_err(werr)?;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(path)
            .map(|m| m.permissions().mode())
            .unwrap_or(0o644);
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(mode))
            .map_err(werr)?;
    }
    Ok(Staged {
        tmp: tmp.into_temp_path(),
        path: path.to_path_buf(),
    })
}

/// The start of the name of every temporary file drapekit writes: the process id of the
/// writer follows, then the target's name, random letters and [`TEMP_SUFFIX`]
/// (`.drapekit-tmp-4242-square.obj.a1B2c3.tmp`), so that [`remove_stale_temps`] knows its own
/// files and whether the run that wrote one is still going.
pub const TEMP_PREFIX: &str = ".drapekit-tmp-";

/// The end of the name of every temporary file drapekit writes (see [`TEMP_PREFIX`]).
pub const TEMP_SUFFIX: &str = ".tmp";

/// The process id in the name of a temporary file of drapekit's ([`TEMP_PREFIX`]); `None`
/// for any other name.
///
/// ```
/// use drapekit::io::temp_writer;
/// assert_eq!(temp_writer(".drapekit-tmp-4242-square.obj.a1B2c3.tmp"), Some(4242));
/// assert_eq!(temp_writer(".square.obj.a1B2c3.tmp"), None);
/// assert_eq!(temp_writer(".drapekit-tmp-x-square.obj.tmp"), None);
/// assert_eq!(temp_writer(".drapekit-tmp-4242-square.obj"), None);
/// ```
pub fn temp_writer(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(TEMP_PREFIX)?.strip_suffix(TEMP_SUFFIX)?;
    let (pid, _) = rest.split_once('-')?;
    if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    pid.parse().ok().filter(|&p| p > 0)
}

/// Whether process `pid` is running (on other systems than Unix: always, so nothing is
/// removed).
fn running(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(pid) = libc::pid_t::try_from(pid) else {
            return false;
        };
        // SAFETY: signal 0 only checks that the process exists; nothing is sent.
        let r = unsafe { libc::kill(pid, 0) };
        r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

/// Removes the temporary files that runs killed before they could clean up (SIGKILL, a power
/// cut) left in `dir`: regular files named by [`TEMP_PREFIX`] and [`TEMP_SUFFIX`] whose
/// writer is no longer running. Any other file, and the files of a run still going, stay; a
/// missing folder has none. Returns the files removed.
pub fn remove_stale_temps(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(pid) = name.to_str().and_then(temp_writer) else {
            continue;
        };
        let is_file = e.file_type().is_ok_and(|t| t.is_file());
        if is_file && !running(pid) && std::fs::remove_file(e.path()).is_ok() {
            removed.push(e.path());
        }
    }
    removed.sort();
    removed
}

/// What a name written as a file name inside an output folder may not be: empty, `.` or `..`,
/// or hold a path separator (`/`, `\`), a drive colon (`:`) or a control character. Such a name
/// could write outside the folder (`/tmp/x`, `../x`) or nowhere.
pub const FILE_NAME_RULE: &str =
    "not empty, not '.' or '..', no '/', '\\', ':' or control characters";

/// Whether `name` can be a file name (before its extension) inside an output folder: see
/// [`FILE_NAME_RULE`].
pub fn is_safe_file_name(name: &str) -> bool {
    !(name.is_empty()
        || name == "."
        || name == ".."
        || name
            .chars()
            .any(|c| matches!(c, '/' | '\\' | ':') || c.is_control()))
}

/// File names (before their extension) for `wanted`, in order, none equal to another or to one
/// of `taken`: a name that is not safe ([`is_safe_file_name`]) becomes `fallback`, and a name
/// already used gets `_2`, `_3`, ... appended. Names are compared ignoring case, as folders on
/// macOS and Windows do.
///
/// ```
/// use drapekit::io::unique_file_names;
/// let wanted = ["sphere", "sphere", "square", "a/b"].map(String::from);
/// let names = unique_file_names(&wanted, &["Square".to_string()], "object");
/// assert_eq!(names, ["sphere", "sphere_2", "square_2", "object"]);
/// ```
pub fn unique_file_names(wanted: &[String], taken: &[String], fallback: &str) -> Vec<String> {
    let mut used: std::collections::HashSet<String> =
        taken.iter().map(|t| t.to_lowercase()).collect();
    let mut out = Vec::with_capacity(wanted.len());
    for w in wanted {
        let base = if is_safe_file_name(w) { w } else { fallback };
        let mut name = base.to_string();
        let mut k = 2;
        while !used.insert(name.to_lowercase()) {
            name = format!("{base}_{k}");
            k += 1;
        }
        out.push(name);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_that_leave_the_folder_are_not_file_names() {
        for bad in ["", ".", "..", "/tmp/x", "../x", "a\\b", "c:x", "a\nb"] {
            assert!(!is_safe_file_name(bad), "{bad:?}");
        }
        for good in ["skirt", "front panel", ".hidden", "a..b", "piece-1"] {
            assert!(is_safe_file_name(good), "{good:?}");
        }
    }

    #[test]
    fn a_commit_refused_for_one_target_changes_none() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.txt"), dir.path().join("b.txt"));
        std::fs::write(&a, "old").unwrap();
        std::fs::create_dir(&b).unwrap();
        let staged = [&a, &b]
            .map(|p| stage(p, &[], |w| w.write_all(b"new")).unwrap())
            .into_iter()
            .collect();
        assert!(commit(staged).is_err());
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old");
        let mut names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        assert_eq!(names, ["a.txt", "b.txt"], "no temporary file left");
    }

    #[test]
    fn sniffing() {
        assert_eq!(Format::sniff(b"ply\nformat ascii 1.0\n"), Some(Format::Ply));
        assert_eq!(Format::sniff(b"# c\nv 0 0 0\n"), Some(Format::Obj));
        assert_eq!(Format::sniff(b"; lisp\n(0 0 0)\n"), Some(Format::Triples));
        assert_eq!(
            Format::sniff(b"solid x\nfacet normal 0 0 1\n"),
            Some(Format::Stl)
        );
        assert_eq!(Format::sniff(b"hello world\n"), None);
        assert_eq!(Format::sniff(b"glTF\x02\0\0\0"), Some(Format::Glb));
        let json = b"\xEF\xBB\xBF {\n  \"asset\": {\"version\": \"2.0\"}}";
        assert_eq!(Format::sniff(json), Some(Format::Gltf));
        assert_eq!(Format::sniff(b"{\"units\": \"m\"}"), None);
    }

    #[test]
    fn stale_temporary_files_of_dead_writers_go_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let put = |name: &str| std::fs::write(dir.path().join(name), "x").unwrap();
        // Above Linux's largest process id (2^22): no such process.
        let dead = format!("{TEMP_PREFIX}4194305-a.obj.Xy12Zw{TEMP_SUFFIX}");
        let live = format!(
            "{TEMP_PREFIX}{}-b.obj.Xy12Zw{TEMP_SUFFIX}",
            std::process::id()
        );
        let foreign = [
            ".a.obj.Xy12Zw.tmp",
            "notes.tmp",
            ".drapekit-tmp-x-c.tmp",
            "a.obj",
        ];
        put(&dead);
        put(&live);
        foreign.iter().for_each(|f| put(f));
        std::fs::create_dir(
            dir.path()
                .join(format!("{TEMP_PREFIX}4194305-d{TEMP_SUFFIX}")),
        )
        .unwrap();
        let removed = remove_stale_temps(dir.path());
        assert_eq!(removed, [dir.path().join(&dead)]);
        let mut left = names(dir.path());
        left.sort();
        let mut expected: Vec<String> = foreign.iter().map(|f| f.to_string()).collect();
        expected.push(live);
        expected.push(format!("{TEMP_PREFIX}4194305-d{TEMP_SUFFIX}"));
        expected.sort();
        assert_eq!(
            left, expected,
            "a live writer's file, others' files and folders stay"
        );
        assert!(remove_stale_temps(&dir.path().join("missing")).is_empty());
    }

    fn names(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect()
    }

    #[test]
    fn temporary_files_carry_the_prefix_and_the_writers_id() {
        let dir = tempfile::tempdir().unwrap();
        let staged = stage(&dir.path().join("a.obj"), &[], |w| w.write_all(b"x")).unwrap();
        let name = names(dir.path()).pop().unwrap();
        assert_eq!(temp_writer(&name), Some(std::process::id()), "{name}");
        drop(staged);
        assert!(names(dir.path()).is_empty());
    }

    #[test]
    fn atomic_write_leaves_nothing_on_failure() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("o.obj");
        std::fs::write(&out, b"old").unwrap();
        let r = write_atomic(&out, &[], |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read(&out).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
