//! The two ray queries of a [`RayQuery`](super::RayQuery) implementation, written once:
//! [`ray_queries`] writes `closest_hit` and `any_hit` over one walk that takes `any`, and
//! [`ClosureWalk::leaf_query`] is that walk for the structures that call a closure per
//! primitive.

use super::{LeafTest, Query, Stack, TraversalStats};
use crate::ray::Ray;
use crate::simd_level::SimdLevel;

/// A structure whose walk calls a closure per primitive and keeps its traversal state in its
/// own frame, ignoring the context's stack (the grid, the kd-tree): its two ray queries are
/// [`ClosureWalk::leaf_query`].
pub(crate) trait ClosureWalk {
    /// Closest hit, or any hit when `any`, of `ray` by `intersect(prim, ray shrunk to the
    /// closest hit so far)` under the tie rule; counters added to `stats`.
    fn traverse<H>(
        &self,
        ray: &Ray,
        intersect: impl FnMut(u32, &Ray) -> Option<(f32, H)>,
        stats: Option<&mut TraversalStats>,
        any: bool,
    ) -> Option<(u32, H)>;

    /// Both ray queries: the leaf test prepared once per ray (a refused ray tests nothing),
    /// then [`ClosureWalk::traverse`] with the context's statistics.
    #[inline]
    fn leaf_query<T: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        any: bool,
        ray: &Ray,
        leaf: &mut T,
        ctx: &mut Query<'_, L, S>,
    ) -> S::Out<(u32, T::Hit)> {
        let Some(pre) = leaf.prepare(ray) else {
            return S::answer(Ok(None));
        };
        let stats = ctx.stats.as_deref_mut();
        S::answer(Ok(self.traverse(
            ray,
            |p, r| leaf.intersect(&pre, p, r),
            stats,
            any,
        )))
    }
}

/// Writes the two ray queries of a [`RayQuery`](super::RayQuery) implementation as
/// `self.$query(any, ray, leaf, ctx)`: `closest_hit` with `any = false`, `any_hit` with
/// `true`, each with the given attributes (`#[inline]`, ...). For structures whose two queries
/// share one walk; `$query` returns `S::Out<(u32, T::Hit)>`.
macro_rules! ray_queries {
    ($(#[$attr:meta])* $query:ident) => {
        $crate::query::forward::ray_queries!(@one closest_hit false $(#[$attr])* $query);
        $crate::query::forward::ray_queries!(@one any_hit true $(#[$attr])* $query);
    };
    (@one $name:ident $any:literal $(#[$attr:meta])* $query:ident) => {
        $(#[$attr])*
        fn $name<
            T: $crate::query::LeafTest,
            L: $crate::simd_level::SimdLevel,
            S: $crate::query::Stack,
        >(
            &self,
            ray: &$crate::ray::Ray,
            leaf: &mut T,
            ctx: &mut $crate::query::Query<'_, L, S>,
        ) -> S::Out<(u32, T::Hit)> {
            self.$query($any, ray, leaf, ctx)
        }
    };
}
pub(crate) use ray_queries;
