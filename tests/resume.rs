//! Checkpoints through the library (no signals): a run cancelled after step k and continued from
//! its checkpoint (written to bytes and read back) ends with the same bits as a run that was
//! never stopped, for every integrator; checkpoints that do not belong are refused.

use drapekit::cloth::fabric::Fabric;
use drapekit::cloth::integrate::saved::Kept;
use drapekit::cloth::integrate::{Integrator, SolverSettings};
use drapekit::cloth::model::ClothModel;
use drapekit::cloth::pattern::{self, Pins};
use drapekit::collide::Collider;
use drapekit::math::{Point2, Point3, Vec3};
use drapekit::sim::checkpoint::Fingerprint;
use drapekit::sim::{self, Checkpoint, CheckpointError, Control, RunStats, SimError, Stop, World};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// A square of `fabric` (`half` m from its centre to a side, particles `spacing` apart) `gap`
/// m above the top of a sphere of radius 0.3 (friction 0.5), falling at `speed` m/s.
fn over_sphere(fabric: &Fabric, half: f64, spacing: f64, gap: f64, speed: f64) -> World {
    let s = half;
    let outline = [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| Point2::new(x, y));
    let p = pattern::build(&outline, spacing, fabric, &Pins::default()).unwrap();
    let z = 0.3 + fabric.thickness + gap;
    let placed: Vec<Point3> = p.flat.iter().map(|q| Point3::new(q.x, q.y, z)).collect();
    let (m, x) = ClothModel::assemble(
        &[("square".into(), p, fabric.clone(), placed)],
        Vec3::new(0.0, 0.0, -9.81),
    );
    let mut sphere = drapekit::mesh::generate::icosphere(3);
    for q in &mut sphere.positions {
        *q = Point3::from(q.coords * 0.3);
    }
    let c = Collider::new(
        "sphere".into(),
        sphere,
        [8, 8, 8],
        fabric.thickness,
        Some(0.5),
    );
    let mut w = World::new(m, x, vec![c], Integrator::default());
    w.state
        .v
        .iter_mut()
        .for_each(|v| *v = Vec3::new(0.0, 0.0, -speed));
    w
}

/// A case: the world, the settings, the steps and the step to stop at.
struct Case {
    world: fn() -> World,
    settings: SolverSettings,
    steps: u64,
    at: u64,
}

/// Real cotton dropped from 5 cm at 10 ms steps (it lands in its 10th step).
fn dropped() -> World {
    over_sphere(&Fabric::cotton(), 0.2, 0.02, 0.05, 0.0)
}

/// A soft cloth 0.5 mm above the sphere, falling at 1 m/s: explicit steps reach it at once.
fn soft_falling() -> World {
    let soft = Fabric {
        stretch: [5.0, 5.0],
        shear: 0.5,
        damping: 20.0,
        ..Fabric::cotton()
    };
    over_sphere(&soft, 0.2, 0.04, 0.5e-3, 1.0)
}

fn case(integrator: Integrator) -> Case {
    let settings = SolverSettings::new(integrator);
    if integrator.is_explicit() {
        let dt = 0.9 * soft_falling_step(integrator);
        return Case {
            world: soft_falling,
            settings: settings.with_dt(dt),
            steps: 400,
            at: 250,
        };
    }
    Case {
        world: dropped,
        settings,
        steps: 30,
        at: 16,
    }
}

fn soft_falling_step(integrator: Integrator) -> f64 {
    let w = soft_falling();
    let m = &w.model;
    integrator.stable_step(
        drapekit::cloth::stability::frequency_bound(m),
        drapekit::cloth::stability::min_damping(m),
    )
}

/// Runs `c` from its world with a frame after every step; `control` as given, and the flag
/// set after step `stop_at` when there is one.
fn run(
    c: &Case,
    stop_at: Option<u64>,
    resume: Option<&Checkpoint>,
) -> (World, Result<RunStats, SimError>) {
    let mut w = (c.world)();
    let flag = AtomicBool::new(false);
    let mut frame = |step: u64, _: &World| {
        if Some(step) == stop_at {
            flag.store(true, Ordering::SeqCst);
        }
        Ok(false)
    };
    let control = Control {
        cancel: Some(&flag),
        resume,
        ..Control::default()
    };
    let stop = Stop::Steps(c.steps);
    let r = sim::run(
        &mut w,
        &c.settings,
        stop,
        Some(1),
        &mut frame,
        &|_| {},
        control,
    );
    (w, r)
}

fn bits(x: &[Point3], v: &[Vec3]) -> Vec<u64> {
    x.iter()
        .flat_map(|p| p.coords.iter().copied().collect::<Vec<_>>())
        .chain(v.iter().flat_map(|q| q.iter().copied().collect::<Vec<_>>()))
        .map(f64::to_bits)
        .collect()
}

/// The checkpoint of `c` after its step `at`, through bytes.
fn checkpoint_of(c: &Case) -> Checkpoint {
    let (w, r) = run(c, Some(c.at), None);
    let Err(SimError::Interrupted(ck)) = r else {
        panic!("the run was not interrupted: {r:?}");
    };
    assert_eq!(ck.step, c.at);
    assert_eq!(ck.time, c.at as f64 * c.settings.dt);
    assert_eq!(
        ck.state, w.state,
        "the checkpoint holds the world at the stop"
    );
    let bytes = ck.encode();
    let back = Checkpoint::decode(&bytes, Path::new("x.checkpoint")).unwrap();
    assert_eq!(back, *ck, "the bytes give the checkpoint back");
    back
}

#[test]
fn a_resumed_run_ends_with_the_bits_of_an_uninterrupted_one_for_every_integrator() {
    for integrator in Integrator::ALL {
        let c = case(integrator);
        let (whole, r) = run(&c, None, None);
        let whole_stats = r.unwrap_or_else(|e| panic!("{integrator}: {e}"));
        let ck = checkpoint_of(&c);
        // The case exercises what is kept: contacts at the stop, and the solver's own state.
        let contacts = ck.state.contact.iter().filter(|c| c.is_some()).count();
        assert!(contacts > 0, "{integrator}: no contact at step {}", c.at);
        match &ck.solver.kept {
            Kept::Nothing => assert!(integrator.is_explicit()),
            Kept::Implicit(k) => {
                assert!(k.normal_force.iter().any(|&f| f > 0.0), "{integrator}");
                assert!(k.stuck.iter().any(|&s| s), "{integrator}: none stuck");
            }
            Kept::Projective(k) => {
                assert!(
                    k.stiff.iter().any(|&s| s > 1.0),
                    "{integrator}: no stiffening"
                );
                assert!(
                    !k.update.index.is_empty(),
                    "{integrator}: no low-rank update"
                );
            }
        }
        let (resumed, r) = run(&c, None, Some(&ck));
        let stats = r.unwrap_or_else(|e| panic!("{integrator}: {e}"));
        assert!(
            bits(&resumed.state.x, &resumed.state.v) == bits(&whole.state.x, &whole.state.v),
            "{integrator}: the resumed run ends elsewhere"
        );
        assert_eq!(resumed.state.contact, whole.state.contact, "{integrator}");
        assert_eq!(resumed.grid_built_at, whole.grid_built_at, "{integrator}");
        assert_eq!(stats.steps, whole_stats.steps);
        let counters = |s: &RunStats| {
            let t = &s.solver;
            let n = [t.factorisations, t.low_rank_columns, t.cg_iterations];
            (n, t.pd_iterations, s.at_rest, s.time)
        };
        assert_eq!(counters(&stats), counters(&whole_stats), "{integrator}");
    }
}

#[test]
fn a_checkpoint_of_another_integrator_or_world_is_refused() {
    let c = case(Integrator::ProjectiveDynamics);
    let ck = checkpoint_of(&c);
    let other = Case {
        settings: SolverSettings::new(Integrator::ImplicitEuler),
        ..case(Integrator::ProjectiveDynamics)
    };
    let (_, r) = run(&other, None, Some(&ck));
    let Err(SimError::Checkpoint(CheckpointError::Mismatch { what, .. })) = r else {
        panic!("{r:?}");
    };
    assert_eq!(what, "the solver state");
    let coarse = Case {
        world: soft_falling,
        ..case(Integrator::ProjectiveDynamics)
    };
    let (_, r) = run(&coarse, None, Some(&ck));
    let Err(SimError::Checkpoint(CheckpointError::Mismatch { what, .. })) = r else {
        panic!("{r:?}");
    };
    assert_eq!(what, "the number of particles");
}

#[test]
fn damaged_foreign_and_mismatched_checkpoints_are_refused_by_name() {
    let c = case(Integrator::Leapfrog);
    let mut ck = checkpoint_of(&c);
    ck.fingerprint = Fingerprint {
        scene: [7; 32],
        options: "glb=false".into(),
    };
    let path = Path::new("OUT/scene.checkpoint");
    let bytes = ck.encode();
    // One bit flipped anywhere in the body: the checksum says so.
    let mut flipped = bytes.clone();
    flipped[bytes.len() / 2] ^= 4;
    let e = Checkpoint::decode(&flipped, path).unwrap_err();
    assert!(matches!(e, CheckpointError::Damaged { .. }), "{e}");
    assert!(
        e.to_string().contains("OUT/scene.checkpoint is damaged"),
        "{e}"
    );
    // Cut short.
    let e = Checkpoint::decode(&bytes[..bytes.len() - 1], path).unwrap_err();
    assert!(matches!(e, CheckpointError::Damaged { .. }), "{e}");
    // Not a checkpoint, or another version.
    let e = Checkpoint::decode(b"# a scene file\n[solver]\n", path).unwrap_err();
    assert!(matches!(e, CheckpointError::NotACheckpoint { .. }), "{e}");
    let mut v2 = bytes.clone();
    v2[16] = 2;
    let e = Checkpoint::decode(&v2, path).unwrap_err();
    assert!(
        matches!(e, CheckpointError::Version { found: 2, .. }),
        "{e}"
    );
    // Another scene, other options.
    let now = |scene: u8, options: &str| Fingerprint {
        scene: [scene; 32],
        options: options.into(),
    };
    assert!(ck.check(&now(7, "glb=false"), path).is_ok());
    let e = ck.check(&now(8, "glb=false"), path).unwrap_err();
    assert!(e.to_string().contains("another scene"), "{e}");
    let e = ck.check(&now(7, "glb=true"), path).unwrap_err();
    assert!(
        e.to_string().contains("glb=false; this run: glb=true"),
        "{e}"
    );
}
