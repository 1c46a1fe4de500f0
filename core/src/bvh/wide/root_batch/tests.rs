//! The batches of small trees against single rays (a root leaf: bit for bit, statistics
//! included; a tree with nodes: closest hits bit for bit, any hits hit for hit; at every SIMD
//! level the CPU has) and against a brute-force loop.

use crate::bvh::wide::{Bvh8, binary_options, group_capacity};
use crate::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, node_capacity};
use crate::mesh::TriangleMesh;
use crate::query::{Query, QueryStack, RayQuery, TraversalStats, Triangles};
use crate::ray::Ray;
use crate::simd::level::{Portable, SimdLevel};
use crate::test_util::{Lcg, brute_watertight, lcg_soup};
use crate::triangle::{
    MollerTrumbore, TriangleHit, TriangleIntersector, Watertight, WatertightF32, WatertightF32Exact,
};
use glam::Vec3;
use std::vec;
use std::vec::Vec;

type Answer = Option<(u32, TriangleHit)>;
/// A query level under test: fills the batch answers, returns the single-ray ones.
type BatchAndSingle<'a> = &'a dyn Fn(&[Ray], &mut [Answer]) -> Vec<Answer>;
type VecBvh8 = Bvh8<Vec<crate::bvh::wide::WideNode<8>>, Vec<crate::bvh::wide::LeafGroup>>;

fn bvh8(mesh: &TriangleMesh<'_>) -> VecBvh8 {
    let n = mesh.len();
    let binary = Bvh::build(
        mesh,
        vec![BvhNode::EMPTY; node_capacity(n)],
        vec![0u32; index_capacity(n)],
        &binary_options(BuildOptions::default()),
    )
    .unwrap();
    let nodes = vec![crate::bvh::wide::WideNode::EMPTY; crate::bvh::wide::node_capacity(n)];
    let groups = vec![crate::bvh::wide::LeafGroup::EMPTY; group_capacity(n)];
    crate::bvh::wide::WideBvh::from_binary(&binary, mesh, nodes, groups).unwrap()
}

/// The bits of an answer: equal bits, not only equal values.
fn bits(a: Answer) -> Option<(u32, [u32; 6], bool)> {
    a.map(|(p, h)| {
        let n = h.ng.to_array();
        let f = [h.t, h.b1, h.b2, n[0], n[1], n[2]].map(f32::to_bits);
        (p, f, h.front_face)
    })
}

/// Rays at `mesh` (`n`, not a multiple of eight, so the last chunk is short): from a sphere
/// around it toward points inside its box, toward its vertices and edge midpoints (where the
/// edge rules decide between neighbours), from inside it, along the axes, and every seventh
/// one of an odd kind: invalid (NaN origin, zero direction, `t_min > t_max`), `t_min < 0`, a
/// short `t_max`.
fn rays_at(mesh: &TriangleMesh<'_>, positions: &[Vec3], n: usize, seed: u64) -> Vec<Ray> {
    let mut r = Lcg(seed);
    let (lo, hi) = positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), &p| {
            (a.min(p), b.max(p))
        });
    let (centre, radius) = ((lo + hi) * 0.5, (hi - lo).length().max(1.0));
    let mut tri = 0usize;
    (0..n)
        .map(|k| {
            let origin = centre + r.v(4.0 * radius);
            let target = match k % 4 {
                0 => lo + (hi - lo) * Vec3::new(r.f(), r.f(), r.f()),
                1 => positions[k % positions.len()],
                2 => {
                    tri += 1;
                    let v = mesh.triangle(tri % mesh.len()).unwrap();
                    (v[k % 3] + v[(k + 1) % 3]) * 0.5
                }
                _ => centre + r.v(0.2 * radius),
            };
            let mut ray = match k % 11 {
                5 => Ray::new(centre, r.v(2.0)),
                9 => Ray::new(centre - Vec3::Z * 3.0 * radius, Vec3::Z),
                _ => Ray::new(origin, target - origin),
            };
            if k % 7 == 3 {
                ray = match (k / 7) % 6 {
                    0 => Ray::new(Vec3::splat(f32::NAN), Vec3::X),
                    1 => Ray::new(origin, Vec3::ZERO),
                    2 => Ray {
                        t_min: 5.0,
                        t_max: 1.0,
                        ..ray
                    },
                    3 => Ray { t_min: -1e3, ..ray },
                    4 => Ray { t_max: 0.5, ..ray },
                    _ => Ray::new(ray.origin, ray.direction * 1e-3),
                };
            }
            ray
        })
        .collect()
}

/// The batch of `bvh` with intersector `isect` at `level` against each ray's single query at
/// that level (any hits with `any`, else closest hits): the same answer bits and the same
/// statistics. Returns the hits.
fn batch_equals_single<I: TriangleIntersector, L: SimdLevel>(
    level: L,
    (bvh, mesh): (&VecBvh8, &TriangleMesh<'_>),
    isect: &I,
    rays: &[Ray],
    name: &str,
    any: bool,
) -> usize {
    let mut tris = Triangles::new(mesh, isect);
    let mut stack = QueryStack::new();
    let mut batch: Vec<Answer> = vec![None; rays.len()];
    let (mut together, mut alone) = (TraversalStats::default(), TraversalStats::default());
    let mut ctx = Query::new()
        .on(level)
        .stack(&mut stack)
        .stats(&mut together);
    if any {
        bvh.any_hits(rays, &mut tris, &mut ctx, &mut batch).unwrap();
    } else {
        bvh.closest_hits(rays, &mut tris, &mut ctx, &mut batch)
            .unwrap();
    }
    let mut hits = 0;
    for (i, ray) in rays.iter().enumerate() {
        let mut ctx = Query::new().on(level).stats(&mut alone);
        let single = if any {
            bvh.any_hit(ray, &mut tris, &mut ctx)
        } else {
            bvh.closest_hit(ray, &mut tris, &mut ctx)
        };
        assert_eq!(bits(batch[i]), bits(single), "{name}: ray {i} {ray:?}");
        hits += usize::from(single.is_some());
    }
    assert_eq!(together, alone, "{name}");
    hits
}

/// [`batch_equals_single`] for closest and for any hits.
fn both_equal_single<I: TriangleIntersector, L: SimdLevel>(
    level: L,
    tree: (&VecBvh8, &TriangleMesh<'_>),
    isect: &I,
    rays: &[Ray],
    name: &str,
) -> usize {
    batch_equals_single(level, tree, isect, rays, name, true);
    batch_equals_single(level, tree, isect, rays, name, false)
}

/// Each of `rays` as a batch of one through `bvh`'s closest-hit batch, watertight, against
/// the brute-force loop over `mesh`: the same answer bits (mesh `m` in the messages).
fn batch_is_brute_force((bvh, mesh): (&VecBvh8, &TriangleMesh<'_>), rays: &[Ray], m: usize) {
    for (i, ray) in rays.iter().enumerate() {
        let mut tris = Triangles::new(mesh, &Watertight);
        let mut stack = QueryStack::new();
        let mut out = [None];
        bvh.closest_hits(
            core::slice::from_ref(ray),
            &mut tris,
            &mut Query::new().stack(&mut stack),
            &mut out,
        )
        .unwrap();
        let want = brute_watertight(mesh, ray);
        assert_eq!(bits(out[0]), bits(want), "mesh {m}, ray {i}: brute force");
    }
}

/// Shadow rays off `mesh`'s surface: each of `rays` that hits it spawned from its hit towards
/// a point light outside the mesh, or back through the mesh ([`crate::hit::spawn_ray_to`]).
fn shadow_rays(bvh: &VecBvh8, mesh: &TriangleMesh<'_>, rays: &[Ray], seed: u64) -> Vec<Ray> {
    let mut r = Lcg(seed);
    let mut tris = Triangles::new(mesh, &Watertight);
    rays.iter()
        .filter_map(|ray| {
            let (prim, h) = bvh.closest_hit(ray, &mut tris, &mut Query::new())?;
            let v = mesh.triangle(prim as usize)?;
            let light = if r.f() < 0.7 {
                r.v(10.0) + Vec3::splat(6.0)
            } else {
                ray.origin
            };
            Some(crate::hit::spawn_ray_to(&h.to_hit(&v), light))
        })
        .collect()
}

/// Closed and open meshes of one to eight triangles (one to three groups: the tree is one
/// leaf, no node), each with every watertight intersector (the cull across rays) and
/// Möller–Trumbore (none: the rays go alone), at every level: the batch answers each ray as
/// its single query does, closest and any hits, shadow rays spawned off the surface included
/// (the triangle a ray starts on refused by its plane), and the watertight answers are the
/// brute-force loop's.
#[test]
fn a_root_leaf_batch_answers_each_ray_as_alone() {
    let tetra = (
        vec![
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
        ],
        vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
    );
    let octa = (
        crate::solids::OCTAHEDRON_VERTICES.to_vec(),
        crate::solids::OCTAHEDRON_TRIANGLES.to_vec(),
    );
    let mut meshes = vec![tetra, octa];
    meshes.extend((1..=8).map(|n| lcg_soup(n, 40 + n as u64, 1.5, 1.0)));
    for (m, (pos, tri)) in meshes.iter().enumerate() {
        let mesh = TriangleMesh::new(pos, tri);
        let bvh = bvh8(&mesh);
        assert_eq!(bvh.node_count(), 0, "mesh {m}: the root is a leaf");
        let rays = rays_at(&mesh, pos, 8 * 125 + 5, 7 + m as u64);
        batch_is_brute_force((&bvh, &mesh), &rays, m);
        let hits = both_equal_single(Portable, (&bvh, &mesh), &Watertight, &rays, "watertight");
        assert!(hits > rays.len() / 5, "mesh {m}: only {hits} hits");
        let shadow = shadow_rays(&bvh, &mesh, &rays, 3 + m as u64);
        assert!(
            shadow.len() > rays.len() / 5,
            "mesh {m}: {} shadow rays",
            shadow.len()
        );
        let tree = (&bvh, &mesh);
        batch_equals_single(Portable, tree, &Watertight, &shadow, "shadow", true);
        both_equal_single(Portable, tree, &WatertightF32, &rays, "f32");
        both_equal_single(Portable, tree, &WatertightF32Exact, &rays, "f32 exact");
        both_equal_single(Portable, tree, &MollerTrumbore::default(), &rays, "mt");
        #[cfg(target_arch = "x86_64")]
        if let Some(level) = crate::test_util::avx2_or_skip(
            "bvh::wide::root_batch::tests::a_root_leaf_batch_answers_each_ray_as_alone",
        ) {
            both_equal_single(level, tree, &Watertight, &rays, "avx2");
            batch_equals_single(level, tree, &Watertight, &shadow, "avx2 shadow", true);
            both_equal_single(level, tree, &WatertightF32Exact, &rays, "avx2 exact");
        }
    }
}

/// The cube and soups of 9 to 32 triangles (seeds `seed + n`): meshes whose trees mostly
/// have nodes over at most eight groups (the tests skip the others).
fn small_tree_meshes(seed: u64) -> Vec<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let cube = (
        crate::solids::CUBE_VERTICES.to_vec(),
        crate::solids::CUBE_TRIANGLES.to_vec(),
    );
    let mut meshes = vec![cube];
    meshes.extend(
        (9..=32)
            .step_by(3)
            .map(|n| lcg_soup(n, seed + n as u64, 1.5, 1.0)),
    );
    meshes
}

/// Runs `check(m, positions, mesh, tree)` on each mesh `m` of [`small_tree_meshes`]`(seed)`
/// whose tree has nodes over at most eight groups; at least three must.
fn each_small_tree(seed: u64, mut check: impl FnMut(usize, &[Vec3], TriangleMesh<'_>, VecBvh8)) {
    let mut small = 0;
    for (m, (pos, tri)) in small_tree_meshes(seed).iter().enumerate() {
        let mesh = TriangleMesh::new(pos, tri);
        let bvh = bvh8(&mesh);
        if bvh.node_count() == 0 || bvh.groups().len() > 8 {
            continue;
        }
        small += 1;
        check(m, pos, mesh, bvh);
    }
    assert!(small >= 3, "only {small} small trees with nodes");
}

/// Trees with nodes over a few dozen triangles (the cube, soups of 9 to 32), at every level:
/// the any-hit batch, which tests every triangle as one run, hits exactly where each ray's
/// single any hit does, camera-like and shadow rays, and each hit is its triangle's own
/// watertight hit, bit for bit, inside the ray's interval.
#[test]
fn a_small_tree_any_hit_batch_hits_where_each_ray_alone_does() {
    each_small_tree(90, |m, pos, mesh, bvh| {
        let rays = rays_at(&mesh, pos, 8 * 125 + 5, 11 + m as u64);
        let shadow = shadow_rays(&bvh, &mesh, &rays, 5 + m as u64);
        assert!(
            shadow.len() > rays.len() / 10,
            "mesh {m}: {} shadow rays",
            shadow.len()
        );
        let check = |level: BatchAndSingle<'_>, rays: &[Ray]| {
            let mut batch: Vec<Answer> = vec![None; rays.len()];
            let single = level(rays, &mut batch);
            let mut hits = 0;
            for (i, ray) in rays.iter().enumerate() {
                assert_eq!(
                    batch[i].is_some(),
                    single[i].is_some(),
                    "mesh {m}, ray {i} {ray:?}"
                );
                if let Some((prim, h)) = batch[i] {
                    hits += 1;
                    let v = mesh.triangle(prim as usize).unwrap();
                    let own = Watertight.intersect(ray, &v);
                    assert_eq!(
                        bits(own.map(|o| (prim, o))),
                        bits(batch[i]),
                        "mesh {m}, ray {i}"
                    );
                    assert!(h.t > ray.t_min && h.t <= ray.t_max, "mesh {m}, ray {i}");
                }
            }
            hits
        };
        let portable = |rays: &[Ray], out: &mut [Answer]| {
            let mut tris = Triangles::new(&mesh, &Watertight);
            let mut stack = QueryStack::new();
            bvh.any_hits(rays, &mut tris, &mut Query::new().stack(&mut stack), out)
                .unwrap();
            rays.iter()
                .map(|r| bvh.any_hit(r, &mut tris, &mut Query::new()))
                .collect::<Vec<_>>()
        };
        let hits = check(&portable, &rays);
        assert!(hits > rays.len() / 5, "mesh {m}: only {hits} hits");
        check(&portable, &shadow);
        #[cfg(target_arch = "x86_64")]
        if let Some(level) = crate::test_util::avx2_or_skip(
            "bvh::wide::root_batch::tests::a_small_tree_any_hit_batch_hits_where_each_ray_alone_does",
        ) {
            let avx2 = |rays: &[Ray], out: &mut [Answer]| {
                let mut tris = Triangles::new(&mesh, &Watertight);
                let mut stack = QueryStack::new();
                bvh.any_hits(
                    rays,
                    &mut tris,
                    &mut Query::new().on(level).stack(&mut stack),
                    out,
                )
                .unwrap();
                rays.iter()
                    .map(|r| bvh.any_hit(r, &mut tris, &mut Query::new().on(level)))
                    .collect::<Vec<_>>()
            };
            check(&avx2, &rays);
            check(&avx2, &shadow);
        }
    });
}

/// Trees with nodes over a few dozen triangles (the cube, soups of 9 to 32), every
/// intersector with the cull across rays, at every level: the closest-hit batch (its packets:
/// such a tree's closest hits are not taken as one run) answers each ray as its single-ray
/// walk does, bit for bit, camera-like and shadow rays (`t_min > 0` and short intervals among
/// them), and the watertight answers are the brute-force loop's.
#[test]
fn a_small_tree_closest_hit_batch_answers_each_ray_as_alone() {
    each_small_tree(70, |m, pos, mesh, bvh| {
        let mut rays = rays_at(&mesh, pos, 8 * 125 + 5, 13 + m as u64);
        let shadow = shadow_rays(&bvh, &mesh, &rays, 9 + m as u64);
        assert!(
            shadow.len() > rays.len() / 10,
            "mesh {m}: {} shadow rays",
            shadow.len()
        );
        rays.extend(shadow);
        let check = |level: BatchAndSingle<'_>, name: &str| {
            let mut batch: Vec<Answer> = vec![None; rays.len()];
            let single = level(&rays, &mut batch);
            for (i, ray) in rays.iter().enumerate() {
                assert_eq!(
                    bits(batch[i]),
                    bits(single[i]),
                    "{name}, mesh {m}, ray {i} {ray:?}"
                );
            }
            batch.iter().filter(|a| a.is_some()).count()
        };
        macro_rules! at_level {
            ($level:expr, $isect:expr) => {
                |rays: &[Ray], out: &mut [Answer]| {
                    let mut tris = Triangles::new(&mesh, $isect);
                    let mut stack = QueryStack::new();
                    bvh.closest_hits(
                        rays,
                        &mut tris,
                        &mut Query::new().on($level).stack(&mut stack),
                        out,
                    )
                    .unwrap();
                    rays.iter()
                        .map(|r| bvh.closest_hit(r, &mut tris, &mut Query::new().on($level)))
                        .collect::<Vec<_>>()
                }
            };
        }
        let hits = check(&at_level!(Portable, &Watertight), "watertight");
        assert!(hits > rays.len() / 5, "mesh {m}: only {hits} hits");
        batch_is_brute_force((&bvh, &mesh), &rays, m);
        check(&at_level!(Portable, &WatertightF32), "f32");
        check(&at_level!(Portable, &WatertightF32Exact), "f32 exact");
        #[cfg(target_arch = "x86_64")]
        if let Some(level) = crate::test_util::avx2_or_skip(
            "bvh::wide::root_batch::tests::a_small_tree_closest_hit_batch_answers_each_ray_as_alone",
        ) {
            check(&at_level!(level, &Watertight), "avx2");
            check(&at_level!(level, &WatertightF32Exact), "avx2 exact");
        }
    });
}

/// A root leaf's batch runs on the cull across rays where the leaf test has one: taken for
/// the watertight test (its `sheared_rays`), the answers written the single-ray ones;
/// refused, with nothing written, for Möller–Trumbore (no such cull), whose rays the caller
/// then walks alone.
#[test]
fn a_root_leaf_batch_takes_the_cull_across_rays_where_the_test_has_one() {
    use crate::bvh::wide::ChildRef;
    let (pos, tri) = lcg_soup(8, 48, 1.5, 1.0);
    let mesh = TriangleMesh::new(&pos, &tri);
    let bvh = bvh8(&mesh);
    let ChildRef::Leaf { start, count } = bvh.root() else {
        panic!("eight triangles: the root is a leaf");
    };
    let rays = rays_at(&mesh, &pos, 8 * 4 + 3, 5);
    // A sentinel in every slot: what the batch writes replaces it.
    let unwritten: Answer = Some((
        u32::MAX,
        TriangleHit {
            t: -1.0,
            b1: -1.0,
            b2: -1.0,
            ng: Vec3::ZERO,
            front_face: false,
        },
    ));
    // `root_leaf_hits` of every ray with `isect`: whether it took them, and what it wrote.
    fn batch<I: TriangleIntersector>(
        (bvh, mesh): (&VecBvh8, &TriangleMesh<'_>),
        (start, count): (u32, u32),
        isect: &I,
        rays: &[Ray],
        unwritten: Answer,
    ) -> (bool, Vec<Answer>) {
        let mut out = vec![unwritten; rays.len()];
        let mut tris = Triangles::new(mesh, isect);
        let taken =
            bvh.root_leaf_hits((start, count), rays, &mut tris, &mut Query::new(), &mut out);
        (taken, out)
    }
    let tree = (&bvh, &mesh);
    let (taken, out) = batch(tree, (start, count), &Watertight, &rays, unwritten);
    assert!(taken, "the watertight test culls across rays");
    let mut tris = Triangles::new(&mesh, &Watertight);
    let mut hits = 0;
    for (i, ray) in rays.iter().enumerate() {
        let single = bvh.closest_hit(ray, &mut tris, &mut Query::new());
        assert_eq!(bits(out[i]), bits(single), "ray {i}");
        hits += usize::from(single.is_some());
    }
    assert!(hits > rays.len() / 5, "only {hits} hits");
    let mt = MollerTrumbore::default();
    let (taken, out) = batch(tree, (start, count), &mt, &rays, unwritten);
    assert!(!taken, "Möller–Trumbore has no cull across rays");
    assert!(
        out.iter().all(|&a| bits(a) == bits(unwritten)),
        "nothing written when refused"
    );
}
