//! `drapekit convert IN -o OUT`: read, prepare, write, report.

use super::ReadArgs;
use crate::io::{self, Format, ReadInfo, WriteOptions};
use crate::mesh::diagnose::ShellState;
use crate::mesh::prepare::{prepare, PrepareOptions, PrepareReport};
use crate::mesh::transform::{Units, Up};
use crate::mesh::weld::WeldTolerance;
use crate::mesh::TriMesh;
use anyhow::bail;
use clap::Args;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `drapekit convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The mesh to convert (.txt/.tri vertex triples, .obj, .stl, .ply).
    pub input: PathBuf,
    /// Where to write the result; the format follows the extension unless --to says.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Output format: triples, obj, stl or ply.
    #[arg(long, value_name = "FORMAT", value_parser = super::parse_format)]
    pub to: Option<Format>,
    /// Write ASCII STL or PLY instead of binary.
    #[arg(long)]
    pub ascii: bool,
    /// Write the JSON report here.
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// Print the JSON report on stdout instead of the summary.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub read: ReadArgs,
    /// Weld distance: `0.01` (absolute, input units) or `1e-6rel` (times the bounding-box diagonal).
    #[arg(long, value_name = "TOL", default_value = "1e-6rel", value_parser = parse_weld)]
    pub weld_tol: WeldTolerance,
    /// Do not weld vertices.
    #[arg(long)]
    pub no_weld: bool,
    /// Keep degenerate faces.
    #[arg(long)]
    pub keep_degenerate: bool,
    /// Keep duplicate faces.
    #[arg(long)]
    pub keep_duplicates: bool,
    /// Do not reorient faces.
    #[arg(long)]
    pub no_orient: bool,
    /// Keep non-manifold vertices (a surface pinched at a point) instead of splitting each
    /// into one vertex per fan.
    #[arg(long)]
    pub keep_nonmanifold_vertices: bool,
    /// Units of the input: mm, cm, m or in (with --to-units).
    #[arg(long, value_name = "U", value_parser = parse_units)]
    pub units: Option<Units>,
    /// Convert to these units (needs --units).
    #[arg(long, value_name = "U", value_parser = parse_units, requires = "units")]
    pub to_units: Option<Units>,
    /// Up axis of the input: y or z (with --to-up).
    #[arg(long, value_name = "AXIS", value_parser = parse_up)]
    pub up: Option<Up>,
    /// Rotate to this up axis (needs --up).
    #[arg(long, value_name = "AXIS", value_parser = parse_up, requires = "up")]
    pub to_up: Option<Up>,
    /// Also write a picture of the output beside it (`OUT` with the extension `.png`), from
    /// the front, right and above, up being `--to-up`, else `--up`, else z.
    #[arg(long)]
    pub preview: bool,
}

fn parse_weld(s: &str) -> Result<WeldTolerance, String> {
    s.parse()
}
fn parse_units(s: &str) -> Result<Units, String> {
    s.parse()
}
fn parse_up(s: &str) -> Result<Up, String> {
    s.parse()
}

impl ConvertArgs {
    /// The library's preparation options.
    pub fn prepare_options(&self) -> PrepareOptions {
        PrepareOptions {
            weld: (!self.no_weld).then_some(self.weld_tol),
            drop_degenerate: !self.keep_degenerate,
            drop_duplicates: !self.keep_duplicates,
            split_vertices: !self.keep_nonmanifold_vertices,
            orient: !self.no_orient,
            units: self.units.zip(self.to_units),
            up: self.up.zip(self.to_up),
        }
    }
}

/// The JSON report of `convert`. Every key is documented in the README.
#[derive(Debug, Serialize)]
pub struct ConvertReport {
    /// Input path.
    pub input: String,
    /// Output path.
    pub output: String,
    /// Input format as read (e.g. `stl-binary`).
    pub input_format: String,
    /// Output format.
    pub output_format: Format,
    /// Face records in the input (before triangulation).
    pub input_faces: usize,
    /// Triangles after reading.
    pub input_triangles: usize,
    /// Distinct vertices after reading.
    pub input_vertices: usize,
    /// Triangles written.
    pub output_faces: usize,
    /// Vertices written.
    pub output_vertices: usize,
    /// Vertices merged by welding.
    pub welded_vertices: usize,
    /// Degenerate faces dropped.
    pub degenerate_faces: usize,
    /// Duplicate faces dropped.
    pub duplicate_faces: usize,
    /// Faces whose winding was reversed.
    pub flipped_faces: usize,
    /// Vertices added by splitting non-manifold vertices (one per extra fan).
    pub split_vertices: usize,
    /// Quads in the input.
    pub quads: usize,
    /// Quads whose corners are not in one plane.
    pub nonplanar_quads: usize,
    /// Components after.
    pub components: usize,
    /// Closed components after.
    pub closed_components: usize,
    /// Open components after.
    pub open_components: usize,
    /// Edges shared by three or more faces (reported, left alone).
    pub non_manifold_edges: usize,
    /// Shell state after.
    pub shell_state: ShellState,
    /// Wall time of the whole conversion, seconds.
    pub wall_seconds: f64,
    /// The preview picture (`--preview`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preview: Option<String>,
    /// What the reader found.
    pub read: ReadInfo,
    /// Every preparation step in detail, and the full diagnosis after.
    pub prepare: PrepareReport,
}

/// Flags given that change nothing: `--ascii` for a text format, `--units` without `--to-units`,
/// `--up` without `--to-up` (clap already refuses the reverse).
fn idle_flags(args: &ConvertArgs, out_format: Format) -> Vec<String> {
    let mut w: Vec<String> = super::ascii_warning(args.ascii, out_format)
        .into_iter()
        .collect();
    if args.units.is_some() && args.to_units.is_none() {
        w.push(
            "--units does nothing without --to-units (convert scales from one to the other)".into(),
        );
    }
    if args.up.is_some() && args.to_up.is_none() {
        w.push("--up does nothing without --to-up (convert rotates from one to the other)".into());
    }
    w
}

/// Reads the input and prepares it; refuses a mesh with no faces, as read or as prepared.
fn read_and_prepare(
    args: &ConvertArgs,
    opts: &PrepareOptions,
) -> anyhow::Result<(TriMesh, ReadInfo, PrepareReport)> {
    let read = io::read_mesh(&args.input, &args.read.options())?;
    if read.mesh.faces.is_empty() {
        bail!(
            "{}: no faces to convert ({} vertices, 0 faces): a point cloud or an empty mesh",
            args.input.display(),
            read.mesh.positions.len()
        );
    }
    let mut mesh = read.mesh;
    let prep = prepare(&mut mesh, opts);
    if mesh.faces.is_empty() {
        bail!(
            "{}: every face was degenerate or duplicate; nothing is left to write",
            args.input.display()
        );
    }
    Ok((mesh, read.info, prep))
}

/// Writes the output mesh and, with `--preview`, its picture (committed together); the
/// preview's path.
fn write_outputs(
    args: &ConvertArgs,
    mesh: &TriMesh,
    wopts: &WriteOptions,
    inputs: &[&Path],
) -> anyhow::Result<Option<String>> {
    let (staged, _) = io::stage_mesh(&args.output, mesh, wopts, inputs)?;
    let mut staged = vec![staged];
    let preview = if args.preview {
        let up = args.to_up.or(args.up).unwrap_or(Up::Z);
        let p = super::render::preview_path(&args.output);
        staged.push(stage_preview(&p, &args.output, mesh, up, inputs)?);
        Some(p.display().to_string())
    } else {
        None
    };
    io::commit(staged)?;
    Ok(preview)
}

/// The report of a conversion that began at `start`.
fn convert_report(
    args: &ConvertArgs,
    out_format: Format,
    info: ReadInfo,
    prep: PrepareReport,
    start: Instant,
    preview: Option<String>,
) -> ConvertReport {
    ConvertReport {
        input: args.input.display().to_string(),
        output: args.output.display().to_string(),
        input_format: info.format.clone(),
        output_format: out_format,
        input_faces: info.polygons.polygons,
        input_triangles: prep.input_faces,
        input_vertices: prep.input_vertices,
        output_faces: prep.output_faces,
        output_vertices: prep.output_vertices,
        welded_vertices: prep.welded_vertices,
        degenerate_faces: prep.degenerate_faces,
        duplicate_faces: prep.duplicate_faces,
        flipped_faces: prep.flipped_faces,
        split_vertices: prep.split_vertices,
        quads: info.polygons.quads,
        nonplanar_quads: info.polygons.nonplanar_quads,
        components: prep.after.components,
        closed_components: prep.after.closed_components,
        open_components: prep.after.open_components,
        non_manifold_edges: prep.after.non_manifold_edges,
        shell_state: prep.after.shell_state,
        wall_seconds: start.elapsed().as_secs_f64(),
        preview,
        read: info,
        prepare: prep,
    }
}

/// Runs `drapekit convert`.
pub fn run(args: ConvertArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let opts = args.prepare_options();
    let wopts = WriteOptions {
        format: args.to,
        ascii: args.ascii,
    };
    let out_format = io::output_format(&args.output, &wopts)?;
    super::warn(&idle_flags(&args, out_format));
    if let Some(r) = &args.report {
        if r == &args.output {
            bail!("--report {} is the output mesh path", r.display());
        }
    }
    let (mesh, info, prep) = read_and_prepare(&args, &opts)?;
    let inputs = [args.input.as_path()];
    let preview = write_outputs(&args, &mesh, &wopts, &inputs)?;
    let report = convert_report(&args, out_format, info, prep, start, preview);
    super::finish(
        &report,
        args.report.as_deref(),
        &inputs,
        &args.output,
        args.json,
        |r| print_summary(r, &args.output),
    )
}

/// Stages the preview of `mesh` (the output `out`) at `path`.
fn stage_preview(
    path: &Path,
    out: &Path,
    mesh: &TriMesh,
    up: Up,
    inputs: &[&Path],
) -> anyhow::Result<io::Staged> {
    if path == out {
        bail!(
            "{}: the preview would be written over the output; give the output a mesh extension",
            out.display()
        );
    }
    let item = crate::render::Item::object(mesh, super::render::OBJECT);
    super::render::stage_preview(path, &[item], crate::render::View::Iso, up, inputs)
}

fn print_summary(r: &ConvertReport, out: &Path) {
    println!(
        "{} ({}, {} faces, {} triangles, {} vertices) -> {} ({}, {} triangles, {} vertices)",
        r.input,
        r.input_format,
        r.input_faces,
        r.input_triangles,
        r.input_vertices,
        out.display(),
        r.output_format,
        r.output_faces,
        r.output_vertices
    );
    if let Some(w) = &r.prepare.weld {
        println!(
            "  welded {} vertices (distance {:.3e})",
            w.welded, w.distance
        );
    }
    println!(
        "  dropped {} degenerate and {} duplicate faces; flipped {} faces; {} quads ({} non-planar)",
        r.degenerate_faces, r.duplicate_faces, r.flipped_faces, r.quads, r.nonplanar_quads
    );
    if r.split_vertices > 0 {
        println!(
            "  split non-manifold vertices: {} added (a surface pinched at a point, one vertex per fan)",
            r.split_vertices
        );
    }
    println!(
        "  {} components ({} closed, {} open), {} non-manifold edges; shell state: {}",
        r.components, r.closed_components, r.open_components, r.non_manifold_edges, r.shell_state
    );
    for w in &r.read.warnings {
        println!("  note: {w}");
    }
}
