//! Half-edge meshes on the shared test meshes (`../shared/meshes`), plus property tests of
//! random edit sequences.
//!
//! Large meshes live in `Vec`-backed [`SliceMesh`]es so nothing big is on the stack.

use glam::Vec3;
use halfray_core::float::F32_UNIT_ROUNDOFF;
use halfray_core::halfedge::{
    BuildError, CollapseAt, Counts, DiffuseBoundary, DiffuseError, EdgeId, EdgeRec, FaceRec,
    HalfedgeMesh, LoopWeights, Mesh, MeshStorage, SliceMesh, VertexId, VertexRec,
    build_scratch_len, loop_beta,
};
use halfray_fuzz_props::diffuse_oracle::{F32Fit, diffuse_close, diffuse_reference};
use halfray_fuzz_props::loop_oracle::{LoopPoint, loop_close, loop_reference, reference_beta};
use halfray_tests::meshes_dir;
use proptest::prelude::*;

/// Parses the `v`/`f` lines of a shared OBJ (1-based indices).
fn load(name: &str) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let text = std::fs::read_to_string(meshes_dir().join(name)).unwrap();
    let (mut p, mut t) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f32> = it.map(|x| x.parse().unwrap()).collect();
                p.push(Vec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let c: Vec<u32> = it.map(|x| x.parse::<u32>().unwrap() - 1).collect();
                t.push([c[0], c[1], c[2]]);
            }
            _ => {}
        }
    }
    (p, t)
}

/// Owned buffers for a [`SliceMesh`].
struct Buffers {
    v: Vec<VertexRec>,
    e: Vec<EdgeRec>,
    f: Vec<FaceRec>,
}

impl Buffers {
    fn new(c: Counts) -> Self {
        Self {
            v: vec![VertexRec::EMPTY; c.vertices],
            e: vec![EdgeRec::EMPTY; c.edges],
            f: vec![FaceRec::EMPTY; c.faces],
        }
    }
    fn mesh(&mut self) -> SliceMesh<'_> {
        Mesh::from_slices(&mut self.v, &mut self.e, &mut self.f)
    }
}

/// Capacity that any build of `p`, `t` fits in (E ≤ 3F).
fn caps(p: &[Vec3], t: &[[u32; 3]]) -> Counts {
    Counts {
        vertices: p.len(),
        edges: 3 * t.len(),
        faces: t.len(),
    }
}

fn build_into<'a>(
    b: &'a mut Buffers,
    p: &[Vec3],
    t: &[[u32; 3]],
) -> Result<SliceMesh<'a>, BuildError> {
    let mut m = b.mesh();
    let mut scratch = vec![0u32; build_scratch_len(t.len())];
    m.build(p, t, &mut scratch)?;
    Ok(m)
}

fn euler<S: MeshStorage>(m: &Mesh<S>) -> i64 {
    let referenced = m.vertices().filter(|&v| !m.is_isolated(v)).count() as i64;
    referenced - m.len().edges as i64 + m.len().faces as i64
}

fn boundary_edges<S: MeshStorage>(m: &Mesh<S>) -> usize {
    m.edges().filter(|&e| m.is_boundary_edge(e)).count()
}

/// (file, χ, boundary edges, boundary loops, unreferenced vertices) from the README.
const GOOD: &[(&str, i64, usize, usize, usize)] = &[
    ("tetrahedron.obj", 2, 0, 0, 0),
    ("cube.obj", 2, 0, 0, 0),
    ("octahedron.obj", 2, 0, 0, 0),
    ("spot.obj", 2, 0, 0, 0),
    ("torus.obj", 0, 0, 0, 0),
    ("demosthenes.obj", 1, 67, 1, 0),
    ("bunny.obj", -3, 223, 5, 1113),
];

#[test]
fn shared_meshes_build_validate_and_round_trip() {
    for &(name, chi, bedges, loops, unref) in GOOD {
        let (p, t) = load(name);
        let mut buf = Buffers::new(caps(&p, &t));
        let m = build_into(&mut buf, &p, &t).unwrap_or_else(|e| panic!("{name}: {e}"));
        m.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(m.len().vertices, p.len(), "{name}");
        assert_eq!(m.len().faces, t.len(), "{name}");
        assert_eq!(euler(&m), chi, "{name}: V - E + F");
        assert_eq!(boundary_edges(&m), bedges, "{name}: boundary edges");
        assert_eq!(m.boundary_loops().count(), loops, "{name}: boundary loops");
        assert_eq!(
            m.vertices().filter(|&v| m.is_isolated(v)).count(),
            unref,
            "{name}"
        );
        // Every boundary vertex stores a boundary halfedge; one-rings terminate.
        for v in m.vertices() {
            let n = m.valence(v);
            assert!(n < 64, "{name}: valence {n}");
            if let Some(h) = m.vertex_halfedge(v) {
                let on_boundary = m.outgoing_halfedges(v).any(|g| m.face(g).is_none());
                assert_eq!(m.is_boundary_halfedge(h), on_boundary, "{name}");
            }
        }
        let mut pos = vec![Vec3::ZERO; p.len()];
        let mut tri = vec![[0u32; 3]; t.len()];
        assert_eq!(
            m.export(&mut pos, &mut tri),
            Ok((p.len(), t.len())),
            "{name}"
        );
        assert_eq!(pos, p, "{name}: positions round trip");
        assert_eq!(tri, t, "{name}: triangles round trip");
    }
}

#[test]
fn non_manifold_meshes_are_rejected_by_name() {
    let (p, t) = load("teapot.obj");
    let mut buf = Buffers::new(caps(&p, &t));
    let err = build_into(&mut buf, &p, &t).unwrap_err();
    assert!(
        matches!(err, BuildError::NonManifoldVertex { .. }),
        "teapot: {err:?}"
    );
    assert!(buf.mesh().is_empty());

    let (p, t) = load("beetle.obj");
    let mut buf = Buffers::new(caps(&p, &t));
    let err = build_into(&mut buf, &p, &t).unwrap_err();
    assert!(
        matches!(err, BuildError::NonManifoldEdge { .. }),
        "beetle: {err:?}"
    );
    // The named edge really has three or more faces.
    if let BuildError::NonManifoldEdge { a, b, .. } = err {
        let uses = t
            .iter()
            .filter(|tri| tri.contains(&a.raw()) && tri.contains(&b.raw()))
            .count();
        assert!(uses >= 3, "beetle edge {a:?}-{b:?} used {uses} times");
    }
}

fn assert_close(got: Vec3, want: &LoopPoint, what: &str) {
    assert!(loop_close(got, want), "{what}: {got} vs {want:?}");
}

/// Relative tolerance of the core's `f32` β against the published formula in `f64`: β is
/// rounded to `f32` once (`u = 2⁻²⁴` relative: `3/(8n)` is one correctly rounded division of
/// exact integers, Loop's form an `f64` value rounded to `f32`), and the two `f64` evaluations
/// differ by ~`10⁻¹⁵` (their cosines); `2u` covers both.
const BETA_REL_TOL: f64 = 2.0 * F32_UNIT_ROUNDOFF as f64;

#[test]
fn core_loop_beta_matches_the_published_formulas() {
    for weights in [LoopWeights::Loop, LoopWeights::Warren] {
        for n in 3..40 {
            let got = f64::from(loop_beta(n, weights));
            let want = reference_beta(n, weights);
            assert!(
                (got - want).abs() <= BETA_REL_TOL * want,
                "{weights:?} n={n}: {got} vs {want}"
            );
        }
    }
    // The worked values: Loop's β(6) = 1/16, Warren's β(3) = 3/16.
    assert_eq!(loop_beta(6, LoopWeights::Loop), 0.0625);
    assert_eq!(loop_beta(3, LoopWeights::Warren), 0.1875);
}

fn check_loop(name: &str, weights: LoopWeights) {
    let (p, t) = load(name);
    let mut buf = Buffers::new(caps(&p, &t));
    let m = build_into(&mut buf, &p, &t).unwrap();
    let need = m.len().after_loop();
    let mut out_buf = Buffers::new(need);
    let mut out = out_buf.mesh();
    m.subdivide_loop(&mut out, weights).unwrap();
    out.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(out.len(), need);
    assert_eq!(euler(&out), euler(&m), "{name}: χ preserved");
    assert_eq!(
        boundary_edges(&out),
        2 * boundary_edges(&m),
        "{name}: boundary edges double"
    );
    assert_eq!(
        out.boundary_loops().count(),
        m.boundary_loops().count(),
        "{name}"
    );
    let (even, odd) = loop_reference(&p, &t, |n| reference_beta(n, weights));
    for v in 0..p.len() as u32 {
        assert_close(
            out.position(VertexId::new(v)).unwrap(),
            &even[v as usize],
            name,
        );
    }
    let nv = p.len() as u32;
    for e in m.edges() {
        let [a, b] = m.edge_vertices(e).unwrap();
        let key = (a.raw().min(b.raw()), a.raw().max(b.raw()));
        assert_close(
            out.position(VertexId::new(nv + e.raw())).unwrap(),
            &odd[&key],
            name,
        );
    }
}

#[test]
fn loop_subdivision_matches_reference_on_shared_meshes() {
    for name in [
        "octahedron.obj",
        "cube.obj",
        "spot.obj",
        "torus.obj",
        "demosthenes.obj",
    ] {
        check_loop(name, LoopWeights::Warren);
    }
    check_loop("spot.obj", LoopWeights::Loop);
    check_loop("bunny.obj", LoopWeights::Warren);
}

#[test]
fn loop_two_levels_on_spot() {
    let (p, t) = load("spot.obj");
    let mut b0 = Buffers::new(caps(&p, &t));
    let m0 = build_into(&mut b0, &p, &t).unwrap();
    let c1 = m0.len().after_loop();
    let mut b1 = Buffers::new(c1);
    let mut m1 = b1.mesh();
    m0.subdivide_loop(&mut m1, LoopWeights::Warren).unwrap();
    let mut b2 = Buffers::new(c1.after_loop());
    let mut m2 = b2.mesh();
    m1.subdivide_loop(&mut m2, LoopWeights::Warren).unwrap();
    m2.validate().unwrap();
    assert_eq!(m2.len().faces, 16 * t.len());
    assert_eq!(euler(&m2), 2);
    assert_eq!(m2.boundary_loops().count(), 0);
}

/// Every position's bits (`-0.0` and `0.0` differ), by vertex slot.
fn position_bits<S: MeshStorage>(m: &Mesh<S>) -> Vec<Option<[u32; 3]>> {
    (0..m.slots().vertices as u32)
        .map(|v| {
            m.position(VertexId::new(v))
                .map(|p| p.to_array().map(f32::to_bits))
        })
        .collect()
}

/// One diffuse step worked by hand on an open square pyramid: apex 0 over the rim 1–4 (four
/// triangles, every rim edge on the boundary), rim vertex 1 lifted so that no two rim vertices
/// see the same neighbours, and an unreferenced vertex 5. Every value is a small dyadic
/// rational, so the `f64` oracle and the core's `f32` step must both give them exactly.
#[test]
fn diffuse_on_a_pyramid_by_hand() {
    let p = [
        Vec3::new(0.0, 0.0, 6.0),
        Vec3::new(6.0, 0.0, 3.0),
        Vec3::new(0.0, 6.0, 0.0),
        Vec3::new(-6.0, 0.0, 0.0),
        Vec3::new(0.0, -6.0, 0.0),
        Vec3::new(5.0, 5.0, 5.0),
    ];
    let t = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]];
    // Free, k = 1/2: x' = x + (m − x)/2, m the mean of the neighbours.
    // 0: neighbours 1–4, m = (0, 0, 3)/4 = (0, 0, 0.75), x' = (0, 0, 3.375).
    // 1: neighbours 0, 2, 4, m = (0, 0, 6)/3 = (0, 0, 2), x' = (3, 0, 2.5).
    // 2: neighbours 0, 1, 3, m = (0, 0, 9)/3 = (0, 0, 3), x' = (0, 3, 1.5).
    // 3: neighbours 0, 2, 4, m = (0, 0, 2), x' = (−3, 0, 1).
    // 4: neighbours 0, 1, 3, m = (0, 0, 3), x' = (0, −3, 1.5).
    // 5: no neighbour, stays.
    let free = [
        Vec3::new(0.0, 0.0, 3.375),
        Vec3::new(3.0, 0.0, 2.5),
        Vec3::new(0.0, 3.0, 1.5),
        Vec3::new(-3.0, 0.0, 1.0),
        Vec3::new(0.0, -3.0, 1.5),
        p[5],
    ];
    // Fixed, k = 1: the rim stays, the apex moves to its neighbours' mean (0, 0, 0.75).
    let mut fixed = p;
    fixed[0] = Vec3::new(0.0, 0.0, 0.75);
    for (k, boundary, hand) in [
        (0.5, DiffuseBoundary::Free, free),
        (1.0, DiffuseBoundary::Fixed, fixed),
    ] {
        let want = diffuse_reference(&p, &t, k, boundary);
        let mut buf = Buffers::new(caps(&p, &t));
        let mut m = build_into(&mut buf, &p, &t).unwrap();
        let mut scratch = vec![Vec3::ZERO; p.len()];
        m.diffuse(k as f32, boundary, &mut scratch).unwrap();
        for v in 0..p.len() {
            let got = m.position(VertexId::new(v as u32)).unwrap();
            assert_eq!(
                want[v].at,
                hand[v].as_dvec3(),
                "{boundary:?}: oracle at {v}"
            );
            assert_eq!(got, hand[v], "{boundary:?}: core at {v}");
            assert!(diffuse_close(got, &want[v]), "{boundary:?} {v}");
        }
        m.validate().unwrap();
    }

    // Refusals keep every position bit for bit: a short scratch, and a step whose result is
    // beyond `f32` (rim vertex 1 at x = 3·10³⁸, k = 4: x' = −3·x, which the oracle also
    // classes as an overflow).
    let mut buf = Buffers::new(caps(&p, &t));
    let mut m = build_into(&mut buf, &p, &t).unwrap();
    let kept = position_bits(&m);
    let mut scratch = vec![Vec3::ZERO; p.len()];
    assert_eq!(
        m.diffuse(0.5, DiffuseBoundary::Free, &mut scratch[..p.len() - 1]),
        Err(DiffuseError::ScratchTooSmall { needed: p.len() })
    );
    assert_eq!(position_bits(&m), kept);
    let mut huge = p;
    huge[1].x = 3e38;
    m.set_position(VertexId::new(1), huge[1]).unwrap();
    let kept = position_bits(&m);
    let want = diffuse_reference(&huge, &t, 4.0, DiffuseBoundary::Free);
    assert_eq!(want[1].f32_fit(), F32Fit::Overflows);
    assert_eq!(
        m.diffuse(4.0, DiffuseBoundary::Free, &mut scratch),
        Err(DiffuseError::NonFinite)
    );
    assert_eq!(position_bits(&m), kept);
}

/// One step with each boundary rule on shared meshes, closed (spot) and open (demosthenes;
/// bunny, with unreferenced vertices), against the `f64` oracle at every vertex. `Fixed`
/// must keep some vertices and `Free` move them, so neither comparison is vacuous.
#[test]
fn diffuse_matches_reference_on_shared_meshes() {
    for name in ["spot.obj", "demosthenes.obj", "bunny.obj"] {
        let (p, t) = load(name);
        for boundary in [DiffuseBoundary::Free, DiffuseBoundary::Fixed] {
            let want = diffuse_reference(&p, &t, 0.5, boundary);
            let mut buf = Buffers::new(caps(&p, &t));
            let mut m = build_into(&mut buf, &p, &t).unwrap();
            let mut scratch = vec![Vec3::ZERO; m.slots().vertices];
            m.diffuse(0.5, boundary, &mut scratch).unwrap();
            m.validate().unwrap();
            let mut unmoved = 0;
            for (v, want) in want.iter().enumerate() {
                let got = m.position(VertexId::new(v as u32)).unwrap();
                assert!(
                    diffuse_close(got, want),
                    "{name} {boundary:?} vertex {v}: {got} vs {want:?}"
                );
                unmoved += usize::from(got == p[v]);
            }
            assert!(unmoved < p.len() / 2, "{name} {boundary:?}: {unmoved} kept");
            if boundary == DiffuseBoundary::Fixed && name != "spot.obj" {
                assert!(unmoved > 0, "{name}: no boundary vertex kept");
            }
        }
    }
}

#[test]
fn edits_on_a_real_mesh_keep_invariants() {
    // Flip / split / collapse sweeps over demosthenes (open), then compact and export.
    let (p, t) = load("demosthenes.obj");
    let mut c = caps(&p, &t);
    c.vertices += 4000;
    c.edges += 12000;
    c.faces += 8000;
    let mut buf = Buffers::new(c);
    let mut m = build_into(&mut buf, &p, &t).unwrap();
    let chi = euler(&m);
    let ne = m.slots().edges as u32;
    let (mut flips, mut splits, mut collapses) = (0, 0, 0);
    for e in (0..ne).step_by(7) {
        flips += m.flip_edge(EdgeId::new(e)).is_ok() as usize;
    }
    m.validate().unwrap();
    for e in (0..ne).step_by(11) {
        splits += m.split_edge(EdgeId::new(e)).is_ok() as usize;
    }
    m.validate().unwrap();
    for e in (0..ne).step_by(5) {
        collapses += m
            .collapse_edge(EdgeId::new(e).halfedge(0), CollapseAt::Midpoint)
            .is_ok() as usize;
    }
    m.validate().unwrap();
    assert!(
        flips > 100 && splits > 100 && collapses > 100,
        "{flips} {splits} {collapses}"
    );
    assert_eq!(euler(&m), chi);
    assert_eq!(m.boundary_loops().count(), 1);
    m.compact(|_| {});
    m.validate().unwrap();
    let n = m.len();
    let mut pos = vec![Vec3::ZERO; n.vertices];
    let mut tri = vec![[0u32; 3]; n.faces];
    m.export(&mut pos, &mut tri).unwrap();
    let mut b2 = Buffers::new(caps(&pos, &tri));
    let again = build_into(&mut b2, &pos, &tri).unwrap();
    again.validate().unwrap();
    assert_eq!(again.len(), n);
}

/// One random edit: (kind, element, parameter).
fn op_strategy() -> impl Strategy<Value = (u8, u32, u8)> {
    (0u8..4, any::<u32>(), 0u8..6)
}

type Small = HalfedgeMesh<600, 1800, 1200>;

/// Random flip / split / collapse / smooth sequences on the (once subdivided) octahedron:
/// `validate()` after every op, refused ops leave the mesh bit-for-bit unchanged, χ is
/// preserved. Run through proptest's runner (shrinking kept) so that the test can also count
/// what was exercised: a run where every operation of a kind was refused proves nothing about
/// that kind, so each kind must have been applied many times.
#[test]
fn random_edit_sequences() {
    use proptest::test_runner::{Config, TestRunner};
    use std::cell::Cell;
    let applied: [Cell<usize>; 4] = Default::default();
    let mut runner = TestRunner::new(Config {
        cases: 48,
        ..Config::default()
    });
    let (p, t) = load("octahedron.obj");
    let result = runner.run(&proptest::collection::vec(op_strategy(), 1..120), |ops| {
        let mut base = Box::new(Small::new());
        let mut scratch = vec![0u32; build_scratch_len(t.len())];
        base.build(&p, &t, &mut scratch).unwrap();
        let mut m = Box::new(Small::new());
        base.subdivide_loop(&mut *m, LoopWeights::Warren).unwrap();
        for (kind, x, k) in ops {
            let snap = m.clone();
            let e = EdgeId::new(x % m.slots().edges.max(1) as u32);
            let ok = match kind {
                0 => m.flip_edge(e).is_ok(),
                1 => m.split_edge(e).is_ok(),
                2 => {
                    let at =
                        [CollapseAt::Head, CollapseAt::Tail, CollapseAt::Midpoint][k as usize % 3];
                    m.collapse_edge(e.halfedge(k as u32), at).is_ok()
                }
                _ => {
                    let v = VertexId::new(x % m.slots().vertices.max(1) as u32);
                    m.diffuse_vertex(v, 0.5).is_ok()
                }
            };
            prop_assert_eq!(m.validate(), Ok(()));
            if ok {
                let c = &applied[kind as usize % 4];
                c.set(c.get() + 1);
            } else {
                prop_assert!(*m == *snap, "refused op changed the mesh");
            }
            prop_assert_eq!(euler(&*m), 2);
            prop_assert_eq!(m.boundary_loops().count(), 0);
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e}");
    }
    let counts = applied.map(|c| c.get());
    assert!(
        counts.iter().all(|&c| c >= 50),
        "applied ops per kind (flip, split, collapse, smooth): {counts:?}"
    );
}
