//! The output transfer function (`render --gamma`) and the display-gamma calibration helper
//! (`halfray gamma`).
//!
//! A display with gamma `γ` shows a stored value `a ∈ [0, 1]` at relative luminance `a^γ`.
//! A field of alternating black and white lines has mean luminance ½ on any display, so the
//! grey value `a` that looks the same from a distance satisfies `a^γ = ½`, that is
//! **`γ = ln 0.5 / ln a`** ([`gamma_from_match`]). `halfray gamma --chart OUT.png` writes such
//! lines around grey squares for a range of `γ`; `halfray gamma --match A` turns the matching
//! grey (0–255 or 0–1) into `γ`, which `render --gamma γ` then uses instead of sRGB.

use crate::error::{Error, Result};
use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

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

/// How linear radiance in `[0, 1]` is encoded into the stored value.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Transfer {
    /// The sRGB curve (IEC 61966-2-1): the default.
    #[default]
    Srgb,
    /// A pure power law: stored `= x^(1/γ)`.
    Power(f32),
}

/// Smallest and largest `γ` accepted (a display's gamma is around 1.8–2.6; outside this range
/// the value is a typo, not a display).
pub const GAMMA_RANGE: (f32, f32) = (0.2, 5.0);

impl Transfer {
    /// Linear `x` (clamped to `[0, 1]`, NaN as 0) to the stored value in `[0, 1]`.
    pub fn encode(self, x: f32) -> f32 {
        match self {
            Self::Srgb => linear_to_srgb(x),
            Self::Power(g) => {
                let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
                x.powf(1.0 / g)
            }
        }
    }

    /// Stored value `y` in `[0, 1]` back to linear.
    pub fn decode(self, y: f32) -> f32 {
        match self {
            Self::Srgb => srgb_to_linear(y),
            Self::Power(g) => y.clamp(0.0, 1.0).powf(g),
        }
    }
}

impl fmt::Display for Transfer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Srgb => write!(f, "srgb"),
            Self::Power(g) => write!(f, "{g}"),
        }
    }
}

impl FromStr for Transfer {
    type Err = String;

    /// `srgb`, or a number `γ` in [`GAMMA_RANGE`].
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        if s.eq_ignore_ascii_case("srgb") {
            return Ok(Self::Srgb);
        }
        let g: f32 = s
            .parse()
            .map_err(|_| format!("`{s}` is neither `srgb` nor a number"))?;
        let (lo, hi) = GAMMA_RANGE;
        if !(lo..=hi).contains(&g) {
            return Err(format!("gamma {g} is outside {lo}..={hi}"));
        }
        Ok(Self::Power(g))
    }
}

/// `γ = ln 0.5 / ln a` for the grey `a ∈ (0, 1)` that matches a 50 % line pattern; `None`
/// outside `(0, 1)`.
pub fn gamma_from_match(a: f64) -> Option<f64> {
    (a > 0.0 && a < 1.0).then(|| 0.5f64.ln() / a.ln())
}

/// The gammas of the chart's tiles, left to right.
pub const CHART_GAMMAS: [f32; 7] = [1.6, 1.8, 2.0, 2.2, 2.4, 2.6, 2.8];

/// Side of one chart tile, pixels; the grey square in its centre is half of it.
const TILE: u32 = 96;

/// The calibration chart: one tile per [`CHART_GAMMAS`] entry, alternating black and white
/// rows around a centred square of the grey `round(255 · 0.5^(1/γ))`. Returns the image and
/// the grey of each tile.
pub fn chart() -> (image::RgbaImage, Vec<u8>) {
    let greys: Vec<u8> = CHART_GAMMAS
        .iter()
        .map(|&g| (255.0 * 0.5f64.powf(1.0 / f64::from(g))).round() as u8)
        .collect();
    let img = image::RgbaImage::from_fn(TILE * greys.len() as u32, TILE, |x, y| {
        let (k, tx) = ((x / TILE) as usize, x % TILE);
        let inside =
            (TILE / 4..3 * TILE / 4).contains(&tx) && (TILE / 4..3 * TILE / 4).contains(&y);
        let v = if inside {
            greys[k]
        } else if y % 2 == 0 {
            255
        } else {
            0
        };
        image::Rgba([v, v, v, 255])
    });
    (img, greys)
}

/// Arguments of `halfray gamma`.
#[derive(clap::Args, Debug, Clone)]
#[command(group = clap::ArgGroup::new("what").required(true).multiple(true))]
pub struct GammaArgs {
    /// Write the calibration chart to this PNG (view it at 100 %, from a distance).
    #[arg(long, group = "what")]
    pub chart: Option<PathBuf>,
    /// The grey that matches the line pattern, as a level of 255 (1 and 1.0 mean grey level 1
    /// of 255, not white) or as a fraction below 1 (0.5): prints `γ = ln 0.5 / ln a`.
    #[arg(
        long = "match",
        value_name = "A",
        group = "what",
        allow_negative_numbers = true
    )]
    pub matched: Option<f64>,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
}

/// Runs `halfray gamma`.
pub fn run(args: &GammaArgs) -> Result<()> {
    // `--match` is checked before the chart is written: an error changes no output.
    let matched = args.matched.map(match_report).transpose()?;
    let mut text = String::new();
    if let Some(path) = &args.chart {
        crate::png::check_png_name(crate::outputs::Named::new("--chart", path))?;
        let out = crate::outputs::OutputFile::reserve(path, args.force)?;
        let (img, greys) = chart();
        crate::png::write_png(out, img.width(), img.height(), img.as_raw())?;
        text.push_str(&format!(
            "wrote {}: tiles left to right\n",
            crate::text::path(path)
        ));
        for (g, a) in CHART_GAMMAS.iter().zip(&greys) {
            text.push_str(&format!(
                "  grey {a:3}: your display's gamma is {g} if it matches\n"
            ));
        }
    }
    text.push_str(matched.as_deref().unwrap_or(""));
    crate::console::print_out(&text)
}

/// The report of `--match A` (a grey level `1 ≤ A < 255` of 255, or a fraction `0 < A < 1`):
/// the gamma `ln 0.5 / ln a` and the `--gamma` to render with (the nearest end of
/// [`GAMMA_RANGE`] when it lies outside); a usage error for a grey that is not strictly
/// between black and white.
fn match_report(a: f64) -> Result<String> {
    let frac = if a >= 1.0 { a / 255.0 } else { a };
    let g = gamma_from_match(frac).ok_or_else(|| {
        Error::Usage(format!(
            "--match {a}: the matching grey must lie strictly between black and white (0 < A < 255)"
        ))
    })?;
    let (lo, hi) = GAMMA_RANGE;
    Ok(if (f64::from(lo)..=f64::from(hi)).contains(&g) {
        format!("gamma = ln 0.5 / ln {frac:.4} = {g:.3}; render with --gamma {g:.2}\n")
    } else {
        // `render --gamma` accepts only GAMMA_RANGE: recommend its nearest end, and say so.
        format!(
            "gamma = ln 0.5 / ln {frac:.4} = {g:.3}, outside the accepted {lo}..={hi} \
             (no display has it: check the match); clamped: render with --gamma {}\n",
            if g < f64::from(lo) { lo } else { hi }
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips() {
        for k in 0..=255u8 {
            let x = f32::from(k) / 255.0;
            assert_eq!(crate::png::to_u8(linear_to_srgb(srgb_to_linear(x))), k);
        }
    }

    #[test]
    fn the_matching_grey_gives_the_gamma() {
        // A display of gamma 2.2 shows 0.5^(1/2.2) = 0.7297 at half luminance.
        let a = 0.5f64.powf(1.0 / 2.2);
        assert!((gamma_from_match(a).unwrap() - 2.2).abs() < 1e-12);
        assert!((gamma_from_match(0.5).unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(gamma_from_match(0.0), None);
        assert_eq!(gamma_from_match(1.0), None);
    }

    #[test]
    fn power_transfer_round_trips_and_parses() {
        let t: Transfer = "2.2".parse().unwrap();
        assert_eq!(t, Transfer::Power(2.2));
        for k in 0..=255u8 {
            let y = f32::from(k) / 255.0;
            assert!((t.encode(t.decode(y)) - y).abs() < 1e-5);
        }
        // Half radiance is stored as 0.5^(1/2.2) = 0.7297.
        assert!((t.encode(0.5) - 0.729_740_9).abs() < 1e-6);
        assert_eq!("sRGB".parse(), Ok(Transfer::Srgb));
        for bad in ["0", "-2", "nan", "9", "gamma"] {
            assert!(bad.parse::<Transfer>().is_err(), "{bad}");
        }
    }

    #[test]
    fn the_chart_lines_average_half_and_the_squares_hold_the_greys() {
        let (img, greys) = chart();
        assert_eq!(greys, vec![165, 174, 180, 186, 191, 195, 199]);
        for (k, &a) in greys.iter().enumerate() {
            let x0 = k as u32 * TILE;
            assert_eq!(img.get_pixel(x0 + TILE / 2, TILE / 2).0[0], a);
            let column: Vec<u8> = (0..TILE / 4)
                .map(|y| img.get_pixel(x0 + 2, y).0[0])
                .collect();
            let mean = column.iter().map(|&v| f64::from(v)).sum::<f64>() / column.len() as f64;
            assert_eq!(mean, 127.5, "lines of tile {k}");
        }
    }
}
