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
use halfray_core::triangle::LANES;

/// The surface area of `b` ([`Aabb::surface_area`], 0 for an empty box), in `f64` for the
/// sums: only its ratio to the root's is reported, so half areas and whole ones agree.
fn area(b: &Aabb) -> f64 {
    f64::from(b.surface_area())
}

/// The area sums over one tree (its counts of nodes, slots and leaves are `WideBvh::stats`').
#[derive(Default)]
struct Sums {
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
        let mut s = Sums::default();
        let mut todo = vec![(wide.root(), root)];
        while let Some((child, a)) = todo.pop() {
            match child {
                ChildRef::Inner(i) => {
                    let node = &wide.nodes()[i as usize];
                    s.node_sah += a;
                    for k in 0..8 {
                        if node.child(k) != ChildRef::Empty {
                            todo.push((node.child(k), area(&node.child_bounds(k))));
                        }
                    }
                }
                ChildRef::Leaf { start, count } => {
                    let groups = wide.leaf_groups(start, count).len();
                    s.groups += groups;
                    s.group_sah += a * groups as f64;
                    s.call_sah += a * groups.div_ceil(2) as f64;
                }
                ChildRef::Empty => {}
            }
        }
        let n = obj.triangles.len();
        let shape = wide.stats();
        println!(
            "{mesh}: {n} triangles; SAH {:.3} = inner nodes {:.3} + leaves {:.3} \
             (per eight-lane call {:.3}); {} inner nodes, {:.1} % of slots used; \
             {} leaves, {:.2} triangles each, in {} groups, {:.1} % filled",
            (s.node_sah + s.group_sah) / root,
            s.node_sah / root,
            s.group_sah / root,
            s.call_sah / root,
            shape.nodes,
            100.0 * shape.children as f64 / (8 * shape.nodes.max(1)) as f64,
            shape.leaves,
            n as f64 / shape.leaves.max(1) as f64,
            s.groups,
            100.0 * n as f64 / (LANES * s.groups.max(1)) as f64,
        );
    }
}
