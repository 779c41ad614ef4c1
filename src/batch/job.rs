//! One job, run as a child process of the drapekit binary.
//!
//! A scene job runs `drapekit --jobs T drape OUT/jobs/<id>/scene.toml -o OUT/jobs/<id>/out
//! --report OUT/jobs/<id>/report.json`; a pattern job runs `drapekit --jobs T garment PATTERN
//! --body BODY -o OUT/jobs/<id>/out --report ... --fabric F --spacing S --sew-max --settle-max`.
//! A child process, not a call in this process: a job that panics, aborts or runs out of memory
//! takes only itself down; `--jobs T` gives each job its own thread pool (rayon's is one per
//! process); and each job's outputs and report are exactly those of the command a user would
//! run. Both commands stage their outputs and rename them at the end, so a killed job leaves no
//! half-written mesh. Its stdout and stderr go to `OUT/jobs/<id>/log.txt`.

use super::derive::{self, SceneChanges};
use super::plan::{GarmentKind, Job, Plan};
use super::status::{self, State, Status};
use super::{body, BatchError};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How jobs are run.
#[derive(Debug, Clone)]
pub struct JobContext {
    /// The output folder.
    pub out: PathBuf,
    /// The drapekit binary the jobs run.
    pub exe: PathBuf,
    /// Threads per job (`--jobs` of the child).
    pub threads: usize,
}

/// What a finished job left.
struct Finished {
    seconds: f64,
    report: String,
    mesh: Option<String>,
}

/// Runs one job to its end and returns its final status (also written to its status file).
/// The job's own failure is in the status; an `Err` means its status could not be written.
pub fn run(
    plan: &Plan,
    job: &Job,
    position: usize,
    ctx: &JobContext,
) -> Result<Status, BatchError> {
    let previous = status::read(&ctx.out, &job.id).ok().flatten();
    let kind = match plan.garments[job.garment].kind {
        GarmentKind::Scene { .. } => "scene",
        GarmentKind::Pattern { .. } => "pattern",
    };
    let mut s = Status {
        id: job.id.clone(),
        position,
        axes: plan.axes(job),
        kind: kind.into(),
        spec: plan.spec_hash(job),
        state: State::Running,
        error: None,
        attempts: previous.map_or(0, |p| p.attempts) + 1,
        threads: ctx.threads,
        host: status::host(),
        started: status::now(),
        finished: None,
        seconds: None,
        report: None,
        mesh: None,
    };
    status::write(&ctx.out, &s)?;
    match execute(plan, job, ctx) {
        Ok(f) => {
            s.state = State::Done;
            s.seconds = Some(f.seconds);
            s.report = Some(f.report);
            s.mesh = f.mesh;
        }
        Err(e) => {
            s.state = State::Failed;
            s.error = Some(e.to_string());
        }
    }
    s.finished = Some(status::now());
    status::write(&ctx.out, &s)?;
    Ok(s)
}

fn rel(out: &Path, p: &Path) -> String {
    p.strip_prefix(out).unwrap_or(p).display().to_string()
}

/// Builds the job's command, runs it, and checks its report.
fn execute(plan: &Plan, job: &Job, ctx: &JobContext) -> Result<Finished, BatchError> {
    let dir = status::job_dir(&ctx.out, &job.id);
    let report = dir.join("report.json");
    let outputs = dir.join("out");
    let _ = std::fs::remove_file(&report);
    let mut cmd = Command::new(&ctx.exe);
    cmd.arg("--jobs").arg(ctx.threads.to_string());
    match &plan.garments[job.garment].kind {
        GarmentKind::Scene { file, body_object } => {
            let changes = scene_changes(plan, job, ctx, file, body_object.as_deref())?;
            let text = derive::scene(plan, file, &changes)?;
            let scene = dir.join("scene.toml");
            crate::io::write_atomic(&scene, &[file], |w| {
                std::io::Write::write_all(w, text.as_bytes())
            })?;
            cmd.arg("drape").arg(&scene);
        }
        GarmentKind::Pattern { file, spacing } => {
            pattern_args(&mut cmd, plan, job, ctx, file, *spacing)?;
        }
    }
    cmd.arg("-o").arg(&outputs).arg("--report").arg(&report);
    let seconds = spawn_and_wait(cmd, &dir.join("log.txt"), plan.resources.minutes)?;
    let mesh = main_mesh(&report)?;
    Ok(Finished {
        seconds,
        report: rel(&ctx.out, &report),
        mesh: mesh.map(|m| rel(&ctx.out, Path::new(&m))),
    })
}

/// What a scene job changes in the scene `file`: the body (fitted or cached first), the
/// size's scale, the object they apply to, the fabric.
fn scene_changes<'a>(
    plan: &'a Plan,
    job: &Job,
    ctx: &JobContext,
    file: &Path,
    body_object: Option<&str>,
) -> Result<SceneChanges<'a>, BatchError> {
    Ok(SceneChanges {
        body: job
            .body
            .map(|b| body::mesh(&plan.bodies[b], &ctx.out, &ctx.exe))
            .transpose()?,
        scale: job.size.map(|s| plan.sizes[s].scale),
        object: if job.body.is_some() || job.size.is_some() {
            super::plan::scene_object(file, body_object).map_err(|message| BatchError::Child {
                what: "the scene".into(),
                message,
            })?
        } else {
            0
        },
        fabric: job.fabric.map(|f| {
            let c = &plan.fabrics[f];
            (c.name.as_str(), c.table.as_ref())
        }),
    })
}

/// A pattern job's `garment` arguments: the pattern, the body (scaled to the size), the
/// spacing, the plan's garment solver and the fabric.
fn pattern_args(
    cmd: &mut Command,
    plan: &Plan,
    job: &Job,
    ctx: &JobContext,
    file: &Path,
    spacing: f64,
) -> Result<(), BatchError> {
    let b = &plan.bodies[job
        .body
        .expect("a pattern job has a body (checked by the plan)")];
    let size = job
        .size
        .map(|s| (plan.sizes[s].name.as_str(), plan.sizes[s].scale));
    let body_file = body::for_pattern(b, size, &ctx.out, &ctx.exe)?;
    let g = &plan.garment_solver;
    cmd.arg("garment").arg(file).arg("--body").arg(body_file);
    cmd.args(["--spacing", &spacing.to_string()]);
    cmd.args([
        "--sew-max",
        &g.sew_max.to_string(),
        "--settle-max",
        &g.settle_max.to_string(),
    ]);
    if let Some(f) = job.fabric {
        cmd.args(["--fabric", &plan.fabrics[f].name]);
    }
    if let Some(i) = &g.integrator {
        cmd.args(["--integrator", i]);
    }
    Ok(())
}

/// Runs `cmd` with its output into `log`, killing it after `minutes`; its wall time on success.
fn spawn_and_wait(mut cmd: Command, log: &Path, minutes: u64) -> Result<f64, BatchError> {
    let what = "the job's command".to_string();
    let file = std::fs::File::create(log).map_err(|source| BatchError::Write {
        path: log.to_path_buf(),
        source,
    })?;
    let err = file.try_clone().map_err(|source| BatchError::Write {
        path: log.to_path_buf(),
        source,
    })?;
    let start = Instant::now();
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(file)
        .stderr(err)
        .spawn()
        .map_err(|e| BatchError::Child {
            what: what.clone(),
            message: format!("cannot start: {e}"),
        })?;
    let limit = Duration::from_secs(minutes.saturating_mul(60));
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(BatchError::Timeout { minutes });
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(5)),
            Err(e) => {
                return Err(BatchError::Child {
                    what,
                    message: e.to_string(),
                })
            }
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    if status.success() {
        return Ok(seconds);
    }
    Err(BatchError::Child {
        what,
        message: format!("{status}: {}", error_lines(log)),
    })
}

/// The `error:` line and its causes from a failed command's log (else its last lines).
fn error_lines(log: &Path) -> String {
    let text = std::fs::read_to_string(log).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    let picked: Vec<&str> = match lines.iter().position(|l| l.starts_with("error: ")) {
        Some(i) => lines[i..]
            .iter()
            .take_while(|l| l.starts_with("error: ") || l.starts_with("  "))
            .copied()
            .collect(),
        None => lines[lines.len().saturating_sub(5)..].to_vec(),
    };
    picked.join("\n")
}

/// The main mesh of a job's report: a drape's first piece, a garment's first file.
fn main_mesh(report: &Path) -> Result<Option<String>, BatchError> {
    let text = std::fs::read_to_string(report).map_err(|source| BatchError::Read {
        path: report.to_path_buf(),
        source,
    })?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| BatchError::Json {
        path: report.to_path_buf(),
        message: e.to_string(),
    })?;
    let first = v
        .pointer("/pieces/0/files/0")
        .or_else(|| v.pointer("/files/0"))
        .and_then(|f| f.as_str())
        .map(str::to_string);
    Ok(first)
}
