//! Front-to-back traversal on a fixed stack: closest hit and any hit.

use super::node::{KdNode, KdNodeKind};
use super::{KdTree, T_WIDEN_ABS, TRAVERSAL_STACK_SIZE};
use crate::aabb::{Aabb, SLAB_FAR_SCALE, SLAB_FAR_SCALE_NEGATIVE, SlabRay, pad_far};
use crate::query::forward::{ClosureWalk, PrimTest, Search};
use crate::query::walk::cull_bound;
use crate::ray::Ray;

/// One entry of the traversal stack (12 bytes): a node still to visit and the ray's interval
/// in its padded cell.
#[derive(Clone, Copy, Debug)]
struct KdStackEntry {
    node: u32,
    t0: f32,
    t1: f32,
}

impl KdStackEntry {
    /// An entry to fill a stack with.
    const EMPTY: Self = Self {
        node: 0,
        t0: 0.0,
        t1: 0.0,
    };
}

/// A plane distance moved later by its rounding ([`super::T_WIDEN_REL`], [`T_WIDEN_ABS`]).
/// `±∞` stay as they are.
#[inline(always)]
fn later(t: f32) -> f32 {
    pad_far(t) + T_WIDEN_ABS
}

/// A plane distance moved earlier by its rounding; `±∞` stay as they are.
#[inline(always)]
fn earlier(t: f32) -> f32 {
    let scaled = t * if t > 0.0 {
        SLAB_FAR_SCALE_NEGATIVE
    } else {
        SLAB_FAR_SCALE
    };
    scaled - T_WIDEN_ABS
}

/// The ray as the traversal wants it. Per axis, the origin shifted by the padding `pad`
/// against (`exit`) and along (`entry`) the direction: the distance to a cell's far face
/// moved outward by `pad` is `(plane − exit)/d`, to its near face moved outward
/// `(plane − entry)/d`. Axes with a `±0` direction component are `parallel`.
#[derive(Clone, Copy)]
struct KdRay {
    slab: SlabRay,
    exit: [f32; 3],
    entry: [f32; 3],
    parallel: [bool; 3],
}

impl KdRay {
    fn new(slab: SlabRay, pad: f32) -> Self {
        let toward = glam::Vec3::splat(pad).copysign(slab.direction);
        Self {
            slab,
            exit: (slab.origin - toward).to_array(),
            entry: (slab.origin + toward).to_array(),
            parallel: slab.direction.cmpeq(glam::Vec3::ZERO).into(),
        }
    }

    /// `(plane − shifted)/d` on a non-parallel axis: by the reciprocal, or by division when
    /// the reciprocal overflows ([`SlabRay::divide`]).
    #[inline(always)]
    fn distance(&self, axis: usize, plane: f32, shifted: f32) -> f32 {
        let x = plane - shifted;
        if self.slab.divide {
            x / self.slab.direction[axis]
        } else {
            x * self.slab.inv_dir[axis]
        }
    }

    /// On a parallel axis: whether the origin lies within `pad` below `plane` (`below`) and
    /// within `pad` above it (`above`).
    #[inline(always)]
    fn sides(&self, axis: usize, plane: f32) -> (bool, bool) {
        let (a, b) = (self.exit[axis], self.entry[axis]);
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        (lo <= plane, hi >= plane)
    }

    /// The interval `[t0, t1]` clipped to the padded box `b`, widened; `None` when empty.
    fn clip_box(&self, b: &Aabb, mut t0: f32, mut t1: f32) -> Option<(f32, f32)> {
        for axis in 0..3 {
            let (lo, hi) = (b.min[axis], b.max[axis]);
            if self.parallel[axis] {
                let (below_hi, _) = self.sides(axis, hi);
                let (_, above_lo) = self.sides(axis, lo);
                if !(below_hi && above_lo) {
                    return None;
                }
                continue;
            }
            let (near, far) = if self.slab.negative[axis] {
                (hi, lo)
            } else {
                (lo, hi)
            };
            let enter = earlier(self.distance(axis, near, self.entry[axis]));
            let leave = later(self.distance(axis, far, self.exit[axis]));
            t0 = if enter > t0 { enter } else { t0 };
            t1 = if leave < t1 { leave } else { t1 };
        }
        (t0 <= t1).then_some((t0, t1))
    }
}

/// What one inner node sends on: the near child (visited next) and the far child (pushed),
/// each with its interval, when the ray passes through its padded cell.
type Children = [Option<(u32, f32, f32)>; 2];

impl KdRay {
    /// The children of an inner node splitting `axis` at `s`, for the interval `[t0, t1]`.
    #[inline(always)]
    fn children(&self, axis: usize, s: f32, first: u32, t0: f32, t1: f32) -> Children {
        let (below, above) = (first, first.saturating_add(1));
        if self.parallel[axis] {
            let (b, a) = self.sides(axis, s);
            return [b.then_some((below, t0, t1)), a.then_some((above, t0, t1))];
        }
        let (near, far) = if self.slab.negative[axis] {
            (above, below)
        } else {
            (below, above)
        };
        let leave = later(self.distance(axis, s, self.exit[axis]));
        let enter = earlier(self.distance(axis, s, self.entry[axis]));
        let near_t1 = if leave < t1 { leave } else { t1 };
        let far_t0 = if enter > t0 { enter } else { t0 };
        [
            (t0 <= near_t1).then_some((near, t0, near_t1)),
            (far_t0 <= t1).then_some((far, far_t0, t1)),
        ]
    }
}

/// The walk of the module docs of [`super`].
impl<N: AsRef<[KdNode]>, R: AsRef<[u32]>> ClosureWalk for KdTree<N, R> {
    fn traverse<F: PrimTest<H>, H>(&self, ray: &Ray, s: &mut Search<F, H>) {
        let Some(slab) = SlabRay::new(ray) else {
            return;
        };
        let nodes = self.nodes();
        let refs = self.references();
        if nodes.is_empty() {
            return;
        }
        let kray = KdRay::new(slab, self.pad_frame.pad(slab.origin));
        let Some((t0, t1)) = kray.clip_box(&self.bounds, ray.t_min, cull_bound(ray.t_max)) else {
            return;
        };
        let mut stack = [KdStackEntry::EMPTY; TRAVERSAL_STACK_SIZE];
        let mut sp = 0usize;
        let mut next = Some((0u32, t0, t1));
        // A walk of a tree enters each node at most once: nodes that make it enter more are
        // no tree (storage whose `AsRef` changed since the build, [`KdTree`]'s docs), and the
        // walk ends there, with what it found.
        let mut entries = nodes.len();
        'walk: while let Some((index, t0, t1)) = next.take() {
            let Some(rest) = entries.checked_sub(1) else {
                break;
            };
            entries = rest;
            let t1 = t1.min(cull_bound(s.cur.t_max));
            if t0 <= t1
                && let Some(node) = nodes.get(index as usize)
            {
                s.stats.nodes_visited += 1;
                match node.kind() {
                    KdNodeKind::Inner {
                        axis,
                        position,
                        first,
                    } => {
                        let [near, far] = kray.children(axis, position, first, t0, t1);
                        match (near, far) {
                            (Some(n), Some((f, f0, f1))) => {
                                // By the stack bound (module docs) there is always a slot.
                                if let Some(slot) = stack.get_mut(sp) {
                                    *slot = KdStackEntry {
                                        node: f,
                                        t0: f0,
                                        t1: f1,
                                    };
                                    sp += 1;
                                }
                                next = Some(n);
                            }
                            (one, other) => next = one.or(other),
                        }
                        if next.is_some() {
                            continue;
                        }
                    }
                    KdNodeKind::Leaf { start, count } => {
                        let first = start as usize;
                        let run = refs
                            .get(first..first.saturating_add(count as usize))
                            .unwrap_or(&[]);
                        if s.test(run) {
                            break 'walk;
                        }
                    }
                }
            }
            if sp > 0 {
                sp -= 1;
                next = stack.get(sp).map(|e| (e.node, e.t0, e.t1));
            }
        }
    }
}
