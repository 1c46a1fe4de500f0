//! The disagreement chart of `crosscheck`: per mesh (x), the count of rays in each class of
//! disagreement with Embree (bars, log scale), summed over the run's ray sets. Agreement is
//! left out (it is the rest of the rays; the caption gives the totals). Meshes that could not
//! be checked are named in a line under the caption.

use super::{
    Chart, FAMILY, Marker, PALETTE, category_chart_width, draw_category_axes, draw_legend_below,
    legend_height, read_json,
};
use crate::crosscheck::report::{Report, SetReport};
use crate::error::{Error, Location, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::HashMap;
use std::path::Path;

/// How a set's row counts one class of disagreement.
pub type ClassCount = fn(&SetReport) -> usize;

/// The classes drawn, in order: their names and how a set's row counts them.
pub const CLASSES: [(&str, ClassCount); 8] = [
    ("tie", |r| r.ties),
    ("within tolerance", |r| r.within_tolerance),
    ("Embree wrong", |r| r.embree_wrong),
    ("genuine mismatch", |r| r.genuine_mismatches),
    ("leak halfray", |r| r.leaks_halfray),
    ("leak Embree robust", |r| r.leaks_embree),
    ("leak Embree default", |r| r.leaks_embree_default),
    ("any-hit differs", |r| r.any_hit_disagreements),
];

/// Counts below this are not drawn (the log axis starts here).
const COUNT_FLOOR: f64 = 0.5;

/// The chart's figures, taken from a `crosscheck --json` run.
#[derive(Clone, Debug, PartialEq)]
pub struct DisagreementChart {
    /// Mesh names, in report order (x): the file name, or the path where two meshes of the
    /// run share a file name.
    pub meshes: Vec<String>,
    /// Per mesh, the count of each of [`CLASSES`].
    pub counts: Vec<[usize; CLASSES.len()]>,
    /// Rays checked per mesh.
    pub rays: Vec<usize>,
    /// The ray sets of the run.
    pub sets: Vec<String>,
    /// The meshes that could not be checked (the report's `failed`), named as [`Self::meshes`]
    /// are; a mesh of a merge that failed on some shards only is also in `meshes`, with the
    /// sums of the others.
    pub failed: Vec<String>,
    /// Meshes checked or attempted (the report's `meshes`).
    pub attempted: usize,
}

/// Most failed meshes the chart names; the rest are counted (`… and 12 more`), so that the
/// line stays within the chart's width.
pub const MAX_FAILED_NAMED: usize = 5;
/// Height the line naming the failed meshes adds, pixels: 14-point text and 5 above and
/// below (`DrawingArea::titled`).
const FAILED_LINE: u32 = 24;

impl DisagreementChart {
    /// The chart of `report`: its rows summed per mesh; `None` when a count's total over the
    /// report ([`Report::overflowing_total`]) does not fit in a `usize` (a file no run can have
    /// written). Every sum the chart makes, per mesh or over the meshes, is at most that
    /// total, so none overflows.
    #[must_use]
    pub fn new(report: &Report) -> Option<Self> {
        if report.overflowing_total().is_some() {
            return None;
        }
        let mut chart = Self {
            meshes: Vec::new(),
            counts: Vec::new(),
            rays: Vec::new(),
            sets: report.config.ray_sets.clone(),
            failed: Vec::new(),
            attempted: report.meshes,
        };
        // Rows are a mesh's by its path (`crosscheck` runs two files of one name as two
        // meshes, as its report's per-mesh results do); labelled by file name where that is
        // unambiguous.
        let mut paths: Vec<&str> = Vec::new();
        let mut index: HashMap<&str, usize> = HashMap::new();
        for row in &report.sets {
            let i = match index.get(row.path.as_str()) {
                Some(&i) => i,
                None => {
                    index.insert(&row.path, paths.len());
                    paths.push(&row.path);
                    chart.meshes.push(row.mesh.clone());
                    chart.counts.push([0; CLASSES.len()]);
                    chart.rays.push(0);
                    chart.meshes.len() - 1
                }
            };
            for (c, (_, count)) in chart.counts[i].iter_mut().zip(CLASSES) {
                *c += count(row);
            }
            chart.rays[i] += row.rays;
        }
        // Named together, so that a failed mesh and a checked one of one file name are told
        // apart by their paths here too.
        let checked = chart.meshes.len();
        let failed = report
            .failed
            .iter()
            .map(|f| (crate::text::file_name(Path::new(&f.path)), f.path.as_str()));
        let mut names = crate::text::unambiguous_names(
            std::mem::take(&mut chart.meshes)
                .into_iter()
                .zip(paths)
                .chain(failed),
        );
        chart.failed = names.split_off(checked);
        chart.meshes = names;
        Some(chart)
    }

    /// The chart of a `crosscheck --json` (or `crosscheck merge --json`) file.
    ///
    /// # Errors
    ///
    /// Reading or parsing the file; an input error when it has no rows, or naming the count
    /// whose total overflows ([`DisagreementChart::new`]).
    pub fn from_file(path: &Path) -> Result<Self> {
        let report: Report = read_json(path, "`crosscheck --json`")?;
        let Some(chart) = Self::new(&report) else {
            let name = report.overflowing_total().unwrap_or("rays");
            return Err(Error::input(
                Location::file(path).field(format!("sets.{name}")),
                format!(
                    "the sets' total overflows {} bits: not a run's report",
                    usize::BITS
                ),
            ));
        };
        if chart.meshes.is_empty() {
            let message = match chart.failed_line() {
                Some(failed) => format!("the run checked no mesh ({failed}): nothing to chart"),
                None => "the run checked no mesh: nothing to chart".into(),
            };
            return Err(Error::input(Location::file(path), message));
        }
        Ok(chart)
    }

    /// "N of M meshes could not be checked: NAMES" (at most [`MAX_FAILED_NAMED`] names, each
    /// an excerpt), or `None` when every mesh was checked.
    #[must_use]
    pub fn failed_line(&self) -> Option<String> {
        if self.failed.is_empty() {
            return None;
        }
        let n = self.failed.len();
        let mut names: Vec<String> = self
            .failed
            .iter()
            .take(MAX_FAILED_NAMED)
            .map(|f| crate::text::excerpt(f))
            .collect();
        if n > MAX_FAILED_NAMED {
            names.push(format!("… and {} more", n - MAX_FAILED_NAMED));
        }
        // A hand-edited report may count fewer meshes than it lists as failed.
        let of = self.attempted.max(n);
        Some(format!(
            "{n} of {of} meshes could not be checked: {}",
            names.join(", ")
        ))
    }
}

impl Chart for DisagreementChart {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        let legend: Vec<(String, RGBColor)> = CLASSES
            .iter()
            .enumerate()
            .map(|(c, (name, _))| {
                let total: usize = self.counts.iter().map(|m| m[c]).sum();
                (format!("{name}: {total}"), PALETTE[c % PALETTE.len()])
            })
            .collect();
        let root = &draw_legend_below(root, &legend, Marker::Square)?;
        let n = self.meshes.len();
        let top = self.counts.iter().flatten().fold(10usize, |a, &b| a.max(b)) as f64 * 10.0;
        let total: usize = self.rays.iter().sum();
        let mut area = root.margin(16, 16, 16, 16).titled(
            &format!(
                "cross-check against Embree 4: disagreements per mesh ({total} rays; sets {})",
                self.sets.join(", ")
            ),
            (FAMILY, 18),
        )?;
        if let Some(line) = self.failed_line() {
            area = area.titled(&line, (FAMILY, 14).into_font().color(&PALETTE[1]))?;
        }
        let mut chart = ChartBuilder::on(&area)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .build_cartesian_2d(-0.5..n as f64 - 0.5, (COUNT_FLOOR..top).log_scale())?;
        draw_category_axes(
            &mut chart,
            &self.meshes,
            "rays (log scale; classes with none are not drawn)",
        )?;
        let width = 0.8 / CLASSES.len() as f64;
        for c in 0..CLASSES.len() {
            let colour = PALETTE[c % PALETTE.len()];
            let x0 = |i: usize| i as f64 - 0.4 + c as f64 * width;
            let bars = (0..n).filter(|&i| self.counts[i][c] > 0).map(|i| {
                Rectangle::new(
                    [
                        (x0(i), COUNT_FLOOR),
                        (x0(i) + width, self.counts[i][c] as f64),
                    ],
                    colour.filled(),
                )
            });
            chart.draw_series(bars)?;
        }
        Ok(())
    }

    fn size(&self) -> (u32, u32) {
        (
            category_chart_width(self.meshes.len(), 110),
            640 + legend_height(CLASSES.len())
                + if self.failed.is_empty() {
                    0
                } else {
                    FAILED_LINE
                },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{png_pixels_of, svg_texts};
    use super::super::{Format, render};
    use super::*;

    fn row(
        mesh: &str,
        set: &str,
        ties: usize,
        genuine: usize,
        leaks_default: usize,
    ) -> serde_json::Value {
        let mut r = serde_json::to_value(SetReport::default()).unwrap();
        r["mesh"] = mesh.into();
        r["path"] = format!("m/{mesh}").into();
        r["name"] = set.into();
        r["rays"] = 1000.into();
        r["ties"] = ties.into();
        r["genuine_mismatches"] = genuine.into();
        r["leaks_embree_default"] = leaks_default.into();
        r
    }

    /// Two meshes of one file name in different folders (which `crosscheck` runs as two) are
    /// two categories labelled by their paths; they were summed into one bar.
    #[test]
    fn meshes_that_share_a_file_name_stay_apart() {
        let mut other = row("bunny.obj", "primary", 5, 0, 0);
        other["path"] = "other/bunny.obj".into();
        let json = serde_json::json!({
            "intersector": "watertight", "seed": 1, "rays": 1000,
            "ray_sets": ["primary"], "shard": {"index": 0, "count": 1},
            "threads": 2, "wall_seconds": 1.0, "rays_per_second": 1.0, "meshes": 3,
            "failed": [],
            "sets": [row("bunny.obj", "primary", 2, 0, 0), other,
                     row("dragon.obj", "primary", 1, 0, 0)]
        });
        let report: Report = serde_json::from_value(json).unwrap();
        let chart = DisagreementChart::new(&report).unwrap();
        assert_eq!(
            chart.meshes,
            ["m/bunny.obj", "other/bunny.obj", "dragon.obj"]
        );
        assert_eq!(
            chart.counts.iter().map(|c| c[0]).collect::<Vec<_>>(),
            [2, 5, 1]
        );
    }

    /// Many meshes (each in two rows, the second pass in reverse order; every 1000th file
    /// name shared by two folders) come out in order of first row, summed per path, and
    /// labelled by path exactly where their file name is shared.
    #[test]
    fn many_meshes_are_summed_per_path_and_labelled_by_a_shared_name() {
        const MESHES: usize = 20_000;
        let folder = |i: usize| if i % 1000 == 1 { "other" } else { "m" };
        let name = |i: usize| format!("n{}.obj", if i % 1000 == 1 { i - 1 } else { i });
        let mut sets = Vec::new();
        for (pass, order) in [
            (0, (0..MESHES).collect::<Vec<_>>()),
            (1, (0..MESHES).rev().collect()),
        ] {
            for i in order {
                let mut r = row(
                    &name(i),
                    if pass == 0 { "primary" } else { "edges" },
                    i + pass,
                    0,
                    0,
                );
                r["path"] = format!("{}/{}", folder(i), name(i)).into();
                sets.push(r);
            }
        }
        let json = serde_json::json!({
            "intersector": "watertight", "seed": 1, "rays": 1000,
            "ray_sets": ["primary", "edges"], "shard": {"index": 0, "count": 1},
            "threads": 2, "wall_seconds": 1.0, "rays_per_second": 1.0, "meshes": MESHES,
            "failed": [], "sets": sets
        });
        let report: Report = serde_json::from_value(json).unwrap();
        let chart = DisagreementChart::new(&report).unwrap();
        let shared = |i: usize| i % 1000 <= 1;
        let want: Vec<String> = (0..MESHES)
            .map(|i| {
                if shared(i) {
                    format!("{}/{}", folder(i), name(i))
                } else {
                    name(i)
                }
            })
            .collect();
        assert_eq!(chart.meshes, want);
        let ties: Vec<usize> = chart.counts.iter().map(|c| c[0]).collect();
        assert_eq!(ties, (0..MESHES).map(|i| 2 * i + 1).collect::<Vec<_>>());
        assert_eq!(chart.rays, vec![2000; MESHES]);
    }

    /// A report whose counts summed do not fit in a `usize` (two rows of one mesh, or two
    /// meshes, each `usize::MAX − 1` genuine mismatches) is refused, not drawn wrapped.
    #[test]
    fn counts_that_overflow_when_summed_are_an_input_error() {
        let huge = usize::MAX - 1;
        let dir = tempfile::tempdir().unwrap();
        for (second_mesh, what) in [("bunny.obj", "one mesh"), ("dragon.obj", "two meshes")] {
            let json = serde_json::json!({
                "intersector": "watertight", "seed": 1, "rays": 1000,
                "ray_sets": ["primary", "edges"], "shard": {"index": 0, "count": 1},
                "threads": 2, "wall_seconds": 1.0, "rays_per_second": 1.0, "meshes": 2,
                "failed": [],
                "sets": [row("bunny.obj", "primary", 0, huge, 0),
                         row(second_mesh, "edges", 0, huge, 0)]
            });
            let report: Report = serde_json::from_value(json).unwrap();
            assert_eq!(DisagreementChart::new(&report), None, "{what}");
            let path = dir.path().join("crosscheck.json");
            std::fs::write(&path, serde_json::to_vec(&report).unwrap()).unwrap();
            let e = DisagreementChart::from_file(&path).unwrap_err().to_string();
            assert!(
                e.contains("crosscheck.json") && e.contains("overflow"),
                "{what}: {e}"
            );
        }
    }

    /// A report of the crosscheck's JSON shape with `sets` and `failed` (path and error).
    fn report_with_failures(
        meshes: usize,
        sets: Vec<serde_json::Value>,
        failed: &[&str],
    ) -> Report {
        let failed: Vec<serde_json::Value> = failed
            .iter()
            .map(|p| serde_json::json!({"path": p, "error": format!("{p}:3: bad face")}))
            .collect();
        let json = serde_json::json!({
            "intersector": "watertight", "seed": 1, "rays": 1000,
            "ray_sets": ["primary"], "shard": {"index": 0, "count": 1},
            "threads": 2, "wall_seconds": 1.0, "rays_per_second": 1.0, "meshes": meshes,
            "failed": failed, "sets": sets
        });
        serde_json::from_value(json).unwrap()
    }

    /// Meshes that failed (at load: no rows) are named under the caption, "N of M meshes
    /// could not be checked", by file name, or by path where a checked mesh shares it; they
    /// were left out without a word.
    #[test]
    fn failed_meshes_are_named_under_the_caption() {
        let report = report_with_failures(
            4,
            vec![
                row("bunny.obj", "primary", 2, 0, 0),
                row("tri.obj", "primary", 0, 0, 0),
            ],
            &["meshes/broken.obj", "other/bunny.obj"],
        );
        let chart = DisagreementChart::new(&report).unwrap();
        assert_eq!(chart.meshes, ["m/bunny.obj", "tri.obj"]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c2.json");
        std::fs::write(&path, serde_json::to_vec(&report).unwrap()).unwrap();
        let chart = DisagreementChart::from_file(&path).unwrap();
        let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
        let want = "2 of 4 meshes could not be checked: broken.obj, other/bunny.obj";
        assert!(texts.iter().any(|t| t == want), "{want} not in {texts:?}");
        assert!(
            texts
                .iter()
                .any(|t| t.starts_with("cross-check against Embree 4")),
            "{texts:?}"
        );
        let png = render(&chart, Format::Png).unwrap();
        assert!(
            png_pixels_of(&png, chart.size(), PALETTE[0]) > 50,
            "tie bars"
        );
        // Without failures, no such line.
        let clean = report_with_failures(1, vec![row("tri.obj", "primary", 1, 0, 0)], &[]);
        let chart = DisagreementChart::new(&clean).unwrap();
        let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
        assert!(
            !texts.iter().any(|t| t.contains("could not be checked")),
            "{texts:?}"
        );
    }

    /// Past [`MAX_FAILED_NAMED`] failures the rest are counted; a run whose every mesh failed
    /// is an input error that says how many failed.
    #[test]
    fn many_or_only_failures_are_counted() {
        let names: Vec<String> = (0..8).map(|i| format!("f{i}.obj")).collect();
        let failed: Vec<&str> = names.iter().map(String::as_str).collect();
        let report = report_with_failures(9, vec![row("tri.obj", "primary", 0, 0, 0)], &failed);
        let chart = DisagreementChart::new(&report).unwrap();
        let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
        let want = "8 of 9 meshes could not be checked: f0.obj, f1.obj, f2.obj, f3.obj, f4.obj, … and 3 more";
        assert!(texts.iter().any(|t| t == want), "{want} not in {texts:?}");
        let report = report_with_failures(1, vec![], &["a/broken.obj"]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.json");
        std::fs::write(&path, serde_json::to_vec(&report).unwrap()).unwrap();
        let e = DisagreementChart::from_file(&path).unwrap_err().to_string();
        assert!(
            e.contains("c.json")
                && e.contains("1 of 1 meshes could not be checked: broken.obj")
                && e.contains("nothing to chart"),
            "{e}"
        );
    }

    #[test]
    fn classes_are_summed_per_mesh_from_the_runs_json() {
        let json = serde_json::json!({
            "intersector": "watertight", "seed": 1, "rays": 1000,
            "ray_sets": ["primary", "edges"], "shard": {"index": 0, "count": 1},
            "threads": 2, "wall_seconds": 1.0, "rays_per_second": 1.0, "meshes": 2,
            "failed": [],
            "sets": [row("bunny.obj", "primary", 3, 0, 0), row("bunny.obj", "edges", 4, 0, 17),
                     row("dragon.obj", "primary", 0, 2, 0), row("dragon.obj", "edges", 1, 0, 0)]
        });
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("crosscheck.json");
        let report: Report = match serde_json::from_value(json.clone()) {
            Ok(r) => r,
            Err(e) => panic!("the test's report does not match `Report`: {e}"),
        };
        std::fs::write(&path, serde_json::to_vec(&report).unwrap()).unwrap();
        let chart = DisagreementChart::from_file(&path).unwrap();
        assert_eq!(chart.meshes, ["bunny.obj", "dragon.obj"]);
        assert_eq!(chart.counts[0], [7, 0, 0, 0, 0, 0, 17, 0]);
        assert_eq!(chart.counts[1], [1, 0, 0, 2, 0, 0, 0, 0]);
        assert_eq!(chart.rays, [2000, 2000]);
        let texts = svg_texts(&render(&chart, Format::Svg).unwrap(), chart.size());
        for want in [
            "bunny.obj",
            "dragon.obj",
            "tie: 8",
            "genuine mismatch: 2",
            "leak Embree default: 17",
            "leak halfray: 0",
        ] {
            assert!(texts.iter().any(|t| t == want), "{want} not in {texts:?}");
        }
        assert!(
            texts
                .iter()
                .any(|t| t.contains("4000 rays; sets primary, edges")),
            "{texts:?}"
        );
        let png = render(&chart, Format::Png).unwrap();
        assert!(
            png_pixels_of(&png, chart.size(), PALETTE[0]) > 50,
            "tie bars"
        );
        assert!(
            png_pixels_of(&png, chart.size(), PALETTE[3]) > 20,
            "genuine bars"
        );
    }
}
