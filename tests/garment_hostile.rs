//! Hostile GarmentCode patterns: each defect the pattern hunt found, refused with a clear
//! error or handled, never a panic.

mod common;

use drapekit::garment::assemble::{assemble, AssembleOptions};
use drapekit::garment::parse;
use std::path::Path;

/// The tube fixture's text.
fn tube() -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/garments/tube_specification.json");
    std::fs::read_to_string(p).unwrap()
}

#[test]
fn a_vertex_at_minus_zero_is_sewn_like_one_at_zero() {
    // JSON writers (Python's among them) write a negative zero as -0.0; the cloth's outline
    // particle came back as +0 and the lookup of the sample's particle panicked.
    let text = tube().replacen("[[-30, 0], [30, 0]", "[[-30, -0.0], [30, -0.0]", 1);
    assert_ne!(text, tube());
    let pattern = parse(&text, Path::new("p.json")).unwrap();
    let opts = AssembleOptions {
        spacing: 0.04,
        ..AssembleOptions::default()
    };
    let a = assemble(&pattern, &opts).unwrap();
    let plain = assemble(&parse(&tube(), Path::new("p.json")).unwrap(), &opts).unwrap();
    assert_eq!(a.seams, plain.seams);
    assert_eq!(a.edge_particles, plain.edge_particles);
}
