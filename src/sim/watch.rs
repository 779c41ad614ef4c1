//! The measure phase's watches: stability (finite numbers, bounded energy) and rest.
//!
//! **Energy.** The mechanical energy `E = T + U_springs + U_gravity`, with the gravity energy
//! measured from the positions at the start (so the budget does not depend on where the scene
//! sits), can only fall: damping, friction and the implicit integrators' numerical damping take
//! energy out, and nothing puts it in (pins do no work). A stable integrator's error is bounded;
//! with the implicit integrators, the energy the collide phase adds at large steps (its
//! projections stretch springs) is counted as work put in (`Watch::add_work`);
//! a run whose energy rises above its start (less that work) by more than the scene's energy scale (the work
//! gravity could do over the scene's diagonal plus 1 m, plus the energy at the start) is
//! unstable.
//!
//! **Rest.** With `until_rest`, the cloth is at rest when its kinetic energy stays below the
//! threshold at every check of a window of at least 0.05 s (a swing passes through low energy
//! only briefly), and does not rise over it (a cloth let go from rest starts with none).

use super::{check_every, Stop, World};
use crate::cloth::forces;
use crate::math::{Aabb, Point3};
use serde::Serialize;
use std::collections::VecDeque;
use std::fmt;

/// Why a run was stopped as unstable.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Instability {
    /// A position or velocity is not a finite number.
    NonFinite,
    /// The mechanical energy rose above its start by `rise` joules (more than `budget`).
    EnergyRose { rise: f64, budget: f64 },
}

impl fmt::Display for Instability {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Instability::NonFinite => f.write_str("non-finite positions or velocities"),
            Instability::EnergyRose { rise, .. } => write!(f, "the energy rose by {rise:.3e} J"),
        }
    }
}

/// Whether the energy watch may stop a run ([`super::Control::stability`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum StabilityCheck {
    /// Every check: a non-finite position or velocity, or an energy rise beyond the scene's
    /// budget, ends the run as unstable (the default; the only choice of the command line).
    #[default]
    On,
    /// Never: the run goes on whatever its numbers do. For experiments and tests that show
    /// what the watch prevents; a run without it can end with non-finite positions.
    Off,
}

/// The energy watch of a run.
#[derive(Debug)]
pub struct Watch {
    x0: Vec<Point3>,
    e0: f64,
    budget: f64,
    /// Work done on the cloth by the collide phase, J.
    work: f64,
    check: StabilityCheck,
}

impl Watch {
    /// The watch of a world at its start, checking (see [`Watch::checking`] to switch it off).
    pub fn new(world: &World) -> Watch {
        let m = &world.model;
        let x0 = world.state.x.clone();
        let scene_box = world
            .colliders
            .iter()
            .fold(Aabb::of_points(&x0).unwrap(), |mut b, c| {
                b.include(&c.bbox.min);
                b.include(&c.bbox.max);
                b
            });
        let mass: f64 = m.mass.iter().sum();
        let e0 = forces::kinetic_energy(m, &world.state.v) + forces::spring_energy(m, &x0);
        let budget = mass * m.gravity.norm() * (scene_box.diagonal() + 1.0) + e0 + 1e-9;
        Watch {
            x0,
            e0,
            budget,
            work: 0.0,
            check: StabilityCheck::On,
        }
    }

    /// The same watch with its check switched on or off.
    pub fn checking(self, check: StabilityCheck) -> Watch {
        Watch { check, ..self }
    }

    /// The mechanical energy of the world, relative to the start's gravity energy, J.
    pub fn energy(&self, world: &World) -> f64 {
        let m = &world.model;
        forces::kinetic_energy(m, &world.state.v)
            + forces::spring_energy(m, &world.state.x)
            + forces::gravity_energy(m, &world.state.x, &self.x0)
    }

    /// Adds the energy change of a collide phase, counted as work put in when positive.
    pub fn add_work(&mut self, de: f64) {
        self.work += de.max(0.0);
    }

    /// The energy scale above which a rise is an instability, J.
    pub fn budget(&self) -> f64 {
        self.budget
    }

    /// Whether the world is still sound.
    pub fn check(&self, world: &World) -> Result<(), Instability> {
        if self.check == StabilityCheck::Off {
            return Ok(());
        }
        let s = &world.state;
        let finite = s.x.iter().all(|p| p.iter().all(|c| c.is_finite()))
            && s.v.iter().all(|v| v.iter().all(|c| c.is_finite()));
        if !finite {
            return Err(Instability::NonFinite);
        }
        let e = self.energy(world);
        if !e.is_finite() {
            return Err(Instability::NonFinite);
        }
        if e - self.e0 - self.work > self.budget {
            return Err(Instability::EnergyRose {
                rise: e - self.e0 - self.work,
                budget: self.budget,
            });
        }
        Ok(())
    }
}

/// The energy watch's state, for checkpoints: the start it measures from and the work put in
/// so far.
#[derive(Debug, Clone, PartialEq)]
pub struct WatchState {
    /// Positions at the start (gravity energy is measured from them), m.
    pub x0: Vec<Point3>,
    /// Mechanical energy at the start, J.
    pub e0: f64,
    /// The energy scale, J.
    pub budget: f64,
    /// Work done on the cloth by the collide phase so far, J.
    pub work: f64,
}

impl Watch {
    /// Its state (checkpoints).
    pub fn saved(&self) -> WatchState {
        WatchState {
            x0: self.x0.clone(),
            e0: self.e0,
            budget: self.budget,
            work: self.work,
        }
    }

    /// Continues from a saved state.
    pub fn restore(&mut self, s: &WatchState) {
        self.x0.clone_from(&s.x0);
        self.e0 = s.e0;
        self.budget = s.budget;
        self.work = s.work;
    }
}

/// Kinetic + spring + gravity energy of positions `x` and velocities `v`, gravity measured from
/// `x0`, J.
pub fn mechanical(
    model: &crate::cloth::model::ClothModel,
    x: &[Point3],
    v: &[crate::math::Vec3],
    x0: &[Point3],
) -> f64 {
    forces::kinetic_energy(model, v)
        + forces::spring_energy(model, x)
        + forces::gravity_energy(model, x, x0)
}

/// The rest test of `until_rest`.
#[derive(Debug)]
pub struct Rest {
    threshold: Option<f64>,
    window: usize,
    low: VecDeque<f64>,
}

impl Rest {
    /// The rest test of a run that stops at `stop`, with step `dt`.
    pub fn new(stop: Stop, dt: f64) -> Rest {
        Rest {
            threshold: match stop {
                Stop::UntilRest { energy, .. } => Some(energy),
                Stop::Steps(_) => None,
            },
            window: ((0.05 / (dt * check_every(dt) as f64)).ceil() as usize).max(8),
            low: VecDeque::new(),
        }
    }

    /// The kinetic energies of the checks in its window so far, J (checkpoints).
    pub fn saved(&self) -> Vec<f64> {
        self.low.iter().copied().collect()
    }

    /// Continues from [`Rest::saved`].
    pub fn restore(&mut self, low: &[f64]) {
        self.low = low.iter().copied().collect();
    }

    /// Called at every check: whether the cloth is at rest.
    pub fn at_rest(&mut self, world: &World) -> bool {
        let Some(rest) = self.threshold else {
            return false;
        };
        let ke = forces::kinetic_energy(&world.model, &world.state.v);
        if ke < rest {
            self.low.push_back(ke);
            if self.low.len() > self.window {
                self.low.pop_front();
            }
            self.low.len() == self.window && ke <= self.low[0]
        } else {
            self.low.clear();
            false
        }
    }
}
