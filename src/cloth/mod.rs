//! The particle cloth of `method.md` sections 2-3: fabrics, pattern pieces, the model (what never
//! changes), the state (what changes every step), forces, integrators and the stability estimate.

pub mod elements;
pub mod fabric;
pub mod forces;
pub mod holes;
pub mod integrate;
pub mod model;
pub mod pattern;
pub mod stability;
pub mod state;

pub use fabric::Fabric;
pub use integrate::Integrator;
pub use model::ClothModel;
pub use state::ClothState;
