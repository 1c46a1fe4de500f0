//! [`BehindPlane`]: the part of [`super::Watertight`]'s plane kernel that depends on the
//! triangle only, computed once for many rays, and its refusal of a crossing certainly behind
//! a ray's origin (`crossed_behind`).
//!
//! On x86-64 the exact path of a candidate starts with the plane kernel
//! ([`super::exact::plane_crossing`], or a level's kernel with its bits) and refuses the
//! triangle where it returns its "behind" form; [`BehindPlane::refuses`] returns `true` exactly
//! there, with the same `f64` operations in the same order, so a refused triangle is one the
//! exact path refuses (test: `a_behind_plane_refuses_exactly_where_the_plane_kernel_does`). A
//! batch of rays leaving a surface (shadow rays off a small mesh whose triangles are too large
//! for the eight-lane `f32` cull of `behind.rs`) then pays the triangle's `f64` normal once,
//! not per ray, and each refused ray a few products instead of the exact candidate path.

use super::exact::crossed_behind;
use crate::predicates::ORIENT3D_FILTER_REL;
use crate::ray::Ray;
use glam::{DVec3, Vec3};

/// A triangle's `v0`-based `f64` plane: `v0`, the normal `n = (v1 − v0) × (v2 − v0)` and its
/// rounding scale `N = |v1 − v0| × |v2 − v0|` (absolute values), world units. Only for a
/// triangle whose normal does not cancel (`normal_f64_from_v0`): for the
/// others the plane kernel has no answer and the exact path decides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BehindPlane {
    v0: DVec3,
    n: DVec3,
    nn: DVec3,
}

impl BehindPlane {
    /// The plane of triangle `v`, or `None` when its `v0`-based normal cancels (then nothing is
    /// refused with it).
    #[inline]
    #[must_use]
    pub fn new(v: &[Vec3; 3]) -> Option<Self> {
        let (n, nn) = crate::triangle::normal_f64_from_v0(v)?;
        Some(Self {
            v0: v[0].as_dvec3(),
            n,
            nn,
        })
    }

    /// `true` exactly when the plane kernel of [`super::Watertight`]'s exact path returns its
    /// "behind" form for the ray of `r`: `d·n` clears its orientation filter, `t = ((v0 −
    /// o)·n)/(d·n) < 0` and `crossed_behind` (the crossing certainly behind the origin while
    /// `t_min ≥ 0`). Then the triangle is no hit of the ray. Any ray, valid or not (a NaN or
    /// infinite component fails a comparison: `false`).
    #[inline(always)]
    #[must_use]
    pub fn refuses(&self, r: &PlaneRay<'_>) -> bool {
        let dn = r.d.dot(self.n);
        if !(dn.abs() > ORIENT3D_FILTER_REL * r.d_abs.dot(self.nn)) {
            return false;
        }
        let w = self.v0 - r.o;
        let (wn, w_nn) = (w.dot(self.n), w.abs().dot(self.nn));
        // The kernel's `t = wn/dn < 0` without the quotient: `crossed_behind` asks for `wn` and
        // `dn` of opposite signs, both non-zero (each clears its filter), and their quotient
        // cannot underflow to `−0` (`f32` inputs: a `wn` that clears its filter is at least
        // about `2⁻⁵⁵⁰`, `|dn|` at most `2³⁸⁸`).
        crossed_behind(r.ray, wn, w_nn, dn)
    }
}

/// A ray as [`BehindPlane::refuses`] reads it: its origin, direction and the direction's
/// absolute values in `f64` (exact conversions), made once per ray and tested against many
/// planes.
#[derive(Clone, Copy, Debug)]
pub struct PlaneRay<'a> {
    ray: &'a Ray,
    o: DVec3,
    d: DVec3,
    d_abs: DVec3,
}

impl<'a> PlaneRay<'a> {
    /// `ray` in `f64`.
    #[inline(always)]
    #[must_use]
    pub fn new(ray: &'a Ray) -> Self {
        let d = ray.direction.as_dvec3();
        Self {
            ray,
            o: ray.origin.as_dvec3(),
            d,
            d_abs: d.abs(),
        }
    }
}

/// The lanes among `lanes` (bit `i` for lane `i` of `groups[0]`, `4 + i` of `groups[1]`)
/// whose stored triangle's plane refuses `ray` ([`BehindPlane::refuses`]); lanes without a
/// triangle, or whose normal cancels, are kept. Inlined into each level's caller (the
/// crossed-behind cull's near lanes, `behind.rs`; its AVX2 form in `avx2.rs`).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) fn lanes_refused(
    ray: &Ray,
    groups: [&crate::triangle::TriangleLanes; 2],
    lanes: u32,
) -> u32 {
    let plane_ray = PlaneRay::new(ray);
    let mut out = 0;
    let mut todo = lanes;
    while todo != 0 {
        let bit = todo.trailing_zeros() as usize;
        todo &= todo - 1;
        let Some(p) = groups[(bit >> 2) & 1].get(bit & 3) else {
            continue;
        };
        let v = p.map(Vec3::from_array);
        if BehindPlane::new(&v).is_some_and(|plane| plane.refuses(&plane_ray)) {
            out |= 1 << bit;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hit::spawn_ray_to;
    use crate::test_util::lcg;
    use crate::triangle::{TriangleIntersector, Watertight};

    /// Against the portable plane kernel (`plane_crossing`, the definition every level's
    /// kernel matches bit for bit) and the whole test: on triangles from `1e-3` to `1e3` at
    /// distances up to `1e4`, rays spawned off them towards a point (the triangle they start
    /// on, and rays through it from either side), rays with `t_min < 0`, grazing rays and
    /// invalid rays, `refuses` is `true` exactly where the kernel returns its behind form, and
    /// then `Watertight` misses. Most spawned rays must be refused by their own triangle.
    #[test]
    fn a_behind_plane_refuses_exactly_where_the_plane_kernel_does() {
        let mut s = 41u64;
        let (mut refused, mut spawned, mut spawned_refused) = (0, 0, 0);
        for i in 0..40_000 {
            let scale = 10f32.powf(lcg(&mut s) * 6.0 - 3.0);
            let far = 10f32.powf(lcg(&mut s) * 4.0);
            let c = |s: &mut u64| (lcg(s) - 0.5) * scale;
            let centre = Vec3::new(lcg(&mut s) - 0.5, lcg(&mut s) - 0.5, lcg(&mut s) - 0.5) * far;
            let v = [0; 3].map(|_| centre + Vec3::new(c(&mut s), c(&mut s), c(&mut s)));
            let (b1, b2) = (lcg(&mut s) * 0.5, lcg(&mut s) * 0.5);
            let on = v[0] + (v[1] - v[0]) * b1 + (v[2] - v[0]) * b2;
            let target = centre + Vec3::new(c(&mut s), c(&mut s), c(&mut s)) * 20.0;
            let ray = match i % 5 {
                // Spawned off the triangle itself (its own hit), towards a point.
                0 | 1 => {
                    let hit = Watertight.intersect(&Ray::new(target, on - target), &v);
                    let Some(h) = hit else { continue };
                    spawned += 1;
                    let hit = h.to_hit(&v);
                    spawn_ray_to(&hit, centre + Vec3::new(c(&mut s), c(&mut s), 5.0 * scale))
                }
                // Through the triangle from either side, some from behind its plane.
                2 => Ray::new(target, on - target),
                // An interval starting behind the origin.
                3 => Ray::with_interval(target, target - on, -1.0, f32::INFINITY),
                // Grazing the plane, or invalid.
                _ => {
                    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
                    let mut d = on - target;
                    d -= n * n.dot(d) * (1.0 - 1e-7);
                    if i % 10 == 4 {
                        d.x = f32::NAN;
                    }
                    Ray::new(target, d)
                }
            };
            let want = super::super::exact::plane_crossing(&v, &ray).is_some_and(|p| p.behind);
            let got = BehindPlane::new(&v).is_some_and(|p| p.refuses(&PlaneRay::new(&ray)));
            assert_eq!(got, want, "{v:?} {ray:?}");
            if got {
                refused += 1;
                // Independently of the plane kernel: the exact predicates say the line meets
                // the plane behind the origin (the origin on the side the direction points
                // to, strictly), and the interval starts at 0 or later.
                let side = crate::predicates::orient3d(v[0], v[1], v[2], ray.origin);
                let way = crate::predicates::orient_direction(v[0], v[1], v[2], ray.direction);
                assert!(
                    side != 0 && side == way && ray.t_min >= 0.0,
                    "{v:?} {ray:?}: side {side}, direction {way}"
                );
                assert_eq!(Watertight.intersect(&ray, &v), None, "{v:?} {ray:?}");
                if i % 5 < 2 {
                    spawned_refused += 1;
                }
            }
        }
        assert!(refused > 10_000, "{refused}");
        assert!(
            spawned_refused * 10 > spawned * 9,
            "{spawned_refused} of {spawned}"
        );
    }

    /// A ray parallel to the plane `x = 1` (`d·n = 0` and `|d|·N = 0` exactly: the filter's
    /// tie) is not refused from either side, since the plane kernel's filter is strict and
    /// returns no form for it; the same plane refuses a ray leaving it (`t = −1`).
    #[test]
    fn a_ray_parallel_to_the_plane_is_not_refused() {
        let v = [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 1.0]].map(Vec3::from_array);
        let plane = BehindPlane::new(&v).unwrap();
        for x in [0.0f32, 2.0] {
            let parallel = Ray::new(Vec3::new(x, 0.5, 0.5), Vec3::Z);
            assert!(!plane.refuses(&PlaneRay::new(&parallel)), "origin x = {x}");
            assert_eq!(super::super::exact::plane_crossing(&v, &parallel), None);
        }
        let leaving = Ray::new(Vec3::new(2.0, 0.5, 0.5), Vec3::X);
        assert!(plane.refuses(&PlaneRay::new(&leaving)));
    }
}
