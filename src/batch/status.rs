//! A job's status: `OUT/jobs/<id>/status.json`, written atomically (temporary file + rename) when
//! the job starts (`running`) and when it ends (`done` or `failed`). A batch killed mid-job
//! leaves `running`, which a rerun treats as unfinished.

use super::plan::Axes;
use super::BatchError;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Where a job is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum State {
    /// Started and not finished (or killed).
    Running,
    /// Finished: its outputs and report are in place.
    Done,
    /// Failed: `error` says why.
    Failed,
}

impl std::fmt::Display for State {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            State::Running => "running",
            State::Done => "done",
            State::Failed => "failed",
        })
    }
}

/// The status file of a job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Status {
    /// The job's id.
    pub id: String,
    /// Its position (`--index`).
    pub position: usize,
    /// Its axis values.
    pub axes: Axes,
    /// `scene` (a drape) or `pattern` (a garment).
    pub kind: String,
    /// The hash of the job's definition when it ran (`Plan::spec_hash`).
    pub spec: String,
    /// Where it is.
    pub state: State,
    /// Why it failed.
    pub error: Option<String>,
    /// Runs so far, this one included.
    pub attempts: u32,
    /// Threads the job was given.
    pub threads: usize,
    /// The machine it ran on.
    pub host: Option<String>,
    /// Start, seconds since 1970.
    pub started: f64,
    /// End, seconds since 1970.
    pub finished: Option<f64>,
    /// Wall time of the job's command, s.
    pub seconds: Option<f64>,
    /// The job's report (JSON of `drape` or `garment`), relative to the output folder.
    pub report: Option<String>,
    /// The job's main mesh, relative to the output folder.
    pub mesh: Option<String>,
}

/// The job's folder.
pub fn job_dir(out: &Path, id: &str) -> PathBuf {
    out.join("jobs").join(id)
}

/// The job's status file.
pub fn path(out: &Path, id: &str) -> PathBuf {
    job_dir(out, id).join("status.json")
}

/// Reads a job's status (`None`: the job never started).
pub fn read(out: &Path, id: &str) -> Result<Option<Status>, BatchError> {
    read_file(&path(out, id))
}

/// Reads a status file (`None`: missing).
pub fn read_file(p: &Path) -> Result<Option<Status>, BatchError> {
    let text = match std::fs::read_to_string(p) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => {
            return Err(BatchError::Read {
                path: p.to_path_buf(),
                source,
            })
        }
    };
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| BatchError::Json {
            path: p.to_path_buf(),
            message: e.to_string(),
        })
}

/// Writes a job's status atomically.
pub fn write(out: &Path, s: &Status) -> Result<(), BatchError> {
    let dir = job_dir(out, &s.id);
    std::fs::create_dir_all(&dir).map_err(|source| BatchError::Write {
        path: dir.clone(),
        source,
    })?;
    crate::io::write_atomic(&path(out, &s.id), &[], |w| {
        serde_json::to_writer_pretty(&mut *w, s)?;
        std::io::Write::write_all(w, b"\n")
    })?;
    Ok(())
}

/// Seconds since 1970 now.
pub fn now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// This machine's name (Linux), for the status.
pub fn host() -> Option<String> {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
}
