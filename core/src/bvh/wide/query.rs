//! The [`RayQuery`] implementation of a wide tree (its walks are in `traverse` and `packet`),
//! and the box query.

use super::WideBvh;
use super::node::{ChildRef, LeafGroup, WideNode};
use super::packet::{PACKET, PacketStack, Sharing};
use crate::aabb::Aabb;
use crate::query::QueryError;
use crate::query::{LeafTest, Query, RayQuery, Stack, same_length};
use crate::ray::Ray;
use crate::simd::level::SimdLevel;

/// Pending children of the box query: at most `W − 1` per inner node on the path, over at most
/// `MAX_DEPTH` inner nodes (module docs of [`super`]), plus the `W` children of the node just
/// expanded, for `W ≤ 8`.
const QUERY_STACK: usize = 8 * crate::bvh::MAX_DEPTH + 8;

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]>,
    T: AsRef<[LeafGroup]>,
{
    /// The box query ([`crate::query::RayQuery::query_box`]).
    pub(super) fn boxes_overlapping(
        &self,
        query: &Aabb,
        mut found: impl FnMut(u32) -> bool,
    ) -> usize {
        let nodes = self.nodes();
        let mut reported = 0usize;
        if !query.is_valid() || self.root == ChildRef::EMPTY {
            return 0;
        }
        // The node boxes are relative to the frame's centre, rounded outward: so is the
        // query box (a child overlapping the query still does; its triangles decide).
        let local = query.relative_to(self.box_origin());
        // The root (node 0, or a leaf) first.
        let mut stack = [self.root; QUERY_STACK];
        let mut sp = 1usize;
        // Nodes entered: each at most once in a tree; past `nodes.len()` the nodes are no
        // tree (storage whose `AsRef` changed, [`WideBvh`]'s docs) and no further node is
        // entered, so the walk ends however they point.
        let mut entered = 0usize;
        while sp > 0 {
            sp -= 1;
            match ChildRef::decode(stack[sp]) {
                ChildRef::Inner(i) => {
                    let Some(node) = nodes.get(i as usize).filter(|_| entered < nodes.len()) else {
                        continue;
                    };
                    entered += 1;
                    for k in 0..W {
                        if node.child[k] != ChildRef::EMPTY
                            && node.child_bounds(k).overlaps(&local)
                            && let Some(slot) = stack.get_mut(sp)
                        {
                            *slot = node.child[k];
                            sp += 1;
                        }
                    }
                }
                ChildRef::Leaf { start, count } => {
                    for t in (start..start + count).filter_map(|s| self.triangle(s as usize)) {
                        if t.bounds().overlaps(query) {
                            reported += 1;
                            if !found(t.prim) {
                                return reported;
                            }
                        }
                    }
                }
                ChildRef::Empty => {}
            }
        }
        reported
    }

    /// The batch walk of `rays` into `out` ([`QueryError::LengthMismatch`], nothing written,
    /// unless as long): sixteen rays at a time, the coherent ones as a packet
    /// ([`WideBvh::packet_hits`]) while they share their leaves ([`Sharing`]), the others
    /// alone; every ray alone on a caller stack shorter than the tree's
    /// [`WideBvh::stack_depth`] (so that each gets the single-ray answer, an error
    /// included). Closest hits, or any hits with `ANY`; a tree whose root is a leaf takes its
    /// rays eight at a time ([`WideBvh::root_leaf_hits`]), and so do the any hits of a root leaf
    /// or a tree of at most eight groups ([`WideBvh::small_tree_any_hits`]).
    #[inline(always)]
    fn in_packets<LT: LeafTest, L: SimdLevel, S: Stack, const ANY: bool>(
        &self,
        rays: &[Ray],
        leaf: &mut LT,
        ctx: &mut Query<'_, L, S>,
        out: &mut [S::Out<(u32, LT::Hit)>],
    ) -> Result<(), QueryError> {
        same_length(rays.len(), out.len())?;
        let alone = ctx
            .stack
            .entries()
            .is_some_and(|e| e.len() < self.stack_depth());
        if !alone {
            let done = match ChildRef::decode(self.root) {
                _ if ANY => self.small_tree_any_hits(rays, leaf, ctx, out),
                ChildRef::Leaf { start, count } => {
                    self.root_leaf_hits((start, count), rays, leaf, ctx, out)
                }
                _ => false,
            };
            if done {
                return Ok(());
            }
        }
        let mut stack = PacketStack::new();
        let mut sharing = Sharing::NEW;
        for (rays, out) in rays.chunks(PACKET).zip(out.chunks_mut(PACKET)) {
            let single = if alone || !sharing.try_packet() {
                u32::MAX
            } else {
                let stats = ctx.stats.as_deref_mut();
                let walk = (&mut stack, stats);
                let (single, surplus) =
                    self.packet_hits::<LT, L, ANY>(ctx.level, rays, leaf, walk, |i, found| {
                        if let Some(o) = out.get_mut(i) {
                            *o = S::answer(Ok(found));
                        }
                    });
                sharing.record(surplus);
                single
            };
            for (i, (ray, o)) in rays.iter().zip(out.iter_mut()).enumerate() {
                if single >> i & 1 == 1 {
                    *o = if ANY {
                        self.any_hit(ray, leaf, ctx)
                    } else {
                        self.closest_hit(ray, leaf, ctx)
                    };
                }
            }
        }
        Ok(())
    }
}

impl<const W: usize, N, T> RayQuery for WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]>,
    T: AsRef<[LeafGroup]>,
{
    #[inline(always)]
    fn closest_hit<LT: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        ray: &Ray,
        leaf: &mut LT,
        ctx: &mut Query<'_, L, S>,
    ) -> S::Out<(u32, LT::Hit)> {
        S::answer(self.leaf_query::<LT, false, L, S>(ray, leaf, ctx))
    }

    #[inline(always)]
    fn any_hit<LT: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        ray: &Ray,
        leaf: &mut LT,
        ctx: &mut Query<'_, L, S>,
    ) -> S::Out<(u32, LT::Hit)> {
        S::answer(self.leaf_query::<LT, true, L, S>(ray, leaf, ctx))
    }

    /// Sixteen rays at a time, the coherent ones walked as a packet, the others alone: the
    /// same answers. While the recent packets shared their leaves with less than one ray a
    /// leaf, the next chunks go alone (`Sharing`): rays this far apart are faster alone. A
    /// tree whose root is a leaf takes its rays eight at a time through the leaf test's cull
    /// across rays when it has one (`WideBvh::root_leaf_hits`). On a caller stack shorter
    /// than [`WideBvh::stack_depth`], every ray alone (so that each gets the single-ray
    /// answer, an error included).
    #[inline(always)]
    fn closest_hits<LT: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        rays: &[Ray],
        leaf: &mut LT,
        ctx: &mut Query<'_, L, S>,
        out: &mut [S::Out<(u32, LT::Hit)>],
    ) -> Result<(), QueryError> {
        self.in_packets::<LT, L, S, false>(rays, leaf, ctx, out)
    }

    /// As [`WideBvh::closest_hits`]'s packets: coherent rays (shadow rays towards one light,
    /// whose origins may lie further apart than a closest-hit packet's) walked as a packet of
    /// any-hit rays, each leaving the packet at its first hit; the others alone. Hit or miss
    /// is each ray's single-ray answer; the primitive of a ray walked in a packet is the first
    /// the packet's order reaches, which may not be the single-ray walk's. A tree whose root is
    /// a leaf takes its rays eight at a time through the cull across rays, the triangles'
    /// planes refusing the ones a ray starts on: there each answer is the single-ray one, bit
    /// for bit. A tree of at most eight groups with nodes (a few dozen triangles) tests all
    /// its triangles the same way, without the nodes: hit or miss as the single ray, the
    /// primitive perhaps another (both `WideBvh::small_tree_any_hits`).
    #[inline(always)]
    fn any_hits<LT: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        rays: &[Ray],
        leaf: &mut LT,
        ctx: &mut Query<'_, L, S>,
        out: &mut [S::Out<(u32, LT::Hit)>],
    ) -> Result<(), QueryError> {
        self.in_packets::<LT, L, S, true>(rays, leaf, ctx, out)
    }

    fn query_box<P: crate::mesh::PrimitiveSource + ?Sized>(
        &self,
        _: &P,
        query: &crate::aabb::Aabb,
        found: impl FnMut(u32) -> bool,
    ) -> usize {
        self.boxes_overlapping(query, found)
    }

    fn primitive_count(&self) -> usize {
        self.triangle_count()
    }

    /// `224·nodes + 160·groups` for `W = 8` (module docs).
    fn bytes_used(&self) -> usize {
        core::mem::size_of_val(self.nodes()) + core::mem::size_of_val(self.groups())
    }
}

#[cfg(test)]
mod tests;
