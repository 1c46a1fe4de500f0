//! `halfray crosscheck`: the same rays through halfray's BVH and through Embree 4
//! (`rtcIntersect1` for closest hit, `rtcOccluded1` for any hit), every disagreement judged
//! against an `f64` reference ([`judge`]).
//!
//! Embree runs in both its default and its `RTC_SCENE_FLAG_ROBUST` mode; the robust mode is
//! the one halfray's answers are classified against (the default mode leaks by design, and its
//! leaks are reported separately). Needs the `embree` feature (see the README).

pub mod judge;
pub mod sets;

#[cfg(feature = "embree")]
mod compare;
#[cfg(feature = "embree")]
mod depth;

use crate::error::Result;
use std::path::PathBuf;

/// Arguments of `halfray crosscheck`.
#[derive(clap::Args, Debug, Clone)]
pub struct CrosscheckArgs {
    /// Meshes to cross-check (OBJ).
    #[arg(required = true)]
    pub meshes: Vec<PathBuf>,
    /// Rays per set.
    #[arg(long, default_value_t = 100_000)]
    pub rays: usize,
    /// Seed of the ray sets.
    #[arg(long, default_value_t = 1)]
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
    #[arg(long, default_value_t = 0)]
    pub max_mismatch: usize,
    /// Also render the depth of a camera framing the (first) mesh with both and write
    /// `halfray | embree | difference` side by side to this PNG.
    #[arg(long)]
    pub depth_image: Option<PathBuf>,
    /// Width and height of the depth image.
    #[arg(long, default_value_t = 256)]
    pub depth_size: usize,
}

/// One ray set's results.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SetReport {
    /// Mesh file name.
    pub mesh: String,
    /// Set name.
    pub name: String,
    /// Rays traced (invalid rays for Embree are dropped first).
    pub rays: usize,
    /// Same answer (hit/miss, primitive, `t` within tolerance).
    pub agree: usize,
    /// halfray contradicts the reference beyond its bound.
    pub genuine_mismatches: usize,
    /// Different primitive at the same `t`.
    pub ties: usize,
    /// Disagreement inside the reference's uncertainty (edge within the boundary margin,
    /// grazing `t`).
    pub within_tolerance: usize,
    /// Embree (robust) contradicts the reference, halfray does not.
    pub embree_wrong: usize,
    /// Edge/vertex rays halfray lets through.
    pub leaks_halfray: usize,
    /// Edge/vertex rays Embree robust lets through.
    pub leaks_embree: usize,
    /// Edge/vertex rays Embree default mode lets through.
    pub leaks_embree_default: usize,
    /// Edge/vertex rays crossing transversally (the leak denominator).
    pub leak_rays: usize,
    /// Any-hit disagreements (halfray any-hit vs Embree robust `rtcOccluded1`) on rays whose
    /// closest hits agree or tie (elsewhere a boundary case explains them).
    pub any_hit_disagreements: usize,
    /// Rays whose any-hit answer contradicts the same side's closest-hit answer (either side).
    pub any_vs_closest_inconsistent: usize,
    /// halfray closest-hit throughput, one thread.
    pub mrays_halfray: f64,
    /// Embree robust closest-hit throughput, one thread.
    pub mrays_embree: f64,
    /// Embree default-mode closest-hit throughput, one thread.
    pub mrays_embree_default: f64,
}

/// Runs `halfray crosscheck`.
pub fn run(args: &CrosscheckArgs) -> Result<()> {
    #[cfg(feature = "embree")]
    {
        compare::run(args)
    }
    #[cfg(not(feature = "embree"))]
    {
        let _ = args;
        Err(crate::Error::Other(
            "halfray was built without the `embree` feature: run `bash scripts/setup-embree.sh`, then \
             `EMBREE_DIR=$PWD/.embree cargo run --release -p halfray --features embree -- crosscheck ...`"
                .into(),
        ))
    }
}

/// The per-set table as markdown.
pub fn markdown(rows: &[SetReport]) -> String {
    let mut s = String::from(
        "| mesh | set | rays | agree | ties | within tol | genuine | Embree wrong | leaks halfray | leaks Embree robust | leaks Embree default | any-hit ≠ | Mrays/s halfray | Mrays/s Embree robust | ratio |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let ratio = if r.mrays_embree > 0.0 {
            r.mrays_halfray / r.mrays_embree
        } else {
            0.0
        };
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {}/{} | {}/{} | {}/{} | {} | {:.2} | {:.2} | {:.2} |\n",
            r.mesh,
            r.name,
            r.rays,
            r.agree,
            r.ties,
            r.within_tolerance,
            r.genuine_mismatches,
            r.embree_wrong,
            r.leaks_halfray,
            r.leak_rays,
            r.leaks_embree,
            r.leak_rays,
            r.leaks_embree_default,
            r.leak_rays,
            r.any_hit_disagreements,
            r.mrays_halfray,
            r.mrays_embree,
            ratio
        ));
    }
    s
}
