//! Unit tests of the collapse's choice of children, on binary trees written by hand.

use super::*;
use std::vec::Vec;

/// A binary node over the cube `[0, side]³` (surface area `6·side²`): a leaf of `count`
/// primitives from `start`, or (`count = 0`) an inner node with children `start`, `start + 1`.
fn node(side: f32, start: u32, count: u32) -> BvhNode {
    BvhNode::from_raw([[0.0; 3], [side; 3]], start, count)
}

/// `child_list` expands every inner entry before any leaf run, the largest first, whatever
/// the order of the entries. The tree (52 primitives):
///
/// ```text
/// 0 root ── 1 A (side 1) ── 3 A1: leaf 0..6, 4 A2: leaf 6..12
///        └─ 2 B (side 4) ── 5 C (side 4) ── 7 C1: leaf 12..22, 8 C2: leaf 22..32
///                        └─ 6 D (side 2) ── 9 D1: leaf 32..42, 10 D2: leaf 42..52
/// ```
///
/// A is a run of 12 ≤ `LEAF_MERGE` primitives that opens (12 > `LEAF_OPEN_ABOVE`, an inner
/// node); B, C and D hold 20 or more, so they are inner entries. For `W = 4`, by hand:
/// `[A, B]` → B, the only inner entry, is replaced by its children: `[A, C, D]` → C, the inner
/// entry of larger area (96 against 24): `[A, C1, D, C2]`, full. A stays one leaf run of 12
/// although it comes first and could open. (Opening A first would give `[A1, C, A2, D]` or,
/// taking the later inner entry, D before C: `[A, D1, C, D2]`.)
#[test]
fn inner_entries_expand_before_leaf_runs_largest_first() {
    assert_eq!(
        (LEAF_MERGE, LEAF_OPEN_ABOVE),
        (16, 8),
        "the tree below assumes these"
    );
    let nodes = [
        node(4.0, 1, 0),
        node(1.0, 3, 0),
        node(4.0, 5, 0),
        node(1.0, 0, 6),
        node(1.0, 6, 6),
        node(4.0, 7, 0),
        node(2.0, 9, 0),
        node(4.0, 12, 10),
        node(4.0, 22, 10),
        node(2.0, 32, 10),
        node(2.0, 42, 10),
    ];
    let list = child_list::<4>(&nodes, 0);
    let got: Vec<_> = list.iter().collect();
    assert_eq!(
        got,
        [
            (1, Some(0..12)),
            (7, Some(12..22)),
            (6, None),
            (8, Some(22..32))
        ]
    );
}

/// `group_capacity` is the documented `⌈7N/16⌉`, worked by hand: 0 → 0, 1 → 1, 16 → 7,
/// 17 → ⌈119/16⌉ = 8, 1000 → ⌈7000/16⌉ = 438.
#[test]
fn group_capacity_is_seven_sixteenths_rounded_up() {
    for (n, want) in [(0, 0), (1, 1), (16, 7), (17, 8), (1000, 438)] {
        assert_eq!(crate::bvh::wide::group_capacity(n), want, "{n}");
    }
}

/// A run whose split spares a ray entering the root's box at least `LARGE_NODE_SAVING` tests
/// is an inner entry, expanded before smaller inner ones; in a tree of at most `LEAF_MERGE`
/// triangles it stays one run. The tree (24 primitives; boxes are cubes, area `6·side²`):
///
/// ```text
/// 0 root (side 10) ── 1 A (side 10) ── 3 A1: leaf 0..2 (side 1), 4 A2: leaf 2..4 (side 1)
///                  └─ 2 B (side 1)  ── 5 B1: leaf 4..14, 6 B2: leaf 14..24 (side 1)
/// ```
///
/// A is a run of 4 (≤ `LEAF_OPEN_ABOVE`, so [`opens`] says no), but splitting it spares
/// `4·600 − (2·6 + 2·6) = 2376 ≥ 0.5·600` (the root's area): `[A, B]` → A, the larger:
/// `[A1, B, A2]` → B: `[A1, B1, A2, B2]`. With B's leaves of 2 (8 primitives in all) the
/// whole tree is at most `LEAF_MERGE`: `[A, B]` stay runs.
#[test]
fn a_run_that_spares_enough_tests_is_an_inner_entry() {
    let mut nodes = [
        node(10.0, 1, 0),
        node(10.0, 3, 0),
        node(1.0, 5, 0),
        node(1.0, 0, 2),
        node(1.0, 2, 2),
        node(1.0, 4, 10),
        node(1.0, 14, 10),
    ];
    let got: Vec<_> = child_list::<4>(&nodes, 0).iter().collect();
    assert_eq!(
        got,
        [
            (3, Some(0..2)),
            (5, Some(4..14)),
            (4, Some(2..4)),
            (6, Some(14..24))
        ]
    );
    nodes[5] = node(1.0, 4, 2);
    nodes[6] = node(1.0, 6, 2);
    let got: Vec<_> = child_list::<4>(&nodes, 0).iter().collect();
    assert_eq!(got, [(1, Some(0..4)), (2, Some(4..8))]);
}

/// Random triangles of size about 1 in a cube of side 10 (xorshift, `seed`).
fn soup(count: usize, seed: u32) -> (Vec<glam::Vec3>, Vec<[u32; 3]>) {
    let mut s = seed | 1;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s as f32 / u32::MAX as f32
    };
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for t in 0..count as u32 {
        let c = glam::Vec3::new(next(), next(), next()) * 10.0;
        for _ in 0..3 {
            pos.push(c + glam::Vec3::new(next(), next(), next()));
        }
        tris.push([3 * t, 3 * t + 1, 3 * t + 2]);
    }
    (pos, tris)
}

type Vec8 = WideBvh<8, Vec<WideNode<8>>, Vec<LeafGroup>>;

/// A node and group whose every field is garbage that a collapse must overwrite (`7.0`
/// coordinates, reference and index 7): storage that the one-walk collapse is given.
fn garbage() -> (WideNode<8>, LeafGroup) {
    let mut node = WideNode::<8>::EMPTY;
    let mut group = LeafGroup::EMPTY;
    let t = LeafTriangle {
        v: [[7.0; 3]; 3],
        prim: 7,
    };
    for i in 0..8 {
        node.set_child(
            i,
            &Aabb::new(glam::Vec3::splat(7.0), glam::Vec3::splat(7.0)),
            7,
        );
        group.set(i % LANES, &t);
    }
    (node, group)
}

/// [`WideBvh::from_binary_in`], one walk into garbage-filled storage of the documented
/// bounds, gives the tree of [`WideBvh::from_binary`] (planned, exact storage): the same nodes,
/// slot count and triangles slot by slot; every unused lane of a used group is empty (NaN
/// vertices, index `u32::MAX`), every used lane holds its triangle's vertices from the mesh;
/// the nodes need at most the bound. Leaf sizes from 1 to 16 (the collapse's own binary
/// options among them), several meshes.
#[test]
fn one_walk_gives_the_planned_tree_in_bounded_storage() {
    let mut checked = 0;
    for (count, seed) in [(1, 3), (9, 5), (300, 7), (2000, 11)] {
        let (pos, tris) = soup(count, seed);
        let mesh = TriangleMesh::new(&pos, &tris);
        for options in [
            crate::bvh::BuildOptions::default(),
            super::super::binary_options(crate::bvh::BuildOptions::default()),
            crate::bvh::BuildOptions {
                max_leaf_size: 16,
                ..crate::bvh::BuildOptions::default()
            },
        ] {
            let n = mesh.len();
            let b = Bvh::build(
                &mesh,
                std::vec![BvhNode::EMPTY; crate::bvh::node_capacity(n)],
                std::vec![0u32; crate::bvh::index_capacity(n)],
                &options,
            )
            .unwrap();
            let planned = Vec8::from_binary_with(&b, &mesh, |nodes, groups| {
                (
                    std::vec![WideNode::EMPTY; nodes],
                    std::vec![LeafGroup::EMPTY; groups],
                )
            })
            .unwrap();
            let (gn, gg) = garbage();
            let bound = Vec8::node_bound_for(&b);
            let one = Vec8::from_binary_in(
                &b,
                &mesh,
                std::vec![gn; bound],
                std::vec![gg; group_capacity(n)],
            )
            .unwrap();
            assert!(planned.node_count() <= bound);
            assert_eq!(one.nodes(), planned.nodes(), "{count} {options:?}");
            assert_eq!(one.root(), planned.root());
            assert_eq!(one.groups().len(), planned.groups().len());
            assert!(one.triangles().eq(planned.triangles()));
            for (g, group) in one.groups().iter().enumerate() {
                for lane in 0..LANES {
                    let t = group.triangle(lane).unwrap();
                    if t.prim == u32::MAX {
                        assert!(t.v.iter().flatten().all(|x| x.is_nan()), "{g} {lane}");
                    } else {
                        let v = mesh.triangle(t.prim as usize).unwrap();
                        assert_eq!(t.v, v.map(|p| p.to_array()), "{g} {lane}");
                    }
                }
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 12);
}

/// Storage below the bounds is refused before anything is written; a leaf larger than
/// [`MAX_LEAF_TRIANGLES`] is refused as by `from_binary`.
#[test]
fn one_walk_refuses_small_storage_and_large_leaves() {
    let (pos, tris) = soup(300, 13);
    let mesh = TriangleMesh::new(&pos, &tris);
    let build = |max_leaf_size| {
        Bvh::build(
            &mesh,
            std::vec![BvhNode::EMPTY; crate::bvh::node_capacity(300)],
            std::vec![0u32; crate::bvh::index_capacity(300)],
            &crate::bvh::BuildOptions {
                max_leaf_size,
                leaf_threshold: max_leaf_size,
                ..crate::bvh::BuildOptions::default()
            },
        )
        .unwrap()
    };
    let b = build(4);
    let bound = Vec8::node_bound_for(&b);
    let (gn, gg) = garbage();
    let mut nodes = std::vec![gn; bound - 1];
    let mut groups = std::vec![gg; group_capacity(300)];
    type Borrowed<'a> = WideBvh<8, &'a mut [WideNode<8>], &'a mut [LeafGroup]>;
    let r = Borrowed::from_binary_in(&b, &mesh, &mut nodes[..], &mut groups[..]);
    assert!(matches!(
        r.err(),
        Some(BvhError::Capacity(CapacityError {
            storage: Storage::BvhNodes,
            ..
        }))
    ));
    let mut nodes = std::vec![gn; bound];
    let mut few = std::vec![gg; group_capacity(300) - 1];
    let r = Borrowed::from_binary_in(&b, &mesh, &mut nodes[..], &mut few[..]);
    assert!(matches!(
        r.err(),
        Some(BvhError::Capacity(CapacityError {
            storage: Storage::WideTriangleGroups,
            ..
        }))
    ));
    assert!(nodes.iter().all(|n| *n == gn), "nothing written");
    // Two clusters of 40 triangles whose boxes share their centre, far apart: no split
    // separates a cluster, so it is one leaf of 40 (a root leaf for one cluster).
    let mut cpos = Vec::new();
    for c in [glam::Vec3::ZERO, glam::Vec3::new(100.0, 0.0, 0.0)] {
        for k in 1..=40 {
            let d = glam::Vec3::splat(k as f32 * 0.01);
            cpos.extend([c - d, c + d, c]);
        }
    }
    let ctris: Vec<[u32; 3]> = (0..80u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    for clusters in [1, 2] {
        let cmesh = TriangleMesh::new(&cpos, &ctris[..40 * clusters]);
        let n = cmesh.len();
        let big = Bvh::build(
            &cmesh,
            std::vec![BvhNode::EMPTY; crate::bvh::node_capacity(n)],
            std::vec![0u32; crate::bvh::index_capacity(n)],
            &crate::bvh::BuildOptions {
                max_leaf_size: 40,
                ..crate::bvh::BuildOptions::default()
            },
        )
        .unwrap();
        let r = Vec8::from_binary_in(
            &big,
            &cmesh,
            std::vec![gn; Vec8::node_bound_for(&big)],
            std::vec![gg; group_capacity(n)],
        );
        let e = r.err();
        assert!(
            matches!(
                e,
                Some(BvhError::LeafTooLarge {
                    count: 40,
                    max: MAX_LEAF_TRIANGLES
                })
            ),
            "{clusters}: {e:?}"
        );
        assert_eq!(
            Vec8::node_count_for(&big).err(),
            e,
            "refused by the plan too"
        );
    }
}

/// The binary tree over `mesh` with the collapse's options.
fn collapse_tree(mesh: &TriangleMesh<'_>) -> Bvh<Vec<BvhNode>, Vec<u32>> {
    let n = mesh.len();
    Bvh::build(
        mesh,
        std::vec![BvhNode::EMPTY; crate::bvh::node_capacity(n)],
        std::vec![0u32; crate::bvh::index_capacity(n)],
        &super::super::binary_options(crate::bvh::BuildOptions::default()),
    )
    .unwrap()
}

/// What each constructor says of `mesh` with `b`: `from_binary` (into garbage it must not
/// write when it refuses), `from_binary_with` (whose storage must not be asked for then) and
/// `from_binary_in`, which must agree.
fn collapse_all_ways(
    b: &Bvh<Vec<BvhNode>, Vec<u32>>,
    mesh: &TriangleMesh<'_>,
) -> Result<Vec8, BvhError> {
    let (gn, gg) = garbage();
    let n = mesh.len();
    let (mut nodes, mut groups) = (
        std::vec![gn; Vec8::node_bound_for(b)],
        std::vec![gg; group_capacity(n)],
    );
    type Borrowed<'a> = WideBvh<8, &'a mut [WideNode<8>], &'a mut [LeafGroup]>;
    let two = Borrowed::from_binary(b, mesh, &mut nodes[..], &mut groups[..]).map(|_| ());
    if two.is_err() {
        assert!(nodes.iter().all(|x| *x == gn), "nodes written: {two:?}");
        let g = std::format!("{gg:?}");
        assert!(
            groups.iter().all(|x| std::format!("{x:?}") == g),
            "groups written: {two:?}"
        );
    }
    let mut asked = false;
    let with = Vec8::from_binary_with(b, mesh, |nodes, groups| {
        asked = true;
        (
            std::vec![WideNode::EMPTY; nodes],
            std::vec![LeafGroup::EMPTY; groups],
        )
    });
    assert_eq!(asked, with.is_ok(), "storage asked for iff accepted");
    let one = Vec8::from_binary_in(
        b,
        mesh,
        std::vec![gn; Vec8::node_bound_for(b)],
        std::vec![gg; group_capacity(n)],
    );
    assert_eq!(two.err(), with.as_ref().err().copied());
    assert_eq!(one.as_ref().err(), with.as_ref().err());
    with
}

/// A mesh with the source's triangle count that the binary tree does not bound is refused by
/// every constructor ([`BvhError::TriangleOutsideTree`], before anything is written by the
/// planned ones): one triangle moved 100 away (the audit's reproducer: it was accepted and a
/// ray through the moved triangle missed it), in a tree with nodes and in one that is a root
/// leaf; a vertex one ulp past its leaf's box (the boxes are the vertices' exact
/// minimum and maximum: the check is exact). A mesh the tree bounds is accepted: the source,
/// the source with each triangle's vertices rotated, and the moved mesh after a refit.
#[test]
fn a_mesh_the_binary_tree_does_not_bound_is_refused() {
    for count in [40u32, 5] {
        let soup = |shift_first: f32| -> Vec<glam::Vec3> {
            (0..count)
                .flat_map(|t| {
                    let x = t as f32 + if t == 0 { shift_first } else { 0.0 };
                    let o = glam::Vec3::new(x, 0.0, 0.0);
                    [
                        o,
                        o + glam::Vec3::new(0.5, 0.0, 0.0),
                        o + glam::Vec3::new(0.0, 0.5, 0.0),
                    ]
                })
                .collect()
        };
        let tris: Vec<[u32; 3]> = (0..count).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let (a, moved) = (soup(0.0), soup(100.0));
        let ma = TriangleMesh::new(&a, &tris);
        let mut b = collapse_tree(&ma);
        let w = collapse_all_ways(&b, &ma).unwrap();
        assert_eq!(matches!(w.root(), ChildRef::Leaf { .. }), count == 5);
        let mb = TriangleMesh::new(&moved, &tris);
        assert_eq!(
            collapse_all_ways(&b, &mb).err(),
            Some(BvhError::TriangleOutsideTree { triangle: 0 }),
            "{count}"
        );
        // The vertex of largest x (triangle count − 1's second) is its leaf box's maximum.
        let mut ulp = a.clone();
        let last = 3 * (count as usize - 1) + 1;
        ulp[last].x = ulp[last].x.next_up();
        assert_eq!(
            collapse_all_ways(&b, &TriangleMesh::new(&ulp, &tris)).err(),
            Some(BvhError::TriangleOutsideTree {
                triangle: count as usize - 1
            }),
            "{count}"
        );
        let rotated: Vec<[u32; 3]> = tris.iter().map(|&[i, j, k]| [j, k, i]).collect();
        collapse_all_ways(&b, &TriangleMesh::new(&a, &rotated)).unwrap();
        b.refit(&mb).unwrap();
        let w = collapse_all_ways(&b, &mb).unwrap();
        let ray = crate::ray::Ray::new(glam::Vec3::new(100.1, 0.1, -1.0), glam::Vec3::Z);
        let hit = crate::query::RayQuery::closest_hit(
            &w,
            &ray,
            &mut crate::query::Triangles::new(&mb, &crate::triangle::Watertight),
            &mut crate::query::Query::new(),
        );
        assert_eq!(hit.map(|h| h.0), Some(0), "{count}");
    }
}
