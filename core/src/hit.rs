//! The hit record shared by every primitive, and spawning secondary rays from it.
//!
//! Secondary rays (shadow, reflection, refraction) start at a hit point that is only known up
//! to rounding error. Instead of a global scene epsilon, every [`Hit`] carries a conservative
//! per-component bound `point_error` on `|point − exact surface point|`, and [`spawn_ray`]
//! moves the origin along the geometric normal just far enough to leave that error box
//! (pbrt-v4's `OffsetRayOrigin`), then one more ulp per component to cover the rounding of the
//! move itself. The offset scales with the magnitude of the coordinates, so it is correct at
//! `|p| = 1` and at `|p| = 1e7` alike.

use crate::float::unit_direction_f64;
use crate::ray::Ray;
use crate::tolerance::SHADOW_SEGMENT_END_SLACK;
use glam::{Vec2, Vec3};

/// Where a ray meets a primitive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit, inside the ray's `(t_min, t_max]`.
    pub t: f32,
    /// Hit point, reconstructed on the primitive (barycentric interpolation for triangles,
    /// re-projection for quadrics), not `origin + t·direction`.
    pub point: Vec3,
    /// Conservative absolute error bound on each component of `point`, world units.
    pub point_error: Vec3,
    /// Unit geometric normal. For triangles it is `(v1 − v0) × (v2 − v0)` normalised
    /// (counter-clockwise vertices face the viewer); for closed surfaces it points outward.
    /// It is *not* flipped towards the ray: see `front_face`.
    pub normal: Vec3,
    /// Surface parameters: barycentrics `(b1, b2)` of `v1`, `v2` for triangles (`b0 = 1 − b1 − b2`),
    /// otherwise primitive-specific (documented by each intersector).
    pub uv: Vec2,
    /// `true` when the ray arrives against the normal (`direction · normal < 0`).
    pub front_face: bool,
}

impl Hit {
    /// The normal facing the incoming ray (flipped when the back face was hit).
    #[inline]
    #[must_use]
    pub fn facing_normal(&self) -> Vec3 {
        if self.front_face {
            self.normal
        } else {
            -self.normal
        }
    }

    /// The origin for a ray leaving this hit in direction `w`: [`offset_ray_origin`] with the
    /// hit's normal taken as unit length, as its contract says (not normalised again).
    #[inline]
    #[must_use]
    pub fn spawn_origin(&self, w: Vec3) -> Vec3 {
        offset_to_side(self.point, self.point_error, self.normal, self.side(w) == 1)
    }

    /// The two origins rays leave this hit from, `[front, back]`: [`Hit::spawn_origin`]`(w)`
    /// is `spawn_origins()[`[`Hit::side`]`(w)]` for every `w`, as the offset depends on the
    /// direction only through the side of the surface it points to. For many rays from one
    /// hit (an area light's shadow rays): two offsets, not one a ray.
    #[inline]
    #[must_use]
    pub fn spawn_origins(&self) -> [Vec3; 2] {
        [false, true].map(|back| offset_to_side(self.point, self.point_error, self.normal, back))
    }

    /// Which of [`Hit::spawn_origins`] a ray leaving in direction `w` starts from: 1 when `w`
    /// points against the normal (`w · normal < 0`), else 0 (also for NaN).
    #[inline]
    #[must_use]
    pub fn side(&self, w: Vec3) -> usize {
        usize::from(w.dot(self.normal) < 0.0)
    }
}

/// Moves `p` off the surface with normal `n` to the side `w` points to, by the distance
/// `|n|·p_error` (the extent of the error box along `n`), then pushes each moved component one
/// ulp further away from `p`.
///
/// Contract: if the exact surface point lies in the box `p ± p_error` and the surface is locally
/// the plane with normal `n`, the returned point lies strictly on `w`'s side of that plane. A
/// curved surface is that plane only where the box is small against its radius of curvature:
/// a quadric of radius near `10⁻⁷` of its distance from the origin, or a cone's apex, has
/// error boxes as large as its curvature, and the point may land on the wrong side there.
/// `n` need not be unit length: it is normalised first (in `f64`, so a normal of any finite
/// non-zero length, `1e-30` or `1e30`, gives the offset of its direction). A zero or
/// non-finite `n` has no side: `p` is returned unchanged.
#[must_use]
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    match unit_direction_f64(n) {
        Ok(unit) => {
            let n = unit.as_vec3();
            offset_to_side(p, p_error, n, w.dot(n) < 0.0)
        }
        Err(_) => p,
    }
}

/// [`offset_ray_origin`] to the side of the plane `w` points to: against `n` when `back`.
#[inline]
fn offset_to_side(p: Vec3, p_error: Vec3, n: Vec3, back: bool) -> Vec3 {
    let d = n.abs().dot(p_error);
    let mut offset = n * d;
    if back {
        offset = -offset;
    }
    let mut po = p + offset;
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = po[i].next_up();
        } else if offset[i] < 0.0 {
            po[i] = po[i].next_down();
        }
    }
    po
}

/// A secondary ray leaving `hit` in direction `w` over `(0, +∞]`, with its origin offset by
/// the hit's error bound ([`offset_ray_origin`]). Reflection rays pass the reflected direction,
/// refraction rays the transmitted one (the offset then goes to the far side).
#[must_use]
pub fn spawn_ray(hit: &Hit, w: Vec3) -> Ray {
    Ray::new(hit.spawn_origin(w), w)
}

/// A shadow ray from `hit` towards the point `target` (a light position), with direction
/// `target − origin` over `(0, 1 − SHADOW_SEGMENT_END_SLACK]`
/// ([`crate::tolerance::SHADOW_SEGMENT_END_SLACK`]): anything between the offset origin and the
/// target blocks it, except within that sliver at the target's end. For a target that is
/// itself a surface point use [`spawn_ray_between`], which offsets it off its own surface.
#[must_use]
pub fn spawn_ray_to(hit: &Hit, target: Vec3) -> Ray {
    shadow_segment(hit.spawn_origin(target - hit.point), target)
}

/// [`spawn_ray_to`] from an origin already off the surface: direction `target − origin` over
/// `(0, 1 − SHADOW_SEGMENT_END_SLACK]`. `spawn_ray_to(hit, target)` is
/// `shadow_segment(hit.spawn_origins()[hit.side(target − hit.point)], target)`, bit for bit:
/// the form for many targets from one hit (an area light's points).
#[inline]
#[must_use]
pub fn shadow_segment(origin: Vec3, target: Vec3) -> Ray {
    Ray::with_interval(origin, target - origin, 0.0, 1.0 - SHADOW_SEGMENT_END_SLACK)
}

/// A shadow ray between two surface points (pbrt's `SpawnRayTo(from, to)`): both ends are
/// offset off their surfaces towards each other by their error bounds, so the segment hits
/// neither its source's nor its target's surface.
#[must_use]
pub fn spawn_ray_between(from: &Hit, to: &Hit) -> Ray {
    let target = to.spawn_origin(from.point - to.point);
    spawn_ray_to(from, target)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_leaves_the_error_box_on_the_requested_side() {
        let p = Vec3::new(1.0e5, 2.0, -3.0);
        let err = Vec3::splat(0.01);
        let n = Vec3::new(0.0, 1.0, 0.0);
        let up = offset_ray_origin(p, err, n, Vec3::new(0.3, 1.0, 0.0));
        let down = offset_ray_origin(p, err, n, Vec3::new(0.3, -1.0, 0.0));
        assert!(up.y > p.y + err.y, "{up:?}");
        assert!(down.y < p.y - err.y, "{down:?}");
        assert_eq!(up.x, p.x);
        assert_eq!(up.z, p.z);
    }

    /// The contract for a normal of any length: the exact point may lie anywhere in
    /// `p ± p_error`, so the plane `x = c` may pass through any `c ∈ [−1, 1]`; the origin must
    /// lie beyond `x = 1` to `w`'s side (and below `−1` against it) whether `n` is `2⁻¹⁰⁰`,
    /// `10⁻³`, `0.5`, `1` or `2⁶⁰` times the unit normal (the offset scaled with `|n|²`
    /// before). A zero or non-finite `n` has no side and leaves `p` as it is.
    #[test]
    fn offset_follows_the_normal_s_direction_not_its_length() {
        let (p, err) = (Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0));
        for k in [2f32.powi(-100), 1.0e-3, 0.5, 1.0, 2f32.powi(60)] {
            let n = Vec3::X * k;
            let out = offset_ray_origin(p, err, n, Vec3::new(1.0, 0.5, 0.0));
            let back = offset_ray_origin(p, err, n, Vec3::new(-1.0, 0.5, 0.0));
            assert!(out.x > 1.0 && back.x < -1.0, "|n| = {k}: {out:?} {back:?}");
            assert_eq!((out.y, out.z, back.y, back.z), (0.0, 0.0, 0.0, 0.0));
        }
        let p = Vec3::new(1.0, 2.0, 3.0);
        for n in [
            Vec3::ZERO,
            Vec3::new(f32::NAN, 0.0, 0.0),
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            Vec3::new(1.0, f32::NEG_INFINITY, 0.0),
        ] {
            let got = offset_ray_origin(p, Vec3::splat(1.0e-3), n, Vec3::X);
            assert_eq!(
                got.to_array().map(f32::to_bits),
                p.to_array().map(f32::to_bits),
                "{n:?}"
            );
        }
    }

    /// pbrt-v4's `OffsetRayOrigin` restated here, the oracle of the origins' tests: the error
    /// box's extent along `n`, to `w`'s side, then one ulp further per moved component.
    fn pbrt_offset(p: Vec3, err: Vec3, n: Vec3, w: Vec3) -> [f32; 3] {
        let d = n.x.abs() * err.x + n.y.abs() * err.y + n.z.abs() * err.z;
        let flip = if w.x * n.x + w.y * n.y + w.z * n.z < 0.0 {
            -1.0
        } else {
            1.0
        };
        core::array::from_fn(|i| {
            let off = n[i] * d * flip;
            let q = p[i] + off;
            if off > 0.0 {
                q.next_up()
            } else if off < 0.0 {
                q.next_down()
            } else {
                q
            }
        })
    }

    #[test]
    fn a_hit_s_two_origins_are_the_spawn_origin_of_every_direction() {
        // Hits of unit, tiny, huge, zero and NaN normals; directions on both sides, along and
        // against the normal, in the surface, zero, NaN and infinite.
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let mut checked = 0;
        for case in 0..400 {
            let v = Vec3::new(next(), next(), next());
            let normal = match case % 8 {
                0 => Vec3::ZERO,
                1 => Vec3::NAN,
                2 => v * 1e-25,
                3 => v * 1e30,
                _ => v.normalize_or(Vec3::Z),
            };
            let hit = Hit {
                t: 1.0,
                point: Vec3::new(next(), next(), next()) * [1.0, 1e3, 1e6][case % 3],
                point_error: Vec3::new(next(), next(), next()).abs() * 1e-4,
                normal,
                uv: Vec2::ZERO,
                front_face: true,
            };
            let origins = hit.spawn_origins();
            let r = Vec3::new(next(), next(), next());
            for w in [
                r,
                -r,
                normal,
                -normal,
                r.cross(normal),
                Vec3::ZERO,
                Vec3::NAN,
                Vec3::INFINITY,
            ] {
                let want = pbrt_offset(hit.point, hit.point_error, normal, w);
                let bits = |a: Vec3| a.to_array().map(f32::to_bits);
                assert_eq!(
                    bits(hit.spawn_origin(w)),
                    want.map(f32::to_bits),
                    "{hit:?} {w:?}"
                );
                assert_eq!(
                    bits(origins[hit.side(w)]),
                    want.map(f32::to_bits),
                    "{hit:?} {w:?}"
                );
                // The segment towards a target from the kept origin is `spawn_ray_to`'s.
                let target = hit.point + w;
                let side = hit.side(target - hit.point);
                let (a, b) = (
                    spawn_ray_to(&hit, target),
                    shadow_segment(origins[side], target),
                );
                assert_eq!(bits(a.origin), bits(b.origin));
                assert_eq!(bits(a.direction), bits(b.direction));
                assert_eq!(
                    (a.t_min.to_bits(), a.t_max.to_bits()),
                    (b.t_min.to_bits(), b.t_max.to_bits())
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 3200);
    }

    #[test]
    fn spawn_ray_to_ends_just_short_of_the_target() {
        let hit = Hit {
            t: 1.0,
            point: Vec3::ZERO,
            point_error: Vec3::ZERO,
            normal: Vec3::Z,
            uv: Vec2::ZERO,
            front_face: true,
        };
        let r = spawn_ray_to(&hit, Vec3::new(0.0, 0.0, 5.0));
        assert_eq!(r.t_min, 0.0);
        assert_eq!(r.t_max, 1.0 - SHADOW_SEGMENT_END_SLACK);
        assert_eq!(r.at(1.0), Vec3::new(0.0, 0.0, 5.0));
    }
}
