//! One rigid object: its prepared mesh, face planes, the faces around each face (for sliding),
//! its box, and its grid, built only the first time the cloth can reach the object.

use super::grid::Grid;
use crate::math::{Aabb, Vec3};
use crate::mesh::topology::Topology;
use crate::mesh::TriMesh;
use std::sync::OnceLock;

/// The most cells along one axis the `auto` rule picks.
pub const AUTO_MAX_CELLS: usize = 256;

/// A rigid object the cloth collides with. A clone has everything but the grid, which it
/// builds again on first use with its own `margin`.
#[derive(Debug)]
pub struct Collider {
    /// Name (for reports).
    pub name: String,
    /// The prepared mesh (welded, cleaned, oriented).
    pub mesh: TriMesh,
    /// Face planes `[nx, ny, nz, d]` (unit normal, zero for a degenerate face): a point `p` is `n . p - d` in front of face `f`'s plane
    /// (the normal and offset side by side, read together in the collision loops).
    pub planes: Vec<[f64; 4]>,
    /// The object's box.
    pub bbox: Aabb,
    /// Faces sharing a vertex with each face: `ring_start[f]..ring_start[f+1]` in `ring`.
    ring_start: Vec<u32>,
    ring: Vec<u32>,
    /// Cells along x, y, z.
    pub dims: [usize; 3],
    /// How far beyond its faces a particle is still in contact (the largest cloth thickness).
    pub margin: f64,
    /// Friction of this object (fraction of the tangential force), if it has its own.
    pub friction: Option<f64>,
    /// Extra distance kept between particles and this object's faces, on top of each
    /// particle's thickness, m (default 0; garments keep a clearance from the body so that
    /// cloth edges between resting particles do not dip through it).
    pub clearance: f64,
    /// Whether the mesh is watertight (inside tests make sense).
    pub closed: bool,
    /// Per face: every vertex of the faces around it lies on or behind its plane (the surface is
    /// locally convex there, seen from the front).
    pub convex: Vec<bool>,
    grid: OnceLock<Grid>,
}

impl Collider {
    /// A collider over a prepared mesh.
    pub fn new(
        name: String,
        mesh: TriMesh,
        dims: [usize; 3],
        margin: f64,
        friction: Option<f64>,
    ) -> Collider {
        let normals: Vec<Vec3> = (0..mesh.faces.len())
            .map(|f| {
                let n = mesh.face_cross(f);
                let l = n.norm();
                if l > 0.0 {
                    n / l
                } else {
                    Vec3::zeros()
                }
            })
            .collect();
        let planes = (0..mesh.faces.len())
            .map(|f| {
                let n: Vec3 = normals[f];
                let d = n.dot(&mesh.positions[mesh.faces[f][0] as usize].coords);
                [n.x, n.y, n.z, d]
            })
            .collect();
        let topo = Topology::build(&mesh);
        let mut ring_start = vec![0u32];
        let mut ring = Vec::new();
        for face in &mesh.faces {
            let mut r: Vec<u32> = face
                .iter()
                .flat_map(|&v| topo.vertex_faces(v).iter().copied())
                .collect();
            r.sort_unstable();
            r.dedup();
            ring.extend_from_slice(&r);
            ring_start.push(ring.len() as u32);
        }
        let closed = crate::mesh::diagnose::diagnose_with(
            &mesh,
            &topo,
            &crate::mesh::orient::plan(&mesh, &topo, false),
            false,
            true,
        )
        .watertight;
        let bbox = mesh.bbox().expect("an object has vertices");
        let eps = 1e-9 * bbox.diagonal();
        let convex = (0..mesh.faces.len())
            .map(|f| {
                let n: Vec3 = normals[f];
                let a = mesh.positions[mesh.faces[f][0] as usize];
                ring[ring_start[f] as usize..ring_start[f + 1] as usize]
                    .iter()
                    .all(|&g| {
                        mesh.faces[g as usize]
                            .iter()
                            .all(|&v| (mesh.positions[v as usize] - a).dot(&n) <= eps)
                    })
            })
            .collect();
        Collider {
            name,
            mesh,
            planes,
            bbox,
            ring_start,
            ring,
            dims,
            margin,
            friction,
            clearance: 0.0,
            closed,
            convex,
            grid: OnceLock::new(),
        }
    }

    /// The cell counts of the `auto` rule: cells a third of the mean face edge (a face then
    /// lies in a few cells and a cell holds a few faces: measured fastest on the sphere and torso
    /// scenes, see the README), at most [`AUTO_MAX_CELLS`] per axis. The step does not enter:
    /// cells as long as a particle's travel in a 20 ms step (the rule until 2026-11-30) put
    /// hundreds of faces of a 50,000-face sphere in a cell, and its collision took 10 times
    /// longer for the same result.
    pub fn auto_dims(mesh: &TriMesh) -> [usize; 3] {
        let mut total = 0.0;
        let mut n = 0usize;
        for f in &mesh.faces {
            for i in 0..3 {
                total += (mesh.positions[f[(i + 1) % 3] as usize] - mesh.positions[f[i] as usize])
                    .norm();
                n += 1;
            }
        }
        let mean = if n > 0 { total / n as f64 } else { 1.0 };
        let cell = mean / 3.0;
        let size = mesh.bbox().map_or(Vec3::zeros(), |b| b.size());
        [0, 1, 2].map(|a| ((size[a] / cell).ceil() as usize).clamp(1, AUTO_MAX_CELLS))
    }

    /// The plane of face `f`: its unit normal and offset.
    #[inline(always)]
    pub fn plane(&self, f: usize) -> (Vec3, f64) {
        let [x, y, z, d] = self.planes[f];
        (Vec3::new(x, y, z), d)
    }

    /// The grid, built on first use.
    pub fn grid(&self) -> &Grid {
        self.grid
            .get_or_init(|| Grid::build(&self.mesh, self.dims, self.margin))
    }

    /// Whether the grid has been built.
    pub fn grid_built(&self) -> bool {
        self.grid.get().is_some()
    }

    /// The faces sharing a vertex with face `f` (itself included).
    #[inline]
    pub fn ring(&self, f: usize) -> &[u32] {
        &self.ring[self.ring_start[f] as usize..self.ring_start[f + 1] as usize]
    }
}

impl Clone for Collider {
    fn clone(&self) -> Self {
        Collider {
            name: self.name.clone(),
            mesh: self.mesh.clone(),
            planes: self.planes.clone(),
            bbox: self.bbox,
            ring_start: self.ring_start.clone(),
            ring: self.ring.clone(),
            dims: self.dims,
            margin: self.margin,
            friction: self.friction,
            clearance: self.clearance,
            closed: self.closed,
            convex: self.convex.clone(),
            grid: OnceLock::new(),
        }
    }
}
