//! Unit tests of `watertight`.

use super::*;
use crate::triangle::{F64Reference, TriangleVariant};

#[test]
fn shared_edge_of_two_triangles_is_closed() {
    // Quad split on its diagonal; rays through exact points of the diagonal.
    let a = Vec3::new(0.0, 0.0, 0.0);
    let b = Vec3::new(1.0, 0.0, 0.0);
    let c = Vec3::new(1.0, 1.0, 0.0);
    let d = Vec3::new(0.0, 1.0, 0.0);
    let t1 = [a, b, c];
    let t2 = [a, c, d];
    for i in 1..64 {
        let s = i as f32 / 64.0;
        let target = Vec3::new(s, s, 0.0);
        let origin = Vec3::new(0.1 * s - 3.3, 7.77 - s, 9.1);
        let ray = Ray::new(origin, target - origin);
        let n = [&t1, &t2]
            .iter()
            .filter(|t| Watertight.intersect(&ray, t).is_some())
            .count();
        assert!(n >= 1, "leak at s = {s}");
    }
}

#[test]
fn extreme_scales_give_correct_t() {
    for s in [1.0e-20f32, 1.0e-10, 1.0, 1.0e18, 1.0e20] {
        let tri = [Vec3::ZERO, Vec3::new(s, 0.0, 0.0), Vec3::new(0.0, s, 0.0)];
        let o = Vec3::new(s / 3.0, s / 3.0, s);
        let ray = Ray::new(o, Vec3::new(0.0, 0.0, -1.0));
        let h = Watertight
            .intersect(&ray, &tri)
            .unwrap_or_else(|| panic!("miss at {s}"));
        assert!(((h.t - s) / s).abs() < 1e-6, "s = {s}: t = {}", h.t);
        assert!(h.t.is_finite());
    }
}

/// Found by the `bvh` fuzz target: the origin is 4e-34 above the plane `z = 0` and the ray
/// leaves it (`d_z > 0`), but the dominant axis is `y`, so the sheared depths are ~1e36 and
/// `Σ eᵢzᵢ / det` rounds to ~6e27 instead of the true −3548. The plane-equation `t` in `f64`
/// gets it right: behind the origin, no hit.
#[test]
fn origin_near_plane_with_other_dominant_axis_is_not_hit_from_behind() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let o = Vec3::new(
        f32::from_bits(0x3e80_0021),
        0.25,
        f32::from_bits(0x0808_0000),
    );
    let d = Vec3::new(
        f32::from_bits(0x0201_000c),
        f32::from_bits(0x0303_0200),
        f32::from_bits(0x021c_f605),
    );
    assert_eq!(Watertight.intersect(&Ray::new(o, d), &tri), None);
    // Reversed, it hits at t = 4.092601e-34 / 1.1531674e-37 ≈ 3548.99 (f64 of the inputs).
    let h = Watertight.intersect(&Ray::new(o, -d), &tri).expect("hit");
    let t_ref = f64::from(o.z) / f64::from(d.z);
    assert!(
        (f64::from(h.t) - t_ref).abs() <= 1e-6 * t_ref,
        "t = {}",
        h.t
    );
}

#[test]
fn in_plane_and_degenerate_give_no_hit() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let in_plane = Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X);
    let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
    let point = [Vec3::ONE; 3];
    let through = Ray::new(Vec3::new(0.5, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
    for v in TriangleVariant::ALL {
        assert!(v.intersect(&in_plane, &tri).is_none(), "{}", v.name());
        assert!(v.intersect(&through, &line).is_none(), "{}", v.name());
        assert!(v.intersect(&through, &point).is_none(), "{}", v.name());
    }
}

/// `(Σ crossing_sign, number of non-zero signs, number of closed-test hits)` of `line`
/// over `tris` (the whole line: the interval is unbounded).
fn crossings(tris: &[[Vec3; 3]], origin: Vec3, dir: Vec3) -> (i32, usize, usize) {
    let line = Ray::with_interval(origin, dir, f32::NEG_INFINITY, f32::INFINITY);
    let pre = WatertightRay::new(&line).unwrap();
    let mut sum = 0;
    let mut counted = 0;
    let mut closed = 0;
    for t in tris {
        let s = pre.crossing_sign(origin, t);
        sum += i32::from(s);
        counted += usize::from(s != 0);
        let hit = Watertight.intersect(&line, t);
        closed += usize::from(hit.is_some());
        if s != 0 {
            // A counted crossing is one the closed test reports, with the same facing.
            assert_eq!(
                hit.map(|h| h.front_face),
                Some(s > 0),
                "{t:?} {origin} {dir}"
            );
        }
    }
    (sum, counted, closed)
}

#[test]
fn crossing_sign_counts_a_shared_edge_or_vertex_once() {
    // The unit square split on its diagonal, seen from above (both triangles face the ray).
    let [a, b, c, d] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let square = [[a, b, c], [a, c, d]];
    let down = Vec3::new(0.0, 0.0, -1.0);
    let mut on_diagonal_closed = 0;
    for i in 1..64 {
        let s = i as f32 / 64.0;
        // On the shared diagonal: the closed test reports both, the rule one.
        let (sum, counted, closed) = crossings(&square, Vec3::new(s, s, 1.0), down);
        assert_eq!((sum, counted), (1, 1), "diagonal at {s}");
        on_diagonal_closed += closed;
        // Inside one triangle only.
        let (sum, counted, _) = crossings(&square, Vec3::new(s, s * 0.5, 1.0), down);
        assert_eq!((sum, counted), (1, 1), "inside at {s}");
    }
    assert_eq!(
        on_diagonal_closed,
        2 * 63,
        "the closed test reports both triangles"
    );
    // From below, both face away: −1, once.
    let (sum, counted, _) = crossings(&square, Vec3::new(0.5, 0.5, -1.0), -down);
    assert_eq!((sum, counted), (-1, 1));

    // A fan of eight triangles around the origin (rim on the square of side 2): a ray
    // through the centre vertex, and through every spoke, is counted once.
    let rim = [
        (1.0, 0.0),
        (1.0, 1.0),
        (0.0, 1.0),
        (-1.0, 1.0),
        (-1.0, 0.0),
        (-1.0, -1.0),
        (0.0, -1.0),
        (1.0, -1.0),
    ]
    .map(|(x, y)| Vec3::new(x, y, 0.0));
    let fan: std::vec::Vec<[Vec3; 3]> = (0..8)
        .map(|k| [Vec3::ZERO, rim[k], rim[(k + 1) % 8]])
        .collect();
    let (sum, counted, closed) = crossings(&fan, Vec3::new(0.0, 0.0, 1.0), down);
    assert_eq!((sum, counted, closed), (1, 1, 8), "centre vertex");
    for (k, &r) in rim.iter().enumerate() {
        let mid = r * 0.5 + Vec3::Z;
        let (sum, counted, closed) = crossings(&fan, mid, down);
        assert_eq!((sum, counted, closed), (1, 1, 2), "spoke {k}");
        // Oblique rays through the centre, from every side.
        let oblique = -(r * 0.25 + Vec3::Z);
        let (sum, counted, _) = crossings(&fan, r * 0.25 + Vec3::Z, oblique);
        assert_eq!((sum, counted), (1, 1), "oblique {k}");
    }
}

/// Which triangle [`WatertightRay::crossing_sign`] counts is the one its documented rule
/// names: the one containing the ray's point moved by `(ε, ε²)` in the sheared plane. On a
/// 4 × 4 grid of unit quads in `z = 0` (vertical, horizontal and diagonal shared edges),
/// rays along `+z` (sheared axes x, y) and `−z` (y, x: [`super::super::projection_axes`])
/// through every interior vertex, every interior edge midpoint and a point inside each quad;
/// the oracle moves the point by `ε = 2⁻¹⁰` and finds the triangle holding it with exact
/// orientation signs (dyadic coordinates: every product and sum exact in `f64`).
#[test]
fn crossing_sign_counts_the_triangle_the_perturbation_names() {
    let n = 4u32;
    let pos = |v: u32| Vec3::new((v % (n + 1)) as f32, (v / (n + 1)) as f32, 0.0);
    let tris: std::vec::Vec<[Vec3; 3]> = crate::solids::grid_triangles(n, n)
        .map(|t| t.map(pos))
        .collect();
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let holds = |t: &[Vec3; 3], q: [f64; 2]| {
        let [a, b, c] = t.map(|v| [f64::from(v.x), f64::from(v.y)]);
        orient(a, b, q) > 0.0 && orient(b, c, q) > 0.0 && orient(c, a, q) > 0.0
    };
    let eps = 1.0 / 1024.0;
    let mut points = std::vec::Vec::new();
    for j in 0..=2 * n {
        for i in 0..=2 * n {
            // Half-unit lattice: vertices, edge midpoints, quad centres (on the diagonal).
            points.push([f64::from(i) * 0.5, f64::from(j) * 0.5]);
        }
    }
    points.extend((0..n * n).map(|q| [f64::from(q % n) + 0.75, f64::from(q / n) + 0.25]));
    let mut checked = 0;
    for p in points {
        let interior = |x: f64| x > 0.0 && x < f64::from(n);
        if !(interior(p[0]) && interior(p[1])) {
            continue;
        }
        // (direction z, the world offset of (ε, ε²) in the sheared plane, expected sign)
        for (dz, moved, sign) in [
            (1.0f32, [p[0] + eps, p[1] + eps * eps], -1),
            (-1.0, [p[0] + eps * eps, p[1] + eps], 1),
        ] {
            let origin = Vec3::new(p[0] as f32, p[1] as f32, -dz);
            let pre = WatertightRay::new(&Ray::new(origin, Vec3::new(0.0, 0.0, dz))).unwrap();
            let counted: std::vec::Vec<(usize, i8)> = (0..tris.len())
                .map(|k| (k, pre.crossing_sign(origin, &tris[k])))
                .filter(|&(_, s)| s != 0)
                .collect();
            let want: std::vec::Vec<(usize, i8)> = (0..tris.len())
                .filter(|&k| holds(&tris[k], moved))
                .map(|k| (k, sign))
                .collect();
            assert_eq!(want.len(), 1, "oracle at {p:?}");
            assert_eq!(counted, want, "point {p:?}, direction z {dz}");
            checked += 1;
        }
    }
    // 7 × 7 interior lattice points and 16 quad points, two directions each.
    assert_eq!(checked, 2 * (49 + 16));
}

/// A triangle whose projection is degenerate counts nothing, even for a ray through it: all
/// three vertices on the ray's line (every projected edge of length zero), two of them
/// projecting to one point, and a single point.
#[test]
fn crossing_sign_of_a_degenerate_projection_is_zero() {
    let z = |h: f32| Vec3::new(0.25, 0.5, h);
    let tris = [
        [z(1.0), z(2.0), z(3.0)],
        [z(1.0), z(2.0), Vec3::new(1.0, 0.5, 1.5)],
        [z(1.0); 3],
    ];
    for dz in [1.0f32, -1.0] {
        let origin = z(-5.0 * dz);
        let pre = WatertightRay::new(&Ray::new(origin, Vec3::new(0.0, 0.0, dz))).unwrap();
        for t in &tris {
            assert_eq!(pre.crossing_sign(origin, t), 0, "{t:?} along z {dz}");
        }
    }
}

#[test]
fn crossing_sign_keeps_a_closed_mesh_closed_through_every_edge_and_vertex() {
    // The octahedron (vertices ±e_i, faces outward): every line through a vertex or an
    // edge point enters as often as it leaves, and a transversal one crosses exactly
    // twice; a line touching only a vertex or an edge from outside counts nothing.
    let e = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let mut tris = std::vec::Vec::new();
    for sx in [0usize, 1] {
        for sy in [2usize, 3] {
            for sz in [4usize, 5] {
                let (x, y, z) = (e[sx], e[sy], e[sz]);
                // Outward normal = sign pattern; order the face counter-clockwise.
                let n = x + y + z;
                let tri = if (y - x).cross(z - x).dot(n) > 0.0 {
                    [x, y, z]
                } else {
                    [x, z, y]
                };
                tris.push(tri);
            }
        }
    }
    let mut s = 0x5EED_u64;
    let mut transversal = 0;
    let mut points: std::vec::Vec<Vec3> = e.to_vec();
    for i in 0..6 {
        for j in i + 1..6 {
            if e[i] != -e[j] {
                points.push((e[i] + e[j]) * 0.5);
                points.push(e[i] * 0.25 + e[j] * 0.75);
            }
        }
    }
    for p in &points {
        for _ in 0..200 {
            let dir = crate::test_util::unit_vec(&mut s);
            let (sum, counted, _) = crossings(&tris, *p - dir * 3.0, dir);
            assert_eq!(sum, 0, "through {p} along {dir}");
            assert!(
                counted == 0 || counted == 2,
                "through {p} along {dir}: {counted}"
            );
            // Independent oracle, in f64: the line meets the interior of |x|+|y|+|z| ≤ 1
            // iff that convex piecewise-linear function drops below 1 on it; its minimum
            // is at a breakpoint (a coordinate crossing zero).
            let (o, d) = ((*p - dir * 3.0).as_dvec3(), dir.as_dvec3());
            let f = |t: f64| (o + d * t).abs().element_sum();
            let min = (0..3)
                .filter(|&k| d[k] != 0.0)
                .map(|k| f(-o[k] / d[k]))
                .fold(f64::INFINITY, f64::min);
            // Within the projection's f32 rounding of the surface (~1e-7 here; 1e-5 is
            // far outside it) the test sees a slightly displaced line: only the sum and
            // the parity are promised there.
            if min < 1.0 - 1e-5 {
                assert_eq!(counted, 2, "through {p} along {dir}: enters the solid");
                transversal += 1;
            } else if min > 1.0 + 1e-5 {
                assert_eq!(counted, 0, "through {p} along {dir}: misses the solid");
            }
        }
    }
    assert!(transversal > 1000, "{transversal}");
    // Tangent at a vertex and along an edge, from outside: nothing is counted.
    let (sum, counted, _) = crossings(&tris, Vec3::new(1.0, 0.0, -2.0), Vec3::Z);
    assert_eq!((sum, counted), (0, 0));
    let (sum, counted, _) = crossings(
        &tris,
        Vec3::new(0.5, 0.5, -2.0) + Vec3::new(0.5, 0.5, 0.0),
        Vec3::Z,
    );
    assert_eq!(sum, 0);
    assert!(counted == 0 || counted == 2);
}

/// A sliver spanning 10⁸ in `z` and `7·10⁻²⁴` in `x`, nearly parallel to a ray along `−z`
/// (the `ray_triangle` regression `crash-bf27ce68-underflowing-edge-product-miss`): the `f64`
/// normal from any base vertex has `z = 0` (`0.347 + 6.6·10⁻²⁴` rounds to `0.347`), so the
/// plane form cannot be evaluated, but the triangle is not degenerate and the exact sheared
/// edge functions `(1.6·10⁻⁵⁸, 1.3·10⁻²⁴, 8.4·10⁻³⁶)` share one sign: a hit. `t` against the
/// independent `f64` reference.
#[test]
fn hit_where_the_f64_normal_cancels() {
    let ray = Ray::new(
        Vec3::new(0.0, f32::from_bits(0x0600_0000), 1.0),
        Vec3::new(-0.0, -0.0, -1.0),
    );
    let v = [
        Vec3::new(
            f32::from_bits(0x3eb1_b1b1),
            f32::from_bits(0x3e4c_4fcd),
            f32::from_bits(0x3f80_0045),
        ),
        Vec3::new(-0.0, 0.0, f32::from_bits(0x80)),
        Vec3::new(
            f32::from_bits(0x9900_0000),
            0.0,
            f32::from_bits(0x4ccc_9500),
        ),
    ];
    let n64 = (v[1] - v[0]).as_dvec3().cross((v[2] - v[0]).as_dvec3());
    assert_eq!(n64.z, 0.0, "the case needs a cancelled f64 normal");
    let (t_ref, _) = F64Reference::solve(&ray, &v).expect("the reference hits");
    for tri in [v, [v[1], v[2], v[0]], [v[0], v[2], v[1]]] {
        let hit = Watertight.intersect(&ray, &tri).expect("a hit");
        assert!(
            (f64::from(hit.t) - t_ref).abs() <= 1e-6 * t_ref,
            "{} vs {t_ref}",
            hit.t
        );
    }
}

/// A ray on the line through an edge but outside the triangle: that edge function is exactly
/// zero and the other two have opposite signs (by hand, for the unit right triangle and the
/// point `(2, 0)`: the edge `y = 0` gives 0, the hypotenuse `x + y = 1` the outside sign, the
/// edge `x = 0` the inside one). Two certain opposite signs decide the miss: the four-lane
/// cull reports the lane, and both closed tests miss; a ray at `(0.5, 0)` on the same edge
/// line but on the edge itself is a hit and is not culled.
#[test]
fn two_certain_opposite_edges_are_a_miss_whatever_the_third() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let outside = Ray::new(Vec3::new(2.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
    let on_edge = Ray::new(Vec3::new(0.5, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
    let records = [tri.map(|p| p.to_array()); 1];
    let lanes = TriangleLanes::from_triangles(&records);
    for (ray, culled) in [(outside, true), (on_edge, false)] {
        let pre = WatertightRay::new(&ray).unwrap();
        assert_eq!(
            pre.certain_misses(ray.origin, &lanes) & 1 == 1,
            culled,
            "{ray:?}"
        );
        assert_eq!(
            Watertight.intersect(&ray, &tri).is_none(),
            culled,
            "{ray:?}"
        );
        assert_eq!(
            WatertightF32.intersect(&ray, &tri).is_none(),
            culled,
            "{ray:?}"
        );
    }
}

/// The preparation of a checked ray skips only the check: for valid rays it equals
/// `prepare`, and both are the documented permutation and shear (written out here from
/// `WatertightRay`'s field docs: `kz` the first axis of largest `|d|`, `kx, ky` the next ones
/// cyclically, swapped when `d_kz < 0`; the shear the three `f32` quotients), for every
/// direction octant and dominant axis; an invalid ray is still refused by `prepare`.
#[test]
fn prepare_valid_equals_prepare_on_valid_rays() {
    use crate::test_util::{lcg, unit_vec};
    let documented = |d: Vec3| {
        let a = d.abs().to_array();
        let kz = if a[0] >= a[1] && a[0] >= a[2] {
            0
        } else if a[1] >= a[2] {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let c = d.to_array();
        if c[kz] < 0.0 {
            core::mem::swap(&mut kx, &mut ky);
        }
        let shear = Vec3::new(c[kx] / c[kz], c[ky] / c[kz], 1.0 / c[kz]);
        WatertightRay {
            k: [kx, ky, kz],
            shear,
        }
    };
    let mut s = 41u64;
    let mut octants_axes = [false; 24];
    for _ in 0..2000 {
        let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 100.0 - 50.0;
        let ray = Ray::new(o, unit_vec(&mut s) * (lcg(&mut s) * 10.0 + 1e-3));
        assert!(ray.is_valid());
        let want = Watertight.prepare(&ray);
        assert_eq!(want, Some(documented(ray.direction)), "{ray:?}");
        assert_eq!(Watertight.prepare_valid(&ray), want, "{ray:?}");
        assert_eq!(WatertightF32.prepare_valid(&ray), want, "{ray:?}");
        let d = ray.direction;
        let octant =
            usize::from(d.x < 0.0) | usize::from(d.y < 0.0) << 1 | usize::from(d.z < 0.0) << 2;
        octants_axes[octant * 3 + documented(d).k[2]] = true;
    }
    assert!(octants_axes.iter().all(|&seen| seen), "{octants_axes:?}");
    // Ties go to the lowest axis.
    assert_eq!(documented(Vec3::new(-1.0, 1.0, 1.0)).k, [2, 1, 0]);
    assert_eq!(
        Watertight
            .prepare(&Ray::new(Vec3::ZERO, Vec3::new(-1.0, 1.0, 1.0)))
            .map(|p| p.k),
        Some([2, 1, 0])
    );
    let invalid = Ray::new(Vec3::ZERO, Vec3::ZERO);
    assert_eq!(Watertight.prepare(&invalid), None);
}

/// On x86-64, `finish_exact` takes `common_t`'s answer whenever it has one: that must be the
/// bits `hit_t` (the only path elsewhere) returns for the same inputs, at every SIMD level. Random triangles of
/// every size from 1e-3 to 1e3 at every distance, ordinary rays and rays whose origin lies
/// near the triangle's plane (where the two forms of `t` differ most), plus slivers; most
/// hits take the common case, some do not.
#[cfg(target_arch = "x86_64")]
#[test]
fn the_common_case_gives_the_general_paths_bits() {
    use super::exact::{common_t, hit_t, plane_crossing};
    use crate::test_util::lcg;
    let mut s = 11u64;
    let (mut common, mut general_only) = (0usize, 0usize);
    for i in 0..40_000 {
        let v3 = |s: &mut u64, k: f32| Vec3::new(lcg(s) - 0.5, lcg(s) - 0.5, lcg(s) - 0.5) * k;
        let scale = 10f32.powf(lcg(&mut s) * 6.0 - 3.0);
        let centre = v3(&mut s, 100.0 * scale);
        let mut v = [
            centre + v3(&mut s, scale),
            centre + v3(&mut s, scale),
            centre + v3(&mut s, scale),
        ];
        if i % 7 == 0 {
            // A sliver: the third vertex almost on the first edge.
            v[2] = v[0] + (v[1] - v[0]) * lcg(&mut s) + v3(&mut s, scale * 1e-5);
        }
        let target =
            v[0] + (v[1] - v[0]) * (lcg(&mut s) * 0.5) + (v[2] - v[0]) * (lcg(&mut s) * 0.5);
        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        let origin = if i % 3 == 0 {
            // Near the plane: the direction runs almost along it.
            target + v3(&mut s, 10.0 * scale) - n * (n.dot(v3(&mut s, 10.0 * scale)) * 0.999)
        } else {
            target + v3(&mut s, 50.0 * scale)
        };
        let ray = Ray::new(origin, target - origin);
        let Some(pre) = WatertightRay::new(&ray) else {
            continue;
        };
        let sheared = pre.project_triangle(ray.origin, &v);
        let edges = exact_edges(sheared.0, sheared.1);
        let mixed = edges.iter().any(|&e| e < 0.0) && edges.iter().any(|&e| e > 0.0);
        let det = edges[0] + edges[1] + edges[2];
        if mixed || det == 0.0 || !det.is_finite() {
            continue;
        }
        let c = Candidate {
            ray: &ray,
            pre: &pre,
            v: &v,
            sheared,
            edges,
        };
        let general = hit_t(c, det);
        let portable = common_t(plane_crossing, c, det);
        if let Some(token) = crate::test_util::avx2_or_skip(
            "triangle::watertight::tests::the_common_case_gives_the_general_paths_bits",
        ) {
            let avx2 = common_t(
                |v: &[Vec3; 3], r: &Ray| avx2::plane_crossing(token, v, r),
                c,
                det,
            );
            assert_eq!(avx2.map(f64::to_bits), portable.map(f64::to_bits));
        }
        match portable {
            Some(t) => {
                common += 1;
                assert_eq!(
                    Some(t.to_bits()),
                    general.map(f64::to_bits),
                    "{ray:?} {v:?}"
                );
            }
            None => general_only += 1,
        }
    }
    assert!(common > 10_000, "{common} hits took the common case");
    assert!(general_only > 0, "no hit took the general path");
}

/// Rays that start within rounding of a triangle's plane (a point of the triangle computed in
/// `f32`, each coordinate moved by up to four ulps) towards random directions, half of them
/// grazing the plane (within `10⁻⁸` rad): whenever the exact orientation signs of the origin
/// and the direction against the plane (the expansions of `predicates`, not the filter
/// `crossed_behind` uses) put the crossing behind the origin, `Watertight` reports no hit for
/// `t_min = 0`. Without the refusal a few grazing rays (about 1 in 4 000) are reported as
/// hits: the exact path returns the sheared `t`, rounded to the wrong sign.
#[test]
fn a_plane_crossed_behind_the_origin_is_no_hit() {
    use crate::predicates::{orient_direction, orient3d_exact};
    use crate::test_util::{Lcg, unit_vec};
    let mut r = Lcg(41);
    let mut behind = 0;
    for i in 0..200_000 {
        let size = [1e-3f32, 1.0, 1e3][i % 3];
        let at = r.v(8.0 * size);
        let tri = [at + r.v(size), at + r.v(size), at + r.v(size)];
        let (b1, b2) = (r.f() * 0.5, r.f() * 0.5);
        let p = tri[0] + (tri[1] - tri[0]) * b1 + (tri[2] - tri[0]) * b2;
        let mut ulps =
            |x: f32| f32::from_bits((x.to_bits() as i32 + (r.f() * 9.0) as i32 - 4) as u32);
        let o = Vec3::new(ulps(p.x), ulps(p.y), ulps(p.z));
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
        let mut d = unit_vec(&mut r.0);
        if i % 2 == 0 {
            d = (d - n * d.dot(n) + n * (r.f() - 0.5) * 1e-8).normalize();
        }
        let side = orient3d_exact(tri[0], tri[1], tri[2], o);
        if side == 0 || side != orient_direction(tri[0], tri[1], tri[2], d) {
            continue;
        }
        behind += 1;
        let ray = Ray::new(o, d);
        assert_eq!(Watertight.intersect(&ray, &tri), None, "{tri:?} {ray:?}");
    }
    assert!(behind > 50_000, "{behind}");
}

/// `hit_sheared_on` (no `f32` filter: a leaf calls it for triangles the lane cull kept) gives
/// `hit_sheared`'s answer for **every** triangle, those the filter rejects included, at the portable level and
/// at AVX2 where the CPU has it: triangles near and far, rays through them, past their edges,
/// pointing away and grazing. Every kind of answer occurs: a hit, a filter reject, a miss of
/// the exact path.
#[test]
fn skipping_the_filter_the_cull_repeats_changes_no_answer() {
    use crate::test_util::{Lcg, avx2_or_skip};
    let avx2 = avx2_or_skip(
        "triangle::watertight::tests::skipping_the_filter_the_cull_repeats_changes_no_answer",
    );
    let mut r = Lcg(7);
    let (mut hits, mut rejected, mut exact_misses) = (0, 0, 0);
    for i in 0..40_000 {
        let size = [1e-2f32, 1.0, 1e2][i % 3];
        let at = r.v(4.0 * size);
        let v = [at + r.v(size), at + r.v(size), at + r.v(size)];
        let target = v[0] + (v[1] - v[0]) * (r.f() * 1.2 - 0.1) + (v[2] - v[0]) * (r.f() * 0.6);
        let mut d = target - (at + r.v(8.0 * size));
        if i % 5 == 0 {
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            d -= n * n.dot(d) * 0.9999;
        }
        let ray = Ray::new(target - d, if i % 7 == 0 { -d } else { d });
        let Some(pre) = WatertightRay::new(&ray) else {
            continue;
        };
        let want = Watertight.hit_sheared(&pre, &ray, &v);
        assert_eq!(
            Watertight.hit_sheared_on(Inside(()), Portable, &pre, &ray, &v),
            want,
            "{v:?} {ray:?}"
        );
        if let Some(token) = avx2 {
            assert_eq!(
                Watertight.hit_sheared_on(Inside(()), token, &pre, &ray, &v),
                want,
                "{v:?} {ray:?}"
            );
        }
        let sheared = pre.project_triangle(ray.origin, &v);
        if want.is_some() {
            hits += 1;
        } else if mixed_signs(&filter_edges(sheared.0, sheared.1)) {
            rejected += 1;
        } else {
            exact_misses += 1;
        }
    }
    assert!(
        hits > 5_000 && rejected > 5_000 && exact_misses > 100,
        "{hits} hits, {rejected} rejected by the filter, {exact_misses} missed exactly"
    );
}

/// A ray through each of the six regions outside a triangle (beyond one edge's line, or
/// beyond two at a vertex; the target point given by barycentric coordinates, one or two of
/// them negative) misses, for both windings and for rays along `−z`, `+z` and a tilted
/// direction, in every member of the family tested alone (`intersect`, no cull in front); a
/// ray through an interior point hits there. The oracle is the point's construction: every
/// coordinate is a dyadic fraction, so the points and origins are exact in `f32`.
#[test]
fn every_region_outside_a_triangle_is_a_miss_for_either_facing() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let outside = [
        [-0.25, 0.5, 0.75],
        [0.5, -0.25, 0.75],
        [0.5, 0.75, -0.25],
        [-0.5, -0.5, 2.0],
        [-0.5, 2.0, -0.5],
        [2.0, -0.5, -0.5],
    ];
    let inside = [0.25, 0.25, 0.5];
    let dirs = [
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::Z,
        Vec3::new(0.125, -0.0625, -1.0),
    ];
    type Test<'a> = &'a dyn Fn(&Ray, &[Vec3; 3]) -> Option<TriangleHit>;
    let tests: [(&str, Test<'_>); 3] = [
        ("watertight", &|r, v| Watertight.intersect(r, v)),
        ("watertight-f32", &|r, v| WatertightF32.intersect(r, v)),
        ("watertight-f32-exact", &|r, v| {
            crate::triangle::WatertightF32Exact.intersect(r, v)
        }),
    ];
    for v in [tri, [tri[0], tri[2], tri[1]]] {
        let at = |w: [f32; 3]| v[0] * w[0] + v[1] * w[1] + v[2] * w[2];
        for d in dirs {
            for (name, test) in tests {
                for w in outside {
                    let ray = Ray::new(at(w) - d * 2.0, d);
                    assert!(test(&ray, &v).is_none(), "{name}: {w:?} {v:?} {ray:?}");
                }
                let ray = Ray::new(at(inside) - d * 2.0, d);
                let h = test(&ray, &v).unwrap_or_else(|| panic!("{name}: {v:?} {ray:?}"));
                assert_eq!(h.t, 2.0, "{name}");
                assert!((h.b1 - inside[1]).abs() < 1e-6, "{name}: {h:?}");
                assert!((h.b2 - inside[2]).abs() < 1e-6, "{name}: {h:?}");
                assert_eq!(h.front_face, v[1].cross(v[2]).dot(d) < 0.0, "{name}: {h:?}");
            }
        }
    }
}

/// `WatertightRay`'s fields are private to the crate (outside it only `new` and `of_valid`
/// make one), but code inside it could still build one whose axes are out of range. Its
/// answers are then meaningless (the contract of `of_valid`), but every intersector must
/// still return instead of indexing out of bounds, at every SIMD level.
#[test]
fn a_hand_built_ray_with_axes_out_of_range_never_panics() {
    use crate::triangle::TriangleIntersector;
    let ray = Ray::new(Vec3::new(0.1, 0.2, 0.0), Vec3::Z);
    let tri = [
        Vec3::new(-1.0, -1.0, 2.0),
        Vec3::new(1.0, -1.0, 2.0),
        Vec3::new(0.0, 1.0, 2.0),
    ];
    for kz in [2, 3, 7, usize::MAX] {
        for k in [[0, 1, kz], [kz, 0, 1], [1, kz, 0]] {
            let pre = WatertightRay { k, shear: Vec3::Z };
            // Any answer is allowed; reaching the end without a panic is the property.
            let _ = Watertight.intersect_prepared(&pre, &ray, &tri);
            let _ = WatertightF32.intersect_prepared(&pre, &ray, &tri);
        }
    }
}
