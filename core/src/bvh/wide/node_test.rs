//! The node test of the wide traversal: the ray against all `W` child boxes of a node at once.

use super::node::WideNode;
use crate::aabb::SLAB_FAR_SCALE;
use crate::bvh::padded_ray::PaddedRay;
use crate::simd;
use crate::simd::level::{SimdLevel, Slab8};

impl PaddedRay {
    /// Entry distance of every child box over `[t_min, t_max]` and the mask of the boxes hit
    /// (bit `i` for slot `i`; the distances of the others mean nothing): the robust
    /// slab test of [`crate::aabb::Aabb::intersect_slab`] lane by lane, written branch-free so
    /// that it compiles to a few vector instructions per axis. The common path
    /// (`GENERAL = false`: every reciprocal finite or a zero's `±∞`, `t_min ≥ 0`) pads far
    /// distances by the plain factor [`SLAB_FAR_SCALE`] (a negative far distance means the box
    /// ends before `t_min ≥ 0` whatever the padding); `a > b ? a : b` absorbs a NaN slab
    /// value (`0·∞`) exactly like `f32::max`. An entry at `+∞` is a miss (nothing is accepted
    /// at `t = ∞`).
    // Lane loops are indexed: the form the compiler turns into vector instructions.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(in crate::bvh) fn hit_children<const W: usize, const GENERAL: bool, L: SimdLevel>(
        &self,
        level: L,
        node: &WideNode<W>,
        t_min: f32,
        t_max: f32,
    ) -> ([f32; W], u32) {
        if GENERAL {
            let dist = self.hit_children_general(node, t_min, t_max);
            return (dist, simd::mask_le(&dist, &[f32::MAX; W]));
        }
        // Capped at the largest finite `f32`, so that an entry at `+∞` is never hit.
        let t_max = t_max.min(f32::MAX);
        if let Some(hit) = self.hit8(level, node, t_min, t_max) {
            return hit;
        }
        let mut t_enter = [t_min; W];
        let mut t_exit = [t_max; W];
        for axis in 0..3 {
            let n = self.near[axis];
            let lo = &node.bounds[n][axis];
            let hi = &node.bounds[1 - n][axis];
            let (on, of, inv) = (
                self.origin_near[axis],
                self.origin_far[axis],
                self.inv_dir[axis],
            );
            for i in 0..W {
                let t_near = (lo[i] - on) * inv;
                let t_far = (hi[i] - of) * inv * SLAB_FAR_SCALE;
                t_enter[i] = if t_near > t_enter[i] {
                    t_near
                } else {
                    t_enter[i]
                };
                t_exit[i] = if t_far < t_exit[i] { t_far } else { t_exit[i] };
            }
        }
        (t_enter, simd::mask_le(&t_enter, &t_exit))
    }

    /// [`PaddedRay::hit_children`] by `level`'s eight-lane kernel, for `W = 8` when the level has one
    /// (same operations, same result).
    #[inline(always)]
    fn hit8<const W: usize, L: SimdLevel>(
        &self,
        level: L,
        node: &WideNode<W>,
        t_min: f32,
        t_max: f32,
    ) -> Option<([f32; W], u32)> {
        let lanes =
            |n: usize, axis: usize| <&[f32; 8]>::try_from(&node.bounds.get(n)?.get(axis)?[..]).ok();
        let [nx, ny, nz] = self.near;
        let lo = [lanes(nx, 0)?, lanes(ny, 1)?, lanes(nz, 2)?];
        let hi = [lanes(1 - nx, 0)?, lanes(1 - ny, 1)?, lanes(1 - nz, 2)?];
        let (dist, mask) = level.slab8(&Slab8 {
            lo,
            hi,
            origin_near: self.origin_near,
            origin_far: self.origin_far,
            inv_dir: self.inv_dir,
            far_scale: SLAB_FAR_SCALE,
            t_min,
            t_max,
        })?;
        Some((core::array::from_fn(|i| dist[i & 7]), mask))
    }

    /// [`PaddedRay::hit_children`] for rays with an overflowing reciprocal or `t_min < 0`:
    /// [`crate::aabb::Aabb::intersect_slab`] on each padded child box.
    #[cold]
    #[inline(never)]
    fn hit_children_general<const W: usize>(
        &self,
        node: &WideNode<W>,
        t_min: f32,
        t_max: f32,
    ) -> [f32; W] {
        let mut out = [f32::INFINITY; W];
        for (i, o) in out.iter_mut().enumerate() {
            let b = node.child_bounds(i);
            let padded = crate::aabb::Aabb::new(b.min - self.pad, b.max + self.pad);
            if let Some((t, _)) = padded.intersect_slab(&self.slab, t_min, t_max) {
                *o = t;
            }
        }
        out
    }
}
