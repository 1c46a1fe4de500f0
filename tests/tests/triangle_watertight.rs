//! Watertightness on exact edge and vertex rays (issue 2, "Hard cases"; robustness.md §1.2, §4.2,
//! §6.1 T1, T2, T4, T12).
//!
//! **Correct answer.** Every ray here passes *exactly* through an edge point or a vertex of a
//! mesh with shared, bit-identical vertices ([`halfray_tests::aim_exact`]: `origin + 1·direction
//! = target` holds in real arithmetic; edge points are `f32` points lying exactly on the segment,
//! [`halfray_tests::exact_edge_point`]), at `t = 1`. The exact answer is that *every* incident
//! triangle is hit at `t = 1` (edges are closed). Rays are counted only when they cross the
//! surface transversally and robustly ([`halfray_tests::classify`]: exact orientation signs, plus
//! a clearance of `16·u·R` in projection so that input-level rounding cannot move the ray off the
//! incident triangles); silhouettes and grazing views are skipped and reported as skipped.
//!
//! A **leak** is a counted ray that hits none of the incident triangles. The watertight variants
//! (`watertight`, `watertight-f32`, `f64-reference`, and `watertight-f32-exact`, the `f64`-free
//! test, which must also hit exactly the faces `watertight` hits) must have zero leaks, and every hit they
//! report on an incident triangle must have `t` within [`T_AT_TARGET_TOL`] of 1. Möller–Trumbore
//! (both) and Cramer leaks are counted and printed, never asserted:
//!
//! ```text
//! LEAKS variant=<name> rays=N edge_leaks=X vertex_leaks=Y edge_rays=.. vertex_rays=.. multi_hits=.. set=<set>
//! ```
//!
//! Origins: far, camera-like ones (distance 2–2000) at the exact solids, whose targets have few
//! significant bits; local ones (within the representable box around the target, see the crate
//! docs) at the full-mantissa vertices and edge points of spot, torus and bunny; and, for the
//! translated solids, a camera within 2 units of the world origin.

use glam::{DVec3, Vec3};
use halfray_core::Ray;
use halfray_core::triangle::{
    TriangleIntersector, TriangleVariant, Watertight, WatertightF32Exact,
};
use halfray_tests::{
    CLEARANCE_IN_U, LeakCount, Mesh, Projector, Rng, Target, TargetKind, U32, aim_exact, classify,
    edge_target, exact, fan_normal, vertex_target,
};

/// Required number of counted (robustly transversal) edge + vertex rays over the closed meshes
/// at their original position (issue 2, "Shows").
const MIN_CLOSED_RAYS: usize = 100_000;

/// Tolerance on `|t − 1|` for incident hits of the watertight variants (the exact parameter of
/// the target is 1): `T_AT_TARGET_TOL + T_AT_TARGET_IN_U·u·R / (|d|·sin φ)`, with `R` the
/// largest coordinate of `vertex − origin`, `φ` the angle between the ray and the face. The
/// second term is the propagated input rounding (a few `u·R` in the sheared coordinates,
/// divided by the face's projected extent); the first a floor. Loose on purpose: it catches
/// wrong-`t` hits, not accuracy, which `intersect_hard_cases` measures against the reference.
const T_AT_TARGET_TOL: f64 = 1.0e-5;
/// See [`T_AT_TARGET_TOL`].
const T_AT_TARGET_IN_U: f64 = 64.0;

const VARIANTS: [TriangleVariant; 6] = TriangleVariant::ALL;

/// The `t` tolerance of a hit at the target (`t = 1`) on face `tri`: its rounding error grows
/// like `1/sin` of the angle between the ray and the face (the face's depth along the ray is
/// ill-conditioned near edge-on views); see [`T_AT_TARGET_TOL`].
fn t_tolerance(tri: &[Vec3; 3], ray: &Ray) -> f64 {
    let (d, o) = (ray.direction.as_dvec3(), ray.origin.as_dvec3());
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    let nrm = (b - a).cross(c - a);
    let sin = (nrm.dot(d) / (nrm.length() * d.length())).abs();
    let r = [a, b, c]
        .iter()
        .map(|p| (*p - o).abs().max_element())
        .fold(0.0, f64::max);
    T_AT_TARGET_TOL + T_AT_TARGET_IN_U * U32 * r / (d.length() * sin)
}

/// Per-variant leak tallies plus the failures of the watertight variants.
#[derive(Default)]
struct Tally {
    counts: [LeakCount; 6],
    /// [`WatertightF32Exact`] (the `f64`-free test for microcontrollers), which must also agree
    /// with `watertight` face by face (its edge signs are the same exact ones).
    exact_f32: LeakCount,
    skipped: usize,
    failures: Vec<String>,
}

impl Tally {
    fn test_incident(&mut self, mesh: &Mesh, target: &Target, ray: &Ray) {
        let edge = matches!(target.kind, TargetKind::Edge(..));
        for (vi, &v) in VARIANTS.iter().enumerate() {
            let mut n = 0;
            for &f in &target.faces {
                let tri = mesh.tri(f);
                let Some(h) = v.intersect(ray, &tri) else {
                    continue;
                };
                n += 1;
                if !v.is_watertight() {
                    continue;
                }
                let tol = t_tolerance(&tri, ray);
                if (f64::from(h.t) - 1.0).abs() > tol {
                    self.fail(format!(
                        "{}: incident face {f} hit at t = {}, expected 1 ± {tol:e}: {:?} {:?}, ray {:?}",
                        v.name(),
                        h.t,
                        target.kind,
                        target.point,
                        ray
                    ));
                }
            }
            self.counts[vi].record(edge, n);
            if v.is_watertight() && n == 0 {
                self.fail(format!(
                    "{} leak: {:?} at {:?}, ray {:?}",
                    v.name(),
                    target.kind,
                    target.point,
                    ray
                ));
            }
        }
        let mut n = 0;
        for &f in &target.faces {
            let tri = mesh.tri(f);
            let ours = WatertightF32Exact.intersect(ray, &tri);
            let exact = Watertight.intersect(ray, &tri);
            if ours.is_some() != exact.is_some() {
                self.fail(format!(
                    "{} and watertight disagree on face {f}: {ours:?} vs {exact:?}, {:?} at {:?}, ray {:?}",
                    WatertightF32Exact.name(),
                    target.kind,
                    target.point,
                    ray
                ));
            }
            if let (Some(h), Some(w)) = (ours, exact) {
                n += 1;
                let tol = t_tolerance(&tri, ray);
                if (f64::from(h.t) - 1.0).abs() > tol {
                    self.fail(format!(
                        "{}: face {f} hit at t = {} (watertight: {}), expected 1 ± {tol:e}: ray {:?}",
                        WatertightF32Exact.name(),
                        h.t,
                        w.t,
                        ray
                    ));
                }
            }
        }
        self.exact_f32.record(edge, n);
        if n == 0 {
            self.fail(format!(
                "{} leak: {:?} at {:?}, ray {:?}",
                WatertightF32Exact.name(),
                target.kind,
                target.point,
                ray
            ));
        }
    }

    fn fail(&mut self, msg: String) {
        if self.failures.len() < 20 {
            self.failures.push(msg);
        } else if self.failures.len() == 20 {
            self.failures.push("...".into());
        }
    }

    fn rays(&self) -> usize {
        self.counts[0].rays()
    }

    fn add(&mut self, o: &Self) {
        for (a, b) in self.counts.iter_mut().zip(&o.counts) {
            a.add(b);
        }
        self.exact_f32.add(&o.exact_f32);
        self.skipped += o.skipped;
        self.failures.extend(o.failures.iter().cloned());
    }

    fn print(&self, set: &str) {
        for (vi, &v) in VARIANTS.iter().enumerate() {
            eprintln!("{}", self.counts[vi].line(v, set));
        }
        eprintln!("SKIPPED set={set} skipped={}", self.skipped);
    }

    fn assert_watertight(&self, set: &str) {
        assert!(
            self.failures.is_empty(),
            "{set}: {} failures:\n{}",
            self.failures.len(),
            self.failures.join("\n")
        );
        for (vi, &v) in VARIANTS.iter().enumerate() {
            if v.is_watertight() {
                assert_eq!(self.counts[vi].leaks(), 0, "{set}: {}", v.name());
            }
        }
        assert_eq!(self.exact_f32.leaks(), 0, "{set}: watertight-f32-exact");
        assert_eq!(
            self.exact_f32.rays(),
            self.counts[0].rays(),
            "{set}: watertight-f32-exact saw every ray"
        );
    }
}

/// Where origins come from.
#[derive(Clone, Copy, Debug)]
enum Origins {
    /// Camera-like: distance log-uniform in `[lo, hi]` from the target, mostly from outside.
    Far { lo: f64, hi: f64 },
    /// Local: distance log-uniform in `[lo, hi]`, halved until the exact snap exists.
    Local { lo: f64, hi: f64 },
}

/// Picks an origin guess at `dist` from the target on a direction that mostly enters the
/// surface from outside (against the fan normal), sometimes anything.
fn origin_guess(rng: &mut Rng, p: DVec3, outward: DVec3, dist: f64) -> DVec3 {
    let mut u = rng.unit_vector();
    if rng.chance(0.8) && u.dot(outward) < 0.0 {
        u = -u;
    }
    p + u * dist
}

fn aim(rng: &mut Rng, target: &Target, outward: DVec3, origins: Origins) -> Option<Ray> {
    let p = target.point.as_dvec3();
    match origins {
        Origins::Far { lo, hi } => {
            let dist = rng.log_range(lo, hi);
            let guess = origin_guess(rng, p, outward, dist);
            aim_exact(target.point, guess.as_vec3(), 0.05 * dist)
        }
        Origins::Local { lo, hi } => {
            let mut dist = rng.log_range(lo, hi);
            let u = origin_guess(rng, DVec3::ZERO, outward, 1.0);
            for _ in 0..24 {
                if let Some(r) = aim_exact(target.point, (p + u * dist).as_vec3(), 1.0e-3 * dist) {
                    return Some(r);
                }
                dist *= 0.5;
            }
            None
        }
    }
}

/// Shoots exact rays at random edges and vertices of `mesh` until `edge_quota` edge rays and
/// `vertex_quota` vertex rays are counted (or the attempt budget runs out).
fn run_mesh(
    mesh: &Mesh,
    origins: Origins,
    edge_quota: usize,
    vertex_quota: usize,
    seed: u64,
) -> Tally {
    let mut rng = Rng::new(seed);
    let edges: Vec<_> = mesh
        .edge_faces()
        .into_iter()
        .filter(|(_, f)| f.len() == 2)
        .collect();
    let vfaces = mesh.vertex_faces();
    let used: Vec<u32> = (0..mesh.positions.len() as u32)
        .filter(|&v| !vfaces[v as usize].is_empty())
        .collect();
    let mut tally = Tally::default();
    let (mut ne, mut nv) = (0, 0);
    let budget = 40 * (edge_quota + vertex_quota) + 1000;
    for _ in 0..budget {
        if ne >= edge_quota && nv >= vertex_quota {
            break;
        }
        let want_edge = if ne >= edge_quota {
            false
        } else if nv >= vertex_quota {
            true
        } else {
            rng.chance(0.5)
        };
        let target = if want_edge {
            let (e, faces) = &edges[rng.below(edges.len())];
            match edge_target(mesh, *e, faces, &mut rng, 8, 12) {
                Some(t) => t,
                None => continue,
            }
        } else {
            vertex_target(mesh, &vfaces, used[rng.below(used.len())]).unwrap()
        };
        let outward = fan_normal(mesh, &target.faces);
        let Some(ray) = aim(&mut rng, &target, outward, origins) else {
            continue;
        };
        if classify(mesh, &target, &ray).is_none() {
            tally.skipped += 1;
            continue;
        }
        tally.test_incident(mesh, &target, &ray);
        if want_edge {
            ne += 1;
        } else {
            nv += 1;
        }
    }
    assert!(
        ne >= edge_quota && nv >= vertex_quota,
        "ray budget exhausted: {ne} edge and {nv} vertex rays"
    );
    tally
}

#[test]
fn harness_exact_orientation_is_exact() {
    // det[[a, b, 0], [c, d, 0], [0, 0, 1]] = a·d − b·c = 2⁻⁶⁰ exactly, 0 in plain f64.
    let a = 1.0 + 2f64.powi(-30);
    let c = 1.0 + 2f64.powi(-29);
    assert_eq!(a * a - c, 0.0, "plain f64 loses it");
    assert_eq!(
        exact::det3_sign([a, 1.0, 0.0], [c, a, 0.0], [0.0, 0.0, 1.0]),
        1
    );
    assert_eq!(
        exact::det3_sign([c, a, 0.0], [a, 1.0, 0.0], [0.0, 0.0, 1.0]),
        -1
    );
    assert_eq!(
        exact::det3_sign([a, c, 0.0], [a, c, 0.0], [1.0, 2.0, 3.0]),
        0
    );
    // Triangle orientation: the +z face seen from above is entered through its front.
    let (p, q, r) = (Vec3::ZERO, Vec3::X, Vec3::Y);
    assert_eq!(exact::orient_sign(p, q, r, -Vec3::Z), -1);
    assert_eq!(exact::orient_sign(p, q, r, Vec3::Z), 1);
    assert_eq!(exact::orient_sign(p, q, r, Vec3::new(1.0, 3.0, 0.0)), 0);
    assert_eq!(exact::lowest_bit(0.75), 0.25);
    assert_eq!(exact::lowest_bit(-6.0), 2.0);
    assert_eq!(exact::lowest_bit(0.0), f64::INFINITY);
}

#[test]
fn harness_exact_rays_and_classification() {
    let cube = Mesh::load("cube.obj");
    assert_eq!((cube.positions.len(), cube.triangles.len()), (8, 12));
    let vfaces = cube.vertex_faces();
    let v = cube.positions.iter().position(|&p| p == Vec3::ONE).unwrap() as u32;
    let target = vertex_target(&cube, &vfaces, v).unwrap();
    // Far origin on the diagonal: exact, enters the corner's interior cone: counted, entering.
    let ray = aim_exact(Vec3::ONE, Vec3::new(700.3, 650.1, 720.7), 1.0).unwrap();
    assert_eq!(
        (ray.origin.as_dvec3() + ray.direction.as_dvec3()),
        DVec3::ONE,
        "exact"
    );
    let c = classify(&cube, &target, &ray).expect("transversal");
    assert_eq!(c.side, -1);
    assert!(c.clearance >= c.required);
    // Tangent to the corner (direction outside both the cone and its opposite): skipped.
    let ray = aim_exact(Vec3::ONE, Vec3::new(3.0, 0.5, -2.0), 0.0).unwrap();
    assert!(classify(&cube, &target, &ray).is_none());
    // In the plane of the top face (grazing): skipped.
    let ray = aim_exact(Vec3::ONE, Vec3::new(-3.0, -2.0, 1.0), 0.0).unwrap();
    assert!(classify(&cube, &target, &ray).is_none());
    // A full-mantissa target cannot be aimed at exactly from far away ...
    let p = Vec3::new(0.1, 0.3, 0.7);
    assert!(aim_exact(p, Vec3::new(900.1, 3.3, 1.7), 1.0).is_none());
    // ... but from within its representable box it can, with a full-mantissa direction.
    let r = aim_exact(p, Vec3::new(0.05, 0.45, 0.93), 1.0e-6).unwrap();
    assert_eq!(r.origin.as_dvec3() + r.direction.as_dvec3(), p.as_dvec3());
    // Edge points are exact and on the segment.
    let e = halfray_tests::exact_edge_point(Vec3::new(-1.0, 1.0, 1.0), Vec3::ONE, 3, 3).unwrap();
    assert_eq!(e, Vec3::new(-0.25, 1.0, 1.0));
    assert!(halfray_tests::exact_edge_point(Vec3::ZERO, Vec3::new(0.1, 0.2, 0.3), 1, 1).is_some());
    assert!(halfray_tests::exact_edge_point(Vec3::ZERO, Vec3::new(0.1, 0.2, 0.3), 1, 3).is_some());
    let _ = CLEARANCE_IN_U;
}

/// The headline set: ≥ 100 000 exact, robustly transversal edge and vertex rays over the closed
/// meshes at their own position. Zero leaks for the watertight variants.
#[test]
fn closed_meshes_exact_edge_and_vertex_rays() {
    let sets: [(&str, Origins, usize, u64); 5] = [
        (
            "tetrahedron.obj",
            Origins::Far {
                lo: 2.0,
                hi: 2000.0,
            },
            7_500,
            1,
        ),
        (
            "cube.obj",
            Origins::Far {
                lo: 2.0,
                hi: 2000.0,
            },
            7_500,
            2,
        ),
        (
            "octahedron.obj",
            Origins::Far {
                lo: 2.0,
                hi: 2000.0,
            },
            7_500,
            3,
        ),
        ("spot.obj", Origins::Local { lo: 0.05, hi: 2.0 }, 15_000, 4),
        ("torus.obj", Origins::Local { lo: 0.05, hi: 2.0 }, 15_000, 5),
    ];
    let mut total = Tally::default();
    for (name, origins, quota, seed) in sets {
        let mesh = Mesh::load(name);
        let mut t = run_mesh(&mesh, origins, quota, quota, seed);
        // The exact solids also get local origins (distance 0.05–2), a quarter as many.
        if let Origins::Far { .. } = origins {
            let local = run_mesh(
                &mesh,
                Origins::Local { lo: 0.05, hi: 2.0 },
                quota / 4,
                quota / 4,
                seed + 100,
            );
            t.add(&local);
        }
        t.print(name.trim_end_matches(".obj"));
        total.add(&t);
    }
    total.print("closed");
    assert!(
        total.rays() >= MIN_CLOSED_RAYS,
        "only {} rays",
        total.rays()
    );
    total.assert_watertight("closed");
}

/// Interior (two-face) edges of the open bunny, local exact rays.
#[test]
fn bunny_interior_edges_exact_rays() {
    let bunny = Mesh::load("bunny.obj");
    assert_eq!(bunny.triangles.len(), 69_451);
    let t = run_mesh(&bunny, Origins::Local { lo: 0.005, hi: 0.2 }, 10_000, 0, 11);
    t.print("bunny-interior-edges");
    assert_eq!(t.counts[0].edge_rays, 10_000);
    t.assert_watertight("bunny");
}

// ---------------------------------------------------------------------------------------------
// Translated solids, camera near the world origin
// ---------------------------------------------------------------------------------------------

/// The "front layer" criterion for a convex solid seen from a far camera: the incident faces
/// are entered (exact sign −1), and the projection of the front faces (exact sign −1) covers a
/// disc of radius `CLEARANCE_IN_U·u·R` around the target (distance to the projected silhouette
/// edges). For a convex solid the front faces project onto the silhouette polygon as a single
/// disc-like layer, so every perturbation of the projected vertices below that radius keeps the
/// ray inside it: the ray must hit at least one front face. A miss of all of them is a crack.
///
/// This is what "no leak" means when the camera is so far that `u·R` is comparable with the
/// triangles themselves (`R = 1e6`: `16·u·R ≈ 1`): the effective ray then lands next to the
/// target's edge rather than on it, possibly on a neighbouring face, which is not a leak.
fn front_layer(mesh: &Mesh, target: &Target, ray: &Ray) -> Option<Vec<u32>> {
    let d = ray.direction;
    let side: Vec<i32> = (0..mesh.triangles.len() as u32)
        .map(|f| {
            let [a, b, c] = mesh.tri(f);
            exact::orient_sign(a, b, c, d)
        })
        .collect();
    if target.faces.iter().any(|&f| side[f as usize] != -1) {
        return None;
    }
    let proj = Projector::new(ray);
    let pt = proj.project(target.point);
    let front: Vec<u32> = (0..mesh.triangles.len() as u32)
        .filter(|&f| side[f as usize] == -1)
        .collect();
    let mut r_max: f64 = 0.0;
    for &f in &front {
        for p in mesh.tri(f) {
            r_max = r_max.max((p.as_dvec3() - ray.origin.as_dvec3()).abs().max_element());
        }
    }
    let mut clearance = f64::INFINITY;
    for ((a, b), faces) in mesh.edge_faces() {
        let n_front = faces.iter().filter(|&&f| side[f as usize] == -1).count();
        if n_front == 1 {
            let pa = proj.project(mesh.positions[a as usize]);
            let pb = proj.project(mesh.positions[b as usize]);
            let ab = pb - pa;
            let t = ((pt - pa).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
            clearance = clearance.min((pa + ab * t - pt).length());
        }
    }
    (clearance >= CLEARANCE_IN_U * U32 * r_max).then_some(front)
}

/// The frontend's 8-wide BVH over `mesh` (default build options).
fn wide_bvh(mesh: &Mesh) -> halfray::accel::VecBvh8 {
    let tris = halfray_core::mesh::TriangleMesh::new(&mesh.positions, &mesh.triangles);
    let options = halfray_core::bvh::wide::binary_options(Default::default());
    let binary = halfray::accel::build_binary(&tris, &options).expect("binary BVH");
    halfray::accel::build_wide(&tris, &binary).expect("wide BVH")
}

/// Leaks at non-power-of-two scales and offsets, by the triangles alone and through the BVH
/// (`closest_simd`: the box test's padding and the traversal's culling must not lose the
/// front face at the target).
#[test]
fn translated_solids_camera_at_world_origin() {
    // Power-of-two and other scales and offsets (issue 17: leaks at non-power-of-two sizes).
    // Cases that yield no counted ray: the unit tetrahedron and octahedron at 1e6, where the
    // clearance `classify` and `front_layer` require (a multiple of u·R, R ≈ 1e6: about one
    // unit) is as large as these solids, so no ray counts as robustly transversal. Any other
    // empty case fails: a configuration that silently stops testing anything.
    let mut empty = Vec::new();
    for offset in [1.0e5f32, 123_456.7, 1.0e6] {
        let mut front_total = Tally::default();
        let mut incident_total = Tally::default();
        for (mi, name) in ["tetrahedron.obj", "cube.obj", "octahedron.obj"]
            .into_iter()
            .enumerate()
        {
            for scale in [1.0f32, 16.0, 64.0, 3.0, 10.0] {
                let shift = Vec3::new(offset, 0.5 * offset, -0.75 * offset);
                let mesh = Mesh::load(name).map(|p| p * scale + shift);
                let wide = wide_bvh(&mesh);
                let mut rng = Rng::new(1000 + mi as u64 * 7 + (scale * 10.0) as u64);
                let edges = mesh.edge_faces();
                let vfaces = mesh.vertex_faces();
                let (mut n, mut attempts) = (0, 0);
                while n < 2_500 && attempts < 20_000 {
                    attempts += 1;
                    let edge = rng.chance(0.5);
                    let target = if edge {
                        let (e, faces) = &edges[rng.below(edges.len())];
                        match edge_target(&mesh, *e, faces, &mut rng, 6, 8) {
                            Some(t) => t,
                            None => continue,
                        }
                    } else {
                        vertex_target(&mesh, &vfaces, rng.below(mesh.positions.len()) as u32)
                            .unwrap()
                    };
                    let guess = Vec3::new(
                        rng.f32_in(-2.0, 2.0),
                        rng.f32_in(-2.0, 2.0),
                        rng.f32_in(-2.0, 2.0),
                    );
                    let Some(ray) = aim_exact(target.point, guess, 64.0) else {
                        continue;
                    };
                    assert!(ray.origin.abs().max_element() <= 66.0);
                    let Some(front) = front_layer(&mesh, &target, &ray) else {
                        front_total.skipped += 1;
                        continue;
                    };
                    n += 1;
                    let front_target = Target {
                        kind: target.kind,
                        point: target.point,
                        faces: front,
                    };
                    let mut scratch = Tally::default();
                    scratch.test_incident(&mesh, &front_target, &ray);
                    // Through the BVH, as a user traces (the default SIMD level): the ray
                    // enters the convex solid through the front layer at the target.
                    let tris =
                        halfray_core::mesh::TriangleMesh::new(&mesh.positions, &mesh.triangles);
                    let hit = halfray::accel::closest_simd(&wide, &tris, &Watertight, &ray, None);
                    let entered = hit.is_some_and(|(f, h)| {
                        front_target.faces.contains(&f)
                            && (f64::from(h.t) - 1.0).abs() <= t_tolerance(&mesh.tri(f), &ray)
                    });
                    if !entered {
                        scratch.fail(format!(
                            "BVH closest hit {hit:?} is not a front face at t = 1: {:?} at {:?}, ray {ray:?}",
                            target.kind, target.point
                        ));
                    }
                    front_total.add(&scratch);
                    if classify(&mesh, &target, &ray).is_some() {
                        incident_total.test_incident(&mesh, &target, &ray);
                    } else {
                        incident_total.skipped += 1;
                    }
                }
                eprintln!("TRANSLATED mesh={name} scale={scale} offset={offset:e} rays={n}");
                if n == 0 {
                    empty.push((name, scale, offset));
                }
            }
        }
        assert!(
            front_total.rays() >= 5_000,
            "offset {offset}: only {} rays",
            front_total.rays()
        );
        let set = format!("translated-{offset:e}-front-layer");
        front_total.print(&set);
        let iset = format!("translated-{offset:e}-incident");
        incident_total.print(&iset);
        assert!(incident_total.rays() > 0, "{iset}: no robust incident rays");
        front_total.assert_watertight(&set);
        incident_total.assert_watertight(&iset);
    }
    assert_eq!(
        empty,
        [
            ("tetrahedron.obj", 1.0, 1.0e6),
            ("octahedron.obj", 1.0, 1.0e6)
        ],
        "cases without a counted ray"
    );
}
