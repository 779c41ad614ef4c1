//! The drape simulator: the validation scenes of `fixtures/scenes/` with asserted outcomes,
//! stability at the extremes, determinism, outputs, and bad scenes.

mod common;

use drapekit::cloth::fabric::Fabric;
use drapekit::cloth::integrate::SolverSettings;
use drapekit::cloth::Integrator;
use drapekit::math::{Point3, Vec3};
use drapekit::scene::{self, Scene};
use drapekit::sim::reference::elastic_catenary;
use drapekit::sim::{self, Instability, SimError, World};
use drapekit::sim::{Cells, Stop};
use serde_json::Value;

/// Reads a fixture scene and lets the test change it.
fn scene_with(name: &str, edit: impl FnOnce(&mut Scene)) -> Scene {
    let mut s = scene::read(&common::fixture(&format!("scenes/{name}"))).expect("a valid scene");
    edit(&mut s);
    s
}

/// Runs a scene to its end: the world and the run's figures.
fn simulate(sc: &Scene) -> (World, sim::RunStats) {
    let mut w = sim::load(sc).expect("the scene loads");
    let stats = sim::run_quiet(&mut w, &sc.solver, sc.stop).expect("a stable run");
    (w, stats)
}

/// The particle that is nearest to `p`.
fn gravity_forces(m: &drapekit::cloth::ClothModel) -> Vec<drapekit::math::Vec3> {
    m.mass.iter().map(|&w| m.gravity * w).collect()
}

fn nearest(x: &[Point3], p: &Point3) -> usize {
    (0..x.len())
        .min_by(|&a, &b| (x[a] - p).norm().total_cmp(&(x[b] - p).norm()))
        .unwrap()
}

/// Runs `drapekit drape SCENE -o OUT --report DIR/r.json`, which must succeed: its standard
/// output and the report.
fn drape_with_report(
    scene: &std::path::Path,
    out: &std::path::Path,
    dir: &std::path::Path,
) -> (String, Value) {
    let report = dir.join("r.json");
    let o = drape_cli(scene, out, &["--report", report.to_str().unwrap()]);
    let (stdout, err) = common::text(&o);
    assert!(o.status.success(), "{err}");
    let r = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    (stdout, r)
}

/// Runs `drapekit drape SCENE -o OUT` with `extra` arguments.
fn drape_cli(
    scene: &std::path::Path,
    out: &std::path::Path,
    extra: &[&str],
) -> std::process::Output {
    let mut args = vec![
        "drape",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    common::run(&args)
}

/// The ribbon scene, edited (`from`, `to` replacements, then `tail` appended), written to `dir`.
fn ribbon_variant(dir: &std::path::Path, edits: &[(&str, &str)], tail: &str) -> std::path::PathBuf {
    let mut text = std::fs::read_to_string(common::fixture("scenes/hanging_ribbon.toml")).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{from}");
        text = text.replace(from, to);
    }
    let path = dir.join("ribbon.toml");
    std::fs::write(&path, text + tail).unwrap();
    path
}

/// The ribbon's stopping rule.
const RIBBON_STOP: &str = "until_rest = 1e-9            # J\nmax_steps = 400000";

/// Copies the validation sphere into `dir`, for scenes written there.
fn beside_sphere(dir: &std::path::Path) {
    std::fs::copy(
        common::fixture("scenes/sphere_r0.3.obj"),
        dir.join("sphere_r0.3.obj"),
    )
    .unwrap();
}

/// A scratch directory, removed when dropped.
fn scratch(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("drapekit-drape-{name}-"))
        .tempdir()
        .unwrap()
}

// ---------------------------------------------------------------------------------------------
// A square dropped on a sphere.

#[test]
fn square_dropped_on_a_sphere_rests_on_it_outside_radius_plus_thickness() {
    let sc = scene_with("sphere_drop.toml", |_| {});
    let (w, stats) = simulate(&sc);
    assert!(
        stats.at_rest,
        "the cloth comes to rest ({} steps)",
        stats.steps
    );
    let c = &w.colliders[0];
    // The sphere is an icosphere of radius 0.3: its faces are at least r_in from the centre.
    let r_in = (0..c.mesh.faces.len())
        .map(|f| {
            let [a, b, d] = c.mesh.corners(f);
            let n = (b - a).cross(&(d - a)).normalize();
            n.dot(&a.coords).abs()
        })
        .fold(f64::INFINITY, f64::min);
    assert!(r_in > 0.298 && r_in < 0.3, "{r_in}");
    let th = sc.pieces[0].fabric.thickness;
    let closest = w
        .state
        .x
        .iter()
        .map(|p| p.coords.norm())
        .fold(f64::INFINITY, f64::min);
    assert!(
        closest >= r_in + th - 1e-6,
        "a particle is {closest} from the centre, within r_in + thickness = {}",
        r_in + th
    );
    assert_eq!(sim::particles_inside(&w), vec![Some(0)]);
    let clearance = sim::min_clearance(&w)[0];
    assert!((clearance - th).abs() < 1e-6, "{clearance}");
    // It lies on the sphere: the centre of the square on its top, many particles in contact.
    let top = nearest(&w.state.x, &Point3::new(0.0, 0.0, 1.0));
    assert!((w.state.x[top].coords.norm() - (0.3 + th)).abs() < 2e-3);
    let contacts = w.state.contact.iter().filter(|c| c.is_some()).count();
    assert!(contacts > 200, "{contacts}");
    let (max, mean) = sim::strain(&w.model, &w.state.x);
    assert!(max < 0.02 && mean.abs() < 0.005, "strain {max} {mean}");
}

#[test]
fn real_cotton_drapes_on_the_sphere_with_the_default_solver() {
    // The README's first command: real cotton, no integrator or step in the scene.
    let sc = scene_with("cotton_on_sphere.toml", |_| {});
    assert_eq!(sc.solver, SolverSettings::default());
    assert_eq!(sc.pieces[0].fabric, Fabric::cotton());
    let (w, stats) = simulate(&sc);
    assert!(stats.at_rest, "at rest ({} steps)", stats.steps);
    assert_eq!(sim::particles_inside(&w), vec![Some(0)]);
    let th = sc.pieces[0].fabric.thickness;
    let clearance = sim::min_clearance(&w)[0];
    assert!(clearance > th - 1e-6, "{clearance}");
    // The centre of the square (the particle that started above the sphere's top) rests on
    // the top; the highest particle may be a fold standing beside it.
    let start = sim::load(&sc).expect("the scene loads").state.x;
    let centre = nearest(&start, &Point3::new(0.0, 0.0, 0.33));
    assert!((w.state.x[centre].coords.norm() - (0.3 + th)).abs() < 2e-3);
    assert!(w.state.contact.iter().any(|c| c.is_some()));
    // Cotton hardly stretches under its own weight: the thread springs stay within 1%.
    let (max, mean) = sim::strain(&w.model, &w.state.x);
    assert!(max < 0.01 && mean.abs() < 1e-3, "strain {max} {mean}");
}

// ---------------------------------------------------------------------------------------------
// A ribbon hanging from its two ends: an elastic catenary.

/// Hangs the ribbon at `spacing` and `dt`: the midspan sag of its centre line (m), the
/// horizontal and vertical reactions at one end (N), and the weight of its free particles (N).
fn hang_ribbon(spacing: f64, dt: f64) -> (f64, f64, f64, f64, sim::RunStats) {
    let sc = scene_with("hanging_ribbon.toml", |s| {
        s.pieces[0].spacing = spacing;
        s.solver.dt = dt;
    });
    let w0 = sim::load(&sc).unwrap();
    let mid = nearest(&w0.state.x, &Point3::new(0.0, 0.0, 1.0));
    let z0 = w0.state.x[mid].z;
    let (w, stats) = simulate(&sc);
    let still = vec![Vec3::zeros(); w.model.len()];
    let (mut rx, mut rz, mut weight) = (0.0, 0.0, 0.0);
    for i in 0..w.model.len() {
        if w.model.pinned(i) {
            // The spring force on a pinned particle is what its clamp must hold.
            let f = drapekit::cloth::forces::force_on(
                &w.model,
                &w.state.x,
                &still,
                &gravity_forces(&w.model),
                i,
            ) - w.model.gravity * w.model.mass[i];
            if w.state.x[i].x < 0.0 {
                rx += f.x;
                rz += f.z;
            }
        } else {
            weight += w.model.mass[i] * 9.81;
        }
    }
    (z0 - w.state.x[mid].z, rx.abs(), rz.abs(), weight, stats)
}

#[test]
fn ribbon_hanging_from_its_ends_sags_as_an_elastic_catenary() {
    let f = scene_with("hanging_ribbon.toml", |_| {}).pieces[0]
        .fabric
        .clone();
    let (e, g) = (f.stretch[0], f.shear);
    let ea = e * (e + 2.0 * g) / (e + g); // the spring grid's tensile modulus, N/m
    let (h, sag) = elastic_catenary(1.0, 1.0, f.density * 9.81, ea);
    assert!((sag - 0.1042).abs() < 5e-4, "{sag}");
    let mut errors = Vec::new();
    for (spacing, dt, tol) in [(0.02, 4e-4, 0.02), (0.01, 2e-4, 0.005)] {
        let (s, rx, rz, weight, stats) = hang_ribbon(spacing, dt);
        assert!(stats.at_rest, "spacing {spacing}: at rest");
        let err = (s - sag).abs() / sag;
        assert!(
            err < tol,
            "spacing {spacing}: sag {s} against {sag} ({err:.4})"
        );
        // Statics: each clamp holds half the weight, and the catenary's horizontal tension
        // across the ribbon's 4 cm.
        assert!((2.0 * rz / weight - 1.0).abs() < 0.01, "{rz} {weight}");
        assert!(
            (rx / (h * 0.04) - 1.0).abs() < 0.03,
            "{rx} against {}",
            h * 0.04
        );
        errors.push(err);
    }
    assert!(
        errors[1] < errors[0],
        "the error falls as the spacing halves: {errors:?}"
    );
    // The static answer does not depend on the step.
    let (fine, ..) = hang_ribbon(0.02, 1e-4);
    let (coarse, ..) = hang_ribbon(0.02, 4e-4);
    assert!((fine - coarse).abs() < 2e-4, "{fine} {coarse}");
}

/// The energy of a cloth model at positions `x` (springs `k (L - l)^2 / 2`, bending elements
/// `c |sum w x|^2 / 2`, gravity), its gradient (zero at pinned particles), and products with
/// its Hessian, written here from the model's springs, elements and masses: the static problem
/// of `static_equilibrium`, independent of the library's forces and time stepping.
struct Statics<'a> {
    m: &'a drapekit::cloth::ClothModel,
    free: Vec<bool>,
}

impl Statics<'_> {
    fn bend(&self, e: usize) -> (&[u32], &[f64]) {
        let (a, b) = (
            self.m.bend_start[e] as usize,
            self.m.bend_start[e + 1] as usize,
        );
        (&self.m.bend_nodes[a..b], &self.m.bend_weights[a..b])
    }

    fn bend_sum(&self, e: usize, x: &[Vec3]) -> Vec3 {
        let (nodes, w) = self.bend(e);
        nodes.iter().zip(w).map(|(&v, &w)| x[v as usize] * w).sum()
    }

    fn energy(&self, x: &[Point3]) -> f64 {
        let m = self.m;
        let c: Vec<Vec3> = x.iter().map(|p| p.coords).collect();
        let springs: f64 = m
            .springs
            .iter()
            .map(|s| 0.5 * s.k * ((x[s.b as usize] - x[s.a as usize]).norm() - s.rest).powi(2))
            .sum();
        let bends: f64 = (0..m.bends())
            .map(|e| 0.5 * m.bend_c[e] * self.bend_sum(e, &c).norm_squared())
            .sum();
        let gravity: f64 = (0..m.len()).map(|i| m.mass[i] * m.gravity.dot(&c[i])).sum();
        springs + bends - gravity
    }

    fn gradient(&self, x: &[Point3]) -> Vec<Vec3> {
        let m = self.m;
        let mut g: Vec<Vec3> = (0..m.len()).map(|i| -m.gravity * m.mass[i]).collect();
        for s in &m.springs {
            let d = x[s.b as usize] - x[s.a as usize];
            let f = d * (s.k * (1.0 - s.rest / d.norm()));
            g[s.a as usize] -= f;
            g[s.b as usize] += f;
        }
        let c: Vec<Vec3> = x.iter().map(|p| p.coords).collect();
        for e in 0..m.bends() {
            let b = self.bend_sum(e, &c);
            let (nodes, w) = self.bend(e);
            for (&v, &w) in nodes.iter().zip(w) {
                g[v as usize] += b * (m.bend_c[e] * w);
            }
        }
        self.mask(g)
    }

    fn mask(&self, mut v: Vec<Vec3>) -> Vec<Vec3> {
        for (v, &f) in v.iter_mut().zip(&self.free) {
            if !f {
                *v = Vec3::zeros();
            }
        }
        v
    }

    /// Each spring's Hessian block `k [u u^T + (1 - l / L) (I - u u^T)]`; with `psd`, a
    /// compressed spring's negative transverse part dropped.
    fn spring_blocks(&self, x: &[Point3], psd: bool) -> Vec<nalgebra::Matrix3<f64>> {
        self.m
            .springs
            .iter()
            .map(|s| {
                let d = x[s.b as usize] - x[s.a as usize];
                let (len, u) = (d.norm(), d.normalize());
                let uu = u * u.transpose();
                let t = 1.0 - s.rest / len;
                (uu + (nalgebra::Matrix3::identity() - uu) * if psd { t.max(0.0) } else { t }) * s.k
            })
            .collect()
    }

    fn hessian_times(&self, blocks: &[nalgebra::Matrix3<f64>], p: &[Vec3]) -> Vec<Vec3> {
        let m = self.m;
        let mut out = vec![Vec3::zeros(); m.len()];
        for (s, h) in m.springs.iter().zip(blocks) {
            let t = h * (p[s.a as usize] - p[s.b as usize]);
            out[s.a as usize] += t;
            out[s.b as usize] -= t;
        }
        for e in 0..m.bends() {
            let b = self.bend_sum(e, p);
            let (nodes, w) = self.bend(e);
            for (&v, &w) in nodes.iter().zip(w) {
                out[v as usize] += b * (m.bend_c[e] * w);
            }
        }
        self.mask(out)
    }

    /// The inverses of the 3x3 diagonal blocks of the Hessian with compressed springs'
    /// transverse parts dropped, plus a tenth of their mean eigenvalue in every direction (a
    /// slack spring has no stiffness across it): the preconditioner, and the trust region's
    /// norm.
    fn preconditioner(&self, x: &[Point3]) -> Vec<nalgebra::Matrix3<f64>> {
        let m = self.m;
        let mut d = vec![nalgebra::Matrix3::<f64>::zeros(); m.len()];
        for (s, h) in m.springs.iter().zip(self.spring_blocks(x, true)) {
            d[s.a as usize] += h;
            d[s.b as usize] += h;
        }
        for e in 0..m.bends() {
            let (nodes, w) = self.bend(e);
            for (&v, &w) in nodes.iter().zip(w) {
                d[v as usize] += nalgebra::Matrix3::identity() * (m.bend_c[e] * w * w);
            }
        }
        d.iter()
            .zip(&self.free)
            .map(|(d, &f)| match f {
                true => (d + nalgebra::Matrix3::identity() * (0.1 * d.trace() / 3.0))
                    .try_inverse()
                    .expect("a free particle held by springs"),
                false => nalgebra::Matrix3::zeros(),
            })
            .collect()
    }
}

fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p.dot(q)).sum()
}

/// The static equilibrium of a cloth model from positions `x0` (pinned particles held there):
/// a local minimum of its energy ([`Statics`]), by a trust-region Newton method (Steihaug's
/// conjugate gradients on the exact Hessian, preconditioned by its diagonal blocks; a
/// direction of negative curvature, as along a compressed edge that buckles, is followed to
/// the region's edge). It stops when no free particle has a residual force above `tol` (N).
fn static_equilibrium(m: &drapekit::cloth::ClothModel, x0: &[Point3], tol: f64) -> Vec<Point3> {
    let st = Statics {
        m,
        free: (0..m.len()).map(|i| !m.pinned(i)).collect(),
    };
    let n = m.len();
    let mut x = x0.to_vec();
    let mut radius = 1e-2; // in the preconditioner's norm
    for _ in 0..500 {
        let g = st.gradient(&x);
        if g.iter().all(|v| v.norm() < tol) {
            return x;
        }
        let h = st.spring_blocks(&x, false);
        let inv = st.preconditioner(&x);
        let m_norm = |v: &[Vec3]| -> f64 {
            (0..n)
                .map(|i| match inv[i].try_inverse() {
                    Some(d) => v[i].dot(&(d * v[i])),
                    None => 0.0,
                })
                .sum::<f64>()
                .sqrt()
        };
        // The step to the region's edge from z along p.
        let to_edge = |z: &[Vec3], p: &[Vec3]| -> Vec<Vec3> {
            let (mut lo, mut hi) = (0.0, 1.0);
            while m_norm(&(0..n).map(|i| z[i] + p[i] * hi).collect::<Vec<_>>()) < radius {
                hi *= 2.0;
            }
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let zm: Vec<Vec3> = (0..n).map(|i| z[i] + p[i] * mid).collect();
                if m_norm(&zm) < radius {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            (0..n).map(|i| z[i] + p[i] * lo).collect()
        };
        // Steihaug-Toint CG on H d = -g within the region.
        let mut z = vec![Vec3::zeros(); n];
        let mut r = g.clone();
        let mut y: Vec<Vec3> = (0..n).map(|i| inv[i] * r[i]).collect();
        let mut p: Vec<Vec3> = y.iter().map(|v| -v).collect();
        let r0 = dot(&r, &r).sqrt();
        let d = loop {
            let hp = st.hessian_times(&h, &p);
            let curvature = dot(&p, &hp);
            if curvature <= 0.0 {
                break to_edge(&z, &p);
            }
            let alpha = dot(&r, &y) / curvature;
            let next: Vec<Vec3> = (0..n).map(|i| z[i] + p[i] * alpha).collect();
            if m_norm(&next) >= radius {
                break to_edge(&z, &p);
            }
            let ry = dot(&r, &y);
            for i in 0..n {
                r[i] += hp[i] * alpha;
            }
            z = next;
            if dot(&r, &r).sqrt() < 1e-8 * r0 {
                break z;
            }
            y = (0..n).map(|i| inv[i] * r[i]).collect();
            let beta = dot(&r, &y) / ry;
            for i in 0..n {
                p[i] = -y[i] + p[i] * beta;
            }
        };
        let predicted = -(dot(&g, &d) + 0.5 * dot(&d, &st.hessian_times(&h, &d)));
        let trial: Vec<Point3> = (0..n).map(|i| x[i] + d[i]).collect();
        let (e, e_trial) = (st.energy(&x), st.energy(&trial));
        // Below rounding of the energy (1e-12 of it) the quadratic model is trusted.
        let rho = if predicted < 1e-12 * e.abs() {
            1.0
        } else {
            (e - e_trial) / predicted
        };
        if rho < 0.25 {
            radius *= 0.25;
        } else if rho > 0.75 && m_norm(&d) > 0.99 * radius {
            radius *= 2.0;
        }
        if rho > 1e-4 {
            x = trial;
        }
    }
    panic!("the static solve did not converge to {tol} N");
}

#[test]
fn square_hanging_from_two_corner_pegs_rests_at_its_static_equilibrium() {
    let sc = scene_with("hanging_corners.toml", |_| {});
    let w0 = sim::load(&sc).unwrap();
    let bottom = nearest(&w0.state.x, &Point3::new(0.0, 0.0, 0.76));
    let com = |x: &[Point3]| {
        x.iter()
            .zip(&w0.model.mass)
            .map(|(p, m)| p.z * m)
            .sum::<f64>()
            / w0.model.mass.iter().sum::<f64>()
    };
    let (w, stats) = simulate(&sc);
    assert!(stats.at_rest);
    // The reference: the same spring network's static equilibrium, solved directly (to a
    // millionth of a particle's weight).
    let weight = w0
        .model
        .mass
        .iter()
        .fold(f64::INFINITY, |a, &m| a.min(m * 9.81));
    let x = static_equilibrium(&w0.model, &w0.state.x, 1e-6 * weight);
    let drop = com(&w0.state.x) - com(&w.state.x);
    let sag = w0.state.x[bottom].z - w.state.x[bottom].z;
    let (drop_ref, sag_ref) = (
        com(&w0.state.x) - com(&x),
        w0.state.x[bottom].z - x[bottom].z,
    );
    // The run stops at rest: kinetic energy below until_rest (J), so speeds below
    // sqrt(2 until_rest / mass); at the slowest swing, a pendulum of the cloth's 48 cm
    // (sqrt(g / 0.48) rad/s), that is an amplitude of at most `swing`.
    let Stop::UntilRest { energy, .. } = sc.stop else {
        panic!("the scene stops at rest")
    };
    let mass: f64 = w0.model.mass.iter().sum();
    let swing = (2.0 * energy / mass).sqrt() / (9.81f64 / 0.48).sqrt();
    assert!(drop_ref > 0.005 && sag_ref > 0.005, "{drop_ref} {sag_ref}");
    assert!(
        (drop - drop_ref).abs() < swing,
        "{drop} against {drop_ref} (swing {swing})"
    );
    assert!(
        (sag - sag_ref).abs() < swing,
        "{sag} against {sag_ref} (swing {swing})"
    );
    // Statics: the pegs hold the weight of everything else.
    let still = vec![Vec3::zeros(); w.model.len()];
    let (mut held, mut weight) = (0.0, 0.0);
    for i in 0..w.model.len() {
        if w.model.pinned(i) {
            let f = drapekit::cloth::forces::force_on(
                &w.model,
                &w.state.x,
                &still,
                &gravity_forces(&w.model),
                i,
            ) - w.model.gravity * w.model.mass[i];
            held -= f.z;
        } else {
            weight += w.model.mass[i] * 9.81;
        }
    }
    assert!((held / weight - 1.0).abs() < 1e-3, "{held} {weight}");
    // The pegs have not moved.
    for i in (0..w.model.len()).filter(|&i| w.model.pinned(i)) {
        assert_eq!(w.state.x[i], w0.state.x[i]);
    }
}

// ---------------------------------------------------------------------------------------------
// The Cusick drape test.

fn cusick(preset: &str) -> (f64, World) {
    let sc = scene_with("cusick.toml", |s| {
        s.pieces[0].fabric = Fabric::preset(preset).unwrap();
    });
    let (w, stats) = simulate(&sc);
    assert!(stats.at_rest, "{preset} comes to rest");
    (sim::drape_coefficient(&w, 0, 0.09), w)
}

#[test]
fn cusick_drape_coefficient_rises_with_bending_rigidity() {
    // The real presets, unsoftened: measured woven fabrics lie between about 0.3 and 0.9.
    let sc = scene_with("cusick.toml", |_| {});
    assert_eq!(sc.pieces[0].fabric, Fabric::cotton());
    let mut last = 0.0;
    for preset in ["silk", "cotton", "denim"] {
        let (dc, w) = cusick(preset);
        assert!(dc > 0.3 && dc < 0.95, "{preset}: {dc}");
        assert!(dc > last, "{preset}: {dc} after {last}");
        assert_eq!(sim::particles_inside(&w), vec![Some(0)]);
        // A real fabric hardly stretches under its weight, rim included.
        let (max, _) = sim::strain(&w.model, &w.state.x);
        assert!(max < 0.01, "{preset}: strain {max}");
        // The specimen hangs over the rim: its edge is well below the disc's top.
        let low = w.state.x.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
        assert!(low < -0.02, "{preset}: lowest point {low}");
        last = dc;
    }
}

#[test]
fn drape_coefficient_of_flat_and_hanging_specimens() {
    // Flat: the shadow is the specimen (coefficient 1); hanging straight down from the disc's
    // rim (a cylinder of the disc's radius), the shadow is the disc (coefficient 0).
    let sc = scene_with("cusick.toml", |_| {});
    let mut w = sim::load(&sc).unwrap();
    let dc = sim::drape_coefficient(&w, 0, 0.09);
    assert!((dc - 1.0).abs() < 0.01, "{dc}");
    for p in w.state.x.iter_mut() {
        let r = p.coords.xy().norm();
        if r > 0.09 {
            let s = 0.09 / r;
            *p = Point3::new(p.x * s, p.y * s, -(r - 0.09));
        }
    }
    let dc = sim::drape_coefficient(&w, 0, 0.09);
    assert!(dc.abs() < 0.02, "{dc}");
}

// ---------------------------------------------------------------------------------------------
// Real objects: an open seat and a closed body.

/// The heights, lowest first, where the vertical line through `p` meets `c`'s surface.
fn surfaces_on_vertical(c: &drapekit::collide::Collider, p: &Point3) -> Vec<f64> {
    let mut hits = Vec::new();
    for f in 0..c.mesh.faces.len() {
        let [a, b, d] = c.mesh.corners(f);
        let det = (b.x - a.x) * (d.y - a.y) - (d.x - a.x) * (b.y - a.y);
        if det.abs() < 1e-18 {
            continue;
        }
        let u = ((p.x - a.x) * (d.y - a.y) - (d.x - a.x) * (p.y - a.y)) / det;
        let v = ((b.x - a.x) * (p.y - a.y) - (p.x - a.x) * (b.y - a.y)) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
            hits.push(a.z + u * (b.z - a.z) + v * (d.z - a.z));
        }
    }
    hits.sort_by(f64::total_cmp);
    hits
}

#[test]
fn cloth_dropped_on_the_open_stool_stays_above_its_top_surface() {
    if common::realdata().is_none() {
        return;
    }
    let sc = scene_with("stool.toml", |_| {});
    let (w, stats) = simulate(&sc);
    assert!(stats.at_rest);
    let c = &w.colliders[0];
    assert!(!c.closed, "the stool is an open mesh");
    let th = sc.pieces[0].fabric.thickness;
    // The seat: along the vertical through the stool's middle, its bottom and its top.
    let (lo, hi) = (c.bbox.min, c.bbox.max);
    let middle = Point3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), hi.z + 1.0);
    let [seat_bottom, seat_top] = surfaces_on_vertical(c, &middle)[..] else {
        panic!("the stool's middle is its seat, two surfaces")
    };
    // Along the vertical through a particle, the stool's surfaces come in pairs (top and bottom
    // of the seat, of a leg): a particle that went through one would have an odd number above
    // it. One resting on the stool has none above it and is at least the thickness above the
    // highest. One with surfaces above it is under the seat's rounded rim, where the seat is
    // thinner than in its middle: exactly two surfaces above it (the rim's lower and upper
    // face, not a leg or the flat bottom), both above the seat's bottom, the lower one at
    // least the thickness above the particle.
    let mut over = 0;
    for (i, p) in w.state.x.iter().enumerate() {
        let hits = surfaces_on_vertical(c, p);
        let Some(&top) = hits.last() else { continue };
        let above: Vec<f64> = hits.iter().copied().filter(|&z| z > p.z).collect();
        assert!(
            above.len().is_multiple_of(2),
            "particle {i} at {p:?} is inside the stool: surfaces at {hits:?}"
        );
        if above.is_empty() {
            over += 1;
            assert!(
                p.z >= top + th - 1e-6,
                "particle {i} at {p:?} is nearer the stool's top ({top}) than the thickness"
            );
            continue;
        }
        let rim = above.len() == 2
            && above[0] > seat_bottom + 1e-4
            && above[1] <= seat_top
            && above[0] >= p.z + th - 1e-6;
        assert!(
            rim,
            "particle {i} at {p:?} is under the stool ({above:?} above it) but not under the rim of the seat ({seat_bottom} to {seat_top}) by the thickness"
        );
    }
    // The seat's top (0.39 x 0.43 m) holds about 745 particles of the 1.5 cm grid.
    assert!(over > 500, "{over} particles rest over the stool");
    assert!(sim::min_clearance(&w)[0] >= th - 1e-6);
}

#[test]
fn cape_dropped_over_the_shoulders_stays_outside_the_body() {
    if common::realdata().is_none() {
        return;
    }
    let sc = scene_with("shoulders.toml", |_| {});
    let (w, stats) = simulate(&sc);
    assert!(stats.at_rest);
    assert!(w.colliders[0].closed, "the body is closed");
    assert_eq!(sim::particles_inside(&w), vec![Some(0)]);
    let th = sc.pieces[0].fabric.thickness;
    let clearance = sim::min_clearance(&w)[0];
    assert!(clearance >= th - 1e-6, "{clearance}");
    // It rests on the shoulders: nothing fell off, many particles touch the body.
    let low = w.state.x.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    assert!(low > 0.2, "lowest particle at {low}");
    assert!(w.state.contact.iter().filter(|c| c.is_some()).count() > 100);
}

// ---------------------------------------------------------------------------------------------
// Stability: the boundary against the estimate, and the extremes of stiffness and step.

/// A 20 cm square of `fabric`, spacing 2 cm, pinned at two corners, hanging free.
fn probe_world(fabric: &Fabric, integrator: Integrator) -> World {
    probe_world_pinned(fabric, integrator, true)
}

/// The probe, pinned at its top corners or (`pinned` false) falling free.
fn probe_world_pinned(fabric: &Fabric, integrator: Integrator, pinned: bool) -> World {
    use drapekit::cloth::model::ClothModel;
    use drapekit::cloth::pattern::{self, Pins};
    use drapekit::math::Point2;
    let s = 0.1;
    let outline = [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| Point2::new(x, y));
    let pins = if pinned {
        Pins::at(&[Point2::new(-s, s), Point2::new(s, s)])
    } else {
        Pins::default()
    };
    let p = pattern::build(&outline, 0.02, fabric, &pins).unwrap();
    let placed: Vec<Point3> = p.flat.iter().map(|q| Point3::new(q.x, 0.0, q.y)).collect();
    let (m, x) = ClothModel::assemble(
        &[("probe".into(), p, fabric.clone(), placed)],
        Vec3::new(0.0, 0.0, -9.81),
    );
    World::new(m, x, Vec::new(), integrator)
}

fn probe_run(
    fabric: &Fabric,
    integrator: Integrator,
    dt: f64,
    steps: u64,
) -> Result<World, SimError> {
    let mut w = probe_world(fabric, integrator);
    sim::run_quiet(
        &mut w,
        &SolverSettings::new(integrator).with_dt(dt),
        Stop::Steps(steps),
    )?;
    Ok(w)
}

fn stiffness(k: f64, damping: f64) -> Fabric {
    Fabric {
        stretch: [k, k],
        shear: 0.1 * k,
        bend: [0.0, 0.0],
        damping,
        ..Fabric::cotton()
    }
}

/// The power iteration's estimate of the largest leapfrog step (from above: the true one is
/// smaller).
fn power_step(w: &World) -> f64 {
    2.0 / drapekit::cloth::stability::max_frequency(&w.model, &w.state.x)
}

/// The mechanical energy of `x` and `v`, J: kinetic, springs, and gravity measured from `x0`,
/// summed here from the model's springs and masses (not by the library's energy functions;
/// the probe has no bending elements).
fn energy_here(m: &drapekit::cloth::ClothModel, x: &[Point3], v: &[Vec3], x0: &[Point3]) -> f64 {
    assert_eq!(m.bends(), 0, "the probe has no bending elements");
    let kinetic: f64 = (0..m.len())
        .map(|i| 0.5 * m.mass[i] * v[i].norm_squared())
        .sum();
    let springs: f64 = m
        .springs
        .iter()
        .map(|s| {
            let e = (x[s.b as usize] - x[s.a as usize]).norm() - s.rest;
            0.5 * s.k * e * e
        })
        .sum();
    let gravity: f64 = (0..m.len())
        .map(|i| -m.mass[i] * m.gravity.dot(&(x[i] - x0[i])))
        .sum();
    kinetic + springs + gravity
}

/// Runs the probe unstably and checks when the watch stops it, against the energy recorded at
/// every step and the budget worked out here (the energy scale of `sim::watch`: the work
/// gravity does over the box's diagonal plus 1 m, plus the energy at the start).
fn caught_at_the_first_check_over_the_budget(f: &Fabric, dt: f64, steps: u64) -> SimError {
    let mut w = probe_world(f, Integrator::Leapfrog);
    let x0 = w.state.x.clone();
    let e0 = energy_here(&w.model, &x0, &w.state.v, &x0);
    let diagonal = drapekit::math::Aabb::of_points(&x0).unwrap().diagonal();
    let mass: f64 = w.model.mass.iter().sum();
    let budget = mass * 9.81 * (diagonal + 1.0) + e0;
    // The energy after every step that passed its check (frames are written after it).
    let mut energy = Vec::new();
    let r = sim::run(
        &mut w,
        &SolverSettings::new(Integrator::Leapfrog).with_dt(dt),
        Stop::Steps(steps),
        Some(1),
        &mut |_, w| {
            energy.push(energy_here(&w.model, &w.state.x, &w.state.v, &x0));
            Ok(false)
        },
        &|_| {},
        Default::default(),
    );
    let e = r.expect_err("unstable");
    let SimError::Unstable { step, reason, .. } = &e else {
        panic!("{e}")
    };
    // The run stopped at the step it names, with the state of that step.
    assert_eq!(energy.len() as u64, step - 1, "{e}");
    energy.push(energy_here(&w.model, &w.state.x, &w.state.v, &x0));
    let first = energy
        .iter()
        .position(|&en| en.is_nan() || en - e0 > budget)
        .map(|i| i as u64 + 1)
        .unwrap_or_else(|| panic!("stopped at step {step} with the energy within its budget"));
    // Stopped at the first check (every check_every steps) at or after the first step over
    // the budget: not before (no false alarm), not later (no run on past it).
    let every = sim::check_every(dt);
    assert_eq!(*step, first.div_ceil(every) * every, "{e}");
    if let Instability::EnergyRose { rise, budget: b } = reason {
        assert!(
            (rise / (energy[*step as usize - 1] - e0) - 1.0).abs() < 1e-9,
            "{e}"
        );
        // The watch adds 1e-9 J to its budget (so that a world with no energy has one).
        assert!((b - budget).abs() < 2e-9, "{b} against {budget}");
    }
    e
}

#[test]
fn leapfrog_is_stable_below_the_estimate_and_caught_above_it() {
    for k in [1.0, 1e2, 1e4, 1e6] {
        let f = stiffness(k, 0.5);
        let world = probe_world(&f, Integrator::Leapfrog);
        let est = world.stable_step;
        let above = power_step(&world);
        // The estimate is conservative (Gershgorin), within a factor 2 of the power iteration's.
        assert!(
            est.is_finite() && est > 0.0 && est <= above && est > 0.5 * above,
            "{est} {above}"
        );
        let steps = 2000;
        let w = probe_run(&f, Integrator::Leapfrog, 0.99 * est, steps)
            .unwrap_or_else(|e| panic!("k = {k}: 0.99 x the estimate must be stable: {e}"));
        assert!(w.state.x.iter().all(|p| p.iter().all(|c| c.is_finite())));
        match caught_at_the_first_check_over_the_budget(&f, 1.25 * above, steps) {
            SimError::Unstable { estimate, dt, .. } => {
                assert_eq!(estimate, est);
                assert_eq!(dt, 1.25 * above);
            }
            e => panic!("{e}"),
        }
    }
}

#[test]
fn extremes_of_stiffness_and_step_are_either_stable_or_caught_as_the_estimate_says() {
    for k in [1.0, 1e6] {
        for dt in [1e-6, 1.0 / 30.0] {
            let f = stiffness(k, 0.5);
            let est = probe_world(&f, Integrator::Leapfrog).stable_step;
            let steps = if dt < 1e-5 { 3000 } else { 300 };
            let r = probe_run(&f, Integrator::Leapfrog, dt, steps);
            if dt < 0.8 * est {
                let w = r.unwrap_or_else(|e| panic!("k {k} dt {dt}: {e}"));
                assert!(w.state.x.iter().all(|p| p.iter().all(|c| c.is_finite())));
            } else {
                let e = r
                    .err()
                    .unwrap_or_else(|| panic!("k {k} dt {dt} est {est}: must be caught"));
                let msg = e.to_string();
                assert!(msg.contains("largest stable step"), "{msg}");
                assert!(msg.contains("use dt <="), "{msg}");
            }
        }
    }
    // The corner cases the issue names, by the estimate: soft and slow is stable, stiff and slow
    // is not; stiff and fast is stable.
    let soft = probe_world(&stiffness(1.0, 0.5), Integrator::Leapfrog).stable_step;
    let stiff = probe_world(&stiffness(1e6, 0.5), Integrator::Leapfrog).stable_step;
    assert!(soft > 1e-3 && soft < 1.0 / 30.0, "{soft}");
    assert!(stiff > 1e-6 && stiff < 1e-4, "{stiff}");
}

#[test]
fn a_fabric_too_stiff_for_double_precision_is_refused_at_its_first_step_not_a_panic() {
    // 1e30 N/m at 10 ms: k dt^2 / m about 1e31, where the implicit integrators' matrices (mass
    // plus dt^2 times the springs) are singular in rounding. Each run is refused before its
    // first step with the ratio, the piece and a step that would do, the state untouched.
    let f = stiffness(1e30, 0.5);
    for integrator in [Integrator::ImplicitEuler, Integrator::ProjectiveDynamics] {
        let mut w = probe_world_pinned(&f, integrator, false);
        let x0 = w.state.x.clone();
        let settings = SolverSettings::new(integrator);
        let r = sim::run_quiet(&mut w, &settings, Stop::Steps(10));
        let Err(SimError::Singular {
            step,
            ref piece,
            ratio,
            hint,
            dt,
            ..
        }) = r
        else {
            panic!("{integrator:?}: {r:?}");
        };
        assert_eq!((step, piece.as_str(), dt), (0, "probe", settings.dt));
        let masses =
            (w.model.mass.iter()).fold((f64::MAX, 0.0f64), |(lo, hi), &m| (lo.min(m), hi.max(m)));
        let k_dt2 = 1e30 * dt * dt;
        assert!(
            ratio >= k_dt2 / masses.1 && ratio <= k_dt2 / masses.0,
            "{ratio:e}"
        );
        assert!((hint * hint / (dt * dt) * ratio / sim::RATIO_HINT - 1.0).abs() < 1e-9);
        let msg = r.unwrap_err().to_string();
        for needle in [
            "not positive definite",
            "before its first step",
            "piece 'probe'",
            "softer fabric",
        ] {
            assert!(msg.contains(needle), "{needle}: {msg}");
        }
        assert_eq!(w.state.x, x0, "{integrator:?}");
    }
    // Just under the bound (k dt^2 / m = RATIO_MAX / 2, a million times cotton's at 1 cm) the
    // same square is solved, falls freely as a whole (its springs unstretched) and stays
    // finite; just over it, refused.
    let dt = SolverSettings::new(Integrator::ImplicitEuler).dt;
    let light = probe_world(&f, Integrator::ImplicitEuler)
        .model
        .mass
        .iter()
        .fold(f64::MAX, |a, &m| a.min(m));
    for (scale, refused) in [(0.5, false), (2.0, true)] {
        let k = scale * sim::RATIO_MAX * light / (dt * dt);
        for integrator in [Integrator::ImplicitEuler, Integrator::ProjectiveDynamics] {
            let mut w = probe_world_pinned(&stiffness(k, 0.5), integrator, false);
            let x0 = w.state.x.clone();
            let r = sim::run_quiet(&mut w, &SolverSettings::new(integrator), Stop::Steps(10));
            assert_eq!(
                matches!(r, Err(SimError::Singular { .. })),
                refused,
                "{integrator:?} {scale}: {r:?}"
            );
            if !refused {
                assert!(r.is_ok(), "{integrator:?}: {r:?}");
                let drop: Vec<f64> = (x0.iter().zip(&w.state.x))
                    .map(|(a, b)| a.z - b.z)
                    .collect();
                let (lo, hi) = drop
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(l, h), &d| (l.min(d), h.max(d)));
                // Rounding alone tells the particles apart: at most the condition number (about
                // 8 times k dt^2 / m) times the machine epsilon, relative.
                let bound = 8.0 * scale * sim::RATIO_MAX * f64::EPSILON;
                assert!(
                    lo > 0.0 && hi - lo < bound * hi,
                    "{integrator:?}: drops {lo} to {hi}"
                );
            }
        }
    }
}

#[test]
fn an_instability_at_an_absurd_step_is_reported_in_a_readable_line() {
    // dt = 1e300 s: the time of step 16 is 1.6e301 s, written in four significant digits (it
    // was every one of its 302 digits).
    let e = SimError::Unstable {
        step: 16,
        time: 1.6e301,
        reason: Instability::NonFinite,
        integrator: Integrator::Leapfrog,
        dt: 1e300,
        estimate: 1e-4,
        advice: "use dt <= 9e-5 s".into(),
    };
    let msg = e.to_string();
    assert!(msg.contains("(t = 1.600e301 s, "), "{msg}");
    assert!(msg.len() < 300, "{msg}");
}

#[test]
fn the_stability_check_is_a_run_option_on_by_default() {
    // The probe at 1.25 x the power iteration's step: unstable.
    let f = stiffness(1e4, 0.5);
    let dt = 1.25 * power_step(&probe_world(&f, Integrator::Leapfrog));
    let steps = 300;
    let run = |stability| {
        let mut w = probe_world(&f, Integrator::Leapfrog);
        let mut called = 0;
        let r = sim::run(
            &mut w,
            &SolverSettings::new(Integrator::Leapfrog).with_dt(dt),
            Stop::Steps(steps),
            Some(1),
            &mut |_, _| {
                called += 1;
                Ok(false)
            },
            &|_| {},
            sim::Control {
                stability,
                ..Default::default()
            },
        );
        (r.map(|_| ()), called, w)
    };
    let (r, called, _) = run(sim::StabilityCheck::default());
    assert!(
        matches!(r, Err(SimError::Unstable { .. })),
        "the default checks: {r:?}"
    );
    assert!(called < steps, "{called}");
    // Switched off, the same run goes to its last step, its numbers running away.
    let (r, called, w) = run(sim::StabilityCheck::Off);
    assert!(r.is_ok(), "{r:?}");
    assert_eq!(called, steps);
    let far = w
        .state
        .x
        .iter()
        .any(|p| p.iter().any(|c| !c.is_finite() || c.abs() > 1e3));
    assert!(far, "unchecked, the unstable probe ran away");
}

#[test]
fn explicit_euler_needs_damping_and_a_step_below_its_estimate() {
    // Soft, heavily damped: explicit Euler is stable below c / (c^2/4 + w^2), and not above.
    let f = stiffness(1.0, 40.0);
    let w = probe_world(&f, Integrator::ExplicitEuler);
    let est = w.stable_step;
    assert!((est - 40.0 / (400.0 + w.max_frequency.powi(2))).abs() < 1e-15);
    assert!(probe_run(&f, Integrator::ExplicitEuler, 0.99 * est, 3000).is_ok());
    let wp = drapekit::cloth::stability::max_frequency(&w.model, &w.state.x);
    assert!(matches!(
        probe_run(
            &f,
            Integrator::ExplicitEuler,
            1.5 * 40.0 / (400.0 + wp * wp),
            3000
        ),
        Err(SimError::Unstable { .. })
    ));
    // Without damping it has no stable step.
    let undamped = probe_world(&stiffness(1.0, 0.0), Integrator::ExplicitEuler);
    assert_eq!(undamped.stable_step, 0.0);
}

#[test]
fn a_fabric_too_stiff_for_the_solver_stops_the_cli_with_advice_and_leaves_nothing_behind() {
    let tmp = scratch("singular");
    let dir = tmp.path();
    let scene = ribbon_variant(
        dir,
        &[
            (
                "integrator = \"leapfrog\"\ndt = 2e-4",
                "integrator = \"implicit-euler\"",
            ),
            (RIBBON_STOP, "steps = 20"),
            ("stretch = 50.0", "stretch = 1e30"),
        ],
        "",
    );
    let out = dir.join("out");
    let o = drape_cli(&scene, &out, &[]);
    let (_, err) = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    for needle in [
        "implicit-euler step's matrix is not positive definite",
        "before its first step",
        "piece 'ribbon'",
        "use a smaller dt",
    ] {
        assert!(err.contains(needle), "{needle}: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        !out.exists(),
        "no output after a failed run: {:?}",
        common::listing(dir)
    );
}

#[test]
fn an_unstable_scene_stops_with_advice_and_leaves_nothing_behind() {
    let tmp = scratch("unstable");
    let dir = tmp.path();
    let scene = ribbon_variant(
        dir,
        &[("dt = 2e-4", "dt = 0.02"), (RIBBON_STOP, "steps = 2000")],
        "\n[output]\nframes = 1\nply = true\n",
    );
    let out = dir.join("out");
    // The old debug variable that switched the check off is gone: it changes nothing.
    let o = common::drapekit()
        .args([
            "drape",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .env("DRAPEKIT_NO_STABILITY_CHECK", "1")
        .output()
        .unwrap();
    let (_, err) = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    for needle in [
        "went unstable at step",
        "largest stable step estimated",
        "use dt <=",
    ] {
        assert!(err.contains(needle), "{needle}: {err}");
    }
    assert!(
        !out.exists(),
        "no output after an unstable run: {:?}",
        common::listing(dir)
    );
}

// ---------------------------------------------------------------------------------------------
// Determinism and modelling only what a scene needs.

fn run_in_pool(threads: usize, sc: &Scene) -> World {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| simulate(sc).0)
}

#[test]
fn results_are_identical_with_one_or_two_threads() {
    // 6,561 particles: above the size from which the step runs in parallel.
    let sc = scene_with("sphere_drop.toml", |s| {
        s.pieces[0].spacing = 0.01;
        s.solver.dt = 5e-5;
        s.stop = Stop::Steps(1600);
    });
    assert!(sim::load(&sc).unwrap().model.len() >= drapekit::par::PARALLEL_MIN);
    let one = run_in_pool(1, &sc);
    let two = run_in_pool(2, &sc);
    assert!(
        one.state.contact.iter().any(|c| c.is_some()),
        "the cloth reached the sphere"
    );
    assert_eq!(one.state.x, two.state.x);
    assert_eq!(one.state.v, two.state.v);
}

#[test]
fn the_grid_changes_the_speed_never_the_result() {
    let run = |cells: Cells| {
        let sc = scene_with("sphere_drop.toml", |s| {
            s.cells = cells;
            s.stop = Stop::Steps(1500);
        });
        simulate(&sc).0
    };
    let auto = run(Cells::Auto);
    assert!(auto.state.contact.iter().filter(|c| c.is_some()).count() > 50);
    for cells in [[2, 3, 2], [5, 5, 5], [40, 40, 40]] {
        let w = run(Cells::Fixed(cells));
        assert_eq!(w.state.x, auto.state.x, "cells {cells:?}");
    }
}

#[test]
fn cloth_on_two_objects_touches_both_and_enters_neither() {
    // Two spheres of radius 0.15 m side by side, the right one 5 cm higher.
    let sc = scene_with("sphere_drop.toml", |s| {
        s.stop = Stop::Steps(4000);
        let mut right = s.objects[0].clone();
        s.objects[0].scale = 0.5;
        s.objects[0].translate = Vec3::new(-0.2, 0.0, 0.0);
        right.name = "right".into();
        right.scale = 0.5;
        right.translate = Vec3::new(0.2, 0.0, 0.05);
        s.objects.push(right);
        s.pieces[0].position = Vec3::new(0.0, 0.0, 0.25);
    });
    let (w, _) = simulate(&sc);
    assert_eq!(sim::particles_inside(&w), vec![Some(0), Some(0)]);
    let th = sc.pieces[0].fabric.thickness;
    for (i, c) in sim::min_clearance(&w).into_iter().enumerate() {
        assert!(c >= th - 1e-6, "object {i}: {c}");
    }
    for object in [0, 1] {
        let n = w
            .state
            .contact
            .iter()
            .filter(|c| c.is_some_and(|c| c.object == object))
            .count();
        assert!(n > 20, "object {object}: {n} particles in contact");
    }
}

#[test]
fn an_object_out_of_reach_gets_no_grid_and_changes_nothing() {
    let base = scene_with("sphere_drop.toml", |s| s.stop = Stop::Steps(1500));
    let with_far = scene_with("sphere_drop.toml", |s| {
        s.stop = Stop::Steps(1500);
        let mut far = s.objects[0].clone();
        far.name = "far".into();
        far.translate = Vec3::new(5.0, 0.0, 0.0);
        s.objects.push(far);
    });
    let (a, _) = simulate(&base);
    let (b, _) = simulate(&with_far);
    assert_eq!(
        b.grid_built_at[1], None,
        "the far sphere was never in reach"
    );
    assert!(!b.colliders[1].grid_built(), "no grid over the far sphere");
    assert!(b.colliders[0].grid_built());
    assert!(b.grid_built_at[0].is_some());
    assert_eq!(a.state.x, b.state.x);
}

#[test]
fn lengths_in_centimetres_give_the_same_drape() {
    let m = scene_with("hanging_ribbon.toml", |s| {
        s.pieces[0].spacing = 0.02;
        s.solver.dt = 4e-4;
        s.stop = Stop::Steps(400);
    });
    let tmp = scratch("units");
    let dir = tmp.path();
    let text = std::fs::read_to_string(common::fixture("scenes/hanging_ribbon.toml")).unwrap();
    let cm = text
        .replace("units = \"m\"", "units = \"cm\"")
        .replace(
            "outline = [[-0.5, -0.02], [0.5, -0.02], [0.5, 0.02], [-0.5, 0.02]]",
            "outline = [[-50, -2], [50, -2], [50, 2], [-50, 2]]",
        )
        .replace("spacing = 0.01", "spacing = 2")
        .replace("position = [0.0, 0.0, 1.0]", "position = [0, 0, 100]")
        .replace(
            "pin_segments = [[[-0.5, -0.02], [-0.5, 0.02]], [[0.5, -0.02], [0.5, 0.02]]]",
            "pin_segments = [[[-50, -2], [-50, 2]], [[50, -2], [50, 2]]]",
        );
    std::fs::write(dir.join("cm.toml"), cm).unwrap();
    let mut c = scene::read(&dir.join("cm.toml")).unwrap();
    c.solver.dt = 4e-4;
    c.stop = Stop::Steps(400);
    assert_eq!(c.pieces[0].spacing, 0.02);
    assert!((c.gravity - m.gravity).norm() < 1e-12);
    let (a, _) = simulate(&m);
    let (b, _) = simulate(&c);
    let worst = a
        .state
        .x
        .iter()
        .zip(&b.state.x)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "{worst}");
}

// ---------------------------------------------------------------------------------------------
// The command: outputs, frames, report.

#[test]
fn drape_writes_pieces_frames_and_a_report_of_finite_numbers() {
    let tmp = scratch("outputs");
    let dir = tmp.path();
    let scene = ribbon_variant(
        dir,
        &[
            ("spacing = 0.01", "spacing = 0.02"),
            ("dt = 2e-4", "dt = 4e-4"),
            (RIBBON_STOP, "steps = 1000"),
        ],
        "\n[output]\nframes = 250\nply = true\n",
    );
    let out = dir.join("out");
    let (stdout, r) = drape_with_report(&scene, &out, dir);
    assert!(
        stdout.contains("particles") && stdout.contains("strain"),
        "{stdout}"
    );
    assert_eq!(
        common::listing(&out),
        ["frames", "ribbon.obj", "ribbon.ply"]
    );
    assert_eq!(
        common::listing(&out.join("frames")),
        [
            "ribbon_0000250.obj",
            "ribbon_0000500.obj",
            "ribbon_0000750.obj",
            "ribbon_0001000.obj"
        ]
    );
    for key in [
        "particles",
        "springs",
        "object_faces",
        "cells",
        "steps",
        "dt",
        "wall_seconds",
        "collision_seconds",
        "contacts_end",
        "particles_inside",
        "min_clearance",
        "max_strain",
        "mean_strain",
        "kinetic_energy_end",
        "finite",
    ] {
        assert!(r.get(key).is_some(), "{key} in the report");
    }
    assert_eq!(r["steps"], 1000);
    assert_eq!(r["finite"], true);
    assert_eq!(r["object_faces"], 0);
    let n = r["particles"].as_u64().unwrap() as usize;
    for f in ["ribbon.obj", "ribbon.ply", "frames/ribbon_0000500.obj"] {
        let m = drapekit::io::read_mesh(&out.join(f), &Default::default())
            .unwrap()
            .mesh;
        assert_eq!(m.positions.len(), n, "{f}");
        assert!(m.positions.iter().all(|p| p.iter().all(|c| c.is_finite())));
        assert_eq!(
            m.faces.len(),
            r["pieces"][0]["triangles"].as_u64().unwrap() as usize
        );
    }
    // The clamped ends have not moved; the middle has sagged.
    let m = drapekit::io::read_mesh(&out.join("ribbon.obj"), &Default::default())
        .unwrap()
        .mesh;
    let lowest = m
        .positions
        .iter()
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    assert!(lowest < 0.99, "{lowest}");
    assert!(m
        .positions
        .iter()
        .any(|p| (p - Point3::new(-0.5, 0.0, 1.0)).norm() < 1e-12));
    // The JSON summary is the report.
    let o = drape_cli(&scene, &out, &["--json"]);
    let j: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["particles"], r["particles"]);
}

// ---------------------------------------------------------------------------------------------
// Bad scenes.

/// Runs `drape` on a scene text written to a scratch directory beside a copy of the sphere
/// mesh; asserts exit code 1, that stderr names the file and contains each needle, and that no
/// output was created; its stderr.
fn refused(name: &str, text: &str, needles: &[&str]) -> String {
    refused_with(name, text, &[], needles)
}

/// As `refused`, with extra files (name, content) beside the scene; returns stderr.
fn refused_with(name: &str, text: &str, files: &[(&str, &str)], needles: &[&str]) -> String {
    let tmp = scratch(&format!("bad-{name}"));
    let dir = tmp.path();
    for (f, content) in files {
        std::fs::write(dir.join(f), content).unwrap();
    }
    beside_sphere(dir);
    let scene = dir.join(format!("{name}.toml"));
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let o = drape_cli(&scene, &out, &[]);
    let (_, err) = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{name}: {err}");
    assert!(
        err.contains(&format!("{name}.toml")),
        "{name}: names the file: {err}"
    );
    for n in needles {
        assert!(err.contains(n), "{name}: '{n}' in: {err}");
    }
    assert!(!out.exists(), "{name}: nothing written");
    err
}

/// The good scene of the bad-scene tests (each bad scene is it with a change).
fn good() -> String {
    std::fs::read_to_string(common::fixture("bad_scene_base.toml")).unwrap()
}

#[test]
fn the_good_scene_of_the_bad_scene_tests_runs() {
    let tmp = scratch("good");
    let dir = tmp.path();
    beside_sphere(dir);
    std::fs::write(dir.join("good.toml"), good()).unwrap();
    let o = drape_cli(&dir.join("good.toml"), &dir.join("out"), &[]);
    assert!(o.status.success(), "{}", common::text(&o).1);
}

#[test]
fn bad_scenes_are_refused_naming_the_file_and_the_key() {
    refused(
        "missing_mesh",
        &good().replace("sphere_r0.3.obj", "nowhere.obj"),
        &["object[1].mesh", "nowhere.obj", "does not exist"],
    );
    refused(
        "self_intersecting",
        &good().replace(
            "[[-0.4, -0.4], [0.4, -0.4], [0.4, 0.4], [-0.4, 0.4]]",
            "[[-0.4, -0.4], [0.4, 0.4], [0.4, -0.4], [-0.4, 0.4]]",
        ),
        &["piece[1].outline", "intersects itself"],
    );
    refused(
        "two_points",
        &good().replace(
            "[[-0.4, -0.4], [0.4, -0.4], [0.4, 0.4], [-0.4, 0.4]]",
            "[[0, 0], [1, 0]]",
        ),
        &["piece[1].outline", "at least 3 points"],
    );
    refused(
        "negative_density",
        &(good().replace("fabric = \"cotton\"", "fabric = \"thin\"")
            + "[fabric.thin]\nbase = \"cotton\"\ndensity = -0.1\n"),
        &["fabric.thin.density", "positive"],
    );
    refused(
        "negative_step",
        &good().replace("dt = 1e-4", "dt = -1e-4"),
        &["solver.dt", "positive"],
    );
    refused(
        "unknown_key",
        &good().replace("spacing = 0.05", "spacing = 0.05\ncolour = \"red\""),
        &["unknown_key.toml: line 12, column 1: unknown field `colour`, expected one of"],
    );
    refused(
        "unknown_preset",
        &good().replace("fabric = \"cotton\"", "fabric = \"velvet\""),
        &["piece[1].fabric", "unknown fabric 'velvet'", "cotton"],
    );
    refused(
        "unknown_unit",
        &good().replace("units = \"m\"", "units = \"ft\""),
        &["units", "'ft'"],
    );
    refused(
        "pin_off_the_cloth",
        &good().replace(
            "fabric = \"cotton\"",
            "fabric = \"cotton\"\npin = [[0.0, 0.9]]",
        ),
        &[
            "piece[1].outline",
            "pin 1 at (0, 0.9) is 0.5 from the nearest particle",
        ],
    );
    refused(
        "no_stop",
        &good().replace("steps = 10", ""),
        &["solver", "exactly one of steps, duration or until_rest"],
    );
    refused(
        "bad_cells",
        &(good() + "[collision]\ncells = [0, 5, 5]\n"),
        &["collision.cells", "1..4096"],
    ); // Keys of one integrator in a scene that uses another (the default is projective dynamics).
    refused(
        "newton_with_the_default",
        &good().replace("steps = 10", "steps = 10\nnewton_iterations = 3"),
        &[
            "solver.newton_iterations",
            "integrator = \"implicit-euler\" only",
            "projective-dynamics",
        ],
    );
    refused(
        "bending_hessian_with_the_default",
        &good().replace("steps = 10", "steps = 10\nbending_hessian = \"lumped\""),
        &[
            "solver.bending_hessian",
            "integrator = \"implicit-euler\" only",
        ],
    );
    refused(
        "bending_hessian_unknown",
        &good().replace(
            "steps = 10",
            "steps = 10\nintegrator = \"implicit-euler\"\nbending_hessian = \"diagonal\"",
        ),
        &[
            "solver.bending_hessian",
            "unknown bending Hessian 'diagonal': expected 'exact' or 'lumped'",
        ],
    );
    let err = refused(
        "iterations_with_leapfrog",
        &good().replace(
            "steps = 10",
            "steps = 10\nintegrator = \"leapfrog\"\nchebyshev = 0.9",
        ),
        &["key 'solver.chebyshev': applies to integrator = \"projective-dynamics\" only (this scene uses leapfrog)"],
    );
    // The key by its own name, and no advice about Anderson for a leapfrog scene.
    assert!(!err.contains("solver.iterations"), "{err}");
    assert!(!err.contains("needs anderson = 0"), "{err}");
    refused(
        "chebyshev_with_anderson",
        &good().replace("steps = 10", "steps = 10\nchebyshev = 0.9"),
        &["solver.chebyshev", "needs anderson = 0"],
    );
    refused(
        "strain_band_out_of_range",
        &good().replace("steps = 10", "steps = 10\nstrain_band = -0.1"),
        &["solver.strain_band", "[0, 1), got -0.1"],
    );
    refused(
        "strain_tolerance_out_of_range",
        &good().replace("steps = 10", "steps = 10\nstrain_tolerance = 0"),
        &["solver.strain_tolerance", "(0, 1), got 0"],
    );
    refused(
        "too_many_corrections",
        &good().replace("steps = 10", "steps = 10\ncorrections = 11"),
        &["solver.corrections", "0 (none) to 10 rounds, got 11"],
    );
    refused(
        "anderson_too_deep",
        &good().replace("steps = 10", "steps = 10\nanderson = 1000"),
        &["solver.anderson", "0 (off) to 20", "got 1000"],
    );
    refused(
        "chebyshev_out_of_range",
        &good().replace("steps = 10", "steps = 10\nanderson = 0\nchebyshev = 1.0"),
        &["solver.chebyshev", "(0, 1), got 1"],
    );
    refused(
        "unknown_integrator",
        &good().replace("steps = 10", "steps = 10\nintegrator = \"verlet\""),
        &[
            "solver.integrator",
            "unknown integrator 'verlet'",
            "projective-dynamics",
        ],
    );
}

#[test]
fn every_problem_of_a_scene_is_reported_at_once() {
    let text = good()
        .replace("dt = 1e-4", "dt = -1")
        .replace("sphere_r0.3.obj", "nowhere.obj")
        .replace(
            "fabric = \"cotton\"",
            "fabric = \"velvet\"\nspacing_typo = 1",
        );
    // A TOML-level problem (the unknown key) stops the reading first.
    refused("typo_first", &text, &["unknown field `spacing_typo`"]);
    let text = text.replace("\nspacing_typo = 1", "");
    refused(
        "three_problems",
        &text,
        &[
            "3 problems",
            "key 'solver.dt': must be a positive number, got -1",
            "key 'object[1].mesh'",
            "nowhere.obj does not exist",
            "key 'piece[1].fabric': unknown fabric 'velvet'",
        ],
    );
    // Pieces and meshes are checked together too.
    let text = good()
        .replace(
            "[[-0.4, -0.4], [0.4, -0.4], [0.4, 0.4], [-0.4, 0.4]]",
            "[[-0.4, -0.4], [0.4, 0.4], [0.4, -0.4], [-0.4, 0.4]]",
        )
        .replace("sphere_r0.3.obj", "empty.obj");
    refused_with(
        "piece_and_mesh",
        &text,
        &[("empty.obj", "# nothing\n")],
        &[
            "2 problems",
            "key 'piece[1].outline': the outline intersects itself",
            "key 'object[1].mesh'",
            "empty.obj",
        ],
    );
}

#[test]
fn a_mesh_that_is_not_a_surface_is_refused() {
    // Every face degenerate: nothing to collide with after cleaning.
    let tmp = scratch("flat-mesh");
    let dir = tmp.path();
    std::fs::write(
        dir.join("line.obj"),
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("flat.toml"),
        good().replace("sphere_r0.3.obj", "line.obj"),
    )
    .unwrap();
    let out = dir.join("out");
    let o = drape_cli(&dir.join("flat.toml"), &out, &[]);
    let (_, err) = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    for n in ["flat.toml", "object[1].mesh", "no faces remain"] {
        assert!(err.contains(n), "{n}: {err}");
    }
    assert!(!out.exists());
    // A mesh file that does not parse names its own line.
    std::fs::write(
        dir.join("broken.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("broken.toml"),
        good().replace("sphere_r0.3.obj", "broken.obj"),
    )
    .unwrap();
    let o = drape_cli(&dir.join("broken.toml"), &out, &[]);
    let (_, err) = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("broken.obj:4:") && err.contains("out of range"),
        "{err}"
    );
    assert!(!out.exists());
}

// ---------------------------------------------------------------------------------------------
// The implicit integrators on the validation scenes.

#[test]
fn implicit_integrators_hang_the_ribbon_as_an_elastic_catenary_at_large_steps() {
    let f = scene_with("hanging_ribbon.toml", |_| {}).pieces[0]
        .fabric
        .clone();
    let (e, g) = (f.stretch[0], f.shear);
    let ea = e * (e + 2.0 * g) / (e + g);
    let (_, sag) = elastic_catenary(1.0, 1.0, f.density * 9.81, ea);
    for (integrator, iterations, tol) in [
        (Integrator::ImplicitEuler, 1, 0.02),
        (Integrator::ProjectiveDynamics, 200, 0.02),
    ] {
        let sc = scene_with("hanging_ribbon.toml", |s| {
            s.pieces[0].spacing = 0.02;
            s.solver = SolverSettings {
                iterations,
                ..SolverSettings::new(integrator).with_dt(0.01)
            };
        });
        let w0 = sim::load(&sc).unwrap();
        let mid = nearest(&w0.state.x, &Point3::new(0.0, 0.0, 1.0));
        let (w, stats) = simulate(&sc);
        assert!(stats.at_rest, "{integrator}: at rest");
        let s = w0.state.x[mid].z - w.state.x[mid].z;
        let err = (s - sag).abs() / sag;
        assert!(err < tol, "{integrator}: sag {s} against {sag} ({err:.4})");
    }
}

#[test]
fn implicit_results_are_identical_with_one_or_two_threads() {
    for integrator in [Integrator::ImplicitEuler, Integrator::ProjectiveDynamics] {
        let sc = scene_with("sphere_drop.toml", |s| {
            s.pieces[0].spacing = 0.01;
            s.pieces[0].fabric = Fabric::cotton();
            s.solver = SolverSettings::new(integrator).with_dt(0.005);
            s.stop = Stop::Steps(40);
        });
        assert!(sim::load(&sc).unwrap().model.len() >= drapekit::par::PARALLEL_MIN);
        let one = run_in_pool(1, &sc);
        let two = run_in_pool(2, &sc);
        assert!(
            one.state.contact.iter().any(|c| c.is_some()),
            "{integrator}: the cloth reached the sphere"
        );
        assert_eq!(one.state.x, two.state.x, "{integrator}");
        assert_eq!(one.state.v, two.state.v, "{integrator}");
    }
}

#[test]
fn an_explicit_scene_without_dt_steps_just_under_its_stability_estimate() {
    // Real cotton at 5 mm: leapfrog is stable below about 9.5e-6 s there, so a fixed default of
    // 1e-5 s would blow up. Without `dt` the step is chosen from the cloth's estimate.
    let tmp = scratch("nodt");
    let dir = tmp.path();
    let scene = ribbon_variant(
        dir,
        &[
            ("dt = 2e-4\n", ""),
            ("spacing = 0.01", "spacing = 0.005"),
            ("fabric = \"knit\"", "fabric = \"cotton\""),
            (RIBBON_STOP, "duration = 0.01"),
        ],
        "",
    );
    let out = dir.join("out");
    let (stdout, r) = drape_with_report(&scene, &out, dir);
    assert!(stdout.contains("no dt in the scene"), "{stdout}");
    let (dt, estimate) = (
        r["dt"].as_f64().unwrap(),
        r["stable_step_estimate"].as_f64().unwrap(),
    );
    assert!(r["dt_from_estimate"].as_bool().unwrap());
    assert!((dt / estimate - drapekit::scene::EXPLICIT_STEP_FRACTION).abs() < 1e-12);
    assert!(dt < 1e-5, "{dt}");
    assert_eq!(r["steps"].as_u64().unwrap(), (0.01 / dt).round() as u64);
    // Explicit Euler's estimate for the same cloth asks for billions of steps: refused before
    // the run, naming the key.
    let euler = ribbon_variant(
        dir,
        &[
            ("dt = 2e-4\n", ""),
            (
                "integrator = \"leapfrog\"",
                "integrator = \"explicit-euler\"",
            ),
            ("fabric = \"knit\"", "fabric = \"cotton\""),
            (RIBBON_STOP, "duration = 1.0"),
        ],
        "",
    );
    let o = drape_cli(&euler, &dir.join("out2"), &[]);
    let (_, err) = common::text(&o);
    assert!(!o.status.success());
    assert!(
        err.contains("solver.dt") && err.contains("explicit-euler"),
        "{err}"
    );
    assert!(!dir.join("out2").exists());
}

#[test]
fn a_scene_piece_with_a_hole_has_no_cloth_in_the_hole() {
    let tmp = scratch("hole");
    let dir = tmp.path();
    beside_sphere(dir);
    // A 20 cm square hole in the middle of the 80 cm square.
    let holed = good().replace(
        "spacing = 0.05",
        "holes = [[[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]]\nspacing = 0.05",
    );
    std::fs::write(dir.join("holed.toml"), &holed).unwrap();
    let sc = scene::read(&dir.join("holed.toml")).unwrap();
    let w = sim::load(&sc).unwrap();
    let area: f64 = w.model.pieces[0].area;
    assert!((area - (0.64 - 0.04)).abs() < 1e-9, "{area}");
    let in_hole = |p: &Point3| p.x.abs() < 0.1 - 1e-9 && p.y.abs() < 0.1 - 1e-9;
    assert!(!w.state.x.iter().any(in_hole));
    // A hole that leaves the outline is refused, naming the key and the hole.
    let bad = good().replace(
        "spacing = 0.05",
        "holes = [[[0.3, -0.1], [0.5, -0.1], [0.5, 0.1], [0.3, 0.1]]]\nspacing = 0.05",
    );
    refused(
        "hole_out",
        &bad,
        &["piece[1].holes", "hole 1 is not inside the outline"],
    );
}

#[test]
fn a_scene_seam_sews_two_pieces_edge_to_edge() {
    let tmp = scratch("seam");
    let dir = tmp.path();
    // Two 20 cm squares of real cotton side by side, 4 cm apart, weightless: the seam joins
    // the left one's right edge (bottom to top) to the right one's left edge.
    let text = |a_from: &str| {
        format!(
            r#"units = "m"
gravity = [0.0, 0.0, 0.0]
[solver]
duration = 1.0
[[piece]]
name = "left"
outline = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]
spacing = 0.02
position = [-0.12, 0.0, 0.5]
fabric = "cotton"
[[piece]]
name = "right"
outline = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]
spacing = 0.02
position = [0.12, 0.0, 0.5]
fabric = "cotton"
[[seam]]
a = {{ piece = "left", from = {a_from}, to = [0.1, 0.1] }}
b = {{ piece = "right", from = [-0.1, 0.1], to = [-0.1, -0.1] }}
"#
        )
    };
    std::fs::write(dir.join("seam.toml"), text("[0.1, -0.1]")).unwrap();
    let sc = scene::read(&dir.join("seam.toml")).unwrap();
    // Sewn as laid out: each pair starts at one height, across the 4 cm gap (the sides run
    // opposite ways round their outlines).
    let w0 = sim::load(&sc).unwrap();
    for s in w0.model.springs.iter().filter(|s| s.rest == 0.0) {
        let (a, b) = (w0.state.x[s.a as usize], w0.state.x[s.b as usize]);
        assert!(
            (a.y - b.y).abs() < 1e-9 && (b.x - a.x - 0.04).abs() < 1e-9,
            "{a} {b}"
        );
    }
    let (w, _) = simulate(&sc);
    let seams: Vec<_> = w
        .model
        .springs
        .iter()
        .filter(|s| s.kind == drapekit::cloth::elements::SpringKind::Seam)
        .collect();
    // Eleven particles a side at 2 cm, sewn bottom to bottom, top to top.
    assert_eq!(seams.len(), 11);
    for s in &seams {
        let (a, b) = (w.state.x[s.a as usize], w.state.x[s.b as usize]);
        assert!((a - b).norm() < 1e-3, "gap {}", (a - b).norm());
        assert!((a.y - b.y).abs() < 1e-3);
    }
    assert!(
        w.self_contact.is_some(),
        "sewn pieces collide with each other"
    );
    // A side that does not start at an outline corner is refused, naming the seam's key.
    let bad = text("[0.1, -0.05]");
    refused(
        "seam_off",
        &bad,
        &["seam[1].a", "not on the outline of piece 'left'"],
    );
}

#[test]
fn a_frame_callback_that_reports_rest_ends_the_run_there() {
    let tmp = scratch("frame-rest");
    let dir = tmp.path();
    beside_sphere(dir);
    std::fs::write(dir.join("good.toml"), good()).unwrap();
    let sc = scene::read(&dir.join("good.toml")).unwrap();
    let mut w = sim::load(&sc).unwrap();
    let mut seen = Vec::new();
    let stats = sim::run(
        &mut w,
        &sc.solver,
        sim::Stop::Steps(10),
        Some(2),
        &mut |step, _| {
            seen.push(step);
            Ok(step >= 4)
        },
        &|_| {},
        Default::default(),
    )
    .unwrap();
    assert_eq!(seen, vec![2, 4]);
    assert_eq!(stats.steps, 4);
    assert!(stats.at_rest);
}
