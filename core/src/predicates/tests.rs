//! Unit tests of the exact predicates: expansions, `orient3d` and `orient_direction` against
//! integer determinants and hand-derived cases whose `f64` evaluation cancels.

use super::*;
use crate::test_util::{grid_point, lcg};
use glam::vec3;

/// The exact determinant `det[a − c, b − c, x − c]` of integer points (the oracle).
fn det3_i64(a: [i64; 3], b: [i64; 3], c: [i64; 3], x: [i64; 3]) -> i64 {
    let u = [a[0] - c[0], a[1] - c[1], a[2] - c[2]];
    let v = [b[0] - c[0], b[1] - c[1], b[2] - c[2]];
    let w = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
    u[0] * (v[1] * w[2] - v[2] * w[1])
        + u[1] * (v[2] * w[0] - v[0] * w[2])
        + u[2] * (v[0] * w[1] - v[1] * w[0])
}

#[test]
fn expansion_products_are_exact() {
    // (1 + 2⁻³⁰)² = 1 + 2⁻²⁹ + 2⁻⁶⁰: the last term is lost in one f64 product.
    let x = 1.0 + 2f64.powi(-30);
    let (hi, lo) = two_product(x, x);
    assert_eq!(hi, 1.0 + 2f64.powi(-29));
    assert_eq!(lo, 2f64.powi(-60));
    let mut e = Expansion::<8>::ZERO;
    e.add_product(&[x], &[x], 1.0);
    e.grow(-1.0);
    e.grow(-2f64.powi(-29));
    assert_eq!(e.components(), &[2f64.powi(-60)]);
    e.grow(-2f64.powi(-60));
    assert_eq!(e.sign(), 0);
    assert!(!e.overflowed());
}

/// `orient3d` equals the integer determinant on small grids (many exact zeros, which the
/// filter cannot decide), and its filtered and exact paths agree on random points.
#[test]
fn orient3d_matches_integer_determinant() {
    let mut s = 5u64;
    let mut zeros = 0;
    for _ in 0..20_000 {
        let p = [(); 4].map(|_| grid_point(&mut s, 3.0));
        let i = p.map(|v| [v.x as i64, v.y as i64, v.z as i64]);
        let want = det3_i64(i[0], i[1], i[2], i[3]).signum() as i32;
        zeros += usize::from(want == 0);
        assert_eq!(orient3d(p[0], p[1], p[2], p[3]), want, "{p:?}");
        assert_eq!(orient3d_exact(p[0], p[1], p[2], p[3]), want, "{p:?}");
    }
    assert!(zeros > 1000, "{zeros}");
    for _ in 0..20_000 {
        let p =
            [(); 4].map(|_| vec3(lcg(&mut s) - 0.5, lcg(&mut s) - 0.5, lcg(&mut s) - 0.5) * 1.0e3);
        assert_eq!(
            orient3d(p[0], p[1], p[2], p[3]),
            orient3d_exact(p[0], p[1], p[2], p[3])
        );
    }
}

/// Points on the plane `z = 0` with coordinates spanning 60 orders of magnitude, and a
/// fourth point `z = ±1e-38` off it: the `f64` evaluation cannot see it (the differences are
/// not even exact), the exact path must.
#[test]
fn orient3d_is_exact_across_magnitudes() {
    let a = vec3(1.0e20, 3.0e-7, 0.0);
    let b = vec3(-2.0e5, 1.0e20, 0.0);
    let c = vec3(1.0e-30, 1.0e-25, 0.0);
    // (a − c) × (b − c) has z ≈ 1e40 > 0: the normal points to +z.
    for (z, want) in [(1.0e-38f32, 1), (-1.0e-38, -1), (0.0, 0), (-0.0, 0)] {
        let x = vec3(7.0e10, -3.0e-3, z);
        assert_eq!(orient3d(a, b, c, x), want, "z = {z:e}");
    }
}

/// `orient_direction` equals the integer determinant `det[a − c, b − c, dir]` on small grids
/// (many exact zeros: collinear points, directions in the plane).
#[test]
fn orient_direction_matches_integer_determinant() {
    let mut s = 11u64;
    let mut zeros = 0;
    for _ in 0..20_000 {
        let [a, b, c, dir] = [(); 4].map(|_| grid_point(&mut s, 2.0));
        let i = [a, b, c, c + dir].map(|v| [v.x as i64, v.y as i64, v.z as i64]);
        let want = det3_i64(i[0], i[1], i[2], i[3]).signum() as i32;
        zeros += usize::from(want == 0);
        assert_eq!(orient_direction(a, b, c, dir), want, "{a} {b} {c} {dir}");
    }
    assert!(zeros > 1000, "{zeros}");
}

/// A triangle whose `f64` normal cancels: `v0 = (1, 1, 0)`, `v1 = 0`, `v2 = (−2⁻⁶⁰, 0, 1)`.
/// By hand, `(v1 − v0) × (v2 − v0) = (−1, −1, 0) × (−1 − 2⁻⁶⁰, −1, 1)` has
/// `z = (−1)(−1) − (−1)(−1 − 2⁻⁶⁰) = −2⁻⁶⁰`, while in `f64` `−1 − 2⁻⁶⁰` rounds to `−1` and the
/// component is `0`. So the exact sign of `(0, 0, ±1)·n` is `∓1`; `(1, −1, 0)` lies in the
/// plane's direction set only if `n·(1, −1, 0) = n_x − n_y = 0`: `n_x = (−1)(1) − 0 = −1`,
/// `n_y = 0·(−1 − 2⁻⁶⁰) − (−1)(1) = 1`, so its sign is that of `−2`.
#[test]
fn orient_direction_is_exact_where_f64_cancels() {
    let tiny = f32::from_bits(0x2180_0000); // 2⁻⁶⁰: exponent 127 − 60 = 0x43
    assert_eq!(f64::from(tiny), 2f64.powi(-60));
    let (v0, v1, v2) = (vec3(1.0, 1.0, 0.0), Vec3::ZERO, vec3(-tiny, 0.0, 1.0));
    let n64 = (v1 - v0).as_dvec3().cross((v2 - v0).as_dvec3());
    assert_eq!(
        n64.z, 0.0,
        "the f64 normal must cancel for this case to mean anything"
    );
    assert_eq!(orient_direction(v1, v2, v0, vec3(0.0, 0.0, 1.0)), -1);
    assert_eq!(orient_direction(v1, v2, v0, vec3(0.0, 0.0, -1.0)), 1);
    assert_eq!(orient_direction(v1, v2, v0, vec3(1.0, -1.0, 0.0)), -1);
    // A direction along an edge is in the plane; a collinear triangle has no normal.
    assert_eq!(orient_direction(v1, v2, v0, v2 - v1), 0);
    let line = [
        Vec3::ZERO,
        vec3(1.0e20, 3.0, -7.0),
        vec3(2.0e20, 6.0, -14.0),
    ];
    assert_eq!(
        orient_direction(line[1], line[2], line[0], vec3(0.3, -1.0, 5.0)),
        0
    );
}
