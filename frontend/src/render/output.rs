//! Reading a background image (composited by [`crate::composite`]); colour ramps of the debug
//! modes.

use super::gamma::Transfer;
use crate::error::{Error, Location, Result};
use glam::{Vec3, Vec4};
use std::path::Path;

/// Reads a background image as straight RGBA in `[0, 1]`, checking its size: colour decoded
/// to linear by `transfer`, or with `None` the stored 8-bit values / 255 (the space the debug
/// modes are written in, [`super::Mode::transfer`]); alpha is always the stored value / 255.
pub fn read_background(
    path: &Path,
    width: u32,
    height: u32,
    transfer: Option<Transfer>,
) -> Result<Vec<Vec4>> {
    let img = crate::png::read_rgba8(path)?;
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
            let c = |k: usize| {
                let stored = f32::from(p.0[k]) / 255.0;
                transfer.map_or(stored, |t| t.decode(stored))
            };
            Vec4::new(c(0), c(1), c(2), f32::from(p.0[3]) / 255.0)
        })
        .collect())
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

    /// Colour units (0–1): `t` and the stop position `5t` are rounded in `f32`, so a stop is
    /// met within a few ulps of 1 (`5 · fl(0.2)` is `1 + 1.5e-8`).
    const STOP_AGREEMENT: f32 = 1e-6;

    /// The heat map's ramp: `t = log2(1 + n) / 10` through black, blue, cyan, green, yellow
    /// and red at `t = 0, 0.2, 0.4, 0.6, 0.8, 1`, so 0 nodes are black, 3 blue, 15 cyan, 63
    /// green, 255 yellow and 1023 (or more) red, within [`STOP_AGREEMENT`].
    #[test]
    fn the_heat_ramp_passes_its_stops() {
        for (n, want) in [
            (0, Vec3::ZERO),
            (3, Vec3::Z),
            (15, Vec3::new(0.0, 1.0, 1.0)),
            (63, Vec3::Y),
            (255, Vec3::new(1.0, 1.0, 0.0)),
            (1023, Vec3::X),
            (1 << 40, Vec3::X),
        ] {
            let got = heat(n);
            assert!(
                (got - want).abs().max_element() < STOP_AGREEMENT,
                "{n}: {got}"
            );
        }
    }
}
