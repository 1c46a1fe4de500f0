//! Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013).

use super::{TriangleHit, TriangleIntersector};
use crate::float::diff_of_products_exact_sign;
use crate::ray::Ray;
use glam::Vec3;

/// Per-ray data of the watertight test: the axis permutation that makes the largest direction
/// component `z`, and the shear that maps the ray to the `+z` axis through the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WatertightRay {
    /// Permuted axes `(kx, ky, kz)`; `kz = argmax |d_i|` (ties: lowest index), `kx, ky` follow
    /// cyclically and are swapped when `d_kz < 0` so that the permutation and the scaling by
    /// `1/d_kz` together preserve orientation.
    pub k: [usize; 3],
    /// Shear `(d_kx/d_kz, d_ky/d_kz, 1/d_kz)`.
    pub shear: Vec3,
}

impl WatertightRay {
    /// Prepares `ray`; `None` for an invalid ray.
    #[inline]
    #[must_use]
    pub fn new(ray: &Ray) -> Option<Self> {
        if !ray.is_valid() {
            return None;
        }
        let d = ray.direction;
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            core::mem::swap(&mut kx, &mut ky);
        }
        Some(Self {
            k: [kx, ky, kz],
            shear: Vec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
        })
    }

    /// The three vertices projected with [`WatertightRay::project`]: `([x'], [y'], [z'])`.
    #[inline]
    fn project_triangle(&self, origin: Vec3, v: &[Vec3; 3]) -> ([f32; 3], [f32; 3], [f32; 3]) {
        let (ax, ay, az) = self.project(origin, v[0]);
        let (bx, by, bz) = self.project(origin, v[1]);
        let (cx, cy, cz) = self.project(origin, v[2]);
        ([ax, bx, cx], [ay, by, cy], [az, bz, cz])
    }

    /// The sheared 2-D coordinates of `p − o` and its scaled depth `(x', y', z')`. Plain `f32`
    /// operations (never fused), so the result is a deterministic function of the vertex: a
    /// vertex shared by several triangles projects to the same point in all of them.
    #[inline]
    fn project(&self, origin: Vec3, p: Vec3) -> (f32, f32, f32) {
        let a = p - origin;
        let [kx, ky, kz] = self.k;
        let z = a[kz];
        (
            a[kx] - self.shear.x * z,
            a[ky] - self.shear.y * z,
            self.shear.z * z,
        )
    }
}

/// The watertight test with **exact edge signs**: the three 2-D edge functions are `f64`
/// differences of `f64` products of the sheared `f32` coordinates. Each product is exact, so
/// the single rounding of the difference keeps the exact sign, and zero means exactly on the
/// edge. `det`, `t` and the barycentrics are computed in `f64` and rounded once.
///
/// Edges and vertices are **closed**: a point exactly on an edge is inside. Mixed signs or
/// `det = 0` (ray in the triangle's plane, or a degenerate triangle) give no hit. This is the
/// default intersector; it handles triangles from `1e-20` to `1e20` (f64 has the range).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Watertight;

/// The watertight test as in pbrt-v3: edge functions in `f32`, recomputed in `f64` only when one
/// of them is exactly zero. Sound by monotone rounding (an `f32` difference of rounded products
/// has the correct sign or is zero), provided no product overflows or underflows: very large
/// (≳ 1e19) or very small (≲ 1e-19) triangles can be missed. Kept for the cost/accuracy
/// comparison (`watertight-f32`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WatertightF32;

#[inline]
fn finish_exact(ray: &Ray, edges: [f64; 3], z: [f32; 3], v: &[Vec3; 3]) -> Option<TriangleHit> {
    let [e0, e1, e2] = edges;
    let has_neg = e0 < 0.0 || e1 < 0.0 || e2 < 0.0;
    let has_pos = e0 > 0.0 || e1 > 0.0 || e2 > 0.0;
    if has_neg && has_pos {
        return None;
    }
    let det = e0 + e1 + e2;
    if !(det != 0.0 && det.is_finite()) {
        return None;
    }
    let t_scaled = e0 * z[0] as f64 + e1 * z[1] as f64 + e2 * z[2] as f64;
    let t = (t_scaled / det) as f32;
    if !ray.contains(t) || super::degenerate_or_coplanar(ray, v) {
        return None;
    }
    let inv = 1.0 / det;
    Some(TriangleHit {
        t,
        b1: (e1 * inv) as f32,
        b2: (e2 * inv) as f32,
        ng: (v[1] - v[0]).cross(v[2] - v[0]),
        // det = −2·(signed area of the projected triangle): positive when the triangle is
        // clockwise in the sheared plane, i.e. when its normal opposes the ray.
        front_face: det > 0.0,
    })
}

impl TriangleIntersector for Watertight {
    type Prepared = WatertightRay;

    fn name(&self) -> &'static str {
        "watertight"
    }

    #[inline]
    fn prepare(&self, ray: &Ray) -> Option<WatertightRay> {
        WatertightRay::new(ray)
    }

    #[inline]
    fn intersect_prepared(
        &self,
        pre: &WatertightRay,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        let ([ax, bx, cx], [ay, by, cy], z) = pre.project_triangle(ray.origin, v);
        let edges = [
            diff_of_products_exact_sign(cx, by, cy, bx),
            diff_of_products_exact_sign(ax, cy, ay, cx),
            diff_of_products_exact_sign(bx, ay, by, ax),
        ];
        finish_exact(ray, edges, z, v)
    }
}

impl TriangleIntersector for WatertightF32 {
    type Prepared = WatertightRay;

    fn name(&self) -> &'static str {
        "watertight-f32"
    }

    #[inline]
    fn prepare(&self, ray: &Ray) -> Option<WatertightRay> {
        WatertightRay::new(ray)
    }

    #[inline]
    fn intersect_prepared(
        &self,
        pre: &WatertightRay,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        let ([ax, bx, cx], [ay, by, cy], [az, bz, cz]) = pre.project_triangle(ray.origin, v);
        let mut u = cx * by - cy * bx;
        let mut w = ax * cy - ay * cx;
        let mut s = bx * ay - by * ax;
        if u == 0.0 || w == 0.0 || s == 0.0 {
            u = diff_of_products_exact_sign(cx, by, cy, bx) as f32;
            w = diff_of_products_exact_sign(ax, cy, ay, cx) as f32;
            s = diff_of_products_exact_sign(bx, ay, by, ax) as f32;
        }
        if (u < 0.0 || w < 0.0 || s < 0.0) && (u > 0.0 || w > 0.0 || s > 0.0) {
            return None;
        }
        let det = u + w + s;
        if !(det != 0.0 && det.is_finite()) {
            return None;
        }
        let t_scaled = u * az + w * bz + s * cz;
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        let (b1, b2) = (w * inv, s * inv);
        (ray.contains(t)
            && b1.is_finite()
            && b2.is_finite()
            && !super::degenerate_or_coplanar(ray, v))
        .then(|| TriangleHit {
            t,
            b1,
            b2,
            ng: (v[1] - v[0]).cross(v[2] - v[0]),
            front_face: det > 0.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::TriangleVariant;

    #[test]
    fn shared_edge_of_two_triangles_is_closed() {
        // Quad split on its diagonal; rays through exact points of the diagonal.
        let a = Vec3::new(0.0, 0.0, 0.0);
        let b = Vec3::new(1.0, 0.0, 0.0);
        let c = Vec3::new(1.0, 1.0, 0.0);
        let d = Vec3::new(0.0, 1.0, 0.0);
        let t1 = [a, b, c];
        let t2 = [a, c, d];
        for i in 1..64 {
            let s = i as f32 / 64.0;
            let target = Vec3::new(s, s, 0.0);
            let origin = Vec3::new(0.1 * s - 3.3, 7.77 - s, 9.1);
            let ray = Ray::new(origin, target - origin);
            let n = [&t1, &t2]
                .iter()
                .filter(|t| Watertight.intersect(&ray, t).is_some())
                .count();
            assert!(n >= 1, "leak at s = {s}");
        }
    }

    #[test]
    fn extreme_scales_give_correct_t() {
        for s in [1.0e-20f32, 1.0e-10, 1.0, 1.0e18, 1.0e20] {
            let tri = [Vec3::ZERO, Vec3::new(s, 0.0, 0.0), Vec3::new(0.0, s, 0.0)];
            let o = Vec3::new(s / 3.0, s / 3.0, s);
            let ray = Ray::new(o, Vec3::new(0.0, 0.0, -1.0));
            let h = Watertight
                .intersect(&ray, &tri)
                .unwrap_or_else(|| panic!("miss at {s}"));
            assert!(((h.t - s) / s).abs() < 1e-6, "s = {s}: t = {}", h.t);
            assert!(h.t.is_finite());
        }
    }

    #[test]
    fn in_plane_and_degenerate_give_no_hit() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let in_plane = Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X);
        let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let point = [Vec3::ONE; 3];
        let through = Ray::new(Vec3::new(0.5, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
        for v in TriangleVariant::ALL {
            assert!(v.intersect(&in_plane, &tri).is_none(), "{}", v.name());
            assert!(v.intersect(&through, &line).is_none(), "{}", v.name());
            assert!(v.intersect(&through, &point).is_none(), "{}", v.name());
        }
    }
}
