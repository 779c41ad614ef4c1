//! The cloth state: everything that changes every step, as arrays.

use crate::math::{Point3, Vec3};

/// A particle's contact with an object face, kept from one step to the next (sliding).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Object index.
    pub object: u32,
    /// Face index in the object's mesh.
    pub face: u32,
    /// Which side of the face the particle is on: +1 or -1 along the face normal.
    pub side: f64,
}

/// Positions, velocities and contacts.
#[derive(Debug, Clone, PartialEq)]
pub struct ClothState {
    /// Positions, m.
    pub x: Vec<Point3>,
    /// Velocities, m/s.
    pub v: Vec<Vec3>,
    /// The face each particle slides on, if any.
    pub contact: Vec<Option<Contact>>,
}

impl ClothState {
    /// At rest at `x`.
    pub fn at_rest(x: Vec<Point3>) -> ClothState {
        let n = x.len();
        ClothState {
            x,
            v: vec![Vec3::zeros(); n],
            contact: vec![None; n],
        }
    }
}
