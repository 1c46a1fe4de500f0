//! The binned surface-area heuristic: binning a node's primitives by the centres of their
//! boxes ([`best_sah_split`]) and partitioning them by the chosen split ([`partition`]).

use super::scratch::{Box2, Corner, Refs, RunVisitor, centre2, corner, extend, point};
use super::{BIN_COUNT, TRAVERSAL_COST};
use crate::aabb::Aabb;
use glam::{BVec4A, Vec3, Vec4};

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

/// One set of bins along the three axes: per axis and bin the lower and upper corner of the
/// bin's box and the bin's primitive count. Boxes and counts are kept apart so that a box is
/// 32 bytes on x86-64 (its address a shift of the bin index) and a count one `u32` increment.
#[derive(Clone, Copy)]
pub(super) struct BinSet {
    boxes: [[[Corner; 2]; BIN_COUNT]; 3],
    /// Counts below 2³¹ (at most [`super::MAX_PRIMITIVES`]): `i32` converts to `f32` in one
    /// instruction.
    counts: [[i32; BIN_COUNT]; 3],
}

/// The bins of one node, kept by the split loop across nodes (cleared per node as far as used).
pub(super) type BinSets = [BinSet; BIN_SETS];

/// A set of bins before its first use: all bits zero (so that a fresh
/// [`super::BuildWorkspace`] is zeroed memory, not a copy of a constant); every bin in use is
/// emptied first ([`BinSet::clear`]).
pub(super) const UNUSED_SET: BinSet = BinSet {
    boxes: [[[Corner::ZERO; 2]; BIN_COUNT]; 3],
    counts: [[0; BIN_COUNT]; 3],
};

impl BinSet {
    /// Empties the first `count` bins of every axis.
    #[inline(always)]
    fn clear(&mut self, count: usize) {
        for (boxes, counts) in self.boxes.iter_mut().zip(&mut self.counts) {
            for (b, n) in boxes.iter_mut().zip(counts.iter_mut()).take(count) {
                *b = [Corner::INFINITY, Corner::NEG_INFINITY];
                *n = 0;
            }
        }
    }

    /// Adds the box `lo, hi` to bin `bins[axis]` of each axis. The builder only sees finite
    /// coordinates (validated), so `min`/`max` are one vector instruction each.
    #[inline(always)]
    fn add(&mut self, bins: [usize; 3], lo: Corner, hi: Corner) {
        for ((boxes, counts), b) in self.boxes.iter_mut().zip(&mut self.counts).zip(bins) {
            // `b < BIN_COUNT`, a power of two: the mask changes nothing but proves the index
            // in range.
            let b = b & (BIN_COUNT - 1);
            let corners = &mut boxes[b];
            corners[0] = corners[0].min(lo);
            corners[1] = corners[1].max(hi);
            counts[b] += 1;
        }
    }

    /// Adds the first `count` bins of `other` into this set's.
    fn merge(&mut self, other: &Self, count: usize) {
        for axis in 0..3 {
            for k in 0..count.min(BIN_COUNT) {
                let [lo, hi] = other.boxes[axis][k];
                let corners = &mut self.boxes[axis][k];
                corners[0] = corners[0].min(lo);
                corners[1] = corners[1].max(hi);
                self.counts[axis][k] += other.counts[axis][k];
            }
        }
    }

    /// The union of bins `range` of `axis`.
    fn union(&self, axis: usize, range: core::ops::Range<usize>) -> Aabb {
        let (mut lo, mut hi) = (Corner::INFINITY, Corner::NEG_INFINITY);
        for [blo, bhi] in self
            .boxes
            .get(axis)
            .and_then(|b| b.get(range))
            .unwrap_or(&[])
        {
            lo = lo.min(*blo);
            hi = hi.max(*bhi);
        }
        Aabb::new(point(lo), point(hi))
    }
}

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

    /// The split "the bin along `axis` is below `split`" as lane limits for [`Self::goes_left`]:
    /// `split` in lane `axis`, NaN in the others (every comparison with NaN is false).
    fn limit(&self, axis: usize, split: usize) -> Corner {
        let mut limit = Corner::NAN;
        if let Some(lane) = limit.as_mut().get_mut(axis) {
            *lane = split as f32;
        }
        limit
    }

    /// Whether centre `c` goes left of the split that `limit` ([`Self::limit`]) stands for:
    /// exactly when [`Self::bins`] of `c` along the split's axis is below the split, computed
    /// without the bin index. With `x = (c − lo)·scale` (the same operations, so the same bits
    /// as in [`Self::bins`]), an integer split `1 ≤ s ≤ last` and `y = min(max(x, 0), last)`
    /// the clamped value truncated there: a NaN or negative `x` gives bin 0 < s and `x ≥ s` is
    /// false; otherwise `trunc(y) < s ⟺ y < s` (as `y ≥ 0`) `⟺ x < s` (as `s ≤ last`).
    #[inline(always)]
    fn goes_left(&self, c: Corner, limit: Corner) -> bool {
        !((c - self.lo) * self.scale).cmpge(limit).any()
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

/// Running sums over bins along the three axes at once: per axis the union of the bins'
/// boxes and their primitive count, the counts also as `f32` lanes x, y, z.
#[derive(Clone, Copy)]
struct Sums {
    boxes: [[Corner; 2]; 3],
    counts: [i32; 3],
    /// `counts` as `f32` (each converted from the exact sum).
    lanes: Vec4,
}

impl Sums {
    const EMPTY: Self = Self {
        boxes: [[Corner::INFINITY, Corner::NEG_INFINITY]; 3],
        counts: [0; 3],
        lanes: Vec4::ZERO,
    };

    /// Adds bin `k` of every axis.
    #[inline(always)]
    fn add(&mut self, bins: &BinSet, k: usize) {
        let k = k & (BIN_COUNT - 1);
        for (sum, axis_bins) in self.boxes.iter_mut().zip(&bins.boxes) {
            let [lo, hi] = axis_bins[k];
            sum[0] = sum[0].min(lo);
            sum[1] = sum[1].max(hi);
        }
        for (sum, axis_counts) in self.counts.iter_mut().zip(&bins.counts) {
            *sum += axis_counts[k];
        }
        let [n0, n1, n2] = self.counts;
        self.lanes = Vec4::new(n0 as f32, n1 as f32, n2 as f32, 0.0);
    }

    /// The axes (lanes x, y, z) with a non-zero count (an integer converts to `0.0` only
    /// from 0).
    #[inline(always)]
    fn non_empty(&self) -> BVec4A {
        self.lanes.cmpne(Vec4::ZERO)
    }

    /// Area·count of each axis's box (lanes x, y, z): the area `2·(eₓe_y + e_ye_z + e_zeₓ)`
    /// of the extents `e`, 0 for an empty box.
    #[inline(always)]
    fn cost(&self) -> Vec4 {
        let [e0, e1, e2] = self.boxes.map(|[lo, hi]| hi - lo);
        let ex = Vec4::new(e0.x, e1.x, e2.x, 0.0);
        let ey = Vec4::new(e0.y, e1.y, e2.y, 0.0);
        let ez = Vec4::new(e0.z, e1.z, e2.z, 0.0);
        let area = 2.0 * (ex * ey + ey * ez + ez * ex);
        Vec4::select(self.lanes.cmpeq(Vec4::ZERO), Vec4::ZERO, area) * self.lanes
    }
}

/// The chosen SAH split: `bin(centroid[axis]) < split` goes left.
#[derive(Clone, Copy)]
pub(super) struct Split {
    binner: Binner,
    /// [`Binner::limit`] of the split.
    limit: Corner,
    /// The SAH numerator of the split (see [`best_sah_split`]).
    pub(super) cost: f32,
    /// Box of the left side.
    pub(super) left: Aabb,
    /// Box of the right side.
    pub(super) right: Aabb,
}

impl Split {
    /// The split of `binner`'s bins along `axis` below bin `split`.
    fn new(binner: Binner, axis: usize, split: usize) -> Self {
        Self {
            binner,
            limit: binner.limit(axis, split),
            cost: 0.0,
            left: Aabb::EMPTY,
            right: Aabb::EMPTY,
        }
    }

    /// Whether the primitive with box `lo, hi` goes left, and its centre.
    #[inline(always)]
    fn classify(&self, (lo, hi): Box2) -> (bool, Corner) {
        let c = centre2(lo, hi);
        (self.binner.goes_left(c, self.limit), c)
    }
}

/// Box and centroid box (of the [`centre2`] points) of a run of primitives.
#[inline(always)]
pub(super) fn range_bounds<R: Refs + ?Sized>(
    refs: &R,
    range: core::ops::Range<usize>,
) -> (Aabb, Aabb) {
    let (mut lo, mut hi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    let (mut clo, mut chi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    refs.for_each(range, |plo, phi| {
        lo = lo.min(plo);
        hi = hi.max(phi);
        extend(&mut clo, &mut chi, centre2(plo, phi));
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
#[inline(always)]
pub(super) fn best_sah_split<R: Refs + ?Sized>(
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
    let [first, rest @ ..] = sets;
    let second = rest
        .first_mut()
        .filter(|_| range.len() >= ALTERNATE_SETS_FROM);
    first.clear(bin_count);
    match second {
        Some(second) => {
            second.clear(bin_count);
            refs.for_each_pair(
                range,
                #[inline(always)]
                |(alo, ahi), b| {
                    first.add(binner.bins(centre2(alo, ahi)), alo, ahi);
                    if let Some((blo, bhi)) = b {
                        second.add(binner.bins(centre2(blo, bhi)), blo, bhi);
                    }
                },
            );
            first.merge(second, bin_count);
        }
        None => refs.for_each(
            range,
            #[inline(always)]
            |lo, hi| first.add(binner.bins(centre2(lo, hi)), lo, hi),
        ),
    }
    let bins = &*first;
    // The SAH cost of every candidate plane `k` (below bin `k`) along the three axes at once
    // (lanes x, y, z): a right-to-left sweep keeps area·count of the bins `k..`, a left-to-right
    // one adds area·count of the bins `..k`. Every lane computes what a sweep of its axis
    // alone would, operation for operation.
    // (`k < bin_count ≤ BIN_COUNT`, a power of two: the masks below change no index but prove
    // it in range.)
    const K: usize = BIN_COUNT - 1;
    let mut right_cost = [Vec4::ZERO; BIN_COUNT];
    let mut right_non_empty = [BVec4A::FALSE; BIN_COUNT];
    let mut right = Sums::EMPTY;
    for k in (1..bin_count).rev() {
        right.add(bins, k);
        right_cost[k & K] = right.cost();
        right_non_empty[k & K] = right.non_empty();
    }
    let base = Vec4::splat(TRAVERSAL_COST * parent_area);
    let factor = Vec4::splat(primitive_cost);
    let [ax, ay, az] = binner.active;
    let active = BVec4A::new(ax, ay, az, false);
    let mut cost = [Vec4::ZERO; BIN_COUNT];
    // Bit `4k + axis`: plane `k` of `axis` is a candidate (both sides non-empty, on an axis
    // with extent).
    let mut candidates = 0u64;
    // Per lane, the smallest cost of the candidates (`+∞` for none). A NaN cost is passed
    // over: `min` returns the running value (on x86-64 its right operand whenever a comparison
    // is false, elsewhere the operand that is not NaN), which is never NaN.
    let mut least = Vec4::INFINITY;
    let mut left = Sums::EMPTY;
    for k in 1..bin_count {
        left.add(bins, k - 1);
        let c = base + factor * (left.cost() + right_cost[k & K]);
        cost[k & K] = c;
        let on = left.non_empty() & right_non_empty[k & K] & active;
        candidates |= u64::from(on.bitmask()) << (4 * (k & K));
        least = Vec4::select(on, c, Vec4::INFINITY).min(least);
    }
    let best = cheapest(&cost, candidates, least);
    best.map(|(axis, k, c)| Split {
        cost: c,
        left: bins.union(axis, 0..k),
        right: bins.union(axis, k..bin_count),
        ..Split::new(binner, axis, k)
    })
}

/// The split that a scan of the candidates (bit `4k + axis` of `candidates`) in axis-major
/// order, then by `k`, keeping the first and replacing it only by a strictly smaller
/// `cost[k][axis]`, ends with: `(axis, k, cost)`, `None` without a candidate. `least` holds
/// per lane the smallest cost of that axis's candidates whose cost is not NaN (`+∞` for none).
/// Without the scan: when the first candidate's cost is NaN nothing is smaller, so it stays;
/// otherwise the scan ends at the first candidate whose cost equals the smallest of all
/// (NaN costs are never smaller), which lies on the first axis whose `least` equals it.
#[inline(always)]
fn cheapest(cost: &[Vec4; BIN_COUNT], candidates: u64, least: Vec4) -> Option<(usize, usize, f32)> {
    const AXIS: u64 = 0x1111_1111_1111_1111;
    let on_axis = |axis: usize| candidates & (AXIS << axis);
    let at = |axis: usize, bits: u64| {
        let k = (bits.trailing_zeros() / 4) as usize & (BIN_COUNT - 1);
        (axis, k, cost[k][axis])
    };
    let first = (0..3)
        .find(|&axis| on_axis(axis) != 0)
        .map(|axis| at(axis, on_axis(axis)))?;
    if first.2.is_nan() {
        return Some(first);
    }
    let smallest = least.x.min(least.y).min(least.z);
    for axis in 0..3 {
        if least[axis] != smallest {
            continue;
        }
        let mut bits = on_axis(axis);
        while bits != 0 {
            let found = at(axis, bits);
            if found.2 == smallest {
                return Some(found);
            }
            bits &= bits - 1;
        }
    }
    Some(first)
}

/// Partitions `range` of `refs` in place by the split (left side first; the order within a
/// side is not specified but deterministic); returns the left count and both centroid boxes.
/// Each primitive is classified once; only misplaced pairs are swapped.
#[inline(always)]
pub(super) fn partition<R: Refs>(
    refs: &mut R,
    range: core::ops::Range<usize>,
    split: &Split,
) -> (u32, Aabb, Aabb) {
    refs.visit_run(range, PartitionBy(split))
}

/// [`partition`] on one run of elements.
struct PartitionBy<'a>(&'a Split);

impl RunVisitor for PartitionBy<'_> {
    type Out = (u32, Aabb, Aabb);

    /// Hoare's scheme on shrinking subslices (no index arithmetic or range checks per element):
    /// `rest` holds the elements not yet placed.
    #[inline(always)]
    fn visit<E>(self, run: &mut [E], bounds: impl Fn(&E) -> Box2) -> Self::Out {
        let classify = |e: &E| self.0.classify(bounds(e));
        let (mut llo, mut lhi) = (Corner::INFINITY, Corner::NEG_INFINITY);
        let (mut rlo, mut rhi) = (Corner::INFINITY, Corner::NEG_INFINITY);
        let mut left = 0u32;
        let mut rest = run;
        'outer: loop {
            // The first element from the left that belongs right…
            let (first, right_c, mut tail) = loop {
                let Some((first, tail)) = core::mem::take(&mut rest).split_first_mut() else {
                    break 'outer;
                };
                let (goes_left, c) = classify(first);
                if !goes_left {
                    break (first, c, tail);
                }
                extend(&mut llo, &mut lhi, c);
                left += 1;
                rest = tail;
            };
            // …and the first from the right that belongs left; `first` itself belongs right,
            // so this stops above it.
            let (last, left_c) = loop {
                let Some((last, init)) = core::mem::take(&mut tail).split_last_mut() else {
                    extend(&mut rlo, &mut rhi, right_c);
                    break 'outer;
                };
                let (goes_left, c) = classify(last);
                if goes_left {
                    rest = init;
                    break (last, c);
                }
                extend(&mut rlo, &mut rhi, c);
                tail = init;
            };
            core::mem::swap(first, last);
            extend(&mut llo, &mut lhi, left_c);
            extend(&mut rlo, &mut rhi, right_c);
            left += 1;
        }
        (
            left,
            Aabb::new(point(llo), point(lhi)),
            Aabb::new(point(rlo), point(rhi)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::scratch::{PrimRef, Scratch};

    #[test]
    fn partition_splits_by_bin_and_reports_both_centroid_boxes() {
        // 40 unit boxes with centres at x = 0..40 in a scrambled order; split at bin 5 of
        // 16 over [0, 39]: centres below 39·5/16 = 12.1875 go left. The builder's points and
        // centroid boxes are twice the centres (`centre2`).
        let mut refs_store = [PrimRef::EMPTY; 40];
        for (k, slot) in refs_store.iter_mut().enumerate() {
            let x = ((k * 17) % 40) as f32;
            let b = Aabb::new(Vec3::new(x - 0.5, 0.0, 0.0), Vec3::new(x + 0.5, 1.0, 1.0));
            *slot = PrimRef::new(&b, k as u32);
        }
        let centroids = Aabb::new(Vec3::ZERO, Vec3::new(78.0, 0.0, 0.0));
        let binner = Binner::new(&centroids, 16).unwrap();
        let split = Split::new(binner, 0, 5);
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
        assert_eq!((lc.min.x, lc.max.x), (0.0, 24.0));
        assert_eq!((rc.min.x, rc.max.x), (26.0, 78.0));
    }

    /// [`best_sah_split`] against its documented cost, worked by hand: four boxes
    /// `[x₀, x₁] × [0, 1] × [0, 1]`, of surface area `2·(w + 1 + w) = 4w + 2` for width
    /// `w = x₁ − x₀`:
    ///
    /// | primitive | x        | centre | bin of 4 over the centres' `[0, 4]` |
    /// |-----------|----------|--------|--------------------------------------|
    /// | 0         | [−0.5, 0.5] | 0   | 0                                    |
    /// | 1         | [1, 2]   | 1.5    | 1                                    |
    /// | 2         | [2, 3]   | 2.5    | 2                                    |
    /// | 3         | [1, 7]   | 4      | 3 (the upper end, clamped)           |
    ///
    /// Only x has a centroid extent (every y and z centre is 0.5), and 4 primitives get
    /// `4 + 4/8 = 4` bins: planes `k = 1, 2, 3`, primitives `..k` left. With
    /// `primitive_cost = 2`, `cost = TRAVERSAL_COST·A + 2·(A_L·N_L + A_R·N_R)`:
    ///
    /// * `k = 1`: L `[−0.5, 0.5]` (w 1, A 6, N 1), R `[1, 7]` (w 6, A 26, N 3):
    ///   `6·1 + 26·3 = 84`;
    /// * `k = 2`: L `[−0.5, 2]` (w 2.5, A 12, N 2), R `[1, 7]` (A 26, N 2): `24 + 52 = 76`;
    /// * `k = 3`: L `[−0.5, 3]` (w 3.5, A 16, N 3), R `[1, 7]` (A 26, N 1): `48 + 26 = 74`.
    ///
    /// So `k = 3` wins, at `1·A + 2·74` with the parent `[−0.5, 7]` (w 7.5, `A = 32`):
    /// `32 + 148 = 180`. Without the counts `k = 1` would win (`6 + 26 = 32` against 38 and
    /// 42), and with them swapped (`A_L·N_R + A_R·N_L`) too (44 against 76 and 94). Every
    /// value is a small integer, exact in `f32`: compared exactly.
    #[test]
    fn best_split_costs_as_the_documented_sah() {
        let xs = [(-0.5, 0.5), (1.0, 2.0), (2.0, 3.0), (1.0, 7.0)];
        let refs: [PrimRef; 4] = core::array::from_fn(|i| {
            let (lo, hi) = xs[i];
            let b = Aabb::new(Vec3::new(lo, 0.0, 0.0), Vec3::new(hi, 1.0, 1.0));
            PrimRef::new(&b, i as u32)
        });
        // The builder's centroid box is of the doubled centres (`centre2`): x 0..8, y = z = 1.
        let centroids = Aabb::new(Vec3::new(0.0, 1.0, 1.0), Vec3::new(8.0, 1.0, 1.0));
        let mut sets = [UNUSED_SET; BIN_SETS];
        let split = best_sah_split(&refs[..], &mut sets, 0..4, &centroids, 32.0, 2.0).unwrap();
        let limit: [f32; 3] = core::array::from_fn(|a| split.limit[a]);
        assert_eq!(limit[0], 3.0, "below bin 3 of x");
        assert!(limit[1].is_nan() && limit[2].is_nan(), "{limit:?}");
        assert_eq!(split.cost, 180.0);
        let (l, r) = (split.left, split.right);
        assert_eq!(
            (l.min, l.max),
            (Vec3::new(-0.5, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0))
        );
        assert_eq!(
            (r.min, r.max),
            (Vec3::new(1.0, 0.0, 0.0), Vec3::new(7.0, 1.0, 1.0))
        );
    }

    /// [`cheapest`] against the scan it stands for, written out here: candidates in axis-major
    /// order, then by plane, the first kept and replaced only by a strictly smaller cost. Costs
    /// drawn from a few values so that ties are common, with `±0`, `+∞` and NaN among them;
    /// random candidate sets, the empty one included.
    #[test]
    // The scan written with indices, as its rule is stated.
    #[allow(clippy::needless_range_loop)]
    fn cheapest_is_the_axis_major_scan() {
        let values = [0.0, -0.0, 1.0, 2.0, 2.0, 3.5, f32::INFINITY, f32::NAN];
        let mut seed = 0x9e37_79b9_u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        let mut nan_first = 0;
        for case in 0..20_000 {
            let mut cost = [Vec4::ZERO; BIN_COUNT];
            for c in &mut cost {
                *c = Vec4::from_array(core::array::from_fn(|_| values[next() as usize % 8]));
            }
            // Fewer candidates in some cases, so that single and absent ones occur.
            let density = next() % 4;
            let mut candidates = 0u64;
            for k in 1..BIN_COUNT {
                for axis in 0..3 {
                    if next() % 4 < density {
                        candidates |= 1 << (4 * k + axis);
                    }
                }
            }
            let mut least = Vec4::INFINITY;
            for (k, c) in cost.iter().enumerate() {
                for axis in 0..3 {
                    if candidates >> (4 * k + axis) & 1 == 1 && !c[axis].is_nan() {
                        least[axis] = least[axis].min(c[axis]);
                    }
                }
            }
            let mut scan: Option<(usize, usize, f32)> = None;
            for axis in 0..3 {
                for k in 1..BIN_COUNT {
                    if candidates >> (4 * k + axis) & 1 == 0 {
                        continue;
                    }
                    let c = cost[k][axis];
                    match scan {
                        Some((_, _, b)) if !(c < b) => {}
                        _ => scan = Some((axis, k, c)),
                    }
                }
            }
            let got = cheapest(&cost, candidates, least);
            let key = |r: Option<(usize, usize, f32)>| r.map(|(a, k, c)| (a, k, c.to_bits()));
            assert_eq!(key(got), key(scan), "case {case}");
            nan_first += usize::from(scan.is_some_and(|(_, _, c)| c.is_nan()));
        }
        assert!(nan_first > 100, "a NaN first candidate occurs: {nan_first}");
    }

    /// The bin index along each axis, written from [`Binner`]'s contract (clamped to
    /// `[0, last]`, NaN to 0, truncated) in scalar `f32`, not with its code.
    fn bin_of(binner: &Binner, c: Vec3, axis: usize) -> usize {
        let x = (c[axis] - binner.lo[axis]) * binner.scale[axis];
        let x = if x.is_nan() || x < 0.0 { 0.0 } else { x };
        x.min(binner.last[axis]) as usize
    }

    #[test]
    fn goes_left_is_bin_below_split_for_every_centre() {
        // Centroid boxes with ordinary, huge, tiny (subnormal extent: the scale overflows to
        // infinity) and flat extents; centres inside, on and outside them, and at the extremes.
        let boxes = [
            Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 0.5, 2.0)),
            Aabb::new(Vec3::splat(-3.0e38), Vec3::splat(3.0e38)),
            Aabb::new(Vec3::ZERO, Vec3::new(1.0e-45, 3.0e-39, 1.0e-30)),
            Aabb::new(Vec3::splat(1.0e30), Vec3::new(1.0e30, 2.0e30, 1.0e30)),
        ];
        let mut seed = 0x2545_f491_u32;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        let mut checked = 0;
        for b in &boxes {
            for count in [2, 5, 9, BIN_COUNT] {
                let Some(binner) = Binner::new(b, count) else {
                    continue;
                };
                let mut centres = [
                    b.min,
                    b.max,
                    b.center(),
                    Vec3::splat(f32::MAX),
                    Vec3::splat(-f32::MAX),
                    Vec3::ZERO,
                    Vec3::splat(-0.0),
                    Vec3::splat(f32::MIN_POSITIVE),
                ]
                .to_vec();
                for _ in 0..200 {
                    // A point of the box at a random fraction, or a random finite float.
                    let t =
                        Vec3::new(next() as f32, next() as f32, next() as f32) / u32::MAX as f32;
                    centres.push(b.min + (b.max - b.min) * t);
                    let mut bits = || loop {
                        let f = f32::from_bits(next());
                        if f.is_finite() {
                            break f;
                        }
                    };
                    centres.push(Vec3::new(bits(), bits(), bits()));
                }
                for axis in (0..3).filter(|&a| binner.active[a]) {
                    for split in 1..count {
                        let limit = binner.limit(axis, split);
                        for &c in &centres {
                            let want = bin_of(&binner, c, axis) < split;
                            assert_eq!(binner.bins(corner(c))[axis], bin_of(&binner, c, axis));
                            assert_eq!(
                                binner.goes_left(corner(c), limit),
                                want,
                                "{c:?} axis {axis} split {split} of {count} over {b:?}"
                            );
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert!(checked > 100_000, "{checked}");
    }
}
