//! `drapekit inspect FILE`: the diagnosis of a mesh as it is.

use super::{write_report, ReadArgs};
use crate::io::{self, ReadInfo};
use crate::mesh::diagnose::{diagnose, Diagnosis};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `drapekit inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The mesh to inspect.
    pub file: PathBuf,
    /// Print the JSON report instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON report here.
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub read: ReadArgs,
}

/// The JSON report of `inspect`: the file, what the reader found, and the diagnosis keys at
/// the top level.
#[derive(Debug, Serialize)]
pub struct InspectReport {
    /// The file.
    pub file: String,
    /// What the reader found.
    pub read: ReadInfo,
    /// The diagnosis.
    #[serde(flatten)]
    pub diagnosis: Diagnosis,
}

/// Six decimals, or six significant digits below 0.001 (a 1 mm cube in metres has a volume of
/// 1e-9, which six decimals show as 0.000000).
fn six(x: f64) -> String {
    if x != 0.0 && x.abs() < 1e-3 {
        format!("{x:.5e}")
    } else {
        format!("{x:.6}")
    }
}

/// Runs `drapekit inspect`.
pub fn run(args: InspectArgs) -> anyhow::Result<()> {
    if let Some(r) = &args.report {
        io::check_target(r, &[args.file.as_path()])?;
    }
    let read = io::read_mesh(&args.file, &args.read.options())?;
    let d = diagnose(&read.mesh);
    let report = InspectReport {
        file: args.file.display().to_string(),
        read: read.info,
        diagnosis: d,
    };
    if let Some(r) = &args.report {
        write_report(r, &report, &[args.file.as_path()])?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    print_summary(&report);
    Ok(())
}

/// The report as lines of text.
fn print_summary(report: &InspectReport) {
    let d = &report.diagnosis;
    println!("{} ({})", report.file, report.read.format);
    println!(
        "  {} vertices ({} unreferenced), {} faces, {} edges",
        d.vertices, d.unreferenced_vertices, d.faces, d.edges
    );
    if let Some(b) = &d.bbox {
        println!(
            "  bbox {:?} .. {:?} (diagonal {})",
            b.min,
            b.max,
            six(b.diagonal)
        );
    }
    println!(
        "  {} components ({} closed, {} open)",
        d.components, d.closed_components, d.open_components
    );
    println!(
        "  boundary: {} edges in {} loops; non-manifold: {} edges, {} vertices",
        d.boundary_edges, d.boundary_loops, d.non_manifold_edges, d.non_manifold_vertices
    );
    println!(
        "  degenerate faces {}, duplicate faces {}, near-duplicate vertices {}",
        d.degenerate_faces,
        d.duplicate_faces,
        d.near_duplicate_vertices.unwrap_or(0)
    );
    println!(
        "  winding consistent: {}, outward: {}, watertight: {}, Euler characteristic {}",
        d.winding_consistent, d.outward, d.watertight, d.euler_characteristic
    );
    print_volumes(d);
    println!("  shell state: {}", d.shell_state);
    for w in &report.read.warnings {
        println!("  note: {w}");
    }
}

/// The closed volumes (the first 8, and how many in all), if any.
fn print_volumes(d: &Diagnosis) {
    if !d.volumes.is_empty() {
        let shown: Vec<String> = d.volumes.iter().take(8).map(|v| six(v.volume)).collect();
        let more = if d.volumes.len() > 8 {
            format!(" ... ({} in all)", d.volumes.len())
        } else {
            String::new()
        };
        println!(
            "  closed volumes: {}{} (total {})",
            shown.join(", "),
            more,
            six(d.total_volume)
        );
    }
}
