//! The exact path of [`super::Watertight`] for a triangle its `f32` filter kept (a
//! [`Candidate`]), and the named tolerances of that path, each with its derivation: the exact
//! edge functions' verdict, then `t` ([`hit_t`]: the sheared form `Σ eᵢzᵢ / det` or the `f64`
//! plane form of [`plane_crossing`], whichever is the tighter where they agree; on x86-64 its
//! common case `common_t` first), the barycentrics and the normal ([`finish_exact_at`], out of
//! line as [`finish_exact`]), and the refusal of a plane the line certainly crosses behind the
//! origin ([`crossed_behind`]). `avx2.rs` is the same end compiled for AVX2 and FMA; `plane.rs`
//! and `behind.rs` refuse ahead of it triangles `crossed_behind` would refuse.

use super::WatertightRay;
use crate::float::{gamma, gamma_f64};
use crate::predicates::ORIENT3D_FILTER_REL;
use crate::ray::Ray;
use crate::triangle::TriangleHit;
use glam::{DVec3, Vec3};

/// Absolute floor of the projection error bounds: the `f32` subnormal spacing `2⁻¹⁴⁹`, times 4
/// (each projected value carries up to three roundings that may be absolute below the normal
/// range). World units (sheared).
pub(super) const TINY: f64 = 4.0 * 1.401_298_464_324_817e-45;

/// Relative bound below which the plane-form `t` is returned without evaluating the sheared
/// form: `2⁻²⁶`, a quarter of the `f32` unit roundoff, so the final rounding to `f32` dominates
/// whatever the other form could gain. Unitless.
const PLANE_EXACT_ENOUGH: f64 = 1.0 / 67_108_864.0;

/// The plane form's error bound on `t`, relative to `(|v0 − o|·N + |t|·|d|·N)/|d·n|` (`N` the
/// normal's rounding scale, [`crate::triangle::normal_f64`]), ray parameter: `γ₈`, a
/// first-order bound. `v0 − o` rounds once; each normal component three times against its
/// scale (two differences, the products' difference); the dot products add a product and two
/// sums: `wn` within `γ₇·|v0 − o|·N`, `dn` within `γ₆·|d|·N` (`d` exact); the division rounds
/// once more, `u·|t| ≤ u·|t|·|d|·N/|dn|`. The same constant in the portable and the AVX2
/// kernel.
pub(super) const PLANE_T_ERR: f64 = gamma_f64(8);

/// The slack of the plane form's box test, relative to the largest magnitude of the triangle's
/// box and of the crossing point (plus [`TINY`]), unitless: `γ₈`, as [`PLANE_T_ERR`], covering
/// the crossing's own rounding (`o + d·t`, two roundings a coordinate, and `t`'s error within
/// the box's scale). Which form of `t` is returned depends on it, so the portable and the AVX2
/// kernel share it.
pub(super) const PLANE_BOX_SLACK: f32 = gamma(8);

/// How closely the two forms must agree for the fast path, relative to `|t| + max|zᵢ|`:
/// `2⁻²⁰` (8 `f32` ulps of `2⁻²³`), far above the rounding of either form in a well-conditioned
/// case and far below any disagreement that signals a grazing ray. Unitless.
const AGREE_REL: f64 = 1.0 / 1_048_576.0;

/// A triangle the watertight test's `f32` filter did not reject, with all the rest of its hit
/// path reads: the ray and its preparation, the triangle, its sheared vertices `(x', y', z')`
/// ([`WatertightRay::project_triangle`]) and its exact edge functions ([`exact_edges`]).
/// Passed by value, so that each function on the path reads its fields where the caller put
/// them (on x86-64, the one out-of-line call per candidate receives one copy).
///
/// [`exact_edges`]: super::edges::exact_edges
#[derive(Clone, Copy, Debug)]
pub(super) struct Candidate<'a> {
    pub(super) ray: &'a Ray,
    pub(super) pre: &'a WatertightRay,
    pub(super) v: &'a [Vec3; 3],
    pub(super) sheared: ([f32; 3], [f32; 3], [f32; 3]),
    pub(super) edges: [f64; 3],
}

/// A plane kernel: [`plane_crossing`] or a SIMD level's version of it (the same bits).
pub(super) trait PlaneKernel: Fn(&[Vec3; 3], &Ray) -> Option<PlaneForm> {}

impl<F: Fn(&[Vec3; 3], &Ray) -> Option<PlaneForm>> PlaneKernel for F {}

/// [`hit_t`]'s common case, or `None` for the others: the `v0`-based normal does not cancel,
/// `d·n` clears its filter (`plane`: [`plane_crossing`] or a level's kernel with its bits),
/// and either the crossing is certainly behind the origin ([`PlaneForm::behind`]; then `−∞`,
/// outside the interval, where `hit_t` refuses the triangle) or it lies in the triangle's box
/// and the plane form is exact enough ([`plane_exact_enough`]). Each step is the one [`hit_t`]
/// takes, so where this returns `t`, `hit_t` returns the same `t` (or no hit for `−∞`).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) fn common_t(plane: impl PlaneKernel, c: Candidate<'_>, det: f64) -> Option<f64> {
    let plane = plane(c.v, c.ray)?;
    if plane.behind {
        return Some(f64::NEG_INFINITY);
    }
    let z = c.sheared.2;
    let t_sheared = sheared_t(c.edges, z, det);
    (plane.in_box && plane_exact_enough(&plane, t_sheared, z)).then_some(plane.t)
}

/// The plane form of `t` for the ray `ray` and the triangle `v` when the `v0`-based normal
/// does not cancel ([`crate::triangle::normal_f64_from_v0`]) and `d·n` clears the filter of
/// the exact orientation predicate; `None` otherwise (then [`hit_t`] decides). The portable
/// definition of the levels' plane kernels (`avx2.rs`): each returns these bits.
#[inline(always)]
pub(super) fn plane_crossing(v: &[Vec3; 3], ray: &Ray) -> Option<PlaneForm> {
    let normal = crate::triangle::normal_f64_from_v0(v)?;
    let d = ray.direction.as_dvec3();
    let dn = d.dot(normal.0);
    if !(dn.abs() > ORIENT3D_FILTER_REL * d.abs().dot(normal.1)) {
        return None;
    }
    Some(plane_form(ray, v, normal, d, dn, true))
}

/// The sheared form of `t`: `Σ eᵢzᵢ / det` in `f64` (see [`hit_t`]).
#[inline(always)]
fn sheared_t(edges: [f64; 3], z: [f32; 3], det: f64) -> f64 {
    (edges[0] * f64::from(z[0]) + edges[1] * f64::from(z[1]) + edges[2] * f64::from(z[2])) / det
}

/// The plane form of `t` ([`hit_t`]) and its error bound, and whether its crossing lies in
/// the triangle's box up to rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct PlaneForm {
    /// `((v0 − o)·n)/(d·n)`, ray parameter.
    pub(super) t: f64,
    /// Bound on the error of `t`, ray parameter.
    pub(super) err: f64,
    /// The crossing `o + d·t` lies in the triangle's box, padded by `γ₈` of the coordinates'
    /// magnitude and [`TINY`].
    pub(super) in_box: bool,
    /// The line certainly crosses the plane behind the origin, `t < 0` exactly, and the ray's
    /// `t_min ≥ 0`: no crossing in the interval ([`crossed_behind`]). Then the other fields
    /// are those of [`PlaneForm::BEHIND`].
    pub(super) behind: bool,
}

impl PlaneForm {
    /// The form of a crossing certainly behind the origin: no `t` to refine.
    pub(super) const BEHIND: Self = Self {
        t: f64::NEG_INFINITY,
        err: 0.0,
        in_box: false,
        behind: true,
    };
}

/// `true` when the ray's line crosses the plane certainly behind its origin and `t_min ≥ 0`:
/// `wn = (v0 − o)·n` clears the orientation filter against its permanent `w_nn = |v0 − o|·N`
/// ([`ORIENT3D_FILTER_REL`]: the same determinant as [`crate::predicates::orient3d`]`(v0, v1, v2,
/// o)`, evaluated along its third row, at most eight roundings a term), so its sign is exact,
/// and opposes the sign of `dn = d·n`, exact because the caller's filter passed: `t = wn/dn <
/// 0`. A ray leaving a surface ([`crate::hit::spawn_ray_to`]: its origin moved off the surface
/// by the hit point's error bound) meets the triangle it starts on, and the faces behind it,
/// only so; their rounded `t` would be of the order of its own error, and for a ray grazing
/// the plane the sheared form's sign may be wrong (test
/// `a_plane_crossed_behind_the_origin_is_no_hit`).
#[inline(always)]
pub(super) fn crossed_behind(ray: &Ray, wn: f64, w_nn: f64, dn: f64) -> bool {
    ray.t_min >= 0.0 && wn.abs() > ORIENT3D_FILTER_REL * w_nn && (wn < 0.0) != (dn < 0.0)
}

/// [`PlaneForm`] of the triangle `v` with normal `n` and its scale `nn`
/// ([`crate::triangle::normal_f64`]), for the ray direction `d` (in `f64`) with `dn = d·n ≠ 0`;
/// `dn_certain`: `dn` cleared its orientation filter (its sign is exact), which
/// [`PlaneForm::behind`] needs.
#[inline(always)]
fn plane_form(
    ray: &Ray,
    v: &[Vec3; 3],
    (n, nn): (DVec3, DVec3),
    d: DVec3,
    dn: f64,
    dn_certain: bool,
) -> PlaneForm {
    let w = v[0].as_dvec3() - ray.origin.as_dvec3();
    let (wn, w_nn) = (w.dot(n), w.abs().dot(nn));
    let t = wn / dn;
    // `crossed_behind` implies `t < 0` (the signs it certifies are the computed ones): the
    // crossings in front skip it.
    if t < 0.0 && dn_certain && crossed_behind(ray, wn, w_nn, dn) {
        return PlaneForm::BEHIND;
    }
    let err = PLANE_T_ERR * (w_nn + t.abs() * d.abs().dot(nn)) / dn.abs();
    // The plane crossing must lie in the triangle's box (up to rounding). If it does not, the
    // edge tests decided "inside" within the projection's rounding while the exact line
    // crosses the plane elsewhere (a grazing ray; found by the `bvh` fuzz target): then the
    // sheared `t`, consistent with those edge decisions (and with the neighbours', which keeps
    // a closed mesh closed), is the one.
    let p = ray.origin.as_dvec3() + d * t;
    let lo = v[0].min(v[1]).min(v[2]).as_dvec3();
    let hi = v[0].max(v[1]).max(v[2]).as_dvec3();
    let slack = f64::from(PLANE_BOX_SLACK)
        * (lo.abs().max(hi.abs()).max_element() + p.abs().max_element())
        + TINY;
    PlaneForm {
        t,
        err,
        in_box: p.cmpge(lo - slack).all() && p.cmple(hi + slack).all(),
        behind: false,
    }
}

/// The common case of [`hit_t`]: the two forms agree to well within `f32` rounding
/// ([`AGREE_REL`] of `|t_sheared| + max|zᵢ|`), and the plane form's own bound is below it too
/// ([`PLANE_EXACT_ENOUGH`]); nothing can beat it once rounded to `f32`.
#[inline(always)]
fn plane_exact_enough(plane: &PlaneForm, t_sheared: f64, z: [f32; 3]) -> bool {
    let max_abs_z = f64::from(z[0].abs().max(z[1].abs()).max(z[2].abs()));
    plane.err <= PLANE_EXACT_ENOUGH * plane.t.abs()
        && (plane.t - t_sheared).abs() <= AGREE_REL * (t_sheared.abs() + max_abs_z)
}

/// `t` of a hit that passed the edge tests (see [`Watertight`]): the plane form when its
/// crossing lies in the triangle's box, it agrees with the sheared form within their bounds and
/// its own bound is the smaller; the sheared form otherwise. The two forms and their bounds:
///
/// * **sheared**: `Σ eᵢzᵢ / det`, a convex combination of the vertices' sheared depths, with
///   the smaller of their span and a first-order bound in the manner of pbrt-v3's `δt`
///   (*Physically Based Rendering* 3rd ed., §3.9.6) but per vertex and per edge (a sliver's
///   long coordinate does not inflate the error of its short one), with the projection's
///   rounding measured against the unscaled depth `|(p − o)_kz|` so any direction length works;
/// * **plane**: `((v0 − o)·n)/(d·n)`, `n = (v1 − v0) × (v2 − v0)`, all in `f64`, with the
///   bound `γ₈·(|v0 − o|·N + |t|·|d|·N)/|d·n|`, `N = |v1 − v0| × |v2 − v0|` taken with
///   absolute values (the rounding of the `f64` differences, the cross and dot products).
///
/// `None` for a degenerate triangle or a ray in its plane, decided exactly
/// ([`crate::triangle::degenerate_or_coplanar`]), and for a crossing certainly behind the origin
/// ([`PlaneForm::behind`]). When the `f64` plane form cannot be evaluated although
/// the exact `d·n` is not zero (its `f64` normal cancelled: vertices spanning more than `2²⁹`),
/// the sheared form is the answer.
///
/// [`Watertight`]: super::Watertight
// Only hits get here, and on x86-64 only those whose `t` is not the common case
// ([`common_t`], tried first by `finish_exact_at`): there a cold call that starts over, so the
// hot path keeps only its own values in registers. Out of line elsewhere too: see
// `exact_candidate`.
#[cfg_attr(target_arch = "x86_64", cold, inline(never))]
#[cfg_attr(not(target_arch = "x86_64"), inline(never))]
pub(super) fn hit_t(c: Candidate<'_>, det: f64) -> Option<f64> {
    let Candidate {
        ray,
        pre,
        v,
        sheared: (x, y, z),
        edges,
    } = c;
    let (shear, d_kz) = (pre.shear, ray.direction[pre.axes()[2]]);
    let t_sheared = sheared_t(edges, z, det);
    let normal = crate::triangle::normal_f64(v);
    let (n, nn) = normal;
    let d = ray.direction.as_dvec3();
    let dn = d.dot(n);
    // `d·n` is `det[v1 − v0, v2 − v0, d]` evaluated in `f64` (from the base vertex
    // `normal_f64` chose: a cyclic rotation, the same determinant), with the forward error
    // bound of the exact orientation predicate: beyond it its sign is exact and the triangle
    // is neither degenerate nor parallel to the ray; within it, the exact predicate decides.
    let dn_certain = dn.abs() > ORIENT3D_FILTER_REL * d.abs().dot(nn);
    if !dn_certain {
        if crate::triangle::degenerate_or_coplanar(ray, v) {
            return None;
        }
        if n == DVec3::ZERO || dn == 0.0 {
            return Some(t_sheared);
        }
    }
    let plane = plane_form(ray, v, normal, d, dn, dn_certain);
    if plane.behind {
        return None;
    }
    if !plane.in_box {
        return Some(t_sheared);
    }
    if plane_exact_enough(&plane, t_sheared, z) {
        return Some(plane.t);
    }
    let (t_plane, err_plane) = (plane.t, plane.err);

    // Sheared form. Per vertex: the magnitudes that the projection x' = a_kx − s_x·a_kz rounds
    // against (|a_kx| ≤ |x'| + |s_x·a_kz|, and |a_kz| = |z'|·|d_kz| up to z′'s roundings), the
    // resulting errors of x', y', z', then each edge function's error from them (first order,
    // plus the f64 evaluation), and finally t's (the edge errors also perturb det).
    let g3 = 1.0 + f64::from(gamma(3));
    let proj = f64::from(gamma(4));
    let (sx, sy) = (f64::from(shear.x).abs(), f64::from(shear.y).abs());
    let dkz = f64::from(d_kz).abs();
    let mut dx = [0.0f64; 3];
    let mut dy = [0.0f64; 3];
    let mut dz = [0.0f64; 3];
    for i in 0..3 {
        let az = f64::from(z[i]).abs() * dkz * g3;
        dx[i] = proj * (f64::from(x[i]).abs() + 2.0 * sx * az) + TINY;
        dy[i] = proj * (f64::from(y[i]).abs() + 2.0 * sy * az) + TINY;
        dz[i] = f64::from(gamma(3)) * f64::from(z[i]).abs() + TINY;
    }
    let mut sum_err = 0.0;
    let mut num_err = 0.0;
    for (i, &(p, q)) in [(2usize, 1usize), (0, 2), (1, 0)].iter().enumerate() {
        let (xp, yp, xq, yq) = (
            f64::from(x[p]).abs(),
            f64::from(y[p]).abs(),
            f64::from(x[q]).abs(),
            f64::from(y[q]).abs(),
        );
        let err = (xp + dx[p]) * dy[q]
            + yq * dx[p]
            + (yp + dy[p]) * dx[q]
            + xq * dy[p]
            + gamma_f64(1) * (xp * yq + yp * xq);
        sum_err += err;
        let zi = f64::from(z[i]).abs();
        num_err += edges[i].abs() * dz[i] + err * (zi + dz[i]);
    }
    let denom = det.abs() - sum_err;
    let first_order = if denom > 0.0 {
        (num_err + t_sheared.abs() * sum_err) / denom + gamma_f64(4) * t_sheared.abs()
    } else {
        f64::INFINITY
    };
    // A convex combination of the depths (the edge functions share one sign) cannot leave
    // their range, whatever the rounding of the barycentrics: the depth span also bounds it.
    let min_z = f64::from(z[0].min(z[1]).min(z[2]));
    let max_dz = dz[0].max(dz[1]).max(dz[2]);
    let span = f64::from(z[0].max(z[1]).max(z[2])) - min_z + 2.0 * max_dz;
    let err_sheared = span.min(first_order);

    // The plane form only refines the sheared one: it must lie within the sheared form's
    // first-order bound (else the edge decisions were within rounding and the exact line
    // crosses the plane away from the reported barycentrics), and be the tighter of the two.
    let consistent = (t_plane - t_sheared).abs() <= first_order + err_plane;
    Some(if consistent && err_plane <= err_sheared {
        t_plane
    } else {
        t_sheared
    })
}

/// The exact edge functions' verdict, then the hit: `t` ([`hit_t`]), barycentrics and normal,
/// with the common case of `t` from the plane kernel `plane` ([`common_t`], x86-64 only; the
/// same bits from every kernel). Each level's out-of-line end of the hit path
/// ([`finish_exact`], `avx2::finish_exact`) inlines it, compiled with that level's target
/// features, so that its plane kernel inlines here.
#[inline(always)]
pub(super) fn finish_exact_at(plane: impl PlaneKernel, c: Candidate<'_>) -> Option<TriangleHit> {
    let Candidate { ray, v, edges, .. } = c;
    let [e0, e1, e2] = edges;
    // Mixed signs (a negative and a positive edge function) as one comparison, `lo·hi < 0`
    // with `lo`, `hi` the smallest and largest: a branch on either sign alone would be
    // mispredicted half the time (front and back faces are equally common). Exact: the edge
    // functions are finite and each is zero or at least `2⁻²⁹⁸` in magnitude (a difference of
    // products of `f32` values), so the product neither overflows nor underflows to zero.
    let min = |a: f64, b: f64| if a < b { a } else { b };
    let max = |a: f64, b: f64| if a > b { a } else { b };
    if min(min(e0, e1), e2) * max(max(e0, e1), e2) < 0.0 {
        return None;
    }
    let det = e0 + e1 + e2;
    if !(det != 0.0 && det.is_finite()) {
        return None;
    }
    // On x86-64 the common case of `t` first, alone (see `hit_t`); elsewhere `hit_t` only
    // (the Cortex-M4F image's size).
    #[cfg(target_arch = "x86_64")]
    let common = common_t(plane, c, det);
    #[cfg(not(target_arch = "x86_64"))]
    let common = {
        let _ = plane;
        None
    };
    let t64 = match common {
        Some(t) => t,
        None => hit_t(c, det)?,
    };
    let t = t64 as f32;
    if !ray.contains(t) {
        return None;
    }
    let inv = 1.0 / det;
    Some(TriangleHit {
        t,
        b1: (e1 * inv) as f32,
        b2: (e2 * inv) as f32,
        ng: crate::triangle::geometric_normal(v, (v[1] - v[0]).cross(v[2] - v[0])),
        // det = −2·(signed area of the projected triangle): positive when the triangle is
        // clockwise in the sheared plane, i.e. when its normal opposes the ray.
        front_face: det > 0.0,
    })
}

/// [`finish_exact_at`] with the portable plane kernel ([`plane_crossing`]): out of line on
/// x86-64, inlined elsewhere (see [`exact_candidate`]).
///
/// [`exact_candidate`]: super::exact_candidate
#[cfg_attr(target_arch = "x86_64", inline(never))]
#[cfg_attr(not(target_arch = "x86_64"), inline)]
pub(super) fn finish_exact(c: Candidate<'_>) -> Option<TriangleHit> {
    finish_exact_at(plane_crossing, c)
}
