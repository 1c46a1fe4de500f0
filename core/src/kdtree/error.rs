//! Errors of kd-tree construction.

use crate::error::{write_non_finite_primitive, write_too_many, write_too_small};
use core::fmt;

/// Why a kd-tree build was refused. Every variant is returned before any caller storage
/// (nodes, references, scratch) is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum KdTreeError {
    /// The node storage is empty while the source has primitives (the root needs one node).
    NodeStorageTooSmall {
        /// Nodes required at least.
        needed: usize,
        /// Nodes available.
        available: usize,
    },
    /// The reference storage holds fewer entries than the source has primitives
    /// ([`super::min_reference_capacity`]).
    ReferenceStorageTooSmall {
        /// References required at least.
        needed: usize,
        /// References available.
        available: usize,
    },
    /// The build scratch holds fewer records than the source has primitives
    /// ([`super::min_reference_capacity`]).
    ScratchTooSmall {
        /// Records required at least.
        needed: usize,
        /// Records available.
        available: usize,
    },
    /// More primitives than [`super::MAX_PRIMITIVES`].
    TooManyPrimitives {
        /// Primitives in the source.
        count: usize,
    },
    /// A primitive's bounds are NaN, infinite or empty (non-finite vertex, out-of-range vertex
    /// index), and [`super::KdBuildOptions::exclude_non_finite`] is off.
    NonFinitePrimitive {
        /// The primitive's index in the source.
        index: usize,
    },
}

impl fmt::Display for KdTreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (storage, needed, available) = match *self {
            Self::NodeStorageTooSmall { needed, available } => {
                ("kd-tree node storage", needed, available)
            }
            Self::ReferenceStorageTooSmall { needed, available } => {
                ("kd-tree reference storage", needed, available)
            }
            Self::ScratchTooSmall { needed, available } => {
                ("kd-tree build scratch", needed, available)
            }
            Self::TooManyPrimitives { count } => {
                return write_too_many(f, "primitives", "a kd-tree", count, super::MAX_PRIMITIVES);
            }
            Self::NonFinitePrimitive { index } => return write_non_finite_primitive(f, index),
        };
        write_too_small(f, storage, needed, available)
    }
}

impl core::error::Error for KdTreeError {}
