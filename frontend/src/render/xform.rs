//! Affine object-to-world transforms: rays go to object space with `M⁻¹` (the direction is not
//! renormalised, so `t` is the same in both spaces), hits come back with `M` for points and
//! `M⁻ᵀ` for normals, and the hit point's error bound is carried through (pbrt's transformed
//! error: `(1 + γ₃)·|M|·e + γ₃·(|M|·|p| + |m₃|)` per component).

use glam::{Mat3, Mat4, Vec3, Vec4};
use halfray_core::float::gamma;
use halfray_core::{Hit, Ray};

/// Why a matrix cannot be a transform.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransformError {
    /// A NaN or infinite entry.
    NonFinite,
    /// The bottom row is not `[0, 0, 0, 1]` (projective matrices are not supported).
    NotAffine,
    /// The linear part is singular (a zero scale, or columns that are nearly dependent).
    Singular,
}

impl std::fmt::Display for TransformError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "transform has a non-finite entry",
            Self::NotAffine => "transform matrix must be affine (last row 0 0 0 1)",
            Self::Singular => {
                "transform is singular (zero or degenerate scale): it cannot be inverted"
            }
        })
    }
}

/// Relative determinant below which a linear map counts as singular: `|det| ≤ 1e-6 ·
/// |c0|·|c1|·|c2|` (the columns' volume against their lengths' product, i.e. the sine-like
/// measure of independence). Unitless.
pub const SINGULAR_REL: f32 = 1.0e-6;

/// An invertible affine transform with its inverse and normal matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    m: Mat4,
    inv: Mat4,
    normal: Mat3,
    abs_m: Mat3,
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        m: Mat4::IDENTITY,
        inv: Mat4::IDENTITY,
        normal: Mat3::IDENTITY,
        abs_m: Mat3::IDENTITY,
    };

    /// Checks and inverts `m` (object → world).
    pub fn new(m: Mat4) -> Result<Self, TransformError> {
        if !m.is_finite() {
            return Err(TransformError::NonFinite);
        }
        if m.row(3) != Vec4::new(0.0, 0.0, 0.0, 1.0) {
            return Err(TransformError::NotAffine);
        }
        let lin = Mat3::from_mat4(m);
        let det = lin.determinant();
        let scale = lin.x_axis.length() * lin.y_axis.length() * lin.z_axis.length();
        if !(det.abs() > SINGULAR_REL * scale) || !det.is_finite() {
            return Err(TransformError::Singular);
        }
        let inv = m.inverse();
        if !inv.is_finite() {
            return Err(TransformError::Singular);
        }
        let normal = Mat3::from_mat4(inv).transpose();
        let abs_m = Mat3::from_cols(lin.x_axis.abs(), lin.y_axis.abs(), lin.z_axis.abs());
        Ok(Self {
            m,
            inv,
            normal,
            abs_m,
        })
    }

    /// The object → world matrix.
    pub fn matrix(&self) -> Mat4 {
        self.m
    }

    /// `self` applied after `inner` (`self · inner`).
    pub fn then_after(&self, inner: &Self) -> Result<Self, TransformError> {
        Self::new(self.m * inner.m)
    }

    /// The ray in object space, same interval (`t` is preserved).
    #[inline]
    pub fn ray_to_object(&self, r: &Ray) -> Ray {
        Ray::with_interval(
            self.inv.transform_point3(r.origin),
            self.inv.transform_vector3(r.direction),
            r.t_min,
            r.t_max,
        )
    }

    /// A world-space point.
    #[inline]
    pub fn point_to_world(&self, p: Vec3) -> Vec3 {
        self.m.transform_point3(p)
    }

    /// A world-space normal (`M⁻ᵀ·n`, normalised).
    #[inline]
    pub fn normal_to_world(&self, n: Vec3) -> Vec3 {
        (self.normal * n).normalize_or_zero()
    }

    /// The hit in world space: point with `M` and its error bound carried through, normal with
    /// `M⁻ᵀ`. `t`, `uv` and `front_face` are unchanged (`d_obj·n_obj = d·(M⁻ᵀ n)`).
    #[inline]
    pub fn hit_to_world(&self, h: &Hit) -> Hit {
        let p = self.point_to_world(h.point);
        let g3 = gamma(3);
        let mp = self.abs_m * h.point.abs() + self.m.w_axis.truncate().abs();
        let err = self.abs_m * h.point_error * (1.0 + g3) + mp * g3;
        Hit {
            t: h.t,
            point: p,
            point_error: err,
            normal: self.normal_to_world(h.normal),
            uv: h.uv,
            front_face: h.front_face,
        }
    }

    /// World-space box of an object-space box (its eight corners, padded by their rounding).
    pub fn bounds_to_world(&self, b: &halfray_core::Aabb) -> halfray_core::Aabb {
        let mut out = halfray_core::Aabb::EMPTY;
        for k in 0..8 {
            let c = Vec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            let p = self.point_to_world(c);
            let pad = (self.abs_m * c.abs() + self.m.w_axis.truncate().abs()) * gamma(3);
            out = out.grow(p - pad).grow(p + pad);
        }
        out
    }
}

/// Rotation by `degrees` about `axis` (right-handed), as a matrix; `None` for a zero axis.
pub fn rotation(axis: Vec3, degrees: f32) -> Option<Mat4> {
    let a = axis.normalize_or_zero();
    (a != Vec3::ZERO).then(|| Mat4::from_axis_angle(a, degrees.to_radians()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn singular_and_projective_are_rejected() {
        assert_eq!(
            Transform::new(Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0))),
            Err(TransformError::Singular)
        );
        let mut m = Mat4::IDENTITY;
        m.x_axis.w = 1.0;
        assert_eq!(Transform::new(m), Err(TransformError::NotAffine));
        assert!(Transform::new(Mat4::from_scale(Vec3::splat(1e-3))).is_ok());
    }

    #[test]
    fn normals_use_inverse_transpose() {
        let t = Transform::new(Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0))).unwrap();
        // Plane x + y = 0 in object space scales to x/2 + y = 0: normal (1/2, 1, 0).
        let n = t.normal_to_world(Vec3::new(1.0, 1.0, 0.0));
        assert!((n - Vec3::new(0.5, 1.0, 0.0).normalize()).length() < 1e-6);
    }
}
