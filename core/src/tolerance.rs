//! Named tolerances. Every epsilon the core uses lives here (or is a field of a tolerance value
//! such as [`crate::triangle::MollerTrumbore::det_epsilon`]), with its unit and its reason.
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

/// Relative tolerance on barycentric coordinates reported by the `f32` triangle tests, used by
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
/// Unit: relative to the polygon's bounding-box diagonal. `1e-5` ≈ 168 ulps of `f32`: input
/// written with 6–7 significant digits (typical scene files) is accepted, visibly bent input
/// is refused.
pub const PLANARITY_REL: f32 = 1.0e-5;

/// Relative accuracy the tests demand of `t` for well-conditioned hits (ray within 60° of the
/// normal), relative to `t`: 64 ulps (`64·2⁻²³`). The error analysis of the watertight test
/// (translation, shear and division, each `≤ gamma(3)` of the largest coordinate) bounds the
/// error by a few ulps of the *coordinates*, which for a ray that starts near its target is a
/// few ulps of `t` as well; the slack covers the `1/cos θ` growth up to 60°.
pub const T_REL_TOLERANCE_WELL_CONDITIONED: f32 = 64.0 * f32::EPSILON;
