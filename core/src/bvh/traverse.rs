//! Closest-hit and any-hit traversal on a fixed-size stack.

use super::node::BvhNode;
use super::padded_ray::PaddedRay;
use super::primitive::TriangleMesh;
use super::stats::TraversalStats;
use super::{Bvh, TRAVERSAL_STACK_SIZE, cull_bound, extent_of, improves, projection_pad};
use crate::aabb::{SLAB_FAR_SCALE, SlabRay};
use crate::ray::Ray;
use crate::triangle::{TriangleHit, TriangleIntersector};
use glam::Vec3;

impl PaddedRay {
    /// [`crate::aabb::Aabb::intersect_slab`] on the node's raw corners, with the near/far
    /// corner picked by index instead of by branch. The common path (`GENERAL = false`: no
    /// overflowing reciprocal, `t_min ≥ 0`) pads far distances by the plain factor
    /// [`SLAB_FAR_SCALE`]: a far distance is negative only when the exact one is (monotone
    /// rounding), and then the box ends before `t_min ≥ 0` whatever the padding, so the
    /// hit/miss answer and the entry distance are those of `intersect_slab`, except that an
    /// entry at `+∞` (a `−0` direction component outside a slab) counts as a hit here: one
    /// wasted visit, as no primitive accepts `t = ∞`, for one comparison less per node. `t_enter` and `t_exit` are never
    /// NaN (the ray was validated), so `a > b ? a : b` absorbs a NaN slab value exactly like
    /// `f32::max` does. Returns the entry distance on a hit.
    #[inline(always)]
    pub(super) fn hit_node<const GENERAL: bool>(
        &self,
        node: &BvhNode,
        t_min: f32,
        t_max: f32,
    ) -> Option<f32> {
        if GENERAL {
            return self.hit_node_general(node, t_min, t_max);
        }
        let mut t_enter = t_min;
        let mut t_exit = t_max;
        for axis in 0..3 {
            // `near` holds 0 or 1: `& 1` states it, so the lookups need no bounds check.
            let n = self.near[axis] & 1;
            let lo = node.bounds[n][axis];
            let hi = node.bounds[n ^ 1][axis];
            let t_near = (lo - self.origin_near[axis]) * self.inv_dir[axis];
            let t_far = (hi - self.origin_far[axis]) * self.inv_dir[axis] * SLAB_FAR_SCALE;
            t_enter = if t_near > t_enter { t_near } else { t_enter };
            t_exit = if t_far < t_exit { t_far } else { t_exit };
        }
        (t_enter <= t_exit).then_some(t_enter)
    }

    /// [`PaddedRay::hit_node`] for rays with a subnormal direction component whose reciprocal
    /// overflows, or with `t_min < 0` (a negative far distance must be padded towards `+∞`):
    /// [`crate::aabb::Aabb::intersect_slab`] itself.
    #[cold]
    #[inline(never)]
    fn hit_node_general(&self, node: &BvhNode, t_min: f32, t_max: f32) -> Option<f32> {
        let (lo, hi) = (Vec3::from(node.bounds[0]), Vec3::from(node.bounds[1]));
        let b = crate::aabb::Aabb::new(lo - self.pad, hi + self.pad);
        b.intersect_slab(&self.slab, t_min, t_max).map(|(t, _)| t)
    }
}

/// One stack entry: a node still to visit and the distance at which the ray enters its box.
#[derive(Clone, Copy)]
struct Entry {
    node: u32,
    t_enter: f32,
}

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    /// The closest hit of `ray`, as `(primitive index, intersect's payload)`.
    ///
    /// `intersect(prim, ray)` tests one primitive against `ray`, whose `t_max` is the current
    /// closest `t` (inclusive), and returns `(t, payload)` for a hit in `(t_min, t_max]`. Hits
    /// outside the interval are ignored. Of equal `t`, the smaller primitive index wins (see the
    /// module docs), so the result equals a brute-force loop with the same rule. `stats`, when
    /// given, is **added to**. An invalid ray returns `None` without testing any node.
    pub fn closest_hit<H>(
        &self,
        ray: &Ray,
        intersect: impl FnMut(u32, &Ray) -> Option<(f32, H)>,
        stats: Option<&mut TraversalStats>,
    ) -> Option<(u32, H)> {
        self.traverse::<H, false>(ray, intersect, stats)
    }

    /// Any hit of `ray` (occlusion / shadow rays): traversal stops at the first primitive for
    /// which `intersect` reports a `t` in `(t_min, t_max]`. Which one is found first depends on
    /// the tree; hit/miss does not.
    pub fn any_hit<H>(
        &self,
        ray: &Ray,
        intersect: impl FnMut(u32, &Ray) -> Option<(f32, H)>,
        stats: Option<&mut TraversalStats>,
    ) -> Option<(u32, H)> {
        self.traverse::<H, true>(ray, intersect, stats)
    }

    /// [`Bvh::closest_hit`] over a triangle mesh with the intersector `isect` (prepared once
    /// per ray). Returns the triangle index and its hit.
    #[inline]
    pub fn closest_hit_triangles<T: TriangleIntersector>(
        &self,
        mesh: &TriangleMesh<'_>,
        isect: &T,
        ray: &Ray,
        stats: Option<&mut TraversalStats>,
    ) -> Option<(u32, TriangleHit)> {
        let pre = isect.prepare(ray)?;
        self.closest_hit(
            ray,
            |prim, r| {
                let v = mesh.triangle(prim as usize)?;
                isect.intersect_prepared(&pre, r, &v).map(|h| (h.t, h))
            },
            stats,
        )
    }

    /// [`Bvh::any_hit`] over a triangle mesh with the intersector `isect`.
    #[inline]
    pub fn any_hit_triangles<T: TriangleIntersector>(
        &self,
        mesh: &TriangleMesh<'_>,
        isect: &T,
        ray: &Ray,
        stats: Option<&mut TraversalStats>,
    ) -> Option<(u32, TriangleHit)> {
        let pre = isect.prepare(ray)?;
        self.any_hit(
            ray,
            |prim, r| {
                let v = mesh.triangle(prim as usize)?;
                isect.intersect_prepared(&pre, r, &v).map(|h| (h.t, h))
            },
            stats,
        )
    }

    fn traverse<H, const ANY: bool>(
        &self,
        ray: &Ray,
        intersect: impl FnMut(u32, &Ray) -> Option<(f32, H)>,
        stats: Option<&mut TraversalStats>,
    ) -> Option<(u32, H)> {
        let slab = SlabRay::new(ray)?;
        // The general node test (division for subnormal direction components, outward
        // padding of negative far distances) is needed only for rare rays: decided once per
        // ray, so the common path's node test carries no branch for it.
        if slab.divide || ray.t_min < 0.0 {
            self.walk::<H, ANY, true>(ray, &slab, intersect, stats)
        } else {
            self.walk::<H, ANY, false>(ray, &slab, intersect, stats)
        }
    }

    fn walk<H, const ANY: bool, const GENERAL: bool>(
        &self,
        ray: &Ray,
        slab: &SlabRay,
        mut intersect: impl FnMut(u32, &Ray) -> Option<(f32, H)>,
        stats: Option<&mut TraversalStats>,
    ) -> Option<(u32, H)> {
        let nodes = self.nodes();
        let indices = self.indices();
        let root = nodes.first()?;
        let mut local = TraversalStats::default();
        let mut cur = *ray;
        let mut best: Option<(u32, H)> = None;
        let mut stack = [Entry {
            node: 0,
            t_enter: 0.0,
        }; TRAVERSAL_STACK_SIZE];
        let mut sp = 0usize;

        let nray = PaddedRay::new(slab, projection_pad(slab.origin, extent_of(&root.bounds())));
        local.nodes_visited += 1;
        let mut node = if nray
            .hit_node::<GENERAL>(root, ray.t_min, cull_bound(ray.t_max))
            .is_some()
        {
            Some(root)
        } else {
            None
        };
        'walk: while let Some(n) = node {
            let (start, count) = n.raw();
            if count != 0 {
                let first = start as usize;
                let prims = indices
                    .get(first..first.saturating_add(count as usize))
                    .unwrap_or(&[]);
                for &prim in prims {
                    local.primitives_tested += 1;
                    let Some((t, h)) = intersect(prim, &cur) else {
                        continue;
                    };
                    if improves(&cur, t, prim, best.as_ref().map(|b| b.0)) {
                        cur.t_max = t;
                        best = Some((prim, h));
                        if ANY {
                            break 'walk;
                        }
                    }
                }
            } else {
                let bound = cull_bound(cur.t_max);
                let left = nodes.get(start as usize);
                let right = nodes.get(start as usize + 1);
                let hit_l = left.and_then(|c| nray.hit_node::<GENERAL>(c, cur.t_min, bound));
                let hit_r = right.and_then(|c| nray.hit_node::<GENERAL>(c, cur.t_min, bound));
                local.nodes_visited += 2;
                match (hit_l, hit_r) {
                    (Some(tl), Some(tr)) => {
                        // Near child first; equal entries keep the first child first.
                        let (near, far, t_far) = if tr < tl {
                            (right, start, tl)
                        } else {
                            (left, start + 1, tr)
                        };
                        if let Some(slot) = stack.get_mut(sp) {
                            *slot = Entry {
                                node: far,
                                t_enter: t_far,
                            };
                            sp += 1;
                        }
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = left;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = right;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next entry still within the (shrunk) interval.
            node = None;
            let bound = cull_bound(cur.t_max);
            while sp > 0 {
                sp -= 1;
                let Some(&e) = stack.get(sp) else { break };
                if e.t_enter <= bound {
                    node = nodes.get(e.node as usize);
                    break;
                }
            }
        }
        if let Some(s) = stats {
            s.add(&local);
        }
        best
    }
}
