//! An RGB picture, and its encodings: PNG, animated PNG (APNG) and GIF.
//!
//! PNG and APNG are written by the `png` crate (8-bit RGB, no metadata: the same picture gives
//! the same bytes); GIF by the `gif` crate, each frame reduced to its own 256-colour palette by
//! NeuQuant (deterministic for a given picture).

use std::io::Write;

/// A colour, 8-bit sRGB.
pub type Rgb = [u8; 3];

/// A picture: `width x height` pixels, row-major, top row first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// The pixels.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// A picture filled with `colour`.
    pub fn new(width: u32, height: u32, colour: Rgb) -> Image {
        Image {
            width,
            height,
            pixels: vec![colour; width as usize * height as usize],
        }
    }

    /// Sets pixel `(x, y)` when it is inside the picture.
    pub fn put(&mut self, x: i64, y: i64, colour: Rgb) {
        if (0..i64::from(self.width)).contains(&x) && (0..i64::from(self.height)).contains(&y) {
            self.pixels[y as usize * self.width as usize + x as usize] = colour;
        }
    }

    /// Pixel `(x, y)`.
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Fills the rectangle `[x0, x1) x [y0, y1)` (clipped to the picture).
    pub fn fill(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, colour: Rgb) {
        for y in y0..y1 {
            for x in x0..x1 {
                self.put(x, y, colour);
            }
        }
    }

    /// The pixels as bytes, `r g b` each.
    pub fn bytes(&self) -> Vec<u8> {
        self.pixels.iter().flatten().copied().collect()
    }
}

fn png_error(e: png::EncodingError) -> std::io::Error {
    match e {
        png::EncodingError::IoError(e) => e,
        e => std::io::Error::other(e),
    }
}

/// Writes `img` as an 8-bit RGB PNG.
pub fn write_png(w: impl Write, img: &Image) -> std::io::Result<()> {
    let mut enc = png::Encoder::new(w, img.width, img.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().map_err(png_error)?;
    writer.write_image_data(&img.bytes()).map_err(png_error)?;
    writer.finish().map_err(png_error)
}

/// A frame's size against the animation's: an error when they differ.
fn same_size(f: &Image, size: [u32; 2]) -> std::io::Result<()> {
    if [f.width, f.height] == size {
        return Ok(());
    }
    Err(std::io::Error::other(format!(
        "a frame of {} x {} px in an animation of {} x {} px",
        f.width, f.height, size[0], size[1]
    )))
}

/// Writes `count` frames of `size` px (at least one) as an animated PNG that loops forever,
/// showing each for `delay_ms` milliseconds. Viewers without APNG support show the first.
/// Each frame is encoded as soon as `frames` yields it, so only one is ever held; an error
/// from `frames`, a frame of another size or a count other than `count` stops the writing.
pub fn write_apng<B: std::borrow::Borrow<Image>>(
    w: impl Write,
    size: [u32; 2],
    count: usize,
    delay_ms: u16,
    frames: impl IntoIterator<Item = std::io::Result<B>>,
) -> std::io::Result<()> {
    let n = u32::try_from(count).map_err(std::io::Error::other)?;
    let mut enc = png::Encoder::new(w, size[0], size[1]);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_animated(n, 0).map_err(png_error)?;
    enc.set_frame_delay(delay_ms, 1000).map_err(png_error)?;
    let mut writer = enc.write_header().map_err(png_error)?;
    let mut written = 0;
    for f in frames {
        let f = f?;
        same_size(f.borrow(), size)?;
        writer
            .write_image_data(&f.borrow().bytes())
            .map_err(png_error)?;
        written += 1;
    }
    if written != count {
        return Err(std::io::Error::other(format!(
            "{written} frame(s) for an animation of {count}"
        )));
    }
    writer.finish().map_err(png_error)
}

/// Writes the frames of `size` px (at least one) as a GIF that loops forever, showing each for
/// `delay_cs` hundredths of a second, each encoded as soon as `frames` yields it (one held at a
/// time).
pub fn write_gif<B: std::borrow::Borrow<Image>>(
    w: impl Write,
    size: [u32; 2],
    delay_cs: u16,
    frames: impl IntoIterator<Item = std::io::Result<B>>,
) -> std::io::Result<()> {
    let side = |v: u32| u16::try_from(v).map_err(std::io::Error::other);
    let (width, height) = (side(size[0])?, side(size[1])?);
    let gif_error = |e: gif::EncodingError| match e {
        gif::EncodingError::Io(e) => e,
        e => std::io::Error::other(e),
    };
    let mut enc = gif::Encoder::new(w, width, height, &[]).map_err(gif_error)?;
    enc.set_repeat(gif::Repeat::Infinite).map_err(gif_error)?;
    for f in frames {
        let f = f?;
        same_size(f.borrow(), size)?;
        let mut frame = gif::Frame::from_rgb_speed(width, height, &f.borrow().bytes(), 10);
        frame.delay = delay_cs;
        enc.write_frame(&frame).map_err(gif_error)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;
    use std::rc::Rc;

    /// A writer whose bytes can be counted while it is in use.
    #[derive(Clone, Default)]
    struct Shared(Rc<RefCell<Vec<u8>>>);

    impl Write for Shared {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.0.borrow_mut().extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn animations_are_written_a_frame_at_a_time() {
        for gif in [false, true] {
            let out = Shared::default();
            // The bytes written before each frame is made: an encoder that gathered every
            // frame before writing any would see the same count at each.
            let seen = RefCell::new(Vec::new());
            let make = |k: usize| {
                seen.borrow_mut().push(out.0.borrow().len());
                Ok(Image::new(16, 16, [k as u8 * 40, 0, 0]))
            };
            let frames = (0..4).map(make);
            if gif {
                write_gif(out.clone(), [16, 16], 10, frames).unwrap();
            } else {
                write_apng(out.clone(), [16, 16], 4, 100, frames).unwrap();
            }
            let seen = seen.into_inner();
            assert!(seen.windows(2).all(|w| w[1] > w[0]), "gif {gif}: {seen:?}");
        }
    }

    #[test]
    fn an_animation_of_the_wrong_count_or_size_is_refused() {
        let f = |w| Ok(Image::new(w, 16, [0; 3]));
        let short = write_apng(Vec::new(), [16, 16], 3, 100, [f(16), f(16)]);
        assert!(short.unwrap_err().to_string().contains("2 frame(s)"));
        let wide = write_gif(Vec::new(), [16, 16], 10, [f(16), f(20)]);
        assert!(wide.unwrap_err().to_string().contains("20 x 16 px"));
    }
}
