//! Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013).

use super::{LANES, TriangleHit, TriangleIntersector, TriangleLanes};
use crate::float::{diff_of_products_exact_sign, diff_of_products_sign_filter, gamma, gamma_f64};
use crate::predicates::ORIENT3D_FILTER_REL;
use crate::ray::Ray;
use crate::simd::F32x4;
use crate::simd::level::{Portable, Sheared8, SimdLevel};
use glam::{DVec3, Vec3};

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx2;
mod behind;
mod plane;
mod rays;

pub use plane::{BehindPlane, PlaneRay};
pub use rays::{RAY_LANES, ShearedRays};

/// Per-ray data of the watertight test: the axis permutation that makes the largest direction
/// component `z`, and the shear that maps the ray to the `+z` axis through the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WatertightRay {
    /// Permuted axes `(kx, ky, kz)`; `kz = argmax |d_i|` (ties: lowest index), `kx, ky` follow
    /// cyclically and are swapped when `d_kz < 0` so that the permutation and the scaling by
    /// `1/d_kz` together preserve orientation.
    pub k: [usize; 3],
    /// Shear `(d_kx/d_kz, d_ky/d_kz, 1/d_kz)`.
    pub shear: Vec3,
}

impl WatertightRay {
    /// Prepares `ray`; `None` for an invalid ray.
    #[inline(always)]
    #[must_use]
    pub fn new(ray: &Ray) -> Option<Self> {
        ray.is_valid().then(|| Self::of_valid(ray))
    }

    /// Prepares `ray`, which the caller has checked ([`Ray::is_valid`]); for another ray the
    /// result is meaningless (never undefined: no check is skipped that memory safety needs).
    #[inline(always)]
    #[must_use]
    pub fn of_valid(ray: &Ray) -> Self {
        let d = ray.direction;
        let [kx, ky, kz] = super::projection_axes(d);
        // The three quotients in one four-lane division (each lane the same IEEE quotient).
        // Indexed through a four-lane array with `& 3`: no bounds check, no branch.
        let c = [d.x, d.y, d.z, 0.0];
        let shear = glam::Vec3A::new(c[kx & 3], c[ky & 3], 1.0) / glam::Vec3A::splat(c[kz & 3]);
        Self {
            k: [kx, ky, kz],
            shear: shear.into(),
        }
    }

    /// `k` as indices the compiler knows are below 3: `min(2)` keeps every index in range
    /// without a bounds check (each is 0, 1 or 2 already).
    #[inline(always)]
    fn axes(&self) -> [usize; 3] {
        let [kx, ky, kz] = self.k;
        [kx.min(2), ky.min(2), kz.min(2)]
    }

    /// The lanes of `lanes` among whose three `f32` edge functions (the filter of
    /// [`Watertight`]) two have certain, opposite signs: the triangles both watertight tests
    /// miss (the exact signs of those two already differ, whatever the third). The same
    /// `f32` operations as the projection and the scalar filter, lane by lane (no
    /// fused multiply-add), so a lane is reported exactly when the scalar test rejects it on
    /// its `f32` signs; NaN lanes (unused ones among them) are never reported.
    #[inline(always)]
    #[must_use]
    pub fn certain_misses(&self, origin: Vec3, lanes: &TriangleLanes) -> u32 {
        let [kx, ky, kz] = self.axes();
        let o = origin.to_array();
        let (ox, oy, oz) = (
            F32x4::splat(o[kx]),
            F32x4::splat(o[ky]),
            F32x4::splat(o[kz]),
        );
        let (sx, sy) = (F32x4::splat(self.shear.x), F32x4::splat(self.shear.y));
        // Sheared 2-D coordinates of each vertex: (p_kx − o_kx) − s_x·(p_kz − o_kz), …
        let project = |p: &[[f32; LANES]; 3]| {
            let z = F32x4::load(&p[kz]).sub(oz);
            (
                F32x4::load(&p[kx]).sub(ox).sub(sx.mul(z)),
                F32x4::load(&p[ky]).sub(oy).sub(sy.mul(z)),
            )
        };
        let [p0, p1, p2] = &lanes.v;
        let ((ax, ay), (bx, by), (cx, cy)) = (project(p0), project(p1), project(p2));
        // The filter of `intersect_prepared`, argument for argument.
        let e = [
            cx.mul(by).sub(cy.mul(bx)).sign_bits(),
            ax.mul(cy).sub(ay.mul(cx)).sign_bits(),
            bx.mul(ay).sub(by.mul(ax)).sign_bits(),
        ];
        // A zero or NaN edge sets neither bit: only certain signs count.
        let any = e[0] | e[1] | e[2];
        any & (any >> 4) & 0xF
    }

    /// [`WatertightRay::certain_misses`] of two groups, `first` (bits 0–3) and `second`
    /// (bits 4–7), with `level`'s eight-lane kernel when it has one (the same bits either
    /// way).
    #[inline(always)]
    #[must_use]
    pub fn certain_misses2<L: SimdLevel>(
        &self,
        level: L,
        origin: Vec3,
        first: &TriangleLanes,
        second: &TriangleLanes,
    ) -> u32 {
        let k = self.axes();
        let o = origin.to_array();
        let q = Sheared8 {
            first: permuted_rows(first, k),
            second: permuted_rows(second, k),
            origin: [o[k[0]], o[k[1]], o[k[2]]],
            shear: [self.shear.x, self.shear.y],
        };
        level.certain_misses8(&q).unwrap_or_else(|| {
            super::pair_mask(
                self.certain_misses(origin, first),
                self.certain_misses(origin, second),
            )
        })
    }

    /// How the ray crosses triangle `v` when **each point of the plane is counted once**: `+1`
    /// or `−1` (the sign of the watertight test's `det`, `+1` when the triangle faces the ray,
    /// as [`TriangleHit::front_face`]) when the ray, moved by an infinitesimal `(ε, ε²)` in
    /// the sheared plane, passes strictly inside the triangle; `0` otherwise.
    ///
    /// Where the closed test ([`Watertight`]) reports a ray through an edge shared by two
    /// triangles for both, and through a vertex for its whole fan, this rule (symbolic
    /// perturbation: the half-open "top-left" rule of rasterisers) keeps exactly one of them,
    /// and counts a silhouette edge (one triangle facing the ray, its neighbour facing away)
    /// for both or neither: summed over a closed, consistently oriented mesh, the signs are
    /// the change of its winding number along the line, exactly, whatever edge or vertex the
    /// line passes through. Exact: the edge functions are the exact `f64` differences of
    /// exact products of the sheared coordinates, and a zero one is decided by the sign of an
    /// `f32` coordinate difference, which rounding cannot change. `0` for a triangle whose
    /// projection is degenerate (`det = 0`). A non-zero result implies that the closed test
    /// reports the crossing (when its `t` lies in the interval).
    #[must_use]
    pub fn crossing_sign(&self, origin: Vec3, v: &[Vec3; 3]) -> i8 {
        let (x, y, _) = self.project_triangle(origin, v);
        let ([ax, bx, cx], [ay, by, cy]) = (x, y);
        // Edge functions at the ray (the sheared origin) of the edges C→B, A→C, B→A, the
        // operands of `Watertight`'s edges, and each edge's direction T − S.
        let [e0, e1, e2] = exact_edges(x, y);
        let edges = [
            (e0, bx - cx, by - cy),
            (e1, cx - ax, cy - ay),
            (e2, ax - bx, ay - by),
        ];
        // E_ST(p + (ε, ε²)) = E_ST(p) + d_x·ε² − d_y·ε: when E is exactly zero its sign is
        // −sign(d_y), or sign(d_x) for a horizontal edge (d = 0 only for a degenerate
        // projection, whose det is 0).
        let sign = |x: f64| i8::from(x > 0.0) - i8::from(x < 0.0);
        let perturbed = |(e, dx, dy): (f64, f32, f32)| -> i8 {
            if e != 0.0 {
                sign(e)
            } else if dy != 0.0 {
                -sign(f64::from(dy))
            } else {
                sign(f64::from(dx))
            }
        };
        let s = edges.map(perturbed);
        if s[0] != 0 && s[0] == s[1] && s[1] == s[2] {
            s[0]
        } else {
            0
        }
    }

    /// The three vertices projected with [`WatertightRay::project`]: `([x'], [y'], [z'])`.
    #[inline(always)]
    pub(super) fn project_triangle(
        &self,
        origin: Vec3,
        v: &[Vec3; 3],
    ) -> ([f32; 3], [f32; 3], [f32; 3]) {
        let (ax, ay, az) = self.project(origin, v[0]);
        let (bx, by, bz) = self.project(origin, v[1]);
        let (cx, cy, cz) = self.project(origin, v[2]);
        ([ax, bx, cx], [ay, by, cy], [az, bz, cz])
    }

    /// The sheared 2-D coordinates of `p − o` and its scaled depth `(x', y', z')`. Plain `f32`
    /// operations (never fused), so the result is a deterministic function of the vertex: a
    /// vertex shared by several triangles projects to the same point in all of them.
    #[inline(always)]
    fn project(&self, origin: Vec3, p: Vec3) -> (f32, f32, f32) {
        let a = p - origin;
        // Indexed through a four-lane array with `& 3`: no bounds check (`k` holds axes 0–2).
        let a = [a.x, a.y, a.z, 0.0];
        let [kx, ky, kz] = self.k;
        let z = a[kz & 3];
        (
            a[kx & 3] - self.shear.x * z,
            a[ky & 3] - self.shear.y * z,
            self.shear.z * z,
        )
    }
}

/// The watertight test with **exact edge signs**: the three 2-D edge functions are `f64`
/// differences of `f64` products of the sheared `f32` coordinates. Each product is exact, so
/// the single rounding of the difference keeps the exact sign, and zero means exactly on the
/// edge. `det`, `t` and the barycentrics are computed in `f64` and rounded once.
///
/// Edges and vertices are **closed**: a point exactly on an edge is inside. Mixed signs or
/// `det = 0` (ray in the triangle's plane, or a degenerate triangle) give no hit; so does a
/// triangle whose plane the line certainly crosses behind the origin while `t_min ≥ 0`
/// (the exact signs of the origin's and the direction's orientation against the plane,
/// decided with the plane form of `t`, whatever the rounded `t` would be: the triangle a
/// spawned ray starts on, and the faces behind it).
///
/// `t` is the sheared `Σ eᵢzᵢ / det` (consistent with the edge decisions, accurate relative to
/// the vertices' depth span along the ray) unless the plane equation `((v0 − o)·n)/(d·n)` in
/// `f64` is the tighter of the two and agrees with it: its crossing lies in the triangle's box
/// and within the sheared form's bound. That fixes the case where the `f32` depths swamp `t`
/// (an origin near the plane, seen along a dominant axis the triangle extends in) without
/// trusting the plane form for grazing rays whose edge decisions were within rounding.
///
/// This is the default intersector; it handles triangles from `1e-20` to `1e20` (`f64` has the
/// range). Domain of the exact edge signs: the sheared coordinates carry only relative `f32`
/// rounding while every quantity of the projection (`p − o`, the shear `d_i/d_kz`, its
/// products and the sheared `x'`, `y'`) is a normal number or zero. A direction component more
/// than `2^126` times smaller than the dominant one, or a configuration at the subnormal scale
/// (`≲ 1e-38`), rounds absolutely instead: the test then sees a slightly displaced ray (still
/// the same ray for every triangle, so still watertight, but a BVH's exact box test may cull a
/// vertex or edge hit that a brute-force loop reports).
///
/// **Domain of agreement with [`super::F64Reference`]** (hit/miss where the reference's edge
/// functions and `t` are clear of their error bounds; then `t` and the barycentrics within
/// those bounds; the fuzz property `ray_triangle` checks exactly this): the sheared
/// magnitudes `X = |(p − o)_kx| + |s_x·(p − o)_kz|`, `Y` likewise and `Z = |(p − o)_kz / d_kz|`
/// of every vertex `p` all at most `2⁶⁰` (about `10¹⁸` from the ray's origin), the dominant
/// direction component `|d_kz| ≥ 2⁻¹⁰⁰`, and no projected quantity (`p − o`, the shear
/// products, `x'`, `y'`) subnormal in `f32` or beyond `f32::MAX`. Inside it an acceleration
/// structure's closest hit equals a brute-force loop's (same triangle, same hit record; the
/// `bvh`, `bvh_load`, `grid` and `kdtree` fuzz properties check this). Outside it a hit is still a
/// crossing of a triangle within rounding of the given one, and an acceleration structure's
/// answer a genuine hit no nearer than a brute-force loop's, but not necessarily the same one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Watertight;

/// The watertight test as in pbrt-v3: edge functions in `f32`, recomputed in `f64` only when one
/// of them is exactly zero. Sound by monotone rounding (an `f32` difference of rounded products
/// has the correct sign or is zero), provided no product overflows or underflows: very large
/// (≳ 1e19) or very small (≲ 1e-19) triangles can be missed. **Domain** (where its hit/miss,
/// `t` and barycentrics agree with [`super::F64Reference`] as [`Watertight`]'s do, and its
/// barycentrics stay within the contract's slack of `[0, 1]`): [`Watertight`]'s domain, every
/// vertex coordinate relative to the origin zero or in `[1e-19, 1e19]`, `|det| ≥ 2⁻¹⁰⁰` and
/// `Σ|eᵢzᵢ| ≤ 2¹²⁰` (sheared units, `det = e₀ + e₁ + e₂`). `t = Σ eᵢzᵢ / det` in `f32`, so
/// for an origin near the triangle's plane `t`'s rounding can exceed `t` itself (pbrt-v3
/// guards `t > 0` with an error bound `δt`, which in turn refuses genuine grazing hits; this
/// variant has neither). Kept for the cost/accuracy comparison (`watertight-f32`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WatertightF32;

/// Absolute floor of the projection error bounds: the `f32` subnormal spacing `2⁻¹⁴⁹`, times 4
/// (each projected value carries up to three roundings that may be absolute below the normal
/// range). World units (sheared).
const TINY: f64 = 4.0 * 1.401_298_464_324_817e-45;

/// Relative bound below which the plane-form `t` is returned without evaluating the sheared
/// form: `2⁻²⁶`, a quarter of the `f32` unit roundoff, so the final rounding to `f32` dominates
/// whatever the other form could gain. Unitless.
const PLANE_EXACT_ENOUGH: f64 = 1.0 / 67_108_864.0;

/// The plane form's error bound on `t`, relative to `(|v0 − o|·N + |t|·|d|·N)/|d·n|` (`N` the
/// normal's rounding scale, [`super::normal_f64`]), ray parameter: `γ₈`, a first-order bound.
/// `v0 − o` rounds once; each normal component three times against its scale (two
/// differences, the products' difference); the dot products add a product and two sums: `wn`
/// within `γ₇·|v0 − o|·N`, `dn` within `γ₆·|d|·N` (`d` exact); the division rounds once more,
/// `u·|t| ≤ u·|t|·|d|·N/|dn|`. The same constant in the portable and the AVX2 kernel.
const PLANE_T_ERR: f64 = gamma_f64(8);

/// The slack of the plane form's box test, relative to the largest magnitude of the triangle's
/// box and of the crossing point (plus [`TINY`]), unitless: `γ₈`, as [`PLANE_T_ERR`], covering
/// the crossing's own rounding (`o + d·t`, two roundings a coordinate, and `t`'s error within
/// the box's scale). Which form of `t` is returned depends on it, so the portable and the AVX2
/// kernel share it.
const PLANE_BOX_SLACK: f32 = gamma(8);

/// How closely the two forms must agree for the fast path, relative to `|t| + max|zᵢ|`:
/// `2⁻²⁰` (8 `f32` ulps of `2⁻²³`), far above the rounding of either form in a well-conditioned
/// case and far below any disagreement that signals a grazing ray. Unitless.
const AGREE_REL: f64 = 1.0 / 1_048_576.0;

/// A triangle the watertight test's `f32` filter did not reject, with all the rest of its hit
/// path reads: the ray and its preparation, the triangle, its sheared vertices `(x', y', z')`
/// ([`WatertightRay::project_triangle`]) and its exact edge functions ([`exact_edges`]).
/// Passed by value, so that each function on the path reads its fields where the caller put
/// them (on x86-64, the one out-of-line call per candidate receives one copy).
#[derive(Clone, Copy, Debug)]
struct Candidate<'a> {
    ray: &'a Ray,
    pre: &'a WatertightRay,
    v: &'a [Vec3; 3],
    sheared: ([f32; 3], [f32; 3], [f32; 3]),
    edges: [f64; 3],
}

/// A plane kernel: [`plane_crossing`] or a SIMD level's version of it (the same bits).
trait PlaneKernel: Fn(&[Vec3; 3], &Ray) -> Option<PlaneForm> {}

impl<F: Fn(&[Vec3; 3], &Ray) -> Option<PlaneForm>> PlaneKernel for F {}

/// [`hit_t`]'s common case, or `None` for the others: the `v0`-based normal does not cancel,
/// `d·n` clears its filter (`plane`: [`plane_crossing`] or a level's kernel with its bits),
/// and either the crossing is certainly behind the origin ([`PlaneForm::behind`]; then `−∞`,
/// outside the interval, where `hit_t` refuses the triangle) or it lies in the triangle's box
/// and the plane form is exact enough ([`plane_exact_enough`]). Each step is the one [`hit_t`]
/// takes, so where this returns `t`, `hit_t` returns the same `t` (or no hit for `−∞`).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn common_t(plane: impl PlaneKernel, c: Candidate<'_>, det: f64) -> Option<f64> {
    let plane = plane(c.v, c.ray)?;
    if plane.behind {
        return Some(f64::NEG_INFINITY);
    }
    let z = c.sheared.2;
    let t_sheared = sheared_t(c.edges, z, det);
    (plane.in_box && plane_exact_enough(&plane, t_sheared, z)).then_some(plane.t)
}

/// The plane form of `t` for the ray `ray` and the triangle `v` when the `v0`-based normal
/// does not cancel ([`super::normal_f64_from_v0`]) and `d·n` clears the filter of the exact
/// orientation predicate; `None` otherwise (then [`hit_t`] decides). The portable
/// definition of the levels' plane kernels (`avx2.rs`): each returns these bits.
#[inline(always)]
fn plane_crossing(v: &[Vec3; 3], ray: &Ray) -> Option<PlaneForm> {
    let normal = super::normal_f64_from_v0(v)?;
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
struct PlaneForm {
    /// `((v0 − o)·n)/(d·n)`, ray parameter.
    t: f64,
    /// Bound on the error of `t`, ray parameter.
    err: f64,
    /// The crossing `o + d·t` lies in the triangle's box, padded by `γ₈` of the coordinates'
    /// magnitude and [`TINY`].
    in_box: bool,
    /// The line certainly crosses the plane behind the origin, `t < 0` exactly, and the ray's
    /// `t_min ≥ 0`: no crossing in the interval ([`crossed_behind`]). Then the other fields
    /// are those of [`PlaneForm::BEHIND`].
    behind: bool,
}

impl PlaneForm {
    /// The form of a crossing certainly behind the origin: no `t` to refine.
    const BEHIND: Self = Self {
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
fn crossed_behind(ray: &Ray, wn: f64, w_nn: f64, dn: f64) -> bool {
    ray.t_min >= 0.0 && wn.abs() > ORIENT3D_FILTER_REL * w_nn && (wn < 0.0) != (dn < 0.0)
}

/// [`PlaneForm`] of the triangle `v` with normal `n` and its scale `nn`
/// ([`super::normal_f64`]), for the ray direction `d` (in `f64`) with `dn = d·n ≠ 0`;
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
/// ([`super::degenerate_or_coplanar`]), and for a crossing certainly behind the origin
/// ([`PlaneForm::behind`]). When the `f64` plane form cannot be evaluated although
/// the exact `d·n` is not zero (its `f64` normal cancelled: vertices spanning more than `2²⁹`),
/// the sheared form is the answer.
// Only hits get here, and on x86-64 only those whose `t` is not the common case
// ([`common_t`], tried first by `finish_exact_at`): there a cold call that starts over, so the
// hot path keeps only its own values in registers. Out of line elsewhere too: see
// `exact_candidate`.
#[cfg_attr(target_arch = "x86_64", cold, inline(never))]
#[cfg_attr(not(target_arch = "x86_64"), inline(never))]
fn hit_t(c: Candidate<'_>, det: f64) -> Option<f64> {
    let Candidate {
        ray,
        pre,
        v,
        sheared: (x, y, z),
        edges,
    } = c;
    let (shear, d_kz) = (pre.shear, ray.direction[pre.k[2]]);
    let t_sheared = sheared_t(edges, z, det);
    let normal = super::normal_f64(v);
    let (n, nn) = normal;
    let d = ray.direction.as_dvec3();
    let dn = d.dot(n);
    // `d·n` is `det[v1 − v0, v2 − v0, d]` evaluated in `f64` (from the base vertex
    // `normal_f64` chose: a cyclic rotation, the same determinant), with the forward error
    // bound of the exact orientation predicate: beyond it its sign is exact and the triangle
    // is neither degenerate nor parallel to the ray; within it, the exact predicate decides.
    let dn_certain = dn.abs() > ORIENT3D_FILTER_REL * d.abs().dot(nn);
    if !dn_certain {
        if super::degenerate_or_coplanar(ray, v) {
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
fn finish_exact_at(plane: impl PlaneKernel, c: Candidate<'_>) -> Option<TriangleHit> {
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
        ng: super::geometric_normal(v, (v[1] - v[0]).cross(v[2] - v[0])),
        // det = −2·(signed area of the projected triangle): positive when the triangle is
        // clockwise in the sheared plane, i.e. when its normal opposes the ray.
        front_face: det > 0.0,
    })
}

/// [`finish_exact_at`] with the portable plane kernel ([`plane_crossing`]): out of line on
/// x86-64, inlined elsewhere (see [`exact_candidate`]).
#[cfg_attr(target_arch = "x86_64", inline(never))]
#[cfg_attr(not(target_arch = "x86_64"), inline)]
fn finish_exact(c: Candidate<'_>) -> Option<TriangleHit> {
    finish_exact_at(plane_crossing, c)
}

/// The three edge functions `e0 = c_x·b_y − c_y·b_x`, `e1 = a_x·c_y − a_y·c_x`,
/// `e2 = b_x·a_y − b_y·a_x` of the sheared 2-D vertices `x`, `y`, each evaluated as
/// `diff(p, q, r, s) = p·q − r·s` (the evaluation decides the precision).
#[inline(always)]
fn edges<T>(x: [f32; 3], y: [f32; 3], diff: impl Fn(f32, f32, f32, f32) -> T) -> [T; 3] {
    let ([ax, bx, cx], [ay, by, cy]) = (x, y);
    [
        diff(cx, by, cy, bx),
        diff(ax, cy, ay, cx),
        diff(bx, ay, by, ax),
    ]
}

/// The edge functions of [`edges`] in plain `f32`: the filter of the watertight family, whose
/// signs are exact wherever non-zero and not NaN ([`diff_of_products_sign_filter`]).
#[inline(always)]
pub(super) fn filter_edges(x: [f32; 3], y: [f32; 3]) -> [f32; 3] {
    edges(x, y, diff_of_products_sign_filter)
}

/// The edge functions of [`edges`], each the `f64` difference of exact `f64` products:
/// exact signs, and zero exactly on the edge ([`diff_of_products_exact_sign`]).
#[inline(always)]
pub(super) fn exact_edges(x: [f32; 3], y: [f32; 3]) -> [f64; 3] {
    edges(x, y, diff_of_products_exact_sign)
}

/// `true` when `e` holds both a negative and a positive value (zeros and NaN count as
/// neither): the ray passes outside the triangle.
#[inline(always)]
pub(super) fn mixed_signs(e: &[f32; 3]) -> bool {
    let neg = (e[0] < 0.0) | (e[1] < 0.0) | (e[2] < 0.0);
    let pos = (e[0] > 0.0) | (e[1] > 0.0) | (e[2] > 0.0);
    neg & pos
}

/// The watertight family ([`Watertight`], [`WatertightF32`], [`super::WatertightF32Exact`]):
/// the ray prepared as a [`WatertightRay`] (axis permutation and shear), and a test of one
/// triangle that rejects every triangle two of whose three `f32` edge functions (the filter
/// of [`WatertightRay::certain_misses`]) have certain, opposite signs. Each member supplies
/// its name and its test; [`TriangleIntersector`] (preparation and the four-lane cull) comes
/// with it.
pub trait ShearedTest: Copy + Send + Sync {
    /// The variant's name ([`TriangleIntersector::name`]).
    const NAME: &'static str;

    /// [`TriangleIntersector::intersect_prepared`].
    fn hit_sheared(&self, pre: &WatertightRay, ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit>;

    /// [`ShearedTest::hit_sheared`] at SIMD `level`, for a triangle the family's cull kept
    /// ([`TriangleIntersector::intersect_prepared_on`]: the same answer for every triangle, at
    /// every level). The default ignores the level.
    #[inline(always)]
    fn hit_sheared_on<L: SimdLevel>(
        &self,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        let _ = level;
        self.hit_sheared(pre, ray, v)
    }

    /// [`TriangleIntersector::behind_plane`]. The default has none ([`Watertight`]'s is the
    /// plane of its exact path's kernel, on x86-64).
    #[inline(always)]
    fn behind_plane(&self, v: &[Vec3; 3]) -> Option<BehindPlane> {
        let _ = v;
        None
    }

    /// [`TriangleIntersector::behind_misses2`]: the lanes among `keep` this test certainly
    /// misses because the line crosses their plane behind the origin. The default refuses
    /// none ([`Watertight`] refuses them with [`WatertightRay::behind_misses2`]).
    #[inline(always)]
    fn behind_misses2<L: SimdLevel>(
        &self,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        lanes: [&TriangleLanes; 2],
        keep: u32,
    ) -> u32 {
        let _ = (level, pre, ray, lanes, keep);
        0
    }
}

impl<T: ShearedTest> TriangleIntersector for T {
    #[inline(always)]
    fn behind_plane(&self, v: &[Vec3; 3]) -> Option<BehindPlane> {
        T::behind_plane(self, v)
    }

    type Prepared = WatertightRay;

    fn name(&self) -> &'static str {
        T::NAME
    }

    #[inline(always)]
    fn prepare(&self, ray: &Ray) -> Option<WatertightRay> {
        WatertightRay::new(ray)
    }

    #[inline(always)]
    fn prepare_valid(&self, ray: &Ray) -> Option<WatertightRay> {
        Some(WatertightRay::of_valid(ray))
    }

    #[inline(always)]
    fn intersect_prepared(
        &self,
        pre: &WatertightRay,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        self.hit_sheared(pre, ray, v)
    }

    #[inline(always)]
    fn intersect_prepared_on<L: SimdLevel>(
        &self,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        self.hit_sheared_on(level, pre, ray, v)
    }

    #[inline(always)]
    fn certain_misses(&self, pre: &WatertightRay, ray: &Ray, lanes: &TriangleLanes) -> u32 {
        pre.certain_misses(ray.origin, lanes)
    }

    #[inline(always)]
    fn certain_misses2<L: SimdLevel>(
        &self,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        first: &TriangleLanes,
        second: &TriangleLanes,
    ) -> u32 {
        pre.certain_misses2(level, ray.origin, first, second)
    }

    #[inline(always)]
    fn behind_misses2<L: SimdLevel>(
        &self,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        lanes: [&TriangleLanes; 2],
        keep: u32,
    ) -> u32 {
        T::behind_misses2(self, level, pre, ray, lanes, keep)
    }

    #[inline(always)]
    fn sheared_rays(&self, rays: &[Ray]) -> Option<ShearedRays> {
        Some(ShearedRays::new(rays))
    }
}

impl ShearedTest for Watertight {
    const NAME: &'static str = "watertight";

    #[inline(always)]
    fn hit_sheared(&self, pre: &WatertightRay, ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit> {
        let sheared = pre.project_triangle(ray.origin, v);
        // Most triangles are missed with two certain, opposite signs: decide those in f32
        // (a certain sign is exact) and compute the exact f64 edges only for the rest.
        if mixed_signs(&filter_edges(sheared.0, sheared.1)) {
            return None;
        }
        exact_candidate(Portable, ray, pre, sheared, v)
    }

    /// Without the `f32` filter, which the cull ([`WatertightRay::certain_misses`]) computes
    /// with the same operations for the triangles a leaf tests: a triangle it would reject has
    /// two certain, opposite `f32` signs, so its exact edge signs differ too and the exact path
    /// refuses it first thing (`finish_exact_at`): `hit_sheared`'s answer for every triangle.
    #[inline(always)]
    fn hit_sheared_on<L: SimdLevel>(
        &self,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        exact_candidate(level, ray, pre, pre.project_triangle(ray.origin, v), v)
    }

    /// On x86-64 the plane of the exact path's kernel, whose "behind" form refuses the
    /// triangle first thing ([`BehindPlane`]); elsewhere none (there the exact path takes its
    /// normal from another vertex, `hit_t`).
    #[inline(always)]
    fn behind_plane(&self, v: &[Vec3; 3]) -> Option<BehindPlane> {
        #[cfg(target_arch = "x86_64")]
        return BehindPlane::new(v);
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = v;
            None
        }
    }

    /// On x86-64 [`WatertightRay::behind_misses2`] (the exact path refuses each lane it
    /// reports by `crossed_behind`: the module `behind`); elsewhere none (the Cortex-M4F
    /// image's size).
    #[inline(always)]
    fn behind_misses2<L: SimdLevel>(
        &self,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        [first, second]: [&TriangleLanes; 2],
        keep: u32,
    ) -> u32 {
        #[cfg(target_arch = "x86_64")]
        return pre.behind_misses2(level, ray, first, second, keep);
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (level, pre, ray, first, second, keep);
            0
        }
    }
}

/// The rows of `lanes`, vertex by vertex, in the axis order `k` (each axis `< 3`).
#[inline(always)]
fn permuted_rows(lanes: &TriangleLanes, k: [usize; 3]) -> [[&[f32; LANES]; 3]; 3] {
    // Written out: `array::map` is not always inlined, and this is on the leaf path.
    let [a, b, c] = &lanes.v;
    let [kx, ky, kz] = k;
    [
        [&a[kx], &a[ky], &a[kz]],
        [&b[kx], &b[ky], &b[kz]],
        [&c[kx], &c[ky], &c[kz]],
    ]
}

/// The rest of [`Watertight`] for a triangle the `f32` filter did not reject: exact `f64`
/// edge functions, then [`finish_exact_at`] with `level`'s plane kernel. Most tested
/// triangles never get here.
///
/// Where the hit path is split differs by target (the same code, so the same answers):
/// - **x86-64:** one call per candidate. The exact edge functions and their sign checks are
///   inlined into the caller (in the frontend, the AVX2 + FMA traversal), and the rest,
///   [`finish_exact_at`] with the common case of `t` ([`common_t`]) inlined, is one
///   out-of-line function per level ([`finish_exact`] for the portable level; at the AVX2
///   level `avx2::finish_exact`, compiled for AVX2 and FMA, whose `f64` plane kernel inlines
///   into it); [`hit_t`] is a
///   cold call from it for the other cases. One call measured faster than two (this
///   function and `hit_t` out of line) and than none (the traversal loop grows):
///   `docs/performance.md`.
/// - **Elsewhere:** this function and `hit_t` out of line, which keeps the miss path of a
///   microcontroller's traversal small (the Cortex-M4F image's 8 KiB budget, `docs/embedded.md`).
#[cfg_attr(target_arch = "x86_64", inline(always))]
#[cfg_attr(not(target_arch = "x86_64"), inline(never))]
fn exact_candidate<L: SimdLevel>(
    level: L,
    ray: &Ray,
    pre: &WatertightRay,
    sheared: ([f32; 3], [f32; 3], [f32; 3]),
    v: &[Vec3; 3],
) -> Option<TriangleHit> {
    let c = Candidate {
        ray,
        pre,
        v,
        sheared,
        edges: exact_edges(sheared.0, sheared.1),
    };
    #[cfg(target_arch = "x86_64")]
    if let Some(token) = level.avx2() {
        return avx2::finish_exact(token, c);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = level;
    finish_exact(c)
}

/// All three `f32` edge functions non-zero and finite skip the exact recomputation, so mixed
/// certain signs are a miss here too (the family's cull applies).
impl ShearedTest for WatertightF32 {
    const NAME: &'static str = "watertight-f32";

    #[inline(always)]
    fn hit_sheared(&self, pre: &WatertightRay, ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit> {
        let (x, y, [az, bz, cz]) = pre.project_triangle(ray.origin, v);
        let ([ax, bx, cx], [ay, by, cy]) = (x, y);
        let mut u = cx * by - cy * bx;
        let mut w = ax * cy - ay * cx;
        let mut s = bx * ay - by * ax;
        if u == 0.0 || w == 0.0 || s == 0.0 {
            [u, w, s] = exact_edges(x, y).map(|e| e as f32);
        }
        if (u < 0.0 || w < 0.0 || s < 0.0) && (u > 0.0 || w > 0.0 || s > 0.0) {
            return None;
        }
        let det = u + w + s;
        if !(det != 0.0 && det.is_finite()) {
            return None;
        }
        let t_scaled = u * az + w * bz + s * cz;
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        let (b1, b2) = (w * inv, s * inv);
        (ray.contains(t)
            && b1.is_finite()
            && b2.is_finite()
            && !super::degenerate_or_coplanar(ray, v))
        .then(|| TriangleHit {
            t,
            b1,
            b2,
            ng: super::geometric_normal(v, (v[1] - v[0]).cross(v[2] - v[0])),
            front_face: det > 0.0,
        })
    }
}

#[cfg(test)]
mod tests;
