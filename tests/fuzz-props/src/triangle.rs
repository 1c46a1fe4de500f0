//! `ray_triangle`: decoding, the intersector contract, agreement with the `f64` reference
//! inside the documented domain, and the watertight error bound (the oracle).

use super::*;
use halfray_core::triangle::{TriangleIntersector, WatertightF32Exact};

/// Decodes a `ray_triangle` input: `flags: u8` ([`flags`]), `origin: 3×f32`,
/// `direction: 3×f32`, `t_min: f32`, `t_max: f32`, `v0, v1, v2: 3×f32 each` (69 bytes).
pub fn decode_ray_triangle(data: &[u8]) -> (Ray, [Vec3; 3]) {
    let mut i = Input::new(data);
    let h = RayHeader::decode(&mut i);
    let v = [i.vec3(), i.vec3(), i.vec3()];
    let direction = if h.has(flags::AIM) {
        v[0] + (v[1] - v[0]) * h.dir.x + (v[2] - v[0]) * h.dir.y - h.origin
    } else {
        h.dir
    };
    (h.ray(direction), v)
}

/// Encodes a `ray_triangle` input (see [`decode_ray_triangle`]).
pub fn encode_ray_triangle(fl: u8, o: Vec3, d: Vec3, t: (f32, f32), v: [Vec3; 3]) -> Vec<u8> {
    Enc::new()
        .ray_header(fl, o, d, t)
        .vec3(v[0])
        .vec3(v[1])
        .vec3(v[2])
        .done()
}

/// Fuzz target `ray_triangle`: [`check_ray_triangle`] on [`decode_ray_triangle`]`(data)`, and
/// again with the triangle's vertices rotated and with the winding reversed (same surface).
pub fn ray_triangle(data: &[u8]) {
    let (ray, v) = decode_ray_triangle(data);
    check_ray_triangle(&ray, &v);
    check_ray_triangle(&ray, &[v[1], v[2], v[0]]);
    check_ray_triangle(&ray, &[v[0], v[2], v[1]]);
}

pub(crate) fn tri_context(ray: &Ray, v: &[Vec3; 3]) -> String {
    format!(
        "{}\n  v0 = {}\n  v1 = {}\n  v2 = {}",
        fmt_ray(ray),
        fmt_vec3(v[0]),
        fmt_vec3(v[1]),
        fmt_vec3(v[2])
    )
}

/// The properties of every triangle variant on one ray and triangle:
///
/// 1. **Contract** (all inputs, all [`TriangleVariant`]s): an invalid ray, a non-finite vertex
///    or a triangle with two equal vertices never hits; a hit has `t` finite and in
///    `(t_min, t_max]`, barycentrics `b0 = 1 − b1 − b2`, `b1`, `b2` finite and within
///    [`BARYCENTRIC_SLACK`] of `[0, 1]`, `front_face` agreeing with the sign of `d·ng` when
///    that sign is clear (`|cos| > 10⁻³`), [`TriangleHit::to_hit`]'s point within its own
///    error bound of `Σ bᵢ·vᵢ` (when nothing overflows), and its normal unit and along
///    `(v1 − v0) × (v2 − v0)` (where that is not zero).
/// 2. **Agreement with the f64 reference** (`watertight` and `watertight-f32`, in the domain
///    of [`WatertightBound`]): when every reference edge function is farther from zero than
///    its error bound (equivalently, every reference barycentric `|bᵢ|` exceeds
///    `errᵢ/|det|`) and the reference `t` is farther from `t_min` and `t_max` than the `t`
///    bound, the variant hits exactly when [`F64Reference::solve`] hits in the interval, and
///    then its `t` and barycentrics are within the bounds of the reference's.
pub fn check_ray_triangle(ray: &Ray, v: &[Vec3; 3]) {
    let valid = ray.is_valid();
    let finite = v.iter().all(|p| p.is_finite());
    let mut got = [None; TriangleVariant::ALL.len()];
    for (k, var) in TriangleVariant::ALL.into_iter().enumerate() {
        let h = var.intersect(ray, v);
        if let Some(h) = h {
            let ctx = || format!("variant {}: {h:?}\n{}", var.name(), tri_context(ray, v));
            // `watertight-f32` computes its edge functions and barycentrics in `f32` products,
            // sound only while no product underflows or overflows (its docs: triangles of
            // ≳ 1e19 or ≲ 1e-19 and underflowing projections are outside its domain); there
            // its barycentrics may leave [0, 1] by more than the slack (regression input
            // `ci-crash-c5997b10`: 4.8e30 and subnormal coordinates), so the range is
            // checked only inside that domain.
            let f32_domain = var != TriangleVariant::WatertightF32
                || (!projection_underflows(ray, v) && f32_products_in_range(ray, v));
            check_hit_contract(ray, v, &h, f32_domain, &ctx);
        }
        got[k] = h;
    }
    // The `f64`-free test for microcontrollers: not a `TriangleVariant` (it decides "in the
    // plane" on the sheared projection, not in 3-D `f64`: see its docs), checked here the same
    // way, with `watertight-f32`'s domain for the barycentric range (its `f32` products).
    let exact_f32 = WatertightF32Exact.intersect(ray, v);
    if let Some(h) = exact_f32 {
        let ctx = || format!("watertight-f32-exact: {h:?}\n{}", tri_context(ray, v));
        let f32_domain = !projection_underflows(ray, v) && f32_products_in_range(ray, v);
        check_hit_contract(ray, v, &h, f32_domain, &ctx);
    }
    // An input the contract excludes (invalid ray, non-finite or repeated vertex): that no
    // variant hit it, judged above, is its property.
    if !(valid && finite) || v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
        reached();
    }
    if !(valid && finite) {
        return;
    }
    let Some(bound) = WatertightBound::new(ray, v) else {
        return;
    };
    for (k, var) in TriangleVariant::ALL.into_iter().enumerate() {
        let eval = match var {
            TriangleVariant::Watertight => EdgeEval::ExactF64,
            TriangleVariant::WatertightF32 => EdgeEval::F32,
            _ => continue,
        };
        bound.check_agreement(var.name(), eval, ray, v, got[k]);
    }
    bound.check_agreement("watertight-f32-exact", EdgeEval::F32, ray, v, exact_f32);
}

/// `true` when every vertex coordinate relative to the ray origin is zero or within
/// `[1e-19, 1e19]` in magnitude: the range where `watertight-f32`'s `f32` products neither
/// overflow nor underflow (its documented domain).
pub fn f32_products_in_range(ray: &Ray, v: &[Vec3; 3]) -> bool {
    v.iter().all(|p| {
        (*p - ray.origin)
            .to_array()
            .iter()
            .all(|&c| c == 0.0 || (1.0e-19..=1.0e19).contains(&c.abs()))
    })
}

/// The smallest magnitude of the `f32` products behind an `f32` variant's orientation
/// (`e1 × e2`, about `M²`, and `d·(e1 × e2)`, about `M²·|d|`; `M` the largest `|vᵢ − o|`) for
/// which the orientation check holds it to the sign of the exact `d·n`: `2⁻¹⁰²`, the
/// smallest normal `f32` times `2²⁴`. At or above it, the absolute error of an intermediate
/// that underflows (at most `2⁻¹⁵⁰` per operation) is below `2⁻⁴⁸` of the product, inside the
/// check's relative margin; below it, a variant's `f32` determinant can round to a subnormal
/// of either sign (the `f32` variants' docs: products must stay in the normal range; kept:
/// `cramer-det-underflows-front-face`, a 1e-15 triangle seen along a 1e-15 direction, whose
/// triple product is 1e-45). Same units as `M²·|d|` (length² × |direction|).
const ORIENTATION_PRODUCT_FLOOR: f64 = f32::MIN_POSITIVE as f64 * 16_777_216.0;

fn check_hit_contract(
    ray: &Ray,
    v: &[Vec3; 3],
    h: &TriangleHit,
    barycentric_domain: bool,
    ctx: &dyn Fn() -> String,
) {
    // A hit judged against the contract.
    reached();
    assert!(ray.is_valid(), "invalid ray hit\n{}", ctx());
    assert!(
        v.iter().all(|p| p.is_finite()),
        "triangle with a non-finite vertex hit\n{}",
        ctx()
    );
    assert!(
        !(v[0] == v[1] || v[1] == v[2] || v[2] == v[0]),
        "degenerate triangle (repeated vertex) hit\n{}",
        ctx()
    );
    assert!(ray.contains(h.t), "t outside (t_min, t_max]\n{}", ctx());
    assert!(h.t.is_finite(), "non-finite t\n{}", ctx());
    let (b0, b1, b2) = (h.b0(), h.b1, h.b2);
    for (name, b) in [("b0", b0), ("b1", b1), ("b2", b2)] {
        assert!(b.is_finite(), "{name} = {b:e} is not finite\n{}", ctx());
        assert!(
            !barycentric_domain || (-BARYCENTRIC_SLACK..=1.0 + BARYCENTRIC_SLACK).contains(&b),
            "{name} = {b:e} is not within BARYCENTRIC_SLACK = {BARYCENTRIC_SLACK:e} of [0, 1]\n{}",
            ctx()
        );
    }
    // Orientation, for well-conditioned configurations only: the sign of d·n (f64, with a
    // rigorous bound on its own rounding, since the f64 differences of far-apart f32 values are
    // not exact) is clear, the angle is not grazing (|cos| > 1e-3), and the triangle is not a
    // sliver relative to its distance from the origin (|n| ≥ 1e-2·M², M = max |vᵢ − o|), so
    // that f32 rounding of any variant (≈ 6u·M²·|d|) cannot flip it; and the f32 products
    // behind an f32 variant's determinant (M², M²·|d|) are at least
    // `ORIENTATION_PRODUCT_FLOOR`, so that no underflow makes that rounding absolute.
    let u64 = F64_UNIT_ROUNDOFF;
    let e1 = v[1].as_dvec3() - v[0].as_dvec3();
    let e2 = v[2].as_dvec3() - v[0].as_dvec3();
    let n = e1.cross(e2);
    let (a, b) = (e1.abs(), e2.abs());
    let n_err = DVec3::new(
        a.y * b.z + a.z * b.y,
        a.z * b.x + a.x * b.z,
        a.x * b.y + a.y * b.x,
    ) * (4.0 * u64);
    let d = ray.direction.as_dvec3();
    let dn = d.dot(n);
    let dn_err = d.abs().dot(n_err) + 3.0 * u64 * d.abs().dot(n.abs()) + 1e-300;
    let o = ray.origin.as_dvec3();
    let m = v
        .iter()
        .map(|p| (p.as_dvec3() - o).length())
        .fold(0.0, f64::max);
    let tame = (1e-18..=1e18).contains(&m)
        && (1e-18..=1e18).contains(&d.length())
        && m * m >= ORIENTATION_PRODUCT_FLOOR
        && m * m * d.length() >= ORIENTATION_PRODUCT_FLOOR;
    if tame
        && dn.abs() > 2.0 * dn_err
        && dn.abs() > 1e-3 * d.length() * n.length()
        && n.length() >= 1e-2 * m * m
    {
        assert_eq!(
            h.front_face,
            dn < 0.0,
            "front_face disagrees with d·ng\n{}",
            ctx()
        );
    }
    // Hit-point reconstruction: |point − Σ bᵢvᵢ| ≤ point_error (+ subnormal slack).
    let hit = h.to_hit(v);
    if hit.point.is_finite() && hit.point_error.is_finite() {
        let exact = v[0].as_dvec3() * f64::from(b0)
            + v[1].as_dvec3() * f64::from(b1)
            + v[2].as_dvec3() * f64::from(b2);
        let err = (hit.point.as_dvec3() - exact).abs();
        let allowed = hit.point_error.as_dvec3() * (1.0 + 1e-6) + DVec3::splat(UNDERFLOW_ABS);
        assert!(
            err.cmple(allowed).all(),
            "Hit::point farther than point_error from Σ bᵢvᵢ: error {err:?}, bound {:?}\n{}",
            hit.point_error,
            ctx()
        );
    }
    // The hit's normal: unit within `NORMAL_LEN_ULPS` and along `(v1 − v0) × (v2 − v0)` (here
    // in `f64` from the `f32` vertices, written out) where that `f64` product's direction is
    // certain: its rounding (each difference and product once, `γ₃` of the component's scale
    // `|e₁ᵢ||e₂ⱼ| + |e₁ⱼ||e₂ᵢ|`) below `NORMAL_ORACLE_CLEAR` of its length (at `10³⁸` a
    // difference `1 + 2¹²⁷` is not exact in `f64` and a component can cancel: regression
    // `ci-crash-3dd9dcae-hit-normal`, where the crate's normal was the right one).
    let e = |i: usize, k: usize| f64::from(v[i][k]) - f64::from(v[0][k]);
    let comp = |a: usize, b: usize| {
        let n = e(1, a) * e(2, b) - e(1, b) * e(2, a);
        let scale = (e(1, a) * e(2, b)).abs() + (e(1, b) * e(2, a)).abs();
        (n, scale)
    };
    let (x, y, z) = (comp(1, 2), comp(2, 0), comp(0, 1));
    let n = DVec3::new(x.0, y.0, z.0);
    let err = 3.0 * f64::EPSILON * (x.1 + y.1 + z.1);
    if n.is_finite() && err.is_finite() && err < NORMAL_ORACLE_CLEAR * n.length() {
        let len = hit.normal.as_dvec3().length();
        assert!(
            (len - 1.0).abs() <= NORMAL_LEN_ULPS * f64::from(f32::EPSILON)
                && hit.normal.as_dvec3().dot(n) > 0.0,
            "Hit::normal {:?} (length {len}) is not the unit normal along {n:?}\n{}",
            hit.normal,
            ctx()
        );
    }
}

/// How small the `f64` oracle normal's rounding must be against its length for its direction
/// to be checked: `10⁻³` (then the direction is certain to a milliradian, and a unit normal on
/// the right side has a positive dot product with it whenever the crate's is within a right
/// angle). Unitless.
const NORMAL_ORACLE_CLEAR: f64 = 1.0e-3;

/// How far from 1 a hit's unit normal may be, in `f32` ulps of 1: the `f64` normal is
/// normalised in `f64` and each component rounded once to `f32` (half an ulp each), so the
/// length is within about `√3/2` ulps; 4 leaves a margin.
const NORMAL_LEN_ULPS: f64 = 4.0;

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("ray_triangle", format!("seed-{name}"), bytes);
    let unit = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let dflt = (0.0, f32::INFINITY);
    let aim = flags::AIM | flags::DEFAULT_INTERVAL;
    let o = Vec3::new(0.3, -0.7, 5.0);
    // Plain hit, front and back.
    s.push(t(
        "plain",
        encode_ray_triangle(2, Vec3::new(0.25, 0.25, 5.0), -Vec3::Z, dflt, unit),
    ));
    s.push(t(
        "back",
        encode_ray_triangle(2, Vec3::new(0.25, 0.25, -5.0), Vec3::Z, dflt, unit),
    ));
    // Rays through vertices, edge midpoints and the centroid (exact targets).
    for (name, u, w) in [
        ("vertex0", 0.0, 0.0),
        ("vertex1", 1.0, 0.0),
        ("vertex2", 0.0, 1.0),
        ("edge01", 0.5, 0.0),
        ("edge12", 0.5, 0.5),
        ("edge20", 0.0, 0.5),
        ("centroid", 1.0 / 3.0, 1.0 / 3.0),
        ("outside", 0.75, 0.75),
    ] {
        s.push(t(
            &format!("aim-{name}"),
            encode_ray_triangle(aim, o, Vec3::new(u, w, 0.0), dflt, unit),
        ));
    }
    // A skinny, far triangle hit near its long edge (grazing, T8) and at 1e7 (T12).
    let skinny = [
        Vec3::new(1e7, 0.0, 0.0),
        Vec3::new(1e7 + 11.2, 0.1, 0.0),
        Vec3::new(1e7 + 1.4, 9.7, 0.3),
    ];
    s.push(t(
        "far-skinny-edge",
        encode_ray_triangle(aim, Vec3::ZERO, Vec3::new(0.5, 0.0, 0.0), dflt, skinny),
    ));
    // In-plane ray (T6) and ray parallel one ulp above (T7).
    s.push(t(
        "in-plane",
        encode_ray_triangle(2, Vec3::new(-1.0, 0.25, 0.0), Vec3::X, dflt, unit),
    ));
    s.push(t(
        "parallel-ulp-above",
        encode_ray_triangle(
            2,
            Vec3::new(-1.0, 0.25, f32::from_bits(1)),
            Vec3::X,
            dflt,
            unit,
        ),
    ));
    // Degenerate triangles (T9).
    s.push(t(
        "collinear",
        encode_ray_triangle(
            2,
            Vec3::new(0.5, 0.0, 1.0),
            -Vec3::Z,
            dflt,
            [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        ),
    ));
    s.push(t(
        "point",
        encode_ray_triangle(2, Vec3::new(1.0, 1.0, 2.0), -Vec3::Z, dflt, [Vec3::ONE; 3]),
    ));
    // Tiny and huge triangles (T10, T11).
    for (name, k) in [("tiny", 1e-20f32), ("huge", 1e19), ("subnormal", 1e-40)] {
        let v = [Vec3::ZERO, Vec3::new(k, 0.0, 0.0), Vec3::new(0.0, k, 0.0)];
        s.push(t(
            name,
            encode_ray_triangle(aim, Vec3::new(k, k, k), Vec3::new(0.25, 0.25, 0.0), dflt, v),
        ));
    }
    // Origin on the triangle (T13), hit exactly at t_max (T14), tiny t interval.
    s.push(t(
        "origin-on-triangle",
        encode_ray_triangle(2, Vec3::new(0.25, 0.25, 0.0), Vec3::Z, dflt, unit),
    ));
    s.push(t(
        "hit-at-tmax",
        encode_ray_triangle(0, Vec3::new(0.25, 0.25, 2.0), -Vec3::Z, (0.0, 2.0), unit),
    ));
    s.push(t(
        "tmax-just-short",
        encode_ray_triangle(
            0,
            Vec3::new(0.25, 0.25, 2.0),
            -Vec3::Z,
            (0.0, 2.0f32.next_down()),
            unit,
        ),
    ));
    // Unnormalised directions (T16), ±0 components (T17), dominant-axis ties (T18).
    for (name, d) in [
        ("dir-1e-10", Vec3::new(0.0, 0.0, -1e-10)),
        ("dir-1e10", Vec3::new(0.0, 0.0, -1e10)),
        ("neg-zero", Vec3::new(-0.0, -0.0, -1.0)),
        ("tie-xyz", Vec3::new(-1.0, -1.0, -1.0)),
    ] {
        s.push(t(
            name,
            encode_ray_triangle(2, Vec3::new(0.5, 0.4, 1.0), d, dflt, unit),
        ));
    }
    // Invalid rays (T19) and non-finite vertices (T20).
    for (name, o, d, iv) in [
        ("nan-origin", Vec3::new(f32::NAN, 0.0, 1.0), -Vec3::Z, dflt),
        (
            "inf-direction",
            Vec3::new(0.2, 0.2, 1.0),
            Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
            dflt,
        ),
        ("zero-direction", Vec3::new(0.2, 0.2, 1.0), Vec3::ZERO, dflt),
        (
            "nan-tmax",
            Vec3::new(0.2, 0.2, 1.0),
            -Vec3::Z,
            (0.0, f32::NAN),
        ),
        (
            "inverted-interval",
            Vec3::new(0.2, 0.2, 1.0),
            -Vec3::Z,
            (2.0, 1.0),
        ),
    ] {
        s.push(t(name, encode_ray_triangle(0, o, d, iv, unit)));
    }
    s.push(t(
        "inf-vertex",
        encode_ray_triangle(
            2,
            Vec3::new(0.2, 0.2, 1.0),
            -Vec3::Z,
            dflt,
            [Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::Y],
        ),
    ));
}
