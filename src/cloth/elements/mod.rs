//! The cloth's elements, each with its energy, gradient and Hessian in one place:
//! * [`Spring`]: `E = k (|x_b - x_a| - l)^2 / 2` (`spring.rs`);
//! * [`Bend`]: `E = c |sum_k w_k x_k|^2 / 2` over a few particles (`bend.rs`); a hinge over
//!   an edge is one (`hinge.rs`).
//!
//! Forces are minus the gradients; the implicit integrators use the Hessians (the spring's kept
//! positive semi-definite when asked), projective dynamics their projections. Unit tests compare
//! every gradient with the finite differences of the energy and every Hessian with those of the
//! gradient.

pub mod bend;
pub mod hinge;
pub mod spring;

pub use bend::Bend;
pub use spring::{Spring, SpringKind};
