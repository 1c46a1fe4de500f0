//! A kd-tree over triangles (or any boxed primitives), built with the binned surface-area
//! heuristic into caller storage and traversed front to back with a fixed stack; its closest
//! hit equals a brute-force loop over all primitives, exactly.
//!
//! # Storage
//!
//! [`KdTree::build`] takes three caller arrays:
//! * nodes ([`KdNode`], 8 bytes: split position and axis, or a leaf's reference run);
//! * references (`u32` primitive indices; a primitive straddling split planes is referenced by
//!   every leaf its box overlaps, so there are usually more references than primitives);
//! * a build scratch of [`KdRef`]s (28 bytes each: clipped box and index), whose contents
//!   afterwards mean nothing.
//!
//! Their lengths are the caller's **budgets**: references and scratch must hold at least one
//! entry per primitive ([`min_reference_capacity`]), the node storage at least one node; the
//! builder then splits while the SAH says it pays **and** the budgets allow, and makes a node a
//! leaf when a split would need more references than `min(references.len(), scratch.len())`
//! or more nodes than the node storage holds. Such a tree is valid and exact, only slower;
//! [`KdTree::budget_exhausted`] says whether it happened. The budget is spent depth first
//! (the child below before the one above), so a build that runs out leaves the last nodes it
//! reaches unsplit, however large: on the bunny with a budget of 4 references per triangle
//! and no empty bonus, one such leaf made queries a thousand times slower. Give at least
//! [`reference_capacity`] when speed matters. [`reference_capacity`] and
//! [`node_capacity`] are budgets that the default build of typical meshes stays within
//! (bunny: see [`REFERENCE_FACTOR`]). Too-small storage is refused with a [`KdTreeError`]
//! before anything is written.
//!
//! # Construction
//!
//! Each node's references (boxes already clipped to its cell) are binned by their lower and
//! upper ends into [`BIN_COUNT`] bins per axis of the cell, and the bin boundary of least
//!
//! `cost = TRAVERSAL_COST + INTERSECTION_COST · (1 − EMPTY_BONUS·[one side empty]) ·
//! (m_below·n_below + m_above·n_above) / m`
//!
//! (`m` a cell's surface area; its length for cells flat in two axes) is taken when it beats
//! the leaf cost `INTERSECTION_COST · n`. The references are then partitioned (straddling ones
//! copied to both sides, a box lying in the plane to the side below) and their boxes
//! **clipped to the child's cell** by box–box intersection (conservative: the triangle's part
//! in the cell lies inside the clipped box; no triangle–box clipping). Nodes of at most
//! [`KdBuildOptions::max_leaf_size`] references and nodes at the depth limit
//! ([`max_depth_for`]: `8 + 1.3·log₂ N` as in pbrt, capped at [`MAX_DEPTH`]) are leaves.
//! Flat and degenerate scenes need no special case: an axis of zero extent is never split,
//! a cell of zero area is measured by its length, a point cell is a leaf.
//!
//! Primitives with non-finite or empty bounds (NaN or infinite vertices, out-of-range vertex
//! indices) are an error naming the first ([`KdTreeError::NonFinite`]) or, with
//! [`KdBuildOptions::exclude_non_finite`], left out. Empty input gives a valid empty tree.
//!
//! # Traversal and exactness
//!
//! The ray's interval is clipped to the root cell, then each inner node splits the current
//! interval `[t₀, t₁]` at the plane into the near child's `[t₀, min(t₁, t_exit)]` and the far
//! child's `[max(t₀, t_entry), t₁]`; the near child is visited first, the far one pushed with
//! its interval. A ray parallel to the plane (direction component `±0`) visits the side(s) its
//! origin lies on, with the whole interval. Cell faces are treated as **padded slabs**: the
//! plane is moved outward by the BVH's box padding ([`crate::tolerance::BVH_PROJECTION_PAD`]:
//! `γ₁₆` of how far the tree reaches from the origin, plus two ulps of the origin) for each
//! side, and plane distances are widened
//! outward by [`T_WIDEN_REL`] and [`T_WIDEN_ABS`] (their rounding). Hence every leaf whose
//! padded cell the exact ray passes through within the interval is visited.
//!
//! Why that gives brute force's answer: the watertight test hits a triangle only when the
//! exact ray passes within that padding of it (its sheared coordinates are exact up to
//! `γ₈·max|p − o|`; see [`crate::tolerance::BVH_PROJECTION_PAD`]), i.e. through the padded
//! box of the triangle; every point of the triangle's box lies in the closed cell of a leaf
//! referencing the triangle (the partition rule of the builder, by induction), so the ray
//! passes through the padded cell of such a leaf, near the hit. Leaves are culled only when
//! their entry distance exceeds the current closest `t` padded by
//! [`crate::query::CULL_REL_SLACK`] (the BVH's rule, for the same reasons), never by an early
//! exit at a leaf's far end, so an equal-`t` hit of a smaller index in a later leaf, or a hit
//! exactly on a split plane, is still found. Hits are accepted with the BVH's tie rule
//! ([`crate::bvh`]: `t` in `(t_min, t_max]`, equal `t` → smaller primitive index), and the
//! test of a triangle does not depend on the leaf it is tested from. Invalid rays (NaN, ±∞,
//! zero direction) hit nothing without touching a node.
//!
//! **Stack bound:** the traversal stack holds [`TRAVERSAL_STACK_SIZE`] = [`MAX_DEPTH`] = 64
//! entries of 12 bytes (node, interval). An entry is pushed only when descending from an inner
//! node, at most one per descent, and the entries on the stack are siblings of nodes on the
//! path from the root to the current node, at most one per level below the root; the builder
//! never splits a node at depth ≥ its depth limit ≤ [`MAX_DEPTH`], so no path has more than
//! [`MAX_DEPTH`] levels below the root and the stack never overflows. Trees come only from
//! the builder, so no deeper tree exists.

mod build;
mod error;
mod kdref;
mod node;
mod query;
mod sah;
mod traverse;

#[cfg(test)]
mod tests;

pub use error::KdTreeError;
pub use kdref::KdRef;
pub use node::{KdNode, KdNodeKind, NODE_SIZE};

use crate::aabb::Aabb;
use crate::float::gamma;
use sah::Costs;

/// Bins per axis of the binned SAH. 32 boundaries per axis find most of the empty-space cuts a
/// full sweep finds on scanned meshes, for 256 bytes of counters.
pub const BIN_COUNT: usize = 32;

/// SAH cost of one traversal step (one inner node: a plane distance and a comparison), in
/// units of [`INTERSECTION_COST`]. Unitless.
pub const TRAVERSAL_COST: f32 = 1.0;

/// SAH cost of one triangle test against a traversal step's [`TRAVERSAL_COST`]. Unitless.
/// Measured on the bunny (20 000 incoherent rays, empty bonus 0.5): costs 1, 2, 4 and 8 all
/// give about 19 triangle tests and 47 node visits per ray, while the tree grows from 28.1 to
/// 32.1 bytes per triangle (3.4 to 3.8 references per triangle); hence 1.
pub const INTERSECTION_COST: f32 = 1.0;

/// Fraction of the SAH's intersection term removed when a split leaves one side empty
/// (pbrt's empty bonus): cutting off empty space pays even where the plain SAH would not.
/// Unitless, in `[0, 1]`. Without it (0) the bunny's build needs more than 4 references per
/// triangle, with it 3.4.
pub const EMPTY_BONUS: f32 = 0.5;

/// Deepest a node can be (the root has depth 0); [`max_depth_for`] never exceeds it. It is
/// the traversal stack's bound (module docs).
pub const MAX_DEPTH: usize = 64;

/// Entries of the fixed traversal stack: [`MAX_DEPTH`] (module docs).
pub const TRAVERSAL_STACK_SIZE: usize = MAX_DEPTH;

/// Largest number of primitives a kd-tree can index (a leaf's reference count has 30 bits).
pub const MAX_PRIMITIVES: usize = (1 << 30) - 1;

/// References per primitive of [`reference_capacity`]: the default build of the bunny uses
/// 3.4 per triangle. Unitless.
pub const REFERENCE_FACTOR: usize = 4;

/// Relative widening of every plane distance the traversal computes: each is
/// `(plane − shifted origin)·(1/d)` (or `/d`), at most three roundings (`γ₃`); `2·γ₃` moves the
/// computed value past the exact one. Unitless.
pub const T_WIDEN_REL: f32 = 2.0 * gamma(3);

/// Absolute widening of every plane distance, in units of `t`: a product that underflows
/// into the subnormal range has an absolute, not relative, error (below `2⁻¹⁴⁹`); the smallest
/// normal `f32` covers it.
pub const T_WIDEN_ABS: f32 = f32::MIN_POSITIVE;

/// The automatic depth limit for `n` primitives: `8 + 1.3·⌊log₂ n⌋` (pbrt's rule, rounded),
/// at most [`MAX_DEPTH`]; 0 for `n = 0`.
#[must_use]
pub const fn max_depth_for(n: usize) -> u32 {
    if n == 0 {
        return 0;
    }
    let d = 8 + (13 * n.ilog2() + 5) / 10;
    if d as usize > MAX_DEPTH {
        MAX_DEPTH as u32
    } else {
        d
    }
}

/// The least reference (and scratch) storage a build over `n` primitives accepts: `n`.
#[must_use]
pub const fn min_reference_capacity(n: usize) -> usize {
    n
}

/// A reference (and scratch) budget for `n` primitives: [`REFERENCE_FACTOR`]`·n`
/// (saturating). Any budget of at least `n` works; see the module docs.
#[must_use]
pub const fn reference_capacity(n: usize) -> usize {
    n.saturating_mul(REFERENCE_FACTOR)
}

/// A node budget for `n` primitives: `2·`[`reference_capacity`]`(n)`, the nodes of a tree
/// whose leaves hold one reference each (empty leaves, which cut off empty space, come on
/// top; a build that runs out stops splitting, see the module docs). At least 1 for `n > 0`.
#[must_use]
pub const fn node_capacity(n: usize) -> usize {
    reference_capacity(n).saturating_mul(2)
}

/// Options of [`KdTree::build`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KdBuildOptions {
    /// `false` (default): a primitive with non-finite or empty bounds is an error
    /// ([`KdTreeError::NonFinite`]). `true`: such primitives are left out.
    pub exclude_non_finite: bool,
    /// Nodes with at most this many references are leaves. Values below 1 count as 1.
    /// Default 1 (the SAH decides for every node of two or more).
    pub max_leaf_size: u32,
    /// Depth limit; 0 (default) means [`max_depth_for`] the primitive count. Capped at
    /// [`MAX_DEPTH`].
    pub max_depth: u32,
    /// SAH cost of a traversal step ([`TRAVERSAL_COST`]); a value that is not positive and
    /// finite counts as the default.
    pub traversal_cost: f32,
    /// SAH cost of a primitive test ([`INTERSECTION_COST`]); same rule.
    pub intersection_cost: f32,
    /// Empty-space bonus ([`EMPTY_BONUS`]); values outside `[0, 1]` or NaN count as the
    /// default.
    pub empty_bonus: f32,
}

impl Default for KdBuildOptions {
    fn default() -> Self {
        Self {
            exclude_non_finite: false,
            max_leaf_size: 1,
            max_depth: 0,
            traversal_cost: TRAVERSAL_COST,
            intersection_cost: INTERSECTION_COST,
            empty_bonus: EMPTY_BONUS,
        }
    }
}

impl KdBuildOptions {
    /// The depth limit for `n` primitives (see [`KdBuildOptions::max_depth`]).
    #[must_use]
    pub fn depth_limit(&self, n: usize) -> u32 {
        let d = if self.max_depth == 0 {
            max_depth_for(n)
        } else {
            self.max_depth
        };
        d.min(MAX_DEPTH as u32)
    }

    /// The SAH parameters, defaults in place of invalid values.
    fn costs(&self) -> Costs {
        let positive = |x: f32, d: f32| if x > 0.0 && x.is_finite() { x } else { d };
        let bonus = if (0.0..=1.0).contains(&self.empty_bonus) {
            self.empty_bonus
        } else {
            EMPTY_BONUS
        };
        Costs {
            traversal: f64::from(positive(self.traversal_cost, TRAVERSAL_COST)),
            intersection: f64::from(positive(self.intersection_cost, INTERSECTION_COST)),
            empty_bonus: f64::from(bonus),
        }
    }
}

/// A kd-tree over caller storage `N` (nodes) and `R` (primitive references).
///
/// Typical storage: `Vec<KdNode>` / `Vec<u32>` in a std program, slices or fixed arrays on a
/// microcontroller. Only the first [`KdTree::node_count`] nodes and
/// [`KdTree::reference_count`] references are used.
///
/// The storage's `AsRef` is expected to give the slices the tree was built in for as long as
/// the tree is queried. Storage that gives others later makes the answers meaningless but
/// never a panic or a hang: a walk of a tree enters each node at most once, and every walk
/// that would enter more nodes than the tree has ends there, with what it found.
#[derive(Clone, Debug)]
pub struct KdTree<N, R> {
    nodes: N,
    refs: R,
    node_count: u32,
    ref_count: u32,
    prim_count: u32,
    source_len: usize,
    bounds: Aabb,
    /// Where the tree lies, for the plane padding ([`crate::tolerance::BVH_PROJECTION_PAD`]):
    /// of `bounds`, kept so that a query does not recompute it.
    pad_frame: crate::query::walk::PadFrame,
    depth: u32,
    exhausted: bool,
}

impl<N, R> KdTree<N, R>
where
    N: AsRef<[KdNode]> + AsMut<[KdNode]>,
    R: AsRef<[u32]> + AsMut<[u32]>,
{
    /// Builds a kd-tree over `source` (a [`crate::mesh::TriangleMesh`], a slice of triangles or
    /// boxes) into `nodes` and `refs`, using `scratch` as working memory. See the module docs
    /// for the budgets.
    ///
    /// # Errors
    ///
    /// All returned before any storage is written: [`KdTreeError::TooManyPrimitives`] (more
    /// than [`MAX_PRIMITIVES`]), [`KdTreeError::Capacity`] (no node for a
    /// non-empty source, or references or scratch fewer than [`min_reference_capacity`]`(N)`),
    /// and
    /// [`KdTreeError::NonFinite`] for the first primitive with non-finite or empty
    /// bounds unless [`KdBuildOptions::exclude_non_finite`] is set.
    pub fn build<S: crate::mesh::PrimitiveSource + ?Sized>(
        source: &S,
        mut nodes: N,
        mut refs: R,
        scratch: &mut [KdRef],
        options: &KdBuildOptions,
    ) -> Result<Self, KdTreeError> {
        let built = build::build(source, nodes.as_mut(), refs.as_mut(), scratch, options)?;
        let bounds = built.bounds.unwrap_or(Aabb::EMPTY);
        Ok(Self {
            nodes,
            refs,
            node_count: built.node_count,
            ref_count: built.ref_count,
            prim_count: built.prim_count,
            source_len: source.primitive_count(),
            bounds,
            pad_frame: crate::query::walk::PadFrame::of(&bounds),
            depth: built.depth,
            exhausted: built.exhausted,
        })
    }
}

impl<N: AsRef<[KdNode]>, R: AsRef<[u32]>> KdTree<N, R> {
    /// The used nodes; node 0 is the root (empty for an empty tree).
    #[must_use]
    pub fn nodes(&self) -> &[KdNode] {
        crate::storage::used(self.nodes.as_ref(), self.node_count as usize)
    }

    /// The used references (primitive indices), leaf by leaf.
    #[must_use]
    pub fn references(&self) -> &[u32] {
        crate::storage::used(self.refs.as_ref(), self.ref_count as usize)
    }

    /// Number of nodes in use.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.node_count as usize
    }

    /// Number of references in use (at least [`KdTree::primitive_count`]).
    #[must_use]
    pub fn reference_count(&self) -> usize {
        self.ref_count as usize
    }

    /// Number of primitives in the tree (the source's count minus excluded ones).
    #[must_use]
    pub fn primitive_count(&self) -> usize {
        self.prim_count as usize
    }

    /// Number of primitives the source had at build time.
    #[must_use]
    pub fn source_len(&self) -> usize {
        self.source_len
    }

    /// `true` when the tree holds no primitive (every query misses).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.node_count == 0
    }

    /// The root cell: the box of every primitive in the tree ([`Aabb::EMPTY`] when empty).
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Depth of the deepest leaf (root: 0); at most [`MAX_DEPTH`].
    #[must_use]
    pub fn depth(&self) -> usize {
        self.depth as usize
    }

    /// `true` when the builder left a node unsplit because the reference or node budget was
    /// reached (module docs).
    #[must_use]
    pub fn budget_exhausted(&self) -> bool {
        self.exhausted
    }

    /// Number of leaves, and of those that hold no reference.
    #[must_use]
    pub fn leaf_counts(&self) -> (usize, usize) {
        self.nodes()
            .iter()
            .fold((0, 0), |(l, e), n| match n.kind() {
                KdNodeKind::Leaf { count, .. } => (l + 1, e + usize::from(count == 0)),
                KdNodeKind::Inner { .. } => (l, e),
            })
    }

    /// Gives the storage back.
    #[must_use]
    pub fn into_storage(self) -> (N, R) {
        (self.nodes, self.refs)
    }
}
