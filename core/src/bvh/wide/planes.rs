//! [`LeafPlanes`]: the [`BehindPlane`]s of one leaf's triangles, computed when a ray first
//! needs one and shared by the other rays of a batch that test the same leaf (the any-hit
//! batch of a tree whose root is a leaf).
//!
//! Not used by the packets of trees with nodes: there the eight-lane `f32` cull already
//! refuses the triangle a shadow ray starts on (their triangles are small beside their
//! coordinates), and the planes measured no fewer instructions (`docs/performance.md`).

use super::node::LeafGroup;
use crate::query::LeafTest;
use crate::sealed::Inside;
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
                    .and_then(|t| leaf.behind_plane(Inside(()), &t.vertices()));
            }
            if plane.is_some_and(|plane| plane.refuses(ray)) {
                refused |= 1 << bit;
            }
        }
        refused
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::wide::LeafTriangle;
    use crate::ray::Ray;
    use core::cell::Cell;
    use glam::Vec3;

    /// A leaf test whose planes are [`BehindPlane::new`]'s, counting how often one is asked for.
    struct Counted(Cell<usize>);

    impl LeafTest for Counted {
        type Hit = ();
        type Prepared = ();
        fn prepare(&self, _: &Ray) -> Option<()> {
            Some(())
        }
        fn intersect(&mut self, _: &(), _: u32, _: &Ray) -> Option<(f32, ())> {
            None
        }
        fn behind_plane(&self, _: Inside, v: &[Vec3; 3]) -> Option<BehindPlane> {
            self.0.set(self.0.get() + 1);
            BehindPlane::new(v)
        }
    }

    /// Two triangles of a pair, the plane `z = 0` in lane 0 of the first group (bit 0) and
    /// `z = 5` in lane 1 of the second (bit 5); rays from `z = 10⁻³`, worked by hand: going
    /// up, the first plane is crossed behind the origin (`t = −10⁻³`: refused) and the second
    /// ahead (`t ≈ 5`: kept); going down, the reverse. Each plane is computed at its first
    /// use only, then shared by the later rays.
    #[test]
    fn each_plane_is_computed_once_and_refuses_the_rays_leaving_it() {
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let (mut first, mut second) = (LeafGroup::EMPTY, LeafGroup::EMPTY);
        first.set(0, &LeafTriangle { v: flat, prim: 0 });
        let raised = flat.map(|[x, y, z]| [x, y, z + 5.0]);
        second.set(1, &LeafTriangle { v: raised, prim: 1 });
        let leaf = Counted(Cell::new(0));
        let mut planes = LeafPlanes::NEW;
        let start = Vec3::new(0.25, 0.25, 1e-3);
        let (up, down) = (Ray::new(start, Vec3::Z), Ray::new(start, -Vec3::Z));
        let pair = [&first, &second];
        let refused = |planes: &mut LeafPlanes, ray: &Ray| {
            planes.refused(&leaf, pair, 0, 0b10_0001, &PlaneRay::new(ray))
        };
        assert_eq!(refused(&mut planes, &up), 0b1);
        assert_eq!(leaf.0.get(), 2, "both planes computed");
        assert_eq!(refused(&mut planes, &down), 0b10_0000);
        assert_eq!(leaf.0.get(), 2, "each plane computed once");
    }
}
