//! Cramer's rule on the 3×3 system `b1·e1 + b2·e2 − t·d = o − v0`, in `f32`.

use super::{TriangleHit, TriangleIntersector, finish};
use crate::ray::Ray;
use glam::Vec3;

/// The textbook barycentric form: solve `b1·e1 + b2·e2 − t·d = s` (`e1 = v1 − v0`,
/// `e2 = v2 − v0`, `s = o − v0`) by Cramer's rule, each unknown a ratio of scalar triple
/// products over `det = −d·(e1 × e2)`:
/// `t = (e1 × e2)·s / det`, `b1 = s·(d × e2) / det`, `b2 = d·(s × e1) / det`.
///
/// Unlike Möller–Trumbore it evaluates `t` from the plane normal rather than from the reused
/// cross product `q`, which changes its rounding behaviour, not its guarantees: **not
/// watertight**; only `det = 0` (or NaN) is rejected, without an epsilon. Domain: every
/// product is `f32`, so `det`'s sign (and [`TriangleHit::front_face`]) is the exact one's only
/// while `|e1 × e2|` and `|d·(e1 × e2)|` stay in the normal range; below it (a configuration
/// at the 1e-15 scale seen along a 1e-15 direction) the rounding is absolute and the sign
/// may flip.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cramer;

impl TriangleIntersector for Cramer {
    type Prepared = ();

    fn name(&self) -> &'static str {
        "cramer"
    }

    #[inline(always)]
    fn prepare(&self, ray: &Ray) -> Option<()> {
        ray.is_valid().then_some(())
    }

    #[inline(always)]
    fn intersect_prepared(&self, _: &(), ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit> {
        let e1 = v[1] - v[0];
        let e2 = v[2] - v[0];
        let ng = e1.cross(e2);
        let det = -ray.direction.dot(ng);
        if !(det != 0.0 && det.is_finite()) {
            return None;
        }
        let s = ray.origin - v[0];
        let b1 = s.dot(ray.direction.cross(e2)) / det;
        let b2 = ray.direction.dot(s.cross(e1)) / det;
        if !(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0) {
            return None;
        }
        let t = ng.dot(s) / det;
        finish(ray, t, b1, b2, ng, det > 0.0, v)
    }
}
