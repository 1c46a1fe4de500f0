//! Unit tests of the wide tree's box query on trees written by hand.

use super::*;
use crate::bvh::wide::{group_capacity, node_capacity};
use crate::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, load_scratch_len};
use crate::mesh::TriangleMesh;
use crate::query::{QUERY_STACK_SIZE, QueryStack, StackEntry, TraversalStats, Triangles};
use crate::test_util::triangle_meets_box;
use crate::triangle::Watertight;
use glam::Vec3;
use std::vec;
use std::vec::Vec;

/// A binary tree written by hand: leaves hold their triangles.
enum Tree {
    Leaf(Vec<[Vec3; 3]>),
    Inner(std::boxed::Box<Tree>, std::boxed::Box<Tree>),
}

/// Writes `tree` at node `at` (children appended as pairs, leaves in depth-first order, so
/// that `Bvh::from_parts` accepts it) and returns its box.
fn place(tree: &Tree, at: usize, nodes: &mut Vec<BvhNode>, tris: &mut Vec<[Vec3; 3]>) -> Aabb {
    match tree {
        Tree::Leaf(ts) => {
            let start = tris.len() as u32;
            tris.extend_from_slice(ts);
            let b = ts
                .iter()
                .flatten()
                .fold(Aabb::EMPTY, |b, &p| b.union(Aabb::new(p, p)));
            nodes[at] =
                BvhNode::from_raw([b.min.to_array(), b.max.to_array()], start, ts.len() as u32);
            b
        }
        Tree::Inner(l, r) => {
            let c = nodes.len();
            nodes.extend([BvhNode::EMPTY; 2]);
            let b = place(l, c, nodes, tris).union(place(r, c + 1, nodes, tris));
            nodes[at] = BvhNode::from_raw([b.min.to_array(), b.max.to_array()], c as u32, 0);
            b
        }
    }
}

/// A small triangle at `c` of size `s`.
fn tri(c: Vec3, s: f32) -> [Vec3; 3] {
    [c, c + Vec3::new(s, 0.0, 0.0), c + Vec3::new(0.0, s, s)]
}

/// `n` small triangles about `c` (scale `s`).
fn leaf(n: usize, c: Vec3, s: f32) -> Tree {
    Tree::Leaf(
        (0..n)
            .map(|i| tri(c + Vec3::splat(i as f32 * 0.01 * s), 0.1 * s))
            .collect(),
    )
}

/// The box query keeps every pending child on its stack, up to its bound of
/// `(W − 1)·MAX_DEPTH + W`: a tree whose walk holds 90 pending children at once (more than
/// `MAX_DEPTH + 16`, far fewer than the bound) reports every triangle to a box holding all
/// of them, and to a box holding only the deepest ones exactly those (the oracle: each
/// triangle's box against the query, by brute force).
///
/// The binary tree, level `k = 0..30` at scale `s = 0.8ᵏ`: `p_k = (S_k, q_k)`,
/// `S_k = (9 triangles about −5s, 8 about +5s)` (17 > `LEAF_MERGE`: an inner entry),
/// `q_k = (1 triangle about the origin, p_{k+1})`, `p_30` one triangle. `S_k`'s box (side
/// ~10s) is larger than `q_k`'s (side ~8.8s), so the 4-wide collapse makes `p_k` the node
/// `[S_k's two leaves, q_k's triangle, p_{k+1}]` (worked by the rule of `child_list`): 30
/// wide levels, the next level in the last slot, which the depth-first walk pops first,
/// leaving three children per level pending.
#[test]
fn box_query_keeps_every_pending_child_of_a_deep_lopsided_tree() {
    const LEVELS: i32 = 30;
    let mut tree = leaf(1, Vec3::ZERO, 0.8f32.powi(LEVELS));
    for k in (0..LEVELS).rev() {
        let s = 0.8f32.powi(k);
        let big = Tree::Inner(
            leaf(9, Vec3::splat(-5.0 * s), s).into(),
            leaf(8, Vec3::splat(5.0 * s), s).into(),
        );
        let q = Tree::Inner(leaf(1, Vec3::splat(0.1 * s), s).into(), tree.into());
        tree = Tree::Inner(big.into(), q.into());
    }
    let (mut nodes, mut tris) = (vec![BvhNode::EMPTY], Vec::new());
    place(&tree, 0, &mut nodes, &mut tris);
    let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
    let triangles: Vec<[u32; 3]> = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let mesh = TriangleMesh::new(&positions, &triangles);
    let indices: Vec<u32> = (0..tris.len() as u32).collect();
    let mut scratch = vec![0u32; load_scratch_len(mesh.len())];
    let binary = Bvh::from_parts(&nodes[..], &indices[..], &mesh, &mut scratch).unwrap();
    let count = WideBvh::<4, Vec<WideNode<4>>, Vec<LeafGroup>>::node_count_for(&binary).unwrap();
    let groups = WideBvh::<4, Vec<WideNode<4>>, Vec<LeafGroup>>::group_count_for(&binary).unwrap();
    let wide = WideBvh::<4, _, _>::from_binary(
        &binary,
        &mesh,
        vec![WideNode::<4>::EMPTY; count],
        vec![LeafGroup::EMPTY; groups],
    )
    .unwrap();
    assert_eq!(
        wide.node_count(),
        LEVELS as usize,
        "one wide node per level"
    );
    assert_eq!(tris.len(), 18 * LEVELS as usize + 1);
    let deep = 0.8f32.powi(LEVELS - 3) * 6.0;
    for q in [
        Aabb::new(Vec3::splat(-10.0), Vec3::splat(10.0)),
        Aabb::new(Vec3::splat(-deep), Vec3::splat(deep)),
    ] {
        let mut got = Vec::new();
        wide.query_box(&mesh, &q, |p| {
            got.push(p);
            true
        });
        got.sort_unstable();
        let want: Vec<u32> = (0..tris.len() as u32)
            .filter(|&i| triangle_meets_box(&tris[i as usize], q.min, q.max))
            .collect();
        assert!(want.len() > 30, "{}", want.len());
        assert_eq!(got, want);
    }
}

type VecWide8 = WideBvh<8, Vec<WideNode<8>>, Vec<LeafGroup>>;

/// The 8-wide tree over `mesh`, built as the docs say (binary build with `binary_options`,
/// then the collapse).
fn wide8(mesh: &TriangleMesh<'_>) -> VecWide8 {
    let n = mesh.len();
    let binary = Bvh::build(
        mesh,
        vec![BvhNode::EMPTY; crate::bvh::node_capacity(n)],
        vec![0u32; index_capacity(n)],
        &crate::bvh::wide::binary_options(BuildOptions::default()),
    )
    .unwrap();
    WideBvh::from_binary(
        &binary,
        mesh,
        vec![WideNode::EMPTY; node_capacity(n)],
        vec![LeafGroup::EMPTY; group_capacity(n)],
    )
    .unwrap()
}

/// Rays from one origin in front of `lcg_soup(400, 7, 4.0, 1.0)`: toward it, and away from it
/// (another octant: never in the first one's packet).
const TOWARD: Ray = Ray::new(Vec3::new(0.3, 0.1, -12.0), Vec3::new(0.01, 0.02, 1.0));
const AWAY: Ray = Ray::new(Vec3::new(0.3, 0.1, -12.0), Vec3::new(0.01, 0.02, -1.0));

/// The batch query walks a chunk of 16 rays as a packet when its coherent rays are at least
/// three quarters of it (`packet` module docs): 12 of 16 form a packet, 11 do not. What
/// shows it: the statistics count a packet's node tests once (`packet` module docs), so the
/// batch visits fewer nodes than the same rays one by one with 12 equal rays and 4 of
/// another octant, and exactly as many with 11 and 5 (every ray then walks alone). The
/// answers equal the single-ray ones either way.
#[test]
fn a_chunk_is_a_packet_from_three_quarters_coherent_rays() {
    let (pos, tri) = crate::test_util::lcg_soup(400, 7, 4.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tri);
    let wide = wide8(&mesh);
    for (coherent, packet) in [(12, true), (11, false)] {
        let rays: Vec<Ray> = (0..16)
            .map(|i| if i < coherent { TOWARD } else { AWAY })
            .collect();
        let mut tris = Triangles::new(&mesh, &Watertight);
        let (mut batch, mut alone) = (TraversalStats::default(), TraversalStats::default());
        let mut out = vec![None; 16];
        let mut stack = QueryStack::new();
        wide.closest_hits(
            &rays,
            &mut tris,
            &mut Query::new().stack(&mut stack).stats(&mut batch),
            &mut out,
        )
        .unwrap();
        for (ray, got) in rays.iter().zip(&out) {
            let single = wide.closest_hit(ray, &mut tris, &mut Query::new().stats(&mut alone));
            assert_eq!(*got, single);
        }
        assert!(out[0].is_some(), "the coherent rays hit the soup");
        if packet {
            assert!(
                batch.nodes_visited < alone.nodes_visited,
                "{batch:?} {alone:?}"
            );
        } else {
            assert_eq!(batch, alone);
        }
    }
}

/// On a caller stack shorter than `QUERY_STACK_SIZE` every ray of a batch gets the
/// single-ray answer, the error `StackTooSmall` naming the entries given (`closest_hits`'
/// docs), coherent rays included (no packet walk for them); a stack of exactly that size
/// answers them.
#[test]
fn a_batch_on_a_short_caller_stack_answers_each_ray_the_stack_error() {
    let (pos, tri) = crate::test_util::lcg_soup(400, 7, 4.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tri);
    let wide = wide8(&mesh);
    let rays = [TOWARD; 16];
    let mut tris = Triangles::new(&mesh, &Watertight);
    for available in [QUERY_STACK_SIZE - 1, QUERY_STACK_SIZE] {
        let mut stack = vec![StackEntry::EMPTY; available];
        let mut out = vec![Ok(None); 16];
        wide.closest_hits(
            &rays,
            &mut tris,
            &mut Query::new().stack(&mut stack[..]),
            &mut out,
        )
        .unwrap();
        let single = wide.closest_hit(&TOWARD, &mut tris, &mut Query::new().stack(&mut stack[..]));
        if available < QUERY_STACK_SIZE {
            assert_eq!(single, Err(QueryError::StackTooSmall { available }));
        } else {
            assert!(matches!(single, Ok(Some(_))), "{single:?}");
        }
        assert!(out.iter().all(|o| *o == single), "{available}: {out:?}");
    }
}

/// A tree with no node (empty, or its root a leaf) needs no stack entry (`stack_depth` 0):
/// on a caller stack of 0 or 1 entries every query answers, as brute force does, singly and
/// in a batch; a tree with nodes, 8-wide or 4-wide, needs `QUERY_STACK_SIZE` entries and
/// refuses one fewer for every ray, an invalid ray included (the refusal does not depend on
/// the ray: `WideBvh::stack_depth`'s contract).
#[test]
fn a_tree_without_nodes_needs_no_stack_and_one_with_nodes_needs_the_whole_stack() {
    use crate::test_util::{brute_watertight, lcg_soup, vec_bvh, vec_wide};
    let (pos, tri) = lcg_soup(4, 3, 2.0, 1.0);
    let small = TriangleMesh::new(&pos, &tri);
    let none = TriangleMesh::new(&pos, &[]);
    let binary_opts = crate::bvh::wide::binary_options(BuildOptions::default());
    // Toward each triangle's centroid and beside it, from one origin.
    let rays: Vec<Ray> = tri
        .iter()
        .flat_map(|t| {
            let c = (pos[t[0] as usize] + pos[t[1] as usize] + pos[t[2] as usize]) / 3.0;
            (0..16).map(move |k| {
                let aim = c + Vec3::new(k as f32 * 0.05 - 0.4, (k % 3) as f32 * 0.1, 0.0);
                let from = Vec3::new(0.0, 0.0, -20.0);
                Ray::new(from, aim - from)
            })
        })
        .collect();
    for mesh in [&small, &none] {
        let binary = vec_bvh(mesh, &binary_opts).unwrap();
        let wide = vec_wide::<8>(&binary, mesh).unwrap();
        assert_eq!(wide.stack_depth(), 0, "{} triangles", mesh.len());
        let mut tris = Triangles::new(mesh, &Watertight);
        let mut hits = 0;
        for len in [0, 1] {
            let mut stack = vec![StackEntry::EMPTY; len];
            let mut out = vec![Ok(None); rays.len()];
            let mut any = vec![Ok(None); rays.len()];
            let ctx = &mut Query::new().stack(&mut stack[..]);
            wide.closest_hits(&rays, &mut tris, ctx, &mut out).unwrap();
            wide.any_hits(&rays, &mut tris, ctx, &mut any).unwrap();
            for (i, ray) in rays.iter().enumerate() {
                let want = brute_watertight(mesh, ray);
                hits += usize::from(want.is_some());
                assert_eq!(wide.closest_hit(ray, &mut tris, ctx), Ok(want), "{ray:?}");
                assert_eq!(out[i], Ok(want), "batch {ray:?}");
                let single_any = wide.any_hit(ray, &mut tris, ctx);
                assert_eq!(
                    single_any.map(|a| a.is_some()),
                    Ok(want.is_some()),
                    "{ray:?}"
                );
                assert_eq!(any[i].map(|a| a.is_some()), Ok(want.is_some()), "{ray:?}");
            }
        }
        assert_eq!(
            hits > 0,
            !mesh.is_empty(),
            "the rays must hit the small mesh"
        );
    }

    let (pos, tri) = lcg_soup(400, 7, 4.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tri);
    let binary = vec_bvh(&mesh, &binary_opts).unwrap();
    let (w8, w4) = (
        vec_wide::<8>(&binary, &mesh).unwrap(),
        vec_wide::<4>(&binary, &mesh).unwrap(),
    );
    assert_eq!(
        (w8.stack_depth(), w4.stack_depth()),
        (QUERY_STACK_SIZE, QUERY_STACK_SIZE)
    );
    let invalid = Ray::new(Vec3::NAN, Vec3::X);
    let mut tris = Triangles::new(&mesh, &Watertight);
    let mut less = vec![StackEntry::EMPTY; QUERY_STACK_SIZE - 1];
    let available = less.len();
    for ray in [TOWARD, AWAY, invalid] {
        let ctx = &mut Query::new().stack(&mut less[..]);
        let refused = Err(QueryError::StackTooSmall { available });
        assert_eq!(w8.closest_hit(&ray, &mut tris, ctx), refused, "{ray:?}");
        assert_eq!(w4.closest_hit(&ray, &mut tris, ctx), refused, "{ray:?}");
        assert_eq!(
            w4.any_hit(&ray, &mut tris, ctx).map(|_| ()),
            Err(QueryError::StackTooSmall { available })
        );
    }
}
