//! The other choices that trade accuracy for time: slab test (plain vs conservative), secondary
//! ray offsets (fixed epsilon vs error-bound spawn) and the sphere quadratic (naive vs stable).

use crate::crosscheck::sets::Rng;
use crate::timing::{median_of, per_million};
use glam::{DVec3, Vec3};
use halfray_core::aabb::SlabRay;
use halfray_core::triangle::{TriangleIntersector, Watertight};
use halfray_core::{Aabb, Hit, Ray};
use std::hint::black_box;
use std::time::Instant;

/// The classic scene-wide secondary-ray epsilon a fixed-offset renderer uses: new rays start at
/// the hit point with `t_min = 1e-4` (in units of the unit direction). Shown for comparison.
pub const FIXED_SPAWN_EPSILON: f32 = 1.0e-4;

/// One row of a comparison: a named choice with an error figure and a cost.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ChoiceRow {
    /// What was measured (`slab-plain @ 1e5`, …).
    pub name: String,
    /// Number of trials.
    pub trials: usize,
    /// Failures (false rejects, self-hits, false misses …) per million trials.
    pub failures_per_million: f64,
    /// A second error figure (documented per table: max relative `t` error, mean offset …).
    pub error: f64,
    /// Median ns per operation.
    pub ns: f64,
}

/// Rays that touch a box exactly along one of its edges, at distances `1 … 1e7` from the
/// origin: the box `[lo, hi]` and the ray `o + t·d` with `o + d = (lo.x, hi.y, z)` exactly
/// (all values on a dyadic grid, so the construction is exact in `f32`), `d.x > 0`, `d.y > 0`:
/// the exact ray enters the x slab and leaves the y slab at the same `t = 1`, so the closed box
/// is hit at a single point. Rounding of the slab distances can put `t_near` above `t_far`:
/// that is what Ize's far-distance padding is for. Failures are rejected boxes.
pub fn slab_rows(n: usize, seed: u64, reps: usize) -> Vec<ChoiceRow> {
    let mut rows = Vec::new();
    for dist in [1.0f64, 1.0e3, 1.0e5, 1.0e7] {
        let mut rng = Rng::new(seed ^ dist.to_bits());
        // Grid step: coordinates near `dist` keep ≤ 20 significant bits, so sums are exact.
        let step = 2f64.powi((dist.log2().ceil() as i32) - 20);
        let q = |x: f64| (x / step).round() * step;
        let mut cases: Vec<(Ray, Aabb)> = Vec::with_capacity(n);
        while cases.len() < n {
            let c = rng.unit_vector() * dist;
            let half = (dist * 1.0e-2).max(16.0 * step);
            let lo = DVec3::new(
                q(c.x - half * rng.f64()),
                q(c.y - half * rng.f64()),
                q(c.z - half),
            );
            let hi = DVec3::new(
                q(c.x + half * rng.f64() + step),
                q(c.y + half * rng.f64() + step),
                q(c.z + half),
            );
            let p = DVec3::new(lo.x, hi.y, q((lo.z + hi.z) * 0.5));
            let d = DVec3::new(
                q(rng.f64() * half + step),
                q(rng.f64() * half + step),
                q((rng.f64() - 0.5) * half),
            );
            let o = p - d;
            let (o32, d32, p32) = (o.as_vec3(), d.as_vec3(), p.as_vec3());
            if o32.as_dvec3() + d32.as_dvec3() != p32.as_dvec3() || o32.as_dvec3() != o {
                continue;
            }
            cases.push((Ray::new(o32, d32), Aabb::new(lo.as_vec3(), hi.as_vec3())));
        }
        for (label, conservative) in [("slab-plain", false), ("slab-conservative", true)] {
            let test = |r: &Ray, b: &Aabb| {
                let s = SlabRay::new(r)?;
                if conservative {
                    b.intersect_slab(&s, r.t_min, r.t_max)
                } else {
                    b.intersect_slab_plain(&s, r.t_min, r.t_max)
                }
            };
            let failures = cases.iter().filter(|(r, b)| test(r, b).is_none()).count();
            let ns = median_of(reps, || {
                let start = Instant::now();
                let mut k = 0u32;
                for (r, b) in &cases {
                    k += test(black_box(r), black_box(b)).is_some() as u32;
                }
                black_box(k);
                start.elapsed().as_secs_f64() * 1.0e9 / cases.len().max(1) as f64
            });
            rows.push(ChoiceRow {
                name: format!("{label} @ {dist:e}"),
                trials: cases.len(),
                failures_per_million: per_million(failures, cases.len()),
                error: 0.0,
                ns,
            });
        }
    }
    rows
}

/// Secondary rays leaving triangle hits at `|p| ∈ {1, 1e3, 1e5, 1e7}`, re-tested against their
/// own triangle with the watertight test: failures are self-hits; `error` is the mean distance
/// of the new origin from the surface relative to `|p|` (the "visible gap" the offset leaves);
/// `ns` is the median cost of spawning and re-testing one ray.
pub fn offset_rows(n: usize, seed: u64, reps: usize) -> Vec<ChoiceRow> {
    let mut rows = Vec::new();
    for mag in [1.0f64, 1.0e3, 1.0e5, 1.0e7] {
        let mut rng = Rng::new(seed ^ mag.to_bits() ^ 0x0FF5E7);
        let mut cases: Vec<([Vec3; 3], Hit, Vec3)> = Vec::with_capacity(n);
        while cases.len() < n {
            let c = rng.unit_vector() * mag;
            let size = 1.0 + 10.0 * rng.f64();
            let tri: [Vec3; 3] = [0, 1, 2].map(|_| (c + rng.unit_vector() * size).as_vec3());
            if (tri[1] - tri[0]).cross(tri[2] - tri[0]) == Vec3::ZERO {
                continue;
            }
            let target = (tri[0].as_dvec3() + tri[1].as_dvec3() + tri[2].as_dvec3()) / 3.0;
            let o = target + rng.unit_vector() * size * 3.0;
            let ray = Ray::new(o.as_vec3(), (target - o).as_vec3());
            let Some(h) = Watertight.intersect(&ray, &tri) else {
                continue;
            };
            let hit = h.to_hit(&tri);
            let n_unit = hit.facing_normal().as_dvec3();
            let d = ray.direction.as_dvec3().normalize();
            let w = (d - n_unit * 2.0 * d.dot(n_unit)).as_vec3();
            cases.push((tri, hit, w));
        }
        let plane_dist = |tri: &[Vec3; 3], p: Vec3| {
            let n = (tri[1] - tri[0])
                .cross(tri[2] - tri[0])
                .as_dvec3()
                .normalize();
            (p.as_dvec3() - tri[0].as_dvec3()).dot(n).abs()
        };
        type Spawn = fn(&Hit, Vec3) -> Ray;
        let fixed: Spawn = |hit, w| {
            Ray::with_interval(hit.point, w.normalize(), FIXED_SPAWN_EPSILON, f32::INFINITY)
        };
        let bound: Spawn = halfray_core::spawn_ray;
        for (label, spawn) in [
            ("offset-fixed-epsilon", fixed),
            ("offset-error-bound", bound),
        ] {
            let mut fails = 0usize;
            let mut gap = 0.0f64;
            for (tri, hit, w) in &cases {
                let r = spawn(hit, *w);
                fails += Watertight.intersect(&r, tri).is_some() as usize;
                // The fixed epsilon skips everything closer than FIXED_SPAWN_EPSILON along the ray.
                let start_dist = plane_dist(tri, r.at(r.t_min.max(0.0)));
                gap += start_dist / mag;
            }
            let ns = median_of(reps, || {
                let start = Instant::now();
                let mut k = 0u32;
                for (tri, hit, w) in &cases {
                    let r = spawn(black_box(hit), *w);
                    k += Watertight.intersect(&r, black_box(tri)).is_some() as u32;
                }
                black_box(k);
                start.elapsed().as_secs_f64() * 1.0e9 / cases.len().max(1) as f64
            });
            rows.push(ChoiceRow {
                name: format!("{label} @ |p|={mag:e}"),
                trials: cases.len(),
                failures_per_million: per_million(fails, cases.len()),
                error: gap / cases.len().max(1) as f64,
                ns,
            });
        }
    }
    rows
}

/// The oracle of the sphere rows, sharing no formula with either quadratic: the near crossing
/// of the ray with the sphere, found by bisection in `f64` on the sign of
/// `|o + t·d − c|² − r²` between `t = 0` (outside) and the ray's closest approach to the
/// centre (inside). Near the crossing `o + t·d − c` is about `r` long and its rounding about
/// `2⁻⁵²` of the distance `D`, so `t` is off by about `2⁻⁵¹·D / (r·cos)` of `r`, a relative
/// `2⁻⁵¹ / cos` (`cos` between the ray and the normal there, above 0.4 for these rays): far
/// below the `f32` errors measured. `None` when the ray starts inside or on the sphere, or
/// passes outside it.
fn sphere_oracle(ray: &Ray, center: DVec3, r: f64) -> Option<f64> {
    let (d, f) = (ray.direction.as_dvec3(), ray.origin.as_dvec3() - center);
    let outside = |t: f64| (f + d * t).length_squared() > r * r;
    let closest = -f.dot(d) / d.dot(d);
    if !(outside(0.0) && closest > 0.0 && !outside(closest)) {
        return None;
    }
    let (mut lo, mut hi) = (0.0, closest);
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return Some(mid);
        }
        if outside(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

/// Small spheres far from the ray origin (distance / radius `D/r = 10 … 1e5`), rays aimed at a
/// random point of the sphere's silhouette disc (well inside: at most 0.9 r off-centre), from
/// the origin's neighbourhood. Failures are false misses; `error` is the largest relative `t`
/// error against the bisection oracle (`sphere_oracle`).
pub fn sphere_rows(n: usize, seed: u64, reps: usize) -> Vec<ChoiceRow> {
    use halfray_core::sphere::Sphere;
    let mut rows = Vec::new();
    for ratio in [1.0e1f64, 1.0e3, 1.0e4, 1.0e5] {
        let mut rng = Rng::new(seed ^ ratio.to_bits() ^ 0x5_9E7E);
        let mut cases: Vec<(Ray, Sphere, f64)> = Vec::with_capacity(n);
        while cases.len() < n {
            let r = 0.5 + rng.f64();
            let c = rng.unit_vector() * (ratio * r);
            let Ok(s) = Sphere::new(c.as_vec3(), r as f32) else {
                continue;
            };
            let (c64, r64) = (s.center().as_dvec3(), s.radius() as f64);
            let o = rng.unit_vector() * rng.f64();
            let toward = (c64 - o).normalize();
            let side = toward.any_orthonormal_vector();
            let up = toward.cross(side);
            let (u, v) = (rng.f64() * 2.0 - 1.0, rng.f64() * 2.0 - 1.0);
            if u * u + v * v > 0.81 {
                continue;
            }
            let target = c64 + (side * u + up * v) * r64;
            let ray = Ray::new(o.as_vec3(), (target - o).as_vec3());
            let Some(t_ref) = sphere_oracle(&ray, c64, r64) else {
                continue;
            };
            cases.push((ray, s, t_ref));
        }
        for (label, naive) in [("sphere-naive", true), ("sphere-stable", false)] {
            let hit = |ray: &Ray, s: &Sphere| {
                if naive {
                    s.intersect_naive(ray)
                } else {
                    s.intersect(ray)
                }
            };
            let mut misses = 0usize;
            let mut max_err = 0.0f64;
            for (ray, s, t_ref) in &cases {
                match hit(ray, s) {
                    None => misses += 1,
                    Some(h) => max_err = max_err.max(((h.t as f64 - t_ref) / t_ref).abs()),
                }
            }
            let ns = median_of(reps, || {
                let start = Instant::now();
                let mut k = 0u32;
                for (ray, s, _) in &cases {
                    k += hit(black_box(ray), black_box(s)).is_some() as u32;
                }
                black_box(k);
                start.elapsed().as_secs_f64() * 1.0e9 / cases.len().max(1) as f64
            });
            rows.push(ChoiceRow {
                name: format!("{label} @ D/r={ratio:e}"),
                trials: cases.len(),
                failures_per_million: per_million(misses, cases.len()),
                error: max_err,
                ns,
            });
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Worked by hand on the sphere of radius 2 about `(0, 0, 10)`: a ray up the `z` axis meets
    /// it at `z = 8` (`t = 8`, or 4 at twice the speed), one a unit off the axis at
    /// `z = 10 − √3`; a ray 3 off the axis, one pointing away and one starting inside meet
    /// nothing.
    #[test]
    fn the_sphere_oracle_is_the_near_crossing() {
        let c = DVec3::new(0.0, 0.0, 10.0);
        let t = |o: Vec3, d: Vec3| sphere_oracle(&Ray::new(o, d), c, 2.0);
        let near = |got: Option<f64>, want: f64| {
            assert!(
                got.is_some_and(|g| (g - want).abs() <= 1e-14 * want),
                "{got:?} {want}"
            );
        };
        near(t(Vec3::ZERO, Vec3::Z), 8.0);
        near(t(Vec3::ZERO, Vec3::Z * 2.0), 4.0);
        near(t(Vec3::X, Vec3::Z), 10.0 - 3f64.sqrt());
        assert_eq!(t(Vec3::X * 3.0, Vec3::Z), None);
        assert_eq!(t(Vec3::ZERO, -Vec3::Z), None);
        assert_eq!(t(Vec3::new(0.0, 0.0, 10.0), Vec3::Z), None);
    }
}
