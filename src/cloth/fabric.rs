//! Fabric parameters, their conversion from Kawabata (KES-F) measurements, and named presets.
//!
//! A fabric is given in material terms, independent of the particle spacing `h`; the springs and
//! bending elements of the paper's model (`method.md` s. 2) get their constants from them:
//!
//! * **stretch** `E` (N/m, force per unit width per unit strain), warp and weft: a spring along a
//!   thread between neighbours carries a strip of width `h` over length `h`, so `k = E`.
//! * **shear** `G` (N/m per radian): the two diagonal springs of a cell sheared by `g` store
//!   `k h^2 g^2 / 2`, the continuum's `G g^2 h^2 / 2`, so `k = G`.
//! * **bend** `B` (N m, bending rigidity per unit width), warp and weft: the paper connects each
//!   node's two neighbours over it along a thread. A strip of width `h` bent to curvature `k`
//!   stores `B k^2 h^2 / 2` per node, and the second difference `x_{i-1} - 2 x_i + x_{i+1}` is
//!   `h^2 k` long, so the element over the node stores `(B / h^2) |x_{i-1} - 2 x_i + x_{i+1}|^2 / 2`
//!   (`cloth::pattern`). The paper's linear spring between the same two particles stores
//!   `k h^2 t^4 / 32` for a fold of `t` radians: nothing for gentle folds, and it adds `4k` to the
//!   tensile stiffness; we keep its neighbours and replace its law.
//! * **density** (kg/m^2) gives the particle masses (a third of each incident triangle's area).
//! * **damping** (1/s) is air damping, the force `-damping * m * v` of the paper's `-c_i r_i'`.
//! * **thickness** (m): particles are kept this far from object faces.
//! * **friction** (0..1): the fraction of the tangential force a sliding particle loses.
//!
//! KES-F units convert as: `W` mg/cm^2 x 0.01 = kg/m^2; `B` gf cm^2/cm x 9.80665e-5 = N m;
//! `G` gf/cm/degree x 56.1891 = N/m per radian; tensile stiffness is the secant at the KES load
//! of 500 gf/cm, `490.3325 / (EMT / 100)` N/m; `T` mm x 1e-3 = m; `MIU` is the friction.
//!
//! The presets are **representative** values inside the ranges published for KES-F
//! measurements of each fabric class (Kawabata, *The Standardization and Analysis of Hand
//! Evaluation*, 1980; Hu and Chan, *Textile Research Journal* 68(1), 1998, 57-64; Kenkare and
//! May-Plumlee, *Journal of Textile and Apparel Technology and Management* 4(3), 2005), not the
//! measurement of one particular cloth. Give your own with a `[fabric.NAME]` table.

use crate::math::short;
use serde::Serialize;

/// A fabric (SI units).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fabric {
    /// Areal density, kg/m^2.
    pub density: f64,
    /// Tensile stiffness along warp and weft, N/m.
    pub stretch: [f64; 2],
    /// Shear stiffness, N/m per radian.
    pub shear: f64,
    /// Bending rigidity along warp and weft, N m.
    pub bend: [f64; 2],
    /// Air damping, 1/s.
    pub damping: f64,
    /// Thickness, m.
    pub thickness: f64,
    /// Friction against objects, fraction of the tangential force (0..1).
    pub friction: f64,
}

/// KES-F measurements of a fabric (Kawabata's units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kes {
    /// Mass per area, mg/cm^2.
    pub w: f64,
    /// Bending rigidity warp, weft, gf cm^2/cm.
    pub b: [f64; 2],
    /// Shear rigidity, gf/cm/degree.
    pub g: f64,
    /// Extensibility at 500 gf/cm warp, weft, %.
    pub emt: [f64; 2],
    /// Thickness at 0.5 gf/cm^2, mm.
    pub t: f64,
    /// Coefficient of friction.
    pub miu: f64,
}

impl Fabric {
    /// The fabric of KES-F measurements, with air damping `damping` (1/s).
    ///
    /// ```
    /// use drapekit::cloth::fabric::{Fabric, Kes};
    /// let f = Fabric::from_kes(&Kes { w: 12.0, b: [0.08, 0.06], g: 0.8, emt: [4.0, 5.0], t: 0.3, miu: 0.25 }, 0.5);
    /// assert!((f.density - 0.12).abs() < 1e-12);
    /// assert!((f.stretch[0] - 12_258.3125).abs() < 1e-6);
    /// assert!((f.bend[0] - 7.84532e-6).abs() < 1e-12);
    /// ```
    pub fn from_kes(k: &Kes, damping: f64) -> Fabric {
        Fabric {
            density: k.w * 0.01,
            stretch: k.emt.map(|e| 490.332_5 / (e / 100.0)),
            shear: k.g * 56.189_1,
            bend: k.b.map(|b| b * 9.806_65e-5),
            damping,
            thickness: k.t * 1e-3,
            friction: k.miu,
        }
    }

    /// The named presets and their KES-F values.
    pub fn presets() -> Vec<(&'static str, Kes)> {
        vec![
            (
                "silk",
                Kes {
                    w: 6.0,
                    b: [0.015, 0.012],
                    g: 0.35,
                    emt: [3.5, 4.5],
                    t: 0.15,
                    miu: 0.18,
                },
            ),
            (
                "cotton",
                Kes {
                    w: 12.0,
                    b: [0.08, 0.06],
                    g: 0.8,
                    emt: [4.0, 5.0],
                    t: 0.30,
                    miu: 0.25,
                },
            ),
            (
                "wool",
                Kes {
                    w: 22.0,
                    b: [0.11, 0.09],
                    g: 0.65,
                    emt: [6.0, 8.0],
                    t: 0.55,
                    miu: 0.20,
                },
            ),
            (
                "polyester",
                Kes {
                    w: 10.0,
                    b: [0.05, 0.05],
                    g: 0.9,
                    emt: [3.0, 3.5],
                    t: 0.25,
                    miu: 0.22,
                },
            ),
            (
                "denim",
                Kes {
                    w: 40.0,
                    b: [0.9, 0.6],
                    g: 3.0,
                    emt: [2.5, 3.5],
                    t: 0.9,
                    miu: 0.30,
                },
            ),
        ]
    }

    /// A preset by name (air damping 0.5/s), or `None`.
    pub fn preset(name: &str) -> Option<Fabric> {
        Fabric::presets()
            .into_iter()
            .find(|(n, _)| *n == name)
            .map(|(_, k)| Fabric::from_kes(&k, 0.5))
    }

    /// The cotton preset.
    pub fn cotton() -> Fabric {
        Fabric::preset("cotton").expect("a preset")
    }

    /// Tensile modulus (N/m) along the direction `(c, s)` (cosine and sine with the warp) of the
    /// orthotropic sheet: `1 / (c^4 / E_warp + s^4 / E_weft + c^2 s^2 / G)`. Along the threads it
    /// is the thread's stiffness; on the bias (45 degrees) about `4 G`, as woven cloth stretches
    /// on the bias.
    ///
    /// ```
    /// use drapekit::cloth::fabric::Fabric;
    /// let f = Fabric { stretch: [1000.0, 500.0], shear: 10.0, ..Fabric::cotton() };
    /// assert!((f.directional_stretch(1.0, 0.0) - 1000.0).abs() < 1e-9);
    /// assert!((f.directional_stretch(0.0, 1.0) - 500.0).abs() < 1e-9);
    /// let r = 0.5f64.sqrt();
    /// assert!((f.directional_stretch(r, r) - 1.0 / (0.25e-3 + 0.5e-3 + 0.025)).abs() < 1e-9);
    /// ```
    pub fn directional_stretch(&self, c: f64, s: f64) -> f64 {
        let (c2, s2) = (c * c, s * s);
        let mut compliance = c2 * c2 / self.stretch[0] + s2 * s2 / self.stretch[1];
        if c2 * s2 > 0.0 {
            if self.shear <= 0.0 {
                return 0.0;
            }
            compliance += c2 * s2 / self.shear;
        }
        1.0 / compliance
    }

    /// Every bad value: the field's name and why (empty when the fabric is valid).
    ///
    /// ```
    /// use drapekit::cloth::fabric::Fabric;
    /// let f = Fabric { density: -1.0, friction: 2.0, ..Fabric::cotton() };
    /// let p = f.problems();
    /// assert_eq!(p.iter().map(|e| e.0).collect::<Vec<_>>(), ["density", "friction"]);
    /// assert!(Fabric::cotton().problems().is_empty());
    /// ```
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut out = Vec::new();
        let mut pos = |name: &'static str, v: f64| {
            if !(v.is_finite() && v > 0.0) {
                out.push((name, format!("must be a positive number, got {}", short(v))));
            }
        };
        pos("density", self.density);
        pos("stretch", self.stretch[0]);
        pos("stretch", self.stretch[1]);
        for (name, v) in [
            ("shear", self.shear),
            ("bend", self.bend[0]),
            ("bend", self.bend[1]),
            ("damping", self.damping),
            ("thickness", self.thickness),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                out.push((name, format!("must be a number >= 0, got {}", short(v))));
            }
        }
        if !(0.0..=1.0).contains(&self.friction) {
            out.push((
                "friction",
                format!("must be within 0..1, got {}", short(self.friction)),
            ));
        }
        out
    }
}
