//! What a solver keeps from one step to the next besides the cloth's state, taken out and put
//! back for checkpoints (`sim::checkpoint`).
//!
//! Only what a step reads before it writes it is kept; the rest is scratch that every step
//! fills afresh (projections, right-hand sides, Anderson's history and Chebyshev's weights,
//! which start over each step, the Hessians and preconditioners of implicit Euler). A solver
//! built anew and given its saved state continues exactly as the one it was taken from: the
//! same bits, step after step.

use super::SolveStats;
use crate::cloth::state::Contact;
use crate::math::{Point3, Vec3};

/// A solver's persistent state and its counters.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolverState {
    /// The counters so far (the wall time of factorisations included).
    pub stats: SolveStats,
    /// The integrator's own state.
    pub kept: Kept,
}

/// The state each integrator keeps between steps.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum Kept {
    /// The explicit integrators keep nothing.
    #[default]
    Nothing,
    /// Implicit Euler: the friction state of each particle.
    Implicit(ImplicitKept),
    /// Projective dynamics: contact stiffening, the last projections, the factored matrix.
    Projective(ProjectiveKept),
}

/// Implicit Euler's friction state, per particle.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImplicitKept {
    /// Held by static friction.
    pub stuck: Vec<bool>,
    /// The face's normal force at the end of the last step, N.
    pub normal_force: Vec<f64>,
    /// The direction of kinetic friction for a particle that just broke free.
    pub slip_dir: Vec<Vec3>,
}

/// Projective dynamics' state between steps.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProjectiveKept {
    /// Per particle, what its contact weight is raised by (1 to `CONTACT_STIFFEN_MAX`).
    pub stiff: Vec<f64>,
    /// Per particle, the contact constraint's last projection.
    pub target: Vec<Point3>,
    /// The contacts of the last step.
    pub contact: Vec<Option<Contact>>,
    /// Per particle, the contact weight the global matrix was last factored with.
    pub factored: Vec<f64>,
    /// The low-rank correction on top of that factorisation.
    pub update: UpdateKept,
}

/// A low-rank correction of changed diagonal entries (`lowrank::DiagonalUpdate`): its columns
/// are recomputed from the factor (the same bits), its products are kept as they were (so
/// their bits do not depend on the order the columns came in).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct UpdateKept {
    /// The changed unknowns.
    pub index: Vec<u32>,
    /// Their changes.
    pub delta: Vec<f64>,
    /// `V^T V`, `k x k`, column by column.
    pub gram: Vec<f64>,
}
