//! Refitting: recompute every box after the primitives moved, keeping the tree's topology.

use super::node::BvhNode;
use super::{Bvh, BvhError};
use crate::aabb::Aabb;
use crate::error::NonFiniteError;
use crate::mesh::{PrimitiveSource, is_usable};

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]> + AsMut<[BvhNode]>,
    I: AsRef<[u32]>,
{
    /// Recomputes every node's box from `source` (the same primitives, moved — for example
    /// after half-edge smoothing), bottom-up in one reverse pass over the nodes (children are
    /// always stored after their parent), with no stack and no rebuild. Costs one
    /// [`PrimitiveSource::primitive_bounds`] call per primitive plus one union per node.
    ///
    /// Tree quality degrades as primitives move far; rebuild when queries slow down.
    ///
    /// # Errors
    ///
    /// [`BvhError::SourceLengthMismatch`] (nothing written) when `source` has a
    /// different primitive count than at build time. [`BvhError::NonFinite`] names the
    /// first primitive whose new bounds are non-finite: the refit is still completed, with
    /// that primitive's box treated as empty, so queries stay valid and never report it
    /// while its bounds are non-finite.
    pub fn refit<S: PrimitiveSource + ?Sized>(&mut self, source: &S) -> Result<(), BvhError> {
        if source.primitive_count() != self.source_len {
            return Err(BvhError::SourceLengthMismatch {
                expected: self.source_len,
                found: source.primitive_count(),
            });
        }
        let count = self.node_count as usize;
        let indices = self.indices.as_ref();
        let nodes = self.nodes.as_mut();
        let nodes = match nodes.get_mut(..count) {
            Some(n) => n,
            None => nodes,
        };
        let mut bad: Option<usize> = None;
        for i in (0..nodes.len()).rev() {
            let b = if let Some(range) = nodes[i].primitive_range() {
                let prims = indices.get(range).unwrap_or(&[]);
                prims.iter().fold(Aabb::EMPTY, |acc, &p| {
                    let b = source.primitive_bounds(p as usize);
                    if is_usable(&b) {
                        acc.union(b)
                    } else {
                        let p = p as usize;
                        bad = Some(bad.map_or(p, |q| q.min(p)));
                        acc
                    }
                })
            } else if let Some((l, r)) = nodes[i].children() {
                let get = |c: u32| {
                    nodes
                        .get(c as usize)
                        .filter(|_| c as usize > i)
                        .map_or(Aabb::EMPTY, BvhNode::bounds)
                };
                get(l).union(get(r))
            } else {
                Aabb::EMPTY
            };
            nodes[i].set_bounds(&b);
        }
        match bad {
            Some(index) => Err(NonFiniteError::primitive(index).into()),
            None => Ok(()),
        }
    }
}
