//! The AVX2 + FMA end of [`super::Watertight`]'s hit path: [`finish_exact`], the rest of the
//! test for a candidate the `f32` filter kept, compiled for AVX2 and FMA, and its `f64` plane
//! kernel ([`plane_crossing_avx2`]), which inlines into it. Both return the portable path's
//! bits ([`super::exact::finish_exact`], [`super::exact::plane_crossing`]); and the `f64`
//! plane check of the crossed-behind cull's near lanes ([`near_refused`], the loop of
//! `plane.rs`). Each `unsafe` block enters a compiled-for-AVX2 function on the proof the
//! [`Avx2Fma`] token carries.

use super::exact::{
    Candidate, PLANE_BOX_SLACK, PLANE_T_ERR, PlaneForm, TINY, crossed_behind, finish_exact_at,
};
use crate::ray::Ray;
use crate::simd_level::Avx2Fma;
use crate::triangle::{NORMAL_CANCEL_REL, TriangleHit, TriangleLanes};
use glam::Vec3;

/// [`finish_exact_at`] with the AVX2 plane kernel, for a caller holding the token (out of
/// line, like the portable one: one call per candidate).
#[inline(always)]
pub(super) fn finish_exact(token: Avx2Fma, c: Candidate<'_>) -> Option<TriangleHit> {
    let _ = token;
    // SAFETY: the token exists, so the CPU supports AVX2 and FMA (the contract of
    // `Avx2Fma::new_unchecked`), the only requirement of calling a function compiled for them.
    unsafe { finish_exact_avx2(c) }
}

/// [`finish_exact`]'s body, compiled for AVX2 and FMA: the plane kernel, a closure defined
/// here (so it has the same target features), inlines into it.
#[target_feature(enable = "avx2,fma")]
#[inline(never)]
fn finish_exact_avx2(c: Candidate<'_>) -> Option<TriangleHit> {
    finish_exact_at(|v: &[Vec3; 3], ray: &Ray| plane_crossing_avx2(v, ray), c)
}

/// The crossed-behind cull's `f64` plane check of its near lanes
/// ([`super::plane::lanes_refused`]) compiled for AVX2 and FMA, for a
/// caller holding the token (out of line: one call per cull with near lanes).
#[inline(always)]
pub(super) fn near_refused(
    token: Avx2Fma,
    ray: &Ray,
    groups: [&TriangleLanes; 2],
    near: u32,
) -> u32 {
    let _ = token;
    // SAFETY: the token exists, so the CPU supports AVX2 and FMA (the contract of
    // `Avx2Fma::new_unchecked`), the only requirement of calling a function compiled for them.
    unsafe { near_refused_avx2(ray, groups, near) }
}

/// [`near_refused`]'s body, compiled for AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
#[inline(never)]
fn near_refused_avx2(ray: &Ray, groups: [&TriangleLanes; 2], near: u32) -> u32 {
    super::plane::lanes_refused(ray, groups, near)
}

/// [`super::exact::plane_crossing`] in 256-bit registers: each 3-vector in the lanes `x, y, z` of
/// one `f64` register (the fourth lane zero, never read back), the same IEEE operations in the
/// same order as the portable definition — products, differences and dot products summed
/// `(x + y) + z`, never fused; `min`, `max` as `a < b ? a : b`, `a > b ? a : b` (`minps`,
/// `maxps`, `maxsd`), NaN handling included — so the same bits.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn plane_crossing_avx2(v: &[Vec3; 3], ray: &Ray) -> Option<PlaneForm> {
    use crate::predicates::ORIENT3D_FILTER_REL;
    use core::arch::x86_64::{
        __m256d, _CMP_GE_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _mm_add_sd, _mm_cvtsd_f64, _mm_max_ps,
        _mm_max_sd, _mm_min_ps, _mm_setr_ps, _mm_unpackhi_pd, _mm256_add_pd, _mm256_and_pd,
        _mm256_andnot_pd, _mm256_castpd256_pd128, _mm256_cmp_pd, _mm256_cvtps_pd,
        _mm256_extractf128_pd, _mm256_max_pd, _mm256_movemask_pd, _mm256_mul_pd,
        _mm256_permute4x64_pd, _mm256_set1_pd, _mm256_setzero_pd, _mm256_sub_pd,
    };
    // Built lane by lane from the fields (no load spans two vertices, and no pointer cast).
    let lanes = |p: Vec3| _mm_setr_ps(p.x, p.y, p.z, 0.0);
    let (f0, f1, f2) = (lanes(v[0]), lanes(v[1]), lanes(v[2]));
    let (o, d) = (
        _mm256_cvtps_pd(lanes(ray.origin)),
        _mm256_cvtps_pd(lanes(ray.direction)),
    );
    let (p0, p1, p2) = (
        _mm256_cvtps_pd(f0),
        _mm256_cvtps_pd(f1),
        _mm256_cvtps_pd(f2),
    );
    // Lanes (y, z, x) and (z, x, y) of (x, y, z).
    let yzx = |a: __m256d| _mm256_permute4x64_pd::<0b11_00_10_01>(a);
    let zxy = |a: __m256d| _mm256_permute4x64_pd::<0b11_01_00_10>(a);
    let sign = _mm256_set1_pd(-0.0);
    let abs = |a: __m256d| _mm256_andnot_pd(sign, a);
    let dot = |a: __m256d, b: __m256d| {
        let m = _mm256_mul_pd(a, b);
        let (xy, z) = (_mm256_castpd256_pd128(m), _mm256_extractf128_pd::<1>(m));
        _mm_cvtsd_f64(_mm_add_sd(_mm_add_sd(xy, _mm_unpackhi_pd(xy, xy)), z))
    };
    // max(x, max(y, z)), as `DVec3::max_element`.
    let max_element = |a: __m256d| {
        let (xy, z) = (_mm256_castpd256_pd128(a), _mm256_extractf128_pd::<1>(a));
        _mm_cvtsd_f64(_mm_max_sd(xy, _mm_max_sd(_mm_unpackhi_pd(xy, xy), z)))
    };
    // `normal_f64_from_v0`: the cross product, its scale, the cancellation check.
    let (e1, e2) = (_mm256_sub_pd(p1, p0), _mm256_sub_pd(p2, p0));
    let n = _mm256_sub_pd(
        _mm256_mul_pd(yzx(e1), zxy(e2)),
        _mm256_mul_pd(yzx(e2), zxy(e1)),
    );
    let (a1, a2) = (abs(e1), abs(e2));
    let nn = _mm256_add_pd(
        _mm256_mul_pd(yzx(a1), zxy(a2)),
        _mm256_mul_pd(zxy(a1), yzx(a2)),
    );
    let cancels = _mm256_andnot_pd(
        _mm256_cmp_pd::<_CMP_GT_OQ>(abs(n), _mm256_mul_pd(_mm256_set1_pd(NORMAL_CANCEL_REL), nn)),
        _mm256_cmp_pd::<_CMP_GT_OQ>(nn, _mm256_setzero_pd()),
    );
    if _mm256_movemask_pd(cancels) & 7 != 0 {
        return None;
    }
    // The filter of `d·n`.
    let dn = dot(d, n);
    let d_nn = dot(abs(d), nn);
    if !(dn.abs() > ORIENT3D_FILTER_REL * d_nn) {
        return None;
    }
    // `plane_form`.
    let w = _mm256_sub_pd(p0, o);
    let (wn, w_nn) = (dot(w, n), dot(abs(w), nn));
    let t = wn / dn;
    if t < 0.0 && crossed_behind(ray, wn, w_nn, dn) {
        return Some(PlaneForm::BEHIND);
    }
    let err = PLANE_T_ERR * (w_nn + t.abs() * d_nn) / dn.abs();
    let p = _mm256_add_pd(o, _mm256_mul_pd(d, _mm256_set1_pd(t)));
    let lo = _mm256_cvtps_pd(_mm_min_ps(_mm_min_ps(f0, f1), f2));
    let hi = _mm256_cvtps_pd(_mm_max_ps(_mm_max_ps(f0, f1), f2));
    let slack = f64::from(PLANE_BOX_SLACK)
        * (max_element(_mm256_max_pd(abs(lo), abs(hi))) + max_element(abs(p)))
        + TINY;
    let slack = _mm256_set1_pd(slack);
    let inside = _mm256_and_pd(
        _mm256_cmp_pd::<_CMP_GE_OQ>(p, _mm256_sub_pd(lo, slack)),
        _mm256_cmp_pd::<_CMP_LE_OQ>(p, _mm256_add_pd(hi, slack)),
    );
    Some(PlaneForm {
        t,
        err,
        in_box: _mm256_movemask_pd(inside) & 7 == 7,
        behind: false,
    })
}

/// [`plane_crossing_avx2`] for a caller holding the token (the tests').
#[cfg(test)]
pub(super) fn plane_crossing(token: Avx2Fma, v: &[Vec3; 3], ray: &Ray) -> Option<PlaneForm> {
    let _ = token;
    // SAFETY: as in `finish_exact`: the token proves AVX2 and FMA.
    unsafe { plane_crossing_avx2(v, ray) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{lcg, mixed_f32};

    /// The AVX2 plane kernel against the portable definition
    /// ([`super::super::exact::plane_crossing`], scalar `glam` code), bit for bit (a NaN `t` or
    /// bound matches any NaN: only its comparisons are used), on triangles from `1e-3` to
    /// `1e3` at every distance, slivers, rays along the plane, and coordinates with NaN,
    /// `±∞`, `±0` and subnormals mixed in, some pointing away (crossing at `t = −1`). Every
    /// outcome must occur: a refused triangle (cancelled normal or `d·n` within its filter), a
    /// crossing behind the origin, one in the box, one in the box's padding only (aimed just
    /// past a vertex) and one outside.
    #[test]
    fn avx2_plane_crossing_equals_the_portable_one() {
        let Some(token) = crate::test_util::avx2_or_skip(
            "triangle::watertight::avx2::tests::avx2_plane_crossing_equals_the_portable_one",
        ) else {
            return;
        };
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        let mut s = 29u64;
        let (mut refused, mut behind, mut inside, mut outside) = (0, 0, 0, 0);
        // Crossings aimed outside the triangle's box, within its padding, and found there.
        let mut padded = 0usize;
        for i in 0..40_000 {
            let scale = 10f32.powf(lcg(&mut s) * 6.0 - 3.0);
            let c = |s: &mut u64| {
                if i % 5 == 0 {
                    mixed_f32(s, 0.1, 2.0) * scale
                } else {
                    (lcg(s) - 0.5) * scale
                }
            };
            let centre = Vec3::new(c(&mut s), c(&mut s), c(&mut s)) * 100.0;
            let mut v = [0; 3].map(|_| centre + Vec3::new(c(&mut s), c(&mut s), c(&mut s)));
            if i % 7 == 0 {
                v[2] = v[0] + (v[1] - v[0]) * lcg(&mut s);
            }
            let target =
                v[0] + (v[1] - v[0]) * lcg(&mut s) * 0.5 + (v[2] - v[0]) * lcg(&mut s) * 0.5;
            // Every third: just past `v0` along the edge from `v1`, by a quarter of the box
            // padding's `γ₈` term: outside the triangle's box on an axis where `v0` is
            // extreme, inside the padded box.
            let past = v[0] - v[1];
            let reach = v.iter().fold(0f32, |m, p| m.max(p.abs().max_element()));
            let step =
                0.25 * super::super::exact::PLANE_BOX_SLACK * reach / past.abs().max_element();
            let target = if i % 3 == 1 {
                v[0] + past * step
            } else {
                target
            };
            let b = crate::aabb::Aabb::from_points(&v);
            let off_box = target.cmplt(b.min).any() || target.cmpgt(b.max).any();
            let origin = target + Vec3::new(c(&mut s), c(&mut s), c(&mut s)) * 50.0;
            let mut direction = target - origin;
            if i % 11 == 0 {
                // Along the plane.
                let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
                direction -= n * n.dot(direction);
            }
            if i % 13 == 0 {
                direction = -direction;
            }
            let ray = Ray::new(origin, direction);
            let want = super::super::exact::plane_crossing(&v, &ray);
            let got = plane_crossing(token, &v, &ray);
            match (want, got) {
                (None, None) => refused += 1,
                (Some(w), Some(g)) => {
                    assert!(
                        same(w.t, g.t) && same(w.err, g.err),
                        "{v:?} {ray:?}: {w:?} {g:?}"
                    );
                    assert_eq!(w.in_box, g.in_box, "{v:?} {ray:?}");
                    assert_eq!(w.behind, g.behind, "{v:?} {ray:?}");
                    if w.behind {
                        behind += 1;
                    } else if w.in_box {
                        inside += 1;
                        padded += usize::from(off_box && i % 3 == 1);
                    } else {
                        outside += 1;
                    }
                }
                _ => panic!("{v:?} {ray:?}: {want:?} against {got:?}"),
            }
        }
        assert!(
            refused > 100 && behind > 1_000 && inside > 10_000 && outside > 100 && padded > 1_000,
            "{refused} refused, {behind} behind, {inside} in the box ({padded} in its padding), \
             {outside} outside"
        );
    }
}
