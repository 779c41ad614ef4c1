//! The command line: one subcommand per job. Arguments are validated into the library's option
//! structs before any work starts; errors print their whole chain and exit with status 1 (2 for
//! usage errors, from clap; 128 + the signal's number for a run that Ctrl-C or SIGTERM
//! stopped: `interrupt`).

mod batch;
mod bench;
mod bench_drape;
mod bench_fit;
mod bench_garment;
mod bench_inside;
mod bench_self;
mod bench_solver;
mod bench_speed;
mod convert;
mod drape;
mod drape_garment;
mod fit;
mod garment;
mod inspect;
mod interrupt;
mod render;

use crate::io::Format;
use crate::mesh::polygon::QuadSplit;
use clap::{Args, Parser, Subcommand};
use std::io::IsTerminal;
use std::process::ExitCode;

pub use crate::math::SplitMix;
pub use bench_drape::probe as bench_drape_probe;
pub use convert::ConvertReport;

/// drapekit: clean meshes from CAD exports, fitted mannequins, quick cloth drapes.
#[derive(Debug, Parser)]
#[command(name = "drapekit", version, about, max_term_width = 100)]
pub struct Cli {
    /// Worker threads (1 = serial; default: all cores). Results do not depend on it.
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub jobs: Option<u16>,
    #[command(subcommand)]
    pub command: Command,
}

/// The jobs.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Convert a mesh: read, weld, clean, orient outward, write; report what was fixed.
    Convert(convert::ConvertArgs),
    /// Inspect a mesh as it is: counts, boundaries, manifoldness, winding, volumes, shell state.
    Inspect(inspect::InspectArgs),
    /// Fit a mannequin (dress form) from sections, measurements or a scanned body.
    Fit(fit::FitArgs),
    /// Drape cloth on objects: the particle simulator with the paper's collision grid.
    Drape(drape::DrapeArgs),
    /// Sew a GarmentCode pattern on a body and let it hang (no scene file needed).
    Garment(garment::GarmentArgs),
    /// Draw meshes into a PNG or GIF: named views or three projections, coloured by strain,
    /// distance to the body or contact; a drape's frames as an animation.
    Render(render::RenderArgs),
    /// Batches: a plan's garments x bodies x fabrics x sizes, here or on a scheduler.
    #[command(subcommand)]
    Batch(batch::BatchCommand),
    /// Benchmarks (speed against a baseline in the same run).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

/// How to read an input mesh (shared by every subcommand that reads one).
#[derive(Debug, Clone, Args)]
pub struct ReadArgs {
    /// Input format (default: from the extension, else the content).
    #[arg(long, value_name = "FORMAT", value_parser = parse_format)]
    pub from: Option<Format>,
    /// How quads become triangles: `paper` = (r1,r2,r3)+(r3,r4,r1), `shortest` = shorter diagonal.
    #[arg(long, value_name = "RULE", default_value = "paper", value_parser = parse_quad_split)]
    pub quad_split: QuadSplit,
}

impl ReadArgs {
    /// The library's read options.
    pub fn options(&self) -> crate::io::ReadOptions {
        crate::io::ReadOptions {
            format: self.from,
            quad_split: self.quad_split,
        }
    }
}

fn parse_format(s: &str) -> Result<Format, String> {
    s.parse()
}

fn parse_quad_split(s: &str) -> Result<QuadSplit, String> {
    s.parse()
}

/// Runs the command line; the binary's `main` calls this.
pub fn main() -> ExitCode {
    // Die quietly when stdout is closed (`drapekit inspect x.obj | head`), as Unix tools do,
    // instead of panicking on the failed print. Outputs are complete before any summary prints.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    if let Some(n) = cli.jobs {
        // Only fails if a pool exists already, which cannot happen this early.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(usize::from(n))
            .build_global();
    }
    let result = match cli.command {
        Command::Convert(a) => convert::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Fit(a) => fit::run(a),
        Command::Drape(a) => drape::run(a),
        Command::Garment(a) => garment::run(a),
        Command::Render(a) => render::run(a),
        Command::Batch(b) => batch::run(b, cli.jobs),
        Command::Bench(b) => bench::run(b),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<interrupt::Interrupted>() => {
            eprintln!("{e}");
            let status = e
                .downcast_ref::<interrupt::Interrupted>()
                .map(|i| i.status());
            ExitCode::from(status.unwrap_or(1))
        }
        Err(e) => {
            eprintln!("error: {e}");
            // A cause the message before it already quotes is not printed again.
            let mut said = e.to_string();
            for cause in e.chain().skip(1).map(|c| c.to_string()) {
                if !said.contains(&cause) {
                    eprintln!("  caused by: {cause}");
                }
                said = cause;
            }
            ExitCode::FAILURE
        }
    }
}

/// The warning for `--ascii` with an output format that is text whatever the flag says (OBJ,
/// vertex triples); `None` when the flag chooses something (STL, PLY) or was not given.
pub fn ascii_warning(ascii: bool, format: Format) -> Option<String> {
    let what = match format {
        Format::Obj | Format::Triples => "is always text",
        Format::Glb => "is always binary",
        Format::Gltf => "is always JSON",
        Format::Stl | Format::Ply => return None,
    };
    ascii.then(|| {
        format!(
            "--ascii does nothing for {format} output ({format} {what}): it applies to STL and PLY"
        )
    })
}

/// Prints each warning on stderr.
pub fn warn(warnings: &[String]) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}

/// Removes the temporary files that killed runs left in `dirs` (`io::remove_stale_temps`),
/// and says so on stderr.
pub fn remove_stale_temps(dirs: &[&std::path::Path]) {
    let removed: Vec<_> = dirs
        .iter()
        .flat_map(|d| crate::io::remove_stale_temps(d))
        .collect();
    if !removed.is_empty() {
        let names: Vec<String> = removed.iter().map(|p| p.display().to_string()).collect();
        eprintln!(
            "note: removed {} temporary file{} left by a run that was killed: {}",
            removed.len(),
            if removed.len() == 1 { "" } else { "s" },
            names.join(", ")
        );
    }
}

/// Refuses an output that is a file: every job writes into a directory.
fn refuse_file_output(out: &std::path::Path) -> anyhow::Result<()> {
    if out.is_file() {
        anyhow::bail!(
            "{} is a file: the output must be a directory",
            out.display()
        );
    }
    Ok(())
}

/// Refuses, before any work, a `--report` that is one of `inputs`, the output folder, a
/// folder or in a missing folder (each was refused only when the report was written, after
/// the whole run: the outputs written, the report not).
pub fn check_report(
    report: Option<&std::path::Path>,
    output: &std::path::Path,
    inputs: &[&std::path::Path],
) -> anyhow::Result<()> {
    let Some(r) = report else {
        return Ok(());
    };
    if crate::io::same_target(r, output) {
        anyhow::bail!(
            "--report {}: the report would be written over the output folder",
            r.display()
        );
    }
    crate::io::check_target(r, inputs)?;
    Ok(())
}

/// Whether progress bars may be drawn (stderr is a terminal).
pub fn interactive() -> bool {
    std::io::stderr().is_terminal()
}

/// Writes a JSON report atomically (never over an input).
pub fn write_report<T: serde::Serialize>(
    path: &std::path::Path,
    report: &T,
    inputs: &[&std::path::Path],
) -> anyhow::Result<()> {
    crate::io::write_atomic(path, inputs, |w| {
        serde_json::to_writer_pretty(&mut *w, report)?;
        std::io::Write::write_all(w, b"\n")
    })?;
    Ok(())
}

/// The end of every job: the report file (if asked for, never over an input or the output),
/// then the JSON report or the human summary on stdout.
pub fn finish<T: serde::Serialize>(
    report: &T,
    report_path: Option<&std::path::Path>,
    inputs: &[&std::path::Path],
    output: &std::path::Path,
    json: bool,
    summary: impl FnOnce(&T),
) -> anyhow::Result<()> {
    use anyhow::Context;
    if let Some(r) = report_path {
        let mut all = inputs.to_vec();
        all.push(output);
        write_report(r, report, &all)
            .with_context(|| format!("{} was written, the report was not", output.display()))?;
    }
    if json {
        println!("{}", serde_json::to_string_pretty(report)?);
    } else {
        summary(report);
    }
    Ok(())
}
