//! Scalar and vector types, the axis-aligned box, and every named tolerance.
//!
//! drapekit computes in `f64` throughout. Small vectors come from nalgebra. Every
//! threshold that decides what counts as "equal", "flat" or "degenerate" lives in [`tol`]
//! so a reader of the code finds them all in one place.

/// The scalar type of all geometry.
pub type Real = f64;
/// A point in 3D.
pub type Point3 = nalgebra::Point3<f64>;
/// A vector in 3D.
pub type Vec3 = nalgebra::Vector3<f64>;
/// A point in 2D.
pub type Point2 = nalgebra::Point2<f64>;
/// A vector in 2D.
pub type Vec2 = nalgebra::Vector2<f64>;

/// Named tolerances. Relative ones are multiplied by the bounding-box diagonal (lengths) or
/// its square (areas) of the mesh they apply to.
pub mod tol {
    /// Default weld distance, relative to the bounding-box diagonal.
    pub const WELD_REL_DEFAULT: f64 = 1e-6;
    /// A face whose area is at most this times the squared bounding-box diagonal is degenerate.
    pub const DEGENERATE_AREA_REL: f64 = 1e-12;
    /// A quad is non-planar when its fourth corner lies farther than this times its longer
    /// diagonal from the plane of the first three.
    pub const NONPLANAR_QUAD_REL: f64 = 1e-5;
    /// A closed component whose |signed volume| is at most this times diagonal³ has no
    /// usable inside (a flat, double-sided sheet): it keeps its winding.
    pub const FLAT_VOLUME_REL: f64 = 1e-12;
    /// An open component whose mean generalized winding number is within this of zero has no
    /// preferred side (a flat sheet, a lone triangle): it keeps its winding.
    pub const WINDING_TIE: f64 = 1e-9;
}

/// An axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Point3,
    /// Largest corner.
    pub max: Point3,
}

impl Aabb {
    /// The box of a set of points; `None` when there are none.
    ///
    /// ```
    /// use drapekit::math::{Aabb, Point3};
    /// let b = Aabb::of_points(&[Point3::new(0.0, 0.0, 0.0), Point3::new(3.0, 4.0, 0.0)]).unwrap();
    /// assert_eq!(b.diagonal(), 5.0);
    /// ```
    pub fn of_points(points: &[Point3]) -> Option<Aabb> {
        let first = points.first()?;
        let mut b = Aabb {
            min: *first,
            max: *first,
        };
        for p in points {
            b.include(p);
        }
        Some(b)
    }

    /// Grows the box to contain `p`.
    pub fn include(&mut self, p: &Point3) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(p[k]);
            self.max[k] = self.max[k].max(p[k]);
        }
    }

    /// Edge lengths along x, y, z.
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// Length of the diagonal, without underflow or overflow for a box of any finite size (a
    /// box whose sides all lie within 1e-150 to 1e150 takes the plain formula).
    ///
    /// ```
    /// use drapekit::math::{Aabb, Point3};
    /// let b = Aabb::of_points(&[Point3::origin(), Point3::new(3e-300, 4e-300, 0.0)]).unwrap();
    /// assert!((b.diagonal() / 5e-300 - 1.0).abs() < 1e-15);
    /// ```
    pub fn diagonal(&self) -> f64 {
        let size = self.size();
        let m = size.amax();
        if m > 0.0 && !(1e-150..=1e150).contains(&m) {
            m * (size / m).norm()
        } else {
            size.norm()
        }
    }

    /// Centre point.
    pub fn center(&self) -> Point3 {
        nalgebra::center(&self.min, &self.max)
    }

    /// Whether `p` lies inside or on the box grown by `margin` on every side.
    pub fn contains(&self, p: &Point3, margin: f64) -> bool {
        (0..3).all(|k| p[k] >= self.min[k] - margin && p[k] <= self.max[k] + margin)
    }
}

/// Twice the signed area of the 2D triangle (a, b, c): positive when counter-clockwise.
#[inline]
pub fn orient2d(a: &Point2, b: &Point2, c: &Point2) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// The (unnormalised) Newell normal of a polygon: its length is twice the polygon's area and it
/// points along the right-hand rule of the corner order. Robust for non-planar and concave
/// polygons.
pub fn newell_normal(corners: impl Iterator<Item = Point3> + Clone) -> Vec3 {
    let mut n = Vec3::zeros();
    let mut it = corners.clone().peekable();
    let first = match it.peek() {
        Some(p) => *p,
        None => return n,
    };
    // Relative to the first corner for precision far from the origin.
    let rel: Vec<Vec3> = corners.map(|p| p - first).collect();
    for i in 0..rel.len() {
        let a = rel[i];
        let b = rel[(i + 1) % rel.len()];
        n += a.cross(&b);
    }
    n
}

/// A deterministic pseudo-random sequence (SplitMix64).
pub struct SplitMix(pub u64);

impl SplitMix {
    /// The next value in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `x` for people: at most four significant digits, plain between 1e-3 and 1e4, else in
/// scientific notation (never hundreds of digits); zero is "0", whatever its sign.
///
/// ```
/// use drapekit::math::short;
/// assert_eq!(short(0.01), "0.01");
/// assert_eq!(short(1.0 / 3.0), "0.3333");
/// assert_eq!(short(1e-300), "1.000e-300");
/// assert_eq!(short(2500.0), "2500");
/// assert_eq!(short(-0.0), "0");
/// ```
pub fn short(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        // No "-0".
        return "0".into();
    }
    if !x.is_finite() {
        return format!("{x}");
    }
    if !(1e-3..1e4).contains(&a) {
        return format!("{x:.3e}");
    }
    let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// SplitMix64's output function of `z`: a fixed, well-spread hash of a counter (treap
/// priorities, seeded perturbations), the same on every machine.
///
/// ```
/// assert_eq!(drapekit::math::mix(0), 0xE220_A839_7B1D_CDAF);
/// ```
pub fn mix(z: u64) -> u64 {
    let mut z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The root of `i` in the union-find forest `parent` (`parent[r] == r` at a root), halving
/// the path on the way.
///
/// ```
/// let mut parent = vec![0, 0, 1, 3];
/// assert_eq!(drapekit::math::uf_root(&mut parent, 2), 0);
/// assert_eq!(parent[2], 0);
/// assert_eq!(drapekit::math::uf_root(&mut parent, 3), 3);
/// ```
pub fn uf_root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}
