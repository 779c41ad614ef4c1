//! A short, seeded, deterministic mutation pass over every reader (issue 9): the poor man's
//! fuzzer that runs with the normal test suite, so a reader that starts to panic is caught by CI
//! and not only by whoever runs `cargo fuzz` (README, "Fuzzing").
//!
//! For every fuzz target (`fuzz/checks.rs`, the same checks the cargo-fuzz targets run) and every
//! seed file of `fuzz/corpus/<target>/`, [`ROUNDS`] inputs are made from the seed by one to four
//! stacked mutations drawn from a splitmix64 generator seeded by the target's and the seed's
//! names: bit flips, interesting bytes, insertions, deletions, truncation, a duplicated chunk, a
//! splice with another seed of the target, a number replaced by an extreme one (`1e308`, `-0`,
//! `nan`, `4294967295`, ...), a 32-bit word replaced by an extreme count or float (binary
//! headers: STL's triangle count, glb chunk lengths, PLY binary lists), and a deep run of
//! brackets. The same inputs every run, on any machine. The inputs of `REGRESSIONS` (crashes
//! found and fixed) run first.
//!
//! A failure names the target, the seed and the round, with the input saved to a temporary file
//! to replay: `cargo +nightly fuzz run <target> <file>`. A reader that runs for more than
//! [`HANG`] on one input fails the test the same way (a hang, not a slow machine: the inputs are
//! at most a few kB).

#[path = "../fuzz/checks.rs"]
mod checks;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

/// Mutated inputs per seed file.
const ROUNDS: u64 = 1000;

/// One input running longer than this is a hang.
const HANG: Duration = Duration::from_secs(120);

/// Crashes and hangs found by fuzzing and fixed, minimised: (target, input). Each must read
/// without a panic, in time.
const REGRESSIONS: &[(&str, &[u8])] = &[
    // A binary element of no properties and a count of 2^64 - 1 looped for ever over records
    // that hold no bytes (found by this pass: a mutation broke the face element's only
    // property line, which was then skipped as an unknown header line).
    (
        "mesh_ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n\
          property float y\nproperty float z\nelement face 18446744073709551615\nend_header\n\
          \0\0\0\0\0\0\0\0\0\0\0\0",
    ),
    // Measurements whose shape model had sections of inf or NaN (the fitter then refused
    // "section 1: point 1 is not a finite number", naming no key): a stature near the top of
    // the f64 range, one near its bottom with a huge girth, a huge shoulder width, levels
    // 1e-320 apart.
    (
        "measurements_toml",
        b"stature = 1e308\nbust_girth = 92\nwaist_girth = 74\nwaist_height = 106\n",
    ),
    (
        "measurements_toml",
        b"stature = 168\nbust_girth = 92\nwaist_girth = 74\nwaist_height = 1e-320\n",
    ),
    (
        "measurements_yaml",
        b"body:\n  height: 1e-320\n  bust: 1e-320\n  waist: 9223372036854775807\n  hips: 96\n",
    ),
    (
        "measurements_yaml",
        b"body:\n  height: 171.99\n  bust: 99.8\n  waist: 84.3\n  hips: 103.5\n  shoulder_w: 1e308\n",
    ),
];

/// splitmix64 (Steele, Lea and Flood 2014): a tiny generator of good 64-bit values.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A value in `0..n` (`n > 0`).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// FNV-1a of the names: the generator's seed for one seed file of one target.
fn seed_of(parts: &[&str]) -> u64 {
    parts
        .iter()
        .flat_map(|p| p.bytes().chain([0]))
        .fold(0xCBF2_9CE4_8422_2325, |h, b| {
            (h ^ b as u64).wrapping_mul(0x0100_0000_01B3)
        })
}

/// Numbers that break naive readers: overflow, signed zero, NaN and infinity spelled as text,
/// 32- and 64-bit limits (as counts and indices), subnormals.
const EXTREME_NUMBERS: &[&str] = &[
    "1e308",
    "-1e308",
    "1e309",
    "-0",
    "-0.0",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "4294967295",
    "4294967296",
    "2147483648",
    "-2147483649",
    "18446744073709551615",
    "9223372036854775807",
    "99999999999999999999999",
    "-1",
    "0",
    "1e-320",
    "0x10",
];

/// 32-bit words for binary headers and bodies: counts and lengths at their limits, and the
/// bits of float NaN and infinities.
const EXTREME_WORDS: &[u32] = &[
    0,
    1,
    0xFFFF_FFFF,
    0x7FFF_FFFF,
    0x8000_0000,
    0x0100_0000,
    0x7FC0_0000,
    0x7F80_0000,
    0xFF80_0000,
];

/// Bytes that change a token's meaning in the text formats.
const INTERESTING_BYTES: &[u8] = b"\0\xFF\x7F\x80\n\r\t \",:;#[]{}()/\\-+.e9";

/// Whether byte `b` can be part of a number token.
fn numeric(b: u8) -> bool {
    b.is_ascii_digit() || matches!(b, b'-' | b'+' | b'.' | b'e' | b'E')
}

/// One mutation of `data` (`others`: the target's seeds, for splicing).
fn mutate(rng: &mut SplitMix, data: &mut Vec<u8>, others: &[Vec<u8>]) {
    let len = data.len();
    match rng.below(11) {
        0 if len > 0 => {
            let i = rng.below(len);
            data[i] ^= 1 << rng.below(8);
        }
        1 if len > 0 => {
            let i = rng.below(len);
            data[i] = *rng.pick(INTERESTING_BYTES);
        }
        2 => {
            let at = rng.below(len + 1);
            let n = 1 + rng.below(8);
            let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
            data.splice(at..at, bytes);
        }
        3 if len > 0 => {
            let at = rng.below(len);
            let n = 1 + rng.below(16.min(len - at));
            data.drain(at..at + n);
        }
        4 => data.truncate(rng.below(len + 1)),
        5 if len > 0 => {
            let from = rng.below(len);
            let n = 1 + rng.below(64.min(len - from));
            let chunk = data[from..from + n].to_vec();
            let at = rng.below(len + 1);
            let times = 1 + rng.below(4);
            for _ in 0..times {
                data.splice(at..at, chunk.iter().copied());
            }
        }
        6 => {
            let other = rng.pick(others);
            let cut = rng.below(len + 1);
            let from = rng.below(other.len() + 1);
            data.truncate(cut);
            data.extend_from_slice(&other[from..]);
        }
        7 => replace_number(rng, data),
        8 if len >= 4 => {
            let at = rng.below(len - 3);
            let word = *rng.pick(EXTREME_WORDS);
            let bytes = if rng.below(2) == 0 {
                word.to_le_bytes()
            } else {
                word.to_be_bytes()
            };
            data[at..at + 4].copy_from_slice(&bytes);
        }
        9 => {
            let at = rng.below(len + 1);
            let open = *rng.pick(b"[{(");
            let n = 1 + rng.below(3000);
            data.splice(at..at, std::iter::repeat_n(open, n));
        }
        _ => replace_number(rng, data),
    }
}

/// Replaces a number token of `data` (a run of digits, signs, points and exponents holding a
/// digit), chosen at random, by an extreme number; nothing when there is none.
fn replace_number(rng: &mut SplitMix, data: &mut Vec<u8>) {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < data.len() {
        if numeric(data[i]) {
            let start = i;
            while i < data.len() && numeric(data[i]) {
                i += 1;
            }
            if data[start..i].iter().any(u8::is_ascii_digit) {
                spans.push(start..i);
            }
        } else {
            i += 1;
        }
    }
    if spans.is_empty() {
        return;
    }
    let span = rng.pick(&spans).clone();
    data.splice(span, rng.pick(EXTREME_NUMBERS).bytes());
}

/// The seed files of `target`, sorted by name: every file of `fuzz/corpus/<target>/` but
/// hidden files and the 40-hex-digit names libFuzzer gives the inputs it finds.
fn seeds(target: &str) -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy();
            let found = name.len() == 40 && name.bytes().all(|b| b.is_ascii_hexdigit());
            p.is_file() && !name.starts_with('.') && !found
        })
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    out.sort();
    out
}

/// One input to run: what to call it in a failure, the target, the bytes.
struct Case {
    label: String,
    target: &'static str,
    data: Vec<u8>,
}

/// Every input of the pass, in order: the regressions, then each target's seeds as they are
/// and [`ROUNDS`] mutations of each.
fn cases() -> Vec<Case> {
    let mut out: Vec<Case> = REGRESSIONS
        .iter()
        .enumerate()
        .map(|(i, &(target, data))| Case {
            label: format!("{target} regression {i}"),
            target,
            data: data.to_vec(),
        })
        .collect();
    for &(target, _) in checks::TARGETS {
        let seeds = seeds(target);
        assert!(!seeds.is_empty(), "fuzz/corpus/{target} has no seed");
        let bodies: Vec<Vec<u8>> = seeds.iter().map(|(_, d)| d.clone()).collect();
        for (name, seed) in &seeds {
            let mut rng = SplitMix(seed_of(&[target, name]));
            out.push(Case {
                label: format!("{target} seed {name} as it is"),
                target,
                data: seed.clone(),
            });
            for round in 0..ROUNDS {
                let mut data = seed.clone();
                // One mutation half the time, two a quarter, at most four.
                for _ in 0..1 + (rng.next().trailing_zeros() as usize).min(3) {
                    mutate(&mut rng, &mut data, &bodies);
                }
                out.push(Case {
                    label: format!("{target} seed {name} round {round}"),
                    target,
                    data,
                });
            }
        }
    }
    out
}

/// Saves a failing input for replay; returns where.
fn save(case: &Case) -> PathBuf {
    let file = tempfile::Builder::new()
        .prefix(&format!("drapekit-fuzz-{}-", case.target))
        .suffix(".bin")
        .tempfile()
        .unwrap();
    std::fs::write(file.path(), &case.data).unwrap();
    file.into_temp_path().keep().unwrap()
}

/// What the worker reports: an input it starts, or the failures once done.
enum Progress {
    Start(usize),
    Done(Vec<String>),
}

/// Runs every case on a worker thread (the stack of a main thread, 8 MiB, as the binary has);
/// each panic is a failure. Returns the failures, or the index of a case that hangs.
fn run(cases: std::sync::Arc<Vec<Case>>) -> Result<Vec<String>, usize> {
    let (tx, rx) = mpsc::channel();
    let worker = cases.clone();
    std::thread::Builder::new()
        .name("fuzz_mutation".into())
        .stack_size(8 << 20)
        .spawn(move || {
            let mut failures = Vec::new();
            for (i, case) in worker.iter().enumerate() {
                tx.send(Progress::Start(i)).unwrap();
                let check = checks::check(case.target).unwrap();
                if let Err(e) = catch_unwind(AssertUnwindSafe(|| check(&case.data))) {
                    let msg = e
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_default();
                    let file = save(case);
                    failures.push(format!(
                        "{}: panicked: {msg}\n  input saved to {}",
                        case.label,
                        file.display()
                    ));
                }
            }
            tx.send(Progress::Done(failures)).unwrap();
        })
        .unwrap();
    let mut current = None;
    loop {
        match rx.recv_timeout(HANG) {
            Ok(Progress::Start(i)) => current = Some(i),
            Ok(Progress::Done(f)) => return Ok(f),
            Err(_) => return Err(current.expect("the worker starts at once")),
        }
    }
}

#[test]
fn every_reader_survives_seeded_mutations_of_its_seeds() {
    let cases = std::sync::Arc::new(cases());
    match run(cases.clone()) {
        Ok(failures) => assert!(
            failures.is_empty(),
            "{} of {} inputs failed:\n{}",
            failures.len(),
            cases.len(),
            failures.join("\n")
        ),
        Err(i) => panic!(
            "{}: still running after {HANG:?}\n  input saved to {}",
            cases[i].label,
            save(&cases[i]).display()
        ),
    }
}

#[test]
fn every_seed_is_accepted_by_its_reader() {
    // Mutations of valid files reach past the first checks of a reader.
    for &(target, check) in checks::TARGETS {
        for (name, data) in seeds(target) {
            assert!(check(&data), "fuzz/corpus/{target}/{name} is refused");
        }
    }
}

#[test]
fn the_mutations_are_the_same_every_run() {
    let a: Vec<Vec<u8>> = cases().into_iter().map(|c| c.data).collect();
    let b: Vec<Vec<u8>> = cases().into_iter().map(|c| c.data).collect();
    assert_eq!(a, b);
    // The first outputs of the reference splitmix64.c (Vigna) for the seed 1234567.
    let mut r = SplitMix(1234567);
    assert_eq!(
        [r.next(), r.next(), r.next()],
        [
            6457827717110365317,
            3203168211198807973,
            9817491932198370423
        ]
    );
}

#[test]
fn every_fuzz_target_has_a_check_and_seeds() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/fuzz_targets");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let mut names: Vec<String> = checks::TARGETS
        .iter()
        .map(|(n, _)| format!("{n}.rs"))
        .collect();
    names.sort();
    assert_eq!(files, names, "fuzz/fuzz_targets against checks::TARGETS");
    let manifest = std::fs::read_to_string(dir.join("../Cargo.toml")).unwrap();
    for (n, _) in checks::TARGETS {
        assert!(
            manifest.contains(&format!("name = \"{n}\"\npath = \"fuzz_targets/{n}.rs\"")),
            "fuzz/Cargo.toml has no [[bin]] {n}"
        );
        let target = std::fs::read_to_string(dir.join(format!("{n}.rs"))).unwrap();
        assert!(
            target.contains(&format!("checks::run(\"{n}\", data)")),
            "fuzz_targets/{n}.rs does not run the check {n}"
        );
    }
}
