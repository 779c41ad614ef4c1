//! `drapekit batch` on a real Slurm: tools/slurm_local.sh installs Slurm and munge (Debian
//! packages) and starts a single-node cluster on this machine; the example plan is submitted as
//! an array, waited for, collected, and its table compared with a local run of the same plan
//! (the runs are deterministic: every number must be equal). The daemons are stopped when the
//! test ends, however it ends. Skipped (with a message) when the cluster cannot be started,
//! except under CI=true, where that fails.

mod common;

use common::{drapekit, fixture, text};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/slurm_local.sh")
}

/// The running cluster; stopping it on drop (also when the test panics).
struct Cluster {
    dir: tempfile::TempDir,
}

impl Cluster {
    fn conf(&self) -> PathBuf {
        self.dir.path().join("slurm.conf")
    }

    fn cmd(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", self.conf());
        c
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new(script())
            .arg("stop")
            .arg(self.dir.path())
            .status();
    }
}

fn skip_or_fail(why: &str) -> Option<Cluster> {
    if std::env::var("CI").as_deref() == Ok("true") {
        panic!("the local Slurm cluster could not be started, and CI=true requires it: {why}");
    }
    eprintln!("skipping: the local Slurm cluster could not be started: {why}");
    None
}

fn start() -> Option<Cluster> {
    let dir = tempfile::Builder::new()
        .prefix("drapekit-slurm")
        .tempdir()
        .unwrap();
    let cluster = Cluster { dir };
    let o = Command::new(script())
        .arg("start")
        .arg(cluster.dir.path())
        .output();
    match o {
        Ok(o) if o.status.success() => Some(cluster),
        Ok(o) => skip_or_fail(&String::from_utf8_lossy(&o.stderr)),
        Err(e) => skip_or_fail(&e.to_string()),
    }
}

fn table(out: &Path) -> Vec<Value> {
    let o = drapekit()
        .args(["batch", "collect", "--json"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o).1);
    serde_json::from_slice::<Value>(&o.stdout)
        .unwrap()
        .as_array()
        .unwrap()
        .clone()
}

#[test]
fn example_plan_as_a_slurm_array_matches_a_local_run() {
    let Some(cluster) = start() else { return };
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("slurm");
    let plan = fixture("batch_example.toml");
    let o = drapekit()
        .args(["batch", "slurm"])
        .arg(&plan)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o).1);
    // Submit, and wait until the array has left the queue (at most 5 minutes).
    let o = cluster
        .cmd("sbatch")
        .arg("--parsable")
        .arg(out.join("batch.sbatch"))
        .output()
        .unwrap();
    assert!(o.status.success(), "sbatch: {}", text(&o).1);
    let id = String::from_utf8_lossy(&o.stdout).trim().to_string();
    let deadline = Instant::now() + Duration::from_secs(300);
    loop {
        let q = cluster
            .cmd("squeue")
            .args(["-h", "-j", &id])
            .output()
            .unwrap();
        assert!(q.status.success(), "squeue: {}", text(&q).1);
        if q.stdout.iter().all(u8::is_ascii_whitespace) {
            break;
        }
        if Instant::now() > deadline {
            let _ = cluster.cmd("scancel").arg(&id).status();
            panic!("array job {id} did not finish within 5 minutes");
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    let slurm = table(&out);
    assert_eq!(slurm.len(), 8);
    // Every task logged through Slurm into OUT/logs.
    let logs = common::listing(&out.join("logs"));
    assert_eq!(
        logs.iter().filter(|l| l.ends_with(".out")).count(),
        8,
        "{logs:?}"
    );
    // Each array task ran exactly the job at its own position, once.
    for r in &slurm {
        let log = out.join("logs").join(format!("{id}_{}.out", r["position"]));
        let log = std::fs::read_to_string(&log).unwrap();
        let line = format!("{} {}", r["position"], r["id"].as_str().unwrap());
        let said = |l: &str| l.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(
            log.lines().any(|l| said(l).starts_with(&line)),
            "{line} not in {log}"
        );
        assert!(
            log.contains(": 1 jobs, 0 skipped (done), 1 done, 0 failed"),
            "{log}"
        );
    }
    // The same plan on this machine.
    let local = work.path().join("local");
    let o = drapekit()
        .args(["--jobs", "2", "batch", "run"])
        .arg(&plan)
        .arg("-o")
        .arg(&local)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o).1);
    let local = table(&local);
    assert_eq!(local.len(), 8);
    for (s, l) in slurm.iter().zip(&local) {
        assert_eq!(s["state"], "done", "{s}");
        for k in [
            "position",
            "id",
            "garment",
            "fabric",
            "size",
            "verdict",
            "max_strain",
            "mean_strain",
            "particles_inside",
            "mesh",
        ] {
            assert_eq!(s[k], l[k], "{k} of {}", s["id"]);
        }
    }
    // Stopped, no daemon is left.
    let pids: Vec<String> = ["munged", "slurmctld", "slurmd"]
        .iter()
        .map(|d| {
            std::fs::read_to_string(cluster.dir.path().join(format!("{d}.pid")))
                .unwrap()
                .trim()
                .to_string()
        })
        .collect();
    drop(cluster);
    for p in pids {
        assert!(
            !Path::new("/proc").join(&p).exists(),
            "daemon {p} still runs"
        );
    }
}
