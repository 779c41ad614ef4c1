//! Round-trips and invariants: geometry survives every format, orientation is idempotent, a
//! randomly flipped box comes back identical, prepared meshes are wound consistently outward.

mod common;
use common::{assert_closed_components_outward, fixture, run, text};
use drapekit::io::{read_mesh, write_mesh, ReadOptions, WriteOptions};
use drapekit::math::Point3;
use drapekit::mesh::prepare::{prepare, PrepareOptions};
use drapekit::mesh::{generate, TriMesh};

/// A mesh with awkward numbers: non-terminating binary fractions, tiny, huge, negative zero.
fn awkward_mesh() -> TriMesh {
    let mut m = generate::icosphere(2);
    for p in m.positions.iter_mut() {
        p.coords *= 123.456_789;
        p.x += 0.1 + 0.2;
    }
    m.positions[3].x = -0.0;
    m.positions[7].y = 1.5e-300;
    m.positions[5].z = 9.876_543_210_123_457e5;
    m
}

/// Whether `a` and `b` have the same triangles, corner for corner (vertex numbering may differ).
fn same_triangles(a: &TriMesh, b: &TriMesh, round: impl Fn(Point3) -> Point3) -> bool {
    a.faces.len() == b.faces.len()
        && (0..a.faces.len()).all(|f| a.corners(f).map(&round) == b.corners(f))
}

#[test]
fn every_format_preserves_geometry() {
    let m = awkward_mesh();
    let dir = tempfile::tempdir().unwrap();
    for (name, ascii, exact) in [
        ("m.txt", false, true),
        ("m.obj", false, true),
        ("m.ply", false, true),
        ("m_ascii.ply", true, true),
        ("m_ascii.stl", true, true),
        ("m.stl", false, false),
    ] {
        let p = dir.path().join(name);
        write_mesh(
            &p,
            &m,
            &WriteOptions {
                format: None,
                ascii,
            },
            &[],
        )
        .unwrap();
        let back = read_mesh(&p, &ReadOptions::default()).unwrap().mesh;
        let f32_round = |p: Point3| p.map(|c| c as f32 as f64);
        let ok = if exact {
            same_triangles(&m, &back, |p| p)
        } else {
            same_triangles(&m, &back, f32_round)
        };
        assert!(ok, "{name} changed the geometry");
    }
}

#[test]
fn convert_round_trips_through_every_format_via_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src.obj");
    let m = awkward_mesh();
    write_mesh(&src, &m, &WriteOptions::default(), &[]).unwrap();
    let mut prev = src.clone();
    for (i, ext) in ["txt", "ply", "stl", "obj", "ply", "txt"]
        .iter()
        .enumerate()
    {
        let next = dir.path().join(format!("step{i}.{ext}"));
        let mut args = vec![
            "convert",
            prev.to_str().unwrap(),
            "-o",
            next.to_str().unwrap(),
        ];
        if *ext == "stl" {
            args.push("--ascii");
        }
        let o = run(&args);
        assert!(o.status.success(), "{}", text(&o).1);
        prev = next;
    }
    let back = read_mesh(&prev, &ReadOptions::default()).unwrap().mesh;
    assert!(
        same_triangles(&m, &back, |p| p),
        "geometry changed along txt -> ply -> stl -> obj -> ply -> txt"
    );
}

#[test]
fn vertex_triples_round_trip_bit_exactly() {
    let m = awkward_mesh();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m.txt");
    write_mesh(&p, &m, &WriteOptions::default(), &[]).unwrap();
    let back = read_mesh(&p, &ReadOptions::default()).unwrap().mesh;
    for f in 0..m.faces.len() {
        let a = m.corners(f);
        let b = back.corners(f);
        for k in 0..3 {
            for c in 0..3 {
                assert_eq!(a[k][c].to_bits(), b[k][c].to_bits());
            }
        }
    }
}

/// Flips faces of `m` with a fixed pseudo-random pattern.
fn flip_some(m: &mut TriMesh, seed: u64) -> usize {
    let mut rng = drapekit::cli::SplitMix(seed);
    let mut n = 0;
    for f in 0..m.faces.len() {
        if rng.next_f64() < 0.5 {
            m.flip_face(f);
            n += 1;
        }
    }
    n
}

#[test]
fn randomly_flipped_box_comes_out_identical() {
    let original = generate::boxed(drapekit::math::Vec3::new(3.0, 2.0, 1.0));
    for seed in 1..20 {
        let mut m = original.clone();
        let flipped = flip_some(&mut m, seed);
        let dir = tempfile::tempdir().unwrap();
        let stl = dir.path().join("box.stl");
        write_mesh(&stl, &m, &WriteOptions::default(), &[]).unwrap();
        let out = dir.path().join("box.obj");
        let o = run(&[
            "convert",
            stl.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--json",
        ]);
        assert!(o.status.success());
        let report: serde_json::Value = serde_json::from_str(&text(&o).0).unwrap();
        // Exactly the faces that were flipped go back, whether they were a minority or not.
        assert_eq!(report["flipped_faces"], flipped as u64, "seed {seed}");
        let back = read_mesh(&out, &ReadOptions::default()).unwrap().mesh;
        assert!(
            same_triangles(&original, &back, |p| p),
            "seed {seed}: the box did not come back identical"
        );
    }
}

#[test]
fn prepared_meshes_are_outward_and_prepare_is_idempotent() {
    let mut meshes = vec![("flipped icosphere".to_string(), {
        let mut m = generate::icosphere(3);
        flip_some(&mut m, 7);
        m
    })];
    for f in ["box_quads_lisp.txt", "tetra_3dface.txt"] {
        meshes.push((
            f.into(),
            read_mesh(&fixture(f), &ReadOptions::default())
                .unwrap()
                .mesh,
        ));
    }
    for (name, mut m) in meshes {
        prepare(&mut m, &PrepareOptions::default());
        assert_closed_components_outward(&m, &name);
        let once = m.clone();
        let r = prepare(&mut m, &PrepareOptions::default());
        assert_eq!(
            (
                r.flipped_faces,
                r.welded_vertices,
                r.degenerate_faces,
                r.duplicate_faces
            ),
            (0, 0, 0, 0),
            "{name}"
        );
        assert_eq!(m, once, "{name}: prepare twice changed the mesh");
    }
}

#[test]
fn convert_twice_gives_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.ply");
    let b = dir.path().join("b.ply");
    let src = fixture("box_quads_lisp.txt");
    assert!(
        run(&["convert", src.to_str().unwrap(), "-o", a.to_str().unwrap()])
            .status
            .success()
    );
    let o = run(&[
        "convert",
        a.to_str().unwrap(),
        "-o",
        b.to_str().unwrap(),
        "--json",
    ]);
    let r: serde_json::Value = serde_json::from_str(&text(&o).0).unwrap();
    assert_eq!(r["flipped_faces"], 0);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

#[test]
fn up_axis_change_is_a_rotation_and_units_scale() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box_m_y.obj");
    let src = fixture("box_quads_lisp.txt");
    let o = run(&[
        "convert",
        src.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--units",
        "mm",
        "--to-units",
        "m",
        "--up",
        "z",
        "--to-up",
        "y",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o).1);
    let m = read_mesh(&out, &ReadOptions::default()).unwrap().mesh;
    let b = m.bbox().unwrap();
    // 100 x 60 x 40 mm, Z-up -> 0.1 x 0.04 x 0.06 m, Y-up (the old z is the new y, the old y the new -z).
    assert!(
        (b.size() - drapekit::math::Vec3::new(0.1, 0.04, 0.06)).norm() < 1e-15,
        "{:?}",
        b.size()
    );
    assert!((b.max.z - 0.0).abs() < 1e-15 && (b.min.z + 0.06).abs() < 1e-15);
    assert!(
        (m.signed_volume() - 0.1 * 0.06 * 0.04).abs() < 1e-15,
        "a mirror would make the volume negative"
    );
}

#[test]
fn quad_split_rules_from_the_cli() {
    // One long thin quad per line: the paper's split uses diagonal r1-r3, `shortest` uses r2-r4.
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("q.txt");
    std::fs::write(&src, "0 0 0 10 0 0 11 1 0 1 1 0\n").unwrap();
    for (rule, diag) in [("paper", [0u32, 2]), ("shortest", [1, 3])] {
        let out = dir.path().join(format!("{rule}.obj"));
        let o = run(&[
            "convert",
            src.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quad-split",
            rule,
            "--no-orient",
        ]);
        assert!(o.status.success());
        let m = read_mesh(&out, &ReadOptions::default()).unwrap().mesh;
        let p = |i: u32| {
            Point3::new(
                [0.0, 10.0, 11.0, 1.0][i as usize],
                [0.0, 0.0, 1.0, 1.0][i as usize],
                0.0,
            )
        };
        // Both triangles contain both ends of the chosen diagonal.
        for f in 0..2 {
            let c = m.corners(f);
            assert!(
                c.contains(&p(diag[0])) && c.contains(&p(diag[1])),
                "{rule}: {c:?}"
            );
        }
    }
}

#[test]
fn inspect_reports_json_keys() {
    let o = run(&[
        "inspect",
        fixture("box_quads_lisp.txt").to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success());
    let r: serde_json::Value = serde_json::from_str(&text(&o).0).unwrap();
    assert_eq!(r["faces"], 12);
    assert_eq!(r["vertices"], 8);
    assert_eq!(r["winding_consistent"], false);
    assert_eq!(r["shell_state"], "regular");
    assert_eq!(r["euler_characteristic"], 2);
    assert_eq!(r["watertight"], true);
    assert_eq!(r["read"]["polygons"]["quads"], 6);
    let v = r["volumes"][0]["volume"].as_f64().unwrap();
    // Eight of twelve faces point outward: the majority winding gives the true volume.
    assert!((v - 240_000.0).abs() < 1e-6, "{v}");
}

#[test]
fn inspect_shows_small_sizes_and_refuses_a_bad_report_first() {
    let dir = tempfile::tempdir().unwrap();
    // A tetrahedron of 1 mm in metres: its volume of 1.7e-10 showed as 0.000000.
    let tet = dir.path().join("tet.obj");
    let obj =
        "v 0 0 0\nv 0.001 0 0\nv 0 0.001 0\nv 0 0 0.001\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    std::fs::write(&tet, obj).unwrap();
    let o = run(&["inspect", tet.to_str().unwrap()]);
    let out = text(&o).0;
    assert!(out.contains("closed volumes: 1.66667e-10"), "{out}");
    assert!(out.contains("(diagonal 0.001732)"), "{out}");
    // An open mesh has a total volume of 0, not -0.
    let tri = dir.path().join("tri.obj");
    std::fs::write(&tri, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let json = text(&run(&["inspect", tri.to_str().unwrap(), "--json"])).0;
    assert!(json.contains("\"total_volume\": 0.0"), "{json}");
    // A report that is a folder: refused before the mesh (missing here) is read.
    let (folder, nope) = (dir.path().join("r.json"), dir.path().join("nope.obj"));
    std::fs::create_dir(&folder).unwrap();
    let [nope, folder] = [&nope, &folder].map(|p| p.to_str().unwrap());
    let o = run(&["inspect", nope, "--report", folder]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("exists and is not a file"), "{err}");
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = generate::icosphere(5);
    flip_some(&mut m, 3);
    // An open part too, so the winding-number rule runs.
    let keep: Vec<bool> = (0..m.faces.len())
        .map(|f| m.corners(f)[0].z < 0.7)
        .collect();
    m.retain_faces(&keep);
    let src = dir.path().join("s.stl");
    write_mesh(&src, &m, &WriteOptions::default(), &[]).unwrap();
    let mut outputs = Vec::new();
    for jobs in ["1", "2", "3"] {
        let out = dir.path().join(format!("o{jobs}.ply"));
        let rep = dir.path().join(format!("r{jobs}.json"));
        let o = run(&[
            "--jobs",
            jobs,
            "convert",
            src.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--report",
            rep.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", text(&o).1);
        let mut r: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&rep).unwrap()).unwrap();
        r["wall_seconds"] = 0.into();
        r["output"] = "".into();
        outputs.push((std::fs::read(&out).unwrap(), r));
    }
    assert!(
        outputs.windows(2).all(|w| w[0] == w[1]),
        "output or report differs with --jobs"
    );
}

#[test]
fn an_stl_of_two_tetrahedra_touching_at_a_corner_converts_to_two_closed_ones() {
    // Two outward tetrahedra sharing the corner (1, 1, 1) and nothing else: an STL has no
    // indices, so reading merges that corner into one vertex, a non-manifold one.
    let dir = tempfile::tempdir().unwrap();
    let p = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
    let both = TriMesh {
        positions: vec![
            // The first: its apex at (1, 1, 1) over the base (0,0,0), (1,0,0), (0,1,0).
            p(0.0, 0.0, 0.0),
            p(1.0, 0.0, 0.0),
            p(0.0, 1.0, 0.0),
            p(1.0, 1.0, 1.0),
            // The second: its base corner at (1, 1, 1).
            p(1.0, 1.0, 1.0),
            p(2.0, 1.0, 1.0),
            p(1.0, 2.0, 1.0),
            p(1.0, 1.0, 2.0),
        ],
        faces: [0u32, 4]
            .iter()
            .flat_map(|&o| [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]].map(|f| f.map(|v| v + o)))
            .collect(),
    };
    let src = dir.path().join("pinched.stl");
    write_mesh(&src, &both, &WriteOptions::default(), &[]).unwrap();
    let out = dir.path().join("out.obj");
    let (src, out_s) = (src.to_str().unwrap(), out.to_str().unwrap());
    let report = |extra: &[&str]| {
        let r = common::run_json(&[&["convert", src, "-o", out_s, "--json"], extra].concat()).0;
        (r, read_mesh(&out, &ReadOptions::default()).unwrap().mesh)
    };
    let (r, m) = report(&[]);
    assert_eq!(r["input_vertices"], 7);
    assert_eq!(r["split_vertices"], 1);
    assert_eq!(
        (r["output_vertices"].as_u64(), m.positions.len()),
        (Some(8), 8)
    );
    assert_eq!(r["shell_state"], "closed");
    assert_eq!(r["closed_components"], 2);
    assert_closed_components_outward(&m, "split");
    let (r, m) = report(&["--keep-nonmanifold-vertices"]);
    assert_eq!(
        (r["split_vertices"].as_u64(), m.positions.len()),
        (Some(0), 7)
    );
    assert_eq!(r["shell_state"], "irregular");
}
