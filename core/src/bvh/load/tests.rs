//! Unit tests of `load`.

use super::*;
use crate::bvh::BuildOptions;
use crate::ray::Ray;
use crate::test_util::lcg;
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
        let got = bvh
            .closest_hit_triangles(&mesh, &Watertight, &ray, None)
            .map(|(i, h)| (i, h.t.to_bits()));
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
    assert!(matches!(
        load(&nodes, &idx[..idx.len() - 1], &mesh),
        Err(LoadError::IndexCount { .. })
    ));
    assert!(matches!(
        load(&nodes[..nodes.len() - 1], &idx, &mesh),
        Err(LoadError::ChildOutOfRange { .. }
            | LoadError::LeafRange { .. }
            | LoadError::Uncovered { .. })
    ));
    let mut small = [0u32; 1];
    assert_eq!(
        Bvh::from_parts(&nodes[..], &idx[..], &mesh, &mut small).err(),
        Some(LoadError::ScratchTooSmall {
            needed: load_scratch_len(t.len()),
            available: 1
        })
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
            let got = bvh
                .closest_hit_triangles(&mesh, &Watertight, &ray, None)
                .map(|(i, h)| (i, h.t.to_bits()));
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
    let full = bvh.closest_hit_triangles(&mesh, &Watertight, &ray, None);
    assert_eq!(full.map(|(i, h)| (i, h.t)), Some((64, 6.0)));
    let mut stack = [crate::bvh::StackEntry::EMPTY; MAX_DEPTH];
    let got = bvh.closest_hit_triangles_in(&mut stack, &mesh, &Watertight, &ray, None);
    assert_eq!(got, Ok(full));
}
