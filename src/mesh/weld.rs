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
pub fn weld_map(positions: &[Point3], distance: f64) -> (Vec<u32>, usize) {
    let mut map = vec![0u32; positions.len()];
    if distance == 0.0 || !distance.is_finite() {
        let mut ix = ExactIndexer::with_capacity(positions.len());
        for (i, p) in positions.iter().enumerate() {
            map[i] = ix.index(*p);
        }
        return (map, ix.len());
    }
    let cell = 8.0 * distance;
    let inv = 1.0 / cell;
    let d2 = distance * distance;
    let cell_of = |x: f64| (x * inv).floor() as i64;
    let mut cells = CellTable::with_capacity(positions.len());
    // Representatives: their position, the next one in the same cell, and their new index.
    let mut rep_next: Vec<u32> = Vec::new();
    let mut rep_pos: Vec<Point3> = Vec::new();
    for (i, p) in positions.iter().enumerate() {
        let lo = [
            cell_of(p.x - distance),
            cell_of(p.y - distance),
            cell_of(p.z - distance),
        ];
        let hi = [
            cell_of(p.x + distance),
            cell_of(p.y + distance),
            cell_of(p.z + distance),
        ];
        let mut found = EMPTY;
        'search: for cx in lo[0]..=hi[0] {
            for cy in lo[1]..=hi[1] {
                for cz in lo[2]..=hi[2] {
                    let mut r = cells.head(&[cx, cy, cz]);
                    while r != EMPTY {
                        if (rep_pos[r as usize] - p).norm_squared() <= d2 {
                            found = r;
                            break 'search;
                        }
                        r = rep_next[r as usize];
                    }
                }
            }
        }
        if found == EMPTY {
            let id = rep_pos.len() as u32;
            let c = [cell_of(p.x), cell_of(p.y), cell_of(p.z)];
            rep_next.push(cells.push(c, id));
            rep_pos.push(*p);
            found = id;
        }
        map[i] = found;
    }
    (map, rep_pos.len())
}

/// Welds `mesh` in place; see the module docs. Vertices keep the order of their first
/// appearance; faces are remapped (a face may become degenerate: `clean` drops those).
pub fn weld(mesh: &mut TriMesh, tolerance: WeldTolerance) -> WeldReport {
    let before = mesh.positions.len();
    let distance = tolerance.distance(mesh.diagonal());
    let (map, count) = weld_map(&mesh.positions, distance);
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
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
