//! `drapekit fit`: a mannequin from sections, measurements or a scan.

use crate::fit::fitter::{self, fit_sections, section_targets, FitOptions, FitReport, GirthTarget};
use crate::fit::scan::{torso_sections, ScanOptions};
use crate::fit::{input, measurements, FitError};
use crate::io::{self, Format, ReadOptions, WriteOptions};
use crate::mesh::prepare::{prepare, PrepareOptions};
use crate::mesh::transform::{change_up, scale, Units, Up};
use crate::mesh::TriMesh;
use clap::{ArgGroup, Args};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `drapekit fit`.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("source").required(true).args(["sections", "measurements", "from_mesh"])))]
pub struct FitArgs {
    /// Horizontal sections: a .json file ({"units", "sections": [{"height", "points"}]}) or a .csv (height,x,y).
    #[arg(long, value_name = "FILE")]
    pub sections: Option<PathBuf>,
    /// Body measurements: a .toml file (stature and at least two girths; see the README).
    #[arg(long, value_name = "FILE")]
    pub measurements: Option<PathBuf>,
    /// A scanned body mesh (any format drapekit reads): the torso is sliced and fitted.
    #[arg(long, value_name = "MESH")]
    pub from_mesh: Option<PathBuf>,
    /// Where to write the form (.obj, .ply, .stl, .txt).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Output format instead of the extension's: triples, obj, stl or ply.
    #[arg(long, value_name = "FORMAT", value_parser = super::parse_format)]
    pub format: Option<Format>,
    /// Write ASCII STL or PLY.
    #[arg(long)]
    pub ascii: bool,
    /// Units of a CSV sections file or of the mesh [default: m]. Files that state their own
    /// (JSON sections, measurement sets) refuse a --units that disagrees.
    #[arg(long, value_name = "U", value_parser = parse_units)]
    pub units: Option<Units>,
    /// Write the form in these units [default: the input's].
    #[arg(long, value_name = "U", value_parser = parse_units)]
    pub to_units: Option<Units>,
    /// Up axis of the mesh: y or z.
    #[arg(long, value_name = "AXIS", default_value = "z", value_parser = parse_up)]
    pub up: Up,
    /// Up axis of the written form [default: z; for a mesh, the mesh's].
    #[arg(long, value_name = "AXIS", value_parser = parse_up)]
    pub to_up: Option<Up>,
    /// Sections along the height: slices of the scan [60], sections of the measurement model [41].
    #[arg(long, value_name = "K")]
    pub levels: Option<usize>,
    /// Scan: lowest slice height, in the mesh's units and up coordinate [0.48 of the body's height].
    #[arg(long, value_name = "H1")]
    pub from: Option<f64>,
    /// Scan: highest slice height [0.74 of the body's height].
    #[arg(long, value_name = "H2")]
    pub to: Option<f64>,
    /// Nodes around each section (points it is resampled to).
    #[arg(long, value_name = "N", default_value_t = 128)]
    pub nodes: usize,
    /// Lanczos order along the height: 0, 1 or 2 (lowered, with a warning, when sections are too few).
    #[arg(long, value_name = "M", default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=2))]
    pub lanczos: u8,
    /// Use every S-th section as a node.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub stride: usize,
    /// Choose the fewest nodes and lowest order meeting this error, e.g. 0.5mm (bare numbers are input units).
    #[arg(long, value_name = "LENGTH", value_parser = parse_length, conflicts_with_all = ["nodes", "stride", "lanczos"])]
    pub tolerance: Option<(f64, Option<Units>)>,
    /// Points around each ring of the output.
    #[arg(long, value_name = "N", default_value_t = 128)]
    pub around: usize,
    /// Rings of the output along the height.
    #[arg(long, value_name = "M", default_value_t = 129)]
    pub along: usize,
    /// Leave the top and bottom open.
    #[arg(long)]
    pub open: bool,
    /// Write the JSON report here.
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// Print the JSON report instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Also write a picture of the form beside it (`OUT` with the extension `.png`), from the
    /// front.
    #[arg(long)]
    pub preview: bool,
}

fn parse_units(s: &str) -> Result<Units, String> {
    s.parse()
}
fn parse_up(s: &str) -> Result<Up, String> {
    s.parse()
}

/// A length with an optional unit: `0.5mm`, `0.05 cm`, `5e-4`.
pub fn parse_length(s: &str) -> Result<(f64, Option<Units>), String> {
    let s = s.trim();
    let split = s
        .find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
        .unwrap_or(s.len());
    let (num, unit) = s.split_at(split);
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a length: give e.g. 0.5mm"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("'{s}' must be a positive length"));
    }
    let unit = if unit.trim().is_empty() {
        None
    } else {
        Some(unit.trim().parse::<Units>()?)
    };
    Ok((v, unit))
}

/// The JSON report of `fit`.
#[derive(Debug, Serialize)]
pub struct FitCliReport {
    /// The input file.
    pub input: String,
    /// `sections`, `measurements` or `scan`.
    pub source: &'static str,
    /// With `--measurements`: the set's format (`toml`, `freesewing` or `garmentcode`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measurement_format: Option<&'static str>,
    /// What reading the input assumed (an estimated stature, keys not used).
    pub notes: Vec<String>,
    /// The output file.
    pub output: String,
    /// Units of the input (and of every length in this report but the output's).
    pub units: Units,
    /// Units of the written form.
    pub output_units: Units,
    /// Up axis of the written form.
    pub output_up: Up,
    /// Scan: the slicing band `[from, to]`.
    pub band: Option<[f64; 2]>,
    /// The fit.
    #[serde(flatten)]
    pub fit: FitReport,
    /// Wall time of the whole command, seconds.
    pub wall_seconds: f64,
    /// The preview picture (`--preview`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preview: Option<String>,
}

struct Source {
    path: PathBuf,
    kind: &'static str,
    /// The measurement set's format (`toml`, `freesewing`, `garmentcode`).
    format: Option<&'static str>,
    /// What reading the measurements assumed (an estimated stature, keys not used).
    notes: Vec<String>,
    sections: Vec<crate::fit::section::Section>,
    targets: Vec<GirthTarget>,
    units: Units,
    up: Up,
    band: Option<[f64; 2]>,
}

/// A `--units` that disagrees with the units the input file states is refused (one that
/// agrees, or a file that states none, is fine).
fn units_agree(p: &Path, file: Option<Units>, flag: Option<Units>) -> Result<(), FitError> {
    match file.zip(flag) {
        Some((file, flag)) if file != flag => Err(FitError::Key {
            path: p.to_path_buf(),
            key: "units".into(),
            message: format!(
                "the file's units are {file} (its key 'units' or its format's default), not --units {flag}: --units applies to CSV sections and meshes"
            ),
        }),
        _ => Ok(()),
    }
}

/// The source the flags name: a sections file, a measurement set, or a scanned body.
fn load(args: &FitArgs) -> Result<Source, FitError> {
    if let Some(p) = &args.sections {
        return from_sections(args, p);
    }
    if let Some(p) = &args.measurements {
        return from_measurements(args, p);
    }
    let p = args.from_mesh.as_ref().expect("clap requires one source");
    from_scan(args, p)
}

/// A sections file (`--sections`): its sections, each a girth target under its name.
fn from_sections(args: &FitArgs, p: &Path) -> Result<Source, FitError> {
    let f = input::read(p)?;
    units_agree(p, f.units, args.units)?;
    let units = f.units.or(args.units).unwrap_or(Units::M);
    let mut targets = section_targets(&f.sections, "section");
    for (t, n) in targets.iter_mut().zip(&f.names) {
        if let Some(n) = n {
            t.name = n.clone();
        }
    }
    Ok(Source {
        path: p.to_path_buf(),
        kind: "sections",
        format: None,
        notes: Vec::new(),
        sections: f.sections,
        targets,
        units,
        up: Up::Z,
        band: None,
    })
}

/// A measurement set (`--measurements`, any format read): the shape model's sections.
fn from_measurements(args: &FitArgs, p: &Path) -> Result<Source, FitError> {
    let imported = crate::fit::foreign::read_any(p)?;
    let m = &imported.measurements;
    let (sections, targets, units) = measurements::sections(m, p, args.levels.unwrap_or(41))?;
    units_agree(p, Some(units), args.units)?;
    Ok(Source {
        path: p.to_path_buf(),
        kind: "measurements",
        format: Some(imported.format),
        notes: imported.notes,
        sections,
        targets,
        units,
        up: Up::Z,
        band: None,
    })
}

/// A scanned body (`--from-mesh`): prepared, turned z-up, its torso sliced.
fn from_scan(args: &FitArgs, p: &Path) -> Result<Source, FitError> {
    let mut body = io::read_mesh(p, &ReadOptions::default())?.mesh;
    if body.faces.is_empty() {
        return Err(FitError::Options(format!(
            "{}: the mesh has no faces",
            p.display()
        )));
    }
    crate::fit::scan::check_up(&body, args.up, p)?;
    prepare(&mut body, &PrepareOptions::default());
    if body.faces.is_empty() {
        return Err(FitError::Options(format!(
            "{}: every face of the mesh is degenerate (no area): no body to slice",
            p.display()
        )));
    }
    change_up(&mut body, args.up, Up::Z);
    let opts = ScanOptions {
        levels: args.levels.unwrap_or(60),
        from: args.from,
        to: args.to,
    };
    let (sections, (from, to)) = torso_sections(&body, &opts).map_err(|e| e.in_file(p))?;
    let targets = section_targets(&sections, "level");
    Ok(Source {
        path: p.to_path_buf(),
        kind: "scan",
        format: None,
        notes: Vec::new(),
        sections,
        targets,
        units: args.units.unwrap_or(Units::M),
        up: args.up,
        band: Some([from, to]),
    })
}

/// The input file.
fn source_path(args: &FitArgs) -> &Path {
    let given = [&args.sections, &args.measurements, &args.from_mesh];
    let first = given.into_iter().flatten().next();
    first.map_or(Path::new(""), PathBuf::as_path)
}

/// Checks the flags and the outputs, before the input is read: the flags that do not apply,
/// the counts (every problem), and the form, preview and report paths (none an input, a
/// folder, in a missing folder, or another of them).
fn check_args(args: &FitArgs, wopts: &WriteOptions) -> anyhow::Result<()> {
    let format = io::output_format(&args.output, wopts).map_err(|e| match e {
        io::IoError::UnknownOutputFormat { ext, .. } => anyhow::anyhow!(
            "cannot write {}: unknown output format for extension '{ext}'; give --format triples|obj|stl|ply|glb|gltf",
            args.output.display()
        ),
        e => e.into(),
    })?;
    super::warn(
        &super::ascii_warning(args.ascii, format)
            .into_iter()
            .collect::<Vec<_>>(),
    );
    if args.measurements.is_none() && args.levels.is_some() && args.from_mesh.is_none() {
        anyhow::bail!("--levels applies to --measurements and --from-mesh; a sections file has its own sections");
    }
    if args.from_mesh.is_none() && (args.from.is_some() || args.to.is_some()) {
        anyhow::bail!("--from and --to set the slicing band of --from-mesh");
    }
    for (flag, v) in [("--from", args.from), ("--to", args.to)] {
        if let Some(v) = v.filter(|v| !v.is_finite()) {
            anyhow::bail!("{flag} {v}: expected a height in the mesh's units");
        }
    }
    let mut problems = Vec::new();
    if let Some(levels) = args.levels {
        problems
            .extend(fitter::check_count("--levels", levels, fitter::MAX_LEVELS, "sections").err());
        if levels < 3 {
            problems.push(FitError::TooSmall {
                flag: "--levels".into(),
                value: levels as u64,
                min: 3,
                what: "levels (a surface needs 3)".into(),
            });
        }
    }
    let counts = FitOptions {
        nodes_around: args.nodes,
        around: args.around,
        along: args.along,
        stride: args.stride,
        ..FitOptions::default()
    };
    problems.extend(counts.check_counts().err());
    FitError::from_problems(problems)?;
    check_outputs(args)
}

/// The form, the preview and the report: each refused before any work when it is an input,
/// a folder or in a missing folder, or when two of them are one file.
fn check_outputs(args: &FitArgs) -> anyhow::Result<()> {
    let mut taken = vec![source_path(args)];
    io::check_target(&args.output, &taken)?;
    taken.push(&args.output);
    let preview = super::render::preview_path(&args.output);
    if args.preview {
        if preview == args.output {
            anyhow::bail!(
                "{}: the preview would be written over the output; give the output a mesh extension",
                args.output.display()
            );
        }
        io::check_target(&preview, &taken)?;
        taken.push(&preview);
    }
    if let Some(r) = &args.report {
        if taken[1..].iter().any(|t| io::same_target(t, r)) {
            anyhow::bail!(
                "--report {}: the report would be written over an output",
                r.display()
            );
        }
        io::check_target(r, &taken)?;
    }
    Ok(())
}

/// Runs `drapekit fit`.
pub fn run(args: FitArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let wopts = WriteOptions {
        format: args.format,
        ascii: args.ascii,
    };
    check_args(&args, &wopts)?;
    let mut src = load(&args)?;
    let out_units = args.to_units.unwrap_or(src.units);
    let out_up = args.to_up.unwrap_or(src.up);
    let (mesh, fit) = fit_form(&args, &mut src, out_units, out_up)?;
    let inputs = [src.path.as_path()];
    let preview = write_form(&args, &mesh, &wopts, out_up, &inputs)?;
    let report = FitCliReport {
        input: src.path.display().to_string(),
        source: src.kind,
        measurement_format: src.format,
        notes: src.notes,
        output: args.output.display().to_string(),
        units: src.units,
        output_units: out_units,
        output_up: out_up,
        band: src.band,
        fit,
        wall_seconds: start.elapsed().as_secs_f64(),
        preview,
    };
    super::finish(
        &report,
        args.report.as_deref(),
        &inputs,
        &args.output,
        args.json,
        |r| print_summary(r, &args.output),
    )
}

/// The form fitted to the source's sections (taken from it), scaled to `units` and turned to
/// `up`; the fit's report.
fn fit_form(
    args: &FitArgs,
    src: &mut Source,
    units: Units,
    up: Up,
) -> anyhow::Result<(TriMesh, FitReport)> {
    let tolerance = args
        .tolerance
        .map(|(v, u)| v * u.map_or(1.0, |u| Units::factor(u, src.units)));
    let opts = FitOptions {
        nodes_around: args.nodes,
        lanczos: usize::from(args.lanczos),
        stride: args.stride,
        along: args.along,
        around: args.around,
        caps: !args.open,
        tolerance,
    };
    let sections = std::mem::take(&mut src.sections);
    let fitted = fit_sections(sections, &src.targets, &opts).map_err(|e| e.in_file(&src.path))?;
    let mut mesh = fitted.mesh;
    scale(&mut mesh, Units::factor(src.units, units));
    change_up(&mut mesh, Up::Z, up);
    Ok((mesh, fitted.report))
}

/// Writes the form and, with `--preview`, its picture from the front (committed together);
/// the preview's path.
fn write_form(
    args: &FitArgs,
    mesh: &TriMesh,
    wopts: &WriteOptions,
    up: Up,
    inputs: &[&Path],
) -> anyhow::Result<Option<String>> {
    let (staged, _) = io::stage_mesh(&args.output, mesh, wopts, inputs)?;
    let mut staged = vec![staged];
    let preview = if args.preview {
        let p = super::render::preview_path(&args.output);
        let item = crate::render::Item::object(mesh, super::render::OBJECT);
        let view = crate::render::View::Front;
        staged.push(super::render::stage_preview(&p, &[item], view, up, inputs)?);
        Some(p.display().to_string())
    } else {
        None
    };
    io::commit(staged)?;
    Ok(preview)
}

fn print_summary(r: &FitCliReport, out: &Path) {
    let f = &r.fit;
    println!(
        "{} ({}, {} sections) -> {} ({} vertices, {} faces, {}, {} {}-up)",
        r.input,
        r.source,
        f.sections_given,
        out.display(),
        f.output.vertices,
        f.output.faces,
        f.output.shell_state,
        r.output_units,
        r.output_up
    );
    println!(
        "  nodes: {} along x {} around, Lanczos order {}",
        f.nodes_along, f.nodes_around, f.lanczos
    );
    print_error(r);
    print_girths(f);
    println!(
        "  largest girth deviation {:.3}% over {} levels; {:.3} s",
        100.0 * f.max_girth_deviation,
        f.girths.len(),
        r.wall_seconds
    );
    for n in &r.notes {
        println!("  note: {n}");
    }
    for w in &f.warnings {
        println!("  warning: {w}");
    }
}

/// The estimated error, and the choice `--tolerance` made.
fn print_error(r: &FitCliReport) {
    let f = &r.fit;
    let e = &f.estimated_error;
    match e.total {
        Some(t) => println!(
            "  estimated error {:.3e} {} (around {:.3e}, along {:.3e})",
            t,
            r.units,
            e.around,
            e.along.unwrap_or(f64::NAN)
        ),
        None => println!(
            "  estimated error around {:.3e} {} (too few sections to estimate along)",
            e.around, r.units
        ),
    }
    if let Some(c) = &f.tolerance {
        println!(
            "  tolerance {:.3e} {}: chose {} nodes around, stride {}, order {} ({})",
            c.tolerance,
            r.units,
            c.nodes_around,
            c.stride,
            c.lanczos,
            if c.met { "met" } else { "NOT met" }
        );
    }
}

/// The girths of named levels (a measurement set's), requested against measured.
fn print_girths(f: &FitReport) {
    let named: Vec<_> = f
        .girths
        .iter()
        .filter(|g| !g.name.starts_with("section ") && !g.name.starts_with("level "))
        .collect();
    for g in &named {
        println!(
            "  {:<10} at {:.4}: requested {:.4}, measured {:.4} ({:+.3}%)",
            g.name,
            g.height,
            g.requested,
            g.measured,
            100.0 * g.deviation
        );
    }
}
