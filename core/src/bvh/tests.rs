//! Unit tests of the BVH (the mesh-scale comparisons with brute force live in
//! `tests/tests/bvh_vs_bruteforce.rs`).

use super::*;
use crate::aabb::Aabb;
use crate::mesh::TriangleMesh;
use crate::prelude::*;
use crate::query::walk::pad_to_root;
use crate::query::{Query, QueryError, StackEntry, TraversalStats, Triangles};
use crate::ray::Ray;
use crate::test_util::{
    Lcg, VecBvh, any_watertight, brute_box, brute_watertight, closest_watertight,
    closest_watertight_in, lcg_soup, vec_bvh as build,
};
use crate::triangle::{TriangleIntersector, Watertight};
use glam::Vec3;
use std::format;
use std::vec;
use std::vec::Vec;

/// [`Bvh::build_with_scratch`] into full-capacity vectors, with the caller's `scratch`.
fn build_scratch(
    mesh: &TriangleMesh<'_>,
    scratch: &mut [PrimRef],
    opts: &BuildOptions,
) -> Result<VecBvh, BvhError> {
    let n = mesh.len();
    Bvh::build_with_scratch(
        mesh,
        vec![BvhNode::EMPTY; node_capacity(n)],
        vec![0u32; index_capacity(n)],
        scratch,
        opts,
    )
}

/// The error of a default-options build of `mesh` into `nodes` and `idx`, which must be
/// refused (panics on a successful build).
fn refused(mesh: &TriangleMesh<'_>, nodes: &mut [BvhNode], idx: &mut [u32]) -> BvhError {
    Bvh::build(mesh, nodes, idx, &BuildOptions::default()).unwrap_err()
}

/// The tests' brute force as `(triangle, t)` ([`brute_watertight`]).
fn brute(mesh: &TriangleMesh<'_>, ray: &Ray) -> Option<(u32, f32)> {
    brute_watertight(mesh, ray).map(|(i, h)| (i, h.t))
}

/// `n` random triangles of size about 1 in a box of side 10 ([`lcg_soup`]).
fn soup(n: usize, seed: u64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    lcg_soup(n, seed, 10.0, 1.0)
}

#[test]
fn node_is_32_bytes_and_capacity_is_2n_minus_1() {
    assert_eq!(core::mem::size_of::<BvhNode>(), 32);
    assert_eq!(NODE_SIZE, 32);
    assert_eq!(node_capacity(0), 0);
    assert_eq!(node_capacity(1), 1);
    assert_eq!(node_capacity(10), 19);
    assert_eq!(node_capacity(usize::MAX), usize::MAX - 1, "saturates");
    assert_eq!(index_capacity(7), 7);
}

#[test]
fn empty_input_gives_an_empty_bvh_that_hits_nothing() {
    let mesh = TriangleMesh::new(&[], &[]);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    assert!(bvh.is_empty());
    assert_eq!(bvh.bounds(), crate::aabb::Aabb::EMPTY);
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert!(closest_watertight(&bvh, &mesh, &ray).is_none());
    assert!(any_watertight(&bvh, &mesh, &ray).is_none());
    let mut arr_nodes: [BvhNode; 0] = [];
    let mut arr_idx: [u32; 0] = [];
    assert!(
        Bvh::build(
            &mesh,
            &mut arr_nodes[..],
            &mut arr_idx[..],
            &BuildOptions::default()
        )
        .is_ok()
    );
}

#[test]
fn too_small_storage_is_an_error_before_writing() {
    let (pos, tris) = soup(10, 1);
    let mesh = TriangleMesh::new(&pos, &tris);
    let mut nodes = [BvhNode::EMPTY; 18];
    let mut idx = [7u32; 10];
    let err = refused(&mesh, &mut nodes, &mut idx);
    assert_eq!(
        err,
        BvhError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhNodes,
            needed: 19,
            available: 18
        })
    );
    assert!(nodes.iter().all(|n| *n == BvhNode::EMPTY));
    assert!(idx.iter().all(|&i| i == 7));
    let mut nodes = [BvhNode::EMPTY; 19];
    let mut idx = [7u32; 9];
    let err = refused(&mesh, &mut nodes, &mut idx);
    assert!(matches!(
        err,
        BvhError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhIndices,
            needed: 10,
            ..
        })
    ));
    assert!(nodes.iter().all(|n| *n == BvhNode::EMPTY));
    // Fixed arrays work as storage.
    let mut idx = [0u32; 10];
    let bvh = Bvh::build(&mesh, nodes, &mut idx, &BuildOptions::default()).unwrap();
    assert_eq!(bvh.primitive_count(), 10);
}

#[test]
fn non_finite_primitives_are_named_or_excluded() {
    let (mut pos, mut tris) = soup(8, 2);
    pos[7].y = f32::NAN; // triangle 2
    tris[5] = [0, 1, 999]; // triangle 5: index out of range
    let mesh = TriangleMesh::new(&pos, &tris);
    let mut nodes = vec![BvhNode::EMPTY; node_capacity(8)];
    let err = refused(&mesh, &mut nodes, &mut [0u32; 8]);
    assert_eq!(
        err,
        BvhError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Primitive,
            index: 2
        })
    );
    assert!(nodes.iter().all(|n| *n == BvhNode::EMPTY));
    let opts = BuildOptions {
        exclude_non_finite: true,
        ..BuildOptions::default()
    };
    let bvh = build(&mesh, &opts).unwrap();
    assert_eq!(bvh.primitive_count(), 6);
    assert!(bvh.bounds().is_finite());
    assert!(!bvh.indices().contains(&2) && !bvh.indices().contains(&5));
    // Infinite vertex too.
    pos[0] = Vec3::new(f32::INFINITY, 0.0, 0.0);
    let mesh = TriangleMesh::new(&pos, &tris);
    assert_eq!(
        build(&mesh, &BuildOptions::default()).unwrap_err(),
        BvhError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Primitive,
            index: 0
        })
    );
}

#[test]
fn closest_and_any_hit_match_brute_force_on_a_random_soup() {
    let (pos, tris) = soup(500, 3);
    let mesh = TriangleMesh::new(&pos, &tris);
    for leaf in [1, 4, 16] {
        let bvh = build(
            &mesh,
            &BuildOptions {
                max_leaf_size: leaf,
                ..BuildOptions::default()
            },
        )
        .unwrap();
        assert!(bvh.node_count() <= node_capacity(500));
        let mut r = Lcg(99);
        let mut hits = 0;
        for _ in 0..2000 {
            let o = r.v(30.0);
            let ray = Ray::new(o, r.v(10.0) - o);
            let got = closest_watertight(&bvh, &mesh, &ray).map(|(p, h)| (p, h.t));
            assert_eq!(got, brute(&mesh, &ray), "leaf {leaf} {ray:?}");
            let any = any_watertight(&bvh, &mesh, &ray);
            assert_eq!(any.is_some(), got.is_some());
            hits += usize::from(got.is_some());
        }
        assert!(hits > 100, "{hits}");
    }
}

/// The box padding follows how far the tree reaches from the ray's origin and the origin's
/// own resolution, not the coordinates' magnitude alone (`PadFrame::of`,
/// [`crate::tolerance::BVH_PROJECTION_PAD`]): a soup of side 10 moved `2·10⁴` from the
/// coordinate origin (an `f32` ulp of `2⁻¹⁰` there), its rays moved with it, tests at most
/// 10 % more triangles than at the origin (0.3 % more when written) and answers as brute
/// force. With the padding `γ₁₆·(max|o| + max|scene|)` (0.04 here) it tested 27 % more; a
/// smaller mesh (the bunny, 0.15 across, at the same place) nearly every triangle on every
/// ray.
#[test]
fn a_mesh_far_from_the_coordinate_origin_is_padded_by_its_reach() {
    let (pos, tris) = soup(2000, 17);
    let shift = Vec3::new(2.0e4, -5.0e3, 1.5e4);
    let far_pos: Vec<Vec3> = pos.iter().map(|&p| p + shift).collect();
    let (near, far) = (
        TriangleMesh::new(&pos, &tris),
        TriangleMesh::new(&far_pos, &tris),
    );
    let mut r = Lcg(71);
    let near_rays: Vec<Ray> = (0..1500)
        .map(|_| {
            let o = r.v(30.0);
            Ray::new(o, r.v(10.0) - o)
        })
        .collect();
    let tested = |mesh: &TriangleMesh<'_>, rays: &[Ray]| {
        let bvh = build(mesh, &BuildOptions::default()).unwrap();
        let mut st = TraversalStats::default();
        for ray in rays {
            let _ = closest_watertight_in(&bvh, mesh, ray, &mut Query::new().stats(&mut st));
        }
        st.primitives_tested
    };
    let far_rays: Vec<Ray> = near_rays
        .iter()
        .map(|r| Ray::new(r.origin + shift, r.direction))
        .collect();
    let (at_origin, moved) = (tested(&near, &near_rays), tested(&far, &far_rays));
    assert!(
        moved * 10 <= at_origin * 11,
        "{moved} triangles tested far away, {at_origin} at the origin"
    );
    let bvh = build(&far, &BuildOptions::default()).unwrap();
    let mut hits = 0;
    for ray in &far_rays {
        let got = closest_watertight(&bvh, &far, ray).map(|(p, h)| (p, h.t));
        assert_eq!(got, brute(&far, ray), "{ray:?}");
        hits += usize::from(got.is_some());
    }
    assert!(hits > 300, "{hits}");
}

/// The node test's far distances are padded by a relative factor only: for the unit box and
/// a ray along `(1, −1, 0)` from `(−1, y₀, 0.5)`, by hand the ray is inside the box's `x` slab
/// for `t ∈ [1, 2]` and inside its `y` slab for `t ∈ [y₀ − 1, y₀]`; with `y₀ = 2.5` they
/// overlap on `[1.5, 2]` (a hit entered at `t = 1.5`), with `y₀ = 3.2` they miss each other by
/// `0.2` in `t`, which no rounding padding may bridge.
#[test]
fn node_test_far_padding_does_not_bridge_a_gap() {
    let tri = [
        Vec3::ZERO,
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 1.0),
    ];
    let mesh = TriangleMesh::new(&tri, &[[0, 1, 2]]);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let root = bvh.nodes()[0];
    assert_eq!(root.bounds(), Aabb::new(Vec3::ZERO, Vec3::ONE));
    let test = |y0: f32| {
        let ray = Ray::new(Vec3::new(-1.0, y0, 0.5), Vec3::new(1.0, -1.0, 0.0));
        let slab = crate::aabb::SlabRay::new(&ray).unwrap();
        let padded = padded_ray::PaddedRay::new(&slab, pad_to_root(&root.bounds(), slab.origin));
        padded.hit_node(false, &root, 0.0, f32::INFINITY)
    };
    let hit = test(2.5).expect("the slabs overlap on [1.5, 2]");
    assert!((hit - 1.5).abs() <= 1e-5, "{hit}");
    assert_eq!(test(3.2), None);
    // With `y₀ = 1` the slabs meet only at `t = 1` (the ray touches the box's edge x = y = 0),
    // every distance exact: the closed test hits there, with no projection padding to help
    // (a far distance shrunk by its padding factor instead of grown would miss).
    let ray = Ray::new(Vec3::new(-1.0, 1.0, 0.5), Vec3::new(1.0, -1.0, 0.0));
    let slab = crate::aabb::SlabRay::new(&ray).unwrap();
    let unpadded = padded_ray::PaddedRay::new(&slab, 0.0);
    assert_eq!(
        unpadded.hit_node(false, &root, 0.0, f32::INFINITY),
        Some(1.0)
    );
    assert_eq!(unpadded.hit_node(false, &root, 0.0, 1.0), Some(1.0));
    assert_eq!(
        unpadded.hit_node(false, &root, 0.0, 1.0f32.next_down()),
        None
    );
}

/// The node test prunes: on a 32 × 32 grid of separate unit triangles (1 024 in the plane
/// `z = 0`), a ray straight down onto one triangle's interior tests only the leaves on its
/// path (a few triangles, a few dozen nodes of the ~2 000), and a ray that passes beside the
/// grid visits only the root's children. Answers alone cannot show this: a node test that
/// reported every box as hit would still answer like brute force.
#[test]
fn node_test_prunes_the_tree() {
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for j in 0..32u32 {
        for i in 0..32u32 {
            let o = Vec3::new(2.0 * i as f32, 2.0 * j as f32, 0.0);
            let b = pos.len() as u32;
            pos.extend([o, o + Vec3::X, o + Vec3::Y]);
            tris.push([b, b + 1, b + 2]);
        }
    }
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let mut st = TraversalStats::default();
    let down = Ray::new(
        Vec3::new(2.0 * 7.0 + 0.25, 2.0 * 11.0 + 0.25, 5.0),
        -Vec3::Z,
    );
    let hit = closest_watertight_in(&bvh, &mesh, &down, &mut Query::new().stats(&mut st));
    assert_eq!(hit.map(|(p, _)| p), Some(11 * 32 + 7));
    assert!(
        st.primitives_tested <= 8 && st.nodes_visited <= 64,
        "{st:?} of {} nodes",
        bvh.node_count()
    );
    let mut st = TraversalStats::default();
    let beside = Ray::new(Vec3::new(-5.0, 10.0, 1.0), Vec3::Y);
    assert!(
        closest_watertight_in(&bvh, &mesh, &beside, &mut Query::new().stats(&mut st)).is_none()
    );
    // Both children of the root are tested (and missed): exactly two node tests.
    assert!(st.primitives_tested == 0 && st.nodes_visited == 2, "{st:?}");
}

/// The near child is visited first: down a stack of 16 unit triangles one unit apart (one per
/// leaf), the closest hit is the top one, found after a few triangle tests; the boxes below
/// it are culled, not visited. Of two children entered at the same distance the first is
/// visited first: an any-hit query through two coincident triangles in separate leaves
/// returns the first child's.
#[test]
fn near_child_first_and_ties_to_the_first_child() {
    let one_per_leaf = BuildOptions {
        max_leaf_size: 1,
        leaf_threshold: 1,
        ..BuildOptions::default()
    };
    let mut pos = Vec::new();
    for k in 0..16 {
        let z = k as f32;
        pos.extend([
            Vec3::new(0.0, 0.0, z),
            Vec3::X + z * Vec3::Z,
            Vec3::Y + z * Vec3::Z,
        ]);
    }
    let tris: Vec<[u32; 3]> = (0..16u32).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &one_per_leaf).unwrap();
    for (origin, dir, want) in [(20.0, -1.0, 15u32), (-5.0, 1.0, 0)] {
        let ray = Ray::new(Vec3::new(0.25, 0.25, origin), dir * Vec3::Z);
        let mut st = TraversalStats::default();
        let hit = closest_watertight_in(&bvh, &mesh, &ray, &mut Query::new().stats(&mut st));
        assert_eq!(hit.map(|(p, _)| p), Some(want));
        assert!(st.primitives_tested <= 2, "from z = {origin}: {st:?}");
    }

    let twins = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let mesh = TriangleMesh::new(&twins, &[[0, 1, 2], [0, 1, 2]]);
    let bvh = build(&mesh, &one_per_leaf).unwrap();
    let (left, _) = bvh.nodes()[0]
        .children()
        .expect("two leaves under the root");
    let first = bvh.nodes()[left as usize].primitive_range().unwrap();
    let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
    let any = any_watertight(&bvh, &mesh, &ray);
    assert_eq!(any.map(|(p, _)| p), Some(bvh.indices()[first.start]));
}

#[test]
fn coincident_triangles_build_within_the_depth_limit_and_tie_to_the_smallest_index() {
    let n = 100_000;
    let pos = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let tris = vec![[0u32, 1, 2]; n];
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let s = bvh.stats();
    assert!(s.max_depth <= MAX_DEPTH, "{s:?}");
    assert!(s.max_leaf_size <= DEFAULT_MAX_LEAF_SIZE as usize, "{s:?}");
    let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
    let mut st = TraversalStats::default();
    let (p, h) =
        closest_watertight_in(&bvh, &mesh, &ray, &mut Query::new().stats(&mut st)).unwrap();
    assert_eq!((p, h.t), (0, 1.0));
    assert!(st.primitives_tested >= n as u64);
    assert!(any_watertight(&bvh, &mesh, &ray).is_some());
}

#[test]
fn depth_cap_holds_for_exponentially_spaced_primitives() {
    // Boxes at 2^-k: the SAH peels one primitive per level, so the cap must stop it.
    let boxes: Vec<crate::aabb::Aabb> = (0..200i32)
        .map(|k| {
            let x = 2f32.powi(-k / 2) * if k % 2 == 0 { 1.0 } else { -1.0 };
            let c = Vec3::new(x, 0.0, 0.0);
            crate::aabb::Aabb::new(
                c - Vec3::splat(1e-3 * x.abs()),
                c + Vec3::splat(1e-3 * x.abs()),
            )
        })
        .collect();
    let bvh = build(&boxes[..], &BuildOptions::default()).unwrap();
    let s = bvh.stats();
    assert!(s.max_depth <= MAX_DEPTH, "{s:?}");
    // Every box can still be found.
    for (i, b) in boxes.iter().enumerate() {
        let mut found = false;
        bvh.query_box(&boxes[..], b, |p| {
            found |= p as usize == i;
            true
        });
        assert!(found, "box {i}");
    }
}

#[test]
fn zero_area_and_point_triangles_build_and_miss_cleanly() {
    let pos = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let tris = [[0u32, 1, 2], [0, 0, 0], [1, 1, 1], [0, 1, 3], [3, 3, 3]];
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let ray = Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z);
    let (p, _) = closest_watertight(&bvh, &mesh, &ray).unwrap();
    assert_eq!(p, 3);
    let ray = Ray::new(Vec3::new(0.5, 0.0, -1.0), Vec3::Z);
    assert_eq!(
        closest_watertight(&bvh, &mesh, &ray).map(|x| x.0),
        Some(3),
        "edge point of triangle 3 (closed edges), not the degenerate ones"
    );
}

#[test]
fn invalid_rays_test_no_node() {
    let (pos, tris) = soup(100, 4);
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let bad = [
        Ray::new(Vec3::NAN, Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::new(f32::NAN, 1.0, 0.0)),
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Ray::new(Vec3::splat(f32::INFINITY), Vec3::X),
        Ray::with_interval(Vec3::ZERO, Vec3::X, f32::NAN, 1.0),
        Ray::with_interval(Vec3::ZERO, Vec3::X, 2.0, 1.0),
    ];
    for ray in bad {
        let mut st = TraversalStats::default();
        let hit = bvh.closest_hit(
            &ray,
            &mut |_, _: &Ray| Some((1.0, ())),
            &mut Query::new().stats(&mut st),
        );
        assert!(hit.is_none());
        assert!(
            bvh.any_hit(
                &ray,
                &mut |_, _: &Ray| Some((1.0, ())),
                &mut Query::new().stats(&mut st)
            )
            .is_none()
        );
        assert!(st.nodes_visited <= 1 && st.primitives_tested == 0, "{st:?}");
    }
}

#[test]
fn misbehaving_callbacks_cannot_break_the_interval() {
    let (pos, tris) = soup(50, 5);
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let ray = Ray::with_interval(Vec3::splat(-30.0), Vec3::ONE, 0.0, 100.0);
    for t in [f32::NAN, -1.0, 0.0, 1e30, f32::INFINITY] {
        assert!(
            bvh.closest_hit(&ray, &mut |_, _: &Ray| Some((t, ())), &mut Query::new())
                .is_none()
        );
    }
}

#[test]
fn refit_follows_moved_vertices() {
    let (mut pos, tris) = soup(300, 6);
    let bvh0 = {
        let mesh = TriangleMesh::new(&pos, &tris);
        build(&mesh, &BuildOptions::default()).unwrap()
    };
    let mut bvh = bvh0.clone();
    for p in &mut pos {
        *p = *p * 1.5 + Vec3::new(3.0, -2.0, 0.5);
    }
    let mesh = TriangleMesh::new(&pos, &tris);
    bvh.refit(&mesh).unwrap();
    let fresh = build(&mesh, &BuildOptions::default()).unwrap();
    assert_eq!(bvh.bounds(), fresh.bounds());
    let mut r = Lcg(7);
    for _ in 0..2000 {
        let o = r.v(40.0);
        let ray = Ray::new(o, r.v(10.0) - o);
        let got = closest_watertight(&bvh, &mesh, &ray).map(|(p, h)| (p, h.t));
        assert_eq!(got, brute(&mesh, &ray));
    }
    // Wrong length: refused before writing.
    let short = TriangleMesh::new(&pos, &tris[..10]);
    assert!(matches!(
        bvh.refit(&short),
        Err(BvhError::SourceLengthMismatch { .. })
    ));
    refit_with_non_finite_triangles(&mut bvh, pos, &tris);
}

/// [`Bvh::refit`]'s non-finite contract on `bvh` (built over `pos`, `tris`, an
/// [`lcg_soup`]): the vertices move again and three triangles get a non-finite vertex, in one
/// refit. The error names the smallest of the three indices; the refit still completes
/// (the root box is the moved vertices' box without the three triangles); and closest hits
/// and box queries equal brute force over the moved mesh without them.
///
/// The three are taken from leaves in the refit's order (its reverse pass over the nodes):
/// one from the first leaf, one from the last, and the one with the smallest index of the
/// leaves between, so that the smallest index is neither the first nor the last one the pass
/// meets (naming either instead of the smallest fails).
fn refit_with_non_finite_triangles(bvh: &mut VecBvh, mut pos: Vec<Vec3>, tris: &[[u32; 3]]) {
    let leaves: Vec<&[u32]> = bvh
        .nodes()
        .iter()
        .rev()
        .filter_map(BvhNode::primitive_range)
        .map(|r| &bvh.indices()[r])
        .collect();
    assert!(leaves.len() >= 3, "{} leaves", leaves.len());
    let (first, last) = (leaves[0][0], leaves[leaves.len() - 1][0]);
    let smallest = leaves[1..leaves.len() - 1]
        .iter()
        .flat_map(|l| l.iter().copied())
        .min()
        .unwrap();
    assert!(
        smallest < first && smallest < last,
        "{smallest} {first} {last}"
    );
    for p in &mut pos {
        *p = *p * 0.75 + Vec3::new(-1.0, 4.0, 2.0);
    }
    let bad = [first, smallest, last];
    pos[tris[first as usize][0] as usize].x = f32::NAN;
    pos[tris[smallest as usize][1] as usize].y = f32::INFINITY;
    pos[tris[last as usize][2] as usize].z = f32::NEG_INFINITY;
    let broken = TriangleMesh::new(&pos, tris);
    // The error is checked last: the boxes and queries first show that the refit completed.
    let refitted = bvh.refit(&broken);
    let kept: Vec<u32> = (0..tris.len() as u32)
        .filter(|i| !bad.contains(i))
        .collect();
    let kept_tris: Vec<[u32; 3]> = kept.iter().map(|&i| tris[i as usize]).collect();
    let (lo, hi) = kept_tris
        .iter()
        .flatten()
        .map(|&v| pos[v as usize])
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    let root = bvh.bounds();
    assert_eq!(
        (root.min, root.max),
        (lo, hi),
        "the root box after the refit"
    );
    let others = TriangleMesh::new(&pos, &kept_tris);
    // Rays from random origins at the centre of every triangle, the three included (at their
    // finite vertices' midpoint), and at random points of the mesh's box.
    let mut r = Lcg(12);
    let mut targets: Vec<Vec3> = tris
        .iter()
        .map(|t| t.map(|v| pos[v as usize]))
        .map(|[a, b, c]| {
            if a.is_finite() && b.is_finite() && c.is_finite() {
                (a + b + c) / 3.0
            } else {
                let finite: Vec<Vec3> = [a, b, c].into_iter().filter(|p| p.is_finite()).collect();
                (finite[0] + finite[1]) * 0.5
            }
        })
        .collect();
    targets.extend((0..300).map(|_| lo + (r.v(1.0) + Vec3::splat(0.5)) * (hi - lo)));
    let mut hits = 0;
    for target in targets {
        let o = (lo + hi) * 0.5 + r.v(40.0);
        let ray = Ray::new(o, target - o);
        let got = closest_watertight(&*bvh, &broken, &ray).map(|(p, h)| (p, h.t));
        let want = brute(&others, &ray).map(|(i, t)| (kept[i as usize], t));
        assert_eq!(got, want, "{ray:?}");
        hits += usize::from(want.is_some());
    }
    assert!(hits >= tris.len(), "only {hits} rays hit");
    for k in 0..50 {
        let c = lo + (r.v(1.0) + Vec3::splat(0.5)) * (hi - lo);
        let q = if k == 0 {
            Aabb::new(lo, hi)
        } else {
            Aabb::new(c, c + (r.v(1.0) + Vec3::splat(0.5)) * 3.0)
        };
        let mut got = Vec::new();
        bvh.query_box(&broken, &q, |p| {
            got.push(p);
            true
        });
        got.sort_unstable();
        let want = brute_box(&broken, q.min, q.max);
        assert_eq!(got, want, "box {q:?}");
        if k == 0 {
            assert_eq!(want, kept, "the mesh's box holds every finite triangle");
        }
    }
    assert_eq!(
        refitted,
        Err(BvhError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Primitive,
            index: smallest as usize
        })),
        "names the smallest index of the three"
    );
}

#[test]
fn box_query_finds_exactly_the_overlapping_primitives() {
    let (pos, tris) = soup(400, 8);
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let mut r = Lcg(11);
    for _ in 0..100 {
        let c = r.v(12.0);
        let q = crate::aabb::Aabb::new(c, c + Vec3::new(r.f(), r.f(), r.f()) * 3.0);
        let mut got = Vec::new();
        let n = bvh.query_box(&mesh, &q, |p| {
            got.push(p);
            true
        });
        got.sort_unstable();
        let want = brute_box(&mesh, q.min, q.max);
        assert_eq!(got, want);
        assert_eq!(n, want.len());
    }
    let mut calls = 0;
    let everything = crate::aabb::Aabb::new(Vec3::splat(-100.0), Vec3::splat(100.0));
    assert_eq!(
        bvh.query_box(&mesh, &everything, |_| {
            calls += 1;
            calls < 3
        }),
        3
    );
    assert_eq!(bvh.query_box(&mesh, &crate::aabb::Aabb::EMPTY, |_| true), 0);
}

#[test]
fn clearance_rejects_mismatched_lengths_and_reports_infinity_for_misses() {
    let pos = [
        Vec3::new(-1.0, -1.0, 5.0),
        Vec3::new(3.0, -1.0, 5.0),
        Vec3::new(-1.0, 3.0, 5.0),
    ];
    let tris = [[0u32, 1, 2]];
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let pts = [Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
    let nrm = [Vec3::Z * 2.0, -Vec3::Z, Vec3::ZERO];
    let mut out = [0.0f32; 3];
    let min = bvh
        .clearance(
            &mut Triangles::new(&mesh, &Watertight),
            &pts,
            &nrm,
            &mut out,
        )
        .unwrap();
    assert_eq!(out, [5.0, f32::INFINITY, f32::INFINITY]);
    assert_eq!(min, 5.0);
    let mut short = [0.0f32; 2];
    assert!(matches!(
        bvh.clearance(
            &mut Triangles::new(&mesh, &Watertight),
            &pts,
            &nrm,
            &mut short
        ),
        Err(QueryError::LengthMismatch { .. })
    ));
    let min = bvh
        .clearance(
            &mut |p, r: &Ray| {
                let h = Watertight.intersect(r, &mesh.triangle(p as usize)?)?;
                Some((h.t, ()))
            },
            &pts,
            &nrm,
            &mut out,
        )
        .unwrap();
    assert_eq!(min, 5.0);
}

/// The clearance is a world distance whatever the normal's length: a plane 5 units away along
/// normals from `2⁻⁸⁰` to `2⁸⁰` long (their squares leave `f32`'s range) is 5 units away, to
/// within the ray test's and the product's rounding (a few ulps of 5, `T_ULPS`).
#[test]
fn clearance_is_the_distance_for_normals_of_any_length() {
    /// Rounding allowed on the distance, in ulps of the answer: the intersector's `t`
    /// (watertight, a few roundings) times the normal's exact power-of-two length.
    const T_ULPS: f32 = 8.0;
    let pos = [
        Vec3::new(-1.0, -1.0, 5.0),
        Vec3::new(3.0, -1.0, 5.0),
        Vec3::new(-1.0, 3.0, 5.0),
    ];
    let tris = [[0u32, 1, 2]];
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    for e in [-80, -40, -20, 0, 20, 40, 80] {
        let k = 2f32.powi(e);
        let mut out = [0.0f32; 1];
        let min = bvh
            .clearance(
                &mut Triangles::new(&mesh, &Watertight),
                &[Vec3::ZERO],
                &[Vec3::Z * k],
                &mut out,
            )
            .unwrap();
        assert!(
            (out[0] - 5.0).abs() <= T_ULPS * 5.0 * f32::EPSILON,
            "normal of length 2^{e}: clearance {}",
            out[0]
        );
        assert_eq!(min, out[0]);
    }
}

/// Every node's box and leaf range, in depth-first order (left first).
fn preorder(b: &VecBvh) -> Vec<(Aabb, Option<core::ops::Range<usize>>)> {
    let mut out = Vec::new();
    let mut stack = vec![0u32];
    while let Some(i) = stack.pop() {
        let Some(n) = b.nodes().get(i as usize) else {
            continue;
        };
        out.push((n.bounds(), n.primitive_range()));
        if let Some((l, r)) = n.children() {
            stack.push(r);
            stack.push(l);
        }
    }
    out
}

/// The scratch builder is the same algorithm on precomputed records: it must give the same
/// tree, node for node and index for index, as the plain builder (the oracle here is the plain
/// build, whose agreement with brute force the tests above check), on soups, coincident
/// triangles, a depth-capped chain and with excluded primitives.
#[test]
fn scratch_build_gives_the_same_tree() {
    let mut cases: Vec<(Vec<Vec3>, Vec<[u32; 3]>)> =
        vec![soup(1, 1), soup(2, 2), soup(37, 3), soup(1000, 4)];
    let (pos, _) = soup(1, 5);
    cases.push((pos.clone(), vec![[0, 1, 2]; 50]));
    let chain: Vec<Vec3> = (0..120)
        .flat_map(|i| {
            let x = 1.5f32.powi(i);
            [
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x, 1.0, 0.0),
                Vec3::new(x, 0.0, 1.0),
            ]
        })
        .collect();
    let chain_tris = (0..120u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    cases.push((chain, chain_tris));
    let (mut pos, tris) = soup(300, 6);
    pos[10] = Vec3::NAN;
    pos[400] = Vec3::INFINITY;
    cases.push((pos, tris));
    for (k, (pos, tris)) in cases.iter().enumerate() {
        let mesh = TriangleMesh::new(pos, tris);
        for (max_leaf, leaf_threshold) in [(1, 1), (4, 1), (4, 4), (16, 1)] {
            let opts = BuildOptions {
                max_leaf_size: max_leaf,
                exclude_non_finite: true,
                leaf_threshold,
                ..BuildOptions::default()
            };
            let plain = build(&mesh, &opts).unwrap();
            let n = mesh.len();
            let mut scratch = vec![PrimRef::EMPTY; scratch_capacity(n)];
            let fast = build_scratch(&mesh, &mut scratch, &opts).unwrap();
            // Node placement may differ by one padding slot (the builder aligns sibling pairs
            // to the storage's cache lines): compare the trees as trees.
            assert_eq!(
                preorder(&fast),
                preorder(&plain),
                "case {k} leaf {max_leaf}"
            );
            assert_eq!(fast.indices(), plain.indices(), "case {k} leaf {max_leaf}");
            assert_eq!(fast.source_len(), plain.source_len());
        }
    }
}

/// Builds at the ends of the finite range (coordinates up to `3·10³⁸`, near `f32::MAX`, and
/// down to `10⁻³⁸`, where boxes' extents and the binning scale are subnormal or overflow) and
/// of all-equal centroids give a valid tree: every primitive in exactly one leaf, every box
/// containing its children's boxes and its leaves' triangles (the oracle: the triangles' own
/// vertices), leaves within the size limit.
#[test]
fn huge_tiny_and_coincident_inputs_build_valid_trees() {
    let mut cases = Vec::new();
    for scale in [3.0e37f32, 1.0e-38, 1.0e-44] {
        let (pos, tris) = lcg_soup(400, 9, 10.0, 1.0);
        cases.push((pos.iter().map(|p| *p * scale).collect::<Vec<_>>(), tris));
    }
    let (pos, _) = soup(1, 10);
    cases.push((pos, vec![[0, 1, 2]; 70]));
    for (k, (pos, tris)) in cases.iter().enumerate() {
        let mesh = TriangleMesh::new(pos, tris);
        let opts = BuildOptions {
            exclude_non_finite: true,
            ..BuildOptions::default()
        };
        let mut scratch = vec![PrimRef::EMPTY; scratch_capacity(mesh.len())];
        let bvh = build_scratch(&mesh, &mut scratch, &opts).unwrap();
        let mut seen = vec![0u32; mesh.len()];
        for (node, range) in preorder(&bvh) {
            let Some(range) = range else { continue };
            assert!(range.len() <= DEFAULT_MAX_LEAF_SIZE as usize, "case {k}");
            for &p in &bvh.indices()[range] {
                seen[p as usize] += 1;
                for &v in &tris[p as usize] {
                    assert!(
                        node.contains_point(pos[v as usize]),
                        "case {k}: {p} outside"
                    );
                }
            }
        }
        let usable = (0..mesh.len())
            .filter(|&i| {
                let b = mesh.primitive_bounds(i);
                crate::mesh::is_usable(&b) && b.center().is_finite()
            })
            .count();
        assert_eq!(seen.iter().filter(|&&c| c == 1).count(), usable, "case {k}");
        assert!(seen.iter().all(|&c| c <= 1), "case {k}");
        for n in bvh.nodes() {
            if let Some((l, r)) = n.children() {
                let b = n.bounds();
                for c in [l, r] {
                    let c = bvh.nodes()[c as usize].bounds();
                    assert_eq!(b.union(c), b, "case {k}: child outside its parent");
                }
            }
        }
    }
}

#[test]
fn too_small_scratch_is_refused_before_writing() {
    let (pos, tris) = soup(20, 7);
    let mesh = TriangleMesh::new(&pos, &tris);
    let mut nodes = vec![BvhNode::EMPTY; node_capacity(20)];
    let mut idx = [7u32; 20];
    let mut scratch = vec![PrimRef::EMPTY; 19];
    let r = Bvh::build_with_scratch(
        &mesh,
        &mut nodes[..],
        &mut idx[..],
        &mut scratch,
        &BuildOptions::default(),
    );
    assert_eq!(
        r.err(),
        Some(BvhError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhScratch,
            needed: 20,
            available: 19
        }))
    );
    assert!(nodes.iter().all(|n| *n == BvhNode::EMPTY) && idx.iter().all(|&i| i == 7));
}

#[test]
fn build_in_jobs_gives_the_scratch_build_tree_without_gaps() {
    let mut cases: Vec<(Vec<Vec3>, Vec<[u32; 3]>)> = vec![
        soup(1, 11),
        soup(2, 12),
        soup(37, 13),
        soup(1000, 14),
        soup(3000, 15),
    ];
    let (pos, _) = soup(1, 16);
    cases.push((pos, vec![[0, 1, 2]; 50]));
    let (mut pos, tris) = soup(300, 17);
    pos[10] = Vec3::NAN;
    cases.push((pos, tris));
    let mut parts_built = 0usize;
    for (k, (pos, tris)) in cases.iter().enumerate() {
        let mesh = TriangleMesh::new(pos, tris);
        let n = mesh.len();
        for (max_leaf, leaf_threshold) in [(1, 1), (4, 1), (4, 4)] {
            let opts = BuildOptions {
                max_leaf_size: max_leaf,
                exclude_non_finite: true,
                leaf_threshold,
                ..BuildOptions::default()
            };
            let mut scratch = vec![PrimRef::EMPTY; scratch_capacity(n)];
            let reference = build_scratch(&mesh, &mut scratch, &opts).unwrap();
            for (job_size, slots, order) in [
                (0, 8, 0),
                (2, 8, 0),
                (8, 64, 1),
                (50, 64, 2),
                (50, 3, 0),
                (400, 64, 1),
                (100_000, 64, 0),
            ] {
                let mut jobs = vec![BuildJob::EMPTY; slots];
                let mut seen = 0usize;
                let split = Bvh::build_in_jobs(
                    &mesh,
                    vec![BvhNode::EMPTY; node_capacity(n)],
                    vec![0u32; index_capacity(n)],
                    &mut scratch,
                    &mut jobs,
                    job_size,
                    &opts,
                    |parts| {
                        let parts: Vec<JobPart<'_>> = parts.collect();
                        seen = parts.len();
                        assert!(parts.iter().all(|p| p.primitives() <= job_size.max(1)));
                        match order {
                            // In reverse, as threads may finish.
                            1 => parts.into_iter().rev().for_each(JobPart::build),
                            // Every other one dropped: the build finishes those itself.
                            2 => parts.into_iter().step_by(2).for_each(JobPart::build),
                            _ => parts.into_iter().for_each(JobPart::build),
                        }
                    },
                )
                .unwrap();
                parts_built += seen;
                let what = std::format!("case {k} leaf {max_leaf} jobs {job_size}/{slots}");
                assert_eq!(preorder(&split), preorder(&reference), "{what}");
                assert_eq!(split.indices(), reference.indices(), "{what}");
                // No gaps: every node but the optional cache-line pad slot is in the tree.
                let reachable = preorder(&split).len();
                assert!(
                    split.node_count() == reachable || split.node_count() == reachable + 1,
                    "{what}: {} nodes, {reachable} in the tree",
                    split.node_count()
                );
                let (a, b) = (split.stats(), reference.stats());
                assert_eq!(
                    (a.leaves, a.max_depth, a.max_leaf_size, a.sah_cost),
                    (b.leaves, b.max_depth, b.max_leaf_size, b.sah_cost),
                    "{what}"
                );
                assert!(seen <= slots, "{what}");
            }
        }
    }
    assert!(
        parts_built > 100,
        "the job path must be exercised: {parts_built} parts"
    );
}

#[test]
fn build_in_jobs_refuses_bad_storage_before_running_jobs() {
    let (pos, tris) = soup(40, 18);
    let mesh = TriangleMesh::new(&pos, &tris);
    let mut scratch = vec![PrimRef::EMPTY; 39];
    let mut jobs = vec![BuildJob::EMPTY; 4];
    let mut ran = false;
    let r = Bvh::build_in_jobs(
        &mesh,
        vec![BvhNode::EMPTY; node_capacity(40)],
        vec![0u32; 40],
        &mut scratch,
        &mut jobs,
        8,
        &BuildOptions::default(),
        |_| ran = true,
    );
    assert_eq!(
        r.err(),
        Some(BvhError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhScratch,
            needed: 40,
            available: 39
        }))
    );
    let mut scratch = vec![PrimRef::EMPTY; 40];
    let r = Bvh::build_in_jobs(
        &mesh,
        vec![BvhNode::EMPTY; node_capacity(40) - 1],
        vec![0u32; 40],
        &mut scratch,
        &mut jobs,
        8,
        &BuildOptions::default(),
        |_| ran = true,
    );
    assert!(matches!(
        r,
        Err(BvhError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhNodes,
            ..
        }))
    ));
    assert!(!ran, "no job runs on refused storage");
}

#[test]
fn caller_stacks_of_the_tree_depth_answer_as_the_full_stack_and_shorter_ones_refuse() {
    // A random soup (shallow paths) and 2 000 coincident triangles, where a ray through them
    // keeps both children of every inner node and so needs the whole depth.
    let coincident = (vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0u32, 1, 2]; 2000]);
    let mut refused = 0;
    for (k, (pos, tris)) in [soup(400, 17), coincident].iter().enumerate() {
        let mesh = TriangleMesh::new(pos, tris);
        let bvh = build(&mesh, &BuildOptions::default()).unwrap();
        let depth = bvh.stack_depth();
        // The oracle: the statistics' own walk (depth of the deepest leaf).
        assert_eq!(depth, bvh.stats().max_depth, "case {k}");
        assert!(depth > 3, "case {k}: {depth}");
        let mut r = Lcg(5 + k as u64);
        let mut rays: Vec<Ray> = (0..500)
            .map(|_| {
                let o = r.v(30.0);
                Ray::new(o, r.v(10.0) - o)
            })
            .collect();
        rays.push(Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z));
        for ray in &rays {
            let mut full_stats = TraversalStats::default();
            let full =
                closest_watertight_in(&bvh, &mesh, ray, &mut Query::new().stats(&mut full_stats));
            let any = any_watertight(&bvh, &mesh, ray);
            let mut stack = vec![StackEntry::EMPTY; depth];
            let mut stats = TraversalStats::default();
            let got = closest_watertight_in(
                &bvh,
                &mesh,
                ray,
                &mut Query::new().stack(&mut stack[..]).stats(&mut stats),
            );
            assert_eq!(got, Ok(full), "case {k} {ray:?}");
            assert_eq!(stats, full_stats, "case {k} {ray:?}");
            let got_any = bvh.any_hit(
                ray,
                &mut Triangles::new(&mesh, &Watertight),
                &mut Query::new().stack(&mut stack[..]),
            );
            assert_eq!(got_any, Ok(any), "case {k} {ray:?}");
            // One entry short: the right answer or a refusal, never a wrong answer.
            let mut short = vec![StackEntry::EMPTY; depth - 1];
            match closest_watertight_in(&bvh, &mesh, ray, &mut Query::new().stack(&mut short[..])) {
                Ok(h) => assert_eq!(h, full, "case {k} {ray:?}"),
                Err(e) => {
                    assert_eq!(
                        e,
                        QueryError::StackTooSmall {
                            available: depth - 1
                        }
                    );
                    refused += 1;
                }
            }
        }
    }
    assert!(refused > 0, "no ray needed the whole depth");
}

#[test]
fn build_in_a_caller_workspace_gives_the_same_tree_and_errors() {
    let (pos, tris) = soup(700, 23);
    let mesh = TriangleMesh::new(&pos, &tris);
    let n = mesh.len();
    let mut work = BuildWorkspace::new();
    for leaf in [1, 4] {
        let opts = BuildOptions {
            max_leaf_size: leaf,
            ..BuildOptions::default()
        };
        let plain = build(&mesh, &opts).unwrap();
        // The same workspace, reused: its contents between builds mean nothing.
        for _ in 0..2 {
            let got = Bvh::build_in(
                &mesh,
                vec![BvhNode::EMPTY; node_capacity(n)],
                vec![0u32; index_capacity(n)],
                &mut work,
                &opts,
            )
            .unwrap();
            assert_eq!(preorder(&got), preorder(&plain), "leaf {leaf}");
            assert_eq!(got.indices(), plain.indices(), "leaf {leaf}");
        }
    }
    let small = Bvh::build_in(
        &mesh,
        vec![BvhNode::EMPTY; node_capacity(n) - 1],
        vec![0u32; index_capacity(n)],
        &mut work,
        &BuildOptions::default(),
    );
    assert_eq!(
        small.err(),
        Some(BvhError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::BvhNodes,
            needed: node_capacity(n),
            available: node_capacity(n) - 1
        }))
    );
}

/// The node test's general path (rays with `t_min < 0`, or a direction component whose
/// reciprocal overflows) answers like brute force: random lines through a soup (hits behind
/// the origin count), and rays exactly through each vertex of a triangle that is its own
/// box's extreme corner (a box shrunk by any amount misses them; the closed test hits).
#[test]
fn general_path_rays_equal_brute_force() {
    let (pos, tris) = soup(300, 41);
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let mut r = Lcg(43);
    let mut hits = 0;
    for k in 0..600 {
        let o = r.v(14.0);
        // Aimed at a triangle's centroid, so most rays hit something.
        let [a, b, c] = mesh.triangle(k % tris.len()).unwrap();
        let mut d = (a + b + c) / 3.0 - o;
        if k % 3 == 0 {
            d[k % 2] = 1.0e-40; // 1/d overflows: the division path
        }
        let t_min = if k % 3 == 1 { 0.5 } else { -30.0 };
        let ray = Ray::with_interval(o, d, t_min, f32::INFINITY);
        let got = closest_watertight(&bvh, &mesh, &ray);
        assert_eq!(got.map(|(i, h)| (i, h.t)), brute(&mesh, &ray), "{ray:?}");
        hits += usize::from(got.is_some());
    }
    assert!(hits > 400, "only {hits} of 600 rays hit");

    let tri = [
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(2.0, 1.0, 1.0),
        Vec3::new(1.0, 2.0, 1.0),
    ];
    let mesh = TriangleMesh::new(&tri, &[[0, 1, 2]]);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    for v in tri {
        for t_min in [-5.0, 0.0] {
            let ray = Ray::with_interval(v + Vec3::Z, -Vec3::Z, t_min, f32::INFINITY);
            let got = closest_watertight(&bvh, &mesh, &ray);
            assert_eq!(got.map(|(i, h)| (i, h.t)), Some((0, 1.0)), "{ray:?}");
        }
    }
}

/// The node test's general path is the closed slab test of the box padded outward by the
/// projection pad: rays with `t_min < 0` straight down through each corner of a flat box
/// enter it at `t ≈ 1` (the padding only widens it), and rays a thousandth beside it miss.
#[test]
fn general_node_test_hits_the_corners_and_misses_beside() {
    let node = BvhNode::from_raw([[1.0, 1.0, 1.0], [2.0, 2.0, 1.0]], 0, 1);
    let test = |x: f32, y: f32| {
        let ray = Ray::with_interval(Vec3::new(x, y, 2.0), -Vec3::Z, -5.0, f32::INFINITY);
        let slab = crate::aabb::SlabRay::new(&ray).unwrap();
        let padded = padded_ray::PaddedRay::new(&slab, pad_to_root(&node.bounds(), slab.origin));
        padded.hit_node(true, &node, ray.t_min, ray.t_max)
    };
    for (x, y) in [(1.0, 1.0), (2.0, 1.0), (1.0, 2.0), (2.0, 2.0), (1.5, 1.5)] {
        let t = test(x, y).expect("a corner of the box");
        assert!((t - 1.0).abs() <= 1e-5, "({x}, {y}): {t}");
    }
    for (x, y) in [(0.999, 1.5), (2.001, 1.5), (1.5, 0.999), (1.5, 2.001)] {
        assert_eq!(test(x, y), None, "({x}, {y})");
    }
}

/// Rays with `t_min < 0` take the general node test, which pads a negative far distance
/// outward. A wall of 64 thin triangles about `10³` from the coordinate origin, each with an
/// edge in the wall's face nearest that origin (so in the face of its own box and of every
/// ancestor's) and seen almost edge-on from there (tilted by 0.002–0.02 rad). Rays from near
/// the coordinate origin point away from the wall along lines through points on or a few
/// `u·10³` beside such an edge, and hit it behind the origin. At so shallow an angle the plane
/// crossing whose `t` `Watertight` reports can lie a little beyond that face: within the
/// `γ₁₆` of `pad_to_root` plus the `2γ₃` the outward padding adds, but beyond the pad less the
/// `2γ₃` that the factor for `t_min ≥ 0` ([`crate::aabb::SLAB_FAR_SCALE`]) takes off a
/// negative distance. An interval that starts one ulp before such a hit then keeps the box
/// only with the outward padding (with that factor, 421 of the 9 164 rays miss). Closest and
/// any hit equal brute force, for the whole line and from one ulp before the hit.
#[test]
fn hits_just_beyond_a_box_behind_the_origin_equal_brute_force() {
    let u = f32::EPSILON / 2.0;
    let wall = Vec3::new(-1000.0, -700.0, -500.0);
    // The line of sight to the wall, perpendicular to the edges (along y), and the normal.
    let sight = wall.reject_from(Vec3::Y).normalize();
    let normal = Vec3::Y.cross(sight);
    let mut r = Lcg(1109);
    let (mut pos, mut tris) = (Vec::new(), Vec::new());
    for cell in 0..64u32 {
        // `a`, `b` on the face x = wall.x, the third vertex behind it along the line of sight.
        let a = wall + Vec3::new(0.0, (cell % 8) as f32 * 3.0, (cell / 8) as f32 * 3.0);
        let b = a + Vec3::new(0.0, 0.2 + r.f(), 0.0);
        let tilt = (0.002 + 0.018 * r.f()) * if r.f() < 0.5 { -1.0 } else { 1.0 };
        let depth = 0.2 + r.f();
        let c = a + (sight * tilt.cos() + normal * tilt.sin()) * depth + Vec3::Y * (r.f() - 0.5);
        pos.extend([a, b, c]);
        tris.push([3 * cell, 3 * cell + 1, 3 * cell + 2]);
    }
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let rays = 10_000;
    let (mut behind, mut wrong) = (0, Vec::new());
    for _ in 0..rays {
        let [a, b, c] = mesh.triangle((r.f() * 64.0) as usize % 64).unwrap();
        // Through the edge a–b, or beside it (outward in the triangle's plane) or inside.
        let out = -(c - a).reject_from(b - a).normalize();
        let beside = (-3.0 + 8.0 * r.f()) * u * wall.length();
        let target = a + (b - a) * (0.1 + 0.8 * r.f()) + out * beside;
        let o = r.v(2.0);
        let line = Ray::with_interval(o, o - target, -f32::MAX, f32::INFINITY);
        let Some(own) = Watertight.intersect(&line, &[a, b, c]) else {
            continue;
        };
        assert!(own.t < 0.0, "{line:?}");
        behind += 1;
        let from_hit = Ray::with_interval(o, line.direction, own.t.next_down(), f32::INFINITY);
        for ray in [line, from_hit] {
            let want = brute(&mesh, &ray);
            let got = closest_watertight(&bvh, &mesh, &ray).map(|(i, h)| (i, h.t));
            let any = any_watertight(&bvh, &mesh, &ray).is_some();
            if got != want || any != want.is_some() {
                wrong.push((ray, got, want));
                break;
            }
        }
    }
    assert!(
        behind > rays * 4 / 5,
        "{behind} of {rays} rays hit behind the origin"
    );
    assert!(
        wrong.is_empty(),
        "{} of {behind} rays answer unlike brute force, first {:?}",
        wrong.len(),
        wrong[0]
    );
}

/// The closest hit of `ray` in `bvh` with `isect`, through the query trait.
fn closest<I: TriangleIntersector>(
    bvh: &VecBvh,
    mesh: &TriangleMesh<'_>,
    isect: &I,
    ray: &Ray,
) -> Option<(u32, crate::triangle::TriangleHit)> {
    use crate::query::{Query, RayQuery, Triangles};
    RayQuery::closest_hit(
        bvh,
        ray,
        &mut Triangles::new(mesh, isect),
        &mut Query::new(),
    )
}

/// `isect`'s own hit of triangle `prim` for the whole ray equals `hit` (a genuine hit), and no
/// brute-force hit `want` is farther than it (the weak form: `hit` may only be farther).
fn assert_weak<I: TriangleIntersector>(
    mesh: &TriangleMesh<'_>,
    isect: &I,
    ray: &Ray,
    got: Option<(u32, crate::triangle::TriangleHit)>,
    want: Option<(u32, f32)>,
) {
    if let Some((prim, hit)) = got {
        let own = isect.intersect(ray, &mesh.triangle(prim as usize).unwrap());
        assert_eq!(own, Some(hit), "not a hit of triangle {prim}: {ray:?}");
        let (_, w) = want.expect("brute force finds every hit the tree reports");
        assert!(
            w <= hit.t,
            "nearer than brute force: {} < {w}, {ray:?}",
            hit.t
        );
    }
}

/// `Watertight`'s *Domain of agreement* (vertices' sheared magnitudes `≤ 2⁶⁰`, dominant
/// direction component `≥ 2⁻¹⁰⁰`, no subnormal projection) at both ends, as the fuzz
/// targets `bvh`, `bvh_load`, `grid` and `kdtree` use it: the BVH's closest hit equals the
/// brute-force loop's exactly. Far: 300 triangles scaled by `2⁵⁵` and origins within
/// `8·2⁵⁵`, so every `|p − o|` component is at most `13.5·2⁵⁵ < 2⁵⁹` and, with directions
/// whose dominant component is 1, every sheared magnitude below `2⁶⁰`. Small: the same soup
/// scaled by `2⁻⁵⁰`, directions scaled so that the dominant component is exactly `2⁻¹⁰⁰`
/// (sheared depths below `2⁵⁴`; vertices on a `2⁻⁷³` grid, origins on a `2⁻⁷⁰` one, so no
/// difference is subnormal). Just outside (scaled by `2¹⁰⁰`) only the weak form is promised: the BVH's hit
/// is one `Watertight` reports for that triangle, no nearer than brute force's.
#[test]
fn closest_hit_equals_brute_force_at_both_ends_of_the_watertight_domain() {
    let p = |e: i32| 2f32.powi(e);
    for (scale, dominant, exact) in [
        (p(55), 1.0, true),
        (p(-50), p(-100), true),
        (p(100), 1.0, false),
    ] {
        let (mut pos, tris) = soup(300, 17);
        for v in &mut pos {
            *v *= scale;
        }
        let mesh = TriangleMesh::new(&pos, &tris);
        let bvh = build(&mesh, &BuildOptions::default()).unwrap();
        let mut r = Lcg(5);
        let mut hits = 0;
        for _ in 0..400 {
            let o = r.v(16.0) * scale;
            let dir = r.v(10.0) * scale - o;
            let d = dir / dir.abs().max_element() * dominant;
            if exact {
                assert!(pos.iter().all(|v| (*v - o).abs().max_element() <= p(59)));
            }
            let ray = Ray::new(o, d);
            let got = closest(&bvh, &mesh, &Watertight, &ray);
            let want = brute(&mesh, &ray);
            if exact {
                assert_eq!(got.map(|(i, h)| (i, h.t)), want, "scale {scale:e}: {ray:?}");
            } else {
                assert_weak(&mesh, &Watertight, &ray, got, want);
            }
            hits += usize::from(got.is_some());
        }
        assert!(hits > 40, "scale {scale:e}: {hits} hits");
    }
}

/// `MollerTrumbore`'s weak form in an acceleration structure (its docs): on rays aimed at the
/// shared vertices and edges of a fan (where its inexact edges decide) and at random soup
/// triangles, the BVH's closest hit is one `MollerTrumbore` reports for that triangle and no
/// nearer than the brute-force loop's (a brute-force hit outside its triangle's box can be
/// nearer: the tree never visits it).
#[test]
fn moller_trumbore_in_a_bvh_keeps_the_weak_form() {
    use crate::triangle::MollerTrumbore;
    let brute_mt = |mesh: &TriangleMesh<'_>, ray: &Ray| {
        let mut best: Option<(u32, f32)> = None;
        for i in 0..mesh.len() {
            if let Some(h) = MollerTrumbore::CLASSIC.intersect(ray, &mesh.triangle(i).unwrap())
                && best.is_none_or(|(_, b)| h.t < b)
            {
                best = Some((i as u32, h.t));
            }
        }
        best
    };
    // A fan of 16 slivers around the origin in z = 0, and the random soup.
    let mut pos = vec![Vec3::ZERO];
    let mut tris = Vec::new();
    for k in 0..16u32 {
        let a = k as f32 * core::f32::consts::TAU / 16.0;
        pos.push(Vec3::new(a.cos(), a.sin(), 0.0) * 3.7);
        tris.push([0, k + 1, (k + 1) % 16 + 1]);
    }
    let (soup_pos, soup_tris) = soup(200, 23);
    let base = pos.len() as u32;
    pos.extend(soup_pos);
    tris.extend(soup_tris.iter().map(|t| t.map(|i| i + base)));
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = build(&mesh, &BuildOptions::default()).unwrap();
    let mut r = Lcg(41);
    let mut hits = 0;
    for i in 0..3000 {
        let o = r.v(20.0) + Vec3::new(0.0, 0.0, 9.0);
        // Aimed at a vertex, at the midpoint of a fan edge, or at a random point.
        let target = match i % 3 {
            0 => pos[(r.f() * pos.len() as f32) as usize % pos.len()],
            1 => pos[(r.f() * 16.0) as usize % 16 + 1] * 0.5,
            _ => r.v(10.0),
        };
        let ray = Ray::new(o, target - o);
        let got = closest(&bvh, &mesh, &MollerTrumbore::CLASSIC, &ray);
        assert_weak(
            &mesh,
            &MollerTrumbore::CLASSIC,
            &ray,
            got,
            brute_mt(&mesh, &ray),
        );
        hits += usize::from(got.is_some());
    }
    assert!(hits > 1000, "{hits}");
}

/// A source whose every answer is a new box (it breaks [`PrimitiveSource`]'s contract: the
/// binning and the partition see different bounds, so a partition can leave a half empty).
struct Flicker {
    n: usize,
    state: core::cell::Cell<u64>,
}

impl crate::mesh::PrimitiveSource for Flicker {
    fn primitive_count(&self) -> usize {
        self.n
    }

    fn primitive_bounds(&self, _: usize) -> Aabb {
        let mut s = self.state.get();
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        self.state.set(s);
        let a = Vec3::new(
            (s % 100) as f32,
            (s / 100 % 100) as f32,
            (s / 10_000 % 100) as f32,
        );
        Aabb::new(a, a + Vec3::ONE)
    }
}

/// Walks `b` from the root, checking that every inner node's children lie after it (no
/// cycle), that every leaf holds at least one primitive and that the leaves cover every
/// index slot once; returns the primitives they hold (sorted, checked distinct) and the
/// number of leaves.
fn leaves_of(b: &VecBvh, what: &str) -> (Vec<u32>, usize) {
    let nodes = b.nodes();
    let mut covered = vec![0u32; b.indices().len()];
    let mut leaves = 0usize;
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop().filter(|_| !nodes.is_empty()) {
        let (_, start, count) = nodes[i].to_raw();
        let start = start as usize;
        if count == 0 {
            assert!(
                start > i && start + 1 < nodes.len(),
                "{what}: node {i} → {start}"
            );
            stack.extend([start, start + 1]);
        } else {
            leaves += 1;
            for slot in &mut covered[start..start + count as usize] {
                *slot += 1;
            }
        }
    }
    assert!(covered.iter().all(|&c| c == 1), "{what}: {covered:?}");
    let mut prims = b.indices().to_vec();
    prims.sort_unstable();
    assert!(prims.windows(2).all(|w| w[0] < w[1]), "{what}: {prims:?}");
    (prims, leaves)
}

/// A source whose answers change between calls (`test_util::Fickle`: the audit's, whose
/// primitive 0 turns NaN once each primitive has been asked once, and random ones whose later
/// answers are NaN, infinite, inverted or elsewhere) never gets asked for an index at or
/// beyond its count (it panics), whatever the index storage held before (0 or `u32::MAX`),
/// and gets a well-formed tree holding every primitive once: the count, the root's boxes and
/// the index array come from one pass, whose answers here are the steady ones. Before, a
/// second pass wrote the indices of the primitives it found usable and left the rest of the
/// storage as it was: `u32::MAX` reached the source.
#[test]
fn a_source_that_changes_between_passes_is_never_asked_for_a_bad_index() {
    for exclude_non_finite in [false, true] {
        let options = BuildOptions {
            exclude_non_finite,
            ..BuildOptions::default()
        };
        for fill in [0u32, u32::MAX] {
            let what = format!("audit case, exclude {exclude_non_finite}, fill {fill:#x}");
            let src = crate::test_util::fickle_first(3);
            let b = Bvh::build(
                &src,
                vec![BvhNode::EMPTY; node_capacity(3)],
                vec![fill; index_capacity(3)],
                &options,
            )
            .unwrap();
            assert_eq!(leaves_of(&b, &what).0, [0, 1, 2], "{what}");
        }
        let n = 40usize;
        for seed in 0..100u64 {
            for with_scratch in [false, true] {
                let what = format!("seed {seed}, exclude {exclude_non_finite}, {with_scratch}");
                let src = crate::test_util::fickle_random(n, seed);
                let (nodes, idx) = (
                    vec![BvhNode::EMPTY; node_capacity(n)],
                    vec![u32::MAX; index_capacity(n)],
                );
                let b = if with_scratch {
                    let mut scratch = vec![PrimRef::EMPTY; scratch_capacity(n)];
                    Bvh::build_with_scratch(&src, nodes, idx, &mut scratch, &options)
                } else {
                    Bvh::build(&src, nodes, idx, &options)
                }
                .unwrap();
                let (prims, _) = leaves_of(&b, &what);
                assert!(prims.iter().copied().eq(0..n as u32), "{what}");
            }
        }
    }
}

/// Whatever a source answers, the tree is well formed: walked from the root, every inner
/// node's children lie after it (no cycle), every leaf holds at least one primitive, and the
/// leaves cover every index slot once with a permutation of the primitives. Seed 1 made an
/// empty leaf (read as an inner node pointing back at the root's children) before the
/// partition's empty halves were refused.
#[test]
fn a_source_whose_bounds_change_still_gets_a_well_formed_tree() {
    let n = 40usize;
    for seed in 1..200u64 {
        let src = Flicker {
            n,
            state: core::cell::Cell::new(seed),
        };
        let b = Bvh::build(
            &src,
            vec![BvhNode::EMPTY; node_capacity(n)],
            vec![0u32; index_capacity(n)],
            &BuildOptions::default(),
        )
        .unwrap();
        let (prims, leaves) = leaves_of(&b, &format!("seed {seed}"));
        assert!(prims.iter().copied().eq(0..n as u32), "seed {seed}");
        let stats = b.stats();
        assert_eq!((stats.leaves, stats.primitives), (leaves, n), "seed {seed}");
    }
}

/// Every walk of a binary tree ends, and nothing panics, when the storage's `AsRef` changes
/// after the build (the audit's `asref_hang` reproducer: closest hit and the box query looped
/// for ever on node 0, an inner node whose first child is itself). Two changed node arrays:
/// that self-loop, and shared subtrees whose children all come after their parents (node `i`
/// has children `i + 1`, `i + 2` over 60 levels: a walk that only refused backward children
/// would enter about 10¹² nodes, as the old code did). Each walk enters at most as many
/// nodes as the tree has. Closest and any hit on the query's own stack and on a caller's,
/// the box query, the statistics and the stack depth.
#[test]
fn every_walk_ends_when_the_storage_changes_under_the_tree() {
    use crate::test_util::{Flip, Walks};
    let huge = [[-1.0e3f32; 3], [1.0e3; 3]];
    let (pos, tris) = lcg_soup(100, 5, 4.0, 1.0);
    let n = tris.len();
    let count = build(&TriangleMesh::new(&pos, &tris), &BuildOptions::default())
        .unwrap()
        .node_count();
    assert!(count > 62, "{count} nodes: too few for 60 shared levels");
    let self_loop: Vec<BvhNode> = core::iter::once(BvhNode::from_raw(huge, 0, 0))
        .chain(core::iter::repeat_n(BvhNode::EMPTY, count - 1))
        .collect();
    let shared: Vec<BvhNode> = (0..count as u32)
        .map(|i| match i {
            0..=58 => BvhNode::from_raw(huge, i + 1, 0),
            _ => BvhNode::from_raw(huge, 0, 1),
        })
        .collect();
    for (name, changed) in [("self-loop", self_loop), ("shared subtrees", shared)] {
        let (nodes, flip) = Flip::new(vec![BvhNode::EMPTY; node_capacity(n)], changed);
        let mesh = TriangleMesh::new(&pos, &tris);
        let bvh = Bvh::build(&mesh, nodes, vec![0u32; n], &BuildOptions::default()).unwrap();
        assert_eq!(bvh.node_count(), count);
        flip.store(true, std::sync::atomic::Ordering::Relaxed);
        let ray = Ray::new(Vec3::new(0.0, 0.0, -10.0), Vec3::Z);
        let walks = Walks::new(name, bvh, &pos, &tris, ray);
        walks.end("closest hit", |b, m, r| {
            let _ = closest_watertight(b, m, r);
        });
        walks.end("closest hit on a caller's stack", |b, m, r| {
            let mut stack = [StackEntry::EMPTY; TRAVERSAL_STACK_SIZE];
            let _ = b.closest_hit(
                r,
                &mut Triangles::new(m, &Watertight),
                &mut Query::new().stack(&mut stack[..]),
            );
        });
        walks.end("any hit", |b, m, r| {
            let _ = any_watertight(b, m, r);
        });
        walks.end("box query", |b, m, _| {
            let _ = b.query_box(m, &Aabb::new(Vec3::splat(-1.0), Vec3::ONE), |_| true);
        });
        walks.end("statistics", |b, _, _| {
            let _ = b.stats();
        });
        walks.end("stack depth", |b, _, _| {
            assert!(b.stack_depth() <= TRAVERSAL_STACK_SIZE);
        });
    }
}
