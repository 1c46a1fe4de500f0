//! A committed one-mesh Embree scene and its queries.

use std::fmt;
use std::ptr;
use std::sync::Arc;

use embree4_sys as sys;

use super::*;

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

/// A triangle mesh checked and laid out for Embree once: every index in range, the vertices
/// and indices in buffers Embree reads in place (`rtcSetSharedGeometryBuffer`). Building a
/// scene of it ([`EmbreeScene::from_mesh`]) is then Embree's own work only. Cloning shares the
/// buffers.
#[derive(Clone, Debug)]
pub struct EmbreeMesh(Arc<MeshBuffers>);

#[derive(Debug)]
struct MeshBuffers {
    /// `x y z` per vertex, then one more `f32` (0): Embree reads the last vertex with a
    /// 16-byte load, so a shared `FLOAT3` buffer must have 4 readable bytes past its end.
    vertices: Box<[f32]>,
    /// Three vertex indices per triangle, each below the vertex count.
    indices: Box<[[u32; 3]]>,
}

impl EmbreeMesh {
    /// The mesh of `positions` and `triangles` (triangle `i` becomes `prim_id == i`). Fails if
    /// an index is out of range (Embree reads vertices through the indices unchecked).
    pub fn new(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Result<Self, EmbreeError> {
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
        let mut vertices = Vec::with_capacity(3 * positions.len() + 1);
        vertices.extend(positions.iter().flatten());
        vertices.push(0.0);
        Ok(Self(Arc::new(MeshBuffers {
            vertices: vertices.into_boxed_slice(),
            indices: triangles.into(),
        })))
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        (self.0.vertices.len() - 1) / 3
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.0.indices.len()
    }
}

/// A committed Embree scene holding one triangle mesh (owns one reference to an `RTCScene` and
/// one to its `RTCDevice`, so it may outlive the [`EmbreeDevice`] it was made from, and one to
/// the [`EmbreeMesh`] buffers Embree reads in place, released after the scene).
pub struct EmbreeScene {
    pub(super) raw: sys::RTCScene,
    device: sys::RTCDevice,
    robust: bool,
    triangles: usize,
    /// The buffers the scene's geometry points into: dropped after `Drop::drop` has released
    /// the scene (fields drop after it), so they outlive every use Embree makes of them.
    mesh: EmbreeMesh,
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
    /// Triangle `i` gets `prim_id == i`. Fails if an index is out of range. Checks and copies
    /// the mesh first ([`EmbreeMesh::new`]); [`EmbreeScene::from_mesh`] does not.
    pub fn new(
        device: &EmbreeDevice,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        robust: bool,
    ) -> Result<Self, EmbreeError> {
        Self::from_mesh(device, &EmbreeMesh::new(positions, triangles)?, robust)
    }

    /// A scene of `mesh` (shared, not copied), with Embree's default build quality: the
    /// scene, its flags, the geometry over `mesh`'s buffers, and the commit (Embree's build).
    pub fn from_mesh(
        device: &EmbreeDevice,
        mesh: &EmbreeMesh,
        robust: bool,
    ) -> Result<Self, EmbreeError> {
        Self::build(device, mesh, robust, None)
    }

    /// As [`EmbreeScene::new`], with an explicit build quality.
    pub fn with_quality(
        device: &EmbreeDevice,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        robust: bool,
        quality: BuildQuality,
    ) -> Result<Self, EmbreeError> {
        let mesh = EmbreeMesh::new(positions, triangles)?;
        Self::build(device, &mesh, robust, Some(quality))
    }

    fn build(
        device: &EmbreeDevice,
        mesh: &EmbreeMesh,
        robust: bool,
        quality: Option<BuildQuality>,
    ) -> Result<Self, EmbreeError> {
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
            triangles: mesh.triangle_count(),
            mesh: mesh.clone(),
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
        if mesh.triangle_count() > 0 {
            scene.attach_mesh(device)?;
        }
        // SAFETY: `scene.raw` is live; after commit the scene is never modified again.
        unsafe { sys::rtcCommitScene(scene.raw) };
        device.check("rtcCommitScene")?;
        Ok(scene)
    }

    /// Creates the triangle geometry over the scene's own mesh buffers (shared, not copied)
    /// and attaches it as geometry 0. The mesh has a triangle.
    fn attach_mesh(&self, device: &EmbreeDevice) -> Result<(), EmbreeError> {
        let MeshBuffers { vertices, indices } = &*self.mesh.0;
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
            // SAFETY: `geom` is a live triangle geometry. `vertices` holds `vertex_count()`
            // items of 12 bytes (`FLOAT3`) at stride 12 from offset 0, plus one `f32`, so the
            // 16-byte load Embree makes of the last item stays inside it; it is 4-byte aligned
            // (`f32`), as Embree requires. Embree only reads it, and it lives (unmoved: a boxed
            // slice behind an `Arc`) until after the scene is released: the scene holds the
            // `Arc` (`mesh`) and drops it after `rtcReleaseScene`.
            unsafe {
                sys::rtcSetSharedGeometryBuffer(
                    geom,
                    sys::RTCBufferType::VERTEX,
                    0,
                    sys::RTCFormat::FLOAT3,
                    vertices.as_ptr().cast(),
                    0,
                    12,
                    self.mesh.vertex_count(),
                )
            };
            device.check("rtcSetSharedGeometryBuffer(VERTEX)")?;
            // SAFETY: as above, `indices.len()` items of `UINT3` (`[u32; 3]`, 12 bytes, no
            // padding), 4-byte aligned, every index below the vertex count (`EmbreeMesh::new`).
            unsafe {
                sys::rtcSetSharedGeometryBuffer(
                    geom,
                    sys::RTCBufferType::INDEX,
                    0,
                    sys::RTCFormat::UINT3,
                    indices.as_ptr().cast(),
                    0,
                    12,
                    indices.len(),
                )
            };
            device.check("rtcSetSharedGeometryBuffer(INDEX)")?;
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
