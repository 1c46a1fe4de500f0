//! The binned-SAH build split into independent subtree jobs, for callers that have threads
//! (the core has none): [`Bvh::build_in_jobs`] builds the top of the tree, hands the caller
//! one [`JobPart`] per subtree (disjoint storage, so the parts can be built at once on
//! several threads), then joins them into one tree **equal to
//! [`Bvh::build_with_scratch`]'s** (the same splits of the same records; only the node
//! numbering differs), without gaps.
//!
//! Storage: the same as [`Bvh::build_with_scratch`] plus a caller slice of [`BuildJob`]s
//! (a few per thread: the top stops handing out jobs when it is full). Node slots: a job of
//! `c` primitives is reserved `2c − 2` nodes (the most its subtree can use) after the top's;
//! the join moves each job's nodes down to close the unused part of its reservation, so the
//! tree needs no more than [`super::node_capacity`] nodes, as the plain build.

use super::build::{
    BuildWorkspace, EMPTY_TASK, NodeView, Task, TaskSink, build_top, fill_indices, grow,
    prepare_scratch,
};
use super::scratch::Scratch;
use super::{BuildOptions, Bvh, BvhError, BvhNode, PrimRef};
use crate::mesh::PrimitiveSource;

/// One subtree of a split build: its task, its node reservation and, once built, the nodes it
/// used and the final record of its root. Opaque; storage for [`Bvh::build_in_jobs`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildJob {
    task: Task,
    base: u32,
    reserved: u32,
    used: u32,
    done: bool,
    root: BvhNode,
}

impl BuildJob {
    /// A free slot, for initialising storage: `[BuildJob::EMPTY; K]`.
    pub const EMPTY: Self = Self {
        task: EMPTY_TASK,
        base: 0,
        reserved: 0,
        used: 0,
        done: false,
        root: BvhNode::EMPTY,
    };

    /// Primitives in the subtree (its work, for scheduling).
    #[must_use]
    pub fn primitives(&self) -> usize {
        (self.task.end - self.task.start) as usize
    }
}

impl BuildJob {
    /// A job for `task`, not yet placed.
    fn new(task: Task) -> Self {
        Self {
            task,
            ..Self::EMPTY
        }
    }
}

impl Default for BuildJob {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Where the top of a split build leaves subtrees: a child task of at most `job_size`
/// primitives (and more than a leaf's) becomes a job while there is room.
struct JobSink<'a> {
    jobs: &'a mut [BuildJob],
    len: usize,
    job_size: u32,
}

impl TaskSink for JobSink<'_> {
    fn take(&mut self, task: &Task, max_leaf: u32) -> bool {
        let n = task.end - task.start;
        if n <= max_leaf || n > self.job_size {
            return false;
        }
        match self.jobs.get_mut(self.len) {
            Some(slot) => {
                *slot = BuildJob::new(*task);
                self.len += 1;
                true
            }
            None => false,
        }
    }
}

/// One job with the storage it alone writes: its node reservation and its records. `Send`:
/// build parts on any threads, in any order.
#[derive(Debug)]
pub struct JobPart<'a> {
    job: &'a mut BuildJob,
    nodes: &'a mut [BvhNode],
    refs: &'a mut [PrimRef],
    options: BuildOptions,
}

impl JobPart<'_> {
    /// Primitives in the subtree.
    #[must_use]
    pub fn primitives(&self) -> usize {
        self.job.primitives()
    }

    /// Builds the subtree (the same splits [`Bvh::build_with_scratch`] makes there). Inlined
    /// down to the per-primitive loops, like [`Bvh::build_with_scratch`], so that a caller's
    /// `#[target_feature]` function compiles them with its features.
    #[inline(always)]
    pub fn build(self) {
        build_job(self.job, self.nodes, self.refs, &self.options);
    }
}

#[inline(always)]
fn build_job(
    job: &mut BuildJob,
    nodes: &mut [BvhNode],
    refs: &mut [PrimRef],
    options: &BuildOptions,
) {
    let mut scratch = Scratch {
        refs,
        offset: job.task.start as usize,
    };
    let mut next = job.base;
    let mut view = NodeView {
        nodes,
        base: job.base,
        root: Some((job.task.node, &mut job.root)),
    };
    grow(
        &mut scratch,
        &mut view,
        job.task,
        &mut next,
        options,
        None,
        &mut const { BuildWorkspace::new() },
    );
    job.used = next - job.base;
    job.done = true;
}

/// The parts of a split build, in primitive order (an iterator: collect them to hand them to
/// a thread pool).
#[derive(Debug)]
pub struct JobParts<'a> {
    jobs: core::slice::IterMut<'a, BuildJob>,
    nodes: &'a mut [BvhNode],
    node_base: u32,
    refs: &'a mut [PrimRef],
    ref_base: usize,
    options: BuildOptions,
}

impl<'a> JobParts<'a> {
    /// The parts of `jobs` (sorted by first record, their node reservations set) over the
    /// nodes after the top's `top_nodes` in `nodes` and the first `count` records of
    /// `scratch`.
    fn new(
        jobs: &'a mut [BuildJob],
        nodes: &'a mut [BvhNode],
        top_nodes: u32,
        scratch: &'a mut [PrimRef],
        count: u32,
        options: BuildOptions,
    ) -> Self {
        Self {
            jobs: jobs.iter_mut(),
            nodes: nodes.get_mut(top_nodes as usize..).unwrap_or_default(),
            node_base: top_nodes,
            refs: scratch.get_mut(..count as usize).unwrap_or_default(),
            ref_base: 0,
            options,
        }
    }
}

impl<'a> Iterator for JobParts<'a> {
    type Item = JobPart<'a>;

    fn next(&mut self) -> Option<JobPart<'a>> {
        let job = self.jobs.next()?;
        // Jobs are sorted by node base and by first record, both disjoint: split the front off.
        let skip_nodes = (job.base - self.node_base) as usize;
        let nodes = core::mem::take(&mut self.nodes);
        let (_, rest) = nodes.split_at_mut(skip_nodes.min(nodes.len()));
        let (mine, rest) = rest.split_at_mut((job.reserved as usize).min(rest.len()));
        self.nodes = rest;
        self.node_base = job.base + job.reserved;
        let skip_refs = job.task.start as usize - self.ref_base;
        let refs = core::mem::take(&mut self.refs);
        let (_, rest) = refs.split_at_mut(skip_refs.min(refs.len()));
        let (my_refs, rest) = rest.split_at_mut(job.primitives().min(rest.len()));
        self.refs = rest;
        self.ref_base = job.task.end as usize;
        Some(JobPart {
            job,
            nodes: mine,
            refs: my_refs,
            options: self.options,
        })
    }
}

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]> + AsMut<[BvhNode]>,
    I: AsRef<[u32]> + AsMut<[u32]>,
{
    /// [`Bvh::build_with_scratch`] in pieces: the top of the tree is split here until the
    /// nodes left have at most `job_size` primitives (and more than a leaf's) or `jobs` is
    /// full; `run` gets those subtrees as [`JobPart`]s and builds them (on any threads; a part
    /// it drops is built here afterwards); then the parts are joined into one tree, the same
    /// tree as [`Bvh::build_with_scratch`]'s with another node numbering.
    ///
    /// `job_size = 0` or an empty `jobs` builds everything here.
    ///
    /// # Errors
    ///
    /// As [`Bvh::build_with_scratch`], all returned before `run` is called and before `nodes` or
    /// `indices` are written.
    // The storage of `build_with_scratch`, the job slots and their size, and the runner.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn build_in_jobs<S: PrimitiveSource + ?Sized>(
        source: &S,
        mut nodes: N,
        mut indices: I,
        scratch: &mut [PrimRef],
        jobs: &mut [BuildJob],
        job_size: usize,
        options: &BuildOptions,
        run: impl FnOnce(JobParts<'_>),
    ) -> Result<Self, BvhError> {
        let root = prepare_scratch(source, nodes.as_ref(), indices.as_ref(), scratch, options)?;
        let count = root.count;
        let source_len = source.primitive_count();
        let node_slice = nodes.as_mut();
        if count == 0 {
            return Ok(Self::assemble(nodes, indices, 0, 0, source_len));
        }
        let job_size = u32::try_from(job_size).unwrap_or(u32::MAX);
        let mut sink = JobSink {
            jobs,
            len: 0,
            job_size,
        };
        let top_nodes = build_top(
            &mut Scratch {
                refs: scratch.get_mut(..count as usize).unwrap_or_default(),
                offset: 0,
            },
            node_slice,
            &root,
            options,
            Some(&mut sink),
            &mut const { BuildWorkspace::new() },
        );
        let jobs = sink.jobs.get_mut(..sink.len).unwrap_or_default();
        // Primitive order (the top meets a right child before its left sibling's descendants),
        // then the reservations in that order, and each root's record as the top left it.
        jobs.sort_unstable_by_key(|j| j.task.start);
        let mut base = top_nodes;
        for job in jobs.iter_mut() {
            job.base = base;
            job.reserved = 2 * (job.task.end - job.task.start) - 2;
            base += job.reserved;
            job.root = node_slice
                .get(job.task.node as usize)
                .copied()
                .unwrap_or(BvhNode::EMPTY);
        }

        run(JobParts::new(
            jobs, node_slice, top_nodes, scratch, count, *options,
        ));

        // Jobs the caller did not build, then the join.
        for part in JobParts::new(jobs, node_slice, top_nodes, scratch, count, *options) {
            if !part.job.done {
                part.build();
            }
        }
        let node_count = join(node_slice, top_nodes, jobs);
        fill_indices(
            indices.as_mut(),
            scratch.get(..count as usize).unwrap_or_default(),
        );
        Ok(Self::assemble(
            nodes, indices, node_count, count, source_len,
        ))
    }
}

/// Moves every job's nodes down to follow the previous job's (closing the unused part of each
/// reservation), renumbers their child references, writes each job's root record; returns
/// the node count.
fn join(nodes: &mut [BvhNode], top_nodes: u32, jobs: &[BuildJob]) -> u32 {
    let mut next = top_nodes;
    for job in jobs {
        let shift = job.base - next;
        let (from, used) = (job.base as usize, job.used as usize);
        if shift > 0 && from + used <= nodes.len() {
            nodes.copy_within(from..from + used, next as usize);
        }
        let renumber = |n: &mut BvhNode| {
            if let Some((first, _)) = n.children()
                && first >= job.base
            {
                n.set_inner(first - shift);
            }
        };
        for n in nodes
            .get_mut(next as usize..next as usize + used)
            .unwrap_or_default()
        {
            renumber(n);
        }
        let mut root = job.root;
        renumber(&mut root);
        if let Some(slot) = nodes.get_mut(job.task.node as usize) {
            *slot = root;
        }
        next += job.used;
    }
    next
}
