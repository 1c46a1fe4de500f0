//! The two ray queries of a [`RayQuery`](super::RayQuery) implementation, written once:
//! [`ray_queries`] writes `closest_hit` and `any_hit` over one walk that takes `any`, and
//! [`ClosureWalk::leaf_query`] is that walk for the structures that call a closure per
//! primitive.

use super::walk::test_run;
use super::{LeafTest, Query, Stack, TraversalStats};
use crate::ray::Ray;
use crate::simd_level::SimdLevel;

/// A primitive test of a [`ClosureWalk`]: `intersect(prim, ray)` is the primitive's hit
/// distance along `ray` and its hit, if any.
pub(crate) trait PrimTest<H>: FnMut(u32, &Ray) -> Option<(f32, H)> {}

impl<H, F: FnMut(u32, &Ray) -> Option<(f32, H)>> PrimTest<H> for F {}

/// The state of one closest-hit (or any-hit) walk of a [`ClosureWalk`] structure: the ray
/// shrunk to the closest hit so far, that hit, the primitive test and the walk's counters.
pub(crate) struct Search<F, H> {
    /// The query ray, `t_max` shrunk to the closest hit taken so far.
    pub(crate) cur: Ray,
    /// The closest hit so far under the tie rule: `(primitive, hit)`.
    pub(crate) best: Option<(u32, H)>,
    /// Any hit: the walk ends at the first hit taken.
    any: bool,
    /// `intersect(prim, cur)`: the primitive's hit distance and hit, if any.
    intersect: F,
    /// Nodes or cells visited (counted by the walk) and primitives tested (by [`Search::test`]).
    pub(crate) stats: TraversalStats,
}

impl<F: PrimTest<H>, H> Search<F, H> {
    /// Tests the primitives of `run` in order ([`test_run`]); `true` when an any-hit query is
    /// done.
    #[inline(always)]
    pub(crate) fn test(&mut self, run: &[u32]) -> bool {
        let tested = &mut self.stats.primitives_tested;
        test_run(
            run,
            &mut self.intersect,
            &mut self.cur,
            &mut self.best,
            tested,
            self.any,
        )
    }
}

/// A structure whose walk calls a closure per primitive and keeps its traversal state in its
/// own frame, ignoring the context's stack (the grid, the kd-tree): its two ray queries are
/// [`ClosureWalk::leaf_query`].
pub(crate) trait ClosureWalk {
    /// Walks `ray` (equal to `s.cur` on entry) through the structure, testing the primitives of
    /// each node or cell it visits with [`Search::test`] until the walk's end rule or the
    /// any-hit query stops it; counts the nodes or cells visited in `s.stats`.
    fn traverse<F: PrimTest<H>, H>(&self, ray: &Ray, s: &mut Search<F, H>);

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
        let mut s = Search {
            cur: *ray,
            best: None,
            any,
            intersect: |p, r: &Ray| leaf.intersect(&pre, p, r),
            stats: TraversalStats::default(),
        };
        self.traverse(ray, &mut s);
        if let Some(out) = ctx.stats.as_deref_mut() {
            out.add(&s.stats);
        }
        S::answer(Ok(s.best))
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
