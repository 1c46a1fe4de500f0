//! Errors of grid planning and construction.

use crate::error::{CapacityError, NonFiniteError, write_too_many};
use core::fmt;

/// Why a grid could not be planned or built. Every variant is returned before any caller
/// storage is written, except [`GridError::PlanMismatch`] and
/// [`GridError::TriangleOutsidePlan`] (see there).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum GridError {
    /// Caller storage is too small: the offsets ([`super::GridPlan::required_offsets`], cells
    /// + 1) or the references ([`super::GridPlan::required_references`]).
    Capacity(CapacityError),
    /// A triangle has a non-finite vertex or an out-of-range vertex index, and
    /// [`super::GridOptions::exclude_non_finite`] is off:
    /// [`crate::error::InputElement::Triangle`] with its index in the mesh.
    NonFinite(NonFiniteError),
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
    /// different triangle count (nothing written), or vertices that change the number of
    /// usable (finite, in-range) triangles or the reference count (found after the offsets
    /// were written; the references are untouched).
    PlanMismatch {
        /// What the plan expected (triangles, usable triangles, or references).
        expected: usize,
        /// What the mesh gave.
        found: usize,
    },
    /// [`super::Grid::build`] was given a mesh with a usable triangle whose box is not inside
    /// the plan's box ([`super::GridPlan::bounds`]): its vertices moved out of it since the
    /// plan was made. Rays are clipped to that box, so such a triangle could not be found.
    /// Found after the offsets were written; the references are untouched.
    TriangleOutsidePlan {
        /// The first such triangle's index in the mesh.
        triangle: usize,
    },
}

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Capacity(e) => e.fmt(f),
            Self::NonFinite(e) => e.fmt(f),
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
            Self::TriangleOutsidePlan { triangle } => write!(
                f,
                "triangle {triangle} lies outside the box of the grid plan it was built with"
            ),
        }
    }
}

impl core::error::Error for GridError {}

impl From<CapacityError> for GridError {
    fn from(e: CapacityError) -> Self {
        Self::Capacity(e)
    }
}
