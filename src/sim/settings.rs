//! What a run is told besides the solver's settings: when to stop, and how to cut the collision
//! grids.

/// When a run stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stop {
    /// After this many steps.
    Steps(u64),
    /// When the kinetic energy (J) falls below the threshold, or after `max_steps`.
    UntilRest { energy: f64, max_steps: u64 },
}

impl Stop {
    /// The most steps the run takes.
    pub fn max_steps(&self) -> u64 {
        match *self {
            Stop::Steps(s) => s,
            Stop::UntilRest { max_steps, .. } => max_steps,
        }
    }
}

/// Cells of the collision grids.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cells {
    /// The same counts for every object.
    Fixed([usize; 3]),
    /// The `auto` rule (`Collider::auto_dims`).
    Auto,
}
