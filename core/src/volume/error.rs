//! Errors of the bounding-volume constructors and fits.

use crate::error::NonFiniteError;
use core::fmt;

/// Why a bounding volume could not be built. Nothing is partially built: a constructor or fit
/// either returns a complete, valid volume or one of these.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum VolumeError {
    /// The point set (or mesh) has no points.
    Empty,
    /// A point of the set has a NaN or infinite coordinate
    /// ([`crate::error::InputElement::Point`]: for a mesh, the `index`-th referenced corner,
    /// `3·triangle + corner`); the first such point.
    NonFinite(NonFiniteError),
    /// Triangle `triangle` of a mesh refers to a vertex index beyond the positions.
    VertexIndexOutOfRange {
        /// Index of the first offending triangle.
        triangle: usize,
    },
    /// A centre, endpoint, axis, radius or half-extent passed to a constructor is NaN or
    /// infinite.
    NonFiniteParameter,
    /// A radius or half-extent passed to a constructor is negative.
    NegativeSize,
    /// The axes passed to [`super::Obb::new`] are not orthonormal within
    /// [`super::OBB_ORTHONORMAL_TOL`].
    NotOrthonormal,
    /// The fitted volume's size does not fit in `f32` (points spread over more than
    /// `f32::MAX`).
    TooLarge,
}

impl fmt::Display for VolumeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Empty => f.write_str("no points to bound"),
            Self::NonFinite(e) => e.fmt(f),
            Self::VertexIndexOutOfRange { triangle } => {
                write!(f, "triangle {triangle} refers to a vertex out of range")
            }
            Self::NonFiniteParameter => f.write_str("volume parameter is NaN or infinite"),
            Self::NegativeSize => f.write_str("radius or half-extent is negative"),
            Self::NotOrthonormal => f.write_str("box axes are not orthonormal"),
            Self::TooLarge => f.write_str("bounding volume is too large for f32"),
        }
    }
}

impl core::error::Error for VolumeError {}
