//! Unit tests of `quadric`.

use super::*;
use crate::hit::spawn_ray;
use crate::test_util::unit_vec;
use crate::tolerance::QUADRIC_ROOT_RESIDUAL_REL;
use std::format;

/// Finite inputs whose centred form overflows `f64` are refused as `NonFinite`, as the
/// documentation says: `x² + 2·10²⁰⁰·x = 0` (centre `−10²⁰⁰`, `k = −10⁴⁰⁰`); at `10¹⁰⁰` the
/// same sphere is built.
#[test]
fn a_centred_form_beyond_the_f64_range_is_refused() {
    assert_eq!(
        Quadric::new(DMat3::IDENTITY, DVec3::new(1.0e200, 0.0, 0.0), 0.0).err(),
        Some(GeometryError::NonFinite)
    );
    assert!(Quadric::new(DMat3::IDENTITY, DVec3::new(1.0e100, 0.0, 0.0), 0.0).is_ok());
}

/// `|f(o + t·d)| / (|∇f|·|t·d| + F)`: compared with `QUADRIC_ROOT_RESIDUAL_REL`.
fn residual_ratio(q: &Quadric, ray: &Ray, t: f64) -> f64 {
    let d = ray.direction.as_dvec3();
    let x = ray.origin.as_dvec3() + d * t;
    let scale = q.gradient(x).length() * (d * t).length() + q.eval_abs(x);
    q.eval(x).abs() / scale
}

/// The worked example of issue 2, in all three constructions.
fn worked_example_quadrics() -> [Quadric; 3] {
    // f = (x−2)²/4 + (y−2)² + z²/4 − 1 = x²/4 + y² + z²/4 − x − 4y + 4.
    let a = DMat3::from_diagonal(DVec3::new(0.25, 1.0, 0.25));
    let b = DVec3::new(-0.5, -2.0, 0.0);
    let c = 4.0;
    let q4 = DMat4::from_cols(
        a.x_axis.extend(b.x),
        a.y_axis.extend(b.y),
        a.z_axis.extend(b.z),
        b.extend(c),
    );
    [
        *Ellipsoid::new(Vec3::new(2.0, 2.0, 0.0), Vec3::new(2.0, 1.0, 2.0))
            .unwrap()
            .quadric(),
        Quadric::new(a, b, c).unwrap(),
        Quadric::from_mat4(q4).unwrap(),
    ]
}

#[test]
fn worked_example_from_issue_2() {
    // Ray o = (0,0,0), d = (1,1,0): (5/4)(t−2)² = 1, t = 2 ± √(4/5).
    let s = (4.0f64 / 5.0).sqrt();
    let ray = Ray::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0));
    for q in worked_example_quadrics() {
        // The general form found the same centre.
        assert_eq!(q.reference_point(), DVec3::new(2.0, 2.0, 0.0));
        let (t0, t1) = q.roots(&ray).unwrap();
        assert!((t0 - (2.0 - s)).abs() <= 4.0 * f64::EPSILON, "{t0}");
        assert!((t1 - (2.0 + s)).abs() <= 4.0 * f64::EPSILON, "{t1}");
        let h = q.intersect(&ray).unwrap();
        assert_eq!(h.t, (2.0 - s) as f32);
        let exact = DVec3::new(2.0 - s, 2.0 - s, 0.0);
        let err = (h.point.as_dvec3() - exact).abs();
        assert!(err.x <= h.point_error.x as f64 && err.y <= h.point_error.y as f64);
        assert_eq!(
            h.point,
            exact.as_vec3(),
            "first hit (2 − √(4/5), 2 − √(4/5), 0)"
        );
        // Normal ∝ gradient ((x−2)/2, 2(y−2), z/2) = −s·(1/2, 2, 0) ∝ (−1, −4, 0).
        let n = Vec3::new(-1.0, -4.0, 0.0) / 17f32.sqrt();
        assert!(
            (h.normal - n).length() <= 2.0 * f32::EPSILON,
            "{:?}",
            h.normal
        );
        assert!(h.front_face);
        // The second hit, from just past the first.
        let exit = q
            .intersect(&Ray::with_interval(
                ray.origin,
                ray.direction,
                1.5,
                f32::INFINITY,
            ))
            .unwrap();
        assert_eq!(exit.t, (2.0 + s) as f32);
        assert_eq!(exit.point, DVec3::new(2.0 + s, 2.0 + s, 0.0).as_vec3());
        assert!((exit.normal + n).length() <= 2.0 * f32::EPSILON);
        assert!(!exit.front_face);
        for t in [t0, t1] {
            assert!(residual_ratio(&q, &ray, t) <= QUADRIC_ROOT_RESIDUAL_REL);
        }
    }
}

#[test]
fn ellipsoid_uv_and_constructor_errors() {
    let e = Ellipsoid::new(Vec3::new(2.0, 2.0, 0.0), Vec3::new(2.0, 1.0, 2.0)).unwrap();
    let h = e
        .intersect(&Ray::new(Vec3::new(2.0, 2.0, 10.0), -Vec3::Z))
        .unwrap();
    assert_eq!(h.t, 8.0);
    assert_eq!(h.normal, Vec3::Z);
    assert_eq!(h.uv.y, 0.0);
    assert_eq!(
        Ellipsoid::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0)),
        Err(GeometryError::Degenerate)
    );
    assert_eq!(
        Ellipsoid::new(Vec3::ZERO, Vec3::new(1.0, f32::NAN, 1.0)),
        Err(GeometryError::NonFinite)
    );
    assert_eq!(
        Quadric::new(DMat3::ZERO, DVec3::ZERO, 1.0),
        Err(GeometryError::Degenerate)
    );
    assert_eq!(
        Quadric::new(DMat3::IDENTITY, DVec3::new(f64::INFINITY, 0.0, 0.0), 1.0),
        Err(GeometryError::NonFinite)
    );
    assert_eq!(
        Quadric::cylinder(Vec3::ZERO, Vec3::ZERO, 1.0),
        Err(GeometryError::Degenerate)
    );
    assert_eq!(
        Quadric::cone(Vec3::ZERO, Vec3::Z, 0.0),
        Err(GeometryError::Degenerate)
    );
}

#[test]
fn misses_and_degenerate_directions() {
    let e = Quadric::ellipsoid(Vec3::new(2.0, 2.0, 0.0), Vec3::new(2.0, 1.0, 2.0)).unwrap();
    // Pointing away, and passing beside.
    assert!(
        e.intersect(&Ray::new(Vec3::ZERO, Vec3::new(-1.0, -1.0, 0.0)))
            .is_none()
    );
    assert!(
        e.roots(&Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::X))
            .is_none()
    );
    // Cylinder: along the axis (qa = qb = 0), outside and inside: no root.
    let cyl = Quadric::cylinder(Vec3::ZERO, Vec3::Z, 1.0).unwrap();
    assert!(
        cyl.roots(&Ray::new(Vec3::new(2.0, 0.0, 0.0), Vec3::Z))
            .is_none()
    );
    assert!(
        cyl.roots(&Ray::new(Vec3::new(0.5, 0.0, 0.0), Vec3::Z))
            .is_none()
    );
    // Invalid rays.
    for b in [f32::NAN, f32::INFINITY] {
        let mut r = Ray::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0));
        r.origin.y = b;
        assert!(e.intersect(&r).is_none());
        let mut r = Ray::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0));
        r.direction.z = b;
        assert!(e.intersect(&r).is_none());
    }
    assert!(e.intersect(&Ray::new(Vec3::ZERO, Vec3::ZERO)).is_none());
    let huge = Ray::new(Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX));
    if let Some(h) = e.intersect(&huge) {
        assert!(huge.contains(h.t) && h.point.is_finite(), "{h:?}");
    }
}

#[test]
fn paraboloid_linear_case() {
    // z = x² + y²: A = diag(1, 1, 0), b = (0, 0, −1/2), c = 0 (A singular: no centre).
    let p = Quadric::new(
        DMat3::from_diagonal(DVec3::new(1.0, 1.0, 0.0)),
        DVec3::new(0.0, 0.0, -0.5),
        0.0,
    )
    .unwrap();
    assert_eq!(p.reference_point(), DVec3::ZERO);
    // Along the axis direction qa = 0: one root, z = 0.25 → t = 9.75.
    let ray = Ray::new(Vec3::new(0.5, 0.0, 10.0), -Vec3::Z);
    assert_eq!(p.roots(&ray), Some((9.75, 9.75)));
    let h = p.intersect(&ray).unwrap();
    assert_eq!(h.point, Vec3::new(0.5, 0.0, 0.25));
    // Gradient (2x, 2y, −1) = (1, 0, −1): outward is below the bowl (f > 0 outside).
    assert!((h.normal - Vec3::new(1.0, 0.0, -1.0).normalize()).length() < 1e-6);
    // Recentred at the vertex: same answers.
    let pr = p.recentered(DVec3::new(0.0, 0.0, 0.0)).unwrap();
    assert_eq!(pr.roots(&ray), Some((9.75, 9.75)));
}

/// Rays from near the world origin aimed at a quadric far away: every root satisfies the
/// residual bound, hits are found, and spawned rays leave without re-hitting nearby.
fn far_quadric_suite(q: &Quadric, target: Vec3, spread: f32, seed: u64) -> (usize, f64) {
    let mut st = seed;
    let mut hits = 0;
    let mut worst = 0.0f64;
    for _ in 0..4000 {
        let o = unit_vec(&mut st) * 10.0;
        let aim = target + unit_vec(&mut st) * spread;
        let ray = Ray::new(o, aim - o);
        let Some((t0, t1)) = q.roots(&ray) else {
            continue;
        };
        for t in [t0, t1] {
            let r = residual_ratio(q, &ray, t);
            worst = worst.max(r);
            assert!(r <= QUADRIC_ROOT_RESIDUAL_REL, "residual {r:e}");
        }
        let Some(h) = q.intersect(&ray) else {
            continue;
        };
        hits += 1;
        // The point is within its bound of the surface: |f(p)| / |∇f| ≤ error along n.
        let x = h.point.as_dvec3();
        let dist = q.eval(x).abs() / q.gradient(x).length();
        let along = h.point_error.as_dvec3().dot(h.normal.abs().as_dvec3());
        assert!(dist <= along * 1.01, "dist {dist} > {along}");
        // Spawned rays, both sides: no hit within a small neighbourhood of the origin
        // (a cylinder or cone can be legitimately re-hit far away).
        let near = 1.0e-3 * spread;
        for w in [h.normal, -h.normal, ray.direction, -ray.direction] {
            let sr = spawn_ray(&h, w);
            if let Some(h2) = q.intersect(&sr) {
                assert!(h2.t * w.length() > near, "self-hit at t = {}", h2.t);
            }
        }
    }
    (hits, worst)
}

#[test]
fn far_cylinder_and_cone() {
    // S9: a cylinder 3e4 away, tilted; a cone 9e3 away.
    let axis_point = Vec3::new(1.0e4, -3.0e4, 0.0);
    let cyl = Quadric::cylinder(axis_point, Vec3::new(0.3, 0.1, 1.0), 2.0).unwrap();
    let (hits, worst_c) = far_quadric_suite(&cyl, axis_point, 2.5, 21);
    assert!(hits > 2000, "{hits}");
    let apex = Vec3::new(-5.0e3, 2.0e3, 7.0e3);
    let axis = Vec3::new(1.0, 1.0, 0.0);
    let cone = Quadric::cone(apex, axis, 0.5).unwrap();
    let target = apex + axis.normalize() * 20.0;
    let (hits, worst_k) = far_quadric_suite(&cone, target, 12.0, 22);
    assert!(hits > 2000, "{hits}");
    // A far ellipsoid given in the general (uncentred) matrix form.
    let c = Vec3::new(3.0e4, 1.0e4, -2.0e4);
    let r = Vec3::new(1.0, 0.5, 2.0);
    let e = Quadric::ellipsoid(c, r).unwrap();
    let a = e.matrix();
    let cd = c.as_dvec3();
    let b = -(a * cd);
    let general = Quadric::new(a, b, cd.dot(a * cd) - 1.0).unwrap();
    let (hits, worst_e) = far_quadric_suite(&general, c, 1.5, 23);
    assert!(hits > 1000, "{hits}");
    std::eprintln!(
        "worst residual ratio: cylinder {worst_c:e}, cone {worst_k:e}, ellipsoid {worst_e:e}"
    );
}

#[test]
fn cone_apex_hit_is_finite() {
    let cone = Quadric::cone(Vec3::ZERO, Vec3::Z, 1.0).unwrap();
    let h = cone
        .intersect(&Ray::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-1.0, -2.0, -3.0),
        ))
        .unwrap();
    assert_eq!(h.t, 1.0);
    assert_eq!(h.point, Vec3::ZERO);
    assert!(h.normal.is_finite() && h.point_error.is_finite());
}

/// The residual bound's domain (`Quadric::roots`, *Domain of the residual bound*: the
/// discriminant's scale `max(q_b², |q_a|·|q_c|) ≥ 10⁻²⁹⁰`) at its end: `f = λ(|x|² − 1/2)`
/// with `λ = 2⁻⁴⁸²` puts that scale at `3.4·10⁻²⁹⁰` for the ray from `(−1, −0.6, −0.2)`
/// along `(1, 0.7, 0.3)`. The roots agree with the `f64` roots of `|o + t·d|² = 1/2` (the
/// `λ`-free polynomial, well conditioned) and satisfy `|f(o + t·d)| ≤ 64·2⁻⁵³·(|q_a|t² +
/// 2|q_b||t| + |q_c| + F(o + t·d))` (`F = λ(|x|² + 1/2)`), the residual evaluated here as
/// `λ·(|x|² − 1/2)` (its own rounding, `4·2⁻⁵³·F`, taken off the bound); likewise at
/// `λ = 1`. Just below the domain (`λ = 2⁻⁵⁴⁰`: the scale is subnormal) only `t0 ≤ t1` is
/// promised.
#[test]
fn residual_bound_holds_down_to_the_end_of_its_domain() {
    /// The end of the residual bound's domain (`Quadric::roots`' docs): the smallest
    /// discriminant scale `max(q_b², |q_a|·|q_c|)` it covers, in the ray polynomial's squared
    /// units (here unitless: `f` and `t` are).
    const DOMAIN_END: f64 = 1e-290;
    /// How far above [`DOMAIN_END`] the scaled case may sit and still test the domain's end
    /// (a factor, unitless): `λ = 2⁻⁴⁸²` puts it at `3.4·DOMAIN_END`; asserting it below
    /// `4·DOMAIN_END` proves the case sits at the end, not comfortably inside the domain.
    const NEAR_END_FACTOR: f64 = 4.0;
    /// Relative agreement of `roots` with the stable `f64` roots of the `λ`-free polynomial
    /// (unitless). Both are `f64` roots of the same well-conditioned quadratic (roots `0.38`
    /// and `1.49`, discriminant `b² − ac = 0.77` against `b² = 2.2`: no cancellation), each
    /// within a few `2⁻⁵³` of the exact roots, and `λ` a power of two (scaling is exact):
    /// `10⁻¹²` (≈ 9 000 ulps) leaves ample room and still catches any real loss at the
    /// small scale (a subnormal coefficient or a wrong branch is off by far more).
    const ROOT_AGREEMENT_REL: f64 = 1e-12;
    let u = crate::float::F64_UNIT_ROUNDOFF;
    let (o, d) = (Vec3::new(-1.0, -0.6, -0.2), Vec3::new(1.0, 0.7, 0.3));
    let ray = Ray::new(o, d);
    let (od, dd) = (o.as_dvec3(), d.as_dvec3());
    // The λ-free polynomial a·t² + 2b·t + c, its roots by the stable formula.
    let (a, b, c) = (dd.dot(dd), od.dot(dd), od.dot(od) - 0.5);
    let q = -(b + (b * b - a * c).sqrt().copysign(b));
    let want = ((c / q).min(q / a), (c / q).max(q / a));
    for lambda in [1.0, 2f64.powi(-482)] {
        let quad = Quadric::new(
            DMat3::from_diagonal(DVec3::splat(lambda)),
            DVec3::ZERO,
            -0.5 * lambda,
        )
        .unwrap();
        let (qa, qb, qc) = (a * lambda, b * lambda, c * lambda);
        let scale = (qb * qb).max((qa * qc).abs());
        assert!(
            lambda == 1.0 || (DOMAIN_END..NEAR_END_FACTOR * DOMAIN_END).contains(&scale),
            "{scale:e}"
        );
        let (t0, t1) = quad.roots(&ray).expect("the ray crosses the sphere twice");
        for (t, w) in [(t0, want.0), (t1, want.1)] {
            assert!(
                (t - w).abs() <= ROOT_AGREEMENT_REL * w.abs(),
                "λ = {lambda:e}: {t} vs {w}"
            );
            let x = od + dd * t;
            let big_f = lambda * (x.length_squared() + 0.5);
            let resid = (lambda * (x.length_squared() - 0.5)).abs();
            let bound = 64.0 * u * (qa.abs() * t * t + 2.0 * qb.abs() * t.abs() + qc.abs() + big_f)
                - 4.0 * u * big_f;
            assert!(
                resid <= bound,
                "λ = {lambda:e}: residual {resid:e} > {bound:e}"
            );
        }
    }
    let tiny = 2f64.powi(-540);
    let quad = Quadric::new(
        DMat3::from_diagonal(DVec3::splat(tiny)),
        DVec3::ZERO,
        -0.5 * tiny,
    )
    .unwrap();
    if let Some((t0, t1)) = quad.roots(&ray) {
        assert!(t0 <= t1, "({t0}, {t1})");
    }
}

/// The reviewer's case: a ray along the slanted axis `(1, 1, 0)`, inside the cylinder. The
/// matrix `I − ââᵀ` of the rounded unit axis gave it two roots near `±4.1·10⁷` (a hit, and
/// an entry and exit for CSG); the axial form gives none, and the line is inside throughout.
#[test]
fn a_ray_along_a_slanted_cylinder_axis_has_no_root() {
    let cyl = Quadric::cylinder(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), 1.0).unwrap();
    let ray = Ray::new(Vec3::new(0.0, 0.0, 0.5), Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(cyl.roots(&ray), None);
    assert!(cyl.intersect(&ray).is_none());
    assert!(crate::shape::Shape::line_crossings(&cyl, &ray) == [None, None]);
    assert!(crate::shape::Shape::line_starts_inside(&cyl, &ray));
}

/// A random integer vector in `[−n, n]³` (exact in `f32`), from [`crate::test_util::lcg`].
fn int_vec(st: &mut u64, n: f32) -> Vec3 {
    crate::test_util::grid_point(st, n)
}

/// Rays along random `f32` axes (any components, scaled by powers of two) of random
/// cylinders: `d = λ·w` with `λ ∈ {1, −1, 2, 1/4}` (exact, so `d` is exactly parallel to the
/// axis as given) from an origin half a radius or three radii off the axis. The contract
/// (module documentation, item 3 and *axial form*): `qa = qb = 0`, no root, no hit, no
/// crossing, and the line is inside exactly when its origin is. Oracle: the construction
/// (the origin's offset from the axis, 0.5 r or 3 r, far from r against the `f32` rounding
/// of `p + offset`).
#[test]
fn rays_along_random_cylinder_axes_never_cross() {
    use crate::shape::Shape;
    use crate::test_util::lcg;
    let mut st = 7u64;
    let mut slanted = 0;
    for i in 0..20_000 {
        let scale = [1.0f32, 1.0e-3, 1.0e3, 1.0e-20, 1.0e20][i % 5];
        let w = Vec3::new(lcg(&mut st) - 0.5, lcg(&mut st) - 0.5, lcg(&mut st) - 0.5) * scale;
        if w.abs().max_element() == 0.0 {
            continue;
        }
        if w.to_array().iter().filter(|&&c| c != 0.0).count() >= 2 {
            slanted += 1;
        }
        let p = Vec3::new(lcg(&mut st) - 0.5, lcg(&mut st) - 0.5, lcg(&mut st) - 0.5) * 10.0;
        let r = 0.5 + lcg(&mut st) * 4.0;
        let cyl = Quadric::cylinder(p, w, r).unwrap();
        let inside = i % 2 == 0;
        let off = if inside { 0.5 * r } else { 3.0 * r };
        // (In f64: |w|² overflows f32 at the largest scale.)
        let perp = w.as_dvec3().normalize().any_orthonormal_vector().as_vec3();
        let o = p + perp * off;
        for lambda in [1.0f32, -1.0, 2.0, 0.25] {
            let ray = Ray::new(o, w * lambda);
            let ctx = || format!("axis {w:?}, point {p:?}, r {r}, ray {ray:?}");
            assert_eq!(cyl.roots(&ray), None, "{}", ctx());
            assert!(cyl.intersect(&ray).is_none(), "{}", ctx());
            assert!(cyl.line_crossings(&ray) == [None, None], "{}", ctx());
            assert_eq!(cyl.line_starts_inside(&ray), inside, "{}", ctx());
        }
    }
    assert!(slanted > 15_000, "{slanted}");
}

/// How far a root of a near-axis ray may lie from the exact one, relative to the sum of the
/// exact roots' magnitudes (unitless). In [`near_axis_rays_match_the_exact_roots`] every
/// input is a small integer, so `d × w` and `f₀ × w` are exact and each coefficient carries
/// one or two roundings (`u = 2⁻⁵³`); the judged discriminants are at least `S/1024`
/// (`S = q_b² + |q_a q_c|`), so its rounding (tens of `u·S`, from the shifted origin's
/// evaluation) moves `√Δ`, and each root, by at most about `2¹⁴·u` of the roots' scale.
/// `2⁻³⁶` (`2¹⁷·u`, `1.5·10⁻¹¹`) leaves a factor 8; the matrix form was off by `3·10⁻³`
/// at `10⁻⁷` rad.
const NEAR_AXIS_ROOT_REL: f64 = 1.0 / 68_719_476_736.0;

/// Discriminants judged by [`near_axis_rays_match_the_exact_roots`]: `|Δ| ≥ S/1024`
/// (unitless fraction of `S`), far beyond the code's rounding of `Δ` (tens of `2⁻⁵³·S`).
const NEAR_AXIS_DISC_FRACTION: f64 = 1.0 / 1024.0;

/// Rays `10⁻¹` to `3·10⁻⁷` rad off random slanted integer axes `w` of cylinders, built so
/// that the exact answer is known: `d = m·w + q` with `q = w × k ⊥ w` and `m = 2^j`
/// (`j ∈ [4, 20]`; every component below `2²⁴`, so exact in `f32`), origin
/// `o = p + s·q₂ + h·w` with `q₂ = w × k₂`. The part of `o + t·d − p` across the axis is
/// `s·q₂ + t·q`, so the exact ray polynomial is `|q|²t² + 2s(q₂·q)t + s²|q₂|² − r²`, with
/// integer coefficients (exact in `f64`): its sign of `Δ` decides existence exactly, and its
/// stable `f64` roots are within a few `2⁻⁵³` of the exact ones. Oracle: that construction;
/// tolerance [`NEAR_AXIS_ROOT_REL`]. Also: both crossings (the line is not parallel to the
/// axis, so it starts outside).
#[test]
fn near_axis_rays_match_the_exact_roots() {
    use crate::shape::Shape;
    use crate::test_util::lcg;
    let mut st = 11u64;
    let (mut judged, mut tiny_angle) = (0, 0);
    for _ in 0..20_000 {
        let w = int_vec(&mut st, 8.0);
        if w.to_array().iter().filter(|&&c| c != 0.0).count() < 2 {
            continue;
        }
        let (q, q2) = (
            w.cross(int_vec(&mut st, 4.0)),
            w.cross(int_vec(&mut st, 4.0)),
        );
        if q == Vec3::ZERO {
            continue;
        }
        let m = (1u32 << (4 + (lcg(&mut st) * 17.0) as u32)) as f32;
        let s = (lcg(&mut st) * 5.0).floor() - 2.0;
        let h = (lcg(&mut st) * 41.0).floor() - 20.0;
        let p = int_vec(&mut st, 50.0);
        let r = 1.0 + (lcg(&mut st) * 200.0).floor();
        let d = w * m + q;
        let o = p + q2 * s + w * h;
        assert!(d.abs().max_element() < 16_777_216.0);
        let (qd, q2d, rd) = (q.as_dvec3(), q2.as_dvec3(), r as f64);
        let (a, b, c) = (
            qd.length_squared(),
            s as f64 * q2d.dot(qd),
            (s as f64).powi(2) * q2d.length_squared() - rd * rd,
        );
        let disc = b * b - a * c;
        let scale = b * b + (a * c).abs();
        let cyl = Quadric::cylinder(p, w, r).unwrap();
        let ray = Ray::new(o, d);
        let got = cyl.roots(&ray);
        let ctx = || format!("axis {w:?}, point {p:?}, r {r}, ray {ray:?}: {got:?}");
        if disc.abs() < NEAR_AXIS_DISC_FRACTION * scale {
            continue;
        }
        judged += 1;
        if q.length() * 1.0e5 < d.length() {
            tiny_angle += 1;
        }
        if disc < 0.0 {
            assert_eq!(got, None, "{}", ctx());
            continue;
        }
        let qq = -(b + disc.sqrt().copysign(b));
        let (x, y) = (c / qq, qq / a);
        let want = (x.min(y), x.max(y));
        let (t0, t1) = got.unwrap_or_else(|| panic!("no roots: {}", ctx()));
        let tol = NEAR_AXIS_ROOT_REL * (want.0.abs() + want.1.abs());
        assert!(
            (t0 - want.0).abs() <= tol && (t1 - want.1).abs() <= tol,
            "exact {want:?}: {}",
            ctx()
        );
        assert!(!cyl.line_starts_inside(&ray), "{}", ctx());
        let [c0, c1] = cyl.line_crossings(&ray);
        let (c0, c1) = (c0.unwrap(), c1.unwrap());
        // Each crossing's t is its root rounded to f32.
        for (h, t) in [(c0, want.0), (c1, want.1)] {
            assert!(
                (h.t as f64 - t).abs() <= tol + f64::from(crate::float::gamma(1)) * t.abs(),
                "crossing {} against {t}: {}",
                h.t,
                ctx()
            );
        }
    }
    assert!(judged > 5_000 && tiny_angle > 500, "{judged} {tiny_angle}");
}

/// Rays along a generator of a 45° cone (`τ = 1`) with a slanted integer axis `w` and an
/// integer `q ⊥ w` with `|q| = |w|`, so that `d = m·(w ± q)` is a generator exactly: `f` is
/// linear along the line, whose one crossing is reported twice (module documentation,
/// item 3), or it has none when the slope is zero too. Exact answer: with `f₀ = o − apex`
/// (integers), `f(o + t·d) = 2B·t + C` where `B = m(±f₀·q − f₀·w)` and
/// `C·|w|² = |f₀|²|w|² − 2(f₀·w)²`, so `t = −C/(2B)` is a quotient of exact integers, one
/// rounding in `f64`. Tolerance: [`NEAR_AXIS_ROOT_REL`] of `|t|` (the code's `q_b` and `q_c`
/// carry a rounding or two each here). The matrix form gave `q_a ≈ 10⁻¹⁶` and a second root
/// near `10¹⁶`.
#[test]
fn rays_along_a_cone_generator_have_one_crossing() {
    use crate::test_util::lcg;
    let pairs = [
        (Vec3::new(1.0, 2.0, 2.0), Vec3::new(2.0, 1.0, -2.0)),
        (Vec3::new(2.0, 3.0, 6.0), Vec3::new(3.0, -6.0, 2.0)),
        (Vec3::new(1.0, 4.0, 8.0), Vec3::new(8.0, -4.0, 1.0)),
        (Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, -1.0, 0.0)),
    ];
    let mut st = 5u64;
    let mut linear = 0;
    for i in 0..4_000 {
        let (w, q) = pairs[i % pairs.len()];
        assert!(w.dot(q) == 0.0 && w.length_squared() == q.length_squared());
        let sign = if lcg(&mut st) < 0.5 { 1.0 } else { -1.0 };
        let m = (1u32 << (lcg(&mut st) * 8.0) as u32) as f32;
        let apex = int_vec(&mut st, 50.0);
        let f0 = int_vec(&mut st, 30.0);
        let cone = Quadric::cone(apex, w, 1.0).unwrap();
        let ray = Ray::new(apex + f0, (w + q * sign) * m);
        let (f0d, wd, qd) = (f0.as_dvec3(), w.as_dvec3(), q.as_dvec3());
        let b = m as f64 * (sign as f64 * f0d.dot(qd) - f0d.dot(wd));
        let cw = f0d.length_squared() * wd.length_squared() - 2.0 * f0d.dot(wd).powi(2);
        let got = cone.roots(&ray);
        let ctx = || format!("axis {w:?}, apex {apex:?}, ray {ray:?}: {got:?}");
        if b == 0.0 {
            assert_eq!(got, None, "{}", ctx());
            continue;
        }
        linear += 1;
        let t = -cw / (2.0 * b * wd.length_squared());
        let (t0, t1) = got.unwrap_or_else(|| panic!("no root: {}", ctx()));
        assert_eq!(t0, t1, "{}", ctx());
        assert!(
            (t0 - t).abs() <= NEAR_AXIS_ROOT_REL * t.abs(),
            "exact {t}: {}",
            ctx()
        );
    }
    assert!(linear > 3_000, "{linear}");
}
