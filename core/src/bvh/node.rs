//! The 32-byte BVH node.

use crate::aabb::Aabb;
use core::ops::Range;
use glam::{Vec3, Vec3A};

/// A BVH node: a box and either two adjacent children or a run of primitive indices.
///
/// Layout (`repr(C)`, 32 bytes, 32-byte aligned): `bounds: [min, max]` as `[[f32; 3]; 2]`
/// (24 bytes; indexed by the ray's direction sign bit during traversal), `start: u32`,
/// `count: u32`. An inner node has `count = 0` and its children at `start`
/// and `start + 1`; a leaf has `count ≥ 1` primitives at `indices[start..start + count]`.
/// Fields are private: nodes come from the builder, or from [`BvhNode::from_raw`] through
/// [`super::Bvh::from_parts`], which checks the invariants that bound the traversal (children
/// after their parent, depth ≤ [`super::MAX_DEPTH`]) before any query.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct BvhNode {
    pub(super) bounds: [[f32; 3]; 2],
    start: u32,
    count: u32,
}

/// Size of a [`BvhNode`] in bytes.
pub const NODE_SIZE: usize = core::mem::size_of::<BvhNode>();
const _: () = assert!(NODE_SIZE == 32);

impl Default for BvhNode {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl BvhNode {
    /// An unused node (empty box, empty leaf), for initialising storage:
    /// `[BvhNode::EMPTY; K]`.
    pub const EMPTY: Self = Self {
        bounds: [[f32::INFINITY; 3], [f32::NEG_INFINITY; 3]],
        start: 0,
        count: 0,
    };

    /// A node from its raw fields: `bounds` as `[min, max]`, then `start` and `count` (an
    /// inner node has `count = 0` and its children at `start`, `start + 1`; a leaf covers
    /// `indices[start..start + count]`). For BVHs baked elsewhere: a tree of such nodes is
    /// only queried after [`super::Bvh::from_parts`] has checked it.
    #[must_use]
    pub const fn from_raw(bounds: [[f32; 3]; 2], start: u32, count: u32) -> Self {
        Self {
            bounds,
            start,
            count,
        }
    }

    /// The raw fields `(bounds, start, count)` (see [`BvhNode::from_raw`]), for writing a
    /// baked BVH.
    #[must_use]
    pub const fn to_raw(&self) -> ([[f32; 3]; 2], u32, u32) {
        (self.bounds, self.start, self.count)
    }

    #[inline]
    pub(super) fn set_bounds(&mut self, b: &Aabb) {
        self.bounds = [b.min.to_array(), b.max.to_array()];
    }

    #[inline]
    pub(super) fn set_leaf(&mut self, start: u32, count: u32) {
        self.start = start;
        self.count = count;
    }

    #[inline]
    pub(super) fn set_inner(&mut self, first_child: u32) {
        self.start = first_child;
        self.count = 0;
    }

    /// The node's box.
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        Aabb::new(
            Vec3::from_array(self.bounds[0]),
            Vec3::from_array(self.bounds[1]),
        )
    }

    /// `true` for a leaf.
    #[inline]
    #[must_use]
    pub fn is_leaf(&self) -> bool {
        self.count != 0
    }

    /// Indices of the two children of an inner node (`None` for a leaf).
    #[inline]
    #[must_use]
    pub fn children(&self) -> Option<(u32, u32)> {
        (self.count == 0).then(|| (self.start, self.start.wrapping_add(1)))
    }

    /// The range of the index array a leaf covers (`None` for an inner node).
    #[inline]
    #[must_use]
    pub fn primitive_range(&self) -> Option<Range<usize>> {
        (self.count != 0)
            .then(|| self.start as usize..(self.start as usize).saturating_add(self.count as usize))
    }

    /// `true` when every vertex of `v` lies in the node's (closed) box; `false` for a NaN
    /// coordinate. Exact compares: the builder and [`super::Bvh::refit`] make a leaf's box the
    /// exact `f32` minimum and maximum of its triangles' vertices, and an inner node's the
    /// union of its children's, so a tree holds every triangle of its source.
    ///
    /// Four-lane compares and one mask test, no branch per coordinate: the collapse makes
    /// it once per triangle it copies.
    #[inline]
    pub(crate) fn holds(&self, v: &[Vec3; 3]) -> bool {
        let (lo, hi) = (
            Vec3A::from_array(self.bounds[0]),
            Vec3A::from_array(self.bounds[1]),
        );
        let inside = |p: Vec3| {
            let p = Vec3A::from(p);
            lo.cmple(p) & p.cmple(hi)
        };
        (inside(v[0]) & inside(v[1]) & inside(v[2])).all()
    }

    /// `true` when the box `[lo, hi]` lies in the node's (closed) box; `false` for a NaN
    /// coordinate. The box of several triangles is in it exactly when each triangle is
    /// ([`BvhNode::holds`]).
    #[inline]
    pub(crate) fn holds_box(&self, lo: Vec3A, hi: Vec3A) -> bool {
        let (min, max) = (
            Vec3A::from_array(self.bounds[0]),
            Vec3A::from_array(self.bounds[1]),
        );
        (min.cmple(lo) & hi.cmple(max)).all()
    }

    /// Raw `(start, count)` fields.
    #[inline]
    pub(super) fn raw(&self) -> (u32, u32) {
        (self.start, self.count)
    }
}
