//! Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013).
//!
//! This file holds the intersectors, [`Watertight`] and [`WatertightF32`], and the family
//! trait [`ShearedTest`] with its implementations, among them [`Watertight`]'s entry into its
//! exact path per SIMD level (`exact_candidate`: here, since it calls `avx2.rs`, which builds
//! on `exact.rs`). The rest, one concept per file:
//! - `ray.rs`: [`WatertightRay`], the per-ray axis permutation and shear, the projection of a
//!   triangle with it, the family's lane cull and the half-open crossing rule;
//! - `edges.rs`: the sheared triangle's three edge functions, in `f32` (the filter) and
//!   exact in `f64`, shared by `ray.rs`, the intersectors and `WatertightF32Exact`;
//! - `exact.rs`: [`Watertight`]'s exact path for a candidate the filter kept (`t` in its
//!   sheared and plane forms, the barycentrics, the plane crossed behind the origin) and its
//!   named tolerances;
//! - `avx2.rs` (x86-64): the end of that path compiled for AVX2 and FMA;
//! - `behind.rs`: the eight-lane cull of planes crossed behind the origin
//!   (`WatertightRay::behind_misses2`);
//! - `plane.rs`: [`BehindPlane`], that refusal with a triangle's plane computed once for many
//!   rays;
//! - `rays.rs`: [`ShearedRays`], the family's cull across eight rays.

use super::{TriangleHit, TriangleIntersector, TriangleLanes};
use crate::ray::Ray;
use crate::sealed::Inside;
use crate::simd::level::{Portable, SimdLevel};
use edges::exact_edges;
use exact::{Candidate, finish_exact};
use glam::Vec3;

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx2;
mod behind;
mod edges;
mod exact;
mod plane;
mod ray;
mod rays;

pub(super) use edges::{filter_edges, mixed_signs};
pub use plane::{BehindPlane, PlaneRay};
pub use ray::WatertightRay;
pub use rays::{RAY_LANES, ShearedRays};

/// The watertight test with **exact edge signs**: the three 2-D edge functions are `f64`
/// differences of `f64` products of the sheared `f32` coordinates. Each product is exact, so
/// the single rounding of the difference keeps the exact sign, and zero means exactly on the
/// edge. `det`, `t` and the barycentrics are computed in `f64` and rounded once.
///
/// Edges and vertices are **closed**: a point exactly on an edge is inside. "Exactly" is in the
/// sheared frame: the edge functions are exact for the sheared `f32` coordinates, which round
/// the world's (the shear `d_i/d_kz` and `x' = p_kx − s_x·p_kz` each round unless exact, as
/// for an axis-aligned ray). A ray through a shared edge in world coordinates may so fall just
/// on one side of it, but on the same side for both triangles, which see the same sheared
/// edge: one hit, never none. Only a ray that lands on the sheared edge hits both at equal
/// `t`, where the smaller index wins (the BVH's tie rule). Mixed signs or
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
/// vertex or edge hit that a brute-force loop reports). A direction whose dominant component
/// is below `2⁻¹²⁸` (`1/d_kz` overflows `f32`) is outside the domain: the sheared depths are
/// then infinite or NaN and the ray may pass through a closed mesh; scale such a direction by
/// a power of two first (its `t` scales back exactly).
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

/// The watertight family ([`Watertight`], [`WatertightF32`], [`super::WatertightF32Exact`]):
/// the ray prepared as a [`WatertightRay`] (axis permutation and shear), and a test of one
/// triangle that rejects every triangle two of whose three `f32` edge functions (the filter
/// of [`WatertightRay::certain_misses`]) have certain, opposite signs. Each member supplies
/// its name and its test; [`TriangleIntersector`] (preparation and the four-lane cull) comes
/// with it. Its other provided methods are internal hooks like [`TriangleIntersector`]'s
/// (hidden, sealed by their first argument: neither callable nor overridable elsewhere).
///
/// Sealed: the family's cull rejects a triangle for every member on the strength of each
/// member's test refusing it too, which only this crate's members promise. Another crate's
/// intersector implements [`TriangleIntersector`] itself:
///
/// ```compile_fail,E0277
/// use halfray_core::Ray;
/// use halfray_core::Vec3;
/// use halfray_core::triangle::{ShearedTest, TriangleHit, WatertightRay};
/// #[derive(Clone, Copy)]
/// struct Mine;
/// // Not possible: `ShearedTest` is sealed.
/// impl ShearedTest for Mine {
///     const NAME: &'static str = "mine";
///     fn hit_sheared(&self, _: &WatertightRay, _: &Ray, _: &[Vec3; 3]) -> Option<TriangleHit> {
///         None
///     }
/// }
/// ```
pub trait ShearedTest: Copy + Send + Sync + crate::sealed::Sealed {
    /// The variant's name ([`TriangleIntersector::name`]).
    const NAME: &'static str;

    /// [`TriangleIntersector::intersect_prepared`].
    fn hit_sheared(&self, pre: &WatertightRay, ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit>;

    /// Internal hook (sealed: [`TriangleIntersector`]'s docs). [`ShearedTest::hit_sheared`]
    /// at SIMD `level`, for a triangle the family's cull kept
    /// ([`TriangleIntersector`]'s `intersect_prepared_on`: the same answer for every
    /// triangle, at every level). The default ignores the level.
    #[doc(hidden)]
    #[inline(always)]
    fn hit_sheared_on<L: SimdLevel>(
        &self,
        _: Inside,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        let _ = level;
        self.hit_sheared(pre, ray, v)
    }

    /// Internal hook (sealed: [`TriangleIntersector`]'s docs). [`TriangleIntersector`]'s
    /// `behind_plane`. The default has none ([`Watertight`]'s is the plane of its exact
    /// path's kernel, on x86-64).
    #[doc(hidden)]
    #[inline(always)]
    fn behind_plane(&self, _: Inside, v: &[Vec3; 3]) -> Option<BehindPlane> {
        let _ = v;
        None
    }

    /// Internal hook (sealed: [`TriangleIntersector`]'s docs). [`TriangleIntersector`]'s
    /// `behind_misses2`: the lanes among `keep` this test certainly misses because the line
    /// crosses their plane behind the origin. The default refuses none ([`Watertight`]
    /// refuses them with [`WatertightRay::behind_misses2`]).
    #[doc(hidden)]
    #[inline(always)]
    fn behind_misses2<L: SimdLevel>(
        &self,
        _: Inside,
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

// The hooks' overrides are `doc(hidden)` as the hooks are (`TriangleIntersector`'s docs):
// rustdoc lists a blanket impl's items on every type it covers, hidden trait items included.
impl<T: ShearedTest> TriangleIntersector for T {
    #[doc(hidden)]
    #[inline(always)]
    fn behind_plane(&self, inside: Inside, v: &[Vec3; 3]) -> Option<BehindPlane> {
        T::behind_plane(self, inside, v)
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

    #[doc(hidden)]
    #[inline(always)]
    fn intersect_prepared_on<L: SimdLevel>(
        &self,
        inside: Inside,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        self.hit_sheared_on(inside, level, pre, ray, v)
    }

    #[doc(hidden)]
    #[inline(always)]
    fn certain_misses(
        &self,
        _: Inside,
        pre: &WatertightRay,
        ray: &Ray,
        lanes: &TriangleLanes,
    ) -> u32 {
        pre.certain_misses(ray.origin, lanes)
    }

    #[doc(hidden)]
    #[inline(always)]
    fn certain_misses2<L: SimdLevel>(
        &self,
        _: Inside,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        first: &TriangleLanes,
        second: &TriangleLanes,
    ) -> u32 {
        pre.certain_misses2(level, ray.origin, first, second)
    }

    #[doc(hidden)]
    #[inline(always)]
    fn behind_misses2<L: SimdLevel>(
        &self,
        inside: Inside,
        level: L,
        pre: &WatertightRay,
        ray: &Ray,
        lanes: [&TriangleLanes; 2],
        keep: u32,
    ) -> u32 {
        T::behind_misses2(self, inside, level, pre, ray, lanes, keep)
    }

    #[doc(hidden)]
    #[inline(always)]
    fn sheared_rays(&self, _: Inside, rays: &[Ray]) -> Option<ShearedRays> {
        Some(ShearedRays::new(rays))
    }
}

impl crate::sealed::Sealed for Watertight {}

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
        _: Inside,
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
    fn behind_plane(&self, _: Inside, v: &[Vec3; 3]) -> Option<BehindPlane> {
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
        _: Inside,
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
///
/// [`finish_exact_at`]: exact::finish_exact_at
/// [`common_t`]: exact::common_t
/// [`hit_t`]: exact::hit_t
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

impl crate::sealed::Sealed for WatertightF32 {}

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
