//! The batches of a tree whose root is a leaf (a mesh of a few triangles): eight rays at a
//! time against the run's triangles with the leaf test's cull across rays
//! ([`LeafTest::sheared_rays`]), then each ray's exact test of the lanes its cull kept. A
//! ray whose cull keeps nothing (most of a camera's rays) never gets its own preparation.
//! Any-hit rays (shadow rays, which start on one of these triangles) first drop the kept
//! lanes whose plane certainly crosses them behind their origin ([`LeafTest::behind_plane`],
//! each triangle's plane computed once per batch).

use super::WideBvh;
use super::node::{ChildRef, LeafGroup, WideNode};
use super::planes::LeafPlanes;
use super::traverse::{RunLanes, kept_hits, leaf_groups};
use crate::query::{LeafTest, Query, Stack, TraversalStats};
use crate::ray::Ray;
use crate::sealed::Inside;
use crate::simd::level::SimdLevel;
use crate::triangle::{LANES, PlaneRay, RAY_LANES};

/// Groups a run may span for [`WideBvh::root_leaf_hits`]: each ray's kept lanes are one `u32`,
/// [`LANES`] bits a group.
const MAX_GROUPS: usize = 32 / LANES;

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]>,
    T: AsRef<[LeafGroup]>,
{
    /// [`crate::query::RayQuery::closest_hits`] of a tree whose root is the leaf run
    /// `(start, count)`, when the leaf test culls across rays: `out[i]` is the single-ray
    /// query's answer for `rays[i]`, bit for bit, and the statistics are the single-ray
    /// queries' (the same cull bits, the same lanes tested in the same order). Returns `false`,
    /// with nothing written, when the leaf test has no cull across rays or the run spans more
    /// than [`MAX_GROUPS`] groups; the caller then answers the rays another way. The caller
    /// has checked the lengths and that the context's stack is long enough (a single-ray query
    /// would not refuse it).
    #[inline(always)]
    pub(super) fn root_leaf_hits<LT: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        (start, count): (u32, u32),
        rays: &[Ray],
        leaf: &mut LT,
        ctx: &mut Query<'_, L, S>,
        out: &mut [S::Out<(u32, LT::Hit)>],
    ) -> bool {
        let run = leaf_groups(self.groups(), start, count);
        if run.len() > MAX_GROUPS {
            return false;
        }
        let level = ctx.level;
        let mut local = TraversalStats::default();
        for (chunk, out) in rays.chunks(RAY_LANES).zip(out.chunks_mut(RAY_LANES)) {
            let Some(sheared) = leaf.sheared_rays(Inside(()), chunk) else {
                // A leaf test without the cull refuses the first chunk, before anything is
                // written. Were a later one refused, the caller would answer every ray again
                // (this call's statistics are not added): the answers stay the single-ray ones.
                return false;
            };
            let mut kept = [0u32; RAY_LANES];
            let mut run_lanes = RunLanes::new(start, count);
            for (g, group) in run.iter().enumerate() {
                let mine = run_lanes.next_group();
                for (k, missed) in kept.iter_mut().zip(sheared.certain_misses(&group.lanes)) {
                    *k |= (mine & !missed) << (LANES * (g & (MAX_GROUPS - 1)));
                }
            }
            for ((ray, o), &kept) in chunk.iter().zip(out.iter_mut()).zip(&kept) {
                if kept == 0 {
                    // Nothing to test: no hit (a valid ray counts its triangles as tested).
                    local.primitives_tested += u64::from(count) * u64::from(ray.is_valid());
                    *o = S::answer(Ok(None));
                    continue;
                }
                let best = Self::root_leaf_kept(level, ray, leaf, run, kept, &mut local, count);
                *o = S::answer(Ok(best));
            }
        }
        if let Some(stats) = ctx.stats.as_deref_mut() {
            stats.add(&local);
        }
        true
    }

    /// One ray of [`WideBvh::root_leaf_hits`] whose cull kept the lanes `kept` (not none; the
    /// run's groups `run`, [`LANES`] bits a group): the answer of the single-ray walk of a
    /// root leaf (`WideBvh::root_leaf`), its statistics (`count` triangles for a valid ray)
    /// added to `local`.
    #[inline(always)]
    fn root_leaf_kept<LT: LeafTest, L: SimdLevel>(
        level: L,
        ray: &Ray,
        leaf: &mut LT,
        run: &[LeafGroup],
        kept: u32,
        local: &mut TraversalStats,
        count: u32,
    ) -> Option<(u32, LT::Hit)> {
        if !ray.is_valid() {
            return None;
        }
        // Never refused for a valid ray (the contract of `sheared_rays`).
        let pre = leaf.prepare_valid(ray)?;
        let (mut cur, mut best) = (*ray, None);
        for (p, pair) in run.chunks(2).enumerate() {
            let Some(pair) = lane_pair(pair) else {
                continue;
            };
            let lanes = (kept >> (2 * LANES * (p & 3))) & 0xFF;
            kept_hits::<LT, L, false>(level, leaf, &pre, pair, lanes, (&mut cur, &mut best));
        }
        local.primitives_tested += u64::from(count);
        best
    }

    /// [`crate::query::RayQuery::any_hits`] of a small tree, when the leaf test culls across
    /// rays: every triangle tested as one run, without the nodes, eight rays at a time.
    ///
    /// - A tree whose root is a leaf: `out[i]` is the single-ray any hit of `rays[i]`, bit for
    ///   bit (the lanes tested in the same order; a lane is dropped only where the single-ray
    ///   test refuses it too: by its cull, or by the triangle's
    ///   [`crate::triangle::BehindPlane`], whose refusals the exact test makes first thing).
    /// - A tree with nodes whose triangles fill at most [`MAX_GROUPS`] groups (a mesh of a few
    ///   dozen triangles, such as a cube): hit or miss is each ray's single-ray answer (the
    ///   walk's boxes never cull a triangle the leaf test hits: it finds a hit in the interval
    ///   exactly when some triangle has one), and a hit is a triangle the leaf test reports
    ///   there, perhaps another than the walk's first.
    ///
    /// The statistics count every triangle for each valid ray. Returns `false`, with nothing
    /// written, for a larger tree or a leaf test without the cull across rays, as
    /// [`WideBvh::root_leaf_hits`] does.
    #[inline(always)]
    pub(super) fn small_tree_any_hits<LT: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        rays: &[Ray],
        leaf: &mut LT,
        ctx: &mut Query<'_, L, S>,
        out: &mut [S::Out<(u32, LT::Hit)>],
    ) -> bool {
        if let ChildRef::Leaf { start, count } = ChildRef::decode(self.root) {
            let run = leaf_groups(self.groups(), start, count);
            let slots = RunLanes::new(start, count).first_slots();
            return Self::flat_any_hits((run, slots, count), rays, leaf, ctx, out);
        }
        let run = self.groups();
        // Checked before the nodes are read (`flat_any_hits` checks the root leaf's run).
        if run.len() > MAX_GROUPS {
            return false;
        }
        // The slots of every leaf run (the groups may have skipped lanes between runs).
        let mut slots = 0u64;
        for node in self.nodes() {
            for &child in &node.child {
                if let ChildRef::Leaf { start, count } = ChildRef::decode(child) {
                    slots |= ((1u64 << count.min(32)) - 1) << start.min(32);
                }
            }
        }
        let count = slots.count_ones() & 63;
        Self::flat_any_hits((run, slots as u32, count), rays, leaf, ctx, out)
    }

    /// The any hits of `rays` over the triangles of `run` in the slots `slots` (bit `4g + i`
    /// for lane `i` of group `g`), `count` of them: eight rays at a time through the cull
    /// across rays, then each ray's kept lanes pair by pair in lane order, those its
    /// triangle's plane refuses dropped ([`LeafPlanes`]), its first hit the answer. Returns
    /// `false`, with nothing written, when the run spans more than [`MAX_GROUPS`] groups or
    /// the leaf test has no cull across rays.
    #[inline(always)]
    fn flat_any_hits<LT: LeafTest, L: SimdLevel, S: Stack>(
        (run, slots, count): (&[LeafGroup], u32, u32),
        rays: &[Ray],
        leaf: &mut LT,
        ctx: &mut Query<'_, L, S>,
        out: &mut [S::Out<(u32, LT::Hit)>],
    ) -> bool {
        if run.len() > MAX_GROUPS {
            return false;
        }
        let level = ctx.level;
        let mut local = TraversalStats::default();
        // Each lane's plane, computed when a ray first keeps the lane.
        let mut planes = LeafPlanes::NEW;
        for (chunk, out) in rays.chunks(RAY_LANES).zip(out.chunks_mut(RAY_LANES)) {
            let Some(sheared) = leaf.sheared_rays(Inside(()), chunk) else {
                return false;
            };
            let mut kept = [0u32; RAY_LANES];
            for (g, group) in run.iter().enumerate() {
                let shift = LANES * (g & (MAX_GROUPS - 1));
                let mine = (slots >> shift) & 0xF;
                for (k, missed) in kept.iter_mut().zip(sheared.certain_misses(&group.lanes)) {
                    *k |= (mine & !missed) << shift;
                }
            }
            for ((ray, o), &kept) in chunk.iter().zip(out.iter_mut()).zip(&kept) {
                // The lanes whose plane refuses the ray go first: a ray left with none (a
                // shadow ray whose one kept lane is the triangle it starts on) is a miss
                // without its preparation.
                let mut kept = kept * u32::from(ray.is_valid());
                let plane_ray = PlaneRay::new(ray);
                for (p, pair) in run.chunks(2).enumerate() {
                    let Some(pair) = lane_pair(pair) else {
                        continue;
                    };
                    let shift = 2 * LANES * (p & 3);
                    let lanes = (kept >> shift) & 0xFF;
                    kept &= !(planes.refused(leaf, pair, p, lanes, &plane_ray) << shift);
                }
                // Never refused for a valid ray (the contract of `sheared_rays`).
                let pre = (kept != 0).then(|| leaf.prepare_valid(ray)).flatten();
                let Some(pre) = pre else {
                    local.primitives_tested += u64::from(count) * u64::from(ray.is_valid());
                    *o = S::answer(Ok(None));
                    continue;
                };
                let (mut cur, mut best) = (*ray, None);
                for (p, pair) in run.chunks(2).enumerate() {
                    let Some(pair) = lane_pair(pair) else {
                        continue;
                    };
                    let lanes = (kept >> (2 * LANES * (p & 3))) & 0xFF;
                    let walk = (&mut cur, &mut best);
                    if kept_hits::<LT, L, true>(level, leaf, &pre, pair, lanes, walk) {
                        break;
                    }
                }
                local.primitives_tested += u64::from(count);
                *o = S::answer(Ok(best));
            }
        }
        if let Some(stats) = ctx.stats.as_deref_mut() {
            stats.add(&local);
        }
        true
    }
}

/// The two groups of a chunk of at most two (the leaf loop's pair; a lone group stands for
/// both, its second half's lanes never set), or `None` for an empty chunk.
#[inline(always)]
fn lane_pair(pair: &[LeafGroup]) -> Option<[&LeafGroup; 2]> {
    let (first, second) = pair.split_first()?;
    Some([first, second.first().unwrap_or(first)])
}

#[cfg(test)]
mod tests;
