//! `halfray bench bvh`: BVH build time, size and single-threaded traversal throughput.
//!
//! Rays: the primary rays of a `width × width` camera framing the mesh
//! ([`crate::raysets::Camera::framing`]) and `--rays` incoherent rays
//! ([`crate::raysets::random_rays`], seed [`INCOHERENT_SEED`]). Each throughput is the best of
//! [`TIMED_PASSES`] passes over the whole set on one thread. Brute force (every triangle for
//! every ray) runs on a sample of the incoherent rays sized to about [`BRUTE_FORCE_TESTS`]
//! triangle tests, as a baseline ratio; the BVH's answers on that sample are checked against it.

use crate::atomic::write_bytes_atomic;
use crate::error::{Error, Location, Result};
use crate::obj::read_obj;
use crate::raysets::{Camera, random_rays};
use halfray_core::Ray;
use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, TraversalStats, TriangleMesh};
use halfray_core::bvh::{DEFAULT_MAX_LEAF_SIZE, index_capacity, node_capacity};
use halfray_core::triangle::{
    Cramer, F64Reference, MollerTrumbore, TriangleIntersector, TriangleVariant, Watertight,
    WatertightF32,
};
use std::path::PathBuf;
use std::time::Instant;

/// Seed of the incoherent ray set.
pub const INCOHERENT_SEED: u64 = 0xB7B7_0001;
/// Timed passes per measurement (the best is reported: the machines are noisy).
pub const TIMED_PASSES: usize = 3;
/// Target number of triangle tests of the brute-force baseline.
pub const BRUTE_FORCE_TESTS: usize = 150_000_000;

/// Arguments of `halfray bench bvh`.
#[derive(clap::Args, Debug, Clone)]
pub struct BvhArgs {
    /// Mesh to benchmark (OBJ).
    pub mesh: PathBuf,
    /// Also write the results as JSON to this file (atomically).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Camera image width and height for the primary rays.
    #[arg(long, default_value_t = 1024)]
    pub width: usize,
    /// Number of incoherent random rays.
    #[arg(long, default_value_t = 1_000_000)]
    pub rays: usize,
    /// Triangle intersector (watertight, watertight-f32, moller-trumbore,
    /// moller-trumbore-noeps, cramer, f64-reference).
    #[arg(long, default_value = "watertight")]
    pub intersector: String,
    /// Maximum leaf size of the build.
    #[arg(long, default_value_t = DEFAULT_MAX_LEAF_SIZE)]
    pub leaf_size: u32,
}

/// Everything measured, as written to the JSON file.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BvhReport {
    /// Mesh path.
    pub mesh: String,
    /// Intersector name.
    pub intersector: String,
    /// Triangles in the mesh.
    pub triangles: usize,
    /// Build time, milliseconds (best of the timed builds).
    pub build_ms: f64,
    /// Nodes in use.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Depth of the deepest leaf.
    pub max_depth: usize,
    /// SAH cost relative to the root area.
    pub sah_cost: f64,
    /// Bytes of nodes + indices per triangle.
    pub bytes_per_triangle: f64,
    /// Primary rays per set.
    pub primary_rays: usize,
    /// Incoherent rays per set.
    pub incoherent_rays: usize,
    /// Closest hit, primary rays, Mrays/s.
    pub mrays_closest_primary: f64,
    /// Any hit, primary rays, Mrays/s.
    pub mrays_any_primary: f64,
    /// Closest hit, incoherent rays, Mrays/s.
    pub mrays_closest_incoherent: f64,
    /// Any hit, incoherent rays, Mrays/s.
    pub mrays_any_incoherent: f64,
    /// Share of primary rays that hit.
    pub hit_rate_primary: f64,
    /// Share of incoherent rays that hit.
    pub hit_rate_incoherent: f64,
    /// Mean node boxes tested per primary closest-hit ray.
    pub nodes_per_ray_primary: f64,
    /// Mean triangle tests per primary closest-hit ray.
    pub triangles_per_ray_primary: f64,
    /// Mean node boxes tested per incoherent closest-hit ray.
    pub nodes_per_ray_incoherent: f64,
    /// Mean triangle tests per incoherent closest-hit ray.
    pub triangles_per_ray_incoherent: f64,
    /// Brute-force sample size (incoherent rays).
    pub brute_force_rays: usize,
    /// Brute-force closest hit, Mrays/s.
    pub mrays_brute_force: f64,
    /// `mrays_closest_incoherent / mrays_brute_force`.
    pub speedup_over_brute_force: f64,
    /// Sample rays where the BVH and brute force disagree (must be 0).
    pub brute_force_mismatches: usize,
}

/// Runs the BVH benchmark.
pub fn run(args: &BvhArgs) -> Result<()> {
    let variant = TriangleVariant::from_name(&args.intersector).ok_or_else(|| {
        Error::Usage(format!(
            "unknown intersector `{}` (expected one of: {})",
            args.intersector,
            TriangleVariant::ALL.map(TriangleVariant::name).join(", ")
        ))
    })?;
    if args.width == 0 {
        return Err(Error::Usage("--width must be at least 1".into()));
    }
    let report = match variant {
        TriangleVariant::Watertight => bench(args, &Watertight)?,
        TriangleVariant::WatertightF32 => bench(args, &WatertightF32)?,
        TriangleVariant::MollerTrumbore => bench(args, &MollerTrumbore::CLASSIC)?,
        TriangleVariant::MollerTrumboreNoEps => bench(args, &MollerTrumbore::NO_EPSILON)?,
        TriangleVariant::Cramer => bench(args, &Cramer)?,
        TriangleVariant::F64Reference => bench(args, &F64Reference)?,
    };
    print_report(&report);
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&report)
            .map_err(|e| Error::Other(format!("JSON encoding failed: {e}")))?;
        write_bytes_atomic(path, text.as_bytes())?;
    }
    Ok(())
}

type VecBvh = Bvh<Vec<BvhNode>, Vec<u32>>;

fn bench<T: TriangleIntersector>(args: &BvhArgs, isect: &T) -> Result<BvhReport> {
    let obj = read_obj(&args.mesh)?;
    let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
    let n = mesh.len();
    let options = BuildOptions {
        max_leaf_size: args.leaf_size,
        exclude_non_finite: false,
    };
    let mut build_s = f64::INFINITY;
    let mut bvh: Option<VecBvh> = None;
    for _ in 0..TIMED_PASSES {
        let nodes = vec![BvhNode::EMPTY; node_capacity(n) + 1];
        let indices = vec![0u32; index_capacity(n)];
        let t0 = Instant::now();
        let built = Bvh::build(&mesh, nodes, indices, &options)
            .map_err(|e| Error::input(Location::file(&args.mesh), e.to_string()))?;
        build_s = build_s.min(t0.elapsed().as_secs_f64());
        bvh = Some(built);
    }
    let bvh = bvh.ok_or_else(|| Error::Other("no build".into()))?;
    let stats = bvh.stats();

    let (lo, hi) = obj.bounds().unwrap_or((glam::Vec3::ZERO, glam::Vec3::ONE));
    let primary = Camera::framing(lo, hi, args.width, args.width).rays();
    let incoherent = random_rays(lo, hi, args.rays, INCOHERENT_SEED);

    let closest = |r: &Ray| bvh.closest_hit_triangles(&mesh, isect, r, None).is_some();
    let any = |r: &Ray| bvh.any_hit_triangles(&mesh, isect, r, None).is_some();
    let (mrays_closest_primary, hits_p) = throughput(&primary, closest);
    let (mrays_any_primary, any_p) = throughput(&primary, any);
    let (mrays_closest_incoherent, hits_i) = throughput(&incoherent, closest);
    let (mrays_any_incoherent, any_i) = throughput(&incoherent, any);
    if hits_p != any_p || hits_i != any_i {
        return Err(Error::Other(format!(
            "any-hit disagrees with closest-hit on hit/miss: primary {hits_p} vs {any_p}, incoherent {hits_i} vs {any_i}"
        )));
    }
    let per_ray = |rays: &[Ray]| {
        let mut st = TraversalStats::default();
        for r in rays {
            let _ = bvh.closest_hit_triangles(&mesh, isect, r, Some(&mut st));
        }
        let k = rays.len().max(1) as f64;
        (st.nodes_visited as f64 / k, st.primitives_tested as f64 / k)
    };
    let (nodes_p, tris_p) = per_ray(&primary);
    let (nodes_i, tris_i) = per_ray(&incoherent);

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
            bvh.closest_hit_triangles(&mesh, isect, r, None)
                .map(|(p, h)| (p, h.t))
                != **b
        })
        .count();
    let mrays_brute = sample_len as f64 / brute_s.max(1e-9) / 1e6;

    Ok(BvhReport {
        mesh: args.mesh.display().to_string(),
        intersector: isect.name().to_string(),
        triangles: n,
        build_ms: build_s * 1e3,
        nodes: stats.nodes,
        leaves: stats.leaves,
        max_depth: stats.max_depth,
        sah_cost: stats.sah_cost,
        bytes_per_triangle: stats.bytes_per_primitive,
        primary_rays: primary.len(),
        incoherent_rays: incoherent.len(),
        mrays_closest_primary,
        mrays_any_primary,
        mrays_closest_incoherent,
        mrays_any_incoherent,
        hit_rate_primary: hits_p as f64 / primary.len().max(1) as f64,
        hit_rate_incoherent: hits_i as f64 / incoherent.len().max(1) as f64,
        nodes_per_ray_primary: nodes_p,
        triangles_per_ray_primary: tris_p,
        nodes_per_ray_incoherent: nodes_i,
        triangles_per_ray_incoherent: tris_i,
        brute_force_rays: sample_len,
        mrays_brute_force: mrays_brute,
        speedup_over_brute_force: mrays_closest_incoherent / mrays_brute.max(1e-12),
        brute_force_mismatches: mismatches,
    })
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
fn brute_force<T: TriangleIntersector>(
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
        "bench bvh: {} ({} triangles, {})",
        r.mesh, r.triangles, r.intersector
    );
    println!(
        "  build            {:9.1} ms   nodes {}  leaves {}  depth {}  SAH {:.1}",
        r.build_ms, r.nodes, r.leaves, r.max_depth, r.sah_cost
    );
    println!(
        "  size             {:9.1} bytes/triangle (nodes 32 B + indices 4 B)",
        r.bytes_per_triangle
    );
    println!(
        "  {:<16} {:>9} {:>9} {:>9} {:>11} {:>10}",
        "rays (1 thread)", "closest", "any", "hit rate", "nodes/ray", "tris/ray"
    );
    println!(
        "  {:<16} {:>9.2} {:>9.2} {:>8.1}% {:>11.1} {:>10.1}   Mrays/s, {} rays",
        "primary",
        r.mrays_closest_primary,
        r.mrays_any_primary,
        100.0 * r.hit_rate_primary,
        r.nodes_per_ray_primary,
        r.triangles_per_ray_primary,
        r.primary_rays
    );
    println!(
        "  {:<16} {:>9.2} {:>9.2} {:>8.1}% {:>11.1} {:>10.1}   Mrays/s, {} rays",
        "incoherent",
        r.mrays_closest_incoherent,
        r.mrays_any_incoherent,
        100.0 * r.hit_rate_incoherent,
        r.nodes_per_ray_incoherent,
        r.triangles_per_ray_incoherent,
        r.incoherent_rays
    );
    println!(
        "  brute force      {:9.1} rays/s on {} incoherent rays: BVH is {:.0}x faster; mismatches {}",
        r.mrays_brute_force * 1e6,
        r.brute_force_rays,
        r.speedup_over_brute_force,
        r.brute_force_mismatches
    );
}
