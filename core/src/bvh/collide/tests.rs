//! Unit tests of the collision module: exact predicates, the triangle–triangle test on
//! touching, coplanar, edge–edge, vertex–face, degenerate and just-apart cases with exact
//! expected answers, distances with exact expected values, and the traversal against brute
//! force on small scenes.

use super::tri_tri::segment_triangle;
use super::*;
use crate::bvh::BuildOptions;
use crate::mesh::TriangleMesh;
use crate::test_util::{VecBvh, grid_point, lcg, lcg_soup, vec_bvh};
use crate::transform::Transform;
use glam::{Vec3, vec3};
use std::vec;
use std::vec::Vec;

mod oracle;
use oracle::Feature;

/// `is_degenerate` decides collinearity exactly: a point one ulp off the line is not.
#[test]
fn is_degenerate_is_exact() {
    let (p, q) = (vec3(1.0, 1.0, 1.0), vec3(3.0, 3.0, 3.0));
    let r = vec3(2.0, 2.0, f32::from_bits(2.0f32.to_bits() + 1));
    assert_eq!(orient2d(p, q, r, 0, 1), 0);
    assert_eq!(orient2d(p, q, r, 1, 2), 1);
    assert!(!is_degenerate(&[p, q, r]));
    assert!(is_degenerate(&[p, q, vec3(2.0, 2.0, 2.0)]));
    assert!(is_degenerate(&[p, p, p]));
}

const A: [Vec3; 3] = [
    Vec3::new(0.0, 0.0, 0.0),
    Vec3::new(1.0, 0.0, 0.0),
    Vec3::new(0.0, 1.0, 0.0),
];

/// The triangle of the three points, each `[x, y, z]`.
fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> [Vec3; 3] {
    [a, b, c].map(Vec3::from_array)
}

fn moved(t: [Vec3; 3], d: Vec3) -> [Vec3; 3] {
    t.map(|v| v + d)
}

fn check(a: [Vec3; 3], b: [Vec3; 3], want: bool, what: &str) {
    assert_eq!(triangles_intersect(&a, &b), want, "{what}");
    assert_eq!(triangles_intersect(&b, &a), want, "{what} (swapped)");
    let rot = [b[1], b[2], b[0]];
    assert_eq!(triangles_intersect(&a, &rot), want, "{what} (rotated)");
    let flip = [b[0], b[2], b[1]];
    assert_eq!(triangles_intersect(&a, &flip), want, "{what} (flipped)");
}

#[test]
fn vertex_face_touching_and_just_apart() {
    let b = tri([0.25, 0.25, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]);
    check(A, b, true, "vertex on face");
    let tiny = f32::from_bits(1);
    check(
        A,
        moved(b, vec3(0.0, 0.0, tiny)),
        false,
        "vertex one subnormal above",
    );
    check(
        A,
        moved(b, vec3(0.0, 0.0, -tiny)),
        true,
        "vertex one subnormal below: pierces",
    );
    // The vertex exactly on A's edge, on its vertex, and just outside the hypotenuse.
    let on_edge = tri([0.5, 0.0, 0.0], [0.5, -1.0, 1.0], [0.5, 1.0, 1.0]);
    check(A, on_edge, true, "vertex on edge");
    let on_vertex = tri([1.0, 0.0, 0.0], [2.0, -1.0, 1.0], [2.0, 1.0, 1.0]);
    check(A, on_vertex, true, "vertex on vertex");
    let out = f32::from_bits(0.5f32.to_bits() + 1);
    let outside = tri([0.5, out, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]);
    check(A, outside, false, "vertex one ulp beyond the hypotenuse");
}

#[test]
fn edge_edge_touching_and_just_apart() {
    let a = tri([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]);
    let b = tri([0.0, 0.0, -1.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]);
    check(a, b, true, "edges cross at the origin");
    check(
        a,
        moved(b, vec3(0.0, 1.0e-7, 0.0)),
        false,
        "edges 1e-7 apart",
    );
    check(
        a,
        moved(b, vec3(0.0, -1.0e-7, 0.0)),
        true,
        "edges 1e-7 into each other",
    );
    // Crossing through each other's interiors (general position).
    let c = tri([0.0, -0.5, -1.0], [0.0, -0.5, 1.0], [0.0, 1.0, 0.0]);
    check(a, c, true, "proper crossing");
}

#[test]
fn coplanar_cases() {
    check(A, moved(A, vec3(0.2, 0.2, 0.0)), true, "overlapping");
    check(A, moved(A, vec3(1.0, 0.0, 0.0)), true, "sharing a vertex");
    let mirrored = tri([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]);
    check(A, mirrored, true, "sharing the hypotenuse");
    let e = f32::EPSILON;
    check(
        A,
        moved(mirrored, vec3(e, e, 0.0)),
        false,
        "hypotenuse one step apart",
    );
    let small = tri([0.1, 0.1, 0.0], [0.2, 0.1, 0.0], [0.1, 0.2, 0.0]);
    check(A, small, true, "contained");
    check(
        A,
        moved(A, vec3(0.6, 0.6, 0.0)),
        false,
        "boxes overlap, triangles do not",
    );
    // Coplanar in a tilted plane, with non-integer coordinates: x + y + z = 1.
    let t = tri([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    let u = tri([0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.75, 0.5, -0.25]);
    check(t, u, true, "tilted coplanar, sharing an edge midpoint line");
}

#[test]
fn degenerate_triangles() {
    let tiny = f32::from_bits(1);
    // A segment piercing A, a segment touching it, a point on it, a point off it.
    let seg = tri([0.2, 0.2, -1.0], [0.2, 0.2, 1.0], [0.2, 0.2, 0.0]);
    check(A, seg, true, "segment through the face");
    let seg_touch = tri([0.2, 0.2, 0.0], [0.2, 0.2, 1.0], [0.2, 0.2, 0.5]);
    check(A, seg_touch, true, "segment ending on the face");
    check(
        A,
        moved(seg_touch, vec3(0.0, 0.0, tiny)),
        false,
        "segment ending just above",
    );
    let point = [vec3(0.3, 0.3, 0.0); 3];
    check(A, point, true, "point on the face");
    check(A, [vec3(0.3, 0.3, tiny); 3], false, "point just above");
    // In-plane segment crossing an edge, and one just outside.
    let inplane = tri([-1.0, 0.5, 0.0], [0.25, 0.5, 0.0], [-1.0, 0.5, 0.0]);
    check(A, inplane, true, "in-plane segment crossing the x = 0 edge");
    check(
        A,
        moved(inplane, vec3(-0.25 - 1.0e-7, 0.0, 0.0)),
        false,
        "in-plane, short of it",
    );
    // Two segments: crossing, touching end to end, skew.
    let s1 = tri([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let s2 = tri([0.0, -1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]);
    check(s1, s2, true, "segments crossing");
    check(
        s1,
        moved(s2, vec3(0.0, 0.0, 1.0e-30)),
        false,
        "skew segments",
    );
    let s3 = tri([1.0, 0.0, 0.0], [3.0, 0.0, 0.0], [2.0, 0.0, 0.0]);
    check(s1, s3, true, "collinear segments sharing an end");
    check(
        s1,
        moved(s3, vec3(1.0e-7, 0.0, 0.0)),
        false,
        "collinear segments apart",
    );
    // Non-finite vertices never intersect.
    check(
        A,
        [vec3(f32::NAN, 0.0, 0.0), A[1], A[2]],
        false,
        "NaN vertex",
    );
}

/// Devillers–Guigue equals the edge decomposition (an edge of one triangle meets the other,
/// [`segment_triangle`]) on random small-grid triangles: touching, coplanar and degenerate
/// configurations in abundance.
#[test]
fn devillers_guigue_equals_edge_decomposition_on_grids() {
    let mut s = 11u64;
    let mut hits = 0;
    for _ in 0..40_000 {
        let a = [(); 3].map(|_| grid_point(&mut s, 2.0));
        let b = [(); 3].map(|_| grid_point(&mut s, 2.0));
        if is_degenerate(&a) || is_degenerate(&b) {
            continue;
        }
        let edges = |t: &[Vec3; 3], o: &[Vec3; 3]| {
            (0..3).any(|k| segment_triangle(t[k], t[(k + 1) % 3], o))
        };
        let want = edges(&a, &b) || edges(&b, &a);
        hits += usize::from(want);
        assert_eq!(triangles_intersect(&a, &b), want, "{a:?} {b:?}");
    }
    assert!(hits > 5000, "{hits}");
}

#[test]
fn distances_with_exact_values() {
    // Parallel planes 1 apart, overlapping in projection: vertex–face.
    let up = moved(A, vec3(0.1, 0.1, 1.0));
    assert_eq!(triangle_distance(&A, &up), 1.0);
    // A's edge y = 0 (x in [0, 1]) and a segment-like triangle along y at x = 0.5, z = 2,
    // y in [−3, −1]: closest points (0.5, 0, 0)–(0.5, −1, 2): √5.
    let b = tri([0.5, -1.0, 2.0], [0.5, -3.0, 2.0], [0.5, -2.0, 2.0]);
    let d = triangle_distance(&A, &b);
    assert!((d - 5f64.sqrt()).abs() <= 1e-15, "{d}");
    // Touching: exactly zero; one subnormal apart: positive but tiny.
    let touch = tri([0.25, 0.25, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]);
    assert_eq!(triangle_distance(&A, &touch), 0.0);
    let tiny = f32::from_bits(1);
    let apart = moved(touch, vec3(0.0, 0.0, tiny));
    let d = triangle_distance(&A, &apart);
    assert!(d > 0.0 && d <= 2.0 * f64::from(tiny), "{d:e}");
    // Edge–edge, skew, along the diagonal: the hypotenuse of A against a segment above its
    // midpoint crossing it at right angles, 2 higher.
    let c = tri([0.0, 0.0, 2.0], [1.0, 1.0, 2.0], [0.5, 0.5, 2.0]);
    assert!((triangle_distance(&A, &c) - 2.0).abs() <= 1e-15);
    assert_eq!(
        triangle_distance(&A, &[vec3(f32::NAN, 0.0, 0.0); 3]),
        f64::INFINITY
    );
}

fn tree(mesh: &TriangleMesh<'_>) -> VecBvh {
    vec_bvh(mesh, &BuildOptions::default()).unwrap()
}

/// A placement that scales by `2⁻¹⁰⁰` puts the second mesh's vertices in `f32`'s subnormal
/// range, where `point_to_world` rounds absolutely: `(1000.75)·2⁻⁴⁹ · 2⁻¹⁰⁰` rounds up to
/// `1001·2⁻¹⁴⁹`, 3.5e-46 beyond its exact image, while the relative pad is 3.3e-49. The first
/// mesh's triangle has its vertex exactly at that rounded point, so the two touch (the exact
/// test says so): the query must find the pair (it returned none), and the distance 0.
#[test]
fn a_placement_into_the_subnormal_range_keeps_a_touching_pair() {
    let s = 2f32.powi(-100);
    let tf = Transform::scale(Vec3::splat(s)).unwrap();
    let x = 1000.75 * 2f32.powi(-49);
    let (l, e) = (2f32.powi(-40), 2f32.powi(-140));
    let pb = [vec3(x, 0.0, 0.0), vec3(x - l, l, 0.0), vec3(x - l, 0.0, l)];
    let xa = tf.point_to_world(pb[0]).x;
    assert_eq!(xa, 1001.0 * 2f32.powi(-149), "the image rounds up");
    let pa = [
        vec3(xa, 0.0, 0.0),
        vec3(xa + e, e, 0.0),
        vec3(xa + e, 0.0, e),
    ];
    let t = [[0u32, 1, 2]];
    let (ma, mb) = (TriangleMesh::new(&pa, &t), TriangleMesh::new(&pb, &t));
    let (ta, tb) = (tree(&ma), tree(&mb));
    let (a, b) = (Body::new(&ta, ma).unwrap(), Body::new(&tb, mb).unwrap());
    let placed = pb.map(|v| tf.point_to_world(v));
    assert!(triangles_intersect(&pa, &placed));
    let mut out = [(0u32, 0u32); 2];
    assert_eq!(colliding_pairs(&a, &b, &tf, &mut out).unwrap(), 1);
    assert_eq!(out[0], (0, 0));
    assert!(first_contact(&a, &b, &tf).unwrap().is_some());
    assert_eq!(
        min_distance(&a, &b, &tf, 0.0).unwrap().map(|m| m.distance),
        Some(0.0)
    );
}

#[test]
fn traversal_equals_brute_force_on_small_soups() {
    let mut s = 3u64;
    let mut pairs = 0;
    for round in 0..20 {
        let (pa, ta) = lcg_soup(60, 2 * round + 3, 4.0, 1.0);
        let (pb, tb) = lcg_soup(50, 2 * round + 4, 4.0, 1.0);
        let (ma, mb) = (TriangleMesh::new(&pa, &ta), TriangleMesh::new(&pb, &tb));
        let (ba, bb) = (tree(&ma), tree(&mb));
        let (a, b) = (Body::new(&ba, ma).unwrap(), Body::new(&bb, mb).unwrap());
        let tf = Transform::rotate(vec3(lcg(&mut s), 1.0, lcg(&mut s)), lcg(&mut s) * 6.0)
            .unwrap()
            .then(&Transform::translate(vec3(0.5, -0.3, 0.2) * round as f32 * 0.1).unwrap())
            .unwrap();
        let mut want = Vec::new();
        let mut best: Option<(f64, u32, u32)> = None;
        // The oracle's smallest distance, and the largest coordinate magnitude seen.
        let mut independent = (f64::INFINITY, 0.0f64);
        for i in 0..ta.len() {
            for j in 0..tb.len() {
                let x = ma.triangle(i).unwrap();
                let y = mb.triangle(j).unwrap().map(|v| tf.point_to_world(v));
                if triangles_intersect(&x, &y) {
                    want.push((i as u32, j as u32));
                }
                let d = triangle_distance(&x, &y);
                if best.is_none_or(|b| d < b.0) {
                    best = Some((d, i as u32, j as u32));
                }
                independent.0 = independent.0.min(oracle::distance(&x, &y).0);
                independent.1 = independent.1.max(oracle::magnitude(&x, &y));
            }
        }
        pairs += want.len();
        let mut out = vec![(0u32, 0u32); want.len() + 3];
        let n = colliding_pairs(&a, &b, &tf, &mut out).unwrap();
        let mut got = out[..n].to_vec();
        got.sort_unstable();
        assert_eq!(got, want, "round {round}");
        let first = first_contact(&a, &b, &tf).unwrap();
        assert_eq!(first.is_some(), !want.is_empty());
        assert!(first.is_none_or(|p| want.contains(&p)));
        if want.len() > 1 {
            let mut short = vec![(0u32, 0u32); 1];
            assert_eq!(
                colliding_pairs(&a, &b, &tf, &mut short),
                Err(CollideError::OutputTooSmall {
                    needed: want.len(),
                    available: 1
                })
            );
            assert!(want.contains(&short[0]));
        }
        let (d, i, j) = best.unwrap();
        let c = min_distance(&a, &b, &tf, f64::INFINITY).unwrap().unwrap();
        assert_eq!((c.distance, c.a, c.b), (d, i, j), "round {round}");
        let (o, m) = independent;
        assert!(
            (c.distance - o).abs() <= 2.0 * DISTANCE_ERR_REL * (o + m),
            "round {round}: {} against the oracle's {o}",
            c.distance
        );
        assert_eq!(min_distance(&a, &b, &tf, d).unwrap(), Some(c));
        if d > 0.0 {
            assert_eq!(min_distance(&a, &b, &tf, d * 0.999).unwrap(), None);
        }
    }
    // The soups are dense enough that the pair lists are not all empty.
    assert!(pairs > 40, "only {pairs} colliding pairs in 20 rounds");
}

#[test]
fn errors_and_empty_inputs() {
    let (p, t) = lcg_soup(10, 1, 2.0, 1.0);
    let mesh = TriangleMesh::new(&p, &t);
    let bvh = tree(&mesh);
    let fewer = TriangleMesh::new(&p, &t[..5]);
    assert_eq!(
        Body::new(&bvh, fewer).unwrap_err(),
        CollideError::MeshMismatch { bvh: 10, mesh: 5 }
    );
    let body = Body::new(&bvh, mesh).unwrap();
    let id = Transform::IDENTITY;
    for bad in [f64::NAN, -1.0] {
        assert_eq!(
            min_distance(&body, &body, &id, bad),
            Err(CollideError::InvalidMaxDistance)
        );
    }
    // Against itself, every triangle touches itself: at least 10 pairs, counted with no room.
    match colliding_pairs(&body, &body, &id, &mut []) {
        Err(CollideError::OutputTooSmall {
            needed,
            available: 0,
        }) => assert!(needed >= 10),
        other => panic!("{other:?}"),
    }
    let empty_mesh = TriangleMesh::new(&[], &[]);
    let empty = tree(&empty_mesh);
    let e = Body::new(&empty, empty_mesh).unwrap();
    assert_eq!(colliding_pairs(&e, &body, &id, &mut []), Ok(0));
    assert_eq!(first_contact(&body, &e, &id), Ok(None));
    assert_eq!(min_distance(&e, &body, &id, f64::INFINITY), Ok(None));
    assert!(std::format!("{}", CollideError::TreeTooDeep).contains("stack"));
}

/// Needles `10⁴` long and `10⁻³` wide (a far vertex and two close ones), against triangles
/// near their short edge: the face candidate's normal from the far vertex cancelled, and the
/// distance came out `6.5·10⁻⁷` low (`1.4·10⁴` times the bound), so `min_distance` with the
/// brute-force minimum as its limit pruned the only pair. Expected distances from exact
/// rational arithmetic on the same `f32` inputs (a probe outside this crate).
#[test]
fn needles_keep_the_distance_bound_and_min_distance_finds_them() {
    let cases = [
        (
            [
                vec3(0.2634921, 0.87847114, -0.31220865),
                vec3(0.19537583, 0.1475939, 0.17875943),
                vec3(-0.00014135242, -0.05939707, 0.05485779),
            ],
            [
                vec3(-5919.4106, 6754.426, 4398.207),
                vec3(0.2945272, 0.94170314, -0.37635598),
                vec3(0.2960187, 0.94220704, -0.37512246),
            ],
            9.518938639515215e-2,
        ),
        (
            [
                vec3(-0.26733798, 0.028941803, 0.49950626),
                vec3(0.032662034, 0.1289418, 1.4995062),
                vec3(-0.46733797, 0.32894182, 1.4995062),
            ],
            [
                vec3(8944.808, 4470.5576, -0.21445256),
                vec3(-0.2674749, 0.029173864, 0.24657977),
                vec3(-0.26720667, 0.028637158, 0.24657977),
            ],
            2.529264992462051e-1,
        ),
        (
            [
                vec3(0.7043325, 0.70375013, 0.7917718),
                vec3(1.0043325, 0.80375016, 1.7917719),
                vec3(0.5043325, 1.0037501, 1.7917719),
            ],
            [
                vec3(-5739.925, -8187.4077, -1.902889),
                vec3(0.7045284, 0.7036429, 0.70546293),
                vec3(0.70403713, 0.7039873, 0.70546293),
            ],
            8.630890003860553e-2,
        ),
    ];
    for (k, (a, b, exact)) in cases.into_iter().enumerate() {
        let m = a
            .iter()
            .chain(&b)
            .map(|v| f64::from(v.abs().max_element()))
            .fold(0.0, f64::max);
        for (x, y) in [(&a, &b), (&b, &a)] {
            let got = triangle_distance(x, y);
            assert!(
                (got - exact).abs() <= DISTANCE_ERR_REL * (exact + m),
                "case {k}: {got} against {exact}"
            );
        }
        let t = [[0u32, 1, 2]];
        let (ma, mb) = (TriangleMesh::new(&a, &t), TriangleMesh::new(&b, &t));
        let (ta, tb) = (tree(&ma), tree(&mb));
        let (ba, bb) = (Body::new(&ta, ma).unwrap(), Body::new(&tb, mb).unwrap());
        let d = triangle_distance(&a, &b);
        let found = min_distance(&ba, &bb, &Transform::IDENTITY, d).unwrap();
        assert_eq!(
            found.map(|c| (c.distance, c.a, c.b)),
            Some((d, 0, 0)),
            "case {k}"
        );
    }
}

/// `|got − want| ≤ 2·DISTANCE_ERR_REL·(want + M)`: the function's documented bound, doubled
/// for the oracle's own `f64` rounding (of the same order).
fn assert_near_oracle(a: &[Vec3; 3], b: &[Vec3; 3], what: &str) -> (f64, Feature) {
    let (want, kind) = oracle::distance(a, b);
    let bound = 2.0 * DISTANCE_ERR_REL * (want + oracle::magnitude(a, b));
    for (x, y) in [(a, b), (b, a)] {
        let got = triangle_distance(x, y);
        assert!(
            (got - want).abs() <= bound,
            "{what}: {got:e} against the oracle's {want:e} ({kind:?}), bound {bound:e}: {x:?} {y:?}"
        );
    }
    (want, kind)
}

/// The triangle's vertices in every order: three rotations, each also reversed.
fn orders(t: [Vec3; 3]) -> [[Vec3; 3]; 6] {
    [
        t,
        [t[1], t[2], t[0]],
        [t[2], t[0], t[1]],
        [t[0], t[2], t[1]],
        [t[2], t[1], t[0]],
        [t[1], t[0], t[2]],
    ]
}

/// Two vertical triangles whose closest pair joins the interiors of two edges that are not
/// perpendicular (53° apart): `A`'s edge `(−1, 0, 0)–(1, 0, 0)` (A below it, in `y = 0`) and
/// `B`'s edge along `(3, 4, 0)` at `z = 1` (B above it, in a vertical plane). Every point of
/// A has `z ≤ 0` and of B `z ≥ 1`, with equality only on those two edges, whose projections
/// cross once: the distance is exactly 1, at edge parameters that move with B's shift. No
/// vertex projects into the other face (all project beyond `z` range). In every vertex order
/// of both triangles and both argument orders.
#[test]
fn interior_edge_edge_minimum_of_non_perpendicular_edges() {
    let a = tri([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
    let b = tri([-1.0, -2.0, 1.0], [2.0, 2.0, 1.0], [0.5, 0.0, 2.0]);
    for shift in [
        vec3(0.0, 0.0, 0.0),
        vec3(0.1, 0.3, 0.0),
        vec3(-0.75, 0.5, 0.0),
        vec3(-0.5, -1.0, 0.0),
    ] {
        let b = moved(b, shift);
        for x in orders(a) {
            for y in orders(b) {
                assert_eq!(triangle_distance(&x, &y), 1.0, "{shift}: {x:?} {y:?}");
                assert_eq!(triangle_distance(&y, &x), 1.0, "{shift}: {y:?} {x:?}");
            }
        }
        assert_eq!(
            assert_near_oracle(&a, &b, "vertical"),
            (1.0, Feature::EdgeEdge)
        );
    }
}

/// A general skew case, no edge along an axis: `A`'s edge along `u = (2, 1, 2)` from the
/// origin and `B`'s along `v = (2, −2, 1)` (`u·v = 4`, 64° apart), their common normal
/// `n = u × v = (5, 2, −6)`. B's edge starts at `Q = u/4 − v/2 + n/8`, so the lines' closest
/// pair is at parameters `1/4` and `1/2`, `|n|/8 = √65/8` apart; A's third vertex lies on the
/// `−n` side of its edge, B's on the `+n` side, so the slab between the two edges' planes
/// (normal `n`) separates the triangles and only those edges touch it: the distance is
/// `√65/8`, at the edges' interiors. Every coordinate is dyadic, so exact in `f32`.
#[test]
fn interior_edge_edge_minimum_skew() {
    let a = tri([0.0, 0.0, 0.0], [2.0, 1.0, 2.0], [-0.25, 0.0, 2.5]);
    let b = tri(
        [0.125, 1.5, -0.75],
        [2.125, -0.5, 0.25],
        [2.375, 1.0, -1.75],
    );
    let want = 65f64.sqrt() / 8.0;
    for x in orders(a) {
        for y in orders(b) {
            for d in [triangle_distance(&x, &y), triangle_distance(&y, &x)] {
                assert!((d - want).abs() <= 4.0 * f64::EPSILON, "{d} {want}");
            }
        }
    }
    let (d, kind) = assert_near_oracle(&a, &b, "skew");
    assert_eq!(kind, Feature::EdgeEdge);
    assert!((d - want).abs() <= 4.0 * f64::EPSILON);
}

/// Point-sized triangles (three equal vertices): against a triangle, the point–triangle
/// distance (to the face, an edge's interior, a vertex; zero on it); between two points,
/// their distance.
#[test]
fn point_sized_triangles() {
    let point = |x: f32, y: f32, z: f32| [vec3(x, y, z); 3];
    let cases = [
        // Above the face.
        (point(0.25, 0.25, 5.0), 5.0),
        // Beyond the hypotenuse's interior: to (0.5, 0.5, 0), √(1.5² + 1.5² + 1).
        (point(2.0, 2.0, 1.0), 5.5f64.sqrt()),
        // Beyond the vertex (1, 0, 0): (3, −2, 0) away... √(4 + 4).
        (point(3.0, -2.0, 0.0), 8f64.sqrt()),
        // Below the leg y = 0, in the plane: 0.5.
        (point(0.5, -0.5, 0.0), 0.5),
        // On the face, on an edge, on a vertex: touching.
        (point(0.25, 0.25, 0.0), 0.0),
        (point(0.5, 0.5, 0.0), 0.0),
        (point(0.0, 1.0, 0.0), 0.0),
    ];
    for (p, want) in cases {
        for t in orders(A) {
            for d in [triangle_distance(&p, &t), triangle_distance(&t, &p)] {
                assert!((d - want).abs() <= 4.0 * f64::EPSILON, "{p:?}: {d} {want}");
            }
        }
        assert_near_oracle(&p, &A, "point");
    }
    // Two points: 3-4-12 gives 13; the same point: 0.
    let (p, q) = (point(1.0, 2.0, 3.0), point(4.0, 6.0, 15.0));
    assert_eq!(triangle_distance(&p, &q), 13.0);
    assert_eq!(triangle_distance(&p, &p), 0.0);
    // A point against a segment-sized triangle: to its interior, and past its end.
    let seg = tri([0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [2.0, 0.0, 0.0]);
    for s in orders(seg) {
        assert_eq!(triangle_distance(&point(1.0, 3.0, 4.0), &s), 5.0);
        assert_eq!(triangle_distance(&s, &point(7.0, 4.0, 0.0)), 5.0);
    }
}

/// Random pairs of triangles, general and degenerate (segments, points, repeated vertices),
/// touching, crossing, near and far, at scales 2⁻²⁰ to 2²⁰: `triangle_distance` within its
/// documented bound of the oracle. The sample covers every kind of closest pair.
#[test]
fn distance_equals_the_independent_oracle_on_random_pairs() {
    let mut s = 41u64;
    let mut kinds = [0usize; 4];
    let (mut skew_interior, mut degenerate, mut zero) = (0, 0, 0);
    for k in 0..20_000 {
        let scale = [1.0, 2f32.powi(-20), 2f32.powi(20)][k % 3];
        // Integer vertices (exact touching and coplanar cases) or continuous ones.
        let snapped = k % 2 == 0;
        let t = |s: &mut u64| {
            let v = |s: &mut u64, n: f32| {
                if snapped {
                    grid_point(s, n)
                } else {
                    vec3(lcg(s) - 0.5, lcg(s) - 0.5, lcg(s) - 0.5) * 2.0 * n
                }
            };
            let c = v(s, 2.0);
            [0; 3].map(|_| c + v(s, 1.0))
        };
        let (mut a, mut b) = (t(&mut s), t(&mut s));
        match k % 7 {
            0 => b[2] = b[1],
            1 => a = [a[0]; 3],
            2 => b[2] = b[0].lerp(b[1], 0.25),
            3 => {
                // Both points, or a point and a segment.
                a = [a[0]; 3];
                b = [b[0], b[1], b[1]];
            }
            _ => {}
        }
        let (a, b) = (a.map(|v| v * scale), b.map(|v| v * scale));
        degenerate += usize::from(is_degenerate(&a) || is_degenerate(&b));
        let (d, kind) = assert_near_oracle(&a, &b, "random");
        zero += usize::from(d == 0.0 || triangle_distance(&a, &b) == 0.0);
        kinds[kind as usize] += 1;
        if kind == Feature::EdgeEdge && !is_degenerate(&a) && !is_degenerate(&b) {
            skew_interior += 1;
        }
    }
    assert!(kinds.iter().all(|&n| n > 50), "{kinds:?}");
    assert!(
        skew_interior > 1000 && degenerate > 5000 && zero > 100,
        "{skew_interior} {degenerate} {zero}"
    );
}

/// `segment_distance` on one worked case per branch (distances by hand): two points; a point
/// against a segment (its foot at `t = 1/4`); a segment against a point past its end; skew
/// segments at 45° whose closest points are both interior (`z = 0` and `z = 2` planes, `2`);
/// the far segment's start `p2` nearest (`t < 0`: `s` recomputed for `p2`, the foot at
/// `s = 1/2` of a segment of squared length 4), the same reversed (`t > 1`, from `q2`), and
/// parallel segments (`denom = 0`), whose nearest points are an end of each (`√2`).
#[test]
fn segment_distance_worked_case_of_each_branch() {
    use super::distance::segment_distance;
    use glam::DVec3;
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let o = DVec3::ZERO;
    let cases = [
        ((o, o, v(3.0, 4.0, 0.0), v(3.0, 4.0, 0.0)), 5.0),
        (
            (v(1.0, 1.0, 0.0), v(1.0, 1.0, 0.0), o, v(4.0, 0.0, 0.0)),
            1.0,
        ),
        (
            (o, v(4.0, 0.0, 0.0), v(5.0, 2.0, 0.0), v(5.0, 2.0, 0.0)),
            5f64.sqrt(),
        ),
        (
            (
                v(-1.0, 0.0, 0.0),
                v(3.0, 0.0, 0.0),
                v(0.0, -1.0, 2.0),
                v(2.0, 1.0, 2.0),
            ),
            2.0,
        ),
        (
            (o, v(2.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(1.0, 3.0, 0.0)),
            1.0,
        ),
        (
            (o, v(2.0, 0.0, 0.0), v(1.0, 3.0, 0.0), v(1.0, 1.0, 0.0)),
            1.0,
        ),
        (
            (o, v(2.0, 0.0, 0.0), v(3.0, 1.0, 0.0), v(5.0, 1.0, 0.0)),
            2f64.sqrt(),
        ),
    ];
    for (k, ((p1, q1, p2, q2), want)) in cases.into_iter().enumerate() {
        for (d, what) in [
            (segment_distance(p1, q1, p2, q2), "as given"),
            (segment_distance(q1, p1, q2, p2), "both reversed"),
            (segment_distance(p2, q2, p1, q1), "swapped"),
        ] {
            assert!(
                (d - want).abs() <= 1e-15 * want,
                "case {k} {what}: {d} against {want}"
            );
        }
    }
}

/// `min_distance` at the bound of the brute-force minimum, on a pair whose distance is hard to
/// round: `A` is a long, slightly tilted triangle listed from its far vertex (`2⁴⁶` away, so
/// `M ≈ 7·10¹³`), its top edge `(±1, 0, 0)` at `z = 0`; `B` is small, its lowest vertex `x` at
/// `z = 1` above A's face. The boxes overlap in `x` and `y` and are exactly `1` apart in `z`,
/// so the exact distance is at least `1`. With the face candidate's normal taken at A's far
/// vertex, its terms of size `2⁴⁶·θ` (`θ ≈ 1.2·10⁻³` the tilt) cancelled and it rounded to
/// `1 − 7·10⁻⁷`, below the box distance, and only the pruning pad `ε·M` ([`DISTANCE_ERR_REL`])
/// kept the pair; at the largest angle it no longer cancels (within `ε·(d + M)` of the
/// oracle either way). `min_distance` must report the pair with the bound at the brute-force
/// minimum (computed in the test over every pair) and with no bound.
#[test]
fn min_distance_keeps_a_pair_whose_distance_rounds_below_its_box_distance() {
    let pa = vec![
        vec3(0.20961452, -70368744000000.0, -83128110000.0),
        vec3(-1.0, 0.0, 0.0),
        vec3(1.0, 0.0, 0.0),
    ];
    let x = vec3(0.0591442, -0.0016899328, 1.0);
    // B: a far copy (triangle 0) and the near triangle (1).
    let near = [x, x + vec3(0.25, 0.0, 0.5), x + vec3(0.0, -0.25, 0.5)];
    let mut pb: Vec<Vec3> = near.iter().map(|&v| v + vec3(0.0, 0.0, 3.0)).collect();
    pb.extend(near);
    let (ta, tb) = (vec![[0u32, 1, 2]], vec![[0u32, 1, 2], [3, 4, 5]]);
    let (ma, mb) = (TriangleMesh::new(&pa, &ta), TriangleMesh::new(&pb, &tb));
    // The boxes' distance, exactly: A's top is z = 0, the near triangle's bottom z = 1.
    let box_distance = 1.0;
    let mut best: Option<(f64, u32, u32)> = None;
    for j in 0..tb.len() {
        let d = triangle_distance(&ma.triangle(0).unwrap(), &mb.triangle(j).unwrap());
        if best.is_none_or(|b| d < b.0) {
            best = Some((d, 0, j as u32));
        }
    }
    let (d, i, j) = best.unwrap();
    assert_eq!((i, j), (0, 1));
    let eps = DISTANCE_ERR_REL;
    assert!(d >= box_distance * (1.0 - 2.0 * eps), "{d}");
    let (o, _) = oracle::distance(&ma.triangle(0).unwrap(), &near);
    let m = oracle::magnitude(&ma.triangle(0).unwrap(), &near);
    assert!(
        (d - o).abs() <= 2.0 * eps * (o + m),
        "{d} against the oracle's {o}"
    );
    let (ba, bb) = (tree(&ma), tree(&mb));
    let (a, b) = (Body::new(&ba, ma).unwrap(), Body::new(&bb, mb).unwrap());
    let want = Some(Closest {
        distance: d,
        a: 0,
        b: 1,
    });
    for bound in [d, f64::INFINITY] {
        assert_eq!(
            min_distance(&a, &b, &Transform::IDENTITY, bound).unwrap(),
            want,
            "bound {bound}"
        );
    }
}

/// `Body::new` refuses a tree that does not bound its mesh
/// ([`CollideError::TriangleOutsideTree`]): the audit's reproducer, a tree of triangle A given
/// with A moved 50 away (accepted before, and `first_contact` then missed a probe crossing
/// the moved triangle), and a vertex one ulp past its leaf's box (exact boxes, exact check).
/// A tree that bounds its mesh is accepted: the moved mesh after a refit (which then finds
/// the contact), and a mesh whose vertex went NaN since a refit (the refit keeps the tree
/// usable, and every query leaves that triangle out).
#[test]
fn a_body_whose_tree_does_not_bound_its_mesh_is_refused() {
    let one = [[0u32, 1, 2]];
    let a = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let moved = a.map(|p| p + vec3(50.0, 0.0, 0.0));
    let (ma, mb) = (TriangleMesh::new(&a, &one), TriangleMesh::new(&moved, &one));
    let mut bvh = tree(&ma);
    assert_eq!(
        Body::new(&bvh, mb).unwrap_err(),
        CollideError::TriangleOutsideTree { triangle: 0 }
    );
    let mut ulp = a;
    ulp[1].x = ulp[1].x.next_up();
    assert_eq!(
        Body::new(&bvh, TriangleMesh::new(&ulp, &one)).unwrap_err(),
        CollideError::TriangleOutsideTree { triangle: 0 }
    );
    Body::new(&bvh, ma).unwrap();
    let p = [
        vec3(50.2, 0.2, -1.0),
        vec3(50.2, 0.2, 1.0),
        vec3(50.3, 0.3, 1.0),
    ];
    assert!(triangles_intersect(&moved, &p));
    let pm = TriangleMesh::new(&p, &one);
    let probe_tree = tree(&pm);
    let probe = Body::new(&probe_tree, pm).unwrap();
    bvh.refit(&mb).unwrap();
    let body = Body::new(&bvh, mb).unwrap();
    assert_eq!(
        first_contact(&body, &probe, &Transform::IDENTITY),
        Ok(Some((0, 0)))
    );
    // In a tree of many leaves, the check reads every leaf: the last triangle moved.
    let (pos, tris) = lcg_soup(200, 7, 4.0, 1.0);
    let soup = TriangleMesh::new(&pos, &tris);
    let mut big = tree(&soup);
    assert!(big.node_count() > 50);
    let mut far = pos.clone();
    for v in &mut far[3 * 199..] {
        *v += vec3(0.0, 0.0, 100.0);
    }
    let far_mesh = TriangleMesh::new(&far, &tris);
    assert_eq!(
        Body::new(&big, far_mesh).unwrap_err(),
        CollideError::TriangleOutsideTree { triangle: 199 }
    );
    let mut nan = pos.clone();
    nan[3 * 120] = Vec3::NAN;
    let nan_mesh = TriangleMesh::new(&nan, &tris);
    assert!(
        big.refit(&nan_mesh).is_err(),
        "refit names the NaN triangle"
    );
    Body::new(&big, nan_mesh).unwrap();
}

/// Nearly parallel edges whose closest pair joins their interiors. The reviewer's case:
/// `A = [(−1, 0, 0), (1, 0, 0), (0, −1, 0)]` (`y ≤ 0`) and `B = [(−1, h, e), (1, h, −e),
/// (0, 1, 0)]` (`y ≥ h`) with `h = 10⁻⁷`, `e = 10⁻⁸`: the slab `0 < y < h` separates them and
/// B's edge crosses `z = 0` at `(0, h, 0)`, `h` from A's edge, so the distance is exactly `h`;
/// the closest-point parameter from the Gram determinant `a·e − b²` (relative error
/// `u/sin²θ`, here `θ = 10⁻⁸`) gave `1.005·10⁻⁷`, 70 000 times the bound. The sweep moves
/// A's third vertex to `(0, −1, −1)` (A in the plane `y = z`) and B's to `(0, h + 1, −1/L)`
/// (B's plane has normal `(e, 1, L)`), with B's edge `(∓L, h, ±e)`, `e < h`: still `y ≤ 0`
/// against `y ≥ h` and the same closest pair, exactly `h` apart, but now no edge crosses the
/// other triangle's plane at that pair (A's line meets B's plane at `x = h/e > 1`, and B's
/// edge has `y − z = h ± e > 0`), so an oracle must find it as an edge–edge minimum — the
/// oracle's own closed form had the same cancellation. Over `h`, `e/h`, `L`, axis
/// permutations and mirrors (all exact), in both argument orders, against `h` for both the
/// function and the oracle.
#[test]
fn nearly_parallel_edges_keep_their_interior_closest_pair() {
    let check_case = |a: &[Vec3; 3], b: &[Vec3; 3], h: f32| {
        let (h, m) = (f64::from(h), oracle::magnitude(a, b));
        let bound = DISTANCE_ERR_REL * (h + m);
        for (x, y) in [(a, b), (b, a)] {
            let got = triangle_distance(x, y);
            assert!(
                (got - h).abs() <= bound,
                "{got:e} against {h:e}: {x:?} {y:?}"
            );
        }
        let (o, _) = oracle::distance(a, b);
        assert!(
            (o - h).abs() <= bound,
            "oracle {o:e} against {h:e}: {a:?} {b:?}"
        );
    };
    let a = tri([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]);
    let b = tri([-1.0, 1e-7, 1e-8], [1.0, 1e-7, -1e-8], [0.0, 1.0, 0.0]);
    for x in orders(a) {
        for y in orders(b) {
            check_case(&x, &y, 1e-7);
        }
    }
    let mut s = 3u64;
    let perms = [
        [0, 1, 2],
        [1, 2, 0],
        [2, 0, 1],
        [0, 2, 1],
        [2, 1, 0],
        [1, 0, 2],
    ];
    for k in 0..5_000 {
        let h = 2f32.powi(-3 - (lcg(&mut s) * 27.0) as i32) * (1.0 + lcg(&mut s));
        let e = h * 2f32.powi(-1 - (lcg(&mut s) * 40.0) as i32) * (1.0 + lcg(&mut s));
        let l = [0.5, 1.0, 2.0, 4.0][k % 4];
        let sign = vec3(1.0, -1.0, 1.0) * if k % 2 == 0 { 1.0 } else { -1.0 };
        let perm = perms[k % 6];
        let map = |v: Vec3| Vec3::from_array(perm.map(|i| v[i])) * sign;
        let a = [
            vec3(-1.0, 0.0, 0.0),
            vec3(1.0, 0.0, 0.0),
            vec3(0.0, -1.0, -1.0),
        ]
        .map(map);
        let b = [vec3(-l, h, e), vec3(l, h, -e), vec3(0.0, h + 1.0, -1.0 / l)].map(map);
        check_case(&a, &b, h);
    }
}
