//! The broad phase: simultaneous descent of two BVHs, the second placed by a transform, on a
//! fixed stack of node pairs; leaf pairs go to the exact triangle–triangle test.

use super::body::{Body, DBox, Placement};
use super::tri_tri::triangles_intersect;
use super::{CollideError, PAIR_STACK_SIZE};
use crate::aabb::Aabb;
use crate::bvh::BvhNode;
use crate::mesh::Primitive;
use crate::transform::Transform;
use core::ops::ControlFlow;
use glam::Vec3;

/// Which tree a node pair descends into: the first when it is an inner node and either the
/// second is a leaf or the first's box is at least as large (sum of extents); the second
/// otherwise. `None` for two leaves.
pub(super) fn split_first(a: &BvhNode, b: &BvhNode) -> Option<bool> {
    match (a.is_leaf(), b.is_leaf()) {
        (true, true) => None,
        (false, true) => Some(true),
        (true, false) => Some(false),
        (false, false) => {
            let size = |n: &BvhNode| n.bounds().extent().element_sum();
            Some(size(a) >= size(b))
        }
    }
}

/// The two child pairs of the pair `(ia, ib)` when descending into the first (`true`) or the
/// second tree.
pub(super) fn child_pairs(node: &BvhNode, ia: u32, ib: u32, first: bool) -> [(u32, u32); 2] {
    let (l, r) = node.children().unwrap_or((u32::MAX, u32::MAX));
    if first {
        [(l, ib), (r, ib)]
    } else {
        [(ia, l), (ia, r)]
    }
}

/// A fixed stack of pending node pairs with a payload (see [`PAIR_STACK_SIZE`]).
pub(super) struct PairStack<T: Copy> {
    entries: [(u32, u32, T); PAIR_STACK_SIZE],
    len: usize,
}

impl<T: Copy> PairStack<T> {
    pub(super) fn new(fill: T) -> Self {
        Self {
            entries: [(0, 0, fill); PAIR_STACK_SIZE],
            len: 0,
        }
    }

    /// # Errors
    ///
    /// [`CollideError::TreeTooDeep`] when full (unreachable for valid trees).
    pub(super) fn push(&mut self, e: (u32, u32, T)) -> Result<(), CollideError> {
        let slot = self
            .entries
            .get_mut(self.len)
            .ok_or(CollideError::TreeTooDeep)?;
        *slot = e;
        self.len += 1;
        Ok(())
    }

    pub(super) fn pop(&mut self) -> Option<(u32, u32, T)> {
        self.len = self.len.checked_sub(1)?;
        self.entries.get(self.len).copied()
    }
}

/// Calls `found(a, b)` for every pair of intersecting triangles (`a` of the first body, `b`
/// of the second placed by `b_to_a`), in traversal order, until it breaks.
pub(super) fn for_each_colliding<NA, IA, NB, IB>(
    a: &Body<'_, NA, IA>,
    b: &Body<'_, NB, IB>,
    b_to_a: &Transform,
    mut found: impl FnMut(u32, u32) -> ControlFlow<()>,
) -> Result<(), CollideError>
where
    NA: AsRef<[BvhNode]>,
    IA: AsRef<[u32]>,
    NB: AsRef<[BvhNode]>,
    IB: AsRef<[u32]>,
{
    let place = Placement::new(b_to_a);
    let (na, nb) = (a.nodes(), b.nodes());
    let overlap = |ia: u32, ib: u32| -> bool {
        match (na.get(ia as usize), nb.get(ib as usize)) {
            (Some(x), Some(y)) => place
                .place_box(&y.bounds())
                .is_some_and(|yb| DBox::from_aabb(&x.bounds()).overlaps(&yb)),
            _ => false,
        }
    };
    let mut stack = PairStack::new(());
    let mut current = overlap(0, 0).then_some((0u32, 0u32));
    while let Some((ia, ib)) = current {
        current = None;
        let (Some(x), Some(y)) = (na.get(ia as usize), nb.get(ib as usize)) else {
            continue;
        };
        match split_first(x, y) {
            None => {
                let placed = b.leaf_triangles(y).map(|(q, t)| (q, place.triangle(t)));
                if leaf_pairs(a.leaf_triangles(x), placed, &mut found).is_break() {
                    return Ok(());
                }
            }
            Some(first) => {
                let node = if first { x } else { y };
                let [c0, c1] = child_pairs(node, ia, ib, first);
                match (overlap(c0.0, c0.1), overlap(c1.0, c1.1)) {
                    (true, true) => {
                        stack.push((c1.0, c1.1, ()))?;
                        current = Some(c0);
                    }
                    (true, false) => current = Some(c0),
                    (false, true) => current = Some(c1),
                    (false, false) => {}
                }
            }
        }
        if current.is_none() {
            current = stack.pop().map(|(i, j, ())| (i, j));
        }
    }
    Ok(())
}

/// The narrow phase of two leaves, `(p, ta)` of one and `(q, tb)` of the other (placed):
/// triangle boxes first (exact), then the exact test.
fn leaf_pairs(
    leaf_a: impl Iterator<Item = (u32, [Vec3; 3])> + Clone,
    leaf_b: impl Iterator<Item = (u32, [Vec3; 3])>,
    found: &mut impl FnMut(u32, u32) -> ControlFlow<()>,
) -> ControlFlow<()> {
    for (q, tb) in leaf_b {
        let box_b: Aabb = Primitive::bounds(&tb);
        for (p, ta) in leaf_a.clone() {
            if Primitive::bounds(&ta).overlaps(&box_b) && triangles_intersect(&ta, &tb) {
                found(p, q)?;
            }
        }
    }
    ControlFlow::Continue(())
}

/// Every pair `(a, b)` of intersecting triangles — `a` of the first body, `b` of the second
/// placed in the first's frame by `b_to_a` (any [`Transform`]; rigid in the usual use) — is
/// written to `out`, in traversal order, and their number is returned. Closed triangles:
/// touching counts. The second body's triangles are tested as the `f32` vertices
/// [`Transform::point_to_world`] gives; each test is exact for those (see
/// [`super::triangles_intersect`]), and the broad phase is conservative (node boxes placed
/// with |L|·half-extents and padded by [`super::PLACED_BOX_PAD_REL`] and [`super::PLACED_BOX_PAD_ABS`]), so the result equals a
/// brute-force loop over all pairs. Pass an empty slice to count only.
///
/// # Errors
///
/// [`CollideError::OutputTooSmall`] when there are more pairs than `out` holds: the
/// traversal still completes, `needed` is the total and `out` holds the first pairs found
/// (the size cannot be known before the traversal).
/// [`CollideError::TreeTooDeep`] is unreachable for trees that were built or loaded.
pub fn colliding_pairs<NA, IA, NB, IB>(
    a: &Body<'_, NA, IA>,
    b: &Body<'_, NB, IB>,
    b_to_a: &Transform,
    out: &mut [(u32, u32)],
) -> Result<usize, CollideError>
where
    NA: AsRef<[BvhNode]>,
    IA: AsRef<[u32]>,
    NB: AsRef<[BvhNode]>,
    IB: AsRef<[u32]>,
{
    let mut count = 0usize;
    for_each_colliding(a, b, b_to_a, |p, q| {
        if let Some(slot) = out.get_mut(count) {
            *slot = (p, q);
        }
        count = count.saturating_add(1);
        ControlFlow::Continue(())
    })?;
    if count > out.len() {
        return Err(CollideError::OutputTooSmall {
            needed: count,
            available: out.len(),
        });
    }
    Ok(count)
}

/// The first intersecting triangle pair the traversal finds (`None` when the meshes do not
/// touch): the early-out form of [`colliding_pairs`], with the same conventions. Which pair
/// is first depends on the trees; that there is one does not.
///
/// # Errors
///
/// [`CollideError::TreeTooDeep`], unreachable for trees that were built or loaded.
pub fn first_contact<NA, IA, NB, IB>(
    a: &Body<'_, NA, IA>,
    b: &Body<'_, NB, IB>,
    b_to_a: &Transform,
) -> Result<Option<(u32, u32)>, CollideError>
where
    NA: AsRef<[BvhNode]>,
    IA: AsRef<[u32]>,
    NB: AsRef<[BvhNode]>,
    IB: AsRef<[u32]>,
{
    let mut first = None;
    for_each_colliding(a, b, b_to_a, |p, q| {
        first = Some((p, q));
        ControlFlow::Break(())
    })?;
    Ok(first)
}
