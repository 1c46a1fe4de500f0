//! Judging a disagreement between halfray and Embree against an `f64` reference, never by
//! trusting either side (two tracers that agree may share an error; the reference breaks ties).
//! The reference ([`Reference`]) tests every triangle of the mesh: it shares halfray's
//! triangle algebra (in `f64`) but none of its acceleration structure, so a triangle that
//! halfray's tree fails to visit is still found.

use crate::obj::ObjMesh;
use halfray_core::Ray;
use halfray_core::triangle::{F64Reference, TriangleIntersector};

/// One side's closest-hit answer.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Answer {
    /// Primitive (triangle index).
    pub prim: u32,
    /// Ray parameter.
    pub t: f32,
    /// Barycentric of `v1` (Embree's `u`).
    pub u: f32,
    /// Barycentric of `v2` (Embree's `v`).
    pub v: f32,
}

impl Answer {
    /// halfray's closest hit, `(triangle index, hit)`, as judged.
    #[must_use]
    pub fn of_hit(hit: Option<(u32, halfray_core::triangle::TriangleHit)>) -> Option<Self> {
        hit.map(|(prim, h)| Self {
            prim,
            t: h.t,
            u: h.b1,
            v: h.b2,
        })
    }

    /// Embree's closest hit (`rtcIntersect1`) of `ray` in `scene`, as judged.
    #[cfg(feature = "embree")]
    #[must_use]
    pub fn of_embree(scene: &crate::embree::EmbreeScene, ray: &Ray) -> Option<Self> {
        scene.intersect_ray(ray).map(|h| Self {
            prim: h.prim_id,
            t: h.t,
            u: h.u,
            v: h.v,
        })
    }
}

/// How one ray's two answers relate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Same hit/miss, same primitive, `t` within [`t_tolerance`].
    Agree,
    /// Different primitives at the same `t` (a shared edge or vertex, or coplanar duplicates),
    /// both answers valid on their own triangles ([`answer_is_valid`]). Different primitives
    /// at the same `t` of which one is not valid are judged against the reference instead.
    Tie,
    /// The difference is inside the reference's own uncertainty: the contested hit lies within
    /// the boundary margin ([`ray_space_barycentrics`]) of a triangle's edge, or `t` differs by less than the grazing-scaled
    /// tolerance.
    WithinTolerance,
    /// Embree contradicts the reference beyond the bounds (halfray agrees with it).
    EmbreeWrong,
    /// halfray contradicts the reference beyond the bounds: a genuine mismatch.
    Genuine,
}

/// Relative `t` agreement required of two `f32` answers, in ulps (`2⁻²³`) of the
/// magnitude the hit is computed from. Embree uses an approximate reciprocal refined by one
/// Newton step (≈ 2 ulps), Möller's or Plücker's algebra (≈ 10–100 ulps in the tails: their `t` is a
/// quotient of cancelling triple products) and possibly FMA; 64 ulps covers these for non-grazing rays.
pub const T_TOLERANCE_ULPS: f64 = 64.0;

/// Floor on `|cos θ|` (ray against face normal) when scaling tolerances for grazing rays:
/// the `t` error grows as `1/|cos θ|`; below 1e-4 (0.006° from the plane) we stop trusting
/// either side and the tolerance stops growing.
pub const COS_FLOOR: f64 = 1.0e-4;

/// Distance from an edge, in ulps (`2⁻²³`) of the coordinates' magnitude divided by the
/// triangle's smallest altitude, below which a point counts as "on the boundary": each side's
/// edge decision may legitimately differ there. The `f32` translation and shear of a vertex
/// each round (≈ 3 roundings: a subtraction, a product, a subtraction), and Embree's Plücker/Möller algebra adds a
/// few more; 64 ulps covers both with margin.
pub const BOUNDARY_ULPS: f64 = 64.0;

/// How far, in ulps (`2⁻²³`) of its largest coordinate, the `f32` ray aimed at an edge's or a
/// vertex's point may pass from that point: the point rounds once (an edge's midpoint
/// `(a + b)/2`, half an ulp a coordinate) and the direction `target − origin` once more (half
/// an ulp of `|d|`, at most the target's magnitude for an origin nearer the coordinate origin
/// than twice the target); 2 is twice the sum. Only [`is_leak`] takes it: two answers are
/// compared without it ([`t_tolerance`]). At `LEAK_COS` it spans `2·2⁻²³·|p|/(|d|·10⁻²)` of
/// `t`: a hit beyond the target by less is not counted as a leak, 0.05 of `t` for a ray of
/// length 5 aimed at `10⁴`, 0.5 at `10⁵`.
pub const AIM_ROUNDING_ULPS: f64 = 2.0;

/// One `f32` ulp of `1` (`2⁻²³`): the unit of [`BOUNDARY_ULPS`] and [`T_TOLERANCE_ULPS`].
const EPS: f64 = f32::EPSILON as f64;

/// The `|cos θ|` a leak's `t` tolerance ([`is_leak`]) takes for the faces around the targeted
/// edge or vertex, unitless. The target names a point, not a face: the faces that meet there lie
/// at any angle to the ray, so the tolerance is that of a face met `89.4°` from its normal,
/// `10⁻²` (the square root of [`COS_FLOOR`]): 100 times the tolerance of a face met head on,
/// a hundredth of a face met in its plane.
pub const LEAK_COS: f64 = 1.0e-2;

/// `t` of the intersection of the ray's line with the triangle's plane and `|cos θ|` of the
/// angle between the ray and the plane's normal, `(t, cos)`, in `f64` from the `f32` inputs;
/// `None` when the ray is parallel to the plane or the triangle is degenerate. Whether the
/// crossing lies in the triangle is [`ray_space_barycentrics`]'s question.
pub fn plane_crossing(ray: &Ray, tri: &[glam::Vec3; 3]) -> Option<(f64, f64)> {
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    let n = (b - a).cross(c - a);
    let denom = d.dot(n);
    if denom == 0.0 || !denom.is_finite() {
        return None;
    }
    let t = -(o - a).dot(n) / denom;
    let cos = (denom / (d.length() * n.length())).abs();
    Some((t, cos))
}

/// Barycentrics of the ray's line in the triangle, measured in the plane perpendicular to the
/// ray (the space where the watertight test decides inside/outside), in `f64` from the `f32`
/// inputs, with the boundary margin of that space: `(b, margin)`. A point is on the boundary
/// when some `|b_i| ≤ margin`. `None` when the projected triangle is degenerate (edge-on to the
/// ray, or a degenerate triangle): then every answer about it is on the boundary.
///
/// The margin is [`BOUNDARY_ULPS`] ulps of the largest vertex coordinate relative to the origin
/// (the magnitude the `f32` tests round), divided by the projected triangle's smallest altitude:
/// the change of a barycentric caused by moving a projected vertex by that much.
pub fn ray_space_barycentrics(ray: &Ray, tri: &[glam::Vec3; 3]) -> Option<([f64; 3], f64)> {
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3().normalize_or_zero();
    if d == glam::DVec3::ZERO {
        return None;
    }
    let u = d.any_orthonormal_vector();
    let w = d.cross(u);
    let rel = tri.map(|p| p.as_dvec3() - o);
    let q = rel.map(|v| glam::DVec2::new(v.dot(u), v.dot(w)));
    let area = (q[1] - q[0]).perp_dot(q[2] - q[0]);
    let longest = (q[1] - q[0])
        .length()
        .max((q[2] - q[1]).length())
        .max((q[0] - q[2]).length());
    if area.is_nan() || area == 0.0 || longest.is_nan() || longest <= 0.0 {
        return None;
    }
    let b = [
        q[1].perp_dot(q[2]) / area,
        q[2].perp_dot(q[0]) / area,
        q[0].perp_dot(q[1]) / area,
    ];
    let scale = rel
        .iter()
        .map(|v| v.abs().max_element())
        .fold(0.0, f64::max);
    let altitude = area.abs() / longest;
    Some((b, BOUNDARY_ULPS * EPS * scale / altitude))
}

/// `true` when the ray passes within the boundary margin of an edge of `tri` (or `tri` is
/// edge-on): see [`ray_space_barycentrics`].
pub fn near_boundary(ray: &Ray, tri: &[glam::Vec3; 3]) -> bool {
    ray_space_barycentrics(ray, tri).is_none_or(|(b, m)| b.iter().any(|x| x.abs() <= m))
}

/// `true` when the ray passes through `tri` or within the boundary margin of it.
pub fn inside_or_near(ray: &Ray, tri: &[glam::Vec3; 3]) -> bool {
    ray_space_barycentrics(ray, tri)
        .is_none_or(|(b, m)| b.iter().all(|&x| x >= -m) || b.iter().all(|&x| x <= m))
}

/// The `t` tolerance for a hit at `t` on a face at angle `cos` to the ray: see
/// [`T_TOLERANCE_ULPS`], [`COS_FLOOR`]. Absolute, in ray-parameter units. Relative to `t`
/// alone, not to the origin's magnitude: every tracer judged here subtracts the origin from
/// the vertices first, and `fl(vᵢ − oᵢ)` is within one rounding of `|vᵢ − oᵢ|` (exact when
/// the two are within a factor 2, Sterbenz), so two answers far from the coordinate origin are
/// compared as strictly as at it (a term `|o|/|d|` here made a box of side 1 at `10⁶` accept
/// the back face for the front one, 10 units of `t` away). Where a ray's own construction
/// rounds at the coordinates' magnitude, [`origin_t_tolerance`] and [`is_leak`] add it.
pub fn t_tolerance(t: f64, cos: f64) -> f64 {
    T_TOLERANCE_ULPS * EPS * t.abs() / cos.abs().max(COS_FLOOR)
}

/// The `t` by which a ray's origin, a point computed on a surface and rounded to `f32` (a
/// spawned shadow or ambient-occlusion ray, the `surface` set), may lie off that surface,
/// seen along the ray on a face at angle `cos` to it: [`T_TOLERANCE_ULPS`] ulps of the
/// origin's largest coordinate over `|d|·cos` (ray-parameter units). Only the interval's ends
/// take it ([`at_interval_end`]): whether the surface a ray starts on is crossed just after its
/// start is decided by that rounding, not by either tracer.
pub fn origin_t_tolerance(ray: &Ray, cos: f64) -> f64 {
    let d = ray.direction.as_dvec3().length().max(f64::MIN_POSITIVE);
    let o = ray.origin.as_dvec3().abs().max_element();
    T_TOLERANCE_ULPS * EPS * (o / d) / cos.abs().max(COS_FLOOR)
}

/// Whether `answer` is consistent with the exact geometry of its own triangle: the ray passes
/// through it or within the boundary margin ([`ray_space_barycentrics`]), at a `t` within
/// tolerance of the triangle's plane; or the ray's point at the answer's `t` lies within the
/// boundary distance of the triangle ([`point_near_triangle`]). The second form decides the
/// hits of rays nearly in a triangle's plane, where the plane's crossing moves along the ray by
/// far more than [`t_tolerance`] (capped at [`COS_FLOOR`]) allows when an input moves by one
/// rounding: a ray aimed at a vertex of a face it grazes (`cos ≈ 4·10⁻⁸`) is hit at the vertex,
/// while the line, rounded off the vertex by an ulp, crosses the plane a third of the ray's
/// length further on.
pub fn answer_is_valid(mesh: &ObjMesh, ray: &Ray, a: &Answer) -> bool {
    let Some(tri) = mesh
        .triangles
        .get(a.prim as usize)
        .map(|_| mesh.triangle(a.prim as usize))
    else {
        return false;
    };
    let Some((t, cos)) = plane_crossing(ray, &tri) else {
        return false;
    };
    (inside_or_near(ray, &tri) && (t - a.t as f64).abs() <= t_tolerance(t, cos))
        || point_near_triangle(ray, &tri, a.t as f64)
}

/// `true` when the point of `ray` at `t` lies within the boundary distance of `tri`, in 3-D
/// and `f64` from the `f32` inputs: [`BOUNDARY_ULPS`] ulps of the magnitude the tests round
/// (the largest coordinate of the vertices relative to the origin, as in
/// [`ray_space_barycentrics`]: not the origin's own, which the subtraction `vᵢ − oᵢ` does not
/// round by, see [`t_tolerance`]), the distance that margin stands for. Such a point is where
/// the ray meets the triangle once each relative input moves by a few roundings, whatever the
/// angle between them. A degenerate triangle is its three edges.
pub fn point_near_triangle(ray: &Ray, tri: &[glam::Vec3; 3], t: f64) -> bool {
    let o = ray.origin.as_dvec3();
    let p = o + ray.direction.as_dvec3() * t;
    let v = tri.map(|q| q.as_dvec3());
    let scale = v
        .iter()
        .map(|q| (*q - o).abs().max_element())
        .fold(0.0, f64::max);
    let margin = BOUNDARY_ULPS * EPS * scale;
    distance_to_triangle(p, &v) <= margin
}

/// The distance from `p` to the triangle `v` (its closest point: inside, on an edge or at a
/// vertex), in `f64`; for a degenerate triangle, to the nearest of its edges. `NaN` inputs
/// give `NaN` (no distance is within a margin).
fn distance_to_triangle(p: glam::DVec3, v: &[glam::DVec3; 3]) -> f64 {
    let to_segment = |a: glam::DVec3, b: glam::DVec3| {
        let ab = b - a;
        let len2 = ab.length_squared();
        let s = if len2 > 0.0 {
            ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - (a + ab * s)).length()
    };
    let edges = to_segment(v[0], v[1])
        .min(to_segment(v[1], v[2]))
        .min(to_segment(v[2], v[0]));
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let n2 = n.length_squared();
    if n2 > 0.0 && n2.is_finite() {
        // Inside when `p`'s projection is on the inner side of every edge.
        let inside = (0..3).all(|i| {
            let (a, b) = (v[i], v[(i + 1) % 3]);
            (b - a).cross(p - a).dot(n) >= 0.0
        });
        if inside {
            return ((p - v[0]).dot(n) / n2.sqrt()).abs();
        }
    }
    edges
}

/// The [`t_tolerance`] of the hit `a` on its own triangle: at `a.t`, with the cosine between
/// `ray` and that triangle's plane ([`COS_FLOOR`] when the ray runs in the plane). `a.prim`
/// must index `mesh`'s triangles.
fn hit_t_tolerance(mesh: &ObjMesh, ray: &Ray, a: &Answer) -> f64 {
    t_tolerance(a.t as f64, hit_cos(mesh, ray, a))
}

/// The cosine between `ray` and the plane of the hit `a`'s triangle ([`COS_FLOOR`] when the
/// ray runs in the plane). `a.prim` must index `mesh`'s triangles.
fn hit_cos(mesh: &ObjMesh, ray: &Ray, a: &Answer) -> f64 {
    let tri = mesh.triangle(a.prim as usize);
    plane_crossing(ray, &tri).map_or(COS_FLOOR, |(_, cos)| cos)
}

/// `true` when the hit `r` lies within the `t` tolerance ([`t_tolerance`], on its own
/// triangle's plane) of an end of `ray`'s interval `(t_min, t_max]`: whether it is inside is
/// then not decided by the reference's rounded `t` either (a ray spawned from a point exactly
/// on its face's plane crosses that face at `t = t_min = 0`, which the interval excludes, and
/// the `f64` reference computes `±10⁻¹⁷`), so a side may report it or pass it.
pub fn at_interval_end(mesh: &ObjMesh, ray: &Ray, r: &Answer) -> bool {
    let tol = end_tolerance(mesh, ray, r);
    at_interval_start(mesh, ray, r)
        || (ray.t_max.is_finite() && (r.t as f64 - ray.t_max as f64).abs() <= tol)
}

/// The `t` tolerance of the hit `r` against an end of `ray`'s interval: its own
/// ([`t_tolerance`]) and the origin's rounding off the surface it was spawned on
/// ([`origin_t_tolerance`]), both on `r`'s triangle's plane.
pub fn end_tolerance(mesh: &ObjMesh, ray: &Ray, r: &Answer) -> f64 {
    hit_t_tolerance(mesh, ray, r) + origin_t_tolerance(ray, hit_cos(mesh, ray, r))
}

/// `true` when the hit `r` lies within [`end_tolerance`] of `ray`'s `t_min`
/// ([`at_interval_end`]'s first end: a start-face hit).
pub fn at_interval_start(mesh: &ObjMesh, ray: &Ray, r: &Answer) -> bool {
    (r.t as f64 - ray.t_min as f64).abs() <= end_tolerance(mesh, ray, r)
}

/// How many hits at a ray's interval's start [`judge`] steps past, one after the other, to
/// find what lies beyond them: a start face and a few coplanar copies of it (exported meshes
/// duplicate faces). Past that many the rest counts as undecided.
pub const BEYOND_START_ROUNDS: usize = 8;

/// `ray` from just past `t` (its `t_min` the next `f32` above `t`, or `ray`'s own when that
/// is larger), `None` when that start is not below `t_max`: the ray whose closest hit is the
/// next one beyond a hit at `t`.
pub fn ray_past(ray: &Ray, t: f32) -> Option<Ray> {
    let start = t.next_up().max(ray.t_min);
    (start < ray.t_max).then(|| Ray::with_interval(ray.origin, ray.direction, start, ray.t_max))
}

/// Slack of [`Reference`]'s cull, relative to the distance from the ray's origin to the far
/// side of a triangle's bounding sphere (unitless): a triangle is skipped only when the ray's
/// line passes farther than `(1 + 10⁻⁹)` times its bounding radius plus `10⁻⁹` of that
/// distance from its centroid. The reference's `f64` test, and the cull's own distance, each
/// round by a few `2⁻⁵³` of that distance, so a triangle [`F64Reference`] could hit is never
/// skipped (`10⁻⁹` is about `2²³` such roundings).
pub const REFERENCE_CULL_REL: f64 = 1.0e-9;

/// The `f64` reference of one mesh, which [`judge`] breaks ties against. Its closest hit
/// ([`Reference::closest`]) is [`F64Reference`] (the watertight algorithm in `f64`, closed
/// edges) on every triangle, in index order, keeping the smallest `t` in the ray's interval; of
/// equal `t`, the smaller index (the tie rule of every halfray query). It uses no acceleration
/// structure, so a triangle that halfray's BVH fails to visit is still found: only a bounding
/// sphere per triangle, which skips the triangles whose sphere the ray's line passes clear of
/// ([`REFERENCE_CULL_REL`]). One pass over the mesh per ray: meant for the few rays the two
/// sides disagree on.
pub struct Reference<'a> {
    mesh: &'a ObjMesh,
    /// Each triangle's centroid and bounding radius (around the centroid), in `f64`.
    spheres: Vec<(glam::DVec3, f64)>,
}

impl<'a> Reference<'a> {
    /// The bounding spheres of `mesh`'s triangles.
    pub fn new(mesh: &'a ObjMesh) -> Self {
        let spheres = (0..mesh.triangles.len())
            .map(|i| {
                let v = mesh.triangle(i).map(|p| p.as_dvec3());
                let c = (v[0] + v[1] + v[2]) / 3.0;
                let r = v.iter().map(|p| p.distance(c)).fold(0.0, f64::max);
                (c, r)
            })
            .collect();
        Self { mesh, spheres }
    }

    /// The reference's closest hit of `ray` (see [`Reference`]); `None` for a miss or an
    /// invalid ray.
    pub fn closest(&self, ray: &Ray) -> Option<Answer> {
        let pre = F64Reference.prepare(ray)?;
        let o = ray.origin.as_dvec3();
        let d = ray.direction.as_dvec3();
        let d2 = d.length_squared();
        let mut best: Option<Answer> = None;
        for (i, &(c, r)) in self.spheres.iter().enumerate() {
            let p = c - o;
            let reach = r * (1.0 + REFERENCE_CULL_REL) + REFERENCE_CULL_REL * (p.length() + r);
            // `|p × d| / |d|` is the line's distance from the centroid. A NaN keeps the
            // triangle.
            if p.cross(d).length_squared() > reach * reach * d2 {
                continue;
            }
            if let Some(h) = F64Reference.intersect_prepared(&pre, ray, &self.mesh.triangle(i))
                && best.is_none_or(|b| h.t < b.t)
            {
                best = Some(Answer {
                    prim: i as u32,
                    t: h.t,
                    u: h.b1,
                    v: h.b2,
                });
            }
        }
        best
    }
}

/// Classifies one ray. `reference` gives the `f64` reference's closest hit of a ray (normally
/// [`Reference::closest`]); it is called only when the two sides disagree: on hit/miss, on `t` beyond
/// [`t_tolerance`], or on the primitive at the same `t` where either answer is not valid
/// ([`answer_is_valid`]) on its own triangle. When the reference's hit lies at the interval's
/// start ([`at_interval_start`]: a ray leaving the surface it was spawned on), it is called
/// again for the same ray from just past it ([`ray_past`]), and past each further hit at the
/// start (at most [`BEYOND_START_ROUNDS`]): the first hit beyond them is decided unless on a
/// boundary itself, and a miss or a farther hit must agree with it too.
pub fn judge(
    mesh: &ObjMesh,
    ray: &Ray,
    ours: Option<Answer>,
    embree: Option<Answer>,
    mut reference: impl FnMut(&Ray) -> Option<Answer>,
) -> Verdict {
    let tol_between =
        |x: &Answer, y: &Answer| (x.t as f64 - y.t as f64).abs() <= hit_t_tolerance(mesh, ray, x);
    match (&ours, &embree) {
        (None, None) => return Verdict::Agree,
        (Some(h), Some(e)) if tol_between(h, e) => {
            if h.prim == e.prim {
                return Verdict::Agree;
            }
            if answer_is_valid(mesh, ray, h) && answer_is_valid(mesh, ray, e) {
                return Verdict::Tie;
            }
        }
        _ => {}
    }
    // They disagree on hit/miss, on t, or on the primitive at the same t with an answer its
    // own triangle does not bear out: is each side consistent with the reference?
    let first = reference(ray);
    // Where the reference's own hit is undecided: within the margin of an edge of its
    // triangle, or within the `t` tolerance of an end of the interval.
    let on_boundary = |r: &Answer| {
        near_boundary(ray, &mesh.triangle(r.prim as usize)) || at_interval_end(mesh, ray, r)
    };
    // Beyond a hit undecided only by the interval's start: the reference's next hit, which a
    // miss or a farther hit must also be consistent with (`None`: nothing decided beyond).
    let mut beyond = None;
    if let Some(mut from) = first.filter(|r| at_interval_start(mesh, ray, r)) {
        for _ in 0..BEYOND_START_ROUNDS {
            let Some(later) = ray_past(ray, from.t) else {
                break;
            };
            match reference(&later).filter(|b| b.t > later.t_min) {
                Some(b) if at_interval_start(mesh, ray, &b) => from = b,
                found => {
                    beyond = found;
                    break;
                }
            }
        }
    }
    let beyond_ok = |x: &Option<Answer>| match (x, &beyond) {
        (_, None) => true,
        (_, Some(b)) if on_boundary(b) => true,
        (None, Some(_)) => false,
        (Some(a), Some(b)) => a.t as f64 <= b.t as f64 || tol_between(a, b),
    };
    let ok = |x: &Option<Answer>| match (x, &first) {
        (None, None) => true,
        // A miss where the reference hits: excusable only if the reference's hit is itself on
        // a boundary (within the margin of an edge of its triangle, or of an end of the
        // interval) and nothing decided lies beyond it.
        (None, Some(r)) => on_boundary(r) && beyond_ok(x),
        // A hit the reference does not report, or one closer than the reference's: valid when
        // its own triangle is hit within the boundary margin at that `t` (the reference rounded
        // past an edge this side counted as inside).
        (Some(a), None) => answer_is_valid(mesh, ray, a),
        (Some(a), Some(r)) if a.t as f64 <= r.t as f64 || tol_between(a, r) => {
            answer_is_valid(mesh, ray, a)
        }
        // Farther than the reference: it skipped the reference's hit, which must be on a
        // boundary for that to be excusable, and no decided hit beyond it.
        (Some(a), Some(r)) => on_boundary(r) && answer_is_valid(mesh, ray, a) && beyond_ok(x),
    };
    let (ours_ok, embree_ok) = (ok(&ours), ok(&embree));
    match (ours_ok, embree_ok) {
        (true, true) => Verdict::WithinTolerance,
        (true, false) => Verdict::EmbreeWrong,
        (false, _) => Verdict::Genuine,
    }
}

/// `true` when `answer` (or a miss) lets a ray aimed at an edge or vertex through: it misses,
/// or its hit lies beyond the target (`t > target_t` by more than [`t_tolerance`] at
/// [`LEAK_COS`], plus the target's own rounding: [`AIM_ROUNDING_ULPS`] ulps of its largest
/// coordinate, seen along the ray on a face at [`LEAK_COS`]).
pub fn is_leak(ray: &Ray, answer: Option<&Answer>, target_t: f32) -> bool {
    let t = target_t as f64;
    let d = ray.direction.as_dvec3();
    let target = (ray.origin.as_dvec3() + d * t).abs().max_element();
    let aim = AIM_ROUNDING_ULPS * EPS * target / d.length().max(f64::MIN_POSITIVE) / LEAK_COS;
    match answer {
        None => true,
        Some(a) => (a.t as f64 - t) > t_tolerance(t, LEAK_COS) + aim,
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use glam::Vec3;

    /// Worked by hand on the triangle `z = 0` (normal `+z`): a ray straight down its normal
    /// at twice unit speed crosses at `t = 1/2` with `cos = 1`; one from `(0, 0, 3)` along
    /// `(3, 0, −4)` at `t = 3/4` with `cos = 4/5` (wherever the crossing lies, even outside the
    /// triangle); a ray in a parallel plane and a degenerate triangle have none.
    #[test]
    fn the_plane_crossing_is_t_and_the_cosine_to_the_normal() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let down = Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(plane_crossing(&down, &tri), Some((0.5, 1.0)));
        let slanted = Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::new(3.0, 0.0, -4.0));
        let (t, cos) = plane_crossing(&slanted, &tri).unwrap();
        assert!(
            (t - 0.75).abs() < 1e-15 && (cos - 0.8).abs() < 1e-15,
            "{t} {cos}"
        );
        let parallel = Ray::new(Vec3::new(0.0, 0.0, 1.0), Vec3::X);
        assert_eq!(plane_crossing(&parallel, &tri), None);
        let flat = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        assert_eq!(plane_crossing(&down, &flat), None);
    }

    /// The unit square in `z = 0` as triangles `0 = (0, 1, 2)` and `1 = (0, 2, 3)`, split along
    /// its diagonal from `(0, 0)` to `(1, 1)`.
    pub(in crate::crosscheck) fn quad() -> ObjMesh {
        ObjMesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    fn ans(prim: u32, t: f32) -> Answer {
        Answer {
            prim,
            t,
            u: 0.0,
            v: 0.0,
        }
    }

    /// A reference for the verdicts that must not need one (the two sides agree, or tie).
    fn no_reference(_: &Ray) -> Option<Answer> {
        panic!("the reference was asked for")
    }

    #[test]
    fn verdicts() {
        let m = quad();
        let diag = Ray::new(Vec3::new(0.5, 0.5, 1.0), Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(
            judge(
                &m,
                &diag,
                Some(ans(0, 1.0)),
                Some(ans(0, 1.0)),
                no_reference
            ),
            Verdict::Agree
        );
        assert_eq!(
            judge(
                &m,
                &diag,
                Some(ans(0, 1.0)),
                Some(ans(1, 1.0)),
                no_reference
            ),
            Verdict::Tie
        );
        // Interior of triangle 0; Embree misses: Embree is wrong.
        let inner = Ray::new(Vec3::new(0.7, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let r = Some(ans(0, 1.0));
        assert_eq!(judge(&m, &inner, r, None, |_| r), Verdict::EmbreeWrong);
        // halfray misses an interior hit: genuine.
        assert_eq!(judge(&m, &inner, None, r, |_| r), Verdict::Genuine);
        // On the diagonal, a miss is excusable (boundary).
        assert_eq!(judge(&m, &diag, None, r, |_| r), Verdict::WithinTolerance);
        // Wrong t far beyond tolerance: genuine.
        assert_eq!(
            judge(&m, &inner, Some(ans(0, 1.1)), r, |_| r),
            Verdict::Genuine
        );
        assert!(is_leak(&diag, None, 1.0));
        // halfray names triangle 1 at the right depth, but (0.7, 0.2) lies outside it (the
        // triangle (0,0), (1,1), (0,1) holds only points with y ≥ x, 0.35 away here): the
        // same `t` as Embree's triangle 0 is no tie, and the reference decides.
        assert_eq!(
            judge(&m, &inner, Some(ans(1, 1.0)), r, |_| r),
            Verdict::Genuine
        );
        // Embree names the wrong one: Embree is wrong.
        assert_eq!(
            judge(&m, &inner, r, Some(ans(1, 1.0)), |_| r),
            Verdict::EmbreeWrong
        );
        // A true tie: the ray through the shared diagonal hits both triangles, whichever the
        // reference names.
        assert_eq!(
            judge(&m, &diag, Some(ans(1, 1.0)), Some(ans(0, 1.0)), |_| r),
            Verdict::Tie
        );
        assert!(!is_leak(&diag, Some(&ans(1, 1.0)), 1.0));
        assert!(is_leak(&diag, Some(&ans(1, 1.5)), 1.0));
    }

    /// A cross-check finding (the torus scaled by `10⁻³³`, its `vertices` set, seed 1: ray
    /// 1877, kept here): a ray aimed at vertex 1 of a face whose plane it grazes
    /// (`cos = −3.6·10⁻⁸`). halfray hits that face at the vertex (`u = 1`, `t = 1 − 2⁻²⁴`);
    /// Embree and the reference miss. In exact rational arithmetic (Python `fractions` on
    /// these `f32` values) the line misses the face (barycentrics `−27.0, 10.5, 17.5` in its
    /// plane, crossed at `t = 1.3437`) but passes `2.9·10⁻⁴⁰` from the vertex at halfray's `t`,
    /// 10⁻⁷ of the coordinates: within one rounding of the inputs, no genuine mismatch. The same
    /// answer at `t = 0.9`, `3.9·10⁻³⁴` from the face, stays genuine.
    #[test]
    fn a_hit_at_a_vertex_of_a_grazed_face_is_judged_by_its_point() {
        let m = ObjMesh {
            positions: vec![
                Vec3::new(8.02098e-34, 1.25e-34, 9.14618e-34),
                Vec3::new(8.32106e-34, 1.76777e-34, 8.32107e-34),
                Vec3::new(7.75902e-34, 1.76777e-34, 8.84748e-34),
            ],
            triangles: vec![[0, 1, 2]],
        };
        let ray = Ray::new(
            Vec3::new(-2.057756e-33, 2.8159195e-33, 7.6566206e-34),
            Vec3::new(2.889862e-33, -2.6391424e-33, 6.6444956e-35),
        );
        let (t, cos) = plane_crossing(&ray, &m.triangle(0)).unwrap();
        assert!((t - 1.3437).abs() < 1e-3 && cos.abs() < 1e-7, "{t} {cos}");
        let at = |t: f32| Answer {
            prim: 0,
            t,
            u: 1.0,
            v: 0.0,
        };
        assert_eq!(
            judge(&m, &ray, Some(at(0.99999994)), None, |_| None),
            Verdict::WithinTolerance
        );
        assert_eq!(
            judge(&m, &ray, Some(at(0.9)), None, |_| None),
            Verdict::Genuine
        );
    }

    /// Worked by hand on the triangle `(0,0,0), (2,0,0), (0,2,0)`: a point above its
    /// interior is as far as its height, one beyond the hypotenuse as far as that edge, one
    /// beyond a vertex as far as the vertex; a degenerate triangle is its segment.
    #[test]
    fn the_distance_to_a_triangle_is_to_its_closest_point() {
        use glam::DVec3;
        let tri = [
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        let d = |x: f64, y: f64, z: f64| distance_to_triangle(DVec3::new(x, y, z), &tri);
        assert_eq!(d(0.5, 0.5, 3.0), 3.0);
        assert_eq!(d(0.5, 0.5, -3.0), 3.0);
        assert!((d(2.0, 2.0, 0.0) - 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(d(-3.0, -4.0, 0.0), 5.0);
        assert_eq!(d(5.0, 0.0, 4.0), 5.0);
        let flat = [
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
        ];
        assert_eq!(distance_to_triangle(DVec3::new(1.0, 3.0, 4.0), &flat), 5.0);
        assert!(distance_to_triangle(DVec3::NAN, &tri).is_nan());
    }

    /// A ray that starts exactly on a face's plane (spawned from a point whose coordinates
    /// make its error bound zero: a face in the plane `z = 0`) crosses that face at `t = 0`,
    /// which the interval `(0, ∞]` excludes, while the `f64` reference rounds it to `10⁻¹⁷`
    /// (`TriangleVariant::F64Reference` on such a ray). Passing it is no genuine mismatch, and
    /// neither is reporting it (Embree's `t ≥ t_near`); a reference hit well inside the
    /// interval still is, unless it lies at a finite `t_max`.
    #[test]
    fn a_reference_hit_at_an_end_of_the_interval_is_undecided() {
        // A triangle at z = 0.5, above the quad.
        let m = two_floors();
        let up = Ray::new(Vec3::new(0.7, 0.2, 0.0), Vec3::new(0.0, 0.0, 1.0));
        let start = Some(ans(0, 1.0e-17));
        let above = Some(ans(2, 0.5));
        // Passing the start face, with or without the face above.
        assert_eq!(
            judge(&m, &up, None, start, |_| start),
            Verdict::WithinTolerance
        );
        assert_eq!(
            judge(&m, &up, above, start, |_| start),
            Verdict::WithinTolerance
        );
        // Reporting it at t = 0 (Embree's convention) against a reference that passes it.
        assert_eq!(
            judge(&m, &up, above, Some(ans(0, 0.0)), |_| above),
            Verdict::WithinTolerance
        );
        // The face above is no boundary case: missing it stays genuine.
        assert_eq!(judge(&m, &up, None, above, |_| above), Verdict::Genuine);
        // A finite `t_max` at the face above makes that hit undecided; below it, not.
        let short = Ray::with_interval(up.origin, up.direction, 0.0, 0.5);
        assert_eq!(
            judge(&m, &short, None, above, |_| above),
            Verdict::WithinTolerance
        );
        let shorter = Ray::with_interval(up.origin, up.direction, 0.0, 0.49);
        assert!(at_interval_end(&m, &shorter, &ans(0, 1.0e-17)));
        assert!(!at_interval_end(&m, &shorter, &ans(2, 0.5)));
        assert!(!at_interval_end(&m, &up, &ans(2, 0.5)));
    }

    /// Beyond an undecided start face the reference decides. A reference that rounds the start
    /// face's crossing to `10⁻¹⁷` (as `F64Reference` does on slanted rays spawned on a
    /// coordinate plane) and is otherwise the real one: missing the face above is genuine (it
    /// passed as "within tolerance": any answer behind a start-face hit did), hitting it is
    /// within tolerance, and with nothing decided beyond (`t_max` short of the face above, or
    /// nothing there) a miss still passes.
    #[test]
    fn beyond_an_undecided_start_face_the_reference_decides() {
        let m = two_floors();
        let reference = Reference::new(&m);
        let start = Some(ans(0, 1.0e-17));
        let up = Ray::new(Vec3::new(0.7, 0.2, 0.0), Vec3::new(0.0, 0.0, 1.0));
        let rounding = |r: &Ray| {
            if r.t_min == 0.0 {
                start
            } else {
                reference.closest(r)
            }
        };
        let above = Some(ans(2, 0.5));
        let next = reference.closest(&Ray { t_min: 1e-9, ..up });
        assert_eq!(next.map(|a| (a.prim, a.t)), Some((2, 0.5)));
        assert_eq!(judge(&m, &up, None, start, rounding), Verdict::Genuine);
        assert_eq!(
            judge(&m, &up, Some(ans(0, 1.0)), start, rounding),
            Verdict::Genuine
        );
        assert_eq!(
            judge(&m, &up, above, start, rounding),
            Verdict::WithinTolerance
        );
        assert_eq!(
            judge(&m, &up, start, above, rounding),
            Verdict::WithinTolerance
        );
        let short = Ray::with_interval(up.origin, up.direction, 0.0, 0.25);
        assert_eq!(
            judge(&m, &short, None, start, rounding),
            Verdict::WithinTolerance
        );
        // Over the quad's other triangle (1), which has no copy above.
        let beside = Ray::new(Vec3::new(0.2, 0.7, 0.0), up.direction);
        let start_1 = Some(ans(1, 1.0e-17));
        let rounding_1 = |r: &Ray| {
            if r.t_min == 0.0 {
                start_1
            } else {
                reference.closest(r)
            }
        };
        assert_eq!(
            judge(&m, &beside, None, start_1, rounding_1),
            Verdict::WithinTolerance
        );
        // 64 ulps of the origin's 0.7 (the face met head on), by hand: 5.34e-6.
        assert!(at_interval_start(&m, &up, &ans(0, 5.3e-6)));
        assert!(!at_interval_start(&m, &up, &ans(0, 5.4e-6)));
        assert!(!at_interval_start(&m, &up, &ans(2, 0.5)));
        assert_eq!(ray_past(&up, 0.5).map(|r| r.t_min), Some(0.5f32.next_up()));
        assert_eq!(ray_past(&short, 0.25), None);
        // A wall just ahead of a ray leaving the floor at a grazing angle is decided: it lies
        // within the start's tolerance seen on the floor's plane, but not on its own.
        let mut walled = quad();
        for z in [-1.0, 1.0] {
            walled
                .positions
                .extend([Vec3::new(0.705, -1.0, z), Vec3::new(0.705, 2.0, z)]);
        }
        walled.triangles.extend([[4, 5, 7], [4, 7, 6]]);
        let graze = Ray::new(Vec3::new(0.7, 0.2, -1e-8), Vec3::new(1.0, 0.0, 1e-3));
        let walls = Reference::new(&walled);
        let first = walls.closest(&graze);
        assert!(
            first.is_some_and(|f| f.prim <= 1 && at_interval_start(&walled, &graze, &f)),
            "{first:?}"
        );
        let wall_hit = walls.closest(&Ray {
            t_min: 1e-4,
            ..graze
        });
        assert!(wall_hit.is_some_and(|w| w.prim >= 2), "{wall_hit:?}");
        assert_eq!(
            judge(&walled, &graze, None, wall_hit, |r| walls.closest(r)),
            Verdict::Genuine
        );
        // A start on the floor's diagonal (near an edge of its triangle) still sees beyond: a
        // canopy at z = 0.5 split along the other diagonal.
        let mut canopy = quad();
        canopy.positions.extend(
            [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(x, y)| Vec3::new(x, y, 0.5)),
        );
        canopy.triangles.extend([[4, 5, 7], [5, 6, 7]]);
        let tops = Reference::new(&canopy);
        let diagonal = Ray::new(Vec3::new(0.6, 0.6, 0.0), up.direction);
        let on_diagonal = Some(ans(0, 1.0e-17));
        let rounding_d = |r: &Ray| {
            if r.t_min == 0.0 {
                on_diagonal
            } else {
                tops.closest(r)
            }
        };
        assert!(near_boundary(&diagonal, &canopy.triangle(0)));
        let top = tops.closest(&Ray {
            t_min: 1e-9,
            ..diagonal
        });
        assert!(top.is_some_and(|a| a.prim == 3), "{top:?}");
        assert_eq!(
            judge(&canopy, &diagonal, None, on_diagonal, rounding_d),
            Verdict::Genuine
        );
    }

    /// [`quad`] and, above it at `z = 0.5`, a copy of its triangle 0 (triangle 2).
    pub(in crate::crosscheck) fn two_floors() -> ObjMesh {
        let mut m = quad();
        m.positions
            .extend([0.0, 1.0].map(|x| Vec3::new(x, 0.0, 0.5)));
        m.positions
            .extend([1.0, 0.0].map(|x| Vec3::new(x, 1.0, 0.5)));
        m.triangles.push([4, 5, 6]);
        m
    }

    /// A ray straight down through the interior of both floors of [`two_floors`] meets
    /// triangle 2 first (`t = 0.5`). A halfray that passes it (missing everything, or hitting
    /// triangle 0 at `t = 1`) is a genuine mismatch. A reference that walked halfray's tree would
    /// pass it too and agree with halfray: the verdicts would be "within tolerance" (the second
    /// pair of asserts), which is why [`Reference`] tests every triangle.
    #[test]
    fn a_triangle_halfray_skips_is_genuine_against_the_reference() {
        let m = two_floors();
        let down = Ray::new(Vec3::new(0.7, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let r = Reference::new(&m).closest(&down);
        assert_eq!(r.map(|a| (a.prim, a.t)), Some((2, 0.5)));
        let embree = Some(ans(2, 0.5));
        let floor = Some(ans(0, 1.0));
        assert_eq!(judge(&m, &down, None, embree, |_| r), Verdict::Genuine);
        assert_eq!(judge(&m, &down, floor, embree, |_| r), Verdict::Genuine);
        // What a reference sharing halfray's missed triangle would have said.
        assert_eq!(
            judge(&m, &down, None, embree, |_| None),
            Verdict::WithinTolerance
        );
        assert_eq!(
            judge(&m, &down, floor, embree, |_| floor),
            Verdict::WithinTolerance
        );
    }

    /// The closed box `[o, o + s]³` of 12 triangles: `z = o` is triangles 8 and 9, `z = o + s`
    /// 10 and 11.
    fn box_at(o: f32, s: f32) -> ObjMesh {
        let positions = (0..8)
            .map(|i: u32| {
                let bit = |k: u32| s * ((i >> k) & 1) as f32;
                Vec3::new(o + bit(2), o + bit(1), o + bit(0))
            })
            .collect();
        let quads = [
            [0, 1, 3, 2],
            [4, 6, 7, 5],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 2, 6, 4],
            [1, 5, 7, 3],
        ];
        let triangles = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        ObjMesh {
            positions,
            triangles,
        }
    }

    /// A box far from the coordinate origin is judged as strictly as one at it: the back face
    /// for the front one, 10 % of `t` away, is genuine (a tolerance growing with the origin's
    /// magnitude called it a tie at 10⁶ and at 10⁴ for a 5 cm box); a hit invented beside the
    /// box is genuine; a ray aimed at an edge that passes it and hits the back face leaks
    /// (not counted at 10⁴ before; at 10⁵ the aim's own rounding spans it,
    /// [`AIM_ROUNDING_ULPS`]). The probe's cases, by hand.
    #[test]
    fn answers_far_from_the_coordinate_origin_are_judged_as_at_it() {
        for (o, s) in [(0.0, 1.0), (1.0e6, 1.0), (0.0, 0.05), (1.0e4, 0.05)] {
            let m = box_at(o, s);
            let reference = Reference::new(&m);
            let down = Ray::new(
                Vec3::new(o + 0.3 * s, o + 0.6 * s, o + 11.0 * s),
                Vec3::new(0.0, 0.0, -1.0),
            );
            let front = reference.closest(&down).unwrap();
            assert!(
                front.prim >= 10 && (front.t - 10.0 * s).abs() <= 1e-3 * s,
                "{front:?}"
            );
            let back = ans(if front.prim == 10 { 8 } else { 9 }, 11.0 * s);
            let verdict = judge(&m, &down, Some(back), Some(front), |_| Some(front));
            assert_eq!(verdict, Verdict::Genuine, "box {s} at {o}");
            let beside = Ray::new(
                Vec3::new(o + 6.0 * s, o + 0.5 * s, o + 10.0 * s),
                Vec3::new(0.0, 0.0, -1.0),
            );
            let invented = Some(ans(8, 9.5 * s));
            let verdict = judge(&m, &beside, invented, None, |r| reference.closest(r));
            assert_eq!(verdict, Verdict::Genuine, "box {s} at {o}");
        }
        for o in [0.0, 1.0e4] {
            let target = Vec3::new(o + 0.5, o + 1.0, o + 1.0);
            let origin = Vec3::new(o + 0.5, o + 4.0, o + 5.0);
            let edge = Ray::new(origin, target - origin);
            assert!(is_leak(&edge, Some(&ans(8, 1.25)), 1.0), "at {o}");
            assert!(!is_leak(&edge, Some(&ans(10, 1.0)), 1.0), "at {o}");
        }
    }

    /// The brute-force oracle: [`F64Reference`] on every triangle in index order, no cull,
    /// strict `<` (of equal `t`, the smaller index).
    fn brute(mesh: &ObjMesh, ray: &Ray) -> Option<(u32, f32)> {
        let mut best: Option<(u32, f32)> = None;
        for i in 0..mesh.triangles.len() {
            if let Some(h) = F64Reference.intersect(ray, &mesh.triangle(i))
                && best.is_none_or(|(_, t)| h.t < t)
            {
                best = Some((i as u32, h.t));
            }
        }
        best
    }

    /// An `n × n` grid of unit squares (two triangles each, shared edges and vertices) scaled
    /// by `scale` and moved to `at`, then the same grid again, tilted and jittered, so that
    /// rays meet coplanar-free overlapping layers.
    fn grid_mesh(n: u32, scale: f32, at: Vec3, rng: &mut crate::raysets::Rng) -> ObjMesh {
        let mut m = ObjMesh {
            positions: Vec::new(),
            triangles: Vec::new(),
        };
        for layer in 0..2u32 {
            let base = m.positions.len() as u32;
            for j in 0..=n {
                for i in 0..=n {
                    let jitter = if layer == 0 {
                        0.0
                    } else {
                        rng.range(-0.3, 0.3) as f32
                    };
                    let p = Vec3::new(
                        i as f32,
                        j as f32,
                        layer as f32 * (0.5 + 0.1 * i as f32) + jitter,
                    );
                    m.positions.push(at + p * scale);
                }
            }
            let v = |i: u32, j: u32| base + j * (n + 1) + i;
            for j in 0..n {
                for i in 0..n {
                    m.triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                    m.triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
                }
            }
        }
        m
    }

    /// [`Reference::closest`] equals the brute-force loop, and halfray's BVH with the same
    /// triangle test (the tie rule of the queries), on rays aimed exactly at vertices (ties
    /// among a fan), at edge midpoints, at random points and in random directions, from near
    /// and from 10⁴ grid sizes away (a tiny bounding sphere at a large distance: the cull's
    /// slack), on grids at 1, 10⁻²⁰, 10²⁰ and at 10⁵ from the origin.
    #[test]
    fn the_reference_is_brute_force() {
        let mut rng = crate::raysets::Rng::new(7);
        for (scale, at) in [
            (1.0, Vec3::ZERO),
            (1.0e-20, Vec3::ZERO),
            (1.0e20, Vec3::ZERO),
            (1.0, Vec3::new(1.0e5, -3.0e4, 2.0e5)),
        ] {
            let m = grid_mesh(6, scale, at, &mut rng);
            let reference = Reference::new(&m);
            let accel = crate::accel::MeshAccel::new(m.clone()).unwrap();
            let center = (at + Vec3::splat(3.0 * scale)).as_dvec3();
            let mut hits = 0;
            for k in 0..4000 {
                let tri = m.triangle(rng.below(m.triangles.len()));
                let target = match k % 4 {
                    0 => tri[rng.below(3)].as_dvec3(),
                    1 => (tri[0].as_dvec3() + tri[1].as_dvec3()) / 2.0,
                    2 => {
                        let (a, b) = (rng.f64(), rng.f64());
                        let (a, b) = if a + b > 1.0 {
                            (1.0 - a, 1.0 - b)
                        } else {
                            (a, b)
                        };
                        let [p, q, r] = tri.map(|v| v.as_dvec3());
                        p + (q - p) * a + (r - p) * b
                    }
                    _ => center + rng.unit_vector() * f64::from(scale) * 3.0,
                };
                let dist = f64::from(scale) * if rng.chance(0.5) { 10.0 } else { 6.0e4 };
                let origin = (center + rng.unit_vector() * dist).as_vec3();
                let ray = Ray::new(origin, (target - origin.as_dvec3()).as_vec3());
                let got = reference.closest(&ray).map(|a| (a.prim, a.t));
                let want = brute(&m, &ray);
                assert_eq!(got, want, "{ray:?}");
                let bvh = accel
                    .closest_variant(halfray_core::triangle::TriangleVariant::F64Reference, &ray);
                assert_eq!(got, bvh.map(|(i, h)| (i, h.t)), "{ray:?}");
                hits += usize::from(want.is_some());
            }
            assert!(hits > 2500, "{scale} {at}: {hits} hits");
        }
    }
}
