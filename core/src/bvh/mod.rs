//! A binned-SAH bounding volume hierarchy built into **caller storage** and traversed with a
//! **fixed-size stack**: no allocation, no recursion, no panics.
//!
//! # Overview
//!
//! * Primitives come from a [`PrimitiveSource`] (`N` primitives by index and their bounds,
//!   [`crate::mesh`]).
//!   [`TriangleMesh`](crate::mesh::TriangleMesh) is the main one; any slice of [`Primitive`]s (for example `[Aabb]` or
//!   `[[Vec3; 3]]`) is one too, so spheres, quadrics and instances can live in a BVH: the
//!   intersection itself is supplied at query time as a closure.
//! * [`Bvh::build`] writes into node storage and primitive-index storage that the caller
//!   passes in: anything `AsRef + AsMut` of a slice (arrays, `&mut [T]`, `Vec`s,
//!   `heapless::Vec`s). The capacity is the slice's **length**, not a `Vec`'s capacity: fill
//!   the storage first (`[BvhNode::EMPTY; K]`, `vec![BvhNode::EMPTY; n]`,
//!   `heapless::Vec::from_array([BvhNode::EMPTY; K])`); an empty `Vec::with_capacity(n)` or
//!   `heapless::Vec::new()` holds no slot and is refused ("0 available"). Reserve
//!   [`node_capacity`]`(N)` nodes and [`index_capacity`]`(N)` indices. Too little storage is
//!   a typed error returned **before anything is written**.
//! * Queries: those of every structure ([`RayQuery`](crate::query::RayQuery): closest hit,
//!   any hit, box query, clearance), with the primitive test supplied as a
//!   [`LeafTest`](crate::query::LeafTest) (a closure, or
//!   [`Triangles`](crate::query::Triangles) over a mesh).
//! * [`Bvh::refit`] recomputes every box after the primitives moved, without a rebuild.
//!
//! # Construction (binned SAH)
//!
//! Each node's primitives are binned by the centre of their box into `4 + N/8` bins (at most
//! [`BIN_COUNT`]) along each axis whose
//! centroid extent is non-zero, and the split minimising the surface-area heuristic
//!
//! `cost = TRAVERSAL_COST + INTERSECTION_COST · (A_L·N_L + A_R·N_R) / A`
//!
//! is taken if it beats the leaf cost `INTERSECTION_COST · N` (or the node holds more than
//! [`BuildOptions::max_leaf_size`] primitives). When every centroid coincides (no axis can be
//! binned) a node with too many primitives is split by **count** (first half / second half of
//! its index range); so is every node at depth `MAX_DEPTH − 32` or more, which halves any node
//! to at most `max_leaf_size` primitives before depth [`MAX_DEPTH`] (`N < 2³¹`). Nodes at
//! depth `MAX_DEPTH` are leaves, which is what bounds the traversal stack: see below. Degenerate inputs — 10⁵ coincident triangles,
//! zero-area triangles, points — build and traverse correctly.
//!
//! Primitives whose bounds are not finite (NaN or infinite vertices, out-of-range vertex
//! indices in a [`TriangleMesh`](crate::mesh::TriangleMesh)) are an error naming the primitive
//! ([`BvhError::NonFinite`]) or, with [`BuildOptions::exclude_non_finite`], left out of
//! the tree. Empty input gives a valid empty BVH that hits nothing.
//!
//! # Layout and size
//!
//! A [`BvhNode`] is **32 bytes** (`min: [f32; 3]`, one `u32`, `max: [f32; 3]`, one `u32`;
//! 32-byte aligned so a node never straddles a cache line). The two children of an inner node
//! are adjacent. A leaf refers to a run of the index array. The whole structure takes
//! `32·nodes + 4·N` bytes; with leaves of one primitive that is at most `32·(2N − 1) + 4N < 68`
//! bytes per primitive; with the default SAH leaves (about two triangles each) it is about 39 bytes
//! per triangle (bunny 38.5, dragon 39.3)
//! ([`RayQuery::bytes_per_triangle`](crate::query::RayQuery::bytes_per_triangle)). The vertex and triangle arrays are the caller's and are
//! not counted.
//!
//! # Traversal
//!
//! Closest hit shrinks `t_max` to each accepted hit; boxes are tested with the robust,
//! conservative, NaN-absorbing slab test ([`Aabb::intersect_slab`]) over the closed interval
//! `[t_min, t_max·(1 + CULL_REL_SLACK)]`, the nearer child is visited first (ties: the first
//! child) and the farther one is pushed with its entry distance, which is re-checked when it is
//! popped. **Tie rule:** of two primitives reporting the same `t`, the one with the **smaller
//! primitive index** is returned, so the result does not depend on the tree's shape and equals
//! a brute-force loop over all primitives with the same rule. Invalid rays ([`Ray::validate`])
//! return no hit without testing any node.
//!
//! **Stack bound:** the stack holds [`TRAVERSAL_STACK_SIZE`] = 64 entries of 8 bytes (node
//! index, entry distance): 512 bytes. At most one entry is pushed per inner node on the path
//! from the root, and the builder never creates an inner node at depth ≥ [`MAX_DEPTH`] = 64, so
//! at most 64 entries are ever live. Traversal never overflows the stack and never recurses.
//!
//! [`Aabb::intersect_slab`]: crate::aabb::Aabb::intersect_slab
//! [`Primitive`]: crate::mesh::Primitive
//! [`Ray::validate`]: crate::ray::Ray::validate

mod baked;
mod build;
pub mod collide;
mod error;
mod jobs;
mod load;
mod node;
mod padded_ray;
mod query;
mod refit;
mod sah;
mod scratch;
pub(crate) mod stats;
mod traverse;
pub mod wide;

#[cfg(test)]
mod tests;

pub use baked::{
    BAKED_ALIGN, BAKED_HEADER_BYTES, BAKED_MAGIC, BAKED_VERSION, BakedError, BakedLayout,
};
pub use build::{BuildOptions, BuildWorkspace, LARGE_NODE_SAVING};
pub use error::BvhError;
pub use jobs::{BuildJob, JobPart, JobParts};
pub use load::{LoadError, load_scratch_len};
pub use node::{BvhNode, NODE_SIZE};
pub use scratch::{PrimRef, scratch_capacity};
pub use stats::BvhStats;

use crate::aabb::Aabb;
use crate::getters::{count_getters, getters};
use crate::mesh::PrimitiveSource;

/// Number of centroid bins per axis of the binned SAH, for nodes of 96 primitives or more (a
/// node of `N` fewer uses `4 + N/8`). 16 is within a fraction of a percent of a full sweep's
/// tree quality on scanned meshes and keeps the builder's bin arrays at about 1.3 KiB of stack on a
/// microcontroller (3 axes × 16 bins × 28 bytes; on x86-64 two sets of 48-byte bins, filled
/// alternately).
pub const BIN_COUNT: usize = 16;

/// SAH cost of visiting an inner node (testing its two child boxes), in units where one
/// primitive test costs [`INTERSECTION_COST`]. Unitless.
pub const TRAVERSAL_COST: f32 = 1.0;

/// SAH cost of one primitive intersection test. Unitless. The watertight triangle test (exact
/// `f64` edge functions) costs about as much as two box tests, hence 1.0 against a traversal
/// step (two boxes) of 1.0 gives leaves of a few triangles.
pub const INTERSECTION_COST: f32 = 1.0;

/// Default [`BuildOptions::max_leaf_size`]: nodes with more primitives are always split (when
/// the depth limit allows), smaller ones only when the SAH says a split pays.
pub const DEFAULT_MAX_LEAF_SIZE: u32 = 4;

/// Depth of the deepest possible node (the root has depth 0). Nodes at this depth become leaves
/// whatever their primitive count; it bounds the traversal stack (see the module docs).
pub const MAX_DEPTH: usize = 64;

/// Entries of the fixed traversal stack (node index `u32` + entry distance `f32`, 8 bytes
/// each). Equal to [`MAX_DEPTH`]: one entry per inner node on the path from the root.
pub const TRAVERSAL_STACK_SIZE: usize = MAX_DEPTH;

/// Nodes to reserve for `prim_count` primitives: `2·N − 1` (a binary tree whose every leaf
/// holds at least one primitive), `0` for no primitives. Saturates instead of overflowing.
#[must_use]
pub const fn node_capacity(prim_count: usize) -> usize {
    if prim_count == 0 {
        0
    } else {
        prim_count.saturating_mul(2).saturating_sub(1)
    }
}

/// Primitive indices to reserve for `prim_count` primitives: `N`.
#[must_use]
pub const fn index_capacity(prim_count: usize) -> usize {
    prim_count
}

/// Largest number of primitives a BVH can index: node indices are `u32`, and
/// [`node_capacity`] of it must fit.
pub const MAX_PRIMITIVES: usize = (u32::MAX / 2) as usize;

/// A BVH over caller storage `N` (nodes) and `I` (primitive indices).
///
/// Typical storage: `Vec<BvhNode>` / `Vec<u32>` in a std program, `&mut [BvhNode]` /
/// `&mut [u32]` or fixed arrays `[BvhNode; K]` / `[u32; M]` on a microcontroller. The
/// storage's slice **length** is its capacity (a `Vec`'s or `heapless::Vec`'s spare capacity
/// does not count), so make it full-length first. Only the first [`Bvh::node_count`] nodes
/// and [`Bvh::primitive_count`] indices are used.
///
/// The storage's `AsRef` is expected to give the slices the tree was built in (or checked
/// in, [`Bvh::from_parts`]) for as long as the tree is queried. Storage that gives others
/// later (an A/B flash region switched by a flag, say) makes the answers meaningless but
/// never a panic or a hang: a walk of a tree enters each node at most once, and every walk
/// (queries, [`Bvh::stats`], [`Bvh::stack_depth`]) that would enter more nodes than that
/// (inner nodes, for the ray queries) ends there, with what it found.
///
/// ```
/// use halfray_core::bvh::{BuildOptions, Bvh, BvhError, BvhNode, index_capacity, node_capacity};
/// use halfray_core::mesh::TriangleMesh;
/// use halfray_core::solids::{OCTAHEDRON_TRIANGLES, OCTAHEDRON_VERTICES};
///
/// let mesh = TriangleMesh::new(&OCTAHEDRON_VERTICES, &OCTAHEDRON_TRIANGLES);
/// const K: usize = node_capacity(8);
/// let (n, options) = (mesh.len(), BuildOptions::default());
///
/// // Storage whose length is the capacity: an array, a filled `Vec`, a filled `heapless::Vec`.
/// let mut array = [BvhNode::EMPTY; K];
/// assert!(Bvh::build(&mesh, &mut array, vec![0u32; n], &options).is_ok());
/// let nodes = vec![BvhNode::EMPTY; node_capacity(n)];
/// assert!(Bvh::build(&mesh, nodes, vec![0u32; index_capacity(n)], &options).is_ok());
/// let nodes: heapless::Vec<BvhNode, K> = heapless::Vec::from_array([BvhNode::EMPTY; K]);
/// let indices: heapless::Vec<u32, 8> = heapless::Vec::from_array([0; 8]);
/// assert!(Bvh::build(&mesh, nodes, indices, &options).is_ok());
///
/// // Not these: reserved capacity is not length, so they hold no node ("0 available").
/// let reserved: Vec<BvhNode> = Vec::with_capacity(node_capacity(n));
/// let refused = Bvh::build(&mesh, reserved, vec![0u32; n], &options).unwrap_err();
/// assert!(matches!(refused, BvhError::Capacity(_)));
/// assert!(refused.to_string().contains("0 available"), "{refused}");
/// let empty: heapless::Vec<BvhNode, K> = heapless::Vec::new();
/// assert!(Bvh::build(&mesh, empty, vec![0u32; n], &options).is_err());
/// ```
#[derive(Clone, Debug)]
pub struct Bvh<N, I> {
    nodes: N,
    indices: I,
    node_count: u32,
    prim_count: u32,
    source_len: usize,
}

impl<N: AsRef<[BvhNode]>, I> Bvh<N, I> {
    /// The tree made of storage that holds a built (or checked) tree of `node_count` nodes
    /// over `prim_count` of `source_len` primitives.
    fn assemble(nodes: N, indices: I, node_count: u32, prim_count: u32, source_len: usize) -> Self {
        Self {
            nodes,
            indices,
            node_count,
            prim_count,
            source_len,
        }
    }
}

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]> + AsMut<[BvhNode]>,
    I: AsRef<[u32]> + AsMut<[u32]>,
{
    /// Builds a BVH over `source` into `nodes` and `indices`.
    ///
    /// # Errors
    ///
    /// All returned before any storage is written:
    /// [`BvhError::TooManyPrimitives`] (more than [`MAX_PRIMITIVES`]),
    /// [`BvhError::Capacity`] (fewer than [`node_capacity`]`(N)` nodes or `N` indices), and
    /// [`BvhError::NonFinite`] for the first primitive with non-finite bounds unless
    /// [`BuildOptions::exclude_non_finite`] is set.
    pub fn build<S: PrimitiveSource + ?Sized>(
        source: &S,
        nodes: N,
        indices: I,
        options: &BuildOptions,
    ) -> Result<Self, BvhError> {
        Self::build_in(
            source,
            nodes,
            indices,
            &mut const { BuildWorkspace::new() },
            options,
        )
    }

    /// [`Bvh::build`] with the builder's working memory (bins and pending nodes, about
    /// 4.1 KiB on a 32-bit target) in `work`, which the caller places where it chooses,
    /// instead of on the build's stack. The same tree and the same errors.
    ///
    /// # Errors
    ///
    /// As [`Bvh::build`].
    pub fn build_in<S: PrimitiveSource + ?Sized>(
        source: &S,
        nodes: N,
        indices: I,
        work: &mut BuildWorkspace,
        options: &BuildOptions,
    ) -> Result<Self, BvhError> {
        Self::build_with(source, nodes, indices, |n, i| {
            build::build(source, n, i, options, work)
        })
    }

    /// [`Bvh::build`] with a scratch array of at least [`scratch_capacity`]`(N)` [`PrimRef`]s
    /// (32 bytes each on x86-64, 28 elsewhere) that the builder fills once with every primitive's box and index
    /// and reorders in place, instead of reading the source through the index array at every
    /// level: the same tree, several times faster on large meshes. The same errors, plus
    /// [`BvhError::Capacity`], all before `nodes` or `indices` are written; the
    /// scratch's contents afterwards mean nothing.
    ///
    /// # Errors
    ///
    /// As [`Bvh::build`], plus [`BvhError::Capacity`] (fewer than
    /// [`scratch_capacity`]`(N)` records), all before `nodes` or `indices` are written.
    #[inline(always)]
    pub fn build_with_scratch<S: PrimitiveSource + ?Sized>(
        source: &S,
        nodes: N,
        indices: I,
        scratch: &mut [PrimRef],
        options: &BuildOptions,
    ) -> Result<Self, BvhError> {
        // Inlined to the builder's loops, so that a caller compiles them with its target
        // features (the frontend's AVX2 build).
        Self::build_with(
            source,
            nodes,
            indices,
            #[inline(always)]
            |n, i| build::build_with_scratch(source, n, i, scratch, options),
        )
    }

    /// The tree `build` writes into the storage's slices over `source`: `build` returns
    /// `(node count, primitive count)` or refuses before writing.
    #[inline(always)]
    fn build_with<S: PrimitiveSource + ?Sized>(
        source: &S,
        mut nodes: N,
        mut indices: I,
        build: impl FnOnce(&mut [BvhNode], &mut [u32]) -> Result<(u32, u32), BvhError>,
    ) -> Result<Self, BvhError> {
        let (node_count, prim_count) = build(nodes.as_mut(), indices.as_mut())?;
        Ok(Self::assemble(
            nodes,
            indices,
            node_count,
            prim_count,
            source.primitive_count(),
        ))
    }
}

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    /// The used nodes; node 0 is the root (empty slice for an empty BVH).
    #[inline]
    #[must_use]
    pub fn nodes(&self) -> &[BvhNode] {
        crate::storage::used(self.nodes.as_ref(), self.node_count as usize)
    }

    /// The used primitive indices, in leaf order.
    #[inline]
    #[must_use]
    pub fn indices(&self) -> &[u32] {
        crate::storage::used(self.indices.as_ref(), self.prim_count as usize)
    }

    count_getters! {
        /// Number of nodes in use (≤ [`node_capacity`] of the primitive count).
        node_count = node_count;
        /// Number of primitives in the tree (the source's count minus excluded ones).
        primitive_count = prim_count;
    }

    getters! {
        /// Number of primitives the source had at build time (what [`Bvh::refit`] expects).
        source_len: usize;
    }

    /// `true` when the tree holds no primitive (every query misses).
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.node_count == 0
    }

    /// Bounds of everything in the tree ([`Aabb::EMPTY`] when empty).
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.nodes().first().map_or(Aabb::EMPTY, BvhNode::bounds)
    }

    /// Gives the storage back.
    #[must_use]
    pub fn into_storage(self) -> (N, I) {
        (self.nodes, self.indices)
    }
}
