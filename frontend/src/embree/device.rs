//! The Embree device: creation, version and layout checks.

use std::ffi::CString;
use std::fmt;
use std::ptr;

use embree4_sys as sys;

use super::*;

/// What the runtime library reported at device creation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceInfo {
    /// `RTC_DEVICE_PROPERTY_VERSION`, e.g. 40400 for 4.4.0.
    pub version: u32,
    /// The configuration string the device was created with.
    pub config: String,
    /// `RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED` (we always set the mask to all ones).
    pub ray_mask_supported: bool,
    /// `RTC_DEVICE_PROPERTY_IGNORE_INVALID_RAYS_ENABLED`.
    pub ignore_invalid_rays: bool,
    /// `RTC_DEVICE_PROPERTY_TASKING_SYSTEM`: 0 internal, 1 TBB, 2 PPL.
    pub tasking_system: i64,
    /// 32-bit words of the probe's `RTCRayHit` that the library wrote beyond the 4.2 layout
    /// (word 20 is `instPrimID[0]`, byte 80). `[20]` for the 4.4.0 wheel.
    pub probe_words_past_42_layout: Vec<usize>,
}

impl DeviceInfo {
    /// "4.4.0"-style version string.
    pub fn version_string(&self) -> String {
        format!(
            "{}.{}.{}",
            self.version / 10000,
            self.version / 100 % 100,
            self.version % 100
        )
    }
}

/// An Embree device (owns one reference to an `RTCDevice`).
pub struct EmbreeDevice {
    pub(super) raw: sys::RTCDevice,
    info: DeviceInfo,
}

// SAFETY: an `RTCDevice` handle may be used and released from any thread: Embree's reference
// counts are atomic, object creation on one device is thread-safe, and the error state that
// `ffi::take_error` reads is kept per thread by Embree. `EmbreeDevice` has no interior state of
// its own besides the immutable `info`.
unsafe impl Send for EmbreeDevice {}
// SAFETY: see `Send`; every `&self` method only creates new objects or reads immutable data.
unsafe impl Sync for EmbreeDevice {}

impl EmbreeDevice {
    /// The default device for cross-checking: `threads=1,verbose=0`.
    pub fn new() -> Result<Self, EmbreeError> {
        Self::with_config("threads=1,verbose=0")
    }

    /// A device with an explicit Embree config string (e.g. `"threads=1,verbose=0,isa=sse4.2"`
    /// to pin the ISA, robustness.md E8). The string is NUL-terminated here.
    pub fn with_config(config: &str) -> Result<Self, EmbreeError> {
        let c_config =
            CString::new(config).map_err(|_| EmbreeError::InvalidConfig(config.into()))?;
        // SAFETY: `c_config` is a valid NUL-terminated string that outlives the call; Embree
        // copies what it needs. A null result is handled below.
        let raw = unsafe { sys::rtcNewDevice(c_config.as_ptr()) };
        if raw.is_null() {
            // SAFETY: a null device is allowed and reports this thread's creation error.
            let (code, message) =
                unsafe { ffi::take_error(ptr::null_mut()) }.unwrap_or((1, String::new()));
            return Err(EmbreeError::DeviceCreation { code, message });
        }
        // From here `device` owns the handle, so every early return releases it.
        let mut device = Self {
            raw,
            info: DeviceInfo {
                version: 0,
                config: config.to_owned(),
                ray_mask_supported: false,
                ignore_invalid_rays: false,
                tasking_system: -1,
                probe_words_past_42_layout: Vec::new(),
            },
        };
        let version = device.property(sys::RTCDeviceProperty::VERSION);
        device.info.version = u32::try_from(version).unwrap_or(0);
        if !SUPPORTED_VERSIONS.contains(&device.info.version) {
            return Err(EmbreeError::UnsupportedVersion {
                found: device.info.version,
            });
        }
        if device.property(sys::RTCDeviceProperty::BACKFACE_CULLING_ENABLED) != 0 {
            return Err(EmbreeError::BackfaceCulling);
        }
        device.info.ray_mask_supported =
            device.property(sys::RTCDeviceProperty::RAY_MASK_SUPPORTED) != 0;
        device.info.ignore_invalid_rays =
            device.property(sys::RTCDeviceProperty::IGNORE_INVALID_RAYS_ENABLED) != 0;
        device.info.tasking_system = device.property(sys::RTCDeviceProperty::TASKING_SYSTEM) as i64;
        device.info.probe_words_past_42_layout = device.probe_layout()?;
        Ok(device)
    }

    /// What the library reported at creation.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    fn property(&self, prop: sys::RTCDeviceProperty) -> isize {
        // SAFETY: `self.raw` is a live device; `prop` is a valid property value of the 4.2
        // headers (Embree keeps those numbers in 4.4). An unknown property only sets an error.
        unsafe { sys::rtcGetDeviceProperty(self.raw, prop) }
    }

    /// Takes this thread's pending error on this device, as an `EmbreeError::Api` for `call`.
    pub(super) fn check(&self, call: &'static str) -> Result<(), EmbreeError> {
        // SAFETY: `self.raw` is a live device.
        match unsafe { ffi::take_error(self.raw) } {
            None => Ok(()),
            Some((code, message)) => Err(EmbreeError::Api {
                call,
                code,
                message,
            }),
        }
    }

    /// Traces one ray into a one-triangle scene through a 256-byte buffer of sentinel words and
    /// returns the words the library wrote at or after byte 80 (the end of the 4.2 `RTCRayHit`).
    /// Fails unless the hit is the expected one and nothing was written at or after byte 96.
    fn probe_layout(&self) -> Result<Vec<usize>, EmbreeError> {
        let scene = EmbreeScene::new(self, &PROBE_POSITIONS, &[[0, 1, 2]], false)?;
        let probe = scene.probe_raw_words(PROBE_ORIGIN, PROBE_DIR);
        let past: Vec<usize> = (20..probe.after.len())
            .filter(|&i| probe.after[i] != probe.before[i])
            .collect();
        if let Some(&w) = past.iter().find(|&&w| w >= RAYHIT_BYTES / 4) {
            return Err(EmbreeError::LayoutMismatch(format!(
                "rtcIntersect1 wrote 32-bit word {w} (byte {}), past the {RAYHIT_BYTES}-byte 4.4 RTCRayHit",
                4 * w
            )));
        }
        let hit = probe.hit;
        let ok = hit.is_some_and(|h| {
            h.prim_id == 0
                && (h.t - 1.0).abs() < PROBE_AGREEMENT
                && (h.u - 0.25).abs() < PROBE_AGREEMENT
                && (h.v - 0.25).abs() < PROBE_AGREEMENT
                && h.ng[2] > 0.0
        });
        if !ok {
            return Err(EmbreeError::LayoutMismatch(format!(
                "unexpected probe result {hit:?}"
            )));
        }
        Ok(past)
    }
}

impl Drop for EmbreeDevice {
    fn drop(&mut self) {
        // SAFETY: `self.raw` is a live device and this releases the one reference we own; scenes
        // created from it hold their own reference.
        unsafe { sys::rtcReleaseDevice(self.raw) }
    }
}

impl fmt::Debug for EmbreeDevice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("EmbreeDevice")
            .field("info", &self.info)
            .finish_non_exhaustive()
    }
}

/// Probe geometry: triangle (0,0,0) (1,0,0) (0,1,0); the ray from (0.25,0.25,1) along −z hits it
/// at t = 1, u = v = 0.25.
const PROBE_POSITIONS: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
const PROBE_ORIGIN: [f32; 3] = [0.25, 0.25, 1.0];
const PROBE_DIR: [f32; 3] = [0.0, 0.0, -1.0];

/// How far the probe's `t`, `u` and `v` may lie from `1`, `0.25` and `0.25` (ray parameter and
/// barycentrics, absolute): the probe only tells a right field layout from a wrong one, where a
/// misplaced field reads as a different number altogether; Embree's `f32` test rounds the exact
/// values (exactly representable here) by a few ulps at most, `1e-5` is about 84 ulps of `1`.
const PROBE_AGREEMENT: f32 = 1e-5;
