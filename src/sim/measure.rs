//! What a run measures at its end: strain, particles inside objects, clearance, the drape
//! coefficient.

use super::World;
use crate::cloth::elements::SpringKind;
use crate::cloth::model::ClothModel;
use crate::collide::Collider;
use crate::math::{Point3, Vec3};
use rayon::prelude::*;

/// Largest and mean strain (edge length over rest length, minus one) of the stretch springs.
pub fn strain(model: &ClothModel, x: &[Point3]) -> (f64, f64) {
    let s: Vec<f64> = model
        .springs
        .iter()
        .filter(|s| s.kind == SpringKind::Stretch)
        .map(|s| (x[s.b as usize] - x[s.a as usize]).norm() / s.rest - 1.0)
        .collect();
    if s.is_empty() {
        return (0.0, 0.0);
    }
    (
        s.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        s.iter().sum::<f64>() / s.len() as f64,
    )
}

/// Whether `p` is inside the surface of `c`: its winding number is positive. Closed objects
/// count the crossings of a ray through the object's grid (exact, O(cells along the ray)); open
/// ones, and points on the surface to rounding, use the generalized winding number (above 1/2:
/// robust to small holes). See `collide::inside`.
pub fn inside(c: &Collider, p: &Point3) -> bool {
    crate::collide::inside::inside(c, p)
}

/// Particles inside a closed object, per object (`None` for open objects).
pub fn particles_inside(world: &World) -> Vec<Option<usize>> {
    world
        .colliders
        .iter()
        .map(|c| {
            c.closed
                .then(|| world.state.x.par_iter().filter(|p| inside(c, p)).count())
        })
        .collect()
}

/// How many times larger (or smaller) than the cloth an object may be across (box diagonals)
/// before its placement is suspect. A body in centimetres in a metre scene is 100 times too
/// large, which makes it 60 to 200 times a garment; real scenes stay below 20 (a 30 cm
/// specimen on a 3 m floor: 10).
pub const SCALE_WARN: f64 = 50.0;

/// What looks wrong with a scene before it runs: an object [`SCALE_WARN`] times larger or
/// smaller than the cloth across (units), and cloth that starts inside a closed object (no
/// collision can push it out: it is behind the faces). A message per finding, for the user.
pub fn placement_warnings(world: &World) -> Vec<String> {
    let Some(cloth) = crate::math::Aabb::of_points(&world.state.x) else {
        return Vec::new();
    };
    let across = cloth.diagonal();
    let short = crate::math::short;
    let mut out = Vec::new();
    let inside = particles_inside(world);
    for (c, n) in world.colliders.iter().zip(inside) {
        let Some(b) = crate::math::Aabb::of_points(&c.mesh.positions) else {
            continue;
        };
        let ratio = b.diagonal() / across;
        if !(1.0 / SCALE_WARN..=SCALE_WARN).contains(&ratio) {
            out.push(format!(
                "object '{}' is {} times the cloth's size ({} m across against {} m): are both in the scene's units? An object in centimetres in a metre scene is 100 times too large (set its scale)",
                c.name, short(ratio), short(b.diagonal()), short(across)
            ));
        }
        if let Some(n @ 1..) = n {
            out.push(format!(
                "{n} of {} particles start inside object '{}': no collision can push them out (they are behind its faces); move the piece or check the object's scale and placement",
                world.state.x.len(), c.name
            ));
        }
    }
    out
}

/// The smallest distance of a particle to each object.
pub fn min_clearance(world: &World) -> Vec<f64> {
    world
        .colliders
        .iter()
        .map(|c| {
            let q = crate::mesh::closest::ClosestPoints::new(&c.mesh);
            world
                .state
                .x
                .par_iter()
                .map(|p| q.closest(p).distance)
                .reduce(|| f64::INFINITY, f64::min)
        })
        .collect()
}

/// The most raster cells along the shadow's longer side: 2048, five times the 400 cells a flat
/// square piece spans, so a piece spread wider than five times its own size (a run gone wrong,
/// a particle flung far) is measured on coarser cells instead of a raster that grows with it.
pub const MAX_RASTER_SIDE: usize = 2048;

/// The most point-in-triangle tests of one shadow (over the triangles' boxes): the cells are
/// doubled in size until the boxes hold no more (huge overlapping triangles of a broken run).
pub const MAX_RASTER_TESTS: u64 = 1 << 27;

/// The drape coefficient of a piece (Cusick): its shadow area on the plane across gravity,
/// less the disc's area, over its flat area less the disc's. The shadow is the union of its
/// projected triangles, rasterised at 1/400 of the piece's size ([`shadow`]: the raster and
/// its work are bounded whatever the positions). NaN when a position is not finite.
pub fn drape_coefficient(world: &World, piece: usize, disc_radius: f64) -> f64 {
    let m = &world.model;
    let r = &m.pieces[piece];
    let g = m.gravity.normalize();
    let e1 = g
        .cross(&Vec3::x())
        .try_normalize(1e-9)
        .unwrap_or_else(|| g.cross(&Vec3::y()).normalize());
    let e2 = g.cross(&e1);
    let pts: Vec<(f64, f64)> = world.state.x[r.first..r.first + r.count]
        .iter()
        .map(|p| (p.coords.dot(&e1), p.coords.dot(&e2)))
        .collect();
    let tris: Vec<[usize; 3]> = m.triangles[r.first_triangle..r.first_triangle + r.triangles]
        .iter()
        .map(|t| t.map(|v| v as usize - r.first))
        .collect();
    let disc = std::f64::consts::PI * disc_radius * disc_radius;
    (shadow(&pts, &tris, r.area).area - disc) / (r.area - disc)
}

/// A rasterised shadow: its area, the raster's cells and the point-in-triangle tests done.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shadow {
    /// The covered cells' area (NaN when a point is not finite).
    pub area: f64,
    /// The raster's cell size.
    pub cell: f64,
    /// Cells in the raster.
    pub cells: usize,
    /// Point-in-triangle tests.
    pub tests: u64,
}

/// The area covered by triangles `tris` over plane points `pts`, on a raster of cells
/// `sqrt(area) / 400` across (`area`: the piece's flat area), coarser when the points span more
/// than [`MAX_RASTER_SIDE`] such cells or the triangles' boxes hold more than
/// [`MAX_RASTER_TESTS`] cells (or 9 per triangle). A cell counts when its centre is in a
/// triangle. NaN when a point is not finite or the points' span overflows.
pub fn shadow(pts: &[(f64, f64)], tris: &[[usize; 3]], area: f64) -> Shadow {
    let boxes: Vec<Box2> = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| pts[v]);
            [
                (a.0.min(b.0).min(c.0), a.1.min(b.1).min(c.1)),
                (a.0.max(b.0).max(c.0), a.1.max(b.1).max(c.1)),
            ]
        })
        .collect();
    let Some(r) = Raster::over(pts, &boxes, area) else {
        let finite = pts.iter().all(|p| p.0.is_finite() && p.1.is_finite());
        let area = if finite && tris.is_empty() {
            0.0
        } else {
            f64::NAN
        };
        return Shadow {
            area,
            cell: 0.0,
            cells: 0,
            tests: 0,
        };
    };
    let mut covered = vec![false; r.nx * r.ny];
    let mut tests = 0u64;
    let cross = |p: (f64, f64), q: (f64, f64), s: (f64, f64)| {
        (q.0 - p.0) * (s.1 - p.1) - (q.1 - p.1) * (s.0 - p.0)
    };
    for (t, b) in tris.iter().zip(&boxes) {
        let [a, b_, c] = t.map(|v| pts[v]);
        let area = cross(a, b_, c);
        if area == 0.0 {
            continue;
        }
        let (cols, rows) = r.cells_of(b);
        for j in rows {
            for i in cols.clone() {
                tests += 1;
                let p = r.centre(i, j);
                let (w0, w1, w2) = (cross(b_, c, p), cross(c, a, p), cross(a, b_, p));
                if (w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 && area > 0.0)
                    || (w0 <= 0.0 && w1 <= 0.0 && w2 <= 0.0 && area < 0.0)
                {
                    covered[j * r.nx + i] = true;
                }
            }
        }
    }
    Shadow {
        area: covered.iter().filter(|&&c| c).count() as f64 * r.px * r.px,
        cell: r.px,
        cells: r.nx * r.ny,
        tests,
    }
}

/// A box in the plane: lowest and highest corners.
type Box2 = [(f64, f64); 2];

/// The raster of a shadow: its corner, cell size and cells along x and y.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Raster {
    x0: f64,
    y0: f64,
    px: f64,
    nx: usize,
    ny: usize,
}

impl Raster {
    /// The raster over `pts` for triangles of boxes `boxes` (see [`shadow`]); `None` when a
    /// point is not finite, the span overflows, or there is nothing to cover.
    fn over(pts: &[(f64, f64)], boxes: &[Box2], area: f64) -> Option<Raster> {
        let (mut lo, mut hi) = (
            (f64::INFINITY, f64::INFINITY),
            (f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for &(x, y) in pts {
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        let span = (hi.0 - lo.0).max(hi.1 - lo.1);
        let finite = pts.iter().all(|p| p.0.is_finite() && p.1.is_finite());
        if !(finite && span.is_finite() && area > 0.0) || boxes.is_empty() {
            return None;
        }
        let mut px = (area.sqrt() / 400.0).max(span / MAX_RASTER_SIDE as f64);
        let budget = (MAX_RASTER_TESTS as f64).max(9.0 * boxes.len() as f64);
        while box_cells(boxes, px) > budget {
            px *= 2.0;
        }
        Some(Raster {
            x0: lo.0,
            y0: lo.1,
            px,
            nx: ((hi.0 - lo.0) / px).ceil() as usize + 1,
            ny: ((hi.1 - lo.1) / px).ceil() as usize + 1,
        })
    }

    /// The columns and rows of the cells box `b` touches (at most [`box_cells`] of them).
    fn cells_of(
        &self,
        b: &Box2,
    ) -> (
        std::ops::RangeInclusive<usize>,
        std::ops::RangeInclusive<usize>,
    ) {
        let [l, h] = b;
        let cell = |v: f64, o: f64| (v - o) / self.px;
        (
            cell(l.0, self.x0).floor() as usize
                ..=(cell(h.0, self.x0).ceil() as usize).min(self.nx - 1),
            cell(l.1, self.y0).floor() as usize
                ..=(cell(h.1, self.y0).ceil() as usize).min(self.ny - 1),
        )
    }

    /// The centre of cell (i, j).
    fn centre(&self, i: usize, j: usize) -> (f64, f64) {
        (
            self.x0 + (i as f64 + 0.5) * self.px,
            self.y0 + (j as f64 + 0.5) * self.px,
        )
    }
}

/// An upper bound on the cells `boxes` touch at cell size `px`: each box's extent over `px`,
/// plus 2, per side (9 once `px` is the span).
fn box_cells(boxes: &[Box2], px: f64) -> f64 {
    boxes
        .iter()
        .map(|[l, h]| ((h.0 - l.0) / px + 2.0) * ((h.1 - l.1) / px + 2.0))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::fabric::Fabric;
    use crate::cloth::model::ClothModel;
    use crate::cloth::pattern::{build, Pins};
    use crate::cloth::Integrator;
    use crate::math::Point2;

    /// A flat square of side 0.2 m (spacing 2 cm), across gravity at height 0.
    fn square() -> World {
        let s = 0.1;
        let outline = [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, y)| Point2::new(x, y));
        let fabric = Fabric::cotton();
        let p = build(&outline, 0.02, &fabric, &Pins::default()).unwrap();
        let placed: Vec<Point3> = p.flat.iter().map(|q| Point3::new(q.x, q.y, 0.0)).collect();
        let (m, x) = ClothModel::assemble(
            &[("square".into(), p, fabric, placed)],
            Vec3::new(0.0, 0.0, -9.81),
        );
        World::new(m, x, Vec::new(), Integrator::Leapfrog)
    }

    /// The piece's projected points, triangle boxes and flat area.
    fn projected(w: &World) -> (Vec<(f64, f64)>, Vec<Box2>, f64) {
        let pts: Vec<(f64, f64)> = w.state.x.iter().map(|p| (p.x, p.y)).collect();
        let boxes = w
            .model
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| pts[v as usize]);
                [
                    (a.0.min(b.0).min(c.0), a.1.min(b.1).min(c.1)),
                    (a.0.max(b.0).max(c.0), a.1.max(b.1).max(c.1)),
                ]
            })
            .collect();
        (pts, boxes, w.model.pieces[0].area)
    }

    #[test]
    fn a_flat_piece_casts_its_own_area_at_the_fine_cell() {
        let w = square();
        let (pts, boxes, area) = projected(&w);
        assert!((area - 0.04).abs() < 1e-12, "{area}");
        let r = Raster::over(&pts, &boxes, area).unwrap();
        // The cell is the piece's size over 400 (its area rounds a little).
        assert!((r.px * 400.0 / 0.2 - 1.0).abs() < 1e-12, "{r:?}");
        assert!(r.nx == r.ny && (401..=402).contains(&r.nx), "{r:?}");
        assert!((drape_coefficient(&w, 0, 0.05) - 1.0).abs() < 0.01);
    }

    #[test]
    fn hostile_far_particles_keep_the_raster_and_its_work_bounded() {
        let side = MAX_RASTER_SIDE + 1;
        // One particle flung 1e12 m away, the piece moved to 1e300, and a piece spread over
        // 1e300 with every triangle huge: a bounded raster, bounded tests, a finite answer.
        let mut far = square();
        far.state.x[0].x = 1e12;
        let mut moved = square();
        moved.state.x.iter_mut().for_each(|p| p.x += 1e300);
        let mut spread = square();
        spread.state.x.iter_mut().enumerate().for_each(|(i, p)| {
            p.x *= 1e300 * if i % 2 == 0 { 1.0 } else { -1.0 };
        });
        for (name, w) in [("far", far), ("moved", moved), ("spread", spread)] {
            let (pts, boxes, area) = projected(&w);
            let r = Raster::over(&pts, &boxes, area).unwrap();
            assert!(r.nx <= side && r.ny <= side, "{name}: {r:?}");
            assert!(box_cells(&boxes, r.px) <= MAX_RASTER_TESTS as f64, "{name}");
            let tris: Vec<[usize; 3]> = w
                .model
                .triangles
                .iter()
                .map(|t| t.map(|v| v as usize))
                .collect();
            let s = shadow(&pts, &tris, area);
            assert!(
                s.area.is_finite() && s.tests <= MAX_RASTER_TESTS,
                "{name}: {s:?}"
            );
            assert!(drape_coefficient(&w, 0, 0.05).is_finite(), "{name}");
        }
        // 20,000 triangles each spanning the whole shadow: the cells grow until their boxes
        // hold at most MAX_RASTER_TESTS cells (at the finest raster, 2048^2 each).
        let pts = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
        let boxes = vec![[(0.0, 0.0), (1.0, 1.0)]; 20_000];
        let r = Raster::over(&pts, &boxes, 1e-9).unwrap();
        assert!(box_cells(&boxes, r.px) <= MAX_RASTER_TESTS as f64, "{r:?}");
        assert!(
            box_cells(&boxes, r.px / 2.0) > MAX_RASTER_TESTS as f64,
            "no coarser than needed"
        );
        // A span beyond f64 (from -1e308 to 1e308) cannot be measured: NaN, at once.
        let mut w = square();
        w.state.x[0].x = -1.5e308;
        w.state.x[1].x = 1.5e308;
        assert!(drape_coefficient(&w, 0, 0.05).is_nan());
    }
}
