//! A BVH from nodes and indices made elsewhere (baked on a host into `static` arrays, read
//! from flash or from a file), checked before it is trusted: [`Bvh::from_parts`].
//!
//! Baked data is input, not trusted memory. [`Bvh::from_parts`] walks the tree once, in
//! `O(nodes + primitives)` time with a fixed stack and a caller-provided bitset, and accepts it
//! only if traversal over it terminates within its fixed stack and gives the answers a freshly
//! built tree over the same mesh would give (those of a brute-force loop, with the same tie
//! rule):
//!
//! * **child order**: an inner node's children `c, c + 1` come after it (`c > node`) and lie
//!   inside the node array (so no walk can cycle);
//! * **depth**: no inner node at depth ≥ [`MAX_DEPTH`] (the traversal stack's bound), and no
//!   node reached twice (at most as many node visits as nodes);
//! * **index ranges**: leaves are non-empty and, in depth-first (first child first) order,
//!   cover `indices` exactly once from the start; every index names a triangle of the mesh,
//!   each triangle once (the bitset), and the tree holds every triangle;
//! * **boxes**: every reached box is finite with `min ≤ max`, contains its children's boxes and,
//!   for a leaf, the vertices of its triangles, whose indices and coordinates must be valid and
//!   finite.
//!
//! Nodes that no walk reaches (the builder's alignment padding) are never read by a query and
//! are not checked.

use super::node::BvhNode;
use super::{Bvh, MAX_DEPTH, node_capacity};
use crate::error::{CapacityError, Storage};
use crate::mesh::TriangleMesh;
use core::fmt;

/// Words of the bitset [`Bvh::from_parts`] needs for `triangles` triangles: one bit each.
#[must_use]
pub const fn load_scratch_len(triangles: usize) -> usize {
    triangles.div_ceil(32)
}

/// Why [`Bvh::from_parts`] refused its input. Node and position numbers are indices into the
/// arrays as given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum LoadError {
    /// The index array's length is not the mesh's triangle count.
    IndexCount {
        /// Entries in `indices`.
        indices: usize,
        /// Triangles in the mesh.
        triangles: usize,
    },
    /// More nodes than a tree over the mesh can have (`node_capacity + 1` with the builder's
    /// alignment slot), or none for a non-empty mesh.
    NodeCount {
        /// Nodes given.
        nodes: usize,
        /// Triangles in the mesh.
        triangles: usize,
    },
    /// The bitset holds fewer than [`load_scratch_len`] words
    /// ([`crate::error::Storage::BvhLoadBitset`]).
    Capacity(CapacityError),
    /// An inner node's children are not after it, or lie past the node array.
    ChildOutOfRange {
        /// The inner node.
        node: usize,
    },
    /// An inner node at depth [`MAX_DEPTH`] or deeper.
    TooDeep {
        /// The inner node.
        node: usize,
    },
    /// A node is reached by more than one path (the tree is not a tree).
    SharedNode {
        /// The node reached again.
        node: usize,
    },
    /// A box is not finite, has `min > max`, or does not contain its children's boxes or its
    /// triangles.
    BadBox {
        /// The node.
        node: usize,
    },
    /// A leaf's range is not the next run of `indices` in depth-first order, or runs past it.
    LeafRange {
        /// The leaf.
        node: usize,
    },
    /// `indices[position]` names no triangle of the mesh, or a triangle already listed.
    BadIndex {
        /// Position in `indices`.
        position: usize,
    },
    /// A triangle's vertex index is out of range or its vertex is not finite.
    BadTriangle {
        /// The triangle.
        triangle: usize,
    },
    /// The leaves cover only the first `covered` of the indices.
    Uncovered {
        /// Indices covered by leaves.
        covered: usize,
        /// Indices given.
        indices: usize,
    },
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::IndexCount { indices, triangles } => write!(
                f,
                "{indices} primitive indices for a mesh of {triangles} triangles"
            ),
            Self::NodeCount { nodes, triangles } => write!(
                f,
                "{nodes} nodes cannot form a tree over {triangles} triangles"
            ),
            Self::Capacity(e) => e.fmt(f),
            Self::ChildOutOfRange { node } => write!(
                f,
                "node {node}: children are not after it or lie past the node array"
            ),
            Self::TooDeep { node } => write!(
                f,
                "node {node}: an inner node at depth {MAX_DEPTH} or deeper"
            ),
            Self::SharedNode { node } => write!(f, "node {node} is reached by two paths"),
            Self::BadBox { node } => write!(
                f,
                "node {node}: box not finite, inverted, or not containing its children or triangles"
            ),
            Self::LeafRange { node } => write!(
                f,
                "leaf {node}: its index range is empty, out of order or past the index array"
            ),
            Self::BadIndex { position } => write!(
                f,
                "index {position} names no triangle of the mesh, or one already listed"
            ),
            Self::BadTriangle { triangle } => write!(
                f,
                "triangle {triangle}: vertex index out of range or vertex not finite"
            ),
            Self::Uncovered { covered, indices } => write!(
                f,
                "the leaves cover {covered} of {indices} primitive indices"
            ),
        }
    }
}

impl core::error::Error for LoadError {}

/// `true` when `b` is finite with `min ≤ max` on every axis.
fn finite_box(b: &[[f32; 3]; 2]) -> bool {
    (0..3).all(|k| b[0][k].is_finite() && b[1][k].is_finite() && b[0][k] <= b[1][k])
}

/// `true` when box `outer` contains box `inner`.
fn contains_box(outer: &[[f32; 3]; 2], inner: &[[f32; 3]; 2]) -> bool {
    (0..3).all(|k| outer[0][k] <= inner[0][k] && inner[1][k] <= outer[1][k])
}

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    /// A BVH over `mesh` from `nodes` (node 0 the root; every element is used) and `indices`
    /// (one per triangle), checked as the module docs list; `scratch` is a bitset of at least
    /// [`load_scratch_len`]`(mesh.len())` words (contents ignored, overwritten). Nothing is
    /// copied: the result borrows or owns the storage as given (`&'static [BvhNode]` for
    /// arrays in flash).
    ///
    /// # Errors
    ///
    /// A [`LoadError`] naming the first violation found; the storage is handed back only on
    /// success (it is dropped with the error).
    pub fn from_parts(
        nodes: N,
        indices: I,
        mesh: &TriangleMesh<'_>,
        scratch: &mut [u32],
    ) -> Result<Self, LoadError> {
        check(nodes.as_ref(), indices.as_ref(), mesh, scratch)?;
        let (node_count, prim_count) = (nodes.as_ref().len(), indices.as_ref().len());
        // `check` bounds both counts by `node_capacity(MAX_PRIMITIVES)`, which fits in `u32`.
        Ok(Self::assemble(
            nodes,
            indices,
            node_count as u32,
            prim_count as u32,
            mesh.len(),
        ))
    }
}

/// The checks of [`Bvh::from_parts`].
fn check(
    nodes: &[BvhNode],
    indices: &[u32],
    mesh: &TriangleMesh<'_>,
    scratch: &mut [u32],
) -> Result<(), LoadError> {
    let triangles = mesh.len();
    if indices.len() != triangles || triangles > super::MAX_PRIMITIVES {
        return Err(LoadError::IndexCount {
            indices: indices.len(),
            triangles,
        });
    }
    // The builder's alignment slot adds one node; an empty mesh's one node is refused by the
    // emptiness test.
    let max_nodes = node_capacity(triangles) + 1;
    if nodes.len() > max_nodes || (nodes.is_empty() != (triangles == 0)) {
        return Err(LoadError::NodeCount {
            nodes: nodes.len(),
            triangles,
        });
    }
    let needed = load_scratch_len(triangles);
    let Some(seen) = scratch.get_mut(..needed) else {
        return Err(LoadError::Capacity(CapacityError {
            storage: Storage::BvhLoadBitset,
            needed,
            available: scratch.len(),
        }));
    };
    seen.fill(0);
    if nodes.is_empty() {
        return Ok(());
    }
    // Depth-first, first child first: the pending second children, with their depths. One per
    // level at most, so `MAX_DEPTH + 1` entries suffice once depths are bounded.
    let mut stack = [(0u32, 0u8); MAX_DEPTH + 1];
    let mut sp = 1usize;
    let mut visits = 0usize;
    let mut covered = 0usize;
    while sp > 0 {
        sp -= 1;
        // `sp ≤ MAX_DEPTH + 1` by the depth check below; `get` keeps the loop panic-free.
        let Some(&(node, depth)) = stack.get(sp) else {
            return Err(LoadError::TooDeep { node: 0 });
        };
        let node = node as usize;
        visits += 1;
        if visits > nodes.len() {
            return Err(LoadError::SharedNode { node });
        }
        // In range: the root, or a child checked against `nodes.len()` by its parent.
        let Some(n) = nodes.get(node) else {
            return Err(LoadError::ChildOutOfRange { node });
        };
        let b = &n.bounds;
        if !finite_box(b) {
            return Err(LoadError::BadBox { node });
        }
        match n.children() {
            Some((first, _)) => {
                let first = first as usize;
                if first <= node || first.saturating_add(1) >= nodes.len() {
                    return Err(LoadError::ChildOutOfRange { node });
                }
                if usize::from(depth) >= MAX_DEPTH {
                    return Err(LoadError::TooDeep { node });
                }
                for child in [first, first + 1] {
                    if !nodes.get(child).is_some_and(|c| contains_box(b, &c.bounds)) {
                        return Err(LoadError::BadBox { node });
                    }
                }
                // Second child below the first, so the first is walked first.
                let Some([second_slot, first_slot]) = stack.get_mut(sp..sp + 2) else {
                    return Err(LoadError::TooDeep { node });
                };
                *second_slot = ((first + 1) as u32, depth + 1);
                *first_slot = (first as u32, depth + 1);
                sp += 2;
            }
            None => {
                let (start, count) = n.raw();
                let (start, count) = (start as usize, count as usize);
                if start != covered || count > indices.len() - covered {
                    return Err(LoadError::LeafRange { node });
                }
                for (position, &prim) in indices.iter().enumerate().skip(start).take(count) {
                    let prim = prim as usize;
                    let (word, bit) = (prim / 32, 1u32 << (prim % 32));
                    let Some(seen_word) = seen.get_mut(word).filter(|_| prim < triangles) else {
                        return Err(LoadError::BadIndex { position });
                    };
                    if *seen_word & bit != 0 {
                        return Err(LoadError::BadIndex { position });
                    }
                    *seen_word |= bit;
                    let Some(v) = mesh.triangle(prim) else {
                        return Err(LoadError::BadTriangle { triangle: prim });
                    };
                    if !v.iter().all(|p| p.is_finite()) {
                        return Err(LoadError::BadTriangle { triangle: prim });
                    }
                    for p in v {
                        if !contains_box(b, &[p.to_array(), p.to_array()]) {
                            return Err(LoadError::BadBox { node });
                        }
                    }
                }
                covered += count;
            }
        }
    }
    if covered != indices.len() {
        return Err(LoadError::Uncovered {
            covered,
            indices: indices.len(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests;
