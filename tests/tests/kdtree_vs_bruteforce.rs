//! The kd-tree against brute force over every triangle.
//!
//! The oracle is a plain loop over all triangles with the same intersector and the tie rule
//! (smallest `t`, then smallest index); it shares no code with the tree. The kd-tree's closest
//! hit must equal it exactly (same triangle, same hit record) for the watertight test, and its
//! any-hit must agree on hit/miss, on:
//! * random soups with degenerate triangles (proptest, quantized coordinates so that shared
//!   vertices, coincident and coplanar triangles occur), rays aimed at vertices and edges;
//! * coincident triangles, zero-area triangles, axis-aligned flat meshes (rays in their plane
//!   and through their shared edges and vertices), rays lying in the tree's split planes;
//! * the exact solids with rays through every vertex and edge point;
//! * the bunny on a sample of incoherent and camera rays (figures printed).

use glam::Vec3;
use halfray::obj::read_obj;
use halfray::raysets::{Camera, random_rays};
use halfray_core::Ray;
use halfray_core::kdtree::{
    KdBuildOptions, KdNode, KdNodeKind, KdRef, KdTree, MAX_DEPTH, node_capacity, reference_capacity,
};
use halfray_core::mesh::{PrimitiveSource, TriangleMesh};
use halfray_core::prelude::*;
use halfray_core::solids::grid_triangles;
use halfray_core::triangle::{MollerTrumbore, TriangleIntersector, Watertight, WatertightF32};
use halfray_tests::{
    any_by, brute_triangles as brute, closest_by, meshes_dir, par_map,
    vertex_and_eighth_edge_points,
};
use proptest::prelude::*;

/// Incoherent rays on the bunny (each tested against all 69 451 triangles by the oracle).
const BUNNY_RANDOM_RAYS: usize = 1500;
/// Camera side on the bunny.
const BUNNY_CAMERA_SIDE: usize = 24;

type VecKd = KdTree<Vec<KdNode>, Vec<u32>>;

fn build_opts(mesh: &TriangleMesh<'_>, opts: &KdBuildOptions) -> VecKd {
    let n = mesh.primitive_count();
    let mut scratch = vec![KdRef::EMPTY; reference_capacity(n)];
    KdTree::build(
        mesh,
        vec![KdNode::EMPTY; node_capacity(n).max(1)],
        vec![0u32; reference_capacity(n)],
        &mut scratch,
        opts,
    )
    .unwrap()
}

fn build(mesh: &TriangleMesh<'_>) -> VecKd {
    build_opts(mesh, &KdBuildOptions::default())
}

/// Asserts the kd-tree's closest hit equals the oracle's and any-hit agrees; returns whether
/// the ray hit.
fn check<T: TriangleIntersector>(
    kd: &VecKd,
    mesh: &TriangleMesh<'_>,
    isect: &T,
    ray: &Ray,
) -> bool {
    let want = brute(mesh, isect, ray);
    let got = closest_by(kd, mesh, isect, ray, None);
    assert_eq!(
        got,
        want,
        "{}: closest hit differs for {ray:?}",
        isect.name()
    );
    let any = any_by(kd, mesh, isect, ray);
    assert_eq!(
        any.is_some(),
        want.is_some(),
        "{}: any-hit {any:?} vs {want:?} for {ray:?}",
        isect.name()
    );
    if let Some((p, h)) = any {
        let v = mesh.triangle(p as usize).unwrap();
        assert_eq!(isect.intersect(ray, &v), Some(h), "any-hit record");
    }
    want.is_some()
}

/// Rays lying in every split plane of `kd` (both zero signs), and rays aimed at points of
/// those planes, from origins drawn by `pick`.
fn split_plane_rays(kd: &VecKd, pick: &mut impl FnMut() -> Vec3) -> Vec<Ray> {
    let mut rays = Vec::new();
    for node in kd.nodes() {
        if let KdNodeKind::Inner { axis, position, .. } = node.kind() {
            let mut o = pick();
            o[axis] = position;
            let mut d = pick() - pick();
            for zero in [0.0f32, -0.0] {
                d[axis] = zero;
                if d != Vec3::ZERO {
                    rays.push(Ray::new(o, d));
                }
            }
            let mut target = pick();
            target[axis] = position;
            let o = pick();
            rays.push(Ray::new(o, target - o));
        }
    }
    rays
}

fn load(name: &str) -> halfray::obj::ObjMesh {
    let path = meshes_dir().join(name);
    read_obj(&path).unwrap_or_else(|e| panic!("{name} is required by this test: {e}"))
}

/// A ray aimed from `origin/4` at `p_a + s/8·(p_b − p_a)`: `(a, b, s, origin)`.
type Aim = (u8, u8, u8, [i8; 3]);

/// A quantized triangle soup: vertices on the grid of quarters in `[-4, 4]³`, some triangles
/// sharing vertices, duplicated, reversed, zero-area or flat on an axis plane.
fn soup() -> impl Strategy<Value = (Vec<Vec3>, Vec<[u32; 3]>, Vec<Aim>)> {
    let coord = (-16i8..=16).prop_map(|q| f32::from(q) * 0.25);
    let vertex = (coord.clone(), coord.clone(), coord).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    (proptest::collection::vec(vertex, 3..24), 1usize..40).prop_flat_map(|(pos, nt)| {
        let nv = pos.len() as u32;
        let tri = (0..nv, 0..nv, 0..nv).prop_map(|(a, b, c)| [a, b, c]);
        let aim = (
            any::<u8>(),
            any::<u8>(),
            0u8..9,
            [-24i8..24, -24i8..24, -24i8..24],
        );
        (
            Just(pos),
            proptest::collection::vec(tri, nt),
            proptest::collection::vec(aim, 1..24),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Random quantized soups: kd-tree = brute force for the watertight tests, on aimed rays,
    /// axis-parallel rays and rays in the split planes; a build with a reference budget of one
    /// per triangle (no duplication) and a depth limit of 2 answers the same.
    #[test]
    fn random_soups_equal_brute_force((pos, mut tris, aims) in soup()) {
        // Make some triangles flat on an axis plane and some exact duplicates.
        if tris.len() > 3 {
            let t = tris[0];
            tris.push(t);
            tris.push([t[2], t[1], t[0]]);
            tris.push([t[0], t[0], t[1]]);
        }
        let mesh = TriangleMesh::new(&pos, &tris);
        let trees = [
            build(&mesh),
            build_opts(&mesh, &KdBuildOptions { max_depth: 2, ..KdBuildOptions::default() }),
            {
                let n = mesh.len();
                let mut scratch = vec![KdRef::EMPTY; n];
                KdTree::build(&mesh, vec![KdNode::EMPTY; 64], vec![0; n], &mut scratch,
                    &KdBuildOptions::default()).unwrap()
            },
        ];
        let mut rays = Vec::new();
        for &(a, b, s, o) in &aims {
            let o = Vec3::new(f32::from(o[0]), f32::from(o[1]), f32::from(o[2])) * 0.25;
            let pa = pos[usize::from(a) % pos.len()];
            let pb = pos[usize::from(b) % pos.len()];
            let target = pa + (pb - pa) * (f32::from(s) / 8.0);
            if target != o {
                rays.push(Ray::new(o, target - o));
            }
            for axis in 0..3 {
                for sign in [1.0f32, -1.0] {
                    let mut d = Vec3::new(0.0, -0.0, 0.0);
                    d[axis] = sign;
                    rays.push(Ray::new(o, d));
                }
            }
        }
        let mut k = 0usize;
        let mut pick = || {
            k += 1;
            pos[(k * 7) % pos.len()] + Vec3::new(0.125, -0.375, 0.25) * (k % 5) as f32
        };
        rays.extend(split_plane_rays(&trees[0], &mut pick));
        for kd in &trees {
            prop_assert!(kd.depth() <= MAX_DEPTH);
            for ray in &rays {
                check(kd, &mesh, &Watertight, ray);
                check(kd, &mesh, &WatertightF32, ray);
            }
        }
    }
}

/// Coincident triangles (many copies of one, in shuffled index order) tie to the smallest
/// index; zero-area triangles never hit.
#[test]
fn coincident_and_zero_area_triangles() {
    let mut pos = vec![
        Vec3::ZERO,
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
    ];
    pos.extend([Vec3::ONE, Vec3::new(3.0, 3.0, 3.0)]);
    let mut tris = Vec::new();
    for k in 0..200u32 {
        tris.push(match k % 4 {
            0 => [0, 1, 2],
            1 => [2, 1, 0],
            2 => [3, 3, 4],
            _ => [3, 4, 3],
        });
    }
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    let mut hits = 0;
    for i in 0..40 {
        let x = i as f32 * 0.05;
        for ray in [
            Ray::new(Vec3::new(x, 0.3, 4.0), -Vec3::Z),
            Ray::new(Vec3::new(x, 0.3, -4.0), Vec3::Z),
            Ray::new(Vec3::new(-1.0, x, 1.0), Vec3::new(1.0, 0.0, 0.0)),
            Ray::new(
                Vec3::new(x, x, 5.0),
                Vec3::new(1.0, 1.0, 1.0) - Vec3::new(x, x, 5.0),
            ),
        ] {
            hits += usize::from(check(&kd, &mesh, &Watertight, &ray));
        }
    }
    assert!(hits >= 40, "{hits}");
    let ray = Ray::new(Vec3::new(0.5, 0.5, 4.0), -Vec3::Z);
    assert_eq!(
        closest_by(&kd, &mesh, &Watertight, &ray, None).map(|h| h.0),
        Some(0)
    );
}

/// Axis-aligned flat meshes: three grids, one in each axis plane, sharing the origin, with
/// rays lying in each plane, through every shared vertex and edge midpoint, and in the
/// tree's split planes.
#[test]
fn axis_aligned_flat_meshes() {
    let side = 10u32;
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for axis in 0..3 {
        let base = pos.len() as u32;
        for j in 0..=side {
            for i in 0..=side {
                let mut p = Vec3::ZERO;
                p[(axis + 1) % 3] = i as f32 * 0.5;
                p[(axis + 2) % 3] = j as f32 * 0.5;
                pos.push(p);
            }
        }
        tris.extend(grid_triangles(side, side).map(|t| t.map(|v| base + v)));
    }
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    let mut rays = Vec::new();
    let o = Vec3::new(7.25, 6.5, 8.75);
    for t in &tris {
        let v = t.map(|i| pos[i as usize]);
        for target in [
            v[0],
            (v[0] + v[1]) * 0.5,
            (v[1] + v[2]) * 0.5,
            (v[0] + v[1] + v[2]) / 3.0,
        ] {
            rays.push(Ray::new(o, target - o));
            rays.push(Ray::new(-o, target + o));
        }
    }
    // In the planes of the grids, along and across their lines.
    for axis in 0..3 {
        for k in 0..=side {
            let mut origin = Vec3::splat(-1.0);
            origin[axis] = 0.0;
            origin[(axis + 1) % 3] = k as f32 * 0.5;
            let mut d = Vec3::ZERO;
            d[(axis + 2) % 3] = 1.0;
            rays.push(Ray::new(origin, d));
            d[(axis + 1) % 3] = 0.25;
            rays.push(Ray::new(origin, d));
        }
    }
    let mut k = 0u32;
    let mut pick = || {
        k = k.wrapping_mul(1_103_515_245).wrapping_add(12_345);
        Vec3::new(
            (k % 97) as f32,
            (k / 97 % 89) as f32,
            (k / 8633 % 83) as f32,
        ) * 0.0625
    };
    rays.extend(split_plane_rays(&kd, &mut pick));
    assert!(rays.len() > 2000, "{}", rays.len());
    let hits: usize = rays
        .iter()
        .map(|r| usize::from(check(&kd, &mesh, &Watertight, r)))
        .sum();
    assert!(hits > rays.len() / 2, "{hits} of {}", rays.len());
}

/// The exact solids: rays through every vertex and through edge points `a + k/8·(b − a)`
/// (exactly representable), entering the closed solid there: the kd-tree finds what brute
/// force finds, and brute force finds a hit (no leak).
#[test]
fn exact_vertex_and_edge_rays_on_the_exact_solids() {
    for name in ["tetrahedron.obj", "cube.obj", "octahedron.obj"] {
        let obj = load(name);
        let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
        let kd = build(&mesh);
        let targets = vertex_and_eighth_edge_points(&obj.positions, &obj.triangles);
        for p in targets {
            for jitter in [Vec3::ZERO, Vec3::new(0.125, -0.25, 0.0625)] {
                let o = p * 3.0 + jitter;
                let ray = Ray::new(o, p - o);
                assert!(
                    check(&kd, &mesh, &Watertight, &ray),
                    "{name}: leak at {p:?}"
                );
            }
        }
    }
}

/// The bunny: the default build, a sample of incoherent and camera rays; figures printed.
#[test]
fn bunny_equals_brute_force_on_a_sample_of_rays() {
    let obj = load("bunny.obj");
    let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
    let n = mesh.len();
    let kd = build(&mesh);
    let (leaves, empty) = kd.leaf_counts();
    eprintln!(
        "bunny: {n} triangles, {} nodes ({leaves} leaves, {empty} empty), {} references \
         ({:.2} per triangle), depth {}, {} bytes ({:.1} per triangle), budget exhausted: {}",
        kd.node_count(),
        kd.reference_count(),
        kd.reference_count() as f64 / n as f64,
        kd.depth(),
        kd.bytes_used(),
        kd.bytes_used() as f64 / n as f64,
        kd.budget_exhausted()
    );
    assert!(!kd.budget_exhausted());
    assert_eq!(kd.primitive_count(), n);
    assert!(kd.reference_count() >= n);
    let (lo, hi) = obj.bounds().unwrap();
    let mut rays = random_rays(lo, hi, BUNNY_RANDOM_RAYS, 0x4D7E);
    rays.extend(Camera::framing(lo, hi, BUNNY_CAMERA_SIDE, BUNNY_CAMERA_SIDE).rays());
    let hits: usize = par_map(&rays, |r| usize::from(check(&kd, &mesh, &Watertight, r)))
        .into_iter()
        .sum();
    assert!(hits > rays.len() / 10, "only {hits} hits");
    // Möller–Trumbore through the tree: its hits are genuine and never nearer than brute
    // force's (its inexact edges may report a hit just outside a triangle's box).
    for ray in rays.iter().take(300) {
        let got = closest_by(&kd, &mesh, &MollerTrumbore::CLASSIC, ray, None);
        let want = brute(&mesh, &MollerTrumbore::CLASSIC, ray);
        if let Some((p, h)) = got {
            let v = mesh.triangle(p as usize).unwrap();
            assert_eq!(MollerTrumbore::CLASSIC.intersect(ray, &v), Some(h));
            assert!(want.expect("brute force finds it").1.t <= h.t);
        }
    }
}

/// Huge (1e20) and tiny (1e-20) copies of a random soup: exact agreement at every scale.
#[test]
fn huge_and_tiny_scenes() {
    let mut k = 1u64;
    let mut f = || {
        k = k
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((k >> 40) as f32) / (1u64 << 24) as f32 - 0.5
    };
    let mut base = Vec::new();
    for _ in 0..150 {
        let c = Vec3::new(f(), f(), f()) * 10.0;
        for _ in 0..3 {
            base.push(c + Vec3::new(f(), f(), f()) * 2.0);
        }
    }
    let tris: Vec<[u32; 3]> = (0..150u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    let dirs: Vec<(Vec3, Vec3)> = (0..400)
        .map(|_| (Vec3::new(f(), f(), f()) * 30.0, Vec3::new(f(), f(), f())))
        .collect();
    for scale in [1.0e20f32, 1.0e-20] {
        let pos: Vec<Vec3> = base.iter().map(|p| *p * scale).collect();
        let mesh = TriangleMesh::new(&pos, &tris);
        let kd = build(&mesh);
        let mut hits = 0;
        for (k, &(o, d)) in dirs.iter().enumerate() {
            let o = o * scale;
            hits += usize::from(check(&kd, &mesh, &Watertight, &Ray::new(o, d)));
            let target = pos[(k * 7) % pos.len()];
            hits += usize::from(check(&kd, &mesh, &Watertight, &Ray::new(o, target - o)));
        }
        assert!(hits > 20, "scale {scale}: {hits}");
    }
}
