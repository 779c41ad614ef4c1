//! GarmentCode sewing patterns: reading, validating and sampling specification JSON files.
//!
//! A pattern is a set of flat panels, each a closed loop of straight, Bezier or circular-arc
//! edges in 2D with a rigid placement in 3D (`R (x, y, 0) + t`, `R = Rz Ry Rx` in degrees),
//! and stitches that join pairs of edges. [`spec`] reads a file into a typed [`Pattern`] and
//! reports every problem it finds; [`curve`] evaluates, measures and samples edge curves;
//! [`sample`] samples the outlines with the two edges of every stitch paired point to point;
//! [`gathers`] lists the stitches that join edges of different lengths; [`fit_check`] compares
//! each closed ring of the sewn garment with the body's girth where it sits, before a drape;
//! [`measure`] measures and judges a drape, [`spots`] says where it fails and [`hang`] how
//! each of those rings hangs after it; [`frame`] brings
//! a body from elsewhere under the pattern's panels; [`perturb`] starts a run a tenth of a
//! micron off, to measure how much of its outcome is chance.

pub mod assemble;
pub mod clear;
pub mod curve;
pub mod drape;
pub mod facing;
pub mod fit_check;
pub mod frame;
pub mod gathers;
pub mod hang;
pub mod lift;
pub mod measure;
pub mod perturb;
pub mod sample;
pub mod spec;
pub mod spots;
pub mod transfer;
pub mod waist;

pub use curve::Curve;
pub use spec::{parse, read, Edge, EdgeRef, Panel, Pattern, Problem, SpecError, Stitch};
