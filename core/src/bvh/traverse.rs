//! Closest-hit and any-hit traversal on a fixed-size stack.

use super::node::BvhNode;
use super::padded_ray::PaddedRay;
use super::{Bvh, TRAVERSAL_STACK_SIZE};
use crate::aabb::{SLAB_FAR_SCALE, SlabRay};
use crate::query::QueryError;
use crate::query::TraversalStats;
use crate::query::forward::ray_queries;
use crate::query::walk::{cull_bound, improves, pad_to_root};
use crate::query::{LeafTest, Query, RayQuery, Stack, StackEntry};
use crate::ray::Ray;
use crate::simd_level::SimdLevel;
use glam::Vec3;

impl PaddedRay {
    /// [`crate::aabb::Aabb::intersect_slab`] on the node's raw corners, with the near/far
    /// corner picked by index instead of by branch. The common path (`general` false: no
    /// overflowing reciprocal, `t_min ≥ 0`) pads far distances by the plain factor
    /// [`SLAB_FAR_SCALE`]: a far distance is negative only when the exact one is (monotone
    /// rounding), and then the box ends before `t_min ≥ 0` whatever the padding, so the
    /// hit/miss answer and the entry distance are those of `intersect_slab`, except that an
    /// entry at `+∞` (a `−0` direction component outside a slab) counts as a hit here: one
    /// wasted visit, as no primitive accepts `t = ∞`, for one comparison less per node.
    /// `t_enter` and `t_exit` are never NaN (the ray was validated), so `a > b ? a : b`
    /// absorbs a NaN slab value exactly like `f32::max` does. Returns the entry distance on a
    /// hit. Inlined on hosted targets (it is the inner loop); one out-of-line copy on
    /// bare-metal ones (`target_os = "none"`), where code size is the budget.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    #[cfg_attr(target_os = "none", inline(never))]
    pub(super) fn hit_node(
        &self,
        general: bool,
        node: &BvhNode,
        t_min: f32,
        t_max: f32,
    ) -> Option<f32> {
        if general {
            return self.hit_node_general(node, t_min, t_max);
        }
        let mut t_enter = t_min;
        let mut t_exit = t_max;
        for axis in 0..3 {
            // `near` holds 0 or 1: `& 1` states it, so the lookups need no bounds check.
            let n = self.near[axis] & 1;
            let lo = node.bounds[n][axis];
            let hi = node.bounds[n ^ 1][axis];
            let t_near = (lo - self.origin_near[axis]) * self.inv_dir[axis];
            let t_far = (hi - self.origin_far[axis]) * self.inv_dir[axis] * SLAB_FAR_SCALE;
            t_enter = if t_near > t_enter { t_near } else { t_enter };
            t_exit = if t_far < t_exit { t_far } else { t_exit };
        }
        (t_enter <= t_exit).then_some(t_enter)
    }

    /// [`PaddedRay::hit_node`] for rays with a subnormal direction component whose reciprocal
    /// overflows, or with `t_min < 0` (a negative far distance must be padded towards `+∞`):
    /// [`crate::aabb::Aabb::intersect_slab`] itself.
    #[cold]
    #[inline(never)]
    fn hit_node_general(&self, node: &BvhNode, t_min: f32, t_max: f32) -> Option<f32> {
        let (lo, hi) = (Vec3::from(node.bounds[0]), Vec3::from(node.bounds[1]));
        let b = crate::aabb::Aabb::new(lo - self.pad, hi + self.pad);
        b.intersect_slab(&self.slab, t_min, t_max).map(|(t, _)| t)
    }
}

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    /// Entries of the traversal stack this tree's queries can need: the number of inner
    /// nodes on its longest root-to-leaf path (at most [`TRAVERSAL_STACK_SIZE`]). A caller's
    /// stack ([`crate::query::Query::stack`]) of this many entries never makes a query fail. Walks the whole tree (linear time,
    /// no recursion) in integers only, so that a firmware can call it after loading without
    /// linking [`Bvh::stats`]' `f64` area sums (whose `max_depth` is the same number).
    #[must_use]
    pub fn stack_depth(&self) -> usize {
        let nodes = self.nodes();
        // Depth-first over (node, inner nodes above it): one pending entry per level.
        let mut pending = [(0u32, 0u32); TRAVERSAL_STACK_SIZE + 1];
        let mut sp = usize::from(!nodes.is_empty());
        let mut deepest = 0u32;
        // Each node of a tree is reached at most once: nodes that make the walk reach more
        // are no tree (storage whose `AsRef` changed since the build), and it ends there.
        let mut entries = nodes.len();
        while sp > 0 {
            sp -= 1;
            let Some(&(index, above)) = pending.get(sp) else {
                break;
            };
            let Some(node) = nodes.get(index as usize) else {
                continue;
            };
            let Some(rest) = entries.checked_sub(1) else {
                break;
            };
            entries = rest;
            let (start, count) = node.raw();
            if count != 0 {
                deepest = deepest.max(above);
                continue;
            }
            // Both children one level down; a tree deeper than the bound (not one that was
            // built or loaded) is cut off at it rather than overflowing.
            for child in [start, start.saturating_add(1)] {
                if let Some(slot) = pending.get_mut(sp) {
                    *slot = (child, above + 1);
                    sp += 1;
                }
            }
        }
        (deepest as usize).min(TRAVERSAL_STACK_SIZE)
    }

    /// Closest hit, or any hit when `any`, on `stack`. The general node test (division for
    /// subnormal direction components, outward padding of negative far distances) is needed
    /// only for rare rays: decided once per ray and passed down as a flag (one well-predicted
    /// branch per node test; a copy of the walk per case would double a firmware's code).
    /// Out of line, so that closest and any hit with the same `intersect` share one copy.
    #[inline(never)]
    fn traverse<H>(
        &self,
        stack: &mut [StackEntry],
        ray: &Ray,
        mut intersect: impl FnMut(u32, &Ray) -> Option<(f32, H)>,
        stats: Option<&mut TraversalStats>,
        any: bool,
    ) -> Result<Option<(u32, H)>, QueryError> {
        let Some(slab) = SlabRay::new(ray) else {
            return Ok(None);
        };
        let general = slab.divide || ray.t_min < 0.0;
        let nodes = self.nodes();
        let indices = self.indices();
        let Some(root) = nodes.first() else {
            return Ok(None);
        };
        let mut local = TraversalStats::default();
        let mut cur = *ray;
        let mut best: Option<(u32, H)> = None;
        let mut sp = 0usize;

        let nray = PaddedRay::new(&slab, pad_to_root(&root.bounds(), slab.origin));
        // The root's box is not tested: it is the union of its children's, which are (and a
        // root leaf's primitives are tested exactly).
        let mut node = Some(root);
        // Inner nodes the walk may still enter: a walk of a tree enters each of its fewer than
        // `node_count` inner nodes at most once, and every other step (a leaf, a pop) follows
        // one, so the walk ends however the nodes point. Reached only when the nodes are no
        // tree (storage whose `AsRef` changed since the build, [`Bvh`]'s docs): the walk ends
        // with what it found. (Counted down and tested as one: the cheapest form on the
        // Cortex-M4F, whose C firmware has bytes to spare only in tens.)
        let mut inner_left = self.node_count;
        'walk: while let Some(n) = node {
            let (start, count) = n.raw();
            if count != 0 {
                let first = start as usize;
                let prims = indices
                    .get(first..first.saturating_add(count as usize))
                    .unwrap_or(&[]);
                for &prim in prims {
                    local.primitives_tested += 1;
                    let Some((t, h)) = intersect(prim, &cur) else {
                        continue;
                    };
                    if improves(&cur, t, prim, best.as_ref().map(|b| b.0)) {
                        cur.t_max = t;
                        best = Some((prim, h));
                        if any {
                            break 'walk;
                        }
                    }
                }
            } else {
                inner_left = inner_left.wrapping_sub(1);
                if inner_left == 0 {
                    break;
                }
                let bound = cull_bound(cur.t_max);
                let left = nodes.get(start as usize);
                let right = nodes.get(start as usize + 1);
                // Both children through one call site (the node test is inlined once).
                let mut hits = [None; 2];
                for (h, c) in hits.iter_mut().zip([left, right]) {
                    *h = c.and_then(|c| nray.hit_node(general, c, cur.t_min, bound));
                }
                local.nodes_visited += 2;
                match (hits[0], hits[1]) {
                    (Some(tl), Some(tr)) => {
                        // Near child first; equal entries keep the first child first.
                        let (near, far, t_far) = if tr < tl {
                            (right, start, tl)
                        } else {
                            (left, start + 1, tr)
                        };
                        let Some(slot) = stack.get_mut(sp) else {
                            return Err(QueryError::StackTooSmall {
                                available: stack.len(),
                            });
                        };
                        *slot = StackEntry {
                            node: far,
                            t_enter: t_far,
                        };
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = left;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = right;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next entry still within the (shrunk) interval.
            node = None;
            let bound = cull_bound(cur.t_max);
            while sp > 0 {
                sp -= 1;
                let Some(&e) = stack.get(sp) else { break };
                if e.t_enter <= bound {
                    node = nodes.get(e.node as usize);
                    break;
                }
            }
        }
        if let Some(s) = stats {
            s.add(&local);
        }
        Ok(best)
    }
}

impl<N, I> RayQuery for Bvh<N, I>
where
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    ray_queries!(
        #[inline(always)]
        on_stack
    );

    fn query_box<P: crate::mesh::PrimitiveSource + ?Sized>(
        &self,
        source: &P,
        query: &crate::aabb::Aabb,
        found: impl FnMut(u32) -> bool,
    ) -> usize {
        self.boxes_overlapping(source, query, found)
    }

    fn primitive_count(&self) -> usize {
        self.prim_count as usize
    }

    /// `32·nodes + 4·primitives` ([`super::BvhStats::bytes`]).
    fn bytes_used(&self) -> usize {
        self.nodes().len() * super::NODE_SIZE + self.prim_count as usize * 4
    }
}

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    /// Both ray queries: the context taken apart where the query is called (inlined), so that
    /// the stack's kind and the statistics are values at the call site — the own stack of
    /// [`TRAVERSAL_STACK_SIZE`] entries in the caller's frame, a caller's stack passed on, and
    /// statistics a caller never asks for folded out of the walk it links.
    #[inline(always)]
    fn on_stack<T: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        any: bool,
        ray: &Ray,
        leaf: &mut T,
        ctx: &mut Query<'_, L, S>,
    ) -> S::Out<(u32, T::Hit)> {
        let stats = ctx.stats.as_deref_mut();
        match ctx.stack.entries() {
            Some(stack) => self.leaf_query::<T, S>(any, stack, ray, leaf, stats),
            None => {
                let mut own = [StackEntry::EMPTY; TRAVERSAL_STACK_SIZE];
                self.leaf_query::<T, S>(any, &mut own, ray, leaf, stats)
            }
        }
    }

    /// The leaf test prepared once per ray (a refused ray visits nothing), then the walk on
    /// `stack`. One closure type for closest and any hit, so that both share one traversal (a
    /// firmware links one copy).
    #[inline]
    fn leaf_query<T: LeafTest, S: Stack>(
        &self,
        any: bool,
        stack: &mut [StackEntry],
        ray: &Ray,
        leaf: &mut T,
        stats: Option<&mut TraversalStats>,
    ) -> S::Out<(u32, T::Hit)> {
        let Some(pre) = leaf.prepare(ray) else {
            return S::answer(Ok(None));
        };
        S::answer(self.traverse(stack, ray, leaf.with_prepared(&pre), stats, any))
    }
}
