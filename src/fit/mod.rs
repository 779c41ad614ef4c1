//! Mannequins by trigonometric interpolation sums and the Lanczos correction (`method.md` s. 7).

pub mod error;
pub mod fitter;
pub mod foreign;
pub mod input;
pub mod lanczos;
pub mod measurements;
pub mod scan;
pub mod section;
pub mod surface;
pub mod trig;

pub use error::FitError;
