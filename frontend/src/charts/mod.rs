//! Charts of the benchmarks' JSON, drawn with `plotters` as SVG or PNG.
//!
//! | command | chart |
//! |---|---|
//! | `halfray chart accuracy RUN.json -o OUT` | cost against error of every intersector variant (`bench accuracy --json`; [`accuracy`]) |
//! | `halfray chart corpus RUN.json -o OUT` | halfray over Embree default and robust per mesh and ray set (`bench bvh --json`; [`corpus`]) |
//! | `halfray chart disagreements RUN.json -o OUT` | the cross-check's disagreement classes per mesh (`crosscheck --json`; [`disagreements`]) |
//!
//! The format follows `OUT`'s extension (`.svg` or `.png`); `-o -` writes SVG to stdout. Text is laid out with the Go font
//! embedded in the binary ([`FONT`], registered with `plotters`' `ab_glyph` backend), so no
//! system font is looked up; SVG text names the `sans-serif` family and is drawn by the viewer.
//! PNGs are encoded with the `image` crate the renderer uses.

pub mod accuracy;
pub mod corpus;
pub mod disagreements;

use crate::error::{Error, Location, Result, json_message};
use crate::outputs::{Named, OutputFile, reserve_outputs};
use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::coord::ranged1d::{Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::{Path, PathBuf};

/// The Go Regular font (BSD-3-Clause, `frontend/assets/fonts/LICENSE-Go-fonts.txt`), used for
/// every chart's text.
pub const FONT: &[u8] = include_bytes!("../../assets/fonts/Go-Regular.ttf");
/// The family name the charts' text uses; [`FONT`] is registered under it.
pub const FAMILY: &str = "sans-serif";

/// The colours of series, in order: a colour-blind-safe palette (Okabe and Ito 2008, grey in
/// place of its yellow, which is unreadable on white), then brown and violet, so that the ten
/// ray sets of `bench bvh` each have a colour of their own.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(120, 120, 120),
    RGBColor(0, 0, 0),
    RGBColor(140, 86, 75),
    RGBColor(117, 84, 200),
];

/// Height of one row of a chart's legend, pixels: 13-point text and its 10-pixel marker.
const LEGEND_ROW: u32 = 20;
/// Space above and below a legend's rows, pixels.
const LEGEND_MARGIN: u32 = 12;
/// How far a legend's markers stand from the chart's left edge, pixels (under the y labels).
const LEGEND_INDENT: i32 = 80;

/// Width of a chart of `categories` along x, `per_category` pixels each plus 160 for the
/// y axis, at least 900, pixels (saturating: a run cannot hold `u32::MAX` categories, and a
/// PNG that large is refused by [`render`]).
fn category_chart_width(categories: usize, per_category: u32) -> u32 {
    u32::try_from(categories)
        .unwrap_or(u32::MAX)
        .saturating_mul(per_category)
        .saturating_add(160)
        .max(900)
}

/// Height of a legend of `rows` entries drawn below a chart ([`draw_legend_below`]), pixels.
fn legend_height(rows: usize) -> u32 {
    u32::try_from(rows)
        .unwrap_or(u32::MAX)
        .saturating_mul(LEGEND_ROW)
        .saturating_add(2 * LEGEND_MARGIN)
}

/// A legend entry's marker: the shape its series is drawn with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Marker {
    /// A filled circle (points).
    Dot,
    /// A filled square (bars).
    Square,
}

/// Splits `root` into the plot and, below it, a legend of `entries` (label and colour), one a
/// row in 13-point [`FAMILY`] text beside a `marker` of the colour, and draws the legend; the
/// plot is returned to draw on. Below the plot, the legend hides no data, however many series
/// there are (the chart's height includes [`legend_height`]).
fn draw_legend_below<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    entries: &[(String, RGBColor)],
    marker: Marker,
) -> std::result::Result<DrawingArea<DB, Shift>, DrawingAreaErrorKind<DB::ErrorType>> {
    let (_, h) = root.dim_in_pixel();
    let (plot, legend) = root.split_vertically(h.saturating_sub(legend_height(entries.len())));
    let font = TextStyle::from((FAMILY, 13).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    // Small constants: the casts are exact.
    let (mut y, row) = ((LEGEND_MARGIN + LEGEND_ROW / 2) as i32, LEGEND_ROW as i32);
    for (label, colour) in entries {
        let x = LEGEND_INDENT;
        match marker {
            Marker::Dot => legend.draw(&Circle::new((x, y), 5, colour.filled()))?,
            Marker::Square => legend.draw(&Rectangle::new(
                [(x - 5, y - 5), (x + 5, y + 5)],
                colour.filled(),
            ))?,
        }
        legend.draw(&Text::new(label.clone(), (x + 14, y), font.clone()))?;
        y = y.saturating_add(row);
    }
    Ok(plot)
}

/// Which chart (`halfray chart KIND`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ChartKind {
    /// `bench accuracy --json`: cost against error per intersector variant.
    Accuracy,
    /// `bench bvh --json`: ratios to Embree default and robust per mesh and ray set.
    Corpus,
    /// `crosscheck --json`: disagreement classes per mesh.
    Disagreements,
}

/// Arguments of `halfray chart`.
#[derive(clap::Args, Debug, Clone)]
pub struct ChartArgs {
    /// Which chart.
    #[arg(value_enum)]
    pub kind: ChartKind,
    /// The JSON a run wrote (`--json`).
    pub input: PathBuf,
    /// Output image, `.svg` or `.png` (written atomically; never the input); `-`: SVG to stdout.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
}

/// An image format of the charts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Scalable vector graphics (text as `<text>`).
    Svg,
    /// 8-bit RGB PNG.
    Png,
}

impl Format {
    /// The format of `path`'s extension (case-insensitive); SVG for `-` (stdout).
    ///
    /// # Errors
    ///
    /// [`Error::Usage`] for any other extension.
    pub fn of(path: &Path) -> Result<Self> {
        if path == Path::new("-") {
            return Ok(Format::Svg);
        }
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            _ => Err(Error::Usage(format!(
                "`{}`: a chart is written as .svg or .png",
                crate::text::path(path)
            ))),
        }
    }
}

/// A chart that can be drawn on any `plotters` backend.
pub trait Chart {
    /// Width and height, pixels.
    fn size(&self) -> (u32, u32);
    /// Draws the whole chart on `root` (already filled white).
    ///
    /// # Errors
    ///
    /// The backend's.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>;
}

/// Registers [`FONT`] as [`FAMILY`] (once per process).
fn register_font() -> Result<()> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(Error::internal(
            "the embedded chart font does not parse",
            None,
        ))
    }
}

/// Draws the axes of a chart with one category per `names` entry along x (at the integers
/// 0..n, labelled by [`category_label`], no vertical grid lines) and `y_desc` along y, in the
/// same fonts on every chart.
fn draw_category_axes<'a, DB, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    names: &[String],
    y_desc: &str,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    DB: DrawingBackend + 'a,
    Y: Ranged + ValueFormatter<<Y as Ranged>::ValueType>,
{
    let names = names.to_vec();
    chart
        .configure_mesh()
        .x_labels(names.len())
        .x_label_formatter(&move |v| category_label(&names, *v))
        .disable_x_mesh()
        .y_desc(y_desc)
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 15))
        .draw()
}

/// `svg` with every character XML 1.0 does not allow (its production `Char`: controls other
/// than tab, line feed and carriage return, and the noncharacters U+FFFE and U+FFFF; a Rust
/// `char` is never a surrogate) replaced by U+FFFD: a mesh name read from a run's JSON may hold
/// any character, and one such character makes the whole file unreadable.
fn xml_chars(svg: &str) -> String {
    svg.chars()
        .map(|c| {
            if (c < ' ' && !matches!(c, '\t' | '\n' | '\r')) || matches!(c, '\u{fffe}' | '\u{ffff}')
            {
                char::REPLACEMENT_CHARACTER
            } else {
                c
            }
        })
        .collect()
}

/// `chart` as the bytes of a `format` file.
///
/// # Errors
///
/// Drawing or encoding.
pub fn render(chart: &impl Chart, format: Format) -> Result<Vec<u8>> {
    register_font()?;
    let (w, h) = chart.size();
    let drawing = |e: &dyn std::fmt::Display| Error::encode("the chart", e.to_string());
    match format {
        Format::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(|e| drawing(&e))?;
                chart.draw(&root).map_err(|e| drawing(&e))?;
                root.present().map_err(|e| drawing(&e))?;
            }
            Ok(xml_chars(&svg).into_bytes())
        }
        Format::Png => {
            let bytes = u64::from(w)
                .checked_mul(u64::from(h))
                .and_then(|p| p.checked_mul(3));
            crate::limits::check_memory(&format!("a PNG chart of {w} × {h} pixels"), bytes)?;
            let mut rgb = vec![255u8; w as usize * h as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
                chart.draw(&root).map_err(|e| drawing(&e))?;
                root.present().map_err(|e| drawing(&e))?;
            }
            let mut png = Vec::new();
            image::codecs::png::PngEncoder::new(&mut png)
                .write_image(&rgb, w, h, image::ExtendedColorType::Rgb8)
                .map_err(|e| Error::encode("the chart", e))?;
            Ok(png)
        }
    }
}

/// Draws `chart` into a reserved output, in the format of its path.
///
/// # Errors
///
/// [`Format::of`], drawing, encoding or writing.
pub fn write(chart: &impl Chart, out: OutputFile) -> Result<()> {
    let bytes = render(chart, Format::of(out.path())?)?;
    out.write(|w| w.write_all(&bytes))
}

/// Reads and parses a run's JSON file as `T`.
///
/// # Errors
///
/// [`Error::Io`] reading it ([`crate::input::read_bytes`]: not a folder or a device, at most
/// [`crate::limits::MAX_INPUT_BYTES`]; a leading byte-order mark skipped, [`crate::input::read_text`]);
/// an input error naming the file, line and column where it is not UTF-8, or not JSON of that
/// shape.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path, what: &str) -> Result<T> {
    let text = crate::input::read_text(path, &format!("the JSON of {what}"))?;
    parse_json(path, &text, what)
}

/// Parses `text`, read from `path`, as `T`: [`read_json`]'s parse, for a caller that looks
/// at the text first.
///
/// # Errors
///
/// An input error naming the file, line and column where it is not JSON of that shape.
fn parse_json<T: serde::de::DeserializeOwned>(path: &Path, text: &str, what: &str) -> Result<T> {
    serde_json::from_str(text).map_err(|e| {
        Error::input(
            Location::file(path).json_position(&e),
            format!("not the JSON of {what}: {}", json_message(&e)),
        )
    })
}

/// Runs `halfray chart`: reserves the output (refused first if it is the input) and checks
/// its format before reading the input.
pub fn run(args: &ChartArgs) -> Result<()> {
    let out = reserve_outputs(
        &[Named::new("-o", &args.output)],
        &[Named::new("input", &args.input)],
        args.force,
    )?
    .remove(0);
    Format::of(&args.output)?;
    match args.kind {
        ChartKind::Accuracy => write(&accuracy::AccuracyChart::from_file(&args.input)?, out),
        ChartKind::Corpus => write(&corpus::CorpusChart::from_file(&args.input)?, out),
        ChartKind::Disagreements => write(
            &disagreements::DisagreementChart::from_file(&args.input)?,
            out,
        ),
    }
}

/// How close a category axis's key point must be to an integer to take that category's label,
/// in axis units (one category apart): the key points are the integers as the plotting
/// library computes them from the range, a few `f64` roundings off, far below `10⁻⁶`.
const LABEL_SNAP: f64 = 1e-6;

/// `names[i]` for a coordinate within [`LABEL_SNAP`] of the integer `i`, else nothing:
/// category labels on a continuous axis whose key points are the integers.
fn category_label(names: &[String], v: f64) -> String {
    let i = v.round();
    if (v - i).abs() < LABEL_SNAP && i >= 0.0 {
        names.get(i as usize).cloned().unwrap_or_default()
    } else {
        String::new()
    }
}

/// Magnitudes a chart prints with one decimal (`349.3`); zero too. Outside, one decimal
/// printed `10⁻⁶` ns as `0.0` and `3·10¹²` as fourteen characters: three significant digits
/// in scientific notation instead (`1.20e-6`). Unitless (the bounds of `|v|`).
const PLAIN_NUMBERS: std::ops::Range<f64> = 0.1..1.0e7;

/// A number as a chart's tick or legend prints it: one decimal where `|v|` lies in
/// [`PLAIN_NUMBERS`] (or `v` is zero), else scientific notation with three significant digits.
fn chart_number(v: f64) -> String {
    if v == 0.0 || PLAIN_NUMBERS.contains(&v.abs()) {
        format!("{v:.1}")
    } else {
        format!("{v:.2e}")
    }
}

/// The integration tests' SVG reader, shared with the unit tests below.
#[cfg(test)]
#[path = "../../tests/common/svg.rs"]
mod svg;

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The text of every `<text>` element of an SVG, after checking it parses as XML with an
    /// `<svg>` root of the stated size.
    pub(crate) fn svg_texts(bytes: &[u8], size: (u32, u32)) -> Vec<String> {
        super::svg::svg_texts(bytes, Some(size))
    }

    /// Decodes a PNG, checks its size, and counts its pixels of `colour`.
    pub(crate) fn png_pixels_of(bytes: &[u8], size: (u32, u32), colour: RGBColor) -> usize {
        let img = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
            .expect("a PNG")
            .to_rgb8();
        assert_eq!(img.dimensions(), size);
        img.pixels()
            .filter(|p| p.0 == [colour.0, colour.1, colour.2])
            .count()
    }

    #[test]
    fn format_follows_the_extension() {
        assert_eq!(Format::of(Path::new("a/b.SVG")).unwrap(), Format::Svg);
        assert_eq!(Format::of(Path::new("b.png")).unwrap(), Format::Png);
        assert!(matches!(
            Format::of(Path::new("b.jpg")),
            Err(Error::Usage(_))
        ));
        assert!(matches!(Format::of(Path::new("b")), Err(Error::Usage(_))));
        assert_eq!(Format::of(Path::new("-")).unwrap(), Format::Svg);
    }

    /// A PNG's pixels are counted before they are allocated: a chart of more pixels than the
    /// memory limit allows is a usage error naming its size (a run of 500 000 meshes asked
    /// for 86 GB and aborted the process).
    #[test]
    fn a_png_beyond_the_memory_limit_is_refused_before_allocating() {
        struct Wide;
        impl Chart for Wide {
            fn size(&self) -> (u32, u32) {
                (4_000_000, 640)
            }
            fn draw<DB: DrawingBackend>(
                &self,
                _: &DrawingArea<DB, Shift>,
            ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
                unreachable!("refused before drawing")
            }
        }
        let e = render(&Wide, Format::Png).unwrap_err().to_string();
        assert!(
            e.contains("a PNG chart of 4000000 × 640 pixels needs about 7.2 GiB"),
            "{e}"
        );
    }

    #[test]
    fn category_labels_only_at_integers() {
        let names = vec!["a".to_string(), "b".to_string()];
        assert_eq!(category_label(&names, 1.0), "b");
        assert_eq!(category_label(&names, 0.5), "");
        assert_eq!(category_label(&names, 2.0), "");
        assert_eq!(category_label(&names, -1.0), "");
    }

    /// A report as an editor saves it (a byte-order mark first) is read; bytes that are not
    /// UTF-8 are an error at their line and column, not serde's "key must be a string"; a
    /// syntax error names its place once.
    #[test]
    fn a_bom_is_skipped_and_bad_bytes_or_syntax_are_located_once() {
        #[derive(serde::Deserialize, Debug)]
        struct V {
            a: u32,
        }
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("r.json");
        std::fs::write(&json, b"\xEF\xBB\xBF{\"a\": 7}").unwrap();
        assert_eq!(read_json::<V>(&json, "x").unwrap().a, 7);
        std::fs::write(&json, b"{\n\"a\xff\": 7}").unwrap();
        let e = read_json::<V>(&json, "x").unwrap_err().to_string();
        assert!(
            e.contains("r.json:2:3") && e.contains("0xff is not UTF-8"),
            "{e}"
        );
        std::fs::write(&json, b"{\n\"a\": 7,,}").unwrap();
        let e = read_json::<V>(&json, "x").unwrap_err().to_string();
        assert!(e.contains("r.json:2:") && !e.contains("at line"), "{e}");
    }
}
