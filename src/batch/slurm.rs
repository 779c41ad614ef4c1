//! The `sbatch` array script of a batch.
//!
//! One array task per position (`--array=0-(N-1)`, `%K` when the plan's `resources.throttle`
//! is K > 0), each with the plan's per-job resources (`--cpus-per-task`, `--mem` in MB, `--time`
//! in minutes) and its log in `OUT/logs/<array job>_<task>.{out,err}`. Every task runs the same
//! command, `drapekit batch run PLAN -o OUT`, which reads its position from
//! `SLURM_ARRAY_TASK_ID` and its threads from `SLURM_CPUS_PER_TASK`. Paths are absolute and
//! shell-quoted.

use super::plan::Resources;
use std::path::Path;

/// What the script needs.
#[derive(Debug, Clone)]
pub struct SlurmOptions<'a> {
    /// The drapekit binary (absolute).
    pub exe: &'a Path,
    /// The plan (absolute).
    pub plan: &'a Path,
    /// The output folder (absolute).
    pub out: &'a Path,
    /// Positions (array tasks 0 to positions - 1).
    pub positions: usize,
    /// Per-job resources and the throttle.
    pub resources: Resources,
    /// The partition (`None`: the cluster's default).
    pub partition: Option<&'a str>,
    /// The job's name in the queue.
    pub name: &'a str,
}

fn quote(p: &Path) -> String {
    let s = p.to_string_lossy();
    shlex::try_quote(&s)
        .map(|q| q.into_owned())
        .unwrap_or_else(|_| format!("'{}'", s.replace('\0', "")))
}

/// The script's text.
///
/// ```
/// use drapekit::batch::{plan::Resources, slurm::{script, SlurmOptions}};
/// use std::path::Path;
/// let r = Resources { cpus: 2, mem_mb: 1000, minutes: 10, throttle: 4 };
/// let s = script(&SlurmOptions {
///     exe: Path::new("/opt/drapekit"), plan: Path::new("/p/plan.toml"), out: Path::new("/o"),
///     positions: 20, resources: r, partition: None, name: "grading",
/// });
/// assert!(s.contains("#SBATCH --array=0-19%4\n"));
/// assert!(s.contains("#SBATCH --cpus-per-task=2\n#SBATCH --mem=1000M\n#SBATCH --time=10\n"));
/// assert!(s.contains("#SBATCH --output=/o/logs/%A_%a.out\n"));
/// assert!(s.ends_with("exec /opt/drapekit batch run /p/plan.toml -o /o\n"));
/// ```
pub fn script(o: &SlurmOptions) -> String {
    let r = &o.resources;
    let throttle = if r.throttle > 0 {
        format!("%{}", r.throttle)
    } else {
        String::new()
    };
    let logs = o.out.join("logs");
    let mut s = String::from("#!/bin/bash\n");
    s += &format!("#SBATCH --job-name={}\n", o.name);
    s += &format!(
        "#SBATCH --array=0-{}{throttle}\n",
        o.positions.saturating_sub(1)
    );
    s += "#SBATCH --ntasks=1\n";
    s += &format!("#SBATCH --cpus-per-task={}\n", r.cpus);
    s += &format!("#SBATCH --mem={}M\n", r.mem_mb);
    s += &format!("#SBATCH --time={}\n", r.minutes);
    s += &format!("#SBATCH --output={}\n", logs.join("%A_%a.out").display());
    s += &format!("#SBATCH --error={}\n", logs.join("%A_%a.err").display());
    if let Some(p) = o.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    s += "# Each task runs the job at position $SLURM_ARRAY_TASK_ID (drapekit reads it).\n";
    s += "set -eu\n";
    s += &format!(
        "exec {} batch run {} -o {}\n",
        quote(o.exe),
        quote(o.plan),
        quote(o.out)
    );
    s
}
