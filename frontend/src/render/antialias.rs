//! Adaptive anti-aliasing (`render --samples N`): one ray through every pixel's centre, then
//! up to `N − 1` more only in pixels that differ from a 4-neighbour by more than
//! [`CONTRAST`] — silhouettes, shadow boundaries, mirror rims — so a flat region costs one ray
//! per pixel. The extra samples sit at fixed sub-pixel positions ([`offset`]), so a render is
//! reproducible and `--force-all-effects` stays byte-identical.
//!
//! A refined pixel is the box-filtered mean of its samples, coverage included: alpha is the
//! fraction of samples that hit, and the colour is the alpha-weighted (premultiplied) mean of
//! the hits' colours, kept straight; a pixel no sample hits keeps its centre sample.

use super::gamma::linear_to_srgb;
use super::{PixelOut, RayCounts};
use crate::scene::MAX_LIGHT_SAMPLES;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::LazyLock;

/// Largest difference between a pixel and a 4-neighbour that leaves it with one sample: in
/// sRGB-encoded units of `[0, 1]` per colour channel, and in alpha. 8/255: the steps of a
/// smoothly lit surface between neighbouring pixels stay below it at ordinary resolutions
/// (a ramp needs no anti-aliasing), while silhouettes, shadow boundaries and mirror rims jump
/// by far more.
pub const CONTRAST: f32 = 8.0 / 255.0;

/// Sub-pixel position of extra sample `k ≥ 1`, in `[0, 1)²` from the pixel's corner: the R2
/// low-discrepancy sequence (Roberts, 2018) started at the centre (`k = 0`), so every prefix
/// covers the pixel evenly.
pub fn offset(k: u32) -> (f32, f32) {
    // The plastic number's reciprocals, ρ⁻¹ and ρ⁻².
    const A1: f64 = 0.754_877_666_246_692_7;
    const A2: f64 = 0.569_840_290_998_053_2;
    let k = f64::from(k);
    ((0.5 + A1 * k).fract() as f32, (0.5 + A2 * k).fract() as f32)
}

/// Lens position of sample `k` in the unit square: the Halton sequence in bases 2 and 3
/// (independent of [`offset`]'s R2 sequence, so lens and sub-pixel positions do not align).
pub fn lens_offset(k: u32) -> (f32, f32) {
    let radical = |mut n: u32, base: u32| {
        let (mut x, mut f) = (0.0f64, 1.0f64);
        while n > 0 {
            f /= f64::from(base);
            x += f * f64::from(n % base);
            n /= base;
        }
        x as f32
    };
    (radical(k + 1, 2), radical(k + 1, 3))
}

/// The unit square to the unit disk, area-preserving and continuous (Shirley and Chiu's
/// concentric mapping): `(½, ½)` to the centre, the square's edges to the circle.
pub fn concentric_disk(u: f32, v: f32) -> (f32, f32) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, std::f32::consts::FRAC_PI_4 * (b / a))
    } else {
        (
            b,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a / b),
        )
    };
    (r * phi.cos(), r * phi.sin())
}

/// The points of an area light's disk its `samples` shadow rays aim at, in the disk's unit
/// frame: [`concentric_disk`] of [`lens_offset`]`(k)` for `k < samples`. The first
/// [`MAX_LIGHT_SAMPLES`] (as many as a scene may ask for) are computed once per process, not
/// per shading point; the values are a pure function of `k`, so each hit reads the very
/// values it would compute.
pub fn disk_points(samples: u32) -> impl Iterator<Item = (f32, f32)> {
    static POINTS: LazyLock<Vec<(f32, f32)>> =
        LazyLock::new(|| (0..MAX_LIGHT_SAMPLES).map(disk_point).collect());
    let table: &[(f32, f32)] = &POINTS;
    (0..samples).map(move |k| {
        table
            .get(k as usize)
            .copied()
            .unwrap_or_else(|| disk_point(k))
    })
}

/// [`concentric_disk`] of [`lens_offset`]`(k)`.
fn disk_point(k: u32) -> (f32, f32) {
    let (u, v) = lens_offset(k);
    concentric_disk(u, v)
}

/// The box-filtered mean of samples (the first one the reference, used alone when no sample
/// hits): alpha the fraction that hit, colour the alpha-weighted mean of theirs.
pub(super) fn mean(samples: impl IntoIterator<Item = PixelOut>) -> PixelOut {
    let mut it = samples.into_iter();
    let Some(first) = it.next() else {
        return PixelOut::default();
    };
    let (mut premult, mut alpha, mut n) = (first.value * first.alpha, first.alpha, 1.0f32);
    for s in it {
        premult += s.value * s.alpha;
        alpha += s.alpha;
        n += 1.0;
    }
    let mut out = first;
    if alpha > 0.0 {
        out.value = premult / alpha;
        out.alpha = alpha / n;
    }
    out
}

/// `true` when pixels `a` and `b` differ by more than [`CONTRAST`].
fn differ(a: &PixelOut, b: &PixelOut) -> bool {
    let enc = |v: Vec3| v.to_array().map(linear_to_srgb);
    let (ca, cb) = (enc(a.value), enc(b.value));
    (a.alpha - b.alpha).abs() > CONTRAST || ca.iter().zip(cb).any(|(x, y)| (x - y).abs() > CONTRAST)
}

/// Whether pixel `i` of a `w`-wide image differs from a 4-neighbour.
fn is_edge(px: &[PixelOut], w: usize, i: usize) -> bool {
    let (x, y) = (i % w, i / w);
    let mut n = [None; 4];
    if x > 0 {
        n[0] = Some(i - 1);
    }
    if x + 1 < w {
        n[1] = Some(i + 1);
    }
    if y > 0 {
        n[2] = Some(i - w);
    }
    n[3] = Some(i + w).filter(|&j| j < px.len());
    n.into_iter().flatten().any(|j| differ(&px[i], &px[j]))
}

/// Indices of the pixels of a `w`-wide image that differ from a 4-neighbour.
#[cfg(test)]
fn edges(px: &[PixelOut], w: u32) -> Vec<usize> {
    (0..px.len())
        .filter(|&i| is_edge(px, w as usize, i))
        .collect()
}

/// Refines the pixels of `px` that differ from a 4-neighbour (one centre sample each) to
/// `samples` samples with `sample(x, y, counts)` (image coordinates in pixels), in parallel and
/// in place; returns the rays the extra samples cast. Beside `px` it holds one byte a pixel
/// (which pixels to refine, decided on the unrefined image) and each thread's one pixel's
/// samples ([`super::render_bytes`]).
pub(super) fn refine(
    px: &mut [PixelOut],
    w: u32,
    samples: u32,
    sample: impl Fn(f32, f32, &mut RayCounts) -> PixelOut + Sync,
) -> RayCounts {
    let w = w as usize;
    let todo: Vec<bool> = {
        let px = &*px;
        (0..px.len())
            .into_par_iter()
            .map(|i| is_edge(px, w, i))
            .collect()
    };
    px.par_iter_mut()
        .zip(todo)
        .enumerate()
        .filter(|(_, (_, edge))| *edge)
        .map(|(i, (p, _))| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let mut counts = RayCounts::default();
            let extra: Vec<PixelOut> = (1..samples.min(crate::scene::MAX_SAMPLES))
                .map(|k| {
                    let (dx, dy) = offset(k);
                    sample(x + dx, y + dy, &mut counts)
                })
                .collect();
            *p = mean(std::iter::once(*p).chain(extra));
            counts
        })
        .reduce(RayCounts::default, |mut a, b| {
            a.add(&b);
            a
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn px(value: f32, alpha: f32) -> PixelOut {
        PixelOut {
            value: Vec3::splat(value),
            alpha,
            ..PixelOut::default()
        }
    }

    #[test]
    fn disk_points_are_the_halton_points_mapped_to_the_disk() {
        // Within the table, past it (a light built without the scene's limit), and none.
        for samples in [0, 1, 16, MAX_LIGHT_SAMPLES, MAX_LIGHT_SAMPLES + 44] {
            let got: Vec<(f32, f32)> = disk_points(samples).collect();
            assert_eq!(got.len(), samples as usize);
            for (k, &(x, y)) in (0u32..).zip(&got) {
                // The definition, spelled out: Halton bases 2 and 3 from k + 1, then Shirley
                // and Chiu's concentric map.
                let halton = |base: u32| {
                    let (mut n, mut f, mut x) = (k + 1, 1.0f64, 0.0f64);
                    while n > 0 {
                        f /= f64::from(base);
                        x += f * f64::from(n % base);
                        n /= base;
                    }
                    x as f32
                };
                let (want_x, want_y) = concentric_disk(halton(2), halton(3));
                assert_eq!(
                    (x.to_bits(), y.to_bits()),
                    (want_x.to_bits(), want_y.to_bits()),
                    "k {k}"
                );
                assert!(
                    x * x + y * y <= 1.0 + 1e-6,
                    "k {k}: ({x}, {y}) off the disk"
                );
            }
        }
    }

    #[test]
    fn offsets_start_at_the_centre_and_spread_over_the_pixel() {
        assert_eq!(offset(0), (0.5, 0.5));
        // R2 from its definition: ρ the real root of x³ = x + 1 (Newton from 1.5), sample k
        // at the fractional parts of ½ + k/ρ and ½ + k/ρ²; k = 1, 2, 3 by hand:
        // (0.2549, 0.0698), (0.0098, 0.6397), (0.7646, 0.2095).
        let mut rho = 1.5f64;
        for _ in 0..50 {
            rho -= (rho * rho * rho - rho - 1.0) / (3.0 * rho * rho - 1.0);
        }
        let by_hand = [(0.2549, 0.0698), (0.0098, 0.6397), (0.7646, 0.2095)];
        for k in 1..64u32 {
            let kf = f64::from(k);
            let want = ((0.5 + kf / rho).fract(), (0.5 + kf / (rho * rho)).fract());
            let got = offset(k);
            assert!(
                (f64::from(got.0) - want.0).abs() < 1e-6
                    && (f64::from(got.1) - want.1).abs() < 1e-6,
                "sample {k}: {got:?}, R2 gives {want:?}"
            );
            if let Some(&(x, y)) = by_hand.get(k as usize - 1) {
                assert!((f64::from(got.0) - x).abs() < 1e-4 && (f64::from(got.1) - y).abs() < 1e-4);
            }
        }
        // Every quarter of the pixel gets one of the first eight samples.
        for (qx, qy) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let hit = (0..8)
                .map(offset)
                .any(|(x, y)| (x >= 0.5) as i32 == qx && (y >= 0.5) as i32 == qy);
            assert!(hit, "quarter ({qx}, {qy})");
        }
        assert!(
            (1..64)
                .map(offset)
                .all(|(x, y)| (0.0..1.0).contains(&x) && (0.0..1.0).contains(&y))
        );
    }

    #[test]
    fn only_pixels_next_to_a_difference_are_refined() {
        // 4 × 3: a flat image with one bright pixel at (2, 1).
        let mut img = vec![px(0.2, 1.0); 12];
        img[6] = px(0.9, 1.0);
        let e = edges(&img, 4);
        assert_eq!(e, vec![2, 5, 6, 7, 10]);
        // A difference below the contrast threshold refines nothing.
        let mut img = vec![px(0.2, 1.0); 12];
        img[6] = px(0.201, 1.0);
        assert!(edges(&img, 4).is_empty());
    }

    #[test]
    fn a_refined_pixel_is_the_coverage_weighted_mean() {
        // Two pixels; the first differs. Its extra samples alternate hit (0.8) and miss.
        let mut img = vec![px(0.4, 1.0), px(0.0, 0.0)];
        let counts = refine(&mut img, 2, 4, |x, _, c| {
            c.primary += 1;
            if x.fract() < 0.5 {
                px(0.8, 1.0)
            } else {
                px(0.0, 0.0)
            }
        });
        assert_eq!(counts.primary, 2 * 3, "both pixels differ from each other");
        // R2's x offsets of samples 1, 2, 3 are 0.2549, 0.0098, 0.7646 (see the offsets
        // test): two hits and a miss. Pixel 0: centre 0.4 (α 1) and two hits of 0.8 among
        // four samples: α = 3/4, colour (0.4 + 2·0.8)/3 = 2/3. Pixel 1: a missed centre and
        // the same two hits: α = 2/4, colour 0.8.
        assert!((img[0].alpha - 0.75).abs() < 1e-6, "{}", img[0].alpha);
        assert!(
            (img[0].value.x - 2.0 / 3.0).abs() < 1e-6,
            "{}",
            img[0].value
        );
        assert!((img[1].alpha - 0.5).abs() < 1e-6, "{}", img[1].alpha);
        assert!((img[1].value.x - 0.8).abs() < 1e-6, "{}", img[1].value);
    }
}
