//! Depth-image mode: the depth of a camera framing the mesh, rendered by halfray and by Embree
//! (robust), written side by side with a difference panel.

use crate::accel::MeshAccel;
use crate::embree::{EmbreeScene, takes_ray};
use crate::error::{Error, Result};
use halfray_core::triangle::TriangleVariant;
use image::{ImageEncoder, Rgb, RgbImage};

/// Colour of a pixel whose camera ray lies outside Embree's defined range ([`takes_ray`]),
/// in all three panels: neither side traces it, as the cross-check drops such rays.
const NOT_TRACED: Rgb<u8> = Rgb([255, 0, 255]);

/// The PNG of `halfray | Embree | difference` (`3·size × size` pixels). Depth panels map the nearest
/// hit to white and the farthest to dark grey, misses black. The difference panel is black where
/// both agree within the cross-check's `t` tolerance, red where only halfray hits, blue where
/// only Embree hits, and yellow where both hit at different depths. A pixel whose camera ray
/// Embree cannot take ([`takes_ray`]: a coordinate beyond `FLT_LARGE`, …) is traced by
/// neither side and magenta in all three panels. Prints the pixel counts.
pub fn depth_diff_png(
    accel: &MeshAccel,
    scene: &EmbreeScene,
    variant: TriangleVariant,
    size: usize,
) -> Result<Vec<u8>> {
    let (lo, hi) = accel.mesh.bounds().unwrap_or_default();
    let rays = crate::raysets::Camera::framing(lo, hi, size, size).rays();
    let traced: Vec<bool> = rays.iter().map(takes_ray).collect();
    let ours: Vec<Option<f32>> = rays
        .iter()
        .zip(&traced)
        .map(|(r, &ok)| {
            ok.then(|| accel.closest_variant(variant, r).map(|h| h.1.t))
                .flatten()
        })
        .collect();
    let emb: Vec<Option<f32>> = rays
        .iter()
        .zip(&traced)
        .map(|(r, &ok)| ok.then(|| scene.intersect_ray(r).map(|h| h.t)).flatten())
        .collect();
    let ts = ours.iter().chain(&emb).flatten().copied();
    let (tmin, tmax) = ts.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), t| {
        (a.min(t), b.max(t))
    });
    let shade = |t: Option<f32>| match t {
        None => Rgb([0, 0, 0]),
        Some(t) => {
            let k = if tmax > tmin {
                (t - tmin) / (tmax - tmin)
            } else {
                0.0
            };
            let g = (255.0f32 - 191.0 * k).round() as u8;
            Rgb([g, g, g])
        }
    };
    let mut img = RgbImage::new((3 * size) as u32, size as u32);
    let mut counts = [0usize; 4];
    for i in 0..rays.len() {
        let (x, y) = ((i % size) as u32, (i / size) as u32);
        if !traced[i] {
            counts[3] += 1;
            for panel in 0..3 {
                img.put_pixel(x + panel * size as u32, y, NOT_TRACED);
            }
            continue;
        }
        img.put_pixel(x, y, shade(ours[i]));
        img.put_pixel(x + size as u32, y, shade(emb[i]));
        let diff = match (ours[i], emb[i]) {
            (Some(_), None) => {
                counts[0] += 1;
                Rgb([255, 0, 0])
            }
            (None, Some(_)) => {
                counts[1] += 1;
                Rgb([0, 96, 255])
            }
            (Some(a), Some(b))
                if (a as f64 - b as f64).abs() > super::judge::t_tolerance(a as f64, 1.0) =>
            {
                counts[2] += 1;
                Rgb([255, 220, 0])
            }
            _ => Rgb([0, 0, 0]),
        };
        img.put_pixel(x + 2 * size as u32, y, diff);
    }
    crate::note!(
        "depth image: {}x{} px; only halfray hits: {}, only Embree hits: {}, depth differs: {}, \
         not traced (outside Embree's range): {}",
        size,
        size,
        counts[0],
        counts[1],
        counts[2],
        counts[3]
    );
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| Error::encode("the depth image", e))?;
    Ok(png)
}
