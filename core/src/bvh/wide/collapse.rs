//! Collapsing a binary tree into a wide one (see the module docs of [`super`]).

use super::node::{ChildRef, LeafGroup, LeafTriangle, WideNode};
use super::{LEAF_MERGE, MAX_LEAF_TRIANGLES, MAX_TRIANGLES, WideBvh, group_capacity};
use crate::bvh::{Bvh, BvhError, BvhNode, TriangleMesh};
use crate::triangle::LANES;

/// The leaf run binary node `b` becomes, if it becomes one: a binary leaf, or an inner node
/// whose subtree holds at most [`LEAF_MERGE`] primitives (one wide leaf tests them in a row,
/// cheaper than a node visit). The subtree is walked only as far as that bound: its nodes
/// waiting on the stack each hold a primitive, so more than `LEAF_MERGE` of them, or more
/// than `LEAF_MERGE` primitives seen, means "no" at once. A subtree's primitives are
/// contiguous in index order (binary build), so the run is their index range.
fn as_leaf(nodes: &[BvhNode], b: u32) -> Option<core::ops::Range<usize>> {
    let node = nodes.get(b as usize)?;
    if let Some(r) = node.primitive_range() {
        return Some(r);
    }
    let mut stack = [0u32; LEAF_MERGE];
    stack[0] = b;
    let mut sp = 1usize;
    let (mut lo, mut hi, mut total) = (usize::MAX, 0usize, 0usize);
    while sp > 0 {
        sp -= 1;
        let n = nodes.get(stack[sp] as usize)?;
        if let Some((l, r)) = n.children() {
            if sp + 2 > LEAF_MERGE {
                return None;
            }
            stack[sp] = r;
            stack[sp + 1] = l;
            sp += 2;
        } else {
            let run = n.primitive_range()?;
            total += run.len();
            if total > LEAF_MERGE {
                return None;
            }
            lo = lo.min(run.start);
            hi = hi.max(run.end);
        }
    }
    (total > 0 && hi - lo == total).then_some(lo..hi)
}

/// The binary nodes that become the children of the wide node made from binary node `b`: start
/// with `b`'s two children and, while fewer than `W`, replace the inner one with the largest
/// surface area (ties: the first) by its two children. A leaf `b` gives itself, alone.
fn child_list<const W: usize>(nodes: &[BvhNode], b: u32) -> ([u32; W], usize) {
    let mut list = [0u32; W];
    let Some((l, r)) = nodes
        .get(b as usize)
        .and_then(BvhNode::children)
        .filter(|_| as_leaf(nodes, b).is_none())
    else {
        list[0] = b;
        return (list, 1);
    };
    // Per entry, the area by which it competes for expansion (`None`: it stays, a leaf run),
    // computed once when it enters the list.
    let expandable = |c: u32| {
        nodes
            .get(c as usize)
            .filter(|_| as_leaf(nodes, c).is_none())
            .map(|n| n.bounds().surface_area())
    };
    let mut area: [Option<f32>; W] = [None; W];
    list[0] = l;
    list[1] = r;
    area[0] = expandable(l);
    area[1] = expandable(r);
    let mut len = 2;
    while len < W {
        let mut best: Option<(usize, f32)> = None;
        for (i, a) in area[..len].iter().enumerate() {
            if let Some(a) = *a
                && best.is_none_or(|(_, b)| a > b)
            {
                best = Some((i, a));
            }
        }
        let Some((i, _)) = best else { break };
        let Some((cl, cr)) = nodes.get(list[i] as usize).and_then(BvhNode::children) else {
            break;
        };
        list[i] = cl;
        area[i] = expandable(cl);
        list[len] = cr;
        area[len] = expandable(cr);
        len += 1;
    }
    (list, len)
}

/// Pending wide nodes of the depth-first walk: `(binary node, wide node)`. At most `W − 1`
/// per level are pending besides the one being expanded, over at most `MAX_DEPTH` levels, for
/// `W ≤ 8`.
struct Pending {
    items: [(u32, u32); 8 * crate::bvh::MAX_DEPTH + 1],
    len: usize,
}

impl Pending {
    fn new() -> Self {
        Self {
            items: [(0, 0); 8 * crate::bvh::MAX_DEPTH + 1],
            len: 0,
        }
    }
    fn push(&mut self, item: (u32, u32)) -> bool {
        match self.items.get_mut(self.len) {
            Some(slot) => {
                *slot = item;
                self.len += 1;
                true
            }
            None => false,
        }
    }
    fn pop(&mut self) -> Option<(u32, u32)> {
        self.len = self.len.checked_sub(1)?;
        Some(self.items[self.len])
    }
}

/// Walks the collapse without writing: the wide node count, or the first reason it cannot be
/// built (a leaf too large, a broken binary tree).
fn plan<const W: usize>(nodes: &[BvhNode]) -> Result<usize, BvhError> {
    if nodes.is_empty() {
        return Ok(0);
    }
    const { assert!(W >= 2 && W <= 8) };
    let mut pending = Pending::new();
    let mut count = 1usize;
    if !pending.push((0, 0)) {
        return Err(BvhError::LeafTooLarge { count: 0 });
    }
    while let Some((b, _)) = pending.pop() {
        let (list, len) = child_list::<W>(nodes, b);
        for &c in &list[..len] {
            if let Some(range) = as_leaf(nodes, c) {
                if range.len() > MAX_LEAF_TRIANGLES {
                    return Err(BvhError::LeafTooLarge { count: range.len() });
                }
            } else {
                count += 1;
                if !pending.push((c, 0)) {
                    return Err(BvhError::LeafTooLarge { count: 0 });
                }
            }
        }
    }
    Ok(count)
}

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]> + AsMut<[WideNode<W>]>,
    T: AsRef<[LeafGroup]> + AsMut<[LeafGroup]>,
{
    /// Exact number of wide nodes [`WideBvh::from_binary`] needs for `binary` (0 for an empty
    /// tree). Errors as `from_binary` for a leaf of more than [`MAX_LEAF_TRIANGLES`].
    pub fn node_count_for<BN, BI>(binary: &Bvh<BN, BI>) -> Result<usize, BvhError>
    where
        BN: AsRef<[BvhNode]>,
        BI: AsRef<[u32]>,
    {
        plan::<W>(binary.nodes())
    }

    /// Collapses `binary`, built over `mesh`, into `nodes` and `groups` (see the module
    /// docs).
    ///
    /// Errors, all returned before any storage is written:
    /// [`BvhError::SourceLengthMismatch`] (`mesh` has another triangle count than `binary`'s
    /// source), [`BvhError::TooManyTriangles`], [`BvhError::LeafTooLarge`],
    /// [`BvhError::NodeStorageTooSmall`] (fewer than [`WideBvh::node_count_for`] nodes),
    /// [`BvhError::TriangleStorageTooSmall`] (fewer than [`group_capacity`] groups for the
    /// tree's triangles; the error counts groups),
    /// [`BvhError::NonFinitePrimitive`] (a triangle of the tree no longer has finite vertices).
    pub fn from_binary<BN, BI>(
        binary: &Bvh<BN, BI>,
        mesh: &TriangleMesh<'_>,
        mut nodes: N,
        mut groups: T,
    ) -> Result<Self, BvhError>
    where
        BN: AsRef<[BvhNode]>,
        BI: AsRef<[u32]>,
    {
        if mesh.len() != binary.source_len() {
            return Err(BvhError::SourceLengthMismatch {
                expected: binary.source_len(),
                found: mesh.len(),
            });
        }
        let indices = binary.indices();
        if indices.len() > MAX_TRIANGLES {
            return Err(BvhError::TooManyTriangles {
                count: indices.len(),
            });
        }
        let bnodes = binary.nodes();
        let needed = plan::<W>(bnodes)?;
        if nodes.as_ref().len() < needed {
            return Err(BvhError::NodeStorageTooSmall {
                needed,
                available: nodes.as_ref().len(),
            });
        }
        let needed_groups = group_capacity(indices.len());
        if groups.as_ref().len() < needed_groups {
            return Err(BvhError::TriangleStorageTooSmall {
                needed: needed_groups,
                available: groups.as_ref().len(),
            });
        }
        for &p in indices {
            let ok = mesh
                .triangle(p as usize)
                .is_some_and(|v| v.iter().all(|x| x.is_finite()));
            if !ok {
                return Err(BvhError::NonFinitePrimitive { index: p as usize });
            }
        }

        // Triangles in the binary index order, so a binary leaf's run is the wide leaf's run.
        let out = groups.as_mut();
        for (group, chunk) in out.iter_mut().zip(indices.chunks(LANES)) {
            *group = LeafGroup::EMPTY;
            for (lane, &p) in chunk.iter().enumerate() {
                if let Some(v) = mesh.triangle(p as usize) {
                    let v = [v[0].to_array(), v[1].to_array(), v[2].to_array()];
                    group.set(lane, &LeafTriangle { v, prim: p });
                }
            }
        }

        let wide = nodes.as_mut();
        let mut next = 0u32;
        if needed > 0 {
            wide[0] = WideNode::EMPTY;
            next = 1;
            let mut pending = Pending::new();
            pending.push((0, 0));
            while let Some((b, slot)) = pending.pop() {
                let (list, len) = child_list::<W>(bnodes, b);
                let mut node = WideNode::<W>::EMPTY;
                for (i, &c) in list[..len].iter().enumerate() {
                    let Some(bn) = bnodes.get(c as usize) else {
                        continue;
                    };
                    let reference = if let Some(range) = as_leaf(bnodes, c) {
                        // Checked by `plan`: count ≤ MAX_LEAF_TRIANGLES, start < MAX_TRIANGLES.
                        ChildRef::leaf(range.start as u32, range.len() as u32)
                            .unwrap_or(ChildRef::EMPTY)
                    } else {
                        let child = next;
                        next += 1;
                        if let Some(n) = wide.get_mut(child as usize) {
                            *n = WideNode::EMPTY;
                        }
                        pending.push((c, child));
                        child
                    };
                    node.set_child(i, &bn.bounds(), reference);
                }
                if let Some(n) = wide.get_mut(slot as usize) {
                    *n = node;
                }
            }
        }
        Ok(Self {
            nodes,
            groups,
            node_count: next,
            triangle_count: indices.len() as u32,
            source_len: mesh.len(),
            extent: crate::bvh::extent_of(&binary.bounds()),
        })
    }
}
