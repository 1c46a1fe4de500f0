//! Batches against per-ray [`RayQuery`] calls (bit for bit) and against a brute-force loop
//! over all triangles ([`brute_watertight`], which shares no code with any walk), on several
//! structures, random and camera-like rays, several chunks and a partial one.

use super::*;
use crate::bvh::BuildOptions;
use crate::bvh::wide::binary_options;
use crate::grid::GridOptions;
use crate::kdtree::KdBuildOptions;
use crate::mesh::TriangleMesh;
use crate::query::{
    QUERY_STACK_SIZE, Query, QueryStack, RayQuery, StackEntry, TraversalStats, Triangles,
};
use crate::test_util::{Lcg, brute_watertight, lcg_soup, vec_bvh, vec_grid, vec_kd, vec_wide};
use crate::triangle::{TriangleHit, TriangleIntersector, Watertight};
use std::vec;
use std::vec::Vec;

/// Rays in random order through the mesh's box (origins spread around it), then a camera's
/// rays in scanline order (one origin, a 40×30 image), then shadow rays from a grid of
/// points in the box towards one light (the rays of an any-hit packet), with invalid rays
/// scattered among them.
fn rays(seed: u64) -> Vec<Ray> {
    let mut rng = Lcg(seed);
    let mut out: Vec<Ray> = (0..600)
        .map(|_| {
            let o = rng.v(30.0);
            Ray::new(o, rng.v(6.0) - o)
        })
        .collect();
    let eye = Vec3::new(0.5, 1.0, -14.0);
    for y in 0..30 {
        for x in 0..40 {
            let d = Vec3::new(x as f32 / 40.0 - 0.5, y as f32 / 30.0 - 0.5, 1.0) * 12.0;
            out.push(Ray::new(eye, d));
        }
    }
    let light = Vec3::new(3.0, 20.0, -6.0);
    for y in 0..20 {
        for x in 0..30 {
            let p = Vec3::new(
                x as f32 * 0.03 - 2.0,
                -4.0 + 0.01 * y as f32,
                y as f32 * 0.03,
            );
            out.push(Ray::with_interval(p, light - p, 0.0, 1.0));
        }
    }
    for k in (0..out.len()).step_by(97) {
        out[k] = match k % 3 {
            0 => Ray::new(Vec3::ZERO, Vec3::ZERO),
            1 => Ray::new(Vec3::splat(f32::NAN), Vec3::X),
            _ => Ray::new(Vec3::INFINITY, -Vec3::X),
        };
    }
    out
}

/// The bits of an answer: equal bits, not only equal values.
fn bits(a: Option<(u32, TriangleHit)>) -> Option<(u32, [u32; 3])> {
    a.map(|(p, h)| (p, [h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()]))
}

/// Batches of `q` against its single-ray queries and the brute-force loop; with
/// `walked_alone` (the structures without a packet walk), their statistics too.
fn batch_equals_single<Q: RayQuery>(
    name: &str,
    q: &Q,
    mesh: &TriangleMesh<'_>,
    rays: &[Ray],
    walked_alone: bool,
) {
    let mut tris = Triangles::new(mesh, &Watertight);
    let mut stack = QueryStack::new();
    let (mut batch_stats, mut single_stats) =
        (TraversalStats::default(), TraversalStats::default());
    let mut closest = vec![None; rays.len()];
    let mut ctx = Query::new().stack(&mut stack).stats(&mut batch_stats);
    q.closest_hits(rays, &mut tris, &mut ctx, &mut closest)
        .unwrap();
    let mut any = vec![None; rays.len()];
    let (mut any_stats, mut single_any_stats) =
        (TraversalStats::default(), TraversalStats::default());
    q.any_hits(
        rays,
        &mut tris,
        &mut Query::new().stats(&mut any_stats),
        &mut any,
    )
    .unwrap();

    let mut hits = 0;
    for (i, ray) in rays.iter().enumerate() {
        let single = q.closest_hit(ray, &mut tris, &mut Query::new().stats(&mut single_stats));
        assert_eq!(bits(closest[i]), bits(single), "{name}: closest, ray {i}");
        let brute = brute_watertight(mesh, ray);
        assert_eq!(closest[i], brute, "{name}: brute force, ray {i} {ray:?}");
        let single_any = q.any_hit(
            ray,
            &mut tris,
            &mut Query::new().stats(&mut single_any_stats),
        );
        if walked_alone {
            assert_eq!(bits(any[i]), bits(single_any), "{name}: any, ray {i}");
        }
        // A batch's any hit is a hit of the ray: that triangle alone reports it, bit for bit.
        if let Some((p, h)) = any[i] {
            let alone = mesh
                .triangle(p as usize)
                .and_then(|v| Watertight.intersect(ray, &v));
            assert_eq!(
                bits(Some((p, h))),
                bits(alone.map(|a| (p, a))),
                "{name}: any, ray {i}"
            );
        }
        assert_eq!(
            any[i].is_some(),
            brute.is_some(),
            "{name}: any hit/miss, ray {i}"
        );
        hits += usize::from(brute.is_some());
    }
    // Every ray walked exactly once: the counters sum to the single rays'.
    if walked_alone {
        assert_eq!(batch_stats, single_stats, "{name}: statistics");
        assert_eq!(any_stats, single_any_stats, "{name}: any-hit statistics");
    } else {
        // Packets count their node tests once: fewer than the single rays'.
        assert!(batch_stats.nodes_visited > 0, "{name}: statistics added to");
        assert!(
            any_stats.nodes_visited < single_any_stats.nodes_visited,
            "{name}: any-hit packets {any_stats:?} against single rays {single_any_stats:?}"
        );
    }
    assert!(hits > rays.len() / 5, "{name}: only {hits} hits");
}

#[test]
fn batches_equal_single_rays_on_every_structure() {
    let (pos, tri) = lcg_soup(400, 9, 10.0, 1.5);
    let mesh = TriangleMesh::new(&pos, &tri);
    let rays = rays(4);
    assert!(rays.len() > 4 * BATCH_CHUNK && !rays.len().is_multiple_of(BATCH_CHUNK));

    let bvh = vec_bvh(&mesh, &BuildOptions::default()).unwrap();
    batch_equals_single("bvh", &bvh, &mesh, &rays, true);

    let binary = vec_bvh(&mesh, &binary_options(BuildOptions::default())).unwrap();
    let bvh8 = vec_wide::<8>(&binary, &mesh).unwrap();
    batch_equals_single("bvh8", &bvh8, &mesh, &rays, false);
    let bvh4 = vec_wide::<4>(&binary, &mesh).unwrap();
    batch_equals_single("bvh4", &bvh4, &mesh, &rays, false);

    let grid = vec_grid(&mesh, &GridOptions::default()).unwrap();
    batch_equals_single("grid", &grid, &mesh, &rays, true);

    let kd = vec_kd(&mesh, &KdBuildOptions::default()).unwrap();
    batch_equals_single("kd-tree", &kd, &mesh, &rays, true);
}

#[test]
fn empty_batches_and_length_mismatches() {
    let (pos, tri) = lcg_soup(20, 1, 4.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tri);
    let bvh = vec_bvh(&mesh, &BuildOptions::default()).unwrap();
    let mut tris = Triangles::new(&mesh, &Watertight);
    let mut stats = TraversalStats::default();
    let mut none: [Option<(u32, TriangleHit)>; 0] = [];
    let empty = bvh.closest_hits(
        &[],
        &mut tris,
        &mut Query::new().stats(&mut stats),
        &mut none,
    );
    assert_eq!(empty, Ok(()));
    assert_eq!(
        stats,
        TraversalStats::default(),
        "an empty batch walks nothing"
    );

    let rays = rays(2);
    let hit = rays
        .iter()
        .find_map(|r| brute_watertight(&mesh, r))
        .unwrap();
    for len in [0, rays.len() - 1, rays.len() + 1] {
        let mut out = vec![Some(hit); len];
        let want = Err(QueryError::LengthMismatch {
            expected: rays.len(),
            found: len,
        });
        let mut ctx = Query::new().stats(&mut stats);
        assert_eq!(bvh.closest_hits(&rays, &mut tris, &mut ctx, &mut out), want);
        assert_eq!(bvh.any_hits(&rays, &mut tris, &mut ctx, &mut out), want);
        assert!(out.iter().all(|o| *o == Some(hit)), "nothing written");
    }
    assert_eq!(stats, TraversalStats::default(), "no ray walked");
}

#[test]
fn a_caller_stack_too_small_is_each_rays_answer() {
    let (pos, tri) = lcg_soup(200, 3, 6.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tri);
    let single = BuildOptions {
        max_leaf_size: 1,
        ..BuildOptions::default()
    };
    let bvh = vec_bvh(&mesh, &single).unwrap();
    let mut tris = Triangles::new(&mesh, &Watertight);
    let rays = rays(6);
    for len in [bvh.stack_depth() / 2, QUERY_STACK_SIZE] {
        let mut short = vec![StackEntry::EMPTY; len];
        let mut out = vec![Ok(None); rays.len()];
        let mut ctx = Query::new().stack(&mut short[..]);
        bvh.closest_hits(&rays, &mut tris, &mut ctx, &mut out)
            .unwrap();
        for (i, ray) in rays.iter().enumerate() {
            let mut again = vec![StackEntry::EMPTY; len];
            let mut ctx = Query::new().stack(&mut again[..]);
            let one = RayQuery::closest_hit(&bvh, ray, &mut tris, &mut ctx);
            assert_eq!(out[i], one, "ray {i}, stack of {len}");
        }
        let refused = out.iter().filter(|o| o.is_err()).count();
        assert_eq!(refused > 0, len < QUERY_STACK_SIZE, "stack of {len}");
    }
}

#[test]
fn a_chunk_is_walked_in_a_permutation_grouped_by_octant() {
    let rays = rays(8);
    let mut keys = [0u64; BATCH_CHUNK];
    for chunk in rays.chunks(BATCH_CHUNK) {
        let order = chunk_order(chunk, &mut keys);
        let mut seen: Vec<u64> = order.iter().map(|k| k & 0xFFFF_FFFF).collect();
        seen.sort_unstable();
        assert_eq!(
            seen,
            (0..chunk.len() as u64).collect::<Vec<_>>(),
            "a permutation"
        );
        let octants: Vec<u64> = order.iter().map(|k| k >> 56).collect();
        assert!(octants.is_sorted(), "octants first");
        for &k in order {
            let d = chunk[(k & 0xFFFF_FFFF) as usize].direction;
            let want = u64::from(d.x < 0.0) | u64::from(d.y < 0.0) << 1 | u64::from(d.z < 0.0) << 2;
            assert_eq!(k >> 56, want, "octant of {d:?}");
        }
    }
}

#[test]
fn morton_codes_interleave_x_lowest() {
    assert_eq!(morton3([1, 0, 0]), 0b001);
    assert_eq!(morton3([0, 1, 0]), 0b010);
    assert_eq!(morton3([0, 0, 1]), 0b100);
    assert_eq!(morton3([2, 0, 0]), 0b001_000);
    assert_eq!(morton3([15, 15, 15]), 0xFFF);
    assert_eq!(morton3([8, 0, 1]), 1 << 9 | 1 << 2);
    assert_eq!(cells(Vec3::new(f32::NAN, f32::INFINITY, -3.0)), [0, 15, 0]);
}

/// The sort keys of a chunk, worked by hand from the documented form
/// `(octant << 24 | origin cell << 12 | direction cell) << 32 | index`: origins scaled to 16
/// cells per axis over the chunk's origin bounds (here `[0, 1]³`, the top clamped to cell 15),
/// directions divided by their largest component, shifted to `[0, 2]` and scaled by 8, each
/// cell triple interleaved x lowest.
#[test]
fn a_chunk_s_keys_are_the_documented_cells() {
    let rays = [
        // Origin cells (8, 4, 15): 2⁹ + 2⁷ + 2² + 2⁵ + 2⁸ + 2¹¹ = 2980. Direction
        // (2, 1.5, 0.75)·8 → cells (15, 12, 6): 2⁰ + 2³ + 2⁶ + 2⁹ + 2⁷ + 2¹⁰ + 2⁵ + 2⁸ = 2025.
        // Octant: z < 0, 4.
        Ray::new(Vec3::new(0.5, 0.25, 1.0), Vec3::new(1.0, 0.5, -0.25)),
        // Origin cells (0, 0, 0): 0. Direction (1, 1, 2)·8 → (8, 8, 15):
        // 2⁹ + 2¹⁰ + 2² + 2⁵ + 2⁸ + 2¹¹ = 3876. Octant 0.
        Ray::new(Vec3::ZERO, Vec3::Z),
        // Origin cells (15, 15, 15): 4095. Direction (0, 1.5, 1)·8 → (0, 12, 8):
        // 2⁷ + 2¹⁰ + 2¹¹ = 3200. Octant: x < 0, 1.
        Ray::new(Vec3::ONE, Vec3::new(-2.0, 1.0, 0.0)),
    ];
    let key = |octant: u64, origin: u64, direction: u64, index: u64| {
        (octant << 24 | origin << 12 | direction) << 32 | index
    };
    let mut keys = [0u64; BATCH_CHUNK];
    assert_eq!(
        chunk_order(&rays, &mut keys),
        [
            key(0, 0, 3876, 1),
            key(1, 4095, 3200, 2),
            key(4, 2980, 2025, 0)
        ]
    );
}
