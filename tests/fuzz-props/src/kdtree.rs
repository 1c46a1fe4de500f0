//! The `kdtree` target: small arbitrary triangle soups and rays, kd-tree against brute force.
//!
//! Layout: the `bvh` target's ([`super::bvh::decode`]), with the flag bits read as: bit 0
//! quantized vertex coordinates; bit 1 [`KdBuildOptions::exclude_non_finite`]; bit 2 tight
//! budgets (references and scratch of one per triangle, 7 nodes) instead of
//! [`reference_capacity`] / [`node_capacity`]; bit 3 a depth limit of 2 instead of the
//! automatic one. So the `bvh` corpus is a valid `kdtree` corpus and back.

use super::bvh::{
    Oracle, SEED_DUPLICATE_AIMS, SEED_DUPLICATES, SEED_ORIGIN, SEED_POINTS, Soup, decode,
    encode_quantized, seed_nan_vertex, seed_pyramid, usable_primitives,
};
use super::tree_oracle::checked_build;
use super::{Enc, Seed};
use glam::Vec3;
use halfray_core::kdtree::{
    KdBuildOptions, KdNode, KdNodeKind, KdRef, KdTree, KdTreeError, MAX_DEPTH, node_capacity,
    reference_capacity,
};
use halfray_core::mesh::{PrimitiveSource, TriangleMesh};
use halfray_core::triangle::{MollerTrumbore, Watertight};

type VecKd = KdTree<Vec<KdNode>, Vec<u32>>;

/// Fuzz target `kdtree`: [`check`] on the decoded soup.
pub fn kdtree(data: &[u8]) {
    let fl = data.first().copied().unwrap_or(0);
    check(&decode(data), fl & 4 != 0, fl & 8 != 0);
}

/// Properties of the kd-tree on one soup:
///
/// 1. Too-small storage (no node, one reference or scratch record fewer than triangles) is
///    refused with the matching error, nothing written.
/// 2. The build succeeds, or names the first unusable primitive when `exclude_non_finite` is
///    off; the tree's depth is within its limit and [`MAX_DEPTH`]; every usable primitive is
///    referenced, no other, and no leaf references one twice.
/// 3. For every ray, watertight: closest hit = brute force exactly (same primitive, same hit
///    record) and any hit agrees, inside the watertight test's documented domain (the `bvh`
///    target's narrowing); elsewhere, and for Möller–Trumbore always, the tree's hit is
///    genuine and no nearer than brute force's.
pub fn check(s: &Soup, tight: bool, shallow: bool) {
    let mesh = TriangleMesh::new(&s.positions, &s.triangles);
    let n = mesh.primitive_count();
    let options = KdBuildOptions {
        exclude_non_finite: s.options.exclude_non_finite,
        max_depth: if shallow { 2 } else { 0 },
        ..KdBuildOptions::default()
    };
    let ctx = || format!("options {options:?} tight {tight}\n  {}", s.describe_mesh());
    let valid = usable_primitives(&mesh);
    let first_bad = valid.iter().position(|&ok| !ok);

    // 1. Too-small storage.
    if n > 0 {
        let sentinel = KdNode::default();
        for (nodes, refs, scratch) in [(0, n, n), (1, n - 1, n), (1, n, n - 1)] {
            let mut nd = vec![sentinel; nodes];
            let mut rf = vec![u32::MAX; refs];
            let mut sc = vec![KdRef::EMPTY; scratch];
            let r = KdTree::build(&mesh, &mut nd[..], &mut rf[..], &mut sc, &options);
            let want = if nodes == 0 {
                KdTreeError::Capacity(halfray_core::error::CapacityError {
                    storage: halfray_core::error::Storage::KdNodes,
                    needed: 1,
                    available: 0,
                })
            } else if refs < n {
                KdTreeError::Capacity(halfray_core::error::CapacityError {
                    storage: halfray_core::error::Storage::KdReferences,
                    needed: n,
                    available: n - 1,
                })
            } else {
                KdTreeError::Capacity(halfray_core::error::CapacityError {
                    storage: halfray_core::error::Storage::KdScratch,
                    needed: n,
                    available: n - 1,
                })
            };
            assert_eq!(r.err(), Some(want), "too-small storage\n{}", ctx());
            assert!(
                nd.iter().all(|x| *x == sentinel)
                    && rf.iter().all(|&x| x == u32::MAX)
                    && sc.iter().all(|x| *x == KdRef::EMPTY),
                "refused build wrote into the storage\n{}",
                ctx()
            );
        }
    }

    // 2. Build.
    let (nodes, refs) = if tight {
        (7, n)
    } else {
        (node_capacity(n).max(1), reference_capacity(n))
    };
    let mut scratch = vec![KdRef::EMPTY; refs];
    let built = KdTree::build(
        &mesh,
        vec![KdNode::EMPTY; nodes],
        vec![u32::MAX; refs],
        &mut scratch,
        &options,
    );
    let non_finite = |e: &KdTreeError| match *e {
        KdTreeError::NonFinite(halfray_core::error::NonFiniteError {
            element: halfray_core::error::InputElement::Primitive,
            index,
        }) => Some(index),
        _ => None,
    };
    let exclude = options.exclude_non_finite;
    let Some(kd): Option<VecKd> = checked_build(built, non_finite, first_bad, exclude, &ctx) else {
        return;
    };
    let in_tree = check_structure(&kd, &valid, &options, &ctx);

    // 3. Rays.
    Oracle::each_ray(&mesh, &in_tree, &ctx, &s.rays, |oracle, ray| {
        oracle.check_queries(&kd, "kd-tree", &Watertight, ray, true);
        oracle.check_queries(&kd, "kd-tree", &MollerTrumbore::CLASSIC, ray, false);
    });
}

/// Property 2's structure checks; returns which primitives the tree holds.
fn check_structure(
    kd: &VecKd,
    valid: &[bool],
    options: &KdBuildOptions,
    ctx: &dyn Fn() -> String,
) -> Vec<bool> {
    let n = valid.len();
    assert!(
        kd.depth() <= options.depth_limit(n) as usize && kd.depth() <= MAX_DEPTH,
        "depth {}\n{}",
        kd.depth(),
        ctx()
    );
    let mut in_tree = vec![false; n];
    for node in kd.nodes() {
        if let KdNodeKind::Leaf { start, count } = node.kind() {
            let run = &kd.references()[start as usize..(start + count) as usize];
            for (k, &p) in run.iter().enumerate() {
                assert!(
                    (p as usize) < n && valid[p as usize] && !run[..k].contains(&p),
                    "bad reference {p} in a leaf\n{}",
                    ctx()
                );
                in_tree[p as usize] = true;
            }
        }
    }
    let expected: Vec<bool> = valid.to_vec();
    assert_eq!(in_tree, expected, "referenced primitives\n{}", ctx());
    assert_eq!(kd.primitive_count(), valid.iter().filter(|&&v| v).count());
    in_tree
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("kdtree", format!("seed-{name}"), bytes);
    let (quad, o) = (SEED_POINTS, SEED_ORIGIN);
    // Pyramid (closed fan around the apex) with rays at the apex, the ridges and the base
    // diagonal.
    let pyramid = seed_pyramid();
    let aims = [
        (o, 4, 4, 0),
        (o, 0, 4, 4),
        (o, 0, 2, 4),
        (Vec3::new(-3.0, 1.0, 0.5), 2, 4, 2),
    ];
    s.push(t("pyramid", encode_quantized(&quad, &pyramid, &aims)));
    // The same with tight budgets and a depth limit of 2 (flag bits 2 and 3).
    let mut tight = encode_quantized(&quad, &pyramid, &aims);
    tight[0] |= 4 | 8;
    s.push(t("pyramid-tight-shallow", tight));
    // Coincident triangles (tie rule), reversed copies, zero-area ones: the `bvh` seed's,
    // with a reversed copy in place of the rotated one and a third copy last.
    let mut coincident = SEED_DUPLICATES.to_vec();
    coincident[2] = [2, 1, 0];
    coincident.push([0, 1, 2]);
    s.push(t(
        "coincident-degenerate",
        encode_quantized(&quad, &coincident, &SEED_DUPLICATE_AIMS),
    ));
    // An axis-aligned flat 3×3 grid at z = 0 (shared edges and vertices), a slanted triangle
    // above it so that the tree splits, and rays in the plane z = 0, through grid vertices and
    // edge midpoints, and along the grid lines x = 1, x = 2 (where split planes fall).
    let mut grid: Vec<Vec3> = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            grid.push(Vec3::new(i as f32, j as f32, 0.0));
        }
    }
    grid.extend([Vec3::new(0.0, 0.0, 6.0), Vec3::new(3.0, 0.5, 4.0)]);
    let mut cells: Vec<[u8; 3]> = Vec::new();
    for j in 0..3u8 {
        for i in 0..3u8 {
            let a = j * 4 + i;
            cells.push([a, a + 1, a + 5]);
            cells.push([a, a + 5, a + 4]);
        }
    }
    cells.push([16, 17, 15]);
    let mut e = Enc(encode_quantized(
        &grid,
        &cells,
        &[
            (Vec3::new(1.5, 1.5, 5.0), 5, 5, 0),
            (Vec3::new(1.5, 1.5, 5.0), 5, 6, 4),
            (Vec3::new(-1.0, 1.0, 0.0), 7, 7, 0),
            (Vec3::new(1.0, -2.0, 3.0), 1, 13, 4),
            (Vec3::new(2.0, 1.5, -3.0), 6, 10, 4),
        ],
    ));
    // Raw rays: along a grid line in the plane with a −0 component, and straight down on a
    // shared vertex with ±0 components.
    e = e
        .u8(0)
        .vec3(Vec3::new(1.0, -1.0, 0.0))
        .vec3(Vec3::new(-0.0, 1.0, 0.0))
        .u8(0)
        .vec3(Vec3::new(2.0, 2.0, 3.0))
        .vec3(Vec3::new(-0.0, 0.0, -1.0))
        .u8(0)
        .vec3(Vec3::new(1.0, 2.0, -3.0))
        .vec3(Vec3::new(0.0, -0.0, 1.0));
    s.push(t("flat-grid-plane-rays", e.done()));
    // Huge (1e20) and tiny (1e-20) raw coordinates, rays aimed at vertices and edges.
    for (name, scale) in [("huge-1e20", 1.0e20f32), ("tiny-1e-20", 1.0e-20)] {
        let mut e = Enc::new().u8(0).u8(5).u8(3);
        for p in quad {
            e = e.vec3(p * scale);
        }
        e = e.bytes(&[0, 1, 4, 1, 2, 4, 0, 2, 3]);
        for (k, (a, b, s8)) in [(4u8, 4u8, 0u8), (0, 4, 4), (1, 2, 4)]
            .into_iter()
            .enumerate()
        {
            let origin = Vec3::new(1.0 + k as f32, -3.0, 5.0) * scale;
            e = e.u8(2).vec3(origin).vec3(Vec3::ZERO).u8(a).u8(b).u8(s8);
        }
        s.push(t(name, e.done()));
    }
    // NaN vertex excluded (flag bit 1) and an out-of-range index; a ray with an interval.
    let raw = seed_nan_vertex()
        .bytes(&[0, 1, 2, 0, 1, 3, 2, 1, 5])
        .u8(4)
        .vec3(Vec3::new(0.25, 0.25, 1.0))
        .vec3(-Vec3::Z)
        .f32(0.0)
        .f32(1.0)
        .u8(0)
        .vec3(Vec3::new(f32::NAN, 0.25, 1.0))
        .vec3(-Vec3::Z);
    s.push(t("nan-vertex-excluded", raw.done()));
    s.push(t(
        "out-of-range-index",
        encode_quantized(&quad[..3], &[[0, 1, 2], [0, 1, 4]], &[(o, 0, 1, 4)]),
    ));
    s.push(t("empty", Enc::new().u8(1).u8(0).u8(0).u8(0).done()));
}
