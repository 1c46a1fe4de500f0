//! The BVH against brute force over every primitive.
//!
//! * Every shared mesh: 100 000 incoherent rays and all primary rays of a 256×256 camera (the
//!   871k-triangle dragon on a sample of [`DRAGON_RANDOM_RAYS`] and a [`DRAGON_CAMERA_SIDE`]²
//!   camera, all of them with `HALFRAY_SLOW_TESTS=1`). Both trees (the binary `Bvh` and the
//!   8-wide tree at the SIMD level the frontend picks for this CPU) must report the same `t`
//!   as brute force, and the same triangle (or a different one reporting that same `t`);
//!   any-hit must agree with closest-hit on hit/miss.
//! * Edge and vertex rays on the closed meshes: no leaks through the BVH.
//! * Property tests on random small soups with degenerate triangles.
//! * The hangar/drone clearance query.
//!
//! Brute force over 10⁵ triangles × 1.6·10⁵ rays is too slow for CI as a plain loop, so the
//! reference loop skips triangles with a **conservative cylinder cull** that has nothing to do
//! with the BVH: a triangle is tested only if its bounding sphere (padded by
//! [`CULL_PAD_REL`] of the mesh diagonal) comes near the ray's line. The cull is checked
//! against the plain loop in `brute_force_cull_is_conservative`.

use glam::{DVec3, Vec3};
use halfray::obj::{ObjMesh, read_obj};
use halfray::raysets::{Camera, Rng, random_rays};
use halfray_core::Ray;
use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, MAX_DEPTH, index_capacity, node_capacity};
use halfray_core::float::F32_UNIT_ROUNDOFF;
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{TraversalStats, Triangles};
use halfray_core::tolerance::T_REL_TOLERANCE_WELL_CONDITIONED;
use halfray_core::triangle::{TriangleIntersector, TriangleVariant, Watertight};
use halfray_tests::{any_by, closest_by, meshes_dir, par_map, vertex_and_eighth_edge_points};
use proptest::prelude::*;
use std::collections::HashMap;
use std::path::PathBuf;

const RANDOM_RAYS: usize = 100_000;
const CAMERA_SIDE: usize = 256;
/// Incoherent rays on the dragon in a plain run: the reference loop's cull still touches all
/// 871k spheres per ray, so CI checks a sample (every ray with `HALFRAY_SLOW_TESTS=1`).
const DRAGON_RANDOM_RAYS: usize = 4_000;
/// Camera side on the dragon in a plain run.
const DRAGON_CAMERA_SIDE: usize = 48;

/// Padding of the reference loop's bounding spheres, relative to the mesh diagonal. `f32`
/// rounding in the cull is about `10·2⁻²⁴·|c − o|²·|d|²` on a squared distance; with origins
/// within 3 diagonals that needs a pad above `2.3·10⁻³` of the diagonal: `10⁻²` is 4× that.
const CULL_PAD_REL: f32 = 1.0e-2;

type VecBvh = Bvh<Vec<BvhNode>, Vec<u32>>;

fn slow_tests() -> bool {
    std::env::var("HALFRAY_SLOW_TESTS").is_ok_and(|v| v == "1")
}

fn mesh_paths() -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(meshes_dir())
        .expect("shared meshes folder")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 10, "{paths:?}");
    assert!(paths.iter().any(|p| p.ends_with("dragon.obj")), "{paths:?}");
    paths
}

fn load(name: &str) -> ObjMesh {
    read_obj(&meshes_dir().join(name)).unwrap()
}

fn build(mesh: &TriangleMesh<'_>, leaf: u32) -> VecBvh {
    let n = mesh.len();
    Bvh::build(
        mesh,
        vec![BvhNode::EMPTY; node_capacity(n) + 1],
        vec![0u32; index_capacity(n)],
        &BuildOptions {
            max_leaf_size: leaf,
            ..BuildOptions::default()
        },
    )
    .unwrap()
}

/// Triangles as bounding spheres in structure-of-arrays form, for the reference loop's cull.
struct Spheres {
    cx: Vec<f32>,
    cy: Vec<f32>,
    cz: Vec<f32>,
    r2: Vec<f32>,
}

impl Spheres {
    fn new(mesh: &TriangleMesh<'_>) -> Self {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for p in mesh.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let pad = f64::from(CULL_PAD_REL * (hi - lo).length());
        let mut s = Self {
            cx: vec![],
            cy: vec![],
            cz: vec![],
            r2: vec![],
        };
        for i in 0..mesh.len() {
            let v = mesh.triangle(i).unwrap().map(|p| p.as_dvec3());
            let c = (v[0] + v[1] + v[2]) / 3.0;
            let r = v.iter().map(|p| (*p - c).length()).fold(0.0, f64::max) + pad;
            s.cx.push(c.x as f32);
            s.cy.push(c.y as f32);
            s.cz.push(c.z as f32);
            s.r2.push((r * r) as f32);
        }
        s
    }
}

/// Closest hit over every triangle with the BVH's tie rule (smaller `t`, then smaller index),
/// skipping triangles whose padded bounding sphere misses the ray's line when `cull` is given.
fn brute<T: TriangleIntersector>(
    mesh: &TriangleMesh<'_>,
    cull: Option<&Spheres>,
    isect: &T,
    ray: &Ray,
) -> Option<(u32, f32)> {
    let pre = isect.prepare(ray)?;
    let mut best: Option<(u32, f32)> = None;
    let mut test = |i: usize| {
        if let Some(h) = isect.intersect_prepared(&pre, ray, &mesh.triangle(i).unwrap())
            && best.is_none_or(|(_, t)| h.t < t)
        {
            best = Some((i as u32, h.t));
        }
    };
    match cull {
        None => (0..mesh.len()).for_each(test),
        Some(s) => {
            let (o, d) = (ray.origin, ray.direction);
            let dd = d.length_squared();
            for i in 0..s.cx.len() {
                let oc = Vec3::new(s.cx[i] - o.x, s.cy[i] - o.y, s.cz[i] - o.z);
                if oc.cross(d).length_squared() <= s.r2[i] * dd {
                    test(i);
                }
            }
        }
    }
    best
}

/// Checks the BVH against the reference on `rays`; returns (hits, different-but-tied prims).
fn check_rays(
    name: &str,
    mesh: &TriangleMesh<'_>,
    bvh: &VecBvh,
    wide: &halfray::accel::VecBvh8,
    spheres: &Spheres,
    rays: &[Ray],
) -> (usize, usize) {
    let results = par_map(rays, |ray| {
        let got = closest_by(bvh, mesh, &Watertight, ray, None).map(|(p, h)| (p, h.t));
        let any = any_by(bvh, mesh, &Watertight, ray);
        let wide_got = halfray::accel::closest_simd(wide, mesh, &Watertight, ray, None);
        let wide_any = halfray::accel::any_simd(wide, mesh, &Watertight, ray);
        let want = brute(mesh, Some(spheres), &Watertight, ray);
        let wide_got = wide_got.map(|(p, h)| (p, h.t));
        (got, any.is_some(), wide_got, wide_any.is_some(), want)
    });
    let (mut hits, mut tied) = (0, 0);
    for (ray, (got, any, wide_got, wide_any, want)) in rays.iter().zip(results) {
        assert_eq!(any, got.is_some(), "{name}: any-hit vs closest {ray:?}");
        // The wide tree has the brute-force tie rule exactly (smaller index at equal `t`).
        assert_eq!(wide_got, want, "{name}: wide tree vs brute force {ray:?}");
        assert_eq!(wide_any, want.is_some(), "{name}: wide any-hit {ray:?}");
        match (got, want) {
            (None, None) => {}
            (Some((gp, gt)), Some((wp, wt))) => {
                hits += 1;
                assert_eq!(gt, wt, "{name}: t differs (prims {gp} vs {wp}) {ray:?}");
                if gp != wp {
                    let t_of_gp = Watertight.intersect(ray, &mesh.triangle(gp as usize).unwrap());
                    assert_eq!(t_of_gp.map(|h| h.t), Some(wt), "{name}: {ray:?}");
                    tied += 1;
                }
            }
            _ => panic!("{name}: BVH {got:?} vs brute force {want:?} for {ray:?}"),
        }
    }
    (hits, tied)
}

#[test]
fn closest_and_any_hit_equal_brute_force_on_every_mesh() {
    for path in mesh_paths() {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let obj = read_obj(&path).unwrap();
        let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
        let bvh = build(&mesh, 4);
        let stats = bvh.stats();
        assert!(stats.max_depth <= MAX_DEPTH);
        assert!(bvh.node_count() <= node_capacity(mesh.len()) + 1);
        let wide = halfray::accel::build_wide(&mesh, &bvh).unwrap();
        let spheres = Spheres::new(&mesh);
        let (lo, hi) = obj.bounds().unwrap();
        let (n_random, side) = if name == "dragon.obj" && !slow_tests() {
            halfray::skips::record_skip(&format!(
                "bvh_vs_bruteforce: dragon.obj sampled ({DRAGON_RANDOM_RAYS} random rays and a \
                 {DRAGON_CAMERA_SIDE}² camera, not {RANDOM_RAYS} and {CAMERA_SIDE}²; \
                 HALFRAY_SLOW_TESTS=1 for all)"
            ));
            (DRAGON_RANDOM_RAYS, DRAGON_CAMERA_SIDE)
        } else {
            (RANDOM_RAYS, CAMERA_SIDE)
        };
        let mut rays = random_rays(lo, hi, n_random, 0x7E57);
        rays.extend(Camera::framing(lo, hi, side, side).rays());
        assert!(rays.len() >= n_random + side * side);
        let (hits, tied) = check_rays(&name, &mesh, &bvh, &wide, &spheres, &rays);
        eprintln!(
            "{name}: {} rays, {hits} hits, {tied} ties resolved to another triangle at equal t",
            rays.len()
        );
        assert!(hits > rays.len() / 20, "{name}: only {hits} hits");
    }
}

#[test]
fn brute_force_cull_is_conservative() {
    for name in ["bunny.obj", "beetle.obj", "teapot.obj", "cube.obj"] {
        let obj = load(name);
        let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
        let spheres = Spheres::new(&mesh);
        let (lo, hi) = obj.bounds().unwrap();
        let mut rays = random_rays(lo, hi, 1500, 0xC011);
        rays.extend(Camera::framing(lo, hi, 24, 24).rays());
        let diff = par_map(&rays, |r| {
            (brute(&mesh, None, &Watertight, r) != brute(&mesh, Some(&spheres), &Watertight, r))
                as usize
        });
        assert_eq!(diff.iter().sum::<usize>(), 0, "{name}");
    }
}

#[test]
fn every_intersector_variant_works_through_the_bvh() {
    let obj = load("spot.obj");
    let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
    let bvh = build(&mesh, 4);
    let spheres = Spheres::new(&mesh);
    let (lo, hi) = obj.bounds().unwrap();
    let rays = random_rays(lo, hi, 3000, 0xA11);
    fn check<T: TriangleIntersector>(
        isect: &T,
        mesh: &TriangleMesh<'_>,
        bvh: &VecBvh,
        spheres: &Spheres,
        rays: &[Ray],
    ) {
        for ray in rays {
            let got = closest_by(bvh, mesh, isect, ray, None).map(|(_, h)| h.t);
            let want = brute(mesh, Some(spheres), isect, ray).map(|(_, t)| t);
            assert_eq!(got, want, "{} {ray:?}", isect.name());
            let any = any_by(bvh, mesh, isect, ray).is_some();
            assert_eq!(any, got.is_some(), "{}", isect.name());
        }
    }
    struct Check<'a>(&'a TriangleMesh<'a>, &'a VecBvh, &'a Spheres, &'a [Ray]);
    impl halfray_core::triangle::VariantVisitor for Check<'_> {
        type Output = ();
        fn visit<I: TriangleIntersector>(self, isect: &I) {
            check(isect, self.0, self.1, self.2, self.3)
        }
    }
    for v in TriangleVariant::ALL {
        v.visit(Check(&mesh, &bvh, &spheres, &rays));
    }
}

/// Area-weighted vertex normals (sum of unnormalised face normals), in `f64`.
fn vertex_normals(obj: &ObjMesh) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; obj.positions.len()];
    for t in &obj.triangles {
        let v = t.map(|i| obj.positions[i as usize].as_dvec3());
        let f = (v[1] - v[0]).cross(v[2] - v[0]);
        for &i in t {
            n[i as usize] += f;
        }
    }
    n
}

fn face_normal(obj: &ObjMesh, f: u32) -> DVec3 {
    let v = obj.triangles[f as usize].map(|i| obj.positions[i as usize].as_dvec3());
    (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero()
}

/// How far from 1 the watertight `t` may be for a ray that passes exactly through a point of
/// the surface at `t = 1` (unitless, relative to `t`): 8 ulps of 1. The target is exact, so
/// only the watertight test's own rounding remains (translation, shear and division, each
/// within `gamma(3)` of the coordinates, which here are about `|o − p|`: a few ulps of `t`);
/// the rays measure exactly 1.
const EXACT_TARGET_T_TOL: f32 = 8.0 * f32::EPSILON;

/// Exactly representable rays through vertices and through edge points `a + k/8·(b − a)` of
/// the exact solids (coordinates in {−1, 0, 1}), from `o = 3p + jitter` (dyadic), so the ray
/// passes exactly through `p` at `t = 1` and enters the convex solid there.
#[test]
fn exact_vertex_and_edge_rays_do_not_leak_on_the_exact_solids() {
    for name in ["tetrahedron.obj", "cube.obj", "octahedron.obj"] {
        let obj = load(name);
        let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
        let bvh = build(&mesh, 1);
        let targets = vertex_and_eighth_edge_points(&obj.positions, &obj.triangles);
        let mut rng = Rng::new(0xED6E);
        let mut count = 0;
        for &p in &targets {
            for _ in 0..8 {
                let j = Vec3::new(
                    (rng.below(33) as f32 - 16.0) / 64.0,
                    (rng.below(33) as f32 - 16.0) / 64.0,
                    (rng.below(33) as f32 - 16.0) / 64.0,
                );
                let o = p * 3.0 + j;
                let d = p - o;
                assert_eq!(o + d, p, "exact construction");
                assert_eq!(d.as_dvec3(), p.as_dvec3() - o.as_dvec3(), "exact direction");
                let ray = Ray::new(o, d);
                let (prim, hit) = closest_by(&bvh, &mesh, &Watertight, &ray, None)
                    .unwrap_or_else(|| panic!("{name}: leak at {p:?} from {o:?}"));
                assert!(
                    (hit.t - 1.0).abs() <= EXACT_TARGET_T_TOL,
                    "{name}: t {} at {p:?}",
                    hit.t
                );
                let want = brute(&mesh, None, &Watertight, &ray);
                assert_eq!(Some((prim, hit.t)), want, "{name}: {ray:?}");
                assert!(any_by(&bvh, &mesh, &Watertight, &ray).is_some());
                count += 1;
            }
        }
        assert!(count > 100, "{name}: {count}");
    }
}

/// Rays aimed at every vertex and every edge midpoint of the closed scanned meshes, from
/// outside along the (area-weighted) normal, kept only where they cross every incident face
/// transversally (against each face's outward normal by more than [`TRANSVERSAL_COS`]): the
/// closest hit must exist at `t ≤ 1 + 1e-4` (earlier is another part of the surface) and equal
/// brute force.
#[test]
fn vertex_and_edge_rays_do_not_leak_on_the_closed_meshes() {
    /// Minimum cosine between the reversed ray and each incident face's normal.
    const TRANSVERSAL_COS: f64 = 0.05;
    /// How far past the aimed-at surface point (`t = 1`) the first hit may be (unitless,
    /// relative to `t`). The direction `p − o` is rounded to `f32` (within `u` per component,
    /// so the ray passes within `√3·u·|d|` of `p`) and the watertight test rounds its sheared
    /// coordinates (a few `u` of the coordinates, about `|d|` here); along a ray at cosine
    /// `≥ TRANSVERSAL_COS` to the faces each moves the crossing by that over the cosine: `16·u`
    /// over it (`≈ 1.9e-5`) covers both with margin.
    const PAST_TARGET_T_TOL: f32 = (16.0 * F32_UNIT_ROUNDOFF as f64 / TRANSVERSAL_COS) as f32;
    for name in [
        "tetrahedron.obj",
        "cube.obj",
        "octahedron.obj",
        "spot.obj",
        "torus.obj",
    ] {
        let obj = load(name);
        let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
        let bvh = build(&mesh, 4);
        let spheres = Spheres::new(&mesh);
        let (lo, hi) = obj.bounds().unwrap();
        let h = 0.05 * f64::from((hi - lo).length());
        let normals = vertex_normals(&obj);
        let mut vertex_faces: Vec<Vec<u32>> = vec![vec![]; obj.positions.len()];
        let mut edge_faces: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for (f, t) in obj.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                vertex_faces[a as usize].push(f as u32);
                edge_faces
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push(f as u32);
            }
        }
        let mut aims: Vec<(Vec3, DVec3, Vec<u32>)> = vec![];
        for (v, faces) in vertex_faces.iter().enumerate() {
            aims.push((obj.positions[v], normals[v], faces.clone()));
        }
        let mut edges: Vec<_> = edge_faces.into_iter().collect();
        edges.sort_unstable();
        for ((a, b), faces) in edges {
            assert_eq!(faces.len(), 2, "{name} is closed");
            let p = (obj.positions[a as usize] + obj.positions[b as usize]) * 0.5;
            aims.push((p, normals[a as usize] + normals[b as usize], faces));
        }
        let rays: Vec<Ray> = aims
            .iter()
            .filter_map(|(p, n, faces)| {
                let o = (p.as_dvec3() + n.normalize_or_zero() * h).as_vec3();
                let d = *p - o;
                let dn = d.as_dvec3().normalize_or_zero();
                faces
                    .iter()
                    .all(|&f| dn.dot(face_normal(&obj, f)) < -TRANSVERSAL_COS)
                    .then(|| Ray::new(o, d))
            })
            .collect();
        assert!(
            rays.len() * 10 >= aims.len() * 8,
            "{name}: {} of {}",
            rays.len(),
            aims.len()
        );
        let results = par_map(&rays, |ray| {
            (
                closest_by(&bvh, &mesh, &Watertight, ray, None).map(|(p, h)| (p, h.t)),
                brute(&mesh, Some(&spheres), &Watertight, ray),
            )
        });
        for (ray, (got, want)) in rays.iter().zip(results) {
            let (_, t) = got.unwrap_or_else(|| panic!("{name}: leak {ray:?}"));
            assert!(
                t <= 1.0 + PAST_TARGET_T_TOL,
                "{name}: passed through, t = {t} {ray:?}"
            );
            assert_eq!(got.map(|g| g.1), want.map(|w| w.1), "{name}: {ray:?}");
        }
        eprintln!(
            "{name}: {} transversal edge/vertex rays, 0 leaks",
            rays.len()
        );
    }
}

/// A box mesh `[lo, hi]`, 12 triangles, counter-clockwise seen from outside.
fn box_mesh(lo: Vec3, hi: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = |i: u32| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let positions = (0..8).map(p).collect();
    let quads = [
        [0u32, 2, 3, 1], // z = lo
        [4, 5, 7, 6],    // z = hi
        [0, 1, 5, 4],    // y = lo
        [2, 6, 7, 3],    // y = hi
        [0, 4, 6, 2],    // x = lo
        [1, 3, 7, 5],    // x = hi
    ];
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    (positions, triangles)
}

#[test]
fn drone_in_hangar_clearance_equals_the_wall_distances() {
    let (room_lo, room_hi) = (Vec3::new(-10.0, 0.0, -15.0), Vec3::new(10.0, 8.0, 15.0));
    let (hp, ht) = box_mesh(room_lo, room_hi);
    let hangar = TriangleMesh::new(&hp, &ht);
    let bvh = build(&hangar, 4);
    let (dlo, dhi) = (Vec3::new(1.5, 2.75, -4.5), Vec3::new(2.5, 3.25, -3.5));
    let (dp, dt) = box_mesh(dlo, dhi);
    let obj = ObjMesh {
        positions: dp.clone(),
        triangles: dt,
    };
    // The drone's outward-facing box: check orientation so the normals point outward.
    let normals: Vec<Vec3> = vertex_normals(&obj).iter().map(|n| n.as_vec3()).collect();
    let centre = (dlo + dhi) * 0.5;
    for (p, n) in dp.iter().zip(&normals) {
        assert!(n.dot(*p - centre) > 0.0, "outward normal at {p:?}");
    }
    // Plus the six face centres with axis normals: exact distances.
    let mut points = dp.clone();
    let mut dirs = normals.clone();
    for axis in 0..3 {
        for (side, sign) in [(dlo, -1.0f32), (dhi, 1.0)] {
            let mut p = centre;
            p[axis] = side[axis];
            let mut n = Vec3::ZERO;
            n[axis] = sign * 3.0; // not unit: the distance must still be in world units
            points.push(p);
            dirs.push(n);
        }
    }
    let mut out = vec![0.0f32; points.len()];
    let min = bvh
        .clearance(
            &mut Triangles::new(&hangar, &Watertight),
            &points,
            &dirs,
            &mut out,
        )
        .unwrap();
    // Expected: exit distance of each ray from the room box, in f64.
    let expect: Vec<f64> = points
        .iter()
        .zip(&dirs)
        .map(|(p, n)| {
            let (p, n) = (p.as_dvec3(), n.as_dvec3().normalize());
            (0..3)
                .filter(|&a| n[a] != 0.0)
                .map(|a| {
                    let wall = if n[a] > 0.0 { room_hi[a] } else { room_lo[a] };
                    (f64::from(wall) - p[a]) / n[a]
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    /// Relative tolerance of an exit distance (unitless): the rays meet the walls within 55°
    /// of their normals (the corner normals are `(±1, ±1, ±1)/√3`), so the watertight `t` is
    /// within the core's well-conditioned tolerance; the clearance's `f32` normalisation of
    /// the direction adds a few `u`.
    const EXIT_REL_TOL: f64 =
        T_REL_TOLERANCE_WELL_CONDITIONED as f64 + 4.0 * F32_UNIT_ROUNDOFF as f64;
    for (i, (g, e)) in out.iter().zip(&expect).enumerate() {
        assert!(
            (f64::from(*g) - e).abs() <= EXIT_REL_TOL * e,
            "point {i}: {g} vs {e}"
        );
    }
    // Face centres: exactly the wall gaps (x: 7.5 / 11.5, y: 2.75 floor / 4.75, z: 10.5 / 18.5).
    assert_eq!(&out[8..], &[11.5, 7.5, 2.75, 4.75, 10.5, 18.5]);
    assert_eq!(min, 2.75, "the floor is nearest");
    // Box query: the drone's box overlaps no wall; grown to the floor it touches the floor's
    // two triangles only.
    let drone_box = halfray_core::Aabb::new(dlo, dhi);
    assert_eq!(bvh.query_box(&hangar, &drone_box, |_| true), 0);
    let reaching = halfray_core::Aabb::new(Vec3::new(dlo.x, 0.0, dlo.z), dhi);
    let mut found = vec![];
    bvh.query_box(&hangar, &reaching, |p| {
        found.push(p);
        true
    });
    found.sort_unstable();
    assert_eq!(found, vec![4, 5], "the y = 0 floor");
}

#[test]
fn refit_after_moving_vertices_matches_a_rebuild() {
    let obj = load("spot.obj");
    let mut positions = obj.positions.clone();
    let before = TriangleMesh::new(&positions, &obj.triangles);
    let mut bvh = build(&before, 4);
    let mut wide = halfray::accel::build_wide(&before, &bvh).unwrap();
    // A smoothing-like move: every vertex towards the centroid of its neighbours' box.
    for (i, p) in positions.iter_mut().enumerate() {
        let w = (i % 7) as f32 * 0.01;
        *p += Vec3::new(w, -w * 0.5, w * 0.25);
    }
    let mesh = TriangleMesh::new(&positions, &obj.triangles);
    bvh.refit(&mesh).unwrap();
    wide.refit(&mesh).unwrap();
    let spheres = Spheres::new(&mesh);
    let (lo, hi) = obj.bounds().unwrap();
    let rays = random_rays(lo, hi, 20_000, 0x5EF1);
    check_rays("spot refit", &mesh, &bvh, &wide, &spheres, &rays);
}

#[test]
fn stats_count_visits_and_nan_rays_stop_at_once() {
    let obj = load("bunny.obj");
    let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
    let bvh = build(&mesh, 4);
    let s = bvh.stats();
    assert!(bvh.bytes_per_triangle() < 68.0, "{s:?}");
    let (lo, hi) = obj.bounds().unwrap();
    let mut st = TraversalStats::default();
    let rays = random_rays(lo, hi, 1000, 1);
    for r in &rays {
        let _ = closest_by(&bvh, &mesh, &Watertight, r, &mut st);
    }
    assert!(
        st.nodes_visited >= 1000 && st.primitives_tested > 0,
        "{st:?}"
    );
    assert!(
        st.primitives_tested < 1000 * 100,
        "the BVH culls: {st:?} for {} triangles",
        mesh.len()
    );
    let mut st = TraversalStats::default();
    let nan = Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X);
    assert!(closest_by(&bvh, &mesh, &Watertight, &nan, &mut st).is_none());
    assert!(st.nodes_visited <= 1);
}

fn grid_coord() -> impl Strategy<Value = f32> {
    // A coarse grid makes coincident, collinear and zero-area triangles common.
    prop_oneof![
        4 => (-3i32..=3).prop_map(|i| i as f32),
        1 => (-300i32..=300).prop_map(|i| i as f32 / 97.0),
    ]
}

fn grid_vec() -> impl Strategy<Value = Vec3> {
    (grid_coord(), grid_coord(), grid_coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn soups_match_brute_force(
        positions in prop::collection::vec(grid_vec(), 1..24),
        raw_tris in prop::collection::vec((0u32..64, 0u32..64, 0u32..64), 0..40),
        rays in prop::collection::vec((grid_vec(), grid_vec(), 0u8..4), 1..40),
        leaf in 1u32..6,
    ) {
        let n = positions.len() as u32;
        let tris: Vec<[u32; 3]> = raw_tris.iter().map(|&(a, b, c)| [a % n, b % n, c % n]).collect();
        let mesh = TriangleMesh::new(&positions, &tris);
        let bvh = build(&mesh, leaf);
        prop_assert!(bvh.stats().max_depth <= MAX_DEPTH);
        for &(o, target, kind) in &rays {
            let d = match kind {
                0 => target - o,
                1 => Vec3::new(target.x, 0.0, 0.0),
                2 => Vec3::new(-0.0, target.y, target.z),
                _ => target,
            };
            let ray = Ray::with_interval(o, d, 0.0, if kind == 3 { 2.0 } else { f32::INFINITY });
            let got = closest_by(&bvh, &mesh, &Watertight, &ray, None).map(|(p, h)| (p, h.t));
            prop_assert_eq!(got, brute(&mesh, None, &Watertight, &ray), "{:?}", ray);
            let any = any_by(&bvh, &mesh, &Watertight, &ray);
            prop_assert_eq!(any.is_some(), got.is_some());
        }
    }

    #[test]
    fn soups_with_non_finite_vertices_are_rejected_or_excluded(
        positions in prop::collection::vec(grid_vec(), 3..16),
        raw_tris in prop::collection::vec((0u32..64, 0u32..64, 0u32..64), 1..30),
        bad in 0usize..16,
        value in prop_oneof![Just(f32::NAN), Just(f32::INFINITY), Just(f32::NEG_INFINITY)],
        rays in prop::collection::vec((grid_vec(), grid_vec()), 1..20),
    ) {
        let mut positions = positions;
        let n = positions.len();
        let bad = bad % n;
        positions[bad].y = value;
        let tris: Vec<[u32; 3]> = raw_tris
            .iter()
            .map(|&(a, b, c)| [a % n as u32, b % n as u32, c % n as u32])
            .collect();
        let mesh = TriangleMesh::new(&positions, &tris);
        let first_bad = tris.iter().position(|t| t.contains(&(bad as u32)));
        let strict = Bvh::build(
            &mesh,
            vec![BvhNode::EMPTY; node_capacity(tris.len())],
            vec![0u32; tris.len()],
            &BuildOptions::default(),
        );
        match first_bad {
            Some(i) => prop_assert_eq!(
                strict.unwrap_err(),
                halfray_core::bvh::BvhError::NonFinite(halfray_core::error::NonFiniteError { element: halfray_core::error::InputElement::Primitive, index: i })
            ),
            None => prop_assert!(strict.is_ok()),
        }
        let bvh = Bvh::build(
            &mesh,
            vec![BvhNode::EMPTY; node_capacity(tris.len())],
            vec![0u32; tris.len()],
            &BuildOptions { exclude_non_finite: true, ..BuildOptions::default() },
        )
        .unwrap();
        prop_assert!(bvh.bounds().is_finite() || bvh.is_empty());
        for &(o, t) in &rays {
            let ray = Ray::new(o, t - o);
            let got = closest_by(&bvh, &mesh, &Watertight, &ray, None).map(|(p, h)| (p, h.t));
            prop_assert_eq!(got, brute(&mesh, None, &Watertight, &ray));
        }
    }
}
