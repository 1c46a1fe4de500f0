//! The `grid` target: small arbitrary triangle soups and rays, the uniform grid against brute
//! force.
//!
//! Layout: the `bvh` target's ([`crate::bvh::decode`]: flags, vertices, triangles, up to 8
//! rays), so every `bvh` corpus and regression input is also a `grid` input, with the flag
//! byte read as: bit 0 quantized coordinates, bit 1 [`GridOptions::exclude_non_finite`],
//! bit 2 [`CellAssignment::Bounds`] (else exact), bits 3–4 `λ` ∈ {default, 0.25, 1, 64},
//! bit 5 at most 3 cells per axis.

use super::bvh::{
    Oracle, SEED_DUPLICATES, SEED_ORIGIN, SEED_POINTS, Soup, decode, encode_quantized,
    seed_nan_vertex, seed_pyramid,
};
use super::{Enc, Seed, reached};
use glam::Vec3;
use halfray_core::grid::{CellAssignment, DEFAULT_LAMBDA, Grid, GridError, GridOptions, GridPlan};
use halfray_core::mesh::TriangleMesh;
use halfray_core::triangle::{MollerTrumbore, Watertight};

/// The grid options the flag byte selects (module docs).
pub fn options(flags: u8) -> GridOptions {
    GridOptions {
        lambda: [DEFAULT_LAMBDA, 0.25, 1.0, 64.0][usize::from(flags >> 3) & 3],
        max_cells_per_axis: if flags & 32 != 0 { 3 } else { 1024 },
        assignment: if flags & 4 != 0 {
            CellAssignment::Bounds
        } else {
            CellAssignment::Exact
        },
        exclude_non_finite: flags & 2 != 0,
    }
}

/// Fuzz target `grid`: [`check`] on the decoded soup with the flag byte's options.
pub fn grid(data: &[u8]) {
    let flags = data.first().copied().unwrap_or(0);
    check(&decode(data), &options(flags));
}

/// Triangle `i` when its vertices are in range and finite (what the grid references).
fn usable(mesh: &TriangleMesh<'_>, i: usize) -> bool {
    mesh.triangle(i)
        .is_some_and(|v| v.iter().all(|p| p.is_finite()))
}

type VecGrid = Grid<Vec<u32>, Vec<u32>>;

/// Properties of the grid on one soup:
///
/// 1. Planning fails exactly when a triangle is unusable and `exclude_non_finite` is off
///    (`NonFinite` naming the first triangle); the resolution is within `1..=max` per axis.
/// 2. One offset or one reference too few is refused with the right counts, storage
///    untouched.
/// 3. The exactly sized build has non-decreasing offsets ending at the reference count,
///    strictly increasing cell lists of usable triangles, every usable triangle in at least
///    one cell; the exact assignment's cells are subsets of the bounds assignment's.
/// 4. For every ray: `watertight` closest hit equals brute force exactly (inside the
///    watertight test's documented domain, as for the BVH), any hit agrees on hit/miss and is
///    a genuine hit; Möller–Trumbore (and `watertight` outside the domain): a genuine hit no
///    nearer than brute force's.
pub fn check(s: &Soup, opts: &GridOptions) {
    let mesh = TriangleMesh::new(&s.positions, &s.triangles);
    let n = mesh.len();
    let ctx = || format!("options {opts:?}\n  {}", s.describe_mesh());
    let live: Vec<bool> = (0..n).map(|i| usable(&mesh, i)).collect();
    let first_bad = live.iter().position(|&ok| !ok);
    // 1. Plan.
    let plan = match (GridPlan::new(&mesh, opts), first_bad) {
        (Ok(p), None) => p,
        (Ok(p), Some(_)) if opts.exclude_non_finite => p,
        (
            Err(GridError::NonFinite(halfray_core::error::NonFiniteError {
                element: halfray_core::error::InputElement::Triangle,
                index,
            })),
            Some(bad),
        ) if !opts.exclude_non_finite => {
            reached();
            assert_eq!(index, bad, "wrong NonFinite triangle\n{}", ctx());
            return;
        }
        (r, _) => panic!("plan gave {r:?} (first unusable {first_bad:?})\n{}", ctx()),
    };
    let max = opts.max_cells_per_axis.clamp(1, 1024);
    assert!(
        plan.resolution().iter().all(|&k| (1..=max).contains(&k)),
        "resolution {:?}\n{}",
        plan.resolution(),
        ctx()
    );
    let (no, nr) = (plan.required_offsets(), plan.required_references());
    // 2. Too-small storage.
    let r = Grid::build(&mesh, &plan, vec![7u32; no - 1], vec![7u32; nr]);
    assert_eq!(
        r.err(),
        Some(GridError::Capacity(halfray_core::error::CapacityError {
            storage: halfray_core::error::Storage::GridOffsets,
            needed: no,
            available: no - 1
        })),
        "{}",
        ctx()
    );
    if nr > 0 {
        let (mut off, mut refs) = (vec![7u32; no], vec![7u32; nr - 1]);
        let r = Grid::build(&mesh, &plan, &mut off[..], &mut refs[..]);
        assert_eq!(
            r.err(),
            Some(GridError::Capacity(halfray_core::error::CapacityError {
                storage: halfray_core::error::Storage::GridReferences,
                needed: nr,
                available: nr - 1
            })),
            "{}",
            ctx()
        );
        assert!(off.iter().chain(&refs).all(|&x| x == 7), "wrote\n{}", ctx());
    }
    // 3. Build and invariants.
    let grid: VecGrid = Grid::build(&mesh, &plan, vec![0; no], vec![0; nr])
        .unwrap_or_else(|e| panic!("build: {e}\n{}", ctx()));
    check_layout(&grid, &live, &ctx);
    if opts.assignment == CellAssignment::Exact {
        let wide = GridOptions {
            assignment: CellAssignment::Bounds,
            ..*opts
        };
        let p2 = GridPlan::new(&mesh, &wide).expect("same mesh plans");
        let g2: VecGrid = Grid::build(
            &mesh,
            &p2,
            vec![0; p2.required_offsets()],
            vec![0; p2.required_references()],
        )
        .expect("builds");
        assert_eq!(g2.resolution(), grid.resolution());
        let win = |g: &VecGrid, c: usize| {
            let o = g.offsets();
            g.references()[o[c] as usize..o[c + 1] as usize].to_vec()
        };
        for c in 0..grid.cell_count() {
            let (e, b) = (win(&grid, c), win(&g2, c));
            assert!(e.iter().all(|x| b.contains(x)), "cell {c}\n{}", ctx());
        }
    }
    // 4. Rays.
    Oracle::each_ray(&mesh, &live, &ctx, &s.rays, |oracle, ray| {
        oracle.check_queries(&grid, "grid", &Watertight, ray, true);
        oracle.check_queries(&grid, "grid", &MollerTrumbore::CLASSIC, ray, false);
    });
}

/// Property 3's layout invariants.
fn check_layout(grid: &VecGrid, live: &[bool], ctx: &dyn Fn() -> String) {
    let off = grid.offsets();
    assert_eq!(off.len(), grid.cell_count() + 1, "{}", ctx());
    assert_eq!(off.first(), Some(&0));
    assert_eq!(
        off.last().map(|&x| x as usize),
        Some(grid.reference_count())
    );
    assert!(off.windows(2).all(|w| w[0] <= w[1]), "offsets\n{}", ctx());
    let refs = grid.references();
    let mut seen = vec![false; live.len()];
    for w in off.windows(2) {
        let cell = &refs[w[0] as usize..w[1] as usize];
        assert!(cell.windows(2).all(|p| p[0] < p[1]), "unsorted\n{}", ctx());
        for &t in cell {
            assert!(
                live.get(t as usize) == Some(&true),
                "bad ref {t}\n{}",
                ctx()
            );
            seen[t as usize] = true;
        }
    }
    assert_eq!(seen, live, "every usable triangle in some cell\n{}", ctx());
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("grid", format!("seed-{name}"), bytes);
    let with_flags = |mut b: Vec<u8>, extra: u8| {
        b[0] |= extra;
        b
    };
    // A 4×4 flat quad pair in z = 0, cut into cells whose planes pass through the shared
    // diagonal's end points: rays at the shared edge, a vertex, and along a cell plane.
    let (quad, o) = (SEED_POINTS, SEED_ORIGIN);
    let flat = encode_quantized(
        &quad[..4],
        &[[0, 1, 2], [0, 2, 3]],
        &[
            (o, 0, 2, 4),
            (o, 0, 0, 0),
            (o, 1, 3, 4),
            (Vec3::new(2.0, 2.0, 5.0), 1, 3, 4),
        ],
    );
    s.push(t("flat-shared-edge-lambda1", with_flags(flat.clone(), 16)));
    s.push(t(
        "flat-shared-edge-bounds-3cells",
        with_flags(flat, 4 | 32),
    ));
    // Closed pyramid (shared edges and the apex), λ = 64: many cells, rays along ridges.
    let pyramid = seed_pyramid();
    let aims = [
        (o, 4, 4, 0),
        (o, 0, 4, 4),
        (Vec3::new(-3.0, 1.0, 0.5), 2, 4, 2),
        (Vec3::new(2.0, -8.0, 1.5), 0, 1, 4),
    ];
    s.push(t(
        "pyramid-lambda64",
        with_flags(encode_quantized(&quad, &pyramid, &aims), 24),
    ));
    // Coincident, duplicated and zero-area triangles (tie rule), bounds assignment.
    s.push(t(
        "duplicates-degenerate",
        with_flags(encode_quantized(&quad, &SEED_DUPLICATES, &aims), 4),
    ));
    // Raw rays: axis-parallel with ±0 components along a cell plane (x = 2), from far
    // away (the neighbour-block path) and from 1e30 (every-reference path), NaN.
    let raw_ray = |e: Enc, o: Vec3, d: Vec3| e.u8(0).vec3(o).vec3(d);
    let mut e = Enc::new().u8(1 | 8).u8(5).u8(6);
    for p in quad {
        e = e.qvec3(p);
    }
    for tri in &pyramid {
        e = e.bytes(tri);
    }
    e = raw_ray(e, Vec3::new(2.0, 2.0, 9.0), Vec3::new(0.0, -0.0, -1.0));
    e = raw_ray(e, Vec3::new(2.0, -9.0, 0.0), Vec3::new(-0.0, 1.0, 0.0));
    e = raw_ray(e, Vec3::new(1.0, 1.0, -500.0), Vec3::new(1e-3, 1e-3, 1.0));
    e = raw_ray(e, Vec3::new(1.0, 1.0, -1e30), Vec3::Z);
    e = raw_ray(e, Vec3::NAN, Vec3::Z);
    e = raw_ray(
        e,
        Vec3::new(2.0, 2.0, 1.0),
        Vec3::new(f32::INFINITY, 0.0, 1.0),
    );
    s.push(t("axis-parallel-far-nan-rays", e.done()));
    // Scaled scenes: the pyramid at 1e20 and at 1e-20, rays scaled with it.
    for (name, k) in [("huge-1e20", 1e20f32), ("tiny-1e-20", 1e-20)] {
        let mut e = Enc::new().u8(0).u8(5).u8(6);
        for p in quad {
            e = e.vec3(p * k);
        }
        for tri in &pyramid {
            e = e.bytes(tri);
        }
        e = raw_ray(e, Vec3::new(1.0, -2.0, 1.0) * k, Vec3::new(0.1, 1.0, 0.2));
        e = raw_ray(e, Vec3::new(2.0, 2.0, 9.0) * k, -Vec3::Z);
        e = raw_ray(e, Vec3::new(-9.0, 2.0, 1.0) * k, Vec3::X);
        s.push(t(name, e.done()));
    }
    // A NaN vertex and an out-of-range index, excluded; and refused.
    let raw = seed_nan_vertex().bytes(&[0, 1, 2, 0, 1, 3, 2, 1, 5]);
    let raw = raw_ray(raw, Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
    s.push(t("nan-vertex-excluded", raw.clone().done()));
    let mut refused = raw.done();
    refused[0] = 0;
    s.push(t("nan-vertex-refused", refused));
    s.push(t("empty", Enc::new().u8(1).u8(0).u8(0).u8(0).done()));
}
