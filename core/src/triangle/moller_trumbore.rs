//! Möller–Trumbore 1997, in `f32`.

use super::{TriangleHit, TriangleIntersector, TriangleLanes, finish};
use crate::ray::Ray;
use crate::sealed::Inside;
use crate::simd::{F32x4, V3x4};
use crate::tolerance::MOLLER_TRUMBORE_DET_EPSILON;
use glam::Vec3;

/// Möller–Trumbore ("Fast, minimum storage ray/triangle intersection", 1997).
///
/// Valid hit: `|det| > det_epsilon`, `t ∈ (t_min, t_max]`, `b1 ≥ 0`, `b2 ≥ 0`, `b1 + b2 ≤ 1`.
/// **Not watertight:** the third edge is tested as a rounded sum and neighbouring triangles
/// evaluate a shared edge from different base vertices, so rays through shared edges and
/// vertices can miss both triangles (the test suite counts these leaks). Its determinant
/// `e1·(d × e2)` is `f32` products: its sign ([`TriangleHit::front_face`]) is exact only
/// while they stay in the normal range (as [`super::Cramer`]'s).
///
/// **In an acceleration structure** (BVH, wide BVH, grid, kd-tree) only the *weak form* of
/// agreement with a brute-force loop holds, everywhere: the structure's closest hit is a hit
/// this test reports for that triangle, and it is no nearer than the brute-force loop's
/// closest hit (it may be farther, or missing). Equal answers are not promised, since the
/// inexact edges can report a hit outside the triangle's bounding box, which a structure
/// (rightly) never visits for that ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MollerTrumbore {
    /// Determinant threshold: `|det| ≤ det_epsilon` means "parallel or degenerate". Absolute,
    /// in length² × |direction|. `0.0` rejects only an exactly zero (or NaN) determinant.
    pub det_epsilon: f32,
}

impl MollerTrumbore {
    /// The paper's variant, with [`MOLLER_TRUMBORE_DET_EPSILON`] (`moller-trumbore`).
    pub const CLASSIC: Self = Self {
        det_epsilon: MOLLER_TRUMBORE_DET_EPSILON,
    };
    /// No epsilon: only `det = 0` is rejected (`moller-trumbore-noeps`).
    pub const NO_EPSILON: Self = Self { det_epsilon: 0.0 };
}

impl Default for MollerTrumbore {
    fn default() -> Self {
        Self::CLASSIC
    }
}

impl TriangleIntersector for MollerTrumbore {
    type Prepared = ();

    fn name(&self) -> &'static str {
        if self.det_epsilon > 0.0 {
            "moller-trumbore"
        } else {
            "moller-trumbore-noeps"
        }
    }

    #[inline(always)]
    fn prepare(&self, ray: &Ray) -> Option<()> {
        ray.is_valid().then_some(())
    }

    #[inline(always)]
    fn intersect_prepared(&self, _: &(), ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit> {
        let e1 = v[1] - v[0];
        let e2 = v[2] - v[0];
        let p = ray.direction.cross(e2);
        let det = e1.dot(p);
        // Negated comparison so that a NaN determinant is rejected too.
        if !(det.abs() > self.det_epsilon) {
            return None;
        }
        let inv_det = 1.0 / det;
        let s = ray.origin - v[0];
        let b1 = s.dot(p) * inv_det;
        if !(0.0..=1.0).contains(&b1) {
            return None;
        }
        let q = s.cross(e1);
        let b2 = ray.direction.dot(q) * inv_det;
        if !(b2 >= 0.0 && b1 + b2 <= 1.0) {
            return None;
        }
        let t = e2.dot(q) * inv_det;
        // det = e1·(d × e2) = −d·(e1 × e2): positive when d opposes ng.
        finish(ray, t, b1, b2, e1.cross(e2), det > 0.0, v)
    }

    /// The determinant and barycentric rejections of `intersect_prepared`, lane by lane with
    /// the same operations in the same order (glam's `dot`/`cross` formulas, never fused), so
    /// a lane is reported exactly when the scalar test returns `None` before its `t` check.
    #[inline(always)]
    fn certain_misses(&self, _: Inside, _: &(), ray: &Ray, lanes: &TriangleLanes) -> u32 {
        let [p0, p1, p2] = &lanes.v;
        let (v0, v1, v2) = (V3x4::load(p0), V3x4::load(p1), V3x4::load(p2));
        let (e1, e2) = (v1.sub(v0), v2.sub(v0));
        let d = V3x4::splat(ray.direction);
        let p = d.cross(e2);
        let det = e1.dot(p);
        let inv_det = F32x4::splat(1.0).div(det);
        let s = V3x4::splat(ray.origin).sub(v0);
        let b1 = s.dot(p).mul(inv_det);
        let q = s.cross(e1);
        let b2 = d.dot(q).mul(inv_det);
        let (zero, one) = (F32x4::splat(0.0), F32x4::splat(1.0));
        let keep = det.abs().gt_bits(F32x4::splat(self.det_epsilon))
            & b1.ge_bits(zero)
            & one.ge_bits(b1)
            & b2.ge_bits(zero)
            & one.ge_bits(b1.add(b2));
        !keep & 0xF
    }
}
