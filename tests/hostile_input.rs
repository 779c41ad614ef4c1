//! Hostile input (issue 9): counts that would allocate or run without bound are refused before
//! any work, naming the key or flag and the limit; huge and tiny coordinates give an answer.
//! Every run has a time limit: a hang is a failure, not a stuck test.

mod common;
use common::{drapekit, fixture, listing, text};
use std::process::Output;
use std::time::{Duration, Instant};

/// Runs drapekit with `args`, killing it (and failing) after `limit`.
fn run_within(args: &[&str], limit: Duration) -> Output {
    let mut child = drapekit()
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("drapekit runs");
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("drapekit {args:?} still runs after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// The sphere-drop scene with `edits` (from, to) applied, in a fresh directory.
fn scene(edits: &[(&str, &str)]) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let mut s = std::fs::read_to_string(fixture("scenes/sphere_drop.toml")).unwrap();
    for (from, to) in edits {
        assert!(s.contains(from), "{from}");
        s = s.replace(from, to);
    }
    std::fs::copy(
        fixture("scenes/sphere_r0.3.obj"),
        dir.path().join("sphere_r0.3.obj"),
    )
    .unwrap();
    let path = dir.path().join("s.toml");
    std::fs::write(&path, s).unwrap();
    (dir, path)
}

/// Drapes the edited scene; asserts exit 1 within seconds, every part in the message, and
/// nothing written.
fn drape_refused(edits: &[(&str, &str)], parts: &[&str]) {
    let (dir, path) = scene(edits);
    let out = dir.path().join("out.obj");
    let o = run_within(
        &["drape", path.to_str().unwrap(), "-o", out.to_str().unwrap()],
        Duration::from_secs(20),
    );
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    for p in parts {
        assert!(err.contains(p), "expected {p:?} in: {err}");
    }
    assert!(!out.exists(), "nothing written");
}

#[test]
fn hostile_collision_cells_beyond_the_limit_are_refused() {
    drape_refused(
        &[("cells = \"auto\"", "cells = [4096, 4096, 4096]")],
        &["key 'collision.cells': [4096, 4096, 4096] is 68719476736 cells: at most 16777216"],
    );
}

#[test]
fn hostile_tiny_step_with_a_duration_is_refused() {
    drape_refused(
        &[
            ("dt = 1e-4", "dt = 1e-300"),
            (
                "until_rest = 1e-5            # J of kinetic energy\nmax_steps = 40000",
                "duration = 1.0",
            ),
        ],
        &[
            "key 'solver.duration'",
            "solver.dt = 1e-300 s",
            "at most 100000000",
        ],
    );
}

#[test]
fn hostile_tiny_steps_are_refused_for_every_integrator_even_with_a_step_count() {
    // 1e-300 s squares to 0: projective dynamics' weights m / dt^2 were infinite, and the run
    // was reported as an instability. 1e-9 s is the shortest step a scene may ask for.
    for integrator in ["projective-dynamics", "implicit-euler", "leapfrog"] {
        for dt in ["1e-300", "9.9e-10"] {
            drape_refused(
                &[
                    (
                        "integrator = \"leapfrog\"\ndt = 1e-4",
                        &format!("integrator = \"{integrator}\"\ndt = {dt}"),
                    ),
                    ("max_steps = 40000", "max_steps = 2"),
                ],
                &["key 'solver.dt'", "s is below 1e-9 s"],
            );
        }
    }
    // At the bound itself the scene runs (two steps).
    drape_warnings(&[("dt = 1e-4", "dt = 1e-9")]);
}

#[test]
fn hostile_step_counts_beyond_the_limit_are_refused() {
    drape_refused(
        &[("max_steps = 40000", "max_steps = 100000000000")],
        &["key 'solver.max_steps': 100000000000 steps: at most 100000000"],
    );
}

#[test]
fn hostile_iteration_counts_beyond_their_limits_are_refused() {
    let leapfrog = "integrator = \"leapfrog\"";
    drape_refused(
        &[(
            leapfrog,
            "integrator = \"projective-dynamics\"\niterations = 4000000000",
        )],
        &["key 'solver.iterations': 4000000000 iterations: at most 1000"],
    );
    drape_refused(
        &[(
            leapfrog,
            "integrator = \"implicit-euler\"\nnewton_iterations = 101\ncg_max_iterations = 4294967295",
        )],
        &[
            "2 problems",
            "key 'solver.newton_iterations': 101 iterations: at most 100",
            "key 'solver.cg_max_iterations': 4294967295 iterations: at most 100000",
        ],
    );
    // The limits themselves are accepted (the scene runs two steps).
    let (dir, path) = scene(&[
        (
            leapfrog,
            "integrator = \"implicit-euler\"\nnewton_iterations = 100\ncg_max_iterations = 100000\ndt = 0.01",
        ),
        ("dt = 1e-4", ""),
        (
            "until_rest = 1e-5            # J of kinetic energy\nmax_steps = 40000",
            "steps = 2",
        ),
    ]);
    let o = run_within(
        &[
            "drape",
            path.to_str().unwrap(),
            "-o",
            dir.path().join("out").to_str().unwrap(),
        ],
        Duration::from_secs(120),
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
}

#[test]
fn hostile_frame_counts_beyond_the_limit_are_refused() {
    // A frame every step until rest: up to 40,000 frames (each a mesh file).
    drape_refused(
        &[("cells = \"auto\"", "cells = \"auto\"\n[output]\nframes = 1")],
        &["key 'output.frames': a frame every 1 steps over up to 40000 steps is 40000 frames: at most 10000; give frames = 4 or more"],
    );
}

#[test]
fn hostile_batch_plan_counts_beyond_the_scene_limits_are_refused() {
    // A plan's [solver] and [garment_solver] go into every job: refused with the plan's keys,
    // before any job is made.
    let d = tempfile::tempdir().unwrap();
    let ribbon = fixture("scenes/hanging_ribbon.toml");
    let plan = d.path().join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "[[garment]]\nname = \"a\"\nscene = \"{}\"\n[solver]\niterations = 1001\nnewton_iterations = 4000000000\nanderson = 21\nsteps = 100000001\n[garment_solver]\nsettle_max = 1e300\n",
            ribbon.display()
        ),
    )
    .unwrap();
    let o = run_within(
        &["batch", "plan", plan.to_str().unwrap()],
        Duration::from_secs(20),
    );
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    for needle in [
        "key 'solver.iterations': 1001 iterations: at most 1000",
        "key 'solver.newton_iterations': 4000000000 iterations: at most 100",
        "key 'solver.anderson': must be 0 (off) to 20 vectors of history, got 21",
        "key 'solver.steps': 100000001 steps: at most 100000000",
        "key 'garment_solver.settle_max': 1.000e300 s: at most 3600 s",
    ] {
        assert!(err.contains(needle), "missing {needle:?} in {err}");
    }
    assert_eq!(listing(d.path()), ["plan.toml"], "nothing written");
}

#[test]
fn hostile_garment_stage_times_beyond_the_limit_are_refused() {
    let d = tempfile::tempdir().unwrap();
    for (flag, value, shown) in [
        ("--sew-max", "1e300", "1.000e300"),
        ("--settle-max", "3601", "3601"),
    ] {
        let o = run_within(
            &[
                "garment",
                "p.json",
                "--body",
                "b.obj",
                "-o",
                d.path().join("out").to_str().unwrap(),
                flag,
                value,
            ],
            Duration::from_secs(20),
        );
        let err = text(&o).1;
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains(&format!(
                "{flag} {shown}: must be a positive number of simulated seconds, at most 3600"
            )),
            "{err}"
        );
    }
    assert!(listing(d.path()).is_empty(), "nothing written");
}

#[test]
fn hostile_bench_counts_beyond_their_limits_are_refused() {
    for args in [
        &["bench", "speed", "--runs", "1001"][..],
        &["bench", "speed", "--side", "1001"],
        &["bench", "speed", "--iterations", "1001"],
        &["bench", "speed", "--low-rank-max", "4097"],
        &["bench", "inside", "b.obj", "--points", "10000001"],
        &["bench", "drape", "--steps", "100000001"],
    ] {
        let o = run_within(args, Duration::from_secs(20));
        let err = text(&o).1;
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        let (flag, value) = (args[args.len() - 2], args[args.len() - 1]);
        assert!(
            err.contains(&format!("invalid value '{value}' for '{flag}")) && err.contains("not in"),
            "{args:?}: {err}"
        );
    }
    let o = run_within(
        &["bench", "speed", "--duration", "1e300"],
        Duration::from_secs(20),
    );
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(
            "--duration 1.000e300 s at dt = 1e-2 s is 1.000e302 steps: give 1 to 100000000"
        ),
        "{err}"
    );
}

#[test]
fn hostile_spacing_near_the_particle_cap_is_refused_at_once() {
    // 2.6 million particles: under the grid-node cap, but minutes and gigabytes to build.
    drape_refused(
        &[("spacing = 0.02", "spacing = 0.0005")],
        &[
            "key 'piece[1].spacing'",
            "particles; at most 1000000: use a larger spacing",
        ],
    );
}

#[test]
fn hostile_placement_at_1e308_is_refused_naming_the_key_and_the_rounding() {
    // At 1e308 neighbouring f64 numbers are about 2e292 apart: the 2 cm spacing is lost.
    drape_refused(
        &[(
            "position = [0.0, 0.0, 0.33]",
            "position = [0.0, 0.0, 1e308]",
        )],
        &[
            "key 'piece[1].position': reaches 1.000e308 m from the origin",
            "where coordinates are 2.220e292 m apart",
            "more than a millionth of the spacing (0.02 m)",
            "place it within 9.007e7 m of the origin",
        ],
    );
    // Just inside that reach, the same scene runs and its cloth stays finite.
    let (dir, path) = scene(&[
        (
            "position = [0.0, 0.0, 0.33]",
            "position = [0.0, 0.0, 9.0e7]",
        ),
        (
            "until_rest = 1e-5            # J of kinetic energy\nmax_steps = 40000",
            "steps = 2",
        ),
    ]);
    let out = dir.path().join("out");
    let o = run_within(
        &["drape", path.to_str().unwrap(), "-o", out.to_str().unwrap()],
        Duration::from_secs(60),
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
    let obj = std::fs::read_to_string(out.join("square.obj")).unwrap();
    let zs: Vec<f64> = obj
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| l.split_whitespace().nth(2).unwrap().parse().unwrap())
        .collect();
    assert_eq!(zs.len(), 1681);
    assert!(zs.iter().all(|z| (z - 9.0e7).abs() < 1.0), "{:?}", &zs[..3]);
}

#[test]
fn hostile_large_piece_far_out_is_refused_by_its_thickness() {
    // 80 Gm on a side at 2 Gm spacing: the spacing is resolved 1e12 m out, but coordinates
    // there are 2.2e-4 m apart, a tenth of the fabric's thickness (2 mm here).
    drape_refused(
        &[
            (
                "outline = [[-0.4, -0.4], [0.4, -0.4], [0.4, 0.4], [-0.4, 0.4]]",
                "outline = [[-4e10, -4e10], [4e10, -4e10], [4e10, 4e10], [-4e10, 4e10]]",
            ),
            ("spacing = 0.02", "spacing = 2e9"),
            ("position = [0.0, 0.0, 0.33]", "position = [0.0, 0.0, 1e12]"),
        ],
        &[
            "key 'piece[1].position': reaches 1.000e12 m from the origin",
            "more than a thousandth of the fabric's thickness (0.002 m)",
            "place it within 9.007e9 m of the origin",
        ],
    );
    // The same reach in the outline itself is named as the outline.
    drape_refused(
        &[
            (
                "outline = [[-0.4, -0.4], [0.4, -0.4], [0.4, 0.4], [-0.4, 0.4]]",
                "outline = [[-1e12, -1e12], [1e12, -1e12], [1e12, 1e12], [-1e12, 1e12]]",
            ),
            ("spacing = 0.02", "spacing = 2e11"),
        ],
        &["key 'piece[1].outline': reaches 1.000e12 m from the origin"],
    );
}

fn fit_refused(extra: &[&str], parts: &[&str]) {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("x.obj");
    let mut args = vec![
        "fit",
        "--measurements",
        fixture_str("measurements_size38.toml"),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = run_within(&args, Duration::from_secs(20));
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    for p in parts {
        assert!(err.contains(p), "expected {p:?} in: {err}");
    }
    assert!(listing(d.path()).is_empty(), "nothing written");
}

fn fixture_str(name: &str) -> &'static str {
    Box::leak(fixture(name).to_str().unwrap().to_string().into_boxed_str())
}

#[test]
fn hostile_fit_node_counts_are_refused() {
    fit_refused(
        &["--nodes", "1000000000"],
        &["--nodes 1000000000: at most 65536 nodes around each section"],
    );
    fit_refused(
        &["--around", "100000", "--along", "100000"],
        &["--around x --along 10000000000: at most 16777216 vertices of the form"],
    );
    fit_refused(
        &["--levels", "1000000000"],
        &["--levels 1000000000: at most 10000 sections"],
    );
}

/// A regular tetrahedron scaled by `s`, as OBJ text.
fn tetra(s: f64) -> String {
    let p = [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    let mut t = String::new();
    for q in p {
        t += &format!("v {:e} {:e} {:e}\n", q[0] * s, q[1] * s, q[2] * s);
    }
    t + "f 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n"
}

#[test]
fn hostile_tetrahedra_at_1e100_and_1e_minus_100_convert_and_at_1e300_are_refused() {
    for s in [1e100, 1e-100, 1e300] {
        let (o, _dir, out) = convert_file("t.obj", tetra(s).as_bytes());
        let err = text(&o).1;
        assert!(!err.contains("collinear"), "{s}: {err}");
        if s == 1e300 {
            // Beyond what a volume holds: refused, naming the file, the line and the bound,
            // and nothing written (its report would hold infinities).
            assert_eq!(o.status.code(), Some(1), "{err}");
            assert!(err.contains("t.obj"), "{err}");
            assert!(
                err.contains("t.obj:1: coordinate 1e300 is larger than 1e100 in magnitude"),
                "{err}"
            );
            assert!(!out.exists());
            continue;
        }
        assert_eq!(o.status.code(), Some(0), "{s}: {err}");
        let faces = std::fs::read_to_string(&out)
            .unwrap()
            .lines()
            .filter(|l| l.starts_with("f "))
            .count();
        assert_eq!(faces, 4, "{s}");
    }
}

/// Drapes the edited scene for two steps; returns stderr and the report's `warnings`.
fn drape_warnings(edits: &[(&str, &str)]) -> (String, Vec<String>) {
    let mut edits = edits.to_vec();
    edits.push((
        "until_rest = 1e-5            # J of kinetic energy\nmax_steps = 40000",
        "steps = 2",
    ));
    let (dir, path) = scene(&edits);
    let out = dir.path().join("out");
    let o = run_within(
        &[
            "drape",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--json",
        ],
        Duration::from_secs(60),
    );
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let w = report["warnings"]
        .as_array()
        .expect("warnings in the report");
    (
        stderr,
        w.iter().map(|v| v.as_str().unwrap().to_string()).collect(),
    )
}

#[test]
fn hostile_an_object_in_the_wrong_units_or_cloth_inside_it_is_warned_before_the_run() {
    // The sphere read as if in centimetres: 100 times too large, the cloth inside it.
    let (err, w) = drape_warnings(&[("friction = 0.3", "friction = 0.3\nscale = 100.0")]);
    assert_eq!(w.len(), 2, "{w:?}");
    // 104 m across against the cloth's 1.13 m.
    assert!(w[0].starts_with("object 'sphere_r0.3' is 9"), "{w:?}");
    assert!(w[0].contains("times the cloth's size"), "{w:?}");
    assert!(w[0].contains("(set its scale)"), "{w:?}");
    assert!(
        w[1].contains("of 1681 particles start inside object 'sphere_r0.3'"),
        "{w:?}"
    );
    for m in &w {
        assert!(err.contains(&format!("warning: {m}")), "printed: {err}");
    }
    // The cloth placed through the sphere's centre: its middle starts inside.
    let (_, w) = drape_warnings(&[("position = [0.0, 0.0, 0.33]", "position = [0.0, 0.0, 0.0]")]);
    assert_eq!(w.len(), 1, "{w:?}");
    let n: usize = w[0].split(' ').next().unwrap().parse().unwrap();
    // The particles within the sphere's radius: about pi 0.3^2 / 0.02^2 = 707 of them.
    assert!((600..800).contains(&n), "{w:?}");
    // The scene as it is: nothing to warn about.
    let (_, w) = drape_warnings(&[]);
    assert!(w.is_empty(), "{w:?}");
}

/// Converts `bytes` (a mesh file named `name`, in a fresh folder) to `o.obj` beside it: the
/// run, the folder and the output's path.
fn convert_file(name: &str, bytes: &[u8]) -> (Output, tempfile::TempDir, std::path::PathBuf) {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join(name);
    std::fs::write(&input, bytes).unwrap();
    let out = d.path().join("o.obj");
    let o = run_within(
        &[
            "convert",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        Duration::from_secs(20),
    );
    (o, d, out)
}

/// Converts `bytes` (see [`convert_file`]) and returns stderr with the input named `name`,
/// asserting exit 1 and nothing written.
fn convert_refused(name: &str, bytes: &[u8]) -> String {
    let (o, d, out) = convert_file(name, bytes);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!out.exists(), "nothing written");
    err.replace(d.path().join(name).to_str().unwrap(), name)
}

#[test]
fn hostile_lines_longer_than_a_mebibyte_are_refused_naming_the_line() {
    let too_long = "the line is longer than 1048576 bytes";
    // A comment line of 2 MiB on line 3 of an OBJ.
    let mut obj = b"v 0 0 0\nv 1 0 0\n# ".to_vec();
    obj.extend(std::iter::repeat_n(b'x', 2 << 20));
    obj.extend_from_slice(b"\nv 0 1 0\nf 1 2 3\n");
    let err = convert_refused("long.obj", &obj);
    assert!(
        err.starts_with(&format!("error: long.obj:3: {too_long}")),
        "{err}"
    );
    // A face continued over 2,000 lines of 1 KB (statement of line 4, 2 MB joined).
    let mut obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3".to_vec();
    for _ in 0..2000 {
        obj.extend_from_slice(b" \\\n");
        obj.extend(std::iter::repeat_n(b' ', 1000));
    }
    obj.extend_from_slice(b"\n");
    let err = convert_refused("continued.obj", &obj);
    assert!(
        err.starts_with(&format!("error: continued.obj:4: {too_long}")),
        "{err}"
    );
    // Vertex triples whose second line is a run of 1.5 MiB of digits.
    let mut tri = b"0 0 0\n".to_vec();
    tri.extend(std::iter::repeat_n(b'1', 3 << 19));
    tri.extend_from_slice(b" 0 0\n0 1 0\n");
    let err = convert_refused("long.txt", &tri);
    assert!(
        err.starts_with(&format!("error: long.txt:2: {too_long}")),
        "{err}"
    );
    // A line of exactly 1 MiB is read (here a comment, so the triangle converts).
    let mut ok = b"# ".to_vec();
    ok.extend(std::iter::repeat_n(b'x', (1 << 20) - 2));
    ok.extend_from_slice(b"\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let (o, _dir, out) = convert_file("edge.obj", &ok);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
    assert!(out.exists());
}
