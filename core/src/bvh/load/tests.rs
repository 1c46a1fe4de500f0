//! Unit tests of `load`.

use super::*;
use crate::bvh::BuildOptions;
use crate::query::{Query, StackEntry};
use crate::ray::Ray;
use crate::test_util::{closest_watertight, closest_watertight_in, lcg};
use crate::triangle::Watertight;
use glam::Vec3;
use std::vec;
use std::vec::Vec;

/// A grid of `n × n` quads with jittered heights.
fn grid(n: usize, rng: &mut u64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push(Vec3::new(i as f32, j as f32, lcg(rng) * 0.5));
        }
    }
    (
        p,
        crate::solids::grid_triangles(n as u32, n as u32).collect(),
    )
}

fn built(mesh: &TriangleMesh<'_>) -> (Vec<BvhNode>, Vec<u32>) {
    let mut nodes = vec![BvhNode::EMPTY; node_capacity(mesh.len()) + 1];
    let mut idx = vec![0u32; mesh.len()];
    let n = Bvh::build(mesh, &mut nodes[..], &mut idx[..], &BuildOptions::default())
        .unwrap()
        .node_count();
    nodes.truncate(n);
    (nodes, idx)
}

fn load<'a>(
    nodes: &'a [BvhNode],
    idx: &'a [u32],
    mesh: &TriangleMesh<'_>,
) -> Result<Bvh<&'a [BvhNode], &'a [u32]>, LoadError> {
    let mut scratch = vec![0u32; load_scratch_len(mesh.len())];
    Bvh::from_parts(nodes, idx, mesh, &mut scratch)
}

/// Closest hit by brute force over every triangle, smaller index on equal `t`: the oracle.
fn brute(mesh: &TriangleMesh<'_>, ray: &Ray) -> Option<(u32, u32)> {
    let mut best: Option<(u32, f32)> = None;
    for i in 0..mesh.len() {
        let v = mesh.triangle(i).unwrap();
        if let Some(h) = crate::triangle::TriangleIntersector::intersect(&Watertight, ray, &v)
            && best.is_none_or(|(_, t)| h.t < t)
        {
            best = Some((i as u32, h.t));
        }
    }
    best.map(|(i, t)| (i, t.to_bits()))
}

#[test]
fn a_built_tree_loads_and_answers_like_brute_force() {
    let mut rng = 5u64;
    let (p, t) = grid(12, &mut rng);
    let mesh = TriangleMesh::new(&p, &t);
    let (nodes, idx) = built(&mesh);
    let bvh = load(&nodes, &idx, &mesh).unwrap();
    assert_eq!(bvh.primitive_count(), t.len());
    for _ in 0..2000 {
        let o = Vec3::new(lcg(&mut rng) * 14.0 - 1.0, lcg(&mut rng) * 14.0 - 1.0, 3.0);
        let d = Vec3::new(lcg(&mut rng) - 0.5, lcg(&mut rng) - 0.5, -1.0);
        let ray = Ray::new(o, d);
        let got = closest_watertight(&bvh, &mesh, &ray).map(|(i, h)| (i, h.t.to_bits()));
        assert_eq!(got, brute(&mesh, &ray));
    }
    // The empty mesh loads as the empty tree.
    let empty = TriangleMesh::new(&[], &[]);
    assert!(load(&[], &[], &empty).unwrap().is_empty());
}

#[test]
fn each_broken_invariant_is_refused_with_its_error() {
    let mut rng = 9u64;
    let (p, t) = grid(6, &mut rng);
    let mesh = TriangleMesh::new(&p, &t);
    let (nodes, idx) = built(&mesh);
    let inner = nodes.iter().position(|n| !n.is_leaf()).unwrap();
    let leaf = nodes.iter().rposition(BvhNode::is_leaf).unwrap();
    let parent = nodes
        .iter()
        .position(|n| {
            n.children()
                .is_some_and(|(a, b)| a as usize == leaf || b as usize == leaf)
        })
        .unwrap();
    let with = |i: usize, n: BvhNode| {
        let mut v = nodes.clone();
        v[i] = n;
        v
    };
    let raw = |n: &BvhNode| {
        let (s, c) = n.raw();
        (n.bounds, s, c)
    };
    let (b, s, c) = raw(&nodes[leaf]);
    let (ib, _, _) = raw(&nodes[inner]);
    let cases: Vec<(Vec<BvhNode>, Vec<u32>, LoadError)> = vec![
        // A child pointing back at the root: a cycle.
        (
            with(inner, BvhNode::from_raw(ib, 0, 0)),
            idx.clone(),
            LoadError::ChildOutOfRange { node: inner },
        ),
        // Children past the array.
        (
            with(inner, BvhNode::from_raw(ib, nodes.len() as u32 - 1, 0)),
            idx.clone(),
            LoadError::ChildOutOfRange { node: inner },
        ),
        // A NaN box: refused at its parent, which no longer contains it.
        (
            with(leaf, BvhNode::from_raw([[f32::NAN; 3], b[1]], s, c)),
            idx.clone(),
            LoadError::BadBox { node: parent },
        ),
        // A leaf box shrunk off its triangles.
        (
            with(leaf, BvhNode::from_raw([b[0], b[0]], s, c)),
            idx.clone(),
            LoadError::BadBox { node: leaf },
        ),
        // A leaf range moved past the index array.
        (
            with(leaf, BvhNode::from_raw(b, idx.len() as u32, c)),
            idx.clone(),
            LoadError::LeafRange { node: leaf },
        ),
        // A repeated index (so another triangle is never tested).
        (
            nodes.clone(),
            {
                let mut v = idx.clone();
                v[1] = v[0];
                v
            },
            LoadError::BadIndex { position: 1 },
        ),
    ];
    for (k, (n, i, want)) in cases.into_iter().enumerate() {
        assert_eq!(load(&n, &i, &mesh).err(), Some(want), "case {k}");
    }
    // Truncated arrays.
    assert_eq!(
        load(&nodes, &idx[..idx.len() - 1], &mesh).err(),
        Some(LoadError::IndexCount {
            indices: idx.len() - 1,
            triangles: t.len()
        })
    );
    // The last node dropped: its parent's second child now lies past the array.
    let last_parent = nodes
        .iter()
        .position(|n| {
            n.children()
                .is_some_and(|(_, b)| b as usize == nodes.len() - 1)
        })
        .unwrap();
    assert_eq!(
        load(&nodes[..nodes.len() - 1], &idx, &mesh).err(),
        Some(LoadError::ChildOutOfRange { node: last_parent })
    );
    let mut small = [0u32; 1];
    assert_eq!(
        Bvh::from_parts(&nodes[..], &idx[..], &mesh, &mut small).err(),
        Some(LoadError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhLoadBitset,
            needed: load_scratch_len(t.len()),
            available: 1
        }))
    );
}

/// Random corruptions of a built tree (a field of a node set to a random value, an index
/// replaced, a vertex moved): the loader either refuses the input, or every answer over it
/// equals brute force. Most corruptions must be refused.
#[test]
fn a_corrupted_tree_is_refused_or_still_exact() {
    let mut rng = 17u64;
    let (p, t) = grid(5, &mut rng);
    let (nodes, idx) = built(&TriangleMesh::new(&p, &t));
    let mut refused = 0;
    let trials = 400;
    for trial in 0..trials {
        let (mut n, mut i, mut q) = (nodes.clone(), idx.clone(), p.clone());
        let pick = |r: &mut u64, len: usize| ((lcg(r) * len as f32) as usize).min(len - 1);
        let word = (lcg(&mut rng) * 4096.0) as u32;
        match trial % 4 {
            0 => {
                let k = pick(&mut rng, n.len());
                let (mut b, s, c) = n[k].to_raw();
                b[pick(&mut rng, 2)][pick(&mut rng, 3)] = lcg(&mut rng) * 8.0 - 2.0;
                n[k] = BvhNode::from_raw(b, s, c);
            }
            1 => {
                let k = pick(&mut rng, n.len());
                let (b, s, c) = n[k].to_raw();
                n[k] = if trial % 8 == 1 {
                    BvhNode::from_raw(b, word % 64, c)
                } else {
                    BvhNode::from_raw(b, s, word % 8)
                };
            }
            2 => {
                let k = pick(&mut rng, i.len());
                i[k] = word % 64;
            }
            _ => {
                let k = pick(&mut rng, q.len());
                q[k].z = lcg(&mut rng) * 2.0 - 0.5;
            }
        }
        let mesh = TriangleMesh::new(&q, &t);
        let Ok(bvh) = load(&n, &i, &mesh) else {
            refused += 1;
            continue;
        };
        for _ in 0..200 {
            let o = Vec3::new(lcg(&mut rng) * 7.0 - 1.0, lcg(&mut rng) * 7.0 - 1.0, 3.0);
            let d = Vec3::new(lcg(&mut rng) - 0.5, lcg(&mut rng) - 0.5, -1.0);
            let ray = Ray::new(o, d);
            let got = closest_watertight(&bvh, &mesh, &ray).map(|(i, h)| (i, h.t.to_bits()));
            assert_eq!(got, brute(&mesh, &ray), "trial {trial}");
        }
    }
    assert!(
        refused > trials / 3,
        "only {refused} of {trials} corruptions refused"
    );
}

/// A caterpillar tree over `n` triangles stacked along z: the inner node at depth `k` is
/// node `2k`, with the leaf of triangle `k` and the next inner node as children; the last
/// inner node's children are two leaves.
fn caterpillar(n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<BvhNode>) {
    let p: Vec<Vec3> = (0..n)
        .flat_map(|k| {
            let z = k as f32;
            [
                Vec3::new(0.0, 0.0, z),
                Vec3::new(1.0, 0.0, z),
                Vec3::new(0.0, 1.0, z),
            ]
        })
        .collect();
    let t: Vec<[u32; 3]> = (0..n as u32)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    let slab = |lo: usize, hi: usize| [[0.0, 0.0, lo as f32], [1.0, 1.0, hi as f32]];
    let mut nodes = vec![BvhNode::EMPTY; 2 * n - 1];
    for k in 0..n - 1 {
        nodes[2 * k] = BvhNode::from_raw(slab(k, n - 1), 2 * k as u32 + 1, 0);
        nodes[2 * k + 1] = BvhNode::from_raw(slab(k, k), k as u32, 1);
    }
    nodes[2 * n - 2] = BvhNode::from_raw(slab(n - 1, n - 1), n as u32 - 1, 1);
    (p, t, nodes)
}

#[test]
fn a_chain_deeper_than_the_stack_bound_is_refused() {
    // Deepest inner node at depth n − 2: 62 is accepted, 64 and more are not.
    let (p, t, nodes) = caterpillar(64);
    let mesh = TriangleMesh::new(&p, &t);
    let idx: Vec<u32> = (0..t.len() as u32).collect();
    assert!(load(&nodes, &idx, &mesh).is_ok());
    let (p, t, nodes) = caterpillar(70);
    let mesh = TriangleMesh::new(&p, &t);
    let idx: Vec<u32> = (0..t.len() as u32).collect();
    assert_eq!(
        load(&nodes, &idx, &mesh).err(),
        Some(LoadError::TooDeep {
            node: 2 * MAX_DEPTH
        })
    );
}

/// The deepest tree the bound allows: a caterpillar whose last inner node is at depth 63, so
/// 64 inner nodes sit above its deepest leaves. `stack_depth` (whose own walk keeps one
/// pending entry per level) reports all 64, as the statistics' walk does, and a stack of 64
/// entries answers a ray down the whole chain.
#[test]
fn stack_depth_of_the_deepest_loadable_chain() {
    let (p, t, nodes) = caterpillar(65);
    let mesh = TriangleMesh::new(&p, &t);
    let idx: Vec<u32> = (0..t.len() as u32).collect();
    let bvh = load(&nodes, &idx, &mesh).unwrap();
    assert_eq!(bvh.stack_depth(), MAX_DEPTH);
    assert_eq!(bvh.stats().max_depth, MAX_DEPTH);
    // Down the chain from above: every level is entered before the nearest leaf, at z = 64.
    let ray = Ray::new(Vec3::new(0.25, 0.25, 70.0), -Vec3::Z);
    let full = closest_watertight(&bvh, &mesh, &ray);
    assert_eq!(full.map(|(i, h)| (i, h.t)), Some((64, 6.0)));
    let mut stack = [StackEntry::EMPTY; MAX_DEPTH];
    let got = closest_watertight_in(&bvh, &mesh, &ray, &mut Query::new().stack(&mut stack[..]));
    assert_eq!(got, Ok(full));
}

/// A box of the given corners.
fn slab3(lo: [f32; 3], hi: [f32; 3]) -> [[f32; 3]; 2] {
    [lo, hi]
}

/// The three-triangle fan under the unit square, `z = 0`, with a tree for it:
/// root 0 → (1, 2), node 1 a leaf of indices `0..1`, node 2 a leaf of `1..3`, every box the
/// unit square's.
fn fan() -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<BvhNode>) {
    let p = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let t = vec![[0, 1, 2], [0, 2, 3], [1, 2, 3]];
    let b = slab3([0.0; 3], [1.0, 1.0, 0.0]);
    let nodes = vec![
        BvhNode::from_raw(b, 1, 0),
        BvhNode::from_raw(b, 0, 1),
        BvhNode::from_raw(b, 1, 2),
    ];
    (p, t, nodes)
}

/// The loader's `BadBox` contract ("not finite, or `min > max`") holds at the root, which no
/// parent's containment check covers: each non-finite or inverted root box is refused with
/// exactly `BadBox { node: 0 }`; an inverted box inside its parent's box is refused as its own.
#[test]
fn a_root_box_that_is_infinite_nan_or_inverted_is_a_bad_box() {
    let (p, t, nodes) = fan();
    let mesh = TriangleMesh::new(&p, &t);
    let idx = [0u32, 1, 2];
    assert!(load(&nodes, &idx, &mesh).is_ok());
    let (inf, nan) = (f32::INFINITY, f32::NAN);
    let roots = [
        slab3([-inf; 3], [inf; 3]),
        slab3([-inf, 0.0, 0.0], [1.0, 1.0, 0.0]),
        slab3([0.0; 3], [1.0, inf, 0.0]),
        slab3([0.0, 0.0, -inf], [1.0, 1.0, 0.0]),
        slab3([0.0; 3], [1.0, 1.0, inf]),
        slab3([nan, 0.0, 0.0], [1.0, 1.0, 0.0]),
        slab3([0.0; 3], [1.0, nan, 0.0]),
        // Inverted on one axis (and so on every axis in turn).
        slab3([0.0, 0.0, 0.5], [1.0, 1.0, 0.0]),
        slab3([0.0, 2.0, 0.0], [1.0, 1.0, 0.0]),
        slab3([2.0, 0.0, 0.0], [1.0, 1.0, 0.0]),
    ];
    for (k, b) in roots.into_iter().enumerate() {
        let mut n = nodes.clone();
        n[0] = BvhNode::from_raw(b, 1, 0);
        assert_eq!(
            load(&n, &idx, &mesh).err(),
            Some(LoadError::BadBox { node: 0 }),
            "root box {k}: {b:?}"
        );
    }
    // A leaf box inverted in z but inside its parent's box on every bound: refused as itself.
    let mut n = nodes.clone();
    n[0] = BvhNode::from_raw(slab3([0.0, 0.0, -1.0], [1.0, 1.0, 1.0]), 1, 0);
    n[1] = BvhNode::from_raw(slab3([0.0, 0.0, 0.5], [1.0, 1.0, -0.5]), 0, 1);
    assert_eq!(
        load(&n, &idx, &mesh).err(),
        Some(LoadError::BadBox { node: 1 })
    );
}

/// A child box poking out of its parent's on any single bound is refused at the parent.
#[test]
fn a_child_box_outside_its_parent_on_one_bound_is_a_bad_box() {
    let (p, t, nodes) = fan();
    let mesh = TriangleMesh::new(&p, &t);
    let idx = [0u32, 1, 2];
    let big = slab3([-1.0; 3], [2.0; 3]);
    for child in [1, 2] {
        for side in 0..2 {
            for axis in 0..3 {
                let mut n = nodes.clone();
                let mut b = big;
                b[side][axis] += if side == 0 { -1.0 } else { 1.0 };
                n[0] = BvhNode::from_raw(big, 1, 0);
                let (_, s, c) = n[child].to_raw();
                n[child] = BvhNode::from_raw(if child == 1 { b } else { big }, s, c);
                let (_, s2, c2) = n[3 - child].to_raw();
                n[3 - child] = BvhNode::from_raw(if child == 1 { big } else { b }, s2, c2);
                assert_eq!(
                    load(&n, &idx, &mesh).err(),
                    Some(LoadError::BadBox { node: 0 }),
                    "child {child}, side {side}, axis {axis}"
                );
            }
        }
    }
}

/// One error per broken invariant of the small fan, each the exact variant and numbers the
/// docs name.
#[test]
fn each_error_variant_on_a_small_tree() {
    let (p, t, nodes) = fan();
    let mesh = TriangleMesh::new(&p, &t);
    let idx = [0u32, 1, 2];
    let b = nodes[0].bounds;
    // `NodeCount`: none for a non-empty mesh, some for the empty mesh, more than
    // `node_capacity + 1`.
    assert_eq!(
        load(&[], &idx, &mesh).err(),
        Some(LoadError::NodeCount {
            nodes: 0,
            triangles: 3
        })
    );
    let empty = TriangleMesh::new(&[], &[]);
    assert_eq!(
        load(&nodes[..1], &[], &empty).err(),
        Some(LoadError::NodeCount {
            nodes: 1,
            triangles: 0
        })
    );
    let mut long = nodes.clone();
    long.resize(node_capacity(3) + 2, BvhNode::EMPTY);
    assert_eq!(
        load(&long, &idx, &mesh).err(),
        Some(LoadError::NodeCount {
            nodes: 7,
            triangles: 3
        })
    );
    // Unreached nodes up to `node_capacity + 1` are not read.
    long.truncate(node_capacity(3) + 1);
    assert!(load(&long, &idx, &mesh).is_ok());
    // `IndexCount`: one index too many.
    assert_eq!(
        load(&nodes, &[0, 1, 2, 2], &mesh).err(),
        Some(LoadError::IndexCount {
            indices: 4,
            triangles: 3
        })
    );
    // `Capacity`: no bitset words for a mesh that needs one; any larger bitset works.
    assert_eq!(
        Bvh::from_parts(&nodes[..], &idx[..], &mesh, &mut []).err(),
        Some(LoadError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhLoadBitset,
            needed: 1,
            available: 0
        }))
    );
    assert!(Bvh::from_parts(&nodes[..], &idx[..], &mesh, &mut [u32::MAX; 3]).is_ok());
    // `ChildOutOfRange`: children at the node itself, and a pair whose second is past the end.
    for first in [0, 2] {
        let mut n = nodes.clone();
        n[0] = BvhNode::from_raw(b, first, 0);
        assert_eq!(
            load(&n, &idx, &mesh).err(),
            Some(LoadError::ChildOutOfRange { node: 0 }),
            "first child {first}"
        );
    }
    // `SharedNode`: nodes 1 and 2 are both inner with children 3, 4; node 3 is reached again
    // on the sixth visit of five nodes.
    let shared = vec![
        BvhNode::from_raw(b, 1, 0),
        BvhNode::from_raw(b, 3, 0),
        BvhNode::from_raw(b, 3, 0),
        BvhNode::from_raw(b, 0, 1),
        BvhNode::from_raw(b, 1, 2),
    ];
    assert_eq!(
        load(&shared, &idx, &mesh).err(),
        Some(LoadError::SharedNode { node: 3 })
    );
    // `LeafRange`: a range starting past the covered prefix, and one running past the end.
    for (start, count, leaf) in [(0, 1, 2), (1, 3, 2), (2, 1, 2)] {
        let mut n = nodes.clone();
        n[leaf] = BvhNode::from_raw(b, start, count);
        assert_eq!(
            load(&n, &idx, &mesh).err(),
            Some(LoadError::LeafRange { node: leaf }),
            "leaf {leaf} at {start}..+{count}"
        );
    }
    // `BadIndex`: a triangle number inside the bitset's word but past the mesh, one past
    // the word, and a repeat.
    for (bad, position) in [
        ([0, 5, 2], 1),
        ([0, 1, 40], 2),
        ([0, 1, 1], 2),
        ([2, 1, 2], 2),
    ] {
        assert_eq!(
            load(&nodes, &bad, &mesh).err(),
            Some(LoadError::BadIndex { position }),
            "{bad:?}"
        );
    }
    // `BadTriangle`: a vertex index past the vertices, and a non-finite vertex; both before
    // the box is checked against them.
    let t_bad = [[0, 1, 2], [0, 2, 9], [1, 2, 3]];
    assert_eq!(
        load(&nodes, &idx, &TriangleMesh::new(&p, &t_bad)).err(),
        Some(LoadError::BadTriangle { triangle: 1 })
    );
    for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut q = p.clone();
        q[3].y = v;
        assert_eq!(
            load(&nodes, &idx, &TriangleMesh::new(&q, &t)).err(),
            Some(LoadError::BadTriangle { triangle: 1 }),
            "{v}"
        );
    }
    // `BadBox` for a leaf missing one vertex by one ulp.
    let mut q = p.clone();
    q[2].x = f32::from_bits(1.0f32.to_bits() + 1);
    assert_eq!(
        load(&nodes, &idx, &TriangleMesh::new(&q, &t)).err(),
        Some(LoadError::BadBox { node: 1 })
    );
    // `Uncovered`: one leaf for the first two indices only.
    let root_leaf = [BvhNode::from_raw(b, 0, 2)];
    assert_eq!(
        load(&root_leaf, &idx, &mesh).err(),
        Some(LoadError::Uncovered {
            covered: 2,
            indices: 3
        })
    );
    let root_leaf = [BvhNode::from_raw(b, 0, 3)];
    assert!(load(&root_leaf, &idx, &mesh).is_ok());
}

/// Every error's message names its numbers.
#[test]
fn each_error_message_names_its_numbers() {
    let cases = [
        (
            LoadError::IndexCount {
                indices: 11,
                triangles: 12,
            },
            "11 primitive indices for a mesh of 12 triangles",
        ),
        (
            LoadError::NodeCount {
                nodes: 13,
                triangles: 14,
            },
            "13 nodes cannot form a tree over 14 triangles",
        ),
        (
            LoadError::Capacity(crate::error::CapacityError {
                storage: crate::error::Storage::BvhLoadBitset,
                needed: 15,
                available: 16,
            }),
            "BVH load bitset too small: 15 needed, 16 available",
        ),
        (LoadError::ChildOutOfRange { node: 17 }, "node 17: children"),
        (
            LoadError::TooDeep { node: 18 },
            "node 18: an inner node at depth 64",
        ),
        (
            LoadError::SharedNode { node: 19 },
            "node 19 is reached by two",
        ),
        (LoadError::BadBox { node: 20 }, "node 20: box not finite"),
        (
            LoadError::LeafRange { node: 21 },
            "leaf 21: its index range",
        ),
        (LoadError::BadIndex { position: 22 }, "index 22 names no"),
        (
            LoadError::BadTriangle { triangle: 23 },
            "triangle 23: vertex",
        ),
        (
            LoadError::Uncovered {
                covered: 24,
                indices: 25,
            },
            "the leaves cover 24 of 25",
        ),
    ];
    for (e, want) in cases {
        let s = std::format!("{e}");
        assert!(s.contains(want), "{s:?} lacks {want:?}");
    }
}

/// 64-byte aligned node storage, so the builder uses its spare slot for padding.
#[repr(C, align(64))]
struct Aligned([BvhNode; 32]);

/// The builder's padded layout (node 1 an unreached `EMPTY` slot, `node_capacity + 1` nodes
/// in use when every leaf holds one triangle) loads and answers as brute force; one node more
/// is `NodeCount`.
#[test]
fn the_builders_padded_layout_loads() {
    let mut rng = 23u64;
    let (p, t) = grid(2, &mut rng);
    let mesh = TriangleMesh::new(&p, &t);
    assert_eq!(t.len(), 8);
    let mut store = Aligned([BvhNode::EMPTY; 32]);
    let mut idx = [0u32; 8];
    let options = BuildOptions {
        max_leaf_size: 1,
        ..BuildOptions::default()
    };
    let used = Bvh::build(&mesh, &mut store.0[..], &mut idx[..], &options)
        .unwrap()
        .node_count();
    assert_eq!(used, node_capacity(8) + 1);
    assert_eq!(store.0[1], BvhNode::EMPTY);
    let bvh = load(&store.0[..used], &idx, &mesh).unwrap();
    assert_eq!(bvh.node_count(), used);
    for _ in 0..500 {
        let o = Vec3::new(lcg(&mut rng) * 3.0 - 0.5, lcg(&mut rng) * 3.0 - 0.5, 3.0);
        let ray = Ray::new(o, Vec3::new(lcg(&mut rng) - 0.5, lcg(&mut rng) - 0.5, -1.0));
        let got = closest_watertight(&bvh, &mesh, &ray).map(|(i, h)| (i, h.t.to_bits()));
        assert_eq!(got, brute(&mesh, &ray));
    }
    assert_eq!(
        load(&store.0[..used + 1], &idx, &mesh).err(),
        Some(LoadError::NodeCount {
            nodes: used + 1,
            triangles: 8
        })
    );
}

/// The caterpillar mirrored: every inner node's *first* child is the next inner node and its
/// second a leaf, so the depth-first walk keeps one pending leaf per level (the loader's
/// stack fills to `MAX_DEPTH + 1` entries at the deepest inner node). Inner node at depth `k`
/// is node `2k − 1` (the root node 0), with children `2k + 1` and `2k + 2`; triangle `k` at
/// `z = k`; depth-first order lists triangles `n − 2, n − 1, n − 3, …, 0`.
fn mirrored_caterpillar(n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<BvhNode>, Vec<u32>) {
    let (p, t, _) = caterpillar(n);
    let slab = |lo: usize, hi: usize| [[0.0, 0.0, lo as f32], [1.0, 1.0, hi as f32]];
    let inner = |k: usize| if k == 0 { 0 } else { 2 * k - 1 };
    // Position of triangle k in depth-first order.
    let position = |k: usize| match k {
        _ if k == n - 2 => 0,
        _ if k == n - 1 => 1,
        _ => n - 1 - k,
    };
    let mut nodes = vec![BvhNode::EMPTY; 2 * n - 1];
    let mut idx = vec![0u32; n];
    for k in 0..n - 1 {
        nodes[inner(k)] = BvhNode::from_raw(slab(k, n - 1), 2 * k as u32 + 1, 0);
    }
    for k in 0..n {
        let leaf = if k == n - 1 { 2 * n - 2 } else { 2 * k + 2 };
        let leaf = if k == n - 2 { 2 * n - 3 } else { leaf };
        nodes[leaf] = BvhNode::from_raw(slab(k, k), position(k) as u32, 1);
        idx[position(k)] = k as u32;
    }
    (p, t, nodes, idx)
}

#[test]
fn the_mirrored_deepest_chain_loads_and_one_level_more_is_too_deep() {
    // Deepest inner node at depth 63: accepted, traversed with a stack of `MAX_DEPTH`.
    let (p, t, nodes, idx) = mirrored_caterpillar(MAX_DEPTH + 1);
    let mesh = TriangleMesh::new(&p, &t);
    let bvh = load(&nodes, &idx, &mesh).unwrap();
    assert_eq!(bvh.stack_depth(), MAX_DEPTH);
    assert_eq!(bvh.stats().max_depth, MAX_DEPTH);
    let mut stack = [StackEntry::EMPTY; MAX_DEPTH];
    for (o, d, want) in [(70.0, -1.0, (MAX_DEPTH as u32, 6.0)), (-3.0, 1.0, (0, 3.0))] {
        let ray = Ray::new(Vec3::new(0.25, 0.25, o), Vec3::new(0.0, 0.0, d));
        let got = closest_watertight_in(&bvh, &mesh, &ray, &mut Query::new().stack(&mut stack[..]));
        assert_eq!(got.map(|h| h.map(|(i, h)| (i, h.t))), Ok(Some(want)));
        assert_eq!(brute(&mesh, &ray).map(|(i, _)| i), Some(want.0));
    }
    // Depth 64: refused at that inner node.
    let (p, t, nodes, idx) = mirrored_caterpillar(MAX_DEPTH + 2);
    let mesh = TriangleMesh::new(&p, &t);
    assert_eq!(
        load(&nodes, &idx, &mesh).err(),
        Some(LoadError::TooDeep {
            node: 2 * MAX_DEPTH - 1
        })
    );
}
