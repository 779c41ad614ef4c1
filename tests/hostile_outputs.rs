//! Hostile outputs (issue 9): nothing written outside the output folder, nothing of an earlier run
//! lost to a failed one, numbers in messages people can read, and the traps new users fall into
//! (a Y-up body read as Z-up, an open collider, flags that do nothing) said out loud.

mod common;
use common::{fixture, listing, run, text};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The sphere-drop scene, five steps long, with `edits` (from, to) applied, in `dir`.
fn scene_in(dir: &Path, edits: &[(&str, &str)]) -> PathBuf {
    let mut s = std::fs::read_to_string(fixture("scenes/sphere_drop.toml")).unwrap();
    for (from, to) in [
        (
            "until_rest = 1e-5            # J of kinetic energy\n",
            "steps = 5\n",
        ),
        ("max_steps = 40000\n", ""),
    ]
    .iter()
    .chain(edits)
    {
        assert!(s.contains(from), "{from}");
        s = s.replacen(from, to, 1);
    }
    let sphere = dir.join("sphere_r0.3.obj");
    if !sphere.exists() {
        std::fs::copy(fixture("scenes/sphere_r0.3.obj"), sphere).unwrap();
    }
    let path = dir.join("s.toml");
    std::fs::write(&path, s).unwrap();
    path
}

/// Runs `drapekit COMMAND INPUT -o OUT EXTRA...`.
fn cli(command: &str, input: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let (input, out) = (input.to_str().unwrap(), out.to_str().unwrap());
    run(&[&[command, input, "-o", out], extra].concat())
}

fn drape(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    cli("drape", scene, out, extra)
}

/// Every file under `dir` (relative path -> bytes).
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut m = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().display().to_string();
                m.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    m
}

/// A run of more than 17 digits: more than an f64 has to say.
fn longest_digit_run(s: &str) -> usize {
    s.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

#[test]
fn hostile_piece_names_outside_the_output_folder_are_refused_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let escaped = dir.path().join("escaped");
    let absolute = escaped.display().to_string();
    for name in [absolute.as_str(), "../up", "sub/x", "..", ""] {
        let s = scene_in(
            dir.path(),
            &[("name = \"square\"", &format!("name = {name:?}"))],
        );
        let out = dir.path().join("out");
        let o = drape(&s, &out, &[]);
        let err = text(&o).1;
        assert_eq!(o.status.code(), Some(1), "{name:?}: {err}");
        assert!(
            err.contains("key 'piece[1].name'")
                && err.contains("cannot be a file name in the output folder")
                && err.contains("no '/'"),
            "{name:?}: {err}"
        );
        // Refused at validation: no step was taken, nothing written anywhere.
        assert!(!err.contains("steps"), "{err}");
        assert!(!out.exists(), "{name:?}");
        assert_eq!(
            listing(dir.path()),
            ["s.toml", "sphere_r0.3.obj"],
            "{name:?}"
        );
    }
}

/// Two pieces, PLY as well, a frame every step.
fn two_pieces(dir: &Path, edits: &[(&str, &str)]) -> PathBuf {
    let second = "[[piece]]\nname = \"b\"\noutline = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]\nspacing = 0.05\nposition = [0.0, 0.0, 0.6]\nfabric = \"soft_cotton\"\n\n[output]\nply = true\nframes = 1\n\n# Cotton";
    let mut all = vec![("name = \"square\"", "name = \"a\""), ("# Cotton", second)];
    all.extend_from_slice(edits);
    scene_in(dir, &all)
}

#[test]
fn hostile_a_failed_rerun_leaves_the_earlier_outputs_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let s = two_pieces(dir.path(), &[]);
    let o = drape(&s, &out, &[]);
    assert!(o.status.success(), "{}", text(&o).1);
    let first = snapshot(&out);
    assert!(first.contains_key("a.obj") && first.contains_key("b.ply"));
    assert!(
        first.contains_key("frames/a_0000005.obj"),
        "{:?}",
        first.keys()
    );

    // 1. Fails after the run, on writing: a third piece whose output path is a directory.
    let third = "[[piece]]\nname = \"c\"\noutline = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]\nspacing = 0.05\nposition = [0.0, 0.0, 0.9]\nfabric = \"soft_cotton\"\n\n[output]";
    let s = two_pieces(
        dir.path(),
        &[
            ("[output]", third),
            ("position = [0.0, 0.0, 0.33]", "position = [0.0, 0.0, 0.35]"),
        ],
    );
    std::fs::create_dir(out.join("c.obj")).unwrap();
    let o = drape(&s, &out, &[]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("c.obj"), "{err}");
    std::fs::remove_dir(out.join("c.obj")).unwrap();
    assert_eq!(
        snapshot(&out),
        first,
        "a failed write changed the earlier run's files"
    );

    // 2. Fails during the run, after writing frames: an explicit step far too large.
    let s = two_pieces(
        dir.path(),
        &[("dt = 1e-4", "dt = 0.05"), ("steps = 5", "steps = 2000")],
    );
    let o = drape(&s, &out, &[]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("unstable"), "{err}");
    let after = snapshot(&out);
    assert_eq!(
        after.keys().collect::<Vec<_>>(),
        first.keys().collect::<Vec<_>>(),
        "no file added or removed, no temporary file left"
    );
    assert!(
        after == first,
        "an unstable run changed the earlier run's files"
    );
}

#[test]
fn hostile_huge_and_tiny_keys_are_reported_in_short_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene_in(
        dir.path(),
        &[
            ("friction = 0.3", "friction = 1e300"),
            ("dt = 1e-4", "dt = -1e300"),
            ("spacing = 0.02", "spacing = -1e-300"),
            ("thickness = 0.002", "thickness = 0.002\ndensity = -1e300"),
        ],
    );
    let o = drape(&s, &dir.path().join("out"), &[]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    for part in [
        "key 'solver.dt': must be a positive number, got -1.000e300",
        "key 'object[1].friction': must be within 0..1, got 1.000e300",
        "key 'fabric.soft_cotton.density': must be a positive number, got -1.000e300",
        "key 'piece[1].spacing': must be a positive number, got -1.000e-300",
    ] {
        assert!(err.contains(part), "expected {part:?} in: {err}");
    }
    assert!(longest_digit_run(&err) <= 17, "{err}");

    let s = scene_in(dir.path(), &[("steps = 5", "duration = 1e300")]);
    let err = text(&drape(&s, &dir.path().join("out"), &[])).1;
    assert!(
        err.contains("key 'solver.duration': 1.000e300 s at"),
        "{err}"
    );
    assert!(longest_digit_run(&err) <= 17, "{err}");

    // A fabric so stiff and light that no stable step can be estimated: no "inf" or "0" advice.
    let s = scene_in(
        dir.path(),
        &[
            ("dt = 1e-4\n", ""),
            ("stretch = 1000.0", "stretch = 1e300\ndensity = 1e-300"),
        ],
    );
    let o = drape(&s, &dir.path().join("out"), &[]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("key 'solver.dt'") && err.contains("no stable step"),
        "{err}"
    );
    for bad in ["inf", "NaN", "0.000e0"] {
        assert!(!err.contains(bad), "{bad} in: {err}");
    }
}

#[test]
fn hostile_fit_of_a_y_up_body_read_as_z_up_says_give_up_y() {
    let Some(data) = common::realdata() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("form.obj");
    let body = data.join("bodies/mean_all.obj");
    let o = run(&[
        "fit",
        "--from-mesh",
        body.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(
            "mean_all.obj: the body is 1.72 long along y but only 0.3002 along the up axis z"
        ) && err.contains("give --up y"),
        "{err}"
    );
    assert!(!err.contains("torso splits"), "{err}");
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn hostile_an_open_collider_has_no_inside_count() {
    let dir = tempfile::tempdir().unwrap();
    // A box without its lid under the cloth: open, so no point is inside or outside it.
    std::fs::write(
        dir.path().join("sheet.obj"),
        "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
         f 1 3 2\nf 1 4 3\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n",
    )
    .unwrap();
    let s = scene_in(
        dir.path(),
        &[("mesh = \"sphere_r0.3.obj\"", "mesh = \"sheet.obj\"")],
    );
    let report = dir.path().join("r.json");
    let o = drape(
        &s,
        &dir.path().join("out"),
        &["--report", report.to_str().unwrap()],
    );
    let (summary, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        summary.contains("particles inside objects n/a (open: sheet)"),
        "{summary}"
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert!(r["particles_inside"].is_null(), "{r}");
    assert_eq!(r["open_objects"], serde_json::json!(["sheet"]));
    assert!(r["objects"][0]["particles_inside"].is_null());
    assert_eq!(r["objects"][0]["closed"], false);

    // A closed object still counts.
    let s = scene_in(dir.path(), &[]);
    let (summary, _) = text(&drape(&s, &dir.path().join("out"), &[]));
    assert!(summary.contains("particles inside objects 0;"), "{summary}");
}

#[test]
fn hostile_flags_that_do_nothing_for_the_format_say_so() {
    let dir = tempfile::tempdir().unwrap();
    let input = fixture("scenes/sphere_r0.3.obj");
    let convert = |out: &str, extra: &[&str]| {
        let o = cli("convert", &input, &dir.path().join(out), extra);
        assert!(o.status.success(), "{}", text(&o).1);
        text(&o).1
    };
    let err = convert("x.obj", &["--ascii"]);
    assert!(
        err.contains("warning: --ascii does nothing for obj output (obj is always text)"),
        "{err}"
    );
    let err = convert("x.txt", &["--ascii"]);
    assert!(
        err.contains("--ascii does nothing for triples output"),
        "{err}"
    );
    assert_eq!(convert("x.stl", &["--ascii"]), "");
    let err = convert("y.obj", &["--units", "mm", "--up", "y"]);
    assert!(
        err.contains("--units does nothing without --to-units")
            && err.contains("--up does nothing without --to-up"),
        "{err}"
    );
    assert_eq!(convert("z.obj", &["--units", "mm", "--to-units", "m"]), "");
}
