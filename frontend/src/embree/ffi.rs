//! The few Embree entry points we declare ourselves instead of using `embree4-sys`'s bindings.
//!
//! `embree4-sys` maps `RTCError` to a Rust enum generated from the 4.2 headers (values 0..=6).
//! Embree 4.3+ added error codes; a library returning one of them into that enum would be
//! undefined behaviour. So the error code is read here as a plain `u32`. The last error message
//! getter (added in Embree 4.3) is not in the 4.2 bindings at all. The symbols come from the
//! same `libembree4` that `embree4-sys` links (`-lembree4`).

use std::ffi::{CStr, c_char, c_void};

use embree4_sys::{RTCDevice, RTCScene};

// SAFETY (of the declarations): these match the Embree 4.4 C prototypes
// `RTCError rtcGetDeviceError(RTCDevice)` (a 32-bit C enum, read as `u32`) and
// `const char* rtcGetDeviceLastErrorMessage(RTCDevice)`, both with the C calling convention.
unsafe extern "C" {
    #[link_name = "rtcGetDeviceError"]
    fn rtc_get_device_error(device: RTCDevice) -> u32;
    #[link_name = "rtcGetDeviceLastErrorMessage"]
    fn rtc_get_device_last_error_message(device: RTCDevice) -> *const c_char;
}

// SAFETY (of the declarations): these match the Embree 4.4 C prototypes
// `void rtcIntersect8(const int* valid, RTCScene, struct RTCRayHit8*, struct
// RTCIntersectArguments*)` and its 16-ray twin, C calling convention; the packet is passed as
// an address (its 4.4 layout is `packet::RayHitN`) and the arguments as null (the defaults).
unsafe extern "C" {
    #[link_name = "rtcIntersect8"]
    fn rtc_intersect8_raw(
        valid: *const i32,
        scene: RTCScene,
        rayhit: *mut c_void,
        args: *mut c_void,
    );
    #[link_name = "rtcIntersect16"]
    fn rtc_intersect16_raw(
        valid: *const i32,
        scene: RTCScene,
        rayhit: *mut c_void,
        args: *mut c_void,
    );
}

/// `rtcIntersect8(valid, scene, rayhit, NULL)`.
///
/// # Safety
/// `scene` is a live committed scene; `valid` points to 8 ints and `rayhit` to an
/// `RTCRayHit8` of the 4.4 layout, both 32-byte aligned and initialised.
pub(crate) unsafe fn rtc_intersect8(valid: *const i32, scene: RTCScene, rayhit: *mut c_void) {
    // SAFETY: the caller's guarantees are the function's preconditions.
    unsafe { rtc_intersect8_raw(valid, scene, rayhit, std::ptr::null_mut()) }
}

/// `rtcIntersect16(valid, scene, rayhit, NULL)`.
///
/// # Safety
/// As [`rtc_intersect8`], for 16 rays and 64-byte alignment.
pub(crate) unsafe fn rtc_intersect16(valid: *const i32, scene: RTCScene, rayhit: *mut c_void) {
    // SAFETY: the caller's guarantees are the function's preconditions.
    unsafe { rtc_intersect16_raw(valid, scene, rayhit, std::ptr::null_mut()) }
}

// SAFETY (of the declarations): these match the Embree 4.4 C prototypes
// `void rtcOccluded8(const int* valid, RTCScene, struct RTCRay8*, struct
// RTCOccludedArguments*)` and its 16-ray twin, C calling convention; the packet is passed as an
// address (`RTCRayN` is the prefix of `packet::RayHitN`) and the arguments as null.
unsafe extern "C" {
    #[link_name = "rtcOccluded8"]
    fn rtc_occluded8_raw(valid: *const i32, scene: RTCScene, ray: *mut c_void, args: *mut c_void);
    #[link_name = "rtcOccluded16"]
    fn rtc_occluded16_raw(valid: *const i32, scene: RTCScene, ray: *mut c_void, args: *mut c_void);
}

/// `rtcOccluded8(valid, scene, ray, NULL)`: an occluded lane's `tfar` becomes `−∞`.
///
/// # Safety
/// `scene` is a live committed scene; `valid` points to 8 ints and `ray` to an `RTCRay8` of
/// the 4.4 layout, both 32-byte aligned and initialised.
pub(crate) unsafe fn rtc_occluded8(valid: *const i32, scene: RTCScene, ray: *mut c_void) {
    // SAFETY: the caller's guarantees are the function's preconditions.
    unsafe { rtc_occluded8_raw(valid, scene, ray, std::ptr::null_mut()) }
}

/// `rtcOccluded16(valid, scene, ray, NULL)`.
///
/// # Safety
/// As [`rtc_occluded8`], for 16 rays and 64-byte alignment.
pub(crate) unsafe fn rtc_occluded16(valid: *const i32, scene: RTCScene, ray: *mut c_void) {
    // SAFETY: the caller's guarantees are the function's preconditions.
    unsafe { rtc_occluded16_raw(valid, scene, ray, std::ptr::null_mut()) }
}

/// Human-readable name of an `RTCError` code.
pub(crate) fn error_name(code: u32) -> &'static str {
    match code {
        0 => "RTC_ERROR_NONE",
        1 => "RTC_ERROR_UNKNOWN",
        2 => "RTC_ERROR_INVALID_ARGUMENT",
        3 => "RTC_ERROR_INVALID_OPERATION",
        4 => "RTC_ERROR_OUT_OF_MEMORY",
        5 => "RTC_ERROR_UNSUPPORTED_CPU",
        6 => "RTC_ERROR_CANCELLED",
        7 => "RTC_ERROR_LEVEL_ZERO_RAYTRACING_SUPPORT_MISSING",
        _ => "RTC_ERROR_(unknown code)",
    }
}

/// Takes (and so clears) the calling thread's pending error of `device` (null: errors of
/// `rtcNewDevice`), with the library's last error message.
///
/// # Safety
/// `device` must be null or a live device handle (not yet released by its last owner).
pub(crate) unsafe fn take_error(device: RTCDevice) -> Option<(u32, String)> {
    // SAFETY: the caller guarantees `device` is null or live; Embree accepts null here (it then
    // reports the thread's device-creation error). The call has no other precondition.
    let code = unsafe { rtc_get_device_error(device) };
    if code == 0 {
        return None;
    }
    // SAFETY: as above. The returned pointer is null or a NUL-terminated string owned by the
    // library that stays valid until the next API call on this thread; we copy it at once.
    let message = unsafe {
        let ptr = rtc_get_device_last_error_message(device);
        if ptr.is_null() {
            String::new()
        } else {
            CStr::from_ptr(ptr).to_string_lossy().into_owned()
        }
    };
    Some((code, message))
}
