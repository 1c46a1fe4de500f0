//! The corpus chart of `bench bvh`: per mesh (x) and ray set (colour), halfray's throughput
//! over Embree robust's (filled circle) and over Embree default's (hollow circle); the line at
//! 1 is parity. The legend gives each set's geometric mean over the corpus.

use super::{
    Chart, FAMILY, Marker, PALETTE, category_chart_width, draw_category_axes, draw_legend_below,
    legend_height, parse_json,
};
use crate::bench::bvh::BvhReport;
use crate::bench::bvh::summary::{SetSummary, mesh_labels, mesh_name, set_names, summarize};
use crate::error::{Error, Location, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// The chart's figures, taken from a `bench bvh --json` run.
#[derive(Clone, Debug, PartialEq)]
pub struct CorpusChart {
    /// Mesh labels, in run order (x): the file name, or the path where two meshes of the run
    /// share a file name ([`mesh_labels`]).
    pub meshes: Vec<String>,
    /// Per set: its summary and, per mesh, `[over default, over robust]` (`None` where the
    /// mesh did not run the set).
    pub sets: Vec<(SetSummary, Vec<Option<[f64; 2]>>)>,
}

/// The ratios the chart draws: from a millionth of Embree's throughput to a million times it.
/// A run measures nothing outside (a ray a millisecond against Embree's nanosecond is already
/// far inside); a hand-edited report's `1e308` made the axis infinite and its tick search never
/// ended, so values outside are an input error naming the field.
pub const RATIO_RANGE: std::ops::RangeInclusive<f64> = 1.0e-6..=1.0e6;

impl CorpusChart {
    /// The chart of `reports`; `None` when no set of any mesh has a ratio
    /// ([`crate::bench::bvh::SetFigures::ratios`]: no Embree figures, no rays, or a throughput
    /// that is not positive).
    pub fn new(reports: &[BvhReport]) -> Option<Self> {
        let summaries = summarize(reports);
        if summaries.is_empty() {
            return None;
        }
        let sets = summaries
            .into_iter()
            .map(|s| {
                let per_mesh = reports
                    .iter()
                    .map(|r| r.sets.iter().find(|x| x.name == s.name)?.ratios())
                    .collect();
                (s, per_mesh)
            })
            .collect();
        debug_assert!(!set_names(reports).is_empty());
        Some(Self {
            meshes: mesh_labels(reports),
            sets,
        })
    }

    /// The chart of a `bench bvh --json` file (one report or an array).
    ///
    /// # Errors
    ///
    /// Reading or parsing the file (the line, column and field of a value of the wrong shape);
    /// an input error when it has no mesh, when the run has no Embree figures (it was built
    /// without `--features embree`), when no set has a positive throughput on both sides, or
    /// naming the field of a ratio outside [`RATIO_RANGE`].
    pub fn from_file(path: &Path) -> Result<Self> {
        const WHAT: &str = "`bench bvh --json`";
        let text = crate::input::read_text(path, &format!("the JSON of {WHAT}"))?;
        // One report is an object, several an array: parsed as the one its first character
        // says, so that an error names its line, column and field.
        let many = text.trim_start().starts_with('[');
        let reports: Vec<BvhReport> = if many {
            parse_json(path, &text, WHAT)?
        } else {
            vec![parse_json(path, &text, WHAT)?]
        };
        if reports.is_empty() {
            return Err(Error::input(
                Location::file(path),
                "the run has no mesh: nothing to chart",
            ));
        }
        for (i, r) in reports.iter().enumerate() {
            for (j, set) in r.sets.iter().enumerate() {
                let Some(ratios) = set.ratios() else { continue };
                let Some(&q) = ratios.iter().find(|q| !RATIO_RANGE.contains(q)) else {
                    continue;
                };
                let at = if many {
                    format!("[{i}].sets[{j}]")
                } else {
                    format!("sets[{j}]")
                };
                return Err(Error::input(
                    Location::file(path).field(at),
                    format!(
                        "halfray's throughput over Embree's is {q:e} ({}, set {}): not a ratio \
                         a run measures ({:e} to {:e})",
                        mesh_name(r),
                        set.name,
                        RATIO_RANGE.start(),
                        RATIO_RANGE.end()
                    ),
                ));
            }
        }
        Self::new(&reports).ok_or_else(|| {
            let embree = reports
                .iter()
                .flat_map(|r| &r.sets)
                .any(|s| s.embree_mrays.is_some() || s.embree_robust_mrays.is_some());
            Error::input(
                Location::file(path),
                if embree {
                    "no set has a positive throughput on both sides (halfray and Embree's two \
                     modes, over at least one ray): nothing to chart"
                } else {
                    "the run has no Embree figures (run `bench bvh` built with `--features embree`)"
                },
            )
        })
    }
}

impl Chart for CorpusChart {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let legend: Vec<(String, RGBColor)> = self
            .sets
            .iter()
            .enumerate()
            .map(|(s, (summary, _))| {
                let label = format!(
                    "{}: geo. mean {:.2} ÷ robust, {:.2} ÷ default; worst {:.2} ({})",
                    summary.name,
                    summary.geomean[1],
                    summary.geomean[0],
                    summary.worst[1].0,
                    summary.worst[1].1
                );
                (label, PALETTE[s % PALETTE.len()])
            })
            .collect();
        let root = &draw_legend_below(root, &legend, Marker::Dot)?;
        let n = self.meshes.len();
        let y_max = self
            .sets
            .iter()
            .flat_map(|(_, v)| v.iter().flatten().flatten())
            .fold(1.2f64, |a, &b| a.max(b))
            * 1.15;
        let mut chart = ChartBuilder::on(root)
            .caption(
                "halfray ÷ Embree 4 per mesh and ray set (filled: ÷ robust, hollow: ÷ default)",
                (FAMILY, 20),
            )
            .margin(16)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .build_cartesian_2d(-0.5..n as f64 - 0.5, 0.0..y_max)?;
        draw_category_axes(
            &mut chart,
            &self.meshes,
            "throughput ratio, one thread, same rays",
        )?;
        chart.draw_series(LineSeries::new(
            [(-0.5, 1.0), (n as f64 - 0.5, 1.0)],
            BLACK.stroke_width(1),
        ))?;
        let k = self.sets.len() as f64;
        for (s, (_, per_mesh)) in self.sets.iter().enumerate() {
            let colour = PALETTE[s % PALETTE.len()];
            let offset = (s as f64 - (k - 1.0) / 2.0) * (0.7 / k.max(1.0));
            let at = |i: usize, m: usize| per_mesh[i].map(|r| (i as f64 + offset, r[m]));
            chart.draw_series(
                (0..n)
                    .filter_map(|i| at(i, 1))
                    .map(|p| Circle::new(p, 5, colour.filled())),
            )?;
            chart.draw_series(
                (0..n)
                    .filter_map(|i| at(i, 0))
                    .map(|p| Circle::new(p, 5, colour.stroke_width(2))),
            )?;
        }
        Ok(())
    }

    fn size(&self) -> (u32, u32) {
        (
            category_chart_width(self.meshes.len(), 90),
            640 + legend_height(self.sets.len()),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{png_pixels_of, svg_texts};
    use super::super::{Format, render};
    use super::*;
    use crate::bench::bvh::summary::tests::report;

    #[test]
    fn the_chart_carries_every_mesh_and_each_sets_figures_from_the_json() {
        let reports = vec![
            report(
                "bunny.obj",
                &[("primary", 3.0, 4.0, 3.0), ("shadow", 2.0, 2.0, 1.0)],
            ),
            report(
                "sphere.obj",
                &[("primary", 6.0, 5.0, 4.0), ("shadow", 1.0, 2.0, 2.0)],
            ),
            report(
                "terrain.obj",
                &[("primary", 2.0, 2.5, 2.0), ("shadow", 1.0, 1.0, 1.0)],
            ),
        ];
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("bench.json");
        std::fs::write(&json, serde_json::to_vec(&reports).unwrap()).unwrap();
        let chart = CorpusChart::from_file(&json).unwrap();
        assert_eq!(chart.meshes, ["bunny.obj", "sphere.obj", "terrain.obj"]);
        assert_eq!(chart.sets[0].1[1], Some([6.0 / 5.0, 6.0 / 4.0]));
        let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
        for want in ["bunny.obj", "sphere.obj", "terrain.obj"] {
            assert!(texts.iter().any(|t| t == want), "{want} not in {texts:?}");
        }
        // primary over robust: 1, 1.5, 1 → geometric mean 1.14; over default 0.75, 1.2, 0.8.
        let legend = "primary: geo. mean 1.14 ÷ robust, 0.90 ÷ default; worst 1.00 (bunny.obj)";
        assert!(texts.iter().any(|t| t == legend), "{texts:?}");
        assert!(
            texts
                .iter()
                .any(|t| t.starts_with("shadow: geo. mean 1.00 ÷ robust"))
        );
        let png = render(&chart, Format::Png).unwrap();
        assert!(png_pixels_of(&png, chart.size(), PALETTE[0]) > 50);
        assert!(png_pixels_of(&png, chart.size(), PALETTE[1]) > 50);
        // One report (a single-mesh run writes the object itself) is read too.
        std::fs::write(&json, serde_json::to_vec(&reports[0]).unwrap()).unwrap();
        assert_eq!(CorpusChart::from_file(&json).unwrap().meshes, ["bunny.obj"]);
    }

    /// Two meshes of one file name in different folders are two points labelled by path.
    #[test]
    fn meshes_sharing_a_file_name_are_labelled_by_path() {
        let reports = [
            report("a/m.obj", &[("primary", 3.0, 4.0, 3.0)]),
            report("b/m.obj", &[("primary", 6.0, 5.0, 4.0)]),
        ];
        let chart = CorpusChart::new(&reports).unwrap();
        assert_eq!(chart.meshes, ["dir/a/m.obj", "dir/b/m.obj"]);
        assert_eq!(chart.sets[0].0.worst[1].1, "dir/a/m.obj");
    }

    /// A hand-edited report with an Embree throughput of 0 gave an infinite ratio, and the
    /// chart's axis never finished (the process spun); a negative one a geometric mean of NaN
    /// on the chart; such a set has no ratio.
    #[test]
    fn a_zero_or_negative_throughput_is_no_ratio_and_the_chart_is_drawn() {
        for (side, value) in [(0, 0.0), (1, 0.0), (0, -5.0), (2, -5.0), (2, 0.0)] {
            let mut bad = report("bunny.obj", &[("primary", 3.0, 4.0, 3.0)]);
            match side {
                0 => bad.sets[0].embree_robust_mrays = Some(value),
                1 => bad.sets[0].embree_mrays = Some(value),
                _ => bad.sets[0].mrays = value,
            }
            let good = report("sphere.obj", &[("primary", 6.0, 5.0, 4.0)]);
            let chart = CorpusChart::new(&[bad, good]).unwrap();
            assert_eq!(chart.sets[0].1[0], None, "{side} {value}");
            let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
            assert!(texts.iter().any(|t| t == "sphere.obj"), "{texts:?}");
            assert!(!texts.iter().any(|t| t.contains("NaN")), "{texts:?}");
        }
    }

    /// A ratio beyond `f64::MAX / 1.15` made the axis infinite and its tick search spun
    /// forever (`1.7e308` Mrays/s over 1); ratios outside [`RATIO_RANGE`] are an input error
    /// naming the report and set, the edges of the range are drawn.
    #[test]
    fn a_ratio_no_run_measures_is_refused_naming_its_field() {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("bench.json");
        for (mrays, ok) in [
            (1.7e308, false),
            (2.0e6, false),
            (1.0e6, true),
            (1.0e-6, true),
        ] {
            let good = report("bunny.obj", &[("primary", 3.0, 4.0, 3.0)]);
            let odd = report(
                "far.obj",
                &[("primary", 3.0, 4.0, 3.0), ("ao", mrays, 1.0, 1.0)],
            );
            std::fs::write(&json, serde_json::to_vec(&[good, odd]).unwrap()).unwrap();
            match CorpusChart::from_file(&json) {
                Ok(chart) => {
                    assert!(ok, "{mrays} drawn");
                    let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
                    assert!(texts.iter().any(|t| t == "far.obj"), "{texts:?}");
                }
                Err(e) => {
                    let e = e.to_string();
                    assert!(!ok, "{mrays}: {e}");
                    assert!(
                        e.contains("bench.json: field `[1].sets[1]`")
                            && e.contains("far.obj, set ao"),
                        "{e}"
                    );
                }
            }
        }
    }

    /// Every set of a `bench bvh` run has a colour of its own (ten sets shared eight colours:
    /// `shadow+batch` was drawn as `primary`), and the legend, below the plot, covers no point
    /// (it hid 73 of the corpus chart's 320).
    #[test]
    fn ten_sets_have_ten_colours_and_the_legend_hides_no_point() {
        let sets: Vec<(String, f64)> = (0..10)
            .map(|s| (format!("set{s}"), 0.3 + 0.2 * s as f64))
            .collect();
        let figures: Vec<(&str, f64, f64, f64)> = sets
            .iter()
            .map(|(n, q)| (n.as_str(), *q, 1.0, 1.0))
            .collect();
        let reports: Vec<_> = (0..12)
            .map(|m| report(&format!("m{m}.obj"), &figures))
            .collect();
        let chart = CorpusChart::new(&reports).unwrap();
        let png = render(&chart, Format::Png).unwrap();
        for (s, colour) in PALETTE.iter().enumerate() {
            assert!(png_pixels_of(&png, chart.size(), *colour) > 50, "set {s}");
            assert!(!PALETTE[..s].contains(colour), "colour {s} repeated");
        }
        let svg = String::from_utf8(render(&chart, Format::Svg).unwrap()).unwrap();
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let num = |n: &roxmltree::Node, a: &str| n.attribute(a).unwrap().parse::<f64>().unwrap();
        let legend_top = doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter(|n| n.text().is_some_and(|t| t.contains("geo. mean")))
            .map(|n| num(&n, "y"))
            .fold(f64::INFINITY, f64::min);
        let circles: Vec<f64> = doc
            .descendants()
            .filter(|n| n.has_tag_name("circle"))
            .map(|n| num(&n, "cy") + num(&n, "r"))
            .collect();
        // 12 meshes × 10 sets × 2 (filled, hollow) points, and 10 legend markers.
        assert_eq!(circles.len(), 12 * 10 * 2 + 10);
        let below = circles.iter().filter(|&&y| y > legend_top - 10.0).count();
        assert_eq!(below, 10, "only the legend's own markers reach its rows");
    }

    /// A mesh name from the JSON with characters XML 1.0 forbids (a terminal escape, the
    /// noncharacters U+FFFE and U+FFFF) is drawn with U+FFFD in their place: the SVG stays
    /// well-formed XML (it did not parse before). U+FFFD itself and tab pass.
    #[test]
    fn control_characters_in_a_name_keep_the_svg_well_formed() {
        let chart = CorpusChart::new(&[report(
            "a\u{1b}[31m\u{7}\u{fffe}\u{ffff}\u{fffd}\u{10000}.obj",
            &[("primary", 3.0, 4.0, 3.0)],
        )])
        .unwrap();
        let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
        assert!(
            texts
                .iter()
                .any(|t| t == "a\u{fffd}[31m\u{fffd}\u{fffd}\u{fffd}\u{fffd}\u{10000}.obj"),
            "{texts:?}"
        );
    }

    #[test]
    fn a_run_without_embree_is_refused() {
        let mut r = report("bunny.obj", &[("primary", 3.0, 4.0, 3.0)]);
        r.sets[0].embree_mrays = None;
        r.sets[0].embree_robust_mrays = None;
        assert_eq!(CorpusChart::new(std::slice::from_ref(&r)), None);
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("bench.json");
        std::fs::write(&json, serde_json::to_vec(&[r]).unwrap()).unwrap();
        let e = CorpusChart::from_file(&json).unwrap_err().to_string();
        assert!(
            e.contains("bench.json") && e.contains("no Embree figures"),
            "{e}"
        );
    }

    /// A run with Embree figures whose every throughput is 0 (or a set of no rays) has no
    /// ratio: the error says so, not that Embree was missing from the build (as it did).
    #[test]
    fn a_run_without_a_positive_throughput_is_refused_as_such() {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("bench.json");
        let zero = report("bunny.obj", &[("primary", 0.0, 0.0, 0.0)]);
        let mut empty = report("cube.obj", &[("ao", 3.0, 4.0, 3.0)]);
        empty.sets[0].rays = 0;
        for reports in [vec![zero.clone()], vec![zero, empty]] {
            std::fs::write(&json, serde_json::to_vec(&reports).unwrap()).unwrap();
            let e = CorpusChart::from_file(&json).unwrap_err().to_string();
            assert!(
                e.contains("bench.json")
                    && e.contains("no set has a positive throughput on both sides")
                    && !e.contains("features embree"),
                "{e}"
            );
        }
    }
}
