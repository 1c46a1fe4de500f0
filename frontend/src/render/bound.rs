//! How far the ray tree of one camera ray is followed: the path-weight floor and the cap on
//! secondary rays per camera ray (see [`super::trace`]'s module docs for why these bound the
//! tree). A pixel casts one camera ray, or one per lens or anti-aliasing sample, each with its
//! own tree and its own cap.

/// Smallest path weight a secondary ray is cast for, 2⁻¹³. A subtree whose radiance is at
/// most 1 (the displayable range) then moves the pixel's linear value by less than 1/8192,
/// which after the sRGB curve (steepest at black, slope 12.92) is less than half an 8-bit step
/// (0.5 / 255 / 12.92 ≈ 1/6590). Brighter subtrees (a strong light seen down a long mirror
/// chain) can lose more: the bound is for display-range radiance.
pub const MIN_PATH_WEIGHT: f32 = 1.0 / 8192.0;

/// Most reflection and refraction rays per camera ray: the hard bound when `mirror` and
/// `transparency` are both near 1 and weights barely fall. Each camera ray of a pixel has its
/// own, so a pixel of `S` camera rays (`lens_samples`, or the anti-aliasing samples) casts at
/// most `S × 4096`; at one camera ray per pixel a 640×480 image stays under 1.3·10⁹ secondary
/// rays.
pub const MAX_SECONDARY_RAYS_PER_CAMERA_RAY: u32 = 4096;

/// How far the ray tree of one pixel is followed (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathBound {
    /// Secondary rays are cast only for path weights `≥ min_weight` (and `> 0`).
    pub min_weight: f32,
    /// Most secondary rays per camera ray.
    pub max_secondary_rays: u32,
}

impl PathBound {
    /// Whether a node of path weight `weight` casts a secondary ray of factor `k` (its
    /// material's `mirror` or `transparency`): `k > 0` and the ray's own weight `weight × k`
    /// at least `min_weight`. The one rule: the tracer applies it at every node, and the
    /// effect plan at the camera ray's hit (weight 1, the largest any node has: every factor
    /// is at most 1), so that a material whose factor is below [`MIN_PATH_WEIGHT`] is not
    /// planned as casting rays that never run.
    pub fn casts(&self, weight: f32, k: f32) -> bool {
        k > 0.0 && weight * k >= self.min_weight
    }

    /// The renderer's bound: [`MIN_PATH_WEIGHT`], [`MAX_SECONDARY_RAYS_PER_CAMERA_RAY`].
    pub const RENDER: Self = Self {
        min_weight: MIN_PATH_WEIGHT,
        max_secondary_rays: MAX_SECONDARY_RAYS_PER_CAMERA_RAY,
    };
    /// The whole tree down to `max_depth` (exponential: for tests on small images).
    pub const EXHAUSTIVE: Self = Self {
        min_weight: 0.0,
        max_secondary_rays: u32::MAX,
    };
}

impl Default for PathBound {
    fn default() -> Self {
        Self::RENDER
    }
}
