//! `halfray crosscheck merge PART… --json ALL.json`: the shards of one run combined into the
//! report of the unsharded run.
//!
//! A part is a `--json` report or a `--jsonl` results log of one shard. The parts must belong
//! to one run (same intersector, seed, rays and sets, same shard count `N`), and every mesh must
//! come with each shard `0..N` exactly once: a missing or repeated shard is an error naming the
//! mesh and the files, never a silently partial sum. Counts, timed rays and timed seconds add;
//! every disagreement is kept. A mesh that failed on any shard is failed in the merge, with the
//! sums (counts and disagreements) of the shards on which it was checked: their genuine
//! mismatches and leaks decide the exit status as any others do.

use super::corpus::parse_log;
use super::report::{MeshResult, Report, RunConfig, SetReport};
use super::shard::Shard;
use crate::error::{Error, Location, Result, json_message};
use halfray_core::triangle::TriangleVariant;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// One part file, read.
#[derive(Clone, Debug)]
pub struct Part {
    /// The file.
    pub path: PathBuf,
    /// Its results, one per mesh.
    pub results: Vec<MeshResult>,
    /// The wall-clock seconds it reports (0 for a results log).
    pub wall_seconds: f64,
    /// Its worker threads (0 for a results log).
    pub threads: usize,
}

/// Reads a part: a JSON report (one object with `threads`, as `--json` writes) or a
/// JSON-lines results log (as `--jsonl` writes, several shards' logs concatenated included).
/// A leading UTF-8 byte-order mark is skipped; the file is read bounded
/// ([`crate::input::read_bytes`]).
pub fn read_part(path: &Path) -> Result<Part> {
    let text = crate::input::read_text(path, "a cross-check report or results log")?;
    // A report is one JSON object written over several lines (a log holds one object per
    // line), or on one line with a report's `threads` key: a one-line log is a JSON document
    // too, so parsing alone does not decide (a bad log line must be reported as such).
    // A document that does not parse is a report when its first line is not a JSON value of
    // its own (a report's `{` alone), so that its error names the report's line.
    let is_report = match serde_json::from_str::<serde_json::Value>(&text) {
        Ok(serde_json::Value::Object(m)) => {
            m.contains_key("threads") || text.lines().filter(|l| !l.trim().is_empty()).count() > 1
        }
        Ok(_) => false,
        Err(_) => text
            .lines()
            .find(|l| !l.trim().is_empty())
            .is_some_and(|first| serde_json::from_str::<serde_json::Value>(first).is_err()),
    };
    if !is_report {
        return Ok(Part {
            path: path.to_path_buf(),
            results: parse_log(path, &text)?,
            wall_seconds: 0.0,
            threads: 0,
        });
    }
    match serde_json::from_str::<Report>(&text) {
        Ok(report) => Ok(Part {
            path: path.to_path_buf(),
            results: report.mesh_results(),
            wall_seconds: report.wall_seconds,
            threads: report.threads,
        }),
        Err(e) => Err(Error::input(
            Location::file(path).json_position(&e),
            format!("not a cross-check report: {}", json_message(&e)),
        )),
    }
}

/// Refuses parts whose counts cannot be added: every count ([`SetReport::COUNT_NAMES`])
/// summed over every set of every part, in order, must fit in a `usize` (then every sum the
/// merge makes does too). The error names the part at which the sum overflows, the mesh, the
/// set and the count.
fn check_sums(parts: &[Part]) -> Result<()> {
    let mut totals = [0usize; SetReport::COUNT_NAMES.len()];
    for part in parts {
        for result in &part.results {
            for set in &result.sets {
                for ((total, add), name) in totals
                    .iter_mut()
                    .zip(set.counts())
                    .zip(SetReport::COUNT_NAMES)
                {
                    *total = total.checked_add(add).ok_or_else(|| {
                        Error::input(
                            Location::file(&part.path).field(format!("sets.{name}")),
                            format!(
                                "mesh `{}` set `{}`: {name} = {add} makes the sum over the parts overflow {} bits",
                                crate::text::escaped(&result.path),
                                crate::text::escaped(&set.name),
                                usize::BITS
                            ),
                        )
                    })?;
                }
            }
        }
    }
    Ok(())
}

/// Refuses a part whose results no run can have written (a file edited by hand, or of
/// another version): a checked mesh has exactly the run's sets, in order (a failed one none,
/// or those of a merge's checked shards), and in each set the rays' verdicts (agree, ties,
/// within tolerance, Embree wrong, genuine), every leak count, the any-hit disagreements and
/// the timed rays are each at most its rays (each counts rays, once each); its intersector is
/// one the core has; its timings are finite and not negative.
fn check_consistent(part: &Part) -> Result<()> {
    for result in &part.results {
        let name = &result.config.intersector;
        if TriangleVariant::from_name(name).is_none() {
            return Err(Error::input(
                Location::file(&part.path).field("intersector"),
                format!(
                    "mesh `{}`: `{}` is no intersector of this build",
                    crate::text::escaped(&result.path),
                    crate::text::escaped(name)
                ),
            ));
        }
    }
    for result in part
        .results
        .iter()
        .filter(|r| r.error.is_none() || !r.sets.is_empty())
    {
        let names: Vec<&str> = result.sets.iter().map(|s| s.name.as_str()).collect();
        if names != result.config.ray_sets {
            return Err(Error::input(
                Location::file(&part.path),
                format!(
                    "mesh `{}` has sets {names:?}, its run {:?}",
                    crate::text::escaped(&result.path),
                    result.config.ray_sets
                ),
            ));
        }
        for set in &result.sets {
            for (field, value) in [
                ("secs_halfray", set.secs_halfray),
                ("secs_embree", set.secs_embree),
                ("secs_embree_default", set.secs_embree_default),
                ("mrays_halfray", set.mrays_halfray),
                ("mrays_embree", set.mrays_embree),
                ("mrays_embree_default", set.mrays_embree_default),
            ] {
                if !(value.is_finite() && value >= 0.0) {
                    return Err(Error::input(
                        Location::file(&part.path).field(format!("sets.{field}")),
                        format!(
                            "mesh `{}` set `{}`: {value} is not a time or a throughput a run measures",
                            crate::text::escaped(&result.path),
                            crate::text::escaped(&set.name),
                        ),
                    ));
                }
            }
            let verdicts = [
                set.agree,
                set.ties,
                set.within_tolerance,
                set.embree_wrong,
                set.genuine_mismatches,
            ]
            .iter()
            .try_fold(0usize, |a, &b| a.checked_add(b));
            let each = [
                (
                    "verdicts (agree + ties + within_tolerance + embree_wrong + genuine_mismatches)",
                    verdicts,
                ),
                ("leaks_halfray", Some(set.leaks_halfray)),
                ("leaks_embree", Some(set.leaks_embree)),
                ("leaks_embree_default", Some(set.leaks_embree_default)),
                ("leak_rays", Some(set.leak_rays)),
                ("any_hit_disagreements", Some(set.any_hit_disagreements)),
                ("timed_rays", Some(set.timed_rays)),
            ];
            for (name, count) in each {
                if count.is_none_or(|c| c > set.rays) {
                    return Err(Error::input(
                        Location::file(&part.path),
                        format!(
                            "mesh `{}` set `{}`: {name} = {} is more than its {} rays",
                            crate::text::escaped(&result.path),
                            crate::text::escaped(&set.name),
                            count.map_or("more than 2^64".into(), |c| c.to_string()),
                            set.rays
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Merges the parts (see the module docs).
pub fn merge(parts: &[Part]) -> Result<Report> {
    for part in parts {
        check_consistent(part)?;
    }
    check_sums(parts)?;
    let mut first: Option<(&Path, &RunConfig)> = None;
    // Per mesh path (in order of first appearance): shard index -> (file, result).
    let mut order: Vec<&str> = Vec::new();
    let mut by_mesh: HashMap<&str, HashMap<usize, (&Path, &MeshResult)>> = HashMap::new();
    for part in parts {
        for result in &part.results {
            let config = &result.config;
            match first {
                None => first = Some((&part.path, config)),
                Some((p0, c0)) => {
                    let diff = c0.difference(config).or_else(|| {
                        (c0.shard.count != config.shard.count).then(|| {
                            format!("shard count {} vs {}", c0.shard.count, config.shard.count)
                        })
                    });
                    if let Some(diff) = diff {
                        return Err(Error::Usage(format!(
                            "`{}` and `{}` are not parts of one run ({diff})",
                            crate::text::path(p0),
                            crate::text::path(&part.path)
                        )));
                    }
                }
            }
            let shards = by_mesh.entry(&result.path).or_default();
            if shards.is_empty() {
                order.push(&result.path);
            }
            if let Some((other, _)) = shards.insert(config.shard.index, (&part.path, result)) {
                return Err(Error::Usage(format!(
                    "mesh `{}`: shard {} is in both `{}` and `{}`",
                    crate::text::escaped(&result.path),
                    config.shard,
                    crate::text::path(other),
                    crate::text::path(&part.path)
                )));
            }
        }
    }
    let Some((_, config)) = first else {
        return Err(Error::Usage("the parts hold no results".into()));
    };
    let n = config.shard.count;
    let mut merged = Vec::with_capacity(order.len());
    for path in order {
        let shards = &by_mesh[path];
        let mut rows: Vec<SetReport> = Vec::new();
        let mut errors = Vec::new();
        for k in 0..n {
            let Some((_, result)) = shards.get(&k) else {
                return Err(Error::Usage(format!(
                    "mesh `{}`: shard {k}/{n} is missing from the parts",
                    crate::text::escaped(path)
                )));
            };
            // A failed shard has no rows, unless it is a merge's failed mesh (its checked
            // shards' sums): those are kept too.
            if let Some(e) = &result.error {
                errors.push(format!("shard {k}/{n}: {e}"));
            }
            if result.sets.is_empty() {
                continue;
            }
            if rows.is_empty() {
                rows = result.sets.clone();
                continue;
            }
            let names =
                |sets: &[SetReport]| sets.iter().map(|s| s.name.clone()).collect::<Vec<_>>();
            if names(&rows) != names(&result.sets) {
                return Err(Error::Usage(format!(
                    "mesh `{}`: shard {k}/{n} has sets {:?}, the shards before it {:?}",
                    crate::text::escaped(path),
                    names(&result.sets),
                    names(&rows)
                )));
            }
            for (sum, row) in rows.iter_mut().zip(&result.sets) {
                sum.absorb(row).map_err(|count| {
                    Error::internal(format!("{count} overflowed after check_sums"), None)
                })?;
            }
        }
        merged.push(MeshResult {
            path: path.to_string(),
            config: RunConfig {
                shard: Shard::WHOLE,
                ..config.clone()
            },
            error: (!errors.is_empty()).then(|| errors.join("; ")),
            // A failed mesh keeps the sums of its checked shards: a mismatch or leak in one
            // of them still counts in the verdict.
            sets: rows,
        });
    }
    let wall: f64 = parts.iter().fold(0.0, |a, p| a + p.wall_seconds);
    let threads = parts.iter().map(|p| p.threads).max().unwrap_or(0);
    let mut report = Report::new(
        RunConfig {
            shard: Shard::WHOLE,
            ..config.clone()
        },
        threads,
        wall,
        &merged,
    );
    report.merged_shards = Some(n);
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crosscheck::judge::Answer;
    use crate::crosscheck::report::{DetailKind, Disagreement};

    fn config(shard: Shard) -> RunConfig {
        RunConfig {
            intersector: "watertight".into(),
            seed: 7,
            rays: 9,
            ray_sets: vec!["primary".into(), "edges".into()],
            shard,
        }
    }

    fn detail(index: usize) -> Disagreement {
        Disagreement {
            index,
            kind: DetailKind::Genuine,
            origin: [0.0, 0.0, 1.0],
            direction: [0.0, 0.0, -1.0],
            t_min: 0.0,
            t_max: None,
            halfray: None,
            embree: Some(Answer {
                prim: 3,
                t: 1.0,
                u: 0.25,
                v: 0.5,
            }),
        }
    }

    /// Shard `k` of `n` of a made-up run where ray `i` of a set is genuine when `i % 4 == 1`,
    /// agrees otherwise, and took `i` microseconds on halfray's side.
    fn shard_result(path: &str, k: usize, n: usize) -> MeshResult {
        let shard = Shard::new(k, n).unwrap();
        let sets = ["primary", "edges"]
            .iter()
            .map(|&name| {
                let mut row = SetReport {
                    mesh: path.into(),
                    path: path.into(),
                    name: name.into(),
                    ..SetReport::default()
                };
                for i in (0..9).filter(|&i| shard.contains(i)) {
                    row.rays += 1;
                    row.timed_rays += 1;
                    row.secs_halfray += i as f64 * 1e-6;
                    row.secs_embree += 1e-6;
                    if i % 4 == 1 {
                        row.genuine_mismatches += 1;
                        row.disagreements.push(detail(i));
                    } else {
                        row.agree += 1;
                    }
                }
                row.update_throughput();
                row
            })
            .collect();
        MeshResult {
            path: path.into(),
            config: config(shard),
            error: None,
            sets,
        }
    }

    fn part(name: &str, results: Vec<MeshResult>) -> Part {
        Part {
            path: PathBuf::from(name),
            results,
            wall_seconds: 1.0,
            threads: 2,
        }
    }

    /// The merge of `N` shards equals the unsharded run's figures, written out from
    /// `shard_result`'s definition (not from a merge): per set 9 rays, genuine at rays 1 and 5
    /// (`i % 4 == 1`), the other 7 agreeing, halfray's seconds `(0 + 1 + … + 8)·10⁻⁶ = 36 µs`,
    /// Embree's 9 µs, so 9 rays / 36 µs = 0.25 Mrays/s and 9 / 9 µs = 1 Mrays/s.
    #[test]
    fn merged_shards_equal_the_unsharded_counts() {
        for n in [1, 2, 3, 7] {
            // Parts given in reverse order: the merge does not depend on it.
            let parts: Vec<Part> = (0..n)
                .rev()
                .map(|k| part(&format!("p{k}"), vec![shard_result("a.obj", k, n)]))
                .collect();
            let merged = merge(&parts).unwrap();
            assert_eq!(merged.merged_shards, Some(n));
            assert_eq!(merged.config, config(Shard::WHOLE));
            assert_eq!(merged.meshes, 1);
            let names: Vec<&str> = merged.sets.iter().map(|s| s.name.as_str()).collect();
            assert_eq!(names, ["primary", "edges"], "N = {n}");
            for m in &merged.sets {
                assert_eq!(m.path, "a.obj");
                assert_eq!(
                    (m.rays, m.timed_rays, m.agree, m.genuine_mismatches),
                    (9, 9, 7, 2),
                    "N = {n}"
                );
                assert_eq!(m.disagreements, vec![detail(1), detail(5)], "N = {n}");
                assert!((m.secs_halfray - 36e-6).abs() < 1e-15, "N = {n}");
                assert!((m.secs_embree - 9e-6).abs() < 1e-15, "N = {n}");
                assert!((m.mrays_halfray - 0.25).abs() < 1e-9, "N = {n}");
                assert!((m.mrays_embree - 1.0).abs() < 1e-9, "N = {n}");
            }
            assert_eq!(merged.genuine(), 2 * 2, "rays 1 and 5 of both sets");
            // Time-weighted over both sets: (9 + 9) µs of Embree's over (36 + 36) of halfray's.
            let ratio = merged.throughput_ratio().unwrap();
            assert!((ratio - 0.25).abs() < 1e-12, "N = {n}: {ratio}");
            // Wall seconds add (1 s per part); threads: the largest.
            assert_eq!((merged.wall_seconds, merged.threads), (n as f64, 2));
        }
        // No timed ray, no ratio.
        let empty = Report::new(config(Shard::WHOLE), 1, 0.0, &[]);
        assert_eq!(empty.throughput_ratio(), None);
    }

    /// Parts no run can have written are refused, naming the part, mesh and set (they were
    /// merged, exit 0: a set's count above its rays, a checked mesh without its sets).
    #[test]
    fn counts_no_run_can_write_are_refused() {
        type Edit = fn(&mut MeshResult);
        let edits: [(Edit, &str); 8] = [
            (|r| r.sets[0].agree = 999, "verdicts (agree"),
            (|r| r.sets[0].secs_halfray = -1.0, "sets.secs_halfray"),
            (|r| r.sets[1].mrays_embree = f64::NAN, "sets.mrays_embree"),
            (
                |r| r.sets[1].mrays_embree_default = f64::INFINITY,
                "sets.mrays_embree_default",
            ),
            (
                |r| r.config.intersector = "moller".into(),
                "`moller` is no intersector",
            ),
            (
                |r| r.sets[1].genuine_mismatches = usize::MAX,
                "more than 2^64",
            ),
            (
                |r| r.sets[0].leaks_halfray = r.sets[0].rays + 1,
                "leaks_halfray",
            ),
            (
                |r| r.sets.clear(),
                "has sets [], its run [\"primary\", \"edges\"]",
            ),
        ];
        for (edit, want) in edits {
            let mut result = shard_result("a.obj", 0, 1);
            edit(&mut result);
            let e = merge(&[part("p.json", vec![result])])
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("p.json:") && e.contains("mesh `a.obj`") && e.contains(want),
                "{e}"
            );
        }
        // The same edits on a failed mesh's line are its error's business, not the counts'.
        let mut failed = shard_result("a.obj", 0, 1);
        failed.error = Some("a.obj:1: bad".into());
        failed.sets.clear();
        assert!(merge(&[part("p.json", vec![failed])]).is_ok());
    }

    /// A part's file name and a mesh path from a part are printed escaped in messages: a
    /// control character in them cannot reach the terminal.
    #[test]
    fn paths_in_messages_are_escaped() {
        let mut other = shard_result("a\u{1b}[2J.obj", 1, 2);
        other.config.seed = 8;
        let e = merge(&[
            part("p\u{1b}[31m0", vec![shard_result("a\u{1b}[2J.obj", 0, 2)]),
            part("p\u{7}1", vec![other]),
        ])
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("`p\\u{1b}[31m0` and `p\\u{7}1`") && !e.contains('\u{1b}'),
            "{e}"
        );
        let e = merge(&[part("p\u{1b}0", vec![shard_result("a\u{1b}.obj", 0, 2)])])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("mesh `a\\u{1b}.obj`: shard 1/2 is missing") && !e.contains('\u{1b}'),
            "{e}"
        );
        let e = merge(&[
            part("p\u{1b}0", vec![shard_result("a.obj", 0, 2)]),
            part("q\u{1b}0", vec![shard_result("a.obj", 0, 2)]),
        ])
        .unwrap_err()
        .to_string();
        assert!(e.contains("`p\\u{1b}0` and `q\\u{1b}0`"), "{e}");
    }

    #[test]
    fn a_missing_or_repeated_shard_is_refused() {
        let e = merge(&[
            part("p0", vec![shard_result("a.obj", 0, 3)]),
            part("p2", vec![shard_result("a.obj", 2, 3)]),
        ])
        .unwrap_err();
        assert!(e.to_string().contains("shard 1/3 is missing"), "{e}");
        let e = merge(&[
            part("p0", vec![shard_result("a.obj", 0, 2)]),
            part("q0", vec![shard_result("a.obj", 0, 2)]),
        ])
        .unwrap_err();
        assert!(e.to_string().contains("`p0` and `q0`"), "{e}");
        let mut other = shard_result("a.obj", 1, 2);
        other.config.seed = 8;
        let e = merge(&[
            part("p0", vec![shard_result("a.obj", 0, 2)]),
            part("p1", vec![other]),
        ])
        .unwrap_err();
        assert!(e.to_string().contains("seed 7 vs 8"), "{e}");
    }

    #[test]
    fn a_mesh_failed_on_one_shard_is_failed_in_the_merge() {
        let mut bad = shard_result("b.obj", 1, 2);
        bad.error = Some("b.obj:4:7: field `y`: `nan` is not finite".into());
        bad.sets.clear();
        let merged = merge(&[
            part(
                "p0",
                vec![shard_result("a.obj", 0, 2), shard_result("b.obj", 0, 2)],
            ),
            part("p1", vec![shard_result("a.obj", 1, 2), bad]),
        ])
        .unwrap();
        assert_eq!(merged.meshes, 2);
        assert_eq!(merged.failed.len(), 1);
        assert_eq!(merged.failed[0].path, "b.obj");
        assert!(merged.failed[0].error.contains("shard 1/2: b.obj:4:7"));
        // b.obj's rows are those of its checked shard, 0.
        let b: Vec<&SetReport> = merged.sets.iter().filter(|s| s.path == "b.obj").collect();
        assert_eq!(b.len(), 2);
        for (row, shard0) in b.iter().zip(&shard_result("b.obj", 0, 2).sets) {
            assert_eq!(*row, shard0);
        }
        // Every mesh failed: no rays, a throughput of +0 (an empty `f64` sum is −0, which
        // printed as "-0 rays/s").
        let mut only = shard_result("b.obj", 0, 1);
        only.error = Some("b.obj: bad".into());
        only.sets.clear();
        let merged = merge(&[part("p", vec![only])]).unwrap();
        assert!(merged.rays_per_second == 0.0 && merged.rays_per_second.is_sign_positive());
        assert_eq!(format!("{:.0}", merged.rays_per_second), "0");
    }

    #[test]
    fn reports_and_logs_read_back_as_parts() {
        let dir = tempfile::tempdir().unwrap();
        let result = shard_result("a.obj", 0, 1);
        let report = Report::new(config(Shard::WHOLE), 2, 3.0, std::slice::from_ref(&result));
        let json = dir.path().join("r.json");
        std::fs::write(&json, serde_json::to_vec_pretty(&report).unwrap()).unwrap();
        let part = read_part(&json).unwrap();
        assert_eq!(part.results, vec![result.clone()]);
        assert_eq!((part.wall_seconds, part.threads), (3.0, 2));
        let log = dir.path().join("r.jsonl");
        std::fs::write(&log, serde_json::to_string(&result).unwrap() + "\n").unwrap();
        assert_eq!(read_part(&log).unwrap().results, vec![result]);
        std::fs::write(&json, "{\"sets\": 3}").unwrap();
        let e = read_part(&json).unwrap_err().to_string();
        assert!(
            e.contains("r.json:1:") && e.contains("not a cross-check result line"),
            "{e}"
        );
        std::fs::write(&json, "{\n\"sets\": 3\n}").unwrap();
        let e = read_part(&json).unwrap_err().to_string();
        assert!(
            e.contains("r.json:2:") && e.contains("not a cross-check report"),
            "{e}"
        );
        // A report cut off, or with a bad value far down: its own line, read as a report.
        let whole = serde_json::to_string_pretty(
            &merge(&[super::tests::part("a", vec![shard_result("a.obj", 0, 1)])]).unwrap(),
        )
        .unwrap();
        let lines: Vec<&str> = whole.lines().collect();
        assert!(lines.len() > 20, "{}", lines.len());
        std::fs::write(&json, lines[..20].join("\n")).unwrap();
        let e = read_part(&json).unwrap_err().to_string();
        assert!(
            e.contains("r.json:20:") && e.contains("not a cross-check report"),
            "{e}"
        );
        let bad = whole.replacen(": 0,", ": -1x,", 1);
        let at = 1 + bad.lines().position(|l| l.contains("-1x")).unwrap();
        std::fs::write(&json, &bad).unwrap();
        let e = read_part(&json).unwrap_err().to_string();
        assert!(
            e.contains(&format!("r.json:{at}:")) && e.contains("not a cross-check report"),
            "{e}"
        );
        // A BOM is skipped; shard logs concatenated keep every shard.
        let mut both = b"\xEF\xBB\xBF".to_vec();
        for k in 0..2 {
            let line = serde_json::to_string(&shard_result("a.obj", k, 2)).unwrap();
            both.extend(line.bytes().chain([b'\n']));
        }
        std::fs::write(&log, both).unwrap();
        let merged = merge(&[read_part(&log).unwrap()]).unwrap();
        assert_eq!(merged.merged_shards, Some(2));
    }

    /// Rays dropped as outside Embree's range add over the shards like every count (shard `k`
    /// of 3 drops `k + 1` in each set: 1 + 2 + 3 = 6); a part written before they were counted
    /// (no `rays_outside_embree` key) reads as 0 dropped.
    #[test]
    fn rays_outside_embree_add_over_the_shards() {
        let parts: Vec<Part> = (0..3)
            .map(|k| {
                let mut r = shard_result("a.obj", k, 3);
                for row in &mut r.sets {
                    row.rays_outside_embree = k + 1;
                }
                part(&format!("p{k}"), vec![r])
            })
            .collect();
        let merged = merge(&parts).unwrap();
        let dropped: Vec<usize> = merged.sets.iter().map(|s| s.rays_outside_embree).collect();
        assert_eq!(dropped, [6, 6]);
        assert_eq!(merged.rays_outside_embree(), 12);
        let mut old = serde_json::to_value(shard_result("a.obj", 0, 1)).unwrap();
        for row in old["sets"].as_array_mut().unwrap() {
            row.as_object_mut().unwrap().remove("rays_outside_embree");
        }
        let old: MeshResult = serde_json::from_value(old).unwrap();
        assert!(old.sets.iter().all(|s| s.rays_outside_embree == 0));
    }

    /// Shard logs of a mesh checked on shard 1 (rays 1 and 5 genuine mismatches in both sets,
    /// or instead one leak through the watertight intersector) and failed on shard 0: the
    /// merge keeps shard 1's counts and disagreements beside the failure and exits 3 (a
    /// mismatch), naming the failure too; a merge of that merged report keeps them again.
    #[test]
    fn a_mismatch_on_a_checked_shard_survives_a_failed_one() {
        let dir = tempfile::tempdir().unwrap();
        let leaky = |r: &mut MeshResult| {
            for row in &mut r.sets {
                row.agree += row.genuine_mismatches;
                row.genuine_mismatches = 0;
                row.disagreements.clear();
            }
            r.sets[0].leaks_halfray = 1;
            r.sets[0].leak_rays = 1;
        };
        for (edit, want) in [
            (
                None,
                "4 genuine mismatches (allowed: 0); 1 of 1 meshes could not be checked:",
            ),
            (
                Some(leaky),
                "1 halfray leaks through the watertight intersector; 1 of 1 meshes",
            ),
        ] {
            let mut checked = shard_result("a.obj", 1, 2);
            if let Some(edit) = edit {
                edit(&mut checked);
            }
            let mut failed = shard_result("a.obj", 0, 2);
            failed.error = Some("a.obj:3: field `y`: `nan` is not finite".into());
            failed.sets.clear();
            let logs = [("s1.jsonl", &checked), ("s0.jsonl", &failed)].map(|(name, r)| {
                let path = dir.path().join(name);
                std::fs::write(&path, serde_json::to_string(r).unwrap() + "\n").unwrap();
                read_part(&path).unwrap()
            });
            let merged = merge(&logs).unwrap();
            assert_eq!(merged.failed.len(), 1);
            assert!(merged.failed[0].error.starts_with("shard 0/2: a.obj:3:"));
            assert_eq!(merged.sets, checked.sets);
            // Written and merged again (a merged report is a part of one shard).
            let json = dir.path().join("merged.json");
            std::fs::write(&json, serde_json::to_vec_pretty(&merged).unwrap()).unwrap();
            let again = merge(&[read_part(&json).unwrap()]).unwrap();
            assert_eq!(
                (again.sets.clone(), again.failed.len()),
                (checked.sets.clone(), 1)
            );
            for report in [&merged, &again] {
                let e = crate::crosscheck::finish(report, None, None, 0).unwrap_err();
                assert_eq!(e.exit_code(), crate::error::EXIT_MISMATCH, "{e}");
                assert!(e.to_string().contains(want), "{e}");
            }
        }
    }
}
