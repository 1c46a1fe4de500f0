//! The binned surface-area heuristic of the kd-tree builder and the three-way partition of a
//! node's references.

use super::BIN_COUNT;
use super::kdref::KdRef;
use crate::aabb::Aabb;

/// A chosen split: plane `axis = position`, strictly inside the node's cell, and its SAH cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Split {
    pub(super) axis: usize,
    pub(super) position: f32,
    pub(super) cost: f64,
}

/// The SAH's three parameters (already checked: finite, traversal and intersection positive,
/// bonus in `[0, 1]`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Costs {
    pub(super) traversal: f64,
    pub(super) intersection: f64,
    pub(super) empty_bonus: f64,
}

/// Which children a reference goes to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Side {
    Below,
    Both,
    Above,
}

/// The side(s) of the plane `axis = s` a reference with clipped box `[lo, hi]` on that axis
/// goes to: below when `lo < s` or `hi ≤ s`, above when `hi > s`. So a box straddling the
/// plane goes to both, one touching it from one side goes to that side, and one lying in it
/// (`lo = hi = s`) goes below. Every point `q` of the box then lies in the closed cell of a
/// child that holds the reference (`q < s`: `lo < s`; `q > s`: `hi > s`; `q = s`: the side it
/// was given), which is what makes the traversal exact (module docs of [`super`]).
#[inline]
pub(super) fn side(r: &KdRef, axis: usize, s: f32) -> Side {
    let (lo, hi) = (r.min[axis % 3], r.max[axis % 3]);
    match (lo < s || hi <= s, hi > s) {
        (true, true) => Side::Both,
        (false, true) => Side::Above,
        _ => Side::Below,
    }
}

/// The SAH's measure of a cell of extents `e` (f64, so that huge scenes do not overflow):
/// its half surface area, or, for a cell flat in two axes (a segment, area 0), its length,
/// so that such cells can still be compared (`use_length`).
fn measure(e: [f64; 3], use_length: bool) -> f64 {
    if use_length {
        e[0] + e[1] + e[2]
    } else {
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }
}

/// The split of lowest SAH cost among the [`BIN_COUNT`]` − 1` bin boundaries of each axis of
/// `cell` with a non-zero extent, for the references `refs` (boxes clipped to `cell`):
///
/// `cost = traversal + intersection · (1 − bonus·[a side is empty]) · (m_b·n_b + m_a·n_a) / m`
///
/// with `m` the cell's half area (or length, see [`measure`]) and `n_b`, `n_a` the references
/// below and above, counted by bins (an estimate: the partition classifies exactly). `None`
/// when no axis can be split (every extent zero, or no boundary strictly inside the cell).
pub(super) fn best_split(refs: &[KdRef], cell: &Aabb, costs: &Costs) -> Option<Split> {
    let lo = cell.min.to_array().map(f64::from);
    let hi = cell.max.to_array().map(f64::from);
    let e = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    let use_length = !(measure(e, false) > 0.0);
    let parent = measure(e, use_length);
    if !(parent > 0.0 && parent.is_finite()) {
        return None;
    }
    let n = refs.len() as u64;
    let mut best: Option<Split> = None;
    for axis in 0..3 {
        if !(e[axis] > 0.0) {
            continue;
        }
        // Bins of every reference's lower and upper end (the index is clamped, so NaN and
        // out-of-cell values cannot leave the arrays).
        let mut starts = [0u32; BIN_COUNT];
        let mut ends = [0u32; BIN_COUNT];
        let scale = BIN_COUNT as f64 / e[axis];
        let bin = |x: f32| -> usize {
            let b = (f64::from(x) - lo[axis]) * scale;
            (b as usize).min(BIN_COUNT - 1)
        };
        for r in refs {
            if let Some(c) = starts.get_mut(bin(r.min[axis])) {
                *c += 1;
            }
            if let Some(c) = ends.get_mut(bin(r.max[axis])) {
                *c += 1;
            }
        }
        let (mut below, mut ended) = (0u64, 0u64);
        for k in 1..BIN_COUNT {
            below += u64::from(starts[k - 1]);
            ended += u64::from(ends[k - 1]);
            let above = n - ended;
            let f = k as f64 / BIN_COUNT as f64;
            let position = (lo[axis] + e[axis] * f) as f32;
            if !(position > cell.min[axis] && position < cell.max[axis]) {
                continue;
            }
            let (mut eb, mut ea) = (e, e);
            eb[axis] = f64::from(position) - lo[axis];
            ea[axis] = hi[axis] - f64::from(position);
            let bonus = if below == 0 || above == 0 {
                1.0 - costs.empty_bonus
            } else {
                1.0
            };
            let weighted =
                measure(eb, use_length) * below as f64 + measure(ea, use_length) * above as f64;
            let cost = costs.traversal + costs.intersection * bonus * weighted / parent;
            if best.is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    position,
                    cost,
                });
            }
        }
    }
    best
}

/// Counts `(below only, both, above only)` for the plane `split` (exact, by [`side`]).
pub(super) fn count_sides(refs: &[KdRef], split: &Split) -> (u32, u32, u32) {
    let mut c = (0u32, 0u32, 0u32);
    for r in refs {
        match side(r, split.axis, split.position) {
            Side::Below => c.0 += 1,
            Side::Both => c.1 += 1,
            Side::Above => c.2 += 1,
        }
    }
    c
}

/// Reorders `refs` in place into `[above only | both | below only]` for the plane `split`
/// (a three-way partition, no extra memory).
pub(super) fn partition(refs: &mut [KdRef], split: &Split) {
    let (mut lo, mut mid, mut hi) = (0usize, 0usize, refs.len());
    while mid < hi {
        let Some(r) = refs.get(mid) else { break };
        match side(r, split.axis, split.position) {
            Side::Above => {
                refs.swap(lo, mid);
                lo += 1;
                mid += 1;
            }
            Side::Both => mid += 1,
            Side::Below => {
                hi -= 1;
                refs.swap(mid, hi);
            }
        }
    }
}
