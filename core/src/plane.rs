//! Infinite planes in point–normal form.
//!
//! `t = ((p₀ − o)·N) / (d·N)` (the point form: `p₀ − o` does not cancel
//! when the origin is far from the world origin but near the plane's reference point).
//!
//! Contract of [`Plane::intersect`]:
//! * `d·N == 0` (computed in `f32`), whether the ray lies in the plane or not, is **no hit**
//!   (explicit branch: no `0/0 = NaN` reaches a comparison). A ray whose exact `d·N` is not zero
//!   but rounds to zero is treated as parallel too.
//! * `t` must lie in the ray's `(t_min, t_max]` and be finite; invalid rays ([`Ray::validate`])
//!   hit nothing. No input panics.
//! * Both faces are hit; `front_face = d·N < 0`; `normal` is the plane's unit normal (not
//!   flipped).
//! * `point` is on the plane: for an **axis-aligned** normal (two components exactly zero) the
//!   coordinate along the normal is *snapped* to the plane's coordinate (pbrt's disk trick), so
//!   `point_error` is exactly zero; otherwise `o + t·d` is re-projected once onto the plane
//!   (`p ← p − ((p − p₀)·N)·N`) and `point_error` bounds its remaining distance to the plane
//!   (see [`Plane::intersect`]). As everywhere in halfray (triangles, spheres), the bound is on
//!   the distance to *the surface*, which is what [`crate::hit::spawn_ray`] needs; the position
//!   *along* the surface additionally carries the rounding of `t`.
//! * `uv` = in-plane coordinates `((p − p₀)·T, (p − p₀)·B)` in world units, where `(T, B, N)` is
//!   the right-handed orthonormal basis of Duff et al. 2017 (glam's `any_orthonormal_pair`); for
//!   `N = +z` it is `(x − x₀, y − y₀)`.

use crate::error::GeometryError;
use crate::float::{gamma, unit_direction_f64};
use crate::hit::Hit;
use crate::ray::Ray;
use glam::{DVec3, Vec2, Vec3};

/// An infinite plane through `point` with unit normal `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    point: Vec3,
    normal: Vec3,
}

impl Plane {
    /// A plane through `point` with normal direction `normal` (any non-zero length; it is
    /// normalised here, in `f64`, then rounded: each component is within one `f32` rounding of
    /// the exact unit vector, so `|N·N − 1| ≤ gamma(3)`). A normal with exactly two zero
    /// components is stored as the exact axis vector `±e_k`.
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`] for a non-finite point or normal,
    /// [`GeometryError::Degenerate`] for a zero normal (or one whose length underflows in
    /// `f64`, which cannot happen for finite `f32` input other than zero).
    pub fn new(point: Vec3, normal: Vec3) -> Result<Self, GeometryError> {
        if !point.is_finite() || !normal.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        let mut unit = unit_direction_f64(normal)?.as_vec3();
        if let Some(k) = axis_of(normal) {
            unit = Vec3::ZERO;
            unit[k] = if normal[k] > 0.0 { 1.0 } else { -1.0 };
        }
        Ok(Self {
            point,
            normal: unit,
        })
    }

    /// The reference point `p₀` (world units).
    #[inline]
    #[must_use]
    pub fn point(&self) -> Vec3 {
        self.point
    }

    /// The unit normal `N`.
    #[inline]
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// `Some(k)` when the normal is the axis vector `±e_k` (hits are then snapped exactly).
    #[inline]
    #[must_use]
    pub fn axis(&self) -> Option<usize> {
        axis_of(self.normal)
    }

    /// The in-plane basis `(T, B)` used for `uv` (`T × B = N`).
    #[inline]
    #[must_use]
    pub fn tangents(&self) -> (Vec3, Vec3) {
        self.normal.any_orthonormal_pair()
    }

    /// The ray parameter of the plane crossing, in `(t_min, t_max]`, or `None` (parallel ray,
    /// out of the interval, non-finite `t`, invalid ray). See the module documentation.
    #[inline]
    #[must_use]
    pub fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        if !ray.is_valid() {
            return None;
        }
        let denom = ray.direction.dot(self.normal);
        if denom == 0.0 || !denom.is_finite() {
            return None;
        }
        let num = (self.point - ray.origin).dot(self.normal);
        let t = num / denom;
        (t.is_finite() && ray.contains(t)).then_some(t)
    }

    /// Ray–plane intersection: see the module documentation for the contract.
    ///
    /// **Error bound (non-axis normals).** With `s = fl((p − p₀)·N)` and `p' = fl(p − s·N)`,
    /// the exact distance of `p'` to the plane is at most
    /// `D = gamma(5)·Σ|p_i − p₀_i||N_i| + gamma(3)·|s| + gamma(2)·Σ(|p'_i| + |s·N_i|)|N_i|`
    /// (rounding of `s`, non-unit `|N|`, rounding of the update), and the nearest plane point
    /// differs from `p'` by at most `D·|N_i|` in component `i`; the bound is returned scaled by
    /// `1 + gamma(4)` to cover the rounding of its own evaluation and the division by `N·N`.
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let t = self.intersect_t(ray)?;
        let n = self.normal;
        let p = ray.origin + ray.direction * t;
        if !p.is_finite() {
            return None;
        }
        let (point, point_error) = match self.axis() {
            Some(k) => {
                let mut q = p;
                q[k] = self.point[k];
                (q, Vec3::ZERO)
            }
            None => {
                let rel = p - self.point;
                let s = rel.dot(n);
                let q = p - n * s;
                let an = n.abs();
                let d = gamma(5) * rel.abs().dot(an)
                    + gamma(3) * s.abs()
                    + gamma(2) * (q.abs() + (n * s).abs()).dot(an);
                (q, an * (d * (1.0 + gamma(4))))
            }
        };
        if !point.is_finite() || !point_error.is_finite() {
            return None;
        }
        let (tu, tv) = self.tangents();
        let rel = point - self.point;
        Some(Hit {
            t,
            point,
            point_error,
            normal: n,
            uv: Vec2::new(rel.dot(tu), rel.dot(tv)),
            front_face: ray.direction.dot(n) < 0.0,
        })
    }

    /// Signed distance of `p` from the plane, in `f64` (positive on the normal's side). Used by
    /// tests and by [`crate::polygon`]'s planarity check.
    #[inline]
    #[must_use]
    pub fn signed_distance_f64(&self, p: Vec3) -> f64 {
        let n: DVec3 = self.normal.as_dvec3();
        (p.as_dvec3() - self.point.as_dvec3()).dot(n) / n.length()
    }
}

/// `Some(k)` when exactly the `k`-th component of `n` is non-zero.
#[inline]
fn axis_of(n: Vec3) -> Option<usize> {
    match (n.x != 0.0, n.y != 0.0, n.z != 0.0) {
        (true, false, false) => Some(0),
        (false, true, false) => Some(1),
        (false, false, true) => Some(2),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hit::spawn_ray;
    use crate::test_util::lcg;

    #[test]
    fn constructor_rejects_bad_input() {
        assert_eq!(
            Plane::new(Vec3::ZERO, Vec3::ZERO),
            Err(GeometryError::Degenerate)
        );
        assert_eq!(
            Plane::new(Vec3::ZERO, Vec3::new(0.0, f32::NAN, 1.0)),
            Err(GeometryError::NonFinite)
        );
        assert_eq!(
            Plane::new(Vec3::splat(f32::INFINITY), Vec3::Z),
            Err(GeometryError::NonFinite)
        );
        let p = Plane::new(Vec3::ZERO, Vec3::new(0.0, -7.0, 0.0)).unwrap();
        assert_eq!(p.normal(), Vec3::new(0.0, -1.0, 0.0));
        assert_eq!(p.axis(), Some(1));
        let q = Plane::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)).unwrap();
        assert!((q.normal().length() - 1.0).abs() <= gamma(3));
        assert_eq!(q.axis(), None);
    }

    #[test]
    fn basic_hit_and_faces() {
        let p = Plane::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z).unwrap();
        let h = p
            .intersect(&Ray::new(
                Vec3::new(1.0, 3.0, 5.0),
                Vec3::new(0.0, 0.0, -2.0),
            ))
            .unwrap();
        assert_eq!(h.t, 1.5);
        assert_eq!(h.point, Vec3::new(1.0, 3.0, 2.0));
        assert_eq!(h.point_error, Vec3::ZERO);
        assert_eq!(h.normal, Vec3::Z);
        assert!(h.front_face);
        assert_eq!(h.uv, Vec2::new(1.0, 3.0));
        let back = p
            .intersect(&Ray::new(Vec3::new(1.0, 3.0, -5.0), Vec3::Z))
            .unwrap();
        assert!(!back.front_face);
        assert_eq!(back.t, 7.0);
    }

    #[test]
    fn parallel_rays_miss_in_plane_or_not() {
        // P1: d·N = 0 exactly, both off the plane and in it (0/0 would be NaN).
        let p = Plane::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z).unwrap();
        assert!(p.intersect(&Ray::new(Vec3::ZERO, Vec3::X)).is_none());
        assert!(
            p.intersect(&Ray::new(
                Vec3::new(0.0, 0.0, 2.0),
                Vec3::new(1.0, -1.0, 0.0)
            ))
            .is_none()
        );
        let tilted = Plane::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)).unwrap();
        // (1, -1, 0)·N is exactly zero for the rounded normal (its x and y are equal).
        assert!(
            tilted
                .intersect(&Ray::new(Vec3::ZERO, Vec3::new(1.0, -1.0, 0.0)))
                .is_none()
        );
        assert!(
            tilted
                .intersect(&Ray::new(
                    Vec3::new(3.0, 0.0, 0.0),
                    Vec3::new(-2.0, 2.0, 5.0)
                ))
                .is_none()
        );
    }

    #[test]
    fn interval_is_respected() {
        let p = Plane::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z).unwrap();
        let o = Vec3::ZERO;
        // Hit at t = 2 exactly.
        assert!(
            p.intersect(&Ray::with_interval(o, Vec3::Z, 0.0, 2.0))
                .is_some()
        );
        assert!(
            p.intersect(&Ray::with_interval(o, Vec3::Z, 2.0, 3.0))
                .is_none()
        );
        assert!(
            p.intersect(&Ray::with_interval(o, Vec3::Z, 0.0, 2.0f32.next_down()))
                .is_none()
        );
        // Behind the origin.
        assert!(p.intersect(&Ray::new(o, -Vec3::Z)).is_none());
        // Origin on the plane: t = 0 is excluded.
        assert!(
            p.intersect(&Ray::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z))
                .is_none()
        );
    }

    #[test]
    fn non_finite_and_invalid_rays_never_hit() {
        let planes = [
            Plane::new(Vec3::ZERO, Vec3::Z).unwrap(),
            Plane::new(Vec3::ONE, Vec3::new(0.3, -0.2, 0.9)).unwrap(),
        ];
        let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
        for p in &planes {
            for b in bad {
                let mut r = Ray::new(Vec3::new(0.1, 0.2, 5.0), Vec3::new(0.0, 0.0, -1.0));
                r.origin.x = b;
                assert!(p.intersect(&r).is_none());
                let mut r = Ray::new(Vec3::new(0.1, 0.2, 5.0), Vec3::new(0.0, 0.0, -1.0));
                r.direction.y = b;
                assert!(p.intersect(&r).is_none());
                let mut r = Ray::new(Vec3::new(0.1, 0.2, 5.0), Vec3::new(0.0, 0.0, -1.0));
                // Whatever the special bound, a reported hit lies in the interval.
                r.t_max = b;
                if let Some(h) = p.intersect(&r) {
                    assert!(r.contains(h.t), "{r:?} {h:?}");
                }
                r.t_min = b;
                if let Some(h) = p.intersect(&r) {
                    assert!(r.contains(h.t), "{r:?} {h:?}");
                }
            }
            assert!(p.intersect(&Ray::new(Vec3::ONE, Vec3::ZERO)).is_none());
            // A huge origin overflowing the point computation gives no hit, not a NaN hit.
            let r = Ray::new(Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX));
            if let Some(h) = p.intersect(&r) {
                assert!(h.point.is_finite() && h.point_error.is_finite());
            }
        }
    }

    #[test]
    fn axis_aligned_hits_are_snapped_at_any_scale() {
        for &(z0, far) in &[(0.1f32, 1.0f32), (1.0e5, 1.0e5), (-3.3e6, 1.0e6)] {
            let p = Plane::new(Vec3::new(7.0, -1.0, z0), Vec3::new(0.0, 0.0, -4.0)).unwrap();
            let mut s = 1u64;
            for _ in 0..1000 {
                let o = Vec3::new(lcg(&mut s) * far, lcg(&mut s) * far, z0 + far);
                let d = Vec3::new(lcg(&mut s) - 0.5, lcg(&mut s) - 0.5, -lcg(&mut s) - 0.01);
                let h = p.intersect(&Ray::new(o, d)).unwrap();
                assert_eq!(h.point.z, z0);
                assert_eq!(h.point_error, Vec3::ZERO);
                assert!(h.front_face == (d.z > 0.0));
                // The spawned ray leaves to the requested side and does not re-hit.
                for w in [d, -d, Vec3::new(1.0, 0.0, 0.5), Vec3::new(1.0, 0.0, -0.5)] {
                    let sr = spawn_ray(&h, w);
                    assert!(p.intersect(&sr).is_none());
                }
            }
        }
    }

    #[test]
    fn general_planes_reproject_within_the_bound_and_spawn_cleanly() {
        let mut s = 7u64;
        let mut max_rel = 0.0f64;
        for i in 0..4000 {
            let scale = [1.0f32, 1.0e3, 1.0e5, 1.0e6][i % 4];
            let p0 = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * scale;
            let n = Vec3::new(lcg(&mut s) - 0.5, lcg(&mut s) - 0.5, lcg(&mut s) - 0.5);
            let Ok(plane) = Plane::new(p0, n) else {
                continue;
            };
            let target = p0
                + plane.tangents().0 * (lcg(&mut s) - 0.5) * scale
                + plane.tangents().1 * (lcg(&mut s) - 0.5) * scale;
            let o =
                target + Vec3::new(lcg(&mut s) - 0.5, lcg(&mut s) - 0.5, lcg(&mut s) - 0.5) * scale;
            let Some(h) = plane.intersect(&Ray::new(o, target - o)) else {
                continue;
            };
            // Exact distance (f64) of the reported point to the plane defined by the stored
            // f32 point and normal, against the bound along the normal.
            let dist = plane.signed_distance_f64(h.point).abs();
            let bound = h
                .point_error
                .as_dvec3()
                .dot(plane.normal().abs().as_dvec3());
            assert!(dist <= bound, "dist {dist} > bound {bound}");
            max_rel = max_rel.max(bound / (h.point.length() as f64).max(1e-30));
            for w in [plane.normal(), -plane.normal()] {
                let sr = spawn_ray(&h, w + plane.tangents().0 * 0.7);
                assert!(plane.intersect(&sr).is_none(), "re-hit at {h:?}");
            }
            assert!((h.normal.length() - 1.0).abs() <= gamma(3));
        }
        // The bound is a few ulps of the coordinates.
        assert!(max_rel < 1.0e-5, "{max_rel}");
    }

    #[test]
    fn uv_are_in_plane_coordinates() {
        let plane = Plane::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 1.0, 1.0)).unwrap();
        let (tu, tv) = plane.tangents();
        assert!((tu.cross(tv) - plane.normal()).length() < 1e-6);
        let target = plane.point() + tu * 2.0 - tv * 0.5;
        let o = target + plane.normal() * 4.0;
        let h = plane.intersect(&Ray::new(o, target - o)).unwrap();
        assert!((h.uv - Vec2::new(2.0, -0.5)).length() < 1e-5, "{:?}", h.uv);
    }
}
