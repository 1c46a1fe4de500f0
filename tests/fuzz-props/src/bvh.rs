//! The `bvh` target: small arbitrary triangle soups and rays, BVH against brute force.
//!
//! Layout: `flags: u8` (bit 0: quantized vertex coordinates ([`Input::q`]), else raw
//! `f32`; bit 1: [`BuildOptions::exclude_non_finite`]; bit 2: leaves of one primitive),
//! `vertex count: u8` (mod 25), `triangle count: u8` (mod 17), the vertices, the
//! triangles (three `u8` vertex indices each, taken mod `vertex count + 2` so that some are
//! out of range), then rays until the input ends (at most 8), each `flags: u8` (bit 0:
//! quantized origin and direction; bit 1: aim at `p_i + s·(p_j − p_i)` for two vertex bytes
//! and `s = byte mod 9 / 8`; bit 2: interval from two `f32`s, else `(0, +∞]`), origin,
//! direction, then the aim or interval bytes.

use super::*;
use super::{Enc, Input, fmt_vec3};
pub use crate::tree_oracle::Oracle;
pub(crate) use crate::tree_oracle::usable_primitives;
use crate::tree_oracle::{checked_build, triangle_meets_box};
use glam::Vec3;
use halfray_core::aabb::Aabb;
use halfray_core::bvh::wide::{Bvh8, LeafGroup, WideNode, group_capacity};
use halfray_core::bvh::{BuildOptions, Bvh, BvhError, BvhNode, index_capacity, node_capacity};
use halfray_core::mesh::{PrimitiveSource, TriangleMesh};
use halfray_core::prelude::*;
use halfray_core::query::{Query, Triangles};
use halfray_core::ray::Ray;
use halfray_core::triangle::{MollerTrumbore, TriangleIntersector, Watertight};

/// The decoded input.
#[derive(Clone, Debug)]
pub struct Soup {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles (indices may be out of range).
    pub triangles: Vec<[u32; 3]>,
    /// Build options.
    pub options: BuildOptions,
    /// Rays.
    pub rays: Vec<Ray>,
}

impl Soup {
    /// The soup's vertices and triangles as the failure messages of the `bvh`, `grid` and
    /// `kdtree` targets print them: `positions …` and, on the next line indented by two
    /// spaces, `triangles …` (no trailing newline).
    pub(crate) fn describe_mesh(&self) -> String {
        format!(
            "positions {}\n  triangles {:?}",
            self.positions
                .iter()
                .map(|p| fmt_vec3(*p))
                .collect::<Vec<_>>()
                .join(", "),
            self.triangles
        )
    }
}

/// Decodes a `bvh` input (see the module docs).
pub fn decode(data: &[u8]) -> Soup {
    let mut i = Input::new(data);
    let fl = i.u8();
    let nv = usize::from(i.u8()) % 25;
    let nt = usize::from(i.u8()) % 17;
    let positions: Vec<Vec3> = (0..nv)
        .map(|_| if fl & 1 != 0 { i.qvec3() } else { i.vec3() })
        .collect();
    let m = nv as u32 + 2;
    let triangles = (0..nt)
        .map(|_| {
            [
                u32::from(i.u8()) % m,
                u32::from(i.u8()) % m,
                u32::from(i.u8()) % m,
            ]
        })
        .collect();
    let options = BuildOptions {
        max_leaf_size: if fl & 4 != 0 { 1 } else { 4 },
        exclude_non_finite: fl & 2 != 0,
        ..BuildOptions::default()
    };
    let mut rays = Vec::new();
    while !i.is_empty() && rays.len() < 8 {
        let rf = i.u8();
        let (o, d) = if rf & 1 != 0 {
            (i.qvec3(), i.qvec3())
        } else {
            (i.vec3(), i.vec3())
        };
        let mut ray = Ray::new(o, d);
        if rf & 2 != 0 && !positions.is_empty() {
            let a = positions[usize::from(i.u8()) % nv];
            let b = positions[usize::from(i.u8()) % nv];
            let s = f32::from(i.u8() % 9) / 8.0;
            ray.direction = a + (b - a) * s - o;
        }
        if rf & 4 != 0 {
            ray.t_min = i.f32();
            ray.t_max = i.f32();
        }
        rays.push(ray);
    }
    Soup {
        positions,
        triangles,
        options,
        rays,
    }
}

/// Encodes a quantized soup with default options and `(origin, direction)` rays aimed by
/// vertex pairs: `aims[k] = (origin, i, j, s8)` (aim at `p_i + s8/8·(p_j − p_i)`).
pub fn encode_quantized(
    positions: &[Vec3],
    triangles: &[[u8; 3]],
    aims: &[(Vec3, u8, u8, u8)],
) -> Vec<u8> {
    let mut e = Enc::new()
        .u8(1)
        .u8(positions.len() as u8)
        .u8(triangles.len() as u8);
    for p in positions {
        e = e.qvec3(*p);
    }
    for t in triangles {
        e = e.u8(t[0]).u8(t[1]).u8(t[2]);
    }
    for &(o, a, b, s) in aims {
        e = e.u8(3).qvec3(o).qvec3(Vec3::ZERO).u8(a).u8(b).u8(s);
    }
    e.done()
}

/// Fuzz target `bvh`: [`check`] on [`decode`]`(data)`.
pub fn bvh(data: &[u8]) {
    check(&decode(data));
}

/// `true` when every in-tree vertex lies within [`super::DOMAIN_MAX`] (2⁶⁰) of the origin
/// in every coordinate, the range the watertight test documents (triangles up to ~1e20):
/// beyond it the projected coordinates' products leave the range where the `f64` edge
/// functions and the `t` forms keep their bounds.
pub fn within_domain(mesh: &TriangleMesh<'_>, ray: &Ray, in_tree: &[bool]) -> bool {
    (0..in_tree.len())
        .filter(|&i| in_tree[i])
        .filter_map(|i| mesh.triangle(i))
        .all(|v| {
            v.iter().all(|p| {
                (p.as_dvec3() - ray.origin.as_dvec3()).abs().max_element() <= super::DOMAIN_MAX
            })
        })
}

/// [`super::projection_underflows`] for any triangle in the tree.
pub fn projection_underflows(mesh: &TriangleMesh<'_>, ray: &Ray, in_tree: &[bool]) -> bool {
    (0..in_tree.len())
        .filter(|&i| in_tree[i])
        .filter_map(|i| mesh.triangle(i))
        .any(|v| super::projection_underflows(ray, &v))
}

/// Properties of the BVH on one soup:
///
/// 1. Building with exactly [`node_capacity`] / [`index_capacity`] storage succeeds, unless a
///    primitive has unusable bounds (non-finite vertex, out-of-range index) and
///    `exclude_non_finite` is off: then the error is `NonFinite` naming the first.
/// 2. One node or one index too few gives `Capacity` (`BvhNodes` / `BvhIndices`)
///    with the right counts, and the storage is left untouched.
/// 3. Refitting over the same source leaves every node bit-for-bit unchanged. Refitting a
///    copy over the soup moved ([`moved`]) names the first primitive of the tree whose moved
///    bounds are unusable (or succeeds), and the copy's closest hits, any hits and box
///    queries (as in 4 and 5) equal brute force over the tree's primitives usable after the
///    move.
/// 4. For every ray and for `watertight` and `moller-trumbore`: the closest hit equals the
///    brute-force loop (same primitive, same hit record); any-hit agrees on hit/miss and its
///    primitive really is hit in the interval.
/// 5. A box query (the box spanned by each ray's origin and origin + direction) reports
///    exactly the primitives in the tree that overlap it ([`triangle_meets_box`]).
/// 6. The 8-wide tree gives the binary tree's answers (portable and AVX2 levels).
/// 7. The 8-wide tree's batch query gives its single-ray answers, bit for bit
///    ([`check_batches`]).
pub fn check(s: &Soup) {
    let mesh = TriangleMesh::new(&s.positions, &s.triangles);
    let n = mesh.primitive_count();
    let ctx = || format!("options {:?}\n  {}", s.options, s.describe_mesh());
    let valid = usable_primitives(&mesh);
    let first_bad = valid.iter().position(|&ok| !ok);

    // 2. Too-small storage.
    if n > 0 {
        let sentinel = BvhNode::default();
        let nodes = vec![sentinel; node_capacity(n) - 1];
        let idx = vec![u32::MAX; index_capacity(n)];
        let r = Bvh::build(&mesh, nodes, idx, &s.options);
        match r {
            Err(BvhError::Capacity(halfray_core::error::CapacityError {
                storage: halfray_core::error::Storage::BvhNodes,
                needed,
                available,
            })) => {
                assert_eq!(
                    (needed, available),
                    (node_capacity(n), node_capacity(n) - 1)
                );
            }
            other => panic!("one node too few gave {other:?}\n{}", ctx()),
        }
        let mut nodes = vec![sentinel; node_capacity(n)];
        let mut idx = vec![u32::MAX; index_capacity(n) - 1];
        let r = Bvh::build(&mesh, &mut nodes[..], &mut idx[..], &s.options);
        match r {
            Err(BvhError::Capacity(halfray_core::error::CapacityError {
                storage: halfray_core::error::Storage::BvhIndices,
                needed,
                available,
            })) => {
                assert_eq!((needed, available), (n, n - 1));
            }
            other => panic!("one index too few gave {other:?}\n{}", ctx()),
        }
        assert!(
            nodes.iter().all(|x| *x == sentinel) && idx.iter().all(|&x| x == u32::MAX),
            "refused build wrote into the storage\n{}",
            ctx()
        );
    }

    // 1. Build.
    let nodes = vec![BvhNode::default(); node_capacity(n)];
    let idx = vec![u32::MAX; index_capacity(n)];
    let non_finite = |e: &BvhError| match *e {
        BvhError::NonFinite(halfray_core::error::NonFiniteError {
            element: halfray_core::error::InputElement::Primitive,
            index,
        }) => Some(index),
        _ => None,
    };
    let built = Bvh::build(&mesh, nodes, idx, &s.options);
    let exclude = s.options.exclude_non_finite;
    let Some(mut bvh) = checked_build(built, non_finite, first_bad, exclude, &ctx) else {
        return;
    };
    let expected_count = valid.iter().filter(|&&ok| ok).count();
    assert_eq!(
        bvh.primitive_count(),
        expected_count,
        "primitive count\n{}",
        ctx()
    );
    let mut in_tree = vec![false; n];
    for &p in bvh.indices() {
        let p = p as usize;
        assert!(
            p < n && valid[p] && !in_tree[p],
            "bad index {p} in the tree\n{}",
            ctx()
        );
        in_tree[p] = true;
    }

    // 3. Refit over the same source.
    let before: Vec<BvhNode> = bvh.nodes().to_vec();
    assert_eq!(
        bvh.refit(&mesh),
        Ok(()),
        "refit over the same source\n{}",
        ctx()
    );
    assert_eq!(
        bvh.nodes(),
        &before[..],
        "refit changed the boxes\n{}",
        ctx()
    );

    // 3. Refit over the moved soup.
    let moved_positions = moved(&s.positions);
    let moved_mesh = TriangleMesh::new(&moved_positions, &s.triangles);
    let moved_valid = usable_primitives(&moved_mesh);
    let moved_in_tree: Vec<bool> = (0..n).map(|i| in_tree[i] && moved_valid[i]).collect();
    let moved_ctx = || {
        format!(
            "refitted over the moved positions
{}",
            ctx()
        )
    };
    let mut refitted = bvh.clone();
    let want_refit = match (0..n).find(|&i| in_tree[i] && !moved_valid[i]) {
        Some(index) => Err(BvhError::NonFinite(halfray_core::error::NonFiniteError {
            element: halfray_core::error::InputElement::Primitive,
            index,
        })),
        None => Ok(()),
    };
    assert_eq!(
        refitted.refit(&moved_mesh),
        want_refit,
        "refit over the moved soup
{}",
        moved_ctx()
    );
    Oracle::each_ray(
        &moved_mesh,
        &moved_in_tree,
        &moved_ctx,
        &s.rays,
        |oracle, ray| {
            oracle.check_queries(&refitted, "refitted BVH", &Watertight, ray, true);
            check_box_query(&refitted, oracle, ray);
        },
    );

    // 6. The 8-wide tree collapsed from it: exactly sized storage builds, and every ray
    // below gives the binary tree's answers.
    let wide_nodes = Bvh8::<Vec<WideNode<8>>, Vec<LeafGroup>>::node_count_for(&bvh)
        .unwrap_or_else(|e| panic!("wide node count: {e}\n{}", ctx()));
    let wide = Bvh8::from_binary(
        &bvh,
        &mesh,
        vec![WideNode::<8>::EMPTY; wide_nodes],
        vec![LeafGroup::EMPTY; group_capacity(bvh.primitive_count())],
    )
    .unwrap_or_else(|e| panic!("wide collapse: {e}\n{}", ctx()));

    // 4, 5. Rays.
    Oracle::each_ray(&mesh, &in_tree, &ctx, &s.rays, |oracle, ray| {
        oracle.check_queries(&bvh, "BVH", &Watertight, ray, true);
        check_wide(&wide, oracle, &Watertight, ray, true);
        // Möller–Trumbore's inexact edge tests can report a hit slightly outside the
        // triangle, hence outside its box: only the weak form holds for it.
        check_wide(&wide, oracle, &MollerTrumbore::CLASSIC, ray, false);
        oracle.check_queries(&bvh, "BVH", &MollerTrumbore::CLASSIC, ray, false);
        check_box_query(&bvh, oracle, ray);
    });

    // 7. Ray batches: the same answers as single rays.
    check_batches(&wide, &Watertight, &s.rays, &ctx);
    check_batches(&wide, &MollerTrumbore::CLASSIC, &s.rays, &ctx);
}

/// The soup's positions moved, by an amount the input decides: each vertex to the midpoint
/// of itself and the next one (the last with the first), `p_i·0.5 + p_(i+1)·0.5` (no
/// overflow). A non-finite vertex makes both its own and its predecessor's midpoints
/// non-finite, so a primitive usable at build time can become unusable.
pub fn moved(positions: &[Vec3]) -> Vec<Vec3> {
    (0..positions.len())
        .map(|i| positions[i] * 0.5 + positions[(i + 1) % positions.len()] * 0.5)
        .collect()
}

/// The box query of `bvh` over `oracle.mesh` with the box spanned by `ray`'s origin and
/// origin + direction: exactly the primitives `oracle.in_tree` that [`triangle_meets_box`],
/// each once, and its count is the number reported.
fn check_box_query(bvh: &Bvh<Vec<BvhNode>, Vec<u32>>, oracle: &Oracle<'_, '_>, ray: &Ray) {
    let q = Aabb::new(ray.origin, ray.origin).grow(ray.origin + ray.direction);
    let mut found = Vec::new();
    let reported = bvh.query_box(oracle.mesh, &q, |p| {
        found.push(p);
        true
    });
    found.sort_unstable();
    let expect: Vec<u32> = (0..oracle.in_tree.len())
        .filter(|&i| {
            oracle.in_tree[i]
                && oracle
                    .mesh
                    .triangle(i)
                    .is_some_and(|v| triangle_meets_box(&v, q.min, q.max))
        })
        .map(|i| i as u32)
        .collect();
    assert_eq!(reported, found.len());
    assert_eq!(
        found,
        expect,
        "query_box({q:?}) differs from brute force\n{}",
        (oracle.ctx)()
    );
}

/// The batch queries of the 8-wide tree ([`RayQuery::closest_hits`], `any_hits`) on the soup's
/// rays, each followed by a fan of 7 rays from its origin within about 0.1° of its direction
/// (coherent: walked as packets, whatever the soup): every closest hit equals the single-ray
/// query's, bit for bit, and every any hit is a hit exactly where the single ray's is, at the
/// portable level and, where the CPU has it, the AVX2 level.
///
/// [`RayQuery::closest_hits`]: halfray_core::query::RayQuery::closest_hits
fn check_batches<T: TriangleIntersector>(
    wide: &Bvh8<Vec<WideNode<8>>, Vec<LeafGroup>>,
    isect: &T,
    rays: &[Ray],
    ctx: &dyn Fn() -> String,
) {
    let mut batch = Vec::with_capacity(8 * rays.len());
    for r in rays {
        batch.push(*r);
        let step = r.direction.abs().max_element() * 2e-4;
        for k in 1..8u8 {
            let spread = Vec3::new(f32::from(k & 1), f32::from(k >> 1 & 1), f32::from(k >> 2));
            batch.push(Ray {
                direction: r.direction + spread * step,
                ..*r
            });
        }
    }
    batch_matches(halfray_core::simd_level::Portable, wide, isect, &batch, ctx);
    #[cfg(target_arch = "x86_64")]
    if let Some(level) = avx2_or_skip() {
        batch_matches(level, wide, isect, &batch, ctx);
    }
}

/// [`check_batches`] at SIMD `level`.
fn batch_matches<L: halfray_core::simd_level::SimdLevel, T: TriangleIntersector>(
    level: L,
    wide: &Bvh8<Vec<WideNode<8>>, Vec<LeafGroup>>,
    isect: &T,
    batch: &[Ray],
    ctx: &dyn Fn() -> String,
) {
    use halfray_core::query::{Query, RayQuery, Triangles};
    let mesh = TriangleMesh::new(&[], &[]);
    let mut tris = Triangles::new(&mesh, isect);
    let bits = |h: Option<(u32, halfray_core::triangle::TriangleHit)>| {
        h.map(|(p, h)| (p, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
    };
    let mut out = vec![None; batch.len()];
    wide.closest_hits(batch, &mut tris, &mut Query::new().on(level), &mut out)
        .expect("as many answers as rays");
    let mut any = vec![None; batch.len()];
    wide.any_hits(batch, &mut tris, &mut Query::new().on(level), &mut any)
        .expect("as many answers as rays");
    for (i, r) in batch.iter().enumerate() {
        let one = RayQuery::closest_hit(wide, r, &mut tris, &mut Query::new().on(level));
        assert_eq!(
            bits(out[i]),
            bits(one),
            "{}: batch ray {i} {r:?} differs from the single ray\n{}",
            isect.name(),
            ctx()
        );
        // Any hits: hit or miss as the single ray; a hit within the interval, not nearer than
        // the closest one.
        let single_any = RayQuery::any_hit(wide, r, &mut tris, &mut Query::new().on(level));
        assert_eq!(
            any[i].is_some(),
            single_any.is_some(),
            "{}: batch any hit of ray {i} {r:?} differs from the single ray's\n{}",
            isect.name(),
            ctx()
        );
        if let (Some((_, a)), Some((_, c))) = (any[i], one) {
            assert!(
                a.t > r.t_min && a.t <= r.t_max && a.t >= c.t,
                "{}: batch any hit {a:?} of ray {i} {r:?} (closest {c:?})\n{}",
                isect.name(),
                ctx()
            );
        }
    }
}

/// The AVX2+FMA level, when the CPU has it; otherwise `None`, and the skip is recorded once
/// per process, as the core's tests do (`scripts/test-all.sh` prints `HALFRAY_SKIP_LOG`;
/// with `HALFRAY_REQUIRE_AVX2` set, a missing level is a failure).
#[cfg(target_arch = "x86_64")]
fn avx2_or_skip() -> Option<halfray_core::simd_level::Avx2Fma> {
    static NOTED: std::sync::Once = std::sync::Once::new();
    let level = halfray::simd::avx2_fma();
    if level.is_none() {
        NOTED.call_once(|| {
            assert!(
                std::env::var_os("HALFRAY_REQUIRE_AVX2").is_none(),
                "HALFRAY_REQUIRE_AVX2 is set but the CPU reports no AVX2+FMA"
            );
            halfray::skips::record_skip(
                "SKIPPED halfray-fuzz-props bvh::check_wide: the AVX2 level's answers \
                 (no AVX2+FMA on this CPU)",
            );
        });
    }
    level
}

/// The 8-wide tree's closest and any hit on `ray` checked as every tree's
/// ([`Oracle::check_queries`]); where the CPU has AVX2 and FMA, the queries at that SIMD level
/// (the frontend's: node test, child sort, lane cull and the hit's `f64` plane kernel) must
/// also return the portable answers, bit for bit.
fn check_wide<T: TriangleIntersector>(
    wide: &Bvh8<Vec<WideNode<8>>, Vec<LeafGroup>>,
    oracle: &Oracle<'_, '_>,
    isect: &T,
    ray: &Ray,
    exact: bool,
) {
    let (got, any) = oracle.check_queries(wide, "wide BVH", isect, ray, exact);
    #[cfg(target_arch = "x86_64")]
    if let Some(level) = avx2_or_skip() {
        let mut stack = halfray_core::query::QueryStack::new();
        let simd = wide.closest_hit(
            ray,
            &mut Triangles::new(oracle.mesh, isect),
            &mut Query::new().on(level).stack(&mut stack),
        );
        let bits = |h: Option<(u32, halfray_core::triangle::TriangleHit)>| {
            h.map(|(p, h)| {
                (
                    p,
                    h.t.to_bits(),
                    h.b1.to_bits(),
                    h.b2.to_bits(),
                    h.ng.to_array().map(f32::to_bits),
                    h.front_face,
                )
            })
        };
        assert_eq!(bits(simd), bits(got), "AVX2 level's closest hit: {ray:?}");
        let simd_any = wide.any_hit(
            ray,
            &mut Triangles::new(oracle.mesh, isect),
            &mut Query::new().on(level).stack(&mut stack),
        );
        assert_eq!(
            simd_any.is_some(),
            any.is_some(),
            "AVX2 level's any hit: {ray:?}"
        );
    }
}

/// The five points the `bvh`, `grid` and `kdtree` seeds are built on: the corners of the
/// 4 × 4 square in `z = 0`, counter-clockwise from the origin, then the apex `(2, 2, 3)`
/// above its centre.
pub(crate) const SEED_POINTS: [Vec3; 5] = [
    Vec3::new(0.0, 0.0, 0.0),
    Vec3::new(4.0, 0.0, 0.0),
    Vec3::new(4.0, 4.0, 0.0),
    Vec3::new(0.0, 4.0, 0.0),
    Vec3::new(2.0, 2.0, 3.0),
];

/// The origin of most of the seeds' aimed rays, above and off to the side of
/// [`SEED_POINTS`].
pub(crate) const SEED_ORIGIN: Vec3 = Vec3::new(1.25, -2.5, 7.0);

/// The closed pyramid over [`SEED_POINTS`] as vertex-index bytes: the four sides around
/// apex 4, then the base split on its diagonal 0–2.
pub(crate) fn seed_pyramid() -> Vec<[u8; 3]> {
    (0..4u8)
        .map(|k| [k, (k + 1) % 4, 4])
        .chain([[0, 2, 1], [0, 3, 2]])
        .collect()
}

/// Coincident, duplicated and zero-area triangles over [`SEED_POINTS`] (the tie rule): the
/// quad's first half twice and once rotated, a point, a segment, the quad's second half.
pub(crate) const SEED_DUPLICATES: [[u8; 3]; 6] = [
    [0, 1, 2],
    [0, 1, 2],
    [1, 2, 0],
    [3, 3, 3],
    [0, 1, 1],
    [0, 2, 3],
];

/// Rays at [`SEED_DUPLICATES`] ([`encode_quantized`]'s aims): at the quad's centre and at
/// the midpoint of edge 0–1 from [`SEED_ORIGIN`], and along the segment's line from `−x`.
pub(crate) const SEED_DUPLICATE_AIMS: [(Vec3, u8, u8, u8); 3] = [
    (SEED_ORIGIN, 0, 2, 2),
    (SEED_ORIGIN, 0, 1, 4),
    (Vec3::new(-1.0, 0.0, 0.0), 1, 1, 0),
];

/// The start of the `nan-vertex-excluded` seeds (raw coordinates): flag bit 1
/// (`exclude_non_finite`), four vertices (the origin, `x`, `y` and one with a NaN `x`) and
/// the count of three triangles, whose indices come next.
pub(crate) fn seed_nan_vertex() -> Enc {
    let mut raw = Enc::new().u8(2).u8(4).u8(3);
    for p in [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(f32::NAN, 0.0, 0.0)] {
        raw = raw.vec3(p);
    }
    raw
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("bvh", format!("seed-{name}"), bytes);
    let (quad, o) = (SEED_POINTS, SEED_ORIGIN);
    // Two triangles sharing the diagonal; rays at the shared edge, a shared vertex, interior.
    s.push(t(
        "quad-shared-edge",
        bvh::encode_quantized(
            &quad,
            &[[0, 1, 2], [0, 2, 3]],
            &[(o, 0, 2, 4), (o, 0, 2, 1), (o, 0, 0, 0), (o, 1, 3, 3)],
        ),
    ));
    // Pyramid (closed fan around the apex) with rays at the apex and the ridges: the four
    // sides around apex 4, then the base split on its diagonal 0–2.
    let pyramid = seed_pyramid();
    s.push(t(
        "pyramid",
        bvh::encode_quantized(
            &quad,
            &pyramid,
            &[
                (o, 4, 4, 0),
                (o, 0, 4, 4),
                (Vec3::new(-3.0, 1.0, 0.5), 2, 4, 2),
            ],
        ),
    ));
    // Duplicated coplanar triangles (tie rule), a degenerate one and a collinear one.
    s.push(t(
        "duplicates-degenerate",
        bvh::encode_quantized(&quad, &SEED_DUPLICATES, &SEED_DUPLICATE_AIMS),
    ));
    // Out-of-range vertex index (unusable primitive): the build must name it.
    s.push(t(
        "out-of-range-index",
        bvh::encode_quantized(&quad[..3], &[[0, 1, 2], [0, 1, 4]], &[(o, 0, 1, 4)]),
    ));
    // Same with exclude_non_finite, and a NaN vertex (raw coordinates).
    let raw = seed_nan_vertex()
        .bytes(&[0, 1, 2, 0, 1, 3, 2, 1, 0])
        .u8(0)
        .vec3(Vec3::new(0.25, 0.25, 1.0))
        .vec3(-Vec3::Z)
        .u8(4)
        .vec3(Vec3::new(0.25, 0.25, 1.0))
        .vec3(-Vec3::Z)
        .f32(0.0)
        .f32(1.0);
    s.push(t("nan-vertex-excluded", raw.done()));
    s.push(t("empty", Enc::new().u8(1).u8(0).u8(0).u8(0).done()));
}
