//! Pixels to PNG: sRGB encoding, coverage alpha, reading a background image (composited by
//! [`crate::composite`]), atomic write; colour ramps of the debug modes.

use crate::error::{Error, Location, Result};
use crate::outputs::OutputFile;
use glam::{Vec3, Vec4};
use image::{ImageEncoder, codecs::png::PngEncoder};
use std::path::Path;

/// Linear → sRGB transfer function (IEC 61966-2-1), input clamped to `[0, 1]`.
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB → linear.
pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// A `[0, 1]` value to 8 bits, rounded.
#[inline]
pub fn to_u8(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    (x * 255.0 + 0.5) as u8
}

/// Reads a background image as linear straight RGBA (decoded by `transfer`), checking its size.
pub fn read_background(
    path: &Path,
    width: u32,
    height: u32,
    transfer: super::gamma::Transfer,
) -> Result<Vec<Vec4>> {
    let img = image::ImageReader::open(path)
        .map_err(|e| Error::io(path, e))?
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?
        .decode()
        .map_err(|e| Error::input(Location::file(path), format!("cannot decode image: {e}")))?
        .into_rgba8();
    if img.width() != width || img.height() != height {
        return Err(Error::input(
            Location::file(path),
            format!(
                "background is {}×{} but the render is {width}×{height}",
                img.width(),
                img.height()
            ),
        ));
    }
    Ok(img
        .pixels()
        .map(|p| {
            let c = |k: usize| transfer.decode(f32::from(p.0[k]) / 255.0);
            Vec4::new(c(0), c(1), c(2), f32::from(p.0[3]) / 255.0)
        })
        .collect())
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

/// Heat-map colour of a count: `log2(1 + n) / 10` (1023 nodes → 1) through black, blue, cyan,
/// green, yellow, red. Fixed, so images of different scenes compare.
pub fn heat(n: u64) -> Vec3 {
    let t = ((1.0 + n as f32).log2() / 10.0).clamp(0.0, 1.0);
    const STOPS: [Vec3; 6] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
    ];
    let x = t * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    STOPS[i].lerp(STOPS[i + 1], x - i as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips() {
        for k in 0..=255u8 {
            let x = f32::from(k) / 255.0;
            assert_eq!(to_u8(linear_to_srgb(srgb_to_linear(x))), k);
        }
    }
}
