//! The preparation pipeline behind `drapekit convert`: transform, weld, clean, orient, and the
//! diagnosis of the result. Each step can be turned off and each reports what it did.
//!
//! Order: units and up axis first (an absolute weld tolerance is given in input units and is
//! scaled with the mesh), then weld, drop degenerate faces (welding can make some), drop
//! duplicate faces, split non-manifold vertices (`split`: a surface pinched at a point, as
//! welding or an STL's positions can leave it), drop unreferenced vertices, orient.

use super::diagnose::{diagnose_with, Diagnosis};
use super::orient::{self, OrientReport};
use super::topology::Topology;
use super::transform::{change_up, scale, Units, Up};
use super::weld::{weld, WeldReport, WeldTolerance};
use super::{clean, TriMesh};
use serde::Serialize;

/// What to do to a mesh. `Default` does everything with default tolerances and no transform.
#[derive(Debug, Clone, PartialEq)]
pub struct PrepareOptions {
    /// Weld tolerance (default `1e-6rel`); `None` skips welding.
    pub weld: Option<WeldTolerance>,
    /// Drop degenerate faces (default true).
    pub drop_degenerate: bool,
    /// Drop duplicate faces (default true).
    pub drop_duplicates: bool,
    /// Split each non-manifold vertex into one vertex per fan (default true; `split`).
    pub split_vertices: bool,
    /// Make the winding consistent and outward (default true).
    pub orient: bool,
    /// Input and output units (default: none, no scaling).
    pub units: Option<(Units, Units)>,
    /// Input and output up axis (default: none, no rotation).
    pub up: Option<(Up, Up)>,
}

impl Default for PrepareOptions {
    fn default() -> Self {
        PrepareOptions {
            weld: Some(WeldTolerance::default()),
            drop_degenerate: true,
            drop_duplicates: true,
            split_vertices: true,
            orient: true,
            units: None,
            up: None,
        }
    }
}

/// What preparing did, and the state of the result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PrepareReport {
    /// Vertices before.
    pub input_vertices: usize,
    /// Faces (triangles) before.
    pub input_faces: usize,
    /// Scale factor applied (unit change), 1 when none.
    pub scale: f64,
    /// Up-axis change applied, as `[from, to]`.
    pub up: Option<[Up; 2]>,
    /// Welding, when done.
    pub weld: Option<WeldReport>,
    /// Vertices merged by welding.
    pub welded_vertices: usize,
    /// Degenerate faces dropped.
    pub degenerate_faces: usize,
    /// Duplicate faces dropped.
    pub duplicate_faces: usize,
    /// Vertices added by splitting non-manifold vertices.
    pub split_vertices: usize,
    /// Unreferenced vertices dropped.
    pub unreferenced_vertices: usize,
    /// Orientation, when done.
    pub orient: Option<OrientReport>,
    /// Faces whose winding was reversed.
    pub flipped_faces: usize,
    /// Vertices after.
    pub output_vertices: usize,
    /// Faces after.
    pub output_faces: usize,
    /// The diagnosis of the result.
    pub after: Diagnosis,
}

/// Prepares `mesh` in place.
pub fn prepare(mesh: &mut TriMesh, opts: &PrepareOptions) -> PrepareReport {
    let input_vertices = mesh.positions.len();
    let input_faces = mesh.faces.len();
    let factor = transform(mesh, opts);
    let weld_report = opts.weld.map(|t| {
        let t = match t {
            WeldTolerance::Absolute(d) => WeldTolerance::Absolute(d * factor),
            rel => rel,
        };
        weld(mesh, t)
    });
    let degenerate_faces = if opts.drop_degenerate {
        clean::drop_degenerate(mesh)
    } else {
        0
    };
    let duplicate_faces = if opts.drop_duplicates {
        clean::drop_duplicates(mesh)
    } else {
        0
    };
    let split_vertices = if opts.split_vertices {
        super::split::split_non_manifold_vertices(mesh)
    } else {
        0
    };
    let unreferenced_vertices = mesh.drop_unreferenced_vertices();
    let (after, orient_report) = orient_and_diagnose(mesh, opts);
    PrepareReport {
        input_vertices,
        input_faces,
        scale: factor,
        up: opts.up.map(|(a, b)| [a, b]),
        welded_vertices: weld_report.as_ref().map_or(0, |w| w.welded),
        weld: weld_report,
        degenerate_faces,
        duplicate_faces,
        split_vertices,
        unreferenced_vertices,
        flipped_faces: orient_report.as_ref().map_or(0, |o| o.flipped_faces),
        orient: orient_report,
        output_vertices: mesh.positions.len(),
        output_faces: mesh.faces.len(),
        after,
    }
}

/// Scales and turns `mesh` as `opts` ask; the scale factor (1 without units).
fn transform(mesh: &mut TriMesh, opts: &PrepareOptions) -> f64 {
    let mut factor = 1.0;
    if let Some((from, to)) = opts.units {
        factor = Units::factor(from, to);
        scale(mesh, factor);
    }
    if let Some((from, to)) = opts.up {
        change_up(mesh, from, to);
    }
    factor
}

/// The diagnosis after (of the mesh as it will be oriented, when `opts.orient`), then the
/// orientation applied, with its report.
fn orient_and_diagnose(
    mesh: &mut TriMesh,
    opts: &PrepareOptions,
) -> (Diagnosis, Option<OrientReport>) {
    let topo = Topology::build(mesh);
    let plan = orient::plan(mesh, &topo, true);
    let after = diagnose_with(
        mesh,
        &topo,
        &plan,
        opts.orient,
        opts.drop_degenerate && opts.drop_duplicates,
    );
    let orient_report = if opts.orient {
        orient::apply(mesh, &plan);
        Some(plan.report())
    } else {
        None
    };
    (after, orient_report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::mesh::diagnose::{diagnose, ShellState};
    use crate::mesh::generate;

    /// Splits every face's corners apart (a soup), flips some faces, and checks prepare restores
    /// the original mesh exactly.
    #[test]
    fn soup_with_flips_comes_back_as_the_original() {
        let orig = generate::icosphere(2);
        let mut soup = TriMesh::default();
        for (f, face) in orig.faces.iter().enumerate() {
            let base = soup.positions.len() as u32;
            soup.positions
                .extend(face.iter().map(|&v| orig.positions[v as usize]));
            soup.faces.push(if f % 3 == 0 {
                [base, base + 2, base + 1]
            } else {
                [base, base + 1, base + 2]
            });
        }
        let r = prepare(&mut soup, &PrepareOptions::default());
        assert_eq!(r.after.shell_state, ShellState::Closed);
        assert_eq!(r.output_vertices, orig.positions.len());
        assert_eq!(r.flipped_faces, orig.faces.len().div_ceil(3));
        let d = diagnose(&soup);
        assert!(d.winding_consistent && d.outward && d.watertight);
        assert!((soup.signed_volume() - orig.signed_volume()).abs() < 1e-12);
    }

    /// A soup of an inside-out icosphere, at any scale from 1e-300 to 1e90, is welded, turned
    /// outward and found closed, as at 1: at 1e-300 the weld distance (from a diagonal whose
    /// square underflowed) was zero and the volume's sign lost, so the soup stayed open, or a
    /// shell only "oriented".
    #[test]
    fn a_soup_of_any_size_is_welded_turned_outward_and_closed() {
        let orig = generate::icosphere(2);
        for scale in [1e-300, 1e-200, 1e-120, 1.0, 1e90] {
            let mut soup = TriMesh::default();
            for face in &orig.faces {
                let base = soup.positions.len() as u32;
                // Each corner nudged by a millionth of the scale (as an export rounds), inside
                // out.
                soup.positions.extend(face.iter().map(|&v| {
                    (orig.positions[v as usize] * scale)
                        + Vec3::repeat(scale * 1e-9 * (base % 7) as f64)
                }));
                soup.faces.push([base, base + 2, base + 1]);
            }
            let r = prepare(&mut soup, &PrepareOptions::default());
            assert_eq!(r.after.shell_state, ShellState::Closed, "{scale}");
            assert_eq!(r.output_vertices, orig.positions.len(), "{scale}");
            assert_eq!(r.flipped_faces, orig.faces.len(), "{scale}");
        }
    }
}
