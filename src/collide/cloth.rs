//! Cloth against cloth (issue 8, "Garments"): a spatial hash of the cloth's triangles, the two
//! crossing counts of the report, and position-based self-contact.
//!
//! **The hash** ([`ClothHash`]). Space is cut into cubes of edge `cell` (by default [`AUTO_CELL`]
//! times the mean edge length), numbered `(i, j, k) >= 0` from a corner below the cloth; cube
//! `(i, j, k)` goes to slot `(i + j P + k Q) mod 2^m` (`P`, `Q` large odd numbers: neighbours
//! along `i` share cache lines) of a table of at least twice as many slots as triangles. Each
//! triangle is listed once in the slot of every cube its box overlaps (counting sort: count,
//! prefix sums, fill; O(triangles), no allocation once the buffers have grown). A triangle whose
//! box spans more than [`BIG_CELLS`] cubes is kept on a short list every query reads instead.
//! Boxes are kept rounded outward to `f32` (compact, and a point rounded the same way is never
//! lost). Distinct cubes may share a slot, so a query tests each listed box. A point query reads
//! one slot (every box holding the point is listed in the point's cube), a box query (an edge)
//! the cubes of its box, reporting a triangle only from the first cube (lowest `i`, `j`, `k`) of
//! the overlap of the two cube ranges: each triangle once, without sorting. [`ClothHash::rebuild`]
//! grows each triangle's box by a margin on every side; `resolve_self` shapes them to its pairs
//! (below): the triangle with its edge lines moved out by `LATERAL h` in its plane (mitred
//! corners), grown along axis `a` by `DETECT h |n_a|`, a thin box for a flat layer.
//!
//! **Seams.** Pieces are sewn by springs of rest length 0 between distinct particles. The hash
//! welds the two sides of each seam (`ClothHash::new`'s `seams`): particles joined by seams count
//! as one vertex for "shares a vertex" and for the 1-ring, as in a welded garment mesh, so the
//! sides of a closed seam neither push each other apart nor count as crossing.
//!
//! **Crossings** ([`self_crossing_edges`], [`body_crossing_edges`]). With
//! `O(a, b, c, d) = ((b - a) x (c - a)) . (d - a)` (six times the signed volume of `abcd`,
//! [`orient3d`]), edge `pq` properly crosses triangle `abc` when `O(a, b, c, p) O(a, b, c, q) < 0`
//! and `O(p, q, a, b)`, `O(p, q, b, c)`, `O(p, q, c, a)` are non-zero with one sign (the line
//! `pq` passes inside all three edges). Any zero (touching, grazing, coplanar) is not a crossing.
//! A determinant whose sign rounding could have decided (within Shewchuk's static error bound)
//! counts as zero: a reported crossing is certain for the given coordinates, and coplanar
//! triangles of a tilted flat sheet never cross by rounding noise; a crossing within rounding of
//! an edge or of the plane is not reported (no exact arithmetic). A self crossing needs a triangle
//! that shares no (welded) vertex with the edge; each undirected edge counts once however many
//! triangles it crosses. The body count walks the collider's grid cells along the edge
//! (`Grid::traverse`), testing each face once.
//!
//! **Self-contact** ([`resolve_self`]). A pair is a particle `p` and a triangle `t = abc` holding
//! neither `p` nor a neighbour of `p` (its 1-ring along the triangles' edges, seams welded: the
//! triangles left out are `p`'s star, precomputed, skipped in one walk along each query's sorted
//! list), so a pair never fights the cloth's own springs. With `n` the unit normal of `t`,
//! `(α, β, γ)` the barycentric coordinates of `p`'s projection on `t`'s plane (all `>= -FACE_TOL`:
//! the projection is inside `t`; weights within `FACE_TOL` of 0 are made 0), `q = α a + β b + γ c`,
//! and `s = ±1` the side of `t` that `p` was on at `x_old` (against `t`'s normal at `x_old`,
//! flipped if that normal has turned over), the contact distance is
//! `h = (h_p + (h_a + h_b + h_c) / 3) / 2` (the mean of the two layers' thicknesses) and the
//! constraint
//!
//! ```text
//! C = s n . (p - q) - h >= 0.
//! ```
//!
//! A particle that tunnelled through `t` during the step has `s n . (p - q) < 0`: it is pushed
//! back to its old side. A violated pair is projected along `n` (held fixed), mass-weighted with
//! the inverse masses `w` (0 = pinned): `W = w_p + α² w_a + β² w_b + γ² w_c`, `λ = -C / W`,
//! `Δp = w_p λ s n`, `Δa = -w_a α λ s n` (and `b`, `c` alike). Alone it makes `C = 0` exactly, and
//! `Σ m Δx = λ s n (1 - α - β - γ) = 0`: the centre of mass stays.
//!
//! Pairs are found once per call, at the step's positions: `p` within [`DETECT`]` h` of `t`'s
//! plane (the slack lets a pair that a neighbour's correction brings close be corrected in the
//! same call) and projecting inside `t` with its edge lines moved out by [`LATERAL`]` h` (three
//! slab tests against the edges' in-plane normals, kept with the plane at the rebuild). Each pair
//! notes whether it may be violated already; the first iteration evaluates those, each later pass
//! only the pairs with a vertex the last correction moved (the others are as they were).
//!
//! *Jacobi.* Every iteration evaluates its pairs at the same positions, scales each violated
//! pair's correction by `ω = 1 / max(1, max k_v)` over its moving vertices, where `k_v` counts the
//! violated pairs moving vertex `v`, each by its share of the pair (1 for the particle, its
//! barycentric weight for a corner), then adds the corrections per vertex in a fixed order (a
//! vertex-to-pair table built by counting sort). A vertex moves about as the average of what its
//! pairs ask (the usual averaged Jacobi), but each pair is scaled as a whole, so momentum is kept
//! exactly; per-vertex averaging would not keep it. (Counting a pair by one instead of its share
//! under-relaxes: two offset layers were still not apart after 32 iterations, against 6.)
//!
//! *Velocity.* Then, for every pair corrected in some iteration, the relative velocity
//! `u = v_p - (α v_a + β v_b + γ v_c)` loses its approaching normal part: if `u_n = s n . u < 0`
//! the impulse `P = -u_n / W` along `s n` (momentum `J`, `Δv_p = w_p J`, `Δv_a = -w_a α J`, ...).
//! With `friction = μ > 0`, Coulomb friction adds `min(μ P, |u_t| / W)` against the tangential
//! relative velocity `u_t`, and the positions follow the velocity friction took (`Δx = Δv dt`, as
//! in the body collision). The same Jacobi scaling, the same number of iterations; impulses are
//! equal and opposite, so `Σ m v` is unchanged, with or without friction.
//!
//! **Determinism.** Pairs are found per particle over fixed chunks and concatenated in particle
//! order; every per-pair and per-vertex pass writes its own slot, and per-vertex sums run in the
//! table's order: the result has the same bits for any thread count.
//!
//! **In the step.** `sim::run` calls it through `sim::SelfContact` (which keeps the hash between
//! steps) when the world has one (garments), after the solve and *before* the body pass
//! (`sim::collide`), on the step's old positions (`x_old`, the state before the step) and new
//! positions and velocities:
//!
//! ```text
//! // once per run, seams as the [a, b] particle pairs of the seam springs:
//! let mut hash = ClothHash::new(model.len(), &model.triangles, &seams);
//! // each step, before collide(...):
//! let cloth = SelfCloth::new(&model.triangles, &model.thickness, &model.inv_mass);
//! let stats = resolve_self(&state.x, &mut x_new, &mut v_new, cloth, &mut hash, &opts, dt);
//! // for the report, at the end:
//! hash.rebuild(&x, &model.triangles, hash.cell(), 0.0);
//! let self_crossing = self_crossing_edges(&x, &model.triangles, &hash);
//! let body_crossing = body_crossing_edges_of(&collider, &x, hash.edges());
//! ```
//!
//! The body pass has the last word: a self pass run after it pushed layers lying on the body
//! into it, where the body's segment test (from a start already inside) no longer found them
//! (2,470 of 12,374 particles of `dress_pencil` ended inside `mean_all`, against 4 in this
//! order). The body pass may in turn push a particle into a layer above it by up to the
//! thickness; the next step's self pass separates them.
//!
//! **Limits.** Particle-triangle only: two edges crossing with every vertex clear of the other
//! layer (edge-edge) are not caught, nor a particle beside a boundary edge (its projection falls
//! outside every triangle), nor a fold inside a particle's star (a triangle folded flat over
//! its neighbour: the first crossings `hoody_mean` makes while sewing, README). A particle that
//! moves through the cloth by more than [`DETECT`] contact distances in one step is not found
//! (it is then on the far side for good; the crossing counts report it), and the side is
//! taken from the old positions, so a step that moves a particle around the rim of a triangle
//! can be read as a pass through it. There is no continuous (time-of-impact) test and no
//! fail-safe (impact zones; one was measured, README). A few Jacobi iterations do
//! not separate a deep stack at once: `SelfStats::remaining` says what is left for the next step.

use crate::collide::Collider;
use crate::math::{uf_root, Aabb, Point3, Vec3};
use crate::par;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// The automatic cube edge, in mean edge lengths (measured on the crumpled 14,000-particle
/// sheets of the timing test: 1 to 2 within 5% of instructions, 1.5 the fewest).
pub const AUTO_CELL: f64 = 1.5;

/// Cubes a triangle's grown box may span before it goes on the list every query reads.
pub const BIG_CELLS: usize = 64;

/// Cubes an edge's box may span before its query reads every triangle instead.
pub const BIG_QUERY: usize = 4096;

/// Barycentric tolerance of "the projection is inside the triangle" (so a particle above a shared
/// edge or vertex faces every triangle around it).
pub const FACE_TOL: f64 = 1e-9;

/// Pairs are found within this many contact distances of the triangle's plane (the slack lets a
/// pair that a neighbour's correction brings close be corrected in the same call).
pub const DETECT: f64 = 1.5;

/// ... with the particle's projection inside the triangle with its edge lines moved out by this
/// many contact distances (a pair whose projection stays outside never acts: corrections move
/// along normals).
pub const LATERAL: f64 = 0.25;

/// A pair is still "closer than the thickness" when `C < -REMAIN_TOL h`.
pub const REMAIN_TOL: f64 = 1e-9;

/// Cubes along one axis at most (the cell is enlarged beyond): keeps cube numbers in `u32`.
const MAX_CUBES_AXIS: f64 = (1u64 << 21) as f64;

/// Particles (or edges, or pairs) per work unit of the parallel loops. No result depends on it.
const CHUNK: usize = 256;

/// Invalid self-collision options.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SelfCollisionError {
    /// Friction negative or not finite.
    #[error("self-collision friction must be a finite number >= 0, got {0}")]
    Friction(f64),
    /// Cell not a positive finite length.
    #[error("self-collision cell must be a finite length > 0 m, got {0}")]
    Cell(f64),
    /// No iterations.
    #[error("self-collision needs at least 1 iteration")]
    Iterations,
}

/// How self-contact is resolved.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SelfCollisionOptions {
    /// Jacobi iterations of the position pass, and of the velocity pass (default 2).
    pub iterations: usize,
    /// Coulomb friction between cloth layers, a fraction of the normal impulse (default 0:
    /// layers slide freely; friction between layers changes how a garment settles, so a scene
    /// asks for it).
    pub friction: f64,
    /// Hash cube edge, m; `None` (default): [`AUTO_CELL`] times the mean edge length of the
    /// cloth at the step's positions.
    pub cell: Option<f64>,
}

impl Default for SelfCollisionOptions {
    fn default() -> Self {
        SelfCollisionOptions {
            iterations: 2,
            friction: 0.0,
            cell: None,
        }
    }
}

impl SelfCollisionOptions {
    /// Checks the options.
    pub fn validate(&self) -> Result<(), SelfCollisionError> {
        if self.iterations == 0 {
            return Err(SelfCollisionError::Iterations);
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err(SelfCollisionError::Friction(self.friction));
        }
        if let Some(c) = self.cell {
            if !(c.is_finite() && c > 0.0) {
                return Err(SelfCollisionError::Cell(c));
            }
        }
        Ok(())
    }
}

/// What one [`resolve_self`] call did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct SelfStats {
    /// Pairs found (within [`DETECT`] contact distances of the plane, the projection within
    /// [`LATERAL`] of the triangle).
    pub candidates: usize,
    /// Pairs closer than the contact distance (or on the wrong side) at the start.
    pub contacts: usize,
    /// Pairs pushed apart in at least one iteration.
    pub corrected: usize,
    /// Pairs whose approaching normal velocity was removed (in the first velocity iteration).
    pub approaching: usize,
    /// Pairs still closer than the contact distance after the last iteration (by more than
    /// [`REMAIN_TOL`] of it).
    pub remaining: usize,
    /// Wall time, s.
    pub seconds: f64,
}

/// A particle and a triangle near it, with the particle's side and their contact distance.
#[derive(Debug, Clone, Copy)]
struct Pair {
    p: u32,
    t: u32,
    side: f64,
    h: f64,
    /// Possibly violated where it was found (a superset of the violated pairs then).
    maybe: bool,
}

/// One violated pair's correction in one pass: vertex `k` of pair `pair` (the particle, then
/// the triangle's corners) moves by `coef[k] * dir`, counting `share[k]` at that vertex; `tan` is
/// the friction part of a velocity correction (the positions follow it).
#[derive(Debug, Clone, Copy)]
struct Push {
    pair: u32,
    coef: [f64; 4],
    share: [f64; 4],
    dir: Vec3,
    tan: Vec3,
}

/// The buffers of [`resolve_self`], kept between calls.
#[derive(Debug, Clone, Default)]
struct Work {
    /// Per triangle: the mean thickness of its corners.
    tri_h: Vec<f64>,
    chunks: Vec<Vec<Pair>>,
    pairs: Vec<Pair>,
    /// Per pair: corrected in some position iteration.
    ever: Vec<bool>,
    /// Per vertex: moved by the last position correction, and by any pass of this call.
    moved_last: Vec<bool>,
    moved_any: Vec<bool>,
    /// The pairs a pass evaluates.
    list: Vec<u32>,
    chunk_push: Vec<Vec<Push>>,
    /// The violated pairs of the pass, in pair order.
    push: Vec<Push>,
    /// Per vertex: `vstart[v]..vstart[v + 1]` in `vlist`, entries `4 push + slot`.
    vstart: Vec<u32>,
    vlist: Vec<u32>,
    /// Per vertex: the pushes moving it, each counted by its share.
    vshare: Vec<f64>,
    cursor: Vec<u32>,
}

/// One chunk of the per-triangle arrays a build writes: planes, slabs, cube ranges, boxes.
type BuildChunk<'a> = (
    ((&'a mut [Plane], &'a mut [Slabs]), &'a mut [[u32; 6]]),
    &'a mut [[f32; 6]],
);

/// A triangle's plane `[n, off]`: unit normal (zero for a degenerate triangle) and offset, `p`
/// is `n . p - off` in front.
type Plane = [f64; 4];

/// A triangle's edge slabs: per edge `k` (corner `k` to `k + 1`) its unit in-plane normal
/// pointing inside and offset, the projection of `p` is `m . p - off` inside the edge's line.
type Slabs = [[f64; 4]; 3];

#[inline]
fn plane_at(pl: &[f64; 4], p: &Point3) -> f64 {
    pl[0] * p.x + pl[1] * p.y + pl[2] * p.z - pl[3]
}

/// `v` rounded to `f32` down (`up` false) or up.
#[inline]
fn round32(v: f64, up: bool) -> f32 {
    let r = v as f32;
    if up && f64::from(r) < v {
        r.next_up()
    } else if !up && f64::from(r) > v {
        r.next_down()
    } else {
        r
    }
}

/// Plane distances within this fraction of the cloth's coordinates may be rounding.
const PLANE_TOL_REL: f64 = 1e-12;

/// Each particle's representative: the smallest particle it is sewn to through `seams`, or
/// itself.
fn weld_seams(particles: usize, seams: &[[u32; 2]]) -> Vec<u32> {
    let mut parent: Vec<usize> = (0..particles).collect();
    for &[a, b] in seams {
        let (ra, rb) = (
            uf_root(&mut parent, a as usize),
            uf_root(&mut parent, b as usize),
        );
        if ra != rb {
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    (0..particles)
        .map(|i| uf_root(&mut parent, i) as u32)
        .collect()
}

/// The unique undirected edges of `triangles` keyed by their welded ends (sorted by key), with
/// the smallest particle pair for each key; edges whose ends are welded together are left out.
fn welded_edges(triangles: &[[u32; 3]], weld: &[u32]) -> Vec<([u32; 2], [u32; 2])> {
    let mut all: Vec<([u32; 2], [u32; 2])> = Vec::with_capacity(triangles.len() * 3);
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let (ra, rb) = (weld[a as usize], weld[b as usize]);
            if ra == rb {
                continue;
            }
            all.push(if ra < rb {
                ([ra, rb], [a, b])
            } else {
                ([rb, ra], [b, a])
            });
        }
    }
    all.sort_unstable();
    all.dedup_by_key(|e| e.0);
    all
}

/// Compressed rows of `(row, value)` pairs over `rows` rows: `start[r]..start[r + 1]` in
/// `values` are row `r`'s values, in the order `pairs` gives them (it is called twice: count,
/// then fill).
fn csr<I: Iterator<Item = (u32, u32)>>(rows: usize, pairs: impl Fn() -> I) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; rows + 1];
    for (r, _) in pairs() {
        start[r as usize + 1] += 1;
    }
    for i in 0..rows {
        start[i + 1] += start[i];
    }
    let mut cursor = start.clone();
    let mut values = vec![0u32; start[rows] as usize];
    for (r, v) in pairs() {
        values[cursor[r as usize] as usize] = v;
        cursor[r as usize] += 1;
    }
    (start, values)
}

/// Each representative's star (the triangles at it or at a neighbour in `ring`, sorted, from
/// the triangles at each representative `vt`), as compressed rows: `(star_start, star)`.
fn stars(weld: &[u32], ring: (&[u32], &[u32]), vt: (&[u32], &[u32])) -> (Vec<u32>, Vec<u32>) {
    let ((count, ring), (vt_start, vt)) = (ring, vt);
    let particles = weld.len();
    let mut star_start = vec![0u32; particles + 1];
    let mut star = Vec::new();
    let mut one = Vec::new();
    for r in 0..particles {
        if weld[r] == r as u32 {
            one.clear();
            let ring_r = &ring[count[r] as usize..count[r + 1] as usize];
            for &v in std::iter::once(&(r as u32)).chain(ring_r) {
                one.extend_from_slice(
                    &vt[vt_start[v as usize] as usize..vt_start[v as usize + 1] as usize],
                );
            }
            one.sort_unstable();
            one.dedup();
            star.extend_from_slice(&one);
        }
        star_start[r + 1] = star.len() as u32;
    }
    (star_start, star)
}

/// A spatial hash of the cloth's triangles, with the cloth's fixed topology (welded seams, unique
/// edges, 1-rings) and the buffers of [`resolve_self`]. Build it once per cloth with
/// [`ClothHash::new`]; [`ClothHash::rebuild`] (or `resolve_self`) lists the triangles at new
/// positions.
#[derive(Debug, Clone, Default)]
pub struct ClothHash {
    particles: usize,
    /// Each particle's representative (the smallest particle it is sewn to, or itself).
    weld: Vec<u32>,
    /// Each triangle's corners' representatives.
    tri_weld: Vec<[u32; 3]>,
    /// The triangles at each representative or at a neighbour (its star: never paired with it):
    /// `star_start[r]..star_start[r + 1]` in `star`, sorted.
    star_start: Vec<u32>,
    star: Vec<u32>,
    /// Unique undirected edges (by their ends' representatives), as particle pairs.
    edges: Vec<[u32; 2]>,
    cell: f64,
    inv_cell: f64,
    origin: Point3,
    mask: usize,
    /// A checksum of the positions of the last rebuild (the crossing counts check it).
    positions: f64,
    /// Each triangle's cube range: `[i0, j0, k0, i1, j1, k1]`, inclusive.
    span: Vec<[u32; 6]>,
    /// Each triangle's box grown by the margin, `[lo; hi]`, rounded outward to `f32` (compact
    /// for the broad phase; comparing rounded points against it never loses a triangle).
    boxes: Vec<[f32; 6]>,
    /// Each triangle's plane.
    planes: Vec<Plane>,
    /// Each triangle's edge slabs.
    slabs: Vec<Slabs>,
    /// Point queries look for pairs within this distance of a plane.
    reach: f64,
    /// Plane distances within this are "maybe on the plane" (far above rounding).
    plane_tol: f64,
    start: Vec<u32>,
    fill: Vec<u32>,
    /// The last triangle counted in each slot (build only).
    stamp: Vec<u32>,
    /// Each triangle's slots (build only): `slot_start[t]..slot_start[t + 1]` in `slots`.
    slot_start: Vec<u32>,
    slots: Vec<u32>,
    entries: Vec<u32>,
    big: Vec<u32>,
    built: bool,
    work: Work,
}

impl ClothHash {
    /// The topology of a cloth of `particles` particles and `triangles`, the two sides of each
    /// seam in `seams` welded. No cubes yet: see [`ClothHash::rebuild`].
    pub fn new(particles: usize, triangles: &[[u32; 3]], seams: &[[u32; 2]]) -> ClothHash {
        let weld = weld_seams(particles, seams);
        let tri_weld: Vec<[u32; 3]> = triangles
            .iter()
            .map(|t| t.map(|v| weld[v as usize]))
            .collect();
        let all = welded_edges(triangles, &weld);
        // Each particle's 1-ring of representatives, sorted.
        let (count, mut ring) = csr(particles, || {
            all.iter().flat_map(|(k, _)| [(k[0], k[1]), (k[1], k[0])])
        });
        for r in 0..particles {
            ring[count[r] as usize..count[r + 1] as usize].sort_unstable();
        }
        // The triangles at each representative.
        let (vt_start, vt) = csr(particles, || {
            (tri_weld.iter().enumerate()).flat_map(|(t, tw)| tw.map(|v| (v, t as u32)))
        });
        let (star_start, star) = stars(&weld, (&count, &ring), (&vt_start, &vt));
        ClothHash {
            particles,
            weld,
            tri_weld,
            star_start,
            star,
            edges: all.into_iter().map(|(_, e)| e).collect(),
            cell: 1.0,
            inv_cell: 1.0,
            origin: Point3::origin(),
            ..ClothHash::default()
        }
    }

    /// The cloth's unique undirected edges (ends welded across seams), as particle pairs.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// The cube edge of the last rebuild, m.
    pub fn cell(&self) -> f64 {
        self.cell
    }

    /// Triangle entries in the table (a triangle counts once per slot it is in).
    pub fn entries(&self) -> usize {
        self.entries.len()
    }

    /// Triangles on the list every query reads.
    pub fn big(&self) -> usize {
        self.big.len()
    }

    /// Whether particles `i` and `j` are the same vertex once seams are welded.
    pub fn welded(&self, i: u32, j: u32) -> bool {
        self.weld[i as usize] == self.weld[j as usize]
    }

    /// The triangles at particle `p` or at a neighbour of it (seams welded), sorted.
    #[inline]
    fn star_of(&self, p: u32) -> &[u32] {
        let r = self.weld[p as usize] as usize;
        &self.star[self.star_start[r] as usize..self.star_start[r + 1] as usize]
    }

    /// Whether triangle `t` holds particle `p` or a neighbour of it (seams welded).
    #[cfg(test)]
    fn excluded(&self, p: u32, t: usize) -> bool {
        self.star_of(p).binary_search(&(t as u32)).is_ok()
    }

    /// Lists the triangles at positions `x` in cubes of edge `cell` (m), each triangle's box grown
    /// by `margin` (m: at least the largest distance a point query must find). No allocation
    /// once the buffers have grown to the cloth's size.
    pub fn rebuild(&mut self, x: &[Point3], triangles: &[[u32; 3]], cell: f64, margin: f64) {
        self.build(x, triangles, cell, margin, None);
    }

    /// [`ClothHash::rebuild`], or with `contact = Some(reach)` for contact pairs (see
    /// [`pair_of`]): each triangle's box is then the box of the triangle with its edge lines moved
    /// out by `margin` in its plane (the mitred corners reach `margin / sin(θ / 2)` past a corner
    /// of angle `θ`), grown along axis `a` by `reach |n_a|` (`n` its unit normal): every point whose
    /// projection on the plane is inside that larger triangle and whose distance to the plane is
    /// below `reach` lies in it. For a flat layer that is a much smaller box than one grown by
    /// `reach` on every side. A triangle with a corner too sharp for a finite miter goes on the
    /// list every query reads.
    fn build(
        &mut self,
        x: &[Point3],
        triangles: &[[u32; 3]],
        cell: f64,
        margin: f64,
        contact: Option<f64>,
    ) {
        assert_eq!(x.len(), self.particles, "positions of another cloth");
        assert_eq!(
            triangles.len(),
            self.tri_weld.len(),
            "triangles of another cloth"
        );
        assert!(cell.is_finite() && cell > 0.0, "cell {cell}");
        assert!(margin.is_finite() && margin >= 0.0, "margin {margin}");
        let reach = contact.unwrap_or(margin);
        assert!(reach.is_finite() && reach >= 0.0, "reach {reach}");
        self.built = true;
        self.reach = reach;
        self.positions = checksum(x);
        self.big.clear();
        self.entries.clear();
        if !self.frame(x, cell, margin.max(reach)) {
            return;
        }
        self.triangle_boxes(x, triangles, margin, contact);
        self.count_slots();
        self.fill_slots();
    }

    /// The hashed region round the positions `x`: its origin and cube edge (at least `cell`,
    /// and no more than `MAX_CUBES_AXIS` cubes along an axis), `pad` (m) added round the box;
    /// false (an empty table) when there are no positions.
    fn frame(&mut self, x: &[Point3], cell: f64, pad: f64) -> bool {
        let Some(bbox) = Aabb::of_points(x) else {
            self.mask = 0;
            self.start.clear();
            self.start.resize(2, 0);
            return false;
        };
        let extent = bbox.size().max() + 2.0 * (pad + cell);
        let cell = cell.max(extent / MAX_CUBES_AXIS);
        self.cell = cell;
        self.inv_cell = 1.0 / cell;
        self.origin = bbox.min - Vec3::repeat(pad + cell);
        let scale = (0..3).fold(0.0f64, |m, ax| {
            m.max(bbox.min[ax].abs()).max(bbox.max[ax].abs())
        });
        self.plane_tol = PLANE_TOL_REL * (scale + extent);
        true
    }

    /// Each triangle's plane, slabs (for contacts), range of cubes and `f32` box, in parallel
    /// over fixed chunks ([`triangle_box`]).
    fn triangle_boxes(
        &mut self,
        x: &[Point3],
        triangles: &[[u32; 3]],
        margin: f64,
        contact: Option<f64>,
    ) {
        let nt = triangles.len();
        self.span.resize(nt, [0; 6]);
        self.boxes.resize(nt, [0.0; 6]);
        self.planes.resize(nt, [0.0; 4]);
        self.slabs.resize(nt, [[0.0; 4]; 3]);
        let grid = Grid {
            origin: self.origin,
            inv_cell: self.inv_cell,
            margin,
            contact,
        };
        let mut parts: Vec<BuildChunk> = (self.planes.chunks_mut(CHUNK))
            .zip(self.slabs.chunks_mut(CHUNK))
            .zip(self.span.chunks_mut(CHUNK))
            .zip(self.boxes.chunks_mut(CHUNK))
            .collect();
        par::for_each_mut(&mut parts, par::parallel(nt), |k, (((pl, sl), sp), bx)| {
            for j in 0..pl.len() {
                let c = triangles[k * CHUNK + j].map(|v| x[v as usize]);
                triangle_box(&c, &grid, &mut pl[j], &mut sl[j], &mut sp[j], &mut bx[j]);
            }
        });
    }

    /// Counts each triangle's slots, once each (cubes of one triangle may share a slot: the
    /// stamp holds the last triangle counted in each slot), kept in `slots` (triangle t's at
    /// `slot_start[t]..slot_start[t + 1]`) for the fill; `start` becomes the slots' offsets.
    /// Serial, a few operations per cube. A triangle over more than `BIG_CELLS` cubes goes on
    /// the list every query reads instead.
    fn count_slots(&mut self) {
        let size = (2 * self.span.len()).max(16).next_power_of_two();
        self.mask = size - 1;
        self.start.clear();
        self.start.resize(size + 1, 0);
        self.stamp.clear();
        self.stamp.resize(size, u32::MAX);
        self.slots.clear();
        self.slot_start.clear();
        self.slot_start.push(0);
        for (t, s) in self.span.iter().enumerate() {
            if cubes(s) > BIG_CELLS {
                self.big.push(t as u32);
            } else {
                for k in s[2]..s[5] + 1 {
                    for j in s[1]..s[4] + 1 {
                        for i in s[0]..s[3] + 1 {
                            let slot = slot_of(i, j, k, self.mask);
                            if self.stamp[slot] != t as u32 {
                                self.stamp[slot] = t as u32;
                                self.start[slot + 1] += 1;
                                self.slots.push(slot as u32);
                            }
                        }
                    }
                }
            }
            self.slot_start.push(self.slots.len() as u32);
        }
        for s in 0..size {
            self.start[s + 1] += self.start[s];
        }
    }

    /// Fills the table, triangle by triangle: each slot lists its triangles in increasing order.
    fn fill_slots(&mut self) {
        let size = self.mask + 1;
        self.fill.clear();
        self.fill.extend_from_slice(&self.start[..size]);
        self.entries.resize(self.start[size] as usize, 0);
        for t in 0..self.span.len() {
            for &slot in &self.slots[self.slot_start[t] as usize..self.slot_start[t + 1] as usize] {
                let f = &mut self.fill[slot as usize];
                self.entries[*f as usize] = t as u32;
                *f += 1;
            }
        }
    }

    /// The cube of `p`, if `p` is in the hashed region (beyond it no triangle is within reach).
    #[inline]
    fn cube_of(&self, p: &Point3) -> Option<[u32; 3]> {
        let mut c = [0u32; 3];
        for ax in 0..3 {
            let t = (p[ax] - self.origin[ax]) * self.inv_cell;
            if !(0.0..MAX_CUBES_AXIS * 2.0).contains(&t) {
                return None;
            }
            c[ax] = t as u32;
        }
        Some(c)
    }

    /// Calls `f` with every triangle whose grown box holds `p` (each once), in table order.
    #[inline]
    pub fn for_point(&self, p: &Point3, f: impl FnMut(u32)) {
        self.for_point_except(p, &[], f);
    }

    /// [`ClothHash::for_point`] without the triangles of `except` (sorted): a slot lists its
    /// triangles in increasing order, so one walk along `except` skips them.
    #[inline]
    fn for_point_except(&self, p: &Point3, except: &[u32], mut f: impl FnMut(u32)) {
        debug_assert!(self.built, "rebuild the hash first");
        let Some(c) = self.cube_of(p) else { return };
        let slot = slot_of(c[0], c[1], c[2], self.mask);
        let q = [p.x as f32, p.y as f32, p.z as f32];
        let inside = |t: u32| {
            let b = &self.boxes[t as usize];
            q[0] >= b[0]
                && q[0] <= b[3]
                && q[1] >= b[1]
                && q[1] <= b[4]
                && q[2] >= b[2]
                && q[2] <= b[5]
        };
        for list in [
            &self.entries[self.start[slot] as usize..self.start[slot + 1] as usize],
            &self.big[..],
        ] {
            let mut j = 0;
            for &t in list {
                if inside(t) {
                    while j < except.len() && except[j] < t {
                        j += 1;
                    }
                    if j == except.len() || except[j] != t {
                        f(t);
                    }
                }
            }
        }
    }

    /// Calls `f` with every triangle whose grown box meets the box `lo..hi` (each once); `f`
    /// returns false to stop.
    pub fn for_box(&self, lo: &Point3, hi: &Point3, mut f: impl FnMut(u32) -> bool) {
        debug_assert!(self.built, "rebuild the hash first");
        let (lo32, hi32) = (lo.map(|v| v as f32), hi.map(|v| v as f32));
        let meets = |t: u32| {
            let b = &self.boxes[t as usize];
            (0..3).all(|ax| b[ax] <= hi32[ax] && lo32[ax] <= b[ax + 3])
        };
        let mut q = [0u32; 6];
        for ax in 0..3 {
            let a = ((lo[ax] - self.origin[ax]) * self.inv_cell).max(0.0);
            let b = ((hi[ax] - self.origin[ax]) * self.inv_cell).max(0.0);
            if !(a.is_finite() && b.is_finite()) || b >= MAX_CUBES_AXIS * 2.0 {
                // Far outside: every triangle (the caller's exact test decides).
                for t in 0..self.span.len() as u32 {
                    if meets(t) && !f(t) {
                        return;
                    }
                }
                return;
            }
            q[ax] = a as u32;
            q[ax + 3] = b as u32;
        }
        if cubes(&q) > BIG_QUERY {
            for t in 0..self.span.len() as u32 {
                if meets(t) && !f(t) {
                    return;
                }
            }
            return;
        }
        for k in q[2]..q[5] + 1 {
            for j in q[1]..q[4] + 1 {
                for i in q[0]..q[3] + 1 {
                    let slot = slot_of(i, j, k, self.mask);
                    for &t in
                        &self.entries[self.start[slot] as usize..self.start[slot + 1] as usize]
                    {
                        let s = &self.span[t as usize];
                        // Reported from the first cube of the overlap only.
                        if holds(s, &[i, j, k])
                            && i == s[0].max(q[0])
                            && j == s[1].max(q[1])
                            && k == s[2].max(q[2])
                            && meets(t)
                            && !f(t)
                        {
                            return;
                        }
                    }
                }
            }
        }
        for &t in &self.big {
            if meets(t) && !f(t) {
                return;
            }
        }
    }
}

/// `Σ (x + 2 y + 3 z)` over the positions, in a fixed order.
fn checksum(x: &[Point3]) -> f64 {
    par::sum(x.len(), |i| x[i].x + 2.0 * x[i].y + 3.0 * x[i].z)
}

/// Panics unless `hash` was last rebuilt at `x` with `triangles`.
fn check_built(x: &[Point3], triangles: &[[u32; 3]], hash: &ClothHash) {
    assert_eq!(
        triangles.len(),
        hash.tri_weld.len(),
        "triangles of another cloth"
    );
    assert!(
        hash.built
            && x.len() == hash.particles
            && checksum(x).to_bits() == hash.positions.to_bits(),
        "the hash was built at other positions: rebuild it at these"
    );
}

/// What a triangle's cubes are measured against: the table's origin and inverse cube edge,
/// the margin (m) and the contact reach (`None`: a plain rebuild), as [`ClothHash::build`].
struct Grid {
    origin: Point3,
    inv_cell: f64,
    margin: f64,
    contact: Option<f64>,
}

/// Triangle `c`'s plane `pl`, slabs `sl` (for contacts), range of cubes `sp` and `f32` box
/// `bx`: its box grown by the margin, or for contacts the box of the triangle with its edge
/// lines moved out by the margin (mitred) grown by `reach |n_a|` along axis `a`; a triangle
/// with a corner too sharp for a finite miter, or no area, spans every cube.
fn triangle_box(
    c: &[Point3; 3],
    g: &Grid,
    pl: &mut Plane,
    sl: &mut Slabs,
    sp: &mut [u32; 6],
    bx: &mut [f32; 6],
) {
    let (e0, e1) = (c[1] - c[0], c[2] - c[0]);
    let n = e0.cross(&e1);
    let l = n.norm();
    let ok = l > 0.0 && l.is_finite();
    let n = if ok { n / l } else { Vec3::zeros() };
    *pl = [n.x, n.y, n.z, n.dot(&c[0].coords)];
    let (mut lo, mut hi) = ([c[0].x, c[0].y, c[0].z], [c[0].x, c[0].y, c[0].z]);
    widen(&mut lo, &mut hi, &c[1]);
    widen(&mut lo, &mut hi, &c[2]);
    let everywhere = match g.contact {
        None => {
            for ax in 0..3 {
                lo[ax] -= g.margin;
                hi[ax] += g.margin;
            }
            false
        }
        Some(reach) if ok => !mitred_box(c, &n, g.margin, reach, sl, &mut lo, &mut hi),
        // Degenerate: never a pair, but listed everywhere rather than nowhere.
        Some(_) => true,
    };
    if everywhere {
        let top = MAX_CUBES_AXIS as u32;
        *sp = [0, 0, 0, top, top, top];
        *bx = [
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::INFINITY,
            f32::INFINITY,
        ];
        return;
    }
    for ax in 0..3 {
        // Non-negative by the origin's choice: truncation is floor (a mitred corner may reach
        // below it: clamped, no point is there).
        let (a, b) = (
            (lo[ax] - g.origin[ax]) * g.inv_cell,
            (hi[ax] - g.origin[ax]) * g.inv_cell,
        );
        sp[ax] = if a > 0.0 { a as u32 } else { 0 };
        sp[ax + 3] = if b > MAX_CUBES_AXIS {
            MAX_CUBES_AXIS as u32
        } else if b > 0.0 {
            b as u32
        } else {
            0
        };
        bx[ax] = round32(lo[ax], false);
        bx[ax + 3] = round32(hi[ax], true);
    }
}

/// The box `lo`, `hi` widened to hold `q`.
#[inline]
fn widen(lo: &mut [f64; 3], hi: &mut [f64; 3], q: &Point3) {
    for ax in 0..3 {
        lo[ax] = lo[ax].min(q[ax]);
        hi[ax] = hi[ax].max(q[ax]);
    }
}

/// A contact box (`lo`, `hi`, holding the triangle `c` already): the slabs `sl` of its
/// edges (inward edge normals `n x e / |e|`), its corners moved out by `margin` with both
/// edge lines (mitred: by `-margin (m1 + m2) / (1 + m1 . m2)`), then grown by `reach |n_a|`
/// along each axis `a`. False when a corner is too sharp for a finite miter.
fn mitred_box(
    c: &[Point3; 3],
    n: &Vec3,
    margin: f64,
    reach: f64,
    sl: &mut Slabs,
    lo: &mut [f64; 3],
    hi: &mut [f64; 3],
) -> bool {
    let edges = [c[1] - c[0], c[2] - c[1], -(c[2] - c[0])];
    let mut m = [Vec3::zeros(); 3];
    for k in 0..3 {
        m[k] = n.cross(&edges[k]) / edges[k].norm();
        sl[k] = [m[k].x, m[k].y, m[k].z, m[k].dot(&c[k].coords)];
    }
    for k in 0..3 {
        let (m1, m2) = (m[(k + 2) % 3], m[k]);
        let den = 1.0 + m1.dot(&m2);
        if den.is_nan() || den <= 1e-9 {
            return false;
        }
        let q = c[k] - (m1 + m2) * (margin / den);
        widen(lo, hi, &q);
    }
    for ax in 0..3 {
        let g = reach * n[ax].abs();
        lo[ax] -= g;
        hi[ax] += g;
    }
    true
}

/// Cubes in an inclusive range.
#[inline]
fn cubes(s: &[u32; 6]) -> usize {
    (0..3).fold(1usize, |c, ax| {
        c.saturating_mul(s[ax + 3].saturating_sub(s[ax]) as usize + 1)
    })
}

/// Whether range `s` holds cube `c`.
#[inline]
fn holds(s: &[u32; 6], c: &[u32; 3]) -> bool {
    c[0] >= s[0] && c[0] <= s[3] && c[1] >= s[1] && c[1] <= s[4] && c[2] >= s[2] && c[2] <= s[5]
}

/// The slot of cube `(i, j, k)`.
#[inline]
fn slot_of(i: u32, j: u32, k: u32, mask: usize) -> usize {
    // Consecutive cubes along x get consecutive slots (a sweep along a row of the cloth reads
    // and writes nearby memory); rows and layers are spread by large odd multipliers.
    (u64::from(i)
        .wrapping_add(u64::from(j).wrapping_mul(0x9E37_79B1))
        .wrapping_add(u64::from(k).wrapping_mul(0x85EB_CA77_C2B2_AE63)) as usize)
        & mask
}

/// Shewchuk's static error bound of the orientation determinant, `(7 + 56 ε) ε` with
/// `ε = 2^-53`, a multiple of its permanent.
const ORIENT_BOUND: f64 = (7.0 + 56.0 * f64::EPSILON / 2.0) * f64::EPSILON / 2.0;

/// `((b - a) x (c - a)) . (d - a)`: positive when `d` is on the side of `abc`'s right-hand
/// normal (six times the signed volume of the tetrahedron), and exactly 0 when rounding could
/// have given the sign (within Shewchuk's static error bound: coplanar points come out 0, not
/// rounding noise of either sign).
#[inline]
pub fn orient3d(a: &Point3, b: &Point3, c: &Point3, d: &Point3) -> f64 {
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let (bc, cb) = (bd.y * cd.z, bd.z * cd.y);
    let (ca, ac) = (cd.y * ad.z, cd.z * ad.y);
    let (ab, ba) = (ad.y * bd.z, ad.z * bd.y);
    // Shewchuk's orient3d is det[a - d; b - d; c - d], the opposite sign.
    let det = ad.x * (bc - cb) + bd.x * (ca - ac) + cd.x * (ab - ba);
    let permanent = (bc.abs() + cb.abs()) * ad.x.abs()
        + (ca.abs() + ac.abs()) * bd.x.abs()
        + (ab.abs() + ba.abs()) * cd.x.abs();
    if det.abs() > ORIENT_BOUND * permanent {
        -det
    } else {
        0.0
    }
}

/// Whether segment `pq` properly crosses triangle `abc` (see the module docs: touching is not
/// crossing).
#[inline]
pub fn segment_crosses_triangle(
    p: &Point3,
    q: &Point3,
    a: &Point3,
    b: &Point3,
    c: &Point3,
) -> bool {
    let (sp, sq) = (orient3d(a, b, c, p), orient3d(a, b, c, q));
    if !(sp > 0.0 && sq < 0.0 || sp < 0.0 && sq > 0.0) {
        return false;
    }
    let s1 = orient3d(p, q, a, b);
    let s2 = orient3d(p, q, b, c);
    let s3 = orient3d(p, q, c, a);
    s1 > 0.0 && s2 > 0.0 && s3 > 0.0 || s1 < 0.0 && s2 < 0.0 && s3 < 0.0
}

/// The unique undirected edges of `triangles`, sorted, as `[low, high]` particle pairs.
pub fn cloth_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut e: Vec<[u32; 2]> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])]))
        .filter(|e| e[0] != e[1])
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

/// The mean length of `edges` at `x`, m (0 without edges).
pub fn mean_edge_length(x: &[Point3], edges: &[[u32; 2]]) -> f64 {
    if edges.is_empty() {
        return 0.0;
    }
    par::sum(edges.len(), |e| {
        (x[edges[e][1] as usize] - x[edges[e][0] as usize]).norm()
    }) / edges.len() as f64
}

/// `f(range)` over fixed chunks of `0..n`, in parallel for large `n`; the results in chunk order.
fn map_chunks<T: Send>(n: usize, f: impl Fn(std::ops::Range<usize>) -> T + Sync) -> Vec<T> {
    let chunks = n.div_ceil(CHUNK);
    let part = |c: usize| f(c * CHUNK..((c + 1) * CHUNK).min(n));
    if par::parallel(n) {
        (0..chunks).into_par_iter().map(part).collect()
    } else {
        (0..chunks).map(part).collect()
    }
}

/// Calls `hit(t)` for each triangle that edge `e` of the hash properly crosses and that shares
/// no welded vertex with it; `hit` returns false to stop.
fn edge_crossings(
    hash: &ClothHash,
    x: &[Point3],
    triangles: &[[u32; 3]],
    e: usize,
    mut hit: impl FnMut(u32) -> bool,
) {
    let [a, b] = hash.edges[e];
    let (ra, rb) = (hash.weld[a as usize], hash.weld[b as usize]);
    let (p, q) = (x[a as usize], x[b as usize]);
    let tol = hash.plane_tol;
    hash.for_box(&p.inf(&q), &p.sup(&q), |t| {
        let pl = &hash.planes[t as usize];
        let (dp, dq) = (plane_at(pl, &p), plane_at(pl, &q));
        if dp > tol && dq > tol || dp < -tol && dq < -tol {
            return true;
        }
        let tw = &hash.tri_weld[t as usize];
        if tw.contains(&ra) || tw.contains(&rb) {
            return true;
        }
        let [u, v, w] = triangles[t as usize].map(|i| x[i as usize]);
        if segment_crosses_triangle(&p, &q, &u, &v, &w) {
            return hit(t);
        }
        true
    });
}

/// Every (edge, triangle) pair where a cloth edge properly crosses a cloth triangle sharing no
/// vertex with it, in edge order. `hash` must have been rebuilt at `x` (checked: panics
/// otherwise).
pub fn self_crossings(
    x: &[Point3],
    triangles: &[[u32; 3]],
    hash: &ClothHash,
) -> Vec<([u32; 2], u32)> {
    check_built(x, triangles, hash);
    map_chunks(hash.edges.len(), |r| {
        let mut out = Vec::new();
        for e in r {
            edge_crossings(hash, x, triangles, e, |t| {
                out.push((hash.edges[e], t));
                true
            });
        }
        out
    })
    .concat()
}

/// The number of unique undirected cloth edges that properly cross a cloth triangle sharing no
/// vertex with them (seams welded). `hash` must have been rebuilt at `x` (checked: panics
/// otherwise).
pub fn self_crossing_edges(x: &[Point3], triangles: &[[u32; 3]], hash: &ClothHash) -> usize {
    check_built(x, triangles, hash);
    map_chunks(hash.edges.len(), |r| {
        r.filter(|&e| {
            let mut any = false;
            edge_crossings(hash, x, triangles, e, |_| {
                any = true;
                false
            });
            any
        })
        .count()
    })
    .into_iter()
    .sum()
}

/// The number of unique cloth edges of `triangles` that properly cross a face of the body.
pub fn body_crossing_edges(collider: &Collider, x: &[Point3], triangles: &[[u32; 3]]) -> usize {
    body_crossing_edges_of(collider, x, &cloth_edges(triangles))
}

/// The number of `edges` (particle pairs) that properly cross a face of the body.
pub fn body_crossing_edges_of(collider: &Collider, x: &[Point3], edges: &[[u32; 2]]) -> usize {
    body_crossing_flags(collider, x, edges)
        .into_iter()
        .filter(|&c| c)
        .count()
}

/// Per edge of `edges` (particle pairs), whether it properly crosses a face of the body: each
/// edge walks the cells of the collider's grid it passes, testing each face once.
pub fn body_crossing_flags(collider: &Collider, x: &[Point3], edges: &[[u32; 2]]) -> Vec<bool> {
    let m = collider.margin;
    map_chunks(edges.len(), |r| {
        let mut seen: Vec<u32> = Vec::new();
        r.map(|e| {
            let (p, q) = (x[edges[e][0] as usize], x[edges[e][1] as usize]);
            let (lo, hi) = (p.inf(&q), p.sup(&q));
            let outside = (0..3)
                .any(|k| hi[k] < collider.bbox.min[k] - m || lo[k] > collider.bbox.max[k] + m);
            !outside && segment_crosses_body(collider, &p, &q, &mut seen)
        })
        .collect::<Vec<bool>>()
    })
    .concat()
}

/// Whether segment `pq` properly crosses a face of the collider, walking the grid cells it
/// passes and testing each face once (`seen`: scratch).
pub fn segment_crosses_body(
    collider: &Collider,
    p: &Point3,
    q: &Point3,
    seen: &mut Vec<u32>,
) -> bool {
    let grid = collider.grid();
    seen.clear();
    let mut hit = false;
    grid.traverse(p, q, |cell| {
        for &f in grid.cell_faces(cell) {
            if seen.contains(&f) {
                continue;
            }
            seen.push(f);
            let [a, b, c] = collider.mesh.corners(f as usize);
            if segment_crosses_triangle(p, q, &a, &b, &c) {
                hit = true;
                return false;
            }
        }
        true
    });
    hit
}

/// Triangle `tri` at `x` seen from `p`: its unit normal, the barycentric coordinates of `p`'s
/// projection, and `p`'s signed distance along the normal. `None` for a degenerate triangle.
#[inline]
fn face(x: &[Point3], tri: &[u32; 3], p: &Point3) -> Option<(Vec3, [f64; 3], f64)> {
    let a = x[tri[0] as usize];
    let (e0, e1, ap) = (x[tri[1] as usize] - a, x[tri[2] as usize] - a, p - a);
    let n = e0.cross(&e1);
    let nn = n.norm_squared();
    if !(nn > 0.0 && nn.is_finite()) {
        return None;
    }
    // Barycentric coordinates by dot products (|e0 x e1|^2 is their denominator).
    let (d00, d01, d11) = (e0.dot(&e0), e0.dot(&e1), e1.dot(&e1));
    let (d20, d21) = (ap.dot(&e0), ap.dot(&e1));
    let beta = (d11 * d20 - d01 * d21) / nn;
    let gamma = (d00 * d21 - d01 * d20) / nn;
    let unit = n / nn.sqrt();
    Some((unit, [1.0 - beta - gamma, beta, gamma], ap.dot(&unit)))
}

#[inline]
fn inside(w: &[f64; 3], tol: f64) -> bool {
    w[0] >= -tol && w[1] >= -tol && w[2] >= -tol
}

/// Barycentric weights of an inside projection with those within [`FACE_TOL`] of 0 made 0 (and
/// the rest scaled to sum 1): a particle over a vertex or an edge moves exactly the vertex or
/// the edge's ends, whatever the rounding.
#[inline]
fn snap(w: [f64; 3]) -> [f64; 3] {
    let mut w = w.map(|w| if w.abs() <= FACE_TOL { 0.0 } else { w });
    let sum = w[0] + w[1] + w[2];
    // One weight is at least a third: the last non-zero one takes what the others leave.
    let last = if w[2] != 0.0 {
        2
    } else if w[1] != 0.0 {
        1
    } else {
        0
    };
    let mut rest = 0.0;
    for (k, wk) in w.iter_mut().enumerate() {
        if k != last {
            *wk /= sum;
            rest += *wk;
        }
    }
    w[last] = 1.0 - rest;
    w
}

/// The side of triangle `tri` particle `p` was on at `x_old`, against the normal `n` it has now
/// (0 when on the plane or the old triangle is degenerate).
#[inline]
fn old_side(x_old: &[Point3], tri: &[u32; 3], p: u32, n: &Vec3) -> f64 {
    let a = x_old[tri[0] as usize];
    let n_old = (x_old[tri[1] as usize] - a).cross(&(x_old[tri[2] as usize] - a));
    let d = (x_old[p as usize] - a).dot(&n_old);
    let s = if d > 0.0 {
        1.0
    } else if d < 0.0 {
        -1.0
    } else {
        0.0
    };
    if n_old.dot(n) < 0.0 {
        -s
    } else {
        s
    }
}

/// Particle `i` and triangle `t` at `x` as a pair, if they make one (the caller has left out the
/// triangles holding `i` or a neighbour): not all four are pinned, and with `h` their contact
/// distance (`tri_h[t]` is the mean thickness of `t`'s corners), `i` is within `DETECT h` of
/// `t`'s plane and projects on it inside `t` with its edge lines moved out by `LATERAL h`.
#[inline]
fn pair_of(
    hash: &ClothHash,
    x_old: &[Point3],
    x: &[Point3],
    cloth: &SelfCloth<'_>,
    tri_h: &[f64],
    i: usize,
    t: u32,
) -> Option<Pair> {
    let (triangles, thickness, inv_mass) = (cloth.triangles, cloth.thickness, cloth.inv_mass);
    let p = x[i];
    let pl = &hash.planes[t as usize];
    let d = plane_at(pl, &p);
    if d.abs() >= hash.reach || pl[..3] == [0.0; 3] {
        return None;
    }
    let h = 0.5 * (thickness[i] + tri_h[t as usize]);
    if d.abs() >= DETECT * h {
        return None;
    }
    let sl = &hash.slabs[t as usize];
    let lat = -LATERAL * h;
    if plane_at(&sl[0], &p) <= lat || plane_at(&sl[1], &p) <= lat || plane_at(&sl[2], &p) <= lat {
        return None;
    }
    let tri = &triangles[t as usize];
    if inv_mass[i] == 0.0 && tri.iter().all(|&v| inv_mass[v as usize] == 0.0) {
        return None;
    }
    let mut side = old_side(x_old, tri, i as u32, &Vec3::new(pl[0], pl[1], pl[2]));
    if side == 0.0 {
        side = if d < 0.0 { -1.0 } else { 1.0 };
    }
    // Violated needs the projection inside (within `FACE_TOL` of the barycentric range: far
    // less than this slack inside the edges' lines) and the particle nearer than `h`.
    let slack = -1e-6 * (h + hash.cell);
    let maybe = side * d < h * (1.0 + 1e-6)
        && plane_at(&sl[0], &p) > slack
        && plane_at(&sl[1], &p) > slack
        && plane_at(&sl[2], &p) > slack;
    Some(Pair {
        p: i as u32,
        t,
        side,
        h,
        maybe,
    })
}

/// The pairs of particles `range` at `x` (appended to `out` in particle order).
fn find_pairs(
    hash: &ClothHash,
    x_old: &[Point3],
    x: &[Point3],
    cloth: &SelfCloth<'_>,
    tri_h: &[f64],
    range: std::ops::Range<usize>,
    out: &mut Vec<Pair>,
) {
    for i in range {
        hash.for_point_except(&x[i], hash.star_of(i as u32), |t| {
            if let Some(pair) = pair_of(hash, x_old, x, cloth, tri_h, i, t) {
                out.push(pair);
            }
        });
    }
}

/// The pair's vertices: the particle, then the triangle's corners.
#[inline]
fn verts(pair: &Pair, triangles: &[[u32; 3]]) -> [u32; 4] {
    let t = triangles[pair.t as usize];
    [pair.p, t[0], t[1], t[2]]
}

/// The contact distance violation `C` of a pair at `x` with the snapped barycentric weights of
/// the projection and the unit normal, if the projection is inside the triangle.
#[inline]
fn violation(pair: &Pair, x: &[Point3], triangles: &[[u32; 3]]) -> Option<(f64, [f64; 3], Vec3)> {
    let tri = &triangles[pair.t as usize];
    let (n, w, d) = face(x, tri, &x[pair.p as usize])?;
    inside(&w, FACE_TOL).then(|| (pair.side * d - pair.h, snap(w), n))
}

/// The inverse masses of a pair's vertices and its `W`.
#[inline]
fn inverse_masses(
    pair: &Pair,
    triangles: &[[u32; 3]],
    inv_mass: &[f64],
    w: &[f64; 3],
) -> ([f64; 4], f64) {
    let tri = &triangles[pair.t as usize];
    let im = [
        inv_mass[pair.p as usize],
        inv_mass[tri[0] as usize],
        inv_mass[tri[1] as usize],
        inv_mass[tri[2] as usize],
    ];
    (
        im,
        im[0] + w[0] * w[0] * im[1] + w[1] * w[1] * im[2] + w[2] * w[2] * im[3],
    )
}

/// The position correction of pair `e` at `x`, if it is violated.
#[inline]
fn position_push(
    e: u32,
    pair: &Pair,
    x: &[Point3],
    triangles: &[[u32; 3]],
    inv_mass: &[f64],
) -> Option<Push> {
    let (c, w, n) = violation(pair, x, triangles)?;
    if c >= 0.0 {
        return None;
    }
    let (im, big_w) = inverse_masses(pair, triangles, inv_mass, &w);
    if big_w <= 0.0 {
        return None;
    }
    Some(Push {
        pair: e,
        coef: [im[0], -w[0] * im[1], -w[1] * im[2], -w[2] * im[3]],
        share: [1.0, w[0], w[1], w[2]],
        dir: n * (pair.side * (-c / big_w)),
        tan: Vec3::zeros(),
    })
}

/// The velocity correction of pair `e` at `x`, `v`: the approaching normal relative velocity
/// removed, and Coulomb friction `mu` against the tangential one.
#[inline]
fn velocity_push(
    e: u32,
    pair: &Pair,
    x: &[Point3],
    v: &[Vec3],
    triangles: &[[u32; 3]],
    inv_mass: &[f64],
    mu: f64,
) -> Option<Push> {
    let (_, w, n) = violation(pair, x, triangles)?;
    let tri = &triangles[pair.t as usize];
    let u = v[pair.p as usize]
        - (v[tri[0] as usize] * w[0] + v[tri[1] as usize] * w[1] + v[tri[2] as usize] * w[2]);
    let un = pair.side * n.dot(&u);
    if un >= 0.0 {
        return None;
    }
    let (im, big_w) = inverse_masses(pair, triangles, inv_mass, &w);
    if big_w <= 0.0 {
        return None;
    }
    let pn = -un / big_w;
    let mut tan = Vec3::zeros();
    if mu > 0.0 {
        let ut = u - n * n.dot(&u);
        let l = ut.norm();
        if l > 0.0 {
            tan = ut * (-(mu * pn).min(l / big_w) / l);
        }
    }
    Some(Push {
        pair: e,
        coef: [im[0], -w[0] * im[1], -w[1] * im[2], -w[2] * im[3]],
        share: [1.0, w[0], w[1], w[2]],
        dir: n * (pair.side * pn) + tan,
        tan,
    })
}

/// Evaluates `eval(e)` for every pair `e` of `work.list` over fixed chunks (in parallel for long
/// lists) and keeps the violated ones in `work.push`, in list order; then builds the
/// vertex-to-push table and scales each push by `1 / max(1, max k_v)` over its moving vertices
/// (see the module docs). Returns the number of pushes.
fn evaluate(
    work: &mut Work,
    n: usize,
    triangles: &[[u32; 3]],
    eval: impl Fn(u32, &Pair) -> Option<Push> + Sync,
) -> usize {
    let len = work.list.len();
    let chunks = len.div_ceil(CHUNK);
    work.chunk_push
        .resize_with(chunks.max(work.chunk_push.len()), Vec::new);
    {
        let (list, pairs): (&[u32], &[Pair]) = (&work.list, &work.pairs);
        par::for_each_mut(
            &mut work.chunk_push[..chunks],
            par::parallel(len),
            |c, out| {
                out.clear();
                out.extend(
                    list[c * CHUNK..((c + 1) * CHUNK).min(len)]
                        .iter()
                        .filter_map(|&e| eval(e, &pairs[e as usize])),
                );
            },
        );
    }
    work.push.clear();
    for c in &work.chunk_push[..chunks] {
        work.push.extend_from_slice(c);
    }
    // The table (counting sort), and each vertex's count of pushes by their shares, in order.
    work.vstart.clear();
    work.vstart.resize(n + 1, 0);
    work.vshare.clear();
    work.vshare.resize(n, 0.0);
    for ps in &work.push {
        for (s, v) in verts(&work.pairs[ps.pair as usize], triangles)
            .into_iter()
            .enumerate()
        {
            if ps.coef[s] != 0.0 {
                work.vstart[v as usize + 1] += 1;
                work.vshare[v as usize] += ps.share[s];
            }
        }
    }
    for i in 0..n {
        work.vstart[i + 1] += work.vstart[i];
    }
    work.cursor.clear();
    work.cursor.extend_from_slice(&work.vstart[..n]);
    work.vlist.resize(work.vstart[n] as usize, 0);
    for (k, ps) in work.push.iter_mut().enumerate() {
        let vs = verts(&work.pairs[ps.pair as usize], triangles);
        let mut most = 1.0f64;
        for (s, &v) in vs.iter().enumerate() {
            if ps.coef[s] != 0.0 {
                let v = v as usize;
                work.vlist[work.cursor[v] as usize] = (4 * k + s) as u32;
                work.cursor[v] += 1;
                most = most.max(work.vshare[v]);
            }
        }
        ps.dir /= most;
        ps.tan /= most;
    }
    work.push.len()
}

/// The pushes of a pass and their vertex table, read by the per-vertex passes.
struct Table<'a> {
    push: &'a [Push],
    vstart: &'a [u32],
    vlist: &'a [u32],
}

impl Work {
    /// The vertex-to-push table, with the moved flags to write beside it (last iteration's,
    /// any iteration's).
    fn table(&mut self) -> (Table<'_>, &mut [bool], &mut [bool]) {
        let table = Table {
            push: &self.push,
            vstart: &self.vstart,
            vlist: &self.vlist,
        };
        (table, &mut self.moved_last, &mut self.moved_any)
    }
}

impl Table<'_> {
    /// `Σ coef dir` and `Σ coef tan` over the pushes moving vertex `v`, in table order.
    #[inline]
    fn gather(&self, v: usize) -> (Vec3, Vec3) {
        let mut d = Vec3::zeros();
        let mut t = Vec3::zeros();
        for &e in &self.vlist[self.vstart[v] as usize..self.vstart[v + 1] as usize] {
            let p = &self.push[e as usize / 4];
            let c = p.coef[e as usize % 4];
            d += p.dir * c;
            t += p.tan * c;
        }
        (d, t)
    }
}

/// The cloth as self-contact sees it: its triangles, and per particle its thickness (m) and
/// inverse mass (1/kg, 0 = pinned).
#[derive(Clone, Copy, Debug)]
pub struct SelfCloth<'a> {
    /// The cloth's triangles, as particle indices.
    pub triangles: &'a [[u32; 3]],
    /// Per particle, m.
    pub thickness: &'a [f64],
    /// Per particle, 1/kg; 0 = pinned.
    pub inv_mass: &'a [f64],
}

impl<'a> SelfCloth<'a> {
    /// Bundles the three arrays (same order as the fields).
    pub fn new(triangles: &'a [[u32; 3]], thickness: &'a [f64], inv_mass: &'a [f64]) -> Self {
        SelfCloth {
            triangles,
            thickness,
            inv_mass,
        }
    }
}

/// Self-contact after a step (see the module docs): particles closer than the contact distance to
/// a cloth triangle outside their 1-ring are pushed out to it, on the side they were on at
/// `x_old`, with the triangle's corners (mass-weighted), and the approaching relative normal
/// velocity is removed (with Coulomb friction if asked). `x_old` are the positions before the
/// step; `x`, `v` the step's new positions and velocities (corrected in place); `cloth` the
/// triangles, thicknesses and inverse masses; `dt` the step, s. Rebuilds `hash` at `x`.
pub fn resolve_self(
    x_old: &[Point3],
    x: &mut [Point3],
    v: &mut [Vec3],
    cloth: SelfCloth<'_>,
    hash: &mut ClothHash,
    opts: &SelfCollisionOptions,
    dt: f64,
) -> SelfStats {
    let start = Instant::now();
    let SelfCloth {
        triangles,
        thickness,
        inv_mass,
    } = cloth;
    debug_assert!(opts.validate().is_ok(), "{opts:?}");
    let n = x.len();
    assert!(
        x_old.len() == n && v.len() == n && thickness.len() == n && inv_mass.len() == n,
        "arrays of different lengths"
    );
    let mut stats = SelfStats::default();
    let h_max = par::max(n, |i| thickness[i]);
    if n == 0 || triangles.is_empty() || h_max <= 0.0 {
        stats.seconds = start.elapsed().as_secs_f64();
        return stats;
    }
    let cell = opts.cell.unwrap_or_else(|| {
        let m = AUTO_CELL * mean_edge_length(x, &hash.edges);
        if m > 0.0 {
            m
        } else {
            DETECT * h_max
        }
    });
    hash.build(x, triangles, cell, LATERAL * h_max, Some(DETECT * h_max));
    let mut work = std::mem::take(&mut hash.work);
    triangle_thickness(&mut work, triangles, thickness);
    gather_pairs(&mut work, hash, x_old, x, &cloth);
    let np = work.pairs.len();
    stats.candidates = np;
    work.ever.clear();
    work.ever.resize(np, false);
    for flags in [&mut work.moved_last, &mut work.moved_any] {
        flags.clear();
        flags.resize(n, false);
    }
    stats.contacts = position_passes(&mut work, x, &cloth, opts.iterations);
    // Velocities, for the pairs corrected above.
    work.list.clear();
    for e in 0..np {
        if work.ever[e] {
            work.list.push(e as u32);
        }
    }
    stats.corrected = work.list.len();
    stats.approaching = velocity_passes(&mut work, x, v, &cloth, opts, dt);
    stats.remaining = remaining(&work, x, triangles);
    hash.work = work;
    stats.seconds = start.elapsed().as_secs_f64();
    stats
}

/// Each triangle's thickness: the mean of its corners', m (`work.tri_h`).
fn triangle_thickness(work: &mut Work, triangles: &[[u32; 3]], thickness: &[f64]) {
    work.tri_h.resize(triangles.len(), 0.0);
    par::for_chunks(CHUNK * 4, &mut work.tri_h, |base, hs| {
        for (k, h) in hs.iter_mut().enumerate() {
            *h = triangles[base + k]
                .iter()
                .map(|&v| thickness[v as usize])
                .sum::<f64>()
                / 3.0;
        }
    });
}

/// The pairs of particle and triangle within reach (`work.pairs`), found per particle over
/// fixed chunks, in particle order.
fn gather_pairs(
    work: &mut Work,
    hash: &ClothHash,
    x_old: &[Point3],
    x: &[Point3],
    cloth: &SelfCloth<'_>,
) {
    let n = x.len();
    let chunks = n.div_ceil(CHUNK);
    work.chunks
        .resize_with(chunks.max(work.chunks.len()), Vec::new);
    let tri_h: &[f64] = &work.tri_h;
    par::for_each_mut(&mut work.chunks[..chunks], par::parallel(n), |c, out| {
        out.clear();
        let r = c * CHUNK..((c + 1) * CHUNK).min(n);
        find_pairs(hash, x_old, x, cloth, tri_h, r, out);
    });
    work.pairs.clear();
    for c in &work.chunks[..chunks] {
        work.pairs.extend_from_slice(c);
    }
}

/// Up to `iterations` passes pushing the particles of violated pairs out (positions `x`
/// corrected in place): the first evaluates the pairs possibly violated where they were
/// found, each later pass those with a vertex the last correction moved (a pair can only
/// change when one of its vertices moves). The first pass's count of contacts.
fn position_passes(
    work: &mut Work,
    x: &mut [Point3],
    cloth: &SelfCloth<'_>,
    iterations: usize,
) -> usize {
    let (n, triangles, inv_mass) = (x.len(), cloth.triangles, cloth.inv_mass);
    let mut contacts = 0;
    work.list.clear();
    for (e, pair) in work.pairs.iter().enumerate() {
        if pair.maybe {
            work.list.push(e as u32);
        }
    }
    for it in 0..iterations {
        if it > 0 {
            let Work {
                list,
                pairs,
                moved_last,
                ..
            } = &mut *work;
            list.clear();
            for (e, pair) in pairs.iter().enumerate() {
                if verts(pair, triangles)
                    .iter()
                    .any(|&v| moved_last[v as usize])
                {
                    list.push(e as u32);
                }
            }
        }
        let active = {
            let xr: &[Point3] = x;
            evaluate(work, n, triangles, |e, pair| {
                position_push(e, pair, xr, triangles, inv_mass)
            })
        };
        if it == 0 {
            contacts = active;
        }
        if active == 0 {
            break;
        }
        for ps in &work.push {
            work.ever[ps.pair as usize] = true;
        }
        let (table, moved_last, moved_any) = work.table();
        let vstart = table.vstart;
        par::for_chunks3(CHUNK, n, x, moved_last, moved_any, |base, xs, last, any| {
            for k in 0..xs.len() {
                let v = base + k;
                let moves = vstart[v] < vstart[v + 1];
                xs[k] += table.gather(v).0;
                last[k] = moves;
                any[k] |= moves;
            }
        });
    }
    contacts
}

/// Up to `opts.iterations` passes over the pairs listed in `work.list` removing their
/// approaching relative normal velocity (with Coulomb friction when asked; friction's
/// tangential change also moves `x` by `dt` times it). The first pass's count of approaching
/// pairs.
fn velocity_passes(
    work: &mut Work,
    x: &mut [Point3],
    v: &mut [Vec3],
    cloth: &SelfCloth<'_>,
    opts: &SelfCollisionOptions,
    dt: f64,
) -> usize {
    let (n, triangles, inv_mass) = (x.len(), cloth.triangles, cloth.inv_mass);
    let mut approaching = 0;
    for it in 0..opts.iterations {
        let active = {
            let (xr, vr): (&[Point3], &[Vec3]) = (x, v);
            evaluate(work, n, triangles, |e, pair| {
                velocity_push(e, pair, xr, vr, triangles, inv_mass, opts.friction)
            })
        };
        if it == 0 {
            approaching = active;
        }
        if active == 0 {
            break;
        }
        let (table, _, moved_any) = work.table();
        let vstart = table.vstart;
        let friction = opts.friction > 0.0;
        par::for_chunks3(CHUNK, n, x, v, moved_any, |base, xs, vs, any| {
            for k in 0..xs.len() {
                let v = base + k;
                let (d, t) = table.gather(v);
                vs[k] += d;
                xs[k] += t * dt;
                any[k] |= friction && vstart[v] < vstart[v + 1];
            }
        });
    }
    approaching
}

/// The pairs still closer than the contact distance: among those with a vertex moved in this
/// call, and those possibly violated where found (the others are as they were found: apart).
fn remaining(work: &Work, x: &[Point3], triangles: &[[u32; 3]]) -> usize {
    let (pairs, any): (&[Pair], &[bool]) = (&work.pairs, &work.moved_any);
    map_chunks(pairs.len(), |r| {
        r.filter(|&e| {
            let pair = &pairs[e];
            (pair.maybe || verts(pair, triangles).iter().any(|&v| any[v as usize]))
                && matches!(violation(pair, x, triangles), Some((c, _, _)) if c < -REMAIN_TOL * pair.h)
        })
        .count()
    })
    .into_iter()
    .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::sheets::{crumpled, grid, join};
    use crate::math::SplitMix;
    use crate::mesh::closest::closest_on_triangle;
    use crate::mesh::generate;

    /// One `resolve_self` with the default options and a 1 ms step.
    fn step(
        x_old: &[Point3],
        x: &mut [Point3],
        v: &mut [Vec3],
        cloth: SelfCloth<'_>,
        hash: &mut ClothHash,
    ) -> SelfStats {
        let opts = SelfCollisionOptions::default();
        resolve_self(x_old, x, v, cloth, hash, &opts, 1e-3)
    }

    /// Two 0.1 m squares of `k x k` particles, `b` at height `zb` over `a` at 0.
    pub(super) fn squares(k: usize, zb: f64) -> (Vec<Point3>, Vec<[u32; 3]>) {
        let s = 0.1 / (k - 1) as f64;
        let a = grid(k, k, 0, |i, j| Point3::new(i as f64 * s, j as f64 * s, 0.0));
        let b = grid(k, k, 0, |i, j| Point3::new(i as f64 * s, j as f64 * s, zb));
        join(a, b)
    }

    /// The smallest distance from a particle of one half to a triangle of the other.
    fn min_gap(x: &[Point3], t: &[[u32; 3]], half: usize) -> f64 {
        let mut m = f64::INFINITY;
        let ht = t.len() / 2;
        for (i, p) in x.iter().enumerate() {
            let other = if i < half { &t[ht..] } else { &t[..ht] };
            for tri in other {
                let [a, b, c] = tri.map(|v| x[v as usize]);
                m = m.min((p - closest_on_triangle(p, &a, &b, &c)).norm());
            }
        }
        m
    }

    /// The smallest distance along the normal from a particle of one half to a triangle of the
    /// other that it projects inside (what the constraint holds; a particle beside the other
    /// sheet's boundary edge is not held).
    fn min_gap_inside(x: &[Point3], t: &[[u32; 3]], half: usize) -> f64 {
        let mut m = f64::INFINITY;
        let ht = t.len() / 2;
        for (i, p) in x.iter().enumerate() {
            let other = if i < half { &t[ht..] } else { &t[..ht] };
            for tri in other {
                if let Some((_, w, d)) = face(x, tri, p) {
                    if inside(&w, FACE_TOL) {
                        m = m.min(d.abs());
                    }
                }
            }
        }
        m
    }

    fn momentum(v: &[Vec3], inv_mass: &[f64]) -> Vec3 {
        v.iter().zip(inv_mass).map(|(v, w)| v / *w).sum()
    }

    #[test]
    fn parallel_squares_are_pushed_to_the_thickness_and_keep_their_momentum() {
        let k = 11;
        let (x0, t) = squares(k, 1e-3);
        let n = x0.len();
        let th = vec![3e-3; n];
        let im = vec![1.0 / 0.01; n];
        // b falls on a at 0.5 m/s.
        let mut v: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(0.0, 0.0, if i < n / 2 { 0.0 } else { -0.5 }))
            .collect();
        let p0 = momentum(&v, &im);
        let mut x = x0.clone();
        let mut hash = ClothHash::new(n, &t, &[]);
        let s = step(&x0, &mut x, &mut v, SelfCloth::new(&t, &th, &im), &mut hash);
        assert!(s.contacts > 0 && s.remaining == 0, "{s:?}");
        let gap = min_gap(&x, &t, n / 2);
        assert!(gap >= 3e-3 - 1e-9, "gap {gap}");
        for i in 0..n / 2 {
            assert!((x[i + n / 2].z - x[i].z - 3e-3).abs() < 1e-12);
            // Inelastic: they now move together.
            assert!(
                (v[i + n / 2].z - v[i].z).abs() < 1e-12,
                "{:?} {:?}",
                v[i],
                v[i + n / 2]
            );
        }
        assert!((momentum(&v, &im) - p0).norm() < 1e-12 * p0.norm());
    }

    #[test]
    fn a_square_that_tunnelled_goes_back_to_its_old_side() {
        let k = 11;
        let (x_old, t) = squares(k, 1e-3);
        // During the step b passed through a to 1 mm below.
        let (x_new, _) = squares(k, -1e-3);
        let n = x_old.len();
        let th = vec![3e-3; n];
        let im = vec![1.0 / 0.01; n];
        let mut v: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(0.0, 0.0, if i < n / 2 { 0.0 } else { -2.0 }))
            .collect();
        let mut x = x_new.clone();
        let mut hash = ClothHash::new(n, &t, &[]);
        step(
            &x_old,
            &mut x,
            &mut v,
            SelfCloth::new(&t, &th, &im),
            &mut hash,
        );
        for i in 0..n / 2 {
            assert!(
                (x[i + n / 2].z - x[i].z - 3e-3).abs() < 1e-12,
                "b above a again: {:?} {:?}",
                x[i],
                x[i + n / 2]
            );
        }
        assert!(min_gap(&x, &t, n / 2) >= 3e-3 - 1e-9);
    }

    #[test]
    fn unequal_masses_and_offset_layers_converge_and_keep_momentum() {
        // b shifted off a's grid, masses random, velocities random: Jacobi needs iterations, and
        // momentum is kept in every one (with friction too).
        let k = 11;
        let s = 0.1 / (k - 1) as f64;
        let a = grid(k, k, 0, |i, j| Point3::new(i as f64 * s, j as f64 * s, 0.0));
        let b = grid(k, k, 0, |i, j| {
            Point3::new(
                (i as f64 + 0.37) * s * 0.9,
                (j as f64 + 0.21) * s * 0.9,
                1e-3,
            )
        });
        let (x0, t) = join(a, b);
        let n = x0.len();
        let mut rng = SplitMix(7);
        let im: Vec<f64> = (0..n)
            .map(|_| 1.0 / (0.005 + 0.01 * rng.next_f64()))
            .collect();
        let v0: Vec<Vec3> = (0..n)
            .map(|_| {
                Vec3::new(
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                    rng.next_f64() - 0.5,
                )
            })
            .collect();
        let th = vec![3e-3; n];
        let p0 = momentum(&v0, &im);
        let scale: f64 = v0.iter().zip(&im).map(|(v, w)| v.norm() / w).sum();
        let mut remaining = Vec::new();
        for (iterations, friction) in [(2, 0.0), (8, 0.0), (64, 0.4)] {
            let (mut x, mut v) = (x0.clone(), v0.clone());
            let mut hash = ClothHash::new(n, &t, &[]);
            let opts = SelfCollisionOptions {
                iterations,
                friction,
                cell: None,
            };
            let st = resolve_self(
                &x0,
                &mut x,
                &mut v,
                SelfCloth::new(&t, &th, &im),
                &mut hash,
                &opts,
                1e-3,
            );
            let dp = (momentum(&v, &im) - p0).norm();
            assert!(dp < 1e-13 * scale, "{iterations} {friction}: {dp}");
            // The centre of mass stays too.
            let c0: Vec3 = x0.iter().zip(&im).map(|(p, w)| p.coords / *w).sum();
            let c1: Vec3 = x.iter().zip(&im).map(|(p, w)| p.coords / *w).sum();
            assert!((c1 - c0).norm() < 1e-14 * n as f64, "{iterations}");
            remaining.push((st.remaining, min_gap_inside(&x, &t, n / 2)));
        }
        // Two iterations leave some; eight settle it (each pair counted at a vertex by its
        // share: counted by one, 89 pairs remain after eight, 18 after 32).
        assert!(
            remaining[0].0 > 0,
            "two iterations do not settle it: {remaining:?}"
        );
        assert!(remaining[1].0 == 0, "{remaining:?}");
        assert!(remaining[1].1 >= 3e-3 - 1e-9, "{remaining:?}");
    }

    #[test]
    fn a_pair_a_correction_brings_close_is_corrected_in_the_same_call() {
        // Three aligned squares 3 mm thick: a pinned at 0, b at 1 mm, c at 4.2 mm. b and c start
        // 3.2 mm apart (within reach, not in contact); the first iteration pushes b off a to
        // 3 mm, 1.2 mm from c; the second must push b and c apart.
        let k = 6;
        let s = 0.1 / (k - 1) as f64;
        let layer = |z: f64| {
            grid(k, k, 0, move |i, j| {
                Point3::new(i as f64 * s, j as f64 * s, z)
            })
        };
        let (x0, t) = join(join(layer(0.0), layer(1e-3)), layer(4.2e-3));
        let (n, m) = (x0.len(), k * k);
        let th = vec![3e-3; n];
        let im: Vec<f64> = (0..n).map(|i| if i < m { 0.0 } else { 100.0 }).collect();
        let (mut x, mut v) = (x0.clone(), vec![Vec3::zeros(); n]);
        let mut h = ClothHash::new(n, &t, &[]);
        let st = step(&x0, &mut x, &mut v, SelfCloth::new(&t, &th, &im), &mut h);
        assert!(st.corrected > st.contacts, "{st:?}");
        for i in 0..m {
            assert_eq!(x[i], x0[i], "a is pinned");
            assert!(
                x[2 * m + i].z > 4.2e-3 + 5e-4,
                "c pushed up: {:?}",
                x[2 * m + i]
            );
        }
    }

    #[test]
    fn friction_slows_sliding_layers() {
        let k = 11;
        let (x0, t) = squares(k, 1e-3);
        let n = x0.len();
        let th = vec![3e-3; n];
        let im = vec![100.0; n];
        let v0: Vec<Vec3> = (0..n)
            .map(|i| {
                if i < n / 2 {
                    Vec3::zeros()
                } else {
                    Vec3::new(0.3, 0.0, -0.5)
                }
            })
            .collect();
        let slide = |friction: f64| {
            let (mut x, mut v) = (x0.clone(), v0.clone());
            let mut hash = ClothHash::new(n, &t, &[]);
            let opts = SelfCollisionOptions {
                friction,
                ..Default::default()
            };
            resolve_self(
                &x0,
                &mut x,
                &mut v,
                SelfCloth::new(&t, &th, &im),
                &mut hash,
                &opts,
                1e-3,
            );
            assert!((momentum(&v, &im) - momentum(&v0, &im)).norm() < 1e-12);
            v[n - 1].x - v[0].x
        };
        assert!((slide(0.0) - 0.3).abs() < 1e-12);
        // mu |dv_n| = 0.2 x 0.5 of the relative sliding speed goes.
        assert!((slide(0.2) - 0.2).abs() < 1e-9, "{}", slide(0.2));
        assert!(slide(1.0).abs() < 1e-12, "stuck");
    }

    #[test]
    fn sewn_pieces_do_not_push_at_their_seam() {
        // Two pieces meeting at a right angle along a seam of coincident particles.
        let k = 6;
        let s = 0.02;
        let a = grid(k, k, 0, |i, j| Point3::new(i as f64 * s, j as f64 * s, 0.0));
        let b = grid(k, k, 0, |i, j| Point3::new(0.0, j as f64 * s, i as f64 * s));
        let (x0, t) = join(a, b);
        let n = x0.len();
        let seams: Vec<[u32; 2]> = (0..k as u32).map(|j| [j, (k * k) as u32 + j]).collect();
        let th = vec![3e-3; n];
        let im = vec![100.0; n];
        let run = |seams: &[[u32; 2]]| {
            let (mut x, mut v) = (x0.clone(), vec![Vec3::zeros(); n]);
            let mut hash = ClothHash::new(n, &t, seams);
            let st = step(&x0, &mut x, &mut v, SelfCloth::new(&t, &th, &im), &mut hash);
            (st, x == x0, self_crossing_edges(&x0, &t, &hash))
        };
        let (st, same, crossing) = run(&seams);
        assert_eq!((st.candidates, same, crossing), (0, true, 0), "{st:?}");
        let (st, same, _) = run(&[]);
        assert!(
            st.contacts > 0 && !same,
            "unsewn, the seam's sides collide: {st:?}"
        );
    }

    /// A sheet extruded along y from a profile of columns `(x, z, y0, y1)`, `rows` particles per
    /// column.
    fn extrude(cols: &[(f64, f64, f64, f64)], rows: usize) -> (Vec<Point3>, Vec<[u32; 3]>) {
        grid(cols.len(), rows, 0, |i, j| {
            let (x, z, y0, y1) = cols[i];
            Point3::new(x, y0 + (y1 - y0) * j as f64 / (rows - 1) as f64, z)
        })
    }

    fn rebuilt(x: &[Point3], t: &[[u32; 3]]) -> ClothHash {
        let mut h = ClothHash::new(x.len(), t, &[]);
        let cell = mean_edge_length(x, h.edges());
        h.rebuild(x, t, cell, 0.0);
        h
    }

    /// Brute force: every edge against every triangle sharing no vertex with it.
    fn crossing_edges_brute(x: &[Point3], t: &[[u32; 3]]) -> usize {
        cloth_edges(t)
            .iter()
            .filter(|e| {
                t.iter().any(|tri| {
                    !tri.contains(&e[0])
                        && !tri.contains(&e[1])
                        && segment_crosses_triangle(
                            &x[e[0] as usize],
                            &x[e[1] as usize],
                            &x[tri[0] as usize],
                            &x[tri[1] as usize],
                            &x[tri[2] as usize],
                        )
                })
            })
            .count()
    }

    #[test]
    fn a_flat_sheet_does_not_cross_itself() {
        // In a general plane (coplanar points then give rounding noise, not exact zeros), and in
        // a plane of constant z.
        let (u, w) = (
            Vec3::new(0.8, 0.36, -0.48),
            Vec3::new(-0.28, 0.96, 0.0).normalize(),
        );
        let origin = Point3::new(0.31, -0.27, 1.13);
        for tilted in [true, false] {
            let (x, t) = grid(30, 20, 0, |i, j| {
                let (a, b) = (0.013 * i as f64, 0.017 * j as f64);
                if tilted {
                    origin + u * a + w * b
                } else {
                    Point3::new(a, b, 0.4)
                }
            });
            let h = rebuilt(&x, &t);
            assert_eq!(self_crossing_edges(&x, &t, &h), 0, "tilted {tilted}");
            assert!(self_crossings(&x, &t, &h).is_empty());
            assert_eq!(crossing_edges_brute(&x, &t), 0, "tilted {tilted}");
        }
    }

    #[test]
    fn a_flap_folded_through_the_sheet_crosses_along_the_line() {
        // The profile: flat along z = 0 from x = 0 to 1 (columns every 0.1), up at x = 1 to
        // z = 0.5, back along z = 0.5 to x = 0.53, then down through the flat part to z = -0.3
        // (columns every 0.08 from z = 0.5: z = 0 falls between 0.02 and -0.06). Over the top
        // the rows narrow from y in [0, 1] to the flap's [0.152, 0.845]. 11 rows.
        let mut cols: Vec<(f64, f64, f64, f64)> = Vec::new();
        for i in 0..=10 {
            cols.push((0.1 * i as f64, 0.0, 0.0, 1.0));
        }
        for i in 1..=5 {
            cols.push((1.0, 0.1 * i as f64, 0.0, 1.0));
        }
        let top = [0.9, 0.8, 0.7, 0.6, 0.53];
        for (i, &x) in top.iter().enumerate() {
            let f = (i + 1) as f64 / top.len() as f64;
            cols.push((x, 0.5, 0.152 * f, 1.0 - 0.155 * f));
        }
        for i in 1..=10 {
            cols.push((0.53, 0.5 - 0.08 * i as f64, 0.152, 0.845));
        }
        let (x, t) = extrude(&cols, 11);
        // The flap meets z = 0 along x = 0.53, y in [0.152, 0.845], inside the flat part.
        // Flap edges through the flat part: those of its strip between z = 0.02 and -0.06: 11
        // rows and 10 diagonals, all inside y in (0, 1), none on a flat-part edge (the flat
        // part's edges meet x = 0.53 at y = 0.1 m and 0.1 m + 0.03).
        // Edges of the flat part through the flap: its strip between x = 0.5 and 0.6; rows at
        // y = 0.1 m and diagonals at y = 0.1 m + 0.03 (0.3 of the way along), those strictly
        // inside (0.152, 0.845): rows m = 2..8 (7) and diagonals m = 2..8 (7).
        let expected = 21 + 14;
        let h = rebuilt(&x, &t);
        assert_eq!(self_crossing_edges(&x, &t, &h), expected);
        assert_eq!(crossing_edges_brute(&x, &t), expected);
        let pairs = self_crossings(&x, &t, &h);
        let mut once = pairs.clone();
        once.sort_unstable();
        once.dedup();
        assert_eq!(once.len(), pairs.len(), "each (edge, triangle) once");
        let mut edges: Vec<[u32; 2]> = pairs.iter().map(|p| p.0).collect();
        edges.dedup();
        assert_eq!(edges.len(), expected);
    }

    #[test]
    fn two_sheets_in_an_x_cross_along_their_line() {
        // Sheet 1 in the plane through the y axis at angle 0.5 rad from the xy plane, sheet 2 at
        // -0.5 rad; they meet along the y axis. In each sheet's own coordinate s (across the
        // line), the line is s = 0.
        let (c, sn) = (0.5f64.cos(), 0.5f64.sin());
        // Sheet 1: s = -0.47 + 0.1 i (0 is 0.7 of the way from -0.07 to 0.03), y = 0.1 j.
        let s1 = grid(10, 11, 0, |i, j| {
            let s = -0.47 + 0.1 * i as f64;
            Point3::new(s * c, 0.1 * j as f64, s * sn)
        });
        // Sheet 2: s = -0.44 + 0.1 i (0 is 0.4 of the way from -0.04 to 0.06),
        // y = -0.0513 + 0.1107 j.
        let y2 = |j: usize| -0.0513 + 0.1107 * j as f64;
        let s2 = grid(10, 11, 0, |i, j| {
            let s = -0.44 + 0.1 * i as f64;
            Point3::new(s * c, y2(j), -s * sn)
        });
        // Sheet 1's strip edges meet the line at y = 0.1 j (rows) and 0.1 j + 0.07 (diagonals),
        // all inside sheet 2's y range [-0.0513, 1.0557]: 11 + 10.
        let mut expected = 21;
        // Sheet 2's at y2(j) (rows) and y2(j) + 0.4 x 0.1107 (diagonals), counted inside (0, 1).
        for j in 0..11 {
            expected += usize::from(y2(j) > 0.0 && y2(j) < 1.0);
            if j < 10 {
                let y = y2(j) + 0.4 * 0.1107;
                expected += usize::from(y > 0.0 && y < 1.0);
            }
        }
        assert_eq!(expected, 21 + 9 + 9);
        let (x, t) = join(s1, s2);
        let h = rebuilt(&x, &t);
        assert_eq!(self_crossing_edges(&x, &t, &h), expected);
        assert_eq!(crossing_edges_brute(&x, &t), expected);
    }

    #[test]
    fn body_crossings_of_a_sheet_through_a_sphere() {
        let sphere = generate::icosphere(3);
        // Convex: inside is behind every face plane.
        let collider = Collider::new("ball".into(), sphere, [12, 12, 12], 0.003, None);
        let (x, t) = grid(41, 37, 0, |i, j| {
            Point3::new(
                -1.3 + 0.0651 * i as f64,
                -1.2 + 0.0663 * j as f64,
                0.1234 + 0.01 * i as f64,
            )
        });
        let count = body_crossing_edges(&collider, &x, &t);
        // Each edge against every face.
        let edges = cloth_edges(&t);
        let brute = edges
            .iter()
            .filter(|e| {
                (0..collider.mesh.faces.len()).any(|f| {
                    let [a, b, c] = collider.mesh.corners(f);
                    segment_crosses_triangle(&x[e[0] as usize], &x[e[1] as usize], &a, &b, &c)
                })
            })
            .count();
        // Analytically for a convex body: an edge crosses the surface when one end is inside,
        // or when both are outside and its part behind every plane has positive length.
        let analytic = edges
            .iter()
            .filter(|e| {
                let (p, q) = (x[e[0] as usize], x[e[1] as usize]);
                let (mut t0, mut t1) = (0.0f64, 1.0f64);
                let mut inside = [true, true];
                for f in 0..collider.mesh.faces.len() {
                    let (nrm, off) = collider.plane(f);
                    let (dp, dq) = (nrm.dot(&p.coords) - off, nrm.dot(&q.coords) - off);
                    inside[0] &= dp < 0.0;
                    inside[1] &= dq < 0.0;
                    if dp >= 0.0 && dq >= 0.0 {
                        t1 = -1.0;
                    } else if dp >= 0.0 {
                        t0 = t0.max(dp / (dp - dq));
                    } else if dq >= 0.0 {
                        t1 = t1.min(dp / (dp - dq));
                    }
                }
                inside[0] != inside[1] || (!inside[0] && !inside[1] && t1 > t0)
            })
            .count();
        assert!(count > 100, "{count}");
        assert_eq!(count, brute);
        assert_eq!(count, analytic);
        let far: Vec<Point3> = x.iter().map(|p| p + Vec3::new(0.0, 0.0, 5.0)).collect();
        assert_eq!(body_crossing_edges(&collider, &far, &t), 0);
    }

    #[test]
    fn the_hash_finds_the_pairs_a_brute_force_search_finds() {
        let (x, t) = crumpled(24, 0.2, 11, 0.0004);
        let n = x.len();
        let mut rng = SplitMix(3);
        let th: Vec<f64> = (0..n).map(|_| 0.002 + 0.002 * rng.next_f64()).collect();
        let im: Vec<f64> = (0..n).map(|i| if i % 7 == 0 { 0.0 } else { 1.0 }).collect();
        let x_old = x.clone();
        let hmax = th.iter().cloned().fold(0.0, f64::max);
        let mut h = ClothHash::new(n, &t, &[]);
        let mean = mean_edge_length(&x, h.edges());
        h.build(&x, &t, mean, LATERAL * hmax, Some(DETECT * hmax));
        let tri_h: Vec<f64> = t
            .iter()
            .map(|tri| tri.iter().map(|&v| th[v as usize]).sum::<f64>() / 3.0)
            .collect();
        // Every (particle, triangle): the pair test against its definition, and the brute list.
        let mut brute = Vec::new();
        for i in 0..n {
            let star: Vec<u32> = t
                .iter()
                .filter(|s| s.contains(&(i as u32)))
                .flatten()
                .copied()
                .collect();
            for (ti, tri) in t.iter().enumerate() {
                let got = !h.excluded(i as u32, ti)
                    && pair_of(
                        &h,
                        &x_old,
                        &x,
                        &SelfCloth::new(&t, &th, &im),
                        &tri_h,
                        i,
                        ti as u32,
                    )
                    .is_some();
                let c = tri.map(|v| x[v as usize]);
                let nrm = (c[1] - c[0]).cross(&(c[2] - c[0])).normalize();
                let hh = 0.5 * (th[i] + tri.iter().map(|&v| th[v as usize]).sum::<f64>() / 3.0);
                // The projection, and its distance inside each edge's line.
                let d = (x[i] - c[0]).dot(&nrm);
                let q = x[i] - nrm * d;
                let inside_by = (0..3)
                    .map(|k| {
                        let e = c[(k + 1) % 3] - c[k];
                        nrm.cross(&e).dot(&(q - c[k])) / e.norm()
                    })
                    .fold(f64::INFINITY, f64::min);
                let in_star = tri.iter().any(|v| star.contains(v));
                let all_pinned = im[i] == 0.0 && tri.iter().all(|&v| im[v as usize] == 0.0);
                let want =
                    !in_star && !all_pinned && d.abs() < DETECT * hh && inside_by > -LATERAL * hh;
                assert_eq!(got, want, "particle {i}, triangle {ti}");
                if got {
                    brute.push((i as u32, ti as u32));
                }
            }
        }
        assert!(brute.len() > 500, "{}", brute.len());
        // Cubes from far smaller than a triangle (most on the list every query reads) to larger.
        // Boxes as `resolve_self` grows them, cubes from far smaller than a triangle (most on
        // the list every query reads) to larger.
        for cell in [mean / 20.0, mean / 3.0, mean, 4.0 * mean] {
            h.build(&x, &t, cell, LATERAL * hmax, Some(DETECT * hmax));
            let mut found = Vec::new();
            find_pairs(
                &h,
                &x_old,
                &x,
                &SelfCloth::new(&t, &th, &im),
                &tri_h,
                0..n,
                &mut found,
            );
            // Every violated pair is flagged for the first iteration.
            for pair in &found {
                if matches!(violation(pair, &x, &t), Some((c, _, _)) if c < 0.0) {
                    assert!(pair.maybe, "{pair:?}");
                }
            }
            assert!(found.iter().any(|p| p.maybe) && found.iter().any(|p| !p.maybe));
            let found: Vec<(u32, u32)> = found.iter().map(|p| (p.p, p.t)).collect();
            let mut sorted = found.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), found.len(), "each pair once (cell {cell})");
            assert!(
                sorted == brute,
                "cell {cell}: {} pairs, {} by brute force",
                sorted.len(),
                brute.len()
            );
        }
        // Edge queries against the brute force too.
        h.rebuild(&x, &t, mean, 0.0);
        let crossing = self_crossing_edges(&x, &t, &h);
        assert!(crossing > 0);
        assert_eq!(crossing, crossing_edges_brute(&x, &t));
        h.rebuild(&x, &t, mean / 20.0, 0.0);
        assert!(h.big() > 0);
        assert_eq!(self_crossing_edges(&x, &t, &h), crossing);
    }

    #[test]
    fn one_and_two_threads_give_the_same_bits() {
        let (x0, t) = crumpled(64, 0.5, 5, 0.002);
        let n = x0.len();
        assert!(n >= par::PARALLEL_MIN);
        // The step moved every particle a little, some through a neighbouring layer.
        let mut rng = SplitMix(9);
        let x1: Vec<Point3> = x0
            .iter()
            .map(|p| p + Vec3::new(rng.next_f64(), rng.next_f64(), 4.0 * rng.next_f64()) * 1e-3)
            .collect();
        let v1: Vec<Vec3> = (0..n)
            .map(|_| Vec3::new(0.0, 0.0, -0.3 * rng.next_f64()))
            .collect();
        let th = vec![0.003; n];
        let im: Vec<f64> = (0..n)
            .map(|i| if i % 97 == 0 { 0.0 } else { 50.0 })
            .collect();
        let sphere = Collider::new(
            "s".into(),
            generate::uv_sphere(Point3::new(0.05, 0.25, 0.0), 0.08, 12, 24),
            [8, 8, 8],
            0.003,
            None,
        );
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let (mut x, mut v) = (x1.clone(), v1.clone());
                    let mut h = ClothHash::new(n, &t, &[]);
                    let opts = SelfCollisionOptions {
                        friction: 0.3,
                        ..Default::default()
                    };
                    let mut st = resolve_self(
                        &x0,
                        &mut x,
                        &mut v,
                        SelfCloth::new(&t, &th, &im),
                        &mut h,
                        &opts,
                        1e-3,
                    );
                    st.seconds = 0.0;
                    // A second step reuses the buffers.
                    let x_prev = x.clone();
                    let st2 = resolve_self(
                        &x_prev,
                        &mut x,
                        &mut v,
                        SelfCloth::new(&t, &th, &im),
                        &mut h,
                        &opts,
                        1e-3,
                    );
                    // Crossings after the steps, and of the step's input.
                    let cell = h.cell();
                    h.rebuild(&x, &t, cell, 0.0);
                    let mut crossings = self_crossings(&x, &t, &h);
                    h.rebuild(&x1, &t, cell, 0.0);
                    crossings.extend(self_crossings(&x1, &t, &h));
                    let body = body_crossing_edges(&sphere, &x, &t);
                    (x, v, st, st2.candidates, crossings, body)
                })
        };
        let one = run(1);
        let two = run(2);
        // Long enough for every loop to run in parallel with two threads.
        assert!(one.2.candidates > par::PARALLEL_MIN, "{:?}", one.2);
        assert!(one.2.contacts > par::PARALLEL_MIN, "{:?}", one.2);
        assert!(!one.4.is_empty());
        assert!(one.5 > 0);
        assert_eq!(one, two);
    }

    #[test]
    #[should_panic(expected = "built at other positions")]
    fn crossings_need_a_hash_built_at_the_positions() {
        let (x, t) = squares(5, 1e-3);
        let mut h = ClothHash::new(x.len(), &t, &[]);
        h.rebuild(&x, &t, 0.03, 0.0);
        let moved: Vec<Point3> = x.iter().map(|p| p + Vec3::new(0.0, 0.0, 1e-3)).collect();
        self_crossing_edges(&moved, &t, &h);
    }

    #[test]
    fn options_are_checked() {
        assert_eq!(SelfCollisionOptions::default().validate(), Ok(()));
        let bad = |o: SelfCollisionOptions| o.validate().is_err();
        assert!(bad(SelfCollisionOptions {
            iterations: 0,
            ..Default::default()
        }));
        assert!(bad(SelfCollisionOptions {
            friction: -0.1,
            ..Default::default()
        }));
        assert!(bad(SelfCollisionOptions {
            cell: Some(0.0),
            ..Default::default()
        }));
        assert!(bad(SelfCollisionOptions {
            cell: Some(f64::NAN),
            ..Default::default()
        }));
    }
}
