//! Rays with a parametric interval.
//!
//! **Interval convention (everywhere in halfray):** a ray is the set of points
//! `origin + t·direction` for `t` in the half-open interval **`(t_min, t_max]`**: the lower end
//! is *exclusive*, the upper end *inclusive*. This is Embree's fast-mode convention and pbrt's
//! `t > 0` test: a ray that starts exactly on a surface (`t = t_min = 0`) does not report that
//! surface, while a hit exactly at `t_max` (a shadow ray to a light sitting on a surface, or
//! a closest-hit search shrinking `t_max` to the current hit) is kept.
//!
//! The direction need not be unit length; `t` is measured in units of `|direction|`.

use crate::error::RayError;
use glam::Vec3;

/// A ray `origin + t·direction`, `t ∈ (t_min, t_max]`.
///
/// Fields are public so that hot loops can build rays without checks; every intersector in this
/// crate treats a ray that [`Ray::validate`] would reject as a ray that hits nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Ray origin, world units.
    pub origin: Vec3,
    /// Ray direction, not necessarily normalised; must be finite and non-zero.
    pub direction: Vec3,
    /// Exclusive lower end of the interval, in units of `|direction|`. Must not be NaN.
    pub t_min: f32,
    /// Inclusive upper end of the interval. May be `+∞`; must not be NaN.
    pub t_max: f32,
}

impl Ray {
    /// A ray over `(0, +∞]`, unchecked.
    #[inline]
    #[must_use]
    pub const fn new(origin: Vec3, direction: Vec3) -> Self {
        Self {
            origin,
            direction,
            t_min: 0.0,
            t_max: f32::INFINITY,
        }
    }

    /// A ray over `(t_min, t_max]`, unchecked.
    #[inline]
    #[must_use]
    pub const fn with_interval(origin: Vec3, direction: Vec3, t_min: f32, t_max: f32) -> Self {
        Self {
            origin,
            direction,
            t_min,
            t_max,
        }
    }

    /// A checked ray: see [`Ray::validate`].
    ///
    /// # Errors
    ///
    /// As [`Ray::validate`].
    pub fn try_new(
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Result<Self, RayError> {
        let ray = Self::with_interval(origin, direction, t_min, t_max);
        ray.validate()?;
        Ok(ray)
    }

    /// Checks the ray: finite origin, finite non-zero direction, `t_min` not NaN and not `+∞`,
    /// `t_max` not NaN, and `t_min ≤ t_max`. (`t_min < t_max` is not required: an empty
    /// interval is valid and simply hits nothing.)
    ///
    /// # Errors
    ///
    /// The first check that fails, as a [`RayError`].
    pub fn validate(&self) -> Result<(), RayError> {
        if !self.origin.is_finite() {
            return Err(RayError::NonFiniteOrigin);
        }
        if !self.direction.is_finite() {
            return Err(RayError::NonFiniteDirection);
        }
        if self.direction == Vec3::ZERO {
            return Err(RayError::ZeroDirection);
        }
        if self.t_min.is_nan() || self.t_max.is_nan() || self.t_min == f32::INFINITY {
            return Err(RayError::BadInterval);
        }
        if self.t_min > self.t_max {
            return Err(RayError::BadInterval);
        }
        Ok(())
    }

    /// `true` when [`Ray::validate`] accepts the ray. Out of line on bare-metal targets
    /// (`target_os = "none"`), where each query's preparation would otherwise carry a copy.
    #[cfg_attr(not(target_os = "none"), inline)]
    #[cfg_attr(target_os = "none", inline(never))]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        // The conditions of `validate`, combined without short-circuits (one branch for the
        // caller instead of one per field, and compact code on small targets).
        // On the bits: a non-finite value has all exponent bits set; `±0` has no bit but
        // the sign.
        const EXP: u32 = 0x7F80_0000;
        let (o, d) = (self.origin, self.direction);
        let mut finite = true;
        for v in [o.x, o.y, o.z, d.x, d.y, d.z] {
            finite &= v.to_bits() & EXP != EXP;
        }
        let nonzero = (d.x.to_bits() | d.y.to_bits() | d.z.to_bits()) << 1 != 0;
        // NaN fails both comparisons; `t_min = +∞` fails the first.
        let interval = (self.t_min < f32::INFINITY) & (self.t_min <= self.t_max);
        finite & nonzero & interval
    }

    /// `true` when `t` lies in `(t_min, t_max]` and is finite: a "hit" at `t = ±∞` (an
    /// overflowed intersection) is no hit, even for `t_max = +∞`. False for NaN.
    #[inline]
    #[must_use]
    pub fn contains(&self, t: f32) -> bool {
        t > self.t_min && t <= self.t_max && t != f32::INFINITY
    }

    /// The point at parameter `t`. Note: for hit points prefer the primitive's own
    /// reconstruction (barycentric interpolation), whose error is bounded independently of `t`.
    #[inline]
    #[must_use]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.direction * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_is_open_below_closed_above() {
        let r = Ray::with_interval(Vec3::ZERO, Vec3::X, 1.0, 2.0);
        assert!(!r.contains(1.0));
        assert!(r.contains(1.0f32.next_up()));
        assert!(r.contains(2.0));
        assert!(!r.contains(2.0f32.next_up()));
        assert!(!r.contains(f32::NAN));
        let open = Ray::new(Vec3::ZERO, Vec3::X);
        assert!(open.contains(f32::MAX));
        assert!(!open.contains(f32::INFINITY), "a hit at infinity is no hit");
    }

    #[test]
    fn validate_rejects_each_bad_field() {
        let ok = Ray::new(Vec3::ZERO, Vec3::Z);
        assert_eq!(ok.validate(), Ok(()));
        let mut r = ok;
        r.origin.x = f32::NAN;
        assert_eq!(r.validate(), Err(RayError::NonFiniteOrigin));
        let mut r = ok;
        r.direction.y = f32::INFINITY;
        assert_eq!(r.validate(), Err(RayError::NonFiniteDirection));
        let mut r = ok;
        r.direction = Vec3::new(0.0, -0.0, 0.0);
        assert_eq!(r.validate(), Err(RayError::ZeroDirection));
        let mut r = ok;
        r.t_max = f32::NAN;
        assert_eq!(r.validate(), Err(RayError::BadInterval));
        let mut r = ok;
        r.t_min = 3.0;
        r.t_max = 2.0;
        assert_eq!(r.validate(), Err(RayError::BadInterval));
        assert!(Ray::try_new(Vec3::ZERO, Vec3::X, 0.0, 0.0).is_ok());
    }

    #[test]
    fn is_valid_agrees_with_validate_on_every_special_value() {
        let special = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            f32::MIN_POSITIVE,
            f32::from_bits(1), // the smallest subnormal
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut checked = 0;
        for (i, &a) in special.iter().enumerate() {
            for &b in &special {
                for &c in &special {
                    let rays = [
                        Ray {
                            origin: Vec3::new(a, 1.0, b),
                            direction: Vec3::new(c, 0.0, 0.0),
                            t_min: 0.0,
                            t_max: f32::INFINITY,
                        },
                        Ray {
                            origin: Vec3::ZERO,
                            direction: Vec3::new(a, b, c),
                            t_min: 0.0,
                            t_max: 1.0,
                        },
                        Ray {
                            origin: Vec3::ONE,
                            direction: Vec3::new(0.0, special[(i + 3) % special.len()], 0.0),
                            t_min: a,
                            t_max: b,
                        },
                    ];
                    for r in rays {
                        assert_eq!(r.is_valid(), r.validate().is_ok(), "{r:?}");
                        checked += 1;
                    }
                }
            }
        }
        assert_eq!(checked, 3000);
    }
}
