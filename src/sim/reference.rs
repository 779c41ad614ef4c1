//! Analytic answers the validation scenes and benchmarks compare against.

/// Irvine's elastic catenary (supports level, `span` apart): the horizontal tension (N per
/// unit width) and the midspan sag (m) of a cable of unstretched length `l0`, weight `w` per
/// unstretched length and axial stiffness `ea` (Irvine, *Cable Structures*, 1981, s. 1.3). The
/// span of a horizontal tension `H` is `H l0 / EA + 2 (H / w) asinh(w l0 / (2 H))`, solved for
/// `H` by bisection; the sag is `w l0^2 / (8 EA) + (H l0 / (w l0)) (sqrt(1 + (w l0 / 2H)^2) - 1)`.
///
/// ```
/// use drapekit::sim::reference::elastic_catenary;
/// // The hanging ribbon scene: 1 m of a 50 N/m knit between supports 1 m apart.
/// let (_, sag) = elastic_catenary(1.0, 1.0, 0.12 * 9.81, 50.5);
/// assert!((sag - 0.1042).abs() < 5e-4, "{sag}");
/// // Nearly inextensible: a 1 m chain between supports 0.8 m apart sags as the catenary
/// // `a (cosh(0.4 / a) - 1)` with `2 a sinh(0.4 / a) = 1`: 0.2654 m.
/// let (_, sag) = elastic_catenary(1.0, 0.8, 1.0, 1e9);
/// assert!((sag - 0.2654).abs() < 5e-4, "{sag}");
/// ```
pub fn elastic_catenary(l0: f64, span: f64, w: f64, ea: f64) -> (f64, f64) {
    let total = w * l0;
    let span_of = |h: f64| h * l0 / ea + 2.0 * (h / w) * (total / (2.0 * h)).asinh();
    let (mut lo, mut hi): (f64, f64) = (1e-9, 1e9);
    for _ in 0..300 {
        let mid = (lo * hi).sqrt();
        if span_of(mid) > span {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let h = (lo * hi).sqrt();
    let sag = total * l0 / (8.0 * ea)
        + (h * l0 / total) * ((1.0 + (total / (2.0 * h)).powi(2)).sqrt() - 1.0);
    (h, sag)
}
