//! `drapekit bench ...`: benchmarks. Speed-ups are ratios against a baseline measured in the
//! same run; times are medians; every run's output is checked before its time counts.

use crate::io::{self, ReadOptions};
pub use crate::math::SplitMix;
use crate::mesh::diagnose::{diagnose, ShellState};
use crate::mesh::generate;
use anyhow::{bail, ensure, Context};
use clap::Subcommand;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// The benchmarks.
#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Convert a flipped icosphere binary STL to binary PLY (weld + orient), optionally against trimesh.
    Convert(ConvertBench),
    /// Fit an analytic surface: error and time against nodes for each Lanczos order; fit speed.
    Fit(FitBench),
    /// The paper's collision-grid table on a torso, and integrator accuracy against step size.
    Drape(super::bench_drape::DrapeBench),
    /// The peers' scene: a 1 m square of real cotton dropped on a sphere, 1 s, timed.
    Speed(super::bench_speed::SpeedBench),
    /// The implicit integrators on real cotton: convergence of a step, damping, statics.
    Solver(super::bench_solver::SolverBench),
    /// Cloth against cloth: one step of self-contact on a 1 m sheet, one and two threads.
    SelfContact(super::bench_self::SelfContactBench),
    /// The inside test on a closed body: ray crossings against the winding number.
    Inside(super::bench_inside::InsideBench),
    /// The real patterns sewn and draped on the real bodies at 1 cm: time to rest, verdict.
    Garment(super::bench_garment::GarmentBench),
}

/// The most timed runs of a benchmark configuration (`--runs`).
pub const MAX_RUNS: i64 = 1000;

/// Arguments of `drapekit bench fit`.
#[derive(Debug, clap::Args)]
pub struct FitBench {
    /// Timed repetitions of each measurement (the median is reported).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(1..=super::bench::MAX_RUNS))]
    pub runs: u32,
    /// Also draw the error against the node intervals (log-log, a line per Lanczos order) as
    /// an SVG file.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<std::path::PathBuf>,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `drapekit bench convert`.
#[derive(Debug, clap::Args)]
pub struct ConvertBench {
    /// Icosphere subdivision level: 20 * 4^level triangles (8 gives 1,310,720).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=10))]
    pub level: u32,
    /// Fraction of faces flipped before writing the STL.
    #[arg(long, default_value_t = 0.3)]
    pub flip_fraction: f64,
    /// Timed runs of drapekit convert (the median is reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=super::bench::MAX_RUNS))]
    pub runs: u32,
    /// A Python with trimesh installed: also time trimesh's load + merge_vertices + fix_normals + export
    /// (tools/bench_convert.sh installs one in tools/.venv).
    #[arg(long, value_name = "PYTHON")]
    pub trimesh: Option<PathBuf>,
    /// Keep the generated files in this directory (default: a temporary one).
    #[arg(long, value_name = "DIR")]
    pub keep: Option<PathBuf>,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs a benchmark.
pub fn run(cmd: BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Convert(a) => bench_convert(a),
        BenchCommand::Fit(a) => super::bench_fit::run(a),
        BenchCommand::Drape(a) => super::bench_drape::run(a),
        BenchCommand::Speed(a) => super::bench_speed::run(a),
        BenchCommand::Solver(a) => super::bench_solver::run(a),
        BenchCommand::SelfContact(a) => super::bench_self::run(a),
        BenchCommand::Inside(a) => super::bench_inside::run(a),
        BenchCommand::Garment(a) => super::bench_garment::run(a),
    }
}

/// Wall time and peak memory of one child process.
struct Measured {
    seconds: f64,
    peak_mib: f64,
}

/// Runs `cmd` to completion, measuring its wall time and peak resident memory (from `wait4`).
fn measure(mut cmd: Command, log: &Path) -> anyhow::Result<Measured> {
    let err = std::fs::File::create(log)?;
    let start = Instant::now();
    let child = cmd
        .stdout(Stdio::null())
        .stderr(err)
        .spawn()
        .context("cannot start the benchmark process")?;
    let pid = child.id() as libc::pid_t;
    let mut status: libc::c_int = 0;
    // SAFETY: rusage is plain data, zeroed is a valid value; wait4 writes into both out-params
    // for the child we spawned and have not waited for.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let r = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    let seconds = start.elapsed().as_secs_f64();
    ensure!(
        r == pid,
        "wait4 failed: {}",
        std::io::Error::last_os_error()
    );
    if !(libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0) {
        bail!(
            "the benchmark process failed: {}",
            std::fs::read_to_string(log).unwrap_or_default()
        );
    }
    Ok(Measured {
        seconds,
        peak_mib: usage.ru_maxrss as f64 / 1024.0,
    })
}

/// The median of `v` (the mean of the middle two for an even count; NaNs sort last).
pub(super) fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

#[derive(Debug, Serialize)]
struct TrimeshTimes {
    version: String,
    load: f64,
    merge_vertices: f64,
    fix_normals: f64,
    export: f64,
    total: f64,
    wall: f64,
    faces: u64,
    vertices: u64,
    watertight: bool,
    winding_consistent: bool,
}

#[derive(Debug, Serialize)]
struct ConvertBenchReport {
    triangles: usize,
    flipped_in_input: usize,
    stl_bytes: u64,
    runs_seconds: Vec<f64>,
    runs_peak_mib: Vec<f64>,
    median_seconds: f64,
    peak_mib: f64,
    output_vertices: usize,
    output_faces: usize,
    output_shell_state: ShellState,
    trimesh: Option<TrimeshTimes>,
    speedup_vs_trimesh: Option<f64>,
}

/// The inputs of a convert benchmark: the flipped icosphere written as a binary STL.
struct Generated {
    /// The folder of the files: `--keep`'s, or the temporary one below.
    dir: PathBuf,
    /// The temporary folder (without `--keep`), removed when this is dropped.
    _tmp: Option<tempfile::TempDir>,
    /// The STL file.
    stl: PathBuf,
    /// The icosphere as written.
    sphere: crate::mesh::TriMesh,
    /// Its faces flipped.
    flipped: usize,
    /// The STL file's size.
    stl_bytes: u64,
}

fn bench_convert(a: ConvertBench) -> anyhow::Result<()> {
    ensure!(
        (0.0..=1.0).contains(&a.flip_fraction),
        "--flip-fraction must be within 0..1"
    );
    let say = |s: String| {
        if !a.json {
            println!("{s}");
        }
    };
    let g = generate_input(&a)?;
    say(format!(
        "bench convert: icosphere level {}, {} triangles ({} flipped), binary STL {:.1} MB -> binary PLY, weld + orient",
        a.level,
        g.sphere.faces.len(),
        g.flipped,
        g.stl_bytes as f64 / 1e6
    ));
    let ply = g.dir.join("icosphere.ply");
    let (secs, mibs) = time_converts(&a, &g, &ply, &say)?;
    // The output must be right for the times to mean anything.
    let (out, state) = check_output(&a, &g, &ply)?;
    let med = median(&secs);
    let peak = mibs.iter().cloned().fold(0.0, f64::max);
    say(format!(
        "  median {med:.3} s, peak memory {peak:.0} MiB; output {} vertices, {} faces, shell {}",
        out.positions.len(),
        out.faces.len(),
        state
    ));
    let trimesh = match &a.trimesh {
        Some(py) => Some(time_trimesh(py, &g, med, &say)?),
        None => None,
    };
    let report = ConvertBenchReport {
        triangles: g.sphere.faces.len(),
        flipped_in_input: g.flipped,
        stl_bytes: g.stl_bytes,
        runs_seconds: secs,
        runs_peak_mib: mibs,
        median_seconds: med,
        peak_mib: peak,
        output_vertices: out.positions.len(),
        output_faces: out.faces.len(),
        output_shell_state: state,
        speedup_vs_trimesh: trimesh.as_ref().map(|t| t.total / med),
        trimesh,
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    }
    Ok(())
}

/// The icosphere of `--level` with a `--flip-fraction` of its faces flipped (seed 42),
/// written as `icosphere.stl` into `--keep` or a temporary folder.
fn generate_input(a: &ConvertBench) -> anyhow::Result<Generated> {
    let mut tmp = None;
    let dir = match &a.keep {
        Some(d) => {
            std::fs::create_dir_all(d)?;
            d.clone()
        }
        None => tmp.insert(tempfile::tempdir()?).path().to_path_buf(),
    };
    let stl = dir.join("icosphere.stl");
    let mut sphere = generate::icosphere(a.level);
    let mut rng = SplitMix(42);
    let mut flipped = 0;
    for f in 0..sphere.faces.len() {
        if rng.next_f64() < a.flip_fraction {
            sphere.flip_face(f);
            flipped += 1;
        }
    }
    io::write_mesh(&stl, &sphere, &io::WriteOptions::default(), &[])?;
    let stl_bytes = std::fs::metadata(&stl)?.len();
    Ok(Generated {
        dir,
        _tmp: tmp,
        stl,
        sphere,
        flipped,
        stl_bytes,
    })
}

/// Times `--runs` runs of `drapekit convert` from the STL to `ply` (each line said); returns
/// each run's wall time and peak memory.
fn time_converts(
    a: &ConvertBench,
    g: &Generated,
    ply: &Path,
    say: &dyn Fn(String),
) -> anyhow::Result<(Vec<f64>, Vec<f64>)> {
    let log = g.dir.join("convert.log");
    let exe = std::env::current_exe()?;
    let mut secs = Vec::new();
    let mut mibs = Vec::new();
    say("  run   wall s   peak MiB".into());
    for r in 0..a.runs {
        let _ = std::fs::remove_file(ply);
        let mut cmd = Command::new(&exe);
        cmd.arg("convert").arg(&g.stl).arg("-o").arg(ply);
        let m = measure(cmd, &log)?;
        say(format!(
            "  {:>3}   {:>6.3}   {:>8.1}",
            r + 1,
            m.seconds,
            m.peak_mib
        ));
        secs.push(m.seconds);
        mibs.push(m.peak_mib);
    }
    Ok((secs, mibs))
}

/// The converted mesh and its shell state, refused unless it has the sphere's faces and
/// vertices and is closed.
fn check_output(
    a: &ConvertBench,
    g: &Generated,
    ply: &Path,
) -> anyhow::Result<(crate::mesh::TriMesh, ShellState)> {
    let out = io::read_mesh(ply, &ReadOptions::default())?.mesh;
    let d = diagnose(&out);
    ensure!(
        out.faces.len() == g.sphere.faces.len(),
        "output has {} faces, expected {}",
        out.faces.len(),
        g.sphere.faces.len()
    );
    ensure!(
        out.positions.len() == 10 * 4usize.pow(a.level) + 2,
        "output has {} vertices",
        out.positions.len()
    );
    ensure!(
        d.shell_state == ShellState::Closed,
        "output shell state is {}, expected closed",
        d.shell_state
    );
    Ok((out, d.shell_state))
}

/// Times trimesh (`tools/trimesh_convert.py` run by the Python `py`) on the same STL, and
/// says its times and the speed-up against drapekit's median `med`.
fn time_trimesh(
    py: &Path,
    g: &Generated,
    med: f64,
    say: &dyn Fn(String),
) -> anyhow::Result<TrimeshTimes> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/trimesh_convert.py");
    let tply = g.dir.join("icosphere_trimesh.ply");
    say(format!(
        "  trimesh: running {} (this takes minutes) ...",
        script.display()
    ));
    let start = Instant::now();
    let o = Command::new(py)
        .arg(&script)
        .arg(&g.stl)
        .arg(&tply)
        .output()
        .context("cannot run the trimesh script")?;
    let wall = start.elapsed().as_secs_f64();
    ensure!(
        o.status.success(),
        "the trimesh script failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&o.stdout).context("the trimesh script printed no JSON")?;
    let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let t = TrimeshTimes {
        version: v["version"].as_str().unwrap_or("?").into(),
        load: f("load"),
        merge_vertices: f("merge_vertices"),
        fix_normals: f("fix_normals"),
        export: f("export"),
        total: f("total"),
        wall,
        faces: v["faces"].as_u64().unwrap_or(0),
        vertices: v["vertices"].as_u64().unwrap_or(0),
        watertight: v["watertight"].as_bool().unwrap_or(false),
        winding_consistent: v["winding_consistent"].as_bool().unwrap_or(false),
    };
    say(format!(
        "  trimesh {}: load {:.2} s, merge_vertices {:.2} s, fix_normals {:.2} s, export {:.2} s; total {:.2} s ({} faces, {} vertices, watertight {}, winding consistent {})",
        t.version, t.load, t.merge_vertices, t.fix_normals, t.export, t.total, t.faces, t.vertices, t.watertight, t.winding_consistent
    ));
    say(format!(
        "  speed-up: {:.0}x (trimesh total / drapekit median wall)",
        t.total / med
    ));
    Ok(t)
}
