//! The `ray_quadric` target: general quadrics (matrix form), ellipsoids, cylinders and
//! cones from fuzz bytes; roots against the implicit equation, hits against their own
//! error bound.
//!
//! Layout: `flags: u8` (bits 0–1: 0 general, 1 ellipsoid, 2 cylinder, 3 cone; bit 2:
//! quantized parameters; bit 3: interval `(0, ∞]`), then the ray (`origin`, `direction`,
//! `t_min`, `t_max` unless bit 3), then the parameters: general `A` (6 upper-triangle
//! entries `xx xy xz yy yz zz`), `b` (3), `c`; ellipsoid centre and radii; cylinder axis
//! point, axis direction, radius; cone apex, axis, tan of the half angle.

use super::*;
use super::{Enc, Input, fmt_ray};
use glam::{DMat3, DVec3, Vec3};
use halfray_core::float::F64_UNIT_ROUNDOFF;
use halfray_core::quadric::{Ellipsoid, Quadric};
use halfray_core::ray::Ray;

/// Below this the discriminant's terms are close to the `f64` subnormal range (`2.2e-308`)
/// and round absolutely; residuals are not checked there.
pub const F64_NEAR_UNDERFLOW: f64 = 1e-290;

/// Multiple of the `f64` unit roundoff in the residual bound. The roots come from the
/// stable formulation in `f64` (module docs of `halfray_core::quadric`), whose first-order
/// residual constant is below 20.
pub const K: f64 = 64.0;

/// Decodes a `ray_quadric` input: the surface (or the constructor's error) and the ray.
pub fn decode(data: &[u8]) -> (Result<Quadric, halfray_core::error::GeometryError>, Ray) {
    let mut i = Input::new(data);
    let fl = i.u8();
    let q = fl & 4 != 0;
    let origin = if q { i.qvec3() } else { i.vec3() };
    let direction = i.vec3();
    let (t_min, t_max) = if fl & 8 != 0 {
        (0.0, f32::INFINITY)
    } else {
        (i.f32(), i.f32())
    };
    let ray = Ray::with_interval(origin, direction, t_min, t_max);
    let mut s = || if q { i.q() } else { i.f32() };
    let mut v = || Vec3::new(s(), s(), s());
    let surface = match fl & 3 {
        0 => {
            let e: [f64; 10] = core::array::from_fn(|_| f64::from(s()));
            let a = DMat3::from_cols_array(&[e[0], e[1], e[2], e[1], e[3], e[4], e[2], e[4], e[5]]);
            Quadric::new(a, DVec3::new(e[6], e[7], e[8]), e[9])
        }
        1 => {
            let (c, r) = (v(), v());
            Ellipsoid::new(c, r).map(|e| *e.quadric())
        }
        2 => {
            let (p, a) = (v(), v());
            Quadric::cylinder(p, a, s())
        }
        _ => {
            let (p, a) = (v(), v());
            Quadric::cone(p, a, s())
        }
    };
    (surface, ray)
}

/// Encodes a raw general-quadric input with the default interval.
pub fn encode_general(o: Vec3, d: Vec3, e: [f32; 10]) -> Vec<u8> {
    let mut enc = Enc::new().u8(8).vec3(o).vec3(d);
    for x in e {
        enc = enc.f32(x);
    }
    enc.done()
}

/// Encodes a raw ellipsoid (`kind` 1), cylinder (2) or cone (3) input, default interval.
pub fn encode_shape(kind: u8, o: Vec3, d: Vec3, p: Vec3, q: Vec3, s: f32) -> Vec<u8> {
    let enc = Enc::new().u8(8 | kind).vec3(o).vec3(d).vec3(p).vec3(q);
    if kind == 1 {
        enc.done()
    } else {
        enc.f32(s).done()
    }
}

/// Fuzz target `ray_quadric`.
pub fn ray_quadric(data: &[u8]) {
    let (surface, ray) = decode(data);
    if let Ok(q) = surface {
        check(&q, &ray);
    }
}

/// `(|f|(x), ‖A‖)`: `f` evaluated with absolute values (the scale of its rounding error).
fn scale(q: &Quadric, x: DVec3) -> f64 {
    q.eval_abs(x)
}

/// The properties:
/// 1. Every root from `roots()` satisfies `|f(o + t·d)| ≤ K·u·(|qa|·t² + 2|qb|·|t| + |qc|)`
///    where the `|q·|` are the ray polynomial's coefficients with absolute values
///    (the scale of their rounding error), evaluated in `f64`.
/// 2. A hit has `t` in `(t_min, t_max]`, a unit normal, and a point within its
///    `point_error` of the surface: `|f(p)| ≤ |∇f(p)|·e + 3‖A‖·e² + γ·|f|(p)`, `e = |point_error|`.
/// 3. A ray whose `f64` roots are both clearly outside the interval gets no hit; one whose
///    near root is clearly inside gets a hit at that root.
pub fn check(q: &Quadric, ray: &Ray) {
    let ctx = || format!("quadric {q:?}\n{}", fmt_ray(ray));
    let roots = q.roots(ray);
    let hit = q.intersect(ray);
    if !ray.is_valid() {
        assert!(roots.is_none() && hit.is_none(), "{}", ctx());
        return;
    }
    let u = F64_UNIT_ROUNDOFF;
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let am = q.matrix();
    let aa = DMat3::from_cols(am.x_axis.abs(), am.y_axis.abs(), am.z_axis.abs());
    let xc = q.reference_point();
    let f0 = o - xc;
    // Coefficient scales: |qa| = |d|ᵀ|A||d|, |qb| = |d|ᵀ(|A||f₀| + |b_c|),
    // |qc| = |f|(o) (the same bound eval_abs documents).
    let qa_abs = d.abs().dot(aa * d.abs());
    let bc = q.gradient(xc) * 0.5;
    let k = q.eval(xc);
    let g_abs = bc.abs(); // |b_c|
    let qb_abs = d.abs().dot(aa * f0.abs() + g_abs);
    let qc_abs = scale(q, o);
    // The near root `qc/q` inherits qc's rounding: forward error δ = K·u·|qc|/|q| with
    // |q| ≥ |qb|, which adds qa·δ² + |F'|·δ to the residual.
    let qb = d.dot(q.gradient(o) * 0.5);
    let delta = K * u * qc_abs / qb.abs();
    // The discriminant's scale qb² (or qa·qc) near the f64 subnormal range loses relative
    // precision: roots there are checked for order only.
    let underflows = (qb_abs * qb_abs).max(qa_abs * qc_abs) < F64_NEAR_UNDERFLOW;
    if let Some((t0, t1)) = roots.filter(|_| !underflows) {
        assert!(t0 <= t1, "roots out of order\n{}", ctx());
        for t in [t0, t1] {
            // f in the quadric's centred coordinates, y = (o − x_c) + t·d: a world point
            // o + t·d would round away a displacement that a large curvature still sees.
            let y = f0 + d * t;
            let fx = y.dot(am * y + bc * 2.0) + k;
            let ya = y.abs();
            let f_abs = ya.dot(aa * ya + bc.abs() * 2.0) + k.abs();
            // Plus the rounding of y itself (≤ u·|y| per component).
            let bound = K * u * (qa_abs * t * t + 2.0 * qb_abs * t.abs() + qc_abs + f_abs)
                + qa_abs * delta * delta
                + 2.0 * (qb_abs + qa_abs * t.abs()) * delta;
            if bound.is_finite() && fx.is_finite() {
                assert!(
                    fx.abs() <= bound + 1e-300,
                    "root t = {t:e}: f = {fx:e} > bound {bound:e}\n{}",
                    ctx()
                );
            }
        }
    }
    if let Some(h) = hit {
        super::check_hit_basics(ray, &h, &ctx);
        let p = h.point.as_dvec3();
        let e = h.point_error.as_dvec3().length();
        let fx = q.eval(p);
        let gl = q.gradient(p).length();
        let a_norm =
            (am.x_axis.length_squared() + am.y_axis.length_squared() + am.z_axis.length_squared())
                .sqrt();
        let bound = gl * e + 3.0 * a_norm * e * e + 32.0 * u * scale(q, p);
        if bound.is_finite() && fx.is_finite() {
            assert!(
                fx.abs() <= bound * (1.0 + 1e-9) + 1e-300,
                "hit point {:?}: f = {fx:e} > {bound:e} (point_error {:?})\n{}",
                h.point,
                h.point_error,
                ctx()
            );
        }
        let Some((t0, t1)) = roots else {
            panic!("a hit without roots\n{}", ctx())
        };
        assert!(
            h.t == t0 as f32 || h.t == t1 as f32,
            "hit t = {:e} is neither root ({t0:e}, {t1:e})\n{}",
            h.t,
            ctx()
        );
    }
    // 3. Interval logic against the roots themselves (the f32 rounding of each root is
    // what `contains` sees).
    if let Some((t0, t1)) = roots {
        let c0 = ray.contains(t0 as f32);
        let c1 = ray.contains(t1 as f32);
        match (c0, c1, hit) {
            (true, _, Some(h)) => assert_eq!(h.t, t0 as f32, "near root skipped\n{}", ctx()),
            (false, true, Some(h)) => assert_eq!(h.t, t1 as f32, "{}", ctx()),
            (false, false, Some(_)) => panic!("hit with both roots outside\n{}", ctx()),
            _ => {} // a hit may be dropped only when its point is not representable
        }
    }
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let t = |name: &str, b: Vec<u8>| ("ray_quadric", format!("seed-{name}"), b);
    let o = Vec3::new(-5.0, 0.25, 0.5);
    let x = Vec3::X;
    // The specification's ellipsoid x²/4 + y²/9 + z² = 1 and a ray along x.
    s.push(t(
        "ellipsoid",
        quadric::encode_shape(1, o, x, Vec3::ZERO, Vec3::new(2.0, 3.0, 1.0), 0.0),
    ));
    s.push(t(
        "ellipsoid-far",
        quadric::encode_shape(
            1,
            Vec3::ZERO,
            Vec3::new(1e5, 1.0, 0.0),
            Vec3::new(1e5, 0.0, 0.0),
            Vec3::new(2.0, 3.0, 1.0),
            0.0,
        ),
    ));
    s.push(t(
        "cylinder-along-axis",
        quadric::encode_shape(2, Vec3::ZERO, Vec3::Z, Vec3::ZERO, Vec3::Z, 1.0),
    ));
    s.push(t(
        "cylinder-across",
        quadric::encode_shape(2, o, x, Vec3::ZERO, Vec3::Z, 1.0),
    ));
    s.push(t(
        "cone-apex",
        quadric::encode_shape(3, Vec3::new(-1.0, 0.0, 0.0), x, Vec3::ZERO, Vec3::Z, 0.5),
    ));
    s.push(t(
        "cone-generator",
        quadric::encode_shape(
            3,
            Vec3::new(-1.0, 0.0, -2.0),
            Vec3::new(1.0, 0.0, 2.0),
            Vec3::ZERO,
            Vec3::Z,
            0.5,
        ),
    ));
    // General forms: hyperboloid x² + y² − z² − 1, paraboloid x² + y² − z, plane-like 2x − 1.
    s.push(t(
        "hyperboloid",
        quadric::encode_general(o, x, [1.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0]),
    ));
    s.push(t(
        "paraboloid-axis",
        quadric::encode_general(
            Vec3::new(0.0, 0.0, 5.0),
            -Vec3::Z,
            [1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -0.5, 0.0],
        ),
    ));
    s.push(t(
        "linear",
        quadric::encode_general(
            o,
            x,
            [0.0; 6]
                .into_iter()
                .chain([1.0, 0.0, 0.0, -1.0])
                .collect::<Vec<_>>()
                .try_into()
                .unwrap(),
        ),
    ));
    s.push(t(
        "nan-entry",
        quadric::encode_general(
            o,
            x,
            [1.0, f32::NAN, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0],
        ),
    ));
}
