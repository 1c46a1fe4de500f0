//! Closest-hit and any-hit traversal of a wide tree on a fixed-size stack.

use super::node::{ChildRef, LEAF_BIT, LeafGroup, START_MASK, WideNode};
use super::{WideBvh, add_stats};
use crate::aabb::SlabRay;
use crate::bvh::padded_ray::PaddedRay;
use crate::bvh::stats::TraversalStats;
use crate::bvh::{cull_bound, projection_pad, take_if_better};
use crate::hit_queries::closest_and_any;
use crate::ray::Ray;
use crate::simd;
use crate::simd::level::{Portable, SimdLevel, order_key};
use crate::triangle::{LANES, TriangleHit, TriangleIntersector, TriangleLanes, pair_mask};
use glam::Vec3;

/// Stack entries of the traversal: [`super::stack_size`] of the widest supported tree
/// (`W = 8`), which bounds every narrower one (module docs of [`super`]).
const STACK: usize = super::stack_size(8);

/// The groups holding leaf slots `start .. start + count` (`count ≥ 1`); an empty slice for
/// a run out of range.
#[inline(always)]
fn leaf_groups(groups: &[LeafGroup], start: u32, count: u32) -> &[LeafGroup] {
    let (first, end) = (start as usize, start as usize + count as usize);
    groups
        .get(first / LANES..end.div_ceil(LANES))
        .unwrap_or(&[])
}

/// The lanes that hold leaf slots `start .. start + count` in each group of their run
/// ([`leaf_groups`]), group after group: the first group's from lane `start % LANES`, the
/// last group's up to the run's end.
#[derive(Clone, Copy, Debug)]
pub(super) struct RunLanes {
    /// Lanes of the next group from the run's start on (all after the first group).
    from: u32,
    /// Lanes from the next group's lane 0 to the run's end.
    left: u32,
}

impl RunLanes {
    /// The run of `count` slots from slot `start`.
    #[inline(always)]
    pub(super) fn new(start: u32, count: u32) -> Self {
        let lane = start % LANES as u32;
        Self {
            from: (0xF << lane) & 0xF,
            left: lane.saturating_add(count),
        }
    }

    /// The lanes of the run in the next group.
    #[inline(always)]
    pub(super) fn next_group(&mut self) -> u32 {
        let lanes = self.from & ((1u32 << self.left.min(LANES as u32)) - 1);
        self.from = 0xF;
        self.left = self.left.saturating_sub(LANES as u32);
        lanes
    }
}

/// Hints that the memory of `child` (its node, or its leaf's first triangle group) is read
/// soon. Only addresses are computed, without a bounds check or a decode: a hint never
/// faults, so an address past the end is harmless.
#[inline(always)]
fn prefetch_child<const W: usize>(nodes: &[WideNode<W>], groups: &[LeafGroup], child: u32) {
    if child & LEAF_BIT == 0 {
        simd::lines(nodes.as_ptr().wrapping_add(child as usize));
    } else {
        let start = (child & START_MASK) as usize;
        simd::lines(groups.as_ptr().wrapping_add(start / LANES));
    }
}

/// The [`order_key`]s of the lanes of `dist`, the hit lanes `hits` first, ascending: by
/// `level`'s eight-lane sort for `W = 8` when it has one, otherwise sorted here (the same
/// result: the keys of hit lanes are distinct).
#[inline(always)]
fn sorted_keys<const W: usize, L: SimdLevel>(level: L, dist: &[f32; W], hits: u32) -> [u32; W] {
    const { assert!(W <= 8, "slots must fit the keys' three low bits") };
    if let Ok(d8) = <&[f32; 8]>::try_from(&dist[..])
        && let Some(k) = level.sort_keys8(d8, hits)
    {
        return core::array::from_fn(|i| k[i & 7]);
    }
    let mut keys: [u32; W] = core::array::from_fn(|i| order_key(dist[i], i, (hits >> i) & 1 != 0));
    keys.sort_unstable();
    keys
}

/// What a leaf does with its triangles: the one-triangle test and the four-lane cull. A trait
/// with always-inlined methods rather than closures, so that the test is compiled into the
/// traversal loop (a called closure returns its hit through memory).
trait LeafTest<H> {
    /// `(t, payload)` of a hit of triangle `prim` (vertices `v`) in `ray`'s interval, with the
    /// kernels of SIMD `level` where the test has them (the same answer at every level).
    fn intersect<L: SimdLevel>(
        &mut self,
        level: L,
        prim: u32,
        v: &[Vec3; 3],
        ray: &Ray,
    ) -> Option<(f32, H)>;
    /// The lanes certainly missed ([`TriangleIntersector::certain_misses`]).
    fn cull(&self, lanes: &TriangleLanes, ray: &Ray) -> u32;
    /// The lanes of two groups certainly missed, `first`'s in bits 0–3 and `second`'s in
    /// bits 4–7 ([`TriangleIntersector::certain_misses2`]).
    fn cull2<L: SimdLevel>(
        &self,
        level: L,
        first: &TriangleLanes,
        second: &TriangleLanes,
        ray: &Ray,
    ) -> u32;
}

/// The closure-based queries: every triangle goes to the closure.
struct ClosureTest<F>(F);

impl<H, F: FnMut(u32, &[Vec3; 3], &Ray) -> Option<(f32, H)>> LeafTest<H> for ClosureTest<F> {
    #[inline(always)]
    fn intersect<L: SimdLevel>(
        &mut self,
        _: L,
        prim: u32,
        v: &[Vec3; 3],
        ray: &Ray,
    ) -> Option<(f32, H)> {
        (self.0)(prim, v, ray)
    }

    #[inline(always)]
    fn cull(&self, _: &TriangleLanes, _: &Ray) -> u32 {
        0
    }

    #[inline(always)]
    fn cull2<L: SimdLevel>(&self, _: L, _: &TriangleLanes, _: &TriangleLanes, _: &Ray) -> u32 {
        0
    }
}

/// The intersector-based queries: `isect` with the ray prepared once, when the walk reaches
/// its first leaf (most camera rays reach none and never pay for the preparation).
struct PreparedTest<'a, I: TriangleIntersector> {
    isect: &'a I,
    pre: I::Prepared,
}

impl<'a, I: TriangleIntersector> PreparedTest<'a, I> {
    /// The factory [`WideBvh::traverse`] calls at the first leaf, for a ray it has checked
    /// ([`TriangleIntersector::prepare_valid`]): `None` when `isect` refuses the ray.
    #[inline(always)]
    fn of(isect: &'a I) -> impl FnOnce(&Ray) -> Option<Self> {
        move |ray| {
            Some(Self {
                isect,
                pre: isect.prepare_valid(ray)?,
            })
        }
    }
}

impl<I: TriangleIntersector> LeafTest<TriangleHit> for PreparedTest<'_, I> {
    #[inline(always)]
    fn intersect<L: SimdLevel>(
        &mut self,
        level: L,
        _: u32,
        v: &[Vec3; 3],
        ray: &Ray,
    ) -> Option<(f32, TriangleHit)> {
        let hit = self.isect.intersect_prepared_on(level, &self.pre, ray, v)?;
        Some((hit.t, hit))
    }

    #[inline(always)]
    fn cull(&self, lanes: &TriangleLanes, ray: &Ray) -> u32 {
        self.isect.certain_misses(&self.pre, ray, lanes)
    }

    #[inline(always)]
    fn cull2<L: SimdLevel>(
        &self,
        level: L,
        first: &TriangleLanes,
        second: &TriangleLanes,
        ray: &Ray,
    ) -> u32 {
        self.isect
            .certain_misses2(level, &self.pre, ray, first, second)
    }
}

/// One stack entry: a child reference still to visit and the distance at which the ray enters
/// its box.
#[derive(Clone, Copy, Debug)]
struct Entry {
    child: u32,
    t_enter: f32,
}

/// The traversal stack of a wide tree: `7·MAX_DEPTH + 1` entries of 8 bytes (3.5 KiB), enough for
/// any tree up to 8 wide (module docs of [`super`]). Creating one means writing all of it, so
/// a caller tracing many rays keeps one and passes it to the `_with` and `_on` queries; the plain
/// queries make a fresh one per ray. Its contents between queries mean nothing.
#[derive(Clone, Debug)]
pub struct WideStack {
    entries: [Entry; STACK],
}

impl WideStack {
    /// A stack for any wide tree.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            entries: [Entry {
                child: 0,
                t_enter: 0.0,
            }; STACK],
        }
    }
}

impl Default for WideStack {
    fn default() -> Self {
        Self::new()
    }
}

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]>,
    T: AsRef<[LeafGroup]>,
{
    closest_and_any! {
        /// The closest hit of `ray`, as `(triangle index in the mesh, intersect's payload)`.
        ///
        /// `intersect(prim, vertices, ray)` tests one triangle against `ray`, whose `t_max` is
        /// the current closest `t` (inclusive), and returns `(t, payload)` for a hit in
        /// `(t_min, t_max]`. Of equal `t`, the smaller triangle index wins, so the result equals
        /// a brute-force loop with the same rule. `stats`, when given, is **added to**. An
        /// invalid ray returns `None` without testing any node. Makes a fresh [`WideStack`];
        /// see [`WideBvh::closest_hit_with`] for many rays.
        #[inline]
        fn closest_hit;
        /// Any hit of `ray`: traversal stops at the first triangle for which `intersect`
        /// reports a `t` in `(t_min, t_max]`. Which one is found first depends on the tree;
        /// hit/miss does not.
        #[inline]
        fn any_hit;
        <H>(
            &self,
            ray: &Ray,
            intersect: impl FnMut(u32, &[Vec3; 3], &Ray) -> Option<(f32, H)>,
            stats: Option<&mut TraversalStats>,
        ) -> Option<(u32, H)>, const ANY => {
            let leaf = |_: &Ray| Some(ClosureTest(intersect));
            self.traverse::<H, ANY, _, _>(Portable, &mut WideStack::new(), ray, leaf, stats)
        }
    }

    closest_and_any! {
        /// [`WideBvh::closest_hit`] on a stack the caller keeps across rays.
        #[inline(always)]
        fn closest_hit_with;
        /// [`WideBvh::any_hit`] on a stack the caller keeps across rays.
        #[inline(always)]
        fn any_hit_with;
        <H>(
            &self,
            stack: &mut WideStack,
            ray: &Ray,
            intersect: impl FnMut(u32, &[Vec3; 3], &Ray) -> Option<(f32, H)>,
            stats: Option<&mut TraversalStats>,
        ) -> Option<(u32, H)>, const ANY => {
            let leaf = |_: &Ray| Some(ClosureTest(intersect));
            self.traverse::<H, ANY, _, _>(Portable, stack, ray, leaf, stats)
        }
    }

    closest_and_any! {
        /// [`WideBvh::closest_hit`] with the intersector `isect` (prepared once per ray).
        #[inline]
        fn closest_hit_triangles;
        /// [`WideBvh::any_hit`] with the intersector `isect`.
        #[inline]
        fn any_hit_triangles;
        <I: TriangleIntersector>(
            &self,
            isect: &I,
            ray: &Ray,
            stats: Option<&mut TraversalStats>,
        ) -> Option<(u32, TriangleHit)>, const ANY => {
            let (level, stack, leaf) = (Portable, &mut WideStack::new(), PreparedTest::of(isect));
            self.traverse::<TriangleHit, ANY, _, _>(level, stack, ray, leaf, stats)
        }
    }

    closest_and_any! {
        /// [`WideBvh::closest_hit_triangles`] on a stack the caller keeps across rays, with the
        /// node test at SIMD `level` (see [`crate::simd_level`]; [`Portable`] is the scalar
        /// one): the same answer and statistics at every level.
        #[inline(always)]
        fn closest_hit_triangles_on;
        /// [`WideBvh::any_hit_triangles`] on the caller's stack with the node test at SIMD
        /// `level`.
        #[inline(always)]
        fn any_hit_triangles_on;
        <I: TriangleIntersector, L: SimdLevel>(
            &self,
            level: L,
            stack: &mut WideStack,
            isect: &I,
            ray: &Ray,
            stats: Option<&mut TraversalStats>,
        ) -> Option<(u32, TriangleHit)>, const ANY => {
            let leaf = PreparedTest::of(isect);
            self.traverse::<TriangleHit, ANY, L, _>(level, stack, ray, leaf, stats)
        }
    }

    /// Checks `ray`, then walks the tree; `leaf` makes the leaf test from the ray when the
    /// walk reaches its first leaf (`None`: the test refuses the ray, which then hits
    /// nothing), so that rays that reach no leaf never pay for it.
    #[inline(always)]
    fn traverse<H, const ANY: bool, L: SimdLevel, LT: LeafTest<H>>(
        &self,
        level: L,
        stack: &mut WideStack,
        ray: &Ray,
        leaf: impl FnOnce(&Ray) -> Option<LT>,
        stats: Option<&mut TraversalStats>,
    ) -> Option<(u32, H)> {
        let slab = SlabRay::new(ray)?;
        if slab.divide || ray.t_min < 0.0 {
            self.walk::<H, ANY, true, L, LT>(level, &mut stack.entries, ray, &slab, leaf, stats)
        } else {
            self.walk::<H, ANY, false, L, LT>(level, &mut stack.entries, ray, &slab, leaf, stats)
        }
    }

    /// Orders the children hit by a node (`first` and the lanes of `rest`, a non-empty lane
    /// mask) nearest first, leaves all but the nearest on the stack (farthest deepest) and
    /// returns the nearest. Of equal entry distances the earlier slot is visited first (for
    /// three or more, distances within the low bits [`order_key`] drops may be ordered by
    /// slot: the visiting order only). Prefetches every child left on the stack (the nearest
    /// is read at once: a hint would not get ahead of the loads). At most `W − 1` entries are
    /// pushed, counted in the bound of [`super::stack_size`].
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn order_hits<L: SimdLevel>(
        &self,
        level: L,
        node: &WideNode<W>,
        dist: &[f32; W],
        hits: u32,
        first: Entry,
        stack: &mut [Entry; STACK],
        sp: &mut usize,
        (nodes, groups): (&[WideNode<W>], &[LeafGroup]),
    ) -> u32 {
        let entry = |i: usize| Entry {
            child: node.child[i & (W - 1)],
            t_enter: dist[i & (W - 1)],
        };
        // `first` is the lowest lane of `hits`.
        let mut rest = hits & (hits - 1);
        let second = entry(rest.trailing_zeros() as usize);
        rest &= rest - 1;
        if rest == 0 {
            // Two children: one compare (ties: the earlier slot, `first`, is visited first).
            let (visit, later) = if second.t_enter < first.t_enter {
                (second, first)
            } else {
                (first, second)
            };
            prefetch_child(nodes, groups, later.child);
            if let Some(slot) = stack.get_mut(*sp) {
                *slot = later;
                *sp += 1;
            }
            return visit.child;
        }
        // Three or more: sorted by key, branch-free on the AVX2 level; the others pushed
        // farthest first, so that the second nearest is on top.
        let keys = sorted_keys(level, dist, hits);
        let count = hits.count_ones() as usize;
        for &k in keys.get(1..count).unwrap_or(&[]).iter().rev() {
            let e = entry((k & 7) as usize);
            if let Some(slot) = stack.get_mut(*sp) {
                *slot = e;
                *sp += 1;
            }
            prefetch_child(nodes, groups, e.child);
        }
        node.child[(keys[0] & 7) as usize & (W - 1)]
    }

    /// The node step of the walk: tests the children of node `index` over
    /// `[t_min, bound]` (`bound`: [`cull_bound`] of the current `t_max`), pushes all hit ones
    /// but the nearest ([`WideBvh::order_hits`]) and returns the nearest; `None` when no child
    /// is hit (or `index` is out of range).
    #[inline(always)]
    fn descend<const GENERAL: bool, L: SimdLevel>(
        &self,
        (level, wray, (nodes, groups)): (L, &PaddedRay, (&[WideNode<W>], &[LeafGroup])),
        index: u32,
        (t_min, bound): (f32, f32),
        (stack, sp, local): (&mut [Entry; STACK], &mut usize, &mut TraversalStats),
    ) -> Option<u32> {
        let node = nodes.get(index as usize)?;
        local.nodes_visited += 1;
        let (dist, mut mask) = wray.hit_children::<W, GENERAL, L>(level, node, t_min, bound);
        if mask == 0 {
            return None;
        }
        // `W` is a power of two: `& (W − 1)` keeps every lane index in range without a check.
        let hits = mask;
        let first = mask.trailing_zeros() as usize & (W - 1);
        mask &= mask - 1;
        let near = Entry {
            child: node.child[first],
            t_enter: dist[first],
        };
        Some(if mask == 0 {
            // One child hit (the common case): nothing to order or push.
            near.child
        } else {
            self.order_hits(level, node, &dist, hits, near, stack, sp, (nodes, groups))
        })
    }

    /// Pops the next entry still within `bound` (entries beyond it are dropped); `None` when
    /// the stack is empty.
    #[inline(always)]
    fn pop(stack: &[Entry; STACK], sp: &mut usize, bound: f32) -> Option<u32> {
        loop {
            *sp = sp.checked_sub(1)?;
            let e = stack.get(*sp)?;
            if e.t_enter <= bound {
                return Some(e.child);
            }
        }
    }

    #[inline(always)]
    fn walk<H, const ANY: bool, const GENERAL: bool, L: SimdLevel, LT: LeafTest<H>>(
        &self,
        level: L,
        stack: &mut [Entry; STACK],
        ray: &Ray,
        slab: &SlabRay,
        make_leaf: impl FnOnce(&Ray) -> Option<LT>,
        stats: Option<&mut TraversalStats>,
    ) -> Option<(u32, H)> {
        let tree = (self.nodes(), self.groups());
        let groups = tree.1;
        if tree.0.is_empty() {
            return None;
        }
        let wray = PaddedRay::new(slab, projection_pad(slab.origin, self.extent));
        let mut local = TraversalStats::default();
        let mut cur = *ray;
        let mut best: Option<(u32, H)> = None;
        let mut sp = 0usize;
        // The root is node 0 (its own box is the union of its children's: not tested).
        let mut next = 0u32;
        // Down to the first leaf, nodes only (the interval cannot shrink before a leaf).
        let mut bound = cull_bound(cur.t_max);
        loop {
            let down = match ChildRef::decode(next) {
                ChildRef::Inner(index) => self.descend::<GENERAL, L>(
                    (level, &wray, tree),
                    index,
                    (cur.t_min, bound),
                    (stack, &mut sp, &mut local),
                ),
                ChildRef::Leaf { .. } => break,
                ChildRef::Empty => None,
            };
            match down.or_else(|| Self::pop(stack, &mut sp, bound)) {
                Some(child) => next = child,
                None => {
                    add_stats(stats, &local);
                    return None;
                }
            }
        }
        let Some(mut leaf) = make_leaf(ray) else {
            add_stats(stats, &local);
            return None;
        };
        'walk: loop {
            match ChildRef::decode(next) {
                ChildRef::Inner(index) => {
                    if let Some(child) = self.descend::<GENERAL, L>(
                        (level, &wray, tree),
                        index,
                        (cur.t_min, bound),
                        (stack, &mut sp, &mut local),
                    ) {
                        next = child;
                        continue;
                    }
                }
                ChildRef::Leaf { start, count } => {
                    local.primitives_tested += u64::from(count);
                    // Eight triangles at a time (two groups), straight from their groups: the
                    // lanes the intersector certainly misses are skipped, the others tested one
                    // by one in leaf order. The cull does not depend on the interval, so a hit
                    // in the first group leaves the second's cull valid.
                    let mut rest = leaf_groups(groups, start, count);
                    let mut lanes = RunLanes::new(start, count);
                    while let Some((first, tail)) = rest.split_first() {
                        let (pair, mut todo) = match tail.split_first() {
                            Some((second, after)) => {
                                rest = after;
                                let run = pair_mask(lanes.next_group(), lanes.next_group());
                                let missed = leaf.cull2(level, &first.lanes, &second.lanes, &cur);
                                ([first, second], run & !missed)
                            }
                            None => {
                                rest = tail;
                                let missed = leaf.cull(&first.lanes, &cur);
                                ([first, first], lanes.next_group() & !missed)
                            }
                        };
                        while todo != 0 {
                            let bit = todo.trailing_zeros() as usize;
                            todo &= todo - 1;
                            let group = pair[(bit / LANES) & 1];
                            let Some(tri) = group.triangle(bit & (LANES - 1)) else {
                                break;
                            };
                            let prim = tri.prim;
                            let Some((t, h)) = leaf.intersect(level, prim, &tri.vertices(), &cur)
                            else {
                                continue;
                            };
                            if take_if_better(&mut cur, &mut best, prim, t, h) {
                                bound = cull_bound(t);
                                if ANY {
                                    break 'walk;
                                }
                            }
                        }
                    }
                }
                ChildRef::Empty => {}
            }
            // The next entry still within the (shrunk) interval.
            match Self::pop(stack, &mut sp, bound) {
                Some(child) => next = child,
                None => break,
            }
        }
        add_stats(stats, &local);
        best
    }
}
