//! drapekit: a garment-CAD toolchain.
//!
//! One pipeline, three jobs: convert CAD exports into clean, consistently oriented triangle
//! meshes ([`io`], [`mesh`]); fit mannequins; drape cloth; and draw pictures of the results
//! ([`render`]). `src/main.rs` only calls [`cli::main`].

pub mod batch;
pub mod cli;
pub mod cloth;
pub mod collide;
pub mod fit;
pub mod garment;
pub mod geom;
pub mod io;
pub mod math;
pub mod mesh;
pub mod par;
pub mod plot;
pub mod render;
pub mod scene;
pub mod sim;
