//! What a cross-check run reports: per mesh and set counts ([`SetReport`]), the detail of every
//! disagreement that matters ([`Disagreement`]), one mesh's result as a JSON line
//! ([`MeshResult`]) and the whole run ([`Report`]).
//!
//! Counts add up across shards ([`SetReport::absorb`]); throughput is kept as single-thread
//! seconds on a counted number of timed rays, so merged throughput is total timed rays over
//! total seconds on each side, still single-thread and on the same rays for every side.

use super::judge::Answer;
use super::shard::Shard;
use halfray_core::Ray;
use serde::{Deserialize, Serialize};

/// What fixes a run's rays and answers. The parts of one run (shards, resumed runs) agree on
/// all of it except the shard.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunConfig {
    /// halfray's triangle intersector (`TriangleVariant::name`).
    pub intersector: String,
    /// Seed of the ray sets.
    pub seed: u64,
    /// Rays per set before sharding.
    pub rays: usize,
    /// The ray sets, in report order.
    pub ray_sets: Vec<String>,
    /// Which shard of the rays this is.
    pub shard: Shard,
}

impl RunConfig {
    /// `None` when `other` belongs to the same run (same everything but the shard), else a
    /// description of the first difference.
    pub fn difference(&self, other: &Self) -> Option<String> {
        if self.intersector != other.intersector {
            return Some(format!(
                "intersector {} vs {}",
                self.intersector, other.intersector
            ));
        }
        if self.seed != other.seed {
            return Some(format!("seed {} vs {}", self.seed, other.seed));
        }
        if self.rays != other.rays {
            return Some(format!("rays {} vs {}", self.rays, other.rays));
        }
        if self.ray_sets != other.ray_sets {
            return Some(format!(
                "ray sets {} vs {}",
                self.ray_sets.join(","),
                other.ray_sets.join(",")
            ));
        }
        None
    }
}

/// Kind of a recorded disagreement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DetailKind {
    /// halfray contradicts the `f64` reference beyond its bound.
    Genuine,
    /// Embree robust contradicts the reference, halfray does not.
    EmbreeWrong,
    /// An edge/vertex ray halfray lets through.
    LeakHalfray,
    /// Any-hit answers differ where the closest hits agree or tie.
    AnyHit,
    /// One side's any-hit answer contradicts its own closest-hit answer.
    AnyVsClosest,
}

/// One ray on which the two sides disagree in a way that matters: everything needed to replay
/// it. Ties, differences within tolerance and Embree's own leaks (documented behaviour of the
/// library) are counted, not recorded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Disagreement {
    /// The ray's index in its generated set (the same in every shard).
    pub index: usize,
    /// What the disagreement is.
    pub kind: DetailKind,
    /// Ray origin.
    pub origin: [f32; 3],
    /// Ray direction (not normalised).
    pub direction: [f32; 3],
    /// Start of the ray interval.
    pub t_min: f32,
    /// End of the ray interval; `null` for an unbounded ray.
    pub t_max: Option<f32>,
    /// halfray's closest hit.
    pub halfray: Option<Answer>,
    /// Embree robust's closest hit.
    pub embree: Option<Answer>,
}

impl Disagreement {
    /// A record of `ray` (index `index` in its set) with both sides' answers.
    pub fn new(
        index: usize,
        kind: DetailKind,
        ray: &Ray,
        halfray: Option<Answer>,
        embree: Option<Answer>,
    ) -> Self {
        Self {
            index,
            kind,
            origin: ray.origin.to_array(),
            direction: ray.direction.to_array(),
            t_min: ray.t_min,
            t_max: ray.t_max.is_finite().then_some(ray.t_max),
            halfray,
            embree,
        }
    }
}

/// One ray set's results on one mesh (one shard of it, or all shards merged).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SetReport {
    /// Mesh file name.
    pub mesh: String,
    /// Mesh path as given on the command line or in the mesh list.
    pub path: String,
    /// Set name.
    pub name: String,
    /// Rays traced: the set's generated rays (of this shard) inside Embree's defined range
    /// (`embree::ray_is_valid`).
    pub rays: usize,
    /// The set's generated rays (of this shard) outside Embree's defined range
    /// (`embree::ray_is_valid`: a coordinate beyond `FLT_LARGE`, …): not traced by either side,
    /// not in `rays`. Absent (0) in reports written before it was counted.
    #[serde(default)]
    pub rays_outside_embree: usize,
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
    /// Rays in the single-thread timed passes (spread evenly over the set, `--timing-rays` of
    /// them or all, the same for every side).
    pub timed_rays: usize,
    /// Seconds of halfray's timed closest-hit pass (the timed rays as one batch,
    /// `RayQuery::closest_hits`), one thread.
    pub secs_halfray: f64,
    /// Seconds of Embree robust's timed closest-hit pass, one thread.
    pub secs_embree: f64,
    /// Seconds of Embree default mode's timed closest-hit pass, one thread.
    pub secs_embree_default: f64,
    /// halfray closest-hit throughput, one thread, Mrays/s (`timed_rays / secs_halfray`).
    pub mrays_halfray: f64,
    /// Embree robust closest-hit throughput, one thread, Mrays/s.
    pub mrays_embree: f64,
    /// Embree default-mode closest-hit throughput, one thread, Mrays/s.
    pub mrays_embree_default: f64,
    /// Every recorded disagreement, by ray index.
    pub disagreements: Vec<Disagreement>,
}

impl SetReport {
    /// Recomputes the throughput fields from the timed rays and seconds.
    pub fn update_throughput(&mut self) {
        let rays = self.timed_rays as u64;
        let mrays = |secs| crate::timing::mrays_per_second(rays, secs);
        self.mrays_halfray = mrays(self.secs_halfray);
        self.mrays_embree = mrays(self.secs_embree);
        self.mrays_embree_default = mrays(self.secs_embree_default);
    }

    /// Names of the counts, in the order of [`SetReport::counts`].
    pub const COUNT_NAMES: [&'static str; 14] = [
        "rays",
        "rays_outside_embree",
        "agree",
        "genuine_mismatches",
        "ties",
        "within_tolerance",
        "embree_wrong",
        "leaks_halfray",
        "leaks_embree",
        "leaks_embree_default",
        "leak_rays",
        "any_hit_disagreements",
        "any_vs_closest_inconsistent",
        "timed_rays",
    ];

    /// The counts, in the order of [`SetReport::COUNT_NAMES`].
    pub fn counts(&self) -> [usize; 14] {
        [
            self.rays,
            self.rays_outside_embree,
            self.agree,
            self.genuine_mismatches,
            self.ties,
            self.within_tolerance,
            self.embree_wrong,
            self.leaks_halfray,
            self.leaks_embree,
            self.leaks_embree_default,
            self.leak_rays,
            self.any_hit_disagreements,
            self.any_vs_closest_inconsistent,
            self.timed_rays,
        ]
    }

    fn counts_mut(&mut self) -> [&mut usize; 14] {
        [
            &mut self.rays,
            &mut self.rays_outside_embree,
            &mut self.agree,
            &mut self.genuine_mismatches,
            &mut self.ties,
            &mut self.within_tolerance,
            &mut self.embree_wrong,
            &mut self.leaks_halfray,
            &mut self.leaks_embree,
            &mut self.leaks_embree_default,
            &mut self.leak_rays,
            &mut self.any_hit_disagreements,
            &mut self.any_vs_closest_inconsistent,
            &mut self.timed_rays,
        ]
    }

    /// Adds another shard's results of the same mesh and set: counts, timed rays and seconds
    /// add; disagreements are kept, ordered by ray index. A count whose sum does not fit in a
    /// `usize` is an error naming it (`genuine_mismatches`), and `self` is then unchanged.
    pub fn absorb(&mut self, other: &SetReport) -> Result<(), &'static str> {
        let add = other.counts();
        let mut sums = self.counts();
        for ((sum, add), name) in sums.iter_mut().zip(add).zip(Self::COUNT_NAMES) {
            *sum = sum.checked_add(add).ok_or(name)?;
        }
        for (count, sum) in self.counts_mut().into_iter().zip(sums) {
            *count = sum;
        }
        self.secs_halfray += other.secs_halfray;
        self.secs_embree += other.secs_embree;
        self.secs_embree_default += other.secs_embree_default;
        self.disagreements
            .extend(other.disagreements.iter().cloned());
        self.disagreements.sort_by_key(|d| (d.index, d.kind));
        self.update_throughput();
        Ok(())
    }
}

/// One mesh's result: a JSON line of `--jsonl`, and the unit [`super::merge`] combines.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshResult {
    /// Mesh path as given.
    pub path: String,
    /// The run it belongs to.
    #[serde(flatten)]
    pub config: RunConfig,
    /// Why the mesh could not be checked (unreadable, non-finite, …). Then `sets` is empty,
    /// except in a merge of shards of which some were checked: it holds their sums.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// One row per ray set.
    #[serde(default)]
    pub sets: Vec<SetReport>,
}

/// A mesh that could not be checked.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Failure {
    /// Mesh path as given.
    pub path: String,
    /// The error, naming the file (and line and field where known).
    pub error: String,
}

/// The failure of a mesh on which no ray was compared: every generated one outside Embree's
/// range ([`SetReport::rays_outside_embree`], coordinates beyond `FLT_LARGE`), or, in a run
/// that is not one shard of several, none generated (the aimed sets of a mesh with no
/// interior edge or vertex), so the mesh was not checked. `None` when a ray was compared, or
/// when a shard of more shards than a set has rays was given none.
fn nothing_compared(r: &MeshResult) -> Option<String> {
    let sum = |count: fn(&SetReport) -> usize| {
        r.sets.iter().map(count).fold(0usize, usize::saturating_add)
    };
    let outside = sum(|s| s.rays_outside_embree);
    if sum(|s| s.rays) > 0 {
        return None;
    }
    if outside > 0 {
        return Some(format!(
            "none of its {outside} generated rays is within Embree's range (embree::ray_is_valid): nothing was compared"
        ));
    }
    (r.config.shard == super::shard::Shard::WHOLE)
        .then(|| "its sets generated no ray: nothing was compared".to_string())
}

/// The whole run (`--json`), or the merge of its shards.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// The run; a merged report has shard `0/1` and `merged_shards` set.
    #[serde(flatten)]
    pub config: RunConfig,
    /// Number of shards merged into this report (absent for a single run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merged_shards: Option<usize>,
    /// Worker threads of the run (the largest among merged parts).
    pub threads: usize,
    /// Wall-clock seconds of the whole run (summed over merged parts).
    pub wall_seconds: f64,
    /// Rays checked per wall-clock second (every ray of every set, all threads) by the run's
    /// process: a `--resume`d run counts only the meshes it checked itself, not those its log
    /// already held.
    pub rays_per_second: f64,
    /// Meshes checked or attempted.
    pub meshes: usize,
    /// Meshes that could not be checked.
    pub failed: Vec<Failure>,
    /// One row per checked mesh and set. A mesh in `failed` has none, except in a merge
    /// where some of its shards were checked: its rows hold their sums.
    pub sets: Vec<SetReport>,
}

impl Report {
    /// The report of `results` (in order) under `config`.
    pub fn new(
        config: RunConfig,
        threads: usize,
        wall_seconds: f64,
        results: &[MeshResult],
    ) -> Self {
        let mut failed = Vec::new();
        let mut sets = Vec::new();
        for r in results {
            if let Some(error) = r.error.clone().or_else(|| nothing_compared(r)) {
                failed.push(Failure {
                    path: r.path.clone(),
                    error,
                });
            }
            sets.extend(r.sets.iter().cloned());
        }
        // Throughput only: an `f64` sum cannot overflow. Folded from +0 (an empty `sum()` is
        // −0, printed "-0 rays/s" when every mesh failed).
        let rays: f64 = sets.iter().fold(0.0, |a, s| a + s.rays as f64);
        Self {
            config,
            merged_shards: None,
            threads,
            wall_seconds,
            rays_per_second: if wall_seconds > 0.0 {
                rays / wall_seconds
            } else {
                0.0
            },
            meshes: results.len(),
            failed,
            sets,
        }
    }

    /// Sum of `count` over all sets; `None` when it does not fit in a `usize`.
    pub fn total(&self, count: impl Fn(&SetReport) -> usize) -> Option<usize> {
        self.sets
            .iter()
            .try_fold(0usize, |sum, r| sum.checked_add(count(r)))
    }

    /// The first count ([`SetReport::COUNT_NAMES`]) whose total over all sets does not fit
    /// in a `usize`.
    pub fn overflowing_total(&self) -> Option<&'static str> {
        (0..SetReport::COUNT_NAMES.len())
            .find(|&k| self.total(|r| r.counts()[k]).is_none())
            .map(|k| SetReport::COUNT_NAMES[k])
    }

    /// Total genuine mismatches; `usize::MAX` when the sum does not fit (never less than the
    /// true total, so a verdict on it cannot pass wrongly).
    pub fn genuine(&self) -> usize {
        self.total(|r| r.genuine_mismatches).unwrap_or(usize::MAX)
    }

    /// Total halfray leaks; `usize::MAX` when the sum does not fit.
    pub fn leaks(&self) -> usize {
        self.total(|r| r.leaks_halfray).unwrap_or(usize::MAX)
    }

    /// Total rays; `usize::MAX` when the sum does not fit.
    pub fn rays(&self) -> usize {
        self.total(|r| r.rays).unwrap_or(usize::MAX)
    }

    /// Total generated rays outside Embree's range ([`SetReport::rays_outside_embree`]);
    /// `usize::MAX` when the sum does not fit.
    pub fn rays_outside_embree(&self) -> usize {
        self.total(|r| r.rays_outside_embree).unwrap_or(usize::MAX)
    }

    /// halfray / Embree robust single-thread throughput, time-weighted over all sets (`None`
    /// without timed rays).
    pub fn throughput_ratio(&self) -> Option<f64> {
        let h: f64 = self.sets.iter().map(|r| r.secs_halfray).sum();
        let e: f64 = self.sets.iter().map(|r| r.secs_embree).sum();
        // Passes over no ray time only the loop around them.
        let timed = self.sets.iter().any(|r| r.timed_rays > 0);
        (timed && h > 0.0).then(|| e / h)
    }

    /// The results per mesh (inverse of [`Report::new`]): rows grouped by path in order of
    /// first appearance, a failure's error on its mesh's rows; then the failures without rows.
    pub fn mesh_results(&self) -> Vec<MeshResult> {
        let mut out: Vec<MeshResult> = Vec::new();
        for row in &self.sets {
            match out.iter_mut().find(|m| m.path == row.path) {
                Some(m) => m.sets.push(row.clone()),
                None => out.push(MeshResult {
                    path: row.path.clone(),
                    config: self.config.clone(),
                    error: None,
                    sets: vec![row.clone()],
                }),
            }
        }
        for f in &self.failed {
            match out.iter_mut().find(|m| m.path == f.path) {
                Some(m) => m.error = Some(f.error.clone()),
                None => out.push(MeshResult {
                    path: f.path.clone(),
                    config: self.config.clone(),
                    error: Some(f.error.clone()),
                    sets: Vec::new(),
                }),
            }
        }
        out
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
            crate::text::table_cell(&r.mesh),
            crate::text::table_cell(&r.name),
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
