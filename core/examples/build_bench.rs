//! Build time of the default structure, by phase: the binary scratch build with the wide tree's
//! options ([`binary_options`]) and its collapse into the 8-wide tree, on one thread, best of
//! [`PASSES`]; for profiling the builder without the frontend (`perf record` on this binary).
//!
//! ```sh
//! cargo run --release -p halfray-core --example build_bench -- ../shared/meshes/dragon.obj
//! ```
//! Prints per mesh: triangles, the wide tree's bytes per triangle (nodes and triangle groups),
//! the binary tree's SAH cost (relative to the root's area: the split quality), a fingerprint
//! of the binary tree (FNV-1a over every node's raw fields and the index array: two builds
//! print the same one when they built the same tree), and each phase's best wall-clock and CPU
//! time (ms).

#[path = "common/obj.rs"]
mod obj;

use halfray_core::bvh::wide::{Bvh8, LeafGroup, WideNode, binary_options};
use halfray_core::bvh::{
    BuildOptions, Bvh, BvhNode, PrimRef, index_capacity, node_capacity, scratch_capacity,
};
use halfray_core::mesh::TriangleMesh;
use std::time::Instant;

/// Timed passes per mesh; the best of each phase is kept.
const PASSES: usize = 5;

/// This thread's time on a CPU so far, s, where Linux reports it (`/proc/thread-self/schedstat`,
/// first field, ns): on a shared machine it moves less than the wall clock. `None` elsewhere.
fn cpu_time() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// A phase's best wall-clock and CPU time over the passes, s.
#[derive(Clone, Copy)]
struct Best {
    wall: f64,
    cpu: f64,
}

impl Best {
    const NONE: Self = Self {
        wall: f64::INFINITY,
        cpu: f64::INFINITY,
    };

    /// Times `f` once, keeping the better figures.
    fn time<R>(&mut self, f: impl FnOnce() -> R) -> R {
        let (t0, c0) = (Instant::now(), cpu_time());
        let r = f();
        self.wall = self.wall.min(t0.elapsed().as_secs_f64());
        if let (Some(c0), Some(c1)) = (c0, cpu_time()) {
            self.cpu = self.cpu.min(c1 - c0);
        }
        r
    }
}

/// FNV-1a (64-bit) over the binary tree's nodes (box bits, start, count) and index array.
fn fingerprint(bvh: &Bvh<Vec<BvhNode>, Vec<u32>>) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |w: u32| {
        for b in w.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for n in bvh.nodes() {
        let (bounds, start, count) = n.to_raw();
        bounds.iter().flatten().for_each(|v| eat(v.to_bits()));
        eat(start);
        eat(count);
    }
    bvh.indices().iter().for_each(|&i| eat(i));
    h
}

fn main() {
    let options = binary_options(BuildOptions::default());
    for path in std::env::args().skip(1) {
        let (pos, tri) = obj::load(&path);
        let mesh = TriangleMesh::new(&pos, &tri);
        let n = mesh.len();
        let (mut binary_t, mut wide_t) = (Best::NONE, Best::NONE);
        let mut bytes = 0.0;
        let mut sah = 0.0;
        let mut print = 0;
        for _ in 0..PASSES {
            let binary = binary_t.time(|| {
                Bvh::build_with_scratch(
                    &mesh,
                    vec![BvhNode::EMPTY; node_capacity(n)],
                    vec![0u32; index_capacity(n)],
                    &mut vec![PrimRef::EMPTY; scratch_capacity(n)],
                    &options,
                )
                .expect("build")
            });
            sah = binary.stats().sah_cost;
            print = fingerprint(&binary);
            let wide: Bvh8<Vec<WideNode<8>>, Vec<LeafGroup>> = wide_t.time(|| {
                Bvh8::from_binary_with(&binary, &mesh, |nodes, groups| {
                    (vec![WideNode::EMPTY; nodes], vec![LeafGroup::EMPTY; groups])
                })
                .expect("collapse")
            });
            bytes =
                (size_of_val(wide.nodes()) + size_of_val(wide.groups())) as f64 / n.max(1) as f64;
        }
        println!(
            "{path}: {n} triangles, {bytes:.1} B/tri, binary SAH cost {sah:.3}, tree {print:016x}; wall ms: binary {:.1}, collapse {:.1}, total {:.1}; CPU ms: binary {:.1}, collapse {:.1}, total {:.1}",
            binary_t.wall * 1e3,
            wide_t.wall * 1e3,
            (binary_t.wall + wide_t.wall) * 1e3,
            binary_t.cpu * 1e3,
            wide_t.cpu * 1e3,
            (binary_t.cpu + wide_t.cpu) * 1e3,
        );
    }
}
