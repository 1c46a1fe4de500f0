//! An `f64` reference for tests and benchmarks.

use super::{TriangleHit, TriangleIntersector};
use crate::ray::Ray;
use glam::{DVec3, Vec3};

/// The watertight algorithm carried out entirely in `f64` on the `f32` inputs: translation,
/// shear, edge functions, `det` and `t`. The translation of `f32` values is exact in `f64`,
/// so its only roundings are in the shear and products (about 2⁻⁵⁰ relative): a reference for
/// `t` and for hit/miss away from edges, 2²⁹ times finer than the `f32` variants. Closed edges,
/// no epsilon (`f64-reference`). Not meant for speed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct F64Reference;

/// Per-ray data of [`F64Reference`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct F64Ray {
    k: [usize; 3],
    shear: DVec3,
}

impl F64Reference {
    /// The `f64` hit distance and barycentrics `(t, b0, b1, b2)` without the interval test
    /// (`None` for mixed edge signs, `det = 0` or an invalid ray). Used by tests that need the
    /// reference `t` unrounded.
    #[must_use]
    pub fn solve(ray: &Ray, v: &[Vec3; 3]) -> Option<(f64, [f64; 3])> {
        let pre = Self.prepare(ray)?;
        Self::solve_prepared(&pre, ray, v)
    }

    fn solve_prepared(pre: &F64Ray, ray: &Ray, v: &[Vec3; 3]) -> Option<(f64, [f64; 3])> {
        let o = ray.origin.as_dvec3();
        let [kx, ky, kz] = pre.k;
        let proj = |p: Vec3| {
            let a = p.as_dvec3() - o;
            (
                a[kx] - pre.shear.x * a[kz],
                a[ky] - pre.shear.y * a[kz],
                pre.shear.z * a[kz],
            )
        };
        let (ax, ay, az) = proj(v[0]);
        let (bx, by, bz) = proj(v[1]);
        let (cx, cy, cz) = proj(v[2]);
        let e0 = cx * by - cy * bx;
        let e1 = ax * cy - ay * cx;
        let e2 = bx * ay - by * ax;
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        let det = e0 + e1 + e2;
        if !(det != 0.0 && det.is_finite()) {
            return None;
        }
        let t = (e0 * az + e1 * bz + e2 * cz) / det;
        t.is_finite().then(|| (t, [e0 / det, e1 / det, e2 / det]))
    }
}

impl TriangleIntersector for F64Reference {
    type Prepared = F64Ray;

    fn name(&self) -> &'static str {
        "f64-reference"
    }

    fn prepare(&self, ray: &Ray) -> Option<F64Ray> {
        if !ray.is_valid() {
            return None;
        }
        let [kx, ky, kz] = super::projection_axes(ray.direction);
        let d = ray.direction.as_dvec3();
        Some(F64Ray {
            k: [kx, ky, kz],
            shear: DVec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
        })
    }

    fn intersect_prepared(&self, pre: &F64Ray, ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit> {
        let (t, b) = Self::solve_prepared(pre, ray, v)?;
        let t32 = t as f32;
        (ray.contains(t32) && !super::degenerate_or_coplanar(ray, v)).then(|| TriangleHit {
            t: t32,
            b1: b[1] as f32,
            b2: b[2] as f32,
            ng: super::geometric_normal(v, (v[1] - v[0]).cross(v[2] - v[0])),
            front_face: {
                let n = (v[1] - v[0]).as_dvec3().cross((v[2] - v[0]).as_dvec3());
                n.dot(ray.direction.as_dvec3()) < 0.0
            },
        })
    }
}
