//! The exact triangle–triangle overlap test (Devillers & Guigue 2002, "Faster
//! triangle-triangle intersection tests"), on **closed** triangles of `f32` vertices.
//!
//! Every decision is an orientation sign from [`crate::predicates`], which is exact (a
//! filtered `f64` evaluation with an exact expansion fallback), so the answer is the exact
//! answer for the `f32` triangles as given: touching (a shared vertex, a vertex on a face, an
//! edge on an edge, coplanar overlap, even by a single point) counts as intersecting, and
//! triangles one `f32` step apart are reported apart. No tolerance is involved.
//!
//! * **General position**: Devillers–Guigue: the signs of each triangle's vertices against
//!   the other's plane, a canonical permutation, and two orientation tests on the intervals
//!   cut on the planes' intersection line.
//! * **Coplanar** triangles: the 2-D test ([`overlap_2d`]: edge–edge crossings, containment)
//!   in each of the three axis projections; they overlap iff all three projections do (one
//!   axis projection is injective on their common plane, and projections of overlapping sets
//!   overlap).
//! * **Degenerate** triangles (collinear vertices, segments or points, decided exactly): a
//!   degenerate triangle is the union of its three edges, so it is tested edge by edge
//!   against the other triangle ([`segment_triangle`]), or edge against edge when both are
//!   degenerate ([`segment_segment`]).
//! * Non-finite vertices: never intersecting (the BVH leaves such triangles out anyway).

use crate::predicates::{orient2d, orient3d};
use glam::Vec3;

/// The axis pairs `(i, j)` of the three axis projections (dropping `z`, `x`, `y`).
const PROJECTIONS: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];

/// `true` when the closed triangles `a` and `b` (vertices in the same frame) share at least
/// one point, decided exactly (module docs). Never panics; `false` for non-finite vertices.
#[must_use]
pub fn triangles_intersect(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    if !(a.iter().chain(b).all(|v| v.is_finite())) {
        return false;
    }
    match (is_degenerate(a), is_degenerate(b)) {
        (false, false) => devillers_guigue(a, b),
        (true, false) => edges(a).iter().any(|&(p, q)| segment_triangle(p, q, b)),
        (false, true) => edges(b).iter().any(|&(p, q)| segment_triangle(p, q, a)),
        (true, true) => edges(a)
            .iter()
            .any(|&(p, q)| edges(b).iter().any(|&(r, s)| segment_segment(p, q, r, s))),
    }
}

/// `true` when the three vertices are collinear (or coincide), exactly: the cross product
/// of two edges vanishes in all three axis projections.
#[must_use]
pub fn is_degenerate(t: &[Vec3; 3]) -> bool {
    PROJECTIONS
        .iter()
        .all(|&(i, j)| orient2d(t[0], t[1], t[2], i, j) == 0)
}

fn edges(t: &[Vec3; 3]) -> [(Vec3, Vec3); 3] {
    [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
}

/// The exact sides of `t`'s vertices of the plane through `plane`'s vertices: each the sign
/// [`orient3d`] gives (`1`, `−1`, or `0` on the plane).
fn plane_signs(plane: &[Vec3; 3], t: &[Vec3; 3]) -> [i32; 3] {
    let [a, b, c] = *plane;
    t.map(|x| orient3d(a, b, c, x))
}

/// `true` when the three signs are equal and non-zero: the triangle lies strictly on one
/// side of the plane.
fn strictly_one_side([p, q, r]: [i32; 3]) -> bool {
    p * q > 0 && p * r > 0
}

/// Devillers–Guigue for two non-degenerate triangles.
fn devillers_guigue(t1: &[Vec3; 3], t2: &[Vec3; 3]) -> bool {
    let [p1, q1, r1] = *t1;
    let [p2, q2, r2] = *t2;
    let s1 = plane_signs(t2, t1);
    if strictly_one_side(s1) {
        return false;
    }
    let s2 = plane_signs(t1, t2);
    if strictly_one_side(s2) {
        return false;
    }
    let [dp1, dq1, dr1] = s1;
    let [dp2, dq2, dr2] = s2;
    // Canonical form of T1's vertices: p1 alone on its side (or the appropriate zero case).
    let flip = [dp2, dr2, dq2];
    let (t1c, t2c, s) = if dp1 > 0 {
        if dq1 > 0 {
            ([r1, p1, q1], [p2, r2, q2], flip)
        } else if dr1 > 0 {
            ([q1, r1, p1], [p2, r2, q2], flip)
        } else {
            ([p1, q1, r1], [p2, q2, r2], s2)
        }
    } else if dp1 < 0 {
        if dq1 < 0 {
            ([r1, p1, q1], [p2, q2, r2], s2)
        } else if dr1 < 0 {
            ([q1, r1, p1], [p2, q2, r2], s2)
        } else {
            ([p1, q1, r1], [p2, r2, q2], flip)
        }
    } else if dq1 < 0 {
        if dr1 >= 0 {
            ([q1, r1, p1], [p2, r2, q2], flip)
        } else {
            ([p1, q1, r1], [p2, q2, r2], s2)
        }
    } else if dq1 > 0 {
        if dr1 > 0 {
            ([p1, q1, r1], [p2, r2, q2], flip)
        } else {
            ([q1, r1, p1], [p2, q2, r2], s2)
        }
    } else if dr1 > 0 {
        ([r1, p1, q1], [p2, q2, r2], s2)
    } else if dr1 < 0 {
        ([r1, p1, q1], [p2, r2, q2], flip)
    } else {
        return coplanar(t1, t2);
    };
    canonical_t2(t1c, t2c, s, t1, t2)
}

/// The second permutation (T2's vertices, given their signs against T1's plane) and the
/// final interval test.
fn canonical_t2(t1: [Vec3; 3], t2: [Vec3; 3], s: [i32; 3], o1: &[Vec3; 3], o2: &[Vec3; 3]) -> bool {
    let [p1, q1, r1] = t1;
    let [p2, q2, r2] = t2;
    let [dp2, dq2, dr2] = s;
    let (a, b) = if dp2 > 0 {
        if dq2 > 0 {
            ([p1, r1, q1], [r2, p2, q2])
        } else if dr2 > 0 {
            ([p1, r1, q1], [q2, r2, p2])
        } else {
            ([p1, q1, r1], [p2, q2, r2])
        }
    } else if dp2 < 0 {
        if dq2 < 0 {
            ([p1, q1, r1], [r2, p2, q2])
        } else if dr2 < 0 {
            ([p1, q1, r1], [q2, r2, p2])
        } else {
            ([p1, r1, q1], [p2, q2, r2])
        }
    } else if dq2 < 0 {
        if dr2 >= 0 {
            ([p1, r1, q1], [q2, r2, p2])
        } else {
            ([p1, q1, r1], [p2, q2, r2])
        }
    } else if dq2 > 0 {
        if dr2 > 0 {
            ([p1, r1, q1], [p2, q2, r2])
        } else {
            ([p1, q1, r1], [q2, r2, p2])
        }
    } else if dr2 > 0 {
        ([p1, q1, r1], [r2, p2, q2])
    } else if dr2 < 0 {
        ([p1, r1, q1], [r2, p2, q2])
    } else {
        return coplanar(o1, o2);
    };
    check_min_max(a, b)
}

/// The interval test of the canonical form: the two segments cut on the planes' common line
/// overlap iff neither orientation is positive.
fn check_min_max(t1: [Vec3; 3], t2: [Vec3; 3]) -> bool {
    let [p1, q1, r1] = t1;
    let [p2, q2, r2] = t2;
    // det[p2 − q1, p1 − q1, q2 − q1] and det[p2 − p1, r1 − p1, r2 − p1].
    orient3d(p2, p1, q1, q2) <= 0 && orient3d(p2, r1, p1, r2) <= 0
}

/// Coplanar triangles: the 2-D test must hold in all three axis projections (module docs).
fn coplanar(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    PROJECTIONS.iter().all(|&(i, j)| overlap_2d(a, b, i, j))
}

/// Whether the closed triangles `a` and `b` (possibly degenerate) overlap in the projection
/// onto axes `(i, j)`: some pair of edges meets, or a vertex of one lies in the other (tested
/// only for a triangle non-degenerate in this projection; a degenerate one is its edges).
pub(super) fn overlap_2d(a: &[Vec3; 3], b: &[Vec3; 3], i: usize, j: usize) -> bool {
    let crossing = edges(a).iter().any(|&(p, q)| {
        edges(b)
            .iter()
            .any(|&(r, s)| segments_meet_2d(p, q, r, s, i, j))
    });
    crossing || inside_2d(b[0], a, i, j) || inside_2d(a[0], b, i, j)
}

/// `p` in the closed triangle `t` projected on `(i, j)`; `false` when `t` is degenerate there.
fn inside_2d(p: Vec3, t: &[Vec3; 3], i: usize, j: usize) -> bool {
    let area = orient2d(t[0], t[1], t[2], i, j);
    if area == 0 {
        return false;
    }
    edges(t)
        .iter()
        .all(|&(a, b)| orient2d(a, b, p, i, j) * area >= 0)
}

/// Closed segments `pq` and `rs` meet in the projection on `(i, j)` (any may be a point).
fn segments_meet_2d(p: Vec3, q: Vec3, r: Vec3, s: Vec3, i: usize, j: usize) -> bool {
    let o1 = orient2d(p, q, r, i, j);
    let o2 = orient2d(p, q, s, i, j);
    let o3 = orient2d(r, s, p, i, j);
    let o4 = orient2d(r, s, q, i, j);
    if o1 * o2 < 0 && o3 * o4 < 0 {
        return true;
    }
    (o1 == 0 && in_box_2d(p, q, r, i, j))
        || (o2 == 0 && in_box_2d(p, q, s, i, j))
        || (o3 == 0 && in_box_2d(r, s, p, i, j))
        || (o4 == 0 && in_box_2d(r, s, q, i, j))
}

/// `x` within the axis-aligned box of `a` and `b` on axes `i` and `j` (exact comparisons);
/// for `x` collinear with `a, b` this is "`x` on the closed segment".
fn in_box_2d(a: Vec3, b: Vec3, x: Vec3, i: usize, j: usize) -> bool {
    [i, j].iter().all(|&k| {
        let (a, b, x) = (a[k % 3], b[k % 3], x[k % 3]);
        a.min(b) <= x && x <= a.max(b)
    })
}

/// The closed segment `pq` (possibly a point) meets the closed non-degenerate triangle `t`.
pub(super) fn segment_triangle(p: Vec3, q: Vec3, t: &[Vec3; 3]) -> bool {
    let sp = orient3d(t[0], t[1], t[2], p);
    let sq = orient3d(t[0], t[1], t[2], q);
    if sp * sq > 0 {
        return false;
    }
    if sp == 0 && sq == 0 {
        let seg = [p, q, q];
        return PROJECTIONS.iter().all(|&(i, j)| overlap_2d(&seg, t, i, j));
    }
    // The segment meets the plane in one point; it lies in the closed triangle iff the line
    // pq passes on the same side of (or touches) every edge: the signed volumes of
    // (p, q, a, b) over the three edges never have opposite signs.
    let vol = |a: Vec3, b: Vec3| orient3d(q, a, p, b);
    let v = [vol(t[0], t[1]), vol(t[1], t[2]), vol(t[2], t[0])];
    !(v.contains(&1) && v.contains(&-1))
}

/// The closed segments `pq` and `rs` (either may be a point) meet: coplanar, and meeting in
/// all three axis projections (one of which is injective on a plane containing both).
fn segment_segment(p: Vec3, q: Vec3, r: Vec3, s: Vec3) -> bool {
    orient3d(p, q, r, s) == 0
        && PROJECTIONS
            .iter()
            .all(|&(i, j)| segments_meet_2d(p, q, r, s, i, j))
}
