//! Typed errors of the core. Every fallible constructor returns one of these; nothing panics.

use core::fmt;

/// Why a ray was rejected by [`crate::Ray::validate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum RayError {
    /// An origin component is NaN or infinite.
    NonFiniteOrigin,
    /// A direction component is NaN or infinite.
    NonFiniteDirection,
    /// The direction is `(0, 0, 0)` (either sign of zero).
    ZeroDirection,
    /// `t_min` or `t_max` is NaN, `t_min` is `+∞`, or `t_min > t_max`.
    BadInterval,
}

impl fmt::Display for RayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFiniteOrigin => "ray origin is not finite",
            Self::NonFiniteDirection => "ray direction is not finite",
            Self::ZeroDirection => "ray direction is zero",
            Self::BadInterval => "ray interval is NaN or empty (t_min > t_max)",
        })
    }
}

impl core::error::Error for RayError {}

/// Why a primitive could not be constructed from its data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum GeometryError {
    /// A coordinate or parameter is NaN or infinite.
    NonFinite,
    /// The primitive has no area or volume (zero radius, zero normal, collinear vertices…).
    Degenerate,
    /// A polygon's vertices do not lie in one plane within [`crate::tolerance::PLANARITY_REL`].
    NonPlanar,
    /// A polygon has fewer than three vertices or more than the fixed capacity.
    VertexCount,
    /// A transform matrix is singular (or not invertible within `f32`).
    SingularTransform,
}

impl fmt::Display for GeometryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "non-finite coordinate",
            Self::Degenerate => "degenerate primitive (zero area or volume)",
            Self::NonPlanar => "polygon is not planar",
            Self::VertexCount => "polygon vertex count out of range",
            Self::SingularTransform => "singular transform",
        })
    }
}

impl core::error::Error for GeometryError {}
