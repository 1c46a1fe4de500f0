//! Hard cases for the triangle intersectors and the slab test (issue 2; robustness.md §6.1,
//! §6.4). Every test states the correct answer and checks it; where a non-watertight variant is
//! allowed to be wrong, its behaviour is recorded with a greppable `eprintln!` line instead.

use glam::{DVec3, Vec3};
use halfray_core::aabb::{Aabb, SlabRay};
use halfray_core::tolerance::{BARYCENTRIC_SLACK, T_REL_TOLERANCE_WELL_CONDITIONED};
use halfray_core::triangle::{TriangleHit, TriangleVariant};
use halfray_core::{Ray, Vec2};
use halfray_fuzz_props::{EdgeEval, WatertightBound};
use halfray_tests::{CLEARANCE_IN_U, Mesh, Projector, Rng, U32, min_angle_deg};

const ALL: [TriangleVariant; 6] = TriangleVariant::ALL;

fn hit(v: TriangleVariant, ray: &Ray, tri: &[Vec3; 3]) -> Option<TriangleHit> {
    v.intersect(ray, tri)
}

// ---------------------------------------------------------------------------------------------
// T6: rays lying in the triangle's plane
// ---------------------------------------------------------------------------------------------

/// A ray inside the triangle's plane, crossing the triangle: no hit for every variant
/// (robustness.md §1.2: the coplanar convention, `det = 0`). Built exactly: the origin is
/// `v0 + α·e1 + β·e2` and the direction `γ·e1 + δ·e2` with dyadic coefficients and few-bit
/// vertices, every value checked representable, so the ray lies in the plane in real
/// arithmetic.
#[test]
fn rays_in_the_triangle_plane_never_hit() {
    let tris: [[Vec3; 3]; 4] = [
        [Vec3::ZERO, Vec3::X, Vec3::Y],
        [Vec3::X, Vec3::Y, Vec3::Z],
        [
            Vec3::new(0.3125, -0.75, 1.5),
            Vec3::new(2.0625, 0.5, -0.25),
            Vec3::new(-1.0, 1.75, 0.625),
        ],
        [
            Vec3::new(100.5, -3.25, 7.0),
            Vec3::new(96.0, 5.5, 12.75),
            Vec3::new(104.25, 2.0, -1.5),
        ],
    ];
    let coeffs: [(f32, f32, f32, f32); 6] = [
        (-1.0, 0.25, 1.0, 0.0),
        (-1.0, -1.0, 1.0, 1.0),
        (0.25, -2.0, 0.0, 1.0),
        (2.0, 0.5, -1.0, 0.0),
        (0.25, 0.25, 1.0, -0.5),
        (-0.5, 0.75, 0.75, -0.25),
    ];
    let mut checked = 0;
    let mut failures = Vec::new();
    for tri in &tris {
        let e1 = tri[1] - tri[0];
        let e2 = tri[2] - tri[0];
        for &(a, b, g, d) in &coeffs {
            let o = tri[0] + e1 * a + e2 * b;
            let dir = e1 * g + e2 * d;
            // Exactness: the f64 evaluation agrees with the f32 one bit for bit.
            let od = tri[0].as_dvec3()
                + (tri[1].as_dvec3() - tri[0].as_dvec3()) * f64::from(a)
                + (tri[2].as_dvec3() - tri[0].as_dvec3()) * f64::from(b);
            let dd = (tri[1].as_dvec3() - tri[0].as_dvec3()) * f64::from(g)
                + (tri[2].as_dvec3() - tri[0].as_dvec3()) * f64::from(d);
            assert_eq!(o.as_dvec3(), od, "origin not exact");
            assert_eq!(dir.as_dvec3(), dd, "direction not exact");
            for r in [Ray::new(o, dir), Ray::new(o + dir * 0.5, -dir)] {
                for v in ALL {
                    if let Some(h) = hit(v, &r, tri) {
                        failures.push(format!(
                            "IN_PLANE_HIT variant={} ray={r:?} tri={tri:?} got={h:?}",
                            v.name()
                        ));
                    }
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 48);
    for f in &failures {
        eprintln!("{f}");
    }
    assert!(failures.is_empty(), "{} in-plane hits", failures.len());
}

/// T7: a ray parallel to the plane one ulp above it: no hit for every variant.
#[test]
fn parallel_ray_one_ulp_above_misses() {
    let tri = [
        Vec3::ZERO,
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(0.0, 4.0, 0.0),
    ];
    for z in [f32::from_bits(1), 1.0e-30, 1.0f32.next_up() - 1.0] {
        for dir in [Vec3::new(1.0, 0.5, 0.0), Vec3::new(-0.3, 0.7, -0.0)] {
            let r = Ray::new(Vec3::new(-1.0, 0.5, z), dir);
            for v in ALL {
                assert_eq!(hit(v, &r, &tri), None, "{} z={z}", v.name());
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// T8: grazing rays
// ---------------------------------------------------------------------------------------------

/// `t` error allowed for a grazing hit: `|t − t_ref|·|d| ≤ T_GRAZING_ULPS·2⁻²³·R / sin θ`, with
/// `R` the largest coordinate of `vertex − origin` and θ the angle between the ray and the
/// plane. The watertight test's sheared coordinates carry about `4·u·R = 2·2⁻²³·R` of rounding;
/// along a ray at angle θ to the plane that becomes a depth error `/ sin θ`. 16 gives 8×
/// headroom over that estimate.
const T_GRAZING_ULPS: f64 = 16.0;

/// Skinny triangle (edges ≈ 11.2, 9.7, 1.4, as in embree #387) hit at angles of 1e-3…1e-6 rad
/// through points well inside it (barycentrics ≥ 0.2): the exact answer is a hit at the `t` of
/// [`f64_barycentrics`], decidable in `f32` when the projected triangle leaves the ray a
/// clearance of [`projected_clearance`]'s bound (at 1e-6 rad the projected triangle is about as
/// thin as the rounding of the shear: those rays are skipped, only a finite `t` is required of
/// them). The watertight variants must hit within [`T_GRAZING_ULPS`]; Möller–Trumbore and
/// Cramer are recorded (`GRAZING …` lines: worst error as a fraction of the tolerance).
#[test]
fn grazing_rays_on_a_skinny_triangle() {
    // The triangle in a generic orientation (rotated, rounded to f32), so that no axis is
    // special.
    let rot = glam::DQuat::from_axis_angle(DVec3::new(0.3, -0.5, 0.8).normalize(), 0.9);
    let tri = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(11.2, 0.0, 0.0),
        DVec3::new(1.6, 1.4, 0.0),
    ]
    .map(|p| (rot * p + DVec3::new(3.0, -2.0, 1.0)).as_vec3());
    let ng = (tri[1] - tri[0])
        .as_dvec3()
        .cross((tri[2] - tri[0]).as_dvec3())
        .normalize();
    let t1 = (tri[1] - tri[0]).as_dvec3().normalize();
    let t2 = ng.cross(t1);
    let mut rng = Rng::new(77);
    let mut worst = [0.0f64; 6];
    let mut misses = [0usize; 6];
    let (mut n, mut undecidable) = (0, 0);
    for &angle in &[1.0e-3f64, 1.0e-4, 1.0e-5, 1.0e-6] {
        for _ in 0..500 {
            let b1 = rng.range(0.2, 0.6);
            let b2 = rng.range(0.2, 0.8 - b1);
            let p = tri[0].as_dvec3() * (1.0 - b1 - b2)
                + tri[1].as_dvec3() * b1
                + tri[2].as_dvec3() * b2;
            let phi = rng.range(0.0, std::f64::consts::TAU);
            let dir = (t1 * phi.cos() + t2 * phi.sin()) * angle.cos() - ng * angle.sin();
            let dist = rng.range(1.0, 20.0);
            let ray = Ray::new((p - dir * dist).as_vec3(), dir.as_vec3());
            // Rounding the origin to f32 moves the aimed-at point by up to u·|o|/sin θ along
            // the plane; keep the rays whose exact crossing is still well inside. The oracle is
            // the plain line–plane solve (`f64_barycentrics`), which shares no code with the
            // watertight projection.
            let Some((t_ref, b)) = f64_barycentrics(&ray, &tri) else {
                continue;
            };
            if t_ref <= 0.0 || b.iter().any(|&x| x < 0.05) {
                continue;
            }
            let (clearance, required) = projected_clearance(&ray, &tri);
            if clearance < required {
                // Too thin in projection for f32 to decide: any answer is acceptable, but a
                // reported t must still be finite.
                undecidable += 1;
                for v in ALL {
                    if let Some(h) = hit(v, &ray, &tri) {
                        assert!(h.t.is_finite(), "{}", v.name());
                    }
                }
                continue;
            }
            n += 1;
            let dl = ray.direction.as_dvec3().length();
            let sin = (ray.direction.as_dvec3().dot(ng).abs() / dl).max(1.0e-12);
            let r = tri
                .iter()
                .map(|v| (v.as_dvec3() - ray.origin.as_dvec3()).abs().max_element())
                .fold(0.0, f64::max);
            let tol = T_GRAZING_ULPS * f64::from(f32::EPSILON) * r / (dl * sin);
            for (i, v) in ALL.into_iter().enumerate() {
                match hit(v, &ray, &tri) {
                    Some(h) => {
                        assert!(h.t.is_finite(), "{}: t = {}", v.name(), h.t);
                        let err = (f64::from(h.t) - t_ref).abs();
                        worst[i] = worst[i].max(err / tol);
                        if v.is_watertight() {
                            assert!(
                                err <= tol,
                                "{} at {angle}: t = {} vs {t_ref} (tol {tol:e})",
                                v.name(),
                                h.t
                            );
                        }
                    }
                    None => {
                        misses[i] += 1;
                        assert!(
                            !v.is_watertight(),
                            "{} missed at {angle}: {ray:?}",
                            v.name()
                        );
                    }
                }
            }
        }
    }
    for (i, v) in ALL.into_iter().enumerate() {
        eprintln!(
            "GRAZING variant={} rays={n} misses={} worst_t_err_over_tol={:.3e} undecidable_skipped={undecidable}",
            v.name(),
            misses[i],
            worst[i]
        );
    }
    assert!(n >= 1000, "only {n} decidable grazing rays");
}

// ---------------------------------------------------------------------------------------------
// T17 / B1: ±0 direction components
// ---------------------------------------------------------------------------------------------

/// Every direction with zero components, each zero taken as `+0.0` and as `−0.0`: the triangle
/// results (hit or not, `t`, barycentrics, normal, face) and the box results must be identical.
/// Origins include points on the triangle's edge lines and on the box's face planes.
#[test]
fn signed_zero_directions_give_identical_results() {
    let tris = [
        [Vec3::ZERO, Vec3::X, Vec3::Y],
        [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 1.0, 0.5),
        ],
        [
            Vec3::new(-1.0, -1.0, -1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(-1.0, 1.0, 1.0),
        ],
    ];
    let boxes = [
        Aabb::new(Vec3::ZERO, Vec3::ONE),
        Aabb::new(Vec3::new(-1.0, 0.0, 0.5), Vec3::new(0.0, 0.0, 0.5)),
    ];
    let origins = [
        Vec3::new(0.25, 0.5, 5.0),
        Vec3::new(0.0, 0.5, 5.0),
        Vec3::new(0.5, 0.5, -5.0),
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::new(-5.0, 0.0, 0.0),
        Vec3::new(-5.0, 0.25, 0.5),
        Vec3::new(1.0, 0.5, -3.0),
        Vec3::new(0.5, 1.0, 0.5),
    ];
    let mut compared = 0;
    // Direction templates: 1 or 2 non-zero components, the rest zero.
    for mask in 1u8..7 {
        for signs in 0u8..8 {
            let mut base = [0.0f32; 3];
            for (i, slot) in base.iter_mut().enumerate() {
                if mask & (1 << i) != 0 {
                    *slot = if signs & (1 << i) != 0 { -1.0 } else { 1.0 };
                }
            }
            let zeros: Vec<usize> = (0..3).filter(|&i| base[i] == 0.0).collect();
            let variants: Vec<Vec3> = (0..(1u8 << zeros.len()))
                .map(|zs| {
                    let mut d = base;
                    for (j, &i) in zeros.iter().enumerate() {
                        d[i] = if zs & (1 << j) != 0 { -0.0 } else { 0.0 };
                    }
                    Vec3::from_array(d)
                })
                .collect();
            for &o in &origins {
                let first = Ray::new(o, variants[0]);
                for &d in &variants[1..] {
                    let r = Ray::new(o, d);
                    for tri in &tris {
                        for v in ALL {
                            assert_eq!(
                                hit(v, &first, tri),
                                hit(v, &r, tri),
                                "{}: {:?} vs {:?}",
                                v.name(),
                                first.direction,
                                d
                            );
                        }
                    }
                    for b in &boxes {
                        assert_eq!(b.intersect_ray(&first), b.intersect_ray(&r), "{b:?} {r:?}");
                    }
                    compared += 1;
                }
            }
        }
    }
    assert!(compared > 100, "{compared}");
}

// ---------------------------------------------------------------------------------------------
// T12 (single triangles): translated geometry, t against the f64 line–plane crossing
// ---------------------------------------------------------------------------------------------

/// Relative `t` error (against the line–plane crossing of [`f64_barycentrics`]) allowed for the watertight variants on
/// well-conditioned hits (ray within 60° of the normal) of triangles translated to `1e5` and
/// `1e6`, with the origin either near the triangle or at the world origin: the core's
/// [`T_REL_TOLERANCE_WELL_CONDITIONED`] (64 ulps of `t`). It holds at any offset because every
/// rounding is relative to the coordinates of `vertex − origin`, which are `O(t·|d|)` for these
/// rays (near origin: the translation is exact by Sterbenz; far origin: the triangle is small
/// against the distance).
const T_REL_TOL_TRANSLATED: f64 = T_REL_TOLERANCE_WELL_CONDITIONED as f64;

/// Distance, in the projection along the ray, from the ray to the triangle's boundary, and the
/// distance below which an `f32` intersector may legitimately decide either way:
/// `CLEARANCE_IN_U·u·R` (see [`halfray_tests::CLEARANCE_IN_U`]). With the camera at the world
/// origin and the triangle at `1e6`, `u·R ≈ 0.06` world units — the `f32` shear alone moves the
/// effective ray that far — so "hit" is only decidable for points farther than ~1 unit from
/// the edges.
fn projected_clearance(ray: &Ray, tri: &[Vec3; 3]) -> (f64, f64) {
    let proj = Projector::new(ray);
    let p = tri.map(|v| proj.project(v));
    let mut clearance = f64::INFINITY;
    for k in 0..3 {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        let ab = b - a;
        let t = ((-a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        clearance = clearance.min((a + ab * t).length());
    }
    let r = tri
        .iter()
        .map(|v| (v.as_dvec3() - ray.origin.as_dvec3()).abs().max_element())
        .fold(0.0, f64::max);
    (clearance, CLEARANCE_IN_U * U32 * r)
}

/// Triangles of size 1–30 at `1e5` and `1e6`, rays from near the triangle and from the world
/// origin, through points inside the triangle farther than [`projected_clearance`]'s bound
/// from its edges: the exact answer is a hit at the `t` of [`f64_barycentrics`]; watertight
/// variants must hit within [`T_REL_TOL_TRANSLATED`]. Möller–Trumbore and Cramer are recorded
/// (`TRANSLATED_T …` lines).
#[test]
fn translated_geometry_t_matches_reference() {
    let mut rng = Rng::new(5);
    for offset in [1.0e5f64, 1.0e6] {
        for camera_at_origin in [false, true] {
            let mut worst = [0.0f64; 6];
            let mut misses = [0usize; 6];
            let (mut n, mut attempts) = (0, 0);
            while n < 4000 {
                attempts += 1;
                assert!(attempts < 400_000, "too few usable rays: {n}");
                let c = DVec3::new(offset, -0.5 * offset, 0.25 * offset)
                    + DVec3::new(rng.range(-50.0, 50.0), rng.range(-50.0, 50.0), 0.0);
                let size = rng.log_range(1.0, 30.0);
                let tri = [0, 1, 2].map(|_| (c + rng.unit_vector() * size).as_vec3());
                let ng = (tri[1] - tri[0])
                    .as_dvec3()
                    .cross((tri[2] - tri[0]).as_dvec3());
                let b1 = rng.range(0.05, 0.9);
                let b2 = rng.range(0.05, 0.95 - b1);
                let p = tri[0].as_dvec3() * (1.0 - b1 - b2)
                    + tri[1].as_dvec3() * b1
                    + tri[2].as_dvec3() * b2;
                let o = if camera_at_origin {
                    DVec3::new(
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                    )
                } else {
                    p + rng.unit_vector() * rng.range(1.0, 30.0)
                };
                let ray = Ray::new(o.as_vec3(), (p - o).as_vec3());
                let d = ray.direction.as_dvec3();
                let cos = (ng.dot(d) / (ng.length() * d.length())).abs();
                if cos < 0.5 {
                    continue;
                }
                // Rounding the ray to f32 moves it off the aimed-at point: keep the rays whose
                // exact crossing is inside (`projected_clearance` then demands the margin).
                let Some((t_ref, b)) = f64_barycentrics(&ray, &tri) else {
                    continue;
                };
                if t_ref <= 0.0 || b.iter().any(|&x| x <= 0.0) {
                    continue;
                }
                let (clearance, required) = projected_clearance(&ray, &tri);
                if clearance < required {
                    continue;
                }
                n += 1;
                for (i, v) in ALL.into_iter().enumerate() {
                    match hit(v, &ray, &tri) {
                        Some(h) => {
                            let rel = (f64::from(h.t) - t_ref).abs() / t_ref;
                            worst[i] = worst[i].max(rel);
                            if v.is_watertight() {
                                assert!(
                                    rel <= T_REL_TOL_TRANSLATED,
                                    "{} at {offset}: t = {} vs {t_ref} ({rel:e})",
                                    v.name(),
                                    h.t
                                );
                            }
                        }
                        None => {
                            misses[i] += 1;
                            assert!(!v.is_watertight(), "{} missed: {ray:?} {tri:?}", v.name());
                        }
                    }
                }
            }
            for (i, v) in ALL.into_iter().enumerate() {
                eprintln!(
                    "TRANSLATED_T variant={} offset={offset:e} camera_at_origin={camera_at_origin} rays={n} misses={} max_rel_t_err_ulps={:.2}",
                    v.name(),
                    misses[i],
                    worst[i] / f64::from(f32::EPSILON)
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// T10 / T11: tiny and huge triangles
// ---------------------------------------------------------------------------------------------

/// Relative `t` accuracy demanded of [`halfray_core::triangle::Watertight`] on the `1e-20` and
/// `1e20` triangles (axial and oblique rays through well-inside points): the f64 edge
/// functions neither overflow nor underflow there, so the only errors are the f32 roundings of
/// translation, shear and the final cast — a few ulps; 16 ulps of slack.
const T_REL_TOL_EXTREME: f64 = 16.0 * f32::EPSILON as f64;

/// Relative rounding of each component of the constructed ray, unitless: `2·2⁻²⁴`. The
/// origin `p − dir·dist` and the direction are computed in `f64` and rounded to the nearest
/// `f32` (`2⁻²⁴` each); the factor 2 covers the `f64` roundings of `p` and `p − dir·dist`
/// (`~2⁻⁵²`) with room to spare.
const CONSTRUCTED_RAY_ROUNDING_REL: f64 = 2.0 / 16_777_216.0;

/// How far the exact `t` of the constructed ray (origin `o = f32(p − dir·dist)`, direction
/// `d = f32(dir)`, `p` on the triangle, `dir` a unit vector with `|n̂·dir| = cos`) can be from
/// `dist`, world units: `t = n̂·(p − o)/(n̂·d)` with `o = p − dir·dist + δo` and
/// `d = dir + δd`, `‖δo‖ ≤ r‖o‖`, `‖δd‖ ≤ r` (`r =` [`CONSTRUCTED_RAY_ROUNDING_REL`]), so
/// `|t − dist| ≤ r·(‖o‖ + dist)/(cos − r)`. The oracle of [`tiny_and_huge_triangles`]: it
/// comes from the construction alone, none of the intersection code.
fn constructed_t_slack(origin: Vec3, dist: f64, cos: f64) -> f64 {
    let r = CONSTRUCTED_RAY_ROUNDING_REL;
    r * (origin.as_dvec3().length() + dist) / (cos - r)
}

/// Triangles with edges of `1e-20` and `1e20` (and `1e18`, where f32 products overflow): the
/// exact answer is a hit at `t ≈ dist`, the distance the ray's origin was placed from a point
/// of the triangle (within [`constructed_t_slack`]). `watertight` and `f64-reference` must find
/// it with `t` within that plus [`T_REL_TOL_EXTREME`] of `dist`; every variant that reports a hit must report a
/// finite `t` (never `inf`, the failure mode of f32 products in robustness.md §4.2). What the
/// others do is recorded as `EXTREME variant=… size=… hits=… misses=…`.
#[test]
fn tiny_and_huge_triangles() {
    let mut bugs = Vec::new();
    for s in [1.0e-20f32, 1.0e-10, 1.0e18, 1.0e20] {
        let tris = [
            [Vec3::ZERO, Vec3::new(s, 0.0, 0.0), Vec3::new(0.0, s, 0.0)],
            [
                Vec3::new(0.5 * s, -0.25 * s, 0.125 * s),
                Vec3::new(1.5 * s, 0.75 * s, -0.5 * s),
                Vec3::new(-0.25 * s, 1.25 * s, 0.75 * s),
            ],
        ];
        let mut hits = [0usize; 6];
        let mut misses = [0usize; 6];
        let mut infinite = [0usize; 6];
        let mut rng = Rng::new(s.to_bits().into());
        for tri in &tris {
            for k in 0..50 {
                let b1 = rng.range(0.2, 0.5);
                let b2 = rng.range(0.2, 0.7 - b1);
                let p = tri[0].as_dvec3() * (1.0 - b1 - b2)
                    + tri[1].as_dvec3() * b1
                    + tri[2].as_dvec3() * b2;
                let dir = if k == 0 {
                    DVec3::new(0.0, 0.0, -1.0)
                } else {
                    let mut u = rng.unit_vector();
                    let ng = (tri[1] - tri[0])
                        .as_dvec3()
                        .cross((tri[2] - tri[0]).as_dvec3());
                    if u.dot(ng) > 0.0 {
                        u = -u;
                    }
                    if u.dot(ng).abs() < 0.3 * ng.length() {
                        continue;
                    }
                    u
                };
                let dist = f64::from(s) * rng.range(0.5, 3.0);
                let ray = Ray::new((p - dir * dist).as_vec3(), dir.as_vec3());
                let ng = (tri[1] - tri[0])
                    .as_dvec3()
                    .cross((tri[2] - tri[0]).as_dvec3());
                let cos = dir.dot(ng).abs() / ng.length();
                let t_slack = constructed_t_slack(ray.origin, dist, cos) + T_REL_TOL_EXTREME * dist;
                let t_ref = dist;
                for (i, v) in ALL.into_iter().enumerate() {
                    match hit(v, &ray, tri) {
                        Some(h) => {
                            hits[i] += 1;
                            if !h.t.is_finite() {
                                infinite[i] += 1;
                                if v.is_watertight() {
                                    bugs.push(format!(
                                        "INFINITE_T variant={} size={s:e} ray={ray:?} tri={tri:?} got={h:?} expected_t={t_ref}",
                                        v.name()
                                    ));
                                }
                                continue;
                            }
                            let err = (f64::from(h.t) - t_ref).abs();
                            if matches!(
                                v,
                                TriangleVariant::Watertight | TriangleVariant::F64Reference
                            ) {
                                assert!(
                                    err <= t_slack,
                                    "{} at {s}: t = {} vs dist {t_ref} (|Δ| {err:e} > {t_slack:e})",
                                    v.name(),
                                    h.t
                                );
                            }
                        }
                        None => {
                            misses[i] += 1;
                            assert!(
                                !matches!(
                                    v,
                                    TriangleVariant::Watertight | TriangleVariant::F64Reference
                                ),
                                "{} misses the {s} triangle: {ray:?}",
                                v.name()
                            );
                        }
                    }
                }
            }
        }
        for (i, v) in ALL.into_iter().enumerate() {
            eprintln!(
                "EXTREME variant={} size={s:e} hits={} misses={} infinite_t={}",
                v.name(),
                hits[i],
                misses[i],
                infinite[i]
            );
        }
    }
    for b in bugs.iter().take(4) {
        eprintln!("{b}");
    }
    assert!(
        bugs.is_empty(),
        "{} hits with t = ±inf from watertight variants (robustness.md T11: never)",
        bugs.len()
    );
}

// ---------------------------------------------------------------------------------------------
// T9: degenerate triangles
// ---------------------------------------------------------------------------------------------

/// Zero-area triangles — collinear corners, a repeated corner, all corners equal — are never
/// hit, by any variant, whatever the ray: here rays through the degenerate segment's interior,
/// through its end points and through the repeated corner, from many directions (including
/// rays lying on the segment's line).
#[test]
fn degenerate_triangles_are_never_hit() {
    let a = Vec3::new(0.5, -0.25, 1.0);
    let b = Vec3::new(2.5, 1.75, -3.0);
    let mid = (a + b) * 0.5;
    let tris = [
        [a, mid, b],
        [a, b, mid],
        [a, a, b],
        [a, b, b],
        [b, a, a],
        [a, a, a],
        [Vec3::ZERO; 3],
        [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        [
            Vec3::new(1.0e5, 0.0, 0.0),
            Vec3::new(1.0e5, 1.0, 0.0),
            Vec3::new(1.0e5, 2.0, 0.0),
        ],
    ];
    let mut rng = Rng::new(9);
    let mut n = 0;
    let mut bad = [0usize; 6];
    for tri in &tris {
        let targets = [tri[0], tri[1], tri[2], (tri[0] + tri[2]) * 0.5];
        for &p in &targets {
            for k in 0..40 {
                let dir = if k == 0 {
                    tri[2] - tri[0]
                } else {
                    rng.unit_vector().as_vec3()
                };
                if dir == Vec3::ZERO {
                    continue;
                }
                let ray = Ray::new(p - dir * 3.0, dir);
                for (i, v) in ALL.into_iter().enumerate() {
                    if let Some(h) = hit(v, &ray, tri) {
                        bad[i] += 1;
                        if bad[i] <= 2 {
                            eprintln!(
                                "DEGENERATE_HIT variant={} ray={ray:?} tri={tri:?} got={h:?}",
                                v.name()
                            );
                        }
                    }
                }
                n += 1;
            }
        }
    }
    assert!(n > 1000);
    for (i, v) in ALL.into_iter().enumerate() {
        eprintln!("DEGENERATE variant={} rays={n} hits={}", v.name(), bad[i]);
    }
    assert_eq!(bad, [0; 6], "hits on zero-area triangles");
}

// ---------------------------------------------------------------------------------------------
// T19 / T20 / B8: NaN and infinity
// ---------------------------------------------------------------------------------------------

const SPECIALS: [f32; 3] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];

/// Expected outcome of a ray field set to a special value, from the ray contract
/// ([`Ray::validate`]): any non-finite origin or direction component → no hit; `t_min` NaN or
/// `+∞` → no hit; `t_min = −∞` is a valid interval `(−∞, t_max]` → the hit at `t = 5`;
/// `t_max` NaN or `−∞` → no hit; `t_max = +∞` → the hit.
fn field_expectation(field: usize, value: f32) -> bool {
    match field {
        0..=5 => false,
        6 => value == f32::NEG_INFINITY,
        _ => value == f32::INFINITY,
    }
}

fn set_field(r: &mut Ray, field: usize, value: f32) {
    match field {
        0..=2 => r.origin[field] = value,
        3..=5 => r.direction[field - 3] = value,
        6 => r.t_min = value,
        _ => r.t_max = value,
    }
}

/// NaN and ±∞ in each of the eight ray fields (origin xyz, direction xyz, `t_min`, `t_max`) and
/// in each of the nine vertex components: no panic, and the answer the contract gives (see
/// [`field_expectation`]; any non-finite vertex → no hit), for every variant and for
/// [`Aabb::intersect_ray`].
#[test]
fn nan_and_infinity_in_every_field() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let base = Ray::with_interval(
        Vec3::new(0.25, 0.5, 5.0),
        Vec3::new(0.0, 0.0, -1.0),
        0.0,
        10.0,
    );
    for v in ALL {
        assert!(hit(v, &base, &tri).is_some());
    }
    assert!(unit.intersect_ray(&base).is_some());
    for field in 0..8 {
        for value in SPECIALS {
            let mut r = base;
            set_field(&mut r, field, value);
            let expect = field_expectation(field, value);
            for v in ALL {
                let h = hit(v, &r, &tri);
                assert_eq!(h.is_some(), expect, "{} field {field} = {value}", v.name());
                if let Some(h) = h {
                    assert_eq!(h.t, 5.0, "{}", v.name());
                }
            }
            let b = unit.intersect_ray(&r);
            assert_eq!(b.is_some(), expect, "aabb field {field} = {value}");
            assert_eq!(SlabRay::new(&r).is_some(), r.is_valid());
        }
    }
    // Non-finite vertices: no hit, no panic, whichever vertex and component.
    for corner in 0..3 {
        for axis in 0..3 {
            for value in SPECIALS {
                let mut t = tri;
                t[corner][axis] = value;
                for v in ALL {
                    for r in [base, Ray::new(Vec3::new(0.2, 0.2, -3.0), Vec3::Z)] {
                        assert_eq!(
                            hit(v, &r, &t),
                            None,
                            "{} vertex {corner}.{axis} = {value}",
                            v.name()
                        );
                    }
                }
            }
        }
    }
    // A zero direction is invalid too.
    let r = Ray::new(Vec3::new(0.25, 0.5, 5.0), Vec3::ZERO);
    for v in ALL {
        assert_eq!(hit(v, &r, &tri), None);
    }
    assert_eq!(unit.intersect_ray(&r), None);
}

// ---------------------------------------------------------------------------------------------
// T13 / T14: interval ends
// ---------------------------------------------------------------------------------------------

/// The interval is `(t_min, t_max]`: a hit exactly at `t_max` is reported, one exactly at
/// `t_min` is not, for every variant — on an exact configuration (`t = 5`) and on random rays,
/// where each variant's own `t` is used as the bound.
#[test]
fn hit_exactly_at_t_max_counts_and_at_t_min_does_not() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let o = Vec3::new(0.25, 0.5, 5.0);
    let d = Vec3::new(0.0, 0.0, -1.0);
    for v in ALL {
        let at = |lo: f32, hi: f32| hit(v, &Ray::with_interval(o, d, lo, hi), &tri).map(|h| h.t);
        assert_eq!(at(0.0, 5.0), Some(5.0), "{}", v.name());
        assert_eq!(at(0.0, 5.0f32.next_down()), None, "{}", v.name());
        assert_eq!(at(5.0, 10.0), None, "{}", v.name());
        assert_eq!(at(5.0f32.next_down(), 10.0), Some(5.0), "{}", v.name());
        assert_eq!(at(5.0, 5.0), None, "{}: empty interval", v.name());
    }
    // Origin exactly on the triangle: t = 0 is excluded by the open lower end (T13).
    let on = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::new(0.1, 0.2, 1.0));
    for v in ALL {
        assert_eq!(hit(v, &on, &tri), None, "{}", v.name());
    }
    let mut rng = Rng::new(3);
    for _ in 0..2000 {
        let tri = [0, 1, 2].map(|_| rng.unit_vector().as_vec3() * 3.0);
        let o = (rng.unit_vector() * 10.0).as_vec3();
        let c = (tri[0] + tri[1] + tri[2]) / 3.0;
        let dir = (c + (rng.unit_vector() * 0.5).as_vec3()) - o;
        for v in ALL {
            let Some(h) = hit(v, &Ray::new(o, dir), &tri) else {
                continue;
            };
            let hi = hit(v, &Ray::with_interval(o, dir, 0.0, h.t), &tri);
            assert_eq!(hi.map(|x| x.t), Some(h.t), "{}: at t_max", v.name());
            let lo = hit(v, &Ray::with_interval(o, dir, h.t, f32::INFINITY), &tri);
            assert_eq!(lo, None, "{}: at t_min", v.name());
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The meshes README worked example
// ---------------------------------------------------------------------------------------------

/// `../shared/meshes/README.md`: origin (0.25, 0.5, 5), direction (0, 0, −1). Brute force over
/// all triangles with every variant. Expected (1-based faces): tetrahedron enters at t = 4.25
/// through face 2 and exits at t = 5.25 through face 4; cube enters at 4 (face 12), exits at 6
/// (face 9); octahedron enters at 4.75 (face 1), exits at 5.25 (face 2). No other face is hit
/// (no hit lands on an edge). Entering hits are front faces (outward, counter-clockwise
/// normals), exits back faces; the reconstructed points are (0.25, 0.5, 5 − t). Exactly, for
/// every variant: the ray is axis-aligned and the origin and vertices are small dyadic
/// numbers, so every intermediate value (differences, products, `t` and the barycentrics,
/// which are dyadic with few bits here) is representable in `f32` and no operation rounds.
#[test]
fn meshes_readme_worked_example() {
    let ray = Ray::new(Vec3::new(0.25, 0.5, 5.0), Vec3::new(0.0, 0.0, -1.0));
    let cases: [(&str, [(f32, usize); 2]); 3] = [
        ("tetrahedron.obj", [(4.25, 2), (5.25, 4)]),
        ("cube.obj", [(4.0, 12), (6.0, 9)]),
        ("octahedron.obj", [(4.75, 1), (5.25, 2)]),
    ];
    for (name, expect) in cases {
        let mesh = Mesh::load(name);
        for v in ALL {
            let mut hits: Vec<(f32, usize, bool, Vec3)> = (0..mesh.triangles.len())
                .filter_map(|f| {
                    let tri = mesh.tri(f as u32);
                    hit(v, &ray, &tri).map(|h| (h.t, f + 1, h.front_face, h.to_hit(&tri).point))
                })
                .collect();
            hits.sort_by(|a, b| a.0.total_cmp(&b.0));
            assert_eq!(hits.len(), 2, "{name} {}: {hits:?}", v.name());
            for (k, &(t, face)) in expect.iter().enumerate() {
                let (ht, hf, front, p) = hits[k];
                assert_eq!(hf, face, "{name} {}", v.name());
                assert_eq!(ht, t, "{name} {}: t", v.name());
                assert_eq!(front, k == 0, "{name} {}: front face", v.name());
                let want = Vec3::new(0.25, 0.5, 5.0 - t);
                assert_eq!(p, want, "{name} {}: point", v.name());
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Slab test, robustness.md §6.4 B1–B5, B7, B8
// ---------------------------------------------------------------------------------------------

const UNIT: Aabb = Aabb::new(Vec3::ZERO, Vec3::ONE);

fn slab(b: &Aabb, o: Vec3, d: Vec3) -> Option<(f32, f32)> {
    b.intersect_ray(&Ray::new(o, d))
}

/// B1: origin exactly on a slab plane (each axis, each face), direction component ±0 there:
/// hit (closed box), with the same interval for +0 and −0 and for every axis (by symmetry the
/// ray enters at t = 1 and leaves at t ≈ 2 in every case).
/// B2: the same with the origin one ulp outside: miss.
#[test]
fn slab_b1_b2_origin_on_and_next_to_a_face_plane() {
    let mut reference: Option<(f32, f32)> = None;
    for axis in 0..3 {
        let along = (axis + 1) % 3;
        for face in [0.0f32, 1.0] {
            for zero in [0.0f32, -0.0] {
                let mut o = Vec3::splat(0.5);
                o[axis] = face;
                o[along] = -1.0;
                let mut d = Vec3::ZERO;
                d[axis] = zero;
                d[along] = 1.0;
                let r = slab(&UNIT, o, d).unwrap_or_else(|| panic!("B1 axis {axis} {face} {zero}"));
                assert_eq!(r.0, 1.0);
                match reference {
                    None => reference = Some(r),
                    Some(x) => assert_eq!(x, r, "B1 axis {axis} face {face} zero {zero}"),
                }
                // B2: one ulp outside the face.
                let mut out = o;
                out[axis] = if face == 0.0 {
                    face.next_down()
                } else {
                    face.next_up()
                };
                assert_eq!(slab(&UNIT, out, d), None, "B2 axis {axis} {face} {zero}");
                // ... and one ulp inside still hits.
                let mut inside = o;
                inside[axis] = if face == 0.0 {
                    f32::from_bits(1)
                } else {
                    face.next_down()
                };
                assert!(slab(&UNIT, inside, d).is_some());
            }
        }
    }
}

/// B3: a flat box (zero thickness, e.g. an axis-aligned triangle's bounds) hit head-on: hit,
/// with `t_enter = t_exit` = the plane distance (up to the far padding). B4: rays along a box
/// edge and through a corner only: hit.
#[test]
fn slab_b3_b4_flat_box_edges_and_corners() {
    for axis in 0..3 {
        let mut lo = Vec3::ZERO;
        let mut hi = Vec3::ONE;
        lo[axis] = 2.0;
        hi[axis] = 2.0;
        let flat = Aabb::new(lo, hi);
        let mut o = Vec3::splat(0.5);
        o[axis] = 0.0;
        let mut d = Vec3::ZERO;
        d[axis] = 1.0;
        let (t0, t1) = slab(&flat, o, d).expect("B3 flat box");
        assert_eq!(t0, 2.0);
        assert!((2.0..=2.0 * halfray_core::aabb::SLAB_FAR_SCALE).contains(&t1));
        // Flat box parallel to the ray, ray in its plane: hit.
        let mut o2 = Vec3::splat(0.5);
        o2[axis] = 2.0;
        o2[(axis + 1) % 3] = -1.0;
        let mut d2 = Vec3::ZERO;
        d2[(axis + 1) % 3] = 1.0;
        assert!(slab(&flat, o2, d2).is_some(), "B3 in-plane");
    }
    // Along each of the 12 edges of the unit box.
    for axis in 0..3 {
        for (a, b) in [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)] {
            let mut o = Vec3::ZERO;
            o[(axis + 1) % 3] = a;
            o[(axis + 2) % 3] = b;
            o[axis] = -1.0;
            let mut d = Vec3::ZERO;
            d[axis] = 1.0;
            assert!(
                slab(&UNIT, o, d).is_some(),
                "B4 edge axis {axis} ({a}, {b})"
            );
            let mut dm = d;
            dm[(axis + 1) % 3] = -0.0;
            assert_eq!(slab(&UNIT, o, d), slab(&UNIT, o, dm));
        }
    }
    // Through the (1, 1, 1) corner only: x > 1 before, y > 1 after.
    let r = slab(&UNIT, Vec3::new(2.0, 0.0, 1.0), Vec3::new(-1.0, 1.0, 0.0)).expect("B4 corner");
    assert!(r.0 <= 1.0 && r.1 >= 1.0, "{r:?}");
    // The main diagonal through two corners.
    assert!(slab(&UNIT, Vec3::splat(-1.0), Vec3::ONE).is_some());
}

/// B5: direction components of `±1e-30`, `±1e-40` and `±2⁻¹⁴⁹` (subnormal: the reciprocal
/// overflows to ±∞) and `±0`, origin `(x, 0.5, −1)`, direction `(d_x, 0, 1)` on the unit box
/// (the ray is in the z slab for `t ∈ [1, 2]`). The answer is exact for every one: hit iff
/// `x + d_x·t ∈ [0, 1]` for some `t ∈ [1, 2]` (evaluated in `f64`, exact for these values),
/// including a subnormal `d_x` with an origin a subnormal distance outside, which drifts in
/// (those rays are tested by division; by reciprocal they were culled).
#[test]
fn slab_b5_tiny_and_subnormal_direction_components() {
    let xs = [
        -0.5f32,
        0.0f32.next_down(),
        0.0,
        0.5,
        1.0,
        1.0f32.next_up(),
        2.0,
    ];
    for tiny in [
        1.0e-30f32,
        -1.0e-30,
        1.0e-40,
        -1.0e-40,
        f32::from_bits(1),
        -f32::from_bits(1),
        0.0,
        -0.0,
    ] {
        for x in xs {
            // ∃ t ∈ [1, 2]: −x ≤ d·t ≤ 1 − x, with every quantity exact in f64.
            let (d1, d2) = (f64::from(tiny), 2.0 * f64::from(tiny));
            let (lo, hi) = (-f64::from(x), 1.0 - f64::from(x));
            let exact = d1.max(d2) >= lo && d1.min(d2) <= hi;
            // Components whose reciprocal overflows go through division (aabb module
            // docs), so the answer is exact for them too.
            let expect = exact;
            let r = slab(&UNIT, Vec3::new(x, 0.5, -1.0), Vec3::new(tiny, 0.0, 1.0));
            assert_eq!(r.is_some(), expect, "x = {x:e}, d_x = {tiny:e}: {r:?}");
        }
    }
}

/// B7: a box whose entry is exactly at `t_max` is hit (inclusive); with `t_max` one ulp
/// smaller it is not. B8: NaN rays hit no box.
#[test]
fn slab_b7_b8_entry_at_t_max_and_nan_rays() {
    let o = Vec3::new(0.5, 0.5, -2.0);
    let at = |t_max: f32| UNIT.intersect_ray(&Ray::with_interval(o, Vec3::Z, 0.0, t_max));
    assert_eq!(at(2.0).map(|x| x.0), Some(2.0));
    assert_eq!(at(2.0f32.next_down()), None);
    // Exit exactly at t_min: still a (closed) hit of the box's far face.
    let r = UNIT.intersect_ray(&Ray::with_interval(o, Vec3::Z, 3.0, 10.0));
    assert!(r.is_some());
    for bad in [
        Ray::new(Vec3::NAN, Vec3::Z),
        Ray::new(o, Vec3::new(f32::NAN, 0.0, 1.0)),
        Ray::new(o, Vec3::new(0.0, f32::NAN, f32::NAN)),
        Ray::with_interval(o, Vec3::Z, f32::NAN, 10.0),
        Ray::with_interval(o, Vec3::Z, 0.0, f32::NAN),
        Ray::new(Vec3::new(0.5, f32::INFINITY, 0.5), Vec3::Z),
    ] {
        assert_eq!(UNIT.intersect_ray(&bad), None, "{bad:?}");
        assert!(SlabRay::new(&bad).is_none());
    }
}

// ---------------------------------------------------------------------------------------------
// Random rays: watertight agrees with the reference away from edges
// ---------------------------------------------------------------------------------------------

/// Barycentric distance from the triangle's boundary beyond which the f32 watertight variants
/// must agree with the exact answer (hit inside, miss outside). Unitless. For the rays below
/// (origin within 10 triangle sizes, |cos| ≥ 0.1 against the normal) the projected
/// coordinates carry at most ~8·u·R of rounding with `R ≤ 11·size`, against a projected
/// triangle altitude ≥ 0.1·(altitude); relative to the barycentric scale that is ≈ 1e-5 for
/// the well-shaped triangles used (min angle ≥ 15°): `1e-3` leaves ~100× headroom.
const BARY_MARGIN: f64 = 1.0e-3;

/// Exact-enough (f64, on the f32 inputs) barycentrics and `t` of the line–plane crossing.
fn f64_barycentrics(ray: &Ray, tri: &[Vec3; 3]) -> Option<(f64, [f64; 3])> {
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let n = (b - a).cross(c - a);
    let den = n.dot(d);
    if den == 0.0 {
        return None;
    }
    let t = n.dot(a - o) / den;
    let p = o + d * t;
    let area = n.length_squared();
    let w0 = (b - p).cross(c - p).dot(n) / area;
    let w1 = (c - p).cross(a - p).dot(n) / area;
    let w2 = (a - p).cross(b - p).dot(n) / area;
    Some((t, [w0, w1, w2]))
}

#[test]
fn watertight_agrees_with_reference_away_from_edges() {
    let mut rng = Rng::new(2024);
    let mut checked = 0;
    let mut disagree = [0usize; 6];
    let mut t_worst = [0.0f64; 6];
    let mut b_worst = [0.0f64; 6];
    while checked < 50_000 {
        let scale = rng.log_range(1.0e-3, 1.0e3);
        let center = rng.unit_vector() * rng.range(0.0, 100.0) * scale;
        let tri = [0, 1, 2].map(|_| (center + rng.unit_vector() * scale).as_vec3());
        if min_angle_deg(&tri) < 15.0 {
            continue;
        }
        let o = center + rng.unit_vector() * scale * rng.range(1.0, 10.0);
        let aim = center + rng.unit_vector() * scale * 1.2;
        let ray = Ray::new(o.as_vec3(), (aim - o).as_vec3());
        let ng = (tri[1] - tri[0])
            .as_dvec3()
            .cross((tri[2] - tri[0]).as_dvec3());
        let d = ray.direction.as_dvec3();
        let cos = (ng.dot(d) / (ng.length() * d.length())).abs();
        if cos < 0.1 {
            continue;
        }
        let Some((t, b)) = f64_barycentrics(&ray, &tri) else {
            continue;
        };
        let m = b.iter().copied().fold(f64::INFINITY, f64::min);
        if m.abs() <= BARY_MARGIN || t.abs() <= BARY_MARGIN * 1.0 {
            continue;
        }
        let expect_hit = m > 0.0 && t > 0.0;
        checked += 1;
        for (i, v) in ALL.into_iter().enumerate() {
            let h = hit(v, &ray, &tri);
            if h.is_some() != expect_hit {
                disagree[i] += 1;
                assert!(
                    !v.is_watertight(),
                    "{}: expected hit = {expect_hit} (min bary {m:e}): {ray:?} {tri:?}",
                    v.name()
                );
            }
            if let Some(h) = h {
                // Barycentric post-condition of the trait, and t against the f64 solution.
                if v.is_watertight() {
                    let s = f64::from(BARYCENTRIC_SLACK);
                    let (b1, b2) = (f64::from(h.b1), f64::from(h.b2));
                    assert!(b1 >= -s && b2 >= -s && b1 + b2 <= 1.0 + s, "{h:?}");
                    // Against the exact barycentrics, within the watertight test's derived
                    // per-ray error bound (the fuzz oracle's `WatertightBound`, test code of
                    // its own: edge-function rounding over the determinant, plus the final
                    // roundings).
                    let bound = WatertightBound::new(&ray, &tri).expect("inside its domain");
                    let eval = match v {
                        TriangleVariant::WatertightF32 => EdgeEval::F32,
                        _ => EdgeEval::ExactF64,
                    };
                    let (e, err) = (bound.edges(), bound.edge_errors(eval));
                    assert!((0..3).all(|k| e[k].abs() > err[k]), "{ray:?} {tri:?}");
                    for (k, got) in [(1, b1), (2, b2)] {
                        let tol = bound.barycentric_error(eval, k, b[k]);
                        b_worst[i] = b_worst[i].max((got - b[k]).abs() / tol);
                        assert!(
                            (got - b[k]).abs() <= tol,
                            "{}: b{k} = {got} vs {} (bound {tol:e})",
                            v.name(),
                            b[k]
                        );
                    }
                }
                if cos >= 0.5 && expect_hit {
                    let rel = (f64::from(h.t) - t).abs() / t;
                    t_worst[i] = t_worst[i].max(rel);
                    if v.is_watertight() {
                        assert!(
                            rel <= f64::from(T_REL_TOLERANCE_WELL_CONDITIONED),
                            "{}: t = {} vs {t}",
                            v.name(),
                            h.t
                        );
                    }
                }
            }
        }
    }
    for (i, v) in ALL.into_iter().enumerate() {
        eprintln!(
            "AGREEMENT variant={} rays={checked} disagreements={} max_rel_t_err_ulps={:.2} \
             max_bary_err_over_bound={:.3}",
            v.name(),
            disagree[i],
            t_worst[i] / f64::from(f32::EPSILON),
            b_worst[i]
        );
    }
    let _ = Vec2::ZERO;
}
