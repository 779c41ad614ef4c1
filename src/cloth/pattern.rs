//! Pattern pieces: a 2D outline becomes particles, triangles and the paper's springs.
//!
//! **Particles.** The warp runs along x, the weft along y. A square grid of spacing `h` covers the
//! outline; a grid cell is *full* when its four corners are inside the outline and at least
//! [`CLEARANCE`]`* h` from it, and the corners of full cells are particles. The outline is
//! sampled at most `h` apart, its corners included, so the shape holds.
//!
//! **Triangles.** Each full cell is two triangles. The band between the outline and the full
//! cells is a polygon with holes (the outline, and the boundaries of the blocks of full cells);
//! it is bridged and ear-clipped (`mesh::polygon::triangulate_with_holes`). The triangles give
//! the masses (a third of each incident triangle's area times the density) and the output mesh.
//!
//! **Springs** (`method.md` s. 2), constants from the fabric (`fabric`):
//! * grid particles get the paper's 12 neighbours: stretch to the 4 direct neighbours (warp or
//!   weft), shear on the 4 cell diagonals, bend over one node to the 4 second neighbours along
//!   the threads (when the node between exists);
//! * in the band, every triangle edge not already a grid spring is a stretch spring whose
//!   constant follows its direction (`E_warp cos^2 + E_weft sin^2`), and every interior band
//!   edge gets a bend spring between the two corners opposite it.
//!
//! Bend springs are made only when the fabric has a bending rigidity: a scene computes only
//! what it needs.

use super::fabric::Fabric;
use crate::math::{orient2d, Point2, Point3};
use crate::mesh::polygon::triangulate_with_holes;
use serde::Serialize;
use std::collections::HashMap;

/// Grid corners closer than this many spacings to the outline are not kept.
pub const CLEARANCE: f64 = 0.4;

/// What a spring models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SpringKind {
    /// Along a thread (or a band edge).
    Stretch,
    /// A cell diagonal.
    Shear,
    /// Over one node.
    Bend,
}

/// A linear spring `F = k (|d| - rest) d / |d|`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length, m.
    pub rest: f64,
    /// Constant, N/m.
    pub k: f64,
    /// Kind.
    pub kind: SpringKind,
}

/// A pattern piece, flat.
#[derive(Debug, Clone)]
pub struct Piece {
    /// Particle positions in the piece's plane.
    pub flat: Vec<Point2>,
    /// Triangles (counter-clockwise in the plane).
    pub triangles: Vec<[u32; 3]>,
    /// Springs.
    pub springs: Vec<Spring>,
    /// Particle masses, kg.
    pub mass: Vec<f64>,
    /// Pinned particles.
    pub pinned: Vec<u32>,
    /// Area of the flat piece, m^2.
    pub area: f64,
    /// Grid particles (the first ones).
    pub grid_particles: usize,
}

/// What is wrong with a piece.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PatternError {
    /// Fewer than three distinct outline points.
    #[error("the outline has {found} distinct point(s); a piece needs at least 3")]
    TooFewPoints { found: usize },
    /// NaN or infinity.
    #[error("outline point {index} is not finite")]
    NonFinite { index: usize },
    /// Two edges cross.
    #[error("the outline intersects itself: edge {first} ({a:?} -> {b:?}) crosses edge {second}")]
    SelfIntersecting {
        first: usize,
        second: usize,
        a: [f64; 2],
        b: [f64; 2],
    },
    /// No area.
    #[error("the outline has no area (its points are collinear)")]
    ZeroArea,
    /// A bad spacing.
    #[error("spacing {spacing} must be a positive number")]
    Spacing { spacing: f64 },
    /// Too many particles.
    #[error("spacing {spacing} gives {count} grid nodes over the outline's box; at most 4,000,000: use a larger spacing")]
    TooFine { spacing: f64, count: usize },
    /// A pin away from every particle.
    #[error("pin {index} at ({x}, {y}) is {distance:.3e} from the nearest particle; pins must be outline points or grid crossings")]
    Pin {
        index: usize,
        x: f64,
        y: f64,
        distance: f64,
    },
}

/// Whether segments (a, b) and (c, d) cross or touch, beyond shared endpoints.
fn segments_meet(a: &Point2, b: &Point2, c: &Point2, d: &Point2) -> bool {
    let (d1, d2, d3, d4) = (
        orient2d(a, b, c),
        orient2d(a, b, d),
        orient2d(c, d, a),
        orient2d(c, d, b),
    );
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: &Point2, q: &Point2, r: &Point2| {
        orient2d(p, q, r) == 0.0
            && r.x >= p.x.min(q.x)
            && r.x <= p.x.max(q.x)
            && r.y >= p.y.min(q.y)
            && r.y <= p.y.max(q.y)
    };
    on(a, b, c) || on(a, b, d) || on(c, d, a) || on(c, d, b)
}

/// Checks and orients an outline: distinct, finite, simple, counter-clockwise.
pub fn clean_outline(outline: &[Point2]) -> Result<Vec<Point2>, PatternError> {
    if let Some(i) = outline
        .iter()
        .position(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(PatternError::NonFinite { index: i + 1 });
    }
    let mut p: Vec<Point2> = outline.to_vec();
    p.dedup();
    while p.len() > 1 && p.first() == p.last() {
        p.pop();
    }
    if p.len() < 3 {
        return Err(PatternError::TooFewPoints { found: p.len() });
    }
    let n = p.len();
    for i in 0..n {
        for j in i + 1..n {
            // Adjacent edges share a corner; that is allowed.
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            if segments_meet(&p[i], &p[(i + 1) % n], &p[j], &p[(j + 1) % n]) {
                return Err(PatternError::SelfIntersecting {
                    first: i + 1,
                    second: j + 1,
                    a: [p[i].x, p[i].y],
                    b: [p[(i + 1) % n].x, p[(i + 1) % n].y],
                });
            }
        }
    }
    let a2 = crate::fit::section::signed_area2(&p);
    let per = crate::fit::section::perimeter(&p);
    if a2.abs() <= 1e-12 * per * per {
        return Err(PatternError::ZeroArea);
    }
    if a2 < 0.0 {
        p.reverse();
    }
    Ok(p)
}

fn inside(poly: &[Point2], q: &Point2) -> bool {
    crate::fit::scan::contains(poly, q)
}

fn distance_to_outline(poly: &[Point2], q: &Point2) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let ab = b - a;
            let t = ((q - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
            (a + ab * t - q).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Builds a piece from its outline (piece-plane coordinates, m), spacing (m), fabric and pins.
pub fn build(
    outline: &[Point2],
    spacing: f64,
    fabric: &Fabric,
    pins: &[Point2],
) -> Result<Piece, PatternError> {
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(PatternError::Spacing { spacing });
    }
    let poly = clean_outline(outline)?;
    let h = spacing;
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in &poly {
        x0 = x0.min(p.x);
        x1 = x1.max(p.x);
        y0 = y0.min(p.y);
        y1 = y1.max(p.y);
    }
    let (i0, i1) = ((x0 / h).floor() as i64, (x1 / h).ceil() as i64);
    let (j0, j1) = ((y0 / h).floor() as i64, (y1 / h).ceil() as i64);
    let (ni, nj) = ((i1 - i0 + 1) as usize, (j1 - j0 + 1) as usize);
    if ni.saturating_mul(nj) > 4_000_000 {
        return Err(PatternError::TooFine {
            spacing,
            count: ni.saturating_mul(nj),
        });
    }
    let node =
        |i: usize, j: usize| Point2::new((i0 + i as i64) as f64 * h, (j0 + j as i64) as f64 * h);
    let valid: Vec<bool> = (0..nj)
        .flat_map(|j| (0..ni).map(move |i| (i, j)))
        .map(|(i, j)| {
            let q = node(i, j);
            inside(&poly, &q) && distance_to_outline(&poly, &q) >= CLEARANCE * h
        })
        .collect();
    let full = |i: usize, j: usize| {
        i + 1 < ni
            && j + 1 < nj
            && valid[j * ni + i]
            && valid[j * ni + i + 1]
            && valid[(j + 1) * ni + i]
            && valid[(j + 1) * ni + i + 1]
    };
    let mut kept = vec![false; ni * nj];
    for j in 0..nj {
        for i in 0..ni {
            if full(i, j) {
                for (a, b) in [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)] {
                    kept[b * ni + a] = true;
                }
            }
        }
    }
    // Particles: kept grid nodes (row after row), then the outline samples.
    let mut index = vec![u32::MAX; ni * nj];
    let mut flat: Vec<Point2> = Vec::new();
    for j in 0..nj {
        for i in 0..ni {
            if kept[j * ni + i] {
                index[j * ni + i] = flat.len() as u32;
                flat.push(node(i, j));
            }
        }
    }
    let grid_particles = flat.len();
    let mut outer: Vec<u32> = Vec::new();
    for e in 0..poly.len() {
        let (a, b) = (poly[e], poly[(e + 1) % poly.len()]);
        let m = ((b - a).norm() / h).ceil().max(1.0) as usize;
        for k in 0..m {
            outer.push(flat.len() as u32);
            flat.push(a + (b - a) * (k as f64 / m as f64));
        }
    }
    let id = |i: usize, j: usize| index[j * ni + i];
    // Triangles of full cells.
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for j in 0..nj {
        for i in 0..ni {
            if full(i, j) {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
    }
    let cell_triangles = triangles.len();
    // Boundary loops of the blocks of full cells: directed cell edges whose reverse is absent.
    let mut out_edges: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut directed: std::collections::HashSet<(u32, u32)> = std::collections::HashSet::new();
    for t in 0..cell_triangles / 2 {
        let [a, b, c] = triangles[2 * t];
        let d = triangles[2 * t + 1][2];
        for e in [(a, b), (b, c), (c, d), (d, a)] {
            directed.insert(e);
        }
    }
    let mut boundary: Vec<(u32, u32)> = directed
        .iter()
        .filter(|(a, b)| !directed.contains(&(*b, *a)))
        .copied()
        .collect();
    boundary.sort_unstable();
    for &(a, b) in &boundary {
        out_edges.entry(a).or_default().push(b);
    }
    let mut used: std::collections::HashSet<(u32, u32)> = std::collections::HashSet::new();
    let mut holes: Vec<Vec<u32>> = Vec::new();
    for &(a0, b0) in &boundary {
        if used.contains(&(a0, b0)) {
            continue;
        }
        let mut lp = vec![a0];
        let (mut a, mut b) = (a0, b0);
        loop {
            used.insert((a, b));
            if b == a0 {
                break;
            }
            lp.push(b);
            // At a corner two blocks touch, turn most to the left (stay with this block).
            let din = flat[b as usize] - flat[a as usize];
            let next = out_edges[&b]
                .iter()
                .copied()
                .filter(|&c| !used.contains(&(b, c)))
                .max_by(|&c1, &c2| {
                    let turn = |c: u32| {
                        let dout = flat[c as usize] - flat[b as usize];
                        (din.x * dout.y - din.y * dout.x).atan2(din.dot(&dout))
                    };
                    turn(c1).total_cmp(&turn(c2))
                });
            match next {
                Some(c) => {
                    a = b;
                    b = c;
                }
                None => break,
            }
        }
        lp.reverse();
        holes.push(lp);
    }
    let pos3: Vec<Point3> = flat.iter().map(|p| Point3::new(p.x, p.y, 0.0)).collect();
    let band = triangulate_with_holes(&pos3, &outer, &holes);
    triangles.extend_from_slice(&band);

    // Masses.
    let mut mass = vec![0.0; flat.len()];
    let mut area = 0.0;
    for t in &triangles {
        let a = 0.5
            * orient2d(
                &flat[t[0] as usize],
                &flat[t[1] as usize],
                &flat[t[2] as usize],
            );
        area += a;
        for &v in t {
            mass[v as usize] += fabric.density * a / 3.0;
        }
    }

    // Springs.
    let mut springs: Vec<Spring> = Vec::new();
    let mut paired: std::collections::HashSet<(u32, u32)> = std::collections::HashSet::new();
    let add = |springs: &mut Vec<Spring>, a: u32, b: u32, k: f64, kind: SpringKind| {
        if k > 0.0 {
            let rest = (flat[a as usize] - flat[b as usize]).norm();
            springs.push(Spring {
                a,
                b,
                rest,
                k,
                kind,
            });
        }
    };
    let bends = fabric.bend[0] > 0.0 || fabric.bend[1] > 0.0;
    for j in 0..nj {
        for i in 0..ni {
            let a = id(i, j);
            if a == u32::MAX {
                continue;
            }
            let at = |di: i64, dj: i64| -> u32 {
                let (ii, jj) = (i as i64 + di, j as i64 + dj);
                if ii < 0 || jj < 0 || ii >= ni as i64 || jj >= nj as i64 {
                    u32::MAX
                } else {
                    id(ii as usize, jj as usize)
                }
            };
            for (di, dj, kind) in [(1, 0, 0), (0, 1, 1)] {
                let b = at(di, dj);
                if b != u32::MAX {
                    add(
                        &mut springs,
                        a,
                        b,
                        fabric.stretch[kind],
                        SpringKind::Stretch,
                    );
                    paired.insert((a.min(b), a.max(b)));
                }
                if bends {
                    let (m, c) = (at(di, dj), at(2 * di, 2 * dj));
                    if m != u32::MAX && c != u32::MAX {
                        let k = if kind == 0 {
                            fabric.bend_k(h, 1.0, 0.0)
                        } else {
                            fabric.bend_k(h, 0.0, 1.0)
                        };
                        add(&mut springs, a, c, k, SpringKind::Bend);
                    }
                }
            }
            for (di, dj) in [(1, 1), (-1, 1)] {
                let b = at(di, dj);
                // A diagonal of a full cell.
                let cell_full = if di == 1 {
                    full(i, j)
                } else {
                    i >= 1 && full(i - 1, j)
                };
                if b != u32::MAX && cell_full {
                    add(&mut springs, a, b, fabric.shear, SpringKind::Shear);
                    paired.insert((a.min(b), a.max(b)));
                }
            }
        }
    }
    // The band: stretch along every new edge, bend across every interior edge.
    let mut opposite: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for t in &band {
        for e in 0..3 {
            let (a, b, c) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
            opposite.entry((a.min(b), a.max(b))).or_default().push(c);
        }
    }
    let mut band_edges: Vec<(&(u32, u32), &Vec<u32>)> = opposite.iter().collect();
    band_edges.sort_by_key(|(e, _)| **e);
    for (&(a, b), opp) in band_edges {
        if !paired.contains(&(a, b)) {
            let d = flat[b as usize] - flat[a as usize];
            let l = d.norm();
            add(
                &mut springs,
                a,
                b,
                fabric.stretch_k(d.x / l, d.y / l),
                SpringKind::Stretch,
            );
            paired.insert((a, b));
        }
        if bends && opp.len() == 2 {
            let d = flat[opp[1] as usize] - flat[opp[0] as usize];
            let l = d.norm();
            if l > 0.0 {
                add(
                    &mut springs,
                    opp[0],
                    opp[1],
                    fabric.bend_k(l / 2.0, d.x / l, d.y / l),
                    SpringKind::Bend,
                );
            }
        }
    }

    let mut pinned = Vec::new();
    for (pi, pin) in pins.iter().enumerate() {
        let (best, dist) = flat
            .iter()
            .enumerate()
            .map(|(i, q)| (i, (q - pin).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        if dist > 0.5 * h {
            return Err(PatternError::Pin {
                index: pi + 1,
                x: pin.x,
                y: pin.y,
                distance: dist,
            });
        }
        pinned.push(best as u32);
    }
    pinned.sort_unstable();
    pinned.dedup();
    Ok(Piece {
        flat,
        triangles,
        springs,
        mass,
        pinned,
        area,
        grid_particles,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(s: f64) -> Vec<Point2> {
        vec![
            Point2::new(-s, -s),
            Point2::new(s, -s),
            Point2::new(s, s),
            Point2::new(-s, s),
        ]
    }

    #[test]
    fn square_piece_is_covered_and_weighs_its_area() {
        let f = Fabric::cotton();
        let p = build(&square(0.5), 0.05, &f, &[Point2::new(-0.5, 0.5)]).unwrap();
        assert!((p.area - 1.0).abs() < 1e-12, "{}", p.area);
        let m: f64 = p.mass.iter().sum();
        assert!((m - f.density).abs() < 1e-12);
        // Every triangle counter-clockwise, no overlap: areas add up to the outline's.
        let sum: f64 = p
            .triangles
            .iter()
            .map(|t| {
                0.5 * orient2d(
                    &p.flat[t[0] as usize],
                    &p.flat[t[1] as usize],
                    &p.flat[t[2] as usize],
                )
            })
            .sum();
        let abs: f64 = p
            .triangles
            .iter()
            .map(|t| {
                (0.5 * orient2d(
                    &p.flat[t[0] as usize],
                    &p.flat[t[1] as usize],
                    &p.flat[t[2] as usize],
                ))
                .abs()
            })
            .sum();
        assert!((sum - 1.0).abs() < 1e-12 && (abs - 1.0).abs() < 1e-12);
        assert_eq!(p.pinned.len(), 1);
        // A watertight sheet: every edge used by one or two triangles, boundary = outline.
        let mesh = crate::mesh::TriMesh::new(
            p.flat.iter().map(|q| Point3::new(q.x, q.y, 0.0)).collect(),
            p.triangles.clone(),
        );
        let d = crate::mesh::diagnose::diagnose(&mesh);
        assert_eq!(
            (d.non_manifold_edges, d.boundary_loops, d.components),
            (0, 1, 1)
        );
        assert_eq!(d.euler_characteristic, 1);
    }

    #[test]
    fn interior_particles_have_twelve_neighbours() {
        let p = build(&square(0.5), 0.05, &Fabric::cotton(), &[]).unwrap();
        let mut count = vec![0; p.flat.len()];
        for s in &p.springs {
            if (s.a as usize) < p.grid_particles && (s.b as usize) < p.grid_particles {
                count[s.a as usize] += 1;
                count[s.b as usize] += 1;
            }
        }
        assert_eq!(count.iter().max(), Some(&12));
        let no_bend = Fabric {
            bend: [0.0, 0.0],
            ..Fabric::cotton()
        };
        let q = build(&square(0.5), 0.05, &no_bend, &[]).unwrap();
        assert!(
            q.springs.iter().all(|s| s.kind != SpringKind::Bend),
            "no bend springs without bending rigidity"
        );
    }

    #[test]
    fn concave_outline_and_errors() {
        let l = [
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 0.3),
            (0.3, 0.3),
            (0.3, 1.0),
            (0.0, 1.0),
        ]
        .map(|(x, y)| Point2::new(x, y));
        let p = build(&l, 0.04, &Fabric::cotton(), &[]).unwrap();
        assert!((p.area - 0.51).abs() < 1e-12, "{}", p.area);
        let bow = [(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)].map(|(x, y)| Point2::new(x, y));
        assert!(matches!(
            build(&bow, 0.1, &Fabric::cotton(), &[]),
            Err(PatternError::SelfIntersecting { .. })
        ));
        assert!(matches!(
            build(&bow[..2], 0.1, &Fabric::cotton(), &[]),
            Err(PatternError::TooFewPoints { found: 2 })
        ));
        assert!(matches!(
            build(
                &square(0.5),
                0.1,
                &Fabric::cotton(),
                &[Point2::new(0.05, 0.56)]
            ),
            Err(PatternError::Pin { .. })
        ));
    }
}
