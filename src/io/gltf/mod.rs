//! glTF 2.0: read `.gltf` (JSON, buffers in files beside it or in `data:` URIs) and `.glb`
//! (the binary container), write both.
//!
//! **Reading** ([`read`]): every triangle primitive (mode 4, indexed by unsigned bytes, shorts
//! or ints, or not indexed) of every mesh the default scene places, merged into one
//! [`TriMesh`](crate::mesh::TriMesh). A node's world matrix is the product of the local matrices
//! from its root down, `W = L_root ... L_node`, each `L` given as `matrix` or as
//! `T * R * S` (translation, rotation quaternion, scale); a position `p` is placed at `W p`, and
//! a triangle under a mirroring `W` (`det W < 0`) is turned back. Other modes, sparse
//! accessors and required extensions are refused with the key they are at; so are indices out of
//! range, data beyond its buffer, non-finite positions and missing buffer files. Materials,
//! textures, normals and the rest are read past.
//!
//! **Writing** ([`write_scene`], [`Scene`]): named parts with area-weighted vertex normals
//! ([`vertex_normals`]), optional per-vertex colours, and optional frames played by a `STEP`
//! scale animation (see [`write`](mod@write)). A single mesh is written by `io::write_mesh` as a
//! scene of one part.
//!
//! The JSON structures are the `gltf-json` crate's (the glTF-rs project's): it parses and
//! serialises the whole schema; the binary container, the buffers and the accessors' bytes are
//! read here, so that every size is checked against the bytes present and every error names
//! its file and key.

pub mod glb;
mod read;
pub mod write;

pub use read::{read, MAX_PLACED_VERTICES};
pub use write::{single, stage_scene, vertex_normals, write_scene, Frame, Part, Scene, Surface};
