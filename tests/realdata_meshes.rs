//! The third-party meshes in `../shared/realdata/meshes` come out as their notes in
//! `PROVENANCE.txt` say, and none of the reader defects in `READER_PROBE.tsv` shows through.

mod common;
use common::{assert_closed_components_outward, realdata, run, text};
use drapekit::io::{read_mesh, IoError, ReadOptions};
use drapekit::math::{newell_normal, Point3};
use drapekit::mesh::diagnose::{diagnose, Diagnosis, ShellState};
use drapekit::mesh::prepare::{prepare, PrepareOptions, PrepareReport};
use drapekit::mesh::weld::WeldTolerance;
use drapekit::mesh::TriMesh;
use std::path::{Path, PathBuf};

fn meshes() -> Option<PathBuf> {
    realdata().map(|r| r.join("meshes"))
}

fn read(dir: &Path, name: &str) -> (TriMesh, drapekit::io::ReadInfo) {
    let r = read_mesh(&dir.join(name), &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    (r.mesh, r.info)
}

fn raw(dir: &Path, name: &str) -> Diagnosis {
    diagnose(&read(dir, name).0)
}

fn prepared(dir: &Path, name: &str) -> (TriMesh, PrepareReport) {
    let mut m = read(dir, name).0;
    let r = prepare(&mut m, &PrepareOptions::default());
    (m, r)
}

fn refused(dir: &Path, name: &str) -> String {
    match read_mesh(&dir.join(name), &ReadOptions::default()) {
        Ok(_) => panic!("{name} should be refused"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn every_file_is_read_or_refused_with_a_located_message() {
    let Some(dir) = meshes() else { return };
    let mut files = Vec::new();
    let mut stack = vec![dir.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if !matches!(
                p.extension().and_then(|e| e.to_str()),
                Some("txt" | "tsv" | "mtl")
            ) {
                files.push(p);
            }
        }
    }
    files.sort();
    assert_eq!(
        files.len(),
        77,
        "the mesh files listed in PROVENANCE.txt, less the .mtl"
    );
    let mut refused = Vec::new();
    for f in &files {
        match read_mesh(f, &ReadOptions::default()) {
            Ok(r) => {
                r.mesh.check().unwrap();
                // Every file that reads also prepares and writes.
                // Every file that reads also prepares: consistently wound, closed parts outward.
                if !r.mesh.faces.is_empty() {
                    let mut m = r.mesh;
                    prepare(&mut m, &PrepareOptions::default());
                    m.check().unwrap();
                    assert_closed_components_outward(&m, &f.display().to_string());
                }
            }
            Err(e @ IoError::Malformed { .. }) => {
                let msg = e.to_string();
                assert!(msg.contains(&f.display().to_string()), "{msg}");
                refused.push(f.strip_prefix(&dir).unwrap().display().to_string());
            }
            Err(e) => panic!("{}: unexpected error kind: {e}", f.display()),
        }
    }
    // The truly invalid ones, and nothing else.
    assert_eq!(
        refused,
        vec![
            "assimp/OBJ/number_formats.obj",
            "ply-rs/single_elements_err_ascii.ply",
            "tobj/invalid_index.obj",
            "trimesh/notenoughindices.obj",
        ]
    );
}

#[test]
fn invalid_files_are_refused_with_the_reason() {
    let Some(d) = meshes() else { return };
    // '3.1+e2' is not a number in any grammar (tobj, mesh-loader and others refuse it too).
    let e = refused(&d, "assimp/OBJ/number_formats.obj");
    assert!(
        e.contains("number_formats.obj:11: '3.1+e2' is not a number"),
        "{e}"
    );
    assert!(!e.contains(":7:"), "2.e1 and +1e2 are numbers: {e}");
    let e = refused(&d, "tobj/invalid_index.obj");
    assert!(
        e.ends_with(
            "invalid_index.obj:12: vertex index 7 is out of range: the file has 6 vertices"
        ),
        "{e}"
    );
    let e = refused(&d, "trimesh/notenoughindices.obj");
    assert!(
        e.ends_with("notenoughindices.obj:9: a face needs at least 3 corners, found 2"),
        "{e}"
    );
    let e = refused(&d, "ply-rs/single_elements_err_ascii.ply");
    assert!(e.ends_with("single_elements_err_ascii.ply:10: the file ends in element 'point' 1 of 2: the header promises 2"), "{e}");
}

#[test]
fn multi_solid_ascii_stl_is_read_whole() {
    let Some(d) = meshes() else { return };
    // stl_io 0.10 keeps only the first solid of each of these.
    let (m, info) = read(&d, "trimesh/multibody.stl");
    assert_eq!((m.faces.len(), info.solids), (32, Some(2)));
    assert_eq!(
        read(&d, "trimesh/two_objects_mixed_case_names.stl")
            .0
            .faces
            .len(),
        24
    );
    assert_eq!(
        read(&d, "assimp/STL/triangle_with_two_solids.stl")
            .0
            .faces
            .len(),
        2
    );
    assert_eq!(
        read(&d, "assimp/STL/triangle_with_empty_solid.stl")
            .0
            .faces
            .len(),
        1
    );
    // bodyA is inside out: -0.006 with the winding most of its faces have.
    let raw = diagnose(&m);
    let vols: Vec<f64> = raw.volumes.iter().map(|v| v.volume).collect();
    assert!(vols.iter().any(|v| (v + 0.00595).abs() < 5e-5), "{vols:?}");
    // After convert: 32 triangles, both bodies closed and outward.
    let (m, r) = prepared(&d, "trimesh/multibody.stl");
    assert_eq!(m.faces.len(), 32);
    assert_eq!(
        (r.after.closed_components, r.after.shell_state),
        (2, ShellState::Closed)
    );
    assert!(r.after.volumes.iter().all(|v| v.volume > 0.0 && v.outward));
}

#[test]
fn stl_detection_by_size_not_by_first_word() {
    let Some(d) = meshes() else { return };
    // Binary files whose header starts with 'solid'.
    for f in ["trimesh/angle_block.STL", "trimesh/unit_cube.STL"] {
        assert_eq!(read(&d, f).1.format, "stl-binary", "{f}");
    }
    // 'solid<TAB>name' is ASCII (stl_io misdetects it as binary and fails).
    let (m, info) = read(&d, "assimp/STL/sphereWithHole.stl");
    assert_eq!(info.format, "stl-ascii");
    assert_eq!(m.faces.len(), 285);
    // No extension: sniffed.
    assert_eq!(read(&d, "assimp/STL/formatDetection").1.format, "stl-ascii");
    // The binary and ASCII spiders are the same mesh.
    let a = read(&d, "assimp/STL/Spider_ascii.stl").0;
    let b = read(&d, "assimp/STL/Spider_binary.stl").0;
    assert_eq!(a.faces.len(), b.faces.len());
    for f in 0..a.faces.len() {
        let (ca, cb) = (a.corners(f), b.corners(f));
        for k in 0..3 {
            assert!((ca[k] - cb[k]).norm() < 1e-5, "face {f}");
        }
    }
}

#[test]
fn welding_closes_noise_and_keeps_features() {
    let Some(d) = meshes() else { return };
    // 46 vertices duplicated as 0.0 against 6.1e-17: exact merging leaves 398, welding 352.
    assert_eq!(raw(&d, "trimesh/angle_block.STL").vertices, 398);
    let (m, r) = prepared(&d, "trimesh/angle_block.STL");
    assert_eq!(
        (m.positions.len(), r.after.shell_state),
        (352, ShellState::Closed)
    );
    // 288 near-zero noise duplicates.
    let (m, _) = prepared(&d, "trimesh/featuretype.STL");
    assert_eq!(m.positions.len(), 1722);
    // The split-vertex PLY of the same part welds to the same 1722 vertices and one closed body
    // (the note's 844 components are trimesh's count before merging; ours is 852 by manifold edges).
    let raw_ply = raw(&d, "trimesh/featuretype.ply");
    assert_eq!((raw_ply.vertices, raw_ply.components), (5096, 852));
    let (m, r) = prepared(&d, "trimesh/featuretype.ply");
    assert_eq!(
        (m.positions.len(), r.after.components, r.after.shell_state),
        (1722, 1, ShellState::Closed)
    );
    // Real features 0.03 mm apart in a 300 mm part stay apart: nothing welds.
    let (m, r) = prepared(&d, "trimesh/counter.unitsmm.STL");
    assert_eq!((m.positions.len(), r.welded_vertices), (41837, 0));
    assert_eq!(
        (r.after.closed_components, r.after.shell_state),
        (6, ShellState::Closed)
    );
    // A part in metres, 0.047 across: the relative default keeps all 3672 vertices, where an
    // absolute 1e-4 weld destroys it.
    let (m, _) = prepared(&d, "trimesh/ADIS16480.STL");
    assert_eq!(m.positions.len(), 3672);
    let mut m = read(&d, "trimesh/ADIS16480.STL").0;
    prepare(
        &mut m,
        &PrepareOptions {
            weld: Some(WeldTolerance::Absolute(1e-4)),
            ..Default::default()
        },
    );
    assert!(
        m.positions.len() < 2600,
        "the trap is real: {}",
        m.positions.len()
    );
}

#[test]
fn degenerate_and_duplicate_faces() {
    let Some(d) = meshes() else { return };
    // 200 zero-area faces at the poles.
    let (m, r) = prepared(&d, "trimesh/capsule.obj");
    assert_eq!(r.degenerate_faces, 200);
    assert_eq!(
        (m.faces.len(), r.after.shell_state),
        (10_000, ShellState::Closed)
    );
    // Spider: inconsistent winding, 56 degenerate triangles, 36 duplicates. The note's 20
    // non-manifold edges are all edges of those repeated-corner faces (trimesh counts them);
    // without them no edge has more than two faces.
    let s = raw(&d, "assimp/STL/Spider_binary.stl");
    assert_eq!(
        (s.degenerate_faces, s.duplicate_faces, s.non_manifold_edges),
        (56, 36, 0)
    );
    assert!(!s.winding_consistent);
    let (_, r) = prepared(&d, "assimp/STL/Spider_binary.stl");
    assert_eq!(r.degenerate_faces, 56);
    assert!(r.after.winding_consistent && r.after.outward);
    // Two tetrahedra sharing a face: one duplicate face; three edges with three faces after.
    let (_, r) = prepared(&d, "trimesh/joined_tetrahedra.obj");
    assert_eq!((r.duplicate_faces, r.after.non_manifold_edges), (1, 3));
}

#[test]
fn obj_reader_defects_do_not_show_through() {
    let Some(d) = meshes() else { return };
    // tobj 4.0.5 fails the whole load on an empty `usemtl`; the note's 11 zero-area faces come
    // from fan-triangulating its 13 concave n-gons, which ear clipping avoids.
    let (m, info) = read(&d, "trimesh/wallhole.obj");
    assert_eq!((info.polygons.polygons, info.polygons.ngons), (13, 13));
    assert_eq!(diagnose(&m).degenerate_faces, 0);
    let (_, r) = prepared(&d, "trimesh/wallhole.obj");
    assert_eq!(r.after.shell_state, ShellState::Closed);
    // UTF-16BE (tobj: ReadError).
    let (m, _) = read(&d, "assimp/OBJ/box_UTF16BE.obj");
    assert_eq!(diagnose(&m).shell_state, ShellState::Closed);
    // Negative indices resolve against the running vertex count.
    let n = raw(&d, "trimesh/negative_indices.obj");
    assert_eq!((n.faces, n.shell_state), (12, ShellState::Closed));
    assert!((n.total_volume - 8.0).abs() < 1e-12);
    // A face listing its quad 234 times is one quad.
    let (m, info) = read(&d, "assimp/OBJ/box_longline.obj");
    assert_eq!((m.faces.len(), info.polygons.periodic_polygons), (12, 1));
    // Lines and points are skipped with a warning, faces kept.
    let (m, info) = read(&d, "assimp/OBJ/testmixed.obj");
    assert_eq!(m.faces.len(), 12);
    assert!(info.warnings.iter().any(|w| w.contains("line element")));
}

/// For the polygons of an OBJ file and the triangles read from it (n - 2 per polygon, in order):
/// the sum of the triangles' areas projected on their polygon's Newell normal, the same sum of
/// absolute values, and the polygons' areas. A triangulation without overlap has all three equal
/// (any triangulation has the first equal to the last; a folded triangle makes the second larger).
fn projected_areas(path: &Path, m: &TriMesh) -> (f64, f64, f64) {
    // Join continuation lines ('\\' at the end) as OBJ says.
    let text = std::fs::read_to_string(path)
        .unwrap()
        .replace("\\\r\n", " ")
        .replace("\\\n", " ");
    let mut pos = Vec::new();
    let (mut signed, mut abs, mut poly) = (0.0, 0.0, 0.0);
    let mut next_tri = 0;
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first() {
            Some(&"v") => pos.push(Point3::new(
                w[1].parse().unwrap(),
                w[2].parse().unwrap(),
                w[3].parse().unwrap(),
            )),
            Some(&"f") => {
                let idx: Vec<usize> = w[1..]
                    .iter()
                    .map(|t| t.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                    .collect();
                let n = newell_normal(idx.iter().map(|&i| pos[i]));
                poly += 0.5 * n.norm();
                let n = n.normalize();
                for t in next_tri..next_tri + idx.len() - 2 {
                    let a = 0.5 * m.face_cross(t).dot(&n);
                    signed += a;
                    abs += a.abs();
                }
                next_tri += idx.len() - 2;
            }
            _ => {}
        }
    }
    assert_eq!(next_tri, m.faces.len());
    (signed, abs, poly)
}

#[test]
fn concave_ngons_are_triangulated_without_overlap() {
    let Some(d) = meshes() else { return };
    for f in [
        "assimp/OBJ/concave_polygon.obj",
        "trimesh/wallhole.obj",
        "trimesh/polygonfaces.obj",
    ] {
        let path = d.join(f);
        let (m, info) = read(&d, f);
        assert_eq!(info.polygons.overlapping_polygons, 0, "{f}");
        let (signed, abs, poly) = projected_areas(&path, &m);
        assert!(
            (signed - poly).abs() <= 1e-9 * poly,
            "{f}: triangles sum to {signed}, the polygons {poly}"
        );
        assert!(
            (abs - poly).abs() <= 1e-9 * poly,
            "{f}: triangles overlap: {abs} against {poly}"
        );
    }
    // The LightWave polygon: 66 corners around a hole bridged twice, 64 triangles, all facing +x
    // like the polygon (a fan would fold some over).
    let (m, _) = read(&d, "assimp/OBJ/concave_polygon.obj");
    assert_eq!(m.faces.len(), 64);
    assert!((0..64).all(|f| m.face_cross(f).x < 0.0) || (0..64).all(|f| m.face_cross(f).x > 0.0));
}

#[test]
fn ply_reader_defects_do_not_show_through() {
    let Some(d) = meshes() else { return };
    // A header line without 'comment' (ply-rs rejects the file): skipped with a warning.
    let (m, info) = read(&d, "assimp/PLY/Wuson.ply");
    assert_eq!((m.positions.len(), m.faces.len()), (11184, 3732));
    assert!(
        info.warnings[0].contains("header line 3 skipped"),
        "{:?}",
        info.warnings
    );
    // A comment between element and property lines, and a list property declared on the vertex
    // element but absent from its lines (ply-rs fails): 24 vertices, no faces, a warning.
    let (m, info) = read(&d, "assimp/PLY/issue623.ply");
    assert_eq!((m.positions.len(), m.faces.len()), (24, 0));
    assert!(info
        .warnings
        .iter()
        .any(|w| w.contains("trailing list properties")));
    // Binary payload starting with a newline byte; CRLF header.
    for f in [
        "assimp/PLY/cube_binary_starts_with_nl.ply",
        "assimp/PLY/cube_binary_header_with_RN_newline.ply",
        "assimp/PLY/cube_binary.ply",
    ] {
        let (m, _) = read(&d, f);
        assert_eq!(diagnose(&m).shell_state, ShellState::Closed, "{f}");
        assert!(
            (m.signed_volume().abs() - 1.0).abs() < 1e-6,
            "{f}: {}",
            m.signed_volume()
        );
    }
    // 'vertex_index' instead of 'vertex_indices', quads.
    assert_eq!(read(&d, "assimp/PLY/cube.ply").0.faces.len(), 12);
    // Per-face texcoord lists and extra per-face values.
    let (m, info) = read(&d, "trimesh/fuze_ascii.ply");
    assert_eq!(
        (m.faces.len(), diagnose(&m).shell_state),
        (1000, ShellState::Closed)
    );
    assert!(info.warnings[0].contains("beyond the header's properties"));
    assert_eq!(
        read(&d, "trimesh/cube_blender_uv_meshlab.ply")
            .0
            .faces
            .len(),
        12
    );
    // Per-face RGBA: 119 components.
    assert_eq!(raw(&d, "trimesh/cycloidal.ply").components, 119);
    // Point clouds and empty files read as such.
    assert_eq!(
        read(&d, "trimesh/points_emptyface.ply").0.positions.len(),
        1024
    );
    for f in [
        "trimesh/emptyIO/ply_empty_header.ply",
        "trimesh/emptyIO/stl_empty_ascii.stl",
        "trimesh/emptyIO/stl_empty_bin.stl",
        "ply-rs/empty_2_ok_little_endian.ply",
    ] {
        assert_eq!(read(&d, f).0.faces.len(), 0, "{f}");
    }
}

#[test]
fn topology_notes() {
    let Some(d) = meshes() else { return };
    // Two unit cubes sharing one edge: one non-manifold edge; each cube still closed and outward.
    let s = raw(&d, "trimesh/shared.STL");
    assert_eq!((s.non_manifold_edges, s.closed_components), (1, 2));
    assert!(s
        .volumes
        .iter()
        .all(|v| (v.volume - 1.0).abs() < 1e-9 && v.outward));
    // 3ds Max export: 16 non-manifold edges, 28 bodies.
    let s = raw(&d, "assimp/STL/3DSMaxExport.STL");
    assert_eq!((s.non_manifold_edges, s.components), (16, 28));
    // Teapot: open, 64 boundary edges, 4 bodies.
    let s = raw(&d, "trimesh/teapot.stl");
    assert_eq!(
        (s.boundary_edges, s.components, s.watertight),
        (64, 4, false)
    );
    // Pure soup: 100 components; chair: a double-sided soup, half its faces duplicates.
    assert_eq!(raw(&d, "trimesh/soup.stl").components, 100);
    let (_, r) = prepared(&d, "trimesh/chair_model.obj");
    assert_eq!((r.input_faces, r.duplicate_faces), (12_756, 6382));
    // Closed genus-1 parts: Euler characteristic 0.
    assert_eq!(raw(&d, "trimesh/mirror.ply").euler_characteristic, 0);
    let (_, r) = prepared(&d, "trimesh/octagonal_pocket.ply");
    assert_eq!(
        (r.after.euler_characteristic, r.after.shell_state),
        (0, ShellState::Closed)
    );
    // Genus > 0 CAD part, closed.
    let t = raw(&d, "trimesh/1002_tray_bottom.STL");
    assert!(t.watertight && t.euler_characteristic < 0 && t.shell_state == ShellState::Closed);
    // Cube with an octant removed: 7/8 of the cube's volume.
    let c = raw(&d, "trimesh/7_8ths_cube.stl");
    let b = c.bbox.as_ref().unwrap().size;
    assert!(
        (c.total_volume - 0.875 * b[0] * b[1] * b[2]).abs() < 1e-6 * c.total_volume,
        "{}",
        c.total_volume
    );
}

#[test]
fn open_meshes_face_outward_by_the_winding_rule() {
    let Some(d) = meshes() else { return };
    // A sphere with a hole: after convert the normals point away from the centre.
    let (m, r) = prepared(&d, "assimp/STL/sphereWithHole.stl");
    assert_eq!(r.after.open_components, 1);
    let c = m.bbox().unwrap().center();
    let outward = (0..m.faces.len())
        .filter(|&f| {
            let [a, b, cc] = m.corners(f);
            m.face_cross(f)
                .dot(&((a.coords + b.coords + cc.coords) / 3.0 - c.coords))
                > 0.0
        })
        .count();
    assert_eq!(outward, m.faces.len());
    // Flipped whole first: the rule brings it back.
    let mut m2 = m.clone();
    for f in 0..m2.faces.len() {
        m2.flip_face(f);
    }
    let r = prepare(&mut m2, &PrepareOptions::default());
    assert_eq!(r.flipped_faces, m.faces.len());
    assert_eq!(m2, m);
}

#[test]
fn convert_cli_on_a_real_file_writes_the_report() {
    let Some(d) = meshes() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("multibody.ply");
    let rep = dir.path().join("r.json");
    let src = d.join("trimesh/multibody.stl");
    let o = run(&[
        "convert",
        src.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o).1);
    assert!(text(&o).0.contains("shell state: closed"));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&rep).unwrap()).unwrap();
    assert_eq!(r["input_faces"], 32);
    assert_eq!(r["output_faces"], 32);
    assert_eq!(r["closed_components"], 2);
    assert_eq!(r["shell_state"], "closed");
    assert_eq!(r["input_format"], "stl-ascii");
    assert!(r["flipped_faces"].as_u64().unwrap() > 0);
}

#[test]
fn stls_pinched_at_a_point_are_split_there() {
    let Some(d) = meshes() else { return };
    // Read as it is, each STL has a vertex where two fans of faces meet (its corners are
    // positions only); split, each is open and consistently wound.
    for (file, added) in [
        ("trimesh/teapot.stl", 1),
        ("assimp/STL/sphereWithHole.stl", 2),
    ] {
        let before = raw(&d, file);
        assert_eq!(before.shell_state, ShellState::Irregular, "{file}");
        assert_eq!(before.non_manifold_edges, 0, "{file}");
        assert!(before.non_manifold_vertices > 0, "{file}");
        let (_, r) = prepared(&d, file);
        assert_eq!(r.split_vertices, added, "{file}");
        assert_eq!(r.after.non_manifold_vertices, 0, "{file}");
        assert_eq!(r.after.shell_state, ShellState::Oriented, "{file}");
    }
}
