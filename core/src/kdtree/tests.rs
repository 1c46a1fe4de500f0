//! Unit tests of the kd-tree (the mesh-scale comparisons with brute force live in
//! `tests/tests/kdtree_vs_bruteforce.rs`).

use super::*;
use crate::mesh::{PrimitiveSource, TriangleMesh};
use crate::prelude::*;
use crate::query::{Query, TraversalStats};
use crate::ray::Ray;
use crate::test_util::{
    Lcg, VecKd, any_watertight, brute_watertight as brute, closest_watertight,
    closest_watertight_in, lcg_soup as soup, vec_kd, vec_kd_sized as build_with,
};
use crate::triangle::{TriangleIntersector, Watertight};
use glam::Vec3;
use std::vec;
use std::vec::Vec;

fn build<S: PrimitiveSource + ?Sized>(src: &S) -> VecKd {
    vec_kd(src, &KdBuildOptions::default()).unwrap()
}

fn check(kd: &VecKd, mesh: &TriangleMesh<'_>, ray: &Ray) {
    let want = brute(mesh, ray);
    let got = closest_watertight(kd, mesh, ray);
    assert_eq!(got, want, "{ray:?}");
    let any = any_watertight(kd, mesh, ray);
    assert_eq!(any.is_some(), want.is_some(), "{ray:?}");
    if let Some((p, h)) = any {
        let v = mesh.triangle(p as usize).unwrap();
        assert_eq!(Watertight.intersect(ray, &v), Some(h));
    }
}

/// Rays of every kind over a scene of scale `s` around the origin: random, axis-parallel
/// with both zero signs, from inside, and aimed at vertices and edge midpoints.
fn rays(pos: &[Vec3], s: f32, seed: u64) -> Vec<Ray> {
    let mut r = Lcg(seed);
    let mut out = Vec::new();
    for _ in 0..200 {
        let o = r.v(3.0 * s);
        out.push(Ray::new(o, r.v(1.0)));
        out.push(Ray::new(r.v(0.5 * s), r.v(1.0)));
    }
    for k in 0..60 {
        let o = r.v(1.5 * s);
        for axis in 0..3 {
            for sign in [1.0f32, -1.0] {
                for zero in [0.0f32, -0.0] {
                    let mut d = Vec3::splat(zero);
                    d[axis] = sign;
                    out.push(Ray::new(o, d));
                }
            }
        }
        let a = pos[(k * 7) % pos.len()];
        let b = pos[(k * 13 + 1) % pos.len()];
        out.push(Ray::new(o, a - o));
        out.push(Ray::new(o, (a + b) * 0.5 - o));
    }
    out
}

#[test]
fn node_is_8_bytes_and_capacities() {
    assert_eq!(core::mem::size_of::<KdNode>(), 8);
    assert_eq!(NODE_SIZE, 8);
    assert_eq!(min_reference_capacity(10), 10);
    assert_eq!(reference_capacity(10), 10 * REFERENCE_FACTOR);
    assert_eq!(reference_capacity(usize::MAX), usize::MAX, "saturates");
    assert_eq!(node_capacity(10), 20 * REFERENCE_FACTOR);
    assert_eq!(max_depth_for(0), 0);
    assert_eq!(max_depth_for(1), 8);
    assert_eq!(max_depth_for(1 << 16), 8 + 21);
    assert_eq!(max_depth_for(usize::MAX), MAX_DEPTH as u32);
    assert!(max_depth_for(MAX_PRIMITIVES) as usize <= TRAVERSAL_STACK_SIZE);
    let n = KdNode::inner(2, -1.5, 7);
    assert_eq!(
        n.kind(),
        KdNodeKind::Inner {
            axis: 2,
            position: -1.5,
            first: 7
        }
    );
    assert_eq!(
        KdNode::leaf(5, 3).kind(),
        KdNodeKind::Leaf { start: 5, count: 3 }
    );
    assert!(KdNode::EMPTY.is_leaf());
}

#[test]
fn empty_input_gives_an_empty_tree_that_hits_nothing() {
    let mesh = TriangleMesh::new(&[], &[]);
    let kd = build_with(&mesh, 0, 0, &KdBuildOptions::default()).unwrap();
    assert!(kd.is_empty());
    assert_eq!(kd.bytes_used(), 0);
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert_eq!(closest_watertight(&kd, &mesh, &ray), None);
}

#[test]
fn too_small_storage_is_an_error_before_writing() {
    let (pos, tris) = soup(10, 1, 10.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tris);
    let opts = KdBuildOptions::default();
    let cases = [
        (
            0,
            10,
            10,
            KdTreeError::Capacity(crate::error::CapacityError {
                storage: crate::error::Storage::KdNodes,
                needed: 1,
                available: 0,
            }),
        ),
        (
            5,
            9,
            10,
            KdTreeError::Capacity(crate::error::CapacityError {
                storage: crate::error::Storage::KdReferences,
                needed: 10,
                available: 9,
            }),
        ),
        (
            5,
            10,
            9,
            KdTreeError::Capacity(crate::error::CapacityError {
                storage: crate::error::Storage::KdScratch,
                needed: 10,
                available: 9,
            }),
        ),
    ];
    for (n, r, s, err) in cases {
        let mut nodes = vec![KdNode::inner(1, 9.0, 9); n];
        let mut refs = vec![77u32; r];
        let mut scratch = vec![KdRef::EMPTY; s];
        let got = KdTree::build(&mesh, &mut nodes[..], &mut refs[..], &mut scratch, &opts);
        assert_eq!(got.err(), Some(err));
        assert!(nodes.iter().all(|x| *x == KdNode::inner(1, 9.0, 9)));
        assert!(refs.iter().all(|&x| x == 77));
        assert!(scratch.iter().all(|x| *x == KdRef::EMPTY));
        assert!(!std::format!("{err}").is_empty());
    }
}

#[test]
fn non_finite_primitives_are_named_or_excluded() {
    let (mut pos, mut tris) = soup(8, 2, 10.0, 1.0);
    pos[7].y = f32::NAN;
    tris[5] = [0, 1, 999];
    let mesh = TriangleMesh::new(&pos, &tris);
    let n = mesh.len();
    let err = build_with(&mesh, 64, 64, &KdBuildOptions::default()).err();
    assert_eq!(
        err,
        Some(KdTreeError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Primitive,
            index: 2
        }))
    );
    let opts = KdBuildOptions {
        exclude_non_finite: true,
        ..KdBuildOptions::default()
    };
    let kd = build_with(&mesh, node_capacity(n), reference_capacity(n), &opts).unwrap();
    assert_eq!(kd.primitive_count(), 6);
    assert_eq!(kd.source_len(), 8);
    assert!(kd.references().iter().all(|&p| p != 2 && p != 5));
    let aim = mesh.triangle(2).map(|v| v[0]).unwrap();
    let ray = Ray::new(aim + Vec3::new(0.0, 0.0, 30.0), -Vec3::Z);
    assert_ne!(closest_watertight(&kd, &mesh, &ray).map(|h| h.0), Some(2));
}

#[test]
fn closest_and_any_hit_match_brute_force_on_a_random_soup() {
    let (pos, tris) = soup(300, 3, 10.0, 2.0);
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    assert!(kd.reference_count() >= 300);
    assert!(kd.node_count() > 100, "the SAH splits: {}", kd.node_count());
    assert!(!kd.budget_exhausted());
    let mut hits = 0;
    for ray in rays(&pos, 10.0, 4) {
        check(&kd, &mesh, &ray);
        hits += usize::from(brute(&mesh, &ray).is_some());
    }
    assert!(hits > 200, "{hits}");
}

#[test]
fn traversal_prunes() {
    let (pos, tris) = soup(2000, 5, 40.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    let mut stats = TraversalStats::default();
    let mut r = Lcg(6);
    for _ in 0..100 {
        let ray = Ray::new(r.v(100.0), r.v(1.0));
        let got = closest_watertight_in(&kd, &mesh, &ray, &mut Query::new().stats(&mut stats));
        assert_eq!(got, brute(&mesh, &ray));
    }
    assert!(
        stats.primitives_tested < 100 * 200,
        "{} tests for 100 rays over 2000 triangles",
        stats.primitives_tested
    );
}

#[test]
fn coincident_triangles_tie_to_the_smallest_index() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let pos: Vec<Vec3> = (0..100).flat_map(|_| tri).collect();
    let tris: Vec<[u32; 3]> = (0..100u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    let mut tris = tris;
    tris.swap(0, 57);
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    let ray = Ray::new(Vec3::new(0.2, 0.2, 5.0), -Vec3::Z);
    let got = closest_watertight(&kd, &mesh, &ray);
    assert_eq!(got.map(|h| h.0), Some(0));
    check(&kd, &mesh, &ray);
}

/// An axis-aligned flat grid of quads (two triangles each) at `z = 0`, with rays lying in the
/// plane, through the shared edges and vertices, and in the tree's own split planes.
#[test]
fn flat_grid_shared_edges_vertices_and_split_planes() {
    let side = 12u32;
    let mut pos = Vec::new();
    for j in 0..=side {
        for i in 0..=side {
            pos.push(Vec3::new(i as f32, j as f32, 0.0));
        }
    }
    let mut tris: Vec<[u32; 3]> = crate::solids::grid_triangles(side, side).collect();
    // A second, slanted layer so that the tree has splits on every axis.
    let base = pos.len() as u32;
    for p in pos.clone() {
        pos.push(Vec3::new(p.x, p.y * 0.5, 2.0 + p.y * 0.25));
    }
    let n = tris.len();
    for k in 0..n {
        let t = tris[k];
        tris.push([t[0] + base, t[1] + base, t[2] + base]);
    }
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    let mut rays = Vec::new();
    for j in 0..=side {
        for i in 0..=side {
            let v = Vec3::new(i as f32, j as f32, 0.0);
            rays.push(Ray::new(v + Vec3::new(0.0, 0.0, 5.0), -Vec3::Z));
            rays.push(Ray::new(v + Vec3::new(0.5, 0.0, 5.0), -Vec3::Z));
            rays.push(Ray::new(
                v + Vec3::new(0.5, 0.5, -5.0),
                Vec3::new(-0.0, 0.0, 1.0),
            ));
            rays.push(Ray::new(
                v + Vec3::new(0.0, 0.0, 5.0),
                Vec3::new(0.1, 0.2, -1.0),
            ));
        }
        // In the plane of the flat layer (no hit on it), along and across the grid lines.
        rays.push(Ray::new(Vec3::new(-1.0, j as f32, 0.0), Vec3::X));
        rays.push(Ray::new(
            Vec3::new(-1.0, j as f32 + 0.5, 0.0),
            Vec3::new(1.0, 0.3, 0.0),
        ));
    }
    // Rays lying in every split plane of the tree.
    let mut r = Lcg(7);
    for node in kd.nodes() {
        if let KdNodeKind::Inner { axis, position, .. } = node.kind() {
            let mut o = r.v(30.0) + Vec3::splat(6.0);
            o[axis] = position;
            let mut d = r.v(1.0);
            d[axis] = 0.0;
            rays.push(Ray::new(o, d));
            d[axis] = -0.0;
            rays.push(Ray::new(o, d));
            let mut target = r.v(12.0) + Vec3::splat(6.0);
            target[axis] = position;
            rays.push(Ray::new(o + Vec3::Z * 9.0, target - o - Vec3::Z * 9.0));
        }
    }
    assert!(rays.len() > 700);
    for ray in &rays {
        check(&kd, &mesh, ray);
    }
}

#[test]
fn zero_area_and_point_triangles_build_and_answer_as_brute_force() {
    let mut pos = vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0), Vec3::ONE];
    pos.extend([
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
    ]);
    let tris = vec![
        [0, 1, 2],
        [3, 3, 3],
        [0, 0, 1],
        [4, 5, 6],
        [3, 3, 3],
        [0, 1, 2],
    ];
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    for ray in rays(&pos, 2.0, 8) {
        check(&kd, &mesh, &ray);
    }
    // All points: a single point cell, nothing is hit.
    let pts = [Vec3::ONE; 3];
    let tris = vec![[0u32, 1, 2]; 20];
    let mesh = TriangleMesh::new(&pts, &tris);
    let kd = build(&mesh);
    assert_eq!(kd.node_count(), 1);
    check(&kd, &mesh, &Ray::new(Vec3::ZERO, Vec3::ONE));
}

#[test]
fn invalid_rays_visit_no_node() {
    let (pos, tris) = soup(50, 9, 10.0, 2.0);
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    let bad = [
        Ray::new(Vec3::NAN, Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::new(f32::NAN, 1.0, 0.0)),
        Ray::new(Vec3::ZERO, Vec3::new(0.0, -0.0, 0.0)),
        Ray::new(Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        Ray::with_interval(Vec3::ZERO, Vec3::X, f32::NAN, 1.0),
        Ray::with_interval(Vec3::ZERO, Vec3::X, 2.0, 1.0),
    ];
    for ray in &bad {
        let mut stats = TraversalStats::default();
        assert_eq!(
            closest_watertight_in(&kd, &mesh, ray, &mut Query::new().stats(&mut stats)),
            None
        );
        assert_eq!(
            kd.any_hit(
                ray,
                &mut |_, _: &Ray| Some((1.0, ())),
                &mut Query::new().stats(&mut stats)
            ),
            None
        );
        assert_eq!(stats.nodes_visited, 0);
    }
}

#[test]
fn huge_and_tiny_scenes_answer_as_brute_force() {
    for scale in [1.0e20f32, 1.0e-20, 3.0e15, 1.0e-30] {
        let (pos, tris) = soup(200, 10, 10.0, 2.0);
        let pos: Vec<Vec3> = pos.iter().map(|p| *p * scale).collect();
        let mesh = TriangleMesh::new(&pos, &tris);
        let kd = build(&mesh);
        for ray in rays(&pos, 10.0 * scale, 11) {
            check(&kd, &mesh, &ray);
        }
    }
}

#[test]
fn budgets_stop_splitting_and_stay_exact() {
    let (pos, tris) = soup(400, 12, 10.0, 3.0);
    let mesh = TriangleMesh::new(&pos, &tris);
    let n = mesh.len();
    let full = build(&mesh);
    assert!(full.reference_count() > n, "long triangles straddle planes");
    let opts = KdBuildOptions::default();
    let tight_refs = build_with(&mesh, node_capacity(n), n, &opts).unwrap();
    assert!(tight_refs.budget_exhausted());
    assert_eq!(tight_refs.reference_count(), n);
    let one_node = build_with(&mesh, 1, reference_capacity(n), &opts).unwrap();
    assert!(one_node.budget_exhausted());
    assert_eq!(one_node.node_count(), 1);
    let few_nodes = build_with(&mesh, 40, reference_capacity(n), &opts).unwrap();
    assert!(few_nodes.node_count() <= 40);
    let mut seen = vec![false; n];
    for &p in tight_refs.references() {
        assert!(
            !seen[p as usize],
            "reference {p} twice with no budget to spare"
        );
        seen[p as usize] = true;
    }
    for ray in rays(&pos, 10.0, 13) {
        check(&tight_refs, &mesh, &ray);
        check(&one_node, &mesh, &ray);
        check(&few_nodes, &mesh, &ray);
    }
}

/// Every reference of a leaf overlaps the leaf's cell, and every primitive's box is covered
/// by the cells of the leaves that reference it (checked on the box's corners and centre).
#[test]
fn leaves_cover_their_primitives() {
    let (pos, tris) = soup(300, 14, 10.0, 3.0);
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    let mut cells = Vec::new();
    let mut todo = vec![(0u32, kd.bounds())];
    while let Some((i, cell)) = todo.pop() {
        match kd.nodes()[i as usize].kind() {
            KdNodeKind::Inner {
                axis,
                position,
                first,
            } => {
                assert!(position > cell.min[axis] && position < cell.max[axis]);
                let (mut b, mut a) = (cell, cell);
                b.max[axis] = position;
                a.min[axis] = position;
                todo.push((first, b));
                todo.push((first + 1, a));
            }
            KdNodeKind::Leaf { start, count } => {
                let run = &kd.references()[start as usize..(start + count) as usize];
                for &p in run {
                    assert!(mesh.primitive_bounds(p as usize).overlaps(&cell));
                }
                cells.push((cell, run.to_vec()));
            }
        }
    }
    for p in 0..mesh.len() {
        let b = mesh.primitive_bounds(p);
        for k in 0..9 {
            let q = if k == 8 {
                b.center()
            } else {
                Vec3::new(
                    if k & 1 == 0 { b.min.x } else { b.max.x },
                    if k & 2 == 0 { b.min.y } else { b.max.y },
                    if k & 4 == 0 { b.min.z } else { b.max.z },
                )
            };
            assert!(
                cells
                    .iter()
                    .any(|(c, run)| c.contains_point(q) && run.contains(&(p as u32))),
                "primitive {p} point {q:?} not covered"
            );
        }
    }
}

#[test]
fn depth_limit_holds_for_exponentially_spaced_primitives() {
    // Triangles at 2^-k: an adversarial input for median-free splitting.
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for k in 0..120u32 {
        let x = (-(k as f32)).exp2();
        pos.extend([
            Vec3::new(x, 0.0, 0.0),
            Vec3::new(x, 1.0, 0.0),
            Vec3::new(x, 0.0, 1.0),
        ]);
        tris.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let mesh = TriangleMesh::new(&pos, &tris);
    for max_depth in [0u32, 3, 64, 1000] {
        let opts = KdBuildOptions {
            max_depth,
            ..KdBuildOptions::default()
        };
        let n = mesh.len();
        let kd = build_with(&mesh, node_capacity(n), reference_capacity(n), &opts).unwrap();
        assert!(kd.depth() <= opts.depth_limit(n) as usize);
        assert!(kd.depth() <= MAX_DEPTH);
        for k in 0..120 {
            let x = (-(k as f32)).exp2();
            let ray = Ray::new(Vec3::new(x, 0.25, -1.0), Vec3::Z);
            check(&kd, &mesh, &ray);
            let ray = Ray::new(Vec3::new(-1.0, 0.25, 0.25), Vec3::X);
            check(&kd, &mesh, &ray);
        }
    }
}

#[test]
fn intervals_are_respected_inclusively() {
    let pos = [
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
    ];
    let tris = [[0, 1, 2], [3, 4, 5]];
    let mesh = TriangleMesh::new(&pos, &tris);
    let kd = build(&mesh);
    let o = Vec3::new(0.25, 0.25, 2.0);
    for (t_min, t_max) in [
        (0.0, 1.0),
        (1.0, 2.0),
        (0.0, 0.999),
        (-5.0, f32::INFINITY),
        (f32::NEG_INFINITY, 1.5),
    ] {
        let ray = Ray::with_interval(o, -Vec3::Z, t_min, t_max);
        check(&kd, &mesh, &ray);
    }
    let ray = Ray::with_interval(o, -Vec3::Z, 0.0, 1.0);
    assert_eq!(closest_watertight(&kd, &mesh, &ray).map(|h| h.0), Some(1));
    let ray = Ray::with_interval(o, -Vec3::Z, 1.0, 2.0);
    assert_eq!(closest_watertight(&kd, &mesh, &ray).map(|h| h.0), Some(0));
}

/// Relative difference allowed between the split cost `sah::best_split` reports and the
/// documented formula evaluated here, unitless: both are `f64` sums and products of at most
/// a few dozen terms in different orders (`n·2⁻⁵³ ≈ 1e-14`); `1e-12` leaves margin and is
/// still far below the gap between two candidate planes' costs.
const SAH_COST_AGREEMENT_REL: f64 = 1e-12;

/// The SAH cost of splitting the cell of extents `e` on `axis` at `s` (relative to its lower
/// corner `lo`), written from the formula in [`sah::best_split`]'s docs: half surface area
/// `xy + yz + zx`, or the length `x + y + z` for a cell flat in two axes.
fn documented_cost(
    boxes: &[([f32; 3], [f32; 3])],
    e: [f64; 3],
    lo: [f64; 3],
    axis: usize,
    s: f32,
    costs: &sah::Costs,
) -> f64 {
    let half_area = |e: [f64; 3]| e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
    let segment = half_area(e) == 0.0;
    let m = |e: [f64; 3]| {
        if segment {
            e[0] + e[1] + e[2]
        } else {
            half_area(e)
        }
    };
    let below = boxes.iter().filter(|b| b.0[axis] < s).count() as f64;
    let above = boxes.iter().filter(|b| b.1[axis] > s).count() as f64;
    let (mut eb, mut ea) = (e, e);
    eb[axis] = f64::from(s) - lo[axis];
    ea[axis] = e[axis] - eb[axis];
    let empty = if below == 0.0 || above == 0.0 {
        costs.empty_bonus
    } else {
        0.0
    };
    costs.traversal + costs.intersection * (1.0 - empty) * (m(eb) * below + m(ea) * above) / m(e)
}

/// `best_split` against the documented SAH formula: every bin boundary of every axis with
/// an extent, costed by [`documented_cost`] (references placed at bin centres, so that the
/// binned counts equal the exact ones), the first of least cost chosen; in cells with three
/// extents, flat in one axis (half area `xy`), and flat in two (a segment along each axis:
/// its length). A
/// half-perimeter measure, a wrong count or a wrong bonus changes the cost.
#[test]
fn best_split_costs_as_the_documented_sah() {
    let mut r = Lcg(43);
    let costs = [
        sah::Costs {
            traversal: 1.0,
            intersection: 1.5,
            empty_bonus: 0.0,
        },
        sah::Costs {
            traversal: 0.25,
            intersection: 4.0,
            empty_bonus: 0.5,
        },
        sah::Costs {
            traversal: 2.0,
            intersection: 1.0,
            empty_bonus: 1.0,
        },
    ];
    let mut checked = [0usize; 5];
    for trial in 0..300 {
        // Bin widths 1, 2, 0.5 (powers of two: positions exact), some axes flat.
        let flat = match trial % 5 {
            0 => [false; 3],
            1 => [false, false, true],
            2 => [false, true, true],
            3 => [true, false, true],
            _ => [true, true, false],
        };
        let e = [32.0, 64.0, 16.0].map(f64::from);
        let e: [f64; 3] = core::array::from_fn(|k| if flat[k] { 0.0 } else { e[k] });
        let lo = [-8.0, 4.0, 2.0];
        let n = 1 + (r.f() * 12.0) as usize;
        let boxes: Vec<([f32; 3], [f32; 3])> = (0..n)
            .map(|_| {
                let mut b = ([0f32; 3], [0f32; 3]);
                for k in 0..3 {
                    let w = e[k] / BIN_COUNT as f64;
                    let (mut i, mut j) = ((r.f() * 32.0) as usize, (r.f() * 32.0) as usize);
                    if i > j {
                        core::mem::swap(&mut i, &mut j);
                    }
                    b.0[k] = (lo[k] + w * (i as f64 + 0.5)) as f32;
                    b.1[k] = (lo[k] + w * (j as f64 + 0.5)) as f32;
                }
                b
            })
            .collect();
        let refs: Vec<KdRef> = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| KdRef {
                min: b.0,
                max: b.1,
                prim: i as u32,
            })
            .collect();
        let cell = crate::aabb::Aabb::new(
            Vec3::from_array(lo.map(|x| x as f32)),
            Vec3::from_array(core::array::from_fn(|k| (lo[k] + e[k]) as f32)),
        );
        let c = &costs[trial % 3];
        let mut want: Option<(usize, f32, f64)> = None;
        for axis in (0..3).filter(|&k| e[k] > 0.0) {
            for k in 1..BIN_COUNT {
                let s = (lo[axis] + e[axis] * k as f64 / BIN_COUNT as f64) as f32;
                let cost = documented_cost(&boxes, e, lo, axis, s, c);
                if want.is_none_or(|w| cost < w.2) {
                    want = Some((axis, s, cost));
                }
            }
        }
        let (axis, s, cost) = want.unwrap();
        let got = sah::best_split(&refs, &cell, c).unwrap();
        assert_eq!((got.axis, got.position), (axis, s), "trial {trial}");
        assert!(
            (got.cost - cost).abs() <= SAH_COST_AGREEMENT_REL * cost,
            "trial {trial}: {} against {cost}",
            got.cost
        );
        checked[trial % 5] += 1;
    }
    assert!(checked.iter().all(|&k| k == 60));
    // A point cell cannot be split.
    let point = crate::aabb::Aabb::new(Vec3::ONE, Vec3::ONE);
    let r = [KdRef {
        min: [1.0; 3],
        max: [1.0; 3],
        prim: 0,
    }];
    assert_eq!(sah::best_split(&r, &point, &costs[0]), None);
}

/// Worked SAH costs on a cell flat in z, `[0, 32] × [0, 64] × {0}` (half area 2048; the
/// half perimeter would be 96): one reference spanning x in `[0.5, 1.5]`, the whole of y.
/// Splitting y at 2 (one bin) leaves it in both children: `1 + 1·(1·(32·2) + 1·(32·62))/2048
/// = 2`; splitting x at 2 leaves an empty child above (bonus 0.5): `1 + 0.5·(2·64·1)/2048 =
/// 1.03125`, the least.
#[test]
fn best_split_worked_cost_of_a_cell_flat_in_one_axis() {
    let cell = crate::aabb::Aabb::new(Vec3::ZERO, Vec3::new(32.0, 64.0, 0.0));
    let r = [KdRef {
        min: [0.5, 0.5, 0.0],
        max: [1.5, 63.5, 0.0],
        prim: 0,
    }];
    let c = sah::Costs {
        traversal: 1.0,
        intersection: 1.0,
        empty_bonus: 0.5,
    };
    let got = sah::best_split(&r, &cell, &c).unwrap();
    assert_eq!((got.axis, got.position, got.cost), (0, 2.0, 1.03125));
    // A segment cell `[0, 32] × {0} × {0}`: measured by length; the same reference split at
    // x = 2: `1 + 0.5·(2·1)/32 = 1.03125`.
    let seg = crate::aabb::Aabb::new(Vec3::ZERO, Vec3::new(32.0, 0.0, 0.0));
    let r = [KdRef {
        min: [0.5, 0.0, 0.0],
        max: [1.5, 0.0, 0.0],
        prim: 0,
    }];
    let got = sah::best_split(&r, &seg, &c).unwrap();
    assert_eq!((got.axis, got.position, got.cost), (0, 2.0, 1.03125));
}

/// `KdTree::depth` is the depth of the deepest leaf (root 0), against a walk of the public
/// node array (`KdNode::kind`: children `first` and `first + 1`): 0 for one triangle, and
/// for random soups of 2 to 400 triangles whatever the walk finds (at least 2 for the
/// larger ones).
#[test]
fn depth_is_the_deepest_leaf_of_the_node_array() {
    fn deepest(nodes: &[KdNode], i: usize) -> usize {
        match nodes[i].kind() {
            KdNodeKind::Leaf { .. } => 0,
            KdNodeKind::Inner { first, .. } => {
                let f = first as usize;
                1 + deepest(nodes, f).max(deepest(nodes, f + 1))
            }
        }
    }
    for (n, seed) in [(1, 1), (2, 2), (40, 3), (400, 4)] {
        let (pos, tris) = crate::test_util::lcg_soup(n, seed, 10.0, 1.0);
        let mesh = TriangleMesh::new(&pos, &tris);
        let kd = build(&mesh);
        let want = deepest(kd.nodes(), 0);
        assert_eq!(kd.depth(), want, "{n} triangles");
        assert!(n < 40 || want >= 2, "{n} triangles: depth {want}");
        if n == 1 {
            assert_eq!(want, 0);
        }
    }
}

/// The module docs: a primitive with **empty** (inverted, though finite) or **non-finite**
/// (infinite, though ordered) bounds is an error naming it, or left out on request. Each of
/// the two conditions alone must refuse a box (the NaN test above fails both at once).
#[test]
fn empty_or_infinite_boxes_are_named_or_excluded() {
    let unit = crate::aabb::Aabb::new(Vec3::ZERO, Vec3::ONE);
    let inverted = crate::aabb::Aabb::new(Vec3::ONE, Vec3::ZERO);
    let infinite = crate::aabb::Aabb::new(Vec3::splat(f32::NEG_INFINITY), Vec3::ONE);
    let named = |index| {
        Some(KdTreeError::NonFinite(crate::error::NonFiniteError {
            element: crate::error::InputElement::Primitive,
            index,
        }))
    };
    for bad in [inverted, infinite] {
        let boxes = [unit, bad, unit];
        let err = vec_kd(&boxes[..], &KdBuildOptions::default()).err();
        assert_eq!(err, named(1), "{bad:?}");
        let opts = KdBuildOptions {
            exclude_non_finite: true,
            ..KdBuildOptions::default()
        };
        let kd = vec_kd(&boxes[..], &opts).unwrap();
        assert_eq!(kd.primitive_count(), 2, "{bad:?}");
        assert!(kd.references().iter().all(|&p| p != 1), "{bad:?}");
    }
}

/// The kd-tree of `src` (`n` primitives) built over storage of `4n` entries and a scratch
/// holding records of primitive 99 (as an earlier build over 100 boxes leaves them), and
/// its distinct references, sorted.
fn build_with_stale_scratch(
    src: &impl PrimitiveSource,
    n: usize,
    options: &KdBuildOptions,
) -> (KdTree<Vec<KdNode>, Vec<u32>>, Vec<u32>) {
    let stale = KdRef {
        min: [0.0; 3],
        max: [1.0; 3],
        prim: 99,
    };
    let mut scratch = vec![stale; 4 * n];
    let kd = KdTree::build(
        src,
        vec![KdNode::EMPTY; 4 * n],
        vec![0u32; 4 * n],
        &mut scratch,
        options,
    )
    .unwrap();
    let mut refs = kd.references().to_vec();
    refs.sort_unstable();
    refs.dedup();
    (kd, refs)
}

/// A source whose answers change between calls (`test_util::Fickle`) is never asked for an
/// index at or beyond its count (it panics), whatever the scratch holds from before (here
/// records of primitive 99, as an earlier build over 100 boxes leaves them): the tree's
/// count, box and scratch records come from one pass. The audit's source turns primitive 0
/// NaN once each primitive has been asked once: with exclusion the one pass sees it usable;
/// without, the check does and the filling pass then leaves it out, as if excluded. Before,
/// the count came from the check and the records from a second pass that wrote fewer of them,
/// so a stale record (primitive 99) went into a leaf. Random changing sources (NaN, infinite,
/// inverted or moved answers) give trees whose references are the primitives they count.
#[test]
fn a_source_that_changes_between_passes_is_never_asked_for_a_bad_index() {
    for (exclude_non_finite, held) in [(false, vec![1u32, 2]), (true, vec![0, 1, 2])] {
        let options = KdBuildOptions {
            exclude_non_finite,
            ..KdBuildOptions::default()
        };
        let src = crate::test_util::fickle_first(3);
        let (kd, refs) = build_with_stale_scratch(&src, 3, &options);
        assert_eq!((refs, kd.primitive_count()), (held.clone(), held.len()));
        let everything = Aabb::new(Vec3::splat(-10.0), Vec3::splat(10.0));
        assert!(kd.query_box(&src, &everything, |_| true) <= held.len());
        for seed in 0..100u64 {
            let n = 40;
            let src = crate::test_util::fickle_random(n, seed);
            let (kd, refs) = build_with_stale_scratch(&src, n, &options);
            assert!(
                refs.iter().all(|&p| (p as usize) < n),
                "seed {seed}: {refs:?}"
            );
            assert_eq!(refs.len(), kd.primitive_count(), "seed {seed}");
            let _ = kd.query_box(&src, &everything, |_| true);
        }
    }
}

/// `KdNode::default()` is the empty leaf storage is filled with ([`KdNode::EMPTY`]), not the
/// all-zero inner node whose first child is itself (the derived `Default` the audit found).
#[test]
fn the_default_node_is_the_empty_leaf() {
    assert_eq!(KdNode::default(), KdNode::EMPTY);
    assert!(KdNode::default().is_leaf());
    assert_eq!(
        KdNode::default().kind(),
        KdNodeKind::Leaf { start: 0, count: 0 }
    );
}

/// Every walk of a kd-tree ends, and nothing panics, when the storage's `AsRef` changes after
/// the build (the audit's `asref_hang` reproducer: closest hit looped for ever on node 0, an
/// inner node whose first child is itself). Two changed node arrays: that self-loop, and
/// shared subtrees whose children all come after their parents (node `i` splits `x = 0` with
/// children `i + 1`, `i + 2` over 60 levels: a ray or box crossing the plane enters both
/// children at every level, about 10¹² nodes for a walk that only refused backward children,
/// as the old code did). Each walk enters at most as many nodes as the tree has.
#[test]
fn every_walk_ends_when_the_storage_changes_under_the_tree() {
    use crate::test_util::{Flip, Walks};
    let (pos, tris) = soup(300, 9, 4.0, 1.0);
    let n = tris.len();
    let count = build(&TriangleMesh::new(&pos, &tris)).node_count();
    assert!(count > 62, "{count} nodes: too few for 60 shared levels");
    let self_loop: Vec<KdNode> = core::iter::once(KdNode::inner(0, 0.0, 0))
        .chain(core::iter::repeat_n(KdNode::EMPTY, count - 1))
        .collect();
    let shared: Vec<KdNode> = (0..count as u32)
        .map(|i| match i {
            0..=58 => KdNode::inner(0, 0.0, i + 1),
            _ => KdNode::leaf(0, 1),
        })
        .collect();
    for (name, changed) in [("self-loop", self_loop), ("shared subtrees", shared)] {
        let refs = reference_capacity(n);
        let (nodes, flip) = Flip::new(vec![KdNode::EMPTY; node_capacity(n)], changed);
        let mesh = TriangleMesh::new(&pos, &tris);
        let mut scratch = vec![KdRef::EMPTY; refs];
        let kd = KdTree::build(
            &mesh,
            nodes,
            vec![0u32; refs],
            &mut scratch,
            &KdBuildOptions::default(),
        )
        .unwrap();
        assert_eq!(kd.node_count(), count);
        flip.store(true, std::sync::atomic::Ordering::Relaxed);
        let ray = Ray::new(Vec3::new(-50.0, 0.1, 0.2), Vec3::X);
        let walks = Walks::new(name, kd, &pos, &tris, ray);
        walks.end("closest hit", |k, m, r| {
            let _ = closest_watertight(k, m, r);
        });
        walks.end("any hit", |k, m, r| {
            let _ = any_watertight(k, m, r);
        });
        walks.end("box query", |k, m, _| {
            let _ = k.query_box(m, &Aabb::new(Vec3::splat(-1.0), Vec3::ONE), |_| true);
        });
    }
}
