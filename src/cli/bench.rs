//! `drapekit bench ...`: benchmarks. Speed-ups are ratios against a baseline measured in the
//! same run; times are medians.

use clap::Subcommand;

/// The benchmarks.
#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Convert a flipped icosphere binary STL to binary PLY (weld + orient).
    Convert(ConvertBench),
}

/// Arguments of `drapekit bench convert`.
#[derive(Debug, clap::Args)]
pub struct ConvertBench {
    /// Icosphere subdivision level: 20 * 4^level triangles (8 gives 1,310,720).
    #[arg(long, default_value_t = 8)]
    pub level: u32,
}

/// Runs a benchmark.
pub fn run(cmd: BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Convert(_) => anyhow::bail!("not yet"),
    }
}
