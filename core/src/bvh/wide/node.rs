//! The wide node (child boxes side by side) and the triangle record of its leaves.

use crate::aabb::Aabb;
use crate::triangle::{LANES, TriangleLanes};
use glam::Vec3;

/// A node of a `W`-wide BVH: the boxes of its `W` children, stored as arrays of lanes
/// (`bounds[0]` the lower corners, `bounds[1]` the upper ones, then the axis, then the child),
/// relative to the tree's [`super::WideBvh::box_origin`], and `W` child references
/// ([`ChildRef`]). Unused slots have an empty box (`+∞` lower,
/// `−∞` upper bounds), which no ray hits, and the reference [`ChildRef::EMPTY`].
///
/// Nodes are only created by [`super::WideBvh::from_binary`]: fields are private so that the
/// invariants traversal relies on (children stored after their parent, leaf runs in range)
/// cannot be broken.
///
/// Aligned to 32 bytes: the node test reads each bound array as one row (32 bytes for
/// `W = 8`, 16 for `W = 4`), and from a 32-byte boundary no row spans two cache lines, in any
/// storage (`Vec`'s too). The 8-wide node stays 224 bytes (seven rows); the 4-wide one is
/// padded from 112 to 128 (two lines).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct WideNode<const W: usize> {
    pub(super) bounds: [[[f32; W]; 3]; 2],
    pub(super) child: [u32; W],
}

impl<const W: usize> WideNode<W> {
    /// A node with every slot empty, for initialising storage: `[WideNode::EMPTY; K]`.
    pub const EMPTY: Self = Self {
        bounds: [[[f32::INFINITY; W]; 3], [[f32::NEG_INFINITY; W]; 3]],
        child: [ChildRef::EMPTY; W],
    };

    /// The box of slot `i` relative to the tree's [`super::WideBvh::box_origin`] (add it
    /// back for world coordinates), empty for an unused slot or `i ≥ W`.
    #[must_use]
    pub fn child_bounds(&self, i: usize) -> Aabb {
        if i >= W {
            return Aabb::EMPTY;
        }
        let [lo, hi] = &self.bounds;
        Aabb::new(
            Vec3::new(lo[0][i], lo[1][i], lo[2][i]),
            Vec3::new(hi[0][i], hi[1][i], hi[2][i]),
        )
    }

    /// The reference of slot `i` ([`ChildRef::Empty`] for `i ≥ W`).
    #[must_use]
    pub fn child(&self, i: usize) -> ChildRef {
        self.child
            .get(i)
            .map_or(ChildRef::Empty, |&c| ChildRef::decode(c))
    }

    /// Writes slot `i`: box `b` and the reference `child` (nothing for `i ≥ W`).
    #[inline]
    pub(super) fn set_child(&mut self, i: usize, b: &Aabb, child: u32) {
        if i < W {
            for axis in 0..3 {
                self.bounds[0][axis][i] = b.min[axis];
                self.bounds[1][axis][i] = b.max[axis];
            }
            self.child[i] = child;
        }
    }
}

impl<const W: usize> Default for WideNode<W> {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// What a child slot refers to. Encoded in a `u32`: an inner node's index (below `2³¹`), a
/// leaf (bit 31 set; bits 27–30 the triangle count minus one; bits 0–26 the first triangle
/// record), or `u32::MAX` for an empty slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChildRef {
    /// An unused slot.
    Empty,
    /// An inner node, by index.
    Inner(u32),
    /// A run of triangle records.
    Leaf {
        /// First record.
        start: u32,
        /// Records in the run, `1..=MAX_LEAF_TRIANGLES`.
        count: u32,
    },
}

pub(super) const LEAF_BIT: u32 = 1 << 31;
const COUNT_SHIFT: u32 = 27;
pub(super) const START_MASK: u32 = (1 << COUNT_SHIFT) - 1;

impl ChildRef {
    /// The encoding of an empty slot.
    pub const EMPTY: u32 = u32::MAX;

    /// Decodes a slot.
    #[inline(always)]
    #[must_use]
    pub fn decode(c: u32) -> Self {
        if c == Self::EMPTY {
            Self::Empty
        } else if c & LEAF_BIT == 0 {
            Self::Inner(c)
        } else {
            Self::Leaf {
                start: c & START_MASK,
                count: ((c >> COUNT_SHIFT) & 0xF) + 1,
            }
        }
    }

    /// Encodes a leaf; `None` when `start` needs more than 27 bits, `count` is not in
    /// `1..=MAX_LEAF_TRIANGLES`, or the run is the one whose encoding is [`ChildRef::EMPTY`]'s
    /// (`start = 2²⁷ − 1` with 16 triangles).
    #[must_use]
    pub fn leaf(start: u32, count: u32) -> Option<u32> {
        let ok = start <= START_MASK
            && (1..=super::MAX_LEAF_TRIANGLES as u32).contains(&count)
            && !(start == START_MASK && count == 16);
        ok.then(|| LEAF_BIT | ((count - 1) << COUNT_SHIFT) | start)
    }
}

/// One triangle of a leaf, by value ([`super::WideBvh::triangle`]): its vertices (copied from
/// the mesh, in the mesh's order) and its index in the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafTriangle {
    /// `v0`, `v1`, `v2`.
    pub v: [[f32; 3]; 3],
    /// Index of the triangle in the mesh the tree was built over.
    pub prim: u32,
}

impl LeafTriangle {
    /// The vertices as vectors.
    #[inline(always)]
    #[must_use]
    pub fn vertices(&self) -> [Vec3; 3] {
        [
            Vec3::from_array(self.v[0]),
            Vec3::from_array(self.v[1]),
            Vec3::from_array(self.v[2]),
        ]
    }

    /// The vertices' box.
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        let v = self.vertices();
        Aabb::new(v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]))
    }

    /// `true` when every coordinate is finite (a triangle the refit had to disable is not).
    #[inline]
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.v.iter().flatten().all(|c| c.is_finite())
    }
}

/// Four consecutive triangle slots of the leaves, stored side by side so that a leaf's
/// triangles are tested four at a time (the intersector's lane cull, an internal hook of
/// [`crate::triangle::TriangleIntersector`]) straight from memory: slot `s` of the tree is lane `s % 4` of group `s / 4`. Leaves are
/// runs of slots in leaf order, each touching the fewest groups its length allows (module
/// docs of [`super`]): 40 bytes per slot, 160 per group. Unused lanes hold NaN vertices
/// (never hit) and index `u32::MAX`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct LeafGroup {
    pub(super) lanes: TriangleLanes,
    pub(super) prim: [u32; LANES],
}

impl LeafGroup {
    /// A group with every lane unused, for initialising storage: `[LeafGroup::EMPTY; K]`.
    pub const EMPTY: Self = Self {
        lanes: TriangleLanes::EMPTY,
        prim: [u32::MAX; LANES],
    };

    /// The coordinates, lane by lane.
    #[inline(always)]
    #[must_use]
    pub fn lanes(&self) -> &TriangleLanes {
        &self.lanes
    }

    /// Lane `lane`'s triangle (`None` for `lane ≥ 4`).
    #[inline(always)]
    #[must_use]
    pub fn triangle(&self, lane: usize) -> Option<LeafTriangle> {
        Some(LeafTriangle {
            v: self.lanes.get(lane)?,
            prim: *self.prim.get(lane)?,
        })
    }

    /// Writes `tri` into lane `lane` (nothing for `lane ≥ 4`).
    #[inline]
    pub(super) fn set(&mut self, lane: usize, tri: &LeafTriangle) {
        if let Some(p) = self.prim.get_mut(lane) {
            *p = tri.prim;
            self.lanes.set(lane, &tri.v);
        }
    }
}

impl Default for LeafGroup {
    fn default() -> Self {
        Self::EMPTY
    }
}

const _: () = assert!(core::mem::size_of::<WideNode<8>>() == 224);
const _: () = assert!(core::mem::size_of::<WideNode<4>>() == 128);
const _: () = assert!(
    core::mem::align_of::<WideNode<8>>() == 32 && core::mem::align_of::<WideNode<4>>() == 32
);
const _: () = assert!(core::mem::size_of::<LeafGroup>() == 160);
