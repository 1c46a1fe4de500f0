//! Porter–Duff compositing: the twelve operators of Porter and Duff, "Compositing Digital
//! Images" (SIGGRAPH 1984), with Cairo's (lower case, hyphens) and ImageMagick's names, and
//! `halfray composite A.png B.png --op OP -o OUT.png` (A the source, B the destination).
//!
//! Every operator is `result = A·Fa + B·Fb` on **premultiplied** colour and alpha alike, with
//! the factors of [`Operator::factors`]. Pixels come and go **straight** (non-premultiplied,
//! as PNG stores them): [`Operator::apply`] premultiplies, combines, and divides by the result's
//! alpha (a fully transparent result is `0, 0, 0, 0`). The arithmetic is on whatever values it
//! is given: the stored 8-bit values for `halfray composite` (as Cairo and ImageMagick do by
//! default), linear radiance for `halfray render --background IMG --op OP`.

use crate::error::{Error, Location, Result};
use crate::limits::MEMORY_LIMIT_BYTES;
use crate::outputs::{Named, reserve_outputs};
use crate::png::{decode_peak, read_rgba8, rgba8_bytes};
use crate::text;
use glam::Vec4;
use std::path::PathBuf;

/// A Porter–Duff operator (`--op`): its name here, or Cairo's operator names in lower case
/// with hyphens (`CAIRO_OPERATOR_DEST_OVER` is `dest-over`; `source`, …) or ImageMagick's
/// (`SrcOver`, `DstIn`, …; `--op` ignores case).
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Operator {
    /// Neither: transparent.
    Clear,
    /// A only.
    #[value(aliases = ["copy", "source"])]
    Src,
    /// B only.
    #[value(alias = "dest")]
    Dst,
    /// A over B.
    #[default]
    #[value(aliases = ["src-over", "srcover"])]
    Over,
    /// B over A.
    #[value(aliases = ["dest-over", "dstover"])]
    DstOver,
    /// A where B is.
    #[value(aliases = ["src-in", "srcin"])]
    In,
    /// B where A is.
    #[value(aliases = ["dest-in", "dstin"])]
    DstIn,
    /// A where B is not.
    #[value(aliases = ["src-out", "srcout"])]
    Out,
    /// B where A is not.
    #[value(aliases = ["dest-out", "dstout"])]
    DstOut,
    /// A over B, inside B only.
    #[value(aliases = ["src-atop", "srcatop"])]
    Atop,
    /// B over A, inside A only.
    #[value(aliases = ["dest-atop", "dstatop"])]
    DstAtop,
    /// A where B is not, and B where A is not.
    Xor,
}

impl Operator {
    /// Every operator, in the order of the module docs.
    pub const ALL: [Self; 12] = [
        Self::Clear,
        Self::Src,
        Self::Dst,
        Self::Over,
        Self::DstOver,
        Self::In,
        Self::DstIn,
        Self::Out,
        Self::DstOut,
        Self::Atop,
        Self::DstAtop,
        Self::Xor,
    ];

    /// The factors `(Fa, Fb)` of source and destination for alphas `a` (source) and `b`
    /// (destination), both in `[0, 1]`.
    pub fn factors(self, a: f32, b: f32) -> (f32, f32) {
        match self {
            Self::Clear => (0.0, 0.0),
            Self::Src => (1.0, 0.0),
            Self::Dst => (0.0, 1.0),
            Self::Over => (1.0, 1.0 - a),
            Self::DstOver => (1.0 - b, 1.0),
            Self::In => (b, 0.0),
            Self::DstIn => (0.0, a),
            Self::Out => (1.0 - b, 0.0),
            Self::DstOut => (0.0, 1.0 - a),
            Self::Atop => (b, 1.0 - a),
            Self::DstAtop => (1.0 - b, a),
            Self::Xor => (1.0 - b, 1.0 - a),
        }
    }

    /// `src OP dst` on straight RGBA (alpha in `w`, clamped to `[0, 1]`); a result with zero
    /// alpha is `Vec4::ZERO`.
    pub fn apply(self, src: Vec4, dst: Vec4) -> Vec4 {
        let (a, b) = (src.w.clamp(0.0, 1.0), dst.w.clamp(0.0, 1.0));
        let (fa, fb) = self.factors(a, b);
        let alpha = a * fa + b * fb;
        if alpha <= 0.0 {
            return Vec4::ZERO;
        }
        let rgb = (src.truncate() * (a * fa) + dst.truncate() * (b * fb)) / alpha;
        rgb.extend(alpha.min(1.0))
    }

    /// [`Operator::apply`] for a result written in 8 bits: a result whose alpha rounds to 0
    /// there (below half a step, [`crate::png::to_u8`]) is `Vec4::ZERO`, so it is written
    /// `0, 0, 0, 0` as every fully transparent result.
    pub fn apply_8bit(self, src: Vec4, dst: Vec4) -> Vec4 {
        let out = self.apply(src, dst);
        if crate::png::to_u8(out.w) == 0 {
            Vec4::ZERO
        } else {
            out
        }
    }
}

/// Arguments of `halfray composite`.
#[derive(clap::Args, Debug, Clone)]
pub struct CompositeArgs {
    /// The source image A (PNG; 8-bit RGBA after decoding).
    pub source: PathBuf,
    /// The destination image B, the same size.
    pub destination: PathBuf,
    /// The operator.
    #[arg(long, value_enum, default_value_t, ignore_case = true)]
    pub op: Operator,
    /// Output PNG (written atomically; never an input).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
}

/// `a OP b` pixel by pixel on 8-bit straight RGBA (values scaled to `[0, 1]`, results rounded
/// to the nearest 8-bit value; a result whose alpha rounds to 0 is `0, 0, 0, 0`). Evaluated in `f32`, as the renderer's compositing: a result
/// within about `10⁻⁴` of an 8-bit step's midpoint (`130.49998`) may round to either side.
/// The images must have the same size (checked by the caller).
pub fn composite_rgba8(op: Operator, a: &[u8], b: &[u8]) -> Vec<u8> {
    let px = |p: &[u8]| Vec4::from_array([p[0], p[1], p[2], p[3]].map(|c| f32::from(c) / 255.0));
    a.chunks_exact(4)
        .zip(b.chunks_exact(4))
        .flat_map(|(pa, pb)| {
            op.apply_8bit(px(pa), px(pb))
                .to_array()
                .map(crate::png::to_u8)
        })
        .collect()
}

/// Runs `halfray composite`.
pub fn run(args: &CompositeArgs) -> Result<()> {
    let out = {
        let mut r = reserve_outputs(
            &[Named::new("-o", &args.output)],
            &[
                Named::new("source", &args.source),
                Named::new("destination", &args.destination),
            ],
            args.force,
        )?;
        r.remove(0)
    };
    // After the input check: an output that is an input is "the input".
    crate::png::check_png_name(Named::new("-o", &args.output))?;
    // Both headers before any decode: the sizes must agree, and the memory held at the
    // command's peak must fit the limit: the source decoded (its buffer and 8-bit copy), then
    // the destination decoded beside the source's copy, then both copies and the result.
    let ((w, h), peak_a) = decode_peak(&args.source)?;
    let ((bw, bh), peak_b) = decode_peak(&args.destination)?;
    if (w, h) != (bw, bh) {
        return Err(Error::input(
            Location::file(&args.destination),
            format!(
                "is {bw}×{bh} but the source `{}` is {w}×{h}",
                text::path(&args.source)
            ),
        ));
    }
    let rgba = rgba8_bytes(w, h);
    let bytes = (|| {
        let (rgba, a, b) = (rgba?, peak_a?, peak_b?);
        Some(a.max(rgba.checked_add(b)?).max(rgba.checked_mul(3)?))
    })();
    if bytes.is_none_or(|b| b > MEMORY_LIMIT_BYTES) {
        return Err(Error::input(
            Location::file(&args.source),
            format!(
                "compositing it with `{}`, both {w}×{h}, needs {} at once (the images decoded, their 8-bit copies and the result), more than the {} GiB limit",
                text::path(&args.destination),
                bytes.map_or("more memory".to_string(), |b| format!(
                    "about {:.1} GiB",
                    b as f64 / f64::from(1u32 << 30)
                )),
                MEMORY_LIMIT_BYTES >> 30
            ),
        ));
    }
    let a = read_rgba8(&args.source)?;
    let b = read_rgba8(&args.destination)?;
    if a.dimensions() != b.dimensions() {
        // The files changed between the header and the decode.
        return Err(Error::input(
            Location::file(&args.destination),
            format!("changed size while it was read ({w}×{h} in its header)"),
        ));
    }
    let pixels = composite_rgba8(args.op, a.as_raw(), b.as_raw());
    crate::png::write_png(out, a.width(), a.height(), &pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Source: red at alpha 0.6; destination: blue at alpha 0.5 (straight). The expected
    /// results, worked by hand from Porter and Duff's table in straight form
    /// (`αo = αa·Fa + αb·Fb`, `Co = (Ca·αa·Fa + Cb·αb·Fb) / αo`):
    #[test]
    fn every_operator_on_worked_values() {
        let a = Vec4::new(1.0, 0.0, 0.0, 0.6);
        let b = Vec4::new(0.0, 0.0, 1.0, 0.5);
        let cases = [
            (Operator::Clear, Vec4::ZERO),
            (Operator::Src, Vec4::new(1.0, 0.0, 0.0, 0.6)),
            (Operator::Dst, Vec4::new(0.0, 0.0, 1.0, 0.5)),
            // αo = 0.6 + 0.5·0.4 = 0.8; red 0.6/0.8, blue 0.2/0.8.
            (Operator::Over, Vec4::new(0.75, 0.0, 0.25, 0.8)),
            // αo = 0.5 + 0.6·0.5 = 0.8; red 0.3/0.8, blue 0.5/0.8.
            (Operator::DstOver, Vec4::new(0.375, 0.0, 0.625, 0.8)),
            (Operator::In, Vec4::new(1.0, 0.0, 0.0, 0.3)),
            (Operator::DstIn, Vec4::new(0.0, 0.0, 1.0, 0.3)),
            (Operator::Out, Vec4::new(1.0, 0.0, 0.0, 0.3)),
            (Operator::DstOut, Vec4::new(0.0, 0.0, 1.0, 0.2)),
            // αo = 0.6·0.5 + 0.5·0.4 = 0.5; red 0.3/0.5, blue 0.2/0.5.
            (Operator::Atop, Vec4::new(0.6, 0.0, 0.4, 0.5)),
            // αo = 0.6·0.5 + 0.5·0.6 = 0.6; red 0.3/0.6, blue 0.3/0.6.
            (Operator::DstAtop, Vec4::new(0.5, 0.0, 0.5, 0.6)),
            // αo = 0.6·0.5 + 0.5·0.4 = 0.5; red 0.3/0.5, blue 0.2/0.5.
            (Operator::Xor, Vec4::new(0.6, 0.0, 0.4, 0.5)),
        ];
        assert_eq!(cases.len(), Operator::ALL.len());
        for (op, want) in cases {
            let got = op.apply(a, b);
            assert!(
                (got - want).abs().max_element() < 1e-6,
                "{op:?}: {got} (expected {want})"
            );
        }
    }

    #[test]
    fn opaque_and_transparent_limits() {
        let a = Vec4::new(0.2, 0.4, 0.6, 1.0);
        let b = Vec4::new(0.9, 0.8, 0.7, 1.0);
        let clear = Vec4::new(0.3, 0.3, 0.3, 0.0);
        // Porter and Duff's table with αa = 1, αb = 0: the operators whose source factor is 1
        // there (1, 1 − αb) keep opaque A over a transparent destination; those whose factor
        // is 0 or αb give nothing. With αa = 0, αb = 1, likewise for B: factor 1 or 1 − αa
        // keeps it, 0 or αa does not.
        use Operator::*;
        let keeps_a = [Src, Over, DstOver, Out, DstAtop, Xor];
        let keeps_b = [Dst, Over, DstOver, DstOut, Atop, Xor];
        for op in Operator::ALL {
            let want = if keeps_a.contains(&op) { a } else { Vec4::ZERO };
            assert_eq!(
                op.apply(a, clear),
                want,
                "{op:?}: opaque A onto transparent"
            );
            let want = if keeps_b.contains(&op) { b } else { Vec4::ZERO };
            assert_eq!(
                op.apply(clear, b),
                want,
                "{op:?}: transparent onto opaque B"
            );
        }
        assert_eq!(Operator::Over.apply(a, b), a);
        assert_eq!(Operator::DstOver.apply(a, b), b);
        assert_eq!(Operator::Xor.apply(a, b), Vec4::ZERO);
        assert_eq!(Operator::Atop.apply(a, b), a);
    }

    #[test]
    fn eight_bit_pixels_round_to_the_nearest_value() {
        // 153 = 0.6·255, 128 ≈ 0.502: over gives α = 0.6 + 0.502·0.4 = 0.8008 → 204.
        let a = [255, 0, 0, 153];
        let b = [0, 0, 255, 128];
        let out = composite_rgba8(Operator::Over, &a, &b);
        let (aa, ab) = (153.0 / 255.0, 128.0 / 255.0);
        let alpha: f64 = aa + ab * (1.0 - aa);
        let red = aa / alpha;
        let blue = ab * (1.0 - aa) / alpha;
        let q = |x: f64| (x * 255.0).round() as u8;
        assert_eq!(out, vec![q(red), 0, q(blue), q(alpha)]);
        assert_eq!(out, vec![191, 0, 64, 204]);
    }

    /// `in` of two pixels at alpha 1/255: the result's alpha is (1/255)² = 1/65 025, 0.004 of
    /// a step, so it is written 0, and the pixel is transparent black, not A's colour.
    #[test]
    fn a_result_whose_alpha_rounds_to_zero_is_transparent_black() {
        let out = composite_rgba8(Operator::In, &[200, 100, 50, 1], &[10, 20, 30, 1]);
        assert_eq!(out, vec![0, 0, 0, 0]);
    }
}
