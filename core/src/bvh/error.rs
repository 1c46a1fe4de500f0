//! Errors of BVH construction, refitting and queries.

use crate::error::{write_non_finite_primitive, write_too_many, write_too_small};
use core::fmt;

/// Why a BVH operation was refused. Every variant is returned before any caller storage is
/// written, except [`BvhError::NonFinitePrimitive`] from [`super::Bvh::refit`] (see there).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum BvhError {
    /// The node storage holds fewer nodes than [`super::node_capacity`] requires.
    NodeStorageTooSmall {
        /// Nodes required.
        needed: usize,
        /// Nodes available.
        available: usize,
    },
    /// The index storage holds fewer entries than there are primitives.
    IndexStorageTooSmall {
        /// Indices required.
        needed: usize,
        /// Indices available.
        available: usize,
    },
    /// More primitives than [`super::MAX_PRIMITIVES`].
    TooManyPrimitives {
        /// Primitives in the source.
        count: usize,
    },
    /// A primitive's bounds are NaN, infinite or empty (non-finite vertex, out-of-range vertex
    /// index).
    NonFinitePrimitive {
        /// The primitive's index in the source.
        index: usize,
    },
    /// [`super::Bvh::refit`] was given a source with a different primitive count than the build.
    SourceLengthMismatch {
        /// Primitive count at build time.
        expected: usize,
        /// Primitive count of the source passed now.
        found: usize,
    },
    /// The triangle storage of a wide BVH holds fewer groups than
    /// [`super::wide::group_capacity`] requires.
    TriangleStorageTooSmall {
        /// Triangle groups required.
        needed: usize,
        /// Triangle groups available.
        available: usize,
    },
    /// The builder's scratch holds fewer entries than [`super::scratch_capacity`] requires.
    ScratchTooSmall {
        /// Entries required.
        needed: usize,
        /// Entries available.
        available: usize,
    },
    /// A wide BVH was asked for more triangles than its leaf references can address
    /// ([`super::wide::MAX_TRIANGLES`]).
    TooManyTriangles {
        /// Triangles in the tree.
        count: usize,
    },
    /// A leaf of the binary tree holds more primitives than a wide leaf can
    /// ([`super::wide::MAX_LEAF_TRIANGLES`]): build the binary tree with
    /// [`super::BuildOptions::max_leaf_size`] at most that.
    LeafTooLarge {
        /// Primitives in the leaf.
        count: usize,
    },
    /// A query's traversal stack (the caller's, [`super::Bvh::closest_hit_triangles_in`]) is
    /// too small for the path it had to keep: give it at least [`super::Bvh::stack_depth`]
    /// entries.
    StackTooSmall {
        /// Entries the caller's stack has.
        available: usize,
    },
    /// Slices that must have the same length do not (clearance: points, normals, output).
    LengthMismatch {
        /// Length of the first slice (points).
        expected: usize,
        /// Length of the mismatching slice.
        found: usize,
    },
}

impl fmt::Display for BvhError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NodeStorageTooSmall { needed, available } => {
                write_too_small(f, "BVH node storage", needed, available)
            }
            Self::IndexStorageTooSmall { needed, available } => {
                write_too_small(f, "BVH index storage", needed, available)
            }
            Self::TooManyPrimitives { count } => {
                write_too_many(f, "primitives", "a BVH", count, super::MAX_PRIMITIVES)
            }
            Self::NonFinitePrimitive { index } => write_non_finite_primitive(f, index),
            Self::SourceLengthMismatch { expected, found } => write!(
                f,
                "refit source has {found} primitives, the BVH was built over {expected}"
            ),
            Self::TriangleStorageTooSmall { needed, available } => write!(
                f,
                "wide BVH triangle storage too small: {needed} groups needed, {available} available"
            ),
            Self::ScratchTooSmall { needed, available } => {
                write_too_small(f, "BVH build scratch", needed, available)
            }
            Self::TooManyTriangles { count } => write_too_many(
                f,
                "triangles",
                "a wide BVH",
                count,
                super::wide::MAX_TRIANGLES,
            ),
            Self::LeafTooLarge { count } => write!(
                f,
                "a BVH leaf holds {count} primitives, a wide BVH leaf at most {}",
                super::wide::MAX_LEAF_TRIANGLES
            ),
            Self::StackTooSmall { available } => write!(
                f,
                "traversal stack too small: {available} entries, fewer than the tree's depth needs"
            ),
            Self::LengthMismatch { expected, found } => {
                write!(
                    f,
                    "slice length mismatch: expected {expected}, found {found}"
                )
            }
        }
    }
}

impl core::error::Error for BvhError {}
