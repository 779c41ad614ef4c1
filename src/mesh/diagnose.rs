//! The inspect report: everything worth knowing about a mesh's shell, and its *shell state*.
//!
//! Shell states, from worst to best:
//! * `irregular`: no faces, or degenerate or duplicate faces, or an edge shared by three or more
//!   faces, or a vertex whose faces form more than one fan (non-manifold vertex);
//! * `regular`: a 2-manifold (with or without boundary) whose winding is inconsistent somewhere,
//!   or cannot be made consistent (non-orientable);
//! * `oriented`: a 2-manifold with one consistent winding per component, but open (boundary
//!   edges) or with a closed component facing inward;
//! * `closed`: oriented, watertight (every edge shared by exactly two faces) and every component
//!   facing outward (positive volume).
//!
//! Counting rules: an edge is an unordered vertex pair used by at least one non-degenerate face;
//! a boundary edge is used by exactly one face; boundary loops are the connected pieces of the
//! boundary-edge graph; the Euler characteristic is `V - E + F` over non-degenerate faces and the
//! vertices they use; components are connected through manifold edges (see `orient`).

use super::clean::{find_degenerate, find_duplicates};
use super::orient::{self, Plan};
use super::topology::{is_index_degenerate, Topology, BOUNDARY, NON_MANIFOLD};
use super::weld::{weld_map, WeldTolerance};
use super::TriMesh;
use crate::math::uf_root;
use serde::Serialize;
use std::fmt;

/// Shell state, from worst to best (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ShellState {
    /// Degenerate, duplicate or non-manifold pieces, or no faces.
    Irregular,
    /// Manifold, winding inconsistent.
    Regular,
    /// Manifold, consistently wound; open or partly inward.
    Oriented,
    /// Watertight, consistently wound, outward.
    Closed,
}

impl fmt::Display for ShellState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ShellState::Irregular => "irregular",
            ShellState::Regular => "regular",
            ShellState::Oriented => "oriented",
            ShellState::Closed => "closed",
        })
    }
}

/// Axis-aligned box, for the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoxReport {
    /// Smallest corner.
    pub min: [f64; 3],
    /// Largest corner.
    pub max: [f64; 3],
    /// Edge lengths.
    pub size: [f64; 3],
    /// Diagonal length.
    pub diagonal: f64,
}

/// One closed component's volume.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClosedVolume {
    /// Component number.
    pub component: usize,
    /// Its faces.
    pub faces: usize,
    /// Signed volume with the winding most of the component's faces have.
    pub volume: f64,
    /// Positive volume and consistent winding.
    pub outward: bool,
}

/// The inspect report. Every key is documented in the README.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis {
    /// Vertices in the mesh.
    pub vertices: usize,
    /// Vertices no face uses.
    pub unreferenced_vertices: usize,
    /// Faces (triangles).
    pub faces: usize,
    /// Bounding box (`null` when empty).
    pub bbox: Option<BoxReport>,
    /// Distinct edges.
    pub edges: usize,
    /// Components (faces connected through manifold edges).
    pub components: usize,
    /// Components that are closed.
    pub closed_components: usize,
    /// Components that are open.
    pub open_components: usize,
    /// Edges used by one face.
    pub boundary_edges: usize,
    /// Connected pieces of the boundary.
    pub boundary_loops: usize,
    /// Edges used by three or more faces.
    pub non_manifold_edges: usize,
    /// Vertices whose faces form more than one fan.
    pub non_manifold_vertices: usize,
    /// Faces with a repeated corner or (near) zero area.
    pub degenerate_faces: usize,
    /// Faces repeating an earlier face's vertices.
    pub duplicate_faces: usize,
    /// Vertices within the default weld tolerance of an earlier one (`null` when not computed).
    pub near_duplicate_vertices: Option<usize>,
    /// One winding across every manifold edge.
    pub winding_consistent: bool,
    /// Components that cannot be wound consistently.
    pub non_orientable_components: usize,
    /// Consistent, and every component faces outward by the orient rules.
    pub outward: bool,
    /// Every edge used by exactly two faces.
    pub watertight: bool,
    /// Per closed component.
    pub volumes: Vec<ClosedVolume>,
    /// Sum of the closed components' volumes.
    pub total_volume: f64,
    /// V - E + F.
    pub euler_characteristic: i64,
    /// Overall state.
    pub shell_state: ShellState,
}

/// Inspects `mesh` as it is.
pub fn diagnose(mesh: &TriMesh) -> Diagnosis {
    let topo = Topology::build(mesh);
    let plan = orient::plan(mesh, &topo, true);
    let mut d = diagnose_with(mesh, &topo, &plan, false, false);
    let dist = WeldTolerance::default().distance(mesh.diagonal());
    d.near_duplicate_vertices = Some(mesh.positions.len() - weld_map(&mesh.positions, dist).1);
    d
}

/// Inspects `mesh` with a topology and orientation plan already computed. With `applied`, the
/// winding facts are those after `orient::apply(mesh, plan)` (flips change no other fact).
/// `clean` tells that degenerate and duplicate faces were just dropped (their counts are 0).
pub fn diagnose_with(
    mesh: &TriMesh,
    topo: &Topology,
    plan: &Plan,
    applied: bool,
    clean: bool,
) -> Diagnosis {
    let usage = VertexUsage::of(mesh);
    let half = HalfEdges::of(mesh, topo);
    let edges = half.manifold / 2 + half.boundary + plan.non_manifold_edges;
    let (degenerate, duplicates) = if clean {
        (0, 0)
    } else {
        (find_degenerate(mesh).1, find_duplicates(mesh).1)
    };
    let non_orientable = plan.components.iter().filter(|c| !c.orientable).count();
    let (winding_consistent, outward) = winding(plan, applied, non_orientable);
    let volumes = closed_volumes(plan, applied);
    // From +0: an empty f64 sum is -0, written "-0.0" for a mesh with no closed volume.
    let total_volume = volumes.iter().map(|v| v.volume).fold(0.0, |a, v| a + v);
    let non_manifold_edges = plan.non_manifold_edges;
    let closed_components = plan.components.iter().filter(|c| c.closed).count();
    let mut d = Diagnosis {
        vertices: mesh.positions.len(),
        unreferenced_vertices: usage.unreferenced,
        faces: mesh.faces.len(),
        bbox: mesh.bbox().map(|b| BoxReport {
            min: b.min.coords.into(),
            max: b.max.coords.into(),
            size: b.size().into(),
            diagonal: b.diagonal(),
        }),
        edges,
        components: plan.components.len(),
        closed_components,
        open_components: plan.components.len() - closed_components,
        boundary_edges: half.boundary,
        boundary_loops: half.boundary_loops,
        non_manifold_edges,
        non_manifold_vertices: count_non_manifold_vertices(mesh, topo),
        degenerate_faces: degenerate,
        duplicate_faces: duplicates,
        near_duplicate_vertices: None,
        winding_consistent,
        non_orientable_components: non_orientable,
        outward,
        watertight: usage.faces_ok > 0 && half.boundary == 0 && non_manifold_edges == 0,
        volumes,
        total_volume,
        euler_characteristic: usage.used as i64 - edges as i64 + usage.faces_ok as i64,
        // Set below from the facts above.
        shell_state: ShellState::Irregular,
    };
    d.shell_state = shell_state(&d);
    d
}

/// How the faces use the vertices.
struct VertexUsage {
    /// Faces without a repeated corner.
    faces_ok: usize,
    /// Vertices those faces use.
    used: usize,
    /// Vertices no face uses.
    unreferenced: usize,
}

impl VertexUsage {
    /// Counts the usage in `mesh`.
    fn of(mesh: &TriMesh) -> VertexUsage {
        let nv = mesh.positions.len();
        let mut used = vec![false; nv];
        let mut faces_ok = 0usize;
        for f in &mesh.faces {
            if !is_index_degenerate(f) {
                faces_ok += 1;
                for &v in f {
                    used[v as usize] = true;
                }
            }
        }
        let mut any = vec![false; nv];
        for f in &mesh.faces {
            for &v in f {
                any[v as usize] = true;
            }
        }
        VertexUsage {
            faces_ok,
            used: used.iter().filter(|&&u| u).count(),
            unreferenced: any.iter().filter(|&&u| !u).count(),
        }
    }
}

/// The half-edges of the faces without a repeated corner, by kind, and the boundary's loops.
struct HalfEdges {
    /// Half-edges with one opposite half-edge.
    manifold: usize,
    /// Half-edges with none (boundary edges).
    boundary: usize,
    /// Connected pieces of the boundary-edge graph.
    boundary_loops: usize,
}

impl HalfEdges {
    /// Counts the half-edges of `mesh`; joins the boundary edges' ends by union-find.
    fn of(mesh: &TriMesh, topo: &Topology) -> HalfEdges {
        let mut manifold = 0usize;
        let mut boundary = 0usize;
        // Boundary loops: union-find over the boundary edges' ends.
        let mut parent: Vec<usize> = (0..mesh.positions.len()).collect();
        for (h, &o) in topo.opp.iter().enumerate() {
            if is_index_degenerate(&mesh.faces[h / 3]) {
                continue;
            }
            match o {
                BOUNDARY => {
                    boundary += 1;
                    let f = &mesh.faces[h / 3];
                    let a = uf_root(&mut parent, f[h % 3] as usize);
                    let b = uf_root(&mut parent, f[(h + 1) % 3] as usize);
                    parent[a.max(b)] = a.min(b);
                }
                NON_MANIFOLD => {}
                _ => manifold += 1,
            }
        }
        HalfEdges {
            manifold,
            boundary,
            boundary_loops: boundary_loops(mesh, topo, &mut parent),
        }
    }
}

/// The number of distinct union-find roots among the boundary edges' first ends.
fn boundary_loops(mesh: &TriMesh, topo: &Topology, parent: &mut [usize]) -> usize {
    let mut roots: Vec<usize> = Vec::new();
    for (h, &o) in topo.opp.iter().enumerate() {
        if o == BOUNDARY && !is_index_degenerate(&mesh.faces[h / 3]) {
            roots.push(uf_root(parent, mesh.faces[h / 3][h % 3] as usize));
        }
    }
    roots.sort_unstable();
    roots.dedup();
    roots.len()
}

/// Whether the winding is consistent, and whether it also faces outward by the plan, as the
/// mesh is or (with `applied`) after the plan.
fn winding(plan: &Plan, applied: bool, non_orientable: usize) -> (bool, bool) {
    if applied {
        (non_orientable == 0, non_orientable == 0)
    } else {
        let consistent =
            non_orientable == 0 && plan.components.iter().all(|c| c.inconsistent_faces == 0);
        (consistent, consistent && plan.is_noop())
    }
}

/// The closed components' volumes, as the mesh is or (with `applied`) after the plan.
fn closed_volumes(plan: &Plan, applied: bool) -> Vec<ClosedVolume> {
    plan.components
        .iter()
        .enumerate()
        .filter(|(_, c)| c.closed)
        .map(|(i, c)| {
            let flip = if applied && c.inverted { -1.0 } else { 1.0 };
            let v = flip * c.volume.unwrap_or(0.0);
            let positive = flip * c.volume_sign > 0.0;
            let outward = c.orientable && (applied || c.inconsistent_faces == 0) && positive;
            ClosedVolume {
                component: i,
                faces: c.faces,
                volume: v,
                outward,
            }
        })
        .collect()
}

/// The shell state of a diagnosis whose other facts are set (see the module docs).
fn shell_state(d: &Diagnosis) -> ShellState {
    if d.faces == 0
        || d.degenerate_faces > 0
        || d.duplicate_faces > 0
        || d.non_manifold_edges > 0
        || d.non_manifold_vertices > 0
    {
        ShellState::Irregular
    } else if !d.winding_consistent {
        ShellState::Regular
    } else if d.watertight && d.outward && d.volumes.iter().all(|v| v.outward) {
        ShellState::Closed
    } else {
        ShellState::Oriented
    }
}

/// Vertices whose incident faces, joined through manifold edges at the vertex, form more than
/// one fan: a walk around the vertex across manifold edges, both ways from its first face, must
/// meet every incident face. The walk leaves each face through the edge at the vertex it did not
/// enter by, so it does not depend on the winding.
fn count_non_manifold_vertices(mesh: &TriMesh, topo: &Topology) -> usize {
    // The two half-edges of face f that touch v: leaving v, and entering v.
    let at = |f: usize, v: u32| {
        let i = mesh.faces[f].iter().position(|&x| x == v).unwrap_or(0);
        (f * 3 + i, f * 3 + (i + 2) % 3)
    };
    let mut count = 0;
    for v in 0..mesh.positions.len() as u32 {
        let star = topo.vertex_faces(v);
        if star.len() < 2 {
            continue;
        }
        let f0 = star[0] as usize;
        let (first, second) = at(f0, v);
        let mut seen = 1;
        let mut closed = false;
        for start in [first, second] {
            if closed || seen > star.len() {
                break;
            }
            let mut h = start;
            loop {
                let o = topo.opp[h];
                if o >= NON_MANIFOLD {
                    break;
                }
                let g = o as usize / 3;
                if g == f0 {
                    closed = true;
                    break;
                }
                seen += 1;
                if seen > star.len() {
                    break;
                }
                let (s1, s2) = at(g, v);
                h = if s1 == o as usize { s2 } else { s1 };
            }
        }
        if seen != star.len() {
            count += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn cube_is_closed_sphere_of_euler_two() {
        let d = diagnose(&generate::cube(2.0));
        assert_eq!(d.shell_state, ShellState::Closed);
        assert_eq!((d.vertices, d.edges, d.faces), (8, 18, 12));
        assert_eq!(d.euler_characteristic, 2);
        assert!((d.total_volume - 8.0).abs() < 1e-12);
        assert!(d.watertight && d.outward && d.winding_consistent);
    }

    #[test]
    fn open_box_has_one_boundary_loop() {
        let mut m = generate::cube(1.0);
        m.faces.truncate(10);
        let d = diagnose(&m);
        assert_eq!((d.boundary_edges, d.boundary_loops), (4, 1));
        assert_eq!(d.euler_characteristic, 1);
        assert_eq!(d.shell_state, ShellState::Oriented);
    }

    #[test]
    fn a_tube_open_at_both_ends_has_two_boundary_loops() {
        // The unit cube without its top and bottom (two faces each): a band, two loops of 4 edges.
        let mut m = generate::cube(1.0);
        let z = |f: &[u32; 3], c: f64| f.iter().all(|&v| m.positions[v as usize].z == c);
        let keep: Vec<[u32; 3]> = (m.faces.iter())
            .filter(|f| !z(f, 0.5) && !z(f, -0.5))
            .copied()
            .collect();
        m.faces = keep;
        let d = diagnose(&m);
        assert_eq!((d.boundary_edges, d.boundary_loops), (8, 2));
        assert_eq!(d.euler_characteristic, 0);
    }

    #[test]
    fn two_cubes_touching_at_a_vertex() {
        let mut m = generate::cube(1.0);
        let n = m.positions.len() as u32;
        // A second cube sharing only vertex 7 with the first: a non-manifold vertex.
        let c2 = generate::cube(1.0);
        let off = m.positions[7] - c2.positions[0];
        m.positions
            .extend(c2.positions.iter().skip(1).map(|p| p + off));
        for f in &c2.faces {
            m.faces.push(f.map(|v| if v == 0 { 7 } else { v + n - 1 }));
        }
        let d = diagnose(&m);
        assert_eq!(d.non_manifold_vertices, 1);
        assert_eq!(d.components, 2);
        assert_eq!(d.shell_state, ShellState::Irregular);
    }
}
