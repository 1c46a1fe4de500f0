//! The box query on a wide tree.

use super::WideBvh;
use super::node::{ChildRef, LeafGroup, WideNode};
use crate::aabb::Aabb;

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
        if !query.is_valid() || nodes.is_empty() {
            return 0;
        }
        let mut stack = [0u32; QUERY_STACK];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            match ChildRef::decode(stack[sp]) {
                ChildRef::Inner(i) => {
                    let Some(node) = nodes.get(i as usize) else {
                        continue;
                    };
                    for k in 0..W {
                        if node.child[k] != ChildRef::EMPTY
                            && node.child_bounds(k).overlaps(query)
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
}
