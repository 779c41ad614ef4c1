//! Interrupting `drape` with SIGINT or SIGTERM and resuming it: the exit status, no temporary
//! or partial file left, the finished frames intact, a checkpoint; `--resume` ends with the
//! outputs of a run never stopped, byte for byte. Checkpoints of another scene are refused,
//! and stale temporary files of ours (only those) are cleaned at the start of a run.
#![cfg(unix)]

mod common;

use common::{drapekit, listing, text};
use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// The scene: `cotton_on_sphere.toml` (real cotton, 41 x 41 particles, on the sphere fixture,
/// the default solver) for 300 steps with a frame every 10, dropped from `drop` m. Long enough
/// that a signal sent when the first frame is being written comes well before the end.
fn scene(dir: &Path, name: &str, drop: f64) -> PathBuf {
    let text = std::fs::read_to_string(common::fixture("scenes/cotton_on_sphere.toml")).unwrap();
    let text = text
        .replace("until_rest = 1e-6", "steps = 300")
        .replace("max_steps = 1000", "")
        .replace(
            "position = [0.0, 0.0, 0.33]",
            &format!("position = [0.0, 0.0, {drop}]"),
        )
        + "\n[output]\nframes = 10\n";
    std::fs::create_dir_all(dir).unwrap();
    let sphere = "sphere_r0.3.obj";
    std::fs::copy(common::fixture("scenes").join(sphere), dir.join(sphere)).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn drape(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    drapekit()
        .args([
            "drape".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
        .args(extra)
        .output()
        .unwrap()
}

/// The uninterrupted run (with `--glb` and a report), shared by the tests.
fn reference() -> &'static (tempfile::TempDir, PathBuf) {
    static REF: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    REF.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let s = scene(dir.path(), "drop.toml", 0.33);
        let out = dir.path().join("out");
        let report = dir.path().join("report.json");
        let o = drape(&s, &out, &["--glb", "--report", report.to_str().unwrap()]);
        assert!(o.status.success(), "{:?}", text(&o));
        (dir, out)
    })
}

/// Every file under `dir` (relative path, bytes), sorted.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for name in listing(dir) {
        let p = dir.join(&name);
        if p.is_dir() {
            out.extend(
                files(&p)
                    .into_iter()
                    .map(|(n, b)| (format!("{name}/{n}"), b)),
            );
        } else {
            out.push((name, std::fs::read(&p).unwrap()));
        }
    }
    out
}

/// The files of ours that are temporary (`io::TEMP_PREFIX`), anywhere under `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    let all = files(dir).into_iter().map(|(n, _)| n);
    all.filter(|n| n.contains(drapekit::io::TEMP_PREFIX) || n.ends_with(".tmp"))
        .collect()
}

/// The report without what a resumed run cannot share: wall times, and the folder of the
/// scene and the outputs.
fn comparable_report(path: &Path, dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.replace(&dir.display().to_string(), "DIR");
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    fn strip(v: &mut serde_json::Value) {
        if let Some(m) = v.as_object_mut() {
            m.retain(|k, _| !k.ends_with("_seconds"));
            m.values_mut().for_each(strip);
        } else if let Some(a) = v.as_array_mut() {
            a.iter_mut().for_each(strip);
        }
    }
    strip(&mut v);
    v
}

/// Starts `drape` on `scene` into `out`, waits until its first frame is being written (a
/// temporary file in `out/frames`), sends `signal` and waits for the end.
fn interrupt(scene: &Path, out: &Path, signal: i32) -> Output {
    let child = drapekit()
        .args([
            "drape".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
        .arg("--glb")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let frames = out.join("frames");
    let start = Instant::now();
    while !frames.is_dir() || listing(&frames).is_empty() {
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "no frame after 10 minutes"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    // SAFETY: a signal to the child we started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
    child.wait_with_output().unwrap()
}

fn interrupted_then_resumed(signal: i32, status: i32) {
    let (_keep, reference) = reference();
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "drop.toml", 0.33);
    let out = dir.path().join("out");
    let o = interrupt(&s, &out, signal);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(status), "{err}");
    let checkpoint = out.join("drop.checkpoint");
    assert!(err.contains(&checkpoint.display().to_string()), "{err}");
    assert!(err.contains("--resume"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    assert!(checkpoint.is_file(), "{err}");
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    // The finished frames are complete files, each as the uninterrupted run wrote it.
    let frames = listing(&out.join("frames"));
    assert!(!frames.is_empty());
    for f in &frames {
        let mine = std::fs::read(out.join("frames").join(f)).unwrap();
        let theirs = std::fs::read(reference.join("frames").join(f)).unwrap();
        assert!(mine == theirs, "frame {f} differs");
        let read = drapekit::io::read_mesh(
            &out.join("frames").join(f),
            &drapekit::io::ReadOptions::default(),
        )
        .unwrap();
        assert_eq!(read.mesh.positions.len(), 41 * 41, "{f}");
    }
    // Nothing but frames and the checkpoint: the pieces are written at the end.
    assert_eq!(listing(&out), ["drop.checkpoint", "frames"]);

    let report = dir.path().join("report.json");
    let o = drape(
        &s,
        &out,
        &["--glb", "--resume", "--report", report.to_str().unwrap()],
    );
    assert!(o.status.success(), "{:?}", text(&o));
    assert!(!checkpoint.exists(), "the checkpoint is removed at the end");
    let mine = files(&out);
    let theirs = files(reference);
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&mine), names(&theirs));
    for ((name, a), (_, b)) in mine.iter().zip(&theirs) {
        assert!(a == b, "{name} differs from the uninterrupted run's");
    }
    let ref_dir = reference.parent().unwrap();
    assert_eq!(
        comparable_report(&report, dir.path()),
        comparable_report(&ref_dir.join("report.json"), ref_dir)
    );
}

#[test]
fn sigint_stops_with_130_and_a_checkpoint_that_resumes_to_the_same_bytes() {
    interrupted_then_resumed(libc::SIGINT, 130);
}

#[test]
fn sigterm_stops_with_143_and_a_checkpoint_that_resumes_to_the_same_bytes() {
    interrupted_then_resumed(libc::SIGTERM, 143);
}

#[test]
fn another_scenes_checkpoint_is_refused_and_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let a = scene(&dir.path().join("a"), "drop.toml", 0.33);
    let out = dir.path().join("out");
    let o = interrupt(&a, &out, libc::SIGINT);
    assert_eq!(o.status.code(), Some(130), "{:?}", text(&o));
    let checkpoint = out.join("drop.checkpoint");
    let before = std::fs::read(&checkpoint).unwrap();
    // The same name, dropped from elsewhere: another scene.
    let b = scene(&dir.path().join("b"), "drop.toml", 0.40);
    let o = drape(&b, &out, &["--glb", "--resume"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("was written for another scene"), "{err}");
    // Other options.
    let o = drape(&a, &out, &["--resume"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("glb=true; this run: glb=false"), "{err}");
    assert_eq!(
        std::fs::read(&checkpoint).unwrap(),
        before,
        "left as it was"
    );
    // No checkpoint at all.
    let o = drape(&a, &dir.path().join("elsewhere"), &["--resume"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("there is no checkpoint"), "{err}");
    assert!(!dir.path().join("elsewhere").exists());
}

#[test]
fn stale_temporary_files_of_ours_are_cleaned_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "drop.toml", 0.33);
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("frames")).unwrap();
    let prefix = drapekit::io::TEMP_PREFIX;
    // Left by a run killed with SIGKILL (its process id is past Linux's largest: gone).
    let stale = [
        format!("{prefix}4194305-square.obj.Ab12Cd.tmp"),
        format!("frames/{prefix}4194305-square_0000010.obj.Ef34Gh.tmp"),
    ];
    // Not ours, or of a run still going (this test's own process).
    let kept = [
        ".square.obj.Ab12Cd.tmp".to_string(),
        "notes.txt".into(),
        format!("{prefix}{}-square.obj.Ij56Kl.tmp", std::process::id()),
    ];
    for f in stale.iter().chain(&kept) {
        std::fs::write(out.join(f), "partial").unwrap();
    }
    let o = drape(&s, &out, &[]);
    let (_, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("removed 2 temporary files"), "{err}");
    for f in &stale {
        assert!(!out.join(f).exists(), "{f} stayed");
    }
    for f in &kept {
        assert_eq!(
            std::fs::read_to_string(out.join(f)).unwrap(),
            "partial",
            "{f}"
        );
    }
}
