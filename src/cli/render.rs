//! `drapekit render MESH... -o PICTURE`: pictures of meshes, coloured by strain, distance or
//! contact; a drape's frames as an animation; and the previews other commands write.

use super::ReadArgs;
use crate::io;
use crate::mesh::transform::Up;
use crate::mesh::TriMesh;
use crate::render::{self, field, ColourScale, Image, Item, Layout, RenderOptions, Rgb, Shading};
use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The default colour of the cloth (the first mesh, or a frame's pieces).
pub const CLOTH: Rgb = [0xe0, 0x7a, 0x5f];
/// The default colour of the other meshes.
pub const OBJECT: Rgb = [0xb4, 0xb4, 0xb4];

/// Arguments of `drapekit render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The meshes: the cloth (or garment) first, then the objects under it. Or a drape's
    /// `frames/` folder first (an animation: every piece of each frame is cloth), then objects.
    #[arg(required = true, value_name = "MESH")]
    pub meshes: Vec<PathBuf>,
    /// The picture: `.png` (an animated PNG for frames) or `.gif`.
    #[arg(short, long, value_name = "PICTURE")]
    pub output: PathBuf,
    /// front, back, side, top, iso, xy, xz, yz, or projections (XY, XZ, YZ side by side).
    #[arg(long, default_value = "iso", value_parser = parse_layout)]
    pub view: Layout,
    /// Picture width, px (16 to 8192).
    #[arg(long, default_value_t = 800)]
    pub width: u32,
    /// Picture height, px (16 to 8192).
    #[arg(long, default_value_t = 600)]
    pub height: u32,
    /// Background colour, `#rrggbb`.
    #[arg(long, default_value = "#ffffff", value_parser = parse_colour)]
    pub background: Rgb,
    /// Colours of the meshes in order, `#rrggbb,#rrggbb,...` (default: the cloth terracotta,
    /// the objects grey). With frames, the first is the cloth's.
    #[arg(long, value_name = "COLOURS", value_delimiter = ',', value_parser = parse_colour)]
    pub mesh_colors: Vec<Rgb>,
    /// Colour the cloth by a quantity, with a legend.
    #[arg(long, value_enum, default_value_t = Quantity::Plain)]
    pub color: Quantity,
    /// The body for `distance` and `contact` (default: every mesh after the cloth).
    #[arg(long, value_name = "BODY")]
    pub to: Option<PathBuf>,
    /// `contact`: largest distance that counts as contact, in the meshes' unit (default 3 mm
    /// in metres: drapekit keeps cloth about a fabric thickness, 0.5 to 2 mm, off a body).
    #[arg(long, value_name = "D", default_value_t = 0.003)]
    pub contact_distance: f64,
    /// Colour scale `MIN:MAX` (default: the values' own range, over all frames).
    #[arg(long, value_name = "MIN:MAX", value_parser = parse_range)]
    pub range: Option<[f64; 2]>,
    /// Draw the cloth this much nearer the camera, in the meshes' unit, so a body's facets do
    /// not show through a cloth resting on it (default: 0.2% of the scene's diagonal; 0: off).
    #[arg(long, value_name = "D")]
    pub cloth_lift: Option<f64>,
    /// The up axis, for the named views.
    #[arg(long, default_value = "z")]
    pub up: Up,
    /// `flat` (facets show) or `smooth` (vertex normals).
    #[arg(long, default_value = "smooth")]
    pub shading: Shading,
    /// Frames per second of an animation.
    #[arg(long, default_value_t = 10.0)]
    pub fps: f64,
    /// Print the JSON report instead of the summary.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub read: ReadArgs,
}

/// What colours the cloth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Quantity {
    /// Its colour.
    Plain,
    /// Strain against the flat pattern (the `vt` of drapekit's drape and garment outputs).
    Strain,
    /// Distance to the body (a fit map), in the meshes' unit.
    Distance,
    /// Within `--contact-distance` of the body, or not.
    Contact,
}

/// One mesh in the report.
#[derive(Debug, Serialize)]
pub struct MeshReport {
    /// The file.
    pub path: String,
    /// Vertices.
    pub vertices: usize,
    /// Faces.
    pub faces: usize,
    /// Coloured by the quantity (the cloth).
    pub cloth: bool,
}

/// The JSON report of `render`.
#[derive(Debug, Serialize)]
pub struct RenderReport {
    /// The picture.
    pub output: String,
    /// `png`, `apng` or `gif`.
    pub format: String,
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Frames (1 for a still).
    pub frames: usize,
    /// The view (`projections`: XY, XZ, YZ).
    pub view: String,
    /// Pixels per length unit (every panel and frame has the same).
    pub pixels_per_unit: f64,
    /// What colours the cloth.
    pub color: Quantity,
    /// The values' range over all frames (`null` for `plain`).
    pub value_range: Option<[f64; 2]>,
    /// The legend's range (`--range`, else `value_range`).
    pub scale_range: Option<[f64; 2]>,
    /// The meshes of the first frame (the frames' pieces: one entry each).
    pub meshes: Vec<MeshReport>,
}

fn parse_layout(s: &str) -> Result<Layout, String> {
    s.parse()
}

/// `#rrggbb` (or `rrggbb`).
pub fn parse_colour(s: &str) -> Result<Rgb, String> {
    let h = s.trim().trim_start_matches('#');
    let bad = || format!("colour '{s}': expected #rrggbb (six hexadecimal digits)");
    if h.len() != 6 || !h.is_ascii() {
        return Err(bad());
    }
    let mut c = [0u8; 3];
    for (k, v) in c.iter_mut().enumerate() {
        *v = u8::from_str_radix(&h[2 * k..2 * k + 2], 16).map_err(|_| bad())?;
    }
    Ok(c)
}

fn parse_range(s: &str) -> Result<[f64; 2], String> {
    let bad = || {
        format!(
            "range '{s}': expected MIN:MAX, two finite numbers with MIN < MAX and MAX - MIN finite"
        )
    };
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let (a, b): (f64, f64) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    // A span beyond the numbers (-1e308:1e308) coloured every value as the minimum.
    if !(a < b && (b - a).is_finite()) {
        return Err(bad());
    }
    Ok([a, b])
}

/// The picture's encoding, from the output's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Png,
    Gif,
}

fn encoding(path: &Path) -> anyhow::Result<Encoding> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("png" | "apng") => Ok(Encoding::Png),
        Some("gif") => Ok(Encoding::Gif),
        _ => bail!(
            "{}: the picture must be .png (an animated PNG for frames) or .gif",
            path.display()
        ),
    }
}

/// The frame files of a drape's `frames/` folder (`<piece>_<step>.obj`), grouped by step in
/// step order, each step's pieces in name order.
pub fn frame_files(dir: &Path) -> anyhow::Result<Vec<(u64, Vec<PathBuf>)>> {
    let mut steps: BTreeMap<u64, Vec<PathBuf>> = BTreeMap::new();
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))?;
    for e in entries {
        let path = e
            .with_context(|| format!("cannot read {}", dir.display()))?
            .path();
        if path.extension().and_then(|x| x.to_str()) != Some("obj") {
            continue;
        }
        let (_, step) = piece_and_step(&path).with_context(|| {
            format!(
                "{}: a frame file is named <piece>_<step>.obj (as drape writes them)",
                path.display()
            )
        })?;
        steps.entry(step).or_default().push(path);
    }
    if steps.is_empty() {
        bail!(
            "{}: no frame files (<piece>_<step>.obj) in the folder",
            dir.display()
        );
    }
    for files in steps.values_mut() {
        files.sort_by_key(|f| piece_and_step(f).map(|(p, _)| p));
    }
    Ok(steps.into_iter().collect())
}

/// The piece and step of a frame file `<piece>_<step>.obj`.
fn piece_and_step(path: &Path) -> Option<(String, u64)> {
    let stem = path.file_stem()?.to_str()?;
    let (piece, n) = stem.rsplit_once('_')?;
    if n.is_empty() || !n.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((piece.to_string(), n.parse().ok()?))
}

fn file_name(p: &Path) -> std::borrow::Cow<'_, str> {
    p.file_name().unwrap_or(p.as_os_str()).to_string_lossy()
}

/// What keeps the steps from showing the same pieces once each: a piece twice at a step
/// (`a_01.obj` and `a_1.obj`), or a step with other pieces than the first (two runs' frames).
fn piece_problems(steps: &[(u64, Vec<PathBuf>)]) -> Vec<String> {
    let mut problems = Vec::new();
    let mut first: Option<(u64, Vec<String>)> = None;
    for (step, files) in steps {
        let names: Vec<String> = (files.iter().filter_map(|f| piece_and_step(f)))
            .map(|x| x.0)
            .collect();
        for (k, w) in names.windows(2).enumerate().filter(|(_, w)| w[0] == w[1]) {
            problems.push(format!(
                "{} and {} are both piece '{}' at step {step}",
                file_name(&files[k]),
                file_name(&files[k + 1]),
                w[0]
            ));
        }
        match &first {
            None => first = Some((*step, names)),
            Some((s0, n0)) if *n0 != names => problems.push(format!(
                "step {step} has the piece(s) {}, step {s0} has {}",
                names.join(", "),
                n0.join(", ")
            )),
            Some(_) => {}
        }
    }
    problems
}

/// What keeps each piece from having one mesh at every step: its vertex or face count changes
/// from the piece's first frame.
fn mesh_problems(frames: &[Vec<Loaded>]) -> Vec<String> {
    let size = |l: &Loaded| (l.mesh.positions.len(), l.mesh.faces.len());
    let mut first: BTreeMap<String, &Loaded> = BTreeMap::new();
    let mut problems = Vec::new();
    for b in frames.iter().flatten() {
        let name = piece_and_step(&b.path).map(|x| x.0).unwrap_or_default();
        let a = *first.entry(name).or_insert(b);
        if size(a) != size(b) {
            problems.push(format!(
                "{} has {} vertices and {} faces, {} has {} and {}",
                file_name(&b.path),
                b.mesh.positions.len(),
                b.mesh.faces.len(),
                file_name(&a.path),
                a.mesh.positions.len(),
                a.mesh.faces.len()
            ));
        }
    }
    problems
}

/// Refuses a frames folder with `problems` (at most 20 listed, the rest counted).
fn frame_problems(dir: &Path, problems: Vec<String>) -> anyhow::Result<()> {
    const SHOWN: usize = 20;
    let why = "the frames of one drape show the same pieces, each with its mesh, at every step";
    match problems.len() {
        0 => Ok(()),
        1 => bail!("{}: {}: {why}", dir.display(), problems[0]),
        n => {
            let mut list: String = (problems.iter().take(SHOWN))
                .map(|p| format!("\n  {p}"))
                .collect();
            if n > SHOWN {
                list += &format!("\n  ... and {} more", n - SHOWN);
            }
            bail!(
                "{}: {n} problems in the frames folder ({why}):{list}",
                dir.display()
            )
        }
    }
}

/// A mesh read for drawing, with its rest coordinates if it has them.
struct Loaded {
    path: PathBuf,
    mesh: TriMesh,
    rest: Option<Vec<[f64; 2]>>,
}

fn load(path: &Path, read: &ReadArgs) -> anyhow::Result<Loaded> {
    let r = io::read_mesh(path, &read.options())?;
    Ok(Loaded {
        path: path.to_path_buf(),
        mesh: r.mesh,
        rest: r.texcoords,
    })
}

/// Per-vertex values of a cloth mesh.
fn values(
    cloth: &Loaded,
    q: Quantity,
    body: Option<&TriMesh>,
    contact_distance: f64,
) -> anyhow::Result<Option<Vec<f64>>> {
    Ok(match q {
        Quantity::Plain => None,
        Quantity::Strain => {
            let rest = cloth.rest.as_deref().with_context(|| {
                format!(
                    "{}: no rest coordinates (one `vt` per vertex): --color strain needs a drape \
                     or garment output written by drapekit",
                    cloth.path.display()
                )
            })?;
            let strain = render::strain::vertex_strain(&cloth.mesh, rest);
            Some(strain.map_err(|e| anyhow::anyhow!("{}: strain: {e}", cloth.path.display()))?)
        }
        Quantity::Distance | Quantity::Contact => {
            let body = body.expect("a body is checked for before");
            let d = field::distances(&cloth.mesh, body);
            Some(if q == Quantity::Contact {
                field::contact(&d, contact_distance)
            } else {
                d
            })
        }
    })
}

/// The colour scale for `q` over `values` (or `range`).
fn scale(q: Quantity, range: [f64; 2]) -> Option<ColourScale> {
    let title = match q {
        Quantity::Plain => return None,
        Quantity::Contact => return Some(ColourScale::Contact),
        Quantity::Strain => "STRAIN",
        Quantity::Distance => "DISTANCE",
    };
    Some(ColourScale::Continuous {
        min: range[0],
        max: range[1],
        title: title.into(),
    })
}

/// The whole job, checked.
struct Job {
    /// Frames of cloth meshes (one frame for a still).
    frames: Vec<Vec<Loaded>>,
    /// The objects, in every frame.
    objects: Vec<Loaded>,
    encoding: Encoding,
    animated: bool,
}

/// The slowest animation: 50 s a frame (an APNG delay is at most 65,535 ms).
pub const MIN_FPS: f64 = 0.02;

/// The picture's options; the colour scale over `range` (`0:1` until the values are known).
fn options(args: &RenderArgs, range: Option<[f64; 2]>) -> RenderOptions {
    RenderOptions {
        width: args.width,
        height: args.height,
        layout: args.view,
        up: args.up,
        background: args.background,
        shading: args.shading,
        scale: scale(args.color, range.unwrap_or([0.0, 1.0])),
    }
}

/// Checks the flags and the output, before any file is read.
fn check_flags(args: &RenderArgs) -> anyhow::Result<Encoding> {
    let enc = encoding(&args.output)?;
    options(args, None).check_size()?;
    if !(args.fps.is_finite() && (MIN_FPS..=100.0).contains(&args.fps)) {
        bail!(
            "--fps {}: must be {MIN_FPS} to 100 (a frame shows at most 50 s)",
            args.fps
        );
    }
    if !(args.contact_distance.is_finite() && args.contact_distance >= 0.0) {
        bail!(
            "--contact-distance {}: must be 0 or more",
            args.contact_distance
        );
    }
    if let Some(l) = args.cloth_lift.filter(|l| !(l.is_finite() && *l >= 0.0)) {
        bail!("--cloth-lift {l}: must be 0 or more");
    }
    let measured = matches!(args.color, Quantity::Distance | Quantity::Contact);
    if args.to.is_some() && !measured {
        bail!("--to gives the body of --color distance or contact");
    }
    if args.range.is_some() && !matches!(args.color, Quantity::Strain | Quantity::Distance) {
        bail!("--range applies to --color strain and distance");
    }
    if args.mesh_colors.len() > args.meshes.len() {
        bail!(
            "--mesh-colors: {} colours for {} mesh(es): one per mesh given, in order",
            args.mesh_colors.len(),
            args.meshes.len()
        );
    }
    let inputs: Vec<&Path> = args
        .meshes
        .iter()
        .chain(&args.to)
        .map(|p| p.as_path())
        .collect();
    io::check_target(&args.output, &inputs)?;
    Ok(enc)
}

/// Reads the inputs.
fn gather(args: &RenderArgs) -> anyhow::Result<Job> {
    let encoding = check_flags(args)?;
    let first = &args.meshes[0];
    let animated = first.is_dir();
    let frames: Vec<Vec<Loaded>> = if animated {
        let steps = frame_files(first)?;
        let frames: Vec<Vec<Loaded>> = (steps.iter())
            .map(|(_, files)| files.iter().map(|f| load(f, &args.read)).collect())
            .collect::<anyhow::Result<_>>()?;
        let mut problems = piece_problems(&steps);
        problems.extend(mesh_problems(&frames));
        frame_problems(first, problems)?;
        frames
    } else {
        vec![vec![load(first, &args.read)?]]
    };
    let objects = args.meshes[1..]
        .iter()
        .map(|p| {
            if p.is_dir() {
                bail!(
                    "{}: only the first argument may be a frames folder",
                    p.display()
                );
            }
            load(p, &args.read)
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok(Job {
        frames,
        objects,
        encoding,
        animated,
    })
}

/// The body for distance and contact: `--to`, else the objects joined.
fn body(args: &RenderArgs, job: &Job) -> anyhow::Result<Option<TriMesh>> {
    if !matches!(args.color, Quantity::Distance | Quantity::Contact) {
        return Ok(None);
    }
    let body = match &args.to {
        Some(p) => load(p, &args.read)?.mesh,
        None => field::join(job.objects.iter().map(|o| &o.mesh)),
    };
    if let Some(p) = args.to.as_ref().filter(|_| body.faces.is_empty()) {
        bail!(
            "--to {}: the body has no faces to measure against",
            p.display()
        );
    }
    if body.faces.is_empty() {
        bail!(
            "--color {}: no body with faces to measure against (give --to BODY, or the body after the cloth)",
            format!("{:?}", args.color).to_lowercase()
        );
    }
    Ok(Some(body))
}

/// The smallest and largest of every frame's values.
fn value_range(values: &[Vec<Option<Vec<f64>>>]) -> Option<[f64; 2]> {
    let all = values.iter().flatten().flatten().flatten();
    let (lo, hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
        (a.min(v), b.max(v))
    });
    (lo <= hi).then_some([lo, hi])
}

/// Runs `drapekit render`.
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let job = gather(&args)?;
    // The temporary pictures of renders that were killed (a second signal, or SIGKILL).
    let folder = args.output.parent().filter(|p| !p.as_os_str().is_empty());
    super::remove_stale_temps(&[folder.unwrap_or(Path::new("."))]);
    let body = body(&args, &job)?;
    let values = frame_values(&args, &job, body.as_ref())?;
    let value_range = value_range(&values);
    let scale_range = args
        .range
        .or(value_range)
        .filter(|_| args.color != Quantity::Contact);
    let opts = options(&args, scale_range);
    let framing = render::frame(&opts, || all_points(&job))?;
    let lift = args
        .cloth_lift
        .unwrap_or_else(|| render::default_lift(all_points(&job)));
    let items = |k: usize| frame_items(&args, &job, &values[k], k, lift);
    for k in 0..job.frames.len() {
        render::check(&items(k))?;
    }
    write_pictures(&args, &job, |k| render::render(&items(k), &framing, &opts))?;
    let ranges = [value_range, scale_range];
    let report = render_report(&args, &job, framing.cameras[0].scale, ranges);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_summary(&report);
    }
    Ok(())
}

/// Per-vertex values of each frame's cloth meshes (`None` for `plain`).
type FrameValues = Vec<Vec<Option<Vec<f64>>>>;

/// The values of every frame's cloth meshes, frame by frame.
fn frame_values(
    args: &RenderArgs,
    job: &Job,
    body: Option<&TriMesh>,
) -> anyhow::Result<FrameValues> {
    job.frames
        .iter()
        .map(|f| {
            f.iter()
                .map(|c| values(c, args.color, body, args.contact_distance))
                .collect()
        })
        .collect()
}

/// Every point of every frame and object (what the camera and the lift are fitted to).
fn all_points(job: &Job) -> impl Iterator<Item = &crate::math::Point3> {
    job.frames
        .iter()
        .flatten()
        .chain(&job.objects)
        .flat_map(|l| l.mesh.positions.iter())
}

/// Frame `k`'s items: its cloth meshes (coloured by `values`, lifted), then the objects.
fn frame_items<'a>(
    args: &RenderArgs,
    job: &'a Job,
    values: &'a [Option<Vec<f64>>],
    k: usize,
    lift: f64,
) -> Vec<Item<'a>> {
    let colour = |k: usize, default: Rgb| args.mesh_colors.get(k).copied().unwrap_or(default);
    let cloth = job.frames[k].iter().zip(values);
    cloth
        .map(|(c, v)| Item::cloth(&c.mesh, colour(0, CLOTH), v.as_deref(), lift))
        .chain(
            job.objects
                .iter()
                .enumerate()
                .map(|(k, o)| Item::object(&o.mesh, colour(k + 1, OBJECT))),
        )
        .collect()
}

/// The report of a job drawn at `pixels_per_unit`; `ranges`: the values' and the scale's.
fn render_report(
    args: &RenderArgs,
    job: &Job,
    pixels_per_unit: f64,
    [value_range, scale_range]: [Option<[f64; 2]>; 2],
) -> RenderReport {
    RenderReport {
        output: args.output.display().to_string(),
        format: match (job.encoding, job.animated) {
            (Encoding::Gif, _) => "gif",
            (Encoding::Png, true) => "apng",
            (Encoding::Png, false) => "png",
        }
        .into(),
        width: args.width,
        height: args.height,
        frames: job.frames.len(),
        view: view_name(args.view),
        pixels_per_unit,
        color: args.color,
        value_range,
        scale_range,
        meshes: job.frames[0]
            .iter()
            .map(|l| (l, true))
            .chain(job.objects.iter().map(|l| (l, false)))
            .map(|(l, cloth)| MeshReport {
                path: l.path.display().to_string(),
                vertices: l.mesh.positions.len(),
                faces: l.mesh.faces.len(),
                cloth,
            })
            .collect(),
    }
}

fn view_name(l: Layout) -> String {
    match l {
        Layout::Projections => "projections".into(),
        Layout::View(v) => serde_json::to_value(v)
            .ok()
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_default(),
    }
}

/// Draws the pictures (`draw(k)` is frame `k`) into the output, atomically, never over an
/// input; an animation's frames one at a time, each encoded before the next is drawn.
fn write_pictures(
    args: &RenderArgs,
    job: &Job,
    draw: impl Fn(usize) -> Result<Image, render::RenderError>,
) -> anyhow::Result<()> {
    let mut inputs: Vec<&Path> = job
        .frames
        .iter()
        .flatten()
        .chain(&job.objects)
        .map(|l| l.path.as_path())
        .collect();
    if let Some(t) = &args.to {
        inputs.push(t);
    }
    let delay_ms = (1000.0 / args.fps).round() as u16;
    let (n, size) = (job.frames.len(), [args.width, args.height]);
    // SIGINT or SIGTERM stops the drawing between frames; the picture is then not written.
    let signals = super::interrupt::install()?;
    let stop = || signals.cancel().load(std::sync::atomic::Ordering::SeqCst);
    let drawn = |k: usize| {
        if stop() {
            return Err(std::io::Error::other("interrupted"));
        }
        draw(k).map_err(std::io::Error::other)
    };
    let frames = (0..n).map(&drawn);
    let written = io::write_atomic(&args.output, &inputs, |w| {
        match (job.encoding, job.animated) {
            (Encoding::Gif, _) => render::image::write_gif(w, size, (delay_ms / 10).max(1), frames),
            (Encoding::Png, true) => render::image::write_apng(w, size, n, delay_ms, frames),
            (Encoding::Png, false) => render::image::write_png(w, &drawn(0)?),
        }
    });
    if written.is_err() && stop() {
        let out = args.output.display();
        return Err(signals
            .interrupted(format_args!("while drawing {out}: nothing was written"))
            .into());
    }
    written?;
    Ok(())
}

fn print_summary(r: &RenderReport) {
    let range = match (r.color, r.value_range) {
        (Quantity::Plain, _) => String::new(),
        (q, Some([a, b])) => format!(
            "; {q:?} {} to {}",
            crate::math::short(a),
            crate::math::short(b)
        )
        .to_lowercase(),
        (q, None) => format!("; {q:?}").to_lowercase(),
    };
    println!(
        "{}: {} x {} px {}, {} frame(s), {} view, {} px per unit{}",
        r.output,
        r.width,
        r.height,
        r.format,
        r.frames,
        r.view,
        crate::math::short(r.pixels_per_unit),
        range
    );
}

/// The preview of a command's output: `items` drawn at 640 x 480 from `view`, as PNG bytes'
/// writer staged at `path` (committed with the command's other outputs).
pub fn stage_preview(
    path: &Path,
    items: &[Item],
    view: render::View,
    up: Up,
    inputs: &[&Path],
) -> anyhow::Result<io::Staged> {
    let opts = RenderOptions {
        width: 640,
        height: 480,
        layout: Layout::View(view),
        up,
        ..RenderOptions::default()
    };
    let img = render::render_fitted(items, &opts)
        .with_context(|| format!("{}: the preview", path.display()))?;
    Ok(io::stage(path, inputs, |w| {
        render::image::write_png(w, &img)
    })?)
}

/// `<output without its extension>.png`.
pub fn preview_path(output: &Path) -> PathBuf {
    output.with_extension("png")
}
