//! The triangle rasteriser: edge functions in fixed point, the top-left fill rule, a depth
//! buffer.
//!
//! Vertices are snapped to 1/[`SUB`] pixel. For a triangle `(a, b, c)` the edge function of
//! edge `(a, b)` at point `p` is `E_ab(p) = (b - a) x (p - a)` (2D cross product), exact in
//! integers; the three at a pixel centre are `area` times its barycentric coordinates, so a
//! centre is inside when all three are `>= 0`. A centre exactly on an edge belongs to the
//! triangle only if that edge is a top or a left edge (the top-left rule), so pixels on an
//! edge shared by two triangles are drawn once, never twice or not at all. Depth is
//! interpolated with the barycentric coordinates (exact for an orthographic camera) and a
//! fragment replaces the stored one only when strictly nearer: of two at equal depth the
//! earlier triangle stays. Both sides of a triangle are drawn.
//!
//! Rows are cut into bands of [`BAND`] rows; each triangle is listed, in order, in the bands its
//! rows touch, and the bands are drawn in parallel, each by one thread in triangle order.
//! Every pixel therefore sees the same triangles in the same order whatever the thread count:
//! the buffer is identical for any `--jobs`.

use rayon::prelude::*;

/// Sub-pixel steps per pixel (fixed point: 8 bits).
pub const SUB: i64 = 256;
/// Rows per band (the unit of parallel work).
pub const BAND: usize = 16;
/// Snapped coordinates are clamped to this magnitude so edge functions cannot overflow `i64`.
const LIMIT: i64 = 1 << 29;

/// What a pixel shows: the nearest fragment (16 bytes: an 8192 x 8192 picture's buffer is 1 GiB;
/// the barycentric coordinates are recomputed for the pixels shown, [`barycentric`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fragment {
    /// Depth along the camera's `forward`.
    pub depth: f64,
    /// The triangle drawn (an index into the list given to [`rasterise`]); `u32::MAX`: none.
    pub triangle: u32,
}

impl Fragment {
    /// An empty pixel.
    pub const EMPTY: Fragment = Fragment {
        depth: f64::INFINITY,
        triangle: u32::MAX,
    };

    /// Whether a triangle covers the pixel.
    pub fn is_covered(&self) -> bool {
        self.triangle != u32::MAX
    }
}

/// A triangle in pixel coordinates: `[x, y, depth]` per corner.
pub type ScreenTriangle = [[f64; 3]; 3];

/// Snaps a pixel coordinate to fixed point.
fn snap(v: f64) -> i64 {
    ((v * SUB as f64).round() as i64).clamp(-LIMIT, LIMIT)
}

/// `(b - a) x (p - a)` in fixed point.
fn edge(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Whether edge `a -> b` of a triangle of positive area (as `edge` counts it, y down) is a top
/// edge (horizontal, interior below) or a left edge.
fn top_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    dy < 0 || (dy == 0 && dx > 0)
}

/// Rows `[first, last]` whose pixel centres (`j + 0.5`) may lie in `[lo, hi]` (in pixels),
/// clipped to `0..height`; `None` when there are none.
fn rows(lo: f64, hi: f64, height: usize) -> Option<(usize, usize)> {
    let first = (lo - 0.5).ceil().max(0.0);
    let last = (hi - 0.5).floor().min(height as f64 - 1.0);
    (first <= last).then_some((first as usize, last as usize))
}

/// Draws `triangles` into a `width x height` buffer of fragments (row-major, top row first).
///
/// ```
/// use drapekit::render::raster::rasterise;
/// // Two triangles covering a 4 x 4 square exactly: each pixel is drawn once.
/// let (a, b, c, d) = ([0.0, 0.0, 1.0], [4.0, 0.0, 1.0], [4.0, 4.0, 1.0], [0.0, 4.0, 1.0]);
/// let buf = rasterise(&[[a, b, c], [a, c, d]], 4, 4);
/// assert!(buf.iter().all(|f| f.is_covered()));
/// // The four centres (0.5, 0.5), ..., (3.5, 3.5) lie on the shared diagonal, a left edge of
/// // triangle 0 (above it) and a right edge of triangle 1: triangle 0 takes them.
/// assert_eq!(buf.iter().filter(|f| f.triangle == 0).count(), 6 + 4);
/// assert_eq!(buf.iter().filter(|f| f.triangle == 1).count(), 6);
/// ```
pub fn rasterise(triangles: &[ScreenTriangle], width: usize, height: usize) -> Vec<Fragment> {
    let mut buf = vec![Fragment::EMPTY; width * height];
    if width == 0 || height == 0 {
        return buf;
    }
    let bands = height.div_ceil(BAND);
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); bands];
    for (t, tri) in triangles.iter().enumerate() {
        let lo = tri.iter().map(|c| c[1]).fold(f64::INFINITY, f64::min);
        let hi = tri.iter().map(|c| c[1]).fold(f64::NEG_INFINITY, f64::max);
        if let Some((first, last)) = rows(lo, hi, height) {
            for list in &mut lists[first / BAND..=last / BAND] {
                list.push(t as u32);
            }
        }
    }
    buf.par_chunks_mut(BAND * width)
        .zip(lists.par_iter())
        .enumerate()
        .for_each(|(band, (rows_buf, list))| {
            let top = band * BAND;
            for &t in list {
                draw(&triangles[t as usize], t, rows_buf, width, top);
            }
        });
    buf
}

/// A triangle snapped and wound for its edge functions.
struct Snapped {
    /// Corners in fixed point, turned to positive area; `order[k]`: the given corner at `k`.
    v: [[i64; 2]; 3],
    order: [usize; 3],
    area: f64,
    /// Edge `k` is opposite corner `k`: its function is corner `k`'s weight times `area`.
    edges: [([i64; 2], [i64; 2]); 3],
}

impl Snapped {
    /// `None` for a triangle of no area in fixed point.
    fn new(tri: &ScreenTriangle) -> Option<Snapped> {
        let mut v = tri.map(|c| [snap(c[0]), snap(c[1])]);
        let mut order = [0usize, 1, 2];
        let area = edge(v[0], v[1], v[2]);
        if area == 0 {
            return None;
        }
        if area < 0 {
            v.swap(1, 2);
            order.swap(1, 2);
        }
        Some(Snapped {
            v,
            order,
            area: area.abs() as f64,
            edges: [(v[1], v[2]), (v[2], v[0]), (v[0], v[1])],
        })
    }

    /// The weights, in the snapped order, of edge function values `w`.
    fn weights(&self, w: [i64; 3]) -> [f64; 3] {
        w.map(|e| e as f64 / self.area)
    }
}

/// The fixed-point centre of pixel `(x, y)`.
fn centre(x: usize, y: usize) -> [i64; 2] {
    [x as i64 * SUB + SUB / 2, y as i64 * SUB + SUB / 2]
}

/// The barycentric coordinates of pixel `(x, y)`'s centre in `tri` (its corners as given), as
/// [`rasterise`] interpolated the depth there, bit for bit (the edge functions are exact
/// integers, however they are reached); zeros for a triangle of no area.
///
/// ```
/// use drapekit::render::raster::barycentric;
/// let tri = [[0.0, 0.0, 1.0], [10.0, 0.0, 1.0], [0.0, 10.0, 1.0]];
/// assert_eq!(barycentric(&tri, 0, 0), [0.9, 0.05, 0.05]);
/// ```
pub fn barycentric(tri: &ScreenTriangle, x: usize, y: usize) -> [f64; 3] {
    let Some(s) = Snapped::new(tri) else {
        return [0.0; 3];
    };
    let l = s.weights(s.edges.map(|(a, b)| edge(a, b, centre(x, y))));
    let mut bary = [0.0; 3];
    for k in 0..3 {
        bary[s.order[k]] = l[k];
    }
    bary
}

/// Draws triangle `t` into the rows of one band (`top` is its first row).
fn draw(tri: &ScreenTriangle, t: u32, band: &mut [Fragment], width: usize, top: usize) {
    let Some(s) = Snapped::new(tri) else {
        return;
    };
    let (v, order, edges) = (s.v, s.order, s.edges);
    let band_rows = band.len() / width;
    let xs = v.map(|p| p[0] as f64 / SUB as f64);
    let ys = v.map(|p| p[1] as f64 / SUB as f64);
    let Some((y0, y1)) = rows(
        ys.into_iter().fold(f64::INFINITY, f64::min),
        ys.into_iter().fold(f64::NEG_INFINITY, f64::max),
        top + band_rows,
    ) else {
        return;
    };
    let Some((x0, x1)) = rows(
        xs.into_iter().fold(f64::INFINITY, f64::min),
        xs.into_iter().fold(f64::NEG_INFINITY, f64::max),
        width,
    ) else {
        return;
    };
    let bias = edges.map(|(a, b)| if top_left(a, b) { 0 } else { -1 });
    let depth = order.map(|k| tri[k][2]);
    for y in y0.max(top)..=y1 {
        let row = &mut band[(y - top) * width..(y - top + 1) * width];
        let mut w = edges.map(|(a, b)| edge(a, b, centre(x0, y)));
        // Stepping one pixel right changes E_ab by -(b_y - a_y) SUB.
        let step = edges.map(|(a, b)| -(b[1] - a[1]) * SUB);
        for frag in &mut row[x0..=x1] {
            if (0..3).all(|k| w[k] + bias[k] >= 0) {
                let l = s.weights(w);
                let z = l[0] * depth[0] + l[1] * depth[1] + l[2] * depth[2];
                if z < frag.depth {
                    *frag = Fragment {
                        depth: z,
                        triangle: t,
                    };
                }
            }
            for k in 0..3 {
                w[k] += step[k];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn covered_by(buf: &[Fragment], t: u32) -> usize {
        buf.iter().filter(|f| f.triangle == t).count()
    }

    #[test]
    fn a_fan_covers_its_square_once() {
        // Eight triangles fanned about an off-grid centre: no pixel is missed, the counts
        // add up to the square, whatever the band boundaries.
        let c = [13.37, 17.21, 0.0];
        let ring = [
            [0.0, 0.0],
            [20.0, 0.0],
            [40.0, 0.0],
            [40.0, 20.0],
            [40.0, 40.0],
            [20.0, 40.0],
            [0.0, 40.0],
            [0.0, 20.0],
        ];
        let tris: Vec<ScreenTriangle> = (0..8)
            .map(|k| {
                let (a, b) = (ring[k], ring[(k + 1) % 8]);
                [[a[0], a[1], 0.0], [b[0], b[1], 0.0], c]
            })
            .collect();
        let buf = rasterise(&tris, 40, 40);
        let total: usize = (0..8).map(|t| covered_by(&buf, t)).sum();
        assert_eq!(total, 1600);
        assert!(buf.iter().all(Fragment::is_covered));
    }

    #[test]
    fn the_nearer_triangle_wins_in_either_order() {
        let near = [[0.0, 0.0, 1.0], [10.0, 0.0, 1.0], [0.0, 10.0, 1.0]];
        let far = [[0.0, 0.0, 2.0], [10.0, 0.0, 2.0], [0.0, 10.0, 2.0]];
        let a = rasterise(&[near, far], 10, 10);
        let b = rasterise(&[far, near], 10, 10);
        assert_eq!(covered_by(&a, 0), 45);
        assert_eq!(covered_by(&a, 1), 0);
        assert_eq!(covered_by(&b, 1), 45);
        // Barycentric coordinates follow the corners as given, in either winding.
        let tri = [near[0], near[2], near[1]];
        assert!(rasterise(&[tri], 10, 10)[0].is_covered());
        let bary = barycentric(&tri, 0, 0);
        assert!((bary[0] - 0.9).abs() < 1e-12 && (bary[2] - 0.05).abs() < 1e-12);
    }

    #[test]
    fn recomputed_barycentric_coordinates_give_each_pixel_its_centre_and_its_depth_exactly() {
        // Corners on the fixed-point grid (so the centre is reproduced exactly up to rounding),
        // both windings, unequal depths: the weights, in the corners' order as given, rebuild
        // the pixel centre, and the depth the rasteriser stored is their interpolation, bit for
        // bit.
        let tris: [ScreenTriangle; 2] = [
            [[1.25, 0.5, 3.0], [29.75, 4.0, 1.0], [7.5, 23.25, 2.0]],
            [[7.5, 23.25, 2.0], [29.75, 4.0, 1.0], [1.25, 0.5, 3.0]],
        ];
        for tri in tris {
            let buf = rasterise(&[tri], 32, 32);
            let mut shown = 0;
            for (i, f) in buf.iter().enumerate().filter(|(_, f)| f.is_covered()) {
                let (x, y) = (i % 32, i / 32);
                let b = barycentric(&tri, x, y);
                let at = |c: usize| (0..3).map(|k| b[k] * tri[k][c]).sum::<f64>();
                assert!((at(0) - (x as f64 + 0.5)).abs() < 1e-9, "x at {x},{y}");
                assert!((at(1) - (y as f64 + 0.5)).abs() < 1e-9, "y at {x},{y}");
                assert!((f.depth - at(2)).abs() < 1e-12, "depth at {x},{y}");
                shown += 1;
            }
            assert!(shown > 200, "{shown} pixels");
        }
    }
}
