//! Triangle meshes and the operations that prepare them: weld, clean, orient, transform, and
//! the diagnosis behind `drapekit inspect`.

pub mod clean;
pub mod closest;
pub mod delaunay;
pub mod diagnose;
pub mod generate;
pub mod orient;
pub mod polygon;
pub mod prepare;
pub mod slice;
pub mod split;
pub mod topology;
pub mod transform;
pub mod trimesh;
pub mod weld;

pub use trimesh::TriMesh;
