//! Box queries: every primitive whose box overlaps a query box.

use super::node::BvhNode;
use super::{Bvh, MAX_DEPTH};
use crate::aabb::Aabb;
use crate::mesh::PrimitiveSource;

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    /// The box query ([`crate::query::RayQuery::query_box`]).
    pub(super) fn boxes_overlapping<S: PrimitiveSource + ?Sized>(
        &self,
        source: &S,
        query: &Aabb,
        mut found: impl FnMut(u32) -> bool,
    ) -> usize {
        let nodes = self.nodes();
        let indices = self.indices();
        let mut reported = 0usize;
        if !query.is_valid() {
            return 0;
        }
        // One pending sibling per level at most: MAX_DEPTH + 1 entries suffice.
        let mut stack = [0u32; MAX_DEPTH + 1];
        let mut sp = 0usize;
        let mut node = nodes.first().filter(|r| r.bounds().overlaps(query));
        // A walk of a tree enters each node at most once: nodes that make it enter more are
        // no tree (storage whose `AsRef` changed since the build), and the walk ends there.
        let mut entries = nodes.len();
        while let Some(n) = node {
            let Some(rest) = entries.checked_sub(1) else {
                break;
            };
            entries = rest;
            node = None;
            if let Some(range) = n.primitive_range() {
                for &p in indices.get(range).unwrap_or(&[]) {
                    if source.primitive_bounds(p as usize).overlaps(query) {
                        reported += 1;
                        if !found(p) {
                            return reported;
                        }
                    }
                }
            } else if let Some((l, r)) = n.children() {
                let left = nodes.get(l as usize).filter(|c| c.bounds().overlaps(query));
                let right = nodes.get(r as usize).filter(|c| c.bounds().overlaps(query));
                match (left, right) {
                    (Some(a), Some(_)) => {
                        if let Some(slot) = stack.get_mut(sp) {
                            *slot = r;
                            sp += 1;
                        }
                        node = Some(a);
                    }
                    (a, b) => node = a.or(b),
                }
            }
            if node.is_none() && sp > 0 {
                sp -= 1;
                node = nodes.get(stack[sp] as usize);
            }
        }
        reported
    }
}
