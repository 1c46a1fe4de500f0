//! Triangle–triangle distance in `f64`.
//!
//! The distance between two closed triangles is `0` when they intersect (decided exactly by
//! [`super::triangles_intersect`]); otherwise a closest pair of points is vertex–face or
//! edge–edge, so it is the minimum of the nine segment–segment distances and of the distances
//! from each vertex to the other triangle's plane, counted only where the vertex projects
//! inside that triangle. Everything is evaluated in `f64` from the `f32` vertices.
//!
//! **Error.** Every candidate is the length of a difference between a point computed on (or
//! within rounding of) one triangle and one on the other, so the computed distance `d̃` obeys
//! `d̃ ≥ d − DISTANCE_ERR_REL·(d + M)` where `d` is the exact distance and `M` the largest
//! coordinate magnitude of the two triangles ([`DISTANCE_ERR_REL`]). Above, it may exceed the
//! exact value by the same amount: where a near-tie between candidate features is decided by
//! rounding, and by the rounding of the closest points' parameters (the edge–edge parameter
//! from `n = d₁ × d₂`, whose error is relative to `|d₁||d₂|`, not to its square; see
//! [`DISTANCE_ERR_REL`]). Degenerate triangles (segments, points) need no special case: their
//! vertex–face candidates are skipped (zero normal), their edges still count.

use super::tri_tri::triangles_intersect;
use crate::float::{gamma_f64, sqrt_f64};
use glam::{DVec3, Vec3};

/// Relative rounding bound of [`triangle_distance`], unitless, applied to `d + M` (module
/// docs). Why: a closest point `p + s·(q − p)` is within `γ₃·2M` per coordinate of a point of
/// its segment (difference, product, sum), a plane distance `|(x − a)·n|/|n|` within `γ₁₀` of
/// `|x − a| ≤ 2√3·M` times `|e₁||e₂|/|n| = 1/sin θ` (the normal is taken at the triangle's
/// largest angle `θ`, so this factor is at most 2 unless `θ > 150°`; for a flatter triangle
/// the face candidate's error grows as `1/sin θ`, a limit of this bound), and the final norm
/// adds `γ₅` relative; with both points, three
/// coordinates and the square root that is under `γ₃₂·(d + M)`. `γ₆₄` doubles it, which also
/// absorbs the rounding of the box distances the traversal compares against it.
///
/// Those terms bound how far a candidate lies from a genuine distance (so `d̃ ≥ d − ε·(d + M)`);
/// the excess above `d` also depends on how close the parameters are to the exact closest
/// pair. For two edges at angle `θ`, `s = n·(d₂ × r)/|n|²` with `n = d₁ × d₂`: each component
/// of `n` rounds by about `u·|d₁||d₂|`, so `s` is off by about `δs = u·r⊥/(|d₁| sin²θ)`, `r⊥`
/// the distance of `p₁` from the other edge's line (`≤ d* + |d₁| sin θ`, `d*` the lines'
/// distance). The squared distance along the edge is `d*² + (s − s*)²|d₁|² sin²θ`, stationary
/// at `s*`, so the excess is at most `√(d*² + X²) − d*` with `X = |d₁| sin θ·δs ≤ u·d*/sin θ +
/// u·|d₁|`, and at most the segment's own variation `(|d₁| sin θ)²/(2d*)`: for `X ≤ d*` the
/// smaller of `u²d*/(2 sin²θ)` and `|d₁|² sin²θ/(2d*)` is at most `u·|d₁|/2`, and for `X > d*`
/// (`sin θ < u`) the excess is at most `X ≤ 2u·|d₁|`: in all cases under `4√3·u·M`, inside the
/// doubling. (The textbook denominator `|d₁|²|d₂|² − (d₁·d₂)²` rounds by `u·|d₁|²|d₂|²`,
/// relative `u/sin²θ`: for `sin θ ≲ √u` its `s` is arbitrary and the excess reaches
/// `|d₁|² sin²θ/(2d*)`, e.g. `5·10⁻¹⁰` on edges `10⁻⁷` apart at `10⁻⁸` rad.) The parameter
/// `t`, the projection of the point at `s` onto the other edge, rounds by about `γ₃·(|d₁| + |r|)/|d₂|`
/// of that edge, again a stationary point: its excess is second order, or first order
/// `≤ γ₃·(|d₁| + |r|) ≤ γ₃·4√3·M` when `d*` is at that level.
pub const DISTANCE_ERR_REL: f64 = gamma_f64(64);

fn dv(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

/// The distance between the closed triangles `a` and `b` (same frame), in their coordinate
/// units: `0` exactly when they intersect, else the `f64` evaluation described in the module
/// docs (within [`DISTANCE_ERR_REL`]`·(d + M)` of the exact distance). `+∞` for a non-finite
/// vertex. Never panics.
#[must_use]
pub fn triangle_distance(a: &[Vec3; 3], b: &[Vec3; 3]) -> f64 {
    if !(a.iter().chain(b).all(|v| v.is_finite())) {
        return f64::INFINITY;
    }
    if triangles_intersect(a, b) {
        return 0.0;
    }
    let (a, b) = (a.map(dv), b.map(dv));
    let mut best = f64::INFINITY;
    for i in 0..3 {
        for j in 0..3 {
            let d = segment_distance(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
            best = best.min(d);
        }
    }
    for (x, t) in a.iter().map(|x| (x, &b)).chain(b.iter().map(|x| (x, &a))) {
        if let Some(d) = face_distance(*x, t) {
            best = best.min(d);
        }
    }
    best
}

/// Distance from `x` to the plane of `t` when `x` projects inside the closed triangle `t`
/// (`None` otherwise, or when `t` is degenerate). The normal is the cross product of the two
/// edges at the vertex opposite the longest edge, the largest angle: on a needle (two long
/// edges, one short) the product of the two long edges cancels, and the direction of its
/// rounded value is off by `u·|e₁||e₂|/|n|` (`10⁻⁷` rad and more on a sliver `10⁴` long and
/// `10⁻³` wide), while at the largest angle `|e₁||e₂|/|n| = 1/sin θ ≤ 2` unless `θ > 150°`.
fn face_distance(x: DVec3, t: &[DVec3; 3]) -> Option<f64> {
    let base = crate::triangle::largest_angle_vertex(t);
    let (a, b, c) = (t[base], t[(base + 1) % 3], t[(base + 2) % 3]);
    let n = (b - a).cross(c - a);
    let nn = n.length_squared();
    if !(nn > 0.0) {
        return None;
    }
    let inside = (0..3).all(|k| {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        (q - p).cross(x - p).dot(n) >= 0.0
    });
    inside.then(|| (x - a).dot(n).abs() / sqrt_f64(nn))
}

/// Distance between the closed segments `p1q1` and `p2q2` (either may be a point), by the
/// clamped closest-point parameters (Ericson, Real-Time Collision Detection §5.1.9), with the
/// lines' parameter `s` from `n = d₁ × d₂` (`|n|² = |d₁|²|d₂|² − (d₁·d₂)²` by Lagrange's
/// identity, without its cancellation: [`DISTANCE_ERR_REL`]).
pub(super) fn segment_distance(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> f64 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let (s, t) = if a == 0.0 && e == 0.0 {
        (0.0, 0.0)
    } else if a == 0.0 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e == 0.0 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            // s = (b·f − c·e)/(a·e − b²), both by Binet–Cauchy as products of cross products.
            let n = d1.cross(d2);
            let denom = n.length_squared();
            let s = if denom > 0.0 {
                (n.dot(d2.cross(r)) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t = (b * s + f) / e;
            if t < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s, t)
            }
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * t)).length()
}
