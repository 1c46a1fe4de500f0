//! Conservative overlap tests between bounding volumes.
//!
//! **Contract.** Every test returns `true` ("overlap") whenever the two exact volumes (the
//! closed sets their stored `f32` parameters define) share a point: rounding never makes
//! it report "apart" for overlapping volumes. It may return `true` for volumes that are
//! apart by at most a stated band (`*_BAND_REL`). Each test is a total function of valid
//! volumes (the constructors refuse NaN, infinite and negative parameters), never panics and
//! is symmetric in its arguments' roles as documented.
//!
//! **Rounding model.** `fl(a ∘ b) = (a ∘ b)(1 + δ) + η` with `|δ| ≤ u = 2⁻²⁴` and, only when
//! the result is subnormal, `|η| ≤ 2⁻¹⁵⁰` ([`crate::float`]). Every `f32` test bounds the
//! rounding of each side of its final comparison by `gamma(n)` of a scale it computes, and
//! adds [`UNDERFLOW_PAD_ABS`] for the `η` terms.
//!
//! **Rescaling.** Before an `f32` test evaluates anything, its inputs are multiplied by a
//! power of two ([`rescale_factor`]) when their largest magnitude `m` is above
//! [`RESCALE_ABOVE`] or below [`RESCALE_BELOW`], bringing `m` into `[½, 1)` (or as close as
//! `f32` allows for `m < 2⁻¹²⁷`). That is exact except for components pushed into the
//! subnormal range, whose absolute error (`≤ 2⁻¹⁵⁰` each) [`UNDERFLOW_PAD_ABS`] covers, and
//! it keeps every square and sum finite for all finite `f32` inputs. The absolute part of
//! every false-positive band is then at most [`BAND_ABS_PER_MAGNITUDE`]`·max(m, 1)` world
//! units.
//!
//! **Domain of the bands.** The conservative contract ("overlap" for volumes that share a
//! point) holds for every valid input. The false-positive bands are promised, and fuzzed
//! (`overlap`), for inputs whose largest magnitude `m` lies in `[2⁻⁹⁰, 2⁹⁰]`; outside it the
//! tests still answer, conservatively, but a pair farther apart than the band may be reported
//! overlapping.

use super::rescale::max_abs;
use super::sat;
use super::{BoundingSphere, Capsule, Obb};
use crate::aabb::Aabb;
use crate::float::{gamma, gamma_f64, sqrt_f64};
use glam::{DVec3, Vec3};

pub use super::rescale::{
    BAND_ABS_PER_MAGNITUDE, RESCALE_ABOVE, RESCALE_BELOW, UNDERFLOW_PAD_ABS, rescale_factor,
};
pub use super::sat::{OBB_ABS_R_EPSILON, OBB_OBB_BAND_REL, OBB_SAT_PAD_REL};

/// Relative padding of the squared-distance comparisons of [`sphere_sphere`] and
/// [`sphere_aabb`]: `gamma(12)`, unitless.
///
/// Derivation: the squared distance `d² = Σ dₖ²` takes 5 roundings per term (the
/// difference, exactly rounded from exact `f32` inputs so its sign is right; its square; two
/// sums), all on non-negative quantities, so `fl(d²) ≤ d²(1 + γ₅)`; the squared radius sum
/// `(r₁ + r₂)²` takes 3, so `R² ≤ fl(R²)(1 + γ₃)`... and the padding itself 3 more
/// (`fl(R²) + fl(PAD·fl(R²)) + UNDERFLOW_PAD_ABS`). Overlap (`d² ≤ R²`) then always passes
/// `fl(d²) ≤ fl(R²)·(1 + γ₁₂) + UNDERFLOW_PAD_ABS` since `γ₅ + γ₃ + 3u < γ₁₂`.
pub const SPHERE_PAD_REL: f32 = gamma(12);

/// False-positive band of [`sphere_sphere`] and [`sphere_aabb`], unitless: volumes reported
/// overlapping are at most `SPHERE_BAND_REL·(r₁ + r₂) + BAND_ABS_PER_MAGNITUDE·max(m, 1)`
/// apart (distance between the sets; `m` the largest input magnitude, the absolute term
/// [`BAND_ABS_PER_MAGNITUDE`]). `gamma(16)` ≈ 9.5e-7: the square root of the `1 + γ₁₂`
/// padding and the `γ₅`, `γ₃` roundings of both sides, with margin.
pub const SPHERE_BAND_REL: f32 = gamma(16);

/// Relative padding of the projections `|aₖ·(s − c)|` in [`sphere_obb`], relative to
/// `Σⱼ|aₖⱼ|·|sⱼ − cⱼ| + eₖ`: `gamma(8)`, unitless. The projection takes 4 roundings relative
/// to the sum of the absolute values of its terms (a difference, a product, two sums: the
/// terms may cancel), the subtraction of `eₖ` and of the padding 3 more, applied to
/// quantities at most `Σ|aₖⱼ||sⱼ − cⱼ| + eₖ`.
pub const SPHERE_OBB_PROJ_PAD_REL: f32 = gamma(8);

/// Relative padding of the squared-distance comparison of [`sphere_obb`]: `gamma(64)`,
/// unitless.
///
/// Derivation: the test measures the distance from the sphere's centre to the box in the
/// box's frame `t = A(x − c)` (`A` the matrix of the axes), where the box is exactly
/// `[−e, e]`; with axes orthonormal within `τ =` [`super::OBB_ORTHONORMAL_TOL`],
/// `‖A‖₂ ≤ √(1 + 3τ) ≤ 1 + 2τ`, so that frame distance is at most `(1 + 2τ)` times the
/// Euclidean one, and its square `(1 + 5τ)` times. `5τ = 40u`; the squared sum of the
/// (lowered) excesses takes `γ₅`, `r²` and the padding `γ₄`: `40u + 9u` plus margin
/// `< 64u`.
pub const SPHERE_OBB_PAD_REL: f32 = gamma(64);

/// False-positive band of [`sphere_obb`], unitless: a sphere and a box reported overlapping
/// are at most `SPHERE_OBB_BAND_REL·(r + Σ|sⱼ − cⱼ| + Σeₖ) + A·max(m, 1)` apart (`A =`
/// [`BAND_ABS_PER_MAGNITUDE`]; `gamma(96)` ≈ 5.7e-6): twice the projection padding per axis
/// (`√3·2γ₈`), the relative `γ₆₄` on the squared radius, and the frame's stretch `2τ`.
pub const SPHERE_OBB_BAND_REL: f32 = gamma(96);

/// Relative padding of the capsule tests' separation certificate (in `f64`), unitless:
/// `gamma_f64(16)` of `max|n·(p − q)| + (r₁ + r₂)|n|` over the endpoint pairs.
///
/// Derivation: the candidate axis `n` can be anything (any axis whose projections are
/// disjoint proves separation); only the projections are bounded: each `n·(p − q)` with `p`,
/// `q` `f32` endpoints takes 4 roundings relative to `Σ|nₖ||pₖ − qₖ|`, `(r₁ + r₂)|n|` takes 5
/// relative to itself, the comparison and padding 3: `γ_f64(16)` covers them.
pub const CAPSULE_PAD_REL: f64 = gamma_f64(16);

/// False-positive band of [`capsule_capsule`] and [`capsule_sphere`], unitless (`2⁻³⁰`):
/// capsules reported overlapping are at most
/// `CAPSULE_BAND_REL·(|a₁|₁ + |b₁|₁ + |a₂|₁ + |b₂|₁ + r₁ + r₂)` apart. The certificate axis is the difference of the closest points of the
/// two segments computed in `f64` (Ericson, *Real-Time Collision Detection* §5.1.9), and
/// that axis made perpendicular to the segments: the closest points err by a few `f64`
/// roundings of the coordinates, and once perpendicular to a segment the axis no longer
/// turns that error into a tilt of the segment's projection. `2⁻³⁰` leaves a wide margin
/// (checked by the property tests and the `overlap` fuzz target).
pub const CAPSULE_BAND_REL: f64 = 1.0 / 1_073_741_824.0;

/// `lhs > rhs·(1 + pad) + UNDERFLOW_PAD_ABS`: the "apart" decision of a squared-distance
/// test, `f32`.
#[inline]
fn clearly_greater(lhs: f32, rhs: f32, pad: f32) -> bool {
    lhs > rhs + rhs * pad + UNDERFLOW_PAD_ABS
}

/// Box–box: [`Aabb::overlaps`], which only compares coordinates and is therefore exact
/// (closed boxes; empty or NaN boxes overlap nothing). No band.
#[inline]
#[must_use]
pub fn aabb_aabb(a: &Aabb, b: &Aabb) -> bool {
    a.overlaps(b)
}

/// Sphere–sphere: `|c₁ − c₂| ≤ r₁ + r₂`, in `f32`, padded by [`SPHERE_PAD_REL`]; band
/// [`SPHERE_BAND_REL`].
#[must_use]
pub fn sphere_sphere(a: &BoundingSphere, b: &BoundingSphere) -> bool {
    let m = max_abs(a.center())
        .max(max_abs(b.center()))
        .max(a.radius())
        .max(b.radius());
    let k = rescale_factor(m);
    let d = a.center() * k - b.center() * k;
    let rr = a.radius() * k + b.radius() * k;
    !clearly_greater(d.dot(d), rr * rr, SPHERE_PAD_REL)
}

/// Sphere–box: the squared distance from the centre to the closed box (per axis the excess
/// `max(min − c, c − max, 0)`, exactly signed) against `r²`, in `f32`, padded by
/// [`SPHERE_PAD_REL`]; band [`SPHERE_BAND_REL`] (with `r₂ = 0`). An empty or non-finite box
/// overlaps nothing.
#[must_use]
pub fn sphere_aabb(s: &BoundingSphere, b: &Aabb) -> bool {
    if !b.is_valid() || !b.is_finite() {
        return false;
    }
    let m = max_abs(s.center())
        .max(s.radius())
        .max(max_abs(b.min))
        .max(max_abs(b.max));
    let k = rescale_factor(m);
    let c = s.center() * k;
    let excess = (b.min * k - c).max(c - b.max * k).max(Vec3::ZERO);
    let r = s.radius() * k;
    !clearly_greater(excess.dot(excess), r * r, SPHERE_PAD_REL)
}

/// Sphere–OBB: the squared distance from the centre to the box measured in the box's frame
/// (each excess `|aₖ·(s − c)| − eₖ` lowered by [`SPHERE_OBB_PROJ_PAD_REL`] of its terms,
/// clamped at 0) against `r²` padded by [`SPHERE_OBB_PAD_REL`] for the frame's deviation
/// from orthonormal; `f32`. Band [`SPHERE_OBB_BAND_REL`].
#[must_use]
pub fn sphere_obb(s: &BoundingSphere, b: &Obb) -> bool {
    let e = b.half_extents();
    let m = max_abs(s.center())
        .max(s.radius())
        .max(max_abs(b.center()))
        .max(max_abs(e));
    let k = rescale_factor(m);
    let d = s.center() * k - b.center() * k;
    let e = e * k;
    let axes = b.axes();
    let mut sum = 0.0f32;
    for i in 0..3 {
        let t = axes[i].dot(d).abs();
        let scale = axes[i].abs().dot(d.abs()) + e[i];
        let x = (t - (e[i] + SPHERE_OBB_PROJ_PAD_REL * scale)).max(0.0);
        sum += x * x;
    }
    let r = s.radius() * k;
    !clearly_greater(sum, r * r, SPHERE_OBB_PAD_REL)
}

/// OBB–OBB: the separating-axis test over the 15 axes (3 + 3 face normals, 9 edge cross
/// products; Gottschalk 1996, Ericson §4.4.1) in `f32`, with [`OBB_ABS_R_EPSILON`] added to
/// every `|Rᵢⱼ|` and every comparison padded by [`OBB_SAT_PAD_REL`] (derivations there).
/// Band [`OBB_OBB_BAND_REL`].
#[must_use]
pub fn obb_obb(a: &Obb, b: &Obb) -> bool {
    sat::obb_obb(a, b)
}

/// Box–OBB: [`obb_obb`] in the frame of the OBB's centre: the box moved by `−c` with its
/// bounds rounded outward ([`Aabb::relative_to`]) and converted by [`Obb::from_aabb`] (both
/// contain the exact box, so overlap is never lost), against the OBB centred at the origin
/// (an exact move). Working relative to `c` keeps the conversion's roundings inside the
/// band [`OBB_OBB_BAND_REL`]: the move and the conversion push each face of the box out by
/// at most `8u·(|Δcₖ| + eₖ)` (`u = 2⁻²⁴`; `Δc`, `e` the box's centre offset and half-size),
/// at most `8u·S` along any of the 15 axes, far inside the band's margin. In world
/// coordinates they would be ulps of the box's distance from the origin, which the band of
/// a small box far away does not cover (a box one ulp thick at `x = 10⁶` grew by `2⁻⁴`). An
/// empty or non-finite box overlaps nothing, and a box whose move or conversion leaves `f32`
/// (only beyond the bands' domain) is reported overlapping (conservative).
#[must_use]
pub fn aabb_obb(a: &Aabb, b: &Obb) -> bool {
    if !a.is_valid() || !a.is_finite() {
        return false;
    }
    let moved = Obb::new(Vec3::ZERO, b.axes(), b.half_extents());
    match (Obb::from_aabb(&a.relative_to(b.center())), moved) {
        (Ok(a), Ok(b)) => sat::obb_obb(&a, &b),
        _ => true,
    }
}

/// Capsule–capsule: "apart" only with a certificate: an axis along which the segments'
/// projections are separated by more than `(r₁ + r₂)|n|` plus [`CAPSULE_PAD_REL`] of the
/// evaluated magnitudes. The axes tried are `n = p − q` between the closest points of the
/// two segments (computed in `f64`), `n` made perpendicular to either or both segments, and
/// the segments' common normal. Any axis proves separation, so rounding in `n` cannot make
/// the test wrong, only looser: band [`CAPSULE_BAND_REL`].
///
/// Symmetric: the capsules are taken in a fixed order (by their bit patterns), since the
/// closest-point computation is not symmetric in rounding.
#[must_use]
pub fn capsule_capsule(a: &Capsule, b: &Capsule) -> bool {
    let key = |c: &Capsule| {
        let (p, q) = (c.a().to_array(), c.b().to_array());
        [p[0], p[1], p[2], q[0], q[1], q[2], c.radius()].map(f32::to_bits)
    };
    let (a, b) = if key(a) <= key(b) { (a, b) } else { (b, a) };
    let (p, q) = closest_points_segments(a.a(), a.b(), b.a(), b.b());
    let n = p - q;
    let d1 = b_minus_a(a);
    let d2 = b_minus_a(b);
    // The exact closest direction is perpendicular to each segment whose closest point is
    // interior; rounding in `p`, `q` tilts `n` off it, which a long segment turns into a
    // large loss of gap. So `n` with its component along each segment removed, and the
    // common normal, are tried as well: each is a valid axis on its own.
    let reject = |v: DVec3, d: DVec3| {
        let l2 = d.length_squared();
        if l2 > 0.0 { v - d * (v.dot(d) / l2) } else { v }
    };
    let normal = d1.cross(d2);
    let normal = if normal.dot(n) < 0.0 { -normal } else { normal };
    let candidates = [
        n,
        reject(n, d1),
        reject(n, d2),
        reject(reject(n, d1), d2),
        normal,
    ];
    !candidates.iter().any(|&n| separated_along(a, b, n))
}

/// `b − a` of a capsule's segment, `f64`.
fn b_minus_a(c: &Capsule) -> DVec3 {
    c.b().as_dvec3() - c.a().as_dvec3()
}

/// `true` when `n` proves the capsules apart: the projections of the segments are separated
/// by more than `(r₁ + r₂)|n|` plus [`CAPSULE_PAD_REL`] of the evaluated magnitudes (`n`
/// points from `b` towards `a`).
fn separated_along(a: &Capsule, b: &Capsule, n: DVec3) -> bool {
    let mut gap = f64::INFINITY;
    let mut scale = 0.0f64;
    for x in [a.a(), a.b()] {
        for y in [b.a(), b.b()] {
            let d = x.as_dvec3() - y.as_dvec3();
            gap = gap.min(n.dot(d));
            scale = scale.max(n.abs().dot(d.abs()));
        }
    }
    let reach = (f64::from(a.radius()) + f64::from(b.radius())) * sqrt_f64(n.length_squared());
    gap.is_finite() && gap - reach > CAPSULE_PAD_REL * (scale + reach)
}

/// Capsule–sphere: [`capsule_capsule`] with the sphere as a capsule of one point.
#[must_use]
pub fn capsule_sphere(a: &Capsule, s: &BoundingSphere) -> bool {
    match Capsule::new(s.center(), s.center(), s.radius()) {
        Ok(b) => capsule_capsule(a, &b),
        Err(_) => true,
    }
}

/// Closest points of the segments `[p1, q1]` and `[p2, q2]` in `f64` (Ericson, *Real-Time
/// Collision Detection* §5.1.9, degenerate segments included): `(c1, c2)`. Any rounding only
/// moves the points along their segments.
fn closest_points_segments(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> (DVec3, DVec3) {
    let (p1, q1, p2, q2) = (p1.as_dvec3(), q1.as_dvec3(), p2.as_dvec3(), q2.as_dvec3());
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let f = d2.dot(r);
    let (s, t) = if a <= 0.0 && e <= 0.0 {
        (0.0, 0.0)
    } else if a <= 0.0 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= 0.0 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let s = if s.is_finite() { s } else { 0.0 };
    let t = if t.is_finite() { t } else { 0.0 };
    (p1 + d1 * s, p2 + d2 * t)
}
