//! Helpers shared by the integration tests.
#![allow(dead_code)]

use drapekit::math::Point3;
use drapekit::mesh::orient;
use drapekit::mesh::topology::Topology;
use drapekit::mesh::TriMesh;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The drapekit binary under test.
pub fn drapekit() -> Command {
    Command::new(env!("CARGO_BIN_EXE_drapekit"))
}

/// Runs drapekit with `args`.
pub fn run(args: &[&str]) -> Output {
    drapekit().args(args).output().expect("drapekit runs")
}

/// stdout and stderr as text.
pub fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Runs drapekit, asserts it succeeded (with its stderr as the message) and parses its stdout
/// as JSON; also returns stderr.
pub fn run_json(args: &[&str]) -> (serde_json::Value, String) {
    let o = run(args);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stderr}");
    (
        serde_json::from_str(&stdout).expect("JSON on stdout"),
        stderr,
    )
}

/// `../shared/realdata` beside the repository. Missing: the test says so and is skipped, except
/// under `CI=true`, where it fails.
pub fn realdata() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/realdata");
    if p.is_dir() {
        return Some(p.canonicalize().unwrap());
    }
    if std::env::var("CI").as_deref() == Ok("true") {
        panic!(
            "{} is missing, and CI=true requires the real data",
            p.display()
        );
    }
    eprintln!(
        "skipping: {} not found (real-data tests run where ../shared exists)",
        p.display()
    );
    None
}

/// A file in `fixtures/`.
pub fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// The names of the entries of a directory, sorted.
pub fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Independent check of the orientation invariant: in every closed component, every edge is
/// used exactly once in each direction, and the signed volume is positive.
pub fn assert_closed_components_outward(m: &TriMesh, what: &str) {
    let topo = Topology::build(m);
    let plan = orient::plan(m, &topo, true);
    assert!(plan.is_noop(), "{what}: orienting again would change faces");
    let mut directed: HashMap<(u32, u32, u32), u32> = HashMap::new();
    for (f, face) in m.faces.iter().enumerate() {
        let c = plan.label[f];
        if c == u32::MAX || !plan.components[c as usize].closed {
            continue;
        }
        for i in 0..3 {
            *directed.entry((c, face[i], face[(i + 1) % 3])).or_default() += 1;
        }
    }
    for (&(c, a, b), &n) in &directed {
        assert_eq!(n, 1, "{what}: component {c} uses edge {a}->{b} {n} times");
        assert_eq!(
            directed.get(&(c, b, a)),
            Some(&1),
            "{what}: component {c} edge {a}-{b} is not used once each way"
        );
    }
    for (c, info) in plan.components.iter().enumerate() {
        if info.closed && info.orientable && !info.undecided {
            let faces = (0..m.faces.len()).filter(|&f| plan.label[f] == c as u32);
            let v = m.signed_volume_about(faces, Point3::origin());
            assert!(v > 0.0, "{what}: closed component {c} has volume {v}");
        }
    }
}

/// The third-party checkers of written files (`tools/ensure_test_tools.sh`): the Khronos glTF
/// validator and trimesh, installed once into the target folder's `test-tools`.
pub struct Tools {
    dir: PathBuf,
}

/// The checkers, installed when missing. When they cannot be installed (no network) the test
/// says so and is skipped, except under `CI=true`, where it fails.
pub fn tools() -> Option<Tools> {
    static READY: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    let ready = READY.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .parent()
            .expect("the target folder")
            .join("test-tools");
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/ensure_test_tools.sh");
        match Command::new("bash").arg(&script).arg(&dir).output() {
            Ok(o) if o.status.success() => Ok(dir),
            Ok(o) => Err(String::from_utf8_lossy(&o.stderr).into_owned()),
            Err(e) => Err(e.to_string()),
        }
    });
    match ready {
        Ok(dir) => Some(Tools { dir: dir.clone() }),
        Err(e) if std::env::var("CI").as_deref() == Ok("true") => {
            panic!("CI=true and the glTF validator or trimesh cannot be installed: {e}")
        }
        Err(e) => {
            eprintln!("skipping: the glTF validator or trimesh cannot be installed: {e}");
            None
        }
    }
}

impl Tools {
    fn lines(&self, mut cmd: Command) -> Vec<serde_json::Value> {
        let o = cmd.output().expect("the checker runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .map(|l| serde_json::from_str(l).expect("one JSON object a line"))
            .collect()
    }

    /// The validator's report of each file (`errors`, `warnings`, `messages`, ...).
    pub fn validate(&self, files: &[&Path]) -> Vec<serde_json::Value> {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/gltf_validate.mjs");
        let mut cmd = Command::new("node");
        cmd.arg(script).arg(&self.dir).args(files);
        self.lines(cmd)
    }

    /// What trimesh loads from each file (`vertices`, `faces`, `geometries`, `bounds`).
    pub fn trimesh(&self, files: &[&Path]) -> Vec<serde_json::Value> {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/trimesh_counts.py");
        let mut cmd = Command::new(self.dir.join("venv/bin/python"));
        cmd.arg(script).args(files);
        self.lines(cmd)
    }
}

/// A decoded 8-bit RGB PNG: its width, height and pixels row by row.
pub fn read_png(path: &Path) -> (usize, usize, Vec<[u8; 3]>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    let pixels = buf[..info.buffer_size()]
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    (info.width as usize, info.height as usize, pixels)
}

/// A closed cylinder about the z axis (drapekit's frame) of radius `r` from z0 to z1, its side
/// cut in `n` facets.
pub fn cylinder(r: f64, z0: f64, z1: f64, n: usize) -> TriMesh {
    frustum(r, r, z0, z1, n)
}

/// A closed frustum about the z axis: `n`-gons of radius `r0` at z0 and `r1` at z1. Its
/// section at z is the `n`-gon of radius `r0 + (r1 - r0) (z - z0) / (z1 - z0)`, of perimeter
/// `2 n r sin(pi / n)` (each side face is a planar trapezoid).
pub fn frustum(r0: f64, r1: f64, z0: f64, z1: f64, n: usize) -> TriMesh {
    let mut p = Vec::new();
    for &(r, z) in &[(r0, z0), (r1, z1)] {
        for k in 0..n {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            p.push(Point3::new(r * a.cos(), r * a.sin(), z));
        }
    }
    p.push(Point3::new(0.0, 0.0, z0));
    p.push(Point3::new(0.0, 0.0, z1));
    let (c0, c1) = (2 * n as u32, 2 * n as u32 + 1);
    let mut f = Vec::new();
    for k in 0..n as u32 {
        let j = (k + 1) % n as u32;
        let n = n as u32;
        f.push([k, j, n + j]);
        f.push([k, n + j, n + k]);
        f.push([c0, j, k]);
        f.push([c1, n + k, n + j]);
    }
    TriMesh::new(p, f)
}

/// Writes `mesh` (drapekit's frame, z up) as an OBJ in GarmentCode's frame (y up): the file's
/// `(x, y, z)` is drapekit's `(x, z, -y)`.
pub fn write_y_up_obj(mesh: &TriMesh, path: &Path) {
    let mut obj = String::new();
    for p in &mesh.positions {
        obj += &format!("v {} {} {}\n", p.x, p.z, -p.y);
    }
    for f in &mesh.faces {
        obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    std::fs::write(path, obj).unwrap();
}
