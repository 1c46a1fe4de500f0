//! CSG with mesh operands on lines aimed exactly at mesh edges and vertices: a
//! closed mesh is entered and left once per surface crossing, whatever edge or vertex the line
//! passes through, so union, intersection and difference classify every point of the line as
//! the same line moved off the edge does. Before the fix, both triangles of an edge reported
//! an "enter", the winding count reached 2 and the operand stayed "inside": phantom surfaces.

use glam::Vec3;
use halfray::accel::MeshAccel;
use halfray::obj::read_obj;
use halfray::scene::geom::{CsgOp, Event, Geometry, MeshShape, Node, QueryCtx};
use halfray_core::{Aabb, Ray};
use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Arc;

mod common;
use common::lcg;

const SCENE_MESHES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/meshes");

/// Every closed mesh the example scenes can use as a CSG operand.
const CLOSED: [&str; 5] = [
    "tetrahedron.obj",
    "octahedron.obj",
    "cube.obj",
    "torus.obj",
    "spot.obj",
];

/// Edges/vertices tried per mesh (every one on the small meshes, a fixed sample on the others).
const TARGETS_PER_MESH: usize = 400;

fn mesh_node(name: &str) -> (Arc<MeshShape>, Vec<Vec3>, Vec<[u32; 2]>) {
    let obj = read_obj(&Path::new(SCENE_MESHES).join(name)).unwrap();
    let mut edges = BTreeSet::new();
    for t in &obj.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.insert([a.min(b), a.max(b)]);
        }
    }
    let positions = obj.positions.clone();
    let shape = MeshShape::new(name, MeshAccel::new(obj).unwrap(), None);
    (Arc::new(shape), positions, edges.into_iter().collect())
}

/// Crossings of the whole line through `o` along `d`, and whether it starts inside.
fn events(node: &Node, o: Vec3, d: Vec3) -> (Vec<(f32, bool)>, bool) {
    let line = Ray::with_interval(o, d, f32::NEG_INFINITY, f32::INFINITY);
    let mut out: Vec<Event> = Vec::new();
    let inside = node.events(&line, &mut QueryCtx::default(), &mut out);
    (out.iter().map(|e| (e.t, e.enter)).collect(), inside)
}

/// Two crossings closer than this, relative to `t`, are one touch: `t` of different triangles
/// at one point differs by a few `f32` roundings (~1e-7 relative), and the lines moved by
/// `1e-4` of the radius cannot resolve anything thinner than 1e-5. Unitless.
const TOUCH_REL: f32 = 1e-5;

/// The crossings without touches: two events at (nearly) one `t`, entering and leaving or
/// leaving and re-entering, are an empty interval where a line grazes a surface.
fn touches_removed(events: &[(f32, bool)]) -> Vec<(f32, bool)> {
    let mut proper: Vec<(f32, bool)> = Vec::new();
    for &e in events {
        match proper.last() {
            Some(&(t, enter)) if (e.0 - t).abs() <= TOUCH_REL * t.abs() && enter != e.1 => {
                proper.pop();
            }
            _ => proper.push(e),
        }
    }
    proper
}

fn unit(s: &mut u64) -> Vec3 {
    loop {
        let v = Vec3::new(lcg(s), lcg(s), lcg(s)) * 2.0 - 1.0;
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

#[test]
fn mesh_operands_are_crossed_once_through_edges_and_vertices() {
    let mut seed = 0xC5E6_u64;
    let mut compared = 0usize;
    let mut edge_lines = 0usize;
    for name in CLOSED {
        let (shape, positions, edges) = mesh_node(name);
        let mesh = Node::new(Geometry::Mesh(shape.clone()), 0, None);
        let (lo, hi) = positions
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| {
                (l.min(*p), h.max(*p))
            });
        let (center, radius) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
        // A box cutting through the middle of the mesh, as the CSG partner.
        let cut = Aabb::new(
            center - Vec3::splat(radius),
            center + Vec3::new(radius, 0.1 * radius, radius),
        );
        // Exact points on edges (endpoint, midpoint and a quarter point: exact in f32 for
        // the small meshes' coordinates) and on vertices.
        let mut targets: Vec<Vec3> = positions.clone();
        for e in &edges {
            let (p, q) = (positions[e[0] as usize], positions[e[1] as usize]);
            targets.push((p + q) * 0.5);
            targets.push(p * 0.75 + q * 0.25);
        }
        let step = targets.len().div_ceil(TARGETS_PER_MESH);
        for target in targets.iter().step_by(step) {
            for _ in 0..3 {
                let d = unit(&mut seed);
                let o = *target - d * (3.0 * radius);
                // The mesh alone: where the lines moved to both sides of the edge agree (a
                // transversal line), the exact line crosses exactly as they do, once per
                // surface crossing (two events at one `t` where the line touches a surface
                // are an empty interval, not a crossing).
                let exact = events(&mesh, o, d);
                assert!(!exact.1, "{name}: a closed mesh's line starts outside");
                let side = d.any_orthonormal_vector() * (1e-4 * radius);
                let moved = [events(&mesh, o + side, d), events(&mesh, o - side, d)];
                // Stable: both sides cross alike, each crossing within 1e-2 of the radius (a
                // move of 2e-4 of it shifting a crossing further means a nearly tangent line).
                let stable = moved[0].0.len() == moved[1].0.len()
                    && moved[0]
                        .0
                        .iter()
                        .zip(&moved[1].0)
                        .all(|(a, b)| a.1 == b.1 && (a.0 - b.0).abs() <= 1e-2 * radius);
                if !stable {
                    // Grazing: the two sides differ; only balance is promised.
                    assert_eq!(
                        exact.0.len() % 2,
                        0,
                        "{name}: {:?} through {target}",
                        exact.0
                    );
                    continue;
                }
                let proper = touches_removed(&exact.0);
                assert_eq!(
                    proper.len(),
                    moved[0].0.len(),
                    "{name}: through {target} along {d}: {:?} vs moved {:?}",
                    exact.0,
                    moved[0].0
                );
                for (k, &(_, enter)) in proper.iter().enumerate() {
                    assert_eq!(enter, k % 2 == 0, "{name}: {:?} through {target}", exact.0);
                }
                edge_lines += usize::from(!exact.0.is_empty());
                // The three operations with the box, both operand orders, on the exact line
                // and the moved one: the same inside/outside away from the crossings.
                for op in [CsgOp::Union, CsgOp::Intersection, CsgOp::Difference] {
                    for mesh_first in [true, false] {
                        let (a, b) = (
                            Node::new(Geometry::Mesh(shape.clone()), 0, None),
                            Node::new(Geometry::Box(cut), 0, None),
                        );
                        let (a, b) = if mesh_first { (a, b) } else { (b, a) };
                        let csg = Node::new(Geometry::Csg(op, Box::new(a), Box::new(b)), 0, None);
                        let e0 = touches_removed(&events(&csg, o, d).0);
                        let e1 = touches_removed(&events(&csg, o + side, d).0);
                        // The same crossings in the same order and direction (their `t` may
                        // shift with the sideways move where the line nearly grazes a face).
                        assert_eq!(
                            e0.iter().map(|e| e.1).collect::<Vec<_>>(),
                            e1.iter().map(|e| e.1).collect::<Vec<_>>(),
                            "{name} {op:?} mesh first {mesh_first}: through {target} along {d}: {e0:?} vs {e1:?}"
                        );
                        compared += e0.len();
                    }
                }
            }
        }
    }
    assert!(
        edge_lines > 500,
        "{edge_lines} lines through edges and vertices crossed a mesh"
    );
    assert!(compared > 2000, "{compared} crossings compared");
}

/// Light through a drilled hole: a slab `[−3, 3]² × [−½, ½]` minus the closed cube
/// mesh `[−1, 1]³` has a square hole. A shadow ray along `+z` is occluded exactly when its
/// `(x, y)` lies in the slab and outside the hole (decided analytically, away from the hole's
/// and the slab's sides). Among the rays, every one through the hole along `x = y` meets both of
/// the cube's `z` faces exactly on their diagonal edges, where a double-counted "enter" would
/// leave the drill inside and close the hole. `occludes` must also equal `closest` finding a hit.
#[test]
fn any_hit_passes_through_a_hole_drilled_by_a_mesh() {
    let (cube, _, _) = mesh_node("cube.obj");
    let slab = Aabb::new(Vec3::new(-3.0, -3.0, -0.5), Vec3::new(3.0, 3.0, 0.5));
    let drilled = Node::new(
        Geometry::Csg(
            CsgOp::Difference,
            Box::new(Node::new(Geometry::Box(slab), 0, None)),
            Box::new(Node::new(Geometry::Mesh(cube), 0, None)),
        ),
        0,
        None,
    );
    let mut ctx = QueryCtx::default();
    let mut seed = 0xD811_u64;
    let (mut through_edges, mut blocked, mut open) = (0, 0, 0);
    for i in 0..4000 {
        let (x, y) = if i % 4 == 0 {
            // On the diagonal edges of the cube's z faces (exact binary fractions included).
            let s = if i % 8 == 0 {
                (i % 64) as f32 / 64.0 - 0.5
            } else {
                lcg(&mut seed) * 1.8 - 0.9
            };
            (s, s)
        } else {
            (lcg(&mut seed) * 8.0 - 4.0, lcg(&mut seed) * 8.0 - 4.0)
        };
        let near = |v: f32, side: f32| (v.abs() - side).abs() < 1e-3;
        if near(x, 1.0) || near(y, 1.0) || near(x, 3.0) || near(y, 3.0) {
            continue;
        }
        let in_slab = x.abs() < 3.0 && y.abs() < 3.0;
        let in_hole = x.abs() < 1.0 && y.abs() < 1.0;
        let expected = in_slab && !in_hole;
        let ray = Ray::with_interval(Vec3::new(x, y, -4.0), Vec3::Z, 0.0, 8.0);
        let occluded = drilled.occludes(&ray, &mut ctx);
        assert_eq!(
            occluded, expected,
            "shadow ray at ({x}, {y}): occluded {occluded}, expected {expected}"
        );
        assert_eq!(
            drilled.closest(&ray, &mut ctx).is_some(),
            occluded,
            "closest and occludes disagree at ({x}, {y})"
        );
        through_edges += usize::from(in_hole && x == y);
        blocked += usize::from(expected);
        open += usize::from(!expected);
    }
    assert!(
        through_edges >= 900 && blocked >= 1000 && open >= 1000,
        "{through_edges} rays through the diagonal edges, {blocked} blocked, {open} open"
    );
}
