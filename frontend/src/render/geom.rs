//! Scene geometry: primitives, transformed nodes and CSG, with closest-hit, any-hit and
//! "all crossings along the line" (interval) queries.
//!
//! Every closest-hit query returns a world-space [`Hit`] whose point comes with a conservative
//! error bound, so that secondary rays can start with [`halfray_core::spawn_ray`] and no scene
//! epsilon.
//!
//! **CSG** is evaluated on intervals: each operand reports every crossing of its boundary along
//! the whole line `t ∈ (−∞, +∞)` ([`Node::events`]) with a flag saying whether the ray enters
//! or leaves the solid, plus whether the line starts inside (`t → −∞`). A mesh reports each
//! crossing of its surface once, whatever edge or vertex the line passes through
//! (`mesh_events`); winding counts per operand give its inside/outside state between
//! crossings; the boolean operation combines the two states and every change of the combined
//! state is a crossing of the result.

use crate::accel::MeshAccel;
use crate::render::xform::bounds_to_world;
use glam::{Vec2, Vec3};
use halfray_core::aabb::SlabRay;
use halfray_core::bvh::TraversalStats;
use halfray_core::float::gamma;
use halfray_core::plane::Plane;
use halfray_core::quadric::{Ellipsoid, Quadric};
use halfray_core::sphere::Sphere;
use halfray_core::transform::Transform;
use halfray_core::triangle::{TriangleIntersector, Watertight};
use halfray_core::{Aabb, Hit, Ray};
use std::sync::Arc;

/// A hit with what shading needs besides the geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// World-space hit.
    pub hit: Hit,
    /// Material index.
    pub material: u32,
    /// Barycentrics `(b0, b1, b2)` for triangle hits.
    pub bary: Option<Vec3>,
    /// Unit shading normal, on the same side as `hit.normal` (interpolated vertex normals of a
    /// mesh with `shading = "smooth"`); `None`: shade with the geometric normal. Rays are
    /// spawned from the geometric hit either way.
    pub shading: Option<Vec3>,
}

/// An object-space surface hit in world space: the hit by [`Transform::hit_to_world`], the
/// shading normal by the normal transform, kept on the geometric normal's side (a mirroring
/// transform flips one of them).
fn to_world(t: &Transform, mut h: SurfaceHit) -> SurfaceHit {
    h.hit = t.hit_to_world(&h.hit);
    let geometric = h.hit.normal;
    h.shading = h.shading.map(|n| {
        let w = t.normal_to_world(n);
        if w.dot(geometric) < 0.0 { -w } else { w }
    });
    h
}

impl SurfaceHit {
    /// The normal to shade with, facing the incoming ray: the shading normal when there is
    /// one (flipped with the geometric normal for a back-face hit), else the geometric one.
    pub fn shading_normal(&self) -> Vec3 {
        match self.shading {
            Some(n) if self.hit.front_face => n,
            Some(n) => -n,
            None => self.hit.facing_normal(),
        }
    }
}

/// One boundary crossing along a line.
#[derive(Clone, Copy, Debug)]
pub struct Event {
    /// Ray parameter.
    pub t: f32,
    /// `true` when the line enters the solid here.
    pub enter: bool,
    /// The hit (normal pointing out of the solid).
    pub hit: SurfaceHit,
}

/// Largest polygon the scene format accepts (the core's polygons have a fixed capacity).
pub const POLYGON_MAX_VERTICES: usize = 64;

/// A planar polygon (the core's, even–odd rule).
pub type Polygon = halfray_core::polygon::Polygon<POLYGON_MAX_VERTICES>;

/// A general quadric (solid where `f < 0`), optionally clipped to a box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClippedQuadric {
    /// The surface.
    pub quadric: Quadric,
    /// Clip box (hits outside are dropped); `None` for the whole surface.
    pub clip: Option<Aabb>,
}

/// A mesh primitive (shared by all its instances).
pub struct MeshShape {
    /// Name in the scene file.
    pub name: String,
    /// Triangles and BVH.
    pub accel: MeshAccel,
    /// Boundary (unpaired) directed edges; 0 for a closed, consistently oriented mesh.
    pub boundary_edges: usize,
    /// Unit vertex normals (area-weighted) for smooth shading, one per position.
    pub normals: Option<Vec<Vec3>>,
}

impl std::fmt::Debug for MeshShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "MeshShape({:?}, {} triangles, {} boundary edges)",
            self.name,
            self.accel.mesh.triangles.len(),
            self.boundary_edges
        )
    }
}

/// Boolean operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CsgOp {
    /// A ∪ B.
    Union,
    /// A ∩ B.
    Intersection,
    /// A − B.
    Difference,
}

impl CsgOp {
    #[inline]
    fn apply(self, a: bool, b: bool) -> bool {
        match self {
            Self::Union => a || b,
            Self::Intersection => a && b,
            Self::Difference => a && !b,
        }
    }
}

/// A primitive or a CSG combination.
#[derive(Clone, Debug)]
pub enum Shape {
    /// Sphere.
    Sphere(Sphere),
    /// Ellipsoid.
    Ellipsoid(Ellipsoid),
    /// General quadric.
    Quadric(ClippedQuadric),
    /// Axis-aligned box (a solid).
    Box(Aabb),
    /// Infinite plane through `point` with unit `normal` (as a CSG operand: the half-space
    /// behind the normal).
    Plane(Plane),
    /// Single triangle (counter-clockwise faces the viewer).
    Triangle([Vec3; 3]),
    /// Planar polygon (boxed: 64 inline vertices).
    Polygon(Box<Polygon>),
    /// Triangle mesh instance.
    Mesh(Arc<MeshShape>),
    /// CSG.
    Csg(CsgOp, Box<Node>, Box<Node>),
}

/// A shape with its material and optional transform.
#[derive(Clone, Debug)]
pub struct Node {
    /// The shape in object space.
    pub shape: Shape,
    /// Material index (CSG operands without one inherit the parent's).
    pub material: u32,
    /// Object → world (parent) transform.
    pub transform: Option<Transform>,
    /// Bounds in the parent's space (`None`: unbounded).
    pub bounds: Option<Aabb>,
}

/// Per-query scratch and counters.
#[derive(Default)]
pub struct QueryCtx {
    /// BVH traversal counters (the heat map).
    pub stats: TraversalStats,
    /// When set, solids are intersected through the interval (CSG) path too
    /// (`--force-all-effects`).
    pub force_intervals: bool,
}

// ---------------------------------------------------------------------------------------------
// Primitives

/// The hit of `intersect` at the root `t` of the ray's line: the interval is narrowed to
/// `(t⁻, t]` (one ulp below `t`), so an intersector that takes the nearest root in the interval
/// returns exactly this root, computed as in a plain query.
#[inline]
fn hit_at_root(ray: &Ray, t: f32, intersect: impl Fn(&Ray) -> Option<Hit>) -> Option<Hit> {
    intersect(&Ray::with_interval(
        ray.origin,
        ray.direction,
        t.next_down(),
        t,
    ))
}

/// Whether the line `o + t·d` is inside (`f < 0`) the quadric as `t → −∞`: the sign of the
/// leading coefficient of `f(o + t·d)`.
fn quadric_inside_at_start(q: &Quadric, ray: &Ray) -> bool {
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let qa = d.dot(q.matrix() * d);
    let qb = d.dot(q.gradient(o));
    if qa != 0.0 {
        qa < 0.0
    } else if qb != 0.0 {
        qb > 0.0
    } else {
        q.eval(o) < 0.0
    }
}

impl ClippedQuadric {
    fn in_clip(&self, h: &Hit) -> bool {
        self.clip.is_none_or(|b| b.contains_point(h.point))
    }

    fn closest(&self, ray: &Ray) -> Option<Hit> {
        if self.clip.is_none() {
            return self.quadric.intersect(ray);
        }
        let (t0, t1) = self.quadric.roots(ray)?;
        [t0 as f32, t1 as f32]
            .into_iter()
            .filter(|&t| ray.contains(t))
            .filter_map(|t| hit_at_root(ray, t, |r| self.quadric.intersect(r)))
            .find(|h| self.in_clip(h))
    }
}

/// Hit on an axis-aligned box at `t` entering (`enter`) or leaving, face snapped exactly.
fn box_hits(b: &Aabb, ray: &Ray) -> Option<(Hit, Hit)> {
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    let (mut a0, mut a1) = (0usize, 0usize);
    for axis in 0..3 {
        let (lo, hi) = (f64::from(b.min[axis]), f64::from(b.max[axis]));
        if d[axis] == 0.0 {
            if o[axis] < lo || o[axis] > hi {
                return None;
            }
            continue;
        }
        let (mut n, mut f) = ((lo - o[axis]) / d[axis], (hi - o[axis]) / d[axis]);
        if n > f {
            std::mem::swap(&mut n, &mut f);
        }
        if n > t0 {
            t0 = n;
            a0 = axis;
        }
        if f < t1 {
            t1 = f;
            a1 = axis;
        }
    }
    if !(t0 <= t1) || !t0.is_finite() || !t1.is_finite() {
        return None;
    }
    let mk = |t: f64, axis: usize, enter: bool| {
        let mut p = o + d * t;
        let mut normal = Vec3::ZERO;
        // Entering through the face the ray moves into: the near face.
        let to_max = (d[axis] < 0.0) == enter;
        p[axis] = if to_max {
            f64::from(b.max[axis])
        } else {
            f64::from(b.min[axis])
        };
        normal[axis] = if to_max { 1.0 } else { -1.0 };
        let point = p.as_vec3().clamp(b.min, b.max);
        let mut err = point.abs() * gamma(3);
        err[axis] = 0.0;
        Hit {
            t: t as f32,
            point,
            point_error: err,
            normal,
            uv: Vec2::ZERO,
            front_face: ray.direction.dot(normal) < 0.0,
        }
    };
    Some((mk(t0, a0, true), mk(t1, a1, false)))
}

fn tri_hit(v: &[Vec3; 3], ray: &Ray) -> Option<(Hit, Vec3)> {
    let th = Watertight.intersect(ray, v)?;
    Some((th.to_hit(v), Vec3::new(th.b0(), th.b1, th.b2)))
}

impl MeshShape {
    fn closest(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<(Hit, Vec3, Option<Vec3>)> {
        let (i, th) = self.accel.closest_with_stats(&Watertight, ray, stats)?;
        let v = self.accel.mesh.triangle(i as usize);
        let bary = Vec3::new(th.b0(), th.b1, th.b2);
        let hit = th.to_hit(&v);
        Some((hit, bary, self.shading_normal(i as usize, bary, hit.normal)))
    }

    /// The interpolated vertex normal of triangle `tri` at barycentrics `bary`, turned to the
    /// side of the geometric normal `geometric`; `None` without vertex normals or where they
    /// cancel.
    pub fn shading_normal(&self, tri: usize, bary: Vec3, geometric: Vec3) -> Option<Vec3> {
        let normals = self.normals.as_ref()?;
        let t = self.accel.mesh.triangles.get(tri)?;
        let n = t
            .iter()
            .zip(bary.to_array())
            .map(|(&k, b)| normals.get(k as usize).copied().unwrap_or(Vec3::ZERO) * b)
            .sum::<Vec3>()
            .try_normalize()?;
        Some(if n.dot(geometric) < 0.0 { -n } else { n })
    }

    /// Every triangle the closed watertight test hits on the ray's interval, with its index
    /// and [`halfray_core::triangle::WatertightRay::crossing_sign`] (0 for a triangle that the
    /// rule does not count: the second triangle of an edge, the rest of a vertex's fan).
    fn all_hits(&self, ray: &Ray, stats: &mut TraversalStats, out: &mut Vec<MeshHit>) {
        let Some(pre) = Watertight.prepare(ray) else {
            return;
        };
        let _ = self.accel.bvh().closest_hit::<()>(
            ray,
            |prim, v, r| {
                // `r.t_max` never shrinks: we never report a hit, so every crossing is seen.
                if let Some(th) = Watertight.intersect_prepared(&pre, r, v) {
                    out.push(MeshHit {
                        prim,
                        hit: th.to_hit(v),
                        bary: Vec3::new(th.b0(), th.b1, th.b2),
                        sign: pre.crossing_sign(r.origin, v),
                    });
                }
                None
            },
            Some(stats),
        );
    }
}

/// One triangle hit of [`MeshShape::all_hits`].
struct MeshHit {
    prim: u32,
    hit: Hit,
    bary: Vec3,
    sign: i8,
}

/// The crossings of a closed mesh along a whole line, from its triangle hits: **one per
/// surface crossing**, whatever edge or vertex the line passes through. Hits at equal `t` form
/// one point of the line; there the crossings [`WatertightRay::crossing_sign`] counts (those
/// of the line moved infinitesimally off the edge) become events, alternating from the state
/// before the point, so the winding count changes by exactly their sum. A point where the
/// closed test hits but the rule counts nothing (the line grazes an edge or vertex) becomes an
/// empty interval, two events at the same `t`: the surface is still seen there, as a plain
/// closest hit sees it. Each point's first event carries the hit of its smallest triangle
/// index, the closest-hit rule, so a mesh traced through this path shows the same picture
/// (`--force-all-effects`).
///
/// [`WatertightRay::crossing_sign`]: halfray_core::triangle::WatertightRay::crossing_sign
fn mesh_events(
    mut hits: Vec<MeshHit>,
    event: impl Fn(Hit, Vec3, u32, bool) -> Event,
) -> Vec<Event> {
    hits.sort_by(|a, b| a.hit.t.total_cmp(&b.hit.t).then(a.prim.cmp(&b.prim)));
    let mut out = Vec::with_capacity(hits.len());
    let mut inside = false;
    let mut i = 0;
    while i < hits.len() {
        let t = hits[i].hit.t;
        let group = hits[i..].iter().take_while(|h| h.hit.t == t).count();
        let point = &hits[i..i + group];
        let counted = point.iter().filter(|h| h.sign != 0).count();
        // An empty interval where nothing is counted; else one event per counted crossing.
        let n = if counted == 0 { 2 } else { counted };
        for k in 0..n {
            inside = !inside;
            // The first event: the closest-hit record; later ones: a counted triangle.
            let h = if k == 0 {
                &point[0]
            } else {
                point
                    .iter()
                    .filter(|h| h.sign != 0)
                    .nth(k)
                    .unwrap_or(&point[0])
            };
            out.push(event(h.hit, h.bary, h.prim, inside));
        }
        i += group;
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Nodes

impl Shape {
    /// `true` for shapes that bound a solid (usable as CSG operands).
    pub fn is_solid(&self) -> bool {
        match self {
            Self::Sphere(_) | Self::Ellipsoid(_) | Self::Box(_) | Self::Plane(_) => true,
            Self::Csg(..) => true,
            Self::Quadric(q) => q.clip.is_none(),
            Self::Mesh(m) => m.boundary_edges == 0,
            Self::Triangle(_) | Self::Polygon(_) => false,
        }
    }

    /// Object-space bounds (`None`: unbounded).
    pub fn bounds(&self) -> Option<Aabb> {
        match self {
            Self::Sphere(s) => Some(Aabb::new(
                s.center() - Vec3::splat(s.radius()),
                s.center() + Vec3::splat(s.radius()),
            )),
            Self::Ellipsoid(e) => Some(Aabb::new(e.center() - e.radii(), e.center() + e.radii())),
            Self::Quadric(q) => q.clip,
            Self::Box(b) => Some(*b),
            Self::Plane(_) => None,
            Self::Triangle(v) => Some(Aabb::from_points(v)),
            Self::Polygon(p) => Some(Aabb::from_points(p.vertices())),
            Self::Mesh(m) => m.accel.mesh.bounds().map(|(lo, hi)| Aabb::new(lo, hi)),
            Self::Csg(op, a, b) => match op {
                CsgOp::Union => match (a.bounds, b.bounds) {
                    (Some(x), Some(y)) => Some(x.union(y)),
                    _ => None,
                },
                CsgOp::Intersection => match (a.bounds, b.bounds) {
                    (Some(x), Some(y)) => Some(Aabb::new(x.min.max(y.min), x.max.min(y.max))),
                    (x, y) => x.or(y),
                },
                CsgOp::Difference => a.bounds,
            },
        }
    }
}

/// Pads a box outward by a relative amount so curved primitives' rounding stays inside.
fn pad(b: Aabb) -> Aabb {
    let e = (b.min.abs().max(b.max.abs()) + b.extent()) * gamma(8);
    Aabb::new(b.min - e, b.max + e)
}

impl Node {
    /// A node; bounds are computed from the shape and transform.
    pub fn new(shape: Shape, material: u32, transform: Option<Transform>) -> Self {
        let bounds = shape.bounds().map(|b| {
            let b = pad(b);
            match &transform {
                Some(t) => bounds_to_world(t, &b),
                None => b,
            }
        });
        Self {
            shape,
            material,
            transform,
            bounds,
        }
    }

    /// `true` when the ray's interval can touch the bounds.
    #[inline]
    fn may_hit(&self, ray: &Ray) -> bool {
        match &self.bounds {
            None => true,
            Some(b) => SlabRay::new(ray)
                .and_then(|s| b.intersect_slab(&s, ray.t_min, ray.t_max))
                .is_some(),
        }
    }

    /// Closest hit in `(t_min, t_max]`, in the parent's space.
    pub fn closest(&self, ray: &Ray, ctx: &mut QueryCtx) -> Option<SurfaceHit> {
        if !self.may_hit(ray) {
            return None;
        }
        match &self.transform {
            Some(t) => {
                let local = t.ray_to_object(ray);
                Some(to_world(t, self.closest_local(&local, ctx)?))
            }
            None => self.closest_local(ray, ctx),
        }
    }

    /// Whether anything is hit in `(t_min, t_max]` (shadow rays).
    pub fn occludes(&self, ray: &Ray, ctx: &mut QueryCtx) -> bool {
        if !self.may_hit(ray) {
            return false;
        }
        if let Shape::Mesh(m) = &self.shape {
            let local = match &self.transform {
                Some(t) => t.ray_to_object(ray),
                None => *ray,
            };
            return m.accel.any(&Watertight, &local);
        }
        self.closest(ray, ctx).is_some()
    }

    fn surf(&self, hit: Hit, bary: Option<Vec3>) -> SurfaceHit {
        SurfaceHit {
            hit,
            material: self.material,
            bary,
            shading: None,
        }
    }

    fn closest_local(&self, ray: &Ray, ctx: &mut QueryCtx) -> Option<SurfaceHit> {
        let via_intervals =
            matches!(self.shape, Shape::Csg(..)) || (ctx.force_intervals && self.shape.is_solid());
        if via_intervals {
            let mut events = Vec::new();
            let line =
                Ray::with_interval(ray.origin, ray.direction, f32::NEG_INFINITY, f32::INFINITY);
            self.events_local(&line, ctx, &mut events);
            return events
                .into_iter()
                .find(|e| ray.contains(e.t))
                .map(|e| e.hit);
        }
        let pick = |h: Hit| ray.contains(h.t).then_some(h);
        match &self.shape {
            Shape::Sphere(s) => Some(self.surf(s.intersect(ray)?, None)),
            Shape::Ellipsoid(e) => Some(self.surf(e.intersect(ray)?, None)),
            Shape::Quadric(q) => Some(self.surf(q.closest(ray)?, None)),
            Shape::Box(b) => {
                let (h0, h1) = box_hits(b, ray)?;
                let h = pick(h0).or_else(|| pick(h1))?;
                Some(self.surf(h, None))
            }
            Shape::Plane(p) => Some(self.surf(p.intersect(ray)?, None)),
            Shape::Triangle(v) => {
                let (h, b) = tri_hit(v, ray)?;
                Some(self.surf(h, Some(b)))
            }
            Shape::Polygon(p) => Some(self.surf(p.intersect(ray)?, None)),
            Shape::Mesh(m) => {
                let (h, b, shading) = m.closest(ray, &mut ctx.stats)?;
                Some(SurfaceHit {
                    shading,
                    ..self.surf(h, Some(b))
                })
            }
            Shape::Csg(..) => None,
        }
    }

    /// Every boundary crossing along the ray's line (the ray's interval is ignored: the whole
    /// line is used), sorted by `t`, in the parent's space, and whether the line starts inside.
    pub fn events(&self, ray: &Ray, ctx: &mut QueryCtx, out: &mut Vec<Event>) -> bool {
        match &self.transform {
            Some(t) => {
                let local = t.ray_to_object(ray);
                let start = out.len();
                let inside = self.events_local(&local, ctx, out);
                for e in &mut out[start..] {
                    e.hit = to_world(t, e.hit);
                }
                inside
            }
            None => self.events_local(ray, ctx, out),
        }
    }

    fn event(&self, hit: Hit, bary: Option<Vec3>) -> Event {
        Event {
            t: hit.t,
            enter: hit.front_face,
            hit: self.surf(hit, bary),
        }
    }

    /// Events at both roots of a closed quadric surface (a double root, a tangent line, gives
    /// no crossing).
    fn push_roots(
        &self,
        line: &Ray,
        roots: [f32; 2],
        intersect: impl Fn(&Ray) -> Option<Hit>,
        out: &mut Vec<Event>,
    ) {
        if roots[0] == roots[1] {
            return;
        }
        for t in roots {
            if let Some(h) = hit_at_root(line, t, &intersect) {
                out.push(self.event(h, None));
            }
        }
    }

    fn events_local(&self, ray: &Ray, ctx: &mut QueryCtx, out: &mut Vec<Event>) -> bool {
        let line = Ray::with_interval(ray.origin, ray.direction, f32::NEG_INFINITY, f32::INFINITY);
        match &self.shape {
            Shape::Sphere(s) => {
                if let Some((t0, t1)) = s.roots(&line) {
                    self.push_roots(&line, [t0, t1], |r| s.intersect(r), out);
                }
                false
            }
            Shape::Ellipsoid(e) => {
                if let Some((t0, t1)) = e.roots(&line) {
                    self.push_roots(&line, [t0 as f32, t1 as f32], |r| e.intersect(r), out);
                }
                false
            }
            Shape::Quadric(q) => {
                if let Some((t0, t1)) = q.quadric.roots(&line) {
                    self.push_roots(
                        &line,
                        [t0 as f32, t1 as f32],
                        |r| q.quadric.intersect(r),
                        out,
                    );
                }
                quadric_inside_at_start(&q.quadric, &line)
            }
            Shape::Box(b) => {
                if let Some((h0, h1)) = box_hits(b, &line) {
                    out.push(self.event(h0, None));
                    out.push(self.event(h1, None));
                }
                false
            }
            Shape::Plane(p) => match p.intersect(&line) {
                Some(h) => {
                    let inside = !h.front_face;
                    out.push(self.event(h, None));
                    inside
                }
                None => (line.origin - p.point()).dot(p.normal()) < 0.0,
            },
            Shape::Triangle(v) => {
                if let Some((h, b)) = tri_hit(v, &line) {
                    out.push(self.event(h, Some(b)));
                }
                false
            }
            Shape::Polygon(p) => {
                if let Some(h) = p.intersect(&line) {
                    out.push(self.event(h, None));
                }
                false
            }
            Shape::Mesh(m) => {
                let mut hits = Vec::new();
                m.all_hits(&line, &mut ctx.stats, &mut hits);
                out.extend(mesh_events(hits, |h, b, prim, enter| {
                    let mut e = Event {
                        enter,
                        ..self.event(h, Some(b))
                    };
                    e.hit.shading = m.shading_normal(prim as usize, b, h.normal);
                    e
                }));
                false
            }
            Shape::Csg(op, a, b) => {
                let mut ea = Vec::new();
                let mut eb = Vec::new();
                let ia = a.events(&line, ctx, &mut ea);
                let ib = b.events(&line, ctx, &mut eb);
                combine(*op, &ea, ia, &eb, ib, out)
            }
        }
    }
}

/// Combines two sorted crossing lists with a boolean operation; appends the result's
/// crossings to `out` and returns whether the result starts inside.
pub fn combine(
    op: CsgOp,
    a: &[Event],
    a_inside: bool,
    b: &[Event],
    b_inside: bool,
    out: &mut Vec<Event>,
) -> bool {
    let mut ca = i32::from(a_inside);
    let mut cb = i32::from(b_inside);
    let start = op.apply(a_inside, b_inside);
    let mut state = start;
    let (mut i, mut j) = (0usize, 0usize);
    while i < a.len() || j < b.len() {
        let take_a = j >= b.len() || (i < a.len() && a[i].t <= b[j].t);
        let (e, from_b) = if take_a {
            i += 1;
            (a[i - 1], false)
        } else {
            j += 1;
            (b[j - 1], true)
        };
        let c = if from_b { &mut cb } else { &mut ca };
        *c += if e.enter { 1 } else { -1 };
        let now = op.apply(ca > 0, cb > 0);
        if now != state {
            state = now;
            let mut hit = e.hit;
            if from_b && op == CsgOp::Difference {
                hit.hit.normal = -hit.hit.normal;
                hit.hit.front_face = !hit.hit.front_face;
            }
            out.push(Event {
                t: e.t,
                enter: now,
                hit,
            });
        }
    }
    start
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(shape: Shape) -> Node {
        Node::new(shape, 0, None)
    }

    #[test]
    fn sphere_difference_carves_a_hole() {
        let a = node(Shape::Sphere(Sphere::new(Vec3::ZERO, 1.0).unwrap()));
        let b = node(Shape::Sphere(Sphere::new(Vec3::Z, 0.5).unwrap()));
        let csg = node(Shape::Csg(CsgOp::Difference, Box::new(a), Box::new(b)));
        let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let h = csg.closest(&ray, &mut QueryCtx::default()).unwrap();
        // Hits the inside of the small sphere at z = 0.5, normal pointing out of the result (+z).
        assert!((h.hit.t - 4.5).abs() < 1e-5, "{h:?}");
        assert!((h.hit.normal - Vec3::Z).length() < 1e-5);
        assert!(h.hit.front_face);
    }

    #[test]
    fn forced_intervals_give_identical_hits() {
        for shape in [
            Shape::Sphere(Sphere::new(Vec3::new(0.1, 0.2, 0.0), 1.0).unwrap()),
            Shape::Box(Aabb::new(Vec3::splat(-1.0), Vec3::ONE)),
            Shape::Ellipsoid(Ellipsoid::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 0.5)).unwrap()),
        ] {
            let n = node(shape);
            for o in [Vec3::new(0.3, 0.1, 5.0), Vec3::new(0.0, 0.0, 0.0)] {
                let ray = Ray::new(o, Vec3::new(0.01, -0.02, -1.0));
                let a = n.closest(&ray, &mut QueryCtx::default());
                let mut ctx = QueryCtx {
                    force_intervals: true,
                    ..QueryCtx::default()
                };
                let b = n.closest(&ray, &mut ctx);
                assert_eq!(a, b);
            }
        }
    }
}
