//! The node test of the wide traversal: the ray against all `W` child boxes of a node at once.

use super::node::WideNode;
use crate::aabb::SLAB_FAR_SCALE;
use crate::bvh::padded_ray::PaddedRay;
use crate::simd;
use crate::simd::level::{SimdLevel, Slab8};

/// One axis of the slab test for one box and one ray: the box's near and far planes `lo`,
/// `hi` against the padded origins `on`, `of` and the reciprocals `inv`, `inv_far`
/// ([`far_reciprocal`]), folded into the running entry and exit distances. `t_near = (lo −
/// on)·inv`, `t_far = (hi − of)·inv_far` (never fused), then `enter = t_near > enter ? t_near
/// : enter` and `exit = t_far < exit ? t_far : exit`: a NaN distance (`0·∞`) keeps the running
/// value, like `f32::max`/`min` and like `maxps`/`minps` in the SIMD kernels
/// ([`crate::simd::level::Slab8`]). Every lane loop of the wide walks (single ray, packet
/// interval, packet lanes) is this step; the compiler vectorises the loops around it.
#[inline(always)]
pub(super) fn slab_axis(
    (lo, hi): (f32, f32),
    (on, of): (f32, f32),
    (inv, inv_far): (f32, f32),
    (enter, exit): (f32, f32),
) -> (f32, f32) {
    fold_slab((lo - on) * inv, (hi - of) * inv_far, (enter, exit))
}

/// The fold of one axis's entry and exit distances into the running interval: the selects
/// of [`slab_axis`].
#[inline(always)]
pub(super) fn fold_slab(t_near: f32, t_far: f32, (enter, exit): (f32, f32)) -> (f32, f32) {
    (
        if t_near > enter { t_near } else { enter },
        if t_far < exit { t_far } else { exit },
    )
}

/// The reciprocal of the far distances: `inv · SLAB_FAR_SCALE`, rounded once. Finite for every
/// finite `inv`: the largest finite reciprocal of an `f32` (of the smallest subnormal with
/// one, `≈ 2.9e-39`) is `≈ 3.4028221e38`, whose fold rounds below `f32::MAX` (tested); an
/// infinite `inv` (a zero component) stays infinite.
#[inline(always)]
pub(super) fn far_reciprocal(inv: f32) -> f32 {
    inv * SLAB_FAR_SCALE
}

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
    ///
    /// The factor is folded into the reciprocal, once per ray ([`far_reciprocal`]): a far
    /// distance is `(hi − o_far)·fl(inv·SLAB_FAR_SCALE)`, one product per box fewer on the
    /// node test's critical path than `((hi − o_far)·inv)·SLAB_FAR_SCALE`, with the same
    /// roundings (subtraction, reciprocal, two products), which the bound of
    /// [`SLAB_FAR_SCALE`] counts.
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
            let inv_far = far_reciprocal(inv);
            for i in 0..W {
                (t_enter[i], t_exit[i]) = slab_axis(
                    (lo[i], hi[i]),
                    (on, of),
                    (inv, inv_far),
                    (t_enter[i], t_exit[i]),
                );
            }
        }
        (t_enter, simd::mask_le(&t_enter, &t_exit))
    }

    /// Whether the ray hits box `b` over `[t_min, t_max]`: the common path of
    /// [`PaddedRay::hit_children`] (`GENERAL = false`) on one box, the same operations in the
    /// same order ([`slab_axis`]). Each bound enters its distance monotonically (a near bound
    /// lower along the ray gives a lower or equal entry, a far bound further gives a higher
    /// or equal exit, `±∞` and NaN included: a NaN distance keeps the running value), so a box
    /// containing every child box of a node is hit whenever one of them is: a miss here is a
    /// miss of every child (tested).
    #[inline(always)]
    pub(in crate::bvh) fn hits_box(&self, b: &crate::aabb::Aabb, t_min: f32, t_max: f32) -> bool {
        use glam::Vec3A;
        let inv = Vec3A::from_array(self.inv_dir);
        // The near corner per axis as `near` picks it: `inv` has the direction's sign (`±0`
        // gives `±∞`), so `inv < 0` is `near == 1`. Selected by mask, not by index (no
        // round trip through memory).
        let negative = inv.cmplt(Vec3A::ZERO);
        let (min, max) = (Vec3A::from(b.min), Vec3A::from(b.max));
        let lo = Vec3A::select(negative, max, min);
        let hi = Vec3A::select(negative, min, max);
        let on = Vec3A::from_array(self.origin_near);
        let of = Vec3A::from_array(self.origin_far);
        let inv_far = Vec3A::from_array(self.inv_dir.map(far_reciprocal));
        // The distances of `slab_axis`, then its folds axis by axis.
        let t_near = ((lo - on) * inv).to_array();
        let t_far = ((hi - of) * inv_far).to_array();
        let (mut enter, mut exit) = (t_min, t_max.min(f32::MAX));
        for axis in 0..3 {
            (enter, exit) = fold_slab(t_near[axis], t_far[axis], (enter, exit));
        }
        enter <= exit
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
            inv_far: self.inv_dir.map(far_reciprocal),
            t_min,
            t_max,
        })?;
        Some((core::array::from_fn(|i| dist[i & 7]), mask))
    }

    /// [`PaddedRay::hit_children`] for rays with an extreme reciprocal or `t_min < 0`:
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aabb::{Aabb, SlabRay};
    use crate::bvh::wide::node::ChildRef;
    use crate::ray::Ray;
    use crate::simd::level::Portable;
    use crate::test_util::lcg;
    use glam::{DVec3, Vec3};

    /// The root-box early-out of the closest-hit walk ([`PaddedRay::hits_box`] on the union of
    /// a node's child boxes) against the node test itself ([`PaddedRay::hit_children`], the
    /// path without it, at every level): whenever a child is hit, the union is. Rays with zero
    /// direction components (infinite reciprocals), origins on the boxes' planes (NaN slab
    /// distances), boxes touching the ray, empty slots, padding, and intervals from beyond to
    /// before the boxes; both outcomes must occur often.
    #[test]
    fn a_box_around_the_children_is_hit_when_a_child_is() {
        let mut s = 71u64;
        let (mut hit, mut missed) = (0, 0);
        for i in 0..20_000 {
            let grid = |s: &mut u64| ((lcg(s) * 8.0).floor() - 4.0) * 0.5;
            let v = |s: &mut u64| Vec3::new(grid(s), grid(s), grid(s));
            let origin = v(&mut s) * 1.5;
            let mut dir = Vec3::new(lcg(&mut s) - 0.5, lcg(&mut s) - 0.5, lcg(&mut s) - 0.5);
            for a in 0..3 {
                if lcg(&mut s) < 0.3 {
                    dir[a] = if lcg(&mut s) < 0.5 { 0.0 } else { -0.0 };
                }
            }
            if dir == Vec3::ZERO {
                dir.x = 1.0;
            }
            let t_min = if i % 3 == 0 { lcg(&mut s) * 4.0 } else { 0.0 };
            let t_max = if i % 2 == 0 {
                f32::INFINITY
            } else {
                t_min + lcg(&mut s) * 6.0
            };
            let ray = Ray {
                origin,
                direction: dir,
                t_min,
                t_max,
            };
            let Some(slab) = SlabRay::new(&ray) else {
                continue;
            };
            if slab.divide {
                continue;
            }
            let mut node = WideNode::<8>::EMPTY;
            let mut union = Aabb::EMPTY;
            for k in 0..8 {
                if lcg(&mut s) < 0.25 {
                    continue;
                }
                let (a, b) = (v(&mut s), v(&mut s));
                let b = Aabb::new(a.min(b), a.max(b));
                node.set_child(k, &b, k as u32);
                union = union.union(node.child_bounds(k));
            }
            let pad = if i % 4 == 0 { 0.0 } else { 1e-3 };
            let wray = PaddedRay::new(&slab, pad);
            let (_, mask) = wray.hit_children::<8, false, _>(Portable, &node, t_min, t_max);
            let outer = wray.hits_box(&union, t_min, t_max);
            assert!(mask == 0 || outer, "{ray:?} {node:?}");
            #[cfg(target_arch = "x86_64")]
            if let Some(level) = crate::test_util::avx2_or_skip(
                "bvh::wide::node_test::tests::a_box_around_the_children_is_hit_when_a_child_is",
            ) {
                let (_, m8) = wray.hit_children::<8, false, _>(level, &node, t_min, t_max);
                assert_eq!(m8, mask, "{ray:?} {node:?}");
            }
            if outer {
                hit += 1;
            } else {
                missed += 1;
            }
        }
        assert!(hit > 2000 && missed > 2000, "{hit} hit, {missed} missed");
    }

    /// Boxes that the exact ray only touches: flat in one axis (`lo = hi = c`), the other two
    /// axes bracketing, one `f32` step each way, the exact point (`f64`) where the ray crosses
    /// `c` — including rays with the direction component of the largest finite reciprocal.
    /// The oracle is the
    /// exact crossing, not the node test: every such box must be hit, at every SIMD level,
    /// with no padding (`pad = 0`), and every level must give the same distances and mask.
    #[test]
    fn node_test_never_culls_a_box_the_exact_ray_touches() {
        let mut s = 5u64;
        // The smallest direction component with a finite reciprocal: the largest reciprocal,
        // whose fold must stay finite (then every fold does: both roundings are monotone).
        let tiny = (0..16)
            .map(|k| f32::from_bits((1.0 / f32::MAX).to_bits() - 8 + k))
            .find(|&d| (1.0 / d).is_finite())
            .expect("a finite reciprocal near 1/f32::MAX");
        assert!(!(1.0 / f32::from_bits(tiny.to_bits() - 1)).is_finite());
        assert!(far_reciprocal(1.0 / tiny).is_finite());
        assert!(far_reciprocal(-1.0 / tiny).is_finite());
        let (mut rays, mut extreme) = (0, 0);
        while rays < 4000 {
            let v = |s: &mut u64| Vec3::new(lcg(s) - 0.5, lcg(s) - 0.5, lcg(s) - 0.5);
            let origin = v(&mut s) * 40.0;
            let mut dir = v(&mut s);
            if lcg(&mut s) < 0.2 {
                dir[(lcg(&mut s) * 3.0) as usize % 3] =
                    if lcg(&mut s) < 0.5 { tiny } else { -tiny };
            }
            let ray = Ray::new(origin, dir);
            let Some(slab) = SlabRay::new(&ray) else {
                continue;
            };
            if slab.divide {
                continue;
            }
            rays += 1;
            extreme += usize::from(dir.abs().min_element() == tiny);
            let mut node = WideNode::<8>::EMPTY;
            for i in 0..8 {
                // The flat axis: one the ray moves along (not the tiny one).
                let axis = (i + rays) % 3;
                let axis = if dir[axis].abs() == tiny {
                    (axis + 1) % 3
                } else {
                    axis
                };
                let c = origin[axis] + (lcg(&mut s) - 0.2) * 30.0 * dir[axis].signum();
                let (o, d) = (origin.as_dvec3(), dir.as_dvec3());
                let t = (f64::from(c) - o[axis]) / d[axis];
                if !(t > 0.0) {
                    continue;
                }
                let p: DVec3 = o + d * t;
                let (mut lo, mut hi) = (Vec3::ZERO, Vec3::ZERO);
                for a in 0..3 {
                    let x = p[a] as f32;
                    (lo[a], hi[a]) = if a == axis {
                        (c, c)
                    } else {
                        (x.next_down(), x.next_up())
                    };
                }
                node.set_child(i, &Aabb::new(lo, hi), i as u32);
            }
            let used = node.child.iter().filter(|&&c| c != ChildRef::EMPTY).count();
            let wray = PaddedRay::new(&slab, 0.0);
            let (dist, mask) = wray.hit_children::<8, false, _>(Portable, &node, 0.0, f32::MAX);
            assert_eq!(mask.count_ones() as usize, used, "{ray:?} {node:?}");
            #[cfg(target_arch = "x86_64")]
            if let Some(level) = crate::test_util::avx2_or_skip(
                "bvh::wide::node_test::tests::node_test_never_culls_a_box_the_exact_ray_touches",
            ) {
                let (d8, m8) = wray.hit_children::<8, false, _>(level, &node, 0.0, f32::MAX);
                assert_eq!(m8, mask);
                for i in 0..8 {
                    if mask >> i & 1 == 1 {
                        assert_eq!(d8[i].to_bits(), dist[i].to_bits());
                    }
                }
            }
        }
        assert!(extreme > 200, "{extreme} rays with the largest reciprocal");
    }
}
