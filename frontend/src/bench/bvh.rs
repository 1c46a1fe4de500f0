//! `halfray bench bvh`: BVH build time, size and single-threaded traversal throughput.
//!
//! Rays: the primary rays of a `width × width` camera framing the mesh
//! ([`crate::raysets::Camera::framing`]) and `--rays` incoherent rays
//! ([`crate::raysets::random_rays`], seed [`INCOHERENT_SEED`]). Each throughput is the best of
//! [`TIMED_PASSES`] passes over the whole set on one thread. With `--features embree` the
//! figures compared with Embree are taken **round-robin**: each pass builds (or traces the set
//! with) halfray's default tree, then Embree default, then Embree robust, so a slow spell of
//! the shared machine falls on all three rather than on whichever ran then; the ratios are
//! of the bests. Brute force (every triangle for
//! every ray) runs on a sample of the incoherent rays sized to about [`BRUTE_FORCE_TESTS`]
//! triangle tests, as a baseline ratio; the BVH's answers on that sample are checked against it.

mod rivals;

use crate::accel::{any_simd, build_binary, build_binary_parallel, build_wide, closest_simd};
use crate::error::{Error, Location, Result};
use crate::obj::read_obj;
use halfray_core::Ray;
use halfray_core::bvh::wide::binary_options;
use halfray_core::bvh::{BuildOptions, DEFAULT_MAX_LEAF_SIZE, TraversalStats, TriangleMesh};
use halfray_core::triangle::{TriangleIntersector, VariantVisitor};
use rivals::Rivals;
pub(super) use rivals::interleaved;
use std::path::PathBuf;
use std::time::Instant;

/// Seed of the incoherent ray set.
pub const INCOHERENT_SEED: u64 = 0xB7B7_0001;
/// Timed passes per measurement; the best is reported, so that one preemption of a pass (a
/// few milliseconds for 100 000 camera rays) does not spoil a figure on a shared machine.
pub const TIMED_PASSES: usize = 5;
/// Target number of triangle tests of the brute-force baseline.
pub const BRUTE_FORCE_TESTS: usize = 150_000_000;

/// Arguments of `halfray bench bvh`.
#[derive(clap::Args, Debug, Clone)]
pub struct BvhArgs {
    /// Meshes to benchmark (OBJ), one after another in this run; a summary table of the
    /// ratios to Embree closes the output.
    #[arg(required = true)]
    pub meshes: Vec<PathBuf>,
    /// The JSON output and the ray sets.
    #[command(flatten)]
    pub run: super::RunArgs,
    /// Triangle intersector.
    #[arg(long, value_enum, default_value_t)]
    pub intersector: crate::cli_values::Intersector,
    /// Maximum leaf size of the binary tree's build (the wide tree's binary tree is built with
    /// `wide::binary_options`, whose leaf sizes the collapse sets).
    #[arg(long, default_value_t = DEFAULT_MAX_LEAF_SIZE)]
    pub leaf_size: u32,
}

/// Everything measured, as written to the JSON file. The top-level figures are those of the
/// default structure (the 8-wide BVH, the fastest watertight one); `binary` has the binary
/// tree's on the same rays, and the `embree_*` keys (with `--features embree`) Embree 4's
/// default and robust modes on the same rays in the same run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BvhReport {
    /// Mesh path.
    pub mesh: String,
    /// Intersector name.
    pub intersector: String,
    /// The structure the top-level figures describe (`bvh8`).
    pub structure: String,
    /// SIMD level the queries ran with (`avx2+fma`, `sse2`, `portable`).
    pub simd: String,
    /// Triangles in the mesh.
    pub triangles: usize,
    /// The default structure's figures, at the top level of the JSON (build time: binary build
    /// + collapse; bytes: nodes + copied triangles).
    #[serde(flatten)]
    pub bvh8: StructureReport,
    /// Build time of the default structure on all `build_threads` threads (the binary build's
    /// subtrees in parallel, [`build_binary_parallel`]; the collapse on one), ms. The
    /// top-level `build_ms` is one thread, the figure compared with Embree's.
    pub build_ms_threads: f64,
    /// Threads of `build_ms_threads`.
    pub build_threads: usize,
    /// Leaf slots.
    pub leaves: usize,
    /// Depth of the deepest leaf of the binary tree it was collapsed from.
    pub max_depth: usize,
    /// SAH cost of the binary tree, relative to the root area.
    pub sah_cost: f64,
    /// Primary rays per set.
    pub primary_rays: usize,
    /// Incoherent rays per set.
    pub incoherent_rays: usize,
    /// Share of primary rays that hit.
    pub hit_rate_primary: f64,
    /// Share of incoherent rays that hit.
    pub hit_rate_incoherent: f64,
    /// Brute-force sample size (incoherent rays).
    pub brute_force_rays: usize,
    /// Brute-force closest hit, Mrays/s.
    pub mrays_brute_force: f64,
    /// `mrays_closest_incoherent / mrays_brute_force`.
    pub speedup_over_brute_force: f64,
    /// Sample rays where the wide BVH, the binary BVH and brute force do not all agree (must
    /// be 0).
    pub brute_force_mismatches: usize,
    /// The binary BVH on the same rays.
    pub binary: StructureReport,
    /// Embree 4 build time (default mode, one thread), ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub embree_build_ms: Option<f64>,
    /// Embree 4 default mode, closest hit, primary rays, Mrays/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub embree_mrays_closest_primary: Option<f64>,
    /// Embree 4 default mode, closest hit, incoherent rays, Mrays/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub embree_mrays_closest_incoherent: Option<f64>,
    /// Embree 4 robust mode build time, ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub embree_robust_build_ms: Option<f64>,
    /// Embree 4 robust mode, closest hit, primary rays, Mrays/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub embree_robust_mrays_closest_primary: Option<f64>,
    /// Embree 4 robust mode, closest hit, incoherent rays, Mrays/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub embree_robust_mrays_closest_incoherent: Option<f64>,
}

/// One structure's figures.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct StructureReport {
    /// Build time, ms.
    pub build_ms: f64,
    /// Nodes in use.
    pub nodes: usize,
    /// Bytes the structure adds per triangle.
    pub bytes_per_triangle: f64,
    /// Closest hit, primary rays, Mrays/s.
    pub mrays_closest_primary: f64,
    /// Any hit, primary rays, Mrays/s.
    pub mrays_any_primary: f64,
    /// Closest hit, incoherent rays, Mrays/s.
    pub mrays_closest_incoherent: f64,
    /// Any hit, incoherent rays, Mrays/s.
    pub mrays_any_incoherent: f64,
    /// Mean nodes visited per primary closest-hit ray.
    pub nodes_per_ray_primary: f64,
    /// Mean triangle tests per primary closest-hit ray.
    pub triangles_per_ray_primary: f64,
    /// Mean nodes visited per incoherent closest-hit ray.
    pub nodes_per_ray_incoherent: f64,
    /// Mean triangle tests per incoherent closest-hit ray.
    pub triangles_per_ray_incoherent: f64,
}

/// Runs the BVH benchmark.
pub fn run(args: &BvhArgs) -> Result<()> {
    let variant = args.intersector.0;
    // The two ray sets are held in memory: estimated, and every mesh opened, before any work.
    args.run.check_inputs(&args.meshes)?;
    let mut reports = Vec::with_capacity(args.meshes.len());
    for mesh in &args.meshes {
        struct Bench<'a>(&'a BvhArgs, &'a std::path::Path);
        impl VariantVisitor for Bench<'_> {
            type Output = Result<BvhReport>;
            fn visit<I: TriangleIntersector>(self, isect: &I) -> Result<BvhReport> {
                bench(self.0, self.1, isect)
            }
        }
        let report = variant.visit(Bench(args, mesh))?;
        reports.push(report);
    }
    super::write_json_reports(args.run.json.as_deref(), &reports)?;
    for r in &reports {
        print_report(r);
    }
    print_summary(&reports);
    Ok(())
}

/// The ratios of the run as one Markdown table (the README's performance table): halfray's
/// default structure against Embree robust and default, per mesh, from this run's figures.
fn print_summary(reports: &[BvhReport]) {
    let ratio = |a: f64, b: Option<f64>| b.map_or("-".to_string(), |b| format!("{:.2}", a / b));
    let fig = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.2}"));
    println!();
    println!(
        "| mesh | triangles | closest primary, Mrays/s: halfray / Embree robust / default | ratio robust | ratio default | closest incoherent: halfray / robust / default | ratio robust | ratio default | build ms: halfray / Embree | build ratio | B/tri |"
    );
    println!("|---|---:|---|---:|---:|---|---:|---:|---|---:|---:|");
    for r in reports {
        let name = std::path::Path::new(&r.mesh)
            .file_name()
            .map_or(r.mesh.clone(), |n| n.to_string_lossy().into_owned());
        let b = &r.bvh8;
        println!(
            "| {name} | {} | {:.2} / {} / {} | {} | {} | {:.2} / {} / {} | {} | {} | {:.0} / {} | {} | {:.1} |",
            r.triangles,
            b.mrays_closest_primary,
            fig(r.embree_robust_mrays_closest_primary),
            fig(r.embree_mrays_closest_primary),
            ratio(
                b.mrays_closest_primary,
                r.embree_robust_mrays_closest_primary
            ),
            ratio(b.mrays_closest_primary, r.embree_mrays_closest_primary),
            b.mrays_closest_incoherent,
            fig(r.embree_robust_mrays_closest_incoherent),
            fig(r.embree_mrays_closest_incoherent),
            ratio(
                b.mrays_closest_incoherent,
                r.embree_robust_mrays_closest_incoherent
            ),
            ratio(
                b.mrays_closest_incoherent,
                r.embree_mrays_closest_incoherent
            ),
            b.build_ms,
            r.embree_build_ms
                .map_or("-".to_string(), |x| format!("{x:.0}")),
            ratio(b.build_ms, r.embree_build_ms),
            b.bytes_per_triangle,
        );
    }
}

/// Closest/any-hit throughput and per-ray counts of one structure on both ray sets.
fn measure(
    primary: &[Ray],
    incoherent: &[Ray],
    closest: impl Fn(&Ray, Option<&mut TraversalStats>) -> bool,
    any: impl Fn(&Ray) -> bool,
    rep: &mut StructureReport,
) -> Result<(usize, usize)> {
    let (c_p, hits_p) = throughput(primary, |r| closest(r, None));
    let (a_p, any_p) = throughput(primary, &any);
    let (c_i, hits_i) = throughput(incoherent, |r| closest(r, None));
    let (a_i, any_i) = throughput(incoherent, &any);
    if hits_p != any_p || hits_i != any_i {
        return Err(Error::internal(
            format!(
                "any-hit disagrees with closest-hit on hit/miss: primary {hits_p} vs {any_p}, incoherent {hits_i} vs {any_i}"
            ),
            None,
        ));
    }
    let per_ray = |rays: &[Ray]| {
        let mut st = TraversalStats::default();
        for r in rays {
            closest(r, Some(&mut st));
        }
        let k = rays.len().max(1) as f64;
        (st.nodes_visited as f64 / k, st.primitives_tested as f64 / k)
    };
    (rep.nodes_per_ray_primary, rep.triangles_per_ray_primary) = per_ray(primary);
    (
        rep.nodes_per_ray_incoherent,
        rep.triangles_per_ray_incoherent,
    ) = per_ray(incoherent);
    (
        rep.mrays_closest_primary,
        rep.mrays_any_primary,
        rep.mrays_closest_incoherent,
        rep.mrays_any_incoherent,
    ) = (c_p, a_p, c_i, a_i);
    Ok((hits_p, hits_i))
}

fn bench<T: TriangleIntersector>(
    args: &BvhArgs,
    mesh_path: &std::path::Path,
    isect: &T,
) -> Result<BvhReport> {
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

    let (primary, incoherent) = args.run.ray_sets(&obj);

    let mut binary = StructureReport {
        build_ms: binary_s * 1e3,
        nodes: stats.nodes,
        bytes_per_triangle: stats.bytes_per_primitive,
        ..StructureReport::default()
    };
    measure(
        &primary,
        &incoherent,
        |r, st| bvh.closest_hit_triangles(&mesh, isect, r, st).is_some(),
        |r| bvh.any_hit_triangles(&mesh, isect, r, None).is_some(),
        &mut binary,
    )?;
    let mut top = StructureReport {
        build_ms: wide_s * 1e3,
        nodes: wstats.nodes,
        bytes_per_triangle: wstats.bytes_per_triangle,
        ..StructureReport::default()
    };
    let (hits_p, hits_i) = measure(
        &primary,
        &incoherent,
        |r, st| closest_simd(&wide, isect, r, st).is_some(),
        |r| any_simd(&wide, isect, r).is_some(),
        &mut top,
    )?;

    let sample_len = (BRUTE_FORCE_TESTS / n.max(1))
        .clamp(16, 20_000)
        .min(incoherent.len());
    let sample = &incoherent[..sample_len];
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
            let w = closest_simd(&wide, isect, r, None).map(|(p, h)| (p, h.t));
            let bin = bvh
                .closest_hit_triangles(&mesh, isect, r, None)
                .map(|(p, h)| (p, h.t));
            w != **b || bin != **b
        })
        .count();
    let mrays_brute = sample_len as f64 / brute_s.max(1e-9) / 1e6;
    // The closest-hit figures compared with Embree, round-robin with Embree's two modes.
    let embree = match &rivals {
        Some(r) => {
            let ours = |ray: &Ray| closest_simd(&wide, isect, ray, None).is_some();
            let mut closest: Vec<&dyn Fn(&Ray) -> bool> = vec![&ours];
            let theirs = r.closest();
            closest.extend(theirs.iter().map(|f| f.as_ref()));
            let p = interleaved(&primary, &closest);
            let i = interleaved(&incoherent, &closest);
            (top.mrays_closest_primary, top.mrays_closest_incoherent) = (p[0], i[0]);
            Some(EmbreeFigures {
                build_ms: r.build_ms(),
                primary: [p[1], p[2]],
                incoherent: [i[1], i[2]],
            })
        }
        None => None,
    };

    let speedup = top.mrays_closest_incoherent / mrays_brute.max(1e-12);
    Ok(BvhReport {
        mesh: mesh_path.display().to_string(),
        intersector: isect.name().to_string(),
        structure: "bvh8".into(),
        simd: crate::simd::level_name().into(),
        triangles: n,
        bvh8: top,
        build_ms_threads: threads_s * 1e3,
        build_threads: rayon::current_num_threads(),
        leaves: wstats.leaves,
        max_depth: stats.max_depth,
        sah_cost: stats.sah_cost,
        primary_rays: primary.len(),
        incoherent_rays: incoherent.len(),
        hit_rate_primary: hits_p as f64 / primary.len().max(1) as f64,
        hit_rate_incoherent: hits_i as f64 / incoherent.len().max(1) as f64,
        brute_force_rays: sample_len,
        mrays_brute_force: mrays_brute,
        speedup_over_brute_force: speedup,
        brute_force_mismatches: mismatches,
        binary,
        embree_build_ms: embree.map(|e| e.build_ms[0]),
        embree_mrays_closest_primary: embree.map(|e| e.primary[0]),
        embree_mrays_closest_incoherent: embree.map(|e| e.incoherent[0]),
        embree_robust_build_ms: embree.map(|e| e.build_ms[1]),
        embree_robust_mrays_closest_primary: embree.map(|e| e.primary[1]),
        embree_robust_mrays_closest_incoherent: embree.map(|e| e.incoherent[1]),
    })
}

/// Embree's build times and closest-hit throughputs, `[default, robust]`.
#[derive(Clone, Copy)]
struct EmbreeFigures {
    build_ms: [f64; 2],
    primary: [f64; 2],
    incoherent: [f64; 2],
}

/// Best-of-[`TIMED_PASSES`] throughput of `f` over `rays` in Mrays/s, and the hit count.
fn throughput(rays: &[Ray], f: impl Fn(&Ray) -> bool) -> (f64, usize) {
    let mut best = f64::INFINITY;
    let mut hits = 0;
    for _ in 0..TIMED_PASSES {
        let t0 = Instant::now();
        hits = rays.iter().filter(|r| f(std::hint::black_box(r))).count();
        best = best.min(t0.elapsed().as_secs_f64());
    }
    (rays.len() as f64 / best.max(1e-9) / 1e6, hits)
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

fn print_report(r: &BvhReport) {
    println!(
        "bench bvh: {} ({} triangles, {}, {} on {})",
        r.mesh, r.triangles, r.intersector, r.structure, r.simd
    );
    println!(
        "  {:<22} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "1 thread", "build ms", "B/tri", "closest", "any", "closest", "any"
    );
    println!(
        "  {:<22} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "", "", "", "primary", "primary", "incoh.", "incoh."
    );
    let row = |name: &str, s: &StructureReport| {
        println!(
            "  {:<22} {:>9.1} {:>9.1} {:>9.2} {:>9.2} {:>9.2} {:>9.2}",
            name,
            s.build_ms,
            s.bytes_per_triangle,
            s.mrays_closest_primary,
            s.mrays_any_primary,
            s.mrays_closest_incoherent,
            s.mrays_any_incoherent
        );
    };
    row("halfray bvh8", &r.bvh8);
    row("halfray binary", &r.binary);
    for (name, b, p, i) in [
        (
            "embree default",
            r.embree_build_ms,
            r.embree_mrays_closest_primary,
            r.embree_mrays_closest_incoherent,
        ),
        (
            "embree robust",
            r.embree_robust_build_ms,
            r.embree_robust_mrays_closest_primary,
            r.embree_robust_mrays_closest_incoherent,
        ),
    ] {
        if let (Some(b), Some(p), Some(i)) = (b, p, i) {
            println!(
                "  {:<22} {:>9.1} {:>9} {:>9.2} {:>9} {:>9.2} {:>9}",
                name, b, "88", p, "-", i, "-"
            );
        }
    }
    println!(
        "  bvh8 build on {} threads: {:.1} ms (the same tree)",
        r.build_threads, r.build_ms_threads
    );
    println!(
        "  rays: {} primary ({:.1}% hit), {} incoherent ({:.1}% hit); bvh8 nodes/ray {:.1} / {:.1}, tris/ray {:.1} / {:.1}",
        r.primary_rays,
        100.0 * r.hit_rate_primary,
        r.incoherent_rays,
        100.0 * r.hit_rate_incoherent,
        r.bvh8.nodes_per_ray_primary,
        r.bvh8.nodes_per_ray_incoherent,
        r.bvh8.triangles_per_ray_primary,
        r.bvh8.triangles_per_ray_incoherent
    );
    println!(
        "  brute force      {:9.1} rays/s on {} incoherent rays: BVH is {:.0}x faster; mismatches {}",
        r.mrays_brute_force * 1e6,
        r.brute_force_rays,
        r.speedup_over_brute_force,
        r.brute_force_mismatches
    );
}
