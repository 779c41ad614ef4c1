//! Named views and the orthographic camera fitted to a scene.
//!
//! A view is an orthonormal basis: `right` and `up` span the picture, `forward` points into it.
//! A point `p` lands at pixel `(cx + s (p·right - c_r), cy - s (p·up - c_u))` at depth
//! `p·forward`, where `s` is the scale in pixels per length unit and `(c_r, c_u)` the centre of
//! the scene's extent along `right` and `up`. The projection is orthographic: lengths in the
//! picture plane keep one scale everywhere, as in the paper's three projections (and a sphere of
//! radius `r` covers `pi (s r)^2` pixels). [`fit`] picks `s` so the scene's projected extent
//! fills the panel less a margin of [`MARGIN`] of its smaller side on each edge.
//!
//! Named views are defined for z up (front looks along +y: a GarmentCode body, y up, faces +z,
//! which is -y after `transform::change_up`); for y-up scenes the basis is rotated the same way.

use crate::math::{Point3, Vec3};
use crate::mesh::transform::{change_up_vector, Up};
use std::str::FromStr;

/// Fraction of a panel's smaller side left empty on each edge.
pub const MARGIN: f64 = 0.05;

/// A named direction to look from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum View {
    /// From the front (looking along +y for z up), x to the right.
    Front,
    /// From behind.
    Back,
    /// From the right side (looking along -x for z up).
    Side,
    /// From above, the back at the top of the picture.
    Top,
    /// From front, right and above (along (-1, 1, -1) for z up).
    Iso,
    /// Looking along -z at the xy plane (x right, y up), whatever the up axis: the paper's XY.
    Xy,
    /// Looking along +y at the xz plane (x right, z up): the paper's XZ.
    Xz,
    /// Looking along -x at the yz plane (y right, z up): the paper's YZ.
    Yz,
}

impl FromStr for View {
    type Err = String;
    fn from_str(s: &str) -> Result<View, String> {
        Ok(match s.to_ascii_lowercase().as_str() {
            "front" => View::Front,
            "back" => View::Back,
            "side" => View::Side,
            "top" => View::Top,
            "iso" => View::Iso,
            "xy" => View::Xy,
            "xz" => View::Xz,
            "yz" => View::Yz,
            _ => {
                return Err(format!(
                    "unknown view '{s}': expected front, back, side, top, iso, xy, xz, yz or projections"
                ))
            }
        })
    }
}

impl View {
    /// The paper's label for a projection (`XY`, `XZ`, `YZ`), none for a named view.
    pub fn label(self) -> Option<&'static str> {
        match self {
            View::Xy => Some("XY"),
            View::Xz => Some("XZ"),
            View::Yz => Some("YZ"),
            _ => None,
        }
    }

    /// `(right, up, forward)`, orthonormal, for a scene whose up axis is `up`.
    pub fn basis(self, up: Up) -> (Vec3, Vec3, Vec3) {
        let v = Vec3::new;
        let (right, screen_up) = match self {
            View::Xy => return (v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(0.0, 0.0, -1.0)),
            View::Xz => return (v(1.0, 0.0, 0.0), v(0.0, 0.0, 1.0), v(0.0, 1.0, 0.0)),
            View::Yz => return (v(0.0, 1.0, 0.0), v(0.0, 0.0, 1.0), v(-1.0, 0.0, 0.0)),
            View::Front => (v(1.0, 0.0, 0.0), v(0.0, 0.0, 1.0)),
            View::Back => (v(-1.0, 0.0, 0.0), v(0.0, 0.0, 1.0)),
            View::Side => (v(0.0, 1.0, 0.0), v(0.0, 0.0, 1.0)),
            View::Top => (v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)),
            View::Iso => {
                let r = v(1.0, 1.0, 0.0).normalize();
                let f = v(-1.0, 1.0, -1.0).normalize();
                (r, r.cross(&f))
            }
        };
        let forward = screen_up.cross(&right);
        let rot = |w: Vec3| change_up_vector(w, Up::Z, up);
        (rot(right), rot(screen_up), rot(forward))
    }
}

/// An orthographic camera for one panel of a picture.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// Picture-plane axes and the viewing direction (unit, orthonormal).
    pub right: Vec3,
    /// Up in the picture.
    pub up: Vec3,
    /// Into the picture (depth grows along it).
    pub forward: Vec3,
    /// Pixels per length unit.
    pub scale: f64,
    /// The scene's extent centre along `right` and `up`.
    pub centre: [f64; 2],
    /// The panel's size in pixels.
    pub size: [u32; 2],
}

impl Camera {
    /// `p` in panel pixels (x right, y down; pixel `(i, j)` covers `[i, i+1) x [j, j+1)`) and
    /// its depth along `forward`.
    pub fn project(&self, p: &Point3) -> [f64; 3] {
        let q = p.coords;
        [
            0.5 * f64::from(self.size[0]) + self.scale * (q.dot(&self.right) - self.centre[0]),
            0.5 * f64::from(self.size[1]) - self.scale * (q.dot(&self.up) - self.centre[1]),
            q.dot(&self.forward),
        ]
    }
}

/// The extent of `points` along `right` and `up`: `[min_r, max_r, min_u, max_u]`.
fn extent<'a>(points: impl Iterator<Item = &'a Point3>, right: &Vec3, up: &Vec3) -> [f64; 4] {
    let mut e = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in points {
        let (r, u) = (p.coords.dot(right), p.coords.dot(up));
        e = [e[0].min(r), e[1].max(r), e[2].min(u), e[3].max(u)];
    }
    e
}

/// The largest scale at which an extent `[w, h]` fits a `size` panel less its margins (1 for
/// a scene that is a single point).
pub fn fit_scale(extent: [f64; 2], size: [u32; 2]) -> f64 {
    let margin = MARGIN * f64::from(size[0].min(size[1]));
    let room = [
        f64::from(size[0]) - 2.0 * margin,
        f64::from(size[1]) - 2.0 * margin,
    ];
    let s = (0..2)
        .filter(|&k| extent[k] > 0.0)
        .map(|k| room[k] / extent[k])
        .fold(f64::INFINITY, f64::min);
    if s.is_finite() {
        s
    } else {
        1.0
    }
}

/// Cameras for `views`, each a panel of `size`, framing `points` (called once per view) at one
/// common scale: the largest at which every view fits.
///
/// ```
/// use drapekit::math::Point3;
/// use drapekit::mesh::transform::Up;
/// use drapekit::render::camera::{fit, View};
/// let pts = [Point3::new(-1.0, -2.0, 0.0), Point3::new(1.0, 2.0, 0.5)];
/// let cams = fit(&[View::Xy], Up::Z, [220, 110], || pts.iter());
/// // 4 units of y must fit 110 px less 2 x 5.5 px of margin: 24.75 px per unit.
/// assert_eq!(cams[0].scale, 24.75);
/// assert_eq!(cams[0].project(&Point3::new(0.0, 2.0, 0.0)), [110.0, 5.5, 0.0]);
/// ```
pub fn fit<'a, I>(views: &[View], up: Up, size: [u32; 2], points: impl Fn() -> I) -> Vec<Camera>
where
    I: Iterator<Item = &'a Point3>,
{
    let bases: Vec<_> = views.iter().map(|v| v.basis(up)).collect();
    let extents: Vec<[f64; 4]> = bases
        .iter()
        .map(|(r, u, _)| extent(points(), r, u))
        .collect();
    let scale = extents
        .iter()
        .map(|e| fit_scale([e[1] - e[0], e[3] - e[2]], size))
        .fold(f64::INFINITY, f64::min);
    bases
        .into_iter()
        .zip(extents)
        .map(|((right, up, forward), e)| {
            let centre = if e[0].is_finite() {
                [0.5 * (e[0] + e[1]), 0.5 * (e[2] + e[3])]
            } else {
                [0.0, 0.0]
            };
            Camera {
                right,
                up,
                forward,
                scale: if scale.is_finite() { scale } else { 1.0 },
                centre,
                size,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bases_are_right_handed_and_named_views_look_where_they_say() {
        for up in [Up::Z, Up::Y] {
            for v in [
                View::Front,
                View::Back,
                View::Side,
                View::Top,
                View::Iso,
                View::Xy,
                View::Xz,
                View::Yz,
            ] {
                let (r, u, f) = v.basis(up);
                assert!(
                    (r.cross(&u) + f).norm() < 1e-15,
                    "{v:?}: right x up = -forward"
                );
                assert!((r.norm() - 1.0).abs() < 1e-15 && r.dot(&u).abs() < 1e-15);
            }
        }
        let up_axis = |up| change_up_vector(Vec3::z(), Up::Z, up);
        for up in [Up::Z, Up::Y] {
            assert_eq!(View::Front.basis(up).1, up_axis(up), "front keeps up up");
            assert_eq!(View::Top.basis(up).2, -up_axis(up), "top looks down");
        }
        // y up: the front view looks at a body facing +z, so it looks along -z.
        assert_eq!(View::Front.basis(Up::Y).2, Vec3::new(0.0, 0.0, -1.0));
    }
}
