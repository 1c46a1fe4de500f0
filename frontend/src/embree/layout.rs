//! The Embree 4.4 ray/hit layout, and the guarded slots that `rtcIntersect1` / `rtcOccluded1`
//! write into.
//!
//! `embree4-sys` 0.0.10 was generated from the Embree 4.2.0 headers, where `RTCHit` ends with
//! `instID[RTC_MAX_INSTANCE_LEVEL_COUNT]` (32 bytes, `RTCRayHit` 80 bytes). The 4.4.0 library of
//! the `embreex` wheel is built with instance arrays (`RTC_GEOMETRY_INSTANCE_ARRAY`), so its
//! `RTCHit` has one more field, `instPrimID[RTC_MAX_INSTANCE_LEVEL_COUNT]`: 36 bytes, padded to
//! 48 by the 16-byte alignment, and `RTCRayHit` is 96 bytes. The library writes `instPrimID`, i.e.
//! 4 bytes past a 4.2-sized struct. [`RayHit44`] has the 4.4 layout; [`RayHitSlot`] adds a guard
//! of sentinel words after it so that even a library with a bigger layout than assumed cannot
//! write outside our memory, and so that the layout can be *checked* (see `EmbreeDevice::new`'s
//! probe and the sentinel test).

use embree4_sys as sys;

/// `RTC_INVALID_GEOMETRY_ID`.
pub(crate) const INVALID_ID: u32 = u32::MAX;

/// Sentinel written into every guard word before a call.
pub(crate) const SENTINEL: u32 = 0xDEAD_BEEF;

/// Number of 32-bit guard words after the hit structure (64 bytes).
pub(crate) const GUARD_WORDS: usize = 16;

/// `RTCHit` of Embree 4.4 built with `RTC_MAX_INSTANCE_LEVEL_COUNT = 1` and instance arrays.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hit44 {
    pub ng_x: f32,
    pub ng_y: f32,
    pub ng_z: f32,
    pub u: f32,
    pub v: f32,
    pub prim_id: u32,
    pub geom_id: u32,
    pub inst_id: [u32; 1],
    pub inst_prim_id: [u32; 1],
    // 12 bytes of tail padding (alignment 16) follow; the library does not write them.
}

/// `RTCRayHit` of Embree 4.4: the (unchanged) `RTCRay` followed by [`Hit44`].
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayHit44 {
    pub ray: sys::RTCRay,
    pub hit: Hit44,
}

/// A [`RayHit44`] followed by guard words. This is what we hand to `rtcIntersect1`.
#[repr(C, align(16))]
pub(crate) struct RayHitSlot {
    pub rayhit: RayHit44,
    pub guard: [u32; GUARD_WORDS],
}

/// An `RTCRay` followed by guard words. This is what we hand to `rtcOccluded1` (whose argument
/// type, `RTCRay`, has the same 48-byte layout in 4.2 and 4.4).
#[repr(C, align(16))]
pub(crate) struct RaySlot {
    pub ray: sys::RTCRay,
    pub guard: [u32; GUARD_WORDS],
}

// Compile-time proof of the layout we assume (a wrong edit here fails the build, not a run).
const _: () = {
    use std::mem::{align_of, offset_of, size_of};
    assert!(size_of::<sys::RTCRay>() == 48 && align_of::<sys::RTCRay>() == 16);
    assert!(size_of::<sys::RTCHit>() == 32 && size_of::<sys::RTCRayHit>() == 80); // 4.2 headers
    assert!(offset_of!(Hit44, prim_id) == 20 && offset_of!(Hit44, geom_id) == 24);
    assert!(offset_of!(Hit44, inst_id) == 28 && offset_of!(Hit44, inst_prim_id) == 32);
    assert!(size_of::<Hit44>() == 48 && align_of::<Hit44>() == 16);
    assert!(offset_of!(RayHit44, hit) == 48 && size_of::<RayHit44>() == 96);
    assert!(align_of::<RayHit44>() == 16); // Embree requires 16-byte aligned RTCRayHit
    assert!(offset_of!(RayHitSlot, guard) == 96 && size_of::<RayHitSlot>() == 96 + 64);
    assert!(offset_of!(RaySlot, guard) == 48 && align_of::<RaySlot>() == 16);
};

/// The `RTCRay` for one query: mask all ones (Embree is built with ray masks), time 0, no flags.
pub(crate) fn make_ray(origin: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32) -> sys::RTCRay {
    sys::RTCRay {
        org_x: origin[0],
        org_y: origin[1],
        org_z: origin[2],
        tnear,
        dir_x: dir[0],
        dir_y: dir[1],
        dir_z: dir[2],
        time: 0.0,
        tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

impl RayHitSlot {
    /// A fresh slot: every hit ID invalid, guard words set to [`SENTINEL`].
    pub(crate) fn new(ray: sys::RTCRay) -> Self {
        Self {
            rayhit: RayHit44 {
                ray,
                hit: Hit44 {
                    ng_x: 0.0,
                    ng_y: 0.0,
                    ng_z: 0.0,
                    u: 0.0,
                    v: 0.0,
                    prim_id: INVALID_ID,
                    geom_id: INVALID_ID,
                    inst_id: [INVALID_ID],
                    inst_prim_id: [INVALID_ID],
                },
            },
            guard: [SENTINEL; GUARD_WORDS],
        }
    }

    pub(crate) fn guard_intact(&self) -> bool {
        self.guard.iter().all(|&w| w == SENTINEL)
    }
}

impl RaySlot {
    pub(crate) fn new(ray: sys::RTCRay) -> Self {
        Self {
            ray,
            guard: [SENTINEL; GUARD_WORDS],
        }
    }

    pub(crate) fn guard_intact(&self) -> bool {
        self.guard.iter().all(|&w| w == SENTINEL)
    }
}
