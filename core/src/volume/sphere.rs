//! Bounding spheres: Ritter's fit, made exact-containing by re-measuring in `f64`.

use super::points::{PointSet, points_f64, round_up_padded};
use super::{VolumeError, contain_pad};
use crate::float::sqrt_f64;
use crate::getters::getters;
use glam::{DVec3, Vec3};

/// A closed ball: every point within `radius` of `center` (radius `0` is a single point).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    center: Vec3,
    radius: f32,
}

impl BoundingSphere {
    /// The ball of `radius` (world units, `≥ 0`) around `center`.
    ///
    /// # Errors
    ///
    /// [`VolumeError::NonFiniteParameter`] for a NaN or infinite centre or radius,
    /// [`VolumeError::NegativeSize`] for `radius < 0`.
    pub fn new(center: Vec3, radius: f32) -> Result<Self, VolumeError> {
        if !center.is_finite() || !radius.is_finite() {
            return Err(VolumeError::NonFiniteParameter);
        }
        if radius < 0.0 {
            return Err(VolumeError::NegativeSize);
        }
        Ok(Self {
            center,
            radius: radius.max(0.0),
        })
    }

    getters! {
        /// Centre, world units.
        center: Vec3;
        /// Radius, world units (`≥ 0`).
        radius: f32;
    }

    /// A ball containing every point of `points` (a `&[Vec3]` or a
    /// [`crate::mesh::TriangleMesh`]): Ritter's method (1990) in `f64`. The initial diameter is
    /// the most distant pair among the extreme points along `x`, `y` and `z`; one pass then
    /// grows the ball to each point outside it. The centre is rounded to `f32` and the radius
    /// is measured again from it, in `f64`, padded by [`super::FIT_PAD_REL`] and rounded up,
    /// so the stored ball contains every input point exactly. Ritter's ball is typically
    /// 5–20 % larger than the minimal one; two passes over the points, no storage.
    ///
    /// # Errors
    ///
    /// [`VolumeError::Empty`], [`VolumeError::NonFinite`],
    /// [`VolumeError::VertexIndexOutOfRange`] (see [`PointSet::validate`]);
    /// [`VolumeError::TooLarge`] when the radius exceeds `f32::MAX`.
    pub fn fit<P: PointSet + ?Sized>(points: &P) -> Result<Self, VolumeError> {
        points.validate()?;
        let mut lo = [DVec3::INFINITY; 3];
        let mut hi = [DVec3::NEG_INFINITY; 3];
        for p in points_f64(points) {
            for k in 0..3 {
                if p[k] < lo[k][k] {
                    lo[k] = p;
                }
                if p[k] > hi[k][k] {
                    hi[k] = p;
                }
            }
        }
        let (mut a, mut b) = (lo[0], hi[0]);
        for k in 1..3 {
            if lo[k].distance_squared(hi[k]) > a.distance_squared(b) {
                (a, b) = (lo[k], hi[k]);
            }
        }
        let mut c = (a + b) * 0.5;
        let mut r = a.distance(b) * 0.5;
        for p in points_f64(points) {
            let d = p.distance(c);
            if d > r {
                let grown = (r + d) * 0.5;
                c += (p - c) * ((grown - r) / d);
                r = grown;
            }
        }
        let center = c.as_vec3();
        Self::around(center, points)
    }

    /// The smallest ball around the given `center` containing every point of a validated set
    /// (measured in `f64`, padded, rounded up).
    fn around<P: PointSet + ?Sized>(center: Vec3, points: &P) -> Result<Self, VolumeError> {
        if !center.is_finite() {
            return Err(VolumeError::TooLarge);
        }
        let c = center.as_dvec3();
        let mut r = 0.0f64;
        for p in points_f64(points) {
            // |p − c| in f64: ≤ 5 roundings relative to itself (no cancellation after the
            // correctly rounded differences).
            r = r.max(sqrt_f64((p - c).length_squared()));
        }
        let radius = round_up_padded(r, r).ok_or(VolumeError::TooLarge)?;
        Ok(Self { center, radius })
    }

    /// `true` when `p` lies in the ball, conservatively: `|p − c|² ≤ r²` is evaluated in
    /// `f64` and padded by [`super::CONTAIN_PAD_REL`] of `|p − c|²`, so a point of the exact
    /// ball is never refused (a point up to that relative band outside may be accepted). A
    /// non-finite `p` is never contained.
    #[must_use]
    pub fn contains_point(&self, p: Vec3) -> bool {
        if !p.is_finite() {
            return false;
        }
        let d = p.as_dvec3() - self.center.as_dvec3();
        let r = f64::from(self.radius);
        let d2 = d.length_squared();
        contain_pad(d2, r * r, d2)
    }
}
