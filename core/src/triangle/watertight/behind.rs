//! The eight-lane `f32` form of [`super::exact::crossed_behind`]: a triangle whose plane the ray's
//! line **certainly** crosses behind the origin, while `t_min ≥ 0`, is no hit of
//! [`super::Watertight`]; this refuses such lanes before the exact path, so that the
//! triangle a spawned ray starts on ([`crate::hit::spawn_ray_to`]) and the faces behind it
//! cost a few vector instructions instead of the exact candidate path. It refuses a lane only
//! when the exact path is certain to refuse it too, so the answers are the same, ray for ray.
//!
//! **The rule.** Per lane, in `f32` (the lane formula of [`crate::simd_level::Behind8`], in
//! world axes): `a = p0 − o`, `e1 = p1 − p0`, `e2 = p2 − p0`,
//! `n = e1 × e2`, `wn = a·n` (the orientation `det[a, e1, e2] = det[p0 − o, p1 − o, p2 − o]`)
//! and `dn = d·n`, each with a bound. A lane is refused when `|wn|` and `|dn|` clear their
//! bounds and have opposite signs (then `t = wn/dn < 0` exactly) and `t_min ≥ 0`.
//!
//! **Axes.** The cull works in world axes, straight from the stored groups, while the exact
//! path's edges use the watertight test's permuted axes; its `f64` plane kernel and `hit_t`
//! use world axes too. A permutation `P` of the axes (the watertight swap of `k_x`, `k_y` for
//! `d_kz < 0` is one more transposition) would give `(Pu) × (Pv) = det(P)·P(u × v)`, so `wn`
//! and `dn` would both change sign by `det(P) = ±1`: the sign of `t = wn/dn` is the same in
//! any axis order, and the permanents, `max` and the 1-norms below are sums over the axes,
//! so the bound derivation does not depend on the order either. Taking the edge cull's
//! permuted rows instead would give the same bits for about 40 more instructions a call.
//!
//! **The `f32` bound.** Standard model (`crate::float`), `u = 2⁻²⁴`. Each elementary term of
//! `wn`, `a_i·e1_j·e2_k`, passes through at most 8 roundings: `a_i`, `e1_j`, `e2_k` (one
//! difference each), their product, the difference in `n`, the product with `a_i`, and two
//! of the sum `(x + y) + z`; so `|wn − wn_exact| ≤ γ₈·W` with `W = |a|·N` of the exact
//! values. The computed permanent `w_nn` has the same roundings on positive terms, so
//! `W ≤ w_nn/(1 − γ₈)`, and the error is at most `γ₈/(1 − γ₈)·w_nn = 8u/(1 − 16u)·w_nn`.
//! `dn` has one rounding less per term (the direction is an input): `< 8u·d_nn`.
//! [`BEHIND_REL`] `= 9u`: the computed bound, three roundings
//! (the product, two sums) below its exact value, is at least `(1 − u)³·9u·perm > 8u/(1 −
//! 16u)·perm` plus the margin terms, so `|value| >` bound leaves the exact value beyond the
//! error, of the same sign, by at least the margin terms below.
//!
//! **Underflow and overflow.** A product below the normal range rounds absolutely (at most
//! `2⁻¹⁵⁰`; sums and differences of `f32` are then exact): at most two such in each `n_i`,
//! one more in each product with `a_i` or `d_i`, so an absolute error below
//! `2⁻¹⁴⁷·(|a|₁ + 1)` (resp. `|d|₁`), which the terms with [`BEHIND_TINY`] `= 2⁻¹⁴⁰` cover
//! (the bound's own underflowing products included). An overflow gives `±∞` or NaN in the
//! permanent at least where it gives it in the value (each permanent term is the rounded
//! magnitude of the value's term, rounding is monotone), so the bound is `∞` or NaN and the
//! comparison fails: overflow and NaN never refuse (unused lanes hold NaN).
//!
//! **Why the exact path then refuses it.** [`super::exact::crossed_behind`] needs `dn` and `wn` in
//! `f64` to clear the orientation filter [`crate::predicates::ORIENT3D_FILTER_REL`] `= γ₁₂`
//! (`f64`) against their permanents, with whichever normal the path uses: the `v0`-based one
//! (`plane_crossing`, `normal_f64_from_v0`, tried first on x86-64, and first in
//! `normal_f64`), or, when that one cancels, the one from the vertex opposite the longest edge
//! (`hit_t`, `normal_f64`); `wn` is always `(v0 − o)·n`. Every base's two edges are among
//! `±e1, ±e2, ±(e2 − e1)`, so each of their components is at most `s = |e1| + |e2|` in
//! magnitude, and every permanent component at most `2m²` (`m = max s_i`): the `f64`
//! permanents are at most `(1 + γ₆)·2m²·|d|₁` and `(1 + γ₆)·2m²·|a|₁` (`f64` differences
//! of `f32` values round at most once). The `margin·|·|₁` term of the bound, with
//! [`BEHIND_F64_MARGIN`] `= 2⁻⁴⁰`, keeps the exact value beyond `2⁻⁴⁰·(1 − γ₄)·m²·|·|₁`,
//! more than `2¹⁰` times the `2·γ₁₂·(1 + γ₆)·2m²·|·|₁` that makes each `f64` filter pass
//! (its value within `γ₁₂·perm` of the exact one, beyond `γ₁₂·perm`). With both filters
//! passed the computed signs are the exact ones and opposite, so the computed `t` is negative
//! (the `f64` quotient of values that did not underflow: at least `2⁻⁴⁹⁷` over at most
//! `2³⁸⁸`), and `crossed_behind` refuses the triangle on every path: `common_t` (x86-64) and
//! `hit_t` (every target), whatever the edges decide (mixed signs or a zero `det` refuse it
//! too).
//!
//! **Near lanes: the `f64` plane.** Where `|wn|` does not clear its bound the origin lies
//! within the `f32` formula's rounding of the plane: the triangle a spawned ray starts on
//! when the triangle is about as large as its coordinates (the spawn offset, a few ulps of the
//! coordinates, is then below `BEHIND_REL·w_nn`), as on meshes of a few large faces. Such a
//! lane is checked once more with the triangle's `f64` plane
//! ([`super::BehindPlane::refuses`], which returns `true` exactly where the exact path's plane
//! kernel refuses the triangle as crossed behind, x86-64 only): a few dozen `f64` operations
//! instead of the projection, the exact edges and the plane kernel of the exact path.

use super::WatertightRay;
use crate::ray::Ray;
use crate::simd_level::{Behind8, SimdLevel};
use crate::tolerance::{BEHIND_F64_MARGIN, BEHIND_REL, BEHIND_TINY};
use crate::triangle::TriangleLanes;

/// The lane formula of [`Behind8`] for one triangle `p` (vertices, world axes), origin
/// `o`, direction `d` and `d_l1 = (|d_0| + |d_1|) + |d_2|`: whether the lane is refused, and
/// whether it is near (`|wn|` does not clear `bound_w`). The portable definition every
/// level's kernel reproduces bit for bit.
#[inline(always)]
#[must_use]
pub(super) fn behind_lane(p: [[f32; 3]; 3], o: [f32; 3], d: [f32; 3], d_l1: f32) -> (bool, bool) {
    let [p0, p1, p2] = p;
    let a: [f32; 3] = core::array::from_fn(|j| p0[j] - o[j]);
    let e1: [f32; 3] = core::array::from_fn(|j| p1[j] - p0[j]);
    let e2: [f32; 3] = core::array::from_fn(|j| p2[j] - p0[j]);
    let (yz, zy) = (e1[1] * e2[2], e1[2] * e2[1]);
    let (zx, xz) = (e1[2] * e2[0], e1[0] * e2[2]);
    let (xy, yx) = (e1[0] * e2[1], e1[1] * e2[0]);
    let n = [yz - zy, zx - xz, xy - yx];
    let nn = [
        yz.abs() + zy.abs(),
        zx.abs() + xz.abs(),
        xy.abs() + yx.abs(),
    ];
    let dot = |u: [f32; 3], v: [f32; 3]| (u[0] * v[0] + u[1] * v[1]) + u[2] * v[2];
    let aa = a.map(f32::abs);
    let (wn, w_nn) = (dot(a, n), dot(aa, nn));
    let (dn, d_nn) = (dot(d, n), dot(d.map(f32::abs), nn));
    let max = |x: f32, y: f32| if x > y { x } else { y };
    let s: [f32; 3] = core::array::from_fn(|j| e1[j].abs() + e2[j].abs());
    let m = max(max(s[0], s[1]), s[2]);
    let margin = BEHIND_F64_MARGIN * (m * m) + BEHIND_TINY;
    let a1 = (aa[0] + aa[1]) + aa[2];
    let bound_w = (BEHIND_REL * w_nn + margin * a1) + BEHIND_TINY;
    let bound_d = (BEHIND_REL * d_nn + margin * d_l1) + BEHIND_TINY;
    let side = wn.abs() > bound_w;
    (
        side && dn.abs() > bound_d && (wn < 0.0) != (dn < 0.0),
        !side,
    )
}

impl WatertightRay {
    /// The lanes among `keep` (bits 0–3: `first`'s lanes, 4–7: `second`'s) whose plane the
    /// line of `ray` certainly crosses behind its origin while `ray.t_min ≥ 0` (module docs):
    /// [`super::Watertight`] misses each of them. Refused by the `f32` lane formula, or, for a
    /// near lane, by the triangle's `f64` plane on x86-64 (module docs). `0` when `t_min < 0`
    /// (or NaN). The same bits at every level: `level`'s eight-lane kernel when it has one,
    /// else the lane formula for the kept lanes only; the `f64` plane is the same at every
    /// level. A method of the prepared ray, like the edge cull, although it reads only `ray`
    /// (it works in world axes).
    #[inline(always)]
    #[must_use]
    pub fn behind_misses2<L: SimdLevel>(
        &self,
        level: L,
        ray: &Ray,
        first: &TriangleLanes,
        second: &TriangleLanes,
        keep: u32,
    ) -> u32 {
        if !(ray.t_min >= 0.0) {
            return 0;
        }
        // World axes: the permutation and shear of `self` are not needed (module docs).
        let _ = self;
        let (origin, dir) = (ray.origin.to_array(), ray.direction.to_array());
        let dir_l1 = (dir[0].abs() + dir[1].abs()) + dir[2].abs();
        let q = Behind8 {
            first,
            second,
            origin,
            dir,
            dir_l1,
        };
        let keep = keep & 0xFF;
        let (refused, near) = match level.behind_misses8(&q) {
            Some(mask) => (mask & keep, (mask >> 8) & keep),
            None => {
                let (mut refused, mut near) = (0, 0);
                let mut todo = keep;
                while todo != 0 {
                    let bit = todo.trailing_zeros() as usize;
                    todo &= todo - 1;
                    let group = if bit < 4 { first } else { second };
                    if let Some(p) = group.get(bit & 3) {
                        let (r, n) = behind_lane(p, origin, dir, dir_l1);
                        refused |= u32::from(r) << bit;
                        near |= u32::from(n) << bit;
                    }
                }
                (refused, near)
            }
        };
        if near == 0 {
            return refused;
        }
        refused | near_refused(level, ray, [first, second], near)
    }
}

/// The lanes among `near` (bits as in [`WatertightRay::behind_misses2`]) whose triangle's
/// `f64` plane refuses `ray` ([`super::BehindPlane::refuses`]: exactly where the exact path's
/// plane kernel refuses it as crossed behind); x86-64 only, where the exact path starts with
/// that kernel (elsewhere `0`). One out-of-line call per level, compiled for AVX2 and FMA at
/// that level (the same `f64` operations: the same bits).
#[inline(always)]
fn near_refused<L: SimdLevel>(level: L, ray: &Ray, groups: [&TriangleLanes; 2], near: u32) -> u32 {
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (level, ray, groups, near);
        0
    }
    #[cfg(target_arch = "x86_64")]
    {
        if let Some(token) = level.avx2() {
            return super::avx2::near_refused(token, ray, groups, near);
        }
        near_refused_portable(ray, groups, near)
    }
}

/// [`super::plane::lanes_refused`] for the levels without AVX2, out of line.
#[cfg(target_arch = "x86_64")]
#[inline(never)]
fn near_refused_portable(ray: &Ray, groups: [&TriangleLanes; 2], near: u32) -> u32 {
    super::plane::lanes_refused(ray, groups, near)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predicates::{orient_direction, orient3d_exact};
    use crate::sealed::Inside;
    use crate::simd_level::Portable;
    use crate::test_util::{Lcg, special_f32, unit_vec};
    use crate::triangle::{TriangleIntersector, Watertight};
    use crate::{Ray, spawn_ray_to};
    use glam::Vec3;

    /// Eight triangles around a surface triangle `tri` (lane `at`), with coordinates of
    /// other triangles drawn near and far, a few replaced by NaN, `±∞`, huge or tiny values.
    fn lanes_around(r: &mut Lcg, tri: [Vec3; 3], at: usize) -> [TriangleLanes; 2] {
        let size = (tri[1] - tri[0]).length().max(1e-30);
        let mut lanes = [TriangleLanes::EMPTY; 2];
        for lane in 0..8 {
            let v = if lane == at {
                tri
            } else {
                let c = tri[0] + r.v(8.0 * size);
                let mut v = [c + r.v(size), c + r.v(size), c + r.v(size)];
                if lane % 3 == 0 {
                    // A neighbour sharing the edge v1 v2, folded by a random angle.
                    v = [tri[2], tri[1], tri[1] + r.v(2.0 * size)];
                }
                if r.f() < 0.1 {
                    let special = special_f32(&mut r.0);
                    v[lane % 3][(lane / 3) % 3] = match lane % 4 {
                        0 => special,
                        1 => 1e30,
                        2 => 1e-40,
                        _ => f32::INFINITY,
                    };
                }
                v
            };
            let tri: [[f32; 3]; 3] = v.map(|p| p.to_array());
            lanes[lane / 4].set(lane % 4, &tri);
        }
        lanes
    }

    /// The exact oracle, sharing no code with the cull: the line crosses the plane of `v`
    /// behind the origin (the exact signs of the origin's and the direction's orientation
    /// against the plane, [`crate::predicates`]' expansions, are equal and non-zero).
    fn exactly_behind(ray: &Ray, v: &[Vec3; 3]) -> bool {
        let side = orient3d_exact(v[0], v[1], v[2], ray.origin);
        side != 0 && side == orient_direction(v[0], v[1], v[2], ray.direction)
    }

    /// Every lane the cull refuses, at the portable level and at AVX2 (where the CPU has it,
    /// the same bits for all eight lanes, each kept or not), is refused by the exact path
    /// (`Watertight`'s answer for it is `None`, with and without the lane filter, at every
    /// level) and lies exactly behind the origin. Rays spawned off triangles of sizes
    /// `1e-3`–`1e3` towards a light (`spawn_ray_to`), short AO rays, rays grazing the surface,
    /// origins exactly on the plane, `t_min < 0`; triangle coordinates with NaN, `±∞`,
    /// `1e30` and `1e-40` mixed in. The triangle a spawned ray starts on must be refused
    /// for most rays (else the test would prove nothing).
    #[test]
    fn refused_lanes_are_exact_misses_behind_the_origin() {
        let avx2 = crate::test_util::avx2_or_skip(
            "triangle::watertight::behind::tests::refused_lanes_are_exact_misses_behind_the_origin",
        );
        let mut r = Lcg(42);
        let (mut refused, mut start_refused, mut starts, mut kept_behind) = (0, 0, 0, 0);
        for i in 0..60_000 {
            let size = [1e-3f32, 1.0, 1e3, 1e-20][i % 4];
            let base = r.v(64.0 * size);
            let tri = [base + r.v(size), base + r.v(size), base + r.v(size)];
            let eye = base + r.v(16.0 * size);
            let (b1, b2) = (r.f() * 0.5, r.f() * 0.5);
            let aim = tri[0] + (tri[1] - tri[0]) * b1 + (tri[2] - tri[0]) * b2;
            let Some(h) = Watertight.intersect(&Ray::new(eye, aim - eye), &tri) else {
                continue;
            };
            let hit = h.to_hit(&tri);
            let n = hit.normal;
            let ray = match i % 5 {
                // Towards a light, and a short AO ray.
                0 | 1 => spawn_ray_to(&hit, base + r.v(32.0 * size)),
                2 => {
                    let w = unit_vec(&mut r.0);
                    let w = if w.dot(n) < 0.0 { -w } else { w };
                    let mut ray = spawn_ray_to(&hit, hit.spawn_origin(w) + w * size);
                    ray.t_max *= r.f();
                    ray
                }
                // Grazing: the direction within 1e-7 of the plane.
                3 => {
                    let w = unit_vec(&mut r.0);
                    let w = w - n * w.dot(n) + n * (r.f() - 0.5) * 1e-7;
                    Ray::new(hit.spawn_origin(w), w)
                }
                // The origin on the plane (a vertex), or t_min < 0.
                _ => {
                    let w = unit_vec(&mut r.0);
                    let mut ray = Ray::new(tri[(i / 5) % 3], w);
                    if i % 2 == 0 {
                        ray = Ray::new(hit.spawn_origin(w), w);
                        ray.t_min = -1.0;
                    }
                    ray
                }
            };
            let Some(pre) = WatertightRay::new(&ray) else {
                continue;
            };
            let at = (i / 3) % 8;
            let lanes = lanes_around(&mut r, tri, at);
            let portable = pre.behind_misses2(Portable, &ray, &lanes[0], &lanes[1], 0xFF);
            if let Some(level) = avx2 {
                let got = pre.behind_misses2(level, &ray, &lanes[0], &lanes[1], 0xFF);
                assert_eq!(got, portable, "{ray:?} {lanes:?}");
                // Only the kept lanes.
                let keep = (i as u32).wrapping_mul(2_654_435_761) >> 24;
                let got = pre.behind_misses2(level, &ray, &lanes[0], &lanes[1], keep);
                assert_eq!(got, portable & keep);
                assert_eq!(
                    pre.behind_misses2(Portable, &ray, &lanes[0], &lanes[1], keep),
                    portable & keep
                );
            }
            if ray.t_min < 0.0 {
                assert_eq!(portable, 0);
            }
            for lane in 0..8 {
                let Some(t) = lanes[lane / 4].get(lane % 4) else {
                    continue;
                };
                let v = t.map(Vec3::from_array);
                let is_refused = portable >> lane & 1 == 1;
                if is_refused {
                    refused += 1;
                    assert!(exactly_behind(&ray, &v), "{ray:?} {v:?}");
                    assert_eq!(Watertight.intersect(&ray, &v), None, "{ray:?} {v:?}");
                    assert_eq!(
                        Watertight.intersect_prepared_on(Inside(()), Portable, &pre, &ray, &v),
                        None
                    );
                    if let Some(level) = avx2 {
                        assert_eq!(
                            Watertight.intersect_prepared_on(Inside(()), level, &pre, &ray, &v),
                            None
                        );
                    }
                } else if v.iter().all(|p| p.is_finite()) && exactly_behind(&ray, &v) {
                    kept_behind += 1;
                }
                // Not at the subnormal scale (`1e-20`: the products underflow).
                if lane == at && i % 5 < 3 && i % 4 != 3 {
                    starts += 1;
                    start_refused += usize::from(is_refused);
                }
            }
        }
        assert!(refused > 50_000, "{refused} lanes refused");
        assert!(
            kept_behind > 1_000,
            "{kept_behind} lanes behind kept (grazing, on the plane)"
        );
        assert!(
            start_refused * 10 > starts * 9,
            "start triangles refused: {start_refused} of {starts}"
        );
    }

    /// Needles (width `10⁻⁸`–`10⁻⁵` of their length, half of them along a coordinate axis)
    /// met by rays at grazing angles (`10⁻⁹`–`10⁻⁵` rad, through a point of the needle) from
    /// origins on its plane and off it by up to its width or `10⁻²` of its length: there the
    /// normal's permanent is far below `m²` and the `f64` margin (`BEHIND_F64_MARGIN·m²` of
    /// the 1-norms) decides the bound. Every refused lane lies exactly behind the origin and
    /// is missed by the exact path at every level.
    #[test]
    fn grazed_needles_are_refused_only_behind() {
        let avx2 = crate::test_util::avx2_or_skip(
            "triangle::watertight::behind::tests::grazed_needles_are_refused_only_behind",
        );
        let mut r = Lcg(7);
        let (mut refused, mut behind) = (0, 0);
        for i in 0..40_000 {
            let length = [1e-3f32, 1.0, 1e3][i % 3];
            let width = length * [1e-8f32, 1e-7, 1e-6, 1e-5][(i / 3) % 4];
            // Along a coordinate axis half the time: then the normal's permanent is of the
            // order of width × length, far below `m²`, and the margins decide.
            let axis = if i % 2 == 0 {
                unit_vec(&mut r.0)
            } else {
                [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X][(i / 2) % 4]
            };
            let base = r.v(4.0 * length);
            let tri = [
                base,
                base + axis * length + r.v(width),
                base + axis * (length * r.f()) + r.v(width),
            ];
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
            if n == Vec3::ZERO {
                continue;
            }
            let aim =
                tri[0] + (tri[1] - tri[0]) * (0.5 * r.f()) + (tri[2] - tri[0]) * (0.5 * r.f());
            let along = (axis + r.v(1.0) - n * axis.dot(n)).normalize_or_zero();
            let tilt = [1e-9f32, 1e-7, 1e-5][(i / 12) % 3] * (r.f() - 0.5);
            let dir = along + n * tilt;
            let off = [0.0, 1e-3 * width, width, 1e-4 * length, 1e-2 * length][(i / 36) % 5];
            let lift = n * (off * (r.f() - 0.5));
            let origin = aim - dir * (length * (r.f() - 0.25)) + lift;
            let ray = Ray::new(origin, dir);
            let Some(pre) = WatertightRay::new(&ray) else {
                continue;
            };
            let mut lanes = [TriangleLanes::EMPTY; 2];
            lanes[0].set(0, &tri.map(|p| p.to_array()));
            let portable = pre.behind_misses2(Portable, &ray, &lanes[0], &lanes[1], 0xFF);
            if let Some(level) = avx2 {
                let got = pre.behind_misses2(level, &ray, &lanes[0], &lanes[1], 0xFF);
                assert_eq!(got, portable, "{ray:?} {tri:?}");
            }
            behind += usize::from(exactly_behind(&ray, &tri));
            if portable & 1 == 1 {
                refused += 1;
                assert!(exactly_behind(&ray, &tri), "{ray:?} {tri:?}");
                assert_eq!(Watertight.intersect(&ray, &tri), None, "{ray:?} {tri:?}");
                if let Some(level) = avx2 {
                    assert_eq!(
                        Watertight.intersect_prepared_on(Inside(()), level, &pre, &ray, &tri),
                        None
                    );
                }
            }
        }
        assert!(
            refused > 1_000 && behind > refused,
            "{refused} refused, {behind} behind"
        );
    }

    /// The rule worked by hand where the direction's margin decides (module docs): a needle of
    /// length 1 and width `h` in the plane `x = 0` (`n = (−h, 0, 0)`, `m = 1`), the origin
    /// `(1, 0, 0.5)` (`wn = h`, its bound about `1.5·2⁻⁴⁰`), the direction `(2⁻¹⁰, 0, 1)`
    /// leaving the plane nearly parallel to it (`dn = −2⁻¹⁰·h`, `|d|₁ = 1 + 2⁻¹⁰`). At
    /// `h = 2⁻³⁵`, `|dn| = 2⁻⁴⁵` clears `BEHIND_REL·d_nn` by far but not
    /// `BEHIND_F64_MARGIN·m²·|d|₁ ≈ 2⁻⁴⁰`: kept (and not near: `|wn|` clears its bound). At
    /// `h = 2⁻²⁰`, `|dn| = 2⁻³⁰` clears it: refused. Both levels, through the cull's own `|d|₁`.
    #[test]
    fn the_direction_margin_keeps_a_needle_crossed_nearly_parallel() {
        let avx2 = crate::test_util::avx2_or_skip(
            "triangle::watertight::behind::tests::the_direction_margin_keeps_a_needle_crossed_nearly_parallel",
        );
        let ray = Ray::new(
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::new(2f32.powi(-10), 0.0, 1.0),
        );
        let pre = WatertightRay::new(&ray).unwrap();
        for (h, refused) in [(2f32.powi(-35), 0), (2f32.powi(-20), 1)] {
            let mut lanes = [TriangleLanes::EMPTY; 2];
            lanes[0].set(0, &[[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, h, 0.0]]);
            let got = pre.behind_misses2(Portable, &ray, &lanes[0], &lanes[1], 0xFF);
            assert_eq!(got, refused, "width {h}");
            if let Some(level) = avx2 {
                let got = pre.behind_misses2(level, &ray, &lanes[0], &lanes[1], 0xFF);
                assert_eq!(got, refused, "width {h}, AVX2");
            }
        }
    }

    /// Each level's eight-lane kernel returns the lane formula's two bits for every lane:
    /// refused (bits 0–7) and near (bits 8–15), on the lanes of `lanes_around` (NaN, `±∞`,
    /// huge and tiny coordinates among them) and rays from origins on the surface triangle's
    /// plane, near it, and anywhere.
    #[test]
    fn the_kernel_returns_the_lane_formula_refused_and_near() {
        let Some(level) = crate::test_util::avx2_or_skip(
            "triangle::watertight::behind::tests::the_kernel_returns_the_lane_formula_refused_and_near",
        ) else {
            return;
        };
        let mut r = Lcg(5);
        let mut near_seen = 0;
        for i in 0..20_000 {
            let size = [1e-3f32, 1.0, 1e3][i % 3];
            let base = r.v(4.0 * size);
            let tri = [base + r.v(size), base + r.v(size), base + r.v(size)];
            let lanes = lanes_around(&mut r, tri, i % 8);
            // Origins on and near the surface triangle's plane, and anywhere.
            let (b1, b2) = (r.f() * 0.5, r.f() * 0.5);
            let on = tri[0] + (tri[1] - tri[0]) * b1 + (tri[2] - tri[0]) * b2;
            let origin = if i % 2 == 0 { on } else { on + r.v(size) };
            let dir = unit_vec(&mut r.0);
            let (o, d) = (origin.to_array(), dir.to_array());
            let d_l1 = (d[0].abs() + d[1].abs()) + d[2].abs();
            let q = Behind8 {
                first: &lanes[0],
                second: &lanes[1],
                origin: o,
                dir: d,
                dir_l1: d_l1,
            };
            let got = level
                .behind_misses8(&q)
                .expect("the AVX2 level has the kernel");
            for lane in 0..8 {
                let p: [[f32; 3]; 3] = core::array::from_fn(|v| {
                    core::array::from_fn(|j| lanes[lane / 4].v[v][j][lane % 4])
                });
                let (refused, near) = behind_lane(p, o, d, d_l1);
                assert_eq!(got >> lane & 1 == 1, refused, "{lane} {q:?}");
                assert_eq!(got >> (8 + lane) & 1 == 1, near, "{lane} {q:?}");
                near_seen += usize::from(near);
            }
            assert_eq!(got >> 16, 0);
        }
        assert!(near_seen > 1_000, "{near_seen} near lanes");
    }

    /// A closed mesh of a few large faces (a tetrahedron, its faces as large as its
    /// coordinates): the triangle a shadow or AO ray starts on is too large for the `f32`
    /// formula (near), and its `f64` plane refuses it. Every refused lane is an exact miss
    /// behind the origin at every level, and nearly every start triangle is refused, a fifth
    /// of them or more only by the `f64` plane (about a third with this seed).
    #[test]
    fn a_large_start_triangle_is_refused_by_its_f64_plane() {
        let avx2 = crate::test_util::avx2_or_skip(
            "triangle::watertight::behind::tests::a_large_start_triangle_is_refused_by_its_f64_plane",
        );
        let mut r = Lcg(11);
        let (mut starts, mut refused, mut by_f64) = (0, 0, 0);
        for i in 0..20_000 {
            let scale = [1e-3f32, 1.0, 1e3][i % 3];
            let shift = [Vec3::ZERO, Vec3::splat(0.5 * scale), r.v(2.0 * scale)][(i / 3) % 3];
            let corners = [
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(1.0, -1.0, -1.0),
                Vec3::new(-1.0, 1.0, -1.0),
                Vec3::new(-1.0, -1.0, 1.0),
            ]
            .map(|c| c * scale + shift + r.v(0.1 * scale));
            let faces = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]].map(|f| f.map(|k| corners[k]));
            let mut lanes = [TriangleLanes::EMPTY; 2];
            for (lane, f) in faces.iter().enumerate() {
                lanes[0].set(lane, &f.map(|p| p.to_array()));
            }
            let at = i % 4;
            let tri = faces[at];
            let (b1, b2) = (r.f() * 0.45 + 0.05, r.f() * 0.45 + 0.05);
            let aim = tri[0] + (tri[1] - tri[0]) * b1 + (tri[2] - tri[0]) * b2;
            let eye = aim
                + (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize() * (3.0 * scale)
                + r.v(0.5 * scale);
            let Some(h) = Watertight.intersect(&Ray::new(eye, aim - eye), &tri) else {
                continue;
            };
            let hit = h.to_hit(&tri);
            let ray = if i % 2 == 0 {
                spawn_ray_to(&hit, eye + r.v(4.0 * scale))
            } else {
                let w = unit_vec(&mut r.0);
                let w = if w.dot(hit.normal) < 0.0 { -w } else { w };
                let mut ray = spawn_ray_to(&hit, hit.spawn_origin(w) + w * scale);
                ray.t_max *= 0.5;
                ray
            };
            let Some(pre) = WatertightRay::new(&ray) else {
                continue;
            };
            let portable = pre.behind_misses2(Portable, &ray, &lanes[0], &lanes[0], 0x0F);
            if let Some(level) = avx2 {
                assert_eq!(
                    pre.behind_misses2(level, &ray, &lanes[0], &lanes[0], 0x0F),
                    portable
                );
            }
            assert_eq!(portable >> 4, 0);
            for (lane, f) in faces.iter().enumerate() {
                if portable >> lane & 1 == 1 {
                    assert!(exactly_behind(&ray, f), "{ray:?} {f:?}");
                    assert_eq!(Watertight.intersect(&ray, f), None, "{ray:?} {f:?}");
                    if let Some(level) = avx2 {
                        assert_eq!(
                            Watertight.intersect_prepared_on(Inside(()), level, &pre, &ray, f),
                            None
                        );
                    }
                }
            }
            starts += 1;
            if portable >> at & 1 == 1 {
                refused += 1;
                let (o, d) = (ray.origin.to_array(), ray.direction.to_array());
                let d_l1 = (d[0].abs() + d[1].abs()) + d[2].abs();
                let (f32_refused, _) = behind_lane(tri.map(|p| p.to_array()), o, d, d_l1);
                by_f64 += usize::from(!f32_refused);
            }
        }
        assert!(
            refused * 100 > starts * 99,
            "start triangles refused: {refused} of {starts}"
        );
        assert!(
            by_f64 * 5 > refused,
            "{by_f64} of {refused} only by the f64 plane"
        );
    }
}
