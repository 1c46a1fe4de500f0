//! Mesh-vs-mesh collision and distance against brute force.
//!
//! * The triangle–triangle test against an **independent integer oracle**: coordinates on a
//!   `2⁻¹²` grid, so every predicate of the oracle is exact in `i128`; it decides by a
//!   different method (an edge of one triangle meets the other, the crossing point computed
//!   as a rational), on touching, coplanar and generic pairs, some rigidly moved.
//! * `colliding_pairs` / `first_contact` / `min_distance` equal brute force over all pairs
//!   (with the same triangle test and distance: this checks the traversal) on random meshes
//!   under random rigid transforms.
//! * The bunny against moved copies of itself, with a sweep-and-prune brute force (sorted
//!   boxes, independent of the BVH) over **all** pairs.

use glam::{Vec3, vec3};
use halfray::accel::{VecBvh, build_binary};
use halfray::obj::read_obj;
use halfray_core::bvh::BuildOptions;
use halfray_core::bvh::collide::{
    Body, DISTANCE_ERR_REL, colliding_pairs, first_contact, is_degenerate, min_distance,
    triangle_distance, triangles_intersect,
};
use halfray_core::mesh::TriangleMesh;
use halfray_core::transform::Transform;
use halfray_tests::meshes_dir;

/// Grid step of the oracle's coordinates: `2⁻¹²`. With `|x| ≤ 8` the scaled integers are
/// below `2¹⁵` and the oracle's largest product (a dot product with the normal of a
/// cross product of scaled crossing points) stays below `2¹²¹`, inside `i128`.
const GRID: f64 = 4096.0;

struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / ((1u64 << 24) as f32)
    }
    fn v(&mut self) -> Vec3 {
        vec3(self.f(), self.f(), self.f())
    }
    fn rigid(&mut self, shift: f32) -> Transform {
        let axis = self.v() - 0.5;
        let axis = if axis.length() < 1e-3 { Vec3::Y } else { axis };
        Transform::rotate(axis, self.f() * 6.3)
            .unwrap()
            .then(&Transform::translate((self.v() - 0.5) * shift).unwrap())
            .unwrap()
    }
}

type I3 = [i128; 3];

fn snap(v: Vec3) -> Vec3 {
    (v.as_dvec3() * GRID).round().as_vec3() / GRID as f32
}

fn int(v: Vec3) -> I3 {
    let s = (v.as_dvec3() * GRID).round();
    assert_eq!(s / GRID, v.as_dvec3(), "on the grid");
    [s.x as i128, s.y as i128, s.z as i128]
}

fn sub(a: I3, b: I3) -> I3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: I3, b: I3) -> I3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: I3, b: I3) -> i128 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn scale(a: I3, s: i128) -> I3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// 2-D orientation of `(a, b, c)` dropping axis `k`.
fn orient2(a: I3, b: I3, c: I3, k: usize) -> i128 {
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    ((b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i])).signum()
}

/// Closed 2-D segments meet (dropping axis `k`).
fn seg2(p: I3, q: I3, r: I3, s: I3, k: usize) -> bool {
    let within = |a: I3, b: I3, x: I3| {
        (0..3)
            .filter(|&d| d != k)
            .all(|d| a[d].min(b[d]) <= x[d] && x[d] <= a[d].max(b[d]))
    };
    let (o1, o2) = (orient2(p, q, r, k), orient2(p, q, s, k));
    let (o3, o4) = (orient2(r, s, p, k), orient2(r, s, q, k));
    (o1 * o2 < 0 && o3 * o4 < 0)
        || (o1 == 0 && within(p, q, r))
        || (o2 == 0 && within(p, q, s))
        || (o3 == 0 && within(r, s, p))
        || (o4 == 0 && within(r, s, q))
}

/// The closed segment `pq` meets the closed non-degenerate triangle `t` (integers).
fn seg_tri(p: I3, q: I3, t: [I3; 3]) -> bool {
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let (dp, dq) = (dot(n, sub(p, t[0])), dot(n, sub(q, t[0])));
    if dp.signum() * dq.signum() > 0 {
        return false;
    }
    if dp == 0 && dq == 0 {
        // In the plane: project along the normal's largest axis (injective on the plane).
        let k = (0..3).max_by_key(|&d| n[d].abs()).unwrap();
        let inside = |x: I3| {
            let s: Vec<i128> = (0..3)
                .map(|e| orient2(t[e], t[(e + 1) % 3], x, k))
                .collect();
            s.iter().all(|&v| v >= 0) || s.iter().all(|&v| v <= 0)
        };
        return inside(p) || inside(q) || (0..3).any(|e| seg2(p, q, t[e], t[(e + 1) % 3], k));
    }
    // The crossing point X = (dp·q − dq·p) / (dp − dq), kept as numerator and denominator.
    let den = dp - dq;
    let xn = sub(scale(q, dp), scale(p, dq));
    let signs: Vec<i128> = (0..3)
        .map(|e| {
            let (u, v) = (t[e], t[(e + 1) % 3]);
            dot(n, cross(sub(v, u), sub(xn, scale(u, den)))).signum() * den.signum()
        })
        .collect();
    signs.iter().all(|&s| s >= 0)
}

/// The oracle: non-degenerate closed triangles intersect iff an edge of one meets the other.
fn oracle(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    let (ia, ib) = (a.map(int), b.map(int));
    (0..3).any(|e| seg_tri(ia[e], ia[(e + 1) % 3], ib))
        || (0..3).any(|e| seg_tri(ib[e], ib[(e + 1) % 3], ia))
}

#[test]
fn triangle_test_equals_integer_oracle() {
    let mut r = Rng(7);
    let (mut checked, mut hits, mut coplanar) = (0, 0, 0);
    for case in 0..60_000 {
        let (a, b) = match case % 3 {
            // Small integer grid: shared vertices, edges, coplanar pairs everywhere.
            0 => {
                let mut g = || snap((r.v() * 5.0 - 2.5).floor());
                ([g(), g(), g()], [g(), g(), g()])
            }
            // Coplanar on z = 1, fine grid.
            1 => {
                let mut g = || snap(vec3(r.f() * 4.0 - 2.0, r.f() * 4.0 - 2.0, 1.0));
                ([g(), g(), g()], [g(), g(), g()])
            }
            // Generic triangles, the second rigidly moved near the first, then snapped.
            _ => {
                let a = [r.v(), r.v(), r.v()].map(|v| snap(v * 3.0 - 1.5));
                let tf = r.rigid(1.0);
                let b = [r.v(), r.v(), r.v()].map(|v| snap(tf.point_to_world(v * 3.0 - 1.5)));
                (a, b)
            }
        };
        if is_degenerate(&a) || is_degenerate(&b) {
            continue;
        }
        let want = oracle(&a, &b);
        checked += 1;
        hits += usize::from(want);
        coplanar += usize::from(case % 3 == 1 && want);
        assert_eq!(
            triangles_intersect(&a, &b),
            want,
            "case {case}: {a:?} {b:?}"
        );
    }
    assert!(
        checked > 40_000 && hits > 8_000 && coplanar > 2_000,
        "{checked} {hits} {coplanar}"
    );
}

fn tree(mesh: &TriangleMesh<'_>) -> VecBvh {
    build_binary(mesh, &BuildOptions::default()).unwrap()
}

/// A UV sphere of radius `r` around `c` with `n` segments and `n/2` rings.
fn sphere(c: Vec3, r: f32, n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let rings = n / 2;
    let mut p = Vec::new();
    for i in 0..=rings {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..n {
            let ph = 2.0 * std::f32::consts::PI * j as f32 / n as f32;
            p.push(c + r * vec3(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
        }
    }
    let mut t = Vec::new();
    for i in 0..rings {
        for j in 0..n {
            let (a, b) = (i * n + j, i * n + (j + 1) % n);
            let (c2, d) = (a + n, b + n);
            t.push([a, c2, b]);
            t.push([b, c2, d]);
        }
    }
    (p, t)
}

fn soup(r: &mut Rng, n: u32, spread: f32, size: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    let mut t = Vec::new();
    for i in 0..n {
        let c = r.v() * spread;
        for _ in 0..3 {
            p.push(c + (r.v() - 0.5) * size);
        }
        t.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    (p, t)
}

/// The core's independent distance oracle (its unit tests' copy: one definition).
#[path = "../../core/src/bvh/collide/tests/oracle.rs"]
mod oracle;

/// Brute force over all pairs: the sorted colliding pairs and the closest pair (ties: the
/// smaller `(a, b)`), the latter checked against the independent oracle's smallest distance
/// within twice `DISTANCE_ERR_REL·(d + M)` (the function's bound and the oracle's rounding).
fn brute(
    ma: &TriangleMesh<'_>,
    mb: &TriangleMesh<'_>,
    tf: &Transform,
) -> (Vec<(u32, u32)>, (f64, u32, u32)) {
    let mut pairs = Vec::new();
    let mut best = (f64::INFINITY, u32::MAX, u32::MAX);
    // The oracle's smallest distance, and the largest coordinate magnitude seen.
    let mut independent = (f64::INFINITY, 0.0f64);
    for i in 0..ma.len() {
        let x = ma.triangle(i).unwrap();
        for j in 0..mb.len() {
            let y = mb.triangle(j).unwrap().map(|v| tf.point_to_world(v));
            if triangles_intersect(&x, &y) {
                pairs.push((i as u32, j as u32));
            }
            let d = triangle_distance(&x, &y);
            if d < best.0 {
                best = (d, i as u32, j as u32);
            }
            independent.0 = independent.0.min(oracle::distance(&x, &y).0);
            independent.1 = independent.1.max(oracle::magnitude(&x, &y));
        }
    }
    let (o, m) = independent;
    assert!(
        (best.0 - o).abs() <= 2.0 * DISTANCE_ERR_REL * (o + m),
        "brute force's {} against the oracle's {o}",
        best.0
    );
    (pairs, best)
}

#[test]
fn random_meshes_under_random_rigid_transforms_equal_brute_force() {
    let mut r = Rng(21);
    let (mut colliding_cases, mut apart_cases) = (0, 0);
    for round in 0..24 {
        let (pa, ta) = if round % 2 == 0 {
            sphere(vec3(0.0, 0.0, 0.0), 1.0, 12)
        } else {
            soup(&mut r, 120, 2.0, 0.6)
        };
        let (pb, tb) = if round % 3 == 0 {
            soup(&mut r, 100, 2.0, 0.6)
        } else {
            sphere(vec3(0.2, -0.1, 0.3), 0.8, 10)
        };
        let (ma, mb) = (TriangleMesh::new(&pa, &ta), TriangleMesh::new(&pb, &tb));
        let (ba, bb) = (tree(&ma), tree(&mb));
        let (a, b) = (Body::new(&ba, ma).unwrap(), Body::new(&bb, mb).unwrap());
        let tf = r.rigid(1.5 + round as f32 * 0.25);
        let (want, best) = brute(&ma, &mb, &tf);
        let mut out = vec![(0, 0); want.len()];
        let n = colliding_pairs(&a, &b, &tf, &mut out).unwrap();
        assert_eq!(n, want.len(), "round {round}");
        out.sort_unstable();
        assert_eq!(out, want, "round {round}");
        let first = first_contact(&a, &b, &tf).unwrap();
        assert_eq!(first.is_some(), !want.is_empty());
        assert!(first.is_none_or(|p| want.binary_search(&p).is_ok()));
        if want.is_empty() {
            apart_cases += 1;
        } else {
            colliding_cases += 1;
        }
        let c = min_distance(&a, &b, &tf, f64::INFINITY).unwrap().unwrap();
        assert_eq!((c.distance, c.a, c.b), best, "round {round}");
        // The bound: at the distance itself it is found, just below it nothing is.
        assert_eq!(min_distance(&a, &b, &tf, best.0).unwrap(), Some(c));
        if best.0 > 0.0 {
            assert_eq!(
                min_distance(&a, &b, &tf, best.0 * (1.0 - 1e-9)).unwrap(),
                None
            );
        } else {
            assert_eq!((c.a, c.b), want[0], "the smallest colliding pair");
        }
    }
    assert!(
        colliding_cases >= 5 && apart_cases >= 5,
        "{colliding_cases} {apart_cases}"
    );
}

/// Placed triangles of `mb` by `tf`, their boxes, and their order by box `min.x`.
struct Sweep {
    tris: Vec<[Vec3; 3]>,
    boxes: Vec<(Vec3, Vec3)>,
    order: Vec<usize>,
    widest: f32,
}

impl Sweep {
    fn new(mb: &TriangleMesh<'_>, tf: &Transform) -> Self {
        let tris: Vec<_> = (0..mb.len())
            .map(|j| mb.triangle(j).unwrap().map(|v| tf.point_to_world(v)))
            .collect();
        let boxes: Vec<_> = tris
            .iter()
            .map(|t| (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2])))
            .collect();
        let mut order: Vec<usize> = (0..tris.len()).collect();
        order.sort_by(|&i, &j| boxes[i].0.x.total_cmp(&boxes[j].0.x));
        let widest = boxes.iter().map(|b| b.1.x - b.0.x).fold(0.0, f32::max);
        Self {
            tris,
            boxes,
            order,
            widest,
        }
    }

    /// Indices whose box lies within `margin` of `[lo, hi]` on x (a superset, by the sort).
    fn near(&self, lo: Vec3, hi: Vec3, margin: f32) -> &[usize] {
        let from = lo.x - self.widest - margin;
        let to = hi.x + margin;
        let s = self.order.partition_point(|&j| self.boxes[j].0.x < from);
        let e = self.order.partition_point(|&j| self.boxes[j].0.x <= to);
        &self.order[s..e.max(s)]
    }
}

#[test]
fn bunny_against_moved_copies_equals_sweep_brute_force() {
    let path = meshes_dir().join("bunny.obj");
    let obj = read_obj(&path).unwrap_or_else(|e| panic!("{path:?} is required: {e}"));
    let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
    let bvh = tree(&mesh);
    let body = Body::new(&bvh, mesh).unwrap();
    let bounds = bvh.bounds();
    let ext = bounds.extent();
    let transforms = [
        // Overlapping: turned and shifted by a fifth of the size.
        Transform::rotate(vec3(0.3, 1.0, 0.2), 0.4)
            .unwrap()
            .then(&Transform::translate(ext * 0.2).unwrap())
            .unwrap(),
        // Just apart along x: shifted by the full width plus 2 %.
        Transform::translate(vec3(ext.x * 1.02, 0.0, 0.0)).unwrap(),
        // Turned half round about y and pushed back beside itself.
        Transform::rotate(Vec3::Y, std::f32::consts::PI)
            .unwrap()
            .then(
                &Transform::translate(vec3(bounds.min.x + bounds.max.x + ext.x * 1.1, 0.0, 0.0))
                    .unwrap(),
            )
            .unwrap(),
    ];
    let mut collided = 0;
    for (k, tf) in transforms.iter().enumerate() {
        let sweep = Sweep::new(&mesh, tf);
        let n = colliding_pairs(&body, &body, tf, &mut []).or_else(|e| match e {
            halfray_core::bvh::collide::CollideError::OutputTooSmall { needed, .. } => Ok(needed),
            e => Err(e),
        });
        let n = n.unwrap();
        let mut got = vec![(0, 0); n];
        assert_eq!(colliding_pairs(&body, &body, tf, &mut got).unwrap(), n);
        got.sort_unstable();
        let mut want = Vec::new();
        for i in 0..mesh.len() {
            let x = mesh.triangle(i).unwrap();
            let (lo, hi) = (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]));
            for &j in sweep.near(lo, hi, 0.0) {
                let (blo, bhi) = sweep.boxes[j];
                if blo.cmple(hi).all()
                    && lo.cmple(bhi).all()
                    && triangles_intersect(&x, &sweep.tris[j])
                {
                    want.push((i as u32, j as u32));
                }
            }
        }
        want.sort_unstable();
        assert_eq!(got, want, "transform {k}");
        collided += usize::from(!want.is_empty());
        let c = min_distance(&body, &body, tf, f64::INFINITY)
            .unwrap()
            .unwrap();
        if !want.is_empty() {
            assert_eq!((c.distance, c.a, c.b), (0.0, want[0].0, want[0].1));
            continue;
        }
        // Brute force over every pair whose boxes are within the found distance (a real
        // pair's distance, so an upper bound of the minimum) plus a margin on x.
        let u = c.distance as f32 * 1.01 + 1e-6;
        let mut best = (f64::INFINITY, u32::MAX, u32::MAX);
        for i in 0..mesh.len() {
            let x = mesh.triangle(i).unwrap();
            let (lo, hi) = (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]));
            for &j in sweep.near(lo, hi, u) {
                let d = triangle_distance(&x, &sweep.tris[j]);
                if d < best.0 || (d == best.0 && (i as u32, j as u32) < (best.1, best.2)) {
                    best = (d, i as u32, j as u32);
                }
            }
        }
        assert_eq!((c.distance, c.a, c.b), best, "transform {k}");
        assert!(c.distance > 0.0);
        assert_eq!(first_contact(&body, &body, tf).unwrap(), None);
    }
    assert_eq!(collided, 1);
}
