//! Errors of BVH construction and refitting (a query's error is [`crate::query::QueryError`]).

use crate::error::{CapacityError, NonFiniteError, write_too_many};
use core::fmt;

/// Why a BVH operation was refused. Every variant is returned before any caller storage is
/// written, except [`BvhError::NonFinite`] from [`super::Bvh::refit`] and the errors
/// [`super::wide::WideBvh::from_binary_in`] finds during its walk (see there).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum BvhError {
    /// Caller storage is too small: nodes ([`super::node_capacity`]), indices (one per
    /// primitive), build scratch ([`super::scratch_capacity`]) or a wide tree's triangle
    /// groups ([`super::wide::group_capacity`]); see [`crate::error::Storage`].
    Capacity(CapacityError),
    /// More primitives than [`super::MAX_PRIMITIVES`].
    TooManyPrimitives {
        /// Primitives in the source.
        count: usize,
    },
    /// A primitive's bounds are NaN, infinite or empty (non-finite vertex, out-of-range vertex
    /// index): [`crate::error::InputElement::Primitive`] with its index in the source.
    NonFinite(NonFiniteError),
    /// [`super::Bvh::refit`] was given a source with a different primitive count than the build.
    SourceLengthMismatch {
        /// Primitive count at build time.
        expected: usize,
        /// Primitive count of the source passed now.
        found: usize,
    },
    /// A triangle of the mesh lies outside the box the tree gives it: the mesh is not the one
    /// the binary tree was built (or last refit) over, though it has as many triangles
    /// ([`super::wide::WideBvh::from_binary`]).
    TriangleOutsideTree {
        /// The triangle's index in the mesh.
        triangle: usize,
    },
    /// A wide BVH was asked for more triangles than its leaf references can address
    /// ([`super::wide::MAX_TRIANGLES`]).
    TooManyTriangles {
        /// Triangles in the tree.
        count: usize,
        /// The most a wide BVH addresses ([`super::wide::MAX_TRIANGLES`]).
        max: usize,
    },
    /// A leaf of the binary tree holds more primitives than a wide leaf can
    /// ([`super::wide::MAX_LEAF_TRIANGLES`]): build the binary tree with
    /// [`super::BuildOptions::max_leaf_size`] at most that.
    LeafTooLarge {
        /// Primitives in the leaf.
        count: usize,
        /// The most a wide leaf holds ([`super::wide::MAX_LEAF_TRIANGLES`]).
        max: usize,
    },
}

impl fmt::Display for BvhError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Capacity(e) => e.fmt(f),
            Self::TooManyPrimitives { count } => {
                write_too_many(f, "primitives", "a BVH", count, super::MAX_PRIMITIVES)
            }
            Self::NonFinite(e) => e.fmt(f),
            Self::SourceLengthMismatch { expected, found } => write!(
                f,
                "refit source has {found} primitives, the BVH was built over {expected}"
            ),
            Self::TriangleOutsideTree { triangle } => write!(
                f,
                "triangle {triangle} lies outside its BVH box: the mesh is not the tree's source"
            ),
            Self::TooManyTriangles { count, max } => {
                write_too_many(f, "triangles", "a wide BVH", count, max)
            }
            Self::LeafTooLarge { count, max } => write!(
                f,
                "a BVH leaf holds {count} primitives, a wide BVH leaf at most {max}"
            ),
        }
    }
}

impl core::error::Error for BvhError {}

impl From<CapacityError> for BvhError {
    fn from(e: CapacityError) -> Self {
        Self::Capacity(e)
    }
}

impl From<NonFiniteError> for BvhError {
    fn from(e: NonFiniteError) -> Self {
        Self::NonFinite(e)
    }
}
