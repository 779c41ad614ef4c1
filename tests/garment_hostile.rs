//! Hostile GarmentCode patterns: each defect the pattern hunt found, refused with a clear
//! error or handled, never a panic.

mod common;

use drapekit::garment::assemble::{assemble, AssembleOptions};
use drapekit::garment::{parse, Problem, SpecError};
use std::path::Path;

/// The tube fixture's text.
fn tube() -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/garments/tube_specification.json");
    std::fs::read_to_string(p).unwrap()
}

/// The problems the reader finds in `text` (it must refuse it).
fn problems(text: &str) -> Vec<Problem> {
    match parse(text, Path::new("p.json")) {
        Err(SpecError::Invalid { problems, .. }) => problems,
        other => panic!("expected an invalid pattern, got {other:?}"),
    }
}

#[test]
fn a_vertex_at_minus_zero_is_sewn_like_one_at_zero() {
    // JSON writers (Python's among them) write a negative zero as -0.0; the cloth's outline
    // particle came back as +0 and the lookup of the sample's particle panicked.
    let text = tube().replacen("[[-30, 0], [30, 0]", "[[-30, -0.0], [30, -0.0]", 1);
    assert_ne!(text, tube());
    let pattern = parse(&text, Path::new("p.json")).unwrap();
    let opts = AssembleOptions {
        spacing: 0.04,
        ..AssembleOptions::default()
    };
    let a = assemble(&pattern, &opts).unwrap();
    let plain = assemble(&parse(&tube(), Path::new("p.json")).unwrap(), &opts).unwrap();
    assert_eq!(a.seams, plain.seams);
    assert_eq!(a.edge_particles, plain.edge_particles);
}

/// A pattern of one panel, a regular `n`-gon of radius 40 cm, with vertices `swap` swapped
/// (a crossing) when given.
fn ngon_pattern(n: usize, swap: Option<(usize, usize)>) -> String {
    let mut v: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            [40.0 * a.cos(), 40.0 * a.sin()]
        })
        .collect();
    if let Some((a, b)) = swap {
        v.swap(a, b);
    }
    let edges: Vec<String> = (0..n)
        .map(|i| format!(r#"{{"endpoints": [{i}, {}]}}"#, (i + 1) % n))
        .collect();
    format!(
        r#"{{"pattern": {{"panels": {{"front": {{"vertices": {}, "edges": [{}],
        "translation": [0, 120, 30], "rotation": [0, 0, 0]}}}}, "stitches": []}},
        "properties": {{"curvature_coords": "relative", "units_in_meter": 100}}}}"#,
        serde_json::to_string(&v).unwrap(),
        edges.join(", ")
    )
}

#[test]
fn a_panel_of_300000_vertices_is_checked_for_crossings_in_seconds() {
    // Every pair of the outline's segments was tested: 4.5e10 tests, minutes of a hang (a
    // 1e6-vertex panel: hours). The sweep answers in O(n log n).
    let start = std::time::Instant::now();
    let n = 300_000;
    assert!(parse(&ngon_pattern(n, None), Path::new("p.json")).is_ok());
    let p = problems(&ngon_pattern(n, Some((1000, 1001))));
    assert!(
        matches!(&p[..], [Problem::SelfCrossing { panel, edge_a, edge_b }]
            if panel == "front" && *edge_a >= 999 && *edge_b <= 1001),
        "{p:?}"
    );
    let t = start.elapsed().as_secs_f64();
    assert!(t < 30.0, "{t} s");
}

#[test]
fn ten_thousand_panels_are_refused_by_their_particles_together_before_any_is_built() {
    // Each 60 x 40 cm panel is about 200 particles at 4 cm, well within a piece's limit; all
    // 10,000 were built (2 million particles) and the solver's allocation of 8 GB aborted.
    let panel = r#"{"vertices": [[-30, 0], [30, 0], [30, 40], [-30, 40]],
        "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}],
        "translation": [0, 80, 30], "rotation": [0, 0, 0]}"#;
    let panels: Vec<String> = (0..10_000).map(|i| format!("\"p{i}\": {panel}")).collect();
    let text = format!(
        r#"{{"pattern": {{"panels": {{{}}}, "stitches": []}},
        "properties": {{"curvature_coords": "relative", "units_in_meter": 100}}}}"#,
        panels.join(", ")
    );
    let pattern = parse(&text, Path::new("p.json")).unwrap();
    let opts = AssembleOptions {
        spacing: 0.04,
        ..AssembleOptions::default()
    };
    let start = std::time::Instant::now();
    let errors = assemble(&pattern, &opts).expect_err("refused");
    assert!(start.elapsed().as_secs_f64() < 10.0);
    let message = errors[0].to_string();
    assert!(
        message.starts_with("the pattern's 10000 panel(s) give about ")
            && message.contains("a garment has at most 1000000"),
        "{message}"
    );
}

#[test]
fn a_far_vertex_no_edge_uses_is_named_as_far_not_every_edge_as_zero_length() {
    // The zero-length test measured edges against the farthest vertex, used or not: one at
    // 1e300 made each of the four edges "zero length" and hid the vertex.
    let text = tube().replacen("[-30, 40]]", "[-30, 40], [1e300, 1e300]]", 1);
    let p = problems(&text);
    assert!(
        !p.iter().any(|p| matches!(p, Problem::ZeroLength { .. })),
        "{p:?}"
    );
    assert!(
        matches!(&p[..], [Problem::PanelSize { panel, .. }] if panel == "front"),
        "{p:?}"
    );
}

#[test]
fn a_loop_that_goes_round_twice_is_refused_by_the_reader() {
    // Eight edges twice round the square: no edge ends where the next does not start, and
    // no segment properly crosses another, so the reader let it through and the cloth
    // refused it as an outline crossing itself, without the file's name.
    let edges = r#"[{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]"#;
    let twice = r#"[{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}, {"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]"#;
    let text = tube().replacen(edges, twice, 1);
    assert_ne!(text, tube());
    let p = problems(&text);
    assert_eq!(p.len(), 4, "{p:?}");
    assert_eq!(
        p[0],
        Problem::VertexTwice {
            panel: "front".into(),
            vertex: 0,
            first: 0,
            second: 4
        }
    );
    assert!(p[0]
        .to_string()
        .contains("edges 0 and 4 both start at vertex 0"));
}

#[test]
fn a_panel_with_no_area_is_refused_by_the_reader() {
    // Four vertices on a line: the reader saw no proper crossing and passed it, and the cloth
    // refused it as an outline crossing itself; 1e-6 cm tall, it reached the solver, which
    // failed with a matrix "not positive definite".
    for vertices in [
        "[[0, 0], [10, 0], [20, 0], [30, 0]]",
        "[[-30, 0], [30, 0], [30, 1e-6], [-30, 1e-6]]",
    ] {
        let text = tube().replacen("[[-30, 0], [30, 0], [30, 40], [-30, 40]]", vertices, 1);
        let p = problems(&text);
        assert!(
            matches!(&p[..], [Problem::NoArea { panel, square_metres }]
                if panel == "front" && *square_metres < 1e-6),
            "{vertices}: {p:?}"
        );
    }
    // Half a millimetre by 60 cm is cloth.
    let thin = "[[-30, 0], [30, 0], [30, 0.05], [-30, 0.05]]";
    let text = tube().replacen("[[-30, 0], [30, 0], [30, 40], [-30, 40]]", thin, 1);
    assert!(parse(&text, Path::new("p.json")).is_ok());
}

#[test]
fn a_panel_name_given_twice_is_refused_not_dropped() {
    // JSON keeps the last of two keys: the first "front" was dropped without a word (here the
    // stitches to "back" then named a panel that "does not exist"; without stitches a panel
    // was silently lost).
    let text = tube().replacen("\"back\":", "\"front\":", 1);
    match parse(&text, Path::new("p.json")) {
        Err(SpecError::Shape { message, line, .. }) => {
            assert!(
                message.contains("panel 'front' is given twice in pattern.panels"),
                "{message}"
            );
            assert_eq!(line, 5);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_panel_name_with_a_line_break_is_refused() {
    // "back\nv 1 2 3" was written into the garment's OBJ as a group line and a vertex line.
    let text = tube().replace("\"back\"", "\"back\\nv 1 2 3\"");
    let p = problems(&text);
    assert_eq!(
        p,
        vec![Problem::ControlInName {
            panel: "back\nv 1 2 3".into()
        }]
    );
    assert!(p[0].to_string().contains("control character"));
}

#[test]
fn a_stitch_element_of_the_wrong_shape_says_what_a_stitch_element_is() {
    // A negative edge index said "data did not match any variant of untagged enum
    // RawStitchPart".
    for (bad, shown) in [
        (
            r#"{"panel": "back", "edge": -1}"#,
            r#"{"edge":-1,"panel":"back"}"#,
        ),
        (r#"{"panel": "back"}"#, r#"{"panel":"back"}"#),
        ("5", "not 5"),
    ] {
        let text = tube().replacen(r#"{"panel": "back", "edge": 3}"#, bad, 1);
        match parse(&text, Path::new("p.json")) {
            Err(SpecError::Shape { message, .. }) => assert!(
                message.starts_with(r#"a stitch element is {"panel": NAME, "edge": INDEX}"#)
                    && message.contains(shown),
                "{bad}: {message}"
            ),
            other => panic!("{bad}: {other:?}"),
        }
    }
}

/// `garment` on `pattern` into `out` with `--report report` and a body that does not exist:
/// whether it succeeded, and its stderr.
fn garment_with_report(pattern: &str, out: &str, report: &str) -> (bool, String) {
    let body = "no_such_body.obj";
    let run = common::run(&[
        "garment", pattern, "--body", body, "-o", out, "--report", report,
    ]);
    (run.status.success(), common::text(&run).1)
}

#[test]
fn a_report_over_the_pattern_is_refused_before_any_work() {
    // --report naming the pattern was refused only when the report was written, after the
    // whole run, with the garment already in the output folder ("out was written, the
    // report was not").
    let dir = tempfile::tempdir().unwrap();
    let pattern = dir.path().join("p.json");
    std::fs::write(&pattern, tube()).unwrap();
    let out = dir.path().join("out");
    let (p, o) = (pattern.to_str().unwrap(), out.to_str().unwrap());
    let (ok, stderr) = garment_with_report(p, o, p);
    assert!(!ok);
    assert!(
        stderr.starts_with("error: refusing to write") && stderr.contains("it is the input file"),
        "{stderr}"
    );
    assert!(!out.exists());
    assert_eq!(std::fs::read_to_string(&pattern).unwrap(), tube());
    let (ok, stderr) = garment_with_report(p, o, o);
    assert!(!ok && stderr.contains("over the output folder"), "{stderr}");
}

#[test]
fn a_panel_of_100000_short_edges_is_refused_by_its_crowded_outline() {
    // Each 0.025 mm edge took a particle of its own: 100,000 particles on a 2.5 m outline
    // that needs 63 at 4 cm, and the solver's allocation of 8 GB aborted the run.
    let pattern = parse(&ngon_pattern(100_000, None), Path::new("p.json")).unwrap();
    let opts = AssembleOptions {
        spacing: 0.04,
        ..AssembleOptions::default()
    };
    let errors = assemble(&pattern, &opts).expect_err("refused");
    let message = errors[0].to_string();
    assert!(
        message.starts_with("panel 'front': its outline takes 100000 particles where its 2.513 m at spacing 0.04 m needs about 63"),
        "{message}"
    );
    // The real patterns, gathers and short edges included, are far from it at 2 mm (0.2 in
    // their centimetres): samples against twice the need plus 1000.
    let Some(data) = common::realdata() else {
        return;
    };
    for file in std::fs::read_dir(data.join("patterns")).unwrap() {
        let path = file.unwrap().path();
        if path.extension().is_none_or(|e| e != "json") {
            continue;
        }
        let p = drapekit::garment::read(&path).unwrap();
        let counts = drapekit::garment::sample::edge_segments(&p, 0.2);
        for s in drapekit::garment::sample::sample_all(&p, &counts) {
            let n = s.points.len();
            let perimeter: f64 = (0..n)
                .map(|i| (s.points[(i + 1) % n] - s.points[i]).norm())
                .sum();
            let needed = (perimeter / 0.2).ceil() as usize;
            assert!(n <= 2 * needed, "{}: {n} {needed}", path.display());
        }
    }
}

#[test]
fn a_list_of_the_wrong_length_says_how_many_it_has() {
    // A 3D vertex, a third endpoint or a 2-number translation said "trailing characters" (or
    // "invalid length") at a column.
    for (from, to, expected) in [
        (
            "[[-30, 0], [30, 0], [30, 40], [-30, 40]]",
            "[[-30, 0, 0], [30, 0], [30, 40], [-30, 40]]",
            "vertex 0 has 3 coordinate(s); a panel's vertex is [x, y] (2D)",
        ),
        (
            r#"{"endpoints": [0, 1]}"#,
            r#"{"endpoints": [0, 1, 2]}"#,
            "expected a list of 2 numbers here, got 3",
        ),
        (
            "[0, 80, 30]",
            "[0, 80]",
            "expected a list of 3 numbers here, got 2",
        ),
    ] {
        let text = tube().replacen(from, to, 1);
        assert_ne!(text, tube());
        match parse(&text, Path::new("p.json")) {
            Err(SpecError::Shape { message, .. }) => {
                assert!(message.starts_with(expected), "{message}")
            }
            other => panic!("{to}: {other:?}"),
        }
    }
}

#[test]
fn a_scenes_report_over_an_input_is_refused_before_any_work() {
    // drapekit drape with a [[garment]] and --report naming the scene (or the pattern) sewed
    // and draped the garment, wrote it, and only then refused the report.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tube_specification.json"), tube()).unwrap();
    common::write_y_up_obj(
        &common::cylinder(0.186, 0.5, 1.5, 48),
        &d.join("column.obj"),
    );
    let scene = d.join("scene.toml");
    std::fs::write(
        &scene,
        "[[object]]\nmesh = \"column.obj\"\nup = \"y\"\n\n[[garment]]\npattern = \"tube_specification.json\"\nspacing = 0.04\nsew_max = 0.2\nsettle_max = 0.1\n",
    )
    .unwrap();
    let out = d.join("out");
    for report in [scene.clone(), d.join("tube_specification.json")] {
        let (s, o, r) = (
            scene.to_str().unwrap(),
            out.to_str().unwrap(),
            report.to_str().unwrap(),
        );
        let run = common::run(&["drape", s, "-o", o, "--report", r]);
        let (_, stderr) = common::text(&run);
        assert!(!run.status.success());
        assert!(stderr.contains("it is the input file"), "{stderr}");
        assert!(!out.exists(), "{stderr}");
    }
}

#[test]
fn an_arc_of_a_radius_far_beyond_its_chord_is_the_nearly_straight_edge_it_says() {
    // The front's edge 1 runs from (30, 0) to (30, 40). At radius 1e20 the arc's centre,
    // 1e20 away, rounded the chord's x = 30 off and its middle was drawn 30 cm away, at x = 0,
    // a wrong garment sewn without a word; at 1e300 r^2 overflowed, every point was NaN, and
    // the cloth refused "outline point 17", without the file's name.
    for radius in ["1e20", "1e300", "1.7976931348623157e308"] {
        for right in [0, 1] {
            let curved = format!(
                r#"{{"endpoints": [1, 2], "curvature": {{"type": "circle", "params": [{radius}, 0, {right}]}}}}"#
            );
            let text = tube().replacen(r#"{"endpoints": [1, 2]}"#, &curved, 1);
            assert_ne!(text, tube());
            let pattern = parse(&text, Path::new("p.json")).unwrap();
            let front = &pattern.panels[pattern.panel_index("front").unwrap()];
            let mid = front.edges[1].point(&front.vertices, 0.5);
            let off = (mid - drapekit::math::Point2::new(30.0, 20.0)).norm();
            assert!(off < 1e-9, "{radius}: {mid}");
            let length = front.edges[1].length(&front.vertices);
            assert!((length - 40.0).abs() < 1e-9, "{radius}: {length}");
            let opts = AssembleOptions {
                spacing: 0.04,
                ..AssembleOptions::default()
            };
            let a = assemble(&pattern, &opts).unwrap();
            let plain = assemble(&parse(&tube(), Path::new("p.json")).unwrap(), &opts).unwrap();
            for (piece, straight) in a.pieces.iter().zip(&plain.pieces) {
                assert_eq!(piece.3.len(), straight.3.len(), "{radius}");
                for (p, q) in piece.3.iter().zip(&straight.3) {
                    assert!((p - q).norm() < 1e-9, "{radius}: {p} against {q}");
                }
            }
        }
    }
}

#[test]
fn an_empty_panel_name_is_refused() {
    // "" was read as a panel and sewn (stitches named it, the OBJ had a group "g " of no
    // name); a name of spaces is no better.
    for name in ["", "   "] {
        let text = tube().replace("\"back\"", &format!("\"{name}\"")).replacen(
            "\"back\":",
            &format!("\"{name}\":"),
            1,
        );
        let p = problems(&text);
        assert_eq!(
            p,
            vec![Problem::EmptyName { panel: name.into() }],
            "{name:?}"
        );
        assert!(p[0].to_string().contains("its name is empty"), "{}", p[0]);
    }
}

#[test]
fn a_rotation_beyond_a_thousand_turns_is_refused() {
    // 1e300 degrees was taken as whatever angle its rounding made it.
    for (rotation, axis) in [
        ("[1e300, 0, 0]", 0),
        ("[0, -360000.5, 0]", 1),
        ("[0, 0, 1e20]", 2),
    ] {
        let text = tube().replacen("[0, 0, 0]", rotation, 1);
        assert_ne!(text, tube());
        let p = problems(&text);
        assert!(
            matches!(&p[..], [Problem::RotationTooLarge { panel, axis: a, .. }]
                if panel == "front" && *a == axis),
            "{rotation}: {p:?}"
        );
        assert!(
            p[0].to_string().starts_with("panel 'front': rotation["),
            "{}",
            p[0]
        );
    }
    // Two turns the other way and a thousand turns are angles.
    for rotation in ["[0, -720, 0]", "[360000, 0, 0]"] {
        let text = tube().replacen("[0, 0, 0]", rotation, 1);
        assert!(parse(&text, Path::new("p.json")).is_ok(), "{rotation}");
    }
}

#[test]
fn right_wrong_given_twice_is_refused_with_its_stitch() {
    let once = r#"[{"panel": "front", "edge": 1}, {"panel": "back", "edge": 3}, "right_wrong"]"#;
    let twice = r#"[{"panel": "front", "edge": 1}, {"panel": "back", "edge": 3}, "right_wrong", "right_wrong"]"#;
    let plain = r#"[{"panel": "front", "edge": 1}, {"panel": "back", "edge": 3}]"#;
    assert!(parse(&tube().replacen(plain, once, 1), Path::new("p.json")).is_ok());
    let text = tube().replacen(plain, twice, 1);
    assert_ne!(text, tube());
    let p = problems(&text);
    assert_eq!(p.len(), 1, "{p:?}");
    assert_eq!(
        p[0].to_string(),
        "stitch 0: \"right_wrong\" is given twice; it may be given once"
    );
}

#[test]
fn a_key_given_twice_is_refused_where_it_is() {
    // serde_json's Value keeps the last of two keys: a curvature of "type" circle then cubic
    // was read as the cubic, a stitch element's second "edge" replaced the first, silently.
    // The keys of panels, edges, the pattern and its properties were refused by serde.
    let arc = r#"{"endpoints": [1, 2], "curvature": {"type": "circle", "type": "cubic", "params": [[0.5, 0.1], [0.5, 0.1]]}}"#;
    let edge = r#"{"panel": "back", "edge": 3, "edge": 1}"#;
    let mut cases = vec![
        (
            r#"{"endpoints": [1, 2]}"#.to_string(),
            arc.to_string(),
            "key 'type' is given twice".to_string(),
        ),
        (
            r#"{"panel": "back", "edge": 3}"#.into(),
            edge.into(),
            "key 'edge' is given twice".into(),
        ),
    ];
    for (key, value) in [
        ("translation", "[0, 80, 30]"),
        ("endpoints", "[0, 1]"),
        ("units_in_meter", "100"),
    ] {
        let once = format!(r#""{key}": {value}"#);
        cases.push((
            once.clone(),
            format!("{once}, {once}"),
            format!("duplicate field `{key}`"),
        ));
    }
    for (from, to, key) in cases {
        let text = tube().replacen(&from, &to, 1);
        assert_ne!(text, tube(), "{to}");
        match parse(&text, Path::new("p.json")) {
            Err(e @ SpecError::Shape { .. }) => {
                let m = e.to_string();
                assert!(m.starts_with("p.json:") && m.contains(&key), "{m}");
                // The place is given once, first (serde's own " at line L column C" is cut).
                assert!(!m.contains(" at line "), "{m}");
            }
            other => panic!("{to}: {other:?}"),
        }
    }
}

#[test]
fn a_missing_units_in_meter_is_assumed_and_said_so() {
    // GarmentCode's default of 100 was taken without a word in the summary or the report.
    let text = tube().replacen(r#", "units_in_meter": 100"#, "", 1);
    assert_ne!(text, tube());
    let p = parse(&text, Path::new("p.json")).unwrap();
    assert!(p.units_assumed && p.units_in_meter == 100.0);
    let given = parse(&tube(), Path::new("p.json")).unwrap();
    assert!(!given.units_assumed && given.units_in_meter == 100.0);
    // The run: a column for a body, sewn briefly; the summary and the report say it.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("p.json"), &text).unwrap();
    common::write_y_up_obj(
        &common::cylinder(0.186, 0.5, 1.5, 48),
        &d.join("column.obj"),
    );
    let (out, report) = (d.join("out"), d.join("r.json"));
    let (p, b) = (d.join("p.json"), d.join("column.obj"));
    let (p, b, o, r) = (
        p.to_str().unwrap(),
        b.to_str().unwrap(),
        out.to_str().unwrap(),
        report.to_str().unwrap(),
    );
    let mut args = vec!["garment", p, "--body", b, "-o", o, "--report", r];
    args.extend([
        "--spacing",
        "0.04",
        "--sew-max",
        "0.05",
        "--settle-max",
        "0.05",
    ]);
    let run = common::run(&args);
    let (stdout, stderr) = common::text(&run);
    let said = "the pattern gives no units_in_meter: GarmentCode's default, 100, is assumed";
    assert!(stdout.contains(said), "{stdout}\n{stderr}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let assumed = r["assumed"].as_array().unwrap();
    assert!(
        assumed
            .iter()
            .any(|a| a.as_str().unwrap().starts_with(said)),
        "{r}"
    );
}

#[test]
fn a_scenes_garment_without_units_in_meter_is_assumed_in_centimetres_and_warned() {
    // `drape` with a [[garment]] took GarmentCode's default without a word, where `garment`
    // says it in its summary and report.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = tube().replacen(r#", "units_in_meter": 100"#, "", 1);
    std::fs::write(d.join("p.json"), &text).unwrap();
    common::write_y_up_obj(
        &common::cylinder(0.186, 0.5, 1.5, 48),
        &d.join("column.obj"),
    );
    let scene = "units = \"m\"\n[[object]]\nmesh = \"column.obj\"\nup = \"y\"\n\
                 [[garment]]\npattern = \"p.json\"\nspacing = 0.04\nsew_max = 0.05\nsettle_max = 0.05\n";
    std::fs::write(d.join("scene.toml"), scene).unwrap();
    let (s, o, r) = (d.join("scene.toml"), d.join("out"), d.join("r.json"));
    let args = ["drape", s.to_str().unwrap(), "-o", o.to_str().unwrap()];
    let run = common::run(&[&args[..], &["--report", r.to_str().unwrap()]].concat());
    let (stdout, stderr) = common::text(&run);
    assert!(run.status.success(), "{stdout}\n{stderr}");
    let said = "the pattern gives no units_in_meter: GarmentCode's default, 100, is assumed";
    assert!(stderr.contains(said), "{stderr}");
    let report = std::fs::read_to_string(&r).unwrap();
    assert!(report.contains(said), "{report}");
    // A pattern that gives its units is not warned about.
    std::fs::write(d.join("p.json"), tube()).unwrap();
    let run = common::run(&args);
    let (stdout, stderr) = common::text(&run);
    assert!(
        run.status.success() && !stderr.contains("units_in_meter"),
        "{stdout}\n{stderr}"
    );
}

/// The tube with its front made a 60 cm strip `w` cm wide (its short ends still sewn to the
/// back's sides).
fn strip(w: &str) -> String {
    let strip = format!("[[-30, 0], [30, 0], [30, {w}], [-30, {w}]]");
    tube().replacen("[[-30, 0], [30, 0], [30, 40], [-30, 40]]", &strip, 1)
}

#[test]
fn a_strip_too_thin_for_the_spacing_is_refused_by_name_before_the_solver() {
    // 0.02 to 0.2 mm wide it passed the reader's area floor and the solver failed on it: "not
    // positive definite" or "went unstable", naming no panel's width.
    use drapekit::garment::assemble::{thin_panels, AssembleError};
    let at = |w: &str, h: f64| {
        let pattern = parse(&strip(w), Path::new("p.json")).unwrap();
        let opts = AssembleOptions {
            spacing: h,
            ..AssembleOptions::default()
        };
        let thin = thin_panels(&pattern, h);
        match assemble(&pattern, &opts) {
            Ok(_) => assert!(thin.is_empty()),
            Err(e) => assert_eq!(e.len(), thin.len()),
        }
        thin
    };
    for (w, h) in [
        ("0.002", 0.01),
        ("0.02", 0.01),
        ("0.04", 0.01),
        ("0.07", 0.02),
        ("0.02", 0.04),
        ("0.02", 0.004),
    ] {
        let thin = at(w, h);
        assert!(
            matches!(&thin[..], [AssembleError::Thin { panel, spacing, .. }] if panel == "front" && *spacing == h),
            "{w} cm at {h}: {thin:?}"
        );
        let m = thin[0].to_string();
        assert!(
            m.starts_with("panel 'front' is 0.") && m.contains(" mm wide"),
            "{m}"
        );
    }
    // 0.2 mm: no spacing takes it; 0.7 mm at 2 cm: 1 cm does (it drapes there).
    let m = at("0.02", 0.01)[0].to_string();
    assert!(
        m.ends_with("no spacing from 0.002 to 0.1 m takes it: is it meant to be a panel?"),
        "{m}"
    );
    let m = at("0.07", 0.02)[0].to_string();
    assert!(
        m.ends_with("a spacing from 0.0058 to 0.0155 m would take it (garment --spacing, or spacing in a scene's [[garment]])"),
        "{m}"
    );
    // What drapes is taken: 0.5 mm at 1 cm, 1 mm at 2 cm, 5 mm at 4 cm.
    for (w, h) in [("0.05", 0.01), ("0.1", 0.02), ("0.5", 0.04)] {
        assert!(at(w, h).is_empty(), "{w} cm at {h}");
    }
    // The command names the file and stops before reading the body.
    let dir = tempfile::tempdir().unwrap();
    let pattern = dir.path().join("strip.json");
    std::fs::write(&pattern, strip("0.02")).unwrap();
    let (out, report) = (dir.path().join("out"), dir.path().join("r.json"));
    let (p, o, r) = (
        pattern.to_str().unwrap(),
        out.to_str().unwrap(),
        report.to_str().unwrap(),
    );
    let (ok, stderr) = garment_with_report(p, o, r);
    assert!(!ok);
    let expected = format!("error: {p}: panel 'front' is 0.");
    assert!(stderr.starts_with(&expected), "{stderr}");
}

#[test]
fn every_panel_of_the_real_patterns_and_fixtures_is_wide_enough_with_margin() {
    // Width (twice the area over the perimeter of the sampled outline) against the least the
    // thin check takes, at spacings 1 to 4 cm: the least ratio over every panel.
    use drapekit::garment::assemble::{thin_panels, THIN_FRACTION, THIN_WIDTH_SPACING};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<std::path::PathBuf> = ["tube", "circle_skirt"]
        .iter()
        .map(|n| root.join(format!("fixtures/garments/{n}_specification.json")))
        .collect();
    if let Some(data) = common::realdata() {
        for f in std::fs::read_dir(data.join("patterns")).unwrap() {
            let path = f.unwrap().path();
            if path.extension().is_some_and(|e| e == "json") {
                files.push(path);
            }
        }
    }
    let mut least = f64::INFINITY;
    for path in &files {
        let p = drapekit::garment::read(path).unwrap();
        for h in [0.01, 0.015, 0.02, 0.03, 0.04] {
            assert!(thin_panels(&p, h).is_empty(), "{}", path.display());
            let to_m = 1.0 / p.units_in_meter;
            let counts = drapekit::garment::sample::edge_segments(&p, h / to_m);
            for s in drapekit::garment::sample::sample_all(&p, &counts) {
                let n = s.points.len();
                let (mut area, mut perimeter) = (0.0, 0.0);
                for i in 0..n {
                    let (a, b) = (s.points[i] * to_m, s.points[(i + 1) % n] * to_m);
                    area += a.coords.perp(&b.coords) / 2.0;
                    perimeter += (b - a).norm();
                }
                let limit = (THIN_FRACTION * h).max(THIN_WIDTH_SPACING / h);
                least = least.min(2.0 * area.abs() / perimeter / limit);
            }
        }
    }
    eprintln!("least width over the thin check's limit: {least:.2}");
    assert!(least > 20.0, "{least}");
}
