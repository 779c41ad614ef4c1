//! Time integration (`method.md` s. 3), behind one stepping loop: the integrators differ only in
//! how one step turns positions, velocities and forces into new positions and velocities.
//!
//! * explicit Euler: `x+ = x + h v`, `v+ = v + h F/m`. Stable only below `c / w^2` for air
//!   damping `c` and the highest eigenfrequency `w`: it needs tiny steps, and damping.
//! * leapfrog (symplectic Euler, the papers' default): `v+ = v + h F/m`, `x+ = x + h v+`.
//!   Stable below `2 / w`: an order of magnitude larger steps.
//!
//! Implicit Euler and projective dynamics will join as further variants of [`Integrator`].

use crate::math::{Point3, Vec3};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// The time integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Integrator {
    /// Explicit (forward) Euler.
    ExplicitEuler,
    /// Leapfrog / symplectic Euler (default).
    Leapfrog,
}

impl FromStr for Integrator {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "explicit-euler" => Ok(Integrator::ExplicitEuler),
            "leapfrog" => Ok(Integrator::Leapfrog),
            _ => Err(format!(
                "unknown integrator '{s}': expected 'explicit-euler' or 'leapfrog'"
            )),
        }
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Integrator::ExplicitEuler => "explicit-euler",
            Integrator::Leapfrog => "leapfrog",
        })
    }
}

/// One step of `integrator` for one particle of inverse mass `w` (0: pinned, it stays) from
/// position `x`, velocity `v` and force `f`: the new position and velocity.
#[inline]
pub fn advance(
    integrator: Integrator,
    dt: f64,
    w: f64,
    x: Point3,
    v: Vec3,
    f: Vec3,
) -> (Point3, Vec3) {
    if w == 0.0 {
        return (x, Vec3::zeros());
    }
    let a = f * w;
    match integrator {
        Integrator::ExplicitEuler => (x + v * dt, v + a * dt),
        Integrator::Leapfrog => {
            let v1 = v + a * dt;
            (x + v1 * dt, v1)
        }
    }
}
