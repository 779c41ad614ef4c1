//! Checkpoints: a run's state after a finished step, enough to continue it to the same bits as
//! a run that was never stopped.
//!
//! **What is kept.** Everything the step loop reads before it writes it: the cloth's positions,
//! velocities and contacts; the step and the simulated time; the reach test's last travel;
//! the step each object's grid was first needed; the energy watch (its start, budget and the
//! work put in) and the rest test's window; the counters of the run and of cloth-against-cloth
//! contact; and the solver's own state (`cloth::integrate::saved`: implicit Euler's friction,
//! projective dynamics' contact stiffening, last projections and the factored matrix with its
//! low-rank correction). A caller may add positions it kept in memory (`frames`: drape's glTF
//! animation). What every step fills afresh (Anderson's history, Chebyshev's weights, the
//! self-contact hash) is not kept.
//!
//! **Format.** Binary, little-endian: [`MAGIC`] (16 bytes), [`VERSION`] (`u32`), the body's
//! length (`u64`), the body, and the SHA-256 of the body. Numbers are `u64` and `f64` as their
//! IEEE bits, so every `f64` comes back exactly (NaN and -0 included); lengths precede arrays.
//! JSON was the other choice: its decimal numbers come back exactly only with a careful
//! parser, it has no NaN, and it is three times the size for the arrays that make up almost
//! all of a checkpoint. The checksum catches a damaged or truncated file before anything of it
//! is used.
//!
//! **Fingerprint.** A checkpoint belongs to one scene and one set of options: the SHA-256 of
//! the scene file's bytes and of each object mesh's bytes ([`fingerprint`]), and the options
//! that change what a run writes, as text. [`Checkpoint::check`] refuses another scene's or
//! other options' checkpoint, naming which.

use super::watch::WatchState;
use super::{RunStats, World};
use crate::cloth::integrate::saved::{ImplicitKept, Kept, ProjectiveKept, SolverState, UpdateKept};
use crate::cloth::integrate::{Integrator, SolveStats};
use crate::cloth::state::{ClothState, Contact};
use crate::collide::cloth::SelfStats;
use crate::io::IoError;
use crate::math::{Point3, Vec3};
use crate::scene::Scene;
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// The first 16 bytes of every checkpoint file.
pub const MAGIC: &[u8; 16] = b"drapekit-ckpt\r\n\x1a";

/// The format's version; a file of another version is refused.
pub const VERSION: u32 = 1;

/// What a checkpoint belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct Fingerprint {
    /// SHA-256 of the scene file and its object meshes.
    pub scene: [u8; 32],
    /// The options that change what the run writes, as text (`--glb`, ...).
    pub options: String,
}

/// A run's state after step `step` (module notes).
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// What it belongs to (set by the caller; zeros from the run itself).
    pub fingerprint: Fingerprint,
    /// Steps finished.
    pub step: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Positions, velocities, contacts.
    pub state: ClothState,
    /// The largest distance a particle moved in the last step (the reach test), m.
    pub travel: f64,
    /// The step each object's grid was first needed.
    pub grid_built_at: Vec<Option<u64>>,
    /// The energy watch.
    pub watch: WatchState,
    /// The rest test's window, J.
    pub rest: Vec<f64>,
    /// The run's counters and wall times so far (`solver` as in `solver.stats`).
    pub stats: RunStats,
    /// The solver's state and counters.
    pub solver: SolverState,
    /// Cloth-against-cloth totals, when the world has it.
    pub self_contact: Option<SelfStats>,
    /// Positions the caller kept at earlier steps (drape's glTF animation), m.
    pub frames: Vec<(u64, Vec<Point3>)>,
}

/// Errors of checkpoints.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file could not be read.
    #[error("cannot read the checkpoint {}: {source}", .path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// An input could not be read for the fingerprint.
    #[error("cannot read {} for the checkpoint's fingerprint: {source}", .path.display())]
    Fingerprint {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Not a checkpoint.
    #[error("{} is not a drapekit checkpoint (it does not start with drapekit's header)", .path.display())]
    NotACheckpoint { path: PathBuf },
    /// Another version of the format.
    #[error("{} is a checkpoint of format version {found}; this drapekit reads version {expected}: run without --resume to start over", .path.display())]
    Version {
        path: PathBuf,
        found: u32,
        expected: u32,
    },
    /// Damaged or truncated.
    #[error("{} is damaged ({detail}): run without --resume to start over", .path.display())]
    Damaged { path: PathBuf, detail: String },
    /// Written for another scene.
    #[error("{} was written for another scene (the scene file or one of its object meshes is not the one the interrupted run read): run without --resume to start over, or resume with the scene as it was", .path.display())]
    OtherScene { path: PathBuf },
    /// Written with other options.
    #[error("{} was written with other options ({saved}; this run: {now}): resume with the same options, or run without --resume to start over", .path.display())]
    OtherOptions {
        path: PathBuf,
        saved: String,
        now: String,
    },
    /// Does not fit the world or the solver.
    #[error("the checkpoint does not fit this run: {what} is {found}, expected {expected}")]
    Mismatch {
        what: &'static str,
        found: String,
        expected: String,
    },
    /// Writing failed.
    #[error(transparent)]
    Write(#[from] IoError),
}

/// The fingerprint of `scene` (its file and its object meshes, read again) with `options`.
pub fn fingerprint(scene: &Scene, options: &str) -> Result<Fingerprint, CheckpointError> {
    let mut h = Sha256::new();
    let files = std::iter::once(&scene.path).chain(scene.objects.iter().map(|o| &o.mesh));
    for path in files {
        let bytes = std::fs::read(path).map_err(|source| CheckpointError::Fingerprint {
            path: path.clone(),
            source,
        })?;
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    Ok(Fingerprint {
        scene: h.finalize().into(),
        options: options.to_string(),
    })
}

impl Checkpoint {
    /// Refuses a checkpoint of another scene or other options than `now` (`path` for the
    /// message).
    pub fn check(&self, now: &Fingerprint, path: &Path) -> Result<(), CheckpointError> {
        if self.fingerprint.scene != now.scene {
            return Err(CheckpointError::OtherScene {
                path: path.to_path_buf(),
            });
        }
        if self.fingerprint.options != now.options {
            return Err(CheckpointError::OtherOptions {
                path: path.to_path_buf(),
                saved: self.fingerprint.options.clone(),
                now: now.options.clone(),
            });
        }
        Ok(())
    }

    /// Checks that it fits `world` and `integrator` (array lengths, the solver's kind).
    pub fn fits(&self, world: &World, integrator: Integrator) -> Result<(), CheckpointError> {
        let n = world.model.len();
        let s = &self.state;
        let kept_len = match &self.solver.kept {
            Kept::Nothing => None,
            Kept::Implicit(k) => {
                Some([k.stuck.len(), k.normal_force.len(), k.slip_dir.len()].to_vec())
            }
            Kept::Projective(k) => Some(
                [
                    k.stiff.len(),
                    k.target.len(),
                    k.factored.len(),
                    // The contacts are empty before the first contact step.
                    if k.contact.is_empty() {
                        n
                    } else {
                        k.contact.len()
                    },
                ]
                .to_vec(),
            ),
        };
        let lengths = [s.x.len(), s.v.len(), s.contact.len(), self.watch.x0.len()];
        let particles = lengths.iter().chain(kept_len.iter().flatten());
        if let Some(bad) = particles.copied().find(|&l| l != n) {
            return mismatch("the number of particles", bad, n);
        }
        if self.grid_built_at.len() != world.colliders.len() {
            let c = world.colliders.len();
            return mismatch("the number of objects", self.grid_built_at.len(), c);
        }
        if self.self_contact.is_some() != world.self_contact.is_some() {
            let yes_no = |b: bool| if b { "on" } else { "off" };
            return mismatch(
                "cloth against cloth",
                yes_no(self.self_contact.is_some()),
                yes_no(world.self_contact.is_some()),
            );
        }
        let kind = match (&self.solver.kept, integrator) {
            (Kept::Nothing, i) if i.is_explicit() => None,
            (Kept::Implicit(_), Integrator::ImplicitEuler) => None,
            (Kept::Projective(_), Integrator::ProjectiveDynamics) => None,
            (Kept::Nothing, _) => Some("an explicit integrator's"),
            (Kept::Implicit(_), _) => Some("implicit Euler's"),
            (Kept::Projective(_), _) => Some("projective dynamics'"),
        };
        match kind {
            Some(k) => mismatch("the solver state", k, format!("{integrator}'s")),
            None => Ok(()),
        }
    }

    /// The file's bytes (module notes).
    pub fn encode(&self) -> Vec<u8> {
        let mut e = Enc(Vec::new());
        e.body(self);
        let body = e.0;
        let mut out = Vec::with_capacity(body.len() + 60);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(body.len() as u64).to_le_bytes());
        out.extend_from_slice(&body);
        out.extend_from_slice(&Sha256::digest(&body));
        out
    }

    /// A checkpoint from a file's bytes; `path` names it in errors.
    pub fn decode(bytes: &[u8], path: &Path) -> Result<Checkpoint, CheckpointError> {
        let damaged = |detail: String| CheckpointError::Damaged {
            path: path.to_path_buf(),
            detail,
        };
        if bytes.len() < 16 || &bytes[..16] != MAGIC {
            return Err(CheckpointError::NotACheckpoint {
                path: path.to_path_buf(),
            });
        }
        let head = |at: usize, n: usize| {
            bytes
                .get(at..at + n)
                .ok_or_else(|| damaged(format!("{} bytes, shorter than its header", bytes.len())))
        };
        let version = u32::from_le_bytes(head(16, 4)?.try_into().unwrap());
        if version != VERSION {
            return Err(CheckpointError::Version {
                path: path.to_path_buf(),
                found: version,
                expected: VERSION,
            });
        }
        let len = u64::from_le_bytes(head(20, 8)?.try_into().unwrap());
        let expected = 28u64.saturating_add(len).saturating_add(32);
        if bytes.len() as u64 != expected {
            return Err(damaged(format!(
                "{} bytes where its header says {expected}",
                bytes.len()
            )));
        }
        let body = &bytes[28..28 + len as usize];
        if Sha256::digest(body).as_slice() != &bytes[28 + len as usize..] {
            return Err(damaged("its checksum does not match its content".into()));
        }
        let mut d = Dec { b: body, at: 0 };
        let c = d.body().map_err(damaged)?;
        if d.at != body.len() {
            return Err(damaged(format!("{} bytes left over", body.len() - d.at)));
        }
        Ok(c)
    }

    /// Writes it to `path` atomically (temporary file and rename), never over one of `inputs`.
    pub fn write(&self, path: &Path, inputs: &[&Path]) -> Result<(), CheckpointError> {
        let bytes = self.encode();
        crate::io::write_atomic(path, inputs, |w| std::io::Write::write_all(w, &bytes))?;
        Ok(())
    }

    /// Reads the checkpoint at `path`.
    pub fn read(path: &Path) -> Result<Checkpoint, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|source| CheckpointError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Checkpoint::decode(&bytes, path)
    }
}

fn mismatch(
    what: &'static str,
    found: impl ToString,
    expected: impl ToString,
) -> Result<(), CheckpointError> {
    Err(CheckpointError::Mismatch {
        what,
        found: found.to_string(),
        expected: expected.to_string(),
    })
}

/// The body's writer.
struct Enc(Vec<u8>);

impl Enc {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn len(&mut self, n: usize) {
        self.u64(n as u64);
    }
    fn each_f64(&mut self, v: &[f64]) {
        v.iter().for_each(|&x| self.f64(x));
    }
    fn f64s(&mut self, v: &[f64]) {
        self.len(v.len());
        self.each_f64(v);
    }
    fn triples<'a>(&mut self, v: impl ExactSizeIterator<Item = &'a [f64; 3]>) {
        self.len(v.len());
        v.flatten().for_each(|&x| self.f64(x));
    }
    fn points(&mut self, v: &[Point3]) {
        self.triples(v.iter().map(|p| &p.coords.data.0[0]));
    }
    fn vectors(&mut self, v: &[Vec3]) {
        self.triples(v.iter().map(|p| &p.data.0[0]));
    }
    fn contacts(&mut self, v: &[Option<Contact>]) {
        self.len(v.len());
        for c in v {
            match c {
                None => self.u8(0),
                Some(c) => {
                    self.u8(1);
                    self.u64(c.object.into());
                    self.u64(c.face.into());
                    self.f64(c.side);
                }
            }
        }
    }

    fn body(&mut self, c: &Checkpoint) {
        self.0.extend_from_slice(&c.fingerprint.scene);
        let options = c.fingerprint.options.as_bytes();
        self.len(options.len());
        self.0.extend_from_slice(options);
        self.u64(c.step);
        self.f64(c.time);
        self.points(&c.state.x);
        self.vectors(&c.state.v);
        self.contacts(&c.state.contact);
        self.f64(c.travel);
        self.len(c.grid_built_at.len());
        for g in &c.grid_built_at {
            self.u8(g.is_some().into());
            self.u64(g.unwrap_or(0));
        }
        self.points(&c.watch.x0);
        self.each_f64(&[c.watch.e0, c.watch.budget, c.watch.work]);
        self.f64s(&c.rest);
        let s = &c.stats;
        self.u64(s.steps);
        self.each_f64(&[s.time, s.wall_seconds, s.predict_seconds, s.solve_seconds]);
        self.each_f64(&[s.collision_seconds, s.measure_seconds]);
        self.u8(s.at_rest.into());
        self.solver(&c.solver);
        self.u8(c.self_contact.is_some().into());
        if let Some(t) = &c.self_contact {
            let counts = [t.candidates, t.contacts, t.corrected, t.approaching];
            counts.into_iter().for_each(|x| self.len(x));
            self.len(t.remaining);
            self.f64(t.seconds);
        }
        self.len(c.frames.len());
        for (step, x) in &c.frames {
            self.u64(*step);
            self.points(x);
        }
    }

    fn solver(&mut self, s: &SolverState) {
        let t = &s.stats;
        self.f64(t.factor_seconds);
        let counts = [t.factorisations, t.low_rank_columns, t.cg_iterations];
        counts.into_iter().for_each(|x| self.u64(x));
        self.u64(t.pd_iterations);
        match &s.kept {
            Kept::Nothing => self.u8(0),
            Kept::Implicit(k) => {
                self.u8(1);
                self.len(k.stuck.len());
                k.stuck.iter().for_each(|&b| self.u8(b.into()));
                self.f64s(&k.normal_force);
                self.vectors(&k.slip_dir);
            }
            Kept::Projective(k) => {
                self.u8(2);
                self.f64s(&k.stiff);
                self.points(&k.target);
                self.contacts(&k.contact);
                self.f64s(&k.factored);
                self.len(k.update.index.len());
                k.update.index.iter().for_each(|&u| self.u64(u.into()));
                self.f64s(&k.update.delta);
                self.f64s(&k.update.gram);
            }
        }
    }
}

/// The body's reader; errors say what is wrong and where.
struct Dec<'a> {
    b: &'a [u8],
    at: usize,
}

type Got<T> = Result<T, String>;

impl Dec<'_> {
    fn take(&mut self, n: usize) -> Got<&[u8]> {
        let s = self.b.get(self.at..self.at.saturating_add(n));
        let s = s.ok_or_else(|| format!("it ends inside a record at byte {}", self.at))?;
        self.at += n;
        Ok(s)
    }
    fn u8(&mut self) -> Got<u8> {
        Ok(self.take(1)?[0])
    }
    fn flag(&mut self) -> Got<bool> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(format!("a flag of {b} at byte {}", self.at - 1)),
        }
    }
    fn u64(&mut self) -> Got<u64> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
    fn u32(&mut self) -> Got<u32> {
        let at = self.at;
        let v = self.u64()?;
        u32::try_from(v).map_err(|_| format!("an index of {v} at byte {at}"))
    }
    fn f64(&mut self) -> Got<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// A length of items of at least `size` bytes each (never more than the bytes left).
    fn len(&mut self, size: usize) -> Got<usize> {
        let at = self.at;
        let n = self.u64()?;
        let left = (self.b.len() - self.at) as u64;
        if n.saturating_mul(size as u64) > left {
            return Err(format!("a length of {n} at byte {at}, past its end"));
        }
        Ok(n as usize)
    }
    fn f64s(&mut self) -> Got<Vec<f64>> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
    fn triple(&mut self) -> Got<[f64; 3]> {
        Ok([self.f64()?, self.f64()?, self.f64()?])
    }
    fn points(&mut self) -> Got<Vec<Point3>> {
        let n = self.len(24)?;
        (0..n).map(|_| Ok(Point3::from(self.triple()?))).collect()
    }
    fn vectors(&mut self) -> Got<Vec<Vec3>> {
        let n = self.len(24)?;
        (0..n).map(|_| Ok(Vec3::from(self.triple()?))).collect()
    }
    fn contacts(&mut self) -> Got<Vec<Option<Contact>>> {
        let n = self.len(1)?;
        (0..n)
            .map(|_| {
                Ok(match self.flag()? {
                    false => None,
                    true => Some(Contact {
                        object: self.u32()?,
                        face: self.u32()?,
                        side: self.f64()?,
                    }),
                })
            })
            .collect()
    }

    fn body(&mut self) -> Got<Checkpoint> {
        let scene: [u8; 32] = self.take(32)?.try_into().unwrap();
        let n = self.len(1)?;
        let options = String::from_utf8(self.take(n)?.to_vec())
            .map_err(|_| "its options are not UTF-8".to_string())?;
        let step = self.u64()?;
        let time = self.f64()?;
        let state = ClothState {
            x: self.points()?,
            v: self.vectors()?,
            contact: self.contacts()?,
        };
        let travel = self.f64()?;
        let n = self.len(9)?;
        let mut grid_built_at = Vec::with_capacity(n);
        for _ in 0..n {
            let (built, step) = (self.flag()?, self.u64()?);
            grid_built_at.push(built.then_some(step));
        }
        let watch = WatchState {
            x0: self.points()?,
            e0: self.f64()?,
            budget: self.f64()?,
            work: self.f64()?,
        };
        let rest = self.f64s()?;
        let stats = RunStats {
            steps: self.u64()?,
            time: self.f64()?,
            wall_seconds: self.f64()?,
            predict_seconds: self.f64()?,
            solve_seconds: self.f64()?,
            collision_seconds: self.f64()?,
            measure_seconds: self.f64()?,
            at_rest: self.flag()?,
            solver: SolveStats::default(),
        };
        let solver = self.solver()?;
        let stats = RunStats {
            solver: solver.stats,
            ..stats
        };
        let self_contact = match self.flag()? {
            false => None,
            true => Some(SelfStats {
                candidates: self.u64()? as usize,
                contacts: self.u64()? as usize,
                corrected: self.u64()? as usize,
                approaching: self.u64()? as usize,
                remaining: self.u64()? as usize,
                seconds: self.f64()?,
            }),
        };
        let n = self.len(16)?;
        let mut frames = Vec::with_capacity(n);
        for _ in 0..n {
            frames.push((self.u64()?, self.points()?));
        }
        Ok(Checkpoint {
            fingerprint: Fingerprint { scene, options },
            step,
            time,
            state,
            travel,
            grid_built_at,
            watch,
            rest,
            stats,
            solver,
            self_contact,
            frames,
        })
    }

    fn solver(&mut self) -> Got<SolverState> {
        let stats = SolveStats {
            factor_seconds: self.f64()?,
            factorisations: self.u64()?,
            low_rank_columns: self.u64()?,
            cg_iterations: self.u64()?,
            pd_iterations: self.u64()?,
        };
        let at = self.at;
        let kept = match self.u8()? {
            0 => Kept::Nothing,
            1 => {
                let n = self.len(1)?;
                Kept::Implicit(ImplicitKept {
                    stuck: (0..n).map(|_| self.flag()).collect::<Got<_>>()?,
                    normal_force: self.f64s()?,
                    slip_dir: self.vectors()?,
                })
            }
            2 => Kept::Projective(ProjectiveKept {
                stiff: self.f64s()?,
                target: self.points()?,
                contact: self.contacts()?,
                factored: self.f64s()?,
                update: {
                    let k = self.len(8)?;
                    UpdateKept {
                        index: (0..k).map(|_| self.u32()).collect::<Got<_>>()?,
                        delta: self.f64s()?,
                        gram: self.f64s()?,
                    }
                },
            }),
            t => return Err(format!("a solver of kind {t} at byte {at}")),
        };
        Ok(SolverState { stats, kept })
    }
}
