//! Bad input: every kind gets a message naming the file and the place, a non-zero exit, and no
//! output file (nor a temporary one) left behind.

mod common;
use common::{listing, run, text};
use std::path::Path;

/// Writes `content` as `name` in a fresh directory, converts it to `out.ply`, and returns
/// (exit code, stderr, directory listing after).
fn convert_bad(name: &str, content: &[u8], extra: &[&str]) -> (i32, String, Vec<String>) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join(name);
    std::fs::write(&input, content).unwrap();
    let out = dir.path().join("out.ply");
    let mut args = vec![
        "convert",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = run(&args);
    let (_, err) = text(&o);
    (o.status.code().unwrap_or(-1), err, listing(dir.path()))
}

/// Asserts a failure whose message contains every one of `parts`, with only the input left.
fn assert_refused(name: &str, content: &[u8], parts: &[&str]) {
    let (code, err, files) = convert_bad(name, content, &[]);
    assert_eq!(code, 1, "{name}: exit code; stderr: {err}");
    assert!(
        err.contains(name),
        "{name}: the message names the file: {err}"
    );
    for p in parts {
        assert!(err.contains(p), "{name}: expected {p:?} in: {err}");
    }
    assert_eq!(
        files,
        vec![name.to_string()],
        "{name}: nothing else may be left behind"
    );
}

#[test]
fn triples_wrong_number_count_in_a_face_record() {
    assert_refused("a.txt", b"0 0 0 1 0 0\n", &["a.txt:1: expected 3 numbers (a point), 9 (a triangle) or 12 (a quad) on a line, found 6"]);
}

#[test]
fn triples_block_that_is_not_a_face() {
    let s = b"0 0 0\n1 0 0\n0 1 0\n\n0 0 1\n1 0 1\n0 1 1\n\n0 0 2\n1 0 2\n0 1 2\n1 1 2\n2 2 2\n";
    assert_refused("b.txt", s, &["b.txt:9: a block of 5 points (lines 9-13)"]);
}

#[test]
fn triples_leftover_point() {
    assert_refused(
        "c.txt",
        b"0 0 0\n1 0 0\n0 1 0\n5 5 5\n",
        &["c.txt:4: 1 point(s) left over"],
    );
}

#[test]
fn non_numeric_token_and_all_problems_listed() {
    let (code, err, _) = convert_bad("d.txt", b"0 0 0\n1 0 x\n0 1 0\n0 0 y\n", &[]);
    assert_eq!(code, 1);
    assert!(err.contains("2 problems"), "{err}");
    assert!(
        err.contains("d.txt:2: 'x' is not a number")
            && err.contains("d.txt:4: 'y' is not a number"),
        "{err}"
    );
}

#[test]
fn nan_is_refused() {
    assert_refused(
        "e.obj",
        b"v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n",
        &["e.obj:2: 'NaN' is not a finite number"],
    );
}

#[test]
fn infinity_is_refused() {
    assert_refused(
        "f.txt",
        b"0 0 0\n1 inf 0\n0 1 0\n",
        &["f.txt:2: 'inf' is not a finite number"],
    );
}

fn binary_stl(count_declared: u32, triangles: usize) -> Vec<u8> {
    let mut b = vec![b' '; 80];
    b.extend_from_slice(&count_declared.to_le_bytes());
    for t in 0..triangles {
        b.extend_from_slice(&[0u8; 12]);
        for c in [
            [0.0f32, 0.0, t as f32],
            [1.0, 0.0, t as f32],
            [0.0, 1.0, t as f32],
        ] {
            for v in c {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
        b.extend_from_slice(&[0, 0]);
    }
    b
}

#[test]
fn truncated_binary_stl() {
    let mut b = binary_stl(4, 4);
    b.truncate(84 + 50 * 2 + 17);
    assert_refused("g.stl", &b, &["byte 184 (triangle 2)", "truncated binary STL: the header promises 4 triangles (284 bytes) but the file has 201 bytes"]);
}

#[test]
fn binary_stl_count_disagrees_with_size() {
    let b = binary_stl(2, 3);
    assert_refused("h.stl", &b, &["triangle count 2 disagrees with the file size: 2 triangles take 184 bytes, the file has 234"]);
}

#[test]
fn binary_stl_nan_coordinate() {
    let mut b = binary_stl(1, 1);
    b[84 + 12 + 4..84 + 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_refused(
        "i.stl",
        &b,
        &["byte 100 (triangle 0, corner 0)", "non-finite coordinate"],
    );
}

#[test]
fn ply_promises_more_elements_than_it_has() {
    let s = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    assert_refused(
        "j.ply",
        s,
        &["j.ply:13: the file ends in element 'vertex' 3 of 4: the header promises 4"],
    );
}

#[test]
fn binary_ply_promises_more_faces() {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    let header = b.len();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.push(3);
    for i in [0i32, 1, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    let at = format!("byte {} (element 'face' 1)", header + 36 + 13);
    assert_refused(
        "k.ply",
        &b,
        &[&at, "the file ends in element 'face' 1 of 2"],
    );
}

#[test]
fn ply_without_magic() {
    assert_refused(
        "l.ply",
        b"format ascii 1.0\nend_header\n",
        &["l.ply:1: not a PLY file"],
    );
}

#[test]
fn ply_unknown_type() {
    let s = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n";
    assert_refused("m.ply", s, &["m.ply:4: unknown PLY property type 'quad'"]);
}

#[test]
fn obj_face_index_out_of_range() {
    assert_refused(
        "n.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
        &["n.obj:4: vertex index 4 is out of range: the file has 3 vertices"],
    );
}

#[test]
fn obj_negative_index_before_any_vertex() {
    assert_refused(
        "o.obj",
        b"f -1 -2 -3\nv 0 0 0\n",
        &["o.obj:1: vertex index -1 is out of range"],
    );
}

#[test]
fn obj_face_with_two_corners() {
    assert_refused(
        "p.obj",
        b"v 0 0 0\nv 1 0 0\nf 1 2\n",
        &["p.obj:3: a face needs at least 3 corners, found 2"],
    );
}

#[test]
fn ascii_stl_grammar() {
    let s = b"solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertx 0 1 0\n  endloop\n endfacet\nendsolid x\n";
    assert_refused(
        "q.stl",
        s,
        &["q.stl:6: expected 'vertex' or 'endloop', found 'vertx'"],
    );
}

#[test]
fn unbalanced_lisp_parentheses() {
    assert_refused(
        "r.txt",
        b"(0 0 0)\n(1 0 0\n(0 1 0)\n",
        &["r.txt:2: unbalanced parentheses"],
    );
}

#[test]
fn empty_file() {
    assert_refused("s.stl", b"", &["the file is empty (0 bytes)"]);
}

#[test]
fn unknown_format() {
    assert_refused(
        "t.dat",
        b"hello world\nthis is not a mesh\n",
        &["cannot tell the mesh format", "--from triples|obj|stl|ply"],
    );
}

#[test]
fn point_cloud_has_nothing_to_convert() {
    assert_refused(
        "u.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\n",
        &["no faces to convert (3 vertices, 0 faces)"],
    );
}

#[test]
fn missing_input_file() {
    let dir = tempfile::tempdir().unwrap();
    let o = run(&[
        "convert",
        dir.path().join("nope.obj").to_str().unwrap(),
        "-o",
        dir.path().join("x.ply").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).1.contains("cannot read") && text(&o).1.contains("nope.obj"));
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn unwritable_output_path() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.txt");
    std::fs::write(&input, b"0 0 0\n1 0 0\n0 1 0\n").unwrap();
    // The output's parent is a regular file: nothing can be created there (even as root).
    let out = input.join("out.ply");
    let o = run(&[
        "convert",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o).1;
    assert!(
        err.contains("cannot write") && err.contains("in.txt/out.ply"),
        "{err}"
    );
    // The path given, not the temporary file's.
    assert!(!err.contains(drapekit::io::TEMP_PREFIX), "{err}");
    assert_eq!(listing(dir.path()), vec!["in.txt"]);
}

#[test]
fn output_over_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.obj");
    let content = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::fs::write(&input, content).unwrap();
    // Through a different spelling of the same path, too.
    let other = dir.path().join(".").join("in.obj");
    let o = run(&[
        "convert",
        input.to_str().unwrap(),
        "-o",
        other.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o).1.contains("it is the input file"),
        "{}",
        text(&o).1
    );
    assert_eq!(std::fs::read(&input).unwrap(), content);
    assert_eq!(listing(dir.path()), vec!["in.obj"]);
}

#[test]
fn unknown_output_extension() {
    let (code, err, files) = {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.txt");
        std::fs::write(&input, b"0 0 0\n1 0 0\n0 1 0\n").unwrap();
        let o = run(&[
            "convert",
            input.to_str().unwrap(),
            "-o",
            dir.path().join("out.xyz").to_str().unwrap(),
        ]);
        (o.status.code(), text(&o).1, listing(dir.path()))
    };
    assert_eq!(code, Some(1));
    assert!(
        err.contains("unknown output format for extension 'xyz'"),
        "{err}"
    );
    assert_eq!(files, vec!["in.txt"]);
}

#[test]
fn usage_errors_exit_2_before_any_work() {
    let (code, err, files) = convert_bad("v.txt", b"0 0 0\n1 0 0\n0 1 0\n", &["--weld-tol", "abc"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("weld tolerance 'abc' is not a number"),
        "{err}"
    );
    assert_eq!(files, vec!["v.txt"]);
    let (code, err, _) = convert_bad("w.txt", b"0 0 0\n1 0 0\n0 1 0\n", &["--to-units", "m"]);
    assert_eq!(code, 2);
    assert!(err.contains("--units"), "{err}");
    let (code, err, _) = convert_bad(
        "x.txt",
        b"0 0 0\n1 0 0\n0 1 0\n",
        &["--quad-split", "longest"],
    );
    assert_eq!(code, 2);
    assert!(err.contains("unknown quad split 'longest'"), "{err}");
}

#[test]
fn report_path_equal_to_output_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.txt");
    std::fs::write(&input, b"0 0 0\n1 0 0\n0 1 0\n").unwrap();
    let out = dir.path().join("o.ply");
    let o = run(&[
        "convert",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--report",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!Path::new(&out).exists());
}

#[test]
fn garment_flags_out_of_range_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    for (flag, value) in [
        ("--body-clearance", "-0.001"),
        ("--cloth-friction", "NaN"),
        ("--friction", "-1"),
        ("--spacing", "0"),
    ] {
        let arg = format!("{flag}={value}");
        let o = run(&[
            "garment",
            "no_pattern.json",
            "--body",
            "no_body.obj",
            "-o",
            out.to_str().unwrap(),
            &arg,
        ]);
        let (_, err) = text(&o);
        assert_eq!(o.status.code(), Some(1), "{flag}: {err}");
        assert!(err.contains(flag) && err.contains(value), "{flag}: {err}");
        assert!(listing(dir.path()).is_empty(), "{flag}: nothing written");
    }
}

/// An ASCII PLY of one triangle whose face list is `face` (its vertex indices typed `float`)
/// and whose vertices are typed `float`, with `x0` as the first coordinate.
fn float_ply(x0: &str, face: &str) -> Vec<u8> {
    format!("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n{x0} 0 0\n1 0 0\n0 1 0\n{face}\n").into_bytes()
}

#[test]
fn hostile_ply_face_indices_must_be_integers() {
    for (name, face, value) in [
        ("fi.ply", "3 0 1.7 2", "1.7"),
        ("fn.ply", "3 0 1 nan", "NaN"),
    ] {
        assert_refused(
            name,
            &float_ply("0", face),
            &[&format!(
                "{name}:13: element 'face' 0: vertex index {value} is not a whole number: expected an integer"
            )],
        );
    }
}

#[test]
fn hostile_ply_float_coordinate_beyond_f32_is_refused() {
    assert_refused(
        "big.ply",
        &float_ply("1e39", "3 0 1 2"),
        &["big.ply:10: coordinate 1e39 does not fit the declared type float (at most 3.4028234663852886e38 in magnitude)"],
    );
}

#[test]
fn a_mesh_too_small_for_32_bit_floats_is_not_written_as_binary_stl_or_gltf() {
    // A tetrahedron 1e-40 across went into binary STL and glTF as subnormal 32-bit floats,
    // rounded to multiples of 1.4e-45: its shape silently lost. PLY and OBJ keep 64 bits.
    let tet = |s: f64| {
        format!(
            "v 0 0 0\nv {s:e} 0 0\nv 0 {s:e} 0\nv 0 0 {s:e}\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
        )
    };
    for (s, written) in [(1e-40, false), (1e-300, false), (1e-37, true)] {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("tet.obj");
        std::fs::write(&input, tet(s)).unwrap();
        for out in ["out.stl", "out.glb", "out.ply"] {
            let o = run(&[
                "convert",
                input.to_str().unwrap(),
                "-o",
                dir.path().join(out).to_str().unwrap(),
            ]);
            let (_, err) = text(&o);
            let expect = written || out == "out.ply";
            assert_eq!(o.status.success(), expect, "{s} {out}: {err}");
            assert_eq!(dir.path().join(out).exists(), expect, "{s} {out}");
            if !expect {
                assert!(
                    err.contains(out) && err.contains("below 32-bit floats' normal range"),
                    "{err}"
                );
            }
        }
    }
}
