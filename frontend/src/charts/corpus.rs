//! The corpus chart of `bench bvh`: per mesh (x) and ray set (colour), halfray's throughput
//! over Embree robust's (filled circle) and over Embree default's (hollow circle); the line at
//! 1 is parity. The legend gives each set's geometric mean over the corpus.

use super::{Chart, FAMILY, PALETTE, draw_category_axes, read_json};
use crate::bench::bvh::BvhReport;
use crate::bench::bvh::summary::{SetSummary, mesh_name, set_names, summarize};
use crate::error::{Error, Location, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// The chart's figures, taken from a `bench bvh --json` run.
#[derive(Clone, Debug, PartialEq)]
pub struct CorpusChart {
    /// Mesh file names, in run order (x).
    pub meshes: Vec<String>,
    /// Per set: its summary and, per mesh, `[over default, over robust]` (`None` where the
    /// mesh did not run the set).
    pub sets: Vec<(SetSummary, Vec<Option<[f64; 2]>>)>,
}

/// A `bench bvh --json` file: one report, or an array of them.
#[derive(serde::Deserialize)]
#[serde(untagged)]
enum Reports {
    One(Box<BvhReport>),
    Many(Vec<BvhReport>),
}

impl CorpusChart {
    /// The chart of `reports`.
    ///
    /// # Errors
    ///
    /// `None` when no set has Embree figures.
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
            meshes: reports.iter().map(mesh_name).collect(),
            sets,
        })
    }

    /// The chart of a `bench bvh --json` file (one report or an array).
    ///
    /// # Errors
    ///
    /// Reading or parsing the file; an input error when the run has no Embree figures (it
    /// was built without `--features embree`).
    pub fn from_file(path: &Path) -> Result<Self> {
        let reports = match read_json::<Reports>(path, "`bench bvh --json`")? {
            Reports::One(r) => vec![*r],
            Reports::Many(v) => v,
        };
        Self::new(&reports).ok_or_else(|| {
            Error::input(
                Location::file(path),
                "the run has no Embree figures (run `bench bvh` built with `--features embree`)",
            )
        })
    }
}

impl Chart for CorpusChart {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
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
        for (s, (summary, per_mesh)) in self.sets.iter().enumerate() {
            let colour = PALETTE[s % PALETTE.len()];
            let offset = (s as f64 - (k - 1.0) / 2.0) * (0.7 / k.max(1.0));
            let at = |i: usize, m: usize| per_mesh[i].map(|r| (i as f64 + offset, r[m]));
            chart
                .draw_series(
                    (0..n)
                        .filter_map(|i| at(i, 1))
                        .map(|p| Circle::new(p, 5, colour.filled())),
                )?
                .label(format!(
                    "{}: geo. mean {:.2} ÷ robust, {:.2} ÷ default; worst {:.2} ({})",
                    summary.name,
                    summary.geomean[1],
                    summary.geomean[0],
                    summary.worst[1].0,
                    summary.worst[1].1
                ))
                .legend(move |(x, y)| Circle::new((x, y), 5, colour.filled()));
            chart.draw_series(
                (0..n)
                    .filter_map(|i| at(i, 0))
                    .map(|p| Circle::new(p, 5, colour.stroke_width(2))),
            )?;
        }
        super::draw_legend(&mut chart, SeriesLabelPosition::LowerRight)
    }

    fn size(&self) -> (u32, u32) {
        ((160 + 90 * self.meshes.len() as u32).max(900), 640)
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
        assert_eq!(CorpusChart::new(&[r]), None);
    }
}
