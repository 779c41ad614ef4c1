//! `drapekit fit`: convergence, exact reproduction, girths from real measurements, scan accuracy
//! on real bodies, the extremes, and bad input.

mod common;
use common::{listing, realdata, run, text};
use drapekit::fit::fitter::{fit_sections, FitOptions};
use drapekit::fit::section::Section;
use drapekit::fit::surface;
use drapekit::io::{read_mesh, ReadOptions};
use drapekit::math::{Point2, Point3};
use drapekit::mesh::closest::ClosestPoints;
use drapekit::mesh::diagnose::{diagnose, ShellState};
use drapekit::mesh::transform::{change_up, Up};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Closed around, not periodic along the height.
use drapekit::fit::surface::reference_surface as analytic;

fn max_error(k: usize, m: usize) -> f64 {
    let n = 32;
    let g: Vec<Point3> = (0..k)
        .flat_map(|i| (0..n).map(move |l| analytic(l as f64 / n as f64, i as f64 / (k - 1) as f64)))
        .collect();
    let s = surface::fit(&g, k, n, m);
    let mut e: f64 = 0.0;
    for i in 0..=300 {
        let v = i as f64 / 300.0;
        for (l, p) in s.eval_ring(v, n).iter().enumerate() {
            e = e.max((p - analytic(l as f64 / n as f64, v)).norm());
        }
    }
    e
}

#[test]
fn error_falls_at_least_like_n_to_the_minus_2m_plus_1() {
    for (m, ns) in [
        (0, vec![8, 16, 32, 64, 128]),
        (1, vec![8, 16, 32, 64]),
        (2, vec![8, 16, 32]),
    ] {
        let errs: Vec<f64> = ns.iter().map(|&n| max_error(n + 1, m)).collect();
        for w in 0..errs.len() - 1 {
            let ratio = errs[w] / errs[w + 1];
            let needed = 2f64.powi(2 * m as i32 + 1);
            assert!(ratio >= needed, "m={m}: error {:.3e} -> {:.3e} from {} to {} intervals, ratio {ratio:.2} < {needed}", errs[w], errs[w + 1], ns[w], ns[w + 1]);
        }
    }
}

/// Writes sections as a JSON file.
fn sections_json(
    dir: &Path,
    name: &str,
    units: &str,
    sections: &[(f64, Vec<(f64, f64)>)],
) -> PathBuf {
    let s: Vec<Value> = sections
        .iter()
        .map(|(h, p)| serde_json::json!({"height": h, "points": p.iter().map(|&(x, y)| vec![x, y]).collect::<Vec<_>>()}))
        .collect();
    let path = dir.join(name);
    std::fs::write(
        &path,
        serde_json::to_string(&serde_json::json!({"units": units, "sections": s})).unwrap(),
    )
    .unwrap();
    path
}

fn circle(r: f64, n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|l| std::f64::consts::TAU * l as f64 / n as f64)
        .map(|t| (r * t.cos(), r * t.sin()))
        .collect()
}

fn fit_cli(args: &[&str]) -> (Value, std::process::Output) {
    let mut all = vec!["fit"];
    all.extend_from_slice(args);
    all.push("--json");
    let o = run(&all);
    assert!(o.status.success(), "{}", text(&o).1);
    (serde_json::from_str(&text(&o).0).unwrap(), o)
}

#[test]
fn band_limited_sections_are_reproduced_to_round_off() {
    // Circles (band-limited around) whose radius is linear in height: a cone frustum. The fit
    // reproduces it exactly between the nodes, around and along, whatever the output grid.
    let dir = tempfile::tempdir().unwrap();
    let r = |z: f64| 0.2 + 0.1 * z;
    let secs: Vec<_> = (0..7)
        .map(|i| (i as f64 * 0.25, circle(r(i as f64 * 0.25), 64)))
        .collect();
    let src = sections_json(dir.path(), "cone.json", "m", &secs);
    let out = dir.path().join("cone.obj");
    let (rep, _) = fit_cli(&[
        "--sections",
        src.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--nodes",
        "64",
        "--around",
        "100",
        "--along",
        "37",
        "--open",
    ]);
    assert_eq!(rep["lanczos"], 1);
    let m = read_mesh(&out, &ReadOptions::default()).unwrap().mesh;
    assert_eq!(m.positions.len(), 37 * 100);
    for p in &m.positions {
        let e = ((p.x * p.x + p.y * p.y).sqrt() - r(p.z)).abs();
        assert!(e < 1e-13, "{p:?}: {e:e}");
    }
}

#[test]
fn extremes_work_against_the_analytic_answer() {
    // (sections, points per section, scale, largest error allowed relative to the size)
    // Three sections give only three nodes along: a coarse but correct surface.
    // The input polygons' own chords limit the agreement (a 200-gon's girth is 4e-5 short).
    for (k, pts, scale, rel) in [
        (3usize, 64usize, 1.0, 1e-2),
        (1000, 512, 1.0, 5e-5),
        (20, 4096, 1.0, 1e-6),
        (20, 200, 1000.0, 1e-4),
    ] {
        let sections: Vec<Section> = (0..k)
            .map(|i| {
                let v = i as f64 / (k - 1) as f64;
                let p = (0..pts)
                    .map(|l| analytic(l as f64 / pts as f64, v) * scale)
                    .map(|p| Point2::new(p.x, p.y))
                    .collect();
                Section {
                    height: analytic(0.0, v).z * scale,
                    points: p,
                }
            })
            .collect();
        let f = fit_sections(
            sections,
            &[],
            &FitOptions {
                nodes_around: 256,
                ..FitOptions::default()
            },
        )
        .unwrap();
        if k == 3 {
            assert_eq!(f.report.lanczos, 0);
            assert!(f
                .report
                .warnings
                .iter()
                .any(|w| w.contains("Lanczos order lowered from 1 to 0")));
        }
        assert_eq!(f.report.output.shell_state, ShellState::Closed);
        // The sections are resampled by arc length, so compare what does not depend on the
        // parametrisation around: the height of each ring, and its girth.
        let mut worst: f64 = 0.0;
        for i in 0..=40 {
            let v = i as f64 / 40.0;
            for p in f.surface.eval_ring(v, 64) {
                worst = worst.max((p.z - analytic(0.0, v).z * scale).abs() / scale);
            }
        }
        let girth_at = |v: f64| {
            let ring: Vec<Point2> = f
                .surface
                .eval_ring(v, 4096)
                .iter()
                .map(|p| Point2::new(p.x, p.y))
                .collect();
            drapekit::mesh::slice::girth(&ring)
        };
        for i in 0..=10 {
            let v = i as f64 / 10.0;
            let truth: Vec<Point2> = (0..4096)
                .map(|l| analytic(l as f64 / 4096.0, v) * scale)
                .map(|p| Point2::new(p.x, p.y))
                .collect();
            let g = drapekit::mesh::slice::girth(&truth);
            worst = worst.max((girth_at(v) - g).abs() / g);
        }
        assert!(worst < rel, "k={k} pts={pts} scale={scale}: {worst:e}");
    }
}

#[test]
fn repeated_points_duplicates_collinear_and_non_star_sections() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = circle(1.0, 40);
    c.insert(3, c[3]);
    c.push(c[0]);
    // Repeated points and an identical section given twice: merged, with a warning.
    let src = sections_json(
        dir.path(),
        "rep.json",
        "m",
        &[
            (0.0, c.clone()),
            (1.0, c.clone()),
            (1.0, c.clone()),
            (2.0, c.clone()),
        ],
    );
    let (rep, _) = fit_cli(&[
        "--sections",
        src.to_str().unwrap(),
        "-o",
        dir.path().join("rep.obj").to_str().unwrap(),
    ]);
    assert_eq!(rep["sections"]["merged_duplicates"], 1);
    assert_eq!(
        rep["sections"]["repeated_points"], 8,
        "two in each of the four sections"
    );
    // A C-shaped (not star-shaped) section, the same at every height: a prism, reproduced.
    let cshape: Vec<(f64, f64)> = vec![
        (0.0, 0.0),
        (3.0, 0.0),
        (3.0, 1.0),
        (1.0, 1.0),
        (1.0, 2.0),
        (3.0, 2.0),
        (3.0, 3.0),
        (0.0, 3.0),
    ];
    let src = sections_json(
        dir.path(),
        "c.json",
        "m",
        &[
            (0.0, cshape.clone()),
            (1.0, cshape.clone()),
            (2.0, cshape.clone()),
            (3.0, cshape),
        ],
    );
    let out = dir.path().join("c.obj");
    let (rep, _) = fit_cli(&[
        "--sections",
        src.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--nodes",
        "512",
        "--around",
        "512",
    ]);
    assert_eq!(
        rep["output"]["shell_state"], "closed",
        "the cap of a non-star section is ear-clipped"
    );
    let girth = rep["girths"][1]["measured"].as_f64().unwrap();
    assert!(
        (girth - 12.0).abs() < 0.02,
        "hull of the C is the 3 x 3 square: {girth}"
    );
    // Differing sections at one height, and a collinear one: refused, naming them.
    for (name, secs, msg) in [
        (
            "dup.json",
            vec![
                (0.0, circle(1.0, 8)),
                (1.0, circle(1.0, 8)),
                (1.0, circle(2.0, 8)),
            ],
            "sections 2 and 3 are both at height 1 but differ",
        ),
        (
            "line.json",
            vec![
                (0.0, circle(1.0, 8)),
                (1.0, vec![(0.0, 0.0), (1.0, 1.0), (2.0, 2.0)]),
                (2.0, circle(1.0, 8)),
            ],
            "section 2 (height 1) is degenerate: its points are collinear",
        ),
        (
            "two.json",
            vec![(0.0, circle(1.0, 8)), (1.0, circle(1.0, 8))],
            "2 section(s): a surface needs at least 3",
        ),
        (
            "pts.json",
            vec![
                (0.0, circle(1.0, 8)),
                (1.0, vec![(0.0, 0.0), (1.0, 0.0)]),
                (2.0, circle(1.0, 8)),
            ],
            "section 2 (height 1): 2 distinct point(s)",
        ),
    ] {
        let d = tempfile::tempdir().unwrap();
        let src = sections_json(d.path(), name, "m", &secs);
        let o = run(&[
            "fit",
            "--sections",
            src.to_str().unwrap(),
            "-o",
            d.path().join("x.obj").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(1), "{name}");
        // Named with the file they are in.
        assert!(
            text(&o).1.contains(&format!("{name}: {msg}")),
            "{name}: {}",
            text(&o).1
        );
        assert_eq!(
            listing(d.path()),
            vec![name.to_string()],
            "{name}: nothing written"
        );
    }
}

#[test]
fn malformed_files_are_refused_with_the_place() {
    for (name, content, msg) in [
        (
            "a.json",
            "{\"units\": \"m\", \"sections\": [{\"height\": 1, \"points\": [[0, 0], [1, 0]]\n",
            "a.json:2:0: EOF while parsing",
        ),
        (
            "b.json",
            "{\"units\": \"m\",\n \"sectons\": []}",
            "b.json:2:10: unknown field `sectons`",
        ),
        (
            "c.json",
            "{\"sections\": [{\"height\": \"high\", \"points\": []}]}",
            "c.json:1:31: invalid type: string \"high\", expected f64",
        ),
        (
            "d.csv",
            "height,x,y\n0,0,0\n0,1,0\n0,0,oops\n",
            "d.csv:4: 'oops' is not a number",
        ),
        (
            "e.toml",
            "units = \"cm\"\nstature = 170\nbust_grith = 90\n",
            "e.toml: line 3, column 1: unknown field `bust_grith`",
        ),
        (
            "f.toml",
            "units = \"cm\"\nstature = \"tall\"\nbust_girth = 90\nwaist_girth = 70\n",
            "f.toml: line 2, column 11: invalid type: string \"tall\", expected f64",
        ),
        (
            "g.toml",
            "units = \"cm\"\nstature = 170\nwaist_girth = 70\n",
            "key '*_girth': at least two girths are required, 1 given",
        ),
        (
            "h.toml",
            "units = \"cubits\"\nstature = 170\nwaist_girth = 70\nbust_girth = 90\n",
            "key 'units': unknown unit 'cubits'",
        ),
        (
            "i.toml",
            "stature = 170\nwaist_girth = 70\nbust_girth = -3\nwaist_height = 200\n",
            "i.toml: 2 problems:\n  key 'bust_girth': must be a positive number, got -3\n  key 'waist_height': 200 is not below the stature 170",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let src = dir.path().join(name);
        std::fs::write(&src, content).unwrap();
        let flag = if name.ends_with(".toml") {
            "--measurements"
        } else {
            "--sections"
        };
        let o = run(&[
            "fit",
            flag,
            src.to_str().unwrap(),
            "-o",
            dir.path().join("out.obj").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(1), "{name}");
        let err = text(&o).1;
        assert!(err.contains(msg) && err.contains(name), "{name}: {err}");
        assert_eq!(
            listing(dir.path()),
            vec![name.to_string()],
            "{name}: nothing written"
        );
    }
    let o = run(&[
        "fit",
        "--sections",
        "/nonexistent/s.json",
        "-o",
        "/tmp/never.obj",
    ]);
    assert!(text(&o).1.contains("cannot read /nonexistent/s.json"));
    // Two sources, or none: usage errors.
    assert_eq!(run(&["fit", "-o", "x.obj"]).status.code(), Some(2));
    assert_eq!(
        run(&[
            "fit",
            "--sections",
            "a.json",
            "--measurements",
            "b.toml",
            "-o",
            "x.obj"
        ])
        .status
        .code(),
        Some(2)
    );
    assert_eq!(
        run(&[
            "fit",
            "--sections",
            "a.json",
            "--tolerance",
            "0.5mm",
            "--nodes",
            "12",
            "-o",
            "x.obj"
        ])
        .status
        .code(),
        Some(2)
    );
}

/// A measurements TOML from a GarmentCode body YAML (cm): bust, underbust, waist, hips, and the
/// levels GarmentCode derives (waist = height - head_l - waist_line, bust = height - head_l -
/// vert_bust_line, hip = waist - hips_line).
fn toml_from_yaml(yaml: &str) -> String {
    let get = |k: &str| -> f64 {
        yaml.lines()
            .find_map(|l| {
                l.trim()
                    .strip_prefix(&format!("{k}:"))
                    .map(|v| v.trim().parse().unwrap())
            })
            .unwrap_or_else(|| panic!("{k}"))
    };
    let h = get("height");
    let waist_h = h - get("head_l") - get("waist_line");
    format!(
        "units = \"cm\"\nstature = {h}\nbust_girth = {}\nunderbust_girth = {}\nwaist_girth = {}\nhip_girth = {}\nwaist_height = {waist_h}\nbust_height = {}\nhip_height = {}\n",
        get("bust"),
        get("underbust"),
        get("waist"),
        get("hips"),
        h - get("head_l") - get("vert_bust_line"),
        waist_h - get("hips_line")
    )
}

#[test]
fn forms_from_real_measurements_have_the_requested_girths() {
    let Some(data) = realdata() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut cases = Vec::new();
    for body in ["mean_female", "mean_male", "mean_all"] {
        let path = data.join(format!("bodies/{body}.yaml"));
        let yaml = std::fs::read_to_string(&path).unwrap();
        cases.push((body.to_string(), toml_from_yaml(&yaml), path));
    }
    // FreeSewing's base set (mm). Its 'chest' is the bust girth, 'seat' the ISO hip girth, 'hips'
    // the top hip 125 mm below the waist; no stature is given, so it is estimated as the neck
    // base's height (waistToFloor + hpsToWaistBack) over the model's neck-base proportion 0.845.
    let fs: Value = serde_json::from_str(
        &std::fs::read_to_string(data.join("measurements/with_breasts_base_set_mm.json")).unwrap(),
    )
    .unwrap();
    let g = |k: &str| fs["measurements_mm"][k].as_f64().unwrap();
    let waist_h = g("waistToFloor");
    cases.push((
        "freesewing".into(),
        format!(
            "units = \"mm\"\nstature = {}\nneck_base_girth = {}\nbust_girth = {}\nunderbust_girth = {}\nwaist_girth = {}\ntop_hip_girth = {}\nhip_girth = {}\nwaist_height = {waist_h}\ntop_hip_height = {}\nhip_height = {}\nunderbust_height = {}\nbust_height = {}\nshoulder_width = {}\n",
            (waist_h + g("hpsToWaistBack")) / 0.845,
            g("neck"),
            g("chest"),
            g("underbust"),
            g("waist"),
            g("hips"),
            g("seat"),
            waist_h - g("waistToHips"),
            waist_h - g("waistToSeat"),
            waist_h + g("waistToUnderbust"),
            waist_h + g("waistToUnderbust") + g("bustPointToUnderbust"),
            g("shoulderToShoulder"),
        ),
        data.join("measurements/with_breasts_base_set_mm.json"),
    ));
    for (name, toml, direct) in cases {
        let src = dir.path().join(format!("{name}.toml"));
        std::fs::write(&src, toml).unwrap();
        let out = dir.path().join(format!("{name}.obj"));
        let (rep, _) = fit_cli(&[
            "--measurements",
            src.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ]);
        let girths = rep["girths"].as_array().unwrap();
        assert!(girths.len() >= 4, "{name}");
        // The file read as it is (GarmentCode YAML, FreeSewing JSON) gives the same levels and
        // girths as the hand translation above.
        let (rep2, _) = fit_cli(&[
            "--measurements",
            direct.to_str().unwrap(),
            "-o",
            dir.path()
                .join(format!("{name}_direct.obj"))
                .to_str()
                .unwrap(),
        ]);
        let key = |g: &Value| {
            let f = |k: &str| g[k].as_f64().unwrap();
            (
                g["name"].as_str().unwrap().to_string(),
                f("height"),
                f("requested"),
            )
        };
        let (a, b): (Vec<_>, Vec<_>) = (
            girths.iter().map(key).collect(),
            rep2["girths"].as_array().unwrap().iter().map(key).collect(),
        );
        assert_eq!(a.len(), b.len(), "{name}: {a:?} against {b:?}");
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.0, y.0, "{name}");
            let scale = if name == "freesewing" { 0.1 } else { 1.0 }; // mm against cm
            assert!(
                (x.1 * scale - y.1).abs() < 1e-9 && (x.2 * scale - y.2).abs() < 1e-9,
                "{name}: {x:?} against {y:?}"
            );
        }
        for gc in girths {
            let (req, meas) = (
                gc["requested"].as_f64().unwrap(),
                gc["measured"].as_f64().unwrap(),
            );
            assert!(
                ((meas - req) / req).abs() <= 0.002,
                "{name} {}: requested {req}, measured {meas}",
                gc["name"]
            );
        }
        // Checked independently: the written form is closed and outward, and slicing it gives the girths.
        let m = read_mesh(&out, &ReadOptions::default()).unwrap().mesh;
        assert_eq!(diagnose(&m).shell_state, ShellState::Closed, "{name}");
        for gc in girths {
            let h = gc["height"].as_f64().unwrap();
            let pts: Vec<Point2> = drapekit::mesh::slice::slice(&m, h)
                .iter()
                .flat_map(|l| l.xy())
                .collect();
            let gg = drapekit::mesh::slice::girth(&pts);
            assert!(
                (gg / gc["requested"].as_f64().unwrap() - 1.0).abs() <= 0.002,
                "{name}"
            );
        }
    }
}

#[test]
fn scans_of_real_bodies_are_fitted_within_2mm_mean_5mm_p95() {
    let Some(data) = realdata() else { return };
    let dir = tempfile::tempdir().unwrap();
    for body in [
        "mean_female",
        "mean_male",
        "mean_all",
        "makehuman_hm08_body_only_m",
    ] {
        let src = data.join(format!("bodies/{body}.obj"));
        let out = dir.path().join(format!("{body}.ply"));
        let (rep, _) = fit_cli(&[
            "--from-mesh",
            src.to_str().unwrap(),
            "--up",
            "y",
            "--levels",
            "60",
            "-o",
            out.to_str().unwrap(),
            "--open",
        ]);
        let band = [
            rep["band"][0].as_f64().unwrap(),
            rep["band"][1].as_f64().unwrap(),
        ];
        // Distances from the fitted surface (written Y-up like the scan) to the original mesh.
        let mut body_mesh = read_mesh(&src, &ReadOptions::default()).unwrap().mesh;
        change_up(&mut body_mesh, Up::Y, Up::Z);
        let mut form = read_mesh(&out, &ReadOptions::default()).unwrap().mesh;
        change_up(&mut form, Up::Y, Up::Z);
        let q = ClosestPoints::new(&body_mesh);
        let mut d: Vec<f64> = form
            .positions
            .iter()
            .filter(|p| p.z >= band[0] && p.z <= band[1])
            .map(|p| q.closest(p).distance * 1000.0)
            .collect();
        assert!(d.len() > 10_000, "{body}: {} points in the band", d.len());
        d.sort_by(f64::total_cmp);
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        let p95 = d[d.len() * 95 / 100];
        assert!(
            mean <= 2.0 && p95 <= 5.0,
            "{body}: mean {mean:.3} mm, p95 {p95:.3} mm"
        );
    }
}

#[test]
fn scan_band_across_the_armpits_is_refused_naming_the_level() {
    let Some(data) = realdata() else { return };
    let dir = tempfile::tempdir().unwrap();
    let src = data.join("bodies/mean_female.obj");
    // 0.9 m to 1.35 m crosses the arms' join (~1.25 m): the torso splits.
    let o = run(&[
        "fit",
        "--from-mesh",
        src.to_str().unwrap(),
        "--up",
        "y",
        "--from",
        "0.9",
        "--to",
        "1.35",
        "-o",
        dir.path().join("x.obj").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o).1;
    assert!(
        err.contains("mean_female.obj: scan level") && err.contains("torso splits here"),
        "{err}"
    );
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn tolerance_chooses_nodes_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let secs: Vec<_> = (0..41)
        .map(|i| {
            let v = i as f64 / 40.0;
            // 1000 points: the polygon's chords sag 0.007 mm from the curve, below the tolerances.
            let p = (0..1000)
                .map(|l| analytic(l as f64 / 1000.0, v))
                .map(|p| (p.x * 1000.0, p.y * 1000.0))
                .collect();
            (analytic(0.0, v).z * 1000.0, p)
        })
        .collect();
    let src = sections_json(dir.path(), "mm.json", "mm", &secs);
    let mut chosen = Vec::new();
    for tol in ["2mm", "0.05mm", "0.00005m"] {
        let (rep, _) = fit_cli(&[
            "--sections",
            src.to_str().unwrap(),
            "-o",
            dir.path().join("t.obj").to_str().unwrap(),
            "--tolerance",
            tol,
        ]);
        let c = &rep["tolerance"];
        assert_eq!(c["met"], true, "{tol}");
        assert!(c["expected_error"].as_f64().unwrap() <= c["tolerance"].as_f64().unwrap());
        chosen.push((
            c["nodes_around"].as_u64().unwrap(),
            rep["nodes_along"].as_u64().unwrap(),
        ));
    }
    assert_eq!(
        chosen[1], chosen[2],
        "0.05mm and 0.00005m are the same tolerance"
    );
    assert!(
        chosen[0].0 * chosen[0].1 < chosen[1].0 * chosen[1].1,
        "a looser tolerance needs fewer nodes: {chosen:?}"
    );
}

#[test]
fn output_units_and_up_axis() {
    let dir = tempfile::tempdir().unwrap();
    let secs: Vec<_> = (0..5)
        .map(|i| (i as f64 * 10.0, circle(20.0, 32)))
        .collect();
    let src = sections_json(dir.path(), "cyl.json", "cm", &secs);
    let out = dir.path().join("cyl.obj");
    let (rep, _) = fit_cli(&[
        "--sections",
        src.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--to-up",
        "y",
        "--to-units",
        "m",
    ]);
    assert_eq!(
        (
            rep["output_up"].as_str(),
            rep["output_units"].as_str(),
            rep["units"].as_str()
        ),
        (Some("y"), Some("m"), Some("cm"))
    );
    // Girths are reported in the input's units.
    assert!((rep["girths"][0]["requested"].as_f64().unwrap() - 125.0).abs() < 0.5);
    let m = read_mesh(&out, &ReadOptions::default()).unwrap().mesh;
    let b = m.bbox().unwrap();
    assert!(
        (b.min.y - 0.0).abs() < 1e-12 && (b.max.y - 0.4).abs() < 1e-12,
        "height along +y in metres: {b:?}"
    );
    assert!(m.signed_volume() > 0.0, "still outward after the rotation");
}

/// Runs `fit ARGS`; asserts exit status 1 and a message with each of `parts`.
fn fit_refused(args: &[&str], parts: &[&str]) {
    let mut all = vec!["fit"];
    all.extend_from_slice(args);
    let o = run(&all);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert!(parts.iter().all(|m| err.contains(m)), "{args:?}: {err}");
}

#[test]
fn flags_and_outputs_are_refused_before_the_input_is_read_with_every_problem() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let (nope, out) = (p("nope.toml"), p("form.obj"));
    // Every count out of range at once (--stride 0 was 'nodes around ... at least 3').
    let counts = [
        "--nodes", "0", "--around", "2", "--along", "1", "--stride", "0",
    ];
    let all = [
        "4 problems:",
        "--nodes 0: at least 3",
        "--around 2",
        "--along 1",
        "--stride 0",
    ];
    fit_refused(
        &[&["--measurements", &nope, "-o", &out][..], &counts].concat(),
        &all,
    );
    // --levels 0 gave a model of 10 sections without a word.
    fit_refused(
        &["--measurements", &nope, "-o", &out, "--levels", "0"],
        &["--levels 0"],
    );
    // The hint named convert's --to, which in fit is the top of the band.
    fit_refused(
        &["--measurements", &nope, "-o", &p("f.png")],
        &["give --format"],
    );
    fit_refused(
        &["--measurements", &nope, "-o", &p("no/f.obj")],
        &["does not exist"],
    );
    // --units against a measurement set that states others (it was ignored without a word);
    // the same units are accepted.
    let size38 = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/measurements_size38.toml"
    );
    let units = ["--measurements", size38, "-o", &out, "--units", "mm"];
    fit_refused(
        &units,
        &["key 'units': the file's units are cm", "not --units mm"],
    );
    fit_refused(
        &["--from-mesh", &nope, "-o", &out, "--from", "nan"],
        &["--from NaN"],
    );
    // The report over the form or its preview: the form was written, then the run failed
    // (or the preview was overwritten by the report).
    let report = ["--measurements", &nope, "-o", &out, "--report"];
    let over = ["written over an output"];
    fit_refused(&[&report[..], &[&out]].concat(), &over);
    let png = p("form.png");
    fit_refused(&[&report[..], &[&png, "--preview"]].concat(), &over);
    let r = p("r.json");
    std::fs::create_dir(&r).unwrap();
    let folder = [&report[..], &[&r]].concat();
    fit_refused(&folder, &["exists and is not a file"]);
    assert_eq!(listing(dir.path()), ["r.json"]);
    // A sections file that says its units, and --units that says others.
    let json = sections_json(dir.path(), "s.json", "m", &[(0.0, circle(1.0, 8))]);
    let other = [
        "--sections",
        json.to_str().unwrap(),
        "-o",
        &out,
        "--units",
        "mm",
    ];
    fit_refused(
        &other,
        &["key 'units': the file's units are m", "not --units mm"],
    );
    // 10,001 sections: a fit's time grows as their square (5,000 took 36 s).
    let many: Vec<(f64, Vec<(f64, f64)>)> =
        (0..10_001).map(|k| (k as f64, circle(1.0, 3))).collect();
    let json = sections_json(dir.path(), "many.json", "m", &many);
    let many = ["--sections", json.to_str().unwrap(), "-o", &out];
    fit_refused(&many, &["many.json: 10001 sections: at most 10000"]);
    // A scan whose every face is degenerate: 'the body mesh is empty', no file named.
    let line = p("line.obj");
    std::fs::write(&line, "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n").unwrap();
    let scan = ["--from-mesh", &line, "-o", &out];
    fit_refused(&scan, &["line.obj: every face of the mesh is degenerate"]);
    // The units the set states, given again, are accepted.
    let agreed = ["--measurements", size38, "-o", &out, "--units", "cm"];
    assert_eq!(fit_cli(&agreed).0["units"].as_str(), Some("cm"));
}
