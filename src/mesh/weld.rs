//! Welding: merging vertices that coincide, exactly or within a tolerance.
//!
//! [`ExactIndexer`] gives each distinct position one index (bitwise equality, `-0.0 == 0.0`);
//! readers of index-free formats (STL, vertex triples) use it, which loses nothing.
//!
//! [`weld`] merges vertices closer than a tolerance, by default `1e-6` times the bounding-box
//! diagonal, so float noise (`0.0` against `6.1e-17`) closes while real features a few hundred
//! thousandths of the part apart stay. It runs in O(n) expected time: vertices are visited in
//! order; each looks for an earlier *representative* within the tolerance in the cells of a
//! spatial hash (cell edge 8 x tolerance) that the tolerance ball around it touches; if there is
//! one it maps to it, otherwise it becomes a representative itself. Representatives keep their
//! own positions (no averaging), so the result depends only on the input order, and a point
//! never moves by more than the tolerance.
//!
//! **Closed stays closed.** Welding is for cracks: corners that should be shared but were
//! written apart, which shows as edges with only one face. A vertex whose every edge already
//! has exactly two faces is *sealed*: its faces close into a fan, as everywhere on a closed
//! 2-manifold. Another face brought onto a sealed vertex always breaks the surface there (a
//! third face on an edge, or a second fan: a pinch), unless that face shares the vertex and
//! collapses. So [`weld`] lets a vertex `b` join a representative `a` (with the vertices already
//! merged into it) only when
//!
//! * neither `b` nor any vertex of `a` is sealed (the cracks of a soup or of a split-vertex
//!   export: the usual welding), or
//! * `b` shares an edge with a vertex of `a`: the weld collapses edges shorter than the
//!   tolerance, as it always did (a pole written as a ring of coincident vertices, a sliver
//!   edge); their faces become degenerate and `clean` drops them.
//!
//! Otherwise `b` looks on for another representative, or becomes one. Two sheets of a closed
//! surface that touch within the tolerance (the lips of a body mesh, 0 to 0.3 micrometres
//! apart in a 2 m body, under the default 2.2 micrometres) therefore stay apart, where merging
//! them would pinch the surface into non-manifold edges. (A collapse can still fold a feature
//! smaller than the tolerance whose edges are all shorter than it, a needle-thin spike; such a
//! feature is noise.) [`weld_map`] alone (used by `diagnose` to count near-duplicate vertices)
//! looks at positions only.

use super::topology::{Topology, NON_MANIFOLD};
use super::TriMesh;
use crate::math::{tol, Point3};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// How far apart two vertices may be and still be merged.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "mode", content = "value", rename_all = "kebab-case")]
pub enum WeldTolerance {
    /// A distance in the mesh's own units.
    Absolute(f64),
    /// A fraction of the bounding-box diagonal.
    Relative(f64),
}

impl Default for WeldTolerance {
    fn default() -> Self {
        WeldTolerance::Relative(tol::WELD_REL_DEFAULT)
    }
}

impl WeldTolerance {
    /// The distance this tolerance means for a mesh with bounding-box diagonal `diagonal`.
    pub fn distance(&self, diagonal: f64) -> f64 {
        match *self {
            WeldTolerance::Absolute(d) => d,
            WeldTolerance::Relative(r) => r * diagonal,
        }
    }
}

impl FromStr for WeldTolerance {
    type Err = String;
    /// `0.01` is absolute (mesh units); `1e-6rel` is relative to the bounding-box diagonal.
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        let (num, rel) = match s.strip_suffix("rel") {
            Some(n) => (n.trim(), true),
            None => (s, false),
        };
        let v: f64 = num.parse().map_err(|_| {
            format!(
                "weld tolerance '{s}' is not a number: give e.g. '0.01' (absolute) or '1e-6rel'"
            )
        })?;
        if !v.is_finite() || v < 0.0 {
            return Err(format!("weld tolerance '{s}' must be a finite number >= 0"));
        }
        Ok(if rel {
            WeldTolerance::Relative(v)
        } else {
            WeldTolerance::Absolute(v)
        })
    }
}

impl fmt::Display for WeldTolerance {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WeldTolerance::Absolute(d) => write!(f, "{d:?}"),
            WeldTolerance::Relative(r) => write!(f, "{r:?}rel"),
        }
    }
}

/// What welding did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WeldReport {
    /// The tolerance as asked for.
    pub tolerance: WeldTolerance,
    /// The distance used, in mesh units.
    pub distance: f64,
    /// Vertices before.
    pub vertices_before: usize,
    /// Vertices after (unreferenced ones are kept: see `TriMesh::drop_unreferenced_vertices`).
    pub vertices_after: usize,
    /// Vertices merged into an earlier one.
    pub welded: usize,
    /// Vertices within the tolerance of a representative but kept apart, as merging them would
    /// break a closed fan (see the module docs).
    pub kept_apart: usize,
}

/// Gives each distinct position one index, in order of first appearance.
///
/// ```
/// use drapekit::math::Point3;
/// use drapekit::mesh::weld::ExactIndexer;
/// let mut ix = ExactIndexer::with_capacity(4);
/// assert_eq!(ix.index(Point3::new(0.0, 1.0, 2.0)), 0);
/// assert_eq!(ix.index(Point3::new(-0.0, 1.0, 2.0)), 0);
/// assert_eq!(ix.index(Point3::new(0.0, 1.0, 2.5)), 1);
/// assert_eq!(ix.into_positions().len(), 2);
/// ```
pub struct ExactIndexer {
    positions: Vec<Point3>,
    /// Open addressing: `fingerprint << 32 | index`, or [`EMPTY_SLOT`]. The fingerprint (high
    /// hash bits) settles most mismatches without touching `positions`.
    table: Vec<u64>,
    mask: usize,
}

const EMPTY: u32 = u32::MAX;
const EMPTY_SLOT: u64 = u64::MAX;

#[inline]
fn key_bits(p: &Point3) -> [u64; 3] {
    // +0.0 and -0.0 are the same point.
    [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits)
}

#[inline]
fn hash_bits(k: &[u64; 3]) -> u64 {
    let mut h = k[0].wrapping_mul(0x9E37_79B9_7F4A_7C15);
    h = (h.rotate_left(23) ^ k[1]).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    h = (h.rotate_left(29) ^ k[2]).wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^ (h >> 32)
}

impl ExactIndexer {
    /// An indexer expecting about `n` distinct positions.
    pub fn with_capacity(n: usize) -> ExactIndexer {
        let size = (n.max(8) * 2).next_power_of_two();
        ExactIndexer {
            positions: Vec::with_capacity(n),
            table: vec![EMPTY_SLOT; size],
            mask: size - 1,
        }
    }

    /// The index of `p`, new or existing.
    #[inline]
    pub fn index(&mut self, p: Point3) -> u32 {
        let k = key_bits(&p);
        let h = hash_bits(&k);
        let fp = h >> 32;
        let mut slot = h as usize & self.mask;
        loop {
            let e = self.table[slot];
            if e == EMPTY_SLOT {
                break;
            }
            if e >> 32 == fp && key_bits(&self.positions[e as u32 as usize]) == k {
                return e as u32;
            }
            slot = (slot + 1) & self.mask;
        }
        let id = self.positions.len() as u32;
        self.positions.push(p);
        self.table[slot] = fp << 32 | u64::from(id);
        if self.positions.len() * 2 > self.table.len() {
            self.grow();
        }
        id
    }

    /// Number of distinct positions so far.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether no position was indexed.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The distinct positions, by index.
    pub fn into_positions(self) -> Vec<Point3> {
        self.positions
    }

    fn grow(&mut self) {
        let size = self.table.len() * 2;
        self.table = vec![EMPTY_SLOT; size];
        self.mask = size - 1;
        for (id, p) in self.positions.iter().enumerate() {
            let h = hash_bits(&key_bits(p));
            let mut slot = h as usize & self.mask;
            while self.table[slot] != EMPTY_SLOT {
                slot = (slot + 1) & self.mask;
            }
            self.table[slot] = (h >> 32) << 32 | id as u64;
        }
    }
}

/// Cells of the weld's spatial hash: cell coordinates to the first representative in the cell.
struct CellTable {
    slots: Vec<u32>,
    keys: Vec<[i64; 3]>,
    heads: Vec<u32>,
    mask: usize,
}

impl CellTable {
    fn with_capacity(n: usize) -> CellTable {
        let size = (n.max(8) * 2).next_power_of_two();
        CellTable {
            slots: vec![EMPTY; size],
            keys: Vec::with_capacity(n),
            heads: Vec::with_capacity(n),
            mask: size - 1,
        }
    }

    #[inline]
    fn slot_of(&self, k: &[i64; 3]) -> (usize, bool) {
        let mut slot = hash_bits(&k.map(|c| c as u64)) as usize & self.mask;
        loop {
            let e = self.slots[slot];
            if e == EMPTY {
                return (slot, false);
            }
            if self.keys[e as usize] == *k {
                return (slot, true);
            }
            slot = (slot + 1) & self.mask;
        }
    }

    /// The first representative in cell `k`, or `EMPTY`.
    #[inline]
    fn head(&self, k: &[i64; 3]) -> u32 {
        match self.slot_of(k) {
            (slot, true) => self.heads[self.slots[slot] as usize],
            _ => EMPTY,
        }
    }

    /// Makes `rep` the first representative of cell `k`; returns the previous first.
    fn push(&mut self, k: [i64; 3], rep: u32) -> u32 {
        let (slot, found) = self.slot_of(&k);
        if found {
            let e = self.slots[slot] as usize;
            std::mem::replace(&mut self.heads[e], rep)
        } else {
            self.slots[slot] = self.keys.len() as u32;
            self.keys.push(k);
            self.heads.push(rep);
            if self.keys.len() * 2 > self.slots.len() {
                let size = self.slots.len() * 2;
                self.slots = vec![EMPTY; size];
                self.mask = size - 1;
                for (i, key) in self.keys.iter().enumerate() {
                    let mut s = hash_bits(&key.map(|c| c as u64)) as usize & self.mask;
                    while self.slots[s] != EMPTY {
                        s = (s + 1) & self.mask;
                    }
                    self.slots[s] = i as u32;
                }
            }
            EMPTY
        }
    }
}

/// The weld map: for each vertex, the representative it merges into (`map[i] <= i` holds for
/// representatives' new indices in first-appearance order), and the number of representatives.
/// Positions only: every vertex within the distance of a representative merges.
pub fn weld_map(positions: &[Point3], distance: f64) -> (Vec<u32>, usize) {
    let w = weld_with(positions, distance, None);
    (w.map, w.reps.pos.len())
}

/// Welds `positions`; with `mesh` (whose positions they are), only where the surface stays
/// manifold (see the module docs).
fn weld_with<'a>(positions: &[Point3], distance: f64, mesh: Option<&'a TriMesh>) -> Welder<'a> {
    let mut w = Welder {
        map: Vec::with_capacity(positions.len()),
        reps: Reps::default(),
        mesh,
        seal: None,
        kept_apart: 0,
    };
    if distance == 0.0 || !distance.is_finite() {
        w.exact(positions);
    } else {
        w.spatial(positions, distance);
    }
    w
}

/// Representatives: their position, whether one of their vertices is sealed, and the next
/// representative in the same bucket (a cell, or an exact position).
#[derive(Default)]
struct Reps {
    pos: Vec<Point3>,
    sealed: Vec<bool>,
    next: Vec<u32>,
}

/// A weld in progress: the map of the vertices so far.
struct Welder<'a> {
    map: Vec<u32>,
    reps: Reps,
    /// The mesh whose surface must stay manifold, if any.
    mesh: Option<&'a TriMesh>,
    /// Its sealed vertices, found when the first merge is asked for (a mesh with nothing to
    /// weld needs no topology).
    seal: Option<Seal<'a>>,
    /// Vertices that had a representative within the distance but could join none.
    kept_apart: usize,
}

impl<'a> Welder<'a> {
    /// Whether the next vertex may join representative `r` (see the module docs).
    fn may_join(&mut self, r: u32) -> bool {
        let Some(mesh) = self.mesh else { return true };
        if self.seal.is_none() {
            let seal = Seal::new(mesh);
            for (u, &rep) in self.map.iter().enumerate() {
                self.reps.sealed[rep as usize] |= seal.sealed[u];
            }
            self.seal = Some(seal);
        }
        let Some(seal) = &self.seal else { return true };
        let i = self.map.len();
        (!seal.sealed[i] && !self.reps.sealed[r as usize]) || seal.touches(i, r, &self.map)
    }

    /// The next vertex, at `p`, joins `r`, or with `EMPTY` becomes a representative, made the
    /// head of its bucket by `link` (which returns the previous head). `near`: some
    /// representative was within the distance.
    fn settle(&mut self, p: &Point3, r: u32, near: bool, link: impl FnOnce(u32) -> u32) {
        let sealed = self.seal.as_ref().is_some_and(|s| s.sealed[self.map.len()]);
        let r = if r == EMPTY {
            self.kept_apart += usize::from(near);
            let id = self.reps.pos.len() as u32;
            self.reps.pos.push(*p);
            self.reps.sealed.push(sealed);
            self.reps.next.push(link(id));
            id
        } else {
            self.reps.sealed[r as usize] |= sealed;
            r
        };
        self.map.push(r);
    }

    /// Distance 0: bitwise-equal positions ([`ExactIndexer`]).
    fn exact(&mut self, positions: &[Point3]) {
        let mut ix = ExactIndexer::with_capacity(positions.len());
        // Per distinct position: the latest representative there.
        let mut heads: Vec<u32> = Vec::new();
        for p in positions {
            let k = ix.index(*p) as usize;
            if k == heads.len() {
                heads.push(EMPTY);
            }
            let mut r = heads[k];
            while r != EMPTY && !self.may_join(r) {
                r = self.reps.next[r as usize];
            }
            let near = heads[k] != EMPTY;
            self.settle(p, r, near, |id| std::mem::replace(&mut heads[k], id));
        }
    }

    /// A positive distance: the spatial hash (see the module docs).
    fn spatial(&mut self, positions: &[Point3], distance: f64) {
        let inv = 1.0 / (8.0 * distance);
        let d2 = distance * distance;
        let cell_of = |x: f64| (x * inv).floor() as i64;
        let mut cells = CellTable::with_capacity(positions.len());
        for p in positions {
            let lo = [p.x, p.y, p.z].map(|c| cell_of(c - distance));
            let hi = [p.x, p.y, p.z].map(|c| cell_of(c + distance));
            let (mut found, mut near) = (EMPTY, false);
            'search: for cx in lo[0]..=hi[0] {
                for cy in lo[1]..=hi[1] {
                    for cz in lo[2]..=hi[2] {
                        let mut r = cells.head(&[cx, cy, cz]);
                        while r != EMPTY {
                            if (self.reps.pos[r as usize] - p).norm_squared() <= d2 {
                                near = true;
                                if self.may_join(r) {
                                    found = r;
                                    break 'search;
                                }
                            }
                            r = self.reps.next[r as usize];
                        }
                    }
                }
            }
            let c = [p.x, p.y, p.z].map(cell_of);
            self.settle(p, found, near, |id| cells.push(c, id));
        }
    }
}

/// What [`weld`] must not break: which vertices are sealed, and the faces around each.
struct Seal<'a> {
    mesh: &'a TriMesh,
    topo: Topology,
    /// Per vertex: it has faces, and every edge at it has exactly two.
    sealed: Vec<bool>,
}

impl<'a> Seal<'a> {
    fn new(mesh: &'a TriMesh) -> Seal<'a> {
        let topo = Topology::build(mesh);
        let mut sealed: Vec<bool> = (0..mesh.positions.len() as u32)
            .map(|v| !topo.vertex_faces(v).is_empty())
            .collect();
        for (h, &o) in topo.opp.iter().enumerate() {
            if o >= NON_MANIFOLD {
                let f = &mesh.faces[h / 3];
                sealed[f[h % 3] as usize] = false;
                sealed[f[(h + 1) % 3] as usize] = false;
            }
        }
        Seal { mesh, topo, sealed }
    }

    /// Whether vertex `i` shares an edge with an earlier vertex that `map` sends to `r`.
    fn touches(&self, i: usize, r: u32, map: &[u32]) -> bool {
        self.topo.vertex_faces(i as u32).iter().any(|&f| {
            self.mesh.faces[f as usize]
                .iter()
                .any(|&u| (u as usize) < i && map[u as usize] == r)
        })
    }
}

/// Welds `mesh` in place; see the module docs. Vertices keep the order of their first
/// appearance; faces are remapped (a face may become degenerate: `clean` drops those).
pub fn weld(mesh: &mut TriMesh, tolerance: WeldTolerance) -> WeldReport {
    let before = mesh.positions.len();
    let distance = tolerance.distance(mesh.diagonal());
    let (map, count, kept_apart) = {
        let w = weld_with(&mesh.positions, distance, Some(mesh));
        (w.map, w.reps.pos.len(), w.kept_apart)
    };
    let mut positions = vec![Point3::origin(); count];
    // The representative's own position: the first vertex mapped to each new index.
    let mut seen = vec![false; count];
    for (i, &m) in map.iter().enumerate() {
        if !seen[m as usize] {
            seen[m as usize] = true;
            positions[m as usize] = mesh.positions[i];
        }
    }
    mesh.positions = positions;
    for face in &mut mesh.faces {
        for v in face.iter_mut() {
            *v = map[*v as usize];
        }
    }
    WeldReport {
        tolerance,
        distance,
        vertices_before: before,
        vertices_after: count,
        welded: before - count,
        kept_apart,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    #[test]
    fn parse_tolerance() {
        assert_eq!(
            "0.01".parse::<WeldTolerance>(),
            Ok(WeldTolerance::Absolute(0.01))
        );
        assert_eq!(
            "1e-6rel".parse::<WeldTolerance>(),
            Ok(WeldTolerance::Relative(1e-6))
        );
        assert!("-1".parse::<WeldTolerance>().is_err());
        assert!("abc"
            .parse::<WeldTolerance>()
            .unwrap_err()
            .contains("not a number"));
    }

    #[test]
    fn noise_closes_features_stay() {
        let p = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(6.1e-17, 0.0, 0.0),
            Point3::new(0.03, 0.0, 0.0),
            Point3::new(300.0, 0.0, 0.0),
        ];
        let (map, n) = weld_map(&p, 1e-6 * 300.0);
        assert_eq!(map, vec![0, 0, 1, 2]);
        assert_eq!(n, 3);
    }

    #[test]
    fn neighbour_cells_are_searched() {
        // Two points straddling a cell boundary (cell = 8 * 0.1 = 0.8) are merged.
        let p = vec![Point3::new(0.79, 0.0, 0.0), Point3::new(0.81, 0.0, 0.0)];
        let (map, n) = weld_map(&p, 0.1);
        assert_eq!((map, n), (vec![0, 0], 1));
        // Negative coordinates straddling zero too.
        let p = vec![
            Point3::new(-0.01, -0.01, -0.01),
            Point3::new(0.01, 0.01, 0.01),
        ];
        assert_eq!(weld_map(&p, 0.1).1, 1);
    }

    #[test]
    fn no_chaining_beyond_tolerance() {
        // 0, 0.6, 1.2 with tolerance 1: 0.6 joins 0, 1.2 is 1.2 from the representative: stays.
        let p: Vec<Point3> = [0.0, 0.6, 1.2]
            .iter()
            .map(|&x| Point3::new(x, 0.0, 0.0))
            .collect();
        let (map, n) = weld_map(&p, 1.0);
        assert_eq!((map, n), (vec![0, 0, 1], 2));
    }

    /// Two unit cubes, centred on the origin and on `offset`: for `offset = (1 + g) (1, 1, 1)`
    /// their nearest corners are `g sqrt 3` apart.
    fn two_cubes(offset: Vec3) -> TriMesh {
        let mut m = crate::mesh::generate::cube(1.0);
        let b = m.clone();
        let n = m.positions.len() as u32;
        m.positions.extend(b.positions.iter().map(|p| p + offset));
        m.faces.extend(b.faces.iter().map(|f| f.map(|v| v + n)));
        m
    }

    #[test]
    fn closed_surfaces_touching_within_the_tolerance_stay_apart() {
        // Exactly touching corners (the exact path), and 1e-9 apart (the spatial hash).
        for (gap, tolerance) in [
            (0.0, WeldTolerance::Absolute(0.0)),
            (0.0, WeldTolerance::default()),
            (1e-9, WeldTolerance::default()),
        ] {
            let mut m = two_cubes(Vec3::repeat(1.0 + gap));
            let r = weld(&mut m, tolerance);
            assert_eq!((r.welded, r.kept_apart), (0, 1), "gap {gap}");
            let d = crate::mesh::diagnose::diagnose(&m);
            assert!(d.watertight && d.non_manifold_vertices == 0, "gap {gap}");
        }
    }

    #[test]
    fn a_soup_still_welds() {
        // Every corner its own vertex, with float noise on the copies: nothing is sealed.
        let orig = crate::mesh::generate::icosphere(2);
        let mut soup = TriMesh::default();
        for (f, face) in orig.faces.iter().enumerate() {
            for &v in face {
                let noise = if f % 2 == 0 { 0.0 } else { 1e-12 };
                soup.positions
                    .push(orig.positions[v as usize] + Vec3::repeat(noise));
            }
            let b = 3 * f as u32;
            soup.faces.push([b, b + 1, b + 2]);
        }
        let r = weld(&mut soup, WeldTolerance::default());
        assert_eq!((r.vertices_after, r.kept_apart), (orig.positions.len(), 0));
        assert!(crate::mesh::diagnose::diagnose(&soup).watertight);
    }

    /// A bipyramid over a ring of five points, apexes at z = +-1, with ring point 1 moved to
    /// `1e-9` from ring point 0 (a sliver edge on a closed surface).
    fn bipyramid_with_sliver() -> TriMesh {
        let mut p: Vec<Point3> = (0..5)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / 5.0;
                Point3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        p[1] = p[0] + Vec3::new(0.0, 1e-9, 0.0);
        p.push(Point3::new(0.0, 0.0, 1.0));
        p.push(Point3::new(0.0, 0.0, -1.0));
        let faces = (0..5)
            .flat_map(|i| {
                let j = (i + 1) % 5;
                [[i, j, 5], [j, i, 6]]
            })
            .collect();
        TriMesh::new(p, faces)
    }

    /// A cone over a ring of `n` points whose tip is written as a ring of `n` coincident
    /// points around a hub (the tip's faces have no area): closed, every vertex sealed.
    fn cone_with_ring_tip(n: u32) -> TriMesh {
        let mut p: Vec<Point3> = (0..n)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                Point3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        p.extend((0..=n).map(|_| Point3::new(0.0, 0.0, 1.0)));
        p.push(Point3::origin());
        let (hub, base) = (2 * n, 2 * n + 1);
        let faces = (0..n)
            .flat_map(|i| {
                let j = (i + 1) % n;
                [
                    [j, i, base],
                    [i, j, n + j],
                    [i, n + j, n + i],
                    [n + i, n + j, hub],
                ]
            })
            .collect();
        TriMesh::new(p, faces)
    }

    #[test]
    fn short_edges_of_a_closed_surface_collapse() {
        use super::super::prepare::{prepare, PrepareOptions};
        let mut m = bipyramid_with_sliver();
        let r = prepare(&mut m, &PrepareOptions::default());
        assert_eq!(
            (r.welded_vertices, r.weld.map(|w| w.kept_apart)),
            (1, Some(0))
        );
        assert_eq!((m.positions.len(), m.faces.len()), (6, 8));
        assert!(r.after.watertight && r.after.non_manifold_vertices == 0);
        // A ring of coincident points collapses whole, through its edges: each point touches a
        // point already merged.
        let mut m = cone_with_ring_tip(7);
        assert!(crate::mesh::diagnose::diagnose(&m).watertight);
        let r = prepare(&mut m, &PrepareOptions::default());
        assert_eq!(
            (r.welded_vertices, r.weld.map(|w| w.kept_apart)),
            (7, Some(0))
        );
        assert_eq!((m.positions.len(), m.faces.len()), (9, 14));
        assert_eq!(
            r.after.shell_state,
            crate::mesh::diagnose::ShellState::Closed
        );
    }

    #[test]
    fn exact_indexer_grows() {
        let mut ix = ExactIndexer::with_capacity(1);
        for i in 0..1000 {
            assert_eq!(ix.index(Point3::new(i as f64, 0.0, 0.0)), i);
        }
        for i in 0..1000 {
            assert_eq!(ix.index(Point3::new(i as f64, 0.0, 0.0)), i);
        }
    }
}
