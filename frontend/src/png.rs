//! 8-bit pixels: quantisation of `[0, 1]` values and PNG encoding to a reserved output.

use crate::error::Result;
use crate::outputs::OutputFile;
use image::{ImageEncoder, codecs::png::PngEncoder};

/// A `[0, 1]` value to 8 bits, rounded.
#[inline]
pub fn to_u8(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    (x * 255.0 + 0.5) as u8
}

/// Writes 8-bit RGBA as PNG to a reserved output (atomically, see [`OutputFile`]).
pub fn write_png(out: OutputFile, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    out.write(|w| encode_png(w, width, height, rgba))
}

/// 8-bit RGBA as PNG bytes.
pub fn encode_png(
    w: &mut dyn std::io::Write,
    width: u32,
    height: u32,
    rgba: &[u8],
) -> std::io::Result<()> {
    PngEncoder::new(w)
        .write_image(rgba, width, height, image::ExtendedColorType::Rgba8)
        .map_err(std::io::Error::other)
}
