//! Unit tests of the wide BVH: every query against an independent brute-force loop.

use super::*;
use crate::aabb::Aabb;
use crate::bvh::{BuildOptions, Bvh, BvhError, BvhNode, index_capacity};
use crate::mesh::TriangleMesh;
use crate::prelude::*;
use crate::query::{Query, QueryError, QueryStack, StackEntry, TraversalStats, Triangles};
use crate::ray::Ray;
use crate::simd::level::Portable;
use crate::test_util::{brute_box, lcg, unit_vec};
use crate::triangle::{MollerTrumbore, TriangleIntersector, Watertight};
use glam::Vec3;
use std::vec;
use std::vec::Vec;

type VecBinary = Bvh<Vec<BvhNode>, Vec<u32>>;
type VecWide<const W: usize> = WideBvh<W, Vec<WideNode<W>>, Vec<LeafGroup>>;

fn binary(mesh: &TriangleMesh<'_>, max_leaf: u32) -> VecBinary {
    built(
        mesh,
        &BuildOptions {
            max_leaf_size: max_leaf,
            ..BuildOptions::default()
        },
    )
}

/// The binary tree over `mesh` with `options`, in storage of the exact capacity.
fn built(mesh: &TriangleMesh<'_>, options: &BuildOptions) -> VecBinary {
    let n = mesh.len();
    Bvh::build(
        mesh,
        vec![BvhNode::EMPTY; crate::bvh::node_capacity(n)],
        vec![0u32; index_capacity(n)],
        options,
    )
    .unwrap()
}

fn wide<const W: usize>(mesh: &TriangleMesh<'_>, max_leaf: u32) -> VecWide<W> {
    let b = binary(mesh, max_leaf);
    let count = VecWide::<W>::node_count_for(&b).unwrap();
    let w = VecWide::<W>::from_binary(
        &b,
        mesh,
        vec![WideNode::EMPTY; count],
        vec![LeafGroup::EMPTY; group_capacity(mesh.len())],
    )
    .unwrap();
    assert_eq!(w.node_count(), count, "node_count_for is exact");
    w
}

/// Random triangles of size ~1 in a cube of side 10.
fn soup(n: usize, seed: u64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut s = seed;
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for i in 0..n {
        let c = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 10.0 - 5.0;
        for _ in 0..3 {
            pos.push(c + unit_vec(&mut s) * lcg(&mut s));
        }
        let b = 3 * i as u32;
        tris.push([b, b + 1, b + 2]);
    }
    (pos, tris)
}

/// Closest hit by testing every triangle: smallest `t`, ties to the smaller index.
fn brute<I: TriangleIntersector>(
    mesh: &TriangleMesh<'_>,
    isect: &I,
    ray: &Ray,
) -> Option<(u32, f32)> {
    let mut best: Option<(u32, f32)> = None;
    for i in 0..mesh.len() {
        let Some(v) = mesh.triangle(i) else { continue };
        if let Some(h) = isect.intersect(ray, &v)
            && best.is_none_or(|(_, t)| h.t < t)
        {
            best = Some((i as u32, h.t));
        }
    }
    best
}

fn rays(n: usize, seed: u64) -> Vec<Ray> {
    let mut s = seed;
    (0..n)
        .map(|i| {
            let o = unit_vec(&mut s) * 12.0;
            let target = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 8.0 - 4.0;
            let mut r = Ray::new(o, target - o);
            if i % 5 == 0 {
                r.t_max = lcg(&mut s) * 1.5;
            }
            if i % 7 == 0 {
                r.t_min = -lcg(&mut s);
            }
            r
        })
        .collect()
}

fn check_against_brute<const W: usize>(n: usize, seed: u64, max_leaf: u32) {
    let (pos, tris) = soup(n, seed);
    let mesh = TriangleMesh::new(&pos, &tris);
    let w = wide::<W>(&mesh, max_leaf);
    let mut hits = 0;
    for ray in rays(3000, seed ^ 0xABCD) {
        let got = w
            .closest_hit(
                &ray,
                &mut Triangles::new(&mesh, &Watertight),
                &mut Query::new(),
            )
            .map(|(p, h)| (p, h.t));
        assert_eq!(got, brute(&mesh, &Watertight, &ray), "W={W} {ray:?}");
        // The closure queries, which cull nothing, see every lane of every leaf they visit:
        // the triangles counted as tested are the closure's calls.
        let (mut calls, mut st) = (0u64, TraversalStats::default());
        let by_closure = w.closest_hit(
            &ray,
            &mut |p, r: &Ray| {
                calls += 1;
                let v = mesh.triangle(p as usize)?;
                Watertight.intersect(r, &v).map(|h| (h.t, h.t))
            },
            &mut Query::new().stats(&mut st),
        );
        assert_eq!(by_closure, got, "closure query, W={W} {ray:?}");
        assert_eq!(st.primitives_tested, calls, "{ray:?}");
        let any_by_closure = w.any_hit(
            &ray,
            &mut |p, r: &Ray| {
                Watertight
                    .intersect(r, &mesh.triangle(p as usize)?)
                    .map(|h| (h.t, ()))
            },
            &mut Query::new(),
        );
        assert_eq!(
            any_by_closure.is_some(),
            got.is_some(),
            "closure any-hit {ray:?}"
        );
        let got_mt = w
            .closest_hit(
                &ray,
                &mut Triangles::new(&mesh, &MollerTrumbore::NO_EPSILON),
                &mut Query::new(),
            )
            .map(|(p, h)| (p, h.t));
        assert_eq!(got_mt, brute(&mesh, &MollerTrumbore::NO_EPSILON, &ray));
        let any = w.any_hit(
            &ray,
            &mut Triangles::new(&mesh, &Watertight),
            &mut Query::new(),
        );
        assert_eq!(any.is_some(), got.is_some(), "{ray:?}");
        if let Some((p, h)) = any {
            let v = mesh.triangle(p as usize).unwrap();
            assert_eq!(Watertight.intersect(&ray, &v).map(|x| x.t), Some(h.t));
        }
        hits += usize::from(got.is_some());
        same_at_every_level(&w, &mesh, &ray);
    }
    let want = if n >= 300 { 500 } else { 1 };
    assert!(hits >= want, "the rays must hit something: {hits} of 3000");
}

/// The AVX2 kernels (where the CPU has them: node test, key sort, lane cull, the hit's plane
/// form of `t`) give the portable answers, bit for bit, and statistics.
fn same_at_every_level<const W: usize>(w: &VecWide<W>, mesh: &TriangleMesh<'_>, ray: &Ray) {
    #[cfg(target_arch = "x86_64")]
    if let Some(level) = crate::test_util::avx2_or_skip(
        "bvh::wide::tests::closest_and_any_hit_equal_brute_force_for_both_widths (same_at_every_level)",
    ) {
        let mut stack = QueryStack::new();
        let (mut a, mut b) = (TraversalStats::default(), TraversalStats::default());
        let portable = w.closest_hit(
            ray,
            &mut Triangles::new(mesh, &Watertight),
            &mut Query::new().on(Portable).stack(&mut stack).stats(&mut a),
        );
        let simd = w.closest_hit(
            ray,
            &mut Triangles::new(mesh, &Watertight),
            &mut Query::new().on(level).stack(&mut stack).stats(&mut b),
        );
        assert_eq!(portable, simd, "{ray:?}");
        assert_eq!(a, b, "{ray:?}");
        let portable = w.any_hit(
            ray,
            &mut Triangles::new(mesh, &Watertight),
            &mut Query::new().on(Portable).stack(&mut stack),
        );
        let simd = w.any_hit(
            ray,
            &mut Triangles::new(mesh, &Watertight),
            &mut Query::new().on(level).stack(&mut stack),
        );
        assert_eq!(portable, simd, "{ray:?}");
    }
}

#[test]
fn closest_and_any_hit_equal_brute_force_for_both_widths() {
    for (n, seed) in [(1, 1), (3, 2), (17, 3), (300, 4), (2000, 5)] {
        check_against_brute::<8>(n, seed, 4);
        check_against_brute::<4>(n, seed, 4);
    }
    check_against_brute::<8>(500, 9, 1);
    check_against_brute::<8>(500, 10, 16);
}

#[test]
fn node_sizes_and_counts() {
    assert_eq!(core::mem::size_of::<WideNode<8>>(), 224);
    assert_eq!(core::mem::size_of::<LeafGroup>(), 160);
    let (pos, tris) = soup(2000, 7);
    let mesh = TriangleMesh::new(&pos, &tris);
    let b = binary(&mesh, 4);
    let w = wide::<8>(&mesh, 4);
    // Leaf runs are disjoint slot ranges, each touching the fewest groups its length allows;
    // lanes are skipped before a run only when starting it right after the previous one
    // would touch one group more. Each run is a union of whole binary leaves, at most
    // LEAF_MERGE long unless a binary leaf alone is longer.
    let binary_leaves: Vec<_> = b
        .nodes()
        .iter()
        .filter_map(|n| n.primitive_range())
        .collect();
    let leaf_of: std::collections::HashMap<u32, usize> = binary_leaves
        .iter()
        .enumerate()
        .flat_map(|(i, l)| b.indices()[l.clone()].iter().map(move |&p| (p, i)))
        .collect();
    let mut runs = Vec::new();
    let mut opened = 0;
    for n in w.nodes() {
        let used = (0..8).filter(|&k| n.child(k) != ChildRef::Empty).count();
        for k in 0..8 {
            if let ChildRef::Leaf { start, count } = n.child(k) {
                runs.push(start as usize..(start + count) as usize);
                // Binary leaves hold at most 4 here, so a longer run is a binary subtree,
                // which a node with a slot to spare opens.
                assert!(
                    used == 8 || count as usize <= LEAF_OPEN_ABOVE,
                    "a run of {count} left whole beside {} free slots",
                    8 - used
                );
                opened += usize::from(count as usize <= LEAF_OPEN_ABOVE && used > 2);
            }
        }
    }
    assert!(opened > 0, "some nodes have their leaves opened");
    runs.sort_by_key(|r| r.start);
    let groups_touched = |r: &core::ops::Range<usize>| r.end.div_ceil(4) - r.start / 4;
    let mut next = 0;
    let mut slots_used = 0;
    for r in &runs {
        let gap = r.start.checked_sub(next).expect("runs must not overlap");
        if gap > 0 {
            assert!(
                gap < 4 && r.start % 4 == 0,
                "lanes skipped only up to a group start"
            );
            let unpadded = next..next + r.len();
            assert!(
                groups_touched(&unpadded) > r.len().div_ceil(4),
                "skipped without need"
            );
        }
        assert_eq!(
            groups_touched(r),
            r.len().div_ceil(4),
            "a run touches the fewest groups"
        );
        next = r.end;
        slots_used += r.len();
        let prims: Vec<u32> = (r.start..r.end)
            .map(|s| w.triangle(s).expect("a run's slots hold triangles").prim)
            .collect();
        let mut leaves: Vec<usize> = prims.iter().map(|p| leaf_of[p]).collect();
        leaves.sort_unstable();
        leaves.dedup();
        let inside: usize = leaves.iter().map(|&i| binary_leaves[i].len()).sum();
        assert_eq!(inside, r.len(), "a run is a union of whole binary leaves");
        assert!(r.len() <= LEAF_MERGE.max(4));
    }
    assert_eq!(slots_used, 2000);
    assert_eq!(w.groups().len(), next.div_ceil(4));
    assert!(w.groups().len() <= group_capacity(2000));
    assert_eq!(
        Some(w.groups().len()),
        VecWide::<8>::group_count_for(&b).ok()
    );
    let st = w.stats();
    assert_eq!(st.leaves, runs.len());
    assert!(
        st.leaves < binary_leaves.len(),
        "small subtrees merge into one leaf"
    );
    assert_eq!(st.triangles, 2000);
    assert_eq!(st.children, st.nodes - 1 + st.leaves);
    assert!(st.nodes <= node_capacity(2000));
    assert!(
        st.children >= 3 * st.nodes,
        "the collapse fills nodes: {st:?}"
    );
    assert_eq!(st.bytes, 224 * st.nodes + 160 * w.groups().len());
    // Every triangle appears once, with its own vertices.
    let mut seen = vec![false; 2000];
    for t in w.triangles() {
        assert!(!seen[t.prim as usize]);
        seen[t.prim as usize] = true;
        let v = mesh.triangle(t.prim as usize).unwrap();
        assert_eq!(t.vertices(), v);
    }
}

#[test]
fn storage_too_small_and_bad_leaves_are_refused_before_writing() {
    let (pos, tris) = soup(100, 11);
    let mesh = TriangleMesh::new(&pos, &tris);
    let b = binary(&mesh, 4);
    let count = VecWide::<8>::node_count_for(&b).unwrap();
    let groups = VecWide::<8>::group_count_for(&b).unwrap();
    assert!((25..=group_capacity(100)).contains(&groups));
    // A group with every lane set (no NaN, so `==` sees whether it was written).
    let mut marker = LeafGroup::EMPTY;
    for lane in 0..4 {
        let v = [[7.0 + lane as f32; 3]; 3];
        marker.set(lane, &LeafTriangle { v, prim: 7 });
    }
    let mut nodes = vec![WideNode::<8>::EMPTY; count - 1];
    let mut recs = vec![marker; groups];
    let r = WideBvh::<8, _, _>::from_binary(&b, &mesh, &mut nodes[..], &mut recs[..]);
    assert_eq!(
        r.err(),
        Some(BvhError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhNodes,
            needed: count,
            available: count - 1
        }))
    );
    let mut nodes = vec![WideNode::<8>::EMPTY; count];
    let mut recs = vec![marker; groups - 1];
    let r = WideBvh::<8, _, _>::from_binary(&b, &mesh, &mut nodes[..], &mut recs[..]);
    assert_eq!(
        r.err(),
        Some(BvhError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::WideTriangleGroups,
            needed: groups,
            available: groups - 1
        }))
    );
    assert!(nodes.iter().all(|n| *n == WideNode::EMPTY) && recs.iter().all(|r| *r == marker));
    // Another mesh than the tree's source.
    let other = TriangleMesh::new(&pos, &tris[..50]);
    let r = WideBvh::<8, _, _>::from_binary(&b, &other, &mut nodes[..], &mut recs[..]);
    assert!(matches!(
        r.err(),
        Some(BvhError::SourceLengthMismatch { .. })
    ));
    // Leaves larger than a wide leaf.
    let coincident: Vec<[u32; 3]> = vec![[0, 1, 2]; 40];
    let same = TriangleMesh::new(&pos, &coincident);
    let b40 = binary(&same, 40);
    assert!(matches!(
        VecWide::<8>::node_count_for(&b40),
        Err(BvhError::LeafTooLarge { count: 40, max: 16 })
    ));
}

#[test]
fn storage_made_once_the_sizes_are_known_gives_the_same_tree() {
    let (pos, tris) = soup(300, 5);
    let mesh = TriangleMesh::new(&pos, &tris);
    let b = binary(&mesh, 4);
    // The sizes asked for are the exact node and group counts, read here from a tree built
    // the two-step way into storage of the bound `group_capacity`.
    let reference = wide::<8>(&mesh, 4);
    let mut asked = None;
    let w = VecWide::<8>::from_binary_with(&b, &mesh, |nodes, groups| {
        asked = Some((nodes, groups));
        (vec![WideNode::EMPTY; nodes], vec![LeafGroup::EMPTY; groups])
    })
    .unwrap();
    assert_eq!(
        asked,
        Some((reference.node_count(), reference.groups().len()))
    );
    assert_eq!(w.nodes(), reference.nodes());
    // (Groups hold NaN in unused lanes, which `==` never equates: compared slot by slot.)
    assert_eq!(w.groups().len(), reference.groups().len());
    assert!(w.triangles().eq(reference.triangles()));
    // Less storage than asked for is refused, and a tree that fails a check never asks.
    let r = VecWide::<8>::from_binary_with(&b, &mesh, |nodes, groups| {
        (
            vec![WideNode::EMPTY; nodes - 1],
            vec![LeafGroup::EMPTY; groups],
        )
    });
    assert!(matches!(
        r.err(),
        Some(BvhError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhNodes,
            ..
        }))
    ));
    let other = TriangleMesh::new(&pos, &tris[..10]);
    let mut called = false;
    let r = VecWide::<8>::from_binary_with(&b, &other, |nodes, groups| {
        called = true;
        (vec![WideNode::EMPTY; nodes], vec![LeafGroup::EMPTY; groups])
    });
    assert!(matches!(
        r.err(),
        Some(BvhError::SourceLengthMismatch { .. })
    ));
    assert!(!called);
}

#[test]
fn binary_options_give_the_same_wide_tree_but_for_the_order_inside_leaves() {
    for (n, seed) in [(1, 1), (5, 2), (300, 3), (2000, 4)] {
        let (pos, tris) = soup(n, seed);
        let mesh = TriangleMesh::new(&pos, &tris);
        let full = wide::<8>(&mesh, 4);
        let b = built(&mesh, &binary_options(BuildOptions::default()));
        let full_binary = binary(&mesh, 4);
        assert!(
            b.node_count() < full_binary.node_count() || n < 8,
            "the threshold saves splits: {} vs {}",
            b.node_count(),
            full_binary.node_count()
        );
        let short = VecWide::<8>::from_binary_with(&b, &mesh, |nodes, groups| {
            (vec![WideNode::EMPTY; nodes], vec![LeafGroup::EMPTY; groups])
        })
        .unwrap();
        // Same boxes and child references (leaf runs start and end at the same slots)…
        assert_eq!(short.nodes(), full.nodes(), "n = {n}");
        // …and each leaf run holds the same triangles.
        for node in full.nodes() {
            for i in 0..8 {
                if let ChildRef::Leaf { start, count } = node.child(i) {
                    let run = |w: &VecWide<8>| {
                        let mut t: Vec<(u32, [[u32; 3]; 3])> = (start..start + count)
                            .map(|s| {
                                let tri = w.triangle(s as usize).unwrap();
                                (tri.prim, tri.v.map(|v| v.map(f32::to_bits)))
                            })
                            .collect();
                        t.sort_unstable();
                        t
                    };
                    assert_eq!(run(&short), run(&full), "n = {n}, leaf at {start}");
                }
            }
        }
    }
}

/// Leaf runs straddle groups: a slot's lane and group follow from its index alone, and the
/// lanes of a run in each group are exactly its slots there, taken group by group or two
/// groups at a time (the leaf test's pairs), for every run a leaf can hold.
#[test]
fn run_lanes_cover_exactly_the_run() {
    for start in 0..12u32 {
        for count in 1..=MAX_LEAF_TRIANGLES as u32 {
            let expect: Vec<u32> = (start..start + count).collect();
            let groups = (start as usize / 4)..(start + count).div_ceil(4) as usize;
            let slots = |g: usize, m: u32, width: usize| {
                (0..width)
                    .filter(move |lane| m >> lane & 1 == 1)
                    .map(move |lane| (4 * g + lane) as u32)
            };
            let mut lanes = super::traverse::RunLanes::new(start, count);
            let covered: Vec<u32> = groups
                .clone()
                .flat_map(|g| slots(g, lanes.next_group(), 4))
                .collect();
            assert_eq!(covered, expect, "start {start} count {count}");
            assert_eq!(
                lanes.next_group(),
                0,
                "start {start} count {count}: past the run"
            );
            let mut lanes = super::traverse::RunLanes::new(start, count);
            let covered: Vec<u32> = groups
                .step_by(2)
                .flat_map(|g| slots(g, lanes.next_pair(), 8))
                .collect();
            assert_eq!(covered, expect, "start {start} count {count}, in pairs");
        }
    }
}

/// A leaf run's groups are the groups one of whose four slots lies in the run, and none when
/// one of them is past the end of the groups (the oracle: each group's slot range against
/// the run's, not the index arithmetic of `leaf_groups`).
#[test]
fn leaf_groups_are_the_groups_a_run_touches() {
    let groups = [LeafGroup::EMPTY; 8];
    for start in 0..40u32 {
        for count in 1..=MAX_LEAF_TRIANGLES as u32 {
            let (lo, hi) = (start as usize, (start + count) as usize);
            let touched: Vec<usize> = (0..16).filter(|g| 4 * g < hi && 4 * g + 4 > lo).collect();
            let got = super::traverse::leaf_groups(&groups, start, count);
            if touched.iter().all(|&g| g < groups.len()) {
                assert_eq!(got.len(), touched.len(), "start {start} count {count}");
                assert!(
                    core::ptr::eq(got.as_ptr(), &groups[touched[0]]),
                    "start {start} count {count}"
                );
            } else {
                assert!(got.is_empty(), "start {start} count {count}");
            }
        }
    }
}

/// The box of every vertex of `mesh` (the oracle of a tree's bounds).
fn vertex_box(mesh: &TriangleMesh<'_>) -> Aabb {
    (0..mesh.len())
        .filter_map(|i| mesh.triangle(i))
        .flatten()
        .fold(Aabb::EMPTY, |b, v| b.union(Aabb::new(v, v)))
}

/// Rays at `mesh` for the root-leaf tests: `rays` (some with `t_min < 0` or a short `t_max`),
/// rays at every vertex, at every edge's midpoint and at every triangle's centre from 12
/// directions, and a scanline of camera rays (coherent, so that a batch tries packets).
fn rays_at(mesh: &TriangleMesh<'_>, seed: u64) -> Vec<Ray> {
    let mut out = rays(600, seed);
    let mut s = seed ^ 0x5EED;
    let dirs: Vec<Vec3> = (0..12).map(|_| unit_vec(&mut s)).collect();
    for i in 0..mesh.len() {
        let v = mesh.triangle(i).unwrap();
        let targets = [
            v[0],
            v[1],
            v[2],
            (v[0] + v[1]) * 0.5,
            (v[1] + v[2]) * 0.5,
            (v[0] + v[1] + v[2]) / 3.0,
        ];
        for (k, t) in targets.iter().enumerate() {
            let d = dirs[(i + k) % dirs.len()];
            out.push(Ray::new(*t - d * 5.0, d));
        }
    }
    for k in 0..64 {
        let d = Vec3::new((k as f32 / 64.0 - 0.5) * 0.3, 0.02, 1.0);
        out.push(Ray::new(Vec3::new(0.1, 0.05, -9.0), d));
    }
    out
}

/// Every query of `w` (built over `mesh`) against brute force and, for the batch, against the
/// single-ray query bit for bit, at the portable level and at AVX2 where the CPU has it;
/// returns the closest hits found.
fn queries_equal_brute_force<const W: usize>(
    w: &VecWide<W>,
    mesh: &TriangleMesh<'_>,
    rays: &[Ray],
) -> usize {
    let mut hits = 0;
    for ray in rays {
        let got = w.closest_hit(
            ray,
            &mut Triangles::new(mesh, &Watertight),
            &mut Query::new(),
        );
        assert_eq!(
            got.map(|(p, h)| (p, h.t)),
            brute(mesh, &Watertight, ray),
            "W={W} {ray:?}"
        );
        assert_eq!(
            got,
            crate::test_util::brute_watertight(mesh, ray),
            "W={W} {ray:?}"
        );
        let any = w.any_hit(
            ray,
            &mut Triangles::new(mesh, &Watertight),
            &mut Query::new(),
        );
        assert_eq!(any.is_some(), got.is_some(), "any-hit, W={W} {ray:?}");
        if let Some((p, h)) = any {
            let v = mesh.triangle(p as usize).unwrap();
            assert_eq!(Watertight.intersect(ray, &v).map(|x| x.t), Some(h.t));
        }
        // The closure query sees every lane of the leaf it tests: each call is counted.
        let (mut calls, mut st) = (0u64, TraversalStats::default());
        let by_closure = w.closest_hit(
            ray,
            &mut |p, r: &Ray| {
                calls += 1;
                Watertight
                    .intersect(r, &mesh.triangle(p as usize)?)
                    .map(|h| (h.t, h.t))
            },
            &mut Query::new().stats(&mut st),
        );
        assert_eq!(by_closure, got.map(|(p, h)| (p, h.t)));
        assert_eq!(st.primitives_tested, calls);
        same_at_every_level(w, mesh, ray);
        hits += usize::from(got.is_some());
    }
    let mut batch = vec![None; rays.len()];
    let mut stack = QueryStack::new();
    w.closest_hits(
        rays,
        &mut Triangles::new(mesh, &Watertight),
        &mut Query::new().on(Portable).stack(&mut stack),
        &mut batch,
    )
    .unwrap();
    for (ray, b) in rays.iter().zip(&batch) {
        let single = w.closest_hit(
            ray,
            &mut Triangles::new(mesh, &Watertight),
            &mut Query::new(),
        );
        let bits = |a: &Option<(u32, crate::triangle::TriangleHit)>| {
            a.map(|(p, h)| (p, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
        };
        assert_eq!(bits(b), bits(&single), "batch, W={W} {ray:?}");
    }
    hits
}

/// A tree that is one leaf run that does not open (a binary leaf, or a binary subtree of at
/// most `LEAF_OPEN_ABOVE` triangles) has no node: its root is that leaf, in slots `0..n` of
/// `⌈n/4⌉` groups. A run that opens (a split subtree of more) gets a root node with two or
/// more leaf children, each within the bound; more than `LEAF_MERGE` triangles, a node. Every
/// query answers as brute force in every case.
#[test]
fn a_tree_that_is_one_unopened_leaf_run_has_no_node() {
    for n in 1..=LEAF_MERGE + 1 {
        let (pos, tris) = soup(n, 40 + n as u64);
        let mesh = TriangleMesh::new(&pos, &tris);
        for max_leaf in [1, 4, 16] {
            let w = wide::<8>(&mesh, max_leaf);
            let w4 = wide::<4>(&mesh, max_leaf);
            let st = w.stats();
            assert_eq!(w.bounds(), vertex_box(&mesh), "n = {n}");
            assert_eq!(w4.bounds(), vertex_box(&mesh), "n = {n}");
            let binary_leaf = binary(&mesh, max_leaf).nodes()[0].children().is_none();
            if binary_leaf || n <= LEAF_OPEN_ABOVE {
                for (root, nodes) in [(w.root(), w.node_count()), (w4.root(), w4.node_count())] {
                    assert_eq!(nodes, 0, "n = {n}, leaf {max_leaf}");
                    assert_eq!(
                        root,
                        ChildRef::Leaf {
                            start: 0,
                            count: n as u32
                        }
                    );
                }
                assert!(w.nodes().is_empty());
                assert_eq!(w.groups().len(), n.div_ceil(4));
                assert_eq!(
                    st,
                    WideStats {
                        nodes: 0,
                        leaves: 1,
                        children: 0,
                        triangles: n,
                        bytes: 160 * n.div_ceil(4)
                    }
                );
                assert_eq!(w.bytes_used(), 160 * n.div_ceil(4));
                let mut prims: Vec<u32> = w.triangles().map(|t| t.prim).collect();
                prims.sort_unstable();
                assert_eq!(prims, (0..n as u32).collect::<Vec<_>>());
            } else {
                assert_eq!(w.root(), ChildRef::Inner(0), "n = {n}");
                assert!(st.leaves >= 2, "{st:?}");
                if n <= LEAF_MERGE {
                    assert_eq!(w.node_count(), 1, "n = {n}");
                    let runs: Vec<u32> = (0..8)
                        .filter_map(|k| match w.nodes()[0].child(k) {
                            ChildRef::Leaf { count, .. } => Some(count),
                            ChildRef::Inner(_) => panic!("n = {n}: an inner child"),
                            ChildRef::Empty => None,
                        })
                        .collect();
                    assert_eq!(runs.iter().sum::<u32>() as usize, n, "n = {n}");
                    assert!(
                        runs.iter().all(|&c| c as usize <= LEAF_OPEN_ABOVE),
                        "{runs:?}"
                    );
                }
            }
            let rays = rays_at(&mesh, n as u64);
            let hits = queries_equal_brute_force(&w, &mesh, &rays);
            assert!(hits > 0, "n = {n}: the rays must hit");
            queries_equal_brute_force(&w4, &mesh, &rays);
            // The box query: every triangle whose box meets the query box.
            let mut s = 7u64 + n as u64;
            box_queries_equal_brute_force(&w, &mesh, &mut s, (50, 4.0, Vec3::ZERO));
        }
    }
}

/// Tiny closed shapes with shared edges (a tetrahedron, an octahedron, a cube), built as the
/// frontend builds them (`binary_options`): the tetrahedron (4) and the octahedron (8) are one
/// root leaf of 1 and 2 groups, the cube (12, split by the binary build) a root node over
/// leaves in 3 groups; every query answers as brute force and as the binary tree, rays
/// through edges and vertices included.
#[test]
fn tiny_closed_meshes_answer_as_brute_force() {
    let (cube_pos, cube_tris) = (
        crate::solids::CUBE_VERTICES.to_vec(),
        crate::solids::CUBE_TRIANGLES.to_vec(),
    );
    let tetra_pos = vec![
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(-1.0, -1.0, 1.0),
    ];
    let tetra = vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
    let octa_pos = crate::solids::OCTAHEDRON_VERTICES.to_vec();
    let octa = crate::solids::OCTAHEDRON_TRIANGLES.to_vec();
    for (pos, tris) in [(tetra_pos, tetra), (octa_pos, octa), (cube_pos, cube_tris)] {
        let mesh = TriangleMesh::new(&pos, &tris);
        let n = mesh.len();
        let b = built(&mesh, &binary_options(BuildOptions::default()));
        let mut asked = (0, 0);
        let w = VecWide::<8>::from_binary_with(&b, &mesh, |nodes, groups| {
            asked = (nodes, groups);
            (vec![WideNode::EMPTY; nodes], vec![LeafGroup::EMPTY; groups])
        })
        .unwrap();
        if n <= LEAF_OPEN_ABOVE {
            assert_eq!(asked, (0, n.div_ceil(4)), "exact sizes asked for");
            assert_eq!(
                w.root(),
                ChildRef::Leaf {
                    start: 0,
                    count: n as u32
                }
            );
        } else {
            assert_eq!(asked, (1, 3), "n = {n}: one node, the runs in 3 groups");
            assert_eq!(w.root(), ChildRef::Inner(0));
        }
        assert_eq!(w.stats().bytes, 224 * asked.0 + 160 * asked.1);
        let rays = rays_at(&mesh, 3);
        // At least the rays at the triangles' centres hit.
        assert!(queries_equal_brute_force(&w, &mesh, &rays) >= n);
        for ray in &rays {
            let want = b.closest_hit(
                ray,
                &mut Triangles::new(&mesh, &Watertight),
                &mut Query::new(),
            );
            let got = w.closest_hit(
                ray,
                &mut Triangles::new(&mesh, &Watertight),
                &mut Query::new(),
            );
            assert_eq!(got, want, "against the binary tree: {ray:?}");
        }
    }
}

/// A tree whose root is a leaf is walked without a box test (`root_leaf`): every interval
/// answers as brute force, at every level, for both widths, closest and any hit: rays at each
/// triangle's centre whose interval ends before the tree's box, starts beyond it, ends or
/// starts exactly at the hit, or starts behind the origin; rays that miss the box; invalid
/// rays (NaN, zero direction, empty interval), which hit nothing and call no closure.
#[test]
fn a_root_leaf_answers_every_interval_as_brute_force() {
    let pos = crate::solids::OCTAHEDRON_VERTICES.to_vec();
    let tris = crate::solids::OCTAHEDRON_TRIANGLES.to_vec();
    let mesh = TriangleMesh::new(&pos, &tris);
    let (w8, w4) = (wide::<8>(&mesh, 16), wide::<4>(&mesh, 16));
    assert!(matches!(w8.root(), ChildRef::Leaf { .. }) && w8.node_count() == 0);
    assert!(matches!(w4.root(), ChildRef::Leaf { .. }) && w4.node_count() == 0);
    let mut rays = Vec::new();
    for i in 0..mesh.len() {
        let v = mesh.triangle(i).unwrap();
        let centre = (v[0] + v[1] + v[2]) / 3.0;
        let o = centre * 4.0 + Vec3::new(0.01, 0.02, 0.03);
        let ray = Ray::new(o, centre - o);
        let t = Watertight.intersect(&ray, &v).map_or(0.75, |h| h.t);
        for (t_min, t_max) in [
            (0.0, f32::INFINITY),
            (0.0, 0.25),
            (0.0, t),
            (t, f32::INFINITY),
            (2.0, f32::INFINITY),
            (-3.0, 0.5),
            (-3.0, f32::INFINITY),
        ] {
            rays.push(Ray {
                t_min,
                t_max,
                ..ray
            });
        }
        // Away from the tree: misses the box.
        rays.push(Ray::new(o, o));
    }
    let good = Ray::new(Vec3::new(3.0, 0.1, 0.2), Vec3::new(-1.0, 0.0, 0.0));
    let invalid = [
        Ray::new(Vec3::new(f32::NAN, 0.1, 0.2), Vec3::new(-1.0, 0.0, 0.0)),
        Ray::new(Vec3::new(3.0, 0.1, 0.2), Vec3::ZERO),
        Ray {
            t_min: 2.0,
            t_max: 1.0,
            ..good
        },
    ];
    assert!(queries_equal_brute_force(&w8, &mesh, &rays) >= mesh.len());
    assert!(queries_equal_brute_force(&w4, &mesh, &rays) >= mesh.len());
    for ray in &invalid {
        let mut calls = 0u32;
        let mut count = |_: u32, _: &Ray| -> Option<(f32, ())> {
            calls += 1;
            None
        };
        assert_eq!(w8.closest_hit(ray, &mut count, &mut Query::new()), None);
        assert_eq!(w8.any_hit(ray, &mut count, &mut Query::new()), None);
        assert_eq!(calls, 0, "{ray:?}");
    }
    assert_eq!(queries_equal_brute_force(&w8, &mesh, &invalid), 0);
}

/// Triangles whose plane the ray's line crosses behind its origin, in boxes the ray enters
/// after its origin (where the any-hit walk skips the crossed-behind cull and the exact test
/// refuses them) and in a box around its origin (where the cull drops them): sixteen slanted
/// triangles along +x in the plane `z = 0.1 (x + 1) + 0.2 y`, which the line `y = z = 0`
/// crosses at `x = −1`, each box spanning that line, and a wall at `x = 20` behind them. Every
/// ray hits the wall, in both queries, at every level, for both widths, as brute force.
#[test]
fn planes_crossed_behind_the_origin_are_refused_in_boxes_ahead_and_around_it() {
    let plane = |x: f32, y: f32| Vec3::new(x, y, 0.1 * (x + 1.0) + 0.2 * y);
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for k in 0..16u32 {
        let x = k as f32 * 0.5;
        pos.extend([plane(x, -5.0), plane(x, 5.0), plane(x + 0.4, 0.0)]);
        tris.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let w = pos.len() as u32;
    pos.extend([
        Vec3::new(20.0, -1.0, -1.0),
        Vec3::new(20.0, 1.0, -1.0),
        Vec3::new(20.0, 1.0, 1.0),
        Vec3::new(20.0, -1.0, 1.0),
    ]);
    tris.extend([[w, w + 1, w + 2], [w, w + 2, w + 3]]);
    let mesh = TriangleMesh::new(&pos, &tris);
    let (w8, w4) = (wide::<8>(&mesh, 4), wide::<4>(&mesh, 4));
    assert!(w8.node_count() >= 1 && w4.node_count() >= 1);
    let mut rays = Vec::new();
    for origin_x in [-0.3, 2.2, 5.1] {
        for k in 0..8 {
            let (dy, dz) = ((k as f32 - 3.5) * 0.01, (k % 3) as f32 * 0.01);
            let d = Vec3::new(1.0, dy * 0.01, -dz * 0.01);
            rays.push(Ray::new(Vec3::new(origin_x, dy, dz), d));
        }
    }
    assert_eq!(queries_equal_brute_force(&w8, &mesh, &rays), rays.len());
    assert_eq!(queries_equal_brute_force(&w4, &mesh, &rays), rays.len());
    for ray in &rays {
        let got = w8.any_hit(
            ray,
            &mut Triangles::new(&mesh, &Watertight),
            &mut Query::new(),
        );
        assert!(matches!(got, Some((p, _)) if p >= 16), "{ray:?}");
    }
}

/// A room: the floor and three walls of a cube of side 40 (triangles 0..8, two per wall,
/// listed first so that the binary build's first split is not by index), around a soup of
/// `n` small triangles (size ~0.1 in a cube of side 4 at the centre).
fn room(n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let h = 20.0;
    let c = |x: f32, y: f32, z: f32| Vec3::new(x * h, y * h, z * h);
    let quads = [
        [
            c(-1., -1., -1.),
            c(-1., -1., 1.),
            c(1., -1., 1.),
            c(1., -1., -1.),
        ],
        [
            c(-1., -1., -1.),
            c(1., -1., -1.),
            c(1., 1., -1.),
            c(-1., 1., -1.),
        ],
        [
            c(-1., -1., -1.),
            c(-1., 1., -1.),
            c(-1., 1., 1.),
            c(-1., -1., 1.),
        ],
        [
            c(1., -1., -1.),
            c(1., -1., 1.),
            c(1., 1., 1.),
            c(1., 1., -1.),
        ],
    ];
    let mut pos: Vec<Vec3> = quads.iter().flatten().copied().collect();
    let mut tris: Vec<[u32; 3]> = (0..4u32)
        .flat_map(|q| [[4 * q, 4 * q + 1, 4 * q + 2], [4 * q, 4 * q + 2, 4 * q + 3]])
        .collect();
    let (spos, stris) = soup(n, 77);
    let base = pos.len() as u32;
    pos.extend(spos.iter().map(|p| *p * 0.4));
    tris.extend(stris.iter().map(|t| t.map(|i| i + base)));
    (pos, tris)
}

/// Huge triangles at the top of a tree get leaves of their own: in a room (four walls of
/// side 40 around a soup of 300 small triangles), the frontend's build (`binary_options`,
/// which otherwise never splits a node of 8 or fewer) splits the walls' node because each
/// split spares a ray entering the room more than `LARGE_NODE_SAVING` tests, and the collapse
/// opens it before the soup's nodes: every leaf holding a wall triangle holds that wall's two
/// triangles and nothing else (one leaf of walls had the whole room's box). Every query
/// answers as brute force, from the scratch build and the plain one alike.
#[test]
fn huge_triangles_at_the_top_get_leaves_of_their_own() {
    let (pos, tris) = room(300);
    let mesh = TriangleMesh::new(&pos, &tris);
    let n = mesh.len();
    let options = binary_options(BuildOptions::default());
    let plain = built(&mesh, &options);
    let scratch = Bvh::build_with_scratch(
        &mesh,
        vec![BvhNode::EMPTY; crate::bvh::node_capacity(n)],
        vec![0u32; index_capacity(n)],
        &mut vec![crate::bvh::PrimRef::EMPTY; crate::bvh::scratch_capacity(n)],
        &options,
    )
    .unwrap();
    for b in [&plain, &scratch] {
        let w = VecWide::<8>::from_binary_with(b, &mesh, |nodes, groups| {
            (vec![WideNode::EMPTY; nodes], vec![LeafGroup::EMPTY; groups])
        })
        .unwrap();
        let mut wall_leaves = 0;
        for node in w.nodes() {
            for i in 0..8 {
                if let ChildRef::Leaf { start, count } = node.child(i) {
                    let prims: Vec<u32> = (start..start + count)
                        .map(|s| w.triangle(s as usize).unwrap().prim)
                        .collect();
                    if let Some(&wall) = prims.iter().find(|&&p| p < 8) {
                        wall_leaves += 1;
                        let mut got = prims.clone();
                        got.sort_unstable();
                        let first = wall & !1;
                        assert_eq!(got, [first, first + 1], "a wall's leaf: {prims:?}");
                    }
                }
            }
        }
        assert_eq!(wall_leaves, 4);
        let mut rays = rays_at(&mesh, 9);
        // From inside the room towards every wall, and from outside through it.
        let mut s = 0x800Du64;
        for _ in 0..400 {
            let o = unit_vec(&mut s) * 3.0;
            rays.push(Ray::new(o, unit_vec(&mut s)));
            let far = unit_vec(&mut s) * 50.0;
            let target = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 40.0 - 20.0;
            rays.push(Ray::new(far, target - far));
        }
        assert!(queries_equal_brute_force(&w, &mesh, &rays) > rays.len() / 2);
    }
}

/// The box padding follows how far the tree reaches from the ray's origin, not the
/// coordinates' magnitude ([`crate::tolerance::BVH_PROJECTION_PAD`]; the node boxes are
/// stored relative to the tree's centre, [`WideBvh::box_origin`]): a soup moved about
/// 2·10⁶ from the coordinate origin, its rays moved with it, tests at most 10 % more
/// triangles than at the origin (not the same count: the moved vertices round to a grid of
/// up to 0.125, in a soup of side 10) and answers as brute force, query by query, at every level
/// and in batches. With the padding `γ₁₆·(max|o| + max|scene|)` (3.8 here) it tested nearly
/// every triangle on every ray; with boxes in world coordinates, whose padding keeps the
/// origin's two ulps (0.24 here), 36 % more.
#[test]
fn a_mesh_far_from_the_coordinate_origin_is_padded_by_its_own_reach() {
    let (pos, tris) = soup(600, 21);
    let shift = Vec3::new(1.0e6, -3.0e5, 2.0e6);
    let far_pos: Vec<Vec3> = pos.iter().map(|&p| p + shift).collect();
    let (near, far) = (
        TriangleMesh::new(&pos, &tris),
        TriangleMesh::new(&far_pos, &tris),
    );
    let near_rays = rays(400, 23);
    let far_rays: Vec<Ray> = near_rays
        .iter()
        .map(|r| {
            let mut m = *r;
            m.origin += shift;
            m
        })
        .collect();
    let tested = |mesh: &TriangleMesh<'_>, rays: &[Ray]| {
        let w = wide::<8>(mesh, 4);
        let mut st = TraversalStats::default();
        for ray in rays {
            w.closest_hit(
                ray,
                &mut Triangles::new(mesh, &Watertight),
                &mut Query::new().stats(&mut st),
            );
        }
        (w, st.primitives_tested)
    };
    let (_, at_origin) = tested(&near, &near_rays);
    let (w, moved) = tested(&far, &far_rays);
    assert!(
        moved * 10 <= at_origin * 11,
        "{moved} triangles tested far away, {at_origin} at the origin"
    );
    assert!(queries_equal_brute_force(&w, &far, &far_rays) > far_rays.len() / 4);
    // Box queries take their box into the tree's frame.
    box_queries_equal_brute_force(&w, &far, &mut 5, (100, 2.0, shift));
    // A tree built at the origin and refitted far away takes the new frame.
    let mut refitted = wide::<8>(&near, 4);
    assert_eq!(refitted.box_origin(), refitted.bounds().center());
    assert_eq!(refitted.refit(&far), Ok(()));
    assert_eq!(refitted.bounds(), vertex_box(&far));
    assert_eq!(refitted.box_origin(), refitted.bounds().center());
    assert!(queries_equal_brute_force(&refitted, &far, &far_rays) > far_rays.len() / 4);
    let mut st = TraversalStats::default();
    for ray in &far_rays {
        refitted.closest_hit(
            ray,
            &mut Triangles::new(&far, &Watertight),
            &mut Query::new().stats(&mut st),
        );
    }
    assert!(
        st.primitives_tested * 10 <= at_origin * 11,
        "{} triangles tested after the refit, {at_origin} at the origin",
        st.primitives_tested
    );
}

/// A root leaf's refit: the box follows the moved vertices, a non-finite triangle is named,
/// left out of the box and never reported.
#[test]
fn a_root_leaf_refits() {
    let (mut pos, tris) = soup(LEAF_OPEN_ABOVE, 77);
    let mesh = TriangleMesh::new(&pos, &tris);
    let mut w = wide::<8>(&mesh, 4);
    assert_eq!(w.node_count(), 0);
    assert_eq!(w.refit(&mesh), Ok(()));
    assert_eq!(w.bounds(), vertex_box(&mesh));
    for p in &mut pos {
        *p = *p * 1.5 + Vec3::new(0.5, -2.0, 0.25);
    }
    let moved = TriangleMesh::new(&pos, &tris);
    assert_eq!(w.refit(&moved), Ok(()));
    assert_eq!(w.bounds(), vertex_box(&moved));
    queries_equal_brute_force(&w, &moved, &rays_at(&moved, 9));
    let moved_rays = rays_at(&moved, 10);
    pos[3 * 4 + 2] = Vec3::new(f32::NAN, 0.0, 0.0);
    let broken = TriangleMesh::new(&pos, &tris);
    assert_eq!(
        w.refit(&broken),
        Err(BvhError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Primitive,
            index: 4
        }))
    );
    let others: Vec<[u32; 3]> = tris
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != 4)
        .map(|(_, t)| *t)
        .collect();
    assert_eq!(w.bounds(), vertex_box(&TriangleMesh::new(&pos, &others)));
    for ray in moved_rays {
        let got = w.closest_hit(
            &ray,
            &mut Triangles::new(&broken, &Watertight),
            &mut Query::new(),
        );
        assert_eq!(
            got.map(|(p, h)| (p, h.t)),
            brute(&broken, &Watertight, &ray),
            "{ray:?}"
        );
    }
}

#[test]
fn empty_mesh_and_single_triangle() {
    let mesh = TriangleMesh::new(&[], &[]);
    let w = wide::<8>(&mesh, 4);
    assert!(w.is_empty());
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert!(
        w.closest_hit(
            &ray,
            &mut Triangles::new(&mesh, &Watertight),
            &mut Query::new()
        )
        .is_none()
    );
    assert_eq!(
        w.query_box(
            &mesh,
            &Aabb::new(Vec3::splat(-1e9), Vec3::splat(1e9)),
            |_| true
        ),
        0
    );
    let pos = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let tris = [[0, 1, 2]];
    let mesh = TriangleMesh::new(&pos, &tris);
    let w = wide::<8>(&mesh, 4);
    let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
    let (p, h) = w
        .closest_hit(
            &r,
            &mut Triangles::new(&mesh, &Watertight),
            &mut Query::new(),
        )
        .unwrap();
    assert_eq!((p, h.t), (0, 1.0));
}

#[test]
fn deep_unbalanced_input_stays_within_the_stack_and_finds_everything() {
    // Triangles at 2^-k: the SAH peels one per level; the count split below MEDIAN_DEPTH keeps
    // leaves small, and traversal still finds every triangle.
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for k in 0..300i32 {
        let x = 2f32.powi(-k / 3) * if k % 2 == 0 { 1.0 } else { -1.0 };
        let s = 1e-3 * x.abs();
        let b = pos.len() as u32;
        pos.extend([
            Vec3::new(x - s, -s, 0.0),
            Vec3::new(x + s, -s, 0.0),
            Vec3::new(x, s, 0.0),
        ]);
        tris.push([b, b + 1, b + 2]);
    }
    let mesh = TriangleMesh::new(&pos, &tris);
    let b = binary(&mesh, 4);
    assert!(b.stats().max_leaf_size <= 4, "{:?}", b.stats());
    let w = wide::<8>(&mesh, 4);
    for (i, t) in tris.iter().enumerate() {
        let c = (pos[t[0] as usize] + pos[t[1] as usize] + pos[t[2] as usize]) / 3.0;
        let ray = Ray::new(c + Vec3::Z, -Vec3::Z);
        let got = w
            .closest_hit(
                &ray,
                &mut Triangles::new(&mesh, &Watertight),
                &mut Query::new(),
            )
            .map(|(p, _)| p);
        assert_eq!(
            got,
            brute(&mesh, &Watertight, &ray).map(|(p, _)| p),
            "triangle {i}"
        );
        assert!(got.is_some());
    }
}

/// `count` box queries of `w` over `mesh` (random boxes of side up to `side` in `[−6, 6]³`
/// moved by `at`, drawn from `seed`) against brute force: every triangle whose box meets the
/// query box, each once.
fn box_queries_equal_brute_force<const W: usize>(
    w: &VecWide<W>,
    mesh: &TriangleMesh<'_>,
    seed: &mut u64,
    (count, side, at): (usize, f32, Vec3),
) {
    for _ in 0..count {
        let c = at + Vec3::new(lcg(seed), lcg(seed), lcg(seed)) * 12.0 - 6.0;
        let q = Aabb::new(c, c + Vec3::splat(lcg(seed) * side));
        let mut got = Vec::new();
        w.query_box(mesh, &q, |p| {
            got.push(p);
            true
        });
        got.sort_unstable();
        let expect = brute_box(mesh, q.min, q.max);
        assert_eq!(got, expect, "{} triangles, {q:?}", mesh.len());
    }
}

#[test]
fn box_query_and_clearance_equal_brute_force_and_the_binary_tree() {
    let (pos, tris) = soup(800, 21);
    let mesh = TriangleMesh::new(&pos, &tris);
    let w = wide::<8>(&mesh, 4);
    let b = binary(&mesh, 4);
    let mut s = 99u64;
    box_queries_equal_brute_force(&w, &mesh, &mut s, (200, 2.0, Vec3::ZERO));
    let points: Vec<Vec3> = (0..100).map(|_| unit_vec(&mut s) * 9.0).collect();
    let normals: Vec<Vec3> = points.iter().map(|p| -*p * 0.5).collect();
    let mut a = vec![0.0; 100];
    let mut c = vec![0.0; 100];
    let ma = w
        .clearance(
            &mut Triangles::new(&mesh, &Watertight),
            &points,
            &normals,
            &mut a,
        )
        .unwrap();
    // The oracle: brute force's closest `t` along each normal times the normal's length
    // (in `f64`; the query's `f32` product is within a few ulps of it).
    let mut hits = 0;
    for (i, (&p, &n)) in points.iter().zip(&normals).enumerate() {
        let want = brute(&mesh, &Watertight, &Ray::new(p, n))
            .map_or(f64::INFINITY, |(_, t)| f64::from(t) * n.as_dvec3().length());
        let got = f64::from(a[i]);
        assert!(
            got == want || (got - want).abs() <= 1e-6 * want,
            "point {i}: {got} against brute force's {want}"
        );
        hits += usize::from(want.is_finite());
    }
    assert!(hits > 50, "{hits} of 100 normals hit the soup");
    assert_eq!(ma, a.iter().copied().fold(f32::INFINITY, f32::min));
    assert!(ma.is_finite());
    // The binary tree's query answers the same.
    let mc = b
        .clearance(
            &mut Triangles::new(&mesh, &Watertight),
            &points,
            &normals,
            &mut c,
        )
        .unwrap();
    assert_eq!((ma, &a), (mc, &c));
    assert_eq!(
        w.clearance(
            &mut Triangles::new(&mesh, &Watertight),
            &points,
            &normals[..99],
            &mut a
        ),
        Err(QueryError::LengthMismatch {
            expected: 100,
            found: 99
        })
    );
}

#[test]
fn refit_follows_moved_vertices_and_drops_non_finite_ones() {
    let (mut pos, tris) = soup(500, 31);
    let mesh = TriangleMesh::new(&pos, &tris);
    let mut w = wide::<8>(&mesh, 4);
    let before = w.nodes().to_vec();
    assert_eq!(w.refit(&mesh), Ok(()));
    assert_eq!(
        w.nodes(),
        &before[..],
        "refit over the same mesh changes nothing"
    );
    for p in &mut pos {
        *p = *p * 1.5 + Vec3::new(0.5, -2.0, 0.25);
    }
    pos[4] = Vec3::NAN;
    let moved = TriangleMesh::new(&pos, &tris);
    assert_eq!(
        w.refit(&moved),
        Err(BvhError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Primitive,
            index: 1
        }))
    );
    for ray in rays(2000, 5) {
        let got = w
            .closest_hit(
                &ray,
                &mut Triangles::new(&moved, &Watertight),
                &mut Query::new(),
            )
            .map(|(p, h)| (p, h.t));
        assert_eq!(got, brute(&moved, &Watertight, &ray), "{ray:?}");
    }
    let short = TriangleMesh::new(&pos, &tris[..10]);
    assert!(matches!(
        w.refit(&short),
        Err(BvhError::SourceLengthMismatch { .. })
    ));
}

#[test]
fn invalid_rays_test_nothing() {
    let (pos, tris) = soup(50, 41);
    let mesh = TriangleMesh::new(&pos, &tris);
    let w = wide::<8>(&mesh, 4);
    for ray in [
        Ray::new(Vec3::NAN, Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)),
    ] {
        let mut st = TraversalStats::default();
        assert!(
            w.closest_hit(
                &ray,
                &mut |_, _: &Ray| Some((1.0, ())),
                &mut Query::new().stats(&mut st)
            )
            .is_none()
        );
        assert_eq!(st, TraversalStats::default());
    }
}

#[test]
fn collapse_checks_the_tree_triangles_not_the_whole_mesh() {
    let (mut pos, tris) = soup(300, 41);
    // An unreferenced non-finite position, and triangle 7 made non-finite: a tree built with
    // `exclude_non_finite` leaves triangle 7 out, and the collapse accepts the mesh (the
    // triangle-by-triangle check sees only the tree's triangles).
    pos.push(Vec3::NAN);
    pos[21] = Vec3::INFINITY;
    let mesh = TriangleMesh::new(&pos, &tris);
    let n = mesh.len();
    let b = built(
        &mesh,
        &BuildOptions {
            max_leaf_size: 4,
            exclude_non_finite: true,
            ..BuildOptions::default()
        },
    );
    assert_eq!(b.primitive_count(), n - 1);
    let count = VecWide::<8>::node_count_for(&b).unwrap();
    let w = VecWide::<8>::from_binary(
        &b,
        &mesh,
        vec![WideNode::EMPTY; count],
        vec![LeafGroup::EMPTY; group_capacity(n)],
    )
    .unwrap();
    assert_eq!(w.triangles().count(), n - 1);
    assert!(w.triangles().all(|t| t.prim != 7));

    // A mesh whose tree triangle lost its finite vertices since the binary build, or refers
    // to a vertex that no longer exists: refused, with the triangle, before writing.
    let (pos, mut tris) = soup(300, 42);
    let mesh = TriangleMesh::new(&pos, &tris);
    let b = binary(&mesh, 4);
    let count = VecWide::<8>::node_count_for(&b).unwrap();
    let mut bad = pos.clone();
    bad[3 * 150 + 1] = Vec3::new(f32::NAN, 0.0, 0.0);
    let mut nodes = vec![WideNode::EMPTY; count];
    let mut groups = vec![LeafGroup::EMPTY; group_capacity(300)];
    let err = WideBvh::<8, _, _>::from_binary(
        &b,
        &TriangleMesh::new(&bad, &tris),
        &mut nodes[..],
        &mut groups[..],
    );
    assert_eq!(
        err.err(),
        Some(BvhError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Primitive,
            index: 150
        }))
    );
    assert!(
        nodes.iter().all(|n| *n == WideNode::EMPTY),
        "nodes untouched"
    );
    // (Unused lanes hold NaN, which `==` never equals: compare the printed records.)
    let empty = std::format!("{:?}", LeafGroup::EMPTY);
    assert!(
        groups.iter().all(|g| std::format!("{g:?}") == empty),
        "groups untouched"
    );
    tris[299][2] = 100_000;
    let err = VecWide::<8>::from_binary(
        &b,
        &TriangleMesh::new(&pos, &tris),
        vec![WideNode::EMPTY; count],
        vec![LeafGroup::EMPTY; group_capacity(300)],
    );
    assert_eq!(
        err.err(),
        Some(BvhError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Primitive,
            index: 299
        }))
    );
}

/// `binary_options` sets exactly what its docs say — `leaf_threshold` and `max_leaf_size` at
/// `LEAF_OPEN_ABOVE` (8), the primitive cost at `WIDE_INTERSECTION_COST` (0.3) — and keeps
/// the caller's other options, from options that differ in every field.
#[test]
fn binary_options_are_the_documented_ones() {
    let given = BuildOptions {
        max_leaf_size: 2,
        exclude_non_finite: true,
        leaf_threshold: 1,
        intersection_cost: 5.0,
    };
    let got = binary_options(given);
    assert_eq!((got.leaf_threshold, got.max_leaf_size), (8, 8));
    assert_eq!(got.intersection_cost, 0.3);
    assert!(got.exclude_non_finite);
    let got = binary_options(BuildOptions {
        exclude_non_finite: false,
        ..given
    });
    assert!(!got.exclude_non_finite);
}

/// A leaf reference: bit 31 set, the count less one in bits 27–30, the first record in bits
/// 0–26, worked by hand; refused for a count of 0 or above 16, a start beyond 27 bits, and
/// the one run whose encoding would be `ChildRef::EMPTY` (`u32::MAX`: start `2²⁷ − 1`, 16
/// triangles).
#[test]
fn a_leaf_reference_encodes_its_run_and_refuses_what_does_not_fit() {
    let last = (1u32 << 27) - 1;
    for (start, count, code) in [
        (0, 1, 0x8000_0000),
        (5, 3, 0x9000_0005),
        (0, 16, 0xF800_0000),
        (last, 15, 0xF7FF_FFFF),
        (last, 1, 0x87FF_FFFF),
    ] {
        assert_eq!(ChildRef::leaf(start, count), Some(code), "{start} {count}");
        assert_eq!(ChildRef::decode(code), ChildRef::Leaf { start, count });
    }
    for (start, count) in [
        (0, 0),
        (0, 17),
        (7, 0),
        (7, 17),
        (last + 1, 1),
        (u32::MAX, 4),
    ] {
        assert_eq!(ChildRef::leaf(start, count), None, "{start} {count}");
    }
    assert_eq!(ChildRef::leaf(last, 16), None);
    assert_eq!(ChildRef::decode(ChildRef::EMPTY), ChildRef::Empty);
    assert_eq!(ChildRef::decode(42), ChildRef::Inner(42));
}

/// The closest-hit walk's child order, worked by hand from `order_hits`' contract: of the hit
/// children the nearest is visited next (of equal entry distances the earlier slot) and the
/// others are pushed farthest first, so that the second nearest is on top. Its answers do not
/// depend on the order (the popped entries are checked against the shrunk interval): only this
/// test sees it.
#[test]
fn the_nearest_hit_child_is_visited_first_and_the_rest_pushed_farthest_first() {
    let (pos, tri) = soup(40, 3);
    let mesh = TriangleMesh::new(&pos, &tri);
    let w = wide::<8>(&mesh, 4);
    let mut node = WideNode::<8>::EMPTY;
    // Inner children 10, 11, …: plain node indices (no leaf bit).
    node.child = core::array::from_fn(|i| 10 + i as u32);
    let order = |dist: [f32; 8], hits: u32| {
        let first = hits.trailing_zeros() as usize;
        let mut stack = [StackEntry::EMPTY; super::traverse::STACK];
        let mut sp = 0;
        let entry = StackEntry {
            node: node.child[first],
            t_enter: dist[first],
        };
        let next = w.order_hits(
            Portable,
            &node,
            &dist,
            hits,
            entry,
            &mut stack,
            &mut sp,
            (w.nodes(), w.groups()),
        );
        let pushed: Vec<(u32, f32)> = stack[..sp].iter().map(|e| (e.node, e.t_enter)).collect();
        (next, pushed)
    };
    let inf = f32::INFINITY;
    // Two children, the later nearer: it is visited, the earlier pushed.
    let d = [inf, 5.0, inf, 2.0, inf, inf, inf, inf];
    assert_eq!(order(d, 0b1010), (13, vec![(11, 5.0)]));
    // Two children, the earlier nearer.
    let d = [inf, 2.0, inf, 5.0, inf, inf, inf, inf];
    assert_eq!(order(d, 0b1010), (11, vec![(13, 5.0)]));
    // A tie: the earlier slot first.
    let d = [3.0, inf, inf, inf, inf, inf, 3.0, inf];
    assert_eq!(order(d, 0b100_0001), (10, vec![(16, 3.0)]));
    // Four children: the nearest visited, the farthest deepest, the second nearest on top.
    let d = [7.0, inf, 1.0, 9.0, inf, 4.0, inf, inf];
    assert_eq!(
        order(d, 0b10_1101),
        (12, vec![(13, 9.0), (10, 7.0), (15, 4.0)])
    );
}

/// `WideNode::set_child` writes slot `i`'s bounds and reference and nothing else, and a slot
/// past the node's width is ignored (no panic, the node unchanged).
#[test]
fn a_child_slot_is_written_alone_and_one_past_the_width_is_ignored() {
    let b = Aabb::new(Vec3::new(-1.0, 2.0, -3.0), Vec3::new(4.0, 5.0, 6.0));
    let mut node = WideNode::<4>::EMPTY;
    node.set_child(2, &b, 7);
    for i in 0..4 {
        let want = if i == 2 {
            (b, ChildRef::Inner(7))
        } else {
            (WideNode::<4>::EMPTY.child_bounds(i), ChildRef::Empty)
        };
        assert_eq!((node.child_bounds(i), node.child(i)), want, "slot {i}");
    }
    let before = node;
    node.set_child(4, &b, 9);
    assert_eq!(node, before, "slot 4 of a 4-wide node");
}

/// The box query's contract for a box that is not valid: an inverted box (`min > max` on an
/// axis) or one with a NaN bound reports nothing, even where its corners lie among the
/// tree's triangles (an inverted box between two corners of a triangle's box would otherwise
/// pass a node's overlap test: `lo ≤ max` and `min ≤ hi` both hold there).
#[test]
fn an_inverted_or_nan_query_box_reports_nothing() {
    let (pos, tri) = soup(60, 5);
    let mesh = TriangleMesh::new(&pos, &tri);
    let w = wide::<8>(&mesh, 4);
    // The centre of triangle 0's box, and a step well inside that box.
    let v = tri[0].map(|i| pos[i as usize]);
    let b = Aabb::from_points(&v);
    let (c, d) = (b.center(), (b.max - b.min) * 0.25);
    let mut seen = Vec::new();
    w.query_box(&mesh, &Aabb::new(c - d, c + d), |p| {
        seen.push(p);
        true
    });
    assert!(seen.contains(&0), "the valid box meets triangle 0's box");
    let nan = Vec3::new(f32::NAN, c.y, c.z);
    for q in [
        Aabb::new(c + d, c - d),
        Aabb::new(
            Vec3::new(c.x + d.x, c.y - d.y, c.z - d.z),
            Vec3::new(c.x - d.x, c.y + d.y, c.z + d.z),
        ),
        Aabb::new(nan, c + d),
        Aabb::new(c - d, nan),
    ] {
        let n = w.query_box(&mesh, &q, |p| panic!("{q:?} reported triangle {p}"));
        assert_eq!(n, 0, "{q:?}");
    }
}

/// `stack_size` is `(W − 1)·MAX_DEPTH + 1` for the widths the trees use, and saturates instead
/// of overflowing for a width of 0 or one too large to count.
#[test]
fn stack_size_is_defined_for_every_width() {
    assert_eq!(stack_size(8), 7 * crate::bvh::MAX_DEPTH + 1);
    assert_eq!(stack_size(2), crate::bvh::MAX_DEPTH + 1);
    assert_eq!(stack_size(1), 1);
    assert_eq!(stack_size(0), 1);
    assert_eq!(stack_size(usize::MAX), usize::MAX);
}

/// Every supported width (2, 4 and 8: [`assert_width`]) answers as the binary tree it was
/// collapsed from, on a grid of quads where a slot picked as `i & (W − 1)` for another width
/// would answer wrong (the audit's 3-, 5-, 6- and 7-wide trees disagreed on most rays).
fn agrees_with_the_binary_tree<const W: usize>(mesh: &TriangleMesh<'_>, bin: &VecBinary) {
    let w = VecWide::<W>::from_binary(
        bin,
        mesh,
        vec![WideNode::<W>::EMPTY; VecWide::<W>::node_bound_for(bin)],
        vec![LeafGroup::EMPTY; group_capacity(mesh.len())],
    )
    .unwrap();
    assert!(w.node_count() > 1, "W={W}: the tree must have inner nodes");
    let mut hitting = 0;
    for i in 0..40 {
        for j in 0..40 {
            let (x, y) = (-0.5 + i as f32 * 41.0 / 40.0, -0.5 + j as f32 * 41.0 / 40.0);
            let ray = Ray::new(Vec3::new(x, y, -5.0), Vec3::Z);
            let mut tris = Triangles::new(mesh, &Watertight);
            let want = bin.closest_hit(&ray, &mut tris, &mut Query::new());
            let got = w.closest_hit(&ray, &mut tris, &mut Query::new());
            assert_eq!(got, want, "W={W} {ray:?}");
            let any = w.any_hit(&ray, &mut tris, &mut Query::new());
            assert_eq!(any.is_some(), want.is_some(), "W={W} any-hit {ray:?}");
            hitting += usize::from(want.is_some());
        }
    }
    assert!(
        hitting > 1000,
        "W={W}: the rays must hit the grid: {hitting} of 1600"
    );
}

#[test]
fn every_supported_width_answers_as_the_binary_tree() {
    let n = 40u32;
    let pos: Vec<Vec3> = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| Vec3::new(i as f32, j as f32, 0.0)))
        .collect();
    let tris: Vec<[u32; 3]> = (0..n)
        .flat_map(|j| {
            (0..n).flat_map(move |i| {
                let a = j * (n + 1) + i;
                let (b, c) = (a + 1, a + n + 1);
                [[a, b, c + 1], [a, c + 1, c]]
            })
        })
        .collect();
    let mesh = TriangleMesh::new(&pos, &tris);
    let bin = built(&mesh, &binary_options(BuildOptions::default()));
    agrees_with_the_binary_tree::<2>(&mesh, &bin);
    agrees_with_the_binary_tree::<4>(&mesh, &bin);
    agrees_with_the_binary_tree::<8>(&mesh, &bin);
}

/// A wide tree over storage whose `AsRef` gives other nodes after the build (safe code,
/// [`crate::test_util::Flip`]): a node whose only child is itself, one whose eight children
/// are, and shared subtrees whose children all come after their parents (node `i`'s first two
/// slots `i + 1`, `i + 2` over every stored node: about 10¹² paths from 64 nodes up). Every
/// walk enters a bounded number of nodes, so each ends: closest and any hit on the query's
/// stack and on a caller's, both batches (as packets: sixteen equal rays, whose direction
/// has no zero component so that they are walked as one), the box query and the statistics.
#[test]
fn every_walk_ends_when_the_storage_changes_under_the_tree() {
    use crate::test_util::{Flip, Walks};
    let (pos, tris) = soup(3000, 41);
    let mesh = TriangleMesh::new(&pos, &tris);
    let b = binary(&mesh, 4);
    let count = VecWide::<8>::node_count_for(&b).unwrap();
    // The walks see the first `count` nodes of the storage.
    assert!(count >= 64, "{count} nodes: too few for ~10¹² shared paths");
    let node = |children: &[u32]| {
        let mut n = WideNode::<8>::EMPTY;
        let huge = Aabb::new(Vec3::splat(-1.0e3), Vec3::splat(1.0e3));
        for (i, &c) in children.iter().enumerate() {
            n.set_child(i, &huge, c);
        }
        n
    };
    let leaf = ChildRef::leaf(0, 1).unwrap();
    let only_child = vec![node(&[0])];
    let self_loop = vec![node(&[0; 8])];
    let shared: Vec<WideNode<8>> = (0..count as u32)
        .map(|i| {
            if (i + 2) < count as u32 {
                node(&[i + 1, i + 2])
            } else {
                node(&[leaf])
            }
        })
        .collect();
    for (name, changed) in [
        ("its own only child", only_child),
        ("its own eight children", self_loop),
        ("shared subtrees", shared),
    ] {
        let (nodes, flip) = Flip::new(vec![WideNode::EMPTY; count], changed);
        let groups = vec![LeafGroup::EMPTY; group_capacity(mesh.len())];
        let w = WideBvh::<8, _, _>::from_binary(&b, &mesh, nodes, groups).unwrap();
        flip.store(true, std::sync::atomic::Ordering::Relaxed);
        let ray = Ray::new(
            Vec3::new(0.1, 0.2, -10.0),
            Vec3::new(0.01, 0.02, 1.0).normalize(),
        );
        let walks = Walks::new(name, w, &pos, &tris, ray);
        walks.end("closest hit", |w, m, r| {
            let _ = w.closest_hit(r, &mut Triangles::new(m, &Watertight), &mut Query::new());
        });
        walks.end("closest hit on a caller's stack", |w, m, r| {
            let mut stack = QueryStack::new();
            let _ = w.closest_hit(
                r,
                &mut Triangles::new(m, &Watertight),
                &mut Query::new().stack(&mut stack),
            );
        });
        walks.end("any hit", |w, m, r| {
            let _ = w.any_hit(r, &mut Triangles::new(m, &Watertight), &mut Query::new());
        });
        walks.end("closest hits (a packet)", |w, m, r| {
            let mut out = [None; 16];
            let _ = w.closest_hits(
                &[*r; 16],
                &mut Triangles::new(m, &Watertight),
                &mut Query::new(),
                &mut out,
            );
        });
        walks.end("any hits (a packet)", |w, m, r| {
            let mut out = [None; 16];
            let _ = w.any_hits(
                &[*r; 16],
                &mut Triangles::new(m, &Watertight),
                &mut Query::new(),
                &mut out,
            );
        });
        walks.end("box query", |w, m, _| {
            let _ = w.query_box(m, &Aabb::new(Vec3::splat(-1.0), Vec3::ONE), |_| true);
        });
        walks.end("statistics", |w, _, _| {
            let _ = w.stats();
        });
    }
}
