//! The error of every structure's queries ([`super::RayQuery`]).

use core::fmt;

/// Why a query gave no answer: storage the caller passed does not fit the query, whatever the
/// ray. A query never refuses a ray (an invalid ray hits nothing, [`crate::Ray::validate`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum QueryError {
    /// A query's traversal stack (the caller's, [`super::Query::stack`]) is too small for the
    /// path it had to keep: give it at least the structure's stack depth
    /// ([`crate::bvh::Bvh::stack_depth`], [`crate::bvh::wide::WideBvh::stack_depth`]; a
    /// [`super::QueryStack`] fits every structure) entries.
    StackTooSmall {
        /// Entries the caller's stack has.
        available: usize,
    },
    /// Slices that must have the same length do not: a batch's rays and answers
    /// ([`super::RayQuery::closest_hits`]), or clearance's points, normals and output
    /// ([`super::RayQuery::clearance`]).
    LengthMismatch {
        /// Length of the first slice (rays, points).
        expected: usize,
        /// Length of the mismatching slice.
        found: usize,
    },
}

impl fmt::Display for QueryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
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

impl core::error::Error for QueryError {}
