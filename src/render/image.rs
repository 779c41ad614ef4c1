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

/// Writes `frames` (all of one size, at least one) as an animated PNG that loops forever,
/// showing each for `delay_ms` milliseconds. Viewers without APNG support show the first.
pub fn write_apng(w: impl Write, frames: &[Image], delay_ms: u16) -> std::io::Result<()> {
    let first = &frames[0];
    let mut enc = png::Encoder::new(w, first.width, first.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_animated(frames.len() as u32, 0)
        .map_err(png_error)?;
    enc.set_frame_delay(delay_ms, 1000).map_err(png_error)?;
    let mut writer = enc.write_header().map_err(png_error)?;
    for f in frames {
        writer.write_image_data(&f.bytes()).map_err(png_error)?;
    }
    writer.finish().map_err(png_error)
}

/// Writes `frames` (all of one size, at least one) as a GIF that loops forever, showing each
/// for `delay_cs` hundredths of a second.
pub fn write_gif(w: impl Write, frames: &[Image], delay_cs: u16) -> std::io::Result<()> {
    let first = &frames[0];
    let (width, height) = (first.width as u16, first.height as u16);
    let gif_error = |e: gif::EncodingError| match e {
        gif::EncodingError::Io(e) => e,
        e => std::io::Error::other(e),
    };
    let mut enc = gif::Encoder::new(w, width, height, &[]).map_err(gif_error)?;
    enc.set_repeat(gif::Repeat::Infinite).map_err(gif_error)?;
    for f in frames {
        let mut frame = gif::Frame::from_rgb_speed(width, height, &f.bytes(), 10);
        frame.delay = delay_cs;
        enc.write_frame(&frame).map_err(gif_error)?;
    }
    Ok(())
}
