//! Named tolerances. The core's user-facing epsilons and the bounds several modules share live
//! here (or are fields of a tolerance value such as
//! [`crate::triangle::MollerTrumbore::det_epsilon`]), with their units and reasons; a bound
//! derived for one algorithm is a named constant beside it, derived the same way (`aabb`,
//! `grid`, `volume`, `kdtree`, `query::walk`, `triangle::watertight`).
//!
//! The watertight triangle test, the slab test, the spheres and the spawn offsets use **no**
//! tuned epsilon: they rely on exact predicates or on bounds derived from [`crate::float::gamma`].
//! The constants below are the few places where a user-facing choice is unavoidable.

use crate::float::gamma;

/// Determinant threshold of the textbook Möller–Trumbore test (`|det| ≤ ε` is "parallel").
///
/// Unit: absolute, in (length units)² × |direction| — which is exactly why it is a poor idea:
/// it rejects every triangle smaller than about `√ε` and accepts near-parallel large ones. It
/// is the 1997 paper's value, kept so that the accuracy benchmark can show what it costs.
pub const MOLLER_TRUMBORE_DET_EPSILON: f32 = 1.0e-6;

/// Tolerance on barycentric coordinates reported by the `f32` triangle tests, used by
/// tests and fuzzers to check that a reported `(b0, b1, b2)` lies in `[0, 1]`.
///
/// Unit: absolute on the barycentric (which is unitless). The watertight test decides
/// inside/outside exactly, but divides three exact `f64` edge values by their sum and rounds to
/// `f32`: each barycentric is within `gamma(4)` of `[0, 1]` (two `f64` roundings, one division,
/// one conversion; we use the `f32` gamma, which dominates).
pub const BARYCENTRIC_SLACK: f32 = gamma(4);

/// Maximum relative distance from the plane for a polygon to count as planar: each vertex's
/// distance to the plane through the centroid must be `≤ PLANARITY_REL × diameter`.
///
/// Unit: relative to the polygon's bounding-box diagonal. `1e-5` ≈ 84 ulps of `f32` (`2⁻²³`): input
/// written with 6–7 significant digits (typical scene files) is accepted, visibly bent input
/// is refused.
pub const PLANARITY_REL: f32 = 1.0e-5;

/// Relative accuracy the tests demand of `t` for well-conditioned hits (ray within 60° of the
/// normal), relative to `t`: 64 ulps (`64·2⁻²³`). The error analysis of the watertight test
/// (translation, shear and division, each `≤ gamma(3)` of the largest coordinate) bounds the
/// error by a few ulps of the *coordinates*, which for a ray that starts near its target is a
/// few ulps of `t` as well; the slack covers the `1/cos θ` growth up to 60°.
pub const T_REL_TOLERANCE_WELL_CONDITIONED: f32 = 64.0 * f32::EPSILON;

/// Largest accepted condition number `κ_F(L) = ‖L‖_F·‖L⁻¹‖_F` of the linear part `L` of a
/// [`crate::transform::Transform`]; above it [`crate::transform::Transform::new`] returns
/// [`crate::error::GeometryError::SingularTransform`].
///
/// Unit: relative (scale-invariant; `3` for a rotation). Why this measure: for a 3×3 matrix
/// `‖A‖₂ ≤ ‖A‖_F ≤ √3·‖A‖₂`, so `κ₂(L) ≤ κ_F(L) ≤ 3·κ₂(L)`: the threshold `2²⁰` guarantees
/// `κ₂ ≤ 2²⁰`, i.e. `κ·u ≤ 2⁻⁴` (a point taken to object space and back keeps ≥ 4 correct bits
/// in its worst direction), and refuses no matrix with `κ₂ ≤ 2²⁰/3 ≈ 3.5·10⁵`. A scale
/// `(1, a, a)` (a rod) has `κ_F ≈ √(1 + 2/a²)`, accepted down to `a ≈ 1.35·10⁻⁶`; a flattened
/// sphere `(1, 1, a)` has `κ_F ≈ √2/a`, accepted down to `a ≈ 1.35·10⁻⁶`. (A scaled
/// determinant `|det L| / ‖L‖_F³` bounds `κ₂` too but counts every small axis: it refused a
/// rod `(1, 5·10⁻⁴, 5·10⁻⁴)`, `κ₂ = 2 000`.)
pub const TRANSFORM_MAX_CONDITION: f64 = 1_048_576.0;

/// Smallest scaled determinant `|det A| / ‖A‖_F³` (with singular values `σ₁ ≥ σ₂ ≥ σ₃`,
/// `|det A| ≤ σ₁²σ₃` and `σ₁ ≤ ‖A‖_F`, so `κ₂(A) ≤ ‖A‖_F³ / |det A| ≤ 2²⁰`) for which [`crate::quadric::Quadric::new`] uses the quadric's
/// centre `−A⁻¹b` as the reference point of its centred form. Below it (cylinders, cones with a
/// tiny angle, paraboloids, planes) the centre is absent or far away and the world origin is
/// used instead; the representation is exact either way (see the quadric module), only the
/// cancellation it avoids differs. Unit: relative.
pub const QUADRIC_CENTER_MIN_REL_DET: f64 = 1.0 / 1_048_576.0;

/// Safety factor on the first-order distance estimate `|f(x)| / |∇f(x)|` from a quadric hit
/// point (computed in `f64`) to the surface. Unitless. The estimate is exact for planes and
/// its relative error is `O(dist · curvature)`; at the `~1e-16`-relative distances the `f64`
/// solve leaves, any factor above 1 is conservative, and 2 is used.
pub const QUADRIC_DISTANCE_SLACK: f64 = 2.0;

/// Bound on the residual of a quadric root, relative to the scale of the terms it cancels:
/// `|f(o + t·d)| ≤ QUADRIC_ROOT_RESIDUAL_REL · (|∇f(x)|·|t·d| + F(x))`, where `F(x)` is `f`
/// evaluated with every term replaced by its absolute value. Unit: relative.
///
/// Why this form: a root with relative error `δ` leaves a residual `≈ (∇f·d)·t·δ`, and the
/// evaluation of `f` itself rounds at `≈ u₆₄·F`. The `f64` solve has `δ` of a few `u₆₄`
/// (`u₆₄ = 2⁻⁵³`) for every ray, near-tangent ones included (the discriminant is evaluated at
/// the shifted origin without cancellation). `2⁻⁴⁴` = 512 `u₆₄` leaves a margin of ~100 over the
/// worst case measured by the quadric tests, and is still ~2⁻²⁰ below `f32` resolution.
pub const QUADRIC_ROOT_RESIDUAL_REL: f64 = 1.0 / 17_592_186_044_416.0;

/// Smallest twice-area of a polygon relative to the square of its bounding-box diagonal,
/// `|Σ (v_i − c) × (v_{i+1} − c)| / diag²` (Newell's normal, computed in `f64`: a signed
/// area, in which oppositely wound lobes of a self-intersecting outline cancel); below it
/// [`crate::polygon::Polygon::new`] returns [`crate::error::GeometryError::Degenerate`].
///
/// Unit: relative. `gamma(8)` ≈ 4.8e-7: a polygon that thin is a sliver narrower than a few
/// `f32` ulps of its own size, whose plane (and so the ray–plane hit and the projection axis)
/// is determined by rounding alone.
pub const POLYGON_MIN_AREA_REL: f32 = gamma(8);

/// How far short of its target a shadow segment from [`crate::hit::spawn_ray_to`] ends:
/// `t_max = 1 − SHADOW_SEGMENT_END_SLACK`, relative to the segment length (unitless).
///
/// The target (a light, or a surface point offset off its surface by its error bound) sits at
/// `t = 1`. When the offset is smaller than the `f32` resolution of `t` near 1 (`2⁻²⁴`), the
/// target's own surface can be computed at exactly `t = 1.0` or a few ulps below; 16 ulps of
/// `t` covers the watertight test's rounding of `t` for segments comparable in length to their
/// coordinates. The cost: an occluder within `1e-6` of the segment length from the target is
/// not seen.
pub const SHADOW_SEGMENT_END_SLACK: f32 = 16.0 * crate::float::F32_UNIT_ROUNDOFF;

/// Outward padding of every box a BVH traversal tests, relative to how far the structure
/// reaches from the ray's origin: the box test then never culls a triangle that the
/// watertight test hits, so a BVH query equals a brute-force loop with the same test.
///
/// Unit: relative. The padding is `BVH_PROJECTION_PAD·R + `[`PAD_ORIGIN_SHIFT_REL`]`·max|o|`
/// world units (`PadFrame::pad` in `query::walk`), `R` an upper bound of
/// `max_i |p_i − o_i|` over every point `p` of the structure (its root box).
///
/// Why: the watertight test decides exactly on the **rounded** sheared coordinates
/// `x' = (p_kx − o_kx) − s_x·(p_kz − o_kz)`: a subtraction, a product and a subtraction,
/// with `|s_x| ≤ 1`, on the differences `p − o`, so each is within about
/// `γ₈·max_i |p_i − o_i| ≤ γ₈·R` of the exact one (the rounding is relative to the vertex's
/// distance from the origin, not to the coordinates' magnitude). A hit therefore means the
/// exact ray passes within that distance of the triangle along the two sheared axes, possibly
/// just outside its box. The boxes are padded by shifting the ray's origin (`o ± pad`, see
/// `PaddedRay`), whose rounding takes up to `u·(|o_i| + pad)` off the shift, and the slab's
/// subtraction rounds by up to `u·(R + pad)`: the padding must exceed `γ₈·R` by both.
/// `γ₁₆·R` doubles the first and covers the second; the [`PAD_ORIGIN_SHIFT_REL`] term
/// covers the shift's rounding, which no bound on `R` can: an origin far from the
/// coordinate origin has an ulp larger than a pad of `γ₁₆·R`, and `o ± pad` would round
/// back to `o`. The wide tree therefore stores its boxes relative to its centre `c` and
/// tests them from `o − c` (`PadFrame::local`): the origin, its shift and its term are then
/// measured in that frame, and small wherever the mesh lies. The binary [`crate::bvh::Bvh`]
/// and the kd-tree keep world boxes (`PadFrame::of`): `R` from the origin's distance to the
/// root box's centre plus the box's reach, and the shift term of the origin's own
/// coordinates, two ulps of them (a looser `R = max|o| + max|scene|` once padded the binary
/// tree by `γ₁₆·2·10⁴` on a mesh at `2·10⁴`, more than the bunny's size there).
///
/// Cost: a box grows by ~1e-6 of the distance from the ray's origin to the far side of the
/// structure, plus two `f32` ulps of the origin's coordinates in the structure's frame, a
/// few extra leaf visits on a grazing ray. With `max|o| + max|scene|` instead, a small mesh
/// far from the coordinate origin had every box padded by sixteen times that: the bunny
/// moved to `(10⁴, −3·10³, 2·10⁴)` (coordinates near `2·10⁴`, so 0.04 against its size of
/// 0.15) tested 7 600 triangles per camera ray; with world-coordinate boxes and the two ulps
/// of `2·10⁴`, 29; with boxes relative to the tree's centre, 3.1, as at the coordinate
/// origin (`docs/performance.md`).
pub const BVH_PROJECTION_PAD: f32 = gamma(16);

/// The part of the box padding that covers the rounding of the shifted ray origins `o ± pad`
/// ([`BVH_PROJECTION_PAD`]): `2u`, relative to `max|o|` (unitless). The rounding of
/// `o_i ± pad` is at most `u·(|o_i| + pad)`; `2u·max|o|` exceeds its `u·|o_i|` part, and
/// [`BVH_PROJECTION_PAD`]'s doubling the `u·pad` part. It is two `f32` ulps of the origin's
/// largest coordinate at most: the resolution of the origin itself, in the coordinates the
/// boxes are stored in (world coordinates for the kd-tree, the tree's centre for the wide
/// BVH, where `2·PAD_ORIGIN_SHIFT_REL` also covers the rounding of `o − c`).
pub const PAD_ORIGIN_SHIFT_REL: f32 = 2.0 * crate::float::F32_UNIT_ROUNDOFF;

/// Relative bound of the `f32` values `wn`, `dn` of the watertight test's eight-lane "crossed
/// behind the origin" cull ([`crate::triangle::WatertightRay::behind_misses2`]) against their
/// computed permanents: `9u = 9·2⁻²⁴`, above the error bound `γ₈/(1 − γ₈) = 8u/(1 − 16u)` of
/// `wn` (and `dn`'s smaller one) once the bound's own three roundings are taken off:
/// `(1 − u)³·9u > 8u/(1 − 16u)` (the derivation: `core/src/triangle/watertight/behind.rs`). The
/// smallest such multiple of `u`: a looser bound leaves more lanes near the plane, to the
/// `f64` check. Unitless.
pub const BEHIND_REL: f32 = 9.0 / 16_777_216.0;

/// The margin that makes the `f64` filters of the exact path pass for every base vertex it
/// may choose: `2⁻⁴⁰` of `m²·|·|₁` (the derivation: `core/src/triangle/watertight/behind.rs`; `2¹⁰` times what they need).
/// Unitless: a factor on `m²·|·|₁`, which carries the units.
pub const BEHIND_F64_MARGIN: f32 = 1.0 / 1_099_511_627_776.0;

/// Absolute floor of the cull's bounds: `2⁻¹⁴⁰` (an `f32` subnormal, `2⁹` times the
/// smallest), above the absolute error of products that underflow (`2⁻¹⁴⁷·(|·|₁ + 1)`,
/// derived in `core/src/triangle/watertight/behind.rs`). World units cubed (`wn`) and that
/// per unit of `t` (`dn`).
pub const BEHIND_TINY: f32 = f32::from_bits(1 << 9);
