//! `drapekit batch`: plans (parsing, errors, ids, product), local runs of the example plan,
//! resume, a bad job failing alone, the index from the command line and the schedulers'
//! variables, and the collected table.

mod common;

use common::{drapekit, fixture, text};
use drapekit::batch::{order, plan};
use drapekit::io::{read_mesh, ReadOptions};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn write(dir: &Path, name: &str, body: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, body).unwrap();
    p
}

/// A plan over the fixture scenes, written into `dir` (so relative paths resolve).
fn small_plan(dir: &Path, fabrics: &str, sizes: &[(&str, f64)], extra: &str) -> PathBuf {
    let scenes = fixture("scenes").canonicalize().unwrap();
    let mut s = format!("fabrics = [{fabrics}]\n[solver]\nduration = 0.1\n{extra}\n");
    s += &format!(
        "[[garment]]\nname = \"square\"\nscene = \"{}\"\n",
        scenes.join("cotton_on_sphere.toml").display()
    );
    for (n, k) in sizes {
        s += &format!("[[size]]\nname = \"{n}\"\nscale = {k}\n");
    }
    write(dir, "plan.toml", &s)
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn run_batch(plan: &Path, out: &Path, extra: &[&str]) -> (std::process::Output, Value) {
    let o = drapekit()
        .args(["--jobs", "2", "batch", "run"])
        .arg(plan)
        .arg("-o")
        .arg(out)
        .arg("--json")
        .args(extra)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX")
        .output()
        .unwrap();
    let v = serde_json::from_slice(&o.stdout).unwrap_or(Value::Null);
    (o, v)
}

fn ran_ids(summary: &Value) -> Vec<String> {
    summary["ran"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["id"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn bad_plans_name_the_file_and_every_key() {
    let d = tempfile::tempdir().unwrap();
    // An unknown key: toml names it.
    let p = write(
        d.path(),
        "typo.toml",
        "[[garment]]\nname = \"a\"\nsceen = \"x.toml\"\n",
    );
    let o = drapekit().args(["batch", "plan"]).arg(&p).output().unwrap();
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("typo.toml: line 3, column 1: unknown field `sceen`"),
        "{err}"
    );
    // Bad values: each problem with its key, all at once.
    let p = small_plan(
        d.path(),
        "\"cotton\", \"velvet\"",
        &[("s", 0.0), ("s", 1.0)],
        "[fabric.rough]\nbase = \"cotton\"\nstrech = 3.0\n",
    );
    let o = drapekit().args(["batch", "plan"]).arg(&p).output().unwrap();
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    for needle in [
        "plan.toml",
        "key 'fabrics[1]': 'velvet' is neither a preset",
        "key 'size[0].scale': must be a factor from 0.1 to 10, got 0",
        "key 'size[1].name': 's' is given twice",
        "key 'fabric.rough': defined but not listed",
        "key 'fabric.rough.strech': unknown key",
    ] {
        assert!(err.contains(needle), "missing {needle:?} in {err}");
    }
    // Numbers in messages in short form, never 300 digits.
    let p = small_plan(
        d.path(),
        "\"cotton\"",
        &[],
        "dt = -1e300\n[[size]]\nname = \"big\"\nscale = 1e300\n",
    );
    let o = drapekit().args(["batch", "plan"]).arg(&p).output().unwrap();
    let (_, err) = text(&o);
    for needle in [
        "key 'size[0].scale': must be a factor from 0.1 to 10, got 1.000e300",
        "key 'solver.dt': must be a positive number, got -1.000e300",
    ] {
        assert!(err.contains(needle), "missing {needle:?} in {err}");
    }
    // A missing scene, and a scene with no object for a size to scale.
    let ribbon = fixture("scenes/hanging_ribbon.toml")
        .canonicalize()
        .unwrap();
    let p = write(
        d.path(),
        "missing.toml",
        &format!(
            "[[garment]]\nname = \"a\"\nscene = \"nowhere.toml\"\n[[garment]]\nname = \"b\"\nscene = \"{}\"\n[[size]]\nname = \"m\"\n",
            ribbon.display()
        ),
    );
    let o = drapekit().args(["batch", "plan"]).arg(&p).output().unwrap();
    let (_, err) = text(&o);
    assert!(
        err.contains("key 'garment[0].scene'") && err.contains("nowhere.toml is not a file"),
        "{err}"
    );
    assert!(
        err.contains("key 'garment[1].body_object'") && err.contains("has no [[object]]"),
        "{err}"
    );
    // The missing scene once, by its own key (not again as a scene that cannot be read).
    assert!(!err.contains("key 'garment[0].body_object'"), "{err}");
}

/// `batch plan PLAN` with a time limit (a hang or a quadratic check is a failure).
fn plan_within(plan: &Path, limit: std::time::Duration) -> std::process::Output {
    let mut child = drapekit()
        .args(["batch", "plan"])
        .arg(plan)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    // Read stdout as it comes (the job list can outgrow a pipe's buffer).
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        std::io::Read::read_to_end(&mut stdout, &mut s).unwrap();
        s
    });
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("batch plan {} still runs after {limit:?}", plan.display());
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let mut o = child.wait_with_output().unwrap();
    o.stdout = reader.join().unwrap();
    o
}

#[test]
fn job_counts_beyond_the_limit_are_refused_and_long_lists_checked_quickly() {
    let d = tempfile::tempdir().unwrap();
    // Refused within the time limit, with `needle` in the message.
    let refused = |p: &Path, needle: String| {
        let o = plan_within(p, std::time::Duration::from_secs(30));
        let err = text(&o).1;
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains(&needle), "missing {needle:?} in {err}");
    };
    let n = plan::MAX_JOBS;
    let sizes: String = (0..n)
        .map(|i| format!("[[size]]\nname = \"s{i}\"\n"))
        .collect();
    // The product: 1 garment x 2 fabrics x MAX_JOBS sizes.
    let p = small_plan(d.path(), "\"cotton\", \"silk\"", &[], &sizes);
    refused(
        &p,
        format!(
            "key 'garment x body x fabrics x size': 1 x 1 x 2 x {n} is {} jobs: at most {n}",
            2 * n
        ),
    );
    // A [[job]] list one over the limit.
    let listed = |count: usize, twice: bool| -> String {
        let mut s: String = (0..count)
            .map(|i| format!("[[job]]\ngarment = \"square\"\nsize = \"s{}\"\n", i % n))
            .collect();
        if twice {
            s += "[[job]]\ngarment = \"square\"\nsize = \"s7\"\n";
        }
        s
    };
    let p = small_plan(d.path(), "", &[], &(sizes.clone() + &listed(n + 1, false)));
    refused(
        &p,
        format!("key 'job': {} [[job]] entries: at most {n}", n + 1),
    );
    // A list at the limit with one job twice: found (by a hash set, not pair by pair).
    let p = small_plan(d.path(), "", &[], &(sizes.clone() + &listed(n - 1, true)));
    refused(
        &p,
        format!("key 'job[{}]': job square.s7 is listed twice", n - 1),
    );
    // The same list without the repeat is a plan of MAX_JOBS jobs.
    let p = small_plan(d.path(), "", &[], &(sizes + &listed(n, false)));
    let o = plan_within(&p, std::time::Duration::from_secs(30));
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
}

#[test]
fn product_count_ids_and_positions_stable_under_extension() {
    let d = tempfile::tempdir().unwrap();
    let p = small_plan(
        d.path(),
        "\"cotton\", \"silk\"",
        &[("s", 0.9), ("m", 1.0)],
        "",
    );
    let a = plan::read(&p).unwrap();
    assert_eq!(a.jobs.len(), 4);
    let ids: Vec<_> = a.jobs.iter().map(|j| j.id.as_str()).collect();
    assert_eq!(
        ids,
        [
            "square.cotton.s",
            "square.cotton.m",
            "square.silk.s",
            "square.silk.m"
        ]
    );
    // Extended: a fabric between (the product's order changes) and a size appended.
    let p2 = small_plan(
        d.path(),
        "\"cotton\", \"wool\", \"silk\"",
        &[("s", 0.9), ("m", 1.0), ("l", 1.1)],
        "",
    );
    let b = plan::read(&p2).unwrap();
    assert_eq!(b.jobs.len(), 9);
    for j in &a.jobs {
        let same = b
            .jobs
            .iter()
            .find(|k| k.id == j.id)
            .expect("the id survives");
        assert_eq!(a.spec_hash(j), b.spec_hash(same), "{}", j.id);
    }
    // In an output folder, the old jobs keep their positions; new ones come after.
    let out = d.path().join("out");
    let first = order::update(&out, &a).unwrap();
    let second = order::update(&out, &b).unwrap();
    assert_eq!(second.len(), 9);
    assert_eq!(&second[..4], &first[..]);
    // An explicit list: exactly its jobs, in its order.
    let p3 = small_plan(
        d.path(),
        "\"cotton\", \"silk\"",
        &[("s", 0.9), ("m", 1.0)],
        "[[job]]\ngarment = \"square\"\nfabric = \"silk\"\nsize = \"m\"\n[[job]]\ngarment = \"square\"\nfabric = \"cotton\"\nsize = \"s\"\n",
    );
    let c = plan::read(&p3).unwrap();
    let ids: Vec<_> = c.jobs.iter().map(|j| j.id.as_str()).collect();
    assert_eq!(ids, ["square.silk.m", "square.cotton.s"]);
}

/// Runs the example plan once per test binary (the tests below read it, none changes it).
fn example_run() -> &'static Path {
    static OUT: std::sync::OnceLock<tempfile::TempDir> = std::sync::OnceLock::new();
    OUT.get_or_init(|| {
        let d = tempfile::tempdir().unwrap();
        let (o, v) = run_batch(&fixture("batch_example.toml"), d.path(), &[]);
        assert!(o.status.success(), "{}", text(&o).1);
        assert_eq!(v["done"], 8, "{v}");
        d
    })
    .path()
}

#[test]
fn example_plan_runs_every_job_with_valid_outputs() {
    let out = example_run();
    let p = plan::read(&fixture("batch_example.toml")).unwrap();
    assert_eq!(p.jobs.len(), 8);
    for j in &p.jobs {
        let st = json(&out.join("jobs").join(&j.id).join("status.json"));
        assert_eq!(st["state"], "done", "{st}");
        assert_eq!(st["error"], Value::Null);
        assert_eq!(st["attempts"], 1);
        let report = json(&out.join(st["report"].as_str().unwrap()));
        // The job ran the plan's values: 0.3 s at the default 10 ms step, the fabric asked for.
        assert_eq!(report["steps"], 30, "{}", j.id);
        let fabric = p.axes(j).fabric.unwrap();
        assert_eq!(report["pieces"][0]["fabric"], fabric.as_str());
        let mesh = read_mesh(
            &out.join(st["mesh"].as_str().unwrap()),
            &ReadOptions::default(),
        )
        .unwrap()
        .mesh;
        assert_eq!(
            mesh.positions.len() as u64,
            report["particles"].as_u64().unwrap()
        );
        assert_eq!(
            mesh.faces.len() as u64,
            report["pieces"][0]["triangles"].as_u64().unwrap()
        );
        assert!(mesh
            .positions
            .iter()
            .all(|q| q.iter().all(|c| c.is_finite())));
    }
    // The size scales the body object: the small sphere (0.27 m) lets the square fall further.
    let low = |id: &str| {
        let m = read_mesh(
            &out.join(format!("jobs/{id}/out/square.obj")),
            &ReadOptions::default(),
        )
        .unwrap()
        .mesh;
        m.positions
            .iter()
            .map(|q| q.z)
            .fold(f64::INFINITY, f64::min)
    };
    let scene = std::fs::read_to_string(out.join("jobs/square.cotton.s/scene.toml")).unwrap();
    assert!(scene.contains("scale = 0.9"), "{scene}");
    assert!(low("square.cotton.s") < low("square.cotton.m"));
}

#[test]
fn collect_table_columns_and_values() {
    let out = example_run();
    let o = drapekit()
        .args(["batch", "collect"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o).1);
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "position,id,garment,body,fabric,size,kind,state,verdict,seam_gap_max_mm,body_crossings,self_crossings,max_strain,mean_strain,particles_inside,seconds,mesh,error"
    );
    assert_eq!(lines.count(), 8);
    let rows = json(&out.join("results.json"));
    let rows = rows.as_array().unwrap();
    let ids = order::load(out).unwrap();
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r["position"], k, "rows in position order");
        let id = r["id"].as_str().unwrap();
        assert_eq!(ids[k], id);
        let report = json(&out.join("jobs").join(id).join("report.json"));
        assert_eq!(r["max_strain"], report["max_strain"]);
        assert_eq!(r["mean_strain"], report["mean_strain"]);
        assert_eq!(r["particles_inside"], report["particles_inside"]);
        assert_eq!(r["state"], "done");
        assert_eq!(r["verdict"], "pass");
        assert_eq!(r["kind"], "scene");
        assert_eq!(r["body"], Value::Null);
        assert_eq!(r["seam_gap_max_mm"], Value::Null);
        let parts: Vec<&str> = id.split('.').collect();
        assert_eq!(
            [
                r["garment"].as_str(),
                r["fabric"].as_str(),
                r["size"].as_str()
            ],
            [Some(parts[0]), Some(parts[1]), Some(parts[2])]
        );
        assert!(r["seconds"].as_f64().unwrap() > 0.0);
        // The CSV row says the same.
        let line = csv.lines().nth(k + 1).unwrap();
        assert!(
            line.starts_with(&format!(
                "{k},{id},{},,{},{},scene,done,pass,,,,",
                parts[0], parts[1], parts[2]
            )),
            "{line}"
        );
    }
    let sheet = std::fs::read_to_string(out.join("contact_sheet.tsv")).unwrap();
    assert_eq!(sheet.lines().count(), 8);
    assert!(
        sheet.starts_with(&format!("{}\tjobs/{}/out/", ids[0], ids[0])),
        "{sheet}"
    );
    // The contact sheet: 8 cells of 240 x 180, four to a row, each with its cloth drawn (the
    // terracotta covers a good part of every cell).
    let (w, h, px) = common::read_png(&out.join("contact_sheet.png"));
    assert_eq!((w, h), (960, 360));
    for cell in 0..8 {
        let (x0, y0) = ((cell % 4) * 240, (cell / 4) * 180);
        let px = &px;
        let cloth = (y0..y0 + 180)
            .flat_map(|y| (x0..x0 + 240).map(move |x| px[y * 960 + x]))
            .filter(|c| u16::from(c[0]) > u16::from(c[2]) + 40)
            .count();
        assert!(cloth > 240 * 180 / 10, "cell {cell}: {cloth} cloth pixels");
    }
}

#[test]
fn rerun_skips_done_jobs_and_retries_failed_and_unfinished() {
    let d = tempfile::tempdir().unwrap();
    let p = small_plan(
        d.path(),
        "\"cotton\", \"silk\"",
        &[("s", 0.9), ("m", 1.0)],
        "",
    );
    let out = d.path().join("out");
    let (o, v) = run_batch(&p, &out, &[]);
    assert!(o.status.success(), "{}", text(&o).1);
    assert_eq!(v["done"], 4);
    // One job marked failed, one whose status is gone (as if killed before it was written).
    let status = |id: &str| out.join("jobs").join(id).join("status.json");
    let mut failed = json(&status("square.silk.s"));
    failed["state"] = "failed".into();
    std::fs::write(status("square.silk.s"), failed.to_string()).unwrap();
    std::fs::remove_file(status("square.cotton.m")).unwrap();
    let kept = out.join("jobs/square.cotton.s/out/square.obj");
    let before = (
        std::fs::read(&kept).unwrap(),
        std::fs::metadata(&kept).unwrap().modified().unwrap(),
    );
    let kept_status = std::fs::read(status("square.cotton.s")).unwrap();
    let (o, v) = run_batch(&p, &out, &[]);
    assert!(o.status.success(), "{}", text(&o).1);
    let mut ran = ran_ids(&v);
    ran.sort();
    assert_eq!(ran, ["square.cotton.m", "square.silk.s"]);
    assert_eq!(v["skipped"], 2);
    assert_eq!(json(&status("square.silk.s"))["attempts"], 2);
    let after = (
        std::fs::read(&kept).unwrap(),
        std::fs::metadata(&kept).unwrap().modified().unwrap(),
    );
    assert_eq!(before, after, "a finished job's mesh is untouched");
    assert_eq!(
        kept_status,
        std::fs::read(status("square.cotton.s")).unwrap()
    );
    // A third run has nothing to do; a changed definition (the duration) runs everything again.
    let (_, v) = run_batch(&p, &out, &[]);
    assert_eq!(
        (v["skipped"].as_u64(), v["ran"].as_array().unwrap().len()),
        (Some(4), 0)
    );
    let text2 = std::fs::read_to_string(&p)
        .unwrap()
        .replace("duration = 0.1", "duration = 0.05");
    std::fs::write(&p, text2).unwrap();
    let (_, v) = run_batch(&p, &out, &[]);
    assert_eq!(v["done"], 4, "{v}");
}

#[test]
fn a_bad_job_fails_alone_with_its_error() {
    let d = tempfile::tempdir().unwrap();
    let sphere = fixture("scenes/sphere_r0.3.obj").canonicalize().unwrap();
    write(d.path(), "broken.obj", "v 0 0 0\nv 1 0\nf 1 2 3\n");
    let extra = format!(
        "[[body]]\nname = \"ball\"\nmesh = \"{}\"\n[[body]]\nname = \"broken\"\nmesh = \"broken.obj\"\n",
        sphere.display()
    );
    let p = small_plan(d.path(), "\"cotton\"", &[], &extra);
    let out = d.path().join("out");
    let (o, v) = run_batch(&p, &out, &[]);
    assert_eq!(o.status.code(), Some(1), "a failed job fails the run");
    assert_eq!(
        (v["done"].as_u64(), v["failed"].as_u64()),
        (Some(1), Some(1)),
        "{v}"
    );
    let bad = json(&out.join("jobs/square.broken.cotton/status.json"));
    assert_eq!(bad["state"], "failed");
    let err = bad["error"].as_str().unwrap();
    assert!(
        err.contains("broken.obj:2: a vertex needs 3 coordinates"),
        "{err}"
    );
    let good = json(&out.join("jobs/square.ball.cotton/status.json"));
    assert_eq!(good["state"], "done");
    // The table has both, the error in its row.
    let o = drapekit()
        .args(["batch", "collect", "--json"])
        .arg(&out)
        .output()
        .unwrap();
    let rows: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(rows[1]["state"], "failed");
    assert_eq!(rows[1]["error"].as_str(), Some(err));
    assert_eq!(rows[1]["verdict"], Value::Null);
}

#[test]
fn index_flag_and_scheduler_variables_select_the_same_job() {
    let d = tempfile::tempdir().unwrap();
    let p = small_plan(
        d.path(),
        "\"cotton\", \"silk\"",
        &[("s", 0.9), ("m", 1.0)],
        "",
    );
    let listed = drapekit()
        .args(["batch", "plan", "--json"])
        .arg(&p)
        .output()
        .unwrap();
    let listed: Value = serde_json::from_slice(&listed.stdout).unwrap();
    let want = listed[2]["id"].as_str().unwrap().to_string();
    assert_eq!(listed[2]["position"], 2);
    let ways: [(&str, Option<(&str, &str)>); 3] = [
        ("flag", None),
        ("slurm", Some(("SLURM_ARRAY_TASK_ID", "2"))),
        ("k8s", Some(("JOB_COMPLETION_INDEX", "2"))),
    ];
    for (name, var) in ways {
        let out = d.path().join(name);
        let mut c = drapekit();
        c.args(["batch", "run"])
            .arg(&p)
            .arg("-o")
            .arg(&out)
            .arg("--json");
        c.env_remove("SLURM_ARRAY_TASK_ID")
            .env_remove("JOB_COMPLETION_INDEX");
        match var {
            None => c.args(["--index", "2"]),
            Some((k, v)) => c.env(k, v),
        };
        let o = c.output().unwrap();
        assert!(o.status.success(), "{name}: {}", text(&o).1);
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(ran_ids(&v), std::slice::from_ref(&want), "{name}");
        let dirs = common::listing(&out.join("jobs"));
        assert_eq!(
            dirs,
            std::slice::from_ref(&want),
            "{name}: only that job ran"
        );
    }
    // Out of range: a clear error.
    let o = drapekit()
        .args(["batch", "run"])
        .arg(&p)
        .arg("-o")
        .arg(d.path().join("x"))
        .args(["--index", "9"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o)
        .1
        .contains("job index 9 is out of range: the plan has positions 0 to 3"));
}

#[test]
fn slurm_script_has_the_array_resources_and_command() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let o = drapekit()
        .args(["batch", "slurm"])
        .arg(fixture("batch_example.toml"))
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o).1);
    let s = std::fs::read_to_string(out.join("batch.sbatch")).unwrap();
    let out = out.canonicalize().unwrap();
    for line in [
        "#SBATCH --array=0-7%4".to_string(),
        "#SBATCH --cpus-per-task=1".into(),
        "#SBATCH --mem=500M".into(),
        "#SBATCH --time=5".into(),
        format!("#SBATCH --output={}/logs/%A_%a.out", out.display()),
    ] {
        assert!(s.lines().any(|l| l == line), "missing {line} in\n{s}");
    }
    assert!(s.trim_end().ends_with(&format!(
        "batch run {} -o {}",
        fixture("batch_example.toml")
            .canonicalize()
            .unwrap()
            .display(),
        out.display()
    )));
    assert!(out.join("logs").is_dir());
    assert_eq!(order::load(&out).unwrap().len(), 8);
}

#[test]
fn pattern_jobs_on_a_fitted_body_fit_it_once_and_scale_it() {
    let Some(real) = common::realdata() else {
        return;
    };
    let d = tempfile::tempdir().unwrap();
    let plan = format!(
        "fabrics = [\"cotton\"]\n[garment_solver]\nsew_max = 0.1\nsettle_max = 0.1\n\
         [[garment]]\nname = \"dress\"\npattern = \"{}\"\nspacing = 0.04\n\
         [[body]]\nname = \"f38\"\nmeasurements = \"{}\"\n\
         [[size]]\nname = \"s\"\nscale = 0.95\n[[size]]\nname = \"m\"\nscale = 1.0\n",
        real.join("patterns/dress_pencil_specification.json")
            .display(),
        fixture("measurements_size38.toml")
            .canonicalize()
            .unwrap()
            .display()
    );
    let p = write(d.path(), "plan.toml", &plan);
    let out = d.path().join("out");
    let (o, v) = run_batch(&p, &out, &[]);
    assert!(o.status.success(), "{}", text(&o).1);
    assert_eq!(v["done"], 2, "{v}");
    // One fitted form (size m uses it as it is: y up, scale 1), one scaled copy for size s.
    let bodies = common::listing(&out.join("bodies"));
    assert_eq!(bodies.len(), 2, "{bodies:?}");
    let form = bodies.iter().find(|b| !b.starts_with("f38-s-")).unwrap();
    let small = bodies.iter().find(|b| b.starts_with("f38-s-")).unwrap();
    let top = |f: &str| {
        let m = read_mesh(&out.join("bodies").join(f), &ReadOptions::default())
            .unwrap()
            .mesh;
        m.positions
            .iter()
            .map(|q| q.y)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    assert!((top(small) / top(form) - 0.95).abs() < 1e-9);
    // In metres, y up: the torso of a 168 cm body ends at its neck base, near 1.47 m.
    assert!((1.3..1.6).contains(&top(form)), "{}", top(form));
    // The table carries the garment report's verdict, seam gap, crossings and strain.
    let o = drapekit()
        .args(["batch", "collect", "--json"])
        .arg(&out)
        .output()
        .unwrap();
    let rows: Value = serde_json::from_slice(&o.stdout).unwrap();
    for r in rows.as_array().unwrap() {
        let rep = json(
            &out.join("jobs")
                .join(r["id"].as_str().unwrap())
                .join("report.json"),
        );
        assert_eq!(r["kind"], "pattern");
        assert_eq!(r["verdict"], rep["verdict"]);
        assert_eq!(r["seam_gap_max_mm"], rep["garment"]["seam_gap_max_mm"]);
        assert_eq!(r["body_crossings"], rep["garment"]["body_crossing_edges"]);
        assert_eq!(r["self_crossings"], rep["garment"]["self_crossing_edges"]);
        assert_eq!(r["max_strain"], rep["garment"]["max_strain"]);
        assert_eq!(rep["spacing"], 0.04);
        assert!(rep["body"].as_str().unwrap().contains("/bodies/f38-"));
    }
}
