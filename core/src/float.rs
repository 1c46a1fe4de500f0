//! The floating-point error model every bound in halfray derives from.
//!
//! We follow the standard model of IEEE-754 arithmetic (Higham; pbrt-v4 §6.8): for each basic
//! operation `fl(a ∘ b) = (a ∘ b)(1 + δ)` with `|δ| ≤ u`, where `u` is the unit roundoff. A
//! chain of `n` roundings is bounded by `gamma(n) = n·u / (1 − n·u)`.
//!
//! Nothing here is a tuned tolerance: each value is a property of binary32 arithmetic.

use crate::error::GeometryError;
use glam::{DVec3, Vec3};

/// Unit roundoff of `f32`: `u = 2⁻²⁴` (half of [`f32::EPSILON`]), unitless (relative).
pub const F32_UNIT_ROUNDOFF: f32 = 1.0 / 16_777_216.0;

/// Unit roundoff of `f64`: `2⁻⁵³`, unitless (relative).
pub const F64_UNIT_ROUNDOFF: f64 = 1.0 / 9_007_199_254_740_992.0;

/// `gamma(n) = n·u / (1 − n·u)` for `f32`: the relative error bound of `n` successive
/// roundings. Unitless. Valid for `n·u < 1`, which holds for every `n` used in this crate.
#[inline]
#[must_use]
pub const fn gamma(n: u32) -> f32 {
    let nu = n as f32 * F32_UNIT_ROUNDOFF;
    nu / (1.0 - nu)
}

/// `gamma(n)` for `f64` arithmetic, relative.
#[inline]
#[must_use]
pub const fn gamma_f64(n: u32) -> f64 {
    let nu = n as f64 * F64_UNIT_ROUNDOFF;
    nu / (1.0 - nu)
}

/// Square root usable in `no_std` (through `libm`).
#[inline]
#[must_use]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// Square root of an `f64`, usable in `no_std`.
#[inline]
#[must_use]
pub fn sqrt_f64(x: f64) -> f64 {
    libm::sqrt(x)
}

/// The direction `dir` (any non-zero length) as a unit vector in `f64`: `dir / |dir|` with
/// both the length and the quotient computed in `f64`, for the caller to keep or round to
/// `f32`. Rounded to `f32`, each component is within one `f32` rounding of the exact unit
/// vector.
///
/// # Errors
///
/// [`GeometryError::NonFinite`] for a non-finite `dir`, [`GeometryError::Degenerate`] for a
/// zero one (the `f64` length of a finite non-zero `f32` vector never underflows).
#[inline]
pub(crate) fn unit_direction_f64(dir: Vec3) -> Result<DVec3, GeometryError> {
    if !dir.is_finite() {
        return Err(GeometryError::NonFinite);
    }
    let d = dir.as_dvec3();
    let len = d.length();
    if !(len > 0.0) {
        return Err(GeometryError::Degenerate);
    }
    Ok(d / len)
}

/// `a·b − c·d` evaluated with one rounding of exact `f64` products of `f32` inputs: the sign of
/// the result is the exact sign of `a·b − c·d` for every finite `f32` input (each product of two
/// `f32` fits exactly in an `f64`), and it is zero only when the exact value is zero.
///
/// This is the orientation predicate of the watertight triangle and polygon tests. It must never
/// be written with a fused multiply-add: fusing breaks the antisymmetry `e(a, b) = −e(b, a)`
/// that makes shared edges consistent.
#[inline]
#[must_use]
pub fn diff_of_products_exact_sign(a: f32, b: f32, c: f32, d: f32) -> f64 {
    (a as f64) * (b as f64) - (c as f64) * (d as f64)
}

/// `a·b − c·d` in plain `f32` (two products, one difference; never fused): a **filter** for
/// [`diff_of_products_exact_sign`]. Rounding is monotone, so `a·b > c·d` gives
/// `fl(a·b) ≥ fl(c·d)` and a non-negative difference (and symmetrically): whenever the result
/// is neither zero nor NaN, its sign is the exact sign of `a·b − c·d`, including when one
/// product overflows to `±∞`. A zero (the exact value is zero, or the products underflow or
/// round together) or a NaN (both products overflow alike, or a non-finite input) decides
/// nothing: the caller falls back to the exact predicate. No tolerance is involved.
#[inline(always)]
#[must_use]
pub fn diff_of_products_sign_filter(a: f32, b: f32, c: f32, d: f32) -> f32 {
    a * b - c * d
}

/// `true` when `e` (a result of [`diff_of_products_sign_filter`]) has a certain sign: neither
/// zero nor NaN.
#[inline(always)]
#[must_use]
pub fn sign_is_certain(e: f32) -> bool {
    // `abs() > 0` is false for NaN, unlike `e != 0.0`.
    e.abs() > 0.0
}

/// The exact sign of `a·b − c·d` for finite `f32` inputs, by integer arithmetic only (no
/// floating-point operation, no `f64`): `1`, `−1` or `0`, equal to the sign of
/// [`diff_of_products_exact_sign`] for every finite input, subnormals and the largest values
/// included. `0` for any non-finite input (nothing is decided there).
///
/// Each input is `± m·2^e` with an integer `m < 2²⁴` (its significand, subnormals included),
/// so each product is `± (m_a·m_b)·2^(e_a + e_b)` with an exact 48-bit integer `m_a·m_b`; the
/// two products are then compared by the position of their leading bit and, when it is the
/// same, by their significands shifted to the top of a `u64` (exact: fewer than 64 bits). On
/// a Cortex-M the product is one `umull`; on a core without an FPU nothing falls back to
/// software floating point. For the watertight test on targets where `f64` is emulated.
/// Out of line: its callers reach it only for the rare edges the `f32` filter leaves open.
#[inline(never)]
#[must_use]
pub fn diff_of_products_sign_int(a: f32, b: f32, c: f32, d: f32) -> i32 {
    if !(a.is_finite() && b.is_finite() && c.is_finite() && d.is_finite()) {
        return 0;
    }
    let (p_neg, p) = exact_product(a, b);
    let (q_neg, q) = exact_product(c, d);
    // `P − Q` with `P = ±p`, `Q = ±q` (magnitudes as (leading-bit position, top-aligned bits)).
    let sign = |neg: bool| if neg { -1 } else { 1 };
    match (p, q) {
        (None, None) => 0,
        (Some(_), None) => sign(p_neg),
        (None, Some(_)) => -sign(q_neg),
        (Some(_), Some(_)) if p_neg != q_neg => sign(p_neg),
        (Some(p), Some(q)) => match p.cmp(&q) {
            core::cmp::Ordering::Greater => sign(p_neg),
            core::cmp::Ordering::Less => -sign(p_neg),
            core::cmp::Ordering::Equal => 0,
        },
    }
}

/// `x·y` exactly, as its sign and, unless it is zero, its magnitude as `(position of the
/// leading bit, significand bits shifted so that the leading bit is bit 63)`: magnitudes
/// compare as these pairs do. Finite inputs only.
#[inline(always)]
fn exact_product(x: f32, y: f32) -> (bool, Option<(i32, u64)>) {
    // `|v| = m·2^e`: `m` the significand as an integer, `e` the exponent of its last bit.
    let split = |v: f32| {
        let bits = v.to_bits();
        let exp = ((bits >> 23) & 0xFF) as i32;
        let frac = bits & 0x007F_FFFF;
        if exp == 0 {
            (frac, -149)
        } else {
            (frac | 0x0080_0000, exp - 150)
        }
    };
    let ((mx, ex), (my, ey)) = (split(x), split(y));
    let neg = x.is_sign_negative() != y.is_sign_negative();
    let m = u64::from(mx) * u64::from(my);
    if m == 0 {
        return (neg, None);
    }
    let lz = m.leading_zeros();
    (neg, Some((ex + ey + (63 - lz as i32), m << lz)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// How far the `f32` evaluation of `γₙ` may lie from its `f64` definition, relative:
    /// 16 unit roundoffs, several times the three roundings (one [`F32_UNIT_ROUNDOFF`] each)
    /// of the operations `gamma` does.
    const GAMMA_DEFINITION_REL: f64 = 16.0 * F32_UNIT_ROUNDOFF as f64;

    #[test]
    fn gamma_matches_definition() {
        let u = F32_UNIT_ROUNDOFF as f64;
        for n in [1u32, 3, 5, 7, 16] {
            let expect = n as f64 * u / (1.0 - n as f64 * u);
            assert!(
                ((gamma(n) as f64) - expect).abs() <= expect * GAMMA_DEFINITION_REL,
                "n = {n}"
            );
        }
        assert_eq!(F32_UNIT_ROUNDOFF, f32::EPSILON / 2.0);
    }

    /// The filter never contradicts the exact predicate: on products that cancel to the last
    /// bit, overflow and underflow, it is either undecided or agrees (oracle: `f64` products,
    /// exact for `f32` inputs, and integer arithmetic for the first case).
    #[test]
    fn sign_filter_is_exact_or_undecided() {
        let a = 1.0 + f32::EPSILON;
        let b = 1.0 + 2.0 * f32::EPSILON;
        // a² − b = 2⁻⁴⁶ exactly ((2²³+1)² − (2⁴⁶ + 2²⁴) = 1 in units of 2⁻⁴⁶): f32 loses it.
        assert!(!sign_is_certain(diff_of_products_sign_filter(a, a, b, 1.0)));
        let cases = [
            (a, a, b, 1.0),
            (3.0e38, 10.0, 1.0, 1.0),
            (3.0e38, 10.0, 3.0e38, 9.0),
            (1.0e-30, 1.0e-20, 1.0e-25, 1.0e-25),
            (1.0e-30, 1.0e-20, 2.0e-30, 1.0e-20),
            (-2.5, 4.0, 1.0, -10.0),
            (0.1, 0.3, 0.3, 0.1),
            (f32::NAN, 1.0, 0.0, 0.0),
            (2.0, 3.0, 1.0, 1.0),
            (1.0, 1.0, 2.0, 3.0),
            (1.0e20, 1.0e20, 1.0, 1.0),
            (0.1, 0.3, 0.3, 0.1000001),
        ];
        let mut decided = 0;
        for (a, b, c, d) in cases {
            let f = diff_of_products_sign_filter(a, b, c, d);
            let exact = f64::from(a) * f64::from(b) - f64::from(c) * f64::from(d);
            if sign_is_certain(f) {
                decided += 1;
                assert_eq!(f > 0.0, exact > 0.0, "{a} {b} {c} {d}: {f} vs {exact}");
                assert!(exact != 0.0);
            }
        }
        assert!(
            decided >= 4,
            "the filter decides the clear cases: {decided}"
        );
    }

    #[test]
    fn exact_sign_predicate_is_antisymmetric_and_exact() {
        // 1 + 2^-23 squared minus 1 + 2^-22 is 2^-46 exactly, lost entirely in f32.
        let a = 1.0 + f32::EPSILON;
        let f32_result = a * a - (1.0 + 2.0 * f32::EPSILON);
        assert_eq!(f32_result, 0.0);
        let exact = diff_of_products_exact_sign(a, a, 1.0 + 2.0 * f32::EPSILON, 1.0);
        assert_eq!(exact, 2f64.powi(-46));
        assert_eq!(
            diff_of_products_exact_sign(1.5, 2.25, 3.0, 7.0),
            -diff_of_products_exact_sign(3.0, 7.0, 1.5, 2.25)
        );
    }

    /// The integer predicate equals the sign of the `f64` one (an independent evaluation: exact
    /// `f64` products, one rounding of their difference) on cancellations to the last bit,
    /// subnormals, the largest finite values, signed zeros and random inputs of every scale.
    #[test]
    fn integer_sign_equals_the_f64_sign() {
        let oracle = |a: f32, b: f32, c: f32, d: f32| {
            let e = diff_of_products_exact_sign(a, b, c, d);
            if e > 0.0 {
                1
            } else if e < 0.0 {
                -1
            } else {
                0
            }
        };
        let a = 1.0 + f32::EPSILON;
        let b = 1.0 + 2.0 * f32::EPSILON;
        let tiny = f32::from_bits(1);
        let worked = [
            (a, a, b, 1.0, 1),
            (b, 1.0, a, a, -1),
            (0.1, 0.3, 0.3, 0.1, 0),
            (-0.0, 5.0, 0.0, 7.0, 0),
            (tiny, 1.0, 0.0, 0.0, 1),
            (tiny, tiny, 0.0, 1.0, 1),
            (tiny, 0.5, tiny, 0.5, 0),
            (f32::MAX, f32::MAX, f32::MAX, 1.0, 1),
            (f32::MAX, -f32::MAX, -f32::MAX, f32::MAX, 0),
            (f32::MIN_POSITIVE, f32::MIN_POSITIVE, tiny, 1.0, -1),
            (3.0, 7.0, 21.0, 1.0, 0),
            (-3.0, 7.0, 21.0, -1.0, 0),
        ];
        for (a, b, c, d, want) in worked {
            assert_eq!(oracle(a, b, c, d), want, "oracle {a:e} {b:e} {c:e} {d:e}");
            assert_eq!(
                diff_of_products_sign_int(a, b, c, d),
                want,
                "{a:e} {b:e} {c:e} {d:e}"
            );
        }
        assert_eq!(diff_of_products_sign_int(f32::NAN, 1.0, 0.0, 0.0), 0);
        assert_eq!(diff_of_products_sign_int(f32::INFINITY, 1.0, 0.0, 0.0), 0);
        // Random bit patterns (every exponent) and near-cancelling pairs.
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut counts = [0usize; 3];
        for _ in 0..200_000 {
            let (r1, r2, r3) = (next(), next(), next());
            let f = |r: u64| f32::from_bits(r as u32);
            let (a, b) = (f(r1), f(r1 >> 32));
            let (c, d) = if r3 & 1 == 0 {
                (f(r2), f(r2 >> 32))
            } else {
                // c·d within a few ulps of a·b.
                let bump =
                    |x: f32, k: u64| f32::from_bits(x.to_bits().wrapping_add((k % 3) as u32));
                (bump(a, r3 >> 1), bump(b, r3 >> 3))
            };
            if !(a.is_finite() && b.is_finite() && c.is_finite() && d.is_finite()) {
                continue;
            }
            let want = oracle(a, b, c, d);
            counts[(want + 1) as usize] += 1;
            assert_eq!(
                diff_of_products_sign_int(a, b, c, d),
                want,
                "{a:e} {b:e} {c:e} {d:e}"
            );
        }
        assert!(
            counts.iter().all(|&n| n > 1000),
            "every sign exercised: {counts:?}"
        );
    }
}
