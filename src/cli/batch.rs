//! `drapekit batch plan|run|collect|slurm`: many drapes from one plan file.

use crate::batch::{collect, order, plan, run, slurm, status};
use anyhow::Context;
use clap::{Args, Subcommand};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The subcommands of `drapekit batch`.
#[derive(Debug, Subcommand)]
pub enum BatchCommand {
    /// List the plan's jobs: position, id, kind, axes (and state, with -o).
    Plan(PlanArgs),
    /// Run the jobs on this machine (--jobs at once), or the one at --index (or at the
    /// scheduler's index: SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX).
    Run(RunArgs),
    /// Gather every status and report into OUT/results.csv and OUT/results.json.
    Collect(CollectArgs),
    /// Write OUT/batch.sbatch: a Slurm array script of the plan (submit it with sbatch).
    Slurm(SlurmArgs),
}

/// Arguments of `batch plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// The plan file (TOML; see the README).
    pub plan: PathBuf,
    /// An output folder: its positions (order.json) and the jobs' states.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `batch run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The plan file.
    pub plan: PathBuf,
    /// The output folder (created if needed).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Run only the job at this position (default: the scheduler's index variable, else all).
    #[arg(long, value_name = "N")]
    pub index: Option<usize>,
    /// Print the JSON summary.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `batch collect`.
#[derive(Debug, Args)]
pub struct CollectArgs {
    /// The output folder of a batch.
    pub output: PathBuf,
    /// Print the table as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `batch slurm`.
#[derive(Debug, Args)]
pub struct SlurmArgs {
    /// The plan file.
    pub plan: PathBuf,
    /// The output folder.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// The Slurm partition (default: the cluster's default).
    #[arg(long)]
    pub partition: Option<String>,
    /// Most array tasks at once (default: the plan's resources.throttle; 0: no limit).
    #[arg(long)]
    pub throttle: Option<u32>,
}

/// Runs `drapekit batch`; `jobs` is the global `--jobs` (jobs at once).
pub fn run(cmd: BatchCommand, jobs: Option<u16>) -> anyhow::Result<()> {
    match cmd {
        BatchCommand::Plan(a) => list(a),
        BatchCommand::Run(a) => run_jobs(a, jobs),
        BatchCommand::Collect(a) => gather(a),
        BatchCommand::Slurm(a) => sbatch(a),
    }
}

#[derive(Serialize)]
struct Listed {
    position: usize,
    id: String,
    kind: &'static str,
    axes: plan::Axes,
    state: Option<String>,
}

fn list(a: PlanArgs) -> anyhow::Result<()> {
    let p = plan::read(&a.plan)?;
    let ids = match &a.output {
        Some(o) => order::merge(order::load(o)?, &p),
        None => p.jobs.iter().map(|j| j.id.clone()).collect(),
    };
    let positions = order::positions(&ids);
    let mut rows = Vec::new();
    for j in &p.jobs {
        let state = match &a.output {
            Some(o) => Some(match status::read(o, &j.id)? {
                None => "new".to_string(),
                Some(_) if run::is_done(&p, j, o) => "done".to_string(),
                Some(s) if s.state == status::State::Done => "changed".to_string(),
                Some(s) => s.state.to_string(),
            }),
            None => None,
        };
        rows.push(Listed {
            position: positions[j.id.as_str()],
            id: j.id.clone(),
            kind: match p.garments[j.garment].kind {
                plan::GarmentKind::Scene { .. } => "scene",
                plan::GarmentKind::Pattern { .. } => "pattern",
            },
            axes: p.axes(j),
            state,
        });
    }
    rows.sort_by_key(|r| r.position);
    if a.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    for r in &rows {
        let state = r
            .state
            .as_deref()
            .map(|s| format!("  {s}"))
            .unwrap_or_default();
        println!("{:>5}  {:<40} {}{state}", r.position, r.id, r.kind);
    }
    println!("{} jobs", rows.len());
    Ok(())
}

/// Cores this process may use: Slurm's `SLURM_CPUS_PER_TASK` when set, else the machine's.
fn cores() -> usize {
    std::env::var("SLURM_CPUS_PER_TASK")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

fn output_dir(out: &Path) -> anyhow::Result<PathBuf> {
    if out.is_file() {
        anyhow::bail!("{} is a file: the output must be a folder", out.display());
    }
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    Ok(out.canonicalize()?)
}

fn run_jobs(a: RunArgs, jobs: Option<u16>) -> anyhow::Result<()> {
    let p = plan::read(&a.plan)?;
    let index = match a.index {
        Some(i) => Some(i),
        None => order::env_index(|k| std::env::var(k).ok())?,
    };
    let cores = cores();
    let opts = run::RunOptions {
        out: output_dir(&a.output)?,
        exe: std::env::current_exe().context("cannot find the drapekit binary")?,
        workers: if index.is_some() {
            1
        } else {
            jobs.map_or(cores, usize::from)
        },
        cores,
        index,
    };
    let s = run::run(&p, &opts)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
    } else {
        summary(&s, &opts.out);
    }
    if s.failed > 0 {
        anyhow::bail!(
            "{} of {} jobs failed (their errors are in their status.json)",
            s.failed,
            s.selected
        );
    }
    Ok(())
}

fn summary(s: &run::RunSummary, out: &Path) {
    for st in &s.ran {
        match &st.error {
            None => println!(
                "  {:>4} {:<40} done in {:.2} s",
                st.position,
                st.id,
                st.seconds.unwrap_or(0.0)
            ),
            Some(e) => println!(
                "  {:>4} {:<40} FAILED: {}",
                st.position,
                st.id,
                e.lines().next().unwrap_or("")
            ),
        }
    }
    println!(
        "{}: {} jobs, {} skipped (done), {} done, {} failed; {} at once x {} threads; {:.2} s",
        out.display(),
        s.selected,
        s.skipped,
        s.done,
        s.failed,
        s.workers,
        s.threads,
        s.wall_seconds
    );
}

fn gather(a: CollectArgs) -> anyhow::Result<()> {
    let rows = collect::collect(&a.output)?;
    collect::write(&a.output, &rows)?;
    let picture = crate::batch::sheet::write(&a.output, &rows)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    let count = |s: status::State| rows.iter().filter(|r| r.state == s).count();
    let pass = rows
        .iter()
        .filter(|r| r.verdict.as_deref() == Some("pass"))
        .count();
    let [csv, json, sheet] = collect::paths(&a.output);
    println!(
        "{} jobs: {} done ({} pass), {} failed, {} unfinished\n  {}\n  {}\n  {} (each done job's mesh)",
        rows.len(),
        count(status::State::Done),
        pass,
        count(status::State::Failed),
        count(status::State::Running),
        csv.display(),
        json.display(),
        sheet.display()
    );
    if let Some(p) = picture {
        println!(
            "  {} (the contact sheet: cells in the table's order, numbered by position)",
            p.display()
        );
    }
    Ok(())
}

fn sbatch(a: SlurmArgs) -> anyhow::Result<()> {
    let p = plan::read(&a.plan)?;
    let out = output_dir(&a.output)?;
    let ids = order::update(&out, &p)?;
    let logs = out.join("logs");
    std::fs::create_dir_all(&logs).with_context(|| format!("cannot create {}", logs.display()))?;
    let mut resources = p.resources;
    if let Some(t) = a.throttle {
        resources.throttle = t;
    }
    let exe = std::env::current_exe().context("cannot find the drapekit binary")?;
    let plan_abs = a.plan.canonicalize()?;
    let name = format!(
        "drapekit-{}",
        plan_abs
            .file_stem()
            .map(|s| s.to_string_lossy())
            .unwrap_or_default()
    )
    .replace(
        |c: char| !(c.is_ascii_alphanumeric() || c == '-' || c == '_'),
        "_",
    );
    let text = slurm::script(&slurm::SlurmOptions {
        exe: &exe,
        plan: &plan_abs,
        out: &out,
        positions: ids.len(),
        resources,
        partition: a.partition.as_deref(),
        name: &name,
    });
    let path = out.join("batch.sbatch");
    crate::io::write_atomic(&path, &[&plan_abs], |w| {
        std::io::Write::write_all(w, text.as_bytes())
    })?;
    println!(
        "{} ({} array tasks); submit it with: sbatch {}",
        path.display(),
        ids.len(),
        path.display()
    );
    Ok(())
}
