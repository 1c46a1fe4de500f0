//! [`LeafPlanes`]: the [`BehindPlane`]s of one leaf's triangles, computed when a ray first
//! needs one and shared by the other rays of a batch that test the same leaf (the any-hit
//! batch of a tree whose root is a leaf).
//!
//! Not used by the packets of trees with nodes: there the eight-lane `f32` cull already
//! refuses the triangle a shadow ray starts on (their triangles are small beside their
//! coordinates), and the planes measured no fewer instructions (`docs/performance.md`).

use super::node::LeafGroup;
use crate::query::LeafTest;
use crate::triangle::{BehindPlane, LANES, PlaneRay};

/// Lane slots of [`LeafPlanes`]: a run of up to eight groups (a pair's lanes are bits
/// `8p .. 8p + 8` for its pair `p`), one bit of a `u32` each.
pub(super) const PLANE_SLOTS: usize = 32;

/// The planes of the lanes of one leaf run, by slot (`8p + bit` for bit `bit` of the run's
/// pair `p`, as the leaf loop numbers a pair's lanes); each computed at its first use.
pub(super) struct LeafPlanes {
    planes: [Option<BehindPlane>; PLANE_SLOTS],
    known: u32,
}

impl LeafPlanes {
    /// No plane computed yet.
    pub(super) const NEW: Self = Self {
        planes: [None; PLANE_SLOTS],
        known: 0,
    };

    /// The lanes among `lanes` (bits of the run's pair `p`, groups `pair`) whose triangle's
    /// plane refuses the ray of `ray` ([`LeafTest::behind_plane`], [`BehindPlane::refuses`]):
    /// lanes the leaf test certainly misses. A lane whose slot is past [`PLANE_SLOTS`] is never refused.
    #[inline(always)]
    pub(super) fn refused<LT: LeafTest>(
        &mut self,
        leaf: &LT,
        pair: [&LeafGroup; 2],
        p: usize,
        lanes: u32,
        ray: &PlaneRay<'_>,
    ) -> u32 {
        let mut refused = 0;
        let mut each = lanes;
        while each != 0 {
            let bit = each.trailing_zeros() as usize;
            each &= each - 1;
            let slot = 2 * LANES * p + bit;
            let Some(plane) = self.planes.get_mut(slot) else {
                break;
            };
            if self.known >> slot & 1 == 0 {
                self.known |= 1 << slot;
                *plane = pair[(bit / LANES) & 1]
                    .triangle(bit & (LANES - 1))
                    .and_then(|t| leaf.behind_plane(&t.vertices()));
            }
            if plane.is_some_and(|plane| plane.refuses(ray)) {
                refused |= 1 << bit;
            }
        }
        refused
    }
}
