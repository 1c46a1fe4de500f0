//! Bounding volumes and their overlap tests: spheres, oriented boxes (OBBs) and capsules,
//! next to the axis-aligned [`crate::aabb::Aabb`], for broad-phase collision (the hangar and
//! chopper example of the specification).
//!
//! * **Fits** ([`BoundingSphere::fit`], [`Obb::fit`], [`Capsule::fit`]) take a slice of points
//!   or a [`crate::mesh::TriangleMesh`] (anything implementing [`PointSet`]) and need no
//!   storage. Empty input, a non-finite coordinate or an out-of-range vertex index is a typed
//!   [`VolumeError`]. Every fitted volume **contains every input point exactly** (not just
//!   in `f32` arithmetic): its sizes are measured in `f64` against the stored, `f32` centre
//!   and axes, padded by [`FIT_PAD_REL`] and rounded up.
//! * **Constructors** ([`BoundingSphere::new`], [`Obb::new`], [`Capsule::new`]) refuse NaN,
//!   infinite and negative sizes and non-orthonormal axes with a typed error, so every
//!   volume that exists is finite and valid.
//! * **Overlap tests** ([`overlap`]) are **conservative**: they never report "apart" for
//!   volumes that share a point, whatever the rounding (each test's padding is a named
//!   constant with its derivation). They may report "overlap" for volumes that are apart by
//!   a small documented band. Volumes are closed: touching counts as overlap.
//! * `contains_point` on each volume is conservative in the same way.
//!
//! | pair | function | arithmetic | padding | false-positive band |
//! |---|---|---|---|---|
//! | box–box | [`crate::aabb::Aabb::overlaps`] ([`overlap::aabb_aabb`]) | comparisons only | none (exact) | none |
//! | sphere–sphere | [`overlap::sphere_sphere`] | `f32` | [`overlap::SPHERE_PAD_REL`] | [`overlap::SPHERE_BAND_REL`] |
//! | sphere–box | [`overlap::sphere_aabb`] | `f32` | [`overlap::SPHERE_PAD_REL`] | [`overlap::SPHERE_BAND_REL`] |
//! | sphere–OBB | [`overlap::sphere_obb`] | `f32` | [`overlap::SPHERE_OBB_PAD_REL`] | [`overlap::SPHERE_OBB_BAND_REL`] |
//! | OBB–OBB, box–OBB | [`overlap::obb_obb`], [`overlap::aabb_obb`] | `f32`, 15 axes | [`overlap::OBB_ABS_R_EPSILON`], [`overlap::OBB_SAT_PAD_REL`] | [`overlap::OBB_OBB_BAND_REL`] |
//! | capsule–capsule, capsule–sphere | [`overlap::capsule_capsule`], [`overlap::capsule_sphere`] | `f64` | [`overlap::CAPSULE_PAD_REL`] | [`overlap::CAPSULE_BAND_REL`] |
//!
//! The `f32` tests first rescale their inputs by a power of two when they are huge or tiny
//! ([`overlap`] module docs), so squares neither overflow nor underflow across the whole
//! `f32` range.

mod capsule;
pub mod eigen;
mod error;
mod obb;
pub mod overlap;
mod points;
mod rescale;
mod sat;
mod sphere;
#[cfg(test)]
mod tests;

pub use capsule::Capsule;
pub use error::VolumeError;
pub use obb::{OBB_ORTHONORMALIZE_MAX_DEVIATION, Obb};
pub use points::{FIT_PAD_REL, PointSet};
pub use sphere::BoundingSphere;

/// Largest deviation of the Gram matrix of an OBB's axes from the identity,
/// `max |aᵢ·aⱼ − δᵢⱼ|`, accepted by [`Obb::new`]. Unitless (`gamma(8)` ≈ 4.8e-7).
///
/// Why: axes rounded to `f32` from an exactly orthonormal frame (a fit's `f64` eigenvectors,
/// [`Obb::orthonormalized`]) deviate by at most 3 units of roundoff `u = 2⁻²⁴`; 8u accepts
/// those. (An `f32` rotation matrix computed from a quaternion deviates by up to ~24u:
/// accepting it would triple every OBB band; [`Obb::orthonormalized`] corrects it.) The OBB overlap test's error bound ([`overlap::OBB_ABS_R_EPSILON`],
/// [`overlap::OBB_SAT_PAD_REL`]) is derived for this deviation.
pub const OBB_ORTHONORMAL_TOL: f32 = crate::float::gamma(8);

/// Relative padding of the `contains_point` tests, evaluated in `f64`: `gamma_f64(8)` of the
/// sum of the absolute values of the terms of the compared quantity, unitless. Each test's
/// quantity takes at most 6 roundings of `f32` inputs in `f64` (a difference, a product, two
/// sums, a square root), plus the padding's own two; so a point of the exact volume is never
/// refused.
pub const CONTAIN_PAD_REL: f64 = crate::float::gamma_f64(8);

/// `lhs ≤ rhs + CONTAIN_PAD_REL·scale`.
#[inline]
fn contain_pad(lhs: f64, rhs: f64, scale: f64) -> bool {
    lhs <= rhs + CONTAIN_PAD_REL * scale
}
