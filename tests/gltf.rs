//! glTF 2.0: round trips, the Khronos validator and trimesh on what drapekit writes, the real
//! seats against their OBJ siblings, malformed files, and a drape's objects as placed.

mod common;

use drapekit::io::gltf::{self, Frame, Part, Scene, Surface};
use drapekit::io::{read_mesh, write_mesh, WriteOptions};
use drapekit::math::{Point3, SplitMix};
use drapekit::mesh::TriMesh;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A grid of `n x n` vertices with awkward coordinates (every one an f32, most not short
/// decimals) and its triangles.
fn sheet(n: u32, seed: u64) -> TriMesh {
    let mut r = SplitMix(seed);
    let mut positions = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let jitter = |r: &mut SplitMix| (r.next_f64() - 0.5) * 1e-3;
            let p = [
                f64::from(i) * 0.1 + jitter(&mut r),
                f64::from(j) * 0.1 + jitter(&mut r),
                jitter(&mut r) - 123.456,
            ];
            positions.push(Point3::from(p.map(|c| f64::from(c as f32))));
        }
    }
    let mut faces = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v = j * n + i;
            faces.push([v, v + 1, v + n + 1]);
            faces.push([v, v + n + 1, v + n]);
        }
    }
    TriMesh::new(positions, faces)
}

/// Made-up vertex colours (the strain colours come from the render command): channels in
/// steps of 0.2, each a little above a whole number of 255ths as an f32.
fn rainbow(n: usize) -> Vec<[f32; 4]> {
    let step = |k: usize| (k % 6) as f32 * 0.2;
    (0..n).map(|i| [step(i), step(i + 2), 0.4, 1.0]).collect()
}

/// The colours as 0-255 RGBA, summed.
fn color_sum(colors: &[[f32; 4]]) -> [u64; 4] {
    let mut s = [0; 4];
    for c in colors {
        for k in 0..4 {
            s[k] += (c[k] * 255.0).round() as u64;
        }
    }
    s
}

#[test]
fn glb_and_gltf_round_trip_positions_bit_for_bit_and_faces() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = sheet(9, 7);
    for name in ["x.glb", "x.gltf"] {
        let path = dir.path().join(name);
        write_mesh(&path, &mesh, &WriteOptions::default(), &[]).unwrap();
        let back = read_mesh(&path, &Default::default()).unwrap();
        assert_eq!(back.mesh.positions, mesh.positions, "{name}");
        assert_eq!(back.mesh.faces, mesh.faces, "{name}");
        assert_eq!(back.info.format, &name[2..]);
    }
    // Several parts, one with colours: read back as one mesh, the parts in order.
    let other = sheet(4, 8);
    let mut a = Part::new("a", mesh.clone(), Surface::Cloth);
    a.colors = Some(rainbow(mesh.positions.len()));
    let scene = Scene {
        parts: vec![a, Part::new("b", other.clone(), Surface::Solid)],
        frames: Vec::new(),
    };
    let path = dir.path().join("two.glb");
    gltf::write_scene(&path, &scene, &[]).unwrap();
    let back = read_mesh(&path, &Default::default()).unwrap().mesh;
    let n = mesh.positions.len();
    assert_eq!(back.positions[..n], mesh.positions[..]);
    assert_eq!(back.positions[n..], other.positions[..]);
    let shifted: Vec<[u32; 3]> = other
        .faces
        .iter()
        .map(|f| f.map(|v| v + n as u32))
        .collect();
    assert_eq!(back.faces[mesh.faces.len()..], shifted[..]);
}

/// Runs drapekit, asserting success; returns stdout.
fn ok(args: &[&str]) -> String {
    let o = common::run(args);
    let (stdout, stderr) = common::text(&o);
    assert!(o.status.success(), "{args:?}: {stderr}");
    stdout
}

/// A short drop of a square on two copies of the 30 cm sphere (one `up = "y"`, both scaled and
/// translated), in centimetres; the piece is named like the sphere's file.
fn two_sphere_scene(dir: &Path, output: &str) -> PathBuf {
    let sphere = common::fixture("scenes/sphere_r0.3.obj");
    let text = format!(
        r#"units = "cm"
[solver]
steps = 12
[[object]]
mesh = "{s}"
scale = 100.0
translate = [5.0, -2.0, 1.0]
[[object]]
mesh = "{s}"
up = "y"
scale = 50.0
translate = [90.0, 0.0, -20.0]
[[piece]]
name = "sphere_r0.3"
outline = [[-40, -40], [40, -40], [40, 40], [-40, 40]]
spacing = 5
position = [5.0, -2.0, 33.0]
{output}"#,
        s = sphere.display()
    );
    let path = dir.join("drop.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn drape_writes_the_objects_as_placed_where_the_colliders_are() {
    let dir = tempfile::tempdir().unwrap();
    let scene = two_sphere_scene(dir.path(), "[output]\nply = true\n");
    let out = dir.path().join("out");
    let r: Value = serde_json::from_str(&ok(&[
        "drape",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    // Two objects of one file and a piece of that name: three distinct names.
    assert_eq!(
        common::listing(&out),
        [
            "sphere_r0.3.obj",
            "sphere_r0.3.ply",
            "sphere_r0.3_2.obj",
            "sphere_r0.3_2.ply",
            "sphere_r0.3_3.obj",
            "sphere_r0.3_3.ply"
        ]
    );
    assert_eq!(
        r["objects"][1]["files"][0],
        out.join("sphere_r0.3_3.obj").display().to_string()
    );
    // Each file is the collider's mesh, in the scene's units, to the last bit.
    let sc = drapekit::scene::read(&scene).unwrap();
    let world = drapekit::sim::load(&sc).unwrap();
    for (i, name) in ["sphere_r0.3_2", "sphere_r0.3_3"].iter().enumerate() {
        let collider = &world.colliders[i].mesh;
        for ext in ["obj", "ply"] {
            let placed = read_mesh(&out.join(format!("{name}.{ext}")), &Default::default())
                .unwrap()
                .mesh;
            let cm: Vec<Point3> = collider.positions.iter().map(|p| p * 100.0).collect();
            assert!(
                placed.positions == cm,
                "{name}.{ext}: not the collider's vertices"
            );
            assert!(
                placed.faces == collider.faces,
                "{name}.{ext}: not the collider's faces"
            );
        }
    }
    // And where the scene says: every vertex at the scaled radius about the translated centre
    // (the fixture's vertices, written to 9 decimals, lie on the sphere to 2.1e-9 of its radius).
    for (name, centre, radius) in [
        ("sphere_r0.3_2", [5.0, -2.0, 1.0], 30.0),
        ("sphere_r0.3_3", [90.0, 0.0, -20.0], 15.0),
    ] {
        let placed = read_mesh(&out.join(format!("{name}.obj")), &Default::default())
            .unwrap()
            .mesh;
        let c = Point3::from(centre);
        let worst = placed
            .positions
            .iter()
            .map(|p| ((p - c).norm() - radius).abs())
            .fold(0.0, f64::max);
        assert!(worst < 2.5e-9 * radius, "{name}: {worst}");
    }
}

#[test]
fn written_files_pass_the_khronos_validator_and_load_in_trimesh() {
    let Some(tools) = common::tools() else { return };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // convert: an OBJ to .glb and .gltf.
    let sphere = common::fixture("scenes/sphere_r0.3.obj");
    let convert_glb = d.join("sphere.glb");
    let convert_gltf = d.join("sphere.gltf");
    for o in [&convert_glb, &convert_gltf] {
        ok(&[
            "convert",
            sphere.to_str().unwrap(),
            "-o",
            o.to_str().unwrap(),
        ]);
    }
    // A drape with objects; the same with frames (an animation).
    let still = two_sphere_scene(d, "");
    ok(&[
        "drape",
        still.to_str().unwrap(),
        "-o",
        d.join("still").to_str().unwrap(),
        "--glb",
    ]);
    let moving = d.join("moving");
    std::fs::create_dir(&moving).unwrap();
    let animated = two_sphere_scene(&moving, "[output]\nframes = 5\n");
    ok(&[
        "drape",
        animated.to_str().unwrap(),
        "-o",
        moving.join("out").to_str().unwrap(),
        "--glb",
    ]);
    // Made-up colours on two parts and three frames.
    let colored = d.join("colored.glb");
    let part = |name: &str, m: &TriMesh| {
        let mut p = Part::new(name, m.clone(), Surface::Cloth);
        p.colors = Some(rainbow(m.positions.len()));
        p
    };
    let (a, b) = (sheet(5, 1), sheet(3, 2));
    let frames = (0..3)
        .map(|k| Frame {
            time: 0.25 * f64::from(k),
            parts: vec![part("a", &a), part("b", &b)],
        })
        .collect();
    let scene = Scene {
        parts: vec![part("still", &b)],
        frames,
    };
    gltf::write_scene(&colored, &scene, &[]).unwrap();
    let files = [
        convert_glb.clone(),
        convert_gltf.clone(),
        d.join("still/drop.glb"),
        moving.join("out/drop.glb"),
        colored.clone(),
    ];
    let paths: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    for report in tools.validate(&paths) {
        assert_eq!(report["errors"], 0, "{report}");
        assert_eq!(report["warnings"], 0, "{report}");
        assert_eq!(report["infos"], 0, "{report}");
    }
    // trimesh: every mesh in the file (frames too), so the counts are what was written.
    let converted = read_mesh(&sphere, &Default::default()).unwrap().mesh;
    let r: Value = serde_json::from_str(&ok(&[
        "drape",
        still.to_str().unwrap(),
        "-o",
        d.join("still2").to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    let cloth_v = r["particles"].as_u64().unwrap();
    let cloth_f = r["pieces"][0]["triangles"].as_u64().unwrap();
    let obj_f = r["object_faces"].as_u64().unwrap();
    let obj_v = 2 * converted.positions.len() as u64;
    // The animated drop: frames at steps 5 and 10, and the end (12).
    let expected = [
        (
            converted.positions.len() as u64,
            converted.faces.len() as u64,
        ),
        (
            converted.positions.len() as u64,
            converted.faces.len() as u64,
        ),
        (obj_v + cloth_v, obj_f + cloth_f),
        (obj_v + 3 * cloth_v, obj_f + 3 * cloth_f),
        (9 + 3 * (25 + 9), 8 + 3 * (32 + 8)),
    ];
    let loaded = tools.trimesh(&paths);
    for (t, (v, f)) in loaded.iter().zip(expected) {
        let counts = (t["vertices"].as_u64(), t["faces"].as_u64());
        assert_eq!(counts, (Some(v), Some(f)), "{t}");
    }
    // The colours arrive: 7 coloured meshes, the sum of their 0-255 colours as written.
    let written = [rainbow(9), rainbow(25), rainbow(9)].map(|c| color_sum(&c));
    let want: Vec<u64> = (0..4)
        .map(|k| written[0][k] + 3 * (written[1][k] + written[2][k]))
        .collect();
    assert_eq!(loaded[4]["colored"], 7, "{}", loaded[4]);
    // A drape's cloth carries its strain colours (the objects none): one piece, then 3 frames.
    assert_eq!(loaded[2]["colored"], 1, "{}", loaded[2]);
    assert_eq!(loaded[3]["colored"], 3, "{}", loaded[3]);
    assert_eq!(
        loaded[4]["color_sum"],
        serde_json::json!(want),
        "{}",
        loaded[4]
    );
    // drapekit reads the animated file as a static viewer shows it: the objects and the end.
    let m = read_mesh(&moving.join("out/drop.glb"), &Default::default()).unwrap();
    assert_eq!(m.mesh.positions.len() as u64, obj_v + cloth_v);
    assert_eq!(m.mesh.faces.len() as u64, obj_f + cloth_f);
}

/// The seats' glTF files (Poly Haven, through Blender) read like their OBJ siblings (trimesh's
/// export of the same vertices, 8 decimals): same counts, same faces, same box to 5e-9.
#[test]
fn the_real_seats_read_like_their_obj_siblings() {
    let Some(real) = common::realdata() else {
        return;
    };
    for stem in ["painted_wooden_stool_1k", "sofa_03_1k"] {
        let seats = real.join("seats");
        let g = read_mesh(&seats.join(format!("{stem}.gltf")), &Default::default()).unwrap();
        let o = read_mesh(&seats.join(format!("{stem}.obj")), &Default::default())
            .unwrap()
            .mesh;
        assert_eq!(g.info.format, "gltf");
        assert_eq!(g.mesh.positions.len(), o.positions.len(), "{stem}");
        assert_eq!(g.mesh.faces, o.faces, "{stem}");
        let worst = g
            .mesh
            .positions
            .iter()
            .zip(&o.positions)
            .map(|(a, b)| (a - b).amax())
            .fold(0.0, f64::max);
        assert!(worst <= 5e-9, "{stem}: {worst}");
        let (bg, bo) = (g.mesh.bbox().unwrap(), o.bbox().unwrap());
        assert!(
            (bg.min - bo.min).amax() <= 5e-9 && (bg.max - bo.max).amax() <= 5e-9,
            "{stem}"
        );
    }
    // The stool's box is the one its POSITION accessor declares (min/max, exact).
    let s = read_mesh(
        &real.join("seats/painted_wooden_stool_1k.gltf"),
        &Default::default(),
    )
    .unwrap()
    .mesh;
    let b = s.bbox().unwrap();
    assert_eq!(b.max.y, 0.5779256820678711);
    assert_eq!(b.min.x, -0.18747957050800323);
}

/// A written `.gltf` of a small sheet, as JSON to edit.
fn gltf_json(dir: &Path) -> Value {
    let path = dir.join("base.gltf");
    write_mesh(&path, &sheet(3, 3), &WriteOptions::default(), &[]).unwrap();
    serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap()
}

/// A change to a glTF document.
type Edit = Box<dyn Fn(&mut Value)>;

/// The error reading `name` holding `bytes`.
fn error(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    read_mesh(&path, &Default::default())
        .unwrap_err()
        .to_string()
}

#[test]
fn malformed_gltf_files_get_errors_naming_the_file_and_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let glb = d.join("ok.glb");
    write_mesh(&glb, &sheet(3, 3), &WriteOptions::default(), &[]).unwrap();
    let bytes = std::fs::read(&glb).unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "cut.glb",
            bytes[..bytes.len() - 7].to_vec(),
            "cut.glb: byte 8 (length): truncated binary glTF: the file, by the header's length field, needs",
        ),
        (
            "magic.glb",
            [b"glTX", &bytes[4..]].concat(),
            "magic.glb: byte 0 (magic): not a binary glTF: the file starts with \"glTX\"",
        ),
    ];
    for (name, b, needle) in cases {
        let e = error(d, name, &b);
        assert!(e.contains(needle), "{name}: {e}");
    }
    // A NaN in the first position (the BIN chunk starts after the JSON chunk).
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut nan = bytes.clone();
    let at = 12 + 8 + json_len + 8;
    nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = error(d, "nan.glb", &nan);
    assert!(e.contains("nan.glb: accessors[0] element 0 (meshes[0].primitives[0].attributes.POSITION): non-finite coordinate NaN"), "{e}");
    let base = gltf_json(d);
    let edits: Vec<(&str, Edit, &str)> = vec![
        ("accessor.gltf", Box::new(|j| j["meshes"][0]["primitives"][0]["indices"] = 9.into()),
         "accessor.gltf: meshes[0].primitives[0].indices: accessor 9 does not exist: the file has 3"),
        ("short.gltf", Box::new(|j| j["accessors"][0]["count"] = 10.into()),
         "short.gltf: accessors[0]: 10 elements of 12 bytes (stride 12) from byte 0 needs 120 bytes, but bufferView 0 holds 108"),
        ("view.gltf", Box::new(|j| j["bufferViews"][2]["byteOffset"] = 100_000.into()),
         "view.gltf: bufferViews[2]: bufferView 2 (bytes 100000 to 100096) needs 100096 bytes, but buffer 0 holds"),
        ("missing.gltf", Box::new(|j| j["buffers"][0]["uri"] = "missing%20data.bin".into()),
         "missing.gltf: buffers[0].uri: buffer file"),
        ("lines.gltf", Box::new(|j| j["meshes"][0]["primitives"][0]["mode"] = 1.into()),
         "lines.gltf: meshes[0].primitives[0].mode: primitive mode 1 (Lines): drapekit reads triangles (mode 4, TRIANGLES) only"),
        ("index.gltf", Box::new(|j| j["accessors"][0]["count"] = 4.into()),
         "(meshes[0].primitives[0].indices): vertex index 4 is out of range: the file has 4 vertices"),
        ("draco.gltf", Box::new(|j| j["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"])),
         "draco.gltf: extensionsRequired: the required extension KHR_draco_mesh_compression is not supported"),
        ("cycle.gltf", Box::new(|j| j["nodes"][0]["children"] = serde_json::json!([0])),
         "cycle.gltf: nodes[0]: expected nodes that form trees (one parent each, no cycles), found 'node 0 reached a second time'"),
    ];
    for (name, edit, needle) in edits {
        let mut j = base.clone();
        edit(&mut j);
        let e = error(d, name, &serde_json::to_vec(&j).unwrap());
        assert!(e.contains(needle), "{name}: {e}");
    }
    // The missing file is named as the reader looked for it (the URI percent-decoded).
    let missing = d.join("missing data.bin").display().to_string();
    let e = error(
        d,
        "missing.gltf",
        &std::fs::read(d.join("missing.gltf")).unwrap(),
    );
    assert!(
        e.contains(&format!("buffer file '{missing}' cannot be read")),
        "{e}"
    );
    // The same through the command: exit status 1 and the message.
    let o = common::run(&[
        "convert",
        d.join("cut.glb").to_str().unwrap(),
        "-o",
        d.join("x.obj").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(common::text(&o).1.contains("truncated binary glTF"));
    assert!(!d.join("x.obj").exists());
}

/// Node transforms: a child node (translated, turned a quarter about z, mirrored in x) under a
/// translated parent places each vertex at `T_parent T R S p` and turns each triangle back.
#[test]
fn node_transforms_place_the_mesh_and_a_mirror_turns_its_triangles_back() {
    let dir = tempfile::tempdir().unwrap();
    let mut j = gltf_json(dir.path());
    let h = std::f64::consts::FRAC_1_SQRT_2;
    j["nodes"] = serde_json::json!([
        {"children": [1], "translation": [10.0, 0.0, 0.0]},
        {"mesh": 0, "translation": [1.0, 2.0, 3.0], "rotation": [0.0, 0.0, h, h], "scale": [-1.0, 1.0, 2.0]}
    ]);
    j["scenes"][0]["nodes"] = serde_json::json!([0]);
    let path = dir.path().join("placed.gltf");
    std::fs::write(&path, serde_json::to_vec(&j).unwrap()).unwrap();
    let got = read_mesh(&path, &Default::default()).unwrap().mesh;
    let sheet = sheet(3, 3);
    for (p, q) in sheet.positions.iter().zip(&got.positions) {
        // S: (-x, y, 2z); R: (x, y) -> (-y, x); then + (1, 2, 3) + (10, 0, 0).
        let want = Point3::new(-p.y + 11.0, -p.x + 2.0, 2.0 * p.z + 3.0);
        assert!((want - q).amax() < 1e-12 * want.coords.amax(), "{want} {q}");
    }
    let flipped: Vec<[u32; 3]> = sheet.faces.iter().map(|f| [f[0], f[2], f[1]]).collect();
    assert_eq!(got.faces, flipped);
}
