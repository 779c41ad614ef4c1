//! Positions: which job `--index N` (or a scheduler's array index) means.
//!
//! A position is an index into the list of every id the output folder has seen, kept in
//! `OUT/order.json`: ids already listed keep their positions, ids new to the plan are appended in
//! the plan's order, and ids dropped from the plan keep their (now empty) positions. So a plan
//! extended in any way (a value appended to any axis, a job appended to the list) keeps the
//! position of every job it had, in that folder. Without an output folder the positions are the
//! plan's own order.

use super::plan::Plan;
use super::BatchError;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// The order file of an output folder.
pub fn path(out: &Path) -> PathBuf {
    out.join("order.json")
}

#[derive(serde::Serialize, serde::Deserialize)]
struct OrderFile {
    ids: Vec<String>,
}

/// The ids `out` has given positions to (empty when it has none yet).
pub fn load(out: &Path) -> Result<Vec<String>, BatchError> {
    let p = path(out);
    let text = match std::fs::read_to_string(&p) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(source) => return Err(BatchError::Read { path: p, source }),
    };
    let f: OrderFile = serde_json::from_str(&text).map_err(|e| BatchError::Json {
        path: p,
        message: e.to_string(),
    })?;
    Ok(f.ids)
}

/// `known` with the plan's new ids appended, in the plan's order.
pub fn merge(mut known: Vec<String>, plan: &Plan) -> Vec<String> {
    let seen: HashSet<String> = known.iter().cloned().collect();
    for j in &plan.jobs {
        if !seen.contains(&j.id) {
            known.push(j.id.clone());
        }
    }
    known
}

/// Each id's position in `ids` (an order as [`load`] or [`merge`] give it).
pub fn positions(ids: &[String]) -> HashMap<&str, usize> {
    ids.iter()
        .enumerate()
        .map(|(k, i)| (i.as_str(), k))
        .collect()
}

/// Loads `out`'s order, merges the plan into it and saves it (atomically) when it grew.
pub fn update(out: &Path, plan: &Plan) -> Result<Vec<String>, BatchError> {
    let known = load(out)?;
    let n = known.len();
    let ids = merge(known, plan);
    if ids.len() != n {
        std::fs::create_dir_all(out).map_err(|source| BatchError::Write {
            path: out.to_path_buf(),
            source,
        })?;
        let f = OrderFile { ids: ids.clone() };
        crate::io::write_atomic(&path(out), &[&plan.path], |w| {
            serde_json::to_writer_pretty(&mut *w, &f)?;
            std::io::Write::write_all(w, b"\n")
        })?;
    }
    Ok(ids)
}

/// The schedulers' array-index variables, in the order they are read.
pub const INDEX_VARS: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];

/// The job index a scheduler gives through the environment (`var` looks a variable up): Slurm's
/// `SLURM_ARRAY_TASK_ID`, else Kubernetes' `JOB_COMPLETION_INDEX`; `None` when neither is set.
/// Both set and different is an error.
pub fn env_index(var: impl Fn(&str) -> Option<String>) -> Result<Option<usize>, BatchError> {
    let mut found = Vec::new();
    for name in INDEX_VARS {
        if let Some(v) = var(name).filter(|v| !v.trim().is_empty()) {
            let i = v
                .trim()
                .parse::<usize>()
                .map_err(|_| BatchError::IndexVar {
                    var: name.to_string(),
                    value: v.clone(),
                })?;
            found.push(i);
        }
    }
    match found[..] {
        [] => Ok(None),
        [i] => Ok(Some(i)),
        [s, k, ..] if s == k => Ok(Some(s)),
        [s, k, ..] => Err(BatchError::IndexConflict { slurm: s, k8s: k }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn index_from_either_scheduler() {
        assert_eq!(env_index(env(&[])).unwrap(), None);
        assert_eq!(
            env_index(env(&[("SLURM_ARRAY_TASK_ID", "3")])).unwrap(),
            Some(3)
        );
        assert_eq!(
            env_index(env(&[("JOB_COMPLETION_INDEX", "7")])).unwrap(),
            Some(7)
        );
        assert_eq!(
            env_index(env(&[
                ("SLURM_ARRAY_TASK_ID", "2"),
                ("JOB_COMPLETION_INDEX", "2")
            ]))
            .unwrap(),
            Some(2)
        );
        assert!(matches!(
            env_index(env(&[
                ("SLURM_ARRAY_TASK_ID", "2"),
                ("JOB_COMPLETION_INDEX", "4")
            ])),
            Err(BatchError::IndexConflict { slurm: 2, k8s: 4 })
        ));
        assert!(matches!(
            env_index(env(&[("SLURM_ARRAY_TASK_ID", "x")])),
            Err(BatchError::IndexVar { .. })
        ));
    }
}
