//! Batches of drapes: the product of garments (scenes or patterns), bodies, fabrics and sizes
//! from a plan file, run on this machine or as a scheduler's array.
//!
//! - [`plan`] reads the plan; each job's id is its axis values' names joined by `.`, so adding a
//!   value keeps every id. [`order`] keeps positions (`--index`) stable in an output folder.
//! - [`run`] runs the jobs: `workers` at once, each with `max(1, cores / workers)` threads, each
//!   as a child process of the drapekit binary ([`job`]), its scene derived by
//!   [`derive`](mod@derive), its body fitted or scaled once by [`body`]; [`status`] records
//!   each job atomically, so a rerun skips done jobs and retries the rest.
//! - [`collect`] makes the table; [`slurm`] writes the `sbatch` array script.
//!
//! Layout of an output folder `OUT`: `order.json` (positions), `bodies/` (fitted and scaled
//! bodies), `jobs/<id>/` (`status.json`, `scene.toml` for a scene job, `log.txt`,
//! `report.json`, `out/` with the meshes), `logs/` (the scheduler's), `results.csv`,
//! `results.json`, `contact_sheet.tsv`, `batch.sbatch`.

pub mod body;
pub mod collect;
pub mod derive;
mod error;
pub mod job;
pub mod order;
pub mod plan;
pub mod run;
pub mod sheet;
pub mod slurm;
pub mod status;

pub use error::BatchError;
