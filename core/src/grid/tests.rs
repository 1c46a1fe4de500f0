//! Unit tests of the grid (the mesh-scale comparisons with brute force live in
//! `tests/tests/grid_vs_bruteforce.rs`).

use super::overlap::triangle_overlaps_box;
use super::*;
use crate::mesh::TriangleMesh;
use crate::prelude::*;
use crate::query::{Query, TraversalStats};
use crate::ray::Ray;
use crate::test_util::{
    VecGrid, any_watertight, brute_watertight as brute, closest_watertight, closest_watertight_in,
    lcg, unit_vec, vec_grid as build,
};
use crate::triangle::{TriangleIntersector, Watertight};
use glam::{DVec3, Vec3};
use std::format;
use std::vec;
use std::vec::Vec;

/// The grid of `mesh` with default options but `assignment` (panics when refused).
fn build_assigned(mesh: &TriangleMesh<'_>, assignment: CellAssignment) -> VecGrid {
    let options = GridOptions {
        assignment,
        ..GridOptions::default()
    };
    build(mesh, &options).unwrap()
}

/// A soup of `n` random triangles of size about `size` in a box of side `scale`.
fn soup(seed: u64, n: usize, scale: f32, size: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut s = seed;
    let mut p = Vec::new();
    let mut t = Vec::new();
    for i in 0..n as u32 {
        let c = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * scale;
        for _ in 0..3 {
            p.push(c + unit_vec(&mut s) * size);
        }
        t.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    (p, t)
}

fn check_rays(mesh: &TriangleMesh<'_>, grid: &VecGrid, rays: &[Ray]) -> usize {
    let mut hits = 0;
    for ray in rays {
        let want = brute(mesh, ray);
        let got = closest_watertight(grid, mesh, ray);
        assert_eq!(got, want, "{ray:?}");
        let any = any_watertight(grid, mesh, ray);
        assert_eq!(any.is_some(), want.is_some(), "{ray:?}");
        if let Some((p, h)) = any {
            assert!(ray.contains(h.t));
            let v = mesh.triangle(p as usize).unwrap();
            assert_eq!(Watertight.intersect(ray, &v), Some(h));
        }
        hits += usize::from(want.is_some());
    }
    hits
}

/// The plan of `mesh` with default options but `lambda` cells per triangle.
fn plan_with_lambda(mesh: &TriangleMesh<'_>, lambda: f32) -> GridPlan {
    let options = GridOptions {
        lambda,
        ..GridOptions::default()
    };
    GridPlan::new(mesh, &options).unwrap()
}

/// The module docs' resolution for `n` triangles with scene extents `e` (all non-zero and
/// no axis below one cell), written out here: `round(e_a · (λn / (e_x e_y e_z))^(1/3))`, at
/// least 1.
fn cube_root_resolution(e: DVec3, lambda: f32, n: usize) -> [u32; 3] {
    let k = libm::cbrt(f64::from(lambda) * n as f64 / (e.x * e.y * e.z));
    [0, 1, 2].map(|a| ((e[a] * k).round() as u32).max(1))
}

#[test]
fn resolution_follows_the_cube_root_rule() {
    let (p, t) = soup(1, 1000, 10.0, 0.2);
    let mesh = TriangleMesh::new(&p, &t);
    for lambda in [1.0f32, 4.0, 8.0] {
        let plan = plan_with_lambda(&mesh, lambda);
        let e = plan.bounds().extent().as_dvec3();
        let want = cube_root_resolution(e, lambda, 1000);
        assert_eq!(plan.resolution(), want, "λ {lambda}");
        let cells = plan.cell_count() as f64;
        assert!(
            (cells / (f64::from(lambda) * 1000.0) - 1.0).abs() < 0.25,
            "{cells}"
        );
    }
}

#[test]
fn flat_line_and_point_scenes() {
    // A flat mesh in z = 0: one cell in z, λN cells over the plane.
    let mut p = Vec::new();
    let mut t = Vec::new();
    for i in 0..20u32 {
        for j in 0..20u32 {
            let o = Vec3::new(i as f32, j as f32, 0.0);
            let base = p.len() as u32;
            p.extend([o, o + Vec3::X, o + Vec3::Y]);
            t.push([base, base + 1, base + 2]);
        }
    }
    let mesh = TriangleMesh::new(&p, &t);
    let plan = GridPlan::new(&mesh, &GridOptions::default()).unwrap();
    let [nx, ny, nz] = plan.resolution();
    assert_eq!(nz, 1);
    assert_eq!(nx, ny);
    let want = libm::sqrt(f64::from(DEFAULT_LAMBDA) * 400.0).round() as u32;
    assert_eq!(nx, want);
    // A line (degenerate triangles along x): only x is cut.
    let line: Vec<Vec3> = (0..30).map(|i| Vec3::new(i as f32, 2.0, 3.0)).collect();
    let lt: Vec<[u32; 3]> = (0..29u32).map(|i| [i, i + 1, i]).collect();
    let plan = GridPlan::new(&TriangleMesh::new(&line, &lt), &GridOptions::default()).unwrap();
    assert_eq!(plan.resolution(), [(DEFAULT_LAMBDA * 29.0) as u32, 1, 1]);
    // Coincident points: one cell.
    let pts = [Vec3::splat(5.0); 3];
    let tris = [[0u32, 1, 2]; 7];
    let plan = GridPlan::new(&TriangleMesh::new(&pts, &tris), &GridOptions::default()).unwrap();
    assert_eq!((plan.resolution(), plan.required_references()), ([1; 3], 7));
    // A very thin slab: the thin axis gets one cell, the others share λN.
    let thin: Vec<Vec3> = p.iter().map(|v| *v + Vec3::Z * (v.x * 1e-6)).collect();
    let plan = GridPlan::new(&TriangleMesh::new(&thin, &t), &GridOptions::default()).unwrap();
    assert_eq!(plan.resolution()[2], 1);
    assert!(plan.resolution()[0] > 20);
}

#[test]
fn per_axis_maximum_is_enforced() {
    let line: Vec<Vec3> = (0..3000).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
    let lt: Vec<[u32; 3]> = (0..2999u32).map(|i| [i, i + 1, i]).collect();
    let mesh = TriangleMesh::new(&line, &lt);
    let plan = GridPlan::new(&mesh, &GridOptions::default()).unwrap();
    assert_eq!(plan.resolution(), [MAX_CELLS_PER_AXIS, 1, 1]);
    let opts = GridOptions {
        max_cells_per_axis: 7,
        ..GridOptions::default()
    };
    assert_eq!(GridPlan::new(&mesh, &opts).unwrap().resolution(), [7, 1, 1]);
}

#[test]
fn too_small_storage_is_refused_before_writing() {
    let (p, t) = soup(2, 50, 4.0, 0.5);
    let mesh = TriangleMesh::new(&p, &t);
    let plan = GridPlan::new(&mesh, &GridOptions::default()).unwrap();
    let (no, nr) = (plan.required_offsets(), plan.required_references());
    let mut off = vec![7u32; no - 1];
    let mut refs = vec![7u32; nr];
    let r = Grid::build(&mesh, &plan, &mut off[..], &mut refs[..]);
    assert_eq!(
        r.err(),
        Some(GridError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::GridOffsets,
            needed: no,
            available: no - 1
        }))
    );
    let mut off = vec![7u32; no];
    let mut refs = vec![7u32; nr - 1];
    let r = Grid::build(&mesh, &plan, &mut off[..], &mut refs[..]);
    assert_eq!(
        r.err(),
        Some(GridError::Capacity(crate::error::CapacityError {
            storage: crate::error::Storage::GridReferences,
            needed: nr,
            available: nr - 1
        }))
    );
    assert!(off.iter().chain(&refs).all(|&x| x == 7));
    let other = TriangleMesh::new(&p, &t[..10]);
    let r = Grid::build(&other, &plan, &mut off[..], &mut refs[..]);
    assert!(matches!(r.err(), Some(GridError::PlanMismatch { .. })));
    assert!(off.iter().chain(&refs).all(|&x| x == 7));
    assert!(
        !format!(
            "{}",
            GridError::PlanMismatch {
                expected: 1,
                found: 2
            }
        )
        .is_empty()
    );
}

#[test]
fn non_finite_triangles_are_refused_or_excluded() {
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(f32::NAN, 0.0, 0.0)];
    let t = [[0, 1, 2], [0, 1, 3], [0, 1, 9], [2, 1, 0]];
    let mesh = TriangleMesh::new(&p, &t);
    assert_eq!(
        GridPlan::new(&mesh, &GridOptions::default()).err(),
        Some(GridError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Triangle,
            index: 1
        }))
    );
    let opts = GridOptions {
        exclude_non_finite: true,
        ..GridOptions::default()
    };
    let grid = build(&mesh, &opts).unwrap();
    assert_eq!(grid.triangle_count(), 2);
    assert!(grid.references().iter().all(|&r| r == 0 || r == 3));
    let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
    assert_eq!(closest_watertight(&grid, &mesh, &ray).map(|h| h.0), Some(0));
}

/// A 10 × 10 sheet of small triangles in `z = 0` (triangle `10j + i` at `(i, j)` plus a
/// tenth), with triangle 0 moved by `shift`: the audit's reused-plan scene.
fn sheet(shift: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for j in 0..10 {
        for i in 0..10 {
            let mut o = Vec3::new(i as f32 + 0.1, j as f32 + 0.1, 0.0);
            if i + j == 0 {
                o += shift;
            }
            p.extend([
                o,
                o + Vec3::new(0.5, 0.0, 0.0),
                o + Vec3::new(0.0, 0.5, 0.0),
            ]);
        }
    }
    let t = (0..100u32).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
    (p, t)
}

/// A plan reused for a mesh whose vertices moved (an animation step): a triangle moved out of
/// the plan's box is refused with [`GridError::TriangleOutsidePlan`] (it was accepted, and
/// the grid then missed the hit brute force finds), a triangle that became unusable with
/// [`GridError::PlanMismatch`] on the usable count, and a mesh whose triangles stay in the
/// box (two triangles trading places) builds and answers as brute force does.
#[test]
fn a_reused_plan_refuses_triangles_that_left_its_box() {
    let (a, t) = sheet(Vec3::ZERO);
    let mesh_a = TriangleMesh::new(&a, &t);
    let plan = GridPlan::new(&mesh_a, &GridOptions::default()).unwrap();
    let storage = || {
        (
            vec![0u32; plan.required_offsets()],
            vec![0u32; plan.required_references()],
        )
    };
    // Triangle 0 moved 15 units along +x, beyond the plan's box (x ≤ 9.6).
    let (b, _) = sheet(Vec3::new(15.0, 0.0, 0.0));
    let mesh_b = TriangleMesh::new(&b, &t);
    let (off, refs) = storage();
    assert_eq!(
        Grid::build(&mesh_b, &plan, off, refs).err(),
        Some(GridError::TriangleOutsidePlan { triangle: 0 })
    );
    // A NaN vertex in triangle 7: 99 usable triangles where the plan counted 100.
    let mut nan = a.clone();
    nan[3 * 7 + 1] = Vec3::NAN;
    let (off, refs) = storage();
    assert_eq!(
        Grid::build(&TriangleMesh::new(&nan, &t), &plan, off, refs).err(),
        Some(GridError::PlanMismatch {
            expected: 100,
            found: 99
        })
    );
    // Triangles 0 and 99 trade places: every triangle in the box, the same cells in all.
    let mut swapped = a.clone();
    for k in 0..3 {
        swapped.swap(k, 3 * 99 + k);
    }
    let mesh_s = TriangleMesh::new(&swapped, &t);
    let (off, refs) = storage();
    let grid = Grid::build(&mesh_s, &plan, off, refs).unwrap();
    let rays: Vec<Ray> = (0..10)
        .flat_map(|j| (0..10).map(move |i| Vec3::new(i as f32 + 0.2, j as f32 + 0.2, -1.0)))
        .map(|o| Ray::new(o, Vec3::Z))
        .collect();
    assert_eq!(check_rays(&mesh_s, &grid, &rays), 100);
}

/// Layout invariants and the oracle "each triangle is in the cell of each of its vertices",
/// with the cell computed independently in `f64` from the documented layout.
#[test]
fn every_vertex_cell_references_its_triangle() {
    let (p, t) = soup(3, 300, 8.0, 0.7);
    let mesh = TriangleMesh::new(&p, &t);
    for assignment in [CellAssignment::Bounds, CellAssignment::Exact] {
        let g = build_assigned(&mesh, assignment);
        let off = g.offsets();
        assert_eq!(off.len(), g.cell_count() + 1);
        assert_eq!(off[0], 0);
        assert_eq!(*off.last().unwrap() as usize, g.reference_count());
        assert!(off.windows(2).all(|w| w[0] <= w[1]));
        let b = g.bounds();
        let n = g.resolution();
        for (i, tri) in t.iter().enumerate() {
            for &vi in tri {
                let v = p[vi as usize].as_dvec3();
                let c = [0, 1, 2].map(|a| {
                    let size = (f64::from(b.max[a]) - f64::from(b.min[a])) / f64::from(n[a]);
                    let q = ((v[a] - f64::from(b.min[a])) / size).floor();
                    (q.max(0.0) as u32).min(n[a] - 1)
                });
                let cell = g.cell(c);
                assert!(
                    cell.windows(2).all(|w| w[0] < w[1]),
                    "sorted, no duplicates"
                );
                assert!(
                    cell.contains(&(i as u32)),
                    "{assignment:?} tri {i} cell {c:?}"
                );
            }
        }
    }
}

/// The exact assignment is a subset of the bounds one and strictly smaller on long
/// diagonal triangles (figures for the module docs: the bunny in the cross-crate suite).
#[test]
fn exact_assignment_is_a_subset_of_bounds() {
    let (p, t) = soup(4, 200, 10.0, 3.0);
    let mesh = TriangleMesh::new(&p, &t);
    let a = build_assigned(&mesh, CellAssignment::Bounds);
    let e = build_assigned(&mesh, CellAssignment::Exact);
    assert_eq!(a.resolution(), e.resolution());
    assert!(e.reference_count() * 10 < a.reference_count() * 8);
    for id in 0..a.cell_count() {
        let c = [
            id as u32 % a.resolution()[0],
            (id as u32 / a.resolution()[0]) % a.resolution()[1],
            id as u32 / (a.resolution()[0] * a.resolution()[1]),
        ];
        let (sa, se) = (a.cell(c), e.cell(c));
        assert!(se.iter().all(|x| sa.contains(x)), "cell {c:?}");
    }
}

/// The separating-axis test never separates a triangle from a box that contains one of
/// its points (oracle: sampled barycentric points, in `f64`), including points exactly on
/// the box's faces, edges and corners; and it does separate clearly distant pairs.
#[test]
fn sat_is_conservative_on_sampled_contacts() {
    let mut s = 99u64;
    let mut separated = 0;
    for _ in 0..3000 {
        let v = [0; 3].map(|_| (unit_vec(&mut s) * 2.0).as_dvec3());
        let (b1, b2) = (f64::from(lcg(&mut s)), f64::from(lcg(&mut s)));
        let (b1, b2) = if b1 + b2 > 1.0 {
            (1.0 - b1, 1.0 - b2)
        } else {
            (b1, b2)
        };
        let q = v[0] + (v[1] - v[0]) * b1 + (v[2] - v[0]) * b2;
        // A box with `q` on a corner, an edge, a face, or inside.
        let h = DVec3::new(
            f64::from(lcg(&mut s)),
            f64::from(lcg(&mut s)),
            f64::from(lcg(&mut s)),
        ) * 0.5;
        let kind = (lcg(&mut s) * 4.0) as usize;
        let lo = match kind {
            0 => q,
            1 => q - DVec3::new(0.0, h.y, h.z),
            2 => q - DVec3::new(h.x, 0.0, 0.0),
            _ => q - h,
        };
        assert!(triangle_overlaps_box(&v, lo, lo + h * 2.0), "{v:?} {lo:?}");
        // The same box moved away by more than the triangle's size: separated.
        let far = lo + DVec3::splat(10.0);
        separated += usize::from(!triangle_overlaps_box(&v, far, far + h * 2.0));
    }
    assert_eq!(separated, 3000);
    // A segment and a point are handled conservatively too.
    let seg = [DVec3::ZERO, DVec3::ONE, DVec3::ONE];
    assert!(triangle_overlaps_box(
        &seg,
        DVec3::splat(0.5),
        DVec3::splat(0.5)
    ));
    let pt = [DVec3::ONE; 3];
    assert!(!triangle_overlaps_box(&pt, DVec3::ZERO, DVec3::splat(0.99)));
}

#[test]
fn random_soups_equal_brute_force() {
    for (seed, n, size) in [(5u64, 400usize, 0.6f32), (6, 60, 3.0), (7, 1, 1.0)] {
        let (p, t) = soup(seed, n, 8.0, size);
        let mesh = TriangleMesh::new(&p, &t);
        for assignment in [CellAssignment::Bounds, CellAssignment::Exact] {
            let g = build_assigned(&mesh, assignment);
            let mut s = seed;
            let rays: Vec<Ray> = (0..400)
                .map(|_| {
                    let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 12.0 - 2.0;
                    Ray::new(o, unit_vec(&mut s))
                })
                .collect();
            let hits = check_rays(&mesh, &g, &rays);
            assert!(hits > 10 || n < 10, "{hits}");
        }
    }
}

/// Axis-parallel rays with `±0` components, rays along cell planes, from inside and
/// outside, far origins (neighbour blocks and the every-reference fallback) and invalid rays.
#[test]
fn axis_parallel_far_and_invalid_rays() {
    let (p, t) = soup(8, 500, 8.0, 0.5);
    let mesh = TriangleMesh::new(&p, &t);
    let g = build(&mesh, &GridOptions::default()).unwrap();
    let b = g.bounds();
    let mut rays = Vec::new();
    let mut s = 11u64;
    for _ in 0..200 {
        let o = b.min + (b.max - b.min) * Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s));
        for a in 0..3 {
            for sign in [1.0f32, -1.0] {
                let mut d = Vec3::new(0.0, -0.0, 0.0);
                d[a] = sign;
                rays.push(Ray::new(o, d));
                // Along a cell plane of another axis.
                let mut on = o;
                let k = (a + 1) % 3;
                let size = (b.max[k] - b.min[k]) / g.resolution()[k] as f32;
                on[k] = b.min[k] + size * 3.0;
                rays.push(Ray::new(on, d));
                // From outside the box.
                let mut out = o;
                out[a] = if sign > 0.0 {
                    b.min[a] - 5.0
                } else {
                    b.max[a] + 5.0
                };
                rays.push(Ray::new(out, d));
            }
        }
        let d = unit_vec(&mut s);
        for far in [40.0f32, 300.0, 1e5, 1e30] {
            rays.push(Ray::new(o - d * far, d));
        }
        rays.push(Ray::with_interval(o, d, -3.0, 2.0));
        rays.push(Ray::with_interval(o, d, f32::NEG_INFINITY, f32::INFINITY));
    }
    let hits = check_rays(&mesh, &g, &rays);
    assert!(hits > rays.len() / 4, "{hits} of {}", rays.len());
    for bad in [
        Ray::new(Vec3::NAN, Vec3::Z),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        Ray::new(Vec3::splat(4.0), Vec3::ZERO),
        Ray::with_interval(Vec3::splat(4.0), Vec3::Z, f32::NAN, 1.0),
    ] {
        let mut st = TraversalStats::default();
        assert_eq!(
            closest_watertight_in(&g, &mesh, &bad, &mut Query::new().stats(&mut st)),
            None
        );
        assert_eq!(st, TraversalStats::default());
    }
}

/// Scenes at `1e20` and `1e-20` (rays scaled with them) give brute force's answers.
#[test]
fn huge_and_tiny_scenes() {
    let (p, t) = soup(9, 200, 8.0, 0.6);
    for scale in [1e20f32, 1e-20, 1e-30] {
        let ps: Vec<Vec3> = p.iter().map(|v| *v * scale).collect();
        let mesh = TriangleMesh::new(&ps, &t);
        let g = build(&mesh, &GridOptions::default()).unwrap();
        assert!(g.cell_count() > 100, "{scale}: {:?}", g.resolution());
        let mut s = 12u64;
        let rays: Vec<Ray> = (0..300)
            .map(|_| {
                let o = (Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 12.0 - 2.0) * scale;
                Ray::new(o, unit_vec(&mut s))
            })
            .collect();
        assert!(check_rays(&mesh, &g, &rays) > 10, "{scale}");
    }
}

/// A ray whose origin lies so far on the other side of the grid that its origin in the
/// grid's frame, `o − c`, overflows `f32`, while its differences to the nearer triangles do
/// not (a soup spanning `x ∈ [−3·10³⁸, −10³⁸]`, origins at `x = 2·10³⁸`), still gets brute
/// force's answer, hits included.
#[test]
fn an_origin_beyond_f32_in_the_grids_frame_still_finds_the_hits() {
    let (p, t) = soup(5, 400, 8.0, 0.6);
    let far = Vec3::new(-3.0e38, 0.0, 0.0);
    let ps: Vec<Vec3> = p.iter().map(|&v| v * 2.5e37 + far).collect();
    let mesh = TriangleMesh::new(&ps, &t);
    let g = build(&mesh, &GridOptions::default()).unwrap();
    // Along −x through the centroid (in `f64`, rounded) of each triangle on the near side.
    let rays: Vec<Ray> = t
        .iter()
        .map(|tri| {
            tri.iter()
                .fold(DVec3::ZERO, |m, &i| m + ps[i as usize].as_dvec3())
                / 3.0
        })
        .filter(|c| c.x > -1.5e38)
        .map(|c| Ray::new(Vec3::new(2.0e38, c.y as f32, c.z as f32), -Vec3::X))
        .collect();
    assert!(
        rays.iter()
            .all(|r| !(r.origin - g.bounds().center()).is_finite())
    );
    assert!(check_rays(&mesh, &g, &rays) > 20);
}

/// The walk visits at most `nx + ny + nz − 2` cells (the step bound), here on the diagonal.
#[test]
fn nodes_visited_are_bounded_by_the_resolution() {
    let (p, t) = soup(10, 2000, 8.0, 0.05);
    let mesh = TriangleMesh::new(&p, &t);
    let g = build(&mesh, &GridOptions::default()).unwrap();
    let [nx, ny, nz] = g.resolution();
    let b = g.bounds();
    let mut st = TraversalStats::default();
    let ray = Ray::new(b.min - Vec3::splat(1.0), b.max - b.min);
    let mut miss = |_: u32, _: &Ray| None::<(f32, ())>;
    assert!(
        g.closest_hit(&ray, &mut miss, &mut Query::new().stats(&mut st))
            .is_none()
    );
    assert!(st.nodes_visited <= u64::from(nx + ny + nz - 2), "{st:?}");
    assert!(st.nodes_visited >= u64::from(nx.max(ny).max(nz)), "{st:?}");
    assert!(g.bytes_used() == 4 * (g.cell_count() + 1 + g.reference_count()));
}

#[test]
fn empty_mesh_hits_nothing() {
    let mesh = TriangleMesh::new(&[], &[]);
    let g = build(&mesh, &GridOptions::default()).unwrap();
    assert_eq!((g.cell_count(), g.reference_count()), (1, 0));
    let ray = Ray::new(Vec3::ZERO, Vec3::Z);
    assert!(any_watertight(&g, &mesh, &ray).is_none());
    assert_eq!(g.bytes_per_triangle(), 0.0);
}

/// Rays from far away (`|o|` from 10³ to 10⁷ scene sizes), aimed at the vertices of a dense
/// soup: the watertight test's rounding then spans whole cells, and the neighbour blocks
/// (or the every-reference fallback) must still find brute force's hit.
#[test]
fn far_origins_use_neighbour_blocks() {
    let (p, t) = soup(13, 3000, 1.0, 0.02);
    let mesh = TriangleMesh::new(&p, &t);
    let g = build(&mesh, &GridOptions::default()).unwrap();
    let mut s = 14u64;
    let mut rays = Vec::new();
    for far in [1e3f32, 1e5, 1e6, 1e7] {
        for k in 0..300 {
            let target = p[(k * 7) % p.len()];
            let o = target + unit_vec(&mut s) * far;
            rays.push(Ray::new(o, target - o));
        }
    }
    assert!(check_rays(&mesh, &g, &rays) > 600);
    // The blocks are in use (more cells per ray than a plain walk could visit).
    let mut st = TraversalStats::default();
    for r in &rays {
        let _ = closest_watertight_in(&g, &mesh, r, &mut Query::new().stats(&mut st));
    }
    let [nx, ny, nz] = g.resolution();
    assert!(
        st.nodes_visited > rays.len() as u64 * u64::from(nx + ny + nz),
        "{st:?}"
    );
}

/// How many times the references a pass over all of them tests (the brute force the grid
/// falls back to) a walk may cost, counting cell visits and triangle tests alike (unitless):
/// the walk visits each cell once and fewer cells than there are references, and tests each
/// visited cell's references once, so at most the references themselves.
const WALK_WORK_PER_REFERENCE: u64 = 2;

/// The audit's far-ray scene: 16 384 triangles of side 10⁻³ scattered in the unit cube, a fine
/// grid (`λ = 64`, 102³ cells), and rays along `±x` through a sparse height from
/// `10 … 3·10⁵` away, plus rays from as far aimed at triangles along oblique directions. From
/// `1.2·10⁵` away along `+x` the walk tested a block of 99³ cells around each of 102 cells
/// (71 million visits, 600 times a pass over every reference); a walk now visits each cell
/// once and gives way to that pass when it could visit more cells than there are
/// references. Every ray: the work is within [`WALK_WORK_PER_REFERENCE`] times the
/// references (or the ray fell back to testing each once), and the answer is brute force's.
#[test]
fn far_rays_cost_no_more_than_a_pass_over_every_reference() {
    let mut s = 12345u64;
    let mut r = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut p = Vec::new();
    for _ in 0..16384 {
        let o = Vec3::new(r(), r(), r());
        p.extend([
            o,
            o + Vec3::new(0.001, 0.0, 0.0),
            o + Vec3::new(0.0, 0.001, 0.0),
        ]);
    }
    let t: Vec<[u32; 3]> = (0..16384u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let mesh = TriangleMesh::new(&p, &t);
    let options = GridOptions {
        lambda: 64.0,
        ..GridOptions::default()
    };
    let g = build(&mesh, &options).unwrap();
    let (cells, refs) = (g.cell_count() as u64, g.reference_count() as u64);
    assert_eq!(g.resolution(), [102; 3]);
    let mut rays = Vec::new();
    let mut fell_back = 0;
    let mut s = 21u64;
    for far in [10.0f32, 1e3, 3e3, 1e4, 3e4, 6e4, 1e5, 1.2e5, 1.4e5, 3e5] {
        rays.push(Ray::new(Vec3::new(-far, 0.5003, 0.5007), Vec3::X));
        rays.push(Ray::new(Vec3::new(1.0 + far, 0.5003, 0.5007), -Vec3::X));
        for k in 0..20 {
            // At the triangle's centroid, from `far` away along a random direction.
            let v = mesh.triangle(k * 811).unwrap();
            let target = (v[0] + v[1] + v[2]) / 3.0;
            let o = target - unit_vec(&mut s) * far;
            rays.push(Ray::new(o, target - o));
        }
    }
    let mut hits = 0;
    for ray in &rays {
        let mut st = TraversalStats::default();
        let got = closest_watertight_in(&g, &mesh, ray, &mut Query::new().stats(&mut st));
        assert_eq!(got, brute(&mesh, ray), "{ray:?}");
        hits += usize::from(got.is_some());
        if st.nodes_visited == cells {
            // The pass over every reference: each tested once.
            assert_eq!(st.primitives_tested, refs, "{ray:?}");
            fell_back += 1;
        } else {
            let work = st.nodes_visited + st.primitives_tested;
            assert!(
                work <= WALK_WORK_PER_REFERENCE * refs && st.nodes_visited < refs,
                "{ray:?}: {st:?}, {refs} references"
            );
        }
    }
    // Both ways were taken, and the aimed rays hit.
    assert!(fell_back > 0 && fell_back < rays.len(), "{fell_back}");
    assert!(hits > 20, "{hits}");
}

/// `Grid::padding` is the documented `GRID_RAY_PAD·(reach + extent) + GRID_ABS_PAD` with
/// `reach = extent + ORIGIN_REACH·(longest side)`, worked by hand for the box
/// `[−1, 3] × [0, 2] × [0, 1]` of two triangles: in the grid's frame (centre `(1, 1, ½)`)
/// the box is `[−2, 2] × [−1, 1] × [−½, ½]`, so extent 2 (the largest coordinate magnitude
/// there), longest side 4, `reach = 66` and the padding `68·γ₆₄ + 2⁻¹²⁶` with
/// `γ₆₄ = 64u/(1 − 64u)`, `u = 2⁻²⁴` (evaluated here in `f64`; the frame's outward ulps are
/// far inside the comparison's `10⁻⁶`).
#[test]
fn padding_is_the_documented_formula_worked_by_hand() {
    let pos = [
        Vec3::new(-1.0, 0.0, 0.0),
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::new(3.0, 2.0, 1.0),
        Vec3::new(-1.0, 2.0, 1.0),
    ];
    let tris = [[0, 1, 2], [0, 2, 3]];
    let mesh = TriangleMesh::new(&pos, &tris);
    let g = build(&mesh, &GridOptions::default()).unwrap();
    let u = 2f64.powi(-24);
    let want = 68.0 * (64.0 * u / (1.0 - 64.0 * u)) + 2f64.powi(-126);
    let got = f64::from(g.padding());
    assert!(
        (got - want).abs() <= 1e-6 * want,
        "{got:e} against {want:e}"
    );
}

/// `GridPlan::required_bytes` is its documented `4·(offsets + references)`, and the build
/// accepts storage of exactly those counts.
#[test]
fn required_bytes_is_four_per_offset_and_reference() {
    let (pos, tris) = crate::test_util::lcg_soup(50, 8, 10.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tris);
    let plan = GridPlan::new(&mesh, &GridOptions::default()).unwrap();
    let (o, r) = (plan.required_offsets(), plan.required_references());
    assert!(o > 2 && r >= 50, "{o} offsets, {r} references");
    assert_eq!(plan.required_bytes(), 4 * (o + r));
    assert!(build(&mesh, &GridOptions::default()).is_ok());
}

/// The resolution rule of the module docs depends on the scene's extents only: the soup of
/// [`resolution_follows_the_cube_root_rule`] moved far from the origin gets the cells the
/// formula gives for its extents, taken here from the vertices in `f64` (not from the plan).
#[test]
fn resolution_depends_on_extents_not_position() {
    let (p, t) = soup(1, 1000, 10.0, 0.2);
    let shift = Vec3::new(1000.0, -300.0, 40.0);
    let p: Vec<Vec3> = p.iter().map(|&v| v + shift).collect();
    let mesh = TriangleMesh::new(&p, &t);
    let lo = p.iter().fold(DVec3::INFINITY, |m, v| m.min(v.as_dvec3()));
    let hi = p
        .iter()
        .fold(DVec3::NEG_INFINITY, |m, v| m.max(v.as_dvec3()));
    let e = hi - lo;
    let plan = plan_with_lambda(&mesh, 4.0);
    assert_eq!(plan.resolution(), cube_root_resolution(e, 4.0, 1000));
}

/// A scene far from the coordinate origin is laid out in the grid's frame: the soup of
/// [`far_origins_use_neighbour_blocks`] (side 1, triangles 0.02) moved by
/// `(2·10³, −5·10², 1.5·10³)`, where an `f32` ulp is `2⁻¹³` and a padding by the world
/// coordinates' magnitude (`γ₆₄·(|o| + extent)`, about 0.015) would span a third of a cell,
/// gets the padding of the unmoved soup (within 1 %, computed here from the documented
/// formula on the soup's own box) and its references within 2 %; its rays, from a few sizes
/// away and from inside, equal brute force, and box queries report brute force's set.
#[test]
fn a_far_scene_gets_the_cells_and_padding_of_the_unmoved_one() {
    let (p, t) = soup(13, 3000, 1.0, 0.02);
    let shift = Vec3::new(2.0e3, -5.0e2, 1.5e3);
    let moved: Vec<Vec3> = p.iter().map(|&v| v + shift).collect();
    let (near_mesh, far_mesh) = (TriangleMesh::new(&p, &t), TriangleMesh::new(&moved, &t));
    let (near, far) = (
        build(&near_mesh, &GridOptions::default()).unwrap(),
        build(&far_mesh, &GridOptions::default()).unwrap(),
    );
    assert_eq!(near.resolution(), far.resolution());
    // The documented padding from the far box's extents in `f64`.
    let b = far.bounds();
    let side = (0..3)
        .map(|a| f64::from(b.max[a]) - f64::from(b.min[a]))
        .fold(0.0, f64::max);
    let u = 2f64.powi(-24);
    let want = (64.0 * u / (1.0 - 64.0 * u)) * (side / 2.0 * 2.0 + 16.0 * side);
    let got = f64::from(far.padding());
    assert!(
        (got - want).abs() <= 0.01 * want,
        "{got:e} against {want:e}"
    );
    let (rn, rf) = (near.reference_count() as f64, far.reference_count() as f64);
    assert!((rf - rn).abs() <= 0.02 * rn, "{rf} references against {rn}");
    let mut s = 31u64;
    let mut rays = Vec::new();
    for k in 0..600 {
        let target = moved[(k * 11) % moved.len()];
        let from = if k % 2 == 0 { 3.0 } else { 0.3 };
        let o = target + unit_vec(&mut s) * from;
        rays.push(Ray::new(o, target - o));
    }
    assert!(check_rays(&far_mesh, &far, &rays) > 300);
    for k in 0..40 {
        let c = moved[(k * 37) % moved.len()];
        let q = Aabb::new(c - Vec3::splat(0.05), c + Vec3::splat(0.05));
        let want = boxes_overlapping(&far_mesh, &q);
        assert!(!want.is_empty());
        assert_eq!(reported(&far, &far_mesh, &q), want, "box {k}");
    }
}

/// "An empty or NaN query box reports nothing" (`RayQuery::query_box`): an inverted box
/// (`min > max` by 0.4 on each axis) inside a soup, which the closed-box formula alone
/// (`a.min ≤ b.max` and `b.min ≤ a.max` on each axis) would find overlapping the triangles
/// that span it (counted here by brute force: at least one), and a NaN box, report nothing;
/// the valid box between the same corners reports exactly the brute-force set.
#[test]
fn an_empty_or_nan_query_box_reports_nothing() {
    let (p, t) = soup(3, 300, 10.0, 2.0);
    let mesh = TriangleMesh::new(&p, &t);
    let grid = build_assigned(&mesh, CellAssignment::Bounds);
    let bounds = |i: usize| {
        let v = mesh.triangle(i).unwrap();
        Aabb::new(v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]))
    };
    let (a, b) = (Vec3::splat(5.2), Vec3::splat(4.8));
    let inverted = Aabb::new(a, b);
    let closed_formula = |x: &Aabb, y: &Aabb| x.min.cmple(y.max).all() && y.min.cmple(x.max).all();
    let straddling = (0..t.len())
        .filter(|&i| closed_formula(&bounds(i), &inverted))
        .count();
    assert!(straddling > 0);
    for q in [inverted, Aabb::new(Vec3::splat(f32::NAN), b)] {
        let mut got = Vec::new();
        let n = grid.query_box(&mesh, &q, |p| {
            got.push(p);
            true
        });
        assert_eq!((n, got), (0, vec![]), "{q:?}");
    }
    let valid = Aabb::new(b, a);
    assert_eq!(
        reported(&grid, &mesh, &valid),
        boxes_overlapping(&mesh, &valid)
    );
}

/// The triangles of `mesh` whose boxes overlap `q`, by brute force, in increasing index.
fn boxes_overlapping(mesh: &TriangleMesh<'_>, q: &Aabb) -> Vec<u32> {
    (0..mesh.len() as u32)
        .filter(|&i| {
            let v = mesh.triangle(i as usize).unwrap();
            Aabb::new(v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2])).overlaps(q)
        })
        .collect()
}

/// What `grid`'s box query reports for `q`, sorted.
fn reported(grid: &VecGrid, mesh: &TriangleMesh<'_>, q: &Aabb) -> Vec<u32> {
    let mut got = Vec::new();
    grid.query_box(mesh, q, |p| {
        got.push(p);
        true
    });
    got.sort_unstable();
    got
}

/// One large triangle `(0,0,0) (10,0,0) (0,10,0)` (index 0) and 100 small ones
/// `o, o + (0.1,0,0), o + (0,0.1,0)` at `o = (i, j, 0)`, `i, j ∈ 0..10`, so the grid has many
/// cells. The query box `(9.5,9.5,0)–(9.6,9.6,0)` lies in the empty corner of the large
/// triangle's box `[0,10]²×{0}`, far from its hypotenuse `x + y = 10`, and beyond every
/// small triangle's box (`[i, i+0.1]` on x and y, so none reaches 9.5): by hand, the
/// triangles whose boxes overlap it are exactly `[0]`. Under `Exact` the corner cell does
/// not reference triangle 0, which the box query must still report.
#[test]
fn a_box_in_the_empty_corner_of_a_large_triangles_box_reports_it() {
    let mut p = vec![
        Vec3::ZERO,
        Vec3::new(10.0, 0.0, 0.0),
        Vec3::new(0.0, 10.0, 0.0),
    ];
    let mut t = vec![[0u32, 1, 2]];
    for i in 0..10 {
        for j in 0..10 {
            let o = Vec3::new(i as f32, j as f32, 0.0);
            let b = p.len() as u32;
            p.extend([
                o,
                o + Vec3::new(0.1, 0.0, 0.0),
                o + Vec3::new(0.0, 0.1, 0.0),
            ]);
            t.push([b, b + 1, b + 2]);
        }
    }
    let mesh = TriangleMesh::new(&p, &t);
    let q = Aabb::new(Vec3::new(9.5, 9.5, 0.0), Vec3::new(9.6, 9.6, 0.0));
    for assignment in [CellAssignment::Bounds, CellAssignment::Exact] {
        let grid = build_assigned(&mesh, assignment);
        let [nx, ny, _] = grid.resolution();
        assert!(nx > 4 && ny > 4, "{assignment:?}: {:?}", grid.resolution());
        if assignment == CellAssignment::Exact {
            assert!(!grid.cell([nx - 1, ny - 1, 0]).contains(&0));
        }
        let mut got = Vec::new();
        let n = grid.query_box(&mesh, &q, |p| {
            got.push(p);
            true
        });
        assert_eq!((n, got), (1, vec![0]), "{assignment:?}");
    }
}

/// `query_box` reports every triangle whose box overlaps the query, each once, under both
/// assignments: random soups of small triangles with a few large ones across the scene (some
/// flat in `z = 0`), against the brute-force bounds-overlap loop, for query boxes from points
/// to a quarter of the scene, inside it and around it.
#[test]
fn query_box_equals_brute_force_bounds_overlap_on_random_soups() {
    let mut s = 0x5eed_0b0c_u64;
    for case in 0..24u64 {
        let (mut p, mut t) = soup(case, 150, 8.0, 0.3);
        for _ in 0..1 + case % 4 {
            let b = p.len() as u32;
            p.extend((0..3).map(|_| Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 8.0));
            t.push([b, b + 1, b + 2]);
        }
        if case % 3 == 0 {
            p.iter_mut().for_each(|v| v.z = 0.0);
        }
        let mesh = TriangleMesh::new(&p, &t);
        for assignment in [CellAssignment::Bounds, CellAssignment::Exact] {
            let grid = build_assigned(&mesh, assignment);
            for k in 0..100 {
                let c = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 10.0 - Vec3::ONE;
                let h =
                    Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * [0.0, 0.05, 0.5, 2.0][k % 4];
                let q = Aabb::new(c - h, c + h);
                let mut got = Vec::new();
                let n = grid.query_box(&mesh, &q, |p| {
                    got.push(p);
                    true
                });
                got.sort_unstable();
                let want = boxes_overlapping(&mesh, &q);
                assert_eq!(
                    (n, got),
                    (want.len(), want),
                    "case {case} {assignment:?} {q:?}"
                );
            }
        }
    }
}
