//! The box query and the [`RayQuery`] implementation of the kd-tree.

use super::KdTree;
use super::node::{KdNode, KdNodeKind};
use crate::aabb::Aabb;
use crate::mesh::PrimitiveSource;
use crate::query::RayQuery;
use crate::query::forward::{ClosureWalk, ray_queries};

impl<N: AsRef<[KdNode]>, R: AsRef<[u32]>> RayQuery for KdTree<N, R> {
    ray_queries!(
        #[inline]
        leaf_query
    );

    /// Visits the leaves whose cells the box touches, below before above, and reports a
    /// primitive in the first of them that references it: the first leaf found by the same
    /// walk over its bounds within the box (which reaches a leaf holding it, as every point
    /// of a primitive's box lies in the cell of a leaf that references it).
    fn query_box<P: PrimitiveSource + ?Sized>(
        &self,
        source: &P,
        query: &Aabb,
        mut found: impl FnMut(u32) -> bool,
    ) -> usize {
        if !query.is_valid() {
            return 0;
        }
        let mut reported = 0;
        self.leaves_touching(query, |node, run| {
            for &p in run {
                let b = source.primitive_bounds(p as usize);
                if !b.overlaps(query) {
                    continue;
                }
                let within = Aabb::new(b.min.max(query.min), b.max.min(query.max));
                if self.first_holder(p, &within) != node {
                    continue;
                }
                reported += 1;
                if !found(p) {
                    return false;
                }
            }
            true
        });
        reported
    }

    fn primitive_count(&self) -> usize {
        KdTree::primitive_count(self)
    }

    /// `8·nodes + 4·references` (the mesh, the unused tail of the storage and the scratch are
    /// not counted).
    fn bytes_used(&self) -> usize {
        core::mem::size_of_val(self.nodes()) + core::mem::size_of_val(self.references())
    }
}

impl<N: AsRef<[KdNode]>, R: AsRef<[u32]>> KdTree<N, R> {
    /// Calls `visit(leaf node index, its references)` for every leaf whose (closed) cell may
    /// touch the closed box `b`, depth first, the child below a plane before the one above;
    /// `visit` returns `false` to stop.
    fn leaves_touching(&self, b: &Aabb, mut visit: impl FnMut(u32, &[u32]) -> bool) {
        let (nodes, refs) = (self.nodes(), self.references());
        // One pending child per level: MAX_DEPTH + 1 entries suffice.
        let mut stack = [0u32; super::MAX_DEPTH + 1];
        let mut sp = usize::from(!nodes.is_empty());
        // A walk of a tree reaches each node at most once: nodes that make it reach more are
        // no tree (storage whose `AsRef` changed since the build), and the walk ends there.
        let mut entries = nodes.len();
        while sp > 0 {
            sp -= 1;
            let index = stack[sp];
            let Some(node) = nodes.get(index as usize) else {
                continue;
            };
            let Some(rest) = entries.checked_sub(1) else {
                return;
            };
            entries = rest;
            match node.kind() {
                KdNodeKind::Leaf { start, count } => {
                    let first = start as usize;
                    let run = refs
                        .get(first..first.saturating_add(count as usize))
                        .unwrap_or(&[]);
                    if !visit(index, run) {
                        return;
                    }
                }
                KdNodeKind::Inner {
                    axis,
                    position,
                    first,
                } => {
                    // Pushed above first, so that the child below is visited first.
                    let below = b.min[axis % 3] <= position;
                    let above = b.max[axis % 3] >= position;
                    for (child, go) in [(first.saturating_add(1), above), (first, below)] {
                        if go && let Some(slot) = stack.get_mut(sp) {
                            *slot = child;
                            sp += 1;
                        }
                    }
                }
            }
        }
    }

    /// The first leaf, in [`KdTree::leaves_touching`]'s order over `region`, that references
    /// `p`; `u32::MAX` for none.
    fn first_holder(&self, p: u32, region: &Aabb) -> u32 {
        let mut holder = u32::MAX;
        self.leaves_touching(region, |node, run| {
            if run.contains(&p) {
                holder = node;
                return false;
            }
            true
        });
        holder
    }
}
