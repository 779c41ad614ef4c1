//! Panels that face into the body.
//!
//! GarmentCode lists a panel's outline counter-clockwise seen from outside the garment, so the
//! placed normal `n = R (0, 0, sign A)` (`A` the outline's signed area, `R` the placement's
//! rotation) points away from the body. A panel is facing into the body when the angle between
//! `n` and the horizontal direction `d` from the body's vertical axis to the panel's centre is
//! more than [`FACING_IN_ANGLE_DEG`]: `n . d / |d| < cos(FACING_IN_ANGLE_DEG)`. In the four
//! real patterns (`../shared/realdata/patterns`, 32 panels) the cosine is 0.33 (sleeves) to
//! 1.0 (skirts); a panel flipped by a wrong rotation or a reversed outline gives -0.33 to -1.
//! The simulation would take its inside for its outside (folds and self-contact sides).
//!
//! ```
//! use drapekit::garment::facing::facing_in;
//! use drapekit::garment::parse;
//! // A square front panel 25 cm in front of the axis (z toward the viewer), outline
//! // counter-clockwise: it faces out. Rotated 180 degrees about y, it faces in.
//! let spec = |rot: f64| format!(r#"{{"pattern": {{"panels": {{"front": {{
//!   "vertices": [[-10, 0], [10, 0], [10, 20], [-10, 20]],
//!   "edges": [{{"endpoints": [0, 1]}}, {{"endpoints": [1, 2]}}, {{"endpoints": [2, 3]}}, {{"endpoints": [3, 0]}}],
//!   "translation": [0, 100, 25], "rotation": [0, {rot}, 0]}}}},
//!   "stitches": []}}, "parameters": {{}}, "parameter_order": [],
//!   "properties": {{"curvature_coords": "relative", "units_in_meter": 100}}}}"#);
//! let path = std::path::Path::new("p.json");
//! let out = parse(&spec(0.0), path).unwrap();
//! assert!(facing_in(&out, [0.0, 0.0]).is_empty());
//! let flipped = parse(&spec(180.0), path).unwrap();
//! let f = facing_in(&flipped, [0.0, 0.0]);
//! assert_eq!(f.len(), 1);
//! assert!((f[0].1 - 180.0).abs() < 1e-9);
//! ```

use super::spec::Pattern;
use nalgebra::Vector3;

/// The angle between a panel's normal and the way out from the body beyond which the panel
/// faces into it, degrees.
pub const FACING_IN_ANGLE_DEG: f64 = 120.0;

/// The panels of `pattern` that face into a body whose vertical axis (y up, the pattern's
/// frame and units) passes through `axis = [x, z]`: each name with the angle between its
/// normal and the way out, degrees. Panels whose centre is on the axis are not judged.
pub fn facing_in(pattern: &Pattern, axis: [f64; 2]) -> Vec<(String, f64)> {
    let limit = FACING_IN_ANGLE_DEG.to_radians().cos();
    let mut out = Vec::new();
    for p in &pattern.panels {
        let area = p.signed_area();
        if p.vertices.is_empty() || area == 0.0 {
            continue;
        }
        let n = p.rotation() * Vector3::new(0.0, 0.0, area.signum());
        let mean = p.vertices.iter().fold(Vector3::zeros(), |s, v| {
            s + p.place(*v).coords / p.vertices.len() as f64
        });
        let d = Vector3::new(mean.x - axis[0], 0.0, mean.z - axis[1]);
        let len = d.norm();
        if len < 1e-9 * (1.0 + mean.norm()) {
            continue;
        }
        let cos = n.dot(&d) / len;
        if cos < limit {
            out.push((p.name.clone(), cos.clamp(-1.0, 1.0).acos().to_degrees()));
        }
    }
    out
}
