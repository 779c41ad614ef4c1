//! Edge adjacency of a triangle mesh, built in O(n) without hashing.
//!
//! Half-edge `3f + i` runs from `faces[f][i]` to `faces[f][(i + 1) % 3]`. The half-edges leaving
//! each vertex are listed with their end vertex (a compressed table built by counting sort); the
//! other half-edges on edge `{a, b}` are those leaving `b` towards `a` and those leaving `a`
//! towards `b`, found by scanning two short contiguous lists. The result, `opp[h]`, is the one other
//! half-edge on that edge when exactly two faces share it (a manifold edge), [`BOUNDARY`] when
//! the face is alone on it, and [`NON_MANIFOLD`] when three or more faces share it. Faces with a
//! repeated corner are left out (all their half-edges are [`BOUNDARY`]): clean them first.
//!
//! The half-edge pass runs in parallel over fixed chunks of faces; the result does not depend on
//! the number of threads.

use super::TriMesh;
use rayon::prelude::*;

/// `opp` value of a half-edge no other face shares.
pub const BOUNDARY: u32 = u32::MAX;
/// `opp` value of a half-edge on an edge shared by three or more faces.
pub const NON_MANIFOLD: u32 = u32::MAX - 1;

/// Faces per parallel work unit.
const CHUNK_FACES: usize = 4096;

/// Vertex-to-face incidence and half-edge opposites.
#[derive(Debug, Clone)]
pub struct Topology {
    /// `vf_start[v]..vf_start[v + 1]` indexes `vf_faces` for the faces around vertex `v`.
    pub vf_start: Vec<u32>,
    /// Faces around each vertex, in face order.
    pub vf_faces: Vec<u32>,
    /// The opposite half-edge of each half-edge, or [`BOUNDARY`] / [`NON_MANIFOLD`].
    pub opp: Vec<u32>,
}

/// Whether face `[a, b, c]` repeats a corner.
#[inline]
pub fn is_index_degenerate(f: &[u32; 3]) -> bool {
    f[0] == f[1] || f[1] == f[2] || f[2] == f[0]
}

impl Topology {
    /// Builds the adjacency of `mesh`.
    pub fn build(mesh: &TriMesh) -> Topology {
        let nv = mesh.positions.len();
        let faces = &mesh.faces;
        let mut count = vec![0u32; nv + 1];
        for f in faces {
            if !is_index_degenerate(f) {
                for &v in f {
                    count[v as usize + 1] += 1;
                }
            }
        }
        for v in 0..nv {
            count[v + 1] += count[v];
        }
        // Each vertex has as many outgoing half-edges as incident faces: one table serves both.
        let vf_start = count;
        let mut fill = vf_start.clone();
        let mut vf_faces = vec![0u32; vf_start[nv] as usize];
        // Outgoing half-edges of each vertex: (end vertex, half-edge).
        let mut out = vec![(0u32, 0u32); vf_start[nv] as usize];
        for (fi, f) in faces.iter().enumerate() {
            if !is_index_degenerate(f) {
                for i in 0..3 {
                    let slot = &mut fill[f[i] as usize];
                    vf_faces[*slot as usize] = fi as u32;
                    out[*slot as usize] = (f[(i + 1) % 3], (fi * 3 + i) as u32);
                    *slot += 1;
                }
            }
        }
        let mut opp = vec![BOUNDARY; faces.len() * 3];
        let outgoing =
            |v: u32| &out[vf_start[v as usize] as usize..vf_start[v as usize + 1] as usize];
        opp.par_chunks_mut(CHUNK_FACES * 3)
            .enumerate()
            .for_each(|(chunk, slots)| {
                let h0 = chunk * CHUNK_FACES * 3;
                for (k, slot) in slots.iter_mut().enumerate() {
                    let h = h0 + k;
                    let face = &faces[h / 3];
                    if is_index_degenerate(face) {
                        continue;
                    }
                    let a = face[h % 3];
                    let b = face[(h % 3 + 1) % 3];
                    let mut found = BOUNDARY;
                    let mut n = 0;
                    for &(end, g) in outgoing(b) {
                        if end == a {
                            found = g;
                            n += 1;
                        }
                    }
                    for &(end, g) in outgoing(a) {
                        if end == b && g as usize != h {
                            found = g;
                            n += 1;
                        }
                    }
                    *slot = match n {
                        0 => BOUNDARY,
                        1 => found,
                        _ => NON_MANIFOLD,
                    };
                }
            });
        Topology {
            vf_start,
            vf_faces,
            opp,
        }
    }

    /// Faces around vertex `v`.
    #[inline]
    pub fn vertex_faces(&self, v: u32) -> &[u32] {
        &self.vf_faces[self.vf_start[v as usize] as usize..self.vf_start[v as usize + 1] as usize]
    }

    /// Whether half-edge `h` has exactly one opposite.
    #[inline]
    pub fn is_manifold(&self, h: usize) -> bool {
        self.opp[h] < NON_MANIFOLD
    }

    /// Whether the two faces of the manifold edge of half-edge `h` run it the same way (the
    /// winding is inconsistent across it), given the faces of `mesh`.
    #[inline]
    pub fn same_direction(&self, mesh: &TriMesh, h: usize) -> bool {
        let g = self.opp[h] as usize;
        mesh.faces[h / 3][h % 3] == mesh.faces[g / 3][g % 3]
    }

    /// Connected components of faces through manifold edges: a label per face (degenerate faces
    /// get their own) and the number of components, numbered by their lowest face.
    pub fn components(&self, mesh: &TriMesh) -> (Vec<u32>, usize) {
        let nf = mesh.faces.len();
        let mut label = vec![u32::MAX; nf];
        let mut count = 0u32;
        let mut stack = Vec::new();
        for seed in 0..nf {
            if label[seed] != u32::MAX {
                continue;
            }
            label[seed] = count;
            stack.push(seed);
            while let Some(f) = stack.pop() {
                for i in 0..3 {
                    let o = self.opp[f * 3 + i];
                    if o < NON_MANIFOLD {
                        let g = o as usize / 3;
                        if label[g] == u32::MAX {
                            label[g] = count;
                            stack.push(g);
                        }
                    }
                }
            }
            count += 1;
        }
        (label, count as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn closed_cube_has_all_edges_manifold_and_consistent() {
        let cube = generate::cube(1.0);
        let t = Topology::build(&cube);
        for h in 0..t.opp.len() {
            assert!(t.is_manifold(h));
            assert_eq!(t.opp[t.opp[h] as usize] as usize, h);
            assert!(!t.same_direction(&cube, h));
        }
        assert_eq!(t.components(&cube).1, 1);
    }

    #[test]
    fn flipped_face_is_seen_and_three_faces_are_non_manifold() {
        let mut cube = generate::cube(1.0);
        cube.flip_face(0);
        let t = Topology::build(&cube);
        let inconsistent = (0..3).filter(|&i| t.same_direction(&cube, i)).count();
        assert_eq!(inconsistent, 3);
        // A fin on edge (0, 2) of face 0: three faces on one edge.
        cube.positions.push(crate::math::Point3::new(5.0, 5.0, 5.0));
        cube.faces.push([0, 2, 8]);
        let t = Topology::build(&cube);
        assert_eq!(t.opp.iter().filter(|&&o| o == NON_MANIFOLD).count(), 3);
    }
}
