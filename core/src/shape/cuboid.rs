//! The closed axis-aligned box [`Aabb`] as a solid [`Shape`]: an `f64` slab test whose hit
//! points are snapped exactly onto the face they lie on.

use super::{Shape, whole_line};
use crate::aabb::Aabb;
use crate::float::gamma;
use crate::hit::Hit;
use crate::ray::Ray;
use glam::{Vec2, Vec3};

/// Where the whole line of `ray` (its interval ignored) crosses the closed box `b`: the entry
/// then the exit, `None` when it misses, when the box is empty or NaN, when a crossing is
/// at an infinite `t` or one beyond `f32`'s range (a direction of `10⁻³⁸` towards a box
/// `10³` away), or when the line is invalid (a non-finite origin or direction, or a
/// zero direction: [`Ray::validate`] of the ray with its interval replaced by all reals).
///
/// The slab distances `(lo − o)/d` are computed in `f64` from the `f32` inputs. The
/// difference is exact when the ulps of `lo` and `o` differ by a factor of at most `2²⁸`
/// (the exact difference then fits in `f64`'s 53 bits) and rounds once otherwise (`lo =
/// 10¹⁰`, `o = 10⁻¹⁰`); the quotient rounds once. So `t` is within
/// [`gamma_f64`](crate::float::gamma_f64)`(2)` (about `2⁻⁵²`) relative of the exact slab
/// distance before its rounding to `f32`. A line lying in a face's plane counts as inside
/// that slab. A line through an edge or corner, or touching the box at one point, enters and
/// leaves at the same `t` (both crossings are reported; a closed test, unlike a tangent
/// sphere's double root). Each hit's point is `o + t·d` rounded to `f32`, its coordinate
/// along the face's axis replaced by the face's exact coordinate and the rest clamped into
/// the box; [`Hit::point_error`] is `gamma(3)·|p|` on the two other axes (the `f64` product,
/// sum and rounding to `f32`) and 0 along the face's axis. The normal is the face's outward
/// axis vector, [`Hit::uv`] is zero.
#[must_use]
pub fn box_crossings(b: &Aabb, ray: &Ray) -> Option<[Hit; 2]> {
    if !whole_line(ray).is_valid() || !b.is_valid() {
        return None;
    }
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    let (mut a0, mut a1) = (0usize, 0usize);
    for axis in 0..3 {
        let (lo, hi) = (f64::from(b.min[axis]), f64::from(b.max[axis]));
        if d[axis] == 0.0 {
            if o[axis] < lo || o[axis] > hi {
                return None;
            }
            continue;
        }
        let (mut n, mut f) = ((lo - o[axis]) / d[axis], (hi - o[axis]) / d[axis]);
        if n > f {
            core::mem::swap(&mut n, &mut f);
        }
        if n > t0 {
            t0 = n;
            a0 = axis;
        }
        if f < t1 {
            t1 = f;
            a1 = axis;
        }
    }
    if !(t0 <= t1) || !(t0 as f32).is_finite() || !(t1 as f32).is_finite() {
        return None;
    }
    let mk = |t: f64, axis: usize, enter: bool| {
        let mut p = o + d * t;
        let mut normal = Vec3::ZERO;
        // Entering through the face the ray moves into: the near face.
        let to_max = (d[axis] < 0.0) == enter;
        p[axis] = if to_max {
            f64::from(b.max[axis])
        } else {
            f64::from(b.min[axis])
        };
        normal[axis] = if to_max { 1.0 } else { -1.0 };
        let point = p.as_vec3().clamp(b.min, b.max);
        let mut err = point.abs() * gamma(3);
        err[axis] = 0.0;
        Hit {
            t: t as f32,
            point,
            point_error: err,
            normal,
            uv: Vec2::ZERO,
            front_face: ray.direction.dot(normal) < 0.0,
        }
    };
    Some([mk(t0, a0, true), mk(t1, a1, false)])
}

impl Shape for Aabb {
    /// The box itself.
    fn bounds(&self) -> Aabb {
        *self
    }

    /// The entry of [`box_crossings`] if the ray's interval contains it, else the exit if it
    /// does (a ray starting inside hits the far face from within); `None` for an invalid ray.
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        let [entry, exit] = box_crossings(self, ray)?;
        [entry, exit].into_iter().find(|h| ray.contains(h.t))
    }

    /// Both [`box_crossings`].
    fn line_crossings(&self, ray: &Ray) -> [Option<Hit>; 2] {
        box_crossings(self, &whole_line(ray)).map_or([None, None], |h| h.map(Some))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::float::F32_UNIT_ROUNDOFF;

    /// A crossing whose `t` is finite in `f64` but beyond `f32`'s range (a direction of
    /// `10⁻³⁸` towards a box `10³` away: `t ≈ 10⁴¹`) is no crossing, as an infinite one.
    #[test]
    fn a_crossing_beyond_the_f32_range_is_none() {
        let b = Aabb::new(Vec3::new(1.0e3, -1.0, -1.0), Vec3::new(2.0e3, 1.0, 1.0));
        let ray = Ray::new(Vec3::ZERO, Vec3::new(1.0e-38, 0.0, 0.0));
        assert!(box_crossings(&b, &ray).is_none());
        let ray = Ray::new(Vec3::ZERO, Vec3::new(1.0e-30, 0.0, 0.0));
        let [a, z] = box_crossings(&b, &ray).expect("t = 10³³ is in range");
        assert!(a.t.is_finite() && z.t.is_finite());
    }

    /// The unit box `[0, 1]³` crossed along `+x` at `y = z = 0.5` from `x = −2`: by hand,
    /// entry at `t = 2` on the `−x` face, exit at `t = 3` on the `+x` face, the points exactly
    /// on the faces; from inside (origin at the centre) the exit only; a line beside the box
    /// misses; a diagonal line through the corner `(1, 1, 1)` of `[1, 2]³`'s neighbour touches
    /// at one `t`.
    #[test]
    fn box_worked_example() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let ray = Ray::new(Vec3::new(-2.0, 0.5, 0.5), Vec3::X);
        let [Some(a), Some(c)] = b.line_crossings(&ray) else {
            panic!("the line crosses the box");
        };
        assert_eq!(
            (a.t, a.point, a.normal),
            (2.0, Vec3::new(0.0, 0.5, 0.5), -Vec3::X)
        );
        assert_eq!(
            (c.t, c.point, c.normal),
            (3.0, Vec3::new(1.0, 0.5, 0.5), Vec3::X)
        );
        assert!(a.front_face && !c.front_face);
        assert_eq!((a.point_error.x, c.point_error.x), (0.0, 0.0));
        assert_eq!(b.closest_hit(&ray), Some(a));
        let inside = Ray::new(Vec3::splat(0.5), Vec3::X);
        let h = b.closest_hit(&inside).unwrap();
        assert_eq!((h.t, h.normal, h.front_face), (0.5, Vec3::X, false));
        let beside = Ray::new(Vec3::new(-2.0, 1.5, 0.5), Vec3::X);
        assert_eq!(b.line_crossings(&beside), [None, None]);
        assert_eq!(b.closest_hit(&beside), None);
        let corner = Ray::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.0, 1.0, -1.0));
        let [Some(p), Some(q)] = b.line_crossings(&corner) else {
            panic!("touches the corner");
        };
        assert_eq!((p.t, q.t), (1.0, 1.0));
        assert_eq!(p.point, Vec3::ONE);
    }

    /// Invalid rays ([`Ray::validate`]) hit nothing, as with every other shape: the audit's
    /// infinite direction (it hit at `t = −0`), NaN origin coordinate (`t = 3`) and NaN
    /// direction component, an infinite origin, a zero direction, and bad intervals (NaN
    /// `t_max`, `t_min = +∞`, `t_min > t_max`). The crossings of the ray's line ignore the
    /// interval, so a ray bad only there still has them; the oracle of which rays have
    /// crossings is the sphere inscribed in the box ([`Shape::line_crossings`] of
    /// [`crate::sphere::Sphere`], which validates its rays itself), crossed by the same
    /// line through the centre. An inverted box (`min > max`, empty) and a box with a NaN
    /// bound are missed, as documented.
    #[test]
    fn invalid_rays_and_empty_or_nan_boxes_miss() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let sphere = crate::sphere::Sphere::new(Vec3::splat(0.5), 0.5).unwrap();
        let (o, x) = (Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
        let inf = f32::INFINITY;
        let bad = [
            Ray::with_interval(Vec3::splat(0.5), Vec3::new(inf, 0.0, 0.0), -1.0, 1.0),
            Ray::new(Vec3::new(-1.0, f32::NAN, 0.5), x),
            Ray::new(o, Vec3::new(1.0, f32::NAN, 0.0)),
            Ray::new(Vec3::new(-inf, 0.5, 0.5), x),
            Ray::new(Vec3::splat(0.5), Vec3::ZERO),
            Ray::with_interval(o, x, 0.0, f32::NAN),
            Ray::with_interval(o, x, inf, inf),
            Ray::with_interval(o, x, 2.5, 2.0),
        ];
        for ray in bad {
            assert!(ray.validate().is_err(), "{ray:?}");
            assert_eq!(b.closest_hit(&ray), None, "{ray:?}");
            let crossed = b.line_crossings(&ray).map(|h| h.is_some());
            let want = sphere.line_crossings(&ray).map(|h| h.is_some());
            assert_eq!(crossed, want, "{ray:?}");
            assert_eq!(box_crossings(&b, &ray).is_some(), want[0], "{ray:?}");
        }
        // Along x (a slab of another axis rejects it) and along the diagonal, where every
        // slab's swapped planes alone would give a crossing at `t` in `[1, 2]`.
        // A box with one NaN bound is missed too.
        let inverted = Aabb::new(Vec3::ONE, Vec3::ZERO);
        let nan = Aabb::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ONE);
        for ray in [Ray::new(o, x), Ray::new(-Vec3::ONE, Vec3::ONE)] {
            for b in [inverted, nan] {
                assert_eq!(box_crossings(&b, &ray), None, "{b:?} {ray:?}");
                assert_eq!(b.closest_hit(&ray), None, "{b:?} {ray:?}");
            }
        }
    }

    /// Against an independent oracle: the `f32` slab test of [`Aabb::intersect_ray`] finds
    /// the same entry and exit within its own rounding, over random rays through random boxes.
    /// Relative gap, scaled by `1 + |t|`, allowed between the `f64` box test's crossings and
    /// the `f32` slab test's: the slab test pads its planes by a few `f32` ulps (one
    /// [`F32_UNIT_ROUNDOFF`] relative each) and these rays reach `|t|` of a few units, so
    /// `2¹¹` unit roundoffs leave room for both roundings without letting a wrong face (off
    /// by the box's size) pass.
    const SLAB_AGREEMENT: f32 = 2048.0 * F32_UNIT_ROUNDOFF;

    #[test]
    fn box_agrees_with_the_slab_test() {
        let mut r = crate::test_util::Lcg(3);
        let mut seen = 0;
        for _ in 0..2000 {
            let (p, q) = (r.v(4.0), r.v(4.0));
            let b = Aabb::new(p.min(q), p.max(q));
            let o = r.v(10.0);
            // Aimed near the box: most rays cross it, some miss or graze.
            let ray = Ray::new(o, b.center() + r.v(3.0) - o);
            let slab = b.intersect_ray(&Ray::with_interval(
                ray.origin,
                ray.direction,
                f32::NEG_INFINITY,
                f32::INFINITY,
            ));
            match (box_crossings(&b, &ray), slab) {
                (Some([a, c]), Some((t0, t1))) => {
                    let tol = SLAB_AGREEMENT * (1.0 + t0.abs().max(t1.abs()));
                    assert!(
                        (a.t - t0).abs() <= tol && (c.t - t1).abs() <= tol,
                        "{b:?} {ray:?}"
                    );
                    seen += 1;
                }
                (None, None) => {}
                // A grazing line: the padded slab test may keep what the exact one drops.
                (None, Some((t0, t1))) if t1 - t0 <= SLAB_AGREEMENT * (1.0 + t1.abs()) => {}
                (x, y) => panic!("{b:?} {ray:?}: {x:?} vs {y:?}"),
            }
        }
        assert!(seen > 600, "only {seen} rays crossed a box");
    }
}
