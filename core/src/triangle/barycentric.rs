//! Barycentric coordinates of a point, both ways the specification shows, with their error
//! behaviour on slivers.
//!
//! For a triangle `v0, v1, v2` and a point `p`, the coordinates `(b0, b1, b2)` (sum 1) give
//! `p = b0·v0 + b1·v1 + b2·v2`; a point off the triangle's plane gets the coordinates of its
//! orthogonal projection onto the plane (both methods below).
//!
//! * [`barycentric_signed_areas`]: ratios of signed areas, `bᵢ = n·((vⱼ − p) × (vₖ − p)) / n·n`
//!   with `n = (v1 − v0) × (v2 − v0)` and `(i, j, k)` cyclic: each weight is the sub-triangle
//!   opposite `vᵢ` over the whole triangle.
//! * [`barycentric_dot_system`]: the 2×2 normal equations of `p − v0 = b1·e1 + b2·e2`
//!   (`e1 = v1 − v0`, `e2 = v2 − v0`), solved by Cramer's rule on
//!   `d00 = e1·e1, d01 = e1·e2, d11 = e2·e2, d20 = (p − v0)·e1, d21 = (p − v0)·e2`:
//!   `b1 = (d11·d20 − d01·d21)/D`, `b2 = (d00·d21 − d01·d20)/D`, `D = d00·d11 − d01²`,
//!   `b0 = 1 − b1 − b2` (Ericson, *Real-Time Collision Detection* §3.4).
//!
//! **Error behaviour.** Let `ρ` be the largest of `|e1|`, `|e2|`, `|v1 − v2|` and
//! `|vᵢ − p|`, and `κ = ρ²/|e1 × e2|` ([`sliver_condition`]): about `1/sin θ` for the smallest
//! angle `θ` of the triangle, so `κ ≈ 1` for a well-shaped triangle and huge for a sliver.
//! For `p` in the plane, to first order in `u = 2⁻²⁴`:
//!
//! * signed areas: `|b̂ᵢ − bᵢ| ≤` [`BARYCENTRIC_AREAS_ERROR`]`·κ·(1 + |b0| + |b1| + |b2|)`.
//!   Each cross product loses `γ·ρ²` absolutely and is compared with `|n| = ρ²/κ`:
//!   conditioning `κ`.
//! * dot-product system: `|b̂ᵢ − bᵢ| ≤` [`BARYCENTRIC_DOT_ERROR`]`·κ²·(1 + |b0| + |b1| + |b2|)`.
//!   `D = |e1 × e2|² = |e1|²|e2|² sin²θ` is computed by cancellation from products of size
//!   `ρ⁴`: conditioning `κ² ~ 1/sin²θ`. A sliver with `sin θ ≈ 10⁻³` loses about 6 of the
//!   24 bits with signed areas and all of them with the dot products (test
//!   `sliver_dot_system_loses_twice_the_digits`, against exact rational values).
//!
//! Prefer the signed areas for slivers; the dot-product form is cheaper when many points
//! are projected on one triangle (`d00`, `d01`, `d11`, `D` are per triangle).
//!
//! Worked example (the right triangle of legs 4, a point inside):
//!
//! ```
//! use halfray_core::Vec3;
//! use halfray_core::triangle::barycentric::{barycentric_dot_system, barycentric_signed_areas};
//! let v = [Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 4.0, 0.0)];
//! let p = Vec3::new(1.0, 2.0, 0.0);
//! // n = (0, 0, 16); the sub-triangles opposite v0, v1, v2 have n-components 4, 4, 8 of 16.
//! assert_eq!(barycentric_signed_areas(p, &v), Some([0.25, 0.25, 0.5]));
//! // d00 = 16, d01 = 0, d11 = 16, d20 = 4, d21 = 8, D = 256: b1 = 64/256, b2 = 128/256.
//! assert_eq!(barycentric_dot_system(p, &v), Some([0.25, 0.25, 0.5]));
//! ```

use crate::float::{gamma, sqrt_f64};
use glam::Vec3;

/// First-order error coefficient of [`barycentric_signed_areas`], unitless (`gamma(48)`):
/// `|b̂ᵢ − bᵢ| ≤ BARYCENTRIC_AREAS_ERROR·κ·(1 + Σ|bⱼ|)` for `p` in the plane, `κ` from
/// [`sliver_condition`]. Derivation: the edge differences (`u` each) and the cross products
/// (`γ₃`) give each of `n` and `w = (vⱼ − p) × (vₖ − p)` an absolute error of `√3·γ₅·ρ²`;
/// `n·w` and `n·n` then err by `√3·γ₅·ρ²(|n| + |w|) + γ₃|n||w|` with `|w| = |bᵢ||n|`, i.e.
/// by `≈ 2√3·γ₅·κ` relative to `|n|²` per unit of `(1 + |bᵢ|)`: `≈ 35u·κ`, and the division
/// one more; 48 covers it with margin.
pub const BARYCENTRIC_AREAS_ERROR: f32 = gamma(48);

/// First-order error coefficient of [`barycentric_dot_system`], unitless (`gamma(32)`):
/// `|b̂ᵢ − bᵢ| ≤ BARYCENTRIC_DOT_ERROR·κ²·(1 + Σ|bⱼ|)`. Derivation: each `dᵢⱼ` errs by
/// `γ₅` of the product of its two vectors' lengths (`≤ γ₅·ρ²`), so `D` and the numerators
/// err by `≈ 2γ₇·ρ⁴` absolutely, against `D = |e1 × e2|² = ρ⁴/κ²`; `b0 = 1 − b1 − b2` adds
/// both: `≈ 4γ₇·κ²(1 + Σ|bⱼ|)`, below `γ₃₂·κ²(…)`.
pub const BARYCENTRIC_DOT_ERROR: f32 = gamma(32);

/// `(b0, b1, b2)` of `p` (projected onto the plane) by ratios of signed areas (module
/// docs). `None` when the triangle is degenerate in `f32` (`n·n` zero, subnormal or not
/// finite) or a coordinate is not finite; never panics.
#[must_use]
pub fn barycentric_signed_areas(p: Vec3, v: &[Vec3; 3]) -> Option<[f32; 3]> {
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let nn = n.dot(n);
    if !(nn >= f32::MIN_POSITIVE) || !nn.is_finite() || !p.is_finite() {
        return None;
    }
    let (x0, x1, x2) = (v[0] - p, v[1] - p, v[2] - p);
    let b = [
        n.dot(x1.cross(x2)) / nn,
        n.dot(x2.cross(x0)) / nn,
        n.dot(x0.cross(x1)) / nn,
    ];
    b.iter().all(|x| x.is_finite()).then_some(b)
}

/// `(b0, b1, b2)` of `p` (projected onto the plane) from the 2×2 dot-product system by
/// Cramer's rule (module docs). `None` when `D ≤ 0` in `f32` (degenerate or, for a sliver
/// with `κ² ≳ 1/u`, lost to rounding), or a result is not finite; never panics.
#[must_use]
pub fn barycentric_dot_system(p: Vec3, v: &[Vec3; 3]) -> Option<[f32; 3]> {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let ep = p - v[0];
    let d00 = e1.dot(e1);
    let d01 = e1.dot(e2);
    let d11 = e2.dot(e2);
    let d20 = ep.dot(e1);
    let d21 = ep.dot(e2);
    let denom = d00 * d11 - d01 * d01;
    if !(denom > 0.0) || !denom.is_finite() {
        return None;
    }
    let b1 = (d11 * d20 - d01 * d21) / denom;
    let b2 = (d00 * d21 - d01 * d20) / denom;
    let b = [1.0 - b1 - b2, b1, b2];
    b.iter().all(|x| x.is_finite()).then_some(b)
}

/// The condition number `κ = ρ²/|e1 × e2|` of both barycentric computations (module docs),
/// evaluated in `f64`; `+∞` for a degenerate triangle, NaN for non-finite input.
#[must_use]
pub fn sliver_condition(p: Vec3, v: &[Vec3; 3]) -> f64 {
    let (a, b, c, q) = (
        v[0].as_dvec3(),
        v[1].as_dvec3(),
        v[2].as_dvec3(),
        p.as_dvec3(),
    );
    let rho2 = [b - a, c - a, c - b, a - q, b - q, c - q]
        .iter()
        .map(|d| d.length_squared())
        .fold(0.0f64, f64::max);
    rho2 / sqrt_f64((b - a).cross(c - a).length_squared())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::lcg;

    /// Exact barycentrics of `p` for a triangle in the plane `z = 0` with integer
    /// coordinates, as exact integer ratios evaluated once in `f64`.
    fn exact(p: [i64; 2], v: [[i64; 2]; 3]) -> [f64; 3] {
        let cross = |a: [i64; 2], b: [i64; 2], c: [i64; 2]| {
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        };
        let whole = cross(v[0], v[1], v[2]) as f64;
        [
            cross(p, v[1], v[2]) as f64 / whole,
            cross(p, v[2], v[0]) as f64 / whole,
            cross(p, v[0], v[1]) as f64 / whole,
        ]
    }

    fn to_vec3(a: [i64; 2]) -> Vec3 {
        Vec3::new(a[0] as f32, a[1] as f32, 0.0)
    }

    /// Largest error of `got` against the exact values, and the documented bound's
    /// `(1 + Σ|b|)` factor.
    fn err(got: [f32; 3], want: [f64; 3]) -> (f64, f64) {
        let e = (0..3)
            .map(|i| (f64::from(got[i]) - want[i]).abs())
            .fold(0.0, f64::max);
        (e, 1.0 + want.iter().map(|b| b.abs()).sum::<f64>())
    }

    /// Random integer triangles (exact in `f32`, exact oracle), well shaped and slivers,
    /// points inside and outside: both methods stay within their documented bounds.
    #[test]
    fn both_methods_within_documented_bounds() {
        let mut s = 7u64;
        let mut slivers = 0;
        for case in 0..4000 {
            let mut r = |range: f32| ((lcg(&mut s) * 2.0 - 1.0) * range) as i64;
            let v0 = [r(4000.0), r(4000.0)];
            let v1 = [r(4000.0), r(4000.0)];
            // Every other case: v2 near the line v0–v1 (a sliver).
            let t = f64::from(r(1000.0).abs() as f32) / 1000.0;
            let v2 = if case % 2 == 0 {
                [
                    v0[0] + ((v1[0] - v0[0]) as f64 * t) as i64 + r(3.0),
                    v0[1] + ((v1[1] - v0[1]) as f64 * t) as i64 + r(3.0),
                ]
            } else {
                [r(4000.0), r(4000.0)]
            };
            let p = [r(5000.0), r(5000.0)];
            let v = [v0, v1, v2];
            let vf = v.map(to_vec3);
            let whole = (v1[0] - v0[0]) * (v2[1] - v0[1]) - (v1[1] - v0[1]) * (v2[0] - v0[0]);
            if whole == 0 {
                assert_eq!(barycentric_signed_areas(to_vec3(p), &vf), None);
                continue;
            }
            let want = exact(p, v);
            let kappa = sliver_condition(to_vec3(p), &vf);
            if kappa > 100.0 {
                slivers += 1;
            }
            let (e, f) = err(barycentric_signed_areas(to_vec3(p), &vf).unwrap(), want);
            let bound = f64::from(BARYCENTRIC_AREAS_ERROR) * kappa * f;
            assert!(
                e <= bound,
                "areas: error {e:e} > bound {bound:e}, {v:?} {p:?}"
            );
            let kappa2 = kappa * kappa;
            if let Some(b) = barycentric_dot_system(to_vec3(p), &vf) {
                let (e, f) = err(b, want);
                let bound = f64::from(BARYCENTRIC_DOT_ERROR) * kappa2 * f;
                assert!(
                    e <= bound,
                    "dot: error {e:e} > bound {bound:e}, {v:?} {p:?}"
                );
            } else {
                // Refused only when rounding can have destroyed D (κ² u ≳ 1).
                assert!(kappa2 * f64::from(BARYCENTRIC_DOT_ERROR) >= 1e-3, "{v:?}");
            }
        }
        assert!(slivers > 500, "only {slivers} slivers generated");
    }

    /// A sliver with smallest angle ≈ 1e-3 rad against its exact rational barycentrics: the
    /// dot-product system's error is about `κ` times the signed areas' (κ ≈ 1e3 here), as
    /// the `1/sin θ` versus `1/sin² θ` conditioning says.
    #[test]
    fn sliver_dot_system_loses_twice_the_digits() {
        let v = [[0, 0], [4099, 3], [8191, 13]];
        let p = [3001, 5];
        let vf = v.map(to_vec3);
        let want = exact(p, v);
        let kappa = sliver_condition(to_vec3(p), &vf);
        assert!(kappa > 1e3 && kappa < 1e4, "κ = {kappa}");
        let (ea, _) = err(barycentric_signed_areas(to_vec3(p), &vf).unwrap(), want);
        let (ed, _) = err(barycentric_dot_system(to_vec3(p), &vf).unwrap(), want);
        assert!(ea < 1e-4, "areas error {ea:e}");
        assert!(ed > 20.0 * ea, "dot error {ed:e} not ≫ areas error {ea:e}");
        assert!(ed > 1e-3, "dot error {ed:e}");
    }

    /// Degenerate and non-finite input gives `None`, never a panic; a point off the plane
    /// gets its projection's coordinates.
    #[test]
    fn degenerate_nonfinite_and_off_plane() {
        let v = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        assert_eq!(barycentric_signed_areas(Vec3::ZERO, &line), None);
        assert_eq!(barycentric_dot_system(Vec3::ZERO, &line), None);
        for bad in [f32::NAN, f32::INFINITY] {
            let p = Vec3::new(bad, 0.0, 0.0);
            assert_eq!(barycentric_signed_areas(p, &v), None);
            assert_eq!(barycentric_dot_system(p, &v), None);
            let w = [Vec3::ZERO, Vec3::new(bad, 0.0, 0.0), Vec3::Y];
            assert_eq!(barycentric_signed_areas(Vec3::ZERO, &w), None);
            assert_eq!(barycentric_dot_system(Vec3::ZERO, &w), None);
        }
        let p = Vec3::new(0.25, 0.5, 3.0);
        assert_eq!(barycentric_signed_areas(p, &v), Some([0.25, 0.25, 0.5]));
        assert_eq!(barycentric_dot_system(p, &v), Some([0.25, 0.25, 0.5]));
    }
}
