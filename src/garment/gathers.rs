//! Stitches that join edges of different lengths: gathers (or eases).
//!
//! A stitch pairs its two edges by arc-length fraction, so the longer edge is gathered into the
//! shorter one by the ratio `L_long / L_short`: a bodice's 28.7 cm waist sewn to a skirt's
//! 22.0 cm is gathered by 1.30 (30%), and must buckle into folds along the seam. Pattern makers
//! want to see these before a drape, and a gathered seam is where sewing is slowest (the
//! longer side must fold while it closes). Differences under [`GATHER_MIN`] are rounding in
//! the pattern's curves, not gathers.
//!
//! ```
//! use drapekit::garment::{gathers::gathers, parse};
//! let json = r#"{"pattern": {"panels": {
//!   "a": {"vertices": [[0, 0], [13, 0], [13, 10], [0, 10]], "translation": [0, 0, 20], "rotation": [0, 0, 0],
//!         "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]},
//!   "b": {"vertices": [[0, 0], [10, 0], [10, 10], [0, 10]], "translation": [0, 12, 20], "rotation": [0, 0, 0],
//!         "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]}},
//!   "stitches": [[{"panel": "a", "edge": 2}, {"panel": "b", "edge": 0}]]},
//!   "properties": {"units_in_meter": 100}}"#;
//! let p = parse(json, std::path::Path::new("g.json")).unwrap();
//! let g = gathers(&p);
//! assert_eq!(g.len(), 1);
//! assert_eq!(g[0].edges, ["a:2".to_string(), "b:0".to_string()]);
//! assert!((g[0].lengths_mm[0] - 130.0).abs() < 1e-9 && (g[0].ratio - 1.3).abs() < 1e-12);
//! ```

use super::spec::{EdgeRef, Pattern};
use serde::Serialize;

/// The smallest ratio of a stitch's edge lengths reported as a gather: 2%.
pub const GATHER_MIN: f64 = 1.02;

/// A stitch whose edges differ in length by at least [`GATHER_MIN`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gather {
    /// The stitch (1-based, in the file's order, as in `open_seams`).
    pub stitch: usize,
    /// Its two edges, `panel:edge` (edges 0-based, as in the file).
    pub edges: [String; 2],
    /// Their arc lengths, mm.
    pub lengths_mm: [f64; 2],
    /// The longer over the shorter.
    pub ratio: f64,
}

/// The gathered stitches of `pattern`, in the file's order.
pub fn gathers(pattern: &Pattern) -> Vec<Gather> {
    let mm = 1e3 / pattern.units_in_meter;
    let length = |e: &EdgeRef| {
        let panel = &pattern.panels[e.panel];
        panel.edges[e.edge].length(&panel.vertices) * mm
    };
    let name = |e: &EdgeRef| format!("{}:{}", pattern.panels[e.panel].name, e.edge);
    pattern
        .stitches
        .iter()
        .enumerate()
        .filter_map(|(i, s)| {
            let l = [length(&s.a), length(&s.b)];
            let ratio = l[0].max(l[1]) / l[0].min(l[1]);
            (ratio >= GATHER_MIN).then(|| Gather {
                stitch: i + 1,
                edges: [name(&s.a), name(&s.b)],
                lengths_mm: l,
                ratio,
            })
        })
        .collect()
}
