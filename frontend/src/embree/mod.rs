//! A small, safe wrapper over Intel Embree 4.4 for cross-checking halfray (issue 6).
//!
//! Compiled only with `--features embree`. Set-up (library, link path, rpath): run
//! `bash scripts/setup-embree.sh`, then `EMBREE_DIR=$PWD/.embree cargo test -p halfray --features
//! embree embree`; see `docs/embree.md`.
//!
//! # What this wraps, and why not `embree4-rs`
//! `embree4-rs` 0.0.16 pins `embree4-sys` 0.0.10, generated from the Embree **4.2** headers, while
//! the library we use is **4.4.0**, whose `RTCRayHit` is 16 bytes bigger (see [`layout`]):
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

mod ffi;
mod layout;
#[cfg(test)]
mod tests;

use std::ffi::CString;
use std::fmt;
use std::ptr;

use embree4_sys as sys;

use layout::{GUARD_WORDS, INVALID_ID, RayHitSlot, RaySlot, SENTINEL, make_ray};

/// The Embree versions whose ray/hit layout this module assumes: 4.4.x (`RTC_VERSION` 40400..40499).
pub const SUPPORTED_VERSIONS: std::ops::Range<u32> = 40400..40500;

/// Size in bytes of `RTCRayHit` in the Embree 4.4.0 build we use (80 in the 4.2 headers).
pub const RAYHIT_BYTES: usize = std::mem::size_of::<layout::RayHit44>();

/// Embree's `FLT_LARGE`: ray components of larger magnitude make the result undefined.
pub const FLT_LARGE: f32 = 1.844e18;

/// An error from setting up or using Embree.
#[derive(Debug, Clone, PartialEq)]
pub enum EmbreeError {
    /// The device configuration string holds a NUL byte.
    InvalidConfig(String),
    /// `rtcNewDevice` failed (code is an `RTCError`).
    DeviceCreation { code: u32, message: String },
    /// The runtime library is not Embree 4.4.x, whose ray/hit layout this module assumes.
    UnsupportedVersion { found: u32 },
    /// The library was built with `EMBREE_BACKFACE_CULLING`: it would not be a fair reference.
    BackfaceCulling,
    /// The start-up probe ray showed a ray/hit layout other than the one assumed.
    LayoutMismatch(String),
    /// An Embree call reported an error (code is an `RTCError`).
    Api {
        call: &'static str,
        code: u32,
        message: String,
    },
    /// The mesh cannot be handed to Embree (e.g. an index out of range).
    InvalidMesh(String),
}

impl fmt::Display for EmbreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::InvalidConfig(c) => {
                write!(f, "invalid Embree device config {c:?} (holds a NUL byte)")
            }
            Self::DeviceCreation { code, message } => {
                write!(
                    f,
                    "rtcNewDevice failed: {} ({code}): {message}",
                    ffi::error_name(*code)
                )
            }
            Self::UnsupportedVersion { found } => write!(
                f,
                "Embree {}.{}.{} found, but this build assumes the ray/hit layout of Embree 4.4.x \
                 (run scripts/setup-embree.sh and set EMBREE_DIR)",
                found / 10000,
                found / 100 % 100,
                found % 100
            ),
            Self::BackfaceCulling => {
                write!(
                    f,
                    "this Embree library was built with back-face culling; refusing to use it"
                )
            }
            Self::LayoutMismatch(m) => write!(f, "Embree ray/hit layout check failed: {m}"),
            Self::Api {
                call,
                code,
                message,
            } => {
                write!(
                    f,
                    "{call} failed: {} ({code}): {message}",
                    ffi::error_name(*code)
                )
            }
            Self::InvalidMesh(m) => write!(f, "invalid mesh for Embree: {m}"),
        }
    }
}

impl std::error::Error for EmbreeError {}

impl From<EmbreeError> for crate::error::Error {
    fn from(e: EmbreeError) -> Self {
        Self::Embree(e)
    }
}

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
    raw: sys::RTCDevice,
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
    fn check(&self, call: &'static str) -> Result<(), EmbreeError> {
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
                && (h.t - 1.0).abs() < 1e-5
                && (h.u - 0.25).abs() < 1e-5
                && (h.v - 0.25).abs() < 1e-5
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

/// Build quality of the scene's BVH (`RTCBuildQuality`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BuildQuality {
    Low,
    /// Embree's default.
    #[default]
    Medium,
    High,
}

/// A closest hit reported by Embree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmbreeHit {
    /// Ray parameter of the hit (Embree's `tfar` after the query).
    pub t: f32,
    /// Barycentric weight of the triangle's second vertex.
    pub u: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub v: f32,
    /// Index of the triangle in the slice given to [`EmbreeScene::new`].
    pub prim_id: u32,
    /// Unnormalised geometric normal, `(v1 − v0) × (v2 − v0)` up to Embree's rounding.
    pub ng: [f32; 3],
}

/// A committed Embree scene holding one triangle mesh (owns one reference to an `RTCScene` and
/// one to its `RTCDevice`, so it may outlive the [`EmbreeDevice`] it was made from).
pub struct EmbreeScene {
    raw: sys::RTCScene,
    device: sys::RTCDevice,
    robust: bool,
    triangles: usize,
}

// SAFETY: the scene is committed in `new` and never modified afterwards (no `&mut` API); Embree
// allows `rtcIntersect1`/`rtcOccluded1` on a committed scene from any number of threads at once,
// and its reference counts (released in `Drop`) are atomic.
unsafe impl Send for EmbreeScene {}
// SAFETY: see `Send`.
unsafe impl Sync for EmbreeScene {}

impl EmbreeScene {
    /// Builds a scene of one triangle mesh with Embree's default build quality. `robust` sets
    /// `RTC_SCENE_FLAG_ROBUST` (the fair reference: the default mode leaks at shared edges).
    /// Triangle `i` gets `prim_id == i`. Fails if an index is out of range.
    pub fn new(
        device: &EmbreeDevice,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        robust: bool,
    ) -> Result<Self, EmbreeError> {
        Self::build(device, positions, triangles, robust, None)
    }

    /// As [`EmbreeScene::new`], with an explicit build quality.
    pub fn with_quality(
        device: &EmbreeDevice,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        robust: bool,
        quality: BuildQuality,
    ) -> Result<Self, EmbreeError> {
        Self::build(device, positions, triangles, robust, Some(quality))
    }

    fn build(
        device: &EmbreeDevice,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        robust: bool,
        quality: Option<BuildQuality>,
    ) -> Result<Self, EmbreeError> {
        // Embree reads vertices through the indices without bounds checks: validate them here.
        if let Some((i, tri)) = triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v as usize >= positions.len()))
        {
            return Err(EmbreeError::InvalidMesh(format!(
                "triangle {i} has index {tri:?}, but there are {} vertices",
                positions.len()
            )));
        }
        // SAFETY: `device.raw` is live; a null scene is handled below.
        let raw = unsafe { sys::rtcNewScene(device.raw) };
        if raw.is_null() {
            device.check("rtcNewScene")?;
            return Err(EmbreeError::Api {
                call: "rtcNewScene",
                code: 1,
                message: "null scene".into(),
            });
        }
        // SAFETY: `device.raw` is live; this reference is released in `Drop`.
        unsafe { sys::rtcRetainDevice(device.raw) };
        // From here `scene` owns both references, so every early return releases them.
        let scene = Self {
            raw,
            device: device.raw,
            robust,
            triangles: triangles.len(),
        };
        device.check("rtcNewScene")?;

        let flags = if robust {
            sys::RTCSceneFlags::ROBUST
        } else {
            sys::RTCSceneFlags::NONE
        };
        // SAFETY: `scene.raw` is a live, uncommitted scene; flags is a valid RTCSceneFlags value.
        unsafe { sys::rtcSetSceneFlags(scene.raw, flags) };
        device.check("rtcSetSceneFlags")?;
        if let Some(q) = quality {
            let q = match q {
                BuildQuality::Low => sys::RTCBuildQuality::LOW,
                BuildQuality::Medium => sys::RTCBuildQuality::MEDIUM,
                BuildQuality::High => sys::RTCBuildQuality::HIGH,
            };
            // SAFETY: as above; `q` is a valid RTCBuildQuality value.
            unsafe { sys::rtcSetSceneBuildQuality(scene.raw, q) };
            device.check("rtcSetSceneBuildQuality")?;
        }
        if !triangles.is_empty() {
            scene.attach_mesh(device, positions, triangles)?;
        }
        // SAFETY: `scene.raw` is live; after commit the scene is never modified again.
        unsafe { sys::rtcCommitScene(scene.raw) };
        device.check("rtcCommitScene")?;
        Ok(scene)
    }

    /// Creates the triangle geometry, copies the buffers into Embree-allocated (padded) memory,
    /// and attaches it as geometry 0. `triangles` is non-empty and every index is in range.
    fn attach_mesh(
        &self,
        device: &EmbreeDevice,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
    ) -> Result<(), EmbreeError> {
        // SAFETY: `device.raw` is live; TRIANGLE is a valid geometry type. Null is handled below.
        let geom = unsafe { sys::rtcNewGeometry(device.raw, sys::RTCGeometryType::TRIANGLE) };
        if geom.is_null() {
            device.check("rtcNewGeometry")?;
            return Err(EmbreeError::Api {
                call: "rtcNewGeometry",
                code: 1,
                message: "null geometry".into(),
            });
        }
        let result = (|| {
            device.check("rtcNewGeometry")?;
            // SAFETY: `geom` is a live triangle geometry. Embree allocates `positions.len()` items
            // of 12 bytes (plus the padding it needs for 16-byte loads) and returns a pointer
            // aligned to at least 16 bytes, or null on failure (checked before use).
            let vbuf = unsafe {
                sys::rtcSetNewGeometryBuffer(
                    geom,
                    sys::RTCBufferType::VERTEX,
                    0,
                    sys::RTCFormat::FLOAT3,
                    12,
                    positions.len(),
                )
            };
            device.check("rtcSetNewGeometryBuffer(VERTEX)")?;
            // SAFETY: as above, with `triangles.len()` items of 3 × u32.
            let ibuf = unsafe {
                sys::rtcSetNewGeometryBuffer(
                    geom,
                    sys::RTCBufferType::INDEX,
                    0,
                    sys::RTCFormat::UINT3,
                    12,
                    triangles.len(),
                )
            };
            device.check("rtcSetNewGeometryBuffer(INDEX)")?;
            if vbuf.is_null() || ibuf.is_null() {
                return Err(EmbreeError::Api {
                    call: "rtcSetNewGeometryBuffer",
                    code: 4,
                    message: "null buffer".into(),
                });
            }
            // SAFETY: `vbuf` holds at least `positions.len()` × 12 bytes, is aligned for f32 and
            // does not overlap `positions` (Embree-owned memory); `[f32; 3]` is 12 bytes with no
            // padding. Likewise `ibuf` for `triangles` (`[u32; 3]`, 12 bytes).
            unsafe {
                ptr::copy_nonoverlapping(
                    positions.as_ptr(),
                    vbuf.cast::<[f32; 3]>(),
                    positions.len(),
                );
                ptr::copy_nonoverlapping(
                    triangles.as_ptr(),
                    ibuf.cast::<[u32; 3]>(),
                    triangles.len(),
                );
            }
            // SAFETY: `geom` is live with both buffers set; `self.raw` is live and uncommitted.
            // The scene takes its own reference to the geometry.
            let geom_id = unsafe {
                sys::rtcCommitGeometry(geom);
                sys::rtcAttachGeometry(self.raw, geom)
            };
            device.check("rtcAttachGeometry")?;
            if geom_id != 0 {
                return Err(EmbreeError::Api {
                    call: "rtcAttachGeometry",
                    code: 1,
                    message: format!("expected geometry ID 0, got {geom_id}"),
                });
            }
            Ok(())
        })();
        // SAFETY: releases the reference `rtcNewGeometry` gave us (the scene keeps its own).
        unsafe { sys::rtcReleaseGeometry(geom) };
        result
    }

    /// Whether the scene was built with `RTC_SCENE_FLAG_ROBUST`.
    pub fn is_robust(&self) -> bool {
        self.robust
    }

    /// Number of triangles given to [`EmbreeScene::new`] (degenerate or non-finite ones included;
    /// Embree drops those at build time and never reports them).
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// Closest hit along `origin + t·dir` with `t` in `[tnear, tfar]` (`rtcIntersect1`), or `None`.
    ///
    /// Rays Embree cannot handle (see [`ray_is_valid`]) are not traced and give `None`: filter them
    /// with [`ray_is_valid`] before comparing. Whether a hit at exactly `tnear` or `tfar` is
    /// kept depends on the kernel Embree picked at run time (docs/embree.md): do not rely on it.
    pub fn intersect(
        &self,
        origin: [f32; 3],
        dir: [f32; 3],
        tnear: f32,
        tfar: f32,
    ) -> Option<EmbreeHit> {
        if !ray_is_valid(origin, dir, tnear, tfar) {
            return None;
        }
        let mut slot = RayHitSlot::new(make_ray(origin, dir, tnear, tfar));
        // SAFETY: `self.raw` is a live committed scene. `slot.rayhit` is a fully initialised,
        // 16-byte aligned `RTCRayHit` with the 4.4 layout (96 bytes, checked at compile time in
        // `layout` and against the library by the device's probe), followed by 64 more bytes of
        // our own; the library reads and writes only within those 96 bytes. The 4.2 pointer type
        // of the binding is only nominal: C receives an address. Null arguments select the
        // default `RTCIntersectArguments`, so that struct's layout does not matter.
        unsafe {
            sys::rtcIntersect1(
                self.raw,
                (&raw mut slot.rayhit).cast::<sys::RTCRayHit>(),
                ptr::null_mut(),
            )
        };
        debug_assert!(
            slot.guard_intact(),
            "rtcIntersect1 wrote past the 4.4 RTCRayHit"
        );
        let ray = &slot.rayhit.ray;
        let hit = &slot.rayhit.hit;
        (hit.geom_id != INVALID_ID).then_some(EmbreeHit {
            t: ray.tfar,
            u: hit.u,
            v: hit.v,
            prim_id: hit.prim_id,
            ng: [hit.ng_x, hit.ng_y, hit.ng_z],
        })
    }

    /// [`EmbreeScene::intersect`] for a halfray [`Ray`](halfray_core::Ray) (its origin,
    /// direction and interval).
    pub fn intersect_ray(&self, r: &halfray_core::Ray) -> Option<EmbreeHit> {
        self.intersect(
            r.origin.to_array(),
            r.direction.to_array(),
            r.t_min,
            r.t_max,
        )
    }

    /// [`EmbreeScene::occluded`] for a halfray [`Ray`](halfray_core::Ray).
    pub fn occluded_ray(&self, r: &halfray_core::Ray) -> bool {
        self.occluded(
            r.origin.to_array(),
            r.direction.to_array(),
            r.t_min,
            r.t_max,
        )
    }

    /// Whether anything is hit along `origin + t·dir` with `t` in `[tnear, tfar]` (`rtcOccluded1`,
    /// which sets `tfar` to −∞ on a hit). Invalid rays (see [`ray_is_valid`]) give `false`.
    pub fn occluded(&self, origin: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32) -> bool {
        if !ray_is_valid(origin, dir, tnear, tfar) {
            return false;
        }
        let mut slot = RaySlot::new(make_ray(origin, dir, tnear, tfar));
        // SAFETY: `self.raw` is a live committed scene; `slot.ray` is a fully initialised,
        // 16-byte aligned `RTCRay` (48 bytes, the same in 4.2 and 4.4) followed by 64 bytes of
        // our own. The library writes only `tfar`. Null arguments select the defaults.
        unsafe { sys::rtcOccluded1(self.raw, &raw mut slot.ray, ptr::null_mut()) };
        debug_assert!(slot.guard_intact(), "rtcOccluded1 wrote past RTCRay");
        slot.ray.tfar == f32::NEG_INFINITY
    }

    /// Traces one ray through a 256-byte buffer of sentinel words (only the `RTCRay` and the 4.2
    /// `RTCHit` fields initialised) and returns the buffer before and after: which words the
    /// library wrote shows the real `RTCRayHit` size.
    pub(crate) fn probe_raw_words(&self, origin: [f32; 3], dir: [f32; 3]) -> RawProbe {
        #[repr(C, align(16))]
        struct Words([u32; PROBE_WORDS]);
        let mut words = Words([SENTINEL; PROBE_WORDS]);
        let ray = make_ray(origin, dir, 0.0, f32::INFINITY);
        let ray_words = [
            ray.org_x.to_bits(),
            ray.org_y.to_bits(),
            ray.org_z.to_bits(),
            ray.tnear.to_bits(),
            ray.dir_x.to_bits(),
            ray.dir_y.to_bits(),
            ray.dir_z.to_bits(),
            ray.time.to_bits(),
            ray.tfar.to_bits(),
            ray.mask,
            ray.id,
            ray.flags,
        ];
        words.0[..12].copy_from_slice(&ray_words);
        // 4.2 RTCHit: Ng_x, Ng_y, Ng_z, u, v, primID, geomID, instID[0] (words 12..=19).
        words.0[12..17].fill(0);
        words.0[17..20].fill(INVALID_ID);
        let before = words.0;
        // SAFETY: `self.raw` is a live committed scene. `words` is 256 initialised bytes aligned
        // to 16, holding a valid `RTCRay` and the `RTCHit` fields any Embree 4 reads; the
        // library writes at most `RTCRayHit`'s size, which is below 256 bytes for every
        // instance-level count Embree supports with and without instance arrays.
        unsafe {
            sys::rtcIntersect1(
                self.raw,
                (&raw mut words).cast::<sys::RTCRayHit>(),
                ptr::null_mut(),
            )
        };
        let after = words.0;
        let hit = (after[18] != INVALID_ID).then(|| EmbreeHit {
            t: f32::from_bits(after[8]),
            u: f32::from_bits(after[15]),
            v: f32::from_bits(after[16]),
            prim_id: after[17],
            ng: [
                f32::from_bits(after[12]),
                f32::from_bits(after[13]),
                f32::from_bits(after[14]),
            ],
        });
        RawProbe { before, after, hit }
    }
}

const PROBE_WORDS: usize = 64;
const _: () = assert!(PROBE_WORDS * 4 >= RAYHIT_BYTES + GUARD_WORDS * 4);

/// Result of [`EmbreeScene::probe_raw_words`].
pub(crate) struct RawProbe {
    pub before: [u32; PROBE_WORDS],
    pub after: [u32; PROBE_WORDS],
    pub hit: Option<EmbreeHit>,
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: releases the scene reference and the device reference this value owns (taken in
        // `build`); no query can be running, since queries borrow `self`.
        unsafe {
            sys::rtcReleaseScene(self.raw);
            sys::rtcReleaseDevice(self.device);
        }
    }
}

impl fmt::Debug for EmbreeScene {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("EmbreeScene")
            .field("robust", &self.robust)
            .field("triangles", &self.triangles)
            .finish_non_exhaustive()
    }
}

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
