//! Unit tests of the bounding volumes: fits contain their points (checked in `f64` by code
//! independent of the fits), typed errors, the eigen-solver, and hand-built overlap cases
//! whose answer is known exactly. The randomized conservativeness properties against an
//! `f64` oracle are in `tests/tests/overlap_properties.rs`.

// Index loops mirror the matrix formulas.
#![allow(clippy::needless_range_loop)]

use super::eigen::symmetric_eigen;
use super::overlap::*;
use super::*;
use crate::aabb::Aabb;
use crate::mesh::TriangleMesh;
use crate::test_util::{lcg, unit_vec};
use glam::{DVec3, Mat3, Quat, Vec3};
use std::vec;
use std::vec::Vec;

/// Point clouds that stress the fits: random, clustered far from the origin, collinear,
/// coplanar, one point, duplicates, huge and tiny scales, mixed magnitudes.
fn clouds() -> Vec<Vec<Vec3>> {
    let mut s = 11u64;
    let mut out = Vec::new();
    for scale in [1e-30f32, 1e-3, 1.0, 1e4, 1e30] {
        let off = Vec3::new(3.0, -7.0, 5.0) * scale;
        let rand: Vec<Vec3> = (0..200)
            .map(|_| unit_vec(&mut s) * scale * lcg(&mut s))
            .collect();
        out.push(rand.clone());
        out.push(rand.iter().map(|&p| p * 1e-3 + off * 1e3).collect());
        let dir = unit_vec(&mut s);
        out.push(
            (0..50)
                .map(|i| off + dir * (i as f32 * 0.1 * scale))
                .collect(),
        );
        let (u, v) = (unit_vec(&mut s), unit_vec(&mut s));
        out.push(
            (0..80)
                .map(|_| off + (u * lcg(&mut s) + v * (lcg(&mut s) * 3.0)) * scale)
                .collect(),
        );
    }
    out.push(vec![Vec3::new(1.0, 2.0, 3.0)]);
    out.push(vec![Vec3::new(-4.0, 0.5, 1e20); 7]);
    out.push(vec![
        Vec3::new(1e-40, 0.0, 0.0),
        Vec3::new(0.0, -1e-42, 0.0),
    ]);
    out.push(vec![
        Vec3::new(3e38, -3e38, 1.0),
        Vec3::new(2.9e38, -3e38, 1.5),
        Vec3::new(3e38, -2.5e38, 0.0),
    ]);
    out.push(vec![Vec3::new(1e-20, 0.0, 0.0), Vec3::new(0.0, 1e20, 0.0)]);
    out
}

/// `|p − q|` for `f32` points, in `f64`.
fn dist(p: Vec3, q: DVec3) -> f64 {
    (p.as_dvec3() - q).length()
}

/// Independent `f64` containment checks (no padding beyond the fits' own).
fn in_sphere(s: &BoundingSphere, p: Vec3) -> bool {
    dist(p, s.center().as_dvec3()) <= f64::from(s.radius())
}

fn in_obb(b: &Obb, p: Vec3) -> bool {
    let d = p.as_dvec3() - b.center().as_dvec3();
    (0..3).all(|k| b.axes()[k].as_dvec3().dot(d).abs() <= f64::from(b.half_extents()[k]))
}

/// Distance to the segment by minimising over 2000 samples and refining by bisection on the
/// derivative's sign: a different method from the code under test.
fn in_capsule(c: &Capsule, p: Vec3) -> bool {
    let (a, b) = (c.a().as_dvec3(), c.b().as_dvec3());
    let f = |t: f64| dist(p, a + (b - a) * t);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..200 {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if f(m1) <= f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    let d = f(lo).min(f(hi)).min(f(0.0)).min(f(1.0));
    d <= f64::from(c.radius())
}

#[test]
fn fits_contain_every_point_in_f64() {
    for (n, pts) in clouds().iter().enumerate() {
        let s = BoundingSphere::fit(&pts[..]).unwrap();
        let o = Obb::fit(&pts[..]).unwrap();
        let c = Capsule::fit(&pts[..]).unwrap();
        for &p in pts {
            assert!(in_sphere(&s, p), "cloud {n}: {p} outside {s:?}");
            assert!(in_obb(&o, p), "cloud {n}: {p} outside {o:?}");
            assert!(in_capsule(&c, p), "cloud {n}: {p} outside {c:?}");
            assert!(s.contains_point(p) && o.contains_point(p) && c.contains_point(p));
        }
    }
}

#[test]
fn mesh_fits_contain_referenced_vertices_only() {
    let mut s = 5u64;
    let positions: Vec<Vec3> = (0..30).map(|_| unit_vec(&mut s) * 10.0).collect();
    // Only vertices 0..20 are referenced; 25 is far away and unreferenced.
    let mut positions = positions;
    positions[25] = Vec3::splat(1e6);
    let tris: Vec<[u32; 3]> = (0..18).map(|i| [i, i + 1, i + 2]).collect();
    let mesh = TriangleMesh::new(&positions, &tris);
    let sph = BoundingSphere::fit(&mesh).unwrap();
    let obb = Obb::fit(&mesh).unwrap();
    let cap = Capsule::fit(&mesh).unwrap();
    for &p in &positions[..20] {
        assert!(in_sphere(&sph, p) && in_obb(&obb, p) && in_capsule(&cap, p));
    }
    assert!(sph.radius() < 20.0 && !in_sphere(&sph, positions[25]));
}

#[test]
fn fit_errors_are_typed() {
    let none: [Vec3; 0] = [];
    assert_eq!(BoundingSphere::fit(&none[..]), Err(VolumeError::Empty));
    let bad = [Vec3::ZERO, Vec3::new(0.0, f32::NAN, 0.0)];
    assert_eq!(
        Obb::fit(&bad[..]),
        Err(VolumeError::NonFinite(crate::error::NonFiniteError::new(
            crate::error::InputElement::Point,
            1
        )))
    );
    let inf = [Vec3::new(f32::INFINITY, 0.0, 0.0)];
    assert_eq!(
        Capsule::fit(&inf[..]),
        Err(VolumeError::NonFinite(crate::error::NonFiniteError::new(
            crate::error::InputElement::Point,
            0
        )))
    );
    let pos = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let tris = [[0, 1, 2], [0, 1, 3]];
    let mesh = TriangleMesh::new(&pos, &tris);
    let e = Err(VolumeError::VertexIndexOutOfRange { triangle: 1 });
    assert_eq!(BoundingSphere::fit(&mesh), e);
    assert_eq!(
        Obb::fit(&mesh),
        e.map(|_: BoundingSphere| unreachable_obb())
    );
    let empty_mesh = TriangleMesh::new(&pos, &[]);
    assert_eq!(Capsule::fit(&empty_mesh), Err(VolumeError::Empty));
    let huge = [
        Vec3::new(-3.4e38, -3.4e38, 0.0),
        Vec3::new(3.4e38, 3.4e38, 0.0),
    ];
    assert_eq!(BoundingSphere::fit(&huge[..]), Err(VolumeError::TooLarge));
    // The capsule along the diagonal is thin and fits in f32; it contains both points.
    let cap = Capsule::fit(&huge[..]).unwrap();
    assert!(huge.iter().all(|&p| in_capsule(&cap, p)));
    // Every error has real Display text.
    for e in [
        VolumeError::Empty,
        VolumeError::NonFinite(crate::error::NonFiniteError::new(
            crate::error::InputElement::Point,
            3,
        )),
        VolumeError::VertexIndexOutOfRange { triangle: 2 },
        VolumeError::NonFiniteParameter,
        VolumeError::NegativeSize,
        VolumeError::NotOrthonormal,
        VolumeError::TooLarge,
    ] {
        assert!(std::format!("{e}").len() > 10);
    }
}

/// A placeholder value for the type-changing `map` above (never called: the result is `Err`).
fn unreachable_obb() -> Obb {
    Obb::from_aabb(&Aabb::new(Vec3::ZERO, Vec3::ONE)).unwrap()
}

#[test]
fn constructors_refuse_nonsense() {
    let ax = [Vec3::X, Vec3::Y, Vec3::Z];
    assert_eq!(
        BoundingSphere::new(Vec3::ZERO, f32::NAN),
        Err(VolumeError::NonFiniteParameter)
    );
    assert_eq!(
        BoundingSphere::new(Vec3::ZERO, -1.0),
        Err(VolumeError::NegativeSize)
    );
    assert!(BoundingSphere::new(Vec3::ZERO, -0.0).is_ok());
    assert_eq!(
        Obb::new(Vec3::ZERO, ax, Vec3::new(1.0, -1.0, 1.0)),
        Err(VolumeError::NegativeSize)
    );
    assert_eq!(
        Obb::new(Vec3::ZERO, [Vec3::X, Vec3::X, Vec3::Z], Vec3::ONE),
        Err(VolumeError::NotOrthonormal)
    );
    assert_eq!(
        Obb::new(Vec3::ZERO, [Vec3::X * 1.001, Vec3::Y, Vec3::Z], Vec3::ONE),
        Err(VolumeError::NotOrthonormal)
    );
    assert_eq!(
        Obb::new(Vec3::INFINITY, ax, Vec3::ONE),
        Err(VolumeError::NonFiniteParameter)
    );
    assert_eq!(
        Capsule::new(Vec3::ZERO, Vec3::NAN, 1.0),
        Err(VolumeError::NonFiniteParameter)
    );
    assert_eq!(
        Capsule::new(Vec3::ZERO, Vec3::X, -2.0),
        Err(VolumeError::NegativeSize)
    );
    // f32 rotation matrices from unit quaternions are corrected, keeping handedness and
    // directions; a frame that is not a rotation is refused.
    let mut s = 3u64;
    for _ in 0..1000 {
        let q = Quat::from_axis_angle(unit_vec(&mut s), lcg(&mut s) * 6.3);
        let m = Mat3::from_quat(q);
        let ax = [m.x_axis, m.y_axis, m.z_axis];
        let o = Obb::orthonormalized(Vec3::ZERO, ax, Vec3::ONE).unwrap();
        for k in 0..3 {
            assert!(o.axes()[k].distance(ax[k]) < 1e-5);
        }
    }
    let skew = [Vec3::X, Vec3::new(0.01, 1.0, 0.0), Vec3::Z];
    assert_eq!(
        Obb::orthonormalized(Vec3::ZERO, skew, Vec3::ONE),
        Err(VolumeError::NotOrthonormal)
    );
}

#[test]
fn jacobi_diagonalises_symmetric_matrices() {
    let mut s = 9u64;
    for case in 0..500 {
        let mut a = [[0.0f64; 3]; 3];
        for i in 0..3 {
            for j in i..3 {
                let x = f64::from(lcg(&mut s) * 2.0 - 1.0) * if case % 3 == 0 { 1e30 } else { 1.0 };
                a[i][j] = x;
                a[j][i] = x;
            }
        }
        if case % 5 == 0 {
            a[0][1] = 0.0;
            a[1][0] = 0.0;
            a[1][1] = a[0][0];
        }
        let (l, v) = symmetric_eigen(a);
        let norm = a.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max);
        for k in 0..3 {
            for i in 0..3 {
                // (A v_k)_i − λ_k v_ik
                let av: f64 = (0..3).map(|j| a[i][j] * v[j][k]).sum();
                assert!((av - l[k] * v[i][k]).abs() <= 1e-13 * norm, "case {case}");
            }
            for m in 0..3 {
                let d: f64 = (0..3).map(|i| v[i][k] * v[i][m]).sum();
                let want = if k == m { 1.0 } else { 0.0 };
                assert!((d - want).abs() <= 1e-14, "case {case}");
            }
        }
    }
    let (l, v) = symmetric_eigen([[f64::NAN; 3]; 3]);
    assert!(l[0].is_nan() && v == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
}

#[test]
fn pca_recovers_a_rotated_box() {
    let q = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let half = Vec3::new(4.0, 1.0, 0.25);
    let c = Vec3::new(10.0, -3.0, 2.0);
    let mut pts = Vec::new();
    for i in 0..=8 {
        for j in 0..=8 {
            for k in 0..=8 {
                let t = Vec3::new(i as f32, j as f32, k as f32) / 4.0 - Vec3::ONE;
                pts.push(c + q * (t * half));
            }
        }
    }
    let o = Obb::fit(&pts[..]).unwrap();
    let mut e = o.half_extents().to_array();
    e.sort_by(f32::total_cmp);
    assert!((e[0] - 0.25).abs() < 1e-4 && (e[1] - 1.0).abs() < 1e-4 && (e[2] - 4.0).abs() < 1e-4);
    assert!(o.center().distance(c) < 1e-4);
    // Sphere: Ritter's ball within 20 % of the minimal one (the half-diagonal).
    let r = BoundingSphere::fit(&pts[..]).unwrap().radius();
    assert!(r >= half.length() && r <= 1.2 * half.length());
    // Capsule along the long axis, radius about the cross-section's half-diagonal.
    let cap = Capsule::fit(&pts[..]).unwrap();
    let axis = (cap.b() - cap.a()).normalize();
    assert!(axis.dot(q * Vec3::X).abs() > 0.9999);
    assert!(cap.radius() <= 1.0001 * Vec3::new(0.0, 1.0, 0.25).length());
}

/// Ritter's growth step, worked by hand: points `(−1, 0, 2)`, `(1, 0, 2)`, `(0, 3, 2)`. The
/// extreme pairs along x, y, z have squared lengths 4, 10 and 0, so the initial ball is on
/// `(−1, 0, 2)`–`(0, 3, 2)`: centre `(−½, 3/2, 2)`, radius `√10/2`. `(1, 0, 2)` lies outside at
/// `d = 3/√2`: the ball grows to radius `(√10/2 + d)/2 = (√10 + 3√2)/4` and its centre moves
/// toward the point by `(grown − r)/d = ½ − √5/6` of `(3/2, −3/2, 0)`, to
/// `((1 − √5)/4, (3 + √5)/4, 2)`; `(0, 3, 2)` is then inside (distance² `(23 − 5√5)/4 ≈ 2.96`
/// against the radius² `(7 + 3√5)/4 ≈ 3.43`). The centre is stored rounded to `f32` (within
/// `10⁻⁷` here) and the radius measured again from it: the farthest point is `(1, 0, 2)`, at
/// the grown radius; both checked to `10⁻⁶`.
#[test]
fn sphere_fit_grows_ritters_ball_as_worked_by_hand() {
    let pts = [
        Vec3::new(-1.0, 0.0, 2.0),
        Vec3::new(1.0, 0.0, 2.0),
        Vec3::new(0.0, 3.0, 2.0),
    ];
    let s = BoundingSphere::fit(&pts[..]).unwrap();
    let r5 = 5f64.sqrt();
    let want_c = DVec3::new((1.0 - r5) / 4.0, (3.0 + r5) / 4.0, 2.0);
    let want_r = (10f64.sqrt() + 3.0 * 2f64.sqrt()) / 4.0;
    assert!((s.center().as_dvec3() - want_c).length() < 1e-6, "{s:?}");
    assert!(
        (f64::from(s.radius()) - want_r).abs() < 1e-6,
        "{s:?} against {want_r}"
    );
}

fn sph(c: Vec3, r: f32) -> BoundingSphere {
    BoundingSphere::new(c, r).unwrap()
}

fn obb(c: Vec3, q: Quat, e: Vec3) -> Obb {
    let m = Mat3::from_quat(q);
    Obb::orthonormalized(c, [m.x_axis, m.y_axis, m.z_axis], e).unwrap()
}

#[test]
fn touching_volumes_overlap_at_every_scale() {
    // Powers of two, so the scaled configurations stay exact (subnormal ones included).
    for scale in [-140, -100, -17, 0, 15, 66, 120].map(|k| 2f32.powi(k)) {
        let s = |x: f32| x * scale;
        // Spheres touching exactly (3-4-5 distance).
        let a = sph(Vec3::ZERO, s(2.0));
        let b = sph(Vec3::new(s(3.0), s(4.0), 0.0), s(3.0));
        assert!(
            sphere_sphere(&a, &b) && sphere_sphere(&b, &a),
            "scale {scale}"
        );
        // Sphere touching a box face and a box corner.
        let bx = Aabb::new(Vec3::splat(s(1.0)), Vec3::splat(s(2.0)));
        assert!(sphere_aabb(
            &sph(Vec3::new(s(3.0), s(1.5), s(1.5)), s(1.0)),
            &bx
        ));
        let corner = sph(Vec3::new(s(4.0), s(4.0), s(3.0)), s(3.0));
        assert!(sphere_aabb(&corner, &bx), "scale {scale}");
        // Boxes sharing a face, as OBBs.
        let o1 = Obb::from_aabb(&bx).unwrap();
        let o2 = Obb::from_aabb(&Aabb::new(
            Vec3::new(s(2.0), s(1.0), s(1.0)),
            Vec3::new(s(5.0), s(2.0), s(2.0)),
        ))
        .unwrap();
        assert!(obb_obb(&o1, &o2) && obb_obb(&o2, &o1), "scale {scale}");
        assert!(sphere_obb(&corner, &o1), "scale {scale}");
        // Capsules: crossing segments, parallel touching ones.
        let c1 = Capsule::new(Vec3::ZERO, Vec3::new(s(4.0), 0.0, 0.0), s(1.0)).unwrap();
        let c2 = Capsule::new(
            Vec3::new(s(2.0), s(-3.0), s(2.0)),
            Vec3::new(s(2.0), s(3.0), s(2.0)),
            s(1.0),
        )
        .unwrap();
        assert!(capsule_capsule(&c1, &c2), "scale {scale}");
        let c3 = Capsule::new(
            Vec3::new(s(1.0), s(2.0), 0.0),
            Vec3::new(s(9.0), s(2.0), 0.0),
            s(1.0),
        )
        .unwrap();
        assert!(
            capsule_capsule(&c1, &c3) && capsule_capsule(&c3, &c1),
            "scale {scale}"
        );
        let touching = sph(Vec3::new(s(6.0), 0.0, 0.0), s(1.0));
        assert!(capsule_sphere(&c1, &touching), "scale {scale}");
    }
}

#[test]
fn clearly_apart_volumes_are_apart_at_every_scale() {
    for scale in [-100, -17, 0, 15, 66, 120].map(|k| 2f32.powi(k)) {
        let s = |x: f32| x * scale;
        let a = sph(Vec3::ZERO, s(2.0));
        let b = sph(Vec3::new(s(3.0), s(4.0), 0.0), s(2.999));
        assert!(!sphere_sphere(&a, &b), "scale {scale}");
        let bx = Aabb::new(Vec3::splat(s(1.0)), Vec3::splat(s(2.0)));
        assert!(!sphere_aabb(
            &sph(Vec3::new(s(4.0), s(4.0), s(3.0)), s(2.99)),
            &bx
        ));
        let o1 = Obb::from_aabb(&bx).unwrap();
        assert!(!sphere_obb(
            &sph(Vec3::new(s(4.0), s(4.0), s(3.0)), s(2.99)),
            &o1
        ));
        let c1 = Capsule::new(Vec3::ZERO, Vec3::new(s(4.0), 0.0, 0.0), s(1.0)).unwrap();
        let c3 = Capsule::new(
            Vec3::new(s(1.0), s(2.0), 0.0),
            Vec3::new(s(9.0), s(2.0), 0.0),
            s(0.999),
        )
        .unwrap();
        assert!(!capsule_capsule(&c1, &c3), "scale {scale}");
        assert!(!capsule_sphere(
            &c1,
            &sph(Vec3::new(s(6.0), 0.0, 0.0), s(0.999))
        ));
    }
}

/// Two unit cubes whose closest features are two edges: no face normal separates them,
/// only an edge–edge cross product does (the case the 9 cross axes exist for).
#[test]
fn obb_edge_edge_separation() {
    let qa = Quat::from_rotation_z(core::f32::consts::FRAC_PI_4);
    let h = Vec3::ONE;
    let r2 = core::f32::consts::SQRT_2;
    // Face separation first: A's vertical edge (x = √2) against B's face x = √2 + gap.
    for (gap, want) in [(0.01f32, false), (-0.01, true), (0.0, true)] {
        let a = obb(Vec3::ZERO, qa, h);
        let b = obb(Vec3::new(r2 + 1.0 + gap, 0.0, 0.0), Quat::IDENTITY, h);
        assert_eq!(obb_obb(&a, &b), want, "gap {gap}");
    }
    // Genuine edge–edge: A rotated 45° about z (edge along z at x = √2), B rotated 45°
    // about y (edge along y at x = −√2 from its centre).
    let qb = Quat::from_rotation_y(core::f32::consts::FRAC_PI_4);
    for (gap, want) in [(0.01f32, false), (-0.01, true)] {
        let a = obb(Vec3::ZERO, qa, h);
        let b = obb(Vec3::new(2.0 * r2 + gap, 0.0, 0.0), qb, h);
        assert_eq!(obb_obb(&a, &b), want, "edge–edge gap {gap}");
        // The face axes alone do not separate (so the cross axis did).
        let face_sep = a.axes().iter().chain(b.axes().iter()).any(|&l| {
            let (pa, pb) = (proj(&a, l), proj(&b, l));
            pa.1 < pb.0 || pb.1 < pa.0
        });
        assert!(!face_sep);
    }
}

/// The projection interval of a box onto `l`, in `f64`, from its 8 corners.
fn proj(b: &Obb, l: Vec3) -> (f64, f64) {
    let l = l.as_dvec3();
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for i in 0..8 {
        let mut p = b.center().as_dvec3();
        for k in 0..3 {
            let sgn = if i >> k & 1 == 0 { -1.0 } else { 1.0 };
            p += b.axes()[k].as_dvec3() * (sgn * f64::from(b.half_extents()[k]));
        }
        lo = lo.min(p.dot(l));
        hi = hi.max(p.dot(l));
    }
    (lo, hi)
}

/// Parallel and anti-parallel edges (exact zero and ±1 entries of `R`): the degenerate
/// cross axes must not invent a separation.
#[test]
fn obb_parallel_edges_are_not_separated_by_degenerate_axes() {
    let mut s = 21u64;
    for _ in 0..2000 {
        let q = Quat::from_axis_angle(unit_vec(&mut s), lcg(&mut s) * 6.3);
        let e1 = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) + 0.01;
        let e2 = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) + 0.01;
        let a = obb(Vec3::ZERO, q, e1);
        // Same orientation (R = I up to rounding), centre inside A: must overlap.
        let m = Mat3::from_quat(q);
        let off = m * ((Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 2.0 - 1.0) * e1);
        let b = obb(off, q, e2);
        assert!(obb_obb(&a, &b) && obb_obb(&b, &a));
        assert!(aabb_obb(&Aabb::new(off - e2 * 0.5, off + e2 * 0.5), &a));
    }
}

#[test]
fn aabb_wrappers() {
    let a = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let b = Aabb::new(Vec3::ONE, Vec3::splat(2.0));
    assert!(aabb_aabb(&a, &b));
    assert!(!aabb_aabb(&a, &Aabb::EMPTY));
    assert!(!sphere_aabb(&sph(Vec3::ZERO, 5.0), &Aabb::EMPTY));
    let o = Obb::from_aabb(&b).unwrap();
    assert!(aabb_obb(&a, &o));
    assert!(!aabb_obb(&Aabb::EMPTY, &o));
    assert!(!aabb_obb(
        &Aabb::new(Vec3::splat(-3.0), Vec3::splat(-2.0)),
        &o
    ));
    // from_aabb contains the box exactly, even at f32's limits.
    let big = Aabb::new(Vec3::splat(-3.4e38), Vec3::new(3.4e38, 1.0, 1e-45));
    let ob = Obb::from_aabb(&big).unwrap();
    for p in [big.min, big.max] {
        assert!(in_obb(&ob, p));
    }
    assert_eq!(
        Obb::from_aabb(&Aabb::EMPTY),
        Err(VolumeError::NonFiniteParameter)
    );
}

/// How far a face of [`Obb::from_aabb`]'s box may lie outside the box's face, relative to
/// `M = max(|min|, |max|)` on that axis, unitless: `2⁻²¹` (8 units of roundoff `u = 2⁻²⁴`).
///
/// Derivation: the centre is `fl(min/2 + max/2)`, within `u·M` of the exact midpoint (plus
/// the absolute term below); the half-extent is the larger distance from it to a face, at
/// most the exact half-size plus that `u·M`, padded by `FIT_PAD_REL` (`~2⁻⁵⁰`) and rounded
/// up to `f32` (at most one ulp, `≤ 2u·M`). A face of the converted box thus lies at most
/// `2u·M + 2u·M` (plus the padding) outside the box's: 4u, doubled for margin.
const FROM_AABB_SLACK_REL: f64 = 1.0 / 2_097_152.0;

/// Absolute part of that slack, world units: `2⁻¹⁴⁵` (16 of the smallest subnormal, with
/// margin), for the halvings and the sum of the centre when they are subnormal (`≤ 2⁻¹⁵⁰`
/// each) and the half-extent's rounding up (one subnormal step, `2⁻¹⁴⁹`).
const FROM_AABB_SLACK_ABS: f64 = 16.0 * f32::from_bits(1) as f64;

/// [`Obb::from_aabb`] is tight: each face of the converted box lies outside the box's face
/// by at most [`FROM_AABB_SLACK_REL`]`·M +` [`FROM_AABB_SLACK_ABS`], never inside it (checked
/// in `f64` on the stored centre and half-extents), and the axes are the world axes exactly.
#[test]
fn from_aabb_is_tight() {
    let mut s = 0x0b0c_u64;
    let mut boxes = vec![
        Aabb::new(Vec3::ZERO, Vec3::ONE),
        Aabb::new(Vec3::splat(-1.0), Vec3::ONE),
        Aabb::new(Vec3::new(1e6, 0.0, 0.0), Vec3::new(1e6 + 0.0625, 1.0, 1.0)),
        Aabb::new(Vec3::splat(-3.4e38), Vec3::new(3.4e38, 1.0, 1e-45)),
        Aabb::new(Vec3::new(1e-45, -1e-40, 2.0), Vec3::new(3e-45, 1e-40, 2.0)),
        Aabb::new(Vec3::splat(5.0), Vec3::splat(5.0)),
    ];
    for scale in [1e-38f32, 1e-3, 1.0, 1e5, 1e30] {
        for _ in 0..200 {
            let a = unit_vec(&mut s) * scale * (1.0 + 10.0 * lcg(&mut s));
            let b = a + unit_vec(&mut s) * scale * lcg(&mut s);
            boxes.push(Aabb::new(a.min(b), a.max(b)));
        }
    }
    for bx in boxes {
        let o = Obb::from_aabb(&bx).unwrap();
        assert_eq!(o.axes(), [Vec3::X, Vec3::Y, Vec3::Z], "{bx:?}");
        for k in 0..3 {
            let (lo, hi) = (f64::from(bx.min[k]), f64::from(bx.max[k]));
            let (c, e) = (f64::from(o.center()[k]), f64::from(o.half_extents()[k]));
            let slack = FROM_AABB_SLACK_REL * lo.abs().max(hi.abs()) + FROM_AABB_SLACK_ABS;
            let (below, above) = (lo - (c - e), (c + e) - hi);
            assert!(
                (0.0..=slack).contains(&below) && (0.0..=slack).contains(&above),
                "axis {k}: faces {below:e} below and {above:e} above the box's (slack {slack:e})\n{bx:?}\n{o:?}"
            );
        }
    }
}

#[test]
fn rescale_factor_is_a_power_of_two_bringing_m_near_one() {
    assert_eq!(rescale_factor(0.0), 1.0);
    assert_eq!(rescale_factor(f32::NAN), 1.0);
    assert_eq!(rescale_factor(1.0), 1.0);
    assert_eq!(rescale_factor(RESCALE_ABOVE), 1.0);
    assert_eq!(rescale_factor(RESCALE_BELOW), 1.0);
    let mut m = f32::MAX;
    while m > 0.0 {
        let k = rescale_factor(m);
        let b = k.to_bits();
        assert!(
            b & 0x007F_FFFF == 0 || (b >> 23 == 0 && b.count_ones() == 1),
            "{k:e}"
        );
        assert!(k > 0.0 && k.is_finite(), "{m:e}");
        if !(RESCALE_BELOW..=RESCALE_ABOVE).contains(&m) {
            let s = f64::from(m) * f64::from(k);
            assert_eq!(f64::from(m * k), s, "{m:e}: not exact");
            assert!(s < 1.0 && (s >= 0.5 || m < 1e-38), "{m:e} → {s:e}");
        }
        m *= 0.37;
    }
    assert_eq!(UNDERFLOW_PAD_ABS, 2f32.powi(-140));
}

/// The bands' domain boundary (`overlap` module docs, `m ∈ [2⁻⁹⁰, 2⁹⁰]`): at both ends,
/// unit spheres and boxes scaled by `m` that are apart by 1 % of their size (far beyond
/// every band) are "apart", and touching ones "overlap".
#[test]
fn bands_hold_at_both_ends_of_their_domain() {
    for m in [
        2f32.powi(-90),
        2f32.powi(-60),
        1.0,
        2f32.powi(60),
        2f32.powi(89),
    ] {
        let s = |x: f32| BoundingSphere::new(Vec3::new(x * m, 0.5 * m, -m), m).unwrap();
        assert!(sphere_sphere(&s(0.0), &s(2.0)), "touching at {m:e}");
        assert!(!sphere_sphere(&s(0.0), &s(2.02)), "apart at {m:e}");
        let b = |x: f32| {
            Obb::new(
                Vec3::new(x * m, 0.0, m),
                [Vec3::X, Vec3::Y, Vec3::Z],
                Vec3::splat(m),
            )
            .unwrap()
        };
        assert!(obb_obb(&b(0.0), &b(2.0)), "boxes touching at {m:e}");
        assert!(!obb_obb(&b(0.0), &b(2.02)), "boxes apart at {m:e}");
        let a = Aabb::new(Vec3::new(-m, -m, 0.0), Vec3::new(m, m, 2.0 * m));
        assert!(aabb_obb(&a, &b(2.0)));
        assert!(!aabb_obb(&a, &b(2.02)), "box–OBB apart at {m:e}");
    }
}

/// The absolute part of the bands, [`BAND_ABS_PER_MAGNITUDE`]: a point (a ball of radius 0,
/// so the relative part is 0) just beyond it from a box or another point is "apart" at
/// every scale, with and without rescaling. The fuzzed case that fixed the constant
/// (`fuzz/regressions/overlap/crash-5cee…`): at `m = 2⁶⁸` a point `0.5000076` from the box
/// rounds `fl(d²)` to exactly the `2⁻¹⁴⁰` padding and is reported overlapping, so the
/// band cannot be `2⁻⁶⁹·m`; it is inside `2⁻⁶⁸·m`.
#[test]
fn absolute_band_holds_at_every_scale() {
    assert_eq!(BAND_ABS_PER_MAGNITUDE, 2f32.powi(-68));
    for e in [-90, -61, -60, -1, 0, 1, 59, 60, 61, 68, 89] {
        let m = 2f32.powi(e);
        let gap = BAND_ABS_PER_MAGNITUDE * m.max(1.0) * (1.0 + 1.0 / 64.0);
        let b = Aabb::new(Vec3::new(-m, -gap, 0.0), Vec3::new(0.0, 0.0, 0.0));
        let p = |y: f32| BoundingSphere::new(Vec3::new(0.0, y, 0.0), 0.0).unwrap();
        assert!(sphere_aabb(&p(0.0), &b), "point on the box at 2^{e}");
        assert!(!sphere_aabb(&p(gap), &b), "point beyond the band at 2^{e}");
        let far = BoundingSphere::new(Vec3::new(-m, -gap, 0.0), 0.0).unwrap();
        assert!(!sphere_sphere(&p(gap), &far), "points apart at 2^{e}");
    }
    let b = Aabb::new(Vec3::new(-2f32.powi(68), 0.0, 0.0), Vec3::ZERO);
    let p = BoundingSphere::new(Vec3::new(0.0, 0.500_007_6, 0.0), 0.0).unwrap();
    assert!(
        sphere_aabb(&p, &b),
        "the fuzzed false positive, within the band"
    );
}

/// `contains_point`'s padding is `CONTAIN_PAD_REL` (about `10⁻¹⁵`) of the compared
/// magnitudes, nothing more: at scales `10⁻³`, 1 and `10³`, a point on the boundary of a ball
/// (radius 1 about the origin), a capsule (radius ½ about `[0, 2]` on `x`) and a box
/// (half-extents 1, 2, 3) is contained, and the same point moved outward by `10⁻⁵` of the
/// size (far beyond the padding) is not. Boundaries by hand: `(1, 0, 0)`, `(1, ½, 0)`,
/// `(1, 2, 3)` (a corner).
#[test]
fn contains_point_pads_by_rounding_only() {
    let out = 1.0 + 1e-5;
    for s in [1e-3f32, 1.0, 1e3] {
        let ball = BoundingSphere::new(Vec3::ZERO, s).unwrap();
        assert!(ball.contains_point(Vec3::new(s, 0.0, 0.0)), "{s}");
        assert!(!ball.contains_point(Vec3::new(s * out, 0.0, 0.0)), "{s}");
        let cap = Capsule::new(Vec3::ZERO, Vec3::new(2.0 * s, 0.0, 0.0), 0.5 * s).unwrap();
        assert!(cap.contains_point(Vec3::new(s, 0.5 * s, 0.0)), "{s}");
        assert!(!cap.contains_point(Vec3::new(s, 0.5 * s * out, 0.0)), "{s}");
        assert!(
            !cap.contains_point(Vec3::new(-0.5 * s * out, 0.0, 0.0)),
            "{s}"
        );
        let obb = Obb::new(
            Vec3::ZERO,
            [Vec3::X, Vec3::Y, Vec3::Z],
            Vec3::new(1.0, 2.0, 3.0) * s,
        )
        .unwrap();
        let corner = Vec3::new(1.0, 2.0, 3.0) * s;
        assert!(obb.contains_point(corner), "{s}");
        for k in 0..3 {
            let mut p = corner;
            p[k] *= out;
            assert!(!obb.contains_point(p), "{s} axis {k}");
        }
    }
}

#[test]
fn eigen_solves_matrices_whose_diagonal_difference_overflows() {
    // [[a, b], [b, −a]] ⊕ [r] has the eigenvalues ±√(a² + b²) and r (closed form); for the
    // huge ones a − (−a) overflows f64, so an unscaled Jacobi rotation is skipped.
    for (a, b) in [
        (1e308_f64, 1e307_f64),
        (1.5e308, 1e300),
        (-1e308, 1e308),
        (1e-300, 3e-301),
    ] {
        let r = a.abs().max(b.abs());
        let m = [[a, b, 0.0], [b, -a, 0.0], [0.0, 0.0, r]];
        let (l, v) = symmetric_eigen(m);
        let want = r * ((a / r) * (a / r) + (b / r) * (b / r)).sqrt();
        let mut got = l;
        got.sort_by(f64::total_cmp);
        assert!((got[0] + want).abs() <= 1e-15 * want, "{a} {b}: {l:?}");
        assert!((got[2] - want).abs() <= 1e-15 * want, "{a} {b}: {l:?}");
        assert!(l.contains(&r), "{a} {b}: {l:?}");
        for k in 0..3 {
            for i in 0..3 {
                let av: f64 = (0..3).map(|j| m[i][j] / r * v[j][k]).sum();
                assert!(
                    (av - l[k] / r * v[i][k]).abs() <= 1e-14,
                    "{a} {b} column {k}"
                );
            }
        }
    }
}
