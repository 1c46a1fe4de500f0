//! The `halfedge_ops` target: arbitrary edit sequences on small half-edge meshes.
//!
//! Layout: `start: u8` (mod 6: tetrahedron, octahedron, open 3×3 grid, one triangle,
//! hexagon fan, or a raw mesh: `vertex count: u8` mod 13, `triangle count: u8` mod 17,
//! quantized positions, triangles of three index bytes mod `vertex count + 1`), then
//! operations until the input ends (at most 24), each an opcode byte (mod 10, see [`Op`])
//! followed by its arguments.

use super::Input;
use super::collapse_oracle::{Faces, canonical};
use super::diffuse_oracle::{F32Fit, diffuse_close, diffuse_reference};
use super::loop_oracle::{loop_close, loop_reference, reference_beta};
use super::*;
use glam::Vec3;
use halfray_core::halfedge::{
    CollapseAt, Counts, DiffuseBoundary, DiffuseError, EdgeId, ExportError, FaceId, FlipError,
    HalfedgeId, HalfedgeMesh, LoopWeights, SplitError, SubdivideError, VertexId, build_scratch_len,
};
use halfray_core::solids::OCTAHEDRON_TRIANGLES;
use std::collections::BTreeSet;

/// The mesh type fuzzed: room for two Loop levels of a tetrahedron or one of an
/// octahedron, and for some dozens of splits.
pub type FuzzMesh = HalfedgeMesh<64, 192, 128>;

/// Operations: the first byte of an operation, mod 10, is the index of its opcode in
/// [`Op::ALL`] (the order written here).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// `flip_edge(edge: u8)`.
    Flip,
    /// `split_edge(edge: u8)`.
    Split,
    /// `split_edge_at(edge: u8, raw: u8, point)`: quantized point if `raw` is even, else
    /// three raw `f32`s.
    SplitAt,
    /// `collapse_edge(halfedge: u16, at: u8)`: `at` mod 4 = head, tail, midpoint, point
    /// (quantized).
    Collapse,
    /// `diffuse_vertex(vertex: u8, k: f32)`.
    DiffuseVertex,
    /// `diffuse(k: u8 / 16, boundary: u8, short scratch: u8)`.
    Diffuse,
    /// `subdivide_loop(weights: u8)` into a fresh mesh, which replaces the mesh on success.
    Loop,
    /// `compact`.
    Compact,
    /// `set_position(vertex: u8, raw: u8, point)` (point as for `SplitAt`).
    SetPosition,
    /// `export` (also into a too-small buffer), `build` from the export, re-export.
    ExportRebuild,
}

impl Op {
    /// Every operation, by opcode.
    pub const ALL: [Op; 10] = [
        Op::Flip,
        Op::Split,
        Op::SplitAt,
        Op::Collapse,
        Op::DiffuseVertex,
        Op::Diffuse,
        Op::Loop,
        Op::Compact,
        Op::SetPosition,
        Op::ExportRebuild,
    ];

    /// The operation of an input byte (its opcode, the byte mod 10).
    pub fn decode(byte: u8) -> Op {
        Op::ALL[usize::from(byte) % Op::ALL.len()]
    }
}

/// The mesh's triangle list (positions by vertex slot, triangles by vertex id).
fn exported(mesh: &FuzzMesh) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = vec![Vec3::ZERO; mesh.slots().vertices];
    let mut t = vec![[0u32; 3]; mesh.len().faces];
    let written = mesh.export(&mut p, &mut t);
    assert!(written.is_ok(), "export into exact buffers: {written:?}");
    if let Ok((_, nt)) = written {
        t.truncate(nt);
    }
    (p, t)
}

/// The FuzzMesh's capacity as its type states it (`V`, `E`, `F` of [`FuzzMesh`]).
const CAPACITY: [usize; 3] = [64, 192, 128];

/// Oriented faces as canonical position triples ([`canonical`]).
type FaceList = Vec<[[u32; 3]; 3]>;

/// The undirected edges `(min, max)` of a triangle list.
fn edge_set(ts: &[[u32; 3]]) -> BTreeSet<(u32, u32)> {
    ts.iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect()
}

/// `[V, E, F]` counted from the mesh's state as read through its accessors, not its own
/// counters (`len()`): the live vertex slots (those with a position), the distinct
/// undirected edges of the exported triangles (`validate()` promises every edge has a
/// face, so these are all of them), and the exported triangles.
fn model_counts(mesh: &FuzzMesh) -> [usize; 3] {
    let (_, ts) = exported(mesh);
    let v = (0..mesh.slots().vertices)
        .filter(|&v| mesh.position(vid(v)).is_some())
        .count();
    [v, edge_set(&ts).len(), ts.len()]
}

fn counts_of(c: Counts) -> [usize; 3] {
    [c.vertices, c.edges, c.faces]
}

fn euler(c: [usize; 3]) -> i64 {
    c[0] as i64 - c[1] as i64 + c[2] as i64
}

/// The triangles of `ts` on the undirected edge `a–b`: `(index, opposite vertex, true when
/// the triangle runs a → b)`.
fn wings(ts: &[[u32; 3]], a: u32, b: u32) -> Vec<(usize, u32, bool)> {
    ts.iter()
        .enumerate()
        .filter_map(|(i, t)| {
            (0..3).find_map(|k| {
                let (x, y, z) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                (x == a && y == b)
                    .then_some((i, z, true))
                    .or_else(|| (x == b && y == a).then_some((i, z, false)))
            })
        })
        .collect()
}

/// Number of distinct neighbours of `v` in the edge set.
fn valence(edges: &BTreeSet<(u32, u32)>, v: u32) -> usize {
    edges.iter().filter(|&&(x, y)| x == v || y == v).count()
}

/// A triangle list as corner positions.
fn as_points(ps: &[Vec3], ts: &[[u32; 3]]) -> Vec<[Vec3; 3]> {
    ts.iter().map(|t| t.map(|v| ps[v as usize])).collect()
}

/// What `flip_edge` on edge `a–b` must do, from the documented rules (`can_flip_edge`,
/// `flip_edge`) evaluated on the exported triangle list: `Ok(faces after)` (the wings
/// `(a, b, c)` and `(b, a, d)` become `(c, a, d)` and `(d, b, c)`), or `Err(refusals)` (every
/// documented refusal that applies: boundary, equal wings, wings already joined, an
/// endpoint of valence below 4); `None` when the list does not show a manifold edge (two
/// triangles of opposite directions, or one), which `validate()` rules out.
fn flip_oracle(
    ps: &[Vec3],
    ts: &[[u32; 3]],
    a: u32,
    b: u32,
) -> Option<Result<FaceList, Vec<FlipError>>> {
    let w = wings(ts, a, b);
    let (c, d, fc, fd) = match w.as_slice() {
        [_] => return Some(Err(vec![FlipError::Boundary])),
        [(i, c, true), (j, d, false)] | [(j, d, false), (i, c, true)] => (*c, *d, *i, *j),
        _ => return None,
    };
    let edges = edge_set(ts);
    let mut refusals = Vec::new();
    if c == d {
        refusals.push(FlipError::WingsCoincide);
    }
    if edges.contains(&(c.min(d), c.max(d))) {
        refusals.push(FlipError::DuplicateEdge);
    }
    for v in [a, b] {
        if valence(&edges, v) < 4 {
            refusals.push(FlipError::DegreeTooLow(vid(v as usize)));
        }
    }
    if !refusals.is_empty() {
        return Some(Err(refusals));
    }
    let mut after: Vec<[u32; 3]> = ts
        .iter()
        .enumerate()
        .filter(|&(k, _)| k != fc && k != fd)
        .map(|(_, t)| *t)
        .collect();
    after.push([c, a, d]);
    after.push([d, b, c]);
    Some(Ok(canonical(as_points(ps, &after).into_iter())))
}

/// What `split_edge_at(e, p)` on edge `a–b` must do, from its documentation evaluated on the
/// exported triangle list and the independent counts: `Ok(faces after)` with the new
/// vertex at `pm` (each wing `(a, b, c)` becomes `(a, m, c)`, `(m, b, c)`; a wing `(b, a, d)`
/// becomes `(b, m, d)`, `(m, a, d)`), or `Err(refusals)`: `NonFinitePosition` for a
/// non-finite point, `WingsCoincide` for two wings with one opposite vertex, `Capacity` when
/// the live counts plus `(1, 1 + sides, sides)` exceed [`CAPACITY`] (payload not
/// compared); `None` for a list that does not show a manifold edge.
fn split_oracle(
    ps: &[Vec3],
    ts: &[[u32; 3]],
    counts: [usize; 3],
    a: u32,
    b: u32,
    pm: Vec3,
) -> Option<Result<FaceList, Vec<&'static str>>> {
    let w = wings(ts, a, b);
    if w.is_empty() || w.len() > 2 || (w.len() == 2 && w[0].2 == w[1].2) {
        return None;
    }
    let mut refusals = Vec::new();
    if !pm.is_finite() {
        refusals.push("NonFinitePosition");
    }
    if w.len() == 2 && w[0].1 == w[1].1 {
        refusals.push("WingsCoincide");
    }
    let sides = w.len();
    let need = [1, 1 + sides, sides];
    if (0..3).any(|k| counts[k] + need[k] > CAPACITY[k]) {
        refusals.push("Capacity");
    }
    if !refusals.is_empty() {
        return Some(Err(refusals));
    }
    let (pa, pb) = (ps[a as usize], ps[b as usize]);
    let mut after: Vec<[Vec3; 3]> = ts
        .iter()
        .enumerate()
        .filter(|(k, _)| !w.iter().any(|x| x.0 == *k))
        .map(|(_, t)| t.map(|v| ps[v as usize]))
        .collect();
    for &(_, z, forward) in &w {
        let pz = ps[z as usize];
        if forward {
            after.push([pa, pm, pz]);
            after.push([pm, pb, pz]);
        } else {
            after.push([pb, pm, pz]);
            after.push([pm, pa, pz]);
        }
    }
    Some(Ok(canonical(after.into_iter())))
}

/// The name of a split refusal, to compare with [`split_oracle`]'s.
fn split_error_name(e: &SplitError) -> &'static str {
    match e {
        SplitError::Dead => "Dead",
        SplitError::NonFinitePosition => "NonFinitePosition",
        SplitError::WingsCoincide => "WingsCoincide",
        SplitError::Capacity(_) => "Capacity",
        _ => "other",
    }
}

/// How far `split_edge`'s vertex may sit from the exact midpoint of its edge, per
/// component, relative to the midpoint's magnitude: one `f32` rounding (`2⁻²⁴`). The docs
/// say "at its midpoint"; an `f32` point holds it to one rounding. Unitless.
pub const MIDPOINT_REL: f64 = 1.0 / 16_777_216.0;

/// The absolute part of the midpoint's tolerance, world units: two `f32` subnormal steps
/// (`2⁻¹⁴⁸`), for halving subnormal coordinates (each half rounds by up to one step).
pub const MIDPOINT_ABS: f64 = 2.802_596_928_649_634e-45;

/// The faces of the mesh as canonical position triples.
fn faces_now(mesh: &FuzzMesh) -> Vec<[[u32; 3]; 3]> {
    let (ps, ts) = exported(mesh);
    canonical(as_points(&ps, &ts).into_iter())
}

/// Checks a split's outcome against [`split_oracle`] (edge `e`, requested point `p`, or the
/// midpoint for `None`); `before` is the mesh before the split.
fn check_split(
    mesh: &FuzzMesh,
    before: &FuzzMesh,
    e: EdgeId,
    p: Option<Vec3>,
    r: &Result<VertexId, SplitError>,
    log: &[String],
) {
    let Some([a, b]) = before.edge_vertices(e) else {
        // (With a non-finite point too: the docs list both refusals, not their order.)
        let finite = p.is_none_or(|p| p.is_finite());
        assert!(
            *r == Err(SplitError::Dead) || (!finite && *r == Err(SplitError::NonFinitePosition)),
            "split of a dead edge: {r:?}: {log:?}"
        );
        return;
    };
    let (ps, ts) = exported(before);
    let (a, b) = (a.index() as u32, b.index() as u32);
    assert!(
        edge_set(&ts).contains(&(a.min(b), a.max(b))),
        "edge {e:?} = {a}–{b} is on no exported triangle: {log:?}"
    );
    let pm = match (p, r) {
        (Some(p), _) => p,
        (None, Ok(m)) => {
            let got = mesh.position(*m).expect("the new vertex is live");
            let mid = (ps[a as usize].as_dvec3() + ps[b as usize].as_dvec3()) * 0.5;
            let err = (got.as_dvec3() - mid).abs();
            let tol = mid.abs() * MIDPOINT_REL + MIDPOINT_ABS;
            assert!(
                err.cmple(tol).all(),
                "split_edge put {got:?}, midpoint {mid:?}: {log:?}"
            );
            got
        }
        // A refused midpoint split: the midpoint of two finite points is finite.
        (None, Err(_)) => ((ps[a as usize].as_dvec3() + ps[b as usize].as_dvec3()) * 0.5).as_vec3(),
    };
    let counts = model_counts(before);
    let Some(want) = split_oracle(&ps, &ts, counts, a, b, pm) else {
        return;
    };
    match (r, want) {
        (Ok(_), Ok(faces)) => {
            assert_eq!(faces_now(mesh), faces, "faces after the split: {log:?}");
        }
        (Err(e), Err(names)) => assert!(
            names.contains(&split_error_name(e)),
            "split refused as {e:?}, the rules name {names:?}: {log:?}"
        ),
        (Ok(_), Err(names)) => panic!("split accepted, the rules refuse ({names:?}): {log:?}"),
        (Err(e), Ok(_)) => panic!("split refused as {e:?}, the rules accept: {log:?}"),
    }
}

/// Every slot below the high-water marks is live, read slot by slot through the accessors
/// (not `is_compact`, the mesh's own summary).
fn dense(mesh: &FuzzMesh) -> bool {
    (0..mesh.slots().vertices).all(|v| mesh.position(vid(v)).is_some())
        && (0..mesh.slots().edges).all(|e| mesh.contains_edge(EdgeId::new(e as u32)))
        && (0..mesh.slots().faces).all(|f| mesh.contains_face(FaceId::new(f as u32)))
}

/// What `subdivide_loop` into an empty [`FuzzMesh`] must answer, from its documented
/// refusals evaluated on the exported triangle list and the independent counts: `required`
/// holds every refusal that applies (`NotCompact` for a dead slot below the high-water marks,
/// `Capacity` when `V + E`, `2E + 3F` or `4F` exceed [`CAPACITY`], `CoincidentFaces` for two
/// triangles on one vertex set; the docs list them, not their order). No position refuses
/// it: every Loop rule is a convex combination of finite positions, computed in `f64`.
struct LoopVerdict {
    required: Vec<&'static str>,
    /// The vertex sets of coincident triangle pairs.
    coincident: Vec<[u32; 3]>,
}

fn loop_oracle(mesh: &FuzzMesh) -> LoopVerdict {
    let (_, ts) = exported(mesh);
    let [v, e, f] = model_counts(mesh);
    let mut required = Vec::new();
    if !dense(mesh) {
        required.push("NotCompact");
    }
    let need = [v + e, 2 * e + 3 * f, 4 * f];
    if (0..3).any(|k| need[k] > CAPACITY[k]) {
        required.push("Capacity");
    }
    let mut sets: Vec<[u32; 3]> = ts
        .iter()
        .map(|t| {
            let mut s = *t;
            s.sort_unstable();
            s
        })
        .collect();
    sets.sort_unstable();
    let coincident: Vec<[u32; 3]> = sets
        .windows(2)
        .filter(|w| w[0] == w[1])
        .map(|w| w[0])
        .collect();
    if !coincident.is_empty() {
        required.push("CoincidentFaces");
    }
    LoopVerdict {
        required,
        coincident,
    }
}

/// Checks a Loop subdivision's answer `r` on `mesh` against [`loop_oracle`].
fn check_loop_verdict(mesh: &FuzzMesh, r: &Result<(), SubdivideError>, log: &[String]) {
    let want = loop_oracle(mesh);
    match r {
        Ok(()) => assert!(
            want.required.is_empty(),
            "Loop accepted, the rules refuse ({:?}): {log:?}",
            want.required
        ),
        Err(err) => {
            let name = match err {
                SubdivideError::NotCompact => "NotCompact",
                SubdivideError::Capacity(_) => "Capacity",
                SubdivideError::CoincidentFaces(_) => "CoincidentFaces",
                _ => "other",
            };
            assert!(
                want.required.contains(&name),
                "Loop refused as {err:?}, the rules name {:?}: {log:?}",
                want.required
            );
            // The edge named joins two vertices of one coincident pair.
            if let SubdivideError::CoincidentFaces(e) = err {
                let ends = mesh.edge_vertices(*e).map(|[a, b]| [a.raw(), b.raw()]);
                assert!(
                    ends.is_some_and(|[a, b]| want
                        .coincident
                        .iter()
                        .any(|s| s.contains(&a) && s.contains(&b))),
                    "CoincidentFaces({e:?}) = {ends:?} joins no coincident pair {:?}: {log:?}",
                    want.coincident
                );
            }
        }
    }
}

fn vid(v: usize) -> VertexId {
    VertexId::new(v as u32)
}

/// A position's bits (`-0.0` and `0.0` differ), `None` for a dead or missing vertex.
fn bits(q: Option<Vec3>) -> Option<[u32; 3]> {
    q.map(|q| q.to_array().map(f32::to_bits))
}

/// Asserts that every vertex slot of `mesh` but `except` holds `before`'s position bit for
/// bit (or is dead in both).
fn assert_positions_kept(
    mesh: &FuzzMesh,
    before: &FuzzMesh,
    except: Option<VertexId>,
    log: &[String],
) {
    for w in (0..before.slots().vertices).map(vid) {
        if Some(w) != except {
            assert_eq!(
                bits(mesh.position(w)),
                bits(before.position(w)),
                "{w:?} moved: {log:?}"
            );
        }
    }
}

/// The start meshes (positions, triangles), indexed by the start byte mod 5.
pub fn start_mesh(k: u8) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    match k % 5 {
        0 => (
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        ),
        1 => (
            vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z],
            OCTAHEDRON_TRIANGLES.to_vec(),
        ),
        2 => {
            let p = (0..9)
                .map(|i| Vec3::new((i % 3) as f32, (i / 3) as f32, 0.0))
                .collect();
            let mut t = Vec::new();
            for j in 0..2u32 {
                for i in 0..2u32 {
                    let (a, b, c, d) = (i + 3 * j, i + 1 + 3 * j, i + 4 + 3 * j, i + 3 + 3 * j);
                    t.push([a, b, c]);
                    t.push([a, c, d]);
                }
            }
            (p, t)
        }
        3 => (vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]),
        _ => {
            let mut p = vec![Vec3::ZERO];
            for k in 0..6 {
                let a = k as f32 * core::f32::consts::FRAC_PI_3;
                p.push(Vec3::new(a.cos(), a.sin(), 0.0));
            }
            let t = (1..=6u32).map(|k| [0, k, k % 6 + 1]).collect();
            (p, t)
        }
    }
}

fn point(i: &mut Input<'_>) -> Vec3 {
    if i.u8().is_multiple_of(2) {
        i.qvec3()
    } else {
        i.vec3()
    }
}

/// Fuzz target `halfedge_ops`.
///
/// Properties: no panic; a build either succeeds with `validate()` Ok or fails leaving the
/// mesh empty; after every successful operation `validate()` is Ok, `len()` equals the
/// counts taken off the exported triangle list (live vertex slots, distinct edges,
/// triangles: `model_counts`, not the mesh's own counters) and the Euler characteristic
/// `V − E + F` of those counts is unchanged; a flip and a split are accepted or refused
/// (with a documented kind) as their rules evaluated on the triangle list say
/// (`flip_oracle`, `split_oracle`), leave exactly the faces those rules predict, and
/// `split_edge` puts its vertex at the edge's midpoint within one `f32` rounding
/// ([`MIDPOINT_REL`], [`MIDPOINT_ABS`]); compaction leaves every slot below the high-water
/// marks live (checked slot by slot), the same counts and the same faces; an operation that refuses leaves the mesh
/// bit-for-bit unchanged (`Mesh: PartialEq` compares every slot and the free lists);
/// `can_flip_edge` / `can_collapse_edge` predict `flip_edge` / `collapse_edge` exactly and
/// the collapse survivor sits at the predicted point; a collapse is accepted exactly when the
/// rules evaluated independently on the exported triangle list accept it
/// ([`super::collapse_oracle`]; a fold-over sign within rounding is not judged), and leaves
/// exactly the triangles that oracle predicts; Loop subdivision is accepted or refused, with
/// a documented kind, as its refusals evaluated on the triangle list say (`loop_oracle`:
/// compactness, capacity, coincident faces, positions beyond `f32`), and produces the
/// documented counts `V + E, 2E + 3F, 4F` (evaluated on the independent counts, not
/// `Counts::after_loop`), a new vertex for every edge of the triangle list, puts every old
/// and new vertex where the Loop rules evaluated in `f64` on
/// the exported triangle list put it ([`super::loop_oracle`], within
/// [`super::loop_oracle::LOOP_TOL_ROUNDINGS`]), and leaves its output untouched when it
/// refuses; a successful `diffuse` (`Free` or `Fixed` boundary) puts every live vertex where
/// the uniform Laplacian rule evaluated in `f64` on the exported triangle list puts it
/// ([`super::diffuse_oracle`], within [`super::diffuse_oracle::DIFFUSE_TOL_ROUNDINGS`]), a
/// short scratch is refused as `ScratchTooSmall`, a step the oracle finds clearly finite
/// succeeds and one it finds clearly beyond `f32` is refused as `NonFinite`, and a refusal
/// leaves every position bit for bit; `diffuse_vertex` likewise for its one vertex (`Dead`
/// for a dead one, `NonFinite` for a non-finite `k`), every other position kept bit for bit;
/// a successful `set_position` leaves exactly the given point at the vertex and every other
/// position as it was; a refused export writes nothing; build(export(mesh)) validates and
/// re-exports identically.
pub fn halfedge_ops(data: &[u8]) {
    let mut i = Input::new(data);
    let start = i.u8() % 6;
    let (positions, triangles) = if start == 5 {
        let nv = usize::from(i.u8()) % 13;
        let nt = usize::from(i.u8()) % 17;
        let p: Vec<Vec3> = (0..nv).map(|_| i.qvec3()).collect();
        let m = nv as u32 + 1;
        let t = (0..nt)
            .map(|_| {
                [
                    u32::from(i.u8()) % m,
                    u32::from(i.u8()) % m,
                    u32::from(i.u8()) % m,
                ]
            })
            .collect();
        (p, t)
    } else {
        start_mesh(start)
    };
    let mut log = vec![format!("build {positions:?} {triangles:?}")];
    let mut mesh = FuzzMesh::new();
    let mut scratch = vec![0u32; build_scratch_len(triangles.len())];
    match mesh.build(&positions, &triangles, &mut scratch) {
        Ok(()) => assert_eq!(mesh.validate(), Ok(()), "built mesh invalid: {log:?}"),
        Err(_) => {
            assert!(mesh.is_empty(), "failed build left elements: {log:?}");
            assert_eq!(mesh, FuzzMesh::new(), "failed build left state: {log:?}");
        }
    }

    for _ in 0..24 {
        if i.is_empty() {
            break;
        }
        let before = mesh.clone();
        let slots = mesh.slots();
        let chi = euler(model_counts(&mesh));
        let faces_before = faces_now(&mesh);
        let edge = |i: &mut Input<'_>| EdgeId::new(u32::from(i.u8()) % (slots.edges as u32 + 2));
        let vertex =
            |i: &mut Input<'_>| VertexId::new(u32::from(i.u8()) % (slots.vertices as u32 + 2));
        let op = Op::decode(i.u8());
        // `Ok(keep_chi)` on success, `Err(())` when refused.
        let outcome: Result<bool, String> = match op {
            Op::Flip => {
                let e = edge(&mut i);
                let can = mesh.can_flip_edge(e);
                // The independent oracle, from the triangle list before the flip (the edge's
                // ends read through `edge_vertices`: which pair an edge id names is the
                // mesh's to say; that the pair is an edge of the list is checked).
                let want = before.edge_vertices(e).map(|[a, b]| {
                    let (ps, ts) = exported(&before);
                    let (a, b) = (a.index() as u32, b.index() as u32);
                    assert!(
                        edge_set(&ts).contains(&(a.min(b), a.max(b))),
                        "edge {e:?} = {a}–{b} is on no exported triangle: {log:?}"
                    );
                    flip_oracle(&ps, &ts, a, b)
                });
                let r = mesh.flip_edge(e);
                log.push(format!("flip {e:?} -> {r:?}"));
                assert_eq!(can, r, "can_flip_edge disagrees: {log:?}");
                match (want, &r) {
                    (None, _) => assert_eq!(r, Err(FlipError::Dead), "dead edge: {log:?}"),
                    (Some(None), _) => {}
                    (Some(Some(Ok(faces))), Ok(())) => {
                        assert_eq!(faces_now(&mesh), faces, "faces after the flip: {log:?}");
                    }
                    (Some(Some(Err(kinds))), Err(e)) => assert!(
                        kinds.contains(e),
                        "flip refused as {e:?}, the rules name {kinds:?}: {log:?}"
                    ),
                    (Some(Some(Ok(_))), Err(e)) => {
                        panic!("flip refused as {e:?}, the rules accept: {log:?}")
                    }
                    (Some(Some(Err(kinds))), Ok(())) => {
                        panic!("flip accepted, the rules refuse ({kinds:?}): {log:?}")
                    }
                }
                r.map(|()| true).map_err(|e| format!("{e:?}"))
            }
            Op::Split => {
                let e = edge(&mut i);
                let r = mesh.split_edge(e);
                log.push(format!("split {e:?} -> {r:?}"));
                check_split(&mesh, &before, e, None, &r, &log);
                r.map(|_| true).map_err(|e| format!("{e:?}"))
            }
            Op::SplitAt => {
                let e = edge(&mut i);
                let p = point(&mut i);
                let r = mesh.split_edge_at(e, p);
                log.push(format!("split_at {e:?} {p:?} -> {r:?}"));
                if let Ok(m) = r {
                    assert_eq!(mesh.position(m), Some(p), "split point: {log:?}");
                }
                check_split(&mesh, &before, e, Some(p), &r, &log);
                r.map(|_| true).map_err(|e| format!("{e:?}"))
            }
            Op::Collapse => {
                let h = HalfedgeId::new(u32::from(i.u16()) % (2 * slots.edges as u32 + 2));
                let at = match i.u8() % 4 {
                    0 => CollapseAt::Head,
                    1 => CollapseAt::Tail,
                    2 => CollapseAt::Midpoint,
                    _ => CollapseAt::Point(i.qvec3()),
                };
                // The independent oracle, from the triangle list before the collapse.
                let ends = mesh.tail(h).zip(mesh.head(h));
                let (ps, ts) = exported(&mesh);
                let faces = Faces {
                    positions: &ps,
                    triangles: &ts,
                };
                let expected = ends.and_then(|(a, b)| {
                    let (pa, pb) = (mesh.position(a)?, mesh.position(b)?);
                    let target = match at {
                        CollapseAt::Head => pb,
                        CollapseAt::Tail => pa,
                        CollapseAt::Midpoint => ((pa.as_dvec3() + pb.as_dvec3()) * 0.5).as_vec3(),
                        CollapseAt::Point(p) => p,
                    };
                    let (a, b) = (a.index() as u32, b.index() as u32);
                    if !target.is_finite() {
                        return Some(None);
                    }
                    // `None`: a fold-over sign within rounding (not judged).
                    let ok = faces.may_collapse(a, b, target)?;
                    Some(ok.then(|| faces.after_collapse(a, b, target)))
                });
                let judged = ends.is_none() || expected.is_some();
                let expected = expected.flatten();
                let can = mesh.can_collapse_edge(h, at);
                let r = mesh.collapse_edge(h, at);
                log.push(format!(
                    "collapse {h:?} {at:?} -> {r:?} (predicted {can:?}, oracle {})",
                    expected.is_some()
                ));
                assert_eq!(
                    can.is_ok(),
                    r.is_ok(),
                    "can_collapse_edge disagrees: {log:?}"
                );
                if judged {
                    assert_eq!(
                        expected.is_some(),
                        r.is_ok(),
                        "the rules evaluated on the triangle list disagree: {log:?}"
                    );
                }
                if let (Ok(p), Ok(v)) = (can, r) {
                    assert_eq!(mesh.position(v), Some(p), "survivor position: {log:?}");
                }
                if let Some(want) = expected.filter(|_| r.is_ok()) {
                    let (ps, ts) = exported(&mesh);
                    let got = canonical(ts.iter().map(|t| t.map(|v| ps[v as usize])));
                    assert_eq!(got, want, "faces after the collapse: {log:?}");
                }
                r.map(|_| true).map_err(|e| format!("{e:?}"))
            }
            Op::DiffuseVertex => {
                let v = vertex(&mut i);
                let k = i.f32();
                // The independent oracle: the rule on the triangle list before the step (a
                // single vertex moves whether on the boundary or not).
                let (ps, ts) = exported(&mesh);
                let want = diffuse_reference(&ps, &ts, f64::from(k), DiffuseBoundary::Free);
                let r = mesh.diffuse_vertex(v, k);
                log.push(format!("diffuse_vertex {v:?} {k:e} -> {r:?}"));
                if before.position(v).is_none() {
                    assert_eq!(r, Err(DiffuseError::Dead), "dead vertex: {log:?}");
                } else if !k.is_finite() {
                    assert_eq!(r, Err(DiffuseError::NonFinite), "k: {log:?}");
                } else {
                    // Judged only where the f64 values are clear of f32::MAX by their rounding
                    // bounds: the docs evaluate L, k·L and x + k·L in f32 and refuse when any
                    // overflows (a narrowing listed in fuzz/README.md).
                    let want = &want[v.index()];
                    match want.f32_fit() {
                        F32Fit::Finite => assert!(r.is_ok(), "refused, {want:?}: {log:?}"),
                        F32Fit::Overflows => {
                            assert_eq!(r, Err(DiffuseError::NonFinite), "{want:?}: {log:?}");
                        }
                        F32Fit::Unclear => {}
                    }
                }
                if let Ok(p) = r {
                    assert_eq!(mesh.position(v), Some(p), "returned position: {log:?}");
                    assert!(
                        diffuse_close(p, &want[v.index()]),
                        "diffuse_vertex {v:?}: {p:?} vs {:?}: {log:?}",
                        want[v.index()]
                    );
                    assert_positions_kept(&mesh, &before, Some(v), &log);
                }
                r.map(|_| true).map_err(|e| format!("{e:?}"))
            }
            Op::Diffuse => {
                let k = f32::from(i.u8()) / 16.0;
                let boundary = if i.u8().is_multiple_of(2) {
                    DiffuseBoundary::Free
                } else {
                    DiffuseBoundary::Fixed
                };
                let short = usize::from(i.u8() % 2 == 1 && slots.vertices > 0);
                let mut sc = vec![Vec3::ZERO; slots.vertices - short];
                // The independent oracle: the rule on the triangle list before the step.
                let (ps, ts) = exported(&mesh);
                let want = diffuse_reference(&ps, &ts, f64::from(k), boundary);
                let r = mesh.diffuse(k, boundary, &mut sc);
                log.push(format!("diffuse {k} {boundary:?} short={short} -> {r:?}"));
                let live = || (0..slots.vertices).filter(|&v| before.position(vid(v)).is_some());
                // Success or `NonFinite` judged only where clear (as for `DiffuseVertex`).
                let fits: Vec<F32Fit> = live().map(|v| want[v].f32_fit()).collect();
                if short == 1 {
                    let needed = slots.vertices;
                    let e = Err(DiffuseError::ScratchTooSmall { needed });
                    assert_eq!(r, e, "short scratch: {log:?}");
                } else if fits.contains(&F32Fit::Overflows) {
                    assert_eq!(r, Err(DiffuseError::NonFinite), "overflow: {log:?}");
                } else if fits.iter().all(|&f| f == F32Fit::Finite) {
                    assert_eq!(r, Ok(()), "a finite step refused: {log:?}");
                }
                match r {
                    Ok(()) => {
                        for v in live() {
                            let got = mesh.position(vid(v));
                            assert!(
                                got.is_some_and(|g| diffuse_close(g, &want[v])),
                                "diffuse vertex {v}: {got:?} vs {:?}: {log:?}",
                                want[v]
                            );
                        }
                    }
                    Err(_) => assert_positions_kept(&mesh, &before, None, &log),
                }
                r.map(|()| true).map_err(|e| format!("{e:?}"))
            }
            Op::Loop => {
                let weights = if i.u8().is_multiple_of(2) {
                    LoopWeights::Warren
                } else {
                    LoopWeights::Loop
                };
                let mut out = FuzzMesh::new();
                let r = mesh.subdivide_loop(&mut out, weights);
                log.push(format!("loop {weights:?} -> {r:?}"));
                check_loop_verdict(&mesh, &r, &log);
                match r {
                    Ok(()) => {
                        // Counts against V' = V + E, E' = 2E + 3F, F' = 4F (the documented
                        // rule, evaluated here on independent counts of both meshes).
                        let [v, e, f] = model_counts(&mesh);
                        assert_eq!(
                            model_counts(&out),
                            [v + e, 2 * e + 3 * f, 4 * f],
                            "Loop counts: {log:?}"
                        );
                        // Positions against the f64 rules on the triangle list (the mesh is
                        // compact: vertex slots are vertex ids).
                        let (ps, ts) = exported(&mesh);
                        let (even, odd) = loop_reference(&ps, &ts, |n| reference_beta(n, weights));
                        for (v, want) in even.iter().enumerate() {
                            let got = out.position(VertexId::new(v as u32));
                            assert!(
                                got.is_some_and(|g| loop_close(g, want)),
                                "Loop vertex {v}: {got:?} vs {want:?}: {log:?}"
                            );
                        }
                        let nv = ps.len() as u32;
                        // Every edge of the list has its new vertex checked: the mesh's live
                        // edges are exactly the list's.
                        let live: BTreeSet<(u32, u32)> = mesh
                            .edges()
                            .filter_map(|e| mesh.edge_vertices(e))
                            .map(|[a, b]| (a.raw().min(b.raw()), a.raw().max(b.raw())))
                            .collect();
                        assert_eq!(
                            live.len(),
                            mesh.edges().count(),
                            "two live edges join one pair: {log:?}"
                        );
                        assert!(
                            live == odd.keys().copied().collect::<BTreeSet<_>>(),
                            "live edges differ from the triangle list's: {log:?}"
                        );
                        for e in mesh.edges() {
                            let Some([a, b]) = mesh.edge_vertices(e) else {
                                panic!("edges() gave {e:?}, which has no vertices: {log:?}");
                            };
                            let want = &odd[&(a.raw().min(b.raw()), a.raw().max(b.raw()))];
                            let got = out.position(VertexId::new(nv + e.raw()));
                            assert!(
                                got.is_some_and(|g| loop_close(g, want)),
                                "Loop vertex on {e:?}: {got:?} vs {want:?}: {log:?}"
                            );
                        }
                        mesh = out;
                        Ok(true)
                    }
                    Err(e) => {
                        assert_eq!(out, FuzzMesh::new(), "refused Loop wrote output: {log:?}");
                        Err(format!("{e:?}"))
                    }
                }
            }
            Op::Compact => {
                let mut moves = 0usize;
                mesh.compact(|_| moves += 1);
                log.push(format!("compact ({moves} moves)"));
                // Dense handles, checked slot by slot (not through `is_compact`, the
                // function's own summary, which must agree), and the same faces.
                assert!(
                    dense(&mesh),
                    "a dead slot below the high-water mark after compact: {log:?}"
                );
                assert!(
                    mesh.is_compact(),
                    "is_compact() false on dense slots: {log:?}"
                );
                assert_eq!(
                    model_counts(&mesh),
                    model_counts(&before),
                    "compact changed counts: {log:?}"
                );
                assert_eq!(
                    faces_now(&mesh),
                    faces_before,
                    "compact changed faces: {log:?}"
                );
                Ok(true)
            }
            Op::SetPosition => {
                let v = vertex(&mut i);
                let p = point(&mut i);
                let r = mesh.set_position(v, p);
                log.push(format!("set_position {v:?} {p:?} -> {r:?}"));
                if r.is_ok() {
                    // Exactly `p` at `v` (bit for bit: -0.0 stays -0.0), every other slot
                    // as it was.
                    assert_eq!(bits(mesh.position(v)), bits(Some(p)), "set: {log:?}");
                    assert_positions_kept(&mesh, &before, Some(v), &log);
                }
                r.map(|()| true).map_err(|e| format!("{e:?}"))
            }
            Op::ExportRebuild => {
                let (np, nt) = (slots.vertices, mesh.len().faces);
                if np + nt > 0 {
                    let mut sp = vec![Vec3::splat(7.0); np.saturating_sub(1)];
                    let mut st = vec![[9u32; 3]; nt];
                    let r = mesh.export(&mut sp, &mut st);
                    assert_eq!(
                        r,
                        Err(ExportError::BufferTooSmall {
                            positions: np,
                            triangles: nt
                        }),
                        "short export: {log:?}"
                    );
                    assert!(
                        sp.iter().all(|p| *p == Vec3::splat(7.0))
                            && st.iter().all(|t| *t == [9; 3]),
                        "refused export wrote: {log:?}"
                    );
                }
                let mut p = vec![Vec3::ZERO; np];
                let mut t = vec![[0u32; 3]; nt];
                let r = mesh.export(&mut p, &mut t);
                assert_eq!(r, Ok((np, nt)), "export: {log:?}");
                let mut rebuilt = FuzzMesh::new();
                let mut sc = vec![0u32; build_scratch_len(nt)];
                let b = rebuilt.build(&p, &t, &mut sc);
                log.push(format!("export+rebuild -> {b:?}"));
                assert_eq!(
                    b,
                    Ok(()),
                    "the export of a valid mesh does not build: {log:?}"
                );
                assert_eq!(rebuilt.validate(), Ok(()), "rebuilt mesh: {log:?}");
                let mut p2 = vec![Vec3::ZERO; np];
                let mut t2 = vec![[0u32; 3]; nt];
                assert_eq!(rebuilt.export(&mut p2, &mut t2), Ok((np, nt)));
                assert!(p == p2 && t == t2, "export does not round-trip: {log:?}");
                assert_eq!(mesh, before, "export changed the mesh: {log:?}");
                Ok(true)
            }
        };
        // Every operation's outcome is judged: against its oracle above, and below against
        // the counts (success) or the unchanged mesh (refusal).
        reached();
        match outcome {
            Ok(keep_chi) => {
                // `validate()` is the core's structural invariant check, a separate pass
                // over the records that shares no code with the edits; it is kept as the
                // judge of the half-edge links, which no triangle list shows. The counts
                // and faces are judged independently (model_counts, the oracles above).
                if let Err(e) = mesh.validate() {
                    panic!("validate() = {e:?} after a successful operation: {log:#?}");
                }
                let counts = model_counts(&mesh);
                assert_eq!(
                    counts_of(mesh.len()),
                    counts,
                    "len() differs from the counted elements: {log:#?}"
                );
                if keep_chi {
                    assert_eq!(euler(counts), chi, "V − E + F changed: {log:#?}");
                }
            }
            Err(_) => assert!(
                mesh == before,
                "refused operation changed the mesh: {log:#?}"
            ),
        }
    }
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("halfedge_ops", format!("seed-{name}"), bytes);
    // Opcodes: 0 flip e, 1 split e, 2 split_at e raw p, 3 collapse h16 at, 4 diffuse_vertex v k,
    // 5 diffuse k b short, 6 loop w, 7 compact, 8 set_position v raw p, 9 export+rebuild.
    let q0 = [0u8, 0, 0];
    s.push(t(
        "tetra-loop-loop",
        Enc::new()
            .u8(0)
            .bytes(&[6, 0, 6, 1, 0, 3, 3, 0, 0, 9])
            .done(),
    ));
    s.push(t(
        "tetra-flip-collapse-refused",
        Enc::new()
            .u8(0)
            .bytes(&[0, 0, 0, 1, 3, 0, 0, 0, 3, 5, 0, 2])
            .done(),
    ));
    s.push(t(
        "octa-split-flip-collapse-compact",
        Enc::new()
            .u8(1)
            .bytes(&[
                1, 0, 1, 5, 0, 12, 0, 13, 3, 24, 0, 2, 3, 7, 0, 1, 7, 9, 6, 1,
            ])
            .done(),
    ));
    s.push(t(
        "grid-boundary-ops",
        Enc::new()
            .u8(2)
            .bytes(&[0, 0, 3, 0, 0, 0, 3, 1, 0, 1, 1, 2, 4, 0])
            .bytes(&q0)
            .bytes(&[5, 8, 1, 0, 5, 8, 0, 1, 7, 9])
            .done(),
    ));
    s.push(t(
        "triangle-everything",
        Enc::new()
            .u8(3)
            .bytes(&[0, 0, 1, 0, 3, 2, 0, 1, 6, 0, 9, 7])
            .done(),
    ));
    s.push(t(
        "fan-nonfinite-refusals",
        Enc::new()
            .u8(4)
            .u8(4)
            .u8(0)
            .f32(f32::INFINITY)
            .u8(2)
            .u8(0)
            .u8(1)
            .vec3(Vec3::new(f32::NAN, 0.0, 0.0))
            .u8(8)
            .u8(1)
            .u8(1)
            .vec3(Vec3::new(0.0, f32::INFINITY, 0.0))
            .u8(4)
            .u8(0)
            .f32(1e38)
            .u8(3)
            .u16(0)
            .u8(3)
            .qvec3(Vec3::new(0.0, 0.0, 5.0))
            .done(),
    ));
    // Raw builds: a bowtie (non-manifold vertex), an inconsistent orientation, an edge
    // shared by three faces, a repeated index: every one must fail and leave the mesh empty.
    for (name, nv, tris) in [
        ("raw-bowtie", 5u8, vec![[0u8, 1, 2], [0, 3, 4]]),
        ("raw-flipped", 4, vec![[0, 1, 2], [0, 1, 3]]),
        ("raw-three-faces", 5, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]),
        ("raw-repeated-index", 3, vec![[0, 0, 1]]),
        ("raw-out-of-range", 3, vec![[0, 1, 3]]),
        ("raw-two-triangles", 4, vec![[0, 1, 2], [0, 2, 3]]),
    ] {
        let mut e = Enc::new().u8(5).u8(nv).u8(tris.len() as u8);
        for k in 0..nv {
            e = e.qvec3(Vec3::new(
                f32::from(k),
                f32::from(k * k % 5),
                f32::from(k % 2),
            ));
        }
        for tri in &tris {
            e = e.bytes(tri);
        }
        s.push(t(name, e.bytes(&[1, 0, 0, 0, 7, 9]).done()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The flip and split oracles on the octahedron (vertices `±X, ±Y, ±Z` as 0…5) and the
    /// tetrahedron, against faces written out by hand from the docs' rules.
    #[test]
    fn flip_and_split_oracles_on_hand_cases() {
        let (ps, ts) = start_mesh(1);
        let pts = |t: &[[u32; 3]]| canonical(as_points(&ps, t).into_iter());
        // Edge 0–2 (X–Y): wings (0, 2, 4) and (2, 0, 5) become (4, 0, 5) and (5, 2, 4).
        let mut after: Vec<[u32; 3]> = ts[1..4].iter().chain(&ts[5..]).copied().collect();
        after.extend([[4, 0, 5], [5, 2, 4]]);
        assert_eq!(flip_oracle(&ps, &ts, 0, 2), Some(Ok(pts(&after))));
        assert_eq!(flip_oracle(&ps, &ts, 2, 0), Some(Ok(pts(&after))));
        // The same edge split at p: (0, m, 4), (m, 2, 4), (2, m, 5), (m, 0, 5).
        let p = Vec3::new(0.5, 0.5, 0.0);
        let mut want: Vec<[Vec3; 3]> = as_points(&ps, &after[..6]);
        let [x, y, z, nz] = [ps[0], ps[2], ps[4], ps[5]];
        want.extend([[x, p, z], [p, y, z], [y, p, nz], [p, x, nz]]);
        let counts = [6, 12, 8];
        assert_eq!(
            split_oracle(&ps, &ts, counts, 0, 2, p),
            Some(Ok(canonical(want.into_iter())))
        );
        assert_eq!(
            split_oracle(&ps, &ts, counts, 0, 2, Vec3::NAN),
            Some(Err(vec!["NonFinitePosition"]))
        );
        assert_eq!(
            split_oracle(&ps, &ts, [64, 12, 8], 0, 2, p),
            Some(Err(vec!["Capacity"]))
        );
        // Tetrahedron: the wings of 0–1 are joined and every valence is 3.
        let (ps, ts) = start_mesh(0);
        assert_eq!(
            flip_oracle(&ps, &ts, 0, 1),
            Some(Err(vec![
                FlipError::DuplicateEdge,
                FlipError::DegreeTooLow(vid(0)),
                FlipError::DegreeTooLow(vid(1)),
            ]))
        );
        // One triangle: every edge is a boundary edge.
        let (ps, ts) = start_mesh(3);
        assert_eq!(
            flip_oracle(&ps, &ts, 1, 2),
            Some(Err(vec![FlipError::Boundary]))
        );
        assert_eq!(edge_set(&ts).len(), 3);
        assert_eq!(valence(&edge_set(&start_mesh(4).1), 0), 6);
    }
}
