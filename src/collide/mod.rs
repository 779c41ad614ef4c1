//! Collision of cloth particles with rigid objects (`method.md` s. 4): the uniform grid of
//! cells, the collider of each object, and the contact response with sliding and friction.

pub mod body_points;
pub mod cloth;
pub mod collider;
pub mod contact;
pub mod grid;
pub mod inside;
pub mod sheets;

pub use collider::Collider;
