//! A test oracle for [`super::triangle_distance`] that shares none of its code: the distance
//! between two closed triangles as the smallest distance from an edge of either to the other
//! triangle, each edge–triangle distance enumerated from candidates that are all genuine
//! distances between a point of one triangle and a point of the other (so each is an upper
//! bound), one of which is the minimum:
//!
//! * the point where the edge crosses the triangle's plane (`0` when it lies inside);
//! * each endpoint against the triangle: the foot of the perpendicular when its barycentric
//!   coordinates (a 2 × 2 Gram solve) are in `[0, 1]`, else the three point–edge distances;
//! * the edge against each of the triangle's edges: the four endpoint–segment distances, and
//!   the minimum over the first edge of the point–segment distance to the second, found by a
//!   ternary search (the distance from a point moving along a line to a convex set is convex
//!   in the parameter). No closed-form solve: the Gram determinant `a·e − b²` of the usual
//!   formula cancels for nearly parallel edges (relative error `u/sin²θ`), the same
//!   cancellation the code under test must avoid.
//!
//! Why this covers the minimum: two disjoint convex polygons have a closest pair with a point
//! on an edge of one of them; if they intersect, an edge of one meets the other (or a vertex
//! lies inside it). Evaluated in `f64`; shared with the cross-crate suite through `#[path]`
//! (`tests/tests/mesh_collision.rs`), so it uses nothing of the crate.

use glam::{DVec3, Vec3};

/// Which kind of candidate gave the oracle's answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// An edge crossing the other triangle's plane.
    Crossing,
    /// A vertex's perpendicular foot inside the other triangle's face.
    VertexFace,
    /// The interiors of two edges (both line parameters strictly inside `(0, 1)`).
    EdgeEdge,
    /// An endpoint against a segment (vertex–edge or vertex–vertex).
    VertexEdge,
}

/// Distance from `x` to the closed segment `pq` (a point when `p = q`).
fn point_segment(x: DVec3, p: DVec3, q: DVec3) -> f64 {
    let d = q - p;
    let dd = d.dot(d);
    let s = if dd > 0.0 {
        ((x - p).dot(d) / dd).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (x - (p + d * s)).length()
}

/// Keeps the smaller of `best` and `(d, kind)`.
fn keep(best: &mut (f64, Feature), d: f64, kind: Feature) {
    if d < best.0 {
        *best = (d, kind);
    }
}

/// Distance from `x` to the closed triangle `t`, and the kind of its closest point.
fn point_triangle(x: DVec3, t: &[DVec3; 3]) -> (f64, Feature) {
    let mut best = (f64::INFINITY, Feature::VertexEdge);
    let (e0, e1, w) = (t[1] - t[0], t[2] - t[0], x - t[0]);
    let (g00, g01, g11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let det = g00 * g11 - g01 * g01;
    if det > 0.0 {
        let (r0, r1) = (w.dot(e0), w.dot(e1));
        let u = (g11 * r0 - g01 * r1) / det;
        let v = (g00 * r1 - g01 * r0) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
            keep(
                &mut best,
                (w - e0 * u - e1 * v).length(),
                Feature::VertexFace,
            );
        }
    }
    for k in 0..3 {
        keep(
            &mut best,
            point_segment(x, t[k], t[(k + 1) % 3]),
            Feature::VertexEdge,
        );
    }
    best
}

/// Ternary-search steps of [`segment_segment`]: each keeps 2/3 of the parameter interval, and
/// `(2/3)^100 ≈ 2.5·10⁻¹⁸` is below the `f64` resolution of a parameter in `[0, 1]`.
const TERNARY_STEPS: usize = 100;

/// A search result closer than this to an end of `[0, 1]` is that end (unitless): the final
/// interval is `(2/3)^100 ≈ 2⁻⁵⁸` wide, so a minimum at an end leaves `s < 2⁻⁵⁸`, and an
/// interior minimum this close to an end is a vertex–edge pair to within `2⁻⁵⁵` of the edge.
const ENDPOINT_S: f64 = 1.0 / 36_028_797_018_963_968.0;

/// Distance between the closed segments `p1q1` and `p2q2`: the endpoint–segment distances
/// (vertex–edge), and the minimum over `s ∈ [0, 1]` of the distance from `p1 + s·(q1 − p1)` to
/// the segment `p2q2` by ternary search (convex in `s`), an edge–edge pair when it is smaller
/// than all four.
fn segment_segment(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> (f64, Feature) {
    let mut best = (f64::INFINITY, Feature::VertexEdge);
    for (x, p, q) in [(p1, p2, q2), (q1, p2, q2), (p2, p1, q1), (q2, p1, q1)] {
        keep(&mut best, point_segment(x, p, q), Feature::VertexEdge);
    }
    let g = |s: f64| point_segment(p1 + (q1 - p1) * s, p2, q2);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..TERNARY_STEPS {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        let (g1, g2) = (g(m1), g(m2));
        // A convex function equal at m1 and m2 has its minimum between them.
        if g1 <= g2 {
            hi = m2;
        }
        if g1 >= g2 {
            lo = m1;
        }
    }
    let s = 0.5 * (lo + hi);
    // An edge–edge pair when the minimum is interior to both edges: `s` away from the ends
    // by more than the search's resolution, and the foot on the second edge strictly inside.
    let (d2, x) = (q2 - p2, p1 + (q1 - p1) * s);
    let t = (x - p2).dot(d2) / d2.dot(d2);
    let interior = (ENDPOINT_S..1.0 - ENDPOINT_S).contains(&s) && t > 0.0 && t < 1.0;
    let kind = if interior {
        Feature::EdgeEdge
    } else {
        Feature::VertexEdge
    };
    keep(&mut best, g(s), kind);
    best
}

/// Distance between the closed segment `pq` and the closed triangle `t`.
fn segment_triangle(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> (f64, Feature) {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let (sp, sq) = (n.dot(p - t[0]), n.dot(q - t[0]));
    let mut best = (f64::INFINITY, Feature::VertexEdge);
    for x in [p, q] {
        let (d, kind) = point_triangle(x, t);
        keep(&mut best, d, kind);
    }
    for k in 0..3 {
        let (d, kind) = segment_segment(p, q, t[k], t[(k + 1) % 3]);
        keep(&mut best, d, kind);
    }
    // Last, so that a tie goes to the kinds above.
    if (sp <= 0.0 && sq >= 0.0 || sp >= 0.0 && sq <= 0.0) && sp != sq {
        let x = p + (q - p) * (sp / (sp - sq));
        keep(&mut best, point_triangle(x, t).0, Feature::Crossing);
    }
    best
}

/// The oracle's distance between the closed triangles `a` and `b` and the kind of candidate
/// that gave it.
pub fn distance(a: &[Vec3; 3], b: &[Vec3; 3]) -> (f64, Feature) {
    let (a, b) = (a.map(Vec3::as_dvec3), b.map(Vec3::as_dvec3));
    let mut best = (f64::INFINITY, Feature::VertexEdge);
    for (x, y) in [(&a, &b), (&b, &a)] {
        for k in 0..3 {
            let (d, kind) = segment_triangle(x[k], x[(k + 1) % 3], y);
            keep(&mut best, d, kind);
        }
    }
    best
}

/// The largest coordinate magnitude of the two triangles (the `M` of the distance's error
/// bound).
pub fn magnitude(a: &[Vec3; 3], b: &[Vec3; 3]) -> f64 {
    a.iter()
        .chain(b)
        .map(|v| f64::from(v.abs().max_element()))
        .fold(0.0, f64::max)
}
