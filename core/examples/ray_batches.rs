//! Ray batches against single rays: the 8-wide BVH over each mesh, the same rays traced by
//! [`RayQuery::closest_hit`] one by one (in the set's order) and by [`RayQuery::closest_hits`]
//! (reordered in chunks), both on the same SIMD level and the same kept stack. Prints each
//! set's Mrays/s and the ratio batch/single; every answer is checked equal.
//!
//! ```sh
//! cargo run --release -p halfray-core --example ray_batches -- ../shared/meshes/bunny.obj ../shared/meshes/dragon.obj
//! ```
//! Sets (`width²` = 102 400 rays each, camera framing the mesh's box from -z): camera rays in
//! scanline order, in 8×8 tiles, every 7th scanline ray (stride), and uniform random rays
//! (origins and targets in the box grown ×3, seeded). Timing: see [`time`].

#[path = "common/obj.rs"]
mod obj;

use halfray_core::bvh::wide::{Bvh8, LeafGroup, WideNode, binary_options, group_capacity};
use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, node_capacity};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{Query, QueryStack, Triangles};
use halfray_core::simd_level::{Portable, SimdLevel};
use halfray_core::triangle::{TriangleHit, Watertight};
use halfray_core::{Ray, Vec3};
use std::time::Instant;

/// Timed passes per block; the best is kept.
const PASSES: usize = 9;
/// Rays per timed block (16 batch chunks).
const BLOCK: usize = 4096;
/// Image side of the camera sets.
const WIDTH: usize = 320;
/// Subsampling step of the strided camera set.
const STRIDE: usize = 7;

type Answer = Option<(u32, TriangleHit)>;

fn camera(lo: Vec3, hi: Vec3) -> impl Fn(usize, usize) -> Ray {
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
    let eye = c - Vec3::Z * (2.5 * r);
    move |x, y| {
        let s = |i: usize| (i as f32 + 0.5) / WIDTH as f32 * 2.0 - 1.0;
        let target = c + Vec3::new(s(x) * r, -s(y) * r, 0.0);
        Ray::new(eye, target - eye)
    }
}

fn sets(lo: Vec3, hi: Vec3) -> Vec<(&'static str, Vec<Ray>)> {
    let cam = camera(lo, hi);
    let n = WIDTH * WIDTH;
    let scan: Vec<Ray> = (0..n).map(|k| cam(k % WIDTH, k / WIDTH)).collect();
    let tiles = (0..n)
        .map(|k| {
            let (tile, i) = (k / 64, k % 64);
            let tiles_x = WIDTH / 8;
            cam((tile % tiles_x) * 8 + i % 8, (tile / tiles_x) * 8 + i / 8)
        })
        .collect();
    let stride = (0..n).map(|k| scan[(k * STRIDE) % n]).collect();
    let mut s = 0x5EED_u64;
    let mut f = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let (c, size) = ((lo + hi) * 0.5, (hi - lo) * 3.0);
    let mut p = move || c + (Vec3::new(f(), f(), f()) - Vec3::splat(0.5)) * size;
    let random = (0..n)
        .map(|_| {
            let o = p();
            Ray::new(o, p() - o)
        })
        .collect();
    vec![
        ("primary", scan),
        ("primary-tiles", tiles),
        ("primary-stride", stride),
        ("random", random),
    ]
}

/// Seconds of single rays and of the batch over `rays`, answers checked equal: the rays are
/// timed in blocks of [`BLOCK`], each block [`PASSES`] times round-robin (single, batch,
/// single, ...), and the best time of each block summed per side, so that a preemption of the
/// shared machine (a block takes about a millisecond) spoils one pass of one block, not a
/// figure. Inlined whole into [`time_avx2`], so both sides are compiled for the same target
/// features.
#[inline(always)]
fn time<L: SimdLevel>(
    level: L,
    q: &impl RayQuery,
    tris: &mut Triangles<'_, Watertight>,
    rays: &[Ray],
) -> (f64, f64) {
    let mut stack = QueryStack::new();
    let (mut single, mut batch) = (vec![None; rays.len()], vec![None; rays.len()]);
    let (mut sum_single, mut sum_batch) = (0.0, 0.0);
    for (rays, (single, batch)) in rays
        .chunks(BLOCK)
        .zip(single.chunks_mut(BLOCK).zip(batch.chunks_mut(BLOCK)))
    {
        let (mut best_single, mut best_batch) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..PASSES {
            let t0 = Instant::now();
            let mut ctx = Query::new().on(level).stack(&mut stack);
            for (o, r) in single.iter_mut().zip(rays) {
                *o = q.closest_hit(std::hint::black_box(r), tris, &mut ctx);
            }
            best_single = best_single.min(t0.elapsed().as_secs_f64());
            let t0 = Instant::now();
            let mut ctx = Query::new().on(level).stack(&mut stack);
            q.closest_hits(std::hint::black_box(rays), tris, &mut ctx, batch)
                .expect("lengths match");
            best_batch = best_batch.min(t0.elapsed().as_secs_f64());
        }
        (sum_single, sum_batch) = (sum_single + best_single, sum_batch + best_batch);
    }
    let bits = |a: &Answer| a.map(|(p, h)| (p, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()));
    assert!(
        single.iter().zip(&batch).all(|(a, b)| bits(a) == bits(b)),
        "batch != single"
    );
    (sum_single, sum_batch)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn time_avx2(q: &impl RayQuery, tris: &mut Triangles<'_, Watertight>, rays: &[Ray]) -> (f64, f64) {
    // SAFETY: called only after `is_x86_feature_detected!` found AVX2 and FMA, the token's
    // one requirement.
    time(
        unsafe { halfray_core::simd_level::Avx2Fma::new_unchecked() },
        q,
        tris,
        rays,
    )
}

fn main() {
    for path in std::env::args().skip(1) {
        let (pos, tri) = obj::load(&path);
        let mesh = TriangleMesh::new(&pos, &tri);
        let n = mesh.len();
        let binary = Bvh::build(
            &mesh,
            vec![BvhNode::EMPTY; node_capacity(n)],
            vec![0u32; index_capacity(n)],
            &binary_options(BuildOptions::default()),
        )
        .expect("build");
        let nodes = vec![WideNode::EMPTY; halfray_core::bvh::wide::node_capacity(n)];
        let groups = vec![LeafGroup::EMPTY; group_capacity(n)];
        let bvh8 = Bvh8::from_binary(&binary, &mesh, nodes, groups).expect("collapse");
        let (lo, hi) = pos
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), &p| {
                (l.min(p), h.max(p))
            });
        let mut tris = Triangles::new(&mesh, &Watertight);
        for (name, rays) in sets(lo, hi) {
            #[cfg(target_arch = "x86_64")]
            let avx2 = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
            #[cfg(not(target_arch = "x86_64"))]
            let avx2 = false;
            let (single, batch) = if avx2 {
                // SAFETY: AVX2 and FMA were detected just above.
                #[cfg(target_arch = "x86_64")]
                unsafe {
                    time_avx2(&bvh8, &mut tris, &rays)
                }
                #[cfg(not(target_arch = "x86_64"))]
                unreachable!()
            } else {
                time(Portable, &bvh8, &mut tris, &rays)
            };
            let m = |s: f64| rays.len() as f64 / s / 1e6;
            println!(
                "{path}  {name:15} {} rays  single {:6.2} Mrays/s  batch {:6.2} Mrays/s  batch/single {:.3}x  [{}]",
                rays.len(),
                m(single),
                m(batch),
                single / batch,
                if avx2 { "avx2+fma" } else { "portable" }
            );
        }
    }
}
