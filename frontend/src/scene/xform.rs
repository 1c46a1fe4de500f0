//! Helpers around the core's affine [`Transform`] (rays to object space with `M⁻¹`, normals
//! back with `M⁻ᵀ`, error bounds carried through): rotation matrices from the scene format,
//! world boxes of object boxes, and readable errors.

use glam::{Mat4, Vec3};
use halfray_core::transform::Transform;
use halfray_core::{Aabb, GeometryError};

/// Rotation by `degrees` about `axis` (right-handed), as a matrix; `None` for a zero axis.
pub fn rotation(axis: Vec3, degrees: f32) -> Option<Mat4> {
    let a = axis.normalize_or_zero();
    (a != Vec3::ZERO).then(|| Mat4::from_axis_angle(a, degrees.to_radians()))
}

/// World-space box of an object-space box: its eight corners with their rounding bounds.
pub fn bounds_to_world(t: &Transform, b: &Aabb) -> Aabb {
    let mut out = Aabb::EMPTY;
    for k in 0..8 {
        let c = Vec3::new(
            if k & 1 == 0 { b.min.x } else { b.max.x },
            if k & 2 == 0 { b.min.y } else { b.max.y },
            if k & 4 == 0 { b.min.z } else { b.max.z },
        );
        let (p, e) = t.point_to_world_with_error(c, Vec3::ZERO);
        out = out.grow(p - e).grow(p + e);
    }
    out
}

/// A transform error for scene-file messages.
pub fn describe(e: GeometryError) -> &'static str {
    match e {
        GeometryError::NonFinite => "transform has a non-finite entry",
        GeometryError::Degenerate => "transform matrix must be affine (last row 0 0 0 1)",
        _ => "transform is singular (a zero or degenerate scale): it cannot be inverted",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn world_box_contains_transformed_corners() {
        let t = Transform::new(
            Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
                * rotation(Vec3::Y, 45.0).unwrap()
                * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0)),
        )
        .unwrap();
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::ONE);
        let w = bounds_to_world(&t, &b);
        for c in [Vec3::splat(-1.0), Vec3::ONE, Vec3::new(1.0, -1.0, 1.0)] {
            assert!(w.contains_point(t.point_to_world(c)));
        }
        assert!(rotation(Vec3::ZERO, 10.0).is_none());
        assert_eq!(
            describe(GeometryError::SingularTransform),
            "transform is singular (a zero or degenerate scale): it cannot be inverted"
        );
    }
}
