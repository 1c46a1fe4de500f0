//! The queries of the `mcu-query` image, which links only what a firmware needs to answer rays
//! on a baked BVH: a lean loop (no other check's code), so that the image's size is the query
//! path's.

use super::{Fnv, Rng, Summary, fold_answers};
use halfray_core::Vec3;
use halfray_core::bvh::{Bvh, BvhNode};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{Query, QueryError, StackEntry, Triangles};
use halfray_core::ray::Ray;
use halfray_core::triangle::{TriangleHit, TriangleIntersector};

/// Entries of the traversal stack the query image gives its queries (`8·QUERY_STACK` bytes of
/// the caller's memory): more than the baked trees of `scripts/test-mcu.sh` need (their
/// [`Bvh::stack_depth`] is checked against it on the host; on the target a query that needed
/// more would refuse, which the checks count as a failure).
pub const QUERY_STACK: usize = 24;

/// `rays` rays at `bvh` (over `mesh`), by turns a random ray through the mesh's box, a ray
/// aimed at a vertex and a ray aimed at an edge midpoint, from origins within twice the box's
/// size of its centre, each answered by `answer` (closest hit and any-hit, or `None` when the
/// queries refused) and folded into `hash`. (Aimed through rounded directions, so not exactly
/// through the vertex: the exact edge and vertex rays, whose misses are leaks, are
/// [`super::ray_checks`]'.) Any hit must agree with closest hit on hit/miss; a disagreement or
/// a refusal is counted in [`Summary::leaks`].
pub fn query_checks<N, I>(
    bvh: &Bvh<N, I>,
    mesh: &TriangleMesh<'_>,
    rays: usize,
    hash: &mut Fnv,
    mut answer: impl FnMut(&Ray) -> Option<(Option<(u32, TriangleHit)>, bool)>,
) -> Summary
where
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
        let Some((closest, any)) = answer(&ray) else {
            summary.leaks += 1;
            continue;
        };
        fold_answers(closest, any, &mut summary, hash);
        summary.leaks += (any != closest.is_some()) as u32;
    }
    summary
}

/// One closest-hit query on the caller's traversal `stack`, out of line: each query's frame is
/// then on the stack alone, as in a firmware that makes one query at a time.
///
/// # Errors
///
/// [`QueryError::StackTooSmall`] from [`RayQuery::closest_hit`] on the caller's stack.
#[inline(never)]
pub fn closest_in<T, N, I>(
    isect: &T,
    bvh: &Bvh<N, I>,
    mesh: &TriangleMesh<'_>,
    stack: &mut [StackEntry],
    ray: &Ray,
) -> Result<Option<(u32, TriangleHit)>, QueryError>
where
    T: TriangleIntersector,
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    bvh.closest_hit(
        ray,
        &mut Triangles::new(mesh, isect),
        &mut Query::new().stack(stack),
    )
}

/// One any-hit query on the caller's traversal `stack`, out of line (see [`closest_in`]).
///
/// # Errors
///
/// [`QueryError::StackTooSmall`] from [`RayQuery::any_hit`] on the caller's stack.
#[inline(never)]
pub fn any_in<T, N, I>(
    isect: &T,
    bvh: &Bvh<N, I>,
    mesh: &TriangleMesh<'_>,
    stack: &mut [StackEntry],
    ray: &Ray,
) -> Result<bool, QueryError>
where
    T: TriangleIntersector,
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    Ok(bvh
        .any_hit(
            ray,
            &mut Triangles::new(mesh, isect),
            &mut Query::new().stack(stack),
        )?
        .is_some())
}
