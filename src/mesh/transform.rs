//! Units and axes. A unit change is a uniform scale; an up-axis change is a rotation about x
//! (never a mirror), so the winding and the outward orientation survive it.
//!
//! Z-up to Y-up maps `(x, y, z)` to `(x, z, -y)`; Y-up to Z-up maps `(x, y, z)` to `(x, -z, y)`.
//! Both have determinant +1.

use super::TriMesh;
use crate::math::{Point3, Vec3};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// A length unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    /// Millimetres.
    Mm,
    /// Centimetres.
    Cm,
    /// Metres.
    M,
    /// Inches.
    In,
}

impl Units {
    /// Metres in one of this unit.
    ///
    /// ```
    /// use drapekit::mesh::transform::Units;
    /// assert_eq!(Units::In.metres(), 0.0254);
    /// assert_eq!(Units::factor(Units::Cm, Units::Mm), 10.0);
    /// ```
    pub fn metres(self) -> f64 {
        match self {
            Units::Mm => 1e-3,
            Units::Cm => 1e-2,
            Units::M => 1.0,
            Units::In => 0.0254,
        }
    }

    /// Micrometres in one of this unit (exact integers, so factors are correctly rounded).
    fn micrometres(self) -> f64 {
        match self {
            Units::Mm => 1e3,
            Units::Cm => 1e4,
            Units::M => 1e6,
            Units::In => 25_400.0,
        }
    }

    /// The factor that converts lengths in `from` to lengths in `to`.
    pub fn factor(from: Units, to: Units) -> f64 {
        from.micrometres() / to.micrometres()
    }
}

impl FromStr for Units {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "mm" => Ok(Units::Mm),
            "cm" => Ok(Units::Cm),
            "m" => Ok(Units::M),
            "in" => Ok(Units::In),
            _ => Err(format!("unknown unit '{s}': expected mm, cm, m or in")),
        }
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Units::Mm => "mm",
            Units::Cm => "cm",
            Units::M => "m",
            Units::In => "in",
        })
    }
}

/// The up axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Up {
    /// Y is up (glTF, OBJ from most DCC tools).
    Y,
    /// Z is up (AutoCAD, the paper).
    Z,
}

impl FromStr for Up {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "y" | "Y" => Ok(Up::Y),
            "z" | "Z" => Ok(Up::Z),
            _ => Err(format!("unknown up axis '{s}': expected y or z")),
        }
    }
}

impl fmt::Display for Up {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Up::Y => "y",
            Up::Z => "z",
        })
    }
}

/// Maps a point from `from`-up to `to`-up coordinates.
#[inline]
pub fn change_up_point(p: Point3, from: Up, to: Up) -> Point3 {
    match (from, to) {
        (Up::Z, Up::Y) => Point3::new(p.x, p.z, -p.y),
        (Up::Y, Up::Z) => Point3::new(p.x, -p.z, p.y),
        _ => p,
    }
}

/// Maps a vector from `from`-up to `to`-up coordinates.
pub fn change_up_vector(v: Vec3, from: Up, to: Up) -> Vec3 {
    change_up_point(Point3::from(v), from, to).coords
}

/// Rotates `mesh` from `from`-up to `to`-up.
pub fn change_up(mesh: &mut TriMesh, from: Up, to: Up) {
    for p in &mut mesh.positions {
        *p = change_up_point(*p, from, to);
    }
}

/// Scales `mesh` by `factor` (> 0) about the origin.
pub fn scale(mesh: &mut TriMesh, factor: f64) {
    if factor != 1.0 {
        for p in &mut mesh.positions {
            p.coords *= factor;
        }
    }
}

/// Converts `mesh` from one unit to another.
pub fn change_units(mesh: &mut TriMesh, from: Units, to: Units) {
    scale(mesh, Units::factor(from, to));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn up_change_is_a_rotation_and_round_trips() {
        let mut m = generate::icosphere(1);
        for p in &mut m.positions {
            p.coords += Vec3::new(0.3, 0.2, 0.1);
        }
        let v = m.signed_volume();
        let orig = m.clone();
        change_up(&mut m, Up::Z, Up::Y);
        assert!(
            (m.signed_volume() - v).abs() < 1e-12,
            "a mirror would negate the volume"
        );
        assert_eq!(
            change_up_point(Point3::new(0.0, 0.0, 1.0), Up::Z, Up::Y),
            Point3::new(0.0, 1.0, 0.0)
        );
        change_up(&mut m, Up::Y, Up::Z);
        assert_eq!(m, orig);
    }

    #[test]
    fn unit_factors() {
        assert_eq!(Units::factor(Units::M, Units::Mm), 1000.0);
        assert_eq!(Units::factor(Units::Mm, Units::M), 1e-3);
        assert_eq!(Units::factor(Units::In, Units::Mm), 25.4);
    }
}
