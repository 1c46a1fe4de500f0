//! The packet walk against the single-ray walk (bit for bit, at every SIMD level the CPU has)
//! and against a brute-force loop over all triangles, and the packet node test against every
//! ray's own node test.

use super::*;
use crate::aabb::{Aabb, SlabRay};
use crate::bvh::padded_ray::PaddedRay;
use crate::bvh::wide::{Bvh4, Bvh8, binary_options, group_capacity};
use crate::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, node_capacity};
use crate::hit::spawn_ray_to;
use crate::mesh::TriangleMesh;
use crate::query::{Query, QueryStack, RayQuery, TraversalStats, Triangles};
use crate::simd::level::Portable;
use crate::test_util::{Lcg, brute_watertight, lcg_soup};
use crate::triangle::{TriangleHit, TriangleIntersector, Watertight};
use glam::Vec3;
use std::vec;
use std::vec::Vec;

type Answer = Option<(u32, TriangleHit)>;

/// The bits of an answer: equal bits, not only equal values.
fn bits(a: Answer) -> Option<(u32, [u32; 3])> {
    a.map(|(p, h)| (p, [h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()]))
}

/// A pinhole camera's rays (`w × h`, one origin, a field of `fov` radians across) in
/// scanline order, then in 4×4 tiles, then an orthographic camera's (parallel rays, one
/// origin per pixel, `t_max` finite), then the pinhole's again with every 5th ray replaced by
/// an odd one: another octant, an invalid ray, a zero direction component, `t_min < 0`, a
/// short `t_max`, a tiny direction.
fn camera_rays(eye: Vec3, (w, h): (usize, usize), fov: f32) -> Vec<Ray> {
    let pixel = |x: usize, y: usize| {
        let s = |i: usize, n: usize| (i as f32 / n as f32 - 0.5) * fov * n as f32 / w as f32;
        Ray::new(eye, Vec3::new(s(x, w), s(y, h), 1.0) * 12.0)
    };
    let mut out: Vec<Ray> = (0..w * h).map(|k| pixel(k % w, k / w)).collect();
    for ty in 0..h / 4 {
        for tx in 0..w / 4 {
            for k in 0..16 {
                out.push(pixel(tx * 4 + k % 4, ty * 4 + k / 4));
            }
        }
    }
    for k in 0..w * h {
        let o = Vec3::new(
            (k % w) as f32 * 0.25 - 5.0,
            (k / w) as f32 * 0.25 - 4.0,
            -20.0,
        );
        let mut r = Ray::new(o, Vec3::new(0.01, -0.02, 1.0));
        r.t_max = 24.0;
        out.push(r);
    }
    let mut odd: Vec<Ray> = (0..w * h).map(|k| pixel(k % w, k / w)).collect();
    for (k, r) in odd.iter_mut().enumerate().skip(3).step_by(5) {
        *r = match k % 6 {
            0 => Ray::new(r.origin, -r.direction),
            1 => Ray::new(Vec3::splat(f32::NAN), Vec3::X),
            2 => Ray::new(r.origin, Vec3::new(0.0, r.direction.y, r.direction.z)),
            3 => Ray { t_min: -2.0, ..*r },
            4 => Ray { t_max: 10.0, ..*r },
            _ => Ray::new(r.origin, r.direction * 1e-3),
        };
    }
    out.extend(odd);
    out
}

/// The batch of `q` at `level` against its single-ray queries at that level and the
/// brute-force loop; returns the hits.
fn batch_equals_single<L: SimdLevel, Q: RayQuery>(
    level: L,
    name: &str,
    q: &Q,
    mesh: &TriangleMesh<'_>,
    rays: &[Ray],
) -> usize {
    let mut tris = Triangles::new(mesh, &Watertight);
    let mut stack = QueryStack::new();
    let mut batch: Vec<Answer> = vec![None; rays.len()];
    let (mut packed, mut alone) = (TraversalStats::default(), TraversalStats::default());
    let mut ctx = Query::new().on(level).stack(&mut stack).stats(&mut packed);
    q.closest_hits(rays, &mut tris, &mut ctx, &mut batch)
        .unwrap();
    let mut hits = 0;
    for (i, ray) in rays.iter().enumerate() {
        let single = q.closest_hit(
            ray,
            &mut tris,
            &mut Query::new().on(level).stats(&mut alone),
        );
        assert_eq!(bits(batch[i]), bits(single), "{name}: ray {i} {ray:?}");
        assert_eq!(
            batch[i],
            brute_watertight(mesh, ray),
            "{name}: brute, ray {i}"
        );
        hits += usize::from(single.is_some());
    }
    // The packets ran: they test nodes once for many rays.
    assert!(
        packed.nodes_visited < alone.nodes_visited,
        "{name}: {packed:?} in packets, {alone:?} alone"
    );
    hits
}

type VecWide<const W: usize> = WideBvh<W, Vec<WideNode<W>>, Vec<LeafGroup>>;

fn wide<const W: usize>(mesh: &TriangleMesh<'_>, leaf: u32) -> VecWide<W> {
    let n = mesh.len();
    let options = BuildOptions {
        max_leaf_size: leaf,
        ..binary_options(BuildOptions::default())
    };
    let binary = Bvh::build(
        mesh,
        vec![BvhNode::EMPTY; node_capacity(n)],
        vec![0u32; index_capacity(n)],
        &options,
    )
    .unwrap();
    let nodes = vec![WideNode::EMPTY; crate::bvh::wide::node_capacity(n)];
    WideBvh::from_binary(
        &binary,
        mesh,
        nodes,
        vec![LeafGroup::EMPTY; group_capacity(n)],
    )
    .unwrap()
}

#[test]
fn packets_equal_single_rays_at_every_level() {
    let (pos, tri) = lcg_soup(1500, 21, 4.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tri);
    // 0.14° between neighbouring pixels: a 16-pixel row stays within the packet's cone.
    let rays = camera_rays(Vec3::new(0.5, 0.2, -8.0), (160, 40), 0.4);
    for leaf in [1, 4] {
        let bvh8: Bvh8<_, _> = wide::<8>(&mesh, leaf);
        let bvh4: Bvh4<_, _> = wide::<4>(&mesh, leaf);
        let hits = batch_equals_single(Portable, "bvh8", &bvh8, &mesh, &rays);
        assert!(hits > rays.len() / 4, "only {hits} hits");
        batch_equals_single(Portable, "bvh4", &bvh4, &mesh, &rays);
        #[cfg(target_arch = "x86_64")]
        if let Some(level) = crate::test_util::avx2_or_skip(
            "bvh::wide::packet::tests::packets_equal_single_rays_at_every_level",
        ) {
            batch_equals_single(level, "bvh8 avx2", &bvh8, &mesh, &rays);
            batch_equals_single(level, "bvh4 avx2", &bvh4, &mesh, &rays);
        }
    }
}

/// Coplanar, touching triangles (a grid of squares split in two, with a duplicate of every
/// tenth triangle): rays through shared edges and vertices and equal `t` for several
/// triangles, where the tie rule decides.
#[test]
fn packets_keep_the_tie_rule_on_shared_edges() {
    let mut pos = Vec::new();
    let mut tri = Vec::new();
    let n = 24u32;
    for y in 0..=n {
        for x in 0..=n {
            pos.push(Vec3::new(x as f32 - 12.0, y as f32 - 12.0, 3.0));
        }
    }
    for y in 0..n {
        for x in 0..n {
            let v = y * (n + 1) + x;
            tri.push([v, v + 1, v + n + 2]);
            tri.push([v, v + n + 2, v + n + 1]);
            if (x + y) % 10 == 0 {
                tri.push([v + n + 2, v, v + 1]);
            }
        }
    }
    let mesh = TriangleMesh::new(&pos, &tri);
    // The eye straight over a vertex, 200 units away; pixels half a grid unit apart at the
    // plane (0.14° between neighbours): every ray through a vertex or an edge.
    let eye = Vec3::new(0.0, 0.0, -197.0);
    let rays: Vec<Ray> = (0..32 * 32)
        .map(|k| {
            let p = Vec3::new(
                (k % 32) as f32 * 0.5 - 8.0,
                (k / 32) as f32 * 0.5 - 8.0,
                3.0,
            );
            Ray::new(eye, p - eye)
        })
        .collect();
    let bvh8 = wide::<8>(&mesh, 4);
    let hits = batch_equals_single(Portable, "grid", &bvh8, &mesh, &rays);
    assert_eq!(hits, rays.len(), "a closed grid under every ray");
}

/// The packet node test admits every child any ray of the packet enters, with an entry
/// bound at most that ray's own entry distance: random packets (shared and spread origins,
/// every octant) against random boxes, each ray's own node test
/// ([`PaddedRay::hit_children`]) the oracle.
#[test]
fn the_packet_node_test_bounds_every_rays_own() {
    const EXTENT: f32 = 30.0;
    // A tree centred away from the coordinate origin: the lanes hold origins in its frame.
    let centre = Vec3::new(1000.0, -20.0, 5.0);
    let frame = crate::query::walk::PadFrame::relative(&Aabb::new(
        centre - Vec3::splat(EXTENT),
        centre + Vec3::splat(EXTENT),
    ));
    let mut rng = Lcg(77);
    let mut admitted = 0;
    for round in 0..3000 {
        let octant = Vec3::new(
            if round & 1 == 0 { 1.0 } else { -1.0 },
            if round & 2 == 0 { 1.0 } else { -1.0 },
            if round & 4 == 0 { 1.0 } else { -1.0 },
        );
        let base = (rng.v(2.0).abs() + Vec3::splat(0.05)) * octant;
        let eye = centre + rng.v(20.0);
        let spread = [0.0, 0.01, 0.2][round % 3];
        let mut rays = Vec::new();
        for i in 0..PACKET {
            let d = (base + rng.v(spread)).abs().max(Vec3::splat(1e-3)) * octant;
            let o = if round % 5 == 0 {
                eye + rng.v(1.0)
            } else {
                eye
            };
            let mut ray = Ray::new(o, d);
            ray.t_min = [0.0, rng.f()][i % 2];
            ray.t_max = [f32::INFINITY, 5.0 + 40.0 * rng.f()][(i / 2) % 2];
            let slab = SlabRay::new(&ray).unwrap();
            let (origin, pad) = frame.local(o);
            let w = PaddedRay::new(&SlabRay { origin, ..slab }, pad);
            rays.push((ray, w));
        }
        let near = [octant.x, octant.y, octant.z].map(|s| usize::from(s < 0.0));
        let mut lanes = Lanes::ZERO;
        let only: Vec<Ray> = rays.iter().map(|(r, _)| *r).collect();
        // Likeness that admits every ray of the octant.
        let any = Coherence {
            cone: 0.0,
            reach: f32::INFINITY,
            ..Coherence::new(&only[0], EXTENT)
        };
        let joined = lanes.gather(&only, &frame, near, &any);
        assert_eq!(lane_bits(&joined), 0xFFFF, "round {round}: every ray joins");
        for (i, (_, w)) in rays.iter().enumerate() {
            // Each lane holds its ray's own padded values, bit for bit.
            for axis in 0..3 {
                let lane = [
                    lanes.origin_near[axis][i],
                    lanes.origin_far[axis][i],
                    lanes.inv[axis][i],
                ];
                let own = [w.origin_near[axis], w.origin_far[axis], w.inv_dir[axis]];
                assert_eq!(
                    lane.map(f32::to_bits),
                    own.map(f32::to_bits),
                    "round {round}"
                );
            }
        }
        let interval = Interval::new(&lanes, &joined, near);
        let mut node = WideNode::<8>::EMPTY;
        for slot in 0..7 {
            // Along the packet (most entered by some rays), or anywhere near it; in the
            // frame's coordinates, as a tree stores its boxes.
            let c =
                (eye - centre) + base * (rng.f() * 20.0) + rng.v(if slot < 5 { 3.0 } else { 40.0 });
            let h = rng.v(3.0).abs();
            node.set_child(slot, &Aabb::new(c - h, c + h), slot as u32);
        }
        let (dist, mask) = interval.hit_children(&node, lanes.max_bound());
        for (i, (ray, w)) in rays.iter().enumerate() {
            let (own, own_mask) =
                w.hit_children::<8, false, _>(Portable, &node, ray.t_min, lanes.bound[i]);
            assert_eq!(own_mask & !mask, 0, "round {round}, ray {i}: a child lost");
            for slot in 0..8 {
                if own_mask >> slot & 1 == 1 {
                    assert!(
                        dist[slot] <= own[slot],
                        "round {round}, ray {i}, slot {slot}"
                    );
                    admitted += 1;
                }
            }
            // The leaf test of one slot is the ray's own node test.
            for slot in 0..8 {
                let rays_in = lanes.entering(&node, slot, near);
                assert_eq!(
                    rays_in >> i & 1,
                    own_mask >> slot & 1,
                    "round {round} ray {i}"
                );
            }
        }
    }
    assert!(admitted > 5000, "{admitted} children entered");
}

/// The batch's packet policy: a packet that shares its leaves keeps packets on; one that
/// does not sends the next 1, then 2, 4, … up to `MAX_WAIT` chunks to single rays; the sum is
/// bounded, so a long stretch of sharing packets is undone by a few that do not.
#[test]
fn sharing_waits_longer_while_packets_do_not_share() {
    let mut s = Sharing::NEW;
    assert!(s.try_packet());
    s.record(5);
    assert!(s.try_packet() && s.try_packet());
    // Below zero: one chunk alone, then a packet again.
    s.record(-6);
    assert!(!s.try_packet());
    assert!(s.try_packet());
    let mut waits = Vec::new();
    for _ in 0..9 {
        s.record(-3);
        let mut n = 0;
        while !s.try_packet() {
            n += 1;
        }
        waits.push(n);
    }
    assert_eq!(waits, [2, 4, 8, 16, 32, 64, 64, 64, 64]);
    // The sum is clamped at -SHARE_WINDOW: sharing packets worth SHARE_WINDOW bring it back.
    s.record(SHARE_WINDOW);
    assert!(s.try_packet() && s.try_packet());
    s.record(SHARE_WINDOW * 10);
    s.record(-SHARE_WINDOW - 1);
    assert!(!s.try_packet());
    assert!(s.try_packet(), "the wait starts again at one chunk");
}

/// A packet's share ([`WideBvh::packet_hits`]'s second value): a packet that reaches at
/// most one leaf for two rays counts +1 whatever its rays enter (here: none, the rays pass
/// beside the mesh after the root's node test, as rays between the small objects of a
/// scattered scene do), so that it brings a share left below zero back up; one that reaches
/// many leaves counts the rays that entered them less their number; a chunk not walked as a
/// packet (its probe ray unlike the first) counts 0. And a share of `-k` is back at zero
/// after `k` packets of few leaves.
#[test]
fn a_packet_of_few_leaves_counts_as_paid() {
    let (pos, tri) = lcg_soup(1500, 21, 4.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tri);
    let bvh8: Bvh8<_, _> = wide::<8>(&mesh, 4);
    let mut tris = Triangles::new(&mesh, &Watertight);
    let mut stack = PacketStack::new();
    let mut share = |rays: &[Ray]| {
        let mut stats = TraversalStats::default();
        let (alone, surplus) = bvh8.packet_hits::<_, _, false>(
            Portable,
            rays,
            &mut tris,
            (&mut stack, Some(&mut stats)),
            |_, _| {},
        );
        (alone, surplus, stats)
    };
    // No zero direction component: packets take the node test's common path only.
    let d = Vec3::new(0.01, 0.02, 1.0);
    let grid = |x: f32, y: f32| -> Vec<Ray> {
        (0..16)
            .map(|k| {
                let o = Vec3::new(x + (k % 4) as f32 * 1e-3, y + (k / 4) as f32 * 1e-3, -10.0);
                Ray::new(o, d)
            })
            .collect()
    };
    // Beside the soup (it lies within about 5 of the origin): the root's test, no leaf.
    let (alone, surplus, stats) = share(&grid(20.0, 0.0));
    assert_eq!((alone, surplus), (0, 1), "{stats:?}");
    assert!(
        stats.nodes_visited >= 1 && stats.primitives_tested == 0,
        "{stats:?}"
    );
    // Through the soup: many leaves, each entered by several rays.
    let into = grid(0.1, 0.2);
    let (alone, surplus, stats) = share(&into);
    assert_eq!(alone, 0);
    assert!(
        surplus > 1 && stats.primitives_tested > 0,
        "{surplus} {stats:?}"
    );
    // The probe ray (the 12th) unlike the first: no packet, every ray alone.
    let mut unlike = into.clone();
    unlike[11] = Ray::new(Vec3::new(0.1, 0.2, 10.0), -d);
    let (alone, surplus, stats) = share(&unlike);
    assert_eq!(
        (alone, surplus, stats.nodes_visited),
        (u32::MAX >> 16, 0, 0)
    );
    // Back from below zero: a share of -5 needs five packets of few leaves.
    let mut s = Sharing::NEW;
    s.record(-5);
    for _ in 0..5 {
        while !s.try_packet() {}
        s.record(1);
    }
    assert!(
        s.try_packet() && s.try_packet(),
        "the share is back at zero"
    );
}

/// The triangle `p` of `mesh`.
fn vertices(mesh: &TriangleMesh<'_>, p: u32) -> [Vec3; 3] {
    mesh.triangle(p as usize).unwrap()
}

/// The any-hit batch of `q` at `level` on `rays`: each answer a hit exactly when the
/// brute-force loop and the single-ray any hit find one, and a hit of its ray (that triangle alone reports it, bit for
/// bit); walked in packets (fewer than half the single rays' node tests). Returns the hits.
fn any_batch_hits_as_brute_force<L: SimdLevel, Q: RayQuery>(
    level: L,
    name: &str,
    q: &Q,
    mesh: &TriangleMesh<'_>,
    rays: &[Ray],
) -> usize {
    let mut tris = Triangles::new(mesh, &Watertight);
    let mut batch: Vec<Answer> = vec![None; rays.len()];
    let (mut packed, mut alone) = (TraversalStats::default(), TraversalStats::default());
    let ctx = &mut Query::new().on(level).stats(&mut packed);
    q.any_hits(rays, &mut tris, ctx, &mut batch).unwrap();
    let mut hits = 0;
    for (i, ray) in rays.iter().enumerate() {
        let brute = brute_watertight(mesh, ray);
        assert_eq!(
            batch[i].is_some(),
            brute.is_some(),
            "{name}: ray {i} {ray:?}"
        );
        if let Some((p, h)) = batch[i] {
            let own = Watertight.intersect(ray, &vertices(mesh, p));
            assert_eq!(
                bits(Some((p, h))),
                bits(own.map(|o| (p, o))),
                "{name}: ray {i}"
            );
        }
        hits += usize::from(brute.is_some());
        let single = q.any_hit(
            ray,
            &mut tris,
            &mut Query::new().on(level).stats(&mut alone),
        );
        assert_eq!(
            batch[i].is_some(),
            single.is_some(),
            "{name}: ray {i}, batch against the single-ray any hit"
        );
    }
    assert!(
        packed.nodes_visited * 2 < alone.nodes_visited,
        "{name}: {packed:?} in packets, {alone:?} alone"
    );
    hits
}

/// Shadow rays from a camera's hits towards one light (`spawn_ray_to`: origins on the
/// surface, many pixels apart), the rays of any-hit packets: hit or miss as brute force, each
/// hit one of its ray's, at every SIMD level the CPU has.
#[test]
fn any_hit_packets_hit_exactly_when_single_rays_do() {
    let (pos, tri) = lcg_soup(1500, 21, 4.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tri);
    let light = Vec3::new(2.0, 9.0, -6.0);
    let shadow: Vec<Ray> = camera_rays(Vec3::new(0.5, 0.2, -8.0), (160, 40), 0.05)
        .iter()
        .take(160 * 40)
        .filter_map(|r| brute_watertight(&mesh, r))
        .map(|(p, h)| spawn_ray_to(&h.to_hit(&vertices(&mesh, p)), light))
        .collect();
    assert!(shadow.len() > 1000, "{} shadow rays", shadow.len());
    for leaf in [1, 4] {
        let bvh8: Bvh8<_, _> = wide::<8>(&mesh, leaf);
        let bvh4: Bvh4<_, _> = wide::<4>(&mesh, leaf);
        let hits = any_batch_hits_as_brute_force(Portable, "bvh8", &bvh8, &mesh, &shadow);
        assert!(
            hits > shadow.len() / 10 && hits < shadow.len(),
            "{hits} hits"
        );
        any_batch_hits_as_brute_force(Portable, "bvh4", &bvh4, &mesh, &shadow);
        #[cfg(target_arch = "x86_64")]
        if let Some(level) = crate::test_util::avx2_or_skip(
            "bvh::wide::packet::tests::any_hit_packets_hit_exactly_when_single_rays_do",
        ) {
            any_batch_hits_as_brute_force(level, "bvh8 avx2", &bvh8, &mesh, &shadow);
            any_batch_hits_as_brute_force(level, "bvh4 avx2", &bvh4, &mesh, &shadow);
        }
    }
}
