//! The conformance suite of [`RayQuery`]: every structure, through the trait only, against
//! brute-force loops over all primitives that share no code with the traversals
//! ([`brute_watertight`] for closest hit, a bounds loop for the box query).

use super::*;
use crate::bvh::BuildOptions;
use crate::bvh::wide::binary_options;
use crate::grid::{CellAssignment, GridOptions};
use crate::kdtree::KdBuildOptions;
use crate::mesh::TriangleMesh;
use crate::solids::{CUBE_TRIANGLES, CUBE_VERTICES, grid_triangles};
use crate::test_util::{
    Lcg, brute_box, brute_watertight, closest_watertight, lcg, lcg_soup, vec_bvh, vec_grid, vec_kd,
    vec_wide,
};
use crate::triangle::{TriangleIntersector, Watertight};
use std::vec;
use std::vec::Vec;

/// The test meshes: a random soup, a closed cube (shared edges and vertices), a flat grid of
/// quads (rays through its vertices meet six triangles at one `t`: the tie rule), four
/// coincident copies of one triangle (every hit a tie), and nothing.
fn meshes() -> Vec<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let mut out = vec![lcg_soup(300, 7, 10.0, 1.5)];
    out.push((CUBE_VERTICES.to_vec(), CUBE_TRIANGLES.to_vec()));
    let n = 8u32;
    let flat = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| Vec3::new(i as f32 - 4.0, j as f32 - 4.0, 0.5)))
        .collect();
    out.push((flat, grid_triangles(n, n).collect()));
    let one = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(2.0, -1.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
    ];
    out.push((one, vec![[0, 1, 2]; 4]));
    out.push((Vec::new(), Vec::new()));
    out
}

/// Rays at `mesh`: random ones through its box, ones aimed at its vertices and edge
/// midpoints, ones with a clipped interval, and invalid ones.
fn rays(mesh: &TriangleMesh<'_>, seed: u64) -> Vec<Ray> {
    let mut rng = Lcg(seed);
    let b = (0..mesh.len()).fold(Aabb::EMPTY, |b, p| b.union(mesh.primitive_bounds(p)));
    let (lo, hi) = if b.is_valid() {
        (b.min, b.max)
    } else {
        (-Vec3::ONE, Vec3::ONE)
    };
    let mut out = Vec::new();
    for k in 0..400 {
        let o = (lo + hi) * 0.5 + rng.v(3.0) * (hi - lo).max_element();
        let target = match (k % 3, mesh.triangle(k % mesh.len().max(1))) {
            (1, Some(v)) => v[k % 3],
            (2, Some(v)) => (v[0] + v[1]) * 0.5,
            _ => lo + (hi - lo) * Vec3::new(rng.f(), rng.f(), rng.f()),
        };
        out.push(Ray::new(o, target - o));
        if k % 5 == 0 {
            out.push(Ray::with_interval(o, target - o, 0.3, 0.9));
        }
    }
    out.push(Ray::new(Vec3::ZERO, Vec3::ZERO));
    out.push(Ray::new(Vec3::splat(f32::NAN), Vec3::X));
    out
}

/// Every query of `q` (built over `mesh`) against the brute-force loops.
fn conforms<Q: RayQuery>(name: &str, q: &Q, mesh: &TriangleMesh<'_>) {
    let mut tris = Triangles::new(mesh, &Watertight);
    let mut closure = |prim: u32, r: &Ray| {
        let v = mesh.triangle(prim as usize)?;
        Watertight.intersect(r, &v).map(|h| (h.t, h.t))
    };
    let mut stack = QueryStack::new();
    let mut entries = vec![StackEntry::EMPTY; QUERY_STACK_SIZE];
    let rays = rays(mesh, 11);
    let hits = rays
        .iter()
        .filter(|r| brute_watertight(mesh, r).is_some())
        .count();
    assert!(
        mesh.is_empty() || hits > rays.len() / 5,
        "{name}: {hits} hits"
    );
    for (i, ray) in rays.iter().enumerate() {
        let want = brute_watertight(mesh, ray);
        let got = q.closest_hit(ray, &mut tris, &mut Query::new());
        assert_eq!(got, want, "{name}: closest hit of ray {i} {ray:?}");
        let by_closure = q.closest_hit(ray, &mut closure, &mut Query::new());
        assert_eq!(
            by_closure,
            want.map(|(p, h)| (p, h.t)),
            "{name}: closure, ray {i}"
        );

        // Every context: the same answer and the same counters.
        let [mut a, mut b, mut c] = [TraversalStats::default(); 3];
        let own = q.closest_hit(ray, &mut tris, &mut Query::new().stats(&mut a));
        let kept = q.closest_hit(
            ray,
            &mut tris,
            &mut Query::new().stack(&mut stack).stats(&mut b),
        );
        let slice = Query::new().stack(&mut entries[..]).stats(&mut c);
        let caller = q.closest_hit(ray, &mut tris, &mut { slice });
        assert_eq!(
            (own, kept, caller),
            (want, want, Ok(want)),
            "{name}: contexts, ray {i}"
        );
        assert_eq!((a, a), (b, c), "{name}: statistics, ray {i}");
        assert!(
            want.is_none() || a.primitives_tested > 0,
            "{name}: counted, ray {i}"
        );

        let any = q.any_hit(ray, &mut tris, &mut Query::new());
        assert_eq!(any.is_some(), want.is_some(), "{name}: any hit of ray {i}");
        if let Some((p, h)) = any {
            let v = mesh.triangle(p as usize).unwrap();
            assert_eq!(
                Watertight.intersect(ray, &v),
                Some(h),
                "{name}: any hit is a hit"
            );
        }
    }

    let mut rng = Lcg(5);
    let b = (0..mesh.len()).fold(Aabb::EMPTY, |b, p| b.union(mesh.primitive_bounds(p)));
    let (lo, size) = if b.is_valid() {
        (b.min, b.max - b.min)
    } else {
        (Vec3::ZERO, Vec3::ONE)
    };
    for i in 0..60 {
        let (c, r) = (
            lo + (rng.v(1.0) + Vec3::splat(0.5)) * size,
            rng.v(0.3).abs() * size,
        );
        let query = Aabb::new(c - r, c + r);
        let mut got = Vec::new();
        let n = q.query_box(mesh, &query, |p| {
            got.push(p);
            true
        });
        got.sort_unstable();
        let want = brute_box(mesh, query.min, query.max);
        assert_eq!((n, &got), (want.len(), &want), "{name}: box {i} {query:?}");
        if want.len() > 1 {
            let mut calls = 0;
            assert_eq!(
                q.query_box(mesh, &query, |_| {
                    calls += 1;
                    false
                }),
                1,
                "{name}: stops"
            );
            assert_eq!(calls, 1);
        }
    }
    assert_eq!(
        q.query_box(mesh, &Aabb::EMPTY, |_| true),
        0,
        "{name}: empty box"
    );

    let points: Vec<Vec3> = (0..20)
        .map(|_| lo + (rng.v(1.0) + Vec3::splat(0.5)) * size)
        .collect();
    let normals: Vec<Vec3> = (0..20).map(|_| rng.v(2.0) - Vec3::ONE).collect();
    let mut out = vec![0.0; points.len()];
    let min = q.clearance(&mut tris, &points, &normals, &mut out).unwrap();
    for (k, (&p, &d)) in points.iter().zip(&normals).enumerate() {
        let want = brute_watertight(mesh, &Ray::new(p, d)).map_or(f32::INFINITY, |(_, h)| {
            (f64::from(h.t) * d.as_dvec3().length()) as f32
        });
        assert_eq!(out[k], want, "{name}: clearance {k}");
    }
    assert_eq!(min, out.iter().copied().fold(f32::INFINITY, f32::min));
    assert_eq!(q.primitive_count(), mesh.len(), "{name}: primitives");
    assert_eq!(
        q.bytes_per_triangle() > 0.0,
        !mesh.is_empty(),
        "{name}: size"
    );
}

#[test]
fn every_structure_equals_brute_force_through_the_trait() {
    for (pos, tris) in meshes() {
        let mesh = TriangleMesh::new(&pos, &tris);
        let bvh = |options: &BuildOptions| vec_bvh(&mesh, options).unwrap();
        conforms("bvh", &bvh(&BuildOptions::default()), &mesh);
        let single = BuildOptions {
            max_leaf_size: 1,
            ..BuildOptions::default()
        };
        conforms("bvh, leaves of one", &bvh(&single), &mesh);

        let binary = bvh(&binary_options(BuildOptions::default()));
        conforms("bvh8", &vec_wide::<8>(&binary, &mesh).unwrap(), &mesh);
        conforms("bvh4", &vec_wide::<4>(&binary, &mesh).unwrap(), &mesh);

        for assignment in [CellAssignment::Exact, CellAssignment::Bounds] {
            let options = GridOptions {
                assignment,
                ..GridOptions::default()
            };
            conforms("grid", &vec_grid(&mesh, &options).unwrap(), &mesh);
        }

        let kd = vec_kd(&mesh, &KdBuildOptions::default()).unwrap();
        conforms("kd-tree", &kd, &mesh);
    }
}

/// A random soup of 200 triangles (seed 3), for [`one_per_leaf`].
fn deep_soup() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    lcg_soup(200, 3, 6.0, 1.0)
}

/// The BVH of `mesh` with one triangle a leaf: over [`deep_soup`], a deep tree whose walks
/// need many stack entries.
fn one_per_leaf(mesh: &TriangleMesh<'_>) -> crate::test_util::VecBvh {
    let single = BuildOptions {
        max_leaf_size: 1,
        ..BuildOptions::default()
    };
    vec_bvh(mesh, &single).unwrap()
}

#[test]
fn a_caller_stack_too_small_is_refused_not_cut_short() {
    let (pos, tris) = deep_soup();
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = one_per_leaf(&mesh);
    let mut tris = Triangles::new(&mesh, &Watertight);
    let mut refused = 0;
    for ray in rays(&mesh, 3) {
        // A third of the tree's depth: the right answer or a refusal, never a wrong answer.
        let mut short = vec![StackEntry::EMPTY; bvh.stack_depth() / 3];
        let ctx = &mut Query::new().stack(&mut short[..]);
        match bvh.closest_hit(&ray, &mut tris, ctx) {
            Ok(found) => assert_eq!(found, brute_watertight(&mesh, &ray), "{ray:?}"),
            Err(e) => {
                assert_eq!(
                    e,
                    QueryError::StackTooSmall {
                        available: short.len()
                    }
                );
                refused += 1;
            }
        }
    }
    assert!(refused > 0, "no ray needed the whole depth");
    let ray = Ray::new(Vec3::new(-20.0, 0.1, 0.2), Vec3::X);

    let binary = vec_bvh(&mesh, &binary_options(BuildOptions::default())).unwrap();
    let wide = vec_wide::<8>(&binary, &mesh).unwrap();
    let mut less = vec![StackEntry::EMPTY; QUERY_STACK_SIZE - 1];
    let refused = wide.any_hit(&ray, &mut tris, &mut Query::new().stack(&mut less[..]));
    assert!(
        matches!(refused, Err(QueryError::StackTooSmall { .. })),
        "{refused:?}"
    );
}

/// `StackEntry::default()` is `EMPTY`, so a stack of defaults is a caller's stack like any
/// other (`[StackEntry::default(); N]`).
#[test]
fn default_stack_entries_are_empty() {
    let (d, e) = (StackEntry::default(), StackEntry::EMPTY);
    assert_eq!((d.node, d.t_enter.to_bits()), (e.node, e.t_enter.to_bits()));
    let (pos, tris) = lcg_soup(50, 9, 4.0, 1.0);
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = vec_bvh(&mesh, &BuildOptions::default()).unwrap();
    assert!(bvh.stack_depth() <= 32);
    let mut stack: [StackEntry; 32] = Default::default();
    let mut leaf = Triangles::new(&mesh, &Watertight);
    for ray in rays(&mesh, 2) {
        let got = bvh.closest_hit(&ray, &mut leaf, &mut Query::new().stack(&mut stack));
        assert_eq!(got, Ok(brute_watertight(&mesh, &ray)), "{ray:?}");
    }
}

/// A caller's stack given as an array (`.stack(&mut array)`) is its slice: every ray's
/// answer, refusals included, equals the one on `&mut array[..]`, for a stack long enough
/// and for one too short for some rays.
#[test]
fn a_caller_stack_array_answers_as_its_slice() {
    fn same<const N: usize>(bvh: &impl RayQuery, mesh: &TriangleMesh<'_>) -> (usize, usize) {
        let mut tris = Triangles::new(mesh, &Watertight);
        let mut array = [StackEntry::EMPTY; N];
        let (mut refused, mut hits) = (0, 0);
        for ray in rays(mesh, 5) {
            let by_array = bvh.closest_hit(&ray, &mut tris, &mut Query::new().stack(&mut array));
            let by_slice =
                bvh.closest_hit(&ray, &mut tris, &mut Query::new().stack(&mut array[..]));
            assert_eq!(by_array, by_slice, "{ray:?}");
            let any = bvh.any_hit(&ray, &mut tris, &mut Query::new().stack(&mut array));
            assert_eq!(any.is_err(), by_array.is_err(), "{ray:?}");
            match by_array {
                Err(e) => {
                    assert_eq!(e, QueryError::StackTooSmall { available: N });
                    refused += 1;
                }
                Ok(found) => {
                    assert_eq!(found, brute_watertight(mesh, &ray), "{ray:?}");
                    hits += usize::from(found.is_some());
                }
            }
        }
        (refused, hits)
    }
    let (pos, tris) = deep_soup();
    let mesh = TriangleMesh::new(&pos, &tris);
    let bvh = one_per_leaf(&mesh);
    assert!(bvh.stack_depth() <= 64 && bvh.stack_depth() > 6);
    let (refused, hits) = same::<64>(&bvh, &mesh);
    assert_eq!(refused, 0);
    assert!(hits > 0);
    let (refused, _) = same::<2>(&bvh, &mesh);
    assert!(refused > 0, "no ray needed more than 2 entries");
}

/// `Watertight`'s *Domain of agreement* at its ends for every structure (the fuzz targets
/// `grid`, `kdtree` and the wide trees of `bvh` narrow to it): a soup scaled by `2⁵⁵` (every
/// `|p − o|` component below `2⁵⁹`, directions with dominant component 1) and by `2⁻⁵⁰`
/// (dominant component exactly `2⁻¹⁰⁰`), as in `bvh::tests`' boundary test; the closest hit
/// of the BVH8, the grid and the kd-tree equals the brute-force loop's exactly.
#[test]
fn every_structure_equals_brute_force_at_both_ends_of_the_watertight_domain() {
    fn closest<Q: RayQuery>(q: &Q, mesh: &TriangleMesh<'_>, ray: &Ray) -> Option<(u32, f32)> {
        closest_watertight(q, mesh, ray).map(|(i, h)| (i, h.t))
    }
    for (scale, dominant) in [(2f32.powi(55), 1.0), (2f32.powi(-50), 2f32.powi(-100))] {
        let (mut pos, tris) = lcg_soup(200, 17, 10.0, 1.0);
        for v in &mut pos {
            *v *= scale;
        }
        let mesh = TriangleMesh::new(&pos, &tris);
        let binary = vec_bvh(&mesh, &binary_options(BuildOptions::default())).unwrap();
        let bvh8 = vec_wide::<8>(&binary, &mesh).unwrap();
        let grid = vec_grid(&mesh, &GridOptions::default()).unwrap();
        let kd = vec_kd(&mesh, &KdBuildOptions::default()).unwrap();
        let mut r = Lcg(5);
        let mut hits = 0;
        for _ in 0..300 {
            let o = r.v(16.0) * scale;
            let dir = r.v(10.0) * scale - o;
            let ray = Ray::new(o, dir / dir.abs().max_element() * dominant);
            let want = brute_watertight(&mesh, &ray).map(|(i, h)| (i, h.t));
            assert_eq!(
                closest(&bvh8, &mesh, &ray),
                want,
                "bvh8, scale {scale:e}: {ray:?}"
            );
            assert_eq!(
                closest(&grid, &mesh, &ray),
                want,
                "grid, scale {scale:e}: {ray:?}"
            );
            assert_eq!(
                closest(&kd, &mesh, &ray),
                want,
                "kd-tree, scale {scale:e}: {ray:?}"
            );
            hits += usize::from(want.is_some());
        }
        assert!(hits > 30, "scale {scale:e}: {hits} hits");
    }
}

/// One case of the padding tests: a root box of size `scale` (`10⁻³` to `10³`) centred up to
/// `at` (`0` for every fourth case, else up to `10⁷`) from the coordinate origin, and a ray
/// origin within `reach` (`0.5`, `2` or `100` sizes) of its centre.
struct PadCase {
    root: Aabb,
    origin: Vec3,
    scale: f32,
    at: f32,
    reach: f32,
}

/// 20 000 [`PadCase`]s from `seed`.
fn pad_cases(seed: u64) -> impl Iterator<Item = PadCase> {
    let mut s = seed;
    (0..20_000).map(move |i| PadCase::random(&mut s, i))
}

impl PadCase {
    fn random(s: &mut u64, i: usize) -> Self {
        let scale = 10f32.powf(lcg(s) * 6.0 - 3.0);
        let at = 10f32.powf(lcg(s) * 7.0) * [0.0, 1.0][usize::from(!i.is_multiple_of(4))];
        let centre = Vec3::new(lcg(s), lcg(s), lcg(s)) * 2.0 * at - at;
        let half = Vec3::new(lcg(s), lcg(s), lcg(s)) * scale;
        let reach = [0.5, 2.0, 100.0][i % 3] * scale;
        let origin = centre + (Vec3::new(lcg(s), lcg(s), lcg(s)) * 2.0 - 1.0) * reach;
        Self {
            root: Aabb::new(centre - half, centre + half),
            origin,
            scale,
            at,
            reach,
        }
    }
}

/// The box paddings ([`walk::PadFrame::pad`] in world coordinates, and the binary tree's
/// [`walk::pad_to_root`]) against their requirement, evaluated in `f64`
/// (`crate::tolerance::BVH_PROJECTION_PAD`): each shifted origin `o_i ± pad`, rounded to
/// `f32` as the node test forms it, still lies at least `γ₈·R + u·(R + pad)` beyond `o_i`,
/// `R` the exact largest `|p_i − o_i|` over the root box. Boxes from `10⁻³` to `10³` in size
/// at up to `10⁷` from the coordinate origin, origins inside, beside and far from them. And
/// the padding follows the box's reach from the origin, not the coordinates: within four
/// times `γ₁₆·R + 2u·max|o|`, where `γ₁₆·(max|o| + max|scene|)` (a padding by the
/// coordinates' magnitude) is about sixteen times more for a small box far away (then the
/// origin's two ulps are the padding: the resolution of the input).
#[test]
fn the_box_padding_covers_the_watertight_rounding_wherever_the_box_lies() {
    let u = f64::from(crate::float::F32_UNIT_ROUNDOFF);
    let gamma = |n: f64| n * u / (1.0 - n * u);
    let mut far_and_small = 0;
    for case in pad_cases(0x9AD_u64) {
        let (root, origin) = (case.root, case.origin);
        let (o, lo, hi) = (origin.as_dvec3(), root.min.as_dvec3(), root.max.as_dvec3());
        let r = (lo - o).abs().max((hi - o).abs()).max_element();
        let tight = gamma(16.0) * r + 2.0 * u * f64::from(origin.abs().max_element());
        // The frame's (kd-tree) and the frameless one's (binary tree).
        let pads = [
            walk::PadFrame::of(&root).pad(origin),
            walk::pad_to_root(&root, origin),
        ];
        for pad in pads {
            let need = gamma(8.0) * r + u * (r + f64::from(pad));
            for axis in 0..3 {
                let oi = origin[axis];
                let (up, down) = (
                    f64::from(oi + pad) - f64::from(oi),
                    f64::from(oi) - f64::from(oi - pad),
                );
                assert!(
                    up >= need && down >= need,
                    "{root:?} {origin:?}: pad {pad}, need {need}"
                );
            }
            assert!(
                f64::from(pad) <= 4.0 * tight,
                "{root:?} {origin:?}: pad {pad} against {tight}"
            );
        }
        let pad = pads[0].max(pads[1]);
        // The padding by the coordinates' magnitude, `γ₁₆·(max|o| + max|scene|)`.
        let extent = lo.abs().max(hi.abs()).max_element();
        let loose = gamma(16.0) * (o.abs().max_element() + extent);
        if case.at > 1e5 && case.scale < 1.0 && case.reach < 10.0 * case.scale {
            far_and_small += 1;
            assert!(
                loose > 8.0 * f64::from(pad),
                "{root:?} {origin:?}: {loose} against {pad}"
            );
        }
    }
    assert!(far_and_small > 100, "{far_and_small} small boxes far away");
}

/// The padding of boxes stored relative to the frame's centre ([`walk::PadFrame::local`])
/// against its requirement, evaluated in `f64`: each shifted origin `o'_i ± pad` (`o'` the
/// rounded `o − c`), rounded to `f32` as the node test forms it, still lies at least
/// `γ₈·R + u·(R + pad)` beyond the **exact** `o_i − c_i`, `R` the exact largest
/// `|p_i − o_i|` over the root box; and the box stored relative to `c` contains every exact
/// `p − c` ([`Aabb::relative_to`]). Boxes from `10⁻³` to `10³` in size at up to `10⁷` from
/// the coordinate origin. The padding then no longer depends on where the box lies: within
/// four times `γ₁₆·R + 4u·max|o'|`, and for a small box far away a small fraction of the
/// origin's own two ulps, which the world-coordinate frame ([`walk::PadFrame::of`]) cannot
/// go below.
#[test]
fn the_padding_of_boxes_relative_to_the_tree_centre_covers_the_rounding_anywhere() {
    let u = f64::from(crate::float::F32_UNIT_ROUNDOFF);
    let gamma = |n: f64| n * u / (1.0 - n * u);
    let mut far_and_small = 0;
    for case in pad_cases(0xF4A_u64) {
        let (root, origin) = (case.root, case.origin);
        let frame = walk::PadFrame::relative(&root);
        let c = frame.centre().as_dvec3();
        let (local, pad) = frame.local(origin);
        let (o, lo, hi) = (origin.as_dvec3(), root.min.as_dvec3(), root.max.as_dvec3());
        let r = (lo - o).abs().max((hi - o).abs()).max_element();
        let need = gamma(8.0) * r + u * (r + f64::from(pad));
        let stored = root.relative_to(frame.centre());
        for axis in 0..3 {
            let exact = o[axis] - c[axis];
            let li = local[axis];
            let (up, down) = (f64::from(li + pad) - exact, exact - f64::from(li - pad));
            assert!(
                up >= need && down >= need,
                "{root:?} {origin:?}: pad {pad}, need {need}"
            );
            assert!(
                f64::from(stored.min[axis]) <= lo[axis] - c[axis]
                    && f64::from(stored.max[axis]) >= hi[axis] - c[axis],
                "{root:?}: stored {stored:?}"
            );
        }
        let m = f64::from(local.abs().max_element());
        let tight = gamma(16.0) * r + 4.0 * u * m;
        assert!(
            f64::from(pad) <= 4.0 * tight,
            "{root:?} {origin:?}: pad {pad} against {tight}"
        );
        let shift = 2.0 * u * f64::from(origin.abs().max_element());
        if case.at > 1e5 && case.scale < 1.0 && case.reach < 10.0 * case.scale {
            far_and_small += 1;
            assert!(
                f64::from(pad) < 0.01 * shift,
                "{root:?} {origin:?}: {pad} against two ulps {shift}"
            );
            assert!(f64::from(walk::PadFrame::of(&root).pad(origin)) >= shift);
        }
    }
    assert!(far_and_small > 100, "{far_and_small} small boxes far away");
}
