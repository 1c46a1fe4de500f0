//! The queries of the `mcu-query` image, which links only what a firmware needs to answer rays
//! on a baked BVH: a lean loop (no other check's code), so that the image's size is the query
//! path's.

use super::{Fnv, Rng, Summary, fold_answers};
use halfray_core::Vec3;
use halfray_core::bvh::{Bvh, BvhNode, TriangleMesh};
use halfray_core::ray::Ray;
use halfray_core::triangle::{TriangleHit, TriangleIntersector};

/// `rays` rays at `bvh` (over `mesh`), each with a closest- and an any-hit query with `isect`
/// folded into `hash`: by turns a random ray through the mesh's box, a ray aimed at a vertex
/// and a ray aimed at an edge midpoint, from origins within twice the box's size of its
/// centre. (Aimed through rounded directions, so not exactly through the vertex: the exact
/// edge and vertex rays, whose misses are leaks, are [`super::ray_checks`]'.) Any hit must
/// agree with closest hit on hit/miss; a disagreement is counted in
/// [`Summary::leaks`].
pub fn query_checks<T, N, I>(
    isect: &T,
    bvh: &Bvh<N, I>,
    mesh: &TriangleMesh<'_>,
    rays: usize,
    hash: &mut Fnv,
) -> Summary
where
    T: TriangleIntersector,
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    let b = bvh.bounds();
    let (lo, size) = (b.min, b.max - b.min);
    let center = (b.min + b.max) * 0.5;
    let reach = 2.0 * size.x.max(size.y).max(size.z);
    let mut rng = Rng(0x2545_f491);
    let mut summary = Summary::default();
    for k in 0..rays {
        let o = center
            + Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ) * reach;
        let tri = mesh.triangle(rng.below(mesh.len().max(1)));
        let target = match (k % 3, tri) {
            (1, Some(v)) => v[0],
            (2, Some(v)) => (v[1] + v[2]) * 0.5,
            _ => lo + size * Vec3::new(rng.unit(), rng.unit(), rng.unit()),
        };
        let ray = Ray::new(o, target - o);
        let closest = closest_hit(isect, bvh, mesh, &ray);
        let any = any_hit(isect, bvh, mesh, &ray);
        fold_answers(closest, any, &mut summary, hash);
        summary.leaks += (any != closest.is_some()) as u32;
    }
    summary
}

/// One closest-hit query, out of line: each query's frame (its fixed traversal stack
/// included) is then on the stack alone, as in a firmware that makes one query at a time.
#[inline(never)]
fn closest_hit<T, N, I>(
    isect: &T,
    bvh: &Bvh<N, I>,
    mesh: &TriangleMesh<'_>,
    ray: &Ray,
) -> Option<(u32, TriangleHit)>
where
    T: TriangleIntersector,
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    bvh.closest_hit_triangles(mesh, isect, ray, None)
}

/// One any-hit query, out of line (see [`closest_hit`]).
#[inline(never)]
fn any_hit<T, N, I>(isect: &T, bvh: &Bvh<N, I>, mesh: &TriangleMesh<'_>, ray: &Ray) -> bool
where
    T: TriangleIntersector,
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    bvh.any_hit_triangles(mesh, isect, ray, None).is_some()
}
