//! How far the ray tree of one pixel is followed: the path-weight floor and the per-pixel cap
//! on secondary rays (see [`super::trace`]'s module docs for why these bound the tree).

/// Smallest path weight a secondary ray is cast for, 2⁻¹³. A subtree whose radiance is at
/// most 1 (the displayable range) then moves the pixel's linear value by less than 1/8192,
/// which after the sRGB curve (steepest at black, slope 12.92) is less than half an 8-bit step
/// (0.5 / 255 / 12.92 ≈ 1/6590). Brighter subtrees (a strong light seen down a long mirror
/// chain) can lose more: the bound is for display-range radiance.
pub const MIN_PATH_WEIGHT: f32 = 1.0 / 8192.0;

/// Most reflection and refraction rays per pixel: the hard bound when `mirror` and
/// `transparency` are both near 1 and weights barely fall (4096 per pixel keeps a 640×480
/// image under 1.3·10⁹ secondary rays).
pub const MAX_SECONDARY_RAYS_PER_PIXEL: u32 = 4096;

/// How far the ray tree of one pixel is followed (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathBound {
    /// Secondary rays are cast only for path weights `≥ min_weight` (and `> 0`).
    pub min_weight: f32,
    /// Most secondary rays per pixel.
    pub max_secondary_rays: u32,
}

impl PathBound {
    /// The renderer's bound: [`MIN_PATH_WEIGHT`], [`MAX_SECONDARY_RAYS_PER_PIXEL`].
    pub const RENDER: Self = Self {
        min_weight: MIN_PATH_WEIGHT,
        max_secondary_rays: MAX_SECONDARY_RAYS_PER_PIXEL,
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
