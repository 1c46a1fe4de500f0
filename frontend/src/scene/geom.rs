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

mod csg;
mod mesh;

pub use csg::combine;
pub use halfray_core::quadric::ClippedQuadric;

use crate::accel::MeshAccel;
use crate::scene::xform::bounds_to_world;
use glam::Vec3;
use halfray_core::aabb::SlabRay;
use halfray_core::float::gamma;
use halfray_core::plane::Plane;
use halfray_core::quadric::Ellipsoid;
use halfray_core::query::TraversalStats;
use halfray_core::shape::Shape;
use halfray_core::sphere::Sphere;
use halfray_core::transform::Transform;
use halfray_core::triangle::Watertight;
use halfray_core::{Aabb, Hit, Ray};
use std::sync::{Arc, OnceLock};

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

/// A mesh primitive (shared by all its instances).
pub struct MeshShape {
    /// Name in the scene file.
    pub name: String,
    /// Triangles and BVH.
    pub accel: MeshAccel,
    /// Unit vertex normals (area-weighted) for smooth shading, one per position.
    pub normals: Option<Vec<Vec3>>,
    /// [`MeshShape::boundary_edges`], set by its first call (only a CSG operand needs it);
    /// empty until then.
    pub closedness: OnceLock<usize>,
}

impl MeshShape {
    /// The mesh `name` over `accel`, with smooth-shading `normals` if any; its closedness is
    /// computed when first asked for.
    pub fn new(name: &str, accel: MeshAccel, normals: Option<Vec<Vec3>>) -> Self {
        Self {
            name: name.to_string(),
            accel,
            normals,
            closedness: OnceLock::new(),
        }
    }

    /// Boundary (unpaired) directed edges plus directed edges used more than once
    /// ([`boundary_edge_count`] of the triangles); 0 for a closed, consistently
    /// oriented mesh. Counted on the first call, kept for the others.
    pub fn boundary_edges(&self) -> usize {
        *self
            .closedness
            .get_or_init(|| boundary_edge_count(&self.accel.mesh.triangles))
    }
}

/// Number of directed edges without an opposite partner, plus directed edges used more than
/// once. 0 means every edge is shared by exactly two consistently oriented triangles: the mesh
/// bounds a solid.
pub fn boundary_edge_count(triangles: &[[u32; 3]]) -> usize {
    let mut directed: std::collections::HashMap<(u32, u32), u32> =
        std::collections::HashMap::with_capacity(triangles.len() * 3);
    for t in triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    directed
        .iter()
        .map(|(&(a, b), &n)| {
            let back = directed.get(&(b, a)).copied().unwrap_or(0);
            usize::from(n != 1 || back != 1)
        })
        .sum()
}

impl std::fmt::Debug for MeshShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "MeshShape({:?}, {} triangles, boundary edges {:?})",
            self.name,
            self.accel.mesh.triangles.len(),
            self.closedness.get()
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

/// A scene object's geometry: a primitive (answered by its core [`Shape`]), a mesh instance or a
/// CSG combination.
#[derive(Clone, Debug)]
pub enum Geometry {
    /// Sphere.
    Sphere(Sphere),
    /// Ellipsoid.
    Ellipsoid(Ellipsoid),
    /// General quadric, optionally clipped to a box.
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

/// Fewest rays [`Node::closest_batch`] traces through a mesh as one batch; fewer go one by one
/// (the batch's gathering costs more than its packets save). Two packets of eight rays.
const MESH_BATCH_MIN_RAYS: usize = 16;

/// A shape with its material and optional transform.
#[derive(Clone, Debug)]
pub struct Node {
    /// The shape in object space.
    pub shape: Geometry,
    /// Material index (CSG operands without one inherit the parent's).
    pub material: u32,
    /// `true` when `material` is the enclosing CSG object's (a CSG operand that names none):
    /// [`Node::with_material`] replaces it along with the parent's.
    pub inherits_material: bool,
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

impl Geometry {
    /// `true` for shapes that bound a solid (usable as CSG operands).
    pub fn is_solid(&self) -> bool {
        match self {
            Self::Sphere(_) | Self::Ellipsoid(_) | Self::Box(_) | Self::Plane(_) => true,
            Self::Csg(..) => true,
            Self::Quadric(q) => q.clip.is_none(),
            Self::Mesh(m) => m.boundary_edges() == 0,
            Self::Triangle(_) | Self::Polygon(_) => false,
        }
    }

    /// The core [`Shape`] of a primitive, which answers its queries; `None` for a mesh
    /// and for CSG.
    fn primitive(&self) -> Option<&dyn Shape> {
        Some(match self {
            Self::Sphere(s) => s,
            Self::Ellipsoid(e) => e,
            Self::Quadric(q) => q,
            Self::Box(b) => b,
            Self::Plane(p) => p,
            Self::Triangle(v) => v,
            Self::Polygon(p) => p.as_ref(),
            Self::Mesh(_) | Self::Csg(..) => return None,
        })
    }

    /// The barycentrics `(b0, b1, b2)` of a single triangle's hit (the core's `uv` is
    /// `(b1, b2)`, `b0 = 1 − b1 − b2` as the core computes it); `None` for other shapes.
    fn barycentrics(&self, h: &Hit) -> Option<Vec3> {
        matches!(self, Self::Triangle(_)).then(|| Vec3::new(1.0 - h.uv.x - h.uv.y, h.uv.x, h.uv.y))
    }

    /// Object-space bounds (`None`: unbounded).
    pub fn bounds(&self) -> Option<Aabb> {
        match self {
            Self::Plane(_) => None,
            Self::Quadric(q) => q.clip,
            Self::Sphere(_)
            | Self::Ellipsoid(_)
            | Self::Box(_)
            | Self::Triangle(_)
            | Self::Polygon(_) => self.primitive().map(|s| s.bounds()),
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

/// Outward padding of a node's object-space box before it goes to world space, relative to the
/// box's magnitude (its largest `|coordinate|` plus its extent), unitless. The node's box test
/// runs on the world ray while the shape is hit by its rounded object-space copy
/// (`Transform::ray_to_object`: each component a rounded affine map), and a CSG node's box is
/// combined from its children's: twice the curved shapes' own pad
/// ([`halfray_core::shape::CURVED_BOUNDS_PAD`], `γ₄`), a margin over those roundings so that
/// the box test never refuses a ray the shape's own test would hit.
const NODE_BOUNDS_PAD: f32 = gamma(8);

/// `b` padded outward by [`NODE_BOUNDS_PAD`].
fn pad(b: Aabb) -> Aabb {
    let e = (b.min.abs().max(b.max.abs()) + b.extent()) * NODE_BOUNDS_PAD;
    Aabb::new(b.min - e, b.max + e)
}

impl Node {
    /// A node; bounds are computed from the shape and transform.
    pub fn new(shape: Geometry, material: u32, transform: Option<Transform>) -> Self {
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
            inherits_material: false,
            transform,
            bounds,
        }
    }

    /// This node with material `material`, and so every CSG operand at any depth that
    /// inherits it (through operands that inherit it too); an operand with its own material
    /// keeps it, and so do the operands that inherit from that one.
    pub fn with_material(&self, material: u32) -> Self {
        let shape = match &self.shape {
            Geometry::Csg(op, a, b) => {
                let pass = |n: &Node| {
                    Box::new(if n.inherits_material {
                        n.with_material(material)
                    } else {
                        n.clone()
                    })
                };
                Geometry::Csg(*op, pass(a), pass(b))
            }
            other => other.clone(),
        };
        Self {
            shape,
            material,
            inherits_material: self.inherits_material,
            transform: self.transform,
            bounds: self.bounds,
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

    /// A hit in this node's own space moved to its parent's.
    fn in_parent(&self, h: SurfaceHit) -> SurfaceHit {
        match &self.transform {
            Some(t) => to_world(t, h),
            None => h,
        }
    }

    /// Whether this node's closest hit comes from the crossings of its whole line (CSG, and
    /// every solid with `--force-all-effects`).
    fn via_intervals(&self, ctx: &QueryCtx) -> bool {
        matches!(self.shape, Geometry::Csg(..)) || (ctx.force_intervals && self.shape.is_solid())
    }

    /// The surface hit of a mesh hit `(hit, barycentrics, shading normal)` of this node.
    fn mesh_surface(&self, (h, b, shading): (Hit, Vec3, Option<Vec3>)) -> SurfaceHit {
        SurfaceHit {
            shading,
            ..self.surf(h, Some(b))
        }
    }

    /// [`Node::closest`] of each of `rays`, into `out` (as many entries; the others are left
    /// alone): the same answers. A mesh instance traces the rays its bounds may meet as one
    /// batch, in its own space ([`crate::accel::MeshAccel::closest_batch`]: coherent rays
    /// walked in packets); other shapes take them one by one.
    pub fn closest_batch(&self, rays: &[Ray], ctx: &mut QueryCtx, out: &mut [Option<SurfaceHit>]) {
        let mesh = match &self.shape {
            Geometry::Mesh(m) if rays.len() >= MESH_BATCH_MIN_RAYS && !self.via_intervals(ctx) => m,
            _ => {
                for (o, ray) in out.iter_mut().zip(rays) {
                    *o = self.closest(ray, ctx);
                }
                return;
            }
        };
        let (slots, local) = self.local_rays(rays, out, None);
        for (o, h) in slots
            .into_iter()
            .zip(mesh.closest_batch(&local, &mut ctx.stats))
        {
            *o = h.map(|h| self.in_parent(self.mesh_surface(h)));
        }
    }

    /// [`Node::occludes`] of each of `rays`, into `out` (as many entries; the others are left
    /// alone): the same answers. A mesh instance traces the rays its bounds may meet as one
    /// batch, in its own space ([`crate::accel::MeshAccel::any_batch`]: shadow rays towards
    /// one light walked in packets); other shapes take them one by one.
    pub fn occludes_batch(&self, rays: &[Ray], ctx: &mut QueryCtx, out: &mut [bool]) {
        let mesh = match &self.shape {
            Geometry::Mesh(m) if rays.len() >= MESH_BATCH_MIN_RAYS => m,
            _ => {
                for (o, ray) in out.iter_mut().zip(rays) {
                    *o = self.occludes(ray, ctx);
                }
                return;
            }
        };
        let (slots, local) = self.local_rays(rays, out, false);
        let stats = Some(&mut ctx.stats);
        for (o, h) in slots
            .into_iter()
            .zip(mesh.accel.any_batch(&Watertight, &local, stats))
        {
            *o = h;
        }
    }

    /// Of `rays` and their answer slots `out`, the slots of the rays this node's bounds may
    /// meet ([`Node::may_hit`]) and those rays in the node's own space; every slot of
    /// `out` paired with a ray is set to `none` first (the answer of a ray that misses the
    /// bounds).
    fn local_rays<'o, T: Copy>(
        &self,
        rays: &[Ray],
        out: &'o mut [T],
        none: T,
    ) -> (Vec<&'o mut T>, Vec<Ray>) {
        out.iter_mut()
            .zip(rays)
            .map(|(o, ray)| {
                *o = none;
                (o, ray)
            })
            .filter(|(_, ray)| self.may_hit(ray))
            .map(|(o, ray)| (o, self.to_local(ray)))
            .unzip()
    }

    /// `ray` (in the parent's space) in this node's own space.
    fn to_local(&self, ray: &Ray) -> Ray {
        match &self.transform {
            Some(t) => t.ray_to_object(ray),
            None => *ray,
        }
    }

    /// Whether anything is hit in `(t_min, t_max]` (shadow rays).
    pub fn occludes(&self, ray: &Ray, ctx: &mut QueryCtx) -> bool {
        if !self.may_hit(ray) {
            return false;
        }
        if let Geometry::Mesh(m) = &self.shape {
            return m.accel.any(&Watertight, &self.to_local(ray));
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
        if self.via_intervals(ctx) {
            let mut events = Vec::new();
            let line =
                Ray::with_interval(ray.origin, ray.direction, f32::NEG_INFINITY, f32::INFINITY);
            self.events_local(&line, ctx, &mut events);
            return events
                .into_iter()
                .find(|e| ray.contains(e.t))
                .map(|e| e.hit);
        }
        if let Some(s) = self.shape.primitive() {
            let h = s.closest_hit(ray)?;
            return Some(self.surf(h, self.shape.barycentrics(&h)));
        }
        match &self.shape {
            Geometry::Mesh(m) => Some(self.mesh_surface(m.closest(ray, &mut ctx.stats)?)),
            _ => None,
        }
    }
}
