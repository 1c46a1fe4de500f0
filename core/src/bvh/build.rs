//! Binned-SAH construction into caller storage, without allocation or recursion.
//!
//! One algorithm over two views of the primitives ([`Refs`]): the source read through the
//! index array ([`super::Bvh::build`], no scratch), or a caller-provided scratch array of
//! [`PrimRef`]s (box and index; [`super::scratch`]) filled once and reordered in place
//! ([`super::Bvh::build_with_scratch`]): every level then reads contiguous records instead of
//! re-reading the mesh through the index array, several times faster on large meshes. Both
//! give the same tree. The split itself (binning, the SAH, partitioning) is [`super::sah`].

use super::node::BvhNode;
use super::sah::{BIN_SETS, BinSets, UNUSED_SET, best_sah_split, partition, range_bounds};
use super::scratch::{
    Corner, Indexed, PrimRef, Refs, Scratch, centre2, corner, extend, point, scratch_capacity,
};
use super::{
    BvhError, DEFAULT_MAX_LEAF_SIZE, INTERSECTION_COST, MAX_DEPTH, MAX_PRIMITIVES, index_capacity,
    node_capacity,
};
use crate::aabb::Aabb;
use crate::error::{CapacityError, NonFiniteError, Storage};
use crate::mesh::PrimitiveSource;
use glam::Vec3;

/// Depth from which nodes are split by count rather than by SAH: `MAX_DEPTH − 32`, so that the
/// remaining 32 levels can halve any node of up to `2³¹` primitives down to one.
const MEDIAN_DEPTH: u32 = (MAX_DEPTH - 32) as u32;

/// Options of [`super::Bvh::build`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// Nodes with more primitives than this are always split while the depth limit allows;
    /// smaller nodes are split only when the SAH says it pays. Values below 1 count as 1.
    /// Default [`DEFAULT_MAX_LEAF_SIZE`].
    pub max_leaf_size: u32,
    /// `false` (default): a primitive with non-finite or empty bounds is an error
    /// ([`BvhError::NonFinite`]). `true`: such primitives are left out of the tree
    /// (no query ever reports them).
    pub exclude_non_finite: bool,
    /// Nodes of at most this many primitives become leaves without trying a split (capped
    /// at `max_leaf_size`; values below 1 count as 1), unless the node is so large against the
    /// root that a split spares [`LARGE_NODE_SAVING`] tests per ray. Default 1: the SAH
    /// decides for every node of two or more. A tree that will be collapsed into a wide one is built with
    /// [`LEAF_OPEN_ABOVE`](super::wide::LEAF_OPEN_ABOVE) here and as `max_leaf_size`
    /// ([`super::wide::binary_options`]): the collapse neither splits nor opens a subtree that
    /// small, so splitting it is wasted work.
    pub leaf_threshold: u32,
    /// SAH cost of one primitive test against a traversal step's 1
    /// ([`TRAVERSAL_COST`](super::TRAVERSAL_COST)); larger values give smaller leaves.
    /// Unitless. Default [`INTERSECTION_COST`]; a tree collapsed into a wide one uses
    /// [`WIDE_INTERSECTION_COST`](super::wide::WIDE_INTERSECTION_COST). A value that is not
    /// positive and finite counts as the default.
    pub intersection_cost: f32,
}

impl BuildOptions {
    /// [`BuildOptions::intersection_cost`], the default in place of a value that is not
    /// positive and finite.
    #[must_use]
    pub(super) fn primitive_cost(&self) -> f32 {
        let c = self.intersection_cost;
        if c > 0.0 && c.is_finite() {
            c
        } else {
            INTERSECTION_COST
        }
    }
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            max_leaf_size: DEFAULT_MAX_LEAF_SIZE,
            exclude_non_finite: false,
            leaf_threshold: 1,
            intersection_cost: INTERSECTION_COST,
        }
    }
}

/// A node waiting to be split: its index range, depth and centroid bounds (the box of its
/// primitives' [`centre2`] points, twice their centres; its own box is already written into
/// the node).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Task {
    pub(super) node: u32,
    pub(super) start: u32,
    pub(super) end: u32,
    pub(super) depth: u32,
    pub(super) centroids: Aabb,
    /// Surface area of the whole tree's box (the root's), the scale of
    /// [`split_spares_tests`].
    pub(super) root_area: f32,
}

pub(super) const EMPTY_TASK: Task = Task {
    node: 0,
    start: 0,
    end: 0,
    depth: 0,
    centroids: Aabb::EMPTY,
    root_area: 0.0,
};

/// The builder's working memory: the SAH bins of the three axes
/// ([`BIN_COUNT`](super::BIN_COUNT) each; two sets on x86-64, filled alternately) and the
/// stack of pending nodes (`MAX_DEPTH + 1` entries, one per level). About 4.1 KiB on a 32-bit
/// target. [`super::Bvh::build`] keeps one on its own
/// stack; [`super::Bvh::build_in`] takes the caller's, so that a firmware can place it where
/// it chooses (a `static`, a scratch buffer shared with other phases) instead of the stack.
/// Its contents between builds mean nothing.
#[derive(Clone)]
pub struct BuildWorkspace {
    tasks: [Task; MAX_DEPTH + 1],
    bins: BinSets,
}

impl BuildWorkspace {
    /// A workspace for any build.
    #[must_use]
    pub const fn new() -> Self {
        // All bits zero (a fresh workspace is a memset, not a copy of a constant): every task
        // is written before it is read, every bin in use is emptied before binning.
        const UNUSED_TASK: Task = Task {
            centroids: Aabb::new(Vec3::ZERO, Vec3::ZERO),
            ..EMPTY_TASK
        };
        Self {
            tasks: [UNUSED_TASK; MAX_DEPTH + 1],
            bins: [UNUSED_SET; BIN_SETS],
        }
    }
}

impl core::fmt::Debug for BuildWorkspace {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("BuildWorkspace")
    }
}

impl Default for BuildWorkspace {
    fn default() -> Self {
        Self::new()
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

/// Where the top of a split build leaves subtrees ([`super::jobs`] implements it): `take`
/// keeps a child task for later (true; its node then holds only its box) or leaves it to the
/// split loop (false).
pub(super) trait TaskSink {
    fn take(&mut self, task: &Task, max_leaf: u32) -> bool;
}

/// What the validating pass finds of a build's usable primitives: the root's contents.
#[derive(Clone, Copy, Debug)]
pub(super) struct Usable {
    /// How many there are.
    pub(super) count: u32,
    /// The union of their boxes ([`Aabb::EMPTY`] for none).
    pub(super) bounds: Aabb,
    /// The box of their [`centre2`] points (twice their boxes' centres).
    pub(super) centroids: Aabb,
}

/// The corners of `b` and the point it is binned by ([`centre2`]: twice its centre, infinite
/// beyond `±2¹²⁷`) when it can go into a tree (finite corners, `min ≤ max` on every axis;
/// the spare lane is 0 in all three), else `None`.
#[inline(always)]
fn usable_corners(b: &Aabb) -> Option<(Corner, Corner, Corner)> {
    let (lo, hi) = (corner(b.min), corner(b.max));
    (lo.is_finite() && hi.is_finite() && lo.cmple(hi).all()).then(|| (lo, hi, centre2(lo, hi)))
}

/// Checks the storage (`nodes` and `indices` entries) for the source's `n` primitives (`n`
/// read once by the caller, so that no index at or beyond it is ever asked for) and every
/// primitive (nothing written but what `usable` writes); calls `usable(k, i, bounds)` for the
/// `k`-th usable primitive `i`; returns what it found of the usable primitives, from the same
/// answers that `usable` was given.
#[inline(always)]
fn validate<S: PrimitiveSource + ?Sized>(
    source: &S,
    n: usize,
    (nodes, indices): (usize, usize),
    options: &BuildOptions,
    mut usable: impl FnMut(usize, usize, Aabb),
) -> Result<Usable, BvhError> {
    if n > MAX_PRIMITIVES {
        return Err(BvhError::TooManyPrimitives { count: n });
    }
    CapacityError::check(Storage::BvhNodes, node_capacity(n), nodes)?;
    CapacityError::check(Storage::BvhIndices, index_capacity(n), indices)?;
    // The root's box and centroid box in the builder's vector corners: the same values as
    // `Aabb::union` / `grow` lane by lane, and the box of the `centre2` points.
    let (mut lo, mut hi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    let (mut clo, mut chi) = (Corner::INFINITY, Corner::NEG_INFINITY);
    let mut count = 0u32;
    for i in 0..n {
        let b = source.primitive_bounds(i);
        if let Some((blo, bhi, c)) = usable_corners(&b) {
            lo = lo.min(blo);
            hi = hi.max(bhi);
            extend(&mut clo, &mut chi, c);
            usable(count as usize, i, b);
            count += 1;
        } else if !options.exclude_non_finite {
            return Err(NonFiniteError::primitive(i).into());
        }
    }
    Ok(Usable {
        count,
        bounds: Aabb::new(point(lo), point(hi)),
        centroids: Aabb::new(point(clo), point(chi)),
    })
}

/// Builds into `nodes`/`indices`; returns `(node_count, prim_count)`.
///
/// One pass over the source decides the primitives, the root's boxes and the index array
/// together, so they agree whatever a source answers on later calls ([`PrimitiveSource`]):
/// with [`BuildOptions::exclude_non_finite`] the pass writes the indices of the primitives
/// it finds usable as it goes (no error is possible then); without, it refuses before
/// writing, and having found every primitive usable the indices are `0..n`.
pub(super) fn build<S: PrimitiveSource + ?Sized>(
    source: &S,
    nodes: &mut [BvhNode],
    indices: &mut [u32],
    options: &BuildOptions,
    work: &mut BuildWorkspace,
) -> Result<(u32, u32), BvhError> {
    let n = source.primitive_count();
    let lens = (nodes.len(), indices.len());
    let root = if options.exclude_non_finite {
        validate(source, n, lens, options, |k, i, _| {
            if let Some(slot) = indices.get_mut(k) {
                *slot = i as u32;
            }
        })?
    } else {
        let root = validate(source, n, lens, options, |_, _, _| {})?;
        for (k, slot) in indices.iter_mut().take(root.count as usize).enumerate() {
            *slot = k as u32;
        }
        root
    };
    if root.count == 0 {
        return Ok((0, 0));
    }
    let mut refs = Indexed { source, indices };
    let node_count = build_top(&mut refs, nodes, &root, options, None, work);
    Ok((node_count, root.count))
}

/// [`build`] on a scratch array of [`PrimRef`]s (at least [`scratch_capacity`] entries, else
/// [`BvhError::Capacity`] before anything is written). The scratch's contents after the
/// call mean nothing.
#[inline(always)]
pub(super) fn build_with_scratch<S: PrimitiveSource + ?Sized>(
    source: &S,
    nodes: &mut [BvhNode],
    indices: &mut [u32],
    scratch: &mut [PrimRef],
    options: &BuildOptions,
) -> Result<(u32, u32), BvhError> {
    // One pass over the source: the records are written while validating (the scratch is
    // not output; nodes and indices are written only after the pass succeeds).
    let root = prepare_scratch(source, nodes, indices, scratch, options)?;
    if root.count == 0 {
        return Ok((0, 0));
    }
    let refs = scratch.get_mut(..root.count as usize).unwrap_or_default();
    let mut view = Scratch { refs, offset: 0 };
    let work = &mut const { BuildWorkspace::new() };
    let node_count = build_top(&mut view, nodes, &root, options, None, work);
    fill_indices(indices, view.refs);
    Ok((node_count, root.count))
}

/// `indices[k]` = the source index of record `k` (the final leaf order).
#[inline(always)]
pub(super) fn fill_indices(indices: &mut [u32], refs: &[PrimRef]) {
    for (slot, r) in indices.iter_mut().zip(refs) {
        *slot = r.index();
    }
}

/// Validates `source` and the storage, fills `scratch`: the first pass of
/// [`build_with_scratch`], for the split build. Returns what it found of the usable
/// primitives.
#[inline(always)]
pub(super) fn prepare_scratch<S: PrimitiveSource + ?Sized>(
    source: &S,
    nodes: &[BvhNode],
    indices: &[u32],
    scratch: &mut [PrimRef],
    options: &BuildOptions,
) -> Result<Usable, BvhError> {
    let n = source.primitive_count();
    CapacityError::check(Storage::BvhScratch, scratch_capacity(n), scratch.len())?;
    validate(
        source,
        n,
        (nodes.len(), indices.len()),
        options,
        |k, i, bounds| {
            if let Some(slot) = scratch.get_mut(k) {
                *slot = PrimRef::new(&bounds, i as u32);
            }
        },
    )
}

/// The top of every build: the root, the optional cache-line pad, then [`grow`] from the
/// root (leaving subtrees to `jobs` when given) over the `root` primitives of `refs`.
/// Returns the next free node index.
#[inline(always)]
pub(super) fn build_top<R: Refs>(
    refs: &mut R,
    nodes: &mut [BvhNode],
    root: &Usable,
    options: &BuildOptions,
    jobs: Option<&mut dyn TaskSink>,
    work: &mut BuildWorkspace,
) -> u32 {
    let mut node_count = 1u32;
    if let Some(node) = nodes.first_mut() {
        node.set_bounds(&root.bounds);
    }
    // Sibling pairs are allocated two by two after the root. When the storage has a spare slot,
    // start them at a 64-byte boundary (skipping node 1, left empty) so that the two boxes a
    // traversal step reads share one cache line. Only speed depends on this.
    let base_is_64_aligned = (nodes.as_ptr() as usize).is_multiple_of(64);
    if base_is_64_aligned && nodes.len() > node_capacity(root.count as usize) {
        if let Some(pad) = nodes.get_mut(1) {
            *pad = BvhNode::EMPTY;
        }
        node_count = 2;
    }
    let task = Task {
        node: 0,
        start: 0,
        end: root.count,
        depth: 0,
        centroids: root.centroids,
        root_area: root.bounds.surface_area(),
    };
    let mut view = NodeView {
        nodes,
        base: 0,
        root: None,
    };
    grow(refs, &mut view, task, &mut node_count, options, jobs, work);
    node_count
}

/// The split loop shared by all builders: splits `task`'s node and its descendants, allocating
/// node pairs from `*next` on (global indices of `view`). A child task that `jobs` takes is
/// left for later (its node holds its box).
#[inline(always)]
pub(super) fn grow<R: Refs>(
    refs: &mut R,
    view: &mut NodeView<'_>,
    task: Task,
    next: &mut u32,
    options: &BuildOptions,
    mut jobs: Option<&mut dyn TaskSink>,
    work: &mut BuildWorkspace,
) {
    let max_leaf = options.max_leaf_size.max(1);
    let threshold = options.leaf_threshold.clamp(1, max_leaf);
    let BuildWorkspace { tasks: stack, bins } = work;
    let mut sp = 0usize;
    let mut task = task;
    loop {
        let mut pending = split_node(
            refs,
            view,
            &task,
            (max_leaf, threshold, options.primitive_cost()),
            next,
            bins,
        );
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

/// Primitive tests per ray that splitting a node of at most
/// [`BuildOptions::leaf_threshold`] primitives must spare for the split to be made anyway
/// (and the wide tree's collapse to open such a leaf run): a ray that enters the root's box
/// meets a node of surface area `A` with probability about `A / A_root` (uniformly spread
/// rays), so a leaf of `n` primitives costs it `n·A / A_root` tests on average and its two
/// halves `(n_L·A_L + n_R·A_R) / A_root`. Unitless (tests per ray). A small node of an ordinary
/// mesh is thousands of times smaller than the root and spares far less; this catches the
/// few huge primitives at the top of a tree (a room's walls, each 10⁴ times the object in
/// it: one leaf of three walls, the whole room's box, cost every ray six tests;
/// `docs/performance.md`).
pub const LARGE_NODE_SAVING: f32 = 0.5;

/// `true` when splitting a node of `count` primitives and surface area `area` into halves
/// whose `count·area` sum to `halves` spares a ray entering the root's box (surface area
/// `root_area`) at least [`LARGE_NODE_SAVING`] primitive tests on average. `false` for a root
/// without area or any non-finite input.
#[must_use]
pub(crate) fn split_spares_tests(count: usize, area: f32, halves: f32, root_area: f32) -> bool {
    root_area > 0.0 && count as f32 * area - halves >= LARGE_NODE_SAVING * root_area
}

/// Splits `task`'s node in two, writing the parent and both children's boxes, or makes it a
/// leaf (returns `None`). `(max_leaf, threshold, cost)`: larger nodes are always split, nodes
/// of at most `threshold` only when the split [spares enough tests](split_spares_tests);
/// `cost` is the SAH's primitive cost.
#[inline(always)]
fn split_node<R: Refs>(
    refs: &mut R,
    nodes: &mut NodeView<'_>,
    task: &Task,
    (max_leaf, threshold, cost): (u32, u32, f32),
    node_count: &mut u32,
    bins: &mut BinSets,
) -> Option<(Task, Task)> {
    let count = task.end - task.start;
    let parent_bounds = nodes.bounds(task.node)?;
    let area = parent_bounds.surface_area();
    // A node of at most `threshold` is a leaf unless it is large enough that a split could
    // spare LARGE_NODE_SAVING tests (`halves` = 0 bounds every split's saving).
    let small = count <= threshold;
    if (small && !(count >= 2 && split_spares_tests(count as usize, area, 0.0, task.root_area)))
        || task.depth as usize >= MAX_DEPTH
        || !nodes.has_pair(*node_count)
    {
        make_leaf(nodes, task);
        return None;
    }
    let range = task.start as usize..task.end as usize;
    let split = best_sah_split(refs, bins, range.clone(), &task.centroids, area, cost);
    let leaf_cost = cost * count as f32 * area;
    // Deep in the tree, split by count: from MEDIAN_DEPTH on every split halves the node, so
    // no node reaches MAX_DEPTH with more than `max_leaf` primitives (N < 2³¹ halves to one in
    // 31 levels) and leaves never exceed the requested size.
    let split = split.filter(|_| task.depth < MEDIAN_DEPTH);
    // The split's `n_L·A_L + n_R·A_R` (its SAH numerator without the traversal term).
    let pays = |s: &super::sah::Split| {
        if small {
            let halves = (s.cost - super::TRAVERSAL_COST * area) / cost;
            split_spares_tests(count as usize, area, halves, task.root_area)
        } else {
            s.cost < leaf_cost || count > max_leaf
        }
    };
    let partitioned = match split {
        Some(s) if pays(&s) => {
            let (mid, lc, rc) = partition(refs, range.clone(), &s);
            // A half is empty only when the source's bounds changed between the binning and
            // the partition (a source that breaks `PrimitiveSource`'s contract): then as if no
            // split were found, so that no leaf is empty (a leaf of 0 would read as an inner
            // node) and the tree stays well formed.
            (mid > 0 && mid < count).then_some((task.start + mid, s.left, s.right, lc, rc))
        }
        _ => None,
    };
    let (mid, left_b, right_b, left_c, right_c) = match partitioned {
        Some(p) => p,
        None if count > max_leaf => {
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
            root_area: task.root_area,
        },
        Task {
            node: first + 1,
            start: mid,
            end: task.end,
            depth,
            centroids: right_c,
            root_area: task.root_area,
        },
    ))
}
