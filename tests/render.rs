//! `drapekit render` and the previews: the geometry of the pictures (silhouette areas against
//! the analytic ones, occlusion, the three projections' layout), colours that follow the
//! values, determinism, animations, the rest coordinates drape writes, and bad input.

mod common;

use drapekit::math::{Point3, Vec3};
use drapekit::mesh::{generate, TriMesh};
use std::path::{Path, PathBuf};

const WHITE: [u8; 3] = [255, 255, 255];
const BLACK: [u8; 3] = [0, 0, 0];

/// A scratch directory, removed when dropped.
fn scratch(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("drapekit-render-{name}-"))
        .tempdir()
        .unwrap()
}

/// Writes `mesh` as OBJ at `dir/name`.
fn write_obj(dir: &Path, name: &str, mesh: &TriMesh) -> PathBuf {
    let p = dir.join(name);
    drapekit::io::write_mesh(&p, mesh, &Default::default(), &[]).unwrap();
    p
}

/// A decoded 8-bit RGB PNG: width, height, pixels row by row.
struct Picture {
    width: usize,
    height: usize,
    pixels: Vec<[u8; 3]>,
}

impl Picture {
    fn read(path: &Path) -> Picture {
        let (width, height, pixels) = common::read_png(path);
        Picture {
            width,
            height,
            pixels,
        }
    }

    fn at(&self, x: usize, y: usize) -> [u8; 3] {
        self.pixels[y * self.width + x]
    }

    /// Pixels in columns `x0..x1` for which `keep` holds.
    fn count(&self, x0: usize, x1: usize, keep: impl Fn([u8; 3]) -> bool) -> usize {
        (0..self.height)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| keep(self.at(x, y)))
            .count()
    }
}

/// Runs drapekit; asserts success; returns stdout.
fn ok(args: &[&str]) -> String {
    let o = common::run(args);
    let (out, err) = common::text(&o);
    assert!(o.status.success(), "{args:?}: {err}");
    out
}

/// Runs `render ... --json` and returns the report.
fn render_json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    all.push("--json");
    serde_json::from_str(&ok(&all)).unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A quad `[x0, x1] x [z0, z1]` in the plane `y` (seen by the front view, which looks along +y).
fn quad_xz(x: [f64; 2], z: [f64; 2], y: f64) -> TriMesh {
    TriMesh::new(
        vec![
            Point3::new(x[0], y, z[0]),
            Point3::new(x[1], y, z[0]),
            Point3::new(x[1], y, z[1]),
            Point3::new(x[0], y, z[1]),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

#[test]
fn a_sphere_covers_its_analytic_projected_area_within_one_percent() {
    let dir = scratch("sphere");
    let mut sphere = generate::icosphere(5);
    for p in &mut sphere.positions {
        p.coords *= 0.3;
    }
    let mesh = write_obj(dir.path(), "sphere.obj", &sphere);
    for view in ["front", "iso"] {
        let out = dir.path().join(format!("{view}.png"));
        let r = render_json(&[
            s(&mesh),
            "-o",
            s(&out),
            "--view",
            view,
            "--width",
            "500",
            "--height",
            "400",
        ]);
        let ppu = r["pixels_per_unit"].as_f64().unwrap();
        let pic = Picture::read(&out);
        assert_eq!((pic.width, pic.height), (500, 400));
        let covered = pic.count(0, pic.width, |c| c != WHITE) as f64;
        let disc = std::f64::consts::PI * (0.3 * ppu).powi(2);
        eprintln!("{view}: {covered} pixels covered, pi r^2 = {disc:.1}");
        assert!(
            (covered / disc - 1.0).abs() < 0.01,
            "{view}: {covered} pixels, pi r^2 = {disc:.0} (r = {:.1} px)",
            0.3 * ppu
        );
        // The sphere is centred: as many covered pixels left of the middle as right.
        let left = pic.count(0, 250, |c| c != WHITE) as f64;
        assert!(
            (left / covered - 0.5).abs() < 0.005,
            "{view}: {left} of {covered} on the left"
        );
    }
}

#[test]
fn a_mesh_behind_another_is_hidden_and_in_front_is_seen_in_either_order() {
    let dir = scratch("occlusion");
    let blue = write_obj(
        dir.path(),
        "blue.obj",
        &quad_xz([-1.0, 1.0], [-1.0, 1.0], 0.0),
    );
    let behind = write_obj(
        dir.path(),
        "behind.obj",
        &quad_xz([-0.25, 0.25], [-0.25, 0.25], 0.5),
    );
    let front = write_obj(
        dir.path(),
        "front.obj",
        &quad_xz([-0.25, 0.25], [-0.25, 0.25], -0.5),
    );
    let red = |c: [u8; 3]| c[0] > 0 && c[1] == 0 && c[2] == 0;
    let blueish = |c: [u8; 3]| c[2] > 0 && c[0] == 0 && c[1] == 0;
    for (small, seen) in [(&behind, false), (&front, true)] {
        // Both orders of the arguments, the small square first (as the cloth, lifted) or last.
        for (args, colours) in [
            ([s(small), s(&blue)], "#ff0000,#0000ff"),
            ([s(&blue), s(small)], "#0000ff,#ff0000"),
        ] {
            let out = dir.path().join("o.png");
            let r = render_json(&[
                args[0],
                args[1],
                "-o",
                s(&out),
                "--view",
                "front",
                "--mesh-colors",
                colours,
                "--width",
                "300",
                "--height",
                "300",
            ]);
            let side = 0.5 * r["pixels_per_unit"].as_f64().unwrap();
            let pic = Picture::read(&out);
            let (n_red, n_blue) = (pic.count(0, 300, red), pic.count(0, 300, blueish));
            // A square of side L px covers L^2 pixel centres give or take 2L + 1; the blue one
            // has four times the side of the red one.
            let big = 16.0 * side * side;
            if seen {
                let n = n_red as f64;
                assert!(
                    (n - side * side).abs() <= 2.0 * side + 1.0,
                    "{n} vs {side}^2"
                );
                assert!((n_blue as f64 - (big - side * side)).abs() <= 10.0 * side + 2.0);
            } else {
                assert_eq!(n_red, 0, "the square behind shows through ({args:?})");
                assert!(
                    (n_blue as f64 - big).abs() <= 8.0 * side + 1.0,
                    "{n_blue} vs {big}"
                );
            }
        }
    }
}

#[test]
fn the_three_projections_show_each_plane_at_one_scale() {
    let dir = scratch("projections");
    let mesh = write_obj(
        dir.path(),
        "box.obj",
        &generate::boxed(Vec3::new(3.0, 2.0, 1.0)),
    );
    let out = dir.path().join("p.png");
    let r = render_json(&[
        s(&mesh),
        "-o",
        s(&out),
        "--view",
        "projections",
        "--width",
        "900",
        "--height",
        "300",
    ]);
    let k = r["pixels_per_unit"].as_f64().unwrap();
    assert_eq!(
        k,
        270.0 / 3.0,
        "the longest side fits a 300 px panel less 5% margins"
    );
    let pic = Picture::read(&out);
    // XY shows 3 x 2, XZ 3 x 1, YZ 2 x 1, each centred in its third of the picture.
    for (panel, (a, b)) in [(3.0, 2.0), (3.0, 1.0), (2.0, 1.0)].into_iter().enumerate() {
        let (x0, x1) = (panel * 300, panel * 300 + 300);
        let shaded = |c: [u8; 3]| c != WHITE && c != BLACK;
        let n = pic.count(x0, x1, shaded) as f64;
        let (w, h) = (a * k, b * k);
        assert!(
            (n - w * h).abs() <= w + h + 1.0,
            "panel {panel}: {n} vs {}",
            w * h
        );
        let (mut sx, mut sy) = (0.0, 0.0);
        for y in 0..300 {
            for x in x0..x1 {
                if shaded(pic.at(x, y)) {
                    sx += x as f64 + 0.5;
                    sy += y as f64 + 0.5;
                }
            }
        }
        assert!((sx / n - (x0 as f64 + 150.0)).abs() < 1.0 && (sy / n - 150.0).abs() < 1.0);
        // The panel's label is drawn in black in its top-left corner.
        assert!(
            pic.count(x0, x0 + 20, |c| c == BLACK) > 10,
            "label of panel {panel}"
        );
    }
}

/// A flat strip of `n` cells along x, stretched by `0.01 i` in cell `i`, as an OBJ with its rest
/// coordinates.
fn stretched_strip(dir: &Path, n: usize) -> PathBuf {
    let (mut positions, mut rest, mut faces) = (Vec::new(), Vec::new(), Vec::new());
    let mut x = 0.0;
    for i in 0..=n {
        for y in [0.0, 0.1] {
            positions.push(Point3::new(x, y, 0.0));
            rest.push([i as f64 * 0.1, y]);
        }
        x += 0.1 * (1.0 + 0.01 * i as f64);
        if i < n {
            let v = 2 * i as u32;
            faces.extend([[v, v + 2, v + 3], [v, v + 3, v + 1]]);
        }
    }
    let path = dir.join("strip.obj");
    let mesh = TriMesh::new(positions, faces);
    drapekit::io::write_atomic(&path, &[], |w| {
        drapekit::io::obj::write_with_rest(w, &mesh, &rest, &[])
    })
    .unwrap();
    path
}

#[test]
fn strain_colours_follow_the_values() {
    let dir = scratch("strain");
    let strip = stretched_strip(dir.path(), 20);
    let out = dir.path().join("s.png");
    let r = render_json(&[
        s(&strip),
        "-o",
        s(&out),
        "--color",
        "strain",
        "--view",
        "top",
        "--width",
        "800",
        "--height",
        "200",
    ]);
    let range = r["value_range"].as_array().unwrap();
    // Cell i's edges along x are stretched by 0.01 i; the rest less. The last vertices: 0.19.
    assert_eq!(range[0].as_f64().unwrap(), 0.0);
    assert!(
        (range[1].as_f64().unwrap() - 0.19).abs() < 1e-12,
        "{range:?}"
    );
    let pic = Picture::read(&out);
    let row = pic.height / 2;
    let lum = |c: [u8; 3]| drapekit::render::colormap::luminance(c);
    // The strip's pixels on the middle row: the first run that is not background.
    let strip_px: Vec<(usize, f64)> = (0..pic.width)
        .map(|x| (x, pic.at(x, row)))
        .skip_while(|&(_, c)| c == WHITE)
        .take_while(|&(_, c)| c != WHITE)
        .map(|(x, c)| (x, lum(c)))
        .collect();
    assert!(strip_px.len() > 400, "{} strip pixels", strip_px.len());
    // Along the strip the strain rises, and so does the colour's lightness (viridis), up to
    // the rounding of one channel.
    assert!(
        strip_px.windows(2).all(|w| w[1].1 >= w[0].1 - 0.25),
        "lightness falls along the strip"
    );
    let (first, last) = (strip_px[0].1, strip_px[strip_px.len() - 1].1);
    assert!(last - first > 100.0, "{first} -> {last}");
    // The ends are the map's ends, dimmed alike by the light.
    let b = first / lum(drapekit::render::colormap::viridis(0.0));
    let b_last = last / lum(drapekit::render::colormap::viridis(1.0));
    assert!((b_last - b).abs() < 0.03, "{first} {last}: {b} {b_last}");
}

#[test]
fn renders_are_byte_identical_whatever_the_thread_count() {
    let dir = scratch("determinism");
    let mut sphere = generate::icosphere(3);
    for p in &mut sphere.positions {
        p.coords *= 0.3;
    }
    let sphere = write_obj(dir.path(), "sphere.obj", &sphere);
    let cloth = write_obj(
        dir.path(),
        "cloth.obj",
        &quad_xz([-0.5, 0.5], [-0.5, 0.5], -0.31),
    );
    let picture = |jobs: &str| {
        let out = dir.path().join(format!("j{jobs}.png"));
        ok(&[
            "--jobs",
            jobs,
            "render",
            s(&cloth),
            s(&sphere),
            "-o",
            s(&out),
            "--color",
            "distance",
            "--view",
            "projections",
            "--width",
            "600",
            "--height",
            "400",
        ]);
        std::fs::read(out).unwrap()
    };
    let one = picture("1");
    assert_eq!(one, picture("2"));
    assert_eq!(one, picture("1"));
}

#[test]
fn bad_input_gets_a_clear_error_and_no_picture() {
    let dir = scratch("bad");
    let mesh = write_obj(dir.path(), "box.obj", &generate::cube(1.0));
    let out = dir.path().join("o.png");
    let cases: &[(&[&str], i32, &str)] = &[
        (&["--view", "sideways"], 2, "unknown view 'sideways'"),
        (
            &["--width", "0"],
            1,
            "picture size 0 x 600 px: each side must be 16 to 8192 px",
        ),
        (&["--color", "strain"], 1, "no rest coordinates"),
        (&["--color", "distance"], 1, "no body with faces"),
        (&["--background", "#12345"], 2, "expected #rrggbb"),
        (&["--range", "2:1"], 2, "MIN < MAX"),
    ];
    for (extra, code, message) in cases {
        let mut args = vec!["render", s(&mesh), "-o", s(&out)];
        args.extend_from_slice(extra);
        let o = common::run(&args);
        let (_, err) = common::text(&o);
        assert_eq!(o.status.code(), Some(*code), "{extra:?}: {err}");
        assert!(err.contains(message), "{extra:?}: {err}");
        assert!(!out.exists());
    }
    let missing = dir.path().join("nope.obj");
    let o = common::run(&["render", s(&missing), "-o", s(&out)]);
    assert!(common::text(&o).1.contains("nope.obj"));
    let o = common::run(&["render", s(&mesh), "-o", s(&dir.path().join("o.jpg"))]);
    assert!(common::text(&o).1.contains("must be .png"));
    assert_eq!(common::listing(dir.path()), ["box.obj"]);
}

/// A small scene in centimetres: a 20 cm square falling freely (no objects), frames every 5
/// steps.
const FALLING: &str = r#"units = "cm"
[solver]
steps = 20
[[piece]]
name = "sq"
outline = [[-10, -10], [10, -10], [10, 10], [-10, 10]]
spacing = 4
position = [0, 0, 50]
fabric = "cotton"
[output]
frames = 5
"#;

#[test]
fn drape_writes_rest_coordinates_frames_animate_and_the_preview() {
    let dir = scratch("drape");
    let scene = dir.path().join("fall.toml");
    std::fs::write(&scene, FALLING).unwrap();
    let out = dir.path().join("out");
    ok(&["drape", s(&scene), "-o", s(&out), "--preview"]);
    // The rest coordinates are the flat pattern, in the scene's unit like the positions.
    let sq = out.join("sq.obj");
    let read = drapekit::io::read_mesh(&sq, &Default::default()).unwrap();
    let rest = read.texcoords.expect("per-vertex rest coordinates");
    let (lo, hi) = rest
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), r| (a.min(r[0]), b.max(r[0])));
    assert_eq!((lo, hi), (-10.0, 10.0));
    // Falling freely, the cloth keeps its flat shape: no strain (a unit mismatch would be 99).
    let r = render_json(&[
        s(&sq),
        "-o",
        s(&dir.path().join("s.png")),
        "--color",
        "strain",
    ]);
    for v in r["value_range"].as_array().unwrap() {
        assert!(v.as_f64().unwrap().abs() < 1e-6, "{r}");
    }
    let preview = Picture::read(&out.join("preview.png"));
    assert_eq!((preview.width, preview.height), (640, 480));
    assert!(
        preview.count(0, 640, |c| c != WHITE) > 10_000,
        "the cloth is drawn"
    );
    // The frames (steps 5, 10, 15, 20) as a GIF and as an animated PNG.
    let gif_path = dir.path().join("fall.gif");
    let r = render_json(&[
        s(&out.join("frames")),
        "-o",
        s(&gif_path),
        "--width",
        "160",
        "--height",
        "120",
    ]);
    assert_eq!(
        (r["frames"].as_u64(), r["format"].as_str()),
        (Some(4), Some("gif"))
    );
    let mut dec = gif::DecodeOptions::new()
        .read_info(std::fs::File::open(&gif_path).unwrap())
        .unwrap();
    let mut frames = 0;
    while let Some(f) = dec.read_next_frame().unwrap() {
        assert_eq!((f.width, f.height), (160, 120));
        frames += 1;
    }
    assert_eq!(frames, 4);
    let apng = dir.path().join("fall.png");
    render_json(&[
        s(&out.join("frames")),
        "-o",
        s(&apng),
        "--width",
        "160",
        "--height",
        "120",
    ]);
    let reader = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&apng).unwrap()))
        .read_info()
        .unwrap();
    assert_eq!(
        reader.info().animation_control.map(|a| a.num_frames),
        Some(4)
    );
}

#[test]
fn convert_and_fit_previews_are_written_beside_the_output() {
    let dir = scratch("previews");
    let out = dir.path().join("box.obj");
    ok(&[
        "convert",
        s(&common::fixture("box_quads_lisp.txt")),
        "-o",
        s(&out),
        "--preview",
    ]);
    let pic = Picture::read(&dir.path().join("box.png"));
    assert!(pic.count(0, pic.width, |c| c != WHITE) > 20_000);
    let form = dir.path().join("form.obj");
    ok(&[
        "fit",
        "--measurements",
        s(&common::fixture("measurements_size38.toml")),
        "-o",
        s(&form),
        "--preview",
    ]);
    let pic = Picture::read(&dir.path().join("form.png"));
    // A standing form seen from the front is taller than wide.
    let rows = (0..pic.height)
        .filter(|&y| (0..pic.width).any(|x| pic.at(x, y) != WHITE))
        .count();
    let cols = (0..pic.width)
        .filter(|&x| (0..pic.height).any(|y| pic.at(x, y) != WHITE))
        .count();
    assert!(rows * 2 > cols * 3, "{rows} rows, {cols} columns");
}

/// Runs `render ARGS`; asserts exit status 1 and a message with `message`; returns stderr.
fn refused(args: &[&str], message: &str) -> String {
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    let o = common::run(&all);
    let (_, err) = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert!(err.contains(message), "{args:?}: {err}");
    err
}

#[test]
fn flags_and_the_output_are_refused_before_any_input_is_read() {
    // The input does not exist: each refusal comes before reading it.
    let dir = scratch("early");
    let nope = dir.path().join("nope.obj");
    let folder = dir.path().join("folder.png");
    std::fs::create_dir(&folder).unwrap();
    let out = dir.path().join("o.png");
    let err = refused(
        &[s(&nope), "-o", s(&out), "--width", "15"],
        "picture size 15",
    );
    assert!(!err.contains("nope.obj"), "{err}");
    let narrow = [
        s(&nope),
        "-o",
        s(&out),
        "--width",
        "40",
        "--view",
        "projections",
    ];
    refused(&narrow, "no room for 3 panel(s)");
    let err = refused(&[s(&nope), "-o", s(&folder)], "exists and is not a file");
    assert!(!err.contains("caused by"), "the cause is said once: {err}");
    let lost = dir.path().join("no/such/folder/o.png");
    refused(&[s(&nope), "-o", s(&lost)], "does not exist");
    // 0.01 fps is a delay of 100 s, beyond APNG's 65.535 s: once clamped, now refused.
    refused(&[s(&nope), "-o", s(&out), "--fps", "0.01"], "--fps 0.01");
    let two = [s(&nope), "-o", s(&out), "--mesh-colors", "#ff0000,#00ff00"];
    refused(&two, "--mesh-colors: 2 colours for 1 mesh(es)");
    let mesh = write_obj(dir.path(), "box.obj", &generate::cube(1.0));
    let contact = [s(&mesh), "-o", s(&out), "--color", "contact"];
    refused(&contact, "--color contact:");
    // --to with strain was ignored without a word; a body without faces was not named.
    let strain_to = [
        s(&mesh),
        "-o",
        s(&out),
        "--color",
        "strain",
        "--to",
        s(&mesh),
    ];
    refused(
        &strain_to,
        "--to gives the body of --color distance or contact",
    );
    let points = dir.path().join("points.obj");
    std::fs::write(&points, "v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    let to_points = [
        s(&mesh),
        "-o",
        s(&out),
        "--color",
        "distance",
        "--to",
        s(&points),
    ];
    refused(&to_points, "points.obj: the body has no faces");
    std::fs::remove_file(&points).unwrap();
    // A span beyond the numbers coloured every value as the minimum.
    let o = common::run(&["render", s(&mesh), "-o", s(&out), "--range=-1e308:1e308"]);
    assert_eq!(o.status.code(), Some(2), "{}", common::text(&o).1);
    // A strain of 1e90 / 1e-250: 'mesh 0: the value of vertex 0 is not finite', no file.
    let far = dir.path().join("far.obj");
    let obj = "v 0 0 0\nv 1e90 0 0\nv 0 1 0\nvt 0 0\nvt 1e-250 0\nvt 0 1\nf 1/1 2/2 3/3\n";
    std::fs::write(&far, obj).unwrap();
    refused(
        &[s(&far), "-o", s(&out), "--color", "strain"],
        "far.obj: strain",
    );
    std::fs::remove_file(&far).unwrap();
    assert_eq!(common::listing(dir.path()), ["box.obj", "folder.png"]);
}

#[test]
fn a_frames_folder_of_mixed_frames_is_refused_with_every_problem() {
    let dir = scratch("mixed");
    let out = dir.path().join("o.png");
    let frames = |name: &str, files: &[(&str, TriMesh)]| {
        let f = dir.path().join(name);
        std::fs::create_dir(&f).unwrap();
        for (file, mesh) in files {
            write_obj(&f, file, mesh);
        }
        f
    };
    let (cube, quad) = (generate::cube(1.0), quad_xz([0.0, 1.0], [0.0, 1.0], 0.0));
    let runs = frames(
        "runs",
        &[
            ("sq_0000010.obj", quad.clone()),
            ("sq_0000020.obj", quad.clone()),
            ("cape_0000020.obj", quad.clone()),
            ("sq_0000030.obj", cube.clone()),
        ],
    );
    let err = refused(
        &[s(&runs), "-o", s(&out)],
        "2 problems in the frames folder",
    );
    assert!(
        err.contains("step 20 has the piece(s) cape, sq, step 10 has sq"),
        "{err}"
    );
    assert!(
        err.contains("sq_0000030.obj has 8 vertices and 12 faces"),
        "{err}"
    );
    let twice = frames(
        "twice",
        &[("a_01.obj", quad.clone()), ("a_1.obj", quad.clone())],
    );
    refused(
        &[s(&twice), "-o", s(&out)],
        "a_01.obj and a_1.obj are both piece 'a' at step 1",
    );
    assert!(!out.exists());
    // The same pieces at every step, each with its mesh: an animation.
    let good = frames(
        "good",
        &[
            ("a_b_9999999.obj", quad.clone()),
            ("a_9999999.obj", cube.clone()),
            ("a_b_10000000.obj", quad.clone()),
            ("a_10000000.obj", cube),
        ],
    );
    let report = render_json(&[s(&good), "-o", s(&out), "--width", "64", "--height", "48"]);
    assert_eq!(report["frames"], 2);
}

#[cfg(unix)]
#[test]
fn sigterm_stops_an_animation_between_frames_and_leaves_nothing() {
    let dir = scratch("sigterm");
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let ball = generate::icosphere(3);
    for k in 0..200 {
        write_obj(&frames, &format!("ball_{k:07}.obj"), &ball);
    }
    // A stale temporary picture of a killed render (its writer's id is past Linux's largest).
    let stale = dir.path().join(".drapekit-tmp-4194305-anim.gif.a1B2c3.tmp");
    std::fs::write(&stale, "half a picture").unwrap();
    let out = dir.path().join("anim.gif");
    let child = common::drapekit()
        .args([
            "render",
            s(&frames),
            "-o",
            s(&out),
            "--width",
            "1024",
            "--height",
            "1024",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The stale file goes first; its own temporary picture appears as the first frame is drawn.
    let start = std::time::Instant::now();
    while stale.exists() || common::listing(dir.path()).len() < 2 {
        assert!(
            start.elapsed().as_secs() < 600,
            "no picture begun in 10 minutes"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // SAFETY: a signal to the child we started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let o = child.wait_with_output().unwrap();
    let err = common::text(&o).1;
    assert_eq!(o.status.code(), Some(143), "{err}");
    assert!(
        err.contains("interrupted by SIGTERM while drawing"),
        "{err}"
    );
    assert!(
        err.contains("removed 1 temporary file"),
        "the stale one: {err}"
    );
    assert_eq!(common::listing(dir.path()), ["frames"]);
}
