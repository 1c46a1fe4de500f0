//! Binned-SAH construction into caller storage, without allocation or recursion.
//!
//! One algorithm over two views of the primitives ([`Refs`]): the source read through the
//! index array ([`super::Bvh::build`], no scratch), or a caller-provided scratch array of
//! [`PrimRef`]s (box, centroid, index) filled once and reordered in place
//! ([`super::Bvh::build_with_scratch`]): every level then reads contiguous records instead of
//! re-reading the mesh through the index array, several times faster on large meshes. Both
//! give the same tree.

use super::node::BvhNode;
use super::primitive::{PrimitiveSource, is_usable};
use super::{
    BIN_COUNT, BvhError, DEFAULT_MAX_LEAF_SIZE, INTERSECTION_COST, MAX_DEPTH, MAX_PRIMITIVES,
    TRAVERSAL_COST, index_capacity, node_capacity,
};
use crate::aabb::Aabb;
use glam::Vec3;

/// The builder's box corners: 16-byte SIMD vectors on x86-64 (one `min`/`max` instruction per
/// bin update; the fourth lane is spare: a [`PrimRef`] keeps its index there, bins ignore it),
/// plain `Vec3` elsewhere (smaller records and a smaller stack frame on microcontrollers, where
/// there is no SIMD to use). Same values either way.
#[cfg(target_arch = "x86_64")]
type Corner = glam::Vec4;
#[cfg(not(target_arch = "x86_64"))]
type Corner = Vec3;

/// `v` as a corner (spare lane 0).
#[inline(always)]
fn corner(v: Vec3) -> Corner {
    #[cfg(target_arch = "x86_64")]
    return v.extend(0.0);
    #[cfg(not(target_arch = "x86_64"))]
    return v;
}

/// The `x, y, z` of a corner.
#[inline(always)]
fn point(c: Corner) -> Vec3 {
    #[cfg(target_arch = "x86_64")]
    return c.truncate();
    #[cfg(not(target_arch = "x86_64"))]
    return c;
}

/// The point a primitive is binned by: the centre of its box `lo, hi`, computed as
/// [`Aabb::center`] does (`lo/2 + hi/2`, which cannot overflow), lane by lane.
#[inline(always)]
fn centre(lo: Corner, hi: Corner) -> Corner {
    lo * 0.5 + hi * 0.5
}

/// Growing `[lo, hi]` by `p` (finite corners: one vector `min` and `max`).
#[inline(always)]
fn extend(lo: &mut Corner, hi: &mut Corner, p: Corner) {
    *lo = lo.min(p);
    *hi = hi.max(p);
}

/// Sets of bins filled alternately by the binning loop ([`best_sah_split`]): two on x86-64,
/// one elsewhere (a microcontroller's stack is small and its loads do not overlap anyway).
const BIN_SETS: usize = if cfg!(target_arch = "x86_64") { 2 } else { 1 };

/// The bins of one node, kept by the split loop across nodes (cleared per node as far as used).
type BinSets = [[[Bin; BIN_COUNT]; 3]; BIN_SETS];

/// Depth from which nodes are split by count rather than by SAH: `MAX_DEPTH − 32`, so that the
/// remaining 32 levels can halve any node of up to `2³¹` primitives down to one.
const MEDIAN_DEPTH: u32 = (MAX_DEPTH - 32) as u32;

/// Options of [`super::Bvh::build`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// Nodes with more primitives than this are always split while the depth limit allows;
    /// smaller nodes are split only when the SAH says it pays. Values below 1 count as 1.
    /// Default [`DEFAULT_MAX_LEAF_SIZE`].
    pub max_leaf_size: u32,
    /// `false` (default): a primitive with non-finite or empty bounds is an error
    /// ([`BvhError::NonFinitePrimitive`]). `true`: such primitives are left out of the tree
    /// (no query ever reports them).
    pub exclude_non_finite: bool,
    /// Nodes of at most this many primitives become leaves without trying a split (capped
    /// at `max_leaf_size`; values below 1 count as 1). Default 1: the SAH decides for every
    /// node of two or more. A tree that will be collapsed into a wide one is built with
    /// [`LEAF_MERGE`](super::wide::LEAF_MERGE) here ([`super::wide::binary_options`]): the
    /// collapse turns every subtree that small into one leaf, so splitting it is wasted work.
    pub leaf_threshold: u32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            max_leaf_size: DEFAULT_MAX_LEAF_SIZE,
            exclude_non_finite: false,
            leaf_threshold: 1,
        }
    }
}

/// A node waiting to be split: its index range, depth and centroid bounds (its own box is
/// already written into the node).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Task {
    pub(super) node: u32,
    pub(super) start: u32,
    pub(super) end: u32,
    pub(super) depth: u32,
    pub(super) centroids: Aabb,
}

pub(super) const EMPTY_TASK: Task = Task {
    node: 0,
    start: 0,
    end: 0,
    depth: 0,
    centroids: Aabb::EMPTY,
};

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
struct Bin {
    lo: Corner,
    hi: Corner,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    lo: Corner::INFINITY,
    hi: Corner::NEG_INFINITY,
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
struct Split {
    axis: usize,
    binner: Binner,
    split: usize,
    cost: f32,
    left: Aabb,
    right: Aabb,
}

/// A primitive as the scratch builder keeps it: its box and its index in the source (the
/// centre it is binned by is computed from the box when needed). On x86-64 the corners are
/// 16-byte vectors, so binning is one `min` and one `max` per bin, and the index lives in the
/// lower corner's spare lane: 32 bytes. Elsewhere 28 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimRef {
    lo: Corner,
    hi: Corner,
    #[cfg(not(target_arch = "x86_64"))]
    index: u32,
}

impl PrimRef {
    /// A record for initialising scratch storage: `[PrimRef::EMPTY; K]`.
    pub const EMPTY: Self = Self {
        lo: Corner::INFINITY,
        hi: Corner::NEG_INFINITY,
        #[cfg(not(target_arch = "x86_64"))]
        index: 0,
    };

    /// The record of primitive `index` with box `b`.
    #[inline(always)]
    fn new(b: &Aabb, index: u32) -> Self {
        #[cfg(target_arch = "x86_64")]
        return Self {
            // The bits of `index` are only stored and copied, never computed with, so any
            // bit pattern (a NaN's included) comes back unchanged.
            lo: b.min.extend(f32::from_bits(index)),
            hi: corner(b.max),
        };
        #[cfg(not(target_arch = "x86_64"))]
        return Self {
            lo: b.min,
            hi: b.max,
            index,
        };
    }

    /// The box's corners, spare lanes zero.
    #[inline(always)]
    fn corners(&self) -> (Corner, Corner) {
        // The index's bits are a subnormal `f32` for most indices: arithmetic on them would
        // take the processor's slow path, so the lane is cleared by a bit select first.
        #[cfg(target_arch = "x86_64")]
        return (
            Corner::select(
                glam::BVec4A::new(true, true, true, false),
                self.lo,
                Corner::ZERO,
            ),
            self.hi,
        );
        #[cfg(not(target_arch = "x86_64"))]
        return (self.lo, self.hi);
    }

    /// The primitive's index in the source.
    #[inline(always)]
    fn index(&self) -> u32 {
        #[cfg(target_arch = "x86_64")]
        return self.lo.w.to_bits();
        #[cfg(not(target_arch = "x86_64"))]
        return self.index;
    }
}

impl Default for PrimRef {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Scratch entries [`super::Bvh::build_with_scratch`] needs for `prim_count` primitives: `N`.
#[must_use]
pub const fn scratch_capacity(prim_count: usize) -> usize {
    prim_count
}

/// The primitives being partitioned: the box of element `k` of the current order (its spare
/// lanes mean nothing), and swapping two elements.
pub(super) trait Refs {
    fn get(&self, k: usize) -> (Corner, Corner);
    fn swap(&mut self, i: usize, j: usize);
}

/// The source read through the index array (no scratch).
struct Indexed<'a, S: ?Sized> {
    source: &'a S,
    indices: &'a mut [u32],
}

impl<S: PrimitiveSource + ?Sized> Refs for Indexed<'_, S> {
    #[inline(always)]
    fn get(&self, k: usize) -> (Corner, Corner) {
        let i = self.indices.get(k).map_or(usize::MAX, |&i| i as usize);
        let b = self.source.primitive_bounds(i);
        (corner(b.min), corner(b.max))
    }

    #[inline(always)]
    fn swap(&mut self, i: usize, j: usize) {
        if i < self.indices.len() && j < self.indices.len() {
            self.indices.swap(i, j);
        }
    }
}

/// The scratch records `offset ..` (a job's run holds the records of its primitive range
/// only; positions stay global).
pub(super) struct Scratch<'a> {
    pub(super) refs: &'a mut [PrimRef],
    pub(super) offset: usize,
}

impl Refs for Scratch<'_> {
    #[inline(always)]
    fn get(&self, k: usize) -> (Corner, Corner) {
        k.checked_sub(self.offset)
            .and_then(|k| self.refs.get(k))
            .map_or((Corner::NAN, Corner::NAN), PrimRef::corners)
    }

    #[inline(always)]
    fn swap(&mut self, i: usize, j: usize) {
        let (Some(i), Some(j)) = (i.checked_sub(self.offset), j.checked_sub(self.offset)) else {
            return;
        };
        if i < self.refs.len() && j < self.refs.len() {
            self.refs.swap(i, j);
        }
    }
}

/// The nodes a build writes, by global index: `nodes[k]` is node `base + k`, and `root`, when
/// set, stands for one node outside the slice (a job's root, allocated by the split above it).
pub(super) struct NodeView<'a> {
    pub(super) nodes: &'a mut [BvhNode],
    pub(super) base: u32,
    pub(super) root: Option<(u32, &'a mut BvhNode)>,
}

impl NodeView<'_> {
    #[inline(always)]
    fn get_mut(&mut self, g: u32) -> Option<&mut BvhNode> {
        if let Some((r, rec)) = &mut self.root
            && *r == g
        {
            return Some(rec);
        }
        self.nodes.get_mut(g.checked_sub(self.base)? as usize)
    }

    #[inline(always)]
    fn bounds(&mut self, g: u32) -> Option<Aabb> {
        self.get_mut(g).map(|n| n.bounds())
    }

    /// Whether two more nodes fit when `next` is the next free global index.
    #[inline(always)]
    fn has_pair(&self, next: u32) -> bool {
        next.checked_sub(self.base)
            .is_some_and(|k| k as usize + 2 <= self.nodes.len())
    }
}

/// Where the top of a split build leaves subtrees (see [`super::jobs`]): a child task of at
/// most `job_size` primitives (and more than a leaf's) becomes a job while there is room.
pub(super) struct JobSink<'a> {
    pub(super) jobs: &'a mut [super::jobs::BuildJob],
    pub(super) len: usize,
    pub(super) job_size: u32,
}

impl JobSink<'_> {
    /// Takes `task` as a job (true) or leaves it to the caller (false).
    fn take(&mut self, task: &Task, max_leaf: u32) -> bool {
        let n = task.end - task.start;
        if n <= max_leaf || n > self.job_size {
            return false;
        }
        match self.jobs.get_mut(self.len) {
            Some(slot) => {
                *slot = super::jobs::BuildJob::new(*task);
                self.len += 1;
                true
            }
            None => false,
        }
    }
}

/// Checks the storage and every primitive (nothing written but what `usable` writes); calls
/// `usable(k, i, bounds, centroid)` for the `k`-th usable primitive `i`; returns the usable
/// count and the root's box and centroid box.
fn validate<S: PrimitiveSource + ?Sized>(
    source: &S,
    nodes: &[BvhNode],
    indices: &[u32],
    options: &BuildOptions,
    mut usable: impl FnMut(usize, usize, Aabb, Vec3),
) -> Result<(u32, Aabb, Aabb), BvhError> {
    let n = source.primitive_count();
    if n > MAX_PRIMITIVES {
        return Err(BvhError::TooManyPrimitives { count: n });
    }
    if nodes.len() < node_capacity(n) {
        return Err(BvhError::NodeStorageTooSmall {
            needed: node_capacity(n),
            available: nodes.len(),
        });
    }
    if indices.len() < index_capacity(n) {
        return Err(BvhError::IndexStorageTooSmall {
            needed: index_capacity(n),
            available: indices.len(),
        });
    }
    let mut root_bounds = Aabb::EMPTY;
    let mut root_centroids = Aabb::EMPTY;
    let mut count = 0u32;
    for i in 0..n {
        let b = source.primitive_bounds(i);
        let c = b.center();
        if is_usable(&b) && c.is_finite() {
            root_bounds = root_bounds.union(b);
            root_centroids = root_centroids.grow(c);
            usable(count as usize, i, b, c);
            count += 1;
        } else if !options.exclude_non_finite {
            return Err(BvhError::NonFinitePrimitive { index: i });
        }
    }
    Ok((count, root_bounds, root_centroids))
}

/// Builds into `nodes`/`indices`; returns `(node_count, prim_count)`.
pub(super) fn build<S: PrimitiveSource + ?Sized>(
    source: &S,
    nodes: &mut [BvhNode],
    indices: &mut [u32],
    options: &BuildOptions,
) -> Result<(u32, u32), BvhError> {
    let (count, root_bounds, root_centroids) =
        validate(source, nodes, indices, options, |_, _, _, _| {})?;
    if count == 0 {
        return Ok((0, 0));
    }
    let mut k = 0usize;
    for i in 0..source.primitive_count() {
        let b = source.primitive_bounds(i);
        if !(is_usable(&b) && b.center().is_finite()) {
            continue;
        }
        if let Some(slot) = indices.get_mut(k) {
            *slot = i as u32;
        }
        k += 1;
    }
    let mut refs = Indexed { source, indices };
    let node_count = build_top(
        &mut refs,
        nodes,
        count,
        &root_bounds,
        root_centroids,
        options,
        None,
    );
    Ok((node_count, count))
}

/// [`build`] on a scratch array of [`PrimRef`]s (at least [`scratch_capacity`] entries, else
/// [`BvhError::ScratchTooSmall`] before anything is written). The scratch's contents after the
/// call mean nothing.
pub(super) fn build_with_scratch<S: PrimitiveSource + ?Sized>(
    source: &S,
    nodes: &mut [BvhNode],
    indices: &mut [u32],
    scratch: &mut [PrimRef],
    options: &BuildOptions,
) -> Result<(u32, u32), BvhError> {
    // One pass over the source: the records are written while validating (the scratch is
    // not output; nodes and indices are written only after the pass succeeds).
    let (count, root_bounds, root_centroids) =
        prepare_scratch(source, nodes, indices, scratch, options)?;
    if count == 0 {
        return Ok((0, 0));
    }
    let refs = scratch.get_mut(..count as usize).unwrap_or_default();
    let mut view = Scratch { refs, offset: 0 };
    let node_count = build_top(
        &mut view,
        nodes,
        count,
        &root_bounds,
        root_centroids,
        options,
        None,
    );
    fill_indices(indices, view.refs);
    Ok((node_count, count))
}

/// `indices[k]` = the source index of record `k` (the final leaf order).
pub(super) fn fill_indices(indices: &mut [u32], refs: &[PrimRef]) {
    for (slot, r) in indices.iter_mut().zip(refs) {
        *slot = r.index();
    }
}

/// Validates `source` and the storage, fills `scratch`: the first pass of
/// [`build_with_scratch`], for the split build. Returns the usable count and the root's box
/// and centroid box.
pub(super) fn prepare_scratch<S: PrimitiveSource + ?Sized>(
    source: &S,
    nodes: &[BvhNode],
    indices: &[u32],
    scratch: &mut [PrimRef],
    options: &BuildOptions,
) -> Result<(u32, Aabb, Aabb), BvhError> {
    let n = source.primitive_count();
    if scratch.len() < scratch_capacity(n) {
        return Err(BvhError::ScratchTooSmall {
            needed: scratch_capacity(n),
            available: scratch.len(),
        });
    }
    validate(source, nodes, indices, options, |k, i, bounds, _| {
        if let Some(slot) = scratch.get_mut(k) {
            *slot = PrimRef::new(&bounds, i as u32);
        }
    })
}

/// The top of every build: the root, the optional cache-line pad, then [`grow`] from the
/// root (leaving subtrees to `jobs` when given). Returns the next free node index.
#[allow(clippy::too_many_arguments)]
pub(super) fn build_top<R: Refs>(
    refs: &mut R,
    nodes: &mut [BvhNode],
    count: u32,
    root_bounds: &Aabb,
    root_centroids: Aabb,
    options: &BuildOptions,
    jobs: Option<&mut JobSink<'_>>,
) -> u32 {
    let mut node_count = 1u32;
    if let Some(root) = nodes.first_mut() {
        root.set_bounds(root_bounds);
    }
    // Sibling pairs are allocated two by two after the root. When the storage has a spare slot,
    // start them at a 64-byte boundary (skipping node 1, left empty) so that the two boxes a
    // traversal step reads share one cache line. Only speed depends on this.
    let base_is_64_aligned = (nodes.as_ptr() as usize).is_multiple_of(64);
    if base_is_64_aligned && nodes.len() > node_capacity(count as usize) {
        if let Some(pad) = nodes.get_mut(1) {
            *pad = BvhNode::EMPTY;
        }
        node_count = 2;
    }
    let task = Task {
        node: 0,
        start: 0,
        end: count,
        depth: 0,
        centroids: root_centroids,
    };
    let mut view = NodeView {
        nodes,
        base: 0,
        root: None,
    };
    grow(refs, &mut view, task, &mut node_count, options, jobs);
    node_count
}

/// The split loop shared by all builders: splits `task`'s node and its descendants, allocating
/// node pairs from `*next` on (global indices of `view`). A child task that `jobs` takes is
/// left for later (its node holds its box).
pub(super) fn grow<R: Refs>(
    refs: &mut R,
    view: &mut NodeView<'_>,
    task: Task,
    next: &mut u32,
    options: &BuildOptions,
    mut jobs: Option<&mut JobSink<'_>>,
) {
    let max_leaf = options.max_leaf_size.max(1);
    let threshold = options.leaf_threshold.clamp(1, max_leaf);
    let mut stack = [EMPTY_TASK; MAX_DEPTH + 1];
    let mut bins: BinSets = [[[EMPTY_BIN; BIN_COUNT]; 3]; BIN_SETS];
    let mut sp = 0usize;
    let mut task = task;
    loop {
        let mut pending = split_node(refs, view, &task, (max_leaf, threshold), next, &mut bins);
        if let (Some((left, right)), Some(sink)) = (pending, jobs.as_deref_mut()) {
            pending = match (sink.take(&left, max_leaf), sink.take(&right, max_leaf)) {
                (false, false) => Some((left, right)),
                (true, false) => Some((right, EMPTY_TASK)),
                (false, true) => Some((left, EMPTY_TASK)),
                (true, true) => None,
            };
        }
        match pending {
            Some((left, right)) if right.end > right.start => {
                // Continue with the left child, keep the right one for later. The stack holds
                // at most one pending child per level, and levels stop at MAX_DEPTH.
                if let Some(slot) = stack.get_mut(sp) {
                    *slot = right;
                    sp += 1;
                    task = left;
                } else {
                    // Unreachable by the depth limit; recover by finishing both as leaves.
                    make_leaf(view, &left);
                    make_leaf(view, &right);
                    if sp == 0 {
                        break;
                    }
                    sp -= 1;
                    task = stack[sp];
                }
            }
            Some((only, _)) => task = only,
            None => {
                if sp == 0 {
                    break;
                }
                sp -= 1;
                task = stack[sp];
            }
        }
    }
}

fn make_leaf(view: &mut NodeView<'_>, task: &Task) {
    if let Some(node) = view.get_mut(task.node) {
        node.set_leaf(task.start, task.end - task.start);
    }
}

/// Splits `task`'s node in two, writing the parent and both children's boxes, or makes it a
/// leaf (returns `None`). `(max_leaf, threshold)`: larger nodes are always split, nodes of at
/// most `threshold` never.
fn split_node<R: Refs>(
    refs: &mut R,
    nodes: &mut NodeView<'_>,
    task: &Task,
    (max_leaf, threshold): (u32, u32),
    node_count: &mut u32,
    bins: &mut BinSets,
) -> Option<(Task, Task)> {
    let count = task.end - task.start;
    let parent_bounds = nodes.bounds(task.node)?;
    if count <= threshold || task.depth as usize >= MAX_DEPTH || !nodes.has_pair(*node_count) {
        make_leaf(nodes, task);
        return None;
    }
    let range = task.start as usize..task.end as usize;
    let split = best_sah_split(
        refs,
        bins,
        range.clone(),
        &task.centroids,
        parent_bounds.surface_area(),
    );
    let leaf_cost = INTERSECTION_COST * count as f32 * parent_bounds.surface_area();
    // Deep in the tree, split by count: from MEDIAN_DEPTH on every split halves the node, so
    // no node reaches MAX_DEPTH with more than `max_leaf` primitives (N < 2³¹ halves to one in
    // 31 levels) and leaves never exceed the requested size.
    let split = split.filter(|_| task.depth < MEDIAN_DEPTH);
    let (mid, left_b, right_b, left_c, right_c) = match split {
        Some(s) if s.cost < leaf_cost || count > max_leaf => {
            let (mid, lc, rc) = partition(refs, range, &s);
            (task.start + mid, s.left, s.right, lc, rc)
        }
        _ if count > max_leaf => {
            // All centroids coincide, or the node is deep: split by count, in index order.
            let mid = count / 2;
            let cut = range.start + mid as usize;
            let (lb, lc) = range_bounds(refs, range.start..cut);
            let (rb, rc) = range_bounds(refs, cut..range.end);
            (task.start + mid, lb, rb, lc, rc)
        }
        _ => {
            make_leaf(nodes, task);
            return None;
        }
    };
    let first = *node_count;
    *node_count += 2;
    for (g, b) in [(first, &left_b), (first + 1, &right_b)] {
        if let Some(n) = nodes.get_mut(g) {
            n.set_bounds(b);
        }
    }
    if let Some(n) = nodes.get_mut(task.node) {
        n.set_inner(first);
    }
    let depth = task.depth + 1;
    Some((
        Task {
            node: first,
            start: task.start,
            end: mid,
            depth,
            centroids: left_c,
        },
        Task {
            node: first + 1,
            start: mid,
            end: task.end,
            depth,
            centroids: right_c,
        },
    ))
}

/// Box and centroid box of a run of primitives.
fn range_bounds<R: Refs>(refs: &R, range: core::ops::Range<usize>) -> (Aabb, Aabb) {
    let (mut lo, mut hi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    let (mut clo, mut chi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    for k in range {
        let (plo, phi) = refs.get(k);
        lo = lo.min(plo);
        hi = hi.max(phi);
        extend(&mut clo, &mut chi, centre(plo, phi));
    }
    (
        Aabb::new(point(lo), point(hi)),
        Aabb::new(point(clo), point(chi)),
    )
}

/// Bins the primitives (`min(count, BIN_COUNT)` bins) along every axis with a non-zero
/// centroid extent and returns the
/// cheapest split with both sides non-empty. The cost is the SAH numerator (not divided by the
/// parent's area, so that zero-area parents need no special case):
/// `TRAVERSAL_COST·A + INTERSECTION_COST·(A_L·N_L + A_R·N_R)`.
fn best_sah_split<R: Refs>(
    refs: &R,
    sets: &mut BinSets,
    range: core::ops::Range<usize>,
    centroids: &Aabb,
    parent_area: f32,
) -> Option<Split> {
    // As many bins as primitives, up to BIN_COUNT: a small node needs no more candidate
    // planes than it has primitives, and the sweep costs per bin.
    let bin_count = range.len().clamp(2, BIN_COUNT);
    // An axis without extent bins everything into bin 0 and is skipped below.
    let binner = Binner::new(centroids, bin_count)?;
    // Consecutive primitives go to alternate sets of bins, merged after the loop, so that two
    // primitives in one bin do not wait for each other's update. Only the bins in use are
    // cleared (most nodes are small).
    for axis_bins in sets.iter_mut().flatten() {
        for bin in axis_bins.iter_mut().take(bin_count) {
            *bin = EMPTY_BIN;
        }
    }
    for (n, k) in range.enumerate() {
        let (lo, hi) = refs.get(k);
        let c = centre(lo, hi);
        let set = &mut sets[n & (BIN_SETS - 1)];
        for (axis_bins, b) in set.iter_mut().zip(binner.bins(c)) {
            if let Some(bin) = axis_bins.get_mut(b) {
                bin.add(lo, hi, 1);
            }
        }
    }
    let (bins, rest) = sets.split_at_mut(1);
    let bins = &mut bins[0];
    for set in rest.iter() {
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
                + INTERSECTION_COST * (left.area() * left.count as f32 + right_cost[k]);
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
fn partition<R: Refs>(
    refs: &mut R,
    range: core::ops::Range<usize>,
    split: &Split,
) -> (u32, Aabb, Aabb) {
    let classify = |refs: &R, k: usize| {
        let (lo, hi) = refs.get(k);
        let c = centre(lo, hi);
        let bin = split.binner.bins(c).get(split.axis).copied().unwrap_or(0);
        (bin < split.split, c)
    };
    let (mut llo, mut lhi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    let (mut rlo, mut rhi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    let (mut i, mut j) = (range.start, range.end);
    'outer: while i < j {
        // The first element from the left that belongs right…
        let right_c = loop {
            let (left, c) = classify(refs, i);
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
            let (left, c) = classify(refs, j);
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

    #[test]
    fn prim_ref_keeps_every_index_and_box() {
        // Indices whose bits are a subnormal, a NaN, infinity and the largest allowed.
        let b = Aabb::new(Vec3::new(-1.5, 2.0, -0.0), Vec3::new(3.0, 2.0, 7.25));
        for index in [
            0,
            1,
            0x007F_FFFF,
            0x7F80_0000,
            0x7F80_0001,
            MAX_PRIMITIVES as u32,
        ] {
            let r = PrimRef::new(&b, index);
            let copy = [r, PrimRef::EMPTY];
            assert_eq!(copy[0].index(), index);
            let (lo, hi) = copy[0].corners();
            assert_eq!(Aabb::new(point(lo), point(hi)), b);
            // The spare lanes are zero: no subnormal or NaN reaches the arithmetic.
            assert_eq!(centre(lo, hi), corner(b.center()));
        }
    }

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
