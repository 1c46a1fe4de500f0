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
use halfray_core::error::GeometryError;
use halfray_core::float::F64_UNIT_ROUNDOFF;
use halfray_core::quadric::{Ellipsoid, Quadric};
use halfray_core::ray::Ray;
use num_rational::BigRational;
use num_traits::ToPrimitive;

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

/// The constructor's parameters as decoded, for [`expected_refusal`] (`f64` for the general
/// form: the decoder widens its `f32`s exactly).
#[derive(Clone, Copy, Debug)]
pub enum Params {
    /// `Quadric::new(A, b, c)`: the 6 upper-triangle entries of `A`, then `b`, `c`.
    General([f64; 10]),
    /// `Ellipsoid::new(center, radii)`.
    Ellipsoid(Vec3, Vec3),
    /// `Quadric::cylinder(axis_point, axis_dir, radius)`.
    Cylinder(Vec3, Vec3, f32),
    /// `Quadric::cone(apex, axis_dir, tan_half_angle)`.
    Cone(Vec3, Vec3, f32),
}

/// The constructor's parameters of a `ray_quadric` input (the same bytes [`decode`] reads).
pub fn decode_params(data: &[u8]) -> Params {
    let mut i = Input::new(data);
    let fl = i.u8();
    let q = fl & 4 != 0;
    let _origin = if q { i.qvec3() } else { i.vec3() };
    let _direction = i.vec3();
    if fl & 8 == 0 {
        let _interval = (i.f32(), i.f32());
    }
    let mut s = || if q { i.q() } else { i.f32() };
    let mut v = || Vec3::new(s(), s(), s());
    match fl & 3 {
        0 => Params::General(core::array::from_fn(|_| f64::from(s()))),
        1 => {
            let (c, r) = (v(), v());
            Params::Ellipsoid(c, r)
        }
        2 => {
            let (p, a) = (v(), v());
            Params::Cylinder(p, a, s())
        }
        _ => {
            let (p, a) = (v(), v());
            Params::Cone(p, a, s())
        }
    }
}

/// Largest magnitude the centred form of [`Quadric::new`] may reach, by the bound in
/// [`expected_refusal`], for the oracle to insist on acceptance (unitless, the scale of `k`).
/// The constructor documents a `NonFinite` refusal when the centred form "overflows `f64`"
/// without saying at which rounding of the centre computation; below `10³⁰⁰` (a factor
/// 1.8·10⁸ under `f64::MAX`, far more than the rounding of a 3×3 inverse with condition
/// number ≤ 2²⁰ can add) no step can overflow for entries of `f32` range (the adjugate's
/// products stay below 10⁷⁸), so a refusal there is a defect. Above it the contract leaves
/// the outcome undecided: accepted or `NonFinite`, never `Degenerate`. For the `f32` inputs
/// this target decodes the bound stays below 10¹³⁶ (`4·2⁴⁰·|b|²/‖A‖_F` with
/// `|b| ≤ 5.9·10³⁸`, `‖A‖_F ≥ 1.4·10⁻⁴⁵`), so the band is never entered; it is stated so
/// that the oracle says what it would not judge.
pub const CENTRED_FORM_DECIDED_BELOW: f64 = 1e300;

/// What the constructor must answer, from its documented contract alone (doc comments of
/// `Quadric::new`, `Ellipsoid::new`, `Quadric::cylinder`, `Quadric::cone` and of
/// [`halfray_core::tolerance::QUADRIC_CENTER_MIN_REL_DET`]): `Ok(())` when it must accept,
/// `Err(kinds)` when it must refuse with one of `kinds` (several where the contract names
/// more than one applicable error without ordering them), `None` where the contract leaves
/// it undecided ([`CENTRED_FORM_DECIDED_BELOW`]).
///
/// * General: `NonFinite` for a non-finite entry; `Degenerate` when the symmetric `A` and
///   `b` are all zero (`f` constant); otherwise accepted unless the centred form overflows.
///   The centre is used only when `|det A| ≥ 2⁻²⁰‖A‖_F³` (the tolerance's docs), so with
///   `|det A| = σ₁σ₂σ₃ ≤ ‖A‖_F²σ₃` the smallest singular value is `σ₃ ≥ 2⁻²⁰‖A‖_F`:
///   `|x_c| ≤ |b|/σ₃`, `|b_c| ≤ ‖A‖_F|x_c| + |b|`,
///   `|k| ≤ |x_c|(‖A‖_F|x_c| + 2|b|) + |c|`; otherwise the reference point is the origin
///   (`b_c = b`, `k = c`, finite). The bound is evaluated in `f64` with a factor 4 for its
///   own rounding and that of the inverse.
/// * Ellipsoid: `NonFinite` for a non-finite centre or radius, `Degenerate` for a radius
///   `≤ 0` (`−0.0` included); otherwise accepted (`1/r²` of an `f32` radius is finite in
///   `f64`: between `10⁻⁷⁸` and `10⁹⁰`).
/// * Cylinder, cone: `NonFinite` for a non-finite point, axis or scalar; `Degenerate` for a
///   zero axis (any sign of zero; a subnormal `f32` axis is non-zero in `f64`) or a scalar
///   `≤ 0`; otherwise accepted (`r²` and `1 + τ²` of an `f32` are finite in `f64`).
pub fn expected_refusal(p: &Params) -> Option<Result<(), Vec<GeometryError>>> {
    use GeometryError::{Degenerate, NonFinite};
    let finite3 = |v: Vec3| v.x.is_finite() && v.y.is_finite() && v.z.is_finite();
    let zero3 = |v: Vec3| v.x == 0.0 && v.y == 0.0 && v.z == 0.0;
    let mut kinds = Vec::new();
    match *p {
        Params::General(e) => {
            if e.iter().any(|x| !x.is_finite()) {
                return Some(Err(vec![NonFinite]));
            }
            // `A = 0` and `b = 0`, whatever `c`.
            if e[..9].iter().all(|&x| x == 0.0) {
                return Some(Err(vec![Degenerate]));
            }
            // `A`'s entries: the diagonal once, the off-diagonal twice.
            let fro = (e[0] * e[0]
                + e[3] * e[3]
                + e[5] * e[5]
                + 2.0 * (e[1] * e[1] + e[2] * e[2] + e[4] * e[4]))
                .sqrt();
            let b = (e[6] * e[6] + e[7] * e[7] + e[8] * e[8]).sqrt();
            let bound = if fro > 0.0 {
                let sigma3 = fro / 1_048_576.0;
                let xc = b / sigma3;
                4.0 * (xc * (fro * xc + 2.0 * b) + e[9].abs() + fro * xc + b)
            } else {
                b + e[9].abs()
            };
            if !(bound < CENTRED_FORM_DECIDED_BELOW) {
                return None;
            }
        }
        Params::Ellipsoid(c, r) => {
            if !finite3(c) || !finite3(r) {
                kinds.push(NonFinite);
            }
            // A NaN radius is not `≤ 0` (only NonFinite); `−∞` is both.
            if r.to_array().iter().any(|&x| x <= 0.0) {
                kinds.push(Degenerate);
            }
        }
        Params::Cylinder(pt, axis, s) | Params::Cone(pt, axis, s) => {
            if !finite3(pt) || !finite3(axis) || !s.is_finite() {
                kinds.push(NonFinite);
            }
            if zero3(axis) || s <= 0.0 {
                kinds.push(Degenerate);
            }
        }
    }
    Some(if kinds.is_empty() { Ok(()) } else { Err(kinds) })
}

/// Fuzz target `ray_quadric`.
///
/// Besides [`check`] and [`check_against_exact`] on every surface built: the constructor's
/// answer against [`expected_refusal`] (refusing a valid input, accepting an invalid one, or
/// refusing with another kind than the contract names is a failure).
pub fn ray_quadric(data: &[u8]) {
    let (surface, ray) = decode(data);
    let params = decode_params(data);
    if let Some(want) = expected_refusal(&params) {
        match (&surface, &want) {
            (Ok(_), Ok(())) => {}
            (Err(e), Err(kinds)) => {
                reached();
                assert!(
                    kinds.contains(e),
                    "refused as {e:?}, the contract names {kinds:?}: {params:?}"
                );
            }
            (Ok(q), Err(kinds)) => {
                panic!("accepted {q:?}, the contract refuses it ({kinds:?}): {params:?}")
            }
            (Err(e), Ok(())) => panic!("refused a valid input as {e:?}: {params:?}"),
        }
    } else {
        assert!(
            !matches!(surface, Err(GeometryError::Degenerate)),
            "a centred form beyond {CENTRED_FORM_DECIDED_BELOW:e} refused as Degenerate: \
             {params:?}"
        );
    }
    if let Ok(q) = surface {
        check(&q, &ray);
        check_against_exact(&q, &ray);
    }
}

/// Discriminants below this multiple of `u·S` (`S = |qb|² + |qa|·|qc|`, the scale of the
/// discriminant's rounding with absolute values) are not judged for existence: the code's
/// discriminant carries at most a few tens of `u·S` of error (its two forms are evaluated
/// with a handful of roundings each, and it takes the one with the smaller bound), so beyond
/// this band its sign is the exact one. Unitless.
pub const DISC_BAND_IN_U: f64 = 256.0;

/// Discriminants below this fraction of `S` are not judged for root positions: beyond it the
/// roots are well separated, the discriminant's rounding moves each by about `u·S/√Δ` of
/// `1/|qa|` (far inside [`ROOT_REL_TOL`] of the root scale) and the coefficients' rounding by
/// at most [`root_rounding`]. Unitless.
pub const ROOT_DISC_REL: f64 = 1.0 / 1_073_741_824.0;

/// Tolerance of a root against the exact one, relative to `|r| + √S/|qa|` (the root scale),
/// on top of the root's first-order rounding bound ([`root_rounding`]). Loose on purpose
/// (10⁻⁶ against a discriminant rounding below 10⁻¹⁰ where it is applied): it catches
/// dropped, invented, swapped or wrong roots, not accuracy, which the residual check bounds.
/// Unitless.
pub const ROOT_REL_TOL: f64 = 1e-6;

/// First-order bound of how far rounding the coefficients moves root `r` of a polynomial
/// with discriminant `disc > 0` (`t` units): each coefficient carries at most `K·u` of its
/// absolute-value scale (`qa_abs`, `qb_abs`, `qc_abs`), which moves `p(r)` by at most
/// `K·u·(|qa|·r² + 2·|qb|·|r| + |qc|)`, and `|p'(r)| = 2·√Δ`. Where `qa` cancels (its exact
/// value far below `|qa|`, as for a ray along the asymptote of `y² − z²`), this term is many
/// times [`ROOT_REL_TOL`] of the root scale (kept: `qa-cancels-root-moves`).
fn root_rounding(r: f64, [qa_abs, qb_abs, qc_abs]: [f64; 3], disc: f64) -> f64 {
    K * F64_UNIT_ROUNDOFF * (qa_abs * r * r + 2.0 * qb_abs * r.abs() + qc_abs) / (2.0 * disc.sqrt())
}

/// `uᵀAv` for `q`'s quadratic part as [`Quadric::roots`] documents it, in `f64`, and the same
/// with every product replaced by its absolute value (the scale of its rounding): for a
/// cylinder or cone (`Quadric::axial_form` is `Some((w, τ²))`) the axial form
/// `((u × w)·(v × w) − τ²(u·w)(v·w))/|w|²`, whose exact roots are those of the axis as given,
/// else `uᵀ·matrix()·v`.
fn form_f64(q: &Quadric, u: DVec3, v: DVec3) -> (f64, f64) {
    let (ua, va) = (u.abs(), v.abs());
    match q.axial_form() {
        Some((w, tau2)) => {
            let w = w.as_dvec3();
            let wa = w.abs();
            let cross_abs = |a: DVec3| {
                DVec3::new(
                    a.y * wa.z + a.z * wa.y,
                    a.z * wa.x + a.x * wa.z,
                    a.x * wa.y + a.y * wa.x,
                )
            };
            let w2 = w.length_squared();
            (
                (u.cross(w).dot(v.cross(w)) - tau2 * u.dot(w) * v.dot(w)) / w2,
                (cross_abs(ua).dot(cross_abs(va)) + tau2 * ua.dot(wa) * va.dot(wa)) / w2,
            )
        }
        None => {
            let am = q.matrix();
            let aa = DMat3::from_cols(am.x_axis.abs(), am.y_axis.abs(), am.z_axis.abs());
            (u.dot(am * v), ua.dot(aa * va))
        }
    }
}

/// The ray polynomial `p(t) = qa·t² + 2·qb·t + qc` of `q` along `ray`, in **exact rational
/// arithmetic** from the stored centred form (centre, `A`, `b_c`, `k`: `f(x) = yᵀA y + 2b_cᵀy +
/// k`, `y = x − c`; for a cylinder or cone `yᵀAy` from its axis, as [`form_f64`]) and the
/// ray's `f32` origin and direction: an oracle that shares no arithmetic with
/// [`Quadric::roots`]. `None` when a stored value is not finite.
fn exact_poly(q: &Quadric, ray: &Ray) -> Option<[BigRational; 3]> {
    let r = |x: f64| BigRational::from_float(x);
    let c = q.reference_point();
    let am = q.matrix();
    let bc = q.gradient(c) * 0.5;
    let k = r(q.eval(c))?;
    let v3 = |v: DVec3| -> Option<[BigRational; 3]> { Some([r(v.x)?, r(v.y)?, r(v.z)?]) };
    let dot = |a: &[BigRational; 3], b: &[BigRational; 3]| -> BigRational {
        (0..3).map(|i| &a[i] * &b[i]).sum()
    };
    let cols = match q.axial_form() {
        // A·y = (w × (y × w) − τ²(y·w)·w)/|w|² = (|w|²·y − (1 + τ²)(y·w)·w)/|w|²: A's
        // columns A·e_j, exactly.
        Some((w, tau2)) => {
            let (w, s) = (
                v3(w.as_dvec3())?,
                r(tau2)? + BigRational::from_integer(1.into()),
            );
            let w2 = dot(&w, &w);
            let id = |i: usize, j: usize| BigRational::from_integer(i32::from(i == j).into());
            [0, 1, 2].map(|j| -> [BigRational; 3] {
                core::array::from_fn(|i| id(i, j) - &s * &w[i] * &w[j] / &w2)
            })
        }
        None => [v3(am.x_axis)?, v3(am.y_axis)?, v3(am.z_axis)?],
    };
    // (A·y)_i = Σ_j A_ij y_j, column j holding A_·j.
    let mul = |y: &[BigRational; 3]| -> [BigRational; 3] {
        core::array::from_fn(|i| (0..3).map(|j| &cols[j][i] * &y[j]).sum())
    };
    let (o, d, cc, b) = (
        v3(ray.origin.as_dvec3())?,
        v3(ray.direction.as_dvec3())?,
        v3(c)?,
        v3(bc)?,
    );
    let f0: [BigRational; 3] = core::array::from_fn(|i| &o[i] - &cc[i]);
    let af0 = mul(&f0);
    let g0: [BigRational; 3] = core::array::from_fn(|i| &af0[i] + &b[i]);
    let g0b: [BigRational; 3] = core::array::from_fn(|i| &g0[i] + &b[i]);
    Some([dot(&d, &mul(&d)), dot(&d, &g0), dot(&f0, &g0b) + k])
}

/// The roots against the exact oracle ([`exact_poly`]), where the exact answer is decidable
/// beyond the code's rounding:
/// 1. a discriminant clearly positive (beyond [`DISC_BAND_IN_U`]) must give two roots, one
///    clearly negative none (a dropped or an invented root);
/// 2. where the roots are well separated ([`ROOT_DISC_REL`]), each reported root lies within
///    [`ROOT_REL_TOL`] of the exact one;
/// 3. a near exact root clearly inside the ray's interval must give a hit (a miss), unless
///    the hit point would not be representable.
///
/// Judged only for a clearly quadratic polynomial (`|qa|` beyond `K·u` of its scale: the code
/// then takes the quadratic branch) whose scales are far from `f64` overflow and underflow.
pub fn check_against_exact(q: &Quadric, ray: &Ray) {
    if !ray.is_valid() {
        return;
    }
    let Some([qa, qb, qc]) = exact_poly(q, ray) else {
        return;
    };
    let to = |x: &BigRational| x.to_f64().unwrap_or(f64::NAN);
    let (fa, fb, fc) = (to(&qa), to(&qb), to(&qc));
    let disc = &qb * &qb - &qa * &qc;
    // Scales with absolute values, as the code's rounding sees them.
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let [qa_abs, qb_abs, qc_abs] = coefficient_scales(q, ray);
    let s = qb_abs * qb_abs + qa_abs * qc_abs;
    let u = F64_UNIT_ROUNDOFF;
    let judged = [fa, fb, fc, qa_abs, qb_abs, qc_abs, s]
        .iter()
        .all(|x| x.is_finite() && x.abs() < 1e150)
        && s > 1e-150
        && fa.abs() > K * u * qa_abs;
    if !judged {
        return;
    }
    let ctx = || {
        format!(
            "exact p(t) = {fa:e}·t² + 2·{fb:e}·t + {fc:e}, Δ = {:e}, S = {s:e}\nquadric {q:?}\n{}",
            to(&disc),
            fmt_ray(ray)
        )
    };
    let band = BigRational::from_float(DISC_BAND_IN_U * u * s).expect("finite band");
    let roots = q.roots(ray);
    if disc > band {
        reached();
        assert!(
            roots.is_some(),
            "a clearly positive discriminant, no roots\n{}",
            ctx()
        );
    } else if disc < -band {
        reached();
        assert!(
            roots.is_none(),
            "a clearly negative discriminant, roots {roots:?}\n{}",
            ctx()
        );
    }
    let fd = to(&disc);
    // (A NaN discriminant is not judged either.)
    if fd.is_nan() || fd <= ROOT_DISC_REL * s {
        return;
    }
    // The exact roots to f64 accuracy (the stable form, from the exact coefficients).
    let qq = -(fb + fd.sqrt().copysign(fb));
    let (r0, r1) = {
        let (x, y) = (fc / qq, qq / fa);
        if x <= y { (x, y) } else { (y, x) }
    };
    let scale = s.sqrt() / fa.abs();
    let tol_of =
        |r: f64| ROOT_REL_TOL * (r.abs() + scale) + root_rounding(r, [qa_abs, qb_abs, qc_abs], fd);
    let (t0, t1) = roots.expect("checked above");
    for (t, r) in [(t0, r0), (t1, r1)] {
        assert!(
            (t - r).abs() <= tol_of(r),
            "root {t:e}, exact {r:e}\n{}",
            ctx()
        );
    }
    // 3. A near root clearly inside the interval is a hit (point representable).
    let tol = tol_of(r0);
    let (lo, hi) = (f64::from(ray.t_min), f64::from(ray.t_max));
    let point = o + d * r0;
    // Roots below the sphere target's `MIN_T` round to a `t` (or to 0) from which no hit
    // can be rebuilt in `f32`, like a root beyond 1e30 (kept: `crash-0a29d96f`, a root of
    // 8e-63).
    let inside =
        r0 - tol > lo && r0 + tol <= hi && (super::sphere::MIN_T..1e30).contains(&r0.abs());
    if inside && point.abs().max_element() < 1e30 {
        assert!(
            q.intersect(ray).is_some(),
            "exact root {r0:e} inside ({lo:e}, {hi:e}], no hit\n{}",
            ctx()
        );
    }
}

/// `(|f|(x), ‖A‖)`: `f` evaluated with absolute values (the scale of its rounding error).
fn scale(q: &Quadric, x: DVec3) -> f64 {
    q.eval_abs(x)
}

/// The ray polynomial's coefficient scales `[|qa|, |qb|, |qc|]` (absolute values, the scale of
/// their rounding): `|qa| = |d|ᵀ|A||d|`, `|qb| = |d|ᵀ(|A||f₀| + |b_c|)`, `|qc| = |f|(o)` (the
/// bound `eval_abs` documents), `f₀ = o − x_c`; for a cylinder or cone, `|·|ᵀ|A||·|` of the
/// axial form ([`form_f64`]).
fn coefficient_scales(q: &Quadric, ray: &Ray) -> [f64; 3] {
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let xc = q.reference_point();
    let f0 = o - xc;
    let bc = q.gradient(xc) * 0.5;
    let qc_abs = match q.axial_form() {
        Some(_) => form_f64(q, f0, f0).1 + 2.0 * f0.abs().dot(bc.abs()) + q.eval(xc).abs(),
        None => scale(q, o),
    };
    [
        form_f64(q, d, d).1,
        form_f64(q, d, f0).1 + d.abs().dot(bc.abs()),
        qc_abs,
    ]
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
        reached();
        assert!(roots.is_none() && hit.is_none(), "{}", ctx());
        return;
    }
    let u = F64_UNIT_ROUNDOFF;
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let am = q.matrix();
    let xc = q.reference_point();
    let f0 = o - xc;
    let [qa_abs, qb_abs, qc_abs] = coefficient_scales(q, ray);
    let bc = q.gradient(xc) * 0.5;
    let k = q.eval(xc);
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
            let (quad, quad_abs) = form_f64(q, y, y);
            let fx = quad + y.dot(bc * 2.0) + k;
            let f_abs = quad_abs + y.abs().dot(bc.abs() * 2.0) + k.abs();
            // Plus the rounding of y itself (≤ u·|y| per component).
            let bound = K * u * (qa_abs * t * t + 2.0 * qb_abs * t.abs() + qc_abs + f_abs)
                + qa_abs * delta * delta
                + 2.0 * (qb_abs + qa_abs * t.abs()) * delta;
            if bound.is_finite() && fx.is_finite() {
                reached();
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The refusal oracle on hand-picked inputs, each with the answer the constructor docs
    /// give (written here, not computed), and the constructors agree.
    #[test]
    fn refusals_predicted_from_the_contract() {
        use GeometryError::{Degenerate, NonFinite};
        let v = Vec3::new;
        let one = v(1.0, 1.0, 1.0);
        let cases: [(Params, Result<(), Vec<GeometryError>>); 12] = [
            (Params::Ellipsoid(Vec3::ZERO, one), Ok(())),
            (
                Params::Ellipsoid(Vec3::ZERO, v(1.0, -0.0, 1.0)),
                Err(vec![Degenerate]),
            ),
            (
                Params::Ellipsoid(Vec3::ZERO, v(1.0, f32::NAN, 1.0)),
                Err(vec![NonFinite]),
            ),
            (
                Params::Ellipsoid(Vec3::ZERO, v(1.0, f32::NEG_INFINITY, 1.0)),
                Err(vec![NonFinite, Degenerate]),
            ),
            (Params::Ellipsoid(Vec3::ZERO, v(1e-45, 3e38, 1.0)), Ok(())),
            (
                Params::Cylinder(Vec3::ZERO, v(0.0, -0.0, 0.0), 1.0),
                Err(vec![Degenerate]),
            ),
            (
                Params::Cylinder(Vec3::ZERO, v(1e-45, 0.0, 0.0), 3e38),
                Ok(()),
            ),
            (
                Params::Cone(Vec3::ZERO, Vec3::Z, 0.0),
                Err(vec![Degenerate]),
            ),
            (
                Params::Cone(v(f32::INFINITY, 0.0, 0.0), Vec3::Z, 1.0),
                Err(vec![NonFinite]),
            ),
            (Params::General([0.0; 10]), Err(vec![Degenerate])),
            (
                Params::General([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0]),
                Err(vec![Degenerate]),
            ),
            (
                Params::General([1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 3e38, 3e38, 3e38, 3e38]),
                Ok(()),
            ),
        ];
        for (params, want) in cases {
            assert_eq!(expected_refusal(&params), Some(want.clone()), "{params:?}");
            let built = match params {
                Params::General(e) => {
                    let a = DMat3::from_cols_array(&[
                        e[0], e[1], e[2], e[1], e[3], e[4], e[2], e[4], e[5],
                    ]);
                    Quadric::new(a, DVec3::new(e[6], e[7], e[8]), e[9]).map(|_| ())
                }
                Params::Ellipsoid(c, r) => Ellipsoid::new(c, r).map(|_| ()),
                Params::Cylinder(p, a, r) => Quadric::cylinder(p, a, r).map(|_| ()),
                Params::Cone(p, a, t) => Quadric::cone(p, a, t).map(|_| ()),
            };
            match (built, want) {
                (Ok(()), Ok(())) => {}
                (Err(e), Err(kinds)) => assert!(kinds.contains(&e), "{params:?}: {e:?}"),
                (got, want) => panic!("{params:?}: {got:?}, contract {want:?}"),
            }
        }
        // The general decoder and the parameter decoder read the same bytes.
        let bytes = encode_general(Vec3::ZERO, Vec3::X, [0.0; 10]);
        assert!(matches!(decode_params(&bytes), Params::General(e) if e == [0.0; 10]));
        assert_eq!(decode(&bytes).0, Err(Degenerate));
    }

    /// The oracle's polynomial for the specification's ellipsoid `x²/4 + y²/9 + z² = 1` and the
    /// ray `(−5, ¼, ½) + t·x`, written out by hand from the stored form (`A = diag(¼, fl(1/9),
    /// 1)`, centre 0, `b_c = 0`, `k = −1`): `p(t) = ¼t² + 2·(−5/4)·t + (25/4 + fl(1/9)/16 + ¼ − 1)`,
    /// roots `t = 5 ∓ 2·√(¾ − 1/144)` (where `x² /4 = 1 − y²/9 − z²`); the check passes on it
    /// and a tangent ray at `y = 3` is left unjudged rather than failed.
    #[test]
    fn exact_polynomial_of_the_worked_ellipsoid() {
        let e = Ellipsoid::new(Vec3::ZERO, Vec3::new(2.0, 3.0, 1.0)).unwrap();
        let ray = Ray::new(Vec3::new(-5.0, 0.25, 0.5), Vec3::X);
        let [qa, qb, qc] = exact_poly(e.quadric(), &ray).unwrap();
        let r = |x: f64| BigRational::from_float(x).unwrap();
        let ninth = r(e.quadric().matrix().y_axis.y);
        assert_eq!(ninth, r(1.0 / 9.0));
        assert_eq!(qa, r(0.25));
        assert_eq!(qb, r(-1.25));
        assert_eq!(qc, r(6.25) + ninth * r(0.0625) + r(0.25) - r(1.0));
        let (t0, t1) = e.roots(&ray).unwrap();
        let half = 2.0 * (0.75f64 - 1.0 / 144.0).sqrt();
        assert!((t0 - (5.0 - half)).abs() < 1e-12, "{t0}");
        assert!((t1 - (5.0 + half)).abs() < 1e-12, "{t1}");
        check_against_exact(e.quadric(), &ray);
        check_against_exact(e.quadric(), &Ray::new(Vec3::new(-5.0, 3.0, 0.0), Vec3::X));
    }
}
