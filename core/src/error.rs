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

/// Writes the message of a caller-storage-too-small error:
/// `"{storage} too small: {needed} needed, {available} available"` (`storage` names the
/// structure and the storage, e.g. `"kd-tree node storage"`; counts in the storage's units).
pub(crate) fn write_too_small(
    f: &mut fmt::Formatter<'_>,
    storage: &str,
    needed: usize,
    available: usize,
) -> fmt::Result {
    write!(
        f,
        "{storage} too small: {needed} needed, {available} available"
    )
}

/// Writes the message of a too-much-input error:
/// `"too many {items} for {structure}: {count} (max {max})"` (`items` plural, e.g.
/// `"primitives"`; `structure` with its article, e.g. `"a BVH"`).
pub(crate) fn write_too_many(
    f: &mut fmt::Formatter<'_>,
    items: &str,
    structure: &str,
    count: usize,
    max: usize,
) -> fmt::Result {
    write!(f, "too many {items} for {structure}: {count} (max {max})")
}

/// Writes the message of a build's unusable-primitive error:
/// `"primitive {index} has non-finite or empty bounds"`.
pub(crate) fn write_non_finite_primitive(f: &mut fmt::Formatter<'_>, index: usize) -> fmt::Result {
    write!(f, "primitive {index} has non-finite or empty bounds")
}

#[cfg(test)]
mod tests {
    use crate::bvh::BvhError;
    use crate::grid::GridError;
    use crate::kdtree::KdTreeError;
    use std::string::ToString;

    /// The shared writers give each structure's messages word for word.
    #[test]
    fn storage_and_size_messages() {
        let cases = [
            (
                BvhError::IndexStorageTooSmall {
                    needed: 10,
                    available: 9,
                }
                .to_string(),
                "BVH index storage too small: 10 needed, 9 available",
            ),
            (
                BvhError::NonFinitePrimitive { index: 2 }.to_string(),
                "primitive 2 has non-finite or empty bounds",
            ),
            (
                KdTreeError::TooManyPrimitives { count: 1 << 30 }.to_string(),
                "too many primitives for a kd-tree: 1073741824 (max 1073741823)",
            ),
            (
                GridError::OffsetStorageTooSmall {
                    needed: 3,
                    available: 0,
                }
                .to_string(),
                "grid offset storage too small: 3 needed, 0 available",
            ),
            (
                GridError::TooManyTriangles { count: 5 }.to_string(),
                "too many triangles for a grid: 5 (max 4294967295)",
            ),
        ];
        for (got, want) in cases {
            assert_eq!(got, want);
        }
    }
}
