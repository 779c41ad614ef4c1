//! Orientation: one winding across every manifold edge, then every component facing outward.
//!
//! 1. **Consistency.** Faces are walked breadth-first through manifold edges (see `topology`)
//!    from the lowest-numbered face of each component; a neighbour that runs the shared edge the
//!    same way is flipped. The component then takes the winding most of its faces had (ties: the
//!    lowest face's), so the fewest faces change. A component where the walk meets itself with
//!    the opposite parity (a Moebius band) is *non-orientable*: it is reported, not forced.
//!    Edges shared by three or more faces are never walked across: they are reported.
//! 2. **Outward, closed components.** A component is closed when each of its edges is used by
//!    exactly two of its faces in opposite directions. Its signed volume
//!    `V = sum (a - o) . ((b - o) x (c - o)) / 6` is positive when it faces outward; a
//!    component with negative volume is flipped whole. A flat closed component
//!    (`|V| <= FLAT_VOLUME_REL * diagonal^3`) keeps its winding.
//! 3. **Outward, open components** (a garment, a seat shell, a body with a hole). The rule is
//!    the generalized winding number `w(x) = sum over faces of solid angle / 4 pi` (Jacobson et
//!    al. 2013), evaluated at the centroids of up to [`WINDING_SAMPLES`] faces of the component
//!    against the component's other faces, averaged with area weights. For a closed outward
//!    surface `w` is +1/2 on the surface; for an open one it stays positive when the normals
//!    point to the convex side, away from the space the surface wraps. A component with a
//!    negative mean is flipped whole; a mean of zero (a flat sheet, a lone triangle) keeps its
//!    majority winding.
//!
//! [`plan`] computes all of this without touching the mesh; [`apply`] flips the faces. Running
//! [`orient`] twice changes nothing the second time.

use super::topology::{is_index_degenerate, Topology, NON_MANIFOLD};
use super::TriMesh;
use crate::math::{tol, Point3};
use rayon::prelude::*;
use serde::Serialize;

/// How many faces of an open component sample its winding number.
pub const WINDING_SAMPLES: usize = 64;

/// What the plan found about one component.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ComponentInfo {
    /// Faces in the component.
    pub faces: usize,
    /// Lowest face index.
    pub first_face: usize,
    /// Every edge used by exactly two of its faces in opposite directions (once consistent).
    pub closed: bool,
    /// One winding exists across all its manifold edges.
    pub orientable: bool,
    /// Faces that disagree with the winding most of the component's faces have.
    pub inconsistent_faces: usize,
    /// Signed volume with the majority winding (closed components only).
    pub volume: Option<f64>,
    /// The sign of `volume` (-1, 0 or 1), found at a scale where it does not underflow: the
    /// volume of a 1e-300 m shell is zero in `f64`, its sign is not.
    #[serde(skip)]
    pub volume_sign: f64,
    /// Mean generalized winding number with the majority winding (open components only).
    pub winding: Option<f64>,
    /// The whole component must flip to face outward.
    pub inverted: bool,
    /// No side could be preferred (flat); the majority winding was kept.
    pub undecided: bool,
}

/// The orientation plan: which faces to flip, and why.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Per face: flip it.
    pub flip: Vec<bool>,
    /// Per face: its component (`u32::MAX` for faces with a repeated corner).
    pub label: Vec<u32>,
    /// Per component.
    pub components: Vec<ComponentInfo>,
    /// Edges shared by three or more faces.
    pub non_manifold_edges: usize,
}

/// What orienting did, as the convert report lists it.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct OrientReport {
    /// Faces whose winding was reversed.
    pub flipped_faces: usize,
    /// Faces that disagreed with their component's majority winding.
    pub consistency_flips: usize,
    /// Components flipped whole to face outward.
    pub inverted_components: usize,
    /// Components.
    pub components: usize,
    /// Closed components.
    pub closed_components: usize,
    /// Open components.
    pub open_components: usize,
    /// Components that cannot be wound consistently.
    pub non_orientable_components: usize,
    /// Components with no preferred side (kept as they were).
    pub undecided_components: usize,
    /// Edges shared by three or more faces (left alone).
    pub non_manifold_edges: usize,
}

impl Plan {
    /// Whether the mesh as it is already has the planned winding.
    pub fn is_noop(&self) -> bool {
        !self.flip.iter().any(|&f| f)
    }

    /// The summary of this plan.
    pub fn report(&self) -> OrientReport {
        let c = &self.components;
        OrientReport {
            flipped_faces: self.flip.iter().filter(|&&f| f).count(),
            consistency_flips: c.iter().map(|k| k.inconsistent_faces).sum(),
            inverted_components: c.iter().filter(|k| k.inverted).count(),
            components: c.len(),
            closed_components: c.iter().filter(|k| k.closed).count(),
            open_components: c.iter().filter(|k| !k.closed).count(),
            non_orientable_components: c.iter().filter(|k| !k.orientable).count(),
            undecided_components: c.iter().filter(|k| k.undecided).count(),
            non_manifold_edges: self.non_manifold_edges,
        }
    }
}

/// Plans the orientation of `mesh` (see the module docs). With `outward` false only
/// consistency is planned.
pub fn plan(mesh: &TriMesh, topo: &Topology, outward: bool) -> Plan {
    let nf = mesh.faces.len();
    let mut w = Walk {
        flip: vec![false; nf],
        label: vec![u32::MAX; nf],
        comps: Vec::new(),
        members: Vec::new(),
        queue: std::collections::VecDeque::new(),
    };
    for seed in 0..nf {
        if w.label[seed] != u32::MAX || is_index_degenerate(&mesh.faces[seed]) {
            continue;
        }
        w.component(mesh, topo, seed);
    }
    let non_manifold_edges = w.closedness(mesh, topo);
    w.face_outward(mesh, outward);
    Plan {
        flip: w.flip,
        label: w.label,
        components: w.comps,
        non_manifold_edges,
    }
}

/// The plan being made: the flips and labels so far, the components found and their faces.
struct Walk {
    flip: Vec<bool>,
    label: Vec<u32>,
    comps: Vec<ComponentInfo>,
    /// Per component, its faces in the order the walk met them.
    members: Vec<Vec<u32>>,
    /// The faces met but not yet walked from.
    queue: std::collections::VecDeque<usize>,
}

impl Walk {
    /// Walks the component of face `seed` breadth-first through manifold edges, flipping each
    /// face that runs a shared edge the same way as its neighbour, then keeps the winding most
    /// of its faces have (ties: the seed's).
    fn component(&mut self, mesh: &TriMesh, topo: &Topology, seed: usize) {
        let c = self.comps.len() as u32;
        let mut list = vec![seed as u32];
        let mut orientable = true;
        self.label[seed] = c;
        self.queue.push_back(seed);
        while let Some(f) = self.queue.pop_front() {
            for i in 0..3 {
                let h = f * 3 + i;
                if !topo.is_manifold(h) {
                    continue;
                }
                let g = topo.opp[h] as usize / 3;
                let want = self.flip[f] ^ topo.same_direction(mesh, h);
                if self.label[g] == u32::MAX {
                    self.label[g] = c;
                    self.flip[g] = want;
                    list.push(g as u32);
                    self.queue.push_back(g);
                } else if self.flip[g] != want {
                    orientable = false;
                }
            }
        }
        // Follow the winding most of the component's faces have (ties: the lowest face's).
        let mut inconsistent = list.iter().filter(|&&f| self.flip[f as usize]).count();
        if 2 * inconsistent > list.len() {
            for &f in &list {
                self.flip[f as usize] = !self.flip[f as usize];
            }
            inconsistent = list.len() - inconsistent;
        }
        self.comps.push(ComponentInfo {
            faces: list.len(),
            first_face: seed,
            closed: true,
            orientable,
            inconsistent_faces: inconsistent,
            volume: None,
            volume_sign: 0.0,
            winding: None,
            inverted: false,
            undecided: false,
        });
        self.members.push(list);
    }

    /// Marks the components that are open (a boundary half-edge, or a non-manifold edge not
    /// used by exactly two of their faces) or non-orientable (a non-manifold edge used twice
    /// the same way); returns the number of distinct non-manifold edges.
    fn closedness(&mut self, mesh: &TriMesh, topo: &Topology) -> usize {
        let mut nm: Vec<(u32, u32, u32, i8)> = Vec::new();
        let mut nm_edges: Vec<(u32, u32)> = Vec::new();
        for f in 0..mesh.faces.len() {
            let c = self.label[f];
            if c == u32::MAX {
                continue;
            }
            for i in 0..3 {
                let h = f * 3 + i;
                match topo.opp[h] {
                    o if o < NON_MANIFOLD => {}
                    NON_MANIFOLD => {
                        let mut a = mesh.faces[f][i];
                        let mut b = mesh.faces[f][(i + 1) % 3];
                        if self.flip[f] {
                            std::mem::swap(&mut a, &mut b);
                        }
                        let dir = if a < b { 1 } else { -1 };
                        nm.push((c, a.min(b), a.max(b), dir));
                        nm_edges.push((a.min(b), a.max(b)));
                    }
                    _ => self.comps[c as usize].closed = false,
                }
            }
        }
        nm.sort_unstable();
        for group in nm.chunk_by(|x, y| (x.0, x.1, x.2) == (y.0, y.1, y.2)) {
            let c = group[0].0 as usize;
            let sum: i32 = group.iter().map(|g| i32::from(g.3)).sum();
            if group.len() != 2 {
                self.comps[c].closed = false;
            } else if sum != 0 {
                self.comps[c].orientable = false;
            }
        }
        nm_edges.sort_unstable();
        nm_edges.dedup();
        nm_edges.len()
    }

    /// Measures each component (signed volume when closed, mean winding number when open)
    /// and, with `outward`, decides whether an orientable one is flipped whole or undecided.
    fn face_outward(&mut self, mesh: &TriMesh, outward: bool) {
        let (scaled, s) = well_scaled(mesh);
        let mesh = scaled.as_ref().unwrap_or(mesh);
        let bbox = mesh.bbox();
        let d = bbox.map_or(0.0, |b| b.diagonal());
        let origin = bbox.map_or(Point3::origin(), |b| b.center());
        for (c, info) in self.comps.iter_mut().enumerate() {
            let list = &self.members[c];
            if info.closed {
                let v = signed_volume(mesh, list, &self.flip, origin);
                info.volume = Some(v / (s * s * s));
                info.volume_sign = if v == 0.0 { 0.0 } else { v.signum() };
                if outward && info.orientable {
                    decide(info, v, tol::FLAT_VOLUME_REL * d * d * d);
                }
            } else {
                let w = mean_winding(mesh, list, &self.flip);
                info.winding = Some(w);
                if outward && info.orientable {
                    decide(info, w, tol::WINDING_TIE);
                }
            }
            if info.inverted {
                for &f in list {
                    self.flip[f as usize] = !self.flip[f as usize];
                }
            }
        }
    }
}

/// `mesh` scaled by the power of two `s` that brings its extent to about 1 when that extent is
/// outside 1e-100 to 1e100 (`None`, `s` = 1, for any other mesh): volumes of a 1e-300 m mesh
/// underflow, and every closed one was undecided. A power of two scales exactly, so the signs
/// and windings are the mesh's own.
fn well_scaled(mesh: &TriMesh) -> (Option<TriMesh>, f64) {
    let extent = mesh.bbox().map_or(0.0, |b| b.size().amax());
    let s = crate::mesh::clean::unit_scale(extent);
    if s == 1.0 || (1e-100..=1e100).contains(&extent) {
        return (None, 1.0);
    }
    let mut m = mesh.clone();
    m.positions.iter_mut().for_each(|p| *p *= s);
    (Some(m), s)
}

/// A component whose `measure` (volume or winding) is within `tie` of zero is undecided;
/// otherwise it is inverted when the measure is negative.
fn decide(info: &mut ComponentInfo, measure: f64, tie: f64) {
    if measure.abs() <= tie {
        info.undecided = true;
    } else {
        info.inverted = measure < 0.0;
    }
}

fn signed_volume(mesh: &TriMesh, faces: &[u32], flip: &[bool], origin: Point3) -> f64 {
    let mut v = 0.0;
    for &f in faces {
        let [a, b, c] = mesh.corners(f as usize);
        let t = (a - origin).dot(&(b - origin).cross(&(c - origin)));
        v += if flip[f as usize] { -t } else { t };
    }
    v / 6.0
}

/// Solid angle of triangle (a, b, c) seen from `x` (Van Oosterom and Strackee): positive when
/// `x` sees the triangle's back.
#[inline]
pub fn solid_angle(x: &Point3, a: &Point3, b: &Point3, c: &Point3) -> f64 {
    let (a, b, c) = (a - x, b - x, c - x);
    let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
    let num = a.dot(&b.cross(&c));
    let den = la * lb * lc + a.dot(&b) * lc + b.dot(&c) * la + c.dot(&a) * lb;
    2.0 * num.atan2(den)
}

/// Area-weighted mean generalized winding number of a component at sampled face centroids.
fn mean_winding(mesh: &TriMesh, faces: &[u32], flip: &[bool]) -> f64 {
    if faces.len() < 2 {
        return 0.0;
    }
    let step = faces.len().div_ceil(WINDING_SAMPLES);
    let samples: Vec<u32> = faces.iter().step_by(step).copied().collect();
    let parts: Vec<(f64, f64)> = samples
        .par_iter()
        .map(|&s| {
            let [a, b, c] = mesh.corners(s as usize);
            let x = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let area = mesh.face_area(s as usize);
            let mut w = 0.0;
            for &f in faces {
                if f == s {
                    continue;
                }
                let [p, q, r] = mesh.corners(f as usize);
                let o = solid_angle(&x, &p, &q, &r);
                w += if flip[f as usize] { -o } else { o };
            }
            (area * w / (4.0 * std::f64::consts::PI), area)
        })
        .collect();
    let (sw, sa) = parts
        .iter()
        .fold((0.0, 0.0), |(w, a), p| (w + p.0, a + p.1));
    if sa > 0.0 {
        sw / sa
    } else {
        0.0
    }
}

/// Flips the faces a plan marks.
pub fn apply(mesh: &mut TriMesh, plan: &Plan) {
    for (f, &fl) in plan.flip.iter().enumerate() {
        if fl {
            mesh.flip_face(f);
        }
    }
}

/// Plans and applies the orientation; returns the plan.
pub fn orient(mesh: &mut TriMesh, outward: bool) -> Plan {
    let topo = Topology::build(mesh);
    let p = plan(mesh, &topo, outward);
    apply(mesh, &p);
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn inside_out_cube_is_flipped_whole() {
        let mut m = generate::cube(1.0);
        for f in 0..m.faces.len() {
            m.flip_face(f);
        }
        let p = orient(&mut m, true);
        assert_eq!(p.report().flipped_faces, 12);
        assert_eq!(p.report().inverted_components, 1);
        assert!((m.signed_volume() - 1.0).abs() < 1e-12);
        assert!(orient(&mut m, true).is_noop());
    }

    #[test]
    fn solid_angle_of_closed_surface_is_four_pi_inside() {
        let m = generate::icosphere(2);
        let x = Point3::new(0.1, -0.2, 0.3);
        let total: f64 = (0..m.faces.len())
            .map(|f| {
                let [a, b, c] = m.corners(f);
                solid_angle(&x, &a, &b, &c)
            })
            .sum();
        assert!((total - 4.0 * std::f64::consts::PI).abs() < 1e-9);
        let y = Point3::new(2.0, 0.0, 0.0);
        let outside: f64 = (0..m.faces.len())
            .map(|f| {
                let [a, b, c] = m.corners(f);
                solid_angle(&y, &a, &b, &c)
            })
            .sum();
        assert!(outside.abs() < 1e-9);
    }

    #[test]
    fn open_hemisphere_faces_its_convex_side() {
        // A sphere with its lower half removed: the normals should point away from the centre.
        let full = generate::icosphere(3);
        let keep: Vec<bool> = (0..full.faces.len())
            .map(|f| full.corners(f).iter().map(|p| p.z).sum::<f64>() > 0.0)
            .collect();
        let mut m = full.clone();
        m.retain_faces(&keep);
        for f in 0..m.faces.len() {
            m.flip_face(f);
        }
        let p = orient(&mut m, true);
        assert_eq!(p.report().open_components, 1);
        assert_eq!(p.report().inverted_components, 1);
        for f in 0..m.faces.len() {
            let [a, b, c] = m.corners(f);
            let centroid = (a.coords + b.coords + c.coords) / 3.0;
            assert!(m.face_cross(f).dot(&centroid) > 0.0);
        }
    }

    #[test]
    fn flat_sheet_keeps_the_first_faces_winding() {
        let p = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        // First face points down (-z); the second disagrees.
        let mut m = TriMesh::new(p, vec![[0, 2, 1], [0, 2, 3]]);
        let plan = orient(&mut m, true);
        assert_eq!(plan.report().undecided_components, 1);
        assert_eq!(m.faces, vec![[0, 2, 1], [0, 3, 2]]);
    }

    #[test]
    fn moebius_band_is_non_orientable() {
        let n = 12;
        let mut pos = Vec::new();
        for i in 0..n {
            let t = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            let (s, c) = (t / 2.0).sin_cos();
            for w in [-0.3, 0.3] {
                let r = 1.0 + w * c;
                pos.push(Point3::new(r * t.cos(), r * t.sin(), w * s));
            }
        }
        let mut faces = Vec::new();
        for i in 0..n {
            let (a, b) = (2 * i as u32, 2 * i as u32 + 1);
            let (c, d) = if i + 1 < n { (a + 2, b + 2) } else { (1, 0) };
            faces.push([a, c, b]);
            faces.push([b, c, d]);
        }
        let mut m = TriMesh::new(pos, faces);
        let plan = orient(&mut m, true);
        assert_eq!(plan.report().non_orientable_components, 1);
    }
}
