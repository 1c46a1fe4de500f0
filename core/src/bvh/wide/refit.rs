//! Refitting a wide tree after the mesh's vertices moved.

use super::node::{ChildRef, LeafGroup, WideNode};
use super::{WideBvh, run_bounds};
use crate::aabb::Aabb;
use crate::bvh::BvhError;
use crate::error::NonFiniteError;
use crate::mesh::TriangleMesh;
use crate::triangle::LANES;

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]> + AsMut<[WideNode<W>]>,
    T: AsRef<[LeafGroup]> + AsMut<[LeafGroup]>,
{
    /// Copies the moved vertices of `mesh` (the same triangles, moved) into the triangle
    /// groups and recomputes every child box bottom-up, in one reverse pass over the nodes
    /// (children are stored after their parent), with no stack and no rebuild; a root leaf's
    /// box (a tree with no node) from its triangles. The boxes are then made relative to the
    /// new root box's centre ([`WideBvh::box_origin`]), as a build stores them.
    ///
    /// # Errors
    ///
    /// [`BvhError::SourceLengthMismatch`] (nothing written) when `mesh` has another
    /// triangle count than at build time. [`BvhError::NonFinite`] names the first
    /// triangle whose new vertices are not finite (or whose indices are out of range): the
    /// refit is still completed with that triangle's record made unhittable (NaN vertices)
    /// and its box empty, so queries stay valid and never report it.
    pub fn refit(&mut self, mesh: &TriangleMesh<'_>) -> Result<(), BvhError> {
        if mesh.len() != self.source_len {
            return Err(BvhError::SourceLengthMismatch {
                expected: self.source_len,
                found: mesh.len(),
            });
        }
        let mut bad: Option<usize> = None;
        let count = self.slot_count as usize;
        let groups = self.groups.as_mut();
        for slot in 0..count {
            let Some(group) = groups.get_mut(slot / LANES) else {
                break;
            };
            let lane = slot % LANES;
            // Lanes skipped before a leaf run hold no triangle.
            let Some(mut rec) = group.triangle(lane).filter(|t| t.prim != u32::MAX) else {
                continue;
            };
            let p = rec.prim as usize;
            match mesh.triangle(p).filter(|v| v.iter().all(|x| x.is_finite())) {
                Some(v) => rec.v = [v[0].to_array(), v[1].to_array(), v[2].to_array()],
                None => {
                    rec.v = [[f32::NAN; 3]; 3];
                    bad = Some(bad.map_or(p, |q| q.min(p)));
                }
            }
            group.set(lane, &rec);
        }
        let groups: &[LeafGroup] = groups;
        let count = self.node_count as usize;
        let nodes = self.nodes.as_mut();
        let nodes = match nodes.get_mut(..count) {
            Some(n) => n,
            None => nodes,
        };
        for i in (0..nodes.len()).rev() {
            for slot in 0..W {
                let b = match ChildRef::decode(nodes[i].child[slot]) {
                    ChildRef::Empty => continue,
                    ChildRef::Leaf { start, count } => run_bounds(groups, start, count),
                    ChildRef::Inner(c) => nodes
                        .get(c as usize)
                        .filter(|_| c as usize > i)
                        .map_or(Aabb::EMPTY, |n| {
                            (0..W).fold(Aabb::EMPTY, |b, k| b.union(n.child_bounds(k)))
                        }),
                };
                let reference = nodes[i].child[slot];
                nodes[i].set_child(slot, &b, reference);
            }
        }
        self.set_frame();
        match bad {
            Some(index) => Err(NonFiniteError::primitive(index).into()),
            None => Ok(()),
        }
    }
}
