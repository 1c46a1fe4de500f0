//! Secondary rays never re-hit their own surface (issue 2, "Rays and tolerances"; robustness.md
//! §6.5 R1–R3, R5, and the A13 table).
//!
//! Triangles of size 1–11 are placed at distance `|p| ∈ {1, 1e3, 1e5, 1e7}` from the world
//! origin in random orientations; a primary ray hits each at a random interior point
//! ([`Watertight`]), [`TriangleHit::to_hit`] reconstructs the point with its error bound, and
//! secondary rays leave it. **Correct answer:** a ray leaving a flat triangle away from its
//! plane (reflection: same side as the incoming ray; transmission: the far side; both as
//! `spawn_ray` builds them) never meets that triangle again, so every re-test of the source
//! triangle must miss. The contrast strategy — the raw hit point with a fixed `t_min = 1e-4` —
//! is counted too, and must fail somewhere at `1e5` (where `1e-4` is below the coordinates'
//! resolution), which shows the test can detect self-intersection.

use glam::Vec3;
use halfray_core::hit::offset_ray_origin;
use halfray_core::tolerance::SHADOW_SEGMENT_END_SLACK;
use halfray_core::triangle::{TriangleIntersector, Watertight};
use halfray_core::{Hit, Ray, spawn_ray, spawn_ray_between, spawn_ray_to};
use halfray_tests::{Rng, min_angle_deg};

/// The scales of robustness.md §6.5 R1.
const SCALES: [f64; 4] = [1.0, 1.0e3, 1.0e5, 1.0e7];

/// The scene-blind strategy of the A13 table: raw hit point, `t_min = 1e-4` (absolute, in units
/// of the unit-length direction).
const FIXED_T_MIN: f32 = 1.0e-4;

/// Triangles per scale; each gets [`DIRECTIONS_PER_HIT`] secondary rays.
const TRIANGLES_PER_SCALE: usize = 1_500;
/// Secondary rays per hit: reflection, straight transmission, and random directions on each
/// side, some within 1e-3 rad of the tangent plane (R5, grazing).
const DIRECTIONS_PER_HIT: usize = 10;

/// A random well-shaped triangle at distance `scale` and a Watertight hit on it from a nearby
/// origin: `(triangle, incoming direction, hit)`.
fn random_hit(rng: &mut Rng, scale: f64) -> Option<([Vec3; 3], Vec3, Hit)> {
    let center = rng.unit_vector() * scale;
    let size = rng.range(1.0, 11.0);
    let tri = [0, 1, 2].map(|_| (center + rng.unit_vector() * size).as_vec3());
    if min_angle_deg(&tri) < 10.0 {
        return None;
    }
    let b1 = rng.range(0.05, 0.9);
    let b2 = rng.range(0.05, 0.95 - b1);
    let p = tri[0].as_dvec3() * (1.0 - b1 - b2) + tri[1].as_dvec3() * b1 + tri[2].as_dvec3() * b2;
    let o = p + rng.unit_vector() * rng.range(1.0, 20.0);
    let ray = Ray::new(o.as_vec3(), (p - o).as_vec3());
    let h = Watertight.intersect(&ray, &tri)?;
    Some((tri, ray.direction, h.to_hit(&tri)))
}

/// The secondary directions for a hit: unit vectors on the incoming side (reflections) and on
/// the far side (transmissions), tagged `true` for the incoming side.
fn directions(rng: &mut Rng, incoming: Vec3, n: Vec3) -> Vec<(Vec3, bool)> {
    let d = incoming.as_dvec3().normalize();
    let n = n.as_dvec3();
    let back = if d.dot(n) < 0.0 { n } else { -n };
    let mut out = vec![
        ((d - 2.0 * d.dot(n) * n).as_vec3(), true),
        (d.as_vec3(), false),
    ];
    while out.len() < DIRECTIONS_PER_HIT {
        let mut w = rng.unit_vector();
        if rng.chance(0.3) {
            // Grazing: within 1e-3 rad of the tangent plane.
            w = (w - w.dot(n) * n).normalize() + n * rng.range(-1.0e-3, 1.0e-3);
            w = w.normalize();
        }
        if w.dot(n).abs() < 1.0e-9 {
            continue;
        }
        out.push((w.as_vec3(), w.dot(back) > 0.0));
    }
    out
}

#[test]
fn spawned_rays_never_rehit_their_triangle() {
    let mut rng = Rng::new(42);
    let mut fixed_at_1e5 = 0;
    for scale in SCALES {
        let (mut rays, mut self_hits, mut fixed_self_hits) = (0usize, 0usize, 0usize);
        let mut offset_ulps: f64 = 0.0;
        let mut first_failure = None;
        let mut triangles = 0;
        while triangles < TRIANGLES_PER_SCALE {
            let Some((tri, incoming, hit)) = random_hit(&mut rng, scale) else {
                continue;
            };
            triangles += 1;
            for (w, reflect) in directions(&mut rng, incoming, hit.normal) {
                let ray = spawn_ray(&hit, w);
                // The offset went to the side w points to.
                let moved = (ray.origin - hit.point).as_dvec3();
                let side =
                    moved.dot(hit.normal.as_dvec3()) * w.as_dvec3().dot(hit.normal.as_dvec3());
                assert!(side > 0.0, "offset on the wrong side: {hit:?} {w:?}");
                offset_ulps = offset_ulps
                    .max(moved.length() / f64::from(hit.point.abs().max_element() * f32::EPSILON));
                rays += 1;
                if let Some(h) = Watertight.intersect(&ray, &tri) {
                    self_hits += 1;
                    first_failure.get_or_insert(format!(
                        "scale {scale:e} ({}) : {tri:?} hit {hit:?} w {w:?} -> {h:?}",
                        if reflect {
                            "reflection"
                        } else {
                            "transmission"
                        }
                    ));
                }
                let naive = Ray::with_interval(hit.point, w, FIXED_T_MIN, f32::INFINITY);
                if Watertight.intersect(&naive, &tri).is_some() {
                    fixed_self_hits += 1;
                }
            }
        }
        eprintln!(
            "SELF_HITS strategy=spawn_ray scale={scale:e} rays={rays} self_hits={self_hits} max_offset_ulps_of_p={offset_ulps:.1}"
        );
        eprintln!(
            "SELF_HITS strategy=fixed-tmin-1e-4 scale={scale:e} rays={rays} self_hits={fixed_self_hits}"
        );
        assert_eq!(self_hits, 0, "{}", first_failure.unwrap_or_default());
        if scale == 1.0e5 {
            fixed_at_1e5 = fixed_self_hits;
        }
    }
    assert!(
        fixed_at_1e5 > 0,
        "the fixed t_min = 1e-4 strategy should self-intersect at 1e5; the test cannot see it"
    );
}

/// R3: a shadow ray between two surface points — from a hit on triangle A to a point on a
/// facing triangle B, the target offset off B towards A as [`spawn_ray_to`] documents — hits
/// neither A (its source) nor B (its target's surface): the segment between the offset points
/// lies strictly between the two planes.
#[test]
fn shadow_rays_between_surface_points_hit_neither_end() {
    let mut rng = Rng::new(7);
    let (mut total_a, mut total_b) = (0usize, 0usize);
    let mut examples = Vec::new();
    for scale in SCALES {
        let (mut rays, mut hits_a, mut hits_b) = (0usize, 0usize, 0usize);
        while rays < 5_000 {
            let Some((tri_a, _, hit_a)) = random_hit(&mut rng, scale) else {
                continue;
            };
            let Some((tri_b, _, hit_b)) = random_hit(&mut rng, scale) else {
                continue;
            };
            // The two points must see each other's front: B's point on A's side and vice
            // versa, with a margin so the configuration is not grazing.
            let ab = (hit_b.point - hit_a.point).as_dvec3();
            let (na, nb) = (hit_a.normal.as_dvec3(), hit_b.normal.as_dvec3());
            if ab.length() < 1.0e-3 * scale.max(1.0)
                || ab.normalize().dot(na).abs() < 0.05
                || ab.normalize().dot(nb).abs() < 0.05
            {
                continue;
            }
            let target = offset_ray_origin(
                hit_b.point,
                hit_b.point_error,
                hit_b.normal,
                hit_a.point - hit_b.point,
            );
            let ray = spawn_ray_to(&hit_a, target);
            assert_eq!(
                (ray.t_min, ray.t_max),
                (0.0, 1.0 - SHADOW_SEGMENT_END_SLACK)
            );
            // The same segment through the public two-hit helper.
            assert_eq!(spawn_ray_between(&hit_a, &hit_b), ray);
            rays += 1;
            if let Some(h) = Watertight.intersect(&ray, &tri_a) {
                hits_a += 1;
                examples.push(format!("source hit at {scale:e}: {ray:?} {tri_a:?} {h:?}"));
            }
            if let Some(h) = Watertight.intersect(&ray, &tri_b) {
                hits_b += 1;
                examples.push(format!(
                    "target-surface hit at {scale:e}: {ray:?} target {target:?} {tri_b:?} {h:?}"
                ));
            }
        }
        eprintln!(
            "SHADOW scale={scale:e} rays={rays} source_hits={hits_a} target_surface_hits={hits_b}"
        );
        total_a += hits_a;
        total_b += hits_b;
    }
    for e in examples.iter().take(3) {
        eprintln!("SHADOW_FAILURE {e}");
    }
    assert_eq!(total_a, 0, "shadow rays hit their source triangle");
    assert_eq!(
        total_b, 0,
        "shadow rays hit the target's own surface (spawn_ray_to's closed t_max = 1)"
    );
}
