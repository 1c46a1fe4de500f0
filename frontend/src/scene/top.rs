//! The top level of a scene: a binned-SAH [`Bvh`] over the bounded objects' boxes, and the
//! unbounded ones (planes, unclipped quadrics, CSG over them) in a list, so that a ray costs
//! what the objects near it cost, not what the scene holds.
//!
//! Ties keep the list's rule: of objects hit at the same `t`, the one declared **last** wins
//! (the renderer's rule since its first version). The BVH numbers its primitives in reverse
//! declaration order, so its own tie rule (smaller primitive index) picks the later object,
//! and an equal `t` between the BVH and the list goes to the later object too.

use crate::scene::geom::{Geometry, Node, QueryCtx, SurfaceHit};
use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, node_capacity};
use halfray_core::mesh::PrimitiveSource;
use halfray_core::prelude::*;
use halfray_core::query::Query;
use halfray_core::{Aabb, Ray, Vec3};

/// Rays of a batch whose walks [`TopLevel::closest_batch`] always lists: after them, when
/// more than half of the rays so far met several objects, the rest take the single-ray query.
/// A count of rays, enough for a stable share and small beside a row of pixels.
const PROBED_RAYS: usize = 32;

/// Most bounded objects for which [`TopLevel::closest_batch`] lists each ray's objects and
/// batches them; over it (a crowd of instances, each reached by a few rays of a row) every
/// ray takes the single-ray query. A count of objects: on the example scenes, batches pay
/// with one large mesh and a few objects, and a scene of 10 000 instances, over the limit,
/// runs as fast as single rays (`docs/performance.md`, "The renderer's primary rays").
const BATCHED_OBJECTS_MAX: usize = 64;

/// How far [`TopLevel::bounded_in`] grows its box on every side, as a share of the box's
/// size (its largest coordinate's magnitude plus its longest side; unitless). A box test
/// (`Aabb::intersect_slab`, whose exit distance is padded by `2·γ₃`) admits a segment that
/// misses the box by at most a few `f32` ulps of those magnitudes (≤ 2⁻²⁰ of them); `2⁻¹⁶`
/// covers that sixteen times over, so no object a ray's own box test admits is left out.
pub const HULL_PAD: f32 = 1.0 / 65_536.0;

/// The scene's objects arranged for queries.
#[derive(Debug, Default)]
pub struct TopLevel {
    /// BVH over `bounded` (primitive `k` is `bounded[k]`).
    bvh: Option<Bvh<Vec<BvhNode>, Vec<u32>>>,
    /// Indices of objects with a finite box, in reverse declaration order.
    bounded: Vec<u32>,
    /// Their boxes, `boxes[k]` of object `bounded[k]` (the BVH's primitives).
    boxes: Vec<Aabb>,
    /// Indices of the other objects, in declaration order.
    unbounded: Vec<u32>,
}

/// The objects' boxes as the BVH builder and the box query read them.
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
            boxes,
            unbounded,
        }
    }

    /// The scene's one bounded object where it is a mesh, whose shadow rays
    /// [`TopLevel::occluded_batch`] batches: it takes them all without a walk of the top
    /// level. With several, the walk that lists a shadow ray's objects (a long ray, from a
    /// surface to a light) costs about what its single-ray query does (`instancing.toml`:
    /// ~800 instructions against ~950, `docs/performance.md`), so the batch takes the
    /// single-ray query ray by ray, and a caller gains nothing by gathering its rays.
    pub fn occlusion_batched(&self, objects: &[Node]) -> Option<u32> {
        let [one] = self.bounded[..] else {
            return None;
        };
        let mesh = matches!(objects.get(one as usize)?.shape, Geometry::Mesh(_));
        (mesh && self.bvh.is_some()).then_some(one)
    }

    /// The closest hit over `objects` (those this was built from) in `ray`'s interval, and
    /// the object's index.
    pub fn closest(
        &self,
        objects: &[Node],
        ray: &Ray,
        ctx: &mut QueryCtx,
    ) -> Option<(u32, SurfaceHit)> {
        let (listed, r) = self.closest_listed(objects, ray, ctx);
        self.closest_boxed(objects, (listed, r), ctx)
    }

    /// [`TopLevel::closest`] given `ray`'s [`TopLevel::closest_listed`], `(listed, r)`: the
    /// bounded objects' closest hit in `r`'s interval, or `listed` where it is closer or
    /// later.
    fn closest_boxed(
        &self,
        objects: &[Node],
        (listed, r): (Option<(u32, SurfaceHit)>, Ray),
        ctx: &mut QueryCtx,
    ) -> Option<(u32, SurfaceHit)> {
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
            (Some(a), Some(b)) => Some(closer_or_later(a, b)),
            (a, b) => a.or(b),
        }
    }

    /// [`TopLevel::closest`] of each of `rays`: the same answers, ray for ray. A ray whose
    /// interval meets the box of one bounded object only goes to that object, which takes all
    /// its rays at once ([`Node::closest_batch`]: a mesh walks them in packets); a ray that
    /// meets several takes the single-ray query, whose walk skips the objects behind its
    /// closest hit.
    pub fn closest_batch(
        &self,
        objects: &[Node],
        rays: &[Ray],
        ctx: &mut QueryCtx,
    ) -> Vec<Option<(u32, SurfaceHit)>> {
        let bvh = match &self.bvh {
            Some(bvh) if self.bounded.len() <= BATCHED_OBJECTS_MAX => bvh,
            _ => return rays.iter().map(|r| self.closest(objects, r, ctx)).collect(),
        };
        let (mut best, shrunk): (Vec<_>, Vec<Ray>) = rays
            .iter()
            .map(|ray| self.closest_listed(objects, ray, ctx))
            .unzip();
        // The ray's unbounded objects were tested above: `(best, r)` is its
        // `closest_listed`, which the single-ray query goes on from.
        let pairs = self.one_object_rays(bvh, &shrunk, |i| {
            let slot = &mut best[i as usize];
            *slot = self.closest_boxed(objects, (slot.take(), shrunk[i as usize]), ctx);
        });
        let (mut batch, mut hits) = (Vec::new(), Vec::new());
        for (object, group) in self.by_object(&pairs) {
            batch.clear();
            batch.extend(group.iter().map(|&(_, i)| shrunk[i as usize]));
            hits.clear();
            hits.resize(batch.len(), None);
            objects[object as usize].closest_batch(&batch, ctx, &mut hits);
            for (&(_, i), h) in group.iter().zip(hits.drain(..)) {
                if let Some(h) = h {
                    let slot = &mut best[i as usize];
                    *slot = Some(match slot.take() {
                        Some(a) => closer_or_later(a, (object, h)),
                        None => (object, h),
                    });
                }
            }
        }
        best
    }

    /// [`TopLevel::occluded`] of each of `rays`: the same answers, ray for ray. Where the
    /// scene's one bounded object is a mesh ([`TopLevel::occlusion_batched`]), the rays that
    /// no unbounded object blocks go to it at once ([`Node::occludes_batch`]: shadow rays
    /// walked in packets; a ray that misses its box is answered by the object's own box
    /// test, as the single-ray query's walk answers it); otherwise each ray takes the
    /// single-ray query.
    pub fn occluded_batch(&self, objects: &[Node], rays: &[Ray], ctx: &mut QueryCtx) -> Vec<bool> {
        let Some(object) = self.occlusion_batched(objects) else {
            return rays
                .iter()
                .map(|r| self.occluded(objects, r, ctx))
                .collect();
        };
        let mut blocked: Vec<bool> = rays
            .iter()
            .map(|r| self.occluded_listed(objects, r, ctx))
            .collect();
        let (open, batch): (Vec<usize>, Vec<Ray>) = (0..rays.len())
            .filter(|&i| !blocked[i])
            .map(|i| (i, rays[i]))
            .unzip();
        let mut flags = vec![false; batch.len()];
        objects[object as usize].occludes_batch(&batch, ctx, &mut flags);
        for (i, f) in open.into_iter().zip(flags) {
            blocked[i] = f;
        }
        blocked
    }

    /// Of `rays`, the pairs `(bounded object, ray index)` of the rays whose interval meets the
    /// box of one bounded object only, sorted by object;
    /// `alone(i)` is called for each ray that meets several (it takes the single-ray query),
    /// and for every ray after [`PROBED_RAYS`] once more than half of those before met
    /// several. A ray that meets none appears nowhere.
    fn one_object_rays(
        &self,
        bvh: &Bvh<Vec<BvhNode>, Vec<u32>>,
        rays: &[Ray],
        mut alone: impl FnMut(u32),
    ) -> Vec<(u32, u32)> {
        // One bounded object: every ray goes to it, no walk (one that misses its box is
        // answered there, by the object's own box test, as the single-ray query's walk
        // answers it).
        if self.bounded.len() == 1 {
            return (0u32..).zip(rays).map(|(i, _)| (0, i)).collect();
        }
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut several_seen = 0usize;
        for (i, r) in (0u32..).zip(rays) {
            // Where most rays meet several objects (a crowd of instances), the walk that lists
            // them is spent for nothing: the rest take the single-ray query at once.
            if i as usize >= PROBED_RAYS && 2 * several_seen > i as usize {
                alone(i);
                continue;
            }
            // The walk is an any-hit query whose leaf test records the first primitive and
            // reports a hit at the second, so a ray meeting several stops there; one that
            // does not has seen every leaf its interval meets (the interval never shrank), so
            // its one object is all the single-ray query could test.
            let mut first = None;
            let mut list = |k: u32, r: &Ray| -> Option<(f32, ())> {
                if first.is_none() {
                    first = Some(k);
                    return None;
                }
                // Any `t` of the interval stops the walk (nothing is accepted at `+∞`).
                Some((r.t_max.min(f32::MAX), ()))
            };
            let several = bvh.any_hit(r, &mut list, &mut Query::new()).is_some();
            several_seen += usize::from(several);
            match first {
                _ if several => alone(i),
                Some(k) => pairs.push((k, i)),
                None => {}
            }
        }
        pairs.sort_unstable();
        pairs
    }

    /// The runs of `pairs` (sorted `(bounded object, ray index)`, [`TopLevel::one_object_rays`])
    /// that share an object, each with the object's index in the scene.
    fn by_object<'p>(
        &'p self,
        pairs: &'p [(u32, u32)],
    ) -> impl Iterator<Item = (u32, &'p [(u32, u32)])> + 'p {
        pairs
            .chunk_by(|a, b| a.0 == b.0)
            .filter_map(|group| Some((*self.bounded.get(group[0].0 as usize)?, group)))
    }

    /// The closest hit among the unbounded objects (declaration order, a later one winning an
    /// equal `t`), and `ray` with its interval ending there.
    fn closest_listed(
        &self,
        objects: &[Node],
        ray: &Ray,
        ctx: &mut QueryCtx,
    ) -> (Option<(u32, SurfaceHit)>, Ray) {
        let mut listed: Option<(u32, SurfaceHit)> = None;
        let mut r = *ray;
        for &i in &self.unbounded {
            if let Some(h) = objects[i as usize].closest(&r, ctx) {
                r.t_max = h.hit.t;
                listed = Some((i, h));
            }
        }
        (listed, r)
    }

    /// The bounded objects that rays lying in `hull` may meet, for [`TopLevel::occluded_among`]:
    /// those whose box overlaps `hull` grown by [`HULL_PAD`], at most `max` of them; `None`
    /// when more do (then each ray's walk is the cheaper query). Shadow rays from one hit
    /// towards an area light lie in the box of their origins and targets: one box query for
    /// all of them instead of a walk of the top level each.
    pub fn bounded_in(&self, hull: &Aabb, max: usize) -> Option<Vec<u32>> {
        let Some(bvh) = &self.bvh else {
            return Some(Vec::new());
        };
        let (lo, hi) = (hull.min, hull.max);
        let size = lo.abs().max(hi.abs()).max_element() + (hi - lo).max_element();
        let pad = Vec3::splat(HULL_PAD * size);
        let grown = Aabb::new(lo - pad, hi + pad);
        let mut near = Vec::new();
        let mut over = false;
        bvh.query_box(&Boxes(&self.boxes), &grown, |k| {
            match self.bounded.get(k as usize) {
                Some(&i) if near.len() < max => near.push(i),
                Some(_) => over = true,
                None => {}
            }
            !over
        });
        (!over).then_some(near)
    }

    /// [`TopLevel::occluded`] of a ray lying in the box `near` came from
    /// ([`TopLevel::bounded_in`]), the same answer: the unbounded objects, then the bounded
    /// ones of `near`. A bounded object blocks a ray only where the ray's interval touches
    /// its box (`Node::occludes` tests that first, as the walk does), and the boxes that
    /// interval can touch overlap the grown hull.
    pub fn occluded_among(
        &self,
        objects: &[Node],
        near: &[u32],
        ray: &Ray,
        ctx: &mut QueryCtx,
    ) -> bool {
        self.occluded_listed(objects, ray, ctx)
            || near.iter().any(|&i| objects[i as usize].occludes(ray, ctx))
    }

    /// Whether any object blocks `ray` in its interval.
    pub fn occluded(&self, objects: &[Node], ray: &Ray, ctx: &mut QueryCtx) -> bool {
        self.occluded_listed(objects, ray, ctx) || self.occluded_boxed(objects, ray, ctx)
    }

    /// Whether an unbounded object blocks `ray` in its interval.
    fn occluded_listed(&self, objects: &[Node], ray: &Ray, ctx: &mut QueryCtx) -> bool {
        self.unbounded
            .iter()
            .any(|&i| objects[i as usize].occludes(ray, ctx))
    }

    /// Whether a bounded object blocks `ray` in its interval.
    fn occluded_boxed(&self, objects: &[Node], ray: &Ray, ctx: &mut QueryCtx) -> bool {
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

/// Of two objects' hits `(object index, hit)`, the closer one; of equal `t`, the object
/// declared later (the larger index).
fn closer_or_later(a: (u32, SurfaceHit), b: (u32, SurfaceHit)) -> (u32, SurfaceHit) {
    if b.1.hit.t < a.1.hit.t || (b.1.hit.t == a.1.hit.t && b.0 > a.0) {
        b
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::geom::Geometry;

    /// The two boxes `[0, 1]³` and `[0.5, 1.5]³` (box objects).
    fn two_boxes() -> TopLevel {
        let boxed = |lo: f32| {
            let b = Aabb::new(Vec3::splat(lo), Vec3::splat(lo + 1.0));
            Node {
                shape: Geometry::Box(b),
                material: 0,
                inherits_material: false,
                transform: None,
                bounds: Some(b),
            }
        };
        TopLevel::new(&[boxed(0.0), boxed(0.5)])
    }

    /// Rays along `+x` at height `y = z = 0.75` (through both of [`two_boxes`]) or `0.25`
    /// (through the first only), by `several`.
    fn rays(several: &[bool]) -> Vec<Ray> {
        several
            .iter()
            .map(|&s| {
                let h = if s { 0.75 } else { 0.25 };
                Ray::new(Vec3::new(-1.0, h, h), Vec3::X)
            })
            .collect()
    }

    /// [`TopLevel::one_object_rays`]'s contract: a ray through one box is paired with it, a
    /// ray through both goes `alone`, and after [`PROBED_RAYS`] rays every ray goes `alone` once
    /// more than half of those before met several, and only then.
    #[test]
    fn rays_after_the_probe_go_alone_once_most_met_several() {
        let top = two_boxes();
        let bvh = top.bvh.as_ref().expect("two bounded objects: a tree");
        let first_box = |k: u32| top.bounded[k as usize] == 0;
        let run = |several: &[bool]| {
            let mut alone = Vec::new();
            let pairs = top.one_object_rays(bvh, &rays(several), |i| alone.push(i));
            (pairs, alone)
        };
        // Three rays in four through both boxes (75 % > half) among the probed rays, then
        // rays through the first box only: from ray 32 on, every ray goes alone.
        let n = PROBED_RAYS as u32 + 8;
        let probed = |i: u32| i < PROBED_RAYS as u32;
        let mostly: Vec<bool> = (0..n).map(|i| probed(i) && i % 4 != 3).collect();
        let (pairs, alone) = run(&mostly);
        assert_eq!(
            alone,
            (0..n)
                .filter(|&i| !probed(i) || i % 4 != 3)
                .collect::<Vec<_>>()
        );
        assert!(pairs.iter().all(|&(k, _)| first_box(k)), "{pairs:?}");
        assert_eq!(
            pairs.iter().map(|&(_, i)| i).collect::<Vec<_>>(),
            (0..n)
                .filter(|&i| probed(i) && i % 4 == 3)
                .collect::<Vec<_>>()
        );

        // One ray in four through both (25 %): every ray is still walked, the others paired.
        let few: Vec<bool> = (0..n).map(|i| i % 4 == 3).collect();
        let (pairs, alone) = run(&few);
        assert_eq!(alone, (0..n).filter(|i| i % 4 == 3).collect::<Vec<_>>());
        assert!(pairs.iter().all(|&(k, _)| first_box(k)), "{pairs:?}");
        assert_eq!(
            pairs.iter().map(|&(_, i)| i).collect::<Vec<_>>(),
            (0..n).filter(|i| i % 4 != 3).collect::<Vec<_>>()
        );

        // Every other ray through both (exactly half, not more): still walked.
        let half: Vec<bool> = (0..n).map(|i| i % 2 == 1).collect();
        let (pairs, alone) = run(&half);
        assert_eq!(alone, (0..n).filter(|i| i % 2 == 1).collect::<Vec<_>>());
        assert_eq!(
            pairs.iter().map(|&(_, i)| i).collect::<Vec<_>>(),
            (0..n).filter(|i| i % 2 == 0).collect::<Vec<_>>()
        );
    }
}
