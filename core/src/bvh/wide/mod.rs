//! A **wide** BVH over a triangle mesh: `W` children per node (2, 4 or 8; [`Bvh8`], [`Bvh4`])
//! whose boxes are stored side by side so that one node test covers all of them, and the
//! triangles copied into leaf order. Built by collapsing a binary [`Bvh`](super::Bvh), in
//! **caller storage**, traversed with a **fixed-size stack**; no allocation, no recursion, no
//! panics.
//!
//! # Building
//!
//! [`WideBvh::from_binary`] collapses a built binary tree over a
//! [`TriangleMesh`](crate::mesh::TriangleMesh): each wide node takes its binary node's two
//! children and, while it has fewer than `W`, replaces the inner child with the largest
//! surface area by that child's two children (ties: the first). A binary subtree of at most
//! [`LEAF_MERGE`] triangles becomes one leaf slot (its triangles in a row), and slots still
//! free then go to opening the leaf runs of more than [`LEAF_OPEN_ABOVE`] triangles into
//! their two subtrees, largest surface area first. A tree that is one leaf run that does not
//! open (a binary root that is a leaf, or a binary subtree of at most [`LEAF_OPEN_ABOVE`]
//! triangles: the tetrahedron, the octahedron) has **no node**: its root
//! ([`WideBvh::root`]) is that leaf, and a ray tests its triangles without a node test. The
//! caller passes node storage of at
//! least [`WideBvh::node_count_for`]`(binary)` nodes (exact; [`node_capacity`] is a bound
//! that needs no binary tree) and triangle storage of at least
//! [`WideBvh::group_count_for`]`(binary)` groups (exact; [`group_capacity`]`(N)` always
//! suffices). Too little storage, a binary leaf of more than [`MAX_LEAF_TRIANGLES`]
//! primitives, more than [`MAX_TRIANGLES`] triangles, or a mesh that is not the binary
//! tree's source (another triangle count, or a triangle outside the box of the binary subtree
//! its wide leaf is made from: [`BvhError::TriangleOutsideTree`](super::BvhError::TriangleOutsideTree))
//! is a typed error returned **before anything is written** ([`WideBvh::from_binary_in`],
//! which walks the tree once, finds the leaf and box errors during its walk). A mesh that
//! passes lies in every box of the wide tree, so queries are exact for it.
//!
//! # Layout and size
//!
//! A [`WideNode`] holds, per axis, the `W` lower and the `W` upper bounds (`[[[f32; W]; 3]; 2]`,
//! structure of arrays) and `W` child references: 224 bytes for `W = 8`, 128 for `W = 4`
//! (aligned to 32 bytes).
//! A child reference is an inner node's index, a leaf (a run of at most
//! [`MAX_LEAF_TRIANGLES`] triangle slots), or empty (an empty box, never hit). The triangles
//! (three vertices and the index in the mesh) are copied in leaf order into [`LeafGroup`]s of
//! four, stored side by side so that a leaf is tested four triangles at a time, 40 bytes per
//! triangle slot. A node's leaf runs are placed side by side, best fit first (of the runs
//! left, one that starts without a skip and fills the current group furthest), each
//! where the previous one ended unless it would then touch more
//! groups than the `⌈count/4⌉` it needs; it then starts at the next group (the skipped lanes
//! stay empty: a few more groups in the tree, fewer groups read per leaf).
//! Everything the structure adds, copied triangles included, is `224·nodes + 160·groups`
//! bytes (40 per triangle for a tree with no node) ([`RayQuery::bytes_per_triangle`](crate::query::RayQuery::bytes_per_triangle)); the caller's mesh is not needed by queries.
//!
//! # Traversal
//!
//! As in the binary tree: the robust, conservative, NaN-absorbing slab test on every child box
//! at once, over `[t_min, t_max·(1 + CULL_REL_SLACK)]`; in a leaf, the intersector's
//! four-lane cull (an internal hook of [`crate::triangle::TriangleIntersector`]) skips the
//! triangles it certainly misses and the rest are tested one by one, in leaf order; children
//! hit are visited nearest first
//! (the others pushed with their entry distance, re-checked when popped); the **tie rule** (of
//! equal `t`, the smaller primitive index) makes the closest hit equal a brute-force loop with
//! the same intersector; invalid rays test nothing.
//!
//! **Stack bound:** a node leaves at most `W − 1` entries (all hit children but the nearest),
//! and the entries live at any time are children of the inner nodes on the path from the root
//! to the current node. Every wide inner node is a binary inner node, and a wide child is a
//! binary descendant of its parent, so a wide path has at most as many inner nodes as a
//! binary path: at most [`MAX_DEPTH`](super::MAX_DEPTH) (binary inner nodes have depth
//! `< MAX_DEPTH`). The current node sorts its up to `W` hit children on the stack before
//! popping the nearest, so at most `(W − 1)·(MAX_DEPTH − 1) + W ≤ (W − 1)·MAX_DEPTH + 1`
//! entries are ever stored: [`stack_size`]`(W)` = 449 for `W = 8` (3.5 KiB of 8-byte
//! entries). Traversal never overflows it.

mod collapse;
mod node;
mod node_test;
mod packet;
mod planes;
mod query;
mod refit;
mod root_batch;
mod traverse;

#[cfg(test)]
mod tests;

pub use node::{ChildRef, LeafGroup, LeafTriangle, WideNode};

use crate::aabb::Aabb;
use crate::getters::{count_getters, getters};
use crate::query::TraversalStats;
use glam::Vec3;

/// Most triangles one wide leaf slot can hold (the binary tree's leaves must not be larger).
pub const MAX_LEAF_TRIANGLES: usize = 16;

/// Binary subtrees of at most this many triangles become one wide leaf (their triangles are
/// contiguous in leaf order): testing a few triangles in a row costs less than visiting a node
/// for them: a leaf of 16 is two eight-lane culls where a node step and one cull were needed.
/// Chosen by measurement against 4, 6, 8 and 12 (`docs/performance.md`). At most
/// [`MAX_LEAF_TRIANGLES`].
pub const LEAF_MERGE: usize = 16;

/// Leaf runs of more than this many triangles that are binary subtrees (not binary leaves)
/// are opened into their two children where their wide node has a slot to spare, once every
/// inner child has been expanded, largest surface area first: the node test covers the
/// smaller boxes at no extra cost, and a ray enters only the halves it hits. Most nodes at
/// the bottom of a collapsed tree hold two leaves of up to [`LEAF_MERGE`] and six empty slots
/// without it. Chosen by measurement against no opening and against 4, 6, 10 and 12
/// (`docs/performance.md`): lower values give more leaves to visit.
pub const LEAF_OPEN_ABOVE: usize = 8;

/// SAH cost of a triangle test in a tree collapsed into a wide one, against a traversal step's
/// 1 ([`crate::bvh::TRAVERSAL_COST`]). Unitless. Lower than the binary tree's
/// [`crate::bvh::INTERSECTION_COST`] because a wide leaf tests four triangles per step and
/// culls most of them in one four-lane test, while a wide node step tests eight boxes. It
/// decides leaf or split only for nodes between `leaf_threshold` and `max_leaf_size`;
/// [`binary_options`] sets both to [`LEAF_OPEN_ABOVE`], so there it changes nothing (where a
/// node is split does not depend on it): it matters to a caller who lowers `leaf_threshold`.
pub const WIDE_INTERSECTION_COST: f32 = 0.3;

/// The options of a binary tree built to be collapsed ([`WideBvh::from_binary`]): `options`
/// with [`BuildOptions::leaf_threshold`](crate::bvh::BuildOptions::leaf_threshold) and
/// [`BuildOptions::max_leaf_size`](crate::bvh::BuildOptions::max_leaf_size) at
/// [`LEAF_OPEN_ABOVE`] (every node of more triangles is split, so that a merged leaf run of
/// more can be opened; splitting smaller ones is wasted work, as the collapse makes every
/// subtree of at most [`LEAF_MERGE`] triangles one leaf run and opens only larger runs, or
/// one whose split spares [`LARGE_NODE_SAVING`](crate::bvh::LARGE_NODE_SAVING) tests), and
/// the SAH's primitive cost at [`WIDE_INTERSECTION_COST`]. Splits are made where the SAH puts
/// them (their position does not depend on the leaf sizes), so the collapse gives the same
/// wide tree as from a binary tree split down to single triangles, but for the order of the
/// triangles inside a leaf.
#[must_use]
pub const fn binary_options(options: crate::bvh::BuildOptions) -> crate::bvh::BuildOptions {
    let open = LEAF_OPEN_ABOVE as u32;
    crate::bvh::BuildOptions {
        leaf_threshold: open,
        max_leaf_size: open,
        intersection_cost: WIDE_INTERSECTION_COST,
        ..options
    }
}

/// Most triangles a wide BVH can hold: leaf references address triangle records with 27 bits.
pub const MAX_TRIANGLES: usize = 1 << 27;

/// Entries of the fixed traversal stack of a `W`-wide tree: `(W − 1)·MAX_DEPTH + 1` (module
/// docs); 1 for a width of 0, and `usize::MAX` where the product does not fit.
#[must_use]
pub const fn stack_size(width: usize) -> usize {
    width
        .saturating_sub(1)
        .saturating_mul(super::MAX_DEPTH)
        .saturating_add(1)
}

/// Wide nodes that always suffice for `triangles` triangles, whatever the binary tree: one per
/// binary inner node at most, `N − 1`, and at least 1 (a tree that is one leaf needs none:
/// module docs). Prefer the exact
/// [`WideBvh::node_count_for`] when the binary tree is at hand: trees of scanned meshes use
/// about `N / 12` nodes.
#[must_use]
pub const fn node_capacity(triangles: usize) -> usize {
    if triangles <= 1 { 1 } else { triangles - 1 }
}

/// [`LeafGroup`]s that always suffice for `triangles` triangles, whatever the binary tree:
/// `⌈7N / 16⌉`. A leaf run of `c` triangles takes at most `4⌈c/4⌉ − 1` slots with the lanes
/// skipped to start it at a group boundary (collapse docs), at most `7c/4` (at `c = 4`), and
/// four slots make a group. Prefer the exact [`WideBvh::group_count_for`] (scanned meshes
/// need about `1.07·N/4`).
#[must_use]
pub const fn group_capacity(triangles: usize) -> usize {
    triangles
        .saturating_mul(7)
        .div_ceil(4 * crate::triangle::LANES)
}

/// Refuses, at compile time, a width a wide tree does not support: `width` must be 2, 4 or
/// 8. Traversal picks a child slot as `i & (W − 1)`, which keeps every slot of a node and
/// nothing else only for a power of two, and the node test's sort keys hold a slot in three
/// bits; a node of one child cannot branch. Every constructor ([`WideBvh::from_binary`] and
/// its variants) and every size query ([`WideBvh::node_count_for`],
/// [`WideBvh::group_count_for`]) evaluates it in a `const` block, so a tree of another width
/// does not compile.
const fn assert_width(width: usize) {
    assert!(
        width.is_power_of_two() && 2 <= width && width <= 8,
        "a wide BVH has 2, 4 or 8 children a node"
    );
}

/// A `W`-wide BVH over caller storage `N` (nodes) and `T` (triangle groups).
///
/// **`W` is 2, 4 or 8.** Any other width is refused at compile time (traversal picks a child
/// slot as `i & (W − 1)`, right only for a power of two): building or sizing a tree of width
/// 3 does not compile.
///
/// The storage's `AsRef` is expected to give the slices the tree was built in for as long as
/// the tree is queried. Storage that gives others later (an A/B flash region switched by a
/// flag, say) makes the answers meaningless but never a panic or a hang: a walk of a tree
/// enters each node at most once and finds every inner child stored after its parent, and
/// every walk ends with what it found after a bounded number of node steps: a single ray's
/// follows a single hit child only forward and stops pushing once it has entered more nodes
/// than the storage holds (at most 451 node steps per stored node: the stack's 449 entries
/// + 2); a packet's and the box query's stop entering nodes there.
///
/// ```
/// use halfray_core::bvh::wide::{LeafGroup, WideBvh, WideNode};
/// use halfray_core::bvh::{BuildOptions, Bvh, BvhNode};
/// use halfray_core::mesh::TriangleMesh;
/// use halfray_core::Vec3;
///
/// let (pos, tri) = ([Vec3::ZERO, Vec3::X, Vec3::Y], [[0u32, 1, 2]]);
/// let mesh = TriangleMesh::new(&pos, &tri);
/// let binary = Bvh::build(&mesh, [BvhNode::EMPTY; 1], [0u32; 1], &BuildOptions::default())?;
/// let wide = WideBvh::<4, _, _>::from_binary(
///     &binary,
///     &mesh,
///     [WideNode::<4>::EMPTY; 1],
///     [LeafGroup::EMPTY; 1],
/// )?;
/// assert_eq!(wide.triangle_count(), 1);
/// # Ok::<(), halfray_core::bvh::BvhError>(())
/// ```
///
/// The same with `W = 3` fails to compile:
///
/// ```compile_fail,E0080
/// use halfray_core::bvh::wide::{LeafGroup, WideBvh, WideNode};
/// use halfray_core::bvh::{BuildOptions, Bvh, BvhNode};
/// use halfray_core::mesh::TriangleMesh;
/// use halfray_core::Vec3;
///
/// let (pos, tri) = ([Vec3::ZERO, Vec3::X, Vec3::Y], [[0u32, 1, 2]]);
/// let mesh = TriangleMesh::new(&pos, &tri);
/// let binary = Bvh::build(&mesh, [BvhNode::EMPTY; 1], [0u32; 1], &BuildOptions::default())?;
/// let wide = WideBvh::<3, _, _>::from_binary(
///     &binary,
///     &mesh,
///     [WideNode::<3>::EMPTY; 1],
///     [LeafGroup::EMPTY; 1],
/// )?;
/// assert_eq!(wide.triangle_count(), 1);
/// # Ok::<(), halfray_core::bvh::BvhError>(())
/// ```
#[derive(Clone, Debug)]
pub struct WideBvh<const W: usize, N, T> {
    nodes: N,
    groups: T,
    node_count: u32,
    triangle_count: u32,
    /// Triangle slots in use, the lanes skipped before leaf runs included.
    slot_count: u32,
    source_len: usize,
    /// The root ([`WideBvh::root`]) as a child slot encodes it: node 0, a leaf run (a tree
    /// with no node), or [`ChildRef::EMPTY`] (an empty tree).
    root: u32,
    /// The box of everything in the tree ([`WideBvh::bounds`], kept), in world coordinates.
    root_box: Aabb,
    /// `root_box` relative to the frame's centre, as the node boxes are stored: a closest-hit
    /// walk tests it first, so that a ray missing the whole tree skips the node test's setup.
    root_local: Aabb,
    /// Where the tree lies, for the box padding ([`crate::tolerance::BVH_PROJECTION_PAD`]):
    /// of `root_box`, its centre the origin of the node boxes ([`WideBvh::box_origin`]).
    pad_frame: crate::query::walk::PadFrame,
}

/// An 8-wide BVH (one AVX2 register per bound array).
pub type Bvh8<N, T> = WideBvh<8, N, T>;
/// A 4-wide BVH (one SSE / NEON register per bound array).
pub type Bvh4<N, T> = WideBvh<4, N, T>;

/// Shape and size of a built wide tree ([`WideBvh::stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WideStats {
    /// Nodes in use.
    pub nodes: usize,
    /// Leaves (leaf slots, and a root leaf).
    pub leaves: usize,
    /// Child slots in use (inner and leaf) over all nodes: `children / nodes` is the fill.
    pub children: usize,
    /// Triangles in the tree.
    pub triangles: usize,
    /// Bytes the structure adds: nodes and triangle groups.
    pub bytes: usize,
}

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]>,
    T: AsRef<[LeafGroup]>,
{
    /// The used nodes; node 0 is the root (empty slice for an empty tree and for a tree whose
    /// root is a leaf: [`WideBvh::root`]).
    #[inline]
    #[must_use]
    pub fn nodes(&self) -> &[WideNode<W>] {
        crate::storage::used(self.nodes.as_ref(), self.node_count as usize)
    }

    /// The used triangle groups (slots in leaf order, four per group).
    #[inline]
    #[must_use]
    pub fn groups(&self) -> &[LeafGroup] {
        crate::storage::used(
            self.groups.as_ref(),
            (self.slot_count as usize).div_ceil(crate::triangle::LANES),
        )
    }

    /// The triangle groups the leaf run of `count` slots from slot `start` spans
    /// ([`ChildRef::Leaf`]), the ones the leaf test reads; empty for a run out of range.
    #[inline]
    #[must_use]
    pub fn leaf_groups(&self, start: u32, count: u32) -> &[LeafGroup] {
        traverse::leaf_groups(self.groups(), start, count)
    }

    /// The triangle in slot `slot` (leaf order); `None` past the last slot and for a lane
    /// skipped before a leaf run (module docs).
    #[inline]
    #[must_use]
    pub fn triangle(&self, slot: usize) -> Option<LeafTriangle> {
        if slot >= self.slot_count as usize {
            return None;
        }
        let lanes = crate::triangle::LANES;
        self.groups()
            .get(slot / lanes)?
            .triangle(slot % lanes)
            .filter(|t| t.prim != u32::MAX)
    }

    /// Every triangle in leaf order.
    pub fn triangles(&self) -> impl Iterator<Item = LeafTriangle> + '_ {
        (0..self.slot_count as usize).filter_map(|s| self.triangle(s))
    }

    count_getters! {
        /// Number of nodes in use.
        node_count = node_count;
        /// Number of triangles in the tree.
        triangle_count = triangle_count;
    }

    getters! {
        /// Number of triangles of the mesh at build time (what [`WideBvh::refit`] expects).
        source_len: usize;
    }

    /// `true` when the tree holds no triangle (every query misses).
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.triangle_count == 0
    }

    /// The root: [`ChildRef::Inner`]`(0)` (node 0), a [`ChildRef::Leaf`] holding every
    /// triangle of a tree with no node (module docs), or [`ChildRef::Empty`] for an empty
    /// tree.
    #[inline]
    #[must_use]
    pub fn root(&self) -> ChildRef {
        ChildRef::decode(self.root)
    }

    /// Bounds of everything in the tree ([`Aabb::EMPTY`] when empty): the union of the root
    /// node's child boxes, or of a root leaf's triangles.
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.root_box
    }

    /// The point the node boxes are measured from: [`WideNode::child_bounds`] is the box of
    /// `p − box_origin()` over the child's points `p`, rounded outward ([`Aabb::relative_to`]).
    /// The centre of [`WideBvh::bounds`]; the origin for an empty tree. Stored so, the boxes
    /// and a ray's origin in their frame are small numbers wherever the mesh lies, and so is
    /// the padding each box is tested with ([`crate::tolerance::BVH_PROJECTION_PAD`]).
    #[inline]
    #[must_use]
    pub fn box_origin(&self) -> Vec3 {
        self.pad_frame.centre()
    }

    /// The box of the root computed from the stored triangles, or from the nodes while their
    /// boxes are still in world coordinates (what [`WideBvh::bounds`] keeps).
    fn computed_bounds(&self) -> Aabb {
        match self.root() {
            ChildRef::Inner(i) => self.nodes().get(i as usize).map_or(Aabb::EMPTY, |n| {
                (0..W).fold(Aabb::EMPTY, |b, k| b.union(n.child_bounds(k)))
            }),
            ChildRef::Leaf { start, count } => run_bounds(self.groups(), start, count),
            ChildRef::Empty => Aabb::EMPTY,
        }
    }

    /// Shape and size.
    #[must_use]
    pub fn stats(&self) -> WideStats {
        let nodes = self.nodes();
        // A root leaf is a leaf in no node's slot.
        let (mut leaves, mut children) =
            (usize::from(matches!(self.root(), ChildRef::Leaf { .. })), 0);
        for n in nodes {
            for &c in &n.child {
                match ChildRef::decode(c) {
                    ChildRef::Empty => {}
                    ChildRef::Leaf { .. } => {
                        leaves += 1;
                        children += 1;
                    }
                    ChildRef::Inner(_) => children += 1,
                }
            }
        }
        let triangles = self.triangle_count();
        let bytes = core::mem::size_of_val(nodes) + core::mem::size_of_val(self.groups());
        WideStats {
            nodes: nodes.len(),
            leaves,
            children,
            triangles,
            bytes,
        }
    }

    /// Gives the storage back.
    #[must_use]
    pub fn into_storage(self) -> (N, T) {
        (self.nodes, self.groups)
    }
}

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]> + AsMut<[WideNode<W>]>,
    T: AsRef<[LeafGroup]>,
{
    /// Sets the tree's frame from node boxes just written in world coordinates (by the
    /// collapse, by [`WideBvh::refit`]): the root box from them, the padding frame centred on
    /// it ([`crate::query::walk::PadFrame::relative`]), then every node's boxes made relative
    /// to that centre ([`WideBvh::box_origin`]), rounded outward, in one pass.
    fn set_frame(&mut self) {
        self.root_box = self.computed_bounds();
        self.pad_frame = crate::query::walk::PadFrame::relative(&self.root_box);
        let centre = self.pad_frame.centre();
        self.root_local = self.root_box.relative_to(centre);
        let count = self.node_count as usize;
        let nodes = self.nodes.as_mut();
        for node in nodes.iter_mut().take(count) {
            for slot in 0..W {
                let b = node.child_bounds(slot).relative_to(centre);
                let reference = node.child[slot];
                node.set_child(slot, &b, reference);
            }
        }
    }
}

/// The box of the triangles in slots `start .. start + count` of `groups` (slot `s` is lane
/// `s % 4` of group `s / 4`) with finite vertices: a leaf's box (a triangle the refit had to
/// disable, and a slot past the groups, are left out).
fn run_bounds(groups: &[LeafGroup], start: u32, count: u32) -> Aabb {
    let lanes = crate::triangle::LANES;
    (start as usize..start as usize + count as usize)
        .filter_map(|s| groups.get(s / lanes)?.triangle(s % lanes))
        .filter(LeafTriangle::is_finite)
        .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()))
}

/// Adds `local` to the caller's counters, if any.
#[inline]
fn add_stats(stats: Option<&mut TraversalStats>, local: &TraversalStats) {
    if let Some(s) = stats {
        s.add(local);
    }
}
