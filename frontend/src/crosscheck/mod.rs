//! `halfray crosscheck`: the same rays through halfray's BVH and through Embree 4
//! (`rtcIntersect1` for closest hit, `rtcOccluded1` for any hit), every disagreement judged
//! against an `f64` reference ([`judge`]): the `f64` triangle test on every triangle of the
//! mesh ([`judge::Reference`]), without halfray's BVH.
//!
//! Embree runs in both its default and its `RTC_SCENE_FLAG_ROBUST` mode; the robust mode is
//! the one halfray's answers are classified against (the default mode leaks by design, and its
//! leaks are reported separately). Needs the `embree` feature (see the README).

pub mod corpus;
pub mod judge;
pub mod merge;
pub mod report;
pub mod sets;
pub mod shard;

#[cfg(feature = "embree")]
mod compare;
#[cfg(feature = "embree")]
mod depth;

use crate::error::{Error, Result};
pub use report::{SetReport, markdown};
use std::path::PathBuf;

/// Arguments of `halfray crosscheck`.
#[derive(clap::Args, Debug, Clone)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct CrosscheckArgs {
    /// `merge`: combine shards' reports.
    #[command(subcommand)]
    pub command: Option<CrosscheckCommand>,
    /// Meshes to cross-check (OBJ).
    #[arg(required_unless_present = "mesh_list")]
    pub meshes: Vec<PathBuf>,
    /// A file of mesh paths, one per line (blank lines and lines starting with `#` skipped; a
    /// `#` later in a line is part of the path; relative paths are relative to the current
    /// directory); checked after the MESHES arguments.
    #[arg(long)]
    pub mesh_list: Option<PathBuf>,
    /// Rays per set (before sharding).
    #[arg(long, default_value_t = 100_000)]
    pub rays: usize,
    /// Worker threads for the checks, at most 1024 (`workers::MAX_WORKER_THREADS`) [default:
    /// every core]. The throughput figures stay single-thread passes over `--timing-rays`
    /// rays of each set.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=crate::workers::MAX_WORKER_THREADS as i64))]
    pub threads: Option<u16>,
    /// Rays of each set (of this shard) in the single-thread timed passes (at least 1; all of
    /// them when the set has fewer), spread evenly over the set (of its L rays, ray ⌊i·L/N⌋ for
    /// i < N); the same rays for halfray and both Embree modes, which take
    /// turns for five passes each (the fastest pass of each is reported).
    #[arg(long, default_value_t = 100_000)]
    pub timing_rays: usize,
    /// Check only shard K of N (zero-based, 0 <= K < N): the rays whose index in their set is
    /// K mod N. The N shards together are the unsharded run, ray for ray.
    #[arg(long, value_name = "K/N", default_value = "0/1")]
    pub shard: shard::Shard,
    /// Append each mesh's result to this JSON-lines file as soon as it is done (a regular
    /// file: `--resume` reads it back). A read-only or hard-linked log is refused even with
    /// `--force`: the log is appended to, never replaced.
    #[arg(long)]
    pub jsonl: Option<PathBuf>,
    /// Continue the run in `--jsonl`: skip the meshes it already holds (failed ones are tried
    /// again).
    #[arg(long, requires = "jsonl")]
    pub resume: bool,
    /// Seed of the ray sets.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Comma-separated ray sets; all by default.
    #[arg(
        long,
        value_delimiter = ',',
        value_parser = clap::builder::PossibleValuesParser::new(sets::SET_NAMES)
    )]
    pub sets: Vec<String>,
    /// halfray's triangle intersector.
    #[arg(long, value_enum, default_value_t)]
    pub intersector: crate::cli_values::Intersector,
    /// Write the results as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Exit with code 3 when genuine mismatches (summed over meshes and sets) exceed this.
    /// Any halfray leak exits with code 3 too, whatever this is and whatever the intersector.
    #[arg(long, default_value_t = 0)]
    pub max_mismatch: usize,
    /// Also render the depth of a camera framing the (first) mesh with both and write
    /// `halfray | embree | difference` side by side to this PNG (difference: red only halfray
    /// hits, blue only Embree, yellow both at different depths; magenta in every panel: a
    /// camera ray outside Embree's range, traced by neither).
    #[arg(long)]
    pub depth_image: Option<PathBuf>,
    /// Width and height of the depth image.
    #[arg(long, default_value_t = 256)]
    pub depth_size: usize,
    /// Replace an output (`--json`, `--depth-image`) that is read-only or hard-linked
    /// (keeping its mode); not the `--jsonl` log, which is appended to.
    #[arg(long)]
    pub force: bool,
}

/// Subcommands of `halfray crosscheck`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum CrosscheckCommand {
    /// Merge the shards of one run (`--json` reports or `--jsonl` logs) into the unsharded
    /// report: counts add, every disagreement is kept; a missing or repeated shard is an error.
    Merge(MergeArgs),
}

/// Arguments of `halfray crosscheck merge`.
#[derive(clap::Args, Debug, Clone)]
pub struct MergeArgs {
    /// The parts: one report or results log per shard.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Write the merged report as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Exit with code 3 when genuine mismatches exceed this. Any halfray leak exits with code 3
    /// too, whatever this is and whatever the intersector.
    #[arg(long, default_value_t = 0)]
    pub max_mismatch: usize,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
}

/// Runs `halfray crosscheck` (or `crosscheck merge`).
pub fn run(args: &CrosscheckArgs) -> Result<()> {
    if let Some(CrosscheckCommand::Merge(m)) = &args.command {
        return run_merge(m);
    }
    #[cfg(feature = "embree")]
    {
        compare::run(args)
    }
    #[cfg(not(feature = "embree"))]
    {
        let _ = args;
        Err(crate::Error::Unavailable {
            feature: "embree",
            hint: "run `bash scripts/setup-embree.sh`, then \
                   `EMBREE_DIR=$PWD/.embree cargo run --release -p halfray --features embree -- crosscheck ...`",
        })
    }
}

/// `halfray crosscheck merge`.
fn run_merge(args: &MergeArgs) -> Result<()> {
    use crate::outputs::{Named, reserve_outputs};
    let inputs: Vec<Named<'_>> = args.parts.iter().map(|p| Named::new("part", p)).collect();
    let outputs: Vec<Named<'_>> = args.json.iter().map(|p| Named::new("--json", p)).collect();
    let reserved = reserve_outputs(&outputs, &inputs, args.force)?;
    let parts = args
        .parts
        .iter()
        .map(|p| merge::read_part(p))
        .collect::<Result<Vec<_>>>()?;
    let report = merge::merge(&parts)?;
    finish(
        &report,
        reserved.into_iter().next(),
        None,
        args.max_mismatch,
    )
}

/// Writes `report` to `json` together with `also` (the depth image: both or neither,
/// [`crate::outputs::write_together`]), prints its table and totals, and turns it into the
/// exit status: [`Error::Mismatch`] past `max_mismatch` genuine mismatches or on any halfray
/// leak, whatever the intersector and `max_mismatch` (the rows of a failed mesh's checked
/// shards count; the message names the failed meshes too), else an error naming every mesh
/// that could not be checked.
pub fn finish(
    report: &report::Report,
    json: Option<crate::outputs::OutputFile>,
    also: Option<(crate::outputs::OutputFile, Vec<u8>)>,
    max_mismatch: usize,
) -> Result<()> {
    // The outputs first: one that cannot be written fails before anything is printed.
    let mut outputs: Vec<_> = also.into_iter().collect();
    if let Some(out) = json {
        let bytes =
            serde_json::to_vec_pretty(report).map_err(|e| Error::encode("the JSON report", e))?;
        outputs.insert(0, (out, bytes));
    }
    crate::outputs::write_together(outputs)?;
    crate::say!("{}", markdown(&report.sets));
    if let Some(ratio) = report.throughput_ratio() {
        crate::sayln!(
            "\nthroughput ratio halfray / Embree robust (time-weighted over all sets): {ratio:.2}"
        );
    }
    let rays = report.rays();
    // Results logs do not record their threads: a merge of logs alone does not know them.
    let threads = match report.threads {
        0 => String::new(),
        n => format!(", {n} threads"),
    };
    crate::sayln!(
        "{rays} rays on {} meshes ({} failed) in {:.1} s wall, {:.0} rays/s{threads}{}",
        report.meshes,
        report.failed.len(),
        report.wall_seconds,
        report.rays_per_second,
        report
            .merged_shards
            .map_or(String::new(), |n| format!(" (sums over {n} shards)"))
    );
    let outside = report.rays_outside_embree();
    if outside > 0 {
        crate::sayln!(
            "{outside} generated rays outside Embree's range (embree::ray_is_valid) were not traced"
        );
    }
    let (genuine, leaks) = (report.genuine(), report.leaks());
    let failed = (!report.failed.is_empty()).then(|| Error::MeshesFailed {
        failed: report
            .failed
            .iter()
            .map(|f| (f.path.clone(), f.error.clone()))
            .collect(),
        total: report.meshes,
    });
    // A mismatch decides the status; the failures are named with it, not dropped.
    let and_failed = failed.as_ref().map_or(String::new(), |e| format!("; {e}"));
    if genuine > max_mismatch {
        return Err(Error::Mismatch(format!(
            "{genuine} genuine mismatches (allowed: {max_mismatch}){and_failed}"
        )));
    }
    if leaks > 0 {
        return Err(Error::Mismatch(format!(
            "{leaks} halfray leaks through the {} intersector{and_failed}",
            report.config.intersector
        )));
    }
    failed.map_or(Ok(()), Err)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run (or shard `shard`) of `intersector` over one mesh, `a.obj`, whose one row is
    /// `row` (its mesh and path set to `a.obj`).
    fn report_of(intersector: &str, shard: shard::Shard, row: SetReport) -> report::Report {
        let config = report::RunConfig {
            intersector: intersector.into(),
            seed: 1,
            rays: 10,
            ray_sets: vec![row.name.clone()],
            shard,
        };
        let row = SetReport {
            mesh: "a.obj".into(),
            path: "a.obj".into(),
            ..row
        };
        let result = report::MeshResult {
            path: "a.obj".into(),
            config: config.clone(),
            error: None,
            sets: vec![row],
        };
        report::Report::new(config, 1, 1.0, &[result])
    }

    /// A run of `intersector` whose one row has `leaks` halfray leaks and no genuine mismatch.
    fn leaky_report(intersector: &str, leaks: usize) -> report::Report {
        let row = SetReport {
            name: "edges".into(),
            rays: 10,
            agree: 10,
            leak_rays: 10,
            leaks_halfray: leaks,
            ..SetReport::default()
        };
        report_of(intersector, shard::Shard::WHOLE, row)
    }

    /// A mesh none of whose generated rays Embree could take (all beyond its range), or that
    /// generated none in a whole run, was not checked: the run names it among the meshes that
    /// could not be checked and exits 1, not 0. A mesh with one compared ray, or a shard that
    /// was given no ray, is not such a failure.
    #[test]
    fn a_mesh_with_no_compared_ray_fails_the_run() {
        let row = |rays, outside| SetReport {
            name: "primary".into(),
            rays,
            agree: rays,
            rays_outside_embree: outside,
            ..SetReport::default()
        };
        let whole = shard::Shard::WHOLE;
        let fails = |report: &report::Report, want: &str| {
            assert_eq!(report.failed.len(), 1, "{:?}", report.failed);
            let e = finish(report, None, None, 0).unwrap_err();
            assert_eq!(e.exit_code(), crate::error::EXIT_ERROR, "{e}");
            let message = e.to_string();
            assert!(
                message.contains("1 of 1 meshes could not be checked"),
                "{message}"
            );
            assert!(message.contains(want), "{message}");
        };
        fails(
            &report_of("watertight", whole, row(0, 8180)),
            "a.obj: none of its 8180 generated rays",
        );
        fails(
            &report_of("watertight", whole, row(0, 0)),
            "a.obj: its sets generated no ray",
        );
        let second_of_two: shard::Shard = "1/2".parse().unwrap();
        for (shard, rays) in [(whole, 1), (second_of_two, 0)] {
            let report = report_of("watertight", shard, row(rays, 0));
            assert!(report.failed.is_empty(), "{rays}: {:?}", report.failed);
            assert!(finish(&report, None, None, 0).is_ok(), "{rays}");
        }
    }

    /// A halfray leak fails the run (exit 3) through every intersector, the non-watertight
    /// ones included, whatever `--max-mismatch` allows; a run without leaks or mismatches
    /// passes.
    #[test]
    fn a_halfray_leak_is_exit_3_through_every_intersector() {
        for name in [
            "watertight",
            "moller-trumbore",
            "moller-trumbore-noeps",
            "cramer",
        ] {
            assert!(
                halfray_core::triangle::TriangleVariant::from_name(name).is_some(),
                "{name}"
            );
            let e = finish(&leaky_report(name, 3), None, None, usize::MAX).unwrap_err();
            assert_eq!(e.exit_code(), crate::error::EXIT_MISMATCH, "{name}: {e}");
            assert!(
                e.to_string()
                    .contains(&format!("3 halfray leaks through the {name} intersector")),
                "{e}"
            );
            assert!(
                finish(&leaky_report(name, 0), None, None, 0).is_ok(),
                "{name}"
            );
        }
    }
}
