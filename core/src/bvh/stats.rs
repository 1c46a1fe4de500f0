//! Per-ray traversal counters and whole-tree statistics.

use super::node::{BvhNode, NODE_SIZE};
use super::{Bvh, MAX_DEPTH};

/// Shape and size of a built tree ([`Bvh::stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Nodes in use.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Primitives in the tree.
    pub primitives: usize,
    /// Depth of the deepest leaf (root = 0); at most [`MAX_DEPTH`].
    pub max_depth: usize,
    /// Largest leaf, in primitives.
    pub max_leaf_size: usize,
    /// Bytes of the structure: `32·nodes + 4·primitives`.
    pub bytes: usize,
    /// SAH cost of the tree relative to its root area, with [`super::TRAVERSAL_COST`] and
    /// [`super::INTERSECTION_COST`] (a quality figure for comparing builds).
    pub sah_cost: f64,
}

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    /// Walks the tree once (with the same fixed stack bound as traversal, reaching at most
    /// as many nodes as it has) and reports its shape and size.
    #[must_use]
    pub fn stats(&self) -> BvhStats {
        let nodes = self.nodes();
        let mut s = BvhStats {
            nodes: nodes.len(),
            primitives: self.primitive_count(),
            bytes: nodes.len() * NODE_SIZE + self.primitive_count() * 4,
            ..BvhStats::default()
        };
        let Some(root) = nodes.first() else {
            return s;
        };
        let root_area = f64::from(root.bounds().surface_area());
        let mut stack = [(0u32, 0usize); MAX_DEPTH + 1];
        let mut sp = 1usize;
        let mut cost = 0.0f64;
        // A walk of a tree reaches each node at most once: nodes that make it reach more are
        // no tree (storage whose `AsRef` changed since the build), and the walk ends there.
        let mut entries = nodes.len();
        while sp > 0 {
            sp -= 1;
            let (i, depth) = stack[sp];
            let Some(n) = nodes.get(i as usize) else {
                continue;
            };
            let Some(rest) = entries.checked_sub(1) else {
                break;
            };
            entries = rest;
            let area = f64::from(n.bounds().surface_area());
            s.max_depth = s.max_depth.max(depth);
            if let Some(r) = n.primitive_range() {
                s.leaves += 1;
                s.max_leaf_size = s.max_leaf_size.max(r.len());
                cost += f64::from(super::INTERSECTION_COST) * area * r.len() as f64;
            } else if let Some((l, r)) = n.children() {
                cost += f64::from(super::TRAVERSAL_COST) * area;
                for c in [r, l] {
                    if let Some(slot) = stack.get_mut(sp) {
                        *slot = (c, depth + 1);
                        sp += 1;
                    }
                }
            }
        }
        if root_area > 0.0 {
            s.sah_cost = cost / root_area;
        }
        s
    }
}
