//! Hostile input: a text mesh of millions of blank lines is read with memory proportional to the
//! mesh, not to the line count, and its messages still name the right line. The only test of
//! this binary, so the process's peak memory is its own.

use std::io::Write;

/// The peak resident memory of this process so far (`VmHWM`), in bytes.
fn peak_rss() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("Linux /proc");
    let line = status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .expect("VmHWM");
    let kb: u64 = line
        .split_whitespace()
        .nth(1)
        .and_then(|v| v.parse().ok())
        .expect("a number of kB");
    kb * 1024
}

#[test]
fn hostile_thirty_million_blank_lines_take_little_memory() {
    const BLANK: u64 = 30_000_000;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("blank.obj");
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        w.write_all(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
        let chunk = vec![b'\n'; 1 << 20];
        for _ in 0..BLANK / chunk.len() as u64 {
            w.write_all(&chunk).unwrap();
        }
        w.write_all(&chunk[..(BLANK % chunk.len() as u64) as usize])
            .unwrap();
        w.write_all(b"f 1 2 3\nv 1 2 x\n").unwrap();
    }
    let before = peak_rss();
    let e = drapekit::io::read_mesh(&path, &Default::default())
        .unwrap_err()
        .to_string();
    let grown = peak_rss().saturating_sub(before);
    let bad_line = 3 + BLANK + 2;
    assert!(
        e.contains(&format!("blank.obj:{bad_line}: 'x' is not a number")),
        "{e}"
    );
    // The file is 30 MB; a table of its lines took 16 bytes a line (480 MB and more).
    assert!(
        grown < 16 << 20,
        "reading grew the peak memory by {grown} bytes"
    );
}
