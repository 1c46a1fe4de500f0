//! Errors of kd-tree construction.

use crate::error::{CapacityError, NonFiniteError, write_too_many};
use core::fmt;

/// Why a kd-tree build was refused. Every variant is returned before any caller storage
/// (nodes, references, scratch) is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum KdTreeError {
    /// Caller storage is too small: the node storage is empty while the source has
    /// primitives (the root needs one node), or the reference storage or the build scratch
    /// holds fewer entries than the source has primitives ([`super::min_reference_capacity`]).
    Capacity(CapacityError),
    /// More primitives than [`super::MAX_PRIMITIVES`].
    TooManyPrimitives {
        /// Primitives in the source.
        count: usize,
    },
    /// A primitive's bounds are NaN, infinite or empty (non-finite vertex, out-of-range vertex
    /// index), and [`super::KdBuildOptions::exclude_non_finite`] is off:
    /// [`crate::error::InputElement::Primitive`] with its index in the source.
    NonFinite(NonFiniteError),
}

impl fmt::Display for KdTreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Capacity(e) => e.fmt(f),
            Self::TooManyPrimitives { count } => {
                write_too_many(f, "primitives", "a kd-tree", count, super::MAX_PRIMITIVES)
            }
            Self::NonFinite(e) => e.fmt(f),
        }
    }
}

impl core::error::Error for KdTreeError {}

impl From<CapacityError> for KdTreeError {
    fn from(e: CapacityError) -> Self {
        Self::Capacity(e)
    }
}
