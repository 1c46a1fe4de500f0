//! Errors of grid planning and construction.

use crate::error::{write_too_many, write_too_small};
use core::fmt;

/// Why a grid could not be planned or built. Every variant is returned before any caller
/// storage is written, except [`GridError::PlanMismatch`] (see there).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum GridError {
    /// The offset storage holds fewer entries than [`super::GridPlan::required_offsets`].
    OffsetStorageTooSmall {
        /// Offsets required (cells + 1).
        needed: usize,
        /// Offsets available.
        available: usize,
    },
    /// The reference storage holds fewer entries than
    /// [`super::GridPlan::required_references`].
    ReferenceStorageTooSmall {
        /// References required.
        needed: usize,
        /// References available.
        available: usize,
    },
    /// A triangle has a non-finite vertex or an out-of-range vertex index, and
    /// [`super::GridOptions::exclude_non_finite`] is off.
    NonFiniteTriangle {
        /// The triangle's index in the mesh.
        index: usize,
    },
    /// More triangles than [`super::MAX_TRIANGLES`] (indices are `u32`).
    TooManyTriangles {
        /// Triangles in the mesh.
        count: usize,
    },
    /// The cell references would not fit the `u32` offsets (more than `u32::MAX`), or the
    /// cell count does not fit in memory.
    TooManyReferences {
        /// References the plan counted (saturated).
        count: usize,
    },
    /// [`super::Grid::build`] was given a mesh that is not the one the plan was made for: a
    /// different triangle count (nothing written), or different vertices that change the
    /// reference count (found after the offsets were written; the references are untouched).
    PlanMismatch {
        /// What the plan expected (triangles, or references).
        expected: usize,
        /// What the mesh gave.
        found: usize,
    },
}

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::OffsetStorageTooSmall { needed, available } => {
                write_too_small(f, "grid offset storage", needed, available)
            }
            Self::ReferenceStorageTooSmall { needed, available } => {
                write_too_small(f, "grid reference storage", needed, available)
            }
            Self::NonFiniteTriangle { index } => write!(
                f,
                "triangle {index} has a non-finite vertex or an out-of-range vertex index"
            ),
            Self::TooManyTriangles { count } => {
                write_too_many(f, "triangles", "a grid", count, super::MAX_TRIANGLES)
            }
            Self::TooManyReferences { count } => write!(
                f,
                "too many grid cell references: {count} (max {})",
                u32::MAX
            ),
            Self::PlanMismatch { expected, found } => write!(
                f,
                "the mesh does not match the grid plan: expected {expected}, found {found}"
            ),
        }
    }
}

impl core::error::Error for GridError {}
