//! The watertight test with no `f64` anywhere, for targets that emulate it (Cortex-M4F: `f32`
//! in hardware, `f64` in software; Cortex-M3/M0+: no FPU).

use super::watertight::{filter_edges, mixed_signs};
use super::{ShearedTest, TriangleHit, WatertightRay};
use crate::float::{diff_of_products_sign_int, sign_is_certain};
use crate::ray::Ray;
use glam::Vec3;

/// The watertight test (Woop, Benthin and Wald) in `f32` with **exact edge signs**, computed
/// without `f64`: the same projection and `f32` edge filter as [`super::Watertight`]; when an
/// edge's `f32` value is zero or NaN (or `det` is tiny or overflows), every edge gets its exact
/// sign from integer significand products ([`diff_of_products_sign_int`]) and its value from
/// the coordinates rescaled to unit size. The inside/outside decision of every edge is therefore the
/// one [`super::Watertight`] makes with exact `f64` products, bit for bit, so the two tests
/// are watertight on the same meshes and agree on hit/miss wherever the ray is not in (or
/// within rounding of) the triangle's plane.
///
/// Differences from [`super::Watertight`], the price of staying in `f32`:
/// * `t = Σ (eᵢ / det)·zᵢ` and the barycentrics `eᵢ / det` in `f32` (an edge whose rescaled
///   value rounded to the wrong side enters with the magnitude `f32::MIN_POSITIVE`: its true
///   value is below the `f32` rounding of the others). As for [`super::WatertightF32`], an
///   origin near the triangle's plane makes `t`'s relative rounding large.
/// * Zero area and "ray in the plane" are decided on the sheared projection: `det = 0`
///   exactly (all three edge signs zero). A ray within rounding of the plane may hit, at the
///   sheared `t`; the 3-D `f64` test of the other variants is not available.
/// * Domain: the **edge signs** are exact for all finite sheared coordinates (the rescaling
///   keeps the edge products in range from the subnormal scale to `f32::MAX`); `t`, a convex
///   combination of the sheared depths, overflows only when they reach `f32::MAX` (a `t` that
///   overflows is a miss, as for every variant). The **values** `t` and
///   `eᵢ / det` are `f32` quotients: they carry [`super::WatertightF32`]'s error bound, and so
///   agree with [`super::F64Reference`] as [`super::Watertight`] does, only inside
///   [`super::WatertightF32`]'s domain (`|det| ≥ 2⁻¹⁰⁰`, `Σ|eᵢzᵢ| ≤ 2¹²⁰`, coordinates
///   relative to the origin zero or in `[1e-19, 1e19]`, no underflowing projection); outside
///   it they are finite but their rounding may be absolute.
/// * [`TriangleHit::ng`]: the `f32` cross product, or, when that overflows or underflows, the
///   cross product of the edges each scaled to a largest component of `1` (`f32`, same
///   direction up to rounding).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WatertightF32Exact;

/// Smallest `|det|` the fast path accepts: `2⁻⁶⁴`. Below it the products `eᵢ·zᵢ` of a small
/// configuration may underflow, so the edges are recomputed at unit scale ([`edges_rescaled`]).
/// Unitless (a power of two; any value far above the subnormal range works).
const FAST_DET_MIN: f32 = 1.0 / 18_446_744_073_709_551_616.0;

/// The edges when the fast path cannot decide (an edge zero or NaN, or a tiny or overflowing
/// `det`): the **signs** exact on the given coordinates ([`diff_of_products_sign_int`]), the
/// **values** from the x and the y coordinates each scaled by a power of two so that their
/// largest is about `1` (which scales every edge by the same factor: the ratios `eᵢ/det`,
/// hence `t` and the barycentrics, do not change). A value whose sign disagrees with the exact one (it rounded
/// to zero, or the scaling rounded a subnormal) is replaced by the exact sign times
/// `f32::MIN_POSITIVE`. NaN edges for non-finite coordinates. Out of line: rare.
#[inline(never)]
fn edges_rescaled(x: [f32; 3], y: [f32; 3]) -> [f32; 3] {
    if !x.iter().chain(&y).all(|c| c.is_finite()) {
        return [f32::NAN; 3];
    }
    let ([ax, bx, cx], [ay, by, cy]) = (x, y);
    let sign = [
        diff_of_products_sign_int(cx, by, cy, bx),
        diff_of_products_sign_int(ax, cy, ay, cx),
        diff_of_products_sign_int(bx, ay, by, ax),
    ];
    // Each edge is bilinear in the x's and the y's: scaling all x by one power of two and all
    // y by another scales the three edges alike. Separately, so that an axis far smaller than
    // the other does not fall into the subnormal range.
    let (sx, sy) = (unit_scale(&x), unit_scale(&y));
    let value = filter_edges(x.map(|c| c * sx), y.map(|c| c * sy));
    let pick = |v: f32, s: i32| {
        let agrees = (s > 0 && v > 0.0) || (s < 0 && v < 0.0) || (s == 0 && v == 0.0);
        if agrees {
            v
        } else {
            s as f32 * f32::MIN_POSITIVE
        }
    };
    [
        pick(value[0], sign[0]),
        pick(value[1], sign[1]),
        pick(value[2], sign[2]),
    ]
}

/// The power of two `2^(127 − E)`, `E` the biased exponent of the largest `|c|` of `c`
/// (clamped to a normal power of two): the largest times it lies in `[1, 2)`.
#[inline(always)]
fn unit_scale(c: &[f32; 3]) -> f32 {
    let m = c[0].abs().max(c[1].abs()).max(c[2].abs());
    let biased = (m.to_bits() >> 23) & 0xFF;
    f32::from_bits(254u32.saturating_sub(biased).clamp(1, 254) << 23)
}

/// `(v1 − v0) × (v2 − v0)` in `f32`; when that is zero or not finite, the cross product of the
/// edges each divided by its largest component: halved edges (which cannot overflow) when the
/// product overflowed, the edges themselves when it underflowed (finite then, and exact for
/// subnormal vertices, whose halves would round away); zero only for a triangle with a zero
/// edge or collinear edges.
fn normal_f32(v: &[Vec3; 3]) -> Vec3 {
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    if n.is_finite() && n != Vec3::ZERO {
        return n;
    }
    let k = if n.is_finite() { 1.0 } else { 0.5 };
    let (e1, e2) = (v[1] * k - v[0] * k, v[2] * k - v[0] * k);
    let (s1, s2) = (e1.abs().max_element(), e2.abs().max_element());
    if !(s1 > 0.0 && s2 > 0.0) {
        return Vec3::ZERO;
    }
    let n = (e1 / s1).cross(e2 / s2);
    if n.is_finite() { n } else { Vec3::ZERO }
}

impl crate::sealed::Sealed for WatertightF32Exact {}

impl ShearedTest for WatertightF32Exact {
    const NAME: &'static str = "watertight-f32-exact";

    #[inline(always)]
    fn hit_sheared(&self, pre: &WatertightRay, ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit> {
        let (x, y, [az, bz, cz]) = pre.project_triangle(ray.origin, v);
        let mut e = filter_edges(x, y);
        let certain = sign_is_certain(e[0]) & sign_is_certain(e[1]) & sign_is_certain(e[2]);
        if certain & mixed_signs(&e) {
            return None;
        }
        // Same signs: no cancellation, so `det = 0` only when all three are exactly zero.
        let mut det = e[0] + e[1] + e[2];
        if !(certain && det.abs() >= FAST_DET_MIN && det.is_finite()) {
            e = edges_rescaled(x, y);
            if mixed_signs(&e) {
                return None;
            }
            det = e[0] + e[1] + e[2];
            if !(det != 0.0 && det.is_finite()) {
                return None;
            }
        }
        // `t` as the barycentric combination of the depths, `Σ (eᵢ/det)·zᵢ`, not `(Σ eᵢzᵢ)/det`:
        // the same operation count and rounding order of magnitude, but no intermediate of
        // size `|det|·t`, which overflows for a finite `t` when the triangle is large
        // (`|det| ≈ 10³⁶` at `10¹⁸` across makes `t = 100` overflow) or `t` is near `f32::MAX`.
        let inv = 1.0 / det;
        let (b0, b1, b2) = (e[0] * inv, e[1] * inv, e[2] * inv);
        let t = b0 * az + b1 * bz + b2 * cz;
        (ray.contains(t) && b1.is_finite() && b2.is_finite()).then(|| TriangleHit {
            t,
            b1,
            b2,
            ng: normal_f32(v),
            // As in `Watertight`: det > 0 when the normal opposes the ray.
            front_face: det > 0.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::{TriangleIntersector, Watertight};

    #[test]
    fn plain_hit_matches_the_exact_test() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let ray = Ray::new(Vec3::new(0.25, 0.5, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let h = WatertightF32Exact.intersect(&ray, &tri).expect("hit");
        assert_eq!((h.t, h.b1, h.b2), (5.0, 0.25, 0.5));
        assert_eq!(h.ng, Vec3::Z);
        assert!(h.front_face);
        let w = Watertight.intersect(&ray, &tri).expect("hit");
        assert_eq!(
            (h.t, h.b1, h.b2, h.front_face),
            (w.t, w.b1, w.b2, w.front_face)
        );
        let back = Ray::new(Vec3::new(0.25, 0.5, -5.0), Vec3::Z);
        assert!(
            !WatertightF32Exact
                .intersect(&back, &tri)
                .unwrap()
                .front_face
        );
        // Outside: mixed signs.
        let miss = Ray::new(Vec3::new(0.75, 0.5, 5.0), -Vec3::Z);
        assert!(WatertightF32Exact.intersect(&miss, &tri).is_none());
    }

    /// The values' domain (type docs, `2⁻¹⁰⁰ ≤ |det|`, `Σ|eᵢzᵢ| ≤ 2¹²⁰`) at both ends: a
    /// triangle of size `s` seen from `2s` along a tilted direction, with `s` from `2⁻⁴⁹`
    /// (`|det| = 3s²·…` just above `2⁻¹⁰⁰`) to `2³⁹` (`Σ|eᵢzᵢ|` just below `2¹²⁰`): `t` and the
    /// barycentrics agree with `F64Reference`'s to `f32` rounding (`10⁻⁵` relative).
    #[test]
    fn values_agree_with_the_reference_at_both_ends_of_the_domain() {
        for k in [-49, -30, 0, 30, 39] {
            let s = 2f32.powi(k);
            let tri = [
                Vec3::new(s, 0.0, 0.25 * s),
                Vec3::new(0.0, s, 0.0),
                Vec3::new(-s, -s, -0.25 * s),
            ];
            let ray = Ray::new(
                Vec3::new(0.125 * s, 0.0625 * s, 2.0 * s),
                Vec3::new(0.0625, 0.0625, -1.0),
            );
            let h = WatertightF32Exact.intersect(&ray, &tri).expect("hit");
            let (t, b) = crate::triangle::F64Reference::solve(&ray, &tri).expect("reference hit");
            let near = |x: f32, y: f64, scale: f64| (f64::from(x) - y).abs() <= 1e-5 * scale;
            assert!(near(h.t, t, t), "2^{k}: t {} against {t}", h.t);
            assert!(
                near(h.b1, b[1], 1.0) && near(h.b2, b[2], 1.0),
                "2^{k}: {h:?} {b:?}"
            );
        }
    }

    /// Two triangles sharing the diagonal of a square at `1e-30` (every `f32` edge product
    /// underflows to zero, so the integer predicate decides every sign): rays through exact
    /// points of the diagonal hit at least one of them, and rays through the interior of one
    /// hit exactly that one, as the `f64` test decides.
    #[test]
    fn shared_edge_at_the_subnormal_scale_is_closed() {
        let s = 1.0e-30f32;
        let (a, b, c, d) = (
            Vec3::ZERO,
            Vec3::new(s, 0.0, 0.0),
            Vec3::new(s, s, 0.0),
            Vec3::new(0.0, s, 0.0),
        );
        let (t1, t2) = ([a, b, c], [a, c, d]);
        for i in 1..16 {
            let k = i as f32 / 16.0;
            let on_edge = Vec3::new(k * s, k * s, 0.0);
            let ray = Ray::new(on_edge + Vec3::new(0.0, 0.0, s), -Vec3::Z);
            let hits = [&t1, &t2]
                .iter()
                .filter(|t| WatertightF32Exact.intersect(&ray, t).is_some())
                .count();
            assert!(hits >= 1, "leak at {k}");
            for (p, hit_t1) in [
                (Vec3::new(0.75, 0.25, 0.0), true),
                (Vec3::new(0.25, 0.75, 0.0), false),
            ] {
                let ray = Ray::new(p * s * k + Vec3::new(0.0, 0.0, s), -Vec3::Z);
                assert_eq!(
                    WatertightF32Exact.intersect(&ray, &t1).is_some(),
                    hit_t1,
                    "{k}"
                );
                assert_eq!(
                    WatertightF32Exact.intersect(&ray, &t2).is_some(),
                    !hit_t1,
                    "{k}"
                );
                assert_eq!(
                    Watertight.intersect(&ray, &t1).is_some(),
                    hit_t1,
                    "oracle {k}"
                );
            }
        }
    }

    /// The `f32` cross product overflows (`1e25`) or underflows (`1e-30`): the rescaled
    /// fallback keeps the direction.
    #[test]
    fn normal_of_huge_and_tiny_triangles() {
        for s in [1.0e25f32, 1.0e-30] {
            let v = [Vec3::ZERO, Vec3::new(s, 0.0, 0.0), Vec3::new(0.0, s, 0.0)];
            let n = normal_f32(&v);
            assert!(n.is_finite() && n != Vec3::ZERO, "{s}: {n:?}");
            assert_eq!(n.normalize(), Vec3::Z, "{s}");
        }
        let collinear = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        assert_eq!(normal_f32(&collinear), Vec3::ZERO);
        // Subnormal vertices one ulp apart (found through the C interface): their halves
        // round to the same value, so the halved edges vanished and the normal of a hit was
        // zero; the edges themselves are exact, and the normal is the plane's, with the
        // orientation of the exact cross product (+z for this winding).
        let u = f32::from_bits(1);
        let v = [
            Vec3::new(u, -u, 0.0),
            Vec3::new(0.0, u, 0.0),
            Vec3::new(-u, -u, 0.0),
        ];
        let n = normal_f32(&v);
        assert!(
            n.is_finite() && n.z > 0.0 && n.x == 0.0 && n.y == 0.0,
            "{n:?}"
        );
        let hit = WatertightF32Exact
            .intersect(&Ray::new(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z), &v)
            .expect("the ray through the triangle's inside hits");
        assert!(hit.ng.z > 0.0, "{hit:?}");
    }

    /// A finite `t` is a hit however large `|det|·t` is: a triangle `2·10¹⁸` across hit at
    /// `t = 100`, and a unit one at `t = 10³⁸` (`Σ eᵢzᵢ` overflowed `f32` in both, and the
    /// hits were misses). Oracle: the ray meets the plane `z = 0` at `(0, 0, 0)`, inside the
    /// triangle, at `t = D` exactly; the `f64` watertight test agrees.
    #[test]
    fn a_finite_t_is_a_hit_whatever_the_triangle_size() {
        for (s, d) in [
            (1.0e18f32, 100.0f32),
            (1.0e12, 1.0e14),
            (1.0e10, 1.0e18),
            (1.0, 1.0e38),
        ] {
            let v = [
                Vec3::new(-s, -s, 0.0),
                Vec3::new(s, -s, 0.0),
                Vec3::new(0.0, s, 0.0),
            ];
            let ray = Ray::new(Vec3::new(0.0, 0.0, d), -Vec3::Z);
            let h = WatertightF32Exact.intersect(&ray, &v);
            assert_eq!(h.map(|h| h.t), Some(d), "s = {s:e}, D = {d:e}: {h:?}");
            assert_eq!(Watertight.intersect(&ray, &v).map(|h| h.t), Some(d));
        }
    }

    #[test]
    fn in_plane_and_degenerate_give_no_hit() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let in_plane = Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X);
        assert!(WatertightF32Exact.intersect(&in_plane, &tri).is_none());
        let through = Ray::new(Vec3::new(0.5, 0.0, 1.0), -Vec3::Z);
        for v in [[Vec3::ZERO, Vec3::X, Vec3::X * 2.0], [Vec3::ONE; 3]] {
            assert!(
                WatertightF32Exact.intersect(&through, &v).is_none(),
                "{v:?}"
            );
        }
    }
}
