//! Rescaling the `f32` overlap tests' inputs by a power of two (so squares neither overflow nor
//! underflow) and the absolute padding that covers subnormal results; see the
//! [`super::overlap`] module docs ("Rounding model", "Rescaling").

use glam::Vec3;

/// Absolute padding of every `f32` comparison, in the rescaled units: `2⁻¹⁴⁰`.
///
/// Why: an operation whose result is subnormal has an absolute error up to `2⁻¹⁵⁰` on top of
/// the relative model; no test takes more than 512 such operations (`2⁹·2⁻¹⁵⁰ < 2⁻¹⁴⁰`),
/// whose effect on a compared quantity is at most their sum (every factor they are
/// multiplied by is below `2¹⁰` when the quantities are that small). Cost: nothing at
/// ordinary scales (`2⁻¹⁴⁰ ≈ 7e-43`); it gives every false-positive band the absolute
/// part [`BAND_ABS_PER_MAGNITUDE`].
pub const UNDERFLOW_PAD_ABS: f32 = f32::from_bits(1 << 9);

/// Absolute part of every `f32` overlap test's false-positive band, in world units per unit
/// of `max(m, 1)` (`m` the largest input magnitude): `2⁻⁶⁸`.
///
/// Derivation: a squared-distance test reports "apart" when `fl(d²) > fl(R²)·(1 + pad) +`
/// [`UNDERFLOW_PAD_ABS`] in the rescaled units. Near that threshold `d²` is itself
/// subnormal, so each side carries up to `2⁻¹⁴¹` of absolute error on top of the relative
/// model (see [`UNDERFLOW_PAD_ABS`]): a true `d²` beyond the relative band by
/// `2⁻¹⁴⁰ + 2·2⁻¹⁴¹ = 2⁻¹³⁹` is always reported apart, a distance of `2⁻⁶⁹·⁵` rescaled
/// units. A rescaled unit is at most `2m` world units (`m ∈ [2ᵉ⁻¹, 2ᵉ)` becomes `m·2⁻ᵉ`)
/// and exactly one when nothing is rescaled, so `2⁻⁶⁹·⁵·2·max(m, 1) < 2⁻⁶⁸·max(m, 1)`.
/// The SAT tests compare linear quantities padded by `2⁻¹⁴⁰`: far inside it.
pub const BAND_ABS_PER_MAGNITUDE: f32 = 1.0 / 295_147_905_179_352_825_856.0;

/// Above this largest input magnitude the `f32` tests rescale: `2⁶⁰` (squares of larger
/// values may overflow once summed with the padding).
pub const RESCALE_ABOVE: f32 = 1_152_921_504_606_846_976.0;
/// Below this largest input magnitude the `f32` tests rescale: `2⁻⁶⁰` (squares of smaller
/// values are subnormal).
pub const RESCALE_BELOW: f32 = 1.0 / RESCALE_ABOVE;

/// The power of two the `f32` tests multiply their inputs by, given the largest input
/// magnitude `m`: 1 in `[RESCALE_BELOW, RESCALE_ABOVE]` (and for 0 or NaN), else `2⁻ᵉ` with
/// `m ∈ [2ᵉ⁻¹, 2ᵉ)`, so `m` becomes `[½, 1)` (capped at `2¹²⁷` for `m < 2⁻¹²⁷`).
#[inline]
#[must_use]
pub fn rescale_factor(m: f32) -> f32 {
    if !(m > RESCALE_ABOVE || (m < RESCALE_BELOW && m > 0.0)) {
        return 1.0;
    }
    let (_, e) = libm::frexpf(m);
    let x = (-e).min(127);
    if x >= -126 {
        f32::from_bits(((x + 127) as u32) << 23)
    } else {
        // 2⁻¹²⁷ … 2⁻¹²⁸ (m up to f32::MAX has e ≤ 128): subnormal powers of two.
        f32::from_bits(1u32 << (x + 149).clamp(0, 22))
    }
}

/// Largest absolute component.
#[inline]
pub(crate) fn max_abs(v: Vec3) -> f32 {
    v.abs().max_element()
}
