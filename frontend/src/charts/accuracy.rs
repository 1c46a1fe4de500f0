//! The accuracy-against-time chart of `bench accuracy`: per intersector variant (and Embree's
//! two modes), the cost of an incoherent ray through the BVH against the share of rays answered
//! wrongly.

use super::{
    Chart, FAMILY, Marker, PALETTE, chart_number, draw_legend_below, legend_height, read_json,
};
use crate::error::{Error, Location, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// The bottom of the log error axis, errors per million: a rate below it is drawn on the
/// bottom line, none as a dot, a non-zero one (one leak in 20 million rays: 0.05) as a ring,
/// its legend entry giving the rate and saying "below 0.1".
pub const ERROR_FLOOR: f64 = 0.1;

/// One variant's point.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Variant name, drawn beside the point.
    pub label: String,
    /// ns per incoherent ray through the BVH (x).
    pub ns_per_ray: f64,
    /// Leaks plus false hits per million rays (y).
    pub errors_per_million: f64,
}

impl Point {
    /// Whether the point has errors, fewer than [`ERROR_FLOOR`] per million: drawn on the
    /// bottom line as a ring, told apart from none.
    #[must_use]
    pub fn below_floor(&self) -> bool {
        self.errors_per_million > 0.0 && self.errors_per_million < ERROR_FLOOR
    }
}

/// The fields of a `bench accuracy --json` variant row the chart reads.
#[derive(serde::Deserialize)]
struct VariantView {
    name: String,
    mrays_bvh_incoherent: Option<f64>,
    leaks_per_million: Option<f64>,
    false_hits_per_million: Option<f64>,
}

#[derive(serde::Deserialize)]
struct ReportView {
    variants: Vec<VariantView>,
    /// The mesh of the throughput (absent from reports written before it was recorded).
    #[serde(default)]
    bvh_mesh: Option<String>,
}

/// The chart: one point per variant with a BVH throughput.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyChart {
    /// The points, in the report's order.
    pub points: Vec<Point>,
    /// The mesh the throughput was measured on (the report's `bvh_mesh`), named on the cost
    /// axis; `None` for a report that does not say.
    pub mesh: Option<String>,
}

impl AccuracyChart {
    /// The points of `bench accuracy --json`'s variants: cost `1000 / mrays_bvh_incoherent` ns,
    /// error `leaks_per_million + false_hits_per_million` (variants without a BVH throughput
    /// are left out).
    ///
    /// # Errors
    ///
    /// Reading or parsing the file; an input error naming the field when a value the chart
    /// reads is outside what a run writes (`Refused`), or when no variant has a BVH
    /// throughput.
    pub fn from_file(path: &Path) -> Result<Self> {
        let report: ReportView = read_json(path, "`bench accuracy --json`")?;
        Self::from_view(report).map_err(|r| match r {
            Refused::Nothing => Error::input(Location::file(path), NOTHING_TO_CHART),
            Refused::Field { field, message } => {
                Error::input(Location::file(path).field(field), message)
            }
        })
    }

    /// The chart of a report in memory (`bench accuracy --chart`), read as its JSON is.
    ///
    /// # Errors
    ///
    /// An internal error when `report` does not have the JSON's shape or a value outside what
    /// a run writes; an input error when no variant has a BVH throughput.
    pub fn from_report(report: &impl serde::Serialize) -> Result<Self> {
        let view = serde_json::to_value(report)
            .and_then(serde_json::from_value::<ReportView>)
            .map_err(|e| Error::internal("the accuracy report's JSON", Some(Box::new(e))))?;
        Self::from_view(view).map_err(|r| match r {
            Refused::Nothing => Error::Usage(NOTHING_TO_CHART.into()),
            Refused::Field { field, message } => {
                Error::internal(format!("the accuracy report's `{field}`: {message}"), None)
            }
        })
    }

    fn from_view(report: ReportView) -> std::result::Result<Self, Refused> {
        let mut points = Vec::new();
        for (i, v) in report.variants.into_iter().enumerate() {
            let field = |name: &str| format!("variants[{i}].{name}");
            // 0: nothing was timed (`timing::mrays_per_second`), as good as absent.
            let Some(mrays) = v.mrays_bvh_incoherent.filter(|&m| m != 0.0) else {
                continue;
            };
            if !(MRAYS_RANGE.contains(&mrays)) {
                return Err(Refused::Field {
                    field: field("mrays_bvh_incoherent"),
                    message: format!(
                        "{mrays} Mrays/s is not a throughput a run measures ({:e} to {:e})",
                        MRAYS_RANGE.start(),
                        MRAYS_RANGE.end()
                    ),
                });
            }
            let mut errors = 0.0;
            for (name, value) in [
                ("leaks_per_million", v.leaks_per_million),
                ("false_hits_per_million", v.false_hits_per_million),
            ] {
                let value = value.unwrap_or(0.0);
                if !(0.0..=1.0e6).contains(&value) {
                    return Err(Refused::Field {
                        field: field(name),
                        message: format!("{value} per million is not a share of rays (0 to 10⁶)"),
                    });
                }
                errors += value;
            }
            points.push(Point {
                label: v.name,
                ns_per_ray: 1.0e3 / mrays,
                errors_per_million: errors,
            });
        }
        if points.is_empty() {
            return Err(Refused::Nothing);
        }
        Ok(Self {
            points,
            mesh: report.bvh_mesh,
        })
    }
}

/// The throughputs the chart draws, Mrays/s: from one ray an hour (`3·10⁻¹⁰`, far below any
/// run) to `10⁹` (a nanosecond a ray times a thousand). Values outside, which no run writes
/// (`1e-310`, a subnormal, made an axis of `10³¹³` ns whose tick search never ended), are an
/// input error.
pub const MRAYS_RANGE: std::ops::RangeInclusive<f64> = 3.0e-10..=1.0e9;

/// Why a report's variants cannot be charted.
enum Refused {
    /// No variant has a BVH throughput.
    Nothing,
    /// A value outside what a run writes: the field's path and why.
    Field { field: String, message: String },
}

/// Why a run without BVH throughput cannot be charted.
const NOTHING_TO_CHART: &str = "no variant has `mrays_bvh_incoherent`: nothing to chart";

impl Chart for AccuracyChart {
    fn size(&self) -> (u32, u32) {
        (960, 600 + legend_height(self.points.len()))
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let legend: Vec<(String, RGBColor)> = self
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let label = format!(
                    "{}: {} ns, {} per million{}",
                    p.label,
                    chart_number(p.ns_per_ray),
                    chart_number(p.errors_per_million),
                    if p.below_floor() {
                        format!(" (below {ERROR_FLOOR}: a ring on the bottom line)")
                    } else {
                        String::new()
                    }
                );
                (label, PALETTE[i % PALETTE.len()])
            })
            .collect();
        let root = &draw_legend_below(root, &legend, Marker::Dot)?;
        let x_max = self.points.iter().map(|p| p.ns_per_ray).fold(0.0, f64::max) * 1.2;
        let y_max = self
            .points
            .iter()
            .map(|p| p.errors_per_million)
            .fold(10.0, f64::max)
            * 10.0;
        let mut chart = ChartBuilder::on(root)
            .caption("ray-triangle variants: cost against error", (FAMILY, 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(0.0..x_max, (ERROR_FLOOR..y_max).log_scale())?;
        chart
            .configure_mesh()
            .x_desc(match &self.mesh {
                Some(m) => format!(
                    "ns per incoherent ray through the BVH ({}), one thread",
                    crate::text::excerpt(m)
                ),
                None => "ns per incoherent ray through the BVH, one thread".into(),
            })
            .y_desc(format!(
                "leaks + false hits per million rays (none: a dot on the bottom line; \
                 below {ERROR_FLOOR}: a ring)"
            ))
            .x_label_formatter(&|v| chart_number(*v))
            .y_label_formatter(&|v| chart_number(*v))
            .label_style((FAMILY, 14))
            .axis_desc_style((FAMILY, 15))
            .draw()?;
        for (i, p) in self.points.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let at = (p.ns_per_ray, p.errors_per_million.max(ERROR_FLOOR));
            let style = if p.below_floor() {
                colour.stroke_width(2)
            } else {
                colour.filled()
            };
            chart.draw_series(std::iter::once(Circle::new(at, 6, style)))?;
            chart.draw_series(std::iter::once(Text::new(
                p.label.clone(),
                at,
                (FAMILY, 13).into_font().color(&colour),
            )))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{png_pixels_of, svg_texts};
    use super::super::{Format, render};
    use super::*;

    #[test]
    fn points_come_from_the_runs_json_and_are_drawn_in_both_formats() {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("accuracy.json");
        std::fs::write(
            &json,
            r#"{"variants": [
                {"name": "watertight", "mrays_bvh_incoherent": 5.0, "leaks_per_million": 0.0, "false_hits_per_million": 0.0, "other": 1},
                {"name": "moller-trumbore", "mrays_bvh_incoherent": 6.25, "leaks_per_million": 1200.0, "false_hits_per_million": 34.0},
                {"name": "no-bvh", "mrays_bvh_incoherent": null, "leaks_per_million": 1.0, "false_hits_per_million": null}
            ], "slab": []}"#,
        )
        .unwrap();
        let chart = AccuracyChart::from_file(&json).unwrap();
        assert_eq!(
            chart.points,
            [
                Point {
                    label: "watertight".into(),
                    ns_per_ray: 200.0,
                    errors_per_million: 0.0
                },
                Point {
                    label: "moller-trumbore".into(),
                    ns_per_ray: 160.0,
                    errors_per_million: 1234.0
                },
            ]
        );
        let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
        for want in [
            "watertight: 200.0 ns, 0.0 per million",
            "moller-trumbore: 160.0 ns, 1234.0 per million",
            "ray-triangle variants: cost against error",
        ] {
            assert!(texts.iter().any(|t| t == want), "{want} not in {texts:?}");
        }
        let png = render(&chart, Format::Png).unwrap();
        assert!(png_pixels_of(&png, chart.size(), PALETTE[0]) > 50);
        assert!(png_pixels_of(&png, chart.size(), PALETTE[1]) > 50);
    }

    /// A rate below [`ERROR_FLOOR`] but not zero (one leak in 20 million rays) is printed as
    /// itself and drawn as a ring on the bottom line, where none is a dot; it was printed
    /// "0 per million" and drawn as none.
    #[test]
    fn a_rate_below_the_floor_is_told_apart_from_none() {
        /// How far the printed rate may be from the true one, relative: three significant
        /// digits are printed.
        const PRINTED: f64 = 1e-2;
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("accuracy.json");
        std::fs::write(
            &json,
            r#"{"variants": [
                {"name": "none", "mrays_bvh_incoherent": 5.0, "leaks_per_million": 0.0, "false_hits_per_million": 0.0},
                {"name": "rare", "mrays_bvh_incoherent": 5.0, "leaks_per_million": 0.03, "false_hits_per_million": 0.02},
                {"name": "some", "mrays_bvh_incoherent": 5.0, "leaks_per_million": 0.5, "false_hits_per_million": 0.0}
            ]}"#,
        )
        .unwrap();
        let chart = AccuracyChart::from_file(&json).unwrap();
        let svg = render(&chart, Format::Svg).unwrap();
        let texts = svg_texts(&svg, chart.size());
        let legend = |name: &str| {
            texts
                .iter()
                .find(|t| t.starts_with(&format!("{name}: ")))
                .unwrap_or_else(|| panic!("{name} not in {texts:?}"))
                .clone()
        };
        let rate = |t: &str| -> f64 {
            let rate = t.split(" ns, ").nth(1).unwrap().split(' ').next().unwrap();
            rate.parse().unwrap()
        };
        let rare = legend("rare");
        assert!((rate(&rare) / 0.05 - 1.0).abs() < PRINTED, "{rare}");
        assert!(
            rare.ends_with("(below 0.1: a ring on the bottom line)"),
            "{rare}"
        );
        for name in ["none", "some"] {
            assert!(!legend(name).contains("below"), "{}", legend(name));
        }
        assert_eq!(rate(&legend("none")), 0.0);
        assert!((rate(&legend("some")) / 0.5 - 1.0).abs() < PRINTED);
        // The plot's points (the legend's markers are filled dots too): none and rare on one
        // line, rare alone hollow, some above them.
        let svg = String::from_utf8(svg).unwrap();
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let hex = |c: RGBColor| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
        let point = |c: RGBColor| {
            let circles: Vec<_> = doc
                .descendants()
                .filter(|n| n.has_tag_name("circle"))
                .filter(|n| {
                    [n.attribute("fill"), n.attribute("stroke")]
                        .iter()
                        .any(|a| a.is_some_and(|a| a.eq_ignore_ascii_case(&hex(c))))
                })
                .collect();
            assert_eq!(circles.len(), 2, "a marker and a point: {svg}");
            // The plot's point is drawn after the legend's marker.
            let p = circles[1];
            let cy: f64 = p.attribute("cy").unwrap().parse().unwrap();
            (cy, p.attribute("fill") == Some("none"))
        };
        let (none, rare, some) = (point(PALETTE[0]), point(PALETTE[1]), point(PALETTE[2]));
        assert_eq!((none.1, rare.1, some.1), (false, true, false));
        assert_eq!(none.0, rare.0);
        assert!(some.0 < none.0 - 10.0, "{some:?} {none:?}");
    }

    #[test]
    fn a_run_without_throughput_is_an_input_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("a.json");
        std::fs::write(&json, r#"{"variants": []}"#).unwrap();
        let e = AccuracyChart::from_file(&json).unwrap_err().to_string();
        assert!(
            e.contains("a.json") && e.contains("nothing to chart"),
            "{e}"
        );
        std::fs::write(&json, "{\n\"variants\": 3}").unwrap();
        let e = AccuracyChart::from_file(&json).unwrap_err().to_string();
        assert!(e.contains("a.json") && e.contains(":2"), "{e}");
    }

    /// Values no run writes are input errors naming the field, not a chart (an error rate
    /// of `1e308` or a throughput of `1e-310` made axes whose tick search never ended);
    /// a throughput of 0 (nothing timed) is left out as an absent one is.
    #[test]
    fn values_no_run_writes_are_input_errors_naming_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("a.json");
        let row = |m: &str, l: &str, f: &str| {
            format!(
                r#"{{"variants": [{{"name": "ok", "mrays_bvh_incoherent": 5.0, "leaks_per_million": 0.0, "false_hits_per_million": 0.0}},
                {{"name": "bad", "mrays_bvh_incoherent": {m}, "leaks_per_million": {l}, "false_hits_per_million": {f}}}]}}"#
            )
        };
        for (m, l, f, field) in [
            ("1e-310", "0", "0", "variants[1].mrays_bvh_incoherent"),
            ("-2", "0", "0", "variants[1].mrays_bvh_incoherent"),
            ("1e300", "0", "0", "variants[1].mrays_bvh_incoherent"),
            ("5", "1e308", "0", "variants[1].leaks_per_million"),
            ("5", "-1", "0", "variants[1].leaks_per_million"),
            ("5", "0", "1000001", "variants[1].false_hits_per_million"),
        ] {
            std::fs::write(&json, row(m, l, f)).unwrap();
            let e = AccuracyChart::from_file(&json).unwrap_err().to_string();
            assert!(
                e.contains("a.json") && e.contains(field),
                "{m} {l} {f}: {e}"
            );
        }
        std::fs::write(&json, row("0", "1e6", "1e6")).unwrap();
        let chart = AccuracyChart::from_file(&json).unwrap();
        assert_eq!(chart.points.len(), 1);
        std::fs::write(&json, row("1e9", "1e6", "1e6")).unwrap();
        let chart = AccuracyChart::from_file(&json).unwrap();
        assert_eq!(chart.points[1].errors_per_million, 2.0e6);
        render(&chart, Format::Svg).unwrap();
    }

    /// At both ends of [`MRAYS_RANGE`] every number the chart prints is short and the
    /// legend's time reads back within 1 % (one decimal printed `10⁻⁶` ns as `0.0` on every
    /// tick and in the legend, and `3.3·10¹²` ns as fifteen characters); at the fast end the
    /// time axis's ticks are at least three distinct numbers above zero.
    #[test]
    fn the_time_axis_reads_at_both_ends_of_the_range() {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("a.json");
        for (mrays, ns) in [(1.0e9, 1.0e-6), (3.0e-10, 1.0e3 / 3.0e-10)] {
            std::fs::write(
                &json,
                format!(
                    r#"{{"variants": [{{"name": "v", "mrays_bvh_incoherent": {mrays:e}, "leaks_per_million": 0.0, "false_hits_per_million": 0.0}}]}}"#
                ),
            )
            .unwrap();
            let chart = AccuracyChart::from_file(&json).unwrap();
            let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
            let legend = texts.iter().find(|t| t.starts_with("v: ")).unwrap();
            let shown: f64 = legend[3..].split(" ns").next().unwrap().parse().unwrap();
            assert!((shown / ns - 1.0).abs() < 1e-2, "{legend}: {ns}");
            let numbers: Vec<f64> = texts.iter().filter_map(|t| t.parse().ok()).collect();
            for t in texts.iter().filter(|t| t.parse::<f64>().is_ok()) {
                assert!(t.len() <= 9, "{t} in {texts:?}");
            }
            if ns < 1.0 {
                let mut ticks: Vec<f64> = numbers
                    .into_iter()
                    .filter(|&v| v > 0.0 && v <= 1.2 * ns)
                    .collect();
                ticks.sort_by(f64::total_cmp);
                ticks.dedup();
                assert!(ticks.len() >= 3, "{texts:?}");
            }
        }
    }
}
