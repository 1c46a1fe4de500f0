//! Collapsing a binary tree into a wide one (see the module docs of [`super`]).

use super::group_capacity;
use super::node::{ChildRef, LeafGroup, LeafTriangle, WideNode};
use super::{
    LEAF_MERGE, LEAF_OPEN_ABOVE, MAX_LEAF_TRIANGLES, MAX_TRIANGLES, WideBvh, assert_width,
};
use crate::aabb::Aabb;
use crate::bvh::build::split_spares_tests;
use crate::bvh::{Bvh, BvhError, BvhNode};
use crate::error::{CapacityError, NonFiniteError, Storage};
use crate::mesh::TriangleMesh;
use crate::query::walk::PadFrame;
use crate::triangle::LANES;
use glam::Vec3A;

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

/// `true` when the leaf run `run` of binary node `b` may be opened into `b`'s two children: `b`
/// is an inner node (a merged subtree, not a binary leaf) of more than [`LEAF_OPEN_ABOVE`]
/// triangles.
fn opens(nodes: &[BvhNode], b: u32, run: &core::ops::Range<usize>) -> bool {
    run.len() > LEAF_OPEN_ABOVE
        && nodes
            .get(b as usize)
            .is_some_and(|n| n.children().is_some())
}

/// `true` when the leaf run `run` of binary node `b` is worth opening for its size: `b` is an
/// inner node whose split [spares a ray entering the root's box enough triangle
/// tests](crate::bvh::LARGE_NODE_SAVING) (the binary build splits a node of at most
/// [`LEAF_OPEN_ABOVE`] triangles only then), in a tree of more than [`LEAF_MERGE`] triangles
/// (a smaller one is at most two eight-lane culls, which more leaves would not make fewer).
/// Such a subtree is an inner entry of [`child_list`], not a leaf run: expanded into the
/// node's spare slots, or a node of its own. A room's walls then each have their own flat
/// box, where one run of three walls had the whole room's.
fn opens_for_size(nodes: &[BvhNode], b: u32, run: &core::ops::Range<usize>) -> bool {
    let root_area = nodes.first().map_or(0.0, |n| n.bounds().surface_area());
    let side = |c: u32| {
        Some(as_leaf(nodes, c)?.len() as f32 * nodes.get(c as usize)?.bounds().surface_area())
    };
    let Some(node) = nodes.get(b as usize) else {
        return false;
    };
    let area = node.bounds().surface_area();
    // Cheap test first: no split spares more than the whole run's `n·A`.
    if !split_spares_tests(run.len(), area, 0.0, root_area) {
        return false;
    }
    let Some((l, r)) = node.children() else {
        return false;
    };
    match (side(l), side(r)) {
        (Some(a), Some(c)) => {
            split_spares_tests(run.len(), area, a + c, root_area) && as_leaf(nodes, 0).is_none()
        }
        _ => false,
    }
}

/// The children of the wide node made from binary node `b`: start with `b`'s two children
/// and, while fewer than `W`, replace one entry by its two children: the inner one with the
/// largest surface area (ties: the first) while there is one, then the leaf run that
/// [`opens`] with the largest surface area. Each entry carries its leaf run when it becomes a
/// leaf ([`as_leaf`], unless it [`opens_for_size`]: then it is an inner entry; computed once
/// per entry). `b` is an inner node that is not a leaf run
/// (a tree that is one leaf run has no node: [`root_leaf`]); a binary leaf `b` gives itself,
/// alone.
fn child_list<const W: usize>(nodes: &[BvhNode], b: u32) -> ChildList<W> {
    let mut out = ChildList {
        node: [0u32; W],
        leaf: [const { None }; W],
        len: 0,
    };
    let Some((l, r)) = nodes.get(b as usize).and_then(BvhNode::children) else {
        out.node[0] = b;
        out.leaf[0] = as_leaf(nodes, b);
        out.len = 1;
        return out;
    };
    // Per entry, its claim to be expanded (`None`: it stays): `(inner, area)`, compared
    // lexicographically, so that every inner entry goes before any leaf run.
    let mut claim: [Option<(bool, f32)>; W] = [None; W];
    let put = |out: &mut ChildList<W>, claim: &mut [Option<(bool, f32)>; W], i: usize, c: u32| {
        out.node[i] = c;
        out.leaf[i] = as_leaf(nodes, c).filter(|run| !opens_for_size(nodes, c, run));
        let area = || nodes.get(c as usize).map(|n| n.bounds().surface_area());
        claim[i] = match &out.leaf[i] {
            None => area().map(|a| (true, a)),
            Some(run) if opens(nodes, c, run) => area().map(|a| (false, a)),
            Some(_) => None,
        };
    };
    put(&mut out, &mut claim, 0, l);
    put(&mut out, &mut claim, 1, r);
    let mut len = 2;
    while len < W {
        let mut best: Option<(usize, (bool, f32))> = None;
        for (i, c) in claim[..len].iter().enumerate() {
            if let Some(c) = *c
                && best.is_none_or(|(_, b)| (c.0 && !b.0) || (c.0 == b.0 && c.1 > b.1))
            {
                best = Some((i, c));
            }
        }
        let Some((i, _)) = best else { break };
        let Some((cl, cr)) = nodes.get(out.node[i] as usize).and_then(BvhNode::children) else {
            break;
        };
        put(&mut out, &mut claim, i, cl);
        put(&mut out, &mut claim, len, cr);
        len += 1;
    }
    out.len = len;
    out
}

/// The children [`child_list`] chose: binary node and, for a leaf, its run.
struct ChildList<const W: usize> {
    node: [u32; W],
    leaf: [Option<core::ops::Range<usize>>; W],
    len: usize,
}

impl<const W: usize> ChildList<W> {
    /// Places the leaf runs of the list after slot `slots` (the slots in use so far, moved to
    /// the end of the last run), each by [`place_leaf`], best fit first: of the runs left, one
    /// that starts right at the end of the previous one (no lane skipped) before one that does
    /// not; of those, one that ends its last group exactly, then the one that fills the
    /// current group furthest, then the longest, then the first. Returns each entry's first
    /// slot (`usize::MAX` for an inner entry). A node's runs stay side by side and each
    /// touches the fewest groups its length allows, as in list order, with fewer lanes
    /// skipped between them: a cube's runs of 2, 8 and 2 take 3 groups where list order took
    /// 4. (A run of `4q + m` lanes, `m` in `1..=4`, fits at lane `r` of a group without a
    /// skip exactly when `r + m ≤ 4`: the order is a bin packing of the `m`s into groups.)
    fn place_runs(&self, slots: &mut usize) -> [usize; W] {
        let mut start = [usize::MAX; W];
        let len = |i: usize| self.leaf[i].as_ref().map_or(0, core::ops::Range::len);
        let mut left: u32 = (0..self.len.min(W))
            .filter(|&i| self.leaf[i].is_some())
            .fold(0, |m, i| m | 1 << i);
        while left != 0 {
            let mut pick = left.trailing_zeros() as usize;
            let key = |i: usize| {
                let (end, c) = (*slots, len(i));
                let fits = place_leaf(end, c) == end;
                // The lanes the run's last group ends at, past the current group's start.
                let fill = end % LANES + (c + LANES - 1) % LANES + 1;
                (fits, fits && fill == LANES, if fits { fill } else { 0 }, c)
            };
            let mut best = key(pick);
            let mut rest = left & (left - 1);
            while rest != 0 {
                let i = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                let k = key(i);
                if k > best {
                    (pick, best) = (i, k);
                }
            }
            left &= !(1 << pick);
            let first = place_leaf(*slots, len(pick));
            start[pick] = first;
            *slots = first + len(pick);
        }
        start
    }

    fn iter(&self) -> impl Iterator<Item = (u32, Option<core::ops::Range<usize>>)> + '_ {
        self.node
            .iter()
            .zip(&self.leaf)
            .take(self.len)
            .map(|(&c, l)| (c, l.clone()))
    }
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

/// The first slot of a leaf of `count` triangles placed after slot `end` (the slots in use so
/// far): `end` itself, unless the run would then touch more [`LeafGroup`]s than the
/// `⌈count/4⌉` it needs, in which case the next group boundary (the lanes skipped stay
/// empty). A leaf then reads the fewest groups possible, for a few more groups in the tree;
/// the padding of a leaf is at most
/// `4⌈count/4⌉ − 1 − count` lanes, so `7N/4` slots bound any tree ([`group_capacity`]).
#[inline]
pub(super) const fn place_leaf(end: usize, count: usize) -> usize {
    let touched = (end + count).div_ceil(LANES) - end / LANES;
    if count > 0 && touched > count.div_ceil(LANES) {
        end.next_multiple_of(LANES)
    } else {
        end
    }
}

/// What the collapse needs: wide nodes, and triangle slots (each node's leaf runs placed by
/// [`ChildList::place_runs`], node after node in the order the collapse writes them).
#[derive(Clone, Copy, Debug)]
struct Plan {
    nodes: usize,
    slots: usize,
    /// The first triangle (in walk order) outside the box of the binary node its leaf run is
    /// made from ([`run_outside`]), when the walk was given the mesh.
    outside: Option<u32>,
}

impl Plan {
    fn groups(&self) -> usize {
        self.slots.div_ceil(LANES)
    }
}

/// The leaf run that is the whole tree, when the binary root is one ([`as_leaf`]: a binary
/// leaf, or a subtree of at most [`LEAF_MERGE`] triangles) that does not [`open`](opens): the
/// wide tree then has no node, its root is that leaf. A root node would hold that one leaf
/// alone, and cost 224 bytes and every ray its node test for nothing. A run that opens (more
/// than [`LEAF_OPEN_ABOVE`] triangles in a binary subtree) gets its root node: its children's
/// boxes spare a ray the culls of the halves it misses (a cube's two faces on `±x`, flat
/// boxes, and the eight triangles between: a root leaf of 12 cost its camera and random rays
/// 9 % more instructions, its shadow and ambient-occlusion rays 15 %; `docs/performance.md`).
fn root_leaf(nodes: &[BvhNode]) -> Option<core::ops::Range<usize>> {
    as_leaf(nodes, 0).filter(|run| !opens(nodes, 0, run))
}

/// [`BvhError::LeafTooLarge`] for a leaf run of more than [`MAX_LEAF_TRIANGLES`].
fn leaf_fits(range: &core::ops::Range<usize>) -> Result<(), BvhError> {
    if range.len() > MAX_LEAF_TRIANGLES {
        return Err(BvhError::LeafTooLarge {
            count: range.len(),
            max: MAX_LEAF_TRIANGLES,
        });
    }
    Ok(())
}

/// [`BvhError::TooManyTriangles`] for more than [`MAX_TRIANGLES`] triangles or slots.
fn slots_fit(slots: usize) -> Result<(), BvhError> {
    if slots > MAX_TRIANGLES {
        return Err(BvhError::TooManyTriangles {
            count: slots,
            max: MAX_TRIANGLES,
        });
    }
    Ok(())
}

/// The error of a walk whose pending nodes outgrow [`Pending`] (a broken binary tree deeper
/// than `MAX_DEPTH`), reported as a leaf that cannot be placed.
const PENDING_FULL: BvhError = BvhError::LeafTooLarge {
    count: 0,
    max: MAX_LEAF_TRIANGLES,
};

/// The first triangle of the leaf run `run` (of `indices`) that `mesh` gives outside the box
/// of `node`, the binary node the run is made from, whose box the wide tree gives the run (a
/// triangle the mesh cannot give counts as outside). `None` when the binary tree bounds every
/// triangle of the run, as it does those of its source ([`BvhNode::holds`]). The box of the
/// run's vertices is compared with `node`'s first, once (the vertices are finite:
/// [`check_finite`] refuses the tree otherwise); only when it is not inside are the triangles
/// tested one by one.
fn run_outside(
    node: &BvhNode,
    indices: &[u32],
    run: core::ops::Range<usize>,
    mesh: &TriangleMesh<'_>,
) -> Option<u32> {
    let prims = indices.get(run)?;
    let (mut lo, mut hi, mut missing) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, false);
    for &p in prims {
        let Some(v) = mesh.triangle(p as usize) else {
            missing = true;
            continue;
        };
        for q in v {
            let q = Vec3A::from(q);
            (lo, hi) = (lo.min(q), hi.max(q));
        }
    }
    if !missing && node.holds_box(lo, hi) {
        return None;
    }
    prims
        .iter()
        .copied()
        .find(|&p| !mesh.triangle(p as usize).is_some_and(|v| node.holds(&v)))
}

/// Walks the collapse without writing: what it needs ([`Plan`]), or the first reason it
/// cannot be built (a leaf too large, a broken binary tree). With `source` (the tree's index
/// array and the mesh), also reads every triangle of the tree and records the first outside
/// its run's box ([`Plan::outside`]).
fn plan<const W: usize>(
    nodes: &[BvhNode],
    source: Option<(&[u32], &TriangleMesh<'_>)>,
) -> Result<Plan, BvhError> {
    if nodes.is_empty() {
        return Ok(Plan {
            nodes: 0,
            slots: 0,
            outside: None,
        });
    }
    let outside = |b: u32, run: &core::ops::Range<usize>| {
        let node = nodes.get(b as usize)?;
        source.and_then(|(indices, mesh)| run_outside(node, indices, run.clone(), mesh))
    };
    if let Some(run) = root_leaf(nodes) {
        leaf_fits(&run)?;
        return Ok(Plan {
            nodes: 0,
            slots: run.len(),
            outside: outside(0, &run),
        });
    }
    const { assert_width(W) };
    let mut pending = Pending::new();
    let mut count = 1usize;
    let mut slots = 0usize;
    let mut first_outside = None;
    if !pending.push((0, 0)) {
        return Err(PENDING_FULL);
    }
    while let Some((b, _)) = pending.pop() {
        let list = child_list::<W>(nodes, b);
        for (c, leaf) in list.iter() {
            if let Some(range) = leaf {
                leaf_fits(&range)?;
                if first_outside.is_none() {
                    first_outside = outside(c, &range);
                }
            } else {
                count += 1;
                if !pending.push((c, 0)) {
                    return Err(PENDING_FULL);
                }
            }
        }
        list.place_runs(&mut slots);
    }
    Ok(Plan {
        nodes: count,
        slots,
        outside: first_outside,
    })
}

/// The checks of [`WideBvh::from_binary`] that need no storage: `mesh` has as many triangles
/// as `binary`'s source, the triangle count fits, every leaf fits ([`plan`]), every triangle
/// of the tree has finite vertices, and lies in the box the wide tree gives it (a mesh that
/// is not the tree's source: [`BvhError::TriangleOutsideTree`]). Returns what the `W`-wide
/// tree needs.
fn check<const W: usize, BN, BI>(
    binary: &Bvh<BN, BI>,
    mesh: &TriangleMesh<'_>,
) -> Result<Plan, BvhError>
where
    BN: AsRef<[BvhNode]>,
    BI: AsRef<[u32]>,
{
    check_counts(binary, mesh)?;
    let needed = plan::<W>(binary.nodes(), Some((binary.indices(), mesh)))?;
    slots_fit(needed.slots)?;
    check_finite(binary, mesh)?;
    if let Some(p) = needed.outside {
        return Err(BvhError::TriangleOutsideTree {
            triangle: p as usize,
        });
    }
    Ok(needed)
}

/// The checks of [`check`] that need no plan: the mesh is the tree's source (by count) and
/// the tree has at most [`MAX_TRIANGLES`] triangles.
fn check_counts<BN, BI>(binary: &Bvh<BN, BI>, mesh: &TriangleMesh<'_>) -> Result<(), BvhError>
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
    slots_fit(binary.indices().len())
}

/// Every triangle of the tree has finite vertices.
fn check_finite<BN, BI>(binary: &Bvh<BN, BI>, mesh: &TriangleMesh<'_>) -> Result<(), BvhError>
where
    BN: AsRef<[BvhNode]>,
    BI: AsRef<[u32]>,
{
    let indices = binary.indices();
    // Every triangle of the tree must have finite vertices. When every position is finite
    // and every vertex index in range (two sequential passes), all of them do; only
    // otherwise are the tree's triangles checked one by one (a random-access pass).
    let n_pos = mesh.positions.len();
    let all_usable = mesh.positions.iter().all(|p| p.is_finite())
        && mesh
            .triangles
            .iter()
            .all(|t| t.iter().all(|&i| (i as usize) < n_pos));
    if !all_usable {
        for &p in indices {
            let ok = mesh
                .triangle(p as usize)
                .is_some_and(|v| v.iter().all(|x| x.is_finite()));
            if !ok {
                return Err(NonFiniteError::primitive(p as usize).into());
            }
        }
    }
    Ok(())
}

impl<const W: usize, N, T> WideBvh<W, N, T>
where
    N: AsRef<[WideNode<W>]> + AsMut<[WideNode<W>]>,
    T: AsRef<[LeafGroup]> + AsMut<[LeafGroup]>,
{
    /// Exact number of wide nodes [`WideBvh::from_binary`] needs for `binary` (0 for an empty
    /// tree).
    ///
    /// # Errors
    ///
    /// As `from_binary` for a leaf of more than [`MAX_LEAF_TRIANGLES`].
    pub fn node_count_for<BN, BI>(binary: &Bvh<BN, BI>) -> Result<usize, BvhError>
    where
        BN: AsRef<[BvhNode]>,
        BI: AsRef<[u32]>,
    {
        plan::<W>(binary.nodes(), None).map(|p| p.nodes)
    }

    /// Exact number of [`LeafGroup`]s [`WideBvh::from_binary`] needs for `binary` (at most
    /// [`group_capacity`] of its triangle count).
    ///
    /// # Errors
    ///
    /// As [`WideBvh::node_count_for`].
    pub fn group_count_for<BN, BI>(binary: &Bvh<BN, BI>) -> Result<usize, BvhError>
    where
        BN: AsRef<[BvhNode]>,
        BI: AsRef<[u32]>,
    {
        plan::<W>(binary.nodes(), None).map(|p| p.groups())
    }

    /// Collapses `binary`, built over `mesh`, into `nodes` and `groups` (see the module
    /// docs).
    ///
    /// # Errors
    ///
    /// All returned before any storage is written:
    /// [`BvhError::SourceLengthMismatch`] (`mesh` has another triangle count than `binary`'s
    /// source), [`BvhError::TooManyTriangles`], [`BvhError::LeafTooLarge`],
    /// [`BvhError::Capacity`] (fewer than [`WideBvh::node_count_for`] nodes or
    /// [`WideBvh::group_count_for`] groups; [`group_capacity`] of the triangle count always
    /// suffices),
    /// [`BvhError::NonFinite`] (a triangle of the tree no longer has finite vertices),
    /// [`BvhError::TriangleOutsideTree`] (a triangle of `mesh` lies outside the box of the
    /// binary subtree its wide leaf is made from: `mesh` is not `binary`'s source, or moved
    /// since without a [`Bvh::refit`]). A mesh that passes is bounded by every box of the
    /// wide tree, so its queries are exact for it. (The walk that sizes the tree reads every
    /// triangle of the tree for this check.)
    pub fn from_binary<BN, BI>(
        binary: &Bvh<BN, BI>,
        mesh: &TriangleMesh<'_>,
        nodes: N,
        groups: T,
    ) -> Result<Self, BvhError>
    where
        BN: AsRef<[BvhNode]>,
        BI: AsRef<[u32]>,
    {
        let needed = check::<W, _, _>(binary, mesh)?;
        Self::write::<BN, BI, false>(binary, mesh, Some(needed), nodes, groups)
    }

    /// [`WideBvh::from_binary`] with storage the caller makes once the sizes are known:
    /// `storage(nodes, groups)` is called, after every check on `binary` and `mesh` passed,
    /// with the exact node and group counts ([`WideBvh::node_count_for`],
    /// [`WideBvh::group_count_for`]), and returns the storage (larger is fine). Plans the collapse once
    /// where `node_count_for` followed by `from_binary` plans it twice.
    ///
    /// # Errors
    ///
    /// As [`WideBvh::from_binary`]; the storage errors only when `storage` returns less than
    /// asked for (nothing is written then).
    pub fn from_binary_with<BN, BI>(
        binary: &Bvh<BN, BI>,
        mesh: &TriangleMesh<'_>,
        storage: impl FnOnce(usize, usize) -> (N, T),
    ) -> Result<Self, BvhError>
    where
        BN: AsRef<[BvhNode]>,
        BI: AsRef<[u32]>,
    {
        let needed = check::<W, _, _>(binary, mesh)?;
        let (nodes, groups) = storage(needed.nodes, needed.groups());
        Self::write::<BN, BI, false>(binary, mesh, Some(needed), nodes, groups)
    }

    /// Wide nodes that always suffice for collapsing `binary`, whatever its shape:
    /// `⌈M / 2⌉` for its `M` nodes. Each wide node stands for a distinct inner node of the
    /// binary tree (the root's, or an inner child it does not open), and a binary tree of `M`
    /// nodes has at most `(M − 1) / 2` inner ones (a pad node counted in `M` only lowers
    /// that). Prefer the exact [`WideBvh::node_count_for`] where storage must be tight.
    pub fn node_bound_for<BN, BI>(binary: &Bvh<BN, BI>) -> usize
    where
        BN: AsRef<[BvhNode]>,
        BI: AsRef<[u32]>,
    {
        binary.nodes().len().div_ceil(2)
    }

    /// [`WideBvh::from_binary`] in one walk of the tree where `from_binary` and
    /// [`WideBvh::from_binary_with`] make two (the first to count what the storage needs;
    /// 5–7 % of a build): `nodes` and `groups` must hold the bounds
    /// [`WideBvh::node_bound_for`] and [`group_capacity`] of the triangle count, of which the tree uses [`WideBvh::nodes`] and [`WideBvh::groups`] (memory never
    /// written can stay unmapped: the frontend's storage is). Same tree as `from_binary`.
    ///
    /// # Errors
    ///
    /// As [`WideBvh::from_binary`], with [`BvhError::Capacity`] for storage below those bounds.
    /// A leaf too large ([`BvhError::LeafTooLarge`]), [`BvhError::TooManyTriangles`] from
    /// the padding, a tree of shared subtrees that outgrows the node bound
    /// ([`BvhError::Capacity`]), or a triangle outside its box
    /// ([`BvhError::TriangleOutsideTree`]: checked as each triangle is copied, at no extra
    /// pass) are found during the walk: the storage has been partly written then.
    pub fn from_binary_in<BN, BI>(
        binary: &Bvh<BN, BI>,
        mesh: &TriangleMesh<'_>,
        nodes: N,
        groups: T,
    ) -> Result<Self, BvhError>
    where
        BN: AsRef<[BvhNode]>,
        BI: AsRef<[u32]>,
    {
        check_counts(binary, mesh)?;
        let node_bound = Self::node_bound_for(binary);
        CapacityError::check(Storage::BvhNodes, node_bound, nodes.as_ref().len())?;
        let group_bound = group_capacity(binary.indices().len());
        CapacityError::check(
            Storage::WideTriangleGroups,
            group_bound,
            groups.as_ref().len(),
        )?;
        check_finite(binary, mesh)?;
        Self::write::<BN, BI, true>(binary, mesh, None, nodes, groups)
    }

    /// The collapse itself, for a tree that passed [`check_counts`] and [`check_finite`]:
    /// with its `plan` ([`check`] passed) into storage checked here first, or without one
    /// (each leaf, the slot count and the storage checked as the walk goes, and with
    /// `CHECK_BOXES` every triangle's box as it is copied: `true` exactly without a plan, a
    /// parameter so that the planned collapse's copy loop has no trace of the check).
    fn write<BN, BI, const CHECK_BOXES: bool>(
        binary: &Bvh<BN, BI>,
        mesh: &TriangleMesh<'_>,
        plan: Option<Plan>,
        mut nodes: N,
        mut groups: T,
    ) -> Result<Self, BvhError>
    where
        BN: AsRef<[BvhNode]>,
        BI: AsRef<[u32]>,
    {
        // Every constructor comes here: a width other than 2, 4 or 8 does not compile.
        const { assert_width(W) };
        let indices = binary.indices();
        let bnodes = binary.nodes();
        if let Some(plan) = plan {
            CapacityError::check(Storage::BvhNodes, plan.nodes, nodes.as_ref().len())?;
            CapacityError::check(
                Storage::WideTriangleGroups,
                plan.groups(),
                groups.as_ref().len(),
            )?;
        }

        // Each node's leaf runs as the walk meets the node, placed by `place_runs` (as `plan`),
        // each slot after the runs placed before. A group is emptied when the first run
        // reaching it is copied (`emptied` groups so far: every group a run touches is emptied
        // before the run's lanes are written, never after); the groups no run reaches, at
        // the end.
        let out = groups.as_mut();
        let group_count = out.len();
        let mut emptied = 0usize;
        let mut empty_to = |out: &mut [LeafGroup], end: usize| {
            for group in out.iter_mut().take(end).skip(emptied) {
                *group = LeafGroup::EMPTY;
            }
            emptied = emptied.max(end);
        };
        let mut slots = 0usize;
        // Without a plan (which checked it), the run's triangles are checked to lie in the
        // box of its binary node `bn` as they are copied: the box of the vertices the copy
        // reads anyway, against `bn`'s once per run (the vertices are finite: `check_finite`);
        // when it is not inside, [`run_outside`] names the triangle.
        let mut copy_leaf = |start: usize,
                             range: core::ops::Range<usize>,
                             bn: &BvhNode|
         -> Result<usize, BvhError> {
            empty_to(out, (start + range.len()).div_ceil(LANES));
            let (mut lo, mut hi, mut missing) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, false);
            for (slot, &p) in (start..).zip(indices.get(range.clone()).unwrap_or(&[])) {
                let v = mesh.triangle(p as usize);
                if CHECK_BOXES {
                    match v {
                        Some(v) => {
                            for q in v {
                                let q = Vec3A::from(q);
                                (lo, hi) = (lo.min(q), hi.max(q));
                            }
                        }
                        None => missing = true,
                    }
                }
                if let (Some(group), Some(v)) = (out.get_mut(slot / LANES), v) {
                    let v = [v[0].to_array(), v[1].to_array(), v[2].to_array()];
                    group.set(slot % LANES, &LeafTriangle { v, prim: p });
                }
            }
            if CHECK_BOXES
                && (missing || !bn.holds_box(lo, hi))
                && let Some(p) = run_outside(bn, indices, range, mesh)
            {
                return Err(BvhError::TriangleOutsideTree {
                    triangle: p as usize,
                });
            }
            Ok(start)
        };
        let slots_stored = |slots: usize| -> Result<(), BvhError> {
            slots_fit(slots)?;
            CapacityError::check(
                Storage::WideTriangleGroups,
                slots.div_ceil(LANES),
                group_count,
            )?;
            Ok(())
        };

        let wide = nodes.as_mut();
        let node_count = wide.len();
        let mut next = 0u32;
        let mut root = ChildRef::EMPTY;
        if let Some(range) = root_leaf(bnodes) {
            leaf_fits(&range)?;
            let len = range.len() as u32;
            slots = range.len();
            slots_stored(slots)?;
            let first = match bnodes.first() {
                Some(bn) => copy_leaf(0, range, bn)?,
                None => 0,
            };
            root = ChildRef::leaf(first as u32, len).unwrap_or(ChildRef::EMPTY);
        } else if !bnodes.is_empty() {
            CapacityError::check(Storage::BvhNodes, 1, node_count)?;
            root = 0;
            wide[0] = WideNode::EMPTY;
            next = 1;
            let mut pending = Pending::new();
            pending.push((0, 0));
            while let Some((b, slot)) = pending.pop() {
                let mut node = WideNode::<W>::EMPTY;
                let list = child_list::<W>(bnodes, b);
                for (_, leaf) in list.iter() {
                    if let Some(range) = leaf {
                        leaf_fits(&range)?;
                    }
                }
                let starts = list.place_runs(&mut slots);
                slots_stored(slots)?;
                for (i, (c, leaf)) in list.iter().enumerate() {
                    let Some(bn) = bnodes.get(c as usize) else {
                        continue;
                    };
                    let reference = if let Some(range) = leaf {
                        // Checked above: count ≤ MAX_LEAF_TRIANGLES, slots ≤ MAX_TRIANGLES.
                        let len = range.len() as u32;
                        let start = starts.get(i).copied().unwrap_or(slots);
                        ChildRef::leaf(copy_leaf(start, range, bn)? as u32, len)
                            .unwrap_or(ChildRef::EMPTY)
                    } else {
                        let child = next;
                        next += 1;
                        CapacityError::check(Storage::BvhNodes, next as usize, node_count)?;
                        if let Some(n) = wide.get_mut(child as usize) {
                            *n = WideNode::EMPTY;
                        }
                        if !pending.push((c, child)) {
                            return Err(PENDING_FULL);
                        }
                        child
                    };
                    node.set_child(i, &bn.bounds(), reference);
                }
                if let Some(n) = wide.get_mut(slot as usize) {
                    *n = node;
                }
            }
        }
        empty_to(out, slots.div_ceil(LANES));
        let mut tree = Self {
            nodes,
            groups,
            node_count: next,
            triangle_count: indices.len() as u32,
            slot_count: slots as u32,
            source_len: mesh.len(),
            root,
            root_box: Aabb::EMPTY,
            root_local: Aabb::EMPTY,
            pad_frame: PadFrame::relative(&Aabb::EMPTY),
        };
        tree.set_frame();
        Ok(tree)
    }
}

#[cfg(test)]
mod tests;
