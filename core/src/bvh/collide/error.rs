//! Errors of the mesh-vs-mesh queries.

use core::fmt;

/// Why a collision or distance query was refused or could not report everything.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum CollideError {
    /// A [`super::Body`]'s BVH was built over a different number of triangles than its mesh
    /// has (nothing was traversed).
    MeshMismatch {
        /// Primitives the BVH was built over ([`crate::bvh::Bvh::source_len`]).
        bvh: usize,
        /// Triangles in the mesh given with it.
        mesh: usize,
    },
    /// A triangle of a [`super::Body`]'s mesh lies outside the box of the leaf holding it:
    /// the BVH was built over another mesh with as many triangles, or over this one before
    /// its vertices moved (refit it). Nothing was traversed.
    TriangleOutsideTree {
        /// The triangle's index in the mesh.
        triangle: usize,
    },
    /// The output slice of [`super::colliding_pairs`] is shorter than the number of colliding
    /// pairs. The traversal still ran to the end: `needed` is the exact total, and the slice
    /// holds the first `available` pairs found (traversal order).
    OutputTooSmall {
        /// Colliding pairs in total.
        needed: usize,
        /// Entries of the output slice.
        available: usize,
    },
    /// A node pair did not fit on the fixed traversal stack. Unreachable for trees from
    /// [`crate::bvh::Bvh::build`] or [`crate::bvh::Bvh::from_parts`], whose depth is at most
    /// [`crate::bvh::MAX_DEPTH`] (see [`super::PAIR_STACK_SIZE`]); kept so that no input can
    /// make a query panic or silently skip nodes.
    TreeTooDeep,
    /// `max_distance` of [`super::min_distance`] is NaN or negative.
    InvalidMaxDistance,
}

impl fmt::Display for CollideError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::MeshMismatch { bvh, mesh } => write!(
                f,
                "BVH built over {bvh} primitives but the mesh has {mesh} triangles"
            ),
            Self::TriangleOutsideTree { triangle } => write!(
                f,
                "triangle {triangle} lies outside its BVH leaf's box: the BVH was built over another mesh"
            ),
            Self::OutputTooSmall { needed, available } => write!(
                f,
                "collision output too small: {needed} colliding pairs, room for {available}"
            ),
            Self::TreeTooDeep => write!(
                f,
                "node pair stack overflow: a tree is deeper than the collision stack allows"
            ),
            Self::InvalidMaxDistance => write!(f, "max_distance is NaN or negative"),
        }
    }
}

impl core::error::Error for CollideError {}
