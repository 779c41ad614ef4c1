//! The local pool, and one job by its position.
//!
//! `workers` jobs run at once (std threads taking the next job from a shared counter; each
//! blocks on its child process), each job given `threads = max(1, cores / workers)` threads, so
//! the machine's cores are all used and never oversubscribed. Jobs that are done (status `done`,
//! the same definition hash, the report present) are skipped; failed, unfinished (`running` left
//! by a killed batch) and changed jobs run again. Bodies that need fitting are fitted before the
//! pool starts, once each.

use super::job::{self, JobContext};
use super::plan::{Job, Plan};
use super::status::{self, State, Status};
use super::{order, BatchError};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// How to run a batch.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The output folder.
    pub out: PathBuf,
    /// The drapekit binary the jobs run (the CLI passes its own).
    pub exe: PathBuf,
    /// Jobs at once (at least 1).
    pub workers: usize,
    /// Cores to share among the workers.
    pub cores: usize,
    /// Run only the job at this position.
    pub index: Option<usize>,
}

/// Threads per job: `max(1, cores / workers)`.
///
/// ```
/// assert_eq!(drapekit::batch::run::threads_per_job(8, 3), 2);
/// assert_eq!(drapekit::batch::run::threads_per_job(2, 4), 1);
/// ```
pub fn threads_per_job(cores: usize, workers: usize) -> usize {
    (cores / workers.max(1)).max(1)
}

/// What a run did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunSummary {
    /// Jobs selected (all, or the one of `--index`).
    pub selected: usize,
    /// Of which already done and skipped.
    pub skipped: usize,
    /// Of which run now and done.
    pub done: usize,
    /// Of which run now and failed.
    pub failed: usize,
    /// Jobs at once, and threads each.
    pub workers: usize,
    /// Threads per job.
    pub threads: usize,
    /// The statuses of the jobs run now, in position order.
    pub ran: Vec<Status>,
    /// Wall time, s.
    pub wall_seconds: f64,
}

/// Whether a job is done and unchanged (its status says done, for the same definition, and its
/// report is there).
pub fn is_done(plan: &Plan, job: &Job, out: &std::path::Path) -> bool {
    match status::read(out, &job.id) {
        Ok(Some(s)) => {
            s.state == State::Done
                && s.spec == plan.spec_hash(job)
                && s.report.as_ref().is_some_and(|r| out.join(r).is_file())
        }
        _ => false,
    }
}

/// The jobs selected by `index` (all when `None`), with their positions.
fn select<'a>(
    plan: &'a Plan,
    ids: &[String],
    index: Option<usize>,
) -> Result<Vec<(usize, &'a Job)>, BatchError> {
    let positions = super::order::positions(ids);
    let position = |j: &Job| {
        *positions
            .get(j.id.as_str())
            .expect("every plan id is in the order")
    };
    match index {
        None => {
            let mut v: Vec<_> = plan.jobs.iter().map(|j| (position(j), j)).collect();
            v.sort_by_key(|(p, _)| *p);
            Ok(v)
        }
        Some(n) => {
            let id = ids.get(n).ok_or(BatchError::Index {
                index: n,
                count: ids.len(),
            })?;
            match plan.jobs.iter().find(|j| j.id == *id) {
                Some(j) => Ok(vec![(n, j)]),
                None => Ok(Vec::new()),
            }
        }
    }
}

/// Runs the plan's jobs (or one) into `opts.out`.
pub fn run(plan: &Plan, opts: &RunOptions) -> Result<RunSummary, BatchError> {
    let start = std::time::Instant::now();
    let ids = order::update(&opts.out, plan)?;
    let selected = select(plan, &ids, opts.index)?;
    let pending: Vec<(usize, &Job)> = selected
        .iter()
        .filter(|(_, j)| !is_done(plan, j, &opts.out))
        .copied()
        .collect();
    prefit(plan, &pending, opts);
    let workers = opts.workers.max(1).min(pending.len().max(1));
    let threads = threads_per_job(opts.cores, workers);
    let ctx = JobContext {
        out: opts.out.clone(),
        exe: opts.exe.clone(),
        threads,
    };
    let results = pool(plan, &pending, &ctx, workers)?;
    let failed = results.iter().filter(|s| s.state != State::Done).count();
    Ok(RunSummary {
        selected: selected.len(),
        skipped: selected.len() - pending.len(),
        done: results.len() - failed,
        failed,
        workers,
        threads,
        ran: results,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

/// Fits each measurements body the pending jobs use, once, before the pool (a failure is left
/// for the jobs, which retry it and record the error).
fn prefit(plan: &Plan, pending: &[(usize, &Job)], opts: &RunOptions) {
    let mut bodies: Vec<usize> = pending.iter().filter_map(|(_, j)| j.body).collect();
    bodies.sort_unstable();
    bodies.dedup();
    for b in bodies {
        let _ = super::body::mesh(&plan.bodies[b], &opts.out, &opts.exe);
    }
}

/// Runs `jobs` on `workers` threads; their statuses in the order of `jobs`.
fn pool(
    plan: &Plan,
    jobs: &[(usize, &Job)],
    ctx: &JobContext,
    workers: usize,
) -> Result<Vec<Status>, BatchError> {
    let next = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<Result<Status, BatchError>>>> =
        Mutex::new((0..jobs.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some((pos, j)) = jobs.get(k) else { break };
                let r = job::run(plan, j, *pos, ctx);
                slots.lock().expect("no worker panics holding the lock")[k] = Some(r);
            });
        }
    });
    slots
        .into_inner()
        .expect("the workers have ended")
        .into_iter()
        .map(|r| r.expect("every job ran"))
        .collect()
}
