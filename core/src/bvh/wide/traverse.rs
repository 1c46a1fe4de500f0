//! Closest-hit and any-hit traversal of a wide tree on a fixed-size stack.

use super::node::{ChildRef, LEAF_BIT, LeafGroup, START_MASK, WideNode};
use super::{WideBvh, add_stats};
use crate::aabb::SlabRay;
use crate::bvh::padded_ray::PaddedRay;
use crate::query::QueryError;
use crate::query::walk::{cull_bound, take_if_better};
use crate::query::{LeafTest, Query, QueryStack, Stack, StackEntry, TraversalStats};
use crate::ray::Ray;
use crate::sealed::Inside;
use crate::simd;
use crate::simd::level::{SimdLevel, order_key};
use crate::triangle::LANES;

/// Stack entries of the traversal: [`super::stack_size`] of the widest supported tree
/// (`W = 8`), which bounds every narrower one (module docs of [`super`]).
pub(super) const STACK: usize = crate::query::QUERY_STACK_SIZE;

/// The groups holding leaf slots `start .. start + count` (`count ≥ 1`); an empty slice for
/// a run out of range. Counted from the first group (`⌈(start mod LANES + count) / LANES⌉`
/// of them, the same groups as `⌊start / LANES⌋ .. ⌈(start + count) / LANES⌉`), so that the
/// only check left is the run's end against the slice.
#[inline(always)]
pub(super) fn leaf_groups(groups: &[LeafGroup], start: u32, count: u32) -> &[LeafGroup] {
    let first = start as usize / LANES;
    let n = (start as usize % LANES + count as usize).div_ceil(LANES);
    groups.get(first..first + n).unwrap_or(&[])
}

/// The lanes that hold leaf slots `start .. start + count` in each group of their run
/// ([`leaf_groups`]), group after group: the first group's from lane `start % LANES`, the
/// last group's up to the run's end. One bit per lane of the run's groups, lane 0 of its
/// first group in bit 0 (a run of at most [`super::MAX_LEAF_TRIANGLES`] slots spans at most
/// 19 lanes; longer runs, which no leaf holds, are cut at 61), taken four or eight bits at a
/// time: two instructions per group, not a mask rebuilt from the run's bounds.
#[derive(Clone, Copy, Debug)]
pub(super) struct RunLanes(u64);

impl RunLanes {
    /// The run of `count` slots from slot `start`.
    #[inline(always)]
    pub(super) fn new(start: u32, count: u32) -> Self {
        Self(((1u64 << count.min(61)) - 1) << (start % LANES as u32))
    }

    /// The lanes of the run in the next group.
    #[inline(always)]
    pub(super) fn next_group(&mut self) -> u32 {
        let lanes = (self.0 & 0xF) as u32;
        self.0 >>= LANES;
        lanes
    }

    /// The run's slots in its first eight groups, bit `4g + i` for lane `i` of group `g`
    /// (the groups [`leaf_groups`] returns).
    #[inline(always)]
    pub(super) fn first_slots(&self) -> u32 {
        self.0 as u32
    }

    /// The lanes of the run in the next two groups: the first's in bits 0–3, the second's in
    /// bits 4–7 (as [`crate::triangle::pair_mask`] of two [`RunLanes::next_group`]s).
    #[inline(always)]
    pub(super) fn next_pair(&mut self) -> u32 {
        let lanes = (self.0 & 0xFF) as u32;
        self.0 >>= 2 * LANES;
        lanes
    }
}

/// The leaf test of one ray over the triangle groups `run` of a leaf (`lanes` its slots),
/// eight triangles at a time (two groups) straight from their groups: the lanes the test
/// certainly misses skipped, the others tested one by one in leaf order, each hit offered to
/// the search ([`take_if_better`], which shrinks `cur.t_max`). The cull does not depend on the
/// interval, so a hit in the first group leaves the second's cull valid. Returns `true` when a
/// hit was taken (with `ANY`, at the first one, the rest untested). With `ANY` and `behind`,
/// the kept lanes whose plane the line certainly crosses behind the origin are dropped first
/// ([`LeafTest::behind_misses`]); without `behind` the exact test refuses them (the caller
/// passes `false` where no such lane is likely: a leaf whose box the ray enters after its
/// origin). The answer is the same either way.
#[inline(always)]
pub(super) fn leaf_hits<LT: LeafTest, L: SimdLevel, const ANY: bool>(
    level: L,
    leaf: &mut LT,
    pre: &LT::Prepared,
    (mut run, mut lanes, behind): (&[LeafGroup], RunLanes, bool),
    (cur, best): (&mut Ray, &mut Option<(u32, LT::Hit)>),
) -> bool {
    let mut taken = false;
    while let Some((first, tail)) = run.split_first() {
        let (pair, mut todo) = match tail.split_first() {
            Some((second, after)) => {
                run = after;
                let run_lanes = lanes.next_pair();
                let missed = leaf.certain_misses(
                    Inside(()),
                    level,
                    pre,
                    cur,
                    &first.lanes,
                    Some(&second.lanes),
                );
                ([first, second], run_lanes & !missed)
            }
            None => {
                run = tail;
                let missed = leaf.certain_misses(Inside(()), level, pre, cur, &first.lanes, None);
                ([first, first], lanes.next_group() & !missed)
            }
        };
        if ANY && behind && todo != 0 {
            todo &= !leaf.behind_misses(
                Inside(()),
                level,
                pre,
                cur,
                [&pair[0].lanes, &pair[1].lanes],
                todo,
            );
        }
        if kept_hits::<LT, L, ANY>(level, leaf, pre, pair, todo, (&mut *cur, &mut *best)) {
            if ANY {
                return true;
            }
            taken = true;
        }
    }
    taken
}

/// The exact test of the lanes `todo` of two groups (`pair`; bit `i < 4` for lane `i` of the
/// first, bit `4 + i` for lane `i` of the second), the lanes the culls kept, one by one in
/// lane order, each hit offered to the search ([`take_if_better`], which shrinks
/// `cur.t_max`). Returns `true` when a hit was taken (with `ANY`, at the first one, the rest
/// untested).
#[inline(always)]
pub(super) fn kept_hits<LT: LeafTest, L: SimdLevel, const ANY: bool>(
    level: L,
    leaf: &mut LT,
    pre: &LT::Prepared,
    pair: [&LeafGroup; 2],
    mut todo: u32,
    (cur, best): (&mut Ray, &mut Option<(u32, LT::Hit)>),
) -> bool {
    let mut taken = false;
    while todo != 0 {
        let bit = todo.trailing_zeros() as usize;
        todo &= todo - 1;
        let group = pair[(bit / LANES) & 1];
        let Some(tri) = group.triangle(bit & (LANES - 1)) else {
            break;
        };
        let prim = tri.prim;
        if let Some((t, h)) =
            leaf.intersect_triangle(Inside(()), level, pre, prim, &tri.vertices(), cur)
            && take_if_better(cur, best, prim, t, h)
        {
            if ANY {
                return true;
            }
            taken = true;
        }
    }
    taken
}

/// Whether a walk that has entered `local.nodes_visited` inner nodes (the current one
/// counted) has entered more than `nodes` holds. A walk of a tree enters each node at most
/// once and finds every inner child stored after its parent, so neither check below fires
/// unless the nodes are no tree (storage whose `AsRef` gave other nodes after the build,
/// [`WideBvh`]'s docs). Then the walk still ends, however the nodes point (a child that is its
/// own parent, shared subtrees of about 10¹² paths): a node with one hit child steps only to a
/// later node (at most `nodes.len()` such steps in a row), and past this count a node with
/// several hit children pushes nothing and is left as a miss, so that at most the
/// [`STACK`] entries then on the stack are popped, each followed by at most `nodes.len()`
/// steps: at most `(STACK + 2)·nodes.len()` node steps in all. The checks sit where the walk
/// holds their values anyway (the single child's reference, the sort's path).
#[inline(always)]
pub(super) fn entered_all<const W: usize>(local: &TraversalStats, nodes: &[WideNode<W>]) -> bool {
    local.nodes_visited > nodes.len() as u64
}

/// Hints that the memory of `child` (its node, or its leaf's first triangle group) is read
/// soon. Only addresses are computed, without a bounds check or a decode: a hint never
/// faults, so an address past the end is harmless.
#[inline(always)]
pub(super) fn prefetch_child<const W: usize>(
    nodes: &[WideNode<W>],
    groups: &[LeafGroup],
    child: u32,
) {
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
pub(super) fn sorted_keys<const W: usize, L: SimdLevel>(
    level: L,
    dist: &[f32; W],
    hits: u32,
) -> [u32; W] {
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

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]>,
    T: AsRef<[LeafGroup]>,
{
    /// Entries of a caller's traversal stack ([`crate::query::Query::stack`]) this tree's
    /// queries need: none for a tree with no node (its root a leaf, or empty: the walk pushes
    /// nothing), else [`crate::query::QUERY_STACK_SIZE`] whatever `W` and the tree (the walk
    /// runs on a fixed array of that many entries, so that no push is checked). A shorter
    /// caller stack refuses every query of a tree with nodes, whatever the ray, with
    /// [`QueryError::StackTooSmall`]; one at least this long never makes a query fail.
    #[must_use]
    pub fn stack_depth(&self) -> usize {
        match ChildRef::decode(self.root) {
            ChildRef::Leaf { .. } | ChildRef::Empty => 0,
            _ => STACK,
        }
    }

    /// Both ray queries on the context's stack (a [`QueryStack`]'s worth of its entries, or a
    /// stack of this frame's own); a shorter caller stack is refused with
    /// [`QueryError::StackTooSmall`] unless the tree has no node ([`WideBvh::stack_depth`]).
    #[inline(always)]
    pub(super) fn leaf_query<LT: LeafTest, const ANY: bool, L: SimdLevel, S: Stack>(
        &self,
        ray: &Ray,
        leaf: &mut LT,
        ctx: &mut Query<'_, L, S>,
    ) -> Result<Option<(u32, LT::Hit)>, QueryError> {
        let level = ctx.level;
        let stats = ctx.stats.as_deref_mut();
        let mut best = None;
        match ctx.stack.entries() {
            None => {
                let stack = &mut QueryStack::new().entries;
                self.traverse::<LT, ANY, L>(level, stack, ray, leaf, stats, &mut best);
            }
            Some(entries) => {
                let available = entries.len();
                match entries
                    .get_mut(..STACK)
                    .and_then(|e| <&mut [StackEntry; STACK]>::try_from(e).ok())
                {
                    Some(stack) => {
                        self.traverse::<LT, ANY, L>(level, stack, ray, leaf, stats, &mut best);
                    }
                    // A tree with no node needs no entry: a root leaf's run is tested as
                    // `traverse` tests it, an empty tree hits nothing.
                    None => match ChildRef::decode(self.root) {
                        ChildRef::Leaf { start, count } => {
                            let run = (start, count);
                            self.root_leaf::<LT, ANY, L>(level, run, ray, leaf, stats, &mut best);
                        }
                        ChildRef::Empty => {}
                        _ => return Err(QueryError::StackTooSmall { available }),
                    },
                }
            }
        }
        Ok(best)
    }

    /// Checks `ray`, then walks the tree, the answer left in `best` (`None` on entry; it stays
    /// `None` for a refused ray); the leaf test is prepared when the walk reaches its first
    /// leaf (a refused ray then hits nothing), so that rays that reach no leaf never pay for
    /// it. One slot for the answer, written where the hit is taken: every exit of the walk
    /// leaves it there, with no answer value merged and copied at each return.
    #[inline(always)]
    fn traverse<LT: LeafTest, const ANY: bool, L: SimdLevel>(
        &self,
        level: L,
        stack: &mut [StackEntry; STACK],
        ray: &Ray,
        leaf: &mut LT,
        stats: Option<&mut TraversalStats>,
        best: &mut Option<(u32, LT::Hit)>,
    ) {
        if let ChildRef::Leaf { start, count } = ChildRef::decode(self.root) {
            self.root_leaf::<LT, ANY, L>(level, (start, count), ray, leaf, stats, best);
            return;
        }
        let Some(slab) = SlabRay::new(ray) else {
            return;
        };
        if slab.divide || ray.t_min < 0.0 {
            self.walk::<LT, ANY, true, L>(level, stack, ray, &slab, leaf, stats, best);
        } else {
            self.walk::<LT, ANY, false, L>(level, stack, ray, &slab, leaf, stats, best);
        }
    }

    /// The walk of a tree whose root is the leaf run `(start, count)` (a tree with no node):
    /// checks `ray`, prepares the leaf test and tests the run, the answer left in `best`,
    /// before any node-test setup (reciprocals, padding, the eight-lane broadcasts: about 225
    /// instructions per closest-hit ray and 50 per any-hit ray on the tetrahedron). No box is
    /// tested: a box test only culls rays that hit none of the run's triangles in their
    /// interval, which the leaf test rejects as well.
    #[inline(always)]
    fn root_leaf<LT: LeafTest, const ANY: bool, L: SimdLevel>(
        &self,
        level: L,
        (start, count): (u32, u32),
        ray: &Ray,
        leaf: &mut LT,
        stats: Option<&mut TraversalStats>,
        best: &mut Option<(u32, LT::Hit)>,
    ) {
        if !ray.is_valid() {
            return;
        }
        let Some(pre) = leaf.prepare_valid(ray) else {
            return;
        };
        let (run, lanes) = (
            leaf_groups(self.groups(), start, count),
            RunLanes::new(start, count),
        );
        let mut cur = *ray;
        leaf_hits::<LT, L, ANY>(level, leaf, &pre, (run, lanes, true), (&mut cur, best));
        let local = TraversalStats {
            primitives_tested: u64::from(count),
            ..TraversalStats::default()
        };
        add_stats(stats, &local);
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
    pub(super) fn order_hits<L: SimdLevel>(
        &self,
        level: L,
        node: &WideNode<W>,
        dist: &[f32; W],
        hits: u32,
        first: StackEntry,
        stack: &mut [StackEntry; STACK],
        sp: &mut usize,
        (nodes, groups): (&[WideNode<W>], &[LeafGroup]),
    ) -> u32 {
        let entry = |i: usize| StackEntry {
            node: node.child[i & (W - 1)],
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
            prefetch_child(nodes, groups, later.node);
            if let Some(slot) = stack.get_mut(*sp) {
                *slot = later;
                *sp += 1;
            }
            return visit.node;
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
            prefetch_child(nodes, groups, e.node);
        }
        node.child[(keys[0] & 7) as usize & (W - 1)]
    }

    /// The any-hit form of [`WideBvh::order_hits`]: of the children hit by a node (`hits`, at
    /// least two lanes; `dist` their entry distances) the farthest is returned (visited next)
    /// and the others pushed in slot order, without a sort. An any-hit walk stops at its first
    /// hit, so the order changes only the work, never whether a hit is found; its interval
    /// never shrinks, so [`WideBvh::pop_any`] drops no entry (the entry distances are kept,
    /// the returned child's in `enter`, for the leaf's crossed-behind cull: see
    /// [`leaf_hits`]). The farthest first: a ray leaving a surface (shadow, ambient
    /// occlusion) enters the boxes around its origin nearest, whose triangles rarely block
    /// it, and an occluder found first ends the walk before they are tested. Prefetches each
    /// child pushed. At most `W − 1` entries are pushed, as by `order_hits`.
    #[inline(always)]
    fn push_hits_any(
        node: &WideNode<W>,
        dist: &[f32; W],
        hits: u32,
        (stack, sp, enter): (&mut [StackEntry; STACK], &mut usize, &mut f32),
        (nodes, groups): (&[WideNode<W>], &[LeafGroup]),
    ) -> u32 {
        let mut far = hits.trailing_zeros() as usize & (W - 1);
        let mut rest = hits & (hits - 1);
        while rest != 0 {
            let i = rest.trailing_zeros() as usize & (W - 1);
            rest &= rest - 1;
            if dist[i] > dist[far] {
                far = i;
            }
        }
        let mut rest = hits & !(1 << far);
        while rest != 0 {
            let i = rest.trailing_zeros() as usize & (W - 1);
            rest &= rest - 1;
            let child = node.child[i];
            if let Some(slot) = stack.get_mut(*sp) {
                *slot = StackEntry {
                    node: child,
                    t_enter: dist[i],
                };
                *sp += 1;
            }
            prefetch_child(nodes, groups, child);
        }
        *enter = dist[far];
        node.child[far]
    }

    /// The node step of the walk: tests the children of node `index` over
    /// `[t_min, bound]` (`bound`: [`cull_bound`] of the current `t_max`), pushes all hit ones
    /// but the nearest ([`WideBvh::order_hits`]; for the any-hit walk, `ANY`, all but the
    /// farthest, the others in slot order: [`WideBvh::push_hits_any`]) and returns the one to
    /// visit next;
    /// `None` when no child is hit or `index` is out of range, and where the nodes are no tree
    /// ([`entered_all`]): a single hit child not stored after its parent, or several hit
    /// children once the walk has entered more nodes than `nodes` holds.
    #[inline(always)]
    fn descend<const ANY: bool, const GENERAL: bool, L: SimdLevel>(
        &self,
        (level, wray, (nodes, groups)): (L, &PaddedRay, (&[WideNode<W>], &[LeafGroup])),
        index: u32,
        (t_min, bound): (f32, f32),
        (stack, sp, local, enter): (
            &mut [StackEntry; STACK],
            &mut usize,
            &mut TraversalStats,
            &mut f32,
        ),
    ) -> Option<u32> {
        let node = nodes.get(index as usize)?;
        local.nodes_visited += 1;
        let (dist, mask) = wray.hit_children::<W, GENERAL, L>(level, node, t_min, bound);
        if mask == 0 {
            return None;
        }
        // `W` is a power of two: `& (W − 1)` keeps every lane index in range without a check.
        let first = mask.trailing_zeros() as usize & (W - 1);
        if mask & (mask - 1) == 0 {
            // One child hit (the common case): nothing to order or push. A tree stores an
            // inner child after its parent (a leaf's or an empty slot's reference is larger
            // than any node's index): one that is not is no tree's ([`entered_all`]).
            if ANY {
                *enter = dist[first];
            }
            let only = node.child[first];
            return (only > index).then_some(only);
        }
        if entered_all(local, nodes) {
            return None;
        }
        if ANY {
            return Some(Self::push_hits_any(
                node,
                &dist,
                mask,
                (stack, sp, enter),
                (nodes, groups),
            ));
        }
        let near = StackEntry {
            node: node.child[first],
            t_enter: dist[first],
        };
        Some(self.order_hits(level, node, &dist, mask, near, stack, sp, (nodes, groups)))
    }

    /// Pops the next entry still within `bound` (entries beyond it are dropped); `None` when
    /// the stack is empty.
    #[inline(always)]
    fn pop(stack: &[StackEntry; STACK], sp: &mut usize, bound: f32) -> Option<u32> {
        loop {
            *sp = sp.checked_sub(1)?;
            let e = stack.get(*sp)?;
            if e.t_enter <= bound {
                return Some(e.node);
            }
        }
    }

    /// [`WideBvh::pop`] of the any-hit walk: the top entry, unchecked (its interval has not
    /// shrunk since the entry was pushed within it: the walk ends at its first hit); `None`
    /// when the stack is empty.
    #[inline(always)]
    fn pop_any(stack: &[StackEntry; STACK], sp: &mut usize) -> Option<u32> {
        *sp = sp.checked_sub(1)?;
        stack.get(*sp).map(|e| e.node)
    }

    /// The next entry of the walk: [`WideBvh::pop_any`] for the any-hit walk (its entry
    /// distance left in `enter`), [`WideBvh::pop`] otherwise (`enter` untouched).
    #[inline(always)]
    fn next_entry<const ANY: bool>(
        stack: &[StackEntry; STACK],
        sp: &mut usize,
        bound: f32,
        enter: &mut f32,
    ) -> Option<u32> {
        if ANY {
            let next = Self::pop_any(stack, sp)?;
            // The entry popped stays in its slot.
            *enter = stack.get(*sp).map_or(f32::NEG_INFINITY, |e| e.t_enter);
            Some(next)
        } else {
            Self::pop(stack, sp, bound)
        }
    }

    /// The walk of [`WideBvh::traverse`] for a checked ray (`slab`), its answer left in `best`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn walk<LT: LeafTest, const ANY: bool, const GENERAL: bool, L: SimdLevel>(
        &self,
        level: L,
        stack: &mut [StackEntry; STACK],
        ray: &Ray,
        slab: &SlabRay,
        leaf: &mut LT,
        stats: Option<&mut TraversalStats>,
        best: &mut Option<(u32, LT::Hit)>,
    ) {
        let tree = (self.nodes(), self.groups());
        let groups = tree.1;
        if self.root == ChildRef::EMPTY {
            return;
        }
        // The node boxes are relative to the frame's centre: so is the origin they are
        // tested from (`PadFrame::local`).
        let (origin, pad) = self.pad_frame.local(slab.origin);
        let wray = PaddedRay::new(&SlabRay { origin, ..*slab }, pad);
        let mut local = TraversalStats::default();
        // A closest-hit ray that misses the root's box misses all its children: it ends here,
        // before the node test's eight-lane setup (the root's test counted as its visit).
        // Not for any-hit rays, which mostly start on a surface inside the box.
        if !ANY && !GENERAL && !wray.hits_box(&self.root_local, ray.t_min, cull_bound(ray.t_max)) {
            local.nodes_visited += 1;
            add_stats(stats, &local);
            return;
        }
        let mut cur = *ray;
        let mut sp = 0usize;
        // The root: node 0 (its own box is the union of its children's: not tested). A tree
        // whose root is a leaf took `root_leaf`; were it to get here, the first loop leaves
        // at once.
        let mut next = self.root;
        // With `ANY`, the entry distance of `next`'s box (the root's is not tested: the
        // interval's start), for the leaf's crossed-behind cull; the closest-hit walk leaves it.
        let mut enter = cur.t_min;
        // Down to the first leaf, nodes only (the interval cannot shrink before a leaf).
        let mut bound = cull_bound(cur.t_max);
        loop {
            let down = match ChildRef::decode(next) {
                ChildRef::Inner(index) => self.descend::<ANY, GENERAL, L>(
                    (level, &wray, tree),
                    index,
                    (cur.t_min, bound),
                    (stack, &mut sp, &mut local, &mut enter),
                ),
                ChildRef::Leaf { .. } => break,
                ChildRef::Empty => None,
            };
            match down.or_else(|| Self::next_entry::<ANY>(stack, &mut sp, bound, &mut enter)) {
                Some(child) => next = child,
                None => {
                    add_stats(stats, &local);
                    return;
                }
            }
        }
        let Some(pre) = leaf.prepare_valid(ray) else {
            add_stats(stats, &local);
            return;
        };
        'walk: loop {
            match ChildRef::decode(next) {
                ChildRef::Inner(index) => {
                    if let Some(child) = self.descend::<ANY, GENERAL, L>(
                        (level, &wray, tree),
                        index,
                        (cur.t_min, bound),
                        (stack, &mut sp, &mut local, &mut enter),
                    ) {
                        next = child;
                        continue;
                    }
                }
                ChildRef::Leaf { start, count } => {
                    local.primitives_tested += u64::from(count);
                    let run = leaf_groups(groups, start, count);
                    let lanes = RunLanes::new(start, count);
                    // A box the ray enters after its origin lies wholly ahead of it: a triangle
                    // there whose plane the line crosses behind the origin is nearly parallel
                    // to the ray (rare; the exact test refuses it), so the cull is paid only in
                    // the boxes around the origin, where a surface ray's own neighbours are.
                    let behind = enter <= cur.t_min;
                    let run = (run, lanes, behind);
                    if leaf_hits::<LT, L, ANY>(level, leaf, &pre, run, (&mut cur, best)) {
                        bound = cull_bound(cur.t_max);
                        if ANY {
                            break 'walk;
                        }
                    }
                }
                ChildRef::Empty => {}
            }
            // The next entry still within the (shrunk) interval.
            match Self::next_entry::<ANY>(stack, &mut sp, bound, &mut enter) {
                Some(child) => next = child,
                None => break,
            }
        }
        add_stats(stats, &local);
    }
}
