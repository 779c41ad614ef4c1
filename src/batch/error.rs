//! The errors of `batch`.

use std::path::PathBuf;

/// Everything that can go wrong in a batch (a job's own failure is not one: it is recorded in
/// the job's status and the others go on).
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// A file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A file or folder could not be written or created.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// An output through `io` (atomic writes, staged meshes).
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// TOML syntax, types or unknown keys of the plan.
    #[error("{}: {message}", path.display())]
    Toml { path: PathBuf, message: String },
    /// Values of the plan that cannot be: (key, message) each, every one found.
    #[error("{}: {}", path.display(), problems.iter().map(|(k, m)| format!("key '{k}': {m}")).collect::<Vec<_>>().join("; "))]
    Plan {
        path: PathBuf,
        problems: Vec<(String, String)>,
    },
    /// A JSON file of the output folder (order, status, report) that does not parse.
    #[error("{}: {message}", path.display())]
    Json { path: PathBuf, message: String },
    /// `--index` (or the scheduler's variable) beyond the jobs.
    #[error("job index {index} is out of range: the plan has positions 0 to {}", count.saturating_sub(1))]
    Index { index: usize, count: usize },
    /// A scheduler's index variable that is not a number.
    #[error("the environment variable {var}={value:?} is not a job index (a whole number)")]
    IndexVar { var: String, value: String },
    /// Two schedulers' index variables that disagree.
    #[error("SLURM_ARRAY_TASK_ID={slurm} and JOB_COMPLETION_INDEX={k8s} disagree: give --index")]
    IndexConflict { slurm: usize, k8s: usize },
    /// A child drapekit (a job's command, or the fit of a body) that failed or could not start.
    #[error("{what} failed: {message}")]
    Child { what: String, message: String },
    /// A job that ran past the plan's `resources.minutes`.
    #[error("killed after {minutes} min (the plan's resources.minutes)")]
    Timeout { minutes: u64 },
    /// The output folder holds no batch.
    #[error("{} holds no batch (no jobs/*/status.json)", path.display())]
    Empty { path: PathBuf },
}
