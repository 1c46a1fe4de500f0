//! The uniform grid against brute force over every triangle.
//!
//! * Random soups and degenerate scenes (coincident, duplicated and zero-area triangles,
//!   axis-aligned flat meshes, rays along grid planes, rays through shared edges and
//!   vertices at exact dyadic coordinates), both cell assignments and several `λ`: the grid's
//!   closest hit equals a brute-force loop with the same intersector exactly (same triangle,
//!   same hit record), any hit agrees on hit/miss.
//! * The bunny (`../shared/meshes/bunny.obj`, required): ~10 000 incoherent and primary rays
//!   against brute force; the reference counts of both assignments and the bytes per
//!   triangle are printed (the figures of the `grid` module docs).
//! * Every `bvh` fuzz corpus and regression input (the `grid` target reads the same layout)
//!   through the `grid` property.

use glam::Vec3;
use halfray::obj::read_obj;
use halfray::raysets::{Camera, Rng, random_rays};
use halfray_core::Ray;
use halfray_core::grid::{CellAssignment, DEFAULT_LAMBDA, Grid, GridOptions, GridPlan};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::TraversalStats;
use halfray_core::solids::{CUBE_TRIANGLES, CUBE_VERTICES, grid_triangles};
use halfray_core::triangle::Watertight;
use halfray_tests::{any_by, brute_triangles, closest_by, meshes_dir, par_map};
use std::path::{Path, PathBuf};

const FUZZ_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../fuzz");

type VecGrid = Grid<Vec<u32>, Vec<u32>>;

fn build(mesh: &TriangleMesh<'_>, options: &GridOptions) -> VecGrid {
    let plan = GridPlan::new(mesh, options).unwrap();
    Grid::build(
        mesh,
        &plan,
        vec![0; plan.required_offsets()],
        vec![0; plan.required_references()],
    )
    .unwrap()
}

/// Grid = brute force on every ray, for both assignments and `λ` ∈ {0.5, default, 16};
/// returns the number of hits.
fn check_scene(name: &str, p: &[Vec3], t: &[[u32; 3]], rays: &[Ray]) -> usize {
    let mesh = TriangleMesh::new(p, t);
    let want: Vec<_> = rays
        .iter()
        .map(|r| brute_triangles(&mesh, &Watertight, r))
        .collect();
    for assignment in [CellAssignment::Bounds, CellAssignment::Exact] {
        for lambda in [0.5, DEFAULT_LAMBDA, 16.0] {
            let g = build(
                &mesh,
                &GridOptions {
                    lambda,
                    assignment,
                    ..GridOptions::default()
                },
            );
            for (ray, w) in rays.iter().zip(&want) {
                let got = closest_by(&g, &mesh, &Watertight, ray, None);
                assert_eq!(got, *w, "{name} {assignment:?} λ {lambda}: {ray:?}");
                let any = any_by(&g, &mesh, &Watertight, ray);
                assert_eq!(any.is_some(), w.is_some(), "{name}: any-hit {ray:?}");
            }
        }
    }
    want.iter().filter(|w| w.is_some()).count()
}

/// A flat `k × k` grid of unit squares (two triangles each, shared vertices) in the plane
/// `axis = c`.
fn flat_squares(k: u32, axis: usize, c: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for i in 0..=k {
        for j in 0..=k {
            let mut v = Vec3::splat(c);
            v[(axis + 1) % 3] = i as f32;
            v[(axis + 2) % 3] = j as f32;
            p.push(v);
        }
    }
    (p, grid_triangles(k, k).collect())
}

#[test]
fn random_soups_equal_brute_force() {
    let mut rng = Rng::new(0x6121);
    for (n, size) in [(300usize, 0.5f32), (50, 4.0), (2000, 0.1)] {
        let mut p = Vec::new();
        let mut t = Vec::new();
        for i in 0..n as u32 {
            let c = Vec3::new(
                rng.f32_in(0.0, 10.0),
                rng.f32_in(0.0, 6.0),
                rng.f32_in(0.0, 3.0),
            );
            for _ in 0..3 {
                p.push(c + rng.unit_vector().as_vec3() * size);
            }
            t.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let lo = Vec3::ZERO;
        let hi = Vec3::new(10.0, 6.0, 3.0);
        let rays = random_rays(lo, hi, 600, n as u64);
        let hits = check_scene("soup", &p, &t, &rays);
        assert!(hits > 50, "{hits}");
    }
}

/// Coincident and duplicated triangles (the tie rule picks the smaller index), zero-area
/// triangles (never hit) among them, and reversed copies.
#[test]
fn coincident_and_zero_area_triangles() {
    let (p, base) = flat_squares(6, 2, 1.0);
    let mut t = Vec::new();
    for tri in &base {
        t.push([tri[2], tri[1], tri[0]]);
        t.push(*tri);
        t.push([tri[0], tri[0], tri[1]]);
        t.push([tri[0], tri[1], tri[0]]);
    }
    t.extend_from_slice(&base);
    let mut rng = Rng::new(7);
    let rays: Vec<Ray> = (0..500)
        .map(|_| {
            let target = Vec3::new(rng.f32_in(0.0, 6.0), rng.f32_in(0.0, 6.0), 1.0);
            let o = target + rng.unit_vector().as_vec3() * 3.0;
            Ray::new(o, target - o)
        })
        .collect();
    let hits = check_scene("coincident", &p, &t, &rays);
    assert!(hits > 200, "{hits}");
    // The winner of every hit is the lowest of the coincident copies.
    let mesh = TriangleMesh::new(&p, &t);
    let g = build(&mesh, &GridOptions::default());
    for r in &rays {
        if let Some((i, _)) = closest_by(&g, &mesh, &Watertight, r, None) {
            assert!(i < 4 * base.len() as u32 && i % 4 < 2, "{i}");
        }
    }
}

/// Axis-aligned flat meshes in each axis plane (one cell thick), with rays through their
/// shared edges and vertices (exact: dyadic origins, `o + d` is the target exactly), rays
/// lying in grid planes, and rays parallel to the mesh (in its plane: no hit).
#[test]
fn flat_meshes_shared_edges_and_grid_plane_rays() {
    for axis in 0..3 {
        let (p, t) = flat_squares(8, axis, 2.0);
        let mut rays = Vec::new();
        let mut rng = Rng::new(axis as u64);
        for i in 0..=16 {
            for j in 0..=16 {
                // Vertices (even i, j), edge midpoints and square centres (odd).
                let mut target = Vec3::splat(2.0);
                target[(axis + 1) % 3] = i as f32 * 0.5;
                target[(axis + 2) % 3] = j as f32 * 0.5;
                let jitter = Vec3::new(
                    rng.below(9) as f32 / 8.0,
                    rng.below(9) as f32 / 8.0,
                    rng.below(9) as f32 / 8.0,
                );
                let mut o = target + jitter;
                o[axis] = 6.0;
                let d = target - o;
                assert_eq!(o + d, target);
                rays.push(Ray::new(o, d));
                // Straight down the normal, with ±0 in the other components.
                let mut down = Vec3::new(0.0, -0.0, 0.0);
                down[axis] = -1.0;
                rays.push(Ray::new(o - jitter + Vec3::ZERO, down));
                // In the mesh's plane (no hit) and in a grid plane through it.
                let mut along = Vec3::ZERO;
                along[(axis + 1) % 3] = 1.0;
                let mut start = target;
                start[(axis + 1) % 3] = -1.0;
                rays.push(Ray::new(start, along));
                start[axis] = 2.5;
                rays.push(Ray::new(start, along + down * 0.125));
            }
        }
        let hits = check_scene("flat", &p, &t, &rays);
        // Every vertex/edge/centre ray hits (no leak through shared edges or vertices).
        assert!(hits >= 2 * 17 * 17, "axis {axis}: {hits}");
    }
}

/// A closed box made of 12 triangles, cut into cells whose planes pass through its edges,
/// with rays along those planes (inside the box, along faces) from inside and outside.
#[test]
fn rays_along_grid_planes_through_a_closed_box() {
    // The cube [-1, 1]³ scaled and moved to [0, 4]³.
    let p: Vec<Vec3> = CUBE_VERTICES.map(|v| (v + 1.0) * 2.0).to_vec();
    let t = CUBE_TRIANGLES.to_vec();
    let mut rays = Vec::new();
    for a in 0..3 {
        for u in 0..=8 {
            for v in 0..=8 {
                for sign in [1.0f32, -1.0] {
                    let mut o = Vec3::ZERO;
                    o[(a + 1) % 3] = u as f32 * 0.5;
                    o[(a + 2) % 3] = v as f32 * 0.5;
                    o[a] = if sign > 0.0 { -3.0 } else { 7.0 };
                    let mut d = Vec3::new(-0.0, 0.0, -0.0);
                    d[a] = sign;
                    rays.push(Ray::new(o, d));
                    o[a] = 2.0;
                    rays.push(Ray::new(o, d));
                }
            }
        }
    }
    let hits = check_scene("box", &p, &t, &rays);
    assert!(hits > rays.len() / 2, "{hits}");
}

fn load_bunny() -> halfray::obj::ObjMesh {
    let path = meshes_dir().join("bunny.obj");
    assert!(path.is_file(), "missing shared mesh {}", path.display());
    read_obj(&path).unwrap()
}

/// The bunny: the grid equals brute force on every sampled ray; and the figures.
#[test]
fn bunny_equals_brute_force_and_figures() {
    let obj = load_bunny();
    let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
    let (lo, hi) = obj.bounds().unwrap();
    let grid = build(&mesh, &GridOptions::default());
    let mut rays = random_rays(lo, hi, 1500, 0xB0);
    rays.extend(Camera::framing(lo, hi, 32, 32).rays());
    let results = par_map(&rays, |r| {
        let got = closest_by(&grid, &mesh, &Watertight, r, None);
        let any = any_by(&grid, &mesh, &Watertight, r).is_some();
        (got, any, brute_triangles(&mesh, &Watertight, r))
    });
    let mut hits = 0;
    for (r, (got, any, want)) in rays.iter().zip(results) {
        assert_eq!(got, want, "bunny {r:?}");
        assert_eq!(any, want.is_some(), "bunny any-hit {r:?}");
        hits += usize::from(want.is_some());
    }
    assert!(hits > rays.len() / 5, "{hits}");
    // More rays (every sixth of the figures' sample below) against brute force too.
    let mut many = random_rays(lo, hi, 30_000, 0xB1);
    many.extend(Camera::framing(lo, hi, 128, 128).rays());
    let sample: Vec<Ray> = many.iter().step_by(6).copied().collect();
    let diffs = par_map(&sample, |r| {
        let g = closest_by(&grid, &mesh, &Watertight, r, None);
        usize::from(g != brute_triangles(&mesh, &Watertight, r))
    });
    assert_eq!(diffs.iter().sum::<usize>(), 0);
    let n = mesh.len();
    // Figures: references both ways, bytes per triangle, work per ray.
    let bounds = build(
        &mesh,
        &GridOptions {
            assignment: CellAssignment::Bounds,
            ..GridOptions::default()
        },
    );
    assert_eq!(bounds.resolution(), grid.resolution());
    assert!(grid.reference_count() < bounds.reference_count());
    assert!(grid.reference_count() >= n);
    let mut st = TraversalStats::default();
    for r in &many {
        let _ = closest_by(&grid, &mesh, &Watertight, r, &mut st);
    }
    eprintln!(
        "bunny: {n} triangles, λ {DEFAULT_LAMBDA}, cells {:?}; references exact {} / bounds {} \
         ({:.2} / {:.2} per triangle); {:.1} bytes per triangle; per ray {:.1} cells, {:.1} tests",
        grid.resolution(),
        grid.reference_count(),
        bounds.reference_count(),
        grid.reference_count() as f64 / n as f64,
        bounds.reference_count() as f64 / n as f64,
        grid.bytes_per_triangle(),
        st.nodes_visited as f64 / many.len() as f64,
        st.primitives_tested as f64 / many.len() as f64,
    );
    for lambda in [1.0f32, 2.0, 4.0, 8.0] {
        let g = build(
            &mesh,
            &GridOptions {
                lambda,
                ..GridOptions::default()
            },
        );
        let mut st = TraversalStats::default();
        for r in &many {
            let _ = closest_by(&g, &mesh, &Watertight, r, &mut st);
        }
        eprintln!(
            "bunny λ {lambda}: cells {:?}, {:.1} bytes per triangle, per ray {:.1} cells, \
             {:.1} tests",
            g.resolution(),
            g.bytes_per_triangle(),
            st.nodes_visited as f64 / many.len() as f64,
            st.primitives_tested as f64 / many.len() as f64,
        );
    }
}

/// Every input of the `bvh` fuzz corpus and regressions is a `grid` input (same layout):
/// all of them pass the `grid` property, each with its own flags and with the exact and
/// bounds assignments at λ = 64 (flag bits 2–4).
#[test]
fn bvh_fuzz_inputs_pass_the_grid_property() {
    let mut count = 0;
    for kind in ["corpus", "regressions"] {
        let dir = Path::new(FUZZ_DIR).join(kind).join("bvh");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        for f in files {
            let data = std::fs::read(&f).unwrap();
            if data.is_empty() {
                continue;
            }
            for extra in [None, Some(0x18u8), Some(0x1C)] {
                let mut d = data.clone();
                if let Some(bits) = extra {
                    d[0] = (d[0] & 0x03) | bits;
                }
                let r = std::panic::catch_unwind(|| halfray_fuzz_props::grid::grid(&d));
                assert!(r.is_ok(), "{} (flags {:#x})", f.display(), d[0]);
                count += 1;
            }
        }
    }
    assert!(count > 100, "{count}");
}
