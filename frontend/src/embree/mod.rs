//! A small, safe wrapper over Intel Embree 4.4 for cross-checking halfray.
//!
//! Compiled only with `--features embree`. Set-up (library, link path, rpath): run
//! `bash scripts/setup-embree.sh`, then `EMBREE_DIR=$PWD/.embree cargo test -p halfray --features
//! embree embree`; see `docs/embree.md`.
//!
//! # What this wraps, and why not `embree4-rs`
//! `embree4-rs` 0.0.16 pins `embree4-sys` 0.0.10, generated from the Embree **4.2** headers, while
//! the library we use is **4.4.0**, whose `RTCRayHit` is 16 bytes bigger (see the `layout` module):
//! `embree4_rs::CommittedScene::intersect_1` lets the library write past its stack struct. Its
//! device and scene handles are private, it has no occlusion query, and its device config string
//! is passed without a NUL terminator. So everything here goes through `embree4-sys` directly:
//! - [`EmbreeDevice::new`] creates a one-thread device, refuses any runtime other than 4.4.x,
//!   refuses a library built with back-face culling, and traces a probe ray into a one-triangle
//!   scene with sentinel words after the hit structure to verify the layout before use;
//! - [`EmbreeScene::new`] builds one triangle mesh, optionally with `RTC_SCENE_FLAG_ROBUST`;
//! - [`EmbreeScene::intersect`] (`rtcIntersect1`, closest hit) and [`EmbreeScene::occluded`]
//!   (`rtcOccluded1`, any hit) pass 16-byte aligned 4.4-layout structs followed by 64 bytes of
//!   guard words, with the ray mask all ones and every hit ID reset to invalid on each call.
//!
//! # Flush-to-zero / denormals-are-zero
//! Embree's documentation asks callers to set FTZ and DAZ in MXCSR for performance. This wrapper
//! deliberately leaves MXCSR alone: the cross-check compares against halfray running on the same
//! thread under the default IEEE mode, and robustness.md (5.1, E12) asks for the harness to run
//! without FTZ/DAZ so that subnormal inputs behave the same on both sides. The device is created
//! with `verbose=0`, so no warning is printed. A caller who wants FTZ/DAZ must set it on the
//! tracing thread itself (and measure halfray under the same setting).
//!
//! # Threads
//! The device is created with `threads=1` (scene builds use one thread). Queries run on the
//! caller's thread; a committed [`EmbreeScene`] may be queried from several threads at once
//! (Embree's scenes are thread-safe for traversal after commit), so it is `Send + Sync`.

mod device;
mod error;
mod ffi;
mod layout;
mod packet;
mod scene;
#[cfg(test)]
mod tests;

pub use device::{DeviceInfo, EmbreeDevice};
pub use error::EmbreeError;
pub use scene::{BuildQuality, EmbreeHit, EmbreeMesh, EmbreeScene};

use layout::{GUARD_WORDS, INVALID_ID, RayHitSlot, RaySlot, SENTINEL, make_ray};

/// The Embree versions whose ray/hit layout this module assumes: 4.4.x (`RTC_VERSION` 40400..40499).
pub const SUPPORTED_VERSIONS: std::ops::Range<u32> = 40400..40500;

/// Size in bytes of `RTCRayHit` in the Embree 4.4.0 build we use (80 in the 4.2 headers).
pub const RAYHIT_BYTES: usize = std::mem::size_of::<layout::RayHit44>();

/// Embree's `FLT_LARGE`: ray components of larger magnitude make the result undefined.
pub const FLT_LARGE: f32 = 1.844e18;

/// Whether Embree gives a defined answer for this ray (robustness.md, E10): origin and direction
/// finite with every component of magnitude ≤ [`FLT_LARGE`], direction non-zero, `tnear` finite
/// and ≥ 0, `tfar` not NaN (+∞ is fine). [`EmbreeScene::intersect`] and
/// [`EmbreeScene::occluded`] do not trace other rays.
pub fn ray_is_valid(origin: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32) -> bool {
    let bounded = |c: f32| c.abs() <= FLT_LARGE; // false for NaN and ±∞
    origin.iter().all(|&c| bounded(c))
        && dir.iter().all(|&c| bounded(c))
        && dir.iter().any(|&c| c != 0.0)
        && tnear.is_finite()
        && tnear >= 0.0
        && !tfar.is_nan()
}

/// [`ray_is_valid`] of a halfray ray (what [`EmbreeScene::intersect_ray`] traces).
pub fn takes_ray(r: &halfray_core::Ray) -> bool {
    ray_is_valid(
        r.origin.to_array(),
        r.direction.to_array(),
        r.t_min,
        r.t_max,
    )
}
