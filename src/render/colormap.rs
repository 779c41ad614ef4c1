//! Colouring by a quantity: viridis, the two contact colours, and the legend drawn into the
//! picture.
//!
//! Viridis (van der Walt and Smith, matplotlib's default map) is perceptually uniform and its
//! lightness rises monotonically from dark violet to yellow, so a larger value is always a
//! lighter colour, also in grey print and for colour-blind readers. It is kept here as its 11
//! colours at `t = 0, 0.1, ..., 1` and interpolated linearly between them in sRGB: its luminance
//! rises by more than one unit (of 255) for every 1% of the scale. A value `v` on a scale `[min, max]`
//! takes the colour at `t = (v - min) / (max - min)`, clamped to `[0, 1]` (`t = 0.5` when
//! `min = max`).

use super::font;
use super::image::{Image, Rgb};

/// Viridis at `t = 0, 0.1, ..., 1`.
const VIRIDIS: [Rgb; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

/// Viridis at `t` (clamped to `[0, 1]`; NaN is 0).
///
/// ```
/// use drapekit::render::colormap::viridis;
/// assert_eq!(viridis(0.0), [0x44, 0x01, 0x54]);
/// assert_eq!(viridis(1.0), [0xfd, 0xe7, 0x25]);
/// assert_eq!(viridis(0.05), [70, 19, 101]); // halfway between the first two
/// ```
pub fn viridis(t: f64) -> Rgb {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * 10.0;
    let k = (t.floor() as usize).min(9);
    let f = t - k as f64;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    [0, 1, 2].map(|c| (f64::from(a[c]) + f * (f64::from(b[c]) - f64::from(a[c]))).round() as u8)
}

/// Relative luminance (Rec. 709 weights on the sRGB values), 0 to 255.
pub fn luminance(c: Rgb) -> f64 {
    0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2])
}

/// Colour of a vertex in contact.
pub const CONTACT: Rgb = [0xd6, 0x27, 0x28];
/// Colour of a vertex out of contact.
pub const FREE: Rgb = [0x9e, 0xc9, 0xe2];

/// How per-vertex values become colours.
#[derive(Debug, Clone, PartialEq)]
pub enum ColourScale {
    /// Viridis from `min` to `max`; the legend shows `title` and both ends.
    Continuous {
        /// The value at the dark end.
        min: f64,
        /// The value at the light end.
        max: f64,
        /// The legend's title (upper case; see `font`).
        title: String,
    },
    /// Two colours: [`CONTACT`] where the value is at least 0.5, [`FREE`] elsewhere.
    Contact,
}

impl ColourScale {
    /// The colour of value `v`.
    pub fn colour(&self, v: f64) -> Rgb {
        match self {
            ColourScale::Continuous { min, max, .. } => {
                let t = if max > min {
                    (v - min) / (max - min)
                } else {
                    0.5
                };
                viridis(t)
            }
            ColourScale::Contact if v >= 0.5 => CONTACT,
            ColourScale::Contact => FREE,
        }
    }
}

/// A number as the legend prints it: at most four significant digits, no trailing zeros.
pub fn label(v: f64) -> String {
    crate::math::short(v)
}

/// Font pixels per picture pixel for a picture `height` pixels tall.
pub fn font_scale(height: u32) -> i64 {
    if height >= 400 {
        2
    } else {
        1
    }
}

/// The legend's width for a picture `height` pixels tall: room for nine characters.
pub fn legend_width(height: u32) -> u32 {
    let s = font_scale(height);
    (font::text_width("-0.0000e-0", s) + 4 * s) as u32
}

/// Draws the legend for `scale` into the strip `[x0, width)` of `img`: the title, the maximum,
/// a bar from the light end (top) to the dark end (bottom), the minimum; or the two contact
/// colours with their names.
pub fn draw_legend(img: &mut Image, x0: u32, scale: &ColourScale, ink: Rgb) {
    let s = font_scale(img.height);
    let line = (font::HEIGHT + 3) * s;
    let (x, h) = (i64::from(x0) + 2 * s, i64::from(img.height));
    let top = (h as f64 * super::camera::MARGIN) as i64;
    match scale {
        ColourScale::Continuous { min, max, title } => {
            font::draw_text(img, x, top, title, s, ink);
            font::draw_text(img, x, top + line, &label(*max), s, ink);
            let (bar0, bar1) = (top + 2 * line, h - top - line);
            let bar_w = 6 * font::WIDTH * s / 2;
            for y in bar0..bar1 {
                let t = (bar1 - 1 - y) as f64 / ((bar1 - bar0 - 1).max(1)) as f64;
                img.fill(x, y, x + bar_w, y + 1, viridis(t));
            }
            font::draw_text(img, x, bar1 + 3 * s, &label(*min), s, ink);
        }
        ColourScale::Contact => {
            for (k, (name, colour)) in [("CONTACT", CONTACT), ("FREE", FREE)].iter().enumerate() {
                let y = top + k as i64 * 2 * line;
                img.fill(x, y, x + font::HEIGHT * s, y + font::HEIGHT * s, *colour);
                font::draw_text(img, x + (font::HEIGHT + 2) * s, y, name, s, ink);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_gets_lighter_as_values_grow() {
        // Steps of 1% are always lighter; finer steps never darker beyond the rounding of one
        // 8-bit channel (0.2126 of a unit: red falls where green rises).
        let lum = |n: usize| -> Vec<f64> {
            (0..=n)
                .map(|k| luminance(viridis(k as f64 / n as f64)))
                .collect()
        };
        assert!(lum(100).windows(2).all(|w| w[1] > w[0] + 1.0), "1% lighter");
        assert!(lum(1000).windows(2).all(|w| w[1] > w[0] - 0.22));
        assert!(lum(10)[10] - lum(10)[0] > 190.0);
        let s = ColourScale::Continuous {
            min: -0.02,
            max: 0.08,
            title: "STRAIN".into(),
        };
        assert_eq!(s.colour(-1.0), viridis(0.0));
        assert_eq!(s.colour(0.03), viridis(0.5));
        assert_eq!(s.colour(1.0), viridis(1.0));
    }
}
