//! The batch path against single rays on the benchmark's camera sets, one side per run (for
//! callgrind) or both timed in one run.
//!
//! ```sh
//! cargo build --release -p halfray --example batch_vs_single
//! # instructions of one side (SIDE: single or batch):
//! valgrind --tool=callgrind --toggle-collect='batch_vs_single::run_SIDE' \
//!     target/release/examples/batch_vs_single MESH.obj primary-stride 128 SIDE
//! # both sides timed: blocks of 4096 rays, five passes alternating single and batch, the best
//! # of each block summed, three rounds:
//! target/release/examples/batch_vs_single MESH.obj primary-stride 1024 time
//! ```
//! Rays: `halfray bench bvh`'s sets (`width²` rays). Single rays: `closest_simd` one by one;
//! batch: `closest_batch_simd` over the block into a kept buffer (as the benchmark's batch
//! side). `stats` prints nodes and triangles per ray of both.

use halfray::accel::{
    Answer, VecBvh8, any_batch_simd, any_simd, build_binary, build_wide, closest_batch_simd,
    closest_simd,
};
use halfray::obj::read_obj;
use halfray::raysets::named::{RaySet, watertight_hits};
use halfray_core::Ray;
use halfray_core::bvh::BuildOptions;
use halfray_core::bvh::wide::binary_options;
use halfray_core::mesh::TriangleMesh;
use halfray_core::query::TraversalStats;
use halfray_core::triangle::Watertight;
use std::time::Instant;

/// Rays per timed block.
const BLOCK: usize = 4096;

#[inline(never)]
fn run_single(w: &VecBvh8, m: &TriangleMesh<'_>, rays: &[Ray], any: bool) -> usize {
    rays.iter()
        .filter(|r| {
            let r = std::hint::black_box(r);
            if any {
                any_simd(w, m, &Watertight, r).is_some()
            } else {
                closest_simd(w, m, &Watertight, r, None).is_some()
            }
        })
        .count()
}

#[inline(never)]
fn run_batch(
    w: &VecBvh8,
    m: &TriangleMesh<'_>,
    rays: &[Ray],
    out: &mut [Answer],
    any: bool,
) -> usize {
    let out = &mut out[..rays.len()];
    if any {
        any_batch_simd(w, m, &Watertight, rays, out, None).expect("lengths match");
    } else {
        closest_batch_simd(w, m, &Watertight, rays, out, None).expect("lengths match");
    }
    out.iter().filter(|h| h.is_some()).count()
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let [_, mesh, set, width, side] = &a[..] else {
        eprintln!("usage: batch_vs_single MESH.obj SET WIDTH single|batch|time|stats");
        std::process::exit(2);
    };
    let obj = read_obj(std::path::Path::new(mesh)).expect("mesh");
    let set = <RaySet as clap::ValueEnum>::from_str(set, true).expect("set");
    let width: usize = width.parse().expect("width");
    let tris = TriangleMesh::new(&obj.positions, &obj.triangles);
    let binary = build_binary(&tris, &binary_options(BuildOptions::default())).expect("build");
    let w = build_wide(&tris, &binary).expect("collapse");
    let (lo, hi) = obj.bounds().expect("bounds");
    let hits = watertight_hits(&w, &obj);
    let rays = set.generate(lo, hi, width * width, 0x5eed, &hits);
    let mut out = vec![None; rays.len()];
    // The any-hit sets (shadow, ao) time the any-hit queries.
    let any = matches!(set, RaySet::Shadow | RaySet::Ao);
    match side.as_str() {
        "single" => println!("{} hits", run_single(&w, &tris, &rays, any)),
        "batch" => println!("{} hits", run_batch(&w, &tris, &rays, &mut out, any)),
        "stats" => {
            let (mut single, mut batch) = (TraversalStats::default(), TraversalStats::default());
            for r in &rays {
                closest_simd(&w, &tris, &Watertight, r, Some(&mut single));
            }
            closest_batch_simd(&w, &tris, &Watertight, &rays, &mut out, Some(&mut batch))
                .expect("lengths match");
            let k = rays.len() as f64;
            let per =
                |s: &TraversalStats| (s.nodes_visited as f64 / k, s.primitives_tested as f64 / k);
            println!(
                "single nodes, triangles per ray {:.2?}; batch {:.2?}",
                per(&single),
                per(&batch)
            );
        }
        _ => {
            let (mut single, mut batch) = (0.0, 0.0);
            for _ in 0..3 {
                for block in rays.chunks(BLOCK) {
                    let (mut s, mut b) = (f64::INFINITY, f64::INFINITY);
                    for _ in 0..5 {
                        let t = Instant::now();
                        std::hint::black_box(run_single(&w, &tris, block, any));
                        s = s.min(t.elapsed().as_secs_f64());
                        let t = Instant::now();
                        std::hint::black_box(run_batch(&w, &tris, block, &mut out, any));
                        b = b.min(t.elapsed().as_secs_f64());
                    }
                    (single, batch) = (single + s, batch + b);
                }
            }
            println!(
                "{mesh} {set}: batch speed over single rays {:.3}x",
                single / batch
            );
        }
    }
}
