//! Oriented bounding boxes: a centre, three orthonormal axes and half-extents, fitted by
//! principal component analysis.

use super::eigen::symmetric_eigen;
use super::points::{PointSet, mean_and_covariance, points_f64, round_up_padded};
use super::{OBB_ORTHONORMAL_TOL, VolumeError, contain_pad};
use crate::aabb::Aabb;
use crate::getters::getters;
use glam::{DVec3, Vec3};

/// An oriented box: the points `x` with `|axes[i]·(x − center)| ≤ half_extents[i]` for
/// `i = 0, 1, 2` (the intersection of three slabs, so the definition holds exactly for the
/// stored `f32` axes, which are orthonormal only within [`OBB_ORTHONORMAL_TOL`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Obb {
    center: Vec3,
    axes: [Vec3; 3],
    half_extents: Vec3,
}

impl Obb {
    /// The box around `center` with unit, mutually orthogonal `axes` (either handedness) and
    /// `half_extents` (world units, `≥ 0`, along the corresponding axis).
    ///
    /// # Errors
    ///
    /// [`VolumeError::NonFiniteParameter`] for a NaN or infinite value,
    /// [`VolumeError::NegativeSize`] for a negative half-extent,
    /// [`VolumeError::NotOrthonormal`] when some `|axes[i]·axes[j] − δᵢⱼ|` (in `f64`)
    /// exceeds [`OBB_ORTHONORMAL_TOL`] (an `f32` rotation matrix may: use
    /// [`Obb::orthonormalized`]).
    pub fn new(center: Vec3, axes: [Vec3; 3], half_extents: Vec3) -> Result<Self, VolumeError> {
        if !center.is_finite() || !half_extents.is_finite() || axes.iter().any(|a| !a.is_finite()) {
            return Err(VolumeError::NonFiniteParameter);
        }
        if half_extents.min_element() < 0.0 {
            return Err(VolumeError::NegativeSize);
        }
        if !is_orthonormal(&axes) {
            return Err(VolumeError::NotOrthonormal);
        }
        Ok(Self {
            center,
            axes,
            half_extents: half_extents.max(Vec3::ZERO),
        })
    }

    /// [`Obb::new`] for axes that are only nearly orthonormal, such as an `f32` rotation
    /// matrix (`Mat3::from_quat` deviates by up to ~24 units of roundoff, more than
    /// [`OBB_ORTHONORMAL_TOL`] allows): the axes are re-orthonormalised in `f64` (Gram–Schmidt
    /// on `axes[0]`, `axes[1]`, then `axes[2]` replaced by `±axes[0] × axes[1]` with the
    /// input's handedness) and rounded to `f32`. The box is the one along the corrected
    /// axes, whose directions move by at most about the input's deviation.
    ///
    /// # Errors
    ///
    /// As [`Obb::new`]; [`VolumeError::NotOrthonormal`] when some `|aᵢ·aⱼ − δᵢⱼ|` exceeds
    /// [`OBB_ORTHONORMALIZE_MAX_DEVIATION`] (not a rotation at all).
    pub fn orthonormalized(
        center: Vec3,
        axes: [Vec3; 3],
        half_extents: Vec3,
    ) -> Result<Self, VolumeError> {
        if axes.iter().any(|a| !a.is_finite()) {
            return Err(VolumeError::NonFiniteParameter);
        }
        if gram_deviation(&axes) > OBB_ORTHONORMALIZE_MAX_DEVIATION {
            return Err(VolumeError::NotOrthonormal);
        }
        let [a0, a1, a2] = axes.map(|a| a.as_dvec3());
        let b0 = a0.normalize();
        let b1 = (a1 - b0 * b0.dot(a1)).normalize();
        let b2 = b0.cross(b1);
        let b2 = if b2.dot(a2) < 0.0 { -b2 } else { b2 };
        Self::new(
            center,
            [b0.as_vec3(), b1.as_vec3(), b2.as_vec3()],
            half_extents,
        )
    }

    /// An oriented box containing `aabb` exactly, with the world axes (centre and
    /// half-extents computed in `f64` and rounded outward).
    ///
    /// # Errors
    ///
    /// [`VolumeError::NonFiniteParameter`] for a non-finite or empty box,
    /// [`VolumeError::TooLarge`] when a half-extent exceeds `f32::MAX`.
    pub fn from_aabb(aabb: &Aabb) -> Result<Self, VolumeError> {
        if !aabb.is_finite() || !aabb.is_valid() {
            return Err(VolumeError::NonFiniteParameter);
        }
        let center = aabb.center();
        let axes = [Vec3::X, Vec3::Y, Vec3::Z];
        let c = center.as_dvec3();
        let mut e = [0.0f32; 3];
        for (k, ek) in e.iter_mut().enumerate() {
            let lo = f64::from(aabb.min[k]);
            let hi = f64::from(aabb.max[k]);
            let d = (hi - c[k]).max(c[k] - lo);
            *ek = round_up_padded(d, d).ok_or(VolumeError::TooLarge)?;
        }
        Ok(Self {
            center,
            axes,
            half_extents: Vec3::from_array(e),
        })
    }

    getters! {
        /// Centre, world units.
        center: Vec3;
        /// The three axes (unit and orthogonal within [`OBB_ORTHONORMAL_TOL`]).
        axes: [Vec3; 3];
        /// Half-extents along the axes, world units (`≥ 0`).
        half_extents: Vec3;
    }

    /// A box containing every point of `points` (a `&[Vec3]` or a
    /// [`crate::mesh::TriangleMesh`]), oriented along the principal axes of the points:
    /// the eigenvectors of their covariance matrix (mean and covariance in `f64`, symmetric
    /// Jacobi eigen-solver [`super::eigen::symmetric_eigen`]), rounded to `f32`. The box is
    /// the range of the points' coordinates in that frame: its centre is rounded to `f32`,
    /// and each half-extent is measured again from the stored centre and axes, in `f64`,
    /// padded by [`super::FIT_PAD_REL`] and rounded up, so the stored box contains every
    /// input point exactly.
    ///
    /// Degenerate input is fine: for coincident, collinear or coplanar points some
    /// half-extents are (near) zero; equal eigenvalues give some orthonormal frame of the
    /// eigenspace. PCA boxes are not minimal (a cube's PCA is isotropic, any frame results);
    /// three passes over the points, no storage.
    ///
    /// # Errors
    ///
    /// As [`super::BoundingSphere::fit`].
    pub fn fit<P: PointSet + ?Sized>(points: &P) -> Result<Self, VolumeError> {
        points.validate()?;
        let (mean, cov) = mean_and_covariance(points);
        let (_, v) = symmetric_eigen(cov);
        let mut axes = [Vec3::X, Vec3::Y, Vec3::Z];
        for (k, a) in axes.iter_mut().enumerate() {
            *a = DVec3::new(v[0][k], v[1][k], v[2][k]).as_vec3();
        }
        if !is_orthonormal(&axes) {
            // Cannot happen for the Jacobi rotations (orthonormal to a few f64 ulps, then
            // rounded once); the world axes keep the fit total.
            axes = [Vec3::X, Vec3::Y, Vec3::Z];
        }
        let ad = axes.map(|a| a.as_dvec3());
        let mut lo = DVec3::INFINITY;
        let mut hi = DVec3::NEG_INFINITY;
        for p in points_f64(points) {
            let d = p - mean;
            let t = DVec3::new(ad[0].dot(d), ad[1].dot(d), ad[2].dot(d));
            lo = lo.min(t);
            hi = hi.max(t);
        }
        let mid = (lo + hi) * 0.5;
        let center = (mean + ad[0] * mid.x + ad[1] * mid.y + ad[2] * mid.z).as_vec3();
        if !center.is_finite() {
            return Err(VolumeError::TooLarge);
        }
        let c = center.as_dvec3();
        let mut e = [0.0f64; 3];
        let mut scale = [0.0f64; 3];
        for p in points_f64(points) {
            let d = p - c;
            for k in 0..3 {
                // a·d in f64: ≤ 4 roundings relative to Σ|a_j·d_j| (cancellation possible).
                e[k] = e[k].max(ad[k].dot(d).abs());
                scale[k] = scale[k].max(ad[k].abs().dot(d.abs()));
            }
        }
        let mut half = [0.0f32; 3];
        for k in 0..3 {
            half[k] = round_up_padded(e[k], scale[k]).ok_or(VolumeError::TooLarge)?;
        }
        Ok(Self {
            center,
            axes,
            half_extents: Vec3::from_array(half),
        })
    }

    /// `true` when `p` lies in the box, conservatively: each `|axes[i]·(p − c)| ≤ e_i` is
    /// evaluated in `f64` and padded by [`super::CONTAIN_PAD_REL`] of `Σ|a_ij·(p − c)_j|`, so
    /// a point of the exact box is never refused. A non-finite `p` is never contained.
    #[must_use]
    pub fn contains_point(&self, p: Vec3) -> bool {
        if !p.is_finite() {
            return false;
        }
        let d = p.as_dvec3() - self.center.as_dvec3();
        (0..3).all(|k| {
            let a = self.axes[k].as_dvec3();
            contain_pad(
                a.dot(d).abs(),
                f64::from(self.half_extents[k]),
                a.abs().dot(d.abs()),
            )
        })
    }
}

/// Largest deviation `max |aᵢ·aⱼ − δᵢⱼ|` [`Obb::orthonormalized`] corrects, unitless
/// (`2⁻¹⁰` ≈ 1e-3): far above any rounding of a rotation matrix, far below a frame that is
/// not meant to be one.
pub const OBB_ORTHONORMALIZE_MAX_DEVIATION: f64 = 1.0 / 1024.0;

/// `max |aᵢ·aⱼ − δᵢⱼ|` in `f64` (exact products of `f32`, three roundings: negligible
/// against the tolerances it is compared with).
fn gram_deviation(axes: &[Vec3; 3]) -> f64 {
    let mut dev = 0.0f64;
    for i in 0..3 {
        for j in 0..3 {
            let dot = axes[i].as_dvec3().dot(axes[j].as_dvec3());
            let target = if i == j { 1.0 } else { 0.0 };
            dev = dev.max((dot - target).abs());
        }
    }
    dev
}

/// `true` when every `|aᵢ·aⱼ − δᵢⱼ| ≤` [`OBB_ORTHONORMAL_TOL`] (NaN is not).
pub(crate) fn is_orthonormal(axes: &[Vec3; 3]) -> bool {
    gram_deviation(axes) <= f64::from(OBB_ORTHONORMAL_TOL)
}
