//! The specification's hangar example: a drone (a small closed half-edge mesh) flies inside a
//! hangar (a box room whose walls face inward, as a triangle list in a BVH). The controller
//! casts a ray from every drone vertex along its area-weighted vertex normal (from the
//! half-edge mesh) with [`RayQuery::clearance`](halfray_core::query::RayQuery::clearance) and keeps the nearest wall distance per
//! vertex and the minimum. Every distance here is known analytically.
//!
//! A chopper (fuselage, tail boom, rotor disc, built from boxes and a polygon) then flies
//! along a path of rigid steps towards the far wall; at every step its BVH is tested against
//! the hangar's with the BVH-vs-BVH collision query, and the first contact step is predicted
//! independently from the chopper's vertices moved along the path in `f64`.

use glam::{DVec3, Vec3, vec3};
use halfray_core::bvh::collide::{Body, colliding_pairs, first_contact, min_distance};
use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, node_capacity};
use halfray_core::halfedge::{DiffuseBoundary, HalfedgeMesh, VertexId, build_scratch_len};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::Triangles;
use halfray_core::ray::Ray;
use halfray_core::solids::{CUBE_TRIANGLES, CUBE_VERTICES};
use halfray_core::transform::Transform;
use halfray_core::triangle::Watertight;
use halfray_tests::closest_by;

/// Relative tolerance on a clearance distance against its f64 analytic value. Coordinates
/// are ≤ 20, so one f32 ulp is ≤ 1.9e-6 (≈ 1e-7 relative). The distance passes through the
/// f32 vertex normal (normalisation: a few ulps of direction error, which moves a hit on a
/// wall by distance × direction error), the watertight test's shear and division (a few ulps)
/// and the final `t·|n|` product: well under 100 ulps, i.e. 1e-5 relative.
const CLEARANCE_REL_TOL: f64 = 1e-5;

/// How far a vertex normal of the axis-aligned octahedron drone may be from its axis, per
/// component (unitless). The drone's coordinates are dyadic, so each face normal is exact and
/// the four around a vertex cancel exactly across the axis (by symmetry); only the
/// normalisation rounds the axis component: one square root and one division or reciprocal
/// product, within 2 ulps of 1.
const AXIS_NORMAL_TOL: f32 = 2.0 * f32::EPSILON;

/// How far the `f32` transform's placement of a chopper vertex may be from the `f64`
/// [`placed_f64`], per coordinate, in world units. The chopper's coordinates are at most 5
/// from its centre and the placed ones below 32, where one `f32` ulp is `2⁻¹⁹`: the
/// translation and the result round once each (half an ulp each), and the rotation (the `f32`
/// sine and cosine of the rounded heading, a few `u` each, then three products and two sums)
/// moves a point at distance 5 by about `5·8u ≈ 2⁻¹⁹`. Four ulps, `2⁻¹⁷ ≈ 7.6e-6`, covers the
/// sum with margin.
const PLACEMENT_ABS_TOL: f64 = 1.0 / 131_072.0;

/// How far clear of contact (world units) the predicted gaps at the steps before and at the
/// predicted contact must be, so that the contact step is decided by geometry and not by
/// rounding: `10⁻³`, over a hundred times [`PLACEMENT_ABS_TOL`].
const STEP_DECISION_MARGIN: f64 = 1e-3;

/// The hangar: the room [0, 20] × [0, 8] × [0, 12].
const ROOM_MIN: DVec3 = DVec3::new(0.0, 0.0, 0.0);
const ROOM_MAX: DVec3 = DVec3::new(20.0, 8.0, 12.0);

/// The room's six walls, two triangles each, counter-clockwise seen from **inside** (normals
/// point into the room).
fn hangar() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (lo, hi) = (ROOM_MIN.as_vec3(), ROOM_MAX.as_vec3());
    let mut p = Vec::new();
    for i in 0..8u32 {
        p.push(vec3(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        ));
    }
    // Corner index = x + 2y + 4z (bits). Quads listed counter-clockwise seen from inside.
    let quads = [
        [0, 2, 6, 4], // x = lo, inward +x
        [1, 5, 7, 3], // x = hi, inward −x
        [0, 4, 5, 1], // y = lo (floor), inward +y
        [2, 3, 7, 6], // y = hi (ceiling), inward −y
        [0, 1, 3, 2], // z = lo, inward +z
        [4, 6, 7, 5], // z = hi, inward −z
    ];
    let mut t = Vec::new();
    for [a, b, c, d] in quads {
        t.push([a, b, c]);
        t.push([a, c, d]);
    }
    (p, t)
}

type Hangar = Bvh<Vec<BvhNode>, Vec<u32>>;

fn build_hangar(p: &[Vec3], t: &[[u32; 3]]) -> Hangar {
    let mesh = TriangleMesh::new(p, t);
    Bvh::build(
        &mesh,
        vec![BvhNode::default(); node_capacity(t.len())],
        vec![0u32; index_capacity(t.len())],
        &BuildOptions::default(),
    )
    .unwrap()
}

/// Distance from `p` along direction `d` (any length) to the first wall of the room, in f64.
fn wall_distance(p: DVec3, d: DVec3) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..3 {
        let t = if d[i] > 0.0 {
            (ROOM_MAX[i] - p[i]) / d[i]
        } else if d[i] < 0.0 {
            (ROOM_MIN[i] - p[i]) / d[i]
        } else {
            continue;
        };
        best = best.min(t);
    }
    best * d.length()
}

fn assert_distance(got: f32, want: f64, what: &str) {
    let err = (got as f64 - want).abs();
    assert!(
        err <= CLEARANCE_REL_TOL * want.max(1.0),
        "{what}: clearance {got}, analytic {want} (error {err:e})"
    );
}

type Drone = HalfedgeMesh<8, 18, 12>;

fn build_drone(p: &[Vec3], t: &[[u32; 3]]) -> Drone {
    let mut m = Drone::new();
    let mut scratch = vec![0u32; build_scratch_len(t.len())];
    m.build(p, t, &mut scratch).unwrap();
    m.validate().unwrap();
    m
}

/// An octahedron of circumradius `r` around `c`: vertices ±x, ±y, ±z (in that order),
/// outward-oriented faces.
fn octahedron(c: Vec3, r: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = vec![
        c + r * Vec3::X,
        c - r * Vec3::X,
        c + r * Vec3::Y,
        c - r * Vec3::Y,
        c + r * Vec3::Z,
        c - r * Vec3::Z,
    ];
    let mut t = Vec::new();
    for sx in [0u32, 1] {
        for sy in [0u32, 1] {
            for sz in [0u32, 1] {
                let (x, y, z) = (sx, 2 + sy, 4 + sz);
                // (+X, +Y, +Z) is counter-clockwise from outside; each mirrored axis flips it.
                t.push(if (sx + sy + sz) % 2 == 0 {
                    [x, y, z]
                } else {
                    [x, z, y]
                });
            }
        }
    }
    (p, t)
}

/// The drone's positions and area-weighted vertex normals, from the half-edge mesh.
fn points_and_normals(m: &Drone) -> (Vec<Vec3>, Vec<Vec3>) {
    let n = m.slots().vertices;
    let mut normals = vec![Vec3::ZERO; n];
    assert_eq!(m.vertex_normals(&mut normals).unwrap(), 0);
    let points = (0..n)
        .map(|i| m.position(VertexId::new(i as u32)).unwrap())
        .collect();
    (points, normals)
}

fn clearance(bvh: &Hangar, room: &TriangleMesh<'_>, m: &Drone) -> (Vec<f32>, f32) {
    let (points, normals) = points_and_normals(m);
    let mut out = vec![f32::NAN; points.len()];
    let min = bvh
        .clearance(
            &mut Triangles::new(room, &Watertight),
            &points,
            &normals,
            &mut out,
        )
        .unwrap();
    assert_eq!(
        min,
        out.iter().copied().fold(f32::INFINITY, f32::min),
        "the minimum is the minimum of the per-vertex distances"
    );
    (out, min)
}

/// Per-vertex wall distances of the octahedron around `c` with radius `r`: each vertex normal
/// is its axis (the four faces around it sum to 4·r²·axis by symmetry), so the ray from
/// `c ± r·axis` meets the wall across that axis.
fn octahedron_expected(c: DVec3, r: f64) -> [f64; 6] {
    [
        ROOM_MAX.x - (c.x + r),
        (c.x - r) - ROOM_MIN.x,
        ROOM_MAX.y - (c.y + r),
        (c.y - r) - ROOM_MIN.y,
        ROOM_MAX.z - (c.z + r),
        (c.z - r) - ROOM_MIN.z,
    ]
}

fn check_octahedron(bvh: &Hangar, room: &TriangleMesh<'_>, m: &Drone, c: DVec3, r: f64) -> f32 {
    let (dist, min) = clearance(bvh, room, m);
    let want = octahedron_expected(c, r);
    for (i, (&got, &w)) in dist.iter().zip(&want).enumerate() {
        assert_distance(
            got,
            w,
            &format!("octahedron vertex {i} (centre {c}, r {r})"),
        );
    }
    let want_min = want.iter().copied().fold(f64::INFINITY, f64::min);
    assert_distance(min, want_min, "minimum");
    min
}

#[test]
fn hangar_walls_face_inward() {
    let (p, t) = hangar();
    let room = TriangleMesh::new(&p, &t);
    let bvh = build_hangar(&p, &t);
    for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        let ray = Ray::new(vec3(7.0, 3.0, 5.0), d);
        let (_, hit) = closest_by(&bvh, &room, &Watertight, &ray, None).unwrap();
        assert!(hit.front_face, "wall along {d} is seen from its front");
    }
}

#[test]
fn octahedron_drone_clearance_moves_as_predicted() {
    let (hp, ht) = hangar();
    let room = TriangleMesh::new(&hp, &ht);
    let bvh = build_hangar(&hp, &ht);

    // Start: centre (5, 3, 7), radius 0.5. Distances +x 14.5, −x 4.5, +y 4.5, −y 2.5,
    // +z 4.5, −z 6.5: the floor is nearest (2.5, from the −y vertex).
    let (c, r) = (DVec3::new(5.0, 3.0, 7.0), 0.5);
    let (p, t) = octahedron(c.as_vec3(), r as f32);
    let mut m = build_drone(&p, &t);
    let normals_check = points_and_normals(&m).1;
    for (i, axis) in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]
        .iter()
        .enumerate()
    {
        assert!(
            (normals_check[i] - *axis).abs().max_element() <= AXIS_NORMAL_TOL,
            "vertex {i}: normal {} is its axis {axis}",
            normals_check[i]
        );
    }
    let min = check_octahedron(&bvh, &room, &m, c, r);
    assert_distance(min, 2.5, "start: floor below");

    // Translate by (−3, +4, 0): centre (2, 7, 7). The ceiling is now nearest: 8 − 7.5 = 0.5.
    let shift = DVec3::new(-3.0, 4.0, 0.0);
    for v in 0..6 {
        let v = VertexId::new(v);
        let p = m.position(v).unwrap();
        m.set_position(v, p + shift.as_vec3()).unwrap();
    }
    let c = c + shift;
    let min = check_octahedron(&bvh, &room, &m, c, r);
    assert_distance(min, 0.5, "after translation: ceiling above");

    // One diffusion step with k = ½: the four neighbours of every vertex average to the
    // centre, so x' = x + ½(c − x) and the octahedron shrinks to radius ¼ around the same
    // centre. Every clearance grows by ¼; the minimum becomes 0.75.
    let mut scratch = [Vec3::ZERO; 6];
    m.diffuse(0.5, DiffuseBoundary::Free, &mut scratch).unwrap();
    m.validate().unwrap();
    let min = check_octahedron(&bvh, &room, &m, c, 0.25);
    assert_distance(min, 0.75, "after shrinking: ceiling above");
}

/// The cube of `cube.obj` (the shared meshes), scaled by `h` around `c`: corner
/// `i = 4·[x>0] + 2·[y>0] + [z>0]`, each square split on a diagonal.
fn cube(c: Vec3, h: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = CUBE_VERTICES.map(|v| c + h * v).to_vec();
    (p, CUBE_TRIANGLES.to_vec())
}

/// Area-weighted normal directions of the cube's corners, by hand: every triangle has the
/// same area, and a corner touches both triangles of a square when the square's diagonal runs
/// through it, one otherwise. Corners 0 and 7 lie on three diagonals (the plain diagonal
/// direction); every other corner lies on one, which doubles that axis. An unweighted or
/// angle-weighted normal would give different directions, and so different distances.
const CUBE_NORMAL_DIRECTIONS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [-1.0, -1.0, 2.0],
    [-1.0, 2.0, -1.0],
    [-2.0, 1.0, 1.0],
    [2.0, -1.0, -1.0],
    [1.0, -2.0, 1.0],
    [1.0, 1.0, -2.0],
    [1.0, 1.0, 1.0],
];

#[test]
fn cube_drone_casts_along_area_weighted_corner_normals() {
    let (hp, ht) = hangar();
    let room = TriangleMesh::new(&hp, &ht);
    let bvh = build_hangar(&hp, &ht);
    let (c, h) = (DVec3::new(6.0, 2.0, 3.0), 1.0);
    let (p, t) = cube(c.as_vec3(), h as f32);
    let mut m = build_drone(&p, &t);

    let expected = |c: DVec3| -> Vec<f64> {
        (0..8)
            .map(|i| {
                let corner = c + h * DVec3::new(
                    if i & 4 != 0 { 1.0 } else { -1.0 },
                    if i & 2 != 0 { 1.0 } else { -1.0 },
                    if i & 1 != 0 { 1.0 } else { -1.0 },
                );
                wall_distance(corner, DVec3::from_array(CUBE_NORMAL_DIRECTIONS[i]))
            })
            .collect()
    };

    let check = |m: &Drone, c: DVec3| -> f32 {
        let (dist, min) = clearance(&bvh, &room, m);
        let want = expected(c);
        for (i, (&got, &w)) in dist.iter().zip(&want).enumerate() {
            assert_distance(got, w, &format!("cube corner {i} (centre {c})"));
        }
        let want_min = want.iter().copied().fold(f64::INFINITY, f64::min);
        assert_distance(min, want_min, "minimum");
        min
    };

    // Start, centre (6, 2, 3): corner i at distance t·|d| along d = CUBE_NORMAL_DIRECTIONS[i],
    // t the first wall crossing. Corner 0 = (5, 1, 2) along (−1, −1, −1): the floor at t = 1,
    // √3. Corner 4 = (7, 1, 2) along (2, −1, −1): the floor at t = 1, √6. Corner 5 =
    // (7, 1, 4) along (1, −2, 1): the floor at t = ½, √6/2 ≈ 1.22 — the minimum, although
    // corner 0 is as close to the floor: its normal leans less steeply towards it.
    let min = check(&m, c);
    assert_distance(min, 6f64.sqrt() / 2.0, "start: corner 5 towards the floor");

    // Move the drone up by 1 (the hangar is static: same BVH, just re-run). Corner 5 =
    // (7, 2, 4) now reaches the floor at t = 1: √6. Corner 6 = (7, 4, 2) along (1, 1, −2)
    // reaches the z = 0 wall at t = 1 as before: √6. Corner 0 = (5, 2, 2) reaches the floor
    // and the z = 0 wall together (a room edge) at t = 2: 2√3 ≈ 3.46. The minimum doubles.
    let dy = DVec3::new(0.0, 1.0, 0.0);
    for v in 0..8 {
        let v = VertexId::new(v);
        let p = m.position(v).unwrap();
        m.set_position(v, p + dy.as_vec3()).unwrap();
    }
    let min = check(&m, c + dy);
    assert_distance(min, 6f64.sqrt(), "after moving up: corners 5 and 6");
}

/// The chopper in its own frame (x forward, y up): the fuselage box, the tail boom box
/// behind it and the rotor disc above it (a 16-gon of radius [`ROTOR_RADIUS`], fanned from
/// its hub). Returns the positions, the triangles and the triangle range of the rotor.
fn chopper() -> (Vec<Vec3>, Vec<[u32; 3]>, std::ops::Range<u32>) {
    let mut p = Vec::new();
    let mut t = Vec::new();
    let add_box = |p: &mut Vec<Vec3>, t: &mut Vec<[u32; 3]>, c: Vec3, h: Vec3| {
        let base = p.len() as u32;
        p.extend(CUBE_VERTICES.iter().map(|&v| c + h * v));
        t.extend(CUBE_TRIANGLES.iter().map(|tri| tri.map(|i| i + base)));
    };
    add_box(&mut p, &mut t, vec3(0.0, 0.0, 0.0), vec3(1.5, 0.8, 0.7)); // fuselage
    add_box(&mut p, &mut t, vec3(-3.25, 0.2, 0.0), vec3(1.75, 0.2, 0.2)); // tail boom
    let hub = p.len() as u32;
    p.push(vec3(0.0, ROTOR_HEIGHT, 0.0));
    let first = t.len() as u32;
    for i in 0..ROTOR_SIDES {
        let a = std::f64::consts::TAU * f64::from(i) / f64::from(ROTOR_SIDES);
        p.push(vec3(
            (ROTOR_RADIUS * a.cos()) as f32,
            ROTOR_HEIGHT,
            (ROTOR_RADIUS * a.sin()) as f32,
        ));
        t.push([hub, hub + 1 + i, hub + 1 + (i + 1) % ROTOR_SIDES]);
    }
    let end = t.len() as u32;
    (p, t, first..end)
}

const ROTOR_RADIUS: f64 = 3.0;
const ROTOR_HEIGHT: f32 = 1.2;
const ROTOR_SIDES: u32 = 16;

/// Step `k` of the flight path: the chopper's centre and its heading (yaw about +y, radians).
fn path(k: u32) -> (DVec3, f64) {
    let k = f64::from(k);
    (
        DVec3::new(6.0 + 0.3 * k, 3.5 - 0.01 * k, 6.0 + 0.04 * k),
        0.015 * k,
    )
}

fn placement(k: u32) -> Transform {
    let (c, yaw) = path(k);
    Transform::rotate(Vec3::Y, yaw as f32)
        .unwrap()
        .then(&Transform::translate(c.as_vec3()).unwrap())
        .unwrap()
}

/// The chopper's vertex `v` at step `k`, in f64: a rotation by the heading about +y
/// (x' = x·cos + z·sin, z' = −x·sin + z·cos, the right-hand rule about +y), then the centre.
fn placed_f64(v: Vec3, k: u32) -> DVec3 {
    let (c, yaw) = path(k);
    let (s, co) = yaw.sin_cos();
    let v = v.as_dvec3();
    c + DVec3::new(v.x * co + v.z * s, v.y, -v.x * s + v.z * co)
}

/// Signed gap of `w` to the nearest wall (negative: through it), and which wall
/// (`2·axis + [upper]`).
fn wall_gap(w: DVec3) -> (f64, usize) {
    let mut best = (f64::INFINITY, usize::MAX);
    for axis in 0..3 {
        for (upper, gap) in [(0, w[axis] - ROOM_MIN[axis]), (1, ROOM_MAX[axis] - w[axis])] {
            if gap < best.0 {
                best = (gap, 2 * axis + upper);
            }
        }
    }
    best
}

#[test]
fn chopper_flying_in_first_touches_the_far_wall_with_its_rotor() {
    let (hp, ht) = hangar();
    let room = TriangleMesh::new(&hp, &ht);
    let hangar_bvh = build_hangar(&hp, &ht);
    let (cp, ct, rotor) = chopper();
    let heli = TriangleMesh::new(&cp, &ct);
    let heli_bvh = build_hangar(&cp, &ct);
    let (a, b) = (
        Body::new(&hangar_bvh, room).unwrap(),
        Body::new(&heli_bvh, heli).unwrap(),
    );

    // The prediction: the first step at which some vertex reaches a wall (the chopper is
    // inside the room until then, so a triangle meets a wall exactly when one of its
    // vertices reaches the wall's plane). The f64 rotation matches the f32 matrix.
    let gaps: Vec<(f64, usize, usize)> = (0..60)
        .map(|k| {
            let tf = placement(k);
            (0..cp.len())
                .map(|i| {
                    let w = placed_f64(cp[i], k);
                    assert!(
                        (w - tf.point_to_world(cp[i]).as_dvec3())
                            .abs()
                            .max_element()
                            <= PLACEMENT_ABS_TOL
                    );
                    let (g, wall) = wall_gap(w);
                    (g, wall, i)
                })
                .min_by(|x, y| x.0.total_cmp(&y.0))
                .unwrap()
        })
        .collect();
    let expected = gaps
        .iter()
        .position(|g| g.0 <= 0.0)
        .expect("contact on the path") as u32;
    let (pen, wall, vertex) = gaps[expected as usize];
    let (before, _, _) = gaps[expected as usize - 1];
    // By hand: the rotor tip at 22.5° reaches x = 20 when 6 + 0.3k + 3·cos(0.015k − 22.5°)
    // ≥ 20: 19.77 at k = 36, 20.06 at k = 37 (the tail's end, 5 behind, is at x ≥ 1).
    assert_eq!(expected, 37);
    assert_eq!(wall, 1, "the x = 20 wall");
    let hub = cp.len() - ROTOR_SIDES as usize - 1;
    assert!(vertex > hub, "a rotor tip, not vertex {vertex}");
    // Margins far above f32 rounding (~1e-6 at these coordinates): the step is robust.
    assert!(
        pen < -STEP_DECISION_MARGIN && before > STEP_DECISION_MARGIN,
        "{pen} {before}"
    );

    for k in 0..expected + 4 {
        let tf = placement(k);
        let contact = first_contact(&a, &b, &tf).unwrap();
        assert_eq!(contact.is_some(), k >= expected, "step {k}");
        if k == expected - 1 {
            // One step before: the distance is the predicted gap, from a rotor triangle to
            // the far wall. The wall is exact and the distance is evaluated in f64 (relative
            // error `DISTANCE_ERR_REL = gamma_f64(64)`, ~1e-14 here), so it differs from the
            // prediction by the placement's rounding.
            let c = min_distance(&a, &b, &tf, f64::INFINITY).unwrap().unwrap();
            assert!(
                (c.distance - before).abs() <= PLACEMENT_ABS_TOL,
                "{} vs {before}",
                c.distance
            );
            assert!(rotor.contains(&c.b) && (2..4).contains(&c.a), "{c:?}");
            assert_eq!(min_distance(&a, &b, &tf, before * 0.5).unwrap(), None);
        }
        if k == expected {
            let mut pairs = vec![(0u32, 0u32); 64];
            let n = colliding_pairs(&a, &b, &tf, &mut pairs).unwrap();
            assert!(n >= 1);
            for &(wall_tri, heli_tri) in &pairs[..n] {
                assert!(
                    (2..4).contains(&wall_tri),
                    "hangar triangle {wall_tri}: the x = 20 wall"
                );
                assert!(
                    rotor.contains(&heli_tri),
                    "chopper triangle {heli_tri}: the rotor"
                );
            }
            assert!(pairs[..n].contains(&contact.unwrap()));
        }
    }
}
