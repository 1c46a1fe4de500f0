//! The `ray_sphere` target: the stable quadratic against an `f64` evaluation of the same
//! `f32` inputs, and against the textbook (naive) form where both are well conditioned.
//!
//! Layout: `flags: u8` (bit 0: quantized centre/radius/origin ([`Input::q`]), else raw
//! `f32`; bit 1: interval `(0, ∞]`), `center`, `radius`, `origin`, `direction`, `t_min`,
//! `t_max`. Missing bytes read as zero.

use super::*;
use super::{Enc, Input, fmt_ray};
use glam::Vec3;
use halfray_core::float::F32_UNIT_ROUNDOFF;
use halfray_core::ray::Ray;
use halfray_core::sphere::Sphere;

/// Multiple of `u = 2⁻²⁴` in the residual and `t` bounds below. The first-order analyses
/// (module docs of `halfray_core::sphere`) give constants under 20; 64 leaves room for the
/// second-order terms without hiding a real error, which is orders of magnitude larger.
pub const K: f64 = 64.0;

/// Inputs whose magnitudes (`|o − C|`, `r`, `|t·d|`) lie outside `[DOMAIN_MIN, DOMAIN_MAX]`
/// are only checked for totality: outside it `f32` squares under- or overflow and the
/// relative bounds do not apply (the intersector then answers `None`, documented).
pub const DOMAIN_MIN: f64 = 1e-15;
/// See [`DOMAIN_MIN`].
pub const DOMAIN_MAX: f64 = 1e15;

/// Largest `|t|` checked against the reference: well inside `f32` (a root that overflows
/// `f32` gives no hit, documented).
pub const MAX_T: f64 = 1e30;

/// Smallest `|t|` checked against the reference: a root near the `f32` subnormal range
/// rounds to a `t` from which the hit point cannot be rebuilt.
pub const MIN_T: f64 = 1e-30;

/// Decodes a `ray_sphere` input.
pub fn decode(data: &[u8]) -> (Vec3, f32, Ray) {
    let mut i = Input::new(data);
    let fl = i.u8();
    let q = fl & 1 != 0;
    let center = if q { i.qvec3() } else { i.vec3() };
    let radius = if q { i.q() } else { i.f32() };
    let origin = if q { i.qvec3() } else { i.vec3() };
    let direction = i.vec3();
    let (t_min, t_max) = if fl & 2 != 0 {
        (0.0, f32::INFINITY)
    } else {
        (i.f32(), i.f32())
    };
    (
        center,
        radius,
        Ray::with_interval(origin, direction, t_min, t_max),
    )
}

/// Encodes a raw (`f32`) `ray_sphere` input with the default interval.
pub fn encode(center: Vec3, radius: f32, o: Vec3, d: Vec3) -> Vec<u8> {
    Enc::new()
        .u8(2)
        .vec3(center)
        .f32(radius)
        .vec3(o)
        .vec3(d)
        .done()
}

/// Fuzz target `ray_sphere`.
pub fn ray_sphere(data: &[u8]) {
    let (c, r, ray) = decode(data);
    check(c, r, &ray);
}

/// The properties:
/// 1. `Sphere::new` is `Ok` exactly for a finite centre and a finite radius `> 0`.
/// 2. Every root from `roots()` satisfies the implicit equation: with
///    `F(t) = |o + t·d − C|² − r²` in `f64`, `|F(t)| ≤ K·u·(|o − C|² + r² + (t·|d|)²)`.
/// 3. A hit has `t` in `(t_min, t_max]`, a unit normal along `point − C`, and a point within
///    its own `point_error` of the sphere.
/// 4. Against the `f64` roots of the same inputs: where the ray clearly crosses
///    (`|l| < r − margin`) and a root is clearly inside (or both clearly outside) the
///    interval, the hit (or miss) agrees and `t` is within the bound; a ray that clearly
///    misses (`|l| > r + margin`) gives no hit.
/// 5. Where both forms are well conditioned (`|l| ≤ r/2`, `|o − C| ≤ 10·r`,
///    `|d|`, `|o − C| + r` and their product in `[1e-15, 1e15]`), the naive roots agree
///    with the stable ones.
pub fn check(c: Vec3, r: f32, ray: &Ray) {
    let ctx = || {
        format!(
            "sphere C = {c:?} ({:x?}), r = {r:e} ({:#x})\n{}",
            c.to_array().map(f32::to_bits),
            r.to_bits(),
            fmt_ray(ray)
        )
    };
    let s = match Sphere::new(c, r) {
        Ok(s) => {
            assert!(
                c.is_finite() && r.is_finite() && r > 0.0,
                "accepted\n{}",
                ctx()
            );
            s
        }
        Err(_) => {
            reached();
            assert!(
                !(c.is_finite() && r.is_finite() && r > 0.0),
                "rejected a valid sphere\n{}",
                ctx()
            );
            return;
        }
    };
    let roots = s.roots(ray);
    let hit = s.intersect(ray);
    let naive = s.roots_naive(ray);
    // The naive form has no error bound (documented), but its contract on the interval holds:
    // a hit is at the nearer of its own roots that lies in the interval (it may still give
    // none where the hit point cannot be built).
    let naive_hit = s.intersect_naive(ray);
    if let Some(h) = naive_hit {
        let (a, b) = naive.expect("a naive hit has naive roots");
        let want = if ray.contains(a) { a } else { b };
        assert_eq!(h.t, want, "naive hit vs its roots\n{}", ctx());
        assert!(
            ray.contains(h.t),
            "naive hit t = {:e} outside the interval\n{}",
            h.t,
            ctx()
        );
    }
    if !ray.is_valid() {
        reached();
        assert!(
            roots.is_none() && hit.is_none() && naive.is_none(),
            "{}",
            ctx()
        );
        return;
    }
    let u = f64::from(F32_UNIT_ROUNDOFF);
    let (o, d, cc, rr) = (
        ray.origin.as_dvec3(),
        ray.direction.as_dvec3(),
        c.as_dvec3(),
        f64::from(r),
    );
    let f = o - cc;
    let (fl, dl) = (f.length(), d.length());
    let in_domain = |x: f64| x == 0.0 || (DOMAIN_MIN..=DOMAIN_MAX).contains(&x);
    let domain = in_domain(fl) && in_domain(rr) && fl + rr >= DOMAIN_MIN;
    let resid = |t: f64| (f + d * t).length_squared() - rr * rr;
    // 2. Residuals.
    if let Some((t0, t1)) = roots {
        assert!(t0 <= t1, "roots out of order\n{}", ctx());
        for t in [f64::from(t0), f64::from(t1)] {
            if domain && in_domain(t.abs() * dl) {
                reached();
                // Plus the f32 rounding of t itself (relative u, absolute 2⁻¹⁴⁹ below the
                // normal range) times |F'| ≤ 2|d|·(|o − C| + r + |t·d|) between the
                // computed and the exact root.
                let dt = u * t.abs() + f64::from(f32::from_bits(1));
                let bound = K * u * (fl * fl + rr * rr + (t * dl).powi(2))
                    + 2.0 * dl * (fl + rr + t.abs() * dl) * dt;
                assert!(
                    resid(t).abs() <= bound,
                    "root t = {t:e} has residual {:e} > {bound:e}\n{}",
                    resid(t),
                    ctx()
                );
            }
        }
    }
    // 3. Hit contract.
    if let Some(h) = hit {
        super::check_hit_basics(ray, &h, &ctx);
        let n = h.normal.as_dvec3();
        let p = h.point.as_dvec3();
        if domain && p.is_finite() {
            reached();
            let dist = ((p - cc).length() - rr).abs();
            let e = h.point_error.as_dvec3().length();
            assert!(
                dist <= e + 1e-300,
                "hit point {:?} is {dist:e} from the sphere, bound {e:e}\n{}",
                h.point,
                ctx()
            );
            // The stored point is rounded to f32 near C: its direction from C is only
            // meaningful when that rounding is small against r.
            let radial = (p - cc) / (p - cc).length();
            assert!(
                e > 1e-3 * rr || radial.dot(n) > 0.999,
                "normal {n:?} not along point − C\n{}",
                ctx()
            );
        }
    }
    if !domain || dl == 0.0 {
        return;
    }
    // 4. Against the f64 roots.
    let a = d.dot(d);
    let b = f.dot(d);
    let l = f - d * (b / a);
    let ll = l.length();
    // The tangency band, from the error bound: the intersector's `|l|` (the closest approach,
    // computed from `f = o − C` and the projection `d·(f·d)/(d·d)`, each rounded relative to
    // `|o − C|`) and its comparison with `r` carry at most a few `u·(|o − C| + r)`; `K` of them
    // leaves the constant's room (see [`K`]), nothing more.
    let margin = K * u * (fl + rr);
    if ll > rr + margin {
        reached();
        assert!(
            hit.is_none(),
            "clear miss (|l| = {ll:e}) reported as a hit\n{}",
            ctx()
        );
        return;
    }
    if ll >= rr - margin {
        return; // near-tangent: either answer is right
    }
    let cos = (rr * rr - ll * ll).sqrt() / rr;
    let disc = a * (rr - ll) * (rr + ll);
    let qq = -(b + disc.sqrt().copysign(b));
    let cq = f.dot(f) - rr * rr;
    let (x, y) = (cq / qq, qq / a);
    let (r0, r1) = if x <= y { (x, y) } else { (y, x) };
    // The last term: f32 rounding of a subnormal t.
    let tol = |t: f64| {
        K * u * ((fl * fl + rr * rr) / qq.abs() + (fl + rr) / (dl * cos) + t.abs())
            + 4.0 * f64::from(f32::from_bits(1))
    };
    // Both roots and their distances in range (a root beyond f32::MAX is no hit, documented).
    let (lo, hi) = (r0.abs().min(r1.abs()), r0.abs().max(r1.abs()));
    if !(in_domain(lo * dl) && in_domain(hi * dl)) || hi > MAX_T || lo < MIN_T {
        return;
    }
    let (t_min, t_max) = (f64::from(ray.t_min), f64::from(ray.t_max));
    let status = |t: f64| {
        let e = tol(t);
        if t > t_min + e && t < t_max - e {
            Some(true)
        } else if t < t_min - e || t > t_max + e {
            Some(false)
        } else {
            None
        }
    };
    let expect = match (status(r0), status(r1)) {
        (Some(true), _) => Some(Some(r0)),
        (Some(false), Some(true)) if r1 - r0 > 2.0 * (tol(r0) + tol(r1)) => Some(Some(r1)),
        (Some(false), Some(false)) => Some(None),
        _ => None,
    };
    if expect.is_some() {
        reached();
    }
    match expect {
        Some(Some(t_ref)) => {
            let Some(h) = hit else {
                panic!(
                    "missed: the f64 root {t_ref:e} is clearly inside the interval\n{}",
                    ctx()
                );
            };
            let t = f64::from(h.t);
            assert!(
                (t - t_ref).abs() <= tol(t_ref),
                "t = {t:e}, f64 reference {t_ref:e}, bound {:e}\n{}",
                tol(t_ref),
                ctx()
            );
        }
        Some(None) => assert!(
            hit.is_none(),
            "hit at {:?} although both f64 roots ({r0:e}, {r1:e}) are clearly outside \
             the interval\n{}",
            hit.map(|h| h.t),
            ctx()
        ),
        None => {}
    }
    // 5. Naive against stable where both are well conditioned.
    // The naive form has no scaling: a = d·d, c and b², 4ac must stay normal f32 numbers.
    let naive_range = (1e-15..=1e15).contains(&dl)
        && (1e-15..=1e15).contains(&(fl + rr))
        && (1e-15..=1e15).contains(&(dl * (fl + rr)));
    if ll <= 0.5 * rr && fl <= 10.0 * rr && naive_range {
        let (Some((s0, s1)), Some((n0, n1))) = (roots, naive) else {
            panic!(
                "well-conditioned crossing: stable {roots:?}, naive {naive:?}\n{}",
                ctx()
            );
        };
        let tol = (fl + rr) / dl / 512.0;
        let close = |p: f32, q: f32| (f64::from(p) - f64::from(q)).abs() <= tol;
        assert!(
            close(s0, n0) && close(s1, n1),
            "stable ({s0:e}, {s1:e}) and naive ({n0:e}, {n1:e}) disagree beyond {tol:e}\n{}",
            ctx()
        );
    }
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let t = |name: &str, b: Vec<u8>| ("ray_sphere", format!("seed-{name}"), b);
    let c = Vec3::new(1.0, 2.0, 3.0);
    let x = Vec3::X;
    s.push(t("through-centre", sphere::encode(c, 1.0, c - 5.0 * x, x)));
    s.push(t(
        "tangent",
        sphere::encode(c, 1.0, c + Vec3::new(-5.0, 1.0, 0.0), x),
    ));
    s.push(t(
        "inside",
        sphere::encode(c, 1.0, c, Vec3::new(0.3, -0.2, 0.9)),
    ));
    s.push(t("on-surface-inward", sphere::encode(c, 1.0, c + x, -x)));
    s.push(t("on-surface-outward", sphere::encode(c, 1.0, c + x, x)));
    // Small far spheres (where the textbook discriminant cancels).
    let far = Vec3::new(1e4, 0.0, 0.0);
    s.push(t(
        "far-small",
        sphere::encode(far, 1.0, Vec3::ZERO, far + Vec3::new(0.0, 0.7, 0.0)),
    ));
    let far = Vec3::new(3e6, -2e6, 1e6);
    s.push(t("very-far", sphere::encode(far, 0.5, Vec3::ZERO, far)));
    s.push(t(
        "tiny-direction",
        sphere::encode(c, 1.0, c - 5.0 * x, x * 1e-30),
    ));
    s.push(t(
        "huge-direction",
        sphere::encode(c, 1.0, c - 5.0 * x, x * 1e30),
    ));
    s.push(t("zero-radius", sphere::encode(c, 0.0, c - 5.0 * x, x)));
    s.push(t("nan-radius", sphere::encode(c, f32::NAN, c - 5.0 * x, x)));
    s.push(t(
        "inf-origin",
        sphere::encode(c, 1.0, Vec3::splat(f32::INFINITY), -x),
    ));
    s.push(t(
        "subnormal-radius",
        sphere::encode(Vec3::ZERO, 1e-40, -x, x),
    ));
}
