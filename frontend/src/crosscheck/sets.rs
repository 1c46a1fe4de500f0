//! The cross-check's named ray sets, deterministic for a given seed.
//!
//! | set | rays |
//! |---|---|
//! | `primary`, `primary-tiles`, `primary-stride`, `random`, `shadow`, `ao` | the sets `bench bvh` times, [`RaySet`] (camera rays in scanline order, in 8×8 tiles, with a stride; incoherent rays; shadow and ambient-occlusion rays from the camera's hit points) |
//! | `edges` | aimed at the midpoint of a random shared (two-face) edge, from a random outside origin |
//! | `vertices` | aimed exactly at a random vertex with a closed fan, from a random outside origin |
//! | `grazing` | nearly parallel to a random face (0.06°–0.6° off its plane), through an interior point |
//! | `surface` | starting on a random face (barycentric point, offset by the core's spawn rule), random direction |
//!
//! `edges` and `vertices` rays carry the incident triangles, so that a miss or a hit beyond the
//! target can be recognised as a leak when the ray crosses the surface there transversally.

use crate::obj::ObjMesh;
pub use crate::raysets::Rng;
use crate::raysets::fnv1a;
use crate::raysets::named::RaySet;
use glam::{DVec2, DVec3, Vec3};
use halfray_core::triangle::TriangleHit;
use halfray_core::{Hit, Ray};
use std::collections::HashMap;

/// The names of every set, in report order: [`RaySet::ALL`]'s, then the aimed sets.
pub const SET_NAMES: [&str; 10] = [
    "primary",
    "primary-tiles",
    "primary-stride",
    "random",
    "shadow",
    "ao",
    "edges",
    "vertices",
    "grazing",
    "surface",
];

/// Smallest angle between a grazing ray and its face's plane, radians.
pub const GRAZING_MIN_RAD: f64 = 1.0e-3;
/// Largest angle between a grazing ray and its face's plane, radians.
pub const GRAZING_MAX_RAD: f64 = 1.0e-2;

/// Projected faces whose corner angle has `|sin|` at most this (unitless) count as edge-on:
/// an edge or vertex ray through them is not counted as transversal, because the `f32` ray
/// (rounded from the `f64` construction) may pass on either side of such a sliver.
pub const EDGE_ON_SIN: f64 = 1.0e-6;

/// Largest ray-space boundary margin (barycentric units) an incident triangle may have for an
/// edge or vertex ray to count as robustly transversal: a margin of ½ means the projected
/// altitude is twice the rounding displacement, so the projected orientation cannot flip.
pub const ROBUST_MARGIN: f64 = 0.5;

/// A ray of a set, with what is known about where it was aimed.
#[derive(Clone, Debug)]
pub struct SetRay {
    /// The ray (`t_max = ∞` except where stated).
    pub ray: Ray,
    /// For `edges`/`vertices`: the triangles incident to the target and the target's `t`
    /// (1.0: the direction is `target − origin`). Set only when the crossing is transversal.
    pub target: Option<Target>,
}

/// The aimed-at edge or vertex of a ray.
#[derive(Clone, Debug)]
pub struct Target {
    /// Triangles incident to the edge or vertex.
    pub incident: Vec<u32>,
    /// Ray parameter of the target point.
    pub t: f32,
}

/// Mesh adjacency needed by the sets: triangles per undirected edge and per vertex.
pub struct Adjacency {
    /// Edges with exactly two incident triangles: `(a, b, [f0, f1])`.
    pub shared_edges: Vec<(u32, u32, [u32; 2])>,
    /// Triangles around each vertex.
    pub vertex_faces: Vec<Vec<u32>>,
    /// Vertices whose fan is closed (every edge at the vertex has two faces).
    pub closed_fan_vertices: Vec<u32>,
}

impl Adjacency {
    /// Builds the adjacency of `mesh`.
    pub fn new(mesh: &ObjMesh) -> Self {
        let mut edge_faces: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        let mut vertex_faces = vec![Vec::new(); mesh.positions.len()];
        for (f, t) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edge_faces
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push(f as u32);
                vertex_faces[a as usize].push(f as u32);
            }
        }
        let mut open_vertex = vec![false; mesh.positions.len()];
        let mut shared_edges = Vec::new();
        for (&(a, b), faces) in &edge_faces {
            if faces.len() == 2 && a != b {
                shared_edges.push((a, b, [faces[0], faces[1]]));
            } else {
                open_vertex[a as usize] = true;
                open_vertex[b as usize] = true;
            }
        }
        shared_edges.sort_unstable();
        let closed_fan_vertices = (0..mesh.positions.len() as u32)
            .filter(|&v| !open_vertex[v as usize] && vertex_faces[v as usize].len() >= 3)
            .collect();
        Self {
            shared_edges,
            vertex_faces,
            closed_fan_vertices,
        }
    }
}

fn bounds(mesh: &ObjMesh) -> (DVec3, f64) {
    let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    (
        (lo + hi) * 0.5,
        ((hi - lo).length() * 0.5).max(f64::MIN_POSITIVE),
    )
}

fn random_origin(rng: &mut Rng, center: DVec3, radius: f64) -> Vec3 {
    (center + rng.unit_vector() * (2.0 * radius)).as_vec3()
}

/// Generates `count` rays of the named set (fewer if the mesh has no suitable feature, e.g. no
/// shared edges; `shadow` and `ao` have one per camera ray that hits, found with `hits`).
/// Unknown names give `None`.
pub fn generate(
    name: &str,
    mesh: &ObjMesh,
    adj: &Adjacency,
    count: usize,
    seed: u64,
    hits: &dyn Fn(&Ray) -> Option<Hit>,
) -> Option<Vec<SetRay>> {
    let mut rng = Rng::new(seed ^ fnv1a(name.bytes()));
    let (center, radius) = bounds(mesh);
    if let Some(set) = RaySet::from_name(name) {
        let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
        let rays = set.generate(lo, hi, count, seed ^ fnv1a(name.bytes()), hits);
        return Some(
            rays.into_iter()
                .map(|ray| SetRay { ray, target: None })
                .collect(),
        );
    }
    let rays = match name {
        "edges" if !adj.shared_edges.is_empty() => (0..count)
            .map(|_| {
                let (a, b, faces) = adj.shared_edges[rng.below(adj.shared_edges.len())];
                let target = (mesh.positions[a as usize] + mesh.positions[b as usize]) * 0.5;
                let mut ray = aimed(mesh, &mut rng, center, radius, target, &faces);
                // An edge a few ulps long can have its midpoint round onto a vertex (an end,
                // or the far corner of a sliver): that ray is aimed at the vertex, whose whole
                // fan (not the edge's two triangles) decides whether it crosses transversally.
                // Not counted (the `vertices` set has such rays).
                let on_a_corner = faces
                    .iter()
                    .any(|&f| mesh.triangle(f as usize).contains(&target));
                if on_a_corner {
                    ray.target = None;
                }
                ray
            })
            .collect(),
        "vertices" if !adj.closed_fan_vertices.is_empty() => (0..count)
            .map(|_| {
                let v = adj.closed_fan_vertices[rng.below(adj.closed_fan_vertices.len())];
                let faces = &adj.vertex_faces[v as usize];
                aimed(
                    mesh,
                    &mut rng,
                    center,
                    radius,
                    mesh.positions[v as usize],
                    faces,
                )
            })
            .collect(),
        "grazing" => grazing(mesh, &mut rng, radius, count),
        "surface" => surface(mesh, &mut rng, count),
        "edges" | "vertices" => Vec::new(),
        _ => return None,
    };
    Some(rays)
}

/// The seed of one mesh's ray sets in a run seeded with `run_seed`: derived from the mesh's
/// file name (not its folder or its place in a list), so that a mesh gets the same rays in a
/// sharded, listed or resumed run.
pub fn mesh_seed(run_seed: u64, file_name: &str) -> u64 {
    run_seed.wrapping_add(fnv1a(file_name.bytes()))
}

/// A ray from a random outside origin through `target` (`t = 1` there), with the target's
/// incident faces recorded when the crossing is transversal.
fn aimed(
    mesh: &ObjMesh,
    rng: &mut Rng,
    center: DVec3,
    radius: f64,
    target: Vec3,
    faces: &[u32],
) -> SetRay {
    let o = random_origin(rng, center, radius);
    let ray = Ray::new(o, target - o);
    let transversal = crosses_transversally(mesh, &ray, faces, target);
    SetRay {
        ray,
        target: transversal.then(|| Target {
            incident: faces.to_vec(),
            t: 1.0,
        }),
    }
}

/// `true` when the projections of the incident triangles along the ray all have the same
/// orientation, each taken in the winding that agrees with its neighbours across their shared
/// edges (`fan_windings`: the mesh's own winding need not be consistent), and are
/// non-degenerate (the fan, or the two triangles of an edge, then cover a neighbourhood of the
/// target, so the ray must cross one of them) — judged in `f64` — and
/// every projected triangle is thick enough that moving its vertices by the `f32` rounding of
/// the ray-space coordinates cannot flip its orientation: its ray-space boundary margin
/// ([`crate::crosscheck::judge::ray_space_barycentrics`]) is below [`ROBUST_MARGIN`]; and the
/// ray's line crosses their union inside it, exactly (`line_crosses_fan`). The last holds by construction
/// unless the target's rounding to `f32` (or the direction's) moved the line off the edge by
/// more than a triangle is wide along the ray: an edge's midpoint rounded far from the
/// coordinate origin on a mesh whose triangles are a few ulps of its coordinates (the bunny
/// moved to `2·10⁴`), or an edge next to the mesh's silhouette, whose triangles are nearly
/// edge-on and project thinner than that rounding (the `far` sphere); such a line may cross no
/// triangle at all. Only such crossings are decidable in `f32`, and only they count towards
/// leaks.
pub fn crosses_transversally(mesh: &ObjMesh, ray: &Ray, faces: &[u32], target: Vec3) -> bool {
    let d = ray.direction.as_dvec3().normalize();
    let u = d.any_orthonormal_vector();
    let w = d.cross(u);
    let proj = |p: Vec3| {
        let q = p.as_dvec3() - target.as_dvec3();
        DVec2::new(q.dot(u), q.dot(w))
    };
    let Some(flips) = fan_windings(mesh, faces) else {
        return false;
    };
    let mut sign = 0.0;
    for (&f, flip) in faces.iter().zip(flips) {
        let [a, b, c] = mesh.triangle(f as usize).map(proj);
        let area = if flip { -1.0 } else { 1.0 } * (b - a).perp_dot(c - a);
        let scale = (b - a).length() * (c - a).length();
        if area.is_nan() || area.abs() <= EDGE_ON_SIN * scale {
            return false;
        }
        let tri = mesh.triangle(f as usize);
        if super::judge::ray_space_barycentrics(ray, &tri).is_none_or(|(_, m)| m >= ROBUST_MARGIN) {
            return false;
        }
        if sign == 0.0 {
            sign = area.signum();
        } else if area.signum() != sign {
            return false;
        }
    }
    sign != 0.0 && line_crosses_fan(mesh, ray, faces)
}

/// Whether the line of `ray` crosses the union of `faces` (the triangles around an edge or a
/// vertex) inside it, exactly: it meets one of them ([`meets`]) in its interior, or on
/// an edge that another of `faces` shares (an inner edge of the union, the target edge or a
/// spoke of the target's fan), or at a vertex whose two edges are such edges. Meeting a face
/// only on an outer edge of the union does not count: there the line may touch the surface
/// at a fold (the union's faces then lie on one side of it) and a tracer may pass it; a mesh
/// whose triangles are a few ulps of their coordinates (the octahedron moved to `1.5·10⁷`,
/// where the `f32` spacing is `1`) folds where its vertices were snapped, and an edge ray
/// whose rounded target moved its line off its edge can meet the fan only at such a fold.
fn line_crosses_fan(mesh: &ObjMesh, ray: &Ray, faces: &[u32]) -> bool {
    let shared = |f: u32, a: u32, b: u32| {
        faces.iter().any(|&g| {
            g != f && {
                let t = mesh.triangles[g as usize];
                t.contains(&a) && t.contains(&b)
            }
        })
    };
    faces.iter().any(|&f| {
        let t = mesh.triangles[f as usize];
        let signs = edge_signs(ray, &mesh.triangle(f as usize));
        meets(signs) && (0..3).all(|k| signs[k] != 0 || shared(f, t[k], t[(k + 1) % 3]))
    })
}

/// The signs of the line of `ray` against the edges `v₀v₁`, `v₁v₂`, `v₂v₀` of a triangle
/// (`orient_direction`, the side of the line the edge passes), exactly.
fn edge_signs(ray: &Ray, v: &[Vec3; 3]) -> [i32; 3] {
    use halfray_core::predicates::orient_direction;
    [(0, 1), (1, 2), (2, 0)].map(|(i, j)| orient_direction(v[i], v[j], ray.origin, ray.direction))
}

/// Whether edge signs ([`edge_signs`]) are those of a line that meets the closed triangle:
/// not two opposite ones, and not all zero (a line in the triangle's plane).
fn meets(s: [i32; 3]) -> bool {
    (s.iter().all(|&x| x >= 0) || s.iter().all(|&x| x <= 0)) && s.iter().any(|&x| x != 0)
}

/// For each of `faces` (the triangles around an edge or a vertex), whether to take it in the
/// reverse of its stored winding so that every two of them that share an edge traverse it in
/// opposite directions (the windings of a consistently oriented surface), starting from the
/// first face as stored; all `false` on a consistently oriented mesh. `None` when the faces
/// are not connected through shared edges (a vertex where two fans touch) or admit no such
/// windings (a shared edge traversed three times): such a neighbourhood is not counted.
fn fan_windings(mesh: &ObjMesh, faces: &[u32]) -> Option<Vec<bool>> {
    // The direction in which stored face `f` traverses the undirected edge `{u, w}`: `+1` for
    // `u → w`, `−1` for `w → u`, `0` when it is not one of its edges.
    let direction = |f: u32, u: u32, w: u32| {
        let t = mesh.triangles[f as usize];
        (0..3).fold(0i32, |acc, k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            acc + i32::from(a == u && b == w) - i32::from(a == w && b == u)
        })
    };
    let mut flip: Vec<Option<bool>> = vec![None; faces.len()];
    let mut stack = Vec::with_capacity(faces.len());
    if !faces.is_empty() {
        flip[0] = Some(false);
        stack.push(0);
    }
    while let Some(i) = stack.pop() {
        let fi = faces[i];
        let ti = mesh.triangles[fi as usize];
        let si = if flip[i] == Some(true) { -1 } else { 1 };
        for k in 0..3 {
            let (u, w) = (ti[k], ti[(k + 1) % 3]);
            let di = direction(fi, u, w) * si;
            for (j, &fj) in faces.iter().enumerate() {
                let dj = direction(fj, u, w);
                if j == i || dj == 0 {
                    continue;
                }
                // Consistent: `dj·sj = −di`.
                let want = dj == di;
                match flip[j] {
                    None => {
                        flip[j] = Some(want);
                        stack.push(j);
                    }
                    Some(f) if f != want => return None,
                    Some(_) => {}
                }
            }
        }
    }
    flip.into_iter().collect()
}

fn grazing(mesh: &ObjMesh, rng: &mut Rng, radius: f64, count: usize) -> Vec<SetRay> {
    let mut out = Vec::with_capacity(count);
    let mut guard = 0;
    while out.len() < count && !mesh.triangles.is_empty() && guard < count * 4 {
        guard += 1;
        let f = rng.below(mesh.triangles.len());
        let [a, b, c] = mesh.triangle(f).map(|p| p.as_dvec3());
        let n = (b - a).cross(c - a);
        if n.length_squared() == 0.0 {
            continue;
        }
        let n = n.normalize();
        let (r1, r2) = (rng.f64(), rng.f64());
        let s = r1.sqrt();
        let p = a * (1.0 - s) + b * (s * (1.0 - r2)) + c * (s * r2);
        let in_plane = n.cross(rng.unit_vector()).normalize_or_zero();
        if in_plane == DVec3::ZERO {
            continue;
        }
        let angle = GRAZING_MIN_RAD + (GRAZING_MAX_RAD - GRAZING_MIN_RAD) * rng.f64();
        let d = in_plane * libm::cos(angle) - n * libm::sin(angle);
        let o = p - d * radius;
        out.push(SetRay {
            ray: Ray::new(o.as_vec3(), d.as_vec3()),
            target: None,
        });
    }
    out
}

fn surface(mesh: &ObjMesh, rng: &mut Rng, count: usize) -> Vec<SetRay> {
    let mut out = Vec::with_capacity(count);
    let mut guard = 0;
    while out.len() < count && !mesh.triangles.is_empty() && guard < count * 4 {
        guard += 1;
        let f = rng.below(mesh.triangles.len());
        let v = mesh.triangle(f);
        let (r1, r2) = (rng.f64(), rng.f64());
        let s = r1.sqrt();
        let (b1, b2) = ((s * (1.0 - r2)) as f32, (s * r2) as f32);
        let hit = TriangleHit {
            t: 1.0,
            b1,
            b2,
            ng: (v[1] - v[0]).cross(v[2] - v[0]),
            front_face: true,
        }
        .to_hit(&v);
        if hit.normal == Vec3::ZERO {
            continue;
        }
        let w = rng.unit_vector().as_vec3();
        out.push(SetRay {
            ray: halfray_core::spawn_ray(&hit, w),
            target: None,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether the line of `ray` certainly misses the triangle `v`, in `f64` apart from the
    /// code under test: the Plücker sides `d·((v_i − o) × (v_j − o))` of its three edges
    /// include two opposite ones, each beyond `10⁻⁹` of its magnitude (the `f64` rounding of
    /// products of `f32` differences is below `10⁻¹⁵` of it).
    fn line_clearly_misses(ray: &Ray, v: &[Vec3; 3]) -> bool {
        let (o, d) = (ray.origin.as_dvec3(), ray.direction.as_dvec3());
        let s = [(0, 1), (1, 2), (2, 0)].map(|(i, j)| {
            let (a, b) = (v[i].as_dvec3() - o, v[j].as_dvec3() - o);
            let side = d.dot(a.cross(b));
            let size = d.length() * a.length() * b.length();
            if side.abs() <= 1e-9 * size {
                0.0
            } else {
                side.signum()
            }
        });
        s.contains(&1.0) && s.contains(&-1.0)
    }

    /// A cross-check finding (the octahedron rotated and moved to `1.5·10⁷`, where the `f32`
    /// spacing is `1`: its vertices snap to a grid as coarse as the solid, and it folds; its
    /// `edges` set, ray kept here). The ray is aimed at edge `0–3`'s midpoint, rounded half a
    /// unit off it, so its line passes beside faces 2 and 3. In exact rational arithmetic
    /// (Python `fractions` on these `f32` values) the line meets the mesh only on edge `0–4`
    /// at `t = 1.2`, where faces 0 and 2, consistently wound, face opposite ways along the
    /// ray (`n·d = 6.25` and `−1.25`): a fold it touches, which a tracer may pass. It met face
    /// 2 there, on the fan's outer edge, and so counted, and the watertight test's miss was a
    /// leak; it no longer counts.
    #[test]
    // The coordinates are written exactly (the `f32` values the file's rounded to), not as
    // the shortest decimals that round to them.
    #[allow(clippy::excessive_precision)]
    fn an_edge_ray_that_touches_its_fan_only_at_a_fold_does_not_count() {
        let mesh = ObjMesh {
            positions: vec![
                Vec3::new(15000001.0, -3000000.75, 2000000.125),
                Vec3::new(14999999.0, -2999999.25, 1999999.875),
                Vec3::new(15000000.0, -3000000.0, 2000001.0),
                Vec3::new(15000000.0, -3000000.0, 1999999.0),
                Vec3::new(14999999.0, -3000000.75, 1999999.875),
                Vec3::new(15000001.0, -2999999.25, 2000000.125),
            ],
            triangles: vec![
                [0, 2, 4],
                [0, 5, 2],
                [0, 4, 3],
                [0, 3, 5],
                [1, 4, 2],
                [1, 2, 5],
                [1, 3, 4],
                [1, 5, 3],
            ],
        };
        let origin = Vec3::new(15000001.0, -2999999.25, 1999997.125);
        let target = Vec3::new(15000000.0, -3000000.5, 1999999.5);
        let ray = Ray::new(origin, target - origin);
        assert_eq!(ray.direction, Vec3::new(-1.0, -1.25, 2.375));
        assert!(!crosses_transversally(&mesh, &ray, &[2, 3], target));
        // A line through vertex 0 meets face 2 on its edges `0–4` and `3–0`: inside the
        // union of vertex 0's fan (faces 0–3 share them), on the outer edges of face 2 alone.
        let through = Ray::new(origin, mesh.positions[0] - origin);
        assert!(line_crosses_fan(&mesh, &through, &[0, 1, 2, 3]));
        assert!(!line_crosses_fan(&mesh, &through, &[2]));
    }

    /// The edge and vertex rays counted as transversal do not depend on the winding of the
    /// faces. A tetrahedron wound consistently and the same one with two faces reversed (as
    /// OBJ files from scanners and CAD exports often are) get the same rays and the same
    /// verdicts, ray for ray; and every counted ray crosses the solid there, by an oracle that
    /// ignores the faces: of the two points of its line just before and just after the target,
    /// exactly one lies inside the tetrahedron (its four planes, with normals pointing away
    /// from the opposite vertex, in `f64`). Judged by the stored winding, the reversed faces
    /// made silhouette edges look crossed, and the watertight test's misses there counted as
    /// leaks.
    #[test]
    fn counted_edge_and_vertex_rays_do_not_depend_on_the_winding() {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        let consistent = ObjMesh {
            positions: positions.clone(),
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        };
        let mixed = ObjMesh {
            positions,
            triangles: vec![[0, 1, 2], [0, 1, 3], [0, 3, 2], [1, 3, 2]],
        };
        let inside = |p: glam::DVec3| {
            (0..4).all(|skip| {
                let [a, b, c] = [0, 1, 2, 3]
                    .into_iter()
                    .filter(|&i| i != skip)
                    .map(|i| consistent.positions[i].as_dvec3())
                    .collect::<Vec<_>>()[..]
                else {
                    unreachable!()
                };
                let n = (b - a).cross(c - a);
                let away = -n.dot(consistent.positions[skip].as_dvec3() - a).signum();
                away * n.dot(p - a) < 0.0
            })
        };
        for name in ["edges", "vertices"] {
            let sets = [&consistent, &mixed]
                .map(|m| generate(name, m, &Adjacency::new(m), 3_000, 11, &|_| None).unwrap());
            let (mut counted, mut silhouettes) = (0, 0);
            for (a, b) in sets[0].iter().zip(&sets[1]) {
                assert_eq!(a.ray, b.ray, "{name}");
                assert_eq!(
                    a.target.is_some(),
                    b.target.is_some(),
                    "{name}: {:?}",
                    a.ray
                );
                let (o, d) = (a.ray.origin.as_dvec3(), a.ray.direction.as_dvec3());
                let crosses = inside(o + d * (1.0 - 1e-3)) != inside(o + d * (1.0 + 1e-3));
                if a.target.is_some() {
                    counted += 1;
                    assert!(crosses, "{name}: counted, but does not cross: {:?}", a.ray);
                }
                silhouettes += usize::from(!crosses);
            }
            assert_eq!(sets[0].len(), 3_000, "{name}");
            assert!(
                counted > 200 && silhouettes > 200,
                "{name}: {counted}, {silhouettes}"
            );
        }
    }

    /// An `edges` ray whose target, the edge's midpoint rounded to `f32`, lands on a corner of
    /// the edge's triangles is aimed at that vertex, not the edge, and is not counted: an edge
    /// one ulp long on each axis (its midpoint rounds onto an end) gives no counted ray; the
    /// same triangles a thousand ulps wide give counted ones.
    #[test]
    fn an_edge_whose_midpoint_rounds_onto_a_corner_gives_no_counted_ray() {
        for (ulps, want_counted) in [(1.0f32, false), (1000.0, true)] {
            let a = Vec3::new(2.0e4, -3.0e3, 1.0e4);
            let ulp = a
                .abs()
                .to_array()
                .map(|x| f32::from_bits(x.to_bits() + 1) - x);
            let step = |k: [f32; 3]| a + Vec3::from(k) * Vec3::from(ulp) * ulps;
            let mesh = ObjMesh {
                positions: vec![
                    a,
                    step([1.0, 1.0, 1.0]),
                    step([0.0, 3.0, 1.0]),
                    step([3.0, 0.0, -1.0]),
                ],
                triangles: vec![[0, 1, 2], [1, 0, 3]],
            };
            let rays = generate("edges", &mesh, &Adjacency::new(&mesh), 200, 3, &|_| None).unwrap();
            let counted = rays.iter().filter(|r| r.target.is_some()).count();
            assert_eq!(rays.len(), 200);
            assert_eq!(
                counted > 0,
                want_counted,
                "{counted} counted at {ulps} ulps"
            );
        }
    }

    /// An edge ray counts as a transversal crossing only when its line does meet one of the
    /// edge's two triangles (no counted line misses both clearly, in `f64`). Two triangles sharing an edge, their vertices a few
    /// `f32` ulps apart (as on a mesh moved far from the coordinate origin: the bunny at
    /// `2·10⁴`), aimed at the edge's rounded midpoint from random origins as the `edges` set
    /// aims: many midpoints round off the edge by as much as the triangles are wide, and
    /// their rays miss both. Triangles a thousand ulps wide: every ray meets the edge.
    #[test]
    fn an_edge_ray_counts_only_where_its_line_meets_the_edge() {
        let mut rng = Rng::new(7);
        for (ulps, want_all) in [(3.0f32, false), (3000.0, true)] {
            let (mut counted, mut met) = (0, 0);
            for _ in 0..4_000 {
                let a = Vec3::new(2.0e4, -3.0e3, 1.0e4) + rng.unit_vector().as_vec3() * 100.0;
                let ulp = a
                    .abs()
                    .to_array()
                    .map(|x| f32::from_bits(x.to_bits() + 1) - x);
                let mut off = || {
                    let r = rng.unit_vector().as_vec3() * ulps;
                    a + Vec3::new(
                        r.x.round() * ulp[0],
                        r.y.round() * ulp[1],
                        r.z.round() * ulp[2],
                    )
                };
                let (b, c, d) = (off(), off(), off());
                let mesh = ObjMesh {
                    positions: vec![a, b, c, d],
                    triangles: vec![[0, 1, 2], [1, 0, 3]],
                };
                let target = (a + b) * 0.5;
                let o = random_origin(&mut rng, target.as_dvec3(), f64::from(ulps) * 0.02);
                let ray = Ray::new(o, target - o);
                let meets = (0..2).any(|f| !line_clearly_misses(&ray, &mesh.triangle(f)));
                if crosses_transversally(&mesh, &ray, &[0, 1], target) {
                    counted += 1;
                    met += usize::from(meets);
                    assert!(
                        meets,
                        "counted, but the line meets neither triangle: {ray:?}"
                    );
                }
            }
            assert!(counted > 100, "{counted} counted at {ulps} ulps");
            if want_all {
                assert_eq!(met, counted);
            }
        }
    }

    /// Next to a closed mesh's silhouette the edges' triangles are nearly edge-on: on the
    /// corpus's `far` sphere (at `2.5·10⁴`, its coordinates on a grid of `0.002`, triangles
    /// `0.015` across) an edge ray's rounded target can move its line past both thin
    /// triangles and off the mesh. No counted ray's line clearly misses all the triangles of
    /// its edge; with the earlier rule (through a triangle or within its boundary margin) some
    /// did, and the cross-check reported them as leaks of halfray and Embree alike.
    #[test]
    fn an_edge_ray_beside_the_silhouette_counts_only_if_its_line_crosses() {
        let far =
            crate::mesh_tools::generate::generate(crate::mesh_tools::generate::Kind::Far, 1, None)
                .unwrap();
        let mesh = ObjMesh {
            positions: far.positions,
            triangles: far.triangles,
        };
        let rays = generate("edges", &mesh, &Adjacency::new(&mesh), 60_000, 11, &|_| {
            None
        })
        .unwrap();
        let mut counted = 0;
        for r in &rays {
            let Some(target) = &r.target else { continue };
            counted += 1;
            assert!(
                target
                    .incident
                    .iter()
                    .any(|&f| !line_clearly_misses(&r.ray, &mesh.triangle(f as usize))),
                "counted, but the line misses its edge's triangles: {:?}",
                r.ray
            );
        }
        assert!(counted > 50_000, "{counted} counted");
    }

    /// The cross-machine determinism check of the aimed sets: their fingerprints
    /// ([`crate::raysets::fingerprint`] of every ray's bits, then its target's `t` and incident
    /// triangles, `u32::MAX` for none) over the generated `sphere` of size 6, seed 1, 400 rays
    /// each, seeded as `crosscheck --seed 1` seeds `sphere.obj`. `libm`'s functions, pure Rust:
    /// the values on every platform (and std's on x86-64 glibc before the switch). The six
    /// shared sets are held in `raysets::named`.
    #[test]
    fn the_aimed_sets_keep_their_fingerprints() {
        let mesh = crate::mesh_tools::generate::fingerprint_sphere();
        let adj = Adjacency::new(&mesh);
        let seed = mesh_seed(1, "sphere.obj");
        let want = [
            0x6551_dfd6_2815_1fa0,
            0x359d_5532_f879_265c,
            0x3d6e_7921_0190_730e,
            0x9daf_96dd_7c12_0cd4,
        ];
        let got = ["edges", "vertices", "grazing", "surface"].map(|name| {
            let rays = generate(
                name,
                &mesh,
                &adj,
                400,
                seed,
                &crate::raysets::named::no_hits,
            )
            .unwrap();
            crate::raysets::fingerprint(rays.iter().flat_map(|r| {
                let target = r.target.as_ref().map_or_else(
                    || vec![u32::MAX],
                    |t| {
                        [t.t.to_bits()]
                            .into_iter()
                            .chain(t.incident.iter().copied())
                            .collect()
                    },
                );
                crate::raysets::ray_bits(&r.ray).chain(target)
            }))
        });
        assert_eq!(got, want, "{:#018x?}", got);
    }
}
