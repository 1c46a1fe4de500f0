//! Box and clearance queries on a wide tree.

use super::WideBvh;
use super::node::{ChildRef, LeafGroup, WideNode};
use crate::aabb::Aabb;
use crate::bvh::BvhError;
use crate::bvh::clearance::clearance_loop;
use crate::triangle::TriangleIntersector;
use glam::Vec3;

/// Pending children of the box query: at most `W − 1` per inner node on the path, over at most
/// `MAX_DEPTH` inner nodes (module docs of [`super`]), plus the `W` children of the node just
/// expanded, for `W ≤ 8`.
const QUERY_STACK: usize = 8 * crate::bvh::MAX_DEPTH + 8;

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]>,
    T: AsRef<[LeafGroup]>,
{
    /// Calls `found(prim)` for every triangle whose box overlaps `query` (closed boxes:
    /// touching counts, see [`Aabb::overlaps`]); `found` returns `true` to continue, `false`
    /// to stop. Returns the number reported. An empty or NaN query box reports nothing.
    /// Triangles are visited in tree order.
    pub fn query_box(&self, query: &Aabb, found: impl FnMut(u32) -> bool) -> usize {
        self.boxes_overlapping(query, found)
    }

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

    /// The clearance query of [`crate::bvh::Bvh::clearance_triangles`] on this tree: for each
    /// point, the distance to the nearest hit along its normal (`+∞` for none or an invalid
    /// ray), into `out`; returns the minimum.
    ///
    /// # Errors
    ///
    /// Nothing written:
    /// [`BvhError::LengthMismatch`].
    pub fn clearance_triangles<I: TriangleIntersector>(
        &self,
        isect: &I,
        points: &[Vec3],
        normals: &[Vec3],
        out: &mut [f32],
    ) -> Result<f32, BvhError> {
        clearance_loop(points, normals, out, |ray| {
            self.closest_hit_triangles(isect, ray, None)
                .map(|(_, h)| h.t)
        })
    }
}
