//! The ray as the node tests of both trees want it ([`super::Bvh`]'s two-box test and the
//! wide tree's all-children test).

use crate::aabb::SlabRay;

/// The ray as the node test wants it: reciprocal direction, per axis which of the node's
/// `[min, max]` corners is the near one (the direction's sign bit), and the box padding
/// ([`crate::tolerance::BVH_PROJECTION_PAD`]) folded into two shifted origins (moving a
/// bound outward by `pad` is moving the origin by `pad` the other way; the rounding of
/// `o ± pad` is within the padding's margin).
#[derive(Clone, Copy)]
pub(super) struct PaddedRay {
    pub(super) origin_near: [f32; 3],
    pub(super) origin_far: [f32; 3],
    pub(super) inv_dir: [f32; 3],
    pub(super) near: [usize; 3],
    pub(super) pad: f32,
    pub(super) slab: SlabRay,
}

impl PaddedRay {
    /// `slab` with boxes padded by `pad` world units.
    #[inline(always)]
    pub(super) fn new(slab: &SlabRay, pad: f32) -> Self {
        // `pad` with each direction component's sign (`negative` is that sign bit): a
        // sign-bit copy, not a branch on a random ray's signs.
        let toward = glam::Vec3::splat(pad).copysign(slab.direction);
        Self {
            origin_near: (slab.origin + toward).to_array(),
            origin_far: (slab.origin - toward).to_array(),
            inv_dir: slab.inv_dir.to_array(),
            near: [
                usize::from(slab.negative[0]),
                usize::from(slab.negative[1]),
                usize::from(slab.negative[2]),
            ],
            pad,
            slab: *slab,
        }
    }
}
