//! The closing table of `bench bvh`: per mesh and ray set, halfray's throughput over Embree
//! robust's and default's; per set, the geometric mean over the meshes and the worst mesh; per
//! mesh, the build times and bytes per triangle.

use super::{BvhReport, positive_ratio};
use crate::text;

/// The geometric mean of `values` (the exponential of their logarithms' mean); `None` for no
/// values. The values are meant to be finite and positive ([`positive_ratio`]): a zero one
/// makes the mean 0, a negative one NaN.
#[must_use]
pub fn geometric_mean(values: impl IntoIterator<Item = f64>) -> Option<f64> {
    let (sum, count) = values
        .into_iter()
        .fold((0.0, 0usize), |(sum, count), v| (sum + v.ln(), count + 1));
    (count > 0).then(|| (sum / count as f64).exp())
}

/// One ray set's ratios over the corpus, `[over Embree default, over Embree robust]`.
#[derive(Debug, Clone, PartialEq)]
pub struct SetSummary {
    /// Set name.
    pub name: String,
    /// Meshes with Embree figures for the set.
    pub meshes: usize,
    /// Geometric mean of the per-mesh ratios.
    pub geomean: [f64; 2],
    /// The smallest ratio and its mesh's label ([`mesh_labels`]).
    pub worst: [(f64, String); 2],
}

/// The file name of a report's mesh (its path when it has none).
#[must_use]
pub fn mesh_name(r: &BvhReport) -> String {
    std::path::Path::new(&r.mesh)
        .file_name()
        .map_or(r.mesh.clone(), |n| n.to_string_lossy().into_owned())
}

/// The label of each report's mesh, in order: its [`mesh_name`], or its path where two meshes
/// of the run share a file name ([`text::unambiguous_names`]).
#[must_use]
pub fn mesh_labels(reports: &[BvhReport]) -> Vec<String> {
    text::unambiguous_names(reports.iter().map(|r| (mesh_name(r), r.mesh.as_str())))
}

/// The set names of `reports`, in order of first appearance.
#[must_use]
pub fn set_names(reports: &[BvhReport]) -> Vec<String> {
    let mut seen = std::collections::HashSet::new();
    reports
        .iter()
        .flat_map(|r| &r.sets)
        .filter(|s| seen.insert(s.name.as_str()))
        .map(|s| s.name.clone())
        .collect()
}

/// Per set (in [`set_names`] order), the geometric mean and the worst of the ratios over the
/// meshes that have Embree figures for it; sets without any are left out.
#[must_use]
pub fn summarize(reports: &[BvhReport]) -> Vec<SetSummary> {
    let labels = mesh_labels(reports);
    set_names(reports)
        .into_iter()
        .filter_map(|name| {
            let ratios: Vec<([f64; 2], String)> = reports
                .iter()
                .zip(&labels)
                .filter_map(|(r, label)| {
                    let s = r.sets.iter().find(|s| s.name == name)?;
                    Some((s.ratios()?, label.clone()))
                })
                .collect();
            let geomean = [0, 1].map(|m| geometric_mean(ratios.iter().map(|(q, _)| q[m])));
            let geomean = [geomean[0]?, geomean[1]?];
            let worst = [0, 1].map(|m| {
                ratios
                    .iter()
                    .map(|(q, mesh)| (q[m], mesh.clone()))
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .unwrap_or((f64::NAN, String::new()))
            });
            Some(SetSummary {
                name,
                meshes: ratios.len(),
                geomean,
                worst,
            })
        })
        .collect()
}

/// The closing Markdown, under a header naming the ratios (halfray's Mrays/s when no set has
/// one): one row per mesh ([`mesh_labels`]) with, per set, `ratio over Embree robust / over
/// Embree default` (halfray's Mrays/s where Embree did not run, `–` for a set of no rays), the
/// build times and bytes per triangle; then the geometric-mean and worst rows (`–`, not bold,
/// for a set with a ratio on no mesh), and the worst meshes by name.
#[must_use]
pub fn markdown(reports: &[BvhReport]) -> String {
    let names = set_names(reports);
    let mut s = String::new();
    let any_ratio = reports
        .iter()
        .flat_map(|r| &r.sets)
        .any(|x| x.ratios().is_some());
    s.push_str(if any_ratio {
        "halfray's single-thread throughput over Embree 4's on the same rays, per set: ×robust / ×default\n\n"
    } else {
        "halfray's single-thread throughput, Mrays/s\n\n"
    });
    s.push_str("| mesh | triangles |");
    for n in &names {
        s.push_str(&format!(" {} |", text::table_cell(n)));
    }
    s.push_str(
        " build ms: halfray / Embree | build ×Embree | all threads: halfray / Embree | B/tri |\n|---|---:|",
    );
    s.push_str(&"---:|".repeat(names.len() + 4));
    s.push('\n');
    let mut build_ratios = Vec::new();
    for (r, label) in reports.iter().zip(mesh_labels(reports)) {
        s.push_str(&format!(
            "| {} | {} |",
            text::table_cell(&label),
            r.triangles
        ));
        for n in &names {
            let cell = match r.sets.iter().find(|x| &x.name == n) {
                None => "".to_string(),
                Some(x) => match x.ratios() {
                    Some([d, rb]) => format!("{rb:.2} / {d:.2}"),
                    None if x.rays == 0 => "–".to_string(),
                    None => format!("{:.2} Mrays/s", x.mrays),
                },
            };
            s.push_str(&format!(" {cell} |"));
        }
        let embree = r.embree_build_ms.map_or("-".into(), |e| format!("{e:.0}"));
        let build_ratio = r
            .embree_build_ms
            .and_then(|e| positive_ratio(r.build_ms, e));
        build_ratios.extend(build_ratio);
        let ratio = build_ratio.map_or("-".into(), |q| format!("{q:.2}"));
        let threads = r
            .embree_build_ms_threads
            .map_or("-".into(), |e| format!("{e:.0}"));
        s.push_str(&format!(
            " {:.0} / {embree} | {ratio} | {:.0} / {threads} | {:.1} |\n",
            r.build_ms, r.build_ms_threads, r.bytes_per_triangle
        ));
    }
    let summary = summarize(reports);
    if !summary.is_empty() {
        // A set with a ratio on no mesh has no summary: `–`.
        let cell = |f: &dyn Fn(&SetSummary) -> String, n: &String| {
            summary
                .iter()
                .find(|x| &x.name == n)
                .map_or("–".to_string(), f)
        };
        let geo_build = geometric_mean(build_ratios.iter().copied())
            .map_or(String::new(), |g| format!("{g:.2}"));
        let max_bytes = reports
            .iter()
            .map(|r| r.bytes_per_triangle)
            .fold(0.0, f64::max);
        s.push_str("| **geometric mean** | |");
        for n in &names {
            let c = cell(
                &|x| format!("**{:.2} / {:.2}**", x.geomean[1], x.geomean[0]),
                n,
            );
            s.push_str(&format!(" {c} |"));
        }
        s.push_str(&format!(" | {geo_build} | | |\n| **worst** | |"));
        for n in &names {
            let c = cell(&|x| format!("{:.2} / {:.2}", x.worst[1].0, x.worst[0].0), n);
            s.push_str(&format!(" {c} |"));
        }
        let worst_build = build_ratios
            .iter()
            .copied()
            .reduce(f64::max)
            .map_or(String::new(), |w| format!("{w:.2}"));
        s.push_str(&format!(" | {worst_build} | | {max_bytes:.1} |\n\n"));
        s.push_str(&packet_lines(reports));
        for x in &summary {
            s.push_str(&format!(
                "{}: {} meshes, geometric mean {:.2}× Embree robust, {:.2}× default; worst {:.2}× robust ({}), {:.2}× default ({})\n",
                text::escaped(&x.name),
                x.meshes,
                x.geomean[1],
                x.geomean[0],
                x.worst[1].0,
                text::escaped(&x.worst[1].1),
                x.worst[0].0,
                text::escaped(&x.worst[0].1)
            ));
        }
    }
    s
}

/// The name of Embree's packet call for a set timed with `query` (`SetFigures::query`):
/// `rtcOccluded` for any hit, `rtcIntersect` for closest hits (then `8` or `16`).
pub(super) fn packet_api(query: &str) -> &'static str {
    if query == crate::raysets::named::Query::Any.name() {
        "rtcOccluded"
    } else {
        "rtcIntersect"
    }
}

/// Per batch set, the geometric mean over the meshes with packet ratios
/// ([`SetFigures::packet_ratios`](super::SetFigures::packet_ratios)) of halfray's batch path
/// over Embree's packet API (`rtcIntersect8`/`16`, or `rtcOccluded8`/`16` for an any-hit set),
/// default and robust; one line each, none for a set without such meshes.
fn packet_lines(reports: &[BvhReport]) -> String {
    let mut s = String::new();
    for name in set_names(reports) {
        let mut api = "";
        let ratios: Vec<[f64; 4]> = reports
            .iter()
            .filter_map(|r| {
                let x = r.sets.iter().find(|x| x.name == name)?;
                api = packet_api(&x.query);
                x.packet_ratios()
            })
            .collect();
        let g = [0, 1, 2, 3].map(|i| geometric_mean(ratios.iter().map(|q| q[i])));
        let [Some(g0), Some(g1), Some(g2), Some(g3)] = g else {
            continue;
        };
        let g = [g0, g1, g2, g3];
        s.push_str(&format!(
            "{}: {} meshes, geometric mean over Embree's packet API: {:.2}× {api}8, {:.2}× {api}16 (default); {:.2}×, {:.2}× (robust)\n",
            text::escaped(&name),
            ratios.len(),
            g[0],
            g[1],
            g[2],
            g[3]
        ));
    }
    s
}

#[cfg(test)]
pub(crate) mod tests {
    use super::super::SetFigures;
    use super::*;

    /// A report on `mesh` (under `dir/`) of 10 triangles with the sets `(name, halfray's
    /// Mrays/s, Embree default's, Embree robust's)`; the other figures fixed.
    pub(crate) fn report(mesh: &str, sets: &[(&str, f64, f64, f64)]) -> BvhReport {
        BvhReport {
            mesh: format!("dir/{mesh}"),
            intersector: "watertight".into(),
            structure: "bvh8".into(),
            simd: "portable".into(),
            triangles: 10,
            build_ms: 2.0,
            build_ms_threads: 1.0,
            build_threads: 2,
            nodes: 1,
            leaves: 1,
            bytes_per_triangle: 50.0,
            max_depth: 1,
            sah_cost: 1.0,
            binary_build_ms: 1.0,
            binary_bytes_per_triangle: 40.0,
            embree_build_ms: Some(4.0),
            embree_robust_build_ms: Some(4.0),
            embree_build_ms_threads: Some(3.0),
            sets: sets
                .iter()
                .map(|&(name, ours, def, rob)| SetFigures {
                    name: name.into(),
                    query: "closest".into(),
                    rays: 1,
                    rays_outside_embree: 0,
                    hit_rate: 1.0,
                    embree_hit_rate: Some(1.0),
                    embree_robust_hit_rate: Some(1.0),
                    mrays: ours,
                    nodes_per_ray: 1.0,
                    triangles_per_ray: 1.0,
                    embree_mrays: Some(def),
                    embree_robust_mrays: Some(rob),
                    embree_packet8_mrays: None,
                    embree_packet16_mrays: None,
                })
                .collect(),
            brute_force_rays: 0,
            mrays_brute_force: 0.0,
            brute_force_mismatches: 0,
        }
    }

    #[test]
    fn geometric_mean_and_worst_per_set() {
        // Ratios over default: a 0.5 then 2.0 (mean 1.0); over robust: a 1.0 then 4.0 (mean 2.0).
        let reports = [
            report(
                "a.obj",
                &[("primary", 1.0, 2.0, 1.0), ("ao", 3.0, 3.0, 3.0)],
            ),
            report("b.obj", &[("primary", 4.0, 2.0, 1.0)]),
        ];
        let s = summarize(&reports);
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].name, "primary");
        assert_eq!(s[0].meshes, 2);
        assert!((s[0].geomean[0] - 1.0).abs() < 1e-12, "{:?}", s[0]);
        assert!((s[0].geomean[1] - 2.0).abs() < 1e-12, "{:?}", s[0]);
        assert_eq!(s[0].worst[0], (0.5, "a.obj".to_string()));
        assert_eq!(s[0].worst[1], (1.0, "a.obj".to_string()));
        assert_eq!((s[1].name.as_str(), s[1].meshes), ("ao", 1));
        let md = markdown(&reports);
        assert!(
            md.contains("| a.obj | 10 | 1.00 / 0.50 | 1.00 / 1.00 | 2 / 4 | 0.50 | 1 / 3 | 50.0 |"),
            "{md}"
        );
        assert!(
            md.contains("| **geometric mean** | | **2.00 / 1.00** |"),
            "{md}"
        );
        assert!(md.contains("primary: 2 meshes, geometric mean 2.00× Embree robust, 1.00× default; worst 1.00× robust (a.obj), 0.50× default (a.obj)"), "{md}");
    }

    /// A mesh whose batch set has no rays (its throughputs 0, its ratios 0 over 0) is left
    /// out of the packet line's geometric mean, which is the other mesh's ratios, not NaN.
    #[test]
    fn a_set_of_no_rays_is_left_out_of_the_packet_means() {
        let with_packets = |mesh: &str, ours: f64, p8: [f64; 2], p16: [f64; 2]| {
            let mut r = report(mesh, &[("shadow+batch", ours, ours, ours)]);
            r.sets[0].query = "any".into();
            r.sets[0].embree_packet8_mrays = Some(p8);
            r.sets[0].embree_packet16_mrays = Some(p16);
            r
        };
        let reports = [
            with_packets("empty.obj", 0.0, [0.0; 2], [0.0; 2]),
            with_packets("b.obj", 4.0, [2.0, 1.0], [8.0, 4.0]),
        ];
        assert_eq!(reports[0].sets[0].packet_ratios(), None);
        let md = markdown(&reports);
        assert!(!md.contains("NaN"), "{md}");
        assert!(
            md.contains("shadow+batch: 1 meshes, geometric mean over Embree's packet API: 2.00× rtcOccluded8, 0.50× rtcOccluded16 (default); 4.00×, 1.00× (robust)"),
            "{md}"
        );
    }

    /// Two meshes of one file name in different folders are told apart by their paths in the
    /// rows and the worst-mesh lines; a name only one mesh has stays a file name.
    #[test]
    fn meshes_sharing_a_file_name_are_labelled_by_path() {
        let reports = [
            report("a/m.obj", &[("primary", 1.0, 2.0, 1.0)]),
            report("b/m.obj", &[("primary", 4.0, 2.0, 1.0)]),
            report("c/n.obj", &[("primary", 4.0, 2.0, 1.0)]),
        ];
        assert_eq!(
            mesh_labels(&reports),
            ["dir/a/m.obj", "dir/b/m.obj", "n.obj"]
        );
        let md = markdown(&reports);
        for row in [
            "| dir/a/m.obj | 10 |",
            "| dir/b/m.obj | 10 |",
            "| n.obj | 10 |",
        ] {
            assert!(md.contains(row), "want `{row}` in: {md}");
        }
        assert!(
            md.contains("worst 1.00× robust (dir/a/m.obj), 0.50× default (dir/a/m.obj)"),
            "{md}"
        );
    }

    /// Without Embree figures the header names halfray's Mrays/s, not ratios; a set of no
    /// rays is `–`, not a throughput of 0.
    #[test]
    fn without_ratios_the_header_says_mrays_and_a_set_of_no_rays_is_a_dash() {
        let mut r = report(
            "a.obj",
            &[("primary", 2.5, 0.0, 0.0), ("shadow", 0.0, 0.0, 0.0)],
        );
        for x in &mut r.sets {
            (x.embree_mrays, x.embree_robust_mrays) = (None, None);
        }
        r.sets[1].rays = 0;
        let md = markdown(&[r]);
        assert!(
            md.starts_with("halfray's single-thread throughput, Mrays/s\n\n"),
            "{md}"
        );
        assert!(!md.contains("×robust"), "{md}");
        assert!(md.contains("| a.obj | 10 | 2.50 Mrays/s | – |"), "{md}");
        let with = markdown(&[report("a.obj", &[("primary", 1.0, 2.0, 1.0)])]);
        assert!(
            with.starts_with("halfray's single-thread throughput over Embree 4's"),
            "{with}"
        );
    }

    /// A set with no rays on every mesh has no ratio: its geometric-mean and worst cells are
    /// `–`, not an empty bold `****`, beside a set that has ratios.
    #[test]
    fn a_set_with_no_ratio_on_any_mesh_is_a_dash_in_the_summary_rows() {
        let mut r = report(
            "a.obj",
            &[("primary", 1.0, 2.0, 1.0), ("shadow", 0.0, 0.0, 0.0)],
        );
        r.sets[1].rays = 0;
        let md = markdown(&[r]);
        assert!(!md.contains("****"), "{md}");
        assert!(
            md.contains("| **geometric mean** | | **1.00 / 0.50** | – | | "),
            "{md}"
        );
        assert!(md.contains("| **worst** | | 1.00 / 0.50 | – | | "), "{md}");
    }

    #[test]
    fn geometric_mean_of_no_values_is_none() {
        assert_eq!(geometric_mean([]), None);
        let g = geometric_mean([2.0, 8.0]).unwrap();
        assert!((g - 4.0).abs() < 1e-12, "{g}");
    }
}
