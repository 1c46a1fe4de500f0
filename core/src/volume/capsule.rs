//! Capsules (swept spheres): the points within `radius` of a segment. A capsule bounds
//! long, thin bodies (a rotor, a fuselage) far tighter than a sphere, and unlike a bounding
//! cylinder its overlap tests reduce to segment distances.

use super::eigen::symmetric_eigen;
use super::points::{PointSet, mean_and_covariance, points_f64, round_up_padded};
use super::{VolumeError, contain_pad};
use crate::float::sqrt_f64;
use crate::getters::getters;
use glam::{DVec3, Vec3};

/// A closed capsule: every point within `radius` of the segment `[a, b]` (`a = b` is a ball,
/// radius `0` a segment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    a: Vec3,
    b: Vec3,
    radius: f32,
}

impl Capsule {
    /// The capsule of `radius` (world units, `≥ 0`) around the segment `[a, b]`.
    ///
    /// # Errors
    ///
    /// [`VolumeError::NonFiniteParameter`] for a NaN or infinite value,
    /// [`VolumeError::NegativeSize`] for `radius < 0`.
    pub fn new(a: Vec3, b: Vec3, radius: f32) -> Result<Self, VolumeError> {
        if !a.is_finite() || !b.is_finite() || !radius.is_finite() {
            return Err(VolumeError::NonFiniteParameter);
        }
        if radius < 0.0 {
            return Err(VolumeError::NegativeSize);
        }
        Ok(Self {
            a,
            b,
            radius: radius.max(0.0),
        })
    }

    getters! {
        /// First endpoint of the axis segment.
        a: Vec3;
        /// Second endpoint of the axis segment.
        b: Vec3;
        /// Radius, world units (`≥ 0`).
        radius: f32;
    }

    /// A capsule containing every point of `points` (a `&[Vec3]` or a
    /// [`crate::mesh::TriangleMesh`]), along the principal axis `u` of the points (largest
    /// eigenvalue of their covariance, in `f64`) through their mean `m`: the radius is the
    /// largest distance `d_p` of a point from that line, and the segment `[m + lo·u, m + hi·u]`
    /// is the shortest that covers every point, `lo = min(t_p + s_p)`,
    /// `hi = max(t_p − s_p)` with `t_p = u·(p − m)` and `s_p = √(r² − d_p²)` (one point when
    /// `lo > hi`). The endpoints are rounded to `f32`, and the radius is measured again from
    /// the stored segment, in `f64`, padded by [`super::FIT_PAD_REL`] and rounded up, so the
    /// stored capsule contains every input point exactly. Three passes, no storage.
    ///
    /// # Errors
    ///
    /// As [`super::BoundingSphere::fit`].
    pub fn fit<P: PointSet + ?Sized>(points: &P) -> Result<Self, VolumeError> {
        points.validate()?;
        let (mean, cov) = mean_and_covariance(points);
        let (lambda, v) = symmetric_eigen(cov);
        let mut k = 0;
        for i in 1..3 {
            if lambda[i] > lambda[k] {
                k = i;
            }
        }
        let u = DVec3::new(v[0][k], v[1][k], v[2][k]);
        let u = u / u.length().max(f64::MIN_POSITIVE);
        let mut r2 = 0.0f64;
        for p in points_f64(points) {
            let d = p - mean;
            r2 = r2.max(d.reject_from_normalized(u).length_squared());
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in points_f64(points) {
            let d = p - mean;
            let t = u.dot(d);
            let s = sqrt_f64((r2 - d.reject_from_normalized(u).length_squared()).max(0.0));
            lo = lo.min(t + s);
            hi = hi.max(t - s);
        }
        if lo > hi {
            let mid = (lo + hi) * 0.5;
            (lo, hi) = (mid, mid);
        }
        let a = (mean + u * lo).as_vec3();
        let b = (mean + u * hi).as_vec3();
        if !a.is_finite() || !b.is_finite() {
            return Err(VolumeError::TooLarge);
        }
        let mut r = 0.0f64;
        let mut scale = 0.0f64;
        for p in points_f64(points) {
            let (d, s) = segment_distance_f64(p, a, b);
            r = r.max(d);
            scale = scale.max(s);
        }
        let radius = round_up_padded(r, scale).ok_or(VolumeError::TooLarge)?;
        Ok(Self { a, b, radius })
    }

    /// `true` when `p` lies in the capsule, conservatively: its distance to the segment is
    /// evaluated in `f64` and padded by [`super::CONTAIN_PAD_REL`] of the magnitudes that
    /// evaluation rounds, so a point of the exact capsule is never refused. A non-finite `p`
    /// is never contained.
    #[must_use]
    pub fn contains_point(&self, p: Vec3) -> bool {
        if !p.is_finite() {
            return false;
        }
        let (d, scale) = segment_distance_f64(p.as_dvec3(), self.a, self.b);
        contain_pad(d, f64::from(self.radius), scale)
    }
}

/// The distance from `p` to the segment `[a, b]` in `f64`, and the scale its rounding error
/// is relative to: the computed closest point `q = a + t·(b − a)` (`t` clamped to `[0, 1]`)
/// lies within 3 roundings of `|a| + |t·(b − a)|` of an exact point of the segment (whatever
/// the error of `t`), and `|p − q|` adds 5 relative to itself, so the exact distance is
/// within `gamma_f64(8)` of the returned scale `|a|₁ + |b − a|₁ + |p − q|` of the result.
pub(crate) fn segment_distance_f64(p: DVec3, a: Vec3, b: Vec3) -> (f64, f64) {
    let (a, b) = (a.as_dvec3(), b.as_dvec3());
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = a + ab * t;
    let d = sqrt_f64((p - q).length_squared());
    let scale = a.abs().element_sum() + ab.abs().element_sum() + d;
    (d, scale)
}
