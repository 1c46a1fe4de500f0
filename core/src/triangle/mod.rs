//! Ray–triangle intersection: several algorithms behind one trait, so they can be swapped in
//! the BVH and compared in the accuracy benchmark.
//!
//! | type | name | edges | epsilon |
//! |---|---|---|---|
//! | [`Watertight`] (default) | `watertight` | closed, exact signs (`f64` products) | none |
//! | [`WatertightF32`] | `watertight-f32` | closed, `f32` signs, exact `f64` recomputation of zeros | none |
//! | [`WatertightF32Exact`] | `watertight-f32-exact` | closed, exact signs (`f32` filter, integer products), no `f64` | none |
//! | [`MollerTrumbore`] | `moller-trumbore` / `moller-trumbore-noeps` | not watertight | [`crate::tolerance::MOLLER_TRUMBORE_DET_EPSILON`] or 0 |
//! | [`Cramer`] | `cramer` | not watertight | none (`det = 0` only) |
//! | [`F64Reference`] | `f64-reference` | closed, all in `f64` | none |
//!
//! Common contract of every variant:
//! * A hit has `t` in the ray's `(t_min, t_max]` and barycentrics `(b1, b2)` of `v1`, `v2`
//!   (`b0 = 1 − b1 − b2`), each in `[0, 1]` up to [`crate::tolerance::BARYCENTRIC_SLACK`].
//! * Rays lying in the triangle's plane, degenerate (zero-area) triangles, invalid rays
//!   ([`Ray::validate`]) and non-finite vertices give no hit, and neither does a `t` that
//!   overflows to infinity. "In the plane" and "zero area" are decided in `f64` (see
//!   `degenerate_or_coplanar`), exactly for all but extreme coordinate ranges ([`WatertightF32Exact`],
//!   which never uses `f64`, decides them on its sheared projection instead). No input panics.
//! * Both faces are hit; [`TriangleHit::front_face`] tells which one
//!   (counter-clockwise `v0, v1, v2` seen from the ray's origin is the front).
//!
//! **Watertightness** ([`Watertight`], [`WatertightF32`], [`WatertightF32Exact`], [`F64Reference`]): on a mesh with
//! shared, bit-identical vertices, a ray crossing the surface through an edge or vertex hits at
//! least one of the incident triangles, never none (edges are closed; possibly several hit at
//! the same `t`). The proof needs the edge functions' signs to be exact and the per-vertex shear
//! to be a deterministic function of the vertex: never evaluate them with a fused multiply-add.

pub mod barycentric;
mod cramer;
mod lanes;
mod moller_trumbore;
mod reference;
mod watertight;
mod watertight_f32_exact;

pub use cramer::Cramer;
pub use lanes::{LANES, TriangleLanes, pair_mask};
pub use moller_trumbore::MollerTrumbore;
pub use reference::F64Reference;
pub use watertight::{
    BehindPlane, PlaneRay, RAY_LANES, ShearedRays, ShearedTest, Watertight, WatertightF32,
    WatertightRay,
};
pub use watertight_f32_exact::WatertightF32Exact;

use crate::float::gamma;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::sealed::Inside;
use glam::{Vec2, Vec3};

/// The result of a ray–triangle test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter, in `(t_min, t_max]`.
    pub t: f32,
    /// Barycentric weight of `v1`.
    pub b1: f32,
    /// Barycentric weight of `v2`.
    pub b2: f32,
    /// Unnormalised geometric normal `(v1 − v0) × (v2 − v0)` (Embree's `Ng` convention). When
    /// that `f32` product overflows or underflows to zero (triangles beyond ~1e19 or below
    /// ~1e-23 in size), the same direction from the `f64` product, scaled so that its largest
    /// component is `±1`: always finite and non-zero.
    pub ng: Vec3,
    /// `true` when the ray arrives against `ng` (the counter-clockwise side). It is the sign
    /// of the exact `d·n` (`n = (v1 − v0) × (v2 − v0)`), for every intersector, where that
    /// sign is clear of rounding: `|d·n| > 10⁻³·|d|·|n|` (not grazing), `|n| ≥ 10⁻²·M²`
    /// (not a sliver; `M` the largest `|vᵢ − o|`), `M` and `|d|` in `[10⁻¹⁸, 10¹⁸]`, and the
    /// `f32` products `M²`, `M²·|d|` at least `2⁻¹⁰²` (so none underflows). Outside that
    /// domain an `f32` determinant (Cramer, Möller–Trumbore) or a sheared projection may
    /// round to the other sign; the fuzz property `ray_triangle` checks this domain.
    pub front_face: bool,
}

impl TriangleHit {
    /// Barycentric weight of `v0`.
    #[inline]
    #[must_use]
    pub fn b0(&self) -> f32 {
        1.0 - self.b1 - self.b2
    }

    /// The full [`Hit`] record: the point reconstructed by barycentric interpolation (not
    /// `o + t·d`) with pbrt-v4's bound `gamma(7)·Σ|b_i·v_i|` per component, and the unit normal
    /// of `(v1 − v0) × (v2 − v0)`, computed from `v` in `f64` (from the base vertex whose
    /// product does not cancel: no `f32` product to overflow, underflow or cancel), normalised
    /// there and rounded once: unit within an `f32` rounding a component for triangles of any
    /// size, and of the right orientation on slivers whose `f32` cross product (`ng`) has lost
    /// it. `ng`'s direction, normalised, only where the `f64` normal is zero (collinear
    /// vertices).
    #[must_use]
    pub fn to_hit(&self, v: &[Vec3; 3]) -> Hit {
        let b0 = self.b0();
        let (p0, p1, p2) = (v[0] * b0, v[1] * self.b1, v[2] * self.b2);
        let point = p0 + p1 + p2;
        let point_error = (p0.abs() + p1.abs() + p2.abs()) * gamma(7);
        Hit {
            t: self.t,
            point,
            point_error,
            normal: unit_normal(v).unwrap_or_else(|| self.ng.normalize_or_zero()),
            uv: Vec2::new(self.b1, self.b2),
            front_face: self.front_face,
        }
    }
}

/// A ray–triangle intersection algorithm.
///
/// `prepare` does the per-ray work once (for example the watertight test's axis permutation and
/// shear); `intersect_prepared` is then called per triangle, with the current interval taken
/// from `ray` (BVH traversal shrinks `ray.t_max` as it finds closer hits).
///
/// **Implementing it.** Another crate implements the required methods
/// ([`TriangleIntersector::name`], [`TriangleIntersector::prepare`],
/// [`TriangleIntersector::intersect_prepared`]) and may override
/// [`TriangleIntersector::prepare_valid`] (a ray the query has already checked) and
/// [`TriangleIntersector::intersect`]. The other provided methods are this crate's internal
/// hooks, hidden from these docs: the lane culls the wide trees run on four or eight stored
/// triangles at once, their behind-the-origin refusals, the cull across rays and the hit path
/// at a SIMD level. Their first argument is of a type no other crate can name or make
/// (`sealed::Inside`, in a private module), so they can be neither overridden nor called
/// outside this crate: another crate's intersector keeps their defaults (no cull: every
/// stored triangle goes to `intersect_prepared`). A cull must never change an answer, and
/// only this crate's intersectors, whose tests it repeats, can promise that of theirs.
/// [`TriangleIntersector::prepare_valid`] stays open: skipping a check is the
/// implementation's own business, and the one place the queries rely on more (a valid ray
/// never refused) is a batch cull that only this crate's watertight family enables.
///
/// ```
/// use halfray_core::triangle::{TriangleHit, TriangleIntersector, Watertight, WatertightRay};
/// use halfray_core::{Ray, Vec3};
///
/// /// The watertight test under another name.
/// #[derive(Clone, Copy)]
/// struct Renamed;
///
/// impl TriangleIntersector for Renamed {
///     type Prepared = WatertightRay;
///     fn name(&self) -> &'static str {
///         "renamed"
///     }
///     fn prepare(&self, ray: &Ray) -> Option<WatertightRay> {
///         Watertight.prepare(ray)
///     }
///     fn intersect_prepared(&self, pre: &WatertightRay, ray: &Ray, v: &[Vec3; 3])
///         -> Option<TriangleHit> {
///         Watertight.intersect_prepared(pre, ray, v)
///     }
/// }
///
/// let v = [Vec3::ZERO, Vec3::X, Vec3::Y];
/// let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
/// assert_eq!(Renamed.intersect(&ray, &v), Watertight.intersect(&ray, &v));
/// ```
///
/// Another crate cannot override a hook (here the four-lane cull, `certain_misses`): its
/// signature names a type of a private module.
///
/// ```compile_fail,E0603
/// use halfray_core::triangle::{TriangleHit, TriangleIntersector, TriangleLanes};
/// use halfray_core::{Ray, Vec3};
/// #[derive(Clone, Copy)]
/// struct Mine;
/// impl TriangleIntersector for Mine {
///     type Prepared = ();
///     fn name(&self) -> &'static str {
///         "mine"
///     }
///     fn prepare(&self, _: &Ray) -> Option<()> {
///         Some(())
///     }
///     fn intersect_prepared(&self, _: &(), _: &Ray, _: &[Vec3; 3]) -> Option<TriangleHit> {
///         None
///     }
///     // Not possible: `sealed` is private (and without its `Inside` the signature is not
///     // the trait's).
///     fn certain_misses(
///         &self,
///         _: halfray_core::sealed::Inside,
///         _: &(),
///         _: &Ray,
///         _: &TriangleLanes,
///     ) -> u32 {
///         0b1111
///     }
/// }
/// ```
///
/// Nor call one: it has no value to pass as the first argument.
///
/// ```compile_fail,E0061
/// use halfray_core::triangle::{TriangleIntersector, TriangleLanes, Watertight};
/// use halfray_core::{Ray, Vec3};
/// let ray = Ray::new(Vec3::ZERO, Vec3::Z);
/// let pre = Watertight.prepare(&ray).unwrap();
/// // Not possible: the hook's first argument is missing.
/// let missed = Watertight.certain_misses(&pre, &ray, &TriangleLanes::default());
/// ```
pub trait TriangleIntersector: Copy + Send + Sync {
    /// Per-ray precomputed data.
    type Prepared: Copy;

    /// The variant's name, as used on the command line and in reports.
    fn name(&self) -> &'static str;

    /// Per-ray setup; `None` when the ray is invalid ([`Ray::validate`]).
    fn prepare(&self, ray: &Ray) -> Option<Self::Prepared>;

    /// [`TriangleIntersector::prepare`] for a ray the caller has already checked
    /// ([`Ray::is_valid`]): an implementation may skip the check (the result for another ray
    /// is then meaningless, never unsafe). The default calls `prepare`.
    #[inline(always)]
    fn prepare_valid(&self, ray: &Ray) -> Option<Self::Prepared> {
        self.prepare(ray)
    }

    /// Tests one triangle against a prepared ray, over `(ray.t_min, ray.t_max]`.
    fn intersect_prepared(
        &self,
        pre: &Self::Prepared,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit>;

    /// Internal hook (sealed: trait docs). [`TriangleIntersector::intersect_prepared`] at SIMD
    /// `level` (the same answer at every level), as a BVH leaf calls it for a triangle its
    /// cull (`certain_misses`) kept: an implementation may leave out the part of its test
    /// that the cull repeats, but the answer must be `intersect_prepared`'s for every
    /// triangle. The default ignores the level.
    #[doc(hidden)]
    #[inline(always)]
    fn intersect_prepared_on<L: crate::simd_level::SimdLevel>(
        &self,
        _: Inside,
        level: L,
        pre: &Self::Prepared,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        let _ = level;
        self.intersect_prepared(pre, ray, v)
    }

    /// Internal hook (sealed: trait docs). The lanes of `lanes` that this test certainly
    /// misses (bit `i` for lane `i`), decided for all of them at once with vector
    /// instructions, so that a BVH leaf calls [`TriangleIntersector::intersect_prepared`]
    /// only for the others. An implementation reports a lane only when
    /// `intersect_prepared(pre, ray, triangle)` returns `None` for that lane's triangle,
    /// whatever `ray`'s interval: results never change, only the work does. Bits of unused
    /// (NaN) lanes mean nothing: callers mask them. The default reports none.
    #[doc(hidden)]
    #[inline(always)]
    fn certain_misses(
        &self,
        _: Inside,
        pre: &Self::Prepared,
        ray: &Ray,
        lanes: &TriangleLanes,
    ) -> u32 {
        let _ = (pre, ray, lanes);
        0
    }

    /// Internal hook (sealed: trait docs). `certain_misses` of two groups, `first` (bits 0–3)
    /// and `second` (bits 4–7), at SIMD `level` (the same bits at every level). The default
    /// culls each group alone.
    #[doc(hidden)]
    #[inline(always)]
    fn certain_misses2<L: crate::simd_level::SimdLevel>(
        &self,
        inside: Inside,
        level: L,
        pre: &Self::Prepared,
        ray: &Ray,
        first: &TriangleLanes,
        second: &TriangleLanes,
    ) -> u32 {
        let _ = level;
        pair_mask(
            self.certain_misses(inside, pre, ray, first),
            self.certain_misses(inside, pre, ray, second),
        )
    }

    /// Internal hook (sealed: trait docs). The lanes among `keep` (bits 0–3: `lanes[0]`'s,
    /// 4–7: `lanes[1]`'s; the lanes `certain_misses2` kept) that this test misses because the
    /// ray's line certainly crosses their plane behind its origin while `t_min ≥ 0`, at SIMD
    /// `level` (the same bits at every level). Like `certain_misses`, a lane is reported only
    /// when `intersect_prepared` returns `None` for it. Worth calling for rays that leave a
    /// surface (any-hit queries: shadow, ambient occlusion). The default reports none.
    #[doc(hidden)]
    #[inline(always)]
    fn behind_misses2<L: crate::simd_level::SimdLevel>(
        &self,
        _: Inside,
        level: L,
        pre: &Self::Prepared,
        ray: &Ray,
        lanes: [&TriangleLanes; 2],
        keep: u32,
    ) -> u32 {
        let _ = (level, pre, ray, lanes, keep);
        0
    }

    /// Internal hook (sealed: trait docs). Triangle `v`'s [`BehindPlane`], when this test
    /// refuses every ray the plane [`BehindPlane::refuses`] (`intersect_prepared` returns
    /// `None` for them): a batch of rays leaving a surface computes it once per triangle.
    /// `None`, the default, refuses nothing.
    #[doc(hidden)]
    #[inline(always)]
    fn behind_plane(&self, _: Inside, v: &[Vec3; 3]) -> Option<BehindPlane> {
        let _ = v;
        None
    }

    /// Internal hook (sealed: trait docs). The first [`RAY_LANES`] rays of `rays` side by
    /// side for this test's cull across rays, when it has one: the watertight family's
    /// ([`ShearedRays`]; lane `i` of [`ShearedRays::certain_misses`] is then
    /// `certain_misses` of `rays[i]`, bit for bit, for every valid ray, and
    /// [`TriangleIntersector::prepare_valid`] never refuses a valid ray). `None`, the
    /// default, for the others.
    #[doc(hidden)]
    #[inline(always)]
    fn sheared_rays(&self, _: Inside, rays: &[Ray]) -> Option<ShearedRays> {
        let _ = rays;
        None
    }

    /// Convenience: [`TriangleIntersector::prepare`] then
    /// [`TriangleIntersector::intersect_prepared`].
    #[inline]
    fn intersect(&self, ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit> {
        let pre = self.prepare(ray)?;
        self.intersect_prepared(&pre, ray, v)
    }
}

/// The intersectors chosen by name at run time (the frontend's `--intersector`, its accuracy
/// benchmark's rows, the cross-check), each by its command-line name
/// ([`TriangleIntersector::name`]).
///
/// Every intersector type of this module is one, except [`WatertightF32Exact`]
/// (`watertight-f32-exact`), left out on purpose: it is the `f64`-free test for
/// microcontrollers, used there by type (`examples/mcu`, `halfray-ffi`), and it is outside the
/// module's common contract that the variants here share (it decides "ray in the plane" and
/// zero area on its sheared projection, not in 3-D `f64`), so it is checked against
/// [`Watertight`] on its own (`tests/tests/triangle_watertight.rs`, the `ray_triangle` fuzz
/// target) rather than among these. `from_name("watertight-f32-exact")` is therefore `None`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TriangleVariant {
    /// [`Watertight`] (`watertight`).
    Watertight,
    /// [`WatertightF32`] (`watertight-f32`).
    WatertightF32,
    /// [`MollerTrumbore::CLASSIC`] (`moller-trumbore`).
    MollerTrumbore,
    /// [`MollerTrumbore::NO_EPSILON`] (`moller-trumbore-noeps`).
    MollerTrumboreNoEps,
    /// [`Cramer`] (`cramer`).
    Cramer,
    /// [`F64Reference`] (`f64-reference`).
    F64Reference,
}

impl TriangleVariant {
    /// All variants, default first.
    pub const ALL: [Self; 6] = [
        Self::Watertight,
        Self::WatertightF32,
        Self::MollerTrumbore,
        Self::MollerTrumboreNoEps,
        Self::Cramer,
        Self::F64Reference,
    ];

    /// The command-line name.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Watertight => "watertight",
            Self::WatertightF32 => "watertight-f32",
            Self::MollerTrumbore => "moller-trumbore",
            Self::MollerTrumboreNoEps => "moller-trumbore-noeps",
            Self::Cramer => "cramer",
            Self::F64Reference => "f64-reference",
        }
    }

    /// Parses a command-line name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|v| v.name() == name)
    }

    /// `true` for the variants with the watertight guarantee.
    #[must_use]
    pub const fn is_watertight(self) -> bool {
        matches!(
            self,
            Self::Watertight | Self::WatertightF32 | Self::F64Reference
        )
    }

    /// Runs `visitor` with this variant's intersector, a concrete type (so the visitor's code
    /// is monomorphised per variant): the one place a run-time variant becomes a type.
    pub fn visit<V: VariantVisitor>(self, visitor: V) -> V::Output {
        match self {
            Self::Watertight => visitor.visit(&Watertight),
            Self::WatertightF32 => visitor.visit(&WatertightF32),
            Self::MollerTrumbore => visitor.visit(&MollerTrumbore::CLASSIC),
            Self::MollerTrumboreNoEps => visitor.visit(&MollerTrumbore::NO_EPSILON),
            Self::Cramer => visitor.visit(&Cramer),
            Self::F64Reference => visitor.visit(&F64Reference),
        }
    }

    /// Tests one triangle with this variant (dispatching per call; hot loops should be generic
    /// over [`TriangleIntersector`] instead, through [`TriangleVariant::visit`]).
    #[must_use]
    pub fn intersect(self, ray: &Ray, v: &[Vec3; 3]) -> Option<TriangleHit> {
        struct One<'a>(&'a Ray, &'a [Vec3; 3]);
        impl VariantVisitor for One<'_> {
            type Output = Option<TriangleHit>;
            fn visit<I: TriangleIntersector>(self, isect: &I) -> Self::Output {
                isect.intersect(self.0, self.1)
            }
        }
        self.visit(One(ray, v))
    }
}

/// Code to run with the concrete intersector of a [`TriangleVariant`] chosen at run time
/// ([`TriangleVariant::visit`]): a generic function that a closure cannot express.
pub trait VariantVisitor {
    /// What the code returns.
    type Output;
    /// Runs with `isect`, the variant's intersector.
    fn visit<I: TriangleIntersector>(self, isect: &I) -> Self::Output;
}

/// The axis permutation `[kx, ky, kz]` of the watertight projection for a finite, non-zero
/// direction `d`: `kz` is the index of the largest `|dᵢ|` (ties: the lowest, glam's
/// `max_position` rule), `kx` and `ky` the next two cyclically, swapped when `d_kz < 0` so
/// that the permutation and the scaling by `1/d_kz` together preserve orientation. Shared by
/// [`Watertight`] and [`F64Reference`] (which then shear in `f32` and in `f64`).
#[inline(always)]
#[must_use]
pub fn projection_axes(d: Vec3) -> [usize; 3] {
    // Branch-free (comparisons as integers, selection by masks): the direction of a random
    // ray makes every branch here a coin toss.
    let a = d.abs();
    let y_over_x = usize::from(a.y > a.x);
    let larger = if a.y > a.x { a.y } else { a.x };
    let z_over = usize::from(a.z > larger);
    let kz = (z_over << 1) | (y_over_x & !z_over);
    // The next two axes cyclically, `(kz + 1) mod 3` and `(kz + 2) mod 3` (kz = 0: 1, 2;
    // kz = 1: 2, 0; kz = 2: 0, 1). On x86-64 from 2-bit tables packed into integer constants
    // (a shift and a mask, no table stored to the frame: fewer instructions a ray); elsewhere
    // from four-entry tables indexed with `& 3` (smaller code on the microcontrollers). No
    // bounds check either way (`kz` is 0, 1 or 2).
    #[cfg(target_arch = "x86_64")]
    let (kx, ky) = ((0b00_10_01 >> (2 * kz)) & 3, (0b01_00_10 >> (2 * kz)) & 3);
    #[cfg(not(target_arch = "x86_64"))]
    let (kx, ky) = ([1, 2, 0, 0][kz & 3], [2, 0, 1, 0][kz & 3]);
    let comps = [d.x, d.y, d.z, 0.0];
    let swap = 0usize.wrapping_sub(usize::from(comps[kz & 3] < 0.0));
    let flip = (kx ^ ky) & swap;
    [kx ^ flip, ky ^ flip, kz]
}

/// `true` when the triangle has exactly zero area, or the ray's direction lies exactly in its
/// plane: the exact sign of `d·((v1 − v0) × (v2 − v0))` of the `f32` inputs is zero
/// ([`crate::predicates::orient_direction`]: an `f64` evaluation with a forward error filter,
/// exact expansions when the filter cannot decide). A plain `f64` evaluation would not do:
/// for vertices spanning more than `2²⁹` in one coordinate the differences round, and a
/// component of the normal can cancel to zero for a triangle that is not degenerate.
///
/// Why the watertight test needs it: its shear is rounded to `f32`, which can turn the exact
/// projection of such a triangle (a segment) into a thin sliver with a non-zero determinant,
/// and a ray on that sliver's closed edge would then report a hit. Evaluated only for rays that
/// passed the edge tests, so it costs nothing on misses.
#[inline]
pub(crate) fn degenerate_or_coplanar(ray: &Ray, v: &[Vec3; 3]) -> bool {
    crate::predicates::orient_direction(v[1], v[2], v[0], ray.direction) == 0
}

/// The (unnormalised) normal `(v1 − v0) × (v2 − v0)` in `f64`, computed from the vertex
/// opposite the longest edge (a cyclic rotation, so the orientation is the same): the two edges
/// it spans are the shorter ones, so their `f64` differences keep the short edge's digits.
/// From `v0` of a sliver whose other two vertices are tiny against it, both differences round
/// to `−v0` and the cross product is exactly zero.
/// Also returns `|e1| × |e2|` taken with absolute values (the scale of `n`'s rounding).
/// Always inlined on x86-64, into each level's out-of-line end of the hit path
/// (`watertight::exact::finish_exact_at`).
#[cfg_attr(target_arch = "x86_64", inline(always))]
#[cfg_attr(not(target_arch = "x86_64"), inline)]
pub(crate) fn normal_f64(v: &[Vec3; 3]) -> (glam::DVec3, glam::DVec3) {
    // From v0 first; only when a component cancels is the base vertex chosen (the common case
    // skips three lengths).
    if let Some(n) = normal_f64_from_v0(v) {
        return n;
    }
    let p = [v[0].as_dvec3(), v[1].as_dvec3(), v[2].as_dvec3()];
    let base = largest_angle_vertex(&p);
    let (a, b, c) = (p[base], p[(base + 1) % 3], p[(base + 2) % 3]);
    cross_with_scale(b - a, c - a)
}

/// The index of the vertex opposite the longest edge of `p` (the triangle's largest angle; on
/// ties the lowest index). The two edges at that vertex are the shorter ones, so a cross product
/// taken there keeps the short edge's digits and its direction error is at most `1/sin θ ≤ 2`
/// times the rounding unit unless the angle `θ` exceeds 150°. Squared lengths in `f64`; a
/// non-finite length compares false and falls through to a later index.
#[inline(always)]
pub(crate) fn largest_angle_vertex(p: &[glam::DVec3; 3]) -> usize {
    // Edge opposite vertex i: p[i+1] → p[i+2].
    let len2 = |i: usize| (p[(i + 2) % 3] - p[(i + 1) % 3]).length_squared();
    let (l0, l1, l2) = (len2(0), len2(1), len2(2));
    if l0 >= l1 && l0 >= l2 {
        0
    } else if l1 >= l2 {
        1
    } else {
        2
    }
}

/// [`normal_f64`] from `v0`, `(v1 − v0) × (v2 − v0)` and its scale, or `None` when a component
/// cancels (well below its own rounding scale times 2²⁰, or zero while its scale is not;
/// [`NORMAL_CANCEL_REL`]): per component, `d·n` along an axis sees only that component, and a
/// sliver spanning 2⁶⁰ can cancel one component of the v0-based normal entirely while the
/// others stay large.
#[inline(always)]
pub(crate) fn normal_f64_from_v0(v: &[Vec3; 3]) -> Option<(glam::DVec3, glam::DVec3)> {
    let p0 = v[0].as_dvec3();
    let (n, scale) = cross_with_scale(v[1].as_dvec3() - p0, v[2].as_dvec3() - p0);
    let cancels = |i: usize| scale[i] > 0.0 && !(n[i].abs() > NORMAL_CANCEL_REL * scale[i]);
    (!(cancels(0) || cancels(1) || cancels(2))).then_some((n, scale))
}

/// The unit normal of `(v1 − v0) × (v2 − v0)` ([`normal_f64`], normalised in `f64` and rounded
/// to `f32`), `None` when that normal is zero.
fn unit_normal(v: &[Vec3; 3]) -> Option<Vec3> {
    let n = normal_f64(v).0;
    let len = crate::float::sqrt_f64(n.length_squared());
    (len > 0.0 && len.is_finite()).then(|| (n / len).as_vec3())
}

/// Relative size below which a component of the `v0`-based normal is taken as cancelled and
/// the normal recomputed from the best base vertex: `2⁻²⁰` of that component's rounding scale
/// (`|e1| × |e2|` with absolute values). Unitless.
pub(crate) const NORMAL_CANCEL_REL: f64 = 1.0 / 1_048_576.0;

/// `(e1 × e2, |e1| × |e2|)`, the second taken with absolute values.
#[inline]
fn cross_with_scale(e1: glam::DVec3, e2: glam::DVec3) -> (glam::DVec3, glam::DVec3) {
    let (x, y) = (e1.abs(), e2.abs());
    let scale = glam::DVec3::new(
        x.y * y.z + x.z * y.y,
        x.z * y.x + x.x * y.z,
        x.x * y.y + x.y * y.x,
    );
    (e1.cross(e2), scale)
}

/// [`TriangleHit::ng`]: `ng32` (the `f32` cross product) when it is finite and non-zero,
/// otherwise the `f64` normal scaled by its largest component (an overflowing `f32` cross
/// product is NaN, an underflowing one zero), so the result points along `(v1 − v0) × (v2 − v0)`;
/// `Vec3::ZERO` only when that `f64` normal is zero.
#[inline(always)]
pub(crate) fn geometric_normal(v: &[Vec3; 3], ng32: Vec3) -> Vec3 {
    if ng32.is_finite() && ng32 != Vec3::ZERO {
        return ng32;
    }
    let (n, _) = normal_f64(v);
    let m = n.abs().max_element();
    if m > 0.0 && m.is_finite() {
        (n / m).as_vec3()
    } else {
        Vec3::ZERO
    }
}

/// Checks the common post-conditions and builds the hit; shared by the `f32` variants.
#[inline]
fn finish(
    ray: &Ray,
    t: f32,
    b1: f32,
    b2: f32,
    ng: Vec3,
    front_face: bool,
    v: &[Vec3; 3],
) -> Option<TriangleHit> {
    (ray.contains(t) && b1.is_finite() && b2.is_finite() && !degenerate_or_coplanar(ray, v)).then(
        || TriangleHit {
            t,
            b1,
            b2,
            ng: geometric_normal(v, ng),
            front_face,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(v1 − v0) × (v2 − v0)` of the `f32` vertices, in `f64`, by components written out
    /// here (the oracle of the hit normal's tests, not `normal_f64`).
    fn cross_f64(v: &[Vec3; 3]) -> [f64; 3] {
        let e = |i: usize, k: usize| f64::from(v[i][k]) - f64::from(v[0][k]);
        [
            e(1, 1) * e(2, 2) - e(1, 2) * e(2, 1),
            e(1, 2) * e(2, 0) - e(1, 0) * e(2, 2),
            e(1, 0) * e(2, 1) - e(1, 1) * e(2, 0),
        ]
    }

    /// The vertex opposite the longest edge, worked by hand: a 3-4-5 right triangle listed
    /// from each vertex in turn names its right angle; of two equally long longest edges the
    /// lower index wins; a NaN vertex still gives an index in range.
    #[test]
    fn the_largest_angle_is_opposite_the_longest_edge() {
        use glam::DVec3;
        let (a, b, c) = (
            DVec3::ZERO,
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(0.0, 4.0, 0.0),
        );
        assert_eq!(largest_angle_vertex(&[a, b, c]), 0);
        assert_eq!(largest_angle_vertex(&[b, c, a]), 2);
        assert_eq!(largest_angle_vertex(&[c, a, b]), 1);
        // Two longest edges of equal length (25.25 squared, exact): the lower index wins.
        let iso = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 5.0, 0.0)];
        assert_eq!(largest_angle_vertex(&iso), 0);
        assert_eq!(largest_angle_vertex(&[iso[2], iso[0], iso[1]]), 1);
        assert!(largest_angle_vertex(&[a, DVec3::NAN, c]) < 3);
    }

    /// The hit's normal is the unit normal of the triangle at every size: a right triangle
    /// scaled by `10⁻¹¹ … 10¹⁹` (where `ng`'s `f32` square overflows or underflows, and the
    /// normal came out zero or `1.03` long) is within 4 `f32` ulps of the `f64` unit normal.
    #[test]
    fn the_hit_normal_is_unit_for_triangles_of_any_size() {
        for s in [1.0e-11f32, 1.0e-10, 1.0, 5.0e9, 1.0e10, 1.0e19] {
            let v = [
                Vec3::ZERO,
                Vec3::new(s, 0.0, 0.0),
                Vec3::new(0.3 * s, s, 0.2 * s),
            ];
            let ray = Ray::new(Vec3::new(0.3 * s, 0.3 * s, s), Vec3::new(0.1, 0.2, -1.0));
            let h = Watertight.intersect(&ray, &v).unwrap().to_hit(&v);
            let n = cross_f64(&v);
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            for (k, nk) in n.into_iter().enumerate() {
                let want = nk / len;
                assert!(
                    (f64::from(h.normal[k]) - want).abs() <= 4.0 * f64::from(f32::EPSILON),
                    "scale {s}: normal {:?}, want {want} at {k}",
                    h.normal
                );
            }
        }
    }

    /// A sliver whose `f32` cross product points the wrong way (its normal was 0.28 rad off),
    /// and a triangle of size `10⁻²¹` whose `f32` product underflowed to zero: the normal now
    /// agrees in sign with the exact one against the direction `w`, so the ray spawned along
    /// `w` leaves the triangle (it came back at `t = 4·10⁻⁵` and `8·10⁻³⁰`). Inputs from a
    /// probe against exact rational arithmetic.
    #[test]
    fn rays_spawned_from_slivers_and_tiny_triangles_leave_them() {
        let sliver = [
            Vec3::new(-0.24955761, 0.39648676, -0.7938566),
            Vec3::new(0.36239064, -0.0054495335, 0.25929797),
            Vec3::new(0.12838624, 0.14824726, -0.14342152),
        ];
        let ray = Ray::new(
            Vec3::new(-0.684557, 1.5901769, 2.3139224),
            Vec3::new(0.76976144, -1.4135668, -2.5316586),
        );
        let w = Vec3::new(0.47302952, -0.31584138, 0.8224885);
        let h = Watertight.intersect(&ray, &sliver).unwrap().to_hit(&sliver);
        let n = cross_f64(&sliver);
        let w_n = f64::from(w.x) * n[0] + f64::from(w.y) * n[1] + f64::from(w.z) * n[2];
        assert_eq!(w.dot(h.normal) < 0.0, w_n < 0.0, "normal {:?}", h.normal);
        assert!(
            Watertight
                .intersect(&crate::spawn_ray(&h, w), &sliver)
                .is_none()
        );

        let tiny = [
            Vec3::new(-5.8062344e-22, 2.522993e-21, -9.839929e-21),
            Vec3::new(8.497675e-21, 2.7592314e-21, -8.35069e-21),
            Vec3::new(2.4482916e-21, 2.6017276e-21, -9.343019e-21),
        ];
        let ray = Ray::new(
            Vec3::new(1.1442721e-20, -5.2180017e-20, 6.448538e-20),
            Vec3::new(-7.305328e-18, 5.4825736e-17, -7.355133e-17),
        );
        let h = Watertight.intersect(&ray, &tiny).unwrap().to_hit(&tiny);
        assert!((h.normal.length() - 1.0).abs() < 1.0e-6, "{:?}", h.normal);
        for w in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            assert!(
                Watertight
                    .intersect(&crate::spawn_ray(&h, w), &tiny)
                    .is_none(),
                "{w:?}"
            );
        }
    }

    /// Worked cases of the permutation (ties, signs), and for every sign pattern and
    /// dominant axis: `kz` is dominant, the three indices are a permutation, and the
    /// permutation's parity times the sign of `d_kz` is `+1` (orientation preserved).
    #[test]
    fn projection_axes_pick_the_dominant_axis_and_keep_orientation() {
        assert_eq!(projection_axes(Vec3::new(1.0, 1.0, 1.0)), [1, 2, 0]);
        assert_eq!(projection_axes(Vec3::new(-1.0, 0.5, 0.0)), [2, 1, 0]);
        assert_eq!(projection_axes(Vec3::new(0.5, -2.0, 2.0)), [0, 2, 1]);
        assert_eq!(projection_axes(Vec3::new(0.0, 0.0, -3.0)), [1, 0, 2]);
        for dominant in 0..3 {
            for signs in 0..8 {
                let mut d = Vec3::new(0.25, 0.5, 0.75);
                d[dominant] = 4.0;
                for a in 0..3 {
                    if signs & (1 << a) != 0 {
                        d[a] = -d[a];
                    }
                }
                let k = projection_axes(d);
                assert_eq!(k[2], dominant, "{d:?}");
                let mut sorted = k;
                sorted.sort_unstable();
                assert_eq!(sorted, [0, 1, 2]);
                let inversions =
                    usize::from(k[0] > k[1]) + usize::from(k[0] > k[2]) + usize::from(k[1] > k[2]);
                let parity = if inversions % 2 == 0 { 1.0 } else { -1.0 };
                assert_eq!(parity * d[k[2]].signum(), 1.0, "{d:?} -> {k:?}");
            }
        }
    }

    /// Each variant visits with its own intersector: the intersector's own name is the
    /// variant's (a mix-up in the dispatch would show as another name).
    #[test]
    fn each_variant_visits_with_its_own_intersector() {
        struct Name;
        impl VariantVisitor for Name {
            type Output = &'static str;
            fn visit<I: TriangleIntersector>(self, isect: &I) -> &'static str {
                isect.name()
            }
        }
        for v in TriangleVariant::ALL {
            assert_eq!(v.visit(Name), v.name());
        }
    }

    /// Every intersector type of this module, written out with its variant (`None` for the
    /// one left out on purpose, `WatertightF32Exact`: see [`TriangleVariant`]):
    /// `from_name` of the type's own `name()` is that variant, whose name and whose
    /// dispatched intersector's name are the type's. `ALL` holds exactly the listed variants.
    #[test]
    fn from_name_of_every_intersector_types_name_is_its_variant() {
        fn check<I: TriangleIntersector>(isect: I, want: Option<TriangleVariant>) -> usize {
            let name = isect.name();
            assert_eq!(TriangleVariant::from_name(name), want, "{name}");
            if let Some(v) = want {
                assert_eq!(v.name(), name);
                assert_eq!(
                    v.intersect(&Ray::new(Vec3::new(0.25, 0.5, 5.0), -Vec3::Z), &tri()),
                    isect.intersect(&Ray::new(Vec3::new(0.25, 0.5, 5.0), -Vec3::Z), &tri()),
                    "{name}"
                );
            }
            usize::from(want.is_some())
        }
        use TriangleVariant as V;
        let listed = check(Watertight, Some(V::Watertight))
            + check(WatertightF32, Some(V::WatertightF32))
            + check(WatertightF32Exact, None)
            + check(MollerTrumbore::CLASSIC, Some(V::MollerTrumbore))
            + check(MollerTrumbore::NO_EPSILON, Some(V::MollerTrumboreNoEps))
            + check(Cramer, Some(V::Cramer))
            + check(F64Reference, Some(V::F64Reference));
        assert_eq!(listed, TriangleVariant::ALL.len());
        assert_eq!(WatertightF32Exact.name(), "watertight-f32-exact");
    }

    fn tri() -> [Vec3; 3] {
        [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]
    }

    /// A sliver spanning 2⁶⁰ (vertices near 1e18, 1 and 0) whose `v0`-based `f64` normal loses
    /// its `x` component entirely while `y` and `z` stay large: a ray along `x` was taken to lie
    /// in the plane and missed (found by the `ray_triangle` fuzz target). Expected `t` from
    /// that target's independent `f64` reference (its own error bound there is 5 %).
    #[test]
    fn normal_component_cancelled_from_v0_is_recomputed() {
        let b = f32::from_bits;
        let v = [
            Vec3::new(b(0x0031_3eaa), b(0x5d5d_5d5d), b(0x5d5d_5d5d)),
            Vec3::new(b(0x5d5d_5d5d), b(0x0000_5d5d), b(0x3f80_0041)),
            Vec3::ZERO,
        ];
        let ray = Ray::new(Vec3::new(0.5, b(0x3ecc_c8cd), b(0x3ecc_cccd)), Vec3::X);
        let h = Watertight
            .intersect(&ray, &v)
            .expect("the ray crosses the sliver");
        let t_ref = 3.042_389_700_453_892_6e13;
        // Relative agreement asked of `t`: well inside the reference's 5 % bound.
        const T_REL: f64 = 1e-3;
        assert!(
            ((f64::from(h.t) - t_ref) / t_ref).abs() < T_REL,
            "t = {}",
            h.t
        );
        assert!(!degenerate_or_coplanar(&ray, &v));
    }

    /// Huge and tiny triangles: the f32 cross product overflows (NaN from ∞ − ∞) or underflows
    /// to zero; `ng` falls back to the scaled f64 normal, same direction (the overflow found by
    /// the `bvh` fuzz target: a NaN normal).
    #[test]
    fn geometric_normal_of_huge_and_tiny_triangles() {
        for s in [1e25f32, 1e-30] {
            let v = [Vec3::ZERO, Vec3::new(s, 0.0, 0.0), Vec3::new(0.0, s, 0.0)];
            let h = TriangleVariant::Watertight
                .intersect(&Ray::new(Vec3::new(s / 4.0, s / 4.0, s), -Vec3::Z), &v)
                .unwrap_or_else(|| panic!("{s}"));
            assert!(h.ng.is_finite() && h.ng != Vec3::ZERO, "{s}: {:?}", h.ng);
            assert_eq!(h.ng.normalize(), Vec3::Z, "{s}");
        }
    }

    #[test]
    fn every_variant_agrees_on_a_plain_hit() {
        let ray = Ray::new(Vec3::new(0.25, 0.5, 5.0), Vec3::new(0.0, 0.0, -1.0));
        for v in TriangleVariant::ALL {
            let h = v
                .intersect(&ray, &tri())
                .unwrap_or_else(|| panic!("{}", v.name()));
            assert!((h.t - 5.0).abs() < 1e-6, "{}: {h:?}", v.name());
            assert!(
                (h.b1 - 0.25).abs() < 1e-6 && (h.b2 - 0.5).abs() < 1e-6,
                "{}",
                v.name()
            );
            assert!(
                h.front_face,
                "{}: ray against +z normal is the front",
                v.name()
            );
            assert_eq!(h.ng, Vec3::Z, "{}", v.name());
            let back = Ray::new(Vec3::new(0.25, 0.5, -5.0), Vec3::Z);
            assert!(
                !v.intersect(&back, &tri()).unwrap().front_face,
                "{}",
                v.name()
            );
            assert_eq!(TriangleVariant::from_name(v.name()), Some(v));
        }
    }

    #[test]
    fn to_hit_reconstructs_point_with_error_bound() {
        let ray = Ray::new(Vec3::new(0.25, 0.5, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let h = Watertight.intersect(&ray, &tri()).unwrap().to_hit(&tri());
        assert!((h.point - Vec3::new(0.25, 0.5, 0.0)).abs().max_element() <= 1e-7);
        assert!(h.point_error.max_element() > 0.0 && h.point_error.max_element() < 1e-6);
        assert_eq!(h.normal, Vec3::Z);
    }
}
