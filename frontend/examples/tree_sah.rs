//! The wide tree's shape in the terms of Embree's BVH statistics, to set beside what an
//! Embree device created with `verbose=2` prints after each build.
//!
//! ```sh
//! cargo run --release -p halfray --example tree_sah -- MESH.obj [MESH.obj …]
//! ```
//!
//! Embree's convention (`kernels/bvh/bvh_statistics.cpp`): every inner node costs its box's
//! half area, every leaf its half area times its blocks of four triangles, both over the
//! root's half area; a node's box is the one its parent holds for it, the root's the tree's
//! bounds. Here a leaf's blocks are the four-triangle groups its run spans, and, since the
//! leaf test culls two groups per eight-lane call, the leaf term is also given per call.
//! Only the tree's shape is measured: no ray is traced.

use halfray::accel::{build_binary, build_wide};
use halfray::obj::read_obj;
use halfray_core::aabb::Aabb;
use halfray_core::bvh::BuildOptions;
use halfray_core::bvh::wide::{ChildRef, binary_options};
use halfray_core::mesh::TriangleMesh;

/// The surface area of `b` ([`Aabb::surface_area`], 0 for an empty box), in `f64` for the
/// sums: only its ratio to the root's is reported, so half areas and whole ones agree.
fn area(b: &Aabb) -> f64 {
    f64::from(b.surface_area())
}

/// Sums over one tree.
#[derive(Default)]
struct Shape {
    inner: usize,
    children: usize,
    leaves: usize,
    groups: usize,
    node_sah: f64,
    group_sah: f64,
    call_sah: f64,
}

fn main() {
    for mesh in std::env::args().skip(1) {
        let obj = read_obj(std::path::Path::new(&mesh)).unwrap_or_else(|e| panic!("{mesh}: {e}"));
        let tris = TriangleMesh::new(&obj.positions, &obj.triangles);
        let binary = build_binary(&tris, &binary_options(BuildOptions::default())).expect("build");
        let wide = build_wide(&tris, &binary).expect("collapse");
        let root = area(&wide.bounds());
        let mut s = Shape::default();
        let mut todo = vec![(wide.root(), root)];
        while let Some((child, a)) = todo.pop() {
            match child {
                ChildRef::Inner(i) => {
                    let node = &wide.nodes()[i as usize];
                    s.inner += 1;
                    s.node_sah += a;
                    for k in 0..8 {
                        if node.child(k) != ChildRef::Empty {
                            s.children += 1;
                            todo.push((node.child(k), area(&node.child_bounds(k))));
                        }
                    }
                }
                ChildRef::Leaf { start, count } => {
                    let groups = ((start % 4 + count) as usize).div_ceil(4);
                    s.leaves += 1;
                    s.groups += groups;
                    s.group_sah += a * groups as f64;
                    s.call_sah += a * groups.div_ceil(2) as f64;
                }
                ChildRef::Empty => {}
            }
        }
        let n = obj.triangles.len();
        println!(
            "{mesh}: {n} triangles; SAH {:.3} = inner nodes {:.3} + leaves {:.3} \
             (per eight-lane call {:.3}); {} inner nodes, {:.1} % of slots used; \
             {} leaves, {:.2} triangles each, in {} groups, {:.1} % filled",
            (s.node_sah + s.group_sah) / root,
            s.node_sah / root,
            s.group_sah / root,
            s.call_sah / root,
            s.inner,
            100.0 * s.children as f64 / (8 * s.inner.max(1)) as f64,
            s.leaves,
            n as f64 / s.leaves.max(1) as f64,
            s.groups,
            100.0 * n as f64 / (4 * s.groups.max(1)) as f64,
        );
    }
}
