//! The top level of a scene: a binned-SAH [`Bvh`] over the bounded objects' boxes, and the
//! unbounded ones (planes, unclipped quadrics, CSG over them) in a list, so that a ray costs
//! what the objects near it cost, not what the scene holds.
//!
//! Ties keep the list's rule: of objects hit at the same `t`, the one declared **last** wins
//! (the renderer's rule since its first version). The BVH numbers its primitives in reverse
//! declaration order, so its own tie rule (smaller primitive index) picks the later object,
//! and an equal `t` between the BVH and the list goes to the later object too.

use crate::scene::geom::{Node, QueryCtx, SurfaceHit};
use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, node_capacity};
use halfray_core::mesh::PrimitiveSource;
use halfray_core::prelude::*;
use halfray_core::query::Query;
use halfray_core::{Aabb, Ray};

/// The scene's objects arranged for queries.
#[derive(Debug, Default)]
pub struct TopLevel {
    /// BVH over `bounded` (primitive `k` is `bounded[k]`).
    bvh: Option<Bvh<Vec<BvhNode>, Vec<u32>>>,
    /// Indices of objects with a finite box, in reverse declaration order.
    bounded: Vec<u32>,
    /// Indices of the other objects, in declaration order.
    unbounded: Vec<u32>,
}

/// The objects' boxes as the BVH builder reads them.
struct Boxes<'a>(&'a [Aabb]);

impl PrimitiveSource for Boxes<'_> {
    fn primitive_count(&self) -> usize {
        self.0.len()
    }

    fn primitive_bounds(&self, index: usize) -> Aabb {
        self.0.get(index).copied().unwrap_or(Aabb::EMPTY)
    }
}

impl TopLevel {
    /// Arranges `objects`: a BVH over those with finite bounds, a list for the rest.
    pub fn new(objects: &[Node]) -> Self {
        let mut bounded = Vec::new();
        let mut boxes = Vec::new();
        let mut unbounded = Vec::new();
        for (i, o) in objects.iter().enumerate().rev() {
            match o.bounds {
                Some(b) if b.min.is_finite() && b.max.is_finite() => {
                    bounded.push(i as u32);
                    boxes.push(b);
                }
                _ => unbounded.push(i as u32),
            }
        }
        unbounded.reverse();
        let n = boxes.len();
        let bvh = Bvh::build(
            &Boxes(&boxes),
            vec![BvhNode::EMPTY; node_capacity(n)],
            vec![0u32; index_capacity(n)],
            &BuildOptions {
                max_leaf_size: 2,
                // A degenerate box (an empty CSG intersection) is left out: nothing can hit it.
                exclude_non_finite: true,
                ..BuildOptions::default()
            },
        )
        .ok();
        Self {
            bvh,
            bounded,
            unbounded,
        }
    }

    /// The closest hit over `objects` (those this was built from) in `ray`'s interval, and
    /// the object's index.
    pub fn closest(
        &self,
        objects: &[Node],
        ray: &Ray,
        ctx: &mut QueryCtx,
    ) -> Option<(u32, SurfaceHit)> {
        let mut listed: Option<(u32, SurfaceHit)> = None;
        let mut r = *ray;
        for &i in &self.unbounded {
            if let Some(h) = objects[i as usize].closest(&r, ctx) {
                r.t_max = h.hit.t;
                listed = Some((i, h));
            }
        }
        let Some(bvh) = &self.bvh else {
            return listed;
        };
        let boxed = bvh
            .closest_hit(
                &r,
                &mut |k, r: &Ray| {
                    let i = *self.bounded.get(k as usize)?;
                    let h = objects[i as usize].closest(r, ctx)?;
                    Some((h.hit.t, (i, h)))
                },
                &mut Query::new(),
            )
            .map(|(_, x)| x);
        match (listed, boxed) {
            (Some(a), Some(b)) => Some(
                if b.1.hit.t < a.1.hit.t || (b.1.hit.t == a.1.hit.t && b.0 > a.0) {
                    b
                } else {
                    a
                },
            ),
            (a, b) => a.or(b),
        }
    }

    /// Whether any object blocks `ray` in its interval.
    pub fn occluded(&self, objects: &[Node], ray: &Ray, ctx: &mut QueryCtx) -> bool {
        if self
            .unbounded
            .iter()
            .any(|&i| objects[i as usize].occludes(ray, ctx))
        {
            return true;
        }
        let Some(bvh) = &self.bvh else {
            return false;
        };
        bvh.any_hit(
            ray,
            &mut |k, r: &Ray| {
                let i = *self.bounded.get(k as usize)?;
                // Any `t` of the interval reports "blocked" (nothing is accepted at `+∞`).
                let t = r.t_max.min(f32::MAX);
                objects[i as usize].occludes(r, ctx).then_some((t, ()))
            },
            &mut Query::new(),
        )
        .is_some()
    }
}
