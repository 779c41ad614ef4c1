//! Non-manifold vertices split into one vertex per fan.
//!
//! A vertex is non-manifold when its faces, joined through the manifold edges at it, form more
//! than one *fan* (`diagnose`): two closed surfaces touching at a point, or one surface pinched
//! where two of its vertices landed on the same coordinates. The second is common in STL
//! exports, which store corners by position only: GarmentCode's `mean_all.stl` has 23,751
//! distinct positions where its `mean_all.obj` has 23,752 vertices, two of which round to one
//! `f32` triple, so the STL body reads as one closed surface pinched at a point (Euler
//! characteristic 1 instead of 2), and any tool that walks round a vertex (a vertex normal, an
//! inside test) is misled there.
//!
//! The split: for each vertex `v`, its faces are grouped by a union-find over the edges at `v`
//! that exactly two faces share; the fan holding `v`'s first face (in face order) keeps `v`,
//! each other fan gets a new vertex at the same position, appended in order of `v` then of the
//! fan's first face. Nothing moves, no face is added or dropped, and a manifold mesh is left
//! exactly as it was. A vertex on an edge shared by three or more faces is not split (no choice of
//! pairs would be canonical, and splitting its fans would cut that edge's faces apart: two
//! tetrahedra sharing a face would lose the face); faces with a repeated corner are left out
//! (clean them first).
//!
//! ```
//! use drapekit::mesh::{split::split_non_manifold_vertices, TriMesh};
//! use drapekit::math::Point3;
//! // Two triangles touching at vertex 0 only: a bow tie, one vertex too few.
//! let p = |x: f64, y: f64| Point3::new(x, y, 0.0);
//! let mut m = TriMesh {
//!     positions: vec![p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(-1.0, 0.0), p(-1.0, -1.0)],
//!     faces: vec![[0, 1, 2], [0, 3, 4]],
//! };
//! assert_eq!(split_non_manifold_vertices(&mut m), 1);
//! assert_eq!(m.faces, vec![[0, 1, 2], [5, 3, 4]]);
//! assert_eq!(m.positions[5], m.positions[0]);
//! ```

use super::topology::{is_index_degenerate, Topology, BOUNDARY, NON_MANIFOLD};
use super::TriMesh;
use crate::math::uf_root as root;

/// The fans of vertex `v`: for each face of its star (`topo.vertex_faces(v)`, in order), the
/// index of its fan, fans numbered from 0 in order of their first face; one fan when an edge
/// at `v` has three or more faces (splitting there would cut that edge's faces apart).
fn fans(mesh: &TriMesh, topo: &Topology, v: u32) -> Vec<usize> {
    let star = topo.vertex_faces(v);
    let mut parent: Vec<usize> = (0..star.len()).collect();
    for (k, &f) in star.iter().enumerate() {
        let f = f as usize;
        let i = mesh.faces[f].iter().position(|&x| x == v).unwrap_or(0);
        // The two half-edges of f at v: leaving v, and entering it.
        for h in [3 * f + i, 3 * f + (i + 2) % 3] {
            let o = topo.opp[h];
            if o == NON_MANIFOLD {
                return vec![0; star.len()];
            }
            if o == BOUNDARY {
                continue;
            }
            if let Ok(j) = star.binary_search(&(o / 3)) {
                let (a, b) = (root(&mut parent, k), root(&mut parent, j));
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut number = vec![usize::MAX; star.len()];
    let mut next = 0;
    (0..star.len())
        .map(|k| {
            let r = root(&mut parent, k);
            if number[r] == usize::MAX {
                number[r] = next;
                next += 1;
            }
            number[r]
        })
        .collect()
}

/// Splits every non-manifold vertex of `mesh` into one vertex per fan (module docs); returns
/// the number of vertices added.
pub fn split_non_manifold_vertices(mesh: &mut TriMesh) -> usize {
    let topo = Topology::build(mesh);
    let mut added = 0;
    for v in 0..mesh.positions.len() as u32 {
        let fan = fans(mesh, &topo, v);
        let count = fan.iter().max().map_or(0, |m| m + 1);
        if count < 2 {
            continue;
        }
        let first_new = mesh.positions.len() as u32;
        for _ in 1..count {
            mesh.positions.push(mesh.positions[v as usize]);
        }
        for (&f, &k) in topo.vertex_faces(v).iter().zip(&fan) {
            let face = &mut mesh.faces[f as usize];
            if k > 0 && !is_index_degenerate(face) {
                for c in face.iter_mut().filter(|c| **c == v) {
                    *c = first_new + k as u32 - 1;
                }
            }
        }
        added += count - 1;
    }
    added
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::diagnose::{diagnose, ShellState};
    use crate::mesh::generate;

    /// Two unit icospheres, the second moved so that its vertex `b` lands on the first's
    /// vertex `a`, and welded there: one surface pinched at a point.
    fn pinched() -> (TriMesh, TriMesh) {
        let one = generate::icosphere(1);
        let n = one.positions.len() as u32;
        let (a, b) = (0u32, 3u32);
        let shift = one.positions[a as usize] - one.positions[b as usize];
        let mut two = one.clone();
        two.positions
            .extend(one.positions.iter().map(|p| p + shift));
        two.faces.extend(one.faces.iter().map(|f| f.map(|v| v + n)));
        let apart = two.clone();
        for f in &mut two.faces {
            for c in f.iter_mut().filter(|c| **c == b + n) {
                *c = a;
            }
        }
        (two, apart)
    }

    #[test]
    fn a_pinched_pair_of_spheres_becomes_two_closed_spheres() {
        let (mut m, apart) = pinched();
        let before = diagnose(&m);
        assert_eq!(before.non_manifold_vertices, 1);
        assert_eq!(before.shell_state, ShellState::Irregular);
        assert_eq!(split_non_manifold_vertices(&mut m), 1);
        let after = diagnose(&m);
        assert_eq!(after.non_manifold_vertices, 0);
        assert_eq!(after.shell_state, ShellState::Closed);
        // The faces are the unwelded pair's, the pinched vertex's new copy standing for the
        // second sphere's vertex b.
        let new = m.positions.len() as u32 - 1;
        let b = apart.positions.len() as u32 / 2 + 3;
        for (f, g) in m.faces.iter().zip(&apart.faces) {
            assert_eq!(f.map(|v| if v == new { b } else { v }), *g);
        }
        assert_eq!(m.positions[new as usize], m.positions[0]);
    }

    #[test]
    fn vertices_on_an_edge_of_three_faces_are_not_split() {
        // Two tetrahedra on one triangle (0, 1, 2): its three edges have three faces each.
        let p = |x: f64, y: f64, z: f64| crate::math::Point3::new(x, y, z);
        let mut m = TriMesh {
            positions: vec![
                p(0.0, 0.0, 0.0),
                p(1.0, 0.0, 0.0),
                p(0.0, 1.0, 0.0),
                p(0.2, 0.2, 1.0),
                p(0.2, 0.2, -1.0),
            ],
            faces: vec![
                [0, 2, 1],
                [0, 1, 3],
                [1, 2, 3],
                [2, 0, 3],
                [0, 1, 4],
                [1, 2, 4],
                [2, 0, 4],
            ],
        };
        let before = m.clone();
        assert_eq!(diagnose(&m).non_manifold_edges, 3);
        assert_eq!(split_non_manifold_vertices(&mut m), 0);
        assert_eq!(m, before);
    }

    #[test]
    fn a_manifold_mesh_and_an_open_one_are_left_alone() {
        let mut open = generate::icosphere(2);
        open.faces.drain(0..5);
        for mut m in [generate::icosphere(2), open] {
            let before = m.clone();
            assert_eq!(split_non_manifold_vertices(&mut m), 0);
            assert_eq!(m, before);
        }
    }
}
