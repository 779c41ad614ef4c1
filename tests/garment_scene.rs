//! Scenes with a `[[garment]]`: a GarmentCode pattern sewn on the scene's objects by
//! `drapekit drape`, as `drapekit garment` sews it on a body.

mod common;

use drapekit::math::Point3;
use std::path::Path;

/// A folder with the tube pattern (`tube_specification.json`, from `fixtures/garments`) and a
/// snug 48-gon column round it in the pattern's frame (`column.obj`: y up, metres; drapekit's
/// `(x, y, z)` is the file's `(x, z, -y)`).
fn tube_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        common::fixture("garments/tube_specification.json"),
        dir.path().join("tube_specification.json"),
    )
    .unwrap();
    let body = common::cylinder(0.186, 0.5, 1.5, 48);
    common::write_y_up_obj(&body, &dir.path().join("column.obj"));
    dir
}

/// The scene of the tube on the column, with `extra` lines in its `[[garment]]`.
fn tube_scene(extra: &str) -> String {
    format!(
        "[[object]]\nmesh = \"column.obj\"\nup = \"y\"\n\n[[garment]]\npattern = \"tube_specification.json\"\nspacing = 0.02\n{extra}\n"
    )
}

/// Runs drapekit with `args` and returns its JSON report.
fn run_json(args: &[&str]) -> serde_json::Value {
    common::run_json(args).0
}

/// Runs `drape --json` on the scene `text` (written as `scene.toml` into the tube's folder,
/// after `prepare` has had the folder): the folder, the report and stderr.
fn scene_json(
    text: &str,
    prepare: impl FnOnce(&Path),
) -> (tempfile::TempDir, serde_json::Value, String) {
    let dir = tube_folder();
    let d = dir.path();
    prepare(d);
    let scene = d.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let args = ["drape", scene.to_str().unwrap(), "-o"];
    let (report, stderr) =
        common::run_json(&[&args[..], &[d.join("s").to_str().unwrap(), "--json"]].concat());
    (dir, report, stderr)
}

#[test]
fn a_garment_scene_drapes_as_the_garment_command_does() {
    let dir = tube_folder();
    let d = dir.path();
    let scene = d.join("tube.toml");
    std::fs::write(&scene, tube_scene("settle_max = 0.1")).unwrap();
    let (by_scene, by_command) = (d.join("scene_out"), d.join("command_out"));
    let s = run_json(&[
        "drape",
        scene.to_str().unwrap(),
        "-o",
        by_scene.to_str().unwrap(),
        "--json",
    ]);
    let g = run_json(&[
        "garment",
        d.join("tube_specification.json").to_str().unwrap(),
        "--body",
        d.join("column.obj").to_str().unwrap(),
        "-o",
        by_command.to_str().unwrap(),
        "--spacing",
        "0.02",
        "--settle-max",
        "0.1",
        "--json",
    ]);
    // The same garment report: every measure, the stages, the verdict.
    for key in [
        "particles",
        "triangles",
        "seam_springs",
        "garment",
        "panels",
        "open_seams",
        "sew_open_seams",
        "verdict",
        "failed",
        "moving_fraction",
        "thresholds",
        "fit_check",
        "spots",
    ] {
        assert_eq!(s[key], g[key], "{key}");
    }
    for stage in ["sew", "drape"] {
        for key in ["time", "steps", "seam_gap_max", "done", "moving_fraction"] {
            assert_eq!(s[stage][key], g[stage][key], "{stage}.{key}");
        }
    }
    assert!(s["sew"]["done"].as_bool().unwrap(), "{}", s["sew"]);
    assert!(s["garment"]["seam_gap_max_mm"].as_f64().unwrap() <= 1.0);
    assert_eq!(s["garment"]["body_crossing_edges"], 0);
    assert_eq!(s["objects"][0]["name"], "column");
    assert_eq!(s["objects"][0]["closed"], true);
    assert_eq!(common::listing(&by_scene), vec!["column.obj", "tube.obj"]);
    // The same garment mesh: the scene's in its own frame (z up), the command's in the
    // pattern's (y up), both in metres. The same arithmetic in the same order gives the same
    // bits, and the frames differ by a swap and a sign, which are exact: equal to the last bit.
    let read = |p: &Path| drapekit::io::read_mesh(p, &Default::default()).unwrap();
    let (a, b) = (
        read(&by_scene.join("tube.obj")),
        read(&by_command.join("tube.obj")),
    );
    assert_eq!(a.mesh.faces, b.mesh.faces);
    assert_eq!(a.mesh.positions.len(), b.mesh.positions.len());
    assert!(a.mesh.positions.len() > 1000);
    for (p, q) in a.mesh.positions.iter().zip(&b.mesh.positions) {
        assert_eq!(*p, Point3::new(q.x, -q.z, q.y));
    }
    // The flat pattern as `vt`, and a group per panel, in both.
    assert_eq!(a.texcoords, b.texcoords);
    let text = std::fs::read_to_string(by_scene.join("tube.obj")).unwrap();
    assert!(text.contains("g front") && text.contains("g back"));
    // The column as placed, in the scene's frame.
    let column = read(&by_scene.join("column.obj")).mesh;
    let top = column.positions.iter().map(|p| p.z).fold(0.0, f64::max);
    assert!((top - 1.5).abs() < 1e-12, "{top}");
}

#[test]
fn a_garment_scenes_perturb_and_seam_ramp_are_the_commands() {
    let dir = tube_folder();
    let d = dir.path();
    let scene = d.join("tube.toml");
    std::fs::write(
        &scene,
        tube_scene("settle_max = 0.1\nperturb = 3\nseam_ramp = 2.0"),
    )
    .unwrap();
    let (by_scene, by_command) = (d.join("scene_out"), d.join("command_out"));
    let args = [
        "drape",
        scene.to_str().unwrap(),
        "-o",
        by_scene.to_str().unwrap(),
    ];
    let s = run_json(&[&args[..], &["--json"]].concat());
    let pattern = d.join("tube_specification.json");
    let body = d.join("column.obj");
    let mut args = vec!["garment", pattern.to_str().unwrap(), "--body"];
    args.extend([body.to_str().unwrap(), "-o", by_command.to_str().unwrap()]);
    args.extend(["--spacing", "0.02", "--settle-max", "0.1", "--json"]);
    let plain = run_json(&args);
    args.extend(["--perturb", "3", "--seam-ramp", "2"]);
    let g = run_json(&args);
    let read = |p: &Path| {
        drapekit::io::read_mesh(p, &Default::default())
            .unwrap()
            .mesh
    };
    let (a, b) = (
        read(&by_scene.join("tube.obj")),
        read(&by_command.join("tube.obj")),
    );
    // The same perturbed start, to the bit (the frames differ by an exact swap and sign).
    for (p, q) in a.positions.iter().zip(&b.positions) {
        assert_eq!(*p, Point3::new(q.x, -q.z, q.y));
    }
    // Both ramped the seams over the drape's first checks; the plain run did not.
    assert_eq!(s["seam_ramp"], 2.0);
    assert_eq!(s["drape"]["ramp_checks"], g["drape"]["ramp_checks"]);
    assert!(
        g["drape"]["ramp_checks"].as_u64().unwrap() > 0,
        "{}",
        g["drape"]
    );
    assert_eq!(plain["drape"]["ramp_checks"], 0);
    // And not the plain run's.
    assert_ne!(plain["drape"], g["drape"]);
}

#[test]
fn a_garment_scene_in_centimetres_places_the_pattern_by_its_keys() {
    // The column moved 30 cm along x and the tube with it (`translation`, in the scene's
    // centimetres), turned a quarter about the vertical (`rotation`: the tube is round, the
    // column a 48-gon turned by 12 of its facets, so both are the same shape as before).
    // Sewing closes the seams round the moved column, with nothing through it.
    let dir = tube_folder();
    let d = dir.path();
    let scene = d.join("moved.toml");
    let text = "units = \"cm\"\n[[object]]\nmesh = \"column.obj\"\nup = \"y\"\nscale = 100\ntranslate = [30, 0, 0]\n\n[[garment]]\npattern = \"tube_specification.json\"\nspacing = 2\ntranslation = [30, 0, 0]\nrotation = 90\nsettle_max = 0.1\n";
    std::fs::write(&scene, text).unwrap();
    let out = d.join("out");
    let r = run_json(&[
        "drape",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--glb",
        "--preview",
        "--json",
    ]);
    assert_eq!(
        common::listing(&out),
        ["column.obj", "moved.glb", "preview.png", "tube.obj"]
    );
    assert_eq!(r["units"], "cm");
    assert!((r["spacing"].as_f64().unwrap() - 2.0).abs() < 1e-12);
    assert!(r["sew"]["done"].as_bool().unwrap(), "{}", r["sew"]);
    assert_eq!(r["garment"]["body_crossing_edges"], 0, "{}", r["garment"]);
    assert_eq!(r["garment"]["particles_inside"], 0, "{}", r["garment"]);
    // Written in centimetres: the tube round the column's axis at x = 30 cm.
    let mesh = drapekit::io::read_mesh(&out.join("tube.obj"), &Default::default())
        .unwrap()
        .mesh;
    let n = mesh.positions.len() as f64;
    let c = mesh
        .positions
        .iter()
        .fold([0.0; 2], |s, p| [s[0] + p.x / n, s[1] + p.y / n]);
    // Within a spacing of the axis: the tube is as round as the column (2 cm).
    assert!((c[0] - 30.0).abs() < 2.0 && c[1].abs() < 2.0, "{c:?}");
    // Turned a quarter: the front panel (the back's particles come first) from in front of
    // the axis (-y) to its right (+x). A half tube's centroid is 2 r / pi (12 cm) off the
    // axis; half of that tells the quarter turn from none.
    let back = r["panels"][0]["particles"].as_u64().unwrap() as usize;
    assert_eq!(r["panels"][0]["name"], "back");
    let front = &mesh.positions[back..];
    let m = front.len() as f64;
    let f = front
        .iter()
        .fold([0.0; 2], |s, p| [s[0] + p.x / m, s[1] + p.y / m]);
    assert!(
        f[0] - 30.0 > 6.0 && f[1].abs() < 6.0,
        "front panel at {f:?}"
    );
    // The glTF file: the column and both panels, in metres.
    let glb = drapekit::io::read_mesh(&out.join("moved.glb"), &Default::default())
        .unwrap()
        .mesh;
    let column = drapekit::io::read_mesh(&out.join("column.obj"), &Default::default())
        .unwrap()
        .mesh;
    assert_eq!(
        glb.positions.len(),
        column.positions.len() + mesh.positions.len()
    );
    let x_max = glb.positions.iter().map(|p| p.x).fold(0.0, f64::max);
    assert!((x_max - 0.3).abs() < 0.25, "{x_max} m");
    let radius = mesh
        .positions
        .iter()
        .map(|p| ((p.x - 30.0).powi(2) + p.y.powi(2)).sqrt())
        .fold(f64::INFINITY, f64::min);
    assert!(radius > 18.6, "outside the column: {radius} cm");
}

#[test]
fn a_garment_scene_runs_the_fit_check_on_its_objects_where_the_garment_is_placed() {
    // The tube (120 cm round) and a column 157 cm round: both ends are too short, as the
    // garment command says of the same files. The scene lifts the column and the tube 50 cm
    // and turns the tube a quarter: the same rings, the same girths, 50 cm higher.
    let text = "[[object]]\nmesh = \"fat.obj\"\nup = \"y\"\ntranslate = [0, 0, 0.5]\n\n[[garment]]\npattern = \"tube_specification.json\"\nspacing = 0.05\ntranslation = [0, 0, 0.5]\nrotation = 90\nsew_max = 0.02\nsettle_max = 0.02\n";
    let fat = common::cylinder(0.25, 0.5, 1.5, 48);
    let (dir, s, stderr) = scene_json(text, |d| common::write_y_up_obj(&fat, &d.join("fat.obj")));
    let d = dir.path();
    let g = run_json(&[
        "garment",
        d.join("tube_specification.json").to_str().unwrap(),
        "--body",
        d.join("fat.obj").to_str().unwrap(),
        "-o",
        d.join("g").to_str().unwrap(),
        "--spacing",
        "0.05",
        "--sew-max",
        "0.02",
        "--settle-max",
        "0.02",
        "--json",
    ]);
    let (fs, fg) = (&s["fit_check"], &g["fit_check"]);
    assert_eq!(fs["too_short"], 2, "{fs}");
    assert_eq!(fg["too_short"], 2, "{fg}");
    // Two warnings on stderr before the run, one per end.
    assert_eq!(stderr.matches("warning: fit check").count(), 2, "{stderr}");
    // The tube is placed round the column: no placement warning.
    assert_eq!(s["warnings"], serde_json::json!([]), "{}", s["warnings"]);
    let rings = |f: &serde_json::Value| f["rings"].as_array().unwrap().clone();
    assert_eq!(rings(fs).len(), 2);
    let num = |v: &serde_json::Value| v.as_f64().unwrap();
    for (a, b) in rings(fs).iter().zip(&rings(fg)) {
        assert_eq!(a["edges"], b["edges"]);
        assert_eq!(a["fits"], false);
        for k in 0..2 {
            let (za, zb) = (num(&a["height_m"][k]), num(&b["height_m"][k]));
            assert!((za - zb - 0.5).abs() < 1e-9, "{za} {zb}");
        }
        // The 48-gon turned a quarter (12 facets) about its axis: the same girth.
        for k in 0..2 {
            let (ga, gb) = (num(&a["body_girth_m"][k]), num(&b["body_girth_m"][k]));
            assert!((ga - gb).abs() < 1e-9, "{ga} {gb}");
        }
        let girth = 96.0 * 0.25 * (std::f64::consts::PI / 48.0).sin();
        assert!((num(&a["body_girth_m"][0]) - girth).abs() < 1e-6, "{a}");
    }
}

#[test]
fn a_garment_placed_beside_the_objects_is_warned_of_before_the_run() {
    // The column moved 2 m along x, the tube left where the pattern puts it.
    let text = "[[object]]\nmesh = \"column.obj\"\nup = \"y\"\ntranslate = [2, 0, 0]\n\n[[garment]]\npattern = \"tube_specification.json\"\nspacing = 0.05\nsew_max = 0.02\nsettle_max = 0.02\n";
    let (_dir, s, stderr) = scene_json(text, |_| {});
    let w = s["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    let w = w[0].as_str().unwrap();
    assert!(w.contains("not round the scene's objects"), "{w}");
    // The objects' span in the pattern's frame: the column's x from 2 - 0.186 to 2 + 0.186.
    assert!(w.contains("the objects x 1.814 to 2.186"), "{w}");
    assert!(stderr.contains("warning:") && stderr.contains("translation and rotation"));
}

/// Runs `drape` on the scene `text`, written as `bad.toml` into `dir` beside the tube's files,
/// with `flags`, expecting a refusal before any work (status 1, nothing written): its message.
fn refused_in(dir: &Path, text: &str, flags: &[&str]) -> String {
    let scene = dir.join("bad.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let mut args = vec![
        "drape",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(flags);
    let o = common::run(&args);
    let (_, stderr) = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{text}: {stderr}");
    assert!(!out.exists(), "nothing written: {stderr}");
    stderr
}

/// [`refused_in`] for the tube scene with its `[[garment]]` given `garment` and the rest of
/// the file `more`.
fn refused(garment: &str, more: &str, flags: &[&str]) -> String {
    let dir = tube_folder();
    refused_in(dir.path(), &format!("{}{more}", tube_scene(garment)), flags)
}

#[test]
fn bad_garment_keys_are_refused_by_key_before_work() {
    let cases: &[(&str, &str, &str)] = &[
        (
            "pattern = \"no_such_specification.json\"",
            "key 'garment.pattern'",
            "no_such_specification.json does not exist",
        ),
        (
            "spacing = 0.5",
            "key 'garment.spacing'",
            "0.002 to 0.1 m, got 0.5",
        ),
        (
            "fabric = \"unobtainium\"",
            "key 'garment.fabric'",
            "unknown fabric 'unobtainium'",
        ),
        (
            "sew_max = -1",
            "key 'garment.sew_max'",
            "positive number of simulated seconds",
        ),
        (
            "settle_max = 4000",
            "key 'garment.settle_max'",
            "at most 3600",
        ),
        ("friction = -0.5", "key 'garment.friction'", "0 or more"),
        (
            "body_clearance = -1",
            "key 'garment.body_clearance'",
            "0 or more",
        ),
        (
            "cloth_friction = -1",
            "key 'garment.cloth_friction'",
            "0 or more",
        ),
        ("rotation = nan", "key 'garment.rotation'", "finite angle"),
        (
            "hold_waist = \"hips\"",
            "key 'garment.hold_waist'",
            "expected \"off\", \"auto\" or a height",
        ),
        (
            "hold_waist = inf",
            "key 'garment.hold_waist'",
            "must be a finite height",
        ),
        (
            "seam_ramp = 1",
            "key 'garment.seam_ramp'",
            "must be a factor above 1",
        ),
        ("seam_ramp = \"off\"", "seam_ramp", "expected f64"),
        ("perturb = -1", "perturb = -1", "expected u64"),
        ("perturb = 0.5", "perturb = 0.5", "expected u64"),
        ("size = 40", "unknown field `size`", "expected one of"),
    ];
    for (line, key, what) in cases {
        // A key the tube's scene has (pattern, spacing) is replaced, another added.
        let name = line.split(' ').next().unwrap();
        let plain = tube_scene("");
        let text = match plain.lines().find(|l| l.starts_with(&format!("{name} = "))) {
            Some(old) => plain.replace(old, line),
            None => tube_scene(line),
        };
        let dir = tube_folder();
        let stderr = refused_in(dir.path(), &text, &[]);
        assert!(
            stderr.contains(key) && stderr.contains(what),
            "{line}: {stderr}"
        );
    }
}

#[test]
fn a_patterns_own_errors_are_refused_under_its_key_and_file_name() {
    // The tube's second stitch sews the back's edge 9, which it does not have.
    let dir = tube_folder();
    let d = dir.path();
    let text = std::fs::read_to_string(d.join("tube_specification.json")).unwrap();
    let bad = text.replace(
        r#"{"panel": "back", "edge": 1}"#,
        r#"{"panel": "back", "edge": 9}"#,
    );
    assert_ne!(bad, text);
    std::fs::write(d.join("broken_specification.json"), bad).unwrap();
    let toml = tube_scene("").replace("tube_specification.json", "broken_specification.json");
    let stderr = refused_in(d, &toml, &[]);
    assert!(
        stderr.contains("bad.toml: key 'garment.pattern': ")
            && stderr.contains("broken_specification.json: 1 problem"),
        "{stderr}"
    );
    assert!(stderr.contains("back") && stderr.contains('9'), "{stderr}");
}

#[test]
fn what_a_garment_scene_does_not_support_is_refused_by_key() {
    let piece = "\n[[piece]]\noutline = [[0, 0], [1, 0], [1, 1]]\nspacing = 0.1\n";
    let cases: &[(&str, &str, &str)] = &[
        (piece, "key 'piece'", "not supported with a [[garment]]"),
        (
            "\n[solver]\nsteps = 100\n",
            "key 'solver.steps'",
            "the garment's stages end its run",
        ),
        (
            "\n[solver]\nintegrator = \"leapfrog\"\n",
            "key 'solver.integrator'",
            "leapfrog: garments step at 10 ms",
        ),
        (
            "\n[output]\nframes = 10\n",
            "key 'output.frames'",
            "writes no frames",
        ),
        (
            "\n[report]\ndisc_radius = 0.09\n",
            "key 'report.disc_radius'",
            "for a single piece",
        ),
        (
            "\n[[garment]]\npattern = \"tube_specification.json\"\n",
            "key 'garment'",
            "2 [[garment]] tables: a scene sews one garment",
        ),
    ];
    for (more, key, what) in cases {
        let stderr = refused("", more, &[]);
        assert!(
            stderr.contains(key) && stderr.contains(what),
            "{more}: {stderr}"
        );
    }
    // Gravity goes first in the file (a key of the top table).
    let dir = tube_folder();
    let text = format!("gravity = [0, 0, -1]\n{}", tube_scene(""));
    let stderr = refused_in(dir.path(), &text, &[]);
    assert!(
        stderr.contains("key 'gravity'") && stderr.contains("not supported"),
        "{stderr}"
    );
    // No object to sew it on.
    let bare = tube_scene("").replace("[[object]]\nmesh = \"column.obj\"\nup = \"y\"\n", "");
    let stderr = refused_in(dir.path(), &bare, &[]);
    assert!(
        stderr.contains("key 'object'") && stderr.contains("the body"),
        "{stderr}"
    );
    // --resume: a garment's run keeps no checkpoint.
    let stderr = refused("", "", &["--resume"]);
    assert!(
        stderr.contains("--resume") && stderr.contains("no checkpoint"),
        "{stderr}"
    );
}

#[test]
fn a_panel_facing_into_the_objects_is_refused_under_the_patterns_key() {
    // The tube's back panel without its half turn faces the column.
    let dir = tube_folder();
    let d = dir.path();
    let text = std::fs::read_to_string(d.join("tube_specification.json")).unwrap();
    let flipped = text.replace(
        r#""translation": [0, 80, -30], "rotation": [0, 180, 0]"#,
        r#""translation": [0, 80, -30], "rotation": [0, 0, 0]"#,
    );
    assert_ne!(flipped, text);
    std::fs::write(d.join("tube_specification.json"), flipped).unwrap();
    let stderr = refused_in(d, &tube_scene(""), &[]);
    assert!(
        stderr.contains("bad.toml: key 'garment.pattern': a panel is facing into the body")
            && stderr.contains("back (180 degrees"),
        "{stderr}"
    );
}

#[test]
fn a_garment_scene_moves_a_panel_placed_through_its_object_unless_told_to_keep_it() {
    // The column moved 12.25 cm towards the back pokes 2.25 cm through the tube's back panel.
    let through = |d: &Path| {
        let mut body = common::cylinder(0.2, 0.5, 1.5, 48);
        for p in &mut body.positions {
            p.y += 0.1225;
        }
        common::write_y_up_obj(&body, &d.join("column.obj"));
    };
    let quick = "sew_max = 0.02\nsettle_max = 0.02";
    let (_d, r, _) = scene_json(&tube_scene(quick), through);
    let m = &r["panels_moved_out"];
    assert_eq!(m.as_array().map(Vec::len), Some(1), "{m}");
    assert_eq!(m[0]["panel"], "back");
    assert!(
        (m[0]["distance"].as_f64().unwrap() - 0.03).abs() < 1e-12,
        "{m}"
    );
    let keep = format!("{quick}\nkeep_placement = true");
    let (_d, r, _) = scene_json(&tube_scene(&keep), through);
    assert_eq!(r["panels_moved_out"], serde_json::json!([]));
}

#[test]
fn a_garment_scene_takes_the_garments_bending_hessian_unless_its_solver_names_one() {
    use drapekit::cloth::integrate::direct::BendingHessian;
    use drapekit::garment::drape::GARMENT_BENDING_HESSIAN;
    let dir = tube_folder();
    let hessian = |extra: &str| {
        let scene = dir.path().join("scene.toml");
        std::fs::write(&scene, tube_scene("") + extra).unwrap();
        let s = drapekit::scene::read(&scene).unwrap();
        s.garment.unwrap().settings.solver.bending_hessian
    };
    assert_eq!(hessian(""), GARMENT_BENDING_HESSIAN);
    for h in [BendingHessian::Exact, BendingHessian::Lumped] {
        assert_eq!(
            hessian(&format!("[solver]\nbending_hessian = \"{h}\"\n")),
            h
        );
    }
    // A flat piece's scene keeps the linearised step unless asked.
    let text = std::fs::read_to_string(common::fixture("scenes/hanging_ribbon.toml")).unwrap();
    let s = drapekit::scene::parse(&text, &common::fixture("scenes/hanging_ribbon.toml")).unwrap();
    assert_eq!(s.solver.bending_hessian, BendingHessian::Exact);
}

#[test]
fn a_garment_scene_without_an_integrator_takes_implicit_eulers_keys_and_refuses_projective_ones() {
    let dir = tube_folder();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, tube_scene("") + "[solver]\nnewton_iterations = 2\n").unwrap();
    let s = drapekit::scene::read(&scene).unwrap();
    assert_eq!(s.garment.unwrap().settings.solver.newton_iterations, 2);
    std::fs::write(&scene, tube_scene("") + "[solver]\nchebyshev = 0.9\n").unwrap();
    let e = drapekit::scene::read(&scene).unwrap_err().to_string();
    assert!(
        e.contains(
            "applies to integrator = \"projective-dynamics\" only (this scene uses implicit-euler)"
        ),
        "{e}"
    );
}
