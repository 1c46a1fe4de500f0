//! Unit tests of the half-edge module (hand-made meshes; the shared OBJ meshes are exercised
//! in `tests/tests/halfedge_meshes.rs`).

use std::string::ToString;
use std::vec;
use std::vec::Vec;

use glam::{Vec3, vec3};

use super::*;
use crate::error::{InputElement, NonFiniteError, Storage};
use crate::solids::{OCTAHEDRON_TRIANGLES, OCTAHEDRON_VERTICES};

/// Absolute tolerance for f32 results whose inputs are exact small numbers (|x| ≤ 10): a
/// handful of f32 ulps at that magnitude (ulp(8) ≈ 9.5e-7).
const TOL: f32 = 1e-5;
/// Tolerance for β values (≤ 0.2) computed in f32 against f64: one f32 ulp at 0.2 is 1.5e-8,
/// plus the f64 → f32 rounding of the cosine term.
const BETA_TOL: f64 = 1e-7;
/// Icosahedron edges have length 2; other vertex distances are ≥ 2.47. A quarter unit
/// of slack separates the two cleanly.
const ICOSA_EDGE_SLACK: f32 = 0.25;
/// Minimum distance by which the Warren and Loop results must differ for the test to count
/// as distinguishing them (the actual gaps are ≥ 0.03 on these unit-size meshes).
const WEIGHTINGS_GAP: f32 = 0.01;

type M = HalfedgeMesh<256, 768, 512>;

fn build<const V: usize, const E: usize, const F: usize>(
    p: &[Vec3],
    t: &[[u32; 3]],
) -> Result<HalfedgeMesh<V, E, F>, BuildError> {
    let mut m = HalfedgeMesh::<V, E, F>::new();
    let mut scratch = vec![0u32; build_scratch_len(t.len())];
    m.build(p, t, &mut scratch)?;
    Ok(m)
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() <= TOL
}

/// `Counts` of `vertices`, `edges` and `faces`.
fn counts(vertices: usize, edges: usize, faces: usize) -> Counts {
    Counts {
        vertices,
        edges,
        faces,
    }
}

/// The half-edge from vertex `a` to vertex `b`, or else the one from `b` to `a`.
fn halfedge_between<S: MeshStorage>(m: &Mesh<S>, a: u32, b: u32) -> Option<HalfedgeId> {
    let (a, b) = (VertexId(a), VertexId(b));
    m.find_halfedge(a, b).or_else(|| m.find_halfedge(b, a))
}

/// Vertex `v`'s Loop position with Warren's weights and with Loop's own.
fn loop_positions<S: MeshStorage>(m: &Mesh<S>, v: VertexId) -> (Vec3, Vec3) {
    let at = |w| m.loop_vertex_position(v, w).unwrap();
    (at(LoopWeights::Warren), at(LoopWeights::Loop))
}

fn tetra() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = vec![
        vec3(1., 1., 1.),
        vec3(1., -1., -1.),
        vec3(-1., 1., -1.),
        vec3(-1., -1., 1.),
    ];
    let t = vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]];
    (p, t)
}

fn octa() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    (OCTAHEDRON_VERTICES.to_vec(), OCTAHEDRON_TRIANGLES.to_vec())
}

/// Icosahedron: vertices (0, ±1, ±φ) cyclically; faces = all triples at mutual distance 2,
/// oriented outward.
fn icosa() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let phi = (1.0 + 5f32.sqrt()) / 2.0;
    let mut p = Vec::new();
    for s1 in [-1.0, 1.0] {
        for s2 in [-1.0, 1.0] {
            p.push(vec3(0.0, s1, s2 * phi));
            p.push(vec3(s1, s2 * phi, 0.0));
            p.push(vec3(s2 * phi, 0.0, s1));
        }
    }
    let adj = |a: usize, b: usize| ((p[a] - p[b]).length() - 2.0).abs() < ICOSA_EDGE_SLACK;
    let mut t = Vec::new();
    for a in 0..12 {
        for b in a + 1..12 {
            for c in b + 1..12 {
                if adj(a, b) && adj(b, c) && adj(a, c) {
                    let n = (p[b] - p[a]).cross(p[c] - p[a]);
                    let tri = if n.dot(p[a] + p[b] + p[c]) > 0.0 {
                        [a, b, c]
                    } else {
                        [a, c, b]
                    };
                    t.push(tri.map(|x| x as u32));
                }
            }
        }
    }
    (p, t)
}

/// The issue's fan: D = (4,2,0) surrounded by E, F, C, B, A counter-clockwise.
/// Vertex indices: A0 B1 C2 D3 E4 F5.
fn fan5() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let plane = [(2., 4.), (5., 7.), (7., 3.), (4., 2.), (5., 0.), (6., 1.)];
    let p = plane.iter().map(|&(x, y)| vec3(x, y, 0.)).collect();
    let t = vec![[3, 4, 5], [3, 5, 2], [3, 2, 1], [3, 1, 0], [3, 0, 4]];
    (p, t)
}

/// An open (n × n)-quad grid in the z = 0 plane, each quad split along a diagonal.
fn grid(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push(vec3(i as f32, j as f32, 0.0));
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (p, t)
}

fn euler<S: MeshStorage>(m: &Mesh<S>) -> i64 {
    let referenced = m.vertices().filter(|&v| !m.is_isolated(v)).count() as i64;
    referenced - m.len().edges as i64 + m.len().faces as i64
}

#[test]
fn record_sizes() {
    use core::mem::size_of;
    assert_eq!(size_of::<VertexRec>(), 16);
    assert_eq!(size_of::<HalfedgeRec>(), 16);
    assert_eq!(size_of::<EdgeRec>(), 32);
    assert_eq!(size_of::<FaceRec>(), 4);
    assert_eq!(size_of::<VertexId>(), 4);
    assert_eq!(size_of::<EdgeId>(), 4);
    assert_eq!(size_of::<FaceId>(), 4);
    assert_eq!(size_of::<HalfedgeId>(), 4);
}

#[test]
fn build_small_meshes() {
    let (p, t) = tetra();
    let m: M = build(&p, &t).unwrap();
    m.validate().unwrap();
    assert_eq!(m.len(), counts(4, 6, 4));
    assert_eq!(euler(&m), 2);
    assert_eq!(m.boundary_loops().count(), 0);
    assert!(
        m.vertices()
            .all(|v| m.valence(v) == 3 && !m.is_boundary_vertex(v))
    );

    let (p, t) = grid(3);
    let m: M = build(&p, &t).unwrap();
    m.validate().unwrap();
    assert_eq!(euler(&m), 1);
    assert_eq!(m.boundary_loops().count(), 1);
    let b = m.boundary_loops().next().unwrap();
    assert_eq!(m.loop_halfedges(b).count(), 12);
    // The boundary convention: boundary vertices store a boundary halfedge.
    for v in m.vertices() {
        let h = m.vertex_halfedge(v).unwrap();
        assert_eq!(
            m.is_boundary_halfedge(h),
            m.outgoing_halfedges(v).any(|g| m.face(g).is_none())
        );
    }
}

#[test]
fn build_single_triangle_and_isolated_vertex() {
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y, vec3(5., 5., 5.)];
    let m: M = build(&p, &[[0, 1, 2]]).unwrap();
    m.validate().unwrap();
    assert!(m.is_isolated(VertexId(3)));
    assert_eq!(m.vertex_halfedge(VertexId(3)), None);
    assert_eq!(m.valence(VertexId(3)), 0);
    assert_eq!(m.len(), counts(4, 3, 1));
    for v in 0..3 {
        assert!(m.is_boundary_vertex(VertexId(v)));
        assert_eq!(m.valence(VertexId(v)), 2);
        assert_eq!(m.vertex_faces(VertexId(v)).count(), 1);
    }
    let mut pos = [Vec3::ZERO; 4];
    let mut tri = [[0u32; 3]; 1];
    assert_eq!(m.export(&mut pos, &mut tri), Ok((4, 1)));
    assert_eq!(pos, p);
    assert_eq!(tri, [[0, 1, 2]]);
    assert!(matches!(
        m.export(&mut pos[..3], &mut tri),
        Err(ExportError::BufferTooSmall { .. })
    ));
}

#[test]
fn build_errors_name_the_element() {
    let p: Vec<Vec3> = (0..8)
        .map(|i| vec3(i as f32, (i * i) as f32, 0.0))
        .collect();
    let e = |t: &[[u32; 3]]| build::<8, 32, 16>(&p, t).err();
    // Bowtie: two triangles sharing only vertex 0.
    assert_eq!(
        e(&[[0, 1, 2], [0, 3, 4]]),
        Some(BuildError::NonManifoldVertex {
            vertex: VertexId(0)
        })
    );
    // Edge 0–1 used by three triangles: the third (here the last) is named.
    assert_eq!(
        e(&[[0, 1, 2], [1, 0, 3], [0, 1, 4]]),
        Some(BuildError::NonManifoldEdge {
            a: VertexId(0),
            b: VertexId(1),
            face: FaceId(2)
        })
    );
    // Edge 0–1 used by triangles 1, 3, 4 and 5 (not by 0 or 2): the third user, 4, is named,
    // not the first (1) nor the last (5).
    assert_eq!(
        e(&[
            [3, 4, 5],
            [1, 0, 3],
            [6, 7, 3],
            [0, 1, 2],
            [0, 1, 4],
            [1, 0, 5]
        ]),
        Some(BuildError::NonManifoldEdge {
            a: VertexId(0),
            b: VertexId(1),
            face: FaceId(4)
        })
    );
    // Directed edge 0→1 twice.
    assert_eq!(
        e(&[[0, 1, 2], [0, 1, 3]]),
        Some(BuildError::InconsistentOrientation {
            a: VertexId(0),
            b: VertexId(1),
            face: FaceId(1)
        })
    );
    assert_eq!(
        e(&[[0, 1, 2], [4, 5, 4]]),
        Some(BuildError::RepeatedIndex {
            face: FaceId(1),
            vertex: VertexId(4)
        })
    );
    assert_eq!(
        e(&[[0, 1, 9]]),
        Some(BuildError::IndexOutOfRange {
            face: FaceId(0),
            index: 9
        })
    );
    // The edge pass stops at the first edge in `(min, max)` order: 0–1, used twice in one
    // direction, before 5–6, used by three triangles.
    assert_eq!(
        e(&[[0, 1, 2], [0, 1, 3], [5, 6, 7], [6, 5, 4], [5, 6, 3]]),
        Some(BuildError::InconsistentOrientation {
            a: VertexId(0),
            b: VertexId(1),
            face: FaceId(1)
        })
    );
    // The edge capacity is checked after that pass: a tetrahedron (6 edges) in 5 edge slots
    // is refused for its edges, and with a NaN position for the position first.
    let (tp, tt) = tetra();
    assert!(matches!(
        build::<4, 5, 4>(&tp, &tt).err(),
        Some(BuildError::Capacity(CapacityError {
            storage: Storage::MeshSlots(ElementKind::Edge),
            needed: 6,
            available: 5
        }))
    ));
    let mut nan = tp.clone();
    nan[2].y = f32::NAN;
    assert!(matches!(
        build::<4, 5, 4>(&nan, &tt).err(),
        Some(BuildError::NonFinite(NonFiniteError { index: 2, .. }))
    ));
    // Two tetrahedra sharing one vertex: closed fans, no boundary, still a bowtie.
    let (mut tp, tt) = tetra();
    tp.extend(tp.clone().iter().skip(1).map(|v| *v + vec3(5., 0., 0.)));
    let mut t2 = tt.clone();
    t2.extend(tt.iter().map(|t| t.map(|i| if i == 0 { 0 } else { i + 3 })));
    assert_eq!(
        build::<8, 32, 16>(&tp, &t2).err(),
        Some(BuildError::NonManifoldVertex {
            vertex: VertexId(0)
        })
    );
    // Non-finite position.
    let mut bad = p.clone();
    bad[2].y = f32::NAN;
    assert_eq!(
        build::<8, 32, 16>(&bad, &[[0, 1, 2]]).err(),
        Some(BuildError::NonFinite(NonFiniteError {
            element: InputElement::Vertex,
            index: 2
        }))
    );
    // Every refusal but capacity names an input element, numbered as the caller counts.
    let three = e(&[[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
    assert_eq!(three.culprit(), Some(Culprit::Face(FaceId(2))));
    assert_eq!(
        three.numbered_from(1).to_string(),
        "non-manifold edge between vertices 1 and 2: used by more than two triangles; the third is triangle 3"
    );
    let twice = e(&[[0, 1, 2], [0, 1, 3]]).unwrap();
    assert_eq!(twice.culprit(), Some(Culprit::Face(FaceId(1))));
    assert!(
        twice
            .to_string()
            .starts_with("inconsistent orientation: triangle 1 ")
    );
    let bowtie = e(&[[0, 1, 2], [0, 3, 4]]).unwrap();
    assert_eq!(bowtie.culprit(), Some(Culprit::Vertex(VertexId(0))));
    assert!(
        bowtie
            .numbered_from(1)
            .to_string()
            .starts_with("non-manifold vertex 1 ")
    );
    let nan = build::<8, 32, 16>(&bad, &[[0, 1, 2]]).unwrap_err();
    assert_eq!(nan.culprit(), Some(Culprit::Vertex(VertexId(2))));
    assert_eq!(
        nan.numbered_from(1).to_string(),
        "vertex 3 has a NaN or infinite coordinate"
    );
    // An index at the end of `usize`, numbered from 1: the sum saturates, no overflow.
    let last = BuildError::NonFinite(crate::error::NonFiniteError::new(
        crate::error::InputElement::Vertex,
        usize::MAX,
    ));
    assert_eq!(
        last.numbered_from(1).to_string(),
        std::format!("vertex {} has a NaN or infinite coordinate", u64::MAX)
    );
    // Capacity and scratch.
    let (p, t) = tetra();
    assert!(matches!(
        build::<4, 5, 4>(&p, &t),
        Err(BuildError::Capacity(CapacityError {
            storage: Storage::MeshSlots(ElementKind::Edge),
            needed: 6,
            ..
        }))
    ));
    assert!(matches!(
        build::<3, 6, 4>(&p, &t),
        Err(BuildError::Capacity(CapacityError {
            storage: Storage::MeshSlots(ElementKind::Vertex),
            ..
        }))
    ));
    let mut m = M::new();
    let mut small = [0u32; 5];
    assert_eq!(
        m.build(&p, &t, &mut small),
        Err(BuildError::Capacity(CapacityError {
            storage: Storage::MeshBuildScratch,
            needed: 24,
            available: 5
        }))
    );
    // A failed build leaves the mesh empty.
    let mut scratch = vec![0u32; 64];
    m.build(&p, &t, &mut scratch).unwrap();
    assert!(m.build(&p, &[[0, 1, 1]], &mut scratch).is_err());
    assert!(m.is_empty());
    m.validate().unwrap();
}

#[test]
fn export_round_trip() {
    for (p, t) in [tetra(), octa(), icosa(), fan5(), grid(4)] {
        let m: M = build(&p, &t).unwrap();
        m.validate().unwrap();
        let mut pos = vec![Vec3::ZERO; p.len()];
        let mut tri = vec![[0u32; 3]; t.len()];
        assert_eq!(m.export(&mut pos, &mut tri), Ok((p.len(), t.len())));
        assert_eq!(pos, p);
        assert_eq!(tri, t);
    }
}

#[test]
fn traversal_around_interior_and_boundary_vertices() {
    let (p, t) = fan5();
    let m: M = build(&p, &t).unwrap();
    let d = VertexId(3);
    assert!(!m.is_boundary_vertex(d));
    assert_eq!(m.valence(d), 5);
    // Neighbours counter-clockwise: a rotation of E F C B A.
    let ring: Vec<u32> = m.vertex_neighbors(d).map(|v| v.0).collect();
    let ccw = [4, 5, 2, 1, 0];
    let s = ccw.iter().position(|&x| x == ring[0]).unwrap();
    assert_eq!(ring, (0..5).map(|i| ccw[(s + i) % 5]).collect::<Vec<_>>());
    assert_eq!(m.vertex_faces(d).count(), 5);
    assert_eq!(m.vertex_edges(d).count(), 5);
    // Opposite edges: start at next(halfedge(d)).edge(), then counter-clockwise.
    let h = m.vertex_halfedge(d).unwrap();
    let opp: Vec<EdgeId> = m.opposite_edges(d).collect();
    assert_eq!(opp[0], m.next(h).unwrap().edge());
    assert_eq!(opp.len(), 5);
    for (i, e) in opp.iter().enumerate() {
        let [a, b] = m.edge_vertices(*e).unwrap();
        assert!(m.is_boundary_edge(*e));
        assert!(a != d && b != d);
        // Consecutive opposite edges share a vertex: the ring is connected, in order.
        let [c, dd] = m.edge_vertices(opp[(i + 1) % 5]).unwrap();
        assert!(a == c || a == dd || b == c || b == dd);
    }
    // Counter-clockwise (the fan's faces are, seen from +z): each opposite edge's midpoint is
    // reached from the previous one by a positive turn about D (each step spans one face,
    // less than half a turn). A clockwise ring fails here.
    let at = |v: VertexId| m.position(v).unwrap();
    let mid = |e: EdgeId| {
        let [a, b] = m.edge_vertices(e).unwrap();
        (at(a) + at(b)) * 0.5 - at(d)
    };
    for i in 0..5 {
        let (u, w) = (mid(opp[i]), mid(opp[(i + 1) % 5]));
        assert!(
            u.x * w.y - u.y * w.x > 0.0,
            "opposite edges {i}, {} turn clockwise",
            i + 1
        );
    }
    // Boundary vertex A: two faces, three neighbours, finite walks.
    let a = VertexId(0);
    assert!(m.is_boundary_vertex(a));
    assert_eq!(m.valence(a), 3);
    assert_eq!(m.vertex_faces(a).count(), 2);
    assert_eq!(m.opposite_edges(a).count(), 2);
    // Face traversal.
    let f = FaceId(0);
    assert_eq!(
        m.face_vertex_iter(f).map(|v| v.0).collect::<Vec<_>>(),
        vec![3, 4, 5]
    );
    assert_eq!(
        m.face_vertices(f),
        Some([VertexId(3), VertexId(4), VertexId(5)])
    );
    assert_eq!(m.face_edges(f).count(), 3);
    let nb: Vec<FaceId> = m.face_neighbors(f).collect();
    assert_eq!(nb.len(), 2);
    assert!(nb.contains(&FaceId(1)) && nb.contains(&FaceId(4)));
    assert!(m.find_halfedge(VertexId(0), VertexId(2)).is_none());
    let h = m.find_halfedge(VertexId(3), VertexId(1)).unwrap();
    assert_eq!(
        (m.tail(h), m.head(h)),
        (Some(VertexId(3)), Some(VertexId(1)))
    );
}

#[test]
fn junk_handles_never_panic() {
    let (p, t) = fan5();
    let mut m: M = build(&p, &t).unwrap();
    let before = m.clone();
    for raw in [100, 1 << 20, u32::MAX - 1, u32::MAX] {
        let (v, e, f, h) = (VertexId(raw), EdgeId(raw), FaceId(raw), HalfedgeId(raw));
        let (v, f) = if raw == 100 {
            (VertexId(6), FaceId(5))
        } else {
            (v, f)
        };
        assert_eq!(m.position(v), None);
        assert_eq!(m.next(h), None);
        assert_eq!(m.face_vertices(f), None);
        assert_eq!(m.edge_vertices(e), None);
        assert_eq!(m.valence(v), 0);
        assert_eq!(m.outgoing_halfedges(v).count(), 0);
        assert_eq!(m.face_halfedges(f).count(), 0);
        assert_eq!(m.laplacian(v), None);
        assert_eq!(m.flip_edge(e), Err(FlipError::Dead));
        assert_eq!(m.split_edge(e), Err(SplitError::Dead));
        assert_eq!(
            m.collapse_edge(h, CollapseAt::Midpoint),
            Err(CollapseError::Dead)
        );
        assert_eq!(m.set_position(v, Vec3::ONE), Err(PositionError::Dead));
        assert_eq!(m.diffuse_vertex(v, 0.5), Err(DiffuseError::Dead));
    }
    assert_eq!(
        m.set_position(VertexId(0), Vec3::NAN),
        Err(PositionError::NonFinite)
    );
    assert_eq!(
        m.split_edge_at(EdgeId(0), Vec3::INFINITY),
        Err(SplitError::NonFinitePosition)
    );
    assert_eq!(m, before);
}

#[test]
fn loop_worked_examples_on_the_issue_fan() {
    let (p, t) = fan5();
    let m: M = build(&p, &t).unwrap();
    let (a, b, c, d, e, f) = (p[0], p[1], p[2], p[3], p[4], p[5]);
    // New vertex on BD: 3/8 (B + D) + 1/8 (A + C) = (4.5, 4.25, 0).
    let bd = m.find_halfedge(VertexId(1), VertexId(3)).unwrap().edge();
    assert!(close(
        m.loop_edge_position(bd).unwrap(),
        vec3(4.5, 4.25, 0.0)
    ));
    // D (n = 5, Warren β = 3/40): 25/40 D + 3/40 (A+B+C+E+F) = (4.375, 2.375, 0).
    assert_eq!(loop_beta(5, LoopWeights::Warren), 3.0 / 40.0);
    let dw = m
        .loop_vertex_position(VertexId(3), LoopWeights::Warren)
        .unwrap();
    assert!(close(dw, vec3(4.375, 2.375, 0.0)), "{dw}");
    // Loop's original β from the formula, in f64.
    let cos = (2.0 * std::f64::consts::PI / 5.0).cos();
    let beta = (0.625 - (0.375 + cos / 4.0).powi(2)) / 5.0;
    assert!((loop_beta(5, LoopWeights::Loop) as f64 - beta).abs() < BETA_TOL);
    let sum = (a + b + c + e + f).as_dvec3();
    let expect = (1.0 - 5.0 * beta) * d.as_dvec3() + beta * sum;
    let dl = m
        .loop_vertex_position(VertexId(3), LoopWeights::Loop)
        .unwrap();
    assert!(close(dl, expect.as_vec3()), "{dl} vs {expect}");
    assert!(
        (dl - dw).length() > WEIGHTINGS_GAP,
        "the weightings must differ at n = 5"
    );
    // Through the full subdivision: the numbering is old vertices, then one per edge.
    let mut out = HalfedgeMesh::<64, 128, 64>::new();
    m.subdivide_loop(&mut out, LoopWeights::Warren).unwrap();
    out.validate().unwrap();
    assert!(close(
        out.position(VertexId(3)).unwrap(),
        vec3(4.375, 2.375, 0.0)
    ));
    assert!(close(
        out.position(VertexId(6 + bd.0)).unwrap(),
        vec3(4.5, 4.25, 0.0)
    ));
    // Boundary rules: A is a boundary vertex with boundary neighbours B and E.
    let ap = out.position(VertexId(0)).unwrap();
    assert!(close(ap, 0.75 * a + 0.125 * (b + e)));
    let ab = m.find_halfedge(VertexId(0), VertexId(1)).unwrap().edge();
    assert!(close(
        out.position(VertexId(6 + ab.0)).unwrap(),
        0.5 * (a + b)
    ));
}

#[test]
fn loop_parallelogram_edge_vertex_is_the_midpoint() {
    // ABCD parallelogram; triangles (B, D, A)... edge BD with wings A and C.
    let p = vec![
        vec3(0., 0., 0.),
        vec3(4., 1., 0.),
        vec3(5., 4., 0.),
        vec3(1., 3., 0.),
    ];
    // A0 B1 C2 D3: triangles (A,B,D) and (B,C,D) share BD.
    let t = vec![[0, 1, 3], [1, 2, 3]];
    let m: M = build(&p, &t).unwrap();
    let bd = m.find_halfedge(VertexId(1), VertexId(3)).unwrap().edge();
    assert!(!m.is_boundary_edge(bd));
    assert!(close(
        m.loop_edge_position(bd).unwrap(),
        0.5 * (p[1] + p[3])
    ));
}

fn check_loop_on_closed(p: &[Vec3], t: &[[u32; 3]], valence: usize) {
    let m: M = build(p, t).unwrap();
    for w in [LoopWeights::Warren, LoopWeights::Loop] {
        let mut out = HalfedgeMesh::<512, 1536, 1024>::new();
        m.subdivide_loop(&mut out, w).unwrap();
        out.validate().unwrap();
        assert_eq!(out.len(), m.len().after_loop());
        assert_eq!(euler(&out), euler(&m));
        assert_eq!(out.boundary_loops().count(), 0, "closed stays closed");
        let beta = loop_beta(valence, w) as f64;
        for v in m.vertices() {
            let x = p[v.index()].as_dvec3();
            let nb: glam::DVec3 = p
                .iter()
                .filter(|q| m.vertex_neighbors(v).any(|w| p[w.index()] == **q))
                .map(|q| q.as_dvec3())
                .sum();
            let expect = (1.0 - valence as f64 * beta) * x + beta * nb;
            assert!(close(out.position(v).unwrap(), expect.as_vec3()));
        }
        // Second level.
        let mut out2 = HalfedgeMesh::<2048, 6144, 4096>::new();
        let mut c = out.clone();
        c.compact(|_| {});
        assert_eq!(c, out, "a fresh subdivision is already compact");
        out.subdivide_loop(&mut out2, w).unwrap();
        out2.validate().unwrap();
        assert_eq!(euler(&out2), 2);
        assert_eq!(out2.len(), out.len().after_loop());
    }
    let (w, l) = loop_positions(&m, VertexId(0));
    assert!(
        (w - l).length() > WEIGHTINGS_GAP,
        "weightings differ at valence {valence}"
    );
}

#[test]
fn loop_octahedron_and_icosahedron_weightings_differ() {
    let (p, t) = octa();
    check_loop_on_closed(&p, &t, 4);
    // Octahedron vertex (1,0,0): neighbours sum to 0, so x' = (1 − 4β)·x.
    let m: M = build(&p, &t).unwrap();
    let (w, l) = loop_positions(&m, VertexId(0));
    assert!(close(w, vec3(0.625, 0., 0.)));
    assert!(close(l, vec3(1.0 - 4.0 * 31.0 / 256.0, 0., 0.)));
    let (p, t) = icosa();
    assert_eq!(t.len(), 20);
    check_loop_on_closed(&p, &t, 5);
}

#[test]
fn loop_weights_agree_at_3_and_6() {
    for n in [3, 6] {
        let (w, l) = (
            loop_beta(n, LoopWeights::Warren),
            loop_beta(n, LoopWeights::Loop),
        );
        assert!(((w - l).abs() as f64) < BETA_TOL);
    }
    assert_eq!(loop_beta(3, LoopWeights::Warren), 3.0 / 16.0);
    assert!(((loop_beta(4, LoopWeights::Loop) - 31.0 / 256.0).abs() as f64) < BETA_TOL);
}

#[test]
fn loop_refusals() {
    let (p, t) = octa();
    let m: M = build(&p, &t).unwrap();
    let mut small = HalfedgeMesh::<18, 47, 32>::new();
    let r = m.subdivide_loop(&mut small, LoopWeights::Warren);
    assert!(matches!(
        r,
        Err(SubdivideError::Capacity(CapacityError {
            storage: Storage::MeshSlots(ElementKind::Edge),
            needed: 48,
            ..
        }))
    ));
    assert!(small.is_empty());
    let mut ok = HalfedgeMesh::<18, 48, 32>::new();
    m.subdivide_loop(&mut ok, LoopWeights::Warren).unwrap();
    let mut holey = m.clone();
    let e = holey.edges().next().unwrap();
    holey.split_edge(e).unwrap();
    let v = holey.vertices().last().unwrap();
    let h = holey.vertex_halfedge(v).unwrap();
    holey.collapse_edge(h, CollapseAt::Head).unwrap();
    assert_eq!(
        holey.subdivide_loop(&mut ok, LoopWeights::Warren),
        Err(SubdivideError::NotCompact)
    );
}

#[test]
fn loop_open_grid_boundary_rules() {
    let (p, t) = grid(2);
    let m: M = build(&p, &t).unwrap();
    let mut out = HalfedgeMesh::<64, 160, 64>::new();
    m.subdivide_loop(&mut out, LoopWeights::Warren).unwrap();
    out.validate().unwrap();
    assert_eq!(euler(&out), 1);
    assert_eq!(out.boundary_loops().count(), 1);
    let b = out.boundary_loops().next().unwrap();
    assert_eq!(out.loop_halfedges(b).count(), 16, "boundary edges double");
    // A flat grid stays flat and affine-invariant rules keep the straight boundary straight.
    for v in out.vertices() {
        let q = out.position(v).unwrap();
        assert_eq!(q.z, 0.0);
        if out.is_boundary_vertex(v) && ![0, 2, 6, 8].contains(&v.0) {
            // Off the corners (which the 3/4, 1/8, 1/8 rule rounds off), boundary vertices
            // stay on the boundary lines.
            assert!(
                q.x.abs() < TOL
                    || (q.x - 2.0).abs() < TOL
                    || q.y.abs() < TOL
                    || (q.y - 2.0).abs() < TOL
            );
        }
    }
    // Corner (0,0) with boundary neighbours (1,0) and (0,1).
    assert!(close(
        out.position(VertexId(0)).unwrap(),
        vec3(0.125, 0.125, 0.0)
    ));
}

#[test]
fn flip_rules_and_valence_bookkeeping() {
    let (p, t) = octa();
    let mut m: M = build(&p, &t).unwrap();
    let e = m.find_halfedge(VertexId(0), VertexId(2)).unwrap().edge();
    let h = e.halfedge(0);
    let (a, b) = (m.tail(h).unwrap(), m.head(h).unwrap());
    let c = m.head(m.next(h).unwrap()).unwrap();
    let d = m.head(m.next(h.twin()).unwrap()).unwrap();
    let val = |m: &M, v| m.valence(v);
    let before = [a, b, c, d].map(|v| val(&m, v));
    m.flip_edge(e).unwrap();
    m.validate().unwrap();
    assert_eq!(
        [a, b, c, d].map(|v| val(&m, v)),
        [before[0] - 1, before[1] - 1, before[2] + 1, before[3] + 1]
    );
    assert_eq!(m.edge_vertices(e), Some([d, c]));
    // Flipping back is legal (d and c have valence 5, a and b are no longer joined) and
    // restores the valences and the edge a–b: a flip is an involution on connectivity.
    assert_eq!(m.flip_edge(e), Ok(()));
    m.validate().unwrap();
    assert_eq!([a, b, c, d].map(|v| val(&m, v)), before);
    let back = m.edge_vertices(e).unwrap();
    assert!(back == [a, b] || back == [b, a], "{back:?}");
    // An interior vertex of valence 3 (a, after flipping a–b away again) cannot lose an edge:
    // its link is a triangle, so every edge of its fan has joined wings and is refused as a
    // duplicate before the valence rule (which only boundary vertices reach, below).
    m.flip_edge(e).unwrap();
    assert_eq!(val(&m, a), 3);
    let snap = m.clone();
    let fan: Vec<_> = m
        .edges()
        .filter(|&f| f != e && m.edge_vertices(f).is_some_and(|v| v.contains(&a)))
        .collect();
    assert_eq!(fan.len(), 3);
    for f in fan {
        assert_eq!(m.flip_edge(f), Err(FlipError::DuplicateEdge));
    }
    assert_eq!(m, snap);
    // Tetrahedron: every flip would duplicate an edge.
    let (p, t) = tetra();
    let mut m: M = build(&p, &t).unwrap();
    let snap = m.clone();
    for e in snap.edges() {
        assert_eq!(m.flip_edge(e), Err(FlipError::DuplicateEdge));
    }
    assert_eq!(m, snap);
    // Boundary edge.
    let (p, t) = fan5();
    let mut m: M = build(&p, &t).unwrap();
    let e = m.find_halfedge(VertexId(0), VertexId(1)).unwrap().edge();
    assert_eq!(m.flip_edge(e), Err(FlipError::Boundary));
    // Interior edge D–B: B has valence 3 (boundary) and would drop to 2.
    let e = m.find_halfedge(VertexId(3), VertexId(1)).unwrap().edge();
    assert_eq!(m.flip_edge(e), Err(FlipError::DegreeTooLow(VertexId(1))));
}

#[test]
fn split_interior_and_boundary_edges() {
    let (p, t) = fan5();
    let mut m: M = build(&p, &t).unwrap();
    let before = m.len();
    let e = m.find_halfedge(VertexId(3), VertexId(1)).unwrap().edge();
    let [a, b] = m.edge_vertices(e).unwrap();
    let v = m.split_edge(e).unwrap();
    m.validate().unwrap();
    assert_eq!(
        m.len(),
        counts(before.vertices + 1, before.edges + 3, before.faces + 2)
    );
    assert!(close(
        m.position(v).unwrap(),
        0.5 * (p[a.index()] + p[b.index()])
    ));
    assert_eq!(m.edge_vertices(e), Some([a, v]));
    assert_eq!(m.valence(v), 4);
    assert!(!m.is_boundary_vertex(v));
    // Boundary edge at a given point.
    let e = m.find_halfedge(VertexId(0), VertexId(1)).unwrap().edge();
    let before = m.len();
    let v = m.split_edge_at(e, vec3(3.0, 6.0, 0.0)).unwrap();
    m.validate().unwrap();
    assert_eq!(
        m.len(),
        counts(before.vertices + 1, before.edges + 2, before.faces + 1)
    );
    assert!(m.is_boundary_vertex(v));
    assert_eq!(m.valence(v), 3);
    assert_eq!(m.position(v), Some(vec3(3.0, 6.0, 0.0)));
    assert_eq!(euler(&m), 1);
}

#[test]
fn split_capacity_exact_and_one_short() {
    let (p, t) = tetra();
    // Exactly enough for one interior split: V 5, E 9, F 6.
    let mut m = build::<5, 9, 6>(&p, &t).unwrap();
    let e = EdgeId(0);
    let snap = m.clone();
    m.split_edge(e).unwrap();
    m.validate().unwrap();
    let again = m.clone();
    assert!(matches!(
        m.split_edge(EdgeId(1)),
        Err(SplitError::Capacity(_))
    ));
    assert_eq!(m, again);
    // One edge short.
    let mut m = build::<5, 8, 6>(&p, &t).unwrap();
    let short = m.clone();
    assert_eq!(
        m.split_edge(e),
        Err(SplitError::Capacity(CapacityError {
            storage: Storage::MeshSlots(ElementKind::Edge),
            needed: 3,
            available: 2
        }))
    );
    assert_eq!(m, short);
    let _ = snap;
}

#[test]
fn collapse_rules() {
    // Tetrahedron: refused (wing valence 3).
    let (p, t) = tetra();
    let mut m: M = build(&p, &t).unwrap();
    let snap = m.clone();
    for h in snap.halfedges() {
        assert!(matches!(
            m.collapse_edge(h, CollapseAt::Midpoint),
            Err(CollapseError::WingValence(_))
        ));
    }
    assert_eq!(m, snap);
    // Octahedron: the common neighbours of an edge are exactly its wings, so it collapses
    // (to a closed 5-vertex mesh).
    let (p, t) = octa();
    let mut m: M = build(&p, &t).unwrap();
    let h = m.find_halfedge(VertexId(0), VertexId(2)).unwrap();
    m.collapse_edge(h, CollapseAt::Midpoint).unwrap();
    m.validate().unwrap();
    assert_eq!(m.len(), counts(5, 9, 6));
    // Triangular bipyramid: equator a0 b1 c2, poles n3 s4. Edge a–b has wings n, s; c is a
    // common neighbour of a and b but a–b–c is not a face: the link condition fails.
    let p = vec![
        vec3(1., 0., 0.),
        vec3(-0.5, 0.8, 0.),
        vec3(-0.5, -0.8, 0.),
        Vec3::Z,
        -Vec3::Z,
    ];
    let t = vec![
        [3, 0, 1],
        [3, 1, 2],
        [3, 2, 0],
        [4, 1, 0],
        [4, 2, 1],
        [4, 0, 2],
    ];
    let mut m: M = build(&p, &t).unwrap();
    m.validate().unwrap();
    let snap = m.clone();
    let h = m.find_halfedge(VertexId(0), VertexId(1)).unwrap();
    assert_eq!(
        m.collapse_edge(h, CollapseAt::Midpoint),
        Err(CollapseError::LinkCondition(VertexId(2)))
    );
    assert_eq!(m, snap);
    // Grid: interior edge between two boundary vertices is refused.
    let (p, t) = grid(2);
    let mut m: M = build(&p, &t).unwrap();
    // Vertex ids: id(i,j) = 3j + i. Edge (1,0)–(1,1)... (1,0) boundary, (1,1) interior.
    let h = m.find_halfedge(VertexId(0), VertexId(4)).unwrap(); // (0,0)→(1,1): (0,0) boundary, (1,1) interior
    assert!(m.can_collapse_edge(h, CollapseAt::Head).is_ok());
    let h = halfedge_between(&m, 1, 3);
    assert!(h.is_none());
    let h = m.find_halfedge(VertexId(1), VertexId(5)).unwrap(); // (1,0)→(2,1): both boundary, interior edge
    assert!(!m.is_boundary_edge(h.edge()));
    // ... but the face (1, 2, 5) there is an ear (corner triangle), which is checked first.
    assert_eq!(
        m.collapse_edge(h, CollapseAt::Midpoint),
        Err(CollapseError::Ear(FaceId(2)))
    );
    {
        // A 1 × 3 strip: bottom 0..4, top 4..8; the rung 1–5 is interior, both ends boundary.
        let p: Vec<Vec3> = (0..8)
            .map(|i| vec3((i % 4) as f32, (i / 4) as f32, 0.0))
            .collect();
        let t = vec![
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
        ];
        let mut s: M = build(&p, &t).unwrap();
        let h = s.find_halfedge(VertexId(1), VertexId(5)).unwrap();
        assert!(!s.is_boundary_edge(h.edge()));
        assert_eq!(
            s.collapse_edge(h, CollapseAt::Midpoint),
            Err(CollapseError::InteriorEdgeJoinsBoundaries)
        );
        // A boundary edge of the strip collapses fine.
        let h = s.find_halfedge(VertexId(2), VertexId(1)).unwrap();
        s.collapse_edge(h, CollapseAt::Midpoint).unwrap();
        s.validate().unwrap();
        assert_eq!(euler(&s), 1);
    }
    // The boundary edge 2–5 of that corner triangle may collapse (its other edges are not
    // both boundary).
    let h = m.find_halfedge(VertexId(2), VertexId(5)).unwrap();
    assert!(m.can_collapse_edge(h, CollapseAt::Head).is_ok());
    // Fold-over: dragging the interior vertex far outside flips faces.
    let h = m.find_halfedge(VertexId(4), VertexId(0)).unwrap();
    assert!(matches!(
        m.collapse_edge(h, CollapseAt::Point(vec3(5.0, -1.0, 0.0))),
        Err(CollapseError::FoldOver(_))
    ));
    // Accepted interior → boundary collapse.
    let before = m.len();
    let v = m.collapse_edge(h, CollapseAt::Head).unwrap();
    m.validate().unwrap();
    assert_eq!(v, VertexId(0));
    assert_eq!(m.len().vertices, before.vertices - 1);
    assert_eq!(m.len().faces, before.faces - 2);
    assert_eq!(m.len().edges, before.edges - 3);
    assert_eq!(euler(&m), 1);
    // Accepted boundary-edge collapse on a strip.
    let (p, t) = grid(3);
    let mut m: M = build(&p, &t).unwrap();
    let h = halfedge_between(&m, 1, 2).unwrap();
    assert!(m.is_boundary_edge(h.edge()));
    let before = m.len();
    m.collapse_edge(h, CollapseAt::Midpoint).unwrap();
    m.validate().unwrap();
    assert_eq!(m.len().faces, before.faces - 1);
    assert_eq!(m.len().edges, before.edges - 2);
    assert_eq!(euler(&m), 1);
}

#[test]
fn diffuse_uses_old_positions() {
    let (p, t) = fan5();
    let mut m: M = build(&p, &t).unwrap();
    // Per vertex: D moves to x + k·(mean − x).
    let mean = (p[0] + p[1] + p[2] + p[4] + p[5]) / 5.0;
    let mut c = m.clone();
    let q = c.diffuse_vertex(VertexId(3), 0.5).unwrap();
    assert!(close(q, p[3] + 0.5 * (mean - p[3])));
    // Whole mesh, Jacobi: every vertex from the old positions. Expected values from the
    // triangle list alone (each vertex's neighbours: the other corners of its triangles), not
    // from the mesh's own `laplacian`.
    let expect: Vec<Vec3> = (0..p.len() as u32)
        .map(|i| {
            let mut ring: Vec<u32> = t
                .iter()
                .filter(|tri| tri.contains(&i))
                .flatten()
                .copied()
                .filter(|&j| j != i)
                .collect();
            ring.sort_unstable();
            ring.dedup();
            let mean = ring.iter().map(|&j| p[j as usize]).sum::<Vec3>() / ring.len() as f32;
            p[i as usize] + 0.25 * (mean - p[i as usize])
        })
        .collect();
    assert_eq!(m.vertices().count(), expect.len());
    let mut scratch = vec![Vec3::ZERO; 6];
    m.diffuse(0.25, DiffuseBoundary::Free, &mut scratch)
        .unwrap();
    for (v, e) in m.vertices().zip(&expect) {
        assert!(close(m.position(v).unwrap(), *e));
    }
    m.validate().unwrap();
    // Fixed boundary keeps the rim.
    let mut m: M = build(&p, &t).unwrap();
    m.diffuse(1.0, DiffuseBoundary::Fixed, &mut scratch)
        .unwrap();
    assert_eq!(m.position(VertexId(0)), Some(p[0]));
    assert!(close(m.position(VertexId(3)).unwrap(), mean));
    // Refusals leave the mesh unchanged.
    let snap = m.clone();
    assert_eq!(
        m.diffuse(f32::NAN, DiffuseBoundary::Free, &mut scratch),
        Err(DiffuseError::NonFinite)
    );
    assert_eq!(
        m.diffuse(f32::MAX, DiffuseBoundary::Free, &mut scratch),
        Err(DiffuseError::NonFinite)
    );
    assert_eq!(
        m.diffuse(0.5, DiffuseBoundary::Free, &mut scratch[..2]),
        Err(DiffuseError::ScratchTooSmall { needed: 6 })
    );
    assert_eq!(m, snap);
    // Isolated vertex unchanged.
    let mut m: M = build(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE], &[[0, 1, 2]]).unwrap();
    m.diffuse(0.5, DiffuseBoundary::Free, &mut scratch).unwrap();
    assert_eq!(m.position(VertexId(3)), Some(Vec3::ONE));
}

/// Multiset of faces as position triples rotated to a canonical start.
fn face_set<S: MeshStorage>(m: &Mesh<S>) -> Vec<[[u32; 3]; 3]> {
    let mut v: Vec<[[u32; 3]; 3]> = m
        .faces()
        .map(|f| {
            let c = m
                .face_vertices(f)
                .unwrap()
                .map(|v| m.position(v).unwrap().to_array().map(f32::to_bits));
            let k = (0..3).min_by_key(|&k| c[k]).unwrap();
            [c[k], c[(k + 1) % 3], c[(k + 2) % 3]]
        })
        .collect();
    v.sort();
    v
}

/// A small deterministic PRNG (xorshift64*), so failures replay from the seed.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn random_ops(seed: u64, p: &[Vec3], t: &[[u32; 3]], steps: usize) {
    let mut rng = Rng(seed);
    let mut m: HalfedgeMesh<400, 1200, 800> = build(p, t).unwrap();
    let chi = euler(&m);
    let loops = m.boundary_loops().count();
    let mut scratch = vec![Vec3::ZERO; 400];
    let (mut ok, mut refused) = (0, 0);
    for step in 0..steps {
        let snap = m.clone();
        let ne = m.slots().edges.max(1);
        let nv = m.slots().vertices.max(1);
        let e = EdgeId(rng.below(ne) as u32);
        let r: Result<(), ()> = match rng.below(9) {
            0 | 1 => m.flip_edge(e).map_err(|_| ()),
            2 | 3 => m.split_edge(e).map(|_| ()).map_err(|_| ()),
            4..=6 => {
                let at = [CollapseAt::Head, CollapseAt::Tail, CollapseAt::Midpoint][rng.below(3)];
                m.collapse_edge(e.halfedge(rng.below(2) as u32), at)
                    .map(|_| ())
                    .map_err(|_| ())
            }
            7 => m
                .diffuse_vertex(VertexId(rng.below(nv) as u32), 0.5)
                .map(|_| ())
                .map_err(|_| ()),
            _ => {
                if rng.below(4) == 0 {
                    let faces = face_set(&m);
                    m.compact(|_| {});
                    assert!(m.is_compact());
                    assert_eq!(
                        face_set(&m),
                        faces,
                        "seed {seed} step {step}: compact changed geometry"
                    );
                    Ok(())
                } else {
                    m.diffuse(0.25, DiffuseBoundary::Free, &mut scratch)
                        .map_err(|_| ())
                }
            }
        };
        if let Err(err) = m.validate() {
            panic!("seed {seed} step {step}: {err:?}");
        }
        match r {
            Ok(()) => ok += 1,
            Err(()) => {
                refused += 1;
                assert!(
                    m == snap,
                    "seed {seed} step {step}: refused op changed the mesh"
                );
            }
        }
        assert_eq!(euler(&m), chi, "seed {seed} step {step}");
        assert_eq!(m.boundary_loops().count(), loops, "seed {seed} step {step}");
    }
    assert!(ok > steps / 10 && refused > 0, "ok {ok} refused {refused}");
    // Finally subdivide what is left.
    m.compact(|_| {});
    let mut out = std::boxed::Box::new(HalfedgeMesh::<1600, 4800, 3200>::new());
    if m.subdivide_loop(&mut *out, LoopWeights::Warren).is_ok() {
        out.validate().unwrap();
        assert_eq!(euler(&*out), chi);
    }
}

#[test]
fn random_operation_sequences_keep_invariants() {
    let (p, t) = icosa();
    for seed in 1..=6 {
        random_ops(seed, &p, &t, 400);
    }
    let (p, t) = grid(6);
    for seed in 11..=16 {
        random_ops(seed, &p, &t, 400);
    }
    let (p, t) = octa();
    random_ops(99, &p, &t, 300);
}

#[test]
fn compact_reports_moves_and_reuses_slots() {
    let (p, t) = grid(3);
    let mut m: M = build(&p, &t).unwrap();
    let h = halfedge_between(&m, 5, 6).unwrap();
    m.collapse_edge(h, CollapseAt::Midpoint).unwrap();
    assert!(!m.is_compact());
    let slots = m.slots();
    // Tombstones are reused before new slots.
    let e = m.edges().next().unwrap();
    m.split_edge(e).unwrap();
    assert_eq!(m.slots(), slots);
    m.validate().unwrap();
    let h = halfedge_between(&m, 9, 10).unwrap();
    m.collapse_edge(h, CollapseAt::Head).unwrap();
    let faces = face_set(&m);
    let mut moves = Vec::new();
    m.compact(|mv| moves.push(mv));
    m.validate().unwrap();
    assert!(m.is_compact());
    assert!(!moves.is_empty());
    assert_eq!(face_set(&m), faces);
}

/// The variant's index in the declaration order of [`InvariantError`]. The match is
/// exhaustive (the enum's `#[non_exhaustive]` does not apply inside this crate), so a new
/// variant does not compile until it is given an index here, and
/// `validate_names_the_broken_invariant` then fails until a case breaks it.
fn invariant_index(e: InvariantError) -> usize {
    use super::error::InvariantError as IE;
    match e {
        IE::FreeList(_) => 0,
        IE::HalfedgePair(_) => 1,
        IE::DanglingLink(_) => 2,
        IE::NextPrev(_) => 3,
        IE::SelfLoop(_) => 4,
        IE::HeadTail(_) => 5,
        IE::FaceHalfedge(_) => 6,
        IE::FaceCycle(_) => 7,
        IE::IsolatedEdge(_) => 8,
        IE::BoundaryCycle(_) => 9,
        IE::VertexHalfedge(_) => 10,
        IE::VertexFan(_) => 11,
        IE::BoundaryVertexConvention(_) => 12,
        IE::NonManifoldVertex(_) => 13,
        IE::DuplicateEdge(_) => 14,
        IE::NonFinitePosition(_) => 15,
    }
}

/// Number of [`InvariantError`] variants ([`invariant_index`] numbers them `0..`).
const INVARIANT_VARIANTS: usize = 16;

/// A valid mesh whose vertex `from` is then merged into vertex `into` by hand: every
/// halfedge ending at `from` is made to end at `into`, and `from` is freed. Nothing else is
/// relinked, so `into` ends up with the fans of both.
fn merged(p: &[Vec3], t: &[[u32; 3]], from: u32, into: u32) -> M {
    let mut m: M = build(p, t).unwrap();
    m.validate().unwrap();
    for h in 0..2 * m.slots().edges as u32 {
        if m.head_raw(h) == from {
            m.set_head(h, into);
        }
    }
    m.free_vertex(from);
    m
}

/// Two triangles (0, 1, 2) and (3, 4, 5) apart, then vertex 3 merged into vertex 0: a bowtie
/// whose two boundary loops each pass through vertex 0 once.
fn bowtie() -> M {
    let p = [
        vec3(0., 0., 0.),
        vec3(1., 0., 0.),
        vec3(0., 1., 0.),
        vec3(0., 0., 0.),
        vec3(-1., 0., 0.),
        vec3(0., -1., 0.),
    ];
    merged(&p, &[[0, 1, 2], [3, 4, 5]], 3, 0)
}

/// Each case corrupts the records of a valid mesh by hand so that the named invariant is the
/// first one broken in `validate`'s documented order, and expects exactly that variant with
/// its element. Every variant has a case (checked at the end through [`invariant_index`]).
#[test]
fn validate_names_the_broken_invariant() {
    use super::error::InvariantError as IE;
    let (p, t) = fan5();
    let good: M = build(&p, &t).unwrap();
    good.validate().unwrap();
    // fan5: 6 vertices, 10 edges (5 spokes from the interior vertex 3, 5 rim edges), 5 faces.
    assert_eq!(good.slots(), counts(6, 10, 5));
    let mut seen = [false; INVARIANT_VARIANTS];
    let mut expect = |m: &M, want: IE| {
        assert_eq!(m.validate(), Err(want));
        seen[invariant_index(want)] = true;
    };

    let mut m = good.clone();
    let h = m.find_halfedge(VertexId(3), VertexId(1)).unwrap().0;
    let n = m.next_raw(h);
    let pv = m.prev_raw(h);
    if let Some(r) = m.hr_mut(h) {
        r.next = pv;
    }
    // `h` and its old `next` now fail the next/prev check; the old `prev`, whose face is now
    // a 2-cycle, fails only the later face check, and is numbered after one of them.
    assert!(pv > h.min(n), "{h} {n} {pv}");
    expect(&m, IE::NextPrev(HalfedgeId(h.min(n))));

    let mut m = good.clone();
    m.set_pos(2, Vec3::NAN);
    expect(&m, IE::NonFinitePosition(VertexId(2)));

    // Boundary vertex A storing an interior halfedge breaks the boundary convention.
    let mut m = good.clone();
    let a_int = m
        .outgoing_halfedges(VertexId(0))
        .find(|&g| m.face(g).is_some())
        .unwrap();
    m.set_out(0, a_int.0);
    expect(&m, IE::BoundaryVertexConvention(VertexId(0)));

    // A vertex whose halfedge starts elsewhere.
    let mut m = good.clone();
    m.set_out(3, h ^ 1);
    expect(&m, IE::VertexHalfedge(VertexId(3)));

    // A face pointing at a halfedge of another face.
    let mut m = good.clone();
    let other = m.fh(1);
    m.set_fh(0, other);
    expect(&m, IE::FaceCycle(FaceId(0)));

    // A halfedge whose face is a dead slot (halfedge 0 is checked first).
    let mut m = good.clone();
    m.set_face(0, 77);
    expect(&m, IE::DanglingLink(HalfedgeId(0)));

    // A wrong live count.
    let mut m = good.clone();
    m.live.faces += 1;
    expect(&m, IE::FreeList(ElementKind::Face));

    // Edge 3's second halfedge dead, its first live (liveness, and so the free lists, go by
    // the first): the pair check runs before any halfedge check.
    let mut m = good.clone();
    m.set_head(7, handles::NONE);
    expect(&m, IE::HalfedgePair(EdgeId(3)));

    // Halfedge 0 made to end at its own tail. Its twin becomes a self-loop too and the
    // halfedge before the twin no longer ends where the twin starts, but halfedge 0 is
    // checked first.
    let mut m = good.clone();
    let tail0 = m.tail_raw(0);
    m.set_head(0, tail0);
    expect(&m, IE::SelfLoop(HalfedgeId(0)));

    // Halfedge 0 made to end at a third vertex, neither its tail nor where its next starts.
    let mut m = good.clone();
    let (tail0, head0) = (m.tail_raw(0), m.head_raw(0));
    let w = (0..6).find(|&w| w != tail0 && w != head0).unwrap();
    m.set_head(0, w);
    expect(&m, IE::HeadTail(HalfedgeId(0)));

    // A sixth live face whose stored halfedge belongs to face 0: no halfedge names face 5,
    // so every halfedge check passes and only the face's own check sees it.
    let mut m = good.clone();
    let f = m.alloc_face();
    assert_eq!(f, 5);
    let h0 = m.fh(0);
    m.set_fh(f, h0);
    expect(&m, IE::FaceHalfedge(FaceId(5)));

    // A new edge 10 between two new vertices, linked into a 2-cycle with no face on either
    // side (all its links are consistent; the vertices are left isolated).
    let mut m = good.clone();
    let a = m.alloc_vertex(vec3(9., 9., 0.));
    let b = m.alloc_vertex(vec3(9., 10., 0.));
    let e = m.alloc_edge();
    assert_eq!((a, b, e), (6, 7, 10));
    m.link(20, 21);
    m.link(21, 20);
    m.set_head(20, b);
    m.set_head(21, a);
    expect(&m, IE::IsolatedEdge(EdgeId(10)));

    // An interior halfedge `g` loses its face. Its face's two other halfedges then fail the
    // face-cycle check, so `g` is chosen as the lowest-numbered halfedge of its face: it is
    // checked first and finds its `next` inside a face.
    let mut m = good.clone();
    let g = (0..5)
        .map(|f| {
            let h = m.fh(f);
            let (n, nn) = (m.next_raw(h), m.prev_raw(h));
            h.min(n).min(nn)
        })
        .find(|&g| m.face_raw(g ^ 1) != handles::NONE)
        .expect("some face's lowest halfedge is interior");
    m.set_face(g, handles::NONE);
    expect(&m, IE::BoundaryCycle(HalfedgeId(g)));

    // Bowtie: vertex 0's stored halfedge walks one triangle's fan only; the other
    // triangle's two halfedges out of vertex 0 are in no vertex's fan.
    let m = bowtie();
    expect(&m, IE::VertexFan(VertexId(0)));

    // The same bowtie with its two boundary loops joined into one figure-eight through
    // vertex 0 (1→0 continues with 0→5, 4→0 with 0→2): every link is consistent and vertex
    // 0's fan is one cycle through all four of its halfedges, two of them boundary.
    let mut m = bowtie();
    let he = |m: &M, a, b| m.find_halfedge(VertexId(a), VertexId(b)).unwrap().0;
    let (h10, h40) = (he(&m, 1, 0), he(&m, 4, 0));
    let (h02, h05) = (m.next_raw(h10), m.next_raw(h40));
    assert_eq!([m.head_raw(h02), m.head_raw(h05)], [2, 5]);
    assert!(
        [h10, h40, h02, h05]
            .iter()
            .all(|&h| m.face_raw(h) == handles::NONE)
    );
    m.link(h10, h05);
    m.link(h40, h02);
    expect(&m, IE::NonManifoldVertex(VertexId(0)));

    // An open fan of three triangles around vertex 0 (rim 1, 2, 3, 4) with rim vertex 4
    // merged into rim vertex 1: vertex 0 has two edges to vertex 1 (its first and its last
    // spoke) and is checked first.
    let p = [
        vec3(0., 0., 0.),
        vec3(1., 0., 0.),
        vec3(1., 1., 0.),
        vec3(0., 1., 0.),
        vec3(-1., 1., 0.),
    ];
    let m = merged(&p, &[[0, 1, 2], [0, 2, 3], [0, 3, 4]], 4, 1);
    expect(&m, IE::DuplicateEdge(VertexId(0)));

    let missing: Vec<usize> = (0..INVARIANT_VARIANTS).filter(|&k| !seen[k]).collect();
    assert!(missing.is_empty(), "variants without a case: {missing:?}");
}

/// `set_position` moves exactly the named vertex to exactly the given point (read back by
/// `position` and by `export`), leaves every other position and the connectivity as they
/// were, and a second call replaces the first.
#[test]
fn set_position_moves_only_that_vertex() {
    let (p, t) = tetra();
    let mut m: M = build(&p, &t).unwrap();
    let before = m.clone();
    let q = vec3(0.1, -2.5e7, 3.0e-30);
    assert_eq!(m.set_position(VertexId(2), q), Ok(()));
    m.validate().unwrap();
    let mut want = p.clone();
    want[2] = q;
    let got: Vec<Option<Vec3>> = (0..4).map(|v| m.position(VertexId(v))).collect();
    assert_eq!(got, want.iter().copied().map(Some).collect::<Vec<_>>());
    let mut positions = vec![Vec3::ZERO; 4];
    let mut tris = vec![[0u32; 3]; 4];
    assert_eq!(m.export(&mut positions, &mut tris), Ok((4, 4)));
    assert_eq!(positions, want);
    assert_eq!(tris, t);
    // Only the position changed: putting the old one back restores the mesh bit for bit.
    let r = vec3(-0.0, 7.0, -1.0);
    m.set_position(VertexId(2), r).unwrap();
    assert_eq!(m.position(VertexId(2)), Some(r));
    assert_eq!(
        m.position(VertexId(2)).unwrap().x.to_bits(),
        (-0.0f32).to_bits()
    );
    m.set_position(VertexId(2), p[2]).unwrap();
    assert_eq!(m, before);
}

/// Two triangles glued along all three edges (a "pillow"): splitting any edge would join the
/// new vertex to the shared opposite vertex twice. Refused, mesh unchanged (found by the
/// `halfedge_ops` fuzz target).
#[test]
fn split_refuses_when_wings_coincide() {
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let t = [[0, 1, 2], [0, 2, 1]];
    let mut m = build::<8, 16, 8>(&p, &t).unwrap();
    m.validate().unwrap();
    let before = m.clone();
    for e in 0..3 {
        assert_eq!(m.split_edge(EdgeId(e)), Err(SplitError::WingsCoincide));
        assert_eq!(m, before);
    }
}

/// Loop subdivision near `±f32::MAX`: every Loop rule is a convex combination, so each new
/// coordinate lies within the old ones' range and is finite, even where the `f32` sums of
/// two coordinates overflow. The inputs: a tetrahedron with two vertices at `−3e38` (found by
/// the `halfedge_ops` fuzz target, once refused) and a lone triangle at `x = 2¹²⁷` (boundary
/// rules, `2¹²⁷ + 2¹²⁷` overflows in `f32`).
#[test]
fn subdivide_near_f32_max_stays_finite_and_in_range() {
    let (mut p, t) = tetra();
    p[0] = Vec3::splat(-3.0e38);
    p[1] = Vec3::splat(-3.0e38);
    // 2¹²⁷ and 2¹²⁷ + 4 ulps (an ulp is 2¹⁰⁴ there); their `f32` sum is 2¹²⁸, beyond `f32::MAX`.
    let (x0, x1) = (f32::from_bits(254 << 23), f32::from_bits((254 << 23) | 4));
    let lone = [vec3(x0, 0.0, 0.0), vec3(x1, 0.0, 0.0), vec3(x0, 1.0, 0.0)];
    let check = |pos: &[Vec3], out: &HalfedgeMesh<16, 48, 32>| {
        let lo = pos.iter().fold(Vec3::INFINITY, |a, &b| a.min(b));
        let hi = pos.iter().fold(Vec3::NEG_INFINITY, |a, &b| a.max(b));
        for v in 0..out.len().vertices as u32 {
            let q = out.position(VertexId(v)).unwrap();
            assert!(
                q.is_finite() && q.cmpge(lo).all() && q.cmple(hi).all(),
                "{v}: {q}"
            );
        }
    };
    for w in [LoopWeights::Warren, LoopWeights::Loop] {
        let m = build::<4, 6, 4>(&p, &t).unwrap();
        let mut out = HalfedgeMesh::<16, 48, 32>::new();
        assert_eq!(m.subdivide_loop(&mut out, w), Ok(()));
        out.validate().unwrap();
        check(&p, &out);
        let m = build::<3, 3, 1>(&lone, &[[0, 1, 2]]).unwrap();
        let mut out = HalfedgeMesh::<16, 48, 32>::new();
        assert_eq!(m.subdivide_loop(&mut out, w), Ok(()));
        check(&lone, &out);
        // The boundary edge 0–1's midpoint, worked by hand: 2¹²⁷ + 2 ulps.
        let mid = vec3(f32::from_bits((254 << 23) | 2), 0.0, 0.0);
        let e01 = (0..3).map(EdgeId).find(|&e| {
            let [a, b] = m.edge_vertices(e).unwrap();
            a.0 + b.0 == 1
        });
        assert_eq!(m.loop_edge_position(e01.unwrap()), Some(mid));
    }
}

/// `split_edge` at the midpoint of an edge whose endpoints share a subnormal coordinate: the
/// new vertex keeps it (`f32` halves of the smallest subnormal round to 0).
#[test]
fn split_edge_midpoint_keeps_subnormal_coordinates() {
    let tiny = f32::from_bits(1);
    let p = [
        vec3(tiny, 0.0, 0.0),
        vec3(tiny, 1.0, 0.0),
        vec3(0.0, 0.0, 1.0),
    ];
    let mut m = build::<8, 16, 8>(&p, &[[0, 1, 2]]).unwrap();
    let e = (0..3)
        .map(EdgeId)
        .find(|&e| {
            let [a, b] = m.edge_vertices(e).unwrap();
            a.0 + b.0 == 1
        })
        .unwrap();
    let v = m.split_edge(e).unwrap();
    assert_eq!(m.position(v), Some(vec3(tiny, 0.5, 0.0)));
}

/// A pillow (two faces on the same three vertices) cannot be Loop-subdivided: the two middle
/// triangles would be the same triangle twice (found by the `halfedge_ops` fuzz target).
#[test]
fn subdivide_refuses_coincident_faces() {
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let m = build::<8, 16, 8>(&p, &[[0, 1, 2], [0, 2, 1]]).unwrap();
    let mut out = HalfedgeMesh::<16, 48, 32>::new();
    assert!(matches!(
        m.subdivide_loop(&mut out, LoopWeights::Warren),
        Err(SubdivideError::CoincidentFaces(_))
    ));
}

/// The collapse target each `CollapseAt` names, checked on the octahedron's edge from vertex 0
/// to vertex 2: the head's and the tail's positions, the midpoint `(p₀ + p₂)/2` (exact here:
/// halves of small integers), and a given point; the collapse then leaves a vertex there.
#[test]
fn collapse_targets_are_the_named_points() {
    let (p, t) = octa();
    let m: M = build(&p, &t).unwrap();
    let h = m.find_halfedge(VertexId(0), VertexId(2)).unwrap();
    let mid = (p[0] + p[2]) / 2.0;
    let given = vec3(0.25, -0.5, 0.125);
    for (at, want) in [
        (CollapseAt::Head, p[2]),
        (CollapseAt::Tail, p[0]),
        (CollapseAt::Midpoint, mid),
        (CollapseAt::Point(given), given),
    ] {
        assert_eq!(m.can_collapse_edge(h, at), Ok(want), "{at:?}");
        let mut c = m.clone();
        c.collapse_edge(h, at).unwrap();
        let mut positions = vec![Vec3::ZERO; p.len()];
        let mut tris = vec![[0u32; 3]; t.len()];
        let (n, _) = c.export(&mut positions, &mut tris).unwrap();
        assert!(positions[..n].contains(&want), "{at:?}: {positions:?}");
    }
}

/// The midpoint of two equal subnormal coordinates is that coordinate (`2⁻¹⁴⁹`, the smallest
/// `f32` above zero), and of `2⁻¹⁴⁹` and `3·2⁻¹⁴⁹` it is `2·2⁻¹⁴⁹`: exact by hand. The `f32`
/// form `p₀/2 + p₁/2` gave `0` for the first (each half `2⁻¹⁵⁰` rounded to even, `0`).
#[test]
fn a_midpoint_of_subnormal_coordinates_lies_between_them() {
    // Vertices 0 (+x), 2 (+y) and 4 (+z): z is 0 on the edge 0–2, y on the edge 0–4.
    let (mut p, t) = octa();
    let sub = f32::from_bits;
    (p[0].z, p[2].z) = (sub(1), sub(1));
    (p[0].y, p[4].y) = (sub(1), sub(3));
    let m: M = build(&p, &t).unwrap();
    let mid = |a: u32, b: u32| {
        let h = m.find_halfedge(VertexId(a), VertexId(b)).unwrap();
        m.can_collapse_edge(h, CollapseAt::Midpoint).unwrap()
    };
    assert_eq!(mid(0, 2).z.to_bits(), 1);
    assert_eq!(mid(0, 4).y.to_bits(), 2);
}

/// The documented numbering of Loop subdivision's split edges: old edge `e` from `a` to `b`
/// (its halfedge `2e`) becomes edge `2e` from `a` to the new vertex `V + e` and edge `2e + 1`
/// from there to `b`.
#[test]
fn loop_split_edges_keep_the_old_edge_direction() {
    let m = build::<6, 12, 8>(&OCTAHEDRON_VERTICES, &OCTAHEDRON_TRIANGLES).unwrap();
    let mut out = HalfedgeMesh::<18, 48, 32>::new();
    m.subdivide_loop(&mut out, LoopWeights::Loop).unwrap();
    out.validate().unwrap();
    let v = m.vertices().count() as u32;
    for e in m.edges() {
        let [a, b] = m.edge_vertices(e).unwrap();
        let mid = VertexId(v + e.0);
        assert_eq!(
            out.edge_vertices(EdgeId(2 * e.0)),
            Some([a, mid]),
            "edge {e:?}"
        );
        assert_eq!(
            out.edge_vertices(EdgeId(2 * e.0 + 1)),
            Some([mid, b]),
            "edge {e:?}"
        );
    }
}

/// Every legal collapse of every halfedge of a 4 × 4 grid (interior, boundary and corner
/// edges; each end) leaves a mesh that passes `validate`: among its invariants, every
/// boundary vertex stores its boundary halfedge, which the collapse must re-establish for
/// the surviving vertex and the wings.
#[test]
fn every_legal_collapse_of_a_grid_leaves_a_valid_mesh() {
    let n = 4u32;
    let p: Vec<Vec3> = (0..(n + 1) * (n + 1))
        .map(|v| vec3((v % (n + 1)) as f32, (v / (n + 1)) as f32, 0.0))
        .collect();
    let t: Vec<[u32; 3]> = crate::solids::grid_triangles(n, n).collect();
    let m = build::<25, 56, 32>(&p, &t).unwrap();
    let mut legal = 0;
    for h in m.halfedges() {
        for at in [CollapseAt::Head, CollapseAt::Midpoint] {
            let mut c = m.clone();
            if c.collapse_edge(h, at).is_ok() {
                legal += 1;
                c.validate()
                    .unwrap_or_else(|e| panic!("collapse of {h:?} at {at:?}: {e:?}"));
            }
        }
    }
    assert!(legal > 200, "only {legal} legal collapses");
}

/// A closed fan of `n` triangles around vertex 0 at `centre`, its rim a circle of `radius` in
/// the plane `x = centre.x` (interior vertex 0 of valence `n`).
fn rim_fan(n: u32, centre: Vec3, radius: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = vec![centre];
    for k in 0..n {
        let a = 2.0 * core::f32::consts::PI * k as f32 / n as f32;
        p.push(centre + vec3(0.0, radius * a.cos(), radius * a.sin()));
    }
    let t = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
    (p, t)
}

/// Ten neighbours at 4·10³⁷ (inside the frontend's coordinate domain, ±4.25·10³⁷) sum to
/// 4·10³⁸, beyond the largest `f32`: the Laplacian, the smoothing step and the Loop vertex
/// rule must still give the finite positions of their formulas (here evaluated in `f64`
/// straight from the rim, without the mesh).
#[test]
fn smoothing_and_loop_near_the_largest_coordinates_do_not_overflow() {
    // One f32 rounding at the result's magnitude (4·10³⁷): the f64 sums are exact enough.
    const AT_4E37: f32 = 4e37 * f32::EPSILON;
    let (n, centre) = (10u32, vec3(4e37, 0.0, 0.0));
    let (p, t) = rim_fan(n, centre, 1e36);
    let mut m: M = build(&p, &t).unwrap();
    let rim: glam::DVec3 = p[1..].iter().map(|q| q.as_dvec3()).sum();
    let want_l = rim / f64::from(n) - centre.as_dvec3();
    let l = m.laplacian(VertexId(0)).unwrap();
    assert!(
        (l.as_dvec3() - want_l).abs().max_element() <= f64::from(AT_4E37),
        "{l} vs {want_l}"
    );
    let beta = f64::from(loop_beta(n as usize, LoopWeights::Warren));
    let want = (1.0 - f64::from(n) * beta) * centre.as_dvec3() + beta * rim;
    let got = m
        .loop_vertex_position(VertexId(0), LoopWeights::Warren)
        .unwrap();
    assert!(
        (got.as_dvec3() - want).abs().max_element() <= f64::from(AT_4E37),
        "{got} vs {want}"
    );
    let mut out = HalfedgeMesh::<64, 128, 64>::new();
    m.subdivide_loop(&mut out, LoopWeights::Warren).unwrap();
    let mut scratch = vec![Vec3::ZERO; m.slots().vertices];
    m.diffuse(0.5, DiffuseBoundary::Fixed, &mut scratch)
        .unwrap();
    let moved = m.position(VertexId(0)).unwrap();
    let want = centre.as_dvec3() + 0.5 * want_l;
    assert!(
        (moved.as_dvec3() - want).abs().max_element() <= f64::from(AT_4E37),
        "{moved} vs {want}"
    );
}
