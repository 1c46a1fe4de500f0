//! Spheres: the numerically stable quadratic of Haines, Günther and Akenine-Möller
//! ("Precision Improvements for Ray/Sphere Intersection", Ray Tracing Gems ch. 7), in `f32`.
//!
//! With `f = o − C`, `a = d·d`, `b' = f·d`, `c = f·f − r²`:
//! * **Discriminant without cancellation:** `Δ' = b'² − a·c = a·(r² − |l|²)` where
//!   `l = f − (b'/a)·d` is the vector from the centre to the closest point of the line; it is
//!   evaluated as `a·(r + |l|)·(r − |l|)` (pbrt-v4). The textbook `b'² − a·c` loses everything
//!   when the sphere is small or far (`b'² ≈ a·c`).
//! * **Roots without cancellation:** `q = −(b' + sign(b')·√Δ')`, roots `c/q` and `q/a`
//!   (Numerical Recipes): no subtraction of nearly equal values even when one root is near 0
//!   (a ray spawned on the sphere).
//! * **Direction scaling:** the direction is first scaled by a power of two (exact) so that its
//!   largest component lies in `[0.5, 1)`; `a = d·d` then never overflows or underflows, and
//!   `t` is scaled back exactly. `|d|` from `1e-30` to `1e30` gives the same `t·|d|`.
//!
//! **Domain of the bounds.** The roots satisfy `|o + t·d − C|² = r²` within their residual
//! bound, and `t` is within its bound of the exact root, while `|o − C|`, `r` and `|t·d|` lie
//! in `[10⁻¹⁵, 10¹⁵]` and `10⁻³⁰ ≤ |t| ≤ 10³⁰`; hit or miss is decided exactly outside the
//! tangency band `| |l| − r | ≤ 64·2⁻²⁴·(|o − C| + r)` (inside it, the `f32` rounding of the
//! closest approach `|l|` decides). Outside that range the `f32` squares under- or overflow:
//! the answer is `None` or a `t` without the bound, never a panic or a NaN. The fuzz property
//! `ray_sphere` checks exactly this domain.
//!
//! Hit points are re-projected onto the sphere, `C + r·(p − C)/|p − C|`, with the error bound
//! `gamma(6)·(|C_i| + |r·(p − C)_i/|p − C||)` per component: pbrt's `gamma(5)·|p|` for its
//! centred object-space spheres, plus one rounding for adding the centre. Like every bound in
//! halfray it is the distance to *the surface* (what spawned rays need), not to the exact ray
//! hit.
//!
//! Measured by the test `far_small_sphere_stable_vs_naive` (20 000 rays from the origin aimed
//! inside the inner 90 % of a unit sphere at distance `D`; error of `t` against an `f64`
//! evaluation of the same `f32` inputs, in units of 2⁻²³ relative):
//!
//! | `D/r` | stable: median / p99.9 / max | naive: median / p99.9 / max | naive false misses |
//! |---|---|---|---|
//! | 1e4 | 0.28 / 1.23 / 1.35 | 819 / 3402 / 3477 | 3999 / 20000 |
//! | 1e5 | 0.46 / 1.68 / 1.82 | 81 / 3467 / 4255 | 9053 / 20000 |

use crate::error::GeometryError;
use crate::float::{gamma, sqrt};
use crate::getters::getters;
use crate::hit::Hit;
use crate::ray::Ray;
use core::f32::consts::{PI, TAU};
use glam::{Vec2, Vec3};

/// A sphere with finite centre and finite positive radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    center: Vec3,
    radius: f32,
}

/// `(d·2⁻ᵉ, e)` with `max|d_i·2⁻ᵉ| ∈ [0.5, 1)`; exact (power-of-two scaling), except that
/// components more than 2¹²⁵ times smaller than the largest may lose bits to subnormals.
#[inline]
fn normalize_scale(d: Vec3) -> (Vec3, i32) {
    let m = d.abs().max_element();
    let (_, e) = libm::frexpf(m);
    (
        Vec3::new(
            libm::ldexpf(d.x, -e),
            libm::ldexpf(d.y, -e),
            libm::ldexpf(d.z, -e),
        ),
        e,
    )
}

/// `u = φ/2π` kept in `[0, 1)`: a `φ` just below `0` plus `2π`, or a `φ` just below `2π`
/// divided by it, can round to exactly `1`, which is the seam at `0` (`φ` is periodic), so `1`
/// (and NaN) maps to `0`.
#[inline]
pub(crate) fn seam_wrapped(u: f32) -> f32 {
    if u < 1.0 { u } else { 0.0 }
}

impl Sphere {
    /// A sphere of `radius` around `center`.
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`] for a non-finite centre or radius,
    /// [`GeometryError::Degenerate`] for `radius ≤ 0`.
    pub fn new(center: Vec3, radius: f32) -> Result<Self, GeometryError> {
        if !center.is_finite() || !radius.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        if !(radius > 0.0) {
            return Err(GeometryError::Degenerate);
        }
        Ok(Self { center, radius })
    }

    getters! {
        /// Centre, world units.
        center: Vec3;
        /// Radius, world units.
        radius: f32;
    }

    /// Both roots `t0 ≤ t1` of the ray's line against the sphere (not clipped to the ray's
    /// interval), by the stable formulation (module documentation). A tangent line (`Δ' = 0`)
    /// gives the double root twice, `t0 == t1`. `None` for a miss (`Δ' < 0`), an invalid ray,
    /// or when a root overflows `f32`.
    #[must_use]
    pub fn roots(&self, ray: &Ray) -> Option<(f32, f32)> {
        if !ray.is_valid() {
            return None;
        }
        let (d, e) = normalize_scale(ray.direction);
        // The origin offset and the radius share one power-of-two scale (exact), so that
        // `|l|`, `r² − |l|²` and `f·f` neither underflow for tiny spheres nor overflow for
        // huge distances; `t` scales by the same factor.
        let f = ray.origin - self.center;
        let (_, ef) = libm::frexpf(f.abs().max_element().max(self.radius));
        let f = Vec3::new(
            libm::ldexpf(f.x, -ef),
            libm::ldexpf(f.y, -ef),
            libm::ldexpf(f.z, -ef),
        );
        let r = libm::ldexpf(self.radius, -ef);
        let e = e - ef;
        let a = d.dot(d);
        let b = f.dot(d);
        let l = f - d * (b / a);
        let ll = l.length();
        let disc = a * ((r + ll) * (r - ll));
        if !(disc >= 0.0) || !disc.is_finite() {
            return None;
        }
        let (t0, t1) = if disc == 0.0 {
            let t = -b / a;
            (t, t)
        } else {
            let c = f.dot(f) - r * r;
            let q = -(b + libm::copysignf(sqrt(disc), b));
            let (x, y) = (c / q, q / a);
            if x <= y { (x, y) } else { (y, x) }
        };
        let (t0, t1) = (libm::ldexpf(t0, -e), libm::ldexpf(t1, -e));
        (t0.is_finite() && t1.is_finite()).then_some((t0, t1))
    }

    /// The nearest root in the ray's `(t_min, t_max]`: the near root when it is in the
    /// interval, otherwise the far one (so an origin inside the sphere gets the far side, and a
    /// ray spawned on the sphere going inward gets the far side only), with the re-projected
    /// hit point and its error bound (module documentation), the outward unit normal, and
    /// `uv = (φ/2π, θ/π)` with `φ = atan2(n_y, n_x) ∈ [0, 2π)` and `θ = acos(n_z) ∈ [0, π]`
    /// (the `z` axis is the pole, as in pbrt). `front_face` is `d·n < 0` (`false` from
    /// inside).
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (t0, t1) = self.roots(ray)?;
        let t = if ray.contains(t0) {
            t0
        } else if ray.contains(t1) {
            t1
        } else {
            return None;
        };
        self.hit_at(ray, t, true)
    }

    /// **Benchmark baseline only — do not use for rendering.** The textbook form in `f32`:
    /// `Δ = b² − 4ac` with `b = 2·f·d`, `t = (−b ∓ √Δ)/2a`, the hit point `o + t·d` with no
    /// re-projection, and `point_error = 0` (this path has no error bound; rays spawned from it
    /// self-intersect, which is part of what the accuracy benchmark shows). Loses the
    /// discriminant for small or far spheres and the near root for rays starting on the
    /// sphere. No direction scaling either: `a = d·d` overflows beyond `|d| ≈ 1.8e19`.
    #[must_use]
    pub fn intersect_naive(&self, ray: &Ray) -> Option<Hit> {
        let (t0, t1) = self.roots_naive(ray)?;
        let t = if ray.contains(t0) {
            t0
        } else if ray.contains(t1) {
            t1
        } else {
            return None;
        };
        self.hit_at(ray, t, false)
    }

    /// The two textbook roots `(−b − √Δ)/2a ≤ (−b + √Δ)/2a` of [`Sphere::intersect_naive`]
    /// (benchmark baseline).
    #[must_use]
    pub fn roots_naive(&self, ray: &Ray) -> Option<(f32, f32)> {
        if !ray.is_valid() {
            return None;
        }
        let d = ray.direction;
        let f = ray.origin - self.center;
        let a = d.dot(d);
        let b = 2.0 * f.dot(d);
        let c = f.dot(f) - self.radius * self.radius;
        let disc = b * b - 4.0 * a * c;
        if !(disc >= 0.0) {
            return None;
        }
        let s = sqrt(disc);
        let (t0, t1) = ((-b - s) / (2.0 * a), (-b + s) / (2.0 * a));
        (t0.is_finite() && t1.is_finite()).then_some((t0, t1))
    }

    fn hit_at(&self, ray: &Ray, t: f32, reproject: bool) -> Option<Hit> {
        let p = ray.origin + ray.direction * t;
        // Scaled by a power of two before `length()`, so that a tiny sphere's `|v|²` does not
        // underflow (a non-unit normal; found by the `ray_sphere` fuzz target) and a huge one's
        // does not overflow.
        // `(o − C) + t·d`, not `p − C`: when the origin is near the centre relative to their
        // magnitudes, `o + t·d` can round to the centre itself (found by the `ray_sphere` fuzz
        // target: r = 1e10 at |C| = 3.7e28, origin at the centre).
        let (v, _) = normalize_scale((ray.origin - self.center) + ray.direction * t);
        let len = v.length();
        // `len = 0` would need the hit to be the centre: impossible for a real hit, but the
        // function stays total.
        if !(len > 0.0) || !len.is_finite() {
            return None;
        }
        let normal = v / len;
        let (point, point_error) = if reproject {
            let w = v * (self.radius / len);
            (self.center + w, (self.center.abs() + w.abs()) * gamma(6))
        } else {
            (p, Vec3::ZERO)
        };
        if !point.is_finite() || !normal.is_finite() {
            return None;
        }
        let mut phi = libm::atan2f(normal.y, normal.x);
        if phi < 0.0 {
            phi += TAU;
        }
        let theta = libm::acosf(normal.z.clamp(-1.0, 1.0));
        Some(Hit {
            t,
            point,
            point_error,
            normal,
            uv: Vec2::new(seam_wrapped(phi / TAU), theta / PI),
            front_face: ray.direction.dot(normal) < 0.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hit::spawn_ray;
    use crate::test_util::{lcg, unit_vec};
    use glam::DVec3;
    use std::vec::Vec;

    /// `u = φ/2π` stays below 1 at the seam: a hit at `φ = −10⁻⁹` (just below the `+x` axis),
    /// where `φ + 2π` rounds to `2π`, has `u = 0`; the ellipsoid's `u` the same.
    #[test]
    fn u_stays_below_one_at_the_seam() {
        let ray = Ray::new(Vec3::new(5.0, -1.0e-9, 0.0), -Vec3::X);
        let h = Sphere::new(Vec3::ZERO, 1.0)
            .unwrap()
            .intersect(&ray)
            .unwrap();
        assert!((0.0..1.0).contains(&h.uv.x), "sphere u {}", h.uv.x);
        let e = crate::quadric::Ellipsoid::new(Vec3::ZERO, Vec3::ONE).unwrap();
        let h = e.intersect(&ray).unwrap();
        assert!((0.0..1.0).contains(&h.uv.x), "ellipsoid u {}", h.uv.x);
    }

    /// Reference roots of the exact `f32` inputs, in `f64` (stable form; the `f64` rounding is
    /// ~2⁻²⁹ of an `f32` ulp for these inputs).
    fn reference_roots(s: &Sphere, ray: &Ray) -> Option<(f64, f64)> {
        let o = ray.origin.as_dvec3();
        let d = ray.direction.as_dvec3();
        let c = s.center().as_dvec3();
        let r = s.radius() as f64;
        let f: DVec3 = o - c;
        let a = d.dot(d);
        let b = f.dot(d);
        let l = f - d * (b / a);
        let ll = l.length();
        let disc = a * (r + ll) * (r - ll);
        if disc < 0.0 {
            return None;
        }
        let q = -(b + disc.sqrt().copysign(b));
        let cc = f.dot(f) - r * r;
        let (x, y) = (cc / q, q / a);
        Some((x.min(y), x.max(y)))
    }

    fn ulps_rel(t: f32, reference: f64) -> f64 {
        ((t as f64 - reference) / reference).abs() / f32::EPSILON as f64
    }

    /// Normals stay unit from `r = 1e-21` to `1e18` (`|p − C|²` under- or overflows `f32` at
    /// the ends without the scaling).
    #[test]
    fn unit_normals_for_tiny_and_huge_spheres() {
        for r in [2.079_382_8e-21f32, 1e-10, 1.0, 1e18] {
            let s = Sphere::new(Vec3::splat(r), r).unwrap();
            let ray = Ray::new(Vec3::new(-3.0 * r, 1.3 * r, 0.8 * r), Vec3::X);
            let h = s
                .intersect(&ray)
                .unwrap_or_else(|| panic!("r = {r}: roots {:?}", s.roots(&ray)));
            assert!(
                (h.normal.length() - 1.0).abs() < 1e-6,
                "r = {r}: {:?}",
                h.normal
            );
            let dist = (h.point.as_dvec3() - s.center().as_dvec3()).length();
            assert!(
                (dist / f64::from(r) - 1.0).abs() < 1e-5,
                "r = {r}: {dist:e}"
            );
        }
    }

    #[test]
    fn constructor_rejects_bad_input() {
        assert_eq!(Sphere::new(Vec3::ZERO, 0.0), Err(GeometryError::Degenerate));
        assert_eq!(
            Sphere::new(Vec3::ZERO, -1.0),
            Err(GeometryError::Degenerate)
        );
        assert_eq!(
            Sphere::new(Vec3::ZERO, f32::NAN),
            Err(GeometryError::NonFinite)
        );
        assert_eq!(
            Sphere::new(Vec3::ZERO, f32::INFINITY),
            Err(GeometryError::NonFinite)
        );
        assert_eq!(
            Sphere::new(Vec3::new(f32::NAN, 0.0, 0.0), 1.0),
            Err(GeometryError::NonFinite)
        );
    }

    #[test]
    fn plain_hit_from_outside() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, 10.0), 2.0).unwrap();
        let h = s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).unwrap();
        assert_eq!(h.t, 8.0);
        assert_eq!(h.point, Vec3::new(0.0, 0.0, 8.0));
        assert_eq!(h.normal, -Vec3::Z);
        assert!(h.front_face);
        assert_eq!(s.roots(&Ray::new(Vec3::ZERO, Vec3::Z)), Some((8.0, 12.0)));
        assert!((h.uv.y - 1.0).abs() < 1e-6);
        // Both roots are available even when behind the origin.
        assert_eq!(
            s.roots(&Ray::new(Vec3::new(0.0, 0.0, 20.0), Vec3::Z)),
            Some((-12.0, -8.0))
        );
        assert!(
            s.intersect(&Ray::new(Vec3::new(0.0, 0.0, 20.0), Vec3::Z))
                .is_none()
        );
    }

    #[test]
    fn tangent_rays_give_one_double_root() {
        // S1: perpendicular distance exactly r, and r ± 1 ulp.
        let s = Sphere::new(Vec3::ZERO, 1.0).unwrap();
        let ray = Ray::new(Vec3::new(-5.0, 1.0, 0.0), Vec3::X);
        assert_eq!(s.roots(&ray), Some((5.0, 5.0)));
        let h = s.intersect(&ray).unwrap();
        assert_eq!(h.t, 5.0);
        assert_eq!(h.point, Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(h.normal, Vec3::Y);
        let outside = Ray::new(Vec3::new(-5.0, 1.0f32.next_up(), 0.0), Vec3::X);
        assert!(s.roots(&outside).is_none());
        let inside = Ray::new(Vec3::new(-5.0, 1.0f32.next_down(), 0.0), Vec3::X);
        let (t0, t1) = s.roots(&inside).unwrap();
        assert!(t0 < 5.0 && t1 > 5.0 && t1 - t0 < 1e-3, "{t0} {t1}");
        // Tangent with a non-unit, non-axis direction and scaled sphere.
        let s = Sphere::new(Vec3::new(3.0, 3.0, 0.0), 2.0).unwrap();
        let ray = Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::new(4.0, 0.0, 0.0));
        let (t0, t1) = s.roots(&ray).unwrap();
        assert_eq!((t0, t1), (0.75, 0.75));
        assert!(s.intersect(&ray).is_some());
    }

    #[test]
    fn origin_inside_gives_far_root() {
        // S3.
        let s = Sphere::new(Vec3::new(1.0, 2.0, 3.0), 4.0).unwrap();
        let ray = Ray::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 2.0, 0.0));
        let (t0, t1) = s.roots(&ray).unwrap();
        assert_eq!((t0, t1), (-2.0, 2.0));
        let h = s.intersect(&ray).unwrap();
        assert_eq!(h.t, 2.0);
        assert_eq!(h.point, Vec3::new(1.0, 6.0, 3.0));
        assert_eq!(h.normal, Vec3::Y);
        assert!(!h.front_face);
        // Interval ending before the far root: no hit.
        let short = Ray::with_interval(ray.origin, ray.direction, 0.0, 1.9);
        assert!(s.intersect(&short).is_none());
    }

    #[test]
    fn spawned_rays_from_the_surface() {
        // S4: origin on the sphere after offsetting. Outward: miss; inward: far side only.
        let mut st = 3u64;
        let mut checked = 0;
        for &(c, r) in &[
            (Vec3::ZERO, 1.0f32),
            (Vec3::new(1.0e3, -2.0e3, 5.0e2), 1.0),
            (Vec3::new(-7.0, 3.0, 1.0e5), 10.0),
            (Vec3::new(0.0, 0.0, 0.0), 1.0e6),
        ] {
            let s = Sphere::new(c, r).unwrap();
            for _ in 0..2000 {
                let dir = unit_vec(&mut st);
                let o = c - dir * (4.0 * r) + unit_vec(&mut st) * (0.9 * r);
                let Some(h) = s.intersect(&Ray::new(o, c - o)) else {
                    continue;
                };
                checked += 1;
                let n = h.normal;
                // Outward: any direction in the outer hemisphere, including grazing ones.
                let mut w = unit_vec(&mut st);
                if w.dot(n) < 0.0 {
                    w = -w;
                }
                assert!(s.intersect(&spawn_ray(&h, w)).is_none(), "outward re-hit");
                assert!(s.intersect(&spawn_ray(&h, n)).is_none());
                // Inward: the far side only (the offset origin is strictly inside: the near
                // root is negative), matching the f64 far root of the same ray.
                let w_in = -w;
                let sr = spawn_ray(&h, w_in);
                let (near, far) = reference_roots(&s, &sr).expect("reference");
                assert!(near < 0.0 && far > 0.0, "spawned origin not inside");
                let hin = s.intersect(&sr).expect("inward ray must hit the far side");
                // Compare in distance, against ulps of the coordinates (the f32 origin is only
                // known to that), amplified by the conditioning of short grazing chords:
                // `r − |l|` is a cancellation, and dt ∝ r·δ|l| / chord.
                let err = (hin.t as f64 - far).abs() * w_in.length() as f64;
                let scale = (sr.origin.abs().max_element() + r) as f64;
                let chord = far * w_in.length() as f64;
                let cond = 1.0 + 2.0 * r as f64 / chord;
                assert!(
                    err <= 16.0 * f32::EPSILON as f64 * scale * cond,
                    "t {} vs far root {far}: err {err}, sphere {c} {r}",
                    hin.t
                );
                // Reflection: leaves and misses.
                let refl = h.facing_normal();
                let d = (c - o).normalize();
                let rd = d - refl * 2.0 * d.dot(refl);
                assert!(s.intersect(&spawn_ray(&h, rd)).is_none());
            }
        }
        assert!(checked > 7000);
    }

    #[test]
    fn far_small_sphere_stable_vs_naive() {
        // S2: D/r = 1e4 and 1e5. The stable form hits every ray aimed at the inner 90 % of the
        // disc, with t within a few ulps of the f64 reference; the naive form is much worse.
        for &ratio in &[1.0e4f32, 1.0e5] {
            let mut st = 11u64;
            let s = Sphere::new(Vec3::new(ratio * 0.6, -ratio * 0.48, ratio * 0.64), 1.0).unwrap();
            let (mut stable, mut naive, mut naive_misses) = (Vec::new(), Vec::new(), 0);
            for _ in 0..20_000 {
                let aim = s.center() + unit_vec(&mut st) * (0.9 * lcg(&mut st));
                let ray = Ray::new(Vec3::ZERO, aim);
                let (reference, _) = reference_roots(&s, &ray).expect("reference hit");
                let h = s.intersect(&ray).expect("stable form must not miss");
                stable.push(ulps_rel(h.t, reference));
                match s.intersect_naive(&ray) {
                    Some(hn) => naive.push(ulps_rel(hn.t, reference)),
                    None => naive_misses += 1,
                }
            }
            let stat = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                (v[v.len() / 2], v[v.len() * 999 / 1000], v[v.len() - 1])
            };
            let (s_med, s_p999, s_max) = stat(&mut stable);
            let (n_med, n_p999, n_max) = stat(&mut naive);
            std::eprintln!(
                "D/r = {ratio:e}: stable t error (2^-23 rel) median {s_med:.2} p99.9 {s_p999:.2} \
                 max {s_max:.2}; naive median {n_med:.1} p99.9 {n_p999:.1} max {n_max:.1}, \
                 naive misses {naive_misses}/20000"
            );
            assert!(s_max <= 4.0, "stable max {s_max}");
            assert!(n_med > 10.0 * s_med.max(0.5), "naive median {n_med}");
        }
    }

    #[test]
    fn direction_scale_does_not_change_the_hit() {
        // S7: |d| = 1e-6 and 1e6 (and beyond, where a = d·d would overflow unscaled).
        let s = Sphere::new(Vec3::new(0.5, -0.25, 10.0), 2.0).unwrap();
        let o = Vec3::new(0.1, 0.2, -3.0);
        let d = Vec3::new(0.05, -0.03, 1.0);
        let base = s.intersect(&Ray::new(o, d)).unwrap();
        for k in [1.0e-30f32, 1.0e-6, 1.0e6, 1.0e30] {
            let h = s.intersect(&Ray::new(o, d * k)).unwrap();
            let scaled = h.t * k;
            assert!(
                ((scaled - base.t) / base.t).abs() <= 2.0 * f32::EPSILON,
                "k = {k}: {scaled} vs {}",
                base.t
            );
            assert!((h.point - base.point).length() <= 1e-5);
        }
        // Power-of-two scales give bit-identical results.
        for k in [0.5f32.powi(20), 2.0f32.powi(20)] {
            let h = s.intersect(&Ray::new(o, d * k)).unwrap();
            assert_eq!(h.t * k, base.t);
            assert_eq!(h.point, base.point);
        }
    }

    #[test]
    fn degenerate_and_non_finite_rays_never_hit() {
        // S8 and NaN / inf in any field.
        let s = Sphere::new(Vec3::ZERO, 1.0).unwrap();
        assert!(
            s.intersect(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO))
                .is_none()
        );
        assert!(
            s.roots(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO))
                .is_none()
        );
        for b in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for i in 0..3 {
                let mut r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
                r.origin[i] = b;
                assert!(s.intersect(&r).is_none());
                assert!(s.intersect_naive(&r).is_none());
                let mut r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
                r.direction[i] = b;
                assert!(s.intersect(&r).is_none());
            }
            let mut r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
            r.t_min = b;
            // Any hit reported lies in the interval and is finite.
            if let Some(h) = s.intersect(&r) {
                assert!(r.contains(h.t) && h.point.is_finite(), "{r:?} {h:?}");
            }
        }
        // Extreme but finite values: no panic, no non-finite hit.
        let huge = Ray::new(Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX));
        if let Some(h) = s.intersect(&huge) {
            assert!(h.point.is_finite());
        }
        let far = Sphere::new(Vec3::splat(3.0e38), 1.0e38).unwrap();
        if let Some(h) = far.intersect(&Ray::new(Vec3::splat(-3.0e38), Vec3::ONE)) {
            assert!(h.t.is_finite() && h.point.is_finite(), "{h:?}");
        }
    }

    #[test]
    fn reprojected_point_lies_within_its_bound() {
        let mut st = 5u64;
        for &(c, r) in &[
            (Vec3::ZERO, 1.0f32),
            (Vec3::new(1.0e5, 0.0, -1.0e5), 3.0),
            (Vec3::new(1.0, 1.0, 1.0), 1.0e6),
        ] {
            let s = Sphere::new(c, r).unwrap();
            for _ in 0..2000 {
                let o = c + unit_vec(&mut st) * (3.0 * r);
                let aim = c + unit_vec(&mut st) * (0.99 * r);
                let Some(h) = s.intersect(&Ray::new(o, aim - o)) else {
                    continue;
                };
                // Distance to the exact sphere, in f64.
                let dist = ((h.point.as_dvec3() - c.as_dvec3()).length() - r as f64).abs();
                let along_n = h.point_error.as_dvec3().dot(h.normal.abs().as_dvec3());
                assert!(dist <= along_n, "dist {dist} > {along_n}");
                assert!((h.normal.length() - 1.0).abs() < 1e-6);
                assert!(h.uv.x >= 0.0 && h.uv.x <= 1.0 && h.uv.y >= 0.0 && h.uv.y <= 1.0);
            }
        }
    }

    /// The bounds' domain (module docs, *Domain of the bounds*) at its ends: `r` at `2⁻⁴⁹`
    /// and `2⁴⁷` (`|o − C| ≈ 2.06·r`, `|t·d|` from `1.13·r` to `2.87·r`, all within
    /// `[10⁻¹⁵, 10¹⁵]`) and `|d|` at `2⁵⁰`, 1 and `2⁻⁵¹`, which put the near `|t|` down to
    /// `1.8·10⁻³⁰` and the far one up to `9.1·10²⁹` (within `[10⁻³⁰, 10³⁰]`; each of the six
    /// combinations checked to be inside). The roots are within `64·2⁻²⁴·((|o − C| + r)/|d| + |t|)` of
    /// the `f64` roots of the same `f32` inputs ([`reference_roots`]) and satisfy
    /// `|o + t·d − C|² = r²` within `64·2⁻²⁴·(|o − C|² + r² + |t·d|²)` plus the effect of
    /// `t`'s own rounding (the fuzz property's bounds, `K = 64`). Just outside (`r = 2⁻⁶⁰`,
    /// `2⁶⁰`; `|t|` at `2⁻¹¹⁰`) the docs promise only `None` or a non-NaN `t`.
    #[test]
    fn bounds_hold_at_the_ends_of_their_domain() {
        let u = f64::from(crate::float::F32_UNIT_ROUNDOFF);
        let p = |e: i32| 2f32.powi(e);
        let in_domain = |x: f64| (1e-15..=1e15).contains(&x);
        let mut checked = 0;
        for r in [p(-49), p(47)] {
            for dl in [p(50), 1.0, p(-51)] {
                let c = Vec3::new(0.25 * r, -r, 3.0 * r);
                let s = Sphere::new(c, r).unwrap();
                let ray = Ray::new(c + Vec3::new(-2.0 * r, 0.5 * r, 0.0), Vec3::X * dl);
                let (fl, rr, d) = (
                    (ray.origin - c).as_dvec3().length(),
                    f64::from(r),
                    f64::from(dl),
                );
                let (r0, r1) = reference_roots(&s, &ray).unwrap();
                let inside = [fl, rr, r0 * d, r1 * d].into_iter().all(in_domain)
                    && r0 >= 1e-30
                    && r1 <= 1e30;
                assert!(inside, "r = {r:e}, |d| = {dl:e}: not inside the domain");
                let (t0, t1) = s
                    .roots(&ray)
                    .unwrap_or_else(|| panic!("r = {r:e}, |d| = {dl:e}: no roots"));
                for (t, want) in [(t0, r0), (t1, r1)] {
                    let t = f64::from(t);
                    let tol = 64.0 * u * ((fl + rr) / d + want);
                    assert!(
                        (t - want).abs() <= tol,
                        "r = {r:e}, |d| = {dl:e}: t = {t:e}, f64 root {want:e}, bound {tol:e}"
                    );
                    let x = (ray.origin.as_dvec3() + ray.direction.as_dvec3() * t) - c.as_dvec3();
                    let resid = (x.length_squared() - rr * rr).abs();
                    let bound = 64.0 * u * (fl * fl + rr * rr + (t * d).powi(2))
                        + 2.0 * d * (fl + rr + t * d) * u * t;
                    assert!(resid <= bound, "r = {r:e}: residual {resid:e} > {bound:e}");
                }
                checked += 1;
            }
        }
        assert_eq!(checked, 6);
        for (r, dl) in [(p(-60), 1.0), (p(60), 1.0), (1.0, p(110))] {
            let c = Vec3::new(0.25 * r, -r, 3.0 * r);
            let ray = Ray::new(c + Vec3::new(-2.0 * r, 0.5 * r, 0.0), Vec3::X * dl);
            if let Some((t0, t1)) = Sphere::new(c, r).unwrap().roots(&ray) {
                assert!(!t0.is_nan() && !t1.is_nan() && t0 <= t1, "r = {r:e}");
            }
        }
    }
}
