//! The binned surface-area heuristic: binning a node's primitives by the centres of their
//! boxes ([`best_sah_split`]) and partitioning them by the chosen split ([`partition`]).

use super::scratch::{Corner, Refs, centre, corner, extend, point};
use super::{BIN_COUNT, TRAVERSAL_COST};
use crate::aabb::Aabb;
use glam::Vec3;

/// Sets of bins filled alternately by the binning loop ([`best_sah_split`]): two on x86-64,
/// one elsewhere (a microcontroller's stack is small and its loads do not overlap anyway).
pub(super) const BIN_SETS: usize = if cfg!(target_arch = "x86_64") { 2 } else { 1 };
const _: () = assert!(BIN_COUNT.is_power_of_two() && BIN_SETS.is_power_of_two());

/// Nodes of at least this many primitives are binned into [`BIN_SETS`] alternate sets of
/// bins; smaller ones into one.
const ALTERNATE_SETS_FROM: usize = 64;

/// Bins of a node of `n` primitives: `4 + n/8`, at most [`BIN_COUNT`] (all of them from 96
/// primitives on). Clearing, merging and sweeping the bins cost per bin and node, as much
/// as binning the primitives of a node of tens; fewer candidate planes there change the tree's
/// SAH cost by about 0.1 % (dragon, beams; Embree's `4 + n/20` saves a little more for
/// 0.5–1 %).
#[inline]
const fn bin_count(n: usize) -> usize {
    let k = 4 + n / 8;
    if k > BIN_COUNT { BIN_COUNT } else { k }
}

/// The bins of one node, kept by the split loop across nodes (cleared per node as far as used).
pub(super) type BinSets = [[[Bin; BIN_COUNT]; 3]; BIN_SETS];

/// Maps a centre to its bin along each axis at once. Shared by binning and partitioning so
/// both agree bit for bit. Per axis: `(c − lo)·scale` clamped to `[0, last]` in `f32` (NaN
/// gives 0; the upper clamp keeps the centroid box's upper bound in the last bin), then
/// truncated, which then needs no saturation. An axis without extent has `scale = last = 0`:
/// everything goes to bin 0 there.
#[derive(Clone, Copy)]
struct Binner {
    lo: Corner,
    scale: Corner,
    last: Corner,
    /// Axes with a non-zero centroid extent.
    active: [bool; 3],
}

impl Binner {
    /// `count` bins (`2..=BIN_COUNT`) over the centroid box `centroids`; `None` when no axis
    /// has extent (nothing to bin).
    fn new(centroids: &Aabb, count: usize) -> Option<Self> {
        let extent = centroids.max - centroids.min;
        let active = [extent.x > 0.0, extent.y > 0.0, extent.z > 0.0];
        let per_axis = |on: bool, v: f32| if on { v } else { 0.0 };
        let scale = Vec3::new(
            per_axis(active[0], count as f32 / extent.x),
            per_axis(active[1], count as f32 / extent.y),
            per_axis(active[2], count as f32 / extent.z),
        );
        let last = (count - 1) as f32;
        let last = Vec3::new(
            per_axis(active[0], last),
            per_axis(active[1], last),
            per_axis(active[2], last),
        );
        active.contains(&true).then(|| Self {
            lo: corner(centroids.min),
            scale: corner(scale),
            last: corner(last),
            active,
        })
    }

    /// The bin of centre `c` along each axis.
    #[inline(always)]
    fn bins(&self, c: Corner) -> [usize; 3] {
        let x = (c - self.lo) * self.scale;
        #[cfg(target_arch = "x86_64")]
        return crate::simd::truncate3(x.max(Corner::ZERO).min(self.last));
        #[cfg(not(target_arch = "x86_64"))]
        return core::array::from_fn(|a| {
            let x = if x[a] > 0.0 { x[a] } else { 0.0 };
            let x = if x < self.last[a] { x } else { self.last[a] };
            x as u32 as usize
        });
    }
}

#[derive(Clone, Copy)]
pub(super) struct Bin {
    lo: Corner,
    hi: Corner,
    count: u32,
}

pub(super) const EMPTY_BIN: Bin = Bin {
    lo: Corner::INFINITY,
    hi: Corner::NEG_INFINITY,
    count: 0,
};

/// A bin's value before its first use: all bits zero (so that a fresh
/// [`super::BuildWorkspace`] is zeroed memory, not a copy of a constant); every bin in use is
/// set to [`EMPTY_BIN`] first.
pub(super) const UNUSED_BIN: Bin = Bin {
    lo: Corner::ZERO,
    hi: Corner::ZERO,
    count: 0,
};

impl Bin {
    /// Adds a box (`lo`, `hi`) holding `count` primitives. The builder only sees finite
    /// coordinates (validated), so `min`/`max` are one vector instruction each.
    #[inline(always)]
    fn add(&mut self, lo: Corner, hi: Corner, count: u32) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
        self.count += count;
    }

    /// Surface area of the box, 0 when empty.
    #[inline(always)]
    fn area(&self) -> f32 {
        if self.count == 0 {
            return 0.0;
        }
        let e = self.hi - self.lo;
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    fn aabb(&self) -> Aabb {
        Aabb::new(point(self.lo), point(self.hi))
    }
}

/// The chosen SAH split: `bin(centroid[axis]) < split` goes left.
#[derive(Clone, Copy)]
pub(super) struct Split {
    axis: usize,
    binner: Binner,
    split: usize,
    /// The SAH numerator of the split (see [`best_sah_split`]).
    pub(super) cost: f32,
    /// Box of the left side.
    pub(super) left: Aabb,
    /// Box of the right side.
    pub(super) right: Aabb,
}

impl Split {
    /// Whether element `k` of `refs` goes left, and its centre.
    #[inline(always)]
    fn classify<R: Refs>(&self, refs: &R, k: usize) -> (bool, Corner) {
        let (lo, hi) = refs.get(k);
        let c = centre(lo, hi);
        let bin = self.binner.bins(c).get(self.axis).copied().unwrap_or(0);
        (bin < self.split, c)
    }
}

/// Box and centroid box of a run of primitives.
pub(super) fn range_bounds<R: Refs>(refs: &R, range: core::ops::Range<usize>) -> (Aabb, Aabb) {
    let (mut lo, mut hi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    let (mut clo, mut chi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    refs.for_each(range, |plo, phi| {
        lo = lo.min(plo);
        hi = hi.max(phi);
        extend(&mut clo, &mut chi, centre(plo, phi));
    });
    (
        Aabb::new(point(lo), point(hi)),
        Aabb::new(point(clo), point(chi)),
    )
}

/// Bins the primitives (`min(count, BIN_COUNT)` bins) along every axis with a non-zero
/// centroid extent and returns the
/// cheapest split with both sides non-empty. The cost is the SAH numerator (not divided by the
/// parent's area, so that zero-area parents need no special case):
/// `TRAVERSAL_COST·A + primitive_cost·(A_L·N_L + A_R·N_R)`.
pub(super) fn best_sah_split<R: Refs>(
    refs: &R,
    sets: &mut BinSets,
    range: core::ops::Range<usize>,
    centroids: &Aabb,
    parent_area: f32,
    primitive_cost: f32,
) -> Option<Split> {
    let bin_count = bin_count(range.len());
    // An axis without extent bins everything into bin 0 and is skipped below.
    let binner = Binner::new(centroids, bin_count)?;
    // Consecutive primitives of a large node go to alternate sets of bins, merged after the
    // loop, so that two primitives in one bin do not wait for each other's update; a small
    // node uses one set (clearing and merging a second would cost more than it saves). Only
    // the bins in use are cleared (most nodes are small).
    let set_count = if range.len() >= ALTERNATE_SETS_FROM {
        BIN_SETS
    } else {
        1
    };
    for axis_bins in sets.iter_mut().take(set_count).flatten() {
        for bin in axis_bins.iter_mut().take(bin_count) {
            *bin = EMPTY_BIN;
        }
    }
    let mut n = 0usize;
    let set_mask = set_count - 1;
    refs.for_each(range, |lo, hi| {
        let c = centre(lo, hi);
        let set = &mut sets[n & set_mask & (BIN_SETS - 1)];
        n += 1;
        for (axis_bins, b) in set.iter_mut().zip(binner.bins(c)) {
            // `b < bin_count ≤ BIN_COUNT`, a power of two: the mask changes nothing but
            // proves the index in range.
            axis_bins[b & (BIN_COUNT - 1)].add(lo, hi, 1);
        }
    });
    let (bins, rest) = sets.split_at_mut(1);
    let bins = &mut bins[0];
    for set in rest.iter().take(set_count - 1) {
        for (axis_bins, other) in bins.iter_mut().zip(set) {
            for (bin, o) in axis_bins.iter_mut().zip(other).take(bin_count) {
                bin.add(o.lo, o.hi, o.count);
            }
        }
    }
    let mut best: Option<Split> = None;
    for axis in 0..3 {
        if !binner.active[axis] {
            continue;
        }
        let bins = &bins[axis];
        // Right-to-left sweep: area·count of bins[k..].
        let mut right_cost = [0.0f32; BIN_COUNT];
        let mut acc = EMPTY_BIN;
        for k in (1..bin_count).rev() {
            acc.add(bins[k].lo, bins[k].hi, bins[k].count);
            right_cost[k] = acc.area() * acc.count as f32;
        }
        let mut left = EMPTY_BIN;
        let total: u32 = bins.iter().take(bin_count).map(|b| b.count).sum();
        for k in 1..bin_count {
            left.add(bins[k - 1].lo, bins[k - 1].hi, bins[k - 1].count);
            if left.count == 0 || left.count == total {
                continue;
            }
            let cost = TRAVERSAL_COST * parent_area
                + primitive_cost * (left.area() * left.count as f32 + right_cost[k]);
            // Strict `<`: ties keep the first (lowest axis, lowest bin) split, deterministic.
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    binner,
                    split: k,
                    cost,
                    left: left.aabb(),
                    right: Aabb::EMPTY,
                });
            }
        }
    }
    // The right box of the chosen split, from its bins (not kept per candidate: stack).
    if let Some(b) = best.as_mut() {
        let mut right = EMPTY_BIN;
        for bin in bins[b.axis].get(b.split..bin_count).unwrap_or(&[]) {
            right.add(bin.lo, bin.hi, bin.count);
        }
        b.right = right.aabb();
    }
    best
}

/// Partitions `range` of `refs` in place by the split (left side first; the order within a
/// side is not specified but deterministic); returns the left count and both centroid boxes.
/// Each primitive is classified once; only misplaced pairs are swapped.
pub(super) fn partition<R: Refs>(
    refs: &mut R,
    range: core::ops::Range<usize>,
    split: &Split,
) -> (u32, Aabb, Aabb) {
    let (mut llo, mut lhi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    let (mut rlo, mut rhi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    let (mut i, mut j) = (range.start, range.end);
    'outer: while i < j {
        // The first element from the left that belongs right…
        let right_c = loop {
            let (left, c) = split.classify(refs, i);
            if !left {
                break c;
            }
            extend(&mut llo, &mut lhi, c);
            i += 1;
            if i == j {
                break 'outer;
            }
        };
        // …and the first from the right that belongs left; `i` itself belongs right, so this
        // stops above it.
        let left_c = loop {
            j -= 1;
            if j == i {
                extend(&mut rlo, &mut rhi, right_c);
                break 'outer;
            }
            let (left, c) = split.classify(refs, j);
            if left {
                break c;
            }
            extend(&mut rlo, &mut rhi, c);
        };
        refs.swap(i, j);
        extend(&mut llo, &mut lhi, left_c);
        extend(&mut rlo, &mut rhi, right_c);
        i += 1;
    }
    (
        (i - range.start) as u32,
        Aabb::new(point(llo), point(lhi)),
        Aabb::new(point(rlo), point(rhi)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::scratch::{PrimRef, Scratch};

    #[test]
    fn partition_splits_by_bin_and_reports_both_centroid_boxes() {
        // 40 unit boxes with centres at x = 0..40 in a scrambled order; split at bin 5 of
        // 16 over [0, 39]: centres below 39·5/16 = 12.1875 go left.
        let mut refs_store = [PrimRef::EMPTY; 40];
        for (k, slot) in refs_store.iter_mut().enumerate() {
            let x = ((k * 17) % 40) as f32;
            let b = Aabb::new(Vec3::new(x - 0.5, 0.0, 0.0), Vec3::new(x + 0.5, 1.0, 1.0));
            *slot = PrimRef::new(&b, k as u32);
        }
        let centroids = Aabb::new(Vec3::ZERO, Vec3::new(39.0, 0.0, 0.0));
        let binner = Binner::new(&centroids, 16).unwrap();
        let split = Split {
            axis: 0,
            binner,
            split: 5,
            cost: 0.0,
            left: Aabb::EMPTY,
            right: Aabb::EMPTY,
        };
        let mut view = Scratch {
            refs: &mut refs_store,
            offset: 0,
        };
        let (left, lc, rc) = partition(&mut view, 0..40, &split);
        assert_eq!(left, 13, "centres 0..=12 go left");
        let xs: [f32; 40] = core::array::from_fn(|k| view.get(k).0.x + 0.5);
        assert!(xs[..13].iter().all(|&x| x <= 12.0), "{xs:?}");
        assert!(xs[13..].iter().all(|&x| x >= 13.0), "{xs:?}");
        let mut seen = [false; 40];
        for r in view.refs.iter() {
            seen[r.index() as usize] = true;
        }
        assert!(seen.iter().all(|&s| s), "a permutation");
        assert_eq!((lc.min.x, lc.max.x), (0.0, 12.0));
        assert_eq!((rc.min.x, rc.max.x), (13.0, 39.0));
    }
}
