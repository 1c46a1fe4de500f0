//! Construction into caller storage: no allocation, no recursion.
//!
//! The references of the nodes still to be split live in the caller's scratch array as a
//! stack of contiguous runs, the run of the node being split on top. A split reorders the run
//! into `[above only | both | below only]` ([`super::sah::partition`]) and appends a copy of
//! the `both` records after it: the child above is then `[above only | both]`, the child below
//! `[below only | both (copy)]`, each record's box clipped to its child's cell (box–cell
//! intersection; exact in `f32`, as it only takes minima and maxima). The child below is split
//! next, the one above waits on the task stack (one entry per level). A leaf copies its
//! records' primitive indices to the reference array and frees its run.
//!
//! **Budgets.** A node's children hold at least as many references as the node, so the runs
//! in the scratch plus the references already written to leaves never exceed the final
//! reference count. A split that would make that count exceed the budget
//! `min(references.len(), scratch.len())` is not made (the node becomes a leaf), and neither
//! is one for which no pair of nodes is left in the node storage; [`super::KdTree::budget_exhausted`]
//! reports either.

use super::kdref::KdRef;
use super::node::{KdNode, MAX_FIELD};
use super::sah::{Costs, Split, best_split, count_sides, partition};
use super::{KdBuildOptions, KdTreeError, MAX_DEPTH, MAX_PRIMITIVES};
use crate::aabb::Aabb;
use crate::error::{CapacityError, NonFiniteError, Storage};
use crate::mesh::PrimitiveSource;

/// A node waiting to be split or made a leaf: its scratch run `start..end`, depth and cell.
#[derive(Clone, Copy, Debug)]
struct Task {
    node: u32,
    start: u32,
    end: u32,
    depth: u32,
    cell: Aabb,
}

const EMPTY_TASK: Task = Task {
    node: 0,
    start: 0,
    end: 0,
    depth: 0,
    cell: Aabb::EMPTY,
};

/// What a build produced.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Built {
    pub(super) node_count: u32,
    pub(super) ref_count: u32,
    pub(super) prim_count: u32,
    pub(super) bounds: Option<Aabb>,
    pub(super) depth: u32,
    pub(super) exhausted: bool,
}

/// The state of one build: the caller's storage and the counters.
struct Builder<'a> {
    nodes: &'a mut [KdNode],
    refs: &'a mut [u32],
    scratch: &'a mut [KdRef],
    /// Nodes allocated so far.
    next: u32,
    /// References written to leaves so far.
    written: u32,
    /// Largest node count and reference count allowed.
    node_budget: u32,
    ref_budget: u32,
    depth_limit: u32,
    max_leaf: u32,
    costs: Costs,
    deepest: u32,
    exhausted: bool,
}

/// `true` when `b` can go into a tree: finite and non-empty.
fn usable(b: &Aabb) -> bool {
    b.is_finite() && b.is_valid()
}

/// Checks storage for the source's `n` primitives (`n` read once by the caller: no later pass
/// asks for an index at or beyond it) and, unless unusable primitives are excluded, every
/// primitive (writing nothing).
fn validate<S: PrimitiveSource + ?Sized>(
    source: &S,
    n: usize,
    nodes: &[KdNode],
    refs: &[u32],
    scratch: &[KdRef],
    options: &KdBuildOptions,
) -> Result<(), KdTreeError> {
    if n > MAX_PRIMITIVES {
        return Err(KdTreeError::TooManyPrimitives { count: n });
    }
    CapacityError::check(Storage::KdNodes, usize::from(n > 0), nodes.len())?;
    CapacityError::check(Storage::KdReferences, n, refs.len())?;
    CapacityError::check(Storage::KdScratch, n, scratch.len())?;
    if !options.exclude_non_finite
        && let Some(i) = (0..n).find(|&i| !usable(&source.primitive_bounds(i)))
    {
        return Err(KdTreeError::NonFinite(NonFiniteError::primitive(i)));
    }
    Ok(())
}

/// Writes a scratch record for each usable primitive of `0..n` (at most `n ≤ scratch.len()`
/// of them); returns their count and box, from the same answers as the records.
fn gather<S: PrimitiveSource + ?Sized>(source: &S, n: usize, scratch: &mut [KdRef]) -> (u32, Aabb) {
    let mut bounds = Aabb::EMPTY;
    let mut count = 0u32;
    for i in 0..n {
        let b = source.primitive_bounds(i);
        let Some(slot) = scratch.get_mut(count as usize) else {
            break;
        };
        if !usable(&b) {
            continue;
        }
        *slot = KdRef {
            min: b.min.to_array(),
            max: b.max.to_array(),
            prim: i as u32,
        };
        bounds = bounds.union(b);
        count += 1;
    }
    (count, bounds)
}

/// Builds into the storage; see the module docs.
///
/// The pass that writes the scratch records also decides which primitives the tree holds and
/// the root's box, so the three agree whatever a source answers on later calls
/// ([`PrimitiveSource`]): a primitive that [`validate`] found usable and whose bounds are
/// unusable by then is left out, as if excluded.
pub(super) fn build<S: PrimitiveSource + ?Sized>(
    source: &S,
    nodes: &mut [KdNode],
    refs: &mut [u32],
    scratch: &mut [KdRef],
    options: &KdBuildOptions,
) -> Result<Built, KdTreeError> {
    let n = source.primitive_count();
    validate(source, n, nodes, refs, scratch, options)?;
    let (count, bounds) = gather(source, n, scratch);
    if count == 0 {
        return Ok(Built::default());
    }
    let ref_budget = refs.len().min(scratch.len()).min(u32::MAX as usize) as u32;
    let node_budget = nodes.len().min(MAX_FIELD as usize + 1) as u32;
    let mut b = Builder {
        nodes,
        refs,
        scratch,
        next: 1,
        written: 0,
        node_budget,
        ref_budget,
        depth_limit: options.depth_limit(count as usize),
        max_leaf: options.max_leaf_size.max(1),
        costs: options.costs(),
        deepest: 0,
        exhausted: false,
    };
    b.run(Task {
        node: 0,
        start: 0,
        end: count,
        depth: 0,
        cell: bounds,
    });
    Ok(Built {
        node_count: b.next,
        ref_count: b.written,
        prim_count: count,
        bounds: Some(bounds),
        depth: b.deepest,
        exhausted: b.exhausted,
    })
}

impl Builder<'_> {
    /// The split loop: depth first, the child below first, the one above on the task stack.
    fn run(&mut self, root: Task) {
        // Proof that the stack suffices: a task is pushed only by a split, which happens only
        // at depth < depth_limit ≤ MAX_DEPTH, and the pending tasks are the "above" children of
        // the current task's ancestors, at most one per level 1..=depth_limit.
        let mut stack = [EMPTY_TASK; MAX_DEPTH + 1];
        let mut sp = 0usize;
        let mut task = root;
        loop {
            self.deepest = self.deepest.max(task.depth);
            match self.split(&task) {
                Some((below, above)) => {
                    if let Some(slot) = stack.get_mut(sp) {
                        *slot = above;
                        sp += 1;
                    } else {
                        // Unreachable by the proof above; finish the child as a leaf.
                        self.leaf(&above);
                    }
                    task = below;
                }
                None => {
                    self.leaf(&task);
                    if sp == 0 {
                        break;
                    }
                    sp -= 1;
                    task = stack[sp];
                }
            }
        }
    }

    /// Writes `task`'s node as a leaf over its run's primitives.
    fn leaf(&mut self, task: &Task) {
        let run = self
            .scratch
            .get(task.start as usize..task.end as usize)
            .unwrap_or(&[]);
        let start = self.written;
        for r in run {
            if let Some(slot) = self.refs.get_mut(self.written as usize) {
                *slot = r.prim;
                self.written += 1;
            }
        }
        if let Some(node) = self.nodes.get_mut(task.node as usize) {
            *node = KdNode::leaf(start, self.written - start);
        }
    }

    /// Splits `task`'s node when the SAH says it pays and the budgets allow, writing the inner
    /// node and preparing both children's runs; `None` when the node is to be a leaf.
    fn split(&mut self, task: &Task) -> Option<(Task, Task)> {
        let n = task.end - task.start;
        if n <= self.max_leaf || task.depth >= self.depth_limit {
            return None;
        }
        let (start, end) = (task.start as usize, task.end as usize);
        let run = self.scratch.get(start..end)?;
        let split = best_split(run, &task.cell, &self.costs)?;
        if !(split.cost < self.costs.intersection * f64::from(n)) {
            return None;
        }
        let (_, both, above_only) = count_sides(run, &split);
        let grown = u64::from(self.written) + u64::from(task.end) + u64::from(both);
        if grown > u64::from(self.ref_budget) || self.next > self.node_budget.saturating_sub(2) {
            self.exhausted = true;
            return None;
        }
        self.partition(task, &split, both, above_only)
    }

    /// Reorders the run, copies and clips the straddling records, writes the inner node.
    fn partition(
        &mut self,
        task: &Task,
        split: &Split,
        both: u32,
        above_only: u32,
    ) -> Option<(Task, Task)> {
        let (start, end) = (task.start as usize, task.end as usize);
        partition(self.scratch.get_mut(start..end)?, split);
        let both_at = start + above_only as usize;
        let copy_end = end + both as usize;
        if copy_end > self.scratch.len() {
            return None;
        }
        self.scratch
            .copy_within(both_at..both_at + both as usize, end);
        let (axis, s) = (split.axis, split.position);
        for r in self.scratch.get_mut(both_at..both_at + both as usize)? {
            r.min[axis] = r.min[axis].max(s);
        }
        for r in self.scratch.get_mut(end..copy_end)? {
            r.max[axis] = r.max[axis].min(s);
        }
        let first = self.next;
        self.next += 2;
        *self.nodes.get_mut(task.node as usize)? = KdNode::inner(axis, s, first);
        let (mut below_cell, mut above_cell) = (task.cell, task.cell);
        below_cell.max[axis] = s;
        above_cell.min[axis] = s;
        let depth = task.depth + 1;
        let mid = (both_at + both as usize) as u32;
        Some((
            Task {
                node: first,
                start: mid,
                end: copy_end as u32,
                depth,
                cell: below_cell,
            },
            Task {
                node: first + 1,
                start: task.start,
                end: mid,
                depth,
                cell: above_cell,
            },
        ))
    }
}
