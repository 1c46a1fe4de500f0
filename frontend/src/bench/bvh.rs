//! `halfray bench bvh`: BVH build time, size and single-threaded traversal throughput over a
//! corpus of meshes, against Embree on the same rays in the same run.
//!
//! Rays: the named sets of [`crate::raysets::named`] (camera rays in scanline order, in 8×8
//! tiles and with a stride, `width × width` of each; `--rays` incoherent rays, seed
//! [`INCOHERENT_SEED`]; a shadow and an ambient-occlusion ray from each camera hit). Closest-hit
//! sets are timed with halfray's closest-hit query and Embree's `rtcIntersect1`, any-hit sets
//! with the any-hit query and `rtcOccluded1`. Each throughput is the best of
//! [`TIMED_PASSES`] passes over the whole set on one thread, the passes taken **round-robin**
//! (halfray, Embree default, Embree robust, then again; [`interleaved`]) so that a slow spell of
//! the shared machine falls on all three; builds are timed the same way. The run closes with a
//! table of the ratios per mesh and, per set, their geometric mean and the worst mesh.
//!
//! Each camera set, and the shadow set, is also traced by the batch path
//! ([`closest_batch_simd`], [`any_batch_simd`]: coherent rays in packets; its answers checked
//! equal to the single-ray query's, hit or miss for the shadow rays; timed in calls of
//! `BATCH_BLOCK` rays answered into one kept buffer), reported as the set
//! `<set>+batch`: against Embree's `rtcIntersect1` (`rtcOccluded1`) as above, and against
//! Embree's packet API, `rtcIntersect8` and `rtcIntersect16` (`rtcOccluded8` and
//! `rtcOccluded16`), on the same rays in the same round-robin passes.
//!
//! With Embree compiled in, every side is timed on the rays Embree takes
//! (`embree::takes_ray`; it returns at once on the others, as if it had traced them):
//! the rest of a set's rays are left out for all sides alike, counted in
//! [`SetFigures::rays_outside_embree`] and named in a warning on stderr; a set left with no
//! rays has no ratio.
//!
//! Every side's answers are checked ([`answers`]): halfray's sides' hit counts on every
//! timed pass exactly against halfray's closest-hit count on the same rays; Embree's answers
//! on a sample of each set judged against an `f64` reference, untimed
//! ([`answers::judged_failures`], [`answers::judged_any_failures`]), and each Embree call's
//! counts held within [`answers::EMBREE_HIT_COUNT_TOLERANCE`] of its mode's single-ray call.
//! Embree's hit rates are reported beside halfray's.
//!
//! Brute force (every triangle for every ray) runs on a sample of the incoherent rays sized to
//! about [`BRUTE_FORCE_TESTS`] triangle tests, as a baseline; the BVH's answers on that sample
//! are checked against it. A failed check of either kind fails the run ([`Error::Mismatch`],
//! exit 3) once the JSON is written and the tables printed.

pub mod answers;
mod rivals;
pub mod summary;

use crate::accel::{
    any_batch_simd, any_simd, build_binary, build_binary_parallel, build_wide, closest_batch_simd,
    closest_simd,
};
use crate::crosscheck::corpus::RunMeshes;
use crate::error::{Error, Location, Result};
use crate::obj::read_obj;
use crate::raysets::named::{Query, RaySet, watertight_hits};
use crate::raysets::random_rays;
use crate::timing::{TIMED_PASSES, Timed, interleaved, interleaved_batches};
use answers::{Expected, Side, count_failures, reported_hits};
use glam::Vec3;
use halfray_core::Ray;
use halfray_core::bvh::wide::binary_options;
use halfray_core::bvh::{BuildOptions, DEFAULT_MAX_LEAF_SIZE};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{TraversalStats, Triangles};
use halfray_core::triangle::{TriangleVariant, VariantVisitor, Watertight};
use rivals::{HitQuery, Rivals};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Seed of the incoherent ray set (and of the ambient-occlusion directions).
pub const INCOHERENT_SEED: u64 = 0xB7B7_0001;
/// Target number of triangle tests of the brute-force baseline.
pub const BRUTE_FORCE_TESTS: usize = 150_000_000;

/// Arguments of `halfray bench bvh`.
#[derive(clap::Args, Debug, Clone)]
pub struct BvhArgs {
    /// Meshes to benchmark (OBJ), one after another in this run; a summary table of the
    /// ratios to Embree closes the output.
    #[arg(required_unless_present = "mesh_list")]
    pub meshes: Vec<PathBuf>,
    /// A file of mesh paths, one per line (blank lines and lines starting with `#` skipped; a
    /// `#` later in a line is part of the path; relative paths are relative to the current
    /// directory), benchmarked after the MESHES arguments.
    #[arg(long)]
    pub mesh_list: Option<PathBuf>,
    /// The JSON output and the ray counts.
    #[command(flatten)]
    pub run: super::RunArgs,
    /// Comma-separated ray sets; all by default.
    #[arg(long, value_delimiter = ',', value_enum)]
    pub sets: Vec<RaySet>,
    /// Triangle intersector.
    #[arg(long, value_enum, default_value_t)]
    pub intersector: crate::cli_values::Intersector,
    /// Maximum leaf size of the binary tree's build (the wide tree's binary tree is built with
    /// `wide::binary_options`, whose leaf sizes the collapse sets).
    #[arg(long, default_value_t = DEFAULT_MAX_LEAF_SIZE, value_parser = clap::value_parser!(u32).range(1..))]
    pub leaf_size: u32,
}

/// Everything measured on one mesh, as written to the JSON file. The build and size figures
/// are those of the default structure (the 8-wide BVH, the fastest watertight one), with the
/// binary tree's beside them; `sets` has the throughput of every ray set, with Embree 4's
/// default and robust modes on the same rays in the same run (with `--features embree`).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct BvhReport {
    /// Mesh path.
    pub mesh: String,
    /// Intersector name.
    pub intersector: String,
    /// The structure the figures describe (`bvh8`).
    pub structure: String,
    /// SIMD level the queries ran with (`avx2+fma`, `sse2`, `portable`).
    pub simd: String,
    /// Triangles in the mesh.
    pub triangles: usize,
    /// One-thread build time of the default structure (binary build + collapse), ms.
    pub build_ms: f64,
    /// Build time of the default structure on all `build_threads` threads (the binary build's
    /// subtrees in parallel, [`build_binary_parallel`]; the collapse on one), ms.
    pub build_ms_threads: f64,
    /// Threads of `build_ms_threads`.
    pub build_threads: usize,
    /// Nodes of the default structure.
    pub nodes: usize,
    /// Leaf slots of the default structure.
    pub leaves: usize,
    /// Bytes the default structure adds per triangle (nodes + copied triangles).
    pub bytes_per_triangle: f64,
    /// Depth of the deepest leaf of the binary tree.
    pub max_depth: usize,
    /// SAH cost of the binary tree, relative to the root area.
    pub sah_cost: f64,
    /// The binary tree (`--leaf-size`): one-thread build time, ms.
    pub binary_build_ms: f64,
    /// The binary tree's bytes per triangle (nodes + indices).
    pub binary_bytes_per_triangle: f64,
    /// Embree 4 build time, default mode, one thread, ms.
    pub embree_build_ms: Option<f64>,
    /// Embree 4 build time, robust mode, one thread, ms.
    pub embree_robust_build_ms: Option<f64>,
    /// Embree 4 build time, default mode, on all hardware threads (a device without
    /// `threads=1`), ms; `build_threads` is halfray's thread count beside it.
    #[serde(default)]
    pub embree_build_ms_threads: Option<f64>,
    /// Every ray set's figures, in the order asked.
    pub sets: Vec<SetFigures>,
    /// Brute-force sample size (incoherent rays).
    pub brute_force_rays: usize,
    /// Brute-force closest hit, Mrays/s.
    pub mrays_brute_force: f64,
    /// Sample rays where the wide BVH, the binary BVH and brute force do not all agree (must
    /// be 0: a run with any fails, exit 3, once its outputs are written).
    pub brute_force_mismatches: usize,
}

/// One ray set's figures on one mesh.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SetFigures {
    /// Set name ([`RaySet::name`]).
    pub name: String,
    /// `closest` or `any`: the query timed on both sides.
    pub query: String,
    /// Rays in the set: the rays every side was timed on.
    pub rays: usize,
    /// Rays generated for the set but left out on every side because Embree would not trace
    /// them (`embree::takes_ray`; 0 without Embree, and in reports that predate the
    /// field).
    #[serde(default)]
    pub rays_outside_embree: usize,
    /// Share of the rays that hit, by halfray's closest-hit query (halfray's timed sides are
    /// checked against it; Embree's as [`answers::Expected`] says).
    pub hit_rate: f64,
    /// Share of the rays that hit by Embree 4 default's timed single-ray call
    /// (`rtcIntersect1` or `rtcOccluded1`; of its pass farthest from `hit_rate`, see
    /// [`answers::reported_hits`]).
    #[serde(default)]
    pub embree_hit_rate: Option<f64>,
    /// The same for Embree 4 robust.
    #[serde(default)]
    pub embree_robust_hit_rate: Option<f64>,
    /// halfray's default structure, Mrays/s.
    pub mrays: f64,
    /// Mean nodes visited per ray by this row's own query: the closest-hit query on a
    /// single-ray set (also on an any-hit one, whose hits it is checked against), the batch
    /// call on a `+batch` row ([`closest_batch_simd`], or [`any_batch_simd`] for
    /// `shadow+batch`).
    pub nodes_per_ray: f64,
    /// Mean triangle tests per ray, by the same query as [`SetFigures::nodes_per_ray`].
    pub triangles_per_ray: f64,
    /// Embree 4 default mode, Mrays/s.
    pub embree_mrays: Option<f64>,
    /// Embree 4 robust mode, Mrays/s.
    pub embree_robust_mrays: Option<f64>,
    /// Batch sets (`<set>+batch`: halfray's batch path, Embree's `rtcIntersect1` or
    /// `rtcOccluded1` in the two fields above): Embree's `rtcIntersect8` (`rtcOccluded8` for
    /// the any-hit query) on the same rays, `[default, robust]`, Mrays/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub embree_packet8_mrays: Option<[f64; 2]>,
    /// Batch sets: Embree's `rtcIntersect16` (`rtcOccluded16`), `[default, robust]`, Mrays/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub embree_packet16_mrays: Option<[f64; 2]>,
}

impl SetFigures {
    /// halfray's throughput over Embree default's and over Embree robust's (`None` without
    /// Embree, for a set of no rays, and where either is not a [`positive_ratio`]).
    #[must_use]
    pub fn ratios(&self) -> Option<[f64; 2]> {
        if self.rays == 0 {
            return None;
        }
        Some([
            positive_ratio(self.mrays, self.embree_mrays?)?,
            positive_ratio(self.mrays, self.embree_robust_mrays?)?,
        ])
    }

    /// Batch sets: halfray's throughput over Embree's packet calls, `[8 default, 16 default,
    /// 8 robust, 16 robust]` (`None` without packet figures, and where any is not a
    /// [`positive_ratio`]: a set of no rays has none).
    #[must_use]
    pub fn packet_ratios(&self) -> Option<[f64; 4]> {
        let (p8, p16) = (self.embree_packet8_mrays?, self.embree_packet16_mrays?);
        let r = |e: f64| positive_ratio(self.mrays, e);
        Some([r(p8[0])?, r(p16[0])?, r(p8[1])?, r(p16[1])?])
    }
}

/// `a / b` when it is a finite positive number, else `None`: a throughput of a set of no rays
/// (0 over 0), a zero or negative one, or a report edited by hand gives no ratio, never an
/// infinite one or one that makes a geometric mean NaN.
#[must_use]
pub fn positive_ratio(a: f64, b: f64) -> Option<f64> {
    let r = a / b;
    (r.is_finite() && r > 0.0).then_some(r)
}

/// Runs the BVH benchmark: every mesh measured, then the JSON report written and the tables
/// printed.
///
/// # Errors
///
/// Bad arguments and inputs before any work; a mesh that cannot be measured; writing the
/// outputs; then, once they are written, [`Error::Mismatch`] listing every failed check of the
/// answers timed (a side's hit count off halfray's, [`answers::count_failures`]; brute-force
/// mismatches).
pub fn run(args: &BvhArgs) -> Result<()> {
    let variant = args.intersector.0;
    let run = RunMeshes::read(&args.meshes, args.mesh_list.as_deref(), "benchmark")?;
    run.refuse_repeated("benchmarked")?;
    crate::cli_values::refuse_repeated_sets(&args.sets)?;
    let sets = if args.sets.is_empty() {
        RaySet::ALL.to_vec()
    } else {
        args.sets.clone()
    };
    // One set is held in memory at a time: estimated, and every mesh opened, before any work.
    let meshes = &run.paths;
    args.run
        .check_inputs(super::RayMemory::OneSetAtATime, meshes, &run.named_at)?;
    let json = args.run.reserve_json(meshes, args.mesh_list.as_deref())?;
    let mut reports = Vec::with_capacity(meshes.len());
    let mut failures = Vec::new();
    for (k, mesh) in meshes.iter().enumerate() {
        struct Bench<'a>(&'a BvhArgs, &'a Path, &'a [RaySet]);
        impl VariantVisitor for Bench<'_> {
            type Output = Result<(BvhReport, Vec<String>)>;
            fn visit<I: TriangleIntersector>(self, isect: &I) -> Self::Output {
                bench(self.0, self.1, self.2, isect)
            }
        }
        let (report, mesh_failures) = variant
            .visit(Bench(args, mesh, &sets))
            .map_err(|e| run.noting_list(k, e))?;
        reports.push(report);
        failures.extend(mesh_failures);
    }
    super::write_json_reports(json, &reports)?;
    for r in &reports {
        crate::say!("{}", report_text(r));
    }
    crate::say!("\n{}", summary::markdown(&reports));
    answers::verdict(&failures)
}

/// The rays of `set` for `args` over the box `[lo, hi]`: `width²` camera rays (and a shadow or
/// AO ray per camera hit), `--rays` random ones.
fn set_rays(
    args: &BvhArgs,
    set: RaySet,
    (lo, hi): (Vec3, Vec3),
    hits: &dyn Fn(&Ray) -> Option<halfray_core::Hit>,
) -> Vec<Ray> {
    let count = match set {
        RaySet::Random => args.run.rays,
        _ => args.run.width * args.run.width,
    };
    set.generate(lo, hi, count, INCOHERENT_SEED, hits)
}

/// One mesh's report, with the failed checks of its answers ([`answers::count_failures`], and
/// a non-zero [`BvhReport::brute_force_mismatches`]), each a message naming the mesh.
fn bench<T: TriangleIntersector>(
    args: &BvhArgs,
    mesh_path: &Path,
    sets: &[RaySet],
    isect: &T,
) -> Result<(BvhReport, Vec<String>)> {
    let obj = read_obj(mesh_path)?;
    let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
    let n = mesh.len();
    let options = BuildOptions {
        max_leaf_size: args.leaf_size,
        ..BuildOptions::default()
    };
    // The wide tree's binary tree stops splitting where the collapse would neither split nor
    // open a leaf.
    let wide_options = binary_options(options);
    let build_err =
        |e: halfray_core::bvh::BvhError| Error::input(Location::file(mesh_path), e.to_string());
    let mut binary_s = f64::INFINITY;
    let mut wide_s = f64::INFINITY;
    let mut built = None;
    let mut rivals = Rivals::new(&obj)?;
    for _ in 0..TIMED_PASSES {
        if let Some(r) = rivals.as_mut() {
            r.build_pass()?;
        }
        let t0 = Instant::now();
        let b = build_binary(&mesh, &options).map_err(build_err)?;
        binary_s = binary_s.min(t0.elapsed().as_secs_f64());
        let t1 = Instant::now();
        let collapsed = build_binary(&mesh, &wide_options).map_err(build_err)?;
        let w = build_wide(&mesh, &collapsed).map_err(build_err)?;
        wide_s = wide_s.min(t1.elapsed().as_secs_f64());
        built = Some((b, w));
    }
    let (bvh, wide) = built.ok_or_else(|| Error::internal("no timed build ran", None))?;
    let mut threads_s = f64::INFINITY;
    for _ in 0..TIMED_PASSES {
        if let Some(r) = rivals.as_mut() {
            r.build_pass_threads()?;
        }
        let t0 = Instant::now();
        let b = build_binary_parallel(&mesh, &wide_options).map_err(build_err)?;
        let w = build_wide(&mesh, &b).map_err(build_err)?;
        threads_s = threads_s.min(t0.elapsed().as_secs_f64());
        if w.nodes() != wide.nodes() {
            return Err(Error::internal(
                "the parallel build gave another tree than the one-thread build",
                None,
            ));
        }
    }
    let stats = bvh.stats();
    let wstats = wide.stats();
    let bounds = obj.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    let hits = watertight_hits(&wide, &obj);

    let closest = |r: &Ray| closest_simd(&wide, &mesh, isect, r, None).is_some();
    let any = |r: &Ray| any_simd(&wide, &mesh, isect, r).is_some();
    let mut figures = Vec::with_capacity(sets.len());
    let mut failures = Vec::new();
    let mesh_name = crate::text::path(mesh_path);
    for &set in sets {
        let mut rays = set_rays(args, set, bounds, &hits);
        let generated = rays.len();
        rays.retain(Rivals::take);
        let outside = generated - rays.len();
        if outside > 0 {
            crate::note!(
                "warning: bench bvh {} {set}: {outside} of {generated} rays outside Embree's range, left out on every side{}",
                crate::text::path(mesh_path),
                if rays.is_empty() {
                    " (no ray left: no ratio)"
                } else {
                    ""
                }
            );
        }
        let query = set.query();
        // Hit counts of both queries (they must agree) and the closest-hit query's work.
        let mut st = TraversalStats::default();
        let hit_count = rays
            .iter()
            .filter(|r| closest_simd(&wide, &mesh, isect, r, Some(&mut st)).is_some())
            .count();
        let any_count = rays.iter().filter(|r| any(r)).count();
        if hit_count != any_count {
            return Err(Error::internal(
                format!(
                    "{}: any-hit disagrees with closest-hit on hit/miss in set {set}: {hit_count} vs {any_count}",
                    crate::text::path(mesh_path)
                ),
                None,
            ));
        }
        // halfray's sides are held to its count; Embree's hit rates are reported beside the
        // watertight test's count on the same tree and rays.
        let expected = Expected {
            halfray: hit_count,
            embree: if args.intersector.0 == TriangleVariant::Watertight {
                hit_count
            } else {
                rays.iter()
                    .filter(|r| closest_simd(&wide, &mesh, &Watertight, r, None).is_some())
                    .count()
            },
            embree_from: "the watertight test's closest-hit query",
        };
        let ours: &dyn Fn(&Ray) -> bool = match query {
            Query::Closest => &closest,
            Query::Any => &any,
        };
        let theirs: Vec<HitQuery<'_>> = rivals.as_ref().map_or_else(Vec::new, |r| r.queries(query));
        let mut sides: Vec<&dyn Fn(&Ray) -> bool> = vec![ours];
        sides.extend(theirs.iter().map(|f| f.as_ref()));
        let timed = interleaved(&rays, &sides);
        let api = format!("{}1", summary::packet_api(query.name()));
        // Embree's answers judged on a sample (untimed), each Embree call's counts held to its
        // mode's single-ray call on its first timed pass.
        if let Some(rivals) = &rivals {
            let watertight = |r: &Ray| closest_simd(&wide, &mesh, &Watertight, r, None);
            let names = (mesh_name.as_str(), set.name());
            failures.extend(judged_check(names, &obj, &rays, rivals, query, watertight));
        }
        let named = single_sides(&timed, query, &api);
        let single: Vec<&Timed> = timed.iter().skip(1).collect();
        let sizes = (rays.len(), expected.halfray);
        failures.extend(count_checks(
            (&mesh_name, set.name()),
            sizes,
            &named,
            &single,
            &[0, 1],
        ));
        let k = rays.len().max(1) as f64;
        let rate = |t: &Timed| reported_hits(t, expected.embree) as f64 / k;
        figures.push(SetFigures {
            name: set.name().into(),
            query: query.name().into(),
            rays: rays.len(),
            rays_outside_embree: outside,
            hit_rate: hit_count as f64 / k,
            embree_hit_rate: timed.get(1).map(rate),
            embree_robust_hit_rate: timed.get(2).map(rate),
            mrays: timed[0].mrays,
            nodes_per_ray: st.nodes_visited as f64 / k,
            triangles_per_ray: st.primitives_tested as f64 / k,
            embree_mrays: timed.get(1).map(|t| t.mrays),
            embree_robust_mrays: timed.get(2).map(|t| t.mrays),
            embree_packet8_mrays: None,
            embree_packet16_mrays: None,
        });
        if matches!(
            set,
            RaySet::Primary | RaySet::PrimaryTiles | RaySet::PrimaryStride | RaySet::Shadow
        ) {
            let theirs = rivals.as_ref().map_or_else(Vec::new, |r| r.queries(query));
            let packets = rivals
                .as_ref()
                .map_or_else(Vec::new, |r| r.packet_queries(query));
            let (batch, batch_failures) = batch_figures(
                (&wide, &mesh, isect),
                (&mesh_name, set, &rays, expected, outside),
                &theirs,
                &packets,
            )?;
            figures.push(batch);
            failures.extend(batch_failures);
        }
    }

    let sample_len = (BRUTE_FORCE_TESTS / n.max(1))
        .clamp(16, 20_000)
        .min(args.run.rays);
    let sample = random_rays(bounds.0, bounds.1, sample_len, INCOHERENT_SEED);
    let t0 = Instant::now();
    let brute: Vec<Option<(u32, f32)>> = sample
        .iter()
        .map(|r| brute_force(&mesh, isect, r))
        .collect();
    let brute_s = t0.elapsed().as_secs_f64();
    let mismatches = sample
        .iter()
        .zip(&brute)
        .filter(|(r, b)| {
            let w = closest_simd(&wide, &mesh, isect, r, None).map(|(p, h)| (p, h.t));
            let bin = bvh
                .closest_hit(
                    r,
                    &mut Triangles::new(&mesh, isect),
                    &mut halfray_core::query::Query::new(),
                )
                .map(|(p, h)| (p, h.t));
            w != **b || bin != **b
        })
        .count();
    let embree_build = rivals.as_ref().map(|r| r.build_ms());
    let report = BvhReport {
        mesh: mesh_path.display().to_string(),
        intersector: isect.name().to_string(),
        structure: "bvh8".into(),
        simd: crate::simd::level_name().into(),
        triangles: n,
        build_ms: wide_s * 1e3,
        build_ms_threads: threads_s * 1e3,
        build_threads: rayon::current_num_threads(),
        nodes: wstats.nodes,
        leaves: wstats.leaves,
        bytes_per_triangle: wide.bytes_per_triangle(),
        max_depth: stats.max_depth,
        sah_cost: stats.sah_cost,
        binary_build_ms: binary_s * 1e3,
        binary_bytes_per_triangle: bvh.bytes_per_triangle(),
        embree_build_ms: embree_build.map(|b| b[0]),
        embree_robust_build_ms: embree_build.map(|b| b[1]),
        embree_build_ms_threads: embree_build.map(|b| b[2]),
        sets: figures,
        brute_force_rays: sample_len,
        mrays_brute_force: crate::timing::mrays_per_second(sample_len as u64, brute_s),
        brute_force_mismatches: mismatches,
    };
    failures.extend(answers::brute_force_failure(&report));
    Ok((report, failures))
}

/// The judged check of Embree's sides on the set `set` of `mesh` (query `query`), untimed, on
/// [`answers::JUDGED_RAYS`] of `rays` against the watertight test's closest hits
/// (`watertight`): on a closest-hit set both scenes' `rtcIntersect1`
/// ([`answers::judged_failures`]), on an any-hit set their `rtcOccluded1`, with their
/// `rtcIntersect1` where it differs ([`answers::judged_any_failures`]).
fn judged_check(
    names: (&str, &str),
    mesh: &crate::obj::ObjMesh,
    rays: &[Ray],
    rivals: &Rivals,
    query: Query,
    watertight: impl Fn(&Ray) -> crate::accel::Answer,
) -> Vec<String> {
    use crate::crosscheck::judge::Answer;
    let judged: Vec<Ray> = crate::timing::spread_positions(rays.len(), answers::JUDGED_RAYS)
        .into_iter()
        .filter_map(|i| rays.get(i).copied())
        .collect();
    let reference: Vec<Option<Answer>> = judged
        .iter()
        .map(|r| Answer::of_hit(watertight(r)))
        .collect();
    let modes = ["default", "robust"];
    let api = summary::packet_api(query.name());
    match query {
        Query::Closest => {
            let mut sides: Vec<(String, Vec<Option<Answer>>)> = modes
                .map(|mode| (format!("Embree {mode} {api}1"), Vec::new()))
                .into();
            for r in &judged {
                for (side, answer) in sides.iter_mut().zip(rivals.closest(r)) {
                    side.1.push(answer);
                }
            }
            answers::judged_failures(names, mesh, (&judged, &reference), &sides)
        }
        Query::Any => {
            let mut sides: Vec<(String, Vec<answers::Occlusion>)> = modes
                .map(|mode| (format!("Embree {mode} {api}1"), Vec::new()))
                .into();
            for (r, w) in judged.iter().zip(&reference) {
                let occluded = rivals.occluded(r);
                // Both scenes' nearest hits, asked only where an occlusion differs.
                let nearest = occluded
                    .iter()
                    .any(|&o| o != w.is_some())
                    .then(|| rivals.closest(r));
                for (k, (side, occluded)) in sides.iter_mut().zip(occluded).enumerate() {
                    let nearest = nearest.as_ref().and_then(|n| n.get(k).copied().flatten());
                    side.1.push(answers::Occlusion { occluded, nearest });
                }
            }
            answers::judged_any_failures(names, mesh, (&judged, &reference), &sides)
        }
    }
}

/// Where each Embree call's count is held to, by mode ([`count_checks`]).
const MODE_COUNTS: [&str; 2] = [
    "Embree default's single-ray call on its first timed pass",
    "Embree robust's single-ray call on its first timed pass",
];

/// The count checks of the timed sides `named` (halfray's first, then Embree's) on the set
/// `set` of `mesh` (`rays` rays): halfray's exactly against `halfray`, each Embree side within
/// [`answers::EMBREE_HIT_COUNT_TOLERANCE`] of its mode's single-ray call on its first timed
/// pass (`single[mode]`; `modes[k]` is the mode of `named[k + 1]`, 0 default, 1 robust).
fn count_checks(
    (mesh, set): (&str, &str),
    (rays, halfray): (usize, usize),
    named: &[Side<'_>],
    single: &[&Timed],
    modes: &[usize],
) -> Vec<String> {
    let own = Expected {
        halfray,
        embree: 0,
        embree_from: "",
    };
    let mut failures = count_failures(mesh, set, rays, own, named.get(..1).unwrap_or(&[]));
    for (side, &mode) in named.iter().skip(1).zip(modes) {
        if let (Some(first), Some(from)) = (single.get(mode), MODE_COUNTS.get(mode)) {
            let expected = Expected {
                embree: first.hits[0],
                embree_from: from,
                ..own
            };
            failures.extend(count_failures(
                mesh,
                set,
                rays,
                expected,
                std::slice::from_ref(side),
            ));
        }
    }
    failures
}

/// The timed sides of a set, named for messages: halfray's, then (with Embree) Embree default's
/// and robust's single-ray call `api` (`rtcIntersect1`, `rtcOccluded1`).
fn single_sides<'a>(timed: &'a [Timed], query: Query, api: &str) -> Vec<Side<'a>> {
    let names = [
        format!("halfray's {}-hit query", query.name()),
        format!("Embree default {api}"),
        format!("Embree robust {api}"),
    ];
    timed
        .iter()
        .zip(names)
        .enumerate()
        .map(|(k, (timed, name))| Side {
            name,
            timed,
            embree: k > 0,
        })
        .collect()
}

/// Rays per call of the timed batch side ([`batch_figures`]): a few rows of a camera, a
/// multiple of the packet size (16), its answers (32 bytes each, 128 KB) kept in the L2 cache.
const BATCH_BLOCK: usize = 4096;

/// The batch path's figures on the camera or shadow set `set` of the mesh `mesh_name` (`rays`,
/// with the hit counts `expected`, `outside` more left out as outside Embree's range), with
/// the failed checks of every timed side's hit count ([`answers::count_failures`]):
/// halfray's [`closest_batch_simd`] (checked equal to the single-ray query, bit for bit) or,
/// on an any-hit set, [`any_batch_simd`] (checked to hit exactly where the single-ray query
/// does) against Embree's `rtcIntersect1`/`rtcOccluded1` (`single`: default, robust) and its
/// packet API (`packets`: default by 8 and 16 rays, robust by 8 and 16), timed round-robin on
/// the whole set.
fn batch_figures<T: TriangleIntersector>(
    (wide, mesh, isect): (&crate::accel::VecBvh8, &TriangleMesh<'_>, &T),
    (mesh_name, set, rays, expected, outside): (&str, RaySet, &[Ray], Expected, usize),
    single: &[HitQuery<'_>],
    packets: &[rivals::BatchQuery<'_>],
) -> Result<(SetFigures, Vec<String>)> {
    let internal = |e: halfray_core::query::QueryError| Error::internal(e.to_string(), None);
    let query = set.query();
    let batch = |rays: &[Ray], out: &mut [crate::accel::Answer], st| match query {
        Query::Closest => closest_batch_simd(wide, mesh, isect, rays, out, st),
        Query::Any => any_batch_simd(wide, mesh, isect, rays, out, st),
    };
    let mut out = vec![None; rays.len()];
    let mut st = TraversalStats::default();
    batch(rays, &mut out, Some(&mut st)).map_err(internal)?;
    let bits = |a: &Option<(u32, halfray_core::triangle::TriangleHit)>| match query {
        Query::Closest => a.map(|(p, h)| (p, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits())),
        Query::Any => a.map(|_| (0, 0, 0, 0)),
    };
    let one = |r: &Ray| match query {
        Query::Closest => closest_simd(wide, mesh, isect, r, None),
        Query::Any => any_simd(wide, mesh, isect, r),
    };
    let mismatches = rays
        .iter()
        .zip(&out)
        .filter(|(r, b)| bits(&one(r)) != bits(b))
        .count();
    if mismatches > 0 {
        return Err(Error::internal(
            format!("set {set}: the batch path differs from single rays on {mismatches} rays"),
            None,
        ));
    }
    // Timed block by block into one kept buffer, as a renderer answers a row: the other sides
    // store no answer, and a set-sized buffer (20 MB for a 1024² camera) written and read
    // back would time the memory, not the walk.
    let block = std::cell::RefCell::new(vec![None; BATCH_BLOCK.min(rays.len())]);
    let ours = |rays: &[Ray]| {
        let mut block = block.borrow_mut();
        rays.chunks(BATCH_BLOCK)
            .map(|rays| {
                let out = &mut block[..rays.len()];
                let done = batch(rays, out, None);
                usize::from(done.is_ok()) * out.iter().filter(|h| h.is_some()).count()
            })
            .sum()
    };
    let each: Vec<rivals::BatchQuery<'_>> = single
        .iter()
        .map(|f| {
            Box::new(move |rays: &[Ray]| rays.iter().filter(|r| f(std::hint::black_box(r))).count())
                as rivals::BatchQuery<'_>
        })
        .collect();
    let mut sides: Vec<crate::timing::BatchSide<'_>> = vec![&ours];
    sides.extend(each.iter().chain(packets).map(|f| f.as_ref()));
    let m = interleaved_batches(rays, &sides);
    let name = format!("{}+batch", set.name());
    let api = summary::packet_api(query.name());
    let mut named = single_sides(&m[..m.len().min(3)], query, &format!("{api}1"));
    named[0].name = "halfray's batch path".into();
    let packet_names = ["default", "robust"]
        .into_iter()
        .flat_map(|mode| [8, 16].map(|w| format!("Embree {mode} {api}{w}")));
    named.extend(
        m.iter()
            .skip(3)
            .zip(packet_names)
            .map(|(timed, name)| Side {
                name,
                timed,
                embree: true,
            }),
    );
    let single: Vec<&Timed> = m.iter().skip(1).take(2).collect();
    let sizes = (rays.len(), expected.halfray);
    let failures = count_checks(
        (mesh_name, &name),
        sizes,
        &named,
        &single,
        &[0, 1, 0, 0, 1, 1],
    );
    let k = rays.len().max(1) as f64;
    let rate = |t: &Timed| reported_hits(t, expected.embree) as f64 / k;
    let pair = |a: usize, b: usize| Some([m.get(a)?.mrays, m.get(b)?.mrays]);
    let figures = SetFigures {
        name,
        query: query.name().into(),
        rays: rays.len(),
        rays_outside_embree: outside,
        hit_rate: expected.halfray as f64 / k,
        embree_hit_rate: m.get(1).map(rate),
        embree_robust_hit_rate: m.get(2).map(rate),
        mrays: m[0].mrays,
        nodes_per_ray: st.nodes_visited as f64 / k,
        triangles_per_ray: st.primitives_tested as f64 / k,
        embree_mrays: m.get(1).map(|t| t.mrays),
        embree_robust_mrays: m.get(2).map(|t| t.mrays),
        embree_packet8_mrays: pair(3, 5),
        embree_packet16_mrays: pair(4, 6),
    };
    Ok((figures, failures))
}

/// Closest hit over every triangle, ties to the smaller index (the BVH's rule).
pub(super) fn brute_force<T: TriangleIntersector>(
    mesh: &TriangleMesh<'_>,
    isect: &T,
    ray: &Ray,
) -> Option<(u32, f32)> {
    let pre = isect.prepare(ray)?;
    let mut best: Option<(u32, f32)> = None;
    let mut cur = *ray;
    for i in 0..mesh.len() {
        let Some(v) = mesh.triangle(i) else { continue };
        if let Some(h) = isect.intersect_prepared(&pre, &cur, &v)
            && best.is_none_or(|(_, t)| h.t < t)
        {
            best = Some((i as u32, h.t));
            cur.t_max = h.t;
        }
    }
    best
}

/// The plain-text report of one mesh: the build line, one row per set (the set column as wide
/// as the longest set name), the packet lines of the batch sets and the brute-force line.
fn report_text(r: &BvhReport) -> String {
    use std::fmt::Write as _;
    let opt = |x: Option<f64>, p: usize| x.map_or("-".to_string(), |x| format!("{x:.p$}"));
    let mut out = String::new();
    let w = r
        .sets
        .iter()
        .map(|s| s.name.chars().count())
        .chain(["set".len()])
        .max()
        .unwrap_or(0);
    // Writing to a String cannot fail.
    let _ = writeln!(
        out,
        "bench bvh: {} ({} triangles, {}, {} on {})",
        crate::text::escaped(&r.mesh),
        r.triangles,
        r.intersector,
        r.structure,
        r.simd
    );
    let _ = writeln!(
        out,
        "  build, 1 thread: bvh8 {:.1} ms ({:.1} ms on {} threads, the same tree), {:.1} B/tri; binary {:.1} ms, {:.1} B/tri; Embree default {} ms ({} ms on all threads), robust {} ms",
        r.build_ms,
        r.build_ms_threads,
        r.build_threads,
        r.bytes_per_triangle,
        r.binary_build_ms,
        r.binary_bytes_per_triangle,
        opt(r.embree_build_ms, 1),
        opt(r.embree_build_ms_threads, 1),
        opt(r.embree_robust_build_ms, 1),
    );
    let _ = writeln!(
        out,
        "  {:<w$} {:<7} {:>8} {:>6} {:>8} {:>8} {:>8} {:>7} {:>7} {:>6} {:>6}",
        "set",
        "query",
        "rays",
        "hit %",
        "halfray",
        "E. def",
        "E. rob",
        "/def",
        "/rob",
        "nodes",
        "tris"
    );
    for s in &r.sets {
        let [d, rb] = s.ratios().map_or([None; 2], |[d, rb]| [Some(d), Some(rb)]);
        let _ = writeln!(
            out,
            "  {:<w$} {:<7} {:>8} {:>6.1} {:>8.2} {:>8} {:>8} {:>7} {:>7} {:>6.1} {:>6.1}",
            s.name,
            s.query,
            s.rays,
            100.0 * s.hit_rate,
            s.mrays,
            opt(s.embree_mrays, 2),
            opt(s.embree_robust_mrays, 2),
            opt(d, 2),
            opt(rb, 2),
            s.nodes_per_ray,
            s.triangles_per_ray,
        );
    }
    for s in &r.sets {
        if let (Some(p8), Some(p16)) = (s.embree_packet8_mrays, s.embree_packet16_mrays) {
            let api = summary::packet_api(&s.query);
            let over = s.packet_ratios().map_or("-".into(), |q| {
                format!(
                    "x8 {:.2} / {:.2}, x16 {:.2} / {:.2}",
                    q[0], q[2], q[1], q[3]
                )
            });
            let _ = writeln!(
                out,
                "  {:<w$} Embree packets: {api}8 {:.2} / {:.2}, {api}16 {:.2} / {:.2} Mrays/s (default / robust); batch over them: {over}",
                s.name, p8[0], p8[1], p16[0], p16[1],
            );
        }
    }
    let _ = writeln!(
        out,
        "  brute force {:.1} rays/s on {} incoherent rays; mismatches {}",
        r.mrays_brute_force * 1e6,
        r.brute_force_rays,
        r.brute_force_mismatches
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row of the plain-text table has its query column at the same place, past the
    /// longest set name (`primary-stride+batch`), and so do the header and the packet lines.
    #[test]
    fn the_set_column_is_as_wide_as_the_longest_set_name() {
        let long = "primary-stride+batch";
        let mut r =
            summary::tests::report("m.obj", &[("ao", 1.0, 1.0, 1.0), (long, 1.0, 1.0, 1.0)]);
        r.sets[1].embree_packet8_mrays = Some([1.0, 1.0]);
        r.sets[1].embree_packet16_mrays = Some([1.0, 1.0]);
        let text = report_text(&r);
        let column = 2 + long.len() + 1;
        let rows: Vec<&str> = text
            .lines()
            .filter(|l| {
                l.starts_with("  ") && !l.starts_with("  build") && !l.starts_with("  brute")
            })
            .collect();
        assert_eq!(rows.len(), 4, "{text}");
        for row in rows {
            let second = row[column..].split(' ').next().unwrap();
            assert!(
                ["query", "closest", "Embree"].contains(&second),
                "want the second column at {column} in `{row}`:\n{text}"
            );
            assert_eq!(row.as_bytes()[column - 1], b' ', "{row}");
        }
    }
}
