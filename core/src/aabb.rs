//! Axis-aligned boxes and the robust slab test.
//!
//! The slab test is **closed** (a ray touching a face, edge or corner hits; flat boxes of zero
//! thickness are hit), **conservative** (Ize 2013: the far distance is padded outward by
//! `2·gamma(3)` relative ([`pad_far`]), so a box that contains a point the exact ray passes through is never
//! culled because of rounding), and **NaN-absorbing**: with a direction component of `±0` the
//! reciprocal is `±∞`, and an origin exactly on that slab's plane gives `0·∞ = NaN`; every
//! slab value is merged with `f32::max`/`f32::min` *against the running interval*, which
//! returns the non-NaN operand, so such a slab does not constrain the interval. The result is
//! the same for `+0.0` and `−0.0` and for every axis. An entry at `t = +∞` or an exit at
//! `t = −∞` is no hit (a ray parallel to a slab and outside it gets `[+∞, +∞]` or `[−∞, −∞]`
//! from that slab, depending on the zero's sign).
//!
//! A direction component below `1/f32::MAX ≈ 2.9e-39` in magnitude (subnormal, not zero) has
//! no finite reciprocal, and one above `2¹²⁶ ≈ 8.5e37` a subnormal one (fewer than 24 bits:
//! beyond the padding's `gamma(3)`); a ray with either is tested by division, `(bound − o)/d`
//! (at most two roundings, so the same padding covers it), instead of multiplication by `1/d`,
//! which would cull a box the ray passes through.
//!
//! **Domain.** Never a false miss while every `|bound − origin|` on an axis with a non-zero
//! direction component is at most `f32::MAX` (beyond it the difference overflows to `±∞` and
//! the box can be missed although the exact ray crosses it at a representable distance) and
//! the exact entry distance is at most `f32::MAX` (an entry beyond it rounds to `+∞`, which
//! is no hit, as is an exit below `−f32::MAX`). The padding is relative, so a false hit is bounded (the box is at most
//! `2·gamma(3)` of the far distance beyond the ray) only while the non-zero direction
//! components and the finite slab distances have magnitudes in `[2⁻¹²⁰, 2¹²⁰]`; outside that
//! range `f32` distances round absolutely and a box farther off may be reported hit
//! (conservative: traversal then tests its contents). The fuzz property `ray_box` checks
//! exactly these domains.

use crate::float::gamma;
use crate::ray::Ray;
use glam::Vec3;

/// Factor applied to far slab distances: each distance `(bound − o)·(1/d)` carries at most
/// three roundings (subtraction, reciprocal, product), relative error `≤ gamma(3)`; scaling the
/// far one by `1 + 2·gamma(3)` keeps `t_near ≤ t_far` whenever the exact interval is non-empty
/// (Ize, "Robust BVH Ray Traversal", JCGT 2013). Unitless.
pub const SLAB_FAR_SCALE: f32 = 1.0 + 2.0 * gamma(3);

/// The factor for a *negative* far distance (an interval with `t_min < 0`): `1 − 2·gamma(3)`,
/// which moves it away from the near distance just as [`SLAB_FAR_SCALE`] does for a positive
/// one. (Scaling a negative far distance by `SLAB_FAR_SCALE` would shrink the slab instead.)
/// Unitless.
pub const SLAB_FAR_SCALE_NEGATIVE: f32 = 1.0 - 2.0 * gamma(3);

/// A far slab distance padded outward: `t·(1 ± 2·gamma(3))`, the sign chosen so the result is
/// never less than `t` (the far end only grows). `±∞` and NaN pass through unchanged.
#[inline(always)]
#[must_use]
pub fn pad_far(t: f32) -> f32 {
    t * if t < 0.0 {
        SLAB_FAR_SCALE_NEGATIVE
    } else {
        SLAB_FAR_SCALE
    }
}

/// An axis-aligned box `[min, max]` (closed). `min > max` on any axis means empty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box (`min = +∞`, `max = −∞`): the identity of [`Aabb::union`]; no ray hits it.
    pub const EMPTY: Self = Self {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// The box `[min, max]` (not checked).
    #[inline]
    #[must_use]
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box containing the given points (empty for no points).
    #[must_use]
    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.grow(p))
    }

    /// The box grown to contain `p`.
    #[inline]
    #[must_use]
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box containing both.
    #[inline]
    #[must_use]
    pub fn union(self, other: Self) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// `true` when `min ≤ max` on every axis (a point is a valid, non-empty box).
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z
    }

    /// `true` when every coordinate is finite.
    #[inline]
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// `max − min` (negative components for an empty box).
    #[inline]
    #[must_use]
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Centre of the box, `min/2 + max/2`: finite for every finite box (unlike
    /// `(min + max)/2`, which overflows when both corners are beyond `f32::MAX/2`).
    #[inline]
    #[must_use]
    pub fn center(&self) -> Vec3 {
        self.min * 0.5 + self.max * 0.5
    }

    /// The box of `p − origin` over the points `p` of `self`, rounded outward: each finite
    /// bound is the `f32` difference stepped one ulp outward (the difference is within half
    /// an ulp of the exact one), so the result contains every exact `p − origin`. Infinite
    /// bounds stay as they are (an empty box stays empty); a difference that overflows
    /// becomes infinite on its own side, and the bound on the other side of it the largest
    /// finite value (`f32::MAX` for a lower bound that overflows upward), so that a box beyond
    /// `f32`'s range is `[f32::MAX, +∞]`, not the empty `[+∞, +∞]`. A wide tree stores its node boxes this way, relative
    /// to its centre, so that their bounds and a ray's origin in that frame are small numbers
    /// whatever the coordinates' magnitude.
    #[inline]
    #[must_use]
    pub fn relative_to(&self, origin: Vec3) -> Self {
        // `b` a finite bound whose difference `x` overflowed: the exact difference is beyond
        // `±f32::MAX` on `x`'s side, so a lower bound there is `f32::MAX` (an upper `−f32::MAX`).
        let lower = |b: f32, x: f32| match (x.is_finite(), b.is_finite() && x == f32::INFINITY) {
            (true, _) => x.next_down(),
            (false, true) => f32::MAX,
            (false, false) => x,
        };
        let upper = |b: f32, x: f32| match (x.is_finite(), b.is_finite() && x == f32::NEG_INFINITY)
        {
            (true, _) => x.next_up(),
            (false, true) => f32::MIN,
            (false, false) => x,
        };
        let (lo, hi) = (self.min - origin, self.max - origin);
        Self {
            min: Vec3::from_array(core::array::from_fn(|i| lower(self.min[i], lo[i]))),
            max: Vec3::from_array(core::array::from_fn(|i| upper(self.max[i], hi[i]))),
        }
    }

    /// Surface area (0 for an empty box), used by the SAH.
    #[inline]
    #[must_use]
    pub fn surface_area(&self) -> f32 {
        if !self.is_valid() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Index of the longest axis (0, 1 or 2; ties go to the lower index; 0 when the x extent
    /// is NaN).
    #[inline]
    #[must_use]
    pub fn longest_axis(&self) -> usize {
        self.extent().max_position()
    }

    /// `true` when the two closed boxes share at least one point (touching counts). Empty or
    /// NaN boxes overlap nothing.
    #[inline]
    #[must_use]
    pub fn overlaps(&self, other: &Self) -> bool {
        self.is_valid()
            && other.is_valid()
            && self.min.x <= other.max.x
            && other.min.x <= self.max.x
            && self.min.y <= other.max.y
            && other.min.y <= self.max.y
            && self.min.z <= other.max.z
            && other.min.z <= self.max.z
    }

    /// `true` when `p` lies in the closed box.
    #[inline]
    #[must_use]
    pub fn contains_point(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Robust, conservative slab test on a prepared ray, clipped to the closed interval
    /// `[t_min, t_max]`. Returns the entry and exit distances `(t_enter, t_exit)` when the box
    /// is hit (`t_enter ≤ t_exit`). See the module docs for the guarantees.
    #[inline]
    #[must_use]
    pub fn intersect_slab(&self, ray: &SlabRay, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        self.slab_test(ray, t_min, t_max, pad_far)
    }

    /// The plain (non-conservative) slab test: the same NaN handling, without the
    /// `SLAB_FAR_SCALE` padding. Kept for the accuracy/cost benchmark; BVH traversal uses
    /// [`Aabb::intersect_slab`].
    #[inline]
    #[must_use]
    pub fn intersect_slab_plain(
        &self,
        ray: &SlabRay,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32)> {
        self.slab_test(ray, t_min, t_max, |t| t)
    }

    /// The slab test with the far distances mapped by `far` (the padding, or nothing).
    #[inline(always)]
    fn slab_test(
        &self,
        ray: &SlabRay,
        t_min: f32,
        t_max: f32,
        far: impl Fn(f32) -> f32,
    ) -> Option<(f32, f32)> {
        let mut t_enter = t_min;
        let mut t_exit = t_max;
        for axis in 0..3 {
            let (lo, hi) = if ray.negative[axis] {
                (self.max[axis], self.min[axis])
            } else {
                (self.min[axis], self.max[axis])
            };
            let (t_near, t_far) = ray.slab_distances(axis, lo, hi);
            // `max`/`min` return the non-NaN operand: a NaN slab leaves the interval as it is.
            t_enter = t_near.max(t_enter);
            t_exit = far(t_far).min(t_exit);
        }
        (t_enter <= t_exit && t_enter < f32::INFINITY && t_exit > f32::NEG_INFINITY)
            .then_some((t_enter, t_exit))
    }

    /// Slab test of a ray over its closed interval `[t_min, t_max]`; `None` for an invalid ray
    /// (see [`Ray::validate`]) as well as for a miss.
    #[must_use]
    pub fn intersect_ray(&self, ray: &Ray) -> Option<(f32, f32)> {
        let slab = SlabRay::new(ray)?;
        self.intersect_slab(&slab, ray.t_min, ray.t_max)
    }
}

/// A ray prepared for slab tests: reciprocal direction (true IEEE division, so `±0` gives `±∞`)
/// and the octant from the direction's sign bits (`−0.0` counts as negative, matching
/// `1/−0 = −∞`).
///
/// Only [`SlabRay::new`] makes one, from a valid ray ([`Ray::validate`]): its fields are
/// private, so every `SlabRay` has a finite origin and a finite, non-zero direction whose
/// reciprocal, octant and division flag agree with it. That is what the slab test's
/// guarantees (module docs) rest on: it absorbs NaN slab distances, so a ray with a NaN
/// origin, were one built by hand, would "hit" every box.
///
/// ```compile_fail,E0451
/// use halfray_core::aabb::SlabRay;
/// use halfray_core::Vec3;
/// // Not possible: the fields are private.
/// let nan = SlabRay {
///     origin: Vec3::NAN,
///     inv_dir: Vec3::ONE,
///     negative: [false; 3],
///     direction: Vec3::ONE,
///     divide: false,
/// };
/// ```
#[derive(Clone, Copy, Debug)]
pub struct SlabRay {
    /// Ray origin.
    pub(crate) origin: Vec3,
    /// `1 / direction`, per component.
    pub(crate) inv_dir: Vec3,
    /// Sign bit of each direction component.
    pub(crate) negative: [bool; 3],
    /// Ray direction (used instead of `inv_dir` when `divide` is set).
    pub(crate) direction: Vec3,
    /// `true` when a non-zero direction component has an infinite or subnormal reciprocal
    /// (module docs): slab distances are then computed by division.
    pub(crate) divide: bool,
}

impl SlabRay {
    /// Prepares `ray`; `None` when the ray is invalid ([`Ray::validate`]), so that a NaN ray
    /// can never pass the NaN-absorbing test.
    #[inline]
    #[must_use]
    pub fn new(ray: &Ray) -> Option<Self> {
        if !ray.is_valid() {
            return None;
        }
        let d = ray.direction;
        // One four-lane division (the same IEEE quotient per lane as three scalar ones): the
        // reciprocals head the dependency chain of every query.
        let inv_dir = Vec3::from(glam::Vec3A::ONE / glam::Vec3A::from(d));
        // `dᵢ ≠ ±0` and `1/dᵢ` infinite or subnormal: a subnormal reciprocal (`|dᵢ| > 2¹²⁶`)
        // has lost relative precision beyond the padding's `gamma(3)`.
        #[cfg(target_arch = "x86_64")]
        let divide = {
            // Three lanes at once (SSE, x86-64's baseline): a valid ray has no NaN, so
            // "infinite or subnormal" is "not in [MIN_POSITIVE, ∞)".
            let (a, dv) = (glam::Vec3A::from(inv_dir).abs(), glam::Vec3A::from(d));
            let normal = a.cmpge(glam::Vec3A::splat(f32::MIN_POSITIVE))
                & a.cmplt(glam::Vec3A::splat(f32::INFINITY));
            (dv.cmpne(glam::Vec3A::ZERO) & !normal).any()
        };
        // On the bits elsewhere (compact on small targets): the exponent field all ones or
        // all zeros.
        #[cfg(not(target_arch = "x86_64"))]
        let divide = {
            let overflow = |i: usize| {
                let exponent = (inv_dir[i].to_bits() >> 23) & 0xFF;
                (d[i].to_bits() << 1 != 0) & ((exponent == 0xFF) | (exponent == 0))
            };
            overflow(0) | overflow(1) | overflow(2)
        };
        Some(Self {
            origin: ray.origin,
            inv_dir,
            negative: [
                d.x.is_sign_negative(),
                d.y.is_sign_negative(),
                d.z.is_sign_negative(),
            ],
            direction: d,
            divide,
        })
    }

    /// `((near − o_axis)/d_axis, (far − o_axis)/d_axis)`, unpadded: by the reciprocal, or by
    /// division when a non-zero direction component has an infinite or subnormal reciprocal
    /// (module docs). `±0` components give `±∞` (or NaN for an
    /// origin on the plane) either way; an `axis` other than 0, 1 or 2 gives `(NaN, NaN)`.
    #[inline(always)]
    #[must_use]
    pub fn slab_distances(&self, axis: usize, near: f32, far: f32) -> (f32, f32) {
        let component = |v: Vec3| v.to_array().get(axis).copied().unwrap_or(f32::NAN);
        let o = component(self.origin);
        if self.divide {
            let d = component(self.direction);
            ((near - o) / d, (far - o) / d)
        } else {
            let inv = component(self.inv_dir);
            ((near - o) * inv, (far - o) * inv)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNIT: Aabb = Aabb::new(Vec3::ZERO, Vec3::ONE);

    /// An inverted box (`min > max` on one axis) is empty and overlaps nothing, even a box
    /// that holds both its corners.
    #[test]
    fn an_inverted_box_overlaps_nothing() {
        let inverted = Aabb::new(Vec3::new(5.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 1.0));
        let big = Aabb::new(Vec3::splat(-10.0), Vec3::splat(10.0));
        assert!(!inverted.overlaps(&big) && !big.overlaps(&inverted));
        assert!(!inverted.overlaps(&inverted));
        assert!(UNIT.overlaps(&big));
    }

    /// A box beyond `f32`'s range relative to the origin keeps every exact difference:
    /// `[f32::MAX, f32::MAX] − (−1.99·10³⁸)` is about `5.4·10³⁸`, so the result is
    /// `[f32::MAX, +∞]` (not the empty `[+∞, +∞]`); the mirror case `[−f32::MAX, −∞]`.
    #[test]
    fn a_difference_beyond_the_range_keeps_a_non_empty_box() {
        let far = Aabb::new(Vec3::splat(f32::MAX), Vec3::splat(f32::MAX));
        let r = far.relative_to(Vec3::new(-1.99e38, 0.0, 0.0));
        assert_eq!((r.min.x, r.max.x), (f32::MAX, f32::INFINITY));
        assert!(r.is_valid());
        let near = Aabb::new(Vec3::splat(-f32::MAX), Vec3::splat(-f32::MAX));
        let r = near.relative_to(Vec3::new(f32::MAX, 0.0, 0.0));
        assert_eq!((r.min.x, r.max.x), (f32::NEG_INFINITY, f32::MIN));
        assert!(r.is_valid());
    }

    /// An axis beyond `z` is `(NaN, NaN)`, not a panic; axes 0–2 are the slab's distances,
    /// by the reciprocal and by division alike.
    #[test]
    fn slab_distances_of_an_axis_beyond_z_are_nan() {
        for d in [Vec3::new(2.0, 4.0, -8.0), Vec3::new(1e-39, 4.0, -8.0)] {
            let s = SlabRay::new(&Ray::new(Vec3::ONE, d)).unwrap();
            for axis in [3, 4, usize::MAX] {
                let (a, b) = s.slab_distances(axis, 0.0, 1.0);
                assert!(a.is_nan() && b.is_nan(), "{d} axis {axis}");
            }
            assert_eq!(s.slab_distances(1, 0.0, 9.0), (-0.25, 2.0), "{d}");
        }
    }

    fn hits(b: &Aabb, o: Vec3, d: Vec3) -> bool {
        b.intersect_ray(&Ray::new(o, d)).is_some()
    }

    #[test]
    fn origin_on_face_planes_hits_for_both_zero_signs_and_every_axis() {
        for axis in 0..3 {
            for face in [0.0f32, 1.0] {
                for zero in [0.0f32, -0.0] {
                    let mut o = Vec3::splat(0.5);
                    o[axis] = face;
                    let along = (axis + 1) % 3;
                    o[along] = -1.0;
                    let mut d = Vec3::ZERO;
                    d[axis] = zero;
                    d[along] = 1.0;
                    assert!(hits(&UNIT, o, d), "axis {axis} face {face} zero {zero}");
                }
            }
        }
    }

    /// The far padding is a relative `2·gamma(3)`, not more: a ray from the origin along
    /// `(1, ½, 0)` leaves the slab `x ∈ [1, 1.5]` at `t = 1.5` and enters `y ∈ [2, 3]` at
    /// `t = 4` (exact), a clear miss that any padding of the far distance by a factor of 8/3
    /// or more would turn into a hit; it still hits when the `y` slab starts at `t = 1.5`
    /// exactly (`y ∈ [0.75, 3]`), where the padding keeps the touching interval.
    #[test]
    fn far_padding_is_relative_rounding_only() {
        let d = Vec3::new(1.0, 0.5, 0.0);
        let missed = Aabb::new(Vec3::new(1.0, 2.0, -1.0), Vec3::new(1.5, 3.0, 1.0));
        assert!(!hits(&missed, Vec3::ZERO, d));
        let touching = Aabb::new(Vec3::new(1.0, 0.75, -1.0), Vec3::new(1.5, 3.0, 1.0));
        assert!(hits(&touching, Vec3::ZERO, d));
        assert!(SLAB_FAR_SCALE > 1.0 && SLAB_FAR_SCALE - 1.0 <= 2.0 * gamma(3));
    }

    #[test]
    fn parallel_ray_just_outside_misses() {
        for zero in [0.0f32, -0.0] {
            let o = Vec3::new(0.0f32.next_down(), 0.5, -1.0);
            assert!(!hits(&UNIT, o, Vec3::new(zero, 0.0, 1.0)));
            let o = Vec3::new(1.0f32.next_up(), 0.5, -1.0);
            assert!(!hits(&UNIT, o, Vec3::new(zero, 0.0, 1.0)));
        }
    }

    #[test]
    fn ray_along_box_edge_and_flat_box() {
        assert!(hits(&UNIT, Vec3::new(0.0, 0.0, -1.0), Vec3::Z));
        let flat = Aabb::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.0, 1.0, 2.0));
        assert!(hits(&flat, Vec3::new(0.5, 0.5, 0.0), Vec3::Z));
        assert!(hits(&flat, Vec3::new(0.5, 0.5, 2.0), Vec3::X));
    }

    #[test]
    fn nan_and_zero_rays_hit_nothing() {
        assert!(!hits(&UNIT, Vec3::NAN, Vec3::Z));
        assert!(!hits(
            &UNIT,
            Vec3::splat(0.5),
            Vec3::new(f32::NAN, 0.0, 1.0)
        ));
        assert!(!hits(&UNIT, Vec3::splat(0.5), Vec3::ZERO));
        assert!(!hits(&Aabb::EMPTY, Vec3::splat(0.5), Vec3::Z));
    }

    #[test]
    fn subnormal_and_tiny_direction_components() {
        for tiny in [1.0e-30f32, 1.0e-40, -1.0e-40] {
            assert!(hits(
                &UNIT,
                Vec3::new(0.5, 0.5, -1.0),
                Vec3::new(tiny, 0.0, 1.0)
            ));
            assert!(!hits(
                &UNIT,
                Vec3::new(2.0, 0.5, -1.0),
                Vec3::new(tiny, 0.0, 1.0)
            ));
        }
    }

    /// Found by the `bvh` fuzz target: a ray whose direction components are subnormal aims at
    /// the corner of a flat box (`z = 0`) from `z = 2.77e-40`; `1/d_z` overflows to `−∞`, and
    /// by reciprocal the `z` slab became `[∞, ∞]`. By division it is `[1, 1]`.
    #[test]
    fn subnormal_components_whose_reciprocal_overflows() {
        let flat = Aabb::new(Vec3::ZERO, Vec3::new(4.0, 4.0, 0.0));
        let o = Vec3::new(1.628_021e-21, 0.0, f32::from_bits(0x0003_0401));
        let ray = Ray::new(o, -o);
        let slab = SlabRay::new(&ray).unwrap();
        assert!(slab.divide);
        let (t0, t1) = flat.intersect_ray(&ray).expect("hits the corner at t = 1");
        assert!(t0 <= 1.0 && 1.0 <= t1, "({t0}, {t1})");
        assert!(
            flat.intersect_slab_plain(&slab, 0.0, f32::INFINITY)
                .is_some()
        );
        // Moving away from the box: still a miss.
        assert_eq!(flat.intersect_ray(&Ray::new(o, o)), None);
        // Ordinary rays keep the reciprocal path.
        assert!(!SlabRay::new(&Ray::new(o, Vec3::Z)).unwrap().divide);
    }

    /// Found by the `bvh` fuzz target: `(min + max)/2` overflowed for a box beyond
    /// `f32::MAX/2`, and the BVH builder took such a primitive for a non-finite one.
    #[test]
    fn center_of_far_boxes_is_finite() {
        let b = Aabb::new(Vec3::splat(-1.741e38), Vec3::new(-1.741e38, 3.0e38, 3.4e38));
        let c = b.center();
        assert!(c.is_finite(), "{c:?}");
        assert_eq!(c.x, -1.741e38);
        assert!(b.contains_point(c));
    }

    /// Negative intervals: a hit at `t = −1` on a flat box's corner, with `t_min = −3e36`
    /// (found by the `bvh` fuzz target: the far distance, negative, was padded inward).
    #[test]
    fn negative_interval_flat_box_corner() {
        let flat = Aabb::new(Vec3::ZERO, Vec3::new(4.0, 4.0, 0.0));
        let o = Vec3::splat(5.25);
        let ray = Ray::with_interval(o, o, -3.096_319_3e36, f32::from_bits(0x400));
        let (t0, t1) = flat.intersect_ray(&ray).expect("corner at t = −1");
        assert!(t0 <= -1.0 && -1.0 <= t1, "({t0}, {t1})");
        assert_eq!(pad_far(f32::NEG_INFINITY), f32::NEG_INFINITY);
        assert!(pad_far(-1.0) > -1.0 && pad_far(1.0) > 1.0 && pad_far(0.0) == 0.0);
    }

    /// A ray parallel to a slab and outside it, with either sign of zero, misses: its entry
    /// is `+∞` or its exit `−∞` (found by the `ray_box` fuzz target).
    #[test]
    fn parallel_outside_with_negative_zero_misses() {
        let b = Aabb::new(Vec3::new(0.0, -0.0, 0.0), Vec3::new(1.0, 2.278e-41, 1.0));
        for dy in [0.0f32, -0.0] {
            let ray = Ray::new(
                Vec3::new(0.5, 0.5, -1.0),
                Vec3::new(1.35e-43, dy, 2.278e-41),
            );
            assert_eq!(b.intersect_ray(&ray), None, "d_y = {dy:?}");
            let ray = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::new(0.0, dy, 1.0));
            assert_eq!(b.intersect_ray(&ray), None, "d_y = {dy:?}");
        }
    }

    #[test]
    fn interval_is_respected_inclusively() {
        let r = Ray::with_interval(Vec3::new(0.5, 0.5, -2.0), Vec3::Z, 0.0, 2.0);
        assert_eq!(UNIT.intersect_ray(&r).map(|x| x.0), Some(2.0));
        let r = Ray::with_interval(Vec3::new(0.5, 0.5, -2.0), Vec3::Z, 0.0, 1.999);
        assert!(UNIT.intersect_ray(&r).is_none());
    }

    #[test]
    fn far_thin_box_is_not_culled() {
        // A box 1e7 away, one ulp thick in x, hit by a ray through its middle.
        let x = 1.0e7f32;
        let b = Aabb::new(Vec3::new(x, -1.0, -1.0), Vec3::new(x.next_up(), 1.0, 1.0));
        let o = Vec3::new(0.0, 0.3, 0.2);
        let target = Vec3::new(x, 0.0, 0.0);
        assert!(hits(&b, o, target - o));
    }

    #[test]
    fn overlap_is_closed() {
        let a = UNIT;
        let b = Aabb::new(Vec3::ONE, Vec3::splat(2.0));
        assert!(a.overlaps(&b));
        let c = Aabb::new(Vec3::new(1.0f32.next_up(), 0.0, 0.0), Vec3::splat(2.0));
        assert!(!a.overlaps(&c));
        assert!(!a.overlaps(&Aabb::EMPTY));
        assert_eq!(UNIT.surface_area(), 6.0);
    }

    /// The box of three points, worked by hand: corners, extent, area, longest axis.
    #[test]
    fn box_of_points_worked_example() {
        let p = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-1.0, 5.0, 0.0),
            Vec3::new(2.0, -3.0, 1.0),
        ];
        let b = Aabb::from_points(&p);
        assert_eq!(
            b,
            Aabb::new(Vec3::new(-1.0, -3.0, 0.0), Vec3::new(2.0, 5.0, 3.0))
        );
        assert_eq!(
            Aabb::EMPTY.grow(p[0]).grow(p[1]),
            Aabb::from_points(&p[..2])
        );
        assert_eq!(Aabb::from_points(&[]), Aabb::EMPTY);
        assert_eq!(b.extent(), Vec3::new(3.0, 8.0, 3.0));
        // 2·(3·8 + 8·3 + 3·3)
        assert_eq!(b.surface_area(), 114.0);
        // Extents (2, 3, 4): 2·(6 + 12 + 8).
        let c = Aabb::new(Vec3::new(1.0, 1.0, 1.0), Vec3::new(3.0, 4.0, 5.0));
        assert_eq!(c.surface_area(), 52.0);
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        assert_eq!(b.longest_axis(), 1);
        assert_eq!(c.longest_axis(), 2);
        assert_eq!(
            Aabb::new(Vec3::ZERO, Vec3::new(9.0, 1.0, 2.0)).longest_axis(),
            0
        );
        // Ties go to the lower axis.
        assert_eq!(
            Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 2.0)).longest_axis(),
            1
        );
    }

    /// Validity, finiteness and containment fail on each axis and each corner alone.
    #[test]
    fn each_axis_and_corner_decides_alone() {
        assert!(UNIT.is_valid() && UNIT.is_finite());
        assert!(!Aabb::EMPTY.is_valid());
        for a in 0..3 {
            let mut inverted = UNIT;
            inverted.min[a] = 2.0;
            assert!(!inverted.is_valid(), "axis {a}");
            let (mut lo, mut hi) = (UNIT, UNIT);
            lo.min[a] = f32::NEG_INFINITY;
            hi.max[a] = f32::NAN;
            assert!(!lo.is_finite() && !hi.is_finite(), "axis {a}");
            let mut below = Vec3::splat(0.5);
            below[a] = -0.25;
            let mut above = Vec3::splat(0.5);
            above[a] = 1.25;
            assert!(
                !UNIT.contains_point(below) && !UNIT.contains_point(above),
                "axis {a}"
            );
            let mut on_face = Vec3::splat(0.5);
            on_face[a] = 1.0;
            assert!(UNIT.contains_point(on_face), "closed: axis {a}");
        }
    }

    /// `divide` is set exactly when a non-zero direction component has a reciprocal whose
    /// exponent field is all ones (infinite) or all zeros (subnormal or zero), checked on the
    /// bits against every class of component (zero, subnormal, tiny, normal, near the
    /// reciprocal's subnormal threshold `2¹²⁶`, huge), in every position and sign.
    #[test]
    fn divide_flag_follows_the_reciprocal_exponent() {
        let classes = [
            0.0f32,
            1e-45,
            1e-39,
            2.9e-39,
            3.0e-39,
            1e-30,
            0.5,
            1.0,
            3.0,
            1e30,
            f32::from_bits(0x7E80_0000), // 2^126: reciprocal 2^-126, the smallest normal
            f32::from_bits(0x7E80_0001), // just above: a subnormal reciprocal
            1e38,
            f32::MAX,
        ];
        let mut checked = 0;
        for (i, &a) in classes.iter().enumerate() {
            for &b in &classes[i..] {
                for sign in [1.0f32, -1.0] {
                    let d = Vec3::new(a * sign, b, 1.0);
                    for d in [d, Vec3::new(d.z, d.x, d.y), Vec3::new(d.y, d.z, d.x)] {
                        let Some(slab) = SlabRay::new(&Ray::new(Vec3::ZERO, d)) else {
                            continue;
                        };
                        let want = d.to_array().iter().any(|&c| {
                            let e = ((1.0 / c).to_bits() >> 23) & 0xFF;
                            c != 0.0 && (e == 0xFF || e == 0)
                        });
                        assert_eq!(slab.divide, want, "{d:?}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 500, "{checked}");
    }

    /// A direction component above `2¹²⁶` has a subnormal reciprocal (fewer than 24 bits):
    /// multiplying by it lost more than the padding covers and culled a box the exact ray
    /// crosses on `[0.99999997, 1]` (the `ray_box` regression `crash-ece37715-…`).
    #[test]
    fn huge_direction_components_take_the_division_path() {
        let v = |b: [u32; 3]| Vec3::from_array(b.map(f32::from_bits));
        let ray = Ray::new(
            v([0x0000_0000, 0x3b3f_6000, 0xff7f_ffff]),
            v([0xff3f_0000, 0x6a0d_3fe3, 0x7f7f_9292]),
        );
        let b = Aabb::new(
            v([0xff3f_0000, 0x3f1a_0000, 0xfada_dada]),
            v([0x0001_adff, 0x6a6a_6aff, 0x0000_01ff]),
        );
        assert!(SlabRay::new(&ray).unwrap().divide);
        assert!(b.intersect_ray(&ray).is_some());
    }

    /// The no-false-miss domain (module docs, *Domain*) at its boundary: a box whose far
    /// bound is exactly `f32::MAX` from the origin is hit, and its interval `[0.75, 1]·MAX`
    /// (exact, by hand) is enclosed. Just outside: from `−MAX` with `d = 2` the exact interval
    /// is `[0.625, 0.75]·MAX`, representable, but `bound − o` overflows and the box is missed;
    /// with `d = 0.5` the exact entry `1.5·MAX` is beyond `f32` and the box is no hit either.
    #[test]
    fn no_false_miss_up_to_a_slab_difference_of_f32_max() {
        let h = f32::MAX / 2.0; // exact
        let b = Aabb::new(Vec3::new(h / 2.0, -1.0, -1.0), Vec3::new(h, 1.0, 1.0));
        let (te, tx) = b
            .intersect_ray(&Ray::new(Vec3::new(-h, 0.0, 0.0), Vec3::X))
            .expect("inside the domain: the exact ray crosses the box");
        assert!(te <= 0.75 * f32::MAX && tx >= f32::MAX, "({te:e}, {tx:e})");
        assert!(!hits(
            &b,
            Vec3::new(-f32::MAX, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0)
        ));
        assert!(!hits(&b, Vec3::new(-h, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0)));
    }

    /// The bounded-false-hit domain (module docs, *Domain*: non-zero direction components and
    /// slab distances in `[2⁻¹²⁰, 2¹²⁰]`) at both ends. The ray `o = 0`, `d = (s, s, 0)`
    /// enters the box's `x` slab at `t = N` and leaves its `y` slab at `t = E` (bounds
    /// `N·s`, `E·s`: exact, `s` a power of two): touching (`N = E`) is a hit, and a gap of
    /// `2⁻¹⁹` of the distances (beyond the `2·gamma(3)` padding plus the near distance's
    /// `gamma(3)`, about `5.4·10⁻⁷`) is a miss, for `N` at `2⁻¹²⁰` and `2¹¹⁹` (the far `x`
    /// distance `2N` then at `2¹²⁰`) and `s` at `2⁻¹²⁰`, 1 and `2¹²⁰` where the bounds are
    /// normal `f32`. Just outside (a slab distance `2⁻¹⁴⁹/3`, below the normal range, rounds
    /// to 0): the box `[2⁻¹⁴⁹, 1] × [−1, 0]` beside the ray `(3, 1, 0)·t` (exactly, `x`
    /// reaches it at `t = 2⁻¹⁴⁹/3` where `y` has left it at `t = 0`) is reported hit.
    #[test]
    fn false_hits_bounded_at_both_ends_of_the_tame_domain() {
        let p = |e: i32| 2f32.powi(e);
        let mut checked = 0;
        for (n, gap_e) in [
            (p(-120), p(-120) * (1.0 - p(-19))),
            (p(119), p(119) * (1.0 - p(-19))),
        ] {
            for s in [p(-120), 1.0, p(120)] {
                let exact = |x: f32| f64::from(x) * f64::from(s);
                let normal = |x: f32| {
                    let y = x * s;
                    y.is_finite() && y.abs() >= f32::MIN_POSITIVE && f64::from(y) == exact(x)
                };
                if !(normal(n) && normal(2.0 * n) && normal(gap_e)) {
                    continue;
                }
                let ray = Ray::new(Vec3::ZERO, Vec3::new(s, s, 0.0));
                let bx = |e: f32| {
                    Aabb::new(
                        Vec3::new(n * s, -e * s, -1.0),
                        Vec3::new(2.0 * n * s, e * s, 1.0),
                    )
                };
                let (te, tx) = bx(n)
                    .intersect_ray(&ray)
                    .unwrap_or_else(|| panic!("touching box missed: N = {n:e}, s = {s:e}"));
                assert!(te <= n && tx >= n, "N = {n:e}, s = {s:e}: ({te:e}, {tx:e})");
                assert!(
                    bx(gap_e).intersect_ray(&ray).is_none(),
                    "false hit across a gap of 2^-19: N = {n:e}, s = {s:e}"
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 4, "the grid of boundary cases shrank");
        let tiny = Aabb::new(Vec3::new(p(-149), -1.0, -1.0), Vec3::new(1.0, 0.0, 1.0));
        assert!(hits(&tiny, Vec3::ZERO, Vec3::new(3.0, 1.0, 0.0)));
    }
}
